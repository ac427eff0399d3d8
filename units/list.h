/*
 * list.h: the list unit (SaarCOR seed 002 §4.1: "leaf-nodes store lists of
 * triangle addresses, which are then fetched by the list unit").
 *
 * One operation per non-empty leaf: the leaf's entries (4 bytes each, one
 * contiguous request through the LIST port, into the thread's list buffer),
 * then ceil(rays/width) issue cycles + latency; the intersection unit then
 * tests the entries in list order, the triangle addresses as the read
 * returned them (route.triangles). An empty leaf goes straight back to
 * traversal (route.traverse; counted).
 */
#ifndef SAAR_UNITS_LIST_H
#define SAAR_UNITS_LIST_H

#include "units/thread.h"

/* The thread's last traversal step reached a leaf (t->r). */
void list_leaf(thr_ctx *t);

/* Room for n list entries in the thread's buffer t->list (it grows to the
 * largest leaf or grid cell read; the grid unit's cell reads use it too).
 * 0, or -1 when memory ran out. */
int list_room(thr_ctx *t, uint32_t n);

#endif
