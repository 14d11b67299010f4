/*
 * Tests of src/par/mailbox.c: API contract on one thread, then threaded
 * torture tests in the manner of ck's regressions and liburcu's tests:
 *   - many producers, one consumer: order per producer, exact counts per
 *     kind, no loss, no duplication, bounded pools (recycling);
 *   - a token ring among N threads, each with its own mailbox;
 *   - ping-pong pairs and a request/ack star that only ever block in
 *     fdt_mailbox_wait: a lost wakeup hangs them, and a watchdog fails the
 *     test;
 *   - kicks that publish plain data to the woken thread.
 * Thread counts exceed the cores on purpose (oversubscription makes the
 * wakeup races happen). Payloads and per-token state are plain data handed
 * over by messages only, so ThreadSanitizer checks the mailbox's
 * happens-before edges too.
 *
 * Usage: test_mailbox [messages_per_torture_run [ring_hops_per_token
 *                      [pingpong_rounds]]]
 */
#include "par/mailbox.h"

#include <errno.h>
#include <inttypes.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "testutil.h"

/* ---- watchdog: turns a hang (lost wakeup, deadlock) into a failure ---- */

typedef struct watchdog {
    pthread_t th;
    pthread_mutex_t mu;
    pthread_cond_t cv;
    int done;
    int seconds;
    const char *name;
} watchdog;

static void *watchdog_main(void *arg)
{
    watchdog *w = arg;
    struct timespec dl;
    clock_gettime(CLOCK_REALTIME, &dl);
    dl.tv_sec += w->seconds;
    pthread_mutex_lock(&w->mu);
    while (!w->done) {
        int rc = pthread_cond_timedwait(&w->cv, &w->mu, &dl);
        if (rc == ETIMEDOUT && !w->done) {
            fprintf(stderr, "watchdog: %s still running after %d s "
                    "(lost wakeup or deadlock)\n", w->name, w->seconds);
            _Exit(3);
        }
    }
    pthread_mutex_unlock(&w->mu);
    return NULL;
}

static void watchdog_start(watchdog *w, const char *name, int seconds)
{
    w->done = 0;
    w->seconds = seconds;
    w->name = name;
    CHECK(pthread_mutex_init(&w->mu, NULL) == 0);
    CHECK(pthread_cond_init(&w->cv, NULL) == 0);
    CHECK(pthread_create(&w->th, NULL, watchdog_main, w) == 0);
}

static void watchdog_stop(watchdog *w)
{
    pthread_mutex_lock(&w->mu);
    w->done = 1;
    pthread_cond_signal(&w->cv);
    pthread_mutex_unlock(&w->mu);
    pthread_join(w->th, NULL);
    pthread_cond_destroy(&w->cv);
    pthread_mutex_destroy(&w->mu);
}

/* ---- payload patterns: every field of every kind, derived from (a, x) ---- */

_Static_assert(sizeof(fdt_msg_iamdone) == 16, "no padding in iamdone");
_Static_assert(sizeof(fdt_msg_nodesend) == 112, "no padding in nodesend");
_Static_assert(sizeof(fdt_msg_noderecv) == 32, "no padding in noderecv");
_Static_assert(sizeof(fdt_msg_facesend) == 24, "no padding in facesend");
_Static_assert(sizeof(fdt_msg_facerecv) == 16, "no padding in facerecv");
_Static_assert(sizeof(fdt_msg_abort) == 8, "no padding in abort");

static void fill_payload(fdt_msg *m, uint32_t a, uint64_t x)
{
    switch (m->kind) {
    case FDT_MSG_IAMDONE:
        m->u.iamdone.epoch = x ^ ((uint64_t)a << 40);
        m->u.iamdone.count = -(int64_t)(x + a);
        break;
    case FDT_MSG_NODESEND:
        for (int i = 0; i < 3; i++) {
            for (int j = 0; j < 3; j++)
                m->u.nodesend.xyz[i][j] = (double)(x + 3 * i + j) + 0.25 * a;
            m->u.nodesend.best_xyz[i] = -(double)x - i;
            m->u.nodesend.v[i] = a + (uint32_t)i;
        }
        m->u.nodesend.best = (uint32_t)x;
        break;
    case FDT_MSG_NODERECV:
        for (int j = 0; j < 3; j++)
            m->u.noderecv.best_xyz[j] = 0.5 * (double)x + j;
        m->u.noderecv.best = (x & 3) == 0 ? FDT_MSG_NONE : a;
        m->u.noderecv.tested = (uint32_t)(x * 7);
        break;
    case FDT_MSG_FACESEND:
        m->u.facesend.v[0] = a;
        m->u.facesend.v[1] = (uint32_t)x;
        m->u.facesend.v[2] = (uint32_t)(x >> 32) ^ 0xdeadbeefu;
        m->u.facesend.apex = (x & 1) ? FDT_MSG_NONE : (uint32_t)x * 3u;
        m->u.facesend.tet = (int64_t)x * 1000003 + a;
        break;
    case FDT_MSG_FACERECV:
        m->u.facerecv.v[0] = (uint32_t)x;
        m->u.facerecv.v[1] = a;
        m->u.facerecv.v[2] = a ^ (uint32_t)x;
        m->u.facerecv.status = (int32_t)(x % 7) - 3;
        break;
    case FDT_MSG_ABORT:
        m->u.abort.err = -(int32_t)(x % 9);
        m->u.abort.part = (int32_t)a;
        break;
    default:
        CHECK(!"fill_payload: bad kind");
    }
}

