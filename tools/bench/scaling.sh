#!/usr/bin/env bash
# How each stage's cost grows (issue #11): voxel size, cubemap size and probe count, one at a
# time from the defaults (1 cm voxels, one 256^2 probe), on one recording, release, 2 threads.
# Each run is `./roomprobe bench target=release slam`; the table is taken from its summary line
# (probe: the first probe's map; full_frame: SLAM, the coarse share and every probe).
# usage: tools/bench/scaling.sh RECORDING [FRAMES]   (FRAMES: RGB-D frames per run, default 90)
set -euo pipefail
recording=${1:?usage: tools/bench/scaling.sh RECORDING [FRAMES]}
frames=${2:-90}
cd "$(dirname "$0")/../.."

# One run: its label, then bench arguments; prints a row from the summary line.
run() {
	local label=$1
	shift
	local line
	line=$(./roomprobe bench target=release slam --recording "$recording" --frames "$frames" --threads 2 --no-peers "$@" 2>/dev/null | grep '^summary:' || true)
	if [[ -z $line ]]; then
		printf '%-22s  (the run failed)\n' "$label"
		return
	fi
	local row=$label key
	for key in tracking_ms integration_ms raycast_ms coarse_ms probe_ms full_frame_ms ate_mm; do
		row+=$(printf ' %10s' "$(sed -n "s/.* $key=\([^ ]*\).*/\1/p" <<<"$line")")
	done
	printf '%-22s%s\n' "$label" "${row#"$label"}"
}

printf '%-22s %10s %10s %10s %10s %10s %10s %10s\n' setting tracking integrate raycast coarse probe full_frame ate_mm
run "voxel 2 cm" --voxel-size-m 0.02 --probe-size 256
run "voxel 1 cm (default)" --voxel-size-m 0.01 --probe-size 256
run "voxel 5 mm" --voxel-size-m 0.005 --probe-size 256
run "cubemap 128^2" --probe-size 128
run "cubemap 512^2" --probe-size 512
run "4 probes (256^2)" --probe-size 256 --probes 4
run "16 probes (256^2)" --probe-size 256 --probes 16
