#!/usr/bin/env python3
"""An exported Linux app: ./roomprobe export (inside the toolchain, after ./roomprobe package).

Without --project, the demo: assembles a project in build/export-project/ from what a user would
have (godot_project's project.godot and export_presets.cfg, the demo scenes, the packaged addon:
build/package/addons/roomprobe, the Debian 12 library with its libraries bundled, and a
recording zipped into res://recordings/demo.zip), imports it and exports it with Debian's
templates (the preset's custom_template).

With --project DIR, the user's own project: a copy of DIR (without its .godot/) in
build/export-user/NAME/ gets the packaged addon in place of any addons/roomprobe/ it has, is
imported, and is exported with the preset --preset names (default: its first Linux preset) into
--out (default out/export-NAME/). DIR itself is never written.

Either way the app folder must carry the library and every bundled one. The import's exit code
counts (Godot 4.6's crash after a first headless import, godotengine/godot#111048, is avoided as
the test runner avoids it: tools/rp_godot.py import_command). The last line is one key=value
summary.
"""

import argparse
import os
import shutil
import subprocess
import sys
import time
import zipfile

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(REPO, "tools"))
import rp_godot  # noqa: E402  (tools/: the import command that avoids godot#111048)

APP = "roomprobe_demo.x86_64"
DEBIAN_TEMPLATE = "/usr/bin/godot-template-release"


def zip_folder(folder, out):
    """The recording as one zip with one top-level folder: Godot exports it as is (it imports no zip)."""
    name = os.path.basename(os.path.normpath(folder))
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED, compresslevel=1) as z:
        for root, _, files in sorted(os.walk(folder)):
            for f in sorted(f for f in files if f != ".made-with"):
                path = os.path.join(root, f)
                z.write(path, os.path.join(name, os.path.relpath(path, folder)))


def presets(path):
    """The presets of an export_presets.cfg: [(section, {key: value}), ...], in file order."""
    found, current = [], None
    for line in open(path, encoding="utf-8"):
        line = line.strip()
        if line.startswith("[") and line.endswith("]"):
            current = (line[1:-1], {})
            found.append(current)
        elif current is not None and "=" in line and not line.startswith(";"):
            key, value = line.split("=", 1)
            current[1][key.strip()] = value.strip().strip('"')
    return found


def user_project(args):
    """Copies --project DIR into build/export-user/NAME with the packaged addon; returns (project,
    preset name, app file name). Exits with a message naming DIR for what it lacks."""
    src = os.path.abspath(args.project)
    if not os.path.isfile(os.path.join(src, "project.godot")):
        sys.exit(f"export --project {src}: no project.godot there: name the folder of a Godot project")
    cfg = os.path.join(src, "export_presets.cfg")
    if not os.path.isfile(cfg):
        sys.exit(f"export --project {src}: no export_presets.cfg: add a Linux preset (Project > Export) first")
    sections = presets(cfg)
    names = {opts.get("name"): (section, opts) for section, opts in sections if "options" not in section}
    if args.preset:
        if args.preset not in names:
            sys.exit(f"export --preset {args.preset}: no such preset in {cfg} (it has: {', '.join(n for n in names if n) or 'none'})")
        name = args.preset
    else:
        linux = [n for n, (_, o) in names.items() if o.get("platform") == "Linux"]
        if not linux:
            sys.exit(f"export --project {src}: {cfg} has no Linux preset; add one, or name one with --preset")
        name = linux[0]
    section, opts = names[name]
    app = os.path.basename(opts.get("export_path", "")) or os.path.basename(src) + ".x86_64"
    project = os.path.join(REPO, "build", "export-user", os.path.basename(src))
    shutil.rmtree(project, ignore_errors=True)
    shutil.copytree(src, project, symlinks=False, ignore=shutil.ignore_patterns(".godot"))
    shutil.rmtree(os.path.join(project, "addons", "roomprobe"), ignore_errors=True)
    shutil.copytree(args.addon, os.path.join(project, "addons", "roomprobe"))
    # Godot looks for its templates in the user's data folder; Debian's are elsewhere.
    options = dict(next((o for s, o in sections if s == section + ".options"), {}))
    if not options.get("custom_template/release") and os.path.exists(DEBIAN_TEMPLATE):
        text = open(os.path.join(project, "export_presets.cfg"), encoding="utf-8").read()
        text = text.replace(f"[{section}.options]\n", f"[{section}.options]\n\ncustom_template/release=\"{DEBIAN_TEMPLATE}\"\n", 1)
        open(os.path.join(project, "export_presets.cfg"), "w", encoding="utf-8").write(text)
        print(f"export: the preset names no release template: Debian's {DEBIAN_TEMPLATE} is used (in the copy only)")
    return project, name, app


