/*
 * A share of a periodic run's parts, for frontdt-mpi (issue 33): the
 * library's run (src/api/api.c) with only some of its slabs built, so
 * that each rank builds its own and the rows, gathered, are the whole
 * mesh. Not public: the share is an MPI run's business.
 */
#ifndef FDT_API_PARTS_H
#define FDT_API_PARTS_H

#include <stddef.h>
#include "frontdt.h"

/*
 * As fdt_triangulate_stream for a periodic context (settings.periodic,
 * the sink's periodic_tets set), but only the parts first, first +
 * stride, first + 2 stride, ... of the box's slabs are built and
 * streamed; the slabs are at most the stream's size and at least stride
 * of them when there are points enough, a function of the points and
 * stride alone, so the shares 0 .. stride - 1 together stream every row
 * once. With cells (not NULL; o as fdt_voronoi_stream's, NULL for the
 * defaults), as fdt_voronoi_stream: the share's slabs' points' cells, and
 * the merged duplicates' rows in share 0's, so that the shares together
 * hand on every input point's row once. FDT_EINVAL for another context,
 * a sink without periodic_tets or first >= stride; else
 * fdt_voronoi_stream's errors (FDT_ERANGE for an edge too short for the
 * cells names the share's least). The result's set hash and counts are
 * the share's.
 */
int fdt_triangulate_stream_parts(fdt_context *ctx, const double *xyz, size_t n,
                                 const fdt_sink *sink, const fdt_voronoi_options *o,
                                 const fdt_cell_sink *cells, unsigned first, unsigned stride,
                                 fdt_result **out);

#endif
