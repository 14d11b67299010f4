/*
 * A mesh kept in memory, grown as its tets come: what a front emits in
 * memory mode (src/front/sink.h: each thread's tets, tree-order ids) and
 * what a parallel run gathers them into (src/par/gather.c).
 */
#ifndef FDT_MESHBUF_H
#define FDT_MESHBUF_H

#include <stddef.h>
#include <stdint.h>
#include "frontdt.h"

/* Tets (4 global ids each, positively oriented), their
 * neighbours (optional) and hull faces (3 ids, outward). */
typedef struct fdt_meshbuf {
    uint32_t *tets;
    size_t ntets, tcap;
    int64_t *nbrs;      /* NULL unless wanted; 4 per tet, -1 on the hull */
    uint32_t *hull;
    size_t nhull, hcap;
} fdt_meshbuf;

int fdt_meshbuf_init(fdt_meshbuf *mb, size_t expected_tets, int want_nbrs);
void fdt_meshbuf_free(fdt_meshbuf *mb);
/* Appends tet v (positively oriented); returns its id or -1 (no memory). */
int64_t fdt_meshbuf_add_tet(fdt_meshbuf *mb, const uint32_t v[4]);
int fdt_meshbuf_add_hull(fdt_meshbuf *mb, const uint32_t v[3]);
/* The bytes mb holds (its capacities): fdt_stats.mem_mesh. */
size_t fdt_meshbuf_bytes(const fdt_meshbuf *mb);

#endif
