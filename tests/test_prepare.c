/*
 * Input preparation (src/geom/prepare.c): duplicate merge into the first index
 * (-0 == +0), power-of-two scaling (exact, mixed magnitudes kept normal),
 * NaN and Inf refused with the point named, the merge on several
 * threads equal to one thread's bit for bit, and the merge in the
 * caller's array (fdt_prepare_inplace) equal to the copying one.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geom/prepare.h"
#include "testutil.h"
#include "testpoints.h"

/* The merge on several threads (src/geom/prepare.c, prepare_threads) gives
 * the one-thread result bit for bit, duplicates and scaling included, and
 * names the same first non-finite point. */
static void test_prepare_threads(void)
{
    const size_t want = 90000;
    double *xyz = malloc(want * 3 * sizeof *xyz);
    for (int fam = 0; fam < NFAMILIES; fam++) {
        size_t n = make_points(fam, want, xyz);
        /* duplicates across slices: copies of points from the whole range */
        for (size_t i = 0; i + 7 < n && n >= 1000; i += 97)
            memcpy(xyz + 3 * i, xyz + 3 * ((i * 7919 + 13) % n), 3 * sizeof *xyz);
        fdt_prepared one, par;
        char diag[256];
        EXPECTF(fdt_prepare(xyz, n, 1, &one, diag, sizeof diag) == FDT_OK, "prepare %s",
              family_name[fam]);
        for (int T = 2; T <= 8; T += 3) {
            EXPECTF(fdt_prepare(xyz, n, T, &par, diag, sizeof diag) == FDT_OK, "prepare %s T=%d",
                  family_name[fam], T);
            EXPECTF(par.m == one.m && par.ndup == one.ndup && par.scale_exp == one.scale_exp &&
                      !memcmp(par.p, one.p, 3 * one.m * sizeof *one.p) &&
                      !memcmp(par.orig, one.orig, one.m * sizeof *one.orig) &&
                      !memcmp(par.dupmap, one.dupmap, n * sizeof *one.dupmap),
                  "%s (%zu points, %zu distinct): %d threads differ", family_name[fam], n, one.m,
                  T);
            fdt_prepared_free(&par);
        }
        if (n >= 80000) {
            /* two bad points in different slices: the first is named */
            double keep[2] = {xyz[3 * 70000 + 1], xyz[3 * 40000 + 2]};
            xyz[3 * 70000 + 1] = NAN;
            xyz[3 * 40000 + 2] = -INFINITY;
            char d1[256], d2[256];
            EXPECTF(fdt_prepare(xyz, n, 1, &par, d1, sizeof d1) == FDT_ERANGE &&
                      fdt_prepare(xyz, n, 5, &par, d2, sizeof d2) == FDT_ERANGE &&
                      strstr(d1, "point 40000 has a non-finite z") && !strcmp(d1, d2),
                  "non-finite: '%s' against '%s'", d1, d2);
            xyz[3 * 70000 + 1] = keep[0];
            xyz[3 * 40000 + 2] = keep[1];
        }
        fdt_prepared_free(&one);
    }
    free(xyz);
}

