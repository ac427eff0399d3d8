/*
 * test_memtrace.c: memory traces round-trip (v2, written; v1, still read);
 * truncated, corrupt and foreign files are rejected with a clear message,
 * never a crash, also when the gzip layer is intact and only the records are
 * bad; saarsim-replay runs a trace and fails with one line and exit 2 on bad
 * input.
 */
#include <string.h>
#include <zlib.h>

#include "mem/cache.h"
#include "tests/testutil.h"
#include "traces/memtrace.h"

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

/* Edge values: every type and flag, cycle steps 0..6, large and backward
 * jumps, addresses near 0 and UINT64_MAX, bytes 0, 4, 8, 36 and the extremes. */
static mtr_rec edge_rec(uint64_t i)
{
	static const uint64_t addrs[] = {0,          1,    0x1000, UINT64_MAX, UINT64_MAX - 7,
	                                 1ull << 63, 12345};
	static const uint32_t bytes[] = {8, 36, 4, 0, 1, MTR_MAX_BYTES, 128, 12};
	uint64_t cyc = i % 11 == 10 ? UINT64_MAX - i : i % 13 == 5 ? i / 2 : i * 3 + i % 7;
	mtr_rec r = {cyc, addrs[i % 7] + (i % 3 ? i * 40 : 0), bytes[i % 8], (uint8_t)(i % 4),
	             (uint8_t)(i / 4 % 2)};
	return r;
}

Test(memtrace, round_trip_edges_and_blocks)
{
	char dir[64], p[128];
	diag d;
	tu_tmpdir(dir, sizeof dir);
	snprintf(p, sizeof p, "%s/e.gz", dir);
	const uint64_t n = 3 * MTR_BLOCK_RECS + 17;
	mtr_writer *w = malloc(sizeof *w);
	cr_assert_eq(mtr_open_write(w, p, &d), 0, "%s", d.msg);
	for (uint64_t i = 0; i < n; i++) {
		mtr_rec r = edge_rec(i);
		cr_assert_eq(mtr_write(w, &r, &d), 0, "%s", d.msg);
	}
	mtr_rec bad = {0, 0, 8, 4, 0};
	cr_assert_eq(mtr_write(w, &bad, &d), -1, "type 4 accepted");
	cr_assert_eq(mtr_close_write(w, &d), 0, "%s", d.msg);
	free(w);
	/* mtr_read for a while, then the rest through mtr_read_block */
	mtr_reader *r = malloc(sizeof *r);
	cr_assert_eq(mtr_open_read(r, p, &d), 0, "%s", d.msg);
	uint64_t i = 0;
	mtr_rec x;
	for (; i < 1000; i++) {
		cr_assert_eq(mtr_read(r, &x, &d), 1, "%s", d.msg);
		mtr_rec e = edge_rec(i);
		cr_assert(x.cycle == e.cycle && x.addr == e.addr && x.bytes == e.bytes &&
		              x.type == e.type && x.write == e.write,
		          "record %llu differs", (unsigned long long)i);
	}
	const mtr_rec *blk;
	int k;
	while ((k = mtr_read_block(r, &blk, &d)) > 0)
		for (int j = 0; j < k; j++, i++) {
			mtr_rec e = edge_rec(i);
			cr_assert(blk[j].cycle == e.cycle && blk[j].addr == e.addr &&
			              blk[j].bytes == e.bytes && blk[j].type == e.type &&
			              blk[j].write == e.write,
			          "record %llu differs", (unsigned long long)i);
		}
	cr_assert_eq(k, 0, "%s", d.msg);
	cr_assert_eq(i, n);
	cr_assert_eq(mtr_read(r, &x, &d), 0, "reads past the end");
	mtr_close_read(r);
	free(r);
}

/* A gzip file with exactly these uncompressed bytes (valid CRC). */
static void gz_bytes(const char *path, const unsigned char *b, size_t n)
{
	gzFile g = gzopen(path, "wb1");
	cr_assert(g);
	if (n)
		cr_assert_eq(gzwrite(g, b, (unsigned)n), (int)n);
	cr_assert_eq(gzclose(g), Z_OK);
}

