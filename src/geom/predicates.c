/*
 * Exact orient3d / insphere for all finite doubles, and the symbolic
 * perturbation of Devillers & Teillaud. Sign conventions and the
 * floating-point filters (stage A, with their error bounds) are in
 * src/geom/predicates.h. This file holds an adaptive stage and the exact
 * stages, tried in this order after the filters:
 *
 *   grid (G, I, W): every coordinate a multiple of 2^k and the differences
 *            at most 2^52 of those units (lattices, integer data, computed
 *            grid nodes): the determinant in doubles (G, while it is
 *            exact), 128-bit integers (I) or five 64-bit limbs (W). Tried
 *            before the adaptive stage where the point's coordinates have
 *            few significant bits, and first in the exact stages.
 *   stage X: the coordinates themselves as integers below 2^125 units,
 *            their differences exact in 128 bits, W's limbs up to 2^62
 *            and wider ones beyond: stretched grids from 0, boundary
 *            layers' wall distances, differences that are not doubles.
 *   adaptive: coordinates in stage B's range, differences exact or not:
 *            the determinant of the rounded differences in double-word
 *            arithmetic plus the first-order terms of the differences'
 *            tails, decided when it exceeds a proven bound of order eps^2
 *            times the permanent (analysis above fdt_orient3d_adapt).
 *            Points rounded onto a sphere or a rotated lattice are decided
 *            here; exact zeros never are (they go on to B or C).
 *   stage B: the coordinate differences are exact doubles and every
 *            intermediate stays clear of underflow and overflow: the
 *            determinant of the differences is evaluated exactly with
 *            floating-point expansions (Shewchuk, "Adaptive precision
 *            floating-point arithmetic and fast robust geometric
 *            predicates", DCG 18, 1997: Two-Sum, Two-Product,
 *            Fast-Expansion-Sum, Scale-Expansion and Compress, with zero
 *            elimination). Scanner data with big offsets lands here: by
 *            Sterbenz's lemma nearby coordinates subtract exactly.
 *   stage C: anything else (magnitudes mixed beyond X's span,
 *            subnormals beside normals, inexact differences of such): every double is m 2^k with an integer
 *            |m| < 2^53, so scaling all coordinates by 2^-kmin makes them
 *            integers, and the determinant is evaluated in GMP integers.
 *
 * All compute the same polynomial as the filters, so the sign
 * conventions carry over unchanged.
 */
#include "geom/predicates.h"

#include "base/bits.h"
#include "geom/exact_gmp.h"
#include <float.h>
#include <limits.h>
#include <gmp.h>
#include <math.h>
#include <pthread.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

/* For a positively oriented (v0,v1,v2,v3), (v1,v2,v3,v0) is an odd
 * permutation, so v0 is on the negative side of (v1,v2,v3): that face is
 * already outward; the others follow the same parity count. */
const int fdt_tet_face[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
const int fdt_tet_edge[6][5] = {
    {0, 1, 2, 3, +1}, {0, 2, 1, 3, -1}, {0, 3, 1, 2, +1},
    {1, 2, 0, 3, +1}, {1, 3, 0, 2, -1}, {2, 3, 0, 1, +1},
};

/* Expansion arithmetic needs each operation rounded once to double. */
#if !defined(FLT_EVAL_METHOD) || FLT_EVAL_METHOD != 0
#error "src/geom/predicates.c needs FLT_EVAL_METHOD == 0 (SSE2 doubles, no x87)"
#endif

/* ------------------------------------------------------------------ */
/* Error-free transformations (Shewchuk 1997, section 2).
 *
 * They are exact in IEEE double arithmetic with round-to-nearest-even
 * as long as nothing overflows and every exact intermediate is a multiple
 * of 2^-1074: then each operation's exact result either is a normal number
 * (rounded as in the unbounded-exponent model the proofs assume) or is a
 * multiple of 2^-1074 below 2^-1022 with fewer than 53 significant bits,
 * which both the model and IEEE represent exactly. The stage-B range check
 * (coords_in_range) guarantees this for every operation below. Two-Sum and
 * Two-Diff on their own (no products) are exact for all finite inputs
 * whose sum does not overflow: a sum in the subnormal range is exact. */

/* x + y == a + b exactly, x = fl(a + b) (Knuth's Two-Sum). */
static inline void two_sum(double a, double b, double *x, double *y)
{
    double s = a + b;
    double bv = s - a;
    double av = s - bv;
    double br = b - bv;
    double ar = a - av;
    *x = s;
    *y = ar + br;
}

/* x + y == a - b exactly, x = fl(a - b). */
static inline void two_diff(double a, double b, double *x, double *y)
{
    double s = a - b;
    double bv = a - s;
    double av = s + bv;
    double br = bv - b;
    double ar = a - av;
    *x = s;
    *y = ar + br;
}

/* Dekker's Fast-Two-Sum: needs |a| >= |b| (or a == 0). */
static inline void fast_two_sum(double a, double b, double *x, double *y)
{
    double s = a + b;
    double bv = s - a;
    *x = s;
    *y = b - bv;
}

/* x + y == a * b exactly, x = fl(a * b). With a hardware FMA the error
 * is one fused operation; without one, Veltkamp's split and Dekker's
 * product (the compiler cannot contract anything there, having no FMA).
 * The split multiplies by 2^27 + 1, so |a|, |b| must stay below 2^995;
 * the stage-B check keeps every operand below 2^800. */
#if defined(__FP_FAST_FMA)
static inline void two_product(double a, double b, double *x, double *y)
{
    double p = a * b;
    *x = p;
    *y = __builtin_fma(a, b, -p);
}
#else
static inline void split(double a, double *hi, double *lo)
{
    double c = 0x1.0000002p+27 * a; /* 2^27 + 1 */
    double abig = c - a;
    *hi = c - abig;
    *lo = a - *hi;
}

static inline void two_product(double a, double b, double *x, double *y)
{
    double p = a * b;
    double ahi, alo, bhi, blo;
    split(a, &ahi, &alo);
    split(b, &bhi, &blo);
    double err1 = p - ahi * bhi;
    double err2 = err1 - alo * bhi;
    double err3 = err2 - ahi * blo;
    *x = p;
    *y = alo * blo - err3;
}
#endif

/* ------------------------------------------------------------------ */
/* Expansions: arrays of doubles, increasing magnitude, strongly
 * nonoverlapping (Shewchuk's sense), no zero components; the value is the
 * exact sum, length 0 means 0, and the sign is that of the last (largest)
 * component. Two-Sum and Two-Product outputs under round-to-even are
 * nonadjacent, hence valid two-component expansions once zeros are
 * dropped; Fast-Expansion-Sum and Scale-Expansion map strongly
 * nonoverlapping inputs to strongly nonoverlapping outputs (round-to-even),
 * and dropping zero components preserves that. */

static inline int expansion_sign(const double *e, int n)
{
    if (n == 0)
        return 0;
    return e[n - 1] > 0.0 ? 1 : -1;
}

/* h = e + f (Fast-Expansion-Sum with zero elimination): merge the
 * components by magnitude, then sweep a running sum Q through them,
 * emitting each rounding error. h may not alias e or f; it needs
 * elen + flen slots. Returns the length of h. */
static int expansion_sum(const double *e, int elen, const double *f, int flen, double *h)
{
    int i = 0, j = 0, n = 0;
    const int total = elen + flen;
    if (total == 0)
        return 0;
/* The next component of the merge, smaller magnitudes first. */
#define NEXT_COMPONENT() \
    ((j >= flen || (i < elen && fabs(e[i]) <= fabs(f[j]))) ? e[i++] : f[j++])
    double q = NEXT_COMPONENT();
    double hh;
    if (i + j < total) {
        double g = NEXT_COMPONENT();
        fast_two_sum(g, q, &q, &hh); /* |g| >= |q| by the merge order */
        if (hh != 0.0)
            h[n++] = hh;
        while (i + j < total) {
            g = NEXT_COMPONENT();
            two_sum(q, g, &q, &hh);
            if (hh != 0.0)
                h[n++] = hh;
        }
    }
#undef NEXT_COMPONENT
    if (q != 0.0)
        h[n++] = q;
    return n;
}

/* h = b * e (Scale-Expansion with zero elimination); h needs 2 elen
 * slots and may not alias e. */
static int scale_expansion(const double *e, int elen, double b, double *h)
{
    int n = 0;
    if (elen == 0 || b == 0.0)
        return 0;
    double q, hh, p1, p0, sum;
    two_product(e[0], b, &q, &hh);
    if (hh != 0.0)
        h[n++] = hh;
    for (int i = 1; i < elen; i++) {
        two_product(e[i], b, &p1, &p0);
        two_sum(q, p0, &sum, &hh);
        if (hh != 0.0)
            h[n++] = hh;
        fast_two_sum(p1, sum, &q, &hh);
        if (hh != 0.0)
            h[n++] = hh;
    }
    if (q != 0.0)
        h[n++] = q;
    return n;
}

/* h = a b - c d exactly (at most 4 components). */
static int product_diff(double a, double b, double c, double d, double *h)
{
    double p[2], q[2], x, y;
    int pn = 0, qn = 0;
    two_product(a, b, &x, &y);
    if (y != 0.0)
        p[pn++] = y;
    if (x != 0.0)
        p[pn++] = x;
    two_product(c, d, &x, &y);
    if (y != 0.0)
        q[qn++] = -y;
    if (x != 0.0)
        q[qn++] = -x;
    return expansion_sum(p, pn, q, qn, h);
}

/* ------------------------------------------------------------------ */
/* Stage B admission.
 *
 * All coordinates of the call must be 0 or have magnitude in
 * [2^-lo, 2^hi]. A nonzero double x >= 2^-lo is a multiple of
 * ulp(x) >= 2^(-lo-52), so every difference is a multiple of
 * 2^(-lo-52) and at most 2^(hi+1) in magnitude. The degree-k polynomial
 * (k = 3 for orient, 5 for insphere) then only involves multiples of
 * 2^(-k(lo+52)) >= 2^-1074 and values below (a small constant) 2^(k(hi+1)).
 *   orient3d:  lo = hi = 300: multiples of 2^-1056, values < 2^910;
 *   insphere:  lo = hi = 150: multiples of 2^-1010, values < 2^770
 *              (at most 72 monomials of magnitude 2^755 each).
 * Every operand of a split is a difference, a minor component or an
 * expansion component, hence below 2^800 < 2^995. */
static inline bool coords_in_range(const double *p, double lo, double hi)
{
    for (int k = 0; k < 3; k++) {
        double x = fabs(p[k]);
        if (x != 0.0 && !(x >= lo && x <= hi))
            return false;
    }
    return true;
}

/* Differences out[k] = fl(p[k] - q[k]); true if all are exact. Two-Diff's
 * tail is exact for any finite inputs; an overflowed difference gives a
 * NaN tail, which also reads as inexact. */
static inline bool exact_diff3(const double *p, const double *q, double *out)
{
    bool ok = true;
    for (int k = 0; k < 3; k++) {
        double tail;
        two_diff(p[k], q[k], &out[k], &tail);
        ok = ok && tail == 0.0;
    }
    return ok;
}

/* ------------------------------------------------------------------ */
/* Stage C helpers: doubles as scaled GMP integers. */

/* x != 0 as |x| = m 2^k with m < 2^53 an integer, read from its bits
 * (a subnormal keeps k = -1074): the library's frexp and ldexp and GMP's
 * conversion from double took 13 % of a run on points normalised onto a
 * sphere, where nearly every test reaches stage C (perf, bench/NOTES.md
 * entry 50). */
static uint64_t int_mantissa(double x, int *k)
{
    uint64_t b;
    memcpy(&b, &x, sizeof b);
    int be = (int)((b >> 52) & 0x7ff);
    uint64_t m = b & ((UINT64_C(1) << 52) - 1);
    if (be == 0) { /* subnormal: m 2^-1074 */
        *k = -1074;
        return m;
    }
    *k = be - 1075;
    return m | (UINT64_C(1) << 52);
}

/* See src/geom/exact_gmp.h. */
int fdt_int_exponent(double x)
{
    int k;
    (void)int_mantissa(x, &k);
    return k;
}

static int min_int_exponent(const double *const *pts, int npts)
{
    int kmin = 0;
    bool any = false;
    for (int i = 0; i < npts; i++)
        for (int k = 0; k < 3; k++) {
            double x = pts[i][k];
            if (x == 0.0)
                continue;
            int e = fdt_int_exponent(x);
            if (!any || e < kmin)
                kmin = e;
            any = true;
        }
    return kmin;
}

/* See src/geom/exact_gmp.h. */
void fdt_mpz_set_scaled(mpz_t z, double x, int kmin)
{
    if (x == 0.0) {
        mpz_set_ui(z, 0);
        return;
    }
    int k;
    uint64_t m = int_mantissa(x, &k);
#if ULONG_MAX >= UINT64_MAX
    mpz_set_ui(z, (unsigned long)m);
#else
    mpz_set_ui(z, (unsigned long)(m >> 32));
    mpz_mul_2exp(z, z, 32);
    mpz_add_ui(z, z, (unsigned long)(m & 0xffffffffu));
#endif
    mpz_mul_2exp(z, z, (mp_bitcnt_t)(k - kmin));
    if (x < 0.0)
        mpz_neg(z, z);
}

/* See src/geom/exact_gmp.h. */
void fdt_mpz_det3(mpz_t r, mpz_t *const u, mpz_t *const v, mpz_t *const w, mpz_t t)
{
    mpz_mul(t, v[1], w[2]);
    mpz_submul(t, v[2], w[1]);
    mpz_mul(r, u[0], t);
    mpz_mul(t, v[2], w[0]);
    mpz_submul(t, v[0], w[2]);
    mpz_addmul(r, u[1], t);
    mpz_mul(t, v[0], w[1]);
    mpz_submul(t, v[1], w[0]);
    mpz_addmul(r, u[2], t);
}

/* ------------------------------------------------------------------ */
/* Stage G: points on a coarse binary grid, evaluated in plain doubles.
 *
 * Lattices, extruded 2-D grids and integer data reach the exact stages
 * with determinants that are exactly 0 (cospherical and coplanar sets),
 * where no filter can help; but there the filter's own floating-point
 * evaluation has no rounding error at all, and its sign is exact. (CGAL's
 * interval stage certifies the same cases, as degenerate intervals.)
 *
 * The argument. Let 2^k be the lowest set bit over all nonzero coordinates
 * of the call (k = min over them of int_exponent(x) + ctz(mantissa)), so
 * every coordinate is an integer multiple of 2^k, and so is every exact
 * difference. Let M = the largest rounded difference component / 2^k. If
 * M <= G (G below), every exact difference is at most G 2^k (1 + eps) <
 * 2^53 2^k, an integer multiple of 2^k that a double holds, so the rounded
 * differences are exact. The determinant formula of the filter is
 * homogeneous: every intermediate of degree j is an integer multiple of
 * 2^(jk), and sums only combine terms of one degree. An operation whose
 * exact result is such a multiple with magnitude below 2^53 2^(jk) is
 * exact in IEEE double (a subnormal result included, as long as
 * 2^(jk) >= 2^-1074, and no overflow as long as 2^53 2^(jk) <= DBL_MAX).
 * Bounds on the intermediates, in units of 2^(jk):
 *   orient3d (degree 3): products M^2, 2x2 minors 2M^2, the three terms
 *     2M^3 each, det 6M^3; G = 2^16 gives 6 2^48 < 2^53.
 *   insphere (degree 5): xy products M^2, minors 2M^2, 3x3 minors 6M^3,
 *     lifts 3M^2, lift * minor 18M^5, the sums 36M^5 and 72M^5; G = 2^9
 *     gives 72 2^45 < 2^52.
 * Range: -1074 <= 3k and 3k + 53 + 16 * 3 <= 1023 for orient3d
 * (-358 <= k <= 307); -1074 <= 5k and 5k + 53 + 45 + 7 <= 1023 for
 * insphere (-214 <= k <= 183). Outside, the call goes on to stage B or C.
 */

/* The exponent of the lowest set bit over the nonzero coordinates, or
 * INT_MAX if all are 0; INT_MIN as soon as one is below floor (no grid
 * stage can take the call: most calls on data off any coarse grid end
 * at the first coordinate). */
static int grid_exponent(const double *const *pts, int npts, int floor)
{
    int k = INT_MAX;
    for (int i = 0; i < npts; i++)
        for (int j = 0; j < 3; j++) {
            double x = pts[i][j];
            if (x == 0.0)
                continue;
            int e;
            uint64_t m = int_mantissa(x, &e);
            e += fdt_ctz64(m);
            if (e < floor)
                return INT_MIN;
            if (e < k)
                k = e;
        }
    return k;
}

/* The largest |component| of the rounded differences p_i - q, i < n. */
static double max_diff(const double *const *p, int n, const double *q, double (*out)[3])
{
    double mx = 0.0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < 3; j++) {
            out[i][j] = p[i][j] - q[j];
            double x = fabs(out[i][j]);
            mx = x > mx ? x : mx; /* an infinite difference stays; no NaN from finite input */
        }
    return mx;
}

