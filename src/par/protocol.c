/*
 * The messages of the parallel engine; see protocol.h.
 *
 * Modes (§4). Shared: the apex search walks the own tree, then every other
 * part's tree whose box may hold a better apex (via the bisection tree, so
 * whole groups of parts are skipped at once, nearest first). Message: the
 * same walk, but for another part it sends NODESEND (face coordinates, best
 * so far) to that part's thread and waits for NODERECV, answering the
 * NODESENDs in its own mailbox meanwhile (so waiting threads cannot
 * deadlock, §4) and deferring FACESENDs until the face is done (MPI
 * ranks instead park the face and go on: src/par/engine.c, fdt_eng_resume). Message-mode
 * threads read only their own part's coordinates: a FACESEND carries the
 * coordinates of every id but the lowest (which the receiver owns), and
 * each thread caches the foreign coordinates it has been sent ("ghosts").
 */
#include "par/protocol.h"

#include <sched.h>
#include <stdlib.h>
#include <string.h>

#include "par/termination.h"


int fdt_pfq_push(pfqueue *q, const pface *f)
{
    if (q->head + q->n == q->cap) {
        if (q->head > 0) {
            memmove(q->q, q->q + q->head, q->n * sizeof *q->q);
            q->head = 0;
        }
        if (q->n == q->cap) {
            size_t ncap = q->cap ? q->cap * 2 : 64;
            pface *nq = realloc(q->q, ncap * sizeof *nq);
            if (!nq)
                return FDT_ENOMEM;
            q->q = nq;
            q->cap = ncap;
        }
    }
    q->q[q->head + q->n++] = *f;
    return FDT_OK;
}

/* The ids of face v and its apex (FDT_NONE: none) whose coordinates a
 * message-mode FACESEND carries, in payload order: all but the lowest,
 * which the receiver owns. Sender and receiver both use this order. */
static int carried_ids(const uint32_t v[3], uint32_t apex, uint32_t out[3])
{
    uint32_t ids[4] = {v[0], v[1], v[2], apex};
    int nid = apex == FDT_NONE ? 3 : 4, low = 0;
    for (int i = 1; i < nid; i++)
        if (ids[i] < ids[low])
            low = i;
    int n = 0;
    for (int i = 0; i < nid; i++)
        if (i != low)
            out[n++] = ids[i];
    return n;
}

/* Posts a FACESEND of face v (and apex, or FDT_NONE) to thread `to`,
 * adding its unit first (R1). */
int fdt_proto_send_face(worker *w, int to, const uint32_t v[3], uint32_t apex,
                     int64_t link)
{
    face_payload fp;
    memset(&fp, 0, sizeof fp);
    memcpy(fp.f.v, v, sizeof fp.f.v);
    fp.f.apex = apex;
    fp.f.tet = link;
    if (w->e->mode == FDT_MODE_MESSAGE) {
        uint32_t ids[3];
        int n = carried_ids(v, apex, ids);
        for (int j = 0; j < n; j++) {
            const double *x = coords(w, ids[j]);
            if (!x)
                return FDT_EINTERNAL;
            memcpy(fp.xyz[j], x, 3 * sizeof *x);
        }
    }
    fdt_msg *m;
    int rc = fdt_tp_alloc(w->e->tp, w->id, &m);
    if (rc)
        return rc;
    m->kind = FDT_MSG_FACESEND;
    memcpy(&m->u, &fp, sizeof fp);
    fdt_term_face_sent(w);
    if (fdt_tp_post(w->e->tp, w->id, to, m) < 0)
        return FDT_EINTERNAL;
    return FDT_OK;
}

/* Handles one FACESEND; then removes its unit (R2). */
int fdt_proto_handle_face(worker *w, const pface *pf)
{
    const fdt_msg_facesend *f = &pf->p.f;
    if (w->e->mode == FDT_MODE_MESSAGE) {
        uint32_t ids[3];
        int n = carried_ids(f->v, f->apex, ids);
        for (int j = 0; j < n; j++)
            if (!is_own(w, ids[j])) {
                int err = fdt_ghost_put(&w->ghosts, ids[j], pf->p.xyz[j]);
                if (err)
                    return err;
            }
    }
    int err;
    if (f->apex == FDT_NONE) {
        if (f->v[0] > f->v[1] || f->v[0] > f->v[2] || !is_own(w, f->v[0]))
            return FDT_EINTERNAL;
        err = w->e->ops->face_arrives(w, f->v, pf->sender, f->tet, NULL);
    } else {
        uint32_t v[4] = {f->v[0], f->v[1], f->v[2], f->apex};
        err = w->e->ops->build_requested(w, v, f->tet);
    }
    if (err)
        return err;
    return fdt_term_face_done(w, pf->sender);
}

