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
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/abi.h"
#include "base/fixsum.h"
#include "geom/cell.h"
#include "geom/predicates.h"
#include "mesh/result.h"

struct fdt_voronoi {
    size_t n;
    double box[6];
    double *volume, *area, *centroid, *density; /* owned */
    int32_t *nfaces;                            /* owned */
    uint8_t *flags;                             /* owned */
    size_t zero_faces;
    size_t *nstart; /* n + 1 offsets, or NULL (owned) */
    fdt_vid *nid;   /* owned */
    double *narea;  /* owned */
};

/* The accumulators of the tet pass: per point, its volume, its volume's
 * moment about the point (centroid times volume, relative to the point)
 * and the volume of its tets (DTFE); per adjacency entry (r->adj), the
 * area of the face to that neighbour. */
typedef struct accum {
    fdt_fix *vol, *mom, *dtfe, *face;
    int e_area, e_vol, e_mom; /* the grids: 2^e */
} accum;

int fdt_default_voronoi_options_sized(fdt_voronoi_options *o, size_t struct_size)
{
    return fdt_abi_reset(o, struct_size, struct_size == sizeof(fdt_voronoi_options));
}

void fdt_voronoi_free(fdt_voronoi **pv)
{
    if (!pv || !*pv)
        return;
    fdt_voronoi *v = *pv;
    free(v->volume);
    free(v->area);
    free(v->centroid);
    free(v->density);
    free(v->nfaces);
    free(v->flags);
    free(v->nstart);
    free(v->nid);
    free(v->narea);
    free(v);
    *pv = NULL;
}

static void say(char *diag, size_t size, const char *fmt, ...)
{
    if (!diag || !size)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(diag, size, fmt, ap);
    va_end(ap);
}

