"""frontdt: the exact 3D Delaunay tetrahedralization (Tanemura's advancing
front, parallelised after Merriam, NASA TM-103951, 1992) from Python.

    import numpy as np, frontdt
    t = frontdt.delaunay(np.random.rand(10000, 3))
    t.simplices     # int32 (m, 4), positively oriented, input numbering
    t.neighbors     # int64 (m, 4), -1 on the hull, opposite vertex k
    t.check()       # exact verification; raises frontdt.CheckError
    c = t.voronoi() # Voronoi cells: c["volumes"], c["densities"], ...

The arrays are read-only views of the library's result, which lives as
long as any of them. See help(frontdt.delaunay) and README.md, "Python".
"""
from ._frontdt import CheckError, Triangulation, __version__, check, delaunay


def voronoi(points, box=None, threads=None, periodic=None, centroids=True, densities=True):
    """Each point's Voronoi cell, clipped by box (None: the points' bounding
    box): frontdt.delaunay(points, threads).voronoi(box, centroids,
    densities), a dict of arrays (see help(frontdt.Triangulation.voronoi));
    centroids=False or densities=False leave those out (None), and the
    time they take. periodic="xyz" (or "x,z", ...) with box the periods: the
    cells of the periodic point set, cut by the box's sides across the axes
    that are not periodic, their volumes summing to the box's."""
    if periodic is not None:
        return delaunay(points, threads=threads, periodic=periodic,
                        box=box).voronoi(centroids=centroids, densities=densities)
    return delaunay(points, threads=threads).voronoi(box, centroids=centroids,
                                                     densities=densities)


def interpolate(points, values, queries, method="natural", threads=None, periodic=None,
                box=None):
    """Interpolates values given at points (shape (n,) or (n, k)) at the
    queries: frontdt.delaunay(points, threads, periodic=, box=).interpolate(
    values, queries, method), method "natural" (Sibson) or "linear".
    periodic="xyz" (or "x,z", ...) with box the periods: the points as a
    periodic set, each query wrapped into the box along those axes."""
    if periodic is not None:
        t = delaunay(points, threads=threads, periodic=periodic, box=box)
    else:
        t = delaunay(points, threads=threads)
    return t.interpolate(values, queries, method)


__all__ = ["CheckError", "Triangulation", "check", "delaunay", "interpolate", "voronoi",
           "__version__"]
