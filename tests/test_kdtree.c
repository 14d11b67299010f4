/*
 * kd-tree and apex-search tests against brute force (src/kdtree.c), the
 * seed tetrahedron (src/seed.c), the face table (src/facetab.c) and input
 * preparation (src/prepare.c), on random and degenerate point sets.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "facetab.h"
#include "kdtree.h"
#include "predicates.h"
#include "prepare.h"
#include "seed.h"

static int failures;
#define CHECK(cond, ...)                                                     \
    do {                                                                     \
        if (!(cond)) {                                                       \
            failures++;                                                      \
            fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__);             \
            fprintf(stderr, __VA_ARGS__);                                    \
            fputc('\n', stderr);                                             \
        }                                                                    \
    } while (0)

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static uint64_t rnd(void)
{
    uint64_t z = (rng_state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}
static double urand(void) { return (double)(rnd() >> 11) * 0x1p-53; }

enum { UNIFORM, LATTICE, SPHERE_INT, GRID2D, OFFSET, MIXED, NFAMILIES };
static const char *family_name[] = {"uniform", "lattice", "intsphere", "grid2d", "offset",
                                    "mixed"};

/* Fills up to n distinct-ish points of a family; returns the count. */
static size_t make_points(int fam, size_t n, double *p)
{
    size_t m = 0;
    if (fam == UNIFORM || fam == OFFSET) {
        for (; m < n; m++)
            for (int k = 0; k < 3; k++)
                p[3 * m + k] = fam == UNIFORM ? urand()
                                              : 4.9e6 + floor(urand() * 20000.0) * 1e-3;
    } else if (fam == MIXED) {
        /* leaves of very different sizes side by side: half the points
         * in the unit cube, half in a cube 1e-9 wide inside it, and a
         * few 1e-300 from its corner (the float blocks' frames) */
        for (; m < n; m++)
            for (int k = 0; k < 3; k++)
                p[3 * m + k] = m % 2 == 0 ? urand()
                               : m % 11 == 1 ? 0.25 + urand() * 1e-300
                                             : 0.5 + urand() * 1e-9;
    } else if (fam == LATTICE) {
        int s = (int)cbrt((double)n);
        for (int i = 0; i < s; i++)
            for (int j = 0; j < s; j++)
                for (int k = 0; k < s; k++, m++) {
                    p[3 * m] = i;
                    p[3 * m + 1] = j;
                    p[3 * m + 2] = k;
                }
    } else if (fam == SPHERE_INT) {
        const int r2 = 11 * 11 + 2 * 2; /* many integer points, none redundant */
        for (int i = -12; i <= 12 && m < n; i++)
            for (int j = -12; j <= 12 && m < n; j++)
                for (int k = -12; k <= 12 && m < n; k++)
                    if (i * i + j * j + k * k == r2) {
                        p[3 * m] = i;
                        p[3 * m + 1] = j;
                        p[3 * m + 2] = k;
                        m++;
                    }
    } else {
        int s = (int)sqrt((double)n / 2.0);
        for (int i = 0; i < s; i++)
            for (int j = 0; j < s; j++)
                for (int z = 0; z < 2; z++, m++) {
                    p[3 * m] = i;
                    p[3 * m + 1] = j;
                    p[3 * m + 2] = z;
                }
    }
    return m;
}

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
    CHECK(fdt_prepare(xyz, n, 1, &pr, diag, sizeof diag) == FDT_OK, "prepare %s", family_name[fam]);
    uint32_t m = (uint32_t)pr.m;
    fdt_kdtree t;
    CHECK(fdt_kd_build(&t, pr.p, pr.orig, 0, m, leaf) == FDT_OK, "build");
    if (g_sse_only)
        t.avx2 = 0; /* the SSE kernels, which machines without AVX2 run */
    const double *P = pr.p;
    fdt_kdq kq;
    memset(&kq, 0, sizeof kq);

    /* The float blocks (src/kdtree.c): each leaf's block holds its points
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
            CHECK(((uintptr_t)B & 31) == 0, "block of leaf %u not aligned", i);
            for (int k = 0; k < 3; k++)
                for (uint32_t j = 0; j < row; j++) {
                    if (j >= ln) {
                        CHECK(B[k * row + j] == 0.0f, "padding of leaf %u", i);
                        continue;
                    }
                    if (e < -1000 || e > 1000)
                        continue; /* no frame: the tests use the doubles */
                    double x = ldexp(pr.p[3 * (size_t)(nd->begin + j) + k] - nd->lo[k], -e);
                    CHECK(fabs((double)B[k * row + j] - x) <= 0x1p-23,
                          "%s leaf %u point %u axis %d: %.9g against %.17g", family_name[fam], i, j,
                          k, (double)B[k * row + j], x);
                }
        }
    } else {
        CHECK(0, "%s: no float blocks", family_name[fam]);
    }

    /* Tree invariants: every node's box holds its points, leaves are
     * small, children partition the parent's range. */
    for (uint32_t i = 0; i < t.nnodes; i++) {
        const fdt_kdnode *nd = &t.nodes[i];
        for (uint32_t j = nd->begin; j < nd->end; j++)
            for (int k = 0; k < 3; k++)
                CHECK(P[3 * (size_t)j + k] >= nd->lo[k] && P[3 * (size_t)j + k] <= nd->hi[k],
                      "point %u outside node %u box", j, i);
        if (nd->left) {
            CHECK(t.nodes[nd->left].begin == nd->begin && t.nodes[nd->left].end ==
                  t.nodes[nd->left + 1].begin && t.nodes[nd->left + 1].end == nd->end,
                  "node %u children do not partition it", i);
            CHECK(t.nodes[nd->left].hi[nd->dim] <= t.nodes[nd->left + 1].lo[nd->dim],
                  "node %u children overlap on the split axis", i);
        } else {
            CHECK(nd->end - nd->begin <= (uint32_t)leaf, "leaf %u too big", i);
        }
    }
    /* The permutation keeps each point with its input index. */
    for (uint32_t i = 0; i < m; i++)
        for (int k = 0; k < 3; k++)
            CHECK(ldexp(xyz[3 * (size_t)pr.orig[i] + k], pr.scale_exp) == P[3 * (size_t)i + k],
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
        CHECK(nn != id && d == bd, "%s nearest of %u: got %u", family_name[fam], id, nn);
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
                CHECK(seen[j], "%s ball query missed point %u", family_name[fam], j);
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
        CHECK(s.best == want_apex, "%s apex (top-down) of %u %u %u: got %u want %u",
              family_name[fam], a, b, c, s.best, want_apex);
        fdt_apex_init(&s, P + 3 * (size_t)a, P + 3 * (size_t)b, P + 3 * (size_t)c, a, b, c);
        fdt_apex_search_from(&s, &t, (q & 1) ? a : (uint32_t)(rnd() % m), &kq);
        CHECK(s.best == want_apex, "%s apex (bottom-up) of %u %u %u: got %u want %u",
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
            CHECK((viol != FDT_NONE) == brute_viol, "%s any_inside disagrees with brute force",
                  family_name[fam]);
        }
    }

    /* The seed is a perturbed-Delaunay tet (brute-force emptiness) from
     * several starting points. */
    for (int q = 0; q < 5; q++) {
        uint32_t out[4];
        uint32_t start = (uint32_t)(rnd() % m);
        CHECK(fdt_seed_tet(&t, start, out, &kq) == FDT_OK, "%s seed from %u", family_name[fam], start);
        CHECK(fdt_orient3d(P + 3 * (size_t)out[0], P + 3 * (size_t)out[1], P + 3 * (size_t)out[2],
                           P + 3 * (size_t)out[3], NULL) > 0, "seed not positive");
        for (uint32_t j = 0; j < m; j++)
            if (j != out[0] && j != out[1] && j != out[2] && j != out[3])
                CHECK(fdt_insphere_perturbed(P + 3 * (size_t)out[0], P + 3 * (size_t)out[1],
                                             P + 3 * (size_t)out[2], P + 3 * (size_t)out[3],
                                             P + 3 * (size_t)j, NULL) < 0,
                      "%s seed tet holds point %u", family_name[fam], j);
    }
    fdt_kd_free(&t);
    fdt_prepared_free(&pr);
    free(xyz);
}

