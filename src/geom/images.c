/* Periodic images and exact predicates on them; see images.h. */
#include "geom/images.h"

#include <float.h>
#include <gmp.h>
#include <limits.h>
#include <string.h>

#include "geom/exact_gmp.h"

/* a + b = s + t exactly (Knuth's TwoSum). */
static void two_sum(double a, double b, double *s, double *t)
{
    *s = a + b;
    double bv = *s - a, av = *s - bv;
    *t = (a - av) + (b - bv);
}

int fdt_images_round(const double x[3], const int8_t off[3], const double lo[3],
                     const double hi[3], double out[3], double *err)
{
    const double eps = 0x1p-53, tiny = 0x1p-1073;
    int exact = 1;
    double e = 0;
    for (int k = 0; k < 3; k++) {
        if (off[k] == 0) {
            out[k] = x[k];
            continue;
        }
        /* x + o hi - o lo, o = +-1: two exact sums, then their tails */
        double o = off[k], s, t1, h, t2;
        two_sum(x[k], o * hi[k], &s, &t1);
        two_sum(s, -o * lo[k], &h, &t2);
        double t = t1 + t2;
        out[k] = h + t;
        if (t1 != 0 || t2 != 0) {
            exact = 0;
            /* |h + t1 + t2 - out| <= eps |t| (the tails' sum) + eps |out| */
            double ek = 2 * eps * (fabs(t) + fabs(out[k])) + tiny;
            e = ek > e ? ek : e;
        }
    }
    if (err)
        *err = e;
    return exact;
}

void fdt_images_init(fdt_images *im, const double blo[3], const double bhi[3], double err)
{
    im->o3d_inv = im->isp_inv = 0;
    im->err = err;
    double M = 0;
    for (int k = 0; k < 3; k++) {
        double d = bhi[k] - blo[k];
        if (!(d >= 0 && d <= DBL_MAX))
            return;
        M = d > M ? d : M;
    }
    if (!(M >= 0x1p-100 && M <= 0x1p100) || !(err >= 0 && err <= M))
        return;
    /* The evaluation's rounding (twice the plain filters' constants, a
     * margin: the evaluation is theirs, predicates.h's _sf filters), then the inputs' movement by
     * e = 2 err a difference, expanded so nothing cancels; 1 + 2^-20 for
     * the roundings of these bounds themselves. */
    const double safe = 1 + 0x1p-20, e = 2 * err;
    const double M2 = M * M, M3 = M2 * M, M4 = M3 * M, M5 = M4 * M;
    double o3d = 2 * FDT_O3D_ERRBOUND * 6 * M3 + 6 * (3 * M2 * e + 3 * M * e * e + e * e * e);
    double isp = 2 * FDT_ISP_ERRBOUND * 72 * M5 +
                 72 * (5 * M4 * e + 10 * M3 * e * e + 10 * M2 * e * e * e +
                       5 * M * e * e * e * e + e * e * e * e * e);
    o3d *= safe;
    isp *= safe;
    if (o3d < 0x1p-790 || isp < 0x1p-790)
        return;
    im->o3d_inv = (1 / o3d) * (1 - 0x1p-50);
    im->isp_inv = (1 / isp) * (1 - 0x1p-50);
}

/* ---- the exact stage: GMP integers of the exact images --------------- */

/* Up to five points' exact coordinates, as integers in units of 2^kmin. */
typedef struct exact_pts {
    mpz_t q[5][3];
    mpz_t t, r, s;
    int np;
    int kmin; /* the integers' unit: 2^kmin */
} exact_pts;

static void exact_init(exact_pts *z, const fdt_images *im, const uint32_t *i, int np)
{
    z->np = np;
    int kmin = INT_MAX;
    for (int j = 0; j < np; j++) {
        const double *x = im->X + 3 * (size_t)im->src[i[j]];
        const int8_t *o = im->off + 3 * (size_t)i[j];
        for (int k = 0; k < 3; k++) {
            const double v[3] = {x[k], o[k] ? im->hi[k] : 0.0, o[k] ? im->lo[k] : 0.0};
            for (int w = 0; w < 3; w++)
                if (v[w] != 0.0) {
                    int e = fdt_int_exponent(v[w]);
                    kmin = e < kmin ? e : kmin;
                }
        }
    }
    if (kmin == INT_MAX)
        kmin = 0;
    z->kmin = kmin;
    mpz_inits(z->t, z->r, z->s, NULL);
    for (int j = 0; j < np; j++) {
        const double *x = im->X + 3 * (size_t)im->src[i[j]];
        const int8_t *o = im->off + 3 * (size_t)i[j];
        for (int k = 0; k < 3; k++) {
            mpz_init(z->q[j][k]);
            fdt_mpz_set_scaled(z->q[j][k], x[k], kmin);
            if (o[k]) {
                fdt_mpz_set_scaled(z->t, im->hi[k], kmin);
                fdt_mpz_set_scaled(z->r, im->lo[k], kmin);
                mpz_sub(z->t, z->t, z->r);
                if (o[k] > 0)
                    mpz_addmul_ui(z->q[j][k], z->t, (unsigned long)o[k]);
                else
                    mpz_submul_ui(z->q[j][k], z->t, (unsigned long)-o[k]);
            }
        }
    }
}

