/*
 * Termination and errors of the parallel engine; see termination.h.
 *
 * Termination in shared mode (§4 IAMDONE, §5 "left-over faces"); message
 * mode below. One atomic counter
 * e->work counts outstanding units: one per thread that holds local work
 * (a nonempty face table, or seeds to build: the thread is "active"), one
 * per FACESEND in flight. We count active threads rather than front faces
 * so the shared counter is touched per message and per activation, not per
 * face (counting front faces would put ~6 atomic RMWs per tet on one cache
 * line shared by every thread). Rules:
 *  (R1) A unit is added BEFORE the work it stands for becomes visible: the
 *       sender adds a FACESEND's unit before posting it; a thread adds its
 *       activity unit before inserting into an empty face table.
 *  (R2) A unit is removed only AFTER its effects are counted: a FACESEND's
 *       unit after the receiver handled it (the tet built, faces inserted
 *       under its activity unit, faces sent under their own units); an
 *       activity unit when the thread's face table is empty and its queue
 *       is exhausted.
 *  (R3) Every add is made by a thread that holds a unit it has not yet
 *       removed (its activity unit, or the unit of the FACESEND it is
 *       handling), so the counter is >= 1 before every add.
 * Hence once the counter is 0 it stays 0 (R3), and at that moment no face
 * table holds a face and no FACESEND is in flight (R1, R2): every face ever
 * created was completed by its second tet or found to be on the hull. The
 * thread whose decrement brings it to 0 sends IAMDONE to all others; every
 * thread exits on IAMDONE (or on abort). No face is lost after IAMDONE:
 * there is none left anywhere, and none can appear (R3). A thread whose
 * table empties early and later receives a face is simply active again
 * (R1), unlike §5 where it had to wait for a synchronisation.
 *
 * No untriangulated pocket remains (§5, figure 2; both modes). The paper's pockets came
 * from leaving a placeholder (NN = -1000000 Np) when the apex made a tet
 * owned by another processor, trusting that processor to build it from one
 * of its own faces; a region whose tets all belong to one processor but
 * whose bounding faces all belong to others was then never built. Here no
 * face waits on anybody else's initiative: every front face sits on its
 * owner's queue (pushed when it entered the table) until the owner takes it
 * and either finds it on the hull, builds its tet, or sends the tet to the
 * tet's owner, who builds it (or built it already) and thereby sends the
 * face back completed. So when the counter is 0 every face of every built
 * tet is completed (the tet across it is built) or a hull face. Every
 * built tet is Delaunay (exact apex search), and the perturbed Delaunay
 * tetrahedralization is unique with a connected dual graph. If some of its
 * tets were not built, a path in that graph from a seed to one of them
 * would cross a face g from a built tet to an unbuilt one u; g cannot be
 * completed (the tet across g would be u) nor on the hull (u's fourth
 * vertex lies on g's open side). So no pocket remains. tests/test_parallel.c
 * checks this with 16 and 64 threads on inputs of a few dozen points,
 * where nearly every tet straddles parts.
 *
 * Errors (shared mode). A thread that fails records the first error in an atomic, raises
 * the abort flag and kicks every mailbox; every loop and every wait polls
 * the flag, so all threads exit, the caller joins them and returns the
 * error. The progress callback runs on the calling thread, which cancels
 * the same way.
 *
 * Message mode: termination by messages alone (issue 19; §4's handshake).
 * Nothing above is shared there: each part knows only its own work and
 * the messages it sent and received, as ranks of a distributed run would.
 * FACERECV acknowledges every FACESEND, and termination is detected by
 * Dijkstra-Scholten over them. Each part keeps `engaged`, `parent` and
 * `deficit` (its FACESENDs not yet acknowledged). The roots are the parts
 * that hold seeds; they start engaged with no parent, every other part
 * disengaged. Rules:
 *  (D1) A part sends FACESEND only while engaged (it holds the face, or
 *       handles the FACESEND that made it), and counts it in its deficit.
 *  (D2) A FACESEND that reaches a disengaged part engages it: its sender
 *       becomes the parent, and the acknowledgement is held back.
 *  (D3) Every other FACESEND is acknowledged (FACERECV to its sender)
 *       once it is handled: the tet built, the face in the table or sent
 *       on under our own deficit.
 *  (D4) A part detaches when it is engaged, has nothing to do (empty face
 *       table, queue exhausted, nothing deferred) and a deficit of 0: it
 *       then acknowledges its parent's FACESEND, or, a root, reports its
 *       tree finished with IAMDONE (epoch 1) to part 0.
 *  (D5) Part 0 counts the trees reported finished; when all `roots` are,
 *       it sends IAMDONE (epoch 2) to every other part, and every part
 *       that receives it stops.
 * Invariant: the engaged parts form trees, one for each root not yet
 * reported, along parent edges; a part with a deficit d > 0 has d
 * FACESENDs outstanding, each either in flight, or at an engaged part
 * not yet acknowledged (D2/D3), and a part with a held-back
 * acknowledgement is engaged. A part's parent stays engaged while the part
 * is: its FACESEND is unacknowledged (the parent's deficit >= 1, and it
 * does not detach, D4). Hence a tree shrinks only from its leaves, and a
 * root reports (D4) only once every part that was engaged under it has
 * detached and every FACESEND sent within it has been acknowledged. A
 * reported tree never grows back: only an engaged part sends FACESEND
 * (D1), and it belongs to a live tree; a disengaged part that receives one
 * (even a root after its report, or a part that already detached) joins
 * that live tree (D2). So when part 0 has counted every root (D5) no part
 * is engaged and no FACESEND is in flight (one would keep its sender's
 * deficit > 0, so its sender engaged); no face is in any table (a part
 * with faces has something to do, so is engaged); every face ever created
 * was completed or found to be on the hull, and the argument below on
 * pockets applies unchanged. Conversely, as long as any face remains, its
 * owner is engaged, its root's tree has not been reported, and part 0
 * does not stop the run. A face that arrives after a part detached, or
 * after a root reported its tree (the §5 "left-over faces" after IAMDONE),
 * re-engages it under the sender's live tree (D2) and is built like any
 * other. Channels need not be FIFO for this (the argument never orders
 * two messages of one channel): the shuffle transport of
 * tests/test_transport.c reorders them across senders and delays them.
 * NODESEND/NODERECV play no part: a part asks only while it holds a face
 * (engaged), and waits for the answer before it can detach; the part that
 * answers needs no work of its own.
 *
 * Message mode, errors: a part that fails records its error in its own
 * worker (read by the calling thread after join) and sends ABORT to every
 * other part; a part that receives ABORT stops (also while it waits for a
 * NODERECV, which therefore never blocks for ever on a part that stopped).
 * The calling thread (progress cancel, a thread that could not be
 * created) has its own endpoint (fdt_term_ctl) and does the same. If the
 * ABORT itself cannot be allocated (out of memory) the in-process flag of
 * shared mode is the fallback, the one place message mode touches it; the
 * MPI transport (src/mpi/transport_mpi.c), where no flag is shared, keeps one
 * buffer for each other rank in reserve, so its ABORTs always go out.
 * Shared mode keeps its counter: one RMW on a shared line per FACESEND and
 * activation is cheaper than a FACERECV per FACESEND through the
 * mailboxes, and in one address space nothing is lost by sharing it.
 */
