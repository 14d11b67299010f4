/*
 * The set hash (src/base/sethash.h, fdt_result_set_hash) and the streamed run
 * (fdt_triangulate_stream): the mix's values against an independent
 * implementation of the rule (Python, values pinned below: a change of
 * the rule breaks every hash users and ranks compare), its independence
 * of id order within a tet, of tet order and of the split into partial
 * sums; and on real runs, the same set hash for every mode, thread count
 * and input order, and a streamed run that hands over exactly the
 * in-memory run's tets and hull faces, stops when the sink says so, and
 * refuses what it cannot do.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "frontdt.h"
#include "base/sethash.h"
#include "testutil.h"

static uint64_t value_of(const uint32_t *tets, size_t n)
{
    fdt_sethash h = {0, 0};
    for (size_t i = 0; i < n; i++)
        fdt_sethash_add(&h, tets + 4 * i);
    return fdt_sethash_value(&h);
}

static void test_rule(void)
{
    /* Computed by a separate Python implementation of the rule in
     * src/base/sethash.h (sorted ids, two pairs mixed with SplitMix64's
     * finaliser, sum, count folded in). */
    const uint32_t one[4] = {0, 1, 2, 3};
    const uint32_t two[8] = {3, 1, 2, 0, 4, 1, 2, 3};
    const uint32_t big[4] = {4000000000u, 7, 1, 2};
    EXPECT(value_of(NULL, 0) == 0x4e96155e5f0a1c3full);
    EXPECT(value_of(one, 1) == 0xcce382b0cb4a037cull);
    EXPECT(value_of(two, 2) == 0xdb9483a6320d9fb3ull);
    EXPECT(value_of(big, 1) == 0xa8d43a894f258f51ull);

    /* Every order of a tet's ids (all 24) mixes alike. */
    uint32_t t[4] = {11, 5, 900, 42};
    uint64_t ref = fdt_sethash_tet(t);
    int perm[4] = {0, 1, 2, 3}, count = 0;
    for (int a = 0; a < 4; a++)
        for (int b = 0; b < 4; b++)
            for (int c = 0; c < 4; c++)
                for (int d = 0; d < 4; d++) {
                    if (a == b || a == c || a == d || b == c || b == d || c == d)
                        continue;
                    perm[0] = a, perm[1] = b, perm[2] = c, perm[3] = d;
                    uint32_t p[4];
                    for (int k = 0; k < 4; k++)
                        p[k] = t[perm[k]];
                    EXPECT(fdt_sethash_tet(p) == ref);
                    count++;
                }
    EXPECT(count == 24);

    /* Sets differing in one id, or in the pairing of ids, hash apart; a
     * set and the same set with one tet twice too. */
    const uint32_t s1[8] = {0, 1, 2, 3, 4, 5, 6, 7};
    const uint32_t s2[8] = {0, 1, 4, 5, 2, 3, 6, 7};
    const uint32_t s3[8] = {0, 1, 2, 3, 4, 5, 6, 8};
    const uint32_t s4[12] = {0, 1, 2, 3, 4, 5, 6, 7, 4, 5, 6, 7};
    EXPECT(value_of(s1, 2) != value_of(s2, 2));
    EXPECT(value_of(s1, 2) != value_of(s3, 2));
    EXPECT(value_of(s1, 2) != value_of(s4, 3));

    /* Partial sums of a split add up to the whole, in any order. */
    enum { N = 1000 };
    uint32_t *ts = malloc(sizeof *ts * 4 * N);
    CHECK(ts);
    uint64_t seed = 7;
    for (size_t i = 0; i < 4 * N; i++)
        ts[i] = (uint32_t)(test_rand64(&seed) % 100000);
    fdt_sethash whole = {0, 0}, a = {0, 0}, b = {0, 0}, c = {0, 0};
    fdt_sethash_add_n(&whole, ts, N);
    fdt_sethash_add_n(&a, ts + 4 * 700, N - 700);
    fdt_sethash_add_n(&b, ts, 300);
    fdt_sethash_add_n(&c, ts + 4 * 300, 400);
    fdt_sethash_merge(&a, &b);
    fdt_sethash_merge(&a, &c);
    EXPECT(a.count == N && fdt_sethash_value(&a) == fdt_sethash_value(&whole));
    EXPECT(value_of(ts, N) == fdt_sethash_value(&whole));
    free(ts);
}

