#!/usr/bin/python3
"""The Python module frontdt (python/frontdt/, issue 17 item 3).

usage: test_python.py PKG_DIR FRONTDT GEN_POINTS
       test_python.py --not-built WHY  (exit 77: meson's "skipped")

PKG_DIR is the build's python/ directory, which holds the freshly built
package (frontdt/__init__.py and the extension); meson puts it first on
PYTHONPATH and this test checks the module it imports came from there.

Checks:
 - scipy.spatial.Delaunay (qhull) on non-degenerate random inputs: the same
   simplex set, hull face set and neighbour relation; every tet positive;
 - the CLI's --hash on degenerate inputs from tests/gen_points (lattice,
   duplicates, cospherical, coplanar grids) and the duplicate map;
 - faces/face_tets: every face once, oriented towards face_tets[:, 0];
 - errors: NaN, Inf, fewer than 4 points, coplanar, collinear, wrong
   shapes, bad mode/search/threads; check() and CheckError;
 - threads=2 and the parallel modes give the serial hash and the same
   canonical simplices;
 - the GIL is released (a Python thread counts while a triangulation runs)
   and KeyboardInterrupt cancels a long one;
 - arrays keep the result alive; RSS does not grow over repeated runs.
"""
import gc
import os
import subprocess
import sys
import tempfile
import threading
import time
import _thread

SKIP = 77

if len(sys.argv) >= 2 and sys.argv[1] == "--not-built":
    print("skipped: the Python module was not built (%s; scripts/bootstrap.sh installs "
          "python3-dev and python3-numpy, meson -Dpython=enabled insists)"
          % (sys.argv[2] if len(sys.argv) > 2 else "see meson's summary"))
    sys.exit(SKIP)
if len(sys.argv) != 4:
    sys.exit(__doc__)
PKG_DIR, FRONTDT, GEN_POINTS = (os.path.abspath(a) for a in sys.argv[1:])

import numpy as np  # noqa: E402  (after the skip: numpy is there if built)
import frontdt  # noqa: E402

try:
    import scipy.spatial
except ImportError:
    scipy = None

FAILS = []


def check(cond, what):
    """The shared CHECK idea of tests/testutil.h: record, name, go on."""
    if not cond:
        FAILS.append(what)
        print("FAIL:", what, flush=True)
    return cond


def raises(exc, fn, *args, **kw):
    try:
        fn(*args, **kw)
    except exc as e:
        return str(e) or type(e).__name__
    except Exception as e:  # the wrong kind
        print("  %s raised %s: %s" % (getattr(fn, "__name__", fn), type(e).__name__, e))
    return None


def tetset(s):
    return set(map(tuple, np.sort(np.asarray(s), axis=1).tolist()))


def orient(p, a, b, c, d):
    """det(b-a, c-a, d-a) per row, in floating point (general position)."""
    return np.linalg.det(np.stack([p[b] - p[a], p[c] - p[a], p[d] - p[a]], axis=1))


def neighbour_relation(simp, nbrs):
    """{(sorted tet, vertex opposite) -> sorted neighbour tet or None}."""
    rel = {}
    st = [tuple(sorted(t)) for t in simp.tolist()]
    for i, t in enumerate(simp.tolist()):
        for k in range(4):
            j = int(nbrs[i][k])
            rel[(st[i], t[k])] = st[j] if j >= 0 else None
    return rel


def test_origin():
    f = os.path.realpath(frontdt._frontdt.__file__)
    check(f.startswith(os.path.realpath(PKG_DIR) + os.sep),
          "frontdt imported from %s, not the build's %s" % (f, PKG_DIR))


