#!/usr/bin/env python3
"""extend-doc.py: docs/extending.md's unit-kind walk-through is the patch
that `make extend-check` builds and runs.

  python3 scripts/extend-doc.py [--doc FILE] [--patch FILE]

Every line of code the page's example shows (the ```c blocks from
"### Example: the scene-box clip as a unit" to "That is all.", the lines
"..." left out) must be a line the patch adds or keeps as context,
tests/extend/unit-clip.patch by default, and the patch may change only the
files of the page's "three places" (PLACES below: the unit's .c and .h, the
table's .h and .c, the wiring in sim/chip.c). Lines are compared with their leading and
trailing blanks taken off. So a page edited without the patch, or a patch
without the page, fails here (make test), and the patch itself is built and
run by scripts/extend-check.sh. Exit 0 when every line is found, 1 with one
line per line not found, 2 on bad use or an unreadable file.
"""
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
START = "### Example: the scene-box clip as a unit"
END = "That is all."
# docs/extending.md, "Adding a unit kind": "Adding a kind takes three places"
PLACES = {"units/clip.h", "units/clip.c", "units/unit_table.h", "units/unit_table.c",
          "sim/chip.c"}


def die(msg):
    print("extend-doc: error: %s" % msg, file=sys.stderr)
    sys.exit(2)


def read(path):
    try:
        with open(path, encoding="utf-8") as f:
            return f.read()
    except OSError as e:
        die("%s: %s" % (path, e.strerror))


def doc_lines(path):
    """(line number, text) of each code line of the example's c blocks."""
    text = read(path)
    lines = text.split("\n")
    try:
        a = next(i for i, l in enumerate(lines) if l.strip() == START)
        b = next(i for i in range(a, len(lines)) if lines[i].startswith(END))
    except StopIteration:
        die("%s: no section from '%s' to '%s'" % (path, START, END))
    out, inside = [], False
    for i in range(a, b):
        l = lines[i]
        if l.startswith("```"):
            inside = l.strip() == "```c"
            continue
        if inside:
            if l.strip() and l.strip() != "...":
                out.append((i + 1, l.strip()))
    if not out:
        die("%s: the example shows no code" % path)
    return out


def patch_lines(path):
    """The stripped lines the patch adds or keeps, and the files it changes."""
    have, files = set(), set()
    for l in read(path).split("\n"):
        if l.startswith("+++ b/"):
            files.add(l[6:])
        elif l.startswith(("+", " ")) and not l.startswith("+++"):
            have.add(l[1:].strip())
    if not files:
        die("%s: not a patch (no '+++ b/' line)" % path)
    return have, files


def main(argv):
    doc = os.path.join(ROOT, "docs", "extending.md")
    patch = os.path.join(ROOT, "tests", "extend", "unit-clip.patch")
    args = list(argv)
    while args:
        a = args.pop(0)
        if a in ("--doc", "--patch") and args:
            if a == "--doc":
                doc = args.pop(0)
            else:
                patch = args.pop(0)
        else:
            die("usage: extend-doc.py [--doc FILE] [--patch FILE]")
    shown = doc_lines(doc)
    have, changed = patch_lines(patch)
    bad = 0
    for n, l in shown:
        if l not in have:
            print("%s:%d: the example shows a line the patch does not have: %s" % (doc, n, l))
            bad += 1
    for f in sorted(changed - PLACES):
        print("%s: the patch changes %s, outside the page's three places" % (patch, f))
        bad += 1
    print("extend-doc: %d of %d lines of the example in %s" % (len(shown) - bad, len(shown),
                                                              os.path.basename(patch)))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
