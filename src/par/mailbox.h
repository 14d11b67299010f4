/*
 * Mailboxes: one lock-free multi-producer single-consumer queue per thread,
 * carrying the five message types of Merriam's §4 (iamdone, nodesend,
 * noderecv, facesend, facerecv). See ../shared/design/DESIGN.md, "Mailboxes".
 *
 * A set (fdt_mailboxes) holds one endpoint (fdt_mailbox) per thread. The
 * endpoint of thread i is both its inbox and its outgoing message pool:
 *
 *   sender thread s                          receiver thread r
 *   fdt_mailbox_alloc(s)   <- free list of s
 *   fill kind, tag, payload
 *   fdt_mailbox_post(s, r, m)  --inbox of r-->  fdt_mailbox_poll(r, &copy)
 *                               <--return stack of s--  (node recycled)
 *
 * Design (why this one): the inbox is an intrusive Treiber stack that
 * producers push onto with one CAS, and that the consumer empties all at once
 * with one exchange, then reverses privately into FIFO order (the pattern of
 * Linux's llist). Every message of every producer is pushed at a single
 * linearization point (its successful CAS), and each exchanged batch holds
 * the pushes since the previous exchange, newest first, so reversing it gives
 * push order: FIFO per producer (indeed globally). There is no ABA: the only
 * removal is "take everything", and a push writes m->next = old without
 * reading *old, so a CAS that succeeds after head went A -> NULL -> A still
 * links m correctly in front of A. Producers are lock-free (a failed CAS means
 * another push succeeded); the consumer is wait-free and, unlike a
 * Vyukov-style queue, never sees a half-linked message left by a preempted
 * producer (which matters on an oversubscribed machine).
 * Consumed nodes go back to their sender's pool through the sender's return
 * stack, a second Treiber stack of the same kind (many consumers push, the
 * owner takes everything): again ABA-free. The owner's free list is private.
 * A pool grows by chunks of chunk_msgs messages (one malloc per chunk, never
 * per message); a message is 128 bytes, 64-aligned, so two messages never
 * share a cache line.
 *
 * Synchronization table (liburcu wfcqueue.h style). "owner(i)" means the
 * thread that owns endpoint i; operations on different endpoints never
 * conflict except as listed. Y: may run concurrently. -: must not.
 *
 *                        alloc/   post     post     poll/    kick    counts/
 *                        discard  from i   to i     wait/    i       chunks
 *                        on i                       pending          of i
 *                                                   on i
 *   alloc/discard on i     -        -        Y        -        Y       -
 *   post from i            -        -        Y        -        Y       -
 *   post to i              Y        Y        Y        Y        Y       Y
 *   poll/wait/pending on i -        -        Y        -        Y       -
 *   kick i                 Y        Y        Y        Y        Y       Y
 *   counts/chunks of i     -        -        Y        -        Y       Y
 *
 * In words: alloc, discard, post-from-i, poll, wait, pending on endpoint i
 * are called only by owner(i), hence never concurrently with each other.
 * Any thread may post to endpoint i and kick endpoint i at any time
 * (including owner(i) itself, posting to its own inbox). Returning a
 * consumed node to sender i's pool happens inside poll on another endpoint
 * and is safe concurrently with everything owner(i) does. fdt_mailbox_counts
 * and fdt_mailbox_chunks read plain fields owned by owner(i): call them from
 * owner(i), or after owner(i) is joined (thread join orders the reads).
 * fdt_mailboxes_create/destroy run with no other operation in flight.
 *
 * Waking: an idle consumer blocks in fdt_mailbox_wait(), which sleeps on a
 * per-endpoint mutex + condition variable used only on this slow path. A
 * post that finds the inbox empty (and only then) checks whether the
 * receiver is asleep and signals it; kick does the same without a message.
 * The ordering argument against lost wakeups is in src/par/mailbox.c, at
 * fdt_mailbox_wait().
 *
 * Counters: each endpoint counts messages sent (by post from it) and
 * received (by poll on it), per kind. They are plain integers written only
 * by the owner thread; at the end of a run, the sum over threads of sent[k]
 * equals the sum of received[k] for every kind k once every inbox is empty.
 */
#ifndef FDT_MAILBOX_H
#define FDT_MAILBOX_H

#include <stdalign.h>
#include <stddef.h>
#include <stdint.h>

#include "frontdt.h"

/* The message kinds (fdt_msg_kind, Merriam §4) are public, in
 * include/frontdt.h, with their names (fdt_msg_kind_name); their payloads
 * and handlers are one table in src/par/protocol.c. 0 is not a kind: a freshly
 * allocated message has kind 0 and fdt_mailbox_post refuses it, so a
 * forgotten kind is an error, not a silent IAMDONE. */

