#!/usr/bin/env python3
"""report-diff.py: compare the simulated figures of saarsim JSON reports.

    scripts/report-diff.py [--ignore KEY]... A.json B.json [A2.json B2.json ...]

Compares every value of A with B's (pairs in turn), recursively, except
what depends on the host rather than the simulation: the `host` object
(times, memory) and the program name. Numbers must be equal exactly;
keys in only one report are listed apart (a newer program may report
more). Prints one line per difference and a summary per pair; exits 1
when any value differs (2 on bad arguments), 0 otherwise.

Written to check that a change to the simulator's host side (issue 29,
data-carrying memory) leaves every figure as it was: run the old and the
new saarsim on the same views, modes and configs and compare the reports.
"""
import json
import sys

SKIP_TOP = {"host", "program"}


def walk(a, b, path, out, only):
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            p = f"{path}.{k}" if path else k
            if not path and k in SKIP_TOP or p in IGNORE:
                continue
            if k not in a or k not in b:
                only.append((p, "A" if k in a else "B"))
                continue
            walk(a[k], b[k], p, out, only)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            out.append((path, f"{len(a)} items", f"{len(b)} items"))
            return
        for i, (x, y) in enumerate(zip(a, b)):
            walk(x, y, f"{path}[{i}]", out, only)
    elif a != b:
        out.append((path, a, b))


IGNORE = set()


def main(argv):
    files = []
    it = iter(argv)
    for arg in it:
        if arg == "--ignore":
            IGNORE.add(next(it, ""))
        elif arg in ("-h", "--help"):
            print(__doc__.strip())
            return 0
        else:
            files.append(arg)
    if not files or len(files) % 2:
        print("usage: report-diff.py [--ignore KEY]... A.json B.json [A2.json B2.json ...]",
              file=sys.stderr)
        return 2
    bad = 0
    for fa, fb in zip(files[0::2], files[1::2]):
        try:
            with open(fa) as f:
                a = json.load(f)
            with open(fb) as f:
                b = json.load(f)
        except (OSError, ValueError) as e:
            print(f"report-diff: {e}", file=sys.stderr)
            return 2
        out, only = [], []
        walk(a, b, "", out, only)
        for p, x, y in out:
            print(f"  {p}: {x} != {y}")
        for p, side in only:
            print(f"  {p}: only in {side}")
        print(f"{fa} vs {fb}: {'identical' if not out else f'{len(out)} values differ'}"
              f"{f', {len(only)} keys in one only' if only else ''}")
        bad |= bool(out)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
