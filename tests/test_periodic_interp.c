/*
 * Tests for src/mesh/periodic_interp.c (fdt_interpolate, linear and
 * natural, and fdt_locate on a periodic mesh):
 *  - periodic on x, y, z, both methods: a query and its translates by
 *    whole periods get the same values (to rounding), a query at a point
 *    (or an image of it) that point's values, a constant function the
 *    constant, every value between the least and the largest of the
 *    points' (a convex combination); the same bits on 1, 2 and 3 threads;
 *  - against the plain mesh of the points replicated in the 27 copies
 *    around the box (fdt_triangulate and fdt_interpolate of a plain run,
 *    at the queries wrapped into the box): uniform points and a lattice
 *    (every cell's points cospherical, where the natural neighbours'
 *    cavities reach past the first patch's margin), both methods, 1e-12;
 *  - periodic on x and z with walls of points across y: a linear function
 *    of y reproduced to 1e-12 by both methods, NaN past the walls and for
 *    a query with a NaN coordinate;
 *  - fdt_locate: a row of the mesh holding each query, its barycentric
 *    coordinates in the row's order (summing to 1, none negative), which
 *    weigh the points' values into fdt_interpolate's; a point count
 *    other than the mesh's refused;
 *  - fdt_periodic_patch_make: each tet a translate of its row, neighbours
 *    mutual, points numbered by (id, offsets); on a patch without margin
 *    the cavities that reach its edge are reported (cut, NaN) and the
 *    others' values are the same bits as on a patch with a wide margin,
 *    where none is cut; the whole call started from a patch without
 *    margin (its retries) gives those bits for every query.
 * tests/periodic_e2e.py compares the CLI's values with plain frontdt's of
 * the points replicated around the box.
 */
#include <math.h>
#include <string.h>

#include "frontdt.h"
#include "mesh/locate.h"
#include "mesh/periodic.h"
#include "mesh/periodic_interp.h"
#include "testutil.h"

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
    fdt_result *r = test_periodic_mesh(xyz, n, 7, box);
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
    for (int method = FDT_INTERP_NATURAL; method >= FDT_INTERP_LINEAR; method--) {
    static double again[2 * 4 * 200];
    for (int threads = 3; threads >= 1; threads--) {
        CHECK(fdt_interpolate(r, xyz, n, val, 2, q, 4 * nq, (fdt_interp)method, threads, out,
                              diag, sizeof diag) == FDT_OK);
        if (threads < 3)
            EXPECTF(!memcmp(out, again, sizeof out), "method %d: other bits on %d threads "
                    "than on 3", method, threads);
        memcpy(again, out, sizeof out);
    }
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
    /* other points than the mesh's: refused, not read past their end */
    EXPECT(fdt_interpolate(r, xyz, n - 1, val, 2, q, 1, FDT_INTERP_LINEAR, 1, out, NULL, 0) ==
           FDT_EINVAL);
    EXPECT(fdt_locate(r, xyz, n - 1, q, 1, tet, NULL, 1) == FDT_EINVAL);
    fdt_result_free(&r);
}

/* Periodic on x, y, z against the plain mesh of the 27 copies. The box's
 * corners and periods are dyadic, so x + k L rounded once is the image
 * the periodic run rounds (fdt_images_round). */
