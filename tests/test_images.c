/*
 * Tests for src/geom/images.c: periodic images and the predicates on
 * them, against signs computed here with GMP rationals from the input
 * points, the offsets and the box (an independent spelling of the exact
 * images x + o (hi - lo)).
 *  - fdt_images_round: the exact flag (1 only for the exact image) and
 *    the error bound;
 *  - the semi-static filter on rounded images (fdt_images_static's
 *    bounds): a sign it gives is the exact images' sign;
 *  - fdt_images_orient and fdt_images_insphere (that stage, then the
 *    dynamic one widened by the images' rounding, predicates.h's
 *    fdt_pred_moved, then the exact stages): the
 *    exact sign wherever it is not 0, and inside clusters without the
 *    exact stages on most calls (the box's bounds, a run's, decide none).
 * Inputs: small clusters (1e-3 to 1e-12 of the box) at the box's walls,
 * with every point an image, or some (a cluster across the wall), and
 * clusters whose exact images are coplanar or cospherical (translates of
 * points that are), where the rounded images are not: there the filters
 * must not decide, which a filter without the images' rounding does.
 */
#include <gmp.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "geom/images.h"
#include "testutil.h"

static uint64_t seed = 0x1234abcdu;

static double unif(void)
{
    return (double)(test_rand64(&seed) >> 11) * 0x1p-53;
}

/* The exact image of x under offsets o in the box (lo, hi), as rationals. */
static void exact_image(mpq_t out[3], const double x[3], const int8_t o[3], const double lo[3],
                        const double hi[3])
{
    mpq_t t;
    mpq_init(t);
    for (int k = 0; k < 3; k++) {
        mpq_set_d(out[k], x[k]);
        mpq_set_d(t, hi[k]);
        mpq_t l;
        mpq_init(l);
        mpq_set_d(l, lo[k]);
        mpq_sub(t, t, l); /* the period */
        mpq_clear(l);
        for (int r = 0; r < abs(o[k]); r++)
            (o[k] > 0 ? mpq_add : mpq_sub)(out[k], out[k], t);
    }
    mpq_clear(t);
}

/* The permutations of three columns, the even ones first. */
static const int perm3[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};

/* s = the 3x3 determinant of rows r[0..2] (s initialised). */
static void det3(mpq_t s, mpq_t r[3][3])
{
    mpq_t a;
    mpq_init(a);
    mpq_set_ui(s, 0, 1);
    for (int i = 0; i < 6; i++) {
        mpq_mul(a, r[0][perm3[i][0]], r[1][perm3[i][1]]);
        mpq_mul(a, a, r[2][perm3[i][2]]);
        (i < 3 ? mpq_add : mpq_sub)(s, s, a);
    }
    mpq_clear(a);
}

/* The sign of the 3x3 determinant of rows r[0..2]. */
static int det3_sign(mpq_t r[3][3])
{
    mpq_t s;
    mpq_init(s);
    det3(s, r);
    int sg = mpq_sgn(s);
    mpq_clear(s);
    return sg;
}

/* orient3d of the exact points q[0..3] (CGAL's sign, as fdt_orient3d:
 * that of det[b - a; c - a; d - a]). */
static int exact_orient(mpq_t q[5][3])
{
    mpq_t r[3][3];
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++) {
            mpq_init(r[i][k]);
            mpq_sub(r[i][k], q[i + 1][k], q[0][k]);
        }
    int s = det3_sign(r);
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            mpq_clear(r[i][k]);
    return s;
}

/* CGAL's insphere sign of q[4] against q[0..3], unperturbed: minus the
 * sign of det[p - e, |p - e|^2] (rows p = q[0..3], e = q[4]), expanded
 * along the lifted column. */
static int exact_insphere(mpq_t q[5][3])
{
    mpq_t d[4][4], acc, t;
    mpq_inits(acc, t, NULL);
    for (int r = 0; r < 4; r++) {
        mpq_init(d[r][3]);
        for (int k = 0; k < 3; k++) {
            mpq_init(d[r][k]);
            mpq_sub(d[r][k], q[r][k], q[4][k]);
            mpq_mul(t, d[r][k], d[r][k]);
            mpq_add(d[r][3], d[r][3], t);
        }
    }
    for (int r = 0; r < 4; r++) {
        mpq_t m[3][3];
        int w = 0;
        for (int i = 0; i < 4; i++) {
            if (i == r)
                continue;
            for (int k = 0; k < 3; k++) {
                mpq_init(m[w][k]);
                mpq_set(m[w][k], d[i][k]);
            }
            w++;
        }
        mpq_t s; /* the minor's value, not only its sign */
        mpq_init(s);
        det3(s, m);
        mpq_mul(s, s, d[r][3]);
        ((r + 3) % 2 == 0 ? mpq_add : mpq_sub)(acc, acc, s);
        mpq_clear(s);
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++)
                mpq_clear(m[i][k]);
    }
    int s = -mpq_sgn(acc);
    for (int r = 0; r < 4; r++)
        for (int k = 0; k < 4; k++)
            mpq_clear(d[r][k]);
    mpq_clears(acc, t, NULL);
    return s;
}

