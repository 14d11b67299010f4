/*
 * gen_points FAMILY N SEED OUT.xyz [--shuffle PERM_OUT]
 * gen_points --list
 *
 * Writes about N points of a named family of hard inputs (qhull's
 * q_benchmark idea: cospherical, nearly cospherical, lattice, ...) as
 * "x y z" lines with %.17g, which round-trips every double exactly, or,
 * for the families that imitate a file format (citylidar, sphere12,
 * statue), with the digits such files have. The families imitate what
 * scanned and CFD point clouds do to a Delaunay code: exact cospherical
 * and coplanar sets, huge offsets with tiny extents, extreme magnitudes,
 * near and exact duplicates; the second group (cylinder onwards) the real
 * input classes of issue 16, used by tests/e2e_reference.py at small
 * sizes and by bench/run at large ones. `gen_points` without arguments
 * lists them with one line each.
 *
 * The output is a pure function of (FAMILY, N, SEED) on a given platform,
 * so (family, N, seed) is a complete reproducer. Families marked "~N"
 * below round N to their structure (a lattice has s^3 points).
 *
 * --shuffle applies a random permutation (from SEED) to the output and
 * writes it to PERM_OUT: line i holds the original index of output point
 * i, so tests can map a mesh of the shuffled file back and check that the
 * tetrahedralization does not depend on input order.
 *
 * An OUT ending in .ply gets the same points as binary little-endian PLY
 * (x, y, z as doubles: the values the text file holds, rounded as the
 * family writes them), for the
 * large runs of issue 18, whose text alone would be 6 GB at 10^8 points.
 * The uniform family without --shuffle is then written as it is drawn, a
 * block at a time, so 10^8 points need a few megabytes beside the file.
 */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/hash.h"

/* ------------------------------------------------------------------ RNG */

/* xoshiro256** (Blackman & Vigna), seeded through splitmix64: fast, good
 * statistics, and identical on every platform. */
typedef struct rng {
    uint64_t s[4];
} rng;

static void rng_seed(rng *r, uint64_t seed)
{
    for (int i = 0; i < 4; i++)
        r->s[i] = fdt_splitmix64(&seed);
}

static uint64_t rng_next(rng *r)
{
    return fdt_xoshiro256ss(r->s);
}

/* Uniform in [0, 1) with all 53 bits random. */
static double rng_u01(rng *r)
{
    return (double)(rng_next(r) >> 11) * 0x1.0p-53;
}

/* Uniform integer in [0, n), n >= 1, without modulo bias (rejection). */
static uint64_t rng_below(rng *r, uint64_t n)
{
    uint64_t lim = UINT64_MAX - UINT64_MAX % n;
    uint64_t x;
    do
        x = rng_next(r);
    while (x >= lim);
    return x % n;
}

/* Standard normal by Marsaglia's polar method. */
static double rng_normal(rng *r)
{
    double u, v, s;
    do {
        u = 2.0 * rng_u01(r) - 1.0;
        v = 2.0 * rng_u01(r) - 1.0;
        s = u * u + v * v;
    } while (s >= 1.0 || s == 0.0);
    return u * sqrt(-2.0 * log(s) / s);
}

/* --------------------------------------------------------------- points */

typedef struct pts {
    double *xyz;
    size_t n, cap;
} pts;

static int pts_add(pts *p, double x, double y, double z)
{
    if (p->n == p->cap) {
        size_t cap = p->cap ? 2 * p->cap : 1024;
        double *q = realloc(p->xyz, 3 * cap * sizeof *q);
        if (!q)
            return -1;
        p->xyz = q;
        p->cap = cap;
    }
    p->xyz[3 * p->n] = x;
    p->xyz[3 * p->n + 1] = y;
    p->xyz[3 * p->n + 2] = z;
    p->n++;
    return 0;
}

/* Each family appends its points to p; returns 0, or -1 when out of
 * memory. */
typedef int (*family_fn)(pts *p, size_t n, rng *r);

static int fam_uniform(pts *p, size_t n, rng *r)
{
    for (size_t i = 0; i < n; i++) {
        double x = rng_u01(r), y = rng_u01(r), z = rng_u01(r);
        if (pts_add(p, x, y, z))
            return -1;
    }
    return 0;
}

static int fam_ball(pts *p, size_t n, rng *r)
{
    while (p->n < n) {
        double x = 2 * rng_u01(r) - 1, y = 2 * rng_u01(r) - 1,
               z = 2 * rng_u01(r) - 1;
        if (x * x + y * y + z * z <= 1 && pts_add(p, x, y, z))
            return -1;
    }
    return 0;
}

/* On the unit sphere up to the rounding of the normalisation: every point
 * within an ulp or so of cospherical, so floating-point insphere filters
 * fail on almost every test. */
static int fam_sphere(pts *p, size_t n, rng *r)
{
    while (p->n < n) {
        double x = rng_normal(r), y = rng_normal(r), z = rng_normal(r);
        double s = sqrt(x * x + y * y + z * z);
        if (s < 1e-3)
            continue;
        if (pts_add(p, x / s, y / s, z / s))
            return -1;
    }
    return 0;
}

static int fam_gaussian(pts *p, size_t n, rng *r)
{
    for (size_t i = 0; i < n; i++) {
        double x = rng_normal(r), y = rng_normal(r), z = rng_normal(r);
        if (pts_add(p, x, y, z))
            return -1;
    }
    return 0;
}

/* 90% of the points within 1e-6 of one of 5 centres, 10% spread over the
 * unit cube: a density contrast of ~1e16, as where a scanner dwells. */
static int fam_clusters(pts *p, size_t n, rng *r)
{
    double c[5][3];
    for (int k = 0; k < 5; k++)
        for (int d = 0; d < 3; d++)
            c[k][d] = rng_u01(r);
    for (size_t i = 0; i < n; i++) {
        double x, y, z;
        if (rng_below(r, 10) == 0) {
            x = rng_u01(r);
            y = rng_u01(r);
            z = rng_u01(r);
        } else {
            const double *ck = c[rng_below(r, 5)];
            x = ck[0] + 1e-6 * (2 * rng_u01(r) - 1);
            y = ck[1] + 1e-6 * (2 * rng_u01(r) - 1);
            z = ck[2] + 1e-6 * (2 * rng_u01(r) - 1);
        }
        if (pts_add(p, x, y, z))
            return -1;
    }
    return 0;
}

static size_t round_cbrt(size_t n)
{
    size_t s = (size_t)llround(cbrt((double)n));
    return s < 2 ? 2 : s;
}

/* ~N: the s^3 integer points of a cube. Every unit cell's 8 corners are
 * exactly cospherical, and so are far larger sets. */
static int fam_lattice(pts *p, size_t n, rng *r)
{
    (void)r;
    size_t s = round_cbrt(n);
    for (size_t i = 0; i < s; i++)
        for (size_t j = 0; j < s; j++)
            for (size_t k = 0; k < s; k++)
                if (pts_add(p, (double)i, (double)j, (double)k))
                    return -1;
    return 0;
}

/* Number of integer points on the sphere x^2+y^2+z^2 = m^2, by Hurwitz's
 * formula r3(m^2) = 6 * prod over odd p^a || m of
 * (sigma(p^a) - (-1/p) sigma(p^(a-1))), (-1/p) = +1 for p = 1 mod 4 and
 * -1 for p = 3 mod 4; powers of 2 contribute 1. Lets us pick a radius
 * without enumerating each candidate. */
static double r3_square(uint64_t m)
{
    while (m % 2 == 0)
        m /= 2;
    double count = 6;
    for (uint64_t q = 3; q * q <= m; q += 2) {
        if (m % q)
            continue;
        int a = 0;
        while (m % q == 0) {
            m /= q;
            a++;
        }
        double sig = 0, sig1 = 0, pw = 1;
        for (int e = 0; e <= a; e++) {
            if (e < a)
                sig1 += pw;
            sig += pw;
            pw *= (double)q;
        }
        count *= q % 4 == 1 ? sig - sig1 : sig + sig1;
    }
    if (m > 1) /* one remaining prime, exponent 1 */
        count *= m % 4 == 1 ? (double)m : (double)m + 2;
    return count;
}

static uint64_t isqrt_u64(uint64_t v)
{
    uint64_t x = (uint64_t)sqrt((double)v);
    while (x * x > v)
        x--;
    while ((x + 1) * (x + 1) <= v)
        x++;
    return x;
}

/* ~N: every integer point exactly on a sphere of integer radius m, with
 * the smallest m whose point count is within 10% of N (the best found
 * otherwise). All points cospherical, many coplanar subsets, all on the
 * hull: the tetrahedralization is decided by the perturbation alone. */
