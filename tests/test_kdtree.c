/*
 * kd-tree and apex-search tests against brute force (src/geom/kdtree.c) on the
 * point families of tests/testpoints.h (the seed, the face table and the
 * input preparation have their own files: tests/test_seed.c,
 * tests/test_facetab.c, tests/test_prepare.c); the
 * nearest neighbour's exact lowest-id tie rule against integer brute force
 * and the apex search on ulp grids (issue 20, at the end of the file).
 */
#include <gmp.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geom/kdtree.h"
#include "geom/predicates.h"
#include "geom/prepare.h"
#include "testutil.h"
#include "testpoints.h"

/* Brute-force apex: the first open-side point in the pencil order. */
static uint32_t brute_apex(const double *P, uint32_t n, uint32_t a, uint32_t b, uint32_t c)
{
    uint32_t best = FDT_NONE;
    for (uint32_t i = 0; i < n; i++) {
        if (i == a || i == b || i == c)
            continue;
        const double *d = P + 3 * (size_t)i;
        if (fdt_orient3d(P + 3 * (size_t)a, P + 3 * (size_t)b, P + 3 * (size_t)c, d, NULL) <= 0)
            continue;
        if (best == FDT_NONE ||
            fdt_insphere_perturbed(P + 3 * (size_t)a, P + 3 * (size_t)b, P + 3 * (size_t)c,
                                   P + 3 * (size_t)best, d, NULL) > 0)
            best = i;
    }
    return best;
}

static int collect_cb(void *user, uint32_t id)
{
    uint8_t *seen = user;
    seen[id] = 1;
    return 0;
}

/* Run the float-block kernels' SSE versions even where AVX2 is present. */
static int g_sse_only;

