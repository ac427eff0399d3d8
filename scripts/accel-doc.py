#!/usr/bin/env python3
"""scripts/accel-doc.py: writes docs/ACCEL.md from scripts/accel.sh's runs.

    python3 scripts/accel-doc.py OUT_DIR DOC SIZE "VIEWS" "TIMES" BIG_VIEW BIG_SIZE

Every number in the document is read from a run's JSON (rtref --stats,
saarsim --report) or compared from its image; nothing is typed in. Bad
input (a missing or unreadable run): one line, exit 2.
"""
import json
import os
import sys


def bad(msg):
    print(f"accel-doc: {msg}", file=sys.stderr)
    sys.exit(2)


def load(out, name):
    path = os.path.join(out, name)
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        bad(f"{path}: {e}")


def load_kd(out, name):
    """An rtref kd-tree run: the plain SAH tree the chip walks, not rtref's
    own tree for the view's packets (accel.sh passes --kd-footprint 0)."""
    r = load(out, name)
    fp = r.get("kdtree", {}).get("footprint_from")
    if fp != "none":
        bad(f"{os.path.join(out, name)}: rtref built its kd-tree for a packet footprint "
            f"(footprint_from {fp!r}); the tables compare the plain SAH tree: rerun with "
            "--kd-footprint 0 (delete the run to redo it)")
    return r


def same_image(out, a, b):
    try:
        with open(os.path.join(out, a), "rb") as f, open(os.path.join(out, b), "rb") as g:
            return f.read() == g.read()
    except OSError:
        return None


def rays(r):
    return r["rays"]["total"]


def per_ray(r, key):
    n = rays(r)
    return r[key] / n if n else 0.0


def l1_hit_rate(c):
    """All L1 caches together: hits over accesses."""
    acc = hits = 0
    for v in c["memory"]["hierarchy"]["l1"].values():
        if isinstance(v, dict) and "cache" in v:
            acc += v["cache"]["accesses"]
            hits += v["cache"]["hits"]
    return hits / acc if acc else 0.0


def fmt(x, d=2):
    return f"{x:,.{d}f}"


def yes(v):
    return "yes" if v else ("?" if v is None else "**no**")


def static_section(out, views):
    L = ["## Static shared views", ""]
    L.append("kernel-ref, one host thread, packets of 8x8 rays, shadows and depth 3. "
             "*build*: the host build of the structure (kd-tree: SAH build; grid: "
             "`grid_build`, lambda 5, macrocells 6; frusta of primary rays, secondary rays by the "
             "DDA); *trace*: kernel-ref's traversal and "
             "intersection time; *steps/ray*: kd-node steps (kd: a packet's step counts "
             "once) or slice steps (grid: a frustum's once, the DDA's per ray) over the rays; *tests/ray*: ray-triangle tests per ray; *same image*: the grid's "
             "frame equals the kd-tree's byte for byte. Two-level trees need a scene "
             "of rigid objects placed by transforms (an AFF scene): a static OBJ is one "
             "object, whose two-level tree would be its kd-tree under one instance, so "
             "they are compared on the Robots below (the `robots` view here is the same "
             "scene frozen at t = 0 as an OBJ).")
    L.append("")
    L.append("| view | triangles | kd build ms | grid build ms | grid cells | kd trace ms | "
             "grid trace ms | kd steps/ray | grid steps/ray | kd tests/ray | grid tests/ray "
             "| same image |")
    L.append("|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---|")
    for v in views:
        k, g = load_kd(out, f"{v}-kd.json"), load(out, f"{v}-grid.json")
        res = "x".join(str(n) for n in g["grid"]["resolution"])
        L.append(f"| {v} | {k['triangles']:,} | {fmt(k['build_ms'], 1)} | "
                 f"{fmt(g['grid']['build_ms'], 1)} | {res} | {fmt(k['trace_ms'], 1)} | "
                 f"{fmt(g['trace_ms'], 1)} | {fmt(per_ray(k, 'kd_node_visits'))} | "
                 f"{fmt(per_ray(g, 'kd_node_visits'))} | "
                 f"{fmt(per_ray(k, 'ray_triangle_tests'))} | "
                 f"{fmt(per_ray(g, 'ray_triangle_tests'))} | "
                 f"{yes(same_image(out, f'{v}-kd.ppm', f'{v}-grid.ppm'))} |")
    L.append("")
    L.append("The chip (saarsim, default config, cycle fidelity) on the kd-tree and on the "
             "grid (`--accel grid`: the grid traversal unit, units/gridtrav.c; its memory "
             "image is the frame's plus the grid's cells, lists and macrocell flags, "
             "docs/memory-map.md \"Uniform grid\"). *SDRAM*: bytes read from SDRAM per "
             "frame; *L1 hit rate*: all L1 caches together; *steps*: kd-node steps, or "
             "the grid's slice steps (DDA cell steps for rays alone); *check*: the chip's "
             "frame equals kernel-ref's (for the grid: kernel-ref's grid frame).")
    L.append("")
    L.append("| view | kd chip fps | grid chip fps | kd SDRAM KB/frame | grid SDRAM KB/frame | "
             "kd L1 hit rate | grid L1 hit rate | kd steps/ray | grid steps/ray | "
             "kd tests/ray | grid tests/ray | kd check | grid check |")
    L.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---|")
    for v in views:
        c = load(out, f"{v}-chip.json")
        cg = load(out, f"{v}-chip-grid.json")
        pr, pg = c["ray_types"]["primary"], cg["ray_types"]["primary"]
        L.append(f"| {v} | {fmt(c['fps'], 0)} | {fmt(cg['fps'], 0)} | "
                 f"{fmt(c['memory']['hierarchy']['sdram']['bytes'] / 1024, 1)} | "
                 f"{fmt(cg['memory']['hierarchy']['sdram']['bytes'] / 1024, 1)} | "
                 f"{fmt(l1_hit_rate(c), 3)} | {fmt(l1_hit_rate(cg), 3)} | "
                 f"{fmt(pr['kd_steps_per_ray'])} | {fmt(pg['kd_steps_per_ray'])} | "
                 f"{fmt(pr['triangle_tests_per_ray'])} | {fmt(pg['triangle_tests_per_ray'])} | "
                 f"{yes(c['check']['identical_8bit'])} | {yes(cg['check']['identical_8bit'])} |")
    L.append("")
    L.append("(The chip's steps and tests per ray are its primary rays'.)")
    L.append("")
    return L


