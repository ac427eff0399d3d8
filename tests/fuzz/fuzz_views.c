/* fuzz_views.c: the views file (view_list, then view_load of each name). */
#include "kernel-ref/view.h"
#include "tests/fuzz/fuzz.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t n)
{
	const char *path = fz_file(data, n, ".yaml");
	char names[16][VIEW_NAME_MAX];
	diag d = {{0}};
	int nv = view_list(path, names, 16, &d);
	fz_one_line(nv < 0 ? -1 : 0, &d);
	for (int i = 0; i < nv; i++) {
		view v;
		diag e = {{0}};
		fz_one_line(view_load(&v, path, names[i], &e), &e);
	}
	return 0;
}
