/* The Voronoi cells' computation (src/mesh/voronoi.c) behind the public
 * fdt_voronoi_compute (src/api/api.c, which resolves the thread count). */
#ifndef FDT_VORONOI_H
#define FDT_VORONOI_H

#include "frontdt.h"

/* fdt_voronoi_compute on `threads` threads (at least 1; the caller's is
 * one of them), o not NULL and of this library's size. */
int fdt_voronoi_build(const fdt_result *r, const double *xyz, size_t n, const fdt_voronoi_options *o,
                      int threads, fdt_voronoi **out, char *diag, size_t diag_size);

/* The box the cells are clipped by: o's (FDT_EINVAL, with diag, when it is
 * empty, not finite or leaves a point out) or the bounding box of the
 * points that are not merged duplicates. The rule of fdt_voronoi_compute
 * and of the polyMesh dual (src/mesh/dualmesh.c). */
int fdt_voronoi_box_of(const fdt_result *r, const double *xyz, size_t n,
                       const fdt_voronoi_options *o, double box[6], char *diag, size_t ds);

#endif
