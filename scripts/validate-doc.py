#!/usr/bin/env python3
"""scripts/validate-doc.py: writes docs/VALIDATION.md and
docs/validation-published.png from the runs scripts/validate.sh made.

Called by scripts/validate.sh only (its settings come in VD_* environment
variables: VD_OUT the run folder, VD_DOC the document, VD_SIZE, VD_LARGE,
VD_LIST, VD_TV, VD_ASSUMED, VD_BALLS, VD_COMMIT, VD_DATE, VD_HOST,
VD_LIGHTS). Every figure of "ours" comes from a run's JSON report
(out/validate/DIR/points/ID.json); every published figure from seed 002 as
read in PUBLISHED below (the reading of each Table 5 number is written into
the document). Exit 1 with one line when a run it needs is missing.
"""
import json
import math
import os
import subprocess
import sys

E = os.environ
OUT = E["VD_OUT"]
DOC = E["VD_DOC"]
SIZE, LARGE, SMALL = E["VD_SIZE"], E["VD_LARGE"], E["VD_SMALL"]
VIEWS = E["VD_LIST"].split(",")
TV = E["VD_TV"]
ASSUMED = E.get("VD_ASSUMED") == "1"
BALLS = E["VD_BALLS"]
DOCDIR = os.path.dirname(DOC) or "."
PNG = "validation-published.png"


def fail(msg):
    print("validate-doc: " + msg, file=sys.stderr)
    sys.exit(1)


# ------------------------------------------------------------------ runs
def load(d):
    """The finished points of sweep folder d: list of (target, sets, report)."""
    path = os.path.join(OUT, d)
    if not os.path.isfile(os.path.join(path, "points.tsv")):
        return []
    pts = []
    with open(os.path.join(path, "points.tsv")) as f:
        hdr = f.readline().rstrip("\n").split("\t")
        for line in f:
            c = line.rstrip("\n").split("\t")
            js = os.path.join(path, "points", c[0] + ".json")
            if not os.path.isfile(js):
                continue
            with open(js) as g:
                r = json.load(g)
            target = c[2] if c[2] != "-" else c[1]
            pts.append((target, dict(zip(hdr[3:], c[3:])), r))
    return pts


def pick(pts, target, **kv):
    for t, s, r in pts:
        if t == target and all(s.get(k.replace("__", ".")) == str(v) for k, v in kv.items()):
            return r
    return None


def g(r, path, default=None):
    for k in path.split("."):
        if r is None:
            return default
        if isinstance(r, list):
            r = r[int(k)]
        else:
            r = r.get(k)
    return default if r is None else r


def fig(r):
    """The figures of one run, measured as Table 5 and §4.4 state them."""
    if r is None:
        return None
    u = {k: g(r, "units.%s.utilisation" % k, 0.0) for k in ("rgs", "trav", "list", "isect")}
    bu = max(u, key=u.get)
    peak = g(r, "memory.hierarchy.sdram.peak_gb_s", 0.0)
    fps = g(r, "table.fps", 0.0)
    mb = g(r, "table.sdram_mb_per_frame", 0.0)
    sb = g(r, "memory.hierarchy.sdram.bytes", 0)
    mbytes = g(r, "memory.hierarchy.vma.meta_bytes", None)
    return {
        "fps": fps,
        "fps_mean": g(r, "fps", 0.0),
        "mb": mb,
        "pci": g(r, "table.pci_mb_per_frame", 0.0),
        "pci1": g(r, "per_frame.0.pci_mb", 0.0),
        "util": u,
        "busy": u[bu],
        "busy_unit": bu,
        "bw": fps * mb * 2**20 / (peak * 1e9) if peak else None,
        "bus": g(r, "steady_state.sdram_utilisation", None),
        "meta": g(r, "steady_state.meta_share", None),
        "meta_run": g(r, "memory.hierarchy.sdram.meta_share", None),
        "meta_bytes": (mbytes / sb) if (mbytes is not None and sb) else None,
        "tri": g(r, "triangles", 0),
        "lights": g(r, "lights", 0),
        "img": g(r, "memory_image_bytes", 0),
        "ident": g(r, "check.identical_8bit", None),
        "ratio": g(r, "traversal.trav_isect_ratio", 0.0),
        "work": g(r, "traversal.kd_node_steps", 0) + g(r, "traversal.triangle_tests", 0),
        "steps": g(r, "traversal.kd_node_steps", 0),
        "wait": g(r, "threads.waiting_memory", 0.0),
        "idle": g(r, "threads.idle", 0.0),
        "rays": {k: g(r, "rays." + k, 0) for k in ("primary", "shadow", "reflection", "refraction", "total")},
        "packets": {k: g(r, "packets." + k, 0) for k in ("primary", "shadow", "reflection", "refraction", "total")},
        "depth": g(r, "config.shading.max_depth", None),
        "peak": peak,
        "kdhit": g(r, "memory.hierarchy.l1.kd.cache.hit_rate", None),
        "trihit": g(r, "memory.hierarchy.l1.tri.cache.hit_rate", None),
    }


class Set:
    """The runs of one pair of configs (calibrated, or assumed: prefix asm-)."""

    def __init__(self, pfx):
        self.std = load(pfx + "std")
        self.vma = load(pfx + "vma")
        self.rstd = load(pfx + "roles-std")
        self.rvma = load(pfx + "roles-vma")
        self.qstd = load(pfx + "quiet-std")
        self.qvma = load(pfx + "quiet-vma")
        if not self.std or not self.vma:
            fail("runs missing in %s/%sstd or %svma" % (OUT, pfx, pfx))

    def s(self, v, t=16):
        return fig(pick(self.std, v, chip__threads_per_rtp=t))

    def v(self, v):
        return fig(pick(self.vma, v, chip__threads_per_rtp=16))

    def role(self, name, vma=False):
        """The substitute of a Table 5 row, run with that row's lights."""
        sub = ROLE[name][0]
        if sub == "conference":
            return self.v(sub) if vma else self.s(sub)
        if sub == BALLS:
            return fig(pick(self.rvma if vma else self.rstd, sub, chip__threads_per_rtp=16))
        return fig(pick(self.qvma if vma else self.qstd, sub, chip__threads_per_rtp=16))


CAL = Set("")
ASM = Set("asm-") if ASSUMED else None
SETS = [("calibrated", CAL)] + ([("assumed", ASM)] if ASM else [])

# ------------------------------------------------------------------ published
# seed 002 Table 5 as read (the extracted text lost its decimal points):
# name, raw text, fps std, MB std, fps VMA, MB VMA, PCI MB; Table 4: triangles,
# lights (shadows), reflection depth, textures.
T5 = [
    ("Cruiser", "170 61 121 77 o014", 170, 6.1, 121, 7.7, 0.14, 3637101, 0, 0, "no"),
    ("BQD-1", "137 1.9 135 25 0.03", 137, 1.9, 135, 2.5, 0.03, 2133537, 0, 0, "no"),
    ("BQD-2", "59 26.6 42 341 091", 59, 26.6, 42, 34.1, 0.91, 2133537, 0, 0, "no"),
    ("Quake", "129 9.4 126 11.4°0.01", 129, 9.4, 126, 11.4, 0.01, 39424, 0, 0, "bilinear"),
    ("Conference", "77 8.5 68 10.8 0.09", 77, 8.5, 68, 10.8, 0.09, 282000, 2, 0, "no"),
    ("Office", "a4 21 43 26 002", 44, 2.1, 43, 2.6, 0.02, 33952, 3, 3, "no"),
]
PEAK_PUB = 16 * 133e6  # 128-bit SDRAM at 133 MHz: the "2 GB/s" of §4.7, bytes/s


def pub(name):
    for row in T5:
        if row[0] == name:
            return {
                "fps": row[2], "mb": row[3], "fps_v": row[4], "mb_v": row[5], "pci": row[6],
                "loss": 1 - row[4] / row[2], "ratio": row[5] / row[3],
                "bw": row[2] * row[3] * 1e6 / PEAK_PUB, "bw_v": row[4] * row[5] * 1e6 / PEAK_PUB,
                "tri": row[7], "lights": row[8], "depth": row[9], "tex": row[10],
            }
    raise KeyError(name)


PUB = {row[0]: pub(row[0]) for row in T5}
LOSS = [PUB[n]["loss"] for n in PUB]
RAT = [PUB[n]["ratio"] for n in PUB]
PCI = [PUB[n]["pci"] for n in PUB]
BW = [PUB[n][k] for n in PUB for k in ("bw", "bw_v")]

