"""The build, core, fuzz and soak suites: scons, the doctest programs, the fuzz replays, the soak bench."""

import concurrent.futures
import glob
import os
import re
import shlex
import time

import rp_godot as rp

from . import common
from .common import BUILD_TIMEOUT, CORE_TIMEOUT, Suite
from .fixtures import FIXTURE_RECORDING, make_fixture_recording
from .sanitize import sanitized_build_dir, sanitizer_env, sanitizer_env_text, sanitizer_report, sanitizer_summary


def suite_build(opts):
    s = Suite("build")
    s.logs.append(os.path.join(common.LOGS, "build.log"))
    selected = opts.suite or ["core"]
    # A sanitizer build makes only what the chosen suites run: core_tests for core, the library for godot.
    default = ["tests=yes"] if not opts.sanitize or "core" in selected else ["tests=no"]
    cmd = rp.scons_command(default, opts.scons_args) + ([f"sanitize={opts.sanitize}"] if opts.sanitize else [])
    if opts.sanitize and "godot" in selected:
        cmd.append("sanitize_godot=yes")
    rp.header(f"build: {shlex.join(cmd)}")
    if rp.sconstruct_missing():
        s.fail("build")
        s.notes.append("no SConstruct in the repository root: nothing to build")
        with open(s.logs[0], "w") as f:
            f.write("no SConstruct in the repository root\n")
        print(f"FAILED: there is no SConstruct in {rp.REPO}")
        s.ran = True
        return s
    echo = (lambda line: print("    " + line, flush=True)) if opts.verbose else None
    r = rp.run(cmd, s.logs[0], BUILD_TIMEOUT, echo=echo)
    s.seconds = r.seconds
    s.ran = True
    if r.rc == 0:
        s.passed = 1
        print(f"ok ({rp.fmt_duration(r.seconds)})")
    else:
        s.fail("build")
        why = rp.describe_exit(r)
        s.notes.append(f"scons failed: {why}")
        print(f"FAILED: scons {why} ({rp.fmt_duration(r.seconds)}); the end of its output:")
        rp.tail(r.lines, 40)
    return s


DOCTEST = re.compile(r"\[doctest\] test cases:\s*(\d+)\s*\|\s*(\d+) passed\s*\|\s*(\d+) failed\s*\|\s*(\d+) skipped")


# The device tests (the drivers, and recording from them) mostly wait: for a GigE camera's heartbeat
# to lapse, for frames in real time. core_tests runs them in a second process beside the others, so
# that both cores stay busy while they wait (about a minute less). Their folders are per process.
WAITING_TESTS = "*/test_drivers_*.cpp,*/test_recording_queue.cpp"


def core_runs(prog, opts):
    """The runs of one test program as (log name, command): core_tests in two shards, by source file,
    unless -k chose the cases."""
    name = os.path.basename(prog)
    if opts.k:
        return [(name, [prog, f"-tc={opts.k}"])]
    if name != "core_tests":
        return [(name, [prog])]
    return [(name, [prog, f"-sfe={WAITING_TESTS}"]), (f"{name}-devices", [prog, f"-sf={WAITING_TESTS}"])]


