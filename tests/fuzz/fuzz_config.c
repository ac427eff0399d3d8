/* fuzz_config.c: the YAML hardware config (cfg_load_at, then memcfg_validate:
 * every check a run makes before any scene, each error named by where its
 * value came from). */
#include "sim/config.h"
#include "sim/memconfig.h"
#include "tests/fuzz/fuzz.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t n)
{
	static saar_config c;
	static cfg_origin o; /* large: not on the stack */
	diag d = {{0}};
	int rc = cfg_load_at(&c, fz_file(data, n, ".yaml"), &o, &d);
	fz_one_line(rc, &d);
	if (rc == 0) {
		rc = memcfg_validate(&c, &o, &d);
		fz_one_line(rc, &d);
	}
	return 0;
}
