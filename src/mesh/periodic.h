/*
 * The Delaunay tetrahedralization of a point set periodic in any subset of
 * the three axes (issue 33): the quotient of the DT of the infinite
 * periodic copy, every tet once, its vertices as input points with an
 * image offset each, the hull only across the axes that are not periodic.
 *
 * How (bench/NOTES.md entry 108): the points and their images within a
 * margin m of the box (on each periodic axis: x + L for x - lo <= m, x - L
 * for hi - x <= m, and their combinations on two or three axes) are
 * triangulated by the insertion engine (src/mesh/insert.h,
 * fdt_ins_build_images: every predicate exact on the exact images,
 * src/geom/images.h), and certified. A tet is kept when its
 * lowest vertex (least input index, then least offset) is an input point
 * itself; its offsets are then relative to that vertex. The result is
 * proved, not assumed: every tet with a vertex that is an input point has
 * its circumscribed ball, within the points' extent on the axes that are
 * not periodic, inside the region where every image is present (the box
 * grown by m on each periodic axis), so no image of any point is inside
 * its sphere (ties: the images share their point's perturbation,
 * images.h), and every such hull face a normal with no periodic
 * component, so nothing lies beyond it. Then each input point's star in
 * this mesh is its star in the periodic mesh (a closed neighbourhood of
 * the point made of periodic tets), and the kept tets, the stars' shares,
 * are all of the periodic mesh, each once (sound and complete).
 * Where a ball reaches too far the margin grows to what it reached (and a
 * quarter more) and the run starts again: a function of the input alone
 * (no clock). At m >= the period (every point
 * with all its neighbouring images) a failure means the periodic
 * triangulation is not a simplicial complex in one copy of the box
 * (CGAL's 1-sheet condition): FDT_EDEGENERATE, with the reason.
 */
#ifndef FDT_PERIODIC_H
#define FDT_PERIODIC_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include "frontdt.h"
#include "geom/predicates.h"

/* The periodic box: bit k of axes set when axis k is periodic, with the
 * period hi[k] - lo[k] (the real difference, not rounded) and every point
 * in [lo[k], hi[k]); lo and hi are ignored on the other axes. */
typedef struct fdt_periodic_box {
    unsigned axes;
    double lo[3], hi[3];
} fdt_periodic_box;

/* The box of the periodic axes axes and box (xmin, ymin, zmin, xmax, ymax,
 * zmax: fdt_settings.periodic_box, a result's pbox). */
static inline fdt_periodic_box fdt_periodic_box_of(unsigned axes, const double box[6])
{
    return (fdt_periodic_box){axes, {box[0], box[1], box[2]}, {box[3], box[4], box[5]}};
}

/* The period along axis k (hi - lo rounded), 0 on an axis that is not
 * periodic: the .fdtb header's, the laid-out writers' and walks'. */
static inline double fdt_periodic_period(const fdt_periodic_box *b, int k)
{
    return b->axes >> k & 1 ? b->hi[k] - b->lo[k] : 0;
}

/* Translations by whole periods, in lexicographic order (the cyclic patch
 * pairs of the laid-out polyMesh writers, src/io/write/fmt_foam.c and
 * src/mesh/dualperiodic.c, come in it). */
static inline int fdt_shift_cmp(const int a[3], const int b[3])
{
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k])
            return a[k] < b[k] ? -1 : 1;
    return 0;
}

/* s into the *n distinct shifts sh[] (ascending, room for one more) unless
 * there: a few dozen at most, so a linear insertion. */
static inline void fdt_shift_add(int (*sh)[3], size_t *n, const int s[3])
{
    size_t k = 0;
    while (k < *n && fdt_shift_cmp(sh[k], s) < 0)
        k++;
    if (k < *n && !fdt_shift_cmp(sh[k], s))
        return;
    memmove(sh + k + 1, sh + k, (*n - k) * sizeof *sh);
    memcpy(sh[k], s, sizeof sh[k]);
    (*n)++;
}

/* The result: ntets tets, 4 input indices each ascending (ties: the
 * offsets' order), with 3 offsets each (in periods, 0 on an axis that is
 * not periodic) relative to the first; the hull faces likewise, 3 each;
 * both sorted. */
