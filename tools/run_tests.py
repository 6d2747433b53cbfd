#!/usr/bin/env python3
"""RoomProbe's test runner: ./roomprobe test [OPTIONS] runs it inside the toolchain.

Suites, in order (see tests/README.md):
  host       tests/host/test_paths.sh: ./roomprobe's path arguments from outside the clone; run on the
             host by ./roomprobe test before this runner, which reports them (--host-results)
  build      scons -j<nproc> tests=yes (or the arguments in $ROOMPROBE_SCONS_ARGS / --scons-args)
  core       every build/tests/*_tests (doctest) program
  fuzz       every libFuzzer target of tests/fuzz/ for a few seconds on its corpus (tools/fuzz/fuzz.py;
             clang builds the core again into build/fuzz/)
  soak       roomprobe_bench soak: the fixture back and forth through the engine for 3000 frames;
             resident memory flat after the warm-up
  room       roomprobe_room on a 10-s living-room sweep against its true room (corners, ceiling, up,
             registration), roomprobe_eval's maps with the room found against the true room, and
             the tool's refusals
  editor     godot --headless --editor --quit: a fresh copy of the project and the project itself
             import, and the extension loads and unloads, without errors
  godot      tests/godot/test_*.gd, headless
  rendering  tests/godot/test_rendering_*.gd under xvfb-run with Vulkan (when xvfb-run exists)

The last line printed is exactly "N passed, N failed" (", N skipped" appended when some were
skipped); the exit status is 0 only when nothing failed. Raw logs: build/test-logs/.

--sanitize thread|address (address,undefined) builds with scons sanitize=... into build/debug-tsan|asan/
(apart from the normal build) and runs the core suite (the default) and/or the godot suite under
ThreadSanitizer or AddressSanitizer with UBSan:
  core   build/debug-tsan|asan/tests/core_tests
  godot  scons sanitize_godot=yes also builds the library and the binding's test extension into
         build/debug-tsan|asan/bin/; a scratch copy of godot_project/ in build/debug-tsan|asan/godot_project
         loads them, is imported, and runs tests/godot/test_*.gd in the (uninstrumented) Godot with the
         sanitizer's runtime in LD_PRELOAD
A sanitizer report fails the run it ends (halt_on_error=1), named by its SUMMARY line. Logs go to
build/test-logs/debug-tsan|asan/.
"""

import argparse
import glob
import os
import re
import shlex
import shutil
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import rp_godot as rp  # noqa: E402

SUITES = ["host", "package", "build", "core", "fuzz", "soak", "room", "editor", "godot", "rendering"]
LOGS = os.path.join(rp.BUILD, "test-logs")

BUILD_TIMEOUT = 3600
CORE_TIMEOUT = 900      # per test program
IMPORT_TIMEOUT = 300
GODOT_TIMEOUT = 900
RENDERING_TIMEOUT = 900

# Lines that fail the editor suite (after the known noise is filtered out).
EDITOR_BAD = re.compile(r"ERROR|SCRIPT ERROR|Failed to|leaked")
# Lines that fail the godot and rendering suites, wherever they appear.
GODOT_BAD = re.compile(r"ERROR:|SCRIPT ERROR|leaked|Leaked|ObjectDB instances leaked|Orphan StringName|resources still in use at exit")
# The runner's own lines (they may contain "leaked" in a failure message; those count as results).
RUNNER_LINE = re.compile(r"^\[(PASS|FAIL|SKIP|EXPECTED-ERROR|KNOWN-ENGINE-LEAK)\] ")
RESULT = re.compile(r"^\[(PASS|FAIL|SKIP)\] (\S+)(?:: (.*))?$")
SUMMARY = re.compile(r"^GODOT_TESTS (\d+) passed, (\d+) failed, (\d+) skipped$")
HOST_SUMMARY = re.compile(r"^(?:HOST|PACKAGE)_TESTS (\d+) passed, (\d+) failed in ([\d.]+) s$")
EXPECTED_ERROR = re.compile(r"^\[EXPECTED-ERROR\] (.*)$")
KNOWN_LEAK = re.compile(r"^\[KNOWN-ENGINE-LEAK\] (\d+) (\S+): (.*)$")
RD_LEAK = re.compile(r'^WARNING: (\d+) RIDs of type "([^"]+)" were leaked\.')
ERROR_DETAILS = re.compile(r"^(?:USER )?(?:SCRIPT )?ERROR: (.*)$")
# The first line of a sanitizer's report, and its last.
SANITIZER_START = re.compile(r"^(==\d+==)?(WARNING|ERROR): (Thread|Address|Leak)Sanitizer|: runtime error: ")
SANITIZER_SUMMARY = re.compile(r"^SUMMARY: \w+Sanitizer: .*$")
# halt_on_error: the first report ends the run (TSan exits with 66, ASan and UBSan with 1).
SANITIZER_ENV = {
    "thread": {"TSAN_OPTIONS": "halt_on_error=1 second_deadlock_stack=1"},
    # detect_leaks=0: OpenNI2's driver plugins leak their static objects and are unloaded before
    # LeakSanitizer looks, so their leaks can be neither named nor suppressed (the rest is leak-free).
    # The same holds in Godot, which loads the same drivers through our library; there Godot (not
    # instrumented, and not ours) also keeps allocations to exit, and unloads our library before
    # LeakSanitizer looks, so what it reported could not be told apart or named. Leaks of our code
    # are checked elsewhere: the core's by ./roomprobe soak --sanitize address (LeakSanitizer on),
    # objects left through the engine by the godot suite itself (ObjectDB, RIDs, orphan nodes).
    "address": {"ASAN_OPTIONS": "halt_on_error=1 detect_leaks=0", "UBSAN_OPTIONS": "halt_on_error=1 print_stacktrace=1"},
}
# Only in the godot suite's Godot. allow_user_segv_handler=0: Godot installs its own crash handler
# over ASan's; ASan's report of a bad access (its stack, the memory's history) is the one wanted.
# verify_asan_link_order=0: tests/sanitize/no_deepbind.c is preloaded before ASan's runtime (it must
# come first to replace dlopen), which ASan would otherwise refuse.
SANITIZER_GODOT_ENV = {"address": {"ASAN_OPTIONS": "allow_user_segv_handler=0 verify_asan_link_order=0"}}
# Only in the editor import before it: the editor (Godot 4.6.3's, stripped) takes two of its own
# mutexes in both orders, tens of thousands of lock-order reports with every frame in /usr/bin/godot,
# which a suppression could only name by the module, and so every stack (each has a Godot frame).
# The test run itself, where our code runs, keeps deadlock detection.
SANITIZER_IMPORT_ENV = {"thread": {"TSAN_OPTIONS": "detect_deadlocks=0"}}
TSAN_SUPPRESSIONS = os.path.join(rp.REPO, "tests", "tsan.supp")
# The sanitizer runtimes Godot needs in LD_PRELOAD to load a sanitized library (read from the
# library's DT_NEEDED): the runtime must be the first library in the process.
SANITIZER_RUNTIME = re.compile(r"\[(lib(asan|ubsan|tsan)\.so[.\d]*)\]")
DOCTEST = re.compile(r"\[doctest\] test cases:\s*(\d+)\s*\|\s*(\d+) passed\s*\|\s*(\d+) failed\s*\|\s*(\d+) skipped")


