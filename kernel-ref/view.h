/*
 * view.h: cameras and point lights, read from a views file.
 *
 * The views file format is the one of ../shared/scenes/views.yaml (see
 * docs/views.md):
 *
 *   views:
 *     NAME:
 *       scene: relative/path.obj.gz      # relative to the views file
 *       camera: {eye: [x,y,z], lookat: [x,y,z], up: [x,y,z], fov: degrees}
 *       lights: [[x,y,z], ...]           # optional; white, intensity 1
 *       drt: {spp: 16, aperture: 0.5, ...} # optional; distribution effects (drt.h)
 *       note: "free text"                # optional, ignored
 *
 * A view without `lights` gets one light at lookat + (0, 2R, R), R = half
 * the scene's bounding-box diagonal (view_place_default_light, once the
 * scene is loaded). Parsing uses libyaml; every error names the file, line
 * and column.
 */
#ifndef SAAR_KREF_VIEW_H
#define SAAR_KREF_VIEW_H

#include "kernel-ref/diag.h"
#include "kernel-ref/drt.h"
#include "kernel-ref/scene.h"
#include "kernel-ref/vecmath.h"

#define VIEW_MAX_LIGHTS 16
#define VIEW_NAME_MAX   64
/* Limits of a views file (docs/views.md "Limits"); nesting: YL_DEPTH_MAX
 * (yload.h). */
#define VIEW_FILE_MAX  (4u << 20)
#define VIEW_NODES_MAX (1u << 18)

typedef struct camera {
	vec3 eye, lookat, up;
	float fov_deg; /* vertical field of view, degrees, in (0, 180) */
} camera;

typedef struct light {
	vec3 pos;
	vec3 color; /* white (1,1,1) from views files */
} light;

typedef struct view {
	char name[VIEW_NAME_MAX];
	char scene[1024]; /* scene path resolved against the views file's folder; "" if none */
	camera cam;
	int lights_given; /* 0: place the default light once the scene is known */
	int nlights;
	light lights[VIEW_MAX_LIGHTS];
	drt_params drt; /* distribution effects; all zero: the pinhole frame */
} view;

/* Reads view `name` from `file`. Unknown name: the diag lists the names
 * that exist. Missing keys, wrong types, NaN/Inf numbers, fov out of range,
 * up parallel to the view direction, eye == lookat: -1 with
 * "file:line:col: message". */
int view_load(view *v, const char *file, const char *name, diag *d);

/* Where view `name`'s `scene:` value starts in `file` (1-based), for a
 * message about the scene it names (world_load: "views.yaml:3:12: scene
 * x.obj: cannot open ..."); -1 (and 0, 0) when the file no longer says. */
int view_scene_at(const char *file, const char *name, int *line, int *col);

/* Lists the view names in `file` in file order (at most max); returns the
 * count or -1 with diag. */
int view_list(const char *file, char (*names)[VIEW_NAME_MAX], int max, diag *d);

/* Checks a camera built from flags (same rules as view_load); `what` names
 * the source in the message (e.g. "--eye"). */
int camera_validate(const camera *c, const char *what, diag *d);

/* Writes the view's camera and lights as the JSON keys "camera" ({eye,
 * lookat, up: [x,y,z], fov_deg}) and "light_positions" ([[x,y,z], ...]),
 * so a report says what was rendered even when flags changed the view. */
struct jsonw;
void view_json(struct jsonw *j, const view *v);

/* Describes the camera and lights in one line ("eye (x,y,z) lookat ...
 * fov F; lights (x,y,z) ..."), for text reports. */
void view_describe(const view *v, char *buf, size_t n);

/* The view of the embedded default scene (scene_default). */
void view_default(view *v);

/* If the view has no lights, places the default one for scene s. */
void view_place_default_light(view *v, const scene *s);

/* The view of a scene file given without one: named "bbox", it looks at
 * the centre of box b from direction (0.35, 0.45, 1) with a 45-degree
 * field of view and up (0, 1, 0), at the closest distance that keeps all
 * eight corners inside 95% of a square frame: the rule of the shared
 * views file's "bbox framed from +z" views. Lights are left to
 * view_place_default_light. */
void view_frame_bbox(view *v, aabb b);
/* view_frame_bbox's field of view, degrees (world.c takes a framed
 * view's packet footprint from it before the scene's box is known). */
#define VIEW_FRAME_FOV 45.0

#endif
