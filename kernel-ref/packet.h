/*
 * packet.h: 64-ray packets and their kd-tree traversal, one hardware
 * operation at a time.
 *
 * This is the functional heart that kernel-ref and the chip model share.
 * A packet (SaarCOR: 8x8 pixels, 64 rays) is traversed with per-ray active
 * masks and ONE shared stack (OpenRT/SaarCOR style). The traversal is a
 * state machine: pkt_trav_next() performs exactly one kd-node step, or
 * reports a leaf whose triangles the caller then tests with pkt_isect_tri()
 * (the list unit reads the entries; the intersection unit tests them).
 * kernel-ref drives it in a plain loop; the chip model drives the very same
 * calls from its traversal, list and intersection units and adds time and
 * memory traffic in between. So both see the same rays, the same node and
 * triangle addresses and the same hits.
 *
 * Hit rule, independent of visiting order: a ray keeps the hit with the
 * smallest t, ties broken by the smaller triangle address. A node is
 * skipped for a ray only when its entry distance exceeds the ray's best t
 * (strictly), so every triangle that could tie is still tested. Hence the
 * packet path, the single-ray path and any thread schedule agree exactly.
 *
 * Ray segments through a node are split at the plane distance widened by
 * its rounding-error bound (gamma(3) relative, see trav_split), so the two
 * children's segments overlap slightly rather than leave a gap a hit could
 * fall through.
 *
 * Reduced precision (pkt_precision, docs/NUMERICS.md): the chip model may
 * run traversal and intersection in narrower formats (fpfmt.h). A packet
 * picks its path once, in pkt_trav_begin_fp: full precision keeps the SIMD
 * code below untouched; a reduced stage runs a scalar emulation that rounds
 * after every operation and keeps traversal and the triangle test
 * conservative (directed rounding of segment bounds widened by the
 * format's gamma; edge functions within their error bound count as zero).
 */
#ifndef SAAR_KREF_PACKET_H
#define SAAR_KREF_PACKET_H

#include <stdint.h>

#include "kernel-ref/fpfmt.h"
#include "kernel-ref/memimage.h"

#define PKT_RAYS      64
#define PKT_NOHIT     UINT32_MAX
#define PKT_STACK_MAX 64 /* kernel-ref's stack; the chip's depth is a config key */

enum pkt_type { PKT_PRIMARY, PKT_SHADOW, PKT_REFLECT, PKT_REFRACT, PKT_NTYPES };

/* A packet of up to 64 self-contained rays. Secondary rays carry their
 * pixel and weight, so a packet can finish in any order. Arrays are 32-byte
 * aligned, laid out lane by lane for the SIMD groups (simd.h). */
typedef struct packet {
	float ox[PKT_RAYS], oy[PKT_RAYS], oz[PKT_RAYS];
	float dx[PKT_RAYS], dy[PKT_RAYS], dz[PKT_RAYS];
	float tmax[PKT_RAYS]; /* segment end: light distance for shadow rays */
	/* payload */
	uint32_t pixel[PKT_RAYS];                       /* y * width + x */
	float wr[PKT_RAYS], wg[PKT_RAYS], wb[PKT_RAYS]; /* weight; shadow: the contribution */
	/* results: closest hit; a shadow ray is occluded when tri != PKT_NOHIT
	 * (its t is then -inf, so traversal drops it at once) */
	float t[PKT_RAYS];
	uint32_t tri[PKT_RAYS];           /* triangle record address, PKT_NOHIT if none */
	float bu[PKT_RAYS], bv[PKT_RAYS]; /* barycentrics of v1 and v2 */
	/* two-level scenes (twolevel.h): the hit's instance, the index of its
	 * record in the top level (BVH leaf order), whose transforms the
	 * shader moves the object-space hit into the world with; unused (0)
	 * for a single tree */
	uint32_t inst[PKT_RAYS];
	uint64_t valid; /* rays present */
	uint32_t n;     /* number of rays (lanes 0..n-1 may be valid) */
	uint8_t type, depth;
	uint16_t sample; /* the pixels' sample index (drt.h); children inherit it */
} __attribute__((aligned(32))) packet;

