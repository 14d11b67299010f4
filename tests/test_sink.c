/*
 * The tet sink (src/front/sink.c): batches of the configured size in input
 * numbering, the set hash of what was handed on, the stop codes (of the
 * tets and of the hull callback) and that nothing reaches a sink after it
 * stopped, batch sizes below 1 refused, the face links a front keeps,
 * memory and drop modes, calls serialized across threads; and the serial
 * front and the parallel engine streaming through small batches (many
 * calls a run) with the in-memory run's tets, stopped mid-run by the sink
 * or the progress callback in every mode and thread count (2, 3 and 5
 * threads on 2 cores: no hang); settings.permute_input and the memory
 * statistics through the public API.
 */
#include <pthread.h>
#include <stddef.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "frontdt.h"
#include "geom/kdtree.h"
#include "par/parallel.h"
#include "geom/prepare.h"
#include "base/sethash.h"
#include "front/sink.h"
#include "testutil.h"

/* A sink that counts and hashes what it gets, checks that no two calls
 * overlap, and stops on call number stop_at (0: never) with stop_rc. */
typedef struct tally {
    atomic_int inside;
    int overlaps;
    int calls, hcalls, stop_at, stop_rc, after_stop;
    size_t nt, nh, maxbatch;
    fdt_sethash h;
    fdt_vid last[4];
} tally;

static int tally_tets(void *u, const fdt_vid *t, size_t count)
{
    tally *k = u;
    if (atomic_fetch_add(&k->inside, 1) != 0)
        k->overlaps++;
    int rc = 0;
    k->calls++;
    if (k->stop_at && k->calls > k->stop_at)
        k->after_stop++;
    if (k->stop_at && k->calls >= k->stop_at) {
        rc = k->stop_rc;
    } else {
        fdt_sethash_add_n(&k->h, (const uint32_t *)t, count);
        k->nt += count;
        if (count > k->maxbatch)
            k->maxbatch = count;
        memcpy(k->last, t + 4 * (count - 1), sizeof k->last);
    }
    atomic_fetch_sub(&k->inside, 1);
    return rc;
}

static int tally_hull(void *u, const fdt_vid *f, size_t count)
{
    tally *k = u;
    (void)f;
    if (atomic_fetch_add(&k->inside, 1) != 0)
        k->overlaps++;
    k->hcalls++;
    k->nh += count;
    atomic_fetch_sub(&k->inside, 1);
    return 0;
}

/* Hull callbacks that refuse: a stop (any positive value) and an
 * FDT_E* code passed on. */
static int hull_stop(void *u, const fdt_vid *f, size_t count)
{
    (void)u;
    (void)f;
    (void)count;
    return 3;
}

static int hull_enomem(void *u, const fdt_vid *f, size_t count)
{
    (void)u;
    (void)f;
    (void)count;
    return FDT_ENOMEM;
}

static void tally_init(tally *k)
{
    memset(k, 0, sizeof *k);
    atomic_init(&k->inside, 0);
}

