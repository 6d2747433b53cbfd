"""The summary at the end: one line per suite, its failures and notes, then 'N passed, N failed'."""

import time

import rp_godot as rp

from . import common

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
        print(f"logs: {rp.relpath(common.LOGS)}/ (failed: {', '.join(logs)})")
    print(f"{passed} passed, {failed} failed" + (f", {skipped} skipped" if skipped else ""), flush=True)
    return 0 if failed == 0 else 1
