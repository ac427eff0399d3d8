#!/bin/sh
# scripts/validate.sh: validation against the published SaarCOR results
# (`make validate`; seed 002 §4.4-4.7 and Table 5).
#
#   sh scripts/validate.sh [BUILD_DIR]        (default: build)
#
# Runs the standard and VMA configs (configs/saarcor-std.yaml,
# configs/saarcor-vma.yaml) on the shared scenes, Conference first, through
# scripts/sweep: every view at 16 and 32 threads per RTP with the standard
# chip, at 16 with the VMA, and Conference at 1..64 threads (plotted).
# All runs use --frames 2; fps, MB/frame, hit rates and the meta-data share
# are saarsim's steady-state figures (the second frame), utilisation is over
# both frames. Writes docs/VALIDATION.md (generated: every number comes from
# the run) and docs/validation-threads.png, each replaced atomically.
# Runs are kept in out/validate/ and resumed when rerun with the same binary,
# size and views; a different saarsim binary starts afresh.
#
# Environment:
#   SAAR_SCENES      shared scenes folder (default ../shared/scenes); absent:
#                    skip with a message, exit 0
#   VALIDATE_SIZE    frame size (default 1024x768)
#   VALIDATE_VIEWS   views to run (comma or space separated; default: every
#                    view of views.yaml whose scene file exists, conference first)
#   VALIDATE_JOBS    parallel runs (default: number of cores)
#   VALIDATE_OUT     run folder (default out/validate)
#   SAARSIM          the binary (default BUILD_DIR/saarsim)
#   VALIDATE_DOC     the document to write (default docs/VALIDATION.md); the
#                    plot goes beside it as validation-threads.png
# Needs POSIX sh, awk, GNU parallel (optional) and gnuplot.
set -eu

say() { printf 'validate: %s\n' "$*" >&2; }
die() {
	say "error: $*"
	exit 1
}

ROOT=$(cd "$(dirname "$0")/.." && pwd)
# shellcheck source=scripts/sweep-lib.sh
. "$ROOT/scripts/sweep-lib.sh"
B=${1:-build}
case $B in /*) ;; *) B=$ROOT/$B ;; esac
SAARSIM=${SAARSIM:-$B/saarsim}

SCENES=${SAAR_SCENES:-$ROOT/../shared/scenes}
VIEWS=$SCENES/views.yaml
DOC=${VALIDATE_DOC:-$ROOT/docs/VALIDATION.md}
if [ ! -f "$VIEWS" ]; then
	say "shared scenes not found ($VIEWS; set SAAR_SCENES to the folder);" \
		"skipping the validation, $DOC left unchanged"
	exit 0
fi
VIEWS=$(cd "$(dirname "$VIEWS")" && pwd)/views.yaml
[ -x "$SAARSIM" ] || die "$SAARSIM not found; run 'make' first"
command -v gnuplot >/dev/null 2>&1 || die "gnuplot not found (sh scripts/install-deps.sh)"
SIZE=${VALIDATE_SIZE:-1024x768}
printf '%s\n' "$SIZE" | grep -Eq '^[1-9][0-9]*x[1-9][0-9]*$' || die "VALIDATE_SIZE must be WxH, got '$SIZE'"
JOBS=${VALIDATE_JOBS:-$(nproc 2>/dev/null || echo 2)}
OUT=${VALIDATE_OUT:-$ROOT/out/validate}
DOCDIR=$(dirname "$DOC")
mkdir -p "$DOCDIR" "$OUT"
PNG=$DOCDIR/validation-threads.png
STD=$ROOT/configs/saarcor-std.yaml
VMA=$ROOT/configs/saarcor-vma.yaml
for f in "$STD" "$VMA"; do [ -f "$f" ] || die "$f missing"; done

# views of views.yaml with their scene files, "name<TAB>scene"
ALL=$(awk '
	/^views:/ { in_v = 1; next }
	/^[^ #]/ { in_v = 0 }
	in_v && /^  [A-Za-z0-9_.-]+:[ \t]*$/ { name = $1; sub(/:$/, "", name); next }
	in_v && name != "" && /^    scene:/ { s = $0; sub(/^    scene:[ \t]*/, "", s); gsub(/"/, "", s); gsub(/\047/, "", s); print name "\t" s; name = "" }
' "$VIEWS")
if [ -n "${VALIDATE_VIEWS:-}" ]; then
	WANT=$(printf '%s\n' "$VALIDATE_VIEWS" | tr ',' ' ' | tr ' ' '\n' | awk 'NF')
else
	WANT=$(printf '%s\n' "$ALL" | cut -f1)
fi
LIST=
for v in $(printf '%s\n' "$WANT" | awk '$0 == "conference" { print; next } { rest = rest $0 "\n" } END { printf "%s", rest }'); do
	sc=$(printf '%s\n' "$ALL" | awk -F'\t' -v v="$v" '$1 == v { print $2 }')
	if [ -z "$sc" ]; then
		die "view '$v' is not in $VIEWS"
	elif [ ! -f "$(dirname "$VIEWS")/$sc" ]; then
		say "view $v: scene $sc absent; skipped"
	else
		LIST="$LIST,$v"
	fi
done
LIST=${LIST#,}
[ -n "$LIST" ] || {
	say "none of the views has its scene file in $SCENES; skipping the validation, $DOC left unchanged"
	exit 0
}
case ",$LIST," in *,conference,*) TV=conference ;; *) TV=${LIST%%,*} ;; esac
say "views: $LIST; size $SIZE; thread sweep on $TV"