/* The box: given (and holding every point), or the points' bounding box. */
static int set_box(fdt_voronoi *v, const fdt_result *r, const double *xyz,
                   const fdt_voronoi_options *o, char *diag, size_t ds)
{
    if (o->box_given) {
        memcpy(v->box, o->box, sizeof v->box);
        for (int k = 0; k < 3; k++)
            if (!(v->box[k] < v->box[k + 3]) || !isfinite(v->box[k]) ||
                !isfinite(v->box[k + 3])) {
                say(diag, ds, "the box is empty or not finite in %c", "xyz"[k]);
                return FDT_EINVAL;
            }
        for (size_t i = 0; i < v->n; i++)
            for (int k = 0; k < 3; k++)
                if (xyz[3 * i + k] < v->box[k] || xyz[3 * i + k] > v->box[k + 3]) {
                    say(diag, ds, "point %zu (%.17g %.17g %.17g) lies outside the box", i,
                        xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
                    return FDT_EINVAL;
                }
        return FDT_OK;
    }
    for (int k = 0; k < 3; k++) {
        v->box[k] = INFINITY;
        v->box[k + 3] = -INFINITY;
    }
    for (size_t i = 0; i < v->n; i++)
        if (r->dupmap[i] == (fdt_vid)i)
            for (int k = 0; k < 3; k++) {
                v->box[k] = fmin(v->box[k], xyz[3 * i + k]);
                v->box[k + 3] = fmax(v->box[k + 3], xyz[3 * i + k]);
            }
    return FDT_OK;
}

/* Flags: merged duplicates, hull points. */
static void set_flags(fdt_voronoi *v, const fdt_result *r)
{
    for (size_t i = 0; i < v->n; i++)
        v->flags[i] = r->dupmap[i] != (fdt_vid)i ? FDT_CELL_MERGED : 0;
    for (size_t f = 0; f < 3 * r->nhull; f++)
        v->flags[r->hull[f]] |= FDT_CELL_HULL | FDT_CELL_CLIPPED;
}

/* The grids: terms up to about 16 D^k for the box's largest side D land
 * near 2^102 grid steps (fixsum.h's range). */
static void set_grids(accum *a, const double box[6])
{
    double d = 0;
    for (int k = 0; k < 3; k++)
        d = fmax(d, box[k + 3] - box[k]);
    int ed;
    (void)frexp(d, &ed);
    a->e_area = 2 * ed - 98;
    a->e_vol = 3 * ed - 98;
    a->e_mom = 4 * ed - 98;
}

/* The adjacency entry of neighbour w in i's list (sorted). */
static size_t slot(const fdt_result *r, fdt_vid i, fdt_vid w)
{
    size_t lo = r->adj_start[i], hi = r->adj_start[i + 1];
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (r->adj[mid] < w)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

static void sub3(const double *a, const double *b, double *d)
{
    d[0] = a[0] - b[0];
    d[1] = a[1] - b[1];
    d[2] = a[2] - b[2];
}

static double triple(const double *a, const double *b, const double *c)
{
    return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
           a[2] * (b[0] * c[1] - b[1] * c[0]);
}

/* The circumcentre of the triangle (0, a, b), relative to its first vertex:
 * (|a|^2 b - |b|^2 a) x (a x b) / (2 |a x b|^2). */
static void tri_centre(const double *a, const double *b, double *x)
{
    double n[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                   a[0] * b[1] - a[1] * b[0]};
    double aa = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
    double bb = b[0] * b[0] + b[1] * b[1] + b[2] * b[2];
    double t[3] = {aa * b[0] - bb * a[0], aa * b[1] - bb * a[1], aa * b[2] - bb * a[2]};
    double nn = 2 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    x[0] = (t[1] * n[2] - t[2] * n[1]) / nn;
    x[1] = (t[2] * n[0] - t[0] * n[2]) / nn;
    x[2] = (t[0] * n[1] - t[1] * n[0]) / nn;
}

/* The six edges (i, j) of a tet with its other two vertices (k, l), and
 * the sign of the permutation (i, j, k, l) of (0, 1, 2, 3). */
static const int tet_edge[6][5] = {
    {0, 1, 2, 3, +1}, {0, 2, 1, 3, -1}, {0, 3, 1, 2, +1},
    {1, 2, 0, 3, +1}, {1, 3, 0, 2, -1}, {2, 3, 0, 1, +1},
};

/* One tet's shares (the file's comment). Returns 1 when its circumcentre
 * lies outside the box: then it adds nothing and its points are clipped. */
static int add_tet(const fdt_result *r, const double *xyz, const double box[6],
                   const fdt_vid *tv, accum *a, uint8_t *flags)
{
    /* Canonical order, the points' lexicographic order (ids would change
     * with the input order), so that a tet gives the same bits whichever
     * way round it came and however the input was numbered; sigma: the
     * orientation in that order. */
    fdt_vid s[4] = {tv[0], tv[1], tv[2], tv[3]};
    int sigma = 1;
    for (int x = 1; x < 4; x++)
        for (int y = x; y > 0 && fdt_lex_compare(xyz + 3 * (size_t)s[y - 1],
                                                 xyz + 3 * (size_t)s[y]) > 0; y--) {
            fdt_vid t = s[y];
            s[y] = s[y - 1];
            s[y - 1] = t;
            sigma = -sigma;
        }
    const double *p0 = xyz + 3 * (size_t)s[0];
    double q[4][3] = {{0, 0, 0}};
    for (int m = 1; m < 4; m++)
        sub3(xyz + 3 * (size_t)s[m], p0, q[m]);
    double v6 = sigma * triple(q[1], q[2], q[3]);
    for (int m = 0; m < 4; m++)
        fdt_fix_add(&a->dtfe[s[m]], v6 / 6, a->e_vol);
    double c[3];
    if (fdt_circumcenter_exact(p0, xyz + 3 * (size_t)s[1], xyz + 3 * (size_t)s[2],
                               xyz + 3 * (size_t)s[3], c) != 0)
        c[0] = c[1] = c[2] = INFINITY; /* flat or overflowing: clip its points */
    int outside = 0;
    for (int k = 0; k < 3; k++)
        if (!(p0[k] + c[k] >= box[k] && p0[k] + c[k] <= box[k + 3]))
            outside = 1;
    if (outside) {
        for (int m = 0; m < 4; m++)
            flags[s[m]] |= FDT_CELL_CLIPPED;
        return 1;
    }
    /* f[m]: the circumcentre of the face opposite m, relative to p0. */
    double f[4][3];
    for (int m = 0; m < 4; m++) {
        int u0 = m == 0 ? 1 : 0, u1 = m <= 1 ? 2 : 1, u2 = m <= 2 ? 3 : 2;
        double e1[3], e2[3], x[3];
        sub3(q[u1], q[u0], e1);
        sub3(q[u2], q[u0], e2);
        tri_centre(e1, e2, x);
        for (int k = 0; k < 3; k++)
            f[m][k] = q[u0][k] + x[k];
    }
    for (int e = 0; e < 6; e++) {
        int i = tet_edge[e][0], j = tet_edge[e][1], k = tet_edge[e][2], l = tet_edge[e][3];
        double o = sigma * tet_edge[e][4];
        double u[3], mid[3], cm[3], fp[3], fn[3];
        sub3(q[j], q[i], u);
        for (int d = 0; d < 3; d++)
            mid[d] = 0.5 * (q[i][d] + q[j][d]);
        sub3(c, mid, cm);
        /* Counter-clockwise about u, face (i,j,k) comes before (i,j,l)
         * when (i,j,k,l) is positive: F_prev is the face without l. */
        sub3(o > 0 ? f[l] : f[k], mid, fp);
        sub3(o > 0 ? f[k] : f[l], mid, fn);
        double len = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        /* Twice the signed areas of (M, F, C), seen along u, times |u|. */
        double ap = triple(u, fp, cm), an = triple(u, fn, cm);
        double area = (ap - an) / (2 * len);
        size_t sij = slot(r, s[i], s[j]), sji = slot(r, s[j], s[i]);
        fdt_fix_add(&a->face[sij], area, a->e_area);
        fdt_fix_add(&a->face[sji], area, a->e_area);
        /* The cones from i (and from j, its mirror image): volume
         * area |u| / 6, each piece's centroid (P + M + F + C) / 4. */
        double vp = ap / 12, vn = an / 12;
        for (int end = 0; end < 2; end++) {
            fdt_vid pt = s[end ? j : i];
            const double *qp = q[end ? j : i];
            fdt_fix_add(&a->vol[pt], vp - vn, a->e_vol);
            for (int d = 0; d < 3; d++) {
                double base = mid[d] + c[d] - 2 * qp[d];
                double mp = vp * (base + fp[d] + mid[d] - qp[d]) / 4;
                double mn = vn * (base + fn[d] + mid[d] - qp[d]) / 4;
                fdt_fix_add(&a->mom[3 * (size_t)pt + d], mp - mn, a->e_mom);
            }
        }
    }
    return 0;
}

/* A face counts when its area is above 2^-40 of its cell's surface. */
static int real_face(double area, double total)
{
    return area > FDT_CELL_TOL * total;
}

/* The faces of the clipped cells, kept from the cut until the neighbour
 * lists are built: cell i's are face[fstart[i] .. fstart[i + 1]). */
typedef struct clipped {
    fdt_cell_face *face;
    size_t nface, cap;
    fdt_vid *order; /* scratch: a cell's neighbours in cutting order */
    size_t cap_order;
} clipped;

/* The neighbours in the points' lexicographic order: the cuts, and so the
 * cell's bits, do not depend on how the input was numbered. */
static int cut_order(clipped *cl, const fdt_result *r, const double *xyz, fdt_vid i)
{
    size_t m = r->adj_start[i + 1] - r->adj_start[i];
    if (m > cl->cap_order) {
        fdt_vid *q = realloc(cl->order, m * sizeof *q);
        if (!q)
            return FDT_ENOMEM;
        cl->order = q;
        cl->cap_order = m;
    }
    for (size_t e = 0; e < m; e++) {
        fdt_vid w = r->adj[r->adj_start[i] + e];
        size_t y = e;
        for (; y > 0 && fdt_lex_compare(xyz + 3 * (size_t)cl->order[y - 1],
                                        xyz + 3 * (size_t)w) > 0; y--)
            cl->order[y] = cl->order[y - 1];
        cl->order[y] = w;
    }
    return FDT_OK;
}

/* Point i's cell cut from the box by its neighbours' bisectors. */
static int cut_cell(fdt_voronoi *v, const fdt_result *r, const double *xyz, fdt_vid i,
                    fdt_cell *cell, clipped *cl, size_t *first)
{
    const double *p = xyz + 3 * (size_t)i;
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = v->box[k] - p[k];
        hi[k] = v->box[k + 3] - p[k];
    }
    if (fdt_cell_box(cell, lo, hi) || cut_order(cl, r, xyz, i))
        return FDT_ENOMEM;
    for (size_t e = 0; e < r->adj_start[i + 1] - r->adj_start[i]; e++) {
        fdt_vid w = cl->order[e];
        double nrm[3];
        sub3(xyz + 3 * (size_t)w, p, nrm);
        int got = fdt_cell_cut(cell, nrm, 0.5 * (nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]),
                               w);
        if (got == -1)
            return FDT_ENOMEM;
        if (got < 0)
            return FDT_EINTERNAL;
    }
    if (cl->nface + (size_t)cell->nf > cl->cap) {
        size_t nc = cl->cap ? 2 * cl->cap : 1024;
        while (nc < cl->nface + (size_t)cell->nf)
            nc *= 2;
        fdt_cell_face *q = realloc(cl->face, nc * sizeof *q);
        if (!q)
            return FDT_ENOMEM;
        cl->face = q;
        cl->cap = nc;
    }
    double cen[3];
    fdt_cell_measure(cell, &v->volume[i], &v->area[i], cen, cl->face + cl->nface);
    for (int k = 0; k < 3; k++)
        v->centroid[3 * (size_t)i + k] = p[k] + cen[k];
    /* Faces ascending by label (walls first), zero-area ones dropped. */
    fdt_cell_face *fc = cl->face + cl->nface;
    size_t m = 0;
    for (int f = 0; f < cell->nf; f++) {
        if (!real_face(fc[f].area, v->area[i])) {
            v->zero_faces++;
            continue;
        }
        fdt_cell_face x = fc[f];
        size_t y = m++;
        for (; y > 0 && fc[y - 1].label > x.label; y--)
            fc[y] = fc[y - 1];
        fc[y] = x;
    }
    *first = cl->nface;
    cl->nface += m;
    v->nfaces[i] = (int32_t)m;
    return FDT_OK;
}