static void test_family(int fam, size_t want, int leaf)
{
    double *xyz = malloc(want * 3 * sizeof *xyz);
    size_t n = make_points(fam, want, xyz);
    fdt_prepared pr;
    char diag[256];
    EXPECTF(fdt_prepare(xyz, n, 1, &pr, diag, sizeof diag) == FDT_OK, "prepare %s", family_name[fam]);
    uint32_t m = (uint32_t)pr.m;
    fdt_kdtree t;
    EXPECTF(fdt_kd_build(&t, pr.p, pr.orig, 0, m, leaf) == FDT_OK, "build");
    if (g_sse_only)
        t.avx2 = 0; /* the SSE kernels, which machines without AVX2 run */
    const double *P = pr.p;
    fdt_kdq kq;
    memset(&kq, 0, sizeof kq);

    /* The float blocks (src/geom/kdtree.c): each leaf's block holds its points
     * as (x - lo) 2^-e, e the exponent of the box's largest extent, each
     * within 2^-23 of that value, in rows of a multiple of 8 floats, 32-byte
     * aligned (AVX loads); padding lanes are 0. */
    if (t.fl) {
        for (uint32_t i = 0; i < t.nnodes; i++) {
            const fdt_kdnode *nd = &t.nodes[i];
            if (nd->left)
                continue;
            double ext = 0.0;
            for (int k = 0; k < 3; k++)
                ext = fmax(ext, nd->hi[k] - nd->lo[k]);
            int e = 0;
            if (ext > 0.0)
                (void)frexp(ext, &e);
            uint32_t ln = nd->end - nd->begin, row = (ln + 7) & ~7u;
            const float *B = t.fl + 4 * (size_t)nd->dim;
            EXPECTF(((uintptr_t)B & 31) == 0, "block of leaf %u not aligned", i);
            for (int k = 0; k < 3; k++)
                for (uint32_t j = 0; j < row; j++) {
                    if (j >= ln) {
                        EXPECTF(B[k * row + j] == 0.0f, "padding of leaf %u", i);
                        continue;
                    }
                    if (e < -1000 || e > 1000)
                        continue; /* no frame: the tests use the doubles */
                    double x = ldexp(pr.p[3 * (size_t)(nd->begin + j) + k] - nd->lo[k], -e);
                    EXPECTF(fabs((double)B[k * row + j] - x) <= 0x1p-23,
                          "%s leaf %u point %u axis %d: %.9g against %.17g", family_name[fam], i, j,
                          k, (double)B[k * row + j], x);
                }
        }
    } else {
        EXPECTF(0, "%s: no float blocks", family_name[fam]);
    }

    /* Tree invariants: every node's box holds its points, leaves are
     * small, children partition the parent's range. */
    for (uint32_t i = 0; i < t.nnodes; i++) {
        const fdt_kdnode *nd = &t.nodes[i];
        for (uint32_t j = nd->begin; j < nd->end; j++)
            for (int k = 0; k < 3; k++)
                EXPECTF(P[3 * (size_t)j + k] >= nd->lo[k] && P[3 * (size_t)j + k] <= nd->hi[k],
                      "point %u outside node %u box", j, i);
        if (nd->left) {
            EXPECTF(t.nodes[nd->left].begin == nd->begin && t.nodes[nd->left].end ==
                  t.nodes[nd->left + 1].begin && t.nodes[nd->left + 1].end == nd->end,
                  "node %u children do not partition it", i);
            EXPECTF(t.nodes[nd->left].hi[nd->dim] <= t.nodes[nd->left + 1].lo[nd->dim],
                  "node %u children overlap on the split axis", i);
        } else {
            EXPECTF(nd->end - nd->begin <= (uint32_t)leaf, "leaf %u too big", i);
        }
    }
    /* The permutation keeps each point with its input index. */
    for (uint32_t i = 0; i < m; i++)
        for (int k = 0; k < 3; k++)
            EXPECTF(ldexp(xyz[3 * (size_t)pr.orig[i] + k], pr.scale_exp) == P[3 * (size_t)i + k],
                  "orig map broken at %u", i);

    /* Nearest neighbour against brute force (distance ties allowed). */
    for (int q = 0; q < 200; q++) {
        uint32_t id = (uint32_t)(rnd() % m);
        uint32_t nn = fdt_kd_nearest(&t, P + 3 * (size_t)id, id, &kq);
        double bd = INFINITY;
        for (uint32_t j = 0; j < m; j++) {
            if (j == id)
                continue;
            double dx = P[3 * (size_t)j] - P[3 * (size_t)id], dy = P[3 * (size_t)j + 1] - P[3 * (size_t)id + 1],
                   dz = P[3 * (size_t)j + 2] - P[3 * (size_t)id + 2];
            double d = dx * dx + dy * dy + dz * dz;
            if (d < bd)
                bd = d;
        }
        const double *a = P + 3 * (size_t)nn, *b = P + 3 * (size_t)id;
        double d = (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]);
        EXPECTF(nn != id && d == bd, "%s nearest of %u: got %u", family_name[fam], id, nn);
    }

    /* Ball query returns a superset of the points within r. */
    uint8_t *seen = calloc(m, 1);
    for (int q = 0; q < 50; q++) {
        const double *c = P + 3 * (size_t)(rnd() % m);
        double r = (t.nodes[0].hi[0] - t.nodes[0].lo[0]) * urand() * 0.3;
        memset(seen, 0, m);
        fdt_kd_ball(&t, c, r, collect_cb, seen, &kq);
        for (uint32_t j = 0; j < m; j++) {
            const double *d = P + 3 * (size_t)j;
            double dd = sqrt((d[0] - c[0]) * (d[0] - c[0]) + (d[1] - c[1]) * (d[1] - c[1]) +
                             (d[2] - c[2]) * (d[2] - c[2]));
            if (dd <= r)
                EXPECTF(seen[j], "%s ball query missed point %u", family_name[fam], j);
        }
    }
    free(seen);

    /* Apex search (top-down and bottom-up) against brute force, on faces
     * of random triples, including hull faces (no apex) and flat ones. */
    /* Half the faces are random triples (big spheres, hull faces), half
     * are local: b and c among a's 8 nearest, like real front faces, whose
     * small spheres let the bottom-up search stop early. */
    uint32_t near[8];
    for (int q = 0; q < 600; q++) {
        uint32_t a = (uint32_t)(rnd() % m), b = (uint32_t)(rnd() % m), c = (uint32_t)(rnd() % m);
        if (q & 1) {
            double nd[8];
            int cnt = 0;
            for (uint32_t j = 0; j < m; j++) {
                if (j == a)
                    continue;
                const double *x = P + 3 * (size_t)j, *y = P + 3 * (size_t)a;
                double d = (x[0] - y[0]) * (x[0] - y[0]) + (x[1] - y[1]) * (x[1] - y[1]) +
                           (x[2] - y[2]) * (x[2] - y[2]);
                /* Insertion into the sorted 8 nearest so far. */
                if (cnt == 8 && d >= nd[7])
                    continue;
                int k = cnt < 8 ? cnt++ : 7;
                while (k > 0 && nd[k - 1] > d) {
                    nd[k] = nd[k - 1];
                    near[k] = near[k - 1];
                    k--;
                }
                nd[k] = d;
                near[k] = j;
            }
            b = near[rnd() % 8];
            c = near[rnd() % 8];
        }
        if (a == b || b == c || a == c)
            continue;
        if (fdt_orient3d(P + 3 * (size_t)a, P + 3 * (size_t)b, P + 3 * (size_t)c,
                         P + 3 * (size_t)((a + 1) % m), NULL) == 0 &&
            fdt_orient3d(P + 3 * (size_t)a, P + 3 * (size_t)b, P + 3 * (size_t)c,
                         P + 3 * (size_t)((a + 7) % m), NULL) == 0 && (q & 2))
            continue;
        uint32_t want_apex = brute_apex(P, m, a, b, c);
        fdt_apex s;
        fdt_apex_init(&s, P + 3 * (size_t)a, P + 3 * (size_t)b, P + 3 * (size_t)c, a, b, c);
        fdt_apex_search(&s, &t, &kq);
        EXPECTF(s.best == want_apex, "%s apex (top-down) of %u %u %u: got %u want %u",
              family_name[fam], a, b, c, s.best, want_apex);
        fdt_apex_init(&s, P + 3 * (size_t)a, P + 3 * (size_t)b, P + 3 * (size_t)c, a, b, c);
        fdt_apex_search_from(&s, &t, (q & 1) ? a : (uint32_t)(rnd() % m), &kq);
        EXPECTF(s.best == want_apex, "%s apex (bottom-up) of %u %u %u: got %u want %u",
              family_name[fam], a, b, c, s.best, want_apex);
        if (want_apex != FDT_NONE) {
            /* The found tet is empty of open-side points; any_inside finds
             * a violator exactly when brute force does. */
            uint32_t v[4] = {a, b, c, want_apex};
            uint32_t viol = fdt_kd_any_inside(&t, v, &kq);
            int brute_viol = 0;
            for (uint32_t j = 0; j < m && !brute_viol; j++)
                if (j != a && j != b && j != c && j != want_apex &&
                    fdt_insphere_perturbed(P + 3 * (size_t)a, P + 3 * (size_t)b, P + 3 * (size_t)c,
                                           P + 3 * (size_t)want_apex, P + 3 * (size_t)j, NULL) > 0)
                    brute_viol = 1;
            EXPECTF((viol != FDT_NONE) == brute_viol, "%s any_inside disagrees with brute force",
                  family_name[fam]);
        }
    }

    fdt_kd_free(&t);
    fdt_prepared_free(&pr);
    free(xyz);
}

