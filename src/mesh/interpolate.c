/*
 * Interpolation of values given at the points (issue 32): the public
 * fdt_interpolate, linear (barycentric in the tet holding the query) or
 * natural-neighbour (Sibson).
 *
 * Sibson's coordinates of a query q are the shares of q's Voronoi cell,
 * were q inserted, taken from each old cell: w_p = vol(V_new(q) n V_old(p))
 * / vol(V_new(q)). Its natural neighbours are the points of the tets whose
 * circumsphere holds q (the cavity, found from the tet holding q by exact
 * insphere tests); V_new(q) lies in the union of those tets' circumballs,
 * so it is their bounding box cut by q's bisectors with its natural
 * neighbours; each share is that cell cut further by p's bisectors with
 * the other natural neighbours (src/geom/cell.c, as the Voronoi cells').
 * The coordinates reproduce linear functions (sum w_p p = q); a query
 * outside the hull or on it gets NaN (its new cell is unbounded), a query
 * at a point that point's value.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/spawn.h"
#include "geom/cell.h"
#include "geom/predicates.h"
#include "mesh/locate.h"
#include "mesh/result.h"

typedef struct sibson {
    const fdt_locator *L;    /* shared, read only */
    fdt_cell cell, part;
    fdt_tid *stack, *cavity; /* growable lists of tets */
    size_t cap_stack, cap_cavity;
    fdt_vid *nn;             /* natural neighbours */
    size_t cap_nn;
    double *w;               /* their coordinates */
    size_t cap_w;
} sibson;

static int push(void *pp, size_t *cap, size_t n, size_t size)
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

static int has_tet(const fdt_tid *a, size_t n, fdt_tid t)
{
    for (size_t i = 0; i < n; i++)
        if (a[i] == t)
            return 1;
    return 0;
}

/* The cavity of q from tet t0 (which holds q): every tet reached across
 * faces whose circumsphere holds q strictly. Returns its size, or -1 when
 * out of memory. */
static long cavity(sibson *S, fdt_tid t0, const double *q)
{
    const fdt_result *r = S->L->r;
    const double *X = S->L->xyz;
    size_t nc = 0, ns = 0;
    if (push(&S->cavity, &S->cap_cavity, 0, sizeof *S->cavity) ||
        push(&S->stack, &S->cap_stack, 0, sizeof *S->stack))
        return -1;
    S->cavity[nc++] = t0;
    S->stack[ns++] = t0;
    while (ns) {
        fdt_tid t = S->stack[--ns];
        for (int i = 0; i < 4; i++) {
            fdt_tid u = S->L->nbrs[4 * (size_t)t + (size_t)i];
            if (u < 0 || has_tet(S->cavity, nc, u))
                continue;
            const fdt_vid *tv = r->tets + 4 * (size_t)u;
            if (fdt_insphere(X + 3 * (size_t)tv[0], X + 3 * (size_t)tv[1], X + 3 * (size_t)tv[2],
                             X + 3 * (size_t)tv[3], q, NULL) <= 0)
                continue;
            if (push(&S->cavity, &S->cap_cavity, nc, sizeof *S->cavity) ||
                push(&S->stack, &S->cap_stack, ns, sizeof *S->stack))
                return -1;
            S->cavity[nc++] = u;
            S->stack[ns++] = u;
        }
    }
    return (long)nc;
}

/* Grows the box [lo, hi] (relative to q) to hold the ball of tet t. */
static int add_ball(const sibson *S, fdt_tid t, const double *q, double lo[3], double hi[3])
{
    const double *X = S->L->xyz;
    const fdt_vid *tv = S->L->r->tets + 4 * (size_t)t;
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
static long neighbours(sibson *S, size_t nc, const double *q, double lo[3], double hi[3])
{
    const fdt_result *r = S->L->r;
    const double *X = S->L->xyz;
    size_t m = 0;
    for (int k = 0; k < 3; k++) {
        lo[k] = 0;
        hi[k] = 0;
    }
    for (size_t c = 0; c < nc; c++) {
        fdt_tid t = S->cavity[c];
        const fdt_vid *tv = r->tets + 4 * (size_t)t;
        for (int i = 0; i < 4; i++) {
            size_t y = m;
            while (y > 0 && S->nn[y - 1] > tv[i])
                y--;
            if (y > 0 && S->nn[y - 1] == tv[i])
                continue;
            if (push(&S->nn, &S->cap_nn, m, sizeof *S->nn))
                return -1;
            memmove(S->nn + y + 1, S->nn + y, (m - y) * sizeof *S->nn);
            S->nn[y] = tv[i];
            m++;
        }
        for (int i = 0; i < 4; i++) {
            fdt_tid u = S->L->nbrs[4 * (size_t)t + (size_t)i];
            if (u >= 0 && has_tet(S->cavity, nc, u))
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
            } else if (u < 0 || add_ball(S, t, q, lo, hi) || add_ball(S, u, q, lo, hi)) {
                return -3; /* q in the plane of a hull face: on the hull */
            }
        }
    }
    return (long)m;
}

