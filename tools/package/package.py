#!/usr/bin/env python3
"""The self-contained addon: ./roomprobe package (docs/addon.md).

Runs inside the Debian 12 root (tools/toolchain/packages-ship.txt) after `scons ship=yes
target=release` built the library there. It stages addons/roomprobe/ with:
  - bin/: the library and every shared library it needs beyond the base system (glibc, libstdc++,
    libgcc_s), each given RUNPATH $ORIGIN, plus OpenNI2's device drivers in bin/OpenNI2/Drivers/
    (OpenCV is compiled into the library: SConstruct's ship build; an unstripped file is stripped);
  - roomprobe.gdextension listing them all in [dependencies], so that an export copies them too;
  - the editor plugin's scripts, the icons, the shaders and a README;
  - LICENSE (RoomProbe's, MIT) and licenses/: the Debian copyright file of every package a bundled
    library comes from and of the header-only libraries and static archives compiled in (a missing
    one is an error);
then checks that nothing shipped needs a glibc newer than the baseline, prints the unpacked size with
the largest files (a warning above TARGET_MB, a failure above BUDGET_MB), and zips it.
Then the optional zip of the Aravis plugin (libroomprobe_aravis.so: GigE Vision and USB3 Vision
fisheyes), unzipped over the addon: the plugin, the libraries it needs beyond the addon's, their
licences, and a roomprobe.gdextension that lists them too (package_plugin).
The last line is one key=value summary.
"""

import argparse
import os
import re
import shutil
import stat
import subprocess
import sys
import zipfile

# Header-only libraries compiled into RoomProbe's own library: their licences ship too (CGAL's
# LGPL kernel and polygon code, with Boost's headers; GLM). No GPL CGAL package is compiled in
# (tools/package/check_cgal_licences.sh).
HEADER_ONLY_PACKAGES = ("libcgal-dev", "libboost-dev", "libglm-dev")
# Static archives compiled into the library by the ship build (SConstruct, ship_opencv: keep in step):
# the OpenCV modules RoomProbe calls, whose licences ship as those of the header-only code do.
STATIC_PACKAGES = ("libopencv-calib3d-dev", "libopencv-photo-dev", "libopencv-features2d-dev", "libopencv-flann-dev",
                   "libopencv-imgproc-dev", "libopencv-core-dev")
# RoomProbe's own licence (MIT), at the clone's top.
LICENSE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "LICENSE")

# Present on every Linux that runs Godot 4 (apt itself needs libstdc++): never bundled.
BASE_SYSTEM = re.compile(r"^(linux-vdso|ld-linux-x86-64|libc|libm|libdl|librt|libpthread|libresolv|libutil|libstdc\+\+|libgcc_s)\.so")
GLIBC_BASELINE = (2, 36)
# The unpacked addon's size (issue #37, item 4). TARGET_MB is the target: above it the package
# warns, with the largest files. BUDGET_MB is the hard limit: above it the package fails, so that a new
# dependency (OpenCV's videoio alone brings FFmpeg and GStreamer) cannot slip in unseen. The target
# is out of reach while Embree 3 (43.8 MB, five ISA variants) is bundled as Debian 12 builds it:
# docs/addon.md (Size) says why and what would reach it. Aravis, with GLib, libxml2 and ICU, ships in
# a zip of its own (package_plugin).
TARGET_MB = 60
BUDGET_MB = 120
LIBRARY_NAME = "libroomprobe.linux.release.x86_64.so"
RES = "res://addons/roomprobe"


def run(*args):
    return subprocess.run(args, check=True, capture_output=True, text=True).stdout


def needed_closure(paths):
    """Every shared library the files in paths load, as {soname: resolved path}, base system left out."""
    found = {}
    for path in paths:
        for line in run("ldd", path).splitlines():
            m = re.match(r"\s*(\S+) => (\S+)", line)
            if "not found" in line:
                sys.exit(f"package: {path} needs {line.split()[0]}, which this root does not have")
            if m and not BASE_SYSTEM.match(m.group(1)):
                found[m.group(1)] = m.group(2)
    return found


def strip_if_unstripped(path):
    """strip --strip-unneeded on an ELF file that still has a symbol table (RoomProbe's own library;
    Debian's are stripped already). The dynamic symbols, and so loading, are untouched."""
    if re.search(r"\]\s+\.symtab\s", run("readelf", "-S", "-W", path)):
        run("strip", "--strip-unneeded", path)


