#!/usr/bin/env python3
"""No include arrow runs upward in the core (issue #39).

Usage: tests/host/check_layers.py
Reads the layers of extension/core from docs/ARCHITECTURE.md's line that starts with
'**Layers of the core, bottom up:**' (groups separated by ' < ', folders in a group by ', ', each
in backticks), then every #include <folder/...> in extension/core/*/: a folder may include its
own files and those of the groups below its own, nothing of its own group or above. Prints one
line per arrow that breaks this ('FILE:LINE: folder -> folder') and exits 1 if any, or names a
folder that the line leaves out; else says how many includes it checked and exits 0.
"""

import os
import re
import sys

REPO = os.path.realpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))
CORE = os.path.join(REPO, "extension", "core")
MARK = "**Layers of the core, bottom up:**"
INCLUDE = re.compile(r'^\s*#\s*include\s*<([a-z_0-9]+)/')


def read_layers():
    with open(os.path.join(REPO, "docs", "ARCHITECTURE.md"), encoding="utf-8") as f:
        for line in f:
            if line.startswith(MARK):
                groups = line[len(MARK):].strip().rstrip(".").split(" < ")
                return {name: level for level, group in enumerate(groups) for name in re.findall(r"`([a-z_0-9]+)/?`", group)}
    sys.exit(f"docs/ARCHITECTURE.md: no line starting with {MARK}")


def main():
    layer = read_layers()
    folders = sorted(d for d in os.listdir(CORE) if os.path.isdir(os.path.join(CORE, d)))
    missing = [d for d in folders if d not in layer]
    if missing:
        print("docs/ARCHITECTURE.md: the layers leave out " + ", ".join(missing))
        return 1
    bad = 0
    checked = 0
    for folder in folders:
        for name in sorted(os.listdir(os.path.join(CORE, folder))):
            if not name.endswith((".h", ".cpp")):
                continue
            path = os.path.join(CORE, folder, name)
            with open(path, encoding="utf-8", errors="replace") as f:
                for number, line in enumerate(f, 1):
                    match = INCLUDE.match(line)
                    if not match or match.group(1) not in layer:
                        continue  # a library's header (<glm/...>, <opencv2/...>)
                    target = match.group(1)
                    checked += 1
                    if target != folder and layer[target] >= layer[folder]:
                        print(f"{os.path.relpath(path, REPO)}:{number}: {folder} -> {target}")
                        bad += 1
    if bad:
        print(f"{bad} includes run upward or sideways")
        return 1
    print(f"{checked} includes between {len(folders)} folders, all downward")
    return 0


if __name__ == "__main__":
    sys.exit(main())
