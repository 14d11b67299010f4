/*
 * The MPI transport; see transport_mpi.h.
 *
 * Wire format: a message travels as the bytes of its fdt_msg from `kind`
 * to the end of its kind's payload (fdt_proto_payload_size, the table of
 * src/par/protocol.c), as MPI_BYTE, with one MPI tag. The receiver learns the
 * sender from the status (the `sender` field's bytes are overwritten) and
 * refuses a message whose length is not its kind's (kind 0, which the
 * dispatcher rejects as an internal error). MPI_BYTE assumes every rank
 * has the same byte order and double format, as a homogeneous cluster
 * has; a mixed one would need MPI datatypes per kind.
 *
 * Sends are nonblocking (MPI_Isend): the engine never waits for a send,
 * so two ranks that send each other FACESENDs cannot deadlock (the paper's
 * iPSC/860 csend blocked, §4 works around it by answering its own mail
 * while it waits, which our receive side still does). A sent message's
 * buffer is returned to this endpoint's free list once MPI says the send
 * completed (MPI_Testsome at the next post).
 *
 * Receives poll with MPI_Improbe on any source, then MPI_Mrecv the probed
 * message (matched once, and nobody can take it in between). MPI keeps
 * the order of the messages of one sender to one receiver with one tag:
 * FIFO per pair, the property the shuffle test transport keeps and the
 * termination proof does not even need (src/par/termination.c).
 *
 * Waiting: a rank with nothing to do polls with MPI_Iprobe, yielding at
 * first, then sleeping with a growing pause up to 200 us. Open MPI's
 * blocking receive also busy-polls, which would take the core from the
 * rank that has work when ranks oversubscribe the cores (the tests run 7
 * ranks on 2 cores).
 */
#include "mpi/transport_mpi.h"

#include <limits.h>
#include <sched.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "base/clock.h"
#include "frontdt.h"
#include "par/protocol.h"

/* The MPI tag of every engine message (the communicator is our own). */
#define TMPI_TAG 19

/* The bytes before the payload that travel: kind, sender (overwritten at
 * the receiver), tag. */
#define TMPI_HDR (offsetof(fdt_msg, u) - offsetof(fdt_msg, kind))

typedef struct tmpi {
    MPI_Comm comm;
    int rank, size;
    fdt_msg *free;             /* buffers to reuse (linked by next) */
    fdt_msg *reserve;          /* `size` buffers made at the start, used
                                  only when malloc fails: the ABORTs of a
                                  rank out of memory still go out */
    MPI_Request *req;          /* sends in flight ... */
    fdt_msg **fly;             /* ... and their buffers */
    int nfly, capfly;
    int *done;                 /* MPI_Testsome's indices */
    uint64_t sent[FDT_MSG_KIND_END], received[FDT_MSG_KIND_END];
    int abandoned;
    int skip;                  /* polls left before the next MPI_Iprobe */
} tmpi;

/* The main loop polls once a face (microseconds); an MPI_Iprobe that
 * finds nothing costs a trip through MPI's progress engine, about 5 % of
 * a rank's CPU time at one a face (perf, 300k uniform points, 2 ranks).
 * After an empty probe the next TMPI_POLL_EVERY - 1 polls answer "none"
 * without asking MPI: a message waits a few faces longer, which a parked
 * face (src/par/engine.c) does not notice. A wait (tm_pending, tm_wait)
 * always probes, and a probe that finds mail makes the next poll probe. */
#define TMPI_POLL_EVERY 4

static tmpi *priv(const fdt_transport *t)
{
    return t->priv;
}

static int tm_alloc(fdt_transport *t, int self, fdt_msg **m)
{
    tmpi *s = priv(t);
    if (self != s->rank)
        return FDT_EINVAL;
    fdt_msg *x = s->free;
    if (x)
        s->free = x->next;
    else if (!(x = aligned_alloc(alignof(fdt_msg), sizeof *x))) {
        if (!(x = s->reserve))
            return FDT_ENOMEM;
        s->reserve = x->next;
    }
    memset(x, 0, sizeof *x);
    x->sender = (uint16_t)s->rank;
    *m = x;
    return FDT_OK;
}

static void give_back(tmpi *s, fdt_msg *m)
{
    m->next = s->free;
    s->free = m;
}

