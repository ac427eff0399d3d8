#!/bin/sh
# scripts/dynamic.sh: BART Robots animated on the chip, one kd-tree over the
# flattened scene rebuilt every frame against the two-level tree (issue 33
# item 5; `make dynamic`).
#
#   sh scripts/dynamic.sh [BUILD_DIR]        (default: build)
#
# Six saarsim animations of DYN_FRAMES frames at DYN_FPS frames per second
# of scene time from DYN_T0 (defaults 10, 1, 0), at DYN_SIZE (default
# 160x120), each with configs/saarcor-std.yaml (scene on the board) and
# configs/saarcor-vma.yaml (scene in host memory, read over PCI): flat (a
# cold chip per frame), --two-level --anim-cold (the same, two-level) and
# --two-level (one warm chip, the host's update written between frames).
# Every frame is checked against kernel-ref.
# scripts/dynamic-doc.py writes docs/DYNAMIC.md and docs/dynamic-fps.png
# from the runs' JSON reports. Runs are kept in DYN_OUT (default out/dynamic).
# About a minute on 2 shared cores at the defaults.
set -eu
# No default world-cache folder (issue 36): these runs measure or compare
# builds, renders and sampled warming as they were, and write nothing into
# the user's home; a run that wants a cache names its own (--world-cache).
SAARSIM_CACHE_DIR=off
export SAARSIM_CACHE_DIR

. "$(dirname "$0")/doc-lib.sh"
doc_init dynamic "${1:-build}"
SCENES=${SAAR_SCENES:-$ROOT/../shared/scenes}
AFF=$SCENES/bart_robots_aff/aff/Robot.aff
[ -f "$AFF" ] || bad "$AFF not found (set SAAR_SCENES)"
SIZE=${DYN_SIZE:-160x120}
printf '%s\n' "$SIZE" | grep -Eq '^[1-9][0-9]{0,4}x[1-9][0-9]{0,4}$' || bad "DYN_SIZE must be WxH, got '$SIZE'"
FRAMES=${DYN_FRAMES:-10}
case $FRAMES in '' | *[!0-9]* | 0) bad "DYN_FRAMES must be a positive number, got '$FRAMES'" ;; esac
FPS=${DYN_FPS:-1}
T0=${DYN_T0:-0}
OUT=${DYN_OUT:-$ROOT/out/dynamic}
DOC=${DYN_DOC:-$ROOT/docs/DYNAMIC.md}
mkdir -p "$OUT" "$(dirname "$DOC")"

# run NAME CONFIG [FLAGS]: one animation, reports OUT/NAME-NNNN.json
run() {
	name=$1
	cfg=$2
	shift 2
	rm -f "$OUT/$name"-*.json
	nice "$SAARSIM" --scene "$AFF" --config "$ROOT/configs/$cfg.yaml" --size "$SIZE" \
		--anim-time "$T0" --anim-fps "$FPS" --frames "$FRAMES" --quiet "$@" \
		--report "$OUT/$name.json" >"$OUT/$name.txt" 2>&1 || bad "$name failed (see $OUT/$name.txt)"
	if grep -q "packets DIFFERENT\|single rays DIFFERENT" "$OUT/$name.txt"; then
		bad "$name: a frame differs from kernel-ref's (see $OUT/$name.txt)"
	fi
	# two runs for `make test` to rerun (scripts/figures-check.py): the warm
	# animation as it ran, and the flat one's first frame alone (each flat
	# frame is a fresh world and chip)
	case $name in
	warm-std) python3 "$ROOT/scripts/figures-check.py" --emit saarsim "$OUT/$name.json" \
		per_frame.0.fps steady_state.fps -- --scene "$AFF" --config "$ROOT/configs/$cfg.yaml" \
		--size "$SIZE" --anim-time "$T0" --anim-fps "$FPS" --frames "$FRAMES" --quiet "$@" \
		>"$OUT/$name.check" || bad "$name: figures-check.py --emit failed" ;;
	flat-std)
		f0=$OUT/$name.json
		[ "$FRAMES" -gt 1 ] && f0=$OUT/$name-0000.json
		python3 "$ROOT/scripts/figures-check.py" --emit saarsim "$f0" fps cycles \
			traversal.kd_node_steps -- --scene "$AFF" --config "$ROOT/configs/$cfg.yaml" \
			--size "$SIZE" --anim-time "$T0" --quiet "$@" >"$OUT/$name.check" ||
			bad "$name: figures-check.py --emit failed" ;;
	*) rm -f "$OUT/$name.check" ;;
	esac
}

say "Robots, $FRAMES frames at $FPS fps from t = $T0, $SIZE: flat and two-level, std and VMA"
# two at a time; a failed run fails the script
pair() {
	run "$1" "$2" &
	p1=$!
	run "$3" "$2" --two-level --anim-cold &
	p2=$!
	wait $p1 || exit 2
	wait $p2 || exit 2
	run "$4" "$2" --two-level
}
pair flat-std saarcor-std tl-std warm-std
pair flat-vma saarcor-vma tl-vma warm-vma
DY_OUT=$OUT DY_DOC=$DOC DY_SIZE=$SIZE DY_FRAMES=$FRAMES DY_FPS=$FPS DY_T0=$T0 \
	DY_COMMIT=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown) \
	python3 "$ROOT/scripts/dynamic-doc.py"
say "wrote $DOC"
