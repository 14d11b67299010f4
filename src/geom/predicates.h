/*
 * Exact geometric predicates on double coordinates, and the symbolic
 * perturbation that makes the Delaunay tetrahedralization unique.
 *
 * Sign conventions are CGAL's, so that our mesh equals CGAL's
 * Delaunay_triangulation_3 tet for tet:
 *   fdt_orient3d(a,b,c,d)  = sign det[b-a; c-a; d-a]
 *       > 0: (a,b,c,d) positively oriented (d on the positive side of abc)
 *   fdt_insphere(a,b,c,d,e) for positively oriented (a,b,c,d)
 *       > 0: e strictly inside the circumsphere, < 0 outside, 0 on it
 *       (CGAL side_of_oriented_sphere: ON_POSITIVE_SIDE is +1).
 *
 * Every function is exact for all finite doubles: a floating-point filter
 * with a proven error bound decides most calls; an adaptive stage with a
 * bound of order eps^2 most of the rest (near-degenerate inputs); the
 * remainder, exact zeros among them, are evaluated exactly (expansion
 * arithmetic when no intermediate can underflow, GMP integers otherwise).
 * No global mutable state; thread-safe.
 *
 * The filters are static inline below (the hot path, called tens of
 * millions of times); the exact stages are out of line in
 * src/geom/predicates.c. The filters' error analysis holds whether or not the
 * compiler contracts a*b+c into a fused multiply-add (contraction only
 * removes roundings), but not under -ffast-math (reassociation) or with
 * x87 extended-precision evaluation (src/geom/predicates.c refuses to compile
 * unless FLT_EVAL_METHOD is 0). IEEE round-to-nearest-even is assumed.
 */
#ifndef FDT_PREDICATES_H
#define FDT_PREDICATES_H

#include <float.h>
#include <math.h>
#include <stddef.h>

/* Counters of calls that left the filter; per thread, owned by the caller.
 * May be NULL everywhere below. *_exact: calls that reached an exact
 * stage (B or C); *_adapt: calls the adaptive stage decided, which then
 * need no exact arithmetic (the two are disjoint). */
typedef struct fdt_pred_counts {
    size_t orient_exact;
    size_t insphere_exact;
    size_t orient_adapt;
    size_t insphere_adapt;
    /* Inline insphere filters that could not decide (src/mesh/
     * insert_impl.h's ins_insphere): the insertion checks its star then. */
    size_t insphere_unsure;
} fdt_pred_counts;

/* a += b's exact and adaptive calls (merging threads' or phases'
 * counters; insphere_unsure is each insertion's own, not summed). */
static inline void fdt_pred_counts_add(fdt_pred_counts *a, const fdt_pred_counts *b)
{
    a->orient_exact += b->orient_exact;
    a->insphere_exact += b->insphere_exact;
    a->orient_adapt += b->orient_adapt;
    a->insphere_adapt += b->insphere_adapt;
}

/* The outward faces of a positively oriented tet: face i is opposite
 * vertex i and has that vertex on its negative side (orient3d of the face
 * and v[i] < 0). */
extern const int fdt_tet_face[4][3];

/* The six edges (i, j), i < j, of a tet with its other two vertices
 * (k, l), and the sign of the permutation (i, j, k, l) of (0, 1, 2, 3):
 * {i, j, k, l, sign}. About the direction v[j] - v[i] of a positively
 * oriented tet, its face (i, j, k) comes before (i, j, l) counter-
 * clockwise when the sign is +1 (the Voronoi cells' and the
 * natural-neighbour coordinates' shares). */
extern const int fdt_tet_edge[6][5];

int fdt_orient3d(const double *a, const double *b, const double *c,
                 const double *d, fdt_pred_counts *cnt);
int fdt_insphere(const double *a, const double *b, const double *c,
                 const double *d, const double *e, fdt_pred_counts *cnt);

/* Lexicographic (x, then y, then z) comparison: -1, 0, +1. */
int fdt_lex_compare(const double *p, const double *q);

/* Exact sign of |x - q|^2 - |y - q|^2 for any finite doubles: -1 when x
 * is strictly nearer to q than y, 0 on a tie, +1 otherwise. Floating
 * squared distances can tie (or invert) when the points mix magnitudes
 * (1e-149 next to 1), which made the seed's "nearest neighbour" edge
 * non-Delaunay; callers use this only on floating near-ties. */
int fdt_compare_dist(const double *q, const double *x, const double *y);