static int fam_intsphere(pts *p, size_t n, rng *r)
{
    (void)r;
    uint64_t best = 1;
    double best_err = INFINITY;
    for (uint64_t m = 1; m <= 4 * (uint64_t)n + 8; m++) {
        double c = r3_square(m);
        double e = fabs(c - (double)n);
        if (e < best_err) {
            best_err = e;
            best = m;
        }
        if (e <= 0.1 * (double)n)
            break;
    }
    int64_t m = (int64_t)best, m2 = m * m;
    for (int64_t x = -m; x <= m; x++)
        for (int64_t y = -m; y <= m; y++) {
            int64_t rest = m2 - x * x - y * y;
            if (rest < 0)
                continue;
            int64_t z = (int64_t)isqrt_u64((uint64_t)rest);
            if (z * z != rest)
                continue;
            if (pts_add(p, (double)x, (double)y, (double)z))
                return -1;
            if (z && pts_add(p, (double)x, (double)y, (double)-z))
                return -1;
        }
    if ((double)p->n != r3_square(best)) {
        fprintf(stderr, "gen_points: intsphere: %zu points on radius %lld, "
                "formula says %.0f\n", p->n, (long long)m, r3_square(best));
        return -2;
    }
    return 0;
}

/* ~N: an m x m integer grid extruded once: each (x, y) at z = 0 and at
 * z = 1. Two huge coplanar layers, every unit cell's corners cospherical,
 * and tetrahedra as flat as the extent ratio (m : 1) makes them. */
static int fam_grid2d(pts *p, size_t n, rng *r)
{
    (void)r;
    size_t m = (size_t)llround(sqrt((double)n / 2));
    if (m < 2)
        m = 2;
    for (size_t i = 0; i < m; i++)
        for (size_t j = 0; j < m; j++)
            if (pts_add(p, (double)i, (double)j, 0.0) ||
                pts_add(p, (double)i, (double)j, 1.0))
                return -1;
    return 0;
}

/* Uniform on a 1 mm grid, 20 m cube at 4.9e6 m (UTM northing-like): the
 * relative extent is 4e-6, so about 18 of the 53 mantissa bits vary and
 * floating-point filters fail constantly, as on terrestrial scans. */
static int fam_offset(pts *p, size_t n, rng *r)
{
    for (size_t i = 0; i < n; i++) {
        double c[3];
        for (int d = 0; d < 3; d++)
            c[d] = (4900000000.0 + (double)rng_below(r, 20001)) / 1000.0;
        if (pts_add(p, c[0], c[1], c[2]))
            return -1;
    }
    return 0;
}

/* Uniform scaled to ~1e-150 / ~1e150: products in insphere (degree 5)
 * underflow or overflow double, so filters must notice and go exact. */
static int fam_scaled(pts *p, size_t n, rng *r, double scale)
{
    for (size_t i = 0; i < n; i++) {
        double x = rng_u01(r) * scale, y = rng_u01(r) * scale,
               z = rng_u01(r) * scale;
        if (pts_add(p, x, y, z))
            return -1;
    }
    return 0;
}

static int fam_tiny(pts *p, size_t n, rng *r)
{
    return fam_scaled(p, n, r, 1e-150);
}

static int fam_huge(pts *p, size_t n, rng *r)
{
    return fam_scaled(p, n, r, 1e150);
}

/* Uniform points each followed by a partner 1e-8 away in a random
 * direction: slivers and near-zero orientations everywhere. */
static int fam_neardup(pts *p, size_t n, rng *r)
{
    while (p->n < n) {
        double x = rng_u01(r), y = rng_u01(r), z = rng_u01(r);
        if (pts_add(p, x, y, z))
            return -1;
        if (p->n == n)
            break;
        double u = rng_normal(r), v = rng_normal(r), w = rng_normal(r);
        double s = sqrt(u * u + v * v + w * w);
        if (s == 0)
            s = u = 1;
        if (pts_add(p, x + 1e-8 * u / s, y + 1e-8 * v / s, z + 1e-8 * w / s))
            return -1;
    }
    return 0;
}

/* N points drawn from nd distinct ones, in random order, so a point's
 * first occurrence is anywhere. A fifth of the distinct points have a zero
 * coordinate, written as +0 or -0 at random: the same point either way. */
static int dup_of(pts *p, size_t n, rng *r, size_t nd)
{
    if (nd > n)
        nd = n;
    double *d = malloc(3 * nd * sizeof *d);
    if (!d)
        return -1;
    for (size_t i = 0; i < nd; i++) {
        for (int c = 0; c < 3; c++)
            d[3 * i + c] = 2 * rng_u01(r) - 1;
        if (rng_below(r, 5) == 0)
            d[3 * i + rng_below(r, 3)] = 0.0;
    }
    for (size_t i = 0; i < n; i++) {
        /* Every distinct point at least once, the rest drawn at random. */
        size_t k = i < nd ? i : (size_t)rng_below(r, nd);
        double c[3];
        for (int j = 0; j < 3; j++) {
            c[j] = d[3 * k + j];
            if (c[j] == 0.0 && rng_below(r, 2))
                c[j] = -0.0;
        }
        if (pts_add(p, c[0], c[1], c[2])) {
            free(d);
            return -1;
        }
    }
    free(d);
    for (size_t i = p->n - 1; i > 0; i--) {
        size_t j = (size_t)rng_below(r, i + 1);
        for (int c = 0; c < 3; c++) {
            double t = p->xyz[3 * i + c];
            p->xyz[3 * i + c] = p->xyz[3 * j + c];
            p->xyz[3 * j + c] = t;
        }
    }
    return 0;
}

/* N points from N/10 distinct ones (each about 10 times). */
static int fam_dup(pts *p, size_t n, rng *r)
{
    return dup_of(p, n, r, n / 10 < 4 ? 4 : n / 10);
}

/* Heavy duplication: N points from about sqrt(N) distinct ones (at
 * N = 2500, 50 points each repeated about 50 times). */
static int fam_dupheavy(pts *p, size_t n, rng *r)
{
    size_t nd = (size_t)sqrt((double)n);
    return dup_of(p, n, r, nd < 4 ? 4 : nd);
}

/* Mixed magnitudes in one file: uniform in the unit cube, each point then
 * scaled by 1e-150, 1 or 1e150 (a third each). orient3d and insphere mix
 * terms near 1e-300 with terms near 1e300, beyond what any one power-of-
 * two scaling of the input brings into range, so only exact arithmetic
 * that cannot underflow (GMP integers, README.md Limits) gets them right. */
static int fam_mixed(pts *p, size_t n, rng *r)
{
    static const double scale[3] = {1e-150, 1.0, 1e150};
    for (size_t i = 0; i < n; i++) {
        double s = scale[rng_below(r, 3)];
        double x = rng_u01(r) * s, y = rng_u01(r) * s, z = rng_u01(r) * s;
        if (pts_add(p, x, y, z))
            return -1;
    }
    return 0;
}

/* A large offset and a tiny extent: 2^40 (about 1.1e12) plus random
 * multiples of 2^-12 below 2^10, so coordinates differ in their last 22 of
 * 53 bits only (extent 0.25 at 1.1e12). All values are exact doubles; the
 * points lie on a lattice of the offset, so cospherical and coplanar
 * subsets are everywhere, and every difference is tiny next to the
 * coordinates themselves. */
static int fam_ulpgrid(pts *p, size_t n, rng *r)
{
    for (size_t i = 0; i < n; i++) {
        double c[3];
        for (int d = 0; d < 3; d++)
            c[d] = 0x1p40 + ldexp((double)rng_below(r, 1024), -12);
        if (pts_add(p, c[0], c[1], c[2]))
            return -1;
    }
    return 0;
}

/* m coordinates on [0, len] whose spacings grow geometrically away from
 * the wall(s) by a total factor `growth`: two-sided for a channel, one
 * sided for a boundary layer. The values are computed once and shared by
 * every grid line, so the tensor-product grid is exact: each cell's 8
 * corners are exactly cospherical, each grid plane exactly coplanar. */
static void stretched(double *out, size_t m, double len, double growth,
                      int two_sided)
{
    size_t cells = m - 1;
    double *sp = malloc(cells * sizeof *sp);
    double total = 0;
    for (size_t k = 0; k < cells; k++) {
        double t;
        if (two_sided)
            t = cells > 2 ? (double)(k < cells - 1 - k ? k : cells - 1 - k) /
                                ((double)(cells - 1) / 2)
                          : 0;
        else
            t = cells > 1 ? (double)k / (double)(cells - 1) : 0;
        sp[k] = pow(growth, t);
        total += sp[k];
    }
    double acc = 0;
    out[0] = 0;
    for (size_t k = 0; k < cells; k++) {
        acc += sp[k];
        out[k + 1] = len * (acc / total);
    }
    out[cells] = len;
    free(sp);
}

/* ~N: a stretched structured CFD grid, nx x ny x nz with nx = 2 ny: x
 * clustered at both ends (factor 1e3), y a wall boundary layer (factor
 * 1e4, first cell ~1e-6 of the height), z uniform. */
