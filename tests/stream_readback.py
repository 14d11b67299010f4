#!/usr/bin/python3
"""Streamed outputs against the in-memory ones, and interrupted streamed writes.

usage: stream_readback.py FRONTDT REFERENCE_MD
       stream_readback.py FRONTDT REFERENCE_MD --pieces INDEX REF
       stream_readback.py FRONTDT REFERENCE_MD --periodic-pieces INDEX INPUT REF BOX AXES

--pieces (tests/test_mpi.sh): the pieces of frontdt-mpi's -o INDEX (.pfdtb,
read with doc/reference.md's read_pieces, or .pele: the .ele/.face pieces beside
their .node) hold, all together, the tets and hull faces of the serial
run's REF.ele / REF.face, each the same way round; the index's counts and
names are those of the files; each .fdtb piece's header says piece (flag 8),
no points, the input's point count.

--periodic-pieces (tests/test_mpi.sh, issue 33): the pieces of a periodic
frontdt-mpi run hold, all together, the rows of frontdt's REF.tets of the
same INPUT, each once, normalised as .tets's are: .pfdtb pieces (flags 8 |
4 | 16) read with doc/reference.md's read_fdtb_periodic, the index's set
hash the one on stdin ("set-hash: HEX", frontdt's); a .pvtu through VTK's
own reader as ParaView reads it, each cell's points mapped to rows by their
input_id and by how many periods (BOX, AXES) they lie from that point.

1. A random point set (one duplicate point) is written by the CLI twice: in
   memory (--no-stream: .ele with .node/.face/.neigh, .vtu, .fdtb) and
   streamed (--stream, two threads: .ele with .node/.face, .vtu, .fdtb).
   Each file is parsed back (the .fdtb with the numpy reader of doc/reference.md,
   "Binary mesh", when numpy is installed, else with struct): every file
   holds the same set of tets, each the same way round (the same even
   permutation), the same hull faces, the same points (.node byte for byte,
   .vtu and .fdtb bit for bit), and the streamed and in-memory --set-hash
   agree. The .vtu is read by VTK too when its python module is there.
2. A streamed write stopped by SIGTERM while its temporaries exist: exit 6,
   no temporary left, the targets as they were.
3. A streamed write that fails (file size limit, RLIMIT_FSIZE: EFBIG):
   exit 5, no temporary left, the targets as they were.
4. --stream with an output that cannot stream: exit 1, nothing written.
"""
import os
import random
import re
import resource
import signal
import struct
import subprocess
import sys
import tempfile
import time

FRONTDT = os.path.abspath(sys.argv[1])
README = sys.argv[2]
failures = []


def fail(msg):
    failures.append(msg)
    print("FAIL: " + msg)


def run(args, **kw):
    return subprocess.run([FRONTDT] + args, capture_output=True, text=True, **kw)


def canon_tet(t):
    """(sorted ids, parity of the permutation that sorts t)."""
    t = list(t)
    parity = 0
    for i in range(4):
        for j in range(i + 1, 4):
            if t[i] > t[j]:
                parity ^= 1
    return (tuple(sorted(t)), parity)


def canon_face(f):
    """The rotation that starts at the smallest id (keeps the orientation)."""
    f = list(f)
    k = f.index(min(f))
    return tuple(f[k:] + f[:k])


def read_table(path, k):
    with open(path) as fh:
        first = fh.readline().split()
        count = int(first[0])
        rows = [tuple(int(x) for x in line.split()[1:1 + k]) for line in fh]
    if count != len(rows):
        fail("%s: header says %d rows, %d found" % (path, count, len(rows)))
    for i, line in enumerate(open(path).read().splitlines()[1:]):
        if int(line.split()[0]) != i:
            fail("%s: row %d numbered %s" % (path, i, line.split()[0]))
            break
    return rows


def read_vtu(path):
    data = open(path, "rb").read()
    head = data[:data.index(b"_", data.index(b"<AppendedData")) + 1].decode()
    m = re.search(r'NumberOfPoints="(\d+)" NumberOfCells="(\d+)"', head)
    n, nt = int(m.group(1)), int(m.group(2))
    offs = [int(x) for x in re.findall(r'offset="(\d+)"', head)]
    base = len(head)

    def array(i, fmt, size):
        at = base + offs[i]
        (nbytes,) = struct.unpack_from("<Q", data, at)
        if nbytes != size * struct.calcsize(fmt):
            fail("%s: array %d holds %d bytes, %d expected" % (path, i, nbytes, size))
        return struct.unpack_from("<%d%s" % (size, fmt), data, at + 8)

    pts = array(0, "d", 3 * n)
    conn = array(1, "q", 4 * nt)
    off = array(2, "q", nt)
    types = array(3, "B", nt)
    if list(off) != [4 * (i + 1) for i in range(nt)] or set(types) - {10}:
        fail("%s: offsets or types wrong" % path)
    if not data.endswith(b"</VTKFile>\n"):
        fail("%s: no closing tag" % path)
    return pts, [conn[4 * i:4 * i + 4] for i in range(nt)]


