#!/usr/bin/env bash
# The host suite: ./roomprobe's path arguments from outside the clone (tools/toolchain/paths.sh),
# and the paths the docs name (check_doc_paths.py).
# These run on the host, where the paths live, not inside the toolchain like the other suites:
# ./roomprobe test runs this first, and tools/run_tests.py reports its results as the 'host' suite.
# One test is no path's: no_gpl_cgal_headers, the licence check of the CGAL headers compiled in.
#
# Usage: tests/host/test_paths.sh [--filter SUBSTRING] RESULTS LOG
# Runs the tests whose name ('host::...') contains SUBSTRING (default: all). RESULTS gets one
# '[PASS] name' or '[FAIL] name: why' line a test, then 'HOST_TESTS N passed, N failed in S s';
# LOG gets every command and its output.
# Each test runs ./roomprobe verbs on a scratch folder from mktemp -d, outside the clone; none
# needs ../shared (living_room gets --hdri none).
set -uo pipefail

repo=$(cd "$(dirname "$(readlink -f "$0")")/../.." && pwd)
# shellcheck source=tests/host/harness.sh
source "$repo/tests/host/harness.sh"
host_suite_arguments "$@"
# shellcheck source=tools/toolchain/toolchain.sh
source "$repo/tools/toolchain/toolchain.sh"
kind=$(rp_toolchain_kind) || exit 1

scratch=$(mktemp -d "${TMPDIR:-/tmp}/roomprobe-host-test.XXXXXX") || exit 1
scratch=$(realpath "$scratch")
cleanup() {
	rm -rf -- "$scratch"
	# The mount points enter.sh made in the root (empty folders), and anything a failed test wrote
	# there: the path is unique to this run.
	[[ $kind == host ]] || rm -rf -- "${RP_ROOT:?}$scratch"
}
trap cleanup EXIT

# rp ARGS...: ./roomprobe ARGS from the current folder (harness.sh's logged).
rp() { logged "$repo/roomprobe" "$@"; }

no_files_in_root() { # nothing was written inside the toolchain root at the host path $1
	[[ $kind == host ]] || [[ -z $(find "$RP_ROOT$1" ! -type d 2>/dev/null | head -n1) ]]
}
frame_count() { find "$1" -maxdepth 1 -name '*.zst' 2>/dev/null | wc -l; } # raw frames, the writer's default
frame_lines() { local n; n=$(grep -cv '^#' "$1" 2>/dev/null); echo "${n:-0}"; }

# A TUM RGB-D sequence of 3 frames (tests/host/make_tum.py), made by the toolchain's Python in the
# clone, then copied out of it: $scratch/tum-seq.
tum_sequence() {
	[[ -d $scratch/tum-seq ]] && return 0
	local made=$repo/build/test-data/host-tum
	rm -rf -- "$made"
	rp shell python3 tests/host/make_tum.py "$made" 3 && cp -r -- "$made" "$scratch/tum-seq"
}

# The synthetic rig with fx 531.25 instead of 525, outside the clone: $scratch/rig/rig.yaml.
outside_rig() {
	mkdir -p "$scratch/rig" && sed 's/^  fx: 525.0$/  fx: 531.25/' calib/synthetic_rig.yaml >"$scratch/rig/rig.yaml"
}

test_synth_out_outside_clone() {
	local dir=$scratch/synth
	outside_rig
	rp synth --scene living_room --hdri none --rig "$scratch/rig/rig.yaml" --out "$dir" --seconds 0.2 --cubemap-size 8 --no-calibration --seed 3
	check "synth exited with status $rc" test "$rc" -eq 0
	check "synth did not print '-> $dir'" says "-> $dir"
	check "synth did not use --rig $scratch/rig/rig.yaml (fx 531.25)" grep -q '^ *fx: 531.25$' "$dir/rig.yaml"
	local f
	for f in rig.yaml room.yaml synth.yaml rgb.txt depth.txt fisheye.txt groundtruth/rgb_trajectory.txt groundtruth/cubemaps.txt; do
		check "no $dir/$f" test -s "$dir/$f"
	done
	check "rgb/ holds $(frame_count "$dir/rgb") raw frames for $(frame_lines "$dir/rgb.txt") lines of rgb.txt" \
		test "$(frame_count "$dir/rgb")" -eq "$(frame_lines "$dir/rgb.txt")"
	check "no RGB frames" test "$(frame_count "$dir/rgb")" -gt 0
	check "rgb/000000.zst is not a RoomProbe raw frame" grep -q RPRF <(head -c 12 "$dir/rgb/000000.zst" 2>/dev/null)
	check "files written inside the toolchain root at $RP_ROOT$dir" no_files_in_root "$dir"
}

test_eval_outside_clone() {
	local rec=$scratch/synth
	if [[ ! -d $rec ]]; then # when run alone
		rp synth --scene living_room --hdri none --out "$rec" --seconds 0.2 --cubemap-size 8 --no-calibration --seed 3
		check "synth exited with status $rc" test "$rc" -eq 0
	fi
	rp eval --recording "$rec" --out "$scratch/eval" --cubemap-size 8 --max-cubemaps 1 --no-dense --quiet
	check "eval exited with status $rc" test "$rc" -eq 0
	check "no 'baseline' row in eval's table" grep -q '^baseline' <<<"$out"
	check "no $scratch/eval/ground_truth.exr" test -s "$scratch/eval/ground_truth.exr"
	check "no $scratch/eval/coarse_inpaint.png" test -s "$scratch/eval/coarse_inpaint.png"
	check "files written inside the toolchain root at $RP_ROOT$scratch/eval" no_files_in_root "$scratch/eval"
	# Issue #38: maps already in --out are kept and nothing is evaluated, unless --force.
	local kept
	kept=$(cksum <"$scratch/eval/baseline.png")
	rp eval --recording "$rec" --out "$scratch/eval" --cubemap-size 8 --max-cubemaps 1 --no-dense --quiet
	check "eval into a folder holding its maps exited with status $rc, not 2" test "$rc" -eq 2
	check "eval into a folder holding its maps did not say they are kept" says "$scratch/eval/baseline.exr exists: it is kept (give --force to replace it)"
	check "eval without --force changed baseline.png" test "$(cksum <"$scratch/eval/baseline.png")" = "$kept"
	rp eval --recording "$rec" --out "$scratch/eval" --cubemap-size 8 --max-cubemaps 1 --no-dense --quiet --force
	check "eval --force exited with status $rc" test "$rc" -eq 0
}

