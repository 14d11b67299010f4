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
    fdt_vid *dupmap;     /* n (owned) */
    size_t n, ndup;
    int sorted;          /* tets are in canonical order */
    fdt_stats stats;
    fdt_thread_stats *tstats; /* stats.threads entries, parallel modes only
                                 (owned; NULL in serial mode) */
};

/* fdt_result_hash with the canonical sort (when the result is not sorted
 * yet) on `threads` threads (1 to 64), however many cores there are: for
 * tests that oversubscribe the sort's threads. */
int fdt_result_hash_threads(fdt_result *r, int threads, uint64_t *hash);

#endif
