/*
 * stress_main.c: `make stress` — the numerical stress suite at full size.
 * Runs every case of stress.h over scales and offsets, prints the table
 * and, with --out, writes it into that document between the markers
 * <!-- BEGIN stress --> and <!-- END stress --> (the rest of the file is
 * kept; written to a temporary file and renamed). Without --out nothing
 * is written (it once rewrote docs/NUMERICS.md relative to whatever
 * folder it ran in).
 *
 *   saarsim-stress [--out docs/NUMERICS.md] [--quick] [--views FILE] [--no-precision]
 *
 * It also writes the reduced-precision table between <!-- BEGIN precision
 * --> and <!-- END precision -->: mantissa bits against image error,
 * leaked rays and extra traversal steps, per shared view (views file from
 * --views, else $SAAR_SCENES/views.yaml, else ../shared/scenes/views.yaml;
 * skipped with a note when absent) and the embedded scene, and with --out
 * the plot precision.png beside the document, through gnuplot when it is
 * installed.
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "kernel-ref/atomicfile.h"
#include "kernel-ref/infile.h"
#include "kernel-ref/render.h"
#include "kernel-ref/stress.h"
#include "kernel-ref/world.h"

#define MAXR 64

/* ---- reduced precision ---------------------------------------------------- */

static const int prec_bits[] = {23, 20, 16, 14, 12, 10, 8};
#define NBITS ((int)(sizeof prec_bits / sizeof *prec_bits))

typedef struct prec_row {
	double psnr_ti, psnr_sh; /* trav+isect, shading only */
	uint64_t diff_ti, diff_sh;
	double steps; /* kd-node steps relative to float, trav+isect */
} prec_row;

static pkt_precision prec_of(int m, int trav_isect, int shade)
{
	pkt_precision p;
	pkt_precision_full(&p);
	if (trav_isect) {
		fpfmt_init(&p.trav, 8, m, FPR_NEAREST);
		fpfmt_init(&p.isect, 8, m, FPR_NEAREST);
	}
	if (shade)
		fpfmt_init(&p.shade, 8, m, FPR_NEAREST);
	return p;
}

/* Renders w at res x res with prec into rgb (8-bit); returns node steps. */
static int render_rgb(const world *w, int res, const pkt_precision *prec, uint8_t *rgb,
                      uint64_t *steps)
{
	render_opts ro;
	render_opts_default(&ro);
	ro.width = ro.height = res;
	ro.threads = 2;
	ro.prec = prec;
	framebuf fb;
	render_stats st;
	diag d;
	if (fb_init(&fb, res, res))
		return -1;
	if (render_frame(&w->m, &w->v, &ro, &fb, &st, &d)) {
		fprintf(stderr, "saarsim-stress: %s\n", d.msg);
		fb_free(&fb);
		return -1;
	}
	fb_to_rgb8(&fb, rgb, NULL);
	fb_free(&fb);
	*steps = st.trav.node_steps;
	return 0;
}

/* One view: every format against float. */
static int prec_view(const world *w, int res, prec_row *rows)
{
	size_t n = (size_t)res * (size_t)res * 3;
	uint8_t *ref = malloc(n), *img = malloc(n);
	uint64_t ref_steps = 0, steps = 0;
	int rc = !ref || !img || render_rgb(w, res, NULL, ref, &ref_steps);
	for (int k = 0; k < NBITS && !rc; k++) {
		pkt_precision ti = prec_of(prec_bits[k], 1, 0), sh = prec_of(prec_bits[k], 0, 1);
		rc |= render_rgb(w, res, &ti, img, &steps);
		img_cmp c = img_compare(ref, img, res, res);
		rows[k].psnr_ti = c.psnr;
		rows[k].diff_ti = c.differing_pixels;
		rows[k].steps = ref_steps ? (double)steps / (double)ref_steps : 1.0;
		rc |= render_rgb(w, res, &sh, img, &steps);
		c = img_compare(ref, img, res, res);
		rows[k].psnr_sh = c.psnr;
		rows[k].diff_sh = c.differing_pixels;
	}
	free(ref);
	free(img);
	return rc;
}

