# scripts/doc-lib.sh: the common start of the scripts that run saarsim and
# write a document (scripts/drt.sh, scripts/dynamic.sh). Sourced, not run:
#
#   . "$(dirname "$0")/doc-lib.sh"
#   doc_init NAME "${1:-build}"
#
# Sets ROOT (the repository), B (the build folder, made absolute) and
# SAARSIM (default B/saarsim), and checks that saarsim, gnuplot and python3
# are there; say and bad print "NAME: ..." on stderr (bad exits 2).
DOC_NAME=doc
say() { printf '%s: %s\n' "$DOC_NAME" "$*" >&2; }
bad() {
	say "$*"
	exit 2
}
doc_init() {
	DOC_NAME=$1
	ROOT=$(cd "$(dirname "$0")/.." && pwd)
	B=$2
	case $B in /*) ;; *) B=$ROOT/$B ;; esac
	SAARSIM=${SAARSIM:-$B/saarsim}
	[ -f "$SAARSIM" ] && [ -x "$SAARSIM" ] || bad "$SAARSIM not found; run 'make' first"
	command -v gnuplot >/dev/null 2>&1 || bad "gnuplot not found (sh scripts/install-deps.sh)"
	command -v python3 >/dev/null 2>&1 || bad "python3 not found (sh scripts/install-deps.sh)"
}