/* Compares the active member only: its bytes are all values (no padding,
 * asserted above), unlike the rest of the union after a struct copy. */
static int payload_ok(const fdt_msg *m, uint32_t a, uint64_t x)
{
    fdt_msg ref;
    memset(&ref, 0, sizeof ref);
    ref.kind = m->kind;
    fill_payload(&ref, a, x);
    switch (m->kind) {
    case FDT_MSG_IAMDONE:
        return !memcmp(&ref.u.iamdone, &m->u.iamdone, sizeof ref.u.iamdone);
    case FDT_MSG_NODESEND:
        return !memcmp(&ref.u.nodesend, &m->u.nodesend, sizeof ref.u.nodesend);
    case FDT_MSG_NODERECV:
        return !memcmp(&ref.u.noderecv, &m->u.noderecv, sizeof ref.u.noderecv);
    case FDT_MSG_FACESEND:
        return !memcmp(&ref.u.facesend, &m->u.facesend, sizeof ref.u.facesend);
    case FDT_MSG_FACERECV:
        return !memcmp(&ref.u.facerecv, &m->u.facerecv, sizeof ref.u.facerecv);
    case FDT_MSG_ABORT:
        return !memcmp(&ref.u.abort, &m->u.abort, sizeof ref.u.abort);
    default:
        return 0;
    }
}

/* A kind for (producer, sequence number): a hash, so that runs of every
 * kind and every transition between kinds occur. */
static int kind_of(uint32_t p, uint64_t seq)
{
    uint64_t h = (seq + 1) * 0x9e3779b97f4a7c15ull ^ ((uint64_t)p << 17);
    h ^= h >> 29;
    return 1 + (int)(h % (FDT_MSG_KIND_END - 1));
}

static void post_ok(fdt_mailbox *self, int to, int kind, uint32_t tag,
                    uint32_t a, uint64_t x, int *was_empty)
{
    fdt_msg *m;
    CHECK_EQ(fdt_mailbox_alloc(self, &m), 0);
    m->kind = (uint16_t)kind;
    m->tag = tag;
    fill_payload(m, a, x);
    int rc = fdt_mailbox_post(self, to, m);
    CHECK(rc == 0 || rc == 1);
    if (was_empty)
        *was_empty = rc;
}

/* ---- single-thread contract ---- */