# Table 5 roles and our substitutes: (substitute, lights as run, why)
ROLE = {
    "Cruiser": ("dragon2", "none (--no-lights), as Table 4",
                "large model: the largest shared scene, 202k triangles against 3.6M"),
    "BQD-1": ("dragon2", "none (--no-lights), as Table 4",
              "large model: the same substitute as Cruiser (2.1M triangles)"),
    "BQD-2": ("dragon2", "none (--no-lights), as Table 4",
              "large model: the same substitute as Cruiser (2.1M triangles, as BQD-1)"),
    "Quake": ("sponza", "none (--no-lights), as Table 4",
              "small textured interior: an interior of 66k triangles (its textures are not "
              "in the shared scenes: untextured)"),
    "Conference": ("conference", "the view's two lights, as Table 4",
                   "the same room: the shared 69k-triangle variant, not the paper's 282k"),
    "Office": (BALLS, "its three SPD lights, reflections to depth 3, as Table 4",
               "reflective scene of Office's size (39k triangles, half-mirror spheres, 3 "
               "lights): no shared scene has a reflective material"),
}

TOL = 0.30  # a single published value ("about", "roughly") is read as +-30%
RTOL = 1.5  # a ratio between rows: inside when within a factor of 1.5


# ------------------------------------------------------------------ formatting
def pct(x, d=1):
    return "-" if x is None else ("%." + str(d) + "f%%") % (100 * x)


def f1(x):
    return "-" if x is None else "%.1f" % x


def f2(x):
    return "-" if x is None else "%.2f" % x


def verdict(x, lo, hi, unit):
    """inside/outside [lo, hi] with the margin; unit: '%' (x a fraction,
    margin in points), 'x' (a ratio), 'MB', 'pts' (x in points)."""
    if x is None:
        return "not measured"

    def m(d):
        if unit == "%":
            return "%.1f points" % (100 * d)
        if unit == "x":
            return "%.3f" % d
        if unit == "pts":
            return "%.1f points" % d
        return "%.2f %s" % (d, unit)

    if x < lo:
        return "**outside**, below by %s" % m(lo - x)
    if x > hi:
        return "**outside**, above by %s" % m(x - hi)
    return "inside (%s from the nearer end)" % m(min(x - lo, hi - x))


def rverdict(o, p):
    """a ratio between rows: ours o against published p"""
    if o is None or p is None or o <= 0 or p <= 0:
        return "not measured"
    k = o / p
    side = (o - 1) * (p - 1) >= 0 or abs(p - 1) < 0.02
    if 1 / RTOL <= k <= RTOL and side:
        return "inside (x%.2f of the published ratio)" % k
    return "**outside** (x%.2f of the published ratio%s)" % (k, "" if side else "; other side of 1")


def rng(lo, hi, unit):
    if unit == "%":
        return "%.1f%%-%.1f%%" % (100 * lo, 100 * hi)
    if unit == "pts":
        return "%+.1f to %+.1f points" % (lo, hi)
    if unit == "x":
        return "x%.2f-%.2f" % (lo, hi)
    return "%.2f-%.2f %s" % (lo, hi, unit)


# ------------------------------------------------------------------ figures per set
def measures(S):
    """Every figure the summary needs, from one set of runs."""
    M = {}
    c16, c32, cv = S.s(TV), S.s(TV, 32), S.v(TV)
    M["F1"] = c16["busy"] if c16 else None
    M["F2"] = 100 * (c32["busy"] - c16["busy"]) if c16 and c32 else None
    M["F3"] = 1 - cv["fps"] / c16["fps"] if c16 and cv and c16["fps"] else None
    M["H1"] = cv["mb"] / c16["mb"] if c16 and cv and c16["mb"] else None
    M["H2"] = cv["pci"] if cv else None
    M["H2cold"] = cv["pci1"] if cv else None
    M["H3"] = c16["bw"] if c16 else None
    M["H3v"] = cv["bw"] if cv else None
    M["H5"] = cv["meta"] if cv else None
    M["H5b"] = cv["meta_bytes"] if cv else None
    M["H5t"] = 1 - c16["mb"] / cv["mb"] if c16 and cv and cv["mb"] else None
    # over every view
    per = []
    for v in VIEWS:
        a, b, q = S.s(v), S.s(v, 32), S.v(v)
        if a:
            per.append((v, a, b, q))
    M["per"] = per
    M["util_all"] = [a["busy"] for _, a, _, _ in per]
    M["gain_all"] = [100 * (b["busy"] - a["busy"]) for _, a, b, _ in per if b]
    M["loss_all"] = [1 - q["fps"] / a["fps"] for _, a, _, q in per if q and a["fps"]]
    M["ratio_all"] = [q["mb"] / a["mb"] for _, a, _, q in per if q and a["mb"] > 0.005]
    M["pci_all"] = [q["pci"] for _, a, _, q in per if q]
    M["bw_all"] = [a["bw"] for _, a, _, _ in per] + [q["bw"] for _, _, _, q in per if q]
    M["meta_all"] = [q["meta"] for _, _, _, q in per if q and q["meta"] is not None]
    # the roles
    M["role"] = {n: (S.role(n), S.role(n, True)) for n in PUB}
    return M


MS = {name: measures(S) for name, S in SETS}
MC = MS["calibrated"]
MA = MS.get("assumed")


def mean(xs):
    return sum(xs) / len(xs) if xs else None


def spread(xs, f):
    return "-" if not xs else "%s (mean %s, %s to %s)" % (len(xs), f(mean(xs)), f(min(xs)), f(max(xs)))


# ------------------------------------------------------------------ summary rows
ROWS = []  # dict: id, set, figure, published, measure, ours{set: str}, verdict, plot
POINTS = []  # (group, label, published, ours)
NOPLOT = []  # rows with a plot point whose value cannot be plotted


def row(rid, cset, figure, published, measure, key, fmt, lo, hi, unit, plot=None):
    ours = {}
    for name, M in MS.items():
        x = M[key] if isinstance(key, str) else key(M)
        ours[name] = fmt(x)
    x = MC[key] if isinstance(key, str) else key(MC)
    v = verdict(x, lo, hi, unit)
    ROWS.append(dict(id=rid, set=cset, figure=figure, published=published, measure=measure,
                     ours=ours, verdict=v))
    if plot and x is not None and x > 0:
        POINTS.append((plot[0], rid, plot[1], x))
    elif plot:
        NOPLOT.append("%s (ours %s)" % (rid, ours["calibrated"]))


def rrow(rid, figure, published_s, p, key, plot=None):
    """a ratio between Table 5 rows (item 3)"""
    ours = {name: ("-" if key(M) is None else "%.2f" % key(M)) for name, M in MS.items()}
    x = key(MC)
    ROWS.append(dict(id=rid, set="-", figure=figure, published=published_s, measure="ratio of "
                     "our substitutes' rows", ours=ours, verdict=rverdict(x, p)))
    if plot and x is not None and x > 0:
        POINTS.append((plot, rid, p, x))


def role_f(M, n, vma, k):
    r = M["role"][n][1 if vma else 0]
    return None if r is None else r[k]


def role_loss(M, n):
    a, b = M["role"][n]
    return None if not a or not b or not a["fps"] else 1 - b["fps"] / a["fps"]


def role_ratio(M, n):
    a, b = M["role"][n]
    return None if not a or not b or a["mb"] <= 0 else b["mb"] / a["mb"]


