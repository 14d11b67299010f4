/*
 * A part's own mesh and its final tets (src/front/partmesh.c, issue 31):
 * for every family of tests/testpoints.h split into 1, 2, 3, 5 and 8 parts
 * by the engine's bisection, each part's certified mesh marks the tets
 * whose circumsphere lies strictly inside its cell; every one of them must
 * be a tet of the Delaunay mesh of all the points (built alone, as the
 * reference), and with one part every tet is final.
 *
 * test_partmesh --fraction FILE.xyz P...: the measurement of
 * bench/NOTES.md entry 88: for each part count, the share of the DT's tets
 * that the parts' meshes make final at once (the rest is the walls' work),
 * and the seconds of the parts' builds and of their certificates.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "frontdt.h"
#include "front/partmesh.h"
#include "geom/partition.h"
#include "geom/prepare.h"
#include "mesh/certify.h"
#include "testpoints.h"
#include "testutil.h"

typedef struct key4 {
    uint32_t v[4];
} key4;

static int key_cmp(const void *a, const void *b)
{
    return memcmp(a, b, sizeof(key4)) < 0 ? -1 : memcmp(a, b, sizeof(key4)) > 0;
}

static int u32_cmp(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

static key4 key_of(const uint32_t *v)
{
    key4 k;
    memcpy(k.v, v, sizeof k.v);
    qsort(k.v, 4, sizeof k.v[0], u32_cmp);
    return k;
}

/* The sorted keys of the finite tets of m. */
static key4 *all_keys(const fdt_ins *m, size_t *n)
{
    key4 *k = malloc((m->nfinite + 1) * sizeof *k);
    CHECK(k != NULL);
    size_t c = 0;
    for (uint32_t s = fdt_ins_next_finite(m, 0); s != FDT_NONE; s = fdt_ins_next_finite(m, s + 1))
        k[c++] = key_of(fdt_ins_tet(m, s));
    qsort(k, c, sizeof *k, key_cmp);
    *n = c;
    return k;
}

typedef struct split_result {
    size_t final, total;   /* final tets over the parts, tets of the DT */
    size_t wrong;          /* final tets not in the DT */
    double t_build, t_cert;
} split_result;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Splits the m points of p (prepared: distinct, permuted here) into
 * nparts, classifies each part's mesh, and checks the final tets against
 * the reference DT of all of them. */
static split_result split(double *p, fdt_vid *orig, uint32_t m, int nparts)
{
    split_result r = {0, 0, 0, 0.0, 0.0};
    fdt_partition pt;
    CHECK_EQ(fdt_partition_build(&pt, p, orig, m, nparts, 30, 1), FDT_OK);
    fdt_ins all;
    CHECK_EQ(fdt_ins_build(&all, p, 0, m, NULL), FDT_OK);
    size_t nk;
    key4 *keys = all_keys(&all, &nk);
    r.total = nk;
    fdt_ins_free(&all);
    for (int q = 0; q < nparts; q++) {
        uint32_t lo = pt.start[q], n = pt.start[q + 1] - lo;
        fdt_ins mp;
        double t0 = now();
        int err = fdt_ins_build(&mp, p, lo, n, NULL);
        r.t_build += now() - t0;
        if (err == FDT_EDEGENERATE) {
            fdt_ins_free(&mp);
            continue; /* a flat part (one layer of grid2d): no tet of its own */
        }
        CHECK_EQ(err, FDT_OK);
        t0 = now();
        fdt_certify_fail why;
        CHECK_EQ(fdt_certify(&mp, NULL, &why), FDT_OK);
        r.t_cert += now() - t0;
        uint8_t *fin = malloc(mp.nslots + 1);
        CHECK(fin != NULL);
        size_t nf = fdt_partmesh_final(&mp, &pt.trees[q], fin);
        r.final += nf;
        for (uint32_t s = 0; s < mp.nslots; s++) {
            if (!fin[s])
                continue;
            key4 k = key_of(fdt_ins_tet(&mp, s));
            if (!bsearch(&k, keys, nk, sizeof *keys, key_cmp))
                r.wrong++;
        }
        free(fin);
        fdt_ins_free(&mp);
    }
    free(keys);
    fdt_partition_free(&pt);
    return r;
}

static int measure(const char *path, int argc, char **argv)
{
    double *xyz;
    size_t n;
    char diag[512];
    if (fdt_read_points(path, NULL, &xyz, &n, diag, sizeof diag) != FDT_OK) {
        fprintf(stderr, "%s\n", diag);
        return 2;
    }
    fdt_prepared pr;
    CHECK_EQ(fdt_prepare(xyz, n, 1, &pr, diag, sizeof diag), FDT_OK);
    fdt_free(xyz);
    double *p = malloc(3 * pr.m * sizeof *p);
    CHECK(p != NULL);
    for (int i = 0; i < argc; i++) {
        int parts = atoi(argv[i]);
        memcpy(p, pr.p, 3 * pr.m * sizeof *p);
        split_result r = split(p, pr.orig, (uint32_t)pr.m, parts);
        printf("%s parts %d: %zu of %zu tets final (%.2f %%), wrong %zu; part builds %.3f s, "
               "certificates %.3f s\n",
               path, parts, r.final, r.total, 100.0 * (double)r.final / (double)r.total, r.wrong,
               r.t_build, r.t_cert);
        if (r.wrong)
            return 1;
    }
    free(p);
    fdt_prepared_free(&pr);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc >= 3 && strcmp(argv[1], "--fraction") == 0)
        return measure(argv[2], argc - 3, argv + 3);
    static const int counts[] = {1, 2, 3, 5, 8};
    for (int fam = 0; fam < NFAMILIES; fam++) {
        if (fam == MIXED)
            continue; /* repeats points: the prepare step merges, here none */
        double *p = malloc(3 * 4000 * sizeof *p);
        fdt_vid *orig = malloc(4000 * sizeof *orig);
        CHECK(p && orig);
        size_t m = make_points(fam, 4000, p);
        for (size_t c = 0; c < sizeof counts / sizeof *counts; c++) {
            for (size_t i = 0; i < m; i++)
                orig[i] = (fdt_vid)i;
            split_result r = split(p, orig, (uint32_t)m, counts[c]);
            EXPECTF(r.wrong == 0, "%s, %d parts: %zu final tets not in the DT",
                    family_name[fam], counts[c], r.wrong);
            if (counts[c] == 1)
                EXPECTF(r.final == r.total, "%s, one part: %zu of %zu tets final",
                        family_name[fam], r.final, r.total);
            else if (fam == UNIFORM)
                EXPECTF(r.final > r.total / 2, "uniform, %d parts: only %zu of %zu final",
                        counts[c], r.final, r.total);
            printf("%s, %d parts: %zu of %zu tets final\n", family_name[fam], counts[c],
                   r.final, r.total);
        }
        free(p);
        free(orig);
    }
    return test_report("partmesh");
}