test_bench_tum_outside_clone() {
	tum_sequence || { failures+=("could not make the TUM sequence (see the log)"); return; }
	# Issue #10's command: intrinsics given, the trajectory saved outside the clone.
	mkdir -p "$scratch/trajectories"
	rp bench slam --tum "$scratch/tum-seq" --frames 3 --intrinsics 525,525,319.5,239.5 --save-trajectory "$scratch/trajectories/T.txt"
	check "bench exited with status $rc" test "$rc" -eq 0
	check "bench did not read $scratch/tum-seq" says "roomprobe_bench slam --tum $scratch/tum-seq"
	check "no 'summary: mode=tum frames=3' line" grep -q '^summary: mode=tum frames=3 ' <<<"$out"
	# TUM format: 'timestamp tx ty tz qx qy qz qw', one line per tracked frame (3 here, all good).
	check "$scratch/trajectories/T.txt does not hold 3 lines of 8 numbers" \
		test "$(grep -cE '^[0-9.eE+-]+( [0-9.eE+-]+){7}$' "$scratch/trajectories/T.txt" 2>/dev/null)" -eq 3
	check "files written inside the toolchain root at $RP_ROOT$scratch/trajectories" no_files_in_root "$scratch/trajectories"
	# Issue #38: never into the sequence it reads (its rgb.txt was once overwritten), and an existing
	# trajectory is kept unless --force.
	local index
	index=$(cksum <"$scratch/tum-seq/rgb.txt")
	rp bench slam --tum "$scratch/tum-seq" --frames 3 --intrinsics 525,525,319.5,239.5 --save-trajectory "$scratch/tum-seq/rgb.txt" --force
	check "bench --save-trajectory into the sequence exited with status $rc, not 2" test "$rc" -eq 2
	check "bench --save-trajectory into the sequence: the message does not name the input" says "lies in the input $scratch/tum-seq"
	check "bench --save-trajectory changed the sequence's rgb.txt" test "$(cksum <"$scratch/tum-seq/rgb.txt")" = "$index"
	rp bench slam --tum "$scratch/tum-seq" --frames 3 --intrinsics 525,525,319.5,239.5 --save-trajectory "$scratch/trajectories/T.txt"
	check "bench onto an existing trajectory exited with status $rc, not 2" test "$rc" -eq 2
	check "bench onto an existing trajectory did not say it is kept" says "$scratch/trajectories/T.txt exists: it is kept (give --force to replace it)"
	rp bench slam --tum "$scratch/tum-seq" --frames 3 --intrinsics 525,525,319.5,239.5 --save-trajectory "$scratch/trajectories/T.txt" --force
	check "bench --save-trajectory onto an existing file with --force exited with status $rc" test "$rc" -eq 0
	# Two sources (#17: --tum was once ignored beside --recording): a usage error naming both.
	rp bench slam --recording "$scratch/tum-seq" --tum "$scratch/tum-seq" --frames 3
	check "bench with --recording and --tum exited with status $rc, not 2" test "$rc" -eq 2
	check "bench with two sources did not say to give one" grep -q 'each name a source: give one' <<<"$out"
}

test_relative_paths_from_another_folder() {
	tum_sequence || { failures+=("could not make the TUM sequence (see the log)"); return; }
	mkdir -p "$scratch/work"
	cd "$scratch/work" || return
	rp synth --scene two_rooms --out rel-out --seconds 0.1 --cubemap-size 8 --no-calibration
	check "synth exited with status $rc" test "$rc" -eq 0
	check "synth did not print '-> $scratch/work/rel-out'" says "-> $scratch/work/rel-out"
	rp bench slam --tum ../tum-seq --frames 1
	check "bench exited with status $rc" test "$rc" -eq 0
	check "bench did not read $scratch/tum-seq" says "roomprobe_bench slam --tum $scratch/tum-seq"
	cd "$repo" || return
	check "no $scratch/work/rel-out/rgb.txt" test -s "$scratch/work/rel-out/rgb.txt"
	check "rel-out was made in the clone" test ! -e "$repo/rel-out"
	check "files written inside the toolchain root at $RP_ROOT$scratch/work" no_files_in_root "$scratch/work"
}

test_missing_parent_refused() {
	local out_dir=$scratch/missing/out
	rp synth --scene living_room --hdri none --out "$out_dir" --seconds 0.1
	check "synth --out with a missing parent exited with status $rc" test "$rc" -ne 0
	check "the message does not name 'synth --out $out_dir'" says "error: synth --out $out_dir: the folder $scratch/missing does not exist"
	rp synth --scene living_room --hdri none "--out=$out_dir"
	check "synth --out=... with a missing parent exited with status $rc" test "$rc" -ne 0
	check "the message does not name 'synth --out $out_dir' (--out=)" says "error: synth --out $out_dir:"
	rp bench slam --tum "$scratch" --save-trajectory "$scratch/missing/trajectory.txt"
	check "bench --save-trajectory with a missing folder exited with status $rc" test "$rc" -ne 0
	check "the message does not name 'bench --save-trajectory'" says "error: bench --save-trajectory $scratch/missing/trajectory.txt: the folder $scratch/missing does not exist"
	check "$scratch/missing was made" test ! -e "$scratch/missing"
}

test_unusable_paths_refused() {
	rp bench slam --tum "$scratch/no-such-sequence"
	check "bench --tum with a missing folder exited with status $rc" test "$rc" -ne 0
	check "the message does not name 'bench --tum'" says "error: bench --tum $scratch/no-such-sequence: no such file or folder"
	# An output folder to be made must not be made when another argument is refused.
	rp synth --scene living_room --hdri none --out "$scratch/not-made" --rig "$scratch/no-such-rig.yaml"
	check "synth with a missing --rig exited with status $rc" test "$rc" -ne 0
	check "the message does not name 'synth --rig'" says "error: synth --rig $scratch/no-such-rig.yaml: no such file or folder"
	check "--out was made although --rig was refused" test ! -e "$scratch/not-made"
	if [[ $kind == sysroot ]]; then # the host's own toolchain sees every path: nothing to refuse
		rp synth --scene living_room --hdri none --out /proc/roomprobe-host-test
		check "synth --out /proc/... exited with status $rc" test "$rc" -ne 0
		check "the message does not name 'synth --out /proc/...'" says "error: synth --out /proc/roomprobe-host-test: the toolchain root has its own /proc"
	fi
}

