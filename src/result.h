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

#endif
