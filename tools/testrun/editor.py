"""The editor suite: headless imports of a fresh copy and of the project, and the scene round trip."""

import os
import re
import shlex
import shutil

import rp_godot as rp

from . import common
from .common import EDITOR_BAD, IMPORT_TIMEOUT, Suite, fresh_project_copy, noise_note, show_with_context

ROUNDTRIP = os.path.join(rp.REPO, "tests", "editor", "roundtrip")
# The bound: an idle editor on a RoomProbe scene within a few points of one on an empty scene.
IDLE_CPU_POINTS = 5.0
# What a saved RoomProbe scene must not hold (the probe's own outputs), and what it must keep.
ROUNDTRIP_FORBIDDEN = [("an image", re.compile(r'type="Image"|\bImage\b')), ("a sky", re.compile(r'type="Sky"|\bsky = ')),
                       ("a cubemap", re.compile(r'Cubemap')), ("a driven box", re.compile(r'box_projection|interior = true|origin_offset'))]
ROUNDTRIP_KEPT = ["size = Vector3(1, 2, 3)", "cull_mask = 5", "Transform3D(1, 0, 0, 0, 1, 0, 0, 0, 1, 0.5, 0.5, 0.5)"]


def suite_editor(opts, judged=True):
    """Four checks, one test each; each but the round trip is `godot --headless --editor --quit` (see
    rp_godot.import_command for the extension list written before a first import).

    fresh-import: a scratch copy of godot_project/ without .godot/, as on a fresh clone.
    fresh-reopen: the same copy opened again, now imported.
    scene-roundtrip: in that copy, the editor opens a RoomProbe scene (tests/editor/roundtrip/),
        lets the probe drive a material, a ReflectionProbe and a sky, saves it and quits; the
        saved file must hold the user's values only (no maps, no sky, the probe's box as set),
        and the probe must render no map while nothing changes, and one after a move; then tab
        switches, a reload and closing the scene, with no error logged.
    import: the project itself; this also makes the .godot/ the Godot suites need.
    """
    s = Suite("editor")
    s.logs.append(os.path.join(common.LOGS, "editor.log"))
    s.ran = True
    rp.header(f"editor{'' if judged else ' (prerequisite)'}: fresh import of a scratch copy, then the project's own import")
    checks = []
    scratch = os.path.join(rp.BUILD, "godot-fresh-import")
    if judged:
        fresh_project_copy(scratch)
        checks.insert(0, ("fresh-import", None, os.path.join(common.LOGS, "editor-fresh-import.log")))
        # Then the plain `godot --headless --editor --quit` on that freshly imported copy.
        checks.insert(1, ("fresh-reopen", None, os.path.join(common.LOGS, "editor-fresh-reopen.log")))
        s.logs += [checks[0][2], checks[1][2]]
    checks.append(("import", None, s.logs[0]))
    if judged:
        checks.insert(2, ("scene-roundtrip", None, os.path.join(common.LOGS, "editor-scene-roundtrip.log")))
        s.logs.append(checks[2][2])
    for name, _, log in checks:
        if name == "scene-roundtrip":
            scene_roundtrip(s, scratch, log)
            continue
        # Chosen at run time: the command depends on whether the previous check imported it.
        cmd = rp.import_command(scratch if name.startswith("fresh") else rp.PROJECT)
        r = rp.run(cmd, log, IMPORT_TIMEOUT)
        s.seconds += r.seconds
        kept, dropped = rp.filter_noise(r.lines)
        bad = [line for line in kept if EDITOR_BAD.search(line)]
        if r.rc == 0 and not bad and not r.timed_out:
            s.passed += 1
            print(f"ok {name} ({rp.fmt_duration(r.seconds)}){noise_note(dropped)}")
            continue
        why = rp.describe_exit(r) if r.rc or r.timed_out or r.error else f"{len(bad)} error line(s)"
        s.fail(f"editor::{name}: {why}")
        print(f"FAILED {name}: {why} ({rp.fmt_duration(r.seconds)}): {shlex.join(cmd)}")
        show_with_context(kept, bad)
        if not bad:
            print("    (no error line; the end of its output:)")
            rp.tail([line for line in kept if line.strip() and not line.startswith("[")], 8)
    return s


