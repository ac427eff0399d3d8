#!/usr/bin/env python3
"""layers.py: the layering check (issue 30 item 5; docs/design-layers.md).

  python3 scripts/layers.py [--root DIR]           check the includes
  python3 scripts/layers.py [--root DIR] --long N  list functions over N lines

Reads every .c, .h and .cpp under kernel-ref/, sim/ (with sim/core/ and
sim/modes/), units/, mem/ and traces/ of the repository (DIR, default the
folder above this script); tests/ and scripts/ are exempt. Fails on
  (a) a quoted include that does not name its folder ("cache.h" for
      "mem/cache.h"): the build uses -I. only, and a bare name would
      silently find a file beside the includer instead;
  (b) an include the layer table below forbids;
  (c) an include circle between modules (a module is x.c with x.h; A
      depends on B when A.c or A.h includes B.h), its members in order.
One line per violation, "file:line: what is forbidden and why"; exit 0
when clean, 1 on violations, 2 on bad use. System includes <...> are not
checked.

--long N lists every function longer than N lines (from the line with its
name to its closing brace; a rough brace count over the code without
comments, strings and preprocessor lines) as "file:line: name: L lines";
exit 1 when there is one, else 0.
"""
import os
import re
import sys

# ---- the layer table, lowest layer first ----
# A row: the folder, what its files may include (a folder "x/" or one file),
# and why. A file's layer is the longest folder here that its path starts
# with (sim/core/ before sim/; sim/modes/ is sim/).
LAYERS = [
    ("kernel-ref/", ["kernel-ref/"],
     "the reference tracer and its utilities stand alone: the chip is checked against them"),
    ("sim/core/", ["kernel-ref/", "sim/core/"],
     "the timing kernel (event engine, stats registry) that every layer may use"),
    ("mem/", ["kernel-ref/", "sim/core/", "mem/"],
     "the memory hierarchy knows no units, config schema, CLI or reports"),
    ("units/", ["kernel-ref/", "sim/core/", "mem/memport.h", "units/"],
     "units reach memory only through its port and know no config schema, CLI or reports"),
    ("traces/", ["kernel-ref/", "sim/core/", "mem/", "units/", "traces/"],
     "the trace formats record memory requests and unit ops: above mem/ and units/, below sim/"),
    ("sim/", ["kernel-ref/", "sim/core/", "mem/", "units/", "traces/", "sim/"],
     "the chip's wiring, modes, config, reports and CLI: the top layer"),
]
# Single files a folder never includes although its row allows their folder.
NEVER = [
    ("mem/", "kernel-ref/jsonw.h", "reports are written in sim/"),
    ("units/", "kernel-ref/jsonw.h", "reports are written in sim/"),
    ("mem/", "kernel-ref/world.h", "it holds the command line (world_parse_arg, cli_bad)"),
    ("units/", "kernel-ref/world.h", "it holds the command line (world_parse_arg, cli_bad)"),
]
# Programs (the files with a main; the Makefile's MAINS) sit above every
# library layer. kernel-ref's own programs stay in kernel-ref: the reference
# never depends on the chip it checks.
EVERY = ["kernel-ref/", "sim/core/", "mem/", "units/", "traces/", "sim/"]
PROGRAMS = {
    "sim/main.c": (EVERY, "a program may use every library layer"),
    "traces/replay.c": (EVERY, "a program may use every library layer"),
    "kernel-ref/rtref.c": (["kernel-ref/"], "the reference never depends on the chip"),
    "kernel-ref/stress_main.c": (["kernel-ref/"], "the reference never depends on the chip"),
}
TOPS = ["kernel-ref", "sim", "units", "mem", "traces"]
EXTS = (".c", ".h", ".cpp")


def usage(msg):
    sys.stderr.write("layers.py: %s (usage: layers.py [--root DIR] [--long N])\n" % msg)
    sys.exit(2)


