/*
 * Mailboxes: lock-free MPSC inboxes with per-sender message pools. The
 * design, and which calls may run concurrently, are at the top of
 * src/par/mailbox.h; this file holds the memory-ordering arguments.
 *
 * Shared atomics, per endpoint (all other fields are owner-private):
 *   inbox     Treiber stack of posted messages: pushed (CAS) by any thread,
 *             emptied (exchange) by the owner.
 *   returned  Treiber stack of consumed messages going back to this
 *             endpoint's pool: pushed (CAS) by any consumer, emptied
 *             (exchange) by the owner.
 *   sleeping  1 while the owner is inside the slow path of
 *             fdt_mailbox_wait; written by the owner, read by posters and
 *             kickers to decide whether to signal.
 *   kicked    set by fdt_mailbox_kick, consumed by fdt_mailbox_wait.
 * Every modification of inbox and returned after initialization is a
 * read-modify-write, so a release push heads a release sequence that runs up
 * to the owner's exchange: one acquire exchange synchronizes with every push
 * it takes, whatever the number of pushers in between.
 *
 * No lost wakeups: the "Dekker" handshake between a waker (post to an empty
 * inbox, or kick) and a sleeping owner uses seq_cst operations only: every
 * modification of inbox, sleeping and kicked is seq_cst, and so are the
 * loads the handshake decides on (the owner's inbox and kicked checks in
 * fdt_mailbox_wait, the wakers' loads of sleeping). The argument, at
 * fdt_mailbox_wait, then rests on the single total order S of seq_cst
 * operations alone. (Fences would work too, but ThreadSanitizer does not
 * model atomic_thread_fence, and on x86 a seq_cst CAS or exchange is the
 * same instruction as a release one.) The only weaker accesses are guesses
 * that a seq_cst operation confirms or that decide nothing about sleeping:
 * the relaxed head loads before a CAS, failed CASes, poll's empty pre-check.
 */
#include "par/mailbox.h"

#include <errno.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Messages per chunk when the caller asks for the default: 32 KiB. */
enum { FDT_MAILBOX_DEFAULT_CHUNK = 256 };

struct fdt_mailbox {
    /*
     * Producer-hot line: every post to this endpoint CASes it.
     * Push: CAS(seq_cst, hence release) publishes the message body and its
     * next link (plain writes by the sender before the CAS) to the owner,
     * whose exchange(seq_cst, hence acquire) takes them. seq_cst rather
     * than release/acquire only for the wakeup handshake (top of file). The
     * failure order is relaxed: a failed CAS only reloads the head to retry
     * and never dereferences it.
     */
    alignas(64) _Atomic(fdt_msg *) inbox;

    /*
     * Return line: every consumer that polls one of our messages CASes it.
     * Push: CAS(release) orders the consumer's reads of the message (its copy
     * out) before the owner's exchange(acquire), so the owner's next writes
     * to the recycled node cannot race with that copy. Failure order relaxed,
     * as for inbox.
     */
    alignas(64) _Atomic(fdt_msg *) returned;

    /* Owner-private line(s): plain fields touched only by the owner thread
     * (set, id and chunk_msgs are read-only after creation). */
    alignas(64) fdt_msg *batch;   /* taken from inbox, oldest first */
    fdt_msg *free;                /* free list of our pool */
    fdt_msg *chunks;              /* slot 0 of each chunk, linked by next */
    size_t nchunks;
    fdt_mailboxes *set;
    uint16_t id;
    fdt_mailbox_counts counts;

