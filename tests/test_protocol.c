/*
 * The messages of the parallel engine (src/par/protocol.c), driven by one
 * thread over a hand-built engine (tests/enginefix.h):
 * - each kind's payload size and name, and the refusal of kinds that are
 *   none;
 * - a FACESEND's coordinates in message mode: every id but the lowest, in
 *   the order v[0], v[1], v[2], apex, read from the own part or the ghost
 *   map (an unknown foreign id is FDT_EINTERNAL); the receiver puts the
 *   carried foreign ids in its ghost map with their own coordinates;
 *   shared mode carries none and adds a unit instead;
 * - the deferred FIFO keeps its order across compaction and growth;
 * - the dispatch rows: ABORT, FACERECV, NODERECV for the query waited on
 *   (wrong tag or sender, or none waited on: FDT_EINTERNAL), FACESEND
 *   deferred during a query;
 * - a range query and its answer: NODESEND's contents, the answer offered,
 *   an answer that the asker's exact tests reject, abort while waiting.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "enginefix.h"
#include "par/protocol.h"

/* Eight points: part 0 owns ids 0..3, part 1 ids 4..7; each coordinate
 * tells its id (x = id, y = 10 id, z = 100 id + 1). */
static double g_P[8 * 3];

static void fill_points(void)
{
    for (int i = 0; i < 8; i++) {
        g_P[3 * i] = i;
        g_P[3 * i + 1] = 10.0 * i;
        g_P[3 * i + 2] = 100.0 * i + 1;
    }
}

static int is_point(const double *x, uint32_t id)
{
    return x[0] == g_P[3 * id] && x[1] == g_P[3 * id + 1] && x[2] == g_P[3 * id + 2];
}

static void test_kinds(void)
{
    EXPECT(fdt_proto_payload_size(0) == 0);
    EXPECT(fdt_proto_payload_size(FDT_MSG_KIND_END) == 0);
    EXPECT(fdt_proto_payload_size(-1) == 0);
    EXPECT(fdt_proto_payload_size(FDT_MSG_FACESEND) == sizeof(face_payload));
    EXPECT(fdt_proto_payload_size(FDT_MSG_NODESEND) == sizeof(fdt_msg_nodesend));
    EXPECT(fdt_proto_payload_size(FDT_MSG_NODERECV) == sizeof(fdt_msg_noderecv));
    EXPECT(fdt_proto_payload_size(FDT_MSG_IAMDONE) == sizeof(fdt_msg_iamdone));
    EXPECT(fdt_proto_payload_size(FDT_MSG_FACERECV) == sizeof(fdt_msg_facerecv));
    EXPECT(fdt_proto_payload_size(FDT_MSG_ABORT) == sizeof(fdt_msg_abort));
    for (int k = 1; k < FDT_MSG_KIND_END; k++)
        EXPECTF(fdt_proto_payload_size(k) <= sizeof(((fdt_msg *)0)->u), "kind %d fits", k);
    EXPECT(!strcmp(fdt_msg_kind_name(FDT_MSG_FACESEND), "FACESEND"));
    EXPECT(!strcmp(fdt_msg_kind_name(FDT_MSG_ABORT), "ABORT"));
    EXPECT(!strcmp(fdt_msg_kind_name(0), "?"));
    EXPECT(!strcmp(fdt_msg_kind_name(FDT_MSG_KIND_END), "?"));

    engine *e = fix_engine(2, FDT_MODE_MESSAGE, g_P, 4);
    fdt_msg m;
    memset(&m, 0, sizeof m);
    EXPECT(fdt_proto_dispatch(&e->w[0], &m, NULL) == FDT_EINTERNAL);
    m.kind = FDT_MSG_KIND_END;
    EXPECT(fdt_proto_dispatch(&e->w[0], &m, NULL) == FDT_EINTERNAL);
    /* ABORT stops a message-mode part and says from whom */
    m.kind = FDT_MSG_ABORT;
    m.u.abort.part = 1;
    m.u.abort.err = FDT_ENOMEM;
    EXPECT(fdt_proto_dispatch(&e->w[0], &m, NULL) == FDT_ECANCELED);
    EXPECT(e->w[0].aborted_by == 1);
    /* FACERECV: one FACESEND fewer outstanding; none outstanding: a bug */
    m.kind = FDT_MSG_FACERECV;
    e->w[0].deficit = 1;
    EXPECT(fdt_proto_dispatch(&e->w[0], &m, NULL) == RUN_ON && e->w[0].deficit == 0);
    EXPECT(fdt_proto_dispatch(&e->w[0], &m, NULL) == FDT_EINTERNAL);
    /* NODERECV outside a query */
    m.kind = FDT_MSG_NODERECV;
    EXPECT(fdt_proto_dispatch(&e->w[0], &m, NULL) == FDT_EINTERNAL);
    fix_free(e);
    /* shared mode has no ABORT message (it has the flag) */
    e = fix_engine(2, FDT_MODE_SHARED, g_P, 4);
    m.kind = FDT_MSG_ABORT;
    EXPECT(fdt_proto_dispatch(&e->w[0], &m, NULL) == FDT_EINTERNAL);
    fix_free(e);
}

