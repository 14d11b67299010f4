/* Per-part containers of the parallel engine; see partsets.h. */
#include "par/partsets.h"

#include <stdlib.h>
#include <string.h>

#include "frontdt.h"

static size_t key_hash(const uint32_t k[4])
{
    uint64_t h = (uint64_t)k[0] * 0x9E3779B97F4A7C15ull;
    h ^= (uint64_t)k[1] * 0xC2B2AE3D27D4EB4Full + (h >> 29);
    h ^= (uint64_t)k[2] * 0x165667B19E3779F9ull + (h >> 31);
    h ^= (uint64_t)k[3] * 0xD6E8FEB86659FD93ull + (h >> 27);
    h ^= h >> 32;
    h *= 0x94D049BB133111EBull;
    return (size_t)(h ^ (h >> 29));
}

static int tetset_grow(tetset *s)
{
    size_t ncap = s->cap ? s->cap * 2 : 1024;
    uint32_t(*nk)[4] = malloc(ncap * sizeof *nk);
    if (!nk)
        return FDT_ENOMEM;
    for (size_t i = 0; i < ncap; i++)
        nk[i][0] = UINT32_MAX;
    for (size_t i = 0; i < s->cap; i++) {
        if (s->k[i][0] == UINT32_MAX)
            continue;
        size_t h = key_hash(s->k[i]) & (ncap - 1);
        while (nk[h][0] != UINT32_MAX)
            h = (h + 1) & (ncap - 1);
        memcpy(nk[h], s->k[i], sizeof nk[h]);
    }
    free(s->k);
    s->k = nk;
    s->cap = ncap;
    return FDT_OK;
}

int fdt_tetset_insert(tetset *s, const uint32_t k[4])
{
    if (2 * (s->count + 1) > s->cap) {
        int err = tetset_grow(s);
        if (err)
            return err;
    }
    size_t mask = s->cap - 1, h = key_hash(k) & mask;
    for (;;) {
        uint32_t *e = s->k[h];
        if (e[0] == UINT32_MAX) {
            memcpy(e, k, 4 * sizeof *k);
            s->count++;
            return 1;
        }
        if (e[0] == k[0] && e[1] == k[1] && e[2] == k[2] && e[3] == k[3])
            return 0;
        h = (h + 1) & mask;
    }
}

static size_t id_hash(uint32_t id)
{
    uint64_t h = (uint64_t)id * 0x9E3779B97F4A7C15ull;
    return (size_t)(h ^ (h >> 31));
}

const double *fdt_ghost_find(const ghostmap *gm, uint32_t id)
{
    if (!gm->cap)
        return NULL;
    size_t mask = gm->cap - 1, h = id_hash(id) & mask;
    for (;;) {
        const ghost *e = &gm->g[h];
        if (e->id == id)
            return e->x;
        if (e->id == UINT32_MAX)
            return NULL;
        h = (h + 1) & mask;
    }
}

int fdt_ghost_put(ghostmap *gm, uint32_t id, const double *x)
{
    /* x may point into gm itself (an apex search reads a ghost's
     * coordinates from the table, finish_face puts them back): look the id
     * up before anything moves, and copy x before the table can grow and
     * free the slot it points at. */
    if (fdt_ghost_find(gm, id))
        return FDT_OK; /* coordinates never change */
    double xc[3];
    memcpy(xc, x, sizeof xc);
    if (2 * (gm->count + 1) > gm->cap) {
        size_t ncap = gm->cap ? gm->cap * 2 : 1024;
        ghost *ng = malloc(ncap * sizeof *ng);
        if (!ng)
            return FDT_ENOMEM;
        for (size_t i = 0; i < ncap; i++)
            ng[i].id = UINT32_MAX;
        for (size_t i = 0; i < gm->cap; i++) {
            if (gm->g[i].id == UINT32_MAX)
                continue;
            size_t h = id_hash(gm->g[i].id) & (ncap - 1);
            while (ng[h].id != UINT32_MAX)
                h = (h + 1) & (ncap - 1);
            ng[h] = gm->g[i];
        }
        free(gm->g);
        gm->g = ng;
        gm->cap = ncap;
    }
    size_t mask = gm->cap - 1, h = id_hash(id) & mask;
    for (;;) {
        ghost *e = &gm->g[h];
        if (e->id == UINT32_MAX) {
            e->id = id;
            memcpy(e->x, xc, sizeof e->x);
            gm->count++;
            return FDT_OK;
        }
        h = (h + 1) & mask;
    }
}

int fdt_link_add(linklist *l, int ta, int64_t la, int tb, int64_t lb)
{
    if (l->n == l->cap) {
        size_t ncap = l->cap ? l->cap * 2 : 1024;
        linkrec *nr = realloc(l->r, ncap * sizeof *nr);
        if (!nr)
            return FDT_ENOMEM;
        l->r = nr;
        l->cap = ncap;
    }
    l->r[l->n++] = (linkrec){ta, tb, la, lb};
    return FDT_OK;
}
