/* Face hash table; see facetab.h. */
#include "front/facetab.h"

#include <stdlib.h>
#include <string.h>
#include "frontdt.h"
#include "base/mem.h"

void fdt_face_canon(uint32_t a, uint32_t b, uint32_t c, uint32_t out[3])
{
    /* Cyclic rotations keep the orientation. */
    if (a < b && a < c) {
        out[0] = a; out[1] = b; out[2] = c;
    } else if (b < c) {
        out[0] = b; out[1] = c; out[2] = a;
    } else {
        out[0] = c; out[1] = a; out[2] = b;
    }
}

static int same_set(const uint32_t *a, const uint32_t *b)
{
    return a[0] == b[0] && ((a[1] == b[1] && a[2] == b[2]) || (a[1] == b[2] && a[2] == b[1]));
}

int fdt_facetab_init(fdt_facetab *t, size_t expected)
{
    size_t cap = 1024;
    while (cap < 2 * expected)
        cap <<= 1;
    t->slots = malloc(cap * sizeof *t->slots);
    fdt_mem_advise_huge(t->slots, cap * sizeof *t->slots);
    if (!t->slots)
        return FDT_ENOMEM;
    for (size_t i = 0; i < cap; i++)
        t->slots[i].v[0] = UINT32_MAX;
    t->cap = cap;
    t->count = 0;
    return FDT_OK;
}

void fdt_facetab_free(fdt_facetab *t)
{
    free(t->slots);
    memset(t, 0, sizeof *t);
}

fdt_face *fdt_facetab_find(const fdt_facetab *t, const uint32_t v[3])
{
    size_t mask = t->cap - 1, h = fdt_face_hash(v) & mask;
    for (;;) {
        fdt_face *s = &t->slots[h];
        if (s->v[0] == UINT32_MAX)
            return NULL;
        if (same_set(s->v, v))
            return s;
        h = (h + 1) & mask;
    }
}

static int grow(fdt_facetab *t)
{
    size_t ncap = t->cap * 2;
    fdt_face *ns = malloc(ncap * sizeof *ns);
    fdt_mem_advise_huge(ns, ncap * sizeof *ns);
    if (!ns)
        return FDT_ENOMEM;
    for (size_t i = 0; i < ncap; i++)
        ns[i].v[0] = UINT32_MAX;
    for (size_t i = 0; i < t->cap; i++) {
        if (t->slots[i].v[0] == UINT32_MAX)
            continue;
        size_t h = fdt_face_hash(t->slots[i].v) & (ncap - 1);
        while (ns[h].v[0] != UINT32_MAX)
            h = (h + 1) & (ncap - 1);
        ns[h] = t->slots[i];
    }
    free(t->slots);
    t->slots = ns;
    t->cap = ncap;
    return FDT_OK;
}

fdt_face *fdt_facetab_find_or_insert(fdt_facetab *t, const fdt_face *f, int *err)
{
    *err = FDT_OK;
    /* Keep the load at most 1/2 so probe chains stay short. */
    if (2 * (t->count + 1) > t->cap && (*err = grow(t)) != FDT_OK)
        return NULL;
    size_t mask = t->cap - 1, h = fdt_face_hash(f->v) & mask;
    for (;;) {
        fdt_face *s = &t->slots[h];
        if (s->v[0] == UINT32_MAX) {
            *s = *f;
            t->count++;
            return NULL;
        }
        if (same_set(s->v, f->v))
            return s;
        h = (h + 1) & mask;
    }
}

void fdt_facetab_remove(fdt_facetab *t, fdt_face *s)
{
    /* Backward-shift deletion: move later members of the probe chain into
     * the hole when their home slot does not lie cyclically in (hole, j]. */
    size_t mask = t->cap - 1, i = (size_t)(s - t->slots), j = i;
    for (;;) {
        j = (j + 1) & mask;
        if (t->slots[j].v[0] == UINT32_MAX)
            break;
        size_t home = fdt_face_hash(t->slots[j].v) & mask;
        int stays = (i <= j) ? (i < home && home <= j) : (i < home || home <= j);
        if (stays)
            continue;
        t->slots[i] = t->slots[j];
        i = j;
    }
    t->slots[i].v[0] = UINT32_MAX;
    t->count--;
}