/* A cell summed from its tets: its values, and its real faces counted. */
static void sum_cell(fdt_voronoi *v, const fdt_result *r, const double *xyz, fdt_vid i,
                     const accum *a)
{
    fdt_fix total = {0, 0};
    for (size_t e = r->adj_start[i]; e < r->adj_start[i + 1]; e++)
        fdt_fix_merge(&total, a->face[e]);
    double area = fdt_fix_value(total, a->e_area);
    int32_t m = 0;
    for (size_t e = r->adj_start[i]; e < r->adj_start[i + 1]; e++) {
        if (real_face(fdt_fix_value(a->face[e], a->e_area), area))
            m++;
        else
            v->zero_faces++;
    }
    double vol = fdt_fix_value(a->vol[i], a->e_vol);
    v->volume[i] = vol;
    v->area[i] = area;
    v->nfaces[i] = m;
    for (int k = 0; k < 3; k++)
        v->centroid[3 * (size_t)i + k] =
            xyz[3 * (size_t)i + k] + fdt_fix_value(a->mom[3 * (size_t)i + k], a->e_mom) / vol;
}

/* The neighbour lists (options.neighbors): the summed cells' from their
 * adjacency entries, the clipped cells' from their cut faces. */
static int list_neighbors(fdt_voronoi *v, const fdt_result *r, const accum *a,
                          const clipped *cl, const size_t *first)
{
    v->nstart = malloc((v->n + 1) * sizeof *v->nstart);
    if (!v->nstart)
        return FDT_ENOMEM;
    v->nstart[0] = 0;
    for (size_t i = 0; i < v->n; i++)
        v->nstart[i + 1] = v->nstart[i] + (size_t)v->nfaces[i];
    size_t tot = v->nstart[v->n];
    v->nid = malloc((tot ? tot : 1) * sizeof *v->nid);
    v->narea = malloc((tot ? tot : 1) * sizeof *v->narea);
    if (!v->nid || !v->narea)
        return FDT_ENOMEM;
    for (size_t i = 0; i < v->n; i++) {
        size_t o = v->nstart[i];
        if (v->flags[i] & FDT_CELL_MERGED)
            continue;
        if (v->flags[i] & FDT_CELL_CLIPPED) {
            for (int32_t f = 0; f < v->nfaces[i]; f++) {
                v->nid[o + (size_t)f] = (fdt_vid)cl->face[first[i] + (size_t)f].label;
                v->narea[o + (size_t)f] = cl->face[first[i] + (size_t)f].area;
            }
            continue;
        }
        for (size_t e = r->adj_start[i]; e < r->adj_start[i + 1]; e++) {
            double ar = fdt_fix_value(a->face[e], a->e_area);
            if (real_face(ar, v->area[i])) {
                v->nid[o] = r->adj[e];
                v->narea[o++] = ar;
            }
        }
    }
    return FDT_OK;
}

