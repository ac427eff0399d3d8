/*
 * sampled.h: the drivers of fidelity functional and sampled
 * (docs/fidelity.md): functional processing of a range of tiles with every
 * thread slot stepping in turn on the functional sink, and the sampled
 * frames, with full warming (detailed regions between functional
 * stretches) or stored warming (regions started from the warming run's
 * checkpoints, sim/warming.h). Cycle-level simulation is the chip's own
 * timed dispatcher (chip_run_region).
 */
#ifndef SAAR_SIM_MODES_SAMPLED_H
#define SAAR_SIM_MODES_SAMPLED_H

#include "sim/chip.h"

/* How mode_func_range ends: FR_DRAIN with every slot free; FR_STOP once
 * its last tile is handed out (packets still in flight, for the region
 * after it); FR_RELAX (stored warming, after a region) once every slot has
 * taken a few tiles and one wants a tile on the light-checkpoint grid. */
enum fr_mode { FR_DRAIN, FR_STOP, FR_RELAX };

/* Functional processing of tiles from the RGC's position up to `end`;
 * 1 when it stopped early for an extra region (sampled). */
int mode_func_range(chip *c, int end, int mode);
/* Sampled frame f with full warming, and with stored warming. */
void mode_sampled_frame(chip *c, int f);
void mode_sampled_frame_stored(chip *c, int f);
/* Stored warming, frame f (the warming run open): whether the warming run
 * calls tiles [a, b) memory bound, and whether the jump from a region that
 * ended at tile `at` to the full checkpoint rs drains under the chip's
 * sampling.jump (docs/fidelity.md, "Draining instead of the relax"). */
int mode_warm_hard(chip *c, int f, int a, int b);
int mode_jump_drains(chip *c, int f, int at, int rs);

#endif
