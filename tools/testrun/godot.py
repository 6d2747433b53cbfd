"""The godot and rendering suites: tests/godot/run_tests.gd in Godot, its results, error and leak lines."""

import os
import re
import shlex

import rp_godot as rp

from . import common
from .common import GODOT_TIMEOUT, RENDERING_TIMEOUT, RESULT, Suite, show_with_context
from .fixtures import FIXTURE_BRACKETED, FIXTURE_RGBD_ONLY, ROOM_SWEEP, make_fixture_oni, make_fixture_recording
from .sanitize import godot_env_shown, sanitized_project, sanitizer_env_text, sanitizer_report, sanitizer_summary

# Lines that fail the godot and rendering suites, wherever they appear.
GODOT_BAD = re.compile(r"ERROR:|SCRIPT ERROR|leaked|Leaked|ObjectDB instances leaked|Orphan StringName|resources still in use at exit")
# The runner's own lines (they may contain "leaked" in a failure message; those count as results).
RUNNER_LINE = re.compile(r"^\[(PASS|FAIL|SKIP|EXPECTED-ERROR|KNOWN-ENGINE-LEAK)\] ")
SUMMARY = re.compile(r"^GODOT_TESTS (\d+) passed, (\d+) failed, (\d+) skipped$")
EXPECTED_ERROR = re.compile(r"^\[EXPECTED-ERROR\] (.*)$")
KNOWN_LEAK = re.compile(r"^\[KNOWN-ENGINE-LEAK\] (\d+) (\S+): (.*)$")
RD_LEAK = re.compile(r'^WARNING: (\d+) RIDs of type "([^"]+)" were leaked\.')
ERROR_DETAILS = re.compile(r"^(?:USER )?(?:SCRIPT )?ERROR: (.*)$")


def suite_godot(opts, rendering, allow_empty):
    name = "rendering" if rendering else "godot"
    s = Suite(name)
    s.logs.append(os.path.join(common.LOGS, f"{name}.log"))
    if not rendering:
        make_fixture_recording()
        make_fixture_recording(FIXTURE_BRACKETED, ("--exposure", "bracket", "--no-calibration"))
        make_fixture_recording(FIXTURE_RGBD_ONLY, ("--no-fisheye",))
        make_fixture_recording(ROOM_SWEEP, ("--no-calibration",), seconds=10, seed=1)  # test_nodes_auto_room.gd
        make_fixture_oni()
    project, env = rp.PROJECT, None
    if opts.sanitize:
        if not os.path.exists(os.path.join(rp.BUILD, "bin", "roomprobe_synth")):
            s.notes.append("no fixture recordings: their tools come from the normal build (./roomprobe build)")
        project, env = sanitized_project(opts, s)
        if project is None:
            return s
    user = []
    if opts.filter:
        user += ["--filter", opts.filter]
    if allow_empty:
        user += ["--allow-empty"]
    if rendering:
        if not rp.have("xvfb-run"):
            rp.header("rendering: skipped, no xvfb-run")
            s.notes.append("not run: no xvfb-run")
            return s
        artifacts = os.path.join(common.LOGS, "rendering")
        os.makedirs(artifacts, exist_ok=True)  # tests save their pictures there
        user += ["--rendering", "--files", "test_rendering_*.gd", "--artifacts", artifacts]
        cmd = rp.xvfb_prefix() + rp.godot_base_args(rendering=True)
    else:
        cmd = rp.godot_base_args(rendering=False, project=project)
    cmd += ["-s", "res://tests/run_tests.gd"]
    if user:
        cmd += ["--"] + user
    runs = [(cmd, s.logs[0])]
    if rendering:
        # The same tests under the Mobile renderer, which headsets use (ids end in @mobile).
        at = cmd.index("res://tests/run_tests.gd") - 1  # before its -s (xvfb-run has one too)
        mobile = cmd[:at] + ["--rendering-method", "mobile"] + cmd[at:]
        mobile[mobile.index("--artifacts") + 1] = artifacts + "-mobile"  # its pictures beside Forward+'s
        os.makedirs(artifacts + "-mobile", exist_ok=True)
        runs.append((mobile, os.path.join(common.LOGS, f"{name}-mobile.log")))
        s.logs.append(runs[1][1])
    seconds = 0.0
    for run_cmd, log in runs:
        seconds += run_godot_tests(s, name, run_cmd, log, (RENDERING_TIMEOUT if rendering else GODOT_TIMEOUT) * (4 if env else 1), env, opts)
    status = "ok" if s.failed == 0 else "FAILED"
    print(f"{status}: {s.passed} passed, {s.failed} failed, {s.skipped} skipped ({rp.fmt_duration(seconds)})")
    return s


