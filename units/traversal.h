/*
 * traversal.h: the traversal unit (SaarCOR seed 002 §4.1: "the traversal
 * unit traverses the ray through the spatial index structure ... until a
 * leaf-node is reached").
 *
 * One operation = one pkt_trav_next() step for the whole packet: the kd-node
 * is read through the KD memory port (8 bytes), then the unit spends
 * ceil(rays/width) issue cycles + latency on it. A leaf goes to the list
 * unit; TRAV_DONE goes to the RGS for shading. pkt_trav_begin (the
 * scene-box clip) is part of ray set-up and costs no unit time; a packet
 * whose rays all miss the box skips the core (counted).
 *
 * Stack: the hardware stack holds chip.stack_depth entries. A push beyond
 * it spills the entry to memory (a posted KD write of
 * THR_STACK_ENTRY_BYTES, counted as a stack overflow); popping such an
 * entry reads it back (a KD read the step waits for, counted as a refill;
 * the node read follows it, since the entry names the node).
 * The functional stack (kernel-ref) always has PKT_STACK_MAX entries, so
 * the image never depends on the depth.
 */
#ifndef SAAR_UNITS_TRAVERSAL_H
#define SAAR_UNITS_TRAVERSAL_H

#include "thread.h"

/* The thread's packet enters the ray-tracing core. */
void tu_begin(thr_ctx *t);
/* The next traversal step (after a leaf's triangles, or a node). */
void tu_step(thr_ctx *t);

#endif