/* Points on a 6x6x6 lattice, jittered in one run of four in z only by a
 * multiple of 1/64 (cospherical and coplanar ties for the perturbation),
 * plus uniform points: a mesh whose tets depend on the tie rule. */
static double *cloud(size_t *n)
{
    size_t m = 216 + 400;
    double *p = malloc(sizeof *p * 3 * m);
    CHECK(p);
    size_t k = 0;
    uint64_t seed = 11;
    for (int i = 0; i < 6; i++)
        for (int j = 0; j < 6; j++)
            for (int l = 0; l < 6; l++) {
                p[3 * k] = i;
                p[3 * k + 1] = j;
                p[3 * k + 2] = l + ((i + j + l) % 4 == 0 ? 1.0 / 64 : 0);
                k++;
            }
    while (k < m) {
        for (int c = 0; c < 3; c++)
            p[3 * k + c] = 5.0 * test_unif(&seed);
        k++;
    }
    *n = m;
    return p;
}

static fdt_result *run(const double *p, size_t n, fdt_mode mode, int threads)
{
    fdt_settings s;
    fdt_default_settings(&s);
    s.mode = mode;
    s.n_threads = threads;
    fdt_context *ctx = NULL;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    fdt_result *r = NULL;
    CHECK_EQ(fdt_triangulate(ctx, p, n, &r), FDT_OK);
    fdt_close(&ctx);
    return r;
}

static void test_modes(void)
{
    size_t n;
    double *p = cloud(&n);
    fdt_result *ref = run(p, n, FDT_MODE_SERIAL, 1);
    uint64_t h0, h, c0, c;
    CHECK_EQ(fdt_result_set_hash(ref, &h0), FDT_OK);
    EXPECT(fdt_result_set_hash(NULL, &h) == FDT_EINVAL && fdt_result_set_hash(ref, NULL) == FDT_EINVAL);
    EXPECT(h0 == value_of((const uint32_t *)fdt_result_tets(ref), fdt_result_num_tets(ref)));
    CHECK_EQ(fdt_result_hash(ref, &c0), FDT_OK);
    /* the sort fdt_result_hash made does not change the set */
    CHECK_EQ(fdt_result_set_hash(ref, &h), FDT_OK);
    EXPECT(h == h0);
    const struct {
        fdt_mode mode;
        int threads;
    } runs[] = {{FDT_MODE_SHARED, 2}, {FDT_MODE_SHARED, 3}, {FDT_MODE_MESSAGE, 2}, {FDT_MODE_MESSAGE, 5}};
    for (size_t i = 0; i < sizeof runs / sizeof *runs; i++) {
        fdt_result *r = run(p, n, runs[i].mode, runs[i].threads);
        CHECK_EQ(fdt_result_set_hash(r, &h), FDT_OK);
        CHECK_EQ(fdt_result_hash(r, &c), FDT_OK);
        EXPECTF(h == h0 && c == c0, "mode %d threads %d", (int)runs[i].mode, runs[i].threads);
        fdt_result_free(&r);
    }
    /* The input reversed: other ids, so the set hash of the renumbered
     * tets must equal the reference's. */
    double *q = malloc(sizeof *q * 3 * n);
    CHECK(q);
    for (size_t i = 0; i < n; i++)
        memcpy(q + 3 * i, p + 3 * (n - 1 - i), 3 * sizeof *q);
    fdt_result *r = run(q, n, FDT_MODE_SERIAL, 1);
    size_t nt = fdt_result_num_tets(r);
    fdt_vid *back = malloc(sizeof *back * 4 * nt);
    CHECK(back);
    for (size_t i = 0; i < 4 * nt; i++)
        back[i] = (fdt_vid)(n - 1 - (size_t)fdt_result_tets(r)[i]);
    EXPECT(value_of((const uint32_t *)back, nt) == h0);
    CHECK_EQ(fdt_result_set_hash(r, &h), FDT_OK);
    EXPECT(h != h0); /* the ids differ, so the set does */
    free(back);
    fdt_result_free(&r);
    fdt_result_free(&ref);
    free(q);
    free(p);
}