static void fmt_psnr(char *b, size_t n, double p)
{
	if (isinf(p))
		snprintf(b, n, "identical");
	else
		snprintf(b, n, "%.1f", p);
}

/* gnuplot: mantissa bits against mean PSNR and leaks; optional. */
static void prec_plot(const char *png, const double *ti, const double *sh, const uint64_t *leaks)
{
	if (system("command -v gnuplot >/dev/null 2>&1") != 0) {
		fprintf(stderr, "saarsim-stress: gnuplot not found; no %s\n", png);
		return;
	}
	FILE *g = popen("gnuplot", "w");
	if (!g)
		return;
	fprintf(g,
	        "set terminal pngcairo size 800,480\nset output '%s'\n"
	        "set title 'Reduced precision (8 exponent bits): image error against float'\n"
	        "set xlabel 'mantissa bits'\nset ylabel 'PSNR (dB), mean over views'\n"
	        "set y2label 'leaked rays (closed spheres)'\nset y2tics\nset y2range [0:*]\nset "
	        "ytics nomirror\n"
	        "set xrange [24:7]\nset key bottom left\nset grid\n"
	        "plot '-' u 1:2 w lp lw 2 t 'traversal + intersection', "
	        "'-' u 1:2 w lp lw 2 t 'shading only', "
	        "'-' u 1:2 axes x1y2 w lp lw 2 t 'leaked rays (right axis)'\n",
	        png);
	for (int s = 0; s < 3; s++) {
		for (int k = 0; k < NBITS; k++) {
			double v = s == 0 ? ti[k] : s == 1 ? sh[k] : (double)leaks[k];
			if (s < 2 && isinf(v))
				continue; /* identical: no finite PSNR */
			fprintf(g, "%d %g\n", prec_bits[k], v);
		}
		fputs("e\n", g);
	}
	if (pclose(g) != 0)
		fprintf(stderr, "saarsim-stress: gnuplot failed; %s may be missing\n", png);
}

/* The leak table's rows: per mantissa width, the five spheres' totals;
 * each width's leaked rays into leaks. Returns the length added. */
static size_t prec_leaks(char *t, size_t cap, int sres, uint64_t leaks[NBITS])
{
	size_t len = 0;
	for (int k = 0; k < NBITS; k++) {
		pkt_precision p = prec_of(prec_bits[k], 1, 0);
		const double sc[][2] = {{1e-4, 0}, {1, 0}, {1e4, 0}, {1e6, 0}, {100, 1e5}};
		stress_result tot = {{0}, 0, 0, 0, 0, 0, 0, 0, 0};
		for (size_t i = 0; i < sizeof sc / sizeof *sc; i++) {
			stress_result r = stress_sphere_fp(sc[i][0], sc[i][1], sres, &p);
			tot.rays += r.rays;
			tot.leaked += r.leaked;
			tot.mismatch += r.mismatch;
			tot.ties += r.ties;
			tot.ms += r.ms;
		}
		leaks[k] = tot.leaked;
		len += (size_t)snprintf(
		    t + len, cap - len, "| %d | %llu | %llu | %llu | %llu | %.0f |\n", prec_bits[k],
		    (unsigned long long)tot.rays, (unsigned long long)tot.leaked,
		    (unsigned long long)tot.mismatch, (unsigned long long)tot.ties, tot.ms);
	}
	return len;
}

/* The image-error table's rows: per view (the embedded scene, then each
 * of views' views), per mantissa width; the PSNR sums over the views into
 * sum_ti and sum_sh, their count into *nsum and the views file's view
 * count into *nv_out. Returns the length added. */
