#!/usr/bin/env python3
"""Writes a tiny TUM RGB-D sequence for tests/host/test_paths.sh: make_tum.py FOLDER [FRAMES].

FOLDER gets rgb.txt, depth.txt, groundtruth.txt, rgb/*.png (640x480 8-bit RGB) and depth/*.png
(640x480 16-bit, 5000 units a metre), as extension/core/recording/tum_dataset.h reads them. The
camera (TUM's ROS default intrinsics, fx = fy = 525) stands still in a room's corner: a back
wall, the floor and a side wall, each checkered, so that point-to-plane ICP has all six degrees
of freedom pinned. The ground truth is the identity at every frame. Plain Python (zlib and
struct): the toolchain has no numpy.
"""

import os
import struct
import sys
import zlib

WIDTH, HEIGHT = 640, 480
FX = FY = 525.0
CX, CY = 319.5, 239.5
DEPTH_UNITS_PER_M = 5000
BACK_Z, FLOOR_Y, LEFT_X = 2.4, 0.9, -1.1  # camera frame: x right, y down, z forward
SQUARE_M = 0.25


def png(path, rows, color_type, bit_depth):
    """rows: one bytes object a row, already in PNG's channel order and byte order."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
    header = struct.pack(">IIBBBBB", WIDTH, HEIGHT, bit_depth, color_type, 0, 0, 0)
    raw = b"".join(b"\x00" + row for row in rows)  # filter 0 on every row
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


def render():
    """The RGB and depth rows of the corner seen from the origin."""
    rgb_rows, depth_rows = [], []
    for v in range(HEIGHT):
        dy = (v - CY) / FY
        rgb, depth = bytearray(), bytearray()
        for u in range(WIDTH):
            dx = (u - CX) / FX
            z, plane = BACK_Z, 0  # the ray (dx, dy, 1) * z meets the nearest plane
            if dy > 0 and FLOOR_Y / dy < z:
                z, plane = FLOOR_Y / dy, 1
            if dx < 0 and LEFT_X / dx < z:
                z, plane = LEFT_X / dx, 2
            x, y = dx * z, dy * z
            a, b = ((x, y), (x, z), (y, z))[plane]
            dark = (int((a + 10) / SQUARE_M) + int((b + 10) / SQUARE_M)) % 2
            base = ((200, 170, 140), (120, 140, 170), (150, 190, 120))[plane]
            rgb += bytes(c // 3 if dark else c for c in base)
            depth += struct.pack(">H", round(z * DEPTH_UNITS_PER_M))
        rgb_rows.append(bytes(rgb))
        depth_rows.append(bytes(depth))
    return rgb_rows, depth_rows


def main():
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__.split("\n")[0])
    folder = sys.argv[1]
    frames = int(sys.argv[2]) if len(sys.argv) == 3 else 3
    os.makedirs(os.path.join(folder, "rgb"), exist_ok=True)
    os.makedirs(os.path.join(folder, "depth"), exist_ok=True)
    rgb_rows, depth_rows = render()
    stamps = [f"{1.0 + i / 30:.6f}" for i in range(frames)]
    for t in stamps:
        png(os.path.join(folder, "rgb", f"{t}.png"), rgb_rows, 2, 8)
        png(os.path.join(folder, "depth", f"{t}.png"), depth_rows, 0, 16)
    for name, what in (("rgb", "color images"), ("depth", "depth maps")):
        with open(os.path.join(folder, f"{name}.txt"), "w") as f:
            f.write(f"# {what}\n# a tiny sequence for RoomProbe's tests\n# timestamp filename\n")
            f.writelines(f"{t} {name}/{t}.png\n" for t in stamps)
    with open(os.path.join(folder, "groundtruth.txt"), "w") as f:
        f.write("# ground truth trajectory\n# timestamp tx ty tz qx qy qz qw\n")
        f.writelines(f"{t} 0 0 0 0 0 0 1\n" for t in stamps)


if __name__ == "__main__":
    main()
