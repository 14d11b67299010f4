/*
 * Tests of the transport interface (src/par/transport.c) and of the parallel
 * engine's protocol and termination under adversarial schedules:
 *   - both transports refuse zero endpoints (the shuffle also a delay
 *     outside 0..90) and leave *out NULL;
 *   - the shuffle transport delivers every message once, keeps each
 *     sender's order, reorders across senders (it would test nothing if it
 *     did not), and counts what it hands out;
 *   - the engine (src/par/parallel.c and the modules it is split into) run over
 *     the shuffle transport, a few hundred times (seeds x thread counts
 *     2, 3, 5, 7 x shared and message modes x small hard inputs: uniform,
 *     a cubic lattice, an extruded 2-D grid, clusters, duplicates): the
 *     tets equal serial mode's (set and canonical hash), and every message
 *     kind was received as often as it was sent, in total and per thread.
 * Usage: test_transport [--quick]   (--quick: fewer seeds, for sanitizers)
 * A hang fails the test through alarm().
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "frontdt.h"
#include "par/parallel.h"
#include "geom/prepare.h"
#include "par/transport.h"

#include "testutil.h"

/* ---- the shuffle transport alone ------------------------------------------- */

static void test_shuffle_order(void)
{
    enum { N = 4, PER = 200 };
    fdt_transport *t;
    CHECK_EQ(fdt_transport_shuffle(&t, N, 7, 95), FDT_EINVAL);
    CHECK_EQ(fdt_transport_shuffle(&t, N, 7, -1), FDT_EINVAL);
    /* no endpoints: the mailboxes refuse, and nothing is left */
    t = (fdt_transport *)&t;
    CHECK_EQ(fdt_transport_shuffle(&t, 0, 7, 30), FDT_EINVAL);
    CHECK(t == NULL);
    t = (fdt_transport *)&t;
    CHECK_EQ(fdt_transport_mailbox(&t, 0), FDT_EINVAL);
    CHECK(t == NULL);
    fdt_transport_destroy(NULL);
    CHECK_EQ(fdt_transport_shuffle(&t, N, 7, 30), FDT_OK);
    /* Senders 1..3 post PER messages each to 0, interleaved round-robin;
     * sender s's k-th message has tag k. */
    for (int k = 0; k < PER; k++)
        for (int s = 1; s < N; s++) {
            fdt_msg *m;
            CHECK_EQ(fdt_tp_alloc(t, s, &m), FDT_OK);
            m->kind = FDT_MSG_FACESEND;
            m->tag = (uint32_t)k;
            CHECK(fdt_tp_post(t, s, 0, m) >= 0);
        }
    uint32_t next[N] = {0};
    int got = 0, crossed = 0, last_sender = -1, polls = 0;
    uint32_t last_round = 0;
    while (got < PER * (N - 1)) {
        CHECK(fdt_tp_pending(t, 0));
        CHECK_EQ(fdt_tp_wait(t, 0, 0), FDT_MAILBOX_MESSAGE);
        fdt_msg m;
        CHECK(++polls < 100 * PER * N);
        if (!fdt_tp_poll(t, 0, &m))
            continue; /* held back */
        CHECK(m.sender >= 1 && m.sender < N);
        /* FIFO per sender */
        CHECK_EQ(m.tag, next[m.sender]);
        next[m.sender]++;
        /* posted round by round: a message of an earlier round after a
         * later one is a reordering across senders */
        if (last_sender >= 0 && m.tag < last_round)
            crossed++;
        last_round = m.tag;
        last_sender = m.sender;
        got++;
    }
    CHECK(crossed > 0);
    CHECK(polls > got); /* some polls held everything back */
    fdt_msg m;
    CHECK_EQ(fdt_tp_poll(t, 0, &m), 0);
    CHECK(!fdt_tp_pending(t, 0));
    fdt_mailbox_counts c0, c1;
    fdt_tp_counts(t, 0, &c0);
    fdt_tp_counts(t, 1, &c1);
    CHECK_EQ(c0.received[FDT_MSG_FACESEND], PER * (N - 1));
    CHECK_EQ(c1.sent[FDT_MSG_FACESEND], PER);
    /* a kick still ends a wait on an empty endpoint */
    fdt_tp_kick(t, 0);
    CHECK_EQ(fdt_tp_wait(t, 0, -1), FDT_MAILBOX_KICKED);
    fdt_transport_destroy(&t);
    CHECK(t == NULL);
    fdt_transport_destroy(&t);
    printf("shuffle order: ok (%d cross-sender reorderings, %d polls for %d messages)\n",
           crossed, polls, got);
}

