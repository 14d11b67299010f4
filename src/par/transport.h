/*
 * The transport between the parts of the parallel engine (DESIGN.md,
 * Transport): typed messages (fdt_msg, src/par/mailbox.h) allocated, posted to
 * a part, polled and waited for, one endpoint per part. The engine talks
 * only to this interface; an implementation is a table of operations:
 *  - "mailbox": the in-process lock-free mailboxes (src/par/mailbox.c), FIFO
 *    per sender (indeed globally), what every run uses;
 *  - "shuffle": a test transport over the same mailboxes that delays each
 *    message a random number of polls and delivers, among the senders with
 *    messages waiting, a random one's oldest (seeded): FIFO per sender, as
 *    MPI guarantees for a pair of ranks, and nothing more. Termination and
 *    the handlers must hold under every such schedule (tests/test_transport.c).
 * Who may call what is the mailbox's synchronization table: the operations
 * on endpoint `self` are made by the part that owns it, kick by anyone.
 */
#ifndef FDT_TRANSPORT_H
#define FDT_TRANSPORT_H

#include <stdint.h>

#include "par/mailbox.h"

typedef struct fdt_transport fdt_transport;

typedef struct fdt_transport_ops {
    const char *name;
    /* A message to fill (kind 0, payload zeroed): 0 or FDT_ENOMEM. */
    int (*alloc)(fdt_transport *t, int self, fdt_msg **m);
    /* Sends m (kind and payload set) to part `to`; m is the transport's
     * afterwards. >= 0, or FDT_EINVAL (bad destination or kind). */
    int (*post)(fdt_transport *t, int self, int to, fdt_msg *m);
    /* The next message for self into *out: 1, or 0 if none now. */
    int (*poll)(fdt_transport *t, int self, fdt_msg *out);
    /* Nonzero if a poll may return a message now. */
    int (*pending)(fdt_transport *t, int self);
    /* Blocks until a message may be polled or self is kicked (or
     * timeout_ns passes, < 0: none): FDT_MAILBOX_* or FDT_EINTERNAL. */
    int (*wait)(fdt_transport *t, int self, int64_t timeout_ns);
    /* Ends target's current or next wait (any thread). */
    void (*kick)(fdt_transport *t, int target);
    /* Messages self sent and received (handed to it by poll), by kind;
     * from self, or after self's thread is joined. */
    void (*counts)(const fdt_transport *t, int self, fdt_mailbox_counts *c);
    void (*destroy)(fdt_transport *t);
} fdt_transport_ops;

struct fdt_transport {
    const fdt_transport_ops *ops;
    int n;                 /* endpoints */
    fdt_mailboxes *mbs;    /* both implementations carry the mailboxes */
    void *priv;            /* the implementation's own state */
};

/* The in-process mailboxes for n parts. *out is NULL on failure.
 * 0, FDT_EINVAL, FDT_ENOMEM or FDT_EINTERNAL. */
int fdt_transport_mailbox(fdt_transport **out, int n);
/* The test transport (above) for n parts: seed picks the schedule; each
 * poll that could deliver holds everything back with probability
 * delay_pct / 100 (0..90). */
int fdt_transport_shuffle(fdt_transport **out, int n, uint64_t seed, int delay_pct);
/* Frees t and undelivered messages; *t = NULL. NULL is fine. */
void fdt_transport_destroy(fdt_transport **t);

static inline int fdt_tp_alloc(fdt_transport *t, int self, fdt_msg **m)
{
    return t->ops->alloc(t, self, m);
}
static inline int fdt_tp_post(fdt_transport *t, int self, int to, fdt_msg *m)
{
    return t->ops->post(t, self, to, m);
}
static inline int fdt_tp_poll(fdt_transport *t, int self, fdt_msg *out)
{
    return t->ops->poll(t, self, out);
}
static inline int fdt_tp_pending(fdt_transport *t, int self)
{
    return t->ops->pending(t, self);
}
static inline int fdt_tp_wait(fdt_transport *t, int self, int64_t timeout_ns)
{
    return t->ops->wait(t, self, timeout_ns);
}
static inline void fdt_tp_kick(fdt_transport *t, int target)
{
    t->ops->kick(t, target);
}
static inline void fdt_tp_counts(const fdt_transport *t, int self, fdt_mailbox_counts *c)
{
    t->ops->counts(t, self, c);
}

#endif
