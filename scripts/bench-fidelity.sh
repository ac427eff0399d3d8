#!/bin/sh
# bench-fidelity.sh: run time against error of the fidelity modes (issue 6).
#
#   sh scripts/bench-fidelity.sh BUILD_DIR
#
# For every shared view, the standard and the VMA config, and 1, 16 and 64
# threads per RTP: one `cycle` run (the truth), one `functional` run and
# `sampled` runs at each sample rate; host time (report host.sim_s) and the
# error of fps, every cache hit rate, SDRAM and PCI MB/frame against cycle,
# and whether the true fps fell inside the sampled run's 95% interval.
# Writes docs/FIDELITY.md (between BEGIN/END markers, like bench.sh) and
# docs/fidelity.png (host time against fps error; gnuplot, skipped with a
# note when absent). The targets are computed from the Conference
# 1024x768 standard-config points, never typed.
#
# Knobs (environment): BENCH_SIZE (other views, default 256x192),
# BENCH_VIEWS (default: every view of views.yaml), BENCH_THREADS
# (default "1 16 64"), BENCH_RATES (default "0.02 0.05 0.1 0.2"),
# BENCH_CONF_OFFSETS (Conference replicas at these sampling.offset values
# besides the default 0.5; default "0.15 0.85"; a point "0.1@0.15"),
# BENCH_CONF_SIZE (default 1024x768), BENCH_REPS (runs per point, the
# fastest timed; default 3), BENCH_QUICK=1 (views conference and
# cornell, threads 16, rates 0.05 0.1). The DRT rows (BENCH_DRT_*, and
# BENCH_ONLY=drt to run them alone) follow the rest.
set -eu
# No default world-cache folder (issue 36): these runs measure or compare
# builds, renders and sampled warming as they were, and write nothing into
# the user's home; a run that wants a cache names its own (--world-cache).
SAARSIM_CACHE_DIR=off
export SAARSIM_CACHE_DIR
B=${1:-build}
SIM="$B/saarsim"
SC=${SAAR_SCENES:-../shared/scenes}
[ -d "$SC" ] || SC=/work/shared/scenes
VIEWS_FILE="$SC/views.yaml"
OUT=docs/FIDELITY.md
PLOT=docs/fidelity.png
T0=$(date +%s)
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

SIZE=${BENCH_SIZE:-256x192}
CONF_SIZE=${BENCH_CONF_SIZE:-1024x768}
THREADS=${BENCH_THREADS:-"1 16 64"}
RATES=${BENCH_RATES:-"0.02 0.05 0.1 0.2"}
CONF_OFFSETS=${BENCH_CONF_OFFSETS:-"0.15 0.85"}
REPS=${BENCH_REPS:-3}
if [ "${BENCH_QUICK:-0}" = 1 ]; then
	VIEWS=${BENCH_VIEWS:-"conference cornell"}
	THREADS=${BENCH_THREADS:-16}
	RATES=${BENCH_RATES:-"0.05 0.1"}
else
	VIEWS=${BENCH_VIEWS:-$(awk '/^  [a-z0-9_]+:$/ {sub(":", "", $1); print $1}' "$VIEWS_FILE")}
fi

# one point: prints "key value" lines from the JSON report. The point
# runs $reps times (its results are the same every time, which is
# checked); its host times are the fastest run's: on a shared host single
# runs' times move far more between benchmarks than the fastest of a few
reps=1
run() { # name args...
	n=$1
	shift
	i=0
	while [ "$i" -lt "$reps" ]; do
		"$SIM" "$@" --no-check --world-cache "$TMP/wc" --report "$TMP/$n.$i.json" >/dev/null 2>"$TMP/$n.err" || {
			echo "bench-fidelity: run failed: $*" >&2
			cat "$TMP/$n.err" >&2
			return 1
		}
		i=$((i + 1))
	done
	python3 - "$reps" "$TMP/$n" <<'EOF'
import json, sys
reps, base = int(sys.argv[1]), sys.argv[2]
rs = [json.load(open("%s.%d.json" % (base, i))) for i in range(reps)]
r = rs[0]
if any(x["steady_state"] != r["steady_state"] for x in rs):
    sys.exit("bench-fidelity: repeated runs of one point differ: " + base)
r["host"]["sim_s"] = min(x["host"]["sim_s"] for x in rs)
r["host"]["wall_s"] = min(x["host"]["wall_s"] for x in rs)
f = r["fidelity"]; ss = r["steady_state"]
print("sim_s", r["host"]["sim_s"])
print("wall_s", r["host"]["wall_s"])
print("fps", ss["fps"])
lo, hi = f["fps_ci95"]
print("fps_lo", lo); print("fps_hi", hi if hi is not None else 1e30)
print("fps_bound", f["fps_bound"]); print("bound_by", f["bound_by"])
print("estimated", int(f["estimated"]))
h = ss["hit_rate"]
for t in ("shade", "kd", "list", "tri", "tag_cache", "l2"):
    v = h.get(t) if isinstance(h, dict) else None
    print("hit_" + t.replace("tag_cache", "tag"), v if v is not None else -1)
print("sdram_mb", ss["sdram_mb"])
print("pci_mb", ss["pci_mb"])
print("replayed", int(r["host"].get("packet_record") == "replayed"))
# a unit and its warm-up (the census table below)
print("region_tiles", f.get("unit_tiles", 0) + f.get("warmup_tiles", 0))
EOF
}

