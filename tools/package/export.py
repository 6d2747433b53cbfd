#!/usr/bin/env python3
"""The demo as an exported Linux app: ./roomprobe export (inside the toolchain, after ./roomprobe package).

Assembles a project in build/export-project/ from what a user would have: godot_project's
project.godot and export_presets.cfg, the demo scenes, the packaged addon (build/package/addons/
roomprobe, the Debian 12 library with its libraries bundled) and a recording zipped into
res://recordings/demo.zip; imports it, exports it with Debian's templates (the preset's
custom_template) and checks that the app folder carries the library and every bundled one.
The last line is one key=value summary.
"""

import argparse
import os
import shutil
import subprocess
import sys
import time
import zipfile

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
APP = "roomprobe_demo.x86_64"


def zip_folder(folder, out):
    """The recording as one zip with one top-level folder: Godot exports it as is (it imports no zip)."""
    name = os.path.basename(os.path.normpath(folder))
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as z:
        for root, _, files in sorted(os.walk(folder)):
            for f in sorted(f for f in files if f != ".made-with"):
                path = os.path.join(root, f)
                z.write(path, os.path.join(name, os.path.relpath(path, folder)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--addon", default="build/package/addons/roomprobe")
    ap.add_argument("--recording", help="the recording folder to carry in the pack (default: a 2-s synthetic living "
                    "room, made once into build/export-recording)")
    ap.add_argument("--project", default="build/export-project")
    ap.add_argument("--out", default="out/export")
    args = ap.parse_args()

    start = time.monotonic()
    if not args.recording:
        args.recording = os.path.join(REPO, "build", "export-recording")
        synth = ["--scene", "living_room", "--seconds", "2", "--seed", "1", "--no-calibration", "--hdri", "none"]
        stamp = os.path.join(args.recording, ".made-with")
        if not (os.path.exists(stamp) and open(stamp).read() == " ".join(synth)):
            shutil.rmtree(args.recording, ignore_errors=True)
            print("export: synthesising a 2-s recording to carry (build/export-recording)", flush=True)
            subprocess.run([os.path.join(REPO, "build", "bin", "roomprobe_synth")] + synth + ["--out", args.recording],
                           check=True, stdout=subprocess.DEVNULL)
            open(stamp, "w").write(" ".join(synth))
    project = args.project
    shutil.rmtree(project, ignore_errors=True)
    os.makedirs(os.path.join(project, "recordings"))
    for f in ("project.godot", "export_presets.cfg"):
        shutil.copyfile(os.path.join(REPO, "godot_project", f), os.path.join(project, f))
    shutil.copytree(os.path.join(REPO, "demo_scenes"), os.path.join(project, "demo_scenes"))
    shutil.copytree(args.addon, os.path.join(project, "addons", "roomprobe"))
    zip_folder(args.recording, os.path.join(project, "recordings", "demo.zip"))

    out = os.path.abspath(args.out)
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    log = os.path.join(out, "export.log")
    with open(log, "w") as f:
        # The first run imports the project (and loads the extension), the second exports it.
        for step in (["--import"], ["--export-release", "Linux", os.path.join(out, APP)]):
            r = subprocess.run(["godot", "--headless", "--path", project] + step, stdout=f, stderr=subprocess.STDOUT)
            if r.returncode != 0 and step[0] != "--import":
                sys.exit(f"export: godot {' '.join(step)} failed; see {log}")
    bundled = [l.split("\t")[0] for l in open(os.path.join(args.addon, "bin", "BUNDLED.txt")) if "\t" in l]
    missing = [b for b in ["libroomprobe.linux.release.x86_64.so", APP, APP.replace(".x86_64", ".pck")] + bundled
               if not os.path.exists(os.path.join(out, b))]
    if missing:
        sys.exit(f"export: the app folder lacks {', '.join(missing[:5])}{' ...' if len(missing) > 5 else ''}; see {log}")
    size = sum(os.path.getsize(os.path.join(r, f)) for r, _, fs in os.walk(out) for f in fs)
    print(f"export: {out}/{APP} (run it with --headless -- --quit-at-end, or in a window)")
    print(f"summary: export_s={time.monotonic() - start:.1f} app_mb={size / 1e6:.1f} "
          f"pck_mb={os.path.getsize(os.path.join(out, APP.replace('.x86_64', '.pck'))) / 1e6:.1f} bundled_libraries={len(bundled)}")


if __name__ == "__main__":
    main()