/* Zeroes a packet and sets its type and depth (camera.c). */
void pkt_clear(packet *p, int type, int depth);

/* Per-ray constants for the watertight test (Woop et al., JCGT 2013):
 * the axis permutation kx,ky,kz (kz = dominant direction axis) as lane
 * masks, and the shear Sx,Sy,Sz. */
typedef struct pkt_rayc {
	float sx[PKT_RAYS], sy[PKT_RAYS], sz[PKT_RAYS];
	int32_t kz0[PKT_RAYS], kz1[PKT_RAYS], kx0[PKT_RAYS], kx1[PKT_RAYS], ky0[PKT_RAYS],
	    ky1[PKT_RAYS];                                 /* all-ones when kz==0 / kz==1, etc. */
	float idx[PKT_RAYS], idy[PKT_RAYS], idz[PKT_RAYS]; /* 1/d */
	/* When every ray shares one permutation (coherent packets, nearly
	 * always), origins pre-permuted so the test needs no lane selects. */
	float okx[PKT_RAYS], oky[PKT_RAYS], okz[PKT_RAYS];
	int uniform, ukx, uky, ukz;
} __attribute__((aligned(32))) pkt_rayc;

typedef struct trav_entry {
	uint32_t node;
	uint64_t mask;
	float tn[PKT_RAYS], tf[PKT_RAYS];
} __attribute__((aligned(32))) trav_entry;

enum trav_op {
	TRAV_NODE, /* one inner-node step was done */
	TRAV_LEAF, /* a leaf was reached: test its list, then call again */
	TRAV_DONE  /* no work left: every ray finished or left the scene */
};

/* What one operation touched, for the chip model's timing and traffic. */
typedef struct trav_result {
	int op;
	uint32_t node;       /* node index read (TRAV_NODE, TRAV_LEAF) */
	uint64_t mask;       /* active rays in this operation */
	uint32_t leaf_first; /* TRAV_LEAF: first list entry index */
	uint32_t leaf_count; /* TRAV_LEAF: number of entries */
	int pushed, popped;  /* stack entries pushed / popped by this step */
	int sp;              /* stack depth after the step */
} trav_result;

/* Per-stage formats of the shared math. The identity format (fpfmt_full)
 * in a stage keeps that stage on the full-precision path. */
typedef struct pkt_precision {
	fpfmt trav;  /* traversal: split distances, scene-box clip */
	fpfmt isect; /* intersection: the Woop test */
	fpfmt shade; /* shading (shade_ctx.fp): colours, normals, directions */
} pkt_precision;

/* All three stages at full precision (the reference). */
void pkt_precision_full(pkt_precision *pp);

typedef struct trav_state {
	pkt_rayc rc;
	trav_entry cur; /* node being worked on and its per-ray segments */
	trav_entry
	    spare; /* far-child scratch when the stack is full (never, by kd_build's depth cap) */
	trav_entry *stack;
	int sp, stack_max;
	int shadow; /* any-hit packet: a ray stops at its first occluder */
	/* reduced formats of this packet's traversal and intersection; NULL:
	 * full precision (the SIMD path). Set once by pkt_trav_begin_fp. */
	const fpfmt *fpt, *fpi;
} trav_state;

/* Prepares traversal of p through the image's tree. Clips every valid ray
 * to the scene box; returns the mask of rays that enter it (0: the packet
 * skips the core). stack points at stack_max entries owned by the caller;
 * stack_max must exceed the tree depth (PKT_STACK_MAX always does: kd_build
 * caps the depth below it). A smaller hardware stack is the chip model's
 * business: it sees trav_result.sp and charges spills and refills. */
uint64_t pkt_trav_begin(trav_state *s, packet *p, const mimg *m, trav_entry *stack, int stack_max);

