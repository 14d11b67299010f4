/*
 * Tests for src/mesh/interpolate.c (fdt_interpolate):
 *  - both methods reproduce a linear function (two of them at once, nv 2)
 *    to 1e-12 at random queries inside the hull, give NaN outside and the
 *    point's value at a point;
 *  - natural-neighbour coordinates by symmetry: at the centre of a cube of
 *    a lattice the eight corners weigh 1/8 each ((x-1)(y-1)(z-1)
 *    interpolates to 1/8 there), and at a face's centre the four corners
 *    1/4 each; on the hull NaN (linear: the face's triangle's value);
 *  - natural-neighbour interpolation is continuous where linear is not
 *    smooth: across a tet face it changes by little between queries 1e-9
 *    apart; refusals;
 *  - the coordinates from circumcentres (src/mesh/interpolate.c) agree
 *    with the cells cut (the library's method until session 24, kept
 *    below as the reference) on uniform, clustered, lattice and offset points,
 *    queries near points among them; and the values are the same bits
 *    for any thread count, query order and mesh numbering.
 */
#include <math.h>
#include <string.h>

#include "frontdt.h"
#include "geom/cell.h"
#include "geom/predicates.h"
#include "mesh/locate.h"
#include "mesh/result.h"
#include "testutil.h"

/* the queries on 3 threads (the results do not depend on it) */
#define THREADS 3

/* The points and queries in the unit cube times 2^e: a linear function of
 * the unscaled coordinates reproduced (at 2^-490 and 2^490 the Sibson
 * coordinates, products of six differences, were an internal error and
 * the barycentric ones 3e-3 off or NaN before the frames were scaled). */
static void test_linear_reproduction(fdt_interp method, const char *name, int e)
{
    size_t n = 1500, nq = 300;
    double *xyz = malloc(3 * n * sizeof *xyz), *val = malloc(2 * n * sizeof *val);
    double *q = malloc(3 * nq * sizeof *q), *out = malloc(2 * nq * sizeof *out);
    double *u = malloc(3 * nq * sizeof *u);
    CHECK(xyz && val && q && out && u);
    uint64_t s = 17;
    for (size_t i = 0; i < n; i++) {
        for (int d = 0; d < 3; d++)
            xyz[3 * i + d] = test_unif(&s);
        val[2 * i] = 1 + 2 * xyz[3 * i] - 3 * xyz[3 * i + 1] + 0.5 * xyz[3 * i + 2];
        val[2 * i + 1] = -xyz[3 * i + 2];
    }
    for (size_t k = 0; k < nq; k++)
        for (int d = 0; d < 3; d++)
            u[3 * k + d] = k % 10 == 9 ? xyz[3 * k + (size_t)d]       /* at a point */
                         : k % 10 == 8 ? 2 + test_unif(&s)             /* outside */
                                       : 0.2 + 0.6 * test_unif(&s);    /* well inside */
    for (size_t i = 0; i < 3 * n; i++)
        xyz[i] = ldexp(xyz[i], e);
    for (size_t i = 0; i < 3 * nq; i++)
        q[i] = ldexp(u[i], e);
    fdt_result *r = test_triangulate(xyz, n, 1, 0);
    char diag[256];
    int err = fdt_interpolate(r, xyz, n, val, 2, q, nq, method, THREADS, out, diag, sizeof diag);
    EXPECTF(err == FDT_OK, "%s at 2^%d: %s (%s)", name, e, fdt_strerror(err), diag);
    for (size_t k = 0; k < nq && err == FDT_OK; k++) {
        const double *x = u + 3 * k;
        if (k % 10 == 8) {
            EXPECTF(isnan(out[2 * k]) && isnan(out[2 * k + 1]), "%s: query %zu outside: %g", name,
                    k, out[2 * k]);
            continue;
        }
        double want0 = 1 + 2 * x[0] - 3 * x[1] + 0.5 * x[2], want1 = -x[2];
        EXPECTF(fabs(out[2 * k] - want0) < 1e-12 && fabs(out[2 * k + 1] - want1) < 1e-12,
                "%s at 2^%d: query %zu: %.17g %.17g, want %.17g %.17g", name, e, k, out[2 * k],
                out[2 * k + 1], want0, want1);
    }
    fdt_result_free(&r);
    free(xyz);
    free(val);
    free(q);
    free(u);
    free(out);
}

