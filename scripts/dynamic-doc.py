#!/usr/bin/env python3
"""scripts/dynamic-doc.py: writes docs/DYNAMIC.md and docs/dynamic-fps.png
from the runs scripts/dynamic.sh made (issue 33 item 5: BART Robots, one
kd-tree over the flattened scene rebuilt every frame against the two-level
tree).

Called by scripts/dynamic.sh only (settings in DY_* environment variables:
DY_OUT the runs' folder, DY_DOC the document, DY_SIZE, DY_FRAMES, DY_FPS,
DY_T0, DY_COMMIT). Every figure comes from a run's JSON report
(DY_OUT/<run>-NNNN.json). Exit 1 with one line when a report is missing.
"""
import json
import os
import subprocess
import sys

E = os.environ
OUT, DOC, SIZE = E["DY_OUT"], E["DY_DOC"], E["DY_SIZE"]
FRAMES, FPS, T0 = int(E["DY_FRAMES"]), float(E["DY_FPS"]), float(E["DY_T0"])
DOCDIR = os.path.dirname(DOC) or "."
RUNS = ("flat-std", "tl-std", "warm-std", "flat-vma", "tl-vma", "warm-vma")


def fail(msg):
    print("dynamic-doc: " + msg, file=sys.stderr)
    sys.exit(1)


def load(run):
    if run.startswith("warm"):
        p = os.path.join(OUT, run + ".json")
        if not os.path.isfile(p):
            fail("no report %s" % p)
        with open(p) as f:
            return json.load(f)
    reps = []
    for i in range(FRAMES):
        p = os.path.join(OUT, "%s-%04d.json" % (run, i) if FRAMES > 1 else run + ".json")
        if not os.path.isfile(p):
            fail("no report %s" % p)
        with open(p) as f:
            reps.append(json.load(f))
    return reps


R = {r: load(r) for r in RUNS}


def c(r, name):
    return r["counters"].get(name, 0)


def steps(r):
    """Traversal steps: kd-node steps (and top-level node steps)."""
    return c(r, "trav.node_steps") + c(r, "toplevel.node_steps")


def host_ms(r):
    """The host's per-frame build: the flat scene's kd-tree and image, or
    the two-level scene's top level (its shading image is built once)."""
    h = r["host"]
    if "two_level" in r:
        return r["two_level"]["host_top_level_ms"]
    return 1e3 * (h["kd_build_s"] + h["image_build_s"])


def mb(x):
    return x / (1 << 20)


def warm_frame(cfg, i):
    """Frame i of the warm run: its figures and its update."""
    w = R["warm-" + cfg]
    return w["per_frame"][i], w["two_level"]["per_frame"][i]


def mem_mb(fr, cfg):
    """Memory traffic of a frame: PCI with the VMA, SDRAM without."""
    if cfg == "vma":
        return fr["pci_mb"] if "pci_mb" in fr else fr["table"]["pci_mb_per_frame"]
    return fr["sdram_mb"] if "sdram_mb" in fr else fr["table"]["sdram_mb_per_frame"]


def hits(fr, cache):
    h = fr["hit_rate"] if "hit_rate" in fr else fr["steady_state"]["hit_rate"]
    return 100 * (h[cache] or 0)


def frame_rows(cfg):
    fl, tl = R["flat-" + cfg], R["tl-" + cfg]
    rows = []
    for i in range(FRAMES):
        f, t = fl[i], tl[i]
        wf, wu = warm_frame(cfg, i)
        up_s = wu["update_ms"] * 1e-3
        ok = f["check"]["identical_8bit"] and t["check"]["identical_8bit"]
        rows.append(
            "| %.2f | %.1f | %.2f | %s | %s | %d | %.1f | %.1f | %.1f | %.3f + %.3f | %.1f | %.2f / %.2f / %.2f | %.1f / %.1f / %.1f | %.1f / %.1f / %.1f | %s |"
            % (
                T0 + i / FPS,
                host_ms(f),
                host_ms(t),
                format(steps(f), ","),
                format(steps(t), ","),
                t["two_level"]["transformations"],
                f["fps"],
                t["fps"],
                wf["fps"],
                mb(wu["update_top_level_bytes"]),
                mb(wu["update_world_bytes"]),
                1.0 / (1.0 / wf["fps"] + up_s),
                mem_mb(f, cfg),
                mem_mb(t, cfg),
                mem_mb(wf, cfg),
                hits(f, "kd"),
                hits(t, "kd"),
                hits(wf, "kd"),
                hits(f, "tri"),
                hits(t, "tri"),
                hits(wf, "tri"),
                "yes" if ok else "NO",
            )
        )
    return rows


def warm_ok(cfg):
    t = R["warm-" + cfg]["two_level"]
    return t["frames_identical_before_last"] == FRAMES - 1 and R["warm-" + cfg]["check"]["identical_8bit"]


def mean(xs):
    return sum(xs) / len(xs) if xs else 0.0


def plot(png):
    dat = os.path.join(OUT, "fps.dat")
    with open(dat, "w") as f:
        f.write("# t flat-std tl-std warm-std warm-std+update flat-vma tl-vma warm-vma warm-vma+update\n")
        for i in range(FRAMES):
            row = [T0 + i / FPS]
            for cfg in ("std", "vma"):
                wf, wu = warm_frame(cfg, i)
                row += [R["flat-" + cfg][i]["fps"], R["tl-" + cfg][i]["fps"], wf["fps"],
                        1.0 / (1.0 / wf["fps"] + wu["update_ms"] * 1e-3)]
            f.write(" ".join("%.6g" % x for x in row) + "\n")
    gp = """set terminal png size 900,520
set output '%s.tmp'
set title 'BART Robots on the chip, %s: fps over the animation (log scale)'
set xlabel 'scene time (s)'
set ylabel 'fps'
set key below
set logscale y
set grid
plot '%s' u 1:2 w lp t 'flat, std', '' u 1:3 w lp t 'two-level cold, std', '' u 1:4 w lp t 'two-level warm, std', \\
     '' u 1:5 w l dt 2 t 'warm + update, std', '' u 1:6 w lp t 'flat, VMA', '' u 1:7 w lp t 'two-level cold, VMA', \\
     '' u 1:8 w lp t 'two-level warm, VMA', '' u 1:9 w l dt 2 t 'warm + update, VMA'
""" % (png, SIZE, dat)
    subprocess.run(["gnuplot"], input=gp.encode(), check=True)
    os.replace(png + ".tmp", png)