/* The circumcentre of the tetrahedron (a, b, c, d) relative to a, from
 * exact integer arithmetic, for any finite input (subnormal coordinates
 * included: they are scaled to integers exactly), however flat the tet.
 * Accuracy of each component x[k] against the true value X:
 *   |X| >= 2^-1022 (normal): |x[k] - X| <= 2^-51 |X|;
 *   |X| <  2^-1022 (subnormal range, doubles 2^-1074 apart, so no
 *   relative bound can hold): |x[k] - X| <= 2^-51 |X| + 2^-1074; a
 *   component below 2^-1075 may come back 0.
 * (The quotient is truncated to 53 bits, then ldexp rounds it onto the
 * subnormal grid.) tests/test_predicates.c (test_circumcenter) checks
 * these bounds against GMP rationals on random, flat, mixed 2^-1050..
 * 2^900, subnormal, offset and huge inputs, and prints the largest errors
 * it saw: 2 x 2^-53 relative and 0.5 x 2^-1074 absolute (seeds 1-3, scale
 * 4). 0 on success, -1 when the four points are coplanar or a component
 * overflows a double. For the ill-conditioned spheres the floating
 * formula cannot bound. */
int fdt_circumcenter_exact(const double *a, const double *b, const double *c,
                           const double *d, double x[3]);

/* The circumcentre of the tetrahedron (a, b, c, d), relative to a, as the
 * Voronoi cells and the natural-neighbour coordinates take it: the
 * floating formula where the tet is well shaped (|det| at least 2^-4 of
 * the product of the edges from a: the error is then at most about 2^7
 * ulps of the circumradius), the same formula in double words for flatter
 * tets (|det| down to 2^-40 of that product: a few ulps),
 * fdt_circumcenter_exact for the flattest. 0, or -1 when the points are
 * coplanar (or a component overflows). */
int fdt_circumcenter(const double *a, const double *b, const double *c, const double *d,
                     double x[3]);

/* The circumcentre of the triangle (a, b, c), relative to a: the floating
 * formula where the triangle is well shaped (|n| at least 2^-10 |b - a|
 * |c - a|, n the normal); for a flatter one (nearly collinear, its
 * circumcentre far and the formula's error near |that distance| eps /
 * sin), the exact circumcentre X of the tet (a, b, c, a + n) projected on
 * the plane: X lies on the triangle's axis about |n| / 2 from it, so a
 * normal off by eps / sin moves the projection by about |n| eps / (2 sin)
 * = |b - a| |c - a| eps / 2. Where a + n rounds back onto the plane, n is
 * scaled up (by a power of two, to about |b - a|) and tried again; a
 * triangle collinear to the last bit gets the floating formula's answer. */
void fdt_circumcenter_tri(const double *a, const double *b, const double *c, double x[3]);

/*
 * Perturbed insphere (Devillers & Teillaud 2011, as in CGAL's
 * Delaunay_triangulation_3::side_of_oriented_sphere with perturb=true).
 * Precondition: (a,b,c,d) positively oriented, the five points pairwise
 * distinct. Never returns 0: +1 inside, -1 outside.
 */
int fdt_insphere_perturbed(const double *a, const double *b, const double *c,
                           const double *d, const double *e,
                           fdt_pred_counts *cnt);

/* ------------------------------------------------------------------ */
/* Filters and exact stages, for callers that want to inline the filter. */

/* What a filter returns when it cannot decide the sign. */
#define FDT_PRED_UNSURE 2

/*
 * The exact stages alone (no filter): same results and sign conventions as
 * fdt_orient3d / fdt_insphere; they count the call in cnt (may be NULL).
 */
int fdt_orient3d_exact(const double *a, const double *b, const double *c,
                       const double *d, fdt_pred_counts *cnt);
int fdt_insphere_exact(const double *a, const double *b, const double *c,
                       const double *d, const double *e, fdt_pred_counts *cnt);

/*
 * The adaptive stage alone (src/geom/predicates.c, between the filters and the
 * exact stages): +1 / -1 when it can prove the sign (same conventions as
 * fdt_orient3d / fdt_insphere), FDT_PRED_UNSURE otherwise, and always
 * FDT_PRED_UNSURE for coordinates outside its range (stage B's) or when a
 * point shares a coordinate with a (orient3d) or e (insphere). It never
 * returns 0 and counts nothing. Exposed for tests.
 */
int fdt_orient3d_adapt(const double *a, const double *b, const double *c,
                       const double *d);
int fdt_insphere_adapt(const double *a, const double *b, const double *c,
                       const double *d, const double *e);