static int fam_cfdgrid(pts *p, size_t n, rng *r)
{
    (void)r;
    size_t ny = round_cbrt(n / 2);
    size_t nx = 2 * ny;
    size_t nz = (size_t)llround((double)n / (double)(nx * ny));
    if (nz < 2)
        nz = 2;
    double *cx = malloc(nx * sizeof *cx), *cy = malloc(ny * sizeof *cy),
           *cz = malloc(nz * sizeof *cz);
    if (!cx || !cy || !cz) {
        free(cx);
        free(cy);
        free(cz);
        return -1;
    }
    stretched(cx, nx, 10.0, 1e3, 1);
    stretched(cy, ny, 1.0, 1e4, 0);
    stretched(cz, nz, 0.5, 1.0, 0);
    int rc = 0;
    for (size_t k = 0; k < nz && !rc; k++)
        for (size_t j = 0; j < ny && !rc; j++)
            for (size_t i = 0; i < nx && !rc; i++)
                rc = pts_add(p, cx[i], cy[j], cz[k]);
    free(cx);
    free(cy);
    free(cz);
    return rc;
}

/* Airborne-lidar-like (../shared/data/autzen_lidar_110000.xyz): x, y on a
 * 0.01 ft grid over 1000 ft at ~6.4e5 / 8.5e5, 85% of the points on five
 * exactly horizontal planes (ground, roofs), the rest at quantised random
 * heights (vegetation). */
static int fam_lidar(pts *p, size_t n, rng *r)
{
    static const int plane_cm[5] = {0, 137, 250, 1281, 3002};
    for (size_t i = 0; i < n; i++) {
        double x = (63700000.0 + (double)rng_below(r, 100000)) / 100.0;
        double y = (85300000.0 + (double)rng_below(r, 100000)) / 100.0;
        int64_t zc = rng_below(r, 100) < 85 ? plane_cm[rng_below(r, 5)]
                                            : (int64_t)rng_below(r, 5000);
        double z = (40000.0 + (double)zc) / 100.0;
        if (pts_add(p, x, y, z))
            return -1;
    }
    return 0;
}

/* ------------------------------------------------- real-input families */

/* The families below imitate the classes of real input on which issue 16
 * measured frontdt 2x-800x slower than CGAL, HXT and Geogram: surfaces
 * with an empty inside, structured CFD grids with extreme stretching,
 * rotated lattices, quantised city scans and CAD geometry. Each comment
 * says what it imitates and why it is hard for an advancing front. */

static const double two_pi = 6.283185307179586476925;

/* Families whose point count follows from a continuous size (a spacing or
 * a density) rather than from N directly. gen(p, s, n, r) writes the
 * family at size s (n only picks the layout, never the count); points grow
 * about as s^power (power < 0 for a spacing). Up to 8 passes aim at N:
 * each steps by that power law, kept inside the sizes already seen to give
 * too few and too many points, and they stop within 2% of N. Every pass
 * starts from the same generator state, so the output is still a function
 * of (N, SEED); a family whose structure has a floor (the fixed parts of a
 * CFD grid) stays at its floor for small N. */
typedef int (*scaled_fn)(pts *p, double s, size_t n, rng *r);

static int calibrated(pts *p, size_t n, rng *r, scaled_fn gen, double s,
                      double power)
{
    const rng start = *r;
    double s_few = 0, s_many = 0;
    for (int pass = 0; pass < 8; pass++) {
        pts t = {NULL, 0, 0};
        *r = start;
        int rc = gen(&t, s, n, r);
        size_t got = t.n;
        free(t.xyz);
        if (rc)
            return rc;
        if (got >= n - n / 50 && got <= n + n / 50)
            break;
        if (got < n)
            s_few = s;
        else
            s_many = s;
        double next = s * pow((double)n / (double)(got ? got : 1), 1.0 / power);
        if (s_few > 0 && s_many > 0) {
            double lo = fmin(s_few, s_many), hi = fmax(s_few, s_many);
            if (!(next > lo && next < hi))
                next = sqrt(lo * hi);
        }
        s = next;
    }
    *r = start;
    return gen(p, s, n, r);
}

/* m unit-circle points at equal angle steps, m a multiple of 8, built from
 * the first octant by the circle's eight reflections: the ring is exactly
 * symmetric under x <-> y, x -> -x and y -> -y, as a CAD kernel or a mesh
 * generator that mirrors its work makes it. Every mirror-image pair of
 * chords then bounds an isosceles trapezoid, whose 4 corners are exactly
 * cocircular. */
static void octant_ring(double *x, double *y, size_t m)
{
    size_t q = m / 4, e = m / 8;
    x[0] = 1, y[0] = 0;
    x[q] = 0, y[q] = 1;
    x[2 * q] = -1, y[2 * q] = 0;
    x[3 * q] = 0, y[3 * q] = -1;
    for (size_t k = 1; k <= e; k++) {
        /* At 45 degrees cos and sin round differently: take one value for
         * both so the point is its own mirror image in x = y. */
        double c = k == e ? sqrt(0.5) : cos(two_pi * (double)k / (double)m);
        double s = k == e ? c : sin(two_pi * (double)k / (double)m);
        const size_t idx[8] = {k, q - k, q + k, 2 * q - k,
                               2 * q + k, 3 * q - k, 3 * q + k, m - k};
        const double vx[8] = {c, s, -s, -c, -c, -s, s, c};
        const double vy[8] = {s, c, c, s, -s, -c, -c, -s};
        for (int i = 0; i < 8; i++) {
            x[idx[i]] = vx[i];
            y[idx[i]] = vy[i];
        }
    }
}

/* ~N: an exact cylinder surface, empty inside, as a pipe or tank from a
 * CAD model or a structured scan: m + 1 rings (m a multiple of 8, ~sqrt N)
 * of m equal angle steps, radius 1, ring spacing 2*pi/m (the arc step), so
 * height 2*pi. Every ring is the same symmetric ring (octant_ring) at
 * another z, so any two generator lines and two rings make an exact
 * rectangle and each ring has exactly cocircular trapezoids: thousands of
 * 5-point cospherical sets, decided by the perturbation alone. Every point
 * is on the convex hull, so the tets fill the empty inside with long flat
 * slabs whose circumspheres hold many candidates. */
static int fam_cylinder(pts *p, size_t n, rng *r)
{
    (void)r;
    size_t m = 8 * (size_t)llround(sqrt((double)n) / 8);
    if (m < 8)
        m = 8;
    double *x = malloc(m * sizeof *x), *y = malloc(m * sizeof *y);
    int rc = !x || !y ? -1 : 0;
    if (!rc)
        octant_ring(x, y, m);
    double h = two_pi / (double)m;
    for (size_t j = 0; j <= m && !rc; j++)
        for (size_t i = 0; i < m && !rc; i++)
            rc = pts_add(p, x[i], y[i], (double)j * h);
    free(x);
    free(y);
    return rc;
}

/* ~N: the same pipe as a scanner sees it: m + 1 rings (exactly coplanar,
 * one z each) of m points whose angles are jittered by up to 0.45 of a
 * step, x = cos, y = sin of the angle. The radius is 1 to rounding, so no
 * 4 points of a ring are exactly cocircular but every ring is nearly so:
 * filters fail, exact insphere tests decide. Empty inside, all on the
 * hull, as cylinder. */
static int fam_cylscan(pts *p, size_t n, rng *r)
{
    size_t m = (size_t)llround(sqrt((double)n));
    if (m < 4)
        m = 4;
    double h = two_pi / (double)m;
    for (size_t j = 0; j <= m; j++)
        for (size_t i = 0; i < m; i++) {
            double a = two_pi * ((double)i + 0.9 * rng_u01(r) - 0.45) / (double)m;
            if (pts_add(p, cos(a), sin(a), (double)j * h))
                return -1;
        }
    return 0;
}

/* ~N: the k^3 integer lattice (k = round(cbrt N)) rotated about x by 0.3,
 * then about y by 0.5, then about z by 0.7 radians, in doubles, as a user
 * would rotate a structured block into place. The rotation's rounding
 * breaks most of the lattice's exact cospherical cells into nearly
 * cospherical ones (5 points within a few ulps of one sphere), so the
 * floating-point filters fail on almost every insphere test, yet some
 * cells may stay exactly degenerate. */
static int fam_rotlattice(pts *p, size_t n, rng *r)
{
    (void)r;
    size_t k = round_cbrt(n);
    const double ca = cos(0.3), sa = sin(0.3), cb = cos(0.5), sb = sin(0.5),
                 cc = cos(0.7), sc = sin(0.7);
    for (size_t i = 0; i < k; i++)
        for (size_t j = 0; j < k; j++)
            for (size_t l = 0; l < k; l++) {
                double x = (double)i, y = (double)j, z = (double)l;
                double y1 = ca * y - sa * z, z1 = sa * y + ca * z;
                double x2 = cb * x + sb * z1, z2 = -sb * x + cb * z1;
                double x3 = cc * x2 - sc * y1, y3 = sc * x2 + cc * y1;
                if (pts_add(p, x3, y3, z2))
                    return -1;
            }
    return 0;
}

