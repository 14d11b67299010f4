/*
 * When a parallel run ends (§4 IAMDONE, §5) and how it stops on an error;
 * the proof is at the top of src/termination.c.
 */
#ifndef FDT_TERMINATION_H
#define FDT_TERMINATION_H

#include "engine.h"

/* Adds this thread's activity unit before it puts a face in an empty
 * table (R1; R3: the caller holds another unit while doing so). */
static inline void ensure_active(worker *w)
{
    if (!w->active) {
        /* relaxed: see engine.work; our later removal of this unit is
         * sequenced after it, so it precedes it in work's order. */
        atomic_fetch_add_explicit(&w->e->work, 1, memory_order_relaxed);
        w->active = 1;
    }
}

/* Removes one unit (R2). RUN_DONE if it was the last (IAMDONEs sent). */
int fdt_term_release_unit(worker *w);

/* Records the first error (thread, what) and makes every thread stop. */
void fdt_eng_set_error(engine *e, int err, int thread, const char *what);

#endif