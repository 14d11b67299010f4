/*
 * Voronoi cells from the Delaunay tets (issue 32): the public
 * fdt_voronoi_* calls of include/frontdt.h.
 *
 * A cell that stays inside the box is summed from its tets. The face of
 * cell i shared with neighbour j lies in the bisector plane of edge ij; its
 * vertices are the circumcentres C of the tets around the edge, in the
 * tets' order around it. Fanned from the edge's midpoint M, and each
 * triangle (M, C_T, C_T') split at the circumcentre F of the face the two
 * tets share (it lies on the Voronoi edge C_T C_T'), the face is a signed
 * sum of triangles (M, F, C) each of which belongs to one tet: tet T adds
 * +area(M, F_prev, C) - area(M, F_next, C) to the face of each of its six
 * edges, F_prev and F_next its two faces along the edge in counter-
 * clockwise order about j - i. The cone from point i over such a triangle,
 * a tet of height |j - i| / 2, gives the cell's volume and centroid the
 * same way. The signs make the sum the polygon's area even when C lies
 * outside its tet. Every share is a function of the tet alone, so the
 * cells can be summed from the tets in any order (sums: src/base/fixsum.h).
 *
 * A cell with a vertex outside the box, or unbounded (a hull point), is
 * cut from the box by the bisector planes of its Delaunay neighbours
 * (src/geom/cell.c), as voro++ computes every cell.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/abi.h"
#include "base/diag.h"
#include "base/fixsum.h"
#include "base/mem.h"
#include "base/spawn.h"
#include "geom/cell.h"
#include "geom/morton.h"
#include "geom/predicates.h"
#include "mesh/result.h"
#include "mesh/voronoi.h"

struct fdt_voronoi {
    size_t n;           /* cells (rows) */
    fdt_vid *ids;       /* a batch's rows' input ids, or NULL: row i is
                           point i (owned) */
    double *pts;        /* a batch's rows' points, 3 each, or NULL (owned) */
    double box[6];
    double *volume, *area, *centroid, *density; /* owned */
    int32_t *nfaces;                            /* owned */
    uint8_t *flags;                             /* owned */
    size_t zero_faces;
    unsigned skip;      /* FDT_CELLS_NO_*: centroid, density NULL */
    unsigned periodic;  /* a periodic set's cells: bits 0-2 the periodic
                           axes (fdt_voronoi_set_periodic), else 0 */
    double period[3];   /* the periods on those axes */
    size_t *nstart; /* n + 1 offsets, or NULL (owned) */
    fdt_vid *nid;   /* owned */
    double *narea;  /* owned */
    /* fdt_voronoi_polyhedron's cell and answer (owned) */
    fdt_cell poly;
    double *pverts;
    int32_t *pfaces;
    size_t cap_pverts, cap_pfaces;
};

/* The polyMesh dual's and the polyhedra's second rule
 * (fdt_voronoi_resolution's coords): a Delaunay edge at least 2^-40 of
 * its points' coordinates. */
#define VORONOI_COORD_EXP -40
/* The box sizes whose cells doubles hold (fdt_voronoi_scale): the box's
 * largest side D = f 2^ed, f in [1/2, 1), ed in this range. A cell's
 * volume lies between about 2^-150 D^3 (edges down to 2^-48 D) and D^3,
 * its density between 2^2 D^-3 and 2^152 D^-3: all normal doubles. */
#define VORONOI_MIN_EXP (-290)
#define VORONOI_MAX_EXP 340

/* A work flag beside the public ones: a cell inside the box cut rather
 * than summed (its shares cancel too much). */
#define CELL_CUT 0x80u
/* Another: a point whose DTFE sum is summed again on a grid of its own
 * (tet_pass). */
#define DTFE_FINE 0x40u

/* The computation's own numbering (entry 92 of bench/NOTES.md): the
 * distinct points in Morton order of their coordinates, so that a tet's
 * points and accumulators lie near the previous tet's. Shares are
 * computed from coordinates, never from numbers, so the numbering changes
 * no bit of the result. */
typedef struct vwork {
    size_t n, m;        /* input points; distinct points, numbered 0..m-1 */
    size_t nown;        /* the points whose cells are wanted, 0..nown-1:
                           all m, or a batch's (fdt_voronoi_batch: the
                           rest are their neighbours, numbered after) */
    int batch;          /* rows are local ids 0..nown-1, not input ids */
    uint32_t *perm;     /* local -> input id (owned) */
    uint32_t *loc;      /* input id -> local id, UINT32_MAX if merged
                           (owned; NULL in a batch) */
    double *xyz;        /* 3m local coordinates (owned) */
    uint32_t *tets;     /* 4 local ids a tet, by lowest id (owned) */
    size_t ntets;
    const fdt_vid *rtets; /* the result's tets, in input ids, until
                             bucket_tets maps them into tets (NULL in a
                             batch: its tets are local already) */
    unsigned skip;      /* FDT_CELLS_NO_*: the moments, the DTFE sums left out */
    unsigned periodic;  /* a periodic set's batch: its periodic axes (add_tet) */
    size_t *bcnt;       /* bucket_tets's: each key's next entry */
    uint32_t *btets;    /* and the tets it fills */
    uint8_t *flags;     /* local (owned) */
    double box[6];
    /* the accumulators: per point its volume, the scale of its volume
     * shares' rounding (how much they cancel), its moment about itself
     * (centroid times volume, relative to the point) and the volume of
     * its tets (DTFE); the faces' are the jobs' */
    fdt_fix *vol, *vabs, *mom, *dtfe; /* owned */
    fdt_fix_grid g_area, g_vol, g_mom;
    int ed;                  /* the frame's scale (scale_frame) */
    double min_edge;         /* the shortest Delaunay edge the cells hold */
    const struct vjob *jobs; /* the threads' shares, in order of their points */
    int njobs;
    double *vmax;         /* per point: its largest tet's volume, then (DTFE_FINE)
                           * the step of its own DTFE grid (owned) */
    struct vcell *cells;  /* the own points' cells, by local id, in the
                             computation's frame (owned by cells_run) */
} vwork;

/* A cell as cell_pass computes it, in local order: the rows are then
 * written in their own order (rows_pass), one sequential write a row and
 * a read that can be prefetched, where writing each row as its cell was
 * computed wrote six arrays at random (bench/NOTES.md entry 112). */
typedef struct vcell {
    double volume, area, centroid[3], density;
    int32_t nfaces;
    uint8_t flags;
} vcell;

/* One thread's share: the points [lo, hi) of the local numbering, and
 * the rows [rlo, rhi) of the output. */
typedef struct vjob {
    vwork *w;
    fdt_voronoi *v;
    uint32_t lo, hi;
    size_t rlo, rhi;
    /* point l's neighbours, ascending, adj[adj_start[l - lo] ..
     * adj_start[l - lo + 1]), and the area of the face to each: summed
     * exactly (fsum) until the cells are out, then (areas_pass) the same
     * memory as doubles (farea), half of it given back (owned) */
    size_t *adj_start;
    uint32_t *adj;
    /* own point x's first entry above x that cell_pass has not yet copied
     * to its upper neighbour, relative to its list's start (owned) */
    uint32_t *up;
    union {
        fdt_fix *fsum;
        double *farea;
    };
    fdt_cell cell;
    fdt_cell_face *face; /* its cut cells' real faces, by label (owned) */
    size_t nface, capface;
    uint32_t *order;     /* scratch: a cell's neighbours in cutting order */
    double *dist;        /* scratch: their squared distances */
    size_t cap_order;
    uint64_t *nkey;      /* scratch: a row's neighbours' keys (neighbors_pass) */
    size_t cap_nkey;
    size_t *first;       /* cut cell lo + k: its faces from face[first[k]] */
    size_t nbucket, bbase; /* the tets whose key is in [lo, hi): how many; where
                              they start */
    size_t zero_faces;
    uint32_t short_a, short_b; /* the least edge too short (fdt_edge_less), local ids, or
                                  UINT32_MAX */
    int err;
} vjob;

/* The sizes fdt_voronoi_options has had: this header's, and the one
 * before skip. */
static int options_size_known(size_t size)
{
    return size == sizeof(fdt_voronoi_options) || size == offsetof(fdt_voronoi_options, skip);
}

int fdt_default_voronoi_options_sized(fdt_voronoi_options *o, size_t struct_size)
{
    return fdt_abi_reset(o, struct_size, options_size_known(struct_size));
}

int fdt_voronoi_options_read(const fdt_voronoi_options *o, fdt_voronoi_options *full)
{
    if (!options_size_known(o->struct_size))
        return FDT_EINVAL;
    memset(full, 0, sizeof *full);
    memcpy(full, o, o->struct_size);
    full->struct_size = sizeof *full;
    return full->skip & ~(FDT_CELLS_NO_CENTROIDS | FDT_CELLS_NO_DENSITIES) ? FDT_EINVAL : FDT_OK;
}

void fdt_voronoi_free(fdt_voronoi **pv)
{
    if (!pv || !*pv)
        return;
    fdt_voronoi *v = *pv;
    free(v->ids);
    free(v->pts);
    free(v->volume);
    free(v->area);
    free(v->centroid);
    free(v->density);
    free(v->nfaces);
    free(v->flags);
    free(v->nstart);
    free(v->nid);
    free(v->narea);
    fdt_cell_free(&v->poly);
    free(v->pverts);
    free(v->pfaces);
    free(v);
    *pv = NULL;
}

int fdt_voronoi_box_of(const double *xyz, const fdt_vid *ids, size_t n,
                       const fdt_voronoi_options *o, double box[6], char *diag, size_t ds)
{
    if (o->box_given) {
        memcpy(box, o->box, 6 * sizeof *box);
        for (int k = 0; k < 3; k++)
            if (!(box[k] < box[k + 3]) || !isfinite(box[k]) || !isfinite(box[k + 3])) {
                fdt_diag(diag, ds, "the box is empty or not finite in %c", "xyz"[k]);
                return FDT_EINVAL;
            }
        for (size_t i = 0; i < n; i++)
            for (int k = 0; k < 3; k++)
                if (xyz[3 * i + k] < box[k] || xyz[3 * i + k] > box[k + 3]) {
                    fdt_diag(diag, ds, "point %zu (%.17g %.17g %.17g) lies outside the box",
                             ids ? (size_t)(uint32_t)ids[i] : i, xyz[3 * i], xyz[3 * i + 1],
                             xyz[3 * i + 2]);
                    return FDT_EINVAL;
                }
        return FDT_OK;
    }
    /* a merged duplicate is where its point is; a point not finite (which
     * the triangulation refuses) is left out */
    for (int k = 0; k < 3; k++) {
        box[k] = INFINITY;
        box[k + 3] = -INFINITY;
    }
    for (size_t i = 0; i < n; i++) {
        const double *p = xyz + 3 * i;
        if (isfinite(p[0]) && isfinite(p[1]) && isfinite(p[2]))
            for (int k = 0; k < 3; k++) {
                box[k] = fmin(box[k], p[k]);
                box[k + 3] = fmax(box[k + 3], p[k]);
            }
    }
    return FDT_OK;
}

static inline double max2(double a, double b)
{
    return a > b ? a : b; /* finite operands: fmax is a library call here */
}

/* The largest coordinate of a and b in magnitude (the coords rule). */
static double coord_mag(const double *a, const double *b)
{
    double mag = 0;
    for (int k = 0; k < 3; k++)
        mag = max2(mag, max2(fabs(a[k]), fabs(b[k])));
    return mag;
}

