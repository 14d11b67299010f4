#!/usr/bin/env python3
"""End-to-end checks of the Voronoi cells (issue 32) through the CLI.

Usage: voronoi_voro.py FRONTDT GEN_POINTS VORO_REF|none SCRATCH

1. Against voro++ (tests/voro_ref.cpp, Debian's libvoro++): for uniform,
   clustered (gaussian), lattice, rotated and skewed lattice and cylinder
   points in a box 1 % larger than their bounding box, every cell's volume,
   surface area and centroid, and every face's area, agree to 1e-10 of
   the cell's size (volume, area, cube root of the volume); the
   neighbour lists are equal but for faces of area at most 1e-10 of their
   cell's surface on either side (zero-area faces of degenerate points:
   counted and printed); the volumes add up to the box's to 1e-12.
2. The same bytes from --voronoi at 1 and 3 threads and in message mode,
   and, row for row, for a shuffled input.
3. DTFE: --density equals 4 / (the sum of the volumes of each point's tets)
   computed here from the .tets output, to 1e-12.
4. Refusals: --box not holding every point (exit 1, the point named),
   --voronoi-format with a bad code, --voronoi with --stream.
5. --voronoi cells.vtu: VTK polyhedra read back with VTK (python3-vtk9):
   one VTK_POLYHEDRON a point, the volume of each from its faces (the
   divergence theorem) equal to its "volume" to 1e-10, which is --voronoi's
   %v (skipped without VTK's Python module).
6. Interpolation (--values, --interpolate, --interpolated, --method): a
   linear function reproduced by both methods to 1e-12, nan outside the
   hull; a malformed values file (exit 2, file and line named), an output
   that is the input or a missing partner option (exit 1).
"""
import math
import os
import random
import subprocess
import sys

from vtk_cells import read_polyhedra

FRONTDT, GEN, VORO, SCRATCH = sys.argv[1:5]
os.makedirs(SCRATCH, exist_ok=True)
FMT = "%i %v %F %s %C %h|%n|%f"
failures = []


def fail(msg):
    failures.append(msg)
    if len(failures) <= 30:
        print("FAIL:", msg)


def run(args, **kw):
    return subprocess.run([FRONTDT] + args, capture_output=True, text=True, **kw)


def read_xyz(path):
    pts = []
    for line in open(path):
        f = line.split()
        if len(f) >= 3 and not f[0][0].isalpha():
            pts.append(tuple(float(x) for x in f[:3]))
    return pts


def write_xyz(path, pts):
    with open(path, "w") as f:
        for p in pts:
            f.write("%.17g %.17g %.17g\n" % p)


def box_of(pts):
    lo = [min(p[k] for p in pts) for k in range(3)]
    hi = [max(p[k] for p in pts) for k in range(3)]
    ext = [h - l for l, h in zip(lo, hi)]
    return [l - 0.01 * e for l, e in zip(lo, ext)] + [h + 0.01 * e for h, e in zip(hi, ext)]


def cells(path, box, extra=()):
    out = os.path.join(SCRATCH, "cells.txt")
    r = run([path, "-q", "--box", ",".join("%.17g" % b for b in box), "--voronoi", out,
             "--voronoi-format", FMT] + list(extra))
    if r.returncode != 0:
        fail("frontdt %s: exit %d: %s" % (path, r.returncode, r.stderr.strip()))
        return None
    return open(out).read()


def parse_mine(text):
    rows = []
    for line in text.splitlines():
        head, nb, ar = line.split("|")
        h = head.split()
        rows.append({"v": float(h[1]), "F": float(h[2]), "s": int(h[3]),
                     "C": [float(x) for x in h[4:7]], "flags": int(h[7]),
                     "faces": dict(zip(map(int, nb.split()), map(float, ar.split())))})
    return rows


def parse_ref(text):
    rows = []
    for line in text.splitlines():
        if "|" not in line:
            rows.append(None)
            continue
        head, rest = line.split("|")
        h, r = head.split(), rest.split()
        rows.append({"v": float(h[1]), "F": float(h[2]), "C": [float(x) for x in h[4:7]],
                     "faces": dict(zip(map(int, r[0::2]), map(float, r[1::2])))})
    return rows


