/* The result object behind the public fdt_result_* getters. */
#ifndef FDT_RESULT_H
#define FDT_RESULT_H

#include "frontdt.h"

struct fdt_result {
    fdt_vid *tets;       /* 4 per tet, input numbering, positive (owned) */
    size_t ntets;
    fdt_tid *nbrs;       /* 4 per tet or NULL (owned) */
    fdt_vid *hull;       /* 3 per hull face, outward (owned) */
    size_t nhull;
    unsigned periodic;   /* a periodic run's axes (bit k: axis k), 0 for
                            a plain run: tets and hull faces as rows of
                            ids ascending with offsets (include/
                            frontdt.h's fdt_result_tet_offsets) */
    double pbox[6];      /* its periodic box, as given */
    int8_t *tet_off;     /* 12 per tet, periodic runs (owned) */
    int8_t *hull_off;    /* 9 per hull face, periodic runs (owned) */
    fdt_vid *dupmap;     /* n (owned) */
    size_t n, ndup;
    int sorted;          /* tets are in canonical order */
    int streamed;        /* fdt_triangulate_stream: no tets kept; set_hash
                            holds the emitted tets' set hash */
    uint64_t set_hash;
    fdt_stats stats;
    fdt_thread_stats *tstats; /* stats.threads entries, parallel modes only
                                 (owned; NULL in serial mode) */
    /* Derived on request by src/mesh/faces.c, NULL until then (owned). The
     * face list names tets, so fdt_result_sort drops it; the edges and
     * the adjacency name vertices only and survive the sort. */
    fdt_vid *face_verts; /* 3 per face */
    fdt_tid *face_tets;  /* 2 per face */
    size_t nfaces;
    fdt_vid *edges;      /* 2 per edge, (a, b) a < b, ascending */
    size_t nedges;
    size_t *adj_start;   /* n + 1 offsets into adj */
    fdt_vid *adj;        /* each vertex's neighbours, ascending */
};

/* The .tets line of a periodic tet (include/frontdt.h): its 4 ids, then
 * its 12 offsets, separated by spaces, and a newline, into buf (at least
 * FDT_PERIODIC_ROW_MAX bytes); returns its length. fdt_result_hash hashes
 * these bytes, the .tets writer writes them. */
#define FDT_PERIODIC_ROW_MAX 112
size_t fdt_periodic_row_text(char *buf, const uint32_t id[4], const int8_t off[12]);

/* Frees the face list (src/mesh/faces.c): the tets were renumbered. */
void fdt_result_drop_faces(fdt_result *r);
/* Frees everything src/mesh/faces.c derived (fdt_result_free). */
void fdt_result_drop_derived(fdt_result *r);

/* fdt_result_hash with the canonical sort (when the result is not sorted
 * yet) on `threads` threads (1 to 64), however many cores there are: for
 * tests that oversubscribe the sort's threads. */
int fdt_result_hash_threads(fdt_result *r, int threads, uint64_t *hash);

#endif