int fdt_voronoi_scale(const double box[6], int *ed, char *diag, size_t ds)
{
    double d = fdt_box_side(box);
    (void)frexp(d, ed);
    if (*ed >= VORONOI_MIN_EXP && *ed <= VORONOI_MAX_EXP)
        return FDT_OK;
    fdt_diag(diag, ds, "the box's largest side is %g: the Voronoi cells' volumes and densities "
        "would leave what doubles hold (boxes from 2^%d to 2^%d, about %.1e to %.1e); scale the "
        "points by a power of two, which changes none of their bits but the exponent", d,
        VORONOI_MIN_EXP - 1, VORONOI_MAX_EXP, ldexp(1, VORONOI_MIN_EXP - 1),
        ldexp(1, VORONOI_MAX_EXP));
    return FDT_ERANGE;
}

/* The computation's frame: the local coordinates and the box times
 * 2^-ed, so that the box's largest side lies in [1/2, 1). Every operation
 * of the cells commutes with a power of two, so the results scaled back
 * (rows_pass) are the same bits as in the points' own frame wherever
 * that frame kept clear of underflow and overflow, and the same bits at
 * every scale. */
static void scale_frame(vwork *w)
{
    for (size_t c = 0; c < 3 * w->m; c++)
        w->xyz[c] = ldexp(w->xyz[c], -w->ed);
    for (int k = 0; k < 6; k++)
        w->box[k] = ldexp(w->box[k], -w->ed);
}

/* The grids: terms up to about 16 D^k for the box's largest side D land
 * near 2^102 grid steps (fixsum.h's range). */
static void set_grids(vwork *w)
{
    int ed;
    (void)frexp(fdt_box_side(w->box), &ed);
    w->g_area = fdt_fix_grid_of(2 * ed - 98);
    w->g_vol = fdt_fix_grid_of(3 * ed - 98);
    w->g_mom = fdt_fix_grid_of(4 * ed - 98);
}

/* ---------------------------------------------------------------- numbering */

/* perm, loc and the local coordinates. */
static int number_points(vwork *w, const fdt_result *r, const double *xyz)
{
    uint8_t *merged = malloc(w->n ? w->n : 1);
    w->loc = fdt_mem_alloc_huge(w->n ? w->n : 1, sizeof *w->loc, 0);
    w->perm = fdt_mem_alloc_huge(w->n ? w->n : 1, sizeof *w->perm, 0);
    if (!merged || !w->loc || !w->perm) {
        free(merged);
        return FDT_ENOMEM;
    }
    for (size_t i = 0; i < w->n; i++) {
        merged[i] = r->dupmap[i] != (fdt_vid)i;
        w->loc[i] = UINT32_MAX;
    }
    long m = fdt_morton_order(xyz, w->n, w->box, merged, w->perm);
    free(merged);
    if (m < 0)
        return FDT_ENOMEM;
    w->m = (size_t)m;
    w->xyz = fdt_mem_alloc_huge(3 * (w->m ? w->m : 1), sizeof *w->xyz, 0);
    if (!w->xyz)
        return FDT_ENOMEM;
    for (size_t l = 0; l < w->m; l++) {
        uint32_t g = w->perm[l];
        w->loc[g] = (uint32_t)l;
        memcpy(w->xyz + 3 * l, xyz + 3 * (size_t)g, 3 * sizeof *xyz);
    }
    return FDT_OK;
}

/* The result's tets as the source of the local ones (bucket_tets maps
 * them to local ids as it buckets them). */
static void local_tets(vwork *w, const fdt_result *r)
{
    w->ntets = r->ntets;
    w->rtets = r->tets;
}

/* ---------------------------------------------------------------- tet pass */

/* The entry of nb in the job's point i's neighbour list (ascending, nb
 * in it): a binary search whose steps are conditional moves, not branches
 * (a list holds about 15; each step's side is a coin flip). */
static size_t slot(const vjob *j, uint32_t i, uint32_t nb)
{
    size_t b = j->adj_start[i - j->lo], n = j->adj_start[i - j->lo + 1] - b;
    const uint32_t *a = j->adj + b;
    while (n > 1) {
        size_t half = n / 2;
        a = a[half] <= nb ? a + half : a;
        n -= half;
    }
    return (size_t)(a - j->adj);
}

static void sub3(const double *a, const double *b, double *d)
{
    d[0] = a[0] - b[0];
    d[1] = a[1] - b[1];
    d[2] = a[2] - b[2];
}

static double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double *a, const double *b, double *c)
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static double triple(const double *a, const double *b, const double *c)
{
    double x[3];
    cross3(b, c, x);
    return dot3(a, x);
}

/* p after q in lexicographic (x, y, z) order (distinct points). */
static inline int lex_after(const double *p, const double *q)
{
    if (p[0] != q[0])
        return p[0] > q[0];
    if (p[1] != q[1])
        return p[1] > q[1];
    return p[2] > q[2];
}

static int mine(const vjob *j, uint32_t x)
{
    return x >= j->lo && x < j->hi;
}

/* Tet tv's points in canonical order, the points' lexicographic order
 * (not their ids, which change with the input's order) into s, their
 * differences from s[0] into q[1 .. 3]: the same bits whichever way round
 * the tet came. Returns the orientation in that order (+1 or -1). */
static inline int canon_tet(const double *X, const uint32_t *tv, uint32_t s[4], double q[4][3])
{
    /* Each point's rank is the number of points before it, from the six
     * comparisons, with no branch on their outcomes (an insertion sort's
     * were a coin flip each: 5 % of the tet pass); the orientation's
     * sign is the parity of the pairs out of order. */
    const double *p[4];
    for (int m = 0; m < 4; m++)
        p[m] = X + 3 * (size_t)tv[m];
    int c01 = lex_after(p[0], p[1]), c02 = lex_after(p[0], p[2]), c03 = lex_after(p[0], p[3]);
    int c12 = lex_after(p[1], p[2]), c13 = lex_after(p[1], p[3]), c23 = lex_after(p[2], p[3]);
    s[c01 + c02 + c03] = tv[0];
    s[1 - c01 + c12 + c13] = tv[1];
    s[2 - c02 - c12 + c23] = tv[2];
    s[3 - c03 - c13 - c23] = tv[3];
    const double *p0 = X + 3 * (size_t)s[0];
    q[0][0] = q[0][1] = q[0][2] = 0;
    for (int m = 1; m < 4; m++)
        sub3(X + 3 * (size_t)s[m], p0, q[m]);
    return (c01 + c02 + c03 + c12 + c13 + c23) & 1 ? -1 : 1;
}

/* fdt_voronoi_resolution's refusal of points a and b (input ids, named
 * lower first), len apart: FDT_ERANGE. */
static int too_close(long long a, long long b, double len, double scale, int near, int box_exp,
                     int coords, char *diag, size_t ds)
{
    fdt_diag(diag, ds, "points %lld and %lld are %g apart %s %g: their Voronoi "
        "cells are beyond what doubles hold (a Delaunay edge must be at least "
        "2^%d of the box%s)", a < b ? a : b, a < b ? b : a, len,
        near ? "at coordinates near" : "in a box", scale, box_exp,
        coords ? " and 2^-40 of its points' coordinates" : "");
    return FDT_ERANGE;
}

/* Tet tv's volume for the DTFE sums summed again (tet_pass), taken from its vertex nearest the
 * others (the least reach: its longest edge, in any axis; ties: the
 * lexicographically first): a sliver of three clustered points and a far
 * one, taken from the far one as the shares take it (the lexicographic
 * first), lost every bit in its three long rounded differences (1.5e-21
 * for a true 1e-23, either sign); from a clustered one two differences are
 * exact and the third long one rounds once. A function of the four
 * points, whatever the tet's order, to the bit. */
static double tet_volume(const double *X, const uint32_t *tv)
{
    const double *p[4];
    for (int m = 0; m < 4; m++)
        p[m] = X + 3 * (size_t)tv[m];
    /* each edge's length in any axis once, then each vertex's reach */
    double e[4][4];
    for (int a = 0; a < 4; a++)
        for (int b = a + 1; b < 4; b++)
            e[a][b] = e[b][a] = max2(max2(fabs(p[a][0] - p[b][0]), fabs(p[a][1] - p[b][1])),
                                     fabs(p[a][2] - p[b][2]));
    int best = 0;
    double least = INFINITY;
    for (int m = 0; m < 4; m++) {
        double reach = 0;
        for (int o = 0; o < 4; o++)
            if (o != m)
                reach = max2(reach, e[m][o]);
        if (reach < least || (reach == least && lex_after(p[best], p[m]))) {
            least = reach;
            best = m;
        }
    }
    /* the other three in lexicographic order too: the same rounding
     * whichever way round the tet came */
    const double *o3[3];
    for (int o = 0, r = 0; o < 4; o++)
        if (o != best)
            o3[r++] = p[o];
    for (int x = 1; x < 3; x++)
        for (int y = x; y > 0 && lex_after(o3[y - 1], o3[y]); y--) {
            const double *t = o3[y];
            o3[y] = o3[y - 1];
            o3[y - 1] = t;
        }
    double q[3][3];
    for (int r = 0; r < 3; r++)
        sub3(o3[r], p[best], q[r]);
    return fabs(triple(q[0], q[1], q[2])) / 6;
}

/* add_tet's body for the quantities asked for (moments: the centroids',
 * dtfe: the densities'), constants where add_tet calls it, so that each
 * case compiles without the others' work or tests. */