/* ------------------------------------------------------------------ */
/* Stage I: the same grid in 128-bit integers, for the coarser grids that
 * stage G's doubles cannot hold.
 *
 * With 2^k and the differences as in stage G, and M = the largest rounded
 * difference / 2^k at most L (below 2^53), every exact difference is an
 * integer multiple of 2^k below 2^53 2^k, so the rounded differences are
 * exact and r 2^-k are integers of at most L (the scaling by a power of
 * two is exact: its result is that integer). The determinants are then
 * evaluated exactly in integers, bounded as in stage G:
 *   orient3d: products M^2, minors 2M^2, terms 2M^3, det 6M^3; L = 2^40
 *     gives 6 2^120 < 2^123.
 *   insphere: minors 2M^2 (int64 for M <= 2^24), 3x3 minors 6M^3, lifts
 *     3M^2, lift * minor 18M^5, det 72M^5; L = 2^24 gives 72 2^120 <
 *     2^127.
 * Integer data on a coarse grid (a sphere of integer points, whose every
 * insphere test of five of its points is an exact 0: bench/NOTES.md entry
 * 116) then costs a few dozen integer products instead of stage B's
 * expansions. Without a 128-bit type the call goes on to stage B or C. */
#if defined(__SIZEOF_INT128__)
__extension__ typedef __int128 i128; /* GCC and Clang on 64-bit targets */

/* The n rows of r in units of 2^k as integers, when each is at most L:
 * 1, else 0 (2^-k not a normal double, or a row too long). */
static int grid_ints(double (*r)[3], int n, int k, double mx, double L, int64_t (*z)[3])
{
    if (k < -1022 || k > 1022 || !(mx <= ldexp(L, k)))
        return 0;
    const double s = ldexp(1.0, -k);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < 3; j++)
            z[i][j] = (int64_t)(r[i][j] * s);
    return 1;
}

/*
 * Stage W: the same integers up to 2^52 grid units, the most for which
 * stage G's argument makes the rounded differences exact (computed CFD
 * grid nodes, decimal scans: most data stage B would take), in five
 * 64-bit limbs. Bounds: 2x2 minors below 2^105 (i128), 3x3 minors below
 * 3 2^157, lifts below 3 2^104, lift * minor below 2^265, insphere's det
 * below 2^267 and orient3d's below 2^160: all within 320 bits, two's
 * complement (the products below allow more). Stage B's expansions took
 * 41 % of a wind-tunnel grid's run (bench/NOTES.md entry 116).
 */
#define WL 5
typedef struct wide {
    uint64_t w[WL]; /* little-endian limbs, two's complement */
} wide;
__extension__ typedef unsigned __int128 u128w;

static inline int wide_neg_p(const wide *x)
{
    return (x->w[WL - 1] >> 63) != 0;
}

static inline void wide_negate(wide *x)
{
    uint64_t carry = 1;
    for (int i = 0; i < WL; i++) {
        const uint64_t v = ~x->w[i];
        x->w[i] = v + carry;
        carry = carry && x->w[i] == 0;
    }
}

/* a + b (sub: a - b), modulo 2^320: exact within the bounds above. */
static inline wide wide_add(const wide *a, const wide *b, int sub)
{
    wide r;
    u128w c = sub;
    for (int i = 0; i < WL; i++) {
        c += (u128w)a->w[i] + (sub ? ~b->w[i] : b->w[i]);
        r.w[i] = (uint64_t)c;
        c >>= 64;
    }
    return r;
}

/* |x| for x within the bounds above (never -2^319). */
static wide wide_abs(wide x, int *neg)
{
    *neg = wide_neg_p(&x);
    if (*neg)
        wide_negate(&x);
    return x;
}

/* a b for |a| < 2^63, |b| < 2^127: two products of limbs. */
static inline wide wide_mul_64(int64_t a, i128 b)
{
    const int neg = (a < 0) != (b < 0);
    const uint64_t ma = a < 0 ? (uint64_t)0 - (uint64_t)a : (uint64_t)a;
    const u128w mb = b < 0 ? (u128w)0 - (u128w)b : (u128w)b;
    const u128w p0 = (u128w)ma * (uint64_t)mb, p1 = (u128w)ma * (uint64_t)(mb >> 64);
    const u128w mid = (p0 >> 64) + (uint64_t)p1;
    wide r = {{(uint64_t)p0, (uint64_t)mid, (uint64_t)((p1 >> 64) + (mid >> 64)), 0, 0}};
    if (neg)
        wide_negate(&r);
    return r;
}

/* a b for 0 <= a < 2^127 and |b| < 2^192 (its top two limbs the sign's):
 * six products of limbs, the sum below 2^319 by the bounds above. */
static wide wide_mul_128(i128 a, wide b)
{
    int neg;
    b = wide_abs(b, &neg);
    const uint64_t a0 = (uint64_t)a, a1 = (uint64_t)((u128w)a >> 64);
    wide r = {{0}};
    for (int i = 0; i < 2; i++) {
        const uint64_t ai = i ? a1 : a0;
        u128w c = 0;
        for (int j = 0; j < 3; j++) {
            c += (u128w)ai * b.w[j] + r.w[i + j];
            r.w[i + j] = (uint64_t)c;
            c >>= 64;
        }
        r.w[i + 3] += (uint64_t)c;
    }
    if (neg)
        wide_negate(&r);
    return r;
}

static int wide_sign(const wide *x)
{
    if (wide_neg_p(x))
        return -1;
    for (int i = 0; i < WL; i++)
        if (x->w[i])
            return 1;
    return 0;
}

/* orient3d's sign from integer rows of at most 2^62 (the bounds above
 * hold for that too: minors below 2^126, det below 2^189). */
static int orient_w_sign(int64_t (*z)[3])
{
    const int64_t *u = z[0], *v = z[1], *w = z[2];
    const i128 m0 = (i128)v[1] * w[2] - (i128)v[2] * w[1];
    const i128 m1 = (i128)v[2] * w[0] - (i128)v[0] * w[2];
    const i128 m2 = (i128)v[0] * w[1] - (i128)v[1] * w[0];
    const wide t0 = wide_mul_64(u[0], m0), t1 = wide_mul_64(u[1], m1), t2 = wide_mul_64(u[2], m2);
    const wide s01 = wide_add(&t0, &t1, 0), det = wide_add(&s01, &t2, 0);
    return wide_sign(&det);
}

static int orient_stage_w(double (*r)[3], int k, double mx)
{
    int64_t z[3][3];
    if (!grid_ints(r, 3, k, mx, 0x1p52, z))
        return FDT_PRED_UNSURE;
    return orient_w_sign(z);
}

/* The 3x3 minor x2 yz - y2 xz + z2 xy of insphere (x, y, z the rows'
 * third coordinates, yz ... their 2x2 minors). */
static inline wide minor3(int64_t x2, i128 yz, int64_t y2, i128 xz, int64_t z2, i128 xy)
{
    const wide a = wide_mul_64(x2, yz), b = wide_mul_64(y2, xz), c = wide_mul_64(z2, xy);
    const wide ab = wide_add(&a, &b, 1);
    return wide_add(&ab, &c, 0);
}

/* insphere's CGAL sign from integer rows of at most 2^62 (minors below
 * 2^126, 3x3 minors below 3 2^187, lifts below 3 2^124, det below
 * 2^317). */
static int insphere_w_sign(int64_t (*z)[3])
{
    const int64_t *A = z[0], *B = z[1], *C = z[2], *D = z[3];
    const i128 ab = (i128)A[0] * B[1] - (i128)B[0] * A[1];
    const i128 bc = (i128)B[0] * C[1] - (i128)C[0] * B[1];
    const i128 cd = (i128)C[0] * D[1] - (i128)D[0] * C[1];
    const i128 da = (i128)D[0] * A[1] - (i128)A[0] * D[1];
    const i128 ac = (i128)A[0] * C[1] - (i128)C[0] * A[1];
    const i128 bd = (i128)B[0] * D[1] - (i128)D[0] * B[1];
    /* as insphere_stage_i: abc, bcd, cda (+ + +), dab (+ + +) */
    const wide abc = minor3(A[2], bc, B[2], ac, C[2], ab);
    const wide bcd = minor3(B[2], cd, C[2], bd, D[2], bc);
    const wide cda0 = minor3(C[2], da, -D[2], ac, A[2], cd);
    const wide dab0 = minor3(D[2], ab, -A[2], bd, B[2], da);
    const i128 al = (i128)A[0] * A[0] + (i128)A[1] * A[1] + (i128)A[2] * A[2];
    const i128 bl = (i128)B[0] * B[0] + (i128)B[1] * B[1] + (i128)B[2] * B[2];
    const i128 cl = (i128)C[0] * C[0] + (i128)C[1] * C[1] + (i128)C[2] * C[2];
    const i128 dl = (i128)D[0] * D[0] + (i128)D[1] * D[1] + (i128)D[2] * D[2];
    const wide t0 = wide_mul_128(dl, abc), t1 = wide_mul_128(cl, dab0);
    const wide t2 = wide_mul_128(bl, cda0), t3 = wide_mul_128(al, bcd);
    const wide s01 = wide_add(&t0, &t1, 1), s23 = wide_add(&t2, &t3, 1);
    const wide det = wide_add(&s01, &s23, 0);
    return -wide_sign(&det);
}

