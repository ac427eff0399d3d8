/*
 * config.h: the hardware configuration (YAML) and its schema.
 *
 * One static table (config.c) describes every key: dotted path, type,
 * default, range, unit, provenance and description. The YAML loader, the
 * `--set key=value` overrides, the JSON dump in reports, `--list-config` and
 * docs/config.md are all driven by that table, so they cannot disagree.
 * Nested YAML mappings name dotted paths: `chip: {trav: {width: 4}}` sets
 * chip.trav.width; a key may also be written dotted (`chip.trav.width: 4`).
 *
 * Usage: cfg_load (or cfg_defaults), then any number of cfg_set, then
 * cfg_validate for the checks that involve several keys.
 */
#ifndef SAAR_SIM_CONFIG_H
#define SAAR_SIM_CONFIG_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "kernel-ref/diag.h"
#include "kernel-ref/jsonw.h"
#include "units/unit_table.h"

/* Stored warming's full checkpoints per frame (about: one in each
 * 1/CFG_WARM_FULL_PER_FRAME of it, rounded to the light grid; sim/warming.h,
 * the sampling.warming key's text). */
#define CFG_WARM_FULL_PER_FRAME 64

/* Enum values; the names in the YAML are in config.c's tables, same order. */
typedef enum { CFG_SCHED_ROUND_ROBIN, CFG_SCHED_OLDEST_FIRST } cfg_thread_sched;
/* chip.accel: what the traversal unit walks (issue 34) */
typedef enum { CFG_ACCEL_KD, CFG_ACCEL_GRID } cfg_accel;
/* sampling.demand_model (docs/fidelity.md "Demand models") */
typedef enum {
	CFG_DEMAND_AUTO,
	CFG_DEMAND_MAX,
	CFG_DEMAND_LINEAR,
	CFG_DEMAND_PNORM
} cfg_demand_model;
/* sampling.warming (docs/fidelity.md "Stored warming") */
/* auto: stored when the run has a world cache (chip_create resolves it:
 * a chip's cfg holds FULL or STORED) */
typedef enum { CFG_WARMING_AUTO, CFG_WARMING_FULL, CFG_WARMING_STORED } cfg_warming;
/* sampling.jump (docs/fidelity.md "Stored warming") */
typedef enum {
	CFG_JUMP_RELAX,
	CFG_JUMP_DRAIN,
	CFG_JUMP_MIXED,
	CFG_JUMP_SKIP,
	CFG_JUMP_AUTO /* per frame: relax or skip by the warming run's memory/compute ratio */
} cfg_jump;
typedef enum { CFG_TILES_SCANLINE, CFG_TILES_MORTON } cfg_tile_order;
typedef enum { CFG_MEM_FIXED, CFG_MEM_HIERARCHY } cfg_mem_model;
typedef enum { CFG_MEMIF_FIFO, CFG_MEMIF_ROUND_ROBIN, CFG_MEMIF_FRFCFS } cfg_memif_policy;
typedef enum { CFG_HASH_XOR_FOLD, CFG_HASH_NONE } cfg_addr_hash;
typedef enum { CFG_SDRAM_ROW_BANK_COL, CFG_SDRAM_BANK_ROW_COL } cfg_sdram_mapping;
typedef enum { CFG_HBUS_PCI, CFG_HBUS_PCI66, CFG_HBUS_AGP } cfg_hostbus_preset;
typedef enum { CFG_FIDELITY_CYCLE, CFG_FIDELITY_SAMPLED, CFG_FIDELITY_FUNCTIONAL } cfg_fidelity;

#define CFG_STR_MAX 128
/* Limits of a config file (docs/config.md "Limits"): the configs in
 * configs/ are about 5 KB and under 400 YAML nodes even with every key set,
 * so 1 MiB and 16384 nodes refuse only what is not a config, before it costs
 * time or memory. Nesting: YL_DEPTH_MAX (kernel-ref/yload.h). */
#define CFG_FILE_MAX  (1u << 20)
#define CFG_NODES_MAX 16384

/* One first-level cache (mem/cache.h). */
typedef struct cfg_l1 {
	int size_kb, ways, line; /* capacity, associativity, line bytes (any size) */
	int hit_latency, ports;  /* core cycles; accesses accepted per core cycle */
	int mshrs;               /* outstanding missed lines */
	char replacement[32];    /* policy name (mem/repl.h) */
} cfg_l1;

