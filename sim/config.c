/*
 * config.c: the config schema table and everything driven by it: defaults,
 * the YAML loader (kernel-ref/yload.h; each key is checked and set as the
 * file streams), --set overrides, cross-key checks, the JSON dump,
 * --list-config and docs/config.md.
 *
 * Adding a key is one line in `keys_src` plus the field in saar_config (the
 * unit kinds' keys come from units/unit_table.h: UNIT_KEYS). Keys of
 * one section must stay contiguous in the table (the JSON writer opens each
 * section once; tests check this). Provenance: "published" values cite the
 * seed paper (Wald et al., EG 2003 STAR, seed 002 §4); "assumed" ones say why;
 * "calibrated" ones (.calibrated) were fitted to published figures by
 * scripts/calibrate.sh (docs/CALIBRATION.md) and say what was assumed before.
 */
#include "sim/config.h"
#include "kernel-ref/drt.h"
#include "kernel-ref/infile.h"
#include "kernel-ref/kdtree.h"
#include "kernel-ref/world.h"
#include "kernel-ref/yload.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* a number macro as the digits of a string literal */
#define NUM_STR_(x) #x
#define NUM_STR(x)  NUM_STR_(x)

/* ======================== the schema ======================== */

static const char *const thread_sched_names[] = {"round_robin", "oldest_first", NULL};
static const char *const accel_names[] = {"kd", "grid", NULL};
static const char *const demand_model_names[] = {"auto", "max", "linear", "pnorm", NULL};
static const char *const warming_names[] = {"auto", "full", "stored", NULL};
static const char *const jump_names[] = {"relax", "drain", "mixed", "skip", "auto", NULL};
static const char *const tile_order_names[] = {"scanline", "morton", NULL};
/* the order of enum fp_rmode (kernel-ref/fpfmt.h) */
static const char *const fp_round_names[] = {"nearest", "zero", "up", "down", NULL};
static const char *const mem_model_names[] = {"fixed", "hierarchy", NULL};
static const char *const memif_policy_names[] = {"fifo", "round_robin", "frfcfs", NULL};
static const char *const addr_hash_names[] = {"xor_fold", "none", NULL};
static const char *const sdram_mapping_names[] = {"row:bank:col", "bank:row:col", NULL};
static const char *const hostbus_preset_names[] = {"pci", "pci66", "agp", NULL};
static const char *const fidelity_names[] = {"cycle", "sampled", "functional", NULL};

#define FIELD(f) .off = offsetof(saar_config, f), .size = sizeof(((saar_config *)0)->f)
#define PUB      .published = true, .source = "seed 002 "
#define TIMING   .timing_only = true
#define KEY(p, t, f, d, lo, hi, u)                                                                 \
	.path = p, .type = t, FIELD(f), .def = d, .min = lo, .max = hi, .unit = u
#define INT(p, f, d, lo, hi, u) KEY(p, CFG_INT, f, d, lo, hi, u)
#define FLT(p, f, d, lo, hi, u) KEY(p, CFG_FLOAT, f, d, lo, hi, u)
#define BOOL(p, f, d)           KEY(p, CFG_BOOL, f, d, 0, 1, "")
#define ENUM(p, f, nm)          KEY(p, CFG_ENUM, f, 0, 0, 0, ""), .names = nm

/* clang-format off */
/* The unit keys chip.<name>.count/width/latency of every kind in
 * units/unit_table.h stand where this entry is (keys_init). */
#define UNIT_KEYS {.path = NULL}
/* One first-level cache: sizes and line sizes are published (seed 002 §4.1,
 * §4.7); the timing-side parameters are ours. */