/* Sends face v (apex) from part `from` to `to` and returns the message. */
static int send_and_take(engine *e, int from, int to, const uint32_t v[3], uint32_t apex,
                         fdt_msg *m)
{
    int rc = fdt_proto_send_face(&e->w[from], to, v, apex, 42);
    if (rc != FDT_OK)
        return rc;
    CHECK(fix_poll(e, to, m) == 1);
    CHECK(m->kind == FDT_MSG_FACESEND && m->sender == from);
    return FDT_OK;
}

static void test_facesend(void)
{
    engine *e = fix_engine(2, FDT_MODE_MESSAGE, g_P, 4);
    worker *w0 = &e->w[0], *w1 = &e->w[1];
    fdt_msg m;
    pface pf;
    /* a tet request from part 0: the lowest (0) is skipped, the others in
     * order v[0], v[1], v[2], apex, the apex 5 from part 0's ghosts */
    CHECK_EQ(fdt_ghost_put(&w0->ghosts, 5, g_P + 15), FDT_OK);
    uint32_t v[3] = {2, 0, 3};
    CHECK_EQ(send_and_take(e, 0, 1, v, 5, &m), FDT_OK);
    EXPECT(w0->deficit == 1 && atomic_load(&e->work) == 0);
    fdt_proto_unpack_face(&m, &pf);
    EXPECT(pf.sender == 0 && pf.p.f.tet == 42 && pf.p.f.apex == 5);
    EXPECT(pf.p.f.v[0] == 2 && pf.p.f.v[1] == 0 && pf.p.f.v[2] == 3);
    EXPECT(is_point(pf.p.xyz[0], 2) && is_point(pf.p.xyz[1], 3) && is_point(pf.p.xyz[2], 5));
    /* a face with no apex, the lowest in the middle: two carried */
    uint32_t f[3] = {6, 1, 5};
    CHECK_EQ(fdt_ghost_put(&w0->ghosts, 6, g_P + 18), FDT_OK);
    CHECK_EQ(send_and_take(e, 0, 1, f, FDT_NONE, &m), FDT_OK);
    fdt_proto_unpack_face(&m, &pf);
    EXPECT(is_point(pf.p.xyz[0], 6) && is_point(pf.p.xyz[1], 5));
    const double zero[3] = {0, 0, 0};
    EXPECT(!memcmp(pf.p.xyz[2], zero, sizeof zero));
    EXPECT(w0->deficit == 2);
    /* a face 1, 4, 6 (part 0 has 4 among its ghosts): 4 and 6 carried;
     * at part 1 both are its own (no ghost), and the face is refused: its
     * first id, the lowest, is not part 1's */
    CHECK_EQ(fdt_ghost_put(&w0->ghosts, 4, g_P + 12), FDT_OK);
    uint32_t g[3] = {1, 4, 6};
    CHECK_EQ(send_and_take(e, 0, 1, g, FDT_NONE, &m), FDT_OK);
    fdt_proto_unpack_face(&m, &pf);
    EXPECT(is_point(pf.p.xyz[0], 4) && is_point(pf.p.xyz[1], 6));
    EXPECT(fdt_proto_handle_face(w1, &pf) == FDT_EINTERNAL);
    EXPECT(w1->ghosts.count == 0);
    /* the face 2, 0, 3 as a plain face at part 1: 2 and 3 carried and put
     * in part 1's ghosts from the places the order gives them, then the
     * face is refused (not led by its lowest) before anything is built */
    CHECK_EQ(send_and_take(e, 0, 1, v, FDT_NONE, &m), FDT_OK);
    fdt_proto_unpack_face(&m, &pf);
    EXPECT(fdt_proto_handle_face(w1, &pf) == FDT_EINTERNAL);
    const double *x2 = fdt_ghost_find(&w1->ghosts, 2), *x3 = fdt_ghost_find(&w1->ghosts, 3);
    EXPECT(x2 && is_point(x2, 2) && x3 && is_point(x3, 3));
    EXPECT(w1->ghosts.count == 2);
    EXPECT(fdt_ghost_find(&w1->ghosts, 0) == NULL); /* the lowest: not carried */
    /* an id whose coordinates the sender does not have: a bug, nothing
     * posted and no unit counted */
    uint32_t h[3] = {0, 7, 1};
    long long d = w0->deficit;
    EXPECT(fdt_proto_send_face(w0, 1, h, FDT_NONE, -1) == FDT_EINTERNAL);
    EXPECT(w0->deficit == d && fix_quiet(e));
    fix_free(e);

    /* shared mode: no coordinates, a unit per FACESEND */
    e = fix_engine(2, FDT_MODE_SHARED, g_P, 4);
    CHECK_EQ(send_and_take(e, 0, 1, h, FDT_NONE, &m), FDT_OK);
    fdt_proto_unpack_face(&m, &pf);
    EXPECT(atomic_load(&e->work) == 1);
    double none[3][3];
    memset(none, 0, sizeof none);
    EXPECT(!memcmp(pf.p.xyz, none, sizeof none));
    fix_free(e);
}