static void replicated(const char *what, const double *xyz, size_t n, const double box[6],
                       uint64_t seed)
{
    enum { NQ = 300 };
    const size_t m = 27 * n;
    double *rep = malloc(3 * m * sizeof *rep), *val = malloc(n * sizeof *val),
           *rval = malloc(m * sizeof *rval);
    static double q[3 * NQ], wq[3 * NQ], got[NQ], want[NQ];
    CHECK(rep && val && rval);
    for (size_t i = 0; i < n; i++)
        val[i] = test_unif(&seed) - 0.5;
    for (int c = 0; c < 27; c++) {
        const int o[3] = {c % 3 - 1, c / 3 % 3 - 1, c / 9 - 1};
        for (size_t i = 0; i < n; i++) {
            for (int d = 0; d < 3; d++)
                rep[3 * (c * n + i) + (size_t)d] =
                    xyz[3 * i + (size_t)d] + o[d] * (box[d + 3] - box[d]);
            rval[c * n + i] = val[i];
        }
    }
    for (int k = 0; k < NQ; k++)
        for (int d = 0; d < 3; d++) {
            const double L = box[d + 3] - box[d];
            q[3 * k + d] = box[d] - 2 * L + 5 * L * test_unif(&seed);
            wq[3 * k + d] = box[d] + fmod(q[3 * k + d] - box[d] + 2 * L, L); /* exact */
        }
    fdt_result *r = test_periodic_mesh(xyz, n, 7, box);
    fdt_settings s;
    fdt_default_settings(&s);
    fdt_context *ctx = NULL;
    fdt_result *plain = NULL;
    CHECK(fdt_open(&ctx, &s) == FDT_OK);
    CHECK(fdt_triangulate(ctx, rep, m, &plain) == FDT_OK);
    fdt_close(&ctx);
    for (int method = FDT_INTERP_LINEAR; method <= FDT_INTERP_NATURAL; method++) {
        char diag[256] = "";
        EXPECTF(fdt_interpolate(r, xyz, n, val, 1, q, NQ, (fdt_interp)method, 2, got, diag,
                                sizeof diag) == FDT_OK, "%s: %s", what, diag);
        CHECK(fdt_interpolate(plain, rep, m, rval, 1, wq, NQ, (fdt_interp)method, 2, want, NULL,
                              0) == FDT_OK);
        double worst = 0;
        for (int k = 0; k < NQ; k++) /* NaN stays */
            worst = fabs(got[k] - want[k]) <= worst ? worst : fabs(got[k] - want[k]) + worst;
        EXPECTF(worst < 1e-12, "%s, method %d: %.3g off the replicated mesh's values", what,
                method, worst);
    }
    fdt_result_free(&plain);
    fdt_result_free(&r);
    free(rep);
    free(val);
    free(rval);
}

static void test_replicated(void)
{
    const double box[6] = {0, 0.25, -1, 1, 1.25, 0.5}; /* periods 1, 1, 1.5 */
    enum { N = 400, G = 6 };
    static double xyz[3 * N];
    uint64_t s = 45;
    for (size_t i = 0; i < N; i++)
        for (int d = 0; d < 3; d++)
            xyz[3 * i + (size_t)d] = box[d] + (box[d + 3] - box[d]) * test_unif(&s);
    replicated("uniform", xyz, N, box, 46);
    size_t n = 0;
    for (int i = 0; i < G; i++)
        for (int j = 0; j < G; j++)
            for (int k = 0; k < G; k++, n++) {
                const int ijk[3] = {i, j, k};
                for (int d = 0; d < 3; d++)
                    xyz[3 * n + (size_t)d] = box[d] + (box[d + 3] - box[d]) * ijk[d] / G;
            }
    replicated("lattice", xyz, n, box, 47);
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
    fdt_result *r = test_periodic_mesh(xyz, n, 5, box);
    double q[3 * (NQ + 3)], out[NQ + 3];
    for (int k = 0; k < NQ; k++) {
        q[3 * k] = -3 + 8 * test_unif(&s);
        q[3 * k + 1] = -0.49 + 0.98 * test_unif(&s);
        q[3 * k + 2] = -3 + 8 * test_unif(&s);
    }
    const double past[3][3] = {{0.5, 0.6, 0.5}, {1, -0.7, 4}, {NAN, 0, 0.5}};
    memcpy(q + 3 * NQ, past, sizeof past);
    for (int method = FDT_INTERP_LINEAR; method <= FDT_INTERP_NATURAL; method++) {
        CHECK(fdt_interpolate(r, xyz, n, val, 1, q, NQ + 3, (fdt_interp)method, 1, out, NULL,
                              0) == FDT_OK);
        for (int k = 0; k < NQ; k++)
            EXPECTF(fabs(out[k] - (3 * q[3 * k + 1] - 0.25)) < 1e-12, "channel query %d, "
                    "method %d: %.17g", k, method, out[k]);
        for (int k = NQ; k < NQ + 3; k++)
            EXPECTF(isnan(out[k]), "channel query %d past the walls, method %d: %.17g", k,
                    method, out[k]);
    }
    fdt_result_free(&r);
}

