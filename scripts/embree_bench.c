/*
 * embree_bench.c: our comparison harness against Embree 3 (optional; built
 * by scripts/bench.sh only when libembree-dev is installed).
 *
 * Owns one measurement: the primary rays of one frame, traced single
 * threaded (a) by Embree 3 with packets of 4, 8 and 16 rays (rtcIntersect4,
 * 8, 16: each 8x8 tile as sixteen 2x2, eight 4x2 or four 4x4 packets; the
 * fastest width is Embree's figure, since which is fastest depends on the
 * host's SIMD width: 16 on AVX-512, 8 on AVX2), and (b) by our packet tracer's traversal alone
 * (fru_trace, rtref's packet traversal, on the 64-ray tile packet, no
 * shading), both on exactly the
 * same rays: the scene, view and camera come from world_load() and the rays
 * from cam_primary_packet(), as in rtref. Each is timed best of N passes
 * with ray generation (each tile's packet made in the loop, as rtref makes
 * it), shading excluded, and the ray generation alone, so traversal alone
 * is each time less that one (a frame's packets made in advance would be
 * streamed from memory: slower than making them); the per-pixel hits of
 * the two are compared (hit/miss disagreements; different triangle, and
 * whether the distances differ too, and if so which tracer is closer).
 *
 *   embree_bench --views F --view N [--size WxH] [--runs N] [--quality low|medium|high]
 *                [--robust] [--packet 4|8|16|all] [other scene/view flags of rtref]
 *
 * Prints key=value lines (parsed by scripts/bench.sh). Written from the
 * Embree 3 API documentation (man pages rtcIntersect4/8/16, RTCRayHit4/8/16,
 * rtcNewGeometry, rtcSetNewGeometryBuffer).
 */
#include <embree3/rtcore.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "kernel-ref/camera.h"
#include "kernel-ref/frustum.h"
#include "kernel-ref/packet.h"
#include "kernel-ref/world.h"

static double now_ms(void)
{
	struct timespec ts;
	clock_gettime(CLOCK_MONOTONIC, &ts);
	return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static void on_embree_error(void *user, enum RTCError code, const char *str)
{
	(void)user;
	fprintf(stderr, "embree_bench: Embree error %d: %s\n", (int)code, str ? str : "");
}

static int usage(FILE *f, int rc)
{
	fprintf(f, "usage: embree_bench [options]\n"
	           "  --size WxH            frame size (default 1024x1024)\n"
	           "  --runs N              passes per tracer, best is reported (default 3)\n"
	           "  --quality Q           Embree build quality: low, medium (default), high\n"
	           "  --robust              Embree robust (watertight) mode\n"
	           "  --packet W            Embree's packet width: 4, 8, 16 or all (default all:\n"
	           "                        each timed, the fastest reported as Embree's)\n"
	           "  --list-diffs N        print up to N pixels where the hits differ (stderr)\n");
	fputs(world_usage, f);
	return rc;
}

/* Per-pixel results of one tracer. */
typedef struct hits {
	uint32_t *tri; /* triangle index, UINT32_MAX for a miss */
	float *t;
} hits;

static int hits_alloc(hits *h, size_t n)
{
	h->tri = malloc(n * sizeof *h->tri);
	h->t = malloc(n * sizeof *h->t);
	if (!h->tri || !h->t)
		return -1;
	for (size_t i = 0; i < n; i++) {
		h->tri[i] = UINT32_MAX;
		h->t[i] = INFINITY;
	}
	return 0;
}

static RTCScene embree_scene(RTCDevice dev, const scene *s, enum RTCBuildQuality q, int robust)
{
	RTCScene sc = rtcNewScene(dev);
	if (!sc)
		return NULL;
	rtcSetSceneBuildQuality(sc, q);
	if (robust)
		rtcSetSceneFlags(sc, RTC_SCENE_FLAG_ROBUST);
	RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
	if (!g)
		return NULL;
	rtcSetGeometryBuildQuality(g, q);
	/* Our triangle soup: corner 3i+k of triangle i. Embree pads its own
	 * buffers, so copy rather than share. */
	size_t nv = 3 * (size_t)s->ntris;
	float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
	                                    3 * sizeof(float), nv);
	unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
	                                       3 * sizeof(unsigned), s->ntris);
	if (!vb || !ib)
		return NULL;
	for (size_t i = 0; i < nv; i++) {
		vb[3 * i + 0] = s->v[i].x;
		vb[3 * i + 1] = s->v[i].y;
		vb[3 * i + 2] = s->v[i].z;
		ib[i] = (unsigned)i;
	}
	rtcCommitGeometry(g);
	rtcAttachGeometry(sc, g); /* geomID 0 */
	rtcReleaseGeometry(g);
	rtcCommitScene(sc);
	return sc;
}

