#!/usr/bin/env python3
"""Open3D's tensor VoxelBlockGrid as a peer of RoomProbe's dense SLAM stages (issue #11).

It fuses a RoomProbe recording's RGB-D frames at the recording's true poses, at the voxel size,
truncation and depth range given (RoomProbe's defaults), and raycasts the tracking reference's
size (1/4 of the camera's: 160x120) from each pose, on the CPU. It times each frame's
integration (the frame's block coordinates, then the fusion: together they are what RoomProbe's
integrate() does) and each raycast, and prints their medians. With --out it also writes them as
key=value lines, which `roomprobe_bench slam --open3d-results FILE` turns into the
open3d_*_ratio keys of its summary (`./roomprobe bench ... --open3d` runs both in one go).

Open3D comes from PyPI into a virtual environment that --setup makes (out/open3d-venv by
default; Python 3.8-3.12). Nothing of Open3D is kept in the repository.

  tools/bench/open3d_peer.py --setup
  tools/bench/open3d_peer.py --recording out/eval_living_room [--frames N] [--threads 2] [--out FILE]

The script re-runs itself in the venv's Python when it is started by another one.
Ends with one 'summary: key=value ...' line.
"""

import argparse
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
DEFAULT_VENV = os.path.join(ROOT, "out", "open3d-venv")
OPEN3D_PIN = "open3d==0.19.0"


def fail(p_message):
    sys.exit("open3d_peer: " + p_message)


def venv_python(p_venv):
    return os.path.join(p_venv, "bin", "python")


def setup(p_venv):
    if sys.version_info[:2] > (3, 12) or sys.version_info[:2] < (3, 8):
        fail("Open3D's wheels need Python 3.8 to 3.12; this is %d.%d (run --setup with such a python3)" % sys.version_info[:2])
    if not os.path.exists(venv_python(p_venv)):
        print("open3d_peer: making the virtual environment %s" % p_venv, flush=True)
        subprocess.check_call([sys.executable, "-m", "venv", p_venv])
    print("open3d_peer: pip install %s numpy (about 400 MB)" % OPEN3D_PIN, flush=True)
    subprocess.check_call([venv_python(p_venv), "-m", "pip", "install", "-q", OPEN3D_PIN, "numpy"])
    print("open3d_peer: ready (%s)" % p_venv)


def read_rig(p_path):
    """The RGB camera's pinhole and depth_scale_m from a RoomProbe rig.yaml (OpenCV YAML)."""
    try:
        text = open(p_path).read()
    except OSError as e:
        fail("cannot read the rig %s: %s" % (p_path, e.strerror))
    rgb = re.search(r"^rgb:\s*\n((?:[ \t]+.*\n)+)", text, re.M)
    if not rgb:
        fail("%s: no 'rgb:' camera" % p_path)
    camera = {}
    for key in ("width", "height", "fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"):
        m = re.search(r"^\s+%s:\s*([-+0-9.eE]+)" % key, rgb.group(1), re.M)
        if m:
            camera[key] = float(m.group(1))
    for key in ("width", "height", "fx", "fy", "cx", "cy"):
        if key not in camera:
            fail("%s: rgb.%s is missing" % (p_path, key))
    if any(camera.get(k, 0.0) != 0.0 for k in ("k1", "k2", "p1", "p2", "k3")):
        print("open3d_peer: note: the rgb camera has distortion; the peer uses its pinhole part (timing only)")
    scale = re.search(r"^depth_scale_m:\s*([-+0-9.eE]+)", text, re.M)
    camera["depth_scale_m"] = float(scale.group(1)) if scale else 0.001
    return camera


