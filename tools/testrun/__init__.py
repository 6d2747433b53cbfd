"""RoomProbe's test runner, split by concern; tools/run_tests.py is its entry point (./roomprobe test)."""
