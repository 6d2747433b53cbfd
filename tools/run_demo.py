#!/usr/bin/env python3
"""RoomProbe's demo: ./roomprobe demo [OPTIONS] runs it inside the toolchain.

  1. builds the extension and tools;
  2. synthesises the living_room recording once (out/demo/recording/, 6 s; kept for later runs);
  3. plays it in res://demo_scenes/main.tscn: the RGB image as the background, the AR camera on
     the recording's ground-truth poses, a mirror sphere, a glass sphere and a gold torus on the
     table, each lit by a RoomProbe's live environment map;
  4. writes to out/demo/: the AR frames (Godot's Movie Maker, frames/frame*.png, 15 fps, under
     Xvfb on Mesa's CPU Vulkan), cubemap.exr and cubemap_net.png of the mirror sphere's last map,
     and evaluation.txt (roomprobe_eval: the paper's baseline against the coarse variants).

The paper's figures: --scene NAME plays the same recording with a figure's objects instead
(demo_scenes/figures/figure_scenes.gd): mirror_teapot (Figure 1), water_bottle (Figure 7, top),
prt_mannequin (Figure 7, middle; the ceiling light switches on half-way), metal_teapots
(Figure 7, bottom), chrome_sphere (Figure 11). Its frames, cubemap and picture.png (the frame at
3.7 s, cropped to the objects and doubled; prt_mannequin also picture_before.png, before the
light switches on) go to out/demo/NAME/; no evaluation.

The room without a tape measure: --auto-room plays a 10-s sweep (out/demo/recording_10s/) with
CoarseRoomModel's Automatic floorplan source: the room is found from the sweep while it plays, and
out/demo/auto_room/ gets its frames, room.yaml (the room found) and evaluation.txt (roomprobe_eval
with that room, scored against the recording's truth).

Where it runs:
  default     Movie Maker under xvfb-run (no display needed), then quits
  --window    live in a window on $DISPLAY, until the window is closed (no frames written);
              with --once, it quits when the recording has played (a real-time run, measured)
"""

import argparse
import os
import re
import shlex
import shutil
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import rp_godot as rp  # noqa: E402

OUT = os.path.join(rp.REPO, "out", "demo")
RECORDING = os.path.join(OUT, "recording")
FRAMES = os.path.join(OUT, "frames")
SCENE_OUT = OUT  # the scene's outputs: OUT for main, OUT/NAME for a figure
FIGURES = ["mirror_teapot", "water_bottle", "prt_mannequin", "metal_teapots", "chrome_sphere"]
SCENE = "res://demo_scenes/main.tscn"
FPS = 15
SIZE = "640x480"  # the synthetic rig's RGB camera: the background and the AR camera line up
SECONDS = 6
BAD = re.compile(r"ERROR|Failed to|leaked")


