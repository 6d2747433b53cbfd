"""The host and package suites: the results that ./roomprobe test's host runs wrote, read back."""

import os
import re

import rp_godot as rp

from . import common
from .common import RESULT, Suite

HOST_SUMMARY = re.compile(r"^(?:HOST|PACKAGE)_TESTS (\d+) passed, (\d+) failed in ([\d.]+) s$")


def suite_host(opts, name="host"):
    """The results tests/host/test_paths.sh wrote ('[PASS] host::test', '[FAIL] host::test: why', then
    'HOST_TESTS N passed, N failed in S s'). ./roomprobe test runs it on the host first, since the
    paths it tests are not visible in here; its output has been printed already."""
    s = Suite(name)
    s.logs.append(os.path.join(common.LOGS, f"{name}.log"))
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
