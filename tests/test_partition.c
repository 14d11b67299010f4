/*
 * The partition module (src/geom/partition.c): proportional part sizes for any
 * N (less the work shift), contiguous ranges, owner lookup (empty parts
 * skipped), the permutation kept, bisection boxes holding their points,
 * the composite tree's nearest point against brute force, refusals, and
 * the ranges moved by weights (fdt_partition_recut), a part's own tree
 * built from a partition made elsewhere (fdt_partition_build_own) and the
 * work shift (fdt_partition_work_shift), for src/mpi/mpi_setup.c.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "frontdt.h"
#include "geom/partition.h"
#include "testutil.h"

static void test_partition(void)
{
    struct {
        double *xyz;
        size_t n;
    } p = {malloc(3000 * sizeof(double)), 1000};
    CHECK(p.xyz);
    uint64_t seed = 7;
    for (size_t i = 0; i < 3 * p.n; i++)
        p.xyz[i] = test_unif(&seed);
    const int counts[] = {1, 2, 3, 5, 7, 64, 100, 1000, 1024};
    for (size_t c = 0; c < sizeof counts / sizeof *counts; c++) {
        int np = counts[c];
        double *P = malloc(3 * p.n * sizeof *P);
        fdt_vid *orig = malloc(p.n * sizeof *orig);
        CHECK(P && orig);
        memcpy(P, p.xyz, 3 * p.n * sizeof *P);
        for (size_t i = 0; i < p.n; i++)
            orig[i] = (fdt_vid)i;
        fdt_partition pt;
        CHECK_EQ(fdt_partition_build(&pt, P, orig, (uint32_t)p.n, np, 18, 1 + np % 5), FDT_OK);
        CHECK_EQ(pt.nparts, np);
        CHECK_EQ(pt.start[0], 0);
        CHECK_EQ(pt.start[np], p.n);
        size_t lo = p.n, hi = 0;
        for (int i = 0; i < np; i++) {
            CHECK(pt.start[i] <= pt.start[i + 1]);
            size_t sz = pt.start[i + 1] - pt.start[i];
            if (sz < lo)
                lo = sz;
            if (sz > hi)
                hi = sz;
            /* Every id of the part maps back to it; its tree covers it. */
            for (uint32_t id = pt.start[i]; id < pt.start[i + 1]; id++)
                CHECK_EQ(fdt_partition_owner(&pt, id), i);
            CHECK_EQ(pt.trees[i].n, sz);
            if (sz)
                CHECK_EQ(pt.trees[i].base, pt.start[i]);
        }
        /* Proportional splits, less the work shift (src/geom/partition.c,
         * work_shift: at most a sixteenth of a left side a level, and none
         * below 16 points): sizes near m / N, nobody empty while m >= N. */
        double mean = (double)p.n / np;
        CHECK((double)hi <= 1.5 * mean + 10 && (double)lo >= 0.5 * mean - 10);
        if ((size_t)np <= p.n)
            CHECK(lo >= 1);
        /* The permutation kept every point (orig is a permutation and P
         * follows it). */
        char *seen = calloc(p.n, 1);
        CHECK(seen);
        for (size_t i = 0; i < p.n; i++) {
            CHECK(orig[i] >= 0 && (size_t)orig[i] < p.n && !seen[orig[i]]);
            seen[orig[i]] = 1;
            CHECK(memcmp(P + 3 * i, p.xyz + 3 * (size_t)orig[i], 3 * sizeof *P) == 0);
        }
        free(seen);
        /* Bisection boxes contain their points. */
        for (int j = 0; j < pt.nnodes; j++) {
            const fdt_pnode *nd = &pt.nodes[j];
            for (uint32_t id = nd->begin; id < nd->end; id++)
                for (int k = 0; k < 3; k++)
                    CHECK(P[3 * id + k] >= nd->lo[k] && P[3 * id + k] <= nd->hi[k]);
        }
        /* The composite tree finds the true nearest point. */
        fdt_kdtree all;
        CHECK_EQ(fdt_partition_global_tree(&pt, &all), FDT_OK);
        CHECK_EQ(all.n, p.n);
        uint64_t r = 99;
        for (int q = 0; q < 50; q++) {
            double c3[3] = {test_unif(&r), test_unif(&r), test_unif(&r)};
            uint32_t b = fdt_kd_nearest(&all, c3, FDT_NONE, NULL);
            double bd = INFINITY;
            uint32_t bi = 0;
            for (uint32_t i = 0; i < p.n; i++) {
                double dx = P[3 * i] - c3[0], dy = P[3 * i + 1] - c3[1], dz = P[3 * i + 2] - c3[2];
                double d = dx * dx + dy * dy + dz * dz;
                if (d < bd) {
                    bd = d;
                    bi = i;
                }
            }
            CHECK_EQ(b, bi);
        }
        fdt_kd_free(&all);
        fdt_partition_free(&pt);
        free(P);
        free(orig);
    }
    /* More parts than points: empty parts, and owner() skips them. */
    {
        double P[5 * 3] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
        fdt_vid orig[5] = {0, 1, 2, 3, 4};
        fdt_partition pt;
        CHECK_EQ(fdt_partition_build(&pt, P, orig, 5, 16, 18, 4), FDT_OK);
        int nonempty = 0;
        for (int i = 0; i < 16; i++)
            nonempty += pt.start[i + 1] > pt.start[i];
        CHECK_EQ(nonempty, 5);
        for (uint32_t id = 0; id < 5; id++) {
            int o = fdt_partition_owner(&pt, id);
            CHECK(pt.start[o] <= id && id < pt.start[o + 1]);
        }
        fdt_kdtree all;
        CHECK_EQ(fdt_partition_global_tree(&pt, &all), FDT_OK);
        double q[3] = {0.9, 0.9, 0.9};
        uint32_t b = fdt_kd_nearest(&all, q, FDT_NONE, NULL);
        CHECK(P[3 * b] == 1 && P[3 * b + 1] == 1 && P[3 * b + 2] == 1);
        fdt_kd_free(&all);
        fdt_partition_free(&pt);
    }
    double P1[3] = {0, 0, 0};
    fdt_vid o1[1] = {0};
    fdt_partition pt;
    CHECK_EQ(fdt_partition_build(&pt, P1, o1, 1, 0, 18, 1), FDT_EINVAL);
    CHECK_EQ(fdt_partition_build(&pt, P1, o1, 1, FDT_PARTITION_MAX + 1, 18, 1), FDT_EINVAL);
    free(p.xyz);
    printf("partition: proportional parts, owners, boxes, composite tree\n");
}

