#!/usr/bin/env python3
"""./roomprobe bake-prt: runs godot_project/addons/roomprobe/bake_prt.gd headless.

A fresh clone's project was never imported, and Godot loads a GDExtension in a script run only
when .godot/extension_list.cfg lists it: the editor import (rp_godot.import_command) comes first
when it does not. Arguments go to the script as they are; its exit status is this one's.
"""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import rp_godot as rp  # noqa: E402


def main(argv):
    listed = os.path.join(rp.PROJECT, ".godot", "extension_list.cfg")
    wanted = rp.project_extensions(rp.PROJECT)
    have = []
    if os.path.exists(listed):
        with open(listed) as f:
            have = [line.strip() for line in f if line.strip()]
    if set(wanted) - set(have) or not os.path.isdir(os.path.join(rp.PROJECT, ".godot", "imported")):
        print("bake-prt: importing the Godot project once (first run in this clone)", flush=True)
        r = rp.run(rp.import_command(), None, timeout=600)
        if r.rc != 0:
            rp.tail(r.lines)
            rp.die(f"bake-prt: the project import failed ({rp.describe_exit(r)})")
    cmd = [rp.godot(), "--headless", "--path", rp.PROJECT, "-s", "res://addons/roomprobe/bake_prt.gd", "--", *argv]
    os.execvp(cmd[0], cmd)


if __name__ == "__main__":
    main(sys.argv[1:])