class Suite:
    def __init__(self, name):
        self.name = name
        self.passed = 0
        self.failed = 0
        self.skipped = 0
        self.seconds = 0.0
        self.notes = []      # one-line remarks shown in the summary
        self.failures = []   # names of failed tests
        self.logs = []
        self.ran = False

    def fail(self, what):
        self.failed += 1
        self.failures.append(what)


def main():
    # No abbreviated options: ./roomprobe reads --suite and --filter itself to run the host suite.
    ap = argparse.ArgumentParser(prog="./roomprobe test", description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, allow_abbrev=False,
                                 epilog="suites: " + ", ".join(SUITES))
    ap.add_argument("--suite", action="append", choices=SUITES,
                    help="run only this suite (repeatable); the build and the editor import still run first as "
                         "prerequisites, counted only when they fail")
    ap.add_argument("--filter", metavar="SUBSTRING",
                    help="godot and host suites: run only tests whose 'file::test' (host: 'host::test') contains SUBSTRING")
    ap.add_argument("-k", metavar="PATTERN", help="core suite: doctest -tc=PATTERN (test case names, wildcards * ?)")
    ap.add_argument("--no-build", action="store_true", help="skip the build (use what is built)")
    ap.add_argument("--scons-args", metavar="ARGS",
                    help="arguments for scons instead of '-j<nproc> tests=yes' (also $ROOMPROBE_SCONS_ARGS)")
    ap.add_argument("--sanitize", choices=sorted(SANITIZER_ENV) + ["address,undefined"],
                    help="build with -fsanitize=thread (or address,undefined) into build/<target>-tsan|asan/ and run "
                         "the core suite (default) and/or, with --suite godot, the godot suite against the sanitized "
                         "library (a scratch copy of the project; Godot with the runtime in LD_PRELOAD)")
    ap.add_argument("-v", "--verbose", action="store_true", help="show every output line of every step")
    ap.add_argument("--package-results", metavar="FILE",
                    help="the package suite's results, written by tests/host/test_package.sh (./roomprobe test passes it)")
    ap.add_argument("--host-results", metavar="FILE",
                    help="the host suite's results, written by tests/host/test_paths.sh (./roomprobe test passes it)")
    opts = ap.parse_args()
    if opts.sanitize == "address,undefined":
        opts.sanitize = "address"  # the address build is AddressSanitizer and UndefinedBehaviorSanitizer
    if opts.sanitize and set(opts.suite or ["core"]) - {"build", "core", "godot"}:
        ap.error("--sanitize runs only the core and godot suites (and the build)")
    if opts.sanitize:
        global LOGS
        LOGS = os.path.join(LOGS, sanitized_build_dir(opts))  # the normal run's logs stay as they are

    os.makedirs(LOGS, exist_ok=True)
    selected = opts.suite or (["build", "core"] if opts.sanitize else SUITES)
    results = []
    start = time.monotonic()

    def counted(name):
        return name in selected

    # host: already run by ./roomprobe test, outside the toolchain
    for name in ("host", "package"):
        if counted(name):
            results.append(suite_host(opts, name))
            start -= results[-1].seconds  # the total time includes it

    # build, unless only the host and package suites were asked for
    if not opts.no_build and not set(selected) <= {"host", "package"}:
        s = suite_build(opts)
        if counted("build") or s.failed:
            results.append(s)
        if s.failed:
            return finish(results, start)

    if counted("core"):
        results.append(suite_core(opts))
    if counted("fuzz"):
        results.append(suite_fuzz(opts))
    if counted("soak"):
        results.append(suite_soak(opts))
    if counted("room"):
        results.append(suite_room(opts))

    # A sanitized godot suite imports its own scratch copy of the project instead.
    needs_import = not opts.sanitize and any(counted(n) for n in ("editor", "godot", "rendering"))
    if needs_import:
        s = suite_editor(opts, judged=counted("editor"))
        if counted("editor") or s.failed:
            results.append(s)
        if s.failed and not os.path.isdir(os.path.join(rp.PROJECT, ".godot")):
            return finish(results, start)

    # With --filter and more than one suite that it filters, a suite with no matching test is not
    # a failure; no match in any of them is (checked below).
    filtered = [n for n in ("godot", "rendering", "host", "package") if counted(n)]
    allow_empty = bool(opts.filter) and len(filtered) > 1
    ran_godot = []
    if counted("godot"):
        ran_godot.append(suite_godot(opts, rendering=False, allow_empty=allow_empty))
    if counted("rendering"):
        ran_godot.append(suite_godot(opts, rendering=True, allow_empty=allow_empty))
    results += ran_godot
    ran = [s for s in results if s.ran and s.name in filtered]
    if opts.filter and ran and sum(s.passed + s.failed + s.skipped for s in ran) == 0:
        ran[0].fail(f"no test matched --filter '{opts.filter}'")
    return finish(results, start)