#define L1(c, what, kb)                                                                            \
	{INT("memory.l1." #c ".size_kb", memory.l1.c.size_kb, kb, 1, 1048576, "KB"), PUB "§4.7",   \
	 .desc = "capacity of the " what " cache"},                                                \
	{INT("memory.l1." #c ".ways", memory.l1.c.ways, 4, 1, 64, ""),                             \
	 PUB "§4.7 (L1 caches are 4-way)", .desc = "associativity of the " what " cache (LRU)"},   \
	{INT("memory.l1." #c ".line", memory.l1.c.line, L1LINE_##c, 1, 4096, "bytes"),             \
	 PUB "§4.1 (8 B kd-nodes, 36 B triangles, 8 B shading/lists: 64-bit bus)",                \
	 .desc = "line size of the " what " cache; any size (36 need not be a power of two)"},     \
	{INT("memory.l1." #c ".hit_latency", memory.l1.c.hit_latency, L1HIT_##c, 1, 1000,         \
	     "core cycles"),                                                                       \
	 TIMING, L1HITSRC_##c,                                                                     \
	 .desc = "cycles from access to data for a hit in the " what " cache"},                   \
	{INT("memory.l1." #c ".ports", memory.l1.c.ports, 4, 1, 64, "accesses/cycle"),             \
	 .source = "not published; one port per RTP of the standard chip",                         \
	 .desc = "accesses the " what " cache accepts per core cycle (all RTPs together)"},        \
	{INT("memory.l1." #c ".mshrs", memory.l1.c.mshrs, L1MSHR_##c, 1, 4096, "lines"), TIMING,  \
	 L1MSHRSRC_##c,                                                                            \
	 .desc = "outstanding missed lines of the " what " cache; more misses merge or wait"},      \
	{KEY("memory.l1." #c ".replacement", CFG_STR, memory.l1.c.replacement, 0, 0, 0, ""),       \
	 .sdef = "lru", .source = "not published; LRU assumed (exact; the seed names no policy)",  \
	 .desc = "replacement policy of the " what " cache: lru, plru (tree pseudo-LRU), fifo, "   \
	         "or one registered by name (docs/extending.md)"}
#define FP(st, what)                                                                               \
	{INT("chip.fp." #st ".exp", chip.fp.st.exp, 8, 2, 8, "bits"),                              \
	 .source = "§4.6: SaarCOR cut each stage's floats to the precision it needs; 8 = float",   \
	 .desc = "exponent bits of the " what " datapath"},                                        \
	{INT("chip.fp." #st ".mant", chip.fp.st.mant, 23, 1, 23, "bits"),                          \
	 .source = "§4.6; the widths used are not published; 23 = float",                          \
	 .desc = "mantissa bits of the " what " datapath (docs/NUMERICS.md)"}
#define L1LINE_shade 8
#define L1LINE_kd    8
#define L1LINE_list  8
#define L1LINE_tri   36
/* hit latency and MSHRs: assumed, or calibrated (scripts/calibrate.sh) */
#define L1HIT_ASSUMED  .source = "not published; a small pipelined SRAM"
#define L1MSHR_ASSUMED .source = "not published; one per thread of an RTP"
#define CAL            .calibrated = true, .source = "fitted to F1-F3 (docs/CALIBRATION.md); "
#define L1HIT_CAL      CAL "not published; assumed before: 2 (a small pipelined SRAM)"
#define L1MSHR_CAL(w)  CAL "not published; assumed before: " #w " (one per thread of an RTP)"
#define L1HIT_shade    2
#define L1HIT_kd       8
#define L1HIT_list     2
#define L1HIT_tri      8
#define L1HITSRC_shade L1HIT_ASSUMED
#define L1HITSRC_kd    L1HIT_CAL
#define L1HITSRC_list  L1HIT_ASSUMED
#define L1HITSRC_tri   L1HIT_CAL
#define L1MSHR_shade   16
#define L1MSHR_kd      16
#define L1MSHR_list    16
#define L1MSHR_tri     8
#define L1MSHRSRC_shade L1MSHR_ASSUMED
#define L1MSHRSRC_kd    L1MSHR_ASSUMED
#define L1MSHRSRC_list  L1MSHR_ASSUMED
#define L1MSHRSRC_tri   L1MSHR_CAL(16)
/* clang-format on */

static const cfg_key keys_src[] = {
    {KEY("name", CFG_STR, name, 0, 0, 0, ""), .sdef = "saarcor-std",
     .source = "a label, not hardware",
     .desc = "name of this configuration, copied into reports; a config file without it is "
             "named after the file (its base name without the extension)"},
    {ENUM("fidelity", fidelity, fidelity_names), .source = "a run setting (docs/fidelity.md)",
     .desc = "simulation detail: cycle = cycle-level timing of every unit; sampled = "
             "systematic sample of tiles cycle by cycle, the rest functional, cycles with a 95% "
             "interval; functional = no timing, fps as a bound"},
    {FLT("sampling.rate", sampling.rate, 0.1, 0.0001, 1, ""),
     .source = "a run setting (docs/fidelity.md)",
     .desc = "fidelity sampled: share of the tiles in measured units (1 = every tile, "
             "identical to cycle)"},
    {INT("sampling.unit_tiles", sampling.unit_tiles, 0, 0, 1000000, "tiles"),
     .source = "a run setting (docs/fidelity.md)",
     .desc = "fidelity sampled: consecutive tiles per measured unit; 0 = rtps x threads_per_rtp"},
    {INT("sampling.warmup_tiles", sampling.warmup_tiles, -1, -1, 1000000, "tiles"),
     .source = "a run setting (docs/fidelity.md)",
     .desc = "fidelity sampled: tiles simulated cycle by cycle, unmeasured, before each unit; "
             "-1 = rtps x min(threads_per_rtp, 16) (the region takes over packets in flight "
             "with warm caches; the warm-up refills the memory and unit queues)"},
    {INT("sampling.min_units", sampling.min_units, 8, 3, 1000000, "units"),
     .source = "a run setting (docs/fidelity.md)",
     .desc =
         "fidelity sampled: fewest measured units per frame (at least 3: the frame's start, its "
         "end and one between), whatever the rate; when they "
         "and their warm-ups would cover the frame, every tile is simulated (cycle). Two "
         "or three units that all land in similar parts of a frame give a narrow interval "
         "around a wrong value"},
    {FLT("sampling.offset", sampling.offset, 0.5, 0, 1, ""),
     .source = "a run setting (docs/fidelity.md)",
     .desc = "fidelity sampled: where in its period each warm-up and unit sit (0 = at the "
             "start, 1 = at the end); runs at different offsets are independent replicas"},
    {FLT("sampling.hard_share", sampling.hard_share, 0.6, 0, 100, ""),
     .source = "a run setting (docs/fidelity.md)",
     .desc = "fidelity sampled: a chunk whose memory demand (SDRAM or host-bus time) exceeds "
             "this share of its compute demand (units, L1 ports) is memory bound: such chunks "
             "form their own stratum of the estimate, and one seen in a functional stretch "
             "brings an extra region soon after (at most as many extra as planned); 0 = one "
             "stratum, no extra regions"},
    {FLT("sampling.sdram_factor", sampling.sdram_factor, 0, 0, 10, ""),
     .source = "a run setting (docs/fidelity.md)",
     .desc = "fidelity sampled: the factor k on SDRAM data-bus time in each chunk's demand, "
             "max(compute, k x SDRAM, host bus) (plus sampling.overlap's term), for the SDRAM's "
             "row misses and turnarounds; "
             "0 = fitted to the frame's units (the k in [1, 4] under which one ratio fits them "
             "best), > 0 = this k (the max model's: auto may take pnorm, which has no k)"},
    {FLT("sampling.overlap", sampling.overlap, -1, -1, 4, ""),
     .source = "a run setting (docs/fidelity.md)",
     .desc = "fidelity sampled: the share g of the smaller of compute and k x SDRAM time "
             "added to each chunk's demand, max(compute, k x SDRAM, host bus) + g x "
             "min(compute, k x SDRAM), for the memory latency that compute and memory "
             "time alike leave unhidden; -1 = fitted with k to the frame's units (the g in "
             "[0, 1] under which one ratio fits them best), 0 = none, > 0 = this g (the max "
             "model's: auto may take pnorm, which has no g)"},
    {ENUM("sampling.demand_model", sampling.demand_model, demand_model_names),
     .source = "a run setting (docs/fidelity.md)",
     .desc = "fidelity sampled: how a chunk's cycles follow its resource demands: max = its "
             "busiest resource with SDRAM time x sdram_factor, plus the overlap term "
             "(sampling.overlap; many threads: throughput bound), "
             "linear = a non-negative sum of unit issue cycles, SDRAM and host-bus time fitted "
             "to the units (few threads: latency bound; needs 30 units), pnorm = the p-norm of "
             "every compute resource, SDRAM and host-bus time, p fitted to the units (units "
             "that take turns: a chunk with two resources alike runs above its busiest; "
             "sdram_factor and overlap unused), auto = linear when its leave-one-out error over "
             "the units is below the max model's residual variance, else max or pnorm, "
             "whichever has the smaller residual variance per degree of freedom"},
    {ENUM("sampling.warming", sampling.warming, warming_names),
     .source = "a run setting (docs/fidelity.md)",
     .desc = "fidelity sampled: auto = stored when the run has a world cache (a folder in "
             "use: --world-cache DIR or the default one), else full (the report's "
             "fidelity.warming says which); full = the functional stretches between regions "
             "run, warming the caches as they go; stored = a warming run of the whole frame "
             "(functional, replaying the packet record) is stored once in the world cache "
             "with checkpoints of the chip's state, and each region starts from the "
             "checkpoint at its start, so a run simulates only its regions (needs "
             "a world cache; regions start at checkpoints, one in every "
             "1/" NUM_STR(
                 CFG_WARM_FULL_PER_FRAME) " of the frame). A warming run is reused by every run "
                                          "whose config differs only in its name, "
                                          "timing (latencies, SDRAM timings, MSHRs, scheduling) "
                                          "and sampling keys"},
    {KEY("sampling.jump", CFG_ENUM, sampling.jump, CFG_JUMP_AUTO, 0, 0, ""), .names = jump_names,
     .source = "a run setting (docs/fidelity.md)",
     .desc = "fidelity sampled with stored warming: how a region's packets in flight end "
             "before the jump to the next region's checkpoint: relax = they go on "
             "functionally, with new tiles, until every thread slot took two and a slot "
             "wants a tile on the light grid (the chip then holds what the warming run "
             "held); drain = they finish functionally, no tile handed out, and the jump "
             "adds only the work of the tiles after them, as the warming run split its "
             "counts by tile, the drained work counted at the warming run's demand, not "
             "the drain's own (faster; the warming run counts every step by tile, about "
             "2.4 times its time; where the warming run had not finished those tiles by "
             "the next region's checkpoint, a relax); mixed = drain, but a relax after a "
             "region that ends in a memory-bound chunk or before one that starts after "
             "one; skip = no functional step at all: the chip's counts since its last "
             "restore give way to the warming run's, the timed SDRAM and host-bus traffic "
             "and busy time with them (the timing's own counts, waits, stalls, row hits, "
             "stay the regions') and the estimate is drain's, from the relax's warming run (no "
             "done records; where "
             "that run had not finished the region's tiles by the next checkpoint, a "
             "relax); auto = per frame, relax where the warming run's memory demand is at "
             "least sampling.auto_ratio times its compute demand (a frame nearly all "
             "memory bound, whose relaxes run into the next regions), skip elsewhere"},
    {FLT("sampling.auto_ratio", sampling.auto_ratio, 2, 0, 1000, ""),
     .source = "a run setting, chosen from measured fps errors (docs/fidelity.md)",
     .desc = "sampling.jump auto: a frame relaxes when its warming run's memory demand "
             "(SDRAM or host-bus time, the larger, summed over chunks of unit_tiles) is at "
             "least this many times its compute demand (the busiest unit or L1 port per "
             "chunk, summed), and skips otherwise; 0 = always relax"},
    {FLT("sampling.bias_bound", sampling.bias_bound, 0.02, 0, 1, ""),
     .source = "a run setting (docs/fidelity.md)",
     .desc = "fidelity sampled: share of the estimated cycles added to the 95% interval's "
             "half-width for the units' systematic error, which no spread between units "
             "shows (unit windows ran slightly faster than a full cycle run at the same "
             "places, docs/fidelity.md)"},
    {FLT("chip.clock_mhz", chip.clock_mhz, 533, 1, 10000, "MHz"), PUB "§4.7",
     .desc = "core clock; rounded to a whole-picosecond period (sim/core/engine.h)"},
    {INT("chip.rtps", chip.rtps, 4, 1, 1024, ""), PUB "§4.7",
     .desc = "ray-tracing pipelines (RTPs) on the chip"},
    {INT("chip.threads_per_rtp", chip.threads_per_rtp, 16, 1, 1024, ""), PUB "§4.4, §4.7",
     .desc = "thread contexts per RTP; one thread is one packet"},
    {INT("chip.stack_depth", chip.stack_depth, 64, 1, 1024, "entries"),
     .source = "not published; kernel-ref kd-trees are at most 64 deep (automatic limit <= 60)",
     .desc = "on-chip traversal stack entries per thread; deeper entries spill to memory"},
    {INT("chip.packet_w", chip.packet_w, 8, 8, 8, "pixels"), PUB "§4.5",
     .desc = "packet (tile) width; 8 only: a packet is one of kernel-ref's 8 x 8 tiles"},
    {INT("chip.packet_h", chip.packet_h, 8, 8, 8, "pixels"), PUB "§4.5",
     .desc = "packet (tile) height; 8 only (as packet_w)"},
    {BOOL("chip.masked_packets", chip.masked_packets, 1),
     .source = "§4.5: partly active packets cost about as much as full ones",
     .desc = "true: every packet op costs all packet_w*packet_h rays (inactive rays masked); "
             "false: only active rays cost"},
    {BOOL("chip.cone_cull", chip.cone_cull, 0),
     .source = "not published; seed 004 §4 (enclosing cones of a tile's rays), issue 32",
     .desc = "true: each packet's rays are enclosed in a cone (an RGS op of the packet's "
             "rays as it enters traversal) and every leaf triangle is first tested "
             "against it (a one-cycle packet-level op of the intersection unit); a "
             "triangle outside is skipped for the whole packet (kernel-ref/cone.h). The "
             "image is the same"},
    {ENUM("chip.accel", chip.accel, accel_names),
     .source = "a run setting (issue 34): the kd-tree of seed 002, or seed 003's uniform grid",
     .desc = "the acceleration structure the traversal unit walks: kd (the kd-tree), or grid "
             "(a uniform grid built by the host over the frame's triangles, walked by the "
             "grid traversal unit, units/gridtrav.c; the same as saarsim --accel grid; "
             "docs/design.md, \"The chip on a uniform grid\"). The image is the same"},
    {KEY("chip.thread_sched", CFG_ENUM, chip.thread_sched, CFG_SCHED_OLDEST_FIRST, 0, 0, ""),
     .names = thread_sched_names, TIMING,
     CAL "not published; assumed before: round_robin (the simplest fair policy)",
     .desc = "which ready thread a unit serves next"},
    {ENUM("chip.tile_order", chip.tile_order, tile_order_names),
     .source = "not published; the simplest order",
     .desc = "order in which the RGC hands out screen tiles"},
    FP(trav, "traversal (split distances, scene-box clip)"),
    FP(isect, "intersection (the Woop test)"),
    FP(shade, "shading (colours, normals, directions)"),
    {ENUM("chip.fp.round", chip.fp.round, fp_round_names),
     .source = "IEEE default; SaarCOR's rounding is not published",
     .desc = "rounding of the reduced formats; traversal and intersection bounds stay "
             "conservative in every mode"},
    UNIT_KEYS,
    {INT("frame.width", frame.width, 1024, 1, 16384, "pixels"),
     .source = "a common benchmark size; seed 002 Table 5 does not state it",
     .desc = "image width"},
    {INT("frame.height", frame.height, 768, 1, 16384, "pixels"), .source = "as frame.width",
     .desc = "image height"},
    {INT("frame.frames", frame.frames, 1, 1, 1000000, ""), .source = "a run setting",
     .desc = "frames to render"},
    {INT("shading.max_depth", shading.max_depth, 3, 0, 64, "bounces"),
     .source = "deepest reflection depth in seed 002 Table 4 (Office)",
     .desc = "maximum recursion depth of reflection/refraction rays"},
#define DRTKEY(f, flag, what)                                                                      \
	{                                                                                          \
		KEY("drt." #f, CFG_STR, drt.f, 0, 0, 0, ""),                                       \
		    .sdef = "", .source = "a run setting (empty: the view's drt, docs/views.md)",  \
		    .desc = what "; as the flag " flag " (which wins), its value checked alike"    \
	}
    DRTKEY(spp, "--spp", "samples per pixel: 1, 4, 16 or 64"),
    DRTKEY(aperture, "--aperture", "thin-lens diameter in scene units; 0 = pinhole"),
    DRTKEY(focus, "--focus", "focal distance along the view direction; 0 = |lookat - eye|"),
    DRTKEY(light_size, "--light-size", "side of each light's square; 0 = point lights"),
    DRTKEY(gloss, "--gloss", "Phong exponent of reflection rays; 0 = a mirror"),
    DRTKEY(motion, "--motion", "camera displacement X,Y,Z over the shutter; 0,0,0 = still"),
#undef DRTKEY
    {FLT("kdtree.cost_trav", kdtree.cost_trav, 1, KD_COST_MIN, KD_COST_MAX, ""),
     .source = "kernel-ref kd_params_default", .desc = "SAH cost of a traversal step (K_T)"},
    {FLT("kdtree.cost_isect", kdtree.cost_isect, 1.5, KD_COST_MIN, KD_COST_MAX, ""),
     .source = "kernel-ref kd_params_default", .desc = "SAH cost of a triangle test (K_I)"},
    {INT("kdtree.max_depth", kdtree.max_depth, 0, 0, KD_DEPTH_MAX, "levels"),
     .source = "kernel-ref kd_params_default",
     .desc = "kd-tree depth limit; 0 = 8 + 1.3 log2(triangles), at most 60"},
    {INT("kdtree.leaf_size", kdtree.leaf_size, 2, KD_LEAF_MIN, KD_LEAF_MAX, "triangles"),
     .source = "kernel-ref kd_params_default",
     .desc = "stop splitting at or below this many triangles"},
    {FLT("kdtree.empty_bonus", kdtree.empty_bonus, 0.2, 0, KD_BONUS_MAX, ""),
     .source = "kernel-ref kd_params_default", .desc = "SAH discount for cutting off empty space"},
    {FLT("kdtree.footprint", kdtree.footprint, 0, 0, KD_FOOTPRINT_MAX, ""),
     .source = "kernel-ref kd_params_default (rtref alone takes 0.001)",
     .desc = "SAH for packets this fraction of the scene's diagonal wide; 0 = the plain SAH"},
    {KEY("memory.model", CFG_ENUM, memory.model, CFG_MEM_HIERARCHY, 0, 0, ""),
     .names = mem_model_names,
     .source = "hierarchy models the published memory system; fixed isolates the units",
     .desc = "memory model: fixed = every access takes memory.latency; hierarchy = L1 "
             "caches, memory interface, SDRAM (and the VMA if memory.vma.enabled)"},
    {INT("memory.latency", memory.latency, 20, 0, 100000, "core cycles"), TIMING,
     .source = "placeholder; an L1 hit plus some misses",
     .desc = "latency of every memory access in the fixed model"},
    {KEY("memory.levels", CFG_STR, memory.levels, 0, 0, 0, ""), .sdef = "",
     .source = "a model setting (docs/memory.md, \"Levels\")",
     .desc = "the memory stack by level names, top first: fixed, or l1, [vma,] sdram; "
             "setting it sets memory.model and memory.vma.enabled; empty = as those keys say "
             "(l1,sdram or l1,vma,sdram)"},
    L1(shade, "shading (RGS)", 64),
    L1(kd, "kd-node (traversal)", 64),
    L1(list, "triangle-address list", 64),
    L1(tri, "triangle (intersection)", 144),
    {INT("memory.sdram.mb", memory.sdram.mb, 64, 1, 65536, "MB"), PUB "§4.7",
     .desc = "on-board SDRAM; without VMA the whole memory image must fit"},
    {FLT("memory.sdram.clock_mhz", memory.sdram.clock_mhz, 133, 1, 10000, "MHz"), PUB "§4.7",
     .desc = "SDRAM clock (its own clock domain)"},
    {INT("memory.sdram.bus_bits", memory.sdram.bus_bits, 128, 8, 4096, "bits"), PUB "§4.7",
     .desc = "SDRAM data bus width; one beat per SDRAM cycle (128 bit x 133 MHz = 2 GB/s)"},
    {INT("memory.sdram.banks", memory.sdram.banks, 4, 1, 64, ""), TIMING,
     .source = "not published; PC133 SDRAM devices have 4 internal banks",
     .desc = "independent banks, each with one open row (power of two)"},
    {INT("memory.sdram.row_bytes", memory.sdram.row_bytes, 8192, 16, 1048576, "bytes"), TIMING,
     .source = "not published; 512 columns x 16 bytes across the 128-bit bus",
     .desc = "bytes of one row of one bank across the whole bus (power of two)"},
    {INT("memory.sdram.cl", memory.sdram.cl, 2, 1, 100, "SDRAM cycles"), TIMING,
     CAL "not published; assumed before: 3 (PC133 CL3; CL2 parts exist)",
     .desc = "CAS latency: read command to first data"},
    {INT("memory.sdram.trcd", memory.sdram.trcd, 2, 1, 100, "SDRAM cycles"), TIMING,
     CAL "not published; assumed before: 3 (PC133, 20 ns; 15 ns parts exist)",
     .desc = "ACTIVATE to READ/WRITE"},
    {INT("memory.sdram.trp", memory.sdram.trp, 2, 1, 100, "SDRAM cycles"), TIMING,
     CAL "not published; assumed before: 3 (PC133, 20 ns; 15 ns parts exist)",
     .desc = "PRECHARGE to ACTIVATE"},
    {INT("memory.sdram.tras", memory.sdram.tras, 6, 1, 100, "SDRAM cycles"), TIMING,
     .source = "not published; PC133 (45 ns)", .desc = "ACTIVATE to PRECHARGE, at least"},
    {INT("memory.sdram.burst", memory.sdram.burst, 1, 1, 256, "beats"),
     .source = "not published; SDR burst length is programmable and L1 lines are 1-3 beats",
     .desc = "beats per column command; transfers round up to whole bursts"},
    {ENUM("memory.sdram.mapping", memory.sdram.mapping, sdram_mapping_names), TIMING,
     .source = "not published; consecutive rows interleave over the banks",
     .desc = "address bits from most to least significant: row:bank:col or bank:row:col"},
    {KEY("memory.memif.policy", CFG_ENUM, memory.memif.policy, CFG_MEMIF_FRFCFS, 0, 0, ""), TIMING,
     .names = memif_policy_names,
     .source = "not published; a first-ready controller (fifo's head-of-line blocking on a busy "
               "bank held the SDRAM near 30% bus use: docs/memory.md)",
     .desc = "memory interface arbitration of the L1 miss streams (and VMA meta-data and "
             "host fills): fifo = oldest first; round_robin = by requester; frfcfs = the "
             "request whose bank can deliver first (open row, idle bank), oldest on ties"},
    {BOOL("memory.vma.enabled", memory.vma.enabled, 0), PUB "§4.2, Table 5 (std. SaarCOR)",
     .desc = "the virtual memory architecture: on-board SDRAM caches host memory"},
    {INT("memory.vma.ways", memory.vma.ways, 4, 1, 64, ""), PUB "§4.2",
     .desc = "associativity of the on-board L2 cache"},
    {INT("memory.vma.line", memory.vma.line, 128, 8, 65536, "bytes"), PUB "§4.2",
     .desc = "L2 line size; the unit of DMA over the host bus"},
    {ENUM("memory.vma.hash", memory.vma.hash, addr_hash_names),
     .source = "§4.2 says address hashing is used (published); the function is assumed",
     .desc = "L2 set selection: xor_fold = line index XOR-folded onto the set bits; none = "
             "line index mod sets"},
    {INT("memory.vma.tag_cache_kb", memory.vma.tag_cache_kb, 64, 1, 1048576, "KB"),
     PUB "§4.7 (64 KB for L2-cache meta data)", .desc = "on-chip cache of the L2 meta-data"},
    {INT("memory.vma.tag_cache_ways", memory.vma.tag_cache_ways, 4, 1, 64, ""),
     PUB "§4.7 (L1 caches are 4-way)", .desc = "associativity of the tag cache"},
    {INT("memory.vma.tag_cache_latency", memory.vma.tag_cache_latency, 2, 1, 1000, "core cycles"),
     TIMING, .source = "not published; as the L1 caches (a 4-way SRAM of their size)",
     .desc = "tag cache hit latency"},
    {BOOL("memory.vma.tag_cache_enabled", memory.vma.tag_cache_enabled, 1), PUB "§4.2",
     .desc = "false: every meta-data lookup reads SDRAM (for studies)"},
    {KEY("memory.vma.replacement", CFG_STR, memory.vma.replacement, 0, 0, 0, ""), .sdef = "lru",
     .source = "not published; LRU assumed (the seed names no policy)",
     .desc = "replacement policy of the on-board L2 cache: lru, plru, fifo (mem/repl.h)"},
    {KEY("memory.vma.tag_cache_replacement", CFG_STR, memory.vma.tag_cache_replacement, 0, 0, 0,
         ""),
     .sdef = "lru", .source = "not published; LRU assumed (as the L1 caches)",
     .desc = "replacement policy of the tag cache: lru, plru, fifo (mem/repl.h)"},
    {ENUM("memory.hostbus.preset", memory.hostbus.preset, hostbus_preset_names),
     PUB "§4.7 (standard PCI)",
     .desc = "host bus: pci = 32 bit/33 MHz, pci66 = 64 bit/66 MHz, agp = 32 bit at 266 MT/s "
             "(AGP 4x); the keys below override single values"},
    {INT("memory.hostbus.width_bits", memory.hostbus.width_bits, 0, 0, 1024, "bits"),
     .source = "from the preset", .desc = "data width; 0 = the preset's"},
    {FLT("memory.hostbus.clock_mhz", memory.hostbus.clock_mhz, 0, 0, 10000, "MHz"),
     .source = "from the preset", .desc = "data phases per microsecond; 0 = the preset's"},
    {INT("memory.hostbus.burst", memory.hostbus.burst, 0, 0, 4096, "data phases"),
     .source = "not published; presets assume 32 (a 128-byte line is one PCI burst)",
     .desc = "data phases per bus transaction; 0 = the preset's"},
    {FLT("memory.hostbus.latency_ns", memory.hostbus.latency_ns, -1, -1, 1e6, "ns"),
     .source = "not published; presets assume 300 ns (arbitration, address phase, host "
               "memory read)",
     .desc = "setup latency per transaction; negative = the preset's"},
};

/* The table: keys_src with UNIT_KEYS replaced by three keys per unit kind
 * (units/unit_table.h), built once (keys_init) before any use. */
#define NSRC  (sizeof keys_src / sizeof keys_src[0])
#define NKEYS (NSRC - 1 + 3 * UNIT_NKINDS)
_Static_assert(NKEYS <= CFG_KEYS_MAX, "cfg_origin holds CFG_KEYS_MAX keys");
static cfg_key keys[NKEYS];
/* the unit keys' paths and descriptions */
static char unit_text[UNIT_NKINDS][3][2][96];
static pthread_once_t keys_once = PTHREAD_ONCE_INIT;

/* Key p of unit kind k: chip.<name>.<leaf>, described as `fmt` with the
 * kind's `what`, from the table's default, range and provenance. */
static cfg_key unit_key(int k, int p, const char *leaf, const char *unit, const char *fmt,
                        const unit_param_desc *u, size_t off)
{
	const unit_desc *d = &unit_table[k];
	char *path = unit_text[k][p][0], *desc = unit_text[k][p][1];
	snprintf(path, sizeof unit_text[k][p][0], "chip.%s.%s", d->name, leaf);
	snprintf(desc, sizeof unit_text[k][p][1], fmt, d->what);
	return (cfg_key){.path = path,
	                 .type = CFG_INT,
	                 .off =
	                     offsetof(saar_config, chip.unit) + (size_t)k * sizeof(cfg_unit) + off,
	                 .size = sizeof(int),
	                 .def = u->def,
	                 .min = u->min,
	                 .max = u->max,
	                 .unit = unit,
	                 .published = u->published,
	                 .calibrated = u->calibrated,
	                 .timing_only = u->timing,
	                 .source = u->source,
	                 .desc = desc};
}

static void keys_build(void)
{
	size_t n = 0;
	for (size_t i = 0; i < NSRC; i++) {
		if (keys_src[i].path) {
			keys[n++] = keys_src[i];
			continue;
		}
		for (int k = 0; k < UNIT_NKINDS; k++) {
			const unit_desc *d = &unit_table[k];
			keys[n++] = unit_key(k, 0, "count", "", "number of %s units per RTP",
			                     &d->count, offsetof(cfg_unit, count));
			keys[n++] = unit_key(k, 1, "width", "rays/cycle",
			                     "rays one %s unit accepts per cycle", &d->width,
			                     offsetof(cfg_unit, width));
			keys[n++] = unit_key(k, 2, "latency", "core cycles",
			                     "pipeline latency of one %s unit", &d->latency,
			                     offsetof(cfg_unit, latency));
		}
	}
}

static void keys_init(void)
{
	pthread_once(&keys_once, keys_build);
}

const cfg_key *cfg_keys(size_t *n)
{
	keys_init();
	*n = NKEYS;
	return keys;
}

const cfg_key *cfg_find(const char *path)
{
	keys_init();
	for (size_t i = 0; i < NKEYS; i++)
		if (!strcmp(keys[i].path, path))
			return &keys[i];
	return NULL;
}

/* True if path names a section: some key lies below it. */
static bool is_section(const char *path)
{
	size_t n = strlen(path);
	for (size_t i = 0; i < NKEYS; i++)
		if (!strncmp(keys[i].path, path, n) && keys[i].path[n] == '.')
			return true;
	return false;
}

/* ======================== values ======================== */

static void *field(saar_config *c, const cfg_key *k)
{
	return (char *)c + k->off;
}

static const void *cfield(const saar_config *c, const cfg_key *k)
{
	return (const char *)c + k->off;
}

static void fmt_num(char *buf, size_t n, const cfg_key *k, double v)
{
	snprintf(buf, n, k->type == CFG_FLOAT ? "%g" : "%.0f", v);
}

void cfg_defaults(saar_config *c)
{
	keys_init();
	memset(c, 0, sizeof *c);
	for (size_t i = 0; i < NKEYS; i++) {
		const cfg_key *k = &keys[i];
		void *p = field(c, k);
		switch (k->type) {
		case CFG_INT:
		case CFG_ENUM:
			*(int *)p = (int)k->def;
			break;
		case CFG_UINT:
			*(uint64_t *)p = (uint64_t)k->def;
			break;
		case CFG_FLOAT:
			*(double *)p = k->def;
			break;
		case CFG_BOOL:
			*(bool *)p = k->def != 0;
			break;
		case CFG_STR:
			snprintf(p, k->size, "%s", k->sdef);
			break;
		}
	}
}

/* Parses text s into key k of c. On error writes a message (without the
 * location, which the caller knows) into err and returns -1. */
/* Does the stack name `name` (a comma-separated list) hold level lv? */
static bool levels_has(const char *name, const char *lv)
{
	size_t n = strlen(lv);
	for (const char *p = name; *p;) {
		p += strspn(p, ", ");
		size_t k = strcspn(p, ", ");
		if (k == n && !strncmp(p, lv, n))
			return true;
		p += k;
	}
	return false;
}

/* memory.levels was set: the two keys that name today's stacks follow it
 * (the structure itself is checked where the stack is built). */
static void levels_apply(saar_config *c)
{
	const char *l = c->memory.levels;
	if (!*l)
		return;
	if (levels_has(l, "fixed")) {
		c->memory.model = CFG_MEM_FIXED;
		return;
	}
	c->memory.model = CFG_MEM_HIERARCHY;
	c->memory.vma.enabled = levels_has(l, "vma");
}

/* A drt.* key's value, checked where it is read (so a file's error has
 * its line and column) as its flag's would be: parsed by the world's flag
 * parser, its range by drt_problem; "" (the view's) is always good. */
static int drt_value_ok(const cfg_key *k, const char *s, char *err, size_t n)
{
	if (!*s)
		return 0;
	/* the flag is the key's name: drt.light_size is --light-size */
	char flag[32];
	snprintf(flag, sizeof flag, "--%.20s", k->path + 4);
	for (char *c = flag; *c; c++)
		*c = *c == '_' ? '-' : *c;
	world_opts o;
	memset(&o, 0, sizeof o);
	char *argv[] = {flag, (char *)s};
	int at = 0;
	diag e = {{0}};
	const char *why = NULL;
	if (world_parse_arg(&o, 2, argv, &at, &e) != 1) {
		size_t fl = strlen(flag);
		why = strncmp(e.msg, flag, fl) || strncmp(e.msg + fl, ": ", 2) ? e.msg
		                                                               : e.msg + fl + 2;
	} else {
		const char *key;
		why = drt_problem(&o.drt, &key); /* the other fields 0: always good */
	}
	if (why)
		snprintf(err, n, "%s: %.200s", k->path, why);
	return why ? -1 : 0;
}

static int set_value(saar_config *c, const cfg_key *k, const char *s, char *err, size_t n)
{
	char *end;
	double v = 0;
	char got[96]; /* the offending text, quoted, for messages */
	snprintf(got, sizeof got, *s ? "'%.80s'" : "nothing", s);
	errno = 0;
	switch (k->type) {
	case CFG_INT:
	case CFG_UINT:
		/* base 10 on purpose: "010" is ten, not octal eight */
		v = k->type == CFG_INT ? (double)strtoll(s, &end, 10)
		                       : (double)strtoull(s, &end, 10);
		if (end == s || *end || errno || (k->type == CFG_UINT && strchr(s, '-'))) {
			snprintf(err, n, "%s: expected %s integer, got %s", k->path,
			         k->type == CFG_UINT ? "a non-negative" : "an", got);
			return -1;
		}
		break;
	case CFG_FLOAT:
		v = strtod(s, &end);
		if (end == s || *end || !isfinite(v)) {
			snprintf(err, n, "%s: expected a number, got %s", k->path, got);
			return -1;
		}
		break;
	case CFG_BOOL: {
		static const char *const t[] = {"true", "yes", "on"}, *const f[] = {"false", "no",
		                                                                    "off"};
		v = -1;
		for (int i = 0; i < 3; i++) {
			if (!strcasecmp(s, t[i]))
				v = 1;
			if (!strcasecmp(s, f[i]))
				v = 0;
		}
		if (v < 0) {
			snprintf(err, n, "%s: expected true or false, got %s", k->path, got);
			return -1;
		}
		*(bool *)field(c, k) = v != 0;
		return 0;
	}
	case CFG_ENUM:
		for (int i = 0; k->names[i]; i++) {
			if (!strcmp(s, k->names[i])) {
				*(int *)field(c, k) = i;
				return 0;
			}
		}
		int m = snprintf(err, n, "%s: expected one of", k->path);
		for (int i = 0; k->names[i] && m > 0 && (size_t)m < n; i++)
			m += snprintf(err + m, n - (size_t)m, "%s %s", i ? "," : "", k->names[i]);
		if (m > 0 && (size_t)m < n)
			snprintf(err + m, n - (size_t)m, "; got %s", got);
		return -1;
	case CFG_STR:
		if (strlen(s) >= k->size) {
			snprintf(err, n, "%s: longer than %zu characters", k->path, k->size - 1);
			return -1;
		}
		if (!strncmp(k->path, "drt.", 4) && drt_value_ok(k, s, err, n))
			return -1;
		snprintf(field(c, k), k->size, "%s", s);
		if (field(c, k) == (void *)c->memory.levels)
			levels_apply(c);
		return 0;
	}
	if (v < k->min || v > k->max) {
		char lo[32], hi[32];
		fmt_num(lo, sizeof lo, k, k->min);
		fmt_num(hi, sizeof hi, k, k->max);
		snprintf(err, n, "%s: must be in [%s, %s], got %s", k->path, lo, hi, s);
		return -1;
	}
	void *p = field(c, k);
	if (k->type == CFG_INT)
		*(int *)p = (int)v;
	else if (k->type == CFG_UINT)
		*(uint64_t *)p = strtoull(s, NULL, 10); /* exact above 2^53 */
	else
		*(double *)p = v;
	return 0;
}

/* ======================== unknown keys ======================== */

static size_t edit_distance(const char *a, const char *b)
{
	size_t la = strlen(a), lb = strlen(b), row[128];
	if (lb >= sizeof row / sizeof row[0])
		return (size_t)-1;
	for (size_t j = 0; j <= lb; j++)
		row[j] = j;
	for (size_t i = 1; i <= la; i++) {
		size_t dg = row[0];
		row[0] = i;
		for (size_t j = 1; j <= lb; j++) {
			size_t up = row[j], best = dg + (a[i - 1] != b[j - 1]);
			if (up + 1 < best)
				best = up + 1;
			if (row[j - 1] + 1 < best)
				best = row[j - 1] + 1;
			dg = up;
			row[j] = best;
		}
	}
	return row[lb];
}

/* Writes "unknown key 'p'" plus a suggestion: a key (or, for a section, a
 * section) within a few edits, or one whose trailing components equal p
 * (`rtps` -> `chip.rtps`). */
static void unknown_key(char *err, size_t n, const char *p, bool want_section)
{
	char best[128] = "", cand[128];
	size_t lp = strlen(p), bestd = (lp / 3 > 2 ? lp / 3 : 2) + 1; /* first best wins */
	for (size_t i = 0; i < NKEYS; i++) {
		const char *k = keys[i].path;
		for (const char *dot = k;; dot++) {
			bool end = !*dot;
			if (*dot != '.' && !end)
				continue;
			/* candidate: k up to this dot (a section) or all of k (a key) */
			if (end != want_section) {
				size_t len = (size_t)(dot - k);
				snprintf(cand, sizeof cand, "%.*s", (int)len, k);
				size_t d = edit_distance(p, cand);
				if (len > lp && cand[len - lp - 1] == '.' &&
				    !strcmp(cand + len - lp, p))
					d = 0;
				if (d < bestd) {
					bestd = d;
					snprintf(best, sizeof best, "%s", cand);
				}
			}
			if (end)
				break;
		}
	}
	if (*best)
		snprintf(err, n, "unknown key '%s' (did you mean '%s'?)", p, best);
	else
		snprintf(err, n, "unknown key '%s'", p);
}

/* ======================== YAML ======================== */

typedef struct loader {
	saar_config *c;
	const char *file;
	cfg_origin *o; /* NULL: not kept */
	diag *d;
	int root_map;    /* the root is a mapping: its keys are read */
	int seen[NKEYS]; /* line where each key was set, 0 = not yet */
} loader;

static int err_at(loader *L, const yaml_node_t *nd, const char *fmt, const char *a, const char *b)
{
	return diag_set(L->d, L->file, (int)nd->start_mark.line + 1, (int)nd->start_mark.column + 1,
	                fmt, a, b);
}

static const char *node_kind(const yaml_node_t *nd)
{
	return nd->type == YAML_MAPPING_NODE    ? "a mapping"
	       : nd->type == YAML_SEQUENCE_NODE ? "a sequence"
	                                        : "a value";
}

/* The whole config is read here, as the file streams (kernel-ref/yload.h):
 * each key is checked and its value set as soon as the value starts, so
 * the first bad key stops the load, whatever follows it. A mapping that is
 * a section is read on by the loader, its keys under the section's path. */
static int check_item(void *ctx, const yl_item *it)
{
	loader *L = ctx;
	char path[256], msg[512];
	if (it->at == YL_ROOT) { /* any other root is refused once the file is read */
		L->root_map = it->value->type == YAML_MAPPING_NODE;
		return 0;
	}
	if (!L->root_map)
		return 0;
	const yaml_node_t *kn = it->key, *vn = it->value;
	if (kn->type != YAML_SCALAR_NODE)
		return err_at(L, kn, "keys must be plain names, got %s%s", node_kind(kn), "");
	const char *key = (const char *)kn->data.scalar.value;
	if (it->first) {
		snprintf(msg, sizeof msg, "%d", (int)it->first->start_mark.line + 1);
		return err_at(L, kn, "duplicate key '%s' (first at line %s)", key, msg);
	}
	if ((size_t)snprintf(path, sizeof path, "%s%s%s", it->path, *it->path ? "." : "", key) >=
	    sizeof path)
		return err_at(L, kn, "key too long: '%s'%s", key, "");
	const cfg_key *k = cfg_find(path);
	if (vn->type == YAML_MAPPING_NODE && !k) {
		if (is_section(path))
			return 0;
		unknown_key(msg, sizeof msg, path, true);
		return err_at(L, kn, "%s%s", msg, "");
	}
	if (!k) {
		if (is_section(path))
			return err_at(L, vn,
			              "'%s' is a section: expected a mapping of its keys, got %s",
			              path, node_kind(vn));
		unknown_key(msg, sizeof msg, path, false);
		return err_at(L, kn, "%s%s", msg, "");
	}
	if (vn->type != YAML_SCALAR_NODE)
		return err_at(L, vn, "%s: expected a single value, got %s", path, node_kind(vn));
	size_t i = (size_t)(k - keys);
	if (L->seen[i]) {
		snprintf(msg, sizeof msg, "%d", L->seen[i]);
		return err_at(L, kn, "duplicate key '%s' (first at line %s)", path, msg);
	}
	L->seen[i] = (int)kn->start_mark.line + 1;
	if (set_value(L->c, k, (const char *)vn->data.scalar.value, msg, sizeof msg))
		return err_at(L, vn, "%s%s", msg, "");
	if (L->o) {
		L->o->key[i].who = NULL;
		L->o->key[i].line = (int)vn->start_mark.line + 1;
		L->o->key[i].col = (int)vn->start_mark.column + 1;
		L->o->key[i].seq = ++L->o->seq;
	}
	return 0;
}

/* A config that does not name itself is named after its file: the base
 * name without its extension ("configs/fpga-2004.yaml" -> "fpga-2004"). */
static void name_from_file(saar_config *c, const char *file)
{
	const char *b = strrchr(file, '/');
	b = b ? b + 1 : file;
	const char *dot = strrchr(b, '.');
	size_t n = dot && dot > b ? (size_t)(dot - b) : strlen(b);
	if (n)
		snprintf(c->name, sizeof c->name, "%.*s",
		         (int)(n < sizeof c->name ? n : sizeof c->name - 1), b);
}

int cfg_load(saar_config *c, const char *file, diag *d)
{
	return cfg_load_at(c, file, NULL, d);
}

int cfg_load_at(saar_config *c, const char *file, cfg_origin *o, diag *d)
{
	cfg_defaults(c);
	if (o) {
		memset(o, 0, sizeof *o);
		o->file = file;
	}
	FILE *f;
	int st = in_open(file, &f);
	if (st)
		return diag_set(d, file, 0, 0, "cannot open: %s", in_strerror(st));
	loader L = {.c = c, .file = file, .o = o, .d = d};
	yl_opts yo = {.what = "a config",
	              .syntax = "YAML syntax error",
	              .max_bytes = CFG_FILE_MAX,
	              .max_nodes = CFG_NODES_MAX,
	              .max_depth = YL_DEPTH_MAX,
	              .check = check_item,
	              .ctx = &L};
	yaml_document_t doc;
	int rc = yl_load(&doc, f, file, &yo, d);
	fclose(f);
	if (rc)
		return -1;
	/* everything was read as it streamed, but for a root that is not a
	 * mapping (an empty file has none: all defaults) */
	yaml_node_t *root = yaml_document_get_root_node(&doc);
	if (root && root->type != YAML_MAPPING_NODE)
		rc = err_at(&L, root, "expected a mapping of keys at the top level, got %s%s",
		            node_kind(root), "");
	yaml_document_delete(&doc);
	if (!rc && !L.seen[cfg_find("name") - keys])
		name_from_file(c, file);
	return rc;
}

/* ======================== --set, checks ======================== */

/* Copies [b, e) without surrounding blanks into out; -1 if it does not fit. */
static int trim(char *out, size_t n, const char *b, const char *e)
{
	while (b < e && (*b == ' ' || *b == '\t'))
		b++;
	while (e > b && (e[-1] == ' ' || e[-1] == '\t'))
		e--;
	if ((size_t)(e - b) >= n)
		return -1;
	snprintf(out, n, "%.*s", (int)(e - b), b);
	return 0;
}

int cfg_set_as(saar_config *c, const char *who, const char *assignment, diag *d)
{
	return cfg_set_at(c, who, assignment, NULL, d);
}

int cfg_set_at(saar_config *c, const char *who, const char *assignment, cfg_origin *o, diag *d)
{
	char key[256], val[512], msg[512];
	const char *eq = strchr(assignment, '=');
	if (!eq)
		return diag_set(d, who, 0, 0, "expected key=value, got '%s'", assignment);
	if (trim(key, sizeof key, assignment, eq) || trim(val, sizeof val, eq + 1, strchr(eq, 0)))
		return diag_set(d, who, 0, 0, "key or value too long in '%s'", assignment);
	const cfg_key *k = cfg_find(key);
	if (!k) {
		if (is_section(key))
			return diag_set(d, who, 0, 0,
			                "'%s' is a section; set one of its keys (%s.*)", key, key);
		unknown_key(msg, sizeof msg, key, false);
		return diag_set(d, who, 0, 0, "%s", msg);
	}
	if (set_value(c, k, val, msg, sizeof msg))
		return diag_set(d, who, 0, 0, "%s", msg);
	if (o) {
		size_t i = (size_t)(k - keys);
		o->key[i].who = who;
		o->key[i].line = o->key[i].col = 0;
		o->key[i].seq = ++o->seq;
	}
	return 0;
}

int cfg_set(saar_config *c, const char *assignment, diag *d)
{
	return cfg_set_as(c, "--set", assignment, d);
}

/* The key set last among those whose path starts with the n bytes of
 * name (a key, a section, "memory.vma.tag_cache"), else among those of
 * the section around it, and so on out; -1 when none was set. */
static int last_set(const cfg_origin *o, const char *name, size_t n)
{
	for (;;) {
		int best = -1;
		for (size_t i = 0; i < NKEYS; i++)
			if (o->key[i].seq && !strncmp(keys[i].path, name, n) &&
			    (best < 0 || o->key[i].seq > o->key[best].seq))
				best = (int)i;
		if (best >= 0)
			return best;
		while (n > 0 && name[n - 1] != '.')
			n--;
		if (n-- <= 1)
			return -1;
	}
}

int cfg_blame(const cfg_origin *o, const char *msg, diag *d)
{
	if (!strncmp(msg, "config: ", 8))
		msg += 8;
	int k = o ? last_set(o, msg, strcspn(msg, " :'")) : -1;
	if (k < 0)
		return diag_set(d, "config", 0, 0, "%s", msg);
	if (o->key[k].who)
		return diag_set(d, o->key[k].who, 0, 0, "%s", msg);
	return diag_set(d, o->file, o->key[k].line, o->key[k].col, "%s", msg);
}

int cfg_validate(const saar_config *c, diag *d)
{
	return cfg_validate_at(c, NULL, d);
}

int cfg_validate_at(const saar_config *c, const cfg_origin *o, diag *d)
{
	char msg[sizeof d->msg];
	/* memory.levels set the model and the VMA; a later key must not
	 * contradict it (named by the one of the two set last) */
	const char *l = c->memory.levels;
	if (*l && (levels_has(l, "fixed") ? c->memory.model != CFG_MEM_FIXED
	                                  : c->memory.model != CFG_MEM_HIERARCHY ||
	                                        c->memory.vma.enabled != levels_has(l, "vma"))) {
		size_t m = (size_t)(cfg_find("memory.model") - keys),
		       v = (size_t)(cfg_find("memory.vma.enabled") - keys);
		snprintf(msg, sizeof msg,
		         "%s disagrees with memory.levels '%s' set before it; set one or the other",
		         o && o->key[v].seq > o->key[m].seq ? keys[v].path : keys[m].path, l);
		return cfg_blame(o, msg, d);
	}
	/* sampling.overlap: fitted (negative) is -1, a given share 0 or more */
	if (c->sampling.overlap < 0 && c->sampling.overlap != -1) {
		snprintf(msg, sizeof msg, "sampling.overlap %g: -1 (fitted) or a share from 0 to 4",
		         c->sampling.overlap);
		return cfg_blame(o, msg, d);
	}
	/* No other key constrains another today. (A packet is an 8 x 8 tile: both
	 * packet keys' ranges are [8, 8].) chip.stack_depth may be below the
	 * tree depth: the traversal unit spills the entries beyond it to
	 * memory and reads them back (units/traversal.c, counted as
	 * trav.stack_overflows / trav.stack_refills). The spill area always
	 * has room for PKT_STACK_MAX entries per thread, and kdtree.max_depth
	 * is at most 64 = PKT_STACK_MAX by its range. */
	return 0;
}

const char *cfg_enum_name(const saar_config *c, const char *path)
{
	const cfg_key *k = cfg_find(path);
	if (!k || k->type != CFG_ENUM)
		return NULL;
	return k->names[*(const int *)cfield(c, k)];
}

const char *cfg_jump_name(cfg_jump j)
{
	return j >= CFG_JUMP_RELAX && j <= CFG_JUMP_AUTO ? jump_names[j] : "?";
}

/* ======================== output ======================== */

/* Length of the section part of a path ("chip.trav" in "chip.trav.width"). */
static size_t section_len(const char *p)
{
	const char *dot = strrchr(p, '.');
	return dot ? (size_t)(dot - p) : 0;
}

/* True if the first n characters of a are whole leading components of b. */
static bool is_prefix(const char *a, size_t n, const char *b, size_t bn)
{
	return n == 0 || (n <= bn && !strncmp(a, b, n) && (n == bn || b[n] == '.'));
}

void cfg_write_json(const saar_config *c, jsonw *w)
{
	keys_init();
	char open[256] = ""; /* path of the innermost open section, "" = top */
	size_t ol = 0;
	jsonw_obj_begin(w);
	for (size_t i = 0; i < NKEYS; i++) {
		const cfg_key *k = &keys[i];
		size_t sl = section_len(k->path);
		/* Close sections that do not contain this key, then open the
		 * missing ones one component at a time. */
		while (!is_prefix(open, ol, k->path, sl)) {
			jsonw_obj_end(w);
			ol = section_len(open);
			open[ol] = 0;
		}
		while (ol < sl) {
			size_t s = ol ? ol + 1 : 0, e = s;
			while (e < sl && k->path[e] != '.')
				e++;
			char name[64];
			snprintf(name, sizeof name, "%.*s", (int)(e - s), k->path + s);
			jsonw_key(w, name);
			jsonw_obj_begin(w);
			snprintf(open, sizeof open, "%.*s", (int)e, k->path);
			ol = e;
		}
		const char *leaf = k->path + (sl ? sl + 1 : 0);
		const void *p = cfield(c, k);
		switch (k->type) {
		case CFG_INT:
			jsonw_kint(w, leaf, *(const int *)p);
			break;
		case CFG_UINT:
			jsonw_kuint(w, leaf, *(const uint64_t *)p);
			break;
		case CFG_FLOAT:
			jsonw_knum(w, leaf, *(const double *)p);
			break;
		case CFG_BOOL:
			jsonw_kbool(w, leaf, *(const bool *)p);
			break;
		case CFG_ENUM:
			jsonw_kstr(w, leaf, k->names[*(const int *)p]);
			break;
		case CFG_STR:
			jsonw_kstr(w, leaf, p);
			break;
		}
	}
	for (; ol; ol = section_len(open), open[ol] = 0)
		jsonw_obj_end(w);
	jsonw_obj_end(w);
}

static const char *type_name(const cfg_key *k)
{
	static const char *const n[] = {"int", "uint", "float", "bool", "enum", "string"};
	return n[k->type];
}

static void fmt_default(char *buf, size_t n, const cfg_key *k)
{
	if (k->type == CFG_BOOL)
		snprintf(buf, n, "%s", k->def ? "true" : "false");
	else if (k->type == CFG_ENUM)
		snprintf(buf, n, "%s", k->names[(int)k->def]);
	else if (k->type == CFG_STR)
		snprintf(buf, n, "%s", k->sdef);
	else
		fmt_num(buf, n, k, k->def);
}

/* "[1, 64]" for numbers, "a, b" for enums, "" otherwise. */
static void fmt_range(char *buf, size_t n, const cfg_key *k)
{
	char lo[32], hi[32];
	buf[0] = 0;
	if (k->type == CFG_ENUM) {
		for (int i = 0, m = 0; k->names[i] && m >= 0 && (size_t)m < n; i++)
			m += snprintf(buf + m, n - (size_t)m, "%s%s", i ? ", " : "", k->names[i]);
	} else if (k->type == CFG_INT || k->type == CFG_UINT || k->type == CFG_FLOAT) {
		fmt_num(lo, sizeof lo, k, k->min);
		fmt_num(hi, sizeof hi, k, k->max);
		snprintf(buf, n, "[%s, %s]", lo, hi);
	}
}

const char *cfg_provenance(const cfg_key *k)
{
	return k->published ? "published" : k->calibrated ? "calibrated" : "assumed";
}

void cfg_list(FILE *f)
{
	keys_init();
	char def[64], range[128];
	fprintf(f, "%-24s %-6s %-12s %-24s %-12s %s\n", "KEY", "TYPE", "DEFAULT", "RANGE", "UNIT",
	        "PROVENANCE");
	for (size_t i = 0; i < NKEYS; i++) {
		const cfg_key *k = &keys[i];
		fmt_default(def, sizeof def, k);
		fmt_range(range, sizeof range, k);
		fprintf(f, "%-24s %-6s %-12s %-24s %-12s %s: %s\n    %s\n", k->path, type_name(k),
		        def, range, k->unit, cfg_provenance(k), k->source, k->desc);
	}
}

void cfg_write_markdown(FILE *f)
{
	keys_init();
	char def[64], range[128];
	fputs("# Hardware configuration reference\n\n"
	      "Generated by `saarsim --config-doc` from the schema table in `sim/config.c`;\n"
	      "do not edit by hand. `saarsim --list-config` prints the same keys.\n\n"
	      "## File format\n\n"
	      "A config is one YAML document whose top level is a mapping. Nested mappings\n"
	      "name dotted keys, and a key may also be written dotted, so these are the same:\n\n"
	      "```yaml\n"
	      "chip:\n"
	      "  trav:\n"
	      "    width: 16\n"
	      "chip.isect.width: 4\n"
	      "```\n\n"
	      "Every key is optional: a missing key keeps its default, so an empty file is\n"
	      "the default chip. Values are plain scalars: integers in base 10, numbers,\n"
	      "`true`/`false` (also `yes`/`no`, `on`/`off`), enum names, or strings.\n"
	      "Unknown keys, duplicate keys and values out of range are errors. The file\n"
	      "is checked as it is read (`kernel-ref/yload.c`), so the first bad key stops\n"
	      "it, however much follows.\n\n"
	      "`saarsim --set key=value` (repeatable) overrides one key after the file is\n"
	      "read, e.g. `--set chip.trav.width=8`. The shorthand flags `--fidelity`,\n"
	      "`--sample-rate`, `--unit-tiles`, `--warmup-tiles` and `--kd-cost-trav`,\n"
	      "`--kd-cost-isect`, `--kd-max-depth`, `--kd-leaf-size`, `--kd-empty-bonus`,\n"
	      "`--kd-footprint` are `--set` of their keys, with the same checks; among\n"
	      "them and `--set` the last given wins. `--size` and `--frames` set\n"
	      "`frame.width`, `frame.height` and `frame.frames` after the file and every\n"
	      "`--set`, wherever they stand on the command line: they win over those\n"
	      "keys. saarsim's other options of one value (`--config`, `--size`,\n"
	      "`--frames`, `--out`, `--report`, `--csv`, `--scene`, `--view`, the\n"
	      "camera, drt and grid flags, ...) are given at most once: a second is\n"
	      "refused (`saarsim: --config given twice`), not a silent override of the\n"
	      "first (`--light` and `--set` repeat). Checks that involve several keys, and the memory's (the stack\n"
	      "`memory.levels` names, each cache's geometry and replacement policy, the\n"
	      "SDRAM's and the host bus's parameters, the VMA's on-board cache and tag\n"
	      "cache, the host bus's and the VMA's also while the VMA is off), run\n"
	      "after all overrides, before any scene is loaded (also by `--dry-run` and\n"
	      "by saarsim-replay); their errors name where the value came from (\"Errors\"\n"
	      "below). Every report embeds the resolved config under `\"config\"`, nested\n"
	      "along the dotted paths, so a report says exactly what was simulated.\n\n"
	      "*Provenance*: **published** values come from the SaarCOR description in the\n"
	      "seed paper (Wald et al., *Realtime Ray Tracing and its use for Interactive\n"
	      "Global Illumination*, EG 2003 STAR, §4; `seed 002` below); **assumed** values\n"
	      "are ours, with the reason given.\n\n"
	      "Clocks: the engine counts picoseconds, and a clock of f MHz gets the period\n"
	      "round(10^6 / f) ps (533 MHz -> 1876 ps, 133 MHz -> 7519 ps); the error is\n"
	      "below 0.03% up to 1 GHz.\n",
	      f);
	fprintf(f,
	        "\n### Limits\n\n"
	        "A config is refused, at the line and column where it goes past the limit,\n"
	        "when it\n\n"
	        "- is larger than %u bytes (1 MiB), checked on the file's size before it\n"
	        "  is parsed;\n"
	        "- nests collections deeper than %d levels (a config needs 4: the root,\n"
	        "  `memory:`, `l1:`, `kd:`);\n"
	        "- has more than %d YAML nodes (one that sets every key has about 250);\n"
	        "- has an anchor or alias (`&name`, `*name`): a config has no use for them,\n"
	        "  and an alias lets a few lines stand for a huge document (the \"billion\n"
	        "  laughs\");\n"
	        "- or a second YAML document.\n\n"
	        "The configs in `configs/` are about 5 KB; the limits keep a damaged or\n"
	        "hostile file from costing time or memory (libyaml's scanner takes\n"
	        "quadratic time over deep flow nesting: 200,000 `[` took over a minute).\n",
	        CFG_FILE_MAX, YL_DEPTH_MAX, CFG_NODES_MAX);
	char sec[64] = "?"; /* top-level section of the previous key, "" = top level */
	for (size_t i = 0; i < NKEYS; i++) {
		const cfg_key *k = &keys[i];
		const char *dot = strchr(k->path, '.');
		int tl = dot ? (int)(dot - k->path) : 0;
		if (strlen(sec) != (size_t)tl || strncmp(sec, k->path, (size_t)tl)) {
			snprintf(sec, sizeof sec, "%.*s", tl, k->path);
			if (tl)
				fprintf(f, "\n## `%s`\n\n", sec);
			if (!strcmp(sec, "drt"))
				fputs("Distribution ray tracing (samples per pixel, thin lens, "
				      "area lights,\n"
				      "glossy reflection, camera motion) is the view's (the views "
				      "file's\n"
				      "`drt` key, "
				      "[views.md](views.md#distribution-ray-tracing-drt)); the\n"
				      "flags `--spp`, `--aperture`, `--focus`, `--light-size`, "
				      "`--gloss`,\n"
				      "`--motion` override it, and so do these keys when set (a "
				      "flag wins\n"
				      "over its key), so `scripts/sweep --set "
				      "drt.aperture=0,0.02,0.1`\n"
				      "sweeps it. A key's value is checked as its flag's.\n\n",
				      f);
			if (!tl)
				fputs("\n## Top level\n\n", f);
			fputs("| key | type | default | range | unit | provenance | description |\n"
			      "|---|---|---|---|---|---|---|\n",
			      f);
		}
		fmt_default(def, sizeof def, k);
		fmt_range(range, sizeof range, k);
		fprintf(f, "| `%s` | %s | `%s` | %s | %s | %s: %s | %s |\n", k->path, type_name(k),
		        def, range, k->unit, cfg_provenance(k), k->source, k->desc);
	}
	fputs("\n## Errors\n\n"
	      "Every error is one line and the program exits with status 2. In a file the\n"
	      "line and column (1-based) point at the offending key or value:\n\n"
	      "```\n"
	      "cfg.yaml: cannot open: No such file or directory\n"
	      "cfg.yaml:2:3: unknown key 'chip.tarv' (did you mean 'chip.trav'?)\n"
	      "cfg.yaml:1:1: unknown key 'rtps' (did you mean 'chip.rtps'?)\n"
	      "cfg.yaml:2:9: chip.rtps: expected an integer, got 'four'\n"
	      "cfg.yaml:2:9: chip.rtps: must be in [1, 1024], got 0\n"
	      "cfg.yaml:2:17: chip.thread_sched: expected one of round_robin, oldest_first; got "
	      "'lifo'\n"
	      "cfg.yaml:3:5: chip.rtps: expected a single value, got a mapping\n"
	      "cfg.yaml:1:7: 'chip' is a section: expected a mapping of its keys, got a value\n"
	      "cfg.yaml:3:3: duplicate key 'rtps' (first at line 2)\n"
	      "cfg.yaml:3:2: YAML syntax error: did not find expected key (while parsing a block "
	      "mapping)\n"
	      "cfg.yaml:4:1: only one YAML document is allowed\n"
	      "cfg.yaml: larger than the size limit for a config (1048576 bytes)\n"
	      "cfg.yaml:1:33: YAML nested deeper than 32 levels (the depth limit for a config)\n"
	      "cfg.yaml:2:9: YAML anchors and aliases are not allowed in a config (&r)\n"
	      "--set: expected key=value, got 'chip.rtps'\n"
	      "--set: unknown key 'chip.rtp' (did you mean 'chip.rtps'?)\n"
	      "--set: chip.masked_packets: expected true or false, got 'maybe'\n"
	      "```\n\n"
	      "The checks after loading name the file's line and column of the value at\n"
	      "fault, or the flag that set it; a check of several keys names the one set\n"
	      "last (a default names `config`):\n\n"
	      "```\n"
	      "cfg.yaml:3:12: memory.sdram.banks must be a power of two <= 64, got 3\n"
	      "--set: memory.sdram.row_bytes must be a power of two >= the bus width, got 100\n"
	      "--set: memory.levels 'fixed,l1,sdram': fixed stands alone (one latency for every "
	      "access, no levels beside it)\n"
	      "cfg.yaml:5:18: memory.l1.kd.replacement: unknown replacement policy 'bogus' "
	      "(registered: lru, plru, fifo)\n"
	      "--set: memory.vma.enabled disagrees with memory.levels 'l1,vma,sdram' set before "
	      "it; set one or the other\n"
	      "```\n",
	      f);
}
