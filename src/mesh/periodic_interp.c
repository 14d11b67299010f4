/* Point location and interpolation in a periodic mesh; see periodic_interp.h. */
#include "mesh/periodic_interp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "frontdt.h"
#include "mesh/locate.h"

/* What both calls start with: the mesh laid out (u) with its periodic
 * neighbours, the queries wrapped into the box along the periodic axes,
 * and the first patch's margin: the laid-out tets' largest extent along
 * each periodic axis (the tet holding a query in the box then lies in the
 * patch, and so do the cavities of most). */
typedef struct pview {
    fdt_periodic_unfolded u;
    fdt_tid *unb;
    double *wq;
    double margin[3];
} pview;

static void view_close(pview *v)
{
    fdt_periodic_unfolded_free(&v->u);
    free(v->unb);
    free(v->wq);
    memset(v, 0, sizeof *v);
}

static int view_open(pview *v, const int32_t *tets, const int8_t *off, size_t ntets,
                     const double *X, size_t n, const fdt_periodic_box *b, const double *q,
                     size_t nq)
{
    memset(v, 0, sizeof *v);
    int err = fdt_periodic_unfold(tets, off, ntets, NULL, NULL, 0, X, n, b, &v->u);
    if (!err)
        err = fdt_periodic_unfolded_neighbors(&v->u, &v->unb);
    if (!err && !(v->wq = malloc((3 * nq + 1) * sizeof *v->wq)))
        err = FDT_ENOMEM;
    if (err) {
        view_close(v);
        return err;
    }
    for (int d = 0; d < 3; d++) {
        const double L = fdt_periodic_period(b, d);
        for (size_t k = 0; k < nq; k++) {
            double x = q[3 * k + (size_t)d];
            if (L > 0 && isfinite(x)) {
                x = b->lo[d] + fmod(x - b->lo[d], L);
                x = x < b->lo[d] ? x + L : x;
            }
            v->wq[3 * k + (size_t)d] = x;
        }
        for (size_t t = 0; L > 0 && t < v->u.ntets; t++) {
            double lo, hi;
            fdt_periodic_unfolded_span(&v->u, t, d, &lo, &hi);
            v->margin[d] = hi - lo > v->margin[d] ? hi - lo : v->margin[d];
        }
    }
    return FDT_OK;
}

int fdt_periodic_locate(const int32_t *tets, const int8_t *off, size_t ntets, const double *X,
                        size_t n, const fdt_periodic_box *b, const double *q, size_t nq,
                        fdt_tid *tet, double *bary, int threads)
{
    pview v;
    fdt_periodic_patch p;
    memset(&p, 0, sizeof p);
    fdt_tid *pt = malloc((nq + 1) * sizeof *pt);
    double *pb = malloc((4 * nq + 1) * sizeof *pb);
    int err = pt && pb ? view_open(&v, tets, off, ntets, X, n, b, q, nq) : FDT_ENOMEM;
    if (err) {
        free(pt);
        free(pb);
        return err;
    }
    if (!(err = fdt_periodic_patch_make(&v.u, v.unb, X, b, v.margin, &p))) {
        fdt_locator L;
        fdt_locator_patch(&L, p.tets, p.nbrs, p.ntets, p.xyz);
        err = fdt_locate_with(&L, v.wq, nq, pt, pb, threads);
    }
    for (size_t k = 0; !err && k < nq; k++) {
        tet[k] = pt[k] < 0 ? -1 : (fdt_tid)p.row[pt[k]];
        for (int r = 0; bary && r < 4; r++) {
            bary[4 * k + (size_t)r] = 0;
            /* the weights in the row's order (the layout may have swapped
             * two vertices to orient the tet): by input id, distinct in a
             * tet */
            for (int i = 0; pt[k] >= 0 && i < 4; i++)
                if (p.src[p.tets[4 * (size_t)pt[k] + (size_t)i]] ==
                    tets[4 * (size_t)tet[k] + (size_t)r])
                    bary[4 * k + (size_t)r] = pb[4 * k + (size_t)i];
        }
    }
    fdt_periodic_patch_free(&p);
    view_close(&v);
    free(pt);
    free(pb);
    return err;
}

/* A cavity of a periodic mesh reaches less than its circumspheres'
 * diameters from its query (under one period on an axis periodic on all
 * three, CGAL's 1-sheet condition): a patch whose margin passes this many
 * periods and still cuts one is a bug. */
#define MAX_PERIODS 8

int fdt_periodic_interpolate(const int32_t *tets, const int8_t *off, size_t ntets,
                             const double *X, size_t n, const fdt_periodic_box *b,
                             const double *values, size_t nv, const double *q, size_t nq,
                             fdt_interp method, int threads, double *out, char *diag,
                             size_t diag_size)
{
    return fdt_periodic_interpolate_from(tets, off, ntets, X, n, b, values, nv, q, nq, method,
                                         threads, out, diag, diag_size, 1);
}

int fdt_periodic_interpolate_from(const int32_t *tets, const int8_t *off, size_t ntets,
                                  const double *X, size_t n, const fdt_periodic_box *b,
                                  const double *values, size_t nv, const double *q, size_t nq,
                                  fdt_interp method, int threads, double *out, char *diag,
                                  size_t diag_size, double first)
{
    pview v;
    uint8_t *cut = calloc(nq + 1, 1);
    int err = cut ? view_open(&v, tets, off, ntets, X, n, b, q, nq) : FDT_ENOMEM;
    if (err) {
        free(cut);
        return err;
    }
    for (int d = 0; d < 3; d++)
        v.margin[d] *= first;
    double min_edge;
    const int e = fdt_interpolate_frame(X, n, method, &min_edge);
    for (size_t k = 0; e && k < 3 * nq; k++)
        v.wq[k] = ldexp(v.wq[k], -e);
    /* every query again on a patch of twice the margin while some cavity
     * meets the patch's edge (the values of the others: the same bits,
     * the patch's points being numbered by their images) */
    for (;;) {
        fdt_periodic_patch p;
        if ((err = fdt_periodic_patch_make(&v.u, v.unb, X, b, v.margin, &p)))
            break;
        for (size_t i = 0; e && i < 3 * p.n; i++)
            p.xyz[i] = ldexp(p.xyz[i], -e);
        fdt_locator L;
        fdt_locator_patch(&L, p.tets, p.nbrs, p.ntets, p.xyz);
        L.rounded = 1;
        memset(cut, 0, nq);
        err = fdt_interpolate_with(&L, p.src, values, nv, v.wq, nq, method, threads, out, cut,
                                   min_edge, q, diag, diag_size);
        fdt_periodic_patch_free(&p);
        size_t k = 0; /* the first query cut */
        while (k < nq && !cut[k])
            k++;
        if (err || k == nq)
            break;
        int past = 0;
        for (int d = 0; d < 3; d++) {
            v.margin[d] = v.margin[d] > 0 ? 2 * v.margin[d] : fdt_periodic_period(b, d) / 8;
            past |= v.margin[d] > MAX_PERIODS * fdt_periodic_period(b, d);
        }
        if (past) {
            err = FDT_EINTERNAL;
            if (diag && diag_size)
                snprintf(diag, diag_size, "the natural neighbours of query %zu (%.17g %.17g "
                         "%.17g) reach over %d periods from it (a bug: please report)", k, q[3 * k],
                         q[3 * k + 1], q[3 * k + 2], MAX_PERIODS);
            break;
        }
    }
    view_close(&v);
    free(cut);
    return err;
}