/* One tile's packet p with Embree, as packets of W rays (an 8x8 tile as
 * 64 / W packets of PW x PH pixels); hits into h. One function per width:
 * Embree's RTCRayHit4/8/16 differ only in the length of their arrays. */
#define EMBREE_TILE(W, PW, PH)                                                                     \
	static uint64_t embree_tile##W(RTCScene sc, const packet *p, hits *h)                      \
	{                                                                                          \
		struct RTCIntersectContext ctx;                                                    \
		rtcInitIntersectContext(&ctx);                                                     \
		ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;                                   \
		struct RTCRayHit##W rh;                                                            \
		int valid[W] __attribute__((aligned(64)));                                         \
		uint64_t rays = 0;                                                                 \
		for (int q = 0; q < (TILE_W / PW) * (TILE_H / PH); q++) {                          \
			int qx = (q % (TILE_W / PW)) * PW, qy = (q / (TILE_W / PW)) * PH;          \
			int any = 0;                                                               \
			for (int k = 0; k < W; k++) {                                              \
				int lane = (qy + k / PW) * TILE_W + qx + k % PW;                   \
				int on = (int)((p->valid >> lane) & 1);                            \
				valid[k] = on ? -1 : 0;                                            \
				any |= on;                                                         \
				rh.ray.org_x[k] = p->ox[lane];                                     \
				rh.ray.org_y[k] = p->oy[lane];                                     \
				rh.ray.org_z[k] = p->oz[lane];                                     \
				rh.ray.dir_x[k] = p->dx[lane];                                     \
				rh.ray.dir_y[k] = p->dy[lane];                                     \
				rh.ray.dir_z[k] = p->dz[lane];                                     \
				rh.ray.tnear[k] = 0.0f;                                            \
				rh.ray.tfar[k] = p->tmax[lane];                                    \
				rh.ray.time[k] = 0.0f;                                             \
				rh.ray.mask[k] = UINT32_MAX;                                       \
				rh.ray.id[k] = (unsigned)k;                                        \
				rh.ray.flags[k] = 0;                                               \
				rh.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;                        \
			}                                                                          \
			if (!any)                                                                  \
				continue;                                                          \
			rtcIntersect##W(valid, sc, &ctx, &rh);                                     \
			for (int k = 0; k < W; k++) {                                              \
				if (!valid[k])                                                     \
					continue;                                                  \
				rays++;                                                            \
				int lane = (qy + k / PW) * TILE_W + qx + k % PW;                   \
				uint32_t px = p->pixel[lane];                                      \
				if (rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID) {                 \
					h->tri[px] = rh.hit.primID[k];                             \
					h->t[px] = rh.ray.tfar[k];                                 \
				} else {                                                           \
					h->tri[px] = UINT32_MAX;                                   \
					h->t[px] = INFINITY;                                       \
				}                                                                  \
			}                                                                          \
		}                                                                                  \
		return rays;                                                                       \
	}
EMBREE_TILE(4, 2, 2)
EMBREE_TILE(8, 4, 2)
EMBREE_TILE(16, 4, 4)

typedef uint64_t (*embree_tile_fn)(RTCScene sc, const packet *p, hits *h);

/* The packet widths timed, narrowest first, and their tile functions. */
static const int embree_widths[3] = {4, 8, 16};
static const embree_tile_fn embree_tiles[3] = {embree_tile4, embree_tile8, embree_tile16};

/* One frame with Embree, the rays made tile by tile as rtref makes them;
 * gen_only: the rays made and nothing traced (the time both sides spend
 * on ray generation). */
static uint64_t embree_frame(RTCScene sc, embree_tile_fn tile, const cam_frame *cf, packet *p,
                             int gen_only, hits *h)
{
	int tw = (cf->width + TILE_W - 1) / TILE_W, th = (cf->height + TILE_H - 1) / TILE_H;
	uint64_t rays = 0;
	for (int ty = 0; ty < th; ty++)
		for (int tx = 0; tx < tw; tx++) {
			if (cam_primary_packet(cf, tx, ty, p) == 0)
				continue;
			if (gen_only) /* keep the packet's rays live for the compiler */
				rays += (uint64_t)(p->valid & 1) + (p->dx[0] != p->dx[0]);
			else
				rays += tile(sc, p, h);
		}
	return rays;
}

