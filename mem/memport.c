/*
 * memport.c: request counting and the fixed-latency model (see memport.h).
 */
#include "mem/memport.h"

#include <stdlib.h>
#include <string.h>

#include "mem/store.h"

typedef struct fixed_mem {
	eng *e;
	eng_clock clk;
	uint64_t latency;
	mem_store *ms;
} fixed_mem;

/* The data of a request: a read's bytes come from the store (taken at
 * once: nothing but the request's own thread writes what it reads), a
 * write's go into it. */
static void fixed_data(fixed_mem *f, const mem_req *r)
{
	if (!r->data || !f->ms)
		return;
	if (r->write)
		ms_write(f->ms, r->addr, r->bytes, r->data);
	else
		ms_read(f->ms, r->addr, r->bytes, r->data);
}

static void fixed_peek(void *impl, const mem_req *r, void *dst)
{
	fixed_mem *f = impl;
	if (f->ms)
		ms_read(f->ms, r->addr, r->bytes, dst);
	else
		memset(dst, 0, r->bytes);
}

static void fixed_access_func(void *impl, const mem_req *r)
{
	fixed_data(impl, r);
}

static int fixed_failed(const void *impl)
{
	const fixed_mem *f = impl;
	return f->ms && f->ms->oom;
}

static void fixed_access(void *impl, const mem_req *r, eng_handler done, void *ctx, uint64_t arg)
{
	fixed_mem *f = impl;
	fixed_data(f, r);
	if (done)
		eng_schedule(f->e, eng_after_cycles(f->e, f->clk, f->latency), done, ctx, arg);
}

static void fixed_destroy(void *impl)
{
	free(impl);
}

static const memport_model fixed_model = {
    "fixed", fixed_access, fixed_destroy, fixed_access_func, fixed_peek, fixed_failed, NULL};

int mem_init_fixed(memport *p, eng *e, eng_clock clk, int latency, mem_store *store)
{
	memset(p, 0, sizeof *p);
	fixed_mem *f = malloc(sizeof *f);
	if (!f)
		return -1;
	*f = (fixed_mem){e, clk, latency < 0 ? 0 : (uint64_t)latency, store};
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

int mem_observe(memport *p, const mem_obs *o)
{
	if (!p->model || !p->model->observe)
		return -1;
	p->model->observe(p->impl, o);
	return 0;
}

const char *mem_type_name(int type)
{
	static const char *const n[MEM_NTYPES] = {"shade", "kd", "list", "tri"};
	return type >= 0 && type < MEM_NTYPES ? n[type] : "?";
}
