# shellcheck shell=bash
# Runs inside a private mount namespace (see toolchain.sh): mounts what the root needs,
# then chroots into it. The mounts vanish with the namespace, so there is nothing to undo.
# Usage: enter.sh ROOT REPO SHARED CWD CMD [ARGS...]
# ROOMPROBE_EXTRA_BINDS: more host folders to bind at their own paths, one a line (rp_binds_sorted
# in toolchain.sh: the folders of the caller's paths outside the clone).
set -euo pipefail
root=$1 repo=$2 shared=$3 cwd=$4
shift 4

bind() { # bind SRC at the same path inside the root
	mkdir -p "$root$1"
	mount --rbind "$1" "$root$1"
}
mount -t proc proc "$root/proc"
mount --rbind /dev "$root/dev"
mount --rbind /sys "$root/sys"
# The caller's folders first: should one of them hold the clone, the clone's bind lands on top.
while IFS= read -r dir; do
	[[ -n $dir ]] && bind "$dir"
done <<<"${ROOMPROBE_EXTRA_BINDS:-}"
bind "$repo"
[[ -d $shared ]] && bind "$shared"
# A cache outside the clone (build outputs, generated data) shared with the host, when asked for.
[[ -n ${ROOMPROBE_BUILD_CACHE:-} ]] && bind "$ROOMPROBE_BUILD_CACHE"
cp /etc/resolv.conf "$root/etc/resolv.conf" 2>/dev/null || true

exec chroot "$root" /usr/bin/env -i \
	HOME=/root PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
	TERM="${TERM:-dumb}" LANG=C.UTF-8 CI="${CI:-}" ROOMPROBE_IN_TOOLCHAIN=1 \
	ROOMPROBE_JOBS="${ROOMPROBE_JOBS:-}" \
	/bin/sh -c 'cd "$0" && exec "$@"' "$cwd" "$@"
