/*
 * intersection.h: the intersection unit (SaarCOR seed 002 §4.1: "the intersection
 * unit then loads the data of a triangle and performs the intersection
 * computation").
 *
 * One operation per triangle of a leaf, in list order: the 36-byte triangle
 * record through the TRI port, at the address the list entry as read
 * holds, then ceil(rays/width) issue cycles + latency; at completion
 * pkt_isect_tri_v() (kernel-ref's watertight test) updates the packet from
 * the record's bytes as the read returned them. Shadow packets drop occluded rays after each
 * triangle and stop testing the leaf once none is left, exactly as pkt_trace does.
 */
#ifndef SAAR_UNITS_INTERSECTION_H
#define SAAR_UNITS_INTERSECTION_H

#include "units/thread.h"

/* Tests the next triangle of the current leaf, or resumes traversal
 * (route.traverse). */
void isu_next(thr_ctx *t);

#endif
