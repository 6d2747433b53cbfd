#!/usr/bin/env bash
# run.sh of the bundle tools/bench/device_bench.sh makes (see there): roomprobe_bench on both
# backends, and its thread scaling, on a machine where nothing is installed.
#   run.sh [backends|scaling|all]   (default all); RESULTS=DIR for the runs' whole output
set -uo pipefail
here=$(cd "$(dirname "$0")" && pwd)
what=${1:-all}
[[ $what == backends || $what == scaling || $what == all ]] || { echo "usage: run.sh [backends|scaling|all]" >&2; exit 2; }
results=${RESULTS:-$here/results}
mkdir -p "$results" || exit 1
frames=@FRAMES@
cores=$(nproc)

# The bundled programs through the bundled loader and libraries (the machine's own are not used;
# its Vulkan driver is, through the bundled Vulkan loader).
# The machine's LD_LIBRARY_PATH comes first, then the bundle's folder: --library-path replaces it,
# and NVIDIA's container runtime puts the driver's libraries (which the Vulkan loader opens) only there.
# On the H200 machine (2026-11-28) NVIDIA's Vulkan driver loaded only this way and with Debian's
# glvnd libraries unpacked on the machine (as root, when it has none); with the bundle's folder
# first and the toolchain's glvnd alone the loader said "Could not get 'vkCreateInstance'".
libs=${LD_LIBRARY_PATH:+$LD_LIBRARY_PATH:}$here/lib
if [[ -d $here/gl && $(id -u) == 0 ]] && ! ldconfig -p 2>/dev/null | grep -q 'libGLdispatch\.so\.0 '; then
	for deb in "$here"/gl/*.deb; do dpkg -x "$deb" /; done
	ldconfig
	echo "glvnd libraries unpacked on this machine: $(cd "$here/gl" && ls | tr '\n' ' ')"
fi
bundled() { "$here/lib/ld-linux-x86-64.so.2" --library-path "$libs" "$@"; }
# Each run is bounded (RUN_LIMIT_S, default 180), so one that hangs on a driver costs only itself.
limit_s=${RUN_LIMIT_S:-180}
bounded() { timeout -k 5 "$limit_s" "$here/lib/ld-linux-x86-64.so.2" --library-path "$libs" "$@"; }
# One run: its whole output to results/NAME.txt, its summary line (and where the kernels ran) here.
run() {
	local name=$1
	shift
	bounded "$here/roomprobe_bench" "$@" >"$results/$name.txt" 2>&1
	echo "$name (exit $?): $(grep -m1 'backend (' "$results/$name.txt" | sed 's/^ *//')"
	grep '^summary:' "$results/$name.txt" | sed "s/^/$name /"
}

gpu=none
command -v nvidia-smi >/dev/null 2>&1 && gpu=$(nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv,noheader 2>/dev/null | head -1)
echo "machine: $cores cores, $(awk '/MemTotal/ { printf "%.0f GiB", $2 / 1048576 }' /proc/meminfo), GPU: ${gpu:-none}"
icds=$(ls /etc/vulkan/icd.d/*.json /usr/share/vulkan/icd.d/*.json /usr/local/share/vulkan/icd.d/*.json 2>/dev/null | tr '\n' ' ')
echo "Vulkan driver files: ${icds:-none}"
# NVIDIA's container runtime may put the driver file where the loader does not look
# (/usr/local/nvidia/...): name it for this run. Where there is none at all but the driver's
# library is there (a container given the GPU for compute only), write one naming the library.
nvidia_icd=$(ls /usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json /usr/local/nvidia/etc/vulkan/icd.d/nvidia_icd.json 2>/dev/null | head -1)
if [[ $icds != *nvidia* && -n $nvidia_icd && -z ${VK_DRIVER_FILES:-} ]]; then
	export VK_DRIVER_FILES=$nvidia_icd VK_ICD_FILENAMES=$nvidia_icd
	icds="$icds $nvidia_icd"
	echo "Vulkan driver file outside the loader's search: $nvidia_icd"
fi
if [[ $icds != *nvidia* && -z ${VK_DRIVER_FILES:-} ]]; then
	driver=$( (ldconfig -p 2>/dev/null | awk '/libGLX_nvidia\.so\.0 / { print $NF; exit }'; ls /usr/lib/x86_64-linux-gnu/libGLX_nvidia.so.0 /usr/lib64/libGLX_nvidia.so.0 2>/dev/null) | head -1)
	if [[ -n $driver ]]; then
		printf '{ "file_format_version": "1.0.0", "ICD": { "library_path": "%s", "api_version": "1.3.0" } }\n' "$driver" >"$results/nvidia_icd.json"
		export VK_DRIVER_FILES=$results/nvidia_icd.json VK_ICD_FILENAMES=$results/nvidia_icd.json
		echo "Vulkan driver file written for $driver"
	fi
fi

if [[ $what != scaling ]]; then
	for backend in cpu vulkan; do
		run "7scenes-$backend" slam --7scenes "$here/7scenes" --frames "$frames" --threads "$cores" --backend "$backend"
	done
	room=$results/living_room
	rm -rf "$room"
	start=$(date +%s)
	if bounded "$here/roomprobe_synth" --scene living_room --seconds 3 --no-calibration --rig "$here/synthetic_rig.yaml" \
		--hdri "$here/lebombo_1k.hdr" --out "$room" --threads "$cores" >"$results/synth.txt" 2>&1; then
		echo "living room: 3 s synthesised in $(($(date +%s) - start)) s"
		for backend in cpu vulkan; do
			run "living_room-$backend" slam --recording "$room" --probe-size 256 --threads "$cores" --no-peers --backend "$backend"
		done
		for backend in cpu vulkan; do
			run "living_room-4probes-$backend" slam --recording "$room" --probe-size 256 --probes 4 --threads "$cores" --no-peers --backend "$backend"
		done
		rm -rf "$room"
	else
		echo "living room: synthesis failed (results/synth.txt):"
		tail -3 "$results/synth.txt"
	fi
fi
if [[ $what != backends ]]; then
	for threads in 1 2 4 8 16; do
		run "7scenes-threads$threads" slam --7scenes "$here/7scenes" --frames "$frames" --threads "$threads"
	done
fi