    /*
     * Sleep slow path, on its own line so that the owner's counter updates
     * do not evict it from posters' caches.
     * sleeping: stored (seq_cst) by the owner only, under `lock`; loaded
     *   (seq_cst) by posters and kickers after their seq_cst update of
     *   inbox / kicked. It carries no data: the handshake argument at
     *   fdt_mailbox_wait is its whole purpose.
     * kicked: kick stores 1 (seq_cst, hence release), so what the kicker
     *   wrote before (an abort flag) is visible to the owner once its
     *   exchange (seq_cst, hence acquire) reads 1. seq_cst for the
     *   handshake, as for inbox.
     */
    alignas(64) atomic_int sleeping;
    atomic_int kicked;
    pthread_mutex_t lock; /* guards the sleep/wake handshake only */
    pthread_cond_t wake;  /* signalled by posters/kickers that see sleeping */
};

struct fdt_mailboxes {
    fdt_mailbox *box;  /* n endpoints, 64-aligned, owned */
    int n;
    int n_sync;        /* endpoints whose mutex and condvar exist */
    size_t chunk_msgs;
    size_t max_chunks; /* 0: unlimited */
};

static void destroy_set(fdt_mailboxes *s)
{
    for (int i = 0; i < s->n; i++) {
        fdt_mailbox *b = &s->box[i];
        fdt_msg *c = b->chunks;
        while (c) {
            fdt_msg *next = c->next;
            free(c);
            c = next;
        }
        if (i < s->n_sync) {
            pthread_cond_destroy(&b->wake);
            pthread_mutex_destroy(&b->lock);
        }
    }
    free(s->box);
    free(s);
}

/* Condition variable on CLOCK_MONOTONIC, so that timed waits are immune to
 * wall-clock jumps. */
static int init_sync(fdt_mailbox *b)
{
    if (pthread_mutex_init(&b->lock, NULL) != 0)
        return FDT_EINTERNAL;
    pthread_condattr_t ca;
    if (pthread_condattr_init(&ca) != 0)
        goto fail_mutex;
    int rc = pthread_condattr_setclock(&ca, CLOCK_MONOTONIC);
    if (rc == 0)
        rc = pthread_cond_init(&b->wake, &ca);
    pthread_condattr_destroy(&ca);
    if (rc != 0)
        goto fail_mutex;
    return 0;
fail_mutex:
    pthread_mutex_destroy(&b->lock);
    return FDT_EINTERNAL;
}

int fdt_mailboxes_create(fdt_mailboxes **out, int n_threads,
                         size_t chunk_msgs, size_t max_chunks)
{
    if (!out)
        return FDT_EINVAL;
    *out = NULL;
    if (n_threads < 1 || n_threads > FDT_MAILBOX_MAX_THREADS)
        return FDT_EINVAL;
    if (chunk_msgs == 0)
        chunk_msgs = FDT_MAILBOX_DEFAULT_CHUNK;
    /* One extra slot per chunk holds the chunk link. */
    if (chunk_msgs > SIZE_MAX / sizeof(fdt_msg) - 1)
        return FDT_EINVAL;

    fdt_mailboxes *s = calloc(1, sizeof *s);
    if (!s)
        return FDT_ENOMEM;
    /* sizeof(fdt_mailbox) is a multiple of its 64-byte alignment, as
     * aligned_alloc requires; n <= 65535 keeps the product small. */
    s->box = aligned_alloc(alignof(fdt_mailbox),
                           (size_t)n_threads * sizeof(fdt_mailbox));
    if (!s->box) {
        free(s);
        return FDT_ENOMEM;
    }
    memset(s->box, 0, (size_t)n_threads * sizeof(fdt_mailbox));
    s->n = n_threads;
    s->chunk_msgs = chunk_msgs;
    s->max_chunks = max_chunks;
    for (int i = 0; i < n_threads; i++) {
        fdt_mailbox *b = &s->box[i];
        atomic_init(&b->inbox, NULL);
        atomic_init(&b->returned, NULL);
        atomic_init(&b->sleeping, 0);
        atomic_init(&b->kicked, 0);
        b->set = s;
        b->id = (uint16_t)i;
        if (init_sync(b) != 0) {
            destroy_set(s);
            return FDT_EINTERNAL;
        }
        s->n_sync = i + 1;
    }
    *out = s;
    return 0;
}

