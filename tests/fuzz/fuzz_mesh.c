/*
 * libFuzzer target for the whole pipeline on small, nasty point sets:
 * the input bytes are decoded into at most FUZZ_MAX_POINTS points on an
 * integer lattice (cospherical and coplanar subsets everywhere, duplicates
 * often), optionally scaled near 1e-150 or 1e150, mixed in magnitude, or
 * offset far from the origin; then fdt_triangulate() (serial) runs on them
 * and on the same points in reverse order. A run must
 *  - return FDT_OK or FDT_EDEGENERATE (with a diagnostic), the same for
 *    both orders;
 *  - on success equal the result of shared mode with three threads;
 *  - on success pass fdt_check() (the independent exact verifier), with
 *    and without neighbours, have as many hull faces as tet faces without
 *    a neighbour, and give the same tets for both orders once every vertex
 *    is named by its coordinates (the perturbed Delaunay tetrahedralization
 *    does not depend on input order).
 * A violation aborts (libFuzzer saves the input).
 *
 * Encoding: byte 0 holds the flags below; then 3 bytes a point (signed
 * lattice coordinates), 4 in mixed-magnitude mode (the 4th picks the
 * point's power of two).
 */
#include "frontdt.h"
#include "geom/predicates.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FUZZ_MAX_POINTS 96

enum {
    FM_SCALE_MASK = 3, /* 0: 1, 1: 2^-498 (~1e-150), 2: 2^498, 3: mixed */
    FM_OFFSET = 4,     /* coordinates/2^20 + 2^30: big offset, tiny extent */
    FM_NEIGHBORS = 8,  /* ask for neighbours (checked against the faces) */
};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void fm_violation(const char *what, const char *detail)
{
    fprintf(stderr, "fuzz_mesh: %s%s%s\n", what, detail ? ": " : "",
            detail ? detail : "");
    abort();
}

static size_t fm_decode(const uint8_t *data, size_t size, double *xyz)
{
    unsigned flags = data[0];
    unsigned scale = flags & FM_SCALE_MASK;
    size_t per = scale == 3 ? 4 : 3;
    size_t n = (size - 1) / per;
    if (n > FUZZ_MAX_POINTS)
        n = FUZZ_MAX_POINTS;
    for (size_t i = 0; i < n; i++) {
        const uint8_t *b = data + 1 + i * per;
        int e = 0;
        if (scale == 1)
            e = -498;
        else if (scale == 2)
            e = 498;
        else if (scale == 3)
            e = ((int)(b[3] % 7) - 3) * 166;
        for (int k = 0; k < 3; k++) {
            double v = (double)(int8_t)b[k];
            if (flags & FM_OFFSET)
                v = ldexp(v, -20) + 0x1p30; /* exact: 50 bits */
            xyz[3 * i + k] = ldexp(v, e);
        }
    }
    return n;
}

/* Lexicographic order of points i and j (src/geom/predicates.c; -0 equals
 * +0 there, as in the duplicate merge). */
static int fm_cmp_pt(const double *xyz, int i, int j)
{
    return fdt_lex_compare(xyz + 3 * (size_t)i, xyz + 3 * (size_t)j);
}

static int fm_cmp_tet(const void *a, const void *b)
{
    const int *s = a, *t = b;
    for (int k = 0; k < 4; k++)
        if (s[k] != t[k])
            return s[k] < t[k] ? -1 : 1;
    return 0;
}

/*
 * The tets of r with every vertex named by the rank of its coordinates
 * among the distinct points, each tet's names ascending, tets sorted:
 * equal for any input order. order and rank (n entries) are scratch.
 */
static int *fm_canonical(const fdt_result *r, const double *xyz, size_t n,
                         int *order, int *rank)
{
    /* insertion sort: n is at most FUZZ_MAX_POINTS */
    for (size_t i = 0; i < n; i++) {
        size_t j = i;
        for (; j > 0 && fm_cmp_pt(xyz, order[j - 1], (int)i) > 0; j--)
            order[j] = order[j - 1];
        order[j] = (int)i;
    }
    int cur = -1;
    for (size_t i = 0; i < n; i++) {
        if (i == 0 || fm_cmp_pt(xyz, order[i - 1], order[i]) != 0)
            cur++;
        rank[order[i]] = cur;
    }
    size_t nt = fdt_result_num_tets(r);
    const fdt_vid *t = fdt_result_tets(r);
    int *c = malloc((4 * nt + 1) * sizeof *c);
    if (c == NULL)
        fm_violation("out of memory in the harness", NULL);
    for (size_t i = 0; i < nt; i++) {
        int *q = c + 4 * i;
        for (int k = 0; k < 4; k++)
            q[k] = rank[t[4 * i + k]];
        for (int a = 1; a < 4; a++) /* insertion sort of 4 */
            for (int b = a; b > 0 && q[b] < q[b - 1]; b--) {
                int x = q[b];
                q[b] = q[b - 1];
                q[b - 1] = x;
            }
    }
    qsort(c, nt, 4 * sizeof *c, fm_cmp_tet);
    return c;
}

