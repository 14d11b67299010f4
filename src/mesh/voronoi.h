/* The Voronoi cells' computation (src/mesh/voronoi.c) behind the public
 * fdt_voronoi_compute (src/api/api.c, which resolves the thread count). */
#ifndef FDT_VORONOI_H
#define FDT_VORONOI_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "frontdt.h"

/* The cells' resolution: a Delaunay edge at least 2^FDT_VORONOI_BOX_EXP
 * of the box's largest side (fdt_voronoi_resolution, below: the cells,
 * the polyhedra and the natural-neighbour coordinates). */
#define FDT_VORONOI_BOX_EXP (-48)

/* The Chebyshev length of ab: the square of a length can underflow where
 * the length does not. */
static inline double fdt_cheb(const double *a, const double *b)
{
    double x = fabs(a[0] - b[0]), y = fabs(a[1] - b[1]), z = fabs(a[2] - b[2]);
    x = x > y ? x : y; /* finite operands: fmax is a library call here */
    return x > z ? x : z;
}

/* Whether the edge ab comes before cd, both by point ids: the lower ids
 * first, then the higher. A refusal names the least edge it met, so that
 * its message is the same whatever the thread count and the tets' order. */
static inline int fdt_edge_less(long long a, long long b, long long c, long long d)
{
    long long ab0 = a < b ? a : b, ab1 = a < b ? b : a;
    long long cd0 = c < d ? c : d, cd1 = c < d ? d : c;
    return ab0 < cd0 || (ab0 == cd0 && ab1 < cd1);
}

/* The largest side of box (xmin, ymin, zmin, xmax, ymax, zmax). */
static inline double fdt_box_side(const double box[6])
{
    double side = 0;
    for (int k = 0; k < 3; k++)
        side = box[k + 3] - box[k] > side ? box[k + 3] - box[k] : side;
    return side;
}

/* o, a caller's fdt_voronoi_options of any size include/frontdt.h accepts,
 * as this library's whole struct in *full (the fields o lacks at their
 * defaults): FDT_OK, or FDT_EINVAL for a size it does not know or skip
 * bits it has no name for. */
int fdt_voronoi_options_read(const fdt_voronoi_options *o, fdt_voronoi_options *full);
/* fdt_voronoi_compute on `threads` threads (at least 1; the caller's is
 * one of them), o not NULL and of this library's size. */
int fdt_voronoi_build(const fdt_result *r, const double *xyz, size_t n, const fdt_voronoi_options *o,
                      int threads, fdt_voronoi **out, char *diag, size_t diag_size);

/* The least Delaunay edge too short for the cells (under
 * 2^FDT_VORONOI_BOX_EXP of the box): its points' input ids, a < b, by
 * fdt_edge_less over every edge met; a < 0 when none. */
typedef struct fdt_vshort {
    long long a, b;
    double len; /* its Chebyshev length */
} fdt_vshort;

/* FDT_ERANGE with diag naming sh's edge, as fdt_voronoi_compute does. */
int fdt_voronoi_too_close(const fdt_vshort *sh, const double box[6], char *diag, size_t ds);

/*
 * A batch of cells of a streamed run (src/front/cells.h): the cells of the
 * points own[0 .. nown) from tets, which hold every tet of each of their
 * stars (a tet with none of them is left out). Ids index xyz (3 doubles
 * each, the input's coordinates times 2^xyz_exp: exactly, fdt_prepare's
 * scale); label[id] is the point's input id (the cells' ids, their
 * neighbours' labels, messages). Each cell is computed as
 * fdt_voronoi_build computes it, from its own tets and neighbours alone,
 * so it has the same bits whichever batch holds it.
 */
typedef struct fdt_vbatch {
    const double *xyz;
    int xyz_exp;
    const fdt_vid *label;
    const uint32_t *own;
    size_t nown;
    const uint8_t *own_hull; /* nonzero: own[i] is a hull point */
    const uint32_t *tets;    /* 4 ids a tet */
    size_t ntets;
    const uint32_t *pick;    /* NULL, or the tets taken: ntets indices
                                into tets (a chunk's, without a copy) */
    double box[6];           /* holds every point (the caller checked) */
    int ed;                  /* fdt_voronoi_scale's exponent of box */
    int neighbors;           /* keep each cell's neighbours and face areas */
    unsigned skip;           /* fdt_voronoi_options.skip */
    unsigned periodic;       /* a periodic set's star: its periodic axes
                                (bits 0-2), along which box is three
                                periods each side; else 0 */
} fdt_vbatch;

/* The batch's cells into *out, row i the cell of own[i] (fdt_voronoi_ids:
 * their input ids), on `threads` threads. FDT_ERANGE when one of its tets
 * has an edge too short for the cells (kept in *sh when less than what it
 * holds; diag not written for it); FDT_ENOMEM; FDT_EINTERNAL with diag. */
