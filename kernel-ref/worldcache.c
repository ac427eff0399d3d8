/*
 * worldcache.c: the world cache (worldcache.h, --world-cache DIR).
 *
 * Owns: storing a built world (the memory image, plus the scene, kd-tree
 * and view figures that reports and the default light need) and
 * kernel-ref's reference frame of it, one file each, and reading them
 * back. On the 70k-triangle scenes the import, the kd-tree build and the
 * reference render take longer than a sampled simulation of the frame
 * (PERFORMANCE.md's world cache table), and a sweep paid them at every
 * point.
 *
 * A file is used only when it is certainly what a build would give now:
 * - its key names this program's own bytes (CRC-32 and size of
 *   /proc/self/exe), so a rebuilt program never reads an older file and
 *   the raw structs stored have the writer's layout;
 * - a world's key names the scene source by its real path and every kd
 *   parameter exactly (hex floats); a frame's key names the memory image
 *   by its CRC-32, the camera, lights and render options;
 * - a world's file lists every file the import read (the scene, an MTL,
 *   each texture) with size and modification time; any change refuses it;
 * - a check over the whole contents refuses a damaged or truncated file.
 * A refused file is a miss: the object is built as without a cache and
 * the file replaced. Files are written under a temporary name and renamed,
 * so concurrent sweep points never read half a file; two points missing
 * at once both build, and the last rename wins (both wrote the same bytes).
 *
 * File layout: "SAARWC2\n"; the head: the key (u32 length + bytes), the
 * recorded files (u32 count; each u32 length, bytes, i64 size, i64 mtime
 * seconds, i64 mtime nanoseconds), the fixed parts, zeros up to a multiple
 * of 64 bytes; the tail; the trailer: CRC-32 of the head (u32), zero
 * (u32), tail_hash of the tail (u64). The tail starts 64-byte aligned in
 * the file, so a reader can map the file and use the tail where it lies
 * (wc_get_mapped): a frame's packet record is tens of MB, and reading it
 * into malloc'd memory and running CRC-32 over it showed in functional
 * runs' profiles (host.packet_record_s reports the load).
 */
#define _GNU_SOURCE /* asprintf */
#include "kernel-ref/worldcache.h"

#include "kernel-ref/atomicfile.h"
#include "kernel-ref/spd.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#define WC_MAGIC     "SAARWC2\n"
#define WC_MAGIC_LEN 8
/* entries a folder's eviction looks at (a folder of more is not ours) */
#define WC_MAX_ENTRIES 100000

/* ---- the files a scene came from ---- */

/* The absolute path of a file that does not exist, after the byte
 * SCENE_FILE_ABSENT (malloc'd): its folder's real path and its name, or,
 * when the folder does not exist either (Assimp looks for an MTL under
 * names such as "dir//dir/./name"), the path itself made absolute. NULL
 * when out of memory or the working folder is unknown. */
static char *absent_path(const char *path)
{
	const char *slash = strrchr(path, '/');
	char dir[PATH_MAX], cwd[PATH_MAX];
	int n = slash ? snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path)
	              : snprintf(dir, sizeof dir, ".");
	char *rd = n >= 0 && (size_t)n < sizeof dir ? realpath(dir[0] ? dir : "/", NULL) : NULL,
	     *out = NULL;
	int r;
	if (rd)
		r = asprintf(&out, "%c%s/%s", SCENE_FILE_ABSENT, strcmp(rd, "/") ? rd : "",
		             slash ? slash + 1 : path);
	else if (path[0] == '/')
		r = asprintf(&out, "%c%s", SCENE_FILE_ABSENT, path);
	else
		r = getcwd(cwd, sizeof cwd)
		        ? asprintf(&out, "%c%s/%s", SCENE_FILE_ABSENT, cwd, path)
		        : -1;
	free(rd);
	return r < 0 ? NULL : out;
}