/* Returns the buffers of completed sends to the free list. */
static int reclaim(tmpi *s)
{
    if (s->nfly == 0)
        return FDT_OK;
    int nd = 0;
    if (MPI_Testsome(s->nfly, s->req, &nd, s->done, MPI_STATUSES_IGNORE) != MPI_SUCCESS)
        return FDT_EINTERNAL;
    if (nd == MPI_UNDEFINED || nd == 0)
        return FDT_OK;
    for (int i = 0; i < nd; i++) {
        give_back(s, s->fly[s->done[i]]);
        s->fly[s->done[i]] = NULL;
    }
    /* Compact: completed requests are MPI_REQUEST_NULL now. */
    int k = 0;
    for (int i = 0; i < s->nfly; i++)
        if (s->fly[i]) {
            s->req[k] = s->req[i];
            s->fly[k++] = s->fly[i];
        }
    s->nfly = k;
    return FDT_OK;
}

static int tm_post(fdt_transport *t, int self, int to, fdt_msg *m)
{
    tmpi *s = priv(t);
    size_t pl = fdt_proto_payload_size(m->kind);
    if (self != s->rank || to < 0 || to >= s->size || pl == 0) {
        give_back(s, m);
        return FDT_EINVAL;
    }
    if (reclaim(s) != FDT_OK) {
        give_back(s, m);
        return FDT_EINTERNAL;
    }
    if (s->nfly == s->capfly) {
        int nc = s->capfly ? 2 * s->capfly : 64;
        MPI_Request *nr = realloc(s->req, (size_t)nc * sizeof *nr);
        if (nr)
            s->req = nr;
        fdt_msg **nf = nr ? realloc(s->fly, (size_t)nc * sizeof *nf) : NULL;
        if (nf)
            s->fly = nf;
        int *nd = nf ? realloc(s->done, (size_t)nc * sizeof *nd) : NULL;
        if (!nd) {
            give_back(s, m);
            return FDT_EINTERNAL; /* post cannot report ENOMEM (transport.h) */
        }
        s->done = nd;
        s->capfly = nc;
    }
    if (MPI_Isend(&m->kind, (int)(TMPI_HDR + pl), MPI_BYTE, to, TMPI_TAG, s->comm,
                  &s->req[s->nfly]) != MPI_SUCCESS) {
        give_back(s, m);
        return FDT_EINTERNAL;
    }
    s->fly[s->nfly++] = m;
    s->sent[m->kind]++;
    return 0;
}

static int tm_poll(fdt_transport *t, int self, fdt_msg *out)
{
    tmpi *s = priv(t);
    if (self != s->rank)
        return 0;
    if (s->skip > 0) {
        s->skip--;
        return 0;
    }
    /* A matched probe (MPI-3): the receive takes the message the probe
     * found without matching it again (MPI_Recv after MPI_Iprobe was 2 % of
     * a rank's CPU time, perf, 300k points). */
    int flag = 0;
    MPI_Status st;
    MPI_Message mh;
    if (MPI_Improbe(MPI_ANY_SOURCE, TMPI_TAG, s->comm, &flag, &mh, &st) != MPI_SUCCESS ||
        !flag) {
        s->skip = TMPI_POLL_EVERY - 1;
        return 0;
    }
    int count = 0;
    MPI_Get_count(&st, MPI_BYTE, &count);
    memset(out, 0, sizeof *out);
    /* The probed message, however long, is taken (else it would block the
     * queue); one longer than any kind is cut and refused below. */
    int max = (int)(TMPI_HDR + sizeof out->u);
    if (count < 0 || count > max) {
        /* A matched message must be received; without memory for it
         * the job cannot go on. */
        void *big = malloc(count > 0 ? (size_t)count : 1);
        if (!big)
            MPI_Abort(s->comm, 4);
        MPI_Mrecv(big, count > 0 ? count : 0, MPI_BYTE, &mh, MPI_STATUS_IGNORE);
        free(big);
        out->kind = 0; /* refused by fdt_proto_dispatch */
        return 1;
    }
    if (MPI_Mrecv(&out->kind, count, MPI_BYTE, &mh, MPI_STATUS_IGNORE) != MPI_SUCCESS) {
        out->kind = 0;
        return 1;
    }
    out->sender = (uint16_t)st.MPI_SOURCE;
    size_t pl = fdt_proto_payload_size(out->kind);
    if (pl == 0 || (size_t)count != TMPI_HDR + pl) {
        out->kind = 0;
        return 1;
    }
    s->received[out->kind]++;
    return 1;
}

