#!/bin/sh
# scripts/bench-profile.sh: where cycle mode spends its host time (issue 36).
#
#   sh scripts/bench-profile.sh [REV...]
#
# Counts instructions under callgrind (valgrind --tool=callgrind), which
# other jobs on the machine cannot disturb, unlike wall-clock times: for
# each view of PROFILE_VIEWS (default: conference bunny dragon2 sponza) at
# SIZE (default 256x192), saarsim in cycle mode with the default config,
# counting only chip_run (the simulation: --toggle-collect=chip_run; the
# scene comes from a world cache filled by a first, uncounted run), and
# rtref on the same frame with one host thread, counting only render_frame,
# as saarsim's check renders it (--per-lane --kd-footprint 0: the per-lane
# traversal on the chip's tree, the time sim_to_ref_ratio divides by). It
# writes the top TOP (default 12) functions of each saarsim profile
# by exclusive and by inclusive count.
#
# With REVs (commits), each is built in a temporary worktree and its
# chip_run counted on REV_VIEWS (default: dragon2, one of PROFILE_VIEWS):
# the before/after of each change, from the same run; the table's last row
# is the working tree (the profiles above).
#
# Valgrind cannot run AVX-512 code, so the builds are made with
# ARCH=-mavx2 into B (default build-vg; the same images: docs/design.md,
# the packet width follows the target and the frames are bit-identical).
#
# Writes the section between <!-- BEGIN profile --> and <!-- END profile -->
# of docs/PERFORMANCE.md (other sections are kept; the file is replaced
# atomically) and prints it. Needs POSIX sh, awk, sed, valgrind, git.
set -eu
# say, die and bench_end (not bench_init: this script builds its own
# binaries into B, below)
. "$(dirname "$0")/bench-lib.sh"
BENCH_NAME=bench-profile
# No default world-cache folder (issue 36): these runs measure or compare
# builds, renders and sampled warming as they were, and write nothing into
# the user's home; a run that wants a cache names its own (--world-cache).
SAARSIM_CACHE_DIR=off
export SAARSIM_CACHE_DIR
ROOT=$(cd "$(dirname "$0")/.." && pwd)
cd "$ROOT"
SCENES=${SAAR_SCENES:-$ROOT/../shared/scenes}
VIEWS=$SCENES/views.yaml
[ -f "$VIEWS" ] || die "$VIEWS not found (set SAAR_SCENES)"
command -v valgrind >/dev/null && command -v callgrind_annotate >/dev/null ||
	die "valgrind (callgrind) not found"
SIZE=${SIZE:-256x192}
PROFILE_VIEWS=${PROFILE_VIEWS:-conference bunny dragon2 sponza}
REV_VIEWS=${REV_VIEWS:-dragon2}
TOP=${TOP:-12}
case $TOP in '' | *[!0-9]* | 0) die "TOP must be a positive integer" ;; esac
B=${B:-build-vg}
DOC=docs/PERFORMANCE.md
DOCTMP=$DOC.tmp.$$
TMP=$(mktemp -d "${TMPDIR:-/tmp}/saar-prof.XXXXXX")
WTS=
cleanup() {
	for w in $WTS; do git -C "$ROOT" worktree remove --force "$w" >/dev/null 2>&1 || :; done
	rm -rf "$TMP"
	rm -f "$DOCTMP"
}
trap cleanup EXIT
. "$(dirname "$0")/doc-section.sh"
load0=$(doc_load)
t0=$(date +%s)

say "building saarsim and rtref with ARCH=-mavx2 into $B"
make -s -j2 ARCH=-mavx2 B="$B" "$B/saarsim" "$B/rtref" >&2 || die "build failed"
SIM=$ROOT/$B/saarsim
REF=$ROOT/$B/rtref

# The instruction count of chip_run (saarsim) or render_frame (rtref) in a
# callgrind output file.
total() {
	callgrind_annotate "$1" 2>/dev/null | awk '/PROGRAM TOTALS/ { gsub(",", "", $1); print $1; exit }'
}

# Counts chip_run of saarsim binary $1 on view $2 into $3 (callgrind
# output); the first run, not counted, fills the world cache.
count_sim() {
	"$1" --views "$VIEWS" --view "$2" --size "$SIZE" --no-check --quiet \
		--world-cache "$TMP/wc" --report "$3.json" >/dev/null 2>"$TMP/err" ||
		{ cat "$TMP/err" >&2; die "$1 failed on $2"; }
	valgrind --tool=callgrind --callgrind-out-file="$3" --toggle-collect=chip_run \
		"$1" --views "$VIEWS" --view "$2" --size "$SIZE" --no-check --quiet \
		--world-cache "$TMP/wc" >/dev/null 2>"$TMP/err" ||
		{ cat "$TMP/err" >&2; die "callgrind $1 failed on $2"; }
}