def readme_reader(name="read_fdtb"):
    text = open(README).read()
    m = re.search(r"<!-- fdtb-reader[^>]*-->\n```python\n(.*?)```", text, re.S)
    mp = re.search(r"<!-- fdtb-pieces-reader[^>]*-->\n```python\n(.*?)```", text, re.S)
    mq = re.search(r"<!-- fdtb-periodic-reader[^>]*-->\n```python\n(.*?)```", text, re.S)
    if not m or not mp or not mq:
        fail(README + " has no fdtb-reader, fdtb-pieces-reader or fdtb-periodic-reader block")
        return None
    if max(len(x.group(1).splitlines()) for x in (m, mp, mq)) > 20:
        fail(README + ": an fdtb reader is over 20 lines")
    try:
        import numpy  # noqa: F401
    except ImportError:
        print("numpy not installed: the .fdtb is read with struct")
        return None
    env = {}
    exec(m.group(1), env)
    exec(mp.group(1), env)
    exec(mq.group(1), env)
    return env[name]


def read_fdtb(path, numpy_reader):
    if numpy_reader:
        pts, tets, hull = numpy_reader(path)
        return ([float(x) for x in pts.reshape(-1)], [tuple(int(x) for x in t) for t in tets],
                [tuple(int(x) for x in f) for f in hull])
    data = open(path, "rb").read()
    magic, version, flags, n, nt, nh = struct.unpack_from("<8sIIQQQ", data, 0)
    if magic != b"FDTMESH\0" or version != 1 or flags != 6:
        fail("%s: header %r %d %d" % (path, magic, version, flags))
    at = 64
    pts = struct.unpack_from("<%dd" % (3 * n), data, at)
    at += 24 * n
    ids = struct.unpack_from("<%di" % (4 * nt), data, at)
    at += 16 * nt
    hull = struct.unpack_from("<%di" % (3 * nh), data, at)
    if at + 12 * nh != len(data):
        fail("%s: %d bytes, %d expected" % (path, len(data), at + 12 * nh))
    return (list(pts), [ids[4 * i:4 * i + 4] for i in range(nt)],
            [hull[3 * i:3 * i + 3] for i in range(nh)])


def set_hash(out):
    m = re.search(r"set-hash: ([0-9a-f]{16})", out)
    return m.group(1) if m else None


def listing(d):
    return sorted(os.listdir(d))


def snapshot(d):
    return {f: open(os.path.join(d, f), "rb").read() for f in listing(d)}


def compare(tmp):
    rnd = random.Random(1992)
    pts = [(rnd.random(), rnd.random(), rnd.random()) for _ in range(3000)]
    pts.append(pts[17])  # a duplicate: merged, still an output point
    xyz = os.path.join(tmp, "p.xyz")
    with open(xyz, "w") as fh:
        for p in pts:
            fh.write("%r %r %r\n" % p)
    m, s = os.path.join(tmp, "m"), os.path.join(tmp, "s")
    rm = run([xyz, "--no-stream", "-t", "1", "-o", m + ".ele", "-o", m + ".vtu",
              "-o", m + ".fdtb", "--set-hash"])
    rs = run([xyz, "--stream", "-t", "2", "-o", s + ".ele", "-o", s + ".vtu",
              "-o", s + ".fdtb", "--set-hash"])
    if rm.returncode or rs.returncode:
        fail("runs failed: %s %s" % (rm.stderr, rs.stderr))
        return
    if set_hash(rm.stdout) is None or set_hash(rm.stdout) != set_hash(rs.stdout):
        fail("set hashes differ: %s / %s" % (set_hash(rm.stdout), set_hash(rs.stdout)))
    if os.path.exists(s + ".neigh"):
        fail("a streamed .ele wrote a .neigh")
    if open(m + ".node", "rb").read() != open(s + ".node", "rb").read():
        fail(".node files differ")
    ref = read_table(m + ".ele", 4)
    ref_set = set(canon_tet(t) for t in ref)
    ref_hull = set(canon_face(f) for f in read_table(m + ".face", 3))
    if len(ref_set) != len(ref) or not ref:
        fail("in-memory .ele has repeated tets or none")
    flat = [c for p in pts for c in p]
    numpy_reader = readme_reader()
    meshes = {"s.ele": (None, read_table(s + ".ele", 4), read_table(s + ".face", 3))}
    for tag, base in (("m", m), ("s", s)):
        vp, vt = read_vtu(base + ".vtu")
        meshes[tag + ".vtu"] = (vp, vt, None)
        meshes[tag + ".fdtb"] = read_fdtb(base + ".fdtb", numpy_reader)
    for name, (p, tets, hull) in meshes.items():
        if sorted(canon_tet(t) for t in tets) != sorted(ref_set):
            fail("%s: not the in-memory tets (or not the same way round)" % name)
        if hull is not None and sorted(canon_face(f) for f in hull) != sorted(ref_hull):
            fail("%s: not the in-memory hull" % name)
        if p is not None and list(p) != flat:
            fail("%s: points differ from the input" % name)
    try:
        import vtk
    except ImportError:
        print("vtk not installed: the .vtu is not read by VTK")
        return
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(s + ".vtu")
    reader.Update()
    g = reader.GetOutput()
    if g.GetNumberOfCells() != len(ref) or g.GetNumberOfPoints() != len(pts):
        fail("VTK reads %d cells, %d points" % (g.GetNumberOfCells(), g.GetNumberOfPoints()))


