"""The synthetic recordings (and the .oni) that the soak, room and godot suites play, made once per tool build."""

import os
import shutil

import rp_godot as rp

from . import common

# The synthetic recording the Godot tests play (tests/godot/test_nodes_rig_capture.gd).
FIXTURE_RECORDING = os.path.join(rp.BUILD, "test-data", "living_room_1s")
# The same second with the fisheye bracketed (every other frame 5 stops shorter), for the HDR test
# (tests/godot/test_nodes_coarse_pipeline.gd).
FIXTURE_BRACKETED = os.path.join(rp.BUILD, "test-data", "living_room_1s_bracketed")
# The same second from the RGB-D camera alone (roomprobe_synth --no-fisheye), for
# tests/godot/test_nodes_rgbd_only.gd (issue #43).
FIXTURE_RGBD_ONLY = FIXTURE_RECORDING + "_rgbd_only"
# The room suite's 10-s living-room sweep, which tests/godot/test_nodes_auto_room.gd plays too.
ROOM_SWEEP = os.path.join(rp.BUILD, "test-data", "living_room_10s")


def make_fixture_recording(p_folder=FIXTURE_RECORDING, p_extra=(), seconds=1, seed=7, scene="living_room"):
    """Renders a synthetic recording (living_room, 1 s by default) with the synth tool, once per tool build."""
    tool = os.path.join(rp.BUILD, "bin", "roomprobe_synth")
    stamp = os.path.join(p_folder, ".made-by")
    if not os.path.exists(tool):
        return
    made_by = f"{os.path.getmtime(tool)}"
    if os.path.exists(stamp) and open(stamp).read() == made_by:
        return
    shutil.rmtree(p_folder, ignore_errors=True)
    log = os.path.join(common.LOGS, f"fixture-{os.path.basename(p_folder)}.log")
    r = rp.run([tool, "--scene", scene, "--out", p_folder, "--seconds", str(seconds), "--seed", str(seed), *p_extra], log, 900)
    if r.rc == 0:
        with open(stamp, "w") as f:
            f.write(made_by)
    else:
        print(f"    (the fixture recording could not be made; see {log})")


# The fixture's RGB-D stream as an OpenNI .oni, which the live-rig tests play as if from a depth
# camera (tests/godot/test_nodes_live_rig.gd).
FIXTURE_ONI = FIXTURE_RECORDING + ".oni"


def make_fixture_oni():
    """Writes the fixture recording's RGB-D frames as an .oni with build/bin/roomprobe_oni, once per recording."""
    tool = os.path.join(rp.BUILD, "bin", "roomprobe_oni")
    stamp = os.path.join(FIXTURE_RECORDING, ".made-by")
    if not os.path.exists(tool) or not os.path.exists(stamp):
        return
    if os.path.exists(FIXTURE_ONI) and os.path.getmtime(FIXTURE_ONI) >= max(os.path.getmtime(stamp), os.path.getmtime(tool)):
        return
    if os.path.exists(FIXTURE_ONI):
        os.remove(FIXTURE_ONI)
    log = os.path.join(common.LOGS, "fixture-oni.log")
    r = rp.run([tool, "--recording", FIXTURE_RECORDING, "--out", FIXTURE_ONI], log, 300)
    if r.rc != 0:
        print(f"    (the fixture .oni could not be made; see {log})")