__attribute__((always_inline)) static inline void add_tet_for(vjob *j, const uint32_t *tv,
                                                              const int moments, const int dtfe)
{
    vwork *w = j->w;
    const double *X = w->xyz;
    /* fdt_voronoi_resolution's rule for these cells (box_exp -48, no
     * coords), checked here rather than in a pass of its own: a tet with
     * an edge too short adds nothing (its terms could leave the grid's
     * range), and its edge refuses the input after the pass. */
    int too_short = 0;
    for (int e = 0; e < 6; e++) {
        uint32_t a = tv[fdt_tet_edge[e][0]], b = tv[fdt_tet_edge[e][1]];
        if (fdt_cheb(X + 3 * (size_t)a, X + 3 * (size_t)b) < w->min_edge) {
            too_short = 1;
            if (j->short_a == UINT32_MAX || fdt_edge_less(w->perm[a], w->perm[b],
                                                          w->perm[j->short_a], w->perm[j->short_b])) {
                j->short_a = a;
                j->short_b = b;
            }
        }
    }
    if (too_short)
        return;
    uint32_t s[4];
    double q[4][3];
    int sigma = canon_tet(X, tv, s, q);
    /* which of the canonical points are the job's (bit m: s[m]) */
    unsigned own = 0;
    for (int m = 0; m < 4; m++)
        own |= (unsigned)mine(j, s[m]) << m;
    /* the DTFE share from the canonical differences (tet_volume, more
     * careful and slower, for the sums too small for the box's grid) */
    if (dtfe) {
        double dv = fabs(triple(q[1], q[2], q[3])) / 6;
        for (int m = 0; m < 4; m++)
            if (own >> m & 1) {
                fdt_fix_add(&w->dtfe[s[m]], dv, w->g_vol);
                w->vmax[s[m]] = max2(w->vmax[s[m]], dv);
            }
    }
    const double *p0 = X + 3 * (size_t)s[0];
    double c[3];
    if (fdt_circumcenter(p0, X + 3 * (size_t)s[1], X + 3 * (size_t)s[2], X + 3 * (size_t)s[3],
                         c) != 0) {
        /* Four coplanar points (a flat tet of the perturbed mesh: four
         * cocircular points of a plane, as scans and surfaces of
         * revolution have) have no centre to share out: their cells are
         * cut instead, which the box need not have done (a periodic set's
         * cells never meet it: gen_points torus and cone in a periodic
         * box were refused as cells reaching past their images). */
        for (int m = 0; m < 4; m++)
            if (own >> m & 1)
                w->flags[s[m]] |= CELL_CUT;
        return;
    }
    /* Against the walls relative to p0, as c is: p0 + c rounds at the
     * coordinates' scale (points at 2^40 on a 2^-12 grid: a centre a
     * half step outside rounded onto the wall, and its cells were summed
     * past the box, 3e-6 off), box - p0 at the cell's. */
    unsigned outside = 0; /* the axes along which c leaves the box */
    for (int k = 0; k < 3; k++)
        if (!(c[k] >= w->box[k] - p0[k] && c[k] <= w->box[k + 3] - p0[k]))
            outside |= 1u << k;
    if (outside) {
        /* Along a periodic axis a batch's box is three periods each side
         * (src/mesh/periodic.c), which no true centre leaves (an empty
         * ball is less than a period's diagonal across): one out there is
         * a nearly flat tet's among rounded images (gen_points torus: a
         * tet 2e-20 thick whose centre, 0.1 from its points, came out 9
         * periods away from images rounded by 1e-17). Its cells are cut
         * from the box by their neighbours' bisectors, which rounding
         * moves by as little; only a wall clips them. */
        unsigned flag = outside & ~w->periodic ? FDT_CELL_CLIPPED : CELL_CUT;
        for (int m = 0; m < 4; m++)
            if (own >> m & 1)
                w->flags[s[m]] |= flag;
        return;
    }
    /* f[m]: the circumcentre of the face opposite m, relative to p0. It
     * is computed from the face's own points (edges from its lowest), so
     * the two tets on a face use the same point to the last bit: their
     * shares along the Voronoi edge then cancel where they should. */
    double f[4][3];
    for (int m = 0; m < 4; m++) {
        int u0 = m == 0 ? 1 : 0, u1 = m <= 1 ? 2 : 1, u2 = m <= 2 ? 3 : 2;
        double x[3];
        fdt_circumcenter_tri(X + 3 * (size_t)s[u0], X + 3 * (size_t)s[u1],
                             X + 3 * (size_t)s[u2], x);
        for (int k = 0; k < 3; k++)
            f[m][k] = q[u0][k] + x[k];
    }
    /* Each point's volume and moment shares, summed here in a fixed order
     * (the edges') and added to the grid once a tet. An edge's two cones
     * (from i and from j over the same triangles) have the same volume;
     * their moments about p0 differ by 3 (P_j - P_i) times it, so gm
     * gathers the common part and each point's own part, -3 P vsum, is
     * applied once after the loop. */
    double vsum[4] = {0, 0, 0, 0}, vabs[4] = {0, 0, 0, 0};
    double gm[4][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
    for (int e = 0; e < 6; e++) {
        const int *te = fdt_tet_edge[e];
        int i = te[0], jj = te[1], k = te[2], l = te[3];
        int mi = own >> i & 1, mj = own >> jj & 1;
        if (!mi && !mj)
            continue;
        double o = sigma * te[4];
        double u[3], mid[3], cm[3], fp[3], fn[3];
        sub3(q[jj], q[i], u);
        for (int d = 0; d < 3; d++)
            mid[d] = 0.5 * (q[i][d] + q[jj][d]);
        sub3(c, mid, cm);
        /* Counter-clockwise about u, face (i,j,k) comes before (i,j,l)
         * when (i,j,k,l) is positive: F_prev is the face without l. */
        sub3(o > 0 ? f[l] : f[k], mid, fp);
        sub3(o > 0 ? f[k] : f[l], mid, fn);
        /* Twice the signed areas of (M, F, C), seen along u, times |u|. */
        double ap = triple(u, fp, cm), an = triple(u, fn, cm);
        /* The face's area, once a tet, in the entry of the edge's lower
         * point (its other end reads it there after the pass: cell_pass). */
        int low = s[i] < s[jj] ? i : jj;
        if (low == i ? mi : mj)
            fdt_fix_add(&j->fsum[slot(j, s[low], s[low == i ? jj : i])],
                        (ap - an) / (2 * sqrt(dot3(u, u))), w->g_area);
        /* The cones from i (and from j, its mirror image): volume
         * area |u| / 6, each piece's centroid (P + M + F + C) / 4. */
        double vp = ap / 12, vn = an / 12, cone = vp - vn;
        /* the scale of their rounding: |u| (|F_prev - M| + |F_next - M|) |C - M| */
        double scale = (fabs(u[0]) + fabs(u[1]) + fabs(u[2])) * (fabs(cm[0]) + fabs(cm[1]) + fabs(cm[2])) *
                       (fabs(fp[0]) + fabs(fp[1]) + fabs(fp[2]) + fabs(fn[0]) + fabs(fn[1]) + fabs(fn[2])) / 12;
        double g[3];
        for (int d = 0; moments && d < 3; d++)
            g[d] = cone * (2 * mid[d] + c[d]) + vp * fp[d] - vn * fn[d];
        for (int end = 0; end < 2; end++) {
            int at = end ? jj : i;
            if (!(end ? mj : mi))
                continue;
            vsum[at] += cone;
            vabs[at] += scale;
            for (int d = 0; moments && d < 3; d++)
                gm[at][d] += g[d];
        }
    }
    for (int m = 0; m < 4; m++)
        if (own >> m & 1) {
            fdt_fix_add(&w->vol[s[m]], vsum[m], w->g_vol);
            fdt_fix_add(&w->vabs[s[m]], vabs[m], w->g_vol);
            for (int d = 0; moments && d < 3; d++)
                fdt_fix_add(&w->mom[3 * (size_t)s[m] + d], (gm[m][d] - 3 * q[m][d] * vsum[m]) / 4,
                            w->g_mom);
        }
}

/* One tet's shares to the job's points (the file's comment), those of the
 * quantities asked for: the moments (w->mom) and DTFE sums (w->dtfe) are
 * allocated only then (alloc_work). A tet whose circumcentre lies outside
 * the box adds no share: it marks its points, whose cells are then cut
 * from the box. */
static void add_tet(vjob *j, const uint32_t *tv)
{
    const vwork *w = j->w;
    if (w->mom && w->dtfe)
        add_tet_for(j, tv, 1, 1);
    else if (w->mom)
        add_tet_for(j, tv, 1, 0);
    else if (w->dtfe)
        add_tet_for(j, tv, 0, 1);
    else
        add_tet_for(j, tv, 0, 0);
}

/* ---------------------------------------------------------------- cells */

/* A face counts when its area is above 2^-40 of its cell's surface. */
static int real_face(double area, double total)
{
    return area > FDT_CELL_TOL * total;
}

/* Whether neighbour a of a point (da: its squared distance) is cut
 * before neighbour b: nearer first (its bisector cuts the most off the
 * box, so the later cuts mostly find the cell on their inner side and
 * change nothing), ties in the points' lexicographic order. A function of
 * the coordinates alone: the cuts, and so the cell's bits, do not depend
 * on how the input was numbered. */
static int cut_before(const double *a, double da, const double *b, double db)
{
    return da < db || (da == db && fdt_lex_compare(a, b) < 0);
}

/* Above this many neighbours cut_order merges sorted runs instead of
 * inserting each (a scan's outlier has tens of thousands: the insertion
 * took m^2 / 4 moves). cut_before is a strict order on distinct points,
 * so both give the same order. */
#define CUT_ORDER_MERGE 64

/* cut_order for m neighbours (adj[b ..]) of the point at p: their
 * distances, then a bottom-up merge sort of (order, dist) pairs. */
static int cut_order_merge(vjob *j, const double *p, size_t b, size_t m)
{
    const vwork *w = j->w;
    uint32_t *to = malloc(m * sizeof *to);
    double *td = malloc(m * sizeof *td);
    if (!to || !td) {
        free(to);
        free(td);
        return FDT_ENOMEM;
    }
    for (size_t e = 0; e < m; e++) {
        double d[3];
        j->order[e] = j->adj[b + e];
        sub3(w->xyz + 3 * (size_t)j->order[e], p, d);
        j->dist[e] = dot3(d, d);
    }
    uint32_t *so = j->order, *dso = to;
    double *sd = j->dist, *dsd = td;
    for (size_t width = 1; width < m; width *= 2) {
        for (size_t lo = 0; lo < m; lo += 2 * width) {
            size_t mid = lo + width < m ? lo + width : m, hi = lo + 2 * width < m ? lo + 2 * width : m;
            size_t x = lo, y = mid, o = lo;
            while (x < mid || y < hi) {
                int right = x == mid || (y < hi && cut_before(w->xyz + 3 * (size_t)so[y], sd[y],
                                                              w->xyz + 3 * (size_t)so[x], sd[x]));
                size_t k = right ? y++ : x++;
                dso[o] = so[k];
                dsd[o++] = sd[k];
            }
        }
        uint32_t *t = so;
        so = dso;
        dso = t;
        double *u = sd;
        sd = dsd;
        dsd = u;
    }
    if (so != j->order) /* dist is scratch: only the order is read after */
        memcpy(j->order, so, m * sizeof *so);
    free(to);
    free(td);
    return FDT_OK;
}

/* Point l's neighbours in cutting order (cut_before). */
static int cut_order(vjob *j, uint32_t l)
{
    const vwork *w = j->w;
    size_t b = j->adj_start[l - j->lo], m = j->adj_start[l - j->lo + 1] - b;
    if (m > j->cap_order) {
        uint32_t *q = realloc(j->order, m * sizeof *q);
        double *d = realloc(j->dist, m * sizeof *d);
        if (q)
            j->order = q;
        if (d)
            j->dist = d;
        if (!q || !d)
            return FDT_ENOMEM;
        j->cap_order = m;
    }
    const double *p = w->xyz + 3 * (size_t)l;
    if (m > CUT_ORDER_MERGE)
        return cut_order_merge(j, p, b, m);
    for (size_t e = 0; e < m; e++) {
        uint32_t nb = j->adj[b + e];
        const double *q = w->xyz + 3 * (size_t)nb;
        double d[3];
        sub3(q, p, d);
        double dn = dot3(d, d);
        size_t y = e;
        for (; y > 0 && cut_before(q, dn, w->xyz + 3 * (size_t)j->order[y - 1], j->dist[y - 1]);
             y--) {
            j->order[y] = j->order[y - 1];
            j->dist[y] = j->dist[y - 1];
        }
        j->order[y] = nb;
        j->dist[y] = dn;
    }
    return FDT_OK;
}

/* Point l's cell cut from the box by its neighbours' bisectors; its real
 * faces kept, by label (input ids; walls first). */
static int cut_cell(vjob *j, uint32_t l)
{
    const vwork *w = j->w;
    const double *p = w->xyz + 3 * (size_t)l;
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = w->box[k] - p[k];
        hi[k] = w->box[k + 3] - p[k];
    }
    if (fdt_cell_box(&j->cell, lo, hi) || cut_order(j, l))
        return FDT_ENOMEM;
    for (size_t e = 0; e < j->adj_start[l - j->lo + 1] - j->adj_start[l - j->lo]; e++) {
        uint32_t nb = j->order[e];
        double nrm[3];
        sub3(w->xyz + 3 * (size_t)nb, p, nrm);
        int got = fdt_cell_cut(&j->cell, nrm, 0.5 * dot3(nrm, nrm), (long)w->perm[nb]);
        if (got == -1)
            return FDT_ENOMEM;
        if (got < 0)
            return FDT_EINTERNAL;
    }
    size_t need = j->nface + (size_t)j->cell.nf;
    if (need > j->capface) {
        size_t nc = j->capface ? 2 * j->capface : 1024;
        while (nc < need)
            nc *= 2;
        fdt_cell_face *q = realloc(j->face, nc * sizeof *q);
        if (!q)
            return FDT_ENOMEM;
        j->face = q;
        j->capface = nc;
    }
    vcell *c = &w->cells[l];
    double cen[3];
    fdt_cell_face *fc = j->face + j->nface;
    fdt_cell_measure(&j->cell, &c->volume, &c->area, cen, fc);
    for (int k = 0; k < 3; k++)
        c->centroid[k] = p[k] + cen[k];
    size_t m = 0;
    for (int f = 0; f < j->cell.nf; f++) {
        if (!real_face(fc[f].area, c->area)) {
            j->zero_faces++;
            continue;
        }
        fdt_cell_face x = fc[f];
        size_t y = m++;
        for (; y > 0 && fc[y - 1].label > x.label; y--)
            fc[y] = fc[y - 1];
        fc[y] = x;
    }
    j->first[l - j->lo] = j->nface;
    j->nface += m;
    c->nfaces = (int32_t)m;
    return FDT_OK;
}