/* The emitter alone: batches, renumbering, counts, hash, stop codes. */
static void test_emit(void)
{
    fdt_vid orig[10];
    for (int i = 0; i < 10; i++)
        orig[i] = 100 + 9 - i;
    tally k;
    tally_init(&k);
    fdt_sink us = {sizeof us, tally_tets, tally_hull, &k, NULL, NULL};
    fdt_tsink s;
    CHECK_EQ(fdt_tsink_init(&s, orig, &us), FDT_OK);
    s.batch = 3;
    s.hbatch = 2;
    fdt_emit em;
    CHECK_EQ(fdt_emit_init(&em, &s, NULL), FDT_OK);
    EXPECT(em.packed && em.mb == NULL);
    fdt_sethash want = {0, 0};
    for (uint32_t i = 0; i < 7; i++) {
        uint32_t v[4] = {i, i + 1, i + 2, 9 - i / 2};
        uint32_t r[4];
        for (int j = 0; j < 4; j++)
            r[j] = (uint32_t)orig[v[j]];
        fdt_sethash_add(&want, r);
        EXPECT(fdt_emit_tet(&em, v) == (int64_t)i);
    }
    /* two full batches went on, one tet waits */
    EXPECT(k.calls == 2 && k.nt == 6 && k.maxbatch == 3);
    EXPECT(k.last[0] == 109 - 5 && k.last[3] == 109 - 7);
    for (uint32_t i = 0; i < 3; i++) {
        uint32_t f[3] = {i, 5, 6};
        EXPECT(fdt_emit_hull(&em, f) == FDT_OK);
    }
    EXPECT(k.hcalls == 1 && k.nh == 2);
    CHECK_EQ(fdt_emit_flush(&em), FDT_OK);
    EXPECT(k.calls == 3 && k.nt == 7 && k.hcalls == 2 && k.nh == 3);
    EXPECT(s.ntets == 7 && s.nhull == 3 && em.ntets == 7 && em.nhull == 3);
    EXPECT(fdt_sethash_value(&s.hash) == fdt_sethash_value(&want));
    EXPECT(fdt_sethash_value(&k.h) == fdt_sethash_value(&want));
    /* a second flush hands nothing on and adds nothing */
    CHECK_EQ(fdt_emit_flush(&em), FDT_OK);
    EXPECT(k.calls == 3 && fdt_sethash_value(&s.hash) == fdt_sethash_value(&want));
    fdt_emit_free(&em);
    fdt_tsink_free(&s);

    /* Stops: the code returned, and no call after it, from any emitter. */
    const int rcs[] = {1, 7, FDT_EIO, FDT_ENOMEM, -100};
    const int want_rc[] = {FDT_ECANCELED, FDT_ECANCELED, FDT_EIO, FDT_ENOMEM, FDT_ECANCELED};
    for (int c = 0; c < 5; c++) {
        tally_init(&k);
        k.stop_at = 2;
        k.stop_rc = rcs[c];
        CHECK_EQ(fdt_tsink_init(&s, orig, &us), FDT_OK);
        s.batch = 2;
        fdt_emit a, b;
        CHECK_EQ(fdt_emit_init(&a, &s, NULL), FDT_OK);
        CHECK_EQ(fdt_emit_init(&b, &s, NULL), FDT_OK);
        uint32_t v[4] = {0, 1, 2, 3};
        int64_t got = 0;
        int i = 0;
        for (; i < 10 && got >= 0; i++)
            got = fdt_emit_tet(&a, v);
        EXPECTF(got == want_rc[c] && i == 4, "stop %d: %lld after %d", rcs[c], (long long)got, i);
        EXPECT(fdt_emit_tet(&b, v) == 0);
        EXPECT(fdt_emit_flush(&b) == want_rc[c]);
        EXPECT(k.after_stop == 0 && k.calls == 2 && s.ntets == 2);
        fdt_emit_free(&a);
        fdt_emit_free(&b);
        fdt_tsink_free(&s);
    }

    /* A hull batch refused: its code, from the hull call as from the
     * tets'; a batch size below 1 is refused at the emitter's start;
     * freeing a sink twice is harmless. */
    for (int c = 0; c < 2; c++) {
        tally_init(&k);
        fdt_sink hs = {sizeof hs, tally_tets, c ? hull_enomem : hull_stop, &k, NULL, NULL};
        CHECK_EQ(fdt_tsink_init(&s, orig, &us), FDT_OK);
        s.user = &hs;
        s.hbatch = 2;
        CHECK_EQ(fdt_emit_init(&em, &s, NULL), FDT_OK);
        uint32_t f3[3] = {0, 1, 2};
        EXPECT(fdt_emit_hull(&em, f3) == FDT_OK);
        EXPECT(fdt_emit_hull(&em, f3) == (c ? FDT_ENOMEM : FDT_ECANCELED));
        fdt_emit_free(&em);
        fdt_tsink_free(&s);
        fdt_tsink_free(&s);
    }
    CHECK_EQ(fdt_tsink_init(&s, orig, &us), FDT_OK);
    s.batch = 0;
    EXPECT(fdt_emit_init(&em, &s, NULL) == FDT_EINVAL);
    s.batch = 3;
    s.hbatch = 0;
    EXPECT(fdt_emit_init(&em, &s, NULL) == FDT_EINVAL);
    fdt_tsink_free(&s);

    /* Memory mode keeps tree-order ids; drop mode keeps nothing. */
    fdt_meshbuf mb;
    CHECK_EQ(fdt_meshbuf_init(&mb, 4, 0), FDT_OK);
    CHECK_EQ(fdt_tsink_init(&s, orig, NULL), FDT_OK);
    CHECK_EQ(fdt_emit_init(&em, &s, &mb), FDT_OK);
    uint32_t v[4] = {1, 2, 3, 4}, f[3] = {1, 2, 3};
    EXPECT(fdt_emit_tet(&em, v) == 0 && fdt_emit_tet(&em, v) == 1);
    EXPECT(fdt_emit_hull(&em, f) == FDT_OK);
    EXPECT(mb.ntets == 2 && mb.tets[4] == 1 && mb.tets[7] == 4 && mb.nhull == 1);
    EXPECT(em.packed); /* no neighbours: links carry the opposite vertex */
    CHECK_EQ(fdt_emit_flush(&em), FDT_OK);
    fdt_emit_free(&em);
    CHECK_EQ(fdt_emit_init(&em, &s, NULL), FDT_OK);
    EXPECT(fdt_emit_tet(&em, v) == 0 && fdt_emit_tet(&em, v) == 1 && em.ntets == 2);
    EXPECT(fdt_emit_hull(&em, f) == FDT_OK && em.nhull == 1);
    fdt_emit_free(&em);
    fdt_tsink_free(&s);
    fdt_meshbuf_free(&mb);
}