/* A k^3 lattice turned by 0.01 rad about the skew axis (1, 2, 3): a
 * lattice scanned or exported slightly off its axes. Nearly every sphere is
 * nearly cospherical with its lattice cell, so the ranks vote for the
 * replica mesh, and the small angle leaves the cells' faces almost on the
 * partition's cuts (issue 34: 40^3 of these on 7 ranks read a foreign
 * apex's coordinates past the rank's own points). */
static int fam_skewlattice(pts *p, size_t n, rng *r)
{
    (void)r;
    size_t k = round_cbrt(n);
    const double a = 0.01, c = cos(a), s = sin(a), len = sqrt(14.0);
    const double u = 1.0 / len, v = 2.0 / len, w = 3.0 / len;
    /* Rodrigues' rotation matrix about the unit axis (u, v, w) */
    const double R[3][3] = {
        {c + u * u * (1 - c), u * v * (1 - c) - w * s, u * w * (1 - c) + v * s},
        {v * u * (1 - c) + w * s, c + v * v * (1 - c), v * w * (1 - c) - u * s},
        {w * u * (1 - c) - v * s, w * v * (1 - c) + u * s, c + w * w * (1 - c)}};
    for (size_t i = 0; i < k; i++)
        for (size_t j = 0; j < k; j++)
            for (size_t l = 0; l < k; l++) {
                double q[3] = {(double)i, (double)j, (double)l}, x[3];
                for (int d = 0; d < 3; d++)
                    x[d] = R[d][0] * q[0] + R[d][1] * q[1] + R[d][2] * q[2];
                if (pts_add(p, x[0], x[1], x[2]))
                    return -1;
            }
    return 0;
}

/* A quantised city coordinate: 1e6 m plus a whole number of centimetres,
 * the double nearest to the decimal that "%.2f" prints and a reader parses
 * back, as in a LAS file's scaled integers converted to text. */
static double city_m(int64_t cm)
{
    return (100000000.0 + (double)cm) / 100.0;
}

/* An axis-aligned box, in centimetres, for citylidar and windcity. */
typedef struct box_cm {
    int64_t x0, y0, x1, y1, h;
} box_cm;

static int in_box(const box_cm *b, size_t nb, int64_t x, int64_t y)
{
    for (size_t i = 0; i < nb; i++)
        if (x >= b[i].x0 && x <= b[i].x1 && y >= b[i].y0 && y <= b[i].y1)
            return 1;
    return 0;
}

/* One citylidar at `dens` ground points per m^2 (walls get a quarter of
 * it: the scanner sees them at a grazing angle). */
static int city_gen(pts *p, double dens, size_t n, rng *r)
{
    /* 60 m blocks and 15 m streets; the city grows with N, the density is
     * what calibration adjusts. */
    const int64_t pitch = 7500, block = 6000;
    size_t nbk = (size_t)llround(sqrt((double)n / 20000.0));
    if (nbk < 2)
        nbk = 2;
    int64_t side = (int64_t)nbk * pitch;
    size_t cap = nbk * nbk * 3, nb = 0;
    box_cm *b = malloc(cap * sizeof *b);
    if (!b)
        return -1;
    for (size_t bi = 0; bi < nbk; bi++)
        for (size_t bj = 0; bj < nbk; bj++) {
            /* 1 to 3 buildings side by side along x, 2-6 m apart. */
            int64_t bx = (int64_t)bi * pitch, by = (int64_t)bj * pitch;
            size_t k = 1 + (size_t)rng_below(r, 3);
            int64_t w = block / (int64_t)k;
            for (size_t q = 0; q < k; q++) {
                int64_t gap = 200 + (int64_t)rng_below(r, 401);
                box_cm c;
                c.x0 = bx + (int64_t)q * w + gap / 2;
                c.x1 = bx + (int64_t)(q + 1) * w - gap / 2;
                c.y0 = by + (int64_t)rng_below(r, 1001);
                c.y1 = by + block - (int64_t)rng_below(r, 1001);
                c.h = 300 + (int64_t)rng_below(r, 3701);
                b[nb++] = c;
            }
        }
    int rc = 0;
    /* Ground: flat at one height, hidden under the roofs. */
    size_t ng = (size_t)llround(dens * (double)side * (double)side * 1e-4);
    for (size_t i = 0; i < ng && !rc; i++) {
        int64_t x = (int64_t)rng_below(r, (uint64_t)side + 1),
                y = (int64_t)rng_below(r, (uint64_t)side + 1);
        if (!in_box(b, nb, x, y))
            rc = pts_add(p, city_m(x), city_m(y), city_m(0));
    }
    for (size_t i = 0; i < nb && !rc; i++) {
        const box_cm *c = &b[i];
        int64_t wx = c->x1 - c->x0, wy = c->y1 - c->y0;
        /* Roof: exactly flat. */
        size_t nr = (size_t)llround(dens * (double)wx * (double)wy * 1e-4);
        for (size_t k = 0; k < nr && !rc; k++)
            rc = pts_add(p, city_m(c->x0 + (int64_t)rng_below(r, (uint64_t)wx + 1)),
                         city_m(c->y0 + (int64_t)rng_below(r, (uint64_t)wy + 1)),
                         city_m(c->h));
        /* Walls: exactly vertical planes. */
        size_t nw = (size_t)llround(0.25 * dens * 2.0 * (double)(wx + wy) *
                                    (double)c->h * 1e-4);
        for (size_t k = 0; k < nw && !rc; k++) {
            int64_t t = (int64_t)rng_below(r, (uint64_t)(2 * (wx + wy)));
            int64_t z = (int64_t)rng_below(r, (uint64_t)c->h + 1), x, y;
            if (t < wx)
                x = c->x0 + t, y = c->y0;
            else if (t < 2 * wx)
                x = c->x0 + t - wx, y = c->y1;
            else if (t < 2 * wx + wy)
                x = c->x0, y = c->y0 + t - 2 * wx;
            else
                x = c->x1, y = c->y0 + t - 2 * wx - wy;
            rc = pts_add(p, city_m(x), city_m(y), city_m(z));
        }
    }
    free(b);
    return rc;
}

/* ~N: airborne lidar over a city: a flat ground and flat-roof box
 * buildings (60 m blocks, 1 to 3 buildings each, 3-40 m high) with roofs
 * and walls sampled, every coordinate 1e6 m plus whole centimetres,
 * printed with 2 decimals. Ground and each roof are huge exactly coplanar
 * sets on a 1 cm lattice (exactly cocircular 4-sets among them), the walls
 * exactly vertical planes: orient3d is exactly zero on most flat
 * neighbourhoods, which no floating-point filter can certify. The 1e6
 * offset (a few hundred metres of city) spends ~12 of the 53 bits on the
 * offset, and the decimals are not exact doubles. */
static int fam_citylidar(pts *p, size_t n, rng *r)
{
    return calibrated(p, n, r, city_gen, 1.0, 1.0);
}

/* N points: Fibonacci points on a sphere of radius 100 (the spiral
 * turned by a random phase), printed with 12 significant digits as many
 * programs write floats. The printing moves each point off the sphere by
 * up to ~5e-9 while the points are ~1 apart: every point is on the hull
 * and nearly cospherical with all the others, so nearly every insphere
 * test needs exact arithmetic and each front face sees many candidates. */
static int fam_sphere12(pts *p, size_t n, rng *r)
{
    const double golden = two_pi * (1.0 - 0.5 * (sqrt(5.0) - 1.0));
    double phase = two_pi * rng_u01(r);
    for (size_t i = 0; i < n; i++) {
        double z = 1.0 - (2.0 * (double)i + 1.0) / (double)n;
        double s = sqrt(1.0 - z * z), a = phase + golden * (double)i;
        if (pts_add(p, 100.0 * s * cos(a), 100.0 * s * sin(a), 100.0 * z))
            return -1;
    }
    return 0;
}

/* Radial layers of a CFD O-grid around the unit sphere: first cell 1e-4,
 * each next 1.25 times thicker (at most 50 layers: the outer radius is
 * then ~8). */
static size_t shell_layers(size_t n)
{
    size_t L = (size_t)llround(1.46 * cbrt((double)n));
    return L < 3 ? 3 : L > 50 ? 50 : L;
}

/* Writes the directions d (nd unit vectors) scaled by each layer radius,
 * layer by layer: the radial lines share their direction exactly. */
static int shell_layers_add(pts *p, const double *d, size_t nd, size_t layers)
{
    double rad = 1.0, t = 1e-4;
    for (size_t k = 0; k < layers; k++) {
        for (size_t i = 0; i < nd; i++)
            if (pts_add(p, rad * d[3 * i], rad * d[3 * i + 1], rad * d[3 * i + 2]))
                return -1;
        rad += t;
        t *= 1.25;
    }
    return 0;
}