/* ---- issue 20: exact tie rule of the nearest neighbour, the ball's
 * tolerance on ulp grids -------------------------------------------------- */

/* x 2^1074 as an integer: every double is an integer multiple of 2^-1074,
 * so integers compare distances exactly without the rationals' gcds. */
static void scaled_int(mpz_t z, double x)
{
    mpq_t t;
    mpq_init(t);
    mpq_set_d(t, x);
    mpq_mul_2exp(t, t, 1074);
    mpz_set(z, mpq_numref(t)); /* the denominator is now 1 */
    mpq_clear(t);
}

/* |x - q|^2 (times 2^2148) from scaled integers (z and t initialised by
 * the caller). */
static void exact_dist2(mpz_t z, const mpz_t *q, const mpz_t *x, mpz_t t)
{
    mpz_set_ui(z, 0);
    for (int k = 0; k < 3; k++) {
        mpz_sub(t, x[k], q[k]);
        mpz_addmul(z, t, t);
    }
}

static double float_dist2(const double *q, const double *x)
{
    double dx = x[0] - q[0], dy = x[1] - q[1], dz = x[2] - q[2];
    return dx * dx + dy * dy + dz * dz;
}

/* The exact nearest of the n points of P (Q: the same as scaled_int) to
 * q other than `exclude`, the lowest id on ties, by brute force in
 * integers; *nmin gets how many points are at that distance and *blind
 * whether a point at another distance has the same floating squared
 * distance as the winner. */
