# shellcheck shell=bash
# What the suites that run on the host share (test_paths.sh: 'host', test_package.sh: 'package'):
# their arguments, the checks, and the result lines and summary that tools/run_tests.py reads.
# The caller sets $repo, calls host_suite_arguments "$@", and defines test_NAME for each test.

# host_suite_arguments [--filter SUBSTRING] RESULTS LOG: sets $filter, $results and $log (absolute)
# and empties both files; exits with status 2 and the usage on anything else.
host_suite_arguments() {
	filter=
	if [[ ${1:-} == --filter ]]; then
		filter=$2
		shift 2
	fi
	[[ $# -eq 2 ]] || { echo "usage: $0 [--filter SUBSTRING] RESULTS LOG" >&2; exit 2; }
	results=$(realpath -m -- "$1") log=$(realpath -m -- "$2")
	: >"$results"
	: >"$log"
}

# logged CMD...: runs CMD from the current folder; its output (both streams) in $out and the log,
# its exit status in $rc.
logged() {
	printf '\n$ (cd %q && %s)\n' "$PWD" "$(printf '%q ' "$@")" >>"$log"
	out=$("$@" 2>&1)
	rc=$?
	printf '%s\n[exit status %d]\n' "$out" "$rc" >>"$log"
}

# check WHAT COMMAND...: WHAT is one of the test's failures unless COMMAND succeeds.
check() {
	"${@:2}" || failures+=("$1")
}
says() { grep -qF -- "$1" <<<"$out"; }

# run_host_tests SUITE BLOCKED TEST...: runs test_TEST for each TEST whose 'SUITE::TEST' contains
# $filter, from the clone's folder, and writes '[PASS] SUITE::TEST' or '[FAIL] SUITE::TEST: why'
# to $results and the screen, then 'SUITE_TESTS N passed, N failed in S s' (SUITE in capitals).
# A non-empty BLOCKED fails every test with that reason instead of running it. Status: 0 when
# none failed.
run_host_tests() {
	local suite=$1 blocked=$2 t name line passed=0 failed=0 start seconds t_start
	shift 2
	start=$(date +%s.%N)
	for t in "$@"; do
		t_start=$(date +%s.%N)
		name=$suite::$t
		[[ $name == *"$filter"* ]] || continue
		printf '\n### %s\n' "$name" >>"$log"
		failures=()
		cd "$repo" || exit 1
		if [[ -z $blocked ]]; then
			"test_$t"
		else
			failures=("$blocked")
		fi
		if ((${#failures[@]} == 0)); then
			line="[PASS] $name"
			passed=$((passed + 1))
		else
			line="[FAIL] $name: $(printf '%s; ' "${failures[@]}")"
			line=${line%; }
			failed=$((failed + 1))
		fi
		echo "$line" >>"$results"
		# The screen and the log say how long each took, to find what makes a suite slow.
		seconds=$(awk -v a="$t_start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
		echo "    $line ($seconds s)"
		printf '### %s: %s s\n' "$name" "$seconds" >>"$log"
	done
	seconds=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { printf "%.1f", b - a }')
	echo "${suite^^}_TESTS $passed passed, $failed failed in $seconds s" >>"$results"
	((failed == 0))
}