/*
 * Error-bound constants of the filters (derivations at the filters).
 * eps = 2^-53 is the unit roundoff.
 *   FDT_O3D_ERRBOUND = 8 eps (1 + 2^-12)
 *   FDT_ISP_ERRBOUND = 16 eps (1 + 2^-12)
 * And of the adaptive stage (derivation in src/geom/predicates.c): it decides
 * when |estimate| > bound = fl(C perm), perm the filter's permanent of the
 * rounded differences, computed as in the filters below.
 *   FDT_O3D_ADAPT_ERRBOUND = 41 eps^2
 *   FDT_ISP_ADAPT_ERRBOUND = 109 eps^2
 */
#define FDT_O3D_ERRBOUND 0x1.001p-50
#define FDT_ISP_ERRBOUND 0x1.001p-49
#define FDT_O3D_ADAPT_ERRBOUND 0x1.48p-101
#define FDT_ISP_ADAPT_ERRBOUND 0x1.b4p-100

/* What moving each point by up to dev can change a determinant of degree
 * k whose monomials (c of them) multiply differences of magnitude at most
 * m: c ((M + 2 dev)^k - M^k) <= c k 2 dev (M + 2 dev)^(k-1), M = m over
 * 1 - 2^-50 (the differences' own rounding), with 2^-20 for this bound's
 * roundings. 0 when dev is. Sound for m in fdt_pred_in_range: a product
 * that underflows there loses under 2^-1070, which the filters' margins
 * (2^-62 of a permanent of at least 2^-800) and the cofactors' (below)
 * cover. */
static inline double fdt_pred_moved(double dev, double m, double ck, int k)
{
    if (dev == 0) /* the plain engines' points: a predictable branch */
        return 0;
    const double d = 2 * dev, M = m * (1 + 0x1p-50) + d;
    double p = 1;
    for (int i = 1; i < k; i++)
        p *= M;
    return ck * d * p * (1 + 0x1p-20);
}

/* Whether the magnitude bound x keeps fdt_pred_moved and the cofactors'
 * static bounds (below) sound. */
static inline int fdt_pred_in_range(double x)
{
    return x >= 0x1p-100 && x <= 0x1p100;
}

/* The larger of a and b, branch-free (maxsd; fmax would be a call). */
static inline double fdt_pred_max(double a, double b)
{
    return a > b ? a : b;
}

/* The largest of the k magnitudes |x[i]|. */
static inline double fdt_pred_maxabs(const double *x, int k)
{
    double m = 0;
    for (int i = 0; i < k; i++)
        m = fdt_pred_max(fabs(x[i]), m);
    return m;
}

/*
 * Semi-static filters (the insertion kernel's and the certificate's
 * tests, src/mesh/insert_impl.h, src/mesh/certify.c): for points whose
 * coordinates all lie in one box, a bound on the filters' permanent holds
 * for every call, so a call whose determinant clears it needs no
 * permanent. The filters test it (their sinv argument) right after the
 * determinant: the insertion makes about 43 conflict tests and 20
 * orientation tests a point, and on well-spread points this stage decides
 * 98 % of them without the permanent's flops (bench/NOTES.md entry 91).
 *
 * Why it is exact. Let M be the largest extent hi[k] - lo[k] of the box
 * (rounded up: fl(hi - lo) is monotone, so every computed difference of
 * two coordinates in the box is at most M in magnitude). Every computed
 * permanent of fdt_orient3d_filter_diff and fdt_insphere_filter_diff is a
 * sum of products of such magnitudes, monotone in each, so at most the
 * same expression with every magnitude M: 6 M^3 and 72 M^5 exactly, up to
 * its own roundings, which the factor 1 + 2^-20 below covers (so also
 * under any contraction into fused multiply-adds). With bound = fl(B P),
 * P that bound on the permanent and B the filter's constant, a computed
 * |det| > bound then means:
 *   - the permanent is above the filters' underflow guards: |det| is at
 *     most the permanent (the same association with |.|, see the filters)
 *     up to a factor 1 + 2^-40, and fdt_pred_static_init keeps bound
 *     above 2^-790 and far above the guards' other terms (su 2^-980 and
 *     L (L 2^-960), with su <= 4M and L <= 16 M^2);
 *   - the dynamic filter would decide it, with the same sign: its bound
 *     fl(B perm) is at most fl(B P) (monotone) < |det|, the same computed
 *     determinant.
 * So this stage only ever returns what the filter would. The bounds are
 * kept as reciprocals rounded down, tested as fl(|det| inv) > 1 (which
 * implies |det| > 1 / inv >= bound), so that a zeroed fdt_pred_static,
 * like the one of a box whose extent is 0, not finite, or outside
 * [2^-100, 2^100], never decides: the filters and exact stages handle
 * those calls.
 */