/* The merge on several threads (src/prepare.c, prepare_threads) gives
 * the one-thread result bit for bit, duplicates and scaling included, and
 * names the same first non-finite point. */
static void test_prepare_threads(void)
{
    const size_t want = 90000;
    double *xyz = malloc(want * 3 * sizeof *xyz);
    for (int fam = 0; fam < NFAMILIES; fam++) {
        size_t n = make_points(fam, want, xyz);
        /* duplicates across slices: copies of points from the whole range */
        for (size_t i = 0; i + 7 < n && n >= 1000; i += 97)
            memcpy(xyz + 3 * i, xyz + 3 * ((i * 7919 + 13) % n), 3 * sizeof *xyz);
        fdt_prepared one, par;
        char diag[256];
        CHECK(fdt_prepare(xyz, n, 1, &one, diag, sizeof diag) == FDT_OK, "prepare %s",
              family_name[fam]);
        for (int T = 2; T <= 8; T += 3) {
            CHECK(fdt_prepare(xyz, n, T, &par, diag, sizeof diag) == FDT_OK, "prepare %s T=%d",
                  family_name[fam], T);
            CHECK(par.m == one.m && par.ndup == one.ndup && par.scale_exp == one.scale_exp &&
                      !memcmp(par.p, one.p, 3 * one.m * sizeof *one.p) &&
                      !memcmp(par.orig, one.orig, one.m * sizeof *one.orig) &&
                      !memcmp(par.dupmap, one.dupmap, n * sizeof *one.dupmap),
                  "%s (%zu points, %zu distinct): %d threads differ", family_name[fam], n, one.m,
                  T);
            fdt_prepared_free(&par);
        }
        if (n >= 80000) {
            /* two bad points in different slices: the first is named */
            double keep[2] = {xyz[3 * 70000 + 1], xyz[3 * 40000 + 2]};
            xyz[3 * 70000 + 1] = NAN;
            xyz[3 * 40000 + 2] = -INFINITY;
            char d1[256], d2[256];
            CHECK(fdt_prepare(xyz, n, 1, &par, d1, sizeof d1) == FDT_ERANGE &&
                      fdt_prepare(xyz, n, 5, &par, d2, sizeof d2) == FDT_ERANGE &&
                      strstr(d1, "point 40000 has a non-finite z") && !strcmp(d1, d2),
                  "non-finite: '%s' against '%s'", d1, d2);
            xyz[3 * 70000 + 1] = keep[0];
            xyz[3 * 40000 + 2] = keep[1];
        }
        fdt_prepared_free(&one);
    }
    free(xyz);
}