/* A vertex id slot holding no vertex (equal to FDT_NONE of src/geom/kdtree.h). */
#define FDT_MSG_NONE UINT32_MAX

/* Vertex ids in messages are global ids (uint32, tree order). */

/* FACESEND: "here is a face of yours". v is oriented: the tet the sender
 * built (or is asking the receiver to build) lies on the side given by the
 * lead's convention in src/front/front.c. apex == FDT_MSG_NONE: just add the face to
 * the receiver's front; otherwise the sender found apex for this face and
 * asks the receiver, owner of tet(v, apex), to build that tet. tet is the
 * sender's tet on the closed side of the face, or -1. */
typedef struct fdt_msg_facesend {
    uint32_t v[3];
    uint32_t apex;
    fdt_tid tet;
} fdt_msg_facesend;

/* FACERECV: acknowledgement of a FACESEND (same tag): the face's ids and a
 * status code whose meaning the sender and receiver agree on. */
typedef struct fdt_msg_facerecv {
    uint32_t v[3];
    int32_t status;
} fdt_msg_facerecv;

/* NODESEND: range query. In message mode the receiver cannot read the
 * sender's points, so the face's coordinates travel with their ids. best is
 * the sender's best apex so far (FDT_MSG_NONE: none yet) with its
 * coordinates; the receiver answers whether one of its points beats it. The
 * query id is the message tag. */
typedef struct fdt_msg_nodesend {
    double xyz[3][3];       /* coordinates of v[0], v[1], v[2] */
    double best_xyz[3];     /* coordinates of best (unused if none) */
    uint32_t v[3];
    uint32_t best;
} fdt_msg_nodesend;

/* NODERECV: answer to the NODESEND with the same tag (query id). best is the
 * receiver's better point, or FDT_MSG_NONE if it has none; tested counts the
 * points it examined (for statistics). */
typedef struct fdt_msg_noderecv {
    double best_xyz[3];
    uint32_t best;
    uint32_t tested;
} fdt_msg_noderecv;

/* ABORT: the sender failed with err (an FDT_E* code); part is the part
 * that failed (the sender, or the calling thread's endpoint). */
typedef struct fdt_msg_abort {
    int32_t err;
    int32_t part;
} fdt_msg_abort;

/* IAMDONE: a termination-protocol counter and epoch (src/par/termination.c). */
typedef struct fdt_msg_iamdone {
    uint64_t epoch;
    int64_t count;
} fdt_msg_iamdone;

/*
 * A message: one node of the intrusive queues, exactly two cache lines.
 * next and sender belong to the mailbox: never write them. The rest is the
 * caller's: kind, tag (FACESEND/FACERECV: a tag echoed by the reply;
 * NODESEND/NODERECV: the query id; IAMDONE: free), and the payload for kind.
 */
typedef struct fdt_msg {
    alignas(64) struct fdt_msg *next; /* internal link (inbox, free list) */
    uint16_t kind;                    /* fdt_msg_kind */
    uint16_t sender;                  /* internal: endpoint that allocated it */
    uint32_t tag;
    union {
        fdt_msg_iamdone iamdone;
        fdt_msg_nodesend nodesend;
        fdt_msg_noderecv noderecv;
        fdt_msg_facesend facesend;
        fdt_msg_facerecv facerecv;
        fdt_msg_abort abort;
    } u;
} fdt_msg;

_Static_assert(sizeof(fdt_msg) == 128, "a message is two cache lines");
_Static_assert(alignof(fdt_msg) == 64, "messages start on a cache line");

/* The most endpoints in a set: sender ids are 16 bits. */
#define FDT_MAILBOX_MAX_THREADS 65535

typedef struct fdt_mailboxes fdt_mailboxes;
typedef struct fdt_mailbox fdt_mailbox;

/*
 * Creates a set of n_threads endpoints (1 <= n_threads <=
 * FDT_MAILBOX_MAX_THREADS). chunk_msgs: messages per pool chunk (0: 256).
 * max_chunks: the most chunks one endpoint's pool may hold (0: no limit);
 * at the limit fdt_mailbox_alloc fails with FDT_ENOMEM, a back-pressure
 * signal (the sender can answer its own mail and retry). No memory is
 * allocated for messages until the first alloc. *out is owned by the caller
 * (fdt_mailboxes_destroy) and NULL on failure.
 * Returns 0, FDT_EINVAL, FDT_ENOMEM, or FDT_EINTERNAL (a mutex or condition
 * variable could not be created).
 */