/* A cell summed from its tets: its values, its real faces counted. */
static void sum_cell(vjob *j, uint32_t l)
{
    const vwork *w = j->w;
    vcell *c = &w->cells[l];
    size_t e0 = j->adj_start[l - j->lo], e1 = j->adj_start[l - j->lo + 1];
    fdt_fix total = {0, 0};
    for (size_t e = e0; e < e1; e++)
        fdt_fix_merge(&total, j->fsum[e]);
    double area = fdt_fix_value(total, w->g_area);
    int32_t m = 0;
    for (size_t e = e0; e < e1; e++) {
        if (real_face(fdt_fix_value(j->fsum[e], w->g_area), area))
            m++;
        else
            j->zero_faces++;
    }
    double vol = fdt_fix_value(w->vol[l], w->g_vol);
    c->volume = vol;
    c->area = area;
    c->nfaces = m;
    for (int k = 0; w->mom && k < 3; k++)
        c->centroid[k] =
            w->xyz[3 * (size_t)l + k] + fdt_fix_value(w->mom[3 * (size_t)l + k], w->g_mom) / vol;
}

/* The job's points' neighbour lists in local ids, ascending: each point's
 * tets listed (a counting sort over the tets), the other points of those
 * tets taken once each (a bit a point, cleared after each point: m / 8
 * bytes a thread) and sorted (about 15 of the 78), and a face accumulator
 * for each. */
static int job_adjacency(vjob *j)
{
    const vwork *w = j->w;
    size_t k = j->hi - j->lo;
    size_t *ts = fdt_mem_alloc_huge(k + 1, sizeof *ts, 1);
    uint64_t *seen = calloc(w->m / 64 + 1, sizeof *seen);
    j->adj_start = fdt_mem_alloc_huge(k + 1, sizeof *j->adj_start, 0);
    j->up = fdt_mem_alloc_huge(k ? k : 1, sizeof *j->up, 0);
    if (!ts || !seen || !j->adj_start || !j->up) {
        free(ts);
        free(seen);
        return FDT_ENOMEM;
    }
    for (size_t c = 0; c < 4 * w->ntets; c++)
        if (w->tets[c] >= j->lo && w->tets[c] < j->hi)
            ts[w->tets[c] - j->lo + 1]++;
    for (size_t l = 0; l < k; l++)
        ts[l + 1] += ts[l];
    uint32_t *inc = fdt_mem_alloc_huge(ts[k] ? ts[k] : 1, sizeof *inc, 0);
    if (!inc) {
        free(ts);
        free(seen);
        return FDT_ENOMEM;
    }
    for (size_t c = 0; c < 4 * w->ntets; c++) /* ts[x]: x's next free entry */
        if (w->tets[c] >= j->lo && w->tets[c] < j->hi)
            inc[ts[w->tets[c] - j->lo]++] = (uint32_t)(c / 4);
    /* ts[x] is now the end of point lo + x's tets, ts[x - 1] their start */
    size_t cap = 16 * (k ? k : 1), o = 0;
    j->adj = fdt_mem_alloc_huge(cap, sizeof *j->adj, 0);
    for (size_t x = 0; x < k && j->adj; x++) {
        uint32_t l = j->lo + (uint32_t)x;
        size_t b = j->adj_start[x] = o, c0 = x ? ts[x - 1] : 0;
        /* room for every other point of its tets first, and one more for
         * the append's write past the list: no test an entry */
        size_t most = o + 3 * (ts[x] - c0) + 1;
        if (most > cap) {
            while (cap < most)
                cap *= 2;
            uint32_t *nq = realloc(j->adj, cap * sizeof *nq);
            if (!nq) {
                free(j->adj);
                j->adj = NULL;
                break;
            }
            j->adj = nq;
        }
        uint32_t *adj = j->adj;
        /* the point itself marked seen: its tets' other points only */
        seen[l / 64] |= UINT64_C(1) << (l % 64);
        /* each vertex written at the list's end, which moves on when it
         * is new: no branch on the seen bit (a coin flip a vertex, about
         * 15 new of 81) */
        for (size_t c = c0; c < ts[x]; c++) {
            const uint32_t *tv = w->tets + 4 * (size_t)inc[c];
            for (int q = 0; q < 4; q++) {
                uint32_t u = tv[q];
                uint64_t bit = UINT64_C(1) << (u % 64), word = seen[u / 64];
                adj[o] = u;
                o += !(word & bit);
                seen[u / 64] = word | bit;
            }
        }
        for (size_t e = b + 1; e < o; e++) { /* ascending: insertion, about 15 */
            uint32_t u = adj[e];
            size_t y = e;
            for (; y > b && adj[y - 1] > u; y--)
                adj[y] = adj[y - 1];
            adj[y] = u;
        }
        seen[l / 64] = 0;
        size_t below = 0;
        for (size_t e = b; e < o; e++) {
            seen[adj[e] / 64] = 0;
            below += adj[e] < l;
        }
        j->up[x] = (uint32_t)below;
    }
    j->adj_start[k] = o;
    free(ts);
    free(seen);
    free(inc);
    j->fsum = j->adj ? fdt_mem_alloc_huge(o ? o : 1, sizeof *j->fsum, 1) : NULL;
    return j->fsum ? FDT_OK : FDT_ENOMEM;
}

/* How many tets ahead tet_pass prefetches what add_tet reads of its
 * points' lists: the face sums' entries (slot), a cache miss a share in
 * a fifth of add_tet's samples (1M uniform), as the lists of a tet's
 * other points lie anywhere in the 248 MB of sums; the list's place a
 * step earlier (bench/NOTES.md entry 130; 8 measured the same as 4). */
#define TET_AHEAD 4

/* A thread's first pass: the tets' shares to its points. Threads write
 * disjoint entries only (their own points' accumulators and face sums);
 * pthread_join orders all of it before cell_pass reads it. */
static void *tet_pass(void *arg)
{
    vjob *j = arg;
    vwork *w = j->w;
    if ((j->err = job_adjacency(j)) != FDT_OK)
        return NULL;
    for (size_t t = 0; t < w->ntets; t++) {
        /* each own point's list place, then its neighbours and (4 lines:
         * a dozen or so entries of 16 bytes) its face sums */
        if (t + 2 * TET_AHEAD < w->ntets)
            for (int m = 0; m < 4; m++) {
                uint32_t v = w->tets[4 * (t + 2 * TET_AHEAD) + (size_t)m];
                if (mine(j, v))
                    __builtin_prefetch(&j->adj_start[v - j->lo]);
            }
        if (t + TET_AHEAD < w->ntets)
            for (int m = 0; m < 4; m++) {
                uint32_t v = w->tets[4 * (t + TET_AHEAD) + (size_t)m];
                if (!mine(j, v))
                    continue;
                size_t b = j->adj_start[v - j->lo];
                __builtin_prefetch(&j->adj[b]);
                for (int l = 0; l < 4; l++)
                    __builtin_prefetch(&j->fsum[b + 4 * (size_t)l]);
            }
        const uint32_t *tv = w->tets + 4 * t;
        if (mine(j, tv[0]) || mine(j, tv[1]) || mine(j, tv[2]) || mine(j, tv[3]))
            add_tet(j, tv);
    }
    /* A DTFE sum within 2^40 steps of the box's grid (a cluster 1e-10 wide
     * in a unit box summed to 0: a density of 0) is summed again on a grid
     * of its own, from the point's largest tet (a maximum, and the sum an
     * exact one: the same whatever the tets' order), each tet's volume by
     * tet_volume. Uniform points have none, so this second pass over the
     * tets rarely runs. */
    size_t fine = 0;
    for (uint32_t l = j->lo; w->dtfe && l < j->hi; l++) {
        if (fabs(fdt_fix_value(w->dtfe[l], w->g_vol)) >= 0x1p40 * w->g_vol.step ||
            !(w->vmax[l] > 0))
            continue;
        int ev;
        (void)frexp(w->vmax[l], &ev);
        w->vmax[l] = ldexp(1.0, ev - 98 < -1022 ? -1022 : ev - 98); /* the grid's step */
        memset(&w->dtfe[l], 0, sizeof w->dtfe[l]);
        w->flags[l] |= DTFE_FINE;
        fine++;
    }
    for (size_t t = 0; fine && t < w->ntets; t++) {
        const uint32_t *tv = w->tets + 4 * t;
        double dv = -1;
        for (int m = 0; m < 4; m++) {
            uint32_t l = tv[m];
            if (!mine(j, l) || !(w->flags[l] & DTFE_FINE))
                continue;
            if (dv < 0)
                dv = tet_volume(w->xyz, tv);
            fdt_fix_add(&w->dtfe[l], dv, fdt_fix_grid_of(ilogb(w->vmax[l])));
        }
    }
    return NULL;
}

/* The job owning local point x. */
static const vjob *owner(const vwork *w, uint32_t x)
{
    int lo = 0, hi = w->njobs - 1;
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (w->jobs[mid].lo <= x)
            lo = mid;
        else
            hi = mid - 1;
    }
    return &w->jobs[lo];
}

/* A thread's second pass, after every tet_pass: its points' faces shared
 * with lower points, whose sums the lower point's job kept (add_tet),
 * copied in; then its cells. It reads the other jobs' face sums (written
 * before the join that ended the first pass) and writes only its own
 * entries and output rows; pthread_join orders them before the caller. */
static void *cell_pass(void *arg)
{
    vjob *j = arg;
    vwork *w = j->w;
    if (j->err)
        return NULL;
    /* An own lower neighbour nb meets its upper neighbours l in
     * ascending order, as they stand in its list: its entry for l is the
     * next one above nb (j->up), no search. */
    for (uint32_t l = j->lo; l < j->hi; l++)
        for (size_t e = j->adj_start[l - j->lo]; e < j->adj_start[l - j->lo + 1]; e++) {
            uint32_t nb = j->adj[e];
            if (nb > l)
                break; /* ascending */
            if (mine(j, nb)) {
                j->fsum[e] = j->fsum[j->adj_start[nb - j->lo] + j->up[nb - j->lo]++];
            } else {
                const vjob *oj = owner(w, nb);
                j->fsum[e] = oj->fsum[slot(oj, nb, l)];
            }
        }
    for (uint32_t l = j->lo; l < j->hi && !j->err; l++) {
        vcell *c = &w->cells[l];
        c->flags = w->flags[l] & (FDT_CELL_CLIPPED | FDT_CELL_HULL);
        double dt = !w->dtfe                 ? 0
                    : w->flags[l] & DTFE_FINE
                        ? fdt_fix_value(w->dtfe[l], fdt_fix_grid_of(ilogb(w->vmax[l])))
                        : fdt_fix_value(w->dtfe[l], w->g_vol);
        c->density = dt > 0 ? 4 / dt : 0;
        /* A cell whose shares' rounding scale exceeds its volume 2^8 times
         * (a needle: its Voronoi vertices far from its point for its
         * volume) would keep 8 bits less than the shares' precision: cut
         * it instead (as precise as its cut planes; at 2^12, cells of
         * 1e-3 wide clusters still lost 2e-10). Both sums are exact, so
         * the choice is the same for every order of the tets. */
        /* So is a cell too small for the grid: its summed volume within
         * 2^40 steps of it keeps fewer bits than 1e-12 asks (a cluster
         * 1e-10 wide in a unit box summed to 0). */
        double vl = fabs(fdt_fix_value(w->vol[l], w->g_vol));
        if (!(w->flags[l] & FDT_CELL_CLIPPED) &&
            (fdt_fix_value(w->vabs[l], w->g_vol) > 0x1p8 * vl || vl < 0x1p40 * w->g_vol.step))
            w->flags[l] |= CELL_CUT;
        if (w->flags[l] & (FDT_CELL_CLIPPED | CELL_CUT))
            j->err = cut_cell(j, l);
        else
            sum_cell(j, l);
        if (j->err == FDT_EINTERNAL)
            j->lo = l; /* the point, for the message */
    }
    return NULL;
}