# calibrate never overwrites a rig file, and writes none from a folder without views.
test_calibrate_refuses_and_never_overwrites() {
	mkdir -p "$scratch/views-empty"
	printf 'precious\n' >"$scratch/rig.yaml"
	rp calibrate --images "$scratch/views-empty" --out "$scratch/rig.yaml"
	check "calibrate onto an existing --out exited with status $rc" test "$rc" -ne 0
	check "the message does not say the file is kept" says "$scratch/rig.yaml: exists; it is not overwritten"
	check "the existing rig file changed" grep -qx precious "$scratch/rig.yaml"
	rp calibrate --images "$scratch/views-empty" --out "$scratch/new-rig.yaml"
	check "calibrate from a folder without views exited with status $rc" test "$rc" -ne 0
	check "the message does not name the folder and say it has no views" says "$scratch/views-empty: no views"
	check "a rig file was written from no views" test ! -e "$scratch/new-rig.yaml"
}

# synth's photometric options refuse a bad value with a message naming it, and write nothing.
test_synth_photometric_options_refused() {
	local dir=$scratch/synth-refused
	local -a cases=("--bracket-ev -5,x|--bracket-ev needs 1 to 16 stops" "--tone-curve gamma|--tone-curve needs srgb or log, got 'gamma'"
		"--fisheye-gains 1,1|--fisheye-gains needs three gains" "--vignetting 0|--vignetting needs the gain at the image circle's rim"
		"--exposure sometimes|--exposure needs fixed, auto or bracket, got 'sometimes'")
	for c in "${cases[@]}"; do
		# shellcheck disable=SC2086 # the option and its value are two words
		rp synth --scene living_room --hdri none --out "$dir" --seconds 0.2 ${c%%|*}
		check "synth ${c%%|*} exited with status $rc" test "$rc" -ne 0
		check "synth ${c%%|*}: the message does not say '${c#*|}'" says "${c#*|}"
		# (./roomprobe makes an --out folder outside the clone before the tool runs: it stays, empty)
		check "synth ${c%%|*} wrote into $dir" test -z "$(ls -A "$dir" 2>/dev/null)"
	done
}

# roomprobe_eval refuses a size without bound, an --out that is a file, and a rig whose images
# could not be allocated, each with a message and a non-zero status (issue #17: these aborted).
test_eval_refuses_bad_input() {
	local dir=build/test-data/eval-refused # inside the clone: the tool runs in the toolchain's root too
	cd "$repo" || return
	rm -rf "$dir" && mkdir -p "$dir/recording"
	sed -e 's/  width: 1024/  width: 100000/' -e 's/  height: 1024/  height: 100000/' calib/synthetic_rig.yaml >"$dir/recording/rig.yaml"
	: >"$dir/recording/rgb.txt" && : >"$dir/recording/depth.txt" && : >"$dir/recording/fisheye.txt"
	echo "not a folder" >"$dir/out-file"
	rp eval --recording "$dir/recording" --cubemap-size 100000
	check "eval --cubemap-size 100000 exited with status $rc" test "$rc" -eq 2
	check "eval --cubemap-size 100000: no bound in the message" says "--cubemap-size needs a whole number of pixels in [1, 4096]"
	# The tool itself, not only ./roomprobe's path check, refuses an --out that is a file.
	rp shell build/bin/roomprobe_eval --recording "$dir/recording" --out "$dir/out-file"
	check "roomprobe_eval --out FILE exited with status $rc" test "$rc" -eq 2
	check "roomprobe_eval --out FILE: the message does not say it is a file" says "is a file, not a folder"
	check "roomprobe_eval --out FILE overwrote the file" grep -q "not a folder" "$dir/out-file"
	rp eval --recording "$dir/recording"
	check "eval on a 100000-px fisheye exited with status $rc" test "$rc" -eq 1
	check "eval on a 100000-px fisheye: the message does not name the field" says "rig.yaml: fisheye.width: must be at most 16384 pixels"
}

# Issue #38: a number that sizes a pool, an allocation or a run is finite and within a range the
# message names (roomprobe_bench --threads 100000 crashed; record --seconds inf never ended). Each is
# refused while the arguments are read, status 2.
test_numbers_out_of_range_refused() {
	tum_sequence || { failures+=("could not make the TUM sequence (see the log)"); return; }
	local c
	local -a cases=("--threads 100000|--threads needs a whole number of threads in [1, 1024]"
		"--voxel-size-m 1e-9|--voxel-size-m needs a voxel edge in metres in [0.001, 0.02]"
		"--voxel-size-m nan|--voxel-size-m needs a voxel edge in metres in [0.001, 0.02]"
		"--frames 99999999999999999999|--frames needs a whole number of frames in [1, 10000000]"
		"--probes 64 --probe-size 4096|--probes 64 x --probe-size 4096 need about 240.0 GiB of maps, more than 8 GiB")
	for c in "${cases[@]}"; do
		# shellcheck disable=SC2086 # the option and its value are two words
		rp bench slam --tum "$scratch/tum-seq" ${c%%|*}
		check "bench ${c%%|*} exited with status $rc, not 2" test "$rc" -eq 2
		check "bench ${c%%|*}: the message does not say '${c#*|}'" says "${c#*|}"
	done
	rp eval --recording "$scratch/tum-seq" --texel-size inf
	check "eval --texel-size inf exited with status $rc, not 2" test "$rc" -eq 2
	check "eval --texel-size inf: no bound in the message" says "--texel-size needs a texel edge in metres in [0.001, 1]"
	rp record --rig calib/synthetic_rig.yaml --out "$scratch/record-inf" --seconds inf
	check "record --seconds inf exited with status $rc, not 2" test "$rc" -eq 2
	check "record --seconds inf: no bound in the message" says "--seconds needs a number of seconds in (0, 86400]"
	# Issue #38: the top of --max-blocks' range is 40 GiB of Open3D's blocks (DenseSLAM.max_blocks's
	# 24 GiB is test_bad_properties.gd's): refused, naming the memory, where the machine has less.
	if (($(awk '/^MemTotal:/ { print $2 }' /proc/meminfo) * 1024 < 4194304 * 10240)); then
		rp shell python3 tools/bench/open3d_peer.py --recording "$scratch/tum-seq" --max-blocks 4194304
		check "open3d_peer.py --max-blocks 4194304 exited with status $rc, not 2" test "$rc" -eq 2
		check "open3d_peer.py --max-blocks 4194304: the memory is not named" says "--max-blocks 4194304 needs 40.0 GiB for Open3D's voxel blocks"
	fi
}

