/*
 * Point location and linear interpolation in a periodic mesh (issue 33;
 * src/mesh/periodic.h): the periodic tet that holds a query anywhere in
 * space, and values given at the input points interpolated there,
 * barycentric in that tet (the DTFE's interpolation in a periodic box). The tets are laid out as the writers
 * lay them out (fdt_periodic_unfold) with their periodic neighbours, and
 * each query, wrapped into the box along the periodic axes, is found by a
 * visibility walk that crosses periodic faces by moving the query by
 * whole periods, in a Morton order of the queries, each from the tet the
 * one before ended in. Exact orientation tests on the laid-out points
 * (rounded images); a walk that does not end (rounding at a nearly flat
 * tet) is finished by a search of every tet in every neighbouring copy.
 */
#ifndef FDT_PERIODIC_INTERP_H
#define FDT_PERIODIC_INTERP_H

#include <stddef.h>
#include <stdint.h>

#include "frontdt.h"
#include "mesh/periodic.h"

/*
 * tet[k]: the row (of tets) holding query k, wrapped into the box along
 * the periodic axes, or -1 past the hull across an axis that is not
 * periodic (or not finite); bary (or NULL): its 4 barycentric coordinates
 * in the order of that row's ids (0 for -1). The errors below.
 */
int fdt_periodic_locate(const int32_t *tets, const int8_t *off, size_t ntets, const double *X,
                        size_t n, const fdt_periodic_box *b, const double *q, size_t nq,
                        fdt_tid *tet, double *bary);

/*
 * out[nv k + c]: value c at query k, from values[nv i + c] at input point
 * i (the tets' ids name input points: a merged duplicate's row is not
 * read); NaN for a query beyond the hull across an axis that is not
 * periodic. tets/off: ntets periodic rows (fdt_periodic_mesh's, input
 * numbering); X the n input points; b the box. FDT_OK, FDT_ENOMEM,
 * FDT_ETOOBIG, FDT_EINTERNAL (the mesh's faces do not pair: a bug).
 */
int fdt_periodic_interpolate_linear(const int32_t *tets, const int8_t *off, size_t ntets,
                                    const double *X, size_t n, const fdt_periodic_box *b,
                                    const double *values, size_t nv, const double *q,
                                    size_t nq, double *out);

#endif