/* The same with per-stage formats (prec NULL, or full formats: exactly
 * pkt_trav_begin). prec must outlive the packet's traversal: the state
 * keeps pointers into it. Its shade member is not used here. */
uint64_t pkt_trav_begin_fp(trav_state *s, packet *p, const mimg *m, trav_entry *stack,
                           int stack_max, const pkt_precision *prec);

/* Performs one traversal operation: pops finished work (rays whose best hit
 * lies before an entry's segment leave it), then either steps one inner
 * node (near child next, far child pushed when both are needed) or reports
 * a leaf. */
void pkt_trav_next(trav_state *s, packet *p, const mimg *m, trav_result *r);

/* Mistakes made on purpose in pkt_trav_next, so a test can show that a
 * check catches them (SQLite's fault injection; docs/TESTING.md "Checks
 * that can fail"). Every program leaves pkt_trav_fault at PKT_FAULT_NONE;
 * only tests set it, in their own process. The chip and kernel-ref's
 * packet render both step through pkt_trav_next, so a fault changes both
 * alike; the single-ray path (ray_trace) has its own traversal and does
 * not see it.
 *   PKT_FAULT_NO_FAR_PUSH: the far child is never pushed (rays that need
 *     it lose their hits there: a wrong image).
 *   PKT_FAULT_FAR_FIRST: the far child is visited first and the near one
 *     pushed (back-to-front: more steps and triangle tests, the same
 *     image by the hit rule). */
enum pkt_fault { PKT_FAULT_NONE, PKT_FAULT_NO_FAR_PUSH, PKT_FAULT_FAR_FIRST };
extern int pkt_trav_fault;

/* pkt_trav_next in two halves, for a caller that reads the node itself
 * (the chip model's traversal unit, through its memory). pkt_trav_pop pops
 * finished work: 0 when none is left (r->op = TRAV_DONE), else 1 with
 * r->node the node to visit (at mimg_node_addr) and r->mask its rays;
 * pkt_trav_node then does the step on that node's 8 bytes n. The two are
 * exactly pkt_trav_next. */
int pkt_trav_pop(trav_state *s, packet *p, trav_result *r);
void pkt_trav_node(trav_state *s, packet *p, kd_node n, trav_result *r);
/* How many stack entries the next pkt_trav_pop pops (entries looked at
 * from the top down to the first with live rays), without popping: the
 * chip reads spilled entries back before it pops them. */
int pkt_trav_pops(const trav_state *s, const packet *p);

/* Tests the rays in `mask` against the triangle at tri_addr; updates
 * closest hits (shadow packets: marks occlusion). Returns the mask of rays
 * whose result changed. */
uint64_t pkt_isect_tri(trav_state *s, packet *p, const mimg *m, uint64_t mask, uint32_t tri_addr);
/* The same on the triangle record's 36 bytes as fetched (tri_addr is
 * only the hit's name). */
uint64_t pkt_isect_tri_v(trav_state *s, packet *p, const mimg_tri *tri, uint64_t mask,
                         uint32_t tri_addr);

/* Convenience: the whole traversal in a loop (kernel-ref). Counts into the
 * optional counters; returns the mask of rays that entered the scene box. */
typedef struct trav_counts {
	uint64_t node_steps, leaf_visits, tri_tests, ray_tri_tests, max_sp;
	/* cone culling (cone.h, pkt_trace_cone): triangles a packet skipped,
	 * and the active rays they would have tested */
	uint64_t cone_culled, cone_saved_ray_tests;
} trav_counts;
uint64_t pkt_trace(packet *p, const mimg *m, trav_entry *stack, int stack_max, trav_counts *c);
uint64_t pkt_trace_fp(packet *p, const mimg *m, trav_entry *stack, int stack_max, trav_counts *c,
                      const pkt_precision *prec);