# ---------------------------------------------------------------------------------- fuzz

FUZZ_RESULT = re.compile(r"^fuzz (\w+): (\d+) executions in .*?(no crash.*|FAILED.*)$")


def suite_fuzz(opts):
    """tools/fuzz/fuzz.py all --replay, the short form: each fuzz target, built by the normal build
    (build/tests/replay_TARGET), runs every input of its corpus (made from seeds when missing) and
    of its kept failures once; one test per target. The long form, libFuzzer with ASan and UBSan
    (a clang build of the core, minutes on two cores), is ./roomprobe fuzz TARGET|all --seconds S."""
    s = Suite("fuzz")
    log = os.path.join(LOGS, "fuzz.log")
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


# ---------------------------------------------------------------------------------- soak

# The short soak (the long one: ./roomprobe soak --frames 50000): the fixture played back and
# forth for SOAK_FRAMES RGB-D frames after SOAK_WARMUP frames of warm-up (resident memory climbs
# for the first couple of thousand frames as the allocators' pools fill, then stays), 32² probe.
SOAK_FRAMES = 3000
SOAK_WARMUP = 2000
SOAK_SUMMARY = re.compile(r"^summary: mode=soak .*rss_growth_pct=(-?[\d.]+) .*time_ratio=([\d.]+) lost=(\d+) unreadable=(\d+)")


def suite_soak(opts):
    """roomprobe_bench soak on the fixture recording: one test, passed when resident memory stays
    within 5 % after the warm-up and every frame reads. The time per frame is reported, not judged
    here (a benchmark's figure; the long soak judges it)."""
    s = Suite("soak")
    log = os.path.join(LOGS, "soak.log")
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
        s.fail(f"soak: resident memory {growth:+.2f} % after the warm-up (at most +5 %), {unreadable} frames unreadable")
    else:
        s.passed += 1
    s.notes.append(f"memory {growth:+.2f} %, time per frame x{ratio:.3f} last tenth / first, {lost} frames lost")
    return s


# ---------------------------------------------------------------------------------- host


def suite_host(opts, name="host"):
    """The results tests/host/test_paths.sh wrote ('[PASS] host::test', '[FAIL] host::test: why', then
    'HOST_TESTS N passed, N failed in S s'). ./roomprobe test runs it on the host first, since the
    paths it tests are not visible in here; its output has been printed already."""
    s = Suite(name)
    s.logs.append(os.path.join(LOGS, f"{name}.log"))
    results_file = opts.host_results if name == "host" else opts.package_results
    script = "tests/host/test_paths.sh" if name == "host" else "tests/host/test_package.sh"
    if not results_file:
        s.notes.append(f"the {name} suite runs only from ./roomprobe test, outside the toolchain")
        return s
    s.ran = True
    try:
        with open(results_file) as f:
            lines = f.read().splitlines()
    except OSError as e:
        s.fail(f"{name}: no results ({e.strerror}: {rp.relpath(results_file)})")
        return s
    summary = None
    for line in lines:
        m = RESULT.match(line)
        if m:
            if m.group(1) == "PASS":
                s.passed += 1
            elif m.group(1) == "FAIL":
                s.fail(f"{m.group(2)}: {m.group(3)}" if m.group(3) else m.group(2))
            else:
                s.skipped += 1
        m = HOST_SUMMARY.match(line)
        if m:
            summary = (int(m.group(1)), int(m.group(2)))
            s.seconds = float(m.group(3))
    if summary is None:
        s.fail(f"{name}: {script} ended without its {name.upper()}_TESTS line")
    elif summary != (s.passed, len(s.failures)):
        s.fail(f"{name}: {name.upper()}_TESTS says {summary}, the result lines say {(s.passed, len(s.failures))}")
    return s


# ---------------------------------------------------------------------------------- build


def suite_build(opts):
    s = Suite("build")
    s.logs.append(os.path.join(LOGS, "build.log"))
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


# ---------------------------------------------------------------------------------- core


def suite_core(opts):
    s = Suite("core")
    s.logs.append(os.path.join(LOGS, "core.log"))
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
    with open(s.logs[0], "w") as combined:
        for prog in programs:
            name = os.path.basename(prog)
            log = os.path.join(LOGS, f"core-{name}.log")
            cmd = [prog] + ([f"-tc={opts.k}"] if opts.k else [])
            echo = (lambda line: print("    " + line, flush=True)) if opts.verbose else None
            env = dict(os.environ, **sanitizer_env(opts)) if opts.sanitize else None
            r = rp.run(cmd, log, CORE_TIMEOUT * (4 if opts.sanitize else 1), echo=echo, env=env)
            combined.write(f"# {name}: see {rp.relpath(log)}\n")
            s.logs.append(log)
            s.seconds += r.seconds
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
                continue
            if summary is None:
                why = rp.describe_exit(r) + ", no doctest summary (crashed?)"
                s.fail(f"{name}: {why}")
                print(f"FAILED {name}: {why} ({rp.fmt_duration(r.seconds)}); the end of its output:")
                rp.tail(r.lines, 30)
                continue
            total, passed, failed, skipped = summary
            s.passed += passed
            s.failed += failed
            if not opts.k:  # with -tc, doctest counts the filtered-out cases as skipped
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
            print(f"{status} {name}: {passed} passed, {failed} failed, {skipped} skipped{extra} ({rp.fmt_duration(r.seconds)})")
            if status != "ok" and not opts.verbose:
                show_doctest_failures(lines)
                rp.tail(report, 80)
    return s


def sanitized_build_dir(opts):
    """'' for the normal build/tests/; 'debug-tsan' or 'debug-asan' (SConstruct's build dir) with --sanitize."""
    if not opts.sanitize:
        return ""
    args = opts.scons_args if opts.scons_args is not None else os.environ.get("ROOMPROBE_SCONS_ARGS", "")
    target = "release" if "target=release" in shlex.split(args) else "debug"
    return f"{target}-{'tsan' if opts.sanitize == 'thread' else 'asan'}"


