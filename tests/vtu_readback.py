#!/usr/bin/python3
"""Reads frontdt's .vtu and .vtk output back with VTK itself.

usage: vtu_readback.py FRONTDT

Writes a random point set (with one duplicate point) as .xyz, runs
`frontdt IN -o OUT` for .tets, .vtu and .vtk, and reads the VTK files with
vtkXMLUnstructuredGridReader and vtkUnstructuredGridReader (the readers
ParaView uses). Checks: VTK reports no error; every input point is there,
bit-exact, the duplicate included; the cells are exactly the .tets set;
every cell is a VTK_TETRA with positive volume (exact rational arithmetic).
Exit 77 (meson's "skipped") when the vtk module is not installed.
"""
import os
import random
import subprocess
import sys
import tempfile
from fractions import Fraction

SKIP = 77

try:
    import vtk
except ImportError:
    print("vtk python module not installed: skipped")
    sys.exit(SKIP)


class ErrorCatcher:
    """Collects VTK error and warning events (VTK reports, never raises)."""

    def __init__(self):
        self.messages = []

    def __call__(self, obj, event):
        self.messages.append("%s from %s" % (event, obj.GetClassName()))


def read_tets(path):
    with open(path) as f:
        return [tuple(int(x) for x in line.split()) for line in f]


def det_positive(p, q):
    """Exact sign of det(b-a, c-a, d-a) for the tet q over points p."""
    a, b, c, d = (tuple(Fraction(x) for x in p[i]) for i in q)
    u = [b[k] - a[k] for k in range(3)]
    v = [c[k] - a[k] for k in range(3)]
    w = [d[k] - a[k] for k in range(3)]
    det = (u[0] * (v[1] * w[2] - v[2] * w[1])
           - u[1] * (v[0] * w[2] - v[2] * w[0])
           + u[2] * (v[0] * w[1] - v[1] * w[0]))
    return det > 0


def check_grid(kind, grid, pts, tets_set, errors):
    fails = []
    if errors.messages:
        fails.append("%s: VTK said %s" % (kind, "; ".join(errors.messages)))
    n = grid.GetNumberOfPoints()
    if n != len(pts):
        fails.append("%s: %d points, want %d" % (kind, n, len(pts)))
        return fails
    for i in range(n):
        if tuple(grid.GetPoint(i)) != pts[i]:
            fails.append("%s: point %d is %r, want %r" % (kind, i, grid.GetPoint(i), pts[i]))
            break
    nc = grid.GetNumberOfCells()
    if nc != len(tets_set):
        fails.append("%s: %d cells, want %d (.tets lines)" % (kind, nc, len(tets_set)))
    seen = set()
    ids = vtk.vtkIdList()
    for c in range(nc):
        if grid.GetCellType(c) != vtk.VTK_TETRA:
            fails.append("%s: cell %d has type %d, want VTK_TETRA (10)"
                         % (kind, c, grid.GetCellType(c)))
            break
        grid.GetCellPoints(c, ids)
        q = tuple(ids.GetId(k) for k in range(ids.GetNumberOfIds()))
        if len(q) != 4:
            fails.append("%s: cell %d has %d points" % (kind, c, len(q)))
            break
        if not det_positive(pts, q):
            fails.append("%s: cell %d %r is not positively oriented" % (kind, c, q))
            break
        seen.add(tuple(sorted(q)))
    if seen != tets_set:
        fails.append("%s: cell set differs from the .tets set (%d vs %d distinct)"
                     % (kind, len(seen), len(tets_set)))
    return fails


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    frontdt = os.path.abspath(sys.argv[1])
    rnd = random.Random(20240501)
    pts = [(rnd.uniform(-1, 1), rnd.uniform(-1, 1), rnd.uniform(-1, 1))
           for _ in range(1500)]
    pts.append(pts[17])  # a duplicate: still an input point of the output
    fails = []
    with tempfile.TemporaryDirectory() as d:
        inp = os.path.join(d, "in.xyz")
        with open(inp, "w") as f:
            for p in pts:
                f.write("%r %r %r\n" % p)
        outs = {}
        for ext in ("tets", "vtu", "vtk"):
            out = os.path.join(d, "mesh." + ext)
            r = subprocess.run([frontdt, inp, "-o", out, "--quiet"],
                               capture_output=True, text=True, timeout=300)
            if r.returncode != 0:
                print("frontdt -o %s: exit %d: %s" % (out, r.returncode, r.stderr))
                return 1
            outs[ext] = out
        tets = read_tets(outs["tets"])
        tets_set = set(tets)
        if len(tets_set) != len(tets) or not tets:
            print(".tets has repeated lines or none")
            return 1

        for kind, reader in (("vtu", vtk.vtkXMLUnstructuredGridReader()),
                             ("vtk", vtk.vtkUnstructuredGridReader())):
            errors = ErrorCatcher()
            reader.AddObserver("ErrorEvent", errors)
            reader.AddObserver("WarningEvent", errors)
            reader.SetFileName(outs[kind])
            reader.Update()
            grid = reader.GetOutput()
            fails += check_grid(kind, grid, pts, tets_set, errors)

    for f in fails:
        print("FAIL:", f)
    if fails:
        return 1
    print("vtu/vtk readback ok: %d points, %d tets" % (len(pts), len(tets_set)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
