#!/usr/bin/env python3
"""Every repository path the docs name exists (issue #39: docs/ARCHITECTURE.md had drifted).

Usage: tests/host/check_doc_paths.py [FILE.md ...]
(default: README.md, docs/*.md but docs/addon.md, whose paths are the packaged addon's, and
tests/README.md)

Reads the Markdown files' inline code spans (`...`, outside fenced blocks) and the targets of
their links and images, and takes as a path each one without spaces that holds a '/' or ends in
a source or doc extension (.h, .cpp, .py, .gd, .md...). A path is found when it is:
  - a file or folder of the clone, from its root or from the Markdown file's folder
    (a trailing '/' asks for a folder; a '*' matches as in a shell glob);
  - or, for a path that does not start at a top-level entry of the clone (`engine/live_room.h`,
    `slam/`, `nodes/live_room_link.*`), the tail of one (whole names only);
  - or a bare file name (`room_mesh.cpp`) that some file of the clone has.
Not checked: what lies outside the clone or is made by running it (build/, out/, .godot/,
../shared, absolute paths, ~, res:// and user://, URLs), spans with a placeholder (NAME, DIR,
<name>, ..., |), and the names in NOT_REPOSITORY_PATHS (files inside a recording or an output).
The clone's files are those git knows (tracked, or new and not ignored), plus what the links in
it point at. Prints one line per path not found ('FILE:LINE: `PATH` ...') and exits 1 if any,
else prints how many paths it checked and exits 0.
"""

import fnmatch
import glob
import os
import re
import subprocess
import sys

REPO = os.path.realpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", ".."))

# What a file name ends in for a bare name to count as a path to check. Data names (.yaml, .txt,
# .png, .exr, .json) are left out unless they hold a '/': bare, they name a recording's or an
# output's files far more often than the clone's.
SOURCE_EXTENSIONS = (".h", ".hpp", ".cpp", ".c", ".py", ".sh", ".gd", ".tscn", ".gdshader", ".gdshaderinc",
                     ".md", ".supp", ".gdextension", ".xml")
PATH_EXTENSIONS = SOURCE_EXTENSIONS + (".yaml", ".txt", ".json", ".png", ".cfg", ".obj", ".hdr")

# Made by building or running, or outside the clone: not the clone's to hold.
GENERATED_ROOTS = ("build/", "out/", ".godot/", "godot_project/.godot/", "godot_project/addons/roomprobe/bin/",
                   "tests/godot/binding/bin/")

# Names that look like the clone's paths but are a recording's files or a tool's output.
NOT_REPOSITORY_PATHS = {
    "rgb/", "depth/", "fisheye/", "groundtruth/", "calibration/", "pairs/", "frames/",
    "rgb/000000.png", "rgb/000000.zst", "depth/000000.png", "fisheye/000000.png",
    "groundtruth/rgb_trajectory.txt", "groundtruth/fisheye_trajectory.txt", "groundtruth/cubemaps.txt",
    "groundtruth/cubemaps/", "frames/frame*.png", "bin/BUNDLED.txt", "bin/BUNDLED-aravis.txt", "rgb/*.png", "depth/*.png",
    # TUM RGB-D's own files
    "associate.py", "rgbd_dataset_freiburg1_xyz/",
    # dumped by Godot into build/api/ while SConstruct is read
    "gdextension_interface.h",
}

# Files whose paths are not the clone's: docs/addon.md is the packaged addon's README, and its
# paths lie in the unzipped addons/roomprobe/.
NOT_CHECKED = {"docs/addon.md"}

# A placeholder: a name in capitals (DIR, NAME, FILE.oni, replay_TARGET, frame-NNNNNN), <name>,
# ..., a choice (a|b), braces or a variable. README.md and FIGURES.md are names, not placeholders.
PLACEHOLDER = re.compile(r"(^|/)[A-Z][A-Z0-9_]*(/|$)|(^|/)(FILE|DIR|NAME|TARGET|PATH|OUT|MESH|CMD|VERSION|[A-Z])\."
                         r"|[_-][A-Z]{2,}|<|>|\.\.\.|…|\||\{|\}|\$")
CODE_SPAN = re.compile(r"(`+)(.+?)\1", re.S)
LINK = re.compile(r"\]\(([^)\s]+)\)|<img[^>]*\ssrc=\"([^\"]+)\"")