/* A sink that keeps what it is given, and stops after `stop_after` calls
 * (0: never) with `stop_rc`. */
typedef struct keep {
    fdt_vid *tets, *hull;
    size_t nt, nh, tcap, hcap;
    int calls, stop_after, stop_rc;
} keep;

static int grow_put(fdt_vid **v, size_t *n, size_t *cap, const fdt_vid *src, size_t count, size_t w)
{
    if (*n + count > *cap) {
        size_t nc = 2 * (*n + count);
        fdt_vid *nv = realloc(*v, sizeof *nv * w * nc);
        if (!nv)
            return -1;
        *v = nv;
        *cap = nc;
    }
    memcpy(*v + w * *n, src, sizeof *src * w * count);
    *n += count;
    return 0;
}

static int keep_tets(void *u, const fdt_vid *t, size_t count)
{
    keep *k = u;
    if (k->stop_after && ++k->calls >= k->stop_after)
        return k->stop_rc;
    return grow_put(&k->tets, &k->nt, &k->tcap, t, count, 4);
}

static int keep_hull(void *u, const fdt_vid *f, size_t count)
{
    keep *k = u;
    return grow_put(&k->hull, &k->nh, &k->hcap, f, count, 3);
}

static int cmp_rec(const void *a, const void *b, size_t w)
{
    return memcmp(a, b, w * sizeof(fdt_vid));
}
static int cmp4(const void *a, const void *b) { return cmp_rec(a, b, 4); }
static int cmp3(const void *a, const void *b) { return cmp_rec(a, b, 3); }

/* One form per tet and per hull face, whatever rotation a mode wrote:
 * a tet's ids sorted (its orientation follows from the points), a face
 * rotated to its smallest id (keeping its orientation); then the records
 * sorted. */
static void canon(fdt_vid *t, size_t nt, fdt_vid *f, size_t nf)
{
    for (size_t i = 0; i < nt; i++) {
        fdt_vid *v = t + 4 * i;
        for (int a = 1; a < 4; a++)
            for (int b = a; b > 0 && v[b - 1] > v[b]; b--) {
                fdt_vid x = v[b];
                v[b] = v[b - 1];
                v[b - 1] = x;
            }
    }
    for (size_t i = 0; i < nf; i++) {
        fdt_vid *v = f + 3 * i;
        while (v[0] > v[1] || v[0] > v[2]) {
            fdt_vid x = v[0];
            v[0] = v[1];
            v[1] = v[2];
            v[2] = x;
        }
    }
    qsort(t, nt, 4 * sizeof *t, cmp4);
    qsort(f, nf, 3 * sizeof *f, cmp3);
}

