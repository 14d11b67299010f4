/* Voronoi cells streamed from the sweep: src/front/cellstream.h. */
#include "front/cellstream.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/mem.h"
#include "front/sink.h"

/* A point's progress (fdt_cellstream.state): not yet in a part, in the
 * part just over and not live after it (its cell is due now), live, its
 * cell handed on. HULL beside them: a vertex of a hull face. */
enum { UNSEEN = 0, CLOSING = 1, LIVE = 2, CLOSED = 3, PROGRESS = 3, HULL = 4, IN_CHUNK = 8 };

/* Closing points a batch at most: a batch's working memory is about 550
 * bytes a point (accumulators, neighbour lists and their face sums, its
 * tets), so a part's 2M closing points at once took 1.1 GB beside its
 * mesh; chunks of 2^18 in the part's Morton order recompute the tets
 * shared between chunks (bench/NOTES.md entry 105). */
#define CELL_CHUNK ((size_t)1 << 18)

int fdt_cellstream_init(fdt_cellstream *cs, size_t m)
{
    cs->rc = 0;
    cs->cells = cs->batches = cs->max_held = 0;
    cs->sh.a = cs->sh.b = -1;
    cs->lock_ok = 0;
    cs->state = calloc(m ? m : 1, 1);
    if (!cs->state)
        return FDT_ENOMEM;
    if (pthread_mutex_init(&cs->lock, NULL)) {
        free(cs->state);
        cs->state = NULL;
        return FDT_ENOMEM;
    }
    cs->lock_ok = 1;
    return FDT_OK;
}

void fdt_cellstream_free(fdt_cellstream *cs)
{
    free(cs->state);
    cs->state = NULL;
    if (cs->lock_ok)
        pthread_mutex_destroy(&cs->lock);
    cs->lock_ok = 0;
}

void fdt_cellheld_free(fdt_cellheld *h)
{
    free(h->tets);
    free(h->pool);
    free(h->own);
    free(h->own_hull);
    free(h->chunk);
    memset(h, 0, sizeof *h);
}

int fdt_cellheld_take(fdt_cellheld *into, fdt_cellheld *h)
{
    if (fdt_grow(&into->tets, &into->cap, 4 * (into->n + h->n), sizeof *into->tets))
        return FDT_ENOMEM;
    if (h->n)
        memcpy(into->tets + 4 * into->n, h->tets, 4 * h->n * sizeof *h->tets);
    into->n += h->n;
    h->n = 0;
    return FDT_OK;
}

uint32_t *fdt_cellheld_add(fdt_cellheld *h, size_t count)
{
    if (fdt_grow(&h->pool, &h->poolcap, 4 * (h->npool + count), sizeof *h->pool))
        return NULL;
    uint32_t *at = h->pool + 4 * h->npool;
    h->npool += count;
    return at;
}

/* The pool (held tets, then the part's) split: those with a closing
 * vertex are the batch's (moved to the pool's front), those with a live
 * one held again (a tet can be both); the rest are done with. */
static int split_pool(const uint8_t *state, fdt_cellheld *h, size_t *nbatch)
{
    /* the held tets go in front of the part's, so that one array holds
     * the pool */
    if (fdt_grow(&h->pool, &h->poolcap, 4 * (h->npool + h->n), sizeof *h->pool))
        return FDT_ENOMEM;
    if (h->npool) /* a part that emitted nothing has no pool yet (NULL) */
        memmove(h->pool + 4 * h->n, h->pool, 4 * h->npool * sizeof *h->pool);
    if (h->n)
        memcpy(h->pool, h->tets, 4 * h->n * sizeof *h->tets);
    size_t np = h->npool + h->n, nb = 0, nh = 0;
    for (size_t t = 0; t < np; t++) {
        const uint32_t *v = h->pool + 4 * t;
        int closing = 0, live = 0;
        for (int k = 0; k < 4; k++) {
            int s = state[v[k]] & PROGRESS;
            closing |= s == CLOSING;
            live |= s == LIVE;
        }
        if (live) {
            if (fdt_grow(&h->tets, &h->cap, 4 * (nh + 1), sizeof *h->tets))
                return FDT_ENOMEM;
            memcpy(h->tets + 4 * nh++, v, 4 * sizeof *v);
        }
        if (closing) {
            if (nb != t)
                memcpy(h->pool + 4 * nb, v, 4 * sizeof *v);
            nb++;
        }
    }
    h->n = nh;
    *nbatch = nb;
    return FDT_OK;
}

