/*
 * test_memlevels.c: the hierarchy's levels chosen by name (hier_params
 * levels, mem/hier.h): the stacks the builder names, a stack without the
 * L1s, and stacks that cannot be built.
 */
#include "sim/config.h"
#include "sim/memconfig.h"
#include "tests/testutil.h"

/* Builds levels over cfg's parameters and reads n kd addresses functionally. */
static int build_and_read(const saar_config *cfg, const char *levels, int n, hier_stats *s, diag *d)
{
	hier_params hp;
	cr_assert_eq(memcfg_hier(cfg, &hp, d), 0, "%s", d->msg);
	snprintf(hp.levels, sizeof hp.levels, "%s", levels);
	eng *e = eng_create(16);
	memport mp;
	if (hier_init(&mp, e, eng_clock_mhz(533), &hp, 4 << 20, NULL, d)) {
		eng_destroy(e);
		return -1;
	}
	for (int i = 0; i < n; i++) {
		mem_req q = {(uint64_t)(i % 64) * 8, 8, MEM_KD, 0, 0, NULL, 0};
		mem_access_func(&mp, &q);
	}
	cr_assert_eq(hier_get_stats(&mp, s), 0);
	mem_free(&mp);
	eng_destroy(e);
	return 0;
}

/* The builder names today's stacks from today's keys. Catches a default
 * stack that drifts from memory.model / memory.vma.enabled. */
Test(memlevels, builder_names_todays_stacks)
{
	saar_config cfg;
	cfg_defaults(&cfg);
	diag d;
	char b[48];
	hier_params hp;
	cr_assert_str_eq(memcfg_levels(&cfg, b, sizeof b), "l1,sdram");
	cr_assert_eq(memcfg_hier(&cfg, &hp, &d), 0, "%s", d.msg);
	cr_assert_str_eq(hp.levels, "l1,sdram");
	cr_assert_eq(cfg_set(&cfg, "memory.vma.enabled=true", &d), 0, "%s", d.msg);
	cr_assert_str_eq(memcfg_levels(&cfg, b, sizeof b), "l1,vma,sdram");
	cr_assert_eq(memcfg_hier(&cfg, &hp, &d), 0, "%s", d.msg);
	cr_assert_str_eq(hp.levels, "l1,vma,sdram");
	cr_assert_eq(cfg_set(&cfg, "memory.model=fixed", &d), 0, "%s", d.msg);
	cr_assert_str_eq(memcfg_levels(&cfg, b, sizeof b), "fixed");
}

/* The level below the L1s is the one named: with "vma" the reads reach
 * the on-board cache, with "sdram" they do not. Catches a stack name that
 * is parsed but not obeyed. */
Test(memlevels, stack_decides_the_path)
{
	saar_config cfg;
	cfg_defaults(&cfg);
	diag d;
	hier_stats s;
	cr_assert_eq(build_and_read(&cfg, "l1,sdram", 1000, &s, &d), 0, "%s", d.msg);
	cr_assert_eq(s.vma_enabled, 0);
	cr_assert_eq(s.l1[MEM_KD].accesses, 1000);
	cr_assert_eq(s.l1[MEM_KD].misses, 64);
	cr_assert_eq(s.memif.reads[MEMIF_META], 0);
	cr_assert_eq(s.memif.reads[MEMIF_KD], 64);
	cr_assert_eq(build_and_read(&cfg, "l1,vma,sdram", 1000, &s, &d), 0, "%s", d.msg);
	cr_assert_eq(s.vma_enabled, 1);
	cr_assert_eq(s.l2.accesses, 64, "the 64 L1 misses reach the on-board cache");
	cr_assert_gt(s.memif.reads[MEMIF_META], 0, "the VMA reads its meta-data");
}

Test(memlevels, stacks_that_do_not_stack)
{
	saar_config cfg;
	cfg_defaults(&cfg);
	diag d;
	hier_stats s;
	static const char *const bad[] = {
	    "l1", "vma", "l1,sdram,vma", "sdram,l1", "l1,dram", "l1,vma,vma,sdram", ""};
	for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
		cr_assert_neq(build_and_read(&cfg, bad[i], 1, &s, &d), 0, "'%s' was built", bad[i]);
		cr_assert(strstr(d.msg, "memory.levels"), "%s", d.msg);
	}
}

/* memory.levels names the stack in a config: it sets memory.model and
 * memory.vma.enabled (so every reader of those keys agrees), a later key
 * contradicting it is refused, and the builder builds what it names.
 * Catches the key being stored but not applied. */