static size_t prec_views(char *t, size_t cap, int res, const char *views, double sum_ti[NBITS],
                         double sum_sh[NBITS], int *nsum, int *nv_out)
{
	size_t len = 0;
	char names[16][VIEW_NAME_MAX];
	diag d;
	int nv = 0;
	if (views && access(views, R_OK) == 0) {
		nv = view_list(views, names, 16, &d);
		if (nv < 0) {
			fprintf(stderr, "saarsim-stress: %s\n", d.msg);
			nv = 0;
		}
	}
	for (int v = -1; v < nv; v++) {
		world_opts o;
		world_opts_default(&o);
		/* no default world-cache folder (issue 36): built as before, its
		 * arrays whole, nothing written into the user's home */
		o.cache_dir = "off";
		if (v >= 0) {
			o.views = views;
			o.view = names[v];
		}
		world w;
		if (world_load(&w, &o, &d)) {
			fprintf(stderr, "saarsim-stress: %s (view skipped)\n", d.msg);
			continue;
		}
		prec_row rows[NBITS];
		double t0 = (double)clock();
		int rc = prec_view(&w, res, rows);
		fprintf(stderr, "saarsim-stress: precision, view %s: %.1f s CPU\n",
		        v < 0 ? "embedded" : names[v], ((double)clock() - t0) / CLOCKS_PER_SEC);
		if (!rc) {
			for (int k = 0; k < NBITS; k++) {
				char a[32], b[32];
				fmt_psnr(a, sizeof a, rows[k].psnr_ti);
				fmt_psnr(b, sizeof b, rows[k].psnr_sh);
				len += (size_t)snprintf(
				    t + len, cap - len,
				    "| %s | %d | %s | %llu | %+.1f%% | %s | %llu | chip |\n",
				    v < 0 ? "embedded (default)" : names[v], prec_bits[k], a,
				    (unsigned long long)rows[k].diff_ti,
				    100.0 * (rows[k].steps - 1.0), b,
				    (unsigned long long)rows[k].diff_sh);
				/* a capped PSNR (99 dB) keeps identical frames in the mean */
				sum_ti[k] += isinf(rows[k].psnr_ti) ? 99.0 : rows[k].psnr_ti;
				sum_sh[k] += isinf(rows[k].psnr_sh) ? 99.0 : rows[k].psnr_sh;
			}
			(*nsum)++;
		}
		world_free(&w);
	}
	*nv_out = nv;
	return len;
}

