/* Point location and linear interpolation in a periodic mesh; see periodic_interp.h. */
#include "mesh/periodic_interp.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "frontdt.h"
#include "geom/morton.h"
#include "geom/predicates.h"

typedef struct pwalk {
    const fdt_periodic_unfolded *u;
    const fdt_tid *nb;      /* the laid-out tets' periodic neighbours */
    double L[3];            /* the periods (0 across an axis that is not periodic) */
    uint64_t rng;           /* the walk's choice of face to try first */
} pwalk;

static const double *vpt(const pwalk *w, fdt_vid v)
{
    return w->u->xyz + 3 * (size_t)v;
}

/* Orientation of tet t's vertices with vertex k replaced by p. */
static int side(const pwalk *w, size_t t, int k, const double *p)
{
    const fdt_vid *v = w->u->tets + 4 * t;
    const double *x[4] = {vpt(w, v[0]), vpt(w, v[1]), vpt(w, v[2]), vpt(w, v[3])};
    x[k] = p;
    return fdt_orient3d(x[0], x[1], x[2], x[3], NULL);
}

/* p moved from tet t's frame into that of its neighbour n across the face
 * opposite t's vertex k: the face's points are the same input points in
 * another copy, whole periods away. */
static void cross(const pwalk *w, size_t t, int k, size_t n, double p[3])
{
    const fdt_periodic_unfolded *u = w->u;
    const fdt_vid a = u->tets[4 * t + (size_t)(k == 0)]; /* a vertex of the face */
    for (int i = 0; i < 4; i++) {
        const fdt_vid c = u->tets[4 * n + (size_t)i];
        if (u->src[c] != u->src[a])
            continue;
        for (int d = 0; d < 3; d++)
            p[d] -= (double)(u->off[3 * (size_t)a + d] - u->off[3 * (size_t)c + d]) * w->L[d];
        return;
    }
}

/* The tet holding p (moved into its frame), walking from *t: 1, or 0 past
 * the hull (a face without a neighbour), or -1 when the walk did not end
 * within max steps. */
static int walk(pwalk *w, size_t *t, double p[3], size_t max)
{
    for (size_t step = 0; step < max; step++) {
        int first = (int)((w->rng = w->rng * 6364136223846793005u + 1442695040888963407u) >> 62);
        int k = -1;
        for (int i = 0; i < 4 && k < 0; i++)
            if (side(w, *t, (first + i) & 3, p) < 0)
                k = (first + i) & 3;
        if (k < 0)
            return 1;
        fdt_tid n = w->nb[4 * *t + (size_t)k];
        if (n < 0)
            return 0;
        cross(w, *t, k, (size_t)n, p);
        *t = (size_t)n;
    }
    return -1;
}

/* Barycentric weights of p in tet t (signed volumes in doubles), and how
 * far inside it lies: the least weight. */
static double weights(const pwalk *w, size_t t, const double *p, double wt[4])
{
    const fdt_vid *v = w->u->tets + 4 * t;
    const double *x[4] = {vpt(w, v[0]), vpt(w, v[1]), vpt(w, v[2]), vpt(w, v[3])};
    double vol[4], sum = 0, least = INFINITY;
    for (int k = 0; k < 4; k++) {
        const double *y[4] = {x[0], x[1], x[2], x[3]};
        y[k] = p;
        double a[3], b[3], c[3];
        for (int d = 0; d < 3; d++) {
            a[d] = y[1][d] - y[0][d];
            b[d] = y[2][d] - y[0][d];
            c[d] = y[3][d] - y[0][d];
        }
        vol[k] = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                 a[2] * (b[0] * c[1] - b[1] * c[0]);
        sum += vol[k];
    }
    for (int k = 0; k < 4; k++) {
        wt[k] = sum != 0 ? vol[k] / sum : 0.25;
        least = wt[k] < least ? wt[k] : least;
    }
    return least;
}

/* The walk's last resort: every tet in every copy next to p's (p in the
 * box: the laid-out tets lie within a tet's reach of it), the one p lies
 * deepest in (its least barycentric weight the largest); p moved into its
 * frame. 0 when none holds p (past the hull). */
static int search_all(const pwalk *w, size_t *t, double p[3])
{
    double best = -INFINITY, bp[3] = {0, 0, 0};
    size_t bt = 0;
    for (int c = 0; c < 27; c++) {
        const int o[3] = {c % 3 - 1, c / 3 % 3 - 1, c / 9 - 1};
        if ((o[0] && !w->L[0]) || (o[1] && !w->L[1]) || (o[2] && !w->L[2]))
            continue;
        double q[3];
        for (int d = 0; d < 3; d++)
            q[d] = p[d] + o[d] * w->L[d];
        for (size_t s = 0; s < w->u->ntets; s++) {
            double wt[4], m = weights(w, s, q, wt);
            if (m > best) {
                best = m;
                bt = s;
                memcpy(bp, q, sizeof bp);
            }
        }
    }
    if (!(best >= -0x1p-30))
        return 0;
    *t = bt;
    memcpy(p, bp, sizeof bp);
    return 1;
}