static void test_pfqueue(void)
{
    pfqueue q = {0};
    pface f;
    memset(&f, 0, sizeof f);
    int next_in = 0, next_out = 0;
    /* fill, take some from the front, fill again: the queue compacts when
     * its tail reaches the end with room at the head, grows when full */
    for (int round = 0; round < 6; round++) {
        for (int i = 0; i < 50 + 20 * round; i++) {
            f.sender = next_in++;
            CHECK_EQ(fdt_pfq_push(&q, &f), FDT_OK);
        }
        for (int i = 0; i < 30; i++) {
            EXPECTF(q.q[q.head].sender == next_out, "FIFO order at %d", next_out);
            next_out++;
            q.head++;
            q.n--;
        }
    }
    while (q.n) {
        EXPECTF(q.q[q.head].sender == next_out, "FIFO order at %d", next_out);
        next_out++;
        q.head++;
        q.n--;
    }
    EXPECT(next_out == next_in);
    free(q.q);
}

/* A face with its open side up (z > 0): a=(0,0,0), b=(1,0,0), c=(0,1,0),
 * part 0's ids 0, 1, 2 in a separate coordinate array. */
static double g_Q[8 * 3] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.3, 0.3, 1,
                            0.2, 0.2, 5, 0.3, 0.3, -1, 0, 0, 0, 0, 0, 0};

