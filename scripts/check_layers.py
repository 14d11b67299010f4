#!/usr/bin/env python3
"""Checks that the includes of src/ point down the layers and form no circle.

Usage: scripts/check_layers.py [SOURCE_ROOT]   (default: the script's ../)

Every `#include "..."` of src/**/*.c and src/**/*.h is resolved (from src/,
then beside the including file, then include/) and checked twice:

  up      the including file's layer may not include the included file's
          layer (the ALLOWED table below);
  circle  a module include edge inside a circle. A module is NAME.c plus
          NAME.h in one folder (a header alone is a module too); the module
          graph's strongly connected components of more than one module are
          the circles, and every edge between two modules of one component
          is reported, so breaking a circle only ever removes lines.

Exit status: 0 when there is no violation, 1 when there is one (each is
printed), 2 on a usage error. Python 3 standard library only; run by
`meson test layers`. (The last of the debts the folder move found, issue 35,
were paid in November 2026: there is no list of allowed exceptions.)
"""
import os
import re
import sys

# Layer folders under src/, and which layers each may include (besides
# itself). include/frontdt.h, the public header, may be included anywhere.
# Order, top to bottom: cli -> mpi -> api -> par -> front -> mesh -> geom ->
# base; io/write -> io/read sit beside, above mesh (callers: cli, mpi).
ALLOWED = {
    "cli":      ["mpi", "api", "par", "front", "mesh", "geom", "base", "io/write", "io/read"],
    "mpi":      ["api", "par", "front", "mesh", "geom", "base", "io/write", "io/read"],
    "api":      ["par", "front", "mesh", "geom", "base"],
    "par":      ["front", "mesh", "geom", "base"],
    "front":    ["mesh", "geom", "base"],
    "mesh":     ["geom", "base"],
    "geom":     ["base"],
    "base":     [],
    "io/write": ["io/read", "mesh", "geom", "base"],
    "io/read":  ["mesh", "geom", "base"],
}
PUBLIC = "include/frontdt.h"
INCLUDE_RE = re.compile(r'^\s*#\s*include\s*"([^"]+)"', re.M)


def layer_of(path):
    """The layer of a src/-relative path: its longest ALLOWED folder prefix."""
    best = None
    for layer in ALLOWED:
        if path.startswith(layer + "/") and (best is None or len(layer) > len(best)):
            best = layer
    return best


def module_of(path):
    """src/-relative file -> module name (folder/NAME without extension)."""
    return os.path.splitext(path)[0]


def strip_comments(text):
    # An #include inside a /* */ or // comment is no include.
    text = re.sub(r"/\*.*?\*/", lambda m: "\n" * m.group(0).count("\n"), text, flags=re.S)
    return re.sub(r"//[^\n]*", "", text)


def scan(root):
    """Returns (edges, problems): edges as (from, to) src/-relative paths
    (to is PUBLIC for the public header), problems as violation lines."""
    src = os.path.join(root, "src")
    files = []
    for dirpath, _, names in os.walk(src):
        for n in names:
            if n.endswith((".c", ".h")):
                files.append(os.path.relpath(os.path.join(dirpath, n), src).replace(os.sep, "/"))
    files.sort()
    edges, problems = [], []
    for f in files:
        with open(os.path.join(src, f), encoding="utf-8", errors="replace") as fh:
            text = strip_comments(fh.read())
        if layer_of(f) is None:
            problems.append("nolayer %s" % f)
        for inc in INCLUDE_RE.findall(text):
            beside = os.path.normpath(os.path.join(os.path.dirname(f), inc)).replace(os.sep, "/")
            if os.path.isfile(os.path.join(src, inc)):
                edges.append((f, os.path.normpath(inc).replace(os.sep, "/")))
            elif os.path.isfile(os.path.join(src, beside)):
                edges.append((f, beside))
            elif os.path.isfile(os.path.join(root, "include", inc)) and "include/" + inc == PUBLIC:
                edges.append((f, PUBLIC))
            else:
                problems.append("unresolved %s -> %s" % (f, inc))
    return edges, problems


def up_edges(edges):
    out = []
    for a, b in edges:
        if b == PUBLIC:
            continue
        la, lb = layer_of(a), layer_of(b)
        if la is None or lb is None or la == lb:
            continue
        if lb not in ALLOWED[la]:
            out.append("up %s -> %s" % (a, b))
    return out


def sccs(nodes, succ):
    """Tarjan's strongly connected components, iteratively."""
    index, low, on, stack, comps = {}, {}, set(), [], []
    counter = [0]
    for root in sorted(nodes):
        if root in index:
            continue
        work = [(root, iter(sorted(succ.get(root, ()))))]
        index[root] = low[root] = counter[0]
        counter[0] += 1
        stack.append(root)
        on.add(root)
        while work:
            v, it = work[-1]
            w = next(it, None)
            if w is not None:
                if w not in index:
                    index[w] = low[w] = counter[0]
                    counter[0] += 1
                    stack.append(w)
                    on.add(w)
                    work.append((w, iter(sorted(succ.get(w, ())))))
                elif w in on:
                    low[v] = min(low[v], index[w])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[v])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                comps.append(sorted(comp))
    return comps


def circle_edges(edges):
    succ, nodes = {}, set()
    for a, b in edges:
        if b == PUBLIC:
            continue
        ma, mb = module_of(a), module_of(b)
        nodes.update((ma, mb))
        if ma != mb:
            succ.setdefault(ma, set()).add(mb)
    comps = [c for c in sccs(nodes, succ) if len(c) > 1]
    out = []
    for comp in comps:
        members = set(comp)
        for a in comp:
            for b in sorted(succ.get(a, ())):
                if b in members:
                    out.append("circle %s -> %s" % (a, b))
    return out, comps


def main(argv):
    if len(argv) > 2:
        print(__doc__.strip().splitlines()[2], file=sys.stderr)
        return 2
    root = argv[1] if len(argv) == 2 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
    if not os.path.isdir(os.path.join(root, "src")):
        print("check_layers: no src/ under %s" % root, file=sys.stderr)
        return 2
    edges, problems = scan(root)
    circles, comps = circle_edges(edges)
    found = problems + up_edges(edges) + circles

    print("check_layers: %d include edges, %d violations, %d circles"
          % (len(edges), len(found), len(comps)))
    for comp in comps:
        print("  circle among: %s" % " ".join(comp))
    for v in found:
        print("violation: %s" % v)
    if found:
        print("check_layers: %d violation(s). Includes point down the layers "
              "(the ALLOWED table of scripts/check_layers.py) and form no circle; "
              "move the code, or split the header." % len(found))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
