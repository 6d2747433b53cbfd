"""The room suite: roomprobe_room on synthetic sweeps against their true rooms, and its refusals."""

import os
import re
import shutil
import time

import rp_godot as rp

from . import common
from .common import Suite
from .fixtures import FIXTURE_RECORDING, ROOM_SWEEP, make_fixture_recording

# The room without a tape measure (issue #18): roomprobe_room on a 10-s living-room sweep, tracked
# as live, against the figures (corners within 5 cm, the ceiling within 3 cm, up within
# 0.5 degrees, a given floorplan registered within 2 cm); on the 1-s fixture, which sees one wall,
# a clear state and no file; and the tool's refusals.
ROOM_LINE = re.compile(r"^corner_error_max_m=([\d.]+) ceiling_error_m=([\d.]+) up_error_deg=([\d.]+) registration_error_m=(-?[\d.]+) "
                       r"registration_rms_m=([\d.]+) corner_error_fitted_m=([\d.]+)$")
ROOM_FIGURES = ["corner_error_max_m", "ceiling_error_m", "up_error_deg", "registration_error_m", "registration_rms_m", "corner_error_fitted_m"]
ROOM_LIMITS = {"corner_error_max_m": 0.05, "ceiling_error_m": 0.03, "up_error_deg": 0.5, "registration_error_m": 0.02, "corner_error_fitted_m": 0.05}
# The two rooms' 10-s room sweep (synth --room-sweep: through the doorway into the right room),
# tracked: its corners (the partition's included) after the found world is aligned to the true one
# (the measure), ceiling and up against the same limits. Through the first camera its corners
# carry the tracker's slide by the wardrobe at 2.3 s (13 cm, docs/FIGURES.md), as its registration does: both
# are reported, not judged. The living room judges both corner figures.
ROOM_TWO_ROOMS_JUDGED = ["corner_error_fitted_m", "ceiling_error_m", "up_error_deg"]
ROOM_TWO_ROOMS_SWEEP = os.path.join(rp.BUILD, "test-data", "two_rooms_room_sweep_10s")
ROOM_EVAL_ROW = "+light (gain)"  # the coarse model as the live system runs it (roomprobe_eval's table)
ROOM_PSNR_LIMIT_DB = 0.5


def room_figures_over_limits(p_figures):
    """The figures of roomprobe_room's last line that are outside ROOM_LIMITS, each said with its limit."""
    return [f"{k}={v} (at most {ROOM_LIMITS[k]})" for k, v in p_figures.items() if not (0.0 <= v <= ROOM_LIMITS[k])]


def suite_room(opts):
    s = Suite("room")
    log = os.path.join(common.LOGS, "room.log")
    s.logs.append(log)
    tool = os.path.join(rp.BUILD, "bin", "roomprobe_room")
    rp.header(f"room: {rp.relpath(tool)} on a 10-s living-room sweep, the two rooms' 10-s room sweep and the 1-s fixture")
    s.ran = True
    make_fixture_recording()
    make_fixture_recording(ROOM_SWEEP, ("--no-calibration",), seconds=10, seed=1)
    out = os.path.join(rp.BUILD, "test-data", "room-out")
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    start = time.monotonic()
    found = room_living_sweep(s, tool, out, log)
    # The maps with the room found against the maps with the true room (issue #18: within 0.5 dB):
    # the coarse model's variants, scored against the same true cubemaps.
    if os.path.isfile(found):
        room_found_against_true(s, found, log)
    room_two_rooms(s, tool, out, log)
    room_refusals(s, tool, out, log)
    s.seconds = time.monotonic() - start
    return s


def room_living_sweep(s, tool, out, log):
    """The 10-s living-room sweep against the issue's figures; returns the room file it wrote (or would have)."""
    found = os.path.join(out, "living_room.yaml")
    r = rp.run([tool, "--recording", ROOM_SWEEP, "--out", found], log, 900)
    m = next((ROOM_LINE.match(line) for line in r.lines if ROOM_LINE.match(line)), None)
    if r.rc != 0 or m is None or not os.path.isfile(found) or not os.path.isfile(os.path.join(out, "living_room.png")):
        s.fail(f"room: the 10-s sweep: {rp.describe_exit(r)}, figures line {'found' if m else 'missing'} (see {rp.relpath(log)})")
        rp.tail(r.lines, 20)
    else:
        figures = {k: v for k, v in zip(ROOM_FIGURES, map(float, m.groups())) if k in ROOM_LIMITS}
        print(m.group(0))
        over = room_figures_over_limits(figures)
        if over:
            s.fail("room: the 10-s sweep: " + ", ".join(over))
        else:
            s.passed += 1
        s.notes.append(m.group(0))
    return found