typedef struct fdt_pred_static {
    double o3d_inv; /* decide orient3d when fl(|det| o3d_inv) > 1 */
    double isp_inv; /* decide insphere when fl(|det4| isp_inv) > 1 */
    /* Periodic images (src/geom/images.h), or NULL. Set, the points are
     * rounded images and the two bounds images.h's (fdt_images_init: they
     * add what the rounding can move a determinant); the _sf filters then
     * stop after the semi-static stage, whose sign is the exact images',
     * and the callers take what it leaves to images.h's stages (the
     * dynamic one widened likewise, then the exact ones; src/mesh/
     * insert_impl.h, src/mesh/certify.c). */
    const struct fdt_images *img;
} fdt_pred_static;

/* The bounds for points in the box [lo, hi] (componentwise); img NULL. */
void fdt_pred_static_init(fdt_pred_static *sf, const double lo[3], const double hi[3]);

/*
 * Floating-point filter for orient3d: +1 or -1 when that is certainly the
 * sign of det[b-a; c-a; d-a], FDT_PRED_UNSURE otherwise (never 0). sinv:
 * the semi-static stage's reciprocal bound (fdt_pred_static, above),
 * tested on the determinant before the permanent; 0: none. dyn: 0 stops
 * after that stage (the points are rounded images whose bound is sinv's
 * alone, src/geom/images.h), 1 goes on to the dynamic filter. dev: how
 * far each point may lie from the one whose sign is asked (rounded
 * periodic images), 0 for plain points: the dynamic stage's bound adds
 * what that can move the determinant, fdt_pred_moved over the call's
 * largest difference (6 monomials of 3 differences), or the call stays
 * undecided where that is out of fdt_pred_in_range. images.h's stages
 * pass it; the _sf forms pass the constant 0, which keeps the kernel's
 * inline calls as small as without it.
 *
 * Error bound. Write eps = 2^-53, eta = 2^-1075 (half the smallest
 * subnormal). Every operation obeys fl(x op y) = (x op y)(1 + delta) + mu,
 * |delta| <= eps, |mu| <= eta, and mu = 0 for + and - (a sum that lands in
 * the subnormal range is exact) -- provided nothing overflows.
 *
 * No overflow: perm is computed with the same association as det from the
 * same products, with |.| everywhere; rounding is monotone and
 * |fl(x - y)| <= fl(|x| + |y|), so every intermediate of det is at most
 * the matching intermediate of perm in magnitude. perm <= DBL_MAX therefore
 * means nothing overflowed (an overflowed difference gives perm = inf or
 * NaN, and both fail the test).
 *
 * Rounding without underflow. det is a sum of six monomials t_k = +-u_i
 * v_j w_l of the exact differences. Each reaches det_computed multiplied
 * by at most 8 factors (1 + delta): three differences, the inner product,
 * the inner difference, the outer product and at most two outer sums. So
 * |det_computed - det| <= gamma8 P, gamma8 = 8eps/(1 - 8eps), with
 * P = sum |t_k| the exact permanent; and perm >= (1 - eps)^8 P because
 * perm's terms go through the same number of roundings, all on
 * non-negative values.
 *
 * Underflow. A product's mu in one of the six inner products (v_j w_l) is
 * then multiplied by the computed |u_i| and rounded at most 3 more times;
 * an outer product's mu at most twice. The absolute perturbation of det
 * (and, likewise, the amount by which perm may fall short) is at most
 *   U = 2 eta (1+eps)^4 su' + 3 eta (1+eps)^2,  su' = |ux|+|uy|+|uz|
 * (exact sum of the computed magnitudes; su' <= (1+3eps) su). We require
 * perm >= 2^-800 and su < 2^-42 or fl(su 2^-980) <= perm. If su < 2^-42
 * then U < 2^-1070 anyway; otherwise scaling by 2^-980 is exact and
 * su <= 2^980 perm and U <= 2^-93 perm + 2^-1071 <= 2^-92 perm.
 *
 * Together: |det_computed - det| <= gamma8 P + U and
 * P <= (perm + U) / (1-eps)^8, so the error is at most
 * gamma8 (1-eps)^-8 perm + 2U <= (8eps + 200 eps^2 + 2^-91) perm.
 * The computed bound fl(B perm), B = FDT_O3D_ERRBOUND, is at least
 * B perm (1 - eps) (no underflow: B perm >= 2^-851) = (8eps + 2^-62 - ...)
 * perm, which exceeds the error by ~2^-62 perm. Hence det_computed > bound
 * implies det > 0, and det_computed < -bound implies det < 0.
 */