static int insphere_stage_w(double (*r)[3], int k, double mx)
{
    int64_t z[4][3];
    if (!grid_ints(r, 4, k, mx, 0x1p52, z))
        return FDT_PRED_UNSURE;
    return insphere_w_sign(z);
}

/*
 * Wider integers for stage X (below): magnitudes as little-endian limbs,
 * multiplied by schoolbook (at most 4 x 6 limbs), and sums accumulated in
 * two's complement over as many limbs as their bound needs. Rows below
 * M = 2^126: 2x2 minors below 2M^2 = 2^253 (4 limbs), 3x3 minors below
 * 6M^3 < 2^382 (6), lifts below 3M^2 < 2^254 (4), insphere's det below
 * 72M^5 < 2^637 (10) and orient3d's below 6M^3 (6): every sum fits its
 * limbs with the sign bit to spare, so it is exact however the partial
 * sums wrap. GMP on the same numbers (stage C) spent most of a stretched
 * boundary layer's exact tests in its calls (bench/NOTES.md entry 130).
 */
#define XL 10

/* r[0 .. na + nb) = a[0 .. na) b[0 .. nb), magnitudes. */
static inline void mag_mul(const uint64_t *a, int na, const uint64_t *b, int nb, uint64_t *r)
{
    for (int i = 0; i < na + nb; i++)
        r[i] = 0;
    for (int i = 0; i < na; i++) {
        u128w c = 0;
        for (int j = 0; j < nb; j++) {
            c += (u128w)a[i] * b[j] + r[i + j];
            r[i + j] = (uint64_t)c;
            c >>= 64;
        }
        r[i + nb] = (uint64_t)c;
    }
}

/* |x| as two limbs; 1 when x < 0. */
static inline int i128_mag(i128 x, uint64_t m[2])
{
    const u128w u = x < 0 ? (u128w)0 - (u128w)x : (u128w)x;
    m[0] = (uint64_t)u;
    m[1] = (uint64_t)(u >> 64);
    return x < 0;
}

/* acc (n limbs, two's complement) += x or -x (neg), x a magnitude of nx
 * <= n limbs: acc + ~x + 1 for the negative. */
static inline void tc_add(uint64_t *acc, int n, const uint64_t *x, int nx, int neg)
{
    const uint64_t flip = neg ? ~UINT64_C(0) : 0;
    u128w c = (u128w)neg;
    for (int i = 0; i < n; i++) {
        c += (u128w)acc[i] + ((i < nx ? x[i] : 0) ^ flip);
        acc[i] = (uint64_t)c;
        c >>= 64;
    }
}

/* The magnitude of x (n limbs, two's complement, never -2^(64n-1)) into
 * m; 1 when x < 0. */
static inline int tc_mag(const uint64_t *x, int n, uint64_t *m)
{
    const int neg = (int)(x[n - 1] >> 63);
    const uint64_t flip = neg ? ~UINT64_C(0) : 0;
    u128w c = (u128w)neg;
    for (int i = 0; i < n; i++) {
        c += (u128w)(x[i] ^ flip);
        m[i] = (uint64_t)c;
        c >>= 64;
    }
    return neg;
}

static inline int tc_sign(const uint64_t *x, int n)
{
    if (x[n - 1] >> 63)
        return -1;
    for (int i = 0; i < n; i++)
        if (x[i])
            return 1;
    return 0;
}

/* acc (n limbs) += s a b for a (na limbs) and b (nb limbs) magnitudes of
 * signs sa, sb, s = +1 or -1 (sub). */
static inline void tc_addmul(uint64_t *acc, int n, const uint64_t *a, int na, int sa,
                             const uint64_t *b, int nb, int sb, int sub)
{
    uint64_t p[XL];
    mag_mul(a, na, b, nb, p);
    tc_add(acc, n, p, na + nb, sa ^ sb ^ sub);
}

/* The 2x2 minor p q' - p' q of rows below 2^126 (4 limbs). */
static inline void minor2_x(i128 p, i128 q2, i128 p2, i128 q, uint64_t out[4])
{
    uint64_t a[2], b[2];
    out[0] = out[1] = out[2] = out[3] = 0;
    int sa = i128_mag(p, a), sb = i128_mag(q2, b);
    tc_addmul(out, 4, a, 2, sa, b, 2, sb, 0);
    sa = i128_mag(p2, a);
    sb = i128_mag(q, b);
    tc_addmul(out, 4, a, 2, sa, b, 2, sb, 1);
}

/* x2 yz - y2 xz + z2 xy (6 limbs), as minor3 (yz ... 4-limb minors). */
static void minor3_x(i128 x2, const uint64_t yz[4], i128 y2, const uint64_t xz[4], i128 z2,
                     const uint64_t xy[4], uint64_t out[6])
{
    const i128 c[3] = {x2, y2, z2};
    const uint64_t *m[3] = {yz, xz, xy};
    for (int i = 0; i < 6; i++)
        out[i] = 0;
    for (int t = 0; t < 3; t++) {
        uint64_t a[2], b[4];
        const int sa = i128_mag(c[t], a), sb = tc_mag(m[t], 4, b);
        tc_addmul(out, 6, a, 2, sa, b, 4, sb, t == 1);
    }
}

/* |P|^2 of a row below 2^126 (4 limbs, nonnegative). */
static void lift_x(const i128 *r, uint64_t out[4])
{
    out[0] = out[1] = out[2] = out[3] = 0;
    for (int k = 0; k < 3; k++) {
        uint64_t a[2];
        (void)i128_mag(r[k], a);
        tc_addmul(out, 4, a, 2, 0, a, 2, 0, 0);
    }
}

/* orient3d's sign from rows below 2^126. */
static int orient_x_sign(i128 (*z)[3])
{
    const i128 *u = z[0], *v = z[1], *w = z[2];
    uint64_t m[3][4], det[6] = {0};
    minor2_x(v[1], w[2], v[2], w[1], m[0]);
    minor2_x(v[2], w[0], v[0], w[2], m[1]);
    minor2_x(v[0], w[1], v[1], w[0], m[2]);
    for (int t = 0; t < 3; t++) {
        uint64_t a[2], b[4];
        const int sa = i128_mag(u[t], a), sb = tc_mag(m[t], 4, b);
        tc_addmul(det, 6, a, 2, sa, b, 4, sb, 0);
    }
    return tc_sign(det, 6);
}

/* insphere's CGAL sign from rows below 2^126: insphere_w_sign's terms. */
static int insphere_x_sign(i128 (*z)[3])
{
    const i128 *A = z[0], *B = z[1], *C = z[2], *D = z[3];
    uint64_t ab[4], bc[4], cd[4], da[4], ac[4], bd[4];
    minor2_x(A[0], B[1], B[0], A[1], ab);
    minor2_x(B[0], C[1], C[0], B[1], bc);
    minor2_x(C[0], D[1], D[0], C[1], cd);
    minor2_x(D[0], A[1], A[0], D[1], da);
    minor2_x(A[0], C[1], C[0], A[1], ac);
    minor2_x(B[0], D[1], D[0], B[1], bd);
    uint64_t m3[4][6], l[4][4], det[XL] = {0};
    minor3_x(A[2], bc, B[2], ac, C[2], ab, m3[0]);  /* abc */
    minor3_x(D[2], ab, -A[2], bd, B[2], da, m3[1]); /* dab */
    minor3_x(C[2], da, -D[2], ac, A[2], cd, m3[2]); /* cda */
    minor3_x(B[2], cd, C[2], bd, D[2], bc, m3[3]);  /* bcd */
    lift_x(D, l[0]);
    lift_x(C, l[1]);
    lift_x(B, l[2]);
    lift_x(A, l[3]);
    /* (dl abc - cl dab) + (bl cda - al bcd) */
    for (int t = 0; t < 4; t++) {
        uint64_t b[6];
        const int sb = tc_mag(m3[t], 6, b);
        tc_addmul(det, XL, l[t], 4, 0, b, 6, sb, t & 1);
    }
    return -tc_sign(det, XL);
}

/*
 * Stage X: the coordinates themselves as integers, for differences that
 * are not exact doubles or span more than 2^52 units. With 2^k the lowest
 * set bit over the points' coordinates and every coordinate below 2^125
 * units (k at least ilogb(largest) - 124), x 2^-k is an integer (its
 * significand shifted); the differences to the last point, in i128, are
 * exact. Up to 2^62 units they take the limbs of stage W; beyond, up to
 * 2^126, the wider limbs above. A stretched grid from 0 (cfdgrid: steps
 * of 2^-62 beside coordinates near 1) lands here instead of stage B's
 * expansions (bench/NOTES.md entry 116), and a boundary layer's wall
 * distances (blayer: 2^72 units and more) instead of stage C's GMP
 * (entry 130). 0: beyond 2^126 units; 1: rows below 2^62 in z; 2: rows
 * below 2^126 in zw.
 */
static int coord_rows(const double *const *p, int n, int64_t (*z)[3], i128 (*zw)[3])
{
    double cm = 0;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < 3; j++)
            cm = fabs(p[i][j]) > cm ? fabs(p[i][j]) : cm;
    if (!(cm > 0 && cm <= DBL_MAX))
        return 0;
    const int k = grid_exponent(p, n, ilogb(cm) - 124);
    if (k == INT_MIN || k == INT_MAX)
        return 0;
    i128 q[5][3];
    for (int i = 0; i < n; i++)
        for (int j = 0; j < 3; j++) {
            int e;
            uint64_t m = int_mantissa(p[i][j], &e);
            i128 v = 0;
            if (m) { /* m 2^e, its lowest set bit at or above 2^k */
                const int tz = fdt_ctz64(m);
                v = (i128)((u128w)(m >> tz) << (e + tz - k)); /* below 2^125 */
            }
            q[i][j] = p[i][j] < 0 ? -v : v;
        }
    const i128 lim = (i128)1 << 62;
    int narrow = 1;
    for (int i = 0; i + 1 < n; i++)
        for (int j = 0; j < 3; j++) {
            zw[i][j] = q[i][j] - q[n - 1][j];
            narrow &= zw[i][j] <= lim && zw[i][j] >= -lim;
        }
    if (!narrow)
        return 2;
    for (int i = 0; i + 1 < n; i++)
        for (int j = 0; j < 3; j++)
            z[i][j] = (int64_t)zw[i][j];
    return 1;
}

static int orient_stage_x(const double *a, const double *b, const double *c, const double *d)
{
    const double *const p[4] = {b, c, d, a}; /* rows b - a, c - a, d - a */
    int64_t z[3][3];
    i128 zw[3][3];
    const int r = coord_rows(p, 4, z, zw);
    return r == 1 ? orient_w_sign(z) : r == 2 ? orient_x_sign(zw) : FDT_PRED_UNSURE;
}

static int insphere_stage_x(const double *a, const double *b, const double *c,
                            const double *d, const double *e)
{
    const double *const p[5] = {a, b, c, d, e};
    int64_t z[4][3];
    i128 zw[4][3];
    const int r = coord_rows(p, 5, z, zw);
    return r == 1 ? insphere_w_sign(z) : r == 2 ? insphere_x_sign(zw) : FDT_PRED_UNSURE;
}

static int orient_stage_i(double (*r)[3], int k, double mx)
{
    int64_t z[3][3];
    if (!grid_ints(r, 3, k, mx, 0x1p40, z))
        return orient_stage_w(r, k, mx);
    const int64_t *u = z[0], *v = z[1], *w = z[2];
    const i128 det = u[0] * ((i128)v[1] * w[2] - (i128)v[2] * w[1]) +
                     u[1] * ((i128)v[2] * w[0] - (i128)v[0] * w[2]) +
                     u[2] * ((i128)v[0] * w[1] - (i128)v[1] * w[0]);
    return (det > 0) - (det < 0);
}