def against_voro(family, n, path=None):
    """The cells of gen_points FAMILY N (or the points of path) against
    voro++'s."""
    if path is None:
        path = os.path.join(SCRATCH, family + ".xyz")
        subprocess.run([GEN, family, str(n), "1", path], check=True)
    pts = read_xyz(path)
    box = box_of(pts)
    text = cells(path, box)
    if text is None:
        return
    mine = parse_mine(text)
    ref = parse_ref(subprocess.run([VORO, ",".join("%.17g" % b for b in box)],
                                   input="".join("%.17g %.17g %.17g\n" % p for p in pts),
                                   capture_output=True, text=True, check=True).stdout)
    worst = [0.0] * 4
    zero = compared = 0
    total = 0.0
    for i, (m, r) in enumerate(zip(mine, ref)):
        total += m["v"]
        if m["flags"] & 4 or r is None:
            continue
        compared += 1
        scale = r["v"] ** (1.0 / 3)
        errs = [abs(m["v"] - r["v"]) / r["v"], abs(m["F"] - r["F"]) / r["F"],
                max(abs(a - b) for a, b in zip(m["C"], r["C"])) / scale, 0.0]
        real_r = {k: a for k, a in r["faces"].items() if a > 1e-10 * r["F"]}
        real_m = {k: a for k, a in m["faces"].items() if a > 1e-10 * m["F"]}
        zero += len(r["faces"]) - len(real_r) + len(m["faces"]) - len(real_m)
        if set(real_r) != set(real_m):
            fail("%s point %d: neighbours differ from voro++'s: %s" %
                 (family, i, sorted(set(real_r) ^ set(real_m))))
        else:
            errs[3] = max([abs(real_r[k] - real_m[k]) / r["F"] for k in real_r] + [0.0])
        if m["s"] != len(m["faces"]):
            fail("%s point %d: %%s %d but %d neighbours" % (family, i, m["s"], len(m["faces"])))
        for k in range(4):
            worst[k] = max(worst[k], errs[k])
    bvol = (box[3] - box[0]) * (box[4] - box[1]) * (box[5] - box[2])
    print("%-12s %6d points: %d cells compared with voro++; worst relative differences: volume "
          "%.1e, area %.1e, centroid %.1e, face %.1e; zero-area faces excepted %d; volumes add "
          "to the box's %+.1e" % (family, n, compared, worst[0], worst[1], worst[2], worst[3],
                                  zero, total / bvol - 1))
    if compared < len(pts) * 0.9:
        fail("%s: only %d of %d cells compared" % (family, compared, len(pts)))
    if max(worst) > 1e-10:
        fail("%s: a difference over 1e-10: %s" % (family, worst))
    if abs(total / bvol - 1) > 1e-12:
        fail("%s: the volumes add up to %.17g, the box holds %.17g" % (family, total, bvol))


def same_bits():
    path = os.path.join(SCRATCH, "bits.xyz")
    # more rows than a block of the threaded text (src/io/write/cells.c)
    subprocess.run([GEN, "clusters", "12000", "5", path], check=True)
    pts = read_xyz(path)
    box = box_of(pts)
    base = cells(path, box, ["-t", "1"])
    for extra in (["-t", "3"], ["-t", "2", "--mode", "message"], ["-t", "2", "--mode", "shared"],
                  ["--stream", "-t", "1"], ["--stream", "-t", "3"]):
        if cells(path, box, extra) != base:
            fail("--voronoi differs between -t 1 and %s" % " ".join(extra))
    perm = list(range(len(pts)))
    random.Random(3).shuffle(perm)
    spath = os.path.join(SCRATCH, "shuffled.xyz")
    write_xyz(spath, [pts[p] for p in perm])
    shuffled = cells(spath, box, ["-t", "2"])
    if base is None or shuffled is None:
        return
    rows = base.splitlines()
    differ = 0
    for j, line in enumerate(shuffled.splitlines()):
        # The values but the id and the neighbour ids (renumbered).
        a = rows[perm[j]].split("|")
        b = line.split("|")
        if a[0].split()[1:] != b[0].split()[1:] or sorted(a[2].split()) != sorted(b[2].split()):
            differ += 1
    if differ:
        fail("%d cells differ for the shuffled input" % differ)
    print("same bits: 1, 3 threads, message and shared modes, streamed, and a shuffled input "
          "(%d points)"
          % len(pts))