void fdt_proto_unpack_face(const fdt_msg *m, pface *pf)
{
    memcpy(&pf->p, &m->u, sizeof pf->p);
    pf->sender = m->sender;
}

/* ---- range queries -------------------------------------------------------- */

/*
 * Shared mode, part j's mesh published: the first of j's points in the
 * pencil of the face (ia, ib, ic) is a neighbour that ia would have in
 * the DT of j's points and ia (fdt_ins_conflict_vertices: every front face
 * is a face of the DT of all points, so of the DT of j's points and the
 * face's vertices, where the first point is joined to ia, and adding the
 * other vertices takes edges from ia, never gives it new ones). Offering
 * those few to the search state replaces the kd search of j, which on
 * cylinders and cospherical sets tests thousands of points a face. The
 * faces come in runs with the same lowest vertex (the bucket order of
 * src/front/faceq.c), so the last answer is kept.
 */
/* Conflict regions larger than this are not used: a point just outside a
 * part's large flat hull facet (the cut of a grid) is in conflict with
 * every infinite tet over it, and walking them all for each query cost
 * more than the kd search (an O-grid of 40k points on two threads: 2.6 s
 * CPU with the kd search of the other part, 15.5 s with whole regions). */
#define MESH_QUERY_MAX_TETS 256

int fdt_proto_offer_from_mesh(worker *w, fdt_apex *s, int part)
{
    const fdt_ins *m = &w->e->w[part].orc.mesh;
    if (w->qcache_part != part || w->qcache_v != s->ia) {
        if (!w->qhint) {
            w->qhint = malloc((size_t)w->e->n * sizeof *w->qhint);
            if (!w->qhint)
                return FDT_ENOMEM;
            memset(w->qhint, 0xff, (size_t)w->e->n * sizeof *w->qhint);
        }
        w->qcache_part = -1;
        int rc = fdt_ins_conflict_vertices(m, s->a, &w->qhint[part], MESH_QUERY_MAX_TETS,
                                           &w->iq, &w->kq.pc);
        if (rc < 0)
            return rc;
        w->qcache_part = part;
        w->qcache_v = s->ia;
        w->qcache_big = rc == 1;
    }
    if (w->qcache_big) {
        fdt_apex_search(s, &w->e->pt->trees[part], &w->kq);
        return FDT_OK;
    }
    const double *P = w->e->P;
    for (size_t i = 0; i < w->iq.nvs; i++)
        fdt_apex_offer(s, w->iq.vs[i], P + 3 * (size_t)w->iq.vs[i], &w->kq);
    w->st.mesh_queries++;
    return FDT_OK;
}

/* Answers a NODESEND: the apex search over our own tree with the asker's
 * state rebuilt from the message (the face's and the best point's
 * coordinates; offering the asker's best to a fresh state reproduces its
 * conservative ball exactly, the same arithmetic on the same doubles). */
int fdt_proto_answer_query(worker *w, const fdt_msg *m)
{
    const fdt_msg_nodesend *q = &m->u.nodesend;
    double a[3], b[3], c[3], bx[3];
    memcpy(a, q->xyz[0], sizeof a);
    memcpy(b, q->xyz[1], sizeof b);
    memcpy(c, q->xyz[2], sizeof c);
    memcpy(bx, q->best_xyz, sizeof bx);
    fdt_apex s;
    fdt_apex_init(&s, a, b, c, q->v[0], q->v[1], q->v[2]);
    if (q->best != FDT_MSG_NONE) {
        fdt_apex_offer(&s, q->best, bx, &w->kq);
        if (s.best != q->best)
            return FDT_EINTERNAL;
    }
    size_t tested = w->kq.points;
    int rc;
    if (w->e->walls && w->orc.state == 1) {
        /* The wall engine: the part's own mesh answers (its walls_start
         * ran before any mail is read, so always). */
        if ((rc = fdt_proto_offer_from_mesh(w, &s, w->id)) != FDT_OK)
            return rc;
    } else if (w->tree->n) {
        fdt_apex_search(&s, w->tree, &w->kq);
    }
    fdt_msg *r;
    rc = fdt_tp_alloc(w->e->tp, w->id, &r);
    if (rc)
        return rc;
    r->kind = FDT_MSG_NODERECV;
    r->tag = m->tag;
    r->u.noderecv.tested = (uint32_t)(w->kq.points - tested);
    if (s.best != q->best) {
        r->u.noderecv.best = s.best;
        memcpy(r->u.noderecv.best_xyz, s.bp, sizeof r->u.noderecv.best_xyz);
    } else {
        r->u.noderecv.best = FDT_MSG_NONE;
    }
    w->st.remote_answered++;
    if (fdt_tp_post(w->e->tp, w->id, m->sender, r) < 0)
        return FDT_EINTERNAL;
    return FDT_OK;
}