def demo_project(args):
    """The demo's project in --work, with the packaged addon and a recording; returns (project, preset, app)."""
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
    project = args.work
    shutil.rmtree(project, ignore_errors=True)
    os.makedirs(os.path.join(project, "recordings"))
    for f in ("project.godot", "export_presets.cfg"):
        shutil.copyfile(os.path.join(REPO, "godot_project", f), os.path.join(project, f))
    shutil.copytree(os.path.join(REPO, "demo_scenes"), os.path.join(project, "demo_scenes"))
    shutil.copytree(args.addon, os.path.join(project, "addons", "roomprobe"))
    zip_folder(args.recording, os.path.join(project, "recordings", "demo.zip"))
    return project, "Linux", APP


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--addon", default="build/package/addons/roomprobe")
    ap.add_argument("--project", help="a Godot project of yours to export (a copy gets the packaged addon; DIR is not written)")
    ap.add_argument("--preset", help="with --project: the export preset (default: its first Linux preset)")
    ap.add_argument("--recording", help="the demo: the recording folder to carry in the pack (default: a 2-s synthetic "
                    "living room, made once into build/export-recording)")
    ap.add_argument("--work", default="build/export-project", help="the demo: where its project is assembled")
    ap.add_argument("--out")
    args = ap.parse_args()
    if args.preset and not args.project:
        sys.exit("export --preset goes with --project (the demo has its own preset)")
    if args.project and args.recording:
        sys.exit("export --recording is for the demo; with --project, your project carries its own files")

    start = time.monotonic()
    project, preset, app = user_project(args) if args.project else demo_project(args)
    out = os.path.abspath(args.out or ("out/export-" + os.path.basename(os.path.abspath(args.project)) if args.project else "out/export"))
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    log = os.path.join(out, "export.log")
    with open(log, "w") as f:
        # The import (the extension loaded at start-up: godot#111048), then the export.
        for step in (rp_godot.import_command(project), [rp_godot.godot(), "--headless", "--path", project, "--export-release", preset, os.path.join(out, app)]):
            r = subprocess.run(step, stdout=f, stderr=subprocess.STDOUT)
            if r.returncode != 0:
                sys.exit(f"export: {' '.join(step[1:])} failed with status {r.returncode}; see {log}")
    bundled = [l.split("\t")[0] for l in open(os.path.join(args.addon, "bin", "BUNDLED.txt")) if "\t" in l]
    pck = os.path.splitext(app)[0] + ".pck"
    missing = [b for b in ["libroomprobe.linux.release.x86_64.so", app, pck] + bundled if not os.path.exists(os.path.join(out, b))]
    if missing:
        sys.exit(f"export: the app folder lacks {', '.join(missing[:5])}{' ...' if len(missing) > 5 else ''}; see {log}")
    size = sum(os.path.getsize(os.path.join(r, f)) for r, _, fs in os.walk(out) for f in fs)
    print(f"export: {out}/{app} (run it with --headless, or in a window)")
    print(f"summary: export_s={time.monotonic() - start:.1f} app_mb={size / 1e6:.1f} "
          f"pck_mb={os.path.getsize(os.path.join(out, pck)) / 1e6:.1f} bundled_libraries={len(bundled)} preset={preset}")


if __name__ == "__main__":
    main()
