/* Point location in a result's mesh (src/mesh/locate.c): the walk behind
 * fdt_locate and fdt_interpolate. */
#ifndef FDT_LOCATE_H
#define FDT_LOCATE_H

#include <stddef.h>
#include <stdint.h>

#include "frontdt.h"

typedef struct fdt_locator {
    const fdt_vid *tets;  /* 4 a tet, borrowed */
    size_t ntets;
    const double *xyz;    /* borrowed: the points the tets name */
    const fdt_tid *nbrs;  /* 4 a tet: borrowed, or owned; -1 the hull,
                             FDT_NB_CUT a patch's edge */
    fdt_tid *owned;       /* derived from the face list when r has none */
    size_t cap;           /* steps before a walk gives way to the scan
                             (64 + 4 a tet; tests lower it) */
    int rounded;          /* the points are rounded images of exact ones
                             (a periodic patch's): a tet flat in them is
                             refused, not a bug (src/mesh/interpolate.c) */
} fdt_locator;

/* A neighbour past the edge of a patch (a mesh that is part of a larger
 * one: src/mesh/periodic_interp.c's): not the hull, which is convex. A
 * walk that meets one scans instead; a cavity that meets one says so. */
#define FDT_NB_CUT (-2)

/* Over a result's mesh: FDT_EINVAL (no tets, n not r's), FDT_ENOMEM; r
 * gains its face list when it keeps no neighbours. Read-only afterwards:
 * threads share it. */
int fdt_locator_init(fdt_locator *L, fdt_result *r, const double *xyz, size_t n);
/* Over a patch's ntets tets, their neighbours and points (all borrowed). */
void fdt_locator_patch(fdt_locator *L, const fdt_vid *tets, const fdt_tid *nbrs, size_t ntets,
                       const double *xyz);
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

/* What both query calls start with, over the locator L: *threads cut to
 * one a 64 queries (at least 1), the queries q[0 .. 3 nq) in Morton order
 * of their box (*order, malloc'd), and *jobs: *threads zeroed jobs of
 * job_size bytes (malloc'd), each starting with an fdt_query_run that
 * holds an equal run of that order: the walks of consecutive queries are
 * short. On failure (FDT_ENOMEM) nothing is left to free. */
int fdt_queries_begin(const fdt_locator *L, const double *q, size_t nq, int *threads,
                      uint32_t **order, size_t job_size, void **jobs);
/* Frees what fdt_queries_begin made. */
void fdt_queries_end(uint32_t *order, void *jobs);

/* q's barycentric coordinates in tet t, in the order of its vertices. */
void fdt_barycentric(const fdt_locator *L, fdt_tid t, const double *q, double b[4]);

/* fdt_locate's queries on the mesh of L (src/mesh/query.h): FDT_OK,
 * FDT_ENOMEM. */
int fdt_locate_with(const fdt_locator *L, const double *q, size_t nq, fdt_tid *tet,
                    double *bary, int threads);

/*
 * The frame natural-neighbour coordinates are computed in, for the points
 * xyz[0 .. 3 n): 0, or e when the points' box lies outside 2^-100 ..
 * 2^100 and points and queries are to be scaled by 2^-e first (exact:
 * the coordinates are a function of the points' shape); *min_edge: the
 * shortest Delaunay edge whose cells doubles hold, in the scaled frame
 * (FDT_VORONOI_BOX_EXP). Linear interpolation needs no frame (e 0).
 */
int fdt_interpolate_frame(const double *xyz, size_t n, fdt_interp method, double *min_edge);

/*
 * fdt_interpolate's queries on the mesh of L (in the frame above):
 * src[v] the row of values of L's point v (NULL: v itself; the messages
 * name points by it), q_named the queries as the caller gave them (for
 * the messages). cut (or NULL on a mesh without FDT_NB_CUT): cut[k] set
 * to 1 for a natural-neighbour query whose cavity met a patch's edge (its
 * values left NaN: a larger patch answers it). FDT_OK, FDT_ENOMEM,
 * FDT_ERANGE, FDT_EINTERNAL, with diag.
 */
int fdt_interpolate_with(const fdt_locator *L, const fdt_vid *src, const double *values,
                         size_t nv, const double *q, size_t nq, fdt_interp method, int threads,
                         double *out, uint8_t *cut, double min_edge, const double *q_named,
                         char *diag, size_t diag_size);

#endif