def dtfe():
    path = os.path.join(SCRATCH, "dtfe.xyz")
    subprocess.run([GEN, "gaussian", "3000", "2", path], check=True)
    pts = read_xyz(path)
    tets = os.path.join(SCRATCH, "dtfe.tets")
    dens = os.path.join(SCRATCH, "dtfe.txt")
    r = run([path, "-q", "-o", tets, "--density", dens])
    if r.returncode != 0:
        fail("--density: exit %d: %s" % (r.returncode, r.stderr.strip()))
        return
    vol = [0.0] * len(pts)
    for line in open(tets):
        ids = [int(x) for x in line.split()]
        a, b, c, d = (pts[i] for i in ids)
        u = [b[k] - a[k] for k in range(3)]
        v = [c[k] - a[k] for k in range(3)]
        w = [d[k] - a[k] for k in range(3)]
        det = (u[0] * (v[1] * w[2] - v[2] * w[1]) - u[1] * (v[0] * w[2] - v[2] * w[0]) +
               u[2] * (v[0] * w[1] - v[1] * w[0]))
        for i in ids:
            vol[i] += abs(det) / 6
    worst = 0.0
    for i, line in enumerate(open(dens)):
        rho, flags = line.split()
        want = 4 / vol[i]
        worst = max(worst, abs(float(rho) - want) / want)
    print("DTFE: --density against the .tets: worst relative difference %.1e" % worst)
    if worst > 1e-12:
        fail("DTFE densities differ from the .tets' by %.3g" % worst)


def refusals():
    path = os.path.join(SCRATCH, "ref.xyz")
    subprocess.run([GEN, "uniform", "500", "1", path], check=True)
    out = os.path.join(SCRATCH, "never.txt")
    for stale in (out, out[:-4] + ".vtu"):  # an earlier run's failure
        if os.path.exists(stale):
            os.remove(stale)
    cases = [
        (["--box", "0,0,0,1,1,0.5", "--voronoi", out], 1, "outside the box"),
        (["--voronoi", out, "--voronoi-format", "%i %Q"], 1, "'%Q'"),
        (["--voronoi", out[:-4] + ".vtu", "--stream"], 1, "needs the whole mesh"),
        (["--voronoi", out, "--stream", "--search", "kd"], 1, "sweep order"),
        (["--box", "0,0,0,1,1"], 1, "--box wants six"),
        (["--voronoi-format", "%v"], 1, "needs --voronoi"),
    ]
    for args, code, text in cases:
        r = run([path, "-q"] + args)
        if r.returncode != code or text not in r.stderr:
            fail("%s: exit %d (want %d), stderr %r (want %r)" % (args, r.returncode, code,
                                                                  r.stderr.strip(), text))
        for left in (out, out[:-4] + ".vtu"):
            if os.path.exists(left):
                fail("%s left %s" % (args, left))