/* One frame with our packet traversal (no shading). */
static uint64_t ours_frame(const mimg *m, const cam_frame *cf, packet *p, trav_entry *stack,
                           hits *h)
{
	int tw = (cf->width + TILE_W - 1) / TILE_W, th = (cf->height + TILE_H - 1) / TILE_H;
	uint64_t rays = 0;
	for (int ty = 0; ty < th; ty++)
		for (int tx = 0; tx < tw; tx++) {
			if (cam_primary_packet(cf, tx, ty, p) == 0)
				continue;
			fru_trace(p, m, stack, PKT_STACK_MAX, NULL, NULL, 0);
			for (int lane = 0; lane < PKT_RAYS; lane++) {
				if (!((p->valid >> lane) & 1))
					continue;
				rays++;
				uint32_t px = p->pixel[lane];
				if (p->tri[lane] != PKT_NOHIT) {
					h->tri[px] = mimg_tri_index(m, p->tri[lane]);
					h->t[px] = p->t[lane];
				} else {
					h->tri[px] = UINT32_MAX;
					h->t[px] = INFINITY;
				}
			}
		}
	return rays;
}

static int parse_size(const char *s, int *w, int *h)
{
	char *end;
	errno = 0;
	/* digits only, as saarsim's and rtref's --size: strtol alone takes a
	 * leading blank or sign */
	if (*s < '0' || *s > '9')
		return -1;
	long a = strtol(s, &end, 10);
	if (end == s || (*end != 'x' && *end != 'X') || errno)
		return -1;
	const char *q = end + 1;
	if (*q < '0' || *q > '9')
		return -1;
	long b = strtol(q, &end, 10);
	if (end == q || *end || errno || a < 1 || a > 16384 || b < 1 || b > 16384)
		return -1;
	*w = (int)a;
	*h = (int)b;
	return 0;
}