static void test_prepare(void)
{
    /* Duplicates merge into the first index, -0 == +0; scaling is a power
     * of two; NaN and Inf are refused with the point named. */
    double xyz[] = {1, 2, 3, 0.0, 0, 0, 1, 2, 3, -0.0, 0, 0, 5, 6, 7, 1, 2, 3};
    fdt_prepared pr;
    char diag[256];
    EXPECTF(fdt_prepare(xyz, 6, 1, &pr, diag, sizeof diag) == FDT_OK, "prepare dups");
    EXPECTF(pr.m == 3 && pr.ndup == 3, "distinct %zu dup %zu", pr.m, pr.ndup);
    EXPECTF(pr.dupmap[2] == 0 && pr.dupmap[3] == 1 && pr.dupmap[5] == 0 && pr.dupmap[4] == 4,
          "duplicate map");
    EXPECTF(pr.orig[0] == 0 && pr.orig[1] == 1 && pr.orig[2] == 4, "first indices");
    EXPECTF(ldexp(7.0, pr.scale_exp) == pr.p[8] && ldexp(7.0, pr.scale_exp) < 1.0 &&
          ldexp(7.0, pr.scale_exp) >= 0.5, "scale 2^%d", pr.scale_exp);
    fdt_prepared_free(&pr);
    double big[] = {1e150, 2e150, 3e150, -1e150, 5e149, 1e148};
    EXPECTF(fdt_prepare(big, 2, 1, &pr, diag, sizeof diag) == FDT_OK && pr.p[0] < 1.0, "scale down 1e150");
    fdt_prepared_free(&pr);
    /* Mixed 1e-300 and 1e300: the scale must keep 1e-300 normal (exact). */
    double mixed[] = {1e300, 0, 0, 1e-300, 0, 0};
    EXPECTF(fdt_prepare(mixed, 2, 1, &pr, diag, sizeof diag) == FDT_OK, "mixed");
    EXPECTF(ldexp(pr.p[3], -pr.scale_exp) == 1e-300, "mixed magnitudes not exact");
    fdt_prepared_free(&pr);
    double bad[] = {0, 0, 0, 1, NAN, 2};
    EXPECTF(fdt_prepare(bad, 2, 1, &pr, diag, sizeof diag) == FDT_ERANGE && strstr(diag, "point 1"),
          "NaN not refused: %s", diag);
    double inf[] = {INFINITY, 0, 0};
    EXPECTF(fdt_prepare(inf, 1, 1, &pr, diag, sizeof diag) == FDT_ERANGE, "Inf not refused");
}

/* fdt_prepare_inplace (settings.permute_input): the same result as the
 * copying merge, with the points compacted into the caller's array (every
 * family, duplicates across the range or none, -0 against +0), on one
 * thread and, past 64k points, on two and three (the slices write their
 * own points when there is no duplicate, else in order); the array left
 * as it was when a point is refused. */
static void inplace_case(size_t want, int threads, int dups)
{
    double *xyz = malloc(want * 3 * sizeof *xyz);
    double *work = malloc(want * 3 * sizeof *work);
    CHECK(xyz && work);
    for (int fam = 0; fam < NFAMILIES; fam++) {
        size_t n = make_points(fam, want, xyz);
        for (size_t i = 0; dups && i + 7 < n && n >= 1000; i += 97)
            memcpy(xyz + 3 * i, xyz + 3 * ((i * 7919 + 13) % n), 3 * sizeof *xyz);
        if (dups && n > 10) {
            xyz[3 * 5] = 0.0;
            xyz[3 * 9] = -0.0;
            memcpy(xyz + 3 * 9 + 1, xyz + 3 * 5 + 1, 2 * sizeof *xyz);
        }
        memcpy(work, xyz, 3 * n * sizeof *xyz);
        fdt_prepared ref, in;
        char diag[256];
        CHECK_EQ(fdt_prepare(xyz, n, 1, &ref, diag, sizeof diag), FDT_OK);
        EXPECTF(fdt_prepare_inplace(work, n, threads, &in, diag, sizeof diag) == FDT_OK, "%s",
                family_name[fam]);
        EXPECTF(in.p == work && in.p_borrowed && in.m == ref.m && in.ndup == ref.ndup &&
                    in.scale_exp == ref.scale_exp &&
                    !memcmp(in.p, ref.p, 3 * ref.m * sizeof *ref.p) &&
                    !memcmp(in.orig, ref.orig, ref.m * sizeof *ref.orig) &&
                    !memcmp(in.dupmap, ref.dupmap, n * sizeof *ref.dupmap),
                "%s (%zu points, %zu distinct, %d threads): in place differs", family_name[fam],
                n, ref.m, threads);
        fdt_prepared_free(&in); /* frees the library's arrays, not work */
        EXPECT(in.p == NULL);
        fdt_prepared_free(&ref);
    }
    free(work);
    free(xyz);
}