def scene_roundtrip(s, scratch, log):
    """editor::scene-roundtrip (see suite_editor)."""
    for scene in ["roundtrip_probe.tscn", "empty.tscn"]:
        shutil.copyfile(os.path.join(ROUNDTRIP, scene), os.path.join(scratch, "roundtrip_" + scene.replace("roundtrip_", "")))
    plugin = os.path.join(scratch, "addons", "roomprobe_roundtrip")
    shutil.rmtree(plugin, ignore_errors=True)
    os.makedirs(plugin)
    for f in ["plugin.cfg", "plugin.gd"]:
        shutil.copyfile(os.path.join(ROUNDTRIP, f), os.path.join(plugin, f))
    settings = os.path.join(scratch, "project.godot")
    with open(settings) as f:
        text = f.read()
    text = re.sub(r'enabled=PackedStringArray\((.*)\)', r'enabled=PackedStringArray(\1, "res://addons/roomprobe_roundtrip/plugin.cfg")', text)
    with open(settings, "w") as f:
        f.write(text)
    cmd = [rp.godot(), "--headless", "--editor", "--path", scratch]
    r = rp.run(cmd, log, IMPORT_TIMEOUT)
    s.seconds += r.seconds
    with open(os.path.join(scratch, "roundtrip_probe.tscn")) as f:
        saved = f.read()
    problems = []
    if r.rc != 0 or r.timed_out:
        problems.append(rp.describe_exit(r))
    for expected, problem in [("roundtrip: the probe made a map and drives its outputs", "the probe drove nothing (no map)"),
                              ("roundtrip: saved res://roundtrip_probe.tscn (OK)", "the editor did not save the scene"),
                              ("roundtrip: driven again after saving", "the probe did not drive its outputs again after saving"),
                              ("roundtrip: switched tabs, reloaded and closed", "the tab switches, reload and close did not finish"),
                              ("roundtrip: the inspector previews the map", "the inspector shows no preview of the map"),
                              ("roundtrip: gizmos on the probe and the room", "the probe or the room has no gizmo"),
                              ("roundtrip: a corner moves on the floor and back", "the floorplan gizmo's corner drag or its undo failed")]:
        if not any(expected in line for line in r.lines):
            problems.append(problem)
    idle = next((line for line in r.lines if "roundtrip: idle maps" in line), "")
    moved = next((line for line in r.lines if "roundtrip: maps after a move" in line), "")
    cpu = next((re.search(r"idle cpu scene ([\d.]+)% empty ([\d.]+)%", line) for line in r.lines if "roundtrip: idle cpu" in line), None)
    if not cpu:
        problems.append("the idle CPU was not measured")
    elif float(cpu.group(1)) - float(cpu.group(2)) > IDLE_CPU_POINTS:
        problems.append(f"idle CPU with the RoomProbe scene {cpu.group(1)}%, more than {IDLE_CPU_POINTS:g} points above an empty scene's {cpu.group(2)}%")
    else:
        print(f"    idle CPU of the editor: {cpu.group(1)}% with the RoomProbe scene, {cpu.group(2)}% with an empty scene")
    if "idle maps 0 in" not in idle:
        problems.append(f"the probe renders while the editor is idle ({idle.strip() or 'not measured'})")
    if not moved or moved.strip().endswith(" 0"):
        problems.append(f"the probe did not render after a move ({moved.strip() or 'not measured'})")
    problems += [f"the saved scene holds {what}" for what, pattern in ROUNDTRIP_FORBIDDEN if pattern.search(saved)]
    problems += [f"the saved scene lost '{kept}'" for kept in ROUNDTRIP_KEPT if kept not in saved]
    kept, _ = rp.filter_noise(r.lines)
    bad = [line for line in kept if EDITOR_BAD.search(line)]
    if bad:
        problems.append(f"{len(bad)} error line(s)")
    if not problems:
        s.passed += 1
        print(f"ok scene-roundtrip ({rp.fmt_duration(r.seconds)}; saved {len(saved)} bytes)")
        return
    s.fail(f"editor::scene-roundtrip: {'; '.join(problems)}")
    print(f"FAILED scene-roundtrip: {'; '.join(problems)}: {shlex.join(cmd)}")
    show_with_context(kept, bad)
    for line in saved.splitlines()[:60]:
        print("    | " + line)