# Issue #38: roomprobe_record run directly (./roomprobe makes paths absolute itself) with relative
# paths records where it was started, though OpenNI2 changes the working directory to its drivers'
# folder when it starts. The RGB-D stream is a 0.5-s synthetic recording played as an .oni.
test_record_relative_out_run_directly() {
	local dir=build/test-data/record-relative # inside the clone: the tool runs in the toolchain's root too
	cd "$repo" || return
	rm -rf "$dir" && mkdir -p "$dir"
	rp synth --scene living_room --hdri none --out "$dir/recording" --seconds 0.5 --cubemap-size 8 --no-calibration --seed 3
	check "synth exited with status $rc" test "$rc" -eq 0
	rp oni --recording "$dir/recording" --out "$dir/recording.oni"
	check "oni exited with status $rc" test "$rc" -eq 0
	rp shell sh -c 'cd "$1" && ../../bin/roomprobe_record --rig recording/rig.yaml --rgbd recording.oni --no-fisheye --out rel-out --seconds 1' sh "$dir"
	check "roomprobe_record exited with status $rc" test "$rc" -eq 0
	check "no recording at $dir/rel-out (relative to where roomprobe_record started)" test -s "$dir/rel-out/rgb.txt"
	check "no RGB-D frames in $dir/rel-out/rgb.txt" test "$(frame_lines "$dir/rel-out/rgb.txt")" -gt 0
}

# bake-prt bakes an OBJ given relative to the caller's folder, reuses the bake while the mesh is
# unchanged, and refuses a bad option with its message.
test_bake_prt_bakes_and_caches() {
	local dir=$repo/build/test-data/bake-prt
	rm -rf "$dir" && mkdir -p "$dir"
	printf 'v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\nv 0 1 0\nf 1 4 3 2\nf 1 2 5\nf 2 3 5\nf 3 4 5\nf 4 1 5\n' >"$dir/pyramid.obj"
	cd "$dir" || return
	rp bake-prt pyramid.obj --samples 64
	check "bake-prt exited with status $rc" test "$rc" -eq 0
	check "bake-prt printed no summary with cached=0" says "cached=0"
	check "bake-prt showed no progress" says "baking PRT transfer: 5 / 5 vertices"
	check "bake-prt wrote no pyramid_prt.res" test -s "$dir/pyramid_prt.res"
	rp bake-prt pyramid.obj --samples 64
	check "an unchanged mesh was baked again" says "cached=1"
	rp bake-prt pyramid.obj --samples 7
	check "bake-prt --samples 7 exited with status $rc" test "$rc" -ne 0
	check "the message does not name --samples" says "--samples needs a whole number of directions in [16, 65536], got '7'"
	rp bake-prt missing.obj
	check "the message does not name the missing mesh" says "$dir/missing.obj: no such file"
	cd "$repo" || return
}

# An unknown verb is named, with the list of verbs, and exit status 2; help lists them with 0.
test_unknown_verb_is_named() {
	rp frobnicate
	check "an unknown verb exited with status $rc, not 2" test "$rc" -eq 2
	check "the message does not name the verb 'frobnicate'" says "unknown verb 'frobnicate'"
	check "the message does not list the verbs" says "usage: ./roomprobe VERB"
	rp help
	check "help exited with status $rc" test "$rc" -eq 0
	check "help does not list demo --scene" says "--scene NAME"
}

# ./roomprobe editor's binds (rp_editor_binds): the caller's folder outside the clone is shown in the
# toolchain at its own path, and no bind hides a system folder or holds the toolchain root.
test_editor_sees_the_callers_files() {
	mkdir -p "$scratch/editor-files"
	echo rig >"$scratch/editor-files/rig.yaml"
	local binds
	binds=$(cd "$scratch/editor-files" && RP_CALLER_PWD=$PWD HOME=$RP_CACHE bash -c 'source "$0/tools/toolchain/toolchain.sh" && rp_editor_binds && printf "%s\n" "${RP_BINDS[@]}"' "$repo")
	printf '%s\n' "$binds" >>"$log"
	if [[ $kind == host ]]; then
		check "with the host's toolchain there is nothing to bind" test -z "$binds"
		return
	fi
	check "the caller's folder is not bound" grep -qx "$scratch/editor-files" <<<"$binds"
	check "a bind holds the toolchain root (HOME was its cache)" bash -c '! grep -qx "$0" <<<"$1"' "$RP_CACHE" "$binds"
	local seen
	seen=$(cd "$scratch/editor-files" && RP_CALLER_PWD=$PWD bash -c 'source "$0/tools/toolchain/toolchain.sh" && rp_editor_binds && rp_toolchain_run cat "$1/rig.yaml"' "$repo" "$scratch/editor-files" 2>>"$log")
	check "the toolchain does not see the caller's file at its own path" test "$seen" = rig
}

# Runs a check script with the host's Python when it has one, else the toolchain's.
logged_python() {
	if command -v python3 >/dev/null 2>&1; then
		logged python3 "$@"
	else
		rp shell python3 "$@"
	fi
}

# Issue #39: every repository path that README.md, docs/*.md and tests/README.md name exists
# (tests/host/check_doc_paths.py; docs/ARCHITECTURE.md had drifted from the tree).
test_docs_name_existing_paths() {
	logged_python tests/host/check_doc_paths.py
	check "tests/host/check_doc_paths.py exited with status $rc: $(grep -m3 'names no file' <<<"$out" | tr '\n' ' ')" test "$rc" -eq 0
	check "tests/host/check_doc_paths.py did not say it checked the paths" says "files, all found"
}

# Issue #39: no include arrow of the core runs upward: each folder includes only the layers below
# it, in the order docs/ARCHITECTURE.md gives (tests/host/check_layers.py).
test_core_includes_run_downward() {
	logged_python tests/host/check_layers.py
	check "tests/host/check_layers.py exited with status $rc: $(grep -m3 ' -> ' <<<"$out" | tr '\n' ' ')" test "$rc" -eq 0
	check "tests/host/check_layers.py did not say it checked the includes" says "all downward"
}

# ---------------------------------------------------------------- issue #38: faults and odd inputs
# Each runs the tools directly inside the toolchain (rp shell), on folders under build/test-data
# (the toolchain sees the clone at its own path), and takes a few seconds.