Test(memlevels, config_key_names_the_stack)
{
	saar_config cfg;
	cfg_defaults(&cfg);
	diag d;
	char b[48];
	cr_assert_str_eq(cfg.memory.levels, "");
	cr_assert_eq(cfg_set(&cfg, "memory.levels=l1,vma,sdram", &d), 0, "%s", d.msg);
	cr_assert(cfg.memory.vma.enabled);
	cr_assert_eq(cfg.memory.model, CFG_MEM_HIERARCHY);
	cr_assert_eq(cfg_validate(&cfg, &d), 0, "%s", d.msg);
	cr_assert_str_eq(memcfg_levels(&cfg, b, sizeof b), "l1,vma,sdram");
	cr_assert_eq(cfg_set(&cfg, "memory.vma.enabled=false", &d), 0, "%s", d.msg);
	cr_assert_neq(cfg_validate(&cfg, &d), 0);
	cr_assert(strstr(d.msg, "memory.levels"), "%s", d.msg);
	cr_assert_eq(cfg_set(&cfg, "memory.levels=fixed", &d), 0, "%s", d.msg);
	cr_assert_eq(cfg.memory.model, CFG_MEM_FIXED);
	cr_assert_eq(cfg_validate(&cfg, &d), 0, "%s", d.msg);
	/* the stack without the VMA, through the builder */
	cr_assert_eq(cfg_set(&cfg, "memory.levels=l1,sdram", &d), 0, "%s", d.msg);
	cr_assert_eq(cfg.memory.model, CFG_MEM_HIERARCHY);
	cr_assert(!cfg.memory.vma.enabled);
	eng *e = eng_create(16);
	memport mp;
	cr_assert_eq(mem_init_hier(&mp, e, eng_clock_mhz(533), &cfg, 4 << 20, NULL, &d), 0, "%s",
	             d.msg);
	hier_stats s;
	cr_assert_eq(hier_get_stats(&mp, &s), 0);
	cr_assert_eq(s.vma_enabled, 0);
	mem_free(&mp);
	eng_destroy(e);
	/* a name no level has fails where the stack is built */
	cr_assert_eq(cfg_set(&cfg, "memory.levels=l1,dram", &d), 0, "%s", d.msg);
	e = eng_create(16);
	cr_assert_neq(mem_init_hier(&mp, e, eng_clock_mhz(533), &cfg, 4 << 20, NULL, &d), 0);
	cr_assert(strstr(d.msg, "memory.levels") && strstr(d.msg, "dram"), "%s", d.msg);
	eng_destroy(e);
}

static void count_done(eng *e, void *ctx, uint64_t arg)
{
	(void)e;
	(void)arg;
	(*(int *)ctx)++;
}

/* A read refused for lack of an MSHR is parked for its port slot, which
 * may lie ahead of the fill that frees an MSHR: its wait for an MSHR is
 * then none, never below zero, so the sum over reads is never above the
 * sum of their waits. One port, all in one cycle: 17 misses to distinct
 * lines (16 MSHRs), then 200 reads of the first line, whose port slots
 * run 217 cycles ahead. Catches the wait now - since taken below zero
 * (it wrapped the stall count to about 1e16). */
Test(memlevels, a_parked_reads_wait_is_never_below_zero)
{
	saar_config c;
	diag d;
	cfg_defaults(&c);
	cr_assert_eq(cfg_set(&c, "memory.l1.kd.ports=1", &d), 0, "%s", d.msg);
	hier_params hp;
	cr_assert_eq(memcfg_hier(&c, &hp, &d), 0, "%s", d.msg);
	eng *e = eng_create(64);
	memport mp;
	cr_assert_eq(hier_init(&mp, e, eng_clock_mhz(533), &hp, 1 << 20, NULL, &d), 0, "%s", d.msg);
	int done = 0;
	for (int k = 0; k < 217; k++) {
		mem_req q = {k < 17 ? (uint64_t)k * 4096 : 0, 8, MEM_KD, 0, 0, NULL, 0};
		mem_access(&mp, &q, count_done, &done, 0);
	}
	eng_run(e, ENG_FOREVER);
	hier_stats s;
	cr_assert_eq(hier_get_stats(&mp, &s), 0);
	cr_assert_eq(done, 217, "every read answered");
	cr_assert_gt(s.mshr_stall_cycles[MEM_KD], 0, "no read waited for an MSHR: nothing tested");
	cr_assert_leq(s.mshr_stall_cycles[MEM_KD], s.wait_cycles[MEM_KD],
	              "MSHR stall %llu cycles above the reads' whole wait %llu",
	              (unsigned long long)s.mshr_stall_cycles[MEM_KD],
	              (unsigned long long)s.wait_cycles[MEM_KD]);
	mem_free(&mp);
	eng_destroy(e);
}
