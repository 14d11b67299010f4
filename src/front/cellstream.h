/*
 * Voronoi cells streamed from the sweep (issue 32; bench/NOTES.md entry
 * 105): each cell computed as soon as its point's last tet is out, so a
 * streamed run never holds the cells of more points than its parts do.
 *
 * A point of part k (src/front/sweep.h) that is not live after it has
 * every tet of its star emitted: by part k, or by an earlier part while
 * it was live. So each part, after its emission, hands over its final
 * tets and its new live set; the points of the part that are not live
 * close, and their cells are computed from the tets held for them (every
 * emitted tet with a vertex still live) and the part's own final tets by
 * fdt_voronoi_batch (src/mesh/voronoi.h), which computes each cell from
 * its own tets and neighbours alone: the same bits as the cells of the
 * whole mesh (fdt_voronoi_compute), whatever the parts, the threads or
 * the input's order. Hull points stay live to the last part (their
 * infinite tets never close before it), which marks them.
 */
#ifndef FDT_CELLSTREAM_H
#define FDT_CELLSTREAM_H

#include <pthread.h>
#include <stddef.h>
#include <stdint.h>

#include "frontdt.h"
#include "mesh/voronoi.h"

/* What the sweeps share (one a run). */
typedef struct fdt_cellstream {
    const double *P;          /* the sweep's points, by its ids (borrowed) */
    int p_exp;                /* P is the input's coordinates times 2^p_exp */
    const fdt_vid *orig;      /* the sweep's id -> input id (borrowed) */
    uint8_t *state;           /* per sweep id: a cell's progress (owned;
                                 each sweep writes only its own points',
                                 the meeting part after both are joined) */
    double box[6];            /* the cells' box, the input's frame */
    int ed;                   /* fdt_voronoi_scale of box */
    int neighbors;            /* keep neighbours and face areas */
    unsigned skip;            /* fdt_voronoi_options.skip */
    size_t chunk;             /* closing points a batch at most (0: 2^18;
                                 tests make it small) */
    const fdt_cell_sink *sink;/* the caller's (borrowed) */
    /* Serializes the sink's calls (never two at once, as fdt_sink's) and
     * guards rc, sh and the counts: a sweep's unlock after its call
     * releases what the call wrote to the next sweep's lock. */
    pthread_mutex_t lock;
    int lock_ok;
    int rc;                   /* the sink's stop code (0: none) */
    fdt_vshort sh;            /* the least edge too short for the cells */
    size_t cells, batches;    /* handed on */
    size_t max_held;          /* the most tets one sweep held at once */
} fdt_cellstream;

/* One sweep's tets held for points still live: 4 sweep ids each. */
typedef struct fdt_cellheld {
    uint32_t *tets;
    size_t n, cap;
    uint32_t *pool;           /* scratch: this part's tets (owned) */
    size_t npool, poolcap;
    uint32_t *own;            /* scratch: the closing points */
    uint8_t *own_hull;
    size_t owncap;
    uint32_t *chunk;          /* scratch: a chunk's tets, pool indices */
    size_t chunkcap;
} fdt_cellheld;

/* The state of m points, the lock and the counts; FDT_OK or FDT_ENOMEM.
 * The rest is the caller's to set, before or after (box, ed, neighbors,
 * sink, p_exp; P and orig are fdt_sweep_emit's). */
int fdt_cellstream_init(fdt_cellstream *cs, size_t m);
void fdt_cellstream_free(fdt_cellstream *cs);
void fdt_cellheld_free(fdt_cellheld *h);

/* Appends h's tets to into's (the meeting part takes both halves');
 * FDT_OK or FDT_ENOMEM. */
int fdt_cellheld_take(fdt_cellheld *into, fdt_cellheld *h);

/* Space for this part's final tets: a pointer to 4 * count ids to fill
 * (valid until the next call on h), or NULL when out of memory. */
uint32_t *fdt_cellheld_add(fdt_cellheld *h, size_t count);

/*
 * A part is over: its points part[0 .. npart) (sweep ids), its final tets
 * added by fdt_cellheld_add, its live points live[0 .. nlive) and, in the
 * last part, its hull faces' points hull[0 .. nhull) (ids, repeats
 * allowed). The closing points' cells, in part's order, go to the sink
 * in batches of up to 2^18 computed on `threads` threads. FDT_OK; FDT_ENOMEM;
 * FDT_EINTERNAL (diag); the sink's stop code (FDT_ECANCELED, or its
 * negative FDT_E* value). A tet too short for the cells is kept in cs->sh
 * and the run goes on without handing on more cells (the caller reports
 * it when the run is over: the least one of all, whatever the order).
 */
int fdt_cellstream_part(fdt_cellstream *cs, fdt_cellheld *h, const fdt_vid *part, size_t npart,
                        const uint32_t *live, size_t nlive, const uint32_t *hull, size_t nhull,
                        int threads, char *diag, size_t dlen);

/* A batch's end (err: fdt_voronoi_batch's, or a call that gives its
 * errors): a tet too short for the cells kept in cs->sh when it is the
 * least yet (FDT_OK: the run goes on), another error returned, else v
 * handed to the sink under the lock unless the run is stopping (the
 * sink's stop code). The periodic parts' batches come this way too
 * (src/api/api.c). */
int fdt_cellstream_give(fdt_cellstream *cs, int err, const fdt_voronoi *v, const fdt_vshort *sh);
/* The run is over: the merged duplicates (dupmap: input id -> the input
 * id it was merged into; n input points) as the last batch, their points
 * found through the sweep's points P and ids orig (m of them). FDT_OK,
 * FDT_ENOMEM or the sink's stop code. */
int fdt_cellstream_merged(fdt_cellstream *cs, const fdt_vid *dupmap, size_t n, const double *P,
                          const fdt_vid *orig, size_t m);

#endif