static size_t gunzip(const char *path, unsigned char **buf)
{
	gzFile g = gzopen(path, "rb");
	cr_assert(g);
	size_t cap = 1 << 16, n = 0;
	*buf = malloc(cap);
	int got;
	while ((got = gzread(g, *buf + n, (unsigned)(cap - n))) > 0) {
		n += (size_t)got;
		if (n == cap)
			*buf = realloc(*buf, cap *= 2);
	}
	cr_assert_eq(got, 0);
	gzclose(g);
	return n;
}

static void le32(unsigned char *p, uint32_t v)
{
	for (int i = 0; i < 4; i++)
		p[i] = (unsigned char)(v >> (8 * i));
}

Test(memtrace, v2_bad_records_under_a_good_crc)
{
	char dir[64], p[128], q[128];
	diag d;
	tu_tmpdir(dir, sizeof dir);
	snprintf(p, sizeof p, "%s/t.gz", dir);
	snprintf(q, sizeof q, "%s/bad.gz", dir);
	write_trace(p, 5000); /* 2 blocks: 4096 + 904 records */
	unsigned char *b, *c;
	size_t n = gunzip(p, &b);
	c = malloc(n + 64);
	uint32_t n1 = b[36] | b[37] << 8 | b[38] << 16 | (uint32_t)b[39] << 24; /* block 1 bytes */
	size_t blk2 = 32 + 8 + n1, endb = n - 16;
	struct {
		const char *what, *msg;
		size_t at;
		uint32_t val;
	} cases[] = {
	    {"too many records", "bad block header", 32, MTR_BLOCK_RECS + 1},
	    {"payload too long", "bad block header", 36, MTR_BLOCK_RECS * MTR_REC_MAX + 1},
	    {"payload one short", "bad record", 36, 0},
	    {"payload too short", "bad record", 36, 4096 * 2},
	    {"records beyond the payload", "bad record", blk2, 905},
	    {"end count", "counts", endb + 8, 4999},
	    {"end block size", "bad block header", endb + 4, 9},
	};
	for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
		memcpy(c, b, n);
		uint32_t v = cases[i].val;
		if (!strcmp(cases[i].what, "payload one short"))
			v = n1 - 1;
		le32(c + cases[i].at, v);
		gz_bytes(q, c, n);
		cr_assert_eq(read_all(q, &d), -1, "%s accepted", cases[i].what);
		cr_assert(strstr(d.msg, cases[i].msg) && strstr(d.msg, q), "%s: %s", cases[i].what,
		          d.msg);
	}
	/* a varint longer than 10 bytes */
	memcpy(c, b, n);
	memset(c + 32 + 8 + 1, 0xFF, 12);
	gz_bytes(q, c, n);
	cr_assert_eq(read_all(q, &d), -1);
	cr_assert(strstr(d.msg, "bad record"), "%s", d.msg);
	/* data after the end block; the end block missing; cut mid-block */
	memcpy(c, b, n);
	c[n] = 0;
	gz_bytes(q, c, n + 1);
	cr_assert_eq(read_all(q, &d), -1);
	cr_assert(strstr(d.msg, "after the end"), "%s", d.msg);
	gz_bytes(q, b, endb);
	cr_assert_eq(read_all(q, &d), -1);
	cr_assert(strstr(d.msg, "truncated"), "%s", d.msg);
	for (size_t cut = 33; cut < n; cut += 997) {
		gz_bytes(q, b, cut);
		cr_assert_eq(read_all(q, &d), -1, "cut at %zu accepted", cut);
		cr_assert(strstr(d.msg, "truncated"), "cut at %zu: %s", cut, d.msg);
	}
	/* random damage under a valid CRC: an error or some records, never a
	 * crash or a read out of bounds (run under make SANITIZE=1 test too) */
	uint32_t seed = 12345;
	for (int it = 0; it < 300; it++) {
		memcpy(c, b, n);
		for (int k = 0; k < 1 + it % 4; k++) {
			seed = seed * 1664525u + 1013904223u;
			size_t at = 32 + (seed >> 8) % (n - 32);
			seed = seed * 1664525u + 1013904223u;
			c[at] ^= (unsigned char)(1 + (seed >> 24) % 255);
		}
		gz_bytes(q, c, n);
		long long got = read_all(q, &d);
		cr_assert(got == -1 || got == 5000, "damage %d read %lld records", it, got);
	}
	free(b);
	free(c);
}

