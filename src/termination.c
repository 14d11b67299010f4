/*
 * Termination and errors of the parallel engine; see termination.h.
 *
 * Termination (§4 IAMDONE, §5 "left-over faces"). One atomic counter
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
 * No untriangulated pocket remains (§5, figure 2). The paper's pockets came
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
 * Errors. A thread that fails records the first error in an atomic, raises
 * the abort flag and kicks every mailbox; every loop and every wait polls
 * the flag, so all threads exit, the caller joins them and returns the
 * error. The progress callback runs on the calling thread, which cancels
 * the same way.
 */
#include "termination.h"

void fdt_eng_set_error(engine *e, int err, int thread, const char *what)
{
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