/* ~N: a structured CFD O-grid around a sphere, body empty: a (theta, phi)
 * grid of nt latitude rings of 2 nt points plus both poles, on layers of
 * radius 1, 1 + 1e-4, ... (cells growing 1.25). Each ring is exactly
 * coplanar and nearly cocircular, cells near the wall are 1e-4 thick and
 * ~0.15 wide (aspect 1500), and the empty body is bounded by ~2 nt^2
 * points on one sphere up to rounding: its inside is the sphere family's
 * worst case. (The 40,100 points: 50 layers of 20 x 40 + 2.) */
static int fam_ogrid(pts *p, size_t n, rng *r)
{
    (void)r;
    size_t L = shell_layers(n);
    double per = (double)n / (double)L;
    size_t nt = per > 10 ? (size_t)llround(sqrt((per - 2) / 2)) : 2;
    size_t np = 2 * nt, nd = nt * np + 2;
    double *d = malloc(3 * nd * sizeof *d);
    if (!d)
        return -1;
    size_t k = 0;
    d[k++] = 0, d[k++] = 0, d[k++] = 1;
    for (size_t i = 0; i < nt; i++) {
        double th = 0.5 * two_pi * (double)(i + 1) / (double)(nt + 1);
        for (size_t j = 0; j < np; j++) {
            double ph = two_pi * (double)j / (double)np;
            d[k++] = sin(th) * cos(ph);
            d[k++] = sin(th) * sin(ph);
            d[k++] = cos(th);
        }
    }
    d[k++] = 0, d[k++] = 0, d[k++] = -1;
    int rc = shell_layers_add(p, d, nd, L);
    free(d);
    return rc;
}

/* ~N: a cubed-sphere O-grid (six equiangular gnomonic n x n patches, the
 * 6 n^2 + 2 distinct points of the cube's surface lattice projected on the
 * sphere) on the radial layers of ogrid. The face coordinates tan(angle)
 * are mirrored exactly (t[n - i] = -t[i], t[0] = -1), so the grid has the
 * cube's symmetries bit for bit and its edges and corners, shared by two
 * or three patches, are single points. (The 76,900 points: 50
 * layers of 6 x 16^2 + 2.) */
static int fam_cubedsphere(pts *p, size_t n, rng *r)
{
    (void)r;
    size_t L = shell_layers(n);
    double per = (double)n / (double)L;
    size_t c = per > 14 ? (size_t)llround(sqrt((per - 2) / 6)) : 1;
    double *t = malloc((c + 1) * sizeof *t);
    size_t nd = 6 * c * c + 2;
    double *d = malloc(3 * nd * sizeof *d);
    if (!t || !d) {
        free(t);
        free(d);
        return -1;
    }
    for (size_t i = 0; 2 * i <= c; i++) {
        t[i] = i == 0 ? -1.0 : tan(two_pi / 8 * (2.0 * (double)i / (double)c - 1.0));
        t[c - i] = 2 * i == c ? 0.0 : -t[i]; /* +0 in the middle, not -0 */
    }
    size_t k = 0;
    for (size_t i = 0; i <= c; i++)
        for (size_t j = 0; j <= c; j++)
            for (size_t l = 0; l <= c; l++) {
                if (i != 0 && i != c && j != 0 && j != c && l != 0 && l != c)
                    continue;
                /* A point of the cube's surface (a coordinate is +-1
                 * exactly), projected on the sphere. */
                double a = t[i], b = t[j], e = t[l];
                double s = sqrt(a * a + b * b + e * e);
                d[k++] = a / s;
                d[k++] = b / s;
                d[k++] = e / s;
            }
    int rc = shell_layers_add(p, d, nd, L);
    free(t);
    free(d);
    return rc;
}

/* One plane of extruded: nc = round(s) points around the circle of
 * radius 0.5. */
static int extruded_gen(pts *p, double s, size_t n, rng *r)
{
    (void)n;
    size_t nc = s < 8 ? 8 : s > 1e7 ? 10000000 : (size_t)llround(s);
    double *cx = malloc(nc * sizeof *cx), *cy = malloc(nc * sizeof *cy);
    if (!cx || !cy) {
        free(cx);
        free(cy);
        return -1;
    }
    for (size_t i = 0; i < nc; i++) {
        cx[i] = cos(two_pi * (double)i / (double)nc);
        cy[i] = sin(two_pi * (double)i / (double)nc);
    }
    int rc = 0;
    /* Structured boundary layer: first cell 1e-4, growing 1.2, until the
     * cells are as thick as the wall's cells are wide. */
    double rad = 0.5, t = 1e-4, wide = two_pi * 0.5 / (double)nc;
    while (!rc && t < wide) {
        for (size_t i = 0; i < nc && !rc; i++)
            rc = pts_add(p, rad * cx[i], rad * cy[i], 0.0);
        rad += t;
        t *= 1.2;
    }
    /* Outside it, the rings of an advancing-front mesher out to radius
     * 30: isotropic cells growing by 1 + 2 pi / nc per ring (1.1 at
     * most, 1.5 at least: a coarse grid coarsens faster), each ring with
     * its own phase and every point jittered by a fifth of a cell. */
    double g = 1 + two_pi / (double)nc;
    g = g < 1.1 ? 1.1 : g > 1.5 ? 1.5 : g;
    while (!rc && rad < 30) {
        size_t m = (size_t)llround(two_pi * rad / t);
        double ph = two_pi * rng_u01(r);
        for (size_t i = 0; i < m && !rc; i++) {
            double a = ph + two_pi * ((double)i + 0.2 * (rng_u01(r) - 0.5)) / (double)m;
            double rr = rad + 0.2 * t * (rng_u01(r) - 0.5);
            rc = pts_add(p, rr * cos(a), rr * sin(a), 0.0);
        }
        rad += t;
        t *= g;
    }
    free(cx);
    free(cy);
    return rc;
}

/* ~N: an extruded 2-D CFD grid, as a 2-D solver's mesh turned into a
 * one-cell-thick 3-D case: an O-grid around a circle of diameter 1 (a
 * structured boundary layer of equal-angle rings, first cell 1e-4,
 * growth 1.2) inside an unstructured-looking far field (jittered rings
 * out to radius 30), the whole plane written at z = 0 and again at z = 1.
 * Two huge exactly coplanar layers; every pair of points over each other
 * with another such pair makes an exact rectangle (cocircular 4-set), and
 * the tets are as flat as the 60 : 1 extent ratio makes them. Never
 * fewer than ~1,100 points: the grid's structure has a floor. */
static int fam_extruded(pts *p, size_t n, rng *r)
{
    pts plane = {NULL, 0, 0};
    int rc = calibrated(&plane, (n + 1) / 2, r, extruded_gen, 0.25 * sqrt((double)n), 1.3);
    for (int layer = 0; layer < 2 && !rc; layer++)
        for (size_t i = 0; i < plane.n && !rc; i++)
            rc = pts_add(p, plane.xyz[3 * i], plane.xyz[3 * i + 1], (double)layer);
    free(plane.xyz);
    return rc;
}

/* The surface lattice of a box [x0, x0 + lx] x [y0, y0 + ly] x [z0, z0 +
 * lz] divided into nx x ny x nz equal cells: its points on the four sides
 * and the top (and the bottom when `bottom`), each corner, edge and face
 * point once. The lengths are multiples of 0.5 m, so x0 + lx * i / nx
 * lands exactly on the far face at i = nx. */
static int box_lattice(pts *p, double x0, double y0, double z0, double lx,
                       double ly, double lz, size_t nx, size_t ny, size_t nz,
                       int bottom)
{
    for (size_t k = 0; k <= nz; k++)
        for (size_t j = 0; j <= ny; j++)
            for (size_t i = 0; i <= nx; i++) {
                int side = i == 0 || i == nx || j == 0 || j == ny;
                if (!side && k != nz && !(bottom && k == 0))
                    continue;
                if (pts_add(p, x0 + lx * (double)i / (double)nx,
                            y0 + ly * (double)j / (double)ny,
                            z0 + lz * (double)k / (double)nz))
                    return -1;
            }
    return 0;
}

static size_t cells_of(double len, double h)
{
    size_t c = (size_t)llround(len / h);
    return c < 1 ? 1 : c;
}