void wc_files_add(void *ctx, const char *path)
{
	wc_files *f = ctx;
	/* a file the import looked for and did not find: watched for
	 * appearing (an OBJ's MTL added later changes the scene) */
	char *rp = path[0] == SCENE_FILE_ABSENT ? absent_path(path + 1) : realpath(path, NULL);
	if (!rp) {
		f->lost = 1; /* opened a moment ago; cannot watch it, so do not store */
		return;
	}
	for (int i = 0; i < f->n; i++)
		if (!strcmp(f->path[i], rp)) {
			free(rp);
			return;
		}
	if (f->n == f->cap) {
		int cap = f->cap ? 2 * f->cap : 8;
		char **p = realloc(f->path, (size_t)cap * sizeof *p);
		if (!p) {
			free(rp);
			f->lost = 1;
			return;
		}
		f->path = p;
		f->cap = cap;
	}
	f->path[f->n++] = rp;
}

void wc_files_free(wc_files *f)
{
	for (int i = 0; i < f->n; i++)
		free(f->path[i]);
	free(f->path);
	memset(f, 0, sizeof *f);
}

/* ---- names ---- */

/* CRC-32 and size of this program's own file: a rebuilt program is a
 * different program, whatever its version string says. */
static int exe_identity(unsigned long *crc, long long *size)
{
	FILE *fp = fopen("/proc/self/exe", "rb");
	if (!fp)
		return -1;
	unsigned char buf[1 << 16];
	uLong c = crc32(0L, Z_NULL, 0);
	long long n = 0;
	size_t r;
	while ((r = fread(buf, 1, sizeof buf, fp)) > 0) {
		c = crc32(c, buf, (uInt)r);
		n += (long long)r;
	}
	int bad = ferror(fp);
	fclose(fp);
	*crc = c;
	*size = n;
	return bad ? -1 : 0;
}

/* mkdir -p: every missing folder on the way to dir (the last one too). */
static int mkdirs(const char *dir)
{
	char p[PATH_MAX];
	if (snprintf(p, sizeof p, "%s", dir) >= (int)sizeof p) {
		errno = ENAMETOOLONG;
		return -1;
	}
	for (char *s = p + 1; *s; s++)
		if (*s == '/') {
			*s = '\0';
			if (mkdir(p, 0777) != 0 && errno != EEXIST)
				return -1;
			*s = '/';
		}
	return mkdir(p, 0777) != 0 && errno != EEXIST ? -1 : 0;
}

int wc_prepare(const char *dir, int parents, char *prog, size_t nprog, diag *d)
{
	if ((parents ? mkdirs(dir) : mkdir(dir, 0777)) != 0 && errno != EEXIST)
		return diag_set(d, dir, 0, 0, "--world-cache: cannot create the folder: %s",
		                strerror(errno));
	struct stat st;
	if (stat(dir, &st) != 0 || !S_ISDIR(st.st_mode))
		return diag_set(d, dir, 0, 0, "--world-cache: not a folder");
	if (access(dir, W_OK | X_OK) != 0)
		return diag_set(d, dir, 0, 0, "--world-cache: cannot write to the folder: %s",
		                strerror(errno));
	unsigned long crc;
	long long size;
	if (exe_identity(&crc, &size))
		return diag_set(d, "/proc/self/exe", 0, 0,
		                "--world-cache: cannot read the program's own file");
	snprintf(prog, nprog, "program %08lx %lld", crc, size);
	return 0;
}

/* ---- the folder and its cap ---- */

const char *wc_from_name(int from)
{
	static const char *const n[] = {
	    "off", "--world-cache", "SAARSIM_CACHE_DIR", "XDG_CACHE_HOME", "HOME", "none"};
	return from >= 0 && from <= WC_FROM_NONE ? n[from] : "?";
}

/* A variable's value, NULL when unset or empty. */
static const char *env(const char *name)
{
	const char *v = getenv(name);
	return v && *v ? v : NULL;
}

