#!/usr/bin/env python3
"""Voronoi cells: frontdt against voro++ (issue 32; bench/NOTES.md entry 92).

Usage: bench/voronoi.py [--frontdt build/frontdt] [--gen build/tests/gen_points]
                        [--sizes 1e5,1e6] [--families uniform,gaussian]
                        [--threads 1,2] [--reps 3] [--format FMT]

For each family and size: the points in a box 1 % larger than their bounding
box, then, alternated, `frontdt IN --box B --voronoi OUT --voronoi-format FMT
-t N` (its --stats-json times: the triangulation, the cells with their
writing, and the whole wall time) and Debian's voro++ command (`voro++ -o -c
FMT` on the same box: its wall time, the cells and their writing; voro++ runs
on one thread). Prints medians of --reps runs and the ratios. The default
FMT, '%i %v %F %s %n %f', is one both programs write (frontdt with 17 digits,
voro++ with 6). Needs the voro++ package (scripts/bootstrap.sh installs
voro++-dev, which brings the library; `apt install voro++` the command).
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import tempfile
import time


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--frontdt", default="build/frontdt")
    ap.add_argument("--gen", default="build/tests/gen_points")
    ap.add_argument("--sizes", default="1e5,1e6")
    ap.add_argument("--families", default="uniform,gaussian")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--format", default="%i %v %F %s %n %f")
    a = ap.parse_args()
    voro = shutil.which("voro++")
    if not voro:
        raise SystemExit("bench/voronoi.py: no voro++ command (apt install voro++)")
    tmp = tempfile.mkdtemp(prefix="fdt-voronoi-")
    print("%-9s %8s %3s  %8s %8s %8s  %8s  %s" % ("family", "points", "t", "tri_s", "cells_s",
                                                  "wall_s", "voro++_s", "wall ratio"))
    for fam in a.families.split(","):
        for size in a.sizes.split(","):
            n = int(float(size))
            pts = os.path.join(tmp, "%s.xyz" % fam)
            subprocess.run([a.gen, fam, str(n), "1", pts], check=True)
            xyz = [l.split()[:3] for l in open(pts) if l.strip() and not l[0].isalpha()]
            lo = [min(float(p[k]) for p in xyz) for k in range(3)]
            hi = [max(float(p[k]) for p in xyz) for k in range(3)]
            ext = [h - l for l, h in zip(lo, hi)]
            lo = [l - 0.01 * e for l, e in zip(lo, ext)]
            hi = [h + 0.01 * e for h, e in zip(hi, ext)]
            box = ",".join("%.17g" % b for b in lo + hi)
            vin = os.path.join(tmp, "voro_in")
            with open(vin, "w") as f:
                for i, p in enumerate(xyz):
                    f.write("%d %s %s %s\n" % (i, p[0], p[1], p[2]))
            vargs = [voro, "-o", "-c", a.format]
            for k in range(3):
                vargs += ["%.17g" % lo[k], "%.17g" % hi[k]]
            vargs.append(vin)
            for t in a.threads.split(","):
                fd, vo, ft = [], [], []
                for _ in range(a.reps):
                    out = os.path.join(tmp, "cells.txt")
                    js = os.path.join(tmp, "stats.json")
                    t0 = time.monotonic()
                    subprocess.run([a.frontdt, pts, "-q", "-t", t, "--box", box, "--voronoi", out,
                                    "--voronoi-format", a.format, "--stats-json", js], check=True)
                    wall = time.monotonic() - t0
                    st = json.load(open(js))
                    fd.append((st["t_triangulate"], st["t_voronoi"], wall))
                    t0 = time.monotonic()
                    subprocess.run(vargs, check=True)
                    vo.append(time.monotonic() - t0)
                tri = statistics.median(x[0] for x in fd)
                cel = statistics.median(x[1] for x in fd)
                wall = statistics.median(x[2] for x in fd)
                v = statistics.median(vo)
                print("%-9s %8d %3s  %8.3f %8.3f %8.3f  %8.3f  %.2f" % (fam, n, t, tri, cel, wall,
                                                                      v, wall / v), flush=True)
    shutil.rmtree(tmp)


if __name__ == "__main__":
    main()
