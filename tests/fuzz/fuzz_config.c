/* fuzz_config.c: the YAML hardware config (cfg_load, then cfg_validate). */
#include "sim/config.h"
#include "tests/fuzz/fuzz.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t n)
{
	saar_config c;
	diag d = {{0}};
	int rc = cfg_load(&c, fz_file(data, n, ".yaml"), &d);
	fz_one_line(rc, &d);
	if (rc == 0) {
		rc = cfg_validate(&c, &d);
		fz_one_line(rc, &d);
	}
	return 0;
}