static void test_basic(void)
{
    CHECK(!strcmp(fdt_msg_kind_name(FDT_MSG_IAMDONE), "IAMDONE"));
    CHECK(!strcmp(fdt_msg_kind_name(FDT_MSG_NODESEND), "NODESEND"));
    CHECK(!strcmp(fdt_msg_kind_name(FDT_MSG_NODERECV), "NODERECV"));
    CHECK(!strcmp(fdt_msg_kind_name(FDT_MSG_FACESEND), "FACESEND"));
    CHECK(!strcmp(fdt_msg_kind_name(FDT_MSG_FACERECV), "FACERECV"));
    CHECK(!strcmp(fdt_msg_kind_name(FDT_MSG_ABORT), "ABORT"));
    CHECK(!strcmp(fdt_msg_kind_name(0), "?"));
    CHECK(!strcmp(fdt_msg_kind_name(FDT_MSG_KIND_END), "?"));

    fdt_mailboxes *mbs = (fdt_mailboxes *)&mbs; /* must be reset to NULL */
    CHECK_EQ(fdt_mailboxes_create(&mbs, 0, 0, 0), FDT_EINVAL);
    CHECK(mbs == NULL);
    CHECK_EQ(fdt_mailboxes_create(&mbs, FDT_MAILBOX_MAX_THREADS + 1, 0, 0),
             FDT_EINVAL);
    CHECK_EQ(fdt_mailboxes_create(NULL, 2, 0, 0), FDT_EINVAL);
    CHECK_EQ(fdt_mailboxes_create(&mbs, 2, SIZE_MAX / 64, 0), FDT_EINVAL);
    fdt_mailboxes_destroy(&mbs); /* NULL is fine */
    fdt_mailboxes_destroy(NULL);

    CHECK_EQ(fdt_mailboxes_create(&mbs, 2, 4, 2), 0);
    CHECK_EQ(fdt_mailboxes_count(mbs), 2);
    fdt_mailbox *a = fdt_mailboxes_at(mbs, 0), *b = fdt_mailboxes_at(mbs, 1);
    CHECK(a && b && a != b);
    CHECK(fdt_mailboxes_at(mbs, 2) == NULL && fdt_mailboxes_at(mbs, -1) == NULL);
    CHECK_EQ(fdt_mailbox_id(a), 0);
    CHECK_EQ(fdt_mailbox_id(b), 1);
    CHECK_EQ(fdt_mailbox_chunks(a), 0);
    CHECK(((uintptr_t)a & 63) == 0 && ((uintptr_t)b & 63) == 0);

    /* A new message: kind 0 (refused), our sender id, zero payload. */
    fdt_msg *m;
    CHECK_EQ(fdt_mailbox_alloc(a, &m), 0);
    CHECK(((uintptr_t)m & 63) == 0);
    CHECK_EQ(m->kind, 0);
    CHECK_EQ(m->sender, 0);
    CHECK_EQ(m->u.nodesend.best, 0);
    CHECK_EQ(fdt_mailbox_chunks(a), 1);
    CHECK_EQ(fdt_mailbox_post(a, 1, m), FDT_EINVAL);
    m->kind = FDT_MSG_KIND_END;
    CHECK_EQ(fdt_mailbox_post(a, 1, m), FDT_EINVAL);
    m->kind = FDT_MSG_FACESEND;
    CHECK_EQ(fdt_mailbox_post(a, 2, m), FDT_EINVAL);
    CHECK_EQ(fdt_mailbox_post(a, -1, m), FDT_EINVAL);
    CHECK_EQ(fdt_mailbox_post(b, 0, m), FDT_EINVAL); /* not b's message */
    CHECK_EQ(fdt_mailbox_post(a, 1, NULL), FDT_EINVAL);
    fdt_mailbox_discard(a, m);

    /* Send to self: FIFO, was-empty reports, payloads intact. */
    fdt_msg got;
    CHECK_EQ(fdt_mailbox_poll(a, &got), 0);
    CHECK(!fdt_mailbox_pending(a));
    int we;
    post_ok(a, 0, FDT_MSG_NODESEND, 100, 7, 1000, &we);
    CHECK_EQ(we, 1);
    CHECK(fdt_mailbox_pending(a));
    post_ok(a, 0, FDT_MSG_FACESEND, 101, 7, 1001, &we);
    CHECK_EQ(we, 0);
    post_ok(a, 0, FDT_MSG_IAMDONE, 102, 7, 1002, &we);
    CHECK_EQ(we, 0);
    CHECK_EQ(fdt_mailbox_poll(a, &got), 1);
    CHECK(got.next == NULL);
    CHECK_EQ(got.kind, FDT_MSG_NODESEND);
    CHECK_EQ(got.tag, 100);
    CHECK_EQ(got.sender, 0);
    CHECK(payload_ok(&got, 7, 1000));
    CHECK(!payload_ok(&got, 7, 1001));
    /* A post while the consumer holds a private batch: still FIFO, and the
     * inbox itself was empty. */
    post_ok(a, 0, FDT_MSG_FACERECV, 103, 7, 1003, &we);
    CHECK_EQ(we, 1);
    for (uint32_t t = 101; t <= 103; t++) {
        CHECK_EQ(fdt_mailbox_poll(a, &got), 1);
        CHECK_EQ(got.tag, t);
        CHECK(payload_ok(&got, 7, 1000 + (t - 100)));
    }
    CHECK_EQ(fdt_mailbox_poll(a, &got), 0);

    /* fdt_mailbox_send copies kind, tag and payload. */
    fdt_msg src;
    memset(&src, 0, sizeof src);
    src.kind = FDT_MSG_NODERECV;
    src.tag = 55;
    fill_payload(&src, 3, 12);
    CHECK_EQ(fdt_mailbox_send(a, 1, &src), 1);
    src.kind = 0;
    CHECK_EQ(fdt_mailbox_send(a, 1, &src), FDT_EINVAL);
    src.kind = FDT_MSG_KIND_END;
    CHECK_EQ(fdt_mailbox_send(a, 1, &src), FDT_EINVAL);
    src.kind = FDT_MSG_NODERECV;
    CHECK_EQ(fdt_mailbox_send(a, 2, &src), FDT_EINVAL);
    CHECK_EQ(fdt_mailbox_send(a, -1, &src), FDT_EINVAL);
    CHECK_EQ(fdt_mailbox_send(a, 1, NULL), FDT_EINVAL);
    CHECK_EQ(fdt_mailbox_poll(b, &got), 1);
    CHECK_EQ(got.kind, FDT_MSG_NODERECV);
    CHECK_EQ(got.tag, 55);
    CHECK_EQ(got.sender, 0);
    CHECK(payload_ok(&got, 3, 12));

    /* Pool limit: 2 chunks of 4. Nodes come back once consumed. */
    fdt_msg *held[8];
    int n_held = 0;
    for (;;) {
        int rc = fdt_mailbox_alloc(a, &held[n_held]);
        if (rc != 0) {
            CHECK_EQ(rc, FDT_ENOMEM);
            break;
        }
        n_held++;
        CHECK(n_held <= 8);
    }
    CHECK_EQ(n_held, 8);
    CHECK_EQ(fdt_mailbox_chunks(a), 2);
    fdt_mailbox_discard(a, held[--n_held]);
    CHECK_EQ(fdt_mailbox_alloc(a, &held[n_held++]), 0);
    CHECK_EQ(fdt_mailbox_alloc(a, &m), FDT_ENOMEM);
    for (int i = 0; i < n_held; i++) {
        held[i]->kind = FDT_MSG_FACESEND;
        held[i]->tag = (uint32_t)i;
        fill_payload(held[i], 1, (uint64_t)i);
        CHECK_EQ(fdt_mailbox_post(a, 1, held[i]), i == 0);
    }
    CHECK_EQ(fdt_mailbox_alloc(a, &m), FDT_ENOMEM); /* all in b's inbox */
    for (int i = 0; i < n_held; i++) {
        CHECK_EQ(fdt_mailbox_poll(b, &got), 1);
        CHECK_EQ(got.tag, i);
        CHECK(payload_ok(&got, 1, (uint64_t)i));
    }
    for (int i = 0; i < 8; i++)
        CHECK_EQ(fdt_mailbox_alloc(a, &held[i]), 0);
    CHECK_EQ(fdt_mailbox_chunks(a), 2);
    for (int i = 0; i < 8; i++)
        fdt_mailbox_discard(a, held[i]);

    /* Counts: a sent 4 to itself + 1 + 8 to b; b received 9. */
    fdt_mailbox_counts ca, cb;
    fdt_mailbox_counts_get(a, &ca);
    fdt_mailbox_counts_get(b, &cb);
    CHECK_EQ(ca.sent[0], 0);
    CHECK_EQ(ca.sent[FDT_MSG_NODESEND], 1);
    CHECK_EQ(ca.sent[FDT_MSG_FACESEND], 9);
    CHECK_EQ(ca.sent[FDT_MSG_IAMDONE], 1);
    CHECK_EQ(ca.sent[FDT_MSG_FACERECV], 1);
    CHECK_EQ(ca.sent[FDT_MSG_NODERECV], 1);
    CHECK_EQ(ca.received[FDT_MSG_FACESEND], 1);
    CHECK_EQ(ca.received[FDT_MSG_NODERECV], 0);
    CHECK_EQ(cb.received[FDT_MSG_FACESEND], 8);
    CHECK_EQ(cb.received[FDT_MSG_NODERECV], 1);
    for (int k = 0; k < FDT_MSG_KIND_END; k++)
        CHECK_EQ(cb.sent[k], 0);

    /* Waits: timeout, sticky kick consumed once, messages before kicks. */
    CHECK_EQ(fdt_mailbox_wait(a, 0), FDT_MAILBOX_TIMEOUT);
    double t0 = now_s();
    CHECK_EQ(fdt_mailbox_wait(a, 2000000), FDT_MAILBOX_TIMEOUT);
    CHECK(now_s() - t0 >= 0.0019);
    fdt_mailbox_kick(a);
    fdt_mailbox_kick(a);
    CHECK_EQ(fdt_mailbox_wait(a, -1), FDT_MAILBOX_KICKED);
    CHECK_EQ(fdt_mailbox_wait(a, 0), FDT_MAILBOX_TIMEOUT);
    fdt_mailbox_kick(a);
    post_ok(b, 0, FDT_MSG_IAMDONE, 9, 2, 9, NULL);
    CHECK_EQ(fdt_mailbox_wait(a, -1), FDT_MAILBOX_MESSAGE);
    CHECK_EQ(fdt_mailbox_poll(a, &got), 1);
    CHECK_EQ(got.sender, 1);
    CHECK_EQ(fdt_mailbox_wait(a, 1000000), FDT_MAILBOX_KICKED);
    CHECK_EQ(fdt_mailbox_wait(a, 0), FDT_MAILBOX_TIMEOUT);

    /* Undelivered messages are freed with the set. */
    post_ok(a, 1, FDT_MSG_IAMDONE, 1, 1, 1, NULL);
    fdt_mailboxes_destroy(&mbs);
    CHECK(mbs == NULL);
    printf("basic: ok\n");
}

