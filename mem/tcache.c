/*
 * tcache.c: the timed cache component (see tcache.h).
 */
#include "mem/tcache.h"

#include <stdlib.h>
#include <string.h>

#define TC_CHUNK 256

typedef struct tc_chunk {
	struct tc_chunk *next;
	tc_wait w[TC_CHUNK];
} tc_chunk;

int tcache_init(tcache *t, const cache_params *p, int flags, const char *what, diag *d)
{
	memset(t, 0, sizeof *t);
	if (cache_init(&t->c, p, what, d))
		return -1;
	t->wait = calloc(p->mshrs, sizeof *t->wait);
	if (flags & TC_MBUF)
		t->mbuf = malloc((size_t)p->mshrs * p->line_bytes);
	if (!t->wait || ((flags & TC_MBUF) && !t->mbuf) ||
	    ((flags & TC_DATA) && cache_data_on(&t->c))) {
		tcache_free(t);
		return diag_set(d, "config", 0, 0, "%s: out of memory", what);
	}
	return 0;
}

void tcache_free(tcache *t)
{
	cache_free(&t->c);
	free(t->wait);
	free(t->mbuf);
	for (tc_chunk *c = t->chunks, *n; c; c = n) {
		n = c->next;
		free(c);
	}
	t->wait = NULL;
	t->mbuf = NULL;
	t->chunks = NULL;
	t->free_w = NULL;
}

/* tcache_wait_alloc's rare case, out of line: the free list is empty. */
tc_wait *tcache_wait_grow(tcache *t)
{
	tc_chunk *c = malloc(sizeof *c);
	if (!c) {
		t->oom = 1;
		return NULL;
	}
	c->next = t->chunks;
	t->chunks = c;
	for (int i = 0; i < TC_CHUNK; i++) {
		c->w[i].next = t->free_w;
		t->free_w = &c->w[i];
	}
	tc_wait *w = t->free_w;
	t->free_w = w->next;
	return w;
}