static inline int fdt_orient3d_filter_diff(const double u[3], const double v[3],
                                           const double w[3], double sinv, int dyn,
                                           double dev)
{
    const double ux = u[0], uy = u[1], uz = u[2];
    const double vx = v[0], vy = v[1], vz = v[2];
    const double wx = w[0], wy = w[1], wz = w[2];
    const double vywz = vy * wz, vzwy = vz * wy;
    const double vzwx = vz * wx, vxwz = vx * wz;
    const double vxwy = vx * wy, vywx = vy * wx;
    const double det = ux * (vywz - vzwy) + uy * (vzwx - vxwz) + uz * (vxwy - vywx);
    if (fabs(det) * sinv > 1) /* the semi-static stage (fdt_pred_static) */
        return (det > 0) - (det < 0);
    if (!dyn)
        return FDT_PRED_UNSURE;
    const double aux = fabs(ux), auy = fabs(uy), auz = fabs(uz);
    const double perm = aux * (fabs(vywz) + fabs(vzwy)) + auy * (fabs(vzwx) + fabs(vxwz)) +
                        auz * (fabs(vxwy) + fabs(vywx));
    const double su = aux + auy + auz;
    /* su < 2^-42 passes without the product, which would be subnormal
     * (a microcode assist of about a hundred cycles) and at most perm */
    if (perm >= 0x1p-800 && perm <= DBL_MAX && (su < 0x1p-42 || su * 0x1p-980 <= perm)) {
        double bound = FDT_O3D_ERRBOUND * perm;
        if (dev != 0) {
            const double w3[6] = {vx, vy, vz, wx, wy, wz};
            const double m = fdt_pred_max(fdt_pred_max(aux, auy),
                                          fdt_pred_max(auz, fdt_pred_maxabs(w3, 6)));
            bound = fdt_pred_in_range(m) ? bound + fdt_pred_moved(dev, m, 6 * 3, 3) : INFINITY;
        }
        /* Branch-free: the sign itself is a coin flip on typical input,
         * whether it is certain is nearly always yes. */
        const int s = (det > bound) - (det < -bound);
        if (s != 0)
            return s;
    }
    return FDT_PRED_UNSURE;
}

/* The filter proper works on the rounded differences u = b - a, v = c - a,
 * w = d - a; fdt_orient3d() also calls it on differences rescaled by a
 * power of two when they lie outside the range the bound covers. The _sf
 * form tests the semi-static stage of sf first: the same determinant
 * serves both, so a call the stage cannot decide costs only the
 * comparison more (on scans, whose box is wide next to their tets, it
 * decides 13-25 % of the certificate's tests, on uniform points 98 %). */
static inline int fdt_orient3d_filter_sf(const double *a, const double *b, const double *c,
                                         const double *d, const fdt_pred_static *sf)
{
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    return fdt_orient3d_filter_diff(u, v, w, sf->o3d_inv, sf->img == NULL, 0);
}

static inline int fdt_orient3d_filter(const double *a, const double *b,
                                      const double *c, const double *d)
{
    return fdt_orient3d_filter_sf(a, b, c, d, &(const fdt_pred_static){0, 0, NULL});
}