/* A thread's face sums, after every cell_pass (which read the other
 * jobs' sums: pthread_join orders those reads before these writes), as
 * doubles in place: entry e's double at byte 8 e, its sum read from byte
 * 16 e, so going up every sum is read before its bytes are written over.
 * The upper half is then given back (realloc shrinks in place), before
 * the neighbour lists are allocated: 8 bytes a face less at the run's
 * peak, whose fresh pages cost (bench/NOTES.md entry 130). */
static void *areas_pass(void *arg)
{
    vjob *j = arg;
    const vwork *w = j->w;
    size_t o = j->adj_start[j->hi - j->lo];
    char *b = (char *)j->fsum;
    for (size_t e = 0; e < o; e++) {
        /* byte copies: the compiler keeps each read before the writes
         * over its bytes, whatever the two types */
        fdt_fix f;
        memcpy(&f, b + e * sizeof f, sizeof f);
        double a = fdt_fix_value(f, w->g_area);
        memcpy(b + e * sizeof a, &a, sizeof a);
    }
    double *q = realloc(j->farea, (o ? o : 1) * sizeof *q);
    if (q) /* else the block stays whole: no loss */
        j->farea = q;
    return NULL;
}

/* ---------------------------------------------------------------- results */

/* The local point of output row g: the row itself in a batch, else the
 * row's point's local id (UINT32_MAX: a merged duplicate, whose row
 * stays zero). */
static inline uint32_t local_of(const vwork *w, size_t g)
{
    return w->batch ? (uint32_t)g : w->loc[g];
}

/* How many rows ahead the row passes prefetch what a row reads (its
 * local point's data lie anywhere: input order is not the local order). */
#define ROW_AHEAD 16

/* The factors that take the computation's frame back to the points'
 * (scale_frame): volumes times 2^(3 ed), areas 2^(2 ed), centroids 2^ed,
 * densities 2^(-3 ed). Products with powers of two, not ldexp calls (4 %
 * of a 300k --voronoi run): ed is in [VORONOI_MIN_EXP, VORONOI_MAX_EXP],
 * so each factor is a normal double, and x 2^k rounds once, as ldexp
 * does, underflow and overflow included: the same bits. */
typedef struct vscale {
    double f1, f2, f3, fm3;
} vscale;

static vscale scale_of(const vwork *w)
{
    vscale s = {ldexp(1, w->ed), ldexp(1, 2 * w->ed), ldexp(1, 3 * w->ed), ldexp(1, -3 * w->ed)};
    return s;
}

/* A thread's rows [rlo, rhi): each its point's cell (cell_pass), in the
 * points' frame. Writes only its rows; pthread_join orders them before
 * the caller. */
static void *rows_pass(void *arg)
{
    vjob *j = arg;
    const vwork *w = j->w;
    fdt_voronoi *v = j->v;
    const vscale f = scale_of(w);
    for (size_t g = j->rlo; g < j->rhi; g++) {
        if (g + ROW_AHEAD < j->rhi) {
            uint32_t la = local_of(w, g + ROW_AHEAD);
            if (la != UINT32_MAX) { /* 56 bytes: one or two lines */
                __builtin_prefetch(&w->cells[la]);
                __builtin_prefetch((const char *)&w->cells[la] + sizeof(vcell) - 1);
            }
        }
        uint32_t l = local_of(w, g);
        if (l == UINT32_MAX)
            continue;
        const vcell *c = &w->cells[l];
        v->volume[g] = c->volume * f.f3;
        v->area[g] = c->area * f.f2;
        if (v->density)
            v->density[g] = c->density * f.fm3;
        for (int k = 0; v->centroid && k < 3; k++)
            v->centroid[3 * g + k] = c->centroid[k] * f.f1;
        v->nfaces[g] = c->nfaces;
        v->flags[g] = c->flags;
    }
    return NULL;
}

/* A thread's rows' neighbour lists (v->nstart set): a summed cell's from
 * its list's entries (which its job keeps), a cut cell's from its faces
 * (both by input id, walls first), the areas in the points' frame. */
static void *neighbors_pass(void *arg)
{
    vjob *j = arg;
    const vwork *w = j->w;
    fdt_voronoi *v = j->v;
    const double f2 = scale_of(w).f2;
    for (size_t g = j->rlo; g < j->rhi; g++) {
        /* three reads deep, a stage a distance: the list's place, then
         * the list, then its points' input ids */
        if (g + 2 * ROW_AHEAD < j->rhi) {
            uint32_t la = local_of(w, g + 2 * ROW_AHEAD);
            if (la != UINT32_MAX) {
                const vjob *oa = owner(w, la);
                __builtin_prefetch(&oa->adj_start[la - oa->lo]);
                __builtin_prefetch(&w->flags[la]);
                __builtin_prefetch(&w->cells[la].area);
            }
        }
        if (g + ROW_AHEAD < j->rhi) {
            uint32_t la = local_of(w, g + ROW_AHEAD);
            if (la != UINT32_MAX) {
                const vjob *oa = owner(w, la);
                size_t b = oa->adj_start[la - oa->lo];
                __builtin_prefetch(&oa->adj[b]);
                __builtin_prefetch(&oa->farea[b]);
                __builtin_prefetch(&oa->farea[b] + 8);
            }
        }
        if (g + ROW_AHEAD / 2 < j->rhi) {
            uint32_t la = local_of(w, g + ROW_AHEAD / 2);
            if (la != UINT32_MAX) {
                const vjob *oa = owner(w, la);
                size_t b = oa->adj_start[la - oa->lo], e1 = oa->adj_start[la - oa->lo + 1];
                for (size_t e = b; e < e1; e++)
                    __builtin_prefetch(&w->perm[oa->adj[e]]);
            }
        }
        uint32_t l = local_of(w, g);
        if (l == UINT32_MAX)
            continue;
        const vjob *oj = owner(w, l);
        size_t o = v->nstart[g], k = (size_t)v->nfaces[g];
        if (w->flags[l] & (FDT_CELL_CLIPPED | CELL_CUT)) {
            const fdt_cell_face *fc = oj->face + oj->first[l - oj->lo];
            for (size_t f = 0; f < k; f++) {
                v->nid[o + f] = (fdt_vid)fc[f].label;
                v->narea[o + f] = fc[f].area * f2;
            }
            continue;
        }
        double total = w->cells[l].area;
        if (k > j->cap_nkey) {
            uint64_t *q = realloc(j->nkey, k * sizeof *q);
            if (!q) {
                j->err = FDT_ENOMEM;
                return NULL;
            }
            j->nkey = q;
            j->cap_nkey = k;
        }
        /* The real faces as keys, input id << 32 | entry, sorted: one
         * 8-byte move an insertion step (a dozen entries, in local order,
         * which is not the ids'), where moving the ids, areas and points
         * apart took most of the pass. */
        size_t e0 = oj->adj_start[l - oj->lo], e1 = oj->adj_start[l - oj->lo + 1], m = 0;
        const uint32_t *nb = oj->adj + e0;
        uint64_t *key = j->nkey;
        for (size_t e = e0; e < e1; e++) {
            if (!real_face(oj->farea[e], total))
                continue;
            uint64_t x = (uint64_t)w->perm[nb[e - e0]] << 32 | (e - e0);
            size_t y = m++;
            for (; y > 0 && key[y - 1] > x; y--)
                key[y] = key[y - 1];
            key[y] = x;
        }
        /* Two images of one point (a periodic set's) in their
         * coordinates' order, not the numbering's, which differs from
         * batch to batch: runs of one id sorted again (rare). */
        for (size_t a = 0, b; a < m; a = b) {
            for (b = a + 1; b < m && key[b] >> 32 == key[a] >> 32; b++)
                ;
            for (size_t x = a + 1; x < b; x++) {
                uint64_t kx = key[x];
                const double *px = w->xyz + 3 * (size_t)nb[(uint32_t)kx];
                size_t y = x;
                for (; y > a; y--) {
                    const double *py = w->xyz + 3 * (size_t)nb[(uint32_t)key[y - 1]];
                    if (fdt_lex_compare(py, px) <= 0)
                        break;
                    key[y] = key[y - 1];
                }
                key[y] = kx;
            }
        }
        for (size_t f = 0; f < m; f++) {
            v->nid[o + f] = (fdt_vid)(key[f] >> 32);
            v->narea[o + f] = oj->farea[e0 + (uint32_t)key[f]] * f2;
        }
    }
    return NULL;
}

/* The rows, but those skip leaves out (v->skip). */
static int alloc_cells(fdt_voronoi *v, unsigned skip)
{
    size_t n = v->n ? v->n : 1;
    int cen = !(skip & FDT_CELLS_NO_CENTROIDS), dens = !(skip & FDT_CELLS_NO_DENSITIES);
    v->skip = skip;
    v->volume = fdt_mem_alloc_huge(n, sizeof *v->volume, 1);
    v->area = fdt_mem_alloc_huge(n, sizeof *v->area, 1);
    v->centroid = cen ? fdt_mem_alloc_huge(3 * n, sizeof *v->centroid, 1) : NULL;
    v->density = dens ? fdt_mem_alloc_huge(n, sizeof *v->density, 1) : NULL;
    v->nfaces = fdt_mem_alloc_huge(n, sizeof *v->nfaces, 1);
    v->flags = fdt_mem_alloc_huge(n, sizeof *v->flags, 1);
    return v->volume && v->area && (v->centroid || !cen) && (v->density || !dens) && v->nfaces &&
                   v->flags
               ? FDT_OK
               : FDT_ENOMEM;
}

/* The local flags and accumulators (the callers mark the hull points):
 * the moments only for the centroids, the DTFE sums and largest tets only
 * for the densities (w->skip); the passes test the pointers. */
static int alloc_work(vwork *w)
{
    size_t m = w->m ? w->m : 1;
    int cen = !(w->skip & FDT_CELLS_NO_CENTROIDS), dens = !(w->skip & FDT_CELLS_NO_DENSITIES);
    w->flags = fdt_mem_alloc_huge(m, sizeof *w->flags, 1);
    w->vol = fdt_mem_alloc_huge(m, sizeof *w->vol, 1);
    w->vabs = fdt_mem_alloc_huge(m, sizeof *w->vabs, 1);
    w->mom = cen ? fdt_mem_alloc_huge(3 * m, sizeof *w->mom, 1) : NULL;
    w->dtfe = dens ? fdt_mem_alloc_huge(m, sizeof *w->dtfe, 1) : NULL;
    w->vmax = dens ? fdt_mem_alloc_huge(m, sizeof *w->vmax, 1) : NULL;
    if (!w->flags || !w->vol || !w->vabs || (cen && !w->mom) || (dens && (!w->dtfe || !w->vmax)))
        return FDT_ENOMEM;
    return FDT_OK;
}

