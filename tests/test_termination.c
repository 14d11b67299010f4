/*
 * Termination and errors of the parallel engine (src/par/termination.c), each
 * rule on a scripted sequence played by one thread over a hand-built
 * engine (tests/enginefix.h):
 * - shared mode: the unit counter (R1-R3): the last release sends IAMDONE
 *   to every other part, a release below zero is a bug, IAMDONE while a
 *   part still holds work is refused;
 * - message mode: Dijkstra-Scholten over FACESEND/FACERECV (D1-D5): a
 *   disengaged part is engaged by its first FACESEND and holds its
 *   acknowledgement back, others are acknowledged at once, a part detaches
 *   only with a zero deficit, the roots' trees end at part 0, which ends
 *   the run; every inconsistent message is FDT_EINTERNAL;
 * - errors: the first error wins in shared mode; a message-mode failure
 *   sends ABORT to every other part, once; the calling thread's failure
 *   too; an ABORT that cannot be allocated falls back to the flag and
 *   kicks every part; fdt_term_error names who failed.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "enginefix.h"
#include "par/termination.h"

static long long work(engine *e)
{
    return atomic_load(&e->work);
}

/* Expects exactly one message at `to`, of kind and sender; returns it. */
static fdt_msg expect_msg(engine *e, int to, int kind, int sender)
{
    fdt_msg m;
    memset(&m, 0, sizeof m);
    int got = fix_poll(e, to, &m);
    EXPECTF(got == 1 && m.kind == kind && m.sender == sender,
            "at %d: got %d, kind %d from %d; wanted kind %d from %d", to, got, m.kind,
            m.sender, kind, sender);
    fdt_msg more;
    EXPECTF(!fix_poll(e, to, &more), "at %d: one message only", to);
    return m;
}

static void test_shared_units(void)
{
    engine *e = fix_engine(3, FDT_MODE_SHARED, NULL, 10);
    worker *w0 = &e->w[0], *w1 = &e->w[1], *w2 = &e->w[2];
    /* R1: a part with work holds one unit, added once */
    ensure_active(w0);
    ensure_active(w0);
    EXPECT(work(e) == 1 && w0->active);
    /* a FACESEND's unit, added before its post */
    fdt_term_face_sent(w0);
    EXPECT(work(e) == 2);
    /* part 0 runs dry: gives up its unit; the FACESEND's is still out */
    EXPECT(fdt_term_idle(w0) == RUN_ON);
    EXPECT(!w0->active && work(e) == 1);
    /* a part that is not active, or whose table is not empty, keeps on */
    EXPECT(fdt_term_idle(w0) == RUN_ON && work(e) == 1);
    EXPECT(fix_quiet(e));
    /* part 1 handles the FACESEND under its own new unit, then idles */
    ensure_active(w1);
    EXPECT(work(e) == 2);
    EXPECT(fdt_term_face_done(w1, 0) == RUN_ON); /* R2: the FACESEND's unit */
    EXPECT(work(e) == 1);
    /* an IAMDONE cannot come while a part holds work */
    fdt_msg m = {0};
    m.kind = FDT_MSG_IAMDONE;
    EXPECT(fdt_term_on_iamdone(w1, &m, 0) == FDT_EINTERNAL);
    /* the last unit: part 1 ends the run, IAMDONE to the two others */
    EXPECT(fdt_term_idle(w1) == RUN_DONE);
    EXPECT(work(e) == 0);
    fdt_msg a = expect_msg(e, 0, FDT_MSG_IAMDONE, 1);
    fdt_msg b = expect_msg(e, 2, FDT_MSG_IAMDONE, 1);
    EXPECT(a.u.iamdone.epoch == 1 && b.u.iamdone.epoch == 1);
    EXPECT(fix_quiet(e));
    EXPECT(fdt_term_on_iamdone(w0, &a, 0) == RUN_DONE);
    EXPECT(fdt_term_on_iamdone(w2, &b, 0) == RUN_DONE);
    /* ... but not inside a range query (a part asks only holding a face) */
    EXPECT(fdt_term_on_iamdone(w2, &b, 1) == FDT_EINTERNAL);
    /* a release below zero: a unit removed twice */
    EXPECT(fdt_term_release_unit(w2) == FDT_EINTERNAL);
    /* FACERECV is message mode's alone */
    EXPECT(fdt_term_ack(w2) == FDT_EINTERNAL);
    fix_free(e);
}

