/*
 * test_chip_reads.c: the chip's memory requests are the reads its packets'
 * work needs, request for request. The chip's frame is recorded with
 * chip_trace_mem (traces/memtrace.h); the test walks the same frame with
 * kernel-ref's functions itself (camera packets, the traversal state
 * machine, the triangle test, the shader with its read log), packet by
 * packet as render.c does, and lists the reads each step implies: a kd-node
 * step reads its node, a non-empty leaf its list entries, each tested
 * triangle its record, a shaded packet each distinct logged read once. The
 * two lists must be equal as multisets (the chip's order differs). So a
 * unit that reads the wrong address, or drops or adds reads, fails even
 * when the image stays right (the memory model carries no data).
 */
#include <stdlib.h>
#include <string.h>

#include "kernel-ref/packet.h"
#include "kernel-ref/render.h"
#include "tests/chiptest.h"
#include "tests/handmade.h"
#include "traces/memtrace.h"

typedef struct rd {
	uint64_t addr;
	uint32_t bytes;
} rd;

typedef struct rdlist {
	rd *e;
	size_t n, cap;
} rdlist;

static void put(rdlist *l, uint64_t addr, uint32_t bytes)
{
	if (l->n == l->cap) {
		l->cap = l->cap ? 2 * l->cap : 4096;
		l->e = realloc(l->e, l->cap * sizeof *l->e);
		cr_assert(l->e, "out of memory");
	}
	l->e[l->n++] = (rd){addr, bytes};
}

static int rd_cmp(const void *a, const void *b)
{
	const rd *x = a, *y = b;
	if (x->addr != y->addr)
		return x->addr < y->addr ? -1 : 1;
	return (x->bytes > y->bytes) - (x->bytes < y->bytes);
}

/* What a frame's packets read, by requester type, and how many packets of
 * each type there were. */
typedef struct walk {
	rdlist r[MEM_NTYPES];
	uint64_t packets[PKT_NTYPES];
} walk;

static void walk_free(walk *k)
{
	for (int t = 0; t < MEM_NTYPES; t++)
		free(k->r[t].e);
}

/* One packet through the tree as pkt_trace does it, listing its reads. */
static void walk_trace(walk *k, trav_state *s, packet *p, const mimg *m, trav_entry *stack)
{
	if (!pkt_trav_begin(s, p, m, stack, PKT_STACK_MAX))
		return;
	const uint32_t *lists = mimg_lists(m);
	for (;;) {
		trav_result r;
		pkt_trav_next(s, p, m, &r);
		if (r.op == TRAV_DONE)
			return;
		put(&k->r[MEM_KD], mimg_node_addr(m, r.node), MIMG_NODE_BYTES);
		if (r.op != TRAV_LEAF || !r.leaf_count)
			continue;
		put(&k->r[MEM_LIST], mimg_list_addr(m, r.leaf_first),
		    r.leaf_count * MIMG_LIST_BYTES);
		uint64_t mask = r.mask;
		for (uint32_t e = 0; e < r.leaf_count && mask; e++) {
			uint32_t ta = lists[r.leaf_first + e];
			put(&k->r[MEM_TRI], ta, MIMG_TRI_BYTES);
			pkt_isect_tri(s, p, m, mask, ta);
			if (s->shadow) /* an occluded shadow ray stops */
				for (uint64_t b = mask; b; b &= b - 1)
					if (p->tri[__builtin_ctzll(b)] != PKT_NOHIT)
						mask &= ~(b & -b);
		}
	}
}

/* The frame of w at c's size and shading depth, tile by tile, each tile's
 * packets depth first (render.c's do_tile). */