static void test_prepare(void)
{
    /* Duplicates merge into the first index, -0 == +0; scaling is a power
     * of two; NaN and Inf are refused with the point named. */
    double xyz[] = {1, 2, 3, 0.0, 0, 0, 1, 2, 3, -0.0, 0, 0, 5, 6, 7, 1, 2, 3};
    fdt_prepared pr;
    char diag[256];
    CHECK(fdt_prepare(xyz, 6, 1, &pr, diag, sizeof diag) == FDT_OK, "prepare dups");
    CHECK(pr.m == 3 && pr.ndup == 3, "distinct %zu dup %zu", pr.m, pr.ndup);
    CHECK(pr.dupmap[2] == 0 && pr.dupmap[3] == 1 && pr.dupmap[5] == 0 && pr.dupmap[4] == 4,
          "duplicate map");
    CHECK(pr.orig[0] == 0 && pr.orig[1] == 1 && pr.orig[2] == 4, "first indices");
    CHECK(ldexp(7.0, pr.scale_exp) == pr.p[8] && ldexp(7.0, pr.scale_exp) < 1.0 &&
          ldexp(7.0, pr.scale_exp) >= 0.5, "scale 2^%d", pr.scale_exp);
    fdt_prepared_free(&pr);
    double big[] = {1e150, 2e150, 3e150, -1e150, 5e149, 1e148};
    CHECK(fdt_prepare(big, 2, 1, &pr, diag, sizeof diag) == FDT_OK && pr.p[0] < 1.0, "scale down 1e150");
    fdt_prepared_free(&pr);
    /* Mixed 1e-300 and 1e300: the scale must keep 1e-300 normal (exact). */
    double mixed[] = {1e300, 0, 0, 1e-300, 0, 0};
    CHECK(fdt_prepare(mixed, 2, 1, &pr, diag, sizeof diag) == FDT_OK, "mixed");
    CHECK(ldexp(pr.p[3], -pr.scale_exp) == 1e-300, "mixed magnitudes not exact");
    fdt_prepared_free(&pr);
    double bad[] = {0, 0, 0, 1, NAN, 2};
    CHECK(fdt_prepare(bad, 2, 1, &pr, diag, sizeof diag) == FDT_ERANGE && strstr(diag, "point 1"),
          "NaN not refused: %s", diag);
    double inf[] = {INFINITY, 0, 0};
    CHECK(fdt_prepare(inf, 1, 1, &pr, diag, sizeof diag) == FDT_ERANGE, "Inf not refused");
    /* Dimension check. */
    double flat[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 2, 3, 0};
    CHECK(fdt_seed_check_dimension(flat, (const fdt_vid[]){0, 1, 2, 3, 4}, 5, diag, sizeof diag) ==
          FDT_EDEGENERATE && strstr(diag, "coplanar"), "coplanar: %s", diag);
    double line[] = {0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3};
    CHECK(fdt_seed_check_dimension(line, (const fdt_vid[]){0, 1, 2, 3}, 4, diag, sizeof diag) ==
          FDT_EDEGENERATE && strstr(diag, "collinear"), "collinear: %s", diag);
    CHECK(fdt_seed_check_dimension(line, (const fdt_vid[]){0, 1, 2}, 3, diag, sizeof diag) ==
          FDT_EDEGENERATE && strstr(diag, "only 3"), "three points: %s", diag);
}

