/*
 * gridtrav.h: the grid traversal unit (issue 34; seed 003, Wald, Ize,
 * Kensler, Knoll, Parker, "Ray Tracing Animated Scenes using Coherent
 * Grid Traversal", SIGGRAPH 2006), the traversal unit kind walking a
 * uniform grid instead of a kd-tree (chip.accel grid).
 *
 * A packet's walk is kernel-ref's grid_walk (kernel-ref/gridwalk.h), the
 * step-by-step form of grid_pkt_trace; each of its asks is a read of the
 * grid's image (kernel-ref/gridimage.h, docs/memory-map.md "Uniform
 * grid") and an op of the unit kind that does that work:
 *
 *   macrocell flag (§2.4): 1 byte (KD), a traversal op of the live rays;
 *   cell (§2.2): its two list offsets, 8 bytes (KD), a traversal op;
 *   the cell's entries: count x 4 bytes (LIST), a list op;
 *   a triangle not in the packet's mailbox (§2.3): its record (TRI), an
 *     intersection op of the live rays, or, culled by the frustum, a
 *     packet-level op (one cycle, as the cone test).
 *
 * Rays the frustum cannot hold (scattered origins, a sign or slope apart,
 * seed 003 §4.7) go alone through the 3D DDA within the same walk: the
 * same reads and unit kinds, each op one ray wide (a DDA step is an op of
 * the traversal unit), and the single ray's triangle test. Every decision
 * is made on the bytes the reads returned, in grid_pkt_trace's order, so
 * the frame is kernel-ref's grid frame (which is its kd frame).
 */
#ifndef SAAR_UNITS_GRIDTRAV_H
#define SAAR_UNITS_GRIDTRAV_H

#include "units/thread.h"

/* route.enter and route.traverse with a grid: the packet's walk. */
void gtu_begin(thr_ctx *t);

#endif
