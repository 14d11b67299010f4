/*
 * Tests for src/mesh/periodic_interp.c (fdt_interpolate, linear, and
 * fdt_locate on a periodic mesh):
 *  - periodic on x, y, z: a query and its translates by whole periods get
 *    the same values (to rounding), a query at a point (or an image of it)
 *    that point's values, a constant function the constant, every value
 *    between the least and the largest of the points' (a convex
 *    combination);
 *  - periodic on x and z with walls of points across y: a linear function
 *    of y reproduced to 1e-12, NaN past the walls and for a query with a
 *    NaN coordinate;
 *  - fdt_locate: a row of the mesh holding each query, its barycentric
 *    coordinates in the row's order (summing to 1, none negative), which
 *    weigh the points' values into fdt_interpolate's;
 *  - natural neighbours refused (FDT_EINVAL, with a message).
 * tests/periodic_e2e.py compares the values with a plain mesh of the
 * points replicated around the box.
 */
#include <math.h>
#include <string.h>

#include "frontdt.h"
#include "testutil.h"

static fdt_result *periodic_mesh(const double *xyz, size_t n, unsigned axes, const double box[6])
{
    fdt_settings s;
    fdt_default_settings(&s);
    s.periodic = axes;
    memcpy(s.periodic_box, box, sizeof s.periodic_box);
    fdt_context *ctx = NULL;
    fdt_result *r = NULL;
    CHECK(fdt_open(&ctx, &s) == FDT_OK);
    CHECK(fdt_triangulate(ctx, xyz, n, &r) == FDT_OK);
    fdt_close(&ctx);
    return r;
}

static void test_cube(void)
{
    const size_t n = 800, nq = 200;
    const double box[6] = {-0.5, 0.25, 1, 0.7, 1.25, 2.5}; /* periods 1.2, 1, 1.5 */
    double xyz[3 * 800], val[2 * 800], q[3 * 4 * 200], out[2 * 4 * 200];
    uint64_t s = 41;
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        for (int d = 0; d < 3; d++)
            xyz[3 * i + d] = box[d] + (box[d + 3] - box[d]) * test_unif(&s);
        val[2 * i] = test_unif(&s);
        val[2 * i + 1] = 7.25; /* a constant */
        lo = val[2 * i] < lo ? val[2 * i] : lo;
        hi = val[2 * i] > hi ? val[2 * i] : hi;
    }
    fdt_result *r = periodic_mesh(xyz, n, 7, box);
    /* each query, then three translates of it by whole periods */
    for (size_t k = 0; k < nq; k++) {
        double *a = q + 12 * k;
        for (int d = 0; d < 3; d++)
            a[d] = k % 20 == 0 ? xyz[3 * k + (size_t)d]
                               : box[d] + (box[d + 3] - box[d]) * test_unif(&s);
        for (int t = 1; t < 4; t++)
            for (int d = 0; d < 3; d++)
                a[3 * t + d] = a[d] + (d == t - 1 ? 2 - t : t) * (box[d + 3] - box[d]);
    }
    char diag[256];
    CHECK(fdt_interpolate(r, xyz, n, val, 2, q, 4 * nq, FDT_INTERP_LINEAR, 2, out, diag,
                          sizeof diag) == FDT_OK);
    for (size_t k = 0; k < nq; k++) {
        const double *o = out + 8 * k;
        for (int t = 0; t < 4; t++) {
            EXPECTF(fabs(o[2 * t] - o[0]) < 1e-12, "query %zu, translate %d: %.17g against %.17g",
                    k, t, o[2 * t], o[0]);
            EXPECTF(fabs(o[2 * t + 1] - 7.25) < 1e-12, "query %zu: the constant %.17g", k,
                    o[2 * t + 1]);
        }
        EXPECTF(o[0] >= lo - 1e-12 && o[0] <= hi + 1e-12, "query %zu: %.17g not among the "
                "points' values", k, o[0]);
        if (k % 20 == 0)
            EXPECTF(fabs(o[0] - val[2 * k]) < 1e-12, "query %zu at point %zu: %.17g, not %.17g",
                    k, k, o[0], val[2 * k]);
    }
    /* fdt_locate: a row holding each query, its coordinates in the row's
     * order, which weigh the first values into fdt_interpolate's */
    static fdt_tid tet[4 * 200];
    static double bary[4 * 4 * 200];
    CHECK(fdt_locate(r, xyz, n, q, 4 * nq, tet, bary, 1) == FDT_OK);
    const fdt_vid *rows = fdt_result_tets(r);
    size_t nt = fdt_result_num_tets(r);
    for (size_t k = 0; k < 4 * nq; k++) {
        EXPECTF(tet[k] >= 0 && (size_t)tet[k] < nt, "query %zu: row %lld", k, (long long)tet[k]);
        if (tet[k] < 0 || (size_t)tet[k] >= nt)
            continue;
        double sum = 0, v = 0, least = 1;
        for (int i = 0; i < 4; i++) {
            double c = bary[4 * k + (size_t)i];
            sum += c;
            least = c < least ? c : least;
            v += c * val[2 * (size_t)rows[4 * (size_t)tet[k] + (size_t)i]];
        }
        EXPECTF(fabs(sum - 1) < 1e-12 && least > -1e-12, "query %zu: coordinates sum %.17g, "
                "least %.17g", k, sum, least);
        EXPECTF(fabs(v - out[2 * k]) < 1e-12, "query %zu: %.17g by fdt_locate's coordinates, "
                "%.17g by fdt_interpolate", k, v, out[2 * k]);
    }
    /* natural neighbours: not for a periodic mesh */
    diag[0] = 0;
    EXPECT(fdt_interpolate(r, xyz, n, val, 2, q, 1, FDT_INTERP_NATURAL, 1, out, diag,
                           sizeof diag) == FDT_EINVAL);
    EXPECT(strstr(diag, "linearly") != NULL);
    fdt_result_free(&r);
}