def table4_section(out, views):
    L = ["## Seed 003's Table 4: cells visited and triangle tests", ""]
    L.append("Primary rays only (`--no-shadows --depth 0`), no macrocells, mailboxing and "
             "frustum culling on, the "
             "same grid for all three: single rays by the 3D DDA (`--grid-packet 1`), "
             "frusta of 4x4 and of 8x8 rays. *cells*: cells visited (a frustum's cells "
             "count once per frustum); *ray tests*: ray-triangle tests; *packet tests*: "
             "triangle tests counted once per frustum (one SIMD test of its rays). The "
             "kd-tree's primary rays for comparison (leaf visits per packet, ray-triangle "
             "tests).")
    L.append("")
    L.append("| view | cells 1 | cells 4x4 | cells 8x8 | ratio 4x4 | ratio 8x8 | ray tests 1 | "
             "ray tests 4x4 | ray tests 8x8 | packet tests 4x4 | packet tests 8x8 | "
             "kd ray tests |")
    L.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    trend = {"r4": [], "r8": [], "t4": [], "t8": []}
    for v in views:
        r = {k: load(out, f"{v}-t4-{k}.json") for k in ("1", "4", "8")}
        r["kd"] = load_kd(out, f"{v}-t4-kd.json")
        c1, c4, c8 = (r[k]["leaf_visits"] for k in ("1", "4", "8"))
        t1, t4, t8 = (r[k]["ray_triangle_tests"] for k in ("1", "4", "8"))
        r4, r8 = c1 / c4 if c4 else 0, c1 / c8 if c8 else 0
        trend["r4"].append(r4)
        trend["r8"].append(r8)
        trend["t4"].append(t4 < t1)
        trend["t8"].append(t8 > t4)
        L.append(f"| {v} | {c1:,} | {c4:,} | {c8:,} | {fmt(r4, 1)} | {fmt(r8, 1)} | {t1:,} | "
                 f"{t4:,} | {t8:,} | {r['4']['triangle_tests']:,} | "
                 f"{r['8']['triangle_tests']:,} | {r['kd']['ray_triangle_tests']:,} |")
    L.append("")
    n = len(views)
    L.append("Against the seed's trends (Table 4: 4x4 packets visit 10 to 20 times fewer "
             "cells than single rays, 8x8 packets 8 to 56 times fewer; 4x4 packets make "
             "fewer ray-triangle tests than single rays, 8x8 packets more than 4x4):")
    L.append("")
    L.append(f"* cells, single over 4x4: {fmt(min(trend['r4']), 1)} to "
             f"{fmt(max(trend['r4']), 1)}; single over 8x8: {fmt(min(trend['r8']), 1)} to "
             f"{fmt(max(trend['r8']), 1)} (at {out_size_note()}: a frame this small has "
             "fewer rays per cell than the seed's 1024x1024, so the ratios are smaller);")
    L.append(f"* 4x4 fewer ray-triangle tests than single rays: {sum(trend['t4'])} of {n} "
             f"views; 8x8 more than 4x4: {sum(trend['t8'])} of {n} views. Every ray of a "
             "frustum is tested against every triangle of every cell the frustum overlaps "
             "that the frustum does not cull (mailboxed once per frustum), so the "
             "packets' ray tests count rays a SIMD test carries along.")
    L.append("")
    big, bsize = BIG
    r = {k: load(out, f"{big}-big-t4-{k}.json") for k in ("1", "4", "8")}
    c1, c4, c8 = (r[k]["leaf_visits"] for k in ("1", "4", "8"))
    t1, t4, t8 = (r[k]["ray_triangle_tests"] for k in ("1", "4", "8"))
    (w0, h0), (w1, h1) = (map(int, x.split("x")) for x in (SIZE_NOTE[0], bsize))
    L.append(f"The same on {big} at {bsize} ({w1 * h1 / (w0 * h0):g} times the rays):")
    L.append("")
    L.append("| size | cells 1 | cells 4x4 | cells 8x8 | ratio 4x4 | ratio 8x8 | ray tests 1 | "
             "ray tests 4x4 | ray tests 8x8 |")
    L.append("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    L.append(f"| {bsize} | {c1:,} | {c4:,} | {c8:,} | {fmt(c1 / c4 if c4 else 0, 1)} | "
             f"{fmt(c1 / c8 if c8 else 0, 1)} | {t1:,} | {t4:,} | {t8:,} |")
    L.append("")
    return L


