#!/usr/bin/python3
"""Reads every output format back with the readers users have: VTK and meshio.

usage: vtu_readback.py FRONTDT

Writes a random point set (with one duplicate point) as .xyz and runs the
CLI on it three times:
  - in memory (--no-stream): .tets, .vtu, .vtk, .msh (gmsh 4.1), .msh
    (--format msh2: gmsh 2.2), .mesh (Medit), .ele (TetGen, with .node);
  - streamed (--stream, two threads): .vtu and .ele;
  - with no option: `-o d.vtu`, which streams by default (the case of
    issue 34 item 4); its header must have the streamed layout.
Each file is read by every reader that knows its format:
  - VTK (python3-vtk9): .vtu with vtkXMLUnstructuredGridReader, .vtk with
    vtkUnstructuredGridReader (the readers ParaView uses), no error or
    warning event;
  - meshio (python3-meshio, meshio 5): .vtu, .vtk, both .msh, .mesh, .ele.
Checks on each: every input point is there, in order, bit-exact, the
duplicate included; the tets are exactly the .tets set, none twice; every
tet is positively oriented (exact integer arithmetic); VTK's cells are all
VTK_TETRA. (.fdtb has no outside reader: tests/stream_readback.py reads it
with README.md's reader; the OpenFOAM polyMesh: tests/formats_readback.sh.)
A periodic mesh (--periodic x,z) laid out in .vtu, .vtk, both .msh and .mesh:
its image vertices after the input points, each with its input_id (Medit's
vertex reference); the tets
mapped back equal the .tets rows (periodic(), below).
Each reader missing is said and skipped; exit 77 (meson's "skipped") when
neither is installed.
"""
import os
import random
import re
import subprocess
import sys
import tempfile
from fractions import Fraction

SKIP = 77

try:
    import vtk
except ImportError:
    vtk = None
try:
    import meshio
except ImportError:
    meshio = None


class ErrorCatcher:
    """Collects VTK error and warning events (VTK reports, never raises)."""

    def __init__(self):
        self.messages = []

    def __call__(self, obj, event):
        self.messages.append("%s from %s" % (event, obj.GetClassName()))


def read_tets(path):
    with open(path) as f:
        return [tuple(int(x) for x in line.split()) for line in f]


class Orienter:
    """Exact orientation of tets over the points, by integer arithmetic.

    Every double is an integer times 2^-1074, so the coordinates scaled by
    2^1074 are integers and the determinant's sign is exact. A sorted tet's
    sign is computed once; a tet in another order is that sign times the
    parity of the permutation.
    """

    def __init__(self, pts):
        self.q = [tuple(int(Fraction(x) * 2 ** 1074) for x in p) for p in pts]
        self.sorted_sign = {}

    def _sign(self, t):
        a, b, c, d = (self.q[i] for i in t)
        u = [b[k] - a[k] for k in range(3)]
        v = [c[k] - a[k] for k in range(3)]
        w = [d[k] - a[k] for k in range(3)]
        det = (u[0] * (v[1] * w[2] - v[2] * w[1])
               - u[1] * (v[0] * w[2] - v[2] * w[0])
               + u[2] * (v[0] * w[1] - v[1] * w[0]))
        return (det > 0) - (det < 0)

    def positive(self, t):
        key = tuple(sorted(t))
        s = self.sorted_sign.get(key)
        if s is None:
            s = self.sorted_sign[key] = self._sign(key)
        parity = sum(1 for i in range(4) for j in range(i + 1, 4) if t[i] > t[j]) & 1
        return s * (-1 if parity else 1) > 0


def check_mesh(what, points, tets, ref):
    """points: a list of 3-tuples; tets: a list of 4-tuples; ref: (pts,
    tets_set, orienter). Returns the failures."""
    pts, tets_set, orient = ref
    fails = []
    if len(points) != len(pts):
        return ["%s: %d points, want %d" % (what, len(points), len(pts))]
    for i, p in enumerate(points):
        if tuple(p) != pts[i]:
            fails.append("%s: point %d is %r, want %r" % (what, i, tuple(p), pts[i]))
            break
    seen = set()
    for c, q in enumerate(tets):
        if len(q) != 4:
            fails.append("%s: cell %d has %d points" % (what, c, len(q)))
            break
        if min(q) < 0 or max(q) >= len(pts):
            fails.append("%s: cell %d %r names a point out of range" % (what, c, q))
            break
        if not orient.positive(q):
            fails.append("%s: cell %d %r is not positively oriented" % (what, c, q))
            break
        seen.add(tuple(sorted(q)))
    if len(tets) != len(tets_set):
        fails.append("%s: %d tets, want %d (.tets lines)" % (what, len(tets), len(tets_set)))
    if seen != tets_set:
        fails.append("%s: tet set differs from the .tets set (%d distinct, %d in common, want %d)"
                     % (what, len(seen), len(seen & tets_set), len(tets_set)))
    return fails


