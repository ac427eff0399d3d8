#!/usr/bin/env python3
"""census-need.py: the sample a 1% estimate of a frame needs, from a cycle
run's census (saarsim --census; docs/fidelity.md "Census").

    census-need.py [--hard-share X] [--model auto|max|pnorm]
                   CONFIG THREADS REGION_TILES CENSUS.csv [...]

A Markdown table, one row per census:
the frame's middle, between the head and tail regions of REGION_TILES tiles
(a unit and its warm-up) that sampled mode measures whole, as if every
chunk could be a unit and warming were exact and free. Chunks follow one
of the estimator's demand models (sim/sampling.c), fitted to all chunks
as the estimator fits it to its units: *max*, max(busiest compute
resource, k x SDRAM time, host-bus time) + g x min(busiest compute
resource, k x SDRAM time), k in [1, 4] and g in [0, 1] in steps of 0.02
(the smallest g, then k, under which one ratio fits the chunks best by
least squares); *pnorm*, the p-norm of every compute resource, SDRAM and
host-bus time, p from 1 to 4 in steps of 0.1, then 5, 6, 8, 12, 16 and
infinity (the largest best); *auto* (the default, as sampling.demand_model
auto once the linear model is left out), the one of the two with the
smaller residual variance per degree of freedom (k and g each count where
they leave 1 and 0, p always). Its strata: SDRAM or host-bus time above
sampling.hard_share, X, of the busiest compute resource (default 0.6, the
config's default, which bench-fidelity.sh passes from saarsim
--list-config). The units needed come from the chunks'
variance around the ratio (the ratio estimator's variance with the
finite-population correction), for one ratio and for two strata with
their own ratios and Neyman allocation.
"""
import math
import sys

class Bad(Exception):
    """Bad input: one line, exit status 2."""

# The census's columns (docs/report.md, "Census"), found by name in its
# header: a column added to the census (the transformation unit's xform
# came after this script was written, read by position it shifted the
# SDRAM and host-bus times by one) must not move what the script reads.
FIXED = ("frame", "first_tile", "tiles", "cycles")
MEMORY = ("sdram", "hostbus")

def columns(path, no, line):
    """The header's column indices: frame, first_tile, tiles, cycles, the
    compute resources (every other column before sdram: units and L1s),
    sdram and hostbus."""
    h = [x.strip() for x in line.strip().split(",")]
    missing = [n for n in FIXED + MEMORY if n not in h]
    if missing:
        raise Bad("%s:%d: not a census header (saarsim --census): no column %s"
                  % (path, no, ", ".join(missing)))
    if len(set(h)) != len(h):
        raise Bad("%s:%d: a column named twice in the census header" % (path, no))
    at = {n: h.index(n) for n in FIXED + MEMORY}
    comp = [i for i, n in enumerate(h) if n not in FIXED + MEMORY]
    if not comp:
        raise Bad("%s:%d: no compute resource columns in the census header" % (path, no))
    return at, comp, len(h)

def ratio_ss(c, x):
    """Residual sum of squares of one ratio fitted to cycles c against
    demand x by least squares (sim/sampling.c ratio_ss)."""
    sx = sum(x)
    R = sum(c) / sx if sx > 0 else 0
    return sum((ci - R * xi) ** 2 for ci, xi in zip(c, x))

def max_demand(comp, sdr, hb, k, g):
    """The max model's demand of each chunk (sim/sampling.c demand_kg)."""
    return [max(a, k * b, h) + g * min(a, k * b) for a, b, h in zip(comp, sdr, hb)]

def pnorm_demand(res, comp, sdr, hb, p):
    """The p-norm of each chunk's resources (sim/sampling.c demand_p):
    every compute resource, SDRAM and host-bus time; p infinite, the
    busiest of them."""
    out = []
    for v, a, b, h in zip(res, comp, sdr, hb):
        m = max(a, b, h)
        if m <= 0 or math.isinf(p):
            out.append(max(m, 0.0))
            continue
        out.append(m * sum((y / m) ** p for y in v + [b, h] if y > 0) ** (1 / p))
    return out

