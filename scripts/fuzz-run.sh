#!/bin/sh
# fuzz-run.sh FZ_B SECONDS BUILD NAME...: runs each libFuzzer harness
# FZ_B/fuzz-NAME for SECONDS (make fuzz-smoke; docs/TESTING.md). Corpora
# live in FZ_B/corpus-NAME, seeded from tests/fuzz/seeds/NAME and from files
# the repository and the shared scenes already hold (never copied into the
# repository). Limits per input: 10 s, 2 GB resident, 1 GB in one malloc.
# Exit 1 on the first finding (its input is FZ_B/NAME-crash-* or similar).
set -eu
# No default world-cache folder (issue 36): these runs measure or compare
# builds, renders and sampled warming as they were, and write nothing into
# the user's home; a run that wants a cache names its own (--world-cache).
SAARSIM_CACHE_DIR=off
export SAARSIM_CACHE_DIR
FZ_B=$1
SECS=$2
BUILD=$3
shift 3
ROOT=$(cd "$(dirname "$0")/.." && pwd)
SCENES=${SAAR_SCENES:-$ROOT/../shared/scenes}
status=0
for name in "$@"; do
	corpus=$FZ_B/corpus-$name
	mkdir -p "$corpus"
	if [ -d "$ROOT/tests/fuzz/seeds/$name" ]; then
		cp "$ROOT/tests/fuzz/seeds/$name"/* "$corpus"/
	fi
	case $name in
	config) cp "$ROOT"/configs/*.yaml "$corpus"/ ;;
	views) [ -f "$SCENES/views.yaml" ] && cp "$SCENES/views.yaml" "$corpus"/ ;;
	obj) for f in "$SCENES"/cornell_box/*.obj "$SCENES"/utah_teapot/*.obj; do
		[ -f "$f" ] && cp "$f" "$corpus"/
	done ;;
	ply) # no PLY among the shared scenes: two small ones made here, one
		# ASCII triangle and one binary quad (the repository holds no
		# mesh files; the fuzzer's findings are test cases in
		# tests/test_scene_import.c)
		hdr='ply\nformat %s 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\nelement face %d\nproperty list uchar int vertex_indices\nend_header\n'
		# shellcheck disable=SC2059
		{ printf "$hdr" ascii 3 1; printf '0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n'; } >"$corpus/tri-ascii.ply"
		{ printf "$hdr" binary_little_endian 4 2
		  python3 -c 'import struct,sys; sys.stdout.buffer.write(b"".join(struct.pack("<3f",*p) for p in [(0,0,0),(1,0,0),(0,1,0),(1,1,0)]) + struct.pack("<B3i",3,0,1,2) + struct.pack("<B3i",3,1,3,2))'
		} >"$corpus/quad-binary.ply" ;;
	aff) for f in "$SCENES"/bart_robots_aff/aff/l_heel.aff "$SCENES"/bart_robots_aff/aff/color1.aff \
		"$SCENES"/bart_robots_aff/aff/Robot5.aff; do
		[ -f "$f" ] && cp "$f" "$corpus"/
	done ;;
	trace) [ -f "$corpus/seed.gz" ] || "$BUILD/saarsim" --size 16x16 --no-check \
		--trace-mem "$corpus/seed.gz" >/dev/null ;;
	esac
	echo "fuzz-$name: ${SECS} s from $(ls "$corpus" | wc -l) corpus files"
	# leaks inside Assimp, Criterion and OpenImageIO are suppressed as in
	# make SANITIZE=1 test (tests/lsan.supp says which and why)
	if ! LSAN_OPTIONS="suppressions=$ROOT/tests/lsan.supp:print_suppressions=0" \
		"$FZ_B/fuzz-$name" -max_total_time="$SECS" -timeout=10 -rss_limit_mb=2048 \
		-malloc_limit_mb=1024 -print_final_stats=1 \
		-artifact_prefix="$FZ_B/$name-" "$corpus" >"$FZ_B/fuzz-$name.log" 2>&1; then
		echo "fuzz-$name: FOUND a failing input; see $FZ_B/fuzz-$name.log" >&2
		tail -30 "$FZ_B/fuzz-$name.log" >&2
		status=1
		break
	fi
	grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$FZ_B/fuzz-$name.log" |
		sed "s/^/fuzz-$name: /"
done
exit $status
