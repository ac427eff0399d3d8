/*
 * memconfig.c: the config -> memory parameters builder (see memconfig.h).
 */
#include "sim/memconfig.h"

#include <stdio.h>
#include <string.h>

#include "mem/repl.h"

static const cfg_l1 *l1_cfg(const saar_config *cfg, int t)
{
	switch (t) {
	case MEM_SHADE:
		return &cfg->memory.l1.shade;
	case MEM_KD:
		return &cfg->memory.l1.kd;
	case MEM_LIST:
		return &cfg->memory.l1.list;
	default:
		return &cfg->memory.l1.tri;
	}
}

int memcfg_l1_ports(const saar_config *cfg, int type)
{
	return l1_cfg(cfg, type)->ports;
}

cache_params hier_l1_params(const saar_config *cfg, int type)
{
	const cfg_l1 *c = l1_cfg(cfg, type);
	return (cache_params){(uint64_t)c->size_kb << 10,
	                      (uint32_t)c->ways,
	                      (uint32_t)c->line,
	                      (uint32_t)c->mshrs,
	                      (uint32_t)c->hit_latency,
	                      (uint32_t)c->ports,
	                      CACHE_HASH_NONE,
	                      repl_find(c->replacement)};
}

vma_params hier_vma_params(const saar_config *cfg)
{
	const __typeof__(cfg->memory.vma) *v = &cfg->memory.vma;
	return (vma_params){(uint32_t)v->ways,
	                    (uint32_t)v->line,
	                    v->hash == CFG_HASH_NONE ? CACHE_HASH_NONE : CACHE_HASH_XOR,
	                    v->tag_cache_enabled,
	                    (uint64_t)v->tag_cache_kb << 10,
	                    (uint32_t)v->tag_cache_ways,
	                    (uint32_t)v->tag_cache_latency,
	                    repl_find(v->replacement),
	                    repl_find(v->tag_cache_replacement)};
}

void hier_hbus_params(const saar_config *cfg, hbus_params *hp)
{
	static const char *const pn[] = {"pci", "pci66", "agp"};
	const __typeof__(cfg->memory.hostbus) *b = &cfg->memory.hostbus;
	hbus_preset(pn[b->preset], hp);
	if (b->width_bits > 0)
		hp->width_bits = (uint32_t)b->width_bits;
	if (b->clock_mhz > 0)
		hp->clock_mhz = b->clock_mhz;
	if (b->burst > 0)
		hp->burst = (uint32_t)b->burst;
	if (b->latency_ns >= 0)
		hp->latency_ns = b->latency_ns;
}

/* -1 with d set when name (the value of key) names no policy. */
static int known_policy(const char *key, const char *name, diag *d)
{
	if (repl_find(name))
		return 0;
	char names[256];
	return diag_set(d, "config", 0, 0, "%s: unknown replacement policy '%s' (registered: %s)",
	                key, name, repl_names(names, sizeof names));
}

const char *memcfg_levels(const saar_config *cfg, char *buf, size_t n)
{
	if (*cfg->memory.levels)
		snprintf(buf, n, "%s", cfg->memory.levels);
	else if (cfg->memory.model == CFG_MEM_FIXED)
		snprintf(buf, n, "fixed");
	else
		snprintf(buf, n, "l1,%ssdram", cfg->memory.vma.enabled ? "vma," : "");
	return buf;
}