/* fdt_partition_recut: each part's range holds an equal share of the
 * weights (the first id whose prefix sum reaches p * total / nparts
 * starts part p); heavy low ids move the cut down, an empty weight range
 * leaves a part empty, and the owners follow the new ranges. The trees
 * are not touched. */
static void test_recut(void)
{
    double *P = malloc(3 * 100 * sizeof *P);
    fdt_vid *orig = malloc(100 * sizeof *orig);
    CHECK(P && orig);
    uint64_t seed = 11;
    for (size_t i = 0; i < 300; i++)
        P[i] = test_unif(&seed);
    for (size_t i = 0; i < 100; i++)
        orig[i] = (fdt_vid)i;
    fdt_partition pt;
    CHECK_EQ(fdt_partition_build(&pt, P, orig, 100, 2, 18, 1), FDT_OK);
    uint32_t tree0 = pt.trees[0].n;
    uint32_t w[100];
    for (int i = 0; i < 100; i++)
        w[i] = i < 20 ? 4 : 1; /* 80 + 80: half the weight in ids 0..19 */
    fdt_partition_recut(&pt, w, 160);
    EXPECTF(pt.start[0] == 0 && pt.start[1] == 20 && pt.start[2] == 100, "cut at %u", pt.start[1]);
    EXPECT(fdt_partition_owner(&pt, 19) == 0 && fdt_partition_owner(&pt, 20) == 1);
    EXPECT(pt.trees[0].n == tree0); /* only ownership moved */
    fdt_partition_free(&pt);
    CHECK_EQ(fdt_partition_build(&pt, P, orig, 100, 3, 18, 1), FDT_OK);
    for (int i = 0; i < 100; i++)
        w[i] = i < 50 ? 0 : 1; /* nothing owned below 50 */
    fdt_partition_recut(&pt, w, 50);
    /* goals 16 and 33 of 50: ids 50..65 reach 16, 50..82 reach 33 */
    EXPECTF(pt.start[1] == 66 && pt.start[2] == 83 && pt.start[3] == 100, "cuts at %u, %u",
            pt.start[1], pt.start[2]);
    EXPECT(fdt_partition_owner(&pt, 0) == 0 && fdt_partition_owner(&pt, 66) == 1 &&
           fdt_partition_owner(&pt, 99) == 2);
    for (int i = 0; i < 100; i++)
        w[i] = i == 99 ? 5 : 0; /* all on the last id: two empty parts */
    fdt_partition_recut(&pt, w, 5);
    EXPECT(pt.start[1] == 100 && pt.start[2] == 100);
    EXPECT(fdt_partition_owner(&pt, 99) == 0);
    fdt_partition_free(&pt);
    free(P);
    free(orig);
    printf("partition: recut by weights\n");
}

/*
 * A partition made elsewhere (src/mpi/mpi_setup.c): start and nodes as
 * fdt_partition_build fills them, zeroed trees, then each part's tree by
 * fdt_partition_build_own must be the tree fdt_partition_build built
 * (same nodes, boxes and ranges; the same region, hence the same cells),
 * an empty part's tree left empty.
 */
