# scripts/doc-section.sh: doc_section (and doc_load, doc_commit, doc_cpu for the
# lines that say when and on what), for scripts that write one marked
# part of a document (the bench-*.sh sections of docs/PERFORMANCE.md).
# Sourced, not run: . "$(dirname "$0")/doc-section.sh"
#
# doc_section NAME FILE DOC: the part of DOC from <!-- BEGIN NAME --> to
# <!-- END NAME --> is replaced by FILE (which holds both markers), or FILE
# is appended when DOC has no such part, or becomes DOC when there is none;
# DOC is replaced atomically (a temporary beside it, then mv).
doc_section() {
	if [ -f "$3" ]; then
		awk -v sec="$2" -v b="<!-- BEGIN $1 -->" -v e="<!-- END $1 -->" '
		BEGIN { while ((getline l < sec) > 0) s = s l "\n" }
		index($0, b) { printf "%s", s; skip = 1; done = 1; next }
		index($0, e) { skip = 0; next }
		!skip { print }
		END { if (!done) printf "\n%s", s }' "$3" >"$3.tmp.$$" &&
			mv -f "$3.tmp.$$" "$3"
	else
		cp "$2" "$3"
	fi
}

# doc_cpu: the host's processor model and widest vector extension ("AMD
# EPYC, AVX2"): host times and the ratios between two programs' times
# depend on both (docs/PERFORMANCE.md, "Targets 1 and 2: session 48").
doc_cpu() {
	_m=$(sed -n 's/^model name[[:space:]]*:[[:space:]]*//p' /proc/cpuinfo 2>/dev/null | head -n 1)
	_f=$(grep -m 1 '^flags' /proc/cpuinfo 2>/dev/null)
	case " $_f " in
	*" avx512f "*) _v=AVX-512 ;;
	*" avx2 "*) _v=AVX2 ;;
	*" avx "*) _v=AVX ;;
	*) _v=$(uname -m) ;;
	esac
	printf '%s, %s\n' "${_m:-unknown processor}" "$_v"
}

# doc_load: the load average's three figures ("?" where it cannot be read).
doc_load() {
	cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo "?"
}

# doc_check_line FILE SCENES REPORT KEY... -- ARGS...: appends to FILE the
# figures-check line (scripts/figures-check.py --emit; `make test` reruns
# it) of a saarsim run made with ARGS whose report is REPORT, the shared
# scenes folder SCENES written as $SCENES; nonzero when --emit fails.
# Scripts/ is found under ROOT, else the current folder.
doc_check_line() {
	_cl_file=$1 _cl_scenes=$2
	shift 2
	SAAR_SCENES=$_cl_scenes python3 "${ROOT:-.}/scripts/figures-check.py" --emit saarsim "$@" \
		>>"$_cl_file"
}

# doc_commit: HEAD's short hash, with " (plus uncommitted changes)" when a
# tracked file outside docs/ differs from it (the figures may not be
# HEAD's; a document, such as another section just written, moves none).
doc_commit() {
	_dc=$(git rev-parse --short HEAD)
	[ -z "$(git status --porcelain --untracked-files=no -- . ':!docs')" ] ||
		_dc="$_dc (plus uncommitted changes)"
	printf '%s\n' "$_dc"
}
