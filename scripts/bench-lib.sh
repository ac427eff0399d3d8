# scripts/bench-lib.sh: the common start of the bench-*.sh scripts that
# measure saarsim and write one section of docs/PERFORMANCE.md. Sourced,
# not run:
#
#   . "$(dirname "$0")/bench-lib.sh"
#   bench_init NAME
#
# Sets ROOT (the repository; the script runs from it), B (the build folder,
# default build), SIM (B/saarsim, checked), SCENES and VIEWS (the shared
# scenes and views.yaml, checked); say and die print "NAME: ..." on
# stderr (die exits 1). Turns the default world-cache folder off (issue
# 36): these runs measure builds, renders and warming as they are and
# write nothing into the user's home; a run that wants a cache names its
# own (--world-cache). jget FILE KEY: the first value of KEY in a JSON
# report, quotes removed. bench_views: the names of VIEWS' views (the
# two-space-indented keys under `views:`), one a line. bench_start TAG,
# for a script that writes a section of docs/PERFORMANCE.md: DOC (that
# file), TMP (a scratch folder saar-TAG.*), an exit trap that removes it
# and doc_section's temporary ($DOC.tmp.$$), doc_section and its helpers
# (doc-section.sh), load0 (the load average), t0 (the start, seconds),
# VLIST (bench_views) and ROWS (an empty file $TMP/rows for the rows).
# bench_end, once the measurements are done: elapsed (seconds since
# bench_start), load1 (the load average then), GIT (doc_commit) and
# SECTION (the file the section is written into before doc_section).
# pct_err F T: F's difference from T in percent of T, signed, two decimals.
# md_head LEAD FMT RULE ITEMS...: a markdown table's header row (LEAD,
# then printf FMT of each item) and its rule (RULE, then a right-aligned
# column for each item).
# lt A B: true when number A < number B. bench_min CUR NEW: the smaller
# of the two numbers (NEW when CUR is empty: the best of runs so far).
BENCH_NAME=bench
say() { printf '%s: %s\n' "$BENCH_NAME" "$*" >&2; }
die() {
	say "error: $*"
	exit 1
}
bench_init() {
	BENCH_NAME=$1
	SAARSIM_CACHE_DIR=off
	export SAARSIM_CACHE_DIR
	ROOT=$(cd "$(dirname "$0")/.." && pwd)
	cd "$ROOT"
	B=${B:-build}
	SIM=$ROOT/$B/saarsim
	[ -x "$SIM" ] || die "$SIM not found; run 'make' first"
	SCENES=$(cd "${SAAR_SCENES:-$ROOT/../shared/scenes}" 2>/dev/null && pwd) ||
		die "the shared scenes are not at ${SAAR_SCENES:-$ROOT/../shared/scenes} (set SAAR_SCENES)"
	VIEWS=$SCENES/views.yaml
	[ -f "$VIEWS" ] || die "$VIEWS not found (set SAAR_SCENES)"
}
jget() {
	# shellcheck disable=SC2020
	tr ',{}[]' '\n\n\n\n\n' <"$1" |
		sed -n "s/^[[:space:]]*\"$2\"[[:space:]]*:[[:space:]]*//p" | head -n 1 | tr -d '"'
}
bench_views() {
	awk '/^views:/ { v = 1; next } v && /^[^[:space:]#]/ { v = 0 }
	v && /^  [A-Za-z0-9_-]+:/ { sub(/^  /, ""); sub(/:.*/, ""); print }' "$VIEWS"
}
bench_start() {
	DOC=docs/PERFORMANCE.md
	TMP=$(mktemp -d "${TMPDIR:-/tmp}/saar-$1.XXXXXX")
	trap 'rm -rf "$TMP"; rm -f "$DOC.tmp.$$"' EXIT
	. "$ROOT/scripts/doc-section.sh"
	load0=$(doc_load)
	t0=$(date +%s)
	VLIST=$(bench_views)
	ROWS=$TMP/rows
	: >"$ROWS"
}
bench_end() {
	elapsed=$(($(date +%s) - t0))
	load1=$(doc_load)
	GIT=$(doc_commit)
	SECTION=$TMP/section
}
lt() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a + 0 < b + 0) }'; }
bench_min() {
	if [ -z "$1" ] || lt "$2" "$1"; then echo "$2"; else echo "$1"; fi
}
# The median, the least and the greatest of the numbers given: "med lo hi".
med_range() {
	printf '%s\n' "$@" | sort -g | awk '{ v[++n] = $1 }
	END { if (!n) exit 1; printf "%.4f %.4f %.4f\n", (n % 2 ? v[(n + 1) / 2] : (v[n / 2] + v[n / 2 + 1]) / 2), v[1], v[n] }'
}
md_head() {
	mh_lead=$1 mh_fmt=$2 mh_rule=$3
	shift 3
	printf '%s' "$mh_lead"
	for mh_x in "$@"; do printf "$mh_fmt" "$mh_x"; done
	echo
	printf '%s' "$mh_rule"
	for mh_x in "$@"; do printf -- '---:|'; done
	echo
}
pct_err() {
	awk -v f="$1" -v t="$2" 'BEGIN { printf "%+.2f", (f / t - 1) * 100 }'
}