# Run a snapshot of the binary, so a rebuild during the run neither breaks
# it nor mixes two versions; a rebuilt binary, other configs, size or views
# start afresh.
cp "$SAARSIM" "$OUT/.saarsim.tmp"
mv -f "$OUT/.saarsim.tmp" "$OUT/saarsim"
SAARSIM=$OUT/saarsim
STAMP="$(cksum <"$SAARSIM") $(cat "$STD" "$VMA" | cksum) $SIZE $LIST"
if [ "$(cat "$OUT/stamp" 2>/dev/null)" != "$STAMP" ]; then
	rm -rf "$OUT/std" "$OUT/vma" "$OUT/threads"
	printf '%s\n' "$STAMP" >"$OUT/stamp.tmp"
	mv -f "$OUT/stamp.tmp" "$OUT/stamp"
fi

SWEEP=$ROOT/scripts/sweep
export SAARSIM
COMMON="--views $VIEWS --size $SIZE --frames 2 -j $JOBS"
# shellcheck disable=SC2086
"$SWEEP" --out "$OUT/std" --config "$STD" --view "$LIST" $COMMON --set chip.threads_per_rtp=16,32 ||
	die "standard runs failed (see $OUT/std/points/*.err)"
# shellcheck disable=SC2086
"$SWEEP" --out "$OUT/vma" --config "$VMA" --view "$LIST" $COMMON --set chip.threads_per_rtp=16 ||
	die "VMA runs failed (see $OUT/vma/points/*.err)"
# shellcheck disable=SC2086
"$SWEEP" --out "$OUT/threads" --config "$STD" --view "$TV" $COMMON \
	--set chip.threads_per_rtp=1,2,4,8,16,32,64 --plot -- --no-check ||
	die "thread sweep failed (see $OUT/threads/points/*.err)"
SRC=$OUT/threads/plots/threads-$(printf '%s\n' "$TV" | sed 's/[^A-Za-z0-9._-]/_/g').png
[ -f "$SRC" ] || die "$SRC was not made"
cp "$SRC" "$PNG.tmp.$$"
mv -f "$PNG.tmp.$$" "$PNG"

