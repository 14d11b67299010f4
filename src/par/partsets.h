/*
 * Small per-part containers of the parallel engine (src/par/engine.c): the set
 * of boundary tets a part built (duplicate requests), the coordinates of
 * foreign points a message-mode part was sent (ghosts), and the completed
 * faces between two parts that the gather links (src/par/gather.c).
 */
#ifndef FDT_PARTSETS_H
#define FDT_PARTSETS_H

#include <stddef.h>
#include <stdint.h>


/* Set of boundary tets, keyed on their sorted ids; open addressing, linear
 * probing, no deletion. k[0] == UINT32_MAX marks an empty slot. */
typedef struct tetset {
    uint32_t (*k)[4];
    size_t cap, count;
} tetset;

/* Inserts k: 1 if it was new, 0 if present, FDT_ENOMEM. */
int fdt_tetset_insert(tetset *s, const uint32_t k[4]);

/* Coordinates of foreign points a message-mode thread has been sent. */
typedef struct ghost {
    uint32_t id;       /* UINT32_MAX: empty */
    double x[3];
} ghost;

typedef struct ghostmap {
    ghost *g;
    size_t cap, count;
} ghostmap;

/* The coordinates of id, NULL if it was never put. */
const double *fdt_ghost_find(const ghostmap *gm, uint32_t id);
/* Records id's coordinates (kept if already there): FDT_OK, FDT_ENOMEM. */
int fdt_ghost_put(ghostmap *gm, uint32_t id, const double *x);

/* A completed face whose two tets are not both the owner's: applied by the
 * gather. la, lb are (local tet << 2) | face index in threads ta, tb. */
typedef struct linkrec {
    int32_t ta, tb;
    int64_t la, lb;
} linkrec;

typedef struct linklist {
    linkrec *r;
    size_t n, cap;
} linklist;

int fdt_link_add(linklist *l, int ta, int64_t la, int tb, int64_t lb);

#endif