/* One root (part 1) whose tree spans all three parts. */
static void test_message_tree(void)
{
    engine *e = fix_engine(3, FDT_MODE_MESSAGE, NULL, 10);
    worker *w0 = &e->w[0], *w1 = &e->w[1], *w2 = &e->w[2];
    e->roots = 1;
    w1->engaged = 1;
    /* message mode adds no units, shared or per part */
    ensure_active(w1);
    EXPECT(!w1->active && work(e) == 0);
    /* D1: 1 -> 2 */
    fdt_term_face_sent(w1);
    EXPECT(w1->deficit == 1 && work(e) == 0);
    /* D2: 2 was disengaged: engaged under 1, no acknowledgement yet */
    EXPECT(fdt_term_face_done(w2, 1) == RUN_ON);
    EXPECT(w2->engaged && w2->parent == 1);
    EXPECT(fix_quiet(e));
    /* 2 -> 0 engages 0 under 2 */
    fdt_term_face_sent(w2);
    EXPECT(fdt_term_face_done(w0, 2) == RUN_ON);
    EXPECT(w0->engaged && w0->parent == 2);
    /* D3: a second FACESEND 1 -> 2 is acknowledged at once */
    fdt_term_face_sent(w1);
    EXPECT(w1->deficit == 2);
    EXPECT(fdt_term_face_done(w2, 1) == RUN_ON);
    expect_msg(e, 1, FDT_MSG_FACERECV, 2);
    EXPECT(fdt_term_ack(w1) == RUN_ON && w1->deficit == 1);
    /* D4: 2 cannot detach while its FACESEND to 0 is out, nor 1 */
    EXPECT(fdt_term_idle(w2) == RUN_ON && w2->engaged);
    EXPECT(fdt_term_idle(w1) == RUN_ON && w1->engaged);
    /* ... nor a part with something deferred */
    w0->deferred.n = 1;
    EXPECT(fdt_term_idle(w0) == RUN_ON && w0->engaged);
    w0->deferred.n = 0;
    EXPECT(fix_quiet(e));
    /* 0 detaches: the held-back acknowledgement goes to its parent */
    EXPECT(fdt_term_idle(w0) == RUN_ON);
    EXPECT(!w0->engaged && w0->parent == -1);
    expect_msg(e, 2, FDT_MSG_FACERECV, 0);
    /* idle again: disengaged, nothing more */
    EXPECT(fdt_term_idle(w0) == RUN_ON);
    EXPECT(fix_quiet(e));
    EXPECT(fdt_term_ack(w2) == RUN_ON && w2->deficit == 0);
    EXPECT(fdt_term_idle(w2) == RUN_ON && !w2->engaged);
    expect_msg(e, 1, FDT_MSG_FACERECV, 2);
    EXPECT(fdt_term_ack(w1) == RUN_ON && w1->deficit == 0);
    /* an acknowledgement nobody owes */
    EXPECT(fdt_term_ack(w1) == FDT_EINTERNAL);
    w1->deficit = 0;
    /* the root detaches: its tree is reported to part 0 (epoch 1) */
    EXPECT(fdt_term_idle(w1) == RUN_ON && !w1->engaged);
    fdt_msg t = expect_msg(e, 0, FDT_MSG_IAMDONE, 1);
    EXPECT(t.u.iamdone.epoch == 1);
    /* an epoch-1 report goes to part 0 only */
    EXPECT(fdt_term_on_iamdone(w2, &t, 0) == FDT_EINTERNAL);
    /* D5: the last tree at part 0 ends the run, epoch 2 to the others */
    EXPECT(fdt_term_on_iamdone(w0, &t, 0) == RUN_DONE);
    EXPECT(w0->trees_done == 1);
    fdt_msg d1 = expect_msg(e, 1, FDT_MSG_IAMDONE, 0);
    fdt_msg d2 = expect_msg(e, 2, FDT_MSG_IAMDONE, 0);
    EXPECT(d1.u.iamdone.epoch == 2 && d1.u.iamdone.count == 1);
    EXPECT(fdt_term_on_iamdone(w1, &d1, 0) == RUN_DONE);
    EXPECT(fdt_term_on_iamdone(w2, &d2, 0) == RUN_DONE);
    /* epoch 2 is refused inside a query, while engaged, with a deficit,
     * with faces or deferred FACESENDs, from another part than 0, or with
     * another epoch */
    EXPECT(fdt_term_on_iamdone(w2, &d2, 1) == FDT_EINTERNAL);
    w2->engaged = 1;
    EXPECT(fdt_term_on_iamdone(w2, &d2, 0) == FDT_EINTERNAL);
    w2->engaged = 0;
    w2->deficit = 1;
    EXPECT(fdt_term_on_iamdone(w2, &d2, 0) == FDT_EINTERNAL);
    w2->deficit = 0;
    w2->ft.count = 1;
    EXPECT(fdt_term_on_iamdone(w2, &d2, 0) == FDT_EINTERNAL);
    w2->ft.count = 0;
    w2->deferred.n = 1;
    EXPECT(fdt_term_on_iamdone(w2, &d2, 0) == FDT_EINTERNAL);
    w2->deferred.n = 0;
    fdt_msg bad = d2;
    bad.sender = 1;
    EXPECT(fdt_term_on_iamdone(w2, &bad, 0) == FDT_EINTERNAL);
    bad = d2;
    bad.u.iamdone.epoch = 3;
    EXPECT(fdt_term_on_iamdone(w2, &bad, 0) == FDT_EINTERNAL);
    /* a tree reported once more than there are roots */
    EXPECT(fdt_term_on_iamdone(w0, &t, 0) == FDT_EINTERNAL);
    EXPECT(fix_quiet(e));
    fix_free(e);
}