static uint32_t brute_nearest(const double *P, const mpz_t *Q, uint32_t n, const double *q,
                              uint32_t exclude, int *nmin, int *blind)
{
    mpz_t best, d, t, qq[3];
    mpz_inits(best, d, t, qq[0], qq[1], qq[2], NULL);
    for (int k = 0; k < 3; k++)
        scaled_int(qq[k], q[k]);
    uint32_t bi = FDT_NONE;
    int cnt = 0;
    for (uint32_t j = 0; j < n; j++) {
        if (j == exclude)
            continue;
        exact_dist2(d, qq, Q + 3 * (size_t)j, t);
        int c = bi == FDT_NONE ? -1 : mpz_cmp(d, best);
        if (c < 0) {
            mpz_set(best, d);
            bi = j;
            cnt = 1;
        } else if (c == 0) {
            cnt++;
        }
    }
    *nmin = cnt;
    *blind = 0;
    if (bi != FDT_NONE) {
        double bf = float_dist2(q, P + 3 * (size_t)bi);
        for (uint32_t j = 0; j < n && !*blind; j++) {
            if (j == exclude || float_dist2(q, P + 3 * (size_t)j) != bf)
                continue;
            exact_dist2(d, qq, Q + 3 * (size_t)j, t);
            *blind = mpz_cmp(d, best) != 0;
        }
    }
    mpz_clears(best, d, t, qq[0], qq[1], qq[2], NULL);
    return bi;
}

/* A random integer below 2^L, L uniform in [0, maxbits]; signed if sgn. */
static int64_t rnd_bits(int maxbits, int sgn)
{
    int L = (int)(rnd() % (uint64_t)(maxbits + 1));
    int64_t v = L == 0 ? 0 : (int64_t)(rnd() >> (64 - L));
    return sgn && (rnd() & 1) ? -v : v;
}

/*
 * Point sets full of exact distance ties, some visible only in exact
 * arithmetic (kind as below); returns the count and a query point q that
 * need not be one of them.
 *   0: a small integer lattice scaled by 2^e, e from subnormal (every
 *      squared distance underflows to 0) to 2^900;
 *   1: shells about q: offsets of one integer length (the signed
 *      permutations of a Pythagorean quadruple's (a, b, c) and (d, 0, 0),
 *      whose floating squared lengths may differ), the same moved out by
 *      one unit, and random points farther out, all scaled by 2^e;
 *   2: mixed magnitudes: q + (+-2^-10, j 2^-600, k 2^-600) for small j, k:
 *      every floating squared distance to q is 2^-20, the exact ones
 *      order by j^2 + k^2 (ties: (5,0), (3,4), (0,-5), ...).
 */