def size_report(addon):
    """The unpacked size in MB and the largest files, biggest first, as (MB, path under the addon)."""
    sizes = []
    for root, _, files in os.walk(addon):
        for name in files:
            path = os.path.join(root, name)
            sizes.append((os.path.getsize(path) / 1e6, os.path.relpath(path, addon)))
    sizes.sort(reverse=True)
    return sum(s for s, _ in sizes), sizes


def glibc_needs(path):
    """The newest GLIBC_x.y version that an ELF file asks for."""
    versions = [tuple(int(v) for v in m.split(".")) for m in re.findall(r"GLIBC_(\d+\.\d+(?:\.\d+)?)", run("objdump", "-T", path))]
    return max(versions, default=(0, 0))


def debian_package(path):
    """The Debian package that installed path, or None. Debian 12 keeps some libraries under
    /lib (merged with /usr/lib): dpkg knows them by the path they were installed under."""
    real = os.path.realpath(path)
    candidates = [real]
    for a, b in (("/usr/lib/", "/lib/"), ("/lib/", "/usr/lib/")):
        if real.startswith(a):
            candidates.append(b + real[len(a):])
    for candidate in candidates:
        out = subprocess.run(["dpkg", "-S", candidate], capture_output=True, text=True).stdout
        if out:
            return out.split(":")[0]
    return None


def copy_licences(addon, package_of, extra_packages=()):
    """licenses/PACKAGE.txt (Debian's copyright file) for every package a bundled library comes from
    and every one in extra_packages; a file without one stops the package."""
    licenses = os.path.join(addon, "licenses")
    os.makedirs(licenses)
    missing = [f"bin/{rel} (no Debian package owns it)" for rel, package in sorted(package_of.items()) if not package]
    for package in sorted(set(p for p in package_of.values() if p) | set(extra_packages)):
        copyright_file = f"/usr/share/doc/{package}/copyright"
        if os.path.exists(copyright_file):
            shutil.copyfile(copyright_file, os.path.join(licenses, f"{package}.txt"))
        else:
            missing.append(f"{package} (no {copyright_file})")
    if missing:
        sys.exit("package: no licence found for " + "; ".join(missing))


def copy_tree_files(src, dst, keep):
    """Copies the files under src (following symlinks) whose names keep() accepts."""
    for root, _, files in os.walk(src, followlinks=True):
        for name in sorted(files):
            if keep(name):
                rel = os.path.relpath(os.path.join(root, name), src)
                os.makedirs(os.path.dirname(os.path.join(dst, rel)), exist_ok=True)
                shutil.copyfile(os.path.join(root, name), os.path.join(dst, rel))


def write_gdextension(src, dst, bundled, source_has_libraries=False):
    """The addon's .gdextension: the release library for every build, and its dependencies (src
    may be one written here already: its [dependencies] are replaced)."""
    text = open(src).read()
    if source_has_libraries:
        text = re.sub(r"\n*\[dependencies\].*\Z", "", text, flags=re.S)
    text = re.sub(r"\[libraries\].*?(?=\n\[|\Z)", "[libraries]\n"
                  f'linux.debug.x86_64 = "{RES}/bin/{LIBRARY_NAME}"\n'
                  f'linux.release.x86_64 = "{RES}/bin/{LIBRARY_NAME}"\n', text, flags=re.S)
    # The value is the folder, beside the exported executable, that each file is copied into.
    entries = ",\n\t".join(f'"{RES}/bin/{rel}": "{os.path.dirname(rel)}"' for rel in sorted(bundled))
    text = text.rstrip() + "\n\n[dependencies]\n" + f"linux.x86_64 = {{\n\t{entries}\n}}\n"
    open(dst, "w").write(text)


def bundle(bin_dir, roots, skip=(), extra=None):
    """Copies into bin_dir every shared library that the files in roots load (beside the base system
    and the sonames in skip), and the files of extra ({path under bin/: source}). Returns ({path
    under bin/: source}, {path under bin/: Debian package}); finish_binaries makes them shippable."""
    bundled = {soname: path for soname, path in needed_closure(roots).items() if soname not in skip}
    bundled.update(extra or {})
    package_of = {}
    for rel, path in bundled.items():
        dst = os.path.join(bin_dir, rel)
        os.makedirs(os.path.dirname(dst), exist_ok=True)
        shutil.copyfile(os.path.realpath(path), dst)
        package_of[rel] = debian_package(path)
    return bundled, package_of