/* One windcity with face spacing h (m). */
static int windcity_gen(pts *p, double h, size_t n, rng *r)
{
    if (!(h > 0.01))
        h = 0.01; /* calibration's first steps may overshoot */
    size_t nb = n / 700;
    nb = nb < 4 ? 4 : nb > 300 ? 300 : nb;
    /* Buildings on a 0.5 m grid, 5 m apart at least, footprints 8-40 m,
     * heights 6-80 m with most of them low. Lengths in half metres. */
    int64_t side = (int64_t)llround(sqrt((double)nb * 1600.0 * 3.0)) * 2;
    box_cm *b = malloc(nb * sizeof *b);
    if (!b)
        return -1;
    size_t placed = 0;
    for (size_t tries = 0; placed < nb && tries < 200 * nb; tries++) {
        box_cm c;
        c.x0 = (int64_t)rng_below(r, (uint64_t)side);
        c.y0 = (int64_t)rng_below(r, (uint64_t)side);
        c.x1 = c.x0 + 16 + (int64_t)rng_below(r, 65);
        c.y1 = c.y0 + 16 + (int64_t)rng_below(r, 65);
        double u = rng_u01(r);
        c.h = 12 + (int64_t)(u * u * u * 148.0);
        if (c.x1 > side || c.y1 > side)
            continue;
        int clash = 0;
        for (size_t i = 0; i < placed && !clash; i++)
            clash = c.x0 < b[i].x1 + 10 && b[i].x0 < c.x1 + 10 &&
                    c.y0 < b[i].y1 + 10 && b[i].y0 < c.y1 + 10;
        if (!clash)
            b[placed++] = c;
    }
    int rc = 0;
    int64_t hmax = 0;
    for (size_t i = 0; i < placed && !rc; i++) {
        const box_cm *c = &b[i];
        double lx = 0.5 * (double)(c->x1 - c->x0), ly = 0.5 * (double)(c->y1 - c->y0),
               lz = 0.5 * (double)c->h;
        if (c->h > hmax)
            hmax = c->h;
        rc = box_lattice(p, 0.5 * (double)c->x0, 0.5 * (double)c->y0, 0, lx, ly, lz,
                         cells_of(lx, h), cells_of(ly, h), cells_of(lz, h), 0);
    }
    /* The city's ground, 4 times coarser, around the footprints. */
    double city = 0.5 * (double)side, hg = 4 * h;
    size_t ng = cells_of(city, hg);
    for (size_t j = 0; j <= ng && !rc; j++)
        for (size_t i = 0; i <= ng && !rc; i++) {
            double x = city * (double)i / (double)ng, y = city * (double)j / (double)ng;
            int inside = 0;
            for (size_t q = 0; q < placed && !inside; q++)
                inside = 2 * x >= (double)b[q].x0 && 2 * x <= (double)b[q].x1 &&
                         2 * y >= (double)b[q].y0 && 2 * y <= (double)b[q].y1;
            if (!inside)
                rc = pts_add(p, x, y, 0.0);
        }
    free(b);
    /* The domain box: 5 city widths upstream and to the sides, 10
     * downstream, 6 times the tallest building high, each face a coarse
     * grid (32 x 22 x 6 cells at 200,000 points); its ground points
     * inside the city are left out. */
    if (!rc) {
        pts dom = {NULL, 0, 0};
        double dx = 16 * city, dy = 11 * city, dz = 3.0 * (double)hmax;
        size_t nx = (size_t)llround(sqrt((double)n) / 14);
        nx = nx < 4 ? 4 : nx;
        rc = box_lattice(&dom, -5 * city, -5 * city, 0, dx, dy, dz, nx,
                         cells_of((double)nx * 11, 16), cells_of((double)nx * 6, 32), 1);
        for (size_t i = 0; i < dom.n && !rc; i++) {
            const double *q = &dom.xyz[3 * i];
            if (q[2] == 0 && q[0] >= 0 && q[0] <= city && q[1] >= 0 && q[1] <= city)
                continue;
            rc = pts_add(p, q[0], q[1], q[2]);
        }
        free(dom.xyz);
    }
    return rc;
}

/* ~N: the surface vertices of an urban wind-study CAD model: up to 300
 * box buildings of varied sizes (8-40 m footprints, 6-80 m high) on a
 * ground plane, every wall and roof gridded into equal cells (spacing set
 * by N), the city's ground 4 times coarser, inside a domain box 16 x 11
 * city widths whose faces carry a coarse grid. Every face is a large
 * exactly coplanar set and every cell's corners are exactly cocircular
 * (cospherical with any fifth point); the domain's far corners dwarf the
 * city, so the front also crosses vast empty regions with few points. */
static int fam_windcity(pts *p, size_t n, rng *r)
{
    return calibrated(p, n, r, windcity_gen, 2.0, -2.0);
}

/* sign(c) |c|^e, the superquadric's signed power. */
static double spow(double c, double e)
{
    return c < 0 ? -pow(-c, e) : pow(c, e);
}

/* N points: a scanned statue: a bumpy superquadric about 0.4 x 0.3 x 1.2
 * m (in mm, printed with 6 decimals as scanner software writes), sampled
 * at random parameters (denser where the parametrisation crowds: the
 * poles and the rounded edges), with radial noise of ~0.03 mm, and about
 * 5% of the lines exact copies of an earlier point (overlapping scans
 * merged). A closed surface with an empty inside and a density contrast of
 * 10-100, on which every duplicate must merge. */
static int fam_statue(pts *p, size_t n, rng *r)
{
    for (size_t i = 0; i < n; i++) {
        if (i > 0 && rng_below(r, 20) == 0) {
            const double *q = &p->xyz[3 * rng_below(r, i)];
            if (pts_add(p, q[0], q[1], q[2]))
                return -1;
            continue;
        }
        double eta = asin(2 * rng_u01(r) - 1), om = two_pi * rng_u01(r) - 0.5 * two_pi;
        double bump = 1 + 0.04 * sin(5 * om + 1) * cos(3 * eta) +
                      0.02 * sin(13 * om) * sin(9 * eta) + 0.01 * sin(31 * om + 17 * eta);
        double f = bump * (1 + 5e-5 * rng_normal(r));
        double ce = spow(cos(eta), 0.5);
        double x = 200 * f * ce * spow(cos(om), 0.7);
        double y = 150 * f * ce * spow(sin(om), 0.7);
        double z = 600 * f * spow(sin(eta), 0.5);
        /* Quantise as the file will: a duplicate is then bit for bit the
         * point it copies, and no new duplicates arise from printing. */
        if (pts_add(p, round(x * 1e6) / 1e6, round(y * 1e6) / 1e6, round(z * 1e6) / 1e6))
            return -1;
    }
    return 0;
}

/* N points: N - 1 on the unit sphere with radial jitter 1e-7 and one at
 * the centre, placed at a random line. The centre's Voronoi cell touches
 * every other point's, so it is a vertex of ~2N tets (a cone over the
 * whole surface mesh) and every front face near it sees it as a
 * candidate; the shell is nearly cospherical, as in sphere. */
static int fam_centre(pts *p, size_t n, rng *r)
{
    size_t at = (size_t)rng_below(r, n);
    for (size_t i = 0; i < n; i++) {
        if (i == at) {
            if (pts_add(p, 0, 0, 0))
                return -1;
            continue;
        }
        double x, y, z, s;
        do {
            x = rng_normal(r), y = rng_normal(r), z = rng_normal(r);
            s = sqrt(x * x + y * y + z * z);
        } while (s < 1e-3);
        double rad = (1 + 1e-7 * (2 * rng_u01(r) - 1)) / s;
        if (pts_add(p, rad * x, rad * y, rad * z))
            return -1;
    }
    return 0;
}

/* ~N: a terrestrial scan's lines: L = sqrt(N/2) parallel lines 0.5 m
 * apart, points every 5 cm along each, on a gently curved ground, with
 * 0.1 mm of noise in height. Nearly collinear runs of thousands of points
 * and long thin triangles between the lines. */
static int fam_scanlines(pts *p, size_t n, rng *r)
{
    size_t lines = (size_t)llround(sqrt((double)n / 2.0));
    if (lines < 2)
        lines = 2;
    size_t k = n / lines < 2 ? 2 : n / lines;
    for (size_t i = 0; i < lines; i++)
        for (size_t j = 0; j < k; j++) {
            double x = 0.05 * (double)j;
            double y = 0.5 * (double)i + 0.01 * sin(0.1 * (double)j);
            if (pts_add(p, x, y, 0.002 * x * x + 1e-4 * rng_u01(r)))
                return -1;
        }
    return 0;
}

/* ~N: a boundary-layer block: an m x m grid of spacing 1, eight layers
 * whose heights grow tenfold from 1e-6 (cells of aspect ratio up to 1e6,
 * as a CFD mesh near a wall). Exact cospherical cells at every scale. */
static int fam_blayer(pts *p, size_t n, rng *r)
{
    (void)r;
    size_t m = (size_t)llround(sqrt((double)n / 8.0));
    if (m < 2)
        m = 2;
    double z[8] = {0.0};
    for (int k = 1; k < 8; k++)
        z[k] = z[k - 1] + pow(10.0, (double)(k - 7));
    for (size_t i = 0; i < m; i++)
        for (size_t j = 0; j < m; j++)
            for (int k = 0; k < 8; k++)
                if (pts_add(p, (double)i, (double)j, z[k]))
                    return -1;
    return 0;
}

/* ~N: a torus (R 3, r 1) sampled on its parameter grid: rings of equally
 * spaced points, every ring's points cospherical within rounding. */