Test(memtrace, reads_version_1)
{
	char dir[64], p[128];
	diag d;
	tu_tmpdir(dir, sizeof dir);
	snprintf(p, sizeof p, "%s/v1.gz", dir);
	const uint64_t n = 10000;
	size_t len = 32 + (n + 1) * 24;
	unsigned char *b = calloc(1, len);
	memcpy(b, "SAARMTRC", 8);
	le32(b + 8, 1);
	le32(b + 12, 24);
	le32(b + 16, MTR_FIELDS);
	for (uint64_t i = 0; i <= n; i++) {
		unsigned char *q = b + 32 + i * 24;
		mtr_rec r = {i / 3, 0x1000 + 8 * (i % 5000), (uint32_t)(8 + (i % 2) * 28),
		             (uint8_t)(i % 4), (uint8_t)(i % 97 == 0)};
		if (i == n)
			r = (mtr_rec){UINT64_MAX, n, 0, 0xFF, 0};
		le32(q, (uint32_t)r.cycle);
		le32(q + 4, (uint32_t)(r.cycle >> 32));
		le32(q + 8, (uint32_t)r.addr);
		le32(q + 12, (uint32_t)(r.addr >> 32));
		le32(q + 16, r.bytes);
		q[20] = r.type;
		q[21] = r.write;
	}
	gz_bytes(p, b, len);
	cr_assert_eq(read_chk(p, &d, 1), (long long)n, "%s", d.msg);
	gz_bytes(p, b, len - 24); /* no end record */
	cr_assert_eq(read_all(p, &d), -1);
	cr_assert(strstr(d.msg, "truncated"), "%s", d.msg);
	b[32 + 24 * 77 + 20] = 9; /* a bad type */
	gz_bytes(p, b, len);
	cr_assert_eq(read_all(p, &d), -1);
	cr_assert(strstr(d.msg, "bad record 77"), "%s", d.msg);
	le32(b + 8, 3);
	gz_bytes(p, b, len);
	cr_assert_eq(read_all(p, &d), -1);
	cr_assert(strstr(d.msg, "version 3"), "%s", d.msg);
	free(b);
}

/* The replay's inline hit path changes exactly what cache_lookup does:
 * two caches fed the same lines, one through cache_try_hit first, end with
 * equal tags, stamps and counters (power-of-two and other set counts, both
 * hashes). */
Test(memtrace, replay_hit_path_equals_lookup)
{
	cache_params ps[] = {{2048 * 32, 4, 8, 4, 1, 1, CACHE_HASH_NONE, NULL},
	                     {711 * 4 * 36, 4, 36, 4, 1, 1, CACHE_HASH_NONE, NULL},
	                     {64 * 2 * 16, 2, 16, 4, 1, 1, CACHE_HASH_XOR, NULL}};
	for (size_t k = 0; k < sizeof ps / sizeof ps[0]; k++) {
		cache a, b;
		diag d;
		cr_assert_eq(cache_init(&a, &ps[k], "a", &d), 0, "%s", d.msg);
		cr_assert_eq(cache_init(&b, &ps[k], "b", &d), 0, "%s", d.msg);
		uint32_t seed = 7;
		for (int i = 0; i < 200000; i++) {
			seed = seed * 1664525u + 1013904223u;
			uint64_t line = (seed >> 8) % (i % 3 ? 3000 : 300000);
			if (cache_lookup(&a, line, 8, NULL, NULL) != CACHE_HIT)
				cache_fill(&a, line, NULL);
			if (!cache_try_hit(&b, line, 8) &&
			    cache_lookup(&b, line, 8, NULL, NULL) != CACHE_HIT)
				cache_fill(&b, line, NULL);
		}
		size_t n = (size_t)a.nsets * a.p.ways;
		cr_assert(!memcmp(a.way, b.way, n * sizeof *a.way));
		cr_assert(!memcmp(&a.s, &b.s, sizeof a.s));
		cr_assert(a.s.hits > 0 && a.s.misses > 0);
		cache_free(&a);
		cache_free(&b);
	}
}