typedef struct fdt_periodic_mesh {
    uint32_t *tets;
    int8_t *tet_off;     /* 12 per tet */
    size_t ntets;
    uint32_t *hull;
    int8_t *hull_off;    /* 9 per hull face */
    size_t nhull;
    /* fdt_periodic_build_part with stars: every tet and hull face with a
     * vertex the part owns, in no order, in the build's numbering (the
     * owned points' stars, for their cells: fdt_periodic_part_cells). */
    uint32_t *star_tets;
    int8_t *star_off;
    uint8_t *star_pos;   /* 1 where a star tet is positive in its rows' order */
    size_t nstar;
    uint32_t *star_hull;
    int8_t *star_hull_off;
    size_t nstar_hull;
    /* How it went, for --stats. */
    size_t images;       /* images triangulated with the points (last round) */
    int rounds;          /* margins tried */
    double margin[3];    /* the last margin on each periodic axis */
    fdt_pred_counts pc;  /* exact predicate calls, all rounds */
} fdt_periodic_mesh;

/*
 * The periodic DT of the n points X (3 doubles each, distinct, finite)
 * in the box b, on nthreads threads, into *out (free with
 * fdt_periodic_free). names (may be NULL): point i's name in messages
 * (a merged input's index). FDT_OK; FDT_EINVAL for a box with no periodic axis,
 * hi <= lo or a side beyond doubles, a point outside [lo, hi) on a
 * periodic axis (diag names the first by its index), or two points that
 * coincide; FDT_EDEGENERATE when no periodic triangulation exists in one
 * copy of the box (too few points for its size) or the points do not span
 * 3-D space; FDT_ECHECK if a mesh failed its certificate (a bug);
 * FDT_ENOMEM; FDT_ETOOBIG. diag gets the reason of any error.
 */
int fdt_periodic_build(const double *X, uint32_t n, const int32_t *names,
                       const fdt_periodic_box *b, int nthreads, fdt_periodic_mesh *out,
                       char *diag, size_t diag_size);

void fdt_periodic_free(fdt_periodic_mesh *m);

/* Sorts count canonical rows of nv vertices (*ids, 3 offsets a vertex in
 * *off, both malloc'ed; ids below n, the rows' least first, its offsets
 * 0 and the others' -2..2) into the mesh's order (fdt_periodic_build's),
 * by the build's own buckets: the parts' rows gathered (frontdt-mpi). The
 * arrays are replaced. FDT_OK, FDT_ENOMEM or FDT_EINVAL for an id of n or
 * more or a row that is not canonical (rows unchanged). */
int fdt_periodic_sort_rows(uint32_t **ids, int8_t **off, size_t count, int nv, size_t n);

/*
 * A periodic run in parts (streamed, MPI; bench/NOTES.md entry 110): the
 * box cut into slabs along its longest periodic axis, about part_points
 * points a slab (counted by a histogram of 2^16 bins), each slab a part
 * that owns its points. Part k's build (fdt_periodic_build_part) is the
 * one-part build with the slab as its core on that axis: the owned points,
 * then every copy of any point within the margin of the slab (the other
 * parts' points included), its proofs for the tets with an owned vertex
 * and its balls inside the slab grown by the margin, and it keeps the
 * tets whose least vertex is an owned point. Each periodic tet has one
 * least vertex, so the parts' rows are the one-part build's, each once.
 * A slab whose balls reach half a period away takes the whole box as its
 * core on that axis (the one-part proofs, its own points still the
 * slab's), so a part fails only where the one-part build would. With
 * part_points 0, or n at most part_points: one part, the whole box.
 */
typedef struct fdt_periodic_parts {
    int axis;            /* the slabs' axis (-1: one part) */
    uint32_t nparts;
    double *cut;         /* nparts + 1: part k owns [cut[k], cut[k + 1]) */
    uint32_t *start;     /* nparts + 1 (NULL for one part) */
    uint32_t *idx;       /* the points by part, ascending in each */
    double ylo[3], yhi[3]; /* the points' extent */
} fdt_periodic_parts;

/* FDT_OK or FDT_ENOMEM; X and b as fdt_periodic_build's, checked. */
int fdt_periodic_parts_make(const double *X, uint32_t n, const fdt_periodic_box *b,
                            uint32_t part_points, fdt_periodic_parts *p);
void fdt_periodic_parts_free(fdt_periodic_parts *p);
/* The points part k owns. */
uint32_t fdt_periodic_part_points(const fdt_periodic_parts *p, uint32_t k, uint32_t n);

/* Part k's tets and hull faces (those whose least vertex it owns), sorted,
 * as fdt_periodic_build gives the whole mesh's, and with stars nonzero its
 * points' stars (fdt_periodic_mesh); the errors of fdt_periodic_build but
 * the box's and points' checks, which are the caller's
 * (fdt_periodic_check). */
int fdt_periodic_build_part(const double *X, uint32_t n, const int32_t *names,
                            const fdt_periodic_box *b, const fdt_periodic_parts *parts,
                            uint32_t part, int nthreads, int stars, fdt_periodic_mesh *out,
                            char *diag, size_t diag_size);