/* Blocks until the mailbox holds something (or a kick), after a short
 * spin: a range query's answer usually takes microseconds. */
int fdt_proto_wait_mail(worker *w, int spin, double *acc)
{
    for (int i = 0; i < spin; i++) {
        if (fdt_tp_pending(w->e->tp, w->id) || aborted(w->e))
            return FDT_OK;
        sched_yield();
    }
    double t = fdt_now_s();
    int rc = fdt_tp_wait(w->e->tp, w->id, -1);
    *acc += fdt_now_s() - t;
    return rc < 0 ? FDT_EINTERNAL : FDT_OK;
}

/* Posts a NODESEND to part j: the face and best point of s, query id tag. */
int fdt_proto_post_query(worker *w, const fdt_apex *s, int j, uint32_t tag)
{
    fdt_msg *m;
    int rc = fdt_tp_alloc(w->e->tp, w->id, &m);
    if (rc)
        return rc;
    m->kind = FDT_MSG_NODESEND;
    m->tag = tag;
    fdt_msg_nodesend *q = &m->u.nodesend;
    memcpy(q->xyz[0], s->a, sizeof q->xyz[0]);
    memcpy(q->xyz[1], s->b, sizeof q->xyz[1]);
    memcpy(q->xyz[2], s->c, sizeof q->xyz[2]);
    q->v[0] = s->ia;
    q->v[1] = s->ib;
    q->v[2] = s->ic;
    q->best = s->best == FDT_NONE ? FDT_MSG_NONE : s->best;
    if (s->best != FDT_NONE)
        memcpy(q->best_xyz, s->bp, sizeof q->best_xyz);
    w->st.remote_queries++;
    if (fdt_tp_post(w->e->tp, w->id, j, m) < 0)
        return FDT_EINTERNAL;
    return FDT_OK;
}

/* Offers NODERECV m's better point, if any, to s (its coordinates kept in
 * qb, whose other buffer may hold s's current best). */
int fdt_proto_take_answer(worker *w, const fdt_msg *m, fdt_apex *s, qbuf *qb)
{
    if (m->u.noderecv.best != FDT_MSG_NONE) {
        double *x = qb->x[qb->next];
        qb->next ^= 1;
        memcpy(x, m->u.noderecv.best_xyz, 3 * sizeof *x);
        fdt_apex_offer(s, m->u.noderecv.best, x, &w->kq);
        /* The same exact tests accepted it over there. */
        if (s->best != m->u.noderecv.best)
            return FDT_EINTERNAL;
        w->st.remote_improved++;
    }
    return FDT_OK;
}

/* Message mode: asks part j whether it holds a better apex than s's. */
int fdt_proto_remote_query(worker *w, fdt_apex *s, int j, qbuf *qb)
{
    uint32_t qid = ++w->qid;
    int rc = fdt_proto_post_query(w, s, j, qid);
    if (rc)
        return rc;
    double t0 = fdt_now_s(), waited = 0.0;
    pwait pw = {qid, j, s, qb, 0};
    for (;;) {
        if (aborted(w->e)) {
            /* someone else's error is reported (message mode: the
             * fallback of an ABORT that could not be allocated) */
            w->aborted_by = w->e->n;
            return FDT_ECANCELED;
        }
        fdt_msg in;
        if (!fdt_tp_poll(w->e->tp, w->id, &in)) {
            if ((rc = fdt_proto_wait_mail(w, 64, &waited)) != FDT_OK)
                return rc;
            continue;
        }
        if ((rc = fdt_proto_dispatch(w, &in, &pw)) < 0)
            return rc;
        if (rc != RUN_ON)
            return FDT_EINTERNAL;
        if (pw.answered) {
            w->st.t_query_wait += fdt_now_s() - t0;
            return FDT_OK;
        }
    }
}