/* Five points and their images, as a periodic run holds them. */
typedef struct five {
    double X[15];       /* the input points */
    uint32_t src[5];
    int8_t off[15];
    double P[15];       /* the rounded images */
    uint8_t exact[5];
    fdt_images im;
} five;

/* The images of f->X under f->off in (lo, hi), rounded, and the filters'
 * bounds for them: those of a run's points, the box and a period around. */
static void five_make(five *f, const double lo[3], const double hi[3])
{
    double err = 0;
    for (int i = 0; i < 5; i++) {
        double e;
        f->src[i] = (uint32_t)i;
        f->exact[i] = (uint8_t)fdt_images_round(f->X + 3 * i, f->off + 3 * i, lo, hi, f->P + 3 * i,
                                                &e);
        err = e > err ? e : err;
    }
    memset(&f->im, 0, sizeof f->im);
    f->im.P = f->P;
    f->im.n = 5;
    f->im.X = f->X;
    f->im.src = f->src;
    f->im.off = f->off;
    f->im.exact = f->exact;
    memcpy(f->im.lo, lo, sizeof f->im.lo);
    memcpy(f->im.hi, hi, sizeof f->im.hi);
    double blo[3], bhi[3];
    for (int k = 0; k < 3; k++) {
        blo[k] = lo[k] - (hi[k] - lo[k]);
        bhi[k] = hi[k] + (hi[k] - lo[k]);
    }
    fdt_images_init(&f->im, blo, bhi, err);
}

/* fdt_images_round against the exact image: the flag, and the bound. */
static void check_round(const five *f, mpq_t q[5][3], const double lo[3], const double hi[3])
{
    mpq_t d, e;
    mpq_inits(d, e, NULL);
    for (int i = 0; i < 5; i++) {
        double out[3], err;
        int ex = fdt_images_round(f->X + 3 * i, f->off + 3 * i, lo, hi, out, &err);
        int same = 1;
        for (int k = 0; k < 3; k++) {
            mpq_set_d(d, out[k]);
            mpq_sub(d, d, q[i][k]);
            same &= mpq_sgn(d) == 0;
            mpq_abs(d, d);
            mpq_set_d(e, err);
            EXPECTF(mpq_cmp(d, e) <= 0, "point %d axis %d: the rounding is past its bound", i, k);
        }
        EXPECT(!ex || same); /* 0 may still be exact: tails that cancel */
    }
    mpq_clears(d, e, NULL);
}

typedef struct tally {
    long orient_filtered, insphere_filtered, degenerate;
    fdt_pred_counts exact; /* the predicates' calls to their exact stages */
} tally;

/* Every sign of f's filters and predicates against the exact images. */
static void check_five(five *f, const double lo[3], const double hi[3], tally *ty)
{
    mpq_t q[5][3];
    for (int i = 0; i < 5; i++) {
        for (int k = 0; k < 3; k++)
            mpq_init(q[i][k]);
        exact_image(q[i], f->X + 3 * i, f->off + 3 * i, lo, hi);
    }
    check_round(f, q, lo, hi);
    const double *p[5] = {f->P, f->P + 3, f->P + 6, f->P + 9, f->P + 12};
    const fdt_pred_static sf = fdt_images_static(&f->im);
    int o = exact_orient(q);
    int fo = fdt_orient3d_filter_sf(p[0], p[1], p[2], p[3], &sf);
    if (fo != FDT_PRED_UNSURE) {
        ty->orient_filtered++;
        EXPECTF(fo == o, "orient3d filter %d, exact %d", fo, o);
    }
    EXPECT(fdt_images_orient(&f->im, p[0], p[1], p[2], p[3], &ty->exact) == o);
    if (o == 0)
        ty->degenerate++;
    if (o != 0) {
        /* insphere's precondition: a positive tet */
        if (o < 0) {
            const double *t = p[0];
            p[0] = p[1];
            p[1] = t;
            for (int k = 0; k < 3; k++)
                mpq_swap(q[0][k], q[1][k]);
        }
        int s = exact_insphere(q);
        int fs = fdt_insphere_filter_sf(p[0], p[1], p[2], p[3], p[4], &sf);
        if (fs != FDT_PRED_UNSURE) {
            ty->insphere_filtered++;
            EXPECTF(fs == s, "insphere filter %d, exact %d", fs, s);
        }
        int ps = fdt_images_insphere(&f->im, p[0], p[1], p[2], p[3], p[4], &ty->exact);
        EXPECT(ps == 1 || ps == -1);
        if (s != 0)
            EXPECTF(ps == s, "insphere %d, exact %d", ps, s);
        else
            ty->degenerate++;
    }
    for (int i = 0; i < 5; i++)
        for (int k = 0; k < 3; k++)
            mpq_clear(q[i][k]);
}