static int alloc_cells(fdt_voronoi *v)
{
    size_t n = v->n ? v->n : 1;
    v->volume = calloc(n, sizeof *v->volume);
    v->area = calloc(n, sizeof *v->area);
    v->centroid = calloc(3 * n, sizeof *v->centroid);
    v->density = calloc(n, sizeof *v->density);
    v->nfaces = calloc(n, sizeof *v->nfaces);
    v->flags = calloc(n, sizeof *v->flags);
    return v->volume && v->area && v->centroid && v->density && v->nfaces && v->flags
               ? FDT_OK
               : FDT_ENOMEM;
}

static int alloc_accum(accum *a, size_t n, size_t nadj)
{
    a->vol = calloc(n ? n : 1, sizeof *a->vol);
    a->mom = calloc(3 * (n ? n : 1), sizeof *a->mom);
    a->dtfe = calloc(n ? n : 1, sizeof *a->dtfe);
    a->face = calloc(nadj ? nadj : 1, sizeof *a->face);
    return a->vol && a->mom && a->dtfe && a->face ? FDT_OK : FDT_ENOMEM;
}

static void free_accum(accum *a)
{
    free(a->vol);
    free(a->mom);
    free(a->dtfe);
    free(a->face);
}

int fdt_voronoi_compute(fdt_result *r, const double *xyz, size_t n,
                        const fdt_voronoi_options *o, fdt_voronoi **out, char *diag,
                        size_t diag_size)
{
    fdt_voronoi_options defaults;
    if (diag && diag_size)
        diag[0] = 0;
    if (!o) {
        fdt_default_voronoi_options(&defaults);
        o = &defaults;
    }
    if (!r || !xyz || !out || o->struct_size != sizeof *o)
        return FDT_EINVAL;
    *out = NULL;
    if (r->streamed || n != r->n) {
        say(diag, diag_size, "%zu points given; the cells need the result of "
                             "fdt_triangulate on the same points, with its tets", n);
        return FDT_EINVAL;
    }
    /* The vertex adjacency is derived on request and kept in the result
     * (src/mesh/faces.c): asking for one vertex's neighbours builds it. */
    size_t cnt;
    const fdt_vid *ids;
    int err = n ? fdt_result_vertex_neighbors(r, 0, &cnt, &ids) : FDT_OK;
    if (err)
        return err;
    fdt_voronoi *v = calloc(1, sizeof *v);
    accum a = {0};
    clipped cl = {0};
    size_t *first = NULL;
    fdt_cell cell;
    fdt_cell_init(&cell);
    if (!v)
        return FDT_ENOMEM;
    v->n = n;
    err = alloc_cells(v);
    if (!err)
        err = set_box(v, r, xyz, o, diag, diag_size);
    if (err)
        goto fail;
    set_flags(v, r);
    set_grids(&a, v->box);
    err = alloc_accum(&a, n, n ? r->adj_start[n] : 0);
    first = calloc(n ? n : 1, sizeof *first);
    if (!err && !first)
        err = FDT_ENOMEM;
    if (err)
        goto fail;
    /* The tet pass: shares of the cells inside the box, DTFE volumes. */
    for (size_t t = 0; t < r->ntets; t++)
        add_tet(r, xyz, v->box, r->tets + 4 * t, &a, v->flags);
    /* Each cell: summed, or cut from the box. */
    for (size_t i = 0; i < n && !err; i++) {
        if (v->flags[i] & FDT_CELL_MERGED)
            continue;
        double dt = fdt_fix_value(a.dtfe[i], a.e_vol);
        v->density[i] = dt > 0 ? 4 / dt : 0;
        if (v->flags[i] & FDT_CELL_CLIPPED) {
            err = cut_cell(v, r, xyz, (fdt_vid)i, &cell, &cl, &first[i]);
            if (err == FDT_EINTERNAL)
                say(diag, diag_size, "the cell of point %zu (%.17g %.17g %.17g) could not be cut "
                                     "from the box (a bug: please report)", i, xyz[3 * i],
                    xyz[3 * i + 1], xyz[3 * i + 2]);
        } else {
            sum_cell(v, r, xyz, (fdt_vid)i, &a);
        }
    }
    if (!err && o->neighbors)
        err = list_neighbors(v, r, &a, &cl, first);
    if (err)
        goto fail;
    free_accum(&a);
    free(cl.face);
    free(cl.order);
    free(first);
    fdt_cell_free(&cell);
    *out = v;
    return FDT_OK;
fail:
    free_accum(&a);
    free(cl.face);
    free(cl.order);
    free(first);
    fdt_cell_free(&cell);
    fdt_voronoi_free(&v);
    return err;
}

size_t fdt_voronoi_num_points(const fdt_voronoi *v) { return v ? v->n : 0; }
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
