/*
 * The first Delaunay tetrahedron (§2.1), made exact.
 *
 * The paper promotes the edge from a point to its nearest neighbour to a
 * triangle of minimum circumradius, then to a tetrahedron. With exact
 * arithmetic and cospherical inputs (lattices) the minimum can be shared
 * by many triangles, not all of them Delaunay under the perturbation, so
 * we use the paper's steps to *propose* and exact tests to *decide*:
 *
 * 1. b = nearest neighbour of a. Every other point t lies strictly outside
 *    the closed ball with diameter ab: a point in it would satisfy
 *    |t-a|^2 <= |ab|^2 - |t-b|^2 < |ab|^2. So ab has an empty sphere with
 *    slack, and is an edge of every perturbed Delaunay tetrahedralization.
 * 2. Let R* be the least circumradius of the triangles abt and S* the
 *    smallest sphere through a, b and a minimizer. Moving the centre of a
 *    sphere through a and b from the midpoint of ab (empty) towards the
 *    centre of S* shows that no point lies strictly inside S*, and that
 *    every point on S* also attains R*. Those points and a, b span a cell of
 *    the (unperturbed) Delaunay subdivision containing edge ab, and the
 *    perturbed tetrahedralization refines that cell, so some triangle abt
 *    with R(abt) = R* is a perturbed Delaunay face.
 * 3. For a candidate abc, the apex search on each side gives the best
 *    tetrahedron there; it is accepted only if no point at all lies inside
 *    its perturbed circumsphere (exact test over a conservative ball), so
 *    a wrong candidate is never accepted. We try candidates in order of
 *    floating-point circumradius, all within a relative window of the
 *    minimum (which contains every exact minimizer), then the rest.
 */
#include "front/seed.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Euclidean norm without overflow or underflow of the squares. */
static double norm_robust(const double *v)
{
    double m = fabs(v[0]);
    if (fabs(v[1]) > m)
        m = fabs(v[1]);
    if (fabs(v[2]) > m)
        m = fabs(v[2]);
    if (m == 0.0 || !isfinite(m))
        return m;
    double x = v[0] / m, y = v[1] / m, z = v[2] / m;
    return m * sqrt(x * x + y * y + z * z);
}

/*
 * Exactly: are a, b and t collinear? The triangle is degenerate iff its
 * three projections onto the coordinate planes are, and the projection
 * dropping axis k is degenerate iff orient3d of the three points with
 * coordinate k set to 0 and the unit point on axis k is zero (the
 * determinant is the projected doubled area, up to sign). Every one of
 * those points is a double, so the exact orient3d decides; floating cross
 * products do not, since they underflow or cancel when the input mixes
 * magnitudes.
 */
int fdt_seed_collinear(const double *a, const double *b, const double *t)
{
    for (int k = 0; k < 3; k++) {
        double pa[3], pb[3], pt[3], e[3] = {0.0, 0.0, 0.0};
        memcpy(pa, a, sizeof pa);
        memcpy(pb, b, sizeof pb);
        memcpy(pt, t, sizeof pt);
        pa[k] = pb[k] = pt[k] = 0.0;
        e[k] = 1.0;
        if (fdt_orient3d(pa, pb, pt, e, NULL) != 0)
            return 0;
    }
    return 1;
}