Test(memtrace, replay_tool)
{
	char dir[64], p[128], cmd[1024];
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
	/* a trace cut inside its first block (a whole gzip stream, its
	 * records short) fails after the caches (and the VMA, the timed
	 * hierarchy) are built: one line, exit 2, everything freed (under make
	 * SANITIZE=1 a leak report adds lines and changes the status) */
	snprintf(cmd, sizeof cmd, "gzip -dc %s | head -c 4000 | gzip > %s/cut.gz", p, dir);
	cr_assert_eq(tu_run(cmd), 0, "%s", cmd);
	const char *modes[] = {"", "--timing", "--set memory.vma.enabled=true",
	                       "--set memory.vma.enabled=true --timing"};
	for (int m = 0; m < 4; m++) {
		snprintf(cmd, sizeof cmd, "%s/saarsim-replay %s %s/cut.gz >/dev/null 2>%s/err.txt",
		         tu_bin_dir(), modes[m], dir, dir);
		cr_assert_eq(tu_run(cmd), 2, "%s", cmd);
		snprintf(cmd, sizeof cmd,
		         "test $(wc -l < %s/err.txt) -eq 1 && grep -q cut.gz %s/err.txt", dir, dir);
		cr_assert_eq(tu_run(cmd), 0, "one line naming the trace (%s)", modes[m]);
	}
	/* --json into a folder that does not exist is refused before the
	 * replay: one line, nothing on stdout (the whole replay ran and
	 * printed its figures, then the write failed with exit 2) */
	snprintf(cmd, sizeof cmd,
	         "%s/saarsim-replay --json %s/missing/r.json %s >%s/out.txt 2>%s/err.txt",
	         tu_bin_dir(), dir, p, dir, dir);
	cr_assert_eq(tu_run(cmd), 2, "%s", cmd);
	snprintf(cmd, sizeof cmd,
	         "test $(wc -l < %s/err.txt) -eq 1 && grep -q 'missing does not exist' %s/err.txt",
	         dir, dir);
	cr_assert_eq(tu_run(cmd), 0, "one line naming the folder");
	snprintf(cmd, sizeof cmd, "test ! -s %s/out.txt", dir);
	cr_assert_eq(tu_run(cmd), 0, "the replay ran before the output was refused");
	/* bad command lines: one line with the program's name (the usage
	 * came as a second line; --image-bytes took "", -1 and huge values) */
	const char *bad[] = {"--image-bytes '' %s",
	                     "--image-bytes -1 %s",
	                     "--image-bytes 99999999999999999999 %s",
	                     "--image-bytes 5 --image-bytes 6 %s", /* the second won */
	                     "--bogus %s",
	                     "%s %s",
	                     ""};
	for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
		char args[512];
		snprintf(args, sizeof args, bad[k], p, p);
		snprintf(cmd, sizeof cmd, "%s/saarsim-replay %s >/dev/null 2>%s/err.txt",
		         tu_bin_dir(), args, dir);
		cr_assert_eq(tu_run(cmd), 2, "%s", args);
		snprintf(
		    cmd, sizeof cmd,
		    "test $(wc -l < %s/err.txt) -eq 1 && grep -q '^saarsim-replay: ' %s/err.txt",
		    dir, dir);
		cr_assert_eq(tu_run(cmd), 0, "one line starting with the program's name: %s", args);
	}
}

/* Records that would make a replay run away: a request of gigabytes (a
 * replay walks it line by line; one such record took 85 s) is refused by
 * the writer and by both readers; a cycle beyond what the engine's ticks
 * hold (2^63 aborted on the engine's assert, 2^64-2 hung) is refused by the
 * timed replay with one line and exit 2, while a large but representable
 * cycle still replays. */
