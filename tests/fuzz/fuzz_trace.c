/* fuzz_trace.c: memory traces (mtr_open_read, every record, close); gzip
 * streams and, through zlib's transparent mode, plain bytes. */
#include "tests/fuzz/fuzz.h"
#include "traces/memtrace.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t n)
{
	static mtr_reader r; /* large: its block buffer */
	diag d = {{0}};
	int rc = mtr_open_read(&r, fz_file(data, n, ".gz"), &d);
	fz_one_line(rc, &d);
	if (rc)
		return 0;
	mtr_rec rec;
	while ((rc = mtr_read(&r, &rec, &d)) > 0)
		;
	fz_one_line(rc < 0 ? -1 : 0, &d);
	mtr_close_read(&r);
	return 0;
}