static void test_symmetry(void)
{
    int k = 4;
    size_t n = (size_t)k * k * k;
    double *xyz = malloc(3 * n * sizeof *xyz), *val = malloc(n * sizeof *val);
    CHECK(xyz && val);
    for (size_t i = 0; i < n; i++) {
        double x = (double)(i % (size_t)k), y = (double)(i / (size_t)k % (size_t)k),
               z = (double)(i / ((size_t)k * k));
        xyz[3 * i] = x;
        xyz[3 * i + 1] = y;
        xyz[3 * i + 2] = z;
        val[i] = (x - 1) * (y - 1) * (z - 1); /* 1 at (2,2,2), 0 elsewhere in the cube */
    }
    fdt_result *r = test_triangulate(xyz, n, 1, 0);
    /* the centre of the cube [1,2]^3; the centre of its face z = 1; a
     * point on the hull (natural: NaN; linear: the face's value) */
    const double q[9] = {1.5, 1.5, 1.5, 1.5, 1.5, 1, 1.5, 1.5, 0};
    double out[3];
    CHECK(fdt_interpolate(r, xyz, n, val, 1, q, 3, FDT_INTERP_NATURAL, THREADS, out, NULL, 0) == FDT_OK);
    EXPECTF(fabs(out[0] - 0.125) < 1e-13, "cube centre: %.17g, want 1/8", out[0]);
    EXPECTF(fabs(out[1]) < 1e-13, "face centre: %.17g, want 0", out[1]);
    EXPECTF(isnan(out[2]), "on the hull: %.17g, want NaN", out[2]);
    CHECK(fdt_interpolate(r, xyz, n, val, 1, q + 6, 1, FDT_INTERP_LINEAR, THREADS, out, NULL, 0) == FDT_OK);
    /* on the square's diagonal: -1/2 or 0, by which diagonal the mesh took */
    EXPECTF(out[0] == 0 || fabs(out[0] + 0.5) < 1e-13, "on the hull, linear: %.17g", out[0]);
    fdt_result_free(&r);
    free(xyz);
    free(val);
}

/* Points 1e20 apart around a cluster 1e-150 wide: the cluster's cells are
 * beyond what doubles hold, and Sibson's coordinates of a query among them
 * are refused as the cells would be (FDT_ERANGE, the two points named),
 * not an internal error; linear interpolation there still works. */
static void test_beyond_doubles(void)
{
    size_t n = 530;
    double *xyz = malloc(3 * n * sizeof *xyz), *val = malloc(n * sizeof *val), q[3], out;
    CHECK(xyz && val);
    uint64_t s = 23;
    for (size_t i = 0; i < n; i++)
        for (int d = 0; d < 3; d++)
            xyz[3 * i + d] = (i < 500 ? 1e20 : 1e-150) * test_unif(&s);
    for (size_t i = 0; i < n; i++)
        val[i] = 1;
    for (int d = 0; d < 3; d++)
        q[d] = 1e-150 * test_unif(&s);
    fdt_result *r = test_triangulate(xyz, n, 1, 0);
    char diag[512];
    int err = fdt_interpolate(r, xyz, n, val, 1, q, 1, FDT_INTERP_NATURAL, 1, &out, diag,
                              sizeof diag);
    EXPECTF(err == FDT_ERANGE && strstr(diag, "closer than doubles can hold"),
            "natural among a 1e-150 cluster: %s (%s)", fdt_strerror(err), diag);
    err = fdt_interpolate(r, xyz, n, val, 1, q, 1, FDT_INTERP_LINEAR, 1, &out, diag, sizeof diag);
    EXPECTF(err == FDT_OK && (isnan(out) || fabs(out - 1) < 1e-12), "linear there: %s, %g",
            fdt_strerror(err), out);
    fdt_result_free(&r);
    free(xyz);
    free(val);
}

