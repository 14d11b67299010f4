/*
 * Tests for src/geom/morton.c: Morton order by radix sort, against keys
 * interleaved here bit by bit (an independent spelling of the same key).
 *  - fdt_morton_order: every point not skipped once, keys ascending, the
 *    runs of one key longer than 32 ordered again in their own box, down
 *    to equal points, and ties by index;
 *  - fdt_morton_sort: each point keeps its input index, in the order of
 *    fdt_morton_order over the points' own bounding box, on 1, 2 and 3
 *    threads (slices of the records, of the buckets past 2^21);
 *  - no point, one point, all points equal (a box of width 0);
 *  - past 2^21 points, where the sort splits on the top bits first, with
 *    large buckets and with small ones (sorted by insertion).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geom/morton.h"
#include "testutil.h"

/* The bits a coordinate for n points: 21, or what a 64-bit record leaves
 * beside an index of n - 1 (src/geom/morton.c). */
static int key_bits(size_t n)
{
    int idbits = 1;
    while (((uint64_t)(n ? n - 1 : 0) >> idbits) != 0)
        idbits++;
    return (64 - idbits) / 3 < 21 ? (64 - idbits) / 3 : 21;
}

/* `bits` bits a coordinate in the box, x's bit above y's above z's. */
static uint64_t ref_key(const double *p, const double box[6], int bits)
{
    uint64_t key = 0;
    uint32_t c[3];
    for (int k = 0; k < 3; k++) {
        double w = box[k + 3] - box[k], t = w > 0 ? (p[k] - box[k]) / w : 0;
        t = t > 0 ? (t < 1 ? t : 1) : 0;
        c[k] = (uint32_t)(t * (double)((1u << bits) - 1));
    }
    for (int b = bits - 1; b >= 0; b--)
        for (int k = 0; k < 3; k++)
            key = key << 1 | ((c[k] >> b) & 1);
    return key;
}

static uint64_t rng = 88172645463325252u;
static double unif(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return (double)(rng >> 11) * 0x1p-53;
}

/* n points, some repeated and some in one fine cell, so ties occur, and
 * a fifth in a small box, so that the keys' low digits decide. */
static double *points(size_t n)
{
    double *p = malloc(3 * n * sizeof *p);
    CHECK(p != NULL);
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            p[3 * i + k] = i % 7 == 3 && i > 0 ? p[3 * (i - 1) + k]
                           : i % 11 == 5      ? 0.5 + 1e-9 * unif()
                           : i % 5 == 2       ? 0.25 + 1e-4 * unif() /* keys apart in
                                                                        their low bits */
                                              : unif() * 4 - 1;
    return p;
}

/* order[lo .. hi) by keys in box, ascending; each run of one key longer
 * than 32 by keys in its own points' box, the same way down, unless its
 * points are all one; shorter runs, and runs of one point, by index. */
static void check_run(const double *p, const uint32_t *order, size_t lo, size_t hi,
                      const double box[6], int bits)
{
    for (size_t i = lo, j; i < hi; i = j) {
        uint64_t a = ref_key(p + 3 * (size_t)order[i], box, bits);
        for (j = i + 1; j < hi && ref_key(p + 3 * (size_t)order[j], box, bits) == a; j++)
            ;
        if (j < hi)
            CHECK(ref_key(p + 3 * (size_t)order[j], box, bits) > a);
        double sub[6];
        for (size_t k = i; k < j; k++)
            for (int c = 0; c < 3; c++) {
                double x = p[3 * (size_t)order[k] + (size_t)c];
                sub[c] = k == i || x < sub[c] ? x : sub[c];
                sub[c + 3] = k == i || x > sub[c + 3] ? x : sub[c + 3];
            }
        if (j - i > 32 && (sub[0] != sub[3] || sub[1] != sub[4] || sub[2] != sub[5])) {
            check_run(p, order, i, j, sub, bits);
            continue;
        }
        for (size_t k = i + 1; k < j; k++)
            CHECK(order[k - 1] < order[k]);
    }
}

static void check_order(const double *p, size_t n, const double box[6], const uint8_t *skip,
                        const uint32_t *order, long m)
{
    size_t want = 0;
    for (size_t i = 0; i < n; i++)
        want += !skip || !skip[i];
    CHECK(m == (long)want);
    uint8_t *seen = calloc(n ? n : 1, 1);
    CHECK(seen != NULL);
    for (long i = 0; i < m; i++) {
        CHECK(order[i] < n && !seen[order[i]] && (!skip || !skip[order[i]]));
        seen[order[i]] = 1;
    }
    check_run(p, order, 0, (size_t)m, box, key_bits(n));
    free(seen);
}

