/*
 * When a parallel run ends (§4 IAMDONE, §5) and how it stops on an error;
 * the proof is at the top of src/par/termination.c.
 */
#ifndef FDT_TERMINATION_H
#define FDT_TERMINATION_H

#include "par/state.h"

/* Adds this thread's activity unit before it puts a face in an empty
 * table (R1; R3: the caller holds another unit while doing so). */
static inline void ensure_active(worker *w)
{
    if (!w->active && !w->e->msg_term) {
        /* relaxed: see engine.work; our later removal of this unit is
         * sequenced after it, so it precedes it in work's order. */
        atomic_fetch_add_explicit(&w->e->work, 1, memory_order_relaxed);
        w->active = 1;
    }
}

/* Removes one unit (R2). RUN_DONE if it was the last (IAMDONEs sent). */
int fdt_term_release_unit(worker *w);

/* Before posting a FACESEND: shared mode adds its unit (R1), message mode
 * counts it in the deficit (D1). */
static inline void fdt_term_face_sent(worker *w)
{
    if (w->e->msg_term) {
        w->deficit++;
        return;
    }
    /* R1, relaxed (see engine.work): sequenced before the post, whose
     * release CAS the receiver's poll acquires before it removes the
     * unit, so the add precedes the removal in work's order. */
    atomic_fetch_add_explicit(&w->e->work, 1, memory_order_relaxed);
}

/* After a FACESEND from `sender` was handled: shared mode removes its unit
 * (R2); message mode engages (D2) or acknowledges it (D3). RUN_ON,
 * RUN_DONE or an error. */
int fdt_term_face_done(worker *w, int sender);

/* A FACERECV arrived (message mode): one fewer FACESEND outstanding. */
int fdt_term_ack(worker *w);

/* The part has nothing to do (its table is empty, its queue exhausted,
 * nothing deferred): shared mode gives up its activity unit, message mode
 * detaches if its FACESENDs are acknowledged (D4). RUN_ON, RUN_DONE or an
 * error. */
int fdt_term_idle(worker *w);

/* IAMDONE m arrived. waiting: inside a range query. */
int fdt_term_on_iamdone(worker *w, const fdt_msg *m, int waiting);

/* The calling thread's endpoint in the transport (message mode). */
static inline int fdt_term_ctl(const engine *e)
{
    return e->n;
}

/* Records the first error (thread, what) and makes every thread stop.
 * Shared mode: the error atomic and the abort flag. Message mode: called
 * by worker `thread` on its own thread, which records the error in its own
 * worker and sends ABORT to every part (not if it was itself stopped by
 * an ABORT). */
void fdt_eng_set_error(engine *e, int err, int thread, const char *what);

/* The calling thread's failure (progress cancel; thread: the thread it
 * could not create, or -1): fdt_eng_set_error in shared mode; in message
 * mode recorded in the engine (its own field) and sent as ABORT from its
 * endpoint, once. */
void fdt_term_ctl_fail(engine *e, int err, int thread, const char *what);

/* Message mode: the error of the run, after every worker is joined (0:
 * none); *thread, *what: who and why. */
int fdt_term_error(const engine *e, int *thread, const char **what);

#endif