static uint32_t tie_set(int kind, double *P, uint32_t cap, double q[3])
{
    uint32_t n = 0;
    if (kind == 0) {
        static const int es[] = {-1074, -1060, -600, 0, 900};
        int e = es[rnd() % 5];
        for (int i = 0; i < 6; i++)
            for (int j = 0; j < 6; j++)
                for (int k = 0; k < 6 && n < cap; k++, n++) {
                    P[3 * n] = ldexp((double)i, e);
                    P[3 * n + 1] = ldexp((double)j, e);
                    P[3 * n + 2] = ldexp((double)k, e);
                }
        for (int k = 0; k < 3; k++)
            q[k] = ldexp((double)(rnd() % 11) * 0.5, e);
    } else if (kind == 1) {
        static const int es[] = {-1074, -1040, -500, -52, 0, 400};
        int e = es[rnd() % 6];
        int64_t C[3];
        for (int k = 0; k < 3; k++) {
            C[k] = rnd_bits(50, 1);
            q[k] = ldexp((double)C[k], e);
        }
        while (n + 60 <= cap) {
            int64_t m = rnd_bits(12, 0), nn = rnd_bits(12, 0), r = rnd_bits(12, 0),
                    s = rnd_bits(12, 0);
            int64_t b3[3] = {m * m + nn * nn - r * r - s * s, 2 * (m * s + nn * r),
                             2 * (nn * s - m * r)};
            int64_t d = m * m + nn * nn + r * r + s * s;
            for (int j = 0; j < 54; j++) {
                int64_t v[3] = {0, 0, 0};
                if (j < 48) {
                    static const int perm6[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2},
                                                    {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
                    for (int k = 0; k < 3; k++)
                        v[k] = b3[perm6[j / 8][k]] * (((j >> k) & 1) ? -1 : 1);
                } else {
                    v[(j - 48) / 2] = (j & 1) ? -d : d;
                }
                if (rnd() % 8 == 0) { /* one unit farther on its largest axis */
                    int k = 0;
                    for (int i = 1; i < 3; i++)
                        k = llabs(v[i]) > llabs(v[k]) ? i : k;
                    v[k] += v[k] >= 0 ? 1 : -1;
                }
                if (rnd() % 6 == 0)
                    continue; /* sparser shells */
                for (int k = 0; k < 3; k++)
                    P[3 * n + k] = ldexp((double)(C[k] + v[k]), e);
                n++;
            }
            for (int i = 0; i < 6; i++, n++) /* far points */
                for (int k = 0; k < 3; k++)
                    P[3 * n + k] = ldexp((double)(C[k] + (int64_t)(rnd() % 40000) + 20000), e);
        }
    } else {
        q[0] = 0.5;
        q[1] = 0.0;
        q[2] = 0.0;
        for (int j = -6; j <= 6; j++)
            for (int k = -6; k <= 6 && n + 2 <= cap; k++)
                for (int s = -1; s <= 1; s += 2, n++) {
                    P[3 * n] = 0.5 + s * 0x1p-10;
                    P[3 * n + 1] = ldexp((double)j, -600);
                    P[3 * n + 2] = ldexp((double)k, -600);
                }
    }
    /* Distinct points only (the tree's callers merge duplicates). */
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; i++) {
        int dup = 0;
        for (uint32_t j = 0; j < m && !dup; j++)
            dup = !memcmp(P + 3 * (size_t)i, P + 3 * (size_t)j, 3 * sizeof *P);
        if (!dup)
            memmove(P + 3 * (size_t)m++, P + 3 * (size_t)i, 3 * sizeof *P);
    }
    return m;
}

/*
 * fdt_kd_nearest's rule "an exactly nearest point, the lowest id on exact
 * ties" against brute force in rationals (tests/test_kdtree.c's other
 * nearest-neighbour check compares floating distances, which cannot see
 * the rule), on the tie sets above, from the extra query q and from the
 * set's own points (excluded), with big and tiny leaves. Queries with
 * several nearest points, and with a floating tie between the winner and
 * a point at another exact distance, must both occur.
 */
static void test_nearest_ties(void)
{
    enum { CAP = 720 };
    double *P = malloc(CAP * 3 * sizeof *P);
    fdt_vid *orig = malloc(CAP * sizeof *orig);
    mpz_t *Q = malloc(CAP * 3 * sizeof *Q);
    for (int i = 0; i < 3 * CAP; i++)
        mpz_init(Q[i]);
    long queries = 0, multi = 0, blind = 0;
    for (int round = 0; round < 24; round++) {
        int kind = round % 3, leaf = round % 2 ? 3 : 30;
        double q[3];
        uint32_t n = tie_set(kind, P, CAP, q);
        for (uint32_t i = 0; i < n; i++)
            orig[i] = i;
        fdt_kdtree t;
        EXPECTF(fdt_kd_build(&t, P, orig, 0, n, leaf) == FDT_OK, "build tie set %d", kind);
        for (uint32_t i = 0; i < 3 * n; i++) /* after the build's permutation */
            scaled_int(Q[i], P[i]);
        fdt_kdq kq;
        memset(&kq, 0, sizeof kq);
        for (int qi = 0; qi < 40; qi++) {
            uint32_t ex = qi == 0 ? FDT_NONE : (uint32_t)(rnd() % n);
            const double *qq = ex == FDT_NONE ? q : P + 3 * (size_t)ex;
            int nmin, bl;
            uint32_t want = brute_nearest(P, Q, n, qq, ex, &nmin, &bl);
            uint32_t got = fdt_kd_nearest(&t, qq, ex, &kq);
            queries++;
            multi += nmin > 1;
            blind += bl;
            EXPECTF(got == want, "tie set %d (leaf %d), query %u: nearest %u, want %u (%d at "
                  "the least distance)", kind, leaf, ex, got, want, nmin);
        }
        fdt_kd_free(&t);
    }
    EXPECTF(multi > 0 && blind > 0, "tie sets: %ld of %ld queries with ties, %ld floating-blind",
          multi, queries, blind);
    for (int i = 0; i < 3 * CAP; i++)
        mpz_clear(Q[i]);
    free(Q);
    free(P);
    free(orig);
}