COLS="target chip.threads_per_rtp fps util_rgs util_trav util_list util_isect sdram_mb_per_frame
pci_mb_per_frame meta_share trav_isect_ratio triangles identical_8bit hit_shade hit_kd hit_list hit_tri
hit_tag_cache hit_l2 threads_waiting_memory id threads_idle"
# shellcheck disable=SC2086
csv_cols "$OUT/std/results.csv" $COLS >"$OUT/std.tsv"
# shellcheck disable=SC2086
csv_cols "$OUT/vma/results.csv" $COLS >"$OUT/vma.tsv"
# shellcheck disable=SC2086
csv_cols "$OUT/threads/results.csv" $COLS >"$OUT/threads.tsv"

# Figures only the JSON reports have: first-frame PCI traffic and the memory
# image size of the Conference (or thread-sweep) view with the VMA.
VID=$(awk -F'\t' -v v="$TV" '$1 == v { print $21 }' "$OUT/vma.tsv")
FIRST_PCI=
IMG_BYTES=
if [ -n "$VID" ] && [ -f "$OUT/vma/points/$VID.json" ]; then
	json_flat "$OUT/vma/points/$VID.json" >"$OUT/vma-conf.flat"
	FIRST_PCI=$(awk -F'\t' '$1 == "per_frame.0.pci_mb" { print $2 }' "$OUT/vma-conf.flat")
	IMG_BYTES=$(awk -F'\t' '$1 == "memory_image_bytes" { print $2 }' "$OUT/vma-conf.flat")
fi

COMMIT=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
if [ -n "$(git -C "$ROOT" status --porcelain --untracked-files=no 2>/dev/null)" ]; then
	COMMIT="$COMMIT (with uncommitted changes)"
fi
DATE=$(date -u '+%Y-%m-%d %H:%M UTC')
HOST="$(uname -n), $(uname -m), $(awk -F': ' '/^model name/ { print $2; exit }' /proc/cpuinfo 2>/dev/null || :)"

TMPDOC=$DOC.tmp.$$
trap 'rm -f "$TMPDOC"' EXIT
trap 'exit 130' INT TERM

awk -F'\t' -v std="$OUT/std.tsv" -v vma="$OUT/vma.tsv" -v thr="$OUT/threads.tsv" \
	-v tv="$TV" -v list="$LIST" -v size="$SIZE" -v date="$DATE" -v host="$HOST" \
	-v commit="$COMMIT" -v png="$(basename "$PNG")" -v first_pci="$FIRST_PCI" \
	-v img_bytes="$IMG_BYTES" "$AWK_CSV"'
