/*
 * The order in which a front's faces are advanced (§2.2 leaves it open:
 * every face gets the same tet whenever it is taken, the Delaunay one on
 * its open side, so the order only decides speed and the front's size).
 *
 * Faces are kept in buckets by their lowest vertex id (v[0] of a canonical
 * face), FDT_FACEQ_SHIFT bits of id a bucket, and always taken from the
 * lowest nonempty bucket, last in first out inside it. Ids are in kd-tree
 * order (src/geom/kdtree.c permutes the points), so a bucket is one or two
 * leaves of the tree: the front sweeps through space in tree order and
 * the faces taken one after another search the same few leaves, which
 * stay in the cache. The first in first out queue this replaces grew the
 * front as a shell around the seed, visiting the whole shell (187k faces
 * at 1M uniform points) between two visits to one place; with buckets the
 * largest front is 34k faces and a 1M serial run takes 0.86 of the time
 * (bench/NOTES.md, entry 24).
 *
 * The cost: the order decides which face of each tet is searched (the
 * first to come up), and on points of one sphere, where every search is
 * exhaustive, last in first out inside a bucket wanders and makes them
 * three times slower than the old queue; first in first out inside the
 * buckets fixes that but costs CFD grids 45 % (bench/NOTES.md, entry 30).
 *
 * Faces completed while queued stay queued; the caller skips them when
 * they come up (a face table lookup it makes anyway). One owner thread:
 * no locking.
 */
#ifndef FDT_FACEQ_H
#define FDT_FACEQ_H

#include <stddef.h>
#include <stdint.h>

/* 32 ids a bucket, about two leaves of 18: 16 and 64 gave the same time,
 * 512 6 % more (1M uniform, paired runs; bench/NOTES.md entry 24). */
#define FDT_FACEQ_SHIFT 5

typedef struct fdt_faceq {
    uint32_t **face;      /* owned: bucket k's faces, 3 ids each, a stack;
                             NULL while the bucket has never held one or
                             was freed after it emptied */
    uint32_t *n, *cap;    /* owned: faces in and room of bucket k */
    uint64_t *bits;       /* owned: bit k set iff bucket k is nonempty */
    uint64_t *summary;    /* owned: bit w set iff word w of bits is nonzero */
    size_t nb, nwords;    /* buckets, words of bits */
    size_t cur;           /* no nonempty bucket below cur */
    size_t count;         /* faces queued, stale ones included */
    uint32_t base, nids;  /* lowest ids accepted: [base, base + nids) */
} fdt_faceq;

/* An empty queue for faces whose lowest id is in [base, base + nids).
 * FDT_OK or FDT_ENOMEM (then nothing is held). */
int fdt_faceq_init(fdt_faceq *q, uint32_t base, uint32_t nids);
void fdt_faceq_free(fdt_faceq *q);

/* Queues the canonical face v (v[0] its lowest id, in the queue's
 * range). FDT_OK, FDT_ENOMEM (the queue unchanged) or FDT_EINTERNAL (v[0]
 * out of range: a caller's bug). */
int fdt_faceq_push(fdt_faceq *q, const uint32_t v[3]);

/* Takes the next face into v: 1, or 0 when the queue is empty. */
int fdt_faceq_pop(fdt_faceq *q, uint32_t v[3]);

/* The face that pop will return k pops from now if nothing is pushed
 * meanwhile and it is in the same bucket, else NULL: for prefetching. */
static inline const uint32_t *fdt_faceq_ahead(const fdt_faceq *q, uint32_t k)
{
    if (q->cur >= q->nb || q->n[q->cur] <= k)
        return NULL;
    return q->face[q->cur] + 3 * (size_t)(q->n[q->cur] - 1 - k);
}

/* Drops every queued face (the buckets' memory is kept). */
void fdt_faceq_clear(fdt_faceq *q);

#endif
