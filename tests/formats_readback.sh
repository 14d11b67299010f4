#!/bin/sh
# The output formats read back by their own tools (issue 17, item 2):
#   - OpenFOAM's checkMesh on a polyMesh: topology (boundary definition,
#     cell-to-face addressing, point usage, upper-triangular order, face
#     vertices), face pyramids (every face's normal out of its owner) and
#     cell volumes; the geometric quality checks (aspect ratio, skewness)
#     judge the points, not the mesh, and are not required;
#   - VTK's vtkOpenFOAMReader on the same case (python3-vtk9), same counts;
#   - gmsh -check on .msh 4.1 and 2.2;
#   - meshio on .msh 4.1, 2.2 and Medit .mesh: the tet set equals .tets;
#   - several -o in one run, -o - on standard output, and the refusals: an
#     output that is the input, two -o naming the same file, a binary
#     format on standard output.
# usage: formats_readback.sh FRONTDT   (exit 77: none of the tools installed)
set -eu
FRONTDT=$1
PY=/usr/bin/python3
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
ran=0

# a fixed point set (the demo's generator): 3,000 points, a few duplicates
"$FRONTDT" --demo 3000 -q -o "$T/m.tets" -o "$T/m.msh" --format msh2 -o "$T/m2.msh" \
    -o "$T/m.mesh" -o "$T/m.vtk" -o "$T/all.ele" --all-faces || fail "several -o"
for f in m.tets m.msh m2.msh m.mesh m.vtk all.ele all.node all.face all.neigh; do
    [ -s "$T/$f" ] || fail "-o wrote no $f"
done
head -1 "$T/m2.msh" >/dev/null
sed -n 2p "$T/m2.msh" | grep -q '^2.2 ' || fail "--format msh2 did not apply to the next -o"
sed -n 2p "$T/m.msh" | grep -q '^4.1 ' || fail ".msh is not 4.1"
# every face with --all-faces: (4T + H) / 2 of them, hull ones marked 1
nt=$(wc -l < "$T/m.tets")
nf=$(head -1 "$T/all.face" | cut -d' ' -f1)
nh=$(awk 'NR > 1 && $5 == 1' "$T/all.face" | wc -l)
[ $((2 * nf)) -eq $((4 * nt + nh)) ] || fail "--all-faces: $nf faces for $nt tets, $nh hull"
# standard output: the canonical text by default, byte for byte
"$FRONTDT" --demo 3000 -q -o - > "$T/stdout.tets" || fail "-o -"
cmp -s "$T/stdout.tets" "$T/m.tets" || fail "-o - differs from -o m.tets"
# refusals (exit 1, before any work)
printf '0 0 0\n1 0 0\n0 1 0\n0 0 1\n1 1 1\n' > "$T/in.xyz"
set +e
"$FRONTDT" "$T/in.xyz" -q -o "$T/x.vtu" -o "$T/in.xyz" --format vtk 2>/dev/null; rc=$?
[ $rc -eq 1 ] || fail "output = input: exit $rc"
"$FRONTDT" "$T/in.xyz" -q -o "$T/y.msh" -o "$T/./y.msh" 2>/dev/null; rc=$?
[ $rc -eq 1 ] || fail "two -o, one file: exit $rc"
"$FRONTDT" "$T/in.xyz" -q -o - --format vtu > /dev/null 2>&1; rc=$?
[ $rc -eq 1 ] || fail "binary on stdout: exit $rc"
"$FRONTDT" "$T/in.xyz" -q -o "$T/z.unknown" 2>/dev/null; rc=$?
[ $rc -eq 1 ] || fail "unknown extension: exit $rc"
set -e
[ -s "$T/in.xyz" ] || fail "input damaged"

# OpenFOAM: a case directory with the files checkMesh needs
mkdir -p "$T/case/constant" "$T/case/system"
"$FRONTDT" --demo 3000 -q -o "$T/case/constant/polyMesh" || fail "openfoam"
for f in points faces owner neighbour boundary; do
    [ -s "$T/case/constant/polyMesh/$f" ] || fail "polyMesh/$f missing"
done
ls -a "$T/case/constant" | grep -q '\.tmp\.' && fail "temporary directory left"
# again over the existing directory: files replaced in place
"$FRONTDT" --demo 3000 -q -o "$T/case/constant/polyMesh/" || fail "openfoam over a polyMesh"
for d in controlDict fvSchemes fvSolution; do
    printf 'FoamFile { version 2.0; format ascii; class dictionary; object %s; }\n' "$d" \
        > "$T/case/system/$d"
