/*
 * The gather of the parallel engine; see gather.h.
 *
 * Neighbours. When a face completes, its owner knows both tets (thread,
 * local tet, face index). Both local: it links them at once. Otherwise it
 * appends the pair to its link list, and the gather, which renumbers the
 * threads' tets into one array anyway, applies the list. This replaces a
 * FACERECV reply carrying the tet id when a face completes (one to two
 * messages per boundary face, and writes into another thread's arrays) by
 * nothing at all. FACERECV, "returned for synchronization only" in §4,
 * therefore carries no tet: shared mode sends none (its counters stay 0,
 * checked like the others), message mode sends one for every FACESEND as
 * the acknowledgement its termination detection needs (src/par/termination.c).
 */
#include "par/gather.h"

#include <stdlib.h>
#include <string.h>

/* Slice k of n of [lo, hi). */
static void slice_of(size_t lo, size_t hi, size_t k, size_t n, size_t *a, size_t *b)
{
    *a = lo + (hi - lo) * k / n;
    *b = lo + (hi - lo) * (k + 1) / n;
}

/*
 * The worker's share of the gather, on its own thread once the calling
 * thread has grown thread 0's buffers to the whole mesh (fdt_gather_prepare):
 * its slice of thread 0's tets and hull faces, renumbered where they lie
 * into input numbering by the sink's one rule (fdt_sink_renumber), and its
 * slice of the other threads' ones, copied after them the same way, with
 * the neighbours shifted by their thread's first tet. Two slices, not a
 * thread its own part: the copies write fresh pages, and with two threads
 * the copying one took 31-40 ms of page faults while thread 0 took 6.
 */
void fdt_gather_copy(worker *w)
{
    const engine *e = w->e;
    const fdt_vid *orig = e->orig;
    size_t k = (size_t)w->id, n = (size_t)e->n;
    size_t ta[2], tb[2], ha[2], hb[2]; /* [0]: thread 0's, [1]: the rest */
    slice_of(0, e->toff[1], k, n, &ta[0], &tb[0]);
    slice_of(e->toff[1], e->toff[n], k, n, &ta[1], &tb[1]);
    slice_of(0, e->hoff[1], k, n, &ha[0], &hb[0]);
    slice_of(e->hoff[1], e->hoff[n], k, n, &ha[1], &hb[1]);
    for (size_t i = 0; i < n; i++) {
        const fdt_meshbuf *o = &e->w[i].out;
        int r = i > 0;
        /* thread 0's part already lies in the mesh's buffers */
        const uint32_t *st = r ? o->tets : e->gtets, *sh = r ? o->hull : e->ghull;
        size_t t0 = e->toff[i], h0 = e->hoff[i];
        size_t a = ta[r] > t0 ? ta[r] : t0, b = tb[r] < e->toff[i + 1] ? tb[r] : e->toff[i + 1];
        if (b > a)
            fdt_sink_renumber(orig, (fdt_vid *)e->gtets + 4 * a, st + 4 * (a - t0),
                              4 * (b - a));
        if (e->gnbrs && r)
            for (size_t j = 4 * a; j < 4 * b; j++) {
                int64_t x = o->nbrs[j - 4 * t0];
                e->gnbrs[j] = x < 0 ? -1 : x + (int64_t)t0;
            }
        a = ha[r] > h0 ? ha[r] : h0;
        b = hb[r] < e->hoff[i + 1] ? hb[r] : e->hoff[i + 1];
        if (b > a)
            fdt_sink_renumber(orig, (fdt_vid *)e->ghull + 3 * a, sh + 3 * (a - h0),
                              3 * (b - a));
    }
}

/*
 * The gather, first half (calling thread, every worker done and waiting):
 * each thread's offsets (and the totals at [n]), and thread 0's buffers
 * grown to the totals, so that the other parts are copied after it and
 * then freed: the peak is one mesh plus the other parts rather than two
 * meshes. The copies run on the workers (fdt_gather_copy).
 */
int fdt_gather_prepare(engine *e)
{
    size_t nt = 0, nh = 0;
    e->toff = malloc(((size_t)e->n + 1) * sizeof *e->toff);
    e->hoff = malloc(((size_t)e->n + 1) * sizeof *e->hoff);
    if (!e->toff || !e->hoff)
        return FDT_ENOMEM;
    for (int i = 0; i <= e->n; i++) {
        e->toff[i] = nt;
        e->hoff[i] = nh;
        if (i < e->n) {
            nt += e->w[i].out.ntets;
            nh += e->w[i].out.nhull;
        }
    }
    fdt_meshbuf *mb = &e->w[0].out;
    size_t tcap = nt > mb->tcap ? nt : mb->tcap;
    uint32_t *tt = realloc(mb->tets, tcap * 4 * sizeof *tt);
    if (tt)
        mb->tets = tt;
    int64_t *nn = mb->nbrs ? realloc(mb->nbrs, tcap * 4 * sizeof *nn) : NULL;
    if (nn)
        mb->nbrs = nn;
    size_t hcap = nh > mb->hcap ? nh : mb->hcap;
    uint32_t *hh = realloc(mb->hull, hcap * 3 * sizeof *hh);
    if (hh)
        mb->hull = hh;
    if (!tt || (mb->nbrs && !nn) || !hh)
        return FDT_ENOMEM;
    mb->tcap = tcap;
    mb->hcap = hcap;
    e->gtets = mb->tets;
    e->gnbrs = mb->nbrs;
    e->ghull = mb->hull;
    return FDT_OK;
}

/* The gather, second half (calling thread, after every fdt_gather_copy): the
 * mesh moves out of thread 0, the other parts are freed, and the
 * neighbours across threads are linked from the threads' link lists. */
int fdt_gather_finish(engine *e, fdt_meshbuf *mb)
{
    size_t nt = e->toff[e->n], nh = e->hoff[e->n];
    *mb = e->w[0].out;
    memset(&e->w[0].out, 0, sizeof e->w[0].out);
    mb->ntets = nt;
    mb->nhull = nh;
    for (int i = 1; i < e->n; i++)
        fdt_meshbuf_free(&e->w[i].out);
    if (!e->want_nbrs)
        return FDT_OK;
    const size_t *off = e->toff;
    for (int i = 0; i < e->n; i++) {
        const linklist *l = &e->w[i].links;
        for (size_t j = 0; j < l->n; j++) {
            const linkrec *r = &l->r[j];
            size_t ia = 4 * off[r->ta] + (size_t)r->la;
            size_t ib = 4 * off[r->tb] + (size_t)r->lb;
            mb->nbrs[ia] = (int64_t)(off[r->tb] + (size_t)(r->lb >> 2));
            mb->nbrs[ib] = (int64_t)(off[r->ta] + (size_t)(r->la >> 2));
        }
    }
    /* Every tet slot is linked except the hull faces'. */
    size_t open = 0;
    for (size_t j = 0; j < 4 * nt; j++)
        open += mb->nbrs[j] < 0;
    return open != nh ? FDT_EINTERNAL : FDT_OK;
}