static int insphere_stage_i(double (*r)[3], int k, double mx)
{
    int64_t z[4][3];
    if (!grid_ints(r, 4, k, mx, 0x1p24, z))
        return insphere_stage_w(r, k, mx);
    const int64_t *A = z[0], *B = z[1], *C = z[2], *D = z[3];
    const int64_t ab = A[0] * B[1] - B[0] * A[1], bc = B[0] * C[1] - C[0] * B[1];
    const int64_t cd = C[0] * D[1] - D[0] * C[1], da = D[0] * A[1] - A[0] * D[1];
    const int64_t ac = A[0] * C[1] - C[0] * A[1], bd = B[0] * D[1] - D[0] * B[1];
    const i128 abc = (i128)A[2] * bc - (i128)B[2] * ac + (i128)C[2] * ab;
    const i128 bcd = (i128)B[2] * cd - (i128)C[2] * bd + (i128)D[2] * bc;
    const i128 cda = (i128)C[2] * da + (i128)D[2] * ac + (i128)A[2] * cd;
    const i128 dab = (i128)D[2] * ab + (i128)A[2] * bd + (i128)B[2] * da;
    const int64_t al = A[0] * A[0] + A[1] * A[1] + A[2] * A[2];
    const int64_t bl = B[0] * B[0] + B[1] * B[1] + B[2] * B[2];
    const int64_t cl = C[0] * C[0] + C[1] * C[1] + C[2] * C[2];
    const int64_t dl = D[0] * D[0] + D[1] * D[1] + D[2] * D[2];
    const i128 det = (dl * abc - cl * dab) + (bl * cda - al * bcd);
    return (det < 0) - (det > 0);
}
#else
static int orient_stage_i(double (*r)[3], int k, double mx)
{
    (void)r, (void)k, (void)mx;
    return FDT_PRED_UNSURE;
}

static int insphere_stage_i(double (*r)[3], int k, double mx)
{
    (void)r, (void)k, (void)mx;
    return FDT_PRED_UNSURE;
}

static int orient_stage_x(const double *a, const double *b, const double *c, const double *d)
{
    (void)a, (void)b, (void)c, (void)d;
    return FDT_PRED_UNSURE;
}

static int insphere_stage_x(const double *a, const double *b, const double *c,
                            const double *d, const double *e)
{
    (void)a, (void)b, (void)c, (void)d, (void)e;
    return FDT_PRED_UNSURE;
}
#endif

/* Whether p's coordinates look like a coarse grid's: each nonzero one
 * with at most 41 significant bits (its integer mantissa's lowest 12 bits
 * 0). The gate of the grid stages' early call, before the adaptive stage;
 * not a proof (the stages check for themselves), and the exact stages try
 * them whatever it says. Data off any coarse grid (random doubles, decimal
 * scans) fails at the first coordinate: the stages' differences and
 * exponents there cost 3 % of a pipe scan's instructions (bench/NOTES.md
 * entry 116). */
static inline bool grid_likely(const double *p)
{
    for (int k = 0; k < 3; k++) {
        int e;
        if (p[k] != 0.0 && (int_mantissa(p[k], &e) & 0xfff) != 0)
            return false;
    }
    return true;
}

/* The exact orient3d sign when stage G applies (see above), else
 * FDT_PRED_UNSURE. */
static int orient_stage_g(const double *a, const double *b, const double *c, const double *d)
{
    const double *const pts[4] = {a, b, c, d};
    double r[3][3];
    const double mx = max_diff(pts + 1, 3, a, r);
    if (!(mx > 0.0 && mx <= DBL_MAX))
        return FDT_PRED_UNSURE; /* four equal points (stage B: 0), or past doubles */
    int k = grid_exponent(pts, 4, ilogb(mx) - 52);
    if (k == INT_MIN || k == INT_MAX)
        return FDT_PRED_UNSURE;
    if (k < -358 || k > 307 || !(mx <= ldexp(0x1p16, k)))
        return orient_stage_i(r, k, mx);
    const double *u = r[0], *v = r[1], *w = r[2];
    double det = u[0] * (v[1] * w[2] - v[2] * w[1]) + u[1] * (v[2] * w[0] - v[0] * w[2]) +
                 u[2] * (v[0] * w[1] - v[1] * w[0]);
    return (det > 0.0) - (det < 0.0);
}

/* det4 of fdt_insphere_filter_diff, from the rows A..D alone (no
 * permanent): the grid stage's evaluation. */
static inline double fdt_insphere_det4(const double A[3], const double B[3], const double C[3],
                                       const double D[3])
{
    const double ab = A[0] * B[1] - B[0] * A[1], bc = B[0] * C[1] - C[0] * B[1];
    const double cd = C[0] * D[1] - D[0] * C[1], da = D[0] * A[1] - A[0] * D[1];
    const double ac = A[0] * C[1] - C[0] * A[1], bd = B[0] * D[1] - D[0] * B[1];
    const double abc = A[2] * bc - B[2] * ac + C[2] * ab;
    const double bcd = B[2] * cd - C[2] * bd + D[2] * bc;
    const double cda = C[2] * da + D[2] * ac + A[2] * cd;
    const double dab = D[2] * ab + A[2] * bd + B[2] * da;
    const double alift = A[0] * A[0] + A[1] * A[1] + A[2] * A[2];
    const double blift = B[0] * B[0] + B[1] * B[1] + B[2] * B[2];
    const double clift = C[0] * C[0] + C[1] * C[1] + C[2] * C[2];
    const double dlift = D[0] * D[0] + D[1] * D[1] + D[2] * D[2];
    return (dlift * abc - clift * dab) + (blift * cda - alift * bcd);
}

/* The exact CGAL insphere sign when stage G applies, else
 * FDT_PRED_UNSURE. The formula is fdt_insphere_filter_diff's. */
static int insphere_stage_g(const double *a, const double *b, const double *c,
                            const double *d, const double *e)
{
    const double *const pts[5] = {a, b, c, d, e};
    double r[4][3];
    const double mx = max_diff(pts, 4, e, r);
    if (!(mx > 0.0 && mx <= DBL_MAX))
        return FDT_PRED_UNSURE; /* five equal points: distinctness is broken; let B decide */
    int k = grid_exponent(pts, 5, ilogb(mx) - 52);
    if (k == INT_MIN || k == INT_MAX)
        return FDT_PRED_UNSURE;
    if (k < -214 || k > 183 || !(mx <= ldexp(0x1p9, k)))
        return insphere_stage_i(r, k, mx);
    const double det = fdt_insphere_det4(r[0], r[1], r[2], r[3]);
    return (det < 0.0) - (det > 0.0);
}

/* ------------------------------------------------------------------ */
/* The adaptive stage, between the filters and stages B/C.
 *
 * Why: points near but not exactly on a common sphere or plane whose
 * coordinate differences are inexact (points rounded onto a sphere or
 * printed to 12 digits, rotated lattices) fail the filters, whose bounds
 * are of order eps times the permanent, and stage B refuses them, so they
 * went to GMP at 1-3 us a call (bench/NOTES.md, "Open leads"). Their
 * determinants are typically of order eps times the permanent, far above
 * eps^2 times it, which this stage resolves without GMP.
 *
 * Method. Each coordinate difference is x = r + t, r = fl(x) the rounded
 * difference and t its tail from Two-Diff (exact; |t| <= eps |r| since the
 * rounding error of a normal result is at most half an ulp of it). The
 * determinant F (orient3d's det3, insphere's det4, degree d = 3 or 5) is a
 * sum of monomials, each a product of d differences, so
 *   F(r + t) = F(r) + T1 + R2,
 * T1 = dF(r)[t] the terms with exactly one tail, R2 those with two or
 * more. The stage evaluates F(r) in double-word arithmetic (hi + lo pairs,
 * error of order eps^2), T1 in plain doubles (T1 is itself of order eps),
 * drops R2, and decides when z = fl(hi + fl(lo + T1)) exceeds the bound
 * fl(C perm) in magnitude, perm the filter's permanent of r; otherwise it
 * defers to stage B or C. It never answers 0.
 *
 * Admission: for orient3d, no point shares a coordinate with a, a cheap
 * test for grids, whose near-degeneracies are exact zeros
 * (shares_coordinate); for insphere, at most three zero difference
 * components (see fdt_insphere_adapt); stage B's range (coordinates 0 or of
 * magnitude in [2^-300, 2^300] for orient3d, [2^-150, 2^150] for
 * insphere); and perm >= 2^-800 (so fl(C perm) is normal). Stage B's
 * argument applies to everything below: differences, tails, Veltkamp
 * halves, the tails of Two-Sum and Two-Product and every rounded result
 * are multiples of 2^(-k(lo+52)) for a value of degree k <= d (rounding a
 * multiple of 2^-m to a double keeps it one), hence of 2^-1056 resp.
 * 2^-1010, and below 2^910 resp. 2^770. So nothing overflows, every split
 * operand is below 2^995, and nothing is lost to underflow (a result below
 * 2^-1022 is then a multiple of 2^-1074 with fewer than 53 bits: exact).
 * Every operation obeys fl(x op y) = (x op y)(1 + delta), |delta| <= eps,
 * and Two-Sum, Fast-Two-Sum (|a| >= |b|) and Two-Product are exact.
 *
 * Error accounting. Give each computed X^ of a polynomial X its formal
 * permanent P_X: |leaf| at a leaf, P_X + P_Y for X +- Y, P_X P_Y for X Y
 * (the sum of |monomials| of the expression as written; for F(r) it is
 * what perm computes, before rounding). If |X^ - X| <= a_X P_X, an
 * operation whose own error is at most c (|X^| + |Y^|) (sums) or c |X^ Y^|
 * (products) gives, as |X^| <= (1 + a_X) P_X,
 *   sum:     1 + a_Z <= (1 + max(a_X, a_Y)) (1 + c),
 *   product: 1 + a_Z <= (1 + a_X) (1 + a_Y) (1 + c).
 * So a_F <= exp(K) - 1 with K the largest sum of c along the expression, a
 * product adding both operands' sums. Plain roundings have c = eps, and
 * a <= (1 + eps)^n - 1 with n counted as in the filters. A value within
 * eps (1 + 16 eps) P_X of X counts as one rounding (the hi part of a
 * double word X^ whose a_X is below 15 eps^2: |lo| <= eps |hi|).
 *
 * Double words x = xh + xl, always normalized (|xl| <= eps |xh|: each is
 * the output of an exact transformation):
 *   dw_add: Two-Sum(xh, yh) = s + e, t = fl(e + fl(xl + yl)),
 *     Two-Sum(s, t) (t may exceed s after cancellation). Errors:
 *     eps (|xl| + |yl|) <= eps^2 (|xh| + |yh|) and
 *     eps (|e| + |fl(xl + yl)|) <= eps^2 (2 + eps)(|xh| + |yh|); with
 *     |xh| <= |x| / (1 - eps): c <= (3 + eps) eps^2 / (1 - eps).
 *   dw_scale (a double x times y): Two-Product(x, yh) = p + q,
 *     t = fl(q + fl(x yl)), Fast-Two-Sum(p, t) (|t| < 3 eps |p|). Errors
 *     eps^2 |x yh| and eps^2 (2 + eps) |x yh|: c <= (3 + eps) eps^2 / (1 - eps).
 *   dw_mul: Two-Product(xh, yh) = p + q,
 *     t = fl(q + fl(fl(xh yl) + fl(xl yh))), Fast-Two-Sum(p, t), xl yl
 *     dropped. Errors, times |xh yh| <= |x y| / (1 - eps)^2: eps^2
 *     (dropped), eps^2 twice (products), 2 eps^2 (1 + eps) (inner sum),
 *     eps^2 (1 + 2 (1 + eps)^2) (outer sum): c <= 8.0001 eps^2.
 * Below, K counts c = 3 for dw_add and dw_scale and 8 for dw_mul; the
 * true constants exceed these by a factor below 1 + 2^-40.
 *
 * The remainder: with |t| <= eps |r| factor by factor, a monomial's terms
 * with two or more tails sum to at most ((1 + eps)^d - 1 - d eps) times
 * |monomial of r|: |R2| <= (3 eps^2 + eps^3) P (orient3d),
 * <= (10 eps^2 + 10 eps^3 + ...) P (insphere), P the exact permanent. T1's
 * monomials are F's with one factor replaced by its tail, so its formal
 * permanent is at most d eps P whenever T1 is written as below (each
 * 3x3 determinant's derivative as the sum over its rows of
 * tail . (cross product of the other two rows): the six Leibniz terms with
 * that row's factor replaced; the lift's derivative 2 X . t_X: the two
 * places for the tail in X_k X_k).
 *
 * The last two roundings: w = fl(lo + T1^) errs by at most
 * eps (|lo| + |T1^|), and z = fl(hi + w) by at most eps |z| / (1 - eps).
 * If |F - z| <= E + eps |z| / (1 - eps), then z > E (1 - eps)/(1 - 2 eps)
 * implies F > 0 (and z < -that, F < 0). perm, nonnegative terms rounded n
 * times, is at least (1 - eps)^n P, and fl(C perm) >= C perm (1 - eps).
 *
 * orient3d, F = u . (v x w), rows u, v, w = b-a, c-a, d-a:
 *   F(r): minors of v, w (two exact products, dw_add: K = 3), scaled by
 *   u's components (K = 6), two dw_adds (K = 12): 12.01 eps^2 P.
 *   T1 = t_u . (v x w) + t_v . (w x u) + t_w . (u x v): crossed products
 *   2 roundings (v x w: the minors' hi parts, fewer), times a tail 1, dot
 *   product 2, outer sum 2: n = 7, error <= 7.01 eps * 3 eps P.
 *   R2 <= 3.01 eps^2 P; w: eps (1.01 eps + 3.01 eps) P.
 *   E = (12.01 + 21.03 + 3.01 + 4.02) eps^2 P = 40.07 eps^2 P; perm has
 *   n = 5: C = 40.07 eps^2 (1 + 8 eps) < 41 eps^2 = FDT_O3D_ADAPT_ERRBOUND.
 * insphere, F = det4 of the filter (rows A..D = a-e .. d-e):
 *   F(r): xy minors K = 3; 3x3 minors (scaled: 6, two dw_adds: 12);
 *   lifts (three exact squares, two dw_adds: 6); lift times minor
 *   (dw_mul: 6 + 12 + 8 = 26); two levels of dw_add: K = 32,
 *   32.01 eps^2 P.
 *   T1 = (tD - tC) + (tB - tA), tX = dL M + L dM for row X with lift L and
 *   3x3 minor M (their double words' hi parts: one rounding each),
 *   dL = 2 X . t_X, dM as above from the six pairwise cross products of
 *   A..D. Roundings: cross product 2, times a tail 1, dot 2, sum of three
 *   dots 2, times L 1 + 1: 9 (dL M: 3 + 1 + 1 = 5); tX 1; outer sums 2:
 *   n = 12, error <= 12.01 eps * 5 eps P.
 *   R2 <= 10.01 eps^2 P; w: eps (1.01 eps + 5.01 eps) P.
 *   E = (32.01 + 60.05 + 10.01 + 6.02) eps^2 P = 108.09 eps^2 P; perm has
 *   n = 11: C = 108.09 eps^2 (1 + 14 eps) < 109 eps^2 =
 *   FDT_ISP_ADAPT_ERRBOUND.
 * tests/test_predicates.c checks that calls whose |F| lies just inside
 * the bound defer and just outside it are decided.
 */

