#!/usr/bin/env python3
"""./roomprobe soak [--frames N] [--recording DIR] [--probe-size N] [--sanitize address]

Runs inside the toolchain. Builds roomprobe_bench (target=release, or the AddressSanitizer build
in build/debug-asan/ with --sanitize address) and runs its soak: the recording played back and
forth through the engine with every stage and a probe. Without --recording it plays the test
suite's 1-s living room (build/test-data/living_room_1s), synthesised first when missing.
Under --sanitize address LeakSanitizer looks for leaks when the program exits: the verdict is then
the sanitizers' (a memory error, undefined behaviour or a leak fails the run), since memory and
time under ASan are its own. Otherwise the output ends with the benchmark's 'summary:' line and
the status is the soak's verdict.
"""

import argparse
import os
import subprocess
import sys

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BUILD = os.path.join(REPO, "build")
DEFAULT_RECORDING = os.path.join(BUILD, "test-data", "living_room_1s")


def default_recording():
    """The 1-s living room the Godot tests play (tools/run_tests.py makes it with the same command)."""
    if not os.path.isfile(os.path.join(DEFAULT_RECORDING, "rig.yaml")):
        print(f"soak: synthesising {os.path.relpath(DEFAULT_RECORDING, REPO)}", flush=True)
        subprocess.run(["scons", "-Q", f"-j{os.cpu_count() or 2}", "build/bin/roomprobe_synth"], cwd=REPO, check=True,
                       stdout=subprocess.DEVNULL)
        subprocess.run([os.path.join(BUILD, "bin", "roomprobe_synth"), "--scene", "living_room", "--out", DEFAULT_RECORDING,
                        "--seconds", "1", "--seed", "7"], cwd=REPO, check=True, stdout=subprocess.DEVNULL)
    return DEFAULT_RECORDING


def main():
    ap = argparse.ArgumentParser(prog="./roomprobe soak", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--frames", type=int, default=50000)
    ap.add_argument("--recording")
    ap.add_argument("--probe-size", type=int)
    ap.add_argument("--warmup-frames", type=int, help="frames before memory and time are judged (default: a fifth)")
    ap.add_argument("--sanitize", choices=["address"])
    opts = ap.parse_args()
    if opts.frames < 1:
        ap.error("--frames needs a positive number")
    recording = opts.recording or default_recording()
    if opts.sanitize:
        program, build = os.path.join(BUILD, "debug-asan", "bin", "roomprobe_bench"), ["sanitize=address"]
        # Leaks are looked for at exit; halt_on_error stops at the first memory error.
        env = dict(os.environ, ASAN_OPTIONS="detect_leaks=1 halt_on_error=1", UBSAN_OPTIONS="halt_on_error=1 print_stacktrace=1")
    else:
        program, build, env = os.path.join(BUILD, "bin", "roomprobe_bench"), ["target=release"], None
    made = subprocess.run(["scons", "-Q", f"-j{os.cpu_count() or 2}", *build, os.path.relpath(program, REPO)], cwd=REPO,
                          stdout=subprocess.DEVNULL)
    if made.returncode != 0:
        sys.exit(f"soak: building {os.path.relpath(program, REPO)} failed (scons {' '.join(build)})")
    cmd = [program, "soak", "--recording", recording, "--frames", str(opts.frames)]
    if opts.probe_size:
        cmd += ["--probe-size", str(opts.probe_size)]
    if opts.warmup_frames:
        cmd += ["--warmup-frames", str(opts.warmup_frames)]
    print("soak: " + " ".join(cmd), flush=True)
    if not opts.sanitize:
        sys.exit(subprocess.run(cmd, cwd=REPO, env=env).returncode)
    # Under AddressSanitizer memory and time are the sanitizer's, not the program's: the verdict is
    # the sanitizers' (a memory error, undefined behaviour, or a leak at exit), and the run's end.
    run = subprocess.run(cmd, cwd=REPO, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, errors="replace")
    print(run.stdout, end="")
    reports = [line for line in run.stdout.splitlines()
               if "ERROR: LeakSanitizer" in line or "ERROR: AddressSanitizer" in line or ": runtime error: " in line]
    finished = any(line.startswith("summary: mode=soak") for line in run.stdout.splitlines())
    verdict = "clean" if finished and not reports else ("; ".join(reports[:3]) or f"no summary line (status {run.returncode})")
    print(f"soak under AddressSanitizer and LeakSanitizer: {verdict}")
    sys.exit(0 if verdict == "clean" else 1)


if __name__ == "__main__":
    main()