def read_index(p_recording, p_name):
    """[(timestamp_s, absolute path)] from depth.txt or rgb.txt."""
    path = os.path.join(p_recording, p_name)
    rows = []
    try:
        lines = open(path).read().splitlines()
    except OSError as e:
        fail("cannot read %s: %s" % (path, e.strerror))
    for number, line in enumerate(lines, 1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        parts = line.split()
        if len(parts) != 2:
            fail("%s:%d: expected 'timestamp_s filename'" % (path, number))
        image = os.path.normpath(os.path.join(p_recording, parts[1]))
        if not image.startswith(os.path.normpath(p_recording) + os.sep):
            fail("%s:%d: %s is outside the recording" % (path, number, parts[1]))
        rows.append((float(parts[0]), image))
    return rows


def read_trajectory(p_path):
    """{timestamp_s: 4x4 world_from_camera} from a TUM trajectory."""
    import numpy as np

    poses = []
    try:
        lines = open(p_path).read().splitlines()
    except OSError as e:
        fail("cannot read the poses %s: %s" % (p_path, e.strerror))
    for number, line in enumerate(lines, 1):
        if not line.strip() or line.startswith("#"):
            continue
        v = [float(x) for x in line.split()]
        if len(v) != 8:
            fail("%s:%d: expected 'timestamp tx ty tz qx qy qz qw'" % (p_path, number))
        t, (x, y, z, w) = v[1:4], v[4:8]
        n = (x * x + y * y + z * z + w * w) ** 0.5
        x, y, z, w = x / n, y / n, z / n, w / n
        m = np.eye(4)
        m[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
        m[:3, 3] = t
        poses.append((v[0], m))
    return poses


def nearest(p_rows, p_time, p_tolerance_s=0.02):
    best = min(p_rows, key=lambda r: abs(r[0] - p_time)) if p_rows else None
    return best if best is not None and abs(best[0] - p_time) <= p_tolerance_s else None


def median(p_values):
    s = sorted(p_values)
    n = len(s)
    return float("nan") if n == 0 else (s[n // 2] if n % 2 else 0.5 * (s[n // 2 - 1] + s[n // 2]))


def run(p_args):
    import numpy as np
    import open3d as o3d
    import open3d.core as o3c

    recording = os.path.abspath(p_args.recording)
    camera = read_rig(os.path.join(recording, "rig.yaml"))
    depth_rows = read_index(recording, "depth.txt")
    rgb_rows = read_index(recording, "rgb.txt")
    poses = read_trajectory(p_args.poses or os.path.join(recording, "groundtruth", "rgb_trajectory.txt"))
    frames = []
    for t, depth_path in depth_rows:
        rgb = nearest(rgb_rows, t)
        pose = nearest(poses, t)
        if rgb and pose:
            frames.append((depth_path, rgb[1], pose[1]))
    if p_args.frames:
        frames = frames[:p_args.frames]
    if not frames:
        fail("%s: no depth frame has an RGB frame and a pose within 20 ms" % recording)

    o3d.utility.set_verbosity_level(o3d.utility.VerbosityLevel.Error)  # its range-map notes each frame
    device = o3c.Device("CPU:0")
    width, height = int(camera["width"]), int(camera["height"])
    intrinsic = o3c.Tensor([[camera["fx"], 0, camera["cx"]], [0, camera["fy"], camera["cy"]], [0, 0, 1]], o3c.float64)
    # The reference raycast's camera: 1 / 2^level of the size, pixel centres kept.
    s = 1.0 / (1 << p_args.raycast_level)
    ray_w, ray_h = width >> p_args.raycast_level, height >> p_args.raycast_level
    ray_intrinsic = o3c.Tensor([[camera["fx"] * s, 0, (camera["cx"] + 0.5) * s - 0.5],
                                [0, camera["fy"] * s, (camera["cy"] + 0.5) * s - 0.5], [0, 0, 1]], o3c.float64)
    depth_scale = 1.0 / camera["depth_scale_m"]  # Open3D divides the stored value by it
    trunc_multiplier = p_args.truncation_m / p_args.voxel_size_m
    vbg = o3d.t.geometry.VoxelBlockGrid(attr_names=("tsdf", "weight", "color"),
                                        attr_dtypes=(o3c.float32, o3c.float32, o3c.float32),
                                        attr_channels=((1), (1), (3)), voxel_size=p_args.voxel_size_m,
                                        block_resolution=8, block_count=p_args.max_blocks, device=device)
    integrate_ms, raycast_ms, hits = [], [], []
    for i, (depth_path, rgb_path, world_from_camera) in enumerate(frames):
        depth = o3d.t.io.read_image(depth_path).to(device)
        color = o3d.t.io.read_image(rgb_path).to(device)
        extrinsic = o3c.Tensor(np.linalg.inv(world_from_camera), o3c.float64)
        t0 = time.perf_counter()
        blocks = vbg.compute_unique_block_coordinates(depth, intrinsic, extrinsic, depth_scale, p_args.max_depth_m,
                                                      trunc_voxel_multiplier=trunc_multiplier)
        vbg.integrate(blocks, depth, color, intrinsic, extrinsic, depth_scale, p_args.max_depth_m,
                      trunc_voxel_multiplier=trunc_multiplier)
        t1 = time.perf_counter()
        result = vbg.ray_cast(block_coords=blocks, intrinsic=ray_intrinsic, extrinsic=extrinsic, width=ray_w, height=ray_h,
                              render_attributes=["depth", "normal", "color"], depth_scale=depth_scale,
                              depth_min=p_args.min_depth_m, depth_max=p_args.max_depth_m, weight_threshold=1,
                              trunc_voxel_multiplier=trunc_multiplier, range_map_down_factor=8)
        t2 = time.perf_counter()
        integrate_ms.append((t1 - t0) * 1e3)
        raycast_ms.append((t2 - t1) * 1e3)
        d = result["depth"].cpu().numpy()
        hits.append(float(np.count_nonzero(d > 0)) / d.size)
        if p_args.progress and (i + 1) % 50 == 0:
            print("  %d / %d frames" % (i + 1, len(frames)), flush=True)

    n = len(frames)
    print("Open3D %s VoxelBlockGrid (CPU, %s threads) on %d frames of %s, true poses:" % (
        o3d.__version__, os.environ.get("OMP_NUM_THREADS", "all"), n, recording))
    print("  voxel %.4f m, truncation %.4f m, depth %.2f..%.2f m, 8^3 blocks, at most %d" % (
        p_args.voxel_size_m, p_args.truncation_m, p_args.min_depth_m, p_args.max_depth_m, p_args.max_blocks))
    print("  %-52s %10s %10s" % ("stage", "median ms", "p95 ms"))
    for name, values in (("integration (block coordinates + integrate)", integrate_ms),
                         ("raycast %dx%d (depth, normal, colour)" % (ray_w, ray_h), raycast_ms)):
        print("  %-52s %10.2f %10.2f" % (name, median(values), sorted(values)[int(0.95 * (len(values) - 1))]))
    print("  raycast hit fraction, median: %.3f; blocks allocated: %d" % (median(hits), vbg.hashmap().size()))
    keys = {
        "open3d_version": o3d.__version__,
        "open3d_frames": n,
        "open3d_voxel_size_m": "%.6g" % p_args.voxel_size_m,
        "open3d_truncation_m": "%.6g" % p_args.truncation_m,
        "open3d_raycast_width": ray_w,
        "open3d_raycast_height": ray_h,
        "open3d_threads": os.environ.get("OMP_NUM_THREADS", "all"),
        "open3d_integration_ms": "%.3f" % median(integrate_ms),
        "open3d_raycast_ms": "%.3f" % median(raycast_ms),
    }
    if p_args.out:
        with open(p_args.out, "w") as f:
            f.write("# open3d_peer.py --recording %s: medians over %d frames\n" % (recording, n))
            for k, v in keys.items():
                f.write("%s=%s\n" % (k, v))
    print("summary: mode=open3d_peer " + " ".join("%s=%s" % kv for kv in keys.items()))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--setup", action="store_true", help="make the virtual environment and install Open3D from PyPI")
    parser.add_argument("--venv", default=DEFAULT_VENV, help="the virtual environment (default out/open3d-venv)")
    parser.add_argument("--recording", help="a RoomProbe recording folder")
    parser.add_argument("--poses", help="a TUM trajectory to fuse at (default: the recording's groundtruth/rgb_trajectory.txt)")
    parser.add_argument("--frames", type=int, default=0, help="only the first N frames")
    parser.add_argument("--threads", type=int, default=2, help="OpenMP threads (default 2, as the bench)")
    parser.add_argument("--voxel-size-m", type=float, default=0.01)
    parser.add_argument("--truncation-m", type=float, default=0.04)
    parser.add_argument("--min-depth-m", type=float, default=0.3)
    parser.add_argument("--max-depth-m", type=float, default=4.0)
    parser.add_argument("--max-blocks", type=int, default=40000)
    parser.add_argument("--raycast-level", type=int, default=2, help="raycast at 1 / 2^level of the camera's size (default 2)")
    parser.add_argument("--out", help="write the medians as key=value lines here (for roomprobe_bench --open3d-results)")
    parser.add_argument("--progress", action="store_true")
    args = parser.parse_args()
    if args.setup:
        setup(args.venv)
        return
    if not args.recording:
        parser.error("--recording DIR (or --setup) is needed")
    # roomprobe_bench's bounds (issue #38): ./roomprobe bench --open3d passes --threads and --voxel-size-m on.
    if not 0.001 <= args.voxel_size_m <= 0.02:
        parser.error("--voxel-size-m needs a voxel edge in metres in [0.001, 0.02]")
    if not 1 <= args.threads <= 1024:
        parser.error("--threads needs a whole number of threads in [1, 1024]")
    if not (0 < args.truncation_m <= 1 and 0 <= args.min_depth_m < args.max_depth_m <= 100 and 0 <= args.raycast_level <= 4):
        parser.error("a truncation in (0, 1] m, a depth range 0 <= min < max <= 100 m and a raycast level in [0, 4] are needed")
    if not (0 <= args.frames <= 10000000 and 1 <= args.max_blocks <= 4194304):
        parser.error("--frames needs [0, 10000000] (0: all) and --max-blocks [1, 4194304]")
    # Open3D's VoxelBlockGrid allocates its whole cap at once: 8^3 voxels of five float32 values (tsdf,
    # weight, colour) a block, 10 KiB. A cap beyond the machine's memory is refused here, naming what
    # it needs, rather than failing inside Open3D (issue #38: the top of the range needs 40 GiB).
    block_bytes = 8 ** 3 * 5 * 4
    memory = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    if args.max_blocks * block_bytes > memory:
        parser.error("--max-blocks %d needs %.1f GiB for Open3D's voxel blocks (%d bytes a block), more than this machine's %.1f GiB "
                     "of memory: give at most %d" % (args.max_blocks, args.max_blocks * block_bytes / 2 ** 30, block_bytes, memory / 2 ** 30,
                                                     memory // block_bytes))
    os.environ["OMP_NUM_THREADS"] = str(args.threads)
    try:
        import open3d  # noqa: F401
    except ImportError:
        python = venv_python(args.venv)
        if not os.path.exists(python):
            fail("Open3D is not installed; run tools/bench/open3d_peer.py --setup (it makes %s)" % args.venv)
        if os.path.realpath(sys.prefix) == os.path.realpath(args.venv):
            fail("Open3D does not import in %s; run --setup again" % args.venv)
        os.execv(python, [python, os.path.abspath(__file__)] + sys.argv[1:])
    run(args)


if __name__ == "__main__":
    main()