#include "par/termination.h"

/* Sends a message of kind (payload zero but for epoch/abort fields set by
 * the caller through *m) from endpoint `from` to `to`. */
static int post_simple(engine *e, int from, int to, int kind, int64_t a, int64_t b)
{
    fdt_msg *m;
    int rc = fdt_tp_alloc(e->tp, from, &m);
    if (rc)
        return rc;
    m->kind = (uint16_t)kind;
    if (kind == FDT_MSG_IAMDONE) {
        m->u.iamdone.epoch = (uint64_t)a;
        m->u.iamdone.count = b;
    } else if (kind == FDT_MSG_ABORT) {
        m->u.abort.err = (int32_t)a;
        m->u.abort.part = (int32_t)b;
    }
    return fdt_tp_post(e->tp, from, to, m) < 0 ? FDT_EINTERNAL : FDT_OK;
}

/* Message mode: ABORT from endpoint `from` to every part but itself; the
 * in-process flag if an ABORT cannot be allocated (top of file). */
static void broadcast_abort(engine *e, int from, int err)
{
    int fallback = 0;
    for (int i = 0; i < e->n; i++)
        if (i != from && post_simple(e, from, i, FDT_MSG_ABORT, err, from) != FDT_OK)
            fallback = 1;
    if (fallback) {
        /* release: pairs with aborted()'s acquire, as in shared mode */
        atomic_store_explicit(&e->abort, 1, memory_order_release);
        for (int i = 0; i < e->n; i++)
            fdt_tp_kick(e->tp, i);
    }
}

void fdt_eng_set_error(engine *e, int err, int thread, const char *what)
{
    if (e->msg_term) {
        if (thread >= 0 && thread < e->n && e->w[thread].aborted_by < 0) {
            /* the worker's own thread: its own fields */
            e->w[thread].err = err;
            broadcast_abort(e, thread, err);
        }
        return;
    }
    int expect = 0;
    if (atomic_compare_exchange_strong_explicit(&e->error, &expect, err,
                                                memory_order_acq_rel,
                                                memory_order_acquire)) {
        e->err_thread = thread;
        e->err_what = what;
    }
    atomic_store_explicit(&e->abort, 1, memory_order_release);
    for (int i = 0; i < e->n; i++)
        fdt_tp_kick(e->tp, i);
}

void fdt_term_ctl_fail(engine *e, int err, int thread, const char *what)
{
    if (!e->msg_term) {
        fdt_eng_set_error(e, err, thread, what);
        return;
    }
    if (e->ctl_err)
        return; /* every part has its ABORT already */
    e->ctl_err = err;
    e->err_thread = thread;
    e->err_what = what;
    broadcast_abort(e, fdt_term_ctl(e), err);
}