/* A double word hi + lo, |lo| <= eps |hi|. */
typedef struct dword {
    double hi, lo;
} dword;

/* A double and its Veltkamp halves: a coordinate difference takes part in
 * many products, and is split once. (With a hardware FMA the halves are
 * unused.) */
typedef struct sdouble {
    double v, hi, lo;
} sdouble;

static inline sdouble split_once(double a)
{
    sdouble s = {a, a, 0.0};
#if !defined(__FP_FAST_FMA)
    split(a, &s.hi, &s.lo);
#endif
    return s;
}

/* a b exactly, as a double word (Two-Product on split operands). */
static inline dword prod_s(sdouble a, sdouble b)
{
    double p = a.v * b.v;
#if defined(__FP_FAST_FMA)
    return (dword){p, __builtin_fma(a.v, b.v, -p)};
#else
    double err1 = p - a.hi * b.hi;
    double err2 = err1 - a.lo * b.hi;
    double err3 = err2 - a.hi * b.lo;
    return (dword){p, a.lo * b.lo - err3};
#endif
}

static inline dword dw_add(dword x, dword y)
{
    double s, e, h, l;
    two_sum(x.hi, y.hi, &s, &e);
    double t = e + (x.lo + y.lo);
    two_sum(s, t, &h, &l);
    return (dword){h, l};
}

static inline dword dw_sub(dword x, dword y)
{
    return dw_add(x, (dword){-y.hi, -y.lo});
}

static inline dword dw_scale(sdouble x, dword y)
{
    dword p = prod_s(x, split_once(y.hi));
    double t = p.lo + x.v * y.lo;
    double h, l;
    fast_two_sum(p.hi, t, &h, &l);
    return (dword){h, l};
}

static inline dword dw_mul(dword x, dword y)
{
    dword p = prod_s(split_once(x.hi), split_once(y.hi));
    double t = p.lo + (x.hi * y.lo + x.lo * y.hi);
    double h, l;
    fast_two_sum(p.hi, t, &h, &l);
    return (dword){h, l};
}

/* |x|^2: three exact squares, two dw_adds. */
static inline dword dw_lift(const sdouble *x)
{
    return dw_add(dw_add(prod_s(x[0], x[0]), prod_s(x[1], x[1])), prod_s(x[2], x[2]));
}

/* Whether one of the n points p[i] shares a coordinate with q (then a
 * difference component is 0; the test comes first, as it is cheap):
 * axis-aligned input (grids), whose near-degeneracies are exact zeros (a
 * grid cell's corners are cospherical, its faces' points coplanar) that
 * the adaptive stage can only defer. On `tests/gen_points cfdgrid 20000 1`,
 * serial, the calls that left the filters with such a component were
 * exact zeros but for 102 of 676,921 orient3d and 655 of 238,504 insphere
 * calls, and running the stage on them cost 14 % of the run's
 * instructions (callgrind). Corners of rotated lattice cubes and points
 * rounded onto a sphere share no coordinate. */
static inline bool shares_coordinate(const double *const *p, int n, const double *q)
{
    bool s = false;
    for (int i = 0; i < n; i++)
        s = s || p[i][0] == q[0] || p[i][1] == q[1] || p[i][2] == q[2];
    return s;
}

/* Rounded differences r = fl(p - q) and their tails t (exact). Returns
 * whether any tail is nonzero. */
static inline bool diff_tails(const double *p, const double *q, double *r, double *t)
{
    for (int k = 0; k < 3; k++)
        two_diff(p[k], q[k], &r[k], &t[k]);
    return t[0] != 0.0 || t[1] != 0.0 || t[2] != 0.0;
}

static inline double dot3(const double *x, const double *y)
{
    return (x[0] * y[0] + x[1] * y[1]) + x[2] * y[2];
}

static inline void cross3(const double *x, const double *y, double *z)
{
    z[0] = x[1] * y[2] - x[2] * y[1];
    z[1] = x[2] * y[0] - x[0] * y[2];
    z[2] = x[0] * y[1] - x[1] * y[0];
}

/* The semi-static bounds (predicates.h, fdt_pred_static). */
void fdt_pred_static_init(fdt_pred_static *sf, const double lo[3], const double hi[3])
{
    sf->o3d_inv = sf->isp_inv = 0;
    sf->img = NULL;
    double M = 0;
    for (int k = 0; k < 3; k++) {
        double d = hi[k] - lo[k];
        if (!(d >= 0 && d <= DBL_MAX))
            return;
        M = d > M ? d : M;
    }
    if (!(M >= 0x1p-100 && M <= 0x1p100))
        return;
    /* See predicates.h: the permanents' bounds 6 M^3 and 72 M^5, with
     * room for their own roundings. */
    const double safe = 1 + 0x1p-20, M3 = M * M * M;
    double o3d = FDT_O3D_ERRBOUND * (6 * M3 * safe);
    double isp = FDT_ISP_ERRBOUND * (72 * M3 * M * M * safe);
    /* The dynamic filters' guards, for any permanent above these bounds
     * (they hold with a wide margin for M in range; checked all the same). */
    double su = 4 * M, L = 16 * M * M;
    if (o3d < 0x1p-790 || su * 0x1p-980 > 0.5 * o3d || isp < 0x1p-790 ||
        L * (L * 0x1p-960) > 0.5 * isp)
        return;
    /* Rounded down: (1 - 2^-50) fl(1/x) <= 1/x. */
    sf->o3d_inv = (1 / o3d) * (1 - 0x1p-50);
    sf->isp_inv = (1 / isp) * (1 - 0x1p-50);
}

/* +1 / -1 when |z| > bound proves the sign of F, FDT_PRED_UNSURE else. */
static inline int adapt_sign(dword f, double t1, double bound)
{
    const double z = f.hi + (f.lo + t1);
    if (z > bound)
        return 1;
    if (z < -bound)
        return -1;
    return FDT_PRED_UNSURE;
}

int fdt_orient3d_adapt(const double *a, const double *b, const double *c,
                       const double *d)
{
    const double *const rows[3] = {b, c, d};
    if (shares_coordinate(rows, 3, a))
        return FDT_PRED_UNSURE;
    const double lo = 0x1p-300, hi = 0x1p+300;
    if (!(coords_in_range(a, lo, hi) && coords_in_range(b, lo, hi) &&
          coords_in_range(c, lo, hi) && coords_in_range(d, lo, hi)))
        return FDT_PRED_UNSURE;
    double u[3], v[3], w[3], ut[3], vt[3], wt[3];
    bool tails = diff_tails(b, a, u, ut);
    tails = diff_tails(c, a, v, vt) || tails;
    tails = diff_tails(d, a, w, wt) || tails;
    /* As in fdt_orient3d_filter_diff (the same association). */
    const double perm = fabs(u[0]) * (fabs(v[1] * w[2]) + fabs(v[2] * w[1])) +
                        fabs(u[1]) * (fabs(v[2] * w[0]) + fabs(v[0] * w[2])) +
                        fabs(u[2]) * (fabs(v[0] * w[1]) + fabs(v[1] * w[0]));
    if (!(perm >= 0x1p-800))
        return FDT_PRED_UNSURE;
    sdouble sv[3], sw[3];
    for (int k = 0; k < 3; k++) {
        sv[k] = split_once(v[k]);
        sw[k] = split_once(w[k]);
    }
    const dword mx = dw_sub(prod_s(sv[1], sw[2]), prod_s(sv[2], sw[1]));
    const dword my = dw_sub(prod_s(sv[2], sw[0]), prod_s(sv[0], sw[2]));
    const dword mz = dw_sub(prod_s(sv[0], sw[1]), prod_s(sv[1], sw[0]));
    const dword f = dw_add(dw_add(dw_scale(split_once(u[0]), mx), dw_scale(split_once(u[1]), my)),
                           dw_scale(split_once(u[2]), mz));
    double t1 = 0.0;
    if (tails) {
        const double vw[3] = {mx.hi, my.hi, mz.hi};
        double wu[3], uv[3];
        cross3(w, u, wu);
        cross3(u, v, uv);
        t1 = (dot3(ut, vw) + dot3(vt, wu)) + dot3(wt, uv);
    }
    return adapt_sign(f, t1, FDT_O3D_ADAPT_ERRBOUND * perm);
}

