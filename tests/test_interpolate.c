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
 *    apart; refusals.
 */
#include <math.h>
#include <string.h>

#include "frontdt.h"
#include "testutil.h"

/* the queries on 3 threads (the results do not depend on it) */
#define THREADS 3

static void test_linear_reproduction(fdt_interp method, const char *name)
{
    size_t n = 1500, nq = 300;
    double *xyz = malloc(3 * n * sizeof *xyz), *val = malloc(2 * n * sizeof *val);
    double *q = malloc(3 * nq * sizeof *q), *out = malloc(2 * nq * sizeof *out);
    CHECK(xyz && val && q && out);
    uint64_t s = 17;
    for (size_t i = 0; i < n; i++) {
        for (int d = 0; d < 3; d++)
            xyz[3 * i + d] = test_unif(&s);
        val[2 * i] = 1 + 2 * xyz[3 * i] - 3 * xyz[3 * i + 1] + 0.5 * xyz[3 * i + 2];
        val[2 * i + 1] = -xyz[3 * i + 2];
    }
    for (size_t k = 0; k < nq; k++)
        for (int d = 0; d < 3; d++)
            q[3 * k + d] = k % 10 == 9 ? xyz[3 * k + (size_t)d]       /* at a point */
                         : k % 10 == 8 ? 2 + test_unif(&s)             /* outside */
                                       : 0.2 + 0.6 * test_unif(&s);    /* well inside */
    fdt_result *r = test_triangulate(xyz, n, 1, 0);
    char diag[256];
    CHECK(fdt_interpolate(r, xyz, n, val, 2, q, nq, method, THREADS, out, diag, sizeof diag) == FDT_OK);
    for (size_t k = 0; k < nq; k++) {
        const double *x = q + 3 * k;
        if (k % 10 == 8) {
            EXPECTF(isnan(out[2 * k]) && isnan(out[2 * k + 1]), "%s: query %zu outside: %g", name,
                    k, out[2 * k]);
            continue;
        }
        double want0 = 1 + 2 * x[0] - 3 * x[1] + 0.5 * x[2], want1 = -x[2];
        EXPECTF(fabs(out[2 * k] - want0) < 1e-12 && fabs(out[2 * k + 1] - want1) < 1e-12,
                "%s: query %zu: %.17g %.17g, want %.17g %.17g", name, k, out[2 * k],
                out[2 * k + 1], want0, want1);
    }
    fdt_result_free(&r);
    free(xyz);
    free(val);
    free(q);
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

int main(void)
{
    test_linear_reproduction(FDT_INTERP_LINEAR, "linear");
    test_linear_reproduction(FDT_INTERP_NATURAL, "natural");
    test_symmetry();
    test_continuity_and_refusals();
    return test_report("interpolate");
}