# A 0.2-s recording (8-px cubemaps, no calibration views) at build/test-data/faults/rec, made once.
faults_recording() {
	local rec=build/test-data/faults/rec
	[[ -s $rec/rgb.txt && ! -e $rec/.roomprobe-writing ]] && return 0
	rm -rf "$rec" && mkdir -p build/test-data/faults
	rp shell build/bin/roomprobe_synth --scene living_room --hdri none --out "$rec" --seconds 0.2 --cubemap-size 8 --no-calibration --seed 3
	((rc == 0))
}

# read_only DIR CMD...: CMD run in the toolchain with DIR read-only. As root a read-only bind mount
# (chmod does not stop root), in the toolchain's own mount namespace or, with the host's toolchain,
# a new one (unshare), so that it ends with the command; otherwise the folder made unwritable.
read_only() {
	local dir=$1
	shift
	if [[ $(id -u) != 0 ]]; then
		chmod a-w "$dir"
		rp shell "$@"
		chmod u+w "$dir"
		return
	fi
	local -a wrap=()
	[[ $kind == host ]] && wrap=(unshare -m)
	rp shell "${wrap[@]}" sh -c 'mount --bind "$1" "$1" && mount -o remount,bind,ro "$1" && shift && exec "$@"' sh "$dir" "$@"
}

# A device or a pipe named as an input is said to be one ("/dev/zero" was "no such file"), and
# never read: /dev/zero has no end, a pipe blocks.
test_input_devices_named() {
	local dir=build/test-data/faults/devices
	cd "$repo" || return
	rm -rf "$dir" && mkdir -p "$dir" && mkfifo "$dir/pipe"
	rp synth --scene living_room --hdri "$dir/pipe" --out "$dir/out" --seconds 0.1
	check "synth --hdri PIPE exited with status $rc" test "$rc" -ne 0
	check "./roomprobe did not say the pipe is not a regular file" says "synth --hdri $repo/$dir/pipe: not a regular file or folder (fifo)"
	rp shell timeout 60 build/bin/roomprobe_synth --scene living_room --hdri /dev/zero --out "$dir/out" --seconds 0.1
	check "roomprobe_synth --hdri /dev/zero exited with status $rc" test "$rc" -ne 0
	check "roomprobe_synth --hdri /dev/zero: not said to be a device" says "/dev/zero: not a regular file (a character device), so the panorama cannot be read"
	rp shell timeout 60 build/bin/roomprobe_synth --scene living_room --hdri "$dir/pipe" --out "$dir/out" --seconds 0.1
	check "roomprobe_synth --hdri PIPE: not said to be a pipe" says "pipe: not a regular file (a named pipe (FIFO))"
	rp shell timeout 60 build/bin/roomprobe_calibrate --images "$dir" --ocamcalib /dev/zero --out build/test-data/faults/rig.yaml
	check "roomprobe_calibrate --ocamcalib /dev/zero exited with status $rc" test "$rc" -eq 1
	check "roomprobe_calibrate --ocamcalib /dev/zero: not said to be a device" says "/dev/zero: not a regular file (a character device)"
	rp shell timeout 60 build/bin/roomprobe_eval --recording /dev/zero
	check "roomprobe_eval --recording /dev/zero: not said to be a device" says "/dev/zero: not a folder (a character device)"
	rp shell timeout 60 build/bin/roomprobe_bench slam --recording "$dir" --open3d-results /dev/zero
	check "roomprobe_bench --open3d-results /dev/zero exited with status $rc, not 2" test "$rc" -eq 2
	check "roomprobe_bench --open3d-results /dev/zero: not said to be a device" says "--open3d-results /dev/zero: not a regular file (a character device)"
	rp shell timeout 60 build/bin/roomprobe_bench slam --tum "$dir" --open3d-results "$dir/pipe"
	check "roomprobe_bench --tum --open3d-results exited with status $rc, not 2" test "$rc" -eq 2
	check "roomprobe_bench --tum --open3d-results: not said to go with --recording" says "it goes with --recording"
}

# The Aravis plugin (libroomprobe_aravis.so) missing, or a file of that name that is not it: a
# program that lists Aravis cameras says so, naming the file and the folder, and goes on.
test_aravis_plugin_missing_named() {
	local dir=build/test-data/faults/no-plugin
	cd "$repo" || return
	rm -rf "$dir" && mkdir -p "$dir" && cp build/bin/roomprobe_devices "$dir/"
	rp shell timeout 60 "$dir/roomprobe_devices" --fake
	check "roomprobe_devices without the plugin exited with status $rc" test "$rc" -eq 0
	check "the missing plugin was not named with its folder" says "the Aravis plugin (libroomprobe_aravis.so) is not installed in $repo/$dir"
	cp "$dir/roomprobe_devices" "$dir/libroomprobe_aravis.so"
	rp shell timeout 60 "$dir/roomprobe_devices" --fake
	check "a plugin that is not one was not refused" says "the Aravis plugin $repo/$dir/libroomprobe_aravis.so does not load"
	rp shell timeout 60 build/bin/roomprobe_devices --fake
	check "with the plugin beside it, Aravis' Fake camera was not listed" says "Fake_1"
}

# --hdri where it does not apply (two_rooms shows no panorama: it was ignored, and 10 s were made
# without a word), or naming no file: refused before anything is made.
test_synth_hdri_refused() {
	local dir=build/test-data/faults/hdri
	cd "$repo" || return
	rm -rf "$dir"
	rp shell build/bin/roomprobe_synth --scene two_rooms --hdri /nonexistent.hdr --out "$dir" --seconds 0.1
	check "synth two_rooms --hdri exited with status $rc, not 2" test "$rc" -eq 2
	check "synth two_rooms --hdri: not said not to apply" says "--hdri /nonexistent.hdr: the scene two_rooms shows no panorama; --hdri applies to living_room and panorama_room"
	rp shell build/bin/roomprobe_synth --scene living_room --hdri /nonexistent.hdr --out "$dir" --seconds 0.1
	check "synth living_room --hdri MISSING exited with status $rc, not 2" test "$rc" -eq 2
	check "synth living_room --hdri MISSING: not said to be missing" says "--hdri /nonexistent.hdr: no such file"
	check "synth made $dir although refused" test ! -e "$dir"
}

