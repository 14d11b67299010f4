#!/usr/bin/env python3
"""frontdt.voronoi against scipy's way to cell volumes (issue 32's Python target).

Usage: PYTHONPATH=build/python python3 bench/voronoi_scipy.py [--sizes 1e4,1e5]
                                                             [--reps 3] [--threads 1]

scipy has no cell volumes (scipy #7604 was closed with "use ConvexHull per
cell"): its way is scipy.spatial.Voronoi, then a ConvexHull of each bounded
region's vertices. Here, for uniform points in the unit cube (seed 1), both
are timed (wall, alternated, medians of --reps), the volumes compared on the
cells both have (scipy's bounded regions whose vertices lie inside the box:
those frontdt leaves unclipped) and the ratio printed. Needs numpy and scipy
(Debian python3-scipy) for the Python that runs it.
"""
import argparse
import statistics
import time

import numpy as np
from scipy.spatial import ConvexHull, Voronoi

import frontdt


def scipy_volumes(pts):
    vor = Voronoi(pts)
    vol = np.full(len(pts), np.nan)
    for i, r in enumerate(vor.point_region):
        region = vor.regions[r]
        if not region or -1 in region:
            continue
        vol[i] = ConvexHull(vor.vertices[region]).volume
    return vol, vor


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", default="1e4,1e5")
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--threads", type=int, default=1)
    a = ap.parse_args()
    print("%8s %3s  %10s %10s  %7s  %s" % ("points", "t", "frontdt_s", "scipy_s", "ratio",
                                           "worst relative difference (cells compared)"))
    for size in a.sizes.split(","):
        n = int(float(size))
        pts = np.random.default_rng(1).random((n, 3))
        box = (0.0, 0.0, 0.0, 1.0, 1.0, 1.0)
        fd, sp = [], []
        for _ in range(a.reps):
            t0 = time.monotonic()
            cells = frontdt.voronoi(pts, box=box, threads=a.threads)
            fd.append(time.monotonic() - t0)
            t0 = time.monotonic()
            svol, vor = scipy_volumes(pts)
            sp.append(time.monotonic() - t0)
        vol = cells["volumes"]
        inside = ~np.isnan(svol)
        for i in np.nonzero(inside)[0]:
            v = vor.vertices[vor.regions[vor.point_region[i]]]
            if v.min() < 0 or v.max() > 1:
                inside[i] = False
        worst = float(np.max(np.abs(vol[inside] / svol[inside] - 1))) if inside.any() else 0.0
        f, s = statistics.median(fd), statistics.median(sp)
        print("%8d %3d  %10.3f %10.3f  %7.1f  %.1e (%d)" % (n, a.threads, f, s, s / f, worst,
                                                          int(inside.sum())), flush=True)


if __name__ == "__main__":
    main()
