/*
 * A hand-built parallel engine for the engine modules' unit tests
 * (tests/test_termination.c, tests/test_protocol.c, tests/test_gather.c):
 * n workers with no trees and no threads, and the mailbox transport with
 * the calling thread's endpoint n, so that one test thread can play every
 * part in a scripted order and read what each one posted. Only the fields
 * those modules read are set; the rest stay zero (empty tables).
 */
#ifndef FDT_TEST_ENGINEFIX_H
#define FDT_TEST_ENGINEFIX_H

#include <stdlib.h>
#include <string.h>

#include "par/engine.h"
#include "testutil.h"
#include "par/transport.h"

/* mode: FDT_MODE_SHARED or FDT_MODE_MESSAGE (then termination by
 * messages, msg_term); parts own consecutive ranges of `per` ids of P. */
static inline engine *fix_engine(int n, fdt_mode mode, const double *P, uint32_t per)
{
    engine *e = calloc(1, sizeof *e);
    CHECK(e != NULL);
    e->n = n;
    e->mode = mode;
    e->msg_term = mode == FDT_MODE_MESSAGE;
    e->P = P;
    e->ops = &fdt_eng_ops;
    e->fail_part = -1;
    CHECK_EQ(fdt_transport_mailbox(&e->tp, n + 1), FDT_OK);
    e->w = calloc((size_t)n, sizeof *e->w);
    CHECK(e->w != NULL);
    for (int i = 0; i < n; i++) {
        worker *w = &e->w[i];
        w->e = e;
        w->id = i;
        w->lo = (uint32_t)i * per;
        w->hi = (uint32_t)(i + 1) * per;
        w->parent = -1;
        w->aborted_by = -1;
    }
    return e;
}

static inline void fix_free(engine *e)
{
    for (int i = 0; i < e->n; i++) {
        worker *w = &e->w[i];
        free(w->ghosts.g);
        free(w->links.r);
        free(w->deferred.q);
        free(w->built.k);
        fdt_meshbuf_free(&w->out);
    }
    fdt_transport_destroy(&e->tp);
    free(e->toff);
    free(e->hoff);
    free(e->w);
    free(e);
}

/* The next message at endpoint `to` into *m: 1, or 0 if none. */
static inline int fix_poll(engine *e, int to, fdt_msg *m)
{
    return fdt_tp_poll(e->tp, to, m);
}

/* No message waits at any endpoint. */
static inline int fix_quiet(engine *e)
{
    fdt_msg m;
    for (int i = 0; i <= e->n; i++)
        if (fdt_tp_poll(e->tp, i, &m))
            return 0;
    return 1;
}

#endif
