/*
 * Point location and interpolation in a periodic mesh (issue 33;
 * src/mesh/periodic.h): the periodic tet that holds a query anywhere in
 * space, and values given at the input points interpolated there, linearly
 * in that tet (the DTFE's interpolation in a periodic box) or by natural
 * neighbours (Sibson). Each query is wrapped into the box along the
 * periodic axes and answered by src/mesh/locate.c's walk and
 * src/mesh/interpolate.c's cavity on a patch of the mesh: its tets laid
 * out and translated by whole periods to cover the box and a margin
 * around it (fdt_periodic_patch_make). A walk that reaches the patch's
 * edge scans the patch; a cavity that does is asked again of a patch of
 * twice the margin. The tests are exact on the laid-out points (rounded
 * images), so the values are those of a plain mesh of the points
 * replicated around the box, and the same bits on any thread count.
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
 * in the order of that row's ids (0 for -1). tets/off: ntets periodic
 * rows (fdt_periodic_mesh's, input numbering); X the n input points; b the
 * box. FDT_OK, FDT_ENOMEM, FDT_ETOOBIG, FDT_EINTERNAL (the mesh's faces do
 * not pair: a bug).
 */
int fdt_periodic_locate(const int32_t *tets, const int8_t *off, size_t ntets, const double *X,
                        size_t n, const fdt_periodic_box *b, const double *q, size_t nq,
                        fdt_tid *tet, double *bary, int threads);

/*
 * out[nv k + c]: value c at query k, from values[nv i + c] at input point
 * i (the tets' ids name input points: a merged duplicate's row is not
 * read), by method; NaN for a query beyond the hull across an axis that
 * is not periodic, or (natural neighbours) on it. The errors above, and
 * fdt_interpolate's FDT_ERANGE with diag.
 */
int fdt_periodic_interpolate(const int32_t *tets, const int8_t *off, size_t ntets,
                             const double *X, size_t n, const fdt_periodic_box *b,
                             const double *values, size_t nv, const double *q, size_t nq,
                             fdt_interp method, int threads, double *out, char *diag,
                             size_t diag_size);

/* fdt_periodic_interpolate with the first patch's margin times first (1
 * there: the laid-out tets' largest extent; tests give 0, so that the
 * cavities near the sides are asked again of patches of growing margins). */
int fdt_periodic_interpolate_from(const int32_t *tets, const int8_t *off, size_t ntets,
                                  const double *X, size_t n, const fdt_periodic_box *b,
                                  const double *values, size_t nv, const double *q, size_t nq,
                                  fdt_interp method, int threads, double *out, char *diag,
                                  size_t diag_size, double first);

#endif