static void exact_clear(exact_pts *z)
{
    for (int j = 0; j < z->np; j++)
        for (int k = 0; k < 3; k++)
            mpz_clear(z->q[j][k]);
    mpz_clears(z->t, z->r, z->s, NULL);
}

/* sign det[q1 - q0; q2 - q0; q3 - q0] of the points j[0..3] of z. */
static int orient_z(exact_pts *z, const int j[4])
{
    mpz_t d[3][3];
    for (int r = 0; r < 3; r++)
        for (int k = 0; k < 3; k++) {
            mpz_init(d[r][k]);
            mpz_sub(d[r][k], z->q[j[r + 1]][k], z->q[j[0]][k]);
        }
    fdt_mpz_det3(z->s, d[0], d[1], d[2], z->t);
    for (int r = 0; r < 3; r++)
        for (int k = 0; k < 3; k++)
            mpz_clear(d[r][k]);
    return mpz_sgn(z->s);
}

int fdt_images_orient_exact(const fdt_images *im, const uint32_t i[4], fdt_pred_counts *cnt)
{
    if (cnt)
        cnt->orient_exact++;
    exact_pts z;
    exact_init(&z, im, i, 4);
    static const int j[4] = {0, 1, 2, 3};
    int s = orient_z(&z, j);
    exact_clear(&z);
    return s;
}

/* Lexicographic comparison of points a and b of z. */
static int lex_z(const exact_pts *z, int a, int b)
{
    for (int k = 0; k < 3; k++) {
        int c = mpz_cmp(z->q[a][k], z->q[b][k]);
        if (c)
            return c < 0 ? -1 : 1;
    }
    return 0;
}

/* CGAL's insphere sign of e = point 4 against (0, 1, 2, 3): minus the
 * sign of det[p - e, |p - e|^2] (src/geom/predicates.h's filter). */
static int insphere_z(exact_pts *z)
{
    mpz_t d[4][4];
    for (int r = 0; r < 4; r++) {
        mpz_init(d[r][3]);
        for (int k = 0; k < 3; k++) {
            mpz_init(d[r][k]);
            mpz_sub(d[r][k], z->q[r][k], z->q[4][k]);
            mpz_addmul(d[r][3], d[r][k], d[r][k]);
        }
    }
    /* Laplace along the lifted column: sum_r (-1)^(r+3) l_r minor_r. */
    mpz_t acc;
    mpz_init(acc);
    for (int r = 0; r < 4; r++) {
        mpz_t *rows[3];
        int w = 0;
        for (int q = 0; q < 4; q++)
            if (q != r)
                rows[w++] = d[q];
        fdt_mpz_det3(z->s, rows[0], rows[1], rows[2], z->t);
        mpz_mul(z->s, z->s, d[r][3]);
        if ((r + 3) % 2 == 0)
            mpz_add(acc, acc, z->s);
        else
            mpz_sub(acc, acc, z->s);
    }
    int s = -mpz_sgn(acc);
    mpz_clear(acc);
    for (int r = 0; r < 4; r++)
        for (int k = 0; k < 4; k++)
            mpz_clear(d[r][k]);
    return s;
}

int fdt_images_insphere_exact(const fdt_images *im, const uint32_t i[5], fdt_pred_counts *cnt)
{
    if (cnt)
        cnt->insphere_exact++;
    exact_pts z;
    exact_init(&z, im, i, 5);
    int s = insphere_z(&z);
    if (s == 0) {
        /* The tie broken as fdt_insphere_perturbed does (Devillers and
         * Teillaud): the points in decreasing lexicographic order, the
         * first whose coefficient is not 0 decides; e's is -1. */
        int order[5] = {0, 1, 2, 3, 4};
        for (int a = 1; a < 5; a++) {
            int x = order[a], b = a;
            while (b > 0 && lex_z(&z, order[b - 1], x) < 0) {
                order[b] = order[b - 1];
                b--;
            }
            order[b] = x;
        }
        s = -1;
        for (int r = 0; r < 5; r++) {
            int v = order[r];
            if (v == 4)
                break;
            int j[4] = {0, 1, 2, 3};
            j[v] = 4;
            int o = orient_z(&z, j);
            if (o != 0) {
                s = o;
                break;
            }
        }
    }
    exact_clear(&z);
    return s;
}