def finish_binaries(bin_dir, rels):
    """Executable, stripped, RUNPATH $ORIGIN (OpenNI2's drivers: the bin/ two folders up); then the
    glibc baseline, checked on every file shipped. Returns the newest glibc version needed."""
    for rel in rels:
        dst = os.path.join(bin_dir, rel)
        os.chmod(dst, 0o755)
        strip_if_unstripped(dst)
        origin = "$ORIGIN" if "/" not in rel else "$ORIGIN/../.."
        run("patchelf", "--set-rpath", origin, dst)
    newest = max((glibc_needs(os.path.join(bin_dir, rel)), rel) for rel in rels)
    if newest[0] > GLIBC_BASELINE:
        sys.exit(f"package: bin/{newest[1]} needs GLIBC_{'.'.join(map(str, newest[0]))}, newer than the baseline "
                 f"{'.'.join(map(str, GLIBC_BASELINE))}: build it in the Debian 12 root")
    return newest[0]


def write_bundled_list(path, title, bundled, package_of, newest, static=True):
    with open(path, "w") as f:
        f.write(f"{title}: libraries bundled from Debian 12 (bookworm), each with RUNPATH $ORIGIN.\n"
                f"glibc baseline: {'.'.join(map(str, GLIBC_BASELINE))} (newest needed: GLIBC_{'.'.join(map(str, newest))}).\n\n")
        for rel in sorted(bundled):
            f.write(f"{rel}\t{package_of[rel] or '?'}\n")
        if static:
            f.write("\nCompiled into the library (static, from Debian 12): " + ", ".join(STATIC_PACKAGES) + ".\n")


def write_zip(stage, addon, zip_path):
    """A deterministic zip of addon (names relative to stage): sorted names, one timestamp,
    executable bits kept. Returns the unpacked bytes."""
    os.makedirs(os.path.dirname(os.path.abspath(zip_path)), exist_ok=True)
    size = 0
    with zipfile.ZipFile(zip_path + ".partial", "w", zipfile.ZIP_DEFLATED, compresslevel=9) as z:
        for root, _, files in sorted(os.walk(addon)):
            for name in sorted(files):
                path = os.path.join(root, name)
                info = zipfile.ZipInfo(os.path.relpath(path, stage), date_time=(2026, 1, 1, 0, 0, 0))
                info.external_attr = (stat.S_IFREG | (0o755 if os.access(path, os.X_OK) else 0o644)) << 16
                info.compress_type = zipfile.ZIP_DEFLATED
                with open(path, "rb") as src:
                    data = src.read()
                size += len(data)
                z.writestr(info, data)
    os.replace(zip_path + ".partial", zip_path)
    return size


