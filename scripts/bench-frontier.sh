#!/bin/sh
# scripts/bench-frontier.sh: sampled mode's speed against its fps error
# for a list of sampling settings (issue 36, target 3: what each setting
# buys, so a sweep can choose its own).
#
#   sh scripts/bench-frontier.sh
#
# For each thread count of THREADS (threads per RTP, default 8 16 32; the
# default config has 16) and each view of views.yaml at SIZE (default
# 1024x768): one cycle run (the truth), then for each setting of the list
# below sampled runs at every offset of OFFSETS (default 0.1 0.2 ... 0.9;
# `--set sampling.offset=X`), `--no-check`. The fps errors are
# deterministic (no host time enters them). Then the speed on VIEW
# (default conference) at each thread count: warm whole runs
# (`host.wall_s`, the world, packet record and warming run already in the
# cache; the default check on), cycle and each setting in turn, best of
# RUNS (default 5). A world cache in a temporary folder keeps the runs
# short.
#
# Writes the section between <!-- BEGIN frontier --> and
# <!-- END frontier --> of docs/PERFORMANCE.md and prints it. Needs POSIX
# sh and awk.
set -eu
. "$(dirname "$0")/bench-lib.sh"
bench_init bench-frontier
SIZE=${SIZE:-1024x768}
OFFSETS=${OFFSETS:-0.1 0.2 0.3 0.4 0.5 0.6 0.7 0.8 0.9}
VIEW=${VIEW:-conference}
RUNS=${RUNS:-5}
THREADS=${THREADS:-8 16 32}
case $RUNS in '' | *[!0-9]* | 0) die "RUNS must be a positive integer" ;; esac
for T in $THREADS; do
	case $T in '' | *[!0-9]* | 0) die "THREADS must be positive integers" ;; esac
done
bench_start frontier
echo "$VLIST" | grep -qx "$VIEW" || die "no view $VIEW in $VIEWS"
WC=$TMP/wc
# The settings: label, then the --set arguments (none: the defaults).
SETTINGS=$TMP/settings
cat >"$SETTINGS" <<'EOF'
defaults
units_128 sampling.unit_tiles=128
relax sampling.jump=relax
mixed sampling.jump=mixed
mixed,_units_128 sampling.jump=mixed sampling.unit_tiles=128
mixed,_units_256 sampling.jump=mixed sampling.unit_tiles=256
drain sampling.jump=drain
drain,_units_128 sampling.jump=drain sampling.unit_tiles=128
drain,_units_224,_warm-up_32 sampling.jump=drain sampling.unit_tiles=224 sampling.warmup_tiles=32
drain,_units_256 sampling.jump=drain sampling.unit_tiles=256
drain,_units_320 sampling.jump=drain sampling.unit_tiles=320
skip sampling.jump=skip
skip,_units_128 sampling.jump=skip sampling.unit_tiles=128
skip,_units_256 sampling.jump=skip sampling.unit_tiles=256
EOF
# one run's report into $TMP/r.json: VIEW ARGS...
run() {
	v=$1
	shift
	"$SIM" --views "$VIEWS" --view "$v" --size "$SIZE" --quiet --world-cache "$WC" \
		--report "$TMP/r.json" "$@" </dev/null >"$TMP/out" 2>&1 ||
		{ cat "$TMP/out" >&2; die "saarsim failed on $v $*"; }
}
# the --set arguments of a settings line's fields 2..
sets() {
	for kv in "$@"; do printf -- '--set %s ' "$kv"; done
}
ERRS=$TMP/errs   # threads label view e1,e2,...
TIMES=$TMP/times # threads label wall_s
RATIOS=$TMP/ratios # threads view memory_to_compute jump (the defaults' run)
: >"$ERRS"
: >"$TIMES"
: >"$RATIOS"
for T in $THREADS; do
	for v in $VLIST; do
		say "$T threads, $v: cycle"
		run "$v" --no-check --set chip.threads_per_rtp="$T"
		truth=$(jget "$TMP/r.json" fps)
		while read -r label kvs; do
			say "$T threads, $v: $label"
			line=
			for o in $OFFSETS; do
				# shellcheck disable=SC2046,SC2086
				run "$v" --no-check --set chip.threads_per_rtp="$T" --fidelity sampled \
					--set sampling.offset="$o" $(sets $kvs)
				f=$(jget "$TMP/r.json" fps)
				line="$line,$(pct_err "$f" "$truth")"
			done
			# the jump the defaults took (sampling.jump auto decides per
			# frame, the same at every offset): from the last run's report
			if [ "$label" = defaults ]; then
				j="?"
				[ -n "$(jget "$TMP/r.json" relax)" ] && j=relax
				[ -n "$(jget "$TMP/r.json" skip)" ] && j=skip
				echo "$T $v $(jget "$TMP/r.json" memory_to_compute) $j" >>"$RATIOS"
			fi
			printf '%s %s %s %s\n' "$T" "$label" "$v" "${line#,}" >>"$ERRS"
		done <"$SETTINGS"
	done
	# Speed on VIEW: every setting's warming run is in the cache by now;
	# the check's reference frames join it at the first checked run
	# (discarded).
	say "$T threads, $VIEW: timing (best of $RUNS)"
	run "$VIEW" --set chip.threads_per_rtp="$T"
	i=0
	while [ "$i" -lt "$RUNS" ]; do
		i=$((i + 1))
		run "$VIEW" --set chip.threads_per_rtp="$T"
		echo "$T cycle $(jget "$TMP/r.json" wall_s)" >>"$TIMES"
		while read -r label kvs; do
			# shellcheck disable=SC2046,SC2086
			run "$VIEW" --set chip.threads_per_rtp="$T" --fidelity sampled $(sets $kvs)
			echo "$T $label $(jget "$TMP/r.json" wall_s)" >>"$TIMES"
		done <"$SETTINGS"
	done