/* Two roots, part 0 one of them: part 0 reports its own tree to itself
 * (no message), the run ends at the second report; a FACESEND reaching a
 * root that already reported re-engages it under the sender's live tree
 * (the "left-over faces" of §5). */
static void test_message_two_roots(void)
{
    engine *e = fix_engine(2, FDT_MODE_MESSAGE, NULL, 10);
    worker *w0 = &e->w[0], *w1 = &e->w[1];
    e->roots = 2;
    w0->engaged = w1->engaged = 1;
    EXPECT(fdt_term_idle(w0) == RUN_ON && w0->trees_done == 1);
    EXPECT(fix_quiet(e));
    /* part 1 sends a face to part 0, which reported: re-engaged under 1 */
    fdt_term_face_sent(w1);
    EXPECT(fdt_term_face_done(w0, 1) == RUN_ON && w0->engaged && w0->parent == 1);
    EXPECT(fix_quiet(e));
    EXPECT(fdt_term_idle(w0) == RUN_ON && !w0->engaged);
    expect_msg(e, 1, FDT_MSG_FACERECV, 0);
    EXPECT(fdt_term_ack(w1) == RUN_ON);
    /* part 0 is engaged again (a face), when the last tree is reported
     * while it waits on a query: a bug */
    w0->engaged = 1;
    EXPECT(fdt_term_idle(w1) == RUN_ON);
    fdt_msg t = expect_msg(e, 0, FDT_MSG_IAMDONE, 1);
    EXPECT(fdt_term_on_iamdone(w0, &t, 1) == FDT_EINTERNAL);
    fix_free(e);
}

/* A transport whose alloc always fails and whose kicks are counted: the
 * fallback of an ABORT that cannot be allocated. */
static int g_kicks[8];
static int nomem_alloc(fdt_transport *t, int self, fdt_msg **m)
{
    (void)t;
    (void)self;
    *m = NULL;
    return FDT_ENOMEM;
}
static void count_kick(fdt_transport *t, int target)
{
    (void)t;
    g_kicks[target]++;
}