Test(memtrace, runaway_records_are_refused)
{
	char dir[64], p[128], cmd[512];
	diag d;
	tu_tmpdir(dir, sizeof dir);
	snprintf(p, sizeof p, "%s/t.gz", dir);
	mtr_writer *w = malloc(sizeof *w);
	cr_assert_eq(mtr_open_write(w, p, &d), 0, "%s", d.msg);
	mtr_rec big = {1, 0x1000, MTR_MAX_BYTES + 1, 0, 0};
	cr_assert_eq(mtr_write(w, &big, &d), -1, "a %u-byte request recorded", big.bytes);
	cr_assert(strstr(d.msg, "cannot record a request"), "%s", d.msg);
	big.bytes = MTR_MAX_BYTES;
	cr_assert_eq(mtr_write(w, &big, &d), 0, "%s", d.msg);
	cr_assert_eq(mtr_close_write(w, &d), 0, "%s", d.msg);
	free(w);
	cr_assert_eq(read_all(p, &d), 1, "%s", d.msg);

	/* v2: patch the one record's bytes varint up to MTR_MAX_BYTES + 1 (the
	 * same 4-byte varint length: 2^24 and 2^24 + 1 both take four bytes) */
	unsigned char *b;
	size_t n = gunzip(p, &b);
	unsigned char *last = b + n - 16 - 1; /* the record's last byte, before the end block */
	cr_assert_eq(*last, (MTR_MAX_BYTES >> 21) & 0x7F, "varint layout");
	cr_assert_eq(last[-3], 0x80, "varint layout");
	last[-3] = 0x81;
	gz_bytes(p, b, n);
	cr_assert_eq(read_all(p, &d), -1, "a v2 record over the cap read");
	cr_assert(strstr(d.msg, "asks for more than") && strstr(d.msg, p), "%s", d.msg);
	free(b);

	/* v1: 0xFFFFFFFF bytes */
	size_t len = 32 + 2 * 24;
	b = calloc(1, len);
	memcpy(b, "SAARMTRC", 8);
	le32(b + 8, 1);
	le32(b + 12, 24);
	le32(b + 16, MTR_FIELDS);
	le32(b + 32 + 16, 0xFFFFFFFFu);
	memset(b + 56, 0xFF, 8); /* the end record: cycle UINT64_MAX, type 0xFF, count 1 */
	le32(b + 64, 1);
	b[56 + 20] = 0xFF;
	gz_bytes(p, b, len);
	cr_assert_eq(read_all(p, &d), -1, "a v1 record over the cap read");
	cr_assert(strstr(d.msg, "record 0 asks for 4294967295 bytes"), "%s", d.msg);
	free(b);

	/* cycles: too far for the engine, and far but fine */
	const uint64_t cyc[] = {1ull << 63, UINT64_MAX - 1, 1000000000000ull};
	for (int i = 0; i < 3; i++) {
		w = malloc(sizeof *w);
		cr_assert_eq(mtr_open_write(w, p, &d), 0, "%s", d.msg);
		mtr_rec r = {5, 0x1000, 8, 1, 0};
		cr_assert_eq(mtr_write(w, &r, &d), 0);
		r.cycle = cyc[i];
		cr_assert_eq(mtr_write(w, &r, &d), 0);
		cr_assert_eq(mtr_close_write(w, &d), 0, "%s", d.msg);
		free(w);
		snprintf(cmd, sizeof cmd,
		         "timeout 60 %s/saarsim-replay --timing %s >/dev/null 2>%s/err.txt",
		         tu_bin_dir(), p, dir);
		int rc = tu_run(cmd);
		if (i < 2) {
			cr_assert_eq(rc, 2, "cycle %llu: exit %d", (unsigned long long)cyc[i], rc);
			snprintf(cmd, sizeof cmd,
			         "test $(wc -l < %s/err.txt) -eq 1 && grep -q 'record 2 (counting "
			         "from 1) is at cycle %llu' %s/err.txt",
			         dir, (unsigned long long)cyc[i], dir);
			cr_assert_eq(tu_run(cmd), 0, "one line naming the record (cycle %llu)",
			             (unsigned long long)cyc[i]);
		} else {
			cr_assert_eq(rc, 0, "cycle %llu: exit %d", (unsigned long long)cyc[i], rc);
		}
	}
}