/* The links a front keeps (fdt_emit_link, fdt_emit_unlink). */
static void test_links(void)
{
    fdt_tsink s;
    CHECK_EQ(fdt_tsink_init(&s, NULL, NULL), FDT_OK);
    fdt_emit em;
    CHECK_EQ(fdt_emit_init(&em, &s, NULL), FDT_OK);
    int64_t tid;
    uint32_t opp;
    const int64_t tids[] = {0, 5, (int64_t)UINT32_MAX - 1};
    for (int i = 0; i < 3; i++) {
        fdt_emit_unlink(&em, fdt_emit_link(&em, tids[i], 2, 0xFFFFFFFEu - (uint32_t)i), &tid,
                        &opp);
        EXPECTF(tid == tids[i] && opp == 0xFFFFFFFEu - (uint32_t)i, "packed %d", i);
    }
    /* an id that does not fit: unknown (the oracle walks), vertex kept */
    fdt_emit_unlink(&em, fdt_emit_link(&em, (int64_t)UINT32_MAX + 3, 1, 77), &tid, &opp);
    EXPECT(tid == -1 && opp == 77);
    fdt_emit_free(&em);
    /* With neighbours: (tid << 2) | face, the vertex read from the tet. */
    fdt_meshbuf mb;
    CHECK_EQ(fdt_meshbuf_init(&mb, 4, 1), FDT_OK);
    CHECK_EQ(fdt_emit_init(&em, &s, &mb), FDT_OK);
    EXPECT(!em.packed);
    uint32_t v[4] = {10, 11, 12, 13};
    EXPECT(fdt_emit_tet(&em, v) == 0 && fdt_emit_tet(&em, v) == 1);
    uint64_t l = fdt_emit_link(&em, 1, 2, 12);
    EXPECT(l == (1u << 2 | 2u));
    fdt_emit_unlink(&em, l, &tid, &opp);
    EXPECT(tid == 1 && opp == 12);
    fdt_emit_free(&em);
    fdt_meshbuf_free(&mb);
    fdt_tsink_free(&s);
}

/* Threads emitting at once: calls never overlap, nothing lost. */
typedef struct emitter_arg {
    fdt_tsink *s;
    uint32_t first;
    int rc;
} emitter_arg;

