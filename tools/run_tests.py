#!/usr/bin/env python3
"""RoomProbe's test runner: ./roomprobe test [OPTIONS] runs it inside the toolchain.

Suites, in order (see tests/README.md):
  host       tests/host/test_paths.sh: ./roomprobe's path arguments from outside the clone; run on the
             host by ./roomprobe test before this runner, which reports them (--host-results)
  build      scons -j<nproc> tests=yes (or the arguments in $ROOMPROBE_SCONS_ARGS / --scons-args)
  core       every build/tests/*_tests (doctest) program
  fuzz       every libFuzzer target of tests/fuzz/ for a few seconds on its corpus (tools/fuzz/fuzz.py;
             clang builds the core again into build/fuzz/)
  soak       roomprobe_bench soak: the fixture back and forth through the engine for 2000 frames;
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

import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
# The runner lives in tools/testrun/, one module per concern; this file stays ./roomprobe test's entry point.
from testrun import cli  # noqa: E402


def main():
    return cli.main(__doc__.split("\n")[0])


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:
        print("\ninterrupted", file=sys.stderr)
        sys.exit(130)