def repository_files():
    """The clone's files and folders, as paths from its root ('a/b.h', and 'a/' for each folder)."""
    try:
        listed = subprocess.run(["git", "-C", REPO, "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                                check=True, capture_output=True).stdout.decode().split("\0")
        files = {f for f in listed if f and os.path.lexists(os.path.join(REPO, f))}
    except (OSError, subprocess.CalledProcessError):  # not a git clone: every file under the root
        files = set()
        for top, dirs, names in os.walk(REPO):
            dirs[:] = [d for d in dirs if d not in (".git", "build", "out", ".godot", "__pycache__")]
            links = [d for d in dirs if os.path.islink(os.path.join(top, d))]  # listed as git lists them
            files.update(os.path.relpath(os.path.join(top, n), REPO) for n in names + links)
    # What the project's links point at (godot_project/shaders -> ../shaders): their files too.
    for f in list(files):
        full = os.path.join(REPO, f)
        if os.path.islink(full) and os.path.isdir(full):
            target = os.path.relpath(os.path.realpath(full), REPO)
            files.update(f + g[len(target):] for g in files.copy() if g.startswith(target + "/"))
    folders = set()
    for f in files:
        parts = f.split("/")
        folders.update("/".join(parts[:i]) + "/" for i in range(1, len(parts)))
    return files, folders


def spans(path):
    """(line, text) of each inline code span and link target outside fenced blocks."""
    with open(path, encoding="utf-8") as f:
        text = f.read()
    # Blank out fenced blocks, keeping their lines so that the line numbers hold.
    text = re.sub(r"^```.*?^```", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S | re.M)
    for m in CODE_SPAN.finditer(text):
        yield text.count("\n", 0, m.start()) + 1, m.group(2).strip(), "code"
    for m in LINK.finditer(text):
        target = (m.group(1) or m.group(2)).split("#")[0]
        if target:
            yield text.count("\n", 0, m.start()) + 1, target, "link"


def is_path(span, kind):
    if not span or any(c.isspace() for c in span) or PLACEHOLDER.search(span):
        return False
    if "://" in span or span.startswith(("/", "~", "#", "mailto:", "-")) or "#" in span:
        return False
    if span.startswith(".") and "/" not in span:  # an extension (.oni), not a file
        return False
    if ".gen." in span or any(part.isdigit() for part in span.split("/")):  # generated; fr1/2/3
        return False
    if kind == "link":
        return True
    if "/" in span:
        # An option value or a fraction ("a/b" with no name-like part) is not a path.
        return re.fullmatch(r"[\w.*@+-]+(/[\w.*@+-]*)+", span) is not None and re.search(r"[a-z]", span) is not None
    name = span.rstrip("*")
    return span.endswith(SOURCE_EXTENSIONS) or bool(re.fullmatch(r"[a-z_][\w]*\.\*", span)) and bool(name)


def found(span, doc_dir, files, folders, top_level):
    want_folder = span.endswith("/")
    candidates = []
    for base in ("", doc_dir):
        joined = os.path.normpath(os.path.join(REPO, base, span))
        rel = os.path.relpath(joined, REPO)
        if rel.startswith(".."):
            return True  # outside the clone (../shared): not the clone's to hold
        candidates.append(rel.replace(os.sep, "/") + ("/" if want_folder else ""))
    pool = folders if want_folder else files | folders
    for c in candidates:
        if c.startswith(GENERATED_ROOTS) or c in (g.rstrip("/") for g in GENERATED_ROOTS):
            return True
        if "*" in c:
            if fnmatch.filter(pool, c) or fnmatch.filter(folders, c.rstrip("/") + "/"):
                return True
        elif c in pool or (not want_folder and c + "/" in folders):
            return True
    first = span.split("/")[0]
    if "/" in span.rstrip("/") and (first in top_level or span.startswith((".", ".."))):
        return False  # a path from the root: it had to be found above
    # A tail of a path (whole names), or a bare file name.
    tail = span.lstrip("./")
    pattern = "*/" + tail if "/" in tail.rstrip("/") or want_folder else "*/" + tail
    pool_tail = {"/" + p for p in pool}
    return bool(fnmatch.filter(pool_tail, pattern)) or bool(fnmatch.filter(pool_tail, pattern.rstrip("/") + "/"))


def main(argv):
    os.chdir(REPO)
    docs = argv[1:] or [d for d in ["README.md"] + sorted(glob.glob("docs/*.md")) + ["tests/README.md"]
                        if d not in NOT_CHECKED]
    files, folders = repository_files()
    top_level = {f.split("/")[0] for f in files}
    missing, checked = [], 0
    for doc in docs:
        doc_dir = os.path.dirname(os.path.relpath(os.path.realpath(doc), REPO))
        for line, span, kind in spans(doc):
            if not is_path(span, kind) or span in NOT_REPOSITORY_PATHS:
                continue
            checked += 1
            if not found(span, doc_dir, files, folders, top_level):
                missing.append(f"{doc}:{line}: `{span}` names no file or folder of the clone")
    for m in missing:
        print(m)
    if missing:
        print(f"{len(missing)} of {checked} paths named in {len(docs)} files do not exist")
        return 1
    print(f"{checked} paths named in {len(docs)} files, all found")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