BIG = ["?", "?"]


SIZE_NOTE = ["?"]


def out_size_note():
    return SIZE_NOTE[0]


def robots_section(out, times):
    L = ["## Animated: BART Robots", ""]
    L.append("Each frame is a fresh world at its animation time (rtref `--anim-time T`). "
             "*kd build*: the SAH kd-tree over the flattened frame; *grid build*: the "
             "grid over the same frame; *two-level top*: the tree over the 221 "
             "instances (its bottom level, 23 objects' kd-trees, is built once: "
             "*bottom*). Trace times are kernel-ref's, one thread. *same image*: the "
             "grid's frame equals the kd-tree's (the two-level trees' differ by the "
             "rounding of the object-space test, design.md \"Two-level trees\").")
    L.append("")
    L.append("| t | triangles | kd build ms | grid build ms | two-level top ms | "
             "bottom ms | kd trace ms | grid trace ms | two-level trace ms | grid tests/ray | "
             "kd tests/ray | same image | kd chip fps | grid chip fps | kd chip SDRAM KB | "
             "grid chip SDRAM KB | kd chip L1 hit rate | grid chip L1 hit rate | kd check | "
             "grid check |")
    L.append("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|"
             "---:|---:|---|---|")
    for t in times:
        k = load_kd(out, f"robots-{t}-kd.json")
        g = load(out, f"robots-{t}-grid.json")
        tl = load(out, f"robots-{t}-two-level.json")
        c = load(out, f"robots-{t}-chip.json")
        cg = load(out, f"robots-{t}-chip-grid.json")
        L.append(f"| {t} | {k['triangles']:,} | {fmt(k['build_ms'], 1)} | "
                 f"{fmt(g['grid']['build_ms'], 1)} | "
                 f"{fmt(tl['two_level']['top_build_ms'], 2)} | "
                 f"{fmt(tl['two_level']['bottom_build_ms'], 1)} | {fmt(k['trace_ms'], 1)} | "
                 f"{fmt(g['trace_ms'], 1)} | {fmt(tl['trace_ms'], 1)} | "
                 f"{fmt(per_ray(g, 'ray_triangle_tests'))} | "
                 f"{fmt(per_ray(k, 'ray_triangle_tests'))} | "
                 f"{yes(same_image(out, f'robots-{t}-kd.ppm', f'robots-{t}-grid.ppm'))} | "
                 f"{fmt(c['fps'], 0)} | {fmt(cg['fps'], 0)} | "
                 f"{fmt(c['memory']['hierarchy']['sdram']['bytes'] / 1024, 1)} | "
                 f"{fmt(cg['memory']['hierarchy']['sdram']['bytes'] / 1024, 1)} | "
                 f"{fmt(l1_hit_rate(c), 3)} | {fmt(l1_hit_rate(cg), 3)} | "
                 f"{yes(c['check']['identical_8bit'])} | {yes(cg['check']['identical_8bit'])} |")
    L.append("")
    L.append("The chip's columns: on the kd-tree and on the grid (the grid traversal "
             "unit); the per-frame builds are the host's *kd build* and *grid build* "
             "columns (each frame a fresh world and chip: the grid's image written "
             "with the frame's).")
    L.append("")
    L.append("The chip on the two-level trees (`saarsim --two-level`: the top level "
             "walked by the traversal unit, rays moved into object space and normals "
             "back by the transformation unit; docs/design.md \"The chip on two-level "
             "scenes\"), each frame a fresh chip as above, beside its kd-tree run. "
             "*update KB*: the top level the host writes per frame (warm animations "
             "write only this: docs/DYNAMIC.md).")
    L.append("")
    L.append("| t | kd chip fps | two-level chip fps | kd chip SDRAM KB | two-level chip "
             "SDRAM KB | kd chip L1 hit rate | two-level chip L1 hit rate | top-level "
             "steps/ray | transformations | update KB | two-level check |")
    L.append("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for t in times:
        c = load(out, f"robots-{t}-chip.json")
        ct = load(out, f"robots-{t}-chip-two-level.json")
        tl = ct["two_level"]
        L.append(f"| {t} | {fmt(c['fps'], 0)} | {fmt(ct['fps'], 0)} | "
                 f"{fmt(c['memory']['hierarchy']['sdram']['bytes'] / 1024, 1)} | "
                 f"{fmt(ct['memory']['hierarchy']['sdram']['bytes'] / 1024, 1)} | "
                 f"{fmt(l1_hit_rate(c), 3)} | {fmt(l1_hit_rate(ct), 3)} | "
                 f"{fmt(tl['top_node_steps'] / rays(ct))} | "
                 f"{tl['transformations']:,} | "
                 f"{fmt(tl['update_bytes'] / 1024, 1)} | "
                 f"{yes(ct['check']['identical_8bit'])} |")
    L.append("")
    return L


def main():
    if len(sys.argv) != 8:
        bad("usage: accel-doc.py OUT_DIR DOC SIZE VIEWS TIMES BIG_VIEW BIG_SIZE")
    out, doc, size, views, times = sys.argv[1:6]
    BIG[:] = sys.argv[6:8]
    SIZE_NOTE[0] = size
    views, times = views.split(), times.split()
    L = ["# Acceleration structures: kd-tree, uniform grid, two-level trees", ""]
    L.append("<!-- written by scripts/accel.sh (make accel) and scripts/accel-doc.py; do "
             "not edit by hand -->")
    L.append("")
    L.append(f"Frames of {size} pixels. The kd-tree is kernel-ref's SAH tree "
             "(kernel-ref/kdtree.c), the plain one the chip walks (rtref `--kd-footprint 0`: "
             "rtref's default tree is built for the view's packets, docs/kernel-ref.md "
             "\"rtref's own tree\", and cuts the less the fewer pixels a frame has), the grid seed 003's uniform grid with coherent grid "
             "traversal (kernel-ref/grid.c, gridtrav.c; docs/design.md \"Uniform grid\"), "
             "the two-level trees seed 002 §6's (kernel-ref/twolevel.c). Host times are "
             "from one run each on a shared machine: compare them within a table, not "
             "across runs. Regenerate with `make accel`.")
    L.append("")
    env = os.environ.get
    L.append(f"Generated {env('ACCEL_DATE', 'at an unknown date')} on "
             f"{env('ACCEL_HOST', 'an unknown host')}; commit "
             f"{env('ACCEL_COMMIT', 'unknown')} (runs already in the run folder are "
             "reused, with their own host times).")
    L.append("")
    L += static_section(out, views)
    L += table4_section(out, views)
    L += robots_section(out, times)
    try:  # accel.sh's runs for `make test` to rerun (scripts/figures-check.py)
        with open(os.path.join(out, "checks")) as f:
            L += ["", f.read().strip(), ""]
    except OSError as e:
        bad(f"{os.path.join(out, 'checks')}: {e}")
    tmp = doc + ".tmp"
    with open(tmp, "w") as f:
        f.write("\n".join(L))
    os.replace(tmp, doc)


if __name__ == "__main__":
    main()
