#!/bin/sh
# scripts/accel.sh: the acceleration structures compared (`make accel`;
# issue 34 items 1-3 and 5): docs/ACCEL.md.
#
#   sh scripts/accel.sh [BUILD_DIR]        (default: build)
#
# kernel-ref's kd-tree, the uniform grid of seed 003 (rtref --accel grid)
# and, on the animated Robots, the two-level trees (rtref --two-level), on
# the static shared views and on Robots frames. Per run: host build time,
# kernel-ref trace time (one thread), triangle tests per ray; seed 003's
# Table 4 experiment (cells visited and triangle tests of single rays, 4x4
# and 8x8 packets, primary rays, no macrocells); and the chip's frame rate,
# SDRAM traffic and L1 hit rates (saarsim, default config) on the kd-tree
# and on the grid (saarsim --accel grid: the grid traversal unit, issue 34
# item 4). Every run is `nice`, one
# host thread, at ACCEL_SIZE (default 128x96: a few minutes on 2 shared
# cores). The document is written by scripts/accel-doc.py from the runs'
# JSON: every number in it comes from a run.
#
# Environment:
#   ACCEL_SIZE    frame size (default 128x96)
#   ACCEL_VIEWS   static views of the shared views file (default: every
#                 view it names)
#   ACCEL_TIMES   Robots animation times (default: 0 10 20 30)
#   ACCEL_T4_VIEW the view of the Table 4 runs at 4x the size (conference)
#   ACCEL_OUT     run folder (default out/accel; runs already there are kept)
#   ACCEL_DOC     the document (default docs/ACCEL.md)
#   SAAR_SCENES   the shared scenes (default ../shared/scenes)
# Needs POSIX sh and python3. Bad input: one line, exit 2.
set -eu
# No default world-cache folder (issue 36): these runs measure or compare
# builds, renders and sampled warming as they were, and write nothing into
# the user's home; a run that wants a cache names its own (--world-cache).
SAARSIM_CACHE_DIR=off
export SAARSIM_CACHE_DIR

say() { printf 'accel: %s\n' "$*" >&2; }
bad() {
	say "$*"
	exit 2
}