int fdt_insphere_adapt(const double *a, const double *b, const double *c,
                       const double *d, const double *e)
{
    const double lo = 0x1p-150, hi = 0x1p+150;
    if (!(coords_in_range(a, lo, hi) && coords_in_range(b, lo, hi) &&
          coords_in_range(c, lo, hi) && coords_in_range(d, lo, hi) &&
          coords_in_range(e, lo, hi)))
        return FDT_PRED_UNSURE;
    double A[3], B[3], C[3], D[3], At[3], Bt[3], Ct[3], Dt[3];
    bool tails = diff_tails(a, e, A, At);
    tails = diff_tails(b, e, B, Bt) || tails;
    tails = diff_tails(c, e, C, Ct) || tails;
    tails = diff_tails(d, e, D, Dt) || tails;
    /* Admission (insphere): at most three of the twelve difference
     * components are 0. The corners of an axis-aligned grid cell
     * (lattices, stretched CFD grids) are cospherical, an exact zero this
     * stage can only defer, and five corners of a box have at least four
     * zero components (each corner shares two coordinates with e but the
     * opposite one, which shares none). A pipe scan's rings (one z each)
     * give two or three zeros, and those determinants are not zero: with
     * orient3d's rule (any shared coordinate defers) `tests/gen_points
     * cylscan 100000 1` sent 0.56 M of them to stage B. Measured, serial,
     * whole process, CPU s, this rule against that one (bench/NOTES.md
     * entry 53): cylscan 1.86 / 3.58, cylinder 1.77 / 2.92, ogrid 0.82 /
     * 1.92; cfdgrid 1.66 / 1.68, lattice 0.79 / 0.73, grid2d 0.54 / 0.52
     * (no rule at all: lattice 0.93, grid2d 0.67, cfdgrid 1.85). */
    int zeros = 0;
    for (int k = 0; k < 3; k++)
        zeros += (A[k] == 0.0) + (B[k] == 0.0) + (C[k] == 0.0) + (D[k] == 0.0);
    if (zeros >= 4)
        return FDT_PRED_UNSURE;

    /* perm, as in fdt_insphere_filter_diff (the same association). */
    const double abP = fabs(A[0] * B[1]) + fabs(B[0] * A[1]);
    const double bcP = fabs(B[0] * C[1]) + fabs(C[0] * B[1]);
    const double cdP = fabs(C[0] * D[1]) + fabs(D[0] * C[1]);
    const double daP = fabs(D[0] * A[1]) + fabs(A[0] * D[1]);
    const double acP = fabs(A[0] * C[1]) + fabs(C[0] * A[1]);
    const double bdP = fabs(B[0] * D[1]) + fabs(D[0] * B[1]);
    const double azP = fabs(A[2]), bzP = fabs(B[2]), czP = fabs(C[2]), dzP = fabs(D[2]);
    const double abcP = azP * bcP + bzP * acP + czP * abP;
    const double bcdP = bzP * cdP + czP * bdP + dzP * bcP;
    const double cdaP = czP * daP + dzP * acP + azP * cdP;
    const double dabP = dzP * abP + azP * bdP + bzP * daP;
    const double alP = A[0] * A[0] + A[1] * A[1] + A[2] * A[2];
    const double blP = B[0] * B[0] + B[1] * B[1] + B[2] * B[2];
    const double clP = C[0] * C[0] + C[1] * C[1] + C[2] * C[2];
    const double dlP = D[0] * D[0] + D[1] * D[1] + D[2] * D[2];
    const double perm = (dlP * abcP + clP * dabP) + (blP * cdaP + alP * bcdP);
    if (!(perm >= 0x1p-800))
        return FDT_PRED_UNSURE;

    sdouble sA[3], sB[3], sC[3], sD[3];
    for (int k = 0; k < 3; k++) {
        sA[k] = split_once(A[k]);
        sB[k] = split_once(B[k]);
        sC[k] = split_once(C[k]);
        sD[k] = split_once(D[k]);
    }
    const dword ab = dw_sub(prod_s(sA[0], sB[1]), prod_s(sB[0], sA[1]));
    const dword bc = dw_sub(prod_s(sB[0], sC[1]), prod_s(sC[0], sB[1]));
    const dword cd = dw_sub(prod_s(sC[0], sD[1]), prod_s(sD[0], sC[1]));
    const dword da = dw_sub(prod_s(sD[0], sA[1]), prod_s(sA[0], sD[1]));
    const dword ac = dw_sub(prod_s(sA[0], sC[1]), prod_s(sC[0], sA[1]));
    const dword bd = dw_sub(prod_s(sB[0], sD[1]), prod_s(sD[0], sB[1]));
    const dword abc = dw_add(dw_sub(dw_scale(sA[2], bc), dw_scale(sB[2], ac)), dw_scale(sC[2], ab));
    const dword bcd = dw_add(dw_sub(dw_scale(sB[2], cd), dw_scale(sC[2], bd)), dw_scale(sD[2], bc));
    const dword cda = dw_add(dw_add(dw_scale(sC[2], da), dw_scale(sD[2], ac)), dw_scale(sA[2], cd));
    const dword dab = dw_add(dw_add(dw_scale(sD[2], ab), dw_scale(sA[2], bd)), dw_scale(sB[2], da));
    const dword al = dw_lift(sA), bl = dw_lift(sB), cl = dw_lift(sC), dl = dw_lift(sD);
    const dword f = dw_add(dw_sub(dw_mul(dl, abc), dw_mul(cl, dab)),
                           dw_sub(dw_mul(bl, cda), dw_mul(al, bcd)));

    double t1 = 0.0;
    if (tails) {
        /* Each 3x3 minor is, in turn, every one of its rows dotted with
         * the cross product of the two that follow it cyclically:
         * abc = A.(BxC) = B.(CxA) = C.(AxB), dab = D.(AxB) = A.(BxD) =
         * B.(DxA), cda = C.(DxA) = -D.(CxA) = A.(CxD), bcd = B.(CxD) =
         * -C.(BxD) = D.(BxC); its derivative puts the tail in each row. */
        double AB[3], BC[3], CA[3], DA[3], BD[3], CD[3];
        cross3(A, B, AB);
        cross3(B, C, BC);
        cross3(C, A, CA);
        cross3(D, A, DA);
        cross3(B, D, BD);
        cross3(C, D, CD);
        const double dabc = (dot3(At, BC) + dot3(Bt, CA)) + dot3(Ct, AB);
        const double ddab = (dot3(Dt, AB) + dot3(At, BD)) + dot3(Bt, DA);
        const double dcda = (dot3(Ct, DA) - dot3(Dt, CA)) + dot3(At, CD);
        const double dbcd = (dot3(Bt, CD) - dot3(Ct, BD)) + dot3(Dt, BC);
        const double tD = 2.0 * dot3(D, Dt) * abc.hi + dl.hi * dabc;
        const double tC = 2.0 * dot3(C, Ct) * dab.hi + cl.hi * ddab;
        const double tB = 2.0 * dot3(B, Bt) * cda.hi + bl.hi * dcda;
        const double tA = 2.0 * dot3(A, At) * bcd.hi + al.hi * dbcd;
        t1 = (tD - tC) + (tB - tA);
    }
    /* det4 > 0: e outside, CGAL sign -1. */
    const int s = adapt_sign(f, t1, FDT_ISP_ADAPT_ERRBOUND * perm);
    return s == FDT_PRED_UNSURE ? s : -s;
}

/* ------------------------------------------------------------------ */
/* orient3d, exact stages. */

static int orient_stage_b(const double *u, const double *v, const double *w)
{
    double mx[4], my[4], mz[4], t0[8], t1[8], t2[8], s01[16], det[24];
    int nx = product_diff(v[1], w[2], v[2], w[1], mx);
    int ny = product_diff(v[2], w[0], v[0], w[2], my);
    int nz = product_diff(v[0], w[1], v[1], w[0], mz);
    int n0 = scale_expansion(mx, nx, u[0], t0);
    int n1 = scale_expansion(my, ny, u[1], t1);
    int n2 = scale_expansion(mz, nz, u[2], t2);
    int n01 = expansion_sum(t0, n0, t1, n1, s01);
    int n = expansion_sum(s01, n01, t2, n2, det);
    return expansion_sign(det, n);
}

/* Stage C's integers, one set a thread (orient_stage_c, insphere_stage_c):
 * made on the thread's first call and kept, so that a call allocates
 * nothing once they have grown to its inputs' width. Made and cleared a
 * call, they cost a run on a stretched grid (gen_points blayer, 1.9 M
 * exact calls at 100k points) a tenth of its time in malloc, free and
 * realloc (bench/NOTES.md entry 65). A thread's set is cleared when the
 * thread exits, by the destructor of a pthread key made once
 * (pthread_once, which also makes scratch_key_ok visible to every thread
 * that returns from it); the main thread's stays until the process ends.
 * Without a key (its creation failed) an exiting thread leaves its set,
 * a few hundred bytes. */
typedef struct gmp_scratch {
    mpz_t q[5][3], m3, lift, det, t;
    int ready;
} gmp_scratch;

static _Thread_local gmp_scratch scratch_tls;
static pthread_key_t scratch_key;
static int scratch_key_ok;
static pthread_once_t scratch_once = PTHREAD_ONCE_INIT;

static void scratch_clear(void *p)
{
    gmp_scratch *s = p;
    for (int i = 0; i < 5; i++)
        for (int k = 0; k < 3; k++)
            mpz_clear(s->q[i][k]);
    mpz_clears(s->m3, s->lift, s->det, s->t, NULL);
    s->ready = 0;
}

static void scratch_key_make(void)
{
    scratch_key_ok = pthread_key_create(&scratch_key, scratch_clear) == 0;
}

/* The library unloaded (dlclose) while threads that used it live on must
 * not leave them a key whose destructor is unmapped code: the key goes
 * with the library, and those threads' sets are left, a few hundred
 * bytes each. Runs at exit too, after every worker has been joined. */
__attribute__((destructor)) static void scratch_key_drop(void)
{
    if (scratch_key_ok)
        pthread_key_delete(scratch_key);
}

static gmp_scratch *scratch(void)
{
    gmp_scratch *s = &scratch_tls;
    if (!s->ready) {
        /* Sized for the usual spread of exponents (GMP would otherwise
         * grow each from nothing: 12 % of a run on points normalised onto
         * a sphere); wider inputs still grow them, once. */
        for (int i = 0; i < 5; i++)
            for (int k = 0; k < 3; k++)
                mpz_init2(s->q[i][k], 128);
        mpz_init2(s->m3, 512);
        mpz_init2(s->lift, 512);
        mpz_init2(s->det, 512);
        mpz_init2(s->t, 512);
        s->ready = 1;
        pthread_once(&scratch_once, scratch_key_make);
        if (scratch_key_ok)
            pthread_setspecific(scratch_key, s);
    }
    return s;
}

static int orient_stage_c(const double *a, const double *b, const double *c, const double *d)
{
    const double *const pts[4] = {a, b, c, d};
    int kmin = min_int_exponent(pts, 4);
    gmp_scratch *z = scratch();
    mpz_t *q[4] = {z->q[0], z->q[1], z->q[2], z->q[3]};
    for (int i = 0; i < 4; i++)
        for (int k = 0; k < 3; k++)
            fdt_mpz_set_scaled(q[i][k], pts[i][k], kmin);
    for (int i = 1; i < 4; i++)
        for (int k = 0; k < 3; k++)
            mpz_sub(q[i][k], q[i][k], q[0][k]);
    fdt_mpz_det3(z->det, q[1], q[2], q[3], z->t);
    return mpz_sgn(z->det);
}

/* Whether the n points all have the same value in one coordinate: then
 * every difference to the last point has a 0 in that column, so the
 * orient3d determinant (3 x 3 of differences) and the insphere
 * determinant (4 x 4 of differences and their squared lengths) have a
 * zero column and are exactly 0. Points of one plane of a grid, a flat
 * roof or one ring of a scanned pipe give such tests by the hundred
 * thousand, and each went through stage B or GMP to learn it (bench/
 * NOTES.md entry 53). The perturbation then decides, as for any other
 * zero. */
static inline bool share_axis_plane(const double *const *p, int n)
{
    for (int k = 0; k < 3; k++) {
        bool all = true;
        for (int i = 1; i < n && all; i++)
            all = p[i][k] == p[0][k];
        if (all)
            return true;
    }
    return false;
}

int fdt_orient3d_exact(const double *a, const double *b, const double *c,
                       const double *d, fdt_pred_counts *cnt)
{
    if (cnt)
        cnt->orient_exact++;
    const double *const pts[4] = {a, b, c, d};
    if (share_axis_plane(pts, 4))
        return 0;
    int g = orient_stage_g(a, b, c, d);
    if (g == FDT_PRED_UNSURE)
        g = orient_stage_x(a, b, c, d);
    if (g != FDT_PRED_UNSURE)
        return g;
    double u[3], v[3], w[3];
    bool exact = exact_diff3(b, a, u);
    exact = exact_diff3(c, a, v) && exact;
    exact = exact_diff3(d, a, w) && exact;
    const double lo = 0x1p-300, hi = 0x1p+300;
    if (exact && coords_in_range(a, lo, hi) && coords_in_range(b, lo, hi) &&
        coords_in_range(c, lo, hi) && coords_in_range(d, lo, hi))
        return orient_stage_b(u, v, w);
    return orient_stage_c(a, b, c, d);
}

/*
 * Second chance for the filters, on inputs far from 1 in scale. The
 * bounds need the permanent above 2^-800 (below it, underflow may eat the
 * margin), so differences below about 2^-266 (orient3d, degree 3) or
 * 2^-160 (insphere, degree 5) always failed the filter: a cluster of
 * points 1e-150 across next to points at 1 (prepare scales the largest
 * coordinate near 1) sent every predicate among its points to the exact
 * stages, and those inputs ran thousands of times slower. Both signs are
 * invariant under scaling the differences by a positive power of two, and
 * the filters' proofs hold for any rounded differences: scaling them is
 * exact, except that a value scaled into the subnormal range may lose up
 * to 2^-1075, one more absolute error of the size the proofs' underflow
 * term U already allows for (U is below 2^-92 perm with room to spare).
 * Differences within [2^-100, 2^100] are not rescaled: there the filter
 * failed because the sign is close, and rescaling cannot help.
 */
static int rescale_diffs(double (*rows)[3], int nrows)
{
    double m = 0.0;
    for (int i = 0; i < nrows; i++)
        for (int k = 0; k < 3; k++)
            m = fmax(m, fabs(rows[i][k]));
    if (m == 0.0 || !isfinite(m) || (m >= 0x1p-100 && m <= 0x1p100))
        return 0;
    int e = ilogb(m);
    for (int i = 0; i < nrows; i++)
        for (int k = 0; k < 3; k++)
            rows[i][k] = ldexp(rows[i][k], -e);
    return 1;
}

/* orient3d's determinant is linear in each row, so each row of
 * differences may take its own power of two: a face 1e-150 across tested
 * against a point at distance 1 becomes well scaled too (insphere's lifted
 * rows are not linear in the differences, so it scales them all alike). */