int fdt_images_normal_sign(const fdt_images *im, const uint32_t i[3], int k)
{
    exact_pts z;
    exact_init(&z, im, i, 3);
    int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
    mpz_t u1, u2, v1, v2;
    mpz_inits(u1, u2, v1, v2, NULL);
    mpz_sub(u1, z.q[1][k1], z.q[0][k1]);
    mpz_sub(u2, z.q[1][k2], z.q[0][k2]);
    mpz_sub(v1, z.q[2][k1], z.q[0][k1]);
    mpz_sub(v2, z.q[2][k2], z.q[0][k2]);
    mpz_mul(z.s, u1, v2);
    mpz_submul(z.s, u2, v1);
    int s = mpz_sgn(z.s);
    mpz_clears(u1, u2, v1, v2, NULL);
    exact_clear(&z);
    return s;
}

/*
 * The input points of P's points i[0 .. k) into x, when they are all
 * images in one copy (the same offsets): 1 then, 0 otherwise. Both
 * predicates are invariant under a translation, and so is the
 * perturbation's lexicographic order (images.h), so those input points,
 * doubles, decide for the images with the plain stages: no GMP where the
 * images are rounded (points of a sphere in a copy of the box ran 18M
 * tests through GMP, bench/NOTES.md entry 119).
 */
static int one_copy(const fdt_images *im, const uint32_t *i, int k, const double *x[5])
{
    const int8_t *o = im->off + 3 * (size_t)i[0];
    for (int j = 1; j < k; j++) {
        const int8_t *q = im->off + 3 * (size_t)i[j];
        if (q[0] != o[0] || q[1] != o[1] || q[2] != o[2])
            return 0;
    }
    for (int j = 0; j < k; j++)
        x[j] = im->X + 3 * (size_t)im->src[i[j]];
    return 1;
}

int fdt_images_orient_undecided(const fdt_images *im, const double *a, const double *b,
                                const double *c, const double *d, fdt_pred_counts *cnt)
{
    /* the dynamic stage, widened by the images' rounding */
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double w[3] = {d[0] - a[0], d[1] - a[1], d[2] - a[2]};
    int s = fdt_orient3d_filter_diff(u, v, w, 0, 1, im->err);
    if (s != FDT_PRED_UNSURE)
        return s;
    const uint32_t i[4] = {fdt_images_index(im, a), fdt_images_index(im, b),
                           fdt_images_index(im, c), fdt_images_index(im, d)};
    if (im->exact[i[0]] & im->exact[i[1]] & im->exact[i[2]] & im->exact[i[3]])
        return fdt_orient3d(a, b, c, d, cnt);
    const double *x[5];
    if (one_copy(im, i, 4, x))
        return fdt_orient3d(x[0], x[1], x[2], x[3], cnt);
    return fdt_images_orient_exact(im, i, cnt);
}

int fdt_images_insphere_undecided(const fdt_images *im, const double *a, const double *b,
                                  const double *c, const double *d, const double *e,
                                  fdt_pred_counts *cnt)
{
    /* the dynamic stage, as for orient3d */
    const double A[3] = {a[0] - e[0], a[1] - e[1], a[2] - e[2]};
    const double B[3] = {b[0] - e[0], b[1] - e[1], b[2] - e[2]};
    const double C[3] = {c[0] - e[0], c[1] - e[1], c[2] - e[2]};
    const double D[3] = {d[0] - e[0], d[1] - e[1], d[2] - e[2]};
    int s = fdt_insphere_filter_diff(A, B, C, D, 0, 1, im->err);
    if (s != FDT_PRED_UNSURE)
        return s;
    const uint32_t i[5] = {fdt_images_index(im, a), fdt_images_index(im, b),
                           fdt_images_index(im, c), fdt_images_index(im, d),
                           fdt_images_index(im, e)};
    if (im->exact[i[0]] & im->exact[i[1]] & im->exact[i[2]] & im->exact[i[3]] & im->exact[i[4]])
        return fdt_insphere_perturbed(a, b, c, d, e, cnt);
    const double *x[5];
    if (one_copy(im, i, 5, x))
        return fdt_insphere_perturbed(x[0], x[1], x[2], x[3], x[4], cnt);
    return fdt_images_insphere_exact(im, i, cnt);
}

