#!/usr/bin/env python3
"""End-to-end checks of --dual (issue 32, item 2): the Voronoi cells
clipped by the box as an OpenFOAM polyMesh, through the CLI.

Usage: dual_e2e.py FRONTDT GEN_POINTS SCRATCH [--checkmesh]

Without --checkmesh (always runs, no OpenFOAM needed), on uniform,
clustered, lattice (cospherical), duplicate, cone and torus (rings of
cocircular points) and five points, with the
default box (hull points on the walls) and a given one, the polyMesh files
are read back here and checked on their own: every face has 3 or more
distinct vertices, every vertex is used, owner < neighbour in
upper-triangular order, the six patches xmin .. zmax follow the internal
faces, every cell is closed (each edge once each way round, the faces
turned out of it), each cell's volume from its faces equals --voronoi's %v
for its point (1e-10 relative; merged duplicates have no cell) and the
volumes add up to the box's (1e-12). Refusals: --dual without an OpenFOAM
-o, --dual with --stream, a point outside --box (exit 1 each); points
closer than doubles resolve (gen_points mixed: 1e-150 beside 1e150;
ulpgrid: steps of 2^-52 of the coordinates) refused as input (exit 2). Written
again over the existing polyMesh beside a .tets output of the same run;
the same bytes in serial, shared and message modes.

With --checkmesh: OpenFOAM's checkMesh -allTopology on the same cases,
every topology check OK ("Boundary definition OK" .. "Number of regions: 1
(OK)", cell zip-up, face-face connectivity), face pyramids and cell
volumes OK; exit 77 (skipped) when OpenFOAM is not installed.
"""
import os
import random
import re
import shutil
import subprocess
import sys

import foam_mesh
from foam_mesh import cell_volumes, checkmesh_cmd, make_case, read_polymesh

FRONTDT, GEN, SCRATCH = sys.argv[1:4]
CHECKMESH = "--checkmesh" in sys.argv[4:]
os.makedirs(SCRATCH, exist_ok=True)
failures = []


def fail(msg):
    failures.append(msg)
    print("FAIL:", msg)


WALLS = ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"]


def check_cyclic(name, points, faces, patches, periodic):
    """The cyclic pairs of a periodic dual: partners side by side, each
    other's neighbourPatch with opposite separation vectors along the
    periodic axes only, as many faces; face i of one moved by its
    separation vector is face i of the other from the same point, turned
    the other way (to 1e-9 of the box)."""
    cyc = [p for p in patches if p["type"] == "cyclic"]
    if len(cyc) % 2 or not cyc:
        fail(f"{name}: {len(cyc)} cyclic patches")
        return
    span = max(max(p[k] for p in points) - min(p[k] for p in points) for k in range(3))
    for a, b in zip(cyc[0::2], cyc[1::2]):
        sa, sb = a["separationVector"], b["separationVector"]
        if a["neighbourPatch"] != b["name"] or b["neighbourPatch"] != a["name"] or \
                a["nFaces"] != b["nFaces"] or any(x != -y for x, y in zip(sa, sb)) or \
                any(sa[k] and "xyz"[k] not in periodic for k in range(3)):
            fail(f"{name}: cyclic pair {a} / {b}")
            continue
        for i in range(a["nFaces"]):
            f, g = faces[a["startFace"] + i], faces[b["startFace"] + i]
            moved = [tuple(points[v][k] + sa[k] for k in range(3)) for v in [f[0]] + f[:0:-1]]
            if len(f) != len(g) or any(abs(x[k] - points[v][k]) > 1e-9 * span
                                       for x, v in zip(moved, g) for k in range(3)):
                fail(f"{name}: face {i} of {b['name']} is not face {i} of {a['name']} moved")
                break


