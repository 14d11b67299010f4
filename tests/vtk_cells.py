"""The Voronoi cells' VTK polyhedra (--voronoi FILE.vtu) read back, for
tests/voronoi_voro.py and tests/periodic_e2e.py: each cell's point (its
"point" array), its "volume" array and its volume summed from its faces
(fans from each face's first vertex, taken from the cell's first vertex)."""


def read_polyhedra(path):
    """[(point, volume array, volume from the faces, cell type)] a cell,
    or None where VTK's Python module (python3-vtk9) is missing."""
    try:
        import vtk
        from vtk.util.numpy_support import vtk_to_numpy
    except ImportError:
        return None
    rd = vtk.vtkXMLUnstructuredGridReader()
    rd.SetFileName(path)
    rd.Update()
    g = rd.GetOutput()
    pts = vtk_to_numpy(g.GetPoints().GetData())
    site = vtk_to_numpy(g.GetCellData().GetArray("point"))
    vol = vtk_to_numpy(g.GetCellData().GetArray("volume"))
    cells = []
    for c in range(g.GetNumberOfCells()):
        cell = g.GetCell(c)
        v, base = 0.0, None
        for k in range(cell.GetNumberOfFaces()):
            f = cell.GetFace(k)
            q = [pts[f.GetPointId(j)] for j in range(f.GetNumberOfPoints())]
            base = q[0] if base is None else base
            q = [x - base for x in q]
            for j in range(1, len(q) - 1):
                a, b, d = q[0], q[j], q[j + 1]
                v += (a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) +
                      a[2] * (b[0] * d[1] - b[1] * d[0])) / 6
        cells.append((int(site[c]), float(vol[c]), v, cell.GetCellType()))
    return cells