int wc_choose(const char *flag, char *out, size_t n)
{
	out[0] = '\0';
	const char *v, *suffix = "", *xdg = env("XDG_CACHE_HOME");
	int from;
	if ((v = flag))
		from = WC_FROM_FLAG;
	else if ((v = env("SAARSIM_CACHE_DIR")))
		from = WC_FROM_ENV;
	else if (xdg && xdg[0] == '/') { /* the spec: a relative one is ignored */
		v = xdg;
		from = WC_FROM_XDG;
		suffix = "/saarsim";
	} else if ((v = env("HOME"))) {
		from = WC_FROM_HOME;
		suffix = "/.cache/saarsim";
	} else
		return WC_FROM_NONE;
	if ((from == WC_FROM_FLAG || from == WC_FROM_ENV) && !strcmp(v, "off"))
		return WC_FROM_OFF;
	int k = snprintf(out, n, "%s%s", v, suffix);
	if (k < 0 || (size_t)k >= n) {
		out[0] = '\0';
		return WC_FROM_NONE;
	}
	return from;
}

int wc_cap(long mb, uint64_t *bytes, diag *d)
{
	if (mb < 0) {
		const char *v = getenv("SAARSIM_CACHE_MAX_MB");
		mb = WC_DEFAULT_MAX_MB;
		if (v) {
			char *end;
			errno = 0;
			long long x = strtoll(v, &end, 10);
			if (!*v || *v < '0' || *v > '9' || *end || errno || x > WC_MAX_MB)
				return diag_set(
				    d, "SAARSIM_CACHE_MAX_MB", 0, 0,
				    "'%.40s' is not a size in MB (a whole number, 0 to %d; "
				    "0: no cap)",
				    v, WC_MAX_MB);
			mb = (long)x;
		}
	}
	*bytes = (uint64_t)mb << 20;
	return 0;
}

/* An entry of the folder: KIND-HASH.bin, one of the four kinds. */
static int is_entry(const char *name)
{
	static const char *const kinds[] = {"world-", "frame-", "packets-", "warming-"};
	for (size_t k = 0; k < sizeof kinds / sizeof *kinds; k++) {
		size_t n = strlen(kinds[k]);
		if (strncmp(name, kinds[k], n))
			continue;
		const char *h = name + n;
		if (strlen(h) != 16 + 4 || strcmp(h + 16, ".bin"))
			return 0;
		for (int i = 0; i < 16; i++)
			if (!((h[i] >= '0' && h[i] <= '9') || (h[i] >= 'a' && h[i] <= 'f')))
				return 0;
		return 1;
	}
	return 0;
}

typedef struct wc_ent {
	char name[32];
	uint64_t size;
	struct timespec used;
} wc_ent;

static int by_use(const void *a, const void *b)
{
	const struct timespec *x = &((const wc_ent *)a)->used, *y = &((const wc_ent *)b)->used;
	if (x->tv_sec != y->tv_sec)
		return x->tv_sec < y->tv_sec ? -1 : 1;
	return x->tv_nsec < y->tv_nsec ? -1 : x->tv_nsec > y->tv_nsec;
}

/* The folder's entries (at most WC_MAX_ENTRIES) into *out, their total
 * size into *total; -1 when it cannot be read. */
static int list_entries(const char *dir, wc_ent **out, size_t *nout, uint64_t *total)
{
	DIR *dp = opendir(dir);
	if (!dp)
		return -1;
	wc_ent *e = NULL;
	size_t n = 0, cap = 0;
	*total = 0;
	struct dirent *de;
	while ((de = readdir(dp)) && n < WC_MAX_ENTRIES) {
		struct stat st;
		if (!is_entry(de->d_name) || fstatat(dirfd(dp), de->d_name, &st, 0) != 0 ||
		    !S_ISREG(st.st_mode))
			continue;
		if (n == cap) {
			size_t c = cap ? 2 * cap : 64;
			wc_ent *q = realloc(e, c * sizeof *q);
			if (!q)
				break;
			e = q;
			cap = c;
		}
		memcpy(e[n].name, de->d_name, strlen(de->d_name) + 1); /* is_entry: < 32 */
		e[n].size = (uint64_t)st.st_size;
		e[n].used = st.st_mtim;
		*total += e[n].size;
		n++;
	}
	closedir(dp);
	*out = e;
	*nout = n;
	return 0;
}

