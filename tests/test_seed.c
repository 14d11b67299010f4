/*
 * The seed tetrahedron (src/front/seed.c): from several starting points of every
 * family of tests/testpoints.h the seed is positively oriented and empty
 * of every other point under the perturbed insphere test (brute force);
 * the dimension check names coplanar, collinear and too-small inputs.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geom/kdtree.h"
#include "geom/predicates.h"
#include "geom/prepare.h"
#include "front/seed.h"
#include "testutil.h"
#include "testpoints.h"

static void test_seeds(int fam, size_t want, int leaf, int sse_only)
{
    double *xyz = malloc(want * 3 * sizeof *xyz);
    CHECK(xyz);
    size_t n = make_points(fam, want, xyz);
    fdt_prepared pr;
    char diag[256];
    CHECK(fdt_prepare(xyz, n, 1, &pr, diag, sizeof diag) == FDT_OK);
    uint32_t m = (uint32_t)pr.m;
    fdt_kdtree t;
    CHECK(fdt_kd_build(&t, pr.p, pr.orig, 0, m, leaf) == FDT_OK);
    if (sse_only)
        t.avx2 = 0; /* the SSE kernels, which machines without AVX2 run */
    const double *P = pr.p;
    fdt_kdq kq;
    memset(&kq, 0, sizeof kq);
    /* The seed is a perturbed-Delaunay tet (brute-force emptiness) from
     * several starting points. */
    for (int q = 0; q < 5; q++) {
        uint32_t out[4];
        uint32_t start = (uint32_t)(rnd() % m);
        EXPECTF(fdt_seed_tet(&t, start, out, &kq) == FDT_OK, "%s seed from %u", family_name[fam], start);
        EXPECTF(fdt_orient3d(P + 3 * (size_t)out[0], P + 3 * (size_t)out[1], P + 3 * (size_t)out[2],
                           P + 3 * (size_t)out[3], NULL) > 0, "seed not positive");
        for (uint32_t j = 0; j < m; j++)
            if (j != out[0] && j != out[1] && j != out[2] && j != out[3])
                EXPECTF(fdt_insphere_perturbed(P + 3 * (size_t)out[0], P + 3 * (size_t)out[1],
                                             P + 3 * (size_t)out[2], P + 3 * (size_t)out[3],
                                             P + 3 * (size_t)j, NULL) < 0,
                      "%s seed tet holds point %u", family_name[fam], j);
    }
    fdt_kd_free(&t);
    fdt_prepared_free(&pr);
    free(xyz);
}

static void test_dimension(void)
{
    char diag[256];
    /* A tetrahedron and more pass; each degenerate dimension is named. */
    double tet[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0.25, 0.25, 0.25};
    EXPECTF(fdt_seed_check_dimension(tet, (const fdt_vid[]){0, 1, 2, 3, 4}, 5, diag, sizeof diag) ==
          FDT_OK, "tetrahedron refused: %s", diag);
    double flat[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 2, 3, 0};
    EXPECTF(fdt_seed_check_dimension(flat, (const fdt_vid[]){0, 1, 2, 3, 4}, 5, diag, sizeof diag) ==
          FDT_EDEGENERATE && strstr(diag, "coplanar"), "coplanar: %s", diag);
    double line[] = {0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3};
    EXPECTF(fdt_seed_check_dimension(line, (const fdt_vid[]){0, 1, 2, 3}, 4, diag, sizeof diag) ==
          FDT_EDEGENERATE && strstr(diag, "collinear"), "collinear: %s", diag);
    EXPECTF(fdt_seed_check_dimension(line, (const fdt_vid[]){0, 1, 2}, 3, diag, sizeof diag) ==
          FDT_EDEGENERATE && strstr(diag, "only 3"), "three points: %s", diag);
    /* Larger sets: a line, then a plane, then one point off it, at an
     * index among the first 64, among the 64 spread ones (m (2k + 1) /
     * 128), between them, or last; each found, whichever way. */
    enum { BIG = 5000 };
    double *big = malloc(3 * BIG * sizeof *big);
    fdt_vid *ids = malloc(BIG * sizeof *ids);
    CHECK(big && ids);
    const uint32_t off[] = {BIG, 3, 63, 64, 39, BIG / 2 - 1, BIG / 2 + 7, BIG - 1};
    for (size_t c = 0; c < sizeof off / sizeof off[0]; c++) {
        for (uint32_t i = 0; i < BIG; i++) {
            ids[i] = (fdt_vid)i;
            big[3 * i] = (double)(i % 97);
            big[3 * i + 1] = (double)(i / 97); /* the first 97 on a line */
            big[3 * i + 2] = i == off[c] ? 0.5 : 0.0;
        }
        int rc = fdt_seed_check_dimension(big, ids, BIG, diag, sizeof diag);
        if (off[c] == BIG)
            EXPECTF(rc == FDT_EDEGENERATE && strstr(diag, "coplanar"), "big plane: %s", diag);
        else
            EXPECTF(rc == FDT_OK, "plane with point %u off it refused: %s", off[c], diag);
    }
    free(big);
    free(ids);
}

int main(void)
{
    test_dimension();
    for (int sse_only = 0; sse_only <= 1; sse_only++)
        for (int fam = 0; fam < NFAMILIES; fam++) {
            test_seeds(fam, 700, 18, sse_only);
            test_seeds(fam, 300, 3, sse_only);
        }
    return test_report("test_seed");
}