int fdt_images_orient(const fdt_images *im, const double *a, const double *b, const double *c,
                      const double *d, fdt_pred_counts *cnt)
{
    const fdt_pred_static sf = fdt_images_static(im);
    int s = fdt_orient3d_filter_sf(a, b, c, d, &sf);
    return s != FDT_PRED_UNSURE ? s : fdt_images_orient_undecided(im, a, b, c, d, cnt);
}

int fdt_images_insphere(const fdt_images *im, const double *a, const double *b, const double *c,
                        const double *d, const double *e, fdt_pred_counts *cnt)
{
    const fdt_pred_static sf = fdt_images_static(im);
    int s = fdt_insphere_filter_sf(a, b, c, d, e, &sf);
    return s != FDT_PRED_UNSURE ? s : fdt_images_insphere_undecided(im, a, b, c, d, e, cnt);
}

int fdt_images_ball_inside(const fdt_images *im, const uint32_t i[4], const double A[3],
                           const double B[3], unsigned axes)
{
    exact_pts z;
    exact_init(&z, im, i, 4);
    int kmin = z.kmin;
    int k2 = kmin; /* the bounds' grid too: the points moved onto it */
    for (int k = 0; k < 3; k++)
        for (int w = 0; w < 2; w++) {
            double v = w ? B[k] : A[k];
            if ((axes >> k & 1) && v != 0.0 && fdt_int_exponent(v) < k2)
                k2 = fdt_int_exponent(v);
        }
    for (int j = 0; j < 4 && k2 < kmin; j++)
        for (int k = 0; k < 3; k++)
            mpz_mul_2exp(z.q[j][k], z.q[j][k], (mp_bitcnt_t)(kmin - k2));
    kmin = k2;
    /* u_j = p_j - p_0, D = det[u1; u2; u3] (> 0: a positive tet), and
     * N = |u1|^2 (u2 x u3) + |u2|^2 (u3 x u1) + |u3|^2 (u1 x u2): the
     * centre is p_0 + N / (2D), the radius |N| / (2D). */
    mpz_t u[3][3], l[3], N[3], D, t, s, n2, lim;
    for (int r = 0; r < 3; r++) {
        mpz_init(l[r]);
        mpz_init(N[r]);
        for (int k = 0; k < 3; k++) {
            mpz_init(u[r][k]);
            mpz_sub(u[r][k], z.q[r + 1][k], z.q[0][k]);
            mpz_addmul(l[r], u[r][k], u[r][k]);
        }
    }
    mpz_inits(D, t, s, n2, lim, NULL);
    fdt_mpz_det3(D, u[0], u[1], u[2], t);
    int inside = mpz_sgn(D) > 0;
    for (int r = 0; r < 3 && inside; r++) {
        const mpz_t *a = u[(r + 1) % 3], *b = u[(r + 2) % 3];
        for (int k = 0; k < 3; k++) { /* (a x b)_k l_r */
            int ka = (k + 1) % 3, kb = (k + 2) % 3;
            mpz_mul(t, a[ka], b[kb]);
            mpz_submul(t, a[kb], b[ka]);
            mpz_addmul(N[k], t, l[r]);
        }
    }
    for (int k = 0; k < 3; k++)
        mpz_addmul(n2, N[k], N[k]);
    /* c_k + R < B_k: S = 2D (B_k - p0_k) - N_k > 0 and S^2 > |N|^2; and
     * c_k - R > A_k: S = 2D (p0_k - A_k) + N_k > 0 and S^2 > |N|^2 */
    for (int k = 0; k < 3 && inside; k++) {
        if (!(axes >> k & 1))
            continue;
        for (int w = 0; w < 2 && inside; w++) {
            fdt_mpz_set_scaled(lim, w ? B[k] : A[k], kmin);
            if (w)
                mpz_sub(s, lim, z.q[0][k]);
            else
                mpz_sub(s, z.q[0][k], lim);
            mpz_mul(s, s, D);
            mpz_mul_2exp(s, s, 1);
            if (w)
                mpz_sub(s, s, N[k]);
            else
                mpz_add(s, s, N[k]);
            if (mpz_sgn(s) <= 0) {
                inside = 0;
                break;
            }
            mpz_mul(t, s, s);
            inside = mpz_cmp(t, n2) > 0;
        }
    }
    for (int r = 0; r < 3; r++) {
        mpz_clear(l[r]);
        mpz_clear(N[r]);
        for (int k = 0; k < 3; k++)
            mpz_clear(u[r][k]);
    }
    mpz_clears(D, t, s, n2, lim, NULL);
    exact_clear(&z);
    return inside;
}
