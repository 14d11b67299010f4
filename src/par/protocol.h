/*
 * The messages of the parallel engine (§4): how a part sends faces and tet
 * requests, handles them, answers range queries (NODESEND) and waits for
 * their answers (NODERECV). See src/par/protocol.c. What a FACESEND
 * carries, and what a part keeps of its messages, is part of the state
 * (src/par/state.h).
 */
#ifndef FDT_PROTOCOL_H
#define FDT_PROTOCOL_H

#include <stddef.h>
#include <stdint.h>

#include "par/state.h"

/*
 * What the handlers ask of the part's front: the engine's step
 * (src/par/engine.c), which sits above the messages and calls them, so
 * they call it back through this table (engine.ops).
 */
typedef struct fdt_proto_ops {
    /* A FACESEND's face arrives at its owner (fdt_eng_face_arrives). */
    int (*face_arrives)(struct worker *w, const uint32_t v[3], int thread, int64_t link,
                        fdt_face *known);
    /* A FACESEND asks us to build its tet (fdt_eng_build_requested). */
    int (*build_requested)(struct worker *w, const uint32_t v[4], int64_t mtet);
    /* NODERECV m answers a parked face (fdt_eng_resume). */
    int (*resume)(struct worker *w, const fdt_msg *m);
} fdt_proto_ops;

/* Appends f to the FIFO of FACESENDs deferred while a search waits. */
int fdt_pfq_push(pfqueue *q, const pface *f);

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
/* Offers to s the first of part's points in its pencil from part's
 * published mesh (fdt_ins_conflict_vertices; part's kd search where the
 * conflict region is too large): other parts' meshes in shared mode,
 * the part's own when it answers a NODESEND in the wall engine. */
int fdt_proto_offer_from_mesh(struct worker *w, fdt_apex *s, int part);
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