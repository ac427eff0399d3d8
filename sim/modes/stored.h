/*
 * stored.h: the world-cache side of functional and sampled runs: the
 * packet record (traces/pktrec.h) replayed, or recorded in the first
 * frame through the recording sink (record.h) and stored after it; and
 * stored warming's checkpoints (sim/warming.h), loaded, or built by a
 * warming run (a functional helper chip replaying the record).
 */
#ifndef SAAR_SIM_MODES_STORED_H
#define SAAR_SIM_MODES_STORED_H

#include "sim/chip.h"

/* Functional and sampled runs with a world cache: replay the stored
 * record of this frame, else record the first frame. */
void mode_rec_open(chip *c);
/* After the recorded frame: stores the record (a failure is a warning),
 * and the frames after it replay it. */
void mode_rec_store(chip *c);
/* Replayed tiles take the recorded frame's pixels. */
void mode_rec_pixels(chip *c);
/* Stored warming: the checkpoints from the world cache, else a warming
 * run now; when impossible, full warming runs. */
void mode_warm_open(chip *c);

#endif
