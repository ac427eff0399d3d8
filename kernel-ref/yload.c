/*
 * yload.c: a YAML document built from libyaml's events, with limits
 * enforced as they stream (yload.h says which and why).
 */
#include "kernel-ref/yload.h"

#include <stdarg.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* An open collection. */
typedef struct yl_frame {
	int node;        /* its node id */
	int is_map;      /* mapping (1) or sequence (0) */
	int key;         /* mapping: the key waiting for its value, 0 = none */
	int key_shown;   /* that key was not a scalar and has been checked already */
	size_t path_len; /* the path's length outside this collection */
	size_t items;    /* sequence: items so far */
} yl_frame;

/* A mapping's key in the duplicate table. */
typedef struct yl_slot {
	uint64_t h;
	int map, key; /* node ids; key 0 = free */
} yl_slot;

typedef struct yl {
	yaml_parser_t p;
	yaml_document_t *doc;
	int have_doc; /* doc is initialized */
	const yl_opts *o;
	const char *file;
	diag *d;
	int max_depth;
	FILE *f;
	size_t left;  /* bytes the file may still have */
	int too_big;  /* it had more */
	size_t nodes; /* nodes so far */
	yl_frame st[YL_DEPTH_MAX];
	int depth;
	char *path; /* the path of the innermost collection (yl_item.path) */
	size_t path_len, path_cap;
	yl_slot *tab; /* open addressing, a power of two long */
	size_t tab_cap, tab_used;
	uint64_t seed;
} yl;

static int yl_read(void *data, unsigned char *buf, size_t size, size_t *size_read)
{
	yl *y = data;
	/* one byte past the limit tells a file that grew past it */
	size_t want = size <= y->left ? size : y->left + 1;
	size_t n = fread(buf, 1, want, y->f);
	if (n > y->left) {
		y->too_big = 1;
		return 0;
	}
	y->left -= n;
	*size_read = n;
	return !ferror(y->f);
}

static int too_big(yl *y)
{
	return diag_set(y->d, y->file, 0, 0, "larger than the size limit for %s (%zu bytes)",
	                y->o->what, y->o->max_bytes);
}