int wc_make_room(const char *dir, uint64_t need, uint64_t cap)
{
	if (!cap)
		return 0;
	if (need > cap)
		return -1;
	wc_ent *e;
	size_t n;
	uint64_t total;
	if (list_entries(dir, &e, &n, &total))
		return 0; /* the store will say what is wrong */
	if (total + need > cap) {
		qsort(e, n, sizeof *e, by_use);
		char path[PATH_MAX];
		/* another run may remove the same entry at once: gone is gone */
		for (size_t i = 0; i < n && total + need > cap; i++)
			if (snprintf(path, sizeof path, "%s/%s", dir, e[i].name) <
			        (int)sizeof path &&
			    (unlink(path) == 0 || errno == ENOENT))
				total -= e[i].size;
	}
	free(e);
	return 0;
}

/* crc continued over n bytes (zlib takes at most 4 GiB per call) */
static uLong crc_more(uLong c, const void *p, uint64_t n)
{
	for (uint64_t at = 0; at < n; at += 1u << 30) {
		uint64_t k = n - at < (1u << 30) ? n - at : (1u << 30);
		c = crc32(c, (const Bytef *)p + at, (uInt)k);
	}
	return c;
}

uint32_t wc_crc(const void *p, uint64_t n)
{
	return (uint32_t)crc_more(crc32(0L, Z_NULL, 0), p, n);
}

/* FNV-1a, 64 bits: the file name of a key (the key itself is compared). */
static uint64_t fnv1a(const char *s)
{
	uint64_t h = 14695981039346656037ull;
	for (; *s; s++)
		h = (h ^ (unsigned char)*s) * 1099511628211ull;
	return h;
}

int wc_file(char *out, size_t n, const char *dir, const char *kind, const char *key)
{
	int k = snprintf(out, n, "%s/%s-%016llx.bin", dir, kind, (unsigned long long)fnv1a(key));
	return k < 0 || (size_t)k >= n ? -1 : 0;
}

char *wc_world_key(const char *prog, const char *source, const kd_params *kd)
{
	/* a file by its real path: the same scene named from another folder
	 * is the same entry */
	char *rp = source && !spd_is(source) ? realpath(source, NULL) : NULL;
	char *key;
	int n = asprintf(
	    &key,
	    "saarsim world 1\n%s\nsource %s\nkd %a %a %d %d %a %a %a %a %a %a\nstructs %zu %zu %zu "
	    "%zu\n",
	    prog,
	    rp       ? rp
	    : source ? source
	             : "(embedded)",
	    (double)kd->cost_trav, (double)kd->cost_isect, kd->max_depth, kd->leaf_size,
	    (double)kd->empty_bonus, (double)kd->footprint, (double)kd->fp_angle,
	    (double)kd->fp_eye[0], (double)kd->fp_eye[1], (double)kd->fp_eye[2], sizeof(scene),
	    sizeof(kdtree), sizeof(mimg), sizeof(view));
	free(rp);
	return n < 0 ? NULL : key;
}

