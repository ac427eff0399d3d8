#!/bin/sh
# compare-builds.sh: run two saarsim builds on the same views, modes and
# configs and compare their JSON reports' simulated figures
# (scripts/report-diff.py: everything but `host`).
#
#   scripts/compare-builds.sh OLD_SAARSIM NEW_SAARSIM [OUT_DIR]
#
# Environment: VIEWS (default /work/shared/scenes/views.yaml), NAMES (the
# views, default "cornell teapot bunny sponza conference robots"), SIZE
# (default 256x256), MODES (default "cycle functional sampled"), CONFIGS
# (default "std vma": saarcor-std, and the VMA on a 16 MB board so the
# on-board cache evicts), EXTRA (more saarsim arguments for every run).
# Exits 1 when any pair of reports differs. Written for issue 29 (the
# data-carrying memory must leave every figure as it was).
set -u
# No default world-cache folder (issue 36): these runs measure or compare
# builds, renders and sampled warming as they were, and write nothing into
# the user's home; a run that wants a cache names its own (--world-cache).
SAARSIM_CACHE_DIR=off
export SAARSIM_CACHE_DIR
old=${1:?usage: compare-builds.sh OLD_SAARSIM NEW_SAARSIM [OUT_DIR]}
new=${2:?usage: compare-builds.sh OLD_SAARSIM NEW_SAARSIM [OUT_DIR]}
out=${3:-$(mktemp -d)}
here=$(cd "$(dirname "$0")" && pwd)
VIEWS=${VIEWS:-/work/shared/scenes/views.yaml}
NAMES=${NAMES:-cornell teapot bunny sponza conference robots}
SIZE=${SIZE:-256x256}
MODES=${MODES:-cycle functional sampled}
CONFIGS=${CONFIGS:-std vma}
EXTRA=${EXTRA:-}
mkdir -p "$out" || exit 2
pairs=""
fail=0
for v in $NAMES; do
	for m in $MODES; do
		for c in $CONFIGS; do
			case $c in
			std) cf="" ;;
			vma) cf="--set memory.vma.enabled=true --set memory.sdram.mb=16" ;;
			*) echo "compare-builds: unknown config $c" >&2; exit 2 ;;
			esac
			for b in old new; do
				if [ $b = old ]; then bin=$old; else bin=$new; fi
				# shellcheck disable=SC2086
				if ! "$bin" --views "$VIEWS" --view "$v" --size "$SIZE" --fidelity "$m" \
					$cf $EXTRA --report "$out/$v-$m-$c-$b.json" >"$out/$v-$m-$c-$b.txt" 2>&1; then
					echo "compare-builds: $b failed on $v $m $c (see $out/$v-$m-$c-$b.txt)" >&2
					fail=1
				fi
			done
			grep -q "DIFFERENT" "$out/$v-$m-$c-new.txt" && {
				echo "compare-builds: $v $m $c: the new frame differs from kernel-ref's" >&2
				fail=1
			}
			pairs="$pairs $out/$v-$m-$c-old.json $out/$v-$m-$c-new.json"
		done
	done
done
# shellcheck disable=SC2086
python3 "$here/report-diff.py" $pairs || fail=1
exit $fail
