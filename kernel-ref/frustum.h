/*
 * frustum.h: kernel-ref's own packet traversal loop: the per-lane kd-tree
 * traversal of packet.h with a packet-wide shortcut by interval
 * arithmetic (rtref's default packet path; the chip steps through
 * packet.h's functions alone).
 *
 * At an inner node the per-lane step cuts each of the 64 rays' segments
 * [tn_i, tf_i] at the split plane. Often the plane cuts none of them: it
 * lies beyond every segment (each ray stays in the near child) or before
 * every segment (each ray is in the far child only). Whether it does is
 * decided for the whole packet from intervals, without per-ray work: the
 * rays' distances to the plane lie within the interval that their origins'
 * and inverse directions' intervals give, and their segments within
 * bounds [tn, tf] carried along the walk (Wald, "Realtime Ray Tracing and
 * Interactive Global Illumination", PhD thesis 2004, §7.2 on packet
 * traversal; Reshetov, Soupikov, Hurley, "Multi-Level Ray Tracing
 * Algorithm", SIGGRAPH 2005, §3; interval arithmetic over rays of
 * different origins as in Wald, Boulos, Shirley 2006 [WBS06], which seed
 * 000 "Interactive Distribution Ray Tracing" §3 builds on). Then only the node index changes;
 * otherwise (the plane cuts some segment, or the rays' directions on the
 * split axis have both signs or a zero) the per-lane step runs: the
 * arithmetic of pkt_trav_node, with its selects resolved once where the
 * rays' directions have one sign on the axis. The walk is frustum.c's
 * own (pkt_trav_pop's and pkt_trav_node's order of pops and steps, with
 * the segment buffers changing hands instead of being copied, and the
 * next nodes and a leaf's triangles fetched ahead).
 *
 * Exactly the per-lane traversal: where the shortcut applies the per-lane
 * step would have left every segment and the mask as they are, so the
 * same nodes are visited with the same rays and segments, the same
 * triangles tested, the same hits found and the same work counted
 * (trav_counts); only the time differs. tests/test_frustum.c checks it
 * hit for hit and count for count.
 */
#ifndef SAAR_KREF_FRUSTUM_H
#define SAAR_KREF_FRUSTUM_H

#include "kernel-ref/packet.h"

/* Traces p exactly as pkt_trace_cone does (same arguments, the same
 * returned mask of rays that entered the scene box, the same hits and
 * counts), with the packet shortcut where fru_coherent allows it. */
uint64_t fru_trace(packet *p, const mimg *m, trav_entry *stack, int stack_max, trav_counts *c,
                   const pkt_precision *prec, int cull);

/* Whether fru_trace may take the shortcut for p, given the state
 * pkt_trav_begin_fp left (entered: its result): full precision, no
 * planted pkt_trav_fault, and some axis on which every entered ray's
 * direction has one sign and no zero. For tests. */
int fru_coherent(const trav_state *s, const packet *p, uint64_t entered);

/* Mistakes planted on purpose (docs/TESTING.md "Checks that can fail"),
 * set only by tests, in their own process:
 *   FRU_FAULT_ALWAYS_NEAR: the packet shortcut takes the near child where
 *     every ray needs only the far one (they lose their hits there);
 *   FRU_FAULT_ONE_DIRECTION: the plane-distance interval uses the first
 *     ray's 1/d for all (the packet segment then misses the other rays'
 *     crossings: rays lose hits in children it wrongly skips);
 *   FRU_FAULT_POP_ALL: a pop keeps every ray of the entry, also those
 *     whose best hit lies before its segment (more work counted);
 *   FRU_FAULT_STALE_SEGMENTS: a pop takes the entry's node and rays but
 *     leaves the current segment buffer in place of the entry's (the
 *     buffers change hands instead of being copied: rays step with
 *     another node's segments);
 *   FRU_FAULT_BARY_SWAP: the leaf test's late barycentric division
 *     divides the wrong edge function for bu (w in place of v);
 *   FRU_FAULT_TRI_SHADOW_LAST: the triangle-parallel leaf test
 *     (fru_tri_path) records a shadow ray's last occluder among a chunk
 *     of triangles instead of its first;
 *   FRU_FAULT_TRI_ONE_CHUNK: the triangle-parallel leaf test tests only
 *     the first SIMD_W triangles of a leaf. */
enum fru_fault {
	FRU_FAULT_NONE,
	FRU_FAULT_ALWAYS_NEAR,
	FRU_FAULT_ONE_DIRECTION,
	FRU_FAULT_POP_ALL,
	FRU_FAULT_STALE_SEGMENTS,
	FRU_FAULT_BARY_SWAP,
	FRU_FAULT_TRI_SHADOW_LAST,
	FRU_FAULT_TRI_ONE_CHUNK
};
extern int fru_fault;

/* How fru_trace's leaf test (rays of one axis permutation, no cone
 * culling) takes a leaf: FRU_TRI_AUTO, triangle-parallel (each ray
 * against SIMD_W of the leaf's triangles at once) where that takes fewer
 * vector tests than triangle by triangle over the rays' lane groups, the
 * sparse packets that reach small cells; FRU_TRI_NEVER and FRU_TRI_ALWAYS
 * one way for every leaf. The same hits and counts whichever way (the
 * same floats for each ray and triangle, the first occluder of a shadow
 * ray in the leaf's order). Tests set fru_tri_path; rtref keeps AUTO. */
enum fru_tri { FRU_TRI_AUTO, FRU_TRI_NEVER, FRU_TRI_ALWAYS };
extern int fru_tri_path;

#endif