int fdt_seed_check_dimension(const double *P, const fdt_vid *orig, uint32_t m,
                             char *diag, size_t dlen)
{
    if (m < 4) {
        snprintf(diag, dlen, "only %u distinct point%s: a tetrahedralization needs at least 4",
                 m, m == 1 ? "" : "s");
        return FDT_EDEGENERATE;
    }
    /* Nearly every input has four points spanning space among a few: its
     * first 64, or 64 spread evenly over it. Found exactly there, the
     * answer needs no pass over all points (the two below took 20 ms of
     * the setup at 1M, and 5 ms at citylidar 200k, whose file begins with
     * a flat run of ground). */
    uint32_t few = m < 64 ? m : 64, qc = FDT_NONE;
    uint32_t pick[128], np = 0;
    for (uint32_t i = 2; i < few; i++)
        pick[np++] = i;
    if (m > 128)
        for (uint32_t k = 0; k < 64; k++)
            pick[np++] = (uint32_t)((uint64_t)m * (2 * k + 1) / 128);
    for (uint32_t k = 0; k < np && qc == FDT_NONE; k++)
        if (!fdt_seed_collinear(P, P + 3, P + 3 * (size_t)pick[k]))
            qc = pick[k];
    for (uint32_t k = 0; k < np && qc != FDT_NONE; k++)
        if (pick[k] != qc &&
            fdt_orient3d(P, P + 3, P + 3 * (size_t)qc, P + 3 * (size_t)pick[k], NULL) != 0)
            return FDT_OK;
    /* a = 0, b = the farthest point from a (any b != a will do: points are
     * distinct after the merge), c = the point farthest from line ab, all
     * proposed in floating point and decided exactly below. */
    const double *a = P;
    uint32_t ib = 1;
    double best = -1.0;
    for (uint32_t i = 1; i < m; i++) {
        double d[3] = {P[3 * (size_t)i] - a[0], P[3 * (size_t)i + 1] - a[1], P[3 * (size_t)i + 2] - a[2]};
        double n = norm_robust(d);
        if (n > best) {
            best = n;
            ib = i;
        }
    }
    const double *b = P + 3 * (size_t)ib;
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, nu = norm_robust(u);
    uint32_t ic = FDT_NONE;
    best = 0.0;
    for (uint32_t i = 1; i < m; i++) {
        if (i == ib)
            continue;
        const double *t = P + 3 * (size_t)i;
        double v[3] = {(t[0] - a[0]) / nu, (t[1] - a[1]) / nu, (t[2] - a[2]) / nu};
        double w[3] = {u[1] / nu * v[2] - u[2] / nu * v[1], u[2] / nu * v[0] - u[0] / nu * v[2],
                       u[0] / nu * v[1] - u[1] / nu * v[0]};
        double s = norm_robust(w);
        if (s > best) {
            best = s;
            ic = i;
        }
    }
    /* The floating choice may be collinear after all (rounding made its
     * cross product nonzero), or every floating cross product may have
     * vanished for points that are not collinear: look for an exactly
     * non-collinear third point. */
    if (ic == FDT_NONE || fdt_seed_collinear(a, b, P + 3 * (size_t)ic)) {
        ic = FDT_NONE;
        for (uint32_t i = 1; i < m && ic == FDT_NONE; i++)
            if (i != ib && !fdt_seed_collinear(a, b, P + 3 * (size_t)i))
                ic = i;
    }
    if (ic == FDT_NONE) {
        snprintf(diag, dlen, "all %u distinct points are collinear (on the line through input points %d and %d)",
                 m, (int)orig[0], (int)orig[ib]);
        return FDT_EDEGENERATE;
    }
    /* abc spans a plane exactly, so a point off it exists iff the set is
     * not coplanar. */
    const double *c = P + 3 * (size_t)ic;
    for (uint32_t i = 1; i < m; i++)
        if (i != ib && i != ic && fdt_orient3d(a, b, c, P + 3 * (size_t)i, NULL) != 0)
            return FDT_OK;
    snprintf(diag, dlen, "all %u distinct points are coplanar (in the plane of input points %d, %d and %d)",
             m, (int)orig[0], (int)orig[ib], (int)orig[ic]);
    return FDT_EDEGENERATE;
}

typedef struct cand {
    double r;
    uint32_t id;
} cand;

typedef struct cand_ctx {
    const double *P;
    uint32_t ia, ib;
    double uhat[3], u[3];
    cand *c;
    size_t n, cap;
    int nomem;
    int all; /* keep floating-collinear candidates too (the fallback) */
} cand_ctx;

/* Circumradius of (a, b, t) as |u - v| / (2 sin angle(u, v)), u = b - a,
 * v = t - a, from unit vectors so nothing overflows; INFINITY if the three
 * are collinear in floating point. */
static double circumradius(const cand_ctx *cc, const double *t)
{
    const double *a = cc->P + 3 * (size_t)cc->ia;
    double v[3] = {t[0] - a[0], t[1] - a[1], t[2] - a[2]};
    double nv = norm_robust(v);
    if (nv == 0.0)
        return INFINITY;
    double vh[3] = {v[0] / nv, v[1] / nv, v[2] / nv};
    double w[3] = {cc->uhat[1] * vh[2] - cc->uhat[2] * vh[1],
                   cc->uhat[2] * vh[0] - cc->uhat[0] * vh[2],
                   cc->uhat[0] * vh[1] - cc->uhat[1] * vh[0]};
    double s = norm_robust(w);
    if (s == 0.0)
        return INFINITY;
    double d[3] = {cc->u[0] - v[0], cc->u[1] - v[1], cc->u[2] - v[2]};
    return norm_robust(d) / (2.0 * s);
}

static int cand_cb(void *user, uint32_t id)
{
    cand_ctx *cc = user;
    if (id == cc->ia || id == cc->ib)
        return 0;
    double r = circumradius(cc, cc->P + 3 * (size_t)id);
    if (!isfinite(r) && !cc->all)
        return 0;
    if (cc->n == cc->cap) {
        size_t ncap = cc->cap ? 2 * cc->cap : 64;
        cand *nc = realloc(cc->c, ncap * sizeof *nc);
        if (!nc) {
            cc->nomem = 1;
            return 1;
        }
        cc->c = nc;
        cc->cap = ncap;
    }
    cc->c[cc->n].r = r;
    cc->c[cc->n].id = id;
    cc->n++;
    return 0;
}