P_GRID = [1 + 0.1 * i for i in range(31)] + [5, 6, 8, 12, 16, math.inf]

def fit(model, c, res, comp, sdr, hb):
    """The demand of each chunk under the model fitted to all chunks, and
    the model's name with its parameters for the table."""
    n = len(c)
    best = None
    if model in ("auto", "max"):
        for gs in range(51):
            for ks in range(151):
                k, g = 1 + 0.02 * ks, 0.02 * gs
                e = ratio_ss(c, max_demand(comp, sdr, hb, k, g))
                if best is None or e < best[0] * (1 - 1e-6):
                    best = (e, k, g)
        e, k, g = best
        extra = (k > 1) + (g > 0)
        vmax = e / (n - 1 - extra) if n - 1 - extra > 0 else math.inf
        mx = (max_demand(comp, sdr, hb, k, g), "max, k %.2f, g %.2f" % (k, g))
        if model == "max":
            return mx
    pb = None
    for p in reversed(P_GRID):
        e = ratio_ss(c, pnorm_demand(res, comp, sdr, hb, p))
        if pb is None or e < pb[0] * (1 - 1e-6):
            pb = (e, p)
    e, p = pb
    pn = (pnorm_demand(res, comp, sdr, hb, p),
          "pnorm, p %s" % ("inf" if math.isinf(p) else "%.1f" % p))
    if model == "pnorm":
        return pn
    vp = e / (n - 2) if n > 2 else math.inf
    return pn if vp < vmax else mx

def analyse(path, RW, hard_share=0.6, model="auto"):
    rows = []
    try:
        f = open(path)
    except OSError as e:
        raise Bad("%s: cannot read: %s" % (path, e.strerror))
    cols = None
    with f:
        for no, l in enumerate(f, 1):
            if cols is None:
                cols = columns(path, no, l)
                continue
            at, comp, width = cols
            v = l.strip().split(",")
            if v[at["frame"]] != "1":
                continue
            try:
                if len(v) != width:
                    raise ValueError("%d fields, the header has %d" % (len(v), width))
                rows.append((int(v[at["first_tile"]]), int(v[at["tiles"]]), float(v[at["cycles"]]),
                             [float(v[i]) for i in comp], float(v[at["sdram"]]),
                             float(v[at["hostbus"]])))
            except ValueError as e:
                raise Bad("%s:%d: not a census row (saarsim --census): %s" % (path, no, e))
    if cols is None:
        raise Bad("%s: empty (no census header)" % path)
    N = sum(r[1] for r in rows)
    T = sum(r[2] for r in rows)
    mid = [r for r in rows if r[0] >= RW and r[0] + r[1] <= N - RW]
    if len(mid) < 2:
        raise Bad("%s: %d chunks of frame 1 between the head and tail regions of %d tiles; "
                  "need at least 2" % (path, len(mid), RW))
    c = [r[2] for r in mid]
    M = sum(c)
    res = [r[3] for r in mid]
    comp = [max(v) for v in res]
    sdr = [r[4] for r in mid]
    hb = [r[5] for r in mid]
    n = len(mid)
    x, label = fit(model, c, res, comp, sdr, hb)
    R = M / sum(x)
    d = [ci - R * xi for ci, xi in zip(c, x)]
    q = math.sqrt(sum(v * v for v in d) / (n - 1)) / (R * sum(x) / n)
    hard = sum(ci for ci, a, b, h in zip(c, comp, sdr, hb) if max(b, h) > hard_share * a) / M
    # two strata (memory bound or not, as the estimator's), each with its
    # own ratio, units allocated in proportion to N_h S_h (Neyman): the
    # best two strata can do
    st = {}
    for j in range(n):
        h = max(sdr[j], hb[j]) > hard_share * comp[j]
        st.setdefault(h, []).append(j)
    NS, NS2 = 0.0, 0.0
    for h, J in st.items():
        if len(J) < 2:
            continue
        Rh = sum(c[j] for j in J) / sum(x[j] for j in J)
        Sh = math.sqrt(sum((c[j] - Rh * x[j]) ** 2 for j in J) / (len(J) - 1))
        NS += len(J) * Sh
        NS2 += len(J) * Sh * Sh
    # a sample has at least one unit
    def need_st(rel):
        return max(1.0, NS * NS / ((rel * T) ** 2 + NS2))
    def need(rel):
        if q == 0:  # every chunk on the ratio
            return 1.0
        rm = rel * T / M
        return max(1.0, 1 / ((rm / q) ** 2 + 1 / n))
    share = lambda u: min(1.0, (u * RW + 2 * RW) / N)
    def ideal(units):
        errs = []
        P = n / units
        for o in range(10):
            U = sorted(set(min(n - 1, int(j * P + (o + 0.5) / 10 * P)) for j in range(units)))
            Rh = sum(c[j] for j in U) / sum(x[j] for j in U)
            inU = set(U)
            est = (T - M) + sum(c[j] for j in U) + Rh * sum(x[j] for j in range(n) if j not in inU)
            errs.append((T / est - 1) * 100)
        return math.sqrt(sum(e * e for e in errs) / len(errs)), max(abs(e) for e in errs)
    return dict(n=n, model=label, hard=hard, q=q, nrms=need(0.01), n95=need(0.01 / 1.96), share=share,
                srms=need_st(0.01), s95=need_st(0.01 / 1.96),
                i8=ideal(8) if n >= 8 else None, i16=ideal(16) if n >= 16 else None)