/*
 * Floating-point filter for insphere: +1 / -1 when that is certainly the
 * CGAL insphere sign (see the top of this file), FDT_PRED_UNSURE otherwise.
 * sinv, dyn and dev as for orient3d (72 monomials of 5 differences; the
 * largest difference from the largest lift: a component's square is at
 * most its row's |.|^2, computed within 3 eps, and so is its square
 * root).
 *
 * With A = a-e, B = b-e, C = c-e, D = d-e (rows) and |A|^2 etc.,
 *   det4 = det[A |A|^2; B |B|^2; C |C|^2; D |D|^2]
 *        = (|D|^2 abc - |C|^2 dab) + (|B|^2 cda - |A|^2 bcd),
 * where abc = det[A; B; C] etc. (expanded along the z column from the xy
 * minors ab = Ax By - Bx Ay, ...). det4 equals the lifted 5x5 determinant
 * det[p |p|^2 1] (rows a..e), which is positive exactly when e is outside
 * the sphere of a CGAL-positively oriented (a,b,c,d); so the CGAL sign is
 * -sign(det4).
 *
 * Error bound, in the model of fdt_orient3d_filter. No overflow: perm
 * mirrors det4's evaluation with |.| (same argument). Rounding: each of
 * the monomials (a lift square times a z difference times an xy product:
 * five differences) meets at most 16 roundings: 5 differences, inner
 * product and difference (2), z product (1), two sums of the 3x3 minor
 * (2), the square and two sums of the lift (3), the outer product (1) and
 * two outer sums (2). So |det4_computed - det4| <= gamma16 P and
 * perm >= (1-eps)^16 P.
 * Underflow: with M the largest computed |difference| (so each lift <= 4M^2,
 * each xy minor <= 3M^2, each 3x3 minor <= 10M^3, all up to negligible mu
 * terms), a product's mu is amplified by at most: 24 inner-product paths
 * times M (z) times 4M^2 (lift); 12 z-products times 4M^2; 12 squares times
 * 10M^3 (their 3x3 minor); 4 outer products times 1; with (1+eps)^8 of
 * rounding: U <= 1.01 eta (216 M^3 + 48 M^2 + 4) <= 2^-1066 (M^4 + 1).
 * L = sum of the four computed lifts has M^2 <= 1.01 L + 2^-1070, and we
 * require perm >= 2^-800 and L < 2^-31 or fl(L fl(L 2^-960)) <= perm: an overflow gives
 * inf and fails; if L < 2^-31 then M < 1 and U <= 2^-1065; otherwise
 * L 2^-960 is exact, the product is not subnormal, and
 * L^2 <= (1+eps) 2^960 perm. So U <= 2^-1066 (1.03 * 2^960 perm + 2)
 * <= 2^-104 perm.
 * Total error <= (gamma16 (1-eps)^-16 + 2^-102) perm
 * <= (16 eps + 600 eps^2 + 2^-102) perm, while fl(B perm) with
 * B = FDT_ISP_ERRBOUND is >= (16eps + 2^-61 - 17 eps^2) perm.
 */
static inline int fdt_insphere_filter_diff(const double A[3], const double B[3],
                                           const double C[3], const double D[3],
                                           double sinv, int dyn, double dev)
{
    const double aex = A[0], aey = A[1], aez = A[2];
    const double bex = B[0], bey = B[1], bez = B[2];
    const double cex = C[0], cey = C[1], cez = C[2];
    const double dex = D[0], dey = D[1], dez = D[2];

    const double aexbey = aex * bey, bexaey = bex * aey;
    const double bexcey = bex * cey, cexbey = cex * bey;
    const double cexdey = cex * dey, dexcey = dex * cey;
    const double dexaey = dex * aey, aexdey = aex * dey;
    const double aexcey = aex * cey, cexaey = cex * aey;
    const double bexdey = bex * dey, dexbey = dex * bey;
    const double ab = aexbey - bexaey, bc = bexcey - cexbey;
    const double cd = cexdey - dexcey, da = dexaey - aexdey;
    const double ac = aexcey - cexaey, bd = bexdey - dexbey;

    const double abc = aez * bc - bez * ac + cez * ab;
    const double bcd = bez * cd - cez * bd + dez * bc;
    const double cda = cez * da + dez * ac + aez * cd;
    const double dab = dez * ab + aez * bd + bez * da;

    const double alift = aex * aex + aey * aey + aez * aez;
    const double blift = bex * bex + bey * bey + bez * bez;
    const double clift = cex * cex + cey * cey + cez * cez;
    const double dlift = dex * dex + dey * dey + dez * dez;

    const double det = (dlift * abc - clift * dab) + (blift * cda - alift * bcd);
    if (fabs(det) * sinv > 1) /* the semi-static stage (fdt_pred_static) */
        return (det < 0) - (det > 0);
    if (!dyn)
        return FDT_PRED_UNSURE;

    const double abP = fabs(aexbey) + fabs(bexaey), bcP = fabs(bexcey) + fabs(cexbey);
    const double cdP = fabs(cexdey) + fabs(dexcey), daP = fabs(dexaey) + fabs(aexdey);
    const double acP = fabs(aexcey) + fabs(cexaey), bdP = fabs(bexdey) + fabs(dexbey);
    const double aezP = fabs(aez), bezP = fabs(bez), cezP = fabs(cez), dezP = fabs(dez);
    const double abcP = aezP * bcP + bezP * acP + cezP * abP;
    const double bcdP = bezP * cdP + cezP * bdP + dezP * bcP;
    const double cdaP = cezP * daP + dezP * acP + aezP * cdP;
    const double dabP = dezP * abP + aezP * bdP + bezP * daP;
    const double perm = (dlift * abcP + clift * dabP) + (blift * cdaP + alift * bcdP);

    const double lsum = (alift + blift) + (clift + dlift);
    /* L < 2^-31 passes without the products, whose result would be
     * subnormal and at most perm: on a dense scan (points 1e-5 apart) that
     * assist, about a hundred cycles a test, was 46 % of the insertion's
     * conflict tests (bench/NOTES.md entry 116) */
    if (perm >= 0x1p-800 && perm <= DBL_MAX &&
        (lsum < 0x1p-31 || lsum * (lsum * 0x1p-960) <= perm)) {
        double bound = FDT_ISP_ERRBOUND * perm;
        if (dev != 0) {
            const double m = sqrt(fdt_pred_max(fdt_pred_max(alift, blift),
                                               fdt_pred_max(clift, dlift))) *
                             (1 + 0x1p-50);
            bound = fdt_pred_in_range(m) ? bound + fdt_pred_moved(dev, m, 72 * 5, 5) : INFINITY;
        }
        const int s = (det < -bound) - (det > bound);
        if (s != 0)
            return s;
    }
    return FDT_PRED_UNSURE;
}