done
bench_end
best() { awk -v t="$1" -v l="$2" '$1 == t && $2 == l && (b == "" || $3 < b) { b = $3 } END { print b }' "$TIMES"; }
nv=$(echo "$VLIST" | wc -l)
no=$(echo "$OFFSETS" | wc -w)
# the fields 2.. of a settings line as the table names them
name_of() {
	if [ -z "$1" ]; then echo "(defaults)"; else echo "$1" | sed 's/sampling\.//g; s/ /, /g'; fi
}
{
	echo "<!-- BEGIN frontier -->"
	echo "### Sampled mode: speed against fps error by setting (issue 36, target 3)"
	echo
	echo "Generated by scripts/bench-frontier.sh (\`make bench-frontier\`); do not edit by hand."
	echo
	echo "- Date: $(date -u '+%Y-%m-%d %H:%M UTC') (took $elapsed s); commit $GIT"
	echo "- Machine: $(nproc) CPUs, $(doc_cpu); load average $load0 at start, $load1 at the end (the errors do not depend on it; the times do)"
	echo "- Run: the default config with \`chip.threads_per_rtp\` $THREADS (the default 16); every view of views.yaml at $SIZE; each view's cycle run the truth; each setting's sampled runs (\`--fidelity sampled\` and the setting's \`--set\` keys) at \`sampling.offset\` $OFFSETS, \`--no-check\`. Speed: whole runs on $VIEW with the default check, the world, packet record and warming runs already in the cache, best of $RUNS, against the cycle run's best at the same thread count. Settings name keys under \`sampling.\`; a unit or warm-up length is in tiles whatever the thread count (the defaults: units of one tile per thread slot, warm-ups of one per slot up to 16 per RTP)."
	echo "- *within 2%*: of the $((nv - 1)) views other than robots x $no offsets (robots: docs/fidelity.md, \"Frames that alternate between bottlenecks\"); *mean |error|* over the same points. Offsets whose regions snap to the same stored-warming checkpoints give the same plan, so the offsets are fewer independent replicas than there are offsets."
	echo
	echo "| threads per RTP | setting | $VIEW whole s | speed-up | $VIEW fps errors, lowest to highest | within 2% | mean abs. error | worst view (mean error) | robots mean error |"
	echo "|---:|---|---:|---:|---|---:|---:|---|---:|"
	for T in $THREADS; do
		cyc=$(best "$T" cycle)
		while read -r label kvs; do
			b=$(best "$T" "$label")
			awk -v T="$T" -v l="$label" -v V="$VIEW" -v b="$b" -v c="$cyc" -v name="$(name_of "$kvs")" '
			$1 == T && $2 == l { n = split($4, e, ",")
				s = 0; for (i = 1; i <= n; i++) s += e[i]
				if ($3 == "robots") { rob = s / n; next }
				if ($3 == V) { lo = e[1]; hi = e[1]
					for (i = 2; i <= n; i++) { if (e[i] < lo) lo = e[i]; if (e[i] > hi) hi = e[i] } }
				m = s / n; am = m < 0 ? -m : m
				if (wv == "" || am > wam) { wv = $3; wam = am; wm = m }
				for (i = 1; i <= n; i++) { x = e[i] < 0 ? -e[i] : e[i]; pts++; sa += x; if (x <= 2) ok++ } }
			END { printf "| %s | %s | %.3f | %.2fx | %+.2f%% to %+.2f%% | %d of %d | %.2f%% | %s (%+.2f%%) | %+.2f%% |\n",
					T, name, b, c / b, lo, hi, ok, pts, sa / pts, wv, wm, rob }' "$ERRS"
		done <"$SETTINGS"
	done
	echo
	echo "Cycle runs' whole s on $VIEW: $(for T in $THREADS; do printf '%s threads %.3f; ' "$T" "$(best "$T" cycle)"; done | sed 's/; $//')."
	echo
	echo "The defaults' jump by view: the warming run's memory time over its compute time (the report's \`fidelity.memory_to_compute\`) and the jump \`sampling.jump: auto\` took (relax at \`sampling.auto_ratio\`, 2, or more; docs/fidelity.md):"
	echo
	# shellcheck disable=SC2086
	md_head '| view |' ' %s threads per RTP |' '|---|' $THREADS
	for v in $VLIST; do
		printf '| %s |' "$v"
		for T in $THREADS; do
			awk -v T="$T" -v v="$v" '$1 == T && $2 == v { printf " %.2f %s |", $3, $4 }' "$RATIOS"
		done
		echo
	done
	echo
	echo "Every view's errors, offsets in the order above:"
	echo
	echo "| threads per RTP | setting | view | fps errors (%) |"
	echo "|---:|---|---|---|"
	for T in $THREADS; do
		while read -r label kvs; do
			awk -v T="$T" -v l="$label" -v name="$(name_of "$kvs")" '$1 == T && $2 == l { e = $4; gsub(/,/, " ", e); printf "| %s | %s | %s | %s |\n", T, name, $3, e }' "$ERRS"
		done <"$SETTINGS"
	done
	echo "<!-- END frontier -->"
} >"$SECTION"
doc_section frontier "$SECTION" "$DOC"
cat "$SECTION"
say "wrote $DOC (section frontier)"
