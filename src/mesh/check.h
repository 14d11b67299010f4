/* The first occurrences of points among duplicates (src/mesh/check.c):
 * what fdt_check and the periodic check (src/mesh/periodic.c) require of
 * the tets' vertices. */
#ifndef FDT_CHECK_H
#define FDT_CHECK_H

#include <stddef.h>
#include <stdint.h>

/* Sets first[i] to 1 (leaves it otherwise) for each i that is the least
 * index of its coordinates among the n points xyz (3 doubles each; equal
 * by value, so -0 and +0 are one). 0, or FDT_ENOMEM. */
int fdt_check_first_points(const double *xyz, size_t n, uint8_t *first);

/* The least index with point v's coordinates (a linear scan: for
 * messages). */
size_t fdt_check_first_of(const double *xyz, size_t n, size_t v);

#endif