# A read-only output folder: refused before any work with the system's reason, status 2, nothing
# written, --quiet or not (eval --quiet once exited 0 having written nothing); synth says it too.
test_read_only_output_refused() {
	local ro=build/test-data/faults/read-only rec=build/test-data/faults/rec
	cd "$repo" || return
	faults_recording || { failures+=("could not make the recording (see the log)"); return; }
	rm -rf "$ro" && mkdir -p "$ro"
	read_only "$ro" build/bin/roomprobe_eval --recording "$rec" --out "$ro" --cubemap-size 8 --max-cubemaps 1 --no-dense --quiet
	check "eval --quiet into a read-only --out exited with status $rc, not 2" test "$rc" -eq 2
	check "eval --quiet into a read-only --out: the message does not say why" says "--out $ro: files cannot be written there"
	read_only "$ro" build/bin/roomprobe_eval --recording "$rec" --out "$ro/maps" --cubemap-size 8 --max-cubemaps 1 --no-dense --quiet
	check "eval --quiet into a folder it cannot make exited with status $rc, not 2" test "$rc" -eq 2
	check "eval into a folder it cannot make: the message does not say why" says "--out $ro/maps: cannot create the folder"
	read_only "$ro" build/bin/roomprobe_room --recording "$rec" --out "$ro/room.yaml" --quiet
	check "room --quiet into a read-only folder exited with status $rc, not 2" test "$rc" -eq 2
	check "room into a read-only folder: the message does not say why" says "--out $ro/room.yaml: cannot be opened for writing"
	read_only "$ro" build/bin/roomprobe_calibrate --recording "$rec" --out "$ro/rig.yaml"
	check "calibrate into a read-only folder exited with status $rc, not 2" test "$rc" -eq 2
	check "calibrate into a read-only folder: the message does not say why" says "--out $ro/rig.yaml: cannot be opened for writing"
	read_only "$ro" build/bin/roomprobe_synth --scene two_rooms --out "$ro/rec" --seconds 0.1 --cubemap-size 8 --no-calibration
	check "synth into a read-only folder exited with status $rc" test "$rc" -ne 0
	check "synth into a read-only folder: the message does not say why" says "$ro/rec: cannot create the folder"
	check "something was written into the read-only folder" test -z "$(ls -A "$ro")"
}

# /dev/full (a link to it) as an output file: refused even with --force, never written or removed
# (room's --picture is the room suite's).
test_dev_full_outputs_refused() {
	local dir=build/test-data/faults/full rec=build/test-data/faults/rec
	cd "$repo" || return
	faults_recording || { failures+=("could not make the recording (see the log)"); return; }
	rm -rf "$dir" && mkdir -p "$dir/eval" "$dir/synth"
	ln -s /dev/full "$dir/room.yaml" && ln -s /dev/full "$dir/eval/baseline.exr" && ln -s /dev/full "$dir/synth/rgb.txt" && ln -s /dev/full "$dir/synth-out"
	rp shell build/bin/roomprobe_room --recording "$rec" --out "$dir/room.yaml" --force --quiet
	check "room --out LINK-TO-/dev/full --force exited with status $rc, not 2" test "$rc" -eq 2
	check "room --out /dev/full: not said to be a device" says "--out $dir/room.yaml: is not a regular file (a device, a pipe or a socket)"
	rp shell build/bin/roomprobe_eval --recording "$rec" --out "$dir/eval" --cubemap-size 8 --max-cubemaps 1 --no-dense --quiet --force
	check "eval with a map linked to /dev/full --force exited with status $rc, not 2" test "$rc" -eq 2
	check "eval with a map linked to /dev/full: not said to be a device" says "$dir/eval/baseline.exr: is not a regular file"
	rp shell build/bin/roomprobe_synth --scene two_rooms --out "$dir/synth" --seconds 0.1 --cubemap-size 8 --no-calibration
	check "synth into a folder holding a link to /dev/full exited with status $rc" test "$rc" -ne 0
	check "synth into a folder holding a link to /dev/full: not refused as not empty" says "$dir/synth: the output folder exists and is not empty"
	rp shell build/bin/roomprobe_synth --scene two_rooms --out "$dir/synth-out" --seconds 0.1 --cubemap-size 8 --no-calibration
	check "synth --out LINK-TO-/dev/full exited with status $rc" test "$rc" -ne 0
	check "synth --out LINK-TO-/dev/full: not refused" says "$dir/synth-out: exists and is not a folder"
	local link
	for link in room.yaml eval/baseline.exr synth/rgb.txt synth-out; do
		check "$dir/$link is no longer the link to /dev/full" test "$(readlink "$dir/$link")" = /dev/full
	done
	check "/dev/full is gone" test -c /dev/full
}

# SIGKILL of synth midway: the partial recording plays what its indexes list, and the tools say it
# was never closed (its marker is left); eval, which needs the ground truth written on closing,
# refuses saying so. No crash.
test_synth_killed_midway() {
	local rec=build/test-data/faults/killed
	cd "$repo" || return
	rm -rf "$rec"
	rp shell sh -c 'build/bin/roomprobe_synth --scene two_rooms --out "$1" --seconds 5 --cubemap-size 8 --no-calibration --seed 1 >/dev/null 2>&1 &
		pid=$!; i=0
		while n=$(grep -cv "^#" "$1/depth.txt" 2>/dev/null); [ "${n:-0}" -lt 3 ] && [ $i -lt 600 ]; do sleep 0.05; i=$((i + 1)); done
		kill -KILL $pid; wait $pid; echo "synth ended with status $?"' sh "$rec"
	check "synth was not killed (status 137)" says "synth ended with status 137"
	check "the killed synth left no marker $rec/.roomprobe-writing" test -e "$rec/.roomprobe-writing"
	local frames
	frames=$(frame_lines "$rec/depth.txt")
	check "the killed synth listed $frames depth frames, fewer than 3" test "$frames" -ge 3
	rp shell timeout 120 build/bin/roomprobe_bench slam --recording "$rec" --no-peers --probe-size 8
	check "bench on the killed recording exited with status $rc" test "$rc" -eq 0
	check "bench on the killed recording did not say it was never closed" says "the recording was never closed"
	check "bench on the killed recording played no frame" grep -qE "^summary: mode=[a-z]+ frames=[1-9]" <<<"$out"
	rp shell timeout 120 build/bin/roomprobe_eval --recording "$rec" --no-dense --quiet
	check "eval on the killed recording exited with status $rc, not 1" test "$rc" -eq 1
	check "eval on the killed recording did not say why it refuses" says "no ground-truth RGB-D trajectory (PoseSource::GroundTruth needs it): the recording was never closed"
}

