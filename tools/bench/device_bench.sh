#!/usr/bin/env bash
# The benchmark for a GPU machine where nothing can be installed (issues #36 and #40): the release
# roomprobe_bench and roomprobe_synth with every library they load, the loader that runs them,
# the Vulkan loader (opened at run time, so not in ldd's list), the first FRAMES frames of the real
# 7-Scenes sequence (../shared/data/rgbd-7scenes), and what a 3-s synthetic living room is made
# from (the rig file and the window's HDRI), in one xz archive of at most 60 MiB. On the other machine:
#   tar xf roomprobe-bench.tar.xz && roomprobe-bench/run.sh [backends|scaling|all]   (default all)
# backends: dense SLAM on the 7-Scenes frames, then the whole engine (one 256² probe, then four)
#           on the 3-s living room, synthesised there first, each with --backend cpu and
#           --backend vulkan at all cores;
# scaling:  dense SLAM on the 7-Scenes frames at 1 2 4 8 16 threads, on the CPU.
# It prints the machine, its GPU and the Vulkan driver files, then each run's summary line
# (backend=vulkan where the kernels ran on the device, backend=cpu_fallback where there was none);
# every run's whole output goes to $RESULTS (default roomprobe-bench/results).
#
# Usage, on this machine from the clone: tools/bench/device_bench.sh [--check] OUT.tar.xz [FRAMES]  (FRAMES: 200)
# On the lent device machine (its tool carries at most 64 MiB and returns at most 8 files), one call:
#   carry out/devbench.tar.xz; command: mkdir -p /tmp/rb && tar xJf out/devbench.tar.xz -C /tmp/rb &&
#   RESULTS=/tmp/rb/results /tmp/rb/roomprobe-bench/run.sh all; tar czf $OUT/results.tgz -C /tmp/rb results
# (about 5 minutes of runs; the summary lines are in its output).
# --check: also run the bundle's backends here, inside the toolchain's root (Vulkan on lavapipe).
set -euo pipefail
repo=$(cd "$(dirname "$(readlink -f "$0")")/../.." && pwd)
check=no
[[ ${1:-} == --check ]] && { check=yes; shift; }
[[ $# -ge 1 && $# -le 2 ]] || { echo "usage: tools/bench/device_bench.sh [--check] OUT.tar.xz [FRAMES]" >&2; exit 2; }
out=$(readlink -f "$1")
frames=${2:-200}
[[ $frames =~ ^[0-9]+$ ]] && ((frames >= 10 && frames <= 400)) || { echo "FRAMES: a whole number in [10, 400] (the sequence has 400)" >&2; exit 2; }
[[ -d $(dirname "$out") ]] || { echo "OUT $out: its folder does not exist" >&2; exit 2; }
[[ ! -e $out ]] || { echo "OUT $out exists: it is kept (remove it first)" >&2; exit 2; }
sequence=$repo/../shared/data/rgbd-7scenes
hdri=$repo/../shared/data/hdri/lebombo_1k.hdr
[[ -f $sequence/camera-intrinsics.txt ]] || { echo "no 7-Scenes frames in $sequence (../shared/data)" >&2; exit 1; }
[[ -f $hdri ]] || { echo "no HDRI $hdri (../shared/data)" >&2; exit 1; }

cd "$repo"
./roomprobe build target=release tests=no build/bin/roomprobe_bench build/bin/roomprobe_synth >/dev/null
stage=$(mktemp -d "$repo/out/device-bench.XXXXXX")
trap 'rm -rf "$stage"' EXIT
b=$stage/roomprobe-bench
mkdir -p "$b/lib" "$b/7scenes"
cp build/bin/roomprobe_bench build/bin/roomprobe_synth calib/synthetic_rig.yaml "$hdri" "$b/"
# The libraries as the toolchain's loader resolves them (links followed), the loader itself, and
# the Vulkan loader that gpu/vulkan_api.cpp opens (Apache-2.0; the GPU's driver comes from the machine).
./roomprobe shell bash -c "{ ldd build/bin/roomprobe_bench; ldd build/bin/roomprobe_synth; } | awk '/=> \// { print \$3 } /ld-linux/ { print \$1 }' | sort -u;
	readlink -f /usr/lib/x86_64-linux-gnu/libvulkan.so.1" |
	while IFS= read -r lib; do
		./roomprobe shell cat "$lib" >"$b/lib/$(basename "$lib")"
	done
vulkan=$(ls "$b"/lib/libvulkan.so.1.* | head -1)
mv "$vulkan" "$b/lib/libvulkan.so.1"
chmod +x "$b/lib/ld-linux-x86-64.so.2"
# Debian's glvnd and Vulkan loader packages (MIT-style and Apache-2.0), unpacked there only where the
# machine has no glvnd: NVIDIA's Vulkan driver needs them (see run.sh). From this host's apt.
mkdir -p "$b/gl" /tmp/device-bench-apt/partial
apt_opts=(-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/device-bench-apt)
if ! { apt-get "${apt_opts[@]}" update >/dev/null 2>&1 && (cd "$b/gl" && apt-get "${apt_opts[@]}" download libvulkan1 libglvnd0 libglx0 libgl1 libegl1 libopengl0 libgles2 >/dev/null 2>&1); }; then
	echo "bundle: Debian's glvnd packages could not be downloaded; NVIDIA's Vulkan driver may not load there" >&2
fi
cp "$sequence/camera-intrinsics.txt" "$b/7scenes/"
[[ -f $sequence/gravity-direction.txt ]] && cp "$sequence/gravity-direction.txt" "$b/7scenes/"
for ((i = 0; i < frames; i++)); do
	cp "$sequence"/frame-"$(printf '%06d' "$i")".* "$b/7scenes/"
done
sed "s/@FRAMES@/$frames/" tools/bench/device_bench_run.sh >"$b/run.sh"
chmod +x "$b/run.sh"
tar -C "$stage" -cJf "$out" roomprobe-bench
size_mib=$(($(stat -c %s "$out") / 1048576))
echo "bundle: $out ($size_mib MiB, $frames frames, $(ls "$b/lib" | wc -l) libraries)"
((size_mib <= 60)) || { echo "bundle: over 60 MiB" >&2; exit 1; }
if [[ $check == yes ]]; then
	./roomprobe shell env RESULTS="$stage/results" "$b/run.sh" backends
fi