def suite_core(opts):
    s = Suite("core")
    s.logs.append(os.path.join(common.LOGS, "core.log"))
    tests_dir = os.path.join(rp.BUILD, sanitized_build_dir(opts), "tests")
    programs = sorted(p for p in glob.glob(os.path.join(tests_dir, "*_tests"))
                      if os.path.isfile(p) and os.access(p, os.X_OK))
    rp.header("core: " + (", ".join(rp.relpath(p) for p in programs) or f"no {rp.relpath(tests_dir)}/*_tests programs")
              + (f" ({sanitizer_env_text(opts)})" if opts.sanitize else ""))
    s.ran = True
    if not programs:
        s.notes.append(f"no test programs in {rp.relpath(tests_dir)}/")
        print("no test programs (the build made none)")
        return s
    echo = (lambda line: print("    " + line, flush=True)) if opts.verbose else None
    env = dict(os.environ, **sanitizer_env(opts)) if opts.sanitize else None
    with open(s.logs[0], "w") as combined:
        for prog in programs:
            runs = core_runs(prog, opts)
            logs = [os.path.join(common.LOGS, f"core-{name}.log") for name, _ in runs]
            start = time.monotonic()
            with concurrent.futures.ThreadPoolExecutor(len(runs)) as pool:
                results = list(pool.map(lambda run, log: rp.run(run[1], log, CORE_TIMEOUT * (4 if opts.sanitize else 1), echo=echo, env=env),
                                        runs, logs))
            s.seconds += time.monotonic() - start
            totals = []
            for (name, _), log, r in zip(runs, logs, results):
                combined.write(f"# {name}: see {rp.relpath(log)}\n")
                s.logs.append(log)
                totals.append(core_result(s, name, log, r, opts, sharded=len(runs) > 1))
            if len(runs) > 1 and None not in totals:
                # Each shard counts the other's cases as skipped (doctest's filters); run + skipped is
                # every case in either.
                s.skipped += sum(skipped for _, skipped in totals) - sum(totals[0])
    return s


def core_result(s, name, log, r, opts, sharded):
    """Adds one doctest run's counts and failures to s and prints its line. Returns (cases, skipped)
    from doctest's summary, or None without one."""
    summary = None
    for line in r.lines:
        m = DOCTEST.search(line)
        if m:
            summary = tuple(int(x) for x in m.groups())
    start, report = sanitizer_report(r.lines)
    lines = r.lines[:start]  # doctest's output, before any sanitizer report
    if summary is None and report:
        s.fail(f"{name}: {sanitizer_summary(report)}")
        print(f"FAILED {name}: {rp.describe_exit(r)} on a sanitizer report ({rp.fmt_duration(r.seconds)}); "
              f"the report (all of it in {rp.relpath(log)}):")
        rp.tail(report, 80)
        return None
    if summary is None:
        why = rp.describe_exit(r) + ", no doctest summary (crashed?)"
        s.fail(f"{name}: {why}")
        print(f"FAILED {name}: {why} ({rp.fmt_duration(r.seconds)}); the end of its output:")
        rp.tail(r.lines, 30)
        return None
    total, passed, failed, skipped = summary
    s.passed += passed
    s.failed += failed
    if not opts.k and not sharded:  # with a filter, doctest counts the filtered-out cases as skipped
        s.skipped += skipped
    failed_cases = failed_doctest_cases(lines)
    s.failures += [f"{name}: {c}" for c in failed_cases] or ([f"{name}: {failed} test case(s)"] if failed else [])
    extra = ""
    if r.rc != 0 and failed == 0:
        extra = f"; {rp.describe_exit(r)} although no test case failed"
        if report:
            extra = f"; {rp.describe_exit(r)} on a sanitizer report after the tests: {sanitizer_summary(report)}"
        s.fail(name + extra)
    status = "ok" if failed == 0 and r.rc == 0 else "FAILED"
    shown_skipped = "" if sharded else f", {skipped} skipped"
    print(f"{status} {name}: {passed} passed, {failed} failed{shown_skipped}{extra} ({rp.fmt_duration(r.seconds)})")
    if status != "ok" and not opts.verbose:
        show_doctest_failures(lines)
        rp.tail(report, 80)
    return (total, skipped)


def failed_doctest_cases(lines):
    cases = []
    current = None
    for line in lines:
        m = re.match(r"^TEST CASE:\s+(.*)$", line)
        if m:
            current = m.group(1).strip()
        elif current and re.search(r"\bERROR\b|FATAL ERROR|TEST CASE FAILED|THREW exception", line) and current not in cases:
            cases.append(current)
    return cases


def show_doctest_failures(lines, limit=120):
    """doctest's failure reports: the blocks between its '=====' separators."""
    shown = 0
    block = []
    for line in lines:
        if line.startswith("=" * 20):
            if block:
                for b in block:
                    if shown < limit:
                        print("    " + b)
                        shown += 1
            block = []
        elif not line.startswith("[doctest]"):
            block.append(line)
    if shown >= limit:
        print("    ... (see the log)")


FUZZ_RESULT = re.compile(r"^fuzz (\w+): (\d+) executions in .*?(no crash.*|FAILED.*)$")


