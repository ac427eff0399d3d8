#!/bin/sh
# mutate.sh: the standing mutation tests (`make mutate`).
#
# Every tests/mutants/*.patch is a unified diff (`patch -p1`) that plants
# one named mistake, with a header saying which mistake it models and which
# tests were written to catch it:
#
#   # Mutant: trav-no-far-push
#   # Models: Packet traversal never pushes the far child ...
#   # Caught-by: traverse/far_child_is_pushed_and_visited
#   # Caught-by: ...            (one line per test, Criterion's suite/name)
#
# The script copies the repository's files (tracked and new, not ignored)
# into a scratch folder, build-mutate/src (MUTATE_DIR), builds it and runs
# every named test there on the unmutated copy (each must exist and pass),
# then the whole suite (MUTATE_FULL=0 skips that). Then, one mutant at a
# time: apply it to the copy, rebuild, run each named test alone; the
# mutant is caught only if every one of its named tests fails (a failure
# of some other test does not count). The copy is restored from the
# repository after each mutant. The real tree is never patched.
#
# Results: a table under "## Mutation tests" in docs/TESTING.md (the section
# is replaced, the rest of the file kept; the file is made if missing) and
# on stdout. Exit 0 when every mutant is caught, 1 otherwise, 2 when the
# unmutated copy does not build or pass.
#
# Environment: MUTATE_DIR (scratch folder), MUTATE_JOBS (make -j, 2),
# MUTATE_FULL (1: run the whole suite on the unmutated copy), MUTATE_ONLY
# (a pattern: only the mutants whose file names match it; the document is
# then not written), MUTATE_TIMEOUT (seconds per test run, 900),
# SAAR_SCENES (the shared scenes, default ../shared/scenes).
set -u

REPO=$(cd "$(dirname "$0")/.." && pwd)
WORK=${MUTATE_DIR:-$REPO/build-mutate}
SRC=$WORK/src
LOGS=$WORK/logs
JOBS=${MUTATE_JOBS:-2}
FULL=${MUTATE_FULL:-1}
ONLY=${MUTATE_ONLY:-}
TIMEOUT=${MUTATE_TIMEOUT:-900}
SCENES=${SAAR_SCENES:-$REPO/../shared/scenes}
DOC=$REPO/docs/TESTING.md
T0=$(date +%s)

say() { printf 'mutate: %s\n' "$*"; }
die() {
	printf 'mutate: error: %s\n' "$*" >&2
	exit 2
}

for tool in rsync patch make timeout; do
	command -v "$tool" >/dev/null 2>&1 || die "$tool is needed"
done
case $SCENES in /*) ;; *) SCENES=$(pwd)/$SCENES ;; esac
. "$REPO/scripts/scratch-lib.sh"
scratch_link_shared "$WORK" "$SCENES"

sync_copy() {
	scratch_sync "$REPO" "$SRC"
}

build() { # log file
	(cd "$SRC" && make -j"$JOBS" all build/saarsim-tests) >"$1" 2>&1
}

# Runs test $1 alone in the copy, output into $2. Prints "pass", "fail",
# "timeout" or "missing" (no test of that name ran).
run_test() {
	(cd "$SRC" && SAAR_BIN="$SRC/build" SAAR_SCENES="$SCENES" \
	    LSAN_OPTIONS="suppressions=$SRC/tests/lsan.supp:print_suppressions=0" \
	    timeout "$TIMEOUT" ./build/saarsim-tests --jobs 1 --filter "$1") >"$2" 2>&1
	rc=$?
	if [ "$rc" -eq 124 ]; then
		echo timeout
		return
	fi
	syn=$(grep 'Synthesis: Tested:' "$2" | tail -n 1)
	tested=$(printf '%s\n' "$syn" | sed -n 's/.*Tested: \([0-9]*\).*/\1/p')
	passing=$(printf '%s\n' "$syn" | sed -n 's/.*Passing: \([0-9]*\).*/\1/p')
	if [ "${tested:-0}" != 1 ]; then
		echo missing
	elif [ "$rc" -eq 0 ] && [ "$passing" = 1 ]; then
		echo pass
	else
		echo fail
	fi
}

field() { # file key: the header lines "# key: value", one value a line
	sed -n "s/^# $2: *//p" "$1"
}