static int cand_cmp(const void *x, const void *y)
{
    const cand *p = x, *q = y;
    if (p->r != q->r)
        return p->r < q->r ? -1 : 1;
    return p->id < q->id ? -1 : (p->id > q->id);
}

/* Tries abc on both sides; FDT_OK with out filled if one side's tet is
 * Delaunay, 1 if neither. */
static int try_face(const fdt_kdtree *t, uint32_t ia, uint32_t ib, uint32_t ic,
                    uint32_t out[4], fdt_kdq *kq)
{
    const double *P = t->P;
    for (int side = 0; side < 2; side++) {
        uint32_t x = side ? ic : ib, y = side ? ib : ic;
        fdt_apex s;
        fdt_apex_init(&s, P + 3 * (size_t)ia, P + 3 * (size_t)x, P + 3 * (size_t)y, ia, x, y);
        fdt_apex_search(&s, t, kq);
        if (s.best == FDT_NONE)
            continue;
        uint32_t v[4] = {ia, x, y, s.best};
        if (fdt_kd_any_inside(t, v, kq) == FDT_NONE) {
            memcpy(out, v, sizeof v);
            return FDT_OK;
        }
    }
    return 1;
}

int fdt_seed_tet(const fdt_kdtree *t, uint32_t a, uint32_t out[4], fdt_kdq *kq)
{
    const double *P = t->P;
    uint32_t b = fdt_kd_nearest(t, P + 3 * (size_t)a, a, kq);
    if (b == FDT_NONE)
        return FDT_EINTERNAL;
    cand_ctx cc = {P, a, b, {0}, {0}, NULL, 0, 0, 0, 0};
    const double *pa = P + 3 * (size_t)a, *pb = P + 3 * (size_t)b;
    for (int k = 0; k < 3; k++)
        cc.u[k] = pb[k] - pa[k];
    double nu = norm_robust(cc.u);
    for (int k = 0; k < 3; k++)
        cc.uhat[k] = cc.u[k] / nu;
    double mid[3] = {(pa[0] + pb[0]) * 0.5, (pa[1] + pb[1]) * 0.5, (pa[2] + pb[2]) * 0.5};
    /* Every t with R(abt) <= R lies within 2R of the midpoint (the midpoint
     * is inside the smallest sphere through a, b, t), so a ball of radius r
     * holds every candidate with R <= r / 2. Grow r until it does. */
    double r = nu;
    double rmin = INFINITY;
    const fdt_kdnode *root = &t->nodes[0];
    double diam[3] = {root->hi[0] - root->lo[0], root->hi[1] - root->lo[1], root->hi[2] - root->lo[2]};
    double dmax = 4.0 * norm_robust(diam) + nu;
    for (;;) {
        cc.n = 0;
        fdt_kd_ball(t, mid, r, cand_cb, &cc, kq);
        if (cc.nomem) {
            free(cc.c);
            return FDT_ENOMEM;
        }
        rmin = INFINITY;
        for (size_t i = 0; i < cc.n; i++)
            if (cc.c[i].r < rmin)
                rmin = cc.c[i].r;
        if (isfinite(rmin) && 2.0 * rmin * (1.0 + 1e-6) <= r)
            break;
        if (r > dmax)
            break; /* every point seen: take what there is */
        r = isfinite(rmin) ? 2.0 * rmin * (1.0 + 1e-6) * 1.01 : r * 2.0;
    }
    if (cc.n > 1)
        qsort(cc.c, cc.n, sizeof *cc.c, cand_cmp);
    int rc = FDT_EINTERNAL;
    for (size_t i = 0; i < cc.n; i++)
        if (try_face(t, a, b, cc.c[i].id, out, kq) == FDT_OK) {
            rc = FDT_OK;
            break;
        }
    if (rc != FDT_OK) {
        /* The floating radii can all be wrong when the input mixes
         * magnitudes (a triangle 1e-100 wide next to one 1e-2 wide: the
         * sine cancels), so the window may miss every exact minimizer.
         * ab is an edge of the tetrahedralization (step 1), so some
         * triangle abt is a face of it and try_face accepts it: try every
         * t, floating-collinear ones last. Reached only on such inputs. */
        cc.n = 0;
        cc.all = 1;
        fdt_kd_ball(t, mid, INFINITY, cand_cb, &cc, kq);
        if (cc.nomem) {
            free(cc.c);
            return FDT_ENOMEM;
        }
        if (cc.n > 1)
            qsort(cc.c, cc.n, sizeof *cc.c, cand_cmp);
        for (size_t i = 0; i < cc.n; i++)
            if (try_face(t, a, b, cc.c[i].id, out, kq) == FDT_OK) {
                rc = FDT_OK;
                break;
            }
    }
    free(cc.c);
    return rc;
}
