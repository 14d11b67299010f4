/*
 * The Voronoi dual of a result as one polyhedral mesh (issue 32's --dual),
 * whatever the result: a plain one clipped by a box
 * (src/mesh/dualmesh.h), a periodic one whole across cyclic patches
 * (src/mesh/dualperiodic.h), whose points and images it triangulates
 * first. Not public: the CLI's --dual writes it (src/cli/dual.c).
 */
#ifndef FDT_API_DUAL_H
#define FDT_API_DUAL_H

#include <stddef.h>

#include "frontdt.h"
#include "mesh/dualmesh.h"

/*
 * The dual of r (the result of triangulating the n points xyz, its tets
 * sorted: the vertices and faces are numbered in their order) into *d
 * (owned by the caller: fdt_dualmesh_free; zeroed on an error), checked
 * (fdt_dualmesh_check).
 * A plain result's cells are clipped by o's box (o NULL: the points'
 * bounding box); a periodic result's
 * take its own box, and the triangulation of its points and images runs on
 * `threads` threads (0: one per physical core). The errors of
 * fdt_dualmesh_build and fdt_dualmesh_fold, and the triangulation's, with
 * diag written.
 */
int fdt_dual_build(fdt_result *r, const double *xyz, size_t n, const fdt_voronoi_options *o,
                   int threads, fdt_dualmesh *d, char *diag, size_t diag_size);

#endif