/* "file:line:col: message" at mark m. */
static int at(yl *y, yaml_mark_t m, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

static int at(yl *y, yaml_mark_t m, const char *fmt, ...)
{
	char msg[512];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(msg, sizeof msg, fmt, ap);
	va_end(ap);
	return diag_set(y->d, y->file, (int)m.line + 1, (int)m.column + 1, "%s", msg);
}

static int oom(yl *y)
{
	return diag_set(y->d, y->file, 0, 0, "out of memory while reading YAML");
}

static int parse_error(yl *y)
{
	yaml_parser_t *p = &y->p;
	if (y->too_big)
		return too_big(y);
	if (p->error == YAML_MEMORY_ERROR)
		return oom(y);
	if (p->error == YAML_READER_ERROR)
		return diag_set(y->d, y->file, 0, 0, "unreadable input at byte %zu: %s",
		                p->problem_offset, p->problem ? p->problem : "?");
	return diag_set(y->d, y->file, (int)p->problem_mark.line + 1,
	                (int)p->problem_mark.column + 1, "%s: %s%s%s%s", y->o->syntax,
	                p->problem ? p->problem : "?", p->context ? " (" : "",
	                p->context ? p->context : "", p->context ? ")" : "");
}

/* ---- the path ---- */

static int path_push(yl *y, const char *s, size_t n, size_t index, int is_index)
{
	char num[32];
	if (is_index) {
		n = (size_t)snprintf(num, sizeof num, "[%zu]", index);
		s = num;
	}
	size_t dot = !is_index && y->path_len > 0;
	if (y->path_len + dot + n + 1 > y->path_cap) {
		size_t cap = 2 * (y->path_len + dot + n + 1);
		char *np = realloc(y->path, cap);
		if (!np)
			return oom(y);
		y->path = np;
		y->path_cap = cap;
	}
	if (dot)
		y->path[y->path_len++] = '.';
	memcpy(y->path + y->path_len, s, n);
	y->path_len += n;
	y->path[y->path_len] = 0;
	return 0;
}

/* ---- duplicate keys ---- */

static uint64_t key_hash(uint64_t seed, int map, const yaml_node_t *k)
{
	uint64_t h = seed ^ ((uint64_t)(unsigned)map * 0x9e3779b97f4a7c15ull);
	for (size_t i = 0; i < k->data.scalar.length; i++) {
		h ^= k->data.scalar.value[i];
		h *= 0x100000001b3ull; /* FNV-1a */
	}
	h ^= h >> 30; /* splitmix64's finish: every bit reaches the slot index */
	h *= 0xbf58476d1ce4e5b9ull;
	h ^= h >> 27;
	h *= 0x94d049bb133111ebull;
	return h ^ (h >> 31);
}

static int same_key(const yaml_node_t *a, const yaml_node_t *b)
{
	return a->data.scalar.length == b->data.scalar.length &&
	       !memcmp(a->data.scalar.value, b->data.scalar.value, a->data.scalar.length);
}

static int tab_grow(yl *y)
{
	size_t cap = y->tab_cap ? 2 * y->tab_cap : 64;
	yl_slot *t = calloc(cap, sizeof *t);
	if (!t)
		return oom(y);
	for (size_t i = 0; i < y->tab_cap; i++) {
		if (!y->tab[i].key)
			continue;
		size_t j = y->tab[i].h & (cap - 1);
		while (t[j].key)
			j = (j + 1) & (cap - 1);
		t[j] = y->tab[i];
	}
	free(y->tab);
	y->tab = t;
	y->tab_cap = cap;
	return 0;
}

/* The first key of mapping `map` with the text of scalar key `key`: 0 if
 * key is the first (it is then remembered), -1 when out of memory. */
static int key_first(yl *y, int map, int key)
{
	if (2 * (y->tab_used + 1) > y->tab_cap && tab_grow(y))
		return -1;
	const yaml_node_t *kn = yaml_document_get_node(y->doc, key);
	uint64_t h = key_hash(y->seed, map, kn);
	size_t j = h & (y->tab_cap - 1);
	for (; y->tab[j].key; j = (j + 1) & (y->tab_cap - 1))
		if (y->tab[j].h == h && y->tab[j].map == map &&
		    same_key(yaml_document_get_node(y->doc, y->tab[j].key), kn))
			return y->tab[j].key;
	y->tab[j] = (yl_slot){h, map, key};
	y->tab_used++;
	return 0;
}

/* ---- nodes ---- */

static int check(yl *y, enum yl_at what, int key, int value, int first)
{
	if (!y->o->check)
		return 0;
	yl_item it = {
	    .at = what,
	    .path = y->path ? y->path : "",
	    .depth = y->depth - 1,
	    .key = key ? yaml_document_get_node(y->doc, key) : NULL,
	    .value = value ? yaml_document_get_node(y->doc, value) : NULL,
	    .first = first ? yaml_document_get_node(y->doc, first) : NULL,
	};
	return y->o->check(y->o->ctx, &it);
}

/* Places new node id (a scalar, or a collection just started) in the
 * collection around it, showing the check what it asks to see. For a
 * collection, also opens its path component. */
static int attach(yl *y, int id, int is_coll)
{
	if (!y->depth) {
		if (check(y, YL_ROOT, 0, id, 0))
			return -1;
		return 0;
	}
	yl_frame *fr = &y->st[y->depth - 1];
	const yaml_node_t *nd = yaml_document_get_node(y->doc, id);
	if (!fr->is_map) {
		if (!yaml_document_append_sequence_item(y->doc, fr->node, id))
			return oom(y);
		return is_coll ? path_push(y, NULL, 0, fr->items++, 1) : (fr->items++, 0);
	}
	if (!fr->key) { /* a key */
		fr->key = id;
		fr->key_shown = nd->type != YAML_SCALAR_NODE;
		if (fr->key_shown && check(y, YL_PAIR, id, 0, 0))
			return -1;
		return is_coll ? path_push(y, "?", 1, 0, 0) : 0;
	}
	/* a value */
	int key = fr->key;
	fr->key = 0;
	if (!fr->key_shown) {
		int first = key_first(y, fr->node, key);
		if (first < 0 || check(y, YL_PAIR, key, id, first))
			return -1;
	}
	if (!yaml_document_append_mapping_pair(y->doc, fr->node, key, id))
		return oom(y);
	if (!is_coll)
		return 0;
	const yaml_node_t *kn = yaml_document_get_node(y->doc, key);
	if (kn->type != YAML_SCALAR_NODE)
		return path_push(y, "?", 1, 0, 0);
	return path_push(y, (const char *)kn->data.scalar.value, kn->data.scalar.length, 0, 0);
}

/* The checks every node's event passes. */
static int new_node(yl *y, const yaml_event_t *ev, const yaml_char_t *anchor)
{
	if (anchor)
		return at(y, ev->start_mark, "YAML anchors and aliases are not allowed in %s (&%s)",
		          y->o->what, (const char *)anchor);
	if (y->nodes >= y->o->max_nodes)
		return at(y, ev->start_mark, "more than %zu YAML nodes (the node limit for %s)",
		          y->o->max_nodes, y->o->what);
	y->nodes++;
	return 0;
}

/* The tag a node gets: libyaml's default for none or "!", as in
 * yaml_parser_load. */
static const yaml_char_t *tag_of(const yaml_char_t *t)
{
	return !t || !strcmp((const char *)t, "!") ? NULL : t;
}

static void set_marks(yl *y, int id, const yaml_event_t *ev)
{
	yaml_node_t *n = yaml_document_get_node(y->doc, id);
	n->start_mark = ev->start_mark;
	n->end_mark = ev->end_mark;
}

static int on_scalar(yl *y, const yaml_event_t *ev)
{
	if (new_node(y, ev, ev->data.scalar.anchor))
		return -1;
	if (ev->data.scalar.length > INT32_MAX)
		return too_big(y);
	/* a "\0" escape: every reader takes the value as a C string, cut
	 * there ("good.obj\0x" loaded good.obj without a word) */
	if (memchr(ev->data.scalar.value, 0, ev->data.scalar.length))
		return at(y, ev->start_mark, "a NUL byte (\\0) in a string");
	int id =
	    yaml_document_add_scalar(y->doc, tag_of(ev->data.scalar.tag), ev->data.scalar.value,
	                             (int)ev->data.scalar.length, ev->data.scalar.style);
	if (!id)
		return oom(y);
	set_marks(y, id, ev);
	return attach(y, id, 0);
}

static int on_start(yl *y, const yaml_event_t *ev)
{
	int is_map = ev->type == YAML_MAPPING_START_EVENT;
	if (y->depth >= y->max_depth)
		return at(y, ev->start_mark,
		          "YAML nested deeper than %d levels (the depth limit for %s)",
		          y->max_depth, y->o->what);
	if (new_node(y, ev,
	             is_map ? ev->data.mapping_start.anchor : ev->data.sequence_start.anchor))
		return -1;
	int id = is_map ? yaml_document_add_mapping(y->doc, tag_of(ev->data.mapping_start.tag),
	                                            ev->data.mapping_start.style)
	                : yaml_document_add_sequence(y->doc, tag_of(ev->data.sequence_start.tag),
	                                             ev->data.sequence_start.style);
	if (!id)
		return oom(y);
	set_marks(y, id, ev);
	size_t outer = y->path_len;
	if (attach(y, id, 1))
		return -1;
	y->st[y->depth++] = (yl_frame){.node = id, .is_map = is_map, .path_len = outer};
	return 0;
}

static int on_end(yl *y, const yaml_event_t *ev)
{
	yl_frame *fr = &y->st[--y->depth];
	yaml_document_get_node(y->doc, fr->node)->end_mark = ev->end_mark;
	y->path_len = fr->path_len;
	if (y->path)
		y->path[y->path_len] = 0;
	return 0;
}

/* A second document is refused at its root node (yaml_parser_load would
 * have left it unread). */
static int second_doc(yl *y)
{
	yaml_event_t ev;
	if (!yaml_parser_parse(&y->p, &ev))
		return parse_error(y);
	int rc = at(y, ev.start_mark, "only one YAML document is allowed");
	yaml_event_delete(&ev);
	return rc;
}

static int on_event(yl *y, const yaml_event_t *ev)
{
	switch (ev->type) {
	case YAML_DOCUMENT_START_EVENT:
		if (y->have_doc)
			return second_doc(y);
		if (!yaml_document_initialize(y->doc, NULL, NULL, NULL,
		                              ev->data.document_start.implicit, 1))
			return oom(y);
		y->have_doc = 1;
		y->doc->start_mark = ev->start_mark;
		return 0;
	case YAML_DOCUMENT_END_EVENT:
		y->doc->end_implicit = ev->data.document_end.implicit;
		y->doc->end_mark = ev->end_mark;
		return 0;
	case YAML_ALIAS_EVENT:
		return at(y, ev->start_mark, "YAML anchors and aliases are not allowed in %s (*%s)",
		          y->o->what, (const char *)ev->data.alias.anchor);
	case YAML_SCALAR_EVENT:
		return on_scalar(y, ev);
	case YAML_SEQUENCE_START_EVENT:
	case YAML_MAPPING_START_EVENT:
		return on_start(y, ev);
	case YAML_SEQUENCE_END_EVENT:
	case YAML_MAPPING_END_EVENT:
		return on_end(y, ev);
	default: /* stream start and end */
		return 0;
	}
}

int yl_load(yaml_document_t *doc, FILE *f, const char *file, const yl_opts *o, diag *d)
{
	memset(doc, 0, sizeof *doc);
	struct stat sb;
	if (!fstat(fileno(f), &sb) && sb.st_size > 0 && (uintmax_t)sb.st_size > o->max_bytes)
		return diag_set(d, file, 0, 0, "larger than the size limit for %s (%zu bytes)",
		                o->what, o->max_bytes);
	yl y = {.doc = doc, .o = o, .file = file, .d = d, .f = f, .left = o->max_bytes};
	y.max_depth = o->max_depth > 0 && o->max_depth < YL_DEPTH_MAX ? o->max_depth : YL_DEPTH_MAX;
	/* a seed unknown to the file keeps its keys from all landing in one
	 * slot of the duplicate table; the outcome does not depend on it */
	if (getentropy(&y.seed, sizeof y.seed))
		y.seed = 0x243f6a8885a308d3ull;
	if (!yaml_parser_initialize(&y.p))
		return oom(&y);
	yaml_parser_set_input(&y.p, yl_read, &y);
	int rc = 0;
	for (int end = 0; !rc && !end;) {
		yaml_event_t ev;
		if (!yaml_parser_parse(&y.p, &ev)) {
			rc = parse_error(&y);
			break;
		}
		end = ev.type == YAML_STREAM_END_EVENT;
		rc = on_event(&y, &ev);
		yaml_event_delete(&ev);
	}
	if (!rc && !y.have_doc) { /* an empty file: a document without nodes */
		if (yaml_document_initialize(doc, NULL, NULL, NULL, 1, 1))
			y.have_doc = 1;
		else
			rc = oom(&y);
	}
	if (rc && y.have_doc) {
		yaml_document_delete(doc);
		memset(doc, 0, sizeof *doc);
	}
	free(y.path);
	free(y.tab);
	yaml_parser_delete(&y.p);
	return rc ? -1 : 0;
}