def read_vtk(path):
    """(points, tets, failures) by VTK's own reader for .vtu or .vtk."""
    reader = (vtk.vtkXMLUnstructuredGridReader() if path.endswith(".vtu")
              else vtk.vtkUnstructuredGridReader())
    errors = ErrorCatcher()
    reader.AddObserver("ErrorEvent", errors)
    reader.AddObserver("WarningEvent", errors)
    reader.SetFileName(path)
    reader.Update()
    grid = reader.GetOutput()
    fails = ["VTK said " + m for m in errors.messages]
    points = [grid.GetPoint(i) for i in range(grid.GetNumberOfPoints())]
    tets = []
    ids = vtk.vtkIdList()
    for c in range(grid.GetNumberOfCells()):
        if grid.GetCellType(c) != vtk.VTK_TETRA:
            fails.append("cell %d has type %d, want VTK_TETRA (10)" % (c, grid.GetCellType(c)))
            break
        grid.GetCellPoints(c, ids)
        tets.append(tuple(ids.GetId(k) for k in range(ids.GetNumberOfIds())))
    return points, tets, fails


def read_meshio(path):
    """(points, tets, failures) by meshio.read; cells other than tetra (a
    format's boundary faces) are not tets and are left aside."""
    try:
        m = meshio.read(path)
    except Exception as e:  # meshio raises anything from ReadError to KeyError
        return [], [], ["meshio.read raised %s: %s" % (type(e).__name__, e)]
    points = [tuple(p) for p in m.points.tolist()]
    tets = []
    for block in m.cells:
        if block.type == "tetra":
            tets += [tuple(q) for q in block.data.tolist()]
    return points, tets, []


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    if vtk is None and meshio is None:
        print("neither the vtk nor the meshio python module is installed: skipped")
        return SKIP
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

        def out(name):
            return os.path.join(d, name)

        runs = [
            ["--no-stream", "-o", out("m.tets"), "-o", out("m.vtu"), "-o", out("m.vtk"),
             "-o", out("m.msh"), "--format", "msh2", "-o", out("m2.msh"),
             "-o", out("m.mesh"), "-o", out("m.ele")],
            ["--stream", "--threads", "2", "-o", out("s.vtu"), "-o", out("s.ele")],
            ["-o", out("d.vtu")],
        ]
        for args in runs:
            r = subprocess.run([frontdt, inp, "--quiet"] + args,
                               capture_output=True, text=True, timeout=300)
            if r.returncode != 0:
                print("FAIL: frontdt %s: exit %d: %s" % (" ".join(args), r.returncode, r.stderr))
                return 1
        tets = read_tets(out("m.tets"))
        tets_set = set(tets)
        if len(tets_set) != len(tets) or not tets:
            print("FAIL: .tets has repeated lines or none")
            return 1
        ref = (pts, tets_set, Orienter(pts))

        # The streamed layout: each number the end decides (the cell count
        # first) in a fixed field of 21 bytes (src/io/write/fmt_vtk.c).
        for name in ("s.vtu", "d.vtu"):
            with open(out(name), "rb") as f:
                head = f.read(4096)
            if not re.search(rb'NumberOfCells="[0-9" ]{21}>', head):
                fails.append("%s: not the streamed .vtu layout (the default -o .vtu "
                             "should stream)" % name)

        files = {
            "vtk": ["m.vtu", "s.vtu", "d.vtu", "m.vtk"],
            "meshio": ["m.vtu", "s.vtu", "d.vtu", "m.vtk", "m.msh", "m2.msh",
                       "m.mesh", "m.ele", "s.ele"],
        }
        readers = {"vtk": read_vtk if vtk else None, "meshio": read_meshio if meshio else None}
        checked = []
        for who, names in files.items():
            if readers[who] is None:
                print("%s python module not installed: its reads skipped (%s)"
                      % (who, " ".join(names)))
                continue
            for name in names:
                what = "%s reading %s" % (who, name)
                points, cells, errs = readers[who](out(name))
                new = ["%s: %s" % (what, e) for e in errs]
                if not errs:
                    new += check_mesh(what, points, cells, ref)
                fails += new
                print("%s: %s" % (what, "FAIL" if new else "ok"))
                checked.append(what)

        fails += periodic(frontdt, d, checked)

    for f in fails:
        print("FAIL:", f)
    if fails:
        return 1
    print("readback ok: %d points, %d tets, %d reads" % (len(pts), len(tets_set), len(checked)))
    return 0


def point_src(who, path):
    """The input id of each point (the periodic formats' map back)."""
    if who == "vtk":
        reader = (vtk.vtkXMLUnstructuredGridReader() if path.endswith(".vtu")
                  else vtk.vtkUnstructuredGridReader())
        reader.SetFileName(path)
        reader.Update()
        a = reader.GetOutput().GetPointData().GetArray("input_id")
        return None if a is None else [int(a.GetValue(i)) for i in range(a.GetNumberOfTuples())]
    m = meshio.read(path)
    a = m.point_data.get("medit:ref" if path.endswith(".mesh") else "input_id")
    return None if a is None else [int(v) for v in a.reshape(-1).tolist()]