/* The accumulators (104 bytes a point), freed once every cell is out of
 * them (cell_pass), before the rows and the neighbour lists (12 bytes a
 * face) are written. */
static void free_sums(vwork *w)
{
    free(w->vol);
    free(w->vabs);
    free(w->mom);
    free(w->dtfe);
    free(w->vmax);
    w->vol = w->vabs = w->mom = w->dtfe = NULL;
    w->vmax = NULL;
}

static void free_work(vwork *w)
{
    free(w->perm);
    free(w->loc);
    free(w->xyz);
    free(w->tets);
    free(w->flags);
    free_sums(w);
}

/* The jobs over the own points, in equal ranges of the local numbering. */
static int make_jobs(vwork *w, fdt_voronoi *v, vjob *jobs, int threads)
{
    w->jobs = jobs;
    w->njobs = threads;
    for (int t = 0; t < threads; t++) {
        vjob *j = &jobs[t];
        j->w = w;
        j->v = v;
        j->lo = (uint32_t)(w->nown * (size_t)t / (size_t)threads);
        j->hi = (uint32_t)(w->nown * (size_t)(t + 1) / (size_t)threads);
        j->rlo = v->n * (size_t)t / (size_t)threads;
        j->rhi = v->n * (size_t)(t + 1) / (size_t)threads;
        j->short_a = j->short_b = UINT32_MAX;
        fdt_cell_init(&j->cell);
        j->first = malloc(((size_t)(j->hi - j->lo) + 1) * sizeof *j->first);
        if (!j->first)
            return FDT_ENOMEM;
    }
    return FDT_OK;
}

/* fn on every job (fdt_fork_join), then the first error of any. */
static int fork_join(vjob *jobs, int threads, void *(*fn)(void *))
{
    fdt_fork_join(jobs, sizeof *jobs, threads, fn);
    int err = FDT_OK;
    for (int t = 0; t < threads && !err; t++)
        err = jobs[t].err;
    return err;
}

/* ---------------------------------------------------------------- buckets */

/* A tet's bucket: its lowest local id, which is an own point's (every
 * tet has one), so the jobs' ranges [lo, hi) cover every key. */
static inline uint32_t tet_key(const uint32_t *x)
{
    uint32_t a = x[0] < x[1] ? x[0] : x[1], b = x[2] < x[3] ? x[2] : x[3];
    return a < b ? a : b;
}

/* Tet t in local ids: the result's, mapped (the whole set), or w's own
 * (a batch, numbered so already). */
static inline void local_tet(const vwork *w, size_t t, uint32_t x[4])
{
    if (w->rtets)
        for (int k = 0; k < 4; k++)
            x[k] = w->loc[w->rtets[4 * t + k]];
    else
        memcpy(x, w->tets + 4 * t, 4 * sizeof *x);
}

/* The job's keys counted, then each key's first entry relative to the
 * job's first (a prefix sum over [lo, hi)). */
static void *count_pass(void *arg)
{
    vjob *j = arg;
    vwork *w = j->w;
    size_t *cnt = w->bcnt, run = 0;
    for (size_t t = 0; t < w->ntets; t++) {
        uint32_t x[4];
        local_tet(w, t, x);
        uint32_t k = tet_key(x);
        if (mine(j, k))
            cnt[k]++;
    }
    for (uint32_t k = j->lo; k < j->hi; k++) {
        size_t c = cnt[k];
        cnt[k] = run;
        run += c;
    }
    j->nbucket = run;
    return NULL;
}

/* The job's tets into their buckets, in their order. */
static void *scatter_pass(void *arg)
{
    vjob *j = arg;
    vwork *w = j->w;
    for (size_t t = 0; t < w->ntets; t++) {
        uint32_t x[4];
        local_tet(w, t, x);
        uint32_t k = tet_key(x);
        if (mine(j, k))
            memcpy(w->btets + 4 * (j->bbase + w->bcnt[k]++), x, 4 * sizeof *x);
    }
    return NULL;
}

/* w's tets (local ids) bucketed by their lowest id, so that the tet pass
 * meets the points' accumulators in order (a streamed batch's tets in the
 * insertion's slot order took 2.4 times the tet pass's samples of a 700k
 * run, bench/NOTES.md entry 105): a counting sort on the jobs' threads,
 * each job the keys of its own points (each reads all the tets, twice;
 * the buckets come out as one thread's sort would make them). The
 * result's tets are mapped to local ids as they are read (local_tet), not
 * into a copy first: 16 bytes a tet of fresh memory less (bench/NOTES.md
 * entry 130). Each pass writes only its job's entries of bcnt and btets;
 * pthread_join (fork_join) orders them before the next pass reads them. */
static int bucket_tets(vwork *w, vjob *jobs, int threads)
{
    int err = FDT_OK;
    w->bcnt = fdt_mem_alloc_huge(w->m + 1, sizeof *w->bcnt, 1);
    w->btets = fdt_mem_alloc_huge(w->ntets ? 4 * w->ntets : 1, sizeof *w->btets, 0);
    if (!err && (!w->bcnt || !w->btets))
        err = FDT_ENOMEM;
    if (!err)
        err = fork_join(jobs, threads, count_pass);
    for (size_t t = 0, base = 0; !err && t < (size_t)threads; t++) {
        jobs[t].bbase = base;
        base += jobs[t].nbucket;
    }
    if (!err)
        err = fork_join(jobs, threads, scatter_pass);
    free(w->bcnt);
    w->bcnt = NULL;
    if (!err) {
        free(w->tets); /* a batch's own; NULL for the whole set's */
        w->tets = w->btets;
        w->rtets = NULL;
    } else {
        free(w->btets);
    }
    w->btets = NULL;
    return err;
}

/* The neighbour lists' offsets (by row), then their entries on the
 * threads. */
static int list_neighbors(fdt_voronoi *v, vjob *jobs, int threads)
{
    v->nstart = fdt_mem_alloc_huge(v->n + 1, sizeof *v->nstart, 0);
    if (!v->nstart)
        return FDT_ENOMEM;
    v->nstart[0] = 0;
    for (size_t i = 0; i < v->n; i++)
        v->nstart[i + 1] = v->nstart[i] + (size_t)v->nfaces[i];
    size_t tot = v->nstart[v->n];
    v->nid = fdt_mem_alloc_huge(tot ? tot : 1, sizeof *v->nid, 0);
    v->narea = fdt_mem_alloc_huge(tot ? tot : 1, sizeof *v->narea, 0);
    if (!v->nid || !v->narea)
        return FDT_ENOMEM;
    return fork_join(jobs, threads, neighbors_pass);
}

int fdt_voronoi_resolution(const fdt_result *r, const double *xyz, const double box[6],
                           int box_exp, int coords, char *diag, size_t ds)
{
    const double lim = ldexp(fdt_box_side(box), box_exp);
    fdt_vid sa = -1, sb = -1; /* the least edge too short, if any */
    double slen = 0, smag = 0;
    int snear = 0;
    for (size_t t = 0; t < r->ntets; t++) {
        const fdt_vid *v = r->tets + 4 * t;
        for (int e = 0; e < 6; e++) {
            const fdt_vid va = v[fdt_tet_edge[e][0]], vb = v[fdt_tet_edge[e][1]];
            const double *a = xyz + 3 * (size_t)va, *b = xyz + 3 * (size_t)vb;
            double len = fdt_cheb(a, b), mag = coords ? coord_mag(a, b) : 0;
            int near = coords && len < ldexp(mag, VORONOI_COORD_EXP);
            if ((near || len < lim) && (sa < 0 || fdt_edge_less(va, vb, sa, sb))) {
                sa = va;
                sb = vb;
                slen = len;
                smag = mag;
                snear = near;
            }
        }
    }
    if (sa >= 0)
        return too_close(sa, sb, slen, snear ? smag : fdt_box_side(box), snear, box_exp, coords,
                         diag, ds);
    return FDT_OK;
}


/* The threads for nown cells: about 64 cells a thread at least. */
static int cell_threads(int threads, size_t nown)
{
    if (threads < 1)
        threads = 1;
    if ((size_t)threads > nown / 64 + 1)
        threads = (int)(nown / 64 + 1);
    return threads;
}

/* The Chebyshev length of local edge ab in the points' own frame (the
 * local coordinates are scaled by 2^-ed, exactly). */
static double local_len(const vwork *w, uint32_t a, uint32_t b)
{
    return ldexp(fdt_cheb(w->xyz + 3 * (size_t)a, w->xyz + 3 * (size_t)b), w->ed);
}

/*
 * The steps after the numbering, for the whole set and a batch alike: on
 * the threads, the neighbour lists, the tet pass and the cells; the
 * neighbour lists by row; the cells back in the points' frame. w holds
 * the numbered points and tets in the computation's frame, its flags
 * (the hull points) and its accumulators; v its rows. The least edge too
 * short for the cells goes to *sh (kept when less than what it holds);
 * then FDT_ERANGE, the cells not computed.
 */
static int cells_run(vwork *w, fdt_voronoi *v, int threads, int neighbors, fdt_vshort *sh,
                     char *diag, size_t ds)
{
    vjob *jobs = calloc((size_t)threads, sizeof *jobs);
    if (!jobs)
        return FDT_ENOMEM;
    int err = make_jobs(w, v, jobs, threads);
    if (!err)
        err = bucket_tets(w, jobs, threads);
    if (!err)
        err = fork_join(jobs, threads, tet_pass);
    /* The tets are summed: their block becomes the cells' (realloc
     * shrinks it in place on uniform points, 16 bytes a tet and 6.7 tets
     * a point against 56 bytes a cell), whose pages are then not fresh
     * (a fresh megabyte costs about 2 ms on this VM, bench/NOTES.md
     * entry 126). */
    size_t cbytes = (w->nown ? w->nown : 1) * sizeof *w->cells;
    w->cells = !err ? realloc(w->tets, cbytes) : NULL;
    if (!w->cells) {
        free(w->tets);
        if (!err)
            err = FDT_ENOMEM;
    }
    w->tets = NULL;
    int too_short = 0;
    for (int t = 0; !err && t < threads; t++) {
        const vjob *j = &jobs[t];
        if (j->short_a == UINT32_MAX)
            continue;
        too_short = 1;
        long long a = w->perm[j->short_a], b = w->perm[j->short_b];
        if (sh->a < 0 || fdt_edge_less(a, b, sh->a, sh->b)) {
            sh->a = a < b ? a : b;
            sh->b = a < b ? b : a;
            sh->len = local_len(w, j->short_a, j->short_b);
        }
    }
    if (too_short)
        err = FDT_ERANGE;
    if (!err)
        err = fork_join(jobs, threads, cell_pass);
    if (err == FDT_EINTERNAL)
        for (int t = 0; t < threads; t++)
            if (jobs[t].err == FDT_EINTERNAL) {
                uint32_t l = jobs[t].lo;
                double p[3];
                for (int k = 0; k < 3; k++) /* as given */
                    p[k] = ldexp(w->xyz[3 * (size_t)l + k], w->ed);
                fdt_diag(diag, ds, "the cell of point %u (%.17g %.17g %.17g) could not be "
                    "cut from the box (a bug: please report)", w->perm[l], p[0], p[1], p[2]);
                break;
            }
    for (int t = 0; !err && t < threads; t++)
        v->zero_faces += jobs[t].zero_faces;
    free_sums(w);
    for (int t = 0; t < threads && !neighbors; t++) {
        free(jobs[t].fsum);
        jobs[t].fsum = NULL;
    }
    if (!err && neighbors)
        err = fork_join(jobs, threads, areas_pass);
    if (!err)
        err = fork_join(jobs, threads, rows_pass);
    if (!err && neighbors)
        err = list_neighbors(v, jobs, threads);
    for (int t = 0; t < threads; t++) {
        fdt_cell_free(&jobs[t].cell);
        free(jobs[t].face);
        free(jobs[t].order);
        free(jobs[t].dist);
        free(jobs[t].nkey);
        free(jobs[t].first);
        free(jobs[t].adj_start);
        free(jobs[t].up);
        free(jobs[t].adj);
        free(jobs[t].fsum);
    }
    free(jobs);
    free(w->cells);
    w->cells = NULL;
    return err;
}