static void *emit_many(void *p)
{
    emitter_arg *a = p;
    fdt_emit em;
    a->rc = fdt_emit_init(&em, a->s, NULL);
    for (uint32_t i = 0; i < 5000 && !a->rc; i++) {
        uint32_t v[4] = {a->first + i, 1, 2, 3};
        int64_t t = fdt_emit_tet(&em, v);
        if (t < 0)
            a->rc = (int)t;
    }
    if (!a->rc)
        a->rc = fdt_emit_flush(&em);
    fdt_emit_free(&em);
    return NULL;
}

static void test_threads(void)
{
    enum { T = 4 };
    fdt_vid *orig = malloc(sizeof *orig * (T * 5000 + 8));
    CHECK(orig);
    for (size_t i = 0; i < T * 5000 + 8; i++)
        orig[i] = (fdt_vid)i;
    tally k;
    tally_init(&k);
    fdt_sink us = {sizeof us, tally_tets, tally_hull, &k, NULL, NULL};
    fdt_tsink s;
    CHECK_EQ(fdt_tsink_init(&s, orig, &us), FDT_OK);
    s.batch = 37;
    pthread_t th[T];
    emitter_arg a[T];
    for (int i = 0; i < T; i++) {
        a[i].s = &s;
        a[i].first = 4 + 5000u * (uint32_t)i;
        a[i].rc = 0;
        CHECK(pthread_create(&th[i], NULL, emit_many, &a[i]) == 0);
    }
    for (int i = 0; i < T; i++) {
        pthread_join(th[i], NULL);
        EXPECT(a[i].rc == FDT_OK);
    }
    EXPECT(k.overlaps == 0 && k.nt == T * 5000 && s.ntets == T * 5000);
    EXPECT(fdt_sethash_value(&k.h) == fdt_sethash_value(&s.hash));
    fdt_tsink_free(&s);
    free(orig);
}

/* Uniform points in the unit cube. */
static double *uniform(size_t n, uint64_t seed)
{
    double *p = malloc(sizeof *p * 3 * n);
    CHECK(p);
    for (size_t i = 0; i < 3 * n; i++)
        p[i] = test_unif(&seed);
    return p;
}

/* One streamed run through the internal entry points with a small batch:
 * serial (fdt_front_emit) or parallel (fdt_parallel_run with the sink). */
static int stream_run(const double *xyz, size_t n, fdt_mode mode, int threads, tally *k,
                      size_t batch, fdt_progress_fn prog, void *puser)
{
    fdt_prepared pr;
    char diag[256];
    CHECK_EQ(fdt_prepare(xyz, n, 1, &pr, diag, sizeof diag), FDT_OK);
    fdt_sink us = {sizeof us, tally_tets, tally_hull, k, NULL, NULL};
    fdt_tsink s;
    CHECK_EQ(fdt_tsink_init(&s, pr.orig, &us), FDT_OK);
    s.batch = batch;
    s.hbatch = batch;
    fdt_settings st;
    fdt_default_settings(&st);
    st.progress = prog;
    st.progress_user = puser;
    int err;
    if (mode == FDT_MODE_SERIAL) {
        fdt_kdtree t = {0};
        CHECK_EQ(fdt_kd_build(&t, pr.p, pr.orig, 0, (uint32_t)pr.m, st.leaf_size), FDT_OK);
        fdt_emit em;
        CHECK_EQ(fdt_emit_init(&em, &s, NULL), FDT_OK);
        fdt_front_stats fs;
        memset(&fs, 0, sizeof fs);
        err = fdt_front_emit(&t, 0, FDT_SEARCH_KD, &em, prog, puser, &fs);
        if (!err)
            err = fdt_emit_flush(&em);
        fdt_emit_free(&em);
        fdt_kd_free(&t);
    } else {
        fdt_par_opts opt;
        memset(&opt, 0, sizeof opt);
        opt.sink = &s;
        fdt_par_out out;
        err = fdt_parallel_run(&pr, &st, mode, threads, &opt, &out, diag, sizeof diag);
        if (!err) {
            EXPECT(out.mb.tets == NULL && out.mb.ntets == 0);
            fdt_par_out_free(&out);
        }
    }
    EXPECT(s.ntets == k->nt && s.nhull == k->nh);
    fdt_tsink_free(&s);
    fdt_prepared_free(&pr);
    return err;
}

