/*
 * yload.h: reading a small YAML input (a config, a views file) into a
 * libyaml document, with limits enforced while the file streams.
 *
 * libyaml's own loader (yaml_parser_load) reads the whole document before
 * the caller sees any of it, and its scanner takes quadratic time on deep
 * flow nesting (200,000 `[` took over a minute). yl_load reads the parser's
 * events one by one and builds the yaml_document_t itself (every node
 * keeps the start and end marks yaml_parser_load gives it), refusing, at
 * the event that breaks the rule and with file:line:col:
 *
 *   - a file larger than max_bytes (checked on the file's size before
 *     parsing, and again while reading);
 *   - nesting deeper than max_depth collections;
 *   - more than max_nodes nodes;
 *   - anchors and aliases (&name, *name): a config or views file has no
 *     use for them, and an alias lets a small file stand for a huge
 *     document (the "billion laughs": nine levels of ten aliases each are
 *     10^9 nodes) and would hide the keys it repeats from the checks below;
 *   - a second document ("only one YAML document is allowed");
 *   - whatever the caller's check refuses: it sees the root node as it
 *     starts and every mapping key as its value starts, before anything of
 *     the value is read, so a config stops at its first unknown key however
 *     much follows it.
 *
 * Duplicate keys are found with a hash of each mapping's keys (the check
 * is told of an earlier key with the same text), so a mapping of n keys
 * costs O(n), not O(n^2).
 */
#ifndef SAAR_KREF_YLOAD_H
#define SAAR_KREF_YLOAD_H

#include "kernel-ref/diag.h"

#include <stdio.h>
#include <yaml.h>

/* Nesting limit of both YAML inputs: a config nests 4 collections
 * (memory: l1: kd: size_kb), a views file 5 (views: NAME: camera: eye:
 * [...]); 32 leaves room for free-form `note` values. */
#define YL_DEPTH_MAX 32

enum yl_at {
	YL_ROOT, /* value is the document's root node */
	YL_PAIR  /* key (and value) of a mapping pair */
};

/* What a check is shown. The nodes are valid during the call only. */
typedef struct yl_item {
	enum yl_at at;
	/* YL_PAIR: the keys of the mappings around the pair, joined with '.'
	 * ("" in the root mapping, "chip.trav" under chip: trav:); a sequence
	 * item adds "[i]", a key that is not a scalar "?". */
	const char *path;
	int depth;                /* YL_PAIR: collections around the pair's mapping (0 = root) */
	const yaml_node_t *key;   /* YL_PAIR: the key, a scalar or a collection just started */
	const yaml_node_t *value; /* the value, a scalar or a collection just started
	                           * (no items yet); NULL for a key that is not a scalar,
	                           * which is shown once, before its value */
	const yaml_node_t *first; /* YL_PAIR: an earlier key of this mapping with the same
	                           * text, or NULL */
} yl_item;

/* Returns 0 to go on, or non-zero (having filled the caller's diag) to stop. */
typedef int (*yl_check_fn)(void *ctx, const yl_item *it);

typedef struct yl_opts {
	const char *what;   /* the input in limit messages: "a config", "a views file" */
	const char *syntax; /* prefix of libyaml's syntax errors: "YAML syntax error" */
	size_t max_bytes;   /* file size limit */
	size_t max_nodes;   /* node limit */
	int max_depth;      /* nesting limit, at most YL_DEPTH_MAX; 0 = YL_DEPTH_MAX */
	yl_check_fn check;  /* may be NULL */
	void *ctx;          /* passed to check */
} yl_opts;

/* Reads the YAML document in f (opened by the caller; `file` names it in
 * messages) into doc: 0 with doc initialized (no root node for an empty
 * file; yaml_document_delete it), or -1 with d filled and doc deleted. */
int yl_load(yaml_document_t *doc, FILE *f, const char *file, const yl_opts *o, diag *d);

#endif