def test_scipy():
    if scipy is None:
        print("scipy not installed: the qhull comparison is skipped "
              "(Debian python3-scipy)")
        return
    rng = np.random.default_rng(17)
    inputs = {
        "uniform 3000": rng.random((3000, 3)),
        "gaussian 2000": rng.standard_normal((2000, 3)),
        "ball 2000 (list of lists)": [list(map(float, r)) for r in
                                      (lambda q: q[np.sum(q * q, 1) < 1])(
                                          rng.random((4000, 3)) * 2 - 1)[:2000]],
        "int grid jittered 1500": (rng.integers(0, 1000, (1500, 3))
                                   + rng.random((1500, 3)) * 1e-3),
    }
    for name, pts in inputs.items():
        t = frontdt.delaunay(pts)
        p = np.asarray(pts, dtype=float)
        q = scipy.spatial.Delaunay(p)
        s = t.simplices
        check(s.dtype == np.int32 and s.shape[1] == 4, name + ": simplices int32 (m, 4)")
        check(t.neighbors.dtype == np.int64 and t.neighbors.shape == s.shape,
              name + ": neighbors int64 (m, 4)")
        check(tetset(s) == tetset(q.simplices),
              name + ": tet set differs from scipy's (%d vs %d tets)"
              % (len(s), len(q.simplices)))
        check(tetset(t.convex_hull) == tetset(q.convex_hull), name + ": hull differs from scipy's")
        check(neighbour_relation(s, t.neighbors) ==
              neighbour_relation(q.simplices, q.neighbors), name + ": neighbours differ from scipy's")
        check(np.all(orient(p, *s.T) > 0), name + ": a tet is not positively oriented")
        h = t.convex_hull  # outward: the centroid is on the negative side
        c = p.mean(axis=0)
        check(np.all(np.linalg.det(np.stack([p[h[:, 1]] - p[h[:, 0]], p[h[:, 2]] - p[h[:, 0]],
                                             c - p[h[:, 0]]], axis=1)) < 0),
              name + ": a hull face is not oriented outward")
        check(np.array_equal(t.points, p), name + ": points are not the input")
        qs = q.simplices.copy()  # qhull's orientation varies: make each positive
        neg = orient(p, *qs.T) < 0
        qs[neg, 0], qs[neg, 1] = q.simplices[neg, 1], q.simplices[neg, 0]
        check(frontdt.check(p, qs) is None, name + ": check() refused scipy's mesh")
        t.check()


