/* Point location and interpolation's entry points; see query.h. */
#include "mesh/query.h"

#include <math.h>
#include <stdlib.h>

#include "mesh/locate.h"
#include "mesh/periodic_interp.h"
#include "mesh/result.h"

int fdt_locate_build(fdt_result *r, const double *xyz, size_t n, const double *q, size_t nq,
                     fdt_tid *tet, double *bary, int threads)
{
    if (!r || !xyz || (nq && (!q || !tet)))
        return FDT_EINVAL;
    if (r->periodic) { /* on a patch of its tets laid out around the box */
        if (r->streamed || n != r->n)
            return FDT_EINVAL; /* no mesh kept, or other points */
        const fdt_periodic_box b = fdt_periodic_box_of(r->periodic, r->pbox);
        return fdt_periodic_locate(r->tets, r->tet_off, r->ntets, xyz, n, &b, q, nq, tet, bary,
                                   threads);
    }
    fdt_locator L;
    int err = fdt_locator_init(&L, r, xyz, n);
    if (!err)
        err = fdt_locate_with(&L, q, nq, tet, bary, threads);
    fdt_locator_free(&L);
    return err;
}

/* a copy of the k points p times 2^-e, or NULL */
static double *scaled(const double *p, size_t k, int e)
{
    double *c = malloc((k > 0 ? 3 * k : 1) * sizeof *c);
    for (size_t i = 0; c && i < 3 * k; i++)
        c[i] = ldexp(p[i], -e);
    return c;
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
    if (r->periodic) { /* src/mesh/periodic_interp.h */
        if (r->streamed || n != r->n)
            return FDT_EINVAL; /* no mesh kept, or other points */
        const fdt_periodic_box b = fdt_periodic_box_of(r->periodic, r->pbox);
        return fdt_periodic_interpolate(r->tets, r->tet_off, r->ntets, xyz, n, &b, values, nv, q,
                                        nq, method, threads, out, diag, diag_size);
    }
    double min_edge;
    int e = fdt_interpolate_frame(xyz, n, method, &min_edge);
    double *xs = e ? scaled(xyz, n, e) : NULL, *qs = e ? scaled(q, nq, e) : NULL;
    fdt_locator L;
    int err = e && (!xs || !qs) ? FDT_ENOMEM : fdt_locator_init(&L, r, e ? xs : xyz, n);
    if (!err) {
        err = fdt_interpolate_with(&L, NULL, values, nv, e ? qs : q, nq, method, threads, out,
                                   NULL, min_edge, q, diag, diag_size);
        fdt_locator_free(&L);
    }
    free(xs);
    free(qs);
    return err;
}
