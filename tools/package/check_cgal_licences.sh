#!/usr/bin/env bash
# RoomProbe is meant to be MIT-licensed, so no CGAL package under GPL-3.0 may be compiled in;
# CGAL's LGPL parts (kernel, Polygon_2, predicates) may (issue #37). This lists every CGAL header
# in the include closure of every translation unit that reaches CGAL (g++ -M with the project's
# include folders), reads each header's SPDX line, and fails on a GPL one or on one without it.
#
# Usage, from the clone: ./roomprobe shell bash tools/package/check_cgal_licences.sh [--all]
# (inside the toolchain, whose /usr/include/CGAL the build uses). The translation units checked
# are the .cpp files that include CGAL themselves or through project headers (found by name);
# --all checks every .cpp instead (slower). Last line: 'cgal_licences: ...', status 0 when clean.
set -euo pipefail
cd "$(dirname "$(readlink -f "$0")")/../.."

all=no
[[ ${1:-} == --all ]] && all=yes
cgal=/usr/include/CGAL
[[ -d $cgal ]] || { echo "cgal_licences: no $cgal (run inside ./roomprobe shell)" >&2; exit 2; }

mapfile -t project < <(find extension tools tests -type f \( -name '*.cpp' -o -name '*.h' -o -name '*.hpp' \) -not -path '*/godot-cpp/*' | sort)

# The project files that include CGAL, then those that include one of them (by file name), to a fixpoint.
declare -A reaches=()
for f in "${project[@]}"; do
	grep -q '#include <CGAL/' "$f" && reaches[$f]=1
done
while :; do
	added=0
	for f in "${project[@]}"; do
		[[ -n ${reaches[$f]:-} ]] && continue
		for r in "${!reaches[@]}"; do
			[[ $r == *.cpp ]] && continue
			if grep -Eq "#include [<\"]([^>\"]*/)?$(basename "$r")[>\"]" "$f"; then
				reaches[$f]=1 added=1
				break
			fi
		done
	done
	((added)) || break
done

units=()
for f in "${project[@]}"; do
	[[ $f == *.cpp ]] && { [[ $all == yes ]] || [[ -n ${reaches[$f]:-} ]]; } && units+=("$f")
done

flags=(-std=c++20 -M -MG -Iextension/core -Iextension/drivers -Iextension/godot -Iextension/binding/include -Ibuild/gen -Itests/core)
# Third-party headers only matter for finding the project's; -MG lets a missing one pass.
read -ra pkg <<<"$(pkg-config --cflags-only-I opencv4 OpenEXR libpng 2>/dev/null || true)"
flags+=("${pkg[@]}")

declare -A used_by=()
for unit in "${units[@]}"; do
	deps=$(g++ "${flags[@]}" "$unit" 2>&1) || { echo "cgal_licences: g++ -M failed on $unit:"; echo "$deps" | tail -5; exit 2; }
	while read -r header; do
		used_by[$header]+="${used_by[$header]:+ }$unit"
	done < <(tr ' \\' '\n\n' <<<"$deps" | grep "^$cgal/" | sort -u)
done

bad=0
for header in $(printf '%s\n' "${!used_by[@]}" | sort); do
	spdx=$(grep -m1 -o 'SPDX-License-Identifier:.*' "$header" || true)
	if [[ -z $spdx || $spdx =~ SPDX-License-Identifier:[[:space:]]*GPL- ]]; then
		echo "${header#"$cgal"/}: ${spdx:-no SPDX line} (in ${used_by[$header]})"
		bad=$((bad + 1))
	fi
done
echo "cgal_licences: ${#units[@]} translation units, ${#used_by[@]} CGAL headers, $bad GPL or unlabelled"
((bad == 0))
