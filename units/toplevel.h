/*
 * toplevel.h: the top level of a two-level scene, and the transformation
 * unit (seed 002 §6; Schmittler, Woop, Wagner, Paul, Slusallek, "Realtime
 * Ray Tracing of Dynamic Scenes on an FPGA Chip", Graphics Hardware 2004).
 *
 * A packet walks the top-level BVH over the instances (kernel-ref/
 * twolevel.h, laid out by kernel-ref/tlimage.h): each node's record is
 * read (KD) and its box tested by the traversal unit (one op of the rays
 * tested); at a leaf each instance record is read (KD) and its world box
 * tested (a traversal op); the rays that enter are moved into the
 * object's space by the transformation unit (one op of those rays:
 * tl_pkt_to_object) and traced through the object's kd-tree by the usual
 * traversal, list and intersection units, whose addresses come from the
 * record (thr_ctx.img). When that traversal ends its hits are named in
 * the world image through the triangle map (one LIST read per hit ray)
 * and taken into the world packet (tl_pkt_merge); the walk goes on. When
 * it is over the packet is shaded as for a single tree. Every decision is
 * made on the bytes the reads returned, with kernel-ref's functions in
 * tl_pkt_trace's order, so the frame is kernel-ref's two-level frame.
 */
#ifndef SAAR_UNITS_TOPLEVEL_H
#define SAAR_UNITS_TOPLEVEL_H

#include "units/thread.h"

/* route.enter for two-level scenes: the packet starts the top level. */
void tlu_enter(thr_ctx *t);
/* route.finish for two-level scenes: an object's traversal is over (its
 * hits go back to the world packet), or the walk is (shading). */
void tlu_finish(thr_ctx *t);

#endif