/* The frame, the least edge and the grids of w's box (w->ed set). */
static void set_frame(vwork *w)
{
    scale_frame(w);
    w->min_edge = ldexp(fdt_box_side(w->box), FDT_VORONOI_BOX_EXP);
    set_grids(w);
}

int fdt_voronoi_too_close(const fdt_vshort *sh, const double box[6], char *diag, size_t ds)
{
    return too_close(sh->a, sh->b, sh->len, fdt_box_side(box), 0, FDT_VORONOI_BOX_EXP, 0, diag,
                     ds);
}

int fdt_voronoi_build(const fdt_result *r, const double *xyz, size_t n, const fdt_voronoi_options *o,
                      int threads, fdt_voronoi **out, char *diag, size_t diag_size)
{
    if (diag && diag_size)
        diag[0] = 0;
    *out = NULL;
    if (r->streamed || n != r->n) {
        fdt_diag(diag, diag_size, "%zu points given; the cells need the result of "
                             "fdt_triangulate on the same points, with its tets", n);
        return FDT_EINVAL;
    }
    int err = FDT_OK;
    fdt_voronoi *v = calloc(1, sizeof *v);
    vwork w;
    memset(&w, 0, sizeof w);
    w.n = n;
    if (!v)
        return FDT_ENOMEM;
    v->n = n;
    w.skip = o->skip;
    err = alloc_cells(v, o->skip);
    if (!err)
        err = fdt_voronoi_box_of(xyz, NULL, n, o, v->box, diag, diag_size);
    if (!err)
        err = fdt_voronoi_scale(v->box, &w.ed, diag, diag_size);
    if (err)
        goto done;
    memcpy(w.box, v->box, sizeof w.box);
    /* The steps: number the points (every distinct one is own) and their
     * tets, in the computation's frame; the hull points marked; the
     * cells; the merged duplicates marked. */
    err = number_points(&w, r, xyz);
    if (!err) {
        w.nown = w.m;
        set_frame(&w);
        local_tets(&w, r);
    }
    if (!err)
        err = alloc_work(&w);
    if (!err)
        for (size_t f = 0; f < 3 * r->nhull; f++)
            w.flags[w.loc[r->hull[f]]] |= FDT_CELL_HULL | FDT_CELL_CLIPPED;
    fdt_vshort sh = {-1, -1, 0};
    if (!err)
        err = cells_run(&w, v, cell_threads(threads, w.nown), o->neighbors, &sh, diag, diag_size);
    if (err == FDT_ERANGE && sh.a >= 0)
        (void)fdt_voronoi_too_close(&sh, v->box, diag, diag_size);
    for (size_t i = 0; !err && i < n; i++)
        if (r->dupmap[i] != (fdt_vid)i)
            v->flags[i] = FDT_CELL_MERGED;
done:
    free_work(&w);
    if (err)
        fdt_voronoi_free(&v);
    *out = v;
    return err;
}

/* A batch's numbering: an open-addressing table of id + 1 << 32 | local,
 * at most half full, and the local arrays it fills. */
typedef struct btab {
    uint64_t *t;
    size_t cap;     /* a power of two */
    size_t room;    /* entries perm and xyz hold */
} btab;

static size_t bt_hash(uint32_t id, size_t cap)
{
    return (size_t)(((uint64_t)id * UINT64_C(0x9E3779B97F4A7C15)) >> 32) & (cap - 1);
}

/* The table and the local arrays twice as large. */
static int bt_grow(vwork *w, btab *bt)
{
    size_t cap = 2 * bt->cap;
    uint64_t *t = calloc(cap, sizeof *t);
    uint32_t *perm = realloc(w->perm, cap / 2 * sizeof *perm);
    if (perm)
        w->perm = perm;
    double *xyz = perm ? realloc(w->xyz, 3 * (cap / 2) * sizeof *xyz) : NULL;
    if (xyz)
        w->xyz = xyz;
    if (!t || !perm || !xyz) {
        free(t);
        return FDT_ENOMEM;
    }
    for (size_t i = 0; i < bt->cap; i++)
        if (bt->t[i]) {
            size_t h = bt_hash((uint32_t)(bt->t[i] >> 32) - 1, cap);
            while (t[h])
                h = (h + 1) & (cap - 1);
            t[h] = bt->t[i];
        }
    free(bt->t);
    bt->t = t;
    bt->cap = cap;
    bt->room = cap / 2;
    return FDT_OK;
}

/* A batch's local number of point id (xyz's numbering), made when new;
 * UINT32_MAX when out of memory. */
static uint32_t batch_local(vwork *w, btab *bt, const fdt_vbatch *b, uint32_t id)
{
    size_t h = bt_hash(id, bt->cap);
    for (;; h = (h + 1) & (bt->cap - 1)) {
        uint64_t e = bt->t[h];
        if ((uint32_t)(e >> 32) == id + 1)
            return (uint32_t)e;
        if (e)
            continue;
        if (w->m + 1 > bt->room) {
            if (bt_grow(w, bt))
                return UINT32_MAX;
            return batch_local(w, bt, b, id);
        }
        uint32_t l = (uint32_t)w->m++;
        bt->t[h] = ((uint64_t)id + 1) << 32 | l;
        w->perm[l] = (uint32_t)b->label[id];
        for (int k = 0; k < 3; k++) /* the input's coordinates, exactly */
            w->xyz[3 * (size_t)l + k] = ldexp(b->xyz[3 * (size_t)id + k], -b->xyz_exp);
        return l;
    }
}

/* The batch's points numbered (its own first, in their order; then the
 * other points of its tets as met) and its tets in those numbers, those
 * with no own point left out (cells_run buckets them). */
static int batch_number(vwork *w, const fdt_vbatch *b)
{
    btab bt = {NULL, 32, 0};
    while (bt.cap < 2 * (b->nown + b->nown / 4 + 16)) /* about the own and a layer */
        bt.cap *= 2;
    bt.cap /= 2;
    w->tets = malloc(4 * (b->ntets ? b->ntets : 1) * sizeof *w->tets);
    if (!(bt.t = calloc(bt.cap, sizeof *bt.t)) || !w->tets || bt_grow(w, &bt)) {
        free(bt.t);
        return FDT_ENOMEM;
    }
    w->m = 0;
    int err = FDT_OK;
    for (size_t i = 0; i < b->nown && !err; i++)
        err = batch_local(w, &bt, b, b->own[i]) == UINT32_MAX ? FDT_ENOMEM : FDT_OK;
    w->nown = w->m;
    w->ntets = 0;
    for (size_t t = 0; t < b->ntets && !err; t++) {
        const uint32_t *tv = b->tets + 4 * (size_t)(b->pick ? b->pick[t] : t);
        uint32_t x[4];
        int any = 0;
        for (int k = 0; k < 4 && !err; k++) {
            x[k] = batch_local(w, &bt, b, tv[k]);
            err = x[k] == UINT32_MAX ? FDT_ENOMEM : FDT_OK;
            any |= x[k] < w->nown;
        }
        if (any && !err)
            memcpy(w->tets + 4 * w->ntets++, x, sizeof x);
    }
    free(bt.t);
    return err;
}

int fdt_voronoi_batch(const fdt_vbatch *b, int threads, fdt_voronoi **out, fdt_vshort *sh,
                      char *diag, size_t ds)
{
    *out = NULL;
    fdt_voronoi *v = calloc(1, sizeof *v);
    vwork w;
    memset(&w, 0, sizeof w);
    if (!v)
        return FDT_ENOMEM;
    w.batch = 1;
    w.ed = b->ed;
    w.skip = b->skip;
    w.periodic = b->periodic;
    memcpy(w.box, b->box, sizeof w.box);
    memcpy(v->box, b->box, sizeof v->box);
    /* The steps: number the batch's points and tets, in the computation's
     * frame; the hull points marked; the cells; their ids. */
    int err = batch_number(&w, b);
    v->n = w.nown;
    w.n = w.m;
    if (!err)
        err = alloc_cells(v, b->skip);
    if (!err && !(v->pts = malloc(3 * (w.nown ? w.nown : 1) * sizeof *v->pts)))
        err = FDT_ENOMEM;
    if (!err)
        memcpy(v->pts, w.xyz, 3 * w.nown * sizeof *v->pts);
    if (!err) {
        set_frame(&w);
        err = alloc_work(&w);
    }
    for (size_t i = 0; !err && i < w.nown; i++)
        if (b->own_hull[i])
            w.flags[i] |= FDT_CELL_HULL | FDT_CELL_CLIPPED;
    if (!err)
        err = cells_run(&w, v, cell_threads(threads, w.nown), b->neighbors, sh, diag, ds);
    if (!err && !(v->ids = malloc((w.nown ? w.nown : 1) * sizeof *v->ids)))
        err = FDT_ENOMEM;
    for (size_t i = 0; !err && i < w.nown; i++)
        v->ids[i] = (fdt_vid)w.perm[i];
    free_work(&w);
    if (err)
        fdt_voronoi_free(&v);
    *out = v;
    return err;
}
int fdt_voronoi_merged(const fdt_vid *ids, const double *pts, size_t k, const double box[6],
                       int neighbors, unsigned skip, fdt_voronoi **out)
{
    fdt_voronoi *v = calloc(1, sizeof *v);
    *out = NULL;
    if (!v)
        return FDT_ENOMEM;
    v->n = k;
    memcpy(v->box, box, sizeof v->box);
    int err = alloc_cells(v, skip);
    if (!err && (!(v->ids = malloc((k ? k : 1) * sizeof *v->ids)) ||
                 !(v->pts = malloc(3 * (k ? k : 1) * sizeof *v->pts))))
        err = FDT_ENOMEM;
    if (!err)
        memcpy(v->pts, pts, 3 * k * sizeof *v->pts);
    if (!err && neighbors &&
        (!(v->nstart = calloc(k + 1, sizeof *v->nstart)) || !(v->nid = malloc(sizeof *v->nid)) ||
         !(v->narea = malloc(sizeof *v->narea))))
        err = FDT_ENOMEM;
    for (size_t i = 0; !err && i < k; i++) {
        v->ids[i] = ids[i];
        v->flags[i] = FDT_CELL_MERGED;
    }
    if (err)
        fdt_voronoi_free(&v);
    *out = v;
    return err;
}