char *wc_frame_key(const char *prog, uint32_t image_crc, uint64_t image_size, const view *v,
                   const render_opts *o)
{
	if (o->prec)
		return NULL;
	char *key, *lights = NULL;
	size_t nl = 0;
	FILE *f = open_memstream(&lights, &nl);
	if (!f)
		return NULL;
	for (int i = 0; i < v->nlights; i++) {
		const light *l = &v->lights[i];
		fprintf(f, " (%a %a %a; %a %a %a)", (double)l->pos.x, (double)l->pos.y,
		        (double)l->pos.z, (double)l->color.x, (double)l->color.y,
		        (double)l->color.z);
	}
	if (fclose(f) != 0) {
		free(lights);
		return NULL;
	}
	const camera *c = &v->cam;
	int n =
	    asprintf(&key,
	             "saarsim frame 1\n%s\nimage %08x %llu\ncamera %a %a %a %a %a %a %a %a %a "
	             "%a\nlights %d%s\nframe %d %d depth %d shadows %d single %d background "
	             "%a %a %a\nstructs %zu\n",
	             prog, (unsigned)image_crc, (unsigned long long)image_size, (double)c->eye.x,
	             (double)c->eye.y, (double)c->eye.z, (double)c->lookat.x, (double)c->lookat.y,
	             (double)c->lookat.z, (double)c->up.x, (double)c->up.y, (double)c->up.z,
	             (double)c->fov_deg, v->nlights, lights, o->width, o->height, o->max_depth,
	             o->shadows, o->single_ray, (double)o->background.x, (double)o->background.y,
	             (double)o->background.z, sizeof(render_stats));
	free(lights);
	/* distribution effects name the frame too (a pinhole frame's key is
	 * as it was) */
	const drt_params *p = &v->drt;
	if (n >= 0 && !drt_is_off(p)) {
		char *k2;
		n = asprintf(&k2, "%sdrt %d %a %a %a %a %a %a %a\n", key, drt_spp(p),
		             (double)p->aperture, (double)p->focus, (double)p->light_size,
		             (double)p->gloss, (double)p->motion.x, (double)p->motion.y,
		             (double)p->motion.z);
		free(key);
		key = n < 0 ? NULL : k2;
	}
	return n < 0 ? NULL : key;
}

/* ---- the check ---- */

#define WC_ALIGN   64 /* where the tail starts: a host cache line */
#define WC_TRAILER 16 /* u32 CRC-32 of the head, u32 zero, u64 tail_hash */

/* 64 bits over the tail: four lanes of multiply-xor over 8-byte words,
 * then the lanes and the length mixed. A change to one word changes its
 * lane for good (times an odd constant is a bijection, and so is every
 * later step of the lane), which is what a damaged file needs; the four
 * lanes run near memory speed, several times faster than zlib's CRC-32. */
static uint64_t tail_hash(const void *p, size_t n)
{
	const uint64_t K = 0x9e3779b97f4a7c15ull;
	const unsigned char *b = p;
	uint64_t h[4] = {1, 2, 3, 4};
	size_t i = 0;
	for (; i + 32 <= n; i += 32)
		for (int l = 0; l < 4; l++) {
			uint64_t w;
			memcpy(&w, b + i + 8 * (size_t)l, sizeof w);
			h[l] = (h[l] ^ w) * K;
		}
	for (; i < n; i++)
		h[0] = (h[0] ^ b[i]) * K;
	uint64_t r = n;
	for (int l = 0; l < 4; l++)
		r = (r ^ h[l]) * K;
	return r ^ (r >> 31);
}

/* ---- reading ---- */

/* A mapped file being read: a cursor over the head; once anything does
 * not fit, every later take fails. */
typedef struct wcin {
	const unsigned char *p;
	size_t at, end;
	int bad;
} wcin;

static const void *take(wcin *r, size_t n)
{
	if (r->bad || n > r->end - r->at) {
		r->bad = 1;
		return NULL;
	}
	const void *q = r->p + r->at;
	r->at += n;
	return q;
}

static uint32_t take_u32(wcin *r)
{
	uint32_t v = 0;
	const void *q = take(r, sizeof v);
	if (q)
		memcpy(&v, q, sizeof v);
	return v;
}

/* The recorded files, each still of the recorded size and time, and
 * those recorded absent (size -1) still absent. */
