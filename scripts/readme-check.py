#!/usr/bin/env python3
"""readme-check.py: run the examples of a markdown file and compare their
output with what the file shows (docs/TESTING.md, "Scripts").

    python3 scripts/readme-check.py [--bin DIR] [--scenes DIR] [--keep] [FILE.md]

FILE.md defaults to README.md beside scripts/. Every fenced block whose
lines start with "$ " is an example: each "$ " line is a command, the lines
after it (up to the next command or the fence) the output it shows. The
blocks run in the file's order, in one scratch folder (so a block may use
what an earlier one wrote, as a reader following the page would), with
`build`, `configs` and `scripts` there linking to the repository's (build
to --bin when given), `docs` and `out` empty folders, the default world
cache folder inside it (SAARSIM_CACHE_DIR), and ../shared/scenes in a
command read as --scenes (default: $SAAR_SCENES, else ../shared/scenes
beside the repository).

What is compared: every shown line, in order, against the command's
output (stdout and stderr together), after both sides are normalised:
the scenes folder reads ../shared/scenes, an absolute path ending in
out/... reads out/..., and what the host decides is masked: the numbers
of a `  host:` line (its times) and the default cache folder's path
there, and rtref's "in N ms = N Mrays/s" and "built in N ms". A shown
line "..." (alone, indented or not) stands for any number of lines.
Cycles, fps, counts, hit rates and check results must match exactly:
they depend on no host time. A command gets TIMEOUT seconds (600).

A block right after the line `<!-- readme-check: skip -->` is not run
(its commands need files a reader does not have). A picture right after
the line `<!-- readme-check: picture FILE -->` (`![...](PATH)`) is what
the examples wrote to FILE: once every block has run, PATH (beside the
page) and FILE (in the scratch folder) are compared pixel by pixel with
OpenImageIO's idiff, and must be the same.

Exit status: 0 every example printed what the page shows and every
marked picture is what they drew, 1 some did not (each difference is
printed: the command, the line shown and the line printed; the picture
and how it differs), 2 bad use (a file or folder missing, no idiff).
"""
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SKIP = "<!-- readme-check: skip -->"
TIMEOUT = 600


def die(msg):
    sys.stderr.write("readme-check: %s\n" % msg)
    sys.exit(2)


def closed(cmd):
    """Whether the shell command's quotes are all closed."""
    try:
        shlex.split(cmd, comments=True)
        return True
    except ValueError:
        return False


def pictures(path):
    """The page's checked pictures: (line number, FILE the examples
    write, PATH the page shows)."""
    with open(path, encoding="utf-8") as f:
        lines = f.read().split("\n")
    out = []
    for i, t in enumerate(lines):
        m = re.match(r"\s*<!-- readme-check: picture (\S+) -->\s*$", t)
        if not m:
            continue
        img = re.match(r"\s*!\[[^\]]*\]\(([^)\s]+)\)", lines[i + 1] if i + 1 < len(lines) else "")
        if not img:
            die("%s:%d: a picture marker not followed by a picture ![...](PATH)" % (path, i + 1))
        out.append((i + 2, m.group(1), img.group(1)))
    return out


def examples(path):
    """The page's examples: a list of blocks, each a list of
    (line number, command, [(line number, shown output line)])."""
    try:
        with open(path, encoding="utf-8") as f:
            lines = f.read().split("\n")
    except OSError as e:
        die("%s: %s" % (path, e.strerror))
    blocks, i, skip = [], 0, False
    while i < len(lines):
        s = lines[i].strip()
        if s == SKIP:
            skip = True
        elif s.startswith("```"):
            j = i + 1
            body = []
            while j < len(lines) and not lines[j].strip().startswith("```"):
                body.append((j + 1, lines[j]))
                j += 1
            if j == len(lines):
                die("%s:%d: a fence that is never closed" % (path, i + 1))
            cmds, k = [], 0
            while k < len(body):
                n, t = body[k]
                k += 1
                if t.startswith("$ "):
                    cmd = t[2:]
                    # a quote left open goes on over the next lines
                    while not closed(cmd) and k < len(body):
                        cmd += "\n" + body[k][1]
                        k += 1
                    cmds.append((n, cmd, []))
                elif cmds:
                    cmds[-1][2].append((n, t))
            for c in cmds:  # a blank line between examples shows nothing
                while c[2] and not c[2][-1][1].strip():
                    c[2].pop()
            if cmds and not skip:
                blocks.append(cmds)
            skip = False
            i = j
        elif s:
            skip = skip and s == SKIP
        i += 1
    return blocks


def normalise(line, scenes, work):
    line = line.replace(scenes, "../shared/scenes")
    line = line.replace(work + "/", "")
    line = re.sub(r"(?:/[^\s/:]+)+/out/", "out/", line)
    if line.startswith("  host:"):  # its times, and the default cache folder's path
        line = re.sub(r"stored in [^,)]+", "stored in DIR", line)
        return re.sub(r"[0-9]+(\.[0-9]+)?(e[+-]?[0-9]+)?", "N", line).rstrip()
    line = re.sub(r"in [0-9.]+ ms = [0-9.]+ Mrays/s", "in N ms = N Mrays/s", line)
    line = re.sub(r"built in [0-9.]+ ms", "built in N ms", line)
    return line.rstrip()