static void walk_frame(walk *k, const world *w, const saar_config *c)
{
	memset(k, 0, sizeof *k);
	int W = c->frame.width, H = c->frame.height;
	cam_frame cf;
	cam_setup(&cf, &w->v.cam, W, H);
	framebuf fb;
	cr_assert_eq(fb_init(&fb, W, H), 0);
	render_opts ro;
	render_opts_default(&ro);
	shade_ctx sc = {&w->m, w->v.lights, w->v.nlights, c->shading.max_depth, ro.background, &fb,
	                NULL,  NULL,        NULL};
	int nk = w->v.nlights + 2, cap = (c->shading.max_depth + 2) * nk + 1;
	packet *work = hm_alloc((size_t)cap * sizeof *work), *kids = hm_alloc(nk * sizeof *kids);
	trav_entry *stack = hm_alloc(PKT_STACK_MAX * sizeof *stack);
	trav_state *s = hm_alloc(sizeof *s);
	shade_log log = {malloc(SHADE_LOG_CAP * sizeof(shade_read)), 0, SHADE_LOG_CAP, 0};
	rd *one = malloc(SHADE_LOG_CAP * sizeof *one);
	cr_assert(log.e && one, "out of memory");
	shade_counts cnt;
	memset(&cnt, 0, sizeof cnt);
	for (int ty = 0; ty < (H + 7) / 8; ty++)
		for (int tx = 0; tx < (W + 7) / 8; tx++) {
			int n = 0;
			cam_primary_packet(&cf, tx, ty, &work[n++]);
			while (n > 0) {
				packet *p = &work[--n];
				k->packets[p->type]++;
				walk_trace(k, s, p, &w->m, stack);
				if (p->type == PKT_SHADOW) {
					shade_shadow_done(&sc, p, &cnt);
					continue;
				}
				log.n = 0;
				int made = shade_packet(&sc, p, kids, nk, &log, &cnt);
				cr_assert_eq(log.dropped, 0);
				/* each distinct (address, size) once per packet */
				for (uint32_t i = 0; i < log.n; i++)
					one[i] = (rd){log.e[i].addr, log.e[i].bytes};
				qsort(one, log.n, sizeof *one, rd_cmp);
				for (uint32_t i = 0; i < log.n; i++)
					if (!i || rd_cmp(&one[i], &one[i - 1]))
						put(&k->r[MEM_SHADE], one[i].addr, one[i].bytes);
				for (int j = 0; j < made && n < cap; j++)
					work[n++] = kids[j];
			}
		}
	free(one);
	free(log.e);
	free(s);
	free(stack);
	free(kids);
	free(work);
	fb_free(&fb);
}

/* The chip's frame of w with its memory trace: the reads by type (KD
 * reads of the stack spill area apart, in *spill_reads), and the chip. */
static chip *chip_reads(walk *k, const world *w, const saar_config *c, uint64_t *spill_reads)
{
	char dir[64], path[128];
	tu_tmpdir(dir, sizeof dir);
	snprintf(path, sizeof path, "%s/frame.trace.gz", dir);
	diag d;
	chip *ch = chip_create(c, w, &d);
	cr_assert(ch, "%s", d.msg);
	cr_assert_eq(chip_trace_mem(ch, path, NULL, &d), 0, "%s", d.msg);
	cr_assert_eq(chip_run(ch, &d), 0, "%s", d.msg);
	cr_assert_eq(chip_trace_close(ch, &d), 0, "%s", d.msg);
	memset(k, 0, sizeof *k);
	*spill_reads = 0;
	mtr_reader *r = malloc(sizeof *r);
	cr_assert(r, "out of memory");
	cr_assert_eq(mtr_open_read(r, path, &d), 0, "%s", d.msg);
	mtr_rec x;
	int rc;
	while ((rc = mtr_read(r, &x, &d)) == 1) {
		if (x.write)
			continue;
		if (x.type == MEM_KD && x.addr >= ch->spill_base)
			++*spill_reads;
		else
			put(&k->r[x.type], x.addr, x.bytes);
	}
	cr_assert_eq(rc, 0, "%s", d.msg);
	mtr_close_read(r);
	free(r);
	unlink(path);
	rmdir(dir);
	for (int t = 0; t < PKT_NTYPES; t++) {
		char nm[64];
		snprintf(nm, sizeof nm, "packets.%s", pkt_type_name(t));
		k->packets[t] = stats_get(&ch->st, nm);
	}
	return ch;
}