/*
 * The apex search on ulp grids: coordinates 2^40 + k 2^-12, one ulp apart
 * (tests/gen_points.c's ulpgrid family), scaled by fdt_prepare like real
 * input. The search ball's centre a + x is rounded at the magnitude of a,
 * an error of the order of the grid step, which only the absolute term of
 * the ball's tolerance (update_ball in src/geom/kdtree.c) covers; without it the
 * ball can leave out a point of the true sphere. Both searches against
 * brute force, on local and random faces.
 */
static void test_apex_ulpgrid(void)
{
    static const int side[] = {8, 16, 64, 1024};
    for (int r = 0; r < 8; r++) {
        const size_t want = 500;
        int G = side[r % 4], leaf = r < 4 ? 18 : 3;
        double *xyz = malloc(want * 3 * sizeof *xyz);
        for (size_t i = 0; i < want; i++)
            for (int k = 0; k < 3; k++)
                xyz[3 * i + k] = 0x1p40 + ldexp((double)(rnd() % (uint64_t)G), -12);
        fdt_prepared pr;
        char diag[256];
        EXPECTF(fdt_prepare(xyz, want, 1, &pr, diag, sizeof diag) == FDT_OK, "prepare ulpgrid");
        uint32_t m = (uint32_t)pr.m;
        fdt_kdtree t;
        EXPECTF(fdt_kd_build(&t, pr.p, pr.orig, 0, m, leaf) == FDT_OK, "build ulpgrid");
        const double *P = pr.p;
        fdt_kdq kq;
        memset(&kq, 0, sizeof kq);
        long faces = 0, bad = 0;
        for (int f = 0; f < 400; f++) {
            uint32_t a = (uint32_t)(rnd() % m), b, c;
            if (f & 1) {
                /* b and c among the points nearest a, as on a real front */
                uint32_t near[6];
                double nd[6];
                int cnt = 0;
                for (uint32_t j = 0; j < m; j++) {
                    if (j == a)
                        continue;
                    const double *x = P + 3 * (size_t)j, *y = P + 3 * (size_t)a;
                    double d = (x[0] - y[0]) * (x[0] - y[0]) + (x[1] - y[1]) * (x[1] - y[1]) +
                               (x[2] - y[2]) * (x[2] - y[2]);
                    if (cnt == 6 && d >= nd[5])
                        continue;
                    int k = cnt < 6 ? cnt++ : 5;
                    while (k > 0 && nd[k - 1] > d) {
                        nd[k] = nd[k - 1];
                        near[k] = near[k - 1];
                        k--;
                    }
                    nd[k] = d;
                    near[k] = j;
                }
                b = near[rnd() % 6];
                c = near[rnd() % 6];
            } else {
                b = (uint32_t)(rnd() % m);
                c = (uint32_t)(rnd() % m);
            }
            if (a == b || b == c || a == c)
                continue;
            const double *pa = P + 3 * (size_t)a, *pb = P + 3 * (size_t)b, *pc = P + 3 * (size_t)c;
            uint32_t want_apex = brute_apex(P, m, a, b, c);
            fdt_apex s;
            fdt_apex_init(&s, pa, pb, pc, a, b, c);
            fdt_apex_search(&s, &t, &kq);
            uint32_t top = s.best;
            fdt_apex_init(&s, pa, pb, pc, a, b, c);
            fdt_apex_search_from(&s, &t, a, &kq);
            faces++;
            bad += top != want_apex || s.best != want_apex;
            EXPECTF(top == want_apex && s.best == want_apex,
                  "ulpgrid %d^3 (leaf %d) apex of %u %u %u: top-down %u, bottom-up %u, want %u",
                  G, leaf, a, b, c, top, s.best, want_apex);
        }
        EXPECTF(faces > 300, "ulpgrid: only %ld faces", faces);
        fdt_kd_free(&t);
        fdt_prepared_free(&pr);
        free(xyz);
    }
}