void fdt_mailboxes_destroy(fdt_mailboxes **mbs)
{
    if (!mbs || !*mbs)
        return;
    destroy_set(*mbs);
    *mbs = NULL;
}

int fdt_mailboxes_count(const fdt_mailboxes *mbs)
{
    return mbs->n;
}

fdt_mailbox *fdt_mailboxes_at(fdt_mailboxes *mbs, int i)
{
    if (i < 0 || i >= mbs->n)
        return NULL;
    return &mbs->box[i];
}

int fdt_mailbox_id(const fdt_mailbox *self)
{
    return self->id;
}

/* Adds one chunk to the owner's free list. */
static int grow_pool(fdt_mailbox *self)
{
    const fdt_mailboxes *s = self->set;
    if (s->max_chunks != 0 && self->nchunks >= s->max_chunks)
        return FDT_ENOMEM;
    size_t k = s->chunk_msgs;
    fdt_msg *c = aligned_alloc(alignof(fdt_msg), (k + 1) * sizeof(fdt_msg));
    if (!c)
        return FDT_ENOMEM;
    c[0].next = self->chunks;
    self->chunks = c;
    self->nchunks++;
    /* Link slots 1..k in address order, ahead of the (empty) free list. */
    for (size_t i = 1; i < k; i++)
        c[i].next = &c[i + 1];
    c[k].next = self->free;
    self->free = &c[1];
    return 0;
}

int fdt_mailbox_alloc(fdt_mailbox *self, fdt_msg **out)
{
    fdt_msg *m = self->free;
    if (!m) {
        /* Take back everything consumers returned. acquire: pairs with
         * their release pushes (see `returned`), so their copies of these
         * messages are finished before we reuse the nodes. An exchange
         * rather than a load-then-exchange: a stale NULL would grow the pool
         * (or fail at max_chunks) while nodes wait here. */
        m = atomic_exchange_explicit(&self->returned, NULL,
                                     memory_order_acquire);
        if (!m) {
            int rc = grow_pool(self);
            if (rc != 0)
                return rc;
            m = self->free;
        }
    }
    self->free = m->next;
    memset(m, 0, sizeof *m);
    m->sender = self->id;
    *out = m;
    return 0;
}

void fdt_mailbox_discard(fdt_mailbox *self, fdt_msg *m)
{
    m->next = self->free;
    self->free = m;
}

/*
 * Pushes m on target's inbox; returns 1 if the inbox was empty. The waker
 * half of the handshake argued at fdt_mailbox_wait: the successful CAS C and
 * then the load of sleeping, both seq_cst.
 *
 * Only a push that finds the inbox empty looks for a sleeper. If the inbox
 * held messages, the push P0 that last made it nonempty already did: the
 * owner either sees P0's message (and ours after it) when it checks inbox
 * before sleeping, or is signalled by P0; either way it then exchanges the
 * whole stack, ours included.
 */
static int push_inbox(fdt_mailbox *target, fdt_msg *m)
{
    /* A guess for the CAS; the CAS itself reads the current head. */
    fdt_msg *old = atomic_load_explicit(&target->inbox, memory_order_relaxed);
    do {
        m->next = old;
    } while (!atomic_compare_exchange_weak_explicit(
        &target->inbox, &old, m, memory_order_seq_cst, memory_order_relaxed));
    /* m now belongs to the owner of target: do not touch it. */
    if (old != NULL)
        return 0;
    if (atomic_load_explicit(&target->sleeping, memory_order_seq_cst)) {
        /* A default mutex cannot fail to lock here (no recursion, not
         * robust, initialized at creation). */
        pthread_mutex_lock(&target->lock);
        pthread_cond_signal(&target->wake);
        pthread_mutex_unlock(&target->lock);
    }
    return 1;
}