/* The batch handed on (under the lock), unless the run is stopping or a
 * tet was too short for the cells. */
static int hand_on(fdt_cellstream *cs, const fdt_voronoi *v)
{
    pthread_mutex_lock(&cs->lock);
    int rc = cs->rc;
    if (!rc && cs->sh.a < 0 && v && cs->sink) {
        int got = cs->sink->cells(cs->sink->user, v);
        if (got)
            rc = cs->rc = fdt_sink_code(got);
        cs->cells += fdt_voronoi_num_points(v);
        cs->batches++;
    }
    pthread_mutex_unlock(&cs->lock);
    return rc;
}

int fdt_cellstream_give(fdt_cellstream *cs, int err, const fdt_voronoi *v, const fdt_vshort *sh)
{
    if (err == FDT_ERANGE && sh->a >= 0) {
        pthread_mutex_lock(&cs->lock);
        if (cs->sh.a < 0 || fdt_edge_less(sh->a, sh->b, cs->sh.a, cs->sh.b))
            cs->sh = *sh;
        pthread_mutex_unlock(&cs->lock);
        return FDT_OK; /* the run goes on to find the least */
    }
    return err ? err : hand_on(cs, v);
}

int fdt_cellstream_part(fdt_cellstream *cs, fdt_cellheld *h, const fdt_vid *part, size_t npart,
                        const uint32_t *live, size_t nlive, const uint32_t *hull, size_t nhull,
                        int threads, char *diag, size_t dlen)
{
    uint8_t *state = cs->state;
    /* The steps: the part's points closing, then the live ones live
     * again; the hull's marked; the pool split into the batch's tets and
     * the held ones; the closing points listed; their cells computed and
     * handed on; the closing points closed. */
    for (size_t i = 0; i < npart; i++)
        state[part[i]] = (uint8_t)((state[part[i]] & HULL) | CLOSING);
    for (size_t i = 0; i < nlive; i++)
        state[live[i]] = (uint8_t)((state[live[i]] & HULL) | LIVE);
    for (size_t i = 0; i < nhull; i++)
        state[hull[i]] |= HULL;
    size_t nb;
    if (split_pool(state, h, &nb))
        return FDT_ENOMEM;
    h->npool = 0;
    pthread_mutex_lock(&cs->lock); /* both sweeps' high-water mark */
    if (h->n > cs->max_held)
        cs->max_held = h->n;
    pthread_mutex_unlock(&cs->lock);
    if (fdt_grow(&h->own, &h->owncap, npart, sizeof *h->own) ||
        !(h->own_hull = realloc(h->own_hull, npart ? npart : 1)))
        return FDT_ENOMEM;
    size_t nown = 0;
    for (size_t i = 0; i < npart; i++)
        if ((state[part[i]] & PROGRESS) == CLOSING) {
            h->own_hull[nown] = (state[part[i]] & HULL) != 0;
            h->own[nown++] = (uint32_t)part[i];
        }
    int err = FDT_OK;
    const size_t chunk = cs->chunk ? cs->chunk : CELL_CHUNK;
    for (size_t c0 = 0; c0 < nown && !err; c0 += chunk) {
        size_t c1 = nown - c0 > chunk ? c0 + chunk : nown;
        /* the chunk's tets: those of the batch with a vertex in it (all of
         * them when the batch is one chunk), as indices into the pool */
        const uint32_t *pick = NULL;
        size_t nt = nb;
        if (c1 - c0 < nown) {
            for (size_t i = c0; i < c1; i++)
                state[h->own[i]] |= IN_CHUNK;
            if (fdt_grow(&h->chunk, &h->chunkcap, nb, sizeof *h->chunk)) {
                err = FDT_ENOMEM;
                break;
            }
            nt = 0;
            for (size_t t = 0; t < nb; t++) {
                const uint32_t *v = h->pool + 4 * t;
                if ((state[v[0]] | state[v[1]] | state[v[2]] | state[v[3]]) & IN_CHUNK)
                    h->chunk[nt++] = (uint32_t)t;
            }
            for (size_t i = c0; i < c1; i++)
                state[h->own[i]] &= (uint8_t)~IN_CHUNK;
            pick = h->chunk;
        }
        fdt_vbatch b = {.xyz = cs->P, .xyz_exp = cs->p_exp, .label = cs->orig,
                        .own = h->own + c0, .nown = c1 - c0, .own_hull = h->own_hull + c0,
                        .tets = h->pool, .ntets = nt, .pick = pick, .ed = cs->ed,
                        .neighbors = cs->neighbors, .skip = cs->skip};
        memcpy(b.box, cs->box, sizeof b.box);
        fdt_voronoi *v = NULL;
        fdt_vshort sh = {-1, -1, 0};
        err = fdt_voronoi_batch(&b, threads, &v, &sh, diag, dlen);
        err = fdt_cellstream_give(cs, err, v, &sh);
        fdt_voronoi_free(&v);
    }
    for (size_t i = 0; i < nown; i++)
        state[h->own[i]] = CLOSED;
    return err;
}