/* ---- the engine over the shuffle transport ---------------------------------- */

typedef struct input {
    const char *name;
    double *xyz;
    size_t n;
} input;

static input make_input(const char *name, uint64_t seed)
{
    input in = {name, NULL, 0};
    uint64_t r = seed;
    size_t cap = 512;
    in.xyz = malloc(3 * cap * sizeof *in.xyz);
    CHECK(in.xyz);
    double *x = in.xyz;
    size_t n = 0;
    if (!strcmp(name, "uniform")) {
        for (; n < 300; n++)
            for (int k = 0; k < 3; k++)
                x[3 * n + k] = test_unif(&r);
    } else if (!strcmp(name, "lattice")) {
        /* 5^3 points: every cube's eight corners are cospherical */
        for (int i = 0; i < 5; i++)
            for (int j = 0; j < 5; j++)
                for (int k = 0; k < 5; k++, n++) {
                    x[3 * n] = i;
                    x[3 * n + 1] = j;
                    x[3 * n + 2] = k;
                }
    } else if (!strcmp(name, "extruded")) {
        /* a 2-D grid of 8 x 8 copied on 4 levels */
        for (int l = 0; l < 4; l++)
            for (int i = 0; i < 8; i++)
                for (int j = 0; j < 8; j++, n++) {
                    x[3 * n] = 0.5 * i;
                    x[3 * n + 1] = 0.5 * j;
                    x[3 * n + 2] = 1.5 * l;
                }
    } else if (!strcmp(name, "clusters")) {
        for (int c = 0; c < 4; c++) {
            double cx = test_unif(&r) * 100, cy = test_unif(&r) * 100, cz = test_unif(&r) * 100;
            for (int i = 0; i < 60; i++, n++) {
                x[3 * n] = cx + test_unif(&r);
                x[3 * n + 1] = cy + test_unif(&r);
                x[3 * n + 2] = cz + test_unif(&r);
            }
        }
    } else { /* duplicates: 150 points, then 50 copies of some of them */
        for (; n < 150; n++)
            for (int k = 0; k < 3; k++)
                x[3 * n + k] = test_unif(&r);
        for (int i = 0; i < 50; i++, n++)
            memcpy(x + 3 * n, x + 3 * (test_rand64(&r) % 150), 3 * sizeof *x);
    }
    CHECK(n <= cap);
    in.n = n;
    return in;
}

static int cmp_tet(const void *a, const void *b)
{
    const fdt_vid *x = a, *y = b;
    for (int i = 0; i < 4; i++)
        if (x[i] != y[i])
            return x[i] < y[i] ? -1 : 1;
    return 0;
}

/* The tets with each one's ids ascending, sorted: the canonical set. */
static fdt_vid *canon(const void *tets, size_t nt, int u32)
{
    fdt_vid *c = malloc((nt ? nt : 1) * 4 * sizeof *c);
    CHECK(c);
    for (size_t t = 0; t < nt; t++) {
        fdt_vid v[4];
        for (int i = 0; i < 4; i++)
            v[i] = u32 ? (fdt_vid)((const uint32_t *)tets)[4 * t + i]
                       : ((const fdt_vid *)tets)[4 * t + i];
        for (int i = 1; i < 4; i++)
            for (int j = i; j > 0 && v[j - 1] > v[j]; j--) {
                fdt_vid s = v[j];
                v[j] = v[j - 1];
                v[j - 1] = s;
            }
        memcpy(c + 4 * t, v, sizeof v);
    }
    qsort(c, nt, 4 * sizeof *c, cmp_tet);
    return c;
}

