/*
 * The messages of the parallel engine (§4): what a FACESEND carries, how a
 * part sends faces and tet requests, handles them, answers range queries
 * (NODESEND) and waits for their answers (NODERECV). See src/par/protocol.c.
 */
#ifndef FDT_PROTOCOL_H
#define FDT_PROTOCOL_H

#include <stddef.h>
#include <stdint.h>

#include "geom/kdtree.h"
#include "par/mailbox.h"

struct worker;

/* ---- FACESEND payload ------------------------------------------------- */

/*
 * The mailbox's fdt_msg_facesend (v, apex, tet), followed, in message mode,
 * by the coordinates of the message's ids other than the lowest, in the
 * order v[0], v[1], v[2], apex with the lowest skipped: the receiver owns
 * the lowest (the face's lowest for a face, the tet's lowest for a tet
 * request) and reads it from its own part. The whole payload lives in the
 * message's union (112 bytes) and is moved with memcpy.
 */
typedef struct face_payload {
    fdt_msg_facesend f;
    double xyz[3][3];
} face_payload;

_Static_assert(sizeof(face_payload) <= sizeof(((fdt_msg *)0)->u),
               "a FACESEND with coordinates fits in one message");

/* An unpacked FACESEND, also the element of the deferred queue. */
typedef struct pface {
    face_payload p;
    int sender;
} pface;


/* FIFO of FACESENDs that arrived while a message-mode search waited. */
typedef struct pfqueue {
    pface *q;
    size_t head, n, cap;
} pfqueue;

int fdt_pfq_push(pfqueue *q, const pface *f);

/* Coordinates of the best point when it came from another part: two
 * buffers, so the state's bp (the old best) stays valid while the new
 * candidate is offered. */
typedef struct qbuf {
    double x[2][3];
    int next;
} qbuf;

/* A range query a part waits on (fdt_proto_remote_query): its id, the
 * part asked, the search state and the buffers its answer goes to, and
 * whether the answer came. */
typedef struct pwait {
    uint32_t qid;
    int part;
    fdt_apex *s;
    qbuf *qb;
    int answered;
} pwait;

/* Handles message m by its kind's row (src/par/protocol.c): pw is the query
 * the part waits on, NULL in its main loop. RUN_ON, RUN_DONE or an
 * error (FDT_EINTERNAL for a kind that cannot come here). */
int fdt_proto_dispatch(struct worker *w, const fdt_msg *m, pwait *pw);
/* The bytes of the message's union kind uses (0: not a kind). */
size_t fdt_proto_payload_size(int kind);

/* Posts a FACESEND of face v (and apex, or FDT_NONE) to thread `to`,
 * adding its unit first (R1 of src/par/termination.c). link: the sender's tet
 * and face index, (tid << 2) | i, or -1. */
int fdt_proto_send_face(struct worker *w, int to, const uint32_t v[3], uint32_t apex, int64_t link);
/* Handles one FACESEND; then removes its unit (R2). RUN_ON, RUN_DONE or an
 * error. */
int fdt_proto_handle_face(struct worker *w, const pface *pf);
void fdt_proto_unpack_face(const fdt_msg *m, pface *pf);
/* Answers a NODESEND from our own tree with a NODERECV. */
int fdt_proto_answer_query(struct worker *w, const fdt_msg *m);
/* Blocks until the mailbox holds something (or a kick), after `spin`
 * yields; the seconds blocked are added to *acc. */
int fdt_proto_wait_mail(struct worker *w, int spin, double *acc);
/* Posts a NODESEND of s's face and best point to part j, query id tag. */
int fdt_proto_post_query(struct worker *w, const fdt_apex *s, int j, uint32_t tag);
/* Offers the better point of NODERECV m, if any, to s (coordinates kept
 * in qb). FDT_OK or FDT_EINTERNAL. */
int fdt_proto_take_answer(struct worker *w, const fdt_msg *m, fdt_apex *s, qbuf *qb);
/* Message mode: asks part j whether it holds a better apex than s's and
 * waits for the answer. */
int fdt_proto_remote_query(struct worker *w, fdt_apex *s, int j, qbuf *qb);

#endif