/* ---- many producers, one consumer ---- */

typedef struct torture {
    fdt_mailboxes *mbs;
    int producers;     /* endpoints 1..producers; 0 consumes */
    uint64_t per_producer;
    int capped;        /* pools limited: producers back off on FDT_ENOMEM */
    atomic_ullong backoffs;
    atomic_ullong was_empty;
} torture;

typedef struct targ {
    torture *t;
    int id;
} targ;

static void *torture_producer(void *arg)
{
    targ *ta = arg;
    torture *t = ta->t;
    fdt_mailbox *self = fdt_mailboxes_at(t->mbs, ta->id);
    unsigned long long backoffs = 0, empties = 0;
    for (uint64_t seq = 0; seq < t->per_producer; seq++) {
        fdt_msg *m;
        int rc;
        while ((rc = fdt_mailbox_alloc(self, &m)) != 0) {
            CHECK_EQ(rc, FDT_ENOMEM);
            CHECK(t->capped);
            backoffs++;
            sched_yield();
        }
        m->kind = (uint16_t)kind_of((uint32_t)ta->id, seq);
        m->tag = (uint32_t)seq;
        fill_payload(m, (uint32_t)ta->id, seq);
        rc = fdt_mailbox_post(self, 0, m);
        CHECK(rc == 0 || rc == 1);
        empties += (unsigned long long)rc;
    }
    atomic_fetch_add(&t->backoffs, backoffs);
    atomic_fetch_add(&t->was_empty, empties);
    return NULL;
}