static void test_continuity_and_refusals(void)
{
    size_t n = 400;
    double *xyz = malloc(3 * n * sizeof *xyz), *val = malloc(n * sizeof *val);
    CHECK(xyz && val);
    uint64_t s = 5;
    for (size_t i = 0; i < n; i++) {
        for (int d = 0; d < 3; d++)
            xyz[3 * i + d] = test_unif(&s);
        val[i] = xyz[3 * i] * xyz[3 * i] + sin(5 * xyz[3 * i + 1]);
    }
    fdt_result *r = test_triangulate(xyz, n, 1, 0);
    /* a segment of queries through the middle: the values change little
     * between neighbours 1e-9 apart (no jump at the tets' faces) */
    size_t nq = 2000;
    double *q = malloc(3 * nq * sizeof *q), *out = malloc(nq * sizeof *out);
    CHECK(q && out);
    for (size_t k = 0; k < nq; k++) {
        q[3 * k] = 0.3 + 0.4 * (double)k / (double)nq;
        q[3 * k + 1] = 0.5 + 1e-9 * (double)(k % 2);
        q[3 * k + 2] = 0.45;
    }
    CHECK(fdt_interpolate(r, xyz, n, val, 1, q, nq, FDT_INTERP_NATURAL, THREADS, out, NULL, 0) == FDT_OK);
    double worst = 0;
    for (size_t k = 1; k < nq; k++)
        worst = fmax(worst, fabs(out[k] - out[k - 1]));
    EXPECTF(worst < 0.05, "natural-neighbour values jump by %g between close queries", worst);
    EXPECT(fdt_interpolate(r, xyz, n, val, 0, q, 1, FDT_INTERP_LINEAR, THREADS, out, NULL, 0) ==
           FDT_EINVAL);
    EXPECT(fdt_interpolate(r, xyz, n, val, 1, q, 1, (fdt_interp)7, THREADS, out, NULL, 0) == FDT_EINVAL);
    EXPECT(fdt_interpolate(r, xyz, n, val, 1, q, 1, FDT_INTERP_LINEAR, -2, out, NULL, 0) ==
           FDT_EINVAL);
    EXPECT(fdt_interpolate(NULL, xyz, n, val, 1, q, 1, FDT_INTERP_LINEAR, 1, out, NULL, 0) ==
           FDT_EINVAL);
    EXPECT(fdt_interpolate(r, xyz, n, val, 1, q, 0, FDT_INTERP_NATURAL, 1, NULL, NULL, 0) ==
           FDT_OK); /* no queries */
    fdt_result_free(&r);
    free(xyz);
    free(val);
    free(q);
    free(out);
}


/* ------------------------------------------------------------------ */
/* The reference: Sibson's coordinates by cutting cells, as
 * src/mesh/interpolate.c computed them until session 24 (a box around
 * the query's new cell cut by its bisectors with its natural neighbours,
 * then each neighbour's share cut from that by the neighbour's bisectors
 * with the others; src/geom/cell.c). About m^2 cuts a query. */

typedef struct ref_sibson {
    const fdt_locator *L;    /* shared, read only */
    fdt_cell cell, part;
    fdt_tid *stack, *cavity; /* growable lists of tets */
    size_t cap_stack, cap_cavity;
    fdt_vid *nn;             /* natural neighbours */
    size_t cap_nn;
    double *w;               /* their coordinates */
    size_t cap_w;
} ref_sibson;

static int ref_push(void *pp, size_t *cap, size_t n, size_t size)
{
    if (n < *cap)
        return 0;
    size_t nc = *cap ? 2 * *cap : 64;
    void **p = (void **)pp;
    void *q = realloc(*p, nc * size);
    if (!q)
        return -1;
    *p = q;
    *cap = nc;
    return 0;
}

static int ref_has_tet(const fdt_tid *a, size_t n, fdt_tid t)
{
    for (size_t i = 0; i < n; i++)
        if (a[i] == t)
            return 1;
    return 0;
}

/* The cavity of q from tet t0 (which holds q): every tet reached across
 * faces whose circumsphere holds q strictly. Returns its size, or -1 when
 * out of memory. */
