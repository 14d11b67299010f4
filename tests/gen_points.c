/*
 * gen_points FAMILY N SEED OUT.xyz [--shuffle PERM_OUT]
 * gen_points --list
 *
 * Writes about N points of a named family of hard inputs (qhull's
 * q_benchmark idea: cospherical, nearly cospherical, lattice, ...) as
 * "x y z" lines with %.17g, which round-trips every double exactly. The
 * families imitate what scanned and CFD point clouds do to a Delaunay
 * code: exact cospherical and coplanar sets, huge offsets with tiny
 * extents, extreme magnitudes, near and exact duplicates.
 *
 * The output is a pure function of (FAMILY, N, SEED) on a given platform,
 * so (family, N, seed) is a complete reproducer. Families marked "~N"
 * below round N to their structure (a lattice has s^3 points).
 *
 * --shuffle applies a random permutation (from SEED) to the output and
 * writes it to PERM_OUT: line i holds the original index of output point
 * i, so tests can map a mesh of the shuffled file back and check that the
 * tetrahedralization does not depend on input order.
 */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------ RNG */

/* xoshiro256** (Blackman & Vigna), seeded through splitmix64: fast, good
 * statistics, and identical on every platform. */
typedef struct rng {
    uint64_t s[4];
} rng;

static uint64_t splitmix64(uint64_t *x)
{
    uint64_t z = (*x += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

static void rng_seed(rng *r, uint64_t seed)
{
    for (int i = 0; i < 4; i++)
        r->s[i] = splitmix64(&seed);
}

static uint64_t rotl(uint64_t x, int k)
{
    return (x << k) | (x >> (64 - k));
}

static uint64_t rng_next(rng *r)
{
    uint64_t *s = r->s;
    uint64_t result = rotl(s[1] * 5, 7) * 9;
    uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = rotl(s[3], 45);
    return result;
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

static const struct family {
    const char *name;
    family_fn fn;
} families[] = {
    {"uniform", fam_uniform},     {"ball", fam_ball},
    {"sphere", fam_sphere},       {"gaussian", fam_gaussian},
    {"clusters", fam_clusters},   {"lattice", fam_lattice},
    {"intsphere", fam_intsphere}, {"grid2d", fam_grid2d},
    {"offset", fam_offset},       {"tiny", fam_tiny},
    {"huge", fam_huge},           {"neardup", fam_neardup},
    {"dup", fam_dup},             {"cfdgrid", fam_cfdgrid},
    {"lidar", fam_lidar},         {"dupheavy", fam_dupheavy},
    {"mixed", fam_mixed},         {"ulpgrid", fam_ulpgrid},
};
#define N_FAMILIES (sizeof families / sizeof families[0])

static int usage(const char *argv0)
{
    fprintf(stderr,
            "usage: %s FAMILY N SEED OUT.xyz [--shuffle PERM_OUT]\n"
            "       %s --list\nfamilies:",
            argv0, argv0);
    for (size_t i = 0; i < N_FAMILIES; i++)
        fprintf(stderr, " %s", families[i].name);
    fprintf(stderr, "\n");
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
    FILE *f = fopen(argv[4], "w");
    if (!f) {
        fprintf(stderr, "gen_points: %s: %s\n", argv[4], strerror(errno));
        free(p.xyz);
        free(perm);
        return 1;
    }
    for (size_t i = 0; i < p.n; i++) {
        const double *c = &p.xyz[3 * (perm ? perm[i] : i)];
        if (fprintf(f, "%.17g %.17g %.17g\n", c[0], c[1], c[2]) < 0)
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
