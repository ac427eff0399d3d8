/*
 * view.c: views files (cameras and point lights) through libyaml.
 *
 * Owns view_load, view_list, camera_validate, view_place_default_light
 * and the views' description in reports (view_json, view_describe)
 * (view_default lives with the geometry it frames, in default_scene.c).
 * The file is read into a libyaml document by yl_load (yload.h), which
 * enforces the size, depth and node limits and the file-level rules as it
 * streams; every node keeps its start mark, so each error points at the
 * node it is about as "file:line:col: message". The format is described in
 * docs/views.md.
 */
#include "kernel-ref/view.h"

#include "kernel-ref/infile.h"
#include "kernel-ref/jsonw.h"
#include "kernel-ref/yload.h"

#include <errno.h>
#include <float.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

typedef struct yfile {
	const char *file;
	yaml_document_t doc;
	diag *d;
	int root_map; /* the root is a mapping: check_item checks its keys */
} yfile;

/* Which camera field a problem is about, so view_load can point at it. */
enum cam_field { CAM_EYE, CAM_LOOKAT, CAM_UP, CAM_FOV };

static int node_err(yfile *y, const yaml_node_t *n, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static int node_err(yfile *y, const yaml_node_t *n, const char *fmt, ...)
{
	char msg[768];
	va_list ap;
	va_start(ap, fmt);
	vsnprintf(msg, sizeof msg, fmt, ap);
	va_end(ap);
	int line = n ? (int)n->start_mark.line + 1 : 0;
	int col = n ? (int)n->start_mark.column + 1 : 0;
	return diag_set(y->d, y->file, line, col, "%s", msg);
}

static const char *scalar(const yaml_node_t *n)
{
	return n && n->type == YAML_SCALAR_NODE ? (const char *)n->data.scalar.value : NULL;
}

static yaml_node_t *node(yfile *y, int idx)
{
	return yaml_document_get_node(&y->doc, idx);
}

/* The file-level rules, checked as the file streams (yload.h): the root
 * is a mapping whose only key is `views`, once, a mapping of view names,
 * each a plain string of fewer than VIEW_NAME_MAX characters and unique.
 * The views themselves are checked when one is loaded. */
static int check_item(void *ctx, const yl_item *it)
{
	yfile *y = ctx;
	if (it->at == YL_ROOT) { /* any other root is refused once the file is read */
		y->root_map = it->value->type == YAML_MAPPING_NODE;
		return 0;
	}
	if (!y->root_map)
		return 0;
	const char *s = scalar(it->key);
	if (it->depth == 0) {
		if (!s || strcmp(s, "views") != 0)
			return node_err(
			    y, it->key,
			    "unknown top-level key '%s' (a views file has only `views`)",
			    s ? s : "?");
		if (it->first)
			return node_err(y, it->key, "duplicate key 'views' (first at line %d)",
			                (int)it->first->start_mark.line + 1);
		if (it->value->type != YAML_MAPPING_NODE)
			return node_err(y, it->value,
			                "`views` must be a mapping of view names to views");
		return 0;
	}
	if (it->depth > 1)
		return 0;
	if (!s)
		return node_err(y, it->key, "view names must be plain strings");
	if (!*s) /* --view cannot name it */
		return node_err(y, it->key, "empty view name");
	if (strlen(s) >= VIEW_NAME_MAX)
		return node_err(y, it->key, "view name is longer than %d characters",
		                VIEW_NAME_MAX - 1);
	if (it->first)
		return node_err(y, it->key, "duplicate view name '%s' (first at line %d)", s,
		                (int)it->first->start_mark.line + 1);
	return 0;
}

static int yfile_open(yfile *y, const char *file, diag *d)
{
	memset(y, 0, sizeof *y);
	y->file = file;
	y->d = d;
	FILE *f;
	int st = in_open(file, &f);
	if (st)
		return diag_set(d, file, 0, 0, "cannot open views file: %s", in_strerror(st));
	yl_opts o = {.what = "a views file",
	             .syntax = "not valid YAML",
	             .max_bytes = VIEW_FILE_MAX,
	             .max_nodes = VIEW_NODES_MAX,
	             .max_depth = YL_DEPTH_MAX,
	             .check = check_item,
	             .ctx = y};
	int rc = yl_load(&y->doc, f, file, &o, d);
	fclose(f);
	return rc;
}

/* Looks key up in a mapping node; NULL when absent. */
static yaml_node_t *map_get(yfile *y, const yaml_node_t *map, const char *key,
                            yaml_node_t **keynode)
{
	for (yaml_node_pair_t *p = map->data.mapping.pairs.start; p < map->data.mapping.pairs.top;
	     p++) {
		yaml_node_t *k = node(y, p->key);
		const char *s = scalar(k);
		if (s && strcmp(s, key) == 0) {
			if (keynode)
				*keynode = k;
			return node(y, p->value);
		}
	}
	return NULL;
}

/* The `views` mapping of the document, or NULL with diag filled (what the
 * file-level rules leave: an empty file, a root without `views`). */
static yaml_node_t *views_map(yfile *y)
{
	yaml_node_t *root = yaml_document_get_root_node(&y->doc);
	if (!root) {
		diag_set(y->d, y->file, 0, 0,
		         "file is empty; expected a top-level `views` mapping");
		return NULL;
	}
	yaml_node_t *views =
	    root->type == YAML_MAPPING_NODE ? map_get(y, root, "views", NULL) : NULL;
	if (!views)
		node_err(y, root, "no top-level `views` mapping");
	return views;
}

/* A finite number: strtod must consume the whole scalar (so "1.0x" is an
 * error, not 1.0) and the value must stay finite as a float. */
static int get_num(yfile *y, const yaml_node_t *n, const char *what, float *out)
{
	const char *s = scalar(n);
	if (!s)
		return node_err(y, n, "%s must be a number", what);
	char *end;
	errno = 0;
	double x = strtod(s, &end);
	const char *t = s + strlen(s);
	int nonfinite = !strcasecmp(s, ".nan") || !strcasecmp(s, ".inf") ||
	                !strcasecmp(s, "-.inf") || !strcasecmp(s, "+.inf");
	if (!nonfinite && (end == s || end != t))
		return node_err(y, n, "%s: '%s' is not a number", what, s);
	if (nonfinite || !isfinite(x) || !isfinite((float)x))
		return node_err(y, n, "%s: '%s' is not a finite number (NaN and Inf are rejected)",
		                what, s);
	*out = (float)x;
	return 0;
}

static int get_vec3(yfile *y, const yaml_node_t *n, const char *what, vec3 *out)
{
	if (!n || n->type != YAML_SEQUENCE_NODE)
		return node_err(y, n, "%s must be a list of 3 numbers [x, y, z]", what);
	long cnt = n->data.sequence.items.top - n->data.sequence.items.start;
	if (cnt != 3)
		return node_err(y, n, "%s must have exactly 3 numbers, got %ld", what, cnt);
	float c[3];
	for (int i = 0; i < 3; i++)
		if (get_num(y, node(y, n->data.sequence.items.start[i]), what, &c[i]) != 0)
			return -1;
	*out = v3(c[0], c[1], c[2]);
	return 0;
}

/* The checks shared by view files and command-line flags. Up must not be
 * parallel to the view direction: the camera basis (right = dir x up)
 * would be undefined, so it is rejected rather than guessed. The basis is
 * built in float (camera.c normalises lookat - eye and dir x up through
 * their squared lengths), so a view direction or up whose squared length
 * overflows (lookat - eye infinite from two huge finite points, or longer
 * than about 1e19) or underflows to zero would make it NaN or zero: those
 * are refused for what they are, not passed on as a blank frame or blamed
 * on up. */
static const char *camera_problem(const camera *c, enum cam_field *field)
{
	*field = CAM_EYE;
	if (!v3_finite(c->eye) || !v3_finite(c->lookat) || !v3_finite(c->up) ||
	    !isfinite(c->fov_deg))
		return "camera has a NaN or infinite number";
	*field = CAM_FOV;
	if (!(c->fov_deg > 0.0f && c->fov_deg < 180.0f))
		return "fov must be between 0 and 180 degrees (exclusive)";
	*field = CAM_LOOKAT;
	vec3 dir = v3_sub(c->lookat, c->eye);
	float d2 = v3_dot(dir, dir), u2 = v3_dot(c->up, c->up);
	if (dir.x == 0.0f && dir.y == 0.0f && dir.z == 0.0f)
		return "eye and lookat are the same point";
	if (!(d2 <= FLT_MAX))
		return "eye and lookat are too far apart for float math (more than about 1e19)";
	if (!(d2 >= FLT_MIN))
		return "eye and lookat are too close together for float math (less than about "
		       "1e-19)";
	*field = CAM_UP;
	if (c->up.x == 0.0f && c->up.y == 0.0f && c->up.z == 0.0f)
		return "up must not be the zero vector";
	if (!(u2 <= FLT_MAX) || !(u2 >= FLT_MIN))
		return "up is too long or too short for float math (its length must be between "
		       "about 1e-19 and 1e19)";
	if (v3_len(v3_cross(v3_norm(dir), v3_norm(c->up))) < 1e-3f)
		return "up is parallel to the view direction (lookat - eye)";
	return NULL;
}

int camera_validate(const camera *c, const char *what, diag *d)
{
	enum cam_field f;
	const char *p = camera_problem(c, &f);
	return p ? diag_set(d, what, 0, 0, "%s", p) : 0;
}

/* Collects the values of a mapping's keys, which must all be among the n
 * names in keys (each at most once): vals[i] is the value node of keys[i],
 * or NULL. `where` names the mapping in messages ("view 'x'"). */
static int map_fields(yfile *y, yaml_node_t *map, const char *const *keys, int n,
                      yaml_node_t **vals, const char *where)
{
	yaml_node_t *seen[n > 0 ? n : 1];
	memset(seen, 0, sizeof seen);
	for (int i = 0; i < n; i++)
		vals[i] = NULL;
	for (yaml_node_pair_t *p = map->data.mapping.pairs.start; p < map->data.mapping.pairs.top;
	     p++) {
		yaml_node_t *k = node(y, p->key);
		const char *s = scalar(k);
		int i = 0;
		while (i < n && !(s && strcmp(s, keys[i]) == 0))
			i++;
		if (i == n) {
			char expected[256] = "";
			for (int j = 0; j < n; j++)
				snprintf(expected + strlen(expected),
				         sizeof expected - strlen(expected), "%s%s", j ? ", " : "",
				         keys[j]);
			return node_err(y, k, "unknown key '%s' in %s (expected %s)", s ? s : "?",
			                where, expected);
		}
		if (seen[i])
			return node_err(y, k, "duplicate key '%s'", s);
		seen[i] = k;
		vals[i] = node(y, p->value);
	}
	return 0;
}

static int parse_camera(yfile *y, yaml_node_t *cn, const char *vname, camera *cam)
{
	static const char *const keys[] = {"eye", "lookat", "up", "fov"};
	yaml_node_t *vn[4];
	if (cn->type != YAML_MAPPING_NODE)
		return node_err(y, cn, "camera of view '%s' must be a mapping", vname);
	char where[VIEW_NAME_MAX + 32];
	snprintf(where, sizeof where, "camera of view '%s'", vname);
	if (map_fields(y, cn, keys, 4, vn, where))
		return -1;
	for (int i = 0; i < 4; i++)
		if (!vn[i])
			return node_err(y, cn, "camera of view '%s' has no '%s'", vname, keys[i]);
	if (get_vec3(y, vn[0], "eye", &cam->eye) || get_vec3(y, vn[1], "lookat", &cam->lookat) ||
	    get_vec3(y, vn[2], "up", &cam->up) || get_num(y, vn[3], "fov", &cam->fov_deg))
		return -1;
	enum cam_field f;
	const char *prob = camera_problem(cam, &f);
	return prob ? node_err(y, vn[f], "%s", prob) : 0;
}

static int parse_lights(yfile *y, yaml_node_t *ln, view *v)
{
	if (ln->type != YAML_SEQUENCE_NODE)
		return node_err(y, ln, "lights must be a list of [x, y, z] positions");
	v->lights_given = 1;
	v->nlights = 0;
	for (yaml_node_item_t *it = ln->data.sequence.items.start; it < ln->data.sequence.items.top;
	     it++) {
		yaml_node_t *p = node(y, *it);
		if (v->nlights == VIEW_MAX_LIGHTS)
			return node_err(y, p, "more than %d lights", VIEW_MAX_LIGHTS);
		light *l = &v->lights[v->nlights];
		if (get_vec3(y, p, "light position", &l->pos) != 0)
			return -1;
		l->color = v3(1, 1, 1);
		v->nlights++;
	}
	return 0;
}

/* The scene path is relative to the views file's folder; a procedural
 * scene (spd:NAME...) is kept as it is. */
static int resolve_scene(yfile *y, yaml_node_t *sn, view *v)
{
	const char *s = scalar(sn);
	if (!s || !*s)
		return node_err(y, sn, "scene must be a file path");
	const char *slash = strrchr(y->file, '/');
	int n;
	/* a procedural scene (kernel-ref/spd.h) is a name, not a path */
	if (s[0] == '/' || !slash || !strncmp(s, "spd:", 4))
		n = snprintf(v->scene, sizeof v->scene, "%s", s);
	else
		n = snprintf(v->scene, sizeof v->scene, "%.*s/%s", (int)(slash - y->file), y->file,
		             s);
	if (n < 0 || (size_t)n >= sizeof v->scene)
		return node_err(y, sn, "scene path is too long");
	return 0;
}

/* The `drt` mapping (drt.h): every key optional, each value checked by
 * drt_problem at its node. */
static int parse_drt(yfile *y, yaml_node_t *dn, const char *vname, drt_params *p)
{
	static const char *const keys[] = {"spp",        "aperture", "focus",
	                                   "light_size", "gloss",    "motion"};
	enum { NK = sizeof keys / sizeof *keys };
	yaml_node_t *vn[NK];
	if (dn->type != YAML_MAPPING_NODE)
		return node_err(y, dn, "drt of view '%s' must be a mapping", vname);
	char where[VIEW_NAME_MAX + 32];
	snprintf(where, sizeof where, "drt of view '%s'", vname);
	if (map_fields(y, dn, keys, NK, vn, where))
		return -1;
	float spp = 1, *f[] = {&spp, &p->aperture, &p->focus, &p->light_size, &p->gloss};
	for (int i = 0; i < 5; i++)
		if (vn[i] && get_num(y, vn[i], keys[i], f[i]))
			return -1;
	if (vn[5] && get_vec3(y, vn[5], "motion", &p->motion))
		return -1;
	p->spp = spp == (float)(int)spp && spp >= 1 && spp <= 64 ? (int)spp : -1;
	const char *key, *prob = drt_problem(p, &key);
	if (!prob)
		return 0;
	for (int i = 0; i < NK; i++)
		if (!strcmp(keys[i], key))
			return node_err(y, vn[i] ? vn[i] : dn, "%s", prob);
	return node_err(y, dn, "%s", prob);
}

static int parse_view(yfile *y, yaml_node_t *vn, const char *name, view *v)
{
	if (vn->type != YAML_MAPPING_NODE)
		return node_err(y, vn, "view '%s' must be a mapping", name);
	static const char *const keys[] = {"scene", "camera", "lights", "note", "drt"};
	yaml_node_t *val[5];
	char where[VIEW_NAME_MAX + 16];
	snprintf(where, sizeof where, "view '%s'", name);
	if (map_fields(y, vn, keys, 5, val, where))
		return -1;
	if (val[4] && parse_drt(y, val[4], name, &v->drt))
		return -1;
	if (val[0] && resolve_scene(y, val[0], v))
		return -1;
	if (val[2] && parse_lights(y, val[2], v))
		return -1;
	yaml_node_t *cam = val[1];
	if (!cam)
		return node_err(y, vn, "view '%s' has no camera", name);
	return parse_camera(y, cam, name, &v->cam);
}

int view_load(view *v, const char *file, const char *name, diag *d)
{
	memset(v, 0, sizeof *v);
	yfile y;
	if (yfile_open(&y, file, d) != 0)
		return -1;
	int rc = -1;
	yaml_node_t *views = views_map(&y);
	if (views) {
		yaml_node_t *vn = map_get(&y, views, name, NULL);
		if (vn) {
			snprintf(v->name, sizeof v->name, "%s", name);
			rc = parse_view(&y, vn, name, v);
		} else {
			/* the names that fit in one message, then how many more */
			char list[600] = "";
			size_t len = 0;
			int more = 0, shown = 0;
			for (yaml_node_pair_t *p = views->data.mapping.pairs.start;
			     p < views->data.mapping.pairs.top; p++) {
				const char *s = scalar(node(&y, p->key));
				if (more || len + strlen(s) + 2 >= sizeof list) {
					more++;
					continue;
				}
				len += (size_t)snprintf(list + len, sizeof list - len, "%s%s",
				                        shown++ ? ", " : "", s);
			}
			char tail[48] = "";
			if (more)
				snprintf(tail, sizeof tail, " and %d more", more);
			diag_set(d, file, 0, 0, "no view named '%s'; available views: %s%s", name,
			         shown ? list : "(none)", tail);
		}
	}
	yaml_document_delete(&y.doc);
	if (rc != 0)
		memset(v, 0, sizeof *v);
	return rc;
}

int view_scene_at(const char *file, const char *name, int *line, int *col)
{
	yfile y;
	diag d;
	*line = *col = 0;
	if (yfile_open(&y, file, &d) != 0)
		return -1;
	yaml_node_t *views = views_map(&y);
	yaml_node_t *vn = views ? map_get(&y, views, name, NULL) : NULL;
	yaml_node_t *sn =
	    vn && vn->type == YAML_MAPPING_NODE ? map_get(&y, vn, "scene", NULL) : NULL;
	if (sn) {
		*line = (int)sn->start_mark.line + 1;
		*col = (int)sn->start_mark.column + 1;
	}
	yaml_document_delete(&y.doc);
	return sn ? 0 : -1;
}

int view_list(const char *file, char (*names)[VIEW_NAME_MAX], int max, diag *d)
{
	yfile y;
	if (yfile_open(&y, file, d) != 0)
		return -1;
	int n = -1;
	yaml_node_t *views = views_map(&y);
	if (views) {
		n = 0;
		for (yaml_node_pair_t *p = views->data.mapping.pairs.start;
		     p < views->data.mapping.pairs.top && n < max; p++) {
			/* the file-level rules made every key a plain string */
			const char *s = scalar(node(&y, p->key));
			snprintf(names[n++], VIEW_NAME_MAX, "%s", s ? s : "");
		}
	}
	yaml_document_delete(&y.doc);
	return n;
}

void view_place_default_light(view *v, const scene *s)
{
	if (v->lights_given || v->nlights > 0)
		return;
	float r = 0.5f * v3_len(v3_sub(s->bounds.hi, s->bounds.lo));
	v->lights[0].pos = v3_add(v->cam.lookat, v3(0, 2 * r, r));
	v->lights[0].color = v3(1, 1, 1);
	v->nlights = 1;
}

void view_frame_bbox(view *v, aabb b)
{
	*v = (view){0};
	snprintf(v->name, sizeof v->name, "bbox");
	/* in double: a box far from the origin must not lose the framing */
	double c[3] = {0.5 * ((double)b.lo.x + b.hi.x), 0.5 * ((double)b.lo.y + b.hi.y),
	               0.5 * ((double)b.lo.z + b.hi.z)};
	const double dir[3] = {0.35, 0.45, 1.0};
	double dl = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
	double f[3] = {-dir[0] / dl, -dir[1] / dl, -dir[2] / dl}; /* forward */
	/* right = f x up(0,1,0), then up = right x f */
	double r[3] = {-f[2], 0, f[0]};
	double rl = sqrt(r[0] * r[0] + r[2] * r[2]);
	r[0] /= rl;
	r[2] /= rl;
	double u[3] = {r[1] * f[2] - r[2] * f[1], r[2] * f[0] - r[0] * f[2],
	               r[0] * f[1] - r[1] * f[0]};
	const double fov = VIEW_FRAME_FOV, t = 0.95 * tan(fov * M_PI / 360.0);
	/* eye = c - D f: a corner p (from c) sits at depth D + p.f and must
	 * have |p.r| and |p.u| within t times that depth */
	double dist = 0;
	for (int k = 0; k < 8; k++) {
		double p[3] = {(k & 1 ? b.hi.x : b.lo.x) - c[0], (k & 2 ? b.hi.y : b.lo.y) - c[1],
		               (k & 4 ? b.hi.z : b.lo.z) - c[2]};
		double z = p[0] * f[0] + p[1] * f[1] + p[2] * f[2];
		double x = fabs(p[0] * r[0] + p[1] * r[1] + p[2] * r[2]);
		double y = fabs(p[0] * u[0] + p[1] * u[1] + p[2] * u[2]);
		double need = fmax(x, y) / t - z;
		if (need > dist)
			dist = need;
	}
	if (!(dist > 0))
		dist = 1; /* a single point: any distance frames it */
	v->cam.lookat = v3((float)c[0], (float)c[1], (float)c[2]);
	v->cam.eye = v3((float)(c[0] - dist * f[0]), (float)(c[1] - dist * f[1]),
	                (float)(c[2] - dist * f[2]));
	v->cam.up = v3(0, 1, 0);
	v->cam.fov_deg = (float)fov;
}

static void json_vec(jsonw *j, const char *k, vec3 p)
{
	if (k)
		jsonw_key(j, k);
	jsonw_arr_begin(j);
	jsonw_num(j, p.x);
	jsonw_num(j, p.y);
	jsonw_num(j, p.z);
	jsonw_arr_end(j);
}

void view_json(struct jsonw *j, const view *v)
{
	jsonw_key(j, "camera");
	jsonw_obj_begin(j);
	json_vec(j, "eye", v->cam.eye);
	json_vec(j, "lookat", v->cam.lookat);
	json_vec(j, "up", v->cam.up);
	jsonw_knum(j, "fov_deg", v->cam.fov_deg);
	jsonw_obj_end(j);
	jsonw_key(j, "light_positions");
	jsonw_arr_begin(j);
	for (int i = 0; i < v->nlights; i++)
		json_vec(j, NULL, v->lights[i].pos);
	jsonw_arr_end(j);
	if (drt_is_off(&v->drt)) /* the pinhole frame's reports stay as they were */
		return;
	const drt_params *p = &v->drt;
	jsonw_key(j, "drt");
	jsonw_obj_begin(j);
	jsonw_kint(j, "spp", drt_spp(p));
	jsonw_knum(j, "aperture", p->aperture);
	jsonw_knum(j, "focus", p->focus);
	jsonw_knum(j, "light_size", p->light_size);
	jsonw_knum(j, "gloss", p->gloss);
	json_vec(j, "motion", p->motion);
	jsonw_obj_end(j);
}

void view_describe(const view *v, char *buf, size_t n)
{
	const camera *c = &v->cam;
	size_t k = (size_t)snprintf(
	    buf, n, "eye (%g,%g,%g) lookat (%g,%g,%g) up (%g,%g,%g) fov %g; ", c->eye.x, c->eye.y,
	    c->eye.z, c->lookat.x, c->lookat.y, c->lookat.z, c->up.x, c->up.y, c->up.z, c->fov_deg);
	if (k < n && v->nlights == 0)
		k += (size_t)snprintf(buf + k, n - k, "no lights");
	else if (k < n)
		k += (size_t)snprintf(buf + k, n - k, "light%s", v->nlights == 1 ? "" : "s");
	for (int i = 0; i < v->nlights && k < n; i++)
		k += (size_t)snprintf(buf + k, n - k, " (%g,%g,%g)", v->lights[i].pos.x,
		                      v->lights[i].pos.y, v->lights[i].pos.z);
	const drt_params *p = &v->drt;
	if (k < n && !drt_is_off(p))
		snprintf(
		    buf + k, n - k,
		    "; drt spp %d aperture %g focus %g light_size %g gloss %g motion (%g,%g,%g)",
		    drt_spp(p), p->aperture, p->focus, p->light_size, p->gloss, p->motion.x,
		    p->motion.y, p->motion.z);
}
