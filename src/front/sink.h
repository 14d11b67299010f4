/*
 * The tet sink (issue 18; DESIGN.md, Output): where the fronts' finished
 * tets and hull faces go. A tet is final the moment it is built (§2.2: no
 * flips), so a front hands it on at once and keeps only what it still
 * needs to advance (below). Three destinations, one interface:
 *   - memory: each thread's fdt_meshbuf (tree-order ids; the in-memory
 *     result, with neighbours if asked), renumbered into input numbering
 *     by fdt_sink_renumber when the run is over;
 *   - a caller's fdt_sink: each thread renumbers its tets into input
 *     numbering as it emits them, into a batch of its own, and hands full
 *     batches to the caller under the run's mutex;
 *   - nothing (the oracle's probe): tets are counted and dropped.
 * Renumbering (tree-order id i is input point orig[i]) is done here and
 * nowhere else, for the serial front and the parallel engine alike.
 *
 * What a front needs back from a built tet: for each face of the front,
 * the tet on its closed side: its id and its vertex opposite the face
 * (the insertion-mesh oracle finds the apex from them, src/front/oracle.h), and
 * with neighbours the face index, to link the two tets. Without
 * neighbours a face's link (fdt_face.tet) carries the opposite vertex
 * itself (fdt_emit_link), so no front ever reads a tet back and a
 * streamed run keeps none. The rest of what the fronts keep of built tets
 * is independent of the sink: the oracle's map from tet id to insertion-
 * mesh tet (4 bytes a tet, only while a part reads its apexes from a mesh,
 * src/front/oracle.h), the parallel engine's `built` set (the sorted ids of the
 * tets with a face owned by another part: duplicate requests, src/par/engine.c;
 * it grows with the cuts, not the volume) and its link lists (between
 * parts, with neighbours only).
 */
#ifndef FDT_SINK_H
#define FDT_SINK_H

#include <pthread.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "frontdt.h"
#include "front/meshbuf.h"
#include "base/sethash.h"

/* Tets a thread's batch holds before it goes to the caller's sink: 64k
 * tets are 1 MiB, a batch a writer handles well, and with 1024 threads
 * still only 1 GiB of buffers at most. */
#define FDT_SINK_BATCH (1u << 16)
/* Hull faces likewise (3 ids each). */
#define FDT_SINK_HBATCH (1u << 14)

typedef struct fdt_tsink {
    const fdt_vid *orig;      /* tree-order id -> input index (borrowed) */
    const fdt_sink *user;     /* NULL: memory or nothing (borrowed) */
    size_t batch, hbatch;     /* tets and hull faces a batch holds: set by
                                 fdt_tsink_init (FDT_SINK_BATCH,
                                 FDT_SINK_HBATCH); tests make them small
                                 before any fdt_emit_init */
    /* Serializes the caller's callbacks (the contract: never two at once)
     * and guards rc, hash, ntets, nhull. A thread's unlock after its
     * callback releases what the callback wrote; the next thread's lock
     * acquires it, so a caller's sink state needs no locking of its own. */
    pthread_mutex_t lock;
    int lock_ok;
    /* Under lock: the code of the first callback that asked to stop (0:
     * none). The thread whose call it was returns it at once, and the
     * engine's abort stops the others (src/par/termination.c); a batch that
     * reaches the lock later is not handed on. */
    int rc;
    fdt_sethash hash;         /* under lock: the flushed batches' sum */
    size_t ntets, nhull;      /* under lock: tets and hull faces handed on */
} fdt_tsink;

/* One thread's emitter. Only its thread uses it, except fdt_emit_flush
 * of a finished worker by the calling thread after pthread_join. */
typedef struct fdt_emit {
    fdt_tsink *s;
    fdt_meshbuf *mb;          /* memory: the thread's tets (tree-order ids);
                                 NULL when streaming or dropping */
    int packed;               /* links carry the opposite vertex (no
                                 neighbours: fdt_emit_link) */
    int64_t ntets;            /* tets emitted: the next tet id */
    size_t nhull;             /* hull faces emitted */
    fdt_vid *tb;              /* stream: batch of tets, input numbering */
    size_t tn;
    fdt_vid *hb;              /* stream: batch of hull faces */
    size_t hn;
    fdt_sethash h;            /* stream: this thread's tets so far (its
                                 partial sum, merged at fdt_emit_flush) */
} fdt_emit;

/* A sink for a run: user NULL keeps the tets in the threads' meshbufs. */
int fdt_tsink_init(fdt_tsink *s, const fdt_vid *orig, const fdt_sink *user);
void fdt_tsink_free(fdt_tsink *s);