static void test_facetab(void)
{
    /* Insert many faces, find both orientations, remove in random order
     * (backward-shift deletion must keep every other face findable). */
    enum { N = 20000 };
    fdt_facetab ft;
    CHECK(fdt_facetab_init(&ft, 16) == FDT_OK, "init");
    static uint32_t faces[N][3];
    static uint8_t live[N];
    for (int i = 0; i < N; i++) {
        uint32_t a = (uint32_t)(3 * i), b = (uint32_t)(rnd() % 100000 + 300000), c = (uint32_t)(rnd() % 100000 + 500000);
        fdt_face f;
        fdt_face_canon(b, a, c, f.v);
        CHECK(f.v[0] == a && f.v[1] == c && f.v[2] == b, "canon keeps orientation");
        f.aux = 0;
        f.tet = (uint64_t)i;
        int err;
        CHECK(fdt_facetab_find_or_insert(&ft, &f, &err) == NULL && err == 0, "insert %d", i);
        memcpy(faces[i], f.v, sizeof f.v);
        live[i] = 1;
    }
    CHECK(ft.count == N, "count");
    for (int round = 0; round < 3 * N; round++) {
        int i = (int)(rnd() % N);
        uint32_t rev[3] = {faces[i][0], faces[i][2], faces[i][1]};
        fdt_face *s = fdt_facetab_find(&ft, rev);
        CHECK((s != NULL) == live[i], "find %d (live %d)", i, live[i]);
        if (s) {
            CHECK(s->tet == (uint64_t)i && s->v[1] == faces[i][1], "slot content %d", i);
            fdt_facetab_remove(&ft, s);
            live[i] = 0;
        }
    }
    size_t nlive = 0;
    for (int i = 0; i < N; i++) {
        nlive += live[i];
        CHECK((fdt_facetab_find(&ft, faces[i]) != NULL) == live[i], "final find %d", i);
    }
    CHECK(ft.count == nlive, "count after removals");
    fdt_facetab_free(&ft);
}

int main(void)
{
    test_prepare();
    test_prepare_threads();
    test_facetab();
    for (g_sse_only = 0; g_sse_only <= 1; g_sse_only++)
        for (int fam = 0; fam < NFAMILIES; fam++) {
            test_family(fam, 700, 18);
            test_family(fam, 300, 3);
        }
    if (failures) {
        fprintf(stderr, "%d failures\n", failures);
        return 1;
    }
    printf("kdtree, seed, facetab, prepare: all passed\n");
    return 0;
}