# The top $TOP rows of callgrind_annotate (exclusive, or inclusive with
# $2 = yes) as markdown rows: function (repository-relative file), count,
# share of chip_run. Inclusive lists start below the frame loop (the
# callers every event passes through are left out: chip_run, the engine's
# eng_run and main's chain); the exclusive lists keep eng_run (its own
# count is the event queue's).
top_rows() {
	callgrind_annotate --inclusive="$2" "$1" 2>/dev/null | awk -v top="$TOP" -v tot="$3" \
		-v root="$ROOT/" -v incl="$2" '
	/PROGRAM TOTALS/ || !/^ *[0-9][0-9,]* +\(/ { next }
	{
		n = $1; gsub(",", "", n)
		f = $0
		sub(/^ *[0-9,]+ +\([^)]*\) +/, "", f)
		sub(/ \[.*$/, "", f); gsub(root, "", f); sub(/^\.\//, "", f)
		if (f ~ /^\?\?\?|csu\/|libc_start|:main$|below main/) next
		if (incl == "yes" && f ~ /:chip_run$|:chip_run_region$|:eng_run$/) next
		if (incl == "yes" && n + 0 >= 0.99 * tot) next
		if (f in seen) next
		seen[f] = 1
		printf "| `%s` | %.0f | %.1f%% |\n", f, n, 100 * n / tot
		if (++k >= top) exit
	}'
}

# ---- the profiles ----
# kernel-ref's side is the render saarsim's check makes and its
# sim_to_ref_ratio divides by: the per-lane packet traversal on the
# chip's tree (the plain SAH), not rtref's default (the frustum walk on a
# tree of its own, which renders the frame faster)
CHECK_RENDER="--per-lane --kd-footprint 0"
ROWS=$TMP/rows
: >"$ROWS"
for v in $PROFILE_VIEWS; do
	say "callgrind: saarsim cycle mode, $v $SIZE"
	count_sim "$SIM" "$v" "$TMP/cg-$v"
	say "callgrind: rtref, $v $SIZE"
	"$REF" --views "$VIEWS" --view "$v" --size "$SIZE" --threads 1 $CHECK_RENDER \
		--world-cache "$TMP/wcr" >/dev/null 2>"$TMP/err" || { cat "$TMP/err" >&2; die "rtref failed on $v"; }
	valgrind --tool=callgrind --callgrind-out-file="$TMP/cgr-$v" --toggle-collect=render_frame \
		"$REF" --views "$VIEWS" --view "$v" --size "$SIZE" --threads 1 $CHECK_RENDER \
		--world-cache "$TMP/wcr" >/dev/null 2>"$TMP/err" ||
		{ cat "$TMP/err" >&2; die "callgrind rtref failed on $v"; }
	s=$(total "$TMP/cg-$v")
	r=$(total "$TMP/cgr-$v")
	cy=$(sed -n 's/^[[:space:]]*"cycles"[[:space:]]*:[[:space:]]*\([0-9]*\).*/\1/p' "$TMP/cg-$v.json" | head -n 1)
	[ -n "$cy" ] || cy=$(tr ',{' '\n\n' <"$TMP/cg-$v.json" | sed -n 's/^[[:space:]]*"cycles"[[:space:]]*:[[:space:]]*//p' | head -n 1)
	printf '%s %s %s %s\n' "$v" "$cy" "$s" "$r" >>"$ROWS"
done

# ---- the revisions ----
REVROWS=$TMP/revrows
: >"$REVROWS"
for rev in "$@"; do
	sha=$(git -C "$ROOT" rev-parse --short "$rev" 2>/dev/null) || die "no such revision: $rev"
	subj=$(git -C "$ROOT" log -1 --format=%s "$sha" | cut -c1-90 | sed 's/|/\\|/g')
	wt=$TMP/wt-$sha
	say "building $sha in $wt"
	git -C "$ROOT" worktree add --detach "$wt" "$sha" >/dev/null 2>&1 || die "worktree $sha"
	WTS="$WTS $wt"
	make -s -C "$wt" -j2 ARCH=-mavx2 B=build-vg build-vg/saarsim >&2 || die "build of $sha failed"
	line="$sha|$subj"
	for v in $REV_VIEWS; do
		say "callgrind: $sha, $v $SIZE"
		count_sim "$wt/build-vg/saarsim" "$v" "$TMP/cgv-$sha-$v"
		line="$line|$(total "$TMP/cgv-$sha-$v")"
	done
	echo "$line" >>"$REVROWS"
done
if [ -s "$REVROWS" ]; then
	line="working tree|the profiles above"
	for v in $REV_VIEWS; do
		[ -f "$TMP/cg-$v" ] || die "REV_VIEWS: $v is not in PROFILE_VIEWS"
		line="$line|$(total "$TMP/cg-$v")"
	done
	echo "$line" >>"$REVROWS"
fi

bench_end
{
	echo "<!-- BEGIN profile -->"
	echo "## Profile of cycle mode (issue 36)"
	echo
	echo "Generated by scripts/bench-profile.sh; do not edit by hand."
	echo
	echo "- Date: $(date -u '+%Y-%m-%d %H:%M UTC') (took $elapsed s); commit $GIT"
	echo "- Machine: $(nproc) CPUs, $(doc_cpu); load average $load0 at start, $load1 at the end (other jobs share the machine: wall-clock times there are noisy, instruction counts are not)"
	echo "- Tool: $(valgrind --version) (callgrind), builds for \`-mavx2\` (valgrind runs no AVX-512)"
	echo "- Run: \`saarsim --views views.yaml --view V --size $SIZE --no-check\` (cycle mode, default config), counting chip_run only (\`--toggle-collect=chip_run\`; the scene from a world cache); kernel-ref: \`rtref --threads 1 $CHECK_RENDER\` on the same frame, counting render_frame only (saarsim's check render, which \`sim_to_ref_ratio\` divides by: the per-lane packet traversal on the chip's tree; rtref's default, the frustum walk on its own tree, renders faster)."
	echo
	echo "Instructions (Ir) per frame; *Ir ratio*: saarsim's chip_run over kernel-ref's render. The issue's target (at most 5 times kernel-ref's single-thread time at 1024x768) is a time ratio (saarsim's \`sim_to_ref_ratio\`); instructions per cycle differ between the two programs, so the instruction ratio shows where the time goes and how a change moves it, not the time ratio itself."
	echo
	echo "| view | cycles/frame | saarsim chip_run Ir | kernel-ref render Ir | Ir ratio |"
	echo "|---|---:|---:|---:|---:|"
	awk '{ printf "| %s | %s | %.0f | %.0f | %.1f |\n", $1, $2, $3, $4, ($4 > 0 ? $3 / $4 : 0) }' "$ROWS"
	while read -r v cy s r; do
		echo
		echo "### $v $SIZE: top $TOP functions"
		echo
		echo "Exclusive (the function's own instructions; a header's inline code is listed under the header):"
		echo
		echo "| function | Ir | share of chip_run |"
		echo "|---|---:|---:|"
		top_rows "$TMP/cg-$v" no "$s"
		echo
		echo "Inclusive (with everything it calls; the frame loop and the event dispatcher, which hold everything, left out):"
		echo
		echo "| function | Ir | share of chip_run |"
		echo "|---|---:|---:|"
		top_rows "$TMP/cg-$v" yes "$s"
	done <"$ROWS"
	if [ -s "$REVROWS" ]; then
		echo
		echo "### chip_run instructions by commit ($SIZE)"
		echo
		# shellcheck disable=SC2086
		md_head '| commit | change |' ' %s |' '|---|---|' $REV_VIEWS
		awk -F'|' '{
			printf "| %s | %s |", $1, $2
			for (i = 3; i <= NF; i++) {
				if (NR > 1 && p[i] > 0) printf " %.0f (%+.1f%%) |", $i, 100 * ($i - p[i]) / p[i]
				else printf " %.0f |", $i
				p[i] = $i
			}
			printf "\n"
		}' "$REVROWS"
		echo
		echo "No change between the rows changes a figure (scripts/refmatrix.sh: every report of its matrix identical against a recording of the first); the percentage is against the row above."
	fi
	echo "<!-- END profile -->"
} >"$SECTION"

doc_section profile "$SECTION" "$DOC" # its temporary is $DOCTMP
say "wrote $DOC (section profile)"
cat "$SECTION"
