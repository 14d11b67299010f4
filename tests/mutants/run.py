#!/usr/bin/env python3
"""Mutation check of the tests (issue 20).

Applies each mutant of tests/mutants/mutants.txt, one at a time, to a
scratch copy of the source tree (never to the checkout: the copy lives in a
temporary directory removed at the end, also on Ctrl-C or SIGTERM), builds
it, runs a fast subset of the default suite and reports whether some test
failed (killed) or all passed (survived). A mutant whose text is not found
(the code moved) is reported as stale, one that does not compile as
build-failed; both make the run fail, as does a surviving mutant not marked
equivalent in the list.

usage: tests/mutants/run.py [--only NAME,...] [--tests T,...] [--markdown FILE]
                            [--jobs N] [--keep]
  --tests     the meson tests to run per mutant (default: TESTS below)
  --markdown  also write the result table to FILE
  --keep      keep the scratch tree (its path is printed)

The subset (TESTS) holds the unit tests of the mutated modules and the
engine tests, about 40 s a mutant on a loaded 2-core machine; a hang is
cut by meson's timeout at TIMEOUT_MULT times each test's own.
"""
import argparse
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
TESTS = ["predicates", "kdtree", "seed", "front", "check", "api", "partition",
         "parallel", "insert"]
TIMEOUT_MULT = "0.25"  # parallel: 600 s -> 150 s before a hang counts as killed
SETUP = ["--buildtype=release", "-Denable_bench=false", "-Denable_cgal=disabled",
         "-Denable_tetgen=disabled"]


def parse(path):
    """The records of mutants.txt as dicts (old/new with \\n expanded)."""
    recs = []
    for block in open(path).read().split("\n\n"):
        d = {}
        for line in block.split("\n"):
            if not line.strip() or line.startswith("#"):
                continue
            key, sep, val = line.partition(": ")
            if not sep:
                sys.exit("%s: malformed line: %r" % (path, line))
            d[key] = val
        if not d:
            continue
        for k in ("name", "file", "old", "new", "why"):
            if k not in d:
                sys.exit("%s: record %r lacks %s" % (path, d.get("name"), k))
        d["old"] = d["old"].replace("\\n", "\n")
        d["new"] = d["new"].replace("\\n", "\n")
        recs.append(d)
    return recs


def source_files():
    """Tracked and untracked-but-not-ignored files: the tree as it is."""
    out = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
                         cwd=ROOT, capture_output=True, check=True).stdout
    return [f for f in out.decode().split("\0") if f and os.path.isfile(os.path.join(ROOT, f))]


def copy_tree(dst):
    for f in source_files():
        d = os.path.join(dst, f)
        os.makedirs(os.path.dirname(d), exist_ok=True)
        shutil.copy2(os.path.join(ROOT, f), d)


def sh(cmd, cwd, timeout=None):
    return subprocess.run(cmd, cwd=cwd, capture_output=True, text=True, timeout=timeout)