int fdt_voronoi_batch(const fdt_vbatch *b, int threads, fdt_voronoi **out, fdt_vshort *sh,
                      char *diag, size_t ds);

/* A batch of the k merged duplicates ids (input ids; pts their points, 3
 * each): no cells, flag FDT_CELL_MERGED, as fdt_voronoi_compute gives
 * them; neighbors and skip as the other batches'. */
int fdt_voronoi_merged(const fdt_vid *ids, const double *pts, size_t k, const double box[6],
                       int neighbors, unsigned skip, fdt_voronoi **out);

/* *v, a batch whose rows' ids are distinct and below n, as n rows, row
 * i point i's (fdt_voronoi_compute's shape): a row no batch row has is a
 * merged duplicate's (FDT_CELL_MERGED, no cell). FDT_OK (*v replaced) or
 * FDT_ENOMEM (*v unchanged). */
int fdt_voronoi_spread(fdt_voronoi **v, size_t n);

/* The box the cells are clipped by: o's (FDT_EINVAL, with diag, when it is
 * empty, not finite or leaves a point out) or the bounding box of the
 * finite points (a merged duplicate lies on its point). The rule of
 * fdt_voronoi_compute, of the streamed cells and of the polyMesh dual
 * (src/mesh/dualmesh.c). A point outside is
 * named by its index, or by ids[i] (its input id) when ids is not NULL. */
int fdt_voronoi_box_of(const double *xyz, const fdt_vid *ids, size_t n,
                       const fdt_voronoi_options *o, double box[6], char *diag, size_t ds);

/*
 * FDT_OK, and *ed the exponent of box's largest side D (D = f 2^*ed, f in
 * [1/2, 1)), when the cells' volumes and densities in box are normal
 * doubles (D from about 2.4e-88 to 2.2e102); else FDT_ERANGE with diag
 * (points 1e-151 apart came out volume 0 with no faces, 1e149 apart NaN,
 * before this check). The cells are computed with the points scaled by
 * 2^-ed (src/mesh/voronoi.c, scale_frame).
 */
int fdt_voronoi_scale(const double box[6], int *ed, char *diag, size_t ds);

/* v's cells are a periodic set's, periodic along axes (bits 0-2) with
 * the periods hi - lo there: fdt_voronoi_polyhedron then cuts each cell
 * from its point's own period box on those axes by its neighbours'
 * images, and the checks below measure a neighbour at its nearest image. */
void fdt_voronoi_set_periodic(fdt_voronoi *v, unsigned axes, const double lo[3],
                              const double hi[3]);
/*
 * Whether the cells' vertices can be written as absolute coordinates
 * (fdt_voronoi_polyhedron, the .vtu polyhedra): FDT_ERANGE with diag
 * naming two neighbours closer than 2^-40 of their coordinates (the dual's
 * rule: points at 2^40 on the doubles' 2^-12 grid, tests/gen_points.c
 * ulpgrid, have Voronoi vertices that round by half a cell), else FDT_OK.
 * v needs its neighbours.
 */
int fdt_voronoi_vertices_check(const fdt_voronoi *v, const double *xyz, char *diag, size_t ds);

/*
 * Whether doubles hold the cells of r's points (xyz, as given to
 * fdt_triangulate) in box: FDT_ERANGE, with diag naming two points, when a
 * Delaunay edge (its Chebyshev length: the square of a length can
 * underflow where the length does not) is shorter than 2^box_exp of the
 * box, or, with coords set, than 2^-40 of its points' coordinates.
 * FDT_OK otherwise. Checked before the cells are built, so that
 * FDT_EINTERNAL from them stays a bug's. The limits:
 *  - the cells fdt_voronoi_compute cuts from the box (hull, needle and
 *    tiny cells) are cut relative to their point, from the box's walls:
 *    a cell 1e-15 of the box came out exact, one of 1e-16 could not be
 *    cut, so box_exp -48;
 *  - the polyMesh dual computes everything in one frame and writes its
 *    vertices as absolute coordinates: box_exp -300 (the cells' volumes
 *    underflow: 1e-150 beside 1e150 in one set could not be closed) and
 *    coords (Voronoi vertices between points 2^-40 of their coordinates
 *    apart round to a grid a few thousand steps across the cells:
 *    tests/gen_points.c `ulpgrid`, 2^-12 steps at 2^40, came out 3e-2 off
 *    in volume).
 */
int fdt_voronoi_resolution(const fdt_result *r, const double *xyz, const double box[6],
                           int box_exp, int coords, char *diag, size_t ds);

#endif