/* A channel: periodic in x and z, walls of a grid across y (as
 * tests/periodic_e2e.py's channel), the values 3 y - 0.25. */
static void test_channel(void)
{
    enum { G = 8, NR = 600, NQ = 60 };
    const double box[6] = {0, -0.5, 0.25, 2, 0.5, 1.25};
    static double xyz[3 * (2 * G * G + NR)], val[2 * G * G + NR];
    size_t n = 0;
    for (int side = 0; side < 2; side++)
        for (int i = 0; i < G; i++)
            for (int j = 0; j < G; j++, n++) {
                xyz[3 * n] = box[0] + (box[3] - box[0]) * (i + 0.5) / G;
                xyz[3 * n + 1] = side ? 0.499 : -0.499;
                xyz[3 * n + 2] = box[2] + (box[5] - box[2]) * (j + 0.5) / G;
            }
    uint64_t s = 43;
    for (int i = 0; i < NR; i++, n++)
        for (int d = 0; d < 3; d++)
            xyz[3 * n + (size_t)d] = d == 1 ? -0.48 + 0.96 * test_unif(&s)
                                           : box[d] + (box[d + 3] - box[d]) * test_unif(&s);
    for (size_t i = 0; i < n; i++)
        val[i] = 3 * xyz[3 * i + 1] - 0.25;
    fdt_result *r = periodic_mesh(xyz, n, 5, box);
    double q[3 * (NQ + 3)], out[NQ + 3];
    for (int k = 0; k < NQ; k++) {
        q[3 * k] = -3 + 8 * test_unif(&s);
        q[3 * k + 1] = -0.49 + 0.98 * test_unif(&s);
        q[3 * k + 2] = -3 + 8 * test_unif(&s);
    }
    const double past[3][3] = {{0.5, 0.6, 0.5}, {1, -0.7, 4}, {NAN, 0, 0.5}};
    memcpy(q + 3 * NQ, past, sizeof past);
    CHECK(fdt_interpolate(r, xyz, n, val, 1, q, NQ + 3, FDT_INTERP_LINEAR, 1, out, NULL, 0) ==
          FDT_OK);
    for (int k = 0; k < NQ; k++)
        EXPECTF(fabs(out[k] - (3 * q[3 * k + 1] - 0.25)) < 1e-12, "channel query %d: %.17g", k,
                out[k]);
    for (int k = NQ; k < NQ + 3; k++)
        EXPECTF(isnan(out[k]), "channel query %d past the walls: %.17g", k, out[k]);
    fdt_result_free(&r);
}

int main(void)
{
    test_cube();
    test_channel();
    return test_report("periodic_interp");
}