def run_godot_tests(s, name, cmd, log, timeout, env, opts):
    """One Godot run of run_tests.gd: its results, errors and leaks added to s; returns its seconds."""
    passed, failed, skipped = s.passed, len(s.failures), s.skipped
    rp.header(f"{name}: {shlex.join(cmd)}" + (f" ({sanitizer_env_text(opts, godot_env_shown(env))})" if env else ""))

    def echo(line):
        if opts.verbose or RESULT.match(line):
            print("    " + line, flush=True)

    r = rp.run(cmd, log, timeout, echo=echo, env=env)
    s.seconds += r.seconds
    s.ran = True
    kept, dropped = rp.filter_noise(r.lines)
    # A sanitizer's report fails the run on its own (it ends it: halt_on_error=1); its lines are
    # not Godot's error lines.
    start, report = sanitizer_report(kept)
    if report:
        s.fail(f"{name}: {sanitizer_summary(report)}")
        print(f"FAILED: {rp.describe_exit(r)} on a sanitizer report; the report (all of it in {rp.relpath(log)}):")
        rp.tail(report, 80)

    summary = None
    for line in kept:
        m = RESULT.match(line)
        if m:
            kind, test = m.group(1), m.group(2)
            if kind == "PASS":
                s.passed += 1
            elif kind == "FAIL":
                s.fail(test)
            else:
                s.skipped += 1
        m = SUMMARY.match(line)
        if m:
            summary = tuple(int(x) for x in m.groups())

    failed_tests = [f for f in s.failures[failed:] if not f.startswith(f"{name}: ")]
    if summary is None and not report:
        why = rp.describe_exit(r)
        s.fail(f"{name}: no GODOT_TESTS line ({why}; crashed or hung?)")
        print(f"FAILED: Godot ended without the GODOT_TESTS line ({why}); the end of its output:")
        rp.tail(kept, 30)
    elif summary is None:
        pass  # the report ended it, counted above
    elif summary != (s.passed - passed, len(failed_tests), s.skipped - skipped):
        s.fail(f"{name}: GODOT_TESTS says {summary}, the result lines say {(s.passed - passed, len(failed_tests), s.skipped - skipped)}")
    elif r.rc != (0 if summary[1] == 0 else 1) and not report:
        s.fail(f"{name}: {rp.describe_exit(r)} with {summary[1]} failed")

    bad, tolerated = unexpected_error_lines(kept[:start] + kept[start + len(report):])
    if bad:
        s.fail(f"{name}: error/leak lines in output")
        print(f"FAILED: {len(bad)} error/leak line(s) in Godot's output:")
        show_with_context(kept, bad)
        if any("ObjectDB instances leaked" in b for b in bad):
            print("    (objects that were never freed: rerun the command above with --verbose after --path to list them)")
    for t in tolerated:
        print(f"    note: tolerated {t}")
    s.notes += [f"tolerated {t}" for t in tolerated]
    if dropped:
        s.notes.append(f"{len(dropped)} known noise line(s) ignored")
    return r.seconds


def unexpected_error_lines(lines):
    """The error and leak lines that no test declared; returns (bad lines, tolerated notes).

    A test declares the engine errors it provokes with expect_error() (the runner prints
    "[EXPECTED-ERROR] details" for each that occurred), and engine bugs that leak RIDs at exit
    with known_engine_leak() ("[KNOWN-ENGINE-LEAK] count type: reason").
    """
    expected = [m.group(1) for m in map(EXPECTED_ERROR.match, lines) if m]
    known = {}
    reasons = {}
    for m in map(KNOWN_LEAK.match, lines):
        if m:
            known[m.group(2)] = known.get(m.group(2), 0) + int(m.group(1))
            reasons.setdefault(m.group(2), set()).add(m.group(3))
    bad = []
    tolerated = []
    for line in lines:
        if RUNNER_LINE.match(line) or not GODOT_BAD.search(line):
            continue
        m = ERROR_DETAILS.match(line)
        if m and m.group(1) in expected:
            expected.remove(m.group(1))
            continue
        m = RD_LEAK.match(line)
        if m and known.get(m.group(2)) == int(m.group(1)):
            tolerated.append(f"{line.strip()} ({'; '.join(sorted(reasons[m.group(2)]))})")
            continue
        bad.append(line)
    return bad, tolerated