static void torture_run(int producers, uint64_t total, int capped)
{
    enum { CAP_CHUNK = 64, CAP_CHUNKS = 4 };
    torture t;
    memset(&t, 0, sizeof t);
    t.producers = producers;
    t.per_producer = total / (uint64_t)producers;
    t.capped = capped;
    atomic_init(&t.backoffs, 0);
    atomic_init(&t.was_empty, 0);
    CHECK_EQ(fdt_mailboxes_create(&t.mbs, producers + 1,
                                  capped ? CAP_CHUNK : 0,
                                  capped ? CAP_CHUNKS : 0), 0);
    char name[64];
    snprintf(name, sizeof name, "torture %d producers%s", producers,
             capped ? " capped" : "");
    watchdog wd;
    watchdog_start(&wd, name, 300);

    double t0 = now_s();
    pthread_t th[64];
    targ ta[64];
    CHECK(producers < 64);
    for (int i = 1; i <= producers; i++) {
        ta[i].t = &t;
        ta[i].id = i;
        CHECK(pthread_create(&th[i], NULL, torture_producer, &ta[i]) == 0);
    }

    /* The consumer: this thread. It blocks whenever its inbox is empty. */
    fdt_mailbox *self = fdt_mailboxes_at(t.mbs, 0);
    uint64_t next_seq[64] = {0};
    uint64_t expect[FDT_MSG_KIND_END] = {0};
    uint64_t received = 0, want = t.per_producer * (uint64_t)producers;
    uint64_t waits = 0;
    while (received < want) {
        fdt_msg m;
        if (!fdt_mailbox_poll(self, &m)) {
            int r = fdt_mailbox_wait(self, -1);
            CHECK_EQ(r, FDT_MAILBOX_MESSAGE);
            CHECK(fdt_mailbox_pending(self));
            waits++;
            continue;
        }
        CHECK(m.sender >= 1 && m.sender <= producers);
        /* FIFO per producer, no loss, no duplicate: the exact next. */
        CHECK_EQ(m.tag, (uint32_t)next_seq[m.sender]);
        CHECK_EQ(m.kind, kind_of(m.sender, next_seq[m.sender]));
        CHECK(payload_ok(&m, m.sender, next_seq[m.sender]));
        next_seq[m.sender]++;
        expect[m.kind]++;
        received++;
    }
    for (int i = 1; i <= producers; i++)
        CHECK(pthread_join(th[i], NULL) == 0);
    double dt = now_s() - t0;
    fdt_msg m;
    CHECK_EQ(fdt_mailbox_poll(self, &m), 0); /* nothing extra */
    CHECK_EQ(fdt_mailbox_wait(self, 0), FDT_MAILBOX_TIMEOUT);

    /* Exact counts per kind, recomputed from the sequence numbers. */
    uint64_t want_kind[FDT_MSG_KIND_END] = {0};
    for (int i = 1; i <= producers; i++) {
        CHECK_EQ(next_seq[i], t.per_producer);
        for (uint64_t s = 0; s < t.per_producer; s++)
            want_kind[kind_of((uint32_t)i, s)]++;
    }
    uint64_t sent_sum[FDT_MSG_KIND_END] = {0};
    size_t max_chunks = 0;
    for (int i = 1; i <= producers; i++) {
        fdt_mailbox_counts c;
        fdt_mailbox *p = fdt_mailboxes_at(t.mbs, i);
        fdt_mailbox_counts_get(p, &c);
        for (int k = 0; k < FDT_MSG_KIND_END; k++) {
            sent_sum[k] += c.sent[k];
            CHECK_EQ(c.received[k], 0);
        }
        if (fdt_mailbox_chunks(p) > max_chunks)
            max_chunks = fdt_mailbox_chunks(p);
    }
    fdt_mailbox_counts cc;
    fdt_mailbox_counts_get(self, &cc);
    CHECK_EQ(cc.received[0], 0);
    CHECK_EQ(sent_sum[0], 0);
    for (int k = 1; k < FDT_MSG_KIND_END; k++) {
        CHECK_EQ(want_kind[k], expect[k]);
        CHECK_EQ(cc.received[k], want_kind[k]);
        CHECK_EQ(sent_sum[k], want_kind[k]);
        CHECK(want_kind[k] > 0);
    }
    /* Recycling: with capped pools every producer sent far more messages
     * than its pool holds, yet never went past the cap. */
    if (capped) {
        CHECK(max_chunks <= CAP_CHUNKS);
        CHECK(t.per_producer > 4 * CAP_CHUNK * CAP_CHUNKS);
    }
    CHECK(atomic_load(&t.was_empty) >= 1);
    watchdog_stop(&wd);
    printf("torture: producers=%d capped=%d msgs=%" PRIu64 " time=%.2fs "
           "rate=%.2fM/s consumer_waits=%" PRIu64 " was_empty=%llu "
           "backoffs=%llu max_chunks=%zu: ok\n",
           producers, capped, want, dt, (double)want / dt / 1e6, waits,
           (unsigned long long)atomic_load(&t.was_empty),
           (unsigned long long)atomic_load(&t.backoffs), max_chunks);
    fdt_mailboxes_destroy(&t.mbs);
}