static size_t prec_section(char *t, size_t cap, int quick, const char *views, const char *png)
{
	size_t len = 0;
	int res = quick ? 64 : 256, sres = quick ? 32 : 128;
	time_t now = time(NULL);
	char date[64];
	strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", gmtime(&now));
	len += (size_t)snprintf(
	    t + len, cap - len,
	    "Generated by `make stress` (kernel-ref/stress_main.c) on %s, %s run. Formats: 8 "
	    "exponent bits, the given mantissa bits, round to nearest even; kernel-ref's "
	    "emulation (kernel-ref/fpfmt.h).\n\n"
	    "**Leaks** (traversal + intersection reduced): closed spheres of radius 1e-4, 1, 1e4, "
	    "1e6 at the origin and 100 at 1e5, seen from inside and outside at %dx%d "
	    "(stress_sphere_fp). *mismatch*: packet path against single-ray path at the same "
	    "format.\n\n"
	    "| mantissa bits | rays | leaked | mismatch | not judged | ms |\n"
	    "|---:|---:|---:|---:|---:|---:|\n",
	    date, quick ? "quick" : "full", sres, sres);
	uint64_t leaks[NBITS];
	len += prec_leaks(t + len, cap - len, sres, leaks);
	len += (size_t)snprintf(
	    t + len, cap - len,
	    "\n**Image error** against float at %dx%d (depth 3, shadows), per view: PSNR in dB "
	    "and differing pixels of the 8-bit frame, with traversal + intersection reduced, "
	    "and with shading alone reduced; *kd steps* is traversal steps relative to float "
	    "(of all rays, secondary ones included: the conservative widening makes segments "
	    "longer, while changed hits can change which secondary rays are made, so it can also "
	    "fall). *fps* is the chip's: it comes "
	    "from the chip model once `chip.fp` is wired into it (saarsim), not from "
	    "kernel-ref.\n\n"
	    "| view | mantissa bits | trav+isect PSNR | differing px | kd steps | shading PSNR "
	    "| differing px | fps |\n"
	    "|---|---:|---:|---:|---:|---:|---:|---|\n",
	    res, res);
	double sum_ti[NBITS] = {0}, sum_sh[NBITS] = {0};
	int nsum = 0, nv;
	len += prec_views(t + len, cap - len, res, views, sum_ti, sum_sh, &nsum, &nv);
	if (nv == 0)
		len += (size_t)snprintf(t + len, cap - len,
		                        "\nShared views skipped: %s not found (set SAAR_SCENES or "
		                        "pass --views); the embedded scene only.\n",
		                        views ? views : "views file");
	if (nsum) {
		double mt[NBITS], ms[NBITS];
		for (int k = 0; k < NBITS; k++) {
			mt[k] = sum_ti[k] / nsum;
			ms[k] = sum_sh[k] / nsum;
		}
		if (png) {
			prec_plot(png, mt, ms, leaks);
			len += (size_t)snprintf(
			    t + len, cap - len,
			    "\n![mantissa bits against PSNR and leaks](precision.png)\n");
		}
	}
	return len;
}

/* Replaces the text between the markers in doc (or appends them); returns
 * a new string. */
static char *splice(const char *doc, const char *begin, const char *end, const char *body)
{
	size_t n = (doc ? strlen(doc) : 0) + strlen(body) + strlen(begin) + strlen(end) + 8;
	char *o = malloc(n);
	const char *b = doc ? strstr(doc, begin) : NULL, *e = doc ? strstr(doc, end) : NULL;
	if (b && e && e > b)
		snprintf(o, n, "%.*s%s\n%s%s", (int)(b - doc), doc, begin, body, e);
	else
		snprintf(o, n, "%s\n%s\n%s%s\n", doc ? doc : "", begin, body, end);
	return o;
}

/* The document to splice into (NULL: none yet). */
static char *slurp(const char *path)
{
	char *b, err[256];
	size_t n;
	return in_read_all(path, 0, &b, &n, err, sizeof err) ? NULL : b;
}

/* The command line. */
typedef struct opts {
	const char *out, *views;
	int quick, precision, views_given;
	char vbuf[1024]; /* the default views file: SAAR_SCENES/views.yaml */
} opts;

/* Returns -1 to go on, else the exit status (0 after --help). */
static int parse_args(int argc, char **argv, opts *o)
{
	memset(o, 0, sizeof *o);
	o->precision = 1;
	const char *sc = getenv("SAAR_SCENES");
	snprintf(o->vbuf, sizeof o->vbuf, "%s/views.yaml", sc && *sc ? sc : "../shared/scenes");
	o->views = o->vbuf;
	for (int i = 1; i < argc; i++) {
		int value = !strcmp(argv[i], "--out") || !strcmp(argv[i], "--views");
		if (value && i + 1 >= argc) {
			fprintf(stderr, "saarsim-stress: %s needs a value\n", argv[i]);
			return 2;
		}
		if (!strcmp(argv[i], "--out"))
			o->out = argv[++i];
		else if (!strcmp(argv[i], "--views"))
			o->views = argv[++i], o->views_given = 1;
		else if (!strcmp(argv[i], "--quick"))
			o->quick = 1;
		else if (!strcmp(argv[i], "--no-precision"))
			o->precision = 0;
		else if (!strcmp(argv[i], "--help") || !strcmp(argv[i], "-h")) {
			printf(
			    "usage: saarsim-stress [--out FILE.md] [--quick] [--views FILE] "
			    "[--no-precision]\n"
			    "  prints the numerical stress tables; with --out also writes them "
			    "into FILE.md\n"
			    "  between its <!-- BEGIN/END stress --> and <!-- BEGIN/END precision "
			    "--> markers\n"
			    "  and the plot precision.png beside it (make stress: --out "
			    "docs/NUMERICS.md)\n");
			return 0;
		} else {
			fprintf(stderr,
			        "saarsim-stress: %s: unknown option (usage: saarsim-stress [--out "
			        "FILE] [--quick] [--views FILE] [--no-precision])\n",
			        argv[i]);
			return 2;
		}
	}
	/* the views feed the precision table only: ignored without a word */
	if (o->views_given && !o->precision) {
		fprintf(stderr, "saarsim-stress: --views: for the precision table, not with "
		                "--no-precision\n");
		return 2;
	}
	return -1;
}