static int files_unchanged(wcin *r)
{
	uint32_t n = take_u32(r);
	for (uint32_t i = 0; i < n && !r->bad; i++) {
		uint32_t len = take_u32(r);
		char path[PATH_MAX];
		if (len == 0 || len >= sizeof path)
			return 0;
		const void *q = take(r, len);
		int64_t want[3];
		const void *v = take(r, sizeof want);
		if (!q || !v)
			return 0;
		memcpy(path, q, len);
		path[len] = '\0';
		memcpy(want, v, sizeof want);
		struct stat st;
		if (want[0] == -1) {
			if (stat(path, &st) == 0 || (errno != ENOENT && errno != ENOTDIR))
				return 0;
			continue;
		}
		if (stat(path, &st) != 0 || (int64_t)st.st_size != want[0] ||
		    (int64_t)st.st_mtim.tv_sec != want[1] || (int64_t)st.st_mtim.tv_nsec != want[2])
			return 0;
	}
	return !r->bad;
}

/* A miss leaves the caller's parts zeroed, never half read. */
static void zero_parts(const wc_part *parts, int nparts)
{
	for (int i = 0; i < nparts; i++)
		memset(parts[i].p, 0, parts[i].n);
}

void wc_unmap(wc_map *m)
{
	if (m->base)
		munmap(m->base, m->len);
	m->base = NULL;
	m->len = 0;
}

int wc_get_mapped(const char *file, const char *key, const wc_part *parts, int nparts,
                  const void **tail, size_t *ntail, wc_map *m)
{
	m->base = NULL;
	m->len = 0;
	if (tail) {
		*tail = NULL;
		*ntail = 0;
	}
	/* O_NONBLOCK: something else under the entry's name (a FIFO would
	 * block the open) is a miss like any damaged entry */
	int fd = open(file, O_RDONLY | O_CLOEXEC | O_NONBLOCK);
	if (fd < 0)
		return 0;
	struct stat st;
	void *base = MAP_FAILED;
	/* populated at once: faulting the pages in one by one as the replay
	 * reaches them cost several times more here */
	if (fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size >= WC_MAGIC_LEN + WC_TRAILER &&
	    (uint64_t)st.st_size <= SIZE_MAX)
		base = mmap(NULL, (size_t)st.st_size, PROT_READ, MAP_PRIVATE | MAP_POPULATE, fd, 0);
	close(fd);
	if (base == MAP_FAILED)
		return 0;
	size_t len = (size_t)st.st_size, klen = strlen(key);
	wcin r = {base, WC_MAGIC_LEN, len - WC_TRAILER, 0};
	int hit = 0;
	if (memcmp(base, WC_MAGIC, WC_MAGIC_LEN) || take_u32(&r) != klen)
		goto out;
	const void *k = take(&r, klen);
	if (!k || memcmp(k, key, klen) || !files_unchanged(&r))
		goto out;
	for (int i = 0; i < nparts; i++) {
		const void *q = take(&r, parts[i].n);
		if (q)
			memcpy(parts[i].p, q, parts[i].n);
	}
	take(&r, (WC_ALIGN - r.at % WC_ALIGN) % WC_ALIGN);
	if (r.bad)
		goto out;
	const unsigned char *tr = r.p + len - WC_TRAILER;
	uint32_t crc;
	uint64_t hash;
	memcpy(&crc, tr, sizeof crc);
	memcpy(&hash, tr + 8, sizeof hash);
	size_t n = len - WC_TRAILER - r.at;
	if ((n > 0) != (tail != NULL) || crc != wc_crc(base, r.at) ||
	    hash != tail_hash(r.p + r.at, n))
		goto out;
	hit = 1;
	/* a hit marks the entry used: a capped folder evicts the least
	 * recently used first (wc_make_room); a read-only folder keeps it old */
	utimensat(AT_FDCWD, file, NULL, 0);
	if (tail) {
		*tail = r.p + r.at;
		*ntail = n;
		m->base = base;
		m->len = len;
	}
out:
	if (!hit || !tail)
		munmap(base, len);
	if (!hit)
		zero_parts(parts, nparts);
	return hit;
}