function pct(x) { return sprintf("%.1f%%", 100 * x) }
function f1(x) { return sprintf("%.1f", x) }
function f2(x) { return sprintf("%.2f", x) }
function abs(x) { return x < 0 ? -x : x }
function log10(x) { return log(x) / log(10) }
# the busiest unit of row r of table T: utilisation and name
function busiest(T, r,    k, b) {
	bu = ""; b = -1
	for (k = 1; k <= 4; k++) if (T[r, 3 + k] + 0 > b) { b = T[r, 3 + k] + 0; bu = U[k] }
	return b
}
# "higher"/"lower" by how much, for a value against a range [lo, hi]
function against(x, lo, hi, unit,    d) {
	if (x < lo) return sprintf("lower than the published %s by %.1f %s", rng(lo, hi, unit), lo - x, unit == "%" ? "points" : unit)
	if (x > hi) return sprintf("higher than the published %s by %.1f %s", rng(lo, hi, unit), x - hi, unit == "%" ? "points" : unit)
	return sprintf("inside the published %s", rng(lo, hi, unit))
}
function rng(lo, hi, unit) { return lo == hi ? sprintf("%g%s", lo, unit == "%" ? "%" : " " unit) : sprintf("%g-%g%s", lo, hi, unit == "%" ? "%" : " " unit) }
# ours against a published number: "ours is higher by X% (N times)"
function vs(o, p,    r) {
	if (p == 0) return "n/a"
	r = o / p
	if (r >= 1) return sprintf("ours is higher by %.1f%% (x%.3g, %+.1f orders of magnitude)", 100 * (r - 1), r, log10(r))
	if (r > 0) return sprintf("ours is lower by %.1f%% (x%.3g, %+.1f orders of magnitude)", 100 * (1 - r), r, log10(r))
	return "ours is zero"
}
function load(file, T, N,    line, n, i, f) {
	N[0] = 0
	while ((getline line < file) > 0) {
		n = split(line, f, "\t"); N[0]++
		for (i = 1; i <= n; i++) T[N[0], i] = f[i]
	}
	close(file)
}
# row of table T for view v and threads t (0 if none)
function find(T, N, v, t,    r) {
	for (r = 1; r <= N[0]; r++) if (T[r, 1] == v && T[r, 2] + 0 == t) return r
	return 0
}
BEGIN {
	U[1] = "rgs"; U[2] = "trav"; U[3] = "list"; U[4] = "isect"
	load(std, S, SN); load(vma, V, VN); load(thr, H, HN)
	nv = split(list, views, ",")
	# columns: 1 target 2 threads 3 fps 4-7 util rgs trav list isect 8 sdram_mb 9 pci_mb
	# 10 meta 11 ratio 12 triangles 13 identical 14-17 hit shade kd list tri 18 tag 19 l2 20 wait_mem 21 id

	print "# Validation against the published SaarCOR results"
	print ""
	print "<!-- Generated by scripts/validate.sh (`make validate`); do not edit: every number below comes from the run. -->"
	print ""
	printf "Generated %s on %s; saarsim %s.\n", date, host, commit
	printf "Frame size %s, `--frames 2`: fps, MB/frame, hit rates and the meta-data share are the steady state (the second frame; the published figures are steady state); unit utilisation is over both frames. ", size
	print "Configs: `configs/saarcor-std.yaml` (standard chip) and `configs/saarcor-vma.yaml` (the same chip with the virtual memory architecture over PCI), runs made with `scripts/sweep` (kept in `out/validate/`). Published figures: seed 002 (Wald et al., EG 2003 STAR), §4.4-4.7 and Table 5."
	print ""
	print "| view | triangles | fps (16 threads) | SDRAM MB/frame | image identical to kernel-ref |"
	print "|---|---|---|---|---|"
	for (i = 1; i <= nv; i++) {
		r = find(S, SN, views[i], 16); if (!r) continue
		printf "| %s | %d | %s | %s | %s |\n", views[i], S[r, 12], f1(S[r, 3]), f2(S[r, 8]), S[r, 13] == "1" ? "yes" : (S[r, 13] == "0" ? "**no**" : "not checked")
	}
	print ""

	# ---------------------------------------------------------- 1
	print "## 1. Unit utilisation at 16 threads per pipeline"
	print ""
	print "Published (§4.4): \"Sixteen threads results in 60%-80% utilization\". Ours: the share of issue slots used (`units.*.utilisation`, docs/report.md) of each unit with 16 threads per RTP; the headline is the busiest unit, the one that limits the frame rate."
	print ""
	print "| view | rgs | trav | list | isect | busiest unit |"
	print "|---|---|---|---|---|---|"
	n1 = 0; s1 = 0; lo1 = 2; hi1 = -1
	for (i = 1; i <= nv; i++) {
		r = find(S, SN, views[i], 16); if (!r) continue
		b = busiest(S, r); n1++; s1 += b; if (b < lo1) lo1 = b; if (b > hi1) hi1 = b
		printf "| %s | %s | %s | %s | %s | %s (%s) |\n", views[i], pct(S[r, 4]), pct(S[r, 5]), pct(S[r, 6]), pct(S[r, 7]), pct(b), bu
	}
	u16 = n1 ? 100 * s1 / n1 : 0
	print ""
	printf "Mean busiest-unit utilisation over %d view(s): **%.1f%%** (range %.1f-%.1f%%), %s.\n", n1, u16, 100 * lo1, 100 * hi1, against(u16, 60, 80, "%")
	print ""

	# ---------------------------------------------------------- 2
	print "## 2. Gain from 16 to 32 threads per pipeline"
	print ""
	print "Published (§4.4): \"32 threads increase the utilization by another 10 percent\" (read here as about 10 points)."
	print ""
	print "| view | busiest unit, 16 threads | 32 threads | gain (points) | fps 16 | fps 32 | fps change |"
	print "|---|---|---|---|---|---|---|"
	n2 = 0; g2 = 0; fch = 0
	for (i = 1; i <= nv; i++) {
		r = find(S, SN, views[i], 16); q = find(S, SN, views[i], 32); if (!r || !q) continue
		a = busiest(S, r); b = busiest(S, q); n2++; g2 += 100 * (b - a)
		fc = S[r, 3] > 0 ? 100 * (S[q, 3] / S[r, 3] - 1) : 0; fch += fc
		printf "| %s | %s | %s | %+.1f | %s | %s | %+.1f%% |\n", views[i], pct(a), pct(b), 100 * (b - a), f1(S[r, 3]), f1(S[q, 3]), fc
	}
	gain = n2 ? g2 / n2 : 0; fgain = n2 ? fch / n2 : 0
	print ""
	printf "Mean gain: **%+.1f points** of busiest-unit utilisation (fps %+.1f%%), %s.\n", gain, fgain, against(gain, 10, 10, "%")
	print ""
	printf "Utilisation and frame rate against threads per pipeline, view %s (`chip.threads_per_rtp` = 1..64, standard chip; plot: `scripts/sweep --plot`):\n", tv
	print ""
	printf "![utilisation against threads per pipeline, %s](%s)\n", tv, png
	print ""
	print "| threads per RTP | fps | rgs | trav | list | isect | threads waiting for memory | threads idle |"
	print "|---|---|---|---|---|---|---|---|"
	for (t = 1; t <= 64; t *= 2) {
		r = find(H, HN, tv, t); if (!r) continue
		printf "| %d | %s | %s | %s | %s | %s | %s | %s |\n", t, f1(H[r, 3]), pct(H[r, 4]), pct(H[r, 5]), pct(H[r, 6]), pct(H[r, 7]), pct(H[r, 20]), pct(H[r, 22])
		if (t == 16) { wm16 = H[r, 20]; id16 = H[r, 22] }
	}
	print ""

	# ---------------------------------------------------------- 3
	print "## 3. VMA overhead in frame rate"
	print ""
	print "Published (§4.2): with standard PCI the overhead of the virtual memory architecture is 1-10% against a board holding the whole scene. Ours: 1 - fps(VMA) / fps(standard), 16 threads, 64 MB on board in both."
	print ""
	print "| view | fps standard | fps VMA | overhead | PCI MB/frame | tag cache hits | L2 hits |"
	print "|---|---|---|---|---|---|---|"
	n3 = 0; s3 = 0
	for (i = 1; i <= nv; i++) {
		r = find(S, SN, views[i], 16); q = find(V, VN, views[i], 16); if (!r || !q || S[r, 3] <= 0) continue
		o = 100 * (1 - V[q, 3] / S[r, 3]); n3++; s3 += o
		printf "| %s | %s | %s | %.1f%% | %s | %s | %s |\n", views[i], f1(S[r, 3]), f1(V[q, 3]), o, f2(V[q, 9]), V[q, 18] == "" ? "-" : pct(V[q, 18]), V[q, 19] == "" ? "-" : pct(V[q, 19])
	}
	ovh = n3 ? s3 / n3 : 0
	print ""
	printf "Mean overhead: **%.1f%%**, %s.\n", ovh, against(ovh, 1, 10, "%")
	print ""

	# ---------------------------------------------------------- 4
	print "## 4. Share of SDRAM accesses that are VMA meta-data"
	print ""
	print "Published (§4.2): \"roughly 20% of all accesses to local memory are for fetching and updating the cache'"'"'s meta data\". Ours: `meta_share` of the VMA runs (steady state)."
	print ""
	print "| view | meta-data share | SDRAM MB/frame, VMA |"
	print "|---|---|---|"
	n4 = 0; s4 = 0
	for (i = 1; i <= nv; i++) {
		q = find(V, VN, views[i], 16); if (!q || V[q, 10] == "") continue
		n4++; s4 += 100 * V[q, 10]
		printf "| %s | %s | %s |\n", views[i], pct(V[q, 10]), f2(V[q, 8])
	}
	meta = n4 ? s4 / n4 : 0
	print ""
	printf "Mean meta-data share: **%.1f%%**, %s.\n", meta, against(meta, 20, 20, "%")
	print ""

	# ---------------------------------------------------------- 5
	print "## 5. The Conference row of Table 5"
	print ""
	rs = find(S, SN, "conference", 16); rv = find(V, VN, "conference", 16)
	if (!rs || !rv) {
		print "The Conference view was not part of this run (VALIDATE_VIEWS or its scene file is absent): no comparison."
		print ""
	} else {
		printf "Ours is the 69k-triangle Conference (%d triangles) from the shared scenes, seen from the view `conference` of views.yaml at %s; the paper'"'"'s model, view and frame size differ (Table 5 does not state them), so compare orders of magnitude and trends, not digits.\n", S[rs, 12], size
		print ""
		print "| figure | published | ours | ours against published |"
		print "|---|---|---|---|"
		printf "| fps, standard | 77 | %s | %s |\n", f1(S[rs, 3]), vs(S[rs, 3], 77)
		printf "| SDRAM MB/frame, standard | 8.5 | %s | %s |\n", f2(S[rs, 8]), vs(S[rs, 8], 8.5)
		printf "| fps, VMA | 68 | %s | %s |\n", f1(V[rv, 3]), vs(V[rv, 3], 68)
		printf "| SDRAM MB/frame, VMA | 10.8 | %s | %s |\n", f2(V[rv, 8]), vs(V[rv, 8], 10.8)
		printf "| PCI MB/frame, VMA | 0.09 | %s | %s |\n", f2(V[rv, 9]), vs(V[rv, 9], 0.09)
		print ""
		cf_fps = 100 * (V[rv, 3] / S[rs, 3] - 1); cf_mem = S[rs, 8] > 0 ? 100 * (V[rv, 8] / S[rs, 8] - 1) : 0
		print "Trends (VMA against standard):"
		print ""
		printf "- frame rate: published %+.1f%% (77 -> 68 fps), ours %+.1f%%: %s.\n", 100 * (68 / 77 - 1), cf_fps, (cf_fps < 0) ? "same direction" : "**opposite direction**"
		printf "- SDRAM traffic: published %+.1f%% (8.5 -> 10.8 MB/frame, the meta-data), ours %+.1f%%: %s.\n", 100 * (10.8 / 8.5 - 1), cf_mem, (cf_mem > 0) ? "same direction" : "**opposite direction**"
		printf "- PCI traffic is a small part of the SDRAM traffic: published %.1f%%, ours %.1f%%.\n", 100 * 0.09 / 10.8, (V[rv, 8] > 0) ? 100 * V[rv, 9] / V[rv, 8] : 0
		if (first_pci != "") printf "- first frame (cold board) with the VMA: %s MB over PCI for a %.1f MB memory image; in the steady state the scene %s.\n", f2(first_pci), img_bytes / 1048576, (V[rv, 9] + 0 == 0) ? "stays on the board, nothing crosses PCI" : "still misses the board now and then"
		print ""
	}

	# ---------------------------------------------------------- 6
	print "## 6. Traversal : intersection operation ratio"
	print ""
	print "Published (§4.7): the chip (one traversal and one intersection unit per RTP, traversal 4x as wide in our config) is designed for 4:1 kd-node steps per packet-triangle test; the BQD-2 scene needed 10:1. Ours: `trav_isect_ratio` (kd-node steps / triangle tests) of the standard runs."
	print ""
	print "| view | trav : isect | against the design ratio 4:1 |"
	print "|---|---|---|"
	n6 = 0; s6 = 0; lo6 = 1e9; hi6 = 0
	for (i = 1; i <= nv; i++) {
		r = find(S, SN, views[i], 16); if (!r || S[r, 11] == "") continue
		x = S[r, 11] + 0; n6++; s6 += x; if (x < lo6) lo6 = x; if (x > hi6) hi6 = x
		printf "| %s | %.2f : 1 | %s |\n", views[i], x, (x < 4) ? sprintf("intersection-heavy (%.0f%% of 4:1)", 25 * x) : sprintf("traversal-heavy (%.0f%% of 4:1)", 25 * x)
	}
	rat = n6 ? s6 / n6 : 0
	print ""
	printf "Ratios from %.2f to %.2f (mean %.2f): %s.\n", lo6, hi6, rat, (rat < 4) ? sprintf("lower than the design 4:1 by %.0f%%, far from BQD-2'"'"'s 10:1; our intersection units are the busier ones", 100 * (1 - rat / 4)) : sprintf("higher than the design 4:1 by %.0f%%; the traversal units are the busier ones", 100 * (rat / 4 - 1))
	print ""

	# ---------------------------------------------------------- 7
	print "## Where we disagree"
	print ""
	nd = 0
	if (u16 < 60) { nd++
		printf "- **Utilisation at 16 threads**: ours %.1f%% is lower than the published 60-80%% by %.1f points. Our figure is the issue-slot share of the busiest unit with assumed unit widths (the paper does not say how it counts). With 16 threads our thread contexts (view %s) wait for memory %s and are idle %s of the time: %s\n", u16, 60 - u16, tv, pct(wm16), pct(id16), (wm16 + 0 >= id16 + 0 && wm16 + 0 > 0.3) ? "16 threads do not hide our SDRAM and L1 latencies (assumed timings), so the units starve." : ((id16 + 0 > 0.3) ? "the frame does not keep every context busy (too few 8x8 tiles for the 4 x 16 contexts at this frame size, or the tiles are handed out slower than they finish)." : "the threads mostly queue behind one unit, so the others are starved by the op mix rather than by latency.") }
	else if (u16 > 80) { nd++
		printf "- **Utilisation at 16 threads**: ours %.1f%% is higher than the published 60-80%% by %.1f points: our assumed unit widths make the busiest unit a tighter bottleneck than in the paper'"'"'s design, and our memory latency is hidden well with 16 threads.\n", u16, u16 - 80 }
	if (abs(gain - 10) > 3) { nd++
		if (gain < 10) printf "- **Gain from 16 to 32 threads**: ours %+.1f points is lower than the published +10 by %.1f points (fps %+.1f%%). More threads put more packets on the shared L1 caches and the single SDRAM channel: in our model the extra threads mostly queue for memory or thrash the caches instead of filling idle issue slots.\n", gain, 10 - gain, fgain
		else printf "- **Gain from 16 to 32 threads**: ours %+.1f points is higher than the published +10 by %.1f points: in our model 16 threads leave more latency unhidden than in the paper'"'"'s, so 32 threads still help a lot.\n", gain, gain - 10 }
	if (ovh < 1 || ovh > 10) { nd++
		if (ovh < 1) printf "- **VMA overhead**: ours %.1f%% is lower than the published 1-10%% by %.1f points: our scenes fit in the 64 MB board, so after the first frame nothing is fetched over PCI and the only cost left is the tag lookups.\n", ovh, 1 - ovh
		else printf "- **VMA overhead**: ours %.1f%% is higher than the published 1-10%% by %.1f points: the tag lookups (a %.1f%% meta-data share of SDRAM accesses) lengthen every L1 miss, and with our assumed tag-cache latency and hashing, and a memory-bound chip (section 1), that latency is not hidden.\n", ovh, ovh - 10, meta }
	if (abs(meta - 20) > 5) { nd++
		if (meta < 20) printf "- **Meta-data share**: ours %.1f%% is lower than the published ~20%% by %.1f points: our 64 KB tag cache catches most tag reads in the steady state, and our scenes are small enough that tag lines are rarely updated once the board is warm.\n", meta, 20 - meta
		else printf "- **Meta-data share**: ours %.1f%% is higher than the published ~20%% by %.1f points: more of our tag reads miss the tag cache (our hash function and tag layout are assumed).\n", meta, meta - 20 }
	if (rs && rv) {
		rf = S[rs, 3] / 77
		if (rf > 2 || rf < 0.5) { nd++
			printf "- **Conference frame rate**: %s against the published 77 fps. Our view, frame size, shading (%s, our materials) and kd-tree builder differ from the paper'"'"'s; the frame rate scales with rays per frame and kd-tree quality, so a factor of this size is expected rather than a model error.\n", vs(S[rs, 3], 77), "two point lights" }
		rm = S[rs, 8] / 8.5
		if (rm > 2 || rm < 0.5) { nd++
			printf "- **Conference SDRAM traffic**: %s against the published 8.5 MB/frame (our L1 hit rates: shade %s, kd %s, list %s, tri %s). %s\n", vs(S[rs, 8], 8.5), pct(S[rs, 14]), pct(S[rs, 15]), pct(S[rs, 16]), pct(S[rs, 17]), rm < 1 ? "Our memory image is compact and our view coherent, so the published cache sizes hold most of our working set." : "Our caches miss more: our memory layout and packet order are assumed." }
		if (V[rv, 3] >= S[rs, 3]) { nd++
			printf "- **Conference VMA trend**: the VMA chip is not slower than the standard one in our run (%+.1f%%), against the published -11.7%%.\n", cf_fps }
	}
	if (rat < 2 || rat > 10) { nd++
		printf "- **Traversal:intersection ratio**: our mean %.2f:1 %s the design 4:1. Our kd-tree builder (SAH with `kdtree.cost_isect` 1.5, leaf size 2) and our scenes decide it; the paper'"'"'s trees were tuned for its software tracer.\n", rat, (rat < 4) ? sprintf("is lower by %.0f%% than", 100 * (1 - rat / 4)) : sprintf("is higher by %.0f%% than", 100 * (rat / 4 - 1)) }
	if (!nd) print "- Within the tolerances used here (utilisation 60-80%, gain 10 +- 3 points, VMA overhead 1-10%, meta-data 20 +- 5%, Conference within a factor of 2, ratio 2-10), we agree with every published figure."
	print ""

	# ---------------------------------------------------------- 8
	print "## Known model differences"
	print ""
	print "saarsim is a model of the published SaarCOR description, not of its RTL. The unit widths and pipeline latencies (`chip.*.width`, `chip.*.latency`), the L1 hit latency, ports and MSHRs, the SDRAM timing (PC133 CL3, 4 banks), the memory-interface policy, the VMA hash function and tag-cache latency, the thread scheduler and the tile order are assumed (docs/config.md lists each key as published or assumed). Our scenes are our variants: the 69k-triangle Conference from the shared scenes with its own materials, and the views and lights of views.yaml, at the frame size above; the paper'"'"'s views, frame size and materials are not stated. Our kd-trees come from our own SAH builder, not the paper'"'"'s (which it says were tuned for the software ray tracer), and our shading makes one shadow ray per light and reflections up to `shading.max_depth`. Differences of a few ten percent are therefore expected; the claims to check are the orders of magnitude and the trends (more threads help, the VMA costs little, PCI traffic is small)."
}' >"$TMPDOC"
mv -f "$TMPDOC" "$DOC"
say "wrote $DOC and $PNG"