int fdt_term_error(const engine *e, int *thread, const char **what)
{
    for (int i = 0; i < e->n; i++)
        if (e->w[i].err) {
            *thread = i;
            *what = e->w[i].err == FDT_ENOMEM ? "out of memory" : "inconsistent front";
            return e->w[i].err;
        }
    if (e->ctl_err) {
        *thread = e->err_thread;
        *what = e->err_what;
        return e->ctl_err;
    }
    for (int i = 0; i < e->n; i++)
        if (e->w[i].aborted_by >= 0) {
            /* stopped by an ABORT nobody sent: a bug */
            *thread = i;
            *what = "ABORT without an error";
            return FDT_EINTERNAL;
        }
    return 0;
}

/* Sends IAMDONE to every other thread: the caller brought work to 0. */
static int broadcast_done(worker *w)
{
    for (int j = 0; j < w->e->n; j++) {
        if (j == w->id)
            continue;
        fdt_msg *m;
        int rc = fdt_tp_alloc(w->e->tp, w->id, &m);
        if (rc)
            return rc;
        m->kind = FDT_MSG_IAMDONE;
        m->u.iamdone.epoch = 1;
        m->u.iamdone.count = 0;
        if ((rc = fdt_tp_post(w->e->tp, w->id, j, m)) < 0)
            return FDT_EINTERNAL;
    }
    return RUN_DONE;
}

/* Removes one unit (R2). RUN_DONE if it was the last (IAMDONEs sent). */
int fdt_term_release_unit(worker *w)
{
    /* acq_rel: see engine.work. The RMW reads the latest value in work's
     * modification order, so 0 here means no unit is outstanding. */
    long long left = atomic_fetch_sub_explicit(&w->e->work, 1, memory_order_acq_rel) - 1;
    if (left > 0)
        return RUN_ON;
    if (left < 0)
        return FDT_EINTERNAL;
    return broadcast_done(w);
}

/* ---- message mode: Dijkstra-Scholten (top of file) -------------------------- */

/* D5 at part 0: one more tree finished; the last ends the run. */
static int tree_done(worker *w)
{
    engine *e = w->e;
    if (++w->trees_done < e->roots)
        return RUN_ON;
    if (w->trees_done > e->roots)
        return FDT_EINTERNAL;
    for (int j = 1; j < e->n; j++) {
        int rc = post_simple(e, 0, j, FDT_MSG_IAMDONE, 2, w->trees_done);
        if (rc)
            return rc;
    }
    return RUN_DONE;
}

int fdt_term_face_done(worker *w, int sender)
{
    if (!w->e->msg_term)
        return fdt_term_release_unit(w);
    if (!w->engaged) {
        /* D2: the acknowledgement waits for our detach (D4) */
        w->engaged = 1;
        w->parent = sender;
        return RUN_ON;
    }
    /* D3 */
    return post_simple(w->e, w->id, sender, FDT_MSG_FACERECV, 0, 0);
}

int fdt_term_ack(worker *w)
{
    if (!w->e->msg_term || --w->deficit < 0)
        return FDT_EINTERNAL;
    return RUN_ON;
}

int fdt_term_idle(worker *w)
{
    if (!w->e->msg_term) {
        if (w->active && w->ft.count == 0) {
            /* Queue exhausted and table empty: give up our unit (R2). */
            w->active = 0;
            return fdt_term_release_unit(w);
        }
        return RUN_ON;
    }
    if (!w->engaged || w->deficit > 0 || w->ft.count > 0 || w->deferred.n > 0)
        return RUN_ON;
    /* D4 */
    w->engaged = 0;
    if (w->parent >= 0) {
        int to = w->parent;
        w->parent = -1;
        return post_simple(w->e, w->id, to, FDT_MSG_FACERECV, 0, 0);
    }
    if (w->id == 0)
        return tree_done(w);
    return post_simple(w->e, w->id, 0, FDT_MSG_IAMDONE, 1, 0);
}

int fdt_term_on_iamdone(worker *w, const fdt_msg *m, int waiting)
{
    if (!w->e->msg_term) {
        /* Work is 0: we hold nothing; it cannot come while we wait on a
         * query (we hold a face then). */
        if (waiting || w->active || w->ft.count || w->deferred.n)
            return FDT_EINTERNAL;
        return RUN_DONE;
    }
    if (m->u.iamdone.epoch == 1) {
        /* a root's tree finished (D4), to part 0 */
        if (w->id != 0)
            return FDT_EINTERNAL;
        int rc = tree_done(w);
        /* the last tree cannot finish while we hold a face (we are then
         * engaged in a live tree) */
        return rc == RUN_DONE && waiting ? FDT_EINTERNAL : rc;
    }
    /* epoch 2, from part 0: every tree finished (D5), so we hold nothing */
    if (m->u.iamdone.epoch != 2 || m->sender != 0 || waiting || w->engaged || w->deficit ||
        w->ft.count || w->deferred.n)
        return FDT_EINTERNAL;
    return RUN_DONE;
}