def sanitizer_env(opts, *extra):
    """TSAN_OPTIONS etc.: ours first (then those of the extra tables, e.g. SANITIZER_GODOT_ENV), then
    what the caller set, which wins where both set one."""
    env = {}
    for var, value in SANITIZER_ENV[opts.sanitize].items():
        if var == "TSAN_OPTIONS" and os.path.exists(TSAN_SUPPRESSIONS):
            value += f" suppressions={TSAN_SUPPRESSIONS}"
        for table in extra:
            if var in table.get(opts.sanitize, {}):
                value += " " + table[opts.sanitize][var]
        env[var] = f"{value} {os.environ.get(var, '')}".strip()
    return env


def sanitizer_env_text(opts, env=None):
    return " ".join(f"{k}={shlex.quote(v)}" for k, v in (env or sanitizer_env(opts)).items())


def sanitizer_report(lines):
    """(where the first sanitizer report in lines starts, that report through its SUMMARY line);
    (len(lines), []) when there is none."""
    for i, line in enumerate(lines):
        if SANITIZER_START.search(line):
            report = lines[i:]
            for j, rest in enumerate(report):
                if SANITIZER_SUMMARY.match(rest):
                    return i, report[:j + 1]
            return i, report
    return len(lines), []


def sanitizer_summary(report):
    """'ThreadSanitizer: data race file:line in function', or the report's first line."""
    return next((m.group(0)[len("SUMMARY: "):] for m in map(SANITIZER_SUMMARY.match, report) if m), report[0].strip())


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


# ---------------------------------------------------------------------------------- editor


def suite_editor(opts, judged=True):
    """Four checks, one test each; each but the round trip is `godot --headless --editor --quit` (see
    rp_godot.import_command for the extension list written before a first import).

    fresh-import: a scratch copy of godot_project/ without .godot/, as on a fresh clone.
    fresh-reopen: the same copy opened again, now imported.
    scene-roundtrip: in that copy, the editor opens a RoomProbe scene (tests/editor/roundtrip/),
        lets the probe drive a material, a ReflectionProbe and a sky, saves it and quits; the
        saved file must hold the user's values only (no maps, no sky, the probe's box as set),
        and the probe must render no map while nothing changes, and one after a move; then tab
        switches, a reload and closing the scene, with no error logged.
    import: the project itself; this also makes the .godot/ the Godot suites need.
    """
    s = Suite("editor")
    s.logs.append(os.path.join(LOGS, "editor.log"))
    s.ran = True
    rp.header(f"editor{'' if judged else ' (prerequisite)'}: fresh import of a scratch copy, then the project's own import")
    checks = []
    scratch = os.path.join(rp.BUILD, "godot-fresh-import")
    if judged:
        fresh_project_copy(scratch)
        checks.insert(0, ("fresh-import", None, os.path.join(LOGS, "editor-fresh-import.log")))
        # Then the plain `godot --headless --editor --quit` on that freshly imported copy.
        checks.insert(1, ("fresh-reopen", None, os.path.join(LOGS, "editor-fresh-reopen.log")))
        s.logs += [checks[0][2], checks[1][2]]
    checks.append(("import", None, s.logs[0]))
    if judged:
        checks.insert(2, ("scene-roundtrip", None, os.path.join(LOGS, "editor-scene-roundtrip.log")))
        s.logs.append(checks[2][2])
    for name, _, log in checks:
        if name == "scene-roundtrip":
            scene_roundtrip(s, scratch, log)
            continue
        # Chosen at run time: the command depends on whether the previous check imported it.
        cmd = rp.import_command(scratch if name.startswith("fresh") else rp.PROJECT)
        r = rp.run(cmd, log, IMPORT_TIMEOUT)
        s.seconds += r.seconds
        kept, dropped = rp.filter_noise(r.lines)
        bad = [line for line in kept if EDITOR_BAD.search(line)]
        if r.rc == 0 and not bad and not r.timed_out:
            s.passed += 1
            print(f"ok {name} ({rp.fmt_duration(r.seconds)}){noise_note(dropped)}")
            continue
        why = rp.describe_exit(r) if r.rc or r.timed_out or r.error else f"{len(bad)} error line(s)"
        s.fail(f"editor::{name}: {why}")
        print(f"FAILED {name}: {why} ({rp.fmt_duration(r.seconds)}): {shlex.join(cmd)}")
        show_with_context(kept, bad)
        if not bad:
            print("    (no error line; the end of its output:)")
            rp.tail([line for line in kept if line.strip() and not line.startswith("[")], 8)
    return s


ROUNDTRIP = os.path.join(rp.REPO, "tests", "editor", "roundtrip")
# The bound: an idle editor on a RoomProbe scene within a few points of one on an empty scene.
IDLE_CPU_POINTS = 5.0
# What a saved RoomProbe scene must not hold (the probe's own outputs), and what it must keep.
ROUNDTRIP_FORBIDDEN = [("an image", re.compile(r'type="Image"|\bImage\b')), ("a sky", re.compile(r'type="Sky"|\bsky = ')),
                       ("a cubemap", re.compile(r'Cubemap')), ("a driven box", re.compile(r'box_projection|interior = true|origin_offset'))]
ROUNDTRIP_KEPT = ["size = Vector3(1, 2, 3)", "cull_mask = 5", "Transform3D(1, 0, 0, 0, 1, 0, 0, 0, 1, 0.5, 0.5, 0.5)"]


def fresh_project_copy(dest, leave_out=()):
    """A scratch copy of godot_project/ at dest, as on a fresh clone: no .godot/, the symlinked folders
    (tests/, demo_scenes/, the shaders) copied; leave_out: more names (glob patterns) not copied."""
    shutil.rmtree(dest, ignore_errors=True)
    shutil.copytree(rp.PROJECT, dest, symlinks=False, ignore=shutil.ignore_patterns(".godot", *leave_out))