int fdt_periodic_locate(const int32_t *tets, const int8_t *off, size_t ntets, const double *X,
                        size_t n, const fdt_periodic_box *b, const double *q, size_t nq,
                        fdt_tid *tet, double *bary)
{
    fdt_periodic_unfolded u;
    fdt_tid *nb = NULL;
    uint32_t *order = NULL;
    double *wq = NULL;
    uint8_t *bad = NULL; /* a query with a NaN or infinite coordinate */
    int err = fdt_periodic_unfold(tets, off, ntets, NULL, NULL, 0, X, n, b, &u);
    if (err)
        return err;
    if ((err = fdt_periodic_unfolded_neighbors(&u, &nb)) != FDT_OK)
        goto done;
    /* the queries wrapped into the box along the periodic axes, walked in
     * their Morton order (each from where the one before ended) */
    order = malloc((nq ? nq : 1) * sizeof *order);
    wq = malloc((nq ? 3 * nq : 1) * sizeof *wq);
    bad = calloc(nq ? nq : 1, 1);
    if (!order || !wq || !bad) {
        err = FDT_ENOMEM;
        goto done;
    }
    pwalk w = {&u, nb, {0, 0, 0}, 0x9e3779b97f4a7c15u};
    double box[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
    for (int d = 0; d < 3; d++)
        w.L[d] = fdt_periodic_period(b, d);
    for (size_t k = 0; k < nq; k++) {
        tet[k] = -1;
        for (int i = 0; bary && i < 4; i++)
            bary[4 * k + (size_t)i] = 0;
        for (int d = 0; d < 3; d++) {
            double x = q[3 * k + (size_t)d];
            if (!isfinite(x)) {
                bad[k] = 1;
                break;
            }
            if (w.L[d] > 0) {
                x = b->lo[d] + fmod(x - b->lo[d], w.L[d]);
                x = x < b->lo[d] ? x + w.L[d] : x;
            }
            wq[3 * k + (size_t)d] = x;
            box[d] = x < box[d] ? x : box[d];
            box[d + 3] = x > box[d + 3] ? x : box[d + 3];
        }
    }
    long ordered = fdt_morton_order(wq, nq, box, bad, order);
    if (ordered < 0) {
        err = FDT_ENOMEM;
        goto done;
    }
    /* a walk through a mesh of m tets takes about m^(1/3) steps from a
     * far start: a hundred times that ends any walk that will end */
    size_t max = 100 * (size_t)cbrt((double)(u.ntets + 1)) + 1000, t = 0;
    for (size_t i = 0; i < (size_t)ordered; i++) {
        const size_t k = order[i];
        double p[3] = {wq[3 * k], wq[3 * k + 1], wq[3 * k + 2]}, wt[4];
        int got = u.ntets ? walk(&w, &t, p, max) : 0;
        if (got < 0) { /* from the wrapped query: the walk moved p by periods */
            memcpy(p, wq + 3 * k, sizeof p);
            got = search_all(&w, &t, p);
        }
        if (got <= 0)
            continue;
        tet[k] = (fdt_tid)t;
        if (!bary)
            continue;
        /* the weights in the row's order (the layout may have swapped two
         * vertices to orient the tet): by input id, distinct in a tet */
        weights(&w, t, p, wt);
        for (int r = 0; r < 4; r++)
            for (int v = 0; v < 4; v++)
                if ((int32_t)u.src[u.tets[4 * t + (size_t)v]] == tets[4 * t + (size_t)r])
                    bary[4 * k + (size_t)r] = wt[v];
    }
done:
    free(order);
    free(wq);
    free(bad);
    free(nb);
    fdt_periodic_unfolded_free(&u);
    return err;
}

int fdt_periodic_interpolate_linear(const int32_t *tets, const int8_t *off, size_t ntets,
                                    const double *X, size_t n, const fdt_periodic_box *b,
                                    const double *values, size_t nv, const double *q,
                                    size_t nq, double *out)
{
    fdt_tid *tet = malloc((nq ? nq : 1) * sizeof *tet);
    double *bary = malloc((nq ? 4 * nq : 1) * sizeof *bary);
    int err = tet && bary ? fdt_periodic_locate(tets, off, ntets, X, n, b, q, nq, tet, bary)
                          : FDT_ENOMEM;
    for (size_t k = 0; !err && k < nq; k++)
        for (size_t c = 0; c < nv; c++) {
            double s = tet[k] < 0 ? NAN : 0;
            for (int r = 0; tet[k] >= 0 && r < 4; r++)
                s += bary[4 * k + (size_t)r] *
                     values[nv * (size_t)tets[4 * (size_t)tet[k] + (size_t)r] + c];
            out[nv * k + c] = s;
        }
    free(tet);
    free(bary);
    return err;
}