def warm_summary(cfg):
    w = R["warm-" + cfg]
    ss = w["steady_state"]
    tl = w["two_level"]
    later = tl["per_frame"][1:]
    up = mean([x["update_bytes"] for x in later])
    top = mean([x["update_top_level_bytes"] for x in later])
    ms = mean([x["update_ms"] for x in later])
    return (
        "steady state (frames 2..%d) %.1f fps, %.2f MB %s per frame; update per frame %.3f MB "
        "(top level %.3f MB, the rest of the image %.3f MB), %.1f ms on the host bus"
        % (FRAMES, ss["fps"], ss["pci_mb"] if cfg == "vma" else ss["sdram_mb"],
           "PCI" if cfg == "vma" else "SDRAM", mb(up), mb(top), mb(up - top), ms)
    )


def main():
    png = os.path.join(DOCDIR, "dynamic-fps.png")
    plot(png)
    t0 = R["tl-std"][0]["two_level"]
    hdr = ("| t (s) | host build flat (ms) | host top level (ms) | traversal steps flat | "
           "traversal steps two-level | transformations | fps flat | fps two-level cold | "
           "fps two-level warm | warm update MB (top + world) | fps warm + update | "
           "%s MB flat / cold / warm | kd hit %% flat / cold / warm | "
           "tri hit %% flat / cold / warm | identical |")
    sep = "|" + "---|" * 15
    flat_host = mean([host_ms(r) for r in R["flat-std"]])
    tl_host = mean([host_ms(r) for r in R["tl-std"]])
    L = [
        "# Dynamic scenes: flat rebuild against the two-level tree",
        "",
        "Written by `scripts/dynamic.sh` (`make dynamic`; commit %s) from saarsim runs; "
        "do not edit by hand." % E["DY_COMMIT"],
        "",
        "BART Robots (`bart_robots_aff/aff/Robot.aff`, %d triangles), %d frames at %g "
        "frames per second of scene time from t = %g, %s pixels, every frame checked "
        "against kernel-ref (last column: flat and cold two-level frames; the warm runs' "
        "frames: %s). **Flat**: the scene flattened at the frame's time and one kd-tree "
        "built over it, a new (cold) chip per frame. **Two-level** (`--two-level`, "
        "docs/design.md \"The chip on two-level scenes\"): %d instances of %d objects; "
        "the objects' kd-trees built once (%.0f ms on the host), per frame the top-level "
        "BVH over the instances (%d nodes) rebuilt; **cold** (`--anim-cold`) a new chip per "
        "frame, **warm** one chip for the animation with the host's update written "
        "between frames. Traversal steps: kd-node "
        "steps, plus top-level node steps for the two-level tree (the same cold and "
        "warm). Transformations: packets moved into an instance's space by the "
        "transformation unit (which also moves each shaded packet's hits back into the "
        "world: `normal_transformations` in the reports). fps warm + update: the frame and its update's transfer over "
        "the host bus one after the other. Frame 1's warm update is the top level alone "
        "(the objects and the first frame's records were on the board before)."
        % (R["flat-std"][0]["triangles"], FRAMES, FPS, T0, SIZE,
           "all identical" if warm_ok("std") and warm_ok("vma") else "SOME DIFFER",
           t0["instances"], t0["objects"], t0["host_bottom_level_ms"], t0["top_nodes"]),
        "",
        "Mean host build per frame: %.1f ms flat (kd-tree and image), %.2f ms two-level "
        "(top level)." % (flat_host, tl_host),
        "",
        "Warm, scene on the board: " + warm_summary("std") + ".",
        "",
        "Warm, scene in host memory (VMA): " + warm_summary("vma") + ".",
        "",
        "![fps over the animation](dynamic-fps.png)",
        "",
        "## Scene on the board (configs/saarcor-std.yaml)",
        "",
        hdr % "SDRAM",
        sep,
    ]
    L += frame_rows("std")
    L += ["", "## Scene in host memory, over PCI (configs/saarcor-vma.yaml)", "", hdr % "PCI", sep]
    L += frame_rows("vma")
    checks = []
    for run in ("flat-std", "warm-std"):
        p = os.path.join(OUT, run + ".check")
        if not os.path.isfile(p):
            fail("no %s (scripts/dynamic.sh writes it with the run)" % p)
        with open(p) as f:
            checks.append(f.read().strip())
    L += [""] + checks
    L += [
        "",
        "## What this shows and what it does not",
        "",
        "The warm update is the top level alone (BVH nodes and instance records): the "
        "two-level shading image holds every part's triangle and shading records in its "
        "own frame, the same at every time, and the shader (kernel-ref's and the chip's "
        "RGS, after a transformation-unit op) moves a hit's corners and normals into the "
        "world by the forward and normal matrices of its instance record. The host times "
        "are single measurements on a shared machine.",
        "",
    ]
    tmp = DOC + ".tmp"
    with open(tmp, "w") as f:
        f.write("\n".join(L))
    os.replace(tmp, DOC)


main()