def scene_roundtrip(s, scratch, log):
    """editor::scene-roundtrip (see suite_editor)."""
    for scene in ["roundtrip_probe.tscn", "empty.tscn"]:
        shutil.copyfile(os.path.join(ROUNDTRIP, scene), os.path.join(scratch, "roundtrip_" + scene.replace("roundtrip_", "")))
    plugin = os.path.join(scratch, "addons", "roomprobe_roundtrip")
    shutil.rmtree(plugin, ignore_errors=True)
    os.makedirs(plugin)
    for f in ["plugin.cfg", "plugin.gd"]:
        shutil.copyfile(os.path.join(ROUNDTRIP, f), os.path.join(plugin, f))
    settings = os.path.join(scratch, "project.godot")
    with open(settings) as f:
        text = f.read()
    text = re.sub(r'enabled=PackedStringArray\((.*)\)', r'enabled=PackedStringArray(\1, "res://addons/roomprobe_roundtrip/plugin.cfg")', text)
    with open(settings, "w") as f:
        f.write(text)
    cmd = [rp.godot(), "--headless", "--editor", "--path", scratch]
    r = rp.run(cmd, log, IMPORT_TIMEOUT)
    s.seconds += r.seconds
    with open(os.path.join(scratch, "roundtrip_probe.tscn")) as f:
        saved = f.read()
    problems = []
    if r.rc != 0 or r.timed_out:
        problems.append(rp.describe_exit(r))
    for expected, problem in [("roundtrip: the probe made a map and drives its outputs", "the probe drove nothing (no map)"),
                              ("roundtrip: saved res://roundtrip_probe.tscn (OK)", "the editor did not save the scene"),
                              ("roundtrip: driven again after saving", "the probe did not drive its outputs again after saving"),
                              ("roundtrip: switched tabs, reloaded and closed", "the tab switches, reload and close did not finish"),
                              ("roundtrip: the inspector previews the map", "the inspector shows no preview of the map"),
                              ("roundtrip: gizmos on the probe and the room", "the probe or the room has no gizmo"),
                              ("roundtrip: a corner moves on the floor and back", "the floorplan gizmo's corner drag or its undo failed")]:
        if not any(expected in line for line in r.lines):
            problems.append(problem)
    idle = next((line for line in r.lines if "roundtrip: idle maps" in line), "")
    moved = next((line for line in r.lines if "roundtrip: maps after a move" in line), "")
    cpu = next((re.search(r"idle cpu scene ([\d.]+)% empty ([\d.]+)%", line) for line in r.lines if "roundtrip: idle cpu" in line), None)
    if not cpu:
        problems.append("the idle CPU was not measured")
    elif float(cpu.group(1)) - float(cpu.group(2)) > IDLE_CPU_POINTS:
        problems.append(f"idle CPU with the RoomProbe scene {cpu.group(1)}%, more than {IDLE_CPU_POINTS:g} points above an empty scene's {cpu.group(2)}%")
    else:
        print(f"    idle CPU of the editor: {cpu.group(1)}% with the RoomProbe scene, {cpu.group(2)}% with an empty scene")
    if "idle maps 0 in" not in idle:
        problems.append(f"the probe renders while the editor is idle ({idle.strip() or 'not measured'})")
    if not moved or moved.strip().endswith(" 0"):
        problems.append(f"the probe did not render after a move ({moved.strip() or 'not measured'})")
    problems += [f"the saved scene holds {what}" for what, pattern in ROUNDTRIP_FORBIDDEN if pattern.search(saved)]
    problems += [f"the saved scene lost '{kept}'" for kept in ROUNDTRIP_KEPT if kept not in saved]
    kept, _ = rp.filter_noise(r.lines)
    bad = [line for line in kept if EDITOR_BAD.search(line)]
    if bad:
        problems.append(f"{len(bad)} error line(s)")
    if not problems:
        s.passed += 1
        print(f"ok scene-roundtrip ({rp.fmt_duration(r.seconds)}; saved {len(saved)} bytes)")
        return
    s.fail(f"editor::scene-roundtrip: {'; '.join(problems)}")
    print(f"FAILED scene-roundtrip: {'; '.join(problems)}: {shlex.join(cmd)}")
    show_with_context(kept, bad)
    for line in saved.splitlines()[:60]:
        print("    | " + line)


def noise_note(dropped):
    return f"; {len(dropped)} known noise line(s) ignored" if dropped else ""


def show_with_context(lines, bad, limit=60):
    """Prints each bad line with the indented 'at:'/backtrace lines that follow it."""
    shown = 0
    bad_set = set(id(b) for b in bad)
    i = 0
    while i < len(lines) and shown < limit:
        if id(lines[i]) in bad_set:
            print("    " + lines[i])
            shown += 1
            j = i + 1
            while j < len(lines) and lines[j].startswith(" ") and j - i <= 8:
                print("    " + lines[j])
                j += 1
            i = j
        else:
            i += 1
    if len(bad) > shown:
        print(f"    ... {len(bad) - shown} more")


# ---------------------------------------------------------------------------------- godot


# The synthetic recording the Godot tests play (tests/godot/test_nodes_rig_capture.gd).
# ---------------------------------------------------------------------------------- room

# The room without a tape measure (issue #18): roomprobe_room on a 10-s living-room sweep, tracked
# as live, against the figures (corners within 5 cm, the ceiling within 3 cm, up within
# 0.5 degrees, a given floorplan registered within 2 cm); on the 1-s fixture, which sees one wall,
# a clear state and no file; and the tool's refusals.
ROOM_SWEEP = os.path.join(rp.BUILD, "test-data", "living_room_10s")
ROOM_LINE = re.compile(r"^corner_error_max_m=([\d.]+) ceiling_error_m=([\d.]+) up_error_deg=([\d.]+) registration_error_m=(-?[\d.]+) "
                       r"registration_rms_m=([\d.]+) corner_error_fitted_m=([\d.]+)$")