int fdt_mailboxes_create(fdt_mailboxes **out, int n_threads,
                         size_t chunk_msgs, size_t max_chunks);

/* Frees the set, its pools and any undelivered messages; *mbs = NULL.
 * No thread may use the set any more. NULL and *mbs == NULL are fine. */
void fdt_mailboxes_destroy(fdt_mailboxes **mbs);

int fdt_mailboxes_count(const fdt_mailboxes *mbs);

/* Endpoint i (0 <= i < count), owned by the set. */
fdt_mailbox *fdt_mailboxes_at(fdt_mailboxes *mbs, int i);

/* The endpoint's index in its set (its sender id). */
int fdt_mailbox_id(const fdt_mailbox *self);

/*
 * Sender side; self is the calling thread's own endpoint.
 */

/* Takes a message from self's pool into *out (owned by the caller until
 * posted or discarded). kind is 0, tag 0, payload zeroed. Returns 0, or
 * FDT_ENOMEM (malloc failed, or the pool holds max_chunks chunks and all of
 * its messages are in flight). */
int fdt_mailbox_alloc(fdt_mailbox *self, fdt_msg **out);

/* Gives an allocated, unposted message back to self's pool. */
void fdt_mailbox_discard(fdt_mailbox *self, fdt_msg *m);

/* Enqueues m (allocated from self, kind set) in the inbox of endpoint `to`
 * of the same set, and wakes that endpoint's owner if it sleeps in
 * fdt_mailbox_wait. Ownership of m passes to the mailbox. Counts m as sent
 * by self. Returns 1 if the inbox was empty (this post made it nonempty;
 * the wakeup check was done), 0 if it was not, FDT_EINVAL if `to` is out of
 * range, m's kind is not a kind, or m was not allocated from self (then m
 * stays the caller's). */
int fdt_mailbox_post(fdt_mailbox *self, int to, fdt_msg *m);

/* alloc + copy kind, tag and payload of *src + post. Returns as post, or
 * FDT_ENOMEM as alloc. src is borrowed. */
int fdt_mailbox_send(fdt_mailbox *self, int to, const fdt_msg *src);

/*
 * Receiver side; self is the calling thread's own endpoint.
 */

/* Takes the oldest message of self's inbox, copies it to *out (borrowed;
 * out->next is set to NULL) and returns its node to the sender's pool.
 * Counts it as received. Returns 1 if a message was taken, 0 if the inbox
 * is empty. Never blocks. */
int fdt_mailbox_poll(fdt_mailbox *self, fdt_msg *out);

/* Nonzero if poll would return a message now. */
int fdt_mailbox_pending(fdt_mailbox *self);

enum {
    FDT_MAILBOX_TIMEOUT = 0, /* the time ran out, inbox empty, no kick */
    FDT_MAILBOX_MESSAGE = 1, /* the inbox holds a message: poll returns it */
    FDT_MAILBOX_KICKED = 2   /* fdt_mailbox_kick was called (consumed) */
};

/* Blocks until self's inbox is nonempty or self was kicked, or timeout_ns
 * nanoseconds pass (timeout_ns < 0: no limit; 0: just check). Messages win
 * over a kick: a pending kick is then kept for the next wait on an empty
 * inbox. Returns FDT_MAILBOX_*, or FDT_EINTERNAL if the clock or condition
 * variable failed. No lost wakeups: every post and kick that happens before
 * or during the wait ends it. */
int fdt_mailbox_wait(fdt_mailbox *self, int64_t timeout_ns);

/* Any thread: makes the current or next fdt_mailbox_wait on target return
 * FDT_MAILBOX_KICKED (once, however many kicks arrive before it). For abort
 * flags and termination: set your flag first, then kick; the woken thread
 * then sees the flag. */
void fdt_mailbox_kick(fdt_mailbox *target);

/* Per-kind counts of messages sent (posted from self) and received (polled
 * on self), indexed by fdt_msg_kind (slot 0 unused). See the table for when
 * they may be read. */
typedef struct fdt_mailbox_counts {
    uint64_t sent[FDT_MSG_KIND_END];
    uint64_t received[FDT_MSG_KIND_END];
} fdt_mailbox_counts;

void fdt_mailbox_counts_get(const fdt_mailbox *self, fdt_mailbox_counts *c);

/* Chunks the pool of self has allocated (never decreases). */
size_t fdt_mailbox_chunks(const fdt_mailbox *self);

#endif