static void test_query(void)
{
    engine *e = fix_engine(2, FDT_MODE_MESSAGE, g_Q, 4);
    worker *w0 = &e->w[0], *w1 = &e->w[1];
    fdt_kdtree empty;
    memset(&empty, 0, sizeof empty);
    w0->tree = w1->tree = &empty;
    fdt_apex s;
    qbuf qb = {0};
    fdt_apex_init(&s, g_Q, g_Q + 3, g_Q + 6, 0, 1, 2);

    /* The answer is there before the question (one thread plays both):
     * query 1 of part 0, answered by part 1 with point 5 (0.3, 0.3, 1) on
     * the open side; a FACESEND that arrives meanwhile is deferred. */
    fdt_msg *m;
    CHECK_EQ(fdt_tp_alloc(e->tp, 1, &m), FDT_OK);
    m->kind = FDT_MSG_FACESEND;
    m->u.facesend.v[0] = 0;
    m->u.facesend.apex = FDT_NONE;
    CHECK(fdt_tp_post(e->tp, 1, 0, m) >= 0);
    CHECK_EQ(fdt_tp_alloc(e->tp, 1, &m), FDT_OK);
    m->kind = FDT_MSG_NODERECV;
    m->tag = w0->qid + 1;
    m->u.noderecv.best = 5;
    memcpy(m->u.noderecv.best_xyz, g_Q + 9, 3 * sizeof(double));
    CHECK(fdt_tp_post(e->tp, 1, 0, m) >= 0);
    EXPECT(fdt_proto_remote_query(w0, &s, 1, &qb) == FDT_OK);
    EXPECT(s.best == 5 && s.bp && s.bp[2] == 1 && s.bp != g_Q + 9);
    EXPECT(w0->deferred.n == 1 && w0->st.remote_queries == 1 && w0->st.remote_improved == 1);
    /* the question part 1 got: the face's coordinates and ids, no best */
    fdt_msg q;
    CHECK(fix_poll(e, 1, &q) == 1);
    EXPECT(q.kind == FDT_MSG_NODESEND && q.tag == w0->qid && q.sender == 0);
    EXPECT(q.u.nodesend.best == FDT_MSG_NONE);
    EXPECT(q.u.nodesend.v[0] == 0 && q.u.nodesend.v[1] == 1 && q.u.nodesend.v[2] == 2);
    EXPECT(!memcmp(q.u.nodesend.xyz[1], g_Q + 3, 3 * sizeof(double)));
    /* part 1 answers from its (empty) tree: nothing better */
    EXPECT(fdt_proto_dispatch(w1, &q, NULL) == FDT_OK);
    fdt_msg r;
    CHECK(fix_poll(e, 0, &r) == 1);
    EXPECT(r.kind == FDT_MSG_NODERECV && r.tag == q.tag && r.u.noderecv.best == FDT_MSG_NONE);
    EXPECT(w1->st.remote_answered == 1);

    /* The second question carries the best so far; the answer's tag is
     * not the question's: FDT_EINTERNAL. */
    CHECK_EQ(fdt_tp_alloc(e->tp, 1, &m), FDT_OK);
    m->kind = FDT_MSG_NODERECV;
    m->tag = w0->qid + 7;
    m->u.noderecv.best = FDT_MSG_NONE;
    CHECK(fdt_tp_post(e->tp, 1, 0, m) >= 0);
    EXPECT(fdt_proto_remote_query(w0, &s, 1, &qb) == FDT_EINTERNAL);
    CHECK(fix_poll(e, 1, &q) == 1);
    EXPECT(q.u.nodesend.best == 5 && !memcmp(q.u.nodesend.best_xyz, g_Q + 9, 3 * sizeof(double)));
    /* part 1 checks the asker's best with its own exact tests: point 5 is
     * on the open side, kept; nothing better in an empty tree */
    EXPECT(fdt_proto_answer_query(w1, &q) == FDT_OK);
    CHECK(fix_poll(e, 0, &r) == 1);
    EXPECT(r.u.noderecv.best == FDT_MSG_NONE);
    /* a best below the face cannot be anybody's apex: refused */
    q.u.nodesend.best = 6;
    memcpy(q.u.nodesend.best_xyz, g_Q + 15, 3 * sizeof(double));
    EXPECT(fdt_proto_answer_query(w1, &q) == FDT_EINTERNAL);

    /* an answer from another part than the one asked */
    CHECK_EQ(fdt_tp_alloc(e->tp, 2, &m), FDT_OK);
    m->kind = FDT_MSG_NODERECV;
    m->tag = w0->qid + 1;
    m->u.noderecv.best = FDT_MSG_NONE;
    CHECK(fdt_tp_post(e->tp, 2, 0, m) >= 0);
    EXPECT(fdt_proto_remote_query(w0, &s, 1, &qb) == FDT_EINTERNAL);
    CHECK(fix_poll(e, 1, &q) == 1);

    /* an answer the asker's exact tests reject (below the face) */
    CHECK_EQ(fdt_tp_alloc(e->tp, 1, &m), FDT_OK);
    m->kind = FDT_MSG_NODERECV;
    m->tag = w0->qid + 1;
    m->u.noderecv.best = 6;
    memcpy(m->u.noderecv.best_xyz, g_Q + 15, 3 * sizeof(double));
    CHECK(fdt_tp_post(e->tp, 1, 0, m) >= 0);
    EXPECT(fdt_proto_remote_query(w0, &s, 1, &qb) == FDT_EINTERNAL);
    EXPECT(s.best == 5);
    CHECK(fix_poll(e, 1, &q) == 1);

    /* ABORT while waiting: the query ends with FDT_ECANCELED */
    CHECK_EQ(fdt_tp_alloc(e->tp, 2, &m), FDT_OK);
    m->kind = FDT_MSG_ABORT;
    m->u.abort.part = 2;
    CHECK(fdt_tp_post(e->tp, 2, 0, m) >= 0);
    EXPECT(fdt_proto_remote_query(w0, &s, 1, &qb) == FDT_ECANCELED);
    EXPECT(w0->aborted_by == 2);
    CHECK(fix_poll(e, 1, &q) == 1);
    /* the abort flag (the fallback): the same, from the calling thread */
    w0->aborted_by = -1;
    atomic_store(&e->abort, 1);
    EXPECT(fdt_proto_remote_query(w0, &s, 1, &qb) == FDT_ECANCELED);
    EXPECT(w0->aborted_by == e->n);
    /* and a wait for mail returns at once */
    double acc = 0;
    EXPECT(fdt_proto_wait_mail(w0, 4, &acc) == FDT_OK && acc == 0);
    fix_free(e);
}

int main(void)
{
    fill_points();
    test_kinds();
    test_facesend();
    test_pfqueue();
    test_query();
    return test_report("protocol");
}
