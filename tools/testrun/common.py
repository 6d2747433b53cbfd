"""What every suite shares: the suite list, the log folder, the timeouts, Suite, and output helpers."""

import os
import re
import shutil

import rp_godot as rp

SUITES = ["host", "package", "build", "core", "fuzz", "soak", "room", "editor", "godot", "rendering"]
# Read as common.LOGS when used, never imported by name: --sanitize moves it (cli.main).
LOGS = os.path.join(rp.BUILD, "test-logs")

BUILD_TIMEOUT = 3600
CORE_TIMEOUT = 900      # per test program
IMPORT_TIMEOUT = 300
GODOT_TIMEOUT = 900
RENDERING_TIMEOUT = 900

# Lines that fail the editor suite (after the known noise is filtered out).
EDITOR_BAD = re.compile(r"ERROR|SCRIPT ERROR|Failed to|leaked")
# A test's result line (tests/godot/run_tests.gd, tests/host/harness.sh).
RESULT = re.compile(r"^\[(PASS|FAIL|SKIP)\] (\S+)(?:: (.*))?$")


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


def fresh_project_copy(dest, leave_out=()):
    """A scratch copy of godot_project/ at dest, as on a fresh clone: no .godot/, the symlinked folders
    (tests/, demo_scenes/, the shaders) copied; leave_out: more names (glob patterns) not copied."""
    shutil.rmtree(dest, ignore_errors=True)
    shutil.copytree(rp.PROJECT, dest, symlinks=False, ignore=shutil.ignore_patterns(".godot", *leave_out))


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