/* The inputs checked before the long run: the document can be written, and
 * a views file given, or present where it is looked for, loads whole
 * (every view): a bad one is bad input, not a document that quietly
 * leaves views out. Only a views file absent from the default place skips
 * the shared views. 0, or -1 after the message. */
static int check_inputs(const opts *o)
{
	diag od;
	if (o->out && af_reserve(o->out, "", &od)) {
		fprintf(stderr, "saarsim-stress: %s\n", od.msg);
		return -1;
	}
	if (o->precision && (o->views_given || access(o->views, F_OK) == 0)) {
		char names[16][VIEW_NAME_MAX];
		diag d;
		int nv = view_list(o->views, names, 16, &d);
		for (int v = 0; nv > 0 && v < nv; v++) {
			view vw;
			if (view_load(&vw, o->views, names[v], &d))
				nv = -1;
		}
		if (nv < 0) {
			fprintf(stderr, "saarsim-stress: %s\n", d.msg);
			return -1;
		}
	}
	return 0;
}

/* Runs every stress case into r (at most MAXR); returns how many. */
static int run_cases(stress_result *r, int quick)
{
	int res = quick ? 64 : 256;
	int n = 0;
	const double scales[] = {1e-4, 1e-2, 1, 1e2, 1e4, 1e6};
	for (size_t k = 0; k < sizeof scales / sizeof *scales; k++)
		r[n++] = stress_sphere(scales[k], 0, res);
	const double far_scales[] = {1, 1e2, 1e4};
	for (size_t k = 0; k < sizeof far_scales / sizeof *far_scales; k++)
		r[n++] = stress_sphere(far_scales[k], 1e5, res);
	for (size_t k = 0; k < sizeof scales / sizeof *scales; k++)
		r[n++] = stress_spd_tetra(scales[k], 0, res);
	for (size_t k = 0; k < sizeof far_scales / sizeof *far_scales; k++)
		r[n++] = stress_spd_tetra(far_scales[k], 1e5, res);
	for (size_t k = 0; k < sizeof scales / sizeof *scales; k++)
		r[n++] = stress_acne(scales[k], 0, res);
	for (size_t k = 0; k < sizeof far_scales / sizeof *far_scales; k++)
		r[n++] = stress_acne(far_scales[k], 1e5, res);
	r[n++] = stress_vertices_edges(quick ? 16 : 64);
	r[n++] = stress_flat_axis_parallel(quick ? 16 : 64);
	r[n++] = stress_degenerate(quick ? 64 : 256);
	r[n++] = stress_random(quick ? 200000 : 5000000, 7);
	return n;
}

/* The stress table of the n results into t; the total of the must-be-zero
 * columns into *bad. Returns its length. */