/*
 * fdt_kd_begin / fdt_kd_run / fdt_kd_end (the partition's builders share
 * a tree's jobs) give fdt_kd_build's tree node for node, and the same
 * permutation of the points, whatever order the jobs run in: here the
 * pending jobs are taken from the bottom of the list (breadth first)
 * with a small grain, so the right halves of the top run before the left
 * subtrees are done, and nodes are numbered out of build order.
 */
static void test_jobs(int fam, size_t want, int leaf, uint32_t grain)
{
    double *xyz = malloc(want * 3 * sizeof *xyz);
    size_t n = make_points(fam, want, xyz);
    fdt_prepared a, b;
    char diag[256];
    EXPECTF(fdt_prepare(xyz, n, 1, &a, diag, sizeof diag) == FDT_OK, "prepare");
    EXPECTF(fdt_prepare(xyz, n, 1, &b, diag, sizeof diag) == FDT_OK, "prepare");
    uint32_t m = (uint32_t)a.m;
    fdt_kdtree ta, tb;
    CHECK_EQ(fdt_kd_build(&ta, a.p, a.orig, 0, m, leaf), FDT_OK);
    fdt_kd_job *jobs = malloc((4 * (size_t)m + 8) * sizeof *jobs);
    size_t head = 0, tail = 0, ran = 0;
    CHECK_EQ(fdt_kd_begin(&tb, b.p, b.orig, 0, m, leaf, &jobs[tail++]), FDT_OK);
    while (head < tail) {
        fdt_kd_job kids[2];
        int k = fdt_kd_run(&jobs[head++], grain, kids);
        ran++;
        for (int i = 0; i < k; i++)
            jobs[tail++] = kids[i];
    }
    CHECK_EQ(fdt_kd_end(&tb), FDT_OK);
    EXPECTF(ran > 3 || m <= grain, "%s: %zu jobs", family_name[fam], ran);
    CHECK_EQ(ta.nnodes, tb.nnodes);
    int same = 1;
    for (uint32_t i = 0; i < ta.nnodes && same; i++) {
        const fdt_kdnode *x = &ta.nodes[i], *y = &tb.nodes[i];
        same = x->begin == y->begin && x->end == y->end && x->left == y->left &&
               x->dim == y->dim && memcmp(x->lo, y->lo, sizeof x->lo) == 0 &&
               memcmp(x->hi, y->hi, sizeof x->hi) == 0;
    }
    EXPECTF(same, "%s: the jobs' nodes differ from fdt_kd_build's", family_name[fam]);
    EXPECTF(memcmp(a.p, b.p, 3 * (size_t)m * sizeof *a.p) == 0 &&
                memcmp(a.orig, b.orig, (size_t)m * sizeof *a.orig) == 0,
            "%s: the jobs permuted the points otherwise", family_name[fam]);
    EXPECTF(memcmp(ta.leafof, tb.leafof, (size_t)m * sizeof *ta.leafof) == 0 &&
                memcmp(ta.parent, tb.parent, ta.nnodes * sizeof *ta.parent) == 0,
            "%s: climb tables differ", family_name[fam]);
    free(jobs);
    fdt_kd_free(&ta);
    fdt_kd_free(&tb);
    fdt_prepared_free(&a);
    fdt_prepared_free(&b);
    free(xyz);
}

int main(void)
{
    for (int fam = 0; fam < NFAMILIES; fam++) {
        test_jobs(fam, 5000, 18, 200);
        test_jobs(fam, 3000, 30, 31);
        test_jobs(fam, 700, 3, 4);
    }
    test_nearest_ties();
    test_apex_ulpgrid();
    for (g_sse_only = 0; g_sse_only <= 1; g_sse_only++)
        for (int fam = 0; fam < NFAMILIES; fam++) {
            test_family(fam, 700, 18);
            test_family(fam, 300, 3);
        }
    return test_report("test_kdtree");
}