static int orient3d_filter_rescaled(const double *a, const double *b,
                                    const double *c, const double *d)
{
    double r[3][3];
    int any = 0;
    for (int k = 0; k < 3; k++) {
        r[0][k] = b[k] - a[k];
        r[1][k] = c[k] - a[k];
        r[2][k] = d[k] - a[k];
    }
    for (int i = 0; i < 3; i++)
        any |= rescale_diffs(&r[i], 1);
    if (!any)
        return FDT_PRED_UNSURE;
    return fdt_orient3d_filter_diff(r[0], r[1], r[2], 0, 1, 0);
}

static int insphere_filter_rescaled(const double *a, const double *b,
                                    const double *c, const double *d,
                                    const double *e)
{
    double r[4][3];
    for (int k = 0; k < 3; k++) {
        r[0][k] = a[k] - e[k];
        r[1][k] = b[k] - e[k];
        r[2][k] = c[k] - e[k];
        r[3][k] = d[k] - e[k];
    }
    if (!rescale_diffs(r, 4))
        return FDT_PRED_UNSURE;
    return fdt_insphere_filter_diff(r[0], r[1], r[2], r[3], 0, 1, 0);
}

int fdt_orient3d(const double *a, const double *b, const double *c,
                 const double *d, fdt_pred_counts *cnt)
{
    int s = fdt_orient3d_filter(a, b, c, d);
    if (s != FDT_PRED_UNSURE)
        return s;
    /* On a binary grid the exact sign is a few products away: before the
     * rescaled filter and the adaptive stage, which can only defer an
     * exact 0 */
    s = grid_likely(a) ? orient_stage_g(a, b, c, d) : FDT_PRED_UNSURE;
    if (s != FDT_PRED_UNSURE) {
        if (cnt)
            cnt->orient_exact++;
        return s;
    }
    s = orient3d_filter_rescaled(a, b, c, d);
    if (s != FDT_PRED_UNSURE)
        return s;
    s = fdt_orient3d_adapt(a, b, c, d);
    if (s != FDT_PRED_UNSURE) {
        if (cnt)
            cnt->orient_adapt++;
        return s;
    }
    return fdt_orient3d_exact(a, b, c, d, cnt);
}

/* ------------------------------------------------------------------ */
/* insphere, exact stages. */

/* m = x1 e1 + x2 e2 + x3 e3 for 4-component expansions e_i (24 slots). */
static int combo3(double x1, const double *e1, int n1, double x2, const double *e2, int n2,
                  double x3, const double *e3, int n3, double *m)
{
    double t1[8], t2[8], t3[8], s[16];
    int m1 = scale_expansion(e1, n1, x1, t1);
    int m2 = scale_expansion(e2, n2, x2, t2);
    int m3 = scale_expansion(e3, n3, x3, t3);
    int ns = expansion_sum(t1, m1, t2, m2, s);
    return expansion_sum(s, ns, t3, m3, m);
}

/* |p|^2 as an expansion (6 slots). */
static int square_norm(const double *p, double *h)
{
    double s[3][2], t[4];
    int n[3];
    for (int k = 0; k < 3; k++) {
        double x, y;
        two_product(p[k], p[k], &x, &y);
        n[k] = 0;
        if (y != 0.0)
            s[k][n[k]++] = y;
        if (x != 0.0)
            s[k][n[k]++] = x;
    }
    int nt = expansion_sum(s[0], n[0], s[1], n[1], t);
    return expansion_sum(t, nt, s[2], n[2], h);
}

/*
 * Shewchuk's Compress, in place: the same value with few components.
 * A top-down Fast-Two-Sum sweep gathers the bits into large components;
 * a bottom-up sweep makes the result nonadjacent again (round-to-even),
 * hence valid input for expansion_sum. No zero components remain. The
 * products below would otherwise multiply component counts; after Compress
 * a degree-k value of 53-bit data has about k components. n <= 24.
 */
static int compress(double *e, int n)
{
    if (n <= 1)
        return n;
    double g[24];
    int bottom = n - 1;
    double q = e[n - 1], qq;
    for (int i = n - 2; i >= 0; i--) {
        fast_two_sum(q, e[i], &q, &qq);
        if (qq != 0.0) {
            g[bottom--] = q;
            q = qq;
        }
    }
    g[bottom] = q;
    int top = 0;
    for (int i = bottom + 1; i < n; i++) {
        fast_two_sum(g[i], q, &q, &qq);
        if (qq != 0.0)
            e[top++] = qq;
    }
    if (q != 0.0)
        e[top++] = q;
    return top;
}

/* h = e * f (scale e by each component of f and add up); h needs
 * 2 elen flen slots, at most 288 here (elen <= 24, flen <= 6). */
static int expansion_product(const double *e, int elen, const double *f, int flen, double *h)
{
    double t[48], acc[2][288];
    int n = 0, cur = 0;
    for (int i = 0; i < flen; i++) {
        int nt = scale_expansion(e, elen, f[i], t);
        double *dst = i == flen - 1 ? h : acc[cur ^ 1];
        n = expansion_sum(acc[cur], n, t, nt, dst);
        cur ^= 1;
    }
    return n; /* the last round wrote h (flen == 0: h is empty) */
}

/* The CGAL insphere sign from exact differences A..D (relative to e):
 * -sign det4, det4 as in fdt_insphere_filter. */
static int insphere_stage_b(const double *A, const double *B, const double *C, const double *D)
{
    double ab[4], bc[4], cd[4], da[4], ac[4], bd[4];
    int nab = product_diff(A[0], B[1], B[0], A[1], ab);
    int nbc = product_diff(B[0], C[1], C[0], B[1], bc);
    int ncd = product_diff(C[0], D[1], D[0], C[1], cd);
    int nda = product_diff(D[0], A[1], A[0], D[1], da);
    int nac = product_diff(A[0], C[1], C[0], A[1], ac);
    int nbd = product_diff(B[0], D[1], D[0], B[1], bd);

    /* The 3x3 minors, negated where det4 subtracts them:
     * det4 = |D|^2 abc + |C|^2 (-dab) + |B|^2 cda + |A|^2 (-bcd). */
    double m3[4][24];
    int n3[4];
    n3[0] = combo3(A[2], bc, nbc, -B[2], ac, nac, C[2], ab, nab, m3[0]);      /* abc */
    n3[1] = combo3(-D[2], ab, nab, -A[2], bd, nbd, -B[2], da, nda, m3[1]);    /* -dab */
    n3[2] = combo3(C[2], da, nda, D[2], ac, nac, A[2], cd, ncd, m3[2]);       /* cda */
    n3[3] = combo3(-B[2], cd, ncd, C[2], bd, nbd, -D[2], bc, nbc, m3[3]);     /* -bcd */
    const double *const lifted[4] = {D, C, B, A};

    double acc[2][1152], lift[6], term[288];
    int n = 0, cur = 0;
    for (int i = 0; i < 4; i++) {
        int nl = compress(lift, square_norm(lifted[i], lift));
        int nm = compress(m3[i], n3[i]);
        int nt = expansion_product(m3[i], nm, lift, nl, term);
        n = expansion_sum(acc[cur], n, term, nt, acc[cur ^ 1]);
        cur ^= 1;
    }
    return -expansion_sign(acc[cur], n);
}

static int insphere_stage_c(const double *a, const double *b, const double *c,
                            const double *d, const double *e)
{
    const double *const pts[5] = {a, b, c, d, e};
    int kmin = min_int_exponent(pts, 5);
    gmp_scratch *z = scratch();
    for (int i = 0; i < 5; i++)
        for (int k = 0; k < 3; k++)
            fdt_mpz_set_scaled(z->q[i][k], pts[i][k], kmin);
    for (int i = 0; i < 4; i++)
        for (int k = 0; k < 3; k++)
            mpz_sub(z->q[i][k], z->q[i][k], z->q[4][k]);
    /* det4 = sum over rows i of (-1)^(i+1) |P_i|^2 det3(other rows), the
     * expansion along the lift column (rows A, B, C, D = 0..3). */
    mpz_set_ui(z->det, 0);
    for (int i = 0; i < 4; i++) {
        mpz_t *rows[3];
        for (int j = 0, r = 0; j < 4; j++)
            if (j != i)
                rows[r++] = z->q[j];
        fdt_mpz_det3(z->m3, rows[0], rows[1], rows[2], z->t);
        mpz_mul(z->lift, z->q[i][0], z->q[i][0]);
        mpz_addmul(z->lift, z->q[i][1], z->q[i][1]);
        mpz_addmul(z->lift, z->q[i][2], z->q[i][2]);
        if (i % 2 == 0)
            mpz_submul(z->det, z->lift, z->m3);
        else
            mpz_addmul(z->det, z->lift, z->m3);
    }
    return -mpz_sgn(z->det);
}

int fdt_insphere_exact(const double *a, const double *b, const double *c,
                       const double *d, const double *e, fdt_pred_counts *cnt)
{
    if (cnt)
        cnt->insphere_exact++;
    const double *const pts[5] = {a, b, c, d, e};
    if (share_axis_plane(pts, 5))
        return 0;
    int g = insphere_stage_g(a, b, c, d, e);
    if (g == FDT_PRED_UNSURE)
        g = insphere_stage_x(a, b, c, d, e);
    if (g != FDT_PRED_UNSURE)
        return g;
    double A[3], B[3], C[3], D[3];
    bool exact = exact_diff3(a, e, A);
    exact = exact_diff3(b, e, B) && exact;
    exact = exact_diff3(c, e, C) && exact;
    exact = exact_diff3(d, e, D) && exact;
    const double lo = 0x1p-150, hi = 0x1p+150;
    if (exact && coords_in_range(a, lo, hi) && coords_in_range(b, lo, hi) &&
        coords_in_range(c, lo, hi) && coords_in_range(d, lo, hi) &&
        coords_in_range(e, lo, hi))
        return insphere_stage_b(A, B, C, D);
    return insphere_stage_c(a, b, c, d, e);
}

int fdt_insphere(const double *a, const double *b, const double *c,
                 const double *d, const double *e, fdt_pred_counts *cnt)
{
    int s = fdt_insphere_filter(a, b, c, d, e);
    if (s != FDT_PRED_UNSURE)
        return s;
    /* On a binary grid the exact sign is a few products away: before the
     * rescaled filter and the adaptive stage, which can only defer an exact
     * 0 (a sphere of integer points: every test of five of its points;
     * bench/NOTES.md entry 116) */
    s = grid_likely(e) ? insphere_stage_g(a, b, c, d, e) : FDT_PRED_UNSURE;
    if (s != FDT_PRED_UNSURE) {
        if (cnt)
            cnt->insphere_exact++;
        return s;
    }
    s = insphere_filter_rescaled(a, b, c, d, e);
    if (s != FDT_PRED_UNSURE)
        return s;
    s = fdt_insphere_adapt(a, b, c, d, e);
    if (s != FDT_PRED_UNSURE) {
        if (cnt)
            cnt->insphere_adapt++;
        return s;
    }
    return fdt_insphere_exact(a, b, c, d, e, cnt);
}

/* ------------------------------------------------------------------ */

int fdt_lex_compare(const double *p, const double *q)
{
    for (int k = 0; k < 3; k++) {
        if (p[k] < q[k])
            return -1;
        if (p[k] > q[k])
            return 1;
    }
    return 0;
}

int fdt_compare_dist(const double *q, const double *x, const double *y)
{
    /* Rarely called (near-ties only), so straight to integers: every
     * coordinate is m 2^k with k >= kmin, so scaling by 2^-kmin makes the
     * whole computation exact in mpz. */
    const double *const pts[3] = {q, x, y};
    int kmin = min_int_exponent(pts, 3);
    mpz_t zq, zx, zy, acc, t;
    mpz_init(zq);
    mpz_init(zx);
    mpz_init(zy);
    mpz_init(acc);
    mpz_init(t);
    for (int k = 0; k < 3; k++) {
        fdt_mpz_set_scaled(zq, q[k], kmin);
        fdt_mpz_set_scaled(zx, x[k], kmin);
        fdt_mpz_set_scaled(zy, y[k], kmin);
        mpz_sub(zx, zx, zq);
        mpz_sub(zy, zy, zq);
        mpz_addmul(acc, zx, zx);
        mpz_mul(t, zy, zy);
        mpz_sub(acc, acc, t);
    }
    int s = mpz_sgn(acc);
    mpz_clear(t);
    mpz_clear(acc);
    mpz_clear(zy);
    mpz_clear(zx);
    mpz_clear(zq);
    return s;
}

/* ldexp(n / den, k) to 53 bits, truncated: den > 0. The quotient is first
 * taken to 64-65 significant bits (integer division, so the one
 * truncation there is below 2^-63 relative), then mpz_get_d truncates to
 * 53: within 2^-52 of the true value in all. */
