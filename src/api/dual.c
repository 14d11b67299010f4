/* The dual of a plain or a periodic result; see dual.h. */
#include "api/dual.h"

#include <stdio.h>
#include <string.h>

#include "mesh/dualperiodic.h"

/* The periodic dual of r (src/mesh/dualperiodic.h): the points and the
 * images their cells need, triangulated, their plain dual, folded. */
static int periodic_dual(fdt_result *r, const double *xyz, size_t n, int threads,
                         fdt_dualmesh *d, char *diag, size_t ds)
{
    double pbox[6];
    unsigned axes = fdt_result_periodic(r, pbox);
    fdt_dual_images im;
    int err = fdt_dual_images_make(r, xyz, n, &im, diag, ds);
    if (err != FDT_OK)
        return err;
    fdt_settings s;
    fdt_default_settings(&s);
    s.n_threads = threads;
    fdt_context *ctx = NULL;
    fdt_result *plain = NULL;
    if ((err = fdt_open(&ctx, &s)) == FDT_OK &&
        (err = fdt_triangulate(ctx, im.xyz, im.m, &plain)) != FDT_OK)
        snprintf(diag, ds, "the points and their images: %s", fdt_context_diagnostic(ctx));
    fdt_close(&ctx);
    /* the plain dual numbers its vertices and faces in the tets' order:
     * the canonical one, the same for every thread count */
    if (err == FDT_OK)
        err = fdt_result_sort(plain);
    fdt_dualmesh pd;
    if (err == FDT_OK) {
        fdt_voronoi_options o;
        fdt_default_voronoi_options(&o);
        o.box_given = 1;
        memcpy(o.box, im.box, sizeof o.box);
        /* checked once, folded (fdt_dualmesh_fold) */
        err = fdt_dualmesh_build_unchecked(plain, im.xyz, im.m, &o, &pd, diag, ds);
    }
    fdt_result_free(&plain);
    if (err == FDT_OK) {
        err = fdt_dualmesh_fold(&pd, &im, pbox, axes, d, diag, ds);
        fdt_dualmesh_free(&pd);
    }
    fdt_dual_images_free(&im);
    return err;
}

int fdt_dual_build(fdt_result *r, const double *xyz, size_t n, const fdt_voronoi_options *o,
                   int threads, fdt_dualmesh *d, char *diag, size_t ds)
{
    memset(d, 0, sizeof *d); /* zeroed on every error, as the builders leave it */
    if (r && fdt_result_periodic(r, NULL))
        return periodic_dual(r, xyz, n, threads, d, diag, ds);
    fdt_voronoi_options whole; /* NULL: the points' bounding box */
    if (!o) {
        fdt_default_voronoi_options(&whole);
        o = &whole;
    }
    return fdt_dualmesh_build(r, xyz, n, o, d, diag, ds);
}