int fdt_mailbox_post(fdt_mailbox *self, int to, fdt_msg *m)
{
    fdt_mailboxes *s = self->set;
    if (!m || to < 0 || to >= s->n || m->kind < 1 ||
        m->kind >= FDT_MSG_KIND_END || m->sender != self->id)
        return FDT_EINVAL;
    /* Count before the push: afterwards m may already be recycled. */
    self->counts.sent[m->kind]++;
    return push_inbox(&s->box[to], m);
}

int fdt_mailbox_send(fdt_mailbox *self, int to, const fdt_msg *src)
{
    const fdt_mailboxes *s = self->set;
    if (!src || to < 0 || to >= s->n || src->kind < 1 ||
        src->kind >= FDT_MSG_KIND_END)
        return FDT_EINVAL;
    fdt_msg *m;
    int rc = fdt_mailbox_alloc(self, &m);
    if (rc != 0)
        return rc;
    m->kind = src->kind;
    m->tag = src->tag;
    m->u = src->u;
    return fdt_mailbox_post(self, to, m);
}

int fdt_mailbox_poll(fdt_mailbox *self, fdt_msg *out)
{
    fdt_msg *m = self->batch;
    if (!m) {
        /* Relaxed pre-check: polling an empty inbox must not write its
         * line (that would bounce it between the producers' caches). A
         * stale NULL only delays the message to the next poll; the wait
         * path has its own ordering. */
        if (atomic_load_explicit(&self->inbox, memory_order_relaxed) == NULL)
            return 0;
        /* Acquire (implied by seq_cst): synchronizes with the CAS of every
         * push taken (release sequence, top of file), so the bodies and next
         * links below are visible. seq_cst so that every modification of
         * inbox is in S, as the wakeup argument needs. */
        fdt_msg *lifo = atomic_exchange_explicit(&self->inbox, NULL,
                                                 memory_order_seq_cst);
        /* Newest first: reverse into push order. */
        fdt_msg *fifo = NULL;
        while (lifo) {
            fdt_msg *next = lifo->next;
            lifo->next = fifo;
            fifo = lifo;
            lifo = next;
        }
        m = fifo;
        if (!m)
            return 0;
    }
    self->batch = m->next;
    *out = *m;
    out->next = NULL;
    self->counts.received[m->kind]++;

    /* Return the node to its sender's pool. release: our copy above happens
     * before the sender's acquire exchange and its reuse of the node. */
    fdt_mailbox *owner = &self->set->box[m->sender];
    fdt_msg *old = atomic_load_explicit(&owner->returned, memory_order_relaxed);
    do {
        m->next = old;
    } while (!atomic_compare_exchange_weak_explicit(
        &owner->returned, &old, m, memory_order_release,
        memory_order_relaxed));
    return 1;
}

int fdt_mailbox_pending(fdt_mailbox *self)
{
    return self->batch != NULL ||
           atomic_load_explicit(&self->inbox, memory_order_relaxed) != NULL;
}

/* Consumes a pending kick. The exchange (seq_cst, hence acquire) pairs with
 * the store in fdt_mailbox_kick, so the kicker's earlier writes are visible.
 * The load first avoids an RMW on the common no-kick path; it is seq_cst
 * because inside fdt_mailbox_wait it is the handshake's check of kicked. */
static int take_kick(fdt_mailbox *self)
{
    if (!atomic_load_explicit(&self->kicked, memory_order_seq_cst))
        return 0;
    return atomic_exchange_explicit(&self->kicked, 0, memory_order_seq_cst);
}