static void test_build_own(void)
{
    const struct {
        uint32_t m;
        int np;
    } cases[] = {{600, 1}, {600, 2}, {600, 5}, {5, 8}};
    for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
        uint32_t m = cases[c].m;
        int np = cases[c].np;
        double *P = malloc(3 * (size_t)m * sizeof *P);
        fdt_vid *orig = malloc(m * sizeof *orig);
        CHECK(P && orig);
        uint64_t seed = 13 + c;
        for (size_t i = 0; i < 3 * (size_t)m; i++)
            P[i] = test_unif(&seed);
        for (uint32_t i = 0; i < m; i++)
            orig[i] = (fdt_vid)i;
        fdt_partition pt;
        CHECK_EQ(fdt_partition_build(&pt, P, orig, m, np, 10, 1), FDT_OK);
        /* the other copy: the points as the bisection left them */
        double *P2 = malloc(3 * (size_t)m * sizeof *P2);
        fdt_vid *orig2 = malloc(m * sizeof *orig2);
        CHECK(P2 && orig2);
        memcpy(P2, P, 3 * (size_t)m * sizeof *P2);
        memcpy(orig2, orig, m * sizeof *orig2);
        fdt_partition own = {.nparts = np, .m = m, .nnodes = pt.nnodes};
        own.start = malloc(((size_t)np + 1) * sizeof *own.start);
        own.nodes = malloc((size_t)pt.nnodes * sizeof *own.nodes);
        own.trees = calloc((size_t)np, sizeof *own.trees);
        CHECK(own.start && own.nodes && own.trees);
        memcpy(own.start, pt.start, ((size_t)np + 1) * sizeof *own.start);
        memcpy(own.nodes, pt.nodes, (size_t)pt.nnodes * sizeof *own.nodes);
        for (int p = 0; p < np; p++) {
            EXPECT(fdt_partition_build_own(&own, P2, orig2, p, 10) == FDT_OK);
            const fdt_kdtree *a = &pt.trees[p], *b = &own.trees[p];
            int same = a->n == b->n && a->base == b->base && a->nnodes == b->nnodes;
            for (uint32_t j = 0; same && j < a->nnodes; j++) {
                const fdt_kdnode *x = &a->nodes[j], *y = &b->nodes[j];
                same = x->begin == y->begin && x->end == y->end && x->left == y->left &&
                       memcmp(x->lo, y->lo, sizeof x->lo) == 0 &&
                       memcmp(x->hi, y->hi, sizeof x->hi) == 0;
                if (same && a->cell && b->cell)
                    same = memcmp(a->cell[j], b->cell[j], sizeof a->cell[j]) == 0;
                else if (same)
                    same = !a->cell && !b->cell;
            }
            EXPECTF(same, "m %u, %d parts: part %d's tree (%u nodes, %u points) differs",
                    m, np, p, b->nnodes, b->n);
            if (m < (uint32_t)np)
                EXPECT((a->n == 0) == (pt.start[p] == pt.start[p + 1]));
        }
        fdt_partition_free(&own);
        fdt_partition_free(&pt);
        free(P);
        free(orig);
        free(P2);
        free(orig2);
    }
    printf("partition: parts' own trees as the whole build\n");
}

/* The points the cut moves left for the tets across it: 0.578 count^(2/3)
 * V^(1/3) / w, at most a sixteenth of the left side, nothing for a flat box
 * or parts under 64 points. */
static void test_work_shift(void)
{
    fdt_pnode nd = {.lo = {0, 0, 0}, .hi = {1, 1, 1}};
    uint32_t want = (uint32_t)(0.578 * cbrt(1e6 * 1e6) / 1.0);
    EXPECTF(fdt_partition_work_shift(&nd, 500000, 1000000, 1.0, 1) == want, "%u",
            fdt_partition_work_shift(&nd, 500000, 1000000, 1.0, 1));
    EXPECT(want > 5700 && want < 5800);
    /* a narrow extent: capped at nleft / 16 */
    EXPECT(fdt_partition_work_shift(&nd, 500000, 1000000, 1e-6, 1) == 500000 / 16);
    EXPECT(fdt_partition_work_shift(&nd, 64 * 3 - 1, 1000, 1.0, 3) == 0); /* 63 a part */
    /* 64 a part: 0.578 * 100 = 57.8 capped at 192 / 16 */
    EXPECT(fdt_partition_work_shift(&nd, 64 * 3, 1000, 1.0, 3) == 12);
    EXPECT(fdt_partition_work_shift(&nd, 64 * 3, 1000, 10.0, 3) == 5); /* 5.78 */
    EXPECT(fdt_partition_work_shift(&nd, 500000, 1000000, 0.0, 1) == 0);
    nd.hi[2] = 0; /* flat */
    EXPECT(fdt_partition_work_shift(&nd, 500000, 1000000, 1.0, 1) == 0);
    nd.hi[2] = NAN;
    EXPECT(fdt_partition_work_shift(&nd, 500000, 1000000, 1.0, 1) == 0);
    printf("partition: work shift\n");
}

int main(void)
{
    test_partition();
    test_recut();
    test_build_own();
    test_work_shift();
    return test_report("test_partition");
}