def periodic(frontdt, d, checked):
    """A channel periodic in x and z (walls of grid points across y) laid
    out in .vtu, .vtk, .msh and .mesh: the input points first, bit-exact; each
    other point an image of the input point its input_id names (that
    point moved by whole periods along x and z); every tet positively
    oriented, and mapped back to (input ids, offsets) the .tets rows; the
    .msh hull triangles outward (their normal along -y on the bottom wall,
    +y on the top)."""
    rnd = random.Random(33)
    g = 6
    pts = [((i + 0.5) / g, y, (k + 0.5) / g) for y in (0.05, 0.95)
           for i in range(g) for k in range(g)]
    pts += [(rnd.random(), rnd.uniform(0.1, 0.9), rnd.random()) for _ in range(700)]
    pts.append(pts[40])
    inp = os.path.join(d, "p.xyz")
    with open(inp, "w") as f:
        for p in pts:
            f.write("%r %r %r\n" % p)
    out = lambda name: os.path.join(d, name)
    r = subprocess.run([frontdt, inp, "--quiet", "--periodic", "x,z", "--box", "0,0,0,1,1,1",
                        "-o", out("p.tets"), "-o", out("p.vtu"), "-o", out("p.vtk"),
                        "-o", out("p.msh"), "--format", "msh2", "-o", out("p2.msh"),
                        "-o", out("p.mesh")],
                       capture_output=True, text=True, timeout=300)
    if r.returncode != 0:
        return ["frontdt --periodic: exit %d: %s" % (r.returncode, r.stderr)]
    rows = set()
    for line in open(out("p.tets")):
        v = [int(x) for x in line.split()]
        rows.add((tuple(v[:4]), tuple(v[4:])))
    fails = []
    names = {"vtk": ["p.vtu", "p.vtk"],
             "meshio": ["p.vtu", "p.vtk", "p.msh", "p2.msh", "p.mesh"]}
    readers = {"vtk": read_vtk if vtk else None, "meshio": read_meshio if meshio else None}
    for who, files in names.items():
        if readers[who] is None:
            continue
        for name in files:
            what = "%s reading periodic %s" % (who, name)
            points, cells, errs = readers[who](out(name))
            src = point_src(who, out(name))
            new = ["%s: %s" % (what, e) for e in errs]
            if src is None or len(src) != len(points):
                new.append("%s: no input_id for each point" % what)
            elif points[:len(pts)] != pts or src[:len(pts)] != list(range(len(pts))):
                new.append("%s: the input points are not the first, in order" % what)
            else:
                new += periodic_check(what, pts, points, src, cells, rows)
                if name.endswith(".msh"):
                    new += hull_outward(what, points, out(name))
            fails += new
            print("%s: %s" % (what, "FAIL" if new else "ok"))
            checked.append(what)
    return fails


def periodic_check(what, pts, points, src, cells, rows):
    offs = []
    for i, p in enumerate(points):
        x = pts[src[i]]
        o = tuple(round(p[k] - x[k]) for k in range(3))
        if o[1] != 0 or any(abs(p[k] - (x[k] + o[k])) > 1e-15 for k in range(3)):
            return ["%s: point %d %r is no image of input point %d %r" % (what, i, p, src[i], x)]
        offs.append(o)
    orient = Orienter(points)
    got = set()
    for c, q in enumerate(cells):
        if not orient.positive(q):
            return ["%s: cell %d %r is not positively oriented" % (what, c, q)]
        v = sorted((src[i], offs[i]) for i in q)
        first = v[0][1]
        got.add((tuple(a for a, _ in v),
                 tuple(o[k] - first[k] for _, o in v for k in range(3))))
    if len(cells) != len(rows) or got != rows:
        return ["%s: %d cells, %d distinct, %d of the %d .tets rows"
                % (what, len(cells), len(got), len(got & rows), len(rows))]
    return []


def hull_outward(what, points, path):
    if meshio is None:
        return []
    m = meshio.read(path)
    tri = [t for b in m.cells if b.type == "triangle" for t in b.data.tolist()]
    if not tri:
        return ["%s: no hull triangles" % what]
    for t in tri:
        a, b, c = (points[i] for i in t)
        u = [b[k] - a[k] for k in range(3)]
        v = [c[k] - a[k] for k in range(3)]
        ny = u[2] * v[0] - u[0] * v[2]
        if (ny > 0) != (a[1] > 0.5):
            return ["%s: hull triangle %r is not outward" % (what, t)]
    return []


if __name__ == "__main__":
    sys.exit(main())