def build_rows():
    lo = 1 - TOL
    hi = 1 + TOL
    row("F1", "fit", "busiest-unit utilisation, 16 threads per RTP, Conference (§4.4)",
        "60%-80%", "max over units of `units.*.utilisation`, %s, both frames" % TV, "F1",
        pct, 0.60, 0.80, "%", ("utilisation", 0.70))
    row("§4.4a", "-", "the same over every shared view", "60%-80%",
        "mean of the busiest-unit utilisations of %d views" % len(MC["util_all"]),
        lambda M: mean(M["util_all"]), pct, 0.60, 0.80, "%")
    row("F2", "fit", "16 -> 32 threads: utilisation gain, Conference (§4.4)",
        "about +10 points (read %+.0f to %+.0f)" % (10 * lo, 10 * hi),
        "busiest unit at 32 minus at 16 threads, %s" % TV, "F2",
        lambda x: "-" if x is None else "%+.1f points" % x, 10 * lo, 10 * hi, "pts")
    row("§4.4b", "-", "the same over every shared view", "about +10 points",
        "mean gain over %d views" % len(MC["gain_all"]), lambda M: mean(M["gain_all"]),
        lambda x: "-" if x is None else "%+.1f points" % x, 10 * lo, 10 * hi, "pts")
    p3 = PUB["Conference"]["loss"]
    row("F3", "fit", "Conference fps, standard -> VMA (Table 5): 77 -> 68 fps",
        "-%.1f%% (read %.1f%%-%.1f%%)" % (100 * p3, 100 * p3 * lo, 100 * p3 * hi),
        "1 - fps(VMA)/fps(std), steady state, %s" % TV, "F3", pct, p3 * lo, p3 * hi, "%",
        ("VMA fps loss", p3))
    row("T5-loss", "-", "VMA fps loss over Table 5's scenes", rng(min(LOSS), max(LOSS), "%"),
        "the same, mean over every shared view", lambda M: mean(M["loss_all"]), pct,
        min(LOSS), max(LOSS), "%")
    row("§4.2", "-", "VMA overhead, text (§4.2): \"between 1% and 10%\"", "1%-10%",
        "the same, mean over every shared view", lambda M: mean(M["loss_all"]), pct, 0.01, 0.10,
        "%")
    row("H1", "held out", "VMA SDRAM traffic ratio, Conference 8.5 -> 10.8 MB (Table 5)",
        "x%.2f (Table 5 range %s)" % (PUB["Conference"]["ratio"], rng(min(RAT), max(RAT), "x")),
        "MB/frame VMA / MB/frame std, steady state, %s" % TV, "H1",
        lambda x: "-" if x is None else "x%.3f" % x, min(RAT), max(RAT), "x",
        ("traffic ratio", PUB["Conference"]["ratio"]))
    row("H1all", "held out", "the same over every shared view", rng(min(RAT), max(RAT), "x"),
        "mean over the views with SDRAM traffic", lambda M: mean(M["ratio_all"]),
        lambda x: "-" if x is None else "x%.3f" % x, min(RAT), max(RAT), "x")
    row("H2", "held out", "PCI MB/frame with the VMA, Conference (Table 5: 0.09)",
        "0.01-0.91 MB (Table 5 range)", "`table.pci_mb_per_frame`, steady state, %s" % TV, "H2",
        lambda x: "-" if x is None else "%.3f MB" % x, 0.01, 0.91, "MB",
        ("PCI MB/frame", PUB["Conference"]["pci"]))
    row("H2cold", "held out", "the same, cold first frame (the scene loaded over PCI)",
        "0.01-0.91 MB", "`per_frame[0].pci_mb`, %s" % TV, "H2cold",
        lambda x: "-" if x is None else "%.3f MB" % x, 0.01, 0.91, "MB")
    row("H3", "held out", "SDRAM bandwidth in use, standard chip, Conference (Table 5: %.1f%%)"
        % (100 * PUB["Conference"]["bw"]), rng(min(BW), max(BW), "%") + " (Table 5 range)",
        "fps x MB/frame / peak, steady state, %s" % TV, "H3", pct, min(BW), max(BW), "%",
        ("bandwidth share", PUB["Conference"]["bw"]))
    row("H3v", "held out", "the same with the VMA (Table 5: %.1f%%)" % (100 * PUB["Conference"]["bw_v"]),
        rng(min(BW), max(BW), "%"), "the same, VMA run", "H3v", pct, min(BW), max(BW), "%",
        ("bandwidth share", PUB["Conference"]["bw_v"]))
    row("H3all", "held out", "the same over every shared view (std and VMA)",
        rng(min(BW), max(BW), "%"), "mean over the views", lambda M: mean(M["bw_all"]), pct,
        min(BW), max(BW), "%")
    row("H5", "held out", "meta-data share of SDRAM accesses (§4.2: \"roughly 20%\")",
        "about 20%% (read %.0f%%-%.0f%%)" % (20 * lo, 20 * hi),
        "`steady_state.meta_share` (accesses), VMA, %s" % TV, "H5", pct, 0.2 * lo, 0.2 * hi, "%",
        ("meta-data share", 0.20))
    row("H5b", "held out", "meta-data share of SDRAM bytes", "about 20%",
        "`vma.meta_bytes` / `sdram.bytes`, both frames, VMA, %s" % TV, "H5b", pct, 0.2 * lo,
        0.2 * hi, "%")
    row("H5t", "held out", "meta-data share of the VMA's SDRAM traffic, as Table 5 shows it "
        "(1 - 8.5/10.8 = %.1f%% for Conference)" % (100 * (1 - 8.5 / 10.8)),
        "%.1f%%-%.1f%% (Table 5 range)" % (100 * (1 - 1 / min(RAT)), 100 * (1 - 1 / max(RAT))),
        "1 - MB(std)/MB(VMA), steady state, %s" % TV, "H5t", pct, 1 - 1 / min(RAT),
        1 - 1 / max(RAT), "%")
    row("H5all", "held out", "meta-data share of accesses over every shared view", "about 20%",
        "mean over the VMA runs with SDRAM accesses", lambda M: mean(M["meta_all"]), pct, 0.2 * lo,
        0.2 * hi, "%")
    # per Table 5 row, with the substitutes (item 3): ratios between rows for
    # fps and MB/frame, the per-row VMA figures against Table 5's ranges
    C = PUB["Conference"]
    for n in PUB:
        P = PUB[n]
        sub = ROLE[n][0]
        if n != "Conference":
            # the row's ratio to Conference's, for fps and for SDRAM MB/frame
            for key, tag, what, fmt, label in (
                    ("fps", "fps", "%s fps / Conference fps, standard (Table 5; ours: %s / "
                     "conference)", "%d/%d = %.2f", "fps / Conference"),
                    ("mb", "MB", "%s SDRAM MB/frame / Conference's, standard (ours: %s / "
                     "conference)", "%.1f/%.1f = %.2f", "MB / Conference")):
                rrow("T5 %s %s" % (n, tag), what % (n, sub),
                     fmt % (P[key], C[key], P[key] / C[key]), P[key] / C[key],
                     lambda M, n=n, key=key:
                     (role_f(M, n, False, key) / role_f(M, "Conference", False, key))
                     if role_f(M, n, False, key) and role_f(M, "Conference", False, key)
                     else None,
                     label)
        if n == "Conference":
            row("T5 Conference fps", "-", "Conference fps, standard, digit for digit (Table 5)",
                "77 (read 54-100)", "`table.fps`, steady state, %s at %s" % (TV, SIZE),
                lambda M: role_f(M, n, False, "fps"), lambda x: "-" if x is None else "%.1f" % x,
                77 * lo, 77 * hi, "fps")
            row("T5 Conference MB", "-", "Conference SDRAM MB/frame, standard, digit for digit (Table 5)",
                "8.5 (read 6.0-11.1)", "`table.sdram_mb_per_frame`, steady state, %s" % TV,
                lambda M: role_f(M, n, False, "mb"), lambda x: "-" if x is None else "%.2f MB" % x,
                8.5 * lo, 8.5 * hi, "MB", ("MB/frame (Conference)", 8.5))
            continue  # its VMA loss, traffic ratio, PCI and bandwidth: rows F3, H1, H2, H3
        row("T5 %s loss" % n, "-", "%s: VMA fps loss %d -> %d (ours: %s)" % (n, P["fps"], P["fps_v"], sub),
            "%.1f%% (range %s)" % (100 * P["loss"], rng(min(LOSS), max(LOSS), "%")),
            "1 - fps(VMA)/fps(std) of the substitute", lambda M, n=n: role_loss(M, n), pct,
            min(LOSS), max(LOSS), "%", ("VMA fps loss", P["loss"]))
        row("T5 %s traffic" % n, "held out", "%s: SDRAM traffic ratio %.1f -> %.1f MB (ours: %s)"
            % (n, P["mb"], P["mb_v"], sub), "x%.2f (range %s)" % (P["ratio"], rng(min(RAT), max(RAT), "x")),
            "MB(VMA)/MB(std) of the substitute", lambda M, n=n: role_ratio(M, n),
            lambda x: "-" if x is None else "x%.3f" % x, min(RAT), max(RAT), "x",
            ("traffic ratio", P["ratio"]))
        row("T5 %s PCI" % n, "held out", "%s: PCI MB/frame (ours: %s)" % (n, sub),
            "%.2f (range 0.01-0.91)" % P["pci"], "steady state of the substitute's VMA run",
            lambda M, n=n: role_f(M, n, True, "pci"), lambda x: "-" if x is None else "%.3f MB" % x,
            0.01, 0.91, "MB", ("PCI MB/frame", P["pci"]))
        row("T5 %s bw" % n, "held out", "%s: SDRAM bandwidth in use, std / VMA (ours: %s)" % (n, sub),
            "%.1f%% / %.1f%% (range %s)" % (100 * P["bw"], 100 * P["bw_v"], rng(min(BW), max(BW), "%")),
            "fps x MB/frame / peak, standard run of the substitute",
            lambda M, n=n: role_f(M, n, False, "bw"), pct, min(BW), max(BW), "%",
            ("bandwidth share", P["bw"]))


build_rows()

# ------------------------------------------------------------------ cost law (H4)
COST = {}  # scene -> list of dict(l, depth, fig)
for scene, label in (("conference", "conference"), (BALLS, BALLS)):
    rows = []
    for l in range(4):
        pts = load("cost-%s-l%d" % ("conference" if scene == "conference" else "balls", l))
        for d in (0, 1, 3):
            r = fig(pick(pts, scene, shading__max_depth=d))
            if r:
                rows.append(dict(l=l, d=d, f=r))
    if rows:
        COST[label] = rows