def package_plugin(args, main_bundled, main_gdextension):
    """The optional zip of the Aravis plugin (GigE Vision and USB3 Vision fisheyes), unzipped over
    the addon: the plugin, what it needs beyond the addon's own libraries, their licences, and a
    roomprobe.gdextension that lists the plugin's files too, so that an export copies them."""
    stage = args.stage + "-aravis"
    addon = os.path.join(stage, "addons", "roomprobe")
    shutil.rmtree(addon, ignore_errors=True)
    bin_dir = os.path.join(addon, "bin")
    os.makedirs(bin_dir)
    plugin_name = os.path.basename(args.plugin)
    shutil.copyfile(args.plugin, os.path.join(bin_dir, plugin_name))
    bundled, package_of = bundle(bin_dir, [args.plugin], skip=set(main_bundled))
    newest = finish_binaries(bin_dir, list(bundled) + [plugin_name])
    copy_licences(addon, package_of)
    write_gdextension(main_gdextension, os.path.join(addon, "roomprobe.gdextension"), list(main_bundled) + list(bundled) + [plugin_name],
                      source_has_libraries=True)
    write_bundled_list(os.path.join(bin_dir, "BUNDLED-aravis.txt"), f"The Aravis plugin of RoomProbe {args.version}", bundled, package_of,
                       newest, static=False)
    unpacked_mb, sizes = size_report(addon)
    size = write_zip(stage, addon, args.plugin_zip)
    print(f"package: the Aravis plugin: unpacked {unpacked_mb:.1f} MB; largest: " + ", ".join(f"{rel} {mb:.1f}" for mb, rel in sizes[:6]))
    print(f"package: {args.plugin_zip}")
    return size, len(bundled)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--library", required=True, help="the library built with ship=yes target=release")
    parser.add_argument("--plugin", required=True, help="the Aravis plugin built beside it (libroomprobe_aravis.so)")
    parser.add_argument("--addon", required=True, help="the source addon folder (godot_project/addons/roomprobe)")
    parser.add_argument("--readme", required=True, help="the addon's README (docs/addon.md)")
    parser.add_argument("--stage", required=True, help="folder to stage into (its addons/roomprobe is replaced)")
    parser.add_argument("--zip", required=True, help="the zip to write")
    parser.add_argument("--plugin-zip", required=True, help="the Aravis plugin's zip to write")
    parser.add_argument("--version", required=True)
    args = parser.parse_args()

    addon = os.path.join(args.stage, "addons", "roomprobe")
    shutil.rmtree(addon, ignore_errors=True)
    bin_dir = os.path.join(addon, "bin")
    os.makedirs(bin_dir)

    # The library, OpenNI2's drivers (it loads them from <its folder>/OpenNI2/Drivers) and what they need.
    shutil.copyfile(args.library, os.path.join(bin_dir, LIBRARY_NAME))
    drivers_src = "/usr/lib/x86_64-linux-gnu/OpenNI2/Drivers"
    drivers = sorted(f for f in os.listdir(drivers_src) if f.endswith(".so") and f != "libDummyDevice.so")
    driver_files = {f"OpenNI2/Drivers/{d}": os.path.join(drivers_src, d) for d in drivers}
    bundled, package_of = bundle(bin_dir, [args.library] + list(driver_files.values()), extra=driver_files)
    newest = finish_binaries(bin_dir, list(bundled) + [LIBRARY_NAME])

    # Scripts, icons, shaders, the README and the licences.
    copy_tree_files(args.addon, addon, lambda n: n.endswith((".gd", ".gd.uid", ".cfg", ".svg", ".gdshader",
                                                              ".gdshaderinc", ".uid")) and not n.endswith(".gdextension.uid"))
    shutil.copyfile(args.readme, os.path.join(addon, "README.md"))
    write_gdextension(os.path.join(args.addon, "roomprobe.gdextension"), os.path.join(addon, "roomprobe.gdextension"), bundled)
    # RoomProbe's own licence, and those of the code compiled into the library.
    shutil.copyfile(LICENSE, os.path.join(addon, "LICENSE"))
    copy_licences(addon, package_of, HEADER_ONLY_PACKAGES + STATIC_PACKAGES)
    write_bundled_list(os.path.join(addon, "bin", "BUNDLED.txt"), f"RoomProbe {args.version}", bundled, package_of, newest)

    # The size: the largest files always, a warning above the target, a failure above the budget.
    unpacked_mb, sizes = size_report(addon)
    print(f"package: unpacked {unpacked_mb:.1f} MB; largest: " + ", ".join(f"{rel} {mb:.1f}" for mb, rel in sizes[:8]))
    if unpacked_mb > BUDGET_MB:
        sys.exit(f"package: the unpacked addon is {unpacked_mb:.1f} MB, over its budget of {BUDGET_MB} MB "
                 f"(tools/package/package.py, BUDGET_MB): a new dependency? bin/BUNDLED.txt lists them")
    if unpacked_mb > TARGET_MB:
        print(f"package: warning: the unpacked addon is {unpacked_mb:.1f} MB, above issue #37's target of {TARGET_MB} MB "
              f"(within the budget of {BUDGET_MB} MB); Embree 3 and LAPACK are why: docs/addon.md, Size")

    size = write_zip(args.stage, addon, args.zip)
    print(f"package: {args.zip}")
    plugin_size, plugin_libraries = package_plugin(args, bundled, os.path.join(addon, "roomprobe.gdextension"))
    print(f"summary: zip_mb={os.path.getsize(args.zip) / 1e6:.1f} unpacked_mb={size / 1e6:.1f} bundled_libraries={len(bundled)} "
          f"aravis_zip_mb={os.path.getsize(args.plugin_zip) / 1e6:.1f} aravis_unpacked_mb={plugin_size / 1e6:.1f} "
          f"aravis_libraries={plugin_libraries} glibc_needed={'.'.join(map(str, newest))} glibc_baseline={'.'.join(map(str, GLIBC_BASELINE))} "
          f"target_mb={TARGET_MB} budget_mb={BUDGET_MB}")


if __name__ == "__main__":
    main()
