/*
 * memport.c: request counting and the fixed-latency model (see memport.h).
 */
#include "memport.h"

#include <stdlib.h>
#include <string.h>

typedef struct fixed_mem {
	eng *e;
	eng_clock clk;
	uint64_t latency;
} fixed_mem;

static void fixed_access(void *impl, const mem_req *r, eng_handler done, void *ctx, uint64_t arg)
{
	(void)r;
	fixed_mem *f = impl;
	if (done)
		eng_schedule(f->e, eng_after_cycles(f->e, f->clk, f->latency), done, ctx, arg);
}

static void fixed_destroy(void *impl)
{
	free(impl);
}

static const memport_model fixed_model = {"fixed", fixed_access, fixed_destroy, NULL};

int mem_init_fixed(memport *p, eng *e, eng_clock clk, int latency)
{
	memset(p, 0, sizeof *p);
	fixed_mem *f = malloc(sizeof *f);
	if (!f)
		return -1;
	*f = (fixed_mem){e, clk, latency < 0 ? 0 : (uint64_t)latency};
	p->model = &fixed_model;
	p->impl = f;
	return 0;
}

void mem_free(memport *p)
{
	if (p->model && p->model->destroy)
		p->model->destroy(p->impl);
	memset(p, 0, sizeof *p);
}

const char *mem_type_name(int type)
{
	static const char *const n[MEM_NTYPES] = {"shade", "kd", "list", "tri"};
	return type >= 0 && type < MEM_NTYPES ? n[type] : "?";
}