/* The reads of one type, as multisets: equal, else the first difference. */
static void assert_same_reads(rdlist *want, rdlist *got, int type)
{
	const char *tn = mem_type_name(type);
	qsort(want->e, want->n, sizeof *want->e, rd_cmp);
	qsort(got->e, got->n, sizeof *got->e, rd_cmp);
	size_t i = 0;
	while (i < want->n && i < got->n && !rd_cmp(&want->e[i], &got->e[i]))
		i++;
	if (i == want->n && i == got->n)
		return;
	const rd *a = i < want->n ? &want->e[i] : NULL, *b = i < got->n ? &got->e[i] : NULL;
	cr_assert_fail("%s reads: the chip made %zu, the packets' work needs %zu; first "
	               "difference at #%zu: needed %llu (%u bytes), chip %llu (%u bytes)",
	               tn, got->n, want->n, i, a ? (unsigned long long)a->addr : 0ull,
	               a ? a->bytes : 0u, b ? (unsigned long long)b->addr : 0ull,
	               b ? b->bytes : 0u);
}

/* The embedded room at 48x48 walked both ways: kernel-ref's reads and
 * packets into want, the chip's into got; the chip is returned. */
static chip *both_walks(world *w, saar_config *c, walk *want, walk *got, uint64_t *spills)
{
	tu_load_world(w, NULL, NULL, NULL);
	cfg_defaults(c);
	c->frame.width = c->frame.height = 48;
	walk_frame(want, w, c);
	return chip_reads(got, w, c, spills);
}

/* The reads of one type of a frame of the embedded room (mirror and glass
 * spheres: reflection, refraction and shadow packets) at 48x48, both ways. */
static void frame_reads(int type)
{
	world w;
	saar_config c;
	walk want, got;
	uint64_t spills;
	chip *ch = both_walks(&w, &c, &want, &got, &spills);
	cr_assert_eq(spills, 0, "a 64-entry stack spilled");
	cr_assert_gt(want.r[type].n, 100, "the frame reads little of type %s", mem_type_name(type));
	assert_same_reads(&want.r[type], &got.r[type], type);
	chip_destroy(ch);
	walk_free(&want);
	walk_free(&got);
	world_free(&w);
}

/* Mistake: the traversal unit fetches every kd node from the wrong address
 * (the root's, mimg_node_addr(m, 0), or a neighbour's): the image is still
 * right, since the node itself comes from the shared state machine. The
 * chip's KD reads must be the nodes its packets step through, each as often
 * as kernel-ref's traversal of the same packets steps through it. */
Test(chip_reads, kd_reads_are_the_nodes_stepped)
{
	frame_reads(MEM_KD);
}

/* Mistake: the list unit reads the wrong entries or the intersection unit
 * fetches the wrong triangle records (or skips the fetch). */
Test(chip_reads, list_and_triangle_reads_are_the_leaves_tested)
{
	frame_reads(MEM_LIST);
	frame_reads(MEM_TRI);
}

/* Mistake: the RGS does not issue the shader's reads (normals, materials,
 * triangle records, texels), or issues them more than once per packet.
 * The SHADE reads must be each packet's distinct logged reads. */
Test(chip_reads, shading_reads_are_the_logged_reads)
{
	frame_reads(MEM_SHADE);
}

/* Mistake: the RGS does not spawn a shaded packet's children (shadow,
 * reflection, refraction packets), or spawns them twice. The chip must
 * trace exactly the packets of each type kernel-ref's walk makes, and
 * count each secondary one as spawned. */
Test(chip_reads, children_are_spawned_as_kernel_ref)
{
	world w;
	saar_config c;
	walk want, got;
	uint64_t spills;
	chip *ch = both_walks(&w, &c, &want, &got, &spills);
	uint64_t secondary = 0;
	for (int t = 0; t < PKT_NTYPES; t++) {
		cr_assert_eq(got.packets[t], want.packets[t],
		             "%s packets: chip %llu, kernel-ref %llu", pkt_type_name(t),
		             (unsigned long long)got.packets[t],
		             (unsigned long long)want.packets[t]);
		secondary += t == PKT_PRIMARY ? 0 : want.packets[t];
	}
	cr_assert_gt(want.packets[PKT_SHADOW], 0);
	cr_assert_gt(want.packets[PKT_REFLECT], 0);
	cr_assert_gt(want.packets[PKT_REFRACT], 0);
	cr_assert_eq(stats_get(&ch->st, "rgs.spawned_packets"), secondary);
	chip_destroy(ch);
	walk_free(&want);
	walk_free(&got);
	world_free(&w);
}