ROOT=$(cd "$(dirname "$0")/.." && pwd)
B=${1:-build}
case $B in /*) ;; *) B=$ROOT/$B ;; esac
RTREF=$B/rtref
SAARSIM=$B/saarsim
[ -x "$RTREF" ] && [ -x "$SAARSIM" ] || bad "$B/rtref or $B/saarsim not found; run 'make' first"
command -v python3 >/dev/null 2>&1 || bad "python3 not found (sh scripts/install-deps.sh)"
SIZE=${ACCEL_SIZE:-128x96}
printf '%s\n' "$SIZE" | grep -Eq '^[1-9][0-9]{0,4}x[1-9][0-9]{0,4}$' || bad "ACCEL_SIZE must be WxH, got '$SIZE'"
# every view of views.yaml (its names: two-space-indented keys under views:)
VIEWS=${ACCEL_VIEWS:-$(awk '/^views:/ { v = 1; next } /^[^ #]/ { v = 0 }
	v && /^  [A-Za-z0-9_.-]+:[ \t]*$/ { n = $1; sub(/:$/, "", n); printf "%s ", n }' \
	"${SAAR_SCENES:-$ROOT/../shared/scenes}/views.yaml" 2>/dev/null)}
TIMES=${ACCEL_TIMES:-0 10 20 30}
SC=${SAAR_SCENES:-$ROOT/../shared/scenes}
VF=$SC/views.yaml
AFF=$SC/bart_robots_aff/aff/Robot.aff
[ -r "$VF" ] || bad "$VF not found (set SAAR_SCENES)"
[ -r "$AFF" ] || bad "$AFF not found (set SAAR_SCENES)"
OUT=${ACCEL_OUT:-$ROOT/out/accel}
DOC=${ACCEL_DOC:-$ROOT/docs/ACCEL.md}
mkdir -p "$OUT" "$(dirname "$DOC")"

# run FILE PROG ARGS...: one run into FILE (its JSON), unless it is there
run() {
	f=$1
	shift
	[ -s "$OUT/$f" ] && return 0
	say "$f"
	p=$1
	shift
	case $p in
	rtref) nice "$RTREF" "$@" --threads 1 --stats "$OUT/$f.tmp" >/dev/null ;;
	saarsim) nice "$SAARSIM" "$@" --quiet --report "$OUT/$f.tmp" >/dev/null ;;
	esac
	mv "$OUT/$f.tmp" "$OUT/$f"
}

# rtref's kd runs take the plain SAH tree, the one the chip walks
# (kernel-ref/kdtree.c): by default rtref builds its own for the view's
# packet footprint (docs/kernel-ref.md, "rtref's own tree"), which at this
# size cuts so little that its counts would say more about the frame size
# than about the structure.
KD="--kd-footprint 0"
for v in $VIEWS; do
	W="--views $VF --view $v --size $SIZE"
	run "$v-kd.json" rtref $W $KD --out "$OUT/$v-kd.ppm"
	run "$v-grid.json" rtref $W --accel grid --out "$OUT/$v-grid.ppm"
	run "$v-chip.json" saarsim $W
	run "$v-chip-grid.json" saarsim $W --accel grid
	# seed 003 Table 4: primary rays, no macrocells
	P="$W --no-shadows --depth 0"
	run "$v-t4-kd.json" rtref $P $KD
	for k in 1 4 8; do
		run "$v-t4-$k.json" rtref $P --accel grid --grid-macro 0 --grid-packet "$k"
	done
done

# Table 4 at four times the size on one view: the trend with ray density
BIG=${ACCEL_T4_VIEW:-conference}
BS=$(printf '%s\n' "$SIZE" | awk -Fx '{ print $1 * 4 "x" $2 * 4 }')
P="--views $VF --view $BIG --size $BS --no-shadows --depth 0 --accel grid --grid-macro 0"
for k in 1 4 8; do
	run "$BIG-big-t4-$k.json" rtref $P --grid-packet "$k"
done

for t in $TIMES; do
	R="--scene $AFF --anim-time $t --size $SIZE"
	run "robots-$t-kd.json" rtref $R $KD --out "$OUT/robots-$t-kd.ppm"
	run "robots-$t-grid.json" rtref $R --accel grid --out "$OUT/robots-$t-grid.ppm"
	run "robots-$t-two-level.json" rtref $R --two-level --out "$OUT/robots-$t-two-level.ppm"
	run "robots-$t-chip.json" saarsim $R
	run "robots-$t-chip-grid.json" saarsim $R --accel grid
	run "robots-$t-chip-two-level.json" saarsim $R --two-level
done

# two runs of the first view for `make test` to rerun (scripts/figures-check.py):
# the chip on the kd-tree, and rtref's Table 4 run on the plain tree
set -- $VIEWS
V1=$1
python3 "$ROOT/scripts/figures-check.py" --emit saarsim "$OUT/$V1-chip.json" fps cycles \
	traversal.kd_node_steps -- --views "$VF" --view "$V1" --size "$SIZE" --quiet >"$OUT/checks" &&
	python3 "$ROOT/scripts/figures-check.py" --emit rtref "$OUT/$V1-t4-kd.json" kd_node_visits \
		ray_triangle_tests leaf_visits -- --views "$VF" --view "$V1" --size "$SIZE" \
		--no-shadows --depth 0 --threads 1 $KD >>"$OUT/checks" || bad "figures-check.py --emit failed"

# what the document names as its origin: the commit, the date, the host
ACCEL_COMMIT=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
if [ -n "$(git -C "$ROOT" status --porcelain --untracked-files=no 2>/dev/null)" ]; then
	ACCEL_COMMIT="$ACCEL_COMMIT (with uncommitted changes)"
fi
ACCEL_DATE=$(date -u '+%Y-%m-%d %H:%M UTC')
ACCEL_HOST="$(nproc 2>/dev/null || echo '?') CPUs, $(awk -F': ' '/^model name/ { print $2; exit }' /proc/cpuinfo 2>/dev/null || :)"
export ACCEL_COMMIT ACCEL_DATE ACCEL_HOST
python3 "$ROOT/scripts/accel-doc.py" "$OUT" "$DOC" "$SIZE" "$VIEWS" "$TIMES" "$BIG" "$BS"
say "wrote $DOC"