static int fam_torus(pts *p, size_t n, rng *r)
{
    (void)r;
    size_t nu = (size_t)llround(sqrt(1.15 * (double)n));
    if (nu < 3)
        nu = 3;
    size_t nv = n / nu < 3 ? 3 : n / nu;
    for (size_t i = 0; i < nu; i++)
        for (size_t j = 0; j < nv; j++) {
            double u = two_pi * (double)i / (double)nu, v = two_pi * (double)j / (double)nv;
            double w = 3.0 + cos(v);
            if (pts_add(p, w * cos(u), w * sin(u), sin(v)))
                return -1;
        }
    return 0;
}

/* ~N: a cone, as the vertices of an axisymmetric CAD part: rings of 2m
 * equally spaced points at m heights, the radius growing with the height.
 * Every ring is cocircular, and the empty spheres of the inside are as
 * large as the part. */
static int fam_cone(pts *p, size_t n, rng *r)
{
    (void)r;
    size_t m = (size_t)llround(sqrt((double)n / 2.0));
    if (m < 2)
        m = 2;
    for (size_t i = 1; i <= m; i++)
        for (size_t j = 0; j < 2 * m; j++) {
            double a = two_pi * (double)j / (double)(2 * m), rr = 0.01 * (double)i;
            if (pts_add(p, rr * cos(a), rr * sin(a), 0.02 * (double)i))
                return -1;
        }
    return 0;
}

/* N points along a helix (a curve: a fibre, a wire, a drill path). Its
 * Delaunay tetrahedralization has about 150 tets a point. */
static int fam_helix(pts *p, size_t n, rng *r)
{
    (void)r;
    for (size_t i = 0; i < n; i++) {
        double t = 0.05 * (double)i;
        if (pts_add(p, cos(t), sin(t), 0.02 * t))
            return -1;
    }
    return 0;
}

/* N points on two concentric spheres of radii 1 and 50 (Fibonacci
 * spirals), half on each: a body and its far field, nothing between. */
static int fam_twoshells(pts *p, size_t n, rng *r)
{
    (void)r;
    size_t h = n / 2 < 2 ? 2 : n / 2;
    const double golden = 0.5 * two_pi * (3.0 - sqrt(5.0));
    for (int s = 0; s < 2; s++) {
        double rad = s ? 50.0 : 1.0;
        size_t cnt = s ? (n > h ? n - h : h) : h;
        for (size_t k = 0; k < cnt; k++) {
            double z = 1.0 - 2.0 * ((double)k + 0.5) / (double)cnt;
            double rr = sqrt(1.0 - z * z), ph = (double)k * golden;
            if (pts_add(p, rad * rr * cos(ph), rad * rr * sin(ph), rad * z))
                return -1;
        }
    }
    return 0;
}

/* ~N: the surface of an integer box m^3, every lattice point of its six
 * faces (a CAD solid's surface mesh): exactly coplanar and cospherical
 * everywhere, empty inside. */
static int fam_boxsurf(pts *p, size_t n, rng *r)
{
    (void)r;
    size_t m = (size_t)llround(sqrt((double)n / 6.0));
    if (m < 1)
        m = 1;
    for (size_t a = 0; a <= m; a++)
        for (size_t b = 0; b <= m; b++)
            for (size_t c = 0; c <= m; c++) {
                if (a != 0 && a != m && b != 0 && b != m && c != 0 && c != m)
                    continue;
                if (pts_add(p, (double)a, (double)b, (double)c))
                    return -1;
            }
    return 0;
}

/* ~N: a face-centred cubic crystal, s^3 unit cells of 4 atoms (corners
 * and face centres at halves: exact in binary), a metal's or a molecular
 * dynamics cell's atoms: every octahedral hole has 6 exactly cospherical
 * atoms around it, every tetrahedral one 4, and each is shared by
 * neighbouring holes' spheres. */