static long ref_cavity(ref_sibson *S, fdt_tid t0, const double *q)
{
    const double *X = S->L->xyz;
    size_t nc = 0, ns = 0;
    if (ref_push(&S->cavity, &S->cap_cavity, 0, sizeof *S->cavity) ||
        ref_push(&S->stack, &S->cap_stack, 0, sizeof *S->stack))
        return -1;
    S->cavity[nc++] = t0;
    S->stack[ns++] = t0;
    while (ns) {
        fdt_tid t = S->stack[--ns];
        for (int i = 0; i < 4; i++) {
            fdt_tid u = S->L->nbrs[4 * (size_t)t + (size_t)i];
            if (u < 0 || ref_has_tet(S->cavity, nc, u))
                continue;
            const fdt_vid *tv = S->L->tets + 4 * (size_t)u;
            if (fdt_insphere(X + 3 * (size_t)tv[0], X + 3 * (size_t)tv[1], X + 3 * (size_t)tv[2],
                             X + 3 * (size_t)tv[3], q, NULL) <= 0)
                continue;
            if (ref_push(&S->cavity, &S->cap_cavity, nc, sizeof *S->cavity) ||
                ref_push(&S->stack, &S->cap_stack, ns, sizeof *S->stack))
                return -1;
            S->cavity[nc++] = u;
            S->stack[ns++] = u;
        }
    }
    return (long)nc;
}

/* Grows the box [lo, hi] (relative to q) to hold the ball of tet t. */
static int ref_add_ball(const ref_sibson *S, fdt_tid t, const double *q, double lo[3], double hi[3])
{
    const double *X = S->L->xyz;
    const fdt_vid *tv = S->L->tets + 4 * (size_t)t;
    const double *a = X + 3 * (size_t)tv[0];
    double cc[3];
    if (fdt_circumcenter_exact(a, X + 3 * (size_t)tv[1], X + 3 * (size_t)tv[2],
                               X + 3 * (size_t)tv[3], cc) != 0)
        return -1;
    double rad = sqrt(cc[0] * cc[0] + cc[1] * cc[1] + cc[2] * cc[2]) * (1 + 0x1p-20);
    for (int k = 0; k < 3; k++) {
        lo[k] = fmin(lo[k], a[k] + cc[k] - q[k] - rad);
        hi[k] = fmax(hi[k], a[k] + cc[k] - q[k] + rad);
    }
    return 0;
}

/* The natural neighbours (the cavity's points, each once, ascending) and a
 * box (relative to q) holding V_new(q): the box of its vertices, the
 * circumcentres of q with each face on the cavity's boundary (a face's, if
 * q is in its plane, lies in the union of the balls of the two tets on
 * either side: spheres of one pencil). */
static long ref_neighbours(ref_sibson *S, size_t nc, const double *q, double lo[3], double hi[3])
{
    const double *X = S->L->xyz;
    size_t m = 0;
    for (int k = 0; k < 3; k++) {
        lo[k] = 0;
        hi[k] = 0;
    }
    for (size_t c = 0; c < nc; c++) {
        fdt_tid t = S->cavity[c];
        const fdt_vid *tv = S->L->tets + 4 * (size_t)t;
        for (int i = 0; i < 4; i++) {
            size_t y = m;
            while (y > 0 && S->nn[y - 1] > tv[i])
                y--;
            if (y > 0 && S->nn[y - 1] == tv[i])
                continue;
            if (ref_push(&S->nn, &S->cap_nn, m, sizeof *S->nn))
                return -1;
            memmove(S->nn + y + 1, S->nn + y, (m - y) * sizeof *S->nn);
            S->nn[y] = tv[i];
            m++;
        }
        for (int i = 0; i < 4; i++) {
            fdt_tid u = S->L->nbrs[4 * (size_t)t + (size_t)i];
            if (u >= 0 && ref_has_tet(S->cavity, nc, u))
                continue; /* not on the boundary */
            double cc[3];
            if (fdt_circumcenter_exact(q, X + 3 * (size_t)tv[fdt_tet_face[i][0]],
                                       X + 3 * (size_t)tv[fdt_tet_face[i][1]],
                                       X + 3 * (size_t)tv[fdt_tet_face[i][2]], cc) == 0) {
                for (int k = 0; k < 3; k++) {
                    double slack = 0x1p-20 * fabs(cc[k]);
                    lo[k] = fmin(lo[k], cc[k] - slack);
                    hi[k] = fmax(hi[k], cc[k] + slack);
                }
            } else if (u < 0 || ref_add_ball(S, t, q, lo, hi) || ref_add_ball(S, u, q, lo, hi)) {
                return -3; /* q in the plane of a hull face: on the hull */
            }
        }
    }
    return (long)m;
}