int wc_get(const char *file, const char *key, const wc_part *parts, int nparts, void **tail,
           size_t *ntail)
{
	const void *mt = NULL;
	size_t n = 0;
	wc_map m;
	if (tail) {
		*tail = NULL;
		*ntail = 0;
	}
	if (!wc_get_mapped(file, key, parts, nparts, tail ? &mt : NULL, &n, &m))
		return 0;
	if (tail) {
		void *t = malloc(n);
		if (!t) {
			wc_unmap(&m);
			zero_parts(parts, nparts);
			return 0;
		}
		memcpy(t, mt, n);
		*tail = t;
		*ntail = n;
	}
	wc_unmap(&m);
	return 1;
}

/* ---- writing ---- */

/* A cache file being written: the head's CRC and length so far, and
 * whether anything failed (every later put is then a no-op). */
typedef struct wcout {
	FILE *fp;
	uLong crc;
	uint64_t n;
	int bad;
} wcout;

static void put(wcout *w, const void *p, size_t n)
{
	if (w->bad || fwrite(p, 1, n, w->fp) != n) {
		w->bad = 1;
		return;
	}
	w->crc = crc_more(w->crc, p, n);
	w->n += n;
}

static void put_u32(wcout *w, uint32_t v)
{
	put(w, &v, sizeof v);
}

int wc_put(const char *file, const char *key, const wc_files *f, const wc_part *parts, int nparts,
           const void *tail, size_t ntail, diag *d)
{
	if (f && f->lost)
		return diag_set(d, file, 0, 0, "world cache: a source file could not be recorded");
	afile a;
	if (af_open(&a, file, "", 1))
		return diag_set(d, file, 0, 0, "world cache: cannot write: %s", strerror(errno));
	wcout w = {a.f, crc32(0L, Z_NULL, 0), 0, 0};
	put(&w, WC_MAGIC, WC_MAGIC_LEN);
	put_u32(&w, (uint32_t)strlen(key));
	put(&w, key, strlen(key));
	put_u32(&w, f ? (uint32_t)f->n : 0);
	for (int i = 0; f && i < f->n; i++) {
		/* an absent file: its path and -1s, for files_unchanged */
		const char *p = f->path[i] + (f->path[i][0] == SCENE_FILE_ABSENT);
		struct stat st;
		int64_t v[3] = {-1, -1, -1};
		if (p == f->path[i]) {
			if (stat(p, &st) != 0) {
				w.bad = 1;
				break;
			}
			v[0] = st.st_size;
			v[1] = st.st_mtim.tv_sec;
			v[2] = st.st_mtim.tv_nsec;
		}
		put_u32(&w, (uint32_t)strlen(p));
		put(&w, p, strlen(p));
		put(&w, v, sizeof v);
	}
	for (int i = 0; i < nparts; i++)
		put(&w, parts[i].p, parts[i].n);
	static const unsigned char zeros[WC_ALIGN];
	put(&w, zeros, (size_t)((WC_ALIGN - w.n % WC_ALIGN) % WC_ALIGN));
	uint32_t trailer[4] = {(uint32_t)w.crc, 0, 0, 0};
	uint64_t hash = tail_hash(tail, ntail);
	memcpy(&trailer[2], &hash, sizeof hash);
	if (!w.bad && ((ntail && fwrite(tail, 1, ntail, w.fp) != ntail) ||
	               fwrite(trailer, 1, sizeof trailer, w.fp) != sizeof trailer))
		w.bad = 1;
	if (w.bad) {
		af_abort(&a);
		return diag_set(d, file, 0, 0, "world cache: cannot write: %s", strerror(EIO));
	}
	if (af_commit(&a))
		return diag_set(d, file, 0, 0, "world cache: cannot write: %s", strerror(errno));
	return 0;
}
