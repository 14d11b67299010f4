/*
 * The Voronoi cells of a periodic result as one polyhedral mesh (issue 33
 * item 5 with issue 32's --dual): a cell a point, whole, laid out around
 * its point (its vertices may lie past the box on a periodic axis); the
 * walls of the axes that are not periodic clip the cells as in the plain
 * dual; a face between a cell and an image of another (or of itself)
 * across a period is a cyclic face, its partner the same face moved by
 * whole periods on the other cell (src/mesh/dualmesh.h, fdt_dual_cyclic;
 * OpenFOAM's translational cyclic patches, one pair a translation).
 *
 * How: a point's Voronoi cell is bounded by its Delaunay neighbours'
 * bisectors alone, so in the plain Voronoi diagram of the points together
 * with every image that shares a periodic tet with a point
 * (fdt_dual_images_make), each point's cell is its periodic cell. The
 * caller triangulates that set and builds its plain dual
 * (fdt_dualmesh_build, with the box made here); fdt_dualmesh_fold keeps the
 * points' cells and pairs the faces they share with images.
 */
#ifndef FDT_DUALPERIODIC_H
#define FDT_DUALPERIODIC_H

#include <stddef.h>
#include <stdint.h>

#include "frontdt.h"
#include "mesh/dualmesh.h"

typedef struct fdt_dual_images {
    double *xyz;        /* 3 a point: the cells' points (the result's points
                           that are not merged duplicates, in input order),
                           then the images (owned) */
    size_t m, ncells;   /* points in all; the cells' points among them (first) */
    uint32_t *src;      /* m: the cell of a point's input point (owned) */
    int8_t *off;        /* 3 m: a point's offsets in periods, 0 for the cells'
                           points (owned) */
    size_t n;           /* the result's points */
    int32_t *cell_of;   /* n: an input point's cell, -1 for a merged
                           duplicate (owned) */
    double box[6];      /* the plain dual's: the periodic box on the axes that
                           are not periodic, on the others room for every
                           point and every cell's vertices */
} fdt_dual_images;

/* The set above for the periodic result r of the n points xyz. FDT_OK,
 * FDT_EINVAL (r not periodic, streamed or not of those n points),
 * FDT_ERANGE (a tet's circumcentre beyond doubles), FDT_ENOMEM, each with
 * diag written. */
int fdt_dual_images_make(const fdt_result *r, const double *xyz, size_t n, fdt_dual_images *im,
                         char *diag, size_t diag_size);
void fdt_dual_images_free(fdt_dual_images *im);

/*
 * The periodic dual d of r from the plain dual of im's points clipped by
 * im's box (fdt_dualmesh_build): the cells of im's first ncells points,
 * their faces with each other, on the walls of the axes that are not
 * periodic, and with images as cyclic pairs. On success d is owned by the
 * caller (fdt_dualmesh_free) and has passed fdt_dualmesh_check. FDT_ERANGE
 * when the two faces of a pair do not match (points cospherical across a
 * period whose images are not doubles: their rounding cuts one copy of a
 * Voronoi vertex into two) or an image rounded onto a point; FDT_EINTERNAL
 * when a cell reaches im's box on a periodic axis or the result fails the
 * check; FDT_ENOMEM; diag says which.
 */
int fdt_dualmesh_fold(const fdt_dualmesh *plain, const fdt_dual_images *im, const double pbox[6],
                      unsigned periodic, fdt_dualmesh *d, char *diag, size_t diag_size);

#endif