def periodic(tmp):
    """A periodic .fdtb (flag 16) read back with doc/reference.md's reader:
    the .tets rows (ids and offsets), the points, the periods."""
    reader = readme_reader("read_fdtb_periodic")
    if reader is None:
        return
    rnd = random.Random(33)
    pts = [(2 * rnd.random(), rnd.random(), 0.5 * rnd.random()) for _ in range(800)]
    xyz, base = os.path.join(tmp, "per.xyz"), os.path.join(tmp, "per")
    with open(xyz, "w") as fh:
        for p in pts:
            fh.write("%r %r %r\n" % p)
    r = run([xyz, "--periodic", "xyz", "--box", "0,0,0,2,1,0.5", "-o", base + ".tets",
             "-o", base + ".fdtb"])
    if r.returncode:
        fail("periodic run failed: %s" % r.stderr)
        return
    p, tets, hull, toff, hoff, periods = reader(base + ".fdtb")
    rows = ["%s\n" % " ".join(map(str, list(t) + list(o.reshape(-1))))
            for t, o in zip(tets.tolist(), toff)]
    if "".join(rows) != open(base + ".tets").read():
        fail("periodic .fdtb: its rows are not the .tets lines")
    if [tuple(x) for x in p.tolist()] != pts or list(periods) != [2.0, 1.0, 0.5]:
        fail("periodic .fdtb: points or periods %r" % list(periods))
    if len(hull) or hoff.shape != (0, 3, 3):
        fail("periodic .fdtb: %d hull faces in a set periodic on every axis" % len(hull))


