#!/bin/sh
# scripts/bench-ratio.sh: issue 36's target 2 as the issue states it:
# saarsim's cycle-mode simulation time over kernel-ref's single-thread time
# for the same frame, on every shared view at SIZE (default 1024x768).
#
#   sh scripts/bench-ratio.sh
#
# RUNS saarsim runs per view (default 5: kernel-ref's side varies by about
# 15% between runs of one binary; the default config, cycle mode,
# with the check: the report's host.sim_to_ref_ratio is chip_run's time
# over kernel-ref's packet render of the same frame, timed in the same
# process, one host thread); each side's best time over the runs, then
# their ratio. No world cache, so the reference frame is rendered, not
# read. Beside it, the simulation's best over rtref's default render of
# the same frame (the frustum walk on rtref's own tree, faster than the
# check's per-lane render on the chip's tree), RUNS runs of `rtref
# --threads 1`, their best render_ms. And where cycle mode's time goes:
# the same frame in functional fidelity (the chip's units stepped and
# every read through its memory hierarchy, no timing), RUNS runs without
# a world cache (the math done), and RUNS runs replaying the frame's
# packet record from a scratch world cache (no math: the memory
# system's own work), their best host.sim_s; so cycle's time splits into
# the memory system (replay), the chip's math (functional - replay) and
# the timing model (cycle - functional). Writes the section between
# <!-- BEGIN ratio --> and <!-- END ratio --> of docs/PERFORMANCE.md and
# prints it. Takes a few minutes; run it alone.
set -eu
. "$(dirname "$0")/bench-lib.sh"
bench_init bench-ratio
RTREF=$ROOT/$B/rtref
[ -x "$RTREF" ] || die "$RTREF not found; run 'make' first"
SIZE=${SIZE:-1024x768}
RUNS=${RUNS:-5}
# One functional run of view $1 without the check, further arguments to
# saarsim; its report in $TMP/f.json.
functional() {
	fv=$1
	shift
	"$SIM" --views "$VIEWS" --view "$fv" --size "$SIZE" --quiet --fidelity functional \
		--no-check "$@" --report "$TMP/f.json" >"$TMP/f.txt" 2>&1 ||
		{ cat "$TMP/f.txt" >&2; die "saarsim --fidelity functional $* failed on $fv"; }
}
# The best host.sim_s of RUNS functional runs of view $1; with $2 = 1
# each must have replayed the packet record (every tile); further
# arguments to saarsim.
functional_best() {
	fv=$1 freplay=$2
	shift 2
	fb=
	fr=1
	while [ "$fr" -le "$RUNS" ]; do
		functional "$fv" "$@"
		[ "$freplay" = 0 ] ||
			[ "$(jget "$TMP/f.json" replayed_tiles)" = "$(jget "$TMP/f.json" functional_tiles)" ] ||
			die "$fv: the functional run did not replay the packet record"
		fb=$(bench_min "$fb" "$(jget "$TMP/f.json" sim_s)")
		fr=$((fr + 1))
	done
	echo "$fb"
}
bench_start ratio
# the first view's run as a figures-check line (scripts/figures-check.py):
# `make test` reruns it and compares its cycles with the table's
: >"$TMP/checks"
for v in $VLIST; do
	bs= br= qs=
	r=1
	while [ "$r" -le "$RUNS" ]; do
		say "$v $SIZE, run $r of $RUNS"
		"$SIM" --views "$VIEWS" --view "$v" --size "$SIZE" --quiet \
			--report "$TMP/r.json" >"$TMP/r.txt" 2>&1 || { cat "$TMP/r.txt" >&2; die "saarsim failed on $v"; }
		grep -q "packets identical" "$TMP/r.txt" || die "$v: the frame differs from kernel-ref's"
		s=$(jget "$TMP/r.json" sim_s)
		q=$(jget "$TMP/r.json" sim_to_ref_ratio)
		ref=$(awk -v s="$s" -v q="$q" 'BEGIN { printf "%.6f", (q > 0 ? s / q : 0) }')
		# each side's best over the runs: a minimum of the ratio itself
		# would pick the run whose kernel-ref time was slowed the most
		qs="$qs $q"
		bs=$(bench_min "$bs" "$s")
		br=$(bench_min "$br" "$ref")
		cyc=$(jget "$TMP/r.json" cycles)
		r=$((r + 1))
	done
	if [ ! -s "$TMP/checks" ]; then
		doc_check_line "$TMP/checks" "$SCENES" "$TMP/r.json" cycles fps -- --views "$VIEWS" \
			--view "$v" --size "$SIZE" || die "figures-check.py --emit failed"
	fi
	# rtref's default render of the same frame (the frustum walk on its
	# own tree), one thread: its best render_ms over RUNS runs
	bd=
	r=1
	while [ "$r" -le "$RUNS" ]; do
		"$RTREF" --views "$VIEWS" --view "$v" --size "$SIZE" --threads 1 \
			--stats "$TMP/s.json" >"$TMP/s.txt" 2>&1 || { cat "$TMP/s.txt" >&2; die "rtref failed on $v"; }
		d=$(awk -v m="$(jget "$TMP/s.json" render_ms)" 'BEGIN { printf "%.6f", m / 1000 }')
		bd=$(bench_min "$bd" "$d")
		r=$((r + 1))
	done
	# functional fidelity: with the math (no world cache), then replaying
	# the packet record a first, uncounted run put in a scratch world cache
	bf=$(functional_best "$v" 0)
	functional "$v" --world-cache "$TMP/wc"
	bp=$(functional_best "$v" 1 --world-cache "$TMP/wc")
	rm -rf "$TMP/wc"
	# each run's own ratio (both sides timed in its process: a slow
	# spell of the host slows both), their median and range
	# shellcheck disable=SC2086
	qmr=$(med_range $qs)
	printf '%s %s %s %s %s %s %s %s %s %s\n' "$v" "$cyc" "$bs" "$br" \
		"$(awk -v s="$bs" -v q="$br" 'BEGIN { printf "%.4f", (q > 0 ? s / q : 0) }')" "$bd" \
		"$(awk -v s="$bs" -v q="$bd" 'BEGIN { printf "%.4f", (q > 0 ? s / q : 0) }')" "$bf" "$bp" "$qmr" >>"$ROWS"