/* A floating-point format of one datapath stage (kernel-ref/fpfmt.h). */
typedef struct cfg_fp {
	int exp, mant; /* exponent and mantissa bits; 8, 23 = float */
} cfg_fp;

/* One kind of functional unit inside a ray-tracing pipeline (RTP); the
 * kinds, their keys' defaults and ranges: units/unit_table.h. */
typedef struct cfg_unit {
	int count;   /* units of this kind per RTP */
	int width;   /* rays accepted per cycle: a 64-ray op takes 64/width cycles */
	int latency; /* pipeline latency in core cycles */
} cfg_unit;

typedef struct saar_config {
	char name[CFG_STR_MAX]; /* label copied into reports */
	struct {
		double clock_mhz;
		int rtps, threads_per_rtp, stack_depth;
		int packet_w, packet_h;
		bool masked_packets;
		bool cone_cull;
		cfg_accel accel;
		cfg_thread_sched thread_sched;
		cfg_tile_order tile_order;
		cfg_unit unit[UNIT_NKINDS]; /* by enum unit_kind: chip.<name>.* */
		struct {
			cfg_fp trav, isect, shade;
			int round; /* enum fp_rmode: nearest, zero, up, down */
		} fp;
	} chip;
	struct {
		int width, height, frames;
	} frame;
	struct {
		int max_depth;
	} shading;
	/* Distribution ray tracing of the run, as the flags --spp ... --motion
	 * write it ("" = the view's; sim/main.c hands a set key to the world
	 * as its flag, so both are checked alike): a key for scripts/sweep. */
	struct {
		char spp[16], aperture[32], focus[32], light_size[32], gloss[32], motion[96];
	} drt;
	struct {
		double cost_trav, cost_isect, empty_bonus, footprint;
		int max_depth, leaf_size;
	} kdtree;
	struct {
		cfg_mem_model model;
		int latency;
		/* the stack, top first ("fixed", "l1,vma,sdram"); "": from model
		 * and vma.enabled. Setting it sets those two (docs/memory.md) */
		char levels[48];
		struct {
			cfg_l1 shade, kd, list, tri;
		} l1;
		struct {
			int mb;
			double clock_mhz;
			int bus_bits, banks, row_bytes, cl, trcd, trp, tras, burst;
			cfg_sdram_mapping mapping;
		} sdram;
		struct {
			cfg_memif_policy policy;
		} memif;
		struct {
			bool enabled;
			int ways, line;
			cfg_addr_hash hash;
			int tag_cache_kb, tag_cache_ways, tag_cache_latency;
			bool tag_cache_enabled;
			/* policy names (mem/repl.h) of the on-board and tag caches */
			char replacement[32], tag_cache_replacement[32];
		} vma;
		struct {
			cfg_hostbus_preset preset;
			int width_bits, burst; /* 0 = the preset's value */
			double clock_mhz, latency_ns;
		} hostbus;
	} memory;
	cfg_fidelity fidelity;
	struct {                   /* fidelity sampled (docs/fidelity.md) */
		double rate;       /* share of tiles in measured units; 1 = every tile (= cycle) */
		int unit_tiles;    /* tiles per measured unit; 0 = the chip's thread count */
		int warmup_tiles;  /* detailed tiles before each unit; -1 = the thread count */
		int min_units;     /* fewest units per frame (more than the rate asks if needed) */
		double offset;     /* where in its period each region starts, 0..1 */
		double hard_share; /* memory share above which a chunk is memory bound; 0 = off */
		double bias_bound; /* share of the estimate added to the interval for window bias */
		double sdram_factor; /* k on SDRAM time in the demand; 0 = fitted per frame */
		double overlap;      /* g on min(compute, k x SDRAM) in the demand; < 0 = fitted */
		cfg_demand_model demand_model; /* how a chunk's demand follows its resources */
		cfg_warming warming; /* functional stretches run (full), restored (stored), auto */
		cfg_jump jump;       /* stored: how a region's packets end before a jump */
		double auto_ratio;   /* jump auto: relax at a frame memory/compute ratio >= this */
	} sampling;
} saar_config;

/* ---- the schema ---- */

typedef enum { CFG_INT, CFG_UINT, CFG_FLOAT, CFG_BOOL, CFG_ENUM, CFG_STR } cfg_type;

