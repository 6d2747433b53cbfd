# shellcheck shell=bash
# RoomProbe's toolchain: the host's own Godot 4 and libraries where it has them,
# otherwise a Debian sid root (debootstrap) kept in a cache folder outside the clone.
#
# Sourced by ./roomprobe. Public entry point: rp_toolchain_run CMD [ARGS...]
# runs CMD inside the toolchain with the current directory unchanged; the folders in RP_BINDS
# (set by rp_resolve_paths, paths.sh) are bound there at their own paths too.
#
# The root is entered in a private mount namespace (unshare, as root) or with
# bubblewrap (without root). Every mount lives in that namespace only, so it goes
# away with the last process in it, whichever way the command ends (Ctrl-C included).
#
# Environment:
#   ROOMPROBE_TOOLCHAIN   auto (default) | host | sysroot
#   ROOMPROBE_CACHE       cache folder (default: $XDG_CACHE_HOME/roomprobe or ~/.cache/roomprobe)
#   ROOMPROBE_MIRROR      Debian mirror for the root (default: the host's own apt mirror)

RP_TOOLCHAIN_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
RP_REPO=$(cd "$RP_TOOLCHAIN_DIR/../.." && pwd)
RP_SHARED=$(cd "$RP_REPO/.." && pwd)/shared
RP_PACKAGES_FILE="$RP_TOOLCHAIN_DIR/packages.txt"
RP_CACHE=${ROOMPROBE_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/roomprobe}
RP_ROOT="$RP_CACHE/sid-root"
RP_STAMP_NAME=.roomprobe-packages.sha256
RP_APT_OPTS=(-o Acquire::Check-Valid-Until=false -o Dpkg::Use-Pty=0 -o APT::Install-Recommends=false)

rp_log() { printf 'roomprobe: %s\n' "$*" >&2; }
rp_die() { printf 'roomprobe: error: %s\n' "$*" >&2; exit 1; }