def suite_fuzz(opts):
    """tools/fuzz/fuzz.py all --replay, the short form: each fuzz target, built by the normal build
    (build/tests/replay_TARGET), runs every input of its corpus (made from seeds when missing) and
    of its kept failures once; one test per target. The long form, libFuzzer with ASan and UBSan
    (a clang build of the core, minutes on two cores), is ./roomprobe fuzz TARGET|all --seconds S."""
    s = Suite("fuzz")
    log = os.path.join(common.LOGS, "fuzz.log")
    s.logs.append(log)
    rp.header("fuzz: every fuzz target of tests/fuzz/ on its corpus, once (tools/fuzz/fuzz.py all --replay)")
    s.ran = True
    echo = (lambda line: print("    " + line, flush=True)) if opts.verbose else None
    r = rp.run(["python3", os.path.join(rp.REPO, "tools", "fuzz", "fuzz.py"), "all", "--replay"], log, 1800, echo=echo)
    s.seconds = r.seconds
    for line in r.lines:
        m = FUZZ_RESULT.match(line)
        if m:
            print(line)
            if m.group(3).startswith("no crash"):
                s.passed += 1
            else:
                s.fail(f"fuzz {m.group(1)}: {m.group(3)}")
    if s.passed + s.failed == 0 or (r.rc != 0 and s.failed == 0):
        s.fail(f"fuzz: {rp.describe_exit(r)} (see {rp.relpath(log)})")
        rp.tail(r.lines, 30)
    return s


# The short soak (the long one: ./roomprobe soak --frames 50000): the fixture played back and
# forth for SOAK_FRAMES RGB-D frames, the first SOAK_WARMUP of them warm-up (resident memory climbs
# for the first few hundred frames as the allocators' pools fill, then stays within a sawtooth of
# about 10 %), 32² probe. The 1000 frames judged are as many as before the warm-up was halved.
SOAK_FRAMES = 2000
SOAK_WARMUP = 1000
SOAK_SUMMARY = re.compile(r"^summary: mode=soak .*rss_growth_pct=(-?[\d.]+) .*time_ratio=([\d.]+) lost=(\d+) unreadable=(\d+)")


def suite_soak(opts):
    """roomprobe_bench soak on the fixture recording: one test, passed when resident memory stays
    within 5 % after the warm-up and every frame reads. The time per frame is reported, not judged
    here (a benchmark's figure; the long soak judges it)."""
    s = Suite("soak")
    log = os.path.join(common.LOGS, "soak.log")
    s.logs.append(log)
    make_fixture_recording()
    cmd = [os.path.join(rp.BUILD, "bin", "roomprobe_bench"), "soak", "--recording", FIXTURE_RECORDING, "--frames", str(SOAK_FRAMES),
           "--warmup-frames", str(SOAK_WARMUP), "--probe-size", "32"]
    rp.header(f"soak: {rp.relpath(cmd[0])} soak, {SOAK_FRAMES} frames of the fixture back and forth")
    s.ran = True
    echo = (lambda line: print("    " + line, flush=True)) if opts.verbose else None
    r = rp.run(cmd, log, 3600, echo=echo)
    s.seconds = r.seconds
    m = next((SOAK_SUMMARY.match(line) for line in r.lines if SOAK_SUMMARY.match(line)), None)
    if m is None:
        s.fail(f"soak: {rp.describe_exit(r)}, no summary line (see {rp.relpath(log)})")
        rp.tail(r.lines, 30)
        return s
    growth, ratio, lost, unreadable = float(m.group(1)), float(m.group(2)), int(m.group(3)), int(m.group(4))
    print(next(line for line in r.lines if line.startswith("summary: mode=soak")))
    if growth > 5.0 or unreadable > 0:
        s.fail(f"soak: resident memory {growth:+.2f} % in the last quarter over the highest of the first after the warm-up (at most +5 %), {unreadable} frames unreadable")
    else:
        s.passed += 1
    s.notes.append(f"memory {growth:+.2f} % over the early highest, time per frame x{ratio:.3f} last tenth / first, {lost} frames lost")
    return s
