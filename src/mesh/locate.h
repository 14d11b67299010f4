/* Point location in a result's mesh (src/mesh/locate.c): the walk behind
 * fdt_locate and fdt_interpolate. */
#ifndef FDT_LOCATE_H
#define FDT_LOCATE_H

#include <stddef.h>
#include <stdint.h>

#include "frontdt.h"

typedef struct fdt_locator {
    const fdt_result *r;  /* borrowed */
    const double *xyz;    /* borrowed: the points r was computed from */
    const fdt_tid *nbrs;  /* 4 a tet: r's, or owned */
    fdt_tid *owned;       /* derived from the face list when r has none */
    size_t cap;           /* steps before a walk gives way to the scan
                             (64 + 4 a tet; tests lower it) */
} fdt_locator;

/* FDT_EINVAL (no tets, n not r's), FDT_ENOMEM; r gains its face list
 * when it keeps no neighbours. Read-only afterwards: threads share it. */
int fdt_locator_init(fdt_locator *L, fdt_result *r, const double *xyz, size_t n);
void fdt_locator_free(fdt_locator *L);

/* The tet holding q (its closed inside), or -1 when q lies outside the
 * hull or is not finite. *hint: where the walk starts (any value), then
 * where it ended: a thread's next query starts there. */
fdt_tid fdt_locate_one(const fdt_locator *L, size_t *hint, const double *q);

/* A thread's run of the queries: the first member of each query call's
 * job (src/mesh/locate.c's, src/mesh/interpolate.c's). */
typedef struct fdt_query_run {
    const fdt_locator *L;  /* shared, read only */
    const double *q;       /* all the queries */
    const uint32_t *order; /* this run's query indices */
    size_t count;
} fdt_query_run;

/* What both query calls start with: the locator over r, *threads cut to
 * one a 64 queries (at least 1), the queries q[0 .. 3 nq) in Morton order
 * of their box (*order, malloc'd), and *jobs: *threads zeroed jobs of
 * job_size bytes (malloc'd), each starting with an fdt_query_run that
 * holds an equal run of that order: the walks of consecutive queries are
 * short. On failure (FDT_EINVAL, FDT_ENOMEM) nothing is left to free. */
int fdt_queries_begin(fdt_locator *L, fdt_result *r, const double *xyz, size_t n, const double *q,
                      size_t nq, int *threads, uint32_t **order, size_t job_size, void **jobs);
/* Frees what fdt_queries_begin made. */
void fdt_queries_end(fdt_locator *L, uint32_t *order, void *jobs);

/* q's barycentric coordinates in tet t, in the order of its vertices. */
void fdt_barycentric(const fdt_locator *L, fdt_tid t, const double *q, double b[4]);

/* fdt_locate and fdt_interpolate (include/frontdt.h; src/api/api.c
 * resolves their thread counts) on `threads` threads, at least 1. */
int fdt_locate_build(fdt_result *r, const double *xyz, size_t n, const double *q, size_t nq,
                     fdt_tid *tet, double *bary, int threads);
int fdt_interpolate_build(fdt_result *r, const double *xyz, size_t n, const double *values,
                          size_t nv, const double *q, size_t nq, fdt_interp method,
                          int threads, double *out, char *diag, size_t diag_size);

#endif