/* ---- the kinds: one row each ------------------------------------------------ */

/* IAMDONE: the end of the run (src/par/termination.c). */
static int on_iamdone(worker *w, const fdt_msg *m, pwait *pw)
{
    return fdt_term_on_iamdone(w, m, pw != NULL);
}

static int on_nodesend(worker *w, const fdt_msg *m, pwait *pw)
{
    (void)pw;
    return fdt_proto_answer_query(w, m);
}

/* NODERECV: the answer to the query pw waits on (the only one out: a part
 * asks one part at a time); its better point, if any, is offered. In the
 * main loop (pw NULL) it can only answer a parked face of an MPI rank. */
static int on_noderecv(worker *w, const fdt_msg *m, pwait *pw)
{
    if (!pw) {
        /* An MPI rank's parked face (src/par/engine.c): resumed by its slot. */
        return w->e->park ? w->e->ops->resume(w, m) : FDT_EINTERNAL;
    }
    if (m->tag != pw->qid || m->sender != pw->part)
        return FDT_EINTERNAL;
    int rc = fdt_proto_take_answer(w, m, pw->s, pw->qb);
    if (rc)
        return rc;
    pw->answered = 1;
    return RUN_ON;
}

/* FACESEND: handled at once in the loop; while a search waits it is
 * deferred until the face is done (the search must not change the face
 * table under it). */
static int on_facesend(worker *w, const fdt_msg *m, pwait *pw)
{
    pface pf;
    fdt_proto_unpack_face(m, &pf);
    if (pw)
        return fdt_pfq_push(&w->deferred, &pf);
    return fdt_proto_handle_face(w, &pf);
}

/* FACERECV: a FACESEND of ours was handled (message mode only,
 * src/par/termination.c). */
static int on_facerecv(worker *w, const fdt_msg *m, pwait *pw)
{
    (void)m;
    (void)pw;
    return fdt_term_ack(w);
}

/* ABORT: another part (or the calling thread) failed; we stop, also in
 * the middle of a search (message mode only). */
static int on_abort(worker *w, const fdt_msg *m, pwait *pw)
{
    (void)pw;
    if (!w->e->msg_term)
        return FDT_EINTERNAL;
    w->aborted_by = m->u.abort.part;
    return FDT_ECANCELED;
}

/*
 * The message kinds (§4): name, payload (the bytes of the message's union
 * a kind uses: what a transport that copies bytes, such as MPI, moves),
 * handler. A new kind is a number in include/frontdt.h and one row here.
 */
static const struct msg_kind_row {
    const char *name;
    size_t payload;
    int (*on)(worker *w, const fdt_msg *m, pwait *pw);
} msg_kinds[FDT_MSG_KIND_END] = {
    [FDT_MSG_IAMDONE] = {"IAMDONE", sizeof(fdt_msg_iamdone), on_iamdone},
    [FDT_MSG_NODESEND] = {"NODESEND", sizeof(fdt_msg_nodesend), on_nodesend},
    [FDT_MSG_NODERECV] = {"NODERECV", sizeof(fdt_msg_noderecv), on_noderecv},
    [FDT_MSG_FACESEND] = {"FACESEND", sizeof(face_payload), on_facesend},
    [FDT_MSG_FACERECV] = {"FACERECV", sizeof(fdt_msg_facerecv), on_facerecv},
    [FDT_MSG_ABORT] = {"ABORT", sizeof(fdt_msg_abort), on_abort},
};

const char *fdt_msg_kind_name(int kind)
{
    if (kind <= 0 || kind >= FDT_MSG_KIND_END || !msg_kinds[kind].name)
        return "?";
    return msg_kinds[kind].name;
}

size_t fdt_proto_payload_size(int kind)
{
    if (kind <= 0 || kind >= FDT_MSG_KIND_END)
        return 0;
    return msg_kinds[kind].payload;
}

int fdt_proto_dispatch(worker *w, const fdt_msg *m, pwait *pw)
{
    if (m->kind == 0 || m->kind >= FDT_MSG_KIND_END || !msg_kinds[m->kind].on)
        return FDT_EINTERNAL;
    return msg_kinds[m->kind].on(w, m, pw);
}