def check_topology(name, points, faces, owner, neighbour, patches, periodic=""):
    nint = len(neighbour)
    ncells = max(owner + neighbour) + 1
    used = [False] * len(points)
    for f, fv in enumerate(faces):
        if len(fv) < 3 or len(set(fv)) != len(fv):
            fail(f"{name}: face {f} has vertices {fv}")
        for v in fv:
            used[v] = True
    if not all(used):
        fail(f"{name}: {used.count(False)} vertices in no face")
    for f in range(nint):
        if not owner[f] < neighbour[f]:
            fail(f"{name}: face {f} owner {owner[f]} neighbour {neighbour[f]}")
            break
        if f and (owner[f - 1], neighbour[f - 1]) >= (owner[f], neighbour[f]):
            fail(f"{name}: face {f} out of upper-triangular order")
            break
    names = [p["name"] for p in patches]
    walls = [w for w in WALLS if w[0] not in periodic]
    if names[:len(walls)] != walls or any(p["type"] != "patch" for p in patches[:len(walls)]) \
            or (not periodic and len(names) != 6):
        fail(f"{name}: patches {patches}")
    if periodic:
        check_cyclic(name, points, faces, patches[len(walls):], periodic)
    at = nint
    for p in patches:
        if p["startFace"] != at:
            fail(f"{name}: patch {p['name']} starts at {p['startFace']}, not {at}")
        at += p["nFaces"]
    if at != len(faces):
        fail(f"{name}: the patches end at {at} of {len(faces)} faces")
    edges = {}
    for f, fv in enumerate(faces):
        sides = [(owner[f], False)] + ([(neighbour[f], True)] if f < nint else [])
        for c, rev in sides:
            for i in range(len(fv)):
                a, b = fv[i], fv[(i + 1) % len(fv)]
                key = (c, b, a) if rev else (c, a, b)
                edges[key] = edges.get(key, 0) + 1
    bad = [k for k, n in edges.items() if n != 1 or (k[0], k[2], k[1]) not in edges]
    if bad:
        fail(f"{name}: {len(bad)} half-edges unpaired, e.g. cell {bad[0][0]} edge {bad[0][1:]}")
    return ncells


def run(args, want=0):
    p = subprocess.run([FRONTDT] + args, capture_output=True, text=True)
    if p.returncode != want:
        fail(f"frontdt {' '.join(args)}: exit {p.returncode}, want {want}: {p.stderr.strip()}")
    return p


def one_case(name, xyz, box=None, periodic=""):
    case = os.path.join(SCRATCH, name)
    make_case(case)
    poly = os.path.join(case, "constant", "polyMesh")
    cells = os.path.join(SCRATCH, name + ".cells")
    extra = ["--box", ",".join(repr(x) for x in box)] if box else []
    extra += ["--periodic", periodic] if periodic else []
    run([xyz, "-q", "-o", poly, "--dual", "--voronoi", cells, "--voronoi-format", "%i %v %h"]
        + extra)
    if not os.path.exists(os.path.join(poly, "boundary")):
        fail(f"{name}: no polyMesh written")
        return case
    points, faces, owner, neighbour, patches = read_polymesh(poly)
    ncells = check_topology(name, points, faces, owner, neighbour, patches, periodic)
    rows = [line.split() for line in open(cells)]
    kept = [float(r[1]) for r in rows if not int(r[2]) & 4]
    if len(kept) != ncells:
        fail(f"{name}: {ncells} cells for {len(kept)} points that are not duplicates")
        return case
    vol = cell_volumes(points, faces, owner, neighbour, ncells)
    worst = max(abs(v - w) / max(abs(w), 1e-300) for v, w in zip(vol, kept))
    if worst > 1e-10:
        fail(f"{name}: a cell's volume differs from --voronoi's by {worst:.3g} relative")
    # the cells fill the box (a periodic one's: the cells laid out around
    # their points reach past it on its periodic axes)
    lo = box[:3] if periodic else [min(p[k] for p in points) for k in range(3)]
    hi = box[3:] if periodic else [max(p[k] for p in points) for k in range(3)]
    bvol = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2])
    if abs(sum(vol) - bvol) > 1e-12 * bvol:
        fail(f"{name}: volumes add up to {sum(vol):.17g}, the box's {bvol:.17g}")
    print(f"{name}: {ncells} cells, {len(faces)} faces, {len(points)} vertices: "
          f"volumes within {worst:.2g} of --voronoi's")
    return case


def checkmesh(name, case, rc):
    out = foam_mesh.checkmesh(case, rc, "-allTopology")
    want = ["Boundary definition OK", "Cell to face addressing OK", "Point usage OK",
            "Upper triangular ordering OK", "Face vertices OK", "Number of regions: 1 (OK)",
            "Topological cell zip-up check OK", "Face-face connectivity OK",
            "Face pyramids OK", "Cell volumes OK", "Boundary openness", "Max cell openness"]
    if "periodic" in name:  # the cyclic pairs matched by OpenFOAM
        want.append("Coupled point location match")
    if name == "hcp":
        # crossings of distinct Voronoi edges that round to one place inside
        # a wall stay distinct vertices (merged, the cells did not close:
        # bench/NOTES.md entry 129), so faces there meet at coincident
        # points: checkMesh warns of "non-consecutive shared points" (no
        # failed check); every other topology check must pass
        want.remove("Face-face connectivity OK")
        if not re.search(r"Number of faces with non-consecutive shared points: \d+", out):
            fail(f"checkMesh {name}: neither face-face connectivity nor its warning\n{out}")
            return
    for ok in want:
        if ok not in out:
            fail(f"checkMesh {name}: no '{ok}'\n{out}")
            return
    if "Boundary openness" in out and not re.search(r"Boundary openness .* OK", out):
        fail(f"checkMesh {name}: boundary openness\n{out}")
    print(f"checkMesh {name}: topology OK; " +
          ("mesh OK" if "Mesh OK" in out else
           "; ".join(l.strip() for l in out.splitlines() if l.lstrip().startswith("***"))))