def room_found_against_true(s, found, log):
    """roomprobe_eval's PSNR with the true room and with the found one: one test."""
    psnr = {}
    for name, extra in (("true", []), ("found", ["--room", found])):
        r = rp.run([os.path.join(rp.BUILD, "bin", "roomprobe_eval"), "--recording", ROOM_SWEEP, "--no-dense", "--quiet", *extra],
                   f"{log}.eval-{name}", 900)
        row = next((line for line in r.lines if line.startswith(ROOM_EVAL_ROW)), None)
        psnr[name] = float(row[len(ROOM_EVAL_ROW):].split()[0]) if r.rc == 0 and row else None
    if None in psnr.values():
        s.fail(f"room: the evaluation with the true and the found room: no '{ROOM_EVAL_ROW}' row (see {rp.relpath(log)}.eval-*)")
    else:
        line = f"psnr_true_room_db={psnr['true']:.2f} psnr_found_room_db={psnr['found']:.2f} difference_db={psnr['found'] - psnr['true']:+.2f}"
        print(line)
        s.notes.append(line)
        if abs(psnr["found"] - psnr["true"]) <= ROOM_PSNR_LIMIT_DB:
            s.passed += 1
        else:
            s.fail(f"room: PSNR with the found room differs by more than {ROOM_PSNR_LIMIT_DB} dB: {line}")


def room_two_rooms(s, tool, out, log):
    """Two rooms, the room sweep: the room through the doorway, the partition as walls."""
    make_fixture_recording(ROOM_TWO_ROOMS_SWEEP, ("--no-calibration", "--room-sweep"), seconds=10, seed=1, scene="two_rooms")
    two_rooms = os.path.join(out, "two_rooms.yaml")
    r = rp.run([tool, "--recording", ROOM_TWO_ROOMS_SWEEP, "--out", two_rooms], log + ".two-rooms", 900)
    m = next((ROOM_LINE.match(line) for line in r.lines if ROOM_LINE.match(line)), None)
    corners = next((int(c.group(1)) for c in (re.search(r"^room: \w+: (\d+) corners", line) for line in r.lines) if c), 0)
    if r.rc != 0 or m is None or not os.path.isfile(two_rooms):
        s.fail(f"room: the two rooms' room sweep: {rp.describe_exit(r)}, figures line {'found' if m else 'missing'} (see {rp.relpath(log)}.two-rooms)")
        rp.tail(r.lines, 20)
    else:
        figures = {k: v for k, v in zip(ROOM_FIGURES, map(float, m.groups())) if k in ROOM_TWO_ROOMS_JUDGED}
        print("two rooms, room sweep: " + m.group(0))
        s.notes.append("two rooms, room sweep: " + m.group(0))
        over = room_figures_over_limits(figures)
        if corners != 8:
            over.append(f"{corners} corners, not the true room's 8")
        if over:
            s.fail("room: the two rooms' room sweep: " + ", ".join(over))
        else:
            s.passed += 1


def room_refusals(s, tool, out, log):
    """The 1-s fixture's one wall, then the refused --out and --picture paths: two tests."""
    # One wall seen: a clear state, status 1, and nothing written.
    one_wall = os.path.join(out, "fixture.yaml")
    r = rp.run([tool, "--recording", FIXTURE_RECORDING, "--out", one_wall], log + ".fixture", 300)
    said = "\n".join(r.lines)
    if r.rc == 1 and "do not close a room" in said and not os.path.exists(one_wall):
        s.passed += 1
    else:
        s.fail(f"room: the 1-s fixture (one wall): {rp.describe_exit(r)}, {'no' if 'do not close a room' not in said else 'a'} clear state, "
               f"{'a file written' if os.path.exists(one_wall) else 'nothing written'}")
    # An --out that exists is kept; one that is a folder is refused; a device as --picture is refused,
    # even with --force, and never removed (issue #38: a failed write deleted /dev/full). A link to
    # /dev/full stands in for it: were it removed, only the suite's own link would go.
    kept = os.path.join(out, "kept.yaml")
    with open(kept, "w") as f:
        f.write("mine\n")
    r1 = rp.run([tool, "--recording", FIXTURE_RECORDING, "--out", kept], log + ".kept", 60)
    r2 = rp.run([tool, "--recording", FIXTURE_RECORDING, "--out", out], log + ".folder", 60)
    device = os.path.join(out, "full.png")
    os.symlink("/dev/full", device)
    r3 = rp.run([tool, "--recording", FIXTURE_RECORDING, "--out", os.path.join(out, "device.yaml"), "--picture", device, "--force"], log + ".device", 60)
    device_refused = not os.path.exists("/dev/full") or (r3.rc == 2 and os.path.islink(device) and any("is not a regular file" in line for line in r3.lines))
    if r1.rc == 2 and open(kept).read() == "mine\n" and any("exists: it is kept" in line for line in r1.lines) and r2.rc == 2 and \
            any("is a folder" in line for line in r2.lines) and device_refused:
        s.passed += 1
    else:
        s.fail(f"room: --out refusals: an existing file: {rp.describe_exit(r1)}; a folder: {rp.describe_exit(r2)}; "
               f"--picture a link to /dev/full with --force: {rp.describe_exit(r3)}, the link {'kept' if os.path.islink(device) else 'removed'}")
