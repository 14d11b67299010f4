/*
 * Starting the front (§2.1): the input's dimension check and the first
 * Delaunay tetrahedron.
 */
#ifndef FDT_SEED_H
#define FDT_SEED_H

#include <stddef.h>
#include <stdint.h>
#include "geom/kdtree.h"

/* Exactly: are the points a, b and t collinear? (Each projection onto a
 * coordinate plane degenerate, by exact orient3d; src/front/seed.c says why.) */
int fdt_seed_collinear(const double *a, const double *b, const double *t);

/* FDT_OK if the m points (3 doubles each) span 3-D space; otherwise
 * FDT_EDEGENERATE with the reason in diag (fewer than 4 points, all
 * collinear, all coplanar). orig maps ids to input indices for messages. */
int fdt_seed_check_dimension(const double *P, const fdt_vid *orig, uint32_t m,
                             char *diag, size_t dlen);

/*
 * Finds a tetrahedron of the perturbed Delaunay tetrahedralization of the
 * tree's points near point a, positively oriented, into out[4].
 * Precondition: the points span 3-D space. FDT_OK, FDT_ENOMEM, or
 * FDT_EINTERNAL (which the argument in seed.c says cannot happen).
 */
int fdt_seed_tet(const fdt_kdtree *t, uint32_t a, uint32_t out[4], fdt_kdq *kq);

#endif
