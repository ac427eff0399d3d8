/*
 * test_memtrace.c: memory traces round-trip; truncated, corrupt and foreign
 * files are rejected with a clear message, never a crash; saarsim-replay
 * runs a trace and fails with one line and exit 2 on bad input.
 */
#include <string.h>

#include "memtrace.h"
#include "testutil.h"

static void write_trace(const char *path, uint64_t n)
{
	mtr_writer *w = malloc(sizeof *w);
	diag d;
	cr_assert_eq(mtr_open_write(w, path, &d), 0, "%s", d.msg);
	for (uint64_t i = 0; i < n; i++) {
		mtr_rec r = {i / 3, 0x1000 + 8 * (i % 5000), (uint32_t)(8 + (i % 2) * 28),
		             (uint8_t)(i % 4), (uint8_t)(i % 97 == 0)};
		cr_assert_eq(mtr_write(w, &r, &d), 0);
	}
	cr_assert_eq(mtr_close_write(w, &d), 0, "%s", d.msg);
	free(w);
}

/* Reads everything; returns records read, or -1 with d filled. A corrupt
 * stream may deliver wrong records before its CRC fails at the end, so the
 * content is only checked when asked. */
static long long read_chk(const char *path, diag *d, int check)
{
	mtr_reader *r = malloc(sizeof *r);
	long long n = 0;
	if (mtr_open_read(r, path, d)) {
		free(r);
		return -1;
	}
	mtr_rec x;
	int rc;
	while ((rc = mtr_read(r, &x, d)) == 1) {
		if (!check) {
			n++;
			continue;
		}
		cr_assert_eq(x.cycle, (uint64_t)n / 3);
		cr_assert_eq(x.addr, 0x1000 + 8 * ((uint64_t)n % 5000));
		cr_assert_eq(x.type, n % 4);
		cr_assert_eq(x.write, n % 97 == 0);
		n++;
	}
	mtr_close_read(r);
	free(r);
	return rc < 0 ? -1 : n;
}

static long long read_all(const char *path, diag *d)
{
	return read_chk(path, d, 0);
}

static size_t slurp(const char *path, unsigned char **buf)
{
	FILE *f = fopen(path, "rb");
	cr_assert(f);
	fseek(f, 0, SEEK_END);
	size_t n = (size_t)ftell(f);
	fseek(f, 0, SEEK_SET);
	*buf = malloc(n);
	cr_assert_eq(fread(*buf, 1, n, f), n);
	fclose(f);
	return n;
}

static void spit(const char *path, const unsigned char *b, size_t n)
{
	FILE *f = fopen(path, "wb");
	fwrite(b, 1, n, f);
	fclose(f);
}

Test(memtrace, round_trip)
{
	char dir[64], p[128];
	diag d;
	tu_tmpdir(dir, sizeof dir);
	snprintf(p, sizeof p, "%s/t.gz", dir);
	write_trace(p, 100000);
	cr_assert_eq(read_chk(p, &d, 1), 100000, "%s", d.msg);
	write_trace(p, 0);
	cr_assert_eq(read_chk(p, &d, 1), 0, "%s", d.msg);
}

Test(memtrace, truncated_and_corrupt)
{
	char dir[64], p[128], q[128];
	diag d;
	tu_tmpdir(dir, sizeof dir);
	snprintf(p, sizeof p, "%s/t.gz", dir);
	snprintf(q, sizeof q, "%s/bad.gz", dir);
	write_trace(p, 50000);
	unsigned char *b;
	size_t n = slurp(p, &b);
	/* cut at many places: every one is an error, none a crash */
	for (size_t cut = 0; cut < n; cut += n / 37 + 1) {
		spit(q, b, cut);
		cr_assert_eq(read_all(q, &d), -1, "cut at %zu accepted", cut);
		cr_assert(strstr(d.msg, q), "%s", d.msg);
	}
	spit(q, b, n - 4); /* the gzip trailer gone */
	cr_assert_eq(read_all(q, &d), -1);
	cr_assert(strstr(d.msg, "truncated"), "%s", d.msg);
	/* flipped bytes in the compressed data */
	for (size_t at = 20; at < n - 8; at += n / 23 + 1) {
		unsigned char *c = malloc(n);
		memcpy(c, b, n);
		c[at] ^= 0x5a;
		spit(q, c, n);
		cr_assert_eq(read_all(q, &d), -1, "flip at %zu accepted", at);
		free(c);
	}
	free(b);
	/* not a trace at all */
	tu_write(q, sizeof q, dir, "plain.gz",
	         "hello, this is not a trace at all; not even gzip\n");
	cr_assert_eq(read_all(q, &d), -1);
	cr_assert(strstr(d.msg, "magic"), "%s", d.msg);
	snprintf(q, sizeof q, "%s/missing.gz", dir);
	cr_assert_eq(read_all(q, &d), -1);
	cr_assert(strstr(d.msg, "cannot open"), "%s", d.msg);
}

Test(memtrace, replay_tool)
{
	char dir[64], p[128], cmd[512];
	tu_tmpdir(dir, sizeof dir);
	snprintf(p, sizeof p, "%s/t.gz", dir);
	write_trace(p, 20000);
	snprintf(cmd, sizeof cmd, "%s/saarsim-replay %s > %s/out.txt", tu_bin_dir(), p, dir);
	cr_assert_eq(tu_run(cmd), 0, "%s", cmd);
	snprintf(cmd, sizeof cmd,
	         "%s/saarsim-replay --set memory.vma.enabled=true --set memory.sdram.mb=1 --timing "
	         "%s > /dev/null",
	         tu_bin_dir(), p);
	cr_assert_eq(tu_run(cmd), 0, "%s", cmd);
	snprintf(cmd, sizeof cmd, "%s/saarsim-replay %s/nope.gz 2>%s/err.txt", tu_bin_dir(), dir,
	         dir);
	cr_assert_eq(tu_run(cmd), 2);
	snprintf(cmd, sizeof cmd, "%s/saarsim-replay --set memory.l1.kd.ways=0 %s 2>/dev/null",
	         tu_bin_dir(), p);
	cr_assert_eq(tu_run(cmd), 2);
	snprintf(cmd, sizeof cmd, "test $(wc -l < %s/err.txt) -eq 1", dir);
	cr_assert_eq(tu_run(cmd), 0, "one line of error");
}