def periodic_sets():
    """Periodic duals (issue 33 item 5): uniform points periodic in x, y, z;
    an integer lattice in a box of its period (every cell a cube of
    cospherical points); a channel (x, z: walls of grid points a little
    inside the y sides, random points between) and a duct (x), in boxes
    whose periods are not powers of two, so the images are rounded."""
    sets = []
    uni = os.path.join(SCRATCH, "uniform.xyz")  # main's set, made first
    sets.append(("uniform-periodic-xyz", uni, (0, 0, 0, 1, 1, 1), "x,y,z"))
    lat = os.path.join(SCRATCH, "lattice.xyz")  # 8^3 points, 0 .. 7
    sets.append(("lattice-periodic-xyz", lat, (0, 0, 0, 8, 8, 8), "x,y,z"))
    r = random.Random(5)
    for name, box, axes in (("channel-periodic-xz", (0, -0.5, 0, 2.1, 0.5, 1.3), "x,z"),
                            ("duct-periodic-x", (0, 0, 0, 3.3, 1, 1), "x")):
        lo, hi = box[:3], box[3:]
        pts = set()
        g = 7
        for k in range(3):
            if "xyz"[k] in axes:
                continue
            a, b = [j for j in range(3) if j != k]
            for side in (lo[k] + 1e-3, hi[k] - 1e-3):
                for i in range(g + 1):
                    for j in range(g + 1):
                        q = [0.0] * 3
                        q[k] = side
                        for ax, t in ((a, i), (b, j)):
                            q[ax] = (lo[ax] + (hi[ax] - lo[ax]) * (t + 0.5) / (g + 1)
                                     if "xyz"[ax] in axes else
                                     lo[ax] + 1e-3 + (hi[ax] - lo[ax] - 2e-3) * t / g)
                        pts.add(tuple(q))
        pts = sorted(pts)
        pad = [0 if "xyz"[k] in axes else 0.02 * (hi[k] - lo[k]) for k in range(3)]
        pts += [tuple(lo[k] + pad[k] + (hi[k] - lo[k] - 2 * pad[k]) * r.random()
                      for k in range(3)) for _ in range(1500)]
        xyz = os.path.join(SCRATCH, name + ".xyz")
        with open(xyz, "w") as f:
            f.writelines("%r %r %r\n" % q for q in pts)
        sets.append((name, xyz, box, axes))
    return sets