# True when the host itself has Godot >= 4.4, scons and the development packages.
rp_host_has_toolchain() {
	command -v godot >/dev/null 2>&1 || return 1
	command -v scons >/dev/null 2>&1 || return 1
	command -v pkg-config >/dev/null 2>&1 || return 1
	local version major minor
	version=$(godot --version 2>/dev/null | head -n1) || return 1
	major=${version%%.*}
	minor=${version#*.}; minor=${minor%%.*}
	[[ $major =~ ^[0-9]+$ && $minor =~ ^[0-9]+$ ]] || return 1
	((major > 4 || (major == 4 && minor >= 4))) || return 1
	pkg-config --exists opencv4 OpenEXR aravis-0.8 libopenni2 2>/dev/null || return 1
	[[ -f /usr/include/CGAL/version.h && -f /usr/include/embree4/rtcore.h && -d /usr/include/glm ]] || return 1
}

# The Debian mirror the host's apt already uses, so that no address is hard-coded here.
rp_mirror() {
	if [[ -n ${ROOMPROBE_MIRROR:-} ]]; then
		echo "$ROOMPROBE_MIRROR"
		return
	fi
	local uri
	uri=$(cat /etc/apt/sources.list.d/*.sources 2>/dev/null | awk '/^URIs:/ {for (i = 2; i <= NF; i++) print $i}' | grep -E '/debian/?$' | head -n1)
	[[ -n $uri ]] || uri=$(awk '$1 == "deb" {print $2}' /etc/apt/sources.list 2>/dev/null | grep -E '/debian/?$' | head -n1)
	[[ -n $uri ]] || rp_die "no Debian mirror found in /etc/apt; set ROOMPROBE_MIRROR"
	echo "${uri%/}"
}

# Runs a command inside root $1 as root, with proc, dev, sys and the clone and shared/ at their own
# paths, and the folders in RP_BINDS (rp_resolve_paths) too.
rp_enter_root() {
	local root=$1
	shift
	[[ $EUID -eq 0 ]] || rp_die "entering the sid root for set-up needs root"
	ROOMPROBE_EXTRA_BINDS=$(rp_binds_sorted) unshare --mount --propagation private -- \
		bash "$RP_TOOLCHAIN_DIR/enter.sh" "$root" "$RP_REPO" "$RP_SHARED" "$PWD" "$@"
}

# The same without root, by bubblewrap: the root's /tmp is a fresh tmpfs, and HOME is /tmp.
rp_bwrap_root() {
	local root=$1 dir
	shift
	command -v bwrap >/dev/null 2>&1 || rp_die "without root, entering $root needs bubblewrap (apt-get install bubblewrap)"
	local binds=()
	while IFS= read -r dir; do
		[[ -n $dir ]] && binds+=(--bind "$dir" "$dir")
	done < <(rp_binds_sorted)
	binds+=(--bind "$RP_REPO" "$RP_REPO")
	[[ -d $RP_SHARED ]] && binds+=(--bind "$RP_SHARED" "$RP_SHARED")
	bwrap --bind "$root" / --proc /proc --dev /dev --ro-bind /sys /sys --tmpfs /tmp \
		--ro-bind /etc/resolv.conf /etc/resolv.conf "${binds[@]}" --chdir "$PWD" \
		--setenv HOME /tmp --setenv PATH /usr/local/bin:/usr/bin:/bin -- "$@"
}

# RP_BINDS one a line, sorted, less those inside another one (which the recursive bind of that one
# shows already).
rp_binds_sorted() {
	((${#RP_BINDS[@]} > 0)) || return 0
	printf '%s\n' "${RP_BINDS[@]}" | LC_ALL=C sort -u |
		awk '{ for (i = 1; i <= n; i++) if ($0 == kept[i] || index($0, kept[i] "/") == 1) next; kept[++n] = $0; print }'
}

# Creates or updates the cached sid root so that it holds every package in packages.txt.
rp_ensure_root() { rp_ensure_named_root sid "$RP_ROOT" "$RP_PACKAGES_FILE"; }

# The Debian 12 (bookworm) root that builds the shipped library (./roomprobe package, export):
# built there against bookworm's libraries, the library and the ones bundled with it need
# nothing newer than glibc 2.36 (tools/package/, docs/addon.md).
RP_SHIP_ROOT="$RP_CACHE/bookworm-root"
rp_ensure_ship_root() { rp_ensure_named_root bookworm "$RP_SHIP_ROOT" "$RP_TOOLCHAIN_DIR/packages-ship.txt"; }

# A bare Debian root (minbase plus PACKAGES, space-separated), for tests that must not see the
# toolchain's libraries: the shipped addon loading on bare Debian 12, the exported app on a machine
# with only its engine template.
rp_ensure_bare_root() { # SUITE NAME PACKAGES
	local list="$RP_CACHE/$2.packages"
	mkdir -p "$RP_CACHE"
	printf '%s\n' $3 >"$list.new"
	rp_ensure_named_root "$1" "$RP_CACHE/$2" "$list.new"
}

# Creates or updates root $2, of Debian suite $1, so that it holds every package in file $3
# (one a line, '#' comments). The root is keyed by the list's hash.
rp_ensure_named_root() {
	local suite=$1 root=$2 packages_file=$3 want have list
	list=$(sed -e 's/#.*//' -e 's/[[:space:]]//g' "$packages_file" | grep -v '^$' || true)
	want=$(printf '%s\n' "$suite" "$list" | sha256sum | cut -d' ' -f1)
	[[ $suite == sid ]] && want=$(printf '%s\n' "$list" | sha256sum | cut -d' ' -f1) # as before: keeps existing caches
	have=$(cat "$root/$RP_STAMP_NAME" 2>/dev/null || true)
	[[ $want == "$have" ]] && return 0
	[[ $EUID -eq 0 ]] || rp_die "the $suite root at $root is missing or out of date, and building it needs root (or install Godot >= 4.4 and the packages in $packages_file on the host)"

	mkdir -p "$RP_CACHE"
	exec 9>"$RP_CACHE/lock"
	flock 9
	have=$(cat "$root/$RP_STAMP_NAME" 2>/dev/null || true)
	if [[ $want == "$have" ]]; then
		exec 9>&-
		return 0
	fi

	local start=$SECONDS target=$root name
	name=$(basename "$root")
	if [[ ! -x $root/usr/bin/apt-get ]]; then
		command -v debootstrap >/dev/null 2>&1 || {
			rp_log "installing debootstrap on the host"
			apt-get update -qq >&2 && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq debootstrap >&2
		} || rp_die "could not install debootstrap on the host"
		target="$root.partial"
		rm -rf "$target"
		local mirror
		mirror=$(rp_mirror)
		rp_log "creating a Debian $suite root in $target (debootstrap, about 30 s)"
		debootstrap --variant=minbase --include=ca-certificates "$suite" "$target" "$mirror" >"$RP_CACHE/$name-debootstrap.log" 2>&1 ||
			rp_die "debootstrap failed; see $RP_CACHE/$name-debootstrap.log"
		printf 'Acquire::Check-Valid-Until "false";\nAPT::Install-Recommends "false";\n' >"$target/etc/apt/apt.conf.d/90roomprobe"
	fi
	cp /etc/resolv.conf "$target/etc/resolv.conf" 2>/dev/null || true
	if [[ -n $list ]]; then
		rp_log "installing $(wc -l <<<"$list") packages into the $suite root $name (a minute or two the first time)"
		local RP_BINDS=() # the set-up needs none of the caller's folders
		# The list reaches the root as a file: the root sees the clone only once enter.sh binds it.
		printf '%s\n' "$list" >"$target/tmp/roomprobe-packages"
		rp_enter_root "$target" env DEBIAN_FRONTEND=noninteractive sh -c \
			'apt-get "$@" update -qq && apt-get "$@" install -y -qq $(cat /tmp/roomprobe-packages)' \
			sh "${RP_APT_OPTS[@]}" >"$RP_CACHE/$name-apt.log" 2>&1 ||
			rp_die "installing packages into the root $name failed; see $RP_CACHE/$name-apt.log"
	fi
	echo "$want" >"$target/$RP_STAMP_NAME"
	if [[ $target != "$root" ]]; then
		rm -rf "$root"
		mv "$target" "$root"
	fi
	rp_log "$suite root ready in $((SECONDS - start)) s: $root"
	exec 9>&-
}

# Runs CMD inside root $1 (with root rights or by bubblewrap), from the current directory.
rp_run_in_root() {
	local root=$1
	shift
	if [[ $EUID -eq 0 ]]; then
		rp_enter_root "$root" "$@"
	else
		rp_bwrap_root "$root" "$@"
	fi
}

# Which toolchain to use: prints 'host' or 'sysroot'.
rp_toolchain_kind() {
	case ${ROOMPROBE_TOOLCHAIN:-auto} in
	host) echo host ;;
	sysroot) echo sysroot ;;
	auto) if rp_host_has_toolchain; then echo host; else echo sysroot; fi ;;
	*) rp_die "ROOMPROBE_TOOLCHAIN must be auto, host or sysroot, not '$ROOMPROBE_TOOLCHAIN'" ;;
	esac
}

# Runs CMD in the toolchain, from the current directory.
rp_toolchain_run() {
	if [[ $(rp_toolchain_kind) == host ]]; then
		"$@"
		return
	fi
	rp_ensure_root
	rp_run_in_root "$RP_ROOT" "$@"
}

# shellcheck source=tools/toolchain/paths.sh
source "$RP_TOOLCHAIN_DIR/paths.sh"