/* A box whose periods are not doubles' differences to the last bit. */
static void make_box(double lo[3], double hi[3])
{
    for (int k = 0; k < 3; k++) {
        lo[k] = -0.3 + 0.2 * unif();
        hi[k] = lo[k] + 0.9 + 0.4 * unif();
    }
}

/*
 * Random clusters at a wall: side h of the box, by the lower wall on one
 * axis; each point an image (offset +1 there: past the upper wall, where
 * the box makes |hi| > |lo| and so the images' last place coarser than
 * the points', rounded) or, across the wall, some points by the upper
 * wall with offset 0.
 */
static void clusters(long n, const double *sides, int nsides, tally *ty)
{
    for (long it = 0; it < n; it++) {
        double lo[3], hi[3];
        make_box(lo, hi);
        double h = sides[it % nsides] * (0.5 + unif());
        int ax = (int)(it / nsides % 3), across = (int)(it / (3 * nsides) % 2);
        five f;
        memset(&f, 0, sizeof f);
        for (int i = 0; i < 5; i++)
            for (int k = 0; k < 3; k++) {
                double c = k == ax ? lo[k] + h : lo[k] + 0.5 * (hi[k] - lo[k]);
                double x = c + h * unif();
                f.off[3 * i + k] = 0;
                if (k == ax) {
                    if (across && i % 2) /* by the upper wall, itself */
                        x = hi[k] - h * unif();
                    else
                        f.off[3 * i + k] = 1;
                }
                f.X[3 * i + k] = x;
            }
        five_make(&f, lo, hi);
        check_five(&f, lo, hi, ty);
    }
}

/*
 * Clusters whose exact images are coplanar (the first four points) or
 * cospherical (all five): translates by one offset of points that are,
 * in the doubles, rounded differently. Each point has its own x, so that
 * the images' roundings differ (points sharing an x round alike: a
 * parallelogram or a box's corners would stay planar or cospherical):
 * points of the plane z = x, or of the sphere of radius 5 h about c with
 * integer coordinates in units of h = 2^-j (down to the points' last
 * place, 2^-54 by the lower walls, finer than the images' by the upper),
 * at a corner c on h's grid.
 */
static void degenerate(long n, tally *ty)
{
    static const int sphere[5][3] = {{5, 0, 0}, {0, 5, 0}, {3, 4, 0}, {4, 0, 3}, {-3, 0, -4}};
    static const int plane[5][3] = {{0, 0, 0}, {1, 2, 1}, {2, 1, 2}, {3, 3, 3}, {1, 1, 0}};
    for (long it = 0; it < n; it++) {
        double lo[3], hi[3];
        make_box(lo, hi);
        int j = 10 + (int)(it % 45);
        double h = ldexp(1.0, -j);
        five f;
        memset(&f, 0, sizeof f);
        int8_t o[3] = {0, 0, 0};
        o[it % 3] = 1;
        o[(it / 3) % 3] = 1;
        double c[3];
        for (int k = 0; k < 3; k++) {
            c[k] = ldexp(floor(ldexp(lo[k] + 6 * h, j)), -j); /* on h's grid */
        }
        const int(*u)[3] = it % 2 ? sphere : plane;
        for (int i = 0; i < 5; i++) {
            for (int k = 0; k < 3; k++)
                f.X[3 * i + k] = c[k] + h * u[i][k];
            memcpy(f.off + 3 * i, o, 3);
        }
        five_make(&f, lo, hi);
        check_five(&f, lo, hi, ty);
    }
}

int main(void)
{
    /* Clusters 1e-6 and 1e-9 of the box across: its bounds decide
     * nothing, the dynamic stage nearly everything (without it every call
     * went to the exact stages, bench/NOTES.md entry 119). At 1e-12 the
     * images' rounding is a ten-thousandth of a difference: signs only. */
    static const double small[2] = {1e-6, 1e-9}, others[2] = {1e-3, 1e-12};
    tally ty;
    memset(&ty, 0, sizeof ty);
    clusters(2000, small, 2, &ty);
    EXPECTF(ty.orient_filtered == 0 && ty.insphere_filtered == 0,
            "orient3d %ld, insphere %ld of 2000 decided by the box's bounds", ty.orient_filtered,
            ty.insphere_filtered);
    EXPECTF(ty.exact.orient_exact < 20 && ty.exact.insphere_exact < 20,
            "orient3d %zu, insphere %zu of 2000 exact", ty.exact.orient_exact,
            ty.exact.insphere_exact);
    memset(&ty, 0, sizeof ty);
    clusters(2000, others, 2, &ty);
    tally dg;
    memset(&dg, 0, sizeof dg);
    degenerate(2000, &dg);
    /* every set degenerate in its exact images */
    EXPECTF(dg.degenerate == 2000, "%ld of 2000 sets degenerate", dg.degenerate);
    return test_report("images");
}