int main(int argc, char **argv)
{
	world_opts wo;
	world_opts_default(&wo);
	diag d = {{0}};
	int width = 1024, height = 1024, runs = 3, robust = 0, list_diffs = 0;
	int wsel = 0; /* Embree packet widths timed: 0 all, else one of embree_widths */
	enum RTCBuildQuality quality = RTC_BUILD_QUALITY_MEDIUM;
	const char *qname = "medium";
	for (int i = 1; i < argc;) {
		int r = world_parse_arg(&wo, argc, argv, &i, &d);
		if (r < 0) {
			fprintf(stderr, "embree_bench: %s\n", d.msg);
			return DIAG_EXIT;
		}
		if (r > 0)
			continue;
		const char *a = argv[i];
		if (!strcmp(a, "-h") || !strcmp(a, "--help"))
			return usage(stdout, 0);
		if (!strcmp(a, "--robust")) {
			robust = 1;
			i++;
			continue;
		}
		if (i + 1 >= argc) {
			fprintf(stderr, "embree_bench: %s: unknown option or missing value\n", a);
			return usage(stderr, DIAG_EXIT);
		}
		const char *v = argv[i + 1];
		if (!strcmp(a, "--size")) {
			if (parse_size(v, &width, &height)) {
				fprintf(stderr,
				        "embree_bench: --size: expected WxH (1..16384), got '%s'\n",
				        v);
				return DIAG_EXIT;
			}
		} else if (!strcmp(a, "--runs")) {
			char *end;
			long n = strtol(v, &end, 10);
			if (end == v || *end || n < 1 || n > 100) {
				fprintf(stderr, "embree_bench: --runs: expected 1..100, got '%s'\n",
				        v);
				return DIAG_EXIT;
			}
			runs = (int)n;
		} else if (!strcmp(a, "--list-diffs")) {
			char *end;
			long n = strtol(v, &end, 10);
			if (end == v || *end || n < 0 || n > 1000000) {
				fprintf(
				    stderr,
				    "embree_bench: --list-diffs: expected 0..1000000, got '%s'\n",
				    v);
				return DIAG_EXIT;
			}
			list_diffs = (int)n;
		} else if (!strcmp(a, "--packet")) {
			if (!strcmp(v, "all"))
				wsel = 0;
			else if (!strcmp(v, "4") || !strcmp(v, "8") || !strcmp(v, "16"))
				wsel = atoi(v);
			else {
				fprintf(
				    stderr,
				    "embree_bench: --packet: expected 4, 8, 16 or all, got '%s'\n",
				    v);
				return DIAG_EXIT;
			}
		} else if (!strcmp(a, "--quality")) {
			if (!strcmp(v, "low"))
				quality = RTC_BUILD_QUALITY_LOW;
			else if (!strcmp(v, "medium"))
				quality = RTC_BUILD_QUALITY_MEDIUM;
			else if (!strcmp(v, "high"))
				quality = RTC_BUILD_QUALITY_HIGH;
			else {
				fprintf(
				    stderr,
				    "embree_bench: --quality: expected low, medium or high, got "
				    "'%s'\n",
				    v);
				return DIAG_EXIT;
			}
			qname = v;
		} else {
			fprintf(stderr, "embree_bench: %s: unknown option\n", a);
			return usage(stderr, DIAG_EXIT);
		}
		i += 2;
	}

	world w;
	/* Embree needs the scene's triangles, which a world from the cache
	 * does not hold (world.h): no default world-cache folder (issue 36),
	 * and a named one refused (a hit left the harness without triangles
	 * and it crashed) */
	if (wo.cache_dir && strcmp(wo.cache_dir, "off") != 0) {
		fprintf(stderr, "embree_bench: --world-cache: Embree needs the scene's triangles, "
		                "which a cached world does not hold; use --world-cache off\n");
		return DIAG_EXIT;
	}
	wo.cache_dir = "off";
	world_opts_packet_tree(&wo, height); /* the tree rtref traces */
	if (world_load(&w, &wo, &d)) {
		fprintf(stderr, "embree_bench: %s\n", d.msg);
		return DIAG_EXIT;
	}
	/* Tracing runs on this thread only; one thread for the build too, so
	 * no Embree worker competes with the measurement. */
	RTCDevice dev = rtcNewDevice("threads=1");
	if (!dev) {
		fprintf(stderr, "embree_bench: rtcNewDevice failed (error %d)\n",
		        (int)rtcGetDeviceError(NULL));
		world_free(&w);
		return 1;
	}
	rtcSetDeviceErrorFunction(dev, on_embree_error, NULL);
	double t0 = now_ms();
	RTCScene sc = embree_scene(dev, &w.s, quality, robust);
	double embree_build_ms = now_ms() - t0;
	size_t npix = (size_t)width * (size_t)height;
	hits hw[3], ho;
	packet *p = aligned_alloc(64, (sizeof(packet) + 63) / 64 * 64);
	trav_entry *stack = aligned_alloc(64, (sizeof(trav_entry) * PKT_STACK_MAX + 63) / 64 * 64);
	int nw = 0, wi[3]; /* the widths timed: indices into embree_widths */
	for (int k = 0; k < 3; k++)
		if (!wsel || wsel == embree_widths[k])
			wi[nw++] = k;
	int alloc_failed = 0;
	for (int k = 0; k < nw; k++)
		alloc_failed |= hits_alloc(&hw[k], npix);
	if (!sc || rtcGetDeviceError(dev) != RTC_ERROR_NONE || alloc_failed ||
	    hits_alloc(&ho, npix) || !p || !stack) {
		fprintf(stderr, "embree_bench: setup failed (Embree scene or out of memory)\n");
		return 1;
	}

	cam_frame cf;
	cam_setup(&cf, &w.v.cam, width, height);
	double best_w[3] = {INFINITY, INFINITY, INFINITY}, best_o = INFINITY;
	uint64_t rays_w[3] = {0, 0, 0}, rays_o = 0;
	/* the ray generation alone (the same cam_primary_packet calls), to
	 * take out of both sides' times for traversal alone */
	double best_g = INFINITY;
	for (int r = 0; r < runs; r++) {
		t0 = now_ms();
		embree_frame(sc, embree_tiles[wi[0]], &cf, p, 1, &hw[0]);
		double tg = now_ms() - t0;
		best_g = tg < best_g ? tg : best_g;
	}
	for (int r = 0; r < runs; r++) {
		for (int k = 0; k < nw; k++) {
			t0 = now_ms();
			rays_w[k] = embree_frame(sc, embree_tiles[wi[k]], &cf, p, 0, &hw[k]);
			double te = now_ms() - t0;
			best_w[k] = te < best_w[k] ? te : best_w[k];
		}
		t0 = now_ms();
		rays_o = ours_frame(&w.m, &cf, p, stack, &ho);
		double to = now_ms() - t0;
		best_o = to < best_o ? to : best_o;
	}

	/* Embree's figure: its fastest width; every width must find the same
	 * triangles (the widths share one BVH and one triangle test) */
	int fk = 0;
	for (int k = 1; k < nw; k++)
		if (best_w[k] < best_w[fk])
			fk = k;
	double best_e = best_w[fk];
	uint64_t rays_e = rays_w[fk];
	hits he = hw[fk];
	uint64_t width_diffs = 0;
	for (int k = 0; k < nw; k++)
		for (size_t i = 0; i < npix; i++)
			width_diffs += (uint64_t)(hw[k].tri[i] != he.tri[i]);

	/* Compare per pixel. A different triangle at the same distance (within
	 * a relative 1e-4) is a tie on a shared edge or coplanar faces; a
	 * different distance is a real disagreement. */
	uint64_t hits_e = 0, hits_o = 0, only_e = 0, only_o = 0, diff_tri = 0, diff_t = 0,
	         diff_t_ours = 0;
	for (size_t i = 0; i < npix; i++) {
		int a = he.tri[i] != UINT32_MAX, b = ho.tri[i] != UINT32_MAX;
		hits_e += (uint64_t)a;
		hits_o += (uint64_t)b;
		only_e += (uint64_t)(a && !b);
		only_o += (uint64_t)(b && !a);
		int differ = a != b;
		if (a && b && he.tri[i] != ho.tri[i]) {
			diff_tri++;
			float tol = 1e-4f * fmaxf(fabsf(he.t[i]), fabsf(ho.t[i]));
			if (fabsf(he.t[i] - ho.t[i]) > tol) {
				diff_t++;
				diff_t_ours += (uint64_t)(ho.t[i] < he.t[i]);
			}
			differ = 1;
		}
		if (differ && list_diffs > 0) {
			list_diffs--;
			fprintf(stderr,
			        "pixel %zu,%zu: embree tri %ld t %.9g, ours tri %ld t %.9g\n",
			        i % (size_t)width, i / (size_t)width, a ? (long)he.tri[i] : -1L,
			        (double)he.t[i], b ? (long)ho.tri[i] : -1L, (double)ho.t[i]);
		}
	}

	printf("view=%s\n", w.v.name);
	printf("triangles=%u\n", w.s.ntris);
	printf("size=%dx%d\n", width, height);
	printf("embree_version=%d.%d.%d\n", RTC_VERSION_MAJOR, RTC_VERSION_MINOR,
	       RTC_VERSION_PATCH);
	printf("embree_quality=%s\n", qname);
	printf("embree_robust=%d\n", robust);
	printf("runs=%d\n", runs);
	printf("rays=%llu\n", (unsigned long long)rays_e);
	printf("embree_build_ms=%.1f\n", embree_build_ms);
	printf("embree_packet=%d\n", embree_widths[wi[fk]]);
	for (int k = 0; k < nw; k++) {
		printf("embree%d_mrays=%.3f\n", embree_widths[wi[k]],
		       (double)rays_w[k] / (best_w[k] * 1e3));
		printf("embree%d_trav_only_mrays=%.3f\n", embree_widths[wi[k]],
		       (double)rays_w[k] / ((best_w[k] - best_g) * 1e3));
	}
	printf("embree_width_diffs=%llu\n", (unsigned long long)width_diffs);
	printf("embree_ms=%.2f\n", best_e);
	printf("embree_mrays=%.3f\n", (double)rays_e / (best_e * 1e3));
	printf("embree_hits=%llu\n", (unsigned long long)hits_e);
	printf("ours_trace_ms=%.2f\n", best_o);
	printf("ours_trace_mrays=%.3f\n", (double)rays_o / (best_o * 1e3));
	printf("ours_hits=%llu\n", (unsigned long long)hits_o);
	/* traversal alone: the ray generation's best time taken out of both */
	printf("gen_ms=%.2f\n", best_g);
	printf("embree_trav_only_mrays=%.3f\n", (double)rays_e / ((best_e - best_g) * 1e3));
	printf("ours_trav_only_mrays=%.3f\n", (double)rays_o / ((best_o - best_g) * 1e3));
	printf("hit_only_embree=%llu\n", (unsigned long long)only_e);
	printf("hit_only_ours=%llu\n", (unsigned long long)only_o);
	printf("diff_triangle=%llu\n", (unsigned long long)diff_tri);
	printf("diff_triangle_and_t=%llu\n", (unsigned long long)diff_t);
	printf("diff_t_ours_closer=%llu\n", (unsigned long long)diff_t_ours);

	for (int k = 0; k < nw; k++) {
		free(hw[k].tri);
		free(hw[k].t);
	}
	free(ho.tri);
	free(ho.t);
	free(p);
	free(stack);
	rtcReleaseScene(sc);
	rtcReleaseDevice(dev);
	world_free(&w);
	return 0;
}
