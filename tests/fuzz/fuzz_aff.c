/* fuzz_aff.c: the AFF reader (aff_load), then the scene flattened and its
 * camera at two times (aff_flatten without textures, aff_view). */
#include "kernel-ref/aff.h"
#include "tests/fuzz/fuzz.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t n)
{
	const char *path = fz_file(data, n, ".aff");
	aff_scene a;
	diag d = {{0}};
	int rc = aff_load(&a, path, NULL, NULL, &d);
	fz_one_line(rc, &d);
	if (rc)
		return 0;
	for (int k = 0; k < 2; k++) {
		double t = k ? 7.25 : 0.0;
		scene s;
		view v;
		diag e = {{0}}, f = {{0}};
		int r = aff_flatten(&a, t, 0, &s, &e);
		fz_one_line(r, &e);
		if (!r)
			scene_free(&s);
		fz_one_line(aff_view(&a, t, &v, &f) < 0 ? -1 : 0, &f);
	}
	aff_free(&a);
	return 0;
}