done
cat >> "$T/case/system/controlDict" <<'EOD'
application checkMesh; startFrom startTime; startTime 0; stopAt endTime; endTime 1;
deltaT 1; writeControl timeStep; writeInterval 1;
EOD
cat >> "$T/case/system/fvSchemes" <<'EOD'
ddtSchemes { default Euler; } gradSchemes { default Gauss linear; }
divSchemes { default none; } laplacianSchemes { default Gauss linear corrected; }
interpolationSchemes { default linear; } snGradSchemes { default corrected; }
EOD
foamrc=
for f in /usr/share/openfoam/etc/bashrc /usr/lib/openfoam/openfoam*/etc/bashrc; do
    [ -f "$f" ] && { foamrc=$f; break; }
done
if command -v checkMesh >/dev/null 2>&1 || [ -n "$foamrc" ]; then
    ran=$((ran + 1))
    bash -c "[ -n '$foamrc' ] && . '$foamrc' >/dev/null 2>&1; checkMesh -case '$T/case'" \
        > "$T/checkMesh.log" 2>&1 || { cat "$T/checkMesh.log"; fail "checkMesh exit"; }
    for ok in "Boundary definition OK" "Cell to face addressing OK" "Point usage OK" \
              "Upper triangular ordering OK" "Face vertices OK" "Face pyramids OK" \
              "Cell volumes OK" "Number of regions: 1 (OK)"; do
        grep -q "$ok" "$T/checkMesh.log" || { cat "$T/checkMesh.log"; fail "checkMesh: no '$ok'"; }
    done
    cells=$(grep -E '^ +cells: ' "$T/checkMesh.log" | awk '{print $2}')
    [ "$cells" = "$nt" ] || fail "checkMesh: $cells cells, .tets has $nt"
    echo "checkMesh: ok ($cells cells)"
else
    echo "checkMesh: skipped (Debian package openfoam not installed)"
fi

if $PY -c 'import vtk; vtk.vtkOpenFOAMReader' 2>/dev/null; then
    ran=$((ran + 1))
    touch "$T/case/case.foam"
    $PY - "$T/case/case.foam" "$nt" <<'EOD' || fail "VTK OpenFOAM reader"
import sys, vtk
r = vtk.vtkOpenFOAMReader()
r.SetFileName(sys.argv[1])
r.Update()
it = r.GetOutput().NewIterator()
it.InitTraversal()
cells = 0
while not it.IsDoneWithTraversal():
    ds = it.GetCurrentDataObject()
    if ds.GetNumberOfCells() and ds.GetCellType(0) == vtk.VTK_TETRA:
        cells += ds.GetNumberOfCells()
    it.GoToNextItem()
assert cells == int(sys.argv[2]), (cells, sys.argv[2])
print("vtkOpenFOAMReader: ok (%d tets)" % cells)
EOD
else
    echo "vtkOpenFOAMReader: skipped (python3-vtk9 not installed)"
fi

if command -v gmsh >/dev/null 2>&1; then
    ran=$((ran + 1))
    for f in m.msh m2.msh; do
        gmsh -check "$T/$f" > "$T/gmsh.log" 2>&1 || { cat "$T/gmsh.log"; fail "gmsh -check $f"; }
        grep -q "Error" "$T/gmsh.log" && { cat "$T/gmsh.log"; fail "gmsh -check $f: error"; }
        grep -q "$nt elements\|$nt tetrahedra\|Done checking mesh coherence" "$T/gmsh.log" ||
            { cat "$T/gmsh.log"; fail "gmsh -check $f: no check ran"; }
    done
    echo "gmsh -check: ok"
else
    echo "gmsh -check: skipped (Debian package gmsh not installed)"
fi

if $PY -c 'import meshio' 2>/dev/null; then
    ran=$((ran + 1))
    $PY - "$T" <<'EOD' || fail "meshio"
import sys, meshio
t = sys.argv[1]
want = sorted(tuple(map(int, l.split())) for l in open(t + "/m.tets"))
for f in ("m.msh", "m2.msh", "m.mesh"):
    m = meshio.read(t + "/" + f)
    tets = [c.data for c in m.cells if c.type == "tetra"]
    assert len(tets) == 1, f
    got = sorted(tuple(sorted(int(v) for v in row)) for row in tets[0])
    assert got == want, f + ": tet sets differ"
    assert len(m.points) == 3000, f
    print("meshio %s: ok (%d tets)" % (f, len(got)))
EOD
else
    echo "meshio: skipped (python3-meshio not installed)"
fi
[ $ran -gt 0 ] || exit 77
echo "formats_readback: ok"