def cost_table(label, rows):
    """r: the share of primary rays that spawned reflection rays, measured
    at max_depth 1 (where every reflection ray is a primary ray's), the same
    l; r_all: every reflection ray per primary ray (all bounces)."""
    r1 = {}
    for x in rows:
        if x["d"] == 1 and x["f"]["rays"]["primary"]:
            r1[x["l"]] = 100.0 * x["f"]["rays"]["reflection"] / x["f"]["rays"]["primary"]
    base = next((x["f"]["fps"] for x in rows if x["l"] == 0 and x["d"] == 0), None)
    w0 = next((x["f"]["work"] for x in rows if x["l"] == 0 and x["d"] == 0), None) or 1
    out = []
    prods = []
    rayp = []
    pktp = []
    workp = []
    for x in rows:
        f = x["f"]
        pr = f["rays"]["primary"] or 1
        pp = f["packets"]["primary"] or 1
        rayp.append(f["fps"] * f["rays"]["total"] / pr)
        pktp.append(f["fps"] * f["packets"]["total"] / pp)
        workp.append(f["fps"] * f["work"] / w0)
        rpk = f["rays"]["reflection"] / f["packets"]["reflection"] if f["packets"]["reflection"] else None
        rall = 100.0 * f["rays"]["reflection"] / pr
        r = 0.0 if x["d"] == 0 else r1.get(x["l"], rall)
        # depth 3: every bounce counts (the law's rays per primary ray)
        rl = r if x["d"] <= 1 else rall
        prod = f["fps"] * (1 + x["l"]) * (1 + rl / 100)
        prods.append(prod)
        pred = base / ((1 + x["l"]) * (1 + rl / 100)) if base else None
        out.append("| %d | %d | %.1f | %.1f | %.1f | %.2f | %.2f | %s | %.2f | %.1f | %.1f | %.1f | %.1f | %s | %s |" % (
            x["l"], x["d"], f["fps"], r, rall, f["rays"]["total"] / pr, f["packets"]["total"] / pp,
            "-" if rpk is None else "%.1f" % rpk, f["work"] / w0, prod, rayp[-1], pktp[-1], workp[-1],
            "-" if pred is None else "%.1f" % pred,
            "-" if pred is None else "%+.1f%%" % (100 * (f["fps"] / pred - 1))))
    return out, prods, rayp, pktp, workp


COSTOUT = {}
for label, rows in COST.items():
    COSTOUT[label] = cost_table(label, rows)
H4_SPREAD = {k: (max(p) / min(p) if p and min(p) > 0 else None) for k, (t, p, _, _, _) in COSTOUT.items()}
H4_TOL = 1.25
for k, s in H4_SPREAD.items():
    ROWS.append(dict(id="H4 " + k, set="held out",
                     figure="linear cost law (§4.7): fps x (1+l)(1+r/100) nearly constant, %s" % k,
                     published="nearly constant (read: max/min <= %.2f)" % H4_TOL,
                     measure="max/min of the product over l = 0..3, max_depth 0/1/3",
                     ours={"calibrated": "-" if s is None else "max/min %.2f" % s},
                     verdict=verdict(s, 1.0, H4_TOL, "x")))
for k, (t, prods, rayp, pktp, workp) in COSTOUT.items():
    sr = max(rayp) / min(rayp) if rayp and min(rayp) > 0 else None
    ROWS.append(dict(id="H4 rays " + k, set="-",
                     figure="the same law with the rays the chip traced: fps x rays per primary ray, %s" % k,
                     published="nearly constant (read: max/min <= %.2f)" % H4_TOL,
                     measure="max/min over the same runs; rays from `rays.*`",
                     ours={"calibrated": "-" if sr is None else "max/min %.2f" % sr},
                     verdict=verdict(sr, 1.0, H4_TOL, "x")))
# the board size: VMA runs with 4..64 MB on board
BRD = load("board")
BVIEWS = []
for t, st, r in BRD:
    if t not in BVIEWS:
        BVIEWS.append(t)


def board(v, mb):
    return fig(pick(BRD, v, memory__sdram__mb=mb))


for v in BVIEWS:
    b8, b64 = board(v, 8), board(v, 64)
    k = b8["fps"] / b64["fps"] if b8 and b64 and b64["fps"] else None
    ROWS.append(dict(id="§4.7 8MB " + v, set="-",
                     figure="\"for most scenes even as little as 8 MB are sufficient\" (§4.7), %s" % v,
                     published="sufficient (read: fps with 8 MB >= %.0f%% of fps with 64 MB)" % 90,
                     measure="VMA, fps with `memory.sdram.mb=8` / with 64, steady state",
                     ours={"calibrated": "-" if k is None else "%.1f%%" % (100 * k)},
                     verdict=verdict(k, 0.90, 1e9, "%")))
    x = b8["pci"] if b8 else None
    ROWS.append(dict(id="H2 8MB " + v, set="-",
                     figure="PCI MB/frame with the scene larger than the board (8 MB on board), %s" % v,
                     published="0.01-0.91 MB (Table 5 range)",
                     measure="VMA, `memory.sdram.mb=8`, steady state",
                     ours={"calibrated": "-" if x is None else "%.3f MB" % x},
                     verdict=verdict(x, 0.01, 0.91, "MB")))
    if x is not None and x > 0:
        POINTS.append(("PCI MB/frame", "H2 8MB " + v, PUB["Conference"]["pci"], x))
ROWS.append(dict(id="§4.7 tex", set="-", figure="texturing has hardly any impact (§4.7)",
                 published="hardly any", measure="-", ours={"calibrated": "-"},
                 verdict="not measured: the shared scenes carry no textures"))
ratios = [a["ratio"] for _, a, _, _ in MC["per"]]
ROWS.append(dict(id="§4.7 4:1", set="-", figure="traversal : intersection ops, design ratio (§4.7)",
                 published="4:1 (read %.1f:1-%.1f:1; BQD-2: 10:1)" % (4 * (1 - TOL), 4 * (1 + TOL)),
                 measure="`trav_isect_ratio` (kd steps / triangle tests), std, mean over every view",
                 ours={"calibrated": "%.2f:1 (views %.2f-%.2f)" % (mean(ratios), min(ratios), max(ratios))},
                 verdict=verdict(mean(ratios), 4 * (1 - TOL), 4 * (1 + TOL), "x")))

# ------------------------------------------------------------------ size check
def size_measures(pfx):
    szs, szv = load(pfx + "-std"), load(pfx + "-vma")
    a, b, q = (fig(pick(szs, TV, chip__threads_per_rtp=16)), fig(pick(szs, TV, chip__threads_per_rtp=32)),
               fig(pick(szv, TV, chip__threads_per_rtp=16)))
    if not (a and b and q):
        return None
    return {"F1": a["busy"], "F2": 100 * (b["busy"] - a["busy"]),
            "F3": 1 - q["fps"] / a["fps"] if a["fps"] else None,
            "H1": q["mb"] / a["mb"] if a["mb"] else None, "H5": q["meta"],
            "H3": a["bw"], "H2": q["pci"], "fps": a["fps"], "wait": a["wait"]}


SZ = {"small": size_measures("size-small"), "large": size_measures("size-large")}

# ------------------------------------------------------------------ plot
def plot():
    dat = os.path.join(OUT, "published.dat")
    groups = sorted(set(p[0] for p in POINTS))
    with open(dat, "w") as f:
        for gname in groups:
            f.write("# %s\n" % gname)
            for _, label, p, o in (x for x in POINTS if x[0] == gname):
                if p > 0 and o > 0:
                    f.write("%g %g \"%s\"\n" % (p, o, label))
            f.write("\n\n")
    png = os.path.join(DOCDIR, PNG)
    tmp = png + ".tmp.%d.png" % os.getpid()
    allv = [v for x in POINTS for v in (x[2], x[3]) if v > 0] or [0.01, 10]
    lo, hi = min(allv) / 2, max(allv) * 2
    plots = ", ".join("'%s' index %d using 1:2 with points pt %d ps 1.5 title '%s'" % (dat, i, 5 + 2 * (i % 5), gname)
                      for i, gname in enumerate(groups))
    script = """set terminal pngcairo size 900,800 font ',10'
set output '%s'
set logscale xy
set xrange [%g:%g]
set yrange [%g:%g]
set xlabel 'published (seed 002 Table 5, §4.2, §4.4)'
set ylabel 'simulated (saarsim, calibrated configs, %s)'
set title 'Published against simulated: one point per summary row (ratios, shares, MB)'
set key top left
set grid
plot x title 'ours = published' lc rgb 'gray', x*1.3 notitle dt 2 lc rgb 'gray', x/1.3 notitle dt 2 lc rgb 'gray', %s
""" % (tmp, lo, hi, lo, hi, SIZE, plots)
    subprocess.run(["gnuplot"], input=script.encode(), check=True)
    os.replace(tmp, png)


