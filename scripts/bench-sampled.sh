#!/bin/sh
# scripts/bench-sampled.sh: what a sampled run costs against a cycle run
# with their defaults (issue 36, target 3).
#
#   sh scripts/bench-sampled.sh
#
# Conference at SIZE (default 1024x768), the default config (16 threads
# per RTP), the default check. The headline pairs: a default cycle run
# against a default sampled run, both with the default world-cache
# folder (here SAARSIM_CACHE_DIR names a fresh temporary one for each
# mode, so "cold" is a first run into an empty folder and "warm" the
# run after it), and sampling.warming at its default, auto (stored
# warming, since there is a cache). The rows from before the default
# folder that still mean something: both modes without a cache
# (`--world-cache off`; auto then means full warming) and sampled with
# full warming on the warm cache. Then every shared view at SIZE with
# the defaults and a warm cache: the fps error and the whole-run
# speed-up of the default sampled run (ALL_VIEWS=0 leaves it out).
# Each run once (RUNS=n: the minimum of n; a cold run gets a fresh
# folder each time); the report's host figures split the time: load
# (scene, kd-tree, memory image), simulation, check (kernel-ref's packet
# and single-ray reference frames and the comparisons), whole run. Other
# jobs may share the machine: times are noisy, ratios between runs made
# together less so.
#
# Writes the section between <!-- BEGIN sampled --> and <!-- END sampled -->
# of docs/PERFORMANCE.md and prints it. Needs POSIX sh, awk, sed.
set -eu
say() { printf 'bench-sampled: %s\n' "$*" >&2; }
die() {
	say "error: $*"
	exit 1
}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
cd "$ROOT"
B=${B:-build}
SIM=$ROOT/$B/saarsim
[ -x "$SIM" ] || die "$SIM not found; run 'make' first"
SCENES=${SAAR_SCENES:-$ROOT/../shared/scenes}
VIEWS=$SCENES/views.yaml
[ -f "$VIEWS" ] || die "$VIEWS not found (set SAAR_SCENES)"
SIZE=${SIZE:-1024x768}
VIEW=${VIEW:-conference}
RUNS=${RUNS:-1}
case $RUNS in '' | *[!0-9]* | 0) die "RUNS must be a positive integer" ;; esac
DOC=docs/PERFORMANCE.md
DOCTMP=$DOC.tmp.$$
TMP=$(mktemp -d "${TMPDIR:-/tmp}/saar-smp.XXXXXX")
trap 'rm -rf "$TMP"; rm -f "$DOCTMP"' EXIT
jget() {
	# shellcheck disable=SC2020
	tr ',{}[]' '\n\n\n\n\n' <"$1" |
		sed -n "s/^[[:space:]]*\"$2\"[[:space:]]*:[[:space:]]*//p" | head -n 1 | tr -d '"'
}
load0=$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo "?")
t0=$(date +%s)
ROWS=$TMP/rows
: >"$ROWS"
# one row: label, the label of the row it is compared with, the cache
# folder (a path, "fresh:PATH" for an empty one at every run, or "-" for
# the flag's own), the view, then saarsim arguments; the run with the
# least whole time
point() {
	label=$1 ref=$2 cache=$3 view=$4
	shift 4
	best=
	i=0
	while [ "$i" -lt "$RUNS" ]; do
		i=$((i + 1))
		say "$label $view ($i/$RUNS)"
		case $cache in
		fresh:*)
			dir=${cache#fresh:}
			rm -rf "$dir"
			;;
		-) dir=off ;;
		*) dir=$cache ;;
		esac
		SAARSIM_CACHE_DIR=$dir "$SIM" --views "$VIEWS" --view "$view" --size "$SIZE" --quiet \
			--report "$TMP/r.json" "$@" >"$TMP/r.txt" 2>&1 ||
			{ cat "$TMP/r.txt" >&2; die "saarsim failed: $label"; }
		w=$(jget "$TMP/r.json" wall_s)
		if [ -z "$best" ] || awk -v a="$w" -v b="$best" 'BEGIN { exit !(a < b) }'; then
			best=$w
			cp "$TMP/r.json" "$TMP/best.json"
		fi
	done
	printf '%s %s %s %s %s %s %s %s %s %s %s\n' "$label" "$ref" "$view" \
		"$(jget "$TMP/best.json" fps)" "$(jget "$TMP/best.json" load_s)" \
		"$(jget "$TMP/best.json" sim_s)" "$(jget "$TMP/best.json" check_s)" \
		"$(jget "$TMP/best.json" wall_s)" "$(jget "$TMP/best.json" world_cache | tr ' ' _)" \
		"$(jget "$TMP/best.json" stored_warming | tr ' ' _)" \
		"$(jget "$TMP/best.json" warming | tr ' ' _)" >>"$ROWS"
}
C=$TMP/cache-cycle
S=$TMP/cache-sampled
point cycle_cold cycle_cold "fresh:$C" "$VIEW"
point sampled_cold cycle_cold "fresh:$S" "$VIEW" --fidelity sampled
point cycle_warm cycle_warm "$C" "$VIEW"
point sampled_warm cycle_warm "$S" "$VIEW" --fidelity sampled
point sampled_full_warm cycle_warm "$S" "$VIEW" --fidelity sampled --set sampling.warming=full
point cycle_nocache cycle_nocache - "$VIEW" --world-cache off
point sampled_nocache cycle_nocache - "$VIEW" --world-cache off --fidelity sampled
VROWS=$TMP/vrows
: >"$VROWS"
if [ "${ALL_VIEWS:-1}" != 0 ]; then
	mv "$ROWS" "$TMP/rows.main"
	: >"$ROWS"
	for v in $(sed -n 's/^  \([A-Za-z0-9_-]*\):[[:space:]]*$/\1/p' "$VIEWS"); do
		point cycle cycle "$TMP/cache-views" "$v" # stores
		point cycle cycle "$TMP/cache-views" "$v"
		point sampled cycle "$TMP/cache-views" "$v" --fidelity sampled # stores
		point sampled cycle "$TMP/cache-views" "$v" --fidelity sampled
	done
	mv "$ROWS" "$VROWS"
	mv "$TMP/rows.main" "$ROWS"