static int fam_fcc(pts *p, size_t n, rng *r)
{
    (void)r;
    size_t s = round_cbrt(n / 4 ? n / 4 : 1);
    static const double basis[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
    for (size_t i = 0; i < s; i++)
        for (size_t j = 0; j < s; j++)
            for (size_t k = 0; k < s; k++)
                for (int b = 0; b < 4; b++)
                    if (pts_add(p, (double)i + basis[b][0], (double)j + basis[b][1],
                                (double)k + basis[b][2]))
                        return -1;
    return 0;
}

/* ~N: a hexagonal close-packed crystal, s layers of s x s atoms (unit
 * spacing; rows sqrt(3)/2 apart, every other layer shifted by (1/2,
 * sqrt(3)/6) and sqrt(2/3) higher): the coordinates are rounded
 * irrationals, so its many cospherical groups are cospherical only to
 * rounding (their spheres differ in the last bits), and in its bounding
 * box Voronoi vertices fall within ulps of the walls (the `--dual` of
 * 5 x 5 x 6 and 3 x 3 x 7 once failed there). */
static int fam_hcp(pts *p, size_t n, rng *r)
{
    (void)r;
    size_t s = round_cbrt(n);
    for (size_t l = 0; l < s; l++)
        for (size_t i = 0; i < s; i++)
            for (size_t j = 0; j < s; j++) {
                double x = (double)i + 0.5 * (double)(j % 2) + (l % 2 ? 0.5 : 0);
                double y = (double)j * sqrt(3.0) / 2 + (l % 2 ? sqrt(3.0) / 6 : 0);
                if (pts_add(p, x, y, (double)l * sqrt(2.0 / 3.0)))
                    return -1;
            }
    return 0;
}

/* How a family's coordinates are printed: most as %.17g, which round-trips
 * every double; a few the way their real files are written. */
enum { FMT_17G, FMT_12G, FMT_2F, FMT_6F };

static const struct family {
    const char *name;
    family_fn fn;
    int fmt;
    const char *help;
} families[] = {
    {"uniform", fam_uniform, FMT_17G, "uniform in the unit cube"},
    {"ball", fam_ball, FMT_17G, "uniform in the unit ball"},
    {"sphere", fam_sphere, FMT_17G, "on the unit sphere up to rounding"},
    {"gaussian", fam_gaussian, FMT_17G, "standard normal in 3-D"},
    {"clusters", fam_clusters, FMT_17G, "90% in five 1e-6 clusters, 10% uniform"},
    {"lattice", fam_lattice, FMT_17G, "~N: the s^3 integer lattice"},
    {"intsphere", fam_intsphere, FMT_17G, "~N: every integer point of one sphere"},
    {"grid2d", fam_grid2d, FMT_17G, "~N: an m x m integer grid at z = 0 and z = 1"},
    {"offset", fam_offset, FMT_17G, "1 mm grid in a 20 m cube at 4.9e6"},
    {"tiny", fam_tiny, FMT_17G, "uniform scaled to 1e-150"},
    {"huge", fam_huge, FMT_17G, "uniform scaled to 1e150"},
    {"neardup", fam_neardup, FMT_17G, "uniform pairs 1e-8 apart"},
    {"dup", fam_dup, FMT_17G, "N points from N/10 distinct ones"},
    {"cfdgrid", fam_cfdgrid, FMT_17G, "~N: stretched structured CFD grid"},
    {"lidar", fam_lidar, FMT_17G, "airborne lidar, 0.01 ft grid, five planes"},
    {"dupheavy", fam_dupheavy, FMT_17G, "N points from sqrt(N) distinct ones"},
    {"mixed", fam_mixed, FMT_17G, "magnitudes 1e-150, 1, 1e150 in one file"},
    {"ulpgrid", fam_ulpgrid, FMT_17G, "2^40 plus multiples of 2^-12"},
    {"cylinder", fam_cylinder, FMT_17G,
     "~N: exact pipe surface, symmetric rings, empty inside"},
    {"cylscan", fam_cylscan, FMT_17G, "~N: pipe scan, rings of jittered angles"},
    {"rotlattice", fam_rotlattice, FMT_17G,
     "~N: k^3 lattice rotated by (0.3, 0.5, 0.7) rad"},
    {"skewlattice", fam_skewlattice, FMT_17G,
     "~N: k^3 lattice turned 0.01 rad about the axis (1, 2, 3)"},
    {"citylidar", fam_citylidar, FMT_2F,
     "~N: ground + flat-roof buildings, 1e6 offset, 1 cm steps, %.2f"},
    {"sphere12", fam_sphere12, FMT_12G,
     "Fibonacci sphere of radius 100 printed to 12 digits"},
    {"ogrid", fam_ogrid, FMT_17G,
     "~N: CFD O-grid around a sphere, first cell 1e-4 growing 1.25"},
    {"cubedsphere", fam_cubedsphere, FMT_17G,
     "~N: cubed-sphere O-grid, same radial spacing"},
    {"extruded", fam_extruded, FMT_17G,
     "~N: 2-D O-grid + far field around a circle, at z = 0 and 1"},
    {"windcity", fam_windcity, FMT_17G,
     "~N: CAD box buildings with gridded faces in a domain box"},
    {"statue", fam_statue, FMT_6F,
     "bumpy scanned surface, ~5% exact duplicates, %.6f"},
    {"centre", fam_centre, FMT_17G,
     "N - 1 on a sphere (radial jitter 1e-7) + its centre"},
    {"scanlines", fam_scanlines, FMT_17G, "~N: scan lines 0.5 m apart, 5 cm steps, curved ground"},
    {"blayer", fam_blayer, FMT_17G, "~N: boundary-layer block, 8 layers from 1e-6 growing 10x"},
    {"torus", fam_torus, FMT_17G, "~N: torus surface on its parameter grid"},
    {"cone", fam_cone, FMT_17G, "~N: cone of cocircular rings (axisymmetric CAD part)"},
    {"helix", fam_helix, FMT_17G, "points along a helix (a curve in 3-D)"},
    {"twoshells", fam_twoshells, FMT_17G, "two Fibonacci spheres, radii 1 and 50"},
    {"boxsurf", fam_boxsurf, FMT_17G, "~N: every integer point of a box's surface"},
    {"fcc", fam_fcc, FMT_17G, "~N: face-centred cubic crystal, s^3 cells of 4 atoms"},
    {"hcp", fam_hcp, FMT_17G, "~N: hexagonal close-packed crystal, s^3 atoms, irrational rows"},
};
#define N_FAMILIES (sizeof families / sizeof families[0])

static int usage(const char *argv0)
{
    fprintf(stderr,
            "usage: %s FAMILY N SEED OUT.xyz|OUT.ply [--shuffle PERM_OUT]\n"
            "       %s --list\n"
            "families (~N: the count is rounded to the family's structure;\n"
            "tests/gen_points.c says what each imitates and why it is hard):\n",
            argv0, argv0);
    for (size_t i = 0; i < N_FAMILIES; i++)
        fprintf(stderr, "  %-12s %s\n", families[i].name, families[i].help);
    return 2;
}

static int parse_u64(const char *s, uint64_t *v)
{
    char *end;
    errno = 0;
    unsigned long long x = strtoull(s, &end, 10);
    if (errno || end == s || *end || s[0] == '-')
        return -1;
    *v = x;
    return 0;
}

/* Whether path ends in .ply (any case): binary output. */
static int is_ply(const char *path)
{
    size_t len = strlen(path);
    if (len < 4 || path[len - 4] != '.')
        return 0;
    const char *e = path + len - 3;
    return (e[0] == 'p' || e[0] == 'P') && (e[1] == 'l' || e[1] == 'L') &&
           (e[2] == 'y' || e[2] == 'Y');
}

static int ply_header(FILE *f, const char *family, uint64_t n, uint64_t seed)
{
    return fprintf(f,
                   "ply\nformat binary_little_endian 1.0\n"
                   "comment gen_points %s %llu %llu\n"
                   "element vertex %llu\nproperty double x\nproperty double y\n"
                   "property double z\nend_header\n",
                   family, (unsigned long long)n, (unsigned long long)seed,
                   (unsigned long long)n) < 0;
}

/* Doubles as little-endian bytes into out (8 each), whatever the host. */
static void put_le(unsigned char *out, const double *v, size_t k)
{
    for (size_t i = 0; i < k; i++) {
        uint64_t u;
        memcpy(&u, &v[i], sizeof u);
        for (int b = 0; b < 8; b++)
            out[8 * i + (size_t)b] = (unsigned char)(u >> (8 * b));
    }
}

/* Points per block of the binary writers (1.5 MiB). */
#define PLY_BLOCK 65536

/* The uniform family drawn straight into a binary PLY: the draws of
 * fam_uniform, in its order, never all in memory. */
static int stream_uniform_ply(FILE *f, uint64_t n, uint64_t seed, rng *r)
{
    static double v[3 * PLY_BLOCK];
    static unsigned char b[24 * PLY_BLOCK];
    if (ply_header(f, "uniform", n, seed))
        return 1;
    for (uint64_t i = 0; i < n;) {
        size_t k = n - i < PLY_BLOCK ? (size_t)(n - i) : PLY_BLOCK;
        for (size_t j = 0; j < 3 * k; j++)
            v[j] = rng_u01(r);
        put_le(b, v, 3 * k);
        if (fwrite(b, 24, k, f) != k)
            return 1;
        i += k;
    }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc == 2 && !strcmp(argv[1], "--list")) {
        for (size_t i = 0; i < N_FAMILIES; i++)
            printf("%s\n", families[i].name);
        return 0;
    }
    const char *perm_path = NULL;
    if (argc == 7 && !strcmp(argv[5], "--shuffle"))
        perm_path = argv[6];
    else if (argc != 5)
        return usage(argv[0]);
    const struct family *fam = NULL;
    for (size_t i = 0; i < N_FAMILIES; i++)
        if (!strcmp(argv[1], families[i].name))
            fam = &families[i];
    uint64_t n, seed;
    if (!fam || parse_u64(argv[2], &n) || n < 1 || n > 100000000 ||
        parse_u64(argv[3], &seed))
        return usage(argv[0]);

    rng r;
    rng_seed(&r, seed);
    int ply = is_ply(argv[4]);
    if (ply && !perm_path && fam->fn == fam_uniform) {
        FILE *f = fopen(argv[4], "wb");
        if (!f) {
            fprintf(stderr, "gen_points: %s: %s\n", argv[4], strerror(errno));
            return 1;
        }
        int bad = stream_uniform_ply(f, n, seed, &r);
        if (fclose(f))
            bad = 1;
        if (bad) {
            fprintf(stderr, "gen_points: writing output failed\n");
            return 1;
        }
        return 0;
    }
    pts p = {NULL, 0, 0};
    int rc = fam->fn(&p, (size_t)n, &r);
    if (rc) {
        if (rc == -1)
            fprintf(stderr, "gen_points: out of memory\n");
        free(p.xyz);
        return 1;
    }

    size_t *perm = NULL;
    if (perm_path) {
        /* An independent stream, so the points do not depend on --shuffle. */
        rng rs;
        rng_seed(&rs, seed ^ 0x5f0e1d2c3b4a6978ULL);
        perm = malloc((p.n ? p.n : 1) * sizeof *perm);
        if (!perm) {
            fprintf(stderr, "gen_points: out of memory\n");
            free(p.xyz);
            return 1;
        }
        for (size_t i = 0; i < p.n; i++)
            perm[i] = i;
        for (size_t i = p.n; i > 1; i--) {
            size_t j = (size_t)rng_below(&rs, i);
            size_t t = perm[i - 1];
            perm[i - 1] = perm[j];
            perm[j] = t;
        }
    }

    int bad = 0;
    FILE *f = fopen(argv[4], ply ? "wb" : "w");
    if (!f) {
        fprintf(stderr, "gen_points: %s: %s\n", argv[4], strerror(errno));
        free(p.xyz);
        free(perm);
        return 1;
    }
    if (ply) {
        bad = ply_header(f, fam->name, p.n, seed);
        unsigned char b[24];
        for (size_t i = 0; i < p.n && !bad; i++) {
            double c[3];
            memcpy(c, &p.xyz[3 * (perm ? perm[i] : i)], sizeof c);
            /* the values the family's text holds, rounded as it writes them */
            const char *fmt = fam->fmt == FMT_12G ? "%.12g" : fam->fmt == FMT_2F ? "%.2f"
                              : fam->fmt == FMT_6F ? "%.6f" : NULL;
            for (int k = 0; k < 3 && fmt != NULL; k++) {
                char t[64];
                snprintf(t, sizeof t, fmt, c[k]);
                c[k] = strtod(t, NULL);
            }
            put_le(b, c, 3);
            bad = fwrite(b, 24, 1, f) != 1;
        }
    }
    for (size_t i = 0; i < p.n && !ply; i++) {
        const double *c = &p.xyz[3 * (perm ? perm[i] : i)];
        int w;
        switch (fam->fmt) {
        case FMT_12G:
            w = fprintf(f, "%.12g %.12g %.12g\n", c[0], c[1], c[2]);
            break;
        case FMT_2F:
            w = fprintf(f, "%.2f %.2f %.2f\n", c[0], c[1], c[2]);
            break;
        case FMT_6F:
            w = fprintf(f, "%.6f %.6f %.6f\n", c[0], c[1], c[2]);
            break;
        default:
            w = fprintf(f, "%.17g %.17g %.17g\n", c[0], c[1], c[2]);
        }
        if (w < 0)
            bad = 1;
    }
    if (fclose(f))
        bad = 1;
    if (perm) {
        FILE *g = fopen(perm_path, "w");
        if (!g)
            bad = 1;
        for (size_t i = 0; g && i < p.n; i++)
            if (fprintf(g, "%zu\n", perm[i]) < 0)
                bad = 1;
        if (g && fclose(g))
            bad = 1;
    }
    free(p.xyz);
    free(perm);
    if (bad) {
        fprintf(stderr, "gen_points: writing output failed\n");
        return 1;
    }
    return 0;
}
