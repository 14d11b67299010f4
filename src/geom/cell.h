/* A convex cell cut from a box by half-spaces (src/mesh/voronoi.c, issue 32).
 *
 * The Voronoi cell of a site whose cell leaves the box (a hull point, or
 * one with a Voronoi vertex outside the box) is computed as voro++ computes
 * every cell: start from the box and cut it by the bisector plane of each
 * Delaunay neighbour. Coordinates are relative to the site, which lies in
 * the cell (a cut never removes the origin).
 *
 * The polyhedron is a vertex array and a list of faces, each a ring of
 * vertex indices counter-clockwise seen from outside, with a label: the
 * neighbour whose bisector made it, or a wall (FDT_CELL_WALL(k) for
 * k = 0..5: x-min, x-max, y-min, y-max, z-min, z-max, voro++'s -1..-6).
 *
 * A vertex whose distance to a cutting plane is within FDT_CELL_TOL of the
 * size of the numbers that give it (|n| |x| + |h|, the rounding's scale)
 * counts as on it: it stays, and no sliver of rounding is cut off (voro++
 * has the same kind of tolerance). Not thread-safe
 * per object; one object per thread, reused from cell to cell.
 */
#ifndef FDT_CELL_H
#define FDT_CELL_H

#include <stddef.h>

#define FDT_CELL_WALL(k) (-1 - (k))
#define FDT_CELL_TOL 0x1p-40
/* The coarsest tolerance a cut retries with when FDT_CELL_TOL finds the
 * cell not convex (fdt_cell_cut). */
#define FDT_CELL_TOL_MAX 0x1p-24

typedef struct fdt_cell_ring {
    int start, count; /* ring[start .. start + count) */
    long label;       /* neighbour id, or FDT_CELL_WALL(k) */
} fdt_cell_ring;

typedef struct fdt_cell_scratch {
    double s;            /* signed distance to the cutting plane */
    int side, next, map; /* class; the cap's next vertex; compaction */
} fdt_cell_scratch;

typedef struct fdt_cell {
    double (*p)[3];     /* vertices (owned) */
    int np, capp;
    int *ring;          /* the faces' rings, one after another (owned) */
    int nring, capring;
    fdt_cell_ring *f;   /* faces (owned) */
    int nf, capf;
    /* scratch, kept from call to call (owned) */
    fdt_cell_scratch *v;
    int capv;
    int *ekey;          /* this cut's crossing points: (in, out, index) */
    int ne, cape;
    int *tring;         /* the faces being built */
    int ntring, captring;
    fdt_cell_ring *tf;
    int ntf, captf;
    double (*tp)[3];    /* vertices being compacted */
    int captp;
    /* A cut rewrites only the faces it reaches (cut_tol): the rings it
     * replaces stay in ring[] unreferenced, and the vertices it cuts off
     * in p[] as NaN, until they are as many as the live ones (then one
     * compaction, fdt_cell_compact). */
    int live_ring;      /* ring entries the faces use */
    int ndead;          /* vertices cut off, still in p[] */
    int *touched;       /* this cut's faces: f kept, -1 - f gone */
    int captouched;
    /* Each vertex's faces (inc_head[v]: the first of triples (face, the
     * vertex's place in its ring, next) in inc[]), so that a cut finds the vertices outside its plane by
     * climbing from one vertex to a neighbour farther out and walking
     * the region it reaches, without classing every vertex; inc_ok 0:
     * to be rebuilt (after a compaction, a face cut away, a copy). */
    int *inc_head, capinchead;
    int *inc, ninc, capinc;
    int inc_ok;
    unsigned *stamp;    /* the cut that classed each vertex */
    int capstamp;
    unsigned *fstamp;   /* the cut that reached each face */
    int capfstamp;
    unsigned cutno;
    int *queue, capqueue; /* this cut's vertices outside */
    int hint;           /* where the next climb starts */
    double l1max;       /* a bound on every vertex's |x| + |y| + |z| */
    int classify_all;   /* 1: every cut classes every vertex, never
                           climbs (tests/test_cell.c's second opinion) */
} fdt_cell;

/* One face of a measured cell. */
typedef struct fdt_cell_face {
    long label;
    double area;
} fdt_cell_face;

void fdt_cell_init(fdt_cell *c);
void fdt_cell_free(fdt_cell *c);

/* Makes dst a copy of src (dst's arrays reused). 0, or -1 when out of
 * memory. */
int fdt_cell_copy(fdt_cell *dst, const fdt_cell *src);

/* Makes c the box [lo, hi] (coordinates relative to the site, lo < 0 < hi
 * in each coordinate up to the site lying on a wall: lo <= 0 <= hi).
 * Returns 0, or -1 when out of memory. */
int fdt_cell_box(fdt_cell *c, const double lo[3], const double hi[3]);

/* Keeps the part of c where n . x <= h, the new face labelled `label`.
 * Returns 1 when the cut removed something, 0 when it did not, -1 when
 * out of memory, -2 when the cut would leave nothing of c (never for h > 0
 * and a cell containing the origin; c is unchanged), -3 when the cut found
 * c not convex with FDT_CELL_TOL, the coarser ones up to FDT_CELL_TOL_MAX
 * and none (rounding gone wrong: a bug; c keeps its shape). */
int fdt_cell_cut(fdt_cell *c, const double n[3], double h, long label);

/* Drops the vertices and ring entries no face uses (cuts leave them for
 * later), so that p[0 .. np) are the cell's vertices. For readers of the
 * vertices; the faces and fdt_cell_measure never need it. 0, or -1 when
 * out of memory (c unchanged). */
int fdt_cell_compact(fdt_cell *c);

/* The cell's volume, surface area, centroid (relative to the site), and
 * its faces (labels and areas, faces of zero area included) into
 * faces[0 .. c->nf) when faces is not NULL. */
void fdt_cell_measure(const fdt_cell *c, double *volume, double *area, double centroid[3],
                      fdt_cell_face *faces);

#endif