/* The per-lane traversal loop of pkt_trace_cone after pkt_trav_begin_fp
 * (cone: the packet's cone when culling, else NULL), and its leaf step:
 * the rays of mask tested against the leaf's list entries first..
 * first+count-1 (a shadow ray stops at its first occluder), counted into c
 * (optional). frustum.c's loop shares the leaf step through hooks (NULL:
 * none): isect (NULL: pkt_isect_tri) tests one triangle, finding the same
 * hits; prefetch fetches the leaf's triangles ahead before the first is
 * tested. Where no cone culls and the packet's rays share one axis
 * permutation (pkt_rayc.uniform), frustum.c's fru_leaf tests a leaf
 * itself, with the same counts. */
struct pkt_cone;
typedef struct pkt_leaf_hooks {
	void (*isect)(trav_state *s, packet *p, const mimg_tri *t, uint64_t mask,
	              uint32_t tri_addr);
	int prefetch;
} pkt_leaf_hooks;
void pkt_trace_leaf(trav_state *s, packet *p, const mimg *m, uint32_t first, uint32_t count,
                    uint64_t mask, const struct pkt_cone *cone, trav_counts *c,
                    const pkt_leaf_hooks *hk);
/* The lanes of mask still open after a leaf's triangle was tested for a
 * shadow packet: an occluded shadow ray (one with a hit) stops there.
 * pkt_trace_leaf's step, and fru_leaf's (frustum.c) where it tests a
 * leaf itself. */
static inline uint64_t pkt_shadow_open(const packet *p, uint64_t mask)
{
	for (uint64_t b = mask; b; b &= b - 1) {
		int i = __builtin_ctzll(b);
		if (p->tri[i] != PKT_NOHIT)
			mask &= ~(1ull << i);
	}
	return mask;
}
void pkt_trace_run(trav_state *s, packet *p, const mimg *m, const struct pkt_cone *cone,
                   trav_counts *c);
/* pkt_trace_cone with another loop: the packet enters the scene's box
 * (pkt_trav_begin_fp) and gets its cone when culling, then run (entered:
 * the rays that entered) walks the tree and returns 1, or returns 0 to
 * leave the packet to pkt_trace_run. run NULL: pkt_trace_run. frustum.c's
 * fru_trace is pkt_trace_cone with its own run. */
typedef int (*pkt_runner)(trav_state *s, packet *p, const mimg *m, const struct pkt_cone *cone,
                          uint64_t entered, trav_counts *c);
uint64_t pkt_trace_with(packet *p, const mimg *m, trav_entry *stack, int stack_max, trav_counts *c,
                        const pkt_precision *prec, int cull, pkt_runner run);

/* ---- single-ray path, for checking ---- */
typedef struct ray_hit {
	float t, bu, bv;
	uint32_t tri;  /* PKT_NOHIT if none */
	uint32_t inst; /* two-level: the hit's instance record (packet.inst); else 0 */
} ray_hit;

/* Closest hit (or, with any_hit, the first occluder) in (0, tmax) by plain
 * scalar kd-tree traversal; the same intersection math as the packets. */
ray_hit ray_trace(const mimg *m, vec3 o, vec3 d, float tmax, int any_hit, trav_counts *c);
/* The same with per-stage formats; bit-identical to the packet path with
 * the same formats. */
ray_hit ray_trace_fp(const mimg *m, vec3 o, vec3 d, float tmax, int any_hit, trav_counts *c,
                     const pkt_precision *prec);
/* The same walk over m's kd-tree (full precision) with another leaf test:
 * leaf(ctx, list, count, h) tests the leaf's triangle addresses, keeps
 * the better hit in *h by isect_better, and returns 1 to end the walk.
 * tlflat.c tests each triangle in its object's space this way. */
typedef int (*ray_leaf_fn)(void *ctx, const uint32_t *list, uint32_t count, ray_hit *h);
ray_hit ray_trace_leaves(const mimg *m, vec3 o, vec3 d, float tmax, trav_counts *c,
                         ray_leaf_fn leaf, void *ctx);

#endif