/* saarsim-replay checks the config as saarsim does, with or without
 * --timing: the functional replay builds the L1s (and the VMA) only, yet
 * a bad SDRAM geometry, replacement name or stack is bad input all the
 * same (one line naming where the value came from, exit 2). Catches the
 * checks left to the timed hierarchy's builder (without --timing these
 * ran to exit 0, replacement bogus replayed as LRU). */
Test(memtrace, replay_checks_the_config_without_timing)
{
	char dir[64], p[128], cfgf[128], cmd[1024];
	tu_tmpdir(dir, sizeof dir);
	snprintf(p, sizeof p, "%s/t.gz", dir);
	write_trace(p, 2000);
	tu_write(cfgf, sizeof cfgf, dir, "banks.yaml", "memory:\n  sdram:\n    banks: 3\n");
	const char *bad[][2] = {
	    {"--set memory.sdram.banks=3", "--set: memory.sdram.banks"},
	    {"--set memory.sdram.row_bytes=100", "--set: memory.sdram.row_bytes"},
	    {"--set memory.l1.kd.replacement=bogus", "'bogus'"},
	    {"--set memory.levels=fixed,junk", "memory.levels 'fixed,junk'"},
	    {"--config %s", "banks.yaml:3:12: memory.sdram.banks"}};
	for (size_t k = 0; k < sizeof bad / sizeof *bad; k++) {
		char args[256];
		snprintf(args, sizeof args, bad[k][0], cfgf);
		for (int timing = 0; timing < 2; timing++) {
			snprintf(cmd, sizeof cmd, "%s/saarsim-replay %s %s %s >%s/out.txt 2>%s/err",
			         tu_bin_dir(), args, timing ? "--timing" : "", p, dir, dir);
			cr_assert_eq(tu_run(cmd), 2, "%s", cmd);
			tu_one_line(dir, "saarsim-replay", bad[k][1]);
		}
	}
}

/* saarsim-replay reads --config before every --set, wherever they stand
 * (as saarsim does), and refuses a second --config: the file was loaded
 * where it stood, undoing the --set before it, and a second file dropped
 * the first. Catches the file loaded in its place on the command line. */
Test(memtrace, replay_reads_the_config_first_and_once)
{
	char dir[64], p[128], a[128], cmd[1024];
	tu_tmpdir(dir, sizeof dir);
	snprintf(p, sizeof p, "%s/t.gz", dir);
	write_trace(p, 2000);
	tu_write(a, sizeof a, dir, "a.yaml", "memory.sdram.banks: 8\n");
	snprintf(cmd, sizeof cmd,
	         "%s/saarsim-replay --set memory.sdram.banks=3 --config %s %s >%s/out 2>%s/err",
	         tu_bin_dir(), a, p, dir, dir);
	cr_assert_eq(tu_run(cmd), 2, "%s", cmd);
	tu_one_line(dir, "saarsim-replay", "--set: memory.sdram.banks must be a power of two");
	snprintf(cmd, sizeof cmd, "%s/saarsim-replay --config %s --config %s %s >%s/out 2>%s/err",
	         tu_bin_dir(), a, a, p, dir, dir);
	cr_assert_eq(tu_run(cmd), 2, "%s", cmd);
	tu_one_line(dir, "saarsim-replay", "--config given twice");
	/* the --set after the file wins, and a good one replays */
	snprintf(cmd, sizeof cmd,
	         "%s/saarsim-replay --set memory.sdram.banks=2 --config %s --json %s/r.json %s "
	         ">%s/out 2>%s/err",
	         tu_bin_dir(), a, dir, p, dir, dir);
	cr_assert_eq(tu_run(cmd), 0, "%s: %s", cmd, tu_slurp(dir, "err"));
}