static void test_prepare_inplace(void)
{
    inplace_case(30000, 1, 1);
    inplace_case(140000, 2, 1);
    inplace_case(140000, 3, 0);
    inplace_case(140000, 3, 1);
    double *xyz = malloc(100 * 3 * sizeof *xyz), *work = malloc(100 * 3 * sizeof *work);
    CHECK(xyz && work);
    make_points(0, 100, xyz);
    memcpy(work, xyz, 3 * 100 * sizeof *xyz);
    work[3 * 60 + 1] = NAN;
    memcpy(xyz, work, 3 * 100 * sizeof *xyz);
    fdt_prepared pr;
    char diag[256];
    EXPECT(fdt_prepare_inplace(work, 100, 1, &pr, diag, sizeof diag) == FDT_ERANGE &&
           strstr(diag, "point 60") && !memcmp(work, xyz, 3 * 60 * sizeof *xyz));
    free(work);
    free(xyz);
    /* on three threads, the bad point in the last slice: nothing written */
    const size_t big = 140000;
    xyz = malloc(big * 3 * sizeof *xyz);
    work = malloc(big * 3 * sizeof *work);
    CHECK(xyz && work);
    make_points(0, big, xyz);
    xyz[3 * 130000 + 2] = INFINITY;
    memcpy(work, xyz, 3 * big * sizeof *xyz);
    EXPECT(fdt_prepare_inplace(work, big, 3, &pr, diag, sizeof diag) == FDT_ERANGE &&
           strstr(diag, "point 130000") && !memcmp(work, xyz, 3 * big * sizeof *xyz));
    free(work);
    free(xyz);
}

/* fdt_prepare_scale_exp (the exponent each MPI rank applies, from the
 * extremes reduced over the ranks): the one fdt_prepare picks for the same
 * points, the largest |x| brought into [1/2, 1), the smallest nonzero |x|
 * kept at or above 2^-1021 (the clamp wins over the first), 0 for all
 * zeros. */
static void test_scale_exp(void)
{
    EXPECT(fdt_prepare_scale_exp(0.0, INFINITY) == 0);
    EXPECT(fdt_prepare_scale_exp(1.0, 1.0) == -1);
    EXPECT(fdt_prepare_scale_exp(0.75, 0.75) == 0);
    EXPECT(fdt_prepare_scale_exp(1e-10, 1e-10) == 33); /* 2^-34 <= 1e-10 < 2^-33 */
    /* 1e300 alone: into [1/2, 1); with 1e-300 the clamp keeps it normal */
    int k = fdt_prepare_scale_exp(1e300, 1e300);
    EXPECTF(ldexp(1e300, k) < 1.0 && ldexp(1e300, k) >= 0.5, "1e300: 2^%d", k);
    k = fdt_prepare_scale_exp(1e300, 1e-300);
    EXPECTF(ldexp(1e-300, k) >= ldexp(1.0, -1021) && ldexp(1e-300, k - 1) < ldexp(1.0, -1021),
            "1e300 and 1e-300: 2^%d", k);
    /* random magnitudes: the same exponent as fdt_prepare on the points */
    uint64_t seed = 5;
    char diag[256];
    for (int t = 0; t < 200; t++) {
        double xyz[12];
        double maxabs = 0.0, minabs = INFINITY;
        for (int i = 0; i < 12; i++) {
            double e = (test_unif(&seed) - 0.5) * 1600.0 * (t % 4 == 0 ? 1.0 : 0.1);
            xyz[i] = (i % 5 == 0 && t % 3 == 0) ? 0.0 : ldexp(test_unif(&seed) + 0.01, (int)e);
            if (i % 2)
                xyz[i] = -xyz[i];
            double a = fabs(xyz[i]);
            if (a > maxabs)
                maxabs = a;
            if (a > 0.0 && a < minabs)
                minabs = a;
        }
        fdt_prepared pr;
        CHECK(fdt_prepare(xyz, 4, 1, &pr, diag, sizeof diag) == FDT_OK);
        k = fdt_prepare_scale_exp(maxabs, minabs);
        EXPECTF(k == pr.scale_exp, "trial %d: 2^%d, fdt_prepare 2^%d", t, k, pr.scale_exp);
        fdt_prepared_free(&pr);
    }
}

int main(void)
{
    test_prepare();
    test_scale_exp();
    test_prepare_threads();
    test_prepare_inplace();
    return test_report("test_prepare");
}