def interrupted(tmp):
    d = os.path.join(tmp, "sig")
    os.mkdir(d)
    for name in ("x.vtu", "x.fdtb", "x.ele"):
        with open(os.path.join(d, name), "w") as fh:
            fh.write("old %s\n" % name)
    before = snapshot(d)
    # large enough that the run is still going when its temporaries appear
    p = subprocess.Popen([FRONTDT, "--demo", "400000", "-q", "--stream", "-t", "1",
                          "-o", os.path.join(d, "x.vtu"), "-o", os.path.join(d, "x.fdtb"),
                          "-o", os.path.join(d, "x.ele")],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.time() + 60
    seen = False
    while time.time() < deadline and p.poll() is None:
        if any(".tmp." in f for f in listing(d)):
            seen = True
            break
        time.sleep(0.005)
    if not seen:
        p.kill()
        p.wait()
        fail("signal: no temporary seen before the run ended (rc %s)" % p.returncode)
        return
    time.sleep(0.2)
    p.send_signal(signal.SIGTERM)
    rc = p.wait()
    if rc != 6:
        fail("signal: exit %d, 6 expected" % rc)
    if snapshot(d) != before:
        fail("signal: files changed or left: %s" % listing(d))


def write_fails(tmp):
    d = os.path.join(tmp, "full")
    os.mkdir(d)
    with open(os.path.join(d, "y.fdtb"), "w") as fh:
        fh.write("old\n")
    before = snapshot(d)

    def limit():
        resource.setrlimit(resource.RLIMIT_FSIZE, (200000, 200000))

    r = subprocess.run([FRONTDT, "--demo", "20000", "-q", "--stream",
                        "-o", os.path.join(d, "y.fdtb"), "-o", os.path.join(d, "y.vtu")],
                       capture_output=True, text=True, preexec_fn=limit)
    if r.returncode != 5:
        fail("size limit: exit %d, 5 expected (%s)" % (r.returncode, r.stderr.strip()))
    if snapshot(d) != before:
        fail("size limit: files changed or left: %s" % listing(d))


def refused(tmp):
    d = os.path.join(tmp, "ref")
    os.mkdir(d)
    for out, opt in ((os.path.join(d, "z.tets"), []), (os.path.join(d, "z.vtu"), ["--check"]),
                     (os.path.join(d, "z.vtu"), ["--hash"]), ("-", [])):
        r = run(["--demo", "100", "-q", "--stream", "-o", out] + opt)
        if r.returncode != 1 or "--stream" not in r.stderr:
            fail("--stream -o %s %s: exit %d (%s)" % (out, opt, r.returncode, r.stderr.strip()))
    if listing(d):
        fail("refused runs left %s" % listing(d))


def index_lines(index):
    """The text index: (fields, [(name, tets, hull)])."""
    keys, pieces = {}, []
    lines = open(index).read().splitlines()
    if not lines or lines[0] != "frontdt-pieces 1":
        fail("%s: first line %r" % (index, lines[:1]))
    for line in lines[1:]:
        key, _, val = line.partition(" ")
        if key == "piece":
            name, nt, nh = val.rsplit(" ", 2)
            pieces.append((name, int(nt), int(nh)))
        else:
            keys[key] = val
    return keys, pieces


def pieces(index, ref):
    """--pieces: the mesh of frontdt-mpi's pieces against the serial run's."""
    keys, plist = index_lines(index)
    d = os.path.dirname(index)
    ref_tets = read_table(ref + ".ele", 4)
    ref_hull = read_table(ref + ".face", 3)
    npoints = int(open(ref + ".node").readline().split()[0])
    if int(keys.get("points", -1)) != npoints or int(keys.get("ranks", 0)) != len(plist):
        fail("%s: points %s, ranks %s for %d pieces (input %d points)"
             % (index, keys.get("points"), keys.get("ranks"), len(plist), npoints))
    tt, th = (int(x) for x in keys.get("total", "-1 -1").split())
    if (tt, th) != (sum(p[1] for p in plist), sum(p[2] for p in plist)) or tt != len(ref_tets):
        fail("%s: total %d %d; pieces %d, serial %d tets"
             % (index, tt, th, sum(p[1] for p in plist), len(ref_tets)))
    if not re.fullmatch(r"[0-9a-f]{16}", keys.get("set-hash", "")):
        fail("%s: no set-hash line" % index)
    tets, hull = [], []
    if keys.get("format") == "fdtb":
        for name, nt, nh in plist:
            head = open(os.path.join(d, name), "rb").read(64)
            magic, version, flags, n, cnt_t, cnt_h = struct.unpack_from("<8sIIQQQ", head, 0)
            if magic != b"FDTMESH\0" or version != 1 or flags != 12 or n != npoints \
                    or (cnt_t, cnt_h) != (nt, nh):
                fail("%s: header %r %d flags %d points %d counts %d %d" %
                     (name, magic, version, flags, n, cnt_t, cnt_h))
        reader = readme_reader("read_pieces")
        if reader:
            t, h, rkeys = reader(index)
            if rkeys.get("set-hash") != keys.get("set-hash"):
                fail("the documented read_pieces: fields %r" % rkeys)
            tets = [tuple(int(x) for x in r) for r in t]
            hull = [tuple(int(x) for x in r) for r in h]
        else:
            for name, nt, nh in plist:
                data = open(os.path.join(d, name), "rb").read()
                ids = struct.unpack_from("<%di" % (4 * nt + 3 * nh), data, 64)
                if 64 + 4 * len(ids) != len(data):
                    fail("%s: %d bytes" % (name, len(data)))
                tets += [ids[4 * i:4 * i + 4] for i in range(nt)]
                hull += [ids[4 * nt + 3 * i:4 * nt + 3 * i + 3] for i in range(nh)]
    elif keys.get("format") == "ele":
        node = os.path.join(d, keys.get("node", ""))
        if open(node, "rb").read() != open(ref + ".node", "rb").read():
            fail("%s: not the serial run's .node, byte for byte" % node)
        for name, nt, nh in plist:
            t = read_table(os.path.join(d, name), 4)
            h = read_table(os.path.join(d, name[:-4] + ".face"), 3)
            if (len(t), len(h)) != (nt, nh):
                fail("%s: %d tets, %d faces; the index says %d, %d" % (name, len(t), len(h),
                                                                    nt, nh))
            tets += t
            hull += h
    else:
        fail("%s: format %r" % (index, keys.get("format")))
    if sorted(canon_tet(t) for t in tets) != sorted(canon_tet(t) for t in ref_tets):
        fail("%s: the pieces' tets are not the serial run's (or not the same way round)" % index)
    if sorted(canon_face(f) for f in hull) != sorted(canon_face(f) for f in ref_hull):
        fail("%s: the pieces' hull faces are not the serial run's" % index)


def row_line(ids, offs):
    """A periodic row as a .tets line: ids ascending, then the offsets
    relative to the least one's."""
    order = sorted(range(len(ids)), key=lambda i: ids[i])
    parts = [str(ids[i]) for i in order]
    for i in order:
        parts += [str(offs[i][k] - offs[order[0]][k]) for k in range(3)]
    return " ".join(parts)


def periodic_pieces(index, inp, ref, box, axes):
    """--periodic-pieces: a periodic run's pieces against frontdt's rows."""
    rows = []
    if index.endswith(".pfdtb"):
        keys, plist = index_lines(index)
        reader = readme_reader("read_fdtb_periodic")
        if reader is None:
            return
        for name, nt, nh in plist:
            path = os.path.join(os.path.dirname(index), name)
            flags = struct.unpack_from("<I", open(path, "rb").read(16), 12)[0]
            _, tets, hull, toff, _, _ = reader(path)
            if flags != 28 or (len(tets), len(hull)) != (nt, nh):
                fail("%s: flags %d, %d tets %d hull faces" % (name, flags, len(tets), len(hull)))
            for t, o in zip(tets.tolist(), toff.tolist()):
                line = row_line(t, o)
                if line.split()[:4] != [str(x) for x in t] or line.split()[4:7] != ["0"] * 3:
                    fail("%s: a row not normalised as .tets's: %r" % (name, line))
                rows.append(line)
        if sum(p[1] for p in plist) != int(keys.get("total", "-1 -1").split()[0]):
            fail("%s: the total is not the pieces' sum" % index)
        m = re.search(r"set-hash: ([0-9a-f]{16})", sys.stdin.read())
        if not m or keys.get("set-hash") != m.group(1):
            fail("%s: set-hash %r, frontdt's %r" % (index, keys.get("set-hash"),
                                                    m and m.group(1)))
    else:
        try:
            from vtkmodules.vtkIOXML import vtkXMLPUnstructuredGridReader
        except ImportError:
            print("no python3 VTK: the .pvtu is not read")
            return
        pts = [tuple(float(v) for v in line.split()[:3]) for line in open(inp)]
        period = [box[k + 3] - box[k] if k in axes else 0 for k in range(3)]
        r = vtkXMLPUnstructuredGridReader()
        r.SetFileName(index)
        r.Update()
        g = r.GetOutput()
        src = g.GetPointData().GetArray("input_id")
        if src is None:
            fail("%s: no input_id point data" % index)
            return
        for c in range(g.GetNumberOfCells()):
            ids, offs = [], []
            for k in range(4):
                p = g.GetCell(c).GetPointIds().GetId(k)
                i, x = int(src.GetValue(p)), g.GetPoint(p)
                ids.append(i)
                offs.append([round((x[a] - pts[i][a]) / period[a]) if period[a] else 0
                             for a in range(3)])
            rows.append(row_line(ids, offs))
    want = open(ref).read().splitlines()
    if sorted(rows, key=lambda l: [int(x) for x in l.split()]) != want:
        fail("%s: %d rows, %d of frontdt's %d" % (index, len(rows), len(set(rows) & set(want)),
                                                    len(want)))


if len(sys.argv) == 9 and sys.argv[3] == "--periodic-pieces":
    periodic_pieces(sys.argv[4], sys.argv[5], sys.argv[6],
                    [float(v) for v in sys.argv[7].split(",")],
                    {"xyz".index(a) for a in sys.argv[8] if a in "xyz"})
    if failures:
        sys.exit(1)
    print("stream_readback --periodic-pieces: all checks passed")
    sys.exit(0)

if len(sys.argv) == 6 and sys.argv[3] == "--pieces":
    pieces(sys.argv[4], sys.argv[5])
    if failures:
        sys.exit(1)
    print("stream_readback --pieces: all checks passed")
    sys.exit(0)

with tempfile.TemporaryDirectory() as tmp:
    compare(tmp)
    periodic(tmp)
    interrupted(tmp)
    write_fails(tmp)
    refused(tmp)
if failures:
    sys.exit(1)
print("stream_readback: all checks passed")