/* FNV-1a 64 of the canonical text, as fdt_result_hash defines it. */
static uint64_t canon_hash(const fdt_vid *c, size_t nt)
{
    uint64_t h = 14695981039346656037ull;
    char line[64];
    for (size_t t = 0; t < nt; t++) {
        int len = snprintf(line, sizeof line, "%d %d %d %d\n", (int)c[4 * t], (int)c[4 * t + 1],
                           (int)c[4 * t + 2], (int)c[4 * t + 3]);
        for (int i = 0; i < len; i++) {
            h ^= (unsigned char)line[i];
            h *= 1099511628211ull;
        }
    }
    return h;
}

static int runs;

static void run_shuffled(const input *in, const fdt_vid *ref, size_t nref, uint64_t refhash,
                         fdt_mode mode, int nthreads, uint64_t seed)
{
    fdt_prepared pr;
    char diag[256];
    CHECK_EQ(fdt_prepare(in->xyz, in->n, 1, &pr, diag, sizeof diag), FDT_OK);
    fdt_settings s;
    fdt_default_settings(&s);
    /* odd seeds: shared mode builds the global mesh first, message mode
     * parks faces that wait for answers (the MPI ranks' loop) */
    fdt_par_opts opt = {1, seed, (int)(seed % 4) * 20, 0, 0, 0, (int)(seed % 2), NULL,
                         (int)(seed % 2)};
    fdt_par_out out;
    int err = fdt_parallel_run(&pr, &s, mode, nthreads, &opt, &out, diag, sizeof diag);
    if (err) {
        fprintf(stderr, "%s N=%d mode %d seed %llu: %d %s\n", in->name, nthreads, (int)mode,
                (unsigned long long)seed, err, diag);
        CHECK_EQ(err, FDT_OK);
    }
    CHECK_EQ(out.mb.ntets, nref);
    fdt_vid *c = canon(out.mb.tets, out.mb.ntets, 1);
    CHECK(memcmp(c, ref, nref * 4 * sizeof *c) == 0);
    CHECK_EQ(canon_hash(c, nref), refhash);
    free(c);
    size_t sent[FDT_MSG_KIND_END] = {0}, recv[FDT_MSG_KIND_END] = {0};
    for (int i = 0; i < out.nthreads; i++)
        for (int k = 0; k < FDT_MSG_KIND_END; k++) {
            sent[k] += out.tstats[i].sent[k];
            recv[k] += out.tstats[i].received[k];
        }
    for (int k = 0; k < FDT_MSG_KIND_END; k++) {
        CHECK_EQ(sent[k], recv[k]);
        CHECK_EQ(out.pst.sent[k], sent[k]);
        CHECK_EQ(out.pst.received[k], recv[k]);
    }
    CHECK_EQ(sent[FDT_MSG_ABORT], 0);
    if (mode == FDT_MODE_SHARED) {
        CHECK_EQ(sent[FDT_MSG_NODESEND], 0);
        CHECK_EQ(sent[FDT_MSG_FACERECV], 0);
    } else {
        /* FACERECV acknowledges every FACESEND (src/par/termination.c) */
        CHECK_EQ(sent[FDT_MSG_FACERECV], sent[FDT_MSG_FACESEND]);
        /* the final IAMDONE reached every other part */
        for (int i = 1; i < out.nthreads; i++)
            CHECK_EQ(out.tstats[i].received[FDT_MSG_IAMDONE], 1);
    }
    fdt_par_out_free(&out);
    fdt_prepared_free(&pr);
    runs++;
}

/* A part that fails (injected) ends every part with its error: no hang
 * (alarm), no mesh, the failing part named. */
