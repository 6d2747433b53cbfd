#!/usr/bin/env python3
"""RoomProbe's demo: ./roomprobe demo [OPTIONS] runs it inside the toolchain.

Builds the extension, imports godot_project/ once (so that the extension loads), then runs
res://demo_scenes/main.tscn, which prints what the RoomProbe extension registered (classes,
properties, signals, configuration warnings) and shows a room with a mirror sphere.

Where it runs:
  default     in a window when $DISPLAY is set, else headless (report only, then quit)
  --window    in a window on $DISPLAY (Vulkan), until the window is closed
  --xvfb      under xvfb-run (Vulkan on lavapipe); saves out/demo/screenshot.png and quits
  --headless  no window: the report, some frames, quit
"""

import argparse
import os
import re
import shlex
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import rp_godot as rp  # noqa: E402

OUT = os.path.join(rp.REPO, "out", "demo")
SCENE = "res://demo_scenes/main.tscn"
XVFB_SCREEN = "-screen 0 1280x720x24"
BAD = re.compile(r"ERROR|Failed to|leaked")


def main():
    ap = argparse.ArgumentParser(prog="./roomprobe demo", description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__.split("\n\n", 2)[2])
    mode = ap.add_mutually_exclusive_group()
    mode.add_argument("--window", action="store_true", help="run in a window on $DISPLAY")
    mode.add_argument("--xvfb", action="store_true", help="run under xvfb-run and save out/demo/screenshot.png")
    mode.add_argument("--headless", action="store_true", help="run without a window")
    ap.add_argument("--frames", type=int, metavar="N",
                    help="quit after N frames (default: 120 headless, until closed in a window)")
    ap.add_argument("--no-build", action="store_true", help="skip the build")
    ap.add_argument("--scons-args", metavar="ARGS", help="arguments for scons instead of '-j<nproc>' (also $ROOMPROBE_SCONS_ARGS)")
    opts = ap.parse_args()
    os.makedirs(OUT, exist_ok=True)

    if opts.xvfb:
        mode_name = "xvfb"
    elif opts.window or (not opts.headless and os.environ.get("DISPLAY")):
        mode_name = "window"
    else:
        mode_name = "headless"
    if mode_name == "window" and not os.environ.get("DISPLAY"):
        rp.die("--window needs a display ($DISPLAY is not set); try --xvfb or --headless")
    if mode_name == "xvfb" and not rp.have("xvfb-run"):
        rp.die("--xvfb needs xvfb-run (package xvfb)")

    if not opts.no_build and not build(opts):
        return 1
    import_project()

    # The demo makes no sound: every mode uses the dummy audio driver (no ALSA noise).
    godot_args = rp.godot_base_args(rendering=mode_name != "headless")
    user = []
    frames = opts.frames
    if mode_name == "headless" and frames is None:
        frames = 120
    if frames is not None:
        user += ["--frames", str(frames)]
    cmd = godot_args + [SCENE]
    if mode_name == "xvfb":
        shot = os.path.join(OUT, "screenshot.png")
        if os.path.exists(shot):
            os.remove(shot)
        user += ["--screenshot", shot]
        cmd = rp.xvfb_prefix(XVFB_SCREEN) + cmd + ["--resolution", "1280x720"]
    if user:
        cmd += ["--"] + user
    rp.header(f"demo ({mode_name}): {shlex.join(cmd)}")
    log = os.path.join(OUT, "demo.log")
    noise = rp.NoiseFilter()
    r = rp.run(cmd, log, timeout=None if mode_name == "window" else 600,
               echo=lambda line: [print(k, flush=True) for k in noise.feed(line)])
    for k in noise.flush():
        print(k)
    print(f"\ndemo: Godot ended: {rp.describe_exit(r)} after {rp.fmt_duration(r.seconds)}; log: {rp.relpath(log)}")
    if any(re.match(r'^WARNING: \d+ RIDs of type "Texture" were leaked', line) for line in r.lines):
        print("demo: the Texture RID leak at exit is Godot 4.6's reflection-atlas bug (godotengine/godot#122498),"
              " set off by the scene's ReflectionProbe; not RoomProbe's")
    if mode_name == "xvfb":
        shot = os.path.join(OUT, "screenshot.png")
        if os.path.exists(shot):
            print(f"demo: screenshot: {rp.relpath(shot)}")
        else:
            print("demo: no screenshot was written")
            return 1
    return 0 if r.rc == 0 else 1


def build(opts):
    cmd = rp.scons_command([], opts.scons_args)
    rp.header(f"build: {shlex.join(cmd)}")
    if rp.sconstruct_missing():
        print("no SConstruct yet: skipping the build (the demo shows what is there)")
        return True
    r = rp.run(cmd, os.path.join(OUT, "build.log"), timeout=3600, echo=lambda line: print("    " + line, flush=True))
    if r.rc != 0:
        print(f"demo: the build failed ({rp.describe_exit(r)}); log: {rp.relpath(os.path.join(OUT, 'build.log'))}")
        return False
    return True


def import_project():
    cmd = rp.import_command()
    rp.header(f"import: {shlex.join(cmd)}")
    r = rp.run(cmd, os.path.join(OUT, "import.log"), timeout=300)
    kept, _ = rp.filter_noise(r.lines)
    bad = [line for line in kept if BAD.search(line)]
    if r.rc != 0 or bad:
        print(f"demo: the import reported problems ({rp.describe_exit(r)}); carrying on:")
        for line in bad[:30]:
            print("    " + line)
    else:
        print(f"ok ({rp.fmt_duration(r.seconds)})")


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:
        sys.exit(130)