# small_disk DIR KB SCRIPT ARGS...: sh -c SCRIPT run in the toolchain with a KB-kilobyte tmpfs on
# DIR (a full disk on demand), unmounted when it ends: checks that need the files run inside SCRIPT.
# As root in the toolchain's own mount namespace (a new one with the host's toolchain); otherwise in
# a user namespace of its own.
small_disk() {
	local dir=$1 kb=$2
	shift 2
	local -a wrap=()
	[[ $(id -u) != 0 ]] && wrap=(unshare -r -m)
	[[ $(id -u) == 0 && $kind == host ]] && wrap=(unshare -m)
	rp shell "${wrap[@]}" sh -c 'dir=$1 kb=$2; shift 2; mount -t tmpfs -o size=${kb}k tmpfs "$dir" || exit 99; sh -c "$@"; status=$?; umount "$dir"; exit $status' \
		sh "$dir" "$kb" "$@"
}

# A full disk under each tool's output: the tool stops with the system's reason naming the file and a
# failing status, leaves no temporary file (files are written beside and renamed: no half-written
# one under its name), and keeps what was there; the recordings that synth and record had begun
# play the frames their indexes list.
test_full_disk_outputs() {
	local dir=build/test-data/faults/small rec=build/test-data/faults/rec oni=build/test-data/faults/oni
	cd "$repo" || return
	faults_recording || { failures+=("could not make the recording (see the log)"); return; }
	rm -rf "$dir" "$oni" && mkdir -p "$dir" "$oni"
	rp oni --recording "$rec" --out "$oni/rec.oni"
	check "oni exited with status $rc" test "$rc" -eq 0
	small_disk "$dir" 2000 'd=$1
		build/bin/roomprobe_synth --scene two_rooms --out "$d/synth" --seconds 1 --cubemap-size 8 --no-calibration --seed 1; echo "synth status $?"
		build/bin/roomprobe_bench slam --recording "$d/synth" --no-peers --probe-size 8 | grep "^summary"
		timeout 60 build/bin/roomprobe_record --rig "$2/rig.yaml" --rgbd "$3" --no-fisheye --out "$d/record" --seconds 5; echo "record status $?"
		rm -rf "$d/synth" "$d/record"
		echo kept >"$d/room.yaml"; head -c 100M /dev/zero >"$d/fill" 2>/dev/null; truncate -s -24K "$d/fill"
		build/bin/roomprobe_room --recording "$2" --out "$d/room.yaml" --picture "$d/top.png" --force --quiet; echo "room status $?"
		build/bin/roomprobe_eval --recording "$2" --out "$d/eval" --cubemap-size 8 --max-cubemaps 1 --no-dense --quiet; echo "eval status $?"
		echo "room.yaml holds $(cat "$d/room.yaml")"; echo "temporary files left: $(cd "$d" && find . -name ".*" -type f | tr "\n" " ")"' \
		sh "$dir" "$rec" "$oni/rec.oni"
	check "the tmpfs was not mounted (status 99; see the log)" test "$rc" -ne 99
	check "synth on a full disk did not stop with status 2" says "synth status 2"
	check "synth on a full disk did not name the frame and the reason" grep -qE "roomprobe_synth: $dir/synth/.*: could not be written: No space left on device" <<<"$out"
	check "the recording synth began did not play" grep -qE "^summary: mode=[a-z]+ frames=[1-9]" <<<"$out"
	check "record on a full disk did not stop with status 1" says "record status 1"
	check "record on a full disk did not name the frame and the reason" grep -qE "roomprobe_record: .*$dir/record/.*: could not be written: No space left on device" <<<"$out"
	check "room on a full disk did not name the picture and the reason" says "$dir/top.png: could not be written: No space left on device"
	check "room on a full disk exited with status 0" says "room status 1"
	check "eval on a full disk did not name a map and the reason" grep -qE "$dir/eval/[a-z_]+\\.(exr|png): could not be written: No space left on device" <<<"$out"
	check "eval on a full disk did not stop with status 1" says "eval status 1"
	check "the room.yaml that was there was not kept" says "room.yaml holds kept"
	check "temporary files were left on the full disk" grep -qE '^temporary files left: ?$' <<<"$out"
}

# SIGKILL of record midway (as synth's): what its indexes list plays, and the tools say the recording
# was never closed.
test_record_killed_midway() {
	local rec=build/test-data/faults/rec oni=build/test-data/faults/oni-killed out_dir=build/test-data/faults/record-killed
	cd "$repo" || return
	faults_recording || { failures+=("could not make the recording (see the log)"); return; }
	rm -rf "$oni" "$out_dir" && mkdir -p "$oni"
	rp oni --recording "$rec" --out "$oni/rec.oni"
	rp shell sh -c 'build/bin/roomprobe_record --rig "$1/rig.yaml" --rgbd "$2" --no-fisheye --out "$3" --seconds 30 >/dev/null 2>&1 &
		pid=$!; i=0
		while n=$(grep -cv "^#" "$3/depth.txt" 2>/dev/null); [ "${n:-0}" -lt 3 ] && [ $i -lt 600 ]; do sleep 0.05; i=$((i + 1)); done
		kill -KILL $pid; wait $pid; echo "record ended with status $?"' sh "$rec" "$oni/rec.oni" "$out_dir"
	check "record was not killed (status 137)" says "record ended with status 137"
	check "the killed record left no marker $out_dir/.roomprobe-writing" test -e "$out_dir/.roomprobe-writing"
	check "the killed record listed $(frame_lines "$out_dir/depth.txt") depth frames, fewer than 3" test "$(frame_lines "$out_dir/depth.txt")" -ge 3
	rp shell timeout 120 build/bin/roomprobe_bench slam --recording "$out_dir" --no-peers --probe-size 8
	check "bench on the killed recording exited with status $rc" test "$rc" -eq 0
	check "bench on the killed recording did not say it was never closed" says "the recording was never closed"
	check "bench on the killed recording played no frame" grep -qE "^summary: mode=[a-z]+ frames=[1-9]" <<<"$out"
}

