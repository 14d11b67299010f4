/* The front's face order: buckets by lowest vertex id; see faceq.h. */
#include "front/faceq.h"

#include <stdlib.h>
#include <string.h>
#include "base/bits.h"
#include "frontdt.h"

int fdt_faceq_init(fdt_faceq *q, uint32_t base, uint32_t nids)
{
    memset(q, 0, sizeof *q);
    q->nb = ((size_t)nids >> FDT_FACEQ_SHIFT) + 1;
    q->nwords = (q->nb + 63) / 64;
    size_t nsum = (q->nwords + 63) / 64;
    q->face = calloc(q->nb, sizeof *q->face);
    q->n = calloc(q->nb, sizeof *q->n);
    q->cap = calloc(q->nb, sizeof *q->cap);
    q->bits = calloc(q->nwords, sizeof *q->bits);
    q->summary = calloc(nsum, sizeof *q->summary);
    if (!q->face || !q->n || !q->cap || !q->bits || !q->summary) {
        fdt_faceq_free(q);
        return FDT_ENOMEM;
    }
    q->cur = q->nb;
    q->base = base;
    q->nids = nids;
    return FDT_OK;
}

void fdt_faceq_free(fdt_faceq *q)
{
    if (q->face)
        for (size_t k = 0; k < q->nb; k++)
            free(q->face[k]);
    free(q->face);
    free(q->n);
    free(q->cap);
    free(q->bits);
    free(q->summary);
    memset(q, 0, sizeof *q);
}

int fdt_faceq_push(fdt_faceq *q, const uint32_t v[3])
{
    uint32_t off = v[0] - q->base;
    if (off >= q->nids)
        return FDT_EINTERNAL;
    size_t k = off >> FDT_FACEQ_SHIFT;
    if (q->n[k] == q->cap[k]) {
        uint32_t ncap = q->cap[k] ? 2 * q->cap[k] : 16;
        if (ncap < q->cap[k]) /* 2^32 faces through 32 vertices: a bug */
            return FDT_EINTERNAL;
        uint32_t *nf = realloc(q->face[k], (size_t)ncap * 3 * sizeof *nf);
        if (!nf)
            return FDT_ENOMEM;
        q->face[k] = nf;
        q->cap[k] = ncap;
    }
    memcpy(q->face[k] + 3 * (size_t)q->n[k], v, 3 * sizeof *v);
    if (q->n[k]++ == 0) {
        q->bits[k >> 6] |= (uint64_t)1 << (k & 63);
        q->summary[k >> 12] |= (uint64_t)1 << ((k >> 6) & 63);
    }
    if (k < q->cur)
        q->cur = k;
    q->count++;
    return FDT_OK;
}

/* The lowest nonempty bucket at or above k, or nb. Two levels of bits:
 * at 10M points 312k buckets, 4.9k words, 77 summary words, so a jump
 * over empty buckets reads a few words, not every bucket. */
static size_t next_nonempty(const fdt_faceq *q, size_t k)
{
    if (k >= q->nb)
        return q->nb;
    size_t w = k >> 6;
    uint64_t m = q->bits[w] & (~(uint64_t)0 << (k & 63));
    if (m)
        return (w << 6) + (size_t)fdt_ctz64(m);
    /* words above w: the summary from bit w + 1 */
    size_t w1 = w + 1;
    if (w1 >= q->nwords)
        return q->nb;
    size_t sw = w1 >> 6, nsum = (q->nwords + 63) / 64;
    uint64_t sm = q->summary[sw] & (~(uint64_t)0 << (w1 & 63));
    while (!sm) {
        if (++sw >= nsum)
            return q->nb;
        sm = q->summary[sw];
    }
    size_t w2 = (sw << 6) + (size_t)fdt_ctz64(sm);
    return (w2 << 6) + (size_t)fdt_ctz64(q->bits[w2]);
}

int fdt_faceq_pop(fdt_faceq *q, uint32_t v[3])
{
    size_t k = q->cur;
    if (k >= q->nb || q->n[k] == 0) {
        size_t next = next_nonempty(q, k);
        /* The bucket left behind is empty: give its memory back, so the
         * buckets hold about the front, not every face ever queued. A
         * bucket emptied at cur is refilled at once more often than not
         * (the faces of the tet just built), hence here, not in the pop
         * that emptied it. */
        if (k < q->nb && q->face[k]) {
            free(q->face[k]);
            q->face[k] = NULL;
            q->cap[k] = 0;
        }
        q->cur = k = next;
        if (k >= q->nb)
            return 0;
    }
    uint32_t i = --q->n[k];
    memcpy(v, q->face[k] + 3 * (size_t)i, 3 * sizeof *v);
    if (i == 0) {
        q->bits[k >> 6] &= ~((uint64_t)1 << (k & 63));
        if (!q->bits[k >> 6])
            q->summary[k >> 12] &= ~((uint64_t)1 << ((k >> 6) & 63));
    }
    q->count--;
    return 1;
}

void fdt_faceq_clear(fdt_faceq *q)
{
    for (size_t k = next_nonempty(q, 0); k < q->nb; k = next_nonempty(q, k + 1))
        q->n[k] = 0;
    memset(q->bits, 0, q->nwords * sizeof *q->bits);
    memset(q->summary, 0, (q->nwords + 63) / 64 * sizeof *q->summary);
    q->cur = q->nb;
    q->count = 0;
}