ROOM_FIGURES = ["corner_error_max_m", "ceiling_error_m", "up_error_deg", "registration_error_m", "registration_rms_m", "corner_error_fitted_m"]
ROOM_LIMITS = {"corner_error_max_m": 0.05, "ceiling_error_m": 0.03, "up_error_deg": 0.5, "registration_error_m": 0.02, "corner_error_fitted_m": 0.05}
# The two rooms' 10-s room sweep (synth --room-sweep: through the doorway into the right room),
# tracked: its corners (the partition's included) after the found world is aligned to the true one
# (the measure), ceiling and up against the same limits. Through the first camera its corners
# carry the tracker's slide by the wardrobe at 2.3 s (13 cm, docs/FIGURES.md), as its registration does: both
# are reported, not judged. The living room judges both corner figures.
ROOM_TWO_ROOMS_JUDGED = ["corner_error_fitted_m", "ceiling_error_m", "up_error_deg"]
ROOM_TWO_ROOMS_SWEEP = os.path.join(rp.BUILD, "test-data", "two_rooms_room_sweep_10s")
ROOM_EVAL_ROW = "+light (gain)"  # the coarse model as the live system runs it (roomprobe_eval's table)
ROOM_PSNR_LIMIT_DB = 0.5


def room_figures_over_limits(p_figures):
    """The figures of roomprobe_room's last line that are outside ROOM_LIMITS, each said with its limit."""
    return [f"{k}={v} (at most {ROOM_LIMITS[k]})" for k, v in p_figures.items() if not (0.0 <= v <= ROOM_LIMITS[k])]


def suite_room(opts):
    s = Suite("room")
    log = os.path.join(LOGS, "room.log")
    s.logs.append(log)
    tool = os.path.join(rp.BUILD, "bin", "roomprobe_room")
    rp.header(f"room: {rp.relpath(tool)} on a 10-s living-room sweep, the two rooms' 10-s room sweep and the 1-s fixture")
    s.ran = True
    make_fixture_recording()
    make_fixture_recording(ROOM_SWEEP, ("--no-calibration",), seconds=10, seed=1)
    out = os.path.join(rp.BUILD, "test-data", "room-out")
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    start = time.monotonic()
    found = os.path.join(out, "living_room.yaml")
    r = rp.run([tool, "--recording", ROOM_SWEEP, "--out", found], log, 900)
    m = next((ROOM_LINE.match(line) for line in r.lines if ROOM_LINE.match(line)), None)
    if r.rc != 0 or m is None or not os.path.isfile(found) or not os.path.isfile(os.path.join(out, "living_room.png")):
        s.fail(f"room: the 10-s sweep: {rp.describe_exit(r)}, figures line {'found' if m else 'missing'} (see {rp.relpath(log)})")
        rp.tail(r.lines, 20)
    else:
        figures = {k: v for k, v in zip(ROOM_FIGURES, map(float, m.groups())) if k in ROOM_LIMITS}
        print(m.group(0))
        over = room_figures_over_limits(figures)
        if over:
            s.fail("room: the 10-s sweep: " + ", ".join(over))
        else:
            s.passed += 1
        s.notes.append(m.group(0))
    # The maps with the room found against the maps with the true room (issue #18: within 0.5 dB):
    # the coarse model's variants, scored against the same true cubemaps.
    if os.path.isfile(found):
        psnr = {}
        for name, extra in (("true", []), ("found", ["--room", found])):
            r = rp.run([os.path.join(rp.BUILD, "bin", "roomprobe_eval"), "--recording", ROOM_SWEEP, "--no-dense", "--quiet", *extra],
                       f"{log}.eval-{name}", 900)
            row = next((line for line in r.lines if line.startswith(ROOM_EVAL_ROW)), None)
            psnr[name] = float(row[len(ROOM_EVAL_ROW):].split()[0]) if r.rc == 0 and row else None
        if None in psnr.values():
            s.fail(f"room: the evaluation with the true and the found room: no '{ROOM_EVAL_ROW}' row (see {rp.relpath(log)}.eval-*)")
        else:
            line = f"psnr_true_room_db={psnr['true']:.2f} psnr_found_room_db={psnr['found']:.2f} difference_db={psnr['found'] - psnr['true']:+.2f}"
            print(line)
            s.notes.append(line)
            if abs(psnr["found"] - psnr["true"]) <= ROOM_PSNR_LIMIT_DB:
                s.passed += 1
            else:
                s.fail(f"room: PSNR with the found room differs by more than {ROOM_PSNR_LIMIT_DB} dB: {line}")
    # Two rooms, the room sweep: the room through the doorway, the partition as walls.
    make_fixture_recording(ROOM_TWO_ROOMS_SWEEP, ("--no-calibration", "--room-sweep"), seconds=10, seed=1, scene="two_rooms")
    two_rooms = os.path.join(out, "two_rooms.yaml")
    r = rp.run([tool, "--recording", ROOM_TWO_ROOMS_SWEEP, "--out", two_rooms], log + ".two-rooms", 900)
    m = next((ROOM_LINE.match(line) for line in r.lines if ROOM_LINE.match(line)), None)
    corners = next((int(c.group(1)) for c in (re.search(r"^room: \w+: (\d+) corners", line) for line in r.lines) if c), 0)
    if r.rc != 0 or m is None or not os.path.isfile(two_rooms):
        s.fail(f"room: the two rooms' room sweep: {rp.describe_exit(r)}, figures line {'found' if m else 'missing'} (see {rp.relpath(log)}.two-rooms)")
        rp.tail(r.lines, 20)
    else:
        figures = {k: v for k, v in zip(ROOM_FIGURES, map(float, m.groups())) if k in ROOM_TWO_ROOMS_JUDGED}
        print("two rooms, room sweep: " + m.group(0))
        s.notes.append("two rooms, room sweep: " + m.group(0))
        over = room_figures_over_limits(figures)
        if corners != 8:
            over.append(f"{corners} corners, not the true room's 8")
        if over:
            s.fail("room: the two rooms' room sweep: " + ", ".join(over))
        else:
            s.passed += 1
    # One wall seen: a clear state, status 1, and nothing written.
    one_wall = os.path.join(out, "fixture.yaml")
    r = rp.run([tool, "--recording", FIXTURE_RECORDING, "--out", one_wall], log + ".fixture", 300)
    said = "\n".join(r.lines)
    if r.rc == 1 and "do not close a room" in said and not os.path.exists(one_wall):
        s.passed += 1
    else:
        s.fail(f"room: the 1-s fixture (one wall): {rp.describe_exit(r)}, {'no' if 'do not close a room' not in said else 'a'} clear state, "
               f"{'a file written' if os.path.exists(one_wall) else 'nothing written'}")
    # An --out that exists is kept; one that is a folder is refused; a device as --picture is refused,
    # even with --force, and never removed (issue #38: a failed write deleted /dev/full). A link to
    # /dev/full stands in for it: were it removed, only the suite's own link would go.
    kept = os.path.join(out, "kept.yaml")
    with open(kept, "w") as f:
        f.write("mine\n")
    r1 = rp.run([tool, "--recording", FIXTURE_RECORDING, "--out", kept], log + ".kept", 60)
    r2 = rp.run([tool, "--recording", FIXTURE_RECORDING, "--out", out], log + ".folder", 60)
    device = os.path.join(out, "full.png")
    os.symlink("/dev/full", device)
    r3 = rp.run([tool, "--recording", FIXTURE_RECORDING, "--out", os.path.join(out, "device.yaml"), "--picture", device, "--force"], log + ".device", 60)
    device_refused = not os.path.exists("/dev/full") or (r3.rc == 2 and os.path.islink(device) and any("is not a regular file" in line for line in r3.lines))
    if r1.rc == 2 and open(kept).read() == "mine\n" and any("exists: it is kept" in line for line in r1.lines) and r2.rc == 2 and \
            any("is a folder" in line for line in r2.lines) and device_refused:
        s.passed += 1
    else:
        s.fail(f"room: --out refusals: an existing file: {rp.describe_exit(r1)}; a folder: {rp.describe_exit(r2)}; "
               f"--picture a link to /dev/full with --force: {rp.describe_exit(r3)}, the link {'kept' if os.path.islink(device) else 'removed'}")
    s.seconds = time.monotonic() - start
    return s