/*
 * The Voronoi cells of a periodic mesh, as fdt_voronoi_compute gives a
 * plain mesh's: n rows, row i point i's, merged duplicates (dupmap)
 * FDT_CELL_MERGED. tets, off, hull: the mesh as fdt_periodic_build gives
 * it, renumbered to input ids; X the input points. Each point's cell is
 * computed from its star, the tets around it moved so that it is the point
 * itself (src/mesh/voronoi.h's batch: a cell has the same bits whichever
 * batch holds it); its neighbours are input ids (an image's: its
 * point's). Periodic on every axis no cell is clipped; across an axis that
 * is not periodic the box's sides are walls, which cut the cells that
 * reach them (the hull's points' cells, unbounded, among them), as
 * fdt_voronoi_compute's box; neighbors and skip as fdt_voronoi_options'
 * fields. FDT_EINVAL when a point lies outside the box
 * on such an axis or the box is empty there (diag names the point); the
 * batch's errors otherwise, with diag.
 */
struct fdt_voronoi;
struct fdt_vshort;
int fdt_periodic_cells(const int32_t *tets, const int8_t *off, size_t ntets, const int32_t *hull,
                       size_t nhull, const double *X, size_t n, const int32_t *dupmap,
                       const fdt_periodic_box *b, int threads, int neighbors, unsigned skip,
                       struct fdt_voronoi **out, char *diag, size_t ds);
/* fdt_periodic_cells' checks of the box and the points X (n, as given)
 * across the axes that are not periodic, whose sides are walls: FDT_OK, or
 * FDT_EINVAL with diag naming the side or the first point outside. */
int fdt_periodic_cells_check(const double *X, size_t n, const fdt_periodic_box *b, char *diag,
                             size_t ds);
/* The cells' box of a periodic set in box b: b's sides on the axes that
 * are not periodic (the walls), three periods on each side of it on the
 * periodic ones (every image of a star and its circumcentres, whichever
 * stars a batch holds; a batch grows it where an image lies beyond).
 * fdt_voronoi_box of its cells. */
void fdt_periodic_cells_box(const fdt_periodic_box *b, double box[6]);
/*
 * The cells of the points part k owns (a streamed periodic run's batch,
 * src/mesh/voronoi.h: row i the i-th owned point's, ids names[] of them)
 * from the part's stars (fdt_periodic_build_part with stars), the same
 * bits as fdt_periodic_cells gives them. X: the n points the part was
 * built from, the input's times 2^x_exp (b likewise); names: X's ids to
 * input ids. FDT_ERANGE for an edge too short for the cells (the least
 * kept in *sh, diag not written); else FDT_ENOMEM or FDT_EINTERNAL with
 * diag.
 */
int fdt_periodic_part_cells(const fdt_periodic_mesh *pm, const double *X, uint32_t n, int x_exp,
                            const int32_t *names, const fdt_periodic_parts *parts, uint32_t part,
                            const fdt_periodic_box *b, int threads, int neighbors, unsigned skip,
                            struct fdt_voronoi **out, struct fdt_vshort *sh, char *diag,
                            size_t ds);

/*
 * A periodic mesh laid out in space for the formats that name points by
 * their coordinates (.vtu, .msh): the n input points X first (point i is
 * i), then each image (input id, offsets) a tet or hull face uses,
 * rounded; each tet where its offsets place it (its lowest-id vertex the
 * point itself), positively oriented for the exact images; each hull face
 * likewise, outward (its tet's other vertex on its negative side). src[i]:
 * point i's input id (i for the first n). FDT_OK, FDT_ENOMEM, FDT_ETOOBIG
 * past INT32_MAX points, FDT_EINTERNAL for a hull face no tet has (a
 * bug). off[3i..3i+2]: point i's image offsets, which name the cyclic
 * pairs of faces exactly (src/io/write/fmt_foam.c). Free with
 * fdt_periodic_unfolded_free.
 */
typedef struct fdt_periodic_unfolded {
    double *xyz;     /* 3 each */
    fdt_vid *src;
    int8_t *off;     /* 3 each: the image's offsets (0 0 0 for the first n) */
    size_t n;
    fdt_vid *tets;   /* 4 each */
    size_t ntets;
    fdt_vid *hull;   /* 3 each */
    size_t nhull;
} fdt_periodic_unfolded;

/* The coordinates along axis d of laid-out tet t's points: their least
 * in *lo, their largest in *hi. */