done
bench_end
{
	echo "<!-- BEGIN ratio -->"
	echo "## Cycle mode against kernel-ref on every view (issue 36, target 2)"
	echo
	echo "Generated by scripts/bench-ratio.sh (\`make bench-ratio\`); do not edit by hand."
	echo
	echo "- Date: $(date -u '+%Y-%m-%d %H:%M UTC') (took $elapsed s); commit $GIT"
	echo "- Machine: $(nproc) CPUs, $(doc_cpu); load average $load0 at start, $load1 at the end (other jobs may share the machine: both times in a row come from the same process, so the ratio is less noisy than either)"
	echo "- Run: \`saarsim --views views.yaml --view V --size $SIZE\` (default config, cycle mode, the check on, no world cache), $RUNS runs; *sim s*: the best \`host.sim_s\` (chip_run); *kernel-ref s*: the best time of its packet render of the same frame, one host thread, in the same process (\`host.sim_s\` / \`host.sim_to_ref_ratio\`: the check's render, which steps the per-lane packet traversal the chip models on the chip's tree); *ratio*: the two bests' quotient (the verdict below); *same run*: each run's own ratio (\`host.sim_to_ref_ratio\`, both times from one process, so a slow spell of the host slows both), the median and the range over the $RUNS runs. *rtref s*: rtref's default render of the same frame (the frustum walk on its own tree, which renders faster; \`rtref --threads 1\`, no world cache, best of $RUNS runs, its \`render_ms\`), and the simulation's best over it."
	echo
	echo "| view | cycles/frame | sim s | kernel-ref s | ratio | same run: median (range) | rtref s | ratio to rtref |"
	echo "|---|---:|---:|---:|---:|---:|---:|---:|"
	awk '{ printf "| %s | %d | %.3f | %.3f | %.1f | %.1f (%.1f-%.1f) | %.3f | %.1f |\n", $1, $2, $3, $4, $5, $10, $11, $12, $6, $7 }' "$ROWS"
	echo
	awk '{ n++; if ($5 <= 5) ok++; if (n == 1 || $5 > hi) { hi = $5; hv = $1 } }
	END { printf "Target: at most 5 on every view: %s (%d of %d views; the highest %.1f, %s).\n", (ok == n ? "met" : "NOT met"), ok, n, hi, hv }' "$ROWS"
	echo
	awk '{ n++; if ($10 <= 5) ok++; if ($12 <= 5) all++; if (n == 1 || $10 > hi) { hi = $10; hv = $1 } }
	END { printf "By each run'"'"'s own ratio instead (not the verdict; for the noise between runs): the median at most 5 on %d of %d views (the highest %.1f, %s), every run at most 5 on %d.\n", ok, n, hi, hv, all }' "$ROWS"
	echo
	awk '{ n++; if ($7 <= 5) ok++; if (n == 1 || $7 > hi) { hi = $7; hv = $1 } }
	END { printf "Against rtref'"'"'s default render instead: at most 5 on %d of %d views (the highest %.1f, %s).\n", ok, n, hi, hv }' "$ROWS"
	echo
	echo "### Where cycle mode's time goes (issue 36, target 2)"
	echo
	echo "The same frames split by what the simulation does, each part over kernel-ref's time above: *memory system*, the best \`host.sim_s\` of $RUNS functional runs (\`--fidelity functional --no-check\`) replaying the frame's packet record from a scratch world cache (every read through the chip's caches and SDRAM model functionally, no math, no timing); *math*, the best of $RUNS functional runs without a world cache (the chip's units stepping kernel-ref's per-lane math, the same reads, no timing) less the memory system; *timing*, cycle's *sim s* less that functional best (the events, arbitration and the stalls' retries). The three sum to *ratio*. The best of each side is taken separately, so a part can read a little low or high; and a replay also decodes the packet record, which cycle mode does not, so *memory system* reads high and *math* low by the decoding's time (the hand-written section below measures it)."
	echo
	echo "| view | functional s | replay s | memory system | math | timing | ratio |"
	echo "|---|---:|---:|---:|---:|---:|---:|"
	awk '{ k = $4; if (k <= 0) k = 1e-9
		printf "| %s | %.3f | %.3f | %.1f | %.1f | %.1f | %.1f |\n", $1, $8, $9, $9 / k, ($8 - $9) / k, ($3 - $8) / k, $5 }' "$ROWS"
	echo
	awk '{ n++; k = ($4 > 0 ? $4 : 1e-9); f = $8 / k; if (n == 1 || f > hi) { hi = f; hv = $1 }; if (f <= 5) ok++ }
	END { printf "Functional fidelity with the math over kernel-ref (what cycle mode would take with a timing model that cost nothing): at most 5 on %d of %d views, the highest %.1f (%s).\n", ok, n, hi, hv }' "$ROWS"
	cat "$TMP/checks"
	echo "<!-- END ratio -->"
} >"$SECTION"
doc_section ratio "$SECTION" "$DOC"
say "wrote $DOC (section ratio)"
cat "$SECTION"