static double mpz_ratio_ldexp(const mpz_t n, const mpz_t den, long k, mpz_t t)
{
    if (mpz_sgn(n) == 0)
        return 0.0;
    long sh = 64 - ((long)mpz_sizeinbase(n, 2) - (long)mpz_sizeinbase(den, 2));
    if (sh >= 0) {
        mpz_mul_2exp(t, n, (mp_bitcnt_t)sh);
        mpz_tdiv_q(t, t, den);
    } else {
        mpz_tdiv_q_2exp(t, n, (mp_bitcnt_t)(-sh));
        mpz_tdiv_q(t, t, den);
    }
    long e = k - sh;
    if (e > 4000)
        return mpz_sgn(n) > 0 ? INFINITY : -INFINITY;
    if (e < -4000)
        return 0.0;
    return ldexp(mpz_get_d(t), (int)e);
}

int fdt_circumcenter_exact(const double *a, const double *b, const double *c,
                           const double *d, double x[3])
{
    const double *const pts[4] = {a, b, c, d};
    int kmin = min_int_exponent(pts, 4);
    /* q[0] = a; q[1..3] = u, v, w = b - a, c - a, d - a (scaled, exact) */
    mpz_t q[4][3], cr[3][3], len[3], num[3], det, t;
    for (int i = 0; i < 4; i++)
        for (int k = 0; k < 3; k++) {
            mpz_init(q[i][k]);
            fdt_mpz_set_scaled(q[i][k], pts[i][k], kmin);
        }
    for (int i = 1; i < 4; i++)
        for (int k = 0; k < 3; k++)
            mpz_sub(q[i][k], q[i][k], q[0][k]);
    for (int i = 0; i < 3; i++) {
        mpz_init(len[i]);
        mpz_init(num[i]);
        for (int k = 0; k < 3; k++)
            mpz_init(cr[i][k]);
    }
    mpz_init(det);
    mpz_init(t);
    /* cr[0] = v x w, cr[1] = w x u, cr[2] = u x v; len[i] = |row i|^2 */
    for (int i = 0; i < 3; i++) {
        mpz_t *p = q[1 + (i + 1) % 3], *r = q[1 + (i + 2) % 3];
        for (int k = 0; k < 3; k++) {
            int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
            mpz_mul(cr[i][k], p[k1], r[k2]);
            mpz_submul(cr[i][k], p[k2], r[k1]);
        }
        mpz_set_ui(len[i], 0);
        for (int k = 0; k < 3; k++)
            mpz_addmul(len[i], q[1 + i][k], q[1 + i][k]);
    }
    /* x = (|u|^2 (v x w) + |v|^2 (w x u) + |w|^2 (u x v)) / (2 u.(v x w)) */
    mpz_set_ui(det, 0);
    for (int k = 0; k < 3; k++)
        mpz_addmul(det, q[1][k], cr[0][k]);
    int rc = 0;
    if (mpz_sgn(det) == 0)
        rc = -1;
    else {
        int neg = mpz_sgn(det) < 0;
        mpz_abs(det, det);
        mpz_mul_2exp(det, det, 1);
        for (int k = 0; k < 3 && rc == 0; k++) {
            mpz_mul(num[k], len[0], cr[0][k]);
            mpz_addmul(num[k], len[1], cr[1][k]);
            mpz_addmul(num[k], len[2], cr[2][k]);
            if (neg)
                mpz_neg(num[k], num[k]);
            x[k] = mpz_ratio_ldexp(num[k], det, kmin, t);
            if (!isfinite(x[k]))
                rc = -1;
        }
    }
    mpz_clear(t);
    mpz_clear(det);
    for (int i = 0; i < 3; i++) {
        mpz_clear(len[i]);
        mpz_clear(num[i]);
        for (int k = 0; k < 3; k++)
            mpz_clear(cr[i][k]);
    }
    for (int i = 0; i < 4; i++)
        for (int k = 0; k < 3; k++)
            mpz_clear(q[i][k]);
    return rc;
}

/* The circumcentre formula of fdt_circumcenter_exact in double words:
 * the differences exact (Two-Diff), every product and sum a double word
 * (dw_mul, dw_add: relative error a few eps^2 each). The numerators and
 * the determinant cancel by at most the tet's condition K = |u||v||w| /
 * |det| (what makes the floating formula lose 8 K ulps), so they keep
 * about 2^-100 K of their size: for K <= 2^40 the centre is right to
 * a few ulps of the circumradius (tests/test_predicates.c: at most 3.4). Needs the differences within
 * [2^-200, 2^200] (no split overflows, no tail underflows); the caller
 * checks. */
static void circumcenter_dw(const double *a, const double *b, const double *c, const double *d,
                            double x[3])
{
    dword u[3], v[3], w[3], vw[3], wu[3], uv[3];
    for (int k = 0; k < 3; k++) {
        two_diff(b[k], a[k], &u[k].hi, &u[k].lo);
        two_diff(c[k], a[k], &v[k].hi, &v[k].lo);
        two_diff(d[k], a[k], &w[k].hi, &w[k].lo);
    }
    const dword *rows[3][2] = {{v, w}, {w, u}, {u, v}};
    dword *out[3] = {vw, wu, uv};
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) {
            int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
            out[i][k] = dw_sub(dw_mul(rows[i][0][k1], rows[i][1][k2]),
                               dw_mul(rows[i][0][k2], rows[i][1][k1]));
        }
    dword len[3], det = {0, 0};
    const dword *e[3] = {u, v, w};
    for (int i = 0; i < 3; i++) {
        len[i] = (dword){0, 0};
        for (int k = 0; k < 3; k++) {
            len[i] = dw_add(len[i], dw_mul(e[i][k], e[i][k]));
            if (i == 0)
                det = dw_add(det, dw_mul(u[k], vw[k]));
        }
    }
    for (int k = 0; k < 3; k++) {
        dword num = dw_add(dw_add(dw_mul(len[0], vw[k]), dw_mul(len[1], wu[k])),
                           dw_mul(len[2], uv[k]));
        x[k] = (num.hi + num.lo) / (2 * (det.hi + det.lo));
    }
}

/* predicates.h. Three tiers by the tet's condition K = |u||v||w| / |det|
 * (u, v, w the edges from a): the floating formula for K <= 2^4, whose
 * error is then at most about 8 K = 2^7 ulps of the circumradius (with
 * 2^16, the Voronoi cells' first bound, natural-neighbour coordinates next
 * to 1e-3 wide clusters drifted by 3e-11, with 2^8 by 3e-13: bench/
 * NOTES.md entry 95); double words up to K = 2^40 (a few ulps; about 0.3 us a tet);
 * the exact centre (GMP, some microseconds) beyond, or where the
 * differences leave the double words' range. */
int fdt_circumcenter(const double *a, const double *b, const double *c, const double *d,
                     double x[3])
{
    double u[3], v[3], w[3], vw[3], wu[3], uv[3];
    for (int k = 0; k < 3; k++) {
        u[k] = b[k] - a[k];
        v[k] = c[k] - a[k];
        w[k] = d[k] - a[k];
    }
    cross3(v, w, vw);
    cross3(w, u, wu);
    cross3(u, v, uv);
    double uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
    double vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    double ww = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
    double det = u[0] * vw[0] + u[1] * vw[1] + u[2] * vw[2];
    double l = sqrt(uu * vv * ww);
    if (fabs(det) >= 0x1p-4 * l) {
        for (int k = 0; k < 3; k++)
            x[k] = (uu * vw[k] + vv * wu[k] + ww * uv[k]) / (2 * det);
        return 0;
    }
    double mx = 0, mn = INFINITY;
    for (int k = 0; k < 3; k++) {
        const double e[3] = {fabs(u[k]), fabs(v[k]), fabs(w[k])};
        for (int i = 0; i < 3; i++) {
            mx = fmax(mx, e[i]);
            if (e[i] > 0)
                mn = fmin(mn, e[i]);
        }
    }
    if (fabs(det) >= 0x1p-40 * l && mx <= 0x1p200 && mn >= 0x1p-200) {
        circumcenter_dw(a, b, c, d, x);
        return 0;
    }
    return fdt_circumcenter_exact(a, b, c, d, x);
}

/* The circumcentre of the triangle (0, e1, e2):
 * (|e1|^2 e2 - |e2|^2 e1) x (e1 x e2) / (2 |e1 x e2|^2), given n = e1 x e2,
 * nn = |n|^2, aa = |e1|^2 and bb = |e2|^2 as the caller computed them. */
static void tri_centre(const double *e1, const double *e2, const double *n, double nn, double aa,
                       double bb, double *x)
{
    double t[3];
    for (int k = 0; k < 3; k++)
        t[k] = aa * e2[k] - bb * e1[k];
    cross3(t, n, x);
    for (int k = 0; k < 3; k++)
        x[k] /= 2 * nn;
}

/* predicates.h: without the exact fallback the Voronoi cells next to a
 * nearly collinear face lost up to 1e-8 of their volume (gen_points
 * clusters, bench/NOTES.md entry 92). */
void fdt_circumcenter_tri(const double *a, const double *b, const double *c, double x[3])
{
    double e1[3], e2[3], n[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = b[k] - a[k];
        e2[k] = c[k] - a[k];
    }
    cross3(e1, e2, n);
    double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    double l1 = e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2];
    double l2 = e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2];
    if (nn >= 0x1p-20 * l1 * l2) {
        tri_centre(e1, e2, n, nn, l1, l2, x);
        return;
    }
    double d[3] = {a[0] + n[0], a[1] + n[1], a[2] + n[2]}, X[3];
    int got = nn > 0 ? fdt_circumcenter_exact(a, b, c, d, X) : -1;
    if (got != 0 && nn > 0) {
        int ex;
        (void)frexp(sqrt(l1 / nn), &ex);
        for (int k = 0; k < 3; k++)
            d[k] = a[k] + ldexp(n[k], ex);
        got = fdt_circumcenter_exact(a, b, c, d, X);
    }
    if (got != 0) {
        tri_centre(e1, e2, n, nn, l1, l2, x); /* collinear to the last bit: nothing better */
        return;
    }
    double t = (X[0] * n[0] + X[1] * n[1] + X[2] * n[2]) / nn;
    for (int k = 0; k < 3; k++)
        x[k] = X[k] - t * n[k];
}

/*
 * The symbolic tie-break of the perturbed insphere, for five pairwise
 * distinct points with (a,b,c,d) positively oriented and e exactly on
 * their sphere.
 *
 * Devillers & Teillaud lift each point p to |p|^2 + eps_p, with eps_p
 * infinitely larger for lexicographically larger p. The lifted 5x5
 * determinant is linear in each eps_p, so once its constant term (the
 * unperturbed insphere) vanishes, its sign is that of the coefficient of
 * the largest eps_p that is nonzero, taken in decreasing lexicographic
 * order of p. That coefficient is, in CGAL's sign convention:
 *   p == e:            -1 (it is -orient(a,b,c,d), and (a,b,c,d) is
 *                      positive): e is outside;
 *   p one of a,b,c,d:  orient3d of (a,b,c,d) with p replaced by e in its
 *                      position.
 * This is CGAL's Delaunay_triangulation_3::side_of_oriented_sphere with
 * perturb=true.
 *
 * Termination: the first two points examined cannot both give 0. If the
 * largest is e we stop at once. Otherwise, if both of the first two are
 * among a,b,c,d (say p and p'), two zero orientations put e on both planes
 * spanned by the other two points with p' and with p; those planes are
 * distinct (a,b,c,d are not coplanar) and meet in the line through the two
 * remaining points, which meets the sphere only in those two points; e,
 * on the sphere, would equal one of them. If the second is e we stop
 * there. So the final return is unreachable under the precondition.
 */
static int insphere_tiebreak(const double *a, const double *b, const double *c,
                             const double *d, const double *e, fdt_pred_counts *cnt)
{
    const double *p[5] = {a, b, c, d, e};
    int order[5] = {0, 1, 2, 3, 4};
    /* Insertion sort, lexicographically decreasing. */
    for (int i = 1; i < 5; i++) {
        int x = order[i], j = i;
        while (j > 0 && fdt_lex_compare(p[order[j - 1]], p[x]) < 0) {
            order[j] = order[j - 1];
            j--;
        }
        order[j] = x;
    }
    for (int r = 0; r < 5; r++) {
        int i = order[r];
        if (i == 4)
            return -1;
        const double *q[4] = {a, b, c, d};
        q[i] = e;
        int o = fdt_orient3d(q[0], q[1], q[2], q[3], cnt);
        if (o != 0)
            return o;
    }
    return -1; /* unreachable under the precondition (see above) */
}

int fdt_insphere_perturbed(const double *a, const double *b, const double *c,
                           const double *d, const double *e,
                           fdt_pred_counts *cnt)
{
    int s = fdt_insphere(a, b, c, d, e, cnt);
    if (s != 0)
        return s;
    return insphere_tiebreak(a, b, c, d, e, cnt);
}