def main():
    ap = argparse.ArgumentParser(prog="./roomprobe demo", description=__doc__.split("\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__.split("\n\n", 1)[1])
    ap.add_argument("--window", action="store_true", help="play live in a window on $DISPLAY instead of writing frames")
    ap.add_argument("--once", action="store_true", help="with --window: quit when the recording has played (to measure a real-time run)")
    ap.add_argument("--no-build", action="store_true", help="skip the build")
    ap.add_argument("--no-eval", action="store_true", help="skip the evaluation")
    ap.add_argument("--scons-args", metavar="ARGS", help="arguments for scons instead of '-j<nproc>' (also $ROOMPROBE_SCONS_ARGS)")
    ap.add_argument("--scene", default="main", choices=["main"] + FIGURES,
                    help="main (the three objects) or one of the paper's figures")
    ap.add_argument("--auto-room", action="store_true", help="find the room from a 10-s sweep instead of the recording's room.yaml")
    ap.add_argument("--backend", default="cpu", choices=["cpu", "vulkan", "auto"],
                    help="where the kernels with a GPU twin run (RigCapture.compute_backend; vulkan runs on lavapipe here)")
    opts = ap.parse_args()
    os.makedirs(OUT, exist_ok=True)
    global SCENE_OUT, FRAMES, RECORDING, SECONDS
    if opts.auto_room:
        if opts.scene != "main":
            ap.error("--auto-room plays the main scene")
        SCENE_OUT = os.path.join(OUT, "auto_room")
        FRAMES = os.path.join(SCENE_OUT, "frames")
        RECORDING, SECONDS = os.path.join(OUT, "recording_10s"), 10  # a 6-s sweep sees two walls
    if opts.scene != "main":
        SCENE_OUT = os.path.join(OUT, opts.scene)
        FRAMES = os.path.join(SCENE_OUT, "frames")
        opts.no_eval = True  # the evaluation is of the recording, the same for every scene
    os.makedirs(SCENE_OUT, exist_ok=True)
    if opts.window and not os.environ.get("DISPLAY"):
        rp.die("--window needs a display ($DISPLAY is not set); without it the demo writes frames under Xvfb")
    if not opts.window and not rp.have("xvfb-run"):
        rp.die("the demo needs xvfb-run (package xvfb) to write frames without a display; or use --window")

    if not opts.no_build and not build(opts):
        return 1
    if not synthesise():
        return 1
    import_project()
    if not play(opts.window, opts.once, opts.scene, opts.auto_room, opts.backend):
        return 1
    room = os.path.join(SCENE_OUT, "room.yaml") if opts.auto_room else None
    if opts.auto_room and not os.path.exists(room):
        print("demo: no room was found from the sweep (see the demo's log), so no evaluation with it")
    elif not opts.no_eval and not evaluate(room):
        return 1
    rp.header("demo: outputs")
    summary = getattr(play, "summary", "")
    frames = sorted(f for f in os.listdir(FRAMES) if f.endswith(".png")) if os.path.isdir(FRAMES) else []
    print(f"  AR frames:     {rp.relpath(FRAMES)}/ ({len(frames)} PNG at {FPS} fps)")
    for name in ["cubemap.exr", "cubemap_net.png", "evaluation.txt", "room.yaml", "picture.png", "picture_before.png"]:
        path = os.path.join(SCENE_OUT, name)
        if (name.startswith("picture") or name == "room.yaml") and not os.path.exists(path):
            continue
        print(f"  {name + ':':<14} {rp.relpath(path) if os.path.exists(path) else '(missing)'}")
    # The last line: the figures of the run, key=value (main-thread time per frame, latency, drops).
    print(summary.replace("demo: summary ", "summary: ") if summary else "summary: (the scene printed none)")
    return 0


def build(opts):
    cmd = rp.scons_command([], opts.scons_args)
    rp.header(f"build: {shlex.join(cmd)}")
    r = rp.run(cmd, os.path.join(OUT, "build.log"), timeout=3600, echo=lambda line: print("    " + line, flush=True))
    if r.rc != 0:
        print(f"demo: the build failed ({rp.describe_exit(r)}); log: {rp.relpath(os.path.join(OUT, 'build.log'))}")
        return False
    return True


def synthesise():
    """The recording, once: a stamp names the arguments, so a changed demo makes it again."""
    args = ["--scene", "living_room", "--seconds", str(SECONDS), "--seed", "1", "--no-calibration"]
    stamp = os.path.join(RECORDING, ".made-with")
    if os.path.exists(stamp) and open(stamp).read() == " ".join(args):
        rp.header(f"recording: {rp.relpath(RECORDING)} (already made)")
        return True
    shutil.rmtree(RECORDING, ignore_errors=True)
    cmd = [os.path.join(rp.BUILD, "bin", "roomprobe_synth")] + args + ["--out", RECORDING]
    rp.header(f"recording: {shlex.join(cmd)}")
    r = rp.run(cmd, os.path.join(OUT, "synth.log"), timeout=1800, echo=lambda line: print("    " + line, flush=True))
    if r.rc != 0:
        print(f"demo: synthesising the recording failed ({rp.describe_exit(r)}); log: {rp.relpath(os.path.join(OUT, 'synth.log'))}")
        return False
    with open(stamp, "w") as f:
        f.write(" ".join(args))
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


def play(window, once=False, scene="main", auto_room=False, backend="cpu"):
    cmd = rp.godot_base_args(rendering=True) + ["--resolution", SIZE]
    if not window:
        shutil.rmtree(FRAMES, ignore_errors=True)
        os.makedirs(FRAMES)
        cmd = rp.xvfb_prefix() + cmd + ["--write-movie", os.path.join(FRAMES, "frame.png"), "--fixed-fps", str(FPS)]
    cmd += [SCENE, "--", "--recording", RECORDING, "--out", SCENE_OUT, "--scene", scene] + ([] if window and not once else ["--quit-at-end"])
    cmd += ["--auto-room"] if auto_room else []
    cmd += ["--backend", backend]
    rp.header(f"play ({'window' if window else 'Movie Maker under Xvfb'}): {shlex.join(cmd)}")
    log = os.path.join(SCENE_OUT, "demo.log")
    noise = rp.NoiseFilter()
    r = rp.run(cmd, log, timeout=None if window else 1800,
               echo=lambda line: [print("    " + k, flush=True) for k in noise.feed(line)])
    for k in noise.flush():
        print("    " + k)
    print(f"demo: Godot ended: {rp.describe_exit(r)} after {rp.fmt_duration(r.seconds)}; log: {rp.relpath(log)}")
    play.summary = next((line.strip() for line in reversed(r.lines) if line.strip().startswith("demo: summary ")), "")
    room = next((line.strip() for line in reversed(r.lines) if line.strip().startswith("demo: room_found=")), "")
    if room and play.summary:
        play.summary += room.replace("demo: ", " ", 1)
    if any(re.match(r'^WARNING: \d+ RIDs of type "Texture" were leaked', line) for line in r.lines):
        print("demo: the Texture RID leak at exit is Godot 4.6's reflection-atlas bug (godotengine/godot#122498),"
              " set off by the scene's ReflectionProbe; not RoomProbe's")
    return r.rc == 0


def evaluate(room=None):
    cmd = [os.path.join(rp.BUILD, "bin", "roomprobe_eval"), "--recording", RECORDING] + (["--room", room] if room else [])
    rp.header(f"evaluation: {shlex.join(cmd)}")
    out = os.path.join(SCENE_OUT, "evaluation.txt")
    r = rp.run(cmd, out, timeout=1800, echo=lambda line: print("    " + line, flush=True))
    if r.rc != 0:
        print(f"demo: the evaluation failed ({rp.describe_exit(r)}); log: {rp.relpath(out)}")
    return r.rc == 0


if __name__ == "__main__":
    try:
        sys.exit(main())
    except KeyboardInterrupt:
        sys.exit(130)