static void test_errors(void)
{
    /* shared mode: the first error is the run's; every part is kicked */
    engine *e = fix_engine(3, FDT_MODE_SHARED, NULL, 10);
    fdt_eng_set_error(e, FDT_ENOMEM, 2, "out of memory");
    fdt_eng_set_error(e, FDT_EINTERNAL, 1, "inconsistent front");
    EXPECT(atomic_load(&e->error) == FDT_ENOMEM && e->err_thread == 2 &&
           !strcmp(e->err_what, "out of memory"));
    EXPECT(aborted(e));
    /* the calling thread's failure is the same path there */
    fdt_term_ctl_fail(e, FDT_ECANCELED, -1, "canceled");
    EXPECT(atomic_load(&e->error) == FDT_ENOMEM && e->err_thread == 2);
    EXPECT(fix_quiet(e)); /* kicks, no messages */
    fix_free(e);

    /* message mode: part 1 fails, ABORT to 0 and 2, nothing shared */
    e = fix_engine(3, FDT_MODE_MESSAGE, NULL, 10);
    int th = -7;
    const char *what = NULL;
    EXPECT(fdt_term_error(e, &th, &what) == 0);
    fdt_eng_set_error(e, FDT_EINTERNAL, 1, "inconsistent front");
    EXPECT(e->w[1].err == FDT_EINTERNAL && !aborted(e) && atomic_load(&e->error) == 0);
    for (int to = 0; to < 3; to += 2) {
        fdt_msg m = expect_msg(e, to, FDT_MSG_ABORT, 1);
        EXPECT(m.u.abort.err == FDT_EINTERNAL && m.u.abort.part == 1);
    }
    EXPECT(fix_quiet(e));
    /* a part stopped by an ABORT does not send one of its own */
    e->w[2].aborted_by = 1;
    fdt_eng_set_error(e, FDT_ECANCELED, 2, "canceled");
    EXPECT(e->w[2].err == 0 && fix_quiet(e));
    /* a thread number out of range (the caller's -1) records nothing */
    fdt_eng_set_error(e, FDT_ENOMEM, -1, "out of memory");
    EXPECT(fix_quiet(e));
    EXPECT(fdt_term_error(e, &th, &what) == FDT_EINTERNAL && th == 1 &&
           !strcmp(what, "inconsistent front"));
    e->w[1].err = FDT_ENOMEM;
    EXPECT(fdt_term_error(e, &th, &what) == FDT_ENOMEM && !strcmp(what, "out of memory"));
    e->w[1].err = 0;
    /* stopped by an ABORT that nobody's error explains */
    EXPECT(fdt_term_error(e, &th, &what) == FDT_EINTERNAL && th == 2 &&
           !strcmp(what, "ABORT without an error"));
    e->w[2].aborted_by = -1;
    /* the calling thread cancels: ABORT from its endpoint (3) to every
     * part, once */
    fdt_term_ctl_fail(e, FDT_ECANCELED, -1, "canceled");
    for (int to = 0; to < 3; to++) {
        fdt_msg m = expect_msg(e, to, FDT_MSG_ABORT, 3);
        EXPECT(m.u.abort.err == FDT_ECANCELED && m.u.abort.part == 3);
    }
    fdt_term_ctl_fail(e, FDT_ETHREAD, 1, "could not create a thread");
    EXPECT(fix_quiet(e));
    EXPECT(fdt_term_error(e, &th, &what) == FDT_ECANCELED && th == -1 &&
           !strcmp(what, "canceled"));
    fix_free(e);

    /* ABORT cannot be allocated: the flag, and every part kicked */
    e = fix_engine(3, FDT_MODE_MESSAGE, NULL, 10);
    fdt_transport_ops ops = *e->tp->ops;
    const fdt_transport_ops *saved = e->tp->ops;
    ops.alloc = nomem_alloc;
    ops.kick = count_kick;
    e->tp->ops = &ops;
    fdt_eng_set_error(e, FDT_ENOMEM, 0, "out of memory");
    EXPECT(aborted(e));
    EXPECT(g_kicks[0] == 1 && g_kicks[1] == 1 && g_kicks[2] == 1);
    /* IAMDONE that cannot be allocated: the error comes back */
    e->roots = 1;
    e->w[0].engaged = 1;
    EXPECT(fdt_term_idle(&e->w[0]) == FDT_ENOMEM);
    e->tp->ops = saved;
    fix_free(e);

    /* shared mode: IAMDONE that cannot be allocated */
    e = fix_engine(2, FDT_MODE_SHARED, NULL, 10);
    ops = *e->tp->ops;
    saved = e->tp->ops;
    ops.alloc = nomem_alloc;
    e->tp->ops = &ops;
    ensure_active(&e->w[0]);
    EXPECT(fdt_term_release_unit(&e->w[0]) == FDT_ENOMEM);
    e->tp->ops = saved;
    fix_free(e);
}

int main(void)
{
    test_shared_units();
    test_message_tree();
    test_message_two_roots();
    test_errors();
    return test_report("termination");
}