def strip_code(text):
    """The text with comments blanked and string/char literals emptied
    (quotes kept), newlines kept so line numbers stay. Include lines keep
    their quoted name: a line whose first token is #include is copied."""
    out = []
    i, n = 0, len(text)
    bol = True  # at the beginning of a line (only blanks so far)
    while i < n:
        ch = text[i]
        if bol and ch == "#":
            m = re.match(r"#\s*include\s*[\"<][^\">\n]*[\">]", text[i:])
            if m:
                out.append(m.group(0))
                i += len(m.group(0))
                bol = False
                continue
        if ch == "/" and text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
            continue
        if ch == "/" and text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            i = j
            continue
        if ch in "\"'":
            j = i + 1
            while j < n and text[j] != ch and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            out.append(ch + ch)
            i = j + 1
            continue
        out.append(ch)
        if ch == "\n":
            bol = True
        elif not ch.isspace():
            bol = False
        i += 1
    return "".join(out)


def source_files(root):
    files = []
    for top in TOPS:
        for dirpath, dirnames, names in os.walk(os.path.join(root, top)):
            dirnames.sort()
            for name in sorted(names):
                if name.endswith(EXTS):
                    files.append(os.path.relpath(os.path.join(dirpath, name), root))
    return [f.replace(os.sep, "/") for f in files]


def includes(code):
    """(line number, quoted name) of each #include "..." in stripped code."""
    found = []
    for k, line in enumerate(code.split("\n"), 1):
        m = re.match(r"\s*#\s*include\s*\"([^\"]*)\"", line)
        if m:
            found.append((k, m.group(1)))
    return found


def layer_of(path):
    best = None
    for row in LAYERS:
        if path.startswith(row[0]) and (best is None or len(row[0]) > len(best[0])):
            best = row
    return best


def allowed(target, entries):
    return any(target == e or (e.endswith("/") and target.startswith(e)) for e in entries)


def check_include(path, line, name, root):
    """The violation message for one include, or None."""
    parts = name.split("/")
    if len(parts) < 2 or "." in parts[:-1] or ".." in parts:
        beside = os.path.normpath(os.path.join(os.path.dirname(path), name)).replace(os.sep, "/")
        hint = ' (write "%s")' % beside if os.path.exists(os.path.join(root, beside)) else ""
        return ('%s:%d: #include "%s" does not name its folder%s: the build uses -I. only, '
                "and a bare name finds a file beside the includer" % (path, line, name, hint))
    if path in PROGRAMS:
        entries, why = PROGRAMS[path]
        if not allowed(name, entries):
            return ("%s:%d: the program %s must not include %s: it may include only %s (%s)"
                    % (path, line, path, name, ", ".join(entries), why))
        return None
    folder, entries, why = layer_of(path)
    if not allowed(name, entries):
        return ("%s:%d: %s must not include %s: %s may include only %s (%s)"
                % (path, line, folder, name, folder, ", ".join(entries), why))
    for f, target, reason in NEVER:
        if folder == f and name == target:
            return "%s:%d: %s must not include %s: %s" % (path, line, folder, name, reason)
    return None


def sccs(graph, nodes):
    """Strongly connected components of graph restricted to nodes (Tarjan,
    iterative)."""
    index, low, onstack, stack, comps = {}, {}, set(), [], []
    counter = [0]
    for start in sorted(nodes):
        if start in index:
            continue
        work = [(start, iter(sorted(graph.get(start, {}))))]
        index[start] = low[start] = counter[0]
        counter[0] += 1
        stack.append(start)
        onstack.add(start)
        while work:
            v, it = work[-1]
            advanced = False
            for w in it:
                if w not in nodes:
                    continue
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    onstack.add(w)
                    work.append((w, iter(sorted(graph.get(w, {})))))
                    advanced = True
                    break
                if w in onstack:
                    low[v] = min(low[v], index[w])
            if advanced:
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = set()
                while True:
                    w = stack.pop()
                    onstack.discard(w)
                    comp.add(w)
                    if w == v:
                        break
                comps.append(comp)
    return comps


def shortest_cycle(graph, comp, s):
    """The shortest path s -> ... -> s inside comp (breadth first)."""
    prev = {}
    queue = [s]
    for v in queue:
        for w in sorted(graph.get(v, {})):
            if w not in comp:
                continue
            if w == s:
                path = [v]
                while path[-1] != s:
                    path.append(prev[path[-1]])
                return list(reversed(path)) + [s]
            if w not in prev:
                prev[w] = v
                queue.append(w)
    return [s, s]