static inline void fdt_periodic_unfolded_span(const fdt_periodic_unfolded *u, size_t t, int d,
                                              double *lo, double *hi)
{
    *lo = INFINITY;
    *hi = -INFINITY;
    for (int i = 0; i < 4; i++) {
        const double x = u->xyz[3 * (size_t)u->tets[4 * t + (size_t)i] + (size_t)d];
        *lo = x < *lo ? x : *lo;
        *hi = x > *hi ? x : *hi;
    }
}

int fdt_periodic_unfold(const int32_t *tets, const int8_t *off, size_t ntets, const int32_t *hull,
                        const int8_t *hoff, size_t nhull, const double *X, size_t n,
                        const fdt_periodic_box *b, fdt_periodic_unfolded *u);

/*
 * The neighbours of u's tets in the periodic mesh, for the formats that
 * write them (TetGen's .neigh) or pair faces (OpenFOAM's cyclic patches):
 * nbrs[4 t + k] the tet across tet t's face opposite its vertex k, which
 * may lie in another copy (the face is then a translate of t's), -1 on
 * the hull. Faces are paired by their input ids and the offsets between
 * their points, never by coordinates. FDT_OK, FDT_ENOMEM, FDT_EINTERNAL
 * (a face in more than two tets: a bug). *nbrs is the caller's to free.
 */
int fdt_periodic_unfolded_neighbors(const fdt_periodic_unfolded *u, fdt_tid **nbrs);
void fdt_periodic_unfolded_free(fdt_periodic_unfolded *u);

/*
 * A patch of a periodic mesh: u's laid-out tets and their translates by
 * whole periods whose boxes come within margin[k] of the box b along each
 * periodic axis k, as one plain mesh, for the walks and cavities of
 * src/mesh/locate.c and src/mesh/interpolate.c (src/mesh/periodic_interp.c).
 * Its points are the images (input id, offsets) the tets use, rounded as
 * fdt_periodic_unfold rounds them, numbered in the order of (id, offsets):
 * the same numbers in any order of the mesh's rows, and in the same order
 * in a larger patch. nbrs: -1 across a hull face, FDT_NB_CUT
 * (src/mesh/locate.h) across a face whose other tet lies beyond the
 * patch. row[t]: the row (of u) tet t is a translate of, its vertices in
 * u's order. unb: fdt_periodic_unfolded_neighbors'. FDT_OK, FDT_ENOMEM,
 * FDT_ETOOBIG (a margin of more than 64 periods, or past INT32_MAX
 * points). Free with fdt_periodic_patch_free.
 */
typedef struct fdt_periodic_patch {
    double *xyz;    /* 3 each */
    fdt_vid *src;   /* each point's input id */
    size_t n;
    fdt_vid *tets;  /* 4 each */
    fdt_tid *nbrs;  /* 4 each */
    uint32_t *row;
    size_t ntets;
} fdt_periodic_patch;

int fdt_periodic_patch_make(const fdt_periodic_unfolded *u, const fdt_tid *unb, const double *X,
                            const fdt_periodic_box *b, const double margin[3],
                            fdt_periodic_patch *p);
void fdt_periodic_patch_free(fdt_periodic_patch *p);

/*
 * An independent exact check that tets (4 ids and 12 offsets each, in any
 * vertex order) and hull faces (3 and 9) are the periodic Delaunay mesh of
 * the n points X in box b: ids in range and distinct in a row, every point
 * a vertex (a duplicate's first occurrence named instead), no flat tet,
 * every face in two tets on its two sides, the one's apex outside the
 * other's sphere (the perturbed test, on the exact images), or in one tet
 * and the hull; the hull faces normal to no periodic axis, closed and
 * convex; and the tets' volumes the domain's (the box's, or the hull's
 * flux over one period), so that they cover it once. FDT_OK, FDT_ECHECK
 * with msg saying what and where, FDT_ENOMEM.
 */
int fdt_periodic_check_mesh(const double *X, size_t n, const int32_t *tets, const int8_t *off,
                            size_t ntets, const int32_t *hull, const int8_t *hoff, size_t nhull,
                            const fdt_periodic_box *b, char *msg, size_t len);

/* fdt_periodic_build's checks of the box and of the points in it, alone
 * (a caller checks its input before it scales or merges it, so that the
 * message names the input's index and value). FDT_OK or FDT_EINVAL. */
int fdt_periodic_check(const double *X, size_t n, const fdt_periodic_box *b, char *diag,
                       size_t diag_size);

/* m's ids (below n) renumbered by orig, a merged input's first index of
 * each point, increasing (src/geom/prepare.h), so that every row keeps
 * its order and its least vertex. FDT_OK, or FDT_EINTERNAL when orig is
 * not increasing. */
int fdt_periodic_renumber(fdt_periodic_mesh *m, const int32_t *orig, size_t n);

#endif
