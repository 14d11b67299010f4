/* The transports of the parallel engine; see transport.h. */
#include "par/transport.h"

#include <stdalign.h>
#include <stdlib.h>
#include <string.h>

#include "base/hash.h"
#include "frontdt.h"

/* ---- mailbox: the in-process mailboxes as they are ------------------------ */

static int mb_alloc(fdt_transport *t, int self, fdt_msg **m)
{
    return fdt_mailbox_alloc(fdt_mailboxes_at(t->mbs, self), m);
}

static int mb_post(fdt_transport *t, int self, int to, fdt_msg *m)
{
    return fdt_mailbox_post(fdt_mailboxes_at(t->mbs, self), to, m);
}

static int mb_poll(fdt_transport *t, int self, fdt_msg *out)
{
    return fdt_mailbox_poll(fdt_mailboxes_at(t->mbs, self), out);
}

static int mb_pending(fdt_transport *t, int self)
{
    return fdt_mailbox_pending(fdt_mailboxes_at(t->mbs, self));
}

static int mb_wait(fdt_transport *t, int self, int64_t timeout_ns)
{
    return fdt_mailbox_wait(fdt_mailboxes_at(t->mbs, self), timeout_ns);
}

static void mb_kick(fdt_transport *t, int target)
{
    fdt_mailbox_kick(fdt_mailboxes_at(t->mbs, target));
}

static void mb_counts(const fdt_transport *t, int self, fdt_mailbox_counts *c)
{
    /* fdt_mailboxes_at only indexes the set; it writes nothing. */
    fdt_mailbox_counts_get(fdt_mailboxes_at((fdt_mailboxes *)t->mbs, self), c);
}

static void mb_destroy(fdt_transport *t)
{
    fdt_mailboxes_destroy(&t->mbs);
}

static const fdt_transport_ops mailbox_ops = {
    "mailbox", mb_alloc, mb_post, mb_poll, mb_pending, mb_wait, mb_kick, mb_counts, mb_destroy,
};

static int make(fdt_transport **out, int n, const fdt_transport_ops *ops)
{
    *out = NULL;
    fdt_transport *t = calloc(1, sizeof *t);
    if (!t)
        return FDT_ENOMEM;
    int err = fdt_mailboxes_create(&t->mbs, n, 0, 0);
    if (err) {
        free(t);
        return err;
    }
    t->ops = ops;
    t->n = n;
    *out = t;
    return FDT_OK;
}

int fdt_transport_mailbox(fdt_transport **out, int n)
{
    return make(out, n, &mailbox_ops);
}

void fdt_transport_destroy(fdt_transport **t)
{
    if (!t || !*t)
        return;
    (*t)->ops->destroy(*t);
    free(*t);
    *t = NULL;
}

/* ---- shuffle: delays and reorders across senders (tests) ------------------ */

/*
 * Each endpoint keeps the messages it has taken from its mailbox but not
 * yet handed to its part, in arrival order. A poll first takes everything
 * from the mailbox, then, with probability 1 - delay, hands out the oldest
 * message of the sender of a randomly chosen buffered one: messages of one
 * sender keep their order, messages of different senders come in any order,
 * and any message may wait while its part does other work. Only the owner
 * of an endpoint touches its buffer (the mailbox's rule for poll), so the
 * buffers need no synchronization; kick goes to the mailbox as it is.
 */
typedef struct shuf_ep {
    alignas(64) uint64_t rng;
    fdt_msg *buf;
    size_t n, cap;
    uint64_t received[FDT_MSG_KIND_END]; /* handed to the part, by kind */
} shuf_ep;

typedef struct shuf {
    shuf_ep *ep;
    int delay_pct;
} shuf;

/* Moves everything in self's mailbox to its buffer. FDT_ENOMEM leaves the
 * message in the mailbox (it is polled again later). */