def match(shown, printed):
    """Index into shown of the first line that does not match, with the
    printed line it met (None when the printed output ran out), or None
    when all of shown matches. "..." takes any lines up to the first
    printed line that matches the shown line after it."""
    def go(i, j):
        while i < len(shown):
            if shown[i].strip() == "...":
                if i + 1 == len(shown):
                    return None
                for k in range(j, len(printed)):
                    if go(i + 1, k) is None:
                        return None
                return (i + 1, None)
            if j >= len(printed) or printed[j] != shown[i]:
                return (i, printed[j] if j < len(printed) else None)
            i += 1
            j += 1
        if j < len(printed):
            return (i, printed[j])
        return None
    return go(0, 0)


def main(argv):
    args = argv[1:]
    keep = False
    bindir = None
    scenes = os.environ.get("SAAR_SCENES") or os.path.join(os.path.dirname(ROOT), "shared", "scenes")
    page = os.path.join(ROOT, "README.md")
    while args:
        a = args.pop(0)
        if a == "--keep":
            keep = True
        elif a in ("--bin", "--scenes") and args:
            v = os.path.abspath(args.pop(0))
            if a == "--bin":
                bindir = v
            else:
                scenes = v
        elif a.startswith("-"):
            die("usage: readme-check.py [--bin DIR] [--scenes DIR] [--keep] [FILE.md]")
        else:
            page = a
    scenes = os.path.abspath(scenes)
    bindir = bindir or os.path.join(ROOT, "build")
    for d, what in ((scenes, "scenes folder"), (bindir, "build folder")):
        if not os.path.isdir(d):
            die("%s: no such %s" % (d, what))
    blocks = examples(page)
    if not blocks:
        die("%s: no examples (no fenced lines starting with '$ ')" % page)
    work = os.path.realpath(tempfile.mkdtemp(prefix="readme-check."))
    try:
        os.symlink(bindir, os.path.join(work, "build"))
        for d in ("configs", "scripts"):
            os.symlink(os.path.join(ROOT, d), os.path.join(work, d))
        for d in ("docs", "out", "cache"):
            os.mkdir(os.path.join(work, d))
        env = dict(os.environ)
        env["SAARSIM_CACHE_DIR"] = os.path.join(work, "cache")
        env.pop("SAARSIM", None)
        bad = ncmd = 0
        for block in blocks:
            for n, cmd, shown in block:
                ncmd += 1
                run = cmd.replace("../shared/scenes", scenes)
                # its own process group, so a command that never ends
                # goes with everything it started
                p = subprocess.Popen(["bash", "-c", run], cwd=work, env=env, stdout=subprocess.PIPE,
                                     stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                     start_new_session=True)
                try:
                    text = p.communicate(timeout=TIMEOUT)[0].decode("utf-8", "replace")
                except subprocess.TimeoutExpired:
                    os.killpg(p.pid, signal.SIGKILL)
                    p.communicate()
                    text = "(readme-check: no end after %d s)" % TIMEOUT
                printed = [normalise(t, scenes, work) for t in text.split("\n")]
                while printed and printed[-1] == "":
                    printed.pop()
                want = [normalise(t, scenes, work) for _, t in shown]
                r = match(want, printed)
                if r is not None:
                    bad += 1
                    i, got = r
                    print("%s:%d: $ %s" % (page, n, cmd))
                    if i < len(want):
                        print("  shown (line %d):   %s" % (shown[i][0], want[i]))
                    else:
                        print("  shown:   (nothing more)")
                    print("  printed: %s" % (got if got is not None else "(nothing more)"))
        print("readme-check: %s: %d of %d example commands printed what the page shows" %
              (os.path.relpath(page), ncmd - bad, ncmd))
        pics = pictures(page)
        badpic = 0
        for n, made, shown in pics:
            a = os.path.join(work, made)
            b = os.path.join(os.path.dirname(os.path.abspath(page)), shown)
            why = None
            if not os.path.exists(a):
                why = "the examples wrote no %s" % made
            elif not os.path.exists(b):
                why = "%s does not exist" % shown
            else:
                try:
                    d = subprocess.run(["idiff", a, b], stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
                except OSError:
                    die("idiff (OpenImageIO's tools, openimageio-tools) not found")
                if d.returncode != 0:
                    why = "differs from the %s the examples wrote: %s" % (made, " ".join(
                        t.strip() for t in d.stdout.decode("utf-8", "replace").split("\n")
                        if "pixels" in t or "RMS" in t))
            if why:
                badpic += 1
                print("%s:%d: picture %s: %s" % (page, n, shown, why))
        if pics:
            print("readme-check: %s: %d of %d pictures are what the examples draw" %
                  (os.path.relpath(page), len(pics) - badpic, len(pics)))
        return 1 if bad or badpic else 0
    finally:
        if keep:
            print("readme-check: kept %s" % work)
        else:
            shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main(sys.argv))