plot()


# ------------------------------------------------------------------ document
L = []


def p(s=""):
    L.append(s)


p("# Validation against the published SaarCOR results")
p()
p("<!-- Generated by scripts/validate.sh (`make validate`) and scripts/validate-doc.py; do not edit: "
  "every number below comes from the runs or from seed 002 as read in \"Table 5 as read\". -->")
p()
p("Generated %s on %s; saarsim %s." % (E["VD_DATE"], E["VD_HOST"], E["VD_COMMIT"]))
p()
p("**How measured.** Frame size %s (`VALIDATE_SIZE`; chosen so that `make validate` takes "
  "minutes on 2 cores; the section \"Frame size\" checks the fit verdicts and H1, H2, H3, H5 "
  "at %s), `--frames 2` everywhere: fps, MB/frame, hit rates and meta-data shares are "
  "the steady state (the second frame), as Table 5 reports a running system; unit "
  "utilisation is over both frames. Configs as they are in this branch: "
  "`configs/saarcor-std.yaml` and `configs/saarcor-vma.yaml` (column **calibrated**)%s. "
  "Runs: `scripts/sweep`, kept in `out/validate/`. Published figures: seed 002 (Wald et al., "
  "EG 2003 STAR) §4.2, §4.4, §4.7, Tables 4 and 5."
  % (SIZE, LARGE, "; the uncalibrated assumptions `configs/saarcor-std-assumed.yaml` and "
     "`configs/saarcor-vma-assumed.yaml` (column **assumed**)" if ASSUMED else
     " (no `configs/saarcor-std-assumed.yaml` in this branch: no **assumed** column)"))
p()
p("**Verdicts.** A published range is used as printed. A single published value stated as "
  "\"about\" or \"roughly\", or a single Table 5 row compared digit for digit, is read as "
  "+-%d%% of it. A ratio between two Table 5 rows (item 3: substitutes, where digits are not "
  "comparable) is inside when ours is within a factor of %.1f of the published ratio and on the "
  "same side of 1. Every verdict gives its margin: the distance outside the range, or inside "
  "from the nearer end." % (100 * TOL, RTOL))
p()

def f3_bands():
    """Where the calibrated F3 lies against both bands, from the runs."""
    x = MC["F3"]
    if x is None:
        return "F3 was not measured."
    pl = PUB["Conference"]["loss"]
    cal_lo, cal_hi = 1 - 68.5 / 76.5, 1 - 67.5 / 77.5
    def where(lo, hi):
        if x < lo:
            return "%.2f points below" % (100 * (lo - x))
        if x > hi:
            return "%.2f points above" % (100 * (x - hi))
        return "inside"
    return ("At the calibrated point F3 (%s) is %s this document's band and %s the calibration's."
            % (pct(x), where(pl * (1 - TOL), pl * (1 + TOL)),
               where(cal_lo, cal_hi)))


p("## Calibration: fit and held-out sets")
p()
p("Fixed before any fitting (issue 31; `scripts/calibrate.sh` fits, docs/CALIBRATION.md "
  "reports the fit). The held-out rows are judged only after fitting, with the calibrated "
  "configs as they stand; nothing in them was tuned to the held-out figures. The summary's "
  "set column marks every row fit, held out, or - (neither: reported, not fitted). "
  "Two bands for F3: the calibration fits to the band the rounding of 77 and 68 allows "
  "(10.46%-12.90%, docs/CALIBRATION.md), the narrowest reading of Table 5; the verdicts "
  "here give a single Table 5 value the +-30% every such row gets (8.2%-15.2%), for the "
  "model's error beside the reading's. " + f3_bands())
p()
p("| set | name | published figure |")
p("|---|---|---|")
p("| FIT | F1 | busiest-unit utilisation with 16 threads per RTP inside 60-80% (seed 002 §4.4) on Conference |")
p("| FIT | F2 | the 16 -> 32 threads gain of about +10 points of utilisation (§4.4) |")
p("| FIT | F3 | Conference fps standard vs VMA: 77 -> 68 fps (Table 5; a loss of 11.7%) |")
p("| HELD OUT | H1 | VMA SDRAM traffic ratio x1.21-1.32 (Table 5; Conference 8.5 -> 10.8 MB/frame, x1.27) |")
p("| HELD OUT | H2 | PCI MB/frame 0.01-0.91 (Table 5) |")
p("| HELD OUT | H3 | SDRAM bandwidth in use, fps x MB/frame as a share of the 2 GB/s peak, 4%-74% (Table 5) |")
p("| HELD OUT | H4 | the linear cost law of §4.7: fps x (1+l)(1+r/100) nearly constant for l lights and r% reflected primary rays |")
p("| HELD OUT | H5 | the meta-data share of SDRAM accesses (\"roughly 20%\") |")
p()

p("## Summary: every published figure")
p()
cols = [n for n, _ in SETS]
p("| row | set | published figure (source) | published | ours: how measured | %s | verdict (calibrated) |"
  % " | ".join("ours, " + c for c in reversed(cols)))
p("|---|---|---|---|---|%s---|" % ("---|" * len(cols)))
for r in ROWS:
    p("| %s | %s | %s | %s | %s | %s | %s%s |" % (
        r["id"], r["set"], r["figure"], r["published"], r["measure"],
        " | ".join(r["ours"].get(c, "-") for c in reversed(cols)),
        {"fit": "fit: ", "held out": "held out: ", "-": ""}[r["set"]], r["verdict"]))
p()
nin = sum(1 for r in ROWS if r["verdict"].startswith("inside"))
nout = sum(1 for r in ROWS if "outside" in r["verdict"])
p("%d rows: %d inside, %d outside, %d not measured. Fit rows outside: %s. Held-out rows outside: %s." % (
    len(ROWS), nin, nout, len(ROWS) - nin - nout,
    ", ".join(r["id"] for r in ROWS if r["set"] == "fit" and "outside" in r["verdict"]) or "none",
    ", ".join(r["id"] for r in ROWS if r["set"] == "held out" and "outside" in r["verdict"]) or "none"))
p()
p("![published against simulated](%s)" % PNG)
p()
p("Published against simulated (`%s`): one point per summary row with a positive published "
  "value and a measured one (calibrated configs), both axes logarithmic; the grey line is "
  "ours = published, the dashed lines +-30%%. Ratios between rows are plotted as ratios. "
  "Not plotted (a value of 0 or below has no place on a log axis): %s." % (
      PNG, ", ".join(NOPLOT) or "none"))
p()

p("## Table 5 as read")
p()
CR = PUB["Cruiser"]
BW20 = [PUB[n][k] * 2**20 / 1e6 for n in PUB for k in ("bw", "bw_v")]
p("The extracted text of seed 002 lost Table 5's decimal points. Each row as extracted, and "
  "as read here: an MB figure without a point has one decimal (\"61\" MB/frame at %d fps "
  "would be %.1f GB/s, %.1f times the 2 GB/s peak), PCI figures are below one MB (\"o014\" = "
  "0.14, \"091\" = 0.91, \"002\" = 0.02), fps are integers as printed (\"a4\" = 44). The "
  "one doubtful reading is Cruiser's \"170\" fps (17.0 would also be possible): the loss, "
  "1 - %d/%d = %.1f%%, is the same either way (1 - 12.1/17.0); the bandwidth share would be "
  "%.1f%% instead of %.1f%%, inside the range either way. Bandwidth in use is fps x MB/frame / "
  "(16 B x 133 MHz = %.3f GB/s) with MB = 10^6 bytes, which gives the 4%%-74%% of issue 31 "
  "(with MB = 2^20 it would be %.1f%%-%.1f%%). Table 4 gives triangles, lights (shadows) and "
  "reflection depth." % (
      CR["fps"], CR["fps"] * 61 / 1000, CR["fps"] * 61e6 / PEAK_PUB, CR["fps_v"], CR["fps"],
      100 * CR["loss"], 100 * CR["bw"] / 10, 100 * CR["bw"], PEAK_PUB / 1e9,
      100 * min(BW20), 100 * max(BW20)))
