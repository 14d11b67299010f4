/*
 * The library's point location and interpolation (fdt_locate and
 * fdt_interpolate, include/frontdt.h; issues 32, 33): their arguments
 * checked, then a plain result's queries answered on its own mesh
 * (src/mesh/locate.h) and a periodic result's on a patch of its tets
 * (src/mesh/periodic_interp.h).
 */
#ifndef FDT_QUERY_H
#define FDT_QUERY_H

#include <stddef.h>

#include "frontdt.h"

/* fdt_locate and fdt_interpolate (src/api/api.c resolves their thread
 * counts) on `threads` threads, at least 1. */
int fdt_locate_build(fdt_result *r, const double *xyz, size_t n, const double *q, size_t nq,
                     fdt_tid *tet, double *bary, int threads);
int fdt_interpolate_build(fdt_result *r, const double *xyz, size_t n, const double *values,
                          size_t nv, const double *q, size_t nq, fdt_interp method,
                          int threads, double *out, char *diag, size_t diag_size);

#endif