/* A thread's emitter into s: mb is its meshbuf in memory mode (NULL when
 * s streams, or to drop the tets; then mb must not keep neighbours). */
int fdt_emit_init(fdt_emit *em, fdt_tsink *s, fdt_meshbuf *mb);
void fdt_emit_free(fdt_emit *em);

/* The bytes of em's batches (fdt_stats.mem_sink). */
static inline size_t fdt_emit_bytes(const fdt_emit *em)
{
    return em->tb ? em->s->batch * 4 * sizeof *em->tb + em->s->hbatch * 3 * sizeof *em->hb : 0;
}

/* fdt_emit_tet's every case (fdt_emit_tet inlines the commonest). */
int64_t fdt_emit_tet_any(fdt_emit *em, const uint32_t v[4]);

/* Emits positively oriented tet v (tree-order ids). Returns its id (per
 * thread, from 0), or a negative FDT_E* code: FDT_ENOMEM, or the sink's
 * stop code (FDT_ECANCELED or the caller's negative FDT_E*). Inline for
 * the in-memory mesh without neighbours while its buffer has room: one
 * copy, as the fronts did before the sink (callgrind, 200k uniform points
 * serial: the calls through src/front/sink.c cost 45 instructions a tet). */
static inline int64_t fdt_emit_tet(fdt_emit *em, const uint32_t v[4])
{
    fdt_meshbuf *mb = em->mb;
    if (mb && !mb->nbrs && mb->ntets < mb->tcap) {
        memcpy(mb->tets + 4 * mb->ntets, v, 4 * sizeof *v);
        em->ntets = (int64_t)mb->ntets + 1;
        return (int64_t)mb->ntets++;
    }
    return fdt_emit_tet_any(em, v);
}
/* fdt_emit_tet for a caller that knows each vertex's input index
 * already (in[i] = orig[v[i]]): a stream takes those, memory the tree-order
 * ids. The sweep (src/front/sweep.c) looks each point's index up once for
 * its part instead of four times a tet, reads scattered over the whole
 * orig array (9.6 % of a 4M streamed run). */
int64_t fdt_emit_tet_known(fdt_emit *em, const uint32_t v[4], const fdt_vid in[4]);
/* Emits hull face f (tree-order ids, outward). FDT_OK or as above. */
int fdt_emit_hull(fdt_emit *em, const uint32_t f[3]);
/* Hands the thread's partial batches to the caller's sink (nothing in
 * memory mode) and merges its set hash. FDT_OK or the stop code. */
int fdt_emit_flush(fdt_emit *em);

/* The link a face of tet tid keeps in the face table (fdt_face.tet): with
 * neighbours, (tid << 2) | i (the slot of the neighbour across face i);
 * without, the vertex opposite the face (v[i]) in the high half and the
 * tet id in the low half, UINT32_MAX when the id does not fit (the oracle
 * then walks to the face: slower, same answer). */
static inline uint64_t fdt_emit_link(const fdt_emit *em, int64_t tid, int i, uint32_t opp)
{
    if (!em->packed)
        return ((uint64_t)tid << 2) | (uint64_t)i;
    uint64_t t = (uint64_t)tid < UINT32_MAX ? (uint64_t)tid : UINT32_MAX;
    return ((uint64_t)opp << 32) | t;
}

/* The closed-side tet of a face whose link is `link`, set by this thread:
 * its id (-1: not known) and its vertex opposite the face. */
static inline void fdt_emit_unlink(const fdt_emit *em, uint64_t link, int64_t *tid,
                                   uint32_t *opp)
{
    if (!em->packed) {
        *tid = (int64_t)(link >> 2);
        *opp = em->mb->tets[link];
        return;
    }
    uint32_t t = (uint32_t)link;
    *tid = t == UINT32_MAX ? -1 : (int64_t)t;
    *opp = (uint32_t)(link >> 32);
}

/* Input numbering: dst[i] = orig[src[i]] for count ids (dst may be src).
 * The one renumbering of every mode's output. */
void fdt_sink_renumber(const fdt_vid *orig, fdt_vid *dst, const uint32_t *src, size_t count);

/* The code a caller's nonzero return stands for: its own value if it is a
 * negative FDT_E* code, else FDT_ECANCELED. */
static inline int fdt_sink_code(int rc)
{
    return rc < 0 && rc >= FDT_EFORMAT ? rc : FDT_ECANCELED;
}

#endif
