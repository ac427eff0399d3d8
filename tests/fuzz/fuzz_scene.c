/* fuzz_scene.c: scene files through saarsim's pre-scans and Assimp, in
 * process (scene_import_inproc: what the import's child process runs;
 * the child's limits are not in play here, so a hang or a bomb shows as
 * libFuzzer's timeout or memory limit). Built once per format: FUZZ_EXT is
 * ".obj" or ".ply" (the importer is picked by the extension). */
#include "kernel-ref/scene.h"
#include "tests/fuzz/fuzz.h"

#ifndef FUZZ_EXT
#error "define FUZZ_EXT"
#endif

/* The import silences stderr around Assimp and libpng; in a fuzzer that
 * would swallow libFuzzer's own report of a crash or an allocation past
 * its limit (a finding once left an artifact and an empty log). */
int LLVMFuzzerInitialize(int *argc, char ***argv)
{
	diag_quiet_off();
	return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t n)
{
	scene s;
	diag d = {{0}};
	int rc = scene_import_inproc(&s, fz_file(data, n, FUZZ_EXT), NULL, NULL, &d);
	fz_one_line(rc, &d);
	if (rc == 0)
		scene_free(&s);
	return 0;
}