typedef struct cfg_key {
	const char *path; /* "chip.trav.width" */
	cfg_type type;
	size_t off;               /* offsetof(saar_config, ...) */
	size_t size;              /* sizeof the field (CFG_STR: buffer size) */
	double def, min, max;     /* numeric default and inclusive range; enum: index */
	const char *sdef;         /* CFG_STR default */
	const char *const *names; /* CFG_ENUM names, NULL-terminated */
	const char *unit;         /* "" when dimensionless */
	bool published;           /* value taken from a paper (else assumed) */
	/* value fitted to published figures by scripts/calibrate.sh
	 * (docs/CALIBRATION.md); the source says to which and what was
	 * assumed before */
	bool calibrated;
	/* only timing reads it (latencies, SDRAM timing, MSHRs, scheduling):
	 * functional processing does the same with any value, so stored
	 * warming's key leaves it out (sim/chip.c warm_key) */
	bool timing_only;
	const char *source; /* where published, or why assumed */
	const char *desc;
} cfg_key;

/* A key's provenance: "published", "calibrated" or "assumed". */
const char *cfg_provenance(const cfg_key *k);

/* The whole table, in documentation order (keys of a section contiguous). */
const cfg_key *cfg_keys(size_t *n);
/* The key with this exact dotted path, or NULL. */
const cfg_key *cfg_find(const char *path);

/* Where each key's value came from, for the checks after loading
 * (memcfg_validate, cfg_blame): a line and column of the config file, or a command
 * line flag. The config itself keeps no such record (two configs of the
 * same values are the same bytes). */
#define CFG_KEYS_MAX 320
typedef struct cfg_origin {
	const char *file; /* the config file read (cfg_load_at's name), or NULL */
	struct {
		const char *who; /* the flag that set it ("--set"), NULL: the file or default */
		int line, col;   /* in the file; 0 with no who: the default */
		int seq;         /* the order of setting: 0 = never set */
	} key[CFG_KEYS_MAX];
	int seq;
} cfg_origin;

/* ---- loading ---- */

void cfg_defaults(saar_config *c);
/* Defaults, then the YAML file on top; a file without `name` is named
 * after itself (its base name without the extension). Errors:
 * "file:line:col: message", at the first problem in the file. */
int cfg_load(saar_config *c, const char *file, diag *d);
/* One "key=value" override (the argument of --set). Errors: "--set: ...". */
int cfg_set(saar_config *c, const char *assignment, diag *d);
/* cfg_set on behalf of `who` (a shorthand flag such as --kd-leaf-size):
 * its messages start with who instead of --set. */
int cfg_set_as(saar_config *c, const char *who, const char *assignment, diag *d);
/* cfg_load, cfg_set_as and cfg_validate that keep (and name) where each
 * value came from: o (NULL: not kept) is reset by cfg_load_at and must
 * outlive the file name and `who` given (a program's argv does). */
int cfg_load_at(saar_config *c, const char *file, cfg_origin *o, diag *d);
int cfg_set_at(saar_config *c, const char *who, const char *assignment, cfg_origin *o, diag *d);
/* The checks a value passes only with the others (cross-key checks; the
 * memory's own: memcfg_validate in sim/memconfig.h, which runs this
 * first). An error is named by where the value at fault came from
 * (cfg_blame). */
int cfg_validate_at(const saar_config *c, const cfg_origin *o, diag *d);
/* cfg_validate_at without origins. Errors: "config: ...". */
int cfg_validate(const saar_config *c, diag *d);
/* A check's message msg, which starts with the key or section at fault
 * ("memory.sdram.banks must be ...", "memory.l1.kd: ..."; a leading
 * "config: " is dropped), into d named by where that value came from:
 * "FILE:LINE:COL: msg" (the value in the config file), "--set: msg" (the
 * flag that set it), or "config: msg" (a default, or o NULL). A section
 * names the key of it set last, a key never set the one set last around
 * it. Returns -1. */
int cfg_blame(const cfg_origin *o, const char *msg, diag *d);

/* Name of an enum key's current value (for reports), NULL if not an enum. */
const char *cfg_enum_name(const saar_config *c, const char *path);
/* Name of a sampling.jump value ("relax", ..., "auto"). */
const char *cfg_jump_name(cfg_jump j);

/* ---- output ---- */

/* The resolved config as one JSON object, nested along the dotted paths. */
void cfg_write_json(const saar_config *c, jsonw *w);
/* Every key with type, default, unit, provenance and description. */
void cfg_list(FILE *f);
/* The content of docs/config.md. */
void cfg_write_markdown(FILE *f);

#endif