fi
elapsed=$(($(date +%s) - t0))
load1=$(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo "?")
GIT=$(git rev-parse --short HEAD)
[ -z "$(git status --porcelain --untracked-files=no)" ] || GIT="$GIT (plus uncommitted changes)"
SECTION=$TMP/section
{
	echo "<!-- BEGIN sampled -->"
	echo "## Sampled mode with its defaults (issue 36, target 3)"
	echo
	echo "Generated by scripts/bench-sampled.sh; do not edit by hand."
	echo
	echo "- Date: $(date -u '+%Y-%m-%d %H:%M UTC') (took $elapsed s); commit $GIT"
	echo "- Machine: $(nproc) CPUs; load average $load0 at start, $load1 at the end (other jobs share the machine: times are noisy)"
	echo "- Run: \`saarsim --views views.yaml --view $VIEW --size $SIZE\` with the default config (4 RTPs x 16 threads), the default check and the default world-cache folder (\`SAARSIM_CACHE_DIR\` naming a fresh one per mode: *cold* is the first run into it, *warm* the next), best of $RUNS by whole time; sampled runs at their defaults (\`--fidelity sampled\`: rate 0.1, \`sampling.warming\` auto, which chose *warming* below); *full*: \`--set sampling.warming=full\`; *nocache*: \`--world-cache off\`. Each row's speed-up and fps error are against the cycle row it names."
	echo
	echo "| run | against | fps | fps error | load s | sim s | check s | whole s | whole-run speed-up | sim speed-up | world cache | warming | stored warming |"
	echo "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---|---|"
	awk '{ f[$1] = $4; w[$1] = $8; s[$1] = $6 }
	{ printf "| %s | %s | %.1f | %+.2f%% | %.3f | %.3f | %.3f | %.3f | %.2f | %.2f | %s | %s | %s |\n", $1, $2, $4, 100 * ($4 - f[$2]) / f[$2], $5, $6, $7, $8, w[$2] / $8, s[$2] / $6, $9, $11, $10 }' "$ROWS"
	echo
	awk '{ l[$1] = $5; s[$1] = $6; c[$1] = $7; w[$1] = $8; f[$1] = $4 }
	END {
		printf "With its defaults a sampled run is %.2fx faster than a cycle run as a whole run on a cold cache (%.3f s against %.3f s: the sampled run builds the packet record and the warming run on top of the world and the reference frames) and %.2fx on a warm one (%.3f s against %.3f s), at %+.2f%% fps error. ", w["cycle_cold"] / w["sampled_cold"], w["sampled_cold"], w["cycle_cold"], w["cycle_warm"] / w["sampled_warm"], w["sampled_warm"], w["cycle_warm"], 100 * (f["sampled_warm"] - f["cycle_warm"]) / f["cycle_warm"]
		printf "Warm, load and check take %.3f s of the cycle run and %.3f s of the sampled one; the simulation alone is %.2fx faster (%.3f s against %.3f s). ", l["cycle_warm"] + c["cycle_warm"], l["sampled_warm"] + c["sampled_warm"], s["cycle_warm"] / s["sampled_warm"], s["sampled_warm"], s["cycle_warm"]
		printf "Without a cache (the defaults before issue 36'"'"'s default folder) the sampled run is %.2fx faster (%+.2f%% fps error).\n", w["cycle_nocache"] / w["sampled_nocache"], 100 * (f["sampled_nocache"] - f["cycle_nocache"]) / f["cycle_nocache"]
	}' "$ROWS"
	if [ -s "$VROWS" ]; then
		echo
		echo "Every shared view at $SIZE with the defaults on a warm cache (the second run of each mode; one run each):"
		echo
		echo "| view | cycle fps | sampled fps | fps error | cycle whole s | sampled whole s | whole-run speed-up | sim speed-up | warming |"
		echo "|---|---:|---:|---:|---:|---:|---:|---:|---|"
		awk '{ k = $1 "/" $3 } $1 == "cycle" { cf[$3] = $4; cw[$3] = $8; cs[$3] = $6 }
		$1 == "sampled" { sf[$3] = $4; sw[$3] = $8; ss[$3] = $6; wm[$3] = $11; if (!($3 in seen)) { seen[$3] = 1; order[n++] = $3 } }
		END {
			for (i = 0; i < n; i++) {
				v = order[i]
				e = 100 * (sf[v] - cf[v]) / cf[v]
				printf "| %s | %.1f | %.1f | %+.2f%% | %.3f | %.3f | %.2f | %.2f | %s |\n", v, cf[v], sf[v], e, cw[v], sw[v], cw[v] / sw[v], cs[v] / ss[v], wm[v]
				if (e < 0) e = -e
				if (e <= 2) ok++
			}
			printf "\nWithin 2%% fps error: %d of %d views.\n", ok, n
		}' "$VROWS"
	fi
	echo "<!-- END sampled -->"
} >"$SECTION"

. "$(dirname "$0")/doc-section.sh"
doc_section sampled "$SECTION" "$DOC" # its temporary is $DOCTMP
say "wrote $DOC (section sampled)"
cat "$SECTION"
