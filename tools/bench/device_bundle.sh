#!/usr/bin/env bash
# The thread-scaling benchmark for a machine where nothing can be installed (issue #36): the
# release roomprobe_bench with every library it loads, the loader that runs them, and the first
# FRAMES frames of the real 7-Scenes sequence (../shared/data/rgbd-7scenes), in one xz archive of at
# most 60 MiB. On the other machine:
#   tar xf roomprobe-bench.tar.xz && roomprobe-bench/run.sh [THREADS...]   (default 1 2 4 8 16)
# prints each run's summary line (dense SLAM in step mode: tracking, integration, raycast, ATE).
#
# Usage, on this machine from the clone: tools/bench/device_bundle.sh OUT.tar.xz [FRAMES]  (FRAMES: 200)
# --check: also run the bundle here at 1 and 2 threads, through its own loader.
set -euo pipefail
repo=$(cd "$(dirname "$(readlink -f "$0")")/../.." && pwd)
check=no
[[ ${1:-} == --check ]] && { check=yes; shift; }
[[ $# -ge 1 && $# -le 2 ]] || { echo "usage: tools/bench/device_bundle.sh [--check] OUT.tar.xz [FRAMES]" >&2; exit 2; }
out=$(readlink -f "$1")
frames=${2:-200}
[[ $frames =~ ^[0-9]+$ ]] && ((frames >= 10 && frames <= 400)) || { echo "FRAMES: a whole number in [10, 400] (the sequence has 400)" >&2; exit 2; }
[[ -d $(dirname "$out") ]] || { echo "OUT $out: its folder does not exist" >&2; exit 2; }
[[ ! -e $out ]] || { echo "OUT $out exists: it is kept (remove it first)" >&2; exit 2; }
sequence=$repo/../shared/data/rgbd-7scenes
[[ -f $sequence/camera-intrinsics.txt ]] || { echo "no 7-Scenes frames in $sequence (../shared/data)" >&2; exit 1; }

cd "$repo"
./roomprobe build target=release tests=no build/bin/roomprobe_bench >/dev/null
stage=$(mktemp -d "$repo/out/device-bundle.XXXXXX")
trap 'rm -rf "$stage"' EXIT
b=$stage/roomprobe-bench
mkdir -p "$b/lib" "$b/7scenes"
cp build/bin/roomprobe_bench "$b/"
# The libraries as the toolchain's loader resolves them (links followed), and the loader itself.
./roomprobe shell bash -c "ldd build/bin/roomprobe_bench | awk '/=> \// { print \$3 } /ld-linux/ { print \$1 }' | sort -u" |
	while IFS= read -r lib; do
		./roomprobe shell cat "$lib" >"$b/lib/$(basename "$lib")"
	done
chmod +x "$b/lib/ld-linux-x86-64.so.2"
cp "$sequence/camera-intrinsics.txt" "$b/7scenes/"
[[ -f $sequence/gravity-direction.txt ]] && cp "$sequence/gravity-direction.txt" "$b/7scenes/"
for ((i = 0; i < frames; i++)); do
	cp "$sequence"/frame-"$(printf '%06d' "$i")".* "$b/7scenes/"
done
cat >"$b/run.sh" <<RUN
#!/usr/bin/env bash
# roomprobe_bench slam on the bundled 7-Scenes frames at each thread count given (default 1 2 4 8 16).
here=\$(cd "\$(dirname "\$0")" && pwd)
for t in \${@:-1 2 4 8 16}; do
	"\$here/lib/ld-linux-x86-64.so.2" --library-path "\$here/lib" "\$here/roomprobe_bench" slam --7scenes "\$here/7scenes" --frames $frames --threads "\$t" |
		grep '^summary:' | sed "s/^/threads=\$t /"
done
RUN
chmod +x "$b/run.sh"
tar -C "$stage" -cJf "$out" roomprobe-bench
size_mib=$(($(stat -c %s "$out") / 1048576))
echo "bundle: $out ($size_mib MiB, $frames frames, $(ls "$b/lib" | wc -l) libraries)"
((size_mib <= 60)) || { echo "bundle: over 60 MiB" >&2; exit 1; }
if [[ $check == yes ]]; then
	"$b/run.sh" 1 2
fi