# figures-check lines (scripts/figures-check.py): `make test` reruns a few
# of the runs this file shows, without a world cache, and compares their
# figures with the ones here. check_line FILE REPORT KEY... -- ARGS...
# appends the line for a run made with ARGS to FILE (doc-section.sh's
# doc_check_line).
. scripts/doc-section.sh
check_line() {
	cf_file=$1
	shift
	doc_check_line "$cf_file" "$SC" "$@" || {
		echo "bench-fidelity: figures-check.py --emit failed" >&2
		return 1
	}
}

# ---- distribution ray tracing (issue 32 item 5) ----
# The DRT views of configs/drt-views.yaml (16 samples per pixel, every
# effect on; billiard also at 64) at BENCH_DRT_SIZE (default 512x384: at
# 256x192 the sampled mode's units and warm-ups cover every tile), the
# standard config, 16 threads: cycle (the truth), functional and sampled
# at BENCH_DRT_RATES, BENCH_DRT_REPS runs each (default 1). Written
# between the fidelity-drt markers of docs/FIDELITY.md; BENCH_ONLY=drt
# runs this part alone and leaves the rest of the file as it is.
DRT_VIEWS=configs/drt-views.yaml
DRT_SIZE=${BENCH_DRT_SIZE:-512x384}
DRT_RATES=${BENCH_DRT_RATES:-"0.05 0.1 0.2"}
drt_rows() { # appends rows to $1
	drows=$1
	for vs in billiard-drt@16 billiard-drt@64 cornell-drt@16; do
		view=${vs%@*}
		spp=${vs#*@}
		reps=1
		run warm --views "$DRT_VIEWS" --view "$view" --size 16x16 --fidelity functional \
			>/dev/null || continue
		set -- --views "$DRT_VIEWS" --view "$view" --spp "$spp" --size "$DRT_SIZE" \
			--set chip.threads_per_rtp=16
		reps=${BENCH_DRT_REPS:-1}
		run truth "$@" >"$TMP/dtruth.kv" || continue
		mmodes=
		for r in $DRT_RATES; do mmodes="$mmodes max:$r"; done
		for mode in functional $DRT_RATES $mmodes; do
			if [ "$mode" = functional ]; then
				run pt "$@" --fidelity functional >"$TMP/dpt.kv" || continue
			elif [ "${mode#max:}" != "$mode" ]; then
				# the max demand model alone (auto chooses between it and
				# the p-norm model; docs/fidelity.md)
				run pt "$@" --fidelity sampled --sample-rate "${mode#max:}" \
					--set sampling.warming=full --set sampling.demand_model=max \
					>"$TMP/dpt.kv" || continue
				mode="${mode#max:} max"
			else
				# full warming, as before auto chose stored with a cache
				run pt "$@" --fidelity sampled --sample-rate "$mode" --set sampling.warming=full \
					>"$TMP/dpt.kv" || continue
				# the first rate's sampled run on cornell-drt, for make test
				if [ "$vs" = cornell-drt@16 ] && [ "$mode" = "${DRT_RATES%% *}" ]; then
					check_line "$DRT_CHECKS" "$TMP/pt.0.json" steady_state.fps fidelity.fps_ci95.0 \
						fidelity.fps_ci95.1 -- "$@" --fidelity sampled --sample-rate "$mode" \
						--set sampling.warming=full --no-check
				fi
			fi
			python3 - "$TMP/dtruth.kv" "$TMP/dpt.kv" "$view" "$spp" "$mode" "$DRT_SIZE" >>"$drows" <<'EOF'
import sys
def kv(p):
    d = {}
    for l in open(p):
        k, v = l.split()
        try: d[k] = float(v)
        except ValueError: d[k] = v
    return d
t, s = kv(sys.argv[1]), kv(sys.argv[2])
view, spp, mode, size = sys.argv[3:7]
err = lambda k: (s[k] - t[k]) / t[k] * 100 if t[k] else 0.0
inside = ("yes" if s["fps_lo"] <= t["fps"] <= s["fps_hi"] else "NO") if mode != "functional" else "(bound)"
if mode != "functional" and not s["estimated"]:
    mode += " (all detailed)"
    inside = "(exact)"
hits = ["%.2f" % ((s[k] - t[k]) * 100) if t[k] >= 0 else "-" for k in ("hit_shade", "hit_kd", "hit_list", "hit_tri")]
print("| " + " | ".join([view, spp, mode, size, "%.2f" % t["sim_s"], "%.2f" % s["sim_s"],
      "%.1f" % (t["sim_s"] / s["sim_s"] if s["sim_s"] else 0), "%.2f" % t["fps"], "%.2f" % s["fps"],
      "%.2f" % err("fps"), "%.2f" % s["fps_lo"], "%.2f" % min(s["fps_hi"], 1e9), inside] + hits +
      ["%.2f" % err("sdram_mb") if t["sdram_mb"] else "-"]) + " |")
EOF
		done
	done
}
# Writes the DRT section into $OUT between its markers (appended when the
# file has none).
drt_section() {
	rows="$TMP/drt_rows.md"
	: >"$rows"
	DRT_CHECKS="$TMP/drt_checks.md"
	: >"$DRT_CHECKS"
	drt_rows "$rows"
	sec="$TMP/drt_sec.md"
	{
		echo "<!-- BEGIN fidelity-drt -->"
		echo "## Distribution ray tracing"
		echo
		echo "The DRT views of configs/drt-views.yaml (seed 000: spp samples per pixel with a thin lens, area lights, glossy reflection and camera motion; docs/views.md), standard config, 16 threads, one frame at $DRT_SIZE; each mode against cycle (the truth). Written by \`BENCH_ONLY=drt sh scripts/bench-fidelity.sh\` (also part of \`make bench-fidelity\`) on $(date -u +%Y-%m-%d), $(nproc) host cores; host times (\`host.sim_s\`) are the fastest of ${BENCH_DRT_REPS:-1} run(s). *inside*: the cycle fps lies in the sampled run's 95% interval; *(exact)*: the units and warm-ups covered every tile; *max*: \`sampling.demand_model: max\` (the max demand model alone; the other sampled rows take the default, \`auto\`, which chooses between it and the p-norm model, docs/fidelity.md); hit-rate errors in percentage points."
		echo
		echo "| view | spp | mode | size | cycle sim s | mode sim s | speed-up | cycle fps | mode fps | fps err % | CI lo | CI hi | inside | shade hit err | kd | list | tri | SDRAM MB err % |"
		echo "|---|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|"
		cat "$rows"
		cat "$DRT_CHECKS"
		echo "<!-- END fidelity-drt -->"
	} >"$sec"
	if [ -f "$OUT" ] && grep -q '<!-- BEGIN fidelity-drt -->' "$OUT"; then
		awk -v sec="$sec" '
			/<!-- BEGIN fidelity-drt -->/ {while ((getline l < sec) > 0) print l; skip = 1; next}
			/<!-- END fidelity-drt -->/ {skip = 0; next}
			!skip' "$OUT" >"$TMP/out_drt.md"
		cp "$TMP/out_drt.md" "$OUT"
	else
		{
			echo
			cat "$sec"
		} >>"$OUT"
	fi
	echo "bench-fidelity: wrote the DRT rows of $OUT"
}
if [ "${BENCH_ONLY:-}" = drt ]; then
	drt_section
	exit 0
fi

ROWS="$TMP/rows.tsv"
: >"$ROWS"
CHECKS="$TMP/checks.md" # figures-check lines: Conference, std, 16 threads
: >"$CHECKS"
CENSUS="$TMP/census.txt" # per Conference config and thread count: its census (the sample table)
: >"$CENSUS"
for view in $VIEWS; do
	size=$SIZE
	[ "$view" = conference ] && size=$CONF_SIZE
	reps=1
	# every point reads the world from the cache, as a sweep's points do:
	# built and stored here, once per view (not timed)
	run warm --views "$VIEWS_FILE" --view "$view" --size 16x16 --fidelity functional \
		>/dev/null || continue
	# and the frame's packet record (docs/fidelity.md), which a sweep's
	# first functional or sampled point stores for the others
	run warm --views "$VIEWS_FILE" --view "$view" --size "$size" --fidelity functional \
		>/dev/null || continue
	# shellcheck disable=SC2012 # the newest record is the one just stored
	# (none stored, e.g. the world cache could not be written: the floor
	# line says 0 rather than the benchmark stopping here)
	if [ "$view" = conference ]; then
		REC_BYTES=$(ls -t "$TMP"/wc/packets-*.bin 2>/dev/null | head -1 | xargs -r stat -c %s || true)
	fi
	for cfg in std vma; do
		cf=configs/saarcor-$cfg.yaml
		for tpr in $THREADS; do
			# shellcheck disable=SC2086
			set -- --views "$VIEWS_FILE" --view "$view" --config "$cf" --size "$size" \
				--set chip.threads_per_rtp="$tpr"
			reps=$REPS
			# Conference's truth also writes its census (--census: each
			# chunk's cycles and demand; the sample table below)
			cen=
			[ "$view" = conference ] && cen="--census $TMP/census_${cfg}_$tpr.csv"
			# shellcheck disable=SC2086 # cen is two words or none
			run truth "$@" $cen >"$TMP/truth.kv" || continue
			# Conference, standard config, 16 threads: its truth and
			# its first rate's sampled point, for make test
			chk=
			if [ "$view" = conference ] && [ "$cfg" = std ] && [ "$tpr" = 16 ]; then chk=1; fi
			[ -z "$chk" ] || check_line "$CHECKS" "$TMP/truth.0.json" steady_state.fps cycles \
				-- "$@" --no-check
			censused=
			# Conference: replicas at other sampling offsets too; every
			# rate and offset also with stored warming (rate@offset@stored),
			# whose warming run a sweep's first point stores for the others:
			# built here, once per view, config and thread count (not timed)
			points=functional
			for wm in full stored; do
				for r in $RATES; do
					points="$points $r@0.5@$wm"
					[ "$view" = conference ] && for o in $CONF_OFFSETS; do points="$points $r@$o@$wm"; done
				done
			done
			reps=1
			run warm "$@" --fidelity sampled --set sampling.warming=stored >/dev/null || continue
			reps=$REPS
			for mode in $points; do
				if [ "$mode" = functional ]; then
					run pt "$@" --fidelity functional >"$TMP/pt.kv" || continue
				else
					run pt "$@" --fidelity sampled --sample-rate "${mode%%@*}" \
						--set sampling.offset="$(echo "$mode" | cut -d@ -f2)" \
						--set sampling.warming="$(echo "$mode" | cut -d@ -f3)" \
						>"$TMP/pt.kv" || continue
					if [ -n "$chk" ] && [ "$mode" = "${RATES%% *}@0.5@full" ]; then
						check_line "$CHECKS" "$TMP/pt.0.json" steady_state.fps \
							fidelity.fps_ci95.0 fidelity.fps_ci95.1 -- "$@" --fidelity sampled \
							--sample-rate "${mode%%@*}" --set sampling.offset=0.5 \
							--set sampling.warming=full --no-check
					fi
				fi
				# the census's regions: a sampled point's unit and warm-up
				if [ -n "$cen" ] && [ -z "$censused" ] && [ "$mode" != functional ] && [ "$tpr" -gt 1 ]; then
					awk -v c="$cfg" -v t="$tpr" -v p="$TMP/census_${cfg}_$tpr.csv" \
						'$1 == "region_tiles" {print c, t, $2, p}' "$TMP/pt.kv" >>"$CENSUS"
					censused=1
				fi
				python3 - "$TMP/truth.kv" "$TMP/pt.kv" "$view" "$cfg" "$tpr" "$mode" "$size" >>"$ROWS" <<'EOF'
import sys
def kv(p):
    d = {}
    for l in open(p):
        k, v = l.split()
        try: d[k] = float(v)
        except ValueError: d[k] = v
    return d
t, s = kv(sys.argv[1]), kv(sys.argv[2])
view, cfg, tpr, mode, size = sys.argv[3:8]
if mode != "functional":  # rate@offset@warming: rate, @offset unless the default, ", stored"
    rate, off, wm = mode.split("@")
    mode = rate + ("" if off == "0.5" else "@" + off) + (", stored" if wm == "stored" else "")
err = lambda k: (s[k] - t[k]) / t[k] * 100 if t[k] else 0.0
hits = []
for k in ("hit_shade", "hit_kd", "hit_list", "hit_tri", "hit_tag", "hit_l2"):
    hits.append("%.2f" % ((s[k] - t[k]) * 100) if t[k] >= 0 else "-")
inside = int(s["fps_lo"] <= t["fps"] <= s["fps_hi"]) if mode != "functional" else -1
if mode != "functional" and not s["estimated"]:
    mode += " (all detailed)"   # the units and warm-ups cover the frame: cycle, exactly
    inside = -2
print("\t".join(map(str, [view, cfg, tpr, mode, size, "%.3f" % t["sim_s"], "%.3f" % s["sim_s"],
      "%.1f" % (t["sim_s"] / s["sim_s"] if s["sim_s"] else 0), "%.2f" % t["fps"], "%.2f" % s["fps"],
      "%.2f" % err("fps"), "%.2f" % s["fps_lo"], "%.2f" % min(s["fps_hi"], 1e9), inside] + hits +
      ["%.2f" % err("sdram_mb") if t["sdram_mb"] else "-", "%.2f" % err("pci_mb") if t["pci_mb"] else "-",
       "%.1f" % (t["wall_s"] / s["wall_s"] if s["wall_s"] else 0), int(s["replayed"])])))
EOF
			done
		done
	done
done

# skipping as speed: the same scene without lights / mirrors against with,
# in every mode (the counters from cycle; the other modes must agree)
SKIP="$TMP/skip.txt"
: >"$SKIP"
for variant in "default:" "no lights:--no-lights" "no secondary:--set shading.max_depth=0" \
	"neither:--no-lights --set shading.max_depth=0"; do
	name=${variant%%:*}
	flags=${variant#*:}
	ok=1
	for mode in cycle sampled functional; do
		# shellcheck disable=SC2086
		"$SIM" --scene spd:balls:3 --size 512x512 --no-check --fidelity "$mode" $flags \
			--world-cache "$TMP/wc" --report "$TMP/sk_$mode.json" >/dev/null 2>&1 || ok=0
	done
	[ "$ok" = 1 ] || { echo "| $name | (run failed) |" >>"$SKIP"; continue; }
	python3 - "$TMP" "$name" >>"$SKIP" <<'EOF'
import json, sys
d, name = sys.argv[1], sys.argv[2]
r = {m: json.load(open("%s/sk_%s.json" % (d, m))) for m in ("cycle", "sampled", "functional")}
keys = ("rays.primary", "rays.shadow", "rays.reflection", "rays.refraction", "skip.shadow_no_light",
        "skip.no_secondary")
g = lambda m, k: r[m]["counters"].get(k, 0)
same = all(g(m, k) == g("cycle", k) for m in r for k in keys)
print("| %s | %d | %d | %d | %d | %d | %d | %.3f | %.3f | %.3f | %s |" % (name, g("cycle", "rays.primary"),
      g("cycle", "rays.shadow"), g("cycle", "rays.reflection") + g("cycle", "rays.refraction"),
      g("cycle", "skip.shadow_no_light"), g("cycle", "skip.no_secondary"), r["cycle"]["cycles"],
      r["cycle"]["host"]["sim_s"], r["sampled"]["host"]["sim_s"], r["functional"]["host"]["sim_s"],
      "yes" if same else "NO"))
EOF
done

# replicas: ten sampling offsets per rate of one run; one table row per
# rate with the estimate's error against cycle and how often the interval
# covered it. replicas OUT LABEL RATES TRUTH ARGS...: the cycle truth and
# the sampled runs get ARGS; the truth's report is TRUTH, run only when it
# is not there yet (rows differing in sampling settings alone share it);
# the row starts with LABEL (table cells).
replicas() {
	rout=$1 label=$2 rates=$3 truth=$4
	shift 4
	[ -s "$truth" ] || "$SIM" "$@" --no-check --world-cache "$TMP/wc" --report "$truth" \
		>/dev/null 2>&1 || return 0
	for r in $rates; do
		for o in 0.05 0.15 0.25 0.35 0.45 0.55 0.65 0.75 0.85 0.95; do
			"$SIM" "$@" --no-check --world-cache "$TMP/wc" --fidelity sampled --sample-rate "$r" \
				--set sampling.offset="$o" --set sampling.warming=full --report "$TMP/rp_$o.json" >/dev/null 2>&1 ||
				rm -f "$TMP/rp_$o.json"
		done
		python3 - "$TMP" "$label" "$r" "$truth" >>"$rout" <<'EOF'
import glob, json, sys
d, label, r, truth = sys.argv[1:5]
t = json.load(open(truth))["fidelity"]["fps"]
e, cov, n = [], 0, 0
for f in sorted(glob.glob(d + "/rp_*.json")):
    s = json.load(open(f))["fidelity"]
    lo, hi = s["fps_ci95"]
    hi = hi if hi is not None else 1e30
    e.append((s["fps"] - t) / t * 100)
    cov += lo <= t <= hi
    n += 1
if n:
    print("| %s | %s | %d | %.2f | %+.2f | %.2f | %d of %d |" % (label, r, n, (sum(x * x for x in e) / n) ** 0.5,
          sum(e) / n, max(abs(x) for x in e), cov, n))
EOF
		rm -f "$TMP"/rp_*.json
	done
}

# a small, sparse frame at one thread per RTP, where the sampled estimate
# is weakest
REP="$TMP/rep.txt"
: >"$REP"
REP_VIEW=${BENCH_REP_VIEW:-robots}
if grep -q "^  $REP_VIEW:" "$VIEWS_FILE"; then
	for cfg in std vma; do
		replicas "$REP" "$cfg" "0.05 0.1 0.2" "$TMP/rt_rep_$cfg.json" \
			--views "$VIEWS_FILE" --view "$REP_VIEW" \
			--config configs/saarcor-$cfg.yaml --size "$SIZE" --set chip.threads_per_rtp=1
	done
fi
# the warm-up length at one thread per RTP on Conference (the default is
# one tile per thread: 4)
WUP="$TMP/wup.txt"
: >"$WUP"
# shellcheck disable=SC2086
if printf '%s\n' $VIEWS | grep -qx conference; then
	for cfg in std vma; do
		for w in 4 16 32; do
			replicas "$WUP" "$cfg | $w" "0.05 0.1" "$TMP/rt_wup_$cfg.json" \
				--views "$VIEWS_FILE" --view conference \
				--config configs/saarcor-$cfg.yaml --size "$CONF_SIZE" \
				--set chip.threads_per_rtp=1 --warmup-tiles "$w"
		done
	done
fi

# the plot
if command -v gnuplot >/dev/null 2>&1; then
	awk -F'\t' '$4 != "functional" {e=$11<0?-$11:$11; print $7, e+0.001}' "$ROWS" >"$TMP/s.dat"
	awk -F'\t' '$4 == "functional" {e=$11<0?-$11:$11; print $7, e+0.001}' "$ROWS" >"$TMP/f.dat"
	awk -F'\t' '$4 == "functional" {print $6}' "$ROWS" | sort -u | awk '{print $1, 0.001}' >"$TMP/c.dat"
	gnuplot <<EOF || echo "bench-fidelity: gnuplot failed" >&2
set terminal pngcairo size 900,600
set output "$PLOT"
set logscale xy
set xlabel "host seconds (chip_run)"
set ylabel "|fps error| % (+0.001)"
set title "saarsim fidelity modes: host time against fps error (vs cycle)"
plot "$TMP/s.dat" using 1:2 title "sampled" with points pt 7, \
     "$TMP/f.dat" using 1:2 title "functional (a bound)" with points pt 5, \
     "$TMP/c.dat" using 1:2 title "cycle (truth)" with points pt 9
EOF
fi

# targets from the Conference 1024x768 std points
TGT=$(awk -F'\t' -v cs="$CONF_SIZE" '
	$1 == "conference" && $5 == cs && $14 >= 0 {
		n++; e = $11 < 0 ? -$11 : $11; if ($14 == 1) cov++
		st = $4 ~ /stored$/
		ns += st; if (e <= 1 && $8 >= 10) { ok++; oks += st }
		if (e <= 1 && $8 > fast1) fast1 = $8
		if (e < best || best == "") { best = e; bsp = $8 }
	}
	END {
		if (!n) { print "no estimated Conference " cs " points"; exit }
		printf "Conference %s, sampled (estimated points): %d of %d points within 1%% fps error at >= 10x less host time (target: some; %s; full warming %d of %d, stored warming %d of %d); the fastest point within 1%% ran %.1fx faster than cycle; best error %.2f%% (at %.1fx).\n",
			cs, ok, n, (ok > 0) ? "met" : "NOT met", ok - oks, n - ns, oks, ns, fast1, best, bsp
		printf "- Conference %s: the interval covered the true fps on %d of %d points (%.0f%%; target >= 95%%: %s).\n",
			cs, cov, n, 100 * cov / n, (cov / n >= 0.95) ? "met" : "NOT met"
	}' "$ROWS")
COV=$(awk -F'\t' '$14 >= 0 {n++; c += $14} END {if (n) printf "%d of %d estimated sampled points (%.0f%%)", c, n, 100*c/n; else print "no estimated sampled points"}' "$ROWS")

# what bounds the speed-up on Conference (std, 16 threads per RTP): cycle's
# host time against functional mode with the packet record (the memory
# system's own work) and without it (the math too), and kernel-ref alone
FLOOR="Floor: no Conference point to compare with."
CYC=$(awk -F'\t' -v cs="$CONF_SIZE" '$1 == "conference" && $5 == cs && $2 == "std" {c = $6; if ($3 == 16) {print $6; done = 1; exit}} END {if (!done && c != "") print c}' "$ROWS")
FUNC=$(awk -F'\t' -v cs="$CONF_SIZE" '$1 == "conference" && $5 == cs && $2 == "std" && $3 == 16 && $4 == "functional" {print $7; exit}' "$ROWS")
if [ -n "$CYC" ] && "$B/rtref" --views "$VIEWS_FILE" --view conference --size "$CONF_SIZE" \
	--threads "$(nproc)" --stats "$TMP/rt.json" >/dev/null 2>&1 &&
	"$B/rtref" --views "$VIEWS_FILE" --view conference --size "$CONF_SIZE" \
		--threads 1 --stats "$TMP/rt1.json" >/dev/null 2>&1 &&
	"$SIM" --views "$VIEWS_FILE" --view conference --size "$CONF_SIZE" --fidelity functional \
		--no-check --report "$TMP/fn_math.json" >/dev/null 2>&1; then
	FLOOR=$(python3 - "$TMP/rt.json" "$CYC" "$(nproc)" "$TMP/rt1.json" "${FUNC:-0}" "$TMP/fn_math.json" "${REC_BYTES:-0}" <<'EOF'
import json, sys
r = json.load(open(sys.argv[1])); ms = r["render_ms"] / 1e3; cyc = float(sys.argv[2])
ms1 = json.load(open(sys.argv[4]))["render_ms"] / 1e3; fn = float(sys.argv[5])
fm = json.load(open(sys.argv[6]))["host"]["sim_s"]
s = "Floor: cycle takes %.3f s on Conference (standard config, 16 threads per RTP; 10x would need %.3f s). " % (cyc, cyc / 10)
s += ("Functional mode, which sampled mode runs between its detailed regions, takes %.3f s with the math (%.1fx below cycle)"
      % (fm, cyc / fm))
if fn > 0:
    s += (" and %.3f s replaying the packet record (%.1fx; the record takes %.1f MB): the memory system's own work, every request "
          "through the caches; that plus the detailed regions bounds sampled mode's speed-up"
          % (fn, cyc / fn, float(sys.argv[7]) / 2**20))
s += (". kernel-ref alone renders the frame in %.3f s on one host thread (%.1fx below cycle) and %.3f s on %s"
      % (ms1, cyc / ms1, ms, sys.argv[3]))
# a detailed region replays the record: about a cycle tile's cost less its math
if cyc > ms1:
    s += (". So even with free warming, 10x leaves about %.0f%% of the frame's tiles to simulate in detail "
          "(a tenth of cycle's time over a detailed tile's cost, cycle's per tile less kernel-ref's math; "
          "compare the census table's shares)" % (10 * cyc / (cyc - ms1)))
print(s + ".")
EOF
)
fi

T1=$(date +%s)
SEC="$TMP/section.md"
{
	echo "<!-- BEGIN fidelity -->"
	echo "## Fidelity modes: host time against error"
	echo
	echo "Generated by \`make bench-fidelity\` (scripts/bench-fidelity.sh); do not edit by hand."
	echo
	echo "- Date: $(date -u '+%Y-%m-%d %H:%M UTC') (the run took $((T1 - T0)) s)"
	echo "- Machine: $(nproc) CPUs (nproc); load average $(cut -d' ' -f1-3 /proc/loadavg) at the end"
	echo "- Commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)$(git diff --quiet -- . ':!docs/FIDELITY.md' ':!docs/fidelity.png' 2>/dev/null || echo ' (plus uncommitted changes)')"
	echo "- Views: $(echo $VIEWS); Conference at $CONF_SIZE, the others at $SIZE; threads per RTP: $THREADS; sample rates: $RATES, on Conference also at sampling offsets $CONF_OFFSETS (rate@offset; the default offset is 0.5) (the defaults: units of rtps x threads_per_rtp tiles, a warm-up of rtps x min(threads_per_rtp, 16) tiles before each, at least 8 units; a point marked \"all detailed\" had no room for them and ran as cycle)"
	echo "- $FLOOR"
	echo "- Host time: \`chip_run\` (report host.sim_s), the fastest of $REPS runs per point (their results are the same; on a shared host single runs' times move far more than the fastest of a few); *whole-run speed-up*: the same for the whole process (host.wall_s), what each point of a sweep costs: the world (scene, kd-tree, memory image) and, for functional and sampled points, the frame's packet record (docs/fidelity.md; the *record* column says the point replayed it) come from a world cache built once per view beforehand, as in \`scripts/sweep\` (without one, add the load of PERFORMANCE.md's world cache table to both sides, and the math to the mode: the floor line). Errors: (mode - cycle) / cycle in %; hit rates: difference in percentage points."
	echo
	echo "### Targets"
	echo
	echo "- $TGT"
	echo "- Coverage over all sampled points: $COV."
	echo
	echo "### Conference $CONF_SIZE by config"
	echo
	echo "Sampled: every estimated point (all rates and offsets); its hit rates (every cache, VMA's tag cache and on-board cache included) in points and SDRAM MB in % against cycle's. Functional: its traffic against cycle's (L1 hit rates in points, SDRAM MB in %)."
	echo
	echo "| config | threads | warming | sampled points | rms fps err % | max fps err % | interval covered | speed-up (min-median-max) | whole-run speed-up (median) | sampled: max hit pp | sampled: rms SDRAM MB err % | functional: max L1 hit pp | functional: SDRAM MB err % |"
	echo "|---|---:|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|"
	python3 - "$ROWS" "$CONF_SIZE" <<'EOF'
import sys, statistics
rows = [l.rstrip("\n").split("\t") for l in open(sys.argv[1])]
conf = [r for r in rows if r[0] == "conference" and r[4] == sys.argv[2]]
for cfg in ("std", "vma"):
  for t in sorted({int(r[2]) for r in conf if r[1] == cfg}):
    for wm in ("full", "stored"):
        sel = [r for r in conf if r[1] == cfg and int(r[2]) == t]
        est = [r for r in sel if int(r[13]) >= 0 and (r[3].endswith("stored")) == (wm == "stored")]
        fn = [r for r in sel if r[3] == "functional"]
        if est:
            e = [abs(float(r[10])) for r in est]
            sp = sorted(float(r[7]) for r in est)
            cov = sum(int(r[13]) for r in est)
            hp = [abs(float(x)) for r in est for x in r[14:20] if x != "-"]
            sd = [float(r[20]) for r in est if r[20] != "-"]
            s = "| %s | %d | %s | %d | %.2f | %.2f | %d of %d | %.1f-%.1f-%.1f | %.1f | %.2f | %s |" % (
                cfg, t, wm, len(est), (sum(x * x for x in e) / len(e)) ** 0.5, max(e), cov, len(est),
                sp[0], statistics.median(sp), sp[-1], statistics.median(float(r[22]) for r in est),
                max(hp), "%.2f" % (sum(x * x for x in sd) / len(sd)) ** 0.5 if sd else "-")
        else:
            s = "| %s | %d | %s | 0 | - | - | - | - | - | - | - |" % (cfg, t, wm)
        if fn:
            hp = [abs(float(x)) for x in fn[0][14:18]]
            s += " %.2f | %s |" % (max(hp), fn[0][20])
        else:
            s += " - | - |"
        print(s)
EOF
	echo
	if [ -s "$CENSUS" ]; then
		# the estimator's strata as the config has them
		HS=$("$SIM" --list-config | awk '$1 == "sampling.hard_share" {print $3}')
		echo "### Conference $CONF_SIZE: the sample a 1% error needs"
		echo
		echo "From each truth run's census (\`--census\`: the cycles and resource demand of every chunk of one unit's tiles, docs/fidelity.md \"Census\"), the frame's middle (between the head and tail regions, which sampled mode measures whole) as if every chunk could be a unit and warming were exact and free: the demand model is the one sampling.demand_model auto takes between the max and the p-norm model (the linear model left out), fitted to all chunks (*model*: which, and its fitted parameters); *memory bound*: the share of the middle's cycles in chunks whose SDRAM or host-bus time exceeds $HS of their busiest compute resource (the estimator's strata, sampling.hard_share); *s*: the chunks' residual standard deviation around one ratio, relative to the mean chunk; *8 units*: the fps error of the plain ratio estimate from 8 systematically placed chunks, rms / max over 10 offsets. Then the units a 1% error of the frame needs, from the chunks' variance (the ratio estimator's, with the finite-population correction): *plain* with one ratio, *strata* with the two strata's own ratios and their units allocated in proportion to each stratum's size times its spread (the best two strata can do); in brackets the share of the frame's tiles those units with their warm-ups and the head and tail regions simulate in detail. One thread per RTP (units of 4 tiles, the linear model) is left out. scripts/census-need.py computes it."
		echo
		# shellcheck disable=SC2046 # one argument per word of the list
		python3 scripts/census-need.py --hard-share "$HS" $(cat "$CENSUS")
		echo
	fi
	echo "### Every point"
	echo
	echo "| view | config | threads | mode / rate | size | cycle s | mode s | speed-up | cycle fps | mode fps | fps err % | CI low | CI high | true in CI | shade pp | kd pp | list pp | tri pp | tag pp | l2 pp | SDRAM MB err % | PCI MB err % | whole-run speed-up | record |"
	echo "|---|---|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"
	awk -F'\t' 'BEGIN {OFS=" | "} {if ($14 == 1) $14 = "yes"; else if ($14 == 0) $14 = "NO"; else if ($14 == -2) $14 = "(exact)"; else $14 = "(bound)"; $24 = $24 == 1 ? "replayed" : "-"; $1 = $1; print "| " $0 " |"}' "$ROWS"
	cat "$CHECKS"
	echo
	if [ -s "$REP" ]; then
		echo "### Replicas on a small, sparse frame"
		echo
		echo "$REP_VIEW at $SIZE, one thread per RTP, ten sampling offsets per rate (independent replicas): the estimate's error against cycle and how often the interval covered it. Few units see a frame whose tiles differ widely (empty background beside dense geometry), at a thread count where cycles follow latency more than demand."
		echo
		echo "| config | rate | replicas | rms fps err % | mean fps err % | max fps err % | interval covered |"
		echo "|---|---:|---:|---:|---:|---:|---:|"
		cat "$REP"
		echo
	fi
	if [ -s "$WUP" ]; then
		echo "### Warm-up length at one thread per RTP"
		echo
		echo "Conference at $CONF_SIZE, one thread per RTP (units of 4 tiles; the default warm-up is as long), with warm-ups of 4, 16 and 32 tiles, ten sampling offsets per rate: the estimate's error against cycle and how often the interval covered it (docs/fidelity.md, \"Warm-up under the VMA\")."
		echo
		echo "| config | warm-up tiles | rate | replicas | rms fps err % | mean fps err % | max fps err % | interval covered |"
		echo "|---|---:|---:|---:|---:|---:|---:|---:|"
		cat "$WUP"
		echo
	fi
	echo "### Skipping as speed"
	echo
	echo "SPD balls (level 3), 512x512: what the scene does not need is not simulated, in any mode. Rays, skip counters and cycles from cycle mode; *same counts*: sampled (default rate) and functional counted the same rays and skips; host time (\`host.sim_s\`) per mode."
	echo
	echo "| variant | primary rays | shadow rays | secondary rays | skip.shadow_no_light | skip.no_secondary | cycles | cycle sim s | sampled sim s | functional sim s | same counts |"
	echo "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|"
	cat "$SKIP"
	[ -f "$PLOT" ] && echo && echo "![host time against fps error](fidelity.png)"
	echo "<!-- END fidelity -->"
} >"$SEC"

if [ -f "$OUT" ] && grep -q '<!-- BEGIN fidelity -->' "$OUT"; then
	awk -v sec="$SEC" '
		/<!-- BEGIN fidelity -->/ {while ((getline l < sec) > 0) print l; skip = 1; next}
		/<!-- END fidelity -->/ {skip = 0; next}
		!skip' "$OUT" >"$TMP/out.md"
	cp "$TMP/out.md" "$OUT"
else
	{
		echo "# saarsim fidelity benchmark"
		echo
		echo "Measured, never typed: the section below is written by \`make bench-fidelity\` between its BEGIN/END markers (docs/fidelity.md explains the modes)."
		echo
		cat "$SEC"
	} >"$OUT"
fi
echo "bench-fidelity: wrote $OUT ($((T1 - T0)) s)"
drt_section