/*
 * Lifted cofactors of one tet, for testing its sphere against several
 * points (the certificate, src/mesh/certify.c, tests each finite tet's
 * orientation and about two of its faces' opposite apexes; computing the
 * tet's part once halves the flops of a test).
 *
 * With a as the origin, B = b - a, C = c - a, D = d - a, U = q - a (rows)
 * and |B|^2 etc., expanding the lifted determinant along its last column:
 *   det[B |B|^2; C |C|^2; D |D|^2; U |U|^2] = |U|^2 det - U . N,
 *   det = B . (C x D),  N = |B|^2 (C x D) + |C|^2 (D x B) + |D|^2 (B x C).
 * det is orient3d(a, b, c, d), evaluated exactly as fdt_orient3d_filter_diff
 * evaluates it; for det > 0, E = |U|^2 det - U . N is positive exactly when
 * q is outside the sphere of (a, b, c, d), so the CGAL insphere sign is
 * -sign(E) (tests/test_predicates.c, test_sphere_cof, against the exact
 * predicates).
 *
 * Error bounds, local and static: m bounds every computed difference of
 * the tet (B, C, D), mq = max(m, |U|) those of a test. In the model of
 * fdt_orient3d_filter (fl(x op y) = (x op y)(1 + delta) + mu), as long as
 * nothing underflows, each monomial of det meets at most 8 roundings and
 * each of E at most 17 (U . N's: the difference in U, 12 in N's component
 * -- two differences, a product and a difference in the cross product, two
 * differences squared, a product and two sums in the lift, the product of
 * the two and two sums --, its product, two sums and E's difference;
 * |U|^2 det's fewer). So |error| <= gamma_k P, with P the sum of the
 * monomials' magnitudes, which is at most the same expressions with every
 * difference's magnitude m (mq): 6 m^3 and 72 mq^5, each difference's
 * exact magnitude being at most its rounded one over 1 - eps. The
 * constants FDT_O3D_COF_BOUND = 48 eps (1 + 2^-7) and FDT_ISP_COF_BOUND =
 * 1224 eps (1 + 2^-8), rounded up, exceed gamma_8 6 and gamma_17 72 times (1 - eps)^-5
 * and the roundings of computing fl(K m^3), fl(K mq^5) with a wide
 * margin. Underflow: with m (mq) in [2^-100, 2^100], a product's absolute
 * error mu <= 2^-1075 reaches E multiplied by at most 100 mq^3 < 2^307
 * (a difference's rounding enters relative, a sum's is exact), some fifty
 * times: under 2^-760, while the bound is at least 2^-500 * 2^-43: the
 * margin above covers it. Overflow: every intermediate is at most
 * 72 mq^5 <= 2^507. Outside that range the calls answer FDT_PRED_UNSURE.
 * Points that stand for others up to dev (rounded periodic images): the
 * bounds hold for the determinant of the points as stored, which is within
 * fdt_pred_moved of the one they stand for (each difference moves by
 * at most 2 dev, the permanent grows by at most that), so the calls add it.
 */
#define FDT_O3D_COF_BOUND 0x1.83p-48
#define FDT_ISP_COF_BOUND 0x1.34p-43

typedef struct fdt_sphere_cof {
    const double *a; /* the origin, borrowed */
    double det;      /* orient3d(a, b, c, d) as computed */
    double n[3];     /* N */
    double m;        /* the largest computed |difference| of B, C, D */
    double dev;      /* how far each point may lie from the one it stands
                        for (rounded periodic images, src/geom/images.h):
                        0 from fdt_sphere_cof_init, set by the caller */
} fdt_sphere_cof;