/* ---- token ring ---- */

typedef struct ring {
    fdt_mailboxes *mbs;
    int n;          /* threads */
    int tokens;
    uint64_t hops;  /* per token */
    uint64_t *tok_hops; /* plain: handed from thread to thread by messages */
    atomic_int retired;
    atomic_int done;
} ring;

typedef struct rarg {
    ring *r;
    int id;
} rarg;

static void ring_forward(ring *r, fdt_mailbox *self, int tok)
{
    uint64_t h = r->tok_hops[tok];
    int to = (fdt_mailbox_id(self) + 1) % r->n;
    post_ok(self, to, 1 + (int)(h % 5), (uint32_t)tok, (uint32_t)tok, h, NULL);
}

static void *ring_main(void *arg)
{
    rarg *ra = arg;
    ring *r = ra->r;
    fdt_mailbox *self = fdt_mailboxes_at(r->mbs, ra->id);
    int prev = (ra->id + r->n - 1) % r->n;
    for (int tok = ra->id; tok < r->tokens; tok += r->n)
        ring_forward(r, self, tok);
    for (;;) {
        fdt_msg m;
        if (fdt_mailbox_poll(self, &m)) {
            CHECK_EQ(m.sender, prev);
            int tok = (int)m.tag;
            CHECK(tok >= 0 && tok < r->tokens);
            uint64_t h = r->tok_hops[tok];
            CHECK_EQ(m.kind, 1 + (int)(h % 5));
            CHECK(payload_ok(&m, (uint32_t)tok, h));
            r->tok_hops[tok] = ++h;
            if (h < r->hops) {
                ring_forward(r, self, tok);
            } else if (atomic_fetch_add(&r->retired, 1) + 1 == r->tokens) {
                /* The last token: release everyone. The store to done
                 * happens before each kick (release) that wakes them. */
                atomic_store(&r->done, 1);
                for (int i = 0; i < r->n; i++)
                    fdt_mailbox_kick(fdt_mailboxes_at(r->mbs, i));
            }
            continue;
        }
        if (atomic_load(&r->done))
            break;
        int w = fdt_mailbox_wait(self, -1);
        CHECK(w == FDT_MAILBOX_MESSAGE || w == FDT_MAILBOX_KICKED);
        if (w == FDT_MAILBOX_MESSAGE)
            CHECK(fdt_mailbox_pending(self));
    }
    return NULL;
}

static void ring_run(int n, int tokens, uint64_t hops)
{
    ring r;
    memset(&r, 0, sizeof r);
    r.n = n;
    r.tokens = tokens;
    r.hops = hops;
    r.tok_hops = calloc((size_t)tokens, sizeof *r.tok_hops);
    CHECK(r.tok_hops);
    atomic_init(&r.retired, 0);
    atomic_init(&r.done, 0);
    CHECK_EQ(fdt_mailboxes_create(&r.mbs, n, 16, 0), 0);
    watchdog wd;
    watchdog_start(&wd, "token ring", 300);
    double t0 = now_s();
    pthread_t th[64];
    rarg ra[64];
    CHECK(n <= 64);
    for (int i = 0; i < n; i++) {
        ra[i].r = &r;
        ra[i].id = i;
        CHECK(pthread_create(&th[i], NULL, ring_main, &ra[i]) == 0);
    }
    for (int i = 0; i < n; i++)
        CHECK(pthread_join(th[i], NULL) == 0);
    double dt = now_s() - t0;
    watchdog_stop(&wd);

    /* Token t starts at t % n; hop h goes from (s+h)%n to (s+h+1)%n with
     * kind 1 + h % 5. */
    uint64_t *want_sent = calloc((size_t)n * FDT_MSG_KIND_END, sizeof(uint64_t));
    uint64_t *want_recv = calloc((size_t)n * FDT_MSG_KIND_END, sizeof(uint64_t));
    CHECK(want_sent && want_recv);
    for (int t = 0; t < tokens; t++) {
        CHECK_EQ(r.tok_hops[t], hops);
        for (uint64_t h = 0; h < hops; h++) {
            int from = (int)((t % n + h) % (uint64_t)n);
            int to = (from + 1) % n;
            int k = 1 + (int)(h % 5);
            want_sent[from * FDT_MSG_KIND_END + k]++;
            want_recv[to * FDT_MSG_KIND_END + k]++;
        }
    }
    for (int i = 0; i < n; i++) {
        fdt_mailbox *b = fdt_mailboxes_at(r.mbs, i);
        fdt_msg m;
        CHECK_EQ(fdt_mailbox_poll(b, &m), 0);
        fdt_mailbox_counts c;
        fdt_mailbox_counts_get(b, &c);
        for (int k = 0; k < FDT_MSG_KIND_END; k++) {
            CHECK_EQ(c.sent[k], want_sent[i * FDT_MSG_KIND_END + k]);
            CHECK_EQ(c.received[k], want_recv[i * FDT_MSG_KIND_END + k]);
        }
    }
    printf("ring: threads=%d tokens=%d hops=%" PRIu64 " time=%.2fs: ok\n", n,
           tokens, hops, dt);
    free(want_sent);
    free(want_recv);
    free(r.tok_hops);
    fdt_mailboxes_destroy(&r.mbs);
}