mkdir -p "$SRC" "$LOGS" || die "cannot make $WORK"
rm -f "$LOGS"/*
# The mutants to run (MUTATE_ONLY: those whose file names match it).
selected() { # mutant file
	[ -f "$1" ] && { [ -z "$ONLY" ] || basename "$1" | grep -q -- "$ONLY"; }
}
n=0
for m in "$REPO"/tests/mutants/*.patch; do
	selected "$m" && n=$((n + 1))
done
[ "$n" -gt 0 ] || die "no mutants in tests/mutants/${ONLY:+ matching MUTATE_ONLY=$ONLY}"

# ---- the unmutated copy ----
say "copying the repository into $SRC"
sync_copy
say "building the unmutated copy"
build "$LOGS/build-unmutated.log" || die "the unmutated copy does not build: $LOGS/build-unmutated.log"
NAMED=$(for m in "$REPO"/tests/mutants/*.patch; do
	selected "$m" && field "$m" Caught-by
done | sort -u)
for t in $NAMED; do
	st=$(run_test "$t" "$LOGS/unmutated-$(echo "$t" | tr / -).log")
	[ "$st" = pass ] || die "test $t is $st on the unmutated copy ($LOGS/unmutated-$(echo "$t" | tr / -).log)"
done
say "$(echo "$NAMED" | wc -l) named tests pass on the unmutated copy"
if [ "$FULL" = 1 ]; then
	say "running the whole suite on the unmutated copy"
	(cd "$SRC" && make test SAAR_SCENES="$SCENES") >"$LOGS/suite-unmutated.log" 2>&1 ||
	    die "the suite fails on the unmutated copy: $LOGS/suite-unmutated.log"
	say "$(grep 'Synthesis:' "$LOGS/suite-unmutated.log" | tail -n 1 | sed 's/^\[====\] //')"
fi

# ---- one mutant at a time ----
ROWS=$WORK/rows.md
: >"$ROWS"
total=0
caught=0
for m in "$REPO"/tests/mutants/*.patch; do
	selected "$m" || continue
	id=$(basename "$m" .patch)
	total=$((total + 1))
	models=$(field "$m" Models)
	tests=$(field "$m" Caught-by)
	verdict=yes
	detail=
	if [ -z "$tests" ]; then
		verdict=no
		detail="names no test"
	elif ! (cd "$SRC" && patch -p1 -F0 -s --no-backup-if-mismatch) <"$m" >"$LOGS/$id.patch.log" 2>&1; then
		verdict=no
		detail="does not apply"
	elif ! build "$LOGS/$id.build.log"; then
		verdict=no
		detail="does not build"
	else
		for t in $tests; do
			st=$(run_test "$t" "$LOGS/$id-$(echo "$t" | tr / -).log")
			case $st in
			fail) ;;
			timeout) detail="$detail $t timed out;" ;;
			*)
				verdict=no
				detail="$detail $t: $st;"
				;;
			esac
		done
	fi
	sync_copy
	[ "$verdict" = yes ] && caught=$((caught + 1))
	say "$id: caught $verdict${detail:+ ($detail)}"
	# shellcheck disable=SC2016 # Markdown backquotes
	tl=$(printf '%s\n' "$tests" | sed 's/.*/`&`/' | paste -sd, - | sed 's/,/, /g')
	# shellcheck disable=SC2016
	printf '| `%s` | %s | %s | %s%s |\n' "$id" "$models" "$tl" "$verdict" \
	    "${detail:+ ($detail)}" >>"$ROWS"
done
# leave the copy's objects unmutated for the next run
build "$LOGS/build-final.log" || die "the restored copy does not build: $LOGS/build-final.log"

T1=$(date +%s)
secs=$((T1 - T0))
took=$(printf '%dm%02ds' $((secs / 60)) $((secs % 60)))
say "$caught of $total mutants caught ($took)"

# ---- docs/TESTING.md ----
if [ -z "$ONLY" ]; then
	rev=$(git -C "$REPO" rev-parse --short HEAD 2>/dev/null || echo unknown)
	[ -n "$(git -C "$REPO" status --porcelain -- . ':!docs/TESTING.md' 2>/dev/null)" ] &&
	    rev="$rev with uncommitted changes"
	full_note="every named test passed alone on the unmutated copy"
	[ "$FULL" = 1 ] && full_note="$full_note, and so did the whole suite"
	sect=$WORK/section.md
	{
		cat <<'EOF'
## Mutation tests

`make mutate` (scripts/mutate.sh) plants one known mistake at a time in a
scratch copy of the repository (build-mutate/src; the tree itself is never
patched), rebuilds it and runs the tests written to catch that mistake. A
mutant is a patch in tests/mutants/ whose header says what it models and
names its tests (`# Caught-by: suite/name`, one a line); it counts as
caught only when every named test fails on it, each run alone: a failure
of any other test does not count. Before the mutants, the named tests must
pass on the unmutated copy. `make mutate` fails unless every mutant is
caught; it is not part of `make test`. To add a mutant: write the test,
check that it fails on the mistake, then add the patch (`diff -u` with
paths a/FILE and b/FILE) under its header. `MUTATE_ONLY=pattern make
mutate` runs the matching mutants only (and leaves this page alone).

The build follows the host's vector width (`ARCH`, docs/kernel-ref.md), so
code under `#if __AVX512F__`, `__AVX__` or `__SSE__` is compiled on some
hosts only. A mutant of such code plants its mistake in every width's
branch, or it is caught on one kind of host and not compiled on the
other: mutants 98, 100 and 102, written on the AMD (AVX2) host, changed
the AVX branch alone, and session 59's run on the Intel (AVX-512) host
found them uncaught; they now change every branch. For the same reason a
mistake may show in a test on one host only: mutant 85 (the SLP
vectorizer left on) fails the stress suite on the AMD host and not on the
Intel one, so it names only the test written for it.

EOF
		echo "Last run: $(date -u +%Y-%m-%d), $rev: $caught of $total mutants caught,"
		echo "$full_note; $took on $JOBS jobs."
		echo
		echo '| Mutant | What it models | Tests that must catch it | Caught |'
		echo '|---|---|---|---|'
		cat "$ROWS"
	} >"$sect"
	if [ -f "$DOC" ] && grep -q '^## Mutation tests$' "$DOC"; then
		SECT=$sect awk '
			/^## Mutation tests$/ {
				while ((getline l < ENVIRON["SECT"]) > 0)
					print l
				skip = 1
				next
			}
			skip && /^## / { skip = 0; print "" }
			!skip { print }
		' "$DOC" >"$DOC.tmp" && mv "$DOC.tmp" "$DOC"
	elif [ -f "$DOC" ]; then
		{ echo; cat "$sect"; } >>"$DOC"
	else
		{
			echo "# Testing"
			echo
			cat "$sect"
		} >"$DOC"
	fi
	say "results in docs/TESTING.md"
fi
[ "$caught" -eq "$total" ]