/* Asks to stop at the second report during the run. The report of 1.0
 * that fdt_triangulate_stream makes once the run is done cannot cancel
 * anything, so it is not counted: a run that finished after one report
 * during the run gets it too, and is still a run that was not asked to
 * stop. */
static int stop_progress(void *u, double fr)
{
    if (fr >= 1.0)
        return 0;
    return ++*(int *)u >= 2;
}

static void test_engine(void)
{
    const size_t n = 6000;
    double *p = uniform(n, 5);
    fdt_settings s;
    fdt_default_settings(&s);
    s.mode = FDT_MODE_SERIAL;
    fdt_context *ctx = NULL;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    fdt_result *ref = NULL;
    CHECK_EQ(fdt_triangulate(ctx, p, n, &ref), FDT_OK);
    fdt_close(&ctx);
    uint64_t h0;
    CHECK_EQ(fdt_result_set_hash(ref, &h0), FDT_OK);
    size_t nt = fdt_result_num_tets(ref), nh = fdt_result_num_hull_faces(ref);
    const struct {
        fdt_mode mode;
        int threads;
    } runs[] = {{FDT_MODE_SERIAL, 1}, {FDT_MODE_SHARED, 2},  {FDT_MODE_SHARED, 3},
                {FDT_MODE_SHARED, 5}, {FDT_MODE_MESSAGE, 2}, {FDT_MODE_MESSAGE, 3},
                {FDT_MODE_MESSAGE, 5}};
    for (size_t i = 0; i < sizeof runs / sizeof *runs; i++) {
        /* the whole mesh in batches of 500: about 80 calls */
        tally k;
        tally_init(&k);
        int err = stream_run(p, n, runs[i].mode, runs[i].threads, &k, 500, NULL, NULL);
        EXPECTF(err == FDT_OK && k.nt == nt && k.nh == nh && k.overlaps == 0 &&
                    fdt_sethash_value(&k.h) == h0 && k.maxbatch == 500 && k.calls > 40,
                "mode %d threads %d: err %d, %zu of %zu tets in %d calls", (int)runs[i].mode,
                runs[i].threads, err, k.nt, nt, k.calls);
        /* the sink stops on its 3rd call: the run ends with its code and
         * no call reaches the sink after that */
        const int rcs[] = {1, FDT_EIO};
        for (int c = 0; c < 2; c++) {
            tally_init(&k);
            k.stop_at = 3;
            k.stop_rc = rcs[c];
            err = stream_run(p, n, runs[i].mode, runs[i].threads, &k, 500, NULL, NULL);
            EXPECTF(err == (c ? FDT_EIO : FDT_ECANCELED) && k.after_stop == 0 && k.nt == 1000,
                    "stop: mode %d threads %d: err %d, %zu tets, %d after", (int)runs[i].mode,
                    runs[i].threads, err, k.nt, k.after_stop);
        }
    }
    /* The public entry point with permute_input: the points prepared in
     * the caller's array (left scaled and reordered), the same tets; the
     * memory statistics say where the bytes went, and a caller compiled
     * before them (the first release's fdt_stats) gets the rest. */
    for (size_t i = 0; i < 3; i++) {
        s.mode = runs[i].mode;
        s.n_threads = runs[i].threads;
        s.permute_input = 1;
        CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
        double *own = malloc(sizeof *own * 3 * n);
        CHECK(own);
        memcpy(own, p, sizeof *own * 3 * n);
        tally k;
        tally_init(&k);
        fdt_sink us = {sizeof us, tally_tets, tally_hull, &k, NULL, NULL};
        fdt_result *r = NULL;
        CHECK_EQ(fdt_triangulate_stream(ctx, own, n, &us, &r), FDT_OK);
        uint64_t h;
        fdt_stats st;
        CHECK_EQ(fdt_result_set_hash(r, &h), FDT_OK);
        CHECK_EQ(fdt_result_stats(r, &st), FDT_OK);
        EXPECTF(h == h0 && k.nt == nt && st.tets == nt, "permute_input, mode %d",
                (int)runs[i].mode);
        /* the points (24), their indices (4); no duplicates: no map held
         * during the run */
        EXPECT(st.mem_sink >= (size_t)runs[i].threads * 16 * FDT_SINK_BATCH &&
               st.mem_points == n * 28 && 3 * st.mem_merge >= 16 * n); /* 4/3 n slots */
        /* serial: the parts in sweep order (a part's mesh, no tree, no
         * front); the explicit modes: the parts' fronts, no mesh kept */
        if (runs[i].mode == FDT_MODE_SERIAL)
            EXPECT(st.sweep_parts >= 1 && st.mem_mesh > 100 * n && st.mem_tree == 0 &&
                   st.mem_front == 0);
        else
            EXPECT(st.sweep_parts == 0 && st.mem_mesh == 0 && st.mem_tree > 16 * n &&
                   st.mem_front > 0);
        unsigned char buf[sizeof(fdt_stats) + 16];
        memset(buf, 0xA5, sizeof buf);
        size_t old = offsetof(fdt_stats, mem_points);
        CHECK_EQ(fdt_result_stats_sized(r, (fdt_stats *)buf, old), FDT_OK);
        EXPECT(((fdt_stats *)buf)->struct_size == old && ((fdt_stats *)buf)->tets == nt &&
               buf[old] == 0xA5 && buf[sizeof buf - 1] == 0xA5);
        EXPECT(fdt_result_stats_sized(r, (fdt_stats *)buf, old + 8) == FDT_EINVAL);
        /* 0.2's size (before the insertion's counts): filled to it */
        size_t v2 = offsetof(fdt_stats, ins_conflict_tests);
        memset(buf, 0xA5, sizeof buf);
        CHECK_EQ(fdt_result_stats_sized(r, (fdt_stats *)buf, v2), FDT_OK);
        EXPECT(((fdt_stats *)buf)->struct_size == v2 && ((fdt_stats *)buf)->tets == nt &&
               buf[v2] == 0xA5);
        fdt_result_free(&r);
        /* in memory: the mesh's bytes, no batches */
        s.permute_input = 0;
        fdt_close(&ctx);
        CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
        CHECK_EQ(fdt_triangulate(ctx, p, n, &r), FDT_OK);
        CHECK_EQ(fdt_result_stats(r, &st), FDT_OK);
        EXPECT(st.mem_mesh >= 16 * nt && st.mem_sink == 0 && st.mem_points == n * 28);
        fdt_result_free(&r);
        fdt_close(&ctx);
        free(own);
    }

    /* The progress callback cancels a streamed run too (public API; the
     * parallel engine's calling thread asks every 50 ms, the serial front
     * every 64k tets: 40k points). */
    const size_t n2 = 40000;
    double *q = uniform(n2, 9);
    for (size_t i = 0; i < sizeof runs / sizeof *runs; i++) {
        s.mode = runs[i].mode;
        s.n_threads = runs[i].threads;
        int calls = 0;
        s.progress = stop_progress;
        s.progress_user = &calls;
        CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
        tally k;
        tally_init(&k);
        fdt_sink us = {sizeof us, tally_tets, tally_hull, &k, NULL, NULL};
        fdt_result *r = NULL;
        int err = fdt_triangulate_stream(ctx, q, n2, &us, &r);
        /* a parallel run may finish before its second report */
        EXPECTF(err == FDT_ECANCELED ? r == NULL && calls >= 2 : err == FDT_OK && calls < 2,
                "progress stop: mode %d threads %d: err %d", (int)runs[i].mode, runs[i].threads,
                err);
        if (err == FDT_ECANCELED)
            EXPECT(strcmp(fdt_context_diagnostic(ctx), "") != 0);
        fdt_result_free(&r);
        fdt_close(&ctx);
    }
    free(q);
    fdt_result_free(&ref);
    free(p);
}

int main(void)
{
    test_emit();
    test_links();
    test_threads();
    test_engine();
    return test_report("sink");
}
