/*
 * unit_table.c: the unit kinds of one RTP (see unit_table.h).
 *
 * The seed gives no unit widths; it says the chip "is designed for 4:1
 * ratio" of traversal to intersection operations (§4.7), so traversal is
 * 4x as wide as intersection. A 64-ray packet op takes ceil(64/width)
 * cycles to issue.
 */
#include "units/unit_table.h"

#include <string.h>

#include "mem/memport.h"

/* Every kind: one unit per RTP (published), and a pipeline latency of its
 * own (assumed, or calibrated by scripts/calibrate.sh; timing only). */
#define COUNT                                                                                      \
	{                                                                                          \
		1, 1, 64, 1, 0, "seed 002 §4.1 (one per RTP)", 0                                   \
	}
#define WIDTH(w, why)                                                                              \
	{                                                                                          \
		w, 1, 64, 0, 0, why, 0                                                             \
	}
#define LATENCY(l)                                                                                 \
	{                                                                                          \
		l, 1, 10000, 0, 1, "pipeline depth not published; a few cycles per stage group", 0 \
	}
/* A width fitted by scripts/calibrate.sh; was: the assumed value before. */
#define WIDTH_CAL(w, was, why)                                                                     \
	{                                                                                          \
		w, 1, 64, 0, 0,                                                                    \
		    "fitted to F1-F3 (docs/CALIBRATION.md); " why "; assumed before: " #was, 1     \
	}
/* A latency fitted by scripts/calibrate.sh; was: the assumed value before. */
#define LATENCY_CAL(l, was)                                                                        \
	{                                                                                          \
		l, 1, 10000, 0, 1,                                                                 \
		    "fitted to F1-F3 (docs/CALIBRATION.md); pipeline depth not published; "        \
		    "assumed before: " #was,                                                       \
		    1                                                                              \
	}

/* clang-format off */
const unit_desc unit_table[UNIT_NKINDS] = {
    [UNIT_RGS] = {"rgs", "ray-generation and shading", COUNT,
                  WIDTH(4, "not published; shading is the costliest op"), LATENCY_CAL(48, 24),
                  MEM_SHADE},
    [UNIT_TRAV] = {"trav", "traversal", COUNT,
                   WIDTH_CAL(24, 16, "not published; 4x isect width (§4.7: designed for 4:1)"),
                   LATENCY_CAL(32, 8),
                   MEM_KD},
    [UNIT_LIST] = {"list", "list", COUNT,
                   WIDTH(64, "not published; one list entry serves the whole packet"), LATENCY(2),
                   MEM_LIST},
    [UNIT_ISECT] = {"isect", "intersection", COUNT,
                    WIDTH_CAL(6, 4, "not published; 1/4 of trav width (§4.7: 4:1)"), LATENCY_CAL(80, 20),
                    MEM_TRI},
    /* Schmittler et al., "Realtime Ray Tracing of Dynamic Scenes on an FPGA
     * Chip" (GH 2004), add a transformation unit that moves a packet's rays
     * into an object's space as it enters an instance (two-level scenes,
     * units/toplevel.c); its width and latency are not taken from there */
    [UNIT_XFORM] = {"xform", "transformation", COUNT,
                    WIDTH(4, "assumed; GH 2004's transformation unit (a 3x4 matrix per ray)"),
                    LATENCY(20), -1},
};
/* clang-format on */

const char *unit_name(int kind)
{
	return kind >= 0 && kind < UNIT_NKINDS ? unit_table[kind].name : "?";
}

int unit_find(const char *name)
{
	for (int k = 0; k < UNIT_NKINDS; k++)
		if (!strcmp(unit_table[k].name, name))
			return k;
	return -1;
}