/* ---- lost wakeups: ping-pong pairs and a request/ack star ---- */

typedef struct pp {
    fdt_mailboxes *mbs;
    uint64_t rounds;
    int n;          /* endpoints */
    int star;       /* 0: pairs (2i, 2i+1); 1: endpoint 0 serves all others */
    atomic_ullong timeouts;
} pp;

typedef struct pparg {
    pp *p;
    int id;
} pparg;

/* Blocks (never spins) until a message arrives. Timed waits on odd ids so
 * that the timeout path races with posts too; a timeout just waits again. */
static void recv_blocking(pp *p, fdt_mailbox *self, fdt_msg *m)
{
    while (!fdt_mailbox_poll(self, m)) {
        int w = fdt_mailbox_wait(self, (fdt_mailbox_id(self) & 1) ? 200000 : -1);
        if (w == FDT_MAILBOX_TIMEOUT) {
            atomic_fetch_add(&p->timeouts, 1);
            continue;
        }
        CHECK_EQ(w, FDT_MAILBOX_MESSAGE);
        CHECK(fdt_mailbox_pending(self));
    }
}

static void *pp_main(void *arg)
{
    pparg *pa = arg;
    pp *p = pa->p;
    fdt_mailbox *self = fdt_mailboxes_at(p->mbs, pa->id);
    fdt_msg m;
    if (p->star && pa->id == 0) {
        /* Server: answers every request with an ack of the next kind. */
        uint64_t total = p->rounds * (uint64_t)(p->n - 1);
        for (uint64_t i = 0; i < total; i++) {
            recv_blocking(p, self, &m);
            CHECK(payload_ok(&m, m.sender, m.tag));
            post_ok(self, m.sender, 1 + m.kind % 5, m.tag, 0, m.tag, NULL);
        }
        return NULL;
    }
    int initiator = p->star || (pa->id % 2 == 0);
    int peer = p->star ? 0 : (pa->id ^ 1);
    for (uint64_t i = 0; i < p->rounds; i++) {
        int kind = 1 + (int)(i % 5);
        if (initiator) {
            int we;
            post_ok(self, peer, kind, (uint32_t)i, (uint32_t)pa->id, i, &we);
            if (!p->star)
                CHECK_EQ(we, 1); /* a pair's inbox is always empty here */
            recv_blocking(p, self, &m);
            CHECK_EQ(m.sender, peer);
            CHECK_EQ(m.tag, (uint32_t)i);
            CHECK_EQ(m.kind, 1 + kind % 5);
            CHECK(payload_ok(&m, p->star ? 0 : (uint32_t)peer, i));
        } else {
            recv_blocking(p, self, &m);
            CHECK_EQ(m.sender, peer);
            CHECK_EQ(m.tag, (uint32_t)i);
            CHECK(payload_ok(&m, (uint32_t)peer, i));
            int we;
            post_ok(self, peer, 1 + m.kind % 5, (uint32_t)i,
                    (uint32_t)pa->id, i, &we);
            CHECK_EQ(we, 1);
        }
    }
    return NULL;
}