/*
 * Lost-wakeup argument. The owner, holding the mutex, stores sleeping = 1
 * (S1), then loads inbox and kicked (L); it sleeps only if both are empty,
 * and keeps the mutex until cond_wait atomically releases it. A waker
 * modifies inbox or kicked (C: a push that found the inbox empty, or the
 * kick's store), then loads sleeping (LS). All four are seq_cst, and every
 * modification of these three variables is seq_cst, so each load returns the
 * last modification preceding it in S; S respects program order, so
 * S1 < L and C < LS.
 * - If C < L in S: L returns C's value or a later one. Later modifications
 *   are other pushes / kicks (nonempty), or the owner's own exchanges, which
 *   all precede S1 in program order and so took C's message before this
 *   wait began (poll then handed it out). So the owner does not sleep on C.
 * - If L < C: then S1 < L < C < LS, so LS returns S1's 1 or a later store:
 *   a 1 makes the waker lock the mutex, which it gets only once the owner
 *   sleeps in cond_wait (or has left), and signal; a 0 is only stored when
 *   the owner leaves the wait. Either way the owner does not sleep past C.
 * After any wakeup, spurious or not, the loop re-runs the checks, each still
 * after S1 with sleeping still 1, so the same holds for every iteration. A
 * signal left over from an earlier wait only causes a spurious wakeup.
 */
int fdt_mailbox_wait(fdt_mailbox *self, int64_t timeout_ns)
{
    if (fdt_mailbox_pending(self))
        return FDT_MAILBOX_MESSAGE;
    if (take_kick(self))
        return FDT_MAILBOX_KICKED;
    if (timeout_ns == 0)
        return FDT_MAILBOX_TIMEOUT;

    struct timespec deadline;
    if (timeout_ns > 0) {
        if (clock_gettime(CLOCK_MONOTONIC, &deadline) != 0)
            return FDT_EINTERNAL;
        int64_t ns = (int64_t)deadline.tv_nsec + timeout_ns % 1000000000;
        deadline.tv_sec += (time_t)(timeout_ns / 1000000000 + ns / 1000000000);
        deadline.tv_nsec = (long)(ns % 1000000000);
    }

    int result = FDT_MAILBOX_TIMEOUT;
    pthread_mutex_lock(&self->lock);
    atomic_store_explicit(&self->sleeping, 1, memory_order_seq_cst); /* S1 */
    for (;;) {
        /* L (with take_kick below). The messages themselves are read only
         * after poll's exchange. */
        if (atomic_load_explicit(&self->inbox, memory_order_seq_cst)) {
            result = FDT_MAILBOX_MESSAGE;
            break;
        }
        if (take_kick(self)) {
            result = FDT_MAILBOX_KICKED;
            break;
        }
        int rc;
        if (timeout_ns > 0)
            rc = pthread_cond_timedwait(&self->wake, &self->lock, &deadline);
        else
            rc = pthread_cond_wait(&self->wake, &self->lock);
        if (rc == ETIMEDOUT) {
            /* One last look: a post may have raced with the timeout. */
            if (atomic_load_explicit(&self->inbox, memory_order_seq_cst))
                result = FDT_MAILBOX_MESSAGE;
            else if (take_kick(self))
                result = FDT_MAILBOX_KICKED;
            else
                result = FDT_MAILBOX_TIMEOUT;
            break;
        }
        if (rc != 0) {
            result = FDT_EINTERNAL;
            break;
        }
    }
    /* Wakers that read this 0 skip the signal: we are awake. */
    atomic_store_explicit(&self->sleeping, 0, memory_order_seq_cst);
    pthread_mutex_unlock(&self->lock);
    return result;
}

void fdt_mailbox_kick(fdt_mailbox *target)
{
    /* C of the handshake; seq_cst, hence release: publishes the kicker's
     * earlier writes to take_kick. */
    atomic_store_explicit(&target->kicked, 1, memory_order_seq_cst);
    if (atomic_load_explicit(&target->sleeping, memory_order_seq_cst)) {
        pthread_mutex_lock(&target->lock);
        pthread_cond_signal(&target->wake);
        pthread_mutex_unlock(&target->lock);
    }
}

void fdt_mailbox_counts_get(const fdt_mailbox *self, fdt_mailbox_counts *c)
{
    *c = self->counts;
}

size_t fdt_mailbox_chunks(const fdt_mailbox *self)
{
    return self->nchunks;
}