static int fm_run(const double *xyz, size_t n, int neighbors, fdt_mode mode,
                  int threads, fdt_result **res, char *diag, size_t dlen)
{
    fdt_settings s;
    fdt_default_settings(&s);
    s.mode = mode;
    s.n_threads = threads;
    s.neighbors = neighbors;
    fdt_context *ctx = NULL;
    int rc = fdt_open(&ctx, &s);
    if (rc != FDT_OK)
        fm_violation("fdt_open failed", fdt_strerror(rc));
    rc = fdt_triangulate(ctx, xyz, n, res);
    snprintf(diag, dlen, "%s", fdt_context_diagnostic(ctx));
    fdt_close(&ctx);
    return rc;
}

static void fm_verify(const fdt_result *r, const double *xyz, size_t n,
                      int neighbors)
{
    char msg[512];
    size_t nt = fdt_result_num_tets(r);
    const fdt_vid *t = fdt_result_tets(r);
    const fdt_tid *nb = fdt_result_neighbors(r);
    if (nt == 0 || t == NULL)
        fm_violation("success without tets", NULL);
    if ((nb != NULL) != (neighbors != 0))
        fm_violation("neighbours present iff asked", NULL);
    if (fdt_check(xyz, n, t, nt, nb, msg, sizeof msg) != FDT_OK)
        fm_violation("fdt_check rejects the mesh", msg);
    if (nb != NULL) {
        if (fdt_check(xyz, n, t, nt, NULL, msg, sizeof msg) != FDT_OK)
            fm_violation("fdt_check without neighbours rejects it", msg);
        size_t open = 0;
        for (size_t i = 0; i < 4 * nt; i++)
            open += nb[i] < 0;
        if (open != fdt_result_num_hull_faces(r))
            fm_violation("hull faces differ from tet faces on the hull",
                         NULL);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    double xyz[3 * FUZZ_MAX_POINTS], rev[3 * FUZZ_MAX_POINTS];
    int order[FUZZ_MAX_POINTS], rank[FUZZ_MAX_POINTS];
    size_t n = fm_decode(data, size, xyz);
    int neighbors = (data[0] & FM_NEIGHBORS) != 0;
    for (size_t i = 0; i < n; i++)
        memcpy(rev + 3 * i, xyz + 3 * (n - 1 - i), 3 * sizeof(double));

    char d1[512], d2[512];
    fdt_result *r1 = NULL, *r2 = NULL;
    int rc1 = fm_run(xyz, n, neighbors, FDT_MODE_SERIAL, 1, &r1, d1, sizeof d1);
    int rc2 = fm_run(rev, n, neighbors, FDT_MODE_SERIAL, 1, &r2, d2, sizeof d2);
    if (rc1 != rc2) {
        char both[1100];
        snprintf(both, sizeof both, "%s / %s: '%s' / '%s'", fdt_strerror(rc1),
                 fdt_strerror(rc2), d1, d2);
        fm_violation("the two input orders give different results", both);
    }
    if (rc1 != FDT_OK) {
        if (rc1 != FDT_EDEGENERATE)
            fm_violation("unexpected error", fdt_strerror(rc1));
        if (d1[0] == '\0' || d2[0] == '\0')
            fm_violation("FDT_EDEGENERATE without a diagnostic", NULL);
        if (r1 != NULL || r2 != NULL)
            fm_violation("a failed call returned a result", NULL);
        return 0;
    }
    fm_verify(r1, xyz, n, neighbors);
    fm_verify(r2, rev, n, neighbors);
    size_t nt = fdt_result_num_tets(r1);
    if (fdt_result_num_tets(r2) != nt)
        fm_violation("the two input orders give different tet counts", NULL);
    int *c1 = fm_canonical(r1, xyz, n, order, rank);
    int *c2 = fm_canonical(r2, rev, n, order, rank);
    if (memcmp(c1, c2, 4 * nt * sizeof *c1) != 0)
        fm_violation("the two input orders give different tets", NULL);
    free(c1);
    free(c2);
    /* Three threads in shared mode advance the faces in another order
     * (three fronts, faces handed between them): a search that depends on
     * the order showed up only that way (the underflowed norm in
     * update_ball, src/geom/kdtree.c). Same input order, so same hash. */
    char d3[512];
    fdt_result *r3 = NULL;
    int rc3 = fm_run(xyz, n, 0, FDT_MODE_SHARED, 3, &r3, d3, sizeof d3);
    if (rc3 != FDT_OK)
        fm_violation("shared mode fails where serial succeeds", d3);
    uint64_t h1 = 0, h3 = 0;
    if (fdt_result_hash(r1, &h1) != FDT_OK || fdt_result_hash(r3, &h3) != FDT_OK)
        fm_violation("fdt_result_hash failed", NULL);
    if (h1 != h3)
        fm_violation("shared mode (3 threads) and serial give different tets", NULL);
    fdt_result_free(&r3);
    fdt_result_free(&r1);
    fdt_result_free(&r2);
    return 0;
}