FIXTURE_RECORDING = os.path.join(rp.BUILD, "test-data", "living_room_1s")
# The same second with the fisheye bracketed (every other frame 5 stops shorter), for the HDR test
# (tests/godot/test_nodes_coarse_pipeline.gd).
FIXTURE_BRACKETED = os.path.join(rp.BUILD, "test-data", "living_room_1s_bracketed")


def make_fixture_recording(p_folder=FIXTURE_RECORDING, p_extra=(), seconds=1, seed=7, scene="living_room"):
    """Renders a synthetic recording (living_room, 1 s by default) with the synth tool, once per tool build."""
    tool = os.path.join(rp.BUILD, "bin", "roomprobe_synth")
    stamp = os.path.join(p_folder, ".made-by")
    if not os.path.exists(tool):
        return
    made_by = f"{os.path.getmtime(tool)}"
    if os.path.exists(stamp) and open(stamp).read() == made_by:
        return
    shutil.rmtree(p_folder, ignore_errors=True)
    log = os.path.join(LOGS, f"fixture-{os.path.basename(p_folder)}.log")
    r = rp.run([tool, "--scene", scene, "--out", p_folder, "--seconds", str(seconds), "--seed", str(seed), *p_extra], log, 900)
    if r.rc == 0:
        with open(stamp, "w") as f:
            f.write(made_by)
    else:
        print(f"    (the fixture recording could not be made; see {log})")


# The fixture's RGB-D stream as an OpenNI .oni, which the live-rig tests play as if from a depth
# camera (tests/godot/test_nodes_live_rig.gd).
FIXTURE_ONI = FIXTURE_RECORDING + ".oni"


def make_fixture_oni():
    """Writes the fixture recording's RGB-D frames as an .oni with build/bin/roomprobe_oni, once per recording."""
    tool = os.path.join(rp.BUILD, "bin", "roomprobe_oni")
    stamp = os.path.join(FIXTURE_RECORDING, ".made-by")
    if not os.path.exists(tool) or not os.path.exists(stamp):
        return
    if os.path.exists(FIXTURE_ONI) and os.path.getmtime(FIXTURE_ONI) >= max(os.path.getmtime(stamp), os.path.getmtime(tool)):
        return
    if os.path.exists(FIXTURE_ONI):
        os.remove(FIXTURE_ONI)
    log = os.path.join(LOGS, "fixture-oni.log")
    r = rp.run([tool, "--recording", FIXTURE_RECORDING, "--out", FIXTURE_ONI], log, 300)
    if r.rc != 0:
        print(f"    (the fixture .oni could not be made; see {log})")


def suite_godot(opts, rendering, allow_empty):
    name = "rendering" if rendering else "godot"
    s = Suite(name)
    s.logs.append(os.path.join(LOGS, f"{name}.log"))
    if not rendering:
        make_fixture_recording()
        make_fixture_recording(FIXTURE_BRACKETED, ("--exposure", "bracket", "--no-calibration"))
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
        artifacts = os.path.join(LOGS, "rendering")
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
        runs.append((mobile, os.path.join(LOGS, f"{name}-mobile.log")))
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


