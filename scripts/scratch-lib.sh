# scratch-lib.sh: the scratch copy of the repository that scripts/mutate.sh
# (make mutate) and scripts/extend-check.sh (make extend-check) build and
# test in, so the tree itself is never patched. Sourced after the caller
# defines die (message; exit 2).

# scratch_link_shared WORK SCENES: files in the repository name the shared
# scenes by a path relative to it (configs/drt-views.yaml:
# ../../shared/scenes/...); beside a copy in WORK/src, as beside the
# repository, ../shared is then the shared folder (the parent of SCENES).
scratch_link_shared() {
	mkdir -p "$1" || die "cannot make $1"
	if [ -d "$2" ] && [ ! -e "$1/shared" ]; then
		ln -s "$(cd "$2/.." && pwd)" "$1/shared" || die "cannot link $1/shared"
	fi
}

# scratch_sync REPO SRC: mirrors the repository's files as they are (changes
# not committed included) into SRC: changed files only (-c: by content, so a
# file a mutant or a patch touched is copied back and, with a fresh mtime,
# rebuilt); files git ignores (the build folders, the scratch folders among
# them) stay out and are kept in the copy.
scratch_sync() {
	rsync -rlc --delete --exclude=/.git --exclude='/build-*/' \
	    --filter=':- .gitignore' "$1/" "$2/" ||
	    die "cannot copy the repository into $2"
}
