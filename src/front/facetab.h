/*
 * The front's face table (§2.2): a hash table keyed on a face's vertex
 * triple. A face enters when the first tet holding it is built (it is then
 * a front face) and leaves when the second tet is built or the face is
 * found to be on the convex hull. Open addressing with linear probing and
 * backward-shift deletion (no tombstones, so a long run does not degrade).
 */
#ifndef FDT_FACETAB_H
#define FDT_FACETAB_H

#include <stddef.h>
#include <stdint.h>
#include "base/bits.h"

typedef struct fdt_face {
    uint32_t v[3];   /* oriented: the open side is orient3d(v0,v1,v2,x) > 0;
                        rotated so v[0] is the smallest id; v[0] ==
                        UINT32_MAX marks an empty slot */
    uint32_t aux;    /* caller's use (e.g. the owner partition) */
    uint64_t tet;    /* (tet id << 2) | local face index of the tet on the
                        closed side */
} fdt_face;

typedef struct fdt_facetab {
    fdt_face *slots;
    size_t cap;      /* power of two */
    size_t count;
} fdt_facetab;

int fdt_facetab_init(fdt_facetab *t, size_t expected);
void fdt_facetab_free(fdt_facetab *t);

/* Rotates (a, b, c) so the smallest id is first, keeping the orientation. */
void fdt_face_canon(uint32_t a, uint32_t b, uint32_t c, uint32_t out[3]);

/* Looks up the face with the same vertex set as the canonical triple v.
 * Returns the slot or NULL. */
fdt_face *fdt_facetab_find(const fdt_facetab *t, const uint32_t v[3]);

/* Finds f's vertex set; if absent inserts f and returns NULL with *err 0.
 * If present returns the existing slot (not modified). *err is FDT_ENOMEM
 * when growing failed. */
fdt_face *fdt_facetab_find_or_insert(fdt_facetab *t, const fdt_face *f, int *err);

/* With v[0] the smallest, the vertex set is (v0, min(v1,v2), max(v1,v2)):
 * hash that so both orientations of a face meet in the same chain. */
static inline size_t fdt_face_hash(const uint32_t v[3])
{
    uint32_t lo = v[1] < v[2] ? v[1] : v[2], hi = v[1] < v[2] ? v[2] : v[1];
    uint64_t h = (uint64_t)v[0] * 0x9E3779B97F4A7C15ull;
    h ^= (uint64_t)lo * 0xC2B2AE3D27D4EB4Full;
    h ^= (uint64_t)hi * 0x165667B19E3779F9ull;
    h ^= h >> 32;
    h *= 0xD6E8FEB86659FD93ull;
    h ^= h >> 32;
    return (size_t)h;
}

/* Asks the memory system for the slot where v's search starts: the table
 * is larger than the caches on big inputs, and the front touches it at
 * random, so a lookup whose slot was asked for early enough finds it in
 * the cache instead of waiting for memory (callers: src/front/front.c,
 * src/par/parallel.c). always_inline: see fdt_prefetch (src/base/bits.h). */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline void fdt_facetab_prefetch(const fdt_facetab *t, const uint32_t v[3])
{
    fdt_prefetch(&t->slots[fdt_face_hash(v) & (t->cap - 1)]);
}

/* The same for the three faces other than f of the tet (f0, f1, f2, d),
 * the faces a tet built on front face f adds (nothing if d is FDT_NONE,
 * UINT32_MAX). */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline void fdt_facetab_prefetch_tet(const fdt_facetab *t, const uint32_t f[3], uint32_t d)
{
    if (d == UINT32_MAX)
        return;
    uint32_t fc[3];
    /* faces 0-2 of fdt_tet_face (src/front/front.h) with the apex as vertex 3:
     * (f1, f2, d), (f0, d, f2), (f0, f1, d); only the vertex sets matter */
    fdt_face_canon(f[1], f[2], d, fc);
    fdt_facetab_prefetch(t, fc);
    fdt_face_canon(f[0], d, f[2], fc);
    fdt_facetab_prefetch(t, fc);
    fdt_face_canon(f[0], f[1], d, fc);
    fdt_facetab_prefetch(t, fc);
}

/* Removes the face in slot s (a pointer returned by find). */
void fdt_facetab_remove(fdt_facetab *t, fdt_face *s);

#endif