def run_tests(build, tests, jobs):
    """Names of the tests that failed (or timed out)."""
    env = dict(os.environ, MESON_TESTTHREADS=str(jobs))
    r = subprocess.run(["nice", "-n", "15", "meson", "test", "-C", build, "--no-rebuild",
                        "--timeout-multiplier", TIMEOUT_MULT, "--print-errorlogs"] + tests,
                       capture_output=True, text=True, env=env)
    failed = []
    for line in r.stdout.splitlines():
        parts = line.split()
        # "N/M frontdt:SUITE / NAME   FAIL   1.2s   exit status 1"
        if len(parts) >= 5 and "/" in parts[0] and parts[2] == "/":
            item = "%s (%s)" % (parts[3], parts[4])
            # (--print-errorlogs lists each failure again at the end)
            if parts[4] not in ("OK", "SKIP", "EXPECTEDFAIL") and item not in failed:
                failed.append(item)
    if r.returncode != 0 and not failed:
        failed.append("meson test exit %d" % r.returncode)
    return failed


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--only", default=None)
    ap.add_argument("--tests", default=",".join(TESTS))
    ap.add_argument("--markdown", default=None)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--keep", action="store_true")
    a = ap.parse_args()
    muts = parse(os.path.join(HERE, "mutants.txt"))
    if a.only:
        want = set(a.only.split(","))
        muts = [m for m in muts if m["name"] in want]
    tests = a.tests.split(",")

    # SIGTERM (meson's timeout, a CI cancel) unwinds like Ctrl-C, so the
    # finally below removes the scratch tree.
    def on_term(signum, frame):
        raise KeyboardInterrupt
    signal.signal(signal.SIGTERM, on_term)

    scratch = tempfile.mkdtemp(prefix="fdt-mutants-")
    rows, bad = [], 0
    t_start = time.time()
    try:
        src = os.path.join(scratch, "src-tree")
        copy_tree(src)
        build = os.path.join(src, "build")
        r = sh(["nice", "-n", "15", "meson", "setup", build] + SETUP, src)
        if r.returncode:
            sys.exit("meson setup failed:\n" + r.stdout[-3000:] + r.stderr[-3000:])
        r = sh(["nice", "-n", "15", "ninja", "-C", build, "-j%d" % a.jobs], src)
        if r.returncode:
            sys.exit("the unmutated tree does not build:\n" + r.stdout[-3000:])
        failed = run_tests(build, tests, a.jobs)
        if failed:
            sys.exit("the unmutated tree fails: %s" % ", ".join(failed))
        print("baseline: %s pass (%.0f s)" % (", ".join(tests), time.time() - t_start),
              flush=True)
        for m in muts:
            t0 = time.time()
            path = os.path.join(src, m["file"])
            orig = open(path).read()
            n = orig.count(m["old"])
            if n != 1:
                result, detail = "STALE", "the text occurs %d times in %s" % (n, m["file"])
            else:
                try:
                    open(path, "w").write(orig.replace(m["old"], m["new"]))
                    r = sh(["nice", "-n", "15", "ninja", "-C", build, "-j%d" % a.jobs], src)
                    if r.returncode:
                        result, detail = "BUILD-FAILED", r.stdout[-300:].replace("\n", " ")
                    else:
                        failed = run_tests(build, tests, a.jobs)
                        if failed:
                            result, detail = "killed", ", ".join(failed)
                        elif "equivalent" in m:
                            result, detail = "equivalent", m["equivalent"]
                        else:
                            result, detail = "SURVIVED", "every test passed"
                finally:
                    open(path, "w").write(orig)
            if result not in ("killed", "equivalent"):
                bad += 1
            dt = time.time() - t0
            rows.append((m["name"], m["file"], result, detail, dt))
            print("%-24s %-18s %-12s %5.0f s  %s" % (m["name"], m["file"], result, dt, detail),
                  flush=True)
        # The restored sources build again (the last mutant undone).
        sh(["nice", "-n", "15", "ninja", "-C", build, "-j%d" % a.jobs], src)
    except KeyboardInterrupt:
        print("interrupted: scratch tree removed, the checkout was never touched",
              file=sys.stderr)
        return 130
    finally:
        if a.keep:
            print("scratch tree kept: %s" % scratch)
        else:
            shutil.rmtree(scratch, ignore_errors=True)

    killed = sum(1 for r in rows if r[2] == "killed")
    summary = "%d mutants: %d killed, %d equivalent, %d not killed (%.0f s)" % (
        len(rows), killed, sum(1 for r in rows if r[2] == "equivalent"), bad,
        time.time() - t_start)
    print(summary)
    if a.markdown:
        with open(a.markdown, "w") as f:
            f.write("| mutant | file | result | failing tests / reason | s |\n")
            f.write("|---|---|---|---|---|\n")
            for name, fl, res, det, dt in rows:
                f.write("| %s | %s | %s | %s | %.0f |\n" % (name, fl, res,
                                                          det.replace("|", "\\|"), dt))
            f.write("\n%s\n" % summary)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