static size_t stress_table(char *t, size_t cap, const stress_result *r, int n, int quick,
                           uint64_t *bad)
{
	int res = quick ? 64 : 256;
	size_t len = 0;
	time_t now = time(NULL);
	char date[64];
	strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", gmtime(&now));
	len += (size_t)snprintf(
	    t + len, cap - len,
	    "Generated by `make stress` (kernel-ref/stress_main.c) on %s, %s run "
	    "(%dx%d views).\n\n"
	    "| case | rays | leaked | acne | disagree | mismatch | not judged / ties | ms |\n"
	    "|---|---:|---:|---:|---:|---:|---:|---:|\n",
	    date, quick ? "quick" : "full", res, res);
	*bad = 0;
	for (int i = 0; i < n; i++) {
		/* a count the case does not measure shows as "-", never as 0 */
		char col[4][32];
		const uint64_t v[4] = {r[i].leaked, r[i].acne, r[i].disagree, r[i].mismatch};
		const unsigned bit[4] = {ST_LEAK, ST_ACNE, ST_DISAGREE, ST_MISMATCH};
		for (int k = 0; k < 4; k++) {
			if (r[i].measured & bit[k])
				snprintf(col[k], sizeof col[k], "%llu", (unsigned long long)v[k]);
			else
				snprintf(col[k], sizeof col[k], "-");
		}
		len += (size_t)snprintf(t + len, cap - len,
		                        "| %s | %llu | %s | %s | %s | %s | %llu | %.0f |\n",
		                        r[i].name, (unsigned long long)r[i].rays, col[0], col[1],
		                        col[2], col[3], (unsigned long long)r[i].ties, r[i].ms);
		*bad += r[i].leaked + r[i].acne + r[i].disagree + r[i].mismatch;
	}
	len += (size_t)snprintf(
	    t + len, cap - len,
	    "\nCrashes or hangs: none (the run completed). Total of the must-be-zero columns: "
	    "%llu.\n",
	    (unsigned long long)*bad);
	return len;
}

/* Splices the tables into the document out between their markers (ptable
 * NULL: the stress table only). 0, or -1 after the message. */
static int write_doc(const char *out, const char *table, const char *ptable)
{
	char *doc = slurp(out);
	char *d1 = splice(doc, "<!-- BEGIN stress -->", "<!-- END stress -->", table);
	free(doc);
	if (ptable) {
		char *d2 = splice(d1, "<!-- BEGIN precision -->", "<!-- END precision -->", ptable);
		free(d1);
		d1 = d2;
	}
	afile a;
	if (af_open(&a, out, "", 1)) {
		fprintf(stderr, "saarsim-stress: %s: cannot write: %s\n", out, strerror(errno));
		free(d1);
		return -1;
	}
	fputs(d1, a.f);
	free(d1);
	if (af_commit(&a)) {
		fprintf(stderr, "saarsim-stress: %s: write failed: %s\n", out, strerror(errno));
		return -1;
	}
	return 0;
}

int main(int argc, char **argv)
{
	static opts o;
	int rc = parse_args(argc, argv, &o);
	if (rc >= 0)
		return rc;
	if (check_inputs(&o))
		return 2;
	stress_result r[MAXR];
	int n = run_cases(r, o.quick);
	char table[32768];
	uint64_t bad;
	stress_table(table, sizeof table, r, n, o.quick, &bad);
	fputs(table, stdout);

	/* the reduced-precision table, with its plot next to the document */
	char *ptable = NULL;
	if (o.precision) {
		ptable = malloc(65536);
		char png[1100];
		const char *slash = o.out ? strrchr(o.out, '/') : NULL;
		if (o.out)
			snprintf(png, sizeof png, "%.*sprecision.png",
			         slash ? (int)(slash - o.out + 1) : 0, o.out);
		prec_section(ptable, 65536, o.quick, o.views, o.out ? png : NULL);
		fputs(ptable, stdout);
	}
	rc = o.out ? write_doc(o.out, table, ptable) : 0;
	free(ptable);
	if (rc)
		return 2;
	return bad ? 1 : 0;
}