/* Sibson's coordinates of q (held by tet t0) into S->w over S->nn[0..m).
 * Returns m, 0 when q lies on the hull (its new cell is unbounded), -1 out
 * of memory, -2 a cut that failed (a bug). */
static long ref_coordinates(ref_sibson *S, fdt_tid t0, const double *q)
{
    const double *X = S->L->xyz;
    const fdt_vid *tv = S->L->tets + 4 * (size_t)t0;
    for (int i = 0; i < 4; i++) /* q at a point: that point alone */
        if (X[3 * (size_t)tv[i]] == q[0] && X[3 * (size_t)tv[i] + 1] == q[1] &&
            X[3 * (size_t)tv[i] + 2] == q[2]) {
            if (ref_push(&S->nn, &S->cap_nn, 0, sizeof *S->nn) ||
                ref_push(&S->w, &S->cap_w, 0, sizeof *S->w))
                return -1;
            S->nn[0] = tv[i];
            S->w[0] = 1;
            return 1;
        }
    long nc = ref_cavity(S, t0, q);
    if (nc < 0)
        return -1;
    double lo[3], hi[3];
    long m = ref_neighbours(S, (size_t)nc, q, lo, hi);
    if (m == -3)
        return 0;
    if (m < 0)
        return m;
    while (S->cap_w < (size_t)m)
        if (ref_push(&S->w, &S->cap_w, S->cap_w, sizeof *S->w))
            return -1;
    /* V_new(q): the box cut by q's bisectors. */
    if (fdt_cell_box(&S->cell, lo, hi))
        return -1;
    for (long k = 0; k < m; k++) {
        const double *p = X + 3 * (size_t)S->nn[k];
        double nrm[3] = {p[0] - q[0], p[1] - q[1], p[2] - q[2]};
        int got = fdt_cell_cut(&S->cell, nrm, 0.5 * (nrm[0] * nrm[0] + nrm[1] * nrm[1] +
                                                     nrm[2] * nrm[2]), S->nn[k]);
        if (got == -1)
            return -1;
        if (got < 0)
            return -2;
    }
    /* Each share: V_new(q) n V_old(p). Inside V_new(q) the old sites that
     * compete are the natural neighbours only (their old cells cover it),
     * so V_old(p) there is cut by p's bisectors with them. */
    double total = 0;
    for (long k = 0; k < m; k++) {
        const double *p = X + 3 * (size_t)S->nn[k];
        if (fdt_cell_copy(&S->part, &S->cell))
            return -1;
        double vol = 0, area, cen[3];
        int empty = 0;
        for (long e = 0; e < m && !empty; e++) {
            if (e == k)
                continue;
            const double *u = X + 3 * (size_t)S->nn[e];
            double nrm[3] = {u[0] - p[0], u[1] - p[1], u[2] - p[2]};
            double h = nrm[0] * (p[0] - q[0]) + nrm[1] * (p[1] - q[1]) + nrm[2] * (p[2] - q[2]) +
                       0.5 * (nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
            int got = fdt_cell_cut(&S->part, nrm, h, S->nn[e]);
            if (got == -1)
                return -1;
            if (got == -3)
                return -2;
            empty = got == -2; /* nothing of V_new(q) is p's */
        }
        if (!empty)
            fdt_cell_measure(&S->part, &vol, &area, cen, NULL);
        S->w[k] = vol;
        total += vol;
    }
    if (!(total > 0))
        return -2;
    for (long k = 0; k < m; k++)
        S->w[k] /= total;
    return m;
}


/* The reference values at the queries (NaN outside the hull and on it),
 * nv columns. */
static void ref_interpolate(fdt_result *r, const double *xyz, size_t n, const double *val,
                            size_t nv, const double *q, size_t nq, double *out)
{
    fdt_locator L;
    CHECK(fdt_locator_init(&L, r, xyz, n) == 0);
    ref_sibson S;
    memset(&S, 0, sizeof S);
    S.L = &L;
    fdt_cell_init(&S.cell);
    fdt_cell_init(&S.part);
    size_t hint = 0;
    for (size_t k = 0; k < nq; k++) {
        double *o = out + nv * k;
        for (size_t c = 0; c < nv; c++)
            o[c] = NAN;
        fdt_tid t = fdt_locate_one(&L, &hint, q + 3 * k);
        if (t < 0)
            continue;
        long m = ref_coordinates(&S, t, q + 3 * k);
        CHECK(m >= 0);
        if (m == 0)
            continue;
        for (size_t c = 0; c < nv; c++) {
            o[c] = 0;
            for (long v = 0; v < m; v++)
                o[c] += S.w[v] * val[nv * (size_t)S.nn[v] + c];
        }
    }
    fdt_cell_free(&S.cell);
    fdt_cell_free(&S.part);
    free(S.stack);
    free(S.cavity);
    free(S.nn);
    free(S.w);
    fdt_locator_free(&L);
}

enum { FAM_UNIFORM, FAM_CLUSTERS, FAM_LATTICE, FAM_OFFSET };

/* n points of a family into xyz (returns the count) and nq queries into
 * q: uniform in the unit cube; five clusters 1e-3 wide holding 90 % of
 * the points, the rest uniform; a 10^3 integer lattice (cospherical
 * cavities); the uniform points 2^20 from the origin. Queries: inside the points' box, a quarter of them near a
 * point (1e-3 to 1e-6 of the spacing away), a few at half-integers on the
 * lattice (cube, face and edge centres). */
static size_t make_family(int fam, size_t n, double *xyz, size_t nq, double *q, uint64_t *s)
{
    double cen[5][3];
    for (int c = 0; c < 5; c++)
        for (int d = 0; d < 3; d++)
            cen[c][d] = 0.2 + 0.6 * test_unif(s);
    if (fam == FAM_LATTICE)
        n = 1000;
    for (size_t i = 0; i < n; i++)
        for (int d = 0; d < 3; d++) {
            double u = test_unif(s);
            xyz[3 * i + d] = fam == FAM_LATTICE ? (double)(i / (d == 0 ? 1 : d == 1 ? 10 : 100) % 10)
                             : fam == FAM_CLUSTERS && i % 10 ? cen[i % 5][d] + 1e-3 * (u - 0.5)
                                                             : u;
        }
    double lo = fam == FAM_LATTICE ? 1 : 0.1, hi = fam == FAM_LATTICE ? 8 : 0.9;
    if (fam == FAM_OFFSET) /* the uniform points 2^20 away: 2^-32 resolution */
        for (size_t i = 0; i < 3 * n; i++)
            xyz[i] += 0x1p20;
    double shift = fam == FAM_OFFSET ? 0x1p20 : 0;
    for (size_t k = 0; k < nq; k++) {
        const double *p = xyz + 3 * ((size_t)(test_unif(s) * (double)n) % n);
        double near = fam == FAM_CLUSTERS ? 1e-5 : fam == FAM_LATTICE ? 1 : 0.05;
        double off = near * pow(10, -3 - 3 * test_unif(s));
        for (int d = 0; d < 3; d++) {
            double u = test_unif(s);
            q[3 * k + d] = k % 4 == 1 ? p[d] + off * (u - 0.5)
                           : fam == FAM_LATTICE && k % 4 == 2 ? floor(lo + (hi - lo) * u) + 0.5 * (double)(k / 4 % 2 + d > 1)
                           : fam == FAM_CLUSTERS && k % 4 == 3 ? p[d] + 1e-3 * (u - 0.5)
                                                               : shift + lo + (hi - lo) * u;
        }
    }
    return n;
}

/* tol: the cut cells' own error is the larger on the lattice (up to 6e-12
 * there, the coordinates from circumcentres 3e-16, against exact rationals:
 * bench/NOTES.md entry 95): a vertex within 2^-40 of a plane counts as on
 * it (src/geom/cell.h), and cospherical cavities put many there. */
static void test_against_cuts(int fam, const char *name, double tol)
{
    size_t n = 3000, nq = 3000, nv = 3;
    double *xyz = malloc(3 * n * sizeof *xyz), *val = malloc(nv * n * sizeof *val);
    double *q = malloc(3 * nq * sizeof *q), *out = malloc(nv * nq * sizeof *out);
    double *ref = malloc(nv * nq * sizeof *ref), *o2 = malloc(nv * nq * sizeof *o2);
    double *qr = malloc(3 * nq * sizeof *qr);
    CHECK(xyz && val && q && out && ref && o2 && qr);
    uint64_t s = 41 + (uint64_t)fam;
    n = make_family(fam, n, xyz, nq, q, &s);
    for (size_t i = 0; i < nv * n; i++)
        val[i] = test_unif(&s);
    fdt_result *r = test_triangulate(xyz, n, 1, 0);
    CHECK(fdt_interpolate(r, xyz, n, val, nv, q, nq, FDT_INTERP_NATURAL, THREADS, out, NULL, 0) ==
          FDT_OK);
    ref_interpolate(r, xyz, n, val, nv, q, nq, ref);
    double worst = 0;
    size_t wk = 0, nan_both = 0;
    for (size_t k = 0; k < nq * nv; k++) {
        if (isnan(out[k]) || isnan(ref[k])) {
            EXPECTF(isnan(out[k]) && isnan(ref[k]), "%s: query %zu: %.17g, cut %.17g", name,
                    k / nv, out[k], ref[k]);
            nan_both++;
            continue;
        }
        if (fabs(out[k] - ref[k]) > worst) {
            worst = fabs(out[k] - ref[k]);
            wk = k / nv;
        }
    }
    printf("  %s: %zu queries, %zu values NaN in both, worst difference from the cut cells "
           "%.3g (query %zu)\n", name, nq, nan_both, worst, wk);
    EXPECTF(worst < tol, "%s: the coordinates differ from the cut cells' by %g (query %zu)",
            name, worst, wk);
    /* the same bits on one thread, with the queries reversed, and on a
     * mesh numbered otherwise (built on two threads) */
    for (size_t k = 0; k < nq; k++)
        memcpy(qr + 3 * k, q + 3 * (nq - 1 - k), 3 * sizeof *q);
    CHECK(fdt_interpolate(r, xyz, n, val, nv, qr, nq, FDT_INTERP_NATURAL, 1, o2, NULL, 0) == FDT_OK);
    size_t differ = 0;
    for (size_t k = 0; k < nq; k++)
        differ += memcmp(o2 + nv * (nq - 1 - k), out + nv * k, nv * sizeof *out) != 0;
    EXPECTF(differ == 0, "%s: %zu queries change bits with the thread count and order", name,
            differ);
    fdt_result *r2 = test_triangulate(xyz, n, 2, 1);
    CHECK(fdt_interpolate(r2, xyz, n, val, nv, q, nq, FDT_INTERP_NATURAL, 2, o2, NULL, 0) == FDT_OK);
    differ = 0;
    for (size_t k = 0; k < nq; k++)
        differ += memcmp(o2 + nv * k, out + nv * k, nv * sizeof *out) != 0;
    EXPECTF(differ == 0, "%s: %zu queries change bits with the mesh's numbering", name, differ);
    fdt_result_free(&r2);
    fdt_result_free(&r);
    free(xyz);
    free(val);
    free(q);
    free(out);
    free(ref);
    free(o2);
    free(qr);
}

int main(void)
{
    for (int e = -490; e <= 490; e += 490) {
        test_linear_reproduction(FDT_INTERP_LINEAR, "linear", e);
        test_linear_reproduction(FDT_INTERP_NATURAL, "natural", e);
    }
    test_symmetry();
    test_continuity_and_refusals();
    test_beyond_doubles();
    test_against_cuts(FAM_UNIFORM, "uniform", 1e-12);
    test_against_cuts(FAM_CLUSTERS, "clusters", 2e-12);
    test_against_cuts(FAM_LATTICE, "lattice", 2e-11);
    test_against_cuts(FAM_OFFSET, "offset", 1e-12);
    return test_report("interpolate");
}
