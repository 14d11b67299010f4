/*
 * The set hash (issue 18): an order-independent 64-bit hash of a set of
 * tets, for runs whose tets are never all in memory at once (streaming,
 * one piece per MPI rank). Each tet's four input ids, sorted ascending
 * (the vertex set names the tet; its orientation follows from the
 * points), go through a strong 64-bit mix; the hash is the sum of the
 * mixes (mod 2^64) with the count folded in at the end. A sum does not
 * depend on the order the tets are met in, nor on how they are split
 * over threads, parts or ranks (partial sums add), so every mode, thread
 * count and rank count gives the same value for the same mesh. It is not
 * the canonical hash (fdt_result_hash, the FNV-1a of the .tets text),
 * which needs the tets sorted.
 */
#ifndef FDT_SETHASH_H
#define FDT_SETHASH_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "base/hash.h"

/* An accumulator: partial sums of disjoint sets add (fdt_sethash_merge). */
typedef struct fdt_sethash {
    uint64_t sum;
    uint64_t count;
} fdt_sethash;

/* The mix of one tet, ids in any order (sorted here by a network of five
 * compare-exchanges). Two 32-bit pairs, each mixed with SplitMix64's
 * finaliser (src/base/hash.h: every input bit flips each output bit with
 * probability close to 1/2, so sums of mixes of distinct tets do not
 * cancel by structure), chained so (a,b,c,d) and (c,d,a,b) differ. */
static inline uint64_t fdt_sethash_tet(const uint32_t t[4])
{
    uint32_t a = t[0], b = t[1], c = t[2], d = t[3], x;
#define FDT_SH_CX(p, q) \
    if (p > q) {        \
        x = p;          \
        p = q;          \
        q = x;          \
    }
    FDT_SH_CX(a, b)
    FDT_SH_CX(c, d)
    FDT_SH_CX(a, c)
    FDT_SH_CX(b, d)
    FDT_SH_CX(b, c)
#undef FDT_SH_CX
    uint64_t lo = ((uint64_t)a << 32) | b, hi = ((uint64_t)c << 32) | d;
    return fdt_mix64(fdt_mix64(lo + 0x9E3779B97F4A7C15ull) ^ hi);
}

static inline void fdt_sethash_add(fdt_sethash *h, const uint32_t t[4])
{
    h->sum += fdt_sethash_tet(t);
    h->count++;
}

/* Adds ntets tets (4 ids each). */
static inline void fdt_sethash_add_n(fdt_sethash *h, const uint32_t *tets, size_t ntets)
{
    uint64_t s = 0;
    for (size_t i = 0; i < ntets; i++)
        s += fdt_sethash_tet(tets + 4 * i);
    h->sum += s;
    h->count += ntets;
}

/* A periodic mesh's rows (issue 33), canonical (4 ids ascending, 12
 * offsets relative to the first: the row names the periodic tet): the
 * tet's mix chained with the offsets' 96 bits, so two rows of the same
 * four points in different images differ. */
static inline uint64_t fdt_sethash_periodic(const uint32_t t[4], const int8_t off[12])
{
    uint64_t a;
    uint32_t c;
    memcpy(&a, off, 8);
    memcpy(&c, off + 8, 4);
    return fdt_mix64(fdt_mix64(fdt_sethash_tet(t) ^ a) + c);
}

static inline void fdt_sethash_add_periodic(fdt_sethash *h, const uint32_t *tets,
                                            const int8_t *off, size_t ntets)
{
    uint64_t s = 0;
    for (size_t i = 0; i < ntets; i++)
        s += fdt_sethash_periodic(tets + 4 * i, off + 12 * i);
    h->sum += s;
    h->count += ntets;
}

/* The union of two disjoint sets (threads, parts, ranks). */
static inline void fdt_sethash_merge(fdt_sethash *into, const fdt_sethash *from)
{
    into->sum += from->sum;
    into->count += from->count;
}

/* The hash of the set: the count folded in, so the empty set and a set
 * whose mixes sum to 0 differ, and the whole mixed once more. */
static inline uint64_t fdt_sethash_value(const fdt_sethash *h)
{
    return fdt_mix64(h->sum ^ fdt_mix64(h->count + 0xD1B54A32D192ED03ull));
}

#endif
