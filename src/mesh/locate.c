/*
 * Point location in a result's mesh (issue 32): the public fdt_locate,
 * and the walk src/mesh/interpolate.c starts from.
 *
 * A visibility walk: from a tet, cross a face that has the query strictly on
 * its outer side (exact orient3d), until none has (the tet holds the query,
 * on its boundary included) or the face crossed is a hull face (the query
 * lies outside the hull, which is convex). On a Delaunay mesh such a walk
 * cannot cycle (Edelsbrunner 1990, the acyclic "in front of" relation);
 * a cap of steps and a scan of every tet back that up, so a walk always
 * ends. Each query starts at the previous query's tet: a run of nearby
 * queries walks a few steps each. On a patch (FDT_NB_CUT), which need not
 * be convex, a walk that reaches the patch's edge scans too.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/spawn.h"
#include "geom/morton.h"
#include "geom/predicates.h"
#include "mesh/locate.h"
#include "mesh/result.h"

int fdt_locator_init(fdt_locator *L, fdt_result *r, const double *xyz, size_t n)
{
    memset(L, 0, sizeof *L);
    if (!r || !xyz || r->streamed || n != r->n || r->ntets == 0)
        return FDT_EINVAL;
    if (r->nbrs) {
        fdt_locator_patch(L, r->tets, r->nbrs, r->ntets, xyz);
        return FDT_OK;
    }
    /* No neighbours kept (settings.neighbors 0): from the face list. */
    size_t nf;
    const fdt_vid *fv;
    const fdt_tid *ft;
    int err = fdt_result_faces(r, &nf, &fv, &ft);
    if (err)
        return err;
    fdt_tid *nb = malloc(4 * r->ntets * sizeof *nb);
    if (!nb)
        return FDT_ENOMEM;
    for (size_t f = 0; f < nf; f++)
        for (int side = 0; side < 2; side++) {
            fdt_tid t = ft[2 * f + side];
            if (t < 0)
                continue;
            /* the face of t opposite the vertex that is not in it */
            const fdt_vid *tv = r->tets + 4 * (size_t)t;
            for (int i = 0; i < 4; i++)
                if (tv[i] != fv[3 * f] && tv[i] != fv[3 * f + 1] && tv[i] != fv[3 * f + 2])
                    nb[4 * (size_t)t + (size_t)i] = ft[2 * f + 1 - side];
        }
    fdt_locator_patch(L, r->tets, nb, r->ntets, xyz);
    L->owned = nb;
    return FDT_OK;
}

void fdt_locator_patch(fdt_locator *L, const fdt_vid *tets, const fdt_tid *nbrs, size_t ntets,
                       const double *xyz)
{
    *L = (fdt_locator){tets, ntets, xyz, nbrs, NULL, 64 + 4 * ntets, 0};
}

void fdt_locator_free(fdt_locator *L)
{
    free(L->owned);
    memset(L, 0, sizeof *L);
}

/* Face i of tet t has q strictly on its outer side. */
static int beyond(const fdt_locator *L, size_t t, int i, const double *q)
{
    const fdt_vid *tv = L->tets + 4 * t;
    const double *X = L->xyz;
    return fdt_orient3d(X + 3 * (size_t)tv[fdt_tet_face[i][0]],
                        X + 3 * (size_t)tv[fdt_tet_face[i][1]],
                        X + 3 * (size_t)tv[fdt_tet_face[i][2]], q, NULL) > 0;
}

/* The tet holding q, by scanning them all (the walk's backstop). */
static fdt_tid scan(const fdt_locator *L, const double *q)
{
    for (size_t t = 0; t < L->ntets; t++) {
        int in = 1;
        for (int i = 0; i < 4 && in; i++)
            in = !beyond(L, t, i, q);
        if (in)
            return (fdt_tid)t;
    }
    return -1;
}

fdt_tid fdt_locate_one(const fdt_locator *L, size_t *hint, const double *q)
{
    for (int k = 0; k < 3; k++)
        if (!isfinite(q[k]))
            return -1;
    if (L->ntets == 0)
        return -1;
    size_t t = *hint < L->ntets ? *hint : 0;
    /* The faces are tried from a rotating start, so that a walk does not
     * favour one direction. */
    for (size_t step = 0; step < L->cap; step++) {
        int moved = 0;
        for (int k = 0; k < 4 && !moved; k++) {
            int i = (int)((step + (size_t)k) & 3);
            if (!beyond(L, t, i, q))
                continue;
            fdt_tid next = L->nbrs[4 * t + (size_t)i];
            if (next == FDT_NB_CUT)
                goto scan;
            if (next < 0) {
                *hint = t;
                return -1; /* beyond a hull face: outside the hull */
            }
            t = (size_t)next;
            moved = 1;
        }
        if (!moved) {
            *hint = t;
            return (fdt_tid)t;
        }
    }
scan:;
    fdt_tid s = scan(L, q);
    if (s >= 0)
        *hint = (size_t)s;
    return s;
}

