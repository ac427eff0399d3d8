#!/usr/bin/env python3
"""heatmap-check.py: checks a saarsim --heatmap folder (docs/observe.md).

  heatmap-check.py DIR [REPORT.json]

Every file of the folder is there; each map's EXR (read with oiiotool) has
the map's size (tiles or pixels) and its values add up to the total and
reach the maximum heatmap.json gives (to float precision). With
REPORT.json (the same run's --report): kd_steps' total is
traversal.kd_node_steps, tri_tests' is traversal.triangle_tests,
l1_misses' (with the unattributed ones) the sum of the L1s' misses,
cycles' the threads' running, waiting_memory and waiting_unit time and
mem_stall's their waiting_memory time (counters rtp<r>.threads.<state>_ps,
in core cycles).

Prints "ok: ..." and exits 0, or one line per problem and exits 1; a file
that cannot be read (missing, not JSON) is one line and exit status 2.
"""
import json
import os
import re
import subprocess
import sys

MAPS = ("cycles", "mem_stall", "l1_misses", "kd_steps", "tri_tests")
problems = []


def bad(msg):
    problems.append(msg)


def exr_values(path):
    """(width, height, values) of a one-channel EXR, via oiiotool."""
    out = subprocess.run(["oiiotool", "--info", "-v", "--dumpdata", path],
                         capture_output=True, text=True).stdout
    m = re.search(r":\s+(\d+) x\s+(\d+), 1 channel, float", out)
    if not m:
        return None
    vals = [float(x) for x in re.findall(r"Pixel \(\d+, \d+\): (\S+)", out)]
    return int(m.group(1)), int(m.group(2)), vals


def near(a, b, rel=2e-6):
    return abs(a - b) <= rel * max(1.0, abs(a), abs(b))


def load(path):
    with open(path) as f:
        try:
            return json.load(f)
        except ValueError as e:
            raise ValueError(f"{path}: not JSON ({e})") from None


def main(argv):
    if not 1 <= len(argv) <= 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    d = argv[0]
    h = load(os.path.join(d, "heatmap.json"))
    for name in MAPS:
        m = h["maps"].get(name)
        if not m:
            bad(f"{name}: not in heatmap.json")
            continue
        for ext in ("png", "exr"):
            if not os.path.getsize(os.path.join(d, f"{name}.{ext}")):
                bad(f"{name}.{ext}: empty")
        ex = exr_values(os.path.join(d, f"{name}.exr"))
        if not ex:
            bad(f"{name}.exr: not a one-channel float image")
            continue
        w, hh, vals = ex
        want = (h["tiles_x"], h["tiles_y"]) if m["per"] == "tile" else (h["width"], h["height"])
        if (w, hh) != want or len(vals) != w * hh:
            bad(f"{name}.exr: {w}x{hh} ({len(vals)} values), want {want[0]}x{want[1]}")
            continue
        # float32 values: each within 2^-24 of its double
        if not near(sum(vals), m["total"], 1e-6):
            bad(f"{name}.exr: values add up to {sum(vals)}, heatmap.json total {m['total']}")
        if not near(max(vals), m["max"], 1e-6):
            bad(f"{name}.exr: maximum {max(vals)}, heatmap.json {m['max']}")
    if len(argv) == 2 and not problems:
        r = load(argv[1])
        t, c, per = r["traversal"], r["counters"], h["period_ps"]
        tot = {k: h["maps"][k]["total"] for k in MAPS}
        if not near(tot["kd_steps"], t["kd_node_steps"]):
            bad(f"kd_steps: {tot['kd_steps']}, report kd_node_steps {t['kd_node_steps']}")
        if not near(tot["tri_tests"], t["triangle_tests"]):
            bad(f"tri_tests: {tot['tri_tests']}, report triangle_tests {t['triangle_tests']}")
        hier = (r.get("memory") or {}).get("hierarchy")
        misses = sum(hier["l1"][k]["cache"]["misses"] for k in ("shade", "kd", "list", "tri")) \
            if hier else 0
        if tot["l1_misses"] + h["l1_misses_unattributed"] != misses:
            bad(f"l1_misses: {tot['l1_misses']} + {h['l1_misses_unattributed']} unattributed, "
                f"report {misses}")
        busy = sum(v for k, v in c.items() if re.match(
            r"rtp\d+\.threads\.(running|waiting_memory|waiting_unit)_ps$", k)) / per
        wm = sum(v for k, v in c.items() if re.match(r"rtp\d+\.threads\.waiting_memory_ps$", k)) / per
        if not near(tot["cycles"], busy):
            bad(f"cycles: {tot['cycles']}, report's busy thread cycles {busy}")
        if not near(tot["mem_stall"], wm):
            bad(f"mem_stall: {tot['mem_stall']}, report's waiting_memory cycles {wm}")
    for p in problems:
        print(p)
    if problems:
        return 1
    print("ok: " + ", ".join(f"{k} {h['maps'][k]['total']:.6g}" for k in MAPS))
    return 0


if __name__ == "__main__":
    if sys.argv[1:2] in (["-h"], ["--help"]):
        print(__doc__.strip())
        sys.exit(0)
    try:
        sys.exit(main(sys.argv[1:]))
    except (OSError, ValueError) as e:  # a file missing or not JSON: one line
        print(f"heatmap-check.py: {e}", file=sys.stderr)
        sys.exit(2)
