/*
 * traversal.h: the traversal unit (SaarCOR seed 002 §4.1: "the traversal
 * unit traverses the ray through the spatial index structure ... until a
 * leaf-node is reached").
 *
 * One operation = one pkt_trav_next() step for the whole packet, in its
 * two halves: pkt_trav_pop picks the node, the node's 8 bytes are read
 * through the KD memory port, and pkt_trav_node steps on the bytes the
 * read returned; then the unit spends ceil(rays/width) issue cycles +
 * latency on it. A leaf goes to the list unit (route.leaf); TRAV_DONE
 * goes to the RGS for shading (route.finish): the route the chip wires,
 * units/unit_table.h. pkt_trav_begin (the scene-box clip against the box the
 * host sets) is part of ray set-up and costs no unit time; a packet whose
 * rays all miss the box skips the core (counted).
 *
 * Stack: the hardware stack holds chip.stack_depth entries. A push beyond
 * it spills the entry to memory (a posted KD write of the entry's
 * THR_STACK_ENTRY_BYTES, counted as a stack overflow), after the node read
 * that made it; popping such an entry reads it back (a KD read the step
 * waits for, counted as a refill; the node read follows it, since the
 * entry names the node), and the pop works on the bytes it returned. The
 * functional stack (kernel-ref's) has PKT_STACK_MAX entries; those past
 * the depth are overwritten by what memory returns before they are
 * popped, so a spill that does not come back intact changes the image.
 */
#ifndef SAAR_UNITS_TRAVERSAL_H
#define SAAR_UNITS_TRAVERSAL_H

#include "units/thread.h"

/* The thread's packet enters the ray-tracing core. */
void tu_begin(thr_ctx *t);
/* The same inside an instance of a two-level scene (route.object): the
 * tree is an object's, whose box misses are no scene-box misses (the top
 * level counts those at its root, toplevel.c node_fetched). */
void tu_begin_object(thr_ctx *t);
/* The packet's rays clipped to its tree's box (the traversal state set
 * up; with scene_box, the box is the scene's and its misses are counted);
 * none entered: the packet went on to shading (route.finish) and 0 is
 * returned. The kd and grid traversal units both start this way. */
uint64_t tu_enter(thr_ctx *t, int scene_box);
/* The next traversal step (after a leaf's triangles, or a node). */
void tu_step(thr_ctx *t);

#endif
