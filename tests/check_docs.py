#!/usr/bin/env python3
"""The documentation against the tree (issue 35): run as the `docs` test.

Usage: check_docs.py FRONTDT SOURCE_ROOT BUILD_ROOT

1. Every long option (--xxx) that `FRONTDT --help` prints appears in the
   man page doc/frontdt.1 (written there as \\-\\-xxx). --help is read at
   test time, so a new option fails the test until the man page has it.
2. Every path that README.md, doc/*.md and the READMEs under src/ name in
   backticks exists: a path starting with src/, tests/, scripts/, bench/,
   doc/, include/ or python/ in the source tree; one starting with build/
   in the build tree, or as a target the source's meson.build of that
   folder names (so an optional peer not built here still counts). Only
   the first word of a backtick span is a path (`tests/x.sh ARGS`); an
   all-capitals word in it that does not exist is a placeholder
   (`tests/test_MODULE.c` is checked as tests/test_*.c). In a README
   under src/, a path may also start at src/ (`geom/kdtree.c`).
3. Every apex search of the table (src/front/search.c), read at test time
   from the names `FRONTDT --search ''` refuses the value with, is named
   where the searches are listed by hand: the --search entry of
   doc/frontdt.1 (as .B NAME), the `--search a|b|c` of doc/reference.md
   and the search= text of delaunay's docstring in
   python/frontdt/_frontdt.c ('NAME'). So a new row fails the test until
   those say what it is.
Exit 0 when all hold, 1 otherwise (each problem printed).
"""
import glob
import os
import re
import subprocess
import sys

PREFIXES = ("src/", "tests/", "scripts/", "bench/", "doc/", "include/", "python/", "build/")
LAYERS = ("base/", "geom/", "mesh/", "front/", "par/", "api/", "io/", "mpi/", "cli/")
# Paths under build/ made by a script rather than by meson.
BUILD_MADE_BY_SCRIPTS = {
    "build/peers": "bench/run --peers-dir (its default)",
}


def help_options(frontdt):
    out = subprocess.run([frontdt, "--help"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                         check=False, universal_newlines=True).stdout
    opts = sorted(set(re.findall(r"(?<![\w-])--[a-z][a-z0-9-]*", out)))
    return opts, out


def check_man(frontdt, root):
    problems = []
    opts, text = help_options(frontdt)
    if len(opts) < 10:
        return ["frontdt --help printed %d long options (expected many):\n%s" % (len(opts), text)]
    man_path = os.path.join(root, "doc", "frontdt.1")
    with open(man_path, encoding="utf-8") as f:
        man = f.read().replace("\\-", "-").replace("\\(hy", "-")
    for o in opts:
        if not re.search(r"(?<![\w-])" + re.escape(o) + r"(?![\w-])", man):
            problems.append("doc/frontdt.1 does not mention %s (printed by frontdt --help)" % o)
    print("docs: %d long options of --help, %d missing from doc/frontdt.1"
          % (len(opts), len(problems)))
    return problems


def search_names(frontdt):
    """The table's names, from the usage message "unknown search '' (auto, kd or mesh)"."""
    out = subprocess.run([frontdt, "--search", ""], stdout=subprocess.PIPE,
                         stderr=subprocess.STDOUT, check=False, universal_newlines=True).stdout
    m = re.search(r"unknown search '' \(([^)]*)\)", out)
    return re.split(r", | or ", m.group(1)) if m else [], out


def check_searches(frontdt, root):
    names, out = search_names(frontdt)
    if not names:
        return ["frontdt --search '' did not list the searches:\n%s" % out]

    def read(rel):
        with open(os.path.join(root, rel), encoding="utf-8") as f:
            return f.read()

    problems = []
    man = re.search(r"^\.BI \\-\\-search .*?(?=^\.TP)", read("doc/frontdt.1"), re.S | re.M)
    ref = re.search(r"`--search ([^`]*)`", read("doc/reference.md"))
    py = re.search(r"search: (.*?) \(as the", read("python/frontdt/_frontdt.c"), re.S)
    places = [("doc/frontdt.1's --search entry", man and man.group(0), r"^\.B %s$"),
              ("doc/reference.md's `--search ...`", ref and "|" + ref.group(1) + "|", r"\|%s\|"),
              ("delaunay's search= docstring", py and py.group(1), r"'%s'")]
    for where, text, pattern in places:
        if not text:
            problems.append("%s not found" % where)
            continue
        for name in names:
            if not re.search(pattern % re.escape(name), text, re.M):
                problems.append("%s does not name the search %s" % (where, name))
    print("docs: %d searches, %d places that list them by hand, %d missing"
          % (len(names), len(places), len(problems)))
    return problems


def named_in_meson(root, rel):
    """build/DIR/NAME: the source's DIR/meson.build names NAME in quotes."""
    d, name = os.path.split(rel)
    mb = os.path.join(root, d, "meson.build")
    if not name or not os.path.isfile(mb):
        return False
    with open(mb, encoding="utf-8") as f:
        return re.search(r"['\"]%s['\"]" % re.escape(name), f.read()) is not None


def exists(root, build, path):
    path = path.rstrip("/")
    if path.startswith("build/") or path == "build":
        rel = path[len("build/"):] if path != "build" else ""
        if path in BUILD_MADE_BY_SCRIPTS or os.path.exists(os.path.join(build, rel)):
            return True
        return named_in_meson(root, rel)
    if os.path.exists(os.path.join(root, path)):
        return True
    pattern = re.sub(r"(?<![a-z])[A-Z]+(?![a-z])", "*", path)
    if pattern != path or any(c in path for c in "*?["):
        return bool(glob.glob(os.path.join(root, pattern)))
    return False


def paths_in(md_path, in_src):
    with open(md_path, encoding="utf-8") as f:
        text = f.read()
    # Fenced code blocks are programs, not paths named in the text.
    text = re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)
    for span in re.findall(r"`([^`\n]+)`", text):
        words = span.split()
        if not words:
            continue
        word = words[0].rstrip(",.;:)")
        word = re.sub(r":\d+$", "", word)
        if word.startswith("./"):
            word = word[2:]
        if word.startswith(PREFIXES) or word == "build/":
            yield word, word
        elif in_src and word.startswith(LAYERS):
            yield word, "src/" + word


def check_paths(root, build):
    docs = [os.path.join(root, "README.md")]
    docs += sorted(glob.glob(os.path.join(root, "doc", "*.md")))
    docs += sorted(glob.glob(os.path.join(root, "src", "**", "README.md"), recursive=True))
    problems, n = [], 0
    for md in docs:
        rel_md = os.path.relpath(md, root)
        in_src = rel_md.startswith("src" + os.sep)
        for shown, path in paths_in(md, in_src):
            n += 1
            if not exists(root, build, path):
                where = " (%s)" % path if path != shown else ""
                problems.append("%s names `%s`%s, which does not exist" % (rel_md, shown, where))
    print("docs: %d paths named in %d documents, %d missing" % (n, len(docs), len(problems)))
    return problems


def main(argv):
    if len(argv) != 4:
        print("usage: check_docs.py FRONTDT SOURCE_ROOT BUILD_ROOT", file=sys.stderr)
        return 2
    frontdt, root, build = argv[1:]
    problems = check_man(frontdt, root) + check_paths(root, build) + check_searches(frontdt, root)
    for p in problems:
        print("FAIL: " + p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