static void test_order(size_t n)
{
    double *p = points(n);
    const double box[6] = {-1, -1, -1, 3, 3, 3};
    uint32_t *order = malloc((n ? n : 1) * sizeof *order);
    uint8_t *skip = malloc(n ? n : 1);
    CHECK(order && skip);
    check_order(p, n, box, NULL, order, fdt_morton_order(p, n, box, NULL, order));
    for (size_t i = 0; i < n; i++)
        skip[i] = i % 3 == 1;
    check_order(p, n, box, skip, order, fdt_morton_order(p, n, box, skip, order));
    free(skip);
    free(order);
    free(p);
}

static void test_sort(size_t n, int threads)
{
    double *p = points(n), *q = malloc((3 * n + 1) * sizeof *q);
    fdt_vid *orig = malloc((n + 1) * sizeof *orig);
    uint32_t *order = malloc((n + 1) * sizeof *order);
    CHECK(q && orig && order);
    memcpy(q, p, 3 * n * sizeof *p);
    for (size_t i = 0; i < n; i++)
        orig[i] = (fdt_vid)(1000 + i);
    double box[6] = {0, 0, 0, 0, 0, 0};
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) {
            double x = p[3 * i + k];
            box[k] = i == 0 || x < box[k] ? x : box[k];
            box[k + 3] = i == 0 || x > box[k + 3] ? x : box[k + 3];
        }
    CHECK(fdt_morton_order(p, n, box, NULL, order) == (long)n);
    CHECK(fdt_morton_sort(q, orig, n, threads) == 0);
    for (size_t i = 0; i < n; i++) {
        CHECK(orig[i] == (fdt_vid)(1000 + order[i])); /* the order, ties by index */
        CHECK(memcmp(q + 3 * i, p + 3 * (size_t)order[i], 3 * sizeof *q) == 0);
    }
    free(order);
    free(orig);
    free(q);
    free(p);
}

/* Past the split with small buckets: 2^21 points in one corner cell and
 * ten groups of 20 far apart, each group its own bucket (the insertion
 * sort of a bucket of up to 32 points, src/geom/morton.c). */
static void test_small_buckets(void)
{
    size_t big = (size_t)1 << 21, n = big + 200;
    double *p = malloc(3 * n * sizeof *p);
    uint32_t *order = malloc(n * sizeof *order);
    CHECK(p && order);
    for (size_t i = 0; i < 3 * big; i++)
        p[i] = 1e-3 * unif();
    for (size_t g = 0; g < 10; g++)
        for (size_t j = 0; j < 20; j++)
            for (int k = 0; k < 3; k++)
                p[3 * (big + 20 * g + j) + (size_t)k] =
                    0.1 + 0.09 * (double)g + 1e-4 * unif() + (k == 1 ? 0.05 * (double)(g % 3) : 0);
    const double box[6] = {0, 0, 0, 1, 1, 1};
    check_order(p, n, box, NULL, order, fdt_morton_order(p, n, box, NULL, order));
    free(order);
    free(p);
}

static void test_equal_points(void)
{
    double p[3 * 5];
    fdt_vid orig[5];
    for (int i = 0; i < 5; i++) {
        p[3 * i] = 2;
        p[3 * i + 1] = -1;
        p[3 * i + 2] = 0.25;
        orig[i] = (fdt_vid)(4 - i);
    }
    CHECK(fdt_morton_sort(p, orig, 5, 2) == 0);
    for (int i = 0; i < 5; i++)
        CHECK(orig[i] == (fdt_vid)(4 - i)); /* one key: the order as it was */
}

/* Queries are ordered too (src/mesh/locate.c), and may be NaN or
 * infinite: a run of them with one key ends (a level that splits nothing
 * stops), each index once. */
static void test_not_finite(void)
{
    size_t n = 300;
    double *p = malloc(3 * n * sizeof *p);
    uint32_t *order = malloc(n * sizeof *order);
    CHECK(p && order);
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            p[3 * i + (size_t)k] = i % 3 == 0   ? NAN
                                   : i % 3 == 1 ? (k == 1 ? INFINITY : 0.25)
                                                : 0.25 + 1e-12 * unif();
    const double box[6] = {0, 0, 0, 1, 1, 1};
    CHECK(fdt_morton_order(p, n, box, NULL, order) == (long)n);
    uint8_t *seen = calloc(n, 1);
    CHECK(seen != NULL);
    for (size_t i = 0; i < n; i++) {
        CHECK(order[i] < n && !seen[order[i]]);
        seen[order[i]] = 1;
    }
    free(seen);
    free(order);
    free(p);
}

int main(void)
{
    /* 300000: the whole-array passes on 2 and 3 threads; 2^21 + 5: past
     * the sort's split (the top bits first, then each bucket;
     * src/geom/morton.c's msort_radix) */
    const size_t sizes[] = {0, 1, 2, 17, 1000, 50000, 300000, ((size_t)1 << 21) + 5};
    for (size_t i = 0; i < sizeof sizes / sizeof *sizes; i++) {
        test_order(sizes[i]);
        for (int t = 1; t <= 3; t++) /* the same order on any threads */
            test_sort(sizes[i], t);
    }
    test_equal_points();
    test_small_buckets();
    test_not_finite();
    return test_report("morton");
}