static void test_stream(void)
{
    size_t n;
    double *p = cloud(&n);
    fdt_result *ref = run(p, n, FDT_MODE_SERIAL, 1);
    uint64_t h0;
    CHECK_EQ(fdt_result_set_hash(ref, &h0), FDT_OK);
    size_t nt = fdt_result_num_tets(ref), nh = fdt_result_num_hull_faces(ref);
    fdt_vid *rt = malloc(sizeof *rt * 4 * nt), *rh = malloc(sizeof *rh * 3 * nh);
    CHECK(rt && rh);
    memcpy(rt, fdt_result_tets(ref), sizeof *rt * 4 * nt);
    memcpy(rh, fdt_result_hull_faces(ref), sizeof *rh * 3 * nh);
    canon(rt, nt, rh, nh);

    const struct {
        fdt_mode mode;
        int threads;
    } runs[] = {{FDT_MODE_SERIAL, 1}, {FDT_MODE_SHARED, 2}, {FDT_MODE_MESSAGE, 3}};
    for (size_t i = 0; i < sizeof runs / sizeof *runs; i++) {
        fdt_settings s;
        fdt_default_settings(&s);
        s.mode = runs[i].mode;
        s.n_threads = runs[i].threads;
        fdt_context *ctx = NULL;
        CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
        keep k;
        memset(&k, 0, sizeof k);
        fdt_sink sink = {sizeof sink, keep_tets, keep_hull, &k, NULL, NULL};
        fdt_result *r = NULL;
        CHECK_EQ(fdt_triangulate_stream(ctx, p, n, &sink, &r), FDT_OK);
        EXPECT(fdt_result_num_tets(r) == 0 && fdt_result_num_hull_faces(r) == 0);
        fdt_stats st;
        CHECK_EQ(fdt_result_stats(r, &st), FDT_OK);
        EXPECT(st.tets == nt && st.hull_faces == nh && st.points == n);
        uint64_t h;
        CHECK_EQ(fdt_result_set_hash(r, &h), FDT_OK);
        EXPECTF(h == h0, "streamed set hash, mode %d", (int)runs[i].mode);
        EXPECT(k.nt == nt && k.nh == nh);
        if (k.nt == nt && k.nh == nh) {
            canon(k.tets, nt, k.hull, nh);
            EXPECT(memcmp(k.tets, rt, sizeof *rt * 4 * nt) == 0);
            EXPECT(memcmp(k.hull, rh, sizeof *rh * 3 * nh) == 0);
        }
        free(k.tets);
        free(k.hull);
        fdt_result_free(&r);
        fdt_close(&ctx);
    }

    /* A sink that stops: FDT_ECANCELED, or its own FDT_E* code; no result. */
    fdt_settings s;
    fdt_default_settings(&s);
    s.mode = FDT_MODE_SERIAL;
    fdt_context *ctx = NULL;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    const int rcs[] = {1, FDT_EIO};
    const int want[] = {FDT_ECANCELED, FDT_EIO};
    for (int i = 0; i < 2; i++) {
        keep k;
        memset(&k, 0, sizeof k);
        k.stop_after = 1;
        k.stop_rc = rcs[i];
        fdt_sink sink = {sizeof sink, keep_tets, NULL, &k, NULL, NULL};
        fdt_result *r = (fdt_result *)&k;
        EXPECTF(fdt_triangulate_stream(ctx, p, n, &sink, &r) == want[i], "stop %d", rcs[i]);
        EXPECT(r == NULL);
        free(k.tets);
    }
    /* Refused: no sink, no tets callback, a sink of unknown size,
     * neighbours (a stream has none). */
    fdt_result *r = NULL;
    keep k;
    memset(&k, 0, sizeof k);
    fdt_sink bad = {sizeof bad, NULL, NULL, &k, NULL, NULL};
    EXPECT(fdt_triangulate_stream(ctx, p, n, NULL, &r) == FDT_EINVAL);
    EXPECT(fdt_triangulate_stream(ctx, p, n, &bad, &r) == FDT_EINVAL);
    bad.tets = keep_tets;
    bad.struct_size = 1;
    EXPECT(fdt_triangulate_stream(ctx, p, n, &bad, &r) == FDT_EINVAL);
    fdt_close(&ctx);
    s.neighbors = 1;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    bad.struct_size = sizeof bad;
    EXPECT(fdt_triangulate_stream(ctx, p, n, &bad, &r) == FDT_EINVAL && r == NULL);
    EXPECT(k.nt == 0);
    fdt_close(&ctx);
    free(k.tets);

    free(rt);
    free(rh);
    fdt_result_free(&ref);
    free(p);
}

int main(void)
{
    test_rule();
    test_modes();
    test_stream();
    return test_report("sethash");
}
