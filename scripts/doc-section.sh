# scripts/doc-section.sh: doc_section, for scripts that write one marked
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