def circles(graph):
    """One cycle per strongly connected part (through its first module);
    then that module is taken out and what stays cyclic is searched again,
    so every circle shows up in at least one line."""
    found = []
    work = [set(graph)]
    while work:
        sub = work.pop()
        for comp in sccs(graph, sub):
            if len(comp) < 2:
                continue
            s = min(comp)
            found.append(shortest_cycle(graph, comp, s))
            work.append(comp - {s})
    return sorted(found)


def check(root):
    files = source_files(root)
    out = []
    graph = {}  # module -> {module it depends on: (file, line)}
    for path in files:
        with open(os.path.join(root, path), encoding="utf-8", errors="replace") as f:
            code = strip_code(f.read())
        mod = os.path.splitext(path)[0]
        for line, name in includes(code):
            msg = check_include(path, line, name, root)
            if msg:
                out.append(msg)
            target = os.path.splitext(name)[0]
            if name.endswith(".h") and target != mod and target.split("/")[0] in TOPS:
                graph.setdefault(mod, {}).setdefault(target, (path, line))
    for cyc in circles(graph):
        path, line = graph[cyc[0]][cyc[1]]
        out.append("%s:%d: include circle %s: modules may not depend on each other in a "
                   "circle (each builds on the ones below it)" % (path, line, " -> ".join(cyc)))
    return out


def long_functions(root, limit):
    out = []
    for path in source_files(root):
        with open(os.path.join(root, path), encoding="utf-8", errors="replace") as f:
            code = strip_code(f.read())
        # preprocessor lines (with their continuations) hold no function
        # but may hold braces (do { } while (0) in a macro): blanked
        lines = code.split("\n")
        cont = False
        for k, ln in enumerate(lines):
            if cont or ln.lstrip().startswith("#"):
                cont = ln.rstrip().endswith("\\")
                lines[k] = ""
        depth, head, name, start, head_line = 0, "", None, 0, 0
        for k, ln in enumerate(lines, 1):
            for ch in ln:
                if ch == "{":
                    if depth == 0:
                        m = re.search(r"(\w+)\s*\([^{};]*\)[\s\w()]*$", head)
                        kw = re.match(r"\s*(typedef|struct|enum|union|extern)\b", head)
                        if re.search(r"extern\s*\"\"\s*$", head):
                            head = ""
                            continue  # extern "C" { ... } holds functions
                        name = m.group(1) if m and not kw and "=" not in head else None
                        start = head_line
                    depth += 1
                    head = ""
                elif ch == "}":
                    depth -= 1
                    if depth == 0 and name:
                        if k - start + 1 > limit:
                            out.append("%s:%d: %s: %d lines" % (path, start, name, k - start + 1))
                        name = None
                    head = ""
                elif ch == ";" and depth == 0:
                    head = ""
                elif depth == 0:
                    if not head.strip() and not ch.isspace():
                        head_line = k
                    head += ch
            if depth == 0:
                head += "\n"
    return out


def main(argv):
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    limit = None
    i = 0
    while i < len(argv):
        a = argv[i]
        if a in ("-h", "--help"):
            print(__doc__.strip())
            return 0
        if a == "--root" and i + 1 < len(argv):
            root = argv[i + 1]
        elif a == "--long" and i + 1 < len(argv):
            if not re.fullmatch(r"[0-9]+", argv[i + 1]) or int(argv[i + 1]) < 1:
                usage("--long: expected a line count >= 1, got '%s'" % argv[i + 1])
            limit = int(argv[i + 1])
        else:
            usage("%s: unknown option or missing value" % a)
        i += 2
    if not os.path.isdir(root):
        usage("--root: %s is not a folder" % root)
    if not any(os.path.isdir(os.path.join(root, t)) for t in TOPS):
        usage("%s holds none of %s" % (root, ", ".join(t + "/" for t in TOPS)))
    out = long_functions(root, limit) if limit else check(root)
    for line in out:
        print(line)
    return 1 if out else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