static void pingpong_run(int n, int star, uint64_t rounds)
{
    pp p;
    memset(&p, 0, sizeof p);
    p.n = n;
    p.star = star;
    p.rounds = rounds;
    atomic_init(&p.timeouts, 0);
    CHECK(star || n % 2 == 0);
    CHECK_EQ(fdt_mailboxes_create(&p.mbs, n, 8, 0), 0);
    watchdog wd;
    watchdog_start(&wd, star ? "request/ack star" : "ping-pong pairs", 300);
    double t0 = now_s();
    pthread_t th[64];
    pparg pa[64];
    CHECK(n <= 64);
    for (int i = 0; i < n; i++) {
        pa[i].p = &p;
        pa[i].id = i;
        CHECK(pthread_create(&th[i], NULL, pp_main, &pa[i]) == 0);
    }
    for (int i = 0; i < n; i++)
        CHECK(pthread_join(th[i], NULL) == 0);
    double dt = now_s() - t0;
    watchdog_stop(&wd);
    uint64_t sent = 0, recv = 0;
    for (int i = 0; i < n; i++) {
        fdt_mailbox *b = fdt_mailboxes_at(p.mbs, i);
        fdt_mailbox_counts c;
        fdt_mailbox_counts_get(b, &c);
        uint64_t s = 0, r = 0;
        for (int k = 1; k < FDT_MSG_KIND_END; k++) {
            s += c.sent[k];
            r += c.received[k];
        }
        uint64_t want = (star && i == 0) ? rounds * (uint64_t)(n - 1) : rounds;
        CHECK_EQ(s, want);
        CHECK_EQ(r, want);
        /* Ping-pong keeps at most one message of each endpoint in flight. */
        CHECK_EQ(fdt_mailbox_chunks(b), 1);
        sent += s;
        recv += r;
    }
    CHECK_EQ(sent, recv);
    printf("%s: threads=%d rounds=%" PRIu64 " messages=%" PRIu64
           " time=%.2fs timed_out_waits=%llu: ok\n",
           star ? "star" : "pingpong", n, rounds, sent, dt,
           (unsigned long long)atomic_load(&p.timeouts));
    fdt_mailboxes_destroy(&p.mbs);
}

/* ---- kicks publish the kicker's plain writes ---- */

typedef struct kk {
    fdt_mailboxes *mbs;
    uint64_t rounds;
    uint64_t value;   /* plain: written by the kicker before each kick */
} kk;

static void *kick_waiter(void *arg)
{
    kk *k = arg;
    fdt_mailbox *self = fdt_mailboxes_at(k->mbs, 1);
    for (uint64_t i = 1; i <= k->rounds; i++) {
        int w = fdt_mailbox_wait(self, -1);
        CHECK_EQ(w, FDT_MAILBOX_KICKED);
        CHECK_EQ(k->value, i);
        post_ok(self, 0, FDT_MSG_IAMDONE, (uint32_t)i, 1, i, NULL);
    }
    return NULL;
}

static void kick_run(uint64_t rounds)
{
    kk k;
    memset(&k, 0, sizeof k);
    k.rounds = rounds;
    CHECK_EQ(fdt_mailboxes_create(&k.mbs, 2, 4, 1), 0);
    watchdog wd;
    watchdog_start(&wd, "kick", 300);
    pthread_t th;
    CHECK(pthread_create(&th, NULL, kick_waiter, &k) == 0);
    fdt_mailbox *self = fdt_mailboxes_at(k.mbs, 0);
    for (uint64_t i = 1; i <= rounds; i++) {
        k.value = i;
        fdt_mailbox_kick(fdt_mailboxes_at(k.mbs, 1));
        fdt_msg m;
        while (!fdt_mailbox_poll(self, &m))
            CHECK_EQ(fdt_mailbox_wait(self, -1), FDT_MAILBOX_MESSAGE);
        CHECK_EQ(m.tag, (uint32_t)i);
        CHECK(payload_ok(&m, 1, i));
    }
    CHECK(pthread_join(th, NULL) == 0);
    watchdog_stop(&wd);
    CHECK_EQ(fdt_mailbox_chunks(fdt_mailboxes_at(k.mbs, 1)), 1);
    printf("kick: rounds=%" PRIu64 ": ok\n", rounds);
    fdt_mailboxes_destroy(&k.mbs);
}

static uint64_t arg_u64(int argc, char **argv, int i, uint64_t dflt)
{
    if (argc <= i)
        return dflt;
    char *end;
    unsigned long long v = strtoull(argv[i], &end, 10);
    if (*end || v == 0) {
        fprintf(stderr, "usage: %s [messages_per_torture_run "
                "[ring_hops_per_token [pingpong_rounds]]]\n", argv[0]);
        exit(2);
    }
    return v;
}

int main(int argc, char **argv)
{
    uint64_t msgs = arg_u64(argc, argv, 1, 1000000);
    uint64_t hops = arg_u64(argc, argv, 2, 20000);
    uint64_t rounds = arg_u64(argc, argv, 3, 20000);
    setvbuf(stdout, NULL, _IOLBF, 0);

    test_basic();
    torture_run(8, msgs, 1);
    torture_run(16, msgs, 1);
    torture_run(8, msgs, 0);
    ring_run(8, 3, hops);
    ring_run(3, 5, hops);
    pingpong_run(16, 0, rounds);
    pingpong_run(9, 1, rounds / 4 + 1);
    kick_run(rounds);
    printf("all mailbox tests passed\n");
    return 0;
}
