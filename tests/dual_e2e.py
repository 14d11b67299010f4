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


def check_topology(name, points, faces, owner, neighbour, patches):
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
    if names != ["xmin", "xmax", "ymin", "ymax", "zmin", "zmax"] or \
            any(p["type"] != "patch" for p in patches):
        fail(f"{name}: patches {patches}")
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


def one_case(name, xyz, box=None):
    case = os.path.join(SCRATCH, name)
    make_case(case)
    poly = os.path.join(case, "constant", "polyMesh")
    cells = os.path.join(SCRATCH, name + ".cells")
    extra = ["--box", ",".join(repr(x) for x in box)] if box else []
    run([xyz, "-q", "-o", poly, "--dual", "--voronoi", cells, "--voronoi-format", "%i %v %h"]
        + extra)
    if not os.path.exists(os.path.join(poly, "boundary")):
        fail(f"{name}: no polyMesh written")
        return case
    points, faces, owner, neighbour, patches = read_polymesh(poly)
    ncells = check_topology(name, points, faces, owner, neighbour, patches)
    rows = [line.split() for line in open(cells)]
    kept = [float(r[1]) for r in rows if not int(r[2]) & 4]
    if len(kept) != ncells:
        fail(f"{name}: {ncells} cells for {len(kept)} points that are not duplicates")
        return case
    vol = cell_volumes(points, faces, owner, neighbour, ncells)
    worst = max(abs(v - w) / max(abs(w), 1e-300) for v, w in zip(vol, kept))
    if worst > 1e-10:
        fail(f"{name}: a cell's volume differs from --voronoi's by {worst:.3g} relative")
    lo = [min(p[k] for p in points) for k in range(3)]
    hi = [max(p[k] for p in points) for k in range(3)]
    bvol = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2])
    if abs(sum(vol) - bvol) > 1e-12 * bvol:
        fail(f"{name}: volumes add up to {sum(vol):.17g}, the box's {bvol:.17g}")
    print(f"{name}: {ncells} cells, {len(faces)} faces, {len(points)} vertices: "
          f"volumes within {worst:.2g} of --voronoi's")
    return case


def checkmesh(name, case, rc):
    out = foam_mesh.checkmesh(case, rc, "-allTopology")
    for ok in ("Boundary definition OK", "Cell to face addressing OK", "Point usage OK",
               "Upper triangular ordering OK", "Face vertices OK", "Number of regions: 1 (OK)",
               "Topological cell zip-up check OK", "Face-face connectivity OK",
               "Face pyramids OK", "Cell volumes OK", "Boundary openness", "Max cell openness"):
        if ok not in out:
            fail(f"checkMesh {name}: no '{ok}'\n{out}")
            return
    if "Boundary openness" in out and not re.search(r"Boundary openness .* OK", out):
        fail(f"checkMesh {name}: boundary openness\n{out}")
    print(f"checkMesh {name}: topology OK; " +
          ("mesh OK" if "Mesh OK" in out else
           "; ".join(l.strip() for l in out.splitlines() if l.lstrip().startswith("***"))))


def main():
    sets = []
    # cone and torus: rings of cocircular points, whose Voronoi edges meet
    # the walls at box edges and corners (cells were left open there)
    for fam, n in (("uniform", 2000), ("gaussian", 2000), ("lattice", 512), ("dup", 500),
                   ("cone", 1000), ("torus", 4000)):
        xyz = os.path.join(SCRATCH, fam + ".xyz")
        subprocess.run([GEN, fam, str(n), "1", xyz], check=True, capture_output=True)
        sets.append((fam, xyz, None))
    five = os.path.join(SCRATCH, "five.xyz")
    with open(five, "w") as f:
        f.write("0 0 0\n1 0 0\n0 1 0\n0 0 1\n0.3 0.3 0.3\n")
    sets.append(("five", five, None))
    sets.append(("five-box", five, (-0.5, 0, 0, 1, 1, 2.5)))
    sets.append(("uniform-box", sets[0][1], (-0.25, 0, -0.5, 1, 1.5, 1)))
    cases = [(name, one_case(name, xyz, box)) for name, xyz, box in sets]
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
        ref = None
        for mode in (["--mode", "serial"], ["--mode", "shared", "-t", "2"],
                     ["--mode", "message", "-t", "3"]):
            d = os.path.join(SCRATCH, "mode-" + mode[1])
            shutil.rmtree(d, ignore_errors=True)
            os.makedirs(d)
            run([uni, "-q", "-o", os.path.join(d, "polyMesh"), "--dual"] + mode)
            got = [open(os.path.join(d, "polyMesh", f), "rb").read()
                   for f in ("points", "faces", "owner", "neighbour", "boundary")]
            if ref is None:
                ref = got
            elif got != ref:
                fail(f"--dual {' '.join(mode)}: not the serial mode's bytes")
    if failures:
        print(f"{len(failures)} failures")
        sys.exit(1)
    print("dual_e2e: ok")


main()