def main():
    sets = []
    # cone and torus: rings of cocircular points, whose Voronoi edges meet
    # the walls at box edges and corners (cells were left open there); fcc
    # and hcp crystals in their bounding boxes (hcp: Voronoi vertices
    # within ulps of the walls and of each other, an internal error until
    # bench/NOTES.md entry 129)
    for fam, n in (("uniform", 2000), ("gaussian", 2000), ("lattice", 512), ("dup", 500),
                   ("cone", 1000), ("torus", 4000), ("fcc", 500), ("hcp", 729)):
        xyz = os.path.join(SCRATCH, fam + ".xyz")
        subprocess.run([GEN, fam, str(n), "1", xyz], check=True, capture_output=True)
        sets.append((fam, xyz, None))
    five = os.path.join(SCRATCH, "five.xyz")
    with open(five, "w") as f:
        f.write("0 0 0\n1 0 0\n0 1 0\n0 0 1\n0.3 0.3 0.3\n")
    sets.append(("five", five, None))
    sets.append(("five-box", five, (-0.5, 0, 0, 1, 1, 2.5)))
    sets.append(("uniform-box", sets[0][1], (-0.25, 0, -0.5, 1, 1.5, 1)))
    sets = [s + ("",) for s in sets] + periodic_sets()
    cases = [(name, one_case(name, xyz, box, per)) for name, xyz, box, per in sets]
    if CHECKMESH:
        rc = checkmesh_cmd()
        if rc is None:
            print("checkMesh: skipped (OpenFOAM not installed)")
            sys.exit(77)
        for name, case in cases:
            checkmesh(name, case, rc)
    else:
        uni = sets[0][1]
        for sub in ("s", "b"):
            shutil.rmtree(os.path.join(SCRATCH, sub), ignore_errors=True)
            os.makedirs(os.path.join(SCRATCH, sub))
        p = run([uni, "-q", "--dual"], want=1)
        if "polyMesh" not in p.stderr:
            fail(f"--dual without an OpenFOAM -o: {p.stderr.strip()}")
        run([uni, "-q", "--dual", "-o", os.path.join(SCRATCH, "m.vtu")], want=1)
        p = run([uni, "-q", "--dual", "--stream", "-o", os.path.join(SCRATCH, "s", "polyMesh")],
                want=1)
        if "--dual" not in p.stderr:
            fail(f"--dual with --stream: {p.stderr.strip()}")
        p = run([uni, "-q", "--dual", "--box", "0.1,0,0,1,1,1", "-o",
                 os.path.join(SCRATCH, "b", "polyMesh")], want=1)
        if "outside the box" not in p.stderr:
            fail(f"a point outside --box: {p.stderr.strip()}")
        if os.path.exists(os.path.join(SCRATCH, "b", "polyMesh")):
            fail("a refused --dual left a polyMesh")
        # cells beyond doubles: refused as input (exit 2) naming two points,
        # never an internal error or a mesh of noise
        for fam in ("mixed", "ulpgrid"):
            xyz = os.path.join(SCRATCH, fam + ".xyz")
            subprocess.run([GEN, fam, "4000", "3", xyz], check=True, capture_output=True)
            p = run([xyz, "-q", "--dual", "-o", os.path.join(SCRATCH, "b", "polyMesh")], want=2)
            if not re.search(r"points \d+ and \d+ are .* beyond what doubles hold", p.stderr):
                fail(f"--dual on {fam}: {p.stderr.strip()}")
            if os.path.exists(os.path.join(SCRATCH, "b", "polyMesh")):
                fail(f"a refused --dual ({fam}) left a polyMesh")
        # a periodic dual whose faces across a period do not survive the
        # images' rounding (a cylinder's cocircular rings in a box whose
        # period is no power of two): refused as input (exit 2), nothing left
        cyl = os.path.join(SCRATCH, "cylinder.xyz")
        subprocess.run([GEN, "cylinder", "3000", "1", cyl], check=True, capture_output=True)
        pts = [tuple(map(float, line.split())) for line in open(cyl)]
        lo = [min(q[k] for q in pts) for k in range(3)]
        hi = [max(q[k] for q in pts) * 15 / 14 - min(q[k] for q in pts) / 14 for k in range(3)]
        p = run([cyl, "-q", "--dual", "--periodic", "x,y,z", "--box",
                 ",".join(repr(x) for x in lo + hi), "-o", os.path.join(SCRATCH, "b", "polyMesh")],
                want=2)
        if "cannot be matched with its copy on the other side" not in p.stderr:
            fail(f"--dual --periodic on a cylinder: {p.stderr.strip()}")
        if os.path.exists(os.path.join(SCRATCH, "b", "polyMesh")):
            fail("a refused periodic --dual left a polyMesh")
        # over an existing polyMesh (its five files replaced), beside a
        # Delaunay output of the same run (the tets as ever)
        case = dict(cases)["uniform"]
        poly = os.path.join(case, "constant", "polyMesh")
        tets = os.path.join(SCRATCH, "m.tets")
        run([uni, "-q", "-o", tets, "-o", poly, "--dual"])
        points, faces, owner, neighbour, patches = read_polymesh(poly)
        check_topology("uniform again", points, faces, owner, neighbour, patches)
        with open(tets) as f:
            if len(f.readline().split()) != 4:
                fail("-o m.tets beside --dual: not a .tets file")
        if any(".tmp." in x for x in os.listdir(os.path.join(case, "constant"))):
            fail("--dual left a temporary beside the polyMesh")
        # the same bytes in every mode and thread count (the tets sorted first)
        chan = [s for s in periodic_sets() if s[0].startswith("channel")][0]
        for what, args in (("", [uni]),
                           (" --periodic", [chan[1], "--periodic", chan[3], "--box",
                                           ",".join(repr(x) for x in chan[2])])):
            ref = None
            for mode in (["--mode", "serial"], ["--mode", "shared", "-t", "2"],
                         ["--mode", "message", "-t", "3"], ["-t", "3"]):
                d = os.path.join(SCRATCH, "mode-" + "".join(mode))
                shutil.rmtree(d, ignore_errors=True)
                os.makedirs(d)
                run(args + ["-q", "-o", os.path.join(d, "polyMesh"), "--dual"] + mode)
                got = [open(os.path.join(d, "polyMesh", f), "rb").read()
                       for f in ("points", "faces", "owner", "neighbour", "boundary")]
                if ref is None:
                    ref = got
                elif got != ref:
                    fail(f"--dual{what} {' '.join(mode)}: not the serial mode's bytes")
    if failures:
        print(f"{len(failures)} failures")
        sys.exit(1)
    print("dual_e2e: ok")


main()