static int shuf_drain(fdt_transport *t, int self, shuf_ep *e)
{
    fdt_mailbox *mb = fdt_mailboxes_at(t->mbs, self);
    while (fdt_mailbox_pending(mb)) {
        if (e->n == e->cap) {
            size_t ncap = e->cap ? 2 * e->cap : 64;
            fdt_msg *nb = aligned_alloc(alignof(fdt_msg), ncap * sizeof *nb);
            if (!nb)
                return FDT_ENOMEM;
            if (e->n)
                memcpy(nb, e->buf, e->n * sizeof *nb);
            free(e->buf);
            e->buf = nb;
            e->cap = ncap;
        }
        if (!fdt_mailbox_poll(mb, &e->buf[e->n]))
            break;
        e->n++;
    }
    return FDT_OK;
}

static int sh_poll(fdt_transport *t, int self, fdt_msg *out)
{
    shuf *s = t->priv;
    shuf_ep *e = &s->ep[self];
    int err = shuf_drain(t, self, e);
    if (err && !e->n)
        return 0;
    if (!e->n || (int)(fdt_splitmix64(&e->rng) % 100) < s->delay_pct)
        return 0;
    size_t pick = (size_t)(fdt_splitmix64(&e->rng) % e->n), i = 0;
    while (e->buf[i].sender != e->buf[pick].sender)
        i++;
    *out = e->buf[i];
    memmove(e->buf + i, e->buf + i + 1, (e->n - i - 1) * sizeof *e->buf);
    e->n--;
    e->received[out->kind]++;
    return 1;
}

static int sh_pending(fdt_transport *t, int self)
{
    shuf *s = t->priv;
    return s->ep[self].n > 0 || fdt_mailbox_pending(fdt_mailboxes_at(t->mbs, self));
}

static int sh_wait(fdt_transport *t, int self, int64_t timeout_ns)
{
    shuf *s = t->priv;
    /* A held-back message is deliverable at the next poll: no sleep. */
    if (s->ep[self].n > 0)
        return FDT_MAILBOX_MESSAGE;
    return fdt_mailbox_wait(fdt_mailboxes_at(t->mbs, self), timeout_ns);
}

static void sh_counts(const fdt_transport *t, int self, fdt_mailbox_counts *c)
{
    const shuf *s = t->priv;
    fdt_mailbox_counts_get(fdt_mailboxes_at((fdt_mailboxes *)t->mbs, self), c);
    memcpy(c->received, s->ep[self].received, sizeof c->received);
}

static void sh_destroy(fdt_transport *t)
{
    shuf *s = t->priv;
    if (s) {
        for (int i = 0; i < t->n; i++)
            free(s->ep[i].buf);
        free(s->ep);
        free(s);
    }
    t->priv = NULL;
    fdt_mailboxes_destroy(&t->mbs);
}

static const fdt_transport_ops shuffle_ops = {
    "shuffle", mb_alloc, mb_post, sh_poll, sh_pending, sh_wait, mb_kick, sh_counts, sh_destroy,
};

int fdt_transport_shuffle(fdt_transport **out, int n, uint64_t seed, int delay_pct)
{
    if (delay_pct < 0 || delay_pct > 90)
        return FDT_EINVAL;
    int err = make(out, n, &shuffle_ops);
    if (err)
        return err;
    fdt_transport *t = *out;
    shuf *s = calloc(1, sizeof *s);
    shuf_ep *ep = s ? aligned_alloc(alignof(shuf_ep), (size_t)n * sizeof *ep) : NULL;
    if (!ep) {
        free(s);
        fdt_transport_destroy(out);
        return FDT_ENOMEM;
    }
    memset(ep, 0, (size_t)n * sizeof *ep);
    for (int i = 0; i < n; i++)
        ep[i].rng = seed * 0x9E3779B97F4A7C15ull + (uint64_t)i + 1;
    s->ep = ep;
    s->delay_pct = delay_pct;
    t->priv = s;
    return FDT_OK;
}
