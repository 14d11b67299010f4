#!/usr/bin/env python3
"""Reads INDEX.pvtu through VTK's own reader (as ParaView does) and checks
that its tets, mapped back to the input's points by coordinates, are the
tets of REF.tets (frontdt's canonical text, input numbering).
Usage: pvtu_check.py INDEX.pvtu INPUT.xyz REF.tets. Exit 77 without VTK."""
import sys

try:
    from vtkmodules.vtkIOXML import vtkXMLPUnstructuredGridReader
except ImportError:
    print("skip: no python3 VTK")
    sys.exit(77)

index, inp, ref = sys.argv[1:4]
first = {}
with open(inp) as f:
    for i, line in enumerate(f):
        xyz = tuple(float(v) for v in line.split()[:3])
        first.setdefault(xyz, i)  # duplicates: the first input index
r = vtkXMLPUnstructuredGridReader()
r.SetFileName(index)
r.Update()
g = r.GetOutput()
pts = g.GetPoints()
got = set()
for c in range(g.GetNumberOfCells()):
    cell = g.GetCell(c)
    if cell.GetCellType() != 10:
        sys.exit(f"cell {c}: type {cell.GetCellType()}, not a tetrahedron")
    ids = cell.GetPointIds()
    got.add(tuple(sorted(first[tuple(pts.GetPoint(ids.GetId(k)))] for k in range(4))))
want = set()
with open(ref) as f:
    for line in f:
        want.add(tuple(sorted(int(v) for v in line.split())))
if g.GetNumberOfCells() != len(want) or got != want:
    sys.exit(f"{index}: {g.GetNumberOfCells()} cells, {len(got & want)} of the {len(want)} reference tets")
print(f"{index}: {len(want)} tets, as the reference")
