# shellcheck shell=bash
# The path arguments of ./roomprobe's verbs, made to work from anywhere on the host.
# Sourced by toolchain.sh.
#
# rp_resolve_paths VERB ARGS... sets RP_ARGS to ARGS with the value of each path option made
# absolute (a relative path is relative to $RP_CALLER_PWD, the caller's folder before ./roomprobe
# changed to the clone), and RP_BINDS to the host folders that the sysroot toolchain must bind at
# their own paths for those values to mean the same file inside it (rp_toolchain_run does). The
# clone and ../shared are always there, so paths in them need no bind; with the host's own
# toolchain nothing does. A path that cannot be made visible is refused, naming the option: the
# tools never read or write inside the root by mistake. Both '--opt VALUE' and '--opt=VALUE' are
# recognised and passed on in the form given.

RP_CALLER_PWD=${RP_CALLER_PWD:-$PWD}
RP_ARGS=()
RP_BINDS=()
RP_PATH=
RP_KIND=
RP_MKDIRS=()

# What VERB's OPTION names: 'in' (an existing file or folder, read), 'out-dir' (a folder written,
# created here when missing: its parent must exist), 'out-file' (a file written: its folder must
# exist); nothing when the option takes no path.
rp_path_option() {
	case "$1 $2" in
	"synth --out" | "eval --out" | "record --out" | "export --out") echo out-dir ;;
	"bench --save-trajectory" | "oni --out" | "calibrate --out" | "room --out" | "room --picture") echo out-file ;;
	"synth --rig" | "synth --hdri" | "bench --recording" | "bench --tum" | "bench --7scenes" | "bench --rig" | \
		"bench --intrinsics" | "bench --open3d-results" | "soak --recording" | "eval --recording" | "room --recording" | "record --rig" | "oni --recording" | \
		"calibrate --images" | "calibrate --recording" | "calibrate --ocamcalib" | "export --project" | "export --recording") echo in ;;
	esac
}

# True when OPTION's VALUE is a word, not a path: --hdri none, --intrinsics fx,fy,cx,cy.
rp_path_literal() {
	[[ $1 == --hdri && $2 == none ]] || [[ $1 == --intrinsics && $2 =~ ^[-+.0-9eE]+(,[-+.0-9eE]+)+$ ]]
}

rp_path_within() { [[ $1 == "$2" || $1 == "$2"/* ]]; }

# The root's own top folder that PATH is in (/ for / itself), which a bind from the host would
# hide or break; nothing (and false) for a path the host may show there (/tmp, /home, /var/tmp...).
rp_system_folder() {
	local rest=${1#/}
	rp_path_within "$1" /var/tmp && return 1
	case /${rest%%/*} in
	/ | /proc | /sys | /dev | /run | /usr | /etc | /bin | /sbin | /lib | /lib32 | /lib64 | /libx32 | /boot | /var) echo "/${rest%%/*}" ;;
	*) return 1 ;;
	esac
}

# rp_visible_path NAME KIND VALUE: the absolute path of VALUE in RP_PATH, with the folder it needs
# bound added to RP_BINDS; dies when that cannot be. NAME ('synth --out') is for the messages.
rp_visible_path() {
	local name=$1 kind=$2 path=$3 bind parent system have
	[[ $path == /* ]] || path=$RP_CALLER_PWD/$path
	[[ $path != *$'\n'* ]] || rp_die "$name: a path with a newline in it is not supported"
	path=$(realpath -m -- "$path")
	parent=$(dirname -- "$path")
	case $kind in
	in)
		[[ -e $path ]] || rp_die "$name $path: no such file or folder"
		# A device, a pipe or a socket is named for what it is (issue #38: /dev/zero was once "no such file").
		[[ -f $path || -d $path ]] || rp_die "$name $path: not a regular file or folder ($(stat -L -c %F -- "$path" 2>/dev/null || echo unknown))"
		bind=$path
		[[ -d $path ]] || bind=$parent
		;;
	out-dir)
		[[ -d $parent ]] || rp_die "$name $path: the folder $parent does not exist; create it first"
		[[ ! -e $path || -d $path ]] || rp_die "$name $path: exists and is not a folder"
		bind=$path
		;;
	out-file)
		[[ -d $parent ]] || rp_die "$name $path: the folder $parent does not exist; create it first"
		bind=$parent
		;;
	esac
	if [[ $RP_KIND == sysroot ]] && ! rp_path_within "$bind" "$RP_REPO" &&
		! { [[ -d $RP_SHARED ]] && rp_path_within "$bind" "$RP_SHARED"; }; then
		! rp_path_within "$bind" "$RP_ROOT" || rp_die "$name $path: this is inside the toolchain root $RP_ROOT; use a folder outside it"
		! system=$(rp_system_folder "$bind") ||
			rp_die "$name $path: the toolchain root has its own $system, so this path cannot be shown inside it; use a folder elsewhere"
		for have in "${RP_BINDS[@]}"; do
			[[ $have == "$bind" ]] && bind=
		done
		[[ -z $bind ]] || RP_BINDS+=("$bind")
	fi
	[[ $kind != out-dir || -d $path ]] || RP_MKDIRS+=("$name" "$path")
	RP_PATH=$path
}

rp_resolve_paths() {
	local verb=$1 arg opt value kind
	shift
	RP_ARGS=()
	RP_BINDS=()
	RP_KIND=$(rp_toolchain_kind)
	RP_MKDIRS=() # option, folder: made once every path is known to be fine
	while (($# > 0)); do
		arg=$1
		shift
		opt=${arg%%=*}
		kind=$(rp_path_option "$verb" "$opt")
		if [[ -z $kind ]] || [[ $arg != *=* && $# -eq 0 ]]; then
			RP_ARGS+=("$arg") # not a path option, or one without its value: the tool says so
			continue
		fi
		if [[ $arg == *=* ]]; then
			value=${arg#*=}
		else
			value=$1
			shift
		fi
		if [[ -n $value ]] && ! rp_path_literal "$opt" "$value"; then
			rp_visible_path "$verb $opt" "$kind" "$value"
			value=$RP_PATH
		fi
		if [[ $arg == *=* ]]; then RP_ARGS+=("$opt=$value"); else RP_ARGS+=("$opt" "$value"); fi
	done
	set -- "${RP_MKDIRS[@]}"
	while (($# > 0)); do
		[[ -d $2 ]] || mkdir -- "$2" || rp_die "$1 $2: could not create the folder"
		shift 2
	done
}

# rp_editor_binds: RP_BINDS for ./roomprobe editor, so that the editor's file dialogs reach the
# user's files: /home, /media, /mnt, /srv, $HOME and the caller's folder, where they exist. A
# folder that the root has its own of (/usr, /etc...), or that holds the toolchain root itself
# (binding it would show the root inside itself), is left out.
rp_editor_binds() {
	local dir have
	RP_BINDS=()
	[[ $(rp_toolchain_kind) == sysroot ]] || return 0
	for dir in /home /media /mnt /srv "${HOME:-}" "$RP_CALLER_PWD"; do
		[[ -n $dir && -d $dir ]] || continue
		dir=$(realpath -- "$dir")
		rp_system_folder "$dir" >/dev/null && continue
		rp_path_within "$RP_ROOT" "$dir" && continue
		rp_path_within "$dir" "$RP_ROOT" && continue
		for have in "${RP_BINDS[@]}"; do
			rp_path_within "$dir" "$have" && continue 2
		done
		RP_BINDS+=("$dir")
	done
}