int memcfg_hier(const saar_config *cfg, hier_params *hp, diag *d)
{
	const __typeof__(cfg->memory) *M = &cfg->memory;
	memset(hp, 0, sizeof *hp);
	for (int t = 0; t < MEM_NTYPES; t++) {
		char key[48];
		snprintf(key, sizeof key, "memory.l1.%s.replacement", mem_type_name(t));
		if (known_policy(key, l1_cfg(cfg, t)->replacement, d))
			return -1;
		hp->l1[t] = hier_l1_params(cfg, t);
	}
	if ((known_policy("memory.vma.replacement", M->vma.replacement, d) ||
	     known_policy("memory.vma.tag_cache_replacement", M->vma.tag_cache_replacement, d)))
		return -1;
	hp->sdram =
	    (sdram_params){(uint64_t)M->sdram.mb << 20,
	                   M->sdram.clock_mhz,
	                   (uint32_t)M->sdram.bus_bits,
	                   (uint32_t)M->sdram.banks,
	                   (uint32_t)M->sdram.row_bytes,
	                   (uint32_t)M->sdram.cl,
	                   (uint32_t)M->sdram.trcd,
	                   (uint32_t)M->sdram.trp,
	                   (uint32_t)M->sdram.tras,
	                   (uint32_t)M->sdram.burst,
	                   M->sdram.mapping == CFG_SDRAM_BANK_ROW_COL ? SDRAM_MAP_BANK_ROW_COL
	                                                              : SDRAM_MAP_ROW_BANK_COL};
	/* the config's policy names are memif's own */
	int pol = memif_policy_parse(cfg_enum_name(cfg, "memory.memif.policy"));
	hp->memif_policy = pol < 0 ? MEMIF_FIFO : pol;
	/* the hierarchy's stack: memory.levels, else the one memory.vma.enabled
	 * names (also under memory.model fixed: trace replay always builds one) */
	if (*M->levels)
		snprintf(hp->levels, sizeof hp->levels, "%s", M->levels);
	else
		snprintf(hp->levels, sizeof hp->levels, "l1,%ssdram", M->vma.enabled ? "vma," : "");
	hp->vma = hier_vma_params(cfg);
	hier_hbus_params(cfg, &hp->hbus);
	return 0;
}

/* The number of names in the stack list l ("l1, vma,sdram": 3). */
static int level_count(const char *l)
{
	int n = 0;
	for (const char *p = l + strspn(l, ", "); *p; p += strspn(p, ", ")) {
		n++;
		p += strcspn(p, ", ");
	}
	return n;
}

int memcfg_check(const saar_config *cfg, diag *d)
{
	const __typeof__(cfg->memory) *M = &cfg->memory;
	char what[32];
	hier_params hp;
	if (memcfg_hier(cfg, &hp, d))
		return -1;
	/* fixed is a model of its own: one latency, no levels */
	int fixed = cfg->memory.model == CFG_MEM_FIXED;
	if (*M->levels && fixed && level_count(M->levels) != 1)
		return diag_set(d, "config", 0, 0,
		                "memory.levels '%s': fixed stands alone (one latency for every "
		                "access, no levels beside it)",
		                M->levels);
	if (!(*M->levels && fixed) && hier_check_levels(hp.levels, d))
		return -1;
	for (int t = 0; t < MEM_NTYPES; t++) {
		snprintf(what, sizeof what, "memory.l1.%s", mem_type_name(t));
		if (cache_check(&hp.l1[t], what, d))
			return -1;
	}
	sdram_timing st;
	hbus hb;
	if (sdram_derive(&hp.sdram, &st, d) || hbus_init(&hb, &hp.hbus, d))
		return -1;
	/* an unused VMA's keys too (the host bus's are checked above) */
	return M->vma.enabled ? vma_check(hp.sdram.bytes, &hp.vma, d)
	                      : vma_check_params(&hp.vma, d);
}

int memcfg_validate(const saar_config *cfg, const cfg_origin *o, diag *d)
{
	if (cfg_validate_at(cfg, o, d))
		return -1;
	diag md;
	return memcfg_check(cfg, &md) ? cfg_blame(o, md.msg, d) : 0;
}

int mem_init_hier(memport *p, eng *e, eng_clock core, const saar_config *cfg, uint64_t image_bytes,
                  mem_store *store, diag *d)
{
	hier_params hp;
	if (memcfg_hier(cfg, &hp, d)) {
		memset(p, 0, sizeof *p);
		return -1;
	}
	return hier_init(p, e, core, &hp, image_bytes, store, d);
}
