/*
 * Periodic images of points, and exact predicates on them (issue 33).
 *
 * A periodic run triangulates the input points with some of their images
 * x + o (hi - lo), o in {-1, 0, 1} on each periodic axis (src/mesh/
 * periodic.h). That sum is not a double in general (hi - lo need not be
 * one either), and the issue asks for the exact images, never rounded
 * first. So the insertion reads P, the images rounded to doubles, through
 * these predicates, which decide for the exact images:
 *   - the filters on P, semi-static (inline in the kernel) and dynamic
 *     (here, out of line), whose bounds add to the evaluation's own
 *     rounding what the images' rounding can move the determinant
 *     (fdt_images_init for the box, predicates.h's fdt_pred_moved for a
 *     call's own differences): a sign they give
 *     is the exact images' sign (the dynamic stage decides inside
 *     clusters, whose tets are too small for the box's bound:
 *     bench/NOTES.md entry 119);
 *   - where it cannot decide: the plain exact predicates when every point
 *     of the call is exact in P (the input points, and images whose sum
 *     rounded to nothing), or on the input points when all are images in
 *     one copy (a translation changes neither sign), otherwise GMP
 *     integers of the exact sums, with
 *     the same symbolic perturbation (fdt_insphere_perturbed's:
 *     lexicographic order of the exact points, which a translation keeps,
 *     so every image of a point is perturbed alike and the perturbed
 *     periodic set stays periodic).
 * The insertion kernel finds these through its filter bounds
 * (fdt_pred_static.img, src/mesh/insert_impl.h).
 */
#ifndef FDT_IMAGES_H
#define FDT_IMAGES_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include "geom/predicates.h"

typedef struct fdt_images {
    const double *P;         /* n points, 3 doubles each: the rounded images */
    uint32_t n;
    const double *X;         /* the input points, 3 doubles each */
    const uint32_t *src;     /* per point of P: its input point (index into X) */
    const int8_t *off;       /* per point of P: 3 offsets, in periods */
    const uint8_t *exact;    /* per point of P: 1 when P holds its exact image */
    double lo[3], hi[3];     /* the period box: axis k's period is the real hi[k] - lo[k] */
    double o3d_inv, isp_inv; /* the filters' reciprocal bounds (fdt_images_init); 0: never decide */
    double err;              /* the largest |image - P| of a coordinate (fdt_images_init's) */
} fdt_images;

/*
 * The image x + off (hi - lo), rounded to doubles into out; returns 1 when
 * out is exactly the image (every sum exact), 0 otherwise (which it may
 * still be, by tails that cancel), and *err (may be NULL) gets a bound on
 * |image - out| over the three coordinates.
 */
int fdt_images_round(const double x[3], const int8_t off[3], const double lo[3],
                     const double hi[3], double out[3], double *err);

/*
 * The filters' bounds for points of P in the box [blo, bhi], each
 * coordinate within err of its exact image (fdt_images_round's, the
 * largest): the evaluation's own bound (src/geom/predicates.h's, twice)
 * plus what moving every coordinate of a call by up to err can change its
 * determinant (6 ((M + 2 err)^3 - M^3) for orient3d, 72 ((M + 2 err)^5 -
 * M^5) for the lifted insphere determinant, M the box's largest side).
 * A box outside [2^-100, 2^100] or err above M gives 0 bounds: every call
 * goes to the exact stages.
 */
void fdt_images_init(fdt_images *im, const double blo[3], const double bhi[3], double err);

/* The exact stages (src/geom/images.c): i[] are indices into P. */
int fdt_images_orient_exact(const fdt_images *im, const uint32_t i[4], fdt_pred_counts *cnt);
int fdt_images_insphere_exact(const fdt_images *im, const uint32_t i[5], fdt_pred_counts *cnt);

/* Whether the closed circumscribed ball of the positive tet of the
 * points i[0..3] of P (their exact images) lies strictly inside (A[k],
 * B[k]) on every axis k of axes, exactly (GMP): where the rounded
 * circumcentre is too uncertain (a flat tet). */
int fdt_images_ball_inside(const fdt_images *im, const uint32_t i[4], const double A[3],
                           const double B[3], unsigned axes);

/* The sign of component k of the normal (b - a) x (c - a) of the exact
 * images of the points i[0..2] of P. */
int fdt_images_normal_sign(const fdt_images *im, const uint32_t i[3], int k);

static inline uint32_t fdt_images_index(const fdt_images *im, const double *p)
{
    return (uint32_t)((size_t)(p - im->P) / 3);
}

/* The semi-static bounds of the filters for the points of P (predicates.h's
 * fdt_pred_static with img set: its _sf filters then stop after that
 * stage). */
static inline fdt_pred_static fdt_images_static(const fdt_images *im)
{
    return (fdt_pred_static){im->o3d_inv, im->isp_inv, im};
}

/*
 * What the filter fdt_orient3d_filter_sf(..., fdt_images_static(im))
 * left undecided, for the points of P at a, b, c, d: the dynamic filter
 * widened by the images' rounding, then the plain exact stages when every
 * one is exact in P or all are images in one copy (on their input
 * points: the predicates and the perturbation are invariant under the
 * translation), else GMP (fdt_images_orient_exact).
 * Out of line: the insertion kernel and the certificate call it on that
 * rare path only, so their filters stay inline and the same as the plain
 * engine's (bench/NOTES.md entry 109).
 */
int fdt_images_orient_undecided(const fdt_images *im, const double *a, const double *b,
                                const double *c, const double *d, fdt_pred_counts *cnt);

/* The same for fdt_insphere_filter_sf: the perturbed insphere's sign
 * (fdt_insphere_perturbed's convention; never 0). */
int fdt_images_insphere_undecided(const fdt_images *im, const double *a, const double *b,
                                  const double *c, const double *d, const double *e,
                                  fdt_pred_counts *cnt);

/* orient3d of the exact images of the points of P at a, b, c, d (CGAL's
 * sign, as fdt_orient3d): the filter, then the stages above. */
int fdt_images_orient(const fdt_images *im, const double *a, const double *b, const double *c,
                      const double *d, fdt_pred_counts *cnt);

/* The perturbed insphere of the exact images of the points of P at a..e
 * (fdt_insphere_perturbed's sign and precondition; never 0): the filter,
 * then the stages above. */
int fdt_images_insphere(const fdt_images *im, const double *a, const double *b, const double *c,
                        const double *d, const double *e, fdt_pred_counts *cnt);

#endif
