#!/bin/sh
# scripts/drt.sh: seed 000 §5's experiments on the chip (`make drt`;
# issue 32 item 3): docs/DRT.md and its plots docs/drt-*.png.
#
#   sh scripts/drt.sh [BUILD_DIR]        (default: build)
#
# Seed 000 (Boulos et al., Interactive Distribution Ray Tracing) §5 varies
# one setting at a time from its video's settings on the billiard table and
# counts triangle intersections per ray type. This does the same on the
# chip, on spd:billiard (docs/spd.md) with the camera and lights of
# configs/drt-views.yaml's billiard-drt view (16 samples per pixel, every
# effect on), one view per point written into DRT_OUT/views.yaml:
#   pinhole   spp 16, pinhole, point lights, mirrors, still camera: the
#             reference every cost per ray is relative to
#   ap-*      aperture 0 .. 0.4 (the video's: 0.02)
#   ls-*      light size 0 .. 1 (0.5)
#   gl-*      Phong exponent 32 .. 4096 (2048) and 0, the mirror
#   mb-*      camera motion over the shutter off, on (0.01, 0, 0) and 10x
# All views run through one scripts/sweep (docs/sweeps.md), `nice`, in
# cycle fidelity with the image check against kernel-ref, at DRT_SIZE
# (default 128x96: a few minutes on 2 shared cores), and with the cone
# culling of seed 004 off and on (chip.cone_cull; docs/DRT.md). The
# document is written by scripts/drt-doc.py from the runs' JSON reports:
# every number in it comes from a run.
#
# Environment:
#   DRT_SIZE   frame size (default 128x96)
#   DRT_JOBS   parallel runs (default 2)
#   DRT_OUT    run folder (default out/drt; a point already run is kept)
#   DRT_DOC    the document (default docs/DRT.md; the plots go beside it)
#   SAARSIM    the binary (default BUILD_DIR/saarsim)
# Needs POSIX sh, python3, GNU parallel and gnuplot. Bad input: one line,
# exit 2.
set -eu
# No default world-cache folder (issue 36): these runs measure or compare
# builds, renders and sampled warming as they were, and write nothing into
# the user's home; a run that wants a cache names its own (--world-cache).
SAARSIM_CACHE_DIR=off
export SAARSIM_CACHE_DIR

. "$(dirname "$0")/doc-lib.sh"
doc_init drt "${1:-build}"
SIZE=${DRT_SIZE:-128x96}
printf '%s\n' "$SIZE" | grep -Eq '^[1-9][0-9]{0,4}x[1-9][0-9]{0,4}$' || bad "DRT_SIZE must be WxH, got '$SIZE'"
JOBS=${DRT_JOBS:-2}
case $JOBS in '' | *[!0-9]* | 0) bad "DRT_JOBS must be a positive number, got '$JOBS'" ;; esac
OUT=${DRT_OUT:-$ROOT/out/drt}
DOC=${DRT_DOC:-$ROOT/docs/DRT.md}
mkdir -p "$OUT" "$(dirname "$DOC")"

# The billiard-drt view's camera and lights (configs/drt-views.yaml).
CAM='{eye: [-0.9, -1.2, 1.5], lookat: [0.25, 0, 0.8], up: [0, 0, 1], fov: 40}'
LIGHTS='[[-0.6, 0, 1.8], [0.6, 0, 1.8]]'
AP=0.02 LS=0.5 GL=2048 MB='[0.01, 0, 0]'
VIEWS=$OUT/views.yaml
NAMES=
view() { # name aperture light_size gloss motion
	printf '  %s:\n    scene: "spd:billiard"\n    camera: %s\n    lights: %s\n' "$1" "$CAM" "$LIGHTS"
	printf '    drt: {spp: 16, aperture: %s, focus: 1.45, light_size: %s, gloss: %s, motion: %s}\n' \
		"$2" "$3" "$4" "$5"
	NAMES="$NAMES,$1"
}
{
	echo "# written by scripts/drt.sh: seed 000 §5's experiments on spd:billiard"
	echo "views:"
	view pinhole 0 0 0 '[0, 0, 0]'
	for a in 0 0.02 0.05 0.1 0.2 0.4; do view "ap-$a" "$a" "$LS" "$GL" "$MB"; done
	for l in 0 0.1 0.25 0.5 1; do view "ls-$l" "$AP" "$l" "$GL" "$MB"; done
	for g in 0 32 128 512 2048 4096; do view "gl-$g" "$AP" "$LS" "$g" "$MB"; done
	view mb-off "$AP" "$LS" "$GL" '[0, 0, 0]'
	view mb-on "$AP" "$LS" "$GL" "$MB"
	view mb-10x "$AP" "$LS" "$GL" "[0.1, 0, 0]"
} >"$VIEWS.tmp"
mv "$VIEWS.tmp" "$VIEWS"
NAMES=${NAMES#,} # the braces ran in this shell: NAMES holds every view

CONE=
if "$SAARSIM" --list-config 2>/dev/null | grep -q '^chip.cone_cull'; then
	CONE="--set chip.cone_cull=false,true"
fi
say "$(printf '%s\n' "$NAMES" | tr ',' '\n' | wc -l | tr -d ' ') views at $SIZE, cycle fidelity${CONE:+, cone culling off and on}"
# shellcheck disable=SC2086
SAARSIM=$SAARSIM nice "$ROOT/scripts/sweep" --out "$OUT/sweep" --views "$VIEWS" --view "$NAMES" \
	--size "$SIZE" $CONE -j "$JOBS" --quiet || bad "the sweep failed (see $OUT/sweep/points/*.err)"
DR_OUT=$OUT/sweep DR_DOC=$DOC DR_SIZE=$SIZE DR_VIEWS=$VIEWS \
	DR_COMMIT=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown) \
	python3 "$ROOT/scripts/drt-doc.py"
say "wrote $DOC"