/* A merged duplicate and the input id of its point. */
typedef struct dup_of {
    fdt_vid rep, id;
} dup_of;

static int dup_cmp(const void *a, const void *b)
{
    const dup_of *x = a, *y = b;
    return x->rep != y->rep ? (x->rep < y->rep ? -1 : 1) : (x->id > y->id) - (x->id < y->id);
}

int fdt_cellstream_merged(fdt_cellstream *cs, const fdt_vid *dupmap, size_t n, const double *P,
                          const fdt_vid *orig, size_t m)
{
    size_t k = 0;
    for (size_t i = 0; i < n; i++)
        k += dupmap[i] != (fdt_vid)i;
    if (!k)
        return FDT_OK;
    dup_of *d = malloc(k * sizeof *d);
    fdt_vid *ids = malloc(k * sizeof *ids);
    double *pts = malloc(3 * k * sizeof *pts);
    int err = d && ids && pts ? FDT_OK : FDT_ENOMEM;
    for (size_t i = 0, j = 0; !err && i < n; i++)
        if (dupmap[i] != (fdt_vid)i)
            d[j++] = (dup_of){dupmap[i], (fdt_vid)i};
    if (!err)
        qsort(d, k, sizeof *d, dup_cmp);
    /* each point's coordinates, as given, to the duplicates of it */
    for (size_t g = 0; !err && g < m; g++) {
        size_t lo = 0, hi = k;
        while (lo < hi) {
            size_t mid = lo + (hi - lo) / 2;
            if (d[mid].rep < orig[g])
                lo = mid + 1;
            else
                hi = mid;
        }
        for (; lo < k && d[lo].rep == orig[g]; lo++)
            for (int c = 0; c < 3; c++)
                pts[3 * lo + (size_t)c] = ldexp(P[3 * g + (size_t)c], -cs->p_exp);
    }
    for (size_t j = 0; !err && j < k; j++)
        ids[j] = d[j].id;
    fdt_voronoi *v = NULL;
    if (!err)
        err = fdt_voronoi_merged(ids, pts, k, cs->box, cs->neighbors, cs->skip, &v);
    if (!err)
        err = hand_on(cs, v);
    fdt_voronoi_free(&v);
    free(d);
    free(ids);
    free(pts);
    return err;
}