def formats_and_refusals():
    """Every --voronoi-format code and the CSV on an input with a duplicate;
    --box and output refusals; malformed --values files."""
    path = os.path.join(SCRATCH, "codes.xyz")
    pts = [(0.1 * (i % 5), 0.13 * (i // 5 % 5), 0.17 * (i // 25)) for i in range(125)]
    pts = [(x + 1e-3 * ((7 * i) % 11), y, z) for i, (x, y, z) in enumerate(pts)] + [pts[0]]
    pts[-1] = (pts[0][0] + 1e-3 * 0, pts[0][1], pts[0][2])
    write_xyz(path, pts)
    out = os.path.join(SCRATCH, "codes.txt")
    r = run([path, "-q", "--voronoi", out, "--voronoi-format", "%i|%x|%y|%z|%c|%C|%d|%h|%%",
             "--density", os.path.join(SCRATCH, "codes_d.txt")])
    if r.returncode:
        fail("all codes: exit %d: %s" % (r.returncode, r.stderr.strip()))
    else:
        rows = [line.rstrip("\n").split("|") for line in open(out)]
        last = rows[-1]
        if len(rows) != len(pts) or last[8] != "%" or int(last[7]) != 4 or \
                [float(x) for x in last[4].split()] != [0.0, 0.0, 0.0]:
            fail("all codes: rows %d, last %r" % (len(rows), last))
        first = rows[0]
        cen = [float(x) for x in first[5].split()]
        rel = [float(x) for x in first[4].split()]
        pos = [float(first[k]) for k in (1, 2, 3)]
        if max(abs(c - (p + q)) for c, p, q in zip(cen, pos, rel)) > 1e-12:
            fail("all codes: %%C is not the point plus %%c: %r" % first)
    csv = os.path.join(SCRATCH, "codes.csv")
    r = run([path, "-q", "--voronoi", csv])
    if r.returncode or not open(csv).readline().startswith("id,x,y,z,volume"):
        fail("csv: exit %d" % r.returncode)
    elif len(open(csv).readlines()) != len(pts) + 1:
        fail("csv: %d lines" % len(open(csv).readlines()))
    vals = os.path.join(SCRATCH, "codes_vals.txt")
    qs = os.path.join(SCRATCH, "codes_q.xyz")
    write_xyz(qs, [(0.2, 0.2, 0.2)])
    iout = os.path.join(SCRATCH, "codes_i.txt")
    cases = [
        (["--box", "0,0,0,1,1,x", "--voronoi", out], 1, "--box wants six"),
        (["--box", "0,0,0;1,1,1", "--voronoi", out], 1, "--box wants six"),
        (["--box", "0,0,0,1,1,1"], 1, "needs --voronoi, --density or --dual"),
        (["--voronoi", out, "--density", out], 1, "named for two outputs"),
        (["--voronoi", os.path.join(SCRATCH, "c.vtu"), "--voronoi-format", "%v"], 1,
         "does not apply to a .vtu"),
        (["--voronoi", out, "--voronoi-format", "%v %"], 1, "not a cell code"),
        (["--voronoi", os.path.join(SCRATCH, "no", "such", "dir.txt")], 5, ""),
    ]
    bad_values = [
        ("1 2\n3\n", ":2:"),            # fewer than the first row
        ("1\n2 3\n", ":2:"),            # more than the first row
        ("1\nnan\n", ":2:"),            # not finite
        ("1,\n", "rows of values"),      # too few rows
    ]
    for b, (text, want) in enumerate(bad_values):
        bv = "%s.%d" % (vals, b)
        with open(bv, "w") as f:
            f.write(text)
        cases.append((["--values", bv, "--interpolate", qs, "--interpolated", iout], 2, want))
    many = os.path.join(SCRATCH, "codes_many.txt")
    with open(many, "w") as f:
        f.write("# values\n\n" + "".join("%d, %d\n" % (i, -i) for i in range(len(pts) + 1)))
    cases.append((["--values", many, "--interpolate", qs, "--interpolated", iout], 2,
                  "more rows than points"))
    cases.append((["--values", os.path.join(SCRATCH, "missing.txt"), "--interpolate", qs,
                   "--interpolated", iout], 2, "missing.txt"))
    for args, code, text in cases:
        r = run([path, "-q"] + args)
        if r.returncode != code or text not in r.stderr:
            fail("%s: exit %d (want %d), stderr %r (want %r)" % (args, r.returncode, code,
                                                                  r.stderr.strip(), text))
    good = os.path.join(SCRATCH, "codes_good.txt")
    with open(good, "w") as f:
        f.write("# two values a point, comments, a blank line, commas\n\n" +
                "".join("%r, %r # x and -x\n" % (p[0], -p[0]) for p in pts))
    r = run([path, "-q", "--values", good, "--interpolate", qs, "--interpolated", iout,
             "--method", "linear"])
    got = open(iout).read().split() if r.returncode == 0 else []
    if r.returncode or len(got) != 2 or abs(float(got[0]) - 0.2) > 1e-12:
        fail("values with comments and commas: exit %d, %r" % (r.returncode, got))


def polyhedra():
    path = os.path.join(SCRATCH, "poly.xyz")
    subprocess.run([GEN, "gaussian", "1500", "3", path], check=True)
    vtu = os.path.join(SCRATCH, "cells.vtu")
    txt = os.path.join(SCRATCH, "cells_v.txt")
    r = run([path, "-q", "--voronoi", vtu])
    r2 = run([path, "-q", "--voronoi", txt, "--voronoi-format", "%i %v %h"])
    if r.returncode or r2.returncode:
        fail("--voronoi .vtu: exit %d / %d: %s" % (r.returncode, r2.returncode, r.stderr))
        return
    got = read_polyhedra(vtu)
    if got is None:
        print("polyhedra: no VTK Python module, not read back")
        return
    rows = [line.split() for line in open(txt)]
    want = {int(i): float(v) for i, v, h in rows if not int(h) & 4}
    if len(got) != len(want):
        fail("cells.vtu: %d cells for %d distinct points" % (len(got), len(want)))
        return
    worst = 0.0
    for s, va, v, kind in got:
        if kind != 42:
            fail("cells.vtu: the cell of point %d has type %d" % (s, kind))
            return
        worst = max(worst, abs(v - want[s]) / want[s], abs(va - want[s]) / want[s])
    print("polyhedra: %d VTK polyhedra read back; volumes from their faces against %%v: worst "
          "%.1e" % (len(got), worst))
    if worst > 1e-10:
        fail("cells.vtu: a polyhedron's volume is off by %.3g" % worst)


def interpolation():
    path = os.path.join(SCRATCH, "interp.xyz")
    subprocess.run([GEN, "uniform", "3000", "4", path], check=True)
    pts = read_xyz(path)
    vals = os.path.join(SCRATCH, "vals.txt")
    with open(vals, "w") as f:
        for p in pts:
            f.write("%.17g %.17g\n" % (1 + 2 * p[0] - p[1], p[2]))
    rng = random.Random(9)
    box = box_of(pts)
    qs = [tuple(box[k] + (box[k + 3] - box[k]) * (1.4 * rng.random() - 0.2) for k in range(3))
          for _ in range(500)]
    qpath = os.path.join(SCRATCH, "queries.xyz")
    write_xyz(qpath, qs)
    out = os.path.join(SCRATCH, "interp.txt")
    for method in ("natural", "linear"):
        r = run([path, "-q", "--values", vals, "--interpolate", qpath, "--interpolated", out,
                 "--method", method, "-t", "2"])
        if r.returncode != 0:
            fail("--interpolate %s: exit %d: %s" % (method, r.returncode, r.stderr.strip()))
            continue
        worst, nan = 0.0, 0
        for q, line in zip(qs, open(out)):
            a, b = (float(x) for x in line.split())
            if a != a:
                nan += 1
                continue
            worst = max(worst, abs(a - (1 + 2 * q[0] - q[1])), abs(b - q[2]))
        print("interpolate %s: %d queries, %d outside (nan), worst error %.1e" %
              (method, len(qs), nan, worst))
        if worst > 1e-12 or nan == 0 or nan == len(qs):
            fail("--interpolate %s: worst %.3g, %d nan" % (method, worst, nan))
    bad = os.path.join(SCRATCH, "badvals.txt")
    with open(bad, "w") as f:
        f.write("1 2\n3 x\n")
    cases = [
        (["--values", bad, "--interpolate", qpath, "--interpolated", out], 2, "badvals.txt:2:"),
        (["--values", vals, "--interpolate", qpath, "--interpolated", path], 1, "would overwrite"),
        (["--values", vals, "--interpolate", qpath], 1, "needs all three"),
        (["--values", vals, "--interpolate", qpath, "--interpolated", out, "--method", "cubic"],
         1, "--method"),
    ]
    for args, code, text in cases:
        r = run([path, "-q"] + args)
        if r.returncode != code or text not in r.stderr:
            fail("%s: exit %d (want %d), stderr %r (want %r)" % (args, r.returncode, code,
                                                                  r.stderr.strip(), text))


def hard_families():
    """Families that broke --voronoi (bench/NOTES.md entry 103): sphere12, nearly
    cospherical, made a cut find its cell not convex (exit 7); ulpgrid's
    cells by the box were summed past it, and its polyhedra written with
    vertices rounded by half a cell; tiny and huge, whose cells' volumes
    leave what doubles hold, came out 0 and NaN with exit 0 and must be
    refused (exit 2)."""
    path = os.path.join(SCRATCH, "hard.xyz")
    out = os.path.join(SCRATCH, "hard.txt")
    # ulpgrid (points at 2^40 on the doubles' own 2^-12 grid): centres a
    # half step outside the box were taken for inside, 3e-9 off in all
    for fam, n, seed, tol in (("sphere12", "20000", "3", 1e-11), ("ulpgrid", "20000", "3", 1e-13)):
        subprocess.run([GEN, fam, n, seed, path], check=True)
        r = run([path, "-q", "--voronoi", out, "--voronoi-format", "%i %v"])
        if r.returncode != 0:
            fail("%s %s %s: exit %d: %s" % (fam, n, seed, r.returncode, r.stderr.strip()))
            continue
        pts = read_xyz(path)
        lo = [min(p[k] for p in pts) for k in range(3)]
        hi = [max(p[k] for p in pts) for k in range(3)]
        bvol = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2])
        total = math.fsum(float(l.split()[1]) for l in open(out))
        if abs(total / bvol - 1) > tol:
            fail("%s: the volumes add up to %.17g of the box's %.17g" % (fam, total, bvol))
        # ulpgrid's Voronoi vertices, as absolute coordinates, round by half a
        # cell: its polyhedra are refused (exit 2), as --dual refuses them
        vtu = os.path.join(SCRATCH, "hard.vtu")
        r = run([path, "-q", "--voronoi", vtu])
        want = 2 if fam == "ulpgrid" else 0
        if r.returncode != want or (want and "as polyhedra" not in r.stderr):
            fail("%s as .vtu: exit %d (want %d): %s" % (fam, r.returncode, want, r.stderr.strip()))
    for fam in ("tiny", "huge"):
        subprocess.run([GEN, fam, "2000", "1", path], check=True)
        r = run([path, "-q", "--voronoi", out])
        if r.returncode != 2 or "would leave what doubles hold" not in r.stderr:
            fail("%s: exit %d (want 2), stderr %r" % (fam, r.returncode, r.stderr.strip()))


def outlier_set():
    """A terrain of 3,000 points and one point high above it (a scan's
    outlier, a bird): its cell has well over a thousand faces, cut from
    the box by climbing and in merged order (bench/NOTES.md entry 129)."""
    r = random.Random(7)
    pts = []
    for _ in range(3000):
        x, y = r.random(), r.random()
        pts.append((x, y, 0.05 * math.sin(7 * x) * math.cos(5 * y)))
    pts.append((0.5, 0.5, 1.0))
    path = os.path.join(SCRATCH, "outlier.xyz")
    write_xyz(path, pts)
    return path


if VORO != "none":
    for fam in ("uniform", "gaussian", "lattice", "rotlattice", "skewlattice", "cylinder"):
        against_voro(fam, 3000)
    against_voro("outlier", 3001, outlier_set())
else:
    print("voro++ not found: the comparison with voro++ is skipped")
same_bits()
dtfe()
refusals()
hard_families()
formats_and_refusals()
polyhedra()
interpolation()
print("%d failures" % len(failures))
sys.exit(1 if failures else 0)
