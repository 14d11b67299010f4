"""OpenFOAM polyMesh directories for the end-to-end tests: read back, cell
volumes from the faces, a case to run checkMesh in, and checkMesh itself
(tests/dual_e2e.py: the Voronoi dual; tests/periodic_e2e.py: a periodic
Delaunay mesh with cyclic patches). Reads only the ASCII subset frontdt
writes."""
import os
import re
import shutil
import subprocess


def foam_body(path):
    text = open(path).read()
    text = text[text.index("FoamFile"):]
    return text[text.index("}") + 1:]


def read_patches(d):
    """The boundary file's patches: dicts with name, type, nFaces,
    startFace, and for a cyclic one neighbourPatch and separationVector."""
    bd = foam_body(os.path.join(d, "boundary"))
    patches = []
    for name, body in re.findall(r"(\w+)\s*\{([^{}]*)\}", bd):
        p = {"name": name}
        for key, val in re.findall(r"(\w+)\s+([^;]*);", body):
            p[key] = val.strip()
        p["nFaces"], p["startFace"] = int(p["nFaces"]), int(p["startFace"])
        if "separationVector" in p:
            p["separationVector"] = tuple(map(float, p["separationVector"].strip("()").split()))
        patches.append(p)
    return patches


def read_polymesh(d):
    """points, faces, owner, neighbour, patches (read_patches)."""
    pts = foam_body(os.path.join(d, "points"))
    points = [tuple(map(float, m.split())) for m in re.findall(r"\(([^()]*)\)",
                                                                 pts[pts.index("(") + 1:])]
    fc = foam_body(os.path.join(d, "faces"))
    faces = [list(map(int, m.split())) for m in re.findall(r"\d+\(([^()]*)\)",
                                                             fc[fc.index("(") + 1:])]

    def labels(name):
        b = foam_body(os.path.join(d, name))
        b = b[b.index("(") + 1:b.rindex(")")]
        return [int(x) for x in b.split()]
    return points, faces, labels("owner"), labels("neighbour"), read_patches(d)


def cell_volumes(points, faces, owner, neighbour, ncells):
    """Each cell's volume from its faces (the divergence theorem, each face
    fanned from its first vertex), a face's normal out of its owner."""
    vol = [0.0] * ncells
    ref = [None] * ncells
    for f, fv in enumerate(faces):
        sides = [(owner[f], 1.0)] + ([(neighbour[f], -1.0)] if f < len(neighbour) else [])
        for c, sg in sides:
            if ref[c] is None:
                ref[c] = points[fv[0]]
            r = ref[c]
            a = [points[fv[0]][k] - r[k] for k in range(3)]
            s = 0.0
            for i in range(1, len(fv) - 1):
                b = [points[fv[i]][k] - r[k] for k in range(3)]
                e = [points[fv[i + 1]][k] - r[k] for k in range(3)]
                s += (a[0] * (b[1] * e[2] - b[2] * e[1]) + a[1] * (b[2] * e[0] - b[0] * e[2]) +
                      a[2] * (b[0] * e[1] - b[1] * e[0]))
            vol[c] += sg * s / 6
    return vol


def make_case(case):
    """An empty case: system's three dictionaries, constant/."""
    shutil.rmtree(case, ignore_errors=True)
    os.makedirs(os.path.join(case, "system"))
    os.makedirs(os.path.join(case, "constant"))
    for d in ("controlDict", "fvSchemes", "fvSolution"):
        with open(os.path.join(case, "system", d), "w") as f:
            f.write("FoamFile { version 2.0; format ascii; class dictionary; object %s; }\n" % d)
            if d == "controlDict":
                f.write("application checkMesh; startFrom startTime; startTime 0; "
                        "stopAt endTime; endTime 1; deltaT 1; writeControl timeStep; "
                        "writeInterval 1;\n")
            if d == "fvSchemes":
                f.write("ddtSchemes { default Euler; } gradSchemes { default Gauss linear; }\n"
                        "divSchemes { default none; } laplacianSchemes { default Gauss linear "
                        "corrected; }\ninterpolationSchemes { default linear; } "
                        "snGradSchemes { default corrected; }\n")


def checkmesh_cmd():
    """OpenFOAM's environment script to source, "" when checkMesh is on the
    PATH already, None when OpenFOAM is not installed."""
    for rc in ("/usr/share/openfoam/etc/bashrc",):
        if os.path.exists(rc):
            return rc
    return "" if shutil.which("checkMesh") else None


def checkmesh(case, rc, *args):
    """checkMesh's output (stdout and stderr) on case."""
    src = f". '{rc}' >/dev/null 2>&1; " if rc else ""
    p = subprocess.run(["bash", "-c", src + f"checkMesh {' '.join(args)} -case '{case}'"],
                       capture_output=True, text=True)
    return p.stdout + p.stderr
