/*
 * Input preparation (DESIGN.md, Data flow): validate coordinates, merge
 * duplicates into their first index, and scale by a power of two.
 *
 * Scaling by 2^k changes no predicate sign (orient3d and insphere are
 * homogeneous and 2^k multiplication is exact while no value leaves the
 * normal range), but keeps the floating-point filters and the kd-tree's
 * sphere computations away from overflow and underflow for inputs near
 * 1e-150 or 1e150.
 */
#ifndef FDT_PREPARE_H
#define FDT_PREPARE_H

#include <stddef.h>
#include <stdint.h>
#include "frontdt.h"

typedef struct fdt_prepared {
    double *p;        /* 3*m distinct scaled coordinates (owned) */
    fdt_vid *orig;    /* m: first input index of each distinct point (owned) */
    size_t m;         /* distinct points */
    fdt_vid *dupmap;  /* n: vertex (first input index) of each input point */
    size_t ndup;      /* input points merged into an earlier one */
    int scale_exp;    /* coordinates were multiplied by 2^scale_exp */
    int p_borrowed;   /* p is the caller's array (fdt_prepare_inplace):
                         not freed by fdt_prepared_free */
    size_t merge_bytes; /* the merge's hash table (freed on return) */
} fdt_prepared;

/* The merge's hash table for n points: its slots (4 bytes each), the
 * power of two >= 4n/3 (load at most 3/4: 5.4 bytes a point at 100M
 * points, where >= 2n took 10.7 and made the merge a streamed run's peak,
 * bench/NOTES.md entry 111), at least 16. */
size_t fdt_prepare_merge_slots(size_t n);

/* Fills pr from n input points, on `threads` threads (one below 64k
 * points, at most 64): the same result for every count.
 * Errors: FDT_ERANGE (NaN/Inf, the first such point named in diag),
 * FDT_ETOOBIG, FDT_ENOMEM. */
int fdt_prepare(const double *xyz, size_t n, int threads, fdt_prepared *pr, char *diag,
                size_t dlen);
/* The same with xyz itself as pr->p: the distinct points are compacted
 * to its front (first occurrence order) and scaled there, so the points
 * are stored once (settings.permute_input); with duplicates the slices
 * are compacted in order on the calling thread (each writes over the
 * one before). On failure xyz is unchanged. */
int fdt_prepare_inplace(double *xyz, size_t n, int threads, fdt_prepared *pr, char *diag,
                        size_t dlen);
void fdt_prepared_free(fdt_prepared *pr);
/* The scale exponent fdt_prepare chooses for points whose largest |x| is
 * maxabs and smallest nonzero |x| minabs (INFINITY: none), for callers
 * that see the points in pieces (src/mpi/mpi_setup.c: each MPI rank its own,
 * the extremes reduced over the ranks). */
int fdt_prepare_scale_exp(double maxabs, double minabs);

#endif