/* Sibson's coordinates of q (held by tet t0) into S->w over S->nn[0..m).
 * Returns m, 0 when q lies on the hull (its new cell is unbounded), -1 out
 * of memory, -2 a cut that failed (a bug). */
static long coordinates(sibson *S, fdt_tid t0, const double *q)
{
    const fdt_result *r = S->L->r;
    const double *X = S->L->xyz;
    const fdt_vid *tv = r->tets + 4 * (size_t)t0;
    for (int i = 0; i < 4; i++) /* q at a point: that point alone */
        if (X[3 * (size_t)tv[i]] == q[0] && X[3 * (size_t)tv[i] + 1] == q[1] &&
            X[3 * (size_t)tv[i] + 2] == q[2]) {
            if (push(&S->nn, &S->cap_nn, 0, sizeof *S->nn) ||
                push(&S->w, &S->cap_w, 0, sizeof *S->w))
                return -1;
            S->nn[0] = tv[i];
            S->w[0] = 1;
            return 1;
        }
    long nc = cavity(S, t0, q);
    if (nc < 0)
        return -1;
    double lo[3], hi[3];
    long m = neighbours(S, (size_t)nc, q, lo, hi);
    if (m == -3)
        return 0;
    if (m < 0)
        return m;
    while (S->cap_w < (size_t)m)
        if (push(&S->w, &S->cap_w, S->cap_w, sizeof *S->w))
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

/* One thread's run of the queries. */
typedef struct ijob {
    fdt_query_run run; /* first: fdt_queries_begin fills it */
    sibson S;
    const double *values;
    size_t nv;
    fdt_interp method;
    double *out;
    int err;
    size_t bad; /* the query that failed */
} ijob;

static void *interpolate_run(void *arg)
{
    ijob *j = arg;
    sibson *S = &j->S;
    const fdt_result *r = S->L->r;
    size_t hint = 0, nv = j->nv;
    for (size_t i = 0; i < j->run.count && !j->err; i++) {
        size_t k = j->run.order[i];
        const double *qk = j->run.q + 3 * k;
        double *o = j->out + nv * k;
        for (size_t c = 0; c < nv; c++)
            o[c] = NAN;
        fdt_tid t = fdt_locate_one(S->L, &hint, qk);
        if (t < 0)
            continue;
        const fdt_vid *tv = r->tets + 4 * (size_t)t;
        if (j->method == FDT_INTERP_LINEAR) {
            double b[4];
            fdt_barycentric(S->L, t, qk, b);
            for (size_t c = 0; c < nv; c++) {
                o[c] = 0;
                for (int v = 0; v < 4; v++)
                    o[c] += b[v] * j->values[nv * (size_t)tv[v] + c];
            }
            continue;
        }
        long m = coordinates(S, t, qk);
        if (m == 0)
            continue; /* on the hull: NaN */
        if (m < 0) {
            j->err = m == -1 ? FDT_ENOMEM : FDT_EINTERNAL;
            j->bad = k;
            break;
        }
        for (size_t c = 0; c < nv; c++) {
            o[c] = 0;
            for (long v = 0; v < m; v++)
                o[c] += S->w[v] * j->values[nv * (size_t)S->nn[v] + c];
        }
    }
    return NULL;
}

int fdt_interpolate_build(fdt_result *r, const double *xyz, size_t n, const double *values,
                          size_t nv, const double *q, size_t nq, fdt_interp method,
                          int threads, double *out, char *diag, size_t diag_size)
{
    if (diag && diag_size)
        diag[0] = 0;
    if (!r || !xyz || !values || nv == 0 || (nq && (!q || !out)) ||
        (method != FDT_INTERP_LINEAR && method != FDT_INTERP_NATURAL))
        return FDT_EINVAL;
    fdt_locator L;
    uint32_t *order;
    void *jp;
    int err = fdt_queries_begin(&L, r, xyz, n, q, nq, &threads, &order, sizeof(ijob), &jp);
    if (err)
        return err;
    ijob *jobs = jp;
    for (int t = 0; t < threads; t++) {
        ijob *j = &jobs[t];
        j->S.L = &L;
        fdt_cell_init(&j->S.cell);
        fdt_cell_init(&j->S.part);
        j->values = values;
        j->nv = nv;
        j->method = method;
        j->out = out;
    }
    fdt_fork_join(jobs, sizeof *jobs, threads, interpolate_run);
    for (int t = 0; t < threads; t++) {
        ijob *j = &jobs[t];
        if (j->err && !err) {
            err = j->err;
            const double *qk = q + 3 * j->bad;
            if (err == FDT_EINTERNAL && diag && diag_size)
                snprintf(diag, diag_size, "natural-neighbour coordinates of query %zu "
                         "(%.17g %.17g %.17g) could not be computed (a bug: please report)",
                         j->bad, qk[0], qk[1], qk[2]);
        }
        fdt_cell_free(&j->S.cell);
        fdt_cell_free(&j->S.part);
        free(j->S.stack);
        free(j->S.cavity);
        free(j->S.nn);
        free(j->S.w);
    }
    fdt_queries_end(&L, order, jobs);
    return err;
}
