/*
 * rgs.h: the ray-generation and shading unit, one per RTP (SaarCOR seed
 * 002 §4.1, §4.3).
 *
 * Three jobs, each one RGS operation (ceil(rays/width) issue cycles +
 * latency):
 *  - primary rays: cam_sample_packet for a tile the RGC handed out, then
 *    the packet enters the ray-tracing core; with spp samples per pixel
 *    (kernel-ref/drt.h) the tile's other spp - 1 primary packets are
 *    made at once and queued like children, and the thread that takes
 *    one generates it with its own RGS op (rgs_secondary);
 *  - shading a traced primary/reflection/refraction packet:
 *    shade_packet_rd() (kernel-ref) adds each ray's direct terms into the
 *    frame buffer and makes the child packets (one shadow packet per light,
 *    reflection, refraction); every scene read it makes goes through the
 *    SHADE memory port, identical (address, size) reads of one packet
 *    coalesced into one request (a packet shares its data: seed 002 §4.1),
 *    and its results are those of the bytes the reads returned (rgs.c:
 *    the addresses are found first, the results made when the reads are
 *    in);
 *  - finishing a shadow packet: shade_shadow_done() adds the unoccluded
 *    rays' contributions.
 * Child packets are self-contained; they queue per RTP (FIFO) for a thread
 * slot, and a freed thread takes a queued packet before a new tile.
 * Frame-buffer adds go to the on-board frame buffer, not through memory.
 */
#ifndef SAAR_UNITS_RGS_H
#define SAAR_UNITS_RGS_H

#include "units/thread.h"

/* Generates the primary packet of tile (tx, ty) on thread t; -1 if out of
 * memory. */
int rgs_primary(thr_ctx *t, int tx, int ty);
/* Starts thread t on a queued secondary packet. */
void rgs_secondary(thr_ctx *t, packet *p);
/* Traversal is over: shade (or finish the shadow packet), then free t. */
void rgs_finish(thr_ctx *t);
/* RTP r's FIFO of secondary packets: queues a child shading made,
 * counted as spawned (-1 when out of memory); after a packet's children,
 * rgs_spawned samples the queue length; rgs_dequeue takes the oldest (0
 * when empty). */
int rgs_spawn(thr_rtp *r, thr_qitem it);
void rgs_spawned(thr_rtp *r);
int rgs_dequeue(thr_rtp *r, thr_qitem *it);
/* The queue's length and its i-th oldest item (i < rgs_queue_len). */
int rgs_queue_len(const thr_rtp *r);
thr_qitem rgs_queue_at(const thr_rtp *r, int i);
/* Empties the queue, and appends an item to it, counting nothing (stored
 * warming restores a checkpoint's queue, sim/modes/replay.h). -1 when
 * out of memory. */
void rgs_queue_clear(thr_rtp *r);
int rgs_queue_put(thr_rtp *r, thr_qitem it);
/* Gives queued packets to idle threads of RTP r (the timed sink, after
 * a shading op: functional drivers hand out work themselves). */
void rgs_dispatch(thr_rtp *r);

#endif