def bad(msg):
    print("census-need.py: " + msg, file=sys.stderr)
    sys.exit(2)

a = sys.argv[1:]
hs = 0.6
model = "auto"
while a[:1] in (["--hard-share"], ["--model"]):
    if len(a) < 2:
        bad("%s: needs a value" % a[0])
    if a[0] == "--hard-share":
        try:
            hs = float(a[1])
        except ValueError:
            bad("--hard-share: expected a number, got '%s'" % a[1])
        if not 0 <= hs < 1e9:
            bad("--hard-share: %s is out of range" % a[1])
    else:
        if a[1] not in ("auto", "max", "pnorm"):
            bad("--model: expected auto, max or pnorm, got '%s'" % a[1])
        model = a[1]
    a = a[2:]
if not a or len(a) % 4:
    bad("usage: census-need.py [--hard-share X] [--model auto|max|pnorm] "
        "CONFIG THREADS REGION_TILES CENSUS.csv [...]")
for i in range(0, len(a), 4):
    if not a[i + 2].isdigit():
        bad("REGION_TILES: expected a whole number, got '%s'" % a[i + 2])
rows = []
for i in range(0, len(a), 4):
    try:
        rows.append((a[i], a[i + 1], analyse(a[i + 3], int(a[i + 2]), hs, model)))
    except Bad as e:
        bad(str(e))
    except (ZeroDivisionError, ValueError) as e:
        bad("%s: a census these figures cannot come from (%s)" % (a[i + 3], e))
print("| config | threads | chunks | memory bound | s | 8 units: rms / max fps err % "
      "| plain: 1% rms | plain: 95% within 1% | strata: 1% rms | strata: 95% within 1% | model |")
print("|---|---:|---:|---:|---:|---|---:|---:|---:|---:|---|")
for cfg, tpr, r in rows:
    fmt = lambda t: "%.2f / %.2f" % t if t else "-"
    sh = lambda u: "%.0f%%" % (100 * r["share"](u))
    print("| %s | %s | %d | %.0f%% | %.3f | %s | %.0f (%s) | %.0f (%s) | %.0f (%s) | %.0f (%s) | %s |" % (
        cfg, tpr, r["n"], 100 * r["hard"], r["q"], fmt(r["i8"]),
        r["nrms"], sh(r["nrms"]), r["n95"], sh(r["n95"]), r["srms"], sh(r["srms"]), r["s95"], sh(r["s95"]),
        r["model"]))