# Two writers on one output: of two synths started together into one folder, one writes it whole and
# the other is refused (the writers' marker, or the folder no longer empty); of two benches saving
# their trajectories to one file with --force, one file is whole (written beside, renamed).
test_two_writers_one_output() {
	local dir=build/test-data/faults/two-writers
	cd "$repo" || return
	tum_sequence || { failures+=("could not make the TUM sequence (see the log)"); return; }
	rm -rf "$dir" && mkdir -p "$dir/rec"
	rp shell sh -c 'for seed in 1 2; do build/bin/roomprobe_synth --scene two_rooms --out "$1/rec" --seconds 0.2 --cubemap-size 8 --no-calibration \
		--seed $seed >"$1/synth-$seed.log" 2>&1 & done; wait' sh "$dir"
	local won=0 refused=0 seed
	for seed in 1 2; do
		grep -q '^wrote ' "$dir/synth-$seed.log" && won=$((won + 1))
		grep -qE 'another writer is recording into this folder now|the output folder exists and is not empty' "$dir/synth-$seed.log" && refused=$((refused + 1))
	done
	check "of two synths into one folder, $won wrote it and $refused was refused (see $dir/synth-*.log)" test "$won" -eq 1 -a "$refused" -eq 1
	local stream
	for stream in rgb depth fisheye; do # one writer's frames, each listed once: no mix
		check "two synths: $stream/ holds $(frame_count "$dir/rec/$stream") frames for $(frame_lines "$dir/rec/$stream.txt") lines of $stream.txt" \
			test "$(frame_count "$dir/rec/$stream")" -eq "$(frame_lines "$dir/rec/$stream.txt")"
	done
	check "two synths: the winner's count is not the folder's" grep -q "^wrote $(frame_lines "$dir/rec/rgb.txt") RGB-D frames, $(frame_lines "$dir/rec/fisheye.txt") fisheye" "$dir"/synth-*.log
	check "two synths: the marker was left" test ! -e "$dir/rec/.roomprobe-writing"
	cp -r "$scratch/tum-seq" "$dir/tum"
	rp shell sh -c 'for n in 2 3; do build/bin/roomprobe_bench slam --tum "$1/tum" --frames $n --intrinsics 525,525,319.5,239.5 --no-peers \
		--save-trajectory "$1/T.txt" --force >"$1/bench-$n.log" 2>&1 & done; wait' sh "$dir"
	local lines
	lines=$(grep -cE '^[0-9.eE+-]+( [0-9.eE+-]+){7}$' "$dir/T.txt" 2>/dev/null)
	check "two benches' trajectory holds $lines poses and $(grep -cv '^#' "$dir/T.txt") lines, not one whole file of 2 or 3" \
		test "$lines" -ge 2 -a "$lines" -le 3 -a "$(grep -cv '^#' "$dir/T.txt")" -eq "$lines"
	check "two benches left a temporary file beside the trajectory" test -z "$(find "$dir" -maxdepth 1 -name '.T.txt.*')"
}

# An output inside the input it reads is refused, even with --force, as bench's --save-trajectory:
# room's --out REC/room.yaml would replace the recording's own room, calibrate's --out REC/rig.yaml
# its rig.
test_outputs_inside_inputs_refused() {
	local rec=$repo/build/test-data/faults/rec sums
	cd "$repo" || return
	faults_recording || { failures+=("could not make the recording (see the log)"); return; }
	sums=$(cksum "$rec/room.yaml" "$rec/rig.yaml")
	rp room --recording "$rec" --out "$rec/room.yaml" --force
	check "room --out REC/room.yaml exited with status $rc, not 2" test "$rc" -eq 2
	check "room --out REC/room.yaml: the message does not name the input" says "--out $rec/room.yaml lies in the input $rec, which it would overwrite"
	rp room --recording "$rec" --out "$scratch/room.yaml" --picture "$rec/top.png"
	check "room --picture inside the recording exited with status $rc, not 2" test "$rc" -eq 2
	check "room --picture inside the recording: the message does not name the input" says "the picture $rec/top.png lies in the input $rec"
	rp calibrate --recording "$rec" --out "$rec/rig.yaml" --force
	check "calibrate --out REC/rig.yaml exited with status $rc, not 2" test "$rc" -eq 2
	check "calibrate --out REC/rig.yaml: the message does not name the input" says "--out $rec/rig.yaml lies in the input $rec"
	rp calibrate --images "$rec" --out "$rec/depth/rig.yaml"
	check "calibrate --out inside --images exited with status $rc, not 2" test "$rc" -eq 2
	check "the recording's room.yaml or rig.yaml changed" test "$(cksum "$rec/room.yaml" "$rec/rig.yaml")" = "$sums"
	check "room or calibrate wrote into the recording" test ! -e "$rec/top.png" -a ! -e "$rec/depth/rig.yaml"
}

# Issue #37: RoomProbe is meant to be MIT-licensed, so no CGAL header under GPL-3.0 may be in any
# translation unit's include closure (CGAL's LGPL kernel and Polygon_2 may).
test_no_gpl_cgal_headers() {
	rp shell bash tools/package/check_cgal_licences.sh
	check "check_cgal_licences.sh exited with status $rc (the GPL headers are in $log)" test "$rc" -eq 0
	check "check_cgal_licences.sh did not say ', 0 GPL or unlabelled'" says ", 0 GPL or unlabelled"
}

tests=(synth_out_outside_clone eval_outside_clone bench_tum_outside_clone relative_paths_from_another_folder missing_parent_refused unusable_paths_refused
	calibrate_refuses_and_never_overwrites synth_photometric_options_refused eval_refuses_bad_input numbers_out_of_range_refused
	record_relative_out_run_directly bake_prt_bakes_and_caches unknown_verb_is_named editor_sees_the_callers_files docs_name_existing_paths core_includes_run_downward
	input_devices_named aravis_plugin_missing_named synth_hdri_refused read_only_output_refused dev_full_outputs_refused full_disk_outputs synth_killed_midway record_killed_midway two_writers_one_output
	outputs_inside_inputs_refused
	no_gpl_cgal_headers)
# The verbs build what they run anyway; building it first says so, and fails once when it does not build.
echo "    building roomprobe_synth, roomprobe_eval, roomprobe_bench, roomprobe_calibrate, roomprobe_record, roomprobe_oni and roomprobe_room"
cd "$repo" || exit 1
rp build -Q build/bin/roomprobe_synth build/bin/roomprobe_eval build/bin/roomprobe_bench build/bin/roomprobe_calibrate build/bin/roomprobe_record \
	build/bin/roomprobe_oni build/bin/roomprobe_room build/bin/roomprobe_devices build/bin/libroomprobe_aravis.so
blocked=
((rc == 0)) || blocked="the tools did not build (see $log)"
run_host_tests host "$blocked" "${tests[@]}"