static int tm_pending(fdt_transport *t, int self)
{
    tmpi *s = priv(t);
    int flag = 0;
    if (self != s->rank)
        return 0;
    if (MPI_Iprobe(MPI_ANY_SOURCE, TMPI_TAG, s->comm, &flag, MPI_STATUS_IGNORE) != MPI_SUCCESS)
        return 0;
    if (flag)
        s->skip = 0; /* the poll after a wait takes the mail */
    return flag;
}

static int tm_wait(fdt_transport *t, int self, int64_t timeout_ns)
{
    double end = timeout_ns < 0 ? 0.0 : fdt_now_s() + (double)timeout_ns * 1e-9;
    long pause_ns = 1000;
    for (int i = 0;; i++) {
        if (tm_pending(t, self))
            return FDT_MAILBOX_MESSAGE;
        if (timeout_ns >= 0 && fdt_now_s() >= end)
            return FDT_MAILBOX_TIMEOUT;
        if (i < 32) {
            sched_yield();
            continue;
        }
        struct timespec ts = {0, pause_ns};
        nanosleep(&ts, NULL);
        if (pause_ns < 200000)
            pause_ns *= 2;
    }
}

static void tm_kick(fdt_transport *t, int target)
{
    /* One thread a rank: nobody else can be waiting on our endpoint. */
    (void)t;
    (void)target;
}

static void tm_counts(const fdt_transport *t, int self, fdt_mailbox_counts *c)
{
    const tmpi *s = priv(t);
    memset(c, 0, sizeof *c);
    if (self != s->rank)
        return;
    memcpy(c->sent, s->sent, sizeof c->sent);
    memcpy(c->received, s->received, sizeof c->received);
}

static void free_list(fdt_msg *m)
{
    while (m) {
        fdt_msg *n = m->next;
        free(m);
        m = n;
    }
}

static void tm_destroy(fdt_transport *t)
{
    tmpi *s = priv(t);
    if (!s)
        return;
    if (s->abandoned) {
        for (int i = 0; i < s->nfly; i++)
            MPI_Request_free(&s->req[i]);
    } else if (s->nfly) {
        /* A finished run: every message was received (the counts are
         * checked), so every send completes. */
        MPI_Waitall(s->nfly, s->req, MPI_STATUSES_IGNORE);
    }
    for (int i = 0; i < s->nfly; i++)
        free(s->fly[i]);
    free_list(s->free);
    free_list(s->reserve);
    free(s->req);
    free(s->fly);
    free(s->done);
    MPI_Comm_free(&s->comm);
    free(s);
    t->priv = NULL;
}

static const fdt_transport_ops mpi_ops = {
    "mpi", tm_alloc, tm_post, tm_poll, tm_pending, tm_wait, tm_kick, tm_counts, tm_destroy,
};

int fdt_transport_mpi(fdt_transport **out, MPI_Comm comm)
{
    *out = NULL;
    fdt_transport *t = calloc(1, sizeof *t);
    tmpi *s = calloc(1, sizeof *s);
    if (!t || !s) {
        free(t);
        free(s);
        return FDT_ENOMEM;
    }
    if (MPI_Comm_dup(comm, &s->comm) != MPI_SUCCESS) {
        free(t);
        free(s);
        return FDT_EINTERNAL;
    }
    MPI_Comm_rank(s->comm, &s->rank);
    MPI_Comm_size(s->comm, &s->size);
    /* One ABORT for every other rank (src/par/termination.c sends them when
     * this rank fails, also out of memory). */
    for (int i = 0; i < s->size; i++) {
        fdt_msg *m = aligned_alloc(alignof(fdt_msg), sizeof *m);
        if (!m) {
            t->priv = s;
            t->ops = &mpi_ops;
            fdt_transport_destroy(&t);
            return FDT_ENOMEM;
        }
        m->next = s->reserve;
        s->reserve = m;
    }
    t->ops = &mpi_ops;
    t->n = s->size;
    t->mbs = NULL;
    t->priv = s;
    *out = t;
    return FDT_OK;
}

void fdt_transport_mpi_abandon(fdt_transport *t)
{
    if (t && t->priv)
        priv(t)->abandoned = 1;
}