static void run_failing(const input *in, fdt_mode mode, int nthreads, uint64_t seed)
{
    fdt_prepared pr;
    char diag[256] = "";
    CHECK_EQ(fdt_prepare(in->xyz, in->n, 1, &pr, diag, sizeof diag), FDT_OK);
    fdt_settings s;
    fdt_default_settings(&s);
    int part = (int)(seed % (uint64_t)nthreads);
    fdt_par_opts opt = {1, seed, (int)(seed % 4) * 20, 1, part, 1 + (size_t)(seed % 7), 0, NULL,
                        (int)(seed % 2)};
    fdt_par_out out;
    int err = fdt_parallel_run(&pr, &s, mode, nthreads, &opt, &out, diag, sizeof diag);
    CHECK_EQ(err, FDT_EINTERNAL);
    char want[64];
    snprintf(want, sizeof want, "worker thread %d:", part);
    if (!strstr(diag, want))
        fprintf(stderr, "diag: %s (want %s)\n", diag, want);
    CHECK(strstr(diag, want) != NULL);
    CHECK(out.mb.tets == NULL && out.tstats == NULL);
    fdt_prepared_free(&pr);
    runs++;
}

int main(int argc, char **argv)
{
    int quick = argc > 1 && !strcmp(argv[1], "--quick");
    alarm(quick ? 1200 : 600);
    test_shuffle_order();
    static const char *const names[] = {"uniform", "lattice", "extruded", "clusters",
                                        "duplicates"};
    static const int threads[] = {2, 3, 5, 7};
    int nseeds = quick ? 4 : 10;
    double t0 = now_s();
    for (size_t f = 0; f < sizeof names / sizeof *names; f++) {
        input in = make_input(names[f], 1000 + f);
        /* the reference: serial mode through the public API */
        fdt_settings s;
        fdt_default_settings(&s);
        s.mode = FDT_MODE_SERIAL;
        fdt_context *ctx;
        fdt_result *r;
        CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
        CHECK_EQ(fdt_triangulate(ctx, in.xyz, in.n, &r), FDT_OK);
        uint64_t refhash;
        CHECK_EQ(fdt_result_hash(r, &refhash), FDT_OK);
        size_t nref = fdt_result_num_tets(r);
        fdt_vid *ref = canon(fdt_result_tets(r), nref, 0);
        CHECK_EQ(canon_hash(ref, nref), refhash);
        for (size_t ti = 0; ti < sizeof threads / sizeof *threads; ti++)
            for (int m = 0; m < 2; m++)
                for (int sd = 0; sd < nseeds; sd++)
                    run_shuffled(&in, ref, nref, refhash,
                                 m ? FDT_MODE_MESSAGE : FDT_MODE_SHARED, threads[ti],
                                 (uint64_t)(f * 1000 + ti * 100 + (size_t)m * 10 + (size_t)sd));
        printf("%-10s %zu points, %zu tets: hash %016llx in every shuffled run\n", names[f],
               in.n, nref, (unsigned long long)refhash);
        free(ref);
        fdt_result_free(&r);
        fdt_close(&ctx);
        free(in.xyz);
    }
    printf("engine over the shuffle transport: %d runs ok in %.1f s\n", runs, now_s() - t0);
    /* failures: ABORT in message mode, the flag in shared mode */
    runs = 0;
    input in = make_input("uniform", 77);
    for (size_t ti = 0; ti < sizeof threads / sizeof *threads; ti++)
        for (int m = 0; m < 2; m++)
            for (int sd = 0; sd < nseeds; sd++)
                run_failing(&in, m ? FDT_MODE_MESSAGE : FDT_MODE_SHARED, threads[ti],
                            (uint64_t)(ti * 100 + (size_t)m * 10 + (size_t)sd));
    free(in.xyz);
    printf("an injected failure of one part ends every part: %d runs ok\n", runs);
    return 0;
}