def test_faces():
    rng = np.random.default_rng(5)
    p = rng.random((1500, 3))
    t = frontdt.delaunay(p)
    f, ft, s = t.faces, t.face_tets, t.simplices
    T, H = len(s), len(t.convex_hull)
    check(f.shape == (len(ft), 3) and ft.shape[1] == 2 and f.dtype == np.int32
          and ft.dtype == np.int64, "faces int32 (f, 3), face_tets int64 (f, 2)")
    check(len(f) == (4 * T + H) // 2, "faces: %d, expected (4T + H) / 2" % len(f))
    all_faces = set()
    for tet in s.tolist():
        for k in range(4):
            all_faces.add(tuple(sorted(tet[:k] + tet[k + 1:])))
    check(tetset(f) == all_faces and len(tetset(f)) == len(f), "faces: not every face once")
    apex = [next(v for v in s[a] if v not in fr) for fr, a in zip(f.tolist(), ft[:, 0])]
    check(np.all(orient(p, f[:, 0], f[:, 1], f[:, 2], np.array(apex)) > 0),
          "faces: face_tets[:, 0] is not on the positive side")
    hull = ft[:, 1] < 0
    check(hull.sum() == H and tetset(f[hull]) == tetset(t.convex_hull),
          "faces: the -1 faces are not the hull")
    for fr, (a, b) in zip(f[~hull].tolist(), ft[~hull].tolist()):
        if not (set(fr) < set(s[a].tolist()) and set(fr) < set(s[b].tolist())):
            check(False, "faces: face %s is not in tets %d and %d" % (fr, a, b))
            break
    e = t.edges
    check(e.shape[1] == 2 and np.all(e[:, 0] < e[:, 1]), "edges: (a, b) with a < b")
    nb = t.vertex_neighbors(7)
    check(set(nb.tolist()) == set(e[e[:, 0] == 7, 1].tolist()) | set(e[e[:, 1] == 7, 0].tolist()),
          "vertex_neighbors(7) is not the edges at 7")
    check(raises(IndexError, t.vertex_neighbors, 1500) is not None, "vertex_neighbors(n) not refused")


def cli_hash(path):
    out = subprocess.run([FRONTDT, path, "--hash", "--quiet"], capture_output=True,
                         text=True, check=True).stdout
    return next(line.split()[1] for line in out.splitlines() if line.startswith("hash:"))


def test_cli_degenerate(tmp):
    for fam, n in [("lattice", 1000), ("dup", 2000), ("intsphere", 400), ("grid2d", 800),
                   ("sphere", 600), ("dupheavy", 1000), ("cylinder", 1500)]:
        path = os.path.join(tmp, fam + ".xyz")
        subprocess.run([GEN_POINTS, fam, str(n), "3", path], check=True)
        p = np.loadtxt(path, ndmin=2)
        t = frontdt.delaunay(p)
        check(t.hash == cli_hash(path), "%s: hash %s, CLI %s" % (fam, t.hash, cli_hash(path)))
        t.check()
        # the duplicate map: each point's first index with equal coordinates
        first = {}
        want = np.array([first.setdefault(tuple(r), i) for i, r in
                         enumerate((p + 0.0).tolist())])  # -0 = +0
        check(np.array_equal(t.duplicates, want), fam + ": duplicate map")
        check(t.stats["duplicates"] == int(np.sum(want != np.arange(len(p)))) and
              t.stats["vertices"] == len(first), fam + ": stats duplicates/vertices")
        check(np.isin(t.simplices, np.nonzero(want == np.arange(len(p)))[0]).all(),
              fam + ": a tet uses a merged duplicate")


def test_errors():
    rng = np.random.default_rng(3)
    p = rng.random((10, 3))
    bad = p.copy()
    bad[3, 1] = np.nan
    m = raises(ValueError, frontdt.delaunay, bad)
    check(m is not None and "point 3" in m, "NaN: ValueError naming point 3 (%r)" % m)
    bad[3, 1] = np.inf
    check(raises(ValueError, frontdt.delaunay, bad) is not None, "Inf: ValueError")
    m = raises(ValueError, frontdt.delaunay, p[:3])
    check(m is not None and "3 distinct" in m, "3 points: ValueError (%r)" % m)
    check(raises(ValueError, frontdt.delaunay, np.repeat(p[:3], 5, axis=0)) is not None,
          "15 points, 3 distinct: ValueError")
    flat = np.c_[p[:, :2], np.full(10, 0.5)]
    m = raises(ValueError, frontdt.delaunay, flat)
    check(m is not None and "coplanar" in m, "coplanar: ValueError (%r)" % m)
    m = raises(ValueError, frontdt.delaunay, np.outer(np.arange(6.0), [1, 2, 3]))
    check(m is not None and "collinear" in m, "collinear: ValueError (%r)" % m)
    for shape in [(10, 2), (10,), (2, 5, 3), (10, 4), (0, 3)]:
        check(raises(ValueError, frontdt.delaunay, np.zeros(shape)) is not None,
              "shape %s: ValueError" % (shape,))
    check(raises(ValueError, frontdt.delaunay, [[1, 2], [3, 4, 5]]) is not None, "ragged: ValueError")
    check(raises((ValueError, TypeError), frontdt.delaunay, [["a", "b", "c"]] * 5) is not None,
          "strings refused")
    check(raises(TypeError, frontdt.delaunay, p.astype(complex)) is not None, "complex: TypeError")
    for kw, exc in [({"mode": "fast"}, ValueError), ({"search": "bsp"}, ValueError),
                    ({"threads": 0}, ValueError), ({"threads": -2}, ValueError),
                    ({"threads": 5000}, ValueError), ({"threads": "2"}, TypeError)]:
        check(raises(exc, frontdt.delaunay, p, **kw) is not None, "%s: %s" % (kw, exc.__name__))
    # check(): a mesh with a tet missing, a flipped tet, wrong neighbours
    t = frontdt.delaunay(rng.random((200, 3)))
    s = np.array(t.simplices)
    check(raises(frontdt.CheckError, frontdt.check, t.points, s[1:]) is not None,
          "check: a missing tet not found")
    s2 = s.copy()
    s2[0, [0, 1]] = s2[0, [1, 0]]
    check(raises(frontdt.CheckError, frontdt.check, t.points, s2) is not None,
          "check: a flipped tet not found")
    nb = np.array(t.neighbors)
    nb[0, 0] = -1 if nb[0, 0] >= 0 else 1
    check(raises(frontdt.CheckError, frontdt.check, t.points, s, nb) is not None,
          "check: a wrong neighbour not found")
    check(frontdt.check(t.points, s, t.neighbors) is None, "check: the mesh itself refused")
    check(issubclass(frontdt.CheckError, RuntimeError), "CheckError is a RuntimeError")


def test_threads():
    p = np.random.default_rng(11).random((20000, 3))
    ref = frontdt.delaunay(p, threads=1, mode="serial")
    check(ref.stats["mode"] == "serial" and ref.stats["threads"] == 1 and
          ref.stats["engine"] == "one-part", "serial stats")
    for kw in [{"threads": 2}, {"threads": 2, "mode": "shared"}, {"threads": 2, "mode": "message"},
               {"threads": 3, "mode": "shared", "search": "mesh"}, {"search": "kd"}]:
        t = frontdt.delaunay(p, **kw)
        check(t.hash == ref.hash, "%s: hash %s, serial %s" % (kw, t.hash, ref.hash))
        check(np.array_equal(t.simplices, ref.simplices) and
              np.array_equal(t.neighbors, ref.neighbors),
              "%s: canonical arrays differ from serial" % kw)
    t = frontdt.delaunay(p, threads=2, mode="shared")
    check(t.stats["threads"] == 2 and t.stats["mode"] == "shared" and
          t.stats["engine"] in ("parts", "parts-mesh"), "threads=2 shared ran on 2 threads")


def test_gil_and_interrupt():
    p = np.random.default_rng(23).random((300000, 3))
    count = [0]
    stop = threading.Event()

    def counter():
        while not stop.is_set():
            count[0] += 1

    t0 = time.monotonic()
    frontdt.delaunay(p, threads=1)
    t_plain = time.monotonic() - t0
    th = threading.Thread(target=counter)
    th.start()
    # the counter's rate with the main thread asleep (GIL free)
    c0, t0 = count[0], time.monotonic()
    time.sleep(0.3)
    free_rate = (count[0] - c0) / (time.monotonic() - t0)
    c0, t0 = count[0], time.monotonic()
    t = frontdt.delaunay(p, threads=1)
    dt, c1 = time.monotonic() - t0, count[0]
    stop.set()
    th.join()
    # Held GIL: the counter runs only in switch intervals (5 ms) around the
    # call and when the progress callback looks for signals: 274k
    # increments in a 5.2 s run against 32M with the GIL released.
    print("GIL: %d increments in the other thread during a %.2f s triangulation "
          "(%.0f a second with the GIL free)" % (c1 - c0, dt, free_rate))
    check(c1 - c0 > 0.1 * free_rate * dt,
          "the GIL is not released: the other thread counted %d in %.2f s (free: %.0f/s)"
          % (c1 - c0, dt, free_rate))
    n_tets = len(t.simplices)
    del t

    # KeyboardInterrupt while the engine runs: canceled well before the end.
    timer = threading.Timer(0.2, _thread.interrupt_main)
    t0 = time.monotonic()
    timer.start()
    try:
        t = frontdt.delaunay(p, threads=1)
        got = "finished (%d tets)" % len(t.simplices)
    except KeyboardInterrupt:
        got = "interrupted"
    el = time.monotonic() - t0
    timer.join()
    # Without the callback's signal check the run goes to its end and the
    # interrupt is raised after it (el about t_plain).
    print("interrupt: %s after %.2f s (a whole run: %.2f s)" % (got, el, t_plain))
    check(got == "interrupted" and el < 0.2 + 0.5 * t_plain,
          "KeyboardInterrupt did not cancel: %s after %.2f s of %.2f s" % (got, el, t_plain))
    check(n_tets > 0, "the GIL run built tets")


def rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def test_lifetime_and_memory():
    p = np.random.default_rng(31).random((10000, 3))
    s = frontdt.delaunay(p).simplices  # the Triangulation goes, its view stays
    gc.collect()
    junk = [np.ones(len(s) * 4, dtype=np.int32) * 7 for _ in range(4)]
    check(isinstance(s.base, frontdt.Triangulation), "simplices' base is the Triangulation")
    check(not s.flags.writeable, "simplices are read-only")
    check(frontdt.check(p, s) is None, "a view outliving its Triangulation changed")
    del junk
    for name in ["simplices", "neighbors", "convex_hull", "duplicates", "faces", "face_tets",
                 "edges", "points"]:
        t = frontdt.delaunay(p[:500])
        a = getattr(t, name)
        copy = np.array(a)
        del t
        gc.collect()
        junk = [np.full(copy.size + 64, 3, dtype=copy.dtype) for _ in range(8)]
        check(a.size > 0 and np.array_equal(a, copy) and not a.flags.writeable,
              name + ": view changed after its Triangulation went")
        del junk
    del s

    # A leak of one result (about 48 bytes a tet: 66k tets) would add 3 MB
    # a run, of the copied points 0.24 MB; errors leak nothing either.
    def one():
        t = frontdt.delaunay(p)
        t.faces, t.edges, t.stats, t.hash, t.vertex_neighbors(3)
        t.check()
        raises(ValueError, frontdt.delaunay, np.r_[p, [[np.nan, 0, 0]]])
        raises(ValueError, frontdt.delaunay, p[:3])
        frontdt.check(p, t.simplices)

    for _ in range(5):
        one()
    gc.collect()
    r0 = rss_bytes()
    runs = 25
    for _ in range(runs):
        one()
    gc.collect()
    grew = rss_bytes() - r0
    print("RSS grew %.1f MB over %d runs after 5 warm-up runs" % (grew / 2**20, runs))
    check(grew < 16 * 2**20, "RSS grew %.1f MB over %d runs" % (grew / 2**20, runs))


def test_voronoi():
    """frontdt.voronoi: the volumes fill the box; the DTFE densities equal
    4 / (the volumes of each point's tets) computed here from simplices; the
    CSR lists are each face seen from both sides; the same bits for a
    shuffled input and 1 or 3 threads; a box not holding a point raises."""
    rng = np.random.default_rng(11)
    pts = rng.random((3000, 3))
    box = (-0.5, 0.0, 0.0, 1.0, 1.25, 1.0)
    t = frontdt.delaunay(pts, threads=1)
    c = t.voronoi(box)
    check(abs(c["volumes"].sum() / (1.5 * 1.25) - 1) < 1e-12, "voronoi: volumes fill the box")
    s = t.simplices
    p = pts[s]
    vol = np.abs(np.einsum("ij,ij->i", p[:, 1] - p[:, 0],
                           np.cross(p[:, 2] - p[:, 0], p[:, 3] - p[:, 0]))) / 6
    per = np.zeros(len(pts))
    for k in range(4):
        np.add.at(per, s[:, k], vol)
    check(np.allclose(c["densities"], 4 / per, rtol=1e-12, atol=0), "voronoi: DTFE densities")
    ptr, nb, fa = c["neighbor_ptr"], c["neighbors"], c["face_areas"]
    check(ptr[-1] == len(nb) == len(fa) and np.all(np.diff(ptr) == c["num_faces"]),
          "voronoi: CSR shape")
    faces = {}
    for i in range(len(pts)):
        for j, a in zip(nb[ptr[i]:ptr[i + 1]], fa[ptr[i]:ptr[i + 1]]):
            if j >= 0:
                faces[(i, int(j))] = a
    ar = c["areas"]
    check(all(abs(a - faces.get((j, i), -1)) <= 1e-10 * max(ar[i], ar[j])
              for (i, j), a in faces.items()),
          "voronoi: each face has one area from both sides (to 1e-10 of the cells' surface)")
    check(np.allclose(c["areas"], np.add.reduceat(fa, ptr[:-1]), rtol=1e-12),
          "voronoi: the faces add up to the surface")
    perm = rng.permutation(len(pts))
    c3 = frontdt.voronoi(pts, box, threads=3)
    cs = frontdt.voronoi(pts[perm], box, threads=2)
    check(np.array_equal(c3["volumes"], c["volumes"]), "voronoi: same bits at 3 threads")
    check(np.array_equal(cs["volumes"], c["volumes"][perm]) and
          np.array_equal(cs["centroids"], c["centroids"][perm]),
          "voronoi: same bits for a shuffled input")
    lean = frontdt.voronoi(pts, box, threads=2, centroids=False, densities=False)
    check(lean["centroids"] is None and lean["densities"] is None and
          all(np.array_equal(lean[k], c[k]) for k in ("volumes", "areas", "num_faces", "flags",
                                                       "neighbor_ptr", "neighbors",
                                                       "face_areas")),
          "voronoi: without centroids and densities, the rest the same bits")
    raises(ValueError, t.voronoi, (0, 0, 0, 1, 1, 0.5))
    raises(ValueError, t.voronoi, (0, 0, 0, 1, 1))


def test_interpolation():
    """find_simplex against scipy's (the same tets for random points: the
    Delaunay mesh is unique), barycentric coordinates, and both methods
    reproducing a linear function; linear against scipy's
    LinearNDInterpolator; NaN outside; refusals."""
    rng = np.random.default_rng(5)
    pts = rng.random((2000, 3))
    q = rng.random((400, 3)) * 1.2 - 0.1
    t = frontdt.delaunay(pts, threads=2)
    idx, bary = t.find_simplex(q, bary=True)
    inside = idx >= 0
    check(inside.sum() > 100 and (~inside).sum() > 10, "find_simplex: inside and outside queries")
    check(np.allclose(np.einsum("kv,kvd->kd", bary[inside], pts[t.simplices[idx[inside]]]),
                      q[inside], atol=1e-12), "find_simplex: barycentric coordinates rebuild q")
    try:
        import scipy.spatial
        import scipy.interpolate
        sd = scipy.spatial.Delaunay(pts)
        si = sd.find_simplex(q)
        check(np.array_equal(si >= 0, inside), "find_simplex: inside the hull as scipy says")
        same = [set(t.simplices[a]) == set(sd.simplices[b]) for a, b in zip(idx[inside],
                                                                             si[inside])]
        check(all(same), "find_simplex: the tet scipy finds")
        f = np.sin(3 * pts[:, 0]) + pts[:, 1] * pts[:, 2]
        ours = t.interpolate(f, q, method="linear")
        theirs = scipy.interpolate.LinearNDInterpolator(sd, f)(q)
        check(np.array_equal(np.isnan(ours), np.isnan(theirs)) and
              np.allclose(ours[inside], theirs[inside], rtol=0, atol=1e-12),
              "interpolate linear: scipy's LinearNDInterpolator's values")
    except ImportError:
        print("test_interpolation: no scipy, compared with nothing")
    lin = np.c_[pts @ [1.0, -2.0, 0.5] + 3, pts[:, 2]]
    want = np.c_[q @ [1.0, -2.0, 0.5] + 3, q[:, 2]]
    for method in ("linear", "natural"):
        got = frontdt.interpolate(pts, lin, q, method=method, threads=3)
        ok = ~np.isnan(got[:, 0])
        check(ok.sum() > 100 and np.abs(got[ok] - want[ok]).max() < 1e-12,
              "interpolate %s: a linear function reproduced" % method)
        check(np.all(np.isnan(got[~inside])), "interpolate %s: NaN outside" % method)
    raises(ValueError, t.interpolate, np.zeros(5), q)
    raises(ValueError, t.interpolate, lin[:, 0], q, method="cubic")


def test_periodic(tmp):
    """periodic= and box= (issue 33): the CLI's --periodic .tets, line for
    line, from simplices and offsets; the same mesh on 1 and 3 threads; its
    cells, interpolation and point location; the argument errors."""
    rng = np.random.default_rng(8)
    pts = rng.random((1500, 3)) * [2.0, 1.0, 3.0] - [0.5, 0.0, 1.0]
    box = (-0.5, 0.0, -1.0, 1.5, 1.0, 2.0)
    t = frontdt.delaunay(pts, periodic="x,y,z", box=box)
    off = t.offsets
    check(off is not None and off.shape == (len(t.simplices), 4, 3) and off.dtype == np.int8,
          "periodic: offsets (m, 4, 3) int8")
    check(t.neighbors is None and t.stats["engine"] == "periodic" and
          t.stats["periodic_images"] > 0, "periodic: no neighbours, the engine and its images")
    path = os.path.join(tmp, "per.xyz")
    np.savetxt(path, pts, fmt="%.17g")
    out = os.path.join(tmp, "per.tets")
    r = subprocess.run([FRONTDT, path, "--periodic", "xyz", "--box", ",".join(map(repr, box)),
                        "-o", out, "--hash", "-q"], capture_output=True, text=True, check=True)
    lines = "".join(" ".join(map(str, list(s) + o.reshape(-1).tolist())) + "\n"
                    for s, o in zip(t.simplices.tolist(), off))
    check(lines == open(out).read(), "periodic: the CLI's .tets")
    check(r.stdout.strip() == "hash: " + t.hash, "periodic: the CLI's hash")
    t3 = frontdt.delaunay(pts, periodic="xyz", box=box, threads=3)
    check(np.array_equal(t3.simplices, t.simplices) and np.array_equal(t3.offsets, off),
          "periodic: 3 threads")
    check(frontdt.delaunay(pts).offsets is None, "plain: no offsets")
    check(t.check() is None, "periodic: check() passes")
    c = t.voronoi()
    check(abs(c["volumes"].sum() / 6.0 - 1) < 1e-12 and not c["flags"].any(),
          "periodic: the cells' volumes are the box's")
    c2 = frontdt.voronoi(pts, box=box, periodic="xyz")
    check(np.array_equal(c2["volumes"], c["volumes"]), "frontdt.voronoi(periodic=)")
    # periodic in x and z: the walls y = 0 and y = 1 (the box's) cut the cells
    wy = pts.copy()
    wy[0::4, 1] = 0.0
    wy[1::4, 1] = 1.0
    tw = frontdt.delaunay(wy, periodic="x,z", box=box)
    cw = tw.voronoi()
    check(abs(cw["volumes"].sum() / 6.0 - 1) < 1e-12 and
          np.array_equal(cw["flags"] & 2 != 0, np.arange(len(wy)) % 4 < 2),
          "periodic x,z: the cells' volumes are the box's, the walls' points on the hull")
    check(raises(ValueError, tw.voronoi, box=(0, 0, 0, 1, 1, 1)) is not None,
          "periodic: cells in another box refused")
    check(tw.check() is None, "periodic x,z: check() passes")
    # interpolation, both methods: a query and its translate by whole
    # periods alike, the same bits on 1 and 3 threads, a constant kept
    vals = np.stack([rng.random(len(pts)), np.full(len(pts), 2.5)], axis=1)
    q = rng.random((200, 3)) * [2.0, 1.0, 3.0] - [0.5, 0.0, 1.0]
    shifted = q + [2.0, -1.0, 6.0]
    for method in ("natural", "linear"):
        a = t.interpolate(vals, q, method=method)
        check(np.allclose(a, t.interpolate(vals, shifted, method=method), rtol=0, atol=1e-12) and
              np.array_equal(a, t3.interpolate(vals, q, method=method)) and
              np.allclose(a[:, 1], 2.5, rtol=0, atol=1e-12),
              "periodic interpolate(%s): translates, threads, a constant" % method)
    check(np.array_equal(frontdt.interpolate(pts, vals, q, periodic="xyz", box=box),
                         t.interpolate(vals, q)), "frontdt.interpolate(periodic=, box=)")
    s = t.find_simplex(shifted)
    check(s.min() >= 0 and s.max() < len(t.simplices), "periodic find_simplex: a row each")
    check(raises(ValueError, frontdt.delaunay, pts, periodic="xz") is not None,
          "periodic without box")
    check(raises(ValueError, frontdt.delaunay, pts, box=box) is not None, "box without periodic")
    check(raises(ValueError, frontdt.delaunay, pts, periodic="xq", box=box) is not None,
          "periodic: a bad axis")
    m = raises(ValueError, frontdt.delaunay, pts, periodic="xyz", box=(0, 0, 0, 1, 1, 1))
    check(m is not None and "outside the periodic box" in m, "periodic: a point outside: %s" % m)


def main():
    print("frontdt", frontdt.__version__, "from", frontdt._frontdt.__file__)
    with tempfile.TemporaryDirectory() as tmp:
        for test in [test_origin, test_scipy, test_faces, lambda: test_cli_degenerate(tmp),
                     test_errors, test_threads, test_gil_and_interrupt,
                     test_lifetime_and_memory, test_voronoi, test_interpolation,
                     lambda: test_periodic(tmp)]:
            t0 = time.monotonic()
            test()
            print("%s: %.1f s" % (getattr(test, "__name__", "?"), time.monotonic() - t0),
                  flush=True)
    if FAILS:
        print("%d check(s) failed" % len(FAILS))
        return 1
    print("all checks passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