int fdt_queries_begin(const fdt_locator *L, const double *q, size_t nq, int *threads,
                      uint32_t **order, size_t job_size, void **jobs)
{
    if (*threads < 1)
        *threads = 1;
    if ((size_t)*threads > nq / 64 + 1)
        *threads = (int)(nq / 64 + 1);
    double box[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
    for (size_t k = 0; k < nq; k++)
        for (int d = 0; d < 3; d++)
            if (isfinite(q[3 * k + d])) {
                box[d] = fmin(box[d], q[3 * k + d]);
                box[d + 3] = fmax(box[d + 3], q[3 * k + d]);
            }
    *order = malloc((nq ? nq : 1) * sizeof **order);
    *jobs = calloc((size_t)*threads, job_size);
    if (!*order || !*jobs || fdt_morton_order(q, nq, box, NULL, *order) < 0) {
        fdt_queries_end(*order, *jobs);
        *order = NULL;
        *jobs = NULL;
        return FDT_ENOMEM;
    }
    for (int t = 0; t < *threads; t++) {
        size_t a = nq * (size_t)t / (size_t)*threads, b = nq * (size_t)(t + 1) / (size_t)*threads;
        fdt_query_run *run = (fdt_query_run *)((char *)*jobs + (size_t)t * job_size);
        *run = (fdt_query_run){L, q, *order + a, b - a};
    }
    return FDT_OK;
}

void fdt_queries_end(uint32_t *order, void *jobs)
{
    free(jobs);
    free(order);
}

void fdt_barycentric(const fdt_locator *L, fdt_tid t, const double *q, double b[4])
{
    const fdt_vid *tv = L->tets + 4 * (size_t)t;
    const double *X = L->xyz;
    /* b[i]: the volume of the tet with vertex i replaced by q, over the
     * tet's, each relative to q (differences first, for accuracy). */
    double d[4][3], m = 0;
    for (int i = 0; i < 4; i++)
        for (int k = 0; k < 3; k++) {
            d[i][k] = X[3 * (size_t)tv[i] + k] - q[k];
            m = fmax(m, fabs(d[i][k]));
        }
    /* The coordinates are ratios of cubes of the differences: outside
     * 2^-200 .. 2^200 the cubes underflow or overflow (points 1e-151
     * apart interpolated 3e-3 off, 1e149 apart NaN), so the differences
     * are scaled by a power of two first (exact but for bits far below
     * the largest's). */
    if (m > 0 && (m < 0x1p-200 || m > 0x1p200)) {
        int e;
        (void)frexp(m, &e);
        for (int i = 0; i < 4; i++)
            for (int k = 0; k < 3; k++)
                d[i][k] = ldexp(d[i][k], -e);
    }
    double s = 0;
    for (int i = 0; i < 4; i++) {
        const double *a = d[fdt_tet_face[i][0]], *bb = d[fdt_tet_face[i][1]],
                     *c = d[fdt_tet_face[i][2]];
        /* orient(face_i, q) with q at the origin: -det[a, b, c] */
        double det = a[0] * (bb[1] * c[2] - bb[2] * c[1]) - a[1] * (bb[0] * c[2] - bb[2] * c[0]) +
                     a[2] * (bb[0] * c[1] - bb[1] * c[0]);
        b[i] = det;
        s += det;
    }
    for (int i = 0; i < 4; i++)
        b[i] = s != 0 ? b[i] / s : 0.25;
}

typedef struct ljob {
    fdt_query_run run; /* first: fdt_queries_begin fills it */
    fdt_tid *tet;
    double *bary;
} ljob;

static void *locate_run(void *arg)
{
    ljob *j = arg;
    const fdt_query_run *run = &j->run;
    size_t hint = 0;
    for (size_t i = 0; i < run->count; i++) {
        size_t k = run->order[i];
        const double *qk = run->q + 3 * k;
        j->tet[k] = fdt_locate_one(run->L, &hint, qk);
        if (!j->bary)
            continue;
        if (j->tet[k] >= 0)
            fdt_barycentric(run->L, j->tet[k], qk, j->bary + 4 * k);
        else
            memset(j->bary + 4 * k, 0, 4 * sizeof *j->bary);
    }
    return NULL;
}

int fdt_locate_with(const fdt_locator *L, const double *q, size_t nq, fdt_tid *tet,
                    double *bary, int threads)
{
    uint32_t *order;
    void *jp;
    int err = fdt_queries_begin(L, q, nq, &threads, &order, sizeof(ljob), &jp);
    if (err)
        return err;
    ljob *jobs = jp;
    for (int t = 0; t < threads; t++) {
        jobs[t].tet = tet;
        jobs[t].bary = bary;
    }
    fdt_fork_join(jobs, sizeof *jobs, threads, locate_run);
    fdt_queries_end(order, jobs);
    return FDT_OK;
}