static void test_patch(void)
{
    enum { N = 500, NQ = 400 };
    const double box[6] = {0, 0, 0, 1, 2, 1};
    static double xyz[3 * N], val[N], q[3 * NQ], wide[NQ], narrow[NQ];
    static uint8_t cut[NQ];
    uint64_t s = 48;
    for (size_t i = 0; i < N; i++) {
        for (int d = 0; d < 3; d++)
            xyz[3 * i + (size_t)d] = box[d + 3] * test_unif(&s);
        val[i] = test_unif(&s);
    }
    for (size_t k = 0; k < NQ; k++)
        for (int d = 0; d < 3; d++)
            q[3 * k + (size_t)d] = box[d + 3] * test_unif(&s);
    fdt_result *r = test_periodic_mesh(xyz, N, 7, box);
    const fdt_periodic_box b = fdt_periodic_box_of(7, box);
    const fdt_vid *rows = fdt_result_tets(r);
    fdt_periodic_unfolded u;
    fdt_tid *unb;
    CHECK(fdt_periodic_unfold(rows, fdt_result_tet_offsets(r), fdt_result_num_tets(r), NULL,
                              NULL, 0, xyz, N, &b, &u) == FDT_OK);
    CHECK(fdt_periodic_unfolded_neighbors(&u, &unb) == FDT_OK);
    const double margins[2][3] = {{0, 0, 0}, {0.5, 1, 0.5}};
    for (int w = 1; w >= 0; w--) {
        fdt_periodic_patch p;
        CHECK(fdt_periodic_patch_make(&u, unb, xyz, &b, margins[w], &p) == FDT_OK);
        size_t cuts = 0, bad = 0;
        for (size_t t = 0; t < p.ntets; t++)
            for (int f = 0; f < 4; f++) {
                fdt_tid o = p.nbrs[4 * t + (size_t)f];
                int back = 0;
                for (int g = 0; o >= 0 && g < 4; g++)
                    back |= p.nbrs[4 * (size_t)o + (size_t)g] == (fdt_tid)t;
                cuts += o == FDT_NB_CUT;
                bad += o == -1 || (o >= 0 && !back);
                int named = 0; /* the row's ids, each once */
                for (int i = 0; i < 4; i++)
                    named += p.src[p.tets[4 * t + (size_t)f]] ==
                             rows[4 * (size_t)p.row[t] + (size_t)i];
                bad += named != 1;
            }
        for (size_t i = 1; i < p.n; i++)
            bad += p.src[i] < p.src[i - 1];
        EXPECTF(bad == 0, "patch %d: %zu faces, ids or points wrong", w, bad);
        EXPECTF(cuts > 0, "patch %d: no face at its edge", w);
        fdt_locator L;
        fdt_locator_patch(&L, p.tets, p.nbrs, p.ntets, p.xyz);
        memset(cut, 0, sizeof cut);
        CHECK(fdt_interpolate_with(&L, p.src, val, 1, q, NQ, FDT_INTERP_NATURAL, 2,
                                   w ? wide : narrow, cut, 0, q, NULL, 0) == FDT_OK);
        size_t ncut = 0, diff = 0;
        for (size_t k = 0; k < NQ; k++) {
            ncut += cut[k];
            if (!w)
                diff += cut[k] ? !isnan(narrow[k])
                               : memcmp(&narrow[k], &wide[k], sizeof *wide) != 0;
        }
        if (w)
            EXPECTF(ncut == 0, "the wide patch cut %zu cavities", ncut);
        else
            EXPECTF(ncut > 0 && ncut < NQ && diff == 0, "the patch without margin: %zu of %d "
                    "cavities cut, %zu values wrong", ncut, NQ, diff);
        fdt_periodic_patch_free(&p);
    }
    /* the whole call from a patch without margin: the cut cavities asked
     * again of patches of growing margins, the values wide's bits */
    CHECK(fdt_periodic_interpolate_from(rows, fdt_result_tet_offsets(r), fdt_result_num_tets(r),
                                        xyz, N, &b, val, 1, q, NQ, FDT_INTERP_NATURAL, 2, narrow,
                                        NULL, 0, 0) == FDT_OK);
    EXPECT(!memcmp(narrow, wide, sizeof wide));
    free(unb);
    fdt_periodic_unfolded_free(&u);
    fdt_result_free(&r);
}

int main(void)
{
    test_patch();
    test_cube();
    test_replicated();
    test_channel();
    return test_report("periodic_interp");
}
