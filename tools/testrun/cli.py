"""The command line: the options, then the chosen suites in order, then the summary."""

import argparse
import os
import time

import rp_godot as rp

from . import common
from .common import SUITES
from .editor import suite_editor
from .godot import suite_godot
from .host import suite_host
from .native import suite_build, suite_core, suite_fuzz, suite_soak
from .report import finish
from .room import suite_room
from .sanitize import SANITIZER_ENV, sanitized_build_dir


def parse_args(description):
    """The options, checked; ./roomprobe test --help shows them."""
    # No abbreviated options: ./roomprobe reads --suite and --filter itself to run the host suite.
    ap = argparse.ArgumentParser(prog="./roomprobe test", description=description,
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
    return opts


def main(description):
    """Runs the chosen suites in order; returns the exit status (0 only when nothing failed)."""
    opts = parse_args(description)
    if opts.sanitize:
        common.LOGS = os.path.join(common.LOGS, sanitized_build_dir(opts))  # the normal run's logs stay as they are

    os.makedirs(common.LOGS, exist_ok=True)
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
