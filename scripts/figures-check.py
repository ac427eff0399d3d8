#!/usr/bin/env python3
"""scripts/figures-check.py: the generated documents' figures are the program's.

A document that a script writes from runs (docs/DYNAMIC.md, DRT.md,
ACCEL.md, VALIDATION.md, NUMERICS.md, FIDELITY.md, CALIBRATION.md and
PERFORMANCE.md's `make bench` and `make bench-ratio` sections) carries,
inside its generated part,
one or more lines

    <!-- figures-check: saarsim ARGS ; KEY=VALUE ; KEY=VALUE ... -->

(a line of its own, outside fenced blocks) written by its generator from one of the runs it shows: the run's
arguments ($SCENES for the shared scenes folder, paths of the repository
relative to it) and some of its report's values (KEY a dotted path into
saarsim's --report JSON or rtref's --stats JSON, VALUE as the JSON had it).

    figures-check.py [--bin DIR] [--scenes DIR] [--root DIR] [DOC ...]

reruns each such run from the repository root (no world cache) and
compares the values exactly. A model change whose documents were not
regenerated fails here (NUMERICS.md's chip fps stayed the pre-calibration
model's for a day; ACCEL.md's kd counts followed another tree). Prints one
line per mismatch and a count; exit 1 on a mismatch, 2 on bad input (a
malformed line, a program that does not run).

    figures-check.py --emit PROG REPORT KEY... -- ARGS...

prints the line for a run the caller made (generators: the values read
from its REPORT, ARGS with the scenes folder given by SAAR_SCENES written
as $SCENES and the repository's root left out).
"""
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile

LINE = re.compile(r"<!-- figures-check: (.*?) -->\s*$")
PROGS = {"saarsim": "--report", "rtref": "--stats"}


def bad(msg):
    print(f"figures-check: {msg}", file=sys.stderr)
    sys.exit(2)


def value_at(doc, path):
    """The value at a dotted path (list items by index), or KeyError."""
    x = doc
    for part in path.split("."):
        if isinstance(x, list):
            x = x[int(part)]
        else:
            x = x[part]
    return x


def load_report(path, where):
    """A run's JSON report, or one line naming it and exit 2."""
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as e:
        bad(f"{where}: {e}")


def as_text(v):
    """A JSON scalar as the check line writes it (json.dumps: 2058.47935,
    258929, null, true)."""
    return json.dumps(v)


def emit(argv):
    if "--" not in argv or len(argv) < 4:
        bad("usage: --emit PROG REPORT KEY... -- ARGS...")
    cut = argv.index("--")
    head, args = argv[:cut], argv[cut + 1:]
    prog, report, keys = head[0], head[1], head[2:]
    if prog not in PROGS or not keys:
        bad(f"--emit: PROG must be saarsim or rtref with at least one KEY, got {head}")
    doc = load_report(report, report)
    root = os.path.dirname(os.path.dirname(os.path.realpath(__file__))) + "/"
    scenes = os.environ.get("SAAR_SCENES") or os.path.join(root, "..", "shared", "scenes")
    scenes = os.path.normpath(os.path.abspath(scenes)) + "/"
    out = []
    for a in args:
        if a.startswith("/"):
            a = os.path.normpath(a)
        if a.startswith(scenes):
            a = "$SCENES/" + a[len(scenes):]
        elif a.startswith(root):
            a = a[len(root):]
        if ";" in a or "-->" in a:
            bad(f"--emit: an argument holds ';' or '-->': {a}")
        out.append(shlex.quote(a))
    parts = [" ".join([prog] + out)]
    for k in keys:
        try:
            parts.append(f"{k}={as_text(value_at(doc, k))}")
        except (KeyError, IndexError, ValueError, TypeError):
            bad(f"{report}: no value at {k}")
    print(f"<!-- figures-check: {' ; '.join(parts)} -->")


def check(argv):
    opts = {"--bin": None, "--scenes": None, "--root": None}
    docs = []
    i = 0
    while i < len(argv):
        if argv[i] in opts and i + 1 < len(argv):
            opts[argv[i]] = argv[i + 1]
            i += 2
        elif argv[i].startswith("-"):
            bad(f"unknown option {argv[i]} (see the file's comment)")
        else:
            docs.append(argv[i])
            i += 1
    root = os.path.abspath(opts["--root"] or os.path.join(os.path.dirname(__file__), ".."))
    bindir = os.path.abspath(opts["--bin"] or os.path.join(root, "build"))
    scenes = os.path.abspath(opts["--scenes"] or os.environ.get("SAAR_SCENES") or
                             os.path.join(root, "..", "shared", "scenes"))
    if not docs:
        d = os.path.join(root, "docs")
        try:
            docs = sorted(os.path.join(d, f) for f in os.listdir(d) if f.endswith(".md"))
        except OSError as e:
            bad(f"{d}: {e}")
    runs = ok = 0
    env = dict(os.environ, SAARSIM_CACHE_DIR="off")
    with tempfile.TemporaryDirectory() as tmp:
        for doc in docs:
            try:
                with open(doc, encoding="utf-8") as f:
                    lines = f.read().splitlines()
            except OSError as e:
                bad(f"{doc}: {e}")
            fenced = False
            for n, text in enumerate(lines, 1):
                if text.lstrip().startswith("```"):
                    fenced = not fenced  # an example in a fenced block is not a check
                m = None if fenced else LINE.match(text)
                if not m:
                    continue
                where = f"{os.path.relpath(doc, root)}:{n}"
                parts = [p.strip() for p in m.group(1).split(" ; ")]
                try:
                    args = shlex.split(parts[0].replace("$SCENES", scenes))
                except ValueError as e:
                    bad(f"{where}: {e}")
                if not args or args[0] not in PROGS or len(parts) < 2:
                    bad(f"{where}: want 'saarsim|rtref ARGS ; KEY=VALUE ...', got {m.group(1)}")
                want = []
                for p in parts[1:]:
                    k, eq, v = p.partition("=")
                    if not eq or not k:
                        bad(f"{where}: '{p}' is not KEY=VALUE")
                    want.append((k, v))
                report = os.path.join(tmp, f"r{runs}.json")
                cmd = [os.path.join(bindir, args[0])] + args[1:] + [PROGS[args[0]], report]
                runs += 1
                try:
                    r = subprocess.run(cmd, cwd=root, env=env, stdout=subprocess.DEVNULL,
                                       stderr=subprocess.PIPE, timeout=600, text=True)
                except (OSError, subprocess.TimeoutExpired) as e:
                    bad(f"{where}: {parts[0]}: {e}")
                if r.returncode != 0:
                    last = (r.stderr.strip().splitlines() or [""])[-1]
                    bad(f"{where}: {parts[0]}: exit {r.returncode}: {last}")
                got = load_report(report, f"{where}: {parts[0]}: its report")
                diffs = []
                for k, v in want:
                    try:
                        g = as_text(value_at(got, k))
                    except (KeyError, IndexError, ValueError, TypeError):
                        g = "(absent)"
                    if g != v:
                        diffs.append(f"{k} shown {v}, the program gives {g}")
                if diffs:
                    print(f"{where}: {parts[0]}: " + "; ".join(diffs))
                else:
                    ok += 1
    print(f"figures-check: {ok} of {runs} runs give the figures their documents show")
    return 0 if ok == runs else 1


def main(argv):
    if argv and argv[0] == "--emit":
        emit(argv[1:])
        return 0
    return check(argv)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