int fdt_voronoi_spread(fdt_voronoi **vp, size_t n)
{
    fdt_voronoi *b = *vp, *v = calloc(1, sizeof *v);
    if (!v)
        return FDT_ENOMEM;
    v->n = n;
    memcpy(v->box, b->box, sizeof v->box);
    v->zero_faces = b->zero_faces;
    int err = alloc_cells(v, b->skip);
    size_t *row = err ? NULL : malloc((n ? n : 1) * sizeof *row);
    if (!err && !row)
        err = FDT_ENOMEM;
    for (size_t i = 0; !err && i < n; i++) {
        row[i] = SIZE_MAX;
        v->flags[i] = FDT_CELL_MERGED;
    }
    for (size_t i = 0; !err && i < b->n; i++) {
        size_t id = (size_t)b->ids[i];
        row[id] = i;
        v->volume[id] = b->volume[i];
        v->area[id] = b->area[i];
        if (v->centroid)
            memcpy(v->centroid + 3 * id, b->centroid + 3 * i, 3 * sizeof *v->centroid);
        if (v->density)
            v->density[id] = b->density[i];
        v->nfaces[id] = b->nfaces[i];
        v->flags[id] = b->flags[i];
    }
    if (!err && b->nstart) {
        size_t total = b->nstart[b->n];
        if (!(v->nstart = malloc((n + 1) * sizeof *v->nstart)) ||
            !(v->nid = malloc((total ? total : 1) * sizeof *v->nid)) ||
            !(v->narea = malloc((total ? total : 1) * sizeof *v->narea)))
            err = FDT_ENOMEM;
        size_t at = 0;
        for (size_t id = 0; !err && id < n; id++) {
            v->nstart[id] = at;
            if (row[id] == SIZE_MAX)
                continue;
            size_t s0 = b->nstart[row[id]], c = b->nstart[row[id] + 1] - s0;
            memcpy(v->nid + at, b->nid + s0, c * sizeof *v->nid);
            memcpy(v->narea + at, b->narea + s0, c * sizeof *v->narea);
            at += c;
        }
        if (!err)
            v->nstart[n] = at;
    }
    free(row);
    if (err) {
        fdt_voronoi_free(&v);
        return err;
    }
    fdt_voronoi_free(vp);
    *vp = v;
    return FDT_OK;
}

size_t fdt_voronoi_num_points(const fdt_voronoi *v) { return v ? v->n : 0; }
const fdt_vid *fdt_voronoi_ids(const fdt_voronoi *v) { return v ? v->ids : NULL; }
const double *fdt_voronoi_points(const fdt_voronoi *v) { return v ? v->pts : NULL; }
const double *fdt_voronoi_volumes(const fdt_voronoi *v) { return v ? v->volume : NULL; }
const double *fdt_voronoi_areas(const fdt_voronoi *v) { return v ? v->area : NULL; }
const double *fdt_voronoi_centroids(const fdt_voronoi *v) { return v ? v->centroid : NULL; }
const int32_t *fdt_voronoi_num_faces(const fdt_voronoi *v) { return v ? v->nfaces : NULL; }
const double *fdt_voronoi_densities(const fdt_voronoi *v) { return v ? v->density : NULL; }
const uint8_t *fdt_voronoi_flags(const fdt_voronoi *v) { return v ? v->flags : NULL; }
size_t fdt_voronoi_zero_faces(const fdt_voronoi *v) { return v ? v->zero_faces : 0; }

void fdt_voronoi_box(const fdt_voronoi *v, double box[6])
{
    if (v && box)
        memcpy(box, v->box, sizeof v->box);
}

int fdt_voronoi_neighbors(const fdt_voronoi *v, fdt_vid i, size_t *count, const fdt_vid **ids,
                          const double **areas)
{
    if (!v || !v->nstart || i < 0 || (size_t)i >= v->n || !count || !ids || !areas)
        return FDT_EINVAL;
    *count = v->nstart[i + 1] - v->nstart[i];
    *ids = v->nid + v->nstart[i];
    *areas = v->narea + v->nstart[i];
    return FDT_OK;
}

/* q - p, moved by whole periods along v's periodic axes into [-L/2, L/2]
 * (the nearest image of q; q - p itself for a set that is not periodic).
 * Both points lie in the box, so one period at most. */
static void nearest_image(const fdt_voronoi *v, const double *p, const double *q, double d[3])
{
    for (int k = 0; k < 3; k++) {
        d[k] = q[k] - p[k];
        double L = v->period[k];
        if (L > 0 && d[k] > 0.5 * L)
            d[k] -= L;
        else if (L > 0 && d[k] < -0.5 * L)
            d[k] += L;
    }
}

/* The least neighbour pair (input ids) of cell i closer than 2^-40 of
 * their coordinates (fdt_voronoi_resolution's coords rule) into *a, *b,
 * kept when less than theirs (*a < 0: none yet); its length and
 * magnitude into *len, *mag. */
static void near_pair(const fdt_voronoi *v, const double *xyz, fdt_vid i, fdt_vid *a,
                      fdt_vid *b, double *len, double *mag)
{
    const double *p = xyz + 3 * (size_t)i;
    for (size_t e = v->nstart[i]; e < v->nstart[i + 1]; e++) {
        fdt_vid nb = v->nid[e];
        if (nb < 0)
            continue; /* a wall */
        const double *q = xyz + 3 * (size_t)nb;
        double img[3]; /* a periodic set's: the image nearest p */
        if (v->periodic) {
            nearest_image(v, p, q, img);
            for (int k = 0; k < 3; k++)
                img[k] += p[k];
            q = img;
        }
        double l = fdt_cheb(p, q), m = coord_mag(p, q);
        if (l < ldexp(m, VORONOI_COORD_EXP) && (*a < 0 || fdt_edge_less(i, nb, *a, *b))) {
            *a = i < nb ? i : nb;
            *b = i < nb ? nb : i;
            *len = l;
            *mag = m;
        }
    }
}

void fdt_voronoi_set_periodic(fdt_voronoi *v, unsigned axes, const double lo[3],
                              const double hi[3])
{
    v->periodic = axes;
    for (int k = 0; k < 3; k++)
        v->period[k] = axes >> k & 1 ? hi[k] - lo[k] : 0;
}

int fdt_voronoi_vertices_check(const fdt_voronoi *v, const double *xyz, char *diag, size_t ds)
{
    fdt_vid a = -1, b = -1;
    double len = 0, mag = 0;
    for (size_t i = 0; v->nstart && i < v->n; i++)
        if (!(v->flags[i] & FDT_CELL_MERGED))
            near_pair(v, xyz, (fdt_vid)i, &a, &b, &len, &mag);
    if (a < 0)
        return FDT_OK;
    return too_close(a, b, len, mag, 1, FDT_VORONOI_BOX_EXP, 1, diag, ds);
}

/*
 * A periodic cell's cuts by its neighbours' other images: the neighbour
 * lists name points, not which image of a point is the neighbour, and a
 * cell may have two images of one point among its neighbours (a sparse
 * set) or a neighbour that is not the nearest image. The nearest images
 * made the cell (fdt_voronoi_polyhedron); every other image whose
 * bisector could still cut it, nearer p than twice the cell's farthest
 * vertex, cuts it too. A bisector of any image of any point of the set
 * keeps the whole Voronoi cell on p's side, so these cuts take off only
 * what is not the cell, and the cell's own faces' images are among them.
 */
static int other_images(fdt_voronoi *v, const double *xyz, fdt_vid i)
{
    const double *p = xyz + 3 * (size_t)i;
    for (size_t e = v->nstart[i]; e < v->nstart[i + 1]; e++) {
        if (v->nid[e] < 0)
            continue;
        double r2 = 0; /* the cell's farthest vertex from p, squared */
        if (fdt_cell_compact(&v->poly))
            return FDT_ENOMEM;
        for (int j = 0; j < v->poly.np; j++)
            r2 = max2(r2, dot3(v->poly.p[j], v->poly.p[j]));
        double d0[3];
        nearest_image(v, p, xyz + 3 * (size_t)v->nid[e], d0);
        /* the shifts, a period at a time, that keep each axis within 2r */
        int s0[3], s1[3];
        double r = 2 * sqrt(r2);
        for (int k = 0; k < 3; k++) {
            s0[k] = s1[k] = 0;
            if (v->period[k] > 0) {
                s0[k] = (int)ceil((-r - d0[k]) / v->period[k]);
                s1[k] = (int)floor((r - d0[k]) / v->period[k]);
            }
        }
        for (int a = s0[0]; a <= s1[0]; a++)
            for (int b = s0[1]; b <= s1[1]; b++)
                for (int c = s0[2]; c <= s1[2]; c++) {
                    if (!a && !b && !c)
                        continue; /* the nearest image, cut already */
                    double nrm[3] = {d0[0] + a * v->period[0], d0[1] + b * v->period[1],
                                     d0[2] + c * v->period[2]};
                    double h2 = dot3(nrm, nrm);
                    if (h2 >= 4 * r2)
                        continue; /* its bisector lies beyond every vertex */
                    int got = fdt_cell_cut(&v->poly, nrm, 0.5 * h2, v->nid[e]);
                    if (got == -1)
                        return FDT_ENOMEM;
                    if (got < 0)
                        return FDT_EINTERNAL;
                }
    }
    return FDT_OK;
}

int fdt_voronoi_polyhedron(fdt_voronoi *v, const double *xyz, fdt_vid i, size_t *nverts,
                           const double **verts, size_t *nfaces, const int32_t **faces)
{
    if (!v || !xyz || !v->nstart || i < 0 || (size_t)i >= v->n || !nverts || !verts ||
        !nfaces || !faces)
        return FDT_EINVAL;
    *nverts = *nfaces = 0;
    if (v->flags[i] & FDT_CELL_MERGED)
        return FDT_OK;
    /* The vertices are absolute coordinates: where they cannot be told
     * apart at the cell's size, a polyhedron would be noise. */
    fdt_vid a = -1, b = -1;
    double len, mag;
    near_pair(v, xyz, i, &a, &b, &len, &mag);
    if (a >= 0)
        return FDT_ERANGE;
    /* The box cut by the bisectors of the cell's neighbours (its faces of
     * no area bound nothing): the cut cells' way, for every cell. */
    const double *p = xyz + 3 * (size_t)i;
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = v->box[k] - p[k];
        hi[k] = v->box[k + 3] - p[k];
    }
    for (int k = 0; k < 3; k++) /* on a periodic axis: the cell of p among its own images */
        if (v->period[k] > 0) {
            lo[k] = -0.5 * v->period[k];
            hi[k] = 0.5 * v->period[k];
        }
    if (fdt_cell_box(&v->poly, lo, hi))
        return FDT_ENOMEM;
    for (size_t e = v->nstart[i]; e < v->nstart[i + 1]; e++) {
        if (v->nid[e] < 0)
            continue; /* a wall: the box has it */
        double nrm[3]; /* q - p itself where no axis is periodic */
        nearest_image(v, p, xyz + 3 * (size_t)v->nid[e], nrm);
        int got = fdt_cell_cut(&v->poly, nrm, 0.5 * dot3(nrm, nrm), v->nid[e]);
        if (got == -1)
            return FDT_ENOMEM;
        if (got < 0)
            return FDT_EINTERNAL;
    }
    int err = v->periodic ? other_images(v, xyz, i) : FDT_OK;
    if (err)
        return err;
    if (fdt_cell_compact(&v->poly))
        return FDT_ENOMEM;
    const fdt_cell *c = &v->poly;
    size_t need_v = 3 * (size_t)c->np, need_f = (size_t)c->nf + (size_t)c->nring;
    if (need_v > v->cap_pverts) {
        double *q = realloc(v->pverts, need_v * sizeof *q);
        if (!q)
            return FDT_ENOMEM;
        v->pverts = q;
        v->cap_pverts = need_v;
    }
    if (need_f > v->cap_pfaces) {
        int32_t *q = realloc(v->pfaces, need_f * sizeof *q);
        if (!q)
            return FDT_ENOMEM;
        v->pfaces = q;
        v->cap_pfaces = need_f;
    }
    for (int j = 0; j < c->np; j++)
        for (int k = 0; k < 3; k++)
            v->pverts[3 * (size_t)j + (size_t)k] = p[k] + c->p[j][k];
    size_t o = 0;
    for (int f = 0; f < c->nf; f++) {
        v->pfaces[o++] = c->f[f].count;
        for (int j = 0; j < c->f[f].count; j++)
            v->pfaces[o++] = c->ring[c->f[f].start + j];
    }
    *nverts = (size_t)c->np;
    *verts = v->pverts;
    *nfaces = (size_t)c->nf;
    *faces = v->pfaces;
    return FDT_OK;
}