def sanitized_project(opts, s):
    """(the scratch copy of the project that loads the sanitized libraries, imported; the environment
    Godot runs in), or (None, None) with a failure recorded in s.

    build/<target>-asan|tsan/godot_project: a fresh copy of godot_project/ without its libraries
    (fresh_project_copy, as the editor suite's), whose two .gdextension files name the sanitized
    library and the binding's test extension from build/<target>-asan|tsan/bin/ (linked into their
    bin/). Godot itself is not instrumented: the sanitizer's runtime goes in LD_PRELOAD, after
    tests/sanitize/no_deepbind.c's library; the tests find the repository through $ROOMPROBE_REPO
    (test_case.gd's repo_path). A report in the import fails the suite as one in the run does.
    """
    build = os.path.join(rp.BUILD, sanitized_build_dir(opts))
    target = sanitized_build_dir(opts).split("-")[0]
    libs = [os.path.join(build, "bin", f"{lib}.linux.{target}.x86_64.so") for lib in ("libroomprobe", "libroomprobe_binding_test")]
    missing = [lib for lib in libs if not os.path.isfile(lib)]
    if missing:
        s.fail(f"godot: no sanitized {', '.join(rp.relpath(m) for m in missing)} (scons sanitize={opts.sanitize} sanitize_godot=yes)")
        print(f"FAILED: {s.failures[-1]}")
        return None, None
    project = os.path.join(build, "godot_project")
    fresh_project_copy(project, leave_out=("*.so",))
    for gdextension, lib in zip(("addons/roomprobe/roomprobe.gdextension", "tests/binding/roomprobe_binding_test.gdextension"), libs):
        folder = os.path.dirname(gdextension)
        os.makedirs(os.path.join(project, folder, "bin"), exist_ok=True)
        os.symlink(lib, os.path.join(project, folder, "bin", os.path.basename(lib)))
        path = os.path.join(project, gdextension)
        with open(path) as f:
            text = f.read()
        # Every Linux entry (debug and release) names the one sanitized library.
        text, n = re.subn(r'^(linux\.\w+\.x86_64 = )"[^"]*"$', lambda m: f'{m.group(1)}"res://{folder}/bin/{os.path.basename(lib)}"', text, flags=re.M)
        if n == 0:
            s.fail(f"godot: {gdextension} names no linux.*.x86_64 library to replace")
            print(f"FAILED: {s.failures[-1]}")
            return None, None
        with open(path, "w") as f:
            f.write(text)
    # ROOMPROBE_SANITIZER: tests that pace a recording by the scene's clock slow it (test_case.gd's sanitizer()).
    env = dict(os.environ, **sanitizer_env(opts, SANITIZER_GODOT_ENV), ROOMPROBE_REPO=rp.REPO, ROOMPROBE_SANITIZER=opts.sanitize)
    runtimes = sanitizer_runtimes(libs[0])
    no_deepbind = os.path.join(build, "bin", "librp_no_deepbind.so")
    if not runtimes or not os.path.isfile(no_deepbind):
        s.fail(f"godot: {rp.relpath(libs[0])} needs no sanitizer runtime (built without sanitize=?)" if not runtimes else
               f"godot: no {rp.relpath(no_deepbind)} (scons sanitize={opts.sanitize} sanitize_godot=yes)")
        print(f"FAILED: {s.failures[-1]}")
        return None, None
    # Godot's GDExtension loader asks for RTLD_DEEPBIND, which the runtimes refuse: no_deepbind's
    # dlopen drops it, so it comes before them (tests/sanitize/no_deepbind.c).
    env["LD_PRELOAD"] = " ".join([no_deepbind] + runtimes + ([os.environ["LD_PRELOAD"]] if os.environ.get("LD_PRELOAD") else []))

    # The import, under the sanitizer too: the editor loads both libraries and writes .godot/.
    log = os.path.join(LOGS, "godot-import.log")
    s.logs.append(log)
    cmd = rp.import_command(project)
    import_env = dict(env, **sanitizer_env(opts, SANITIZER_GODOT_ENV, SANITIZER_IMPORT_ENV))
    rp.header(f"godot: import of the scratch copy: {shlex.join(cmd)} ({sanitizer_env_text(opts, godot_env_shown(import_env))})")
    r = rp.run(cmd, log, IMPORT_TIMEOUT * 4, env=import_env)
    s.seconds += r.seconds
    kept, dropped = rp.filter_noise(r.lines)
    start, report = sanitizer_report(kept)
    bad = [line for line in kept[:start] if EDITOR_BAD.search(line)]
    if report or r.rc != 0 or r.timed_out or bad:
        why = sanitizer_summary(report) if report else rp.describe_exit(r) if r.rc or r.timed_out else f"{len(bad)} error line(s)"
        s.fail(f"godot: the import of {rp.relpath(project)}: {why}")
        print(f"FAILED: the import: {why} ({rp.fmt_duration(r.seconds)}); see {rp.relpath(log)}")
        show_with_context(kept, bad)
        rp.tail(report or ([] if bad else kept), 80)
        return None, None
    print(f"ok ({rp.fmt_duration(r.seconds)}){noise_note(dropped)}")
    return project, env


def sanitizer_runtimes(library):
    """The sanitizer runtimes the library needs (readelf -d's NEEDED), ASan's first: it must be
    loaded before any other library that allocates (UBSan's runtime does)."""
    r = rp.run(["readelf", "-d", library])
    found = [m.group(1) for m in map(SANITIZER_RUNTIME.search, r.lines) if m and "(NEEDED)" in m.string]
    return sorted(found, key=lambda lib: not lib.startswith("libasan"))


def godot_env_shown(env):
    """The variables of env that the sanitized Godot run adds, for the header."""
    return {k: env[k] for k in ("LD_PRELOAD", "ASAN_OPTIONS", "UBSAN_OPTIONS", "TSAN_OPTIONS", "ROOMPROBE_REPO", "ROOMPROBE_SANITIZER") if k in env}


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


# ---------------------------------------------------------------------------------- summary


def finish(results, start):
    print("\n=== summary")
    width = max([len(s.name) for s in results] + [5])
    for s in results:
        status = "FAILED" if s.failed else "ok" if s.ran else "not run"
        line = f"{s.name:<{width}}  {status:<7} {s.passed} passed, {s.failed} failed, {s.skipped} skipped  ({rp.fmt_duration(s.seconds)})"
        print(line)
        for f in s.failures:
            print(f"{'':<{width}}    failed: {f}")
        for n in s.notes:
            print(f"{'':<{width}}    {n}")
    passed = sum(s.passed for s in results)
    failed = sum(s.failed for s in results)
    skipped = sum(s.skipped for s in results)
    print(f"total time {rp.fmt_duration(time.monotonic() - start)}")
    if failed:
        logs = sorted({rp.relpath(log) for s in results if s.failed for log in s.logs})
        print(f"logs: {rp.relpath(LOGS)}/ (failed: {', '.join(logs)})")
    print(f"{passed} passed, {failed} failed" + (f", {skipped} skipped" if skipped else ""), flush=True)
    return 0 if failed == 0 else 1


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:
        print("\ninterrupted", file=sys.stderr)
        sys.exit(130)
