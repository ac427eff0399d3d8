#!/bin/sh
# extend-check.sh (make extend-check): docs/extending.md's unit-kind
# walk-through, built and run. Copies the repository into
# build-extend/src, applies tests/extend/unit-clip.patch there (the page's
# edits: scripts/extend-doc.py, which `make test` runs, holds the page and
# the patch to the same lines), regenerates the copy's docs/config.md as the
# page says, builds it with the repository's flags (-Werror) and checks
# what the page promises from the table alone:
#   - `--list-config` shows chip.clip.count, chip.clip.width, chip.clip.latency;
#   - a run's report has units.clip with ops and a utilisation above 0, and
#     its text summary names the unit;
#   - the suites that derive from the table or run the chip pass: units_table,
#     the chip suites (chip, chip_fp, chip_grid, chip_order, chip_reads,
#     chip_twolevel, memsys_chip), pktrec, modes, fidelity, config, reportcheck.
# The generated documents' figures and the README's examples are not run:
# the clip op adds time to every packet, so they are meant to differ.
# Exit 0 when all hold, 1 when one does not (its log named), 2 on bad use.
# Takes about a minute on two cores.
set -u
REPO=$(cd "$(dirname "$0")/.." && pwd)
WORK=$REPO/build-extend
SRC=$WORK/src
LOG=$WORK/log
JOBS=${JOBS:-2}
SCENES=${SAAR_SCENES:-$REPO/../shared/scenes}
SAARSIM_CACHE_DIR=off
export SAARSIM_CACHE_DIR

say() { printf 'extend-check: %s\n' "$*"; }
die() {
	printf 'extend-check: error: %s\n' "$*" >&2
	exit 2
}
fail() {
	printf 'extend-check: FAILED: %s\n' "$*" >&2
	exit 1
}

[ $# -eq 0 ] || die "usage: sh scripts/extend-check.sh (no arguments; JOBS and SAAR_SCENES from the environment)"
for tool in rsync patch make python3; do
	command -v "$tool" >/dev/null 2>&1 || die "$tool is needed"
done
case $SCENES in /*) ;; *) SCENES=$(pwd)/$SCENES ;; esac
mkdir -p "$SRC" "$LOG" || die "cannot make $WORK"
rm -f "$LOG"/*
. "$REPO/scripts/scratch-lib.sh"
scratch_link_shared "$WORK" "$SCENES"

python3 "$REPO/scripts/extend-doc.py" >"$LOG/doc.txt" 2>&1 ||
	fail "the page and the patch differ: $(cat "$LOG/doc.txt")"
scratch_sync "$REPO" "$SRC"
(cd "$SRC" && patch -p1 -s --no-backup-if-mismatch) <"$REPO/tests/extend/unit-clip.patch" \
	>"$LOG/patch.txt" 2>&1 || fail "the patch does not apply: $(cat "$LOG/patch.txt")"
say "applied tests/extend/unit-clip.patch; building the copy"
(cd "$SRC" && make -j"$JOBS" build/saarsim) >"$LOG/build1.txt" 2>&1 ||
	fail "the copy does not build (log: $LOG/build1.txt): $(grep -m 3 'error' "$LOG/build1.txt")"
"$SRC/build/saarsim" --config-doc >"$SRC/docs/config.md" || fail "--config-doc failed"
(cd "$SRC" && make -j"$JOBS" all build/saarsim-tests) >"$LOG/build.txt" 2>&1 ||
	fail "the copy does not build (log: $LOG/build.txt): $(grep -m 3 'error' "$LOG/build.txt")"

"$SRC/build/saarsim" --list-config >"$LOG/keys.txt" 2>&1 || fail "--list-config failed"
for k in count width latency; do
	grep -q "^chip\.clip\.$k " "$LOG/keys.txt" || fail "--list-config lacks chip.clip.$k"
done
"$SRC/build/saarsim" --size 64x64 --quiet --report "$LOG/r.json" >"$LOG/run.txt" 2>&1 ||
	fail "saarsim failed: $(cat "$LOG/run.txt")"
grep -q ' clip [0-9.]*%' "$LOG/run.txt" || fail "the text summary does not name the clip unit"
python3 - "$LOG/r.json" <<'EOF' || fail "the report's units.clip is missing or idle"
import json, sys
u = json.load(open(sys.argv[1]))["units"]["clip"]
sys.exit(0 if u["ops"] > 0 and u["utilisation"] > 0 else 1)
EOF
say "--list-config, the report and the summary show the unit; running the suites"
(cd "$SRC" && SAAR_BIN="$SRC/build" SAAR_SCENES="$SCENES" SAAR_ROOT="$SRC" \
	LSAN_OPTIONS="suppressions=$SRC/tests/lsan.supp:print_suppressions=0" \
	./build/saarsim-tests --jobs "$JOBS" \
	--filter '@(units_table|chip|chip_fp|chip_grid|chip_order|chip_reads|chip_twolevel|memsys_chip|pktrec|modes|fidelity|config|reportcheck)/*') \
	>"$LOG/tests.txt" 2>&1 || fail "the suites fail (log: $LOG/tests.txt): $(grep -m 5 FAIL "$LOG/tests.txt")"
say "$(grep 'Synthesis' "$LOG/tests.txt" | tail -n 1)"
say "the walk-through builds and runs as docs/extending.md shows it"