static inline void fdt_sphere_cof_init(fdt_sphere_cof *s, const double *a, const double *b,
                                       const double *c, const double *d)
{
    const double ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
    const double vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
    const double wx = d[0] - a[0], wy = d[1] - a[1], wz = d[2] - a[2];
    /* C x D, D x B, B x C, det as in fdt_orient3d_filter_diff */
    const double cdx = vy * wz - vz * wy, cdy = vz * wx - vx * wz, cdz = vx * wy - vy * wx;
    const double dbx = wy * uz - wz * uy, dby = wz * ux - wx * uz, dbz = wx * uy - wy * ux;
    const double bcx = uy * vz - uz * vy, bcy = uz * vx - ux * vz, bcz = ux * vy - uy * vx;
    const double lb = ux * ux + uy * uy + uz * uz;
    const double lc = vx * vx + vy * vy + vz * vz;
    const double ld = wx * wx + wy * wy + wz * wz;
    s->a = a;
    s->det = ux * cdx + uy * cdy + uz * cdz;
    s->n[0] = lb * cdx + lc * dbx + ld * bcx;
    s->n[1] = lb * cdy + lc * dby + ld * bcy;
    s->n[2] = lb * cdz + lc * dbz + ld * bcz;
    const double e[9] = {ux, uy, uz, vx, vy, vz, wx, wy, wz};
    s->m = fdt_pred_maxabs(e, 9);
    s->dev = 0;
}

/* orient3d(a, b, c, d) of the cofactors' tet: +1 / -1 when certain,
 * FDT_PRED_UNSURE otherwise. */
static inline int fdt_sphere_cof_orient(const fdt_sphere_cof *s)
{
    if (!fdt_pred_in_range(s->m))
        return FDT_PRED_UNSURE;
    const double bound = FDT_O3D_COF_BOUND * (s->m * s->m * s->m) +
                         fdt_pred_moved(s->dev, s->m, 6 * 3, 3);
    return s->det > bound ? 1 : s->det < -bound ? -1 : FDT_PRED_UNSURE;
}

/* The CGAL insphere sign of (a, b, c, d, q) for a tet whose det is known
 * to be positive (fdt_sphere_cof_orient, or an exact orient3d): -1 when q
 * is certainly outside, +1 certainly inside, FDT_PRED_UNSURE otherwise. */
static inline int fdt_sphere_cof_insphere(const fdt_sphere_cof *s, const double *q)
{
    const double *a = s->a;
    const double x = q[0] - a[0], y = q[1] - a[1], z = q[2] - a[2];
    const double lu = x * x + y * y + z * z;
    const double e = lu * s->det - (x * s->n[0] + y * s->n[1] + z * s->n[2]);
    double mq = s->m;
    mq = fabs(x) > mq ? fabs(x) : mq;
    mq = fabs(y) > mq ? fabs(y) : mq;
    mq = fabs(z) > mq ? fabs(z) : mq;
    if (!fdt_pred_in_range(mq))
        return FDT_PRED_UNSURE;
    const double m2 = mq * mq, bound = FDT_ISP_COF_BOUND * (m2 * m2 * mq) +
                                       fdt_pred_moved(s->dev, mq, 72 * 5, 5);
    return e > bound ? -1 : e < -bound ? 1 : FDT_PRED_UNSURE;
}

/* As for orient3d: the proper filter takes the rounded differences
 * A = a - e, ..., D = d - e; the _sf form tests sf's stage first. */
static inline int fdt_insphere_filter_sf(const double *a, const double *b, const double *c,
                                         const double *d, const double *e,
                                         const fdt_pred_static *sf)
{
    const double A[3] = {a[0] - e[0], a[1] - e[1], a[2] - e[2]};
    const double B[3] = {b[0] - e[0], b[1] - e[1], b[2] - e[2]};
    const double C[3] = {c[0] - e[0], c[1] - e[1], c[2] - e[2]};
    const double D[3] = {d[0] - e[0], d[1] - e[1], d[2] - e[2]};
    return fdt_insphere_filter_diff(A, B, C, D, sf->isp_inv, sf->img == NULL, 0);
}

static inline int fdt_insphere_filter(const double *a, const double *b,
                                      const double *c, const double *d,
                                      const double *e)
{
    return fdt_insphere_filter_sf(a, b, c, d, e, &(const fdt_pred_static){0, 0, NULL});
}

#endif