p()
p("| scene | extracted text | fps std | MB std | fps VMA | MB VMA | PCI MB | VMA fps loss | traffic ratio | bandwidth std / VMA | 1 - MB std / MB VMA | triangles | lights | depth | textures |")
p("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for row_ in T5:
    P = PUB[row_[0]]
    p("| %s | `%s` | %d | %.1f | %d | %.1f | %.2f | %.1f%% | x%.3f | %.1f%% / %.1f%% | %.1f%% | %s | %d | %d | %s |" % (
        row_[0], row_[1], P["fps"], P["mb"], P["fps_v"], P["mb_v"], P["pci"], 100 * P["loss"],
        P["ratio"], 100 * P["bw"], 100 * P["bw_v"], 100 * (1 - P["mb"] / P["mb_v"]),
        format(P["tri"], ","), P["lights"], P["depth"], P["tex"]))
p()
p("Ranges: VMA fps loss %s, traffic ratio %s, PCI %.2f-%.2f MB/frame, bandwidth in use %s "
  "(both chips), meta-data share of the VMA's traffic %.1f%%-%.1f%%." % (
      rng(min(LOSS), max(LOSS), "%"), rng(min(RAT), max(RAT), "x"), min(PCI), max(PCI),
      rng(min(BW), max(BW), "%"), 100 * (1 - 1 / min(RAT)), 100 * (1 - 1 / max(RAT))))
p()

# ---- per view
p("## 1. Unit utilisation and threads (F1, F2)")
p()
p("Published (§4.4): \"Sixteen threads results in 60%-80% utilization while 32 threads "
  "increase the utilization by another 10 percent\" (read as about +10 points). Ours: the "
  "share of issue slots used (`units.*.utilisation`) of each unit; the busiest unit limits the "
  "frame rate. Standard chip (calibrated), every view.")
p()
p("| view | triangles | image identical to kernel-ref | rgs | trav | list | isect | busiest, 16 | busiest, 32 | gain (points) | fps 16 | fps 32 |")
p("|---|---|---|---|---|---|---|---|---|---|---|---|")
for v, a, b, q in MC["per"]:
    p("| %s | %d | %s | %s | %s | %s | %s | %s (%s) | %s | %s | %.1f | %s |" % (
        v, a["tri"], {True: "yes", False: "**no**"}.get(a["ident"], "not checked"),
        pct(a["util"]["rgs"]), pct(a["util"]["trav"]), pct(a["util"]["list"]), pct(a["util"]["isect"]),
        pct(a["busy"]), a["busy_unit"], pct(b["busy"]) if b else "-",
        "%+.1f" % (100 * (b["busy"] - a["busy"])) if b else "-", a["fps"], f1(b["fps"]) if b else "-"))
p()
p("Busiest-unit utilisation at 16 threads over the views: %s; gain 16 -> 32: %s." % (
    spread(MC["util_all"], pct), spread(MC["gain_all"], lambda x: "%+.1f points" % x)))
p()
p("Utilisation and frame rate against threads per pipeline, view %s (standard chip; plot: "
  "`scripts/sweep --plot`):" % TV)
p()
p("![utilisation against threads per pipeline, %s](validation-threads.png)" % TV)
p()
p("| threads per RTP | fps | rgs | trav | list | isect | threads waiting for memory | threads idle |")
p("|---|---|---|---|---|---|---|---|")
thr = load("threads")
for t in (1, 2, 4, 8, 16, 32, 64):
    x = fig(pick(thr, TV, chip__threads_per_rtp=t))
    if x:
        p("| %d | %.1f | %s | %s | %s | %s | %s | %s |" % (t, x["fps"], pct(x["util"]["rgs"]),
          pct(x["util"]["trav"]), pct(x["util"]["list"]), pct(x["util"]["isect"]), pct(x["wait"]), pct(x["idle"])))
p()

p("## 2. The VMA per view: fps loss (F3), traffic ratio (H1), PCI (H2), bandwidth (H3), meta-data (H5)")
p()
p("Standard against VMA chip, 16 threads, 64 MB on board in both, steady state. Bandwidth in "
  "use: fps x SDRAM bytes per frame / the SDRAM peak of the report (`sdram.peak_gb_s`, "
  "%.3f GB/s), the way Table 5's figures give it; \"bus busy\" is the report's own SDRAM "
  "utilisation (data-bus time), beside it. Meta-data: share of SDRAM accesses (steady state), "
  "share of SDRAM bytes (both frames: the report counts meta-data bytes for the whole run "
  "only), and the share of the VMA's traffic Table 5 would show, 1 - MB(std)/MB(VMA)."
  % (MC["per"][0][1]["peak"] if MC["per"] else 0))
p()
p("| view | fps std | fps VMA | loss | MB std | MB VMA | ratio | PCI MB steady | PCI MB cold frame | memory image MB | bandwidth std / VMA | bus busy std | meta: accesses | meta: bytes | 1 - MB std/MB VMA |")
p("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for v, a, b, q in MC["per"]:
    if not q:
        continue
    p("| %s | %.1f | %.1f | %s | %.2f | %.2f | %s | %.3f | %.2f | %.1f | %s / %s | %s | %s | %s | %s |" % (
        v, a["fps"], q["fps"], pct(1 - q["fps"] / a["fps"]) if a["fps"] else "-", a["mb"], q["mb"],
        "x%.3f" % (q["mb"] / a["mb"]) if a["mb"] > 0.005 else "-", q["pci"], q["pci1"], q["img"] / 2**20,
        pct(a["bw"]), pct(q["bw"]), pct(a["bus"]), pct(q["meta"]), pct(q["meta_bytes"]),
        pct(1 - a["mb"] / q["mb"]) if q["mb"] > 0.005 else "-"))
p()
p("Over the views: VMA fps loss %s (Table 5: %s); traffic ratio %s (Table 5: %s); PCI in the "
  "steady state %s MB (Table 5: 0.01-0.91); bandwidth in use %s (Table 5: %s); meta-data "
  "share of accesses %s (\"roughly 20%%\")." % (
      spread(MC["loss_all"], pct), rng(min(LOSS), max(LOSS), "%"),
      spread(MC["ratio_all"], lambda x: "x%.3f" % x), rng(min(RAT), max(RAT), "x"),
      spread(MC["pci_all"], lambda x: "%.3f" % x), spread(MC["bw_all"], pct), rng(min(BW), max(BW), "%"),
      spread(MC["meta_all"], pct)))
p()
p("Our scenes' memory images (at most %.0f MB) fit in the 64 MB on board, and our view does "
  "not move: once the first frame has loaded the scene over PCI, nothing crosses PCI, so the "
  "steady-state PCI figure is 0 where Table 5's is 0.01-0.91 MB/frame (its scenes take up to "
  "500 MB, §4.7, and its frames may come from moving views; the seed does not say). The cold "
  "first frame's PCI traffic is given beside it." % (max(q["img"] for _, _, _, q in MC["per"] if q) / 2**20))
p()

# ---- roles (item 3)
if BVIEWS:
    p("**The board size.** §4.7: \"For most scenes even as little as 8 MB are sufficient\" "
      "(Table 5 used 64 MB). With a board smaller than the scene's memory image the steady "
      "state fetches over PCI, as Table 5's scenes of up to 500 MB must have; VMA config, %s, "
      "`memory.sdram.mb` 4, 8, 16, 64 (the on-board L2 and its tags share it):" % SIZE)
    p()
    p("| view | memory image MB | board MB | fps | fps vs 64 MB board | SDRAM MB/frame | PCI MB/frame (steady) | meta-data share of accesses |")
    p("|---|---|---|---|---|---|---|---|")
    for v in BVIEWS:
        b64 = board(v, 64)
        for mb in (4, 8, 16, 64):
            x = board(v, mb)
            if x:
                p("| %s | %.1f | %d | %.1f | %s | %.2f | %.3f | %s |" % (
                    v, x["img"] / 2**20, mb, x["fps"],
                    pct(x["fps"] / b64["fps"]) if b64 and b64["fps"] else "-", x["mb"], x["pci"],
                    pct(x["meta"])))
    p()

p("## 3. Table 5's scenes and our substitutes")
p()
p("Table 5's Cruiser, BQD-1/2, Quake and Office are not among the shared scenes. Each row's "
  "role is played by a shared (or procedural) scene run with the row's lights and reflection "
  "depth from Table 4; digits of different scenes are not comparable, so rows are compared by "
  "ratios to the Conference row, and the VMA figures (themselves ratios) against Table 5's "
  "ranges.")
p()
p("| Table 5 row | role | triangles, lights, depth (Table 4) | our substitute | triangles | lights as run | why |")
p("|---|---|---|---|---|---|---|")
ROLE_NAME = {"Cruiser": "large model", "BQD-1": "large model", "BQD-2": "large model",
             "Quake": "small textured interior", "Conference": "interior (the same room)",
             "Office": "reflective office"}
for n in PUB:
    P = PUB[n]
    a = MC["role"][n][0]
    p("| %s | %s | %s, %d, %d | %s | %s | %s | %s |" % (
        n, ROLE_NAME[n], format(P["tri"], ","), P["lights"], P["depth"], ROLE[n][0],
        format(a["tri"], ",") if a else "not run", ROLE[n][1], ROLE[n][2]))
p()
p("| Table 5 row | substitute | fps std | fps / Conference: published | ours | MB std | MB / Conference: published | ours | VMA loss: published | ours | traffic ratio: published | ours | PCI MB: published | ours | bandwidth std: published | ours |")
p("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
cs = MC["role"]["Conference"][0]
for n in PUB:
    P = PUB[n]
    a, b = MC["role"][n]
    if not a:
        continue
    p("| %s | %s | %.1f | %.2f | %s | %.2f | %.2f | %s | %.1f%% | %s | x%.2f | %s | %.2f | %s | %.1f%% | %s |" % (
        n, ROLE[n][0], a["fps"], P["fps"] / PUB["Conference"]["fps"],
        "%.2f" % (a["fps"] / cs["fps"]) if cs and cs["fps"] else "-", a["mb"],
        P["mb"] / PUB["Conference"]["mb"], "%.2f" % (a["mb"] / cs["mb"]) if cs and cs["mb"] else "-",
        100 * P["loss"], pct(role_loss(MC, n)), P["ratio"],
        "-" if role_ratio(MC, n) is None else "x%.3f" % role_ratio(MC, n), P["pci"],
        "%.3f" % b["pci"] if b else "-", 100 * P["bw"], pct(a["bw"])))
p()
p("In Table 5 the large unlit models lose most with the VMA (BQD-2 %.1f%%, Cruiser %.1f%%; "
  "but BQD-1, of the same triangle count in Table 4, %.1f%%), the small unlit interior (Quake) "
  "%.1f%% and the reflective Office %.1f%%. Ours: %s. The ratio columns show whether our "
  "substitutes keep Table 5's order; the summary's \"T5\" rows give each one a verdict." % (
      100 * PUB["BQD-2"]["loss"], 100 * PUB["Cruiser"]["loss"], 100 * PUB["BQD-1"]["loss"],
      100 * PUB["Quake"]["loss"], 100 * PUB["Office"]["loss"],
      ", ".join("%s (%s) %s" % (n, ROLE[n][0], pct(role_loss(MC, n)))
                for n in ("Cruiser", "Quake", "Conference", "Office"))))
p()

# ---- cost law
p("## 4. The linear cost law (H4)")
p()
p("Published (§4.7): for a fixed scene the frame rate falls linearly with the rays per frame, "
  "almost independent of their type: with l lights and r%% of all primary rays reflected, "
  "fps = p / ((1 + l)(1 + r/100)), p the frame rate with no light and no reflection. So "
  "fps x (1+l)(1+r/100) should stay nearly constant. Ours: conference (no reflective material "
  "in the shared scenes: r = 0 at every depth; only the lights vary) and `%s` (the Office "
  "substitute: half-mirror spheres), standard chip (calibrated), 16 threads, lights 0..3 "
  "(`--no-lights`, `--light`: %s), `shading.max_depth` 0 (reflections off), 1 and 3. r is "
  "measured from the report's ray counts: at max_depth 1 every reflection ray is a primary "
  "ray's, so r = reflection rays / primary rays of the depth-1 run (the same l); at depth 3 "
  "the law's product uses every reflection ray per primary ray (r all, column 5), the rays "
  "the deeper bounces add. \"predicted\" is p / ((1+l)(1+r/100)) with p the l = 0, depth 0 run."
  % (BALLS, E["VD_LIGHTS"]))
p()
def spr(xs):
    m = mean(xs)
    sd = math.sqrt(sum((x - m) ** 2 for x in xs) / len(xs)) if xs else 0
    return "mean %.1f, %.1f to %.1f, max/min %s, coefficient of variation %.1f%%" % (
        m, min(xs), max(xs), "%.2f" % (max(xs) / min(xs)) if min(xs) > 0 else "-",
        100 * sd / m if m else 0)


for label, (t, prods, rayp, pktp, workp) in COSTOUT.items():
    p("**%s**" % label)
    p()
    p("| lights l | max_depth | fps | r (% primary rays reflected) | r all (reflection rays per 100 primary) | rays per primary ray | packets per primary packet | active rays per reflection packet | work (kd steps + triangle tests) vs l = 0, depth 0 | **fps x (1+l)(1+r/100)** | fps x rays per primary ray | fps x packets per primary packet | fps x work | predicted fps | measured vs predicted |")
    p("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for line in t:
        p(line)
    p()
    p("Over %d runs: the law's product fps x (1+l)(1+r/100): %s. With the rays the chip traced, "
      "fps x rays per primary ray: %s. With packets, fps x packets per primary packet: %s. With the units' work, fps x (kd steps + triangle tests) "
      "relative to the unlit, unreflected run: %s." % (len(prods), spr(prods), spr(rayp), spr(pktp), spr(workp)))
    p()
def cost_at(label, l, d):
    for x in COST.get(label, []):
        if x["l"] == l and x["d"] == d:
            return x["f"]
    return None


b0, b1 = cost_at(BALLS, 0, 0), cost_at(BALLS, 0, 1)
if b0 and b1 and b0["work"] and b1["fps"]:
    rp = b1["packets"]["reflection"] or 1
    p("Why the law fails with reflections on `%s`: with no light, reflecting %.1f%% of the primary "
      "rays (max_depth 1) adds %.0f%% rays and %.0f%% packets, but multiplies the units' work "
      "(kd steps + triangle tests) by %.2f, the SDRAM traffic from %.2f to %.2f MB/frame, and "
      "divides the frame rate by %.2f. A reflection packet (%.1f active rays of 64 on average) "
      "starts on a sphere of the flake and takes %.0f kd steps, against %.0f for a primary "
      "packet: the law's \"almost constant cost per ray\" (§4.5) does not hold for these rays "
      "in our model: the work per packet and the SDRAM traffic it brings, not the ray count, set the frame "
      "rate." % (
          BALLS, 100.0 * b1["rays"]["reflection"] / b1["rays"]["primary"],
          100.0 * (b1["rays"]["total"] / b0["rays"]["total"] - 1),
          100.0 * (b1["packets"]["total"] / b0["packets"]["total"] - 1),
          b1["work"] / b0["work"], b0["mb"], b1["mb"], b0["fps"] / b1["fps"],
          b1["rays"]["reflection"] / rp, (b1["steps"] - b0["steps"]) / rp,
          b0["steps"] / (b0["packets"]["primary"] or 1)))
    p()
c0, c3 = cost_at("conference", 0, 0), cost_at("conference", 3, 0)
if c0 and c3:
    p("Lights on conference: 3 lights should cost 4x the unlit frame by the law; they make "
      "%.2f rays per primary ray (shadow rays only for lit-facing hits) and cost %.2fx in frame "
      "time." % (c3["rays"]["total"] / c3["rays"]["primary"], c0["fps"] / c3["fps"]))
    p()
p("Shadow rays are counted by the law as one per light per primary ray, but a light behind "
  "the surface or a miss makes none (`skipped.shadow_rays_light_behind`); the \"rays per "
  "primary ray\" column is what the chip actually traced, the law's (1+l)(1+r/100) what it "
  "assumes. A product that grows with l means shadow rays cost less than the law assumes "
  "(fewer of them, or cheaper: they stop at the first occluder).")
p()

# ---- size check
p("## 5. Frame size")
p()
if SZ["small"] and SZ["large"]:
    M = dict(MC)
    c16 = CAL.s(TV)
    M["fps"] = c16["fps"] if c16 else None
    M["wait"] = c16["wait"] if c16 else None
    p("Every figure above is at %s. The fit figures and H1, H2, H3, H5 on %s at half and twice "
      "that size (calibrated configs, the same runs otherwise):" % (SIZE, TV))
    p()
    p("| row | published | at %s | verdict | at %s (default) | verdict | at %s | verdict |" % (SMALL, SIZE, LARGE))
    p("|---|---|---|---|---|---|---|---|")
    pl = PUB["Conference"]["loss"]
    spec = [("F1", "60%-80%", pct, 0.6, 0.8, "%"),
            ("F2", "+%.0f to +%.0f points" % (10 * (1 - TOL), 10 * (1 + TOL)),
             lambda x: "%+.1f points" % x, 10 * (1 - TOL), 10 * (1 + TOL), "pts"),
            ("F3", rng(pl * (1 - TOL), pl * (1 + TOL), "%"), pct, pl * (1 - TOL), pl * (1 + TOL), "%"),
            ("H1", rng(min(RAT), max(RAT), "x"), lambda x: "x%.3f" % x, min(RAT), max(RAT), "x"),
            ("H2", "0.01-0.91 MB", lambda x: "%.3f MB" % x, 0.01, 0.91, "MB"),
            ("H3", rng(min(BW), max(BW), "%"), pct, min(BW), max(BW), "%"),
            ("H5", rng(0.2 * (1 - TOL), 0.2 * (1 + TOL), "%"), pct, 0.2 * (1 - TOL), 0.2 * (1 + TOL), "%")]
    changed = []
    for k, pubs, fmt, lo, hi, unit in spec:
        cells = []
        words = []
        for x in (SZ["small"][k], M[k], SZ["large"][k]):
            v = verdict(x, lo, hi, unit)
            cells += ["-" if x is None else fmt(x), v]
            words.append("below" if "below" in v else "above" if "above" in v else v.split()[0])
        if len(set(words)) > 1:
            changed.append(k)
        p("| %s | %s | %s |" % (k, pubs, " | ".join(cells)))
    p("| fps std, 16 threads | - | %.1f | | %s | | %.1f | |" % (
        SZ["small"]["fps"], "-" if M["fps"] is None else "%.1f" % M["fps"], SZ["large"]["fps"]))
    p("| threads waiting for memory, std, 16 threads | - | %s | | %s | | %s | |" % (
        pct(SZ["small"]["wait"]), pct(M["wait"]), pct(SZ["large"]["wait"])))
    p()
    if changed:
        p("The frame size changes the verdict (inside, below or above) of %s: the share of threads waiting for memory "
          "goes from %s at %s to %s at %s (more rays share each scene byte fetched), so the fit "
          "figures depend on the frame size, which seed 002 does not state. The fit and every "
          "verdict above hold for %s only." % (
              ", ".join(changed), pct(SZ["small"]["wait"]), SMALL, pct(SZ["large"]["wait"]), LARGE, SIZE))
    else:
        p("No verdict changes between %s, %s and %s." % (SMALL, SIZE, LARGE))
else:
    p("The size-check runs are missing.")
p()

# ---- item 5: the mechanism behind the thread trend
p("## 6. What sets the 16 -> 32 threads gain (item 5)")
p()
MECH_B = load("mech-bigl1")
MECH_F = load("mech-fixed")
mrows = [("hierarchy, as configured", CAL.s(TV, 16), CAL.s(TV, 32))]
mrows.append(("hierarchy, L1s 16x the published sizes",
              fig(pick(MECH_B, TV, chip__threads_per_rtp=16)),
              fig(pick(MECH_B, TV, chip__threads_per_rtp=32))))
lats = sorted({int(s["memory.latency"]) for _, s, _ in MECH_F if "memory.latency" in s})
for lat in lats:
    mrows.append(("fixed latency %d cycles (no caches, no SDRAM)" % lat,
                  fig(pick(MECH_F, TV, chip__threads_per_rtp=16, memory__latency=lat)),
                  fig(pick(MECH_F, TV, chip__threads_per_rtp=32, memory__latency=lat))))
mrows = [m for m in mrows if m[1] and m[2]]
if len(mrows) < 3:
    p("The runs of this experiment are missing.")
else:
    def hh(a, b, k):
        return "-" if a[k] is None or b[k] is None else "%s -> %s" % (pct(a[k]), pct(b[k]))
    a0_, b0_ = mrows[0][1], mrows[0][2]
    g0_ = 100 * (b0_["busy"] - a0_["busy"])
    if 0.6 <= a0_["busy"] <= 0.8 and 7 <= g0_ <= 13:
        p("The calibrated standard chip reproduces the published pair (60%%-80%% of the busiest "
          "unit with 16 threads per RTP, about +10 points with 32) at %s: %s and %+.1f points "
          "(F1, F2 above; the gain %.1f points inside its band), not at the other frame sizes "
          "(section 5). What sets the gain in our model, and why it is this sensitive:"
          % (SIZE, pct(a0_["busy"]), g0_, min(g0_ - 7, 13 - g0_)))
    else:
        p("The calibrated standard chip does not reproduce the published pair (60%%-80%% of the "
          "busiest unit with 16 threads per RTP, about +10 points with 32) at %s: %s and %+.1f "
          "points (F1, F2 above). What caps the gain in our model:" % (SIZE, pct(a0_["busy"]), g0_))
    p()
    p("The experiment: %s, standard chip as calibrated, 16 and 32 threads, with the memory as "
      "configured, with L1 caches 16 times their published sizes (so that adding threads no "
      "longer lowers their hit rates) and with a fixed memory latency (every access the same "
      "number of cycles: latency only, no caches, no SDRAM). \"predicted\" is the gain a pure "
      "latency allows, min(2u, 100%%) - u for a 16-thread utilisation u: the busiest unit's "
      "utilisation doubles with the threads until it saturates." % TV)
    p()
    p("| memory | busiest unit, 16 threads | 32 threads | gain (points) | predicted by 2u (points) "
      "| SDRAM MB/frame 16 -> 32 | kd L1 hits 16 -> 32 | tri L1 hits 16 -> 32 | threads waiting for memory 16 -> 32 |")
    p("|---|---|---|---|---|---|---|---|---|")
    for name, a, b in mrows:
        gain = 100 * (b["busy"] - a["busy"])
        pred = 100 * (min(2 * a["busy"], 1.0) - a["busy"])
        mb = "-" if name.startswith("fixed") else "%.2f -> %.2f" % (a["mb"], b["mb"])
        p("| %s | %s (%s) | %s | %+.1f | %+.1f | %s | %s | %s | %s |" % (
            name, pct(a["busy"]), a["busy_unit"], pct(b["busy"]), gain, pred, mb,
            hh(a, b, "kdhit"), hh(a, b, "trihit"), hh(a, b, "wait")))
    p()
    (n0, a0, b0), (n1, a1, b1) = mrows[0], mrows[1]
    fx = [(n, a, b) for n, a, b in mrows[2:]]
    g0 = 100 * (b0["busy"] - a0["busy"])
    g1 = 100 * (b1["busy"] - a1["busy"])
    inside = [n for n, a, b in mrows if 0.6 <= a["busy"] <= 0.8 and 7 <= 100 * (b["busy"] - a["busy"]) <= 13]
    def pr(a):
        return 100 * (min(2 * a["busy"], 1) - a["busy"])
    p("Read from the rows. Under a fixed latency the gain follows the 2u prediction (%s): a "
      "latency that threads overlap gives a sharp knee, so a 16-thread utilisation inside "
      "60%%-80%% would go with a gain of 20 to 40 points, not 10; the published pair describes a "
      "soft knee. In the hierarchy as configured the 16-thread utilisation %s allows %+.1f "
      "points by 2u and %+.1f are measured: 32 threads raise the SDRAM traffic per frame from "
      "%.2f to %.2f MB (%+.1f%%) as each added packet brings its working set into the shared "
      "4-way L1s (kd hits %s, triangle hits %s), and the added misses queue at the SDRAM "
      "(threads waiting for memory %s) instead of overlapping. With L1s 16 times larger the "
      "traffic is %.2f -> %.2f MB, the 16-thread utilisation %s, and the gain %+.1f of the "
      "%+.1f the 2u rule allows there. Two things cap the gain in our model, then: the L1s' "
      "working set growing with the threads (the gap between measured and predicted in the "
      "hierarchy), and saturation of the busiest unit once memory is fast (the big-L1 row). "
      "Rows with both published figures inside their bands (60%%-80%%, +7 to +13 points): %s." % (
          "; ".join("%s: %+.1f measured, %+.1f predicted" % (n.split(" (")[0], 100 * (b["busy"] - a["busy"]), pr(a))
                    for n, a, b in fx),
          pct(a0["busy"]), pr(a0), g0, a0["mb"], b0["mb"],
          100 * (b0["mb"] / a0["mb"] - 1) if a0["mb"] else 0.0,
          hh(a0, b0, "kdhit"), hh(a0, b0, "trihit"), hh(a0, b0, "wait"),
          a1["mb"], b1["mb"], pct(a1["busy"]), g1, pr(a1),
          ", ".join(inside) if inside else "none"))
p()

p("## Known model differences")
p()
p("saarsim is a model of the published SaarCOR description, not of its RTL. Unit widths and "
  "latencies, the L1 hit latency, ports and MSHRs, the SDRAM timings and banks, the PCI "
  "parameters, the VMA hash and tag-cache latency, thread scheduling and tile order are "
  "assumed or calibrated (docs/config.md says of each key whether it is published, assumed or "
  "calibrated; docs/CALIBRATION.md gives the fit). Our scenes are substitutes (section 3): the shared Conference is a 69k-triangle "
  "variant of the paper's 282k one, with its own materials, the views and lights of "
  "views.yaml; the paper's views and frame size are not stated. Our kd-trees come from our "
  "own SAH builder, not the paper's. The shared scenes carry no textures and no reflective "
  "materials, so the texturing claim of §4.7 is not measured and reflections are measured on "
  "a procedural scene.")
p()

if E.get("VD_CHECKS"):  # runs for `make test` to rerun (scripts/figures-check.py)
    p(E["VD_CHECKS"])
    p()

tmp = DOC + ".tmp.%d" % os.getpid()
with open(tmp, "w") as f:
    f.write("\n".join(L))
os.replace(tmp, DOC)
