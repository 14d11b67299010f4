/*
 * Tests for src/mesh/check.c (fdt_check).
 *
 * Correct meshes come from a brute-force generator that needs nothing but
 * the predicates: for n <= 40 points, every positively oriented 4-subset
 * whose perturbed circumsphere holds no other point is a tet of THE
 * perturbed Delaunay tetrahedralization, and these are all of them. Its
 * output is cross-checked independently of fdt_check (total volume equals
 * the known hull volume on lattice inputs). Every such mesh must pass,
 * also shuffled, with vertices rotated, with neighbours, and on degenerate
 * inputs (cube corners + center, a 3x3x3 lattice, a quantised random set,
 * duplicates including -0/+0).
 *
 * Then faults are planted and each must be refused with FDT_ECHECK and a
 * message naming the fault: a flipped tet, every single missing tet, a
 * duplicated tet, a 2-3 flip (a valid triangulation that is not Delaunay),
 * wrong / asymmetric / misplaced neighbour links, an unused point, a
 * non-first duplicate id, ids out of range or repeated, a flat tet, a NaN,
 * and meshes that pass every local check but are not a triangulation of
 * the hull: a double (and triple) cover (a star bipyramid winding around
 * its axis), two disjoint tets, two tets sharing only an edge or a vertex.
 */
#include "base/hash.h"
#include "frontdt.h"
#include "geom/predicates.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "testutil.h"


/* ------------------------------------------------------------------------ */
/* Meshes                                                                    */
/* ------------------------------------------------------------------------ */

typedef struct mesh {
    double *xyz;
    size_t n, ncap;
    fdt_vid *tets;
    size_t nt, tcap;
    fdt_tid *nbrs; /* 4 per tet, or NULL */
} mesh;

static void *xrealloc(void *p, size_t sz)
{
    void *q = realloc(p, sz ? sz : 1);
    if (!q) {
        fprintf(stderr, "out of memory\n");
        exit(2);
    }
    return q;
}

static void mesh_free(mesh *m)
{
    free(m->xyz);
    free(m->tets);
    free(m->nbrs);
    memset(m, 0, sizeof *m);
}

static fdt_vid add_point(mesh *m, double x, double y, double z)
{
    if (m->n == m->ncap) {
        m->ncap = m->ncap ? 2 * m->ncap : 16;
        m->xyz = xrealloc(m->xyz, 3 * m->ncap * sizeof *m->xyz);
    }
    m->xyz[3 * m->n] = x;
    m->xyz[3 * m->n + 1] = y;
    m->xyz[3 * m->n + 2] = z;
    return (fdt_vid)m->n++;
}

static const double *P(const mesh *m, fdt_vid v)
{
    return m->xyz + 3 * (size_t)v;
}

static int orient(const mesh *m, fdt_vid a, fdt_vid b, fdt_vid c, fdt_vid d)
{
    return fdt_orient3d(P(m, a), P(m, b), P(m, c), P(m, d), NULL);
}

/* Appends tet (a b c d), swapping c and d if needed to orient it. Drops the
 * neighbours (they no longer match). */
static void add_tet(mesh *m, fdt_vid a, fdt_vid b, fdt_vid c, fdt_vid d)
{
    if (orient(m, a, b, c, d) < 0) {
        fdt_vid x = c;
        c = d;
        d = x;
    }
    if (m->nt == m->tcap) {
        m->tcap = m->tcap ? 2 * m->tcap : 16;
        m->tets = xrealloc(m->tets, 4 * m->tcap * sizeof *m->tets);
    }
    fdt_vid *t = m->tets + 4 * m->nt++;
    t[0] = a;
    t[1] = b;
    t[2] = c;
    t[3] = d;
    free(m->nbrs);
    m->nbrs = NULL;
}

static void remove_tet(mesh *m, size_t k)
{
    memmove(m->tets + 4 * k, m->tets + 4 * (k + 1),
            4 * (m->nt - k - 1) * sizeof *m->tets);
    m->nt--;
    free(m->nbrs);
    m->nbrs = NULL;
}

static mesh mesh_clone(const mesh *m)
{
    mesh c;
    memset(&c, 0, sizeof c);
    c.n = c.ncap = m->n;
    c.nt = c.tcap = m->nt;
    c.xyz = xrealloc(NULL, 3 * m->n * sizeof *c.xyz);
    memcpy(c.xyz, m->xyz, 3 * m->n * sizeof *c.xyz);
    c.tets = xrealloc(NULL, 4 * m->nt * sizeof *c.tets);
    memcpy(c.tets, m->tets, 4 * m->nt * sizeof *c.tets);
    if (m->nbrs) {
        c.nbrs = xrealloc(NULL, 4 * m->nt * sizeof *c.nbrs);
        memcpy(c.nbrs, m->nbrs, 4 * m->nt * sizeof *c.nbrs);
    }
    return c;
}

/* Point i is the first with its coordinates (== treats -0 as +0). */
static int is_first(const mesh *m, fdt_vid i)
{
    for (fdt_vid j = 0; j < i; j++) {
        if (P(m, j)[0] == P(m, i)[0] && P(m, j)[1] == P(m, i)[1] &&
            P(m, j)[2] == P(m, i)[2])
            return 0;
    }
    return 1;
}

/* The perturbed Delaunay tetrahedralization by exhaustion (small n). */
static void brute_dt(mesh *m)
{
    m->nt = 0;
    fdt_vid n = (fdt_vid)m->n;
    char *first = xrealloc(NULL, (size_t)n);
    for (fdt_vid i = 0; i < n; i++)
        first[i] = (char)is_first(m, i);
    for (fdt_vid a = 0; a < n; a++) {
        for (fdt_vid b = a + 1; b < n; b++) {
            for (fdt_vid c = b + 1; c < n; c++) {
                for (fdt_vid d = c + 1; d < n; d++) {
                    if (!first[a] || !first[b] || !first[c] || !first[d])
                        continue;
                    int o = orient(m, a, b, c, d);
                    if (o == 0)
                        continue;
                    /* Swap the last two if needed: positive order. */
                    fdt_vid v[4] = {a, b, o > 0 ? c : d, o > 0 ? d : c};
                    int empty = 1;
                    for (fdt_vid e = 0; e < n && empty; e++) {
                        if (!first[e] || e == a || e == b || e == c || e == d)
                            continue;
                        if (fdt_insphere_perturbed(P(m, v[0]), P(m, v[1]),
                                                   P(m, v[2]), P(m, v[3]),
                                                   P(m, e), NULL) > 0)
                            empty = 0;
                    }
                    if (empty)
                        add_tet(m, v[0], v[1], v[2], v[3]);
                }
            }
        }
    }
    free(first);
}

static int same_face(const fdt_vid *t, int i, const fdt_vid *u, int j)
{
    int hits = 0;
    for (int p = 0; p < 4; p++) {
        if (p == i)
            continue;
        for (int q = 0; q < 4; q++) {
            if (q != j && t[p] == u[q])
                hits++;
        }
    }
    return hits == 3;
}

/* Neighbours by exhaustion: nbrs[4t+i] = the tet sharing t's face
 * opposite vertex i, -1 if none. */
static void brute_nbrs(mesh *m)
{
    free(m->nbrs);
    m->nbrs = xrealloc(NULL, 4 * m->nt * sizeof *m->nbrs);
    for (size_t t = 0; t < m->nt; t++) {
        for (int i = 0; i < 4; i++) {
            fdt_tid nb = -1;
            for (size_t u = 0; u < m->nt && nb < 0; u++) {
                for (int j = 0; j < 4 && u != t; j++) {
                    if (same_face(m->tets + 4 * t, i, m->tets + 4 * u, j))
                        nb = (fdt_tid)u;
                }
            }
            m->nbrs[4 * t + i] = nb;
        }
    }
}

/* 6 * total volume, in doubles: exact for small integer coordinates. */
static double six_volume(const mesh *m)
{
    double s = 0;
    for (size_t t = 0; t < m->nt; t++) {
        const double *a = P(m, m->tets[4 * t]), *b = P(m, m->tets[4 * t + 1]);
        const double *c = P(m, m->tets[4 * t + 2]);
        const double *d = P(m, m->tets[4 * t + 3]);
        double u[3], v[3], w[3];
        for (int k = 0; k < 3; k++) {
            u[k] = b[k] - a[k];
            v[k] = c[k] - a[k];
            w[k] = d[k] - a[k];
        }
        s += u[0] * (v[1] * w[2] - v[2] * w[1]) -
             u[1] * (v[0] * w[2] - v[2] * w[0]) +
             u[2] * (v[0] * w[1] - v[1] * w[0]);
    }
    return s;
}

/* ------------------------------------------------------------------------ */
/* Expectations                                                              */
/* ------------------------------------------------------------------------ */

static char msgbuf[1024];

static int run(const mesh *m, int with_nbrs)
{
    msgbuf[0] = 'X'; /* must be overwritten */
    msgbuf[1] = '\0';
    return fdt_check(m->xyz, m->n, m->tets, m->nt,
                     with_nbrs ? m->nbrs : NULL, msgbuf, sizeof msgbuf);
}

static void expect_ok(const char *what, const mesh *m)
{
    int rc = run(m, 0);
    if (rc != 0)
        fprintf(stderr, "%s: refused: %s\n", what, msgbuf);
    EXPECT(rc == 0);
    EXPECT(msgbuf[0] == '\0');
    if (m->nbrs) {
        rc = run(m, 1);
        if (rc != 0)
            fprintf(stderr, "%s (with neighbours): refused: %s\n", what,
                    msgbuf);
        EXPECT(rc == 0);
    }
}

/* Expects FDT_ECHECK with `want` in the message (nbrs used if present). */
static void expect_fail(const char *what, const mesh *m, const char *want)
{
    int rc = run(m, m->nbrs != NULL);
    if (rc != FDT_ECHECK || !strstr(msgbuf, want))
        fprintf(stderr, "%s: expected FDT_ECHECK with \"%s\", got %d: %s\n",
                what, want, rc, msgbuf);
    EXPECT(rc == FDT_ECHECK);
    EXPECT(strstr(msgbuf, want) != NULL);
}

/* ------------------------------------------------------------------------ */
/* Random numbers (deterministic)                                            */
/* ------------------------------------------------------------------------ */

static uint64_t rng_state;

static uint64_t rng_next(void)
{
    return fdt_splitmix64(&rng_state);
}

static double rng_unit(void)
{
    return (double)(rng_next() >> 11) * (1.0 / 9007199254740992.0);
}

static size_t rng_below(size_t k)
{
    return (size_t)(rng_next() % k);
}

/* ------------------------------------------------------------------------ */
/* Faults                                                                    */
/* ------------------------------------------------------------------------ */

/*
 * 2-3 flip: an interior face (a b c) between tets with apexes d and e,
 * where segment de crosses the open triangle abc, is replaced by the three
 * tets around de. The result is a valid triangulation of the same points,
 * and not the Delaunay one. Returns 0 if no face allows it.
 */
static int flip23(mesh *m)
{
    brute_nbrs(m);
    for (size_t t = 0; t < m->nt; t++) {
        for (int i = 0; i < 4; i++) {
            fdt_tid u = m->nbrs[4 * t + i];
            if (u < 0)
                continue;
            const fdt_vid *tv = m->tets + 4 * t, *uv = m->tets + 4 * u;
            fdt_vid d = tv[i], e = -1, f[3];
            int k = 0;
            for (int j = 0; j < 4; j++) {
                if (j != i)
                    f[k++] = tv[j];
            }
            for (int j = 0; j < 4; j++) {
                if (uv[j] != f[0] && uv[j] != f[1] && uv[j] != f[2])
                    e = uv[j];
            }
            int s0 = orient(m, d, e, f[0], f[1]);
            int s1 = orient(m, d, e, f[1], f[2]);
            int s2 = orient(m, d, e, f[2], f[0]);
            if (s0 == 0 || s0 != s1 || s1 != s2)
                continue;
            size_t hi = t > (size_t)u ? t : (size_t)u;
            size_t lo = t > (size_t)u ? (size_t)u : t;
            remove_tet(m, hi);
            remove_tet(m, lo);
            add_tet(m, d, e, f[0], f[1]);
            add_tet(m, d, e, f[1], f[2]);
            add_tet(m, d, e, f[2], f[0]);
            return 1;
        }
    }
    return 0;
}

/* Shuffles tet order and rotates each tet's vertices by an even
 * permutation (orientation kept); renumbers neighbours to match. */
static void shuffle(mesh *m)
{
    brute_nbrs(m);
    size_t nt = m->nt;
    size_t *perm = xrealloc(NULL, nt * sizeof *perm); /* new -> old */
    size_t *inv = xrealloc(NULL, nt * sizeof *inv);
    for (size_t i = 0; i < nt; i++)
        perm[i] = i;
    for (size_t i = nt; i > 1; i--) {
        size_t j = rng_below(i), x = perm[i - 1];
        perm[i - 1] = perm[j];
        perm[j] = x;
    }
    for (size_t i = 0; i < nt; i++)
        inv[perm[i]] = i;
    /* Even permutations of positions: identity, three 3-cycles fixing 3,
     * and the double transpositions. */
    static const int rot[6][4] = {{0, 1, 2, 3}, {1, 2, 0, 3}, {2, 0, 1, 3},
                                  {1, 0, 3, 2}, {2, 3, 0, 1}, {3, 2, 1, 0}};
    fdt_vid *tets = xrealloc(NULL, 4 * nt * sizeof *tets);
    fdt_tid *nbrs = xrealloc(NULL, 4 * nt * sizeof *nbrs);
    for (size_t i = 0; i < nt; i++) {
        const int *r = rot[rng_below(6)];
        for (int k = 0; k < 4; k++) {
            tets[4 * i + k] = m->tets[4 * perm[i] + r[k]];
            fdt_tid nb = m->nbrs[4 * perm[i] + r[k]];
            nbrs[4 * i + k] = nb < 0 ? -1 : (fdt_tid)inv[nb];
        }
    }
    free(m->tets);
    free(m->nbrs);
    m->tets = tets;
    m->nbrs = nbrs;
    m->tcap = nt;
    free(perm);
    free(inv);
}

/* A tet with one hull face and one interior face (as an index k, face i). */
static int find_faces(const mesh *m, size_t *th, int *ih, size_t *ti, int *ii)
{
    int gh = 0, gi = 0;
    for (size_t t = 0; t < m->nt; t++) {
        for (int i = 0; i < 4; i++) {
            if (m->nbrs[4 * t + i] < 0 && !gh) {
                *th = t;
                *ih = i;
                gh = 1;
            }
            if (m->nbrs[4 * t + i] >= 0 && !gi) {
                *ti = t;
                *ii = i;
                gi = 1;
            }
        }
    }
    return gh && gi;
}

static int flips_done;

/* Runs every fault that applies to a correct mesh m (with >= 2 tets). */
static void faults(const char *name, const mesh *m0)
{
    char what[256];
    mesh m = mesh_clone(m0);
    brute_nbrs(&m);

    /* A flipped tet. */
    for (size_t k = 0; k < m.nt; k += 1 + m.nt / 5) {
        mesh f = mesh_clone(&m);
        fdt_vid x = f.tets[4 * k];
        f.tets[4 * k] = f.tets[4 * k + 1];
        f.tets[4 * k + 1] = x;
        snprintf(what, sizeof what, "%s: tet %zu flipped", name, k);
        expect_fail(what, &f, "not positively oriented");
        mesh_free(&f);
    }
    /* Every missing tet. */
    for (size_t k = 0; k < m.nt; k++) {
        mesh f = mesh_clone(&m);
        remove_tet(&f, k);
        snprintf(what, sizeof what, "%s: tet %zu missing", name, k);
        expect_fail(what, &f, "");
        EXPECT(strlen(msgbuf) > 10);
        mesh_free(&f);
    }
    /* A duplicated tet, listed again with its vertices rotated. */
    {
        mesh f = mesh_clone(&m);
        size_t k = f.nt / 2;
        fdt_vid *t = f.tets + 4 * k;
        add_tet(&f, t[1], t[2], t[0], t[3]);
        snprintf(what, sizeof what, "%s: tet %zu duplicated", name, k);
        expect_fail(what, &f, "listed twice");
        mesh_free(&f);
    }
    /* A 2-3 flip: valid, not Delaunay. */
    {
        mesh f = mesh_clone(&m);
        if (flip23(&f)) {
            flips_done++;
            snprintf(what, sizeof what, "%s: 2-3 flip", name);
            expect_fail(what, &f, "is not Delaunay");
            brute_nbrs(&f);
            expect_fail(what, &f, "is not Delaunay");
        }
        mesh_free(&f);
    }
    /* Neighbour links. */
    size_t th = 0, ti = 0;
    int ih = 0, ii = 0;
    if (find_faces(&m, &th, &ih, &ti, &ii)) {
        mesh f = mesh_clone(&m);
        fdt_tid right = f.nbrs[4 * ti + ii];
        /* Another tet (maybe ti itself: a self-link is wrong too). */
        f.nbrs[4 * ti + ii] = (fdt_tid)((size_t)(right + 1) % f.nt);
        snprintf(what, sizeof what, "%s: wrong interior link", name);
        expect_fail(what, &f, "neighbour");
        /* The link is correct one way only. */
        f.nbrs[4 * ti + ii] = right;
        for (int j = 0; j < 4; j++) {
            if (f.nbrs[4 * right + j] == (fdt_tid)ti)
                f.nbrs[4 * right + j] = -1;
        }
        snprintf(what, sizeof what, "%s: one-way link", name);
        expect_fail(what, &f, "neighbour");
        mesh_free(&f);

        f = mesh_clone(&m);
        f.nbrs[4 * th + ih] = (fdt_tid)th;
        snprintf(what, sizeof what, "%s: hull face linked", name);
        expect_fail(what, &f, "expected -1");
        f.nbrs[4 * th + ih] = (fdt_tid)f.nt; /* out of range */
        expect_fail(what, &f, "expected -1");
        mesh_free(&f);

        /* Links right but stored under the wrong face index. */
        f = mesh_clone(&m);
        fdt_tid *nb = f.nbrs + 4 * ti;
        fdt_tid x = nb[ii];
        nb[ii] = nb[(ii + 1) % 4];
        nb[(ii + 1) % 4] = x;
        snprintf(what, sizeof what, "%s: links under swapped faces", name);
        if (nb[ii] != nb[(ii + 1) % 4])
            expect_fail(what, &f, "neighbour");
        mesh_free(&f);
    }
    /* An unused point: a copy of a vertex nudged toward tet 0's centroid
     * (inside the hull, not a duplicate). */
    {
        mesh f = mesh_clone(&m);
        double c[3] = {0, 0, 0};
        for (int k = 0; k < 4; k++) {
            for (int j = 0; j < 3; j++)
                c[j] += 0.25 * P(&f, f.tets[k])[j];
        }
        add_point(&f, c[0], c[1], c[2]);
        snprintf(what, sizeof what, "%s: unused point", name);
        expect_fail(what, &f, "is not a vertex of any tet");
        mesh_free(&f);
    }
    /* A duplicate point at the end: fine unused, refused when referenced. */
    {
        mesh f = mesh_clone(&m);
        fdt_vid v = f.tets[4 * (f.nt - 1) + 2];
        double q[3];
        for (int j = 0; j < 3; j++)
            q[j] = P(&f, v)[j] == 0 ? -0.0 : P(&f, v)[j];
        fdt_vid w = add_point(&f, q[0], q[1], q[2]);
        snprintf(what, sizeof what, "%s: unused duplicate point", name);
        expect_ok(what, &f);
        for (size_t k = 0; k < 4 * f.nt; k++) {
            if (f.tets[k] == v)
                f.tets[k] = w;
        }
        char want[64];
        snprintf(want, sizeof want, "a duplicate of point %ld", (long)v);
        snprintf(what, sizeof what, "%s: non-first duplicate used", name);
        expect_fail(what, &f, want);
        mesh_free(&f);
    }
    /* Ids out of range, repeated. */
    {
        mesh f = mesh_clone(&m);
        f.tets[4 * (f.nt - 1) + 3] = (fdt_vid)f.n;
        snprintf(what, sizeof what, "%s: id out of range", name);
        expect_fail(what, &f, "out of range");
        f.tets[4 * (f.nt - 1) + 3] = -1;
        expect_fail(what, &f, "out of range");
        f.tets[4 * (f.nt - 1) + 3] = f.tets[4 * (f.nt - 1)];
        snprintf(what, sizeof what, "%s: repeated id", name);
        expect_fail(what, &f, "repeats vertex");
        mesh_free(&f);
    }
    mesh_free(&m);
}

/* Brute force, then: passes as is, shuffled, with neighbours; faults. */
static void full(const char *name, mesh *m)
{
    brute_dt(m);
    EXPECT(m->nt > 0);
    expect_ok(name, m);
    brute_nbrs(m);
    expect_ok(name, m);
    mesh s = mesh_clone(m);
    shuffle(&s);
    expect_ok(name, &s);
    mesh_free(&s);
    faults(name, m);
}

/* ------------------------------------------------------------------------ */
/* Tests                                                                     */
/* ------------------------------------------------------------------------ */

static void test_args(void)
{
    double xyz[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    fdt_vid tet[4] = {0, 1, 2, 3};
    char msg[64];
    EXPECT(fdt_check(xyz, 4, tet, 1, NULL, msg, sizeof msg) == 0);
    EXPECT(fdt_check(xyz, 4, tet, 1, NULL, NULL, 0) == 0);
    EXPECT(fdt_check(NULL, 4, tet, 1, NULL, msg, sizeof msg) == FDT_EINVAL);
    EXPECT(fdt_check(xyz, 4, NULL, 1, NULL, msg, sizeof msg) == FDT_EINVAL);
    /* n beyond the id type: refused before xyz is read. */
    EXPECT(fdt_check(xyz, (size_t)FDT_VID_MAX + 1, tet, 1, NULL, msg,
                    sizeof msg) == FDT_EINVAL);
    EXPECT(fdt_check(xyz, 4, tet, SIZE_MAX / 2, NULL, msg, sizeof msg) ==
          FDT_EINVAL);
    EXPECT(fdt_check(xyz, 4, tet, 0, NULL, msg, sizeof msg) == FDT_ECHECK);
    EXPECT(strcmp(msg, "no tetrahedra") == 0);
    EXPECT(fdt_check(NULL, 0, NULL, 0, NULL, msg, sizeof msg) == FDT_ECHECK);
    EXPECT(fdt_check(NULL, 0, tet, 1, NULL, msg, sizeof msg) == FDT_ECHECK);
    EXPECT(strstr(msg, "out of range") != NULL);

    /* The message is truncated and NUL-terminated; no write past len. */
    char small[8];
    memset(small, '#', sizeof small);
    fdt_vid flipped[4] = {1, 0, 2, 3};
    EXPECT(fdt_check(xyz, 4, flipped, 1, NULL, small, 5) == FDT_ECHECK);
    EXPECT(strlen(small) == 4 && small[5] == '#');
    EXPECT(fdt_check(xyz, 4, flipped, 1, NULL, msg, sizeof msg) == FDT_ECHECK);
    EXPECT(strcmp(msg, "tet 0 (1 0 2 3) is not positively oriented") == 0);

    /* A single tet with neighbours: all hull. */
    fdt_tid nb[4] = {-1, -1, -1, -1};
    EXPECT(fdt_check(xyz, 4, tet, 1, nb, msg, sizeof msg) == 0);
    nb[2] = 0;
    EXPECT(fdt_check(xyz, 4, tet, 1, nb, msg, sizeof msg) == FDT_ECHECK);

    /* A flat tet; a NaN. */
    double flat[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
    EXPECT(fdt_check(flat, 4, tet, 1, NULL, msg, sizeof msg) == FDT_ECHECK);
    EXPECT(strstr(msg, "flat") != NULL);
    double bad[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, NAN};
    EXPECT(fdt_check(bad, 4, tet, 1, NULL, msg, sizeof msg) == FDT_ECHECK);
    EXPECT(strstr(msg, "non-finite") != NULL);
    bad[11] = INFINITY;
    EXPECT(fdt_check(bad, 4, tet, 1, NULL, msg, sizeof msg) == FDT_ECHECK);
}

/* Five points: triangle abc with apexes d above and e below, segment de
 * through the triangle. Tall apexes: the Delaunay mesh is the 2 tets on
 * abc; flat ones: the 3 tets around de. The other one is valid and must be
 * refused as not Delaunay. */
static void test_five_points(void)
{
    for (int tall = 0; tall < 2; tall++) {
        double h = tall ? 3.0 : 0.125;
        mesh m;
        memset(&m, 0, sizeof m);
        add_point(&m, 0, 0, 0);
        add_point(&m, 4, 0, 0);
        add_point(&m, 0, 4, 0);
        add_point(&m, 1, 1, h);
        add_point(&m, 1, 1, -h);
        brute_dt(&m);
        EXPECT(m.nt == (tall ? 2u : 3u));
        EXPECT(six_volume(&m) == 32 * h); /* 6 * (8 * 2h / 3) */
        expect_ok(tall ? "five tall" : "five flat", &m);
        mesh o;
        memset(&o, 0, sizeof o);
        for (size_t i = 0; i < m.n; i++)
            add_point(&o, m.xyz[3 * i], m.xyz[3 * i + 1], m.xyz[3 * i + 2]);
        if (tall) {
            add_tet(&o, 3, 4, 0, 1);
            add_tet(&o, 3, 4, 1, 2);
            add_tet(&o, 3, 4, 2, 0);
        } else {
            add_tet(&o, 0, 1, 2, 3);
            add_tet(&o, 0, 1, 2, 4);
        }
        expect_fail("five, other triangulation", &o, "is not Delaunay");
        brute_nbrs(&o);
        expect_fail("five, other triangulation", &o, "is not Delaunay");
        full(tall ? "five tall" : "five flat", &m);
        mesh_free(&m);
        mesh_free(&o);
    }
}

/* Cube corners (cospherical) and the center: 12 tets, 2 per cube face. */
static void test_cube_center(void)
{
    mesh m;
    memset(&m, 0, sizeof m);
    for (int i = 0; i < 8; i++)
        add_point(&m, i & 1, (i >> 1) & 1, (i >> 2) & 1);
    add_point(&m, 0.5, 0.5, 0.5);
    brute_dt(&m);
    EXPECT(m.nt == 12);
    EXPECT(six_volume(&m) == 6);
    full("cube+center", &m);
    mesh_free(&m);

    /* Corners only: the perturbation picks one of the cube's 74 ways. */
    memset(&m, 0, sizeof m);
    for (int i = 0; i < 8; i++)
        add_point(&m, i & 1, (i >> 1) & 1, (i >> 2) & 1);
    brute_dt(&m);
    EXPECT(m.nt == 5 || m.nt == 6);
    EXPECT(six_volume(&m) == 6);
    full("cube", &m);
    mesh_free(&m);
}

static void test_lattice(void)
{
    mesh m;
    memset(&m, 0, sizeof m);
    for (int i = 0; i < 27; i++)
        add_point(&m, i % 3, (i / 3) % 3, i / 9);
    brute_dt(&m);
    EXPECT(six_volume(&m) == 48);
    full("lattice 3x3x3", &m);
    mesh_free(&m);

    /* The same lattice listed in another order, with -0 and duplicates. */
    memset(&m, 0, sizeof m);
    for (int i = 26; i >= 0; i--) {
        double x = i % 3, y = (i / 3) % 3, z = i / 9;
        add_point(&m, x ? x : -0.0, y, z);
        if (i % 7 == 0)
            add_point(&m, x, y ? y : -0.0, z);
    }
    brute_dt(&m);
    EXPECT(six_volume(&m) == 48);
    full("lattice 3x3x3 with duplicates", &m);
    mesh_free(&m);
}

static void test_random(void)
{
    for (int seed = 1; seed <= 8; seed++) {
        rng_state = (uint64_t)seed * 7919u;
        mesh m;
        memset(&m, 0, sizeof m);
        size_t n = 14 + 3 * (size_t)seed;
        char name[64];
        if (seed % 2) {
            for (size_t i = 0; i < n; i++)
                add_point(&m, rng_unit(), rng_unit(), rng_unit());
            snprintf(name, sizeof name, "random %zu (seed %d)", n, seed);
        } else {
            /* Quantised: many coplanar and cospherical subsets, and
             * duplicates. */
            for (size_t i = 0; i < n; i++)
                add_point(&m, (double)rng_below(4), (double)rng_below(4),
                          (double)rng_below(3) * 0.5);
            snprintf(name, sizeof name, "quantised %zu (seed %d)", n, seed);
        }
        full(name, &m);
        mesh_free(&m);
    }
    /* Far from the origin, tiny extent: the filter cannot decide. */
    rng_state = 99;
    mesh m;
    memset(&m, 0, sizeof m);
    for (int i = 0; i < 24; i++)
        add_point(&m, 4.9e6 + (double)rng_below(64) * 0.25,
                  3.1e6 + (double)rng_below(64) * 0.25,
                  1.0e3 + (double)rng_below(8) * 0.25);
    full("far and quantised", &m);
    mesh_free(&m);
    EXPECT(flips_done >= 6);
}

/*
 * A star bipyramid: poles N, S at height +-h (h < 1), m equator points on
 * the unit circle, tets (N S p_k p_{k+s}) for k stepping by s around the
 * circle (gcd(s, m) = 1). For s > 1 the tets wind s times around the axis.
 * Every local check passes: each interior face (N S p) is in two tets on
 * opposite sides, the hull (N p_k p_{k+s}), (S p_{k+s} p_k) is closed and
 * convex at each edge, every interior face is locally Delaunay (h < 1), and
 * every point is used. Only the winding of the hull gives it away.
 */
static void star(mesh *m, int np, int s, double h)
{
    memset(m, 0, sizeof *m);
    const double pi = 3.14159265358979323846;
    fdt_vid N = add_point(m, 0, 0, h), S = add_point(m, 0, 0, -h);
    for (int k = 0; k < np; k++)
        add_point(m, cos(2 * pi * k / np), sin(2 * pi * k / np), 0);
    for (int k = 0; k < np; k++) {
        int i = (k * s) % np, j = (k * s + s) % np;
        add_tet(m, N, S, 2 + i, 2 + j);
    }
}

static void test_covers(void)
{
    mesh m;
    star(&m, 5, 1, 0.5);
    expect_ok("star 5/1 (a plain bipyramid)", &m);
    mesh_free(&m);

    star(&m, 5, 2, 0.5);
    expect_fail("star 5/2", &m, "winds 2 times");
    brute_nbrs(&m);
    expect_fail("star 5/2 with neighbours", &m, "winds 2 times");
    mesh_free(&m);

    star(&m, 7, 3, 0.5);
    expect_fail("star 7/3", &m, "winds 3 times");
    mesh_free(&m);

    star(&m, 7, 2, 0.25);
    expect_fail("star 7/2", &m, "winds 2 times");
    mesh_free(&m);

    /* Two disjoint tets; two sharing only an edge; only a vertex. */
    static const double q[3][4][3] = {
        {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
        {{5, 5, 5}, {6, 5, 5}, {5, 6, 5}, {5, 5, 6}},
        {{0, 0, 0}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}},
    };
    memset(&m, 0, sizeof m);
    for (int k = 0; k < 2; k++) {
        for (int i = 0; i < 4; i++)
            add_point(&m, q[k][i][0], q[k][i][1], q[k][i][2]);
    }
    add_tet(&m, 0, 1, 2, 3);
    add_tet(&m, 4, 5, 6, 7);
    expect_fail("two disjoint tets", &m, "hull is not convex");
    mesh_free(&m);

    memset(&m, 0, sizeof m);
    for (int i = 0; i < 4; i++)
        add_point(&m, q[0][i][0], q[0][i][1], q[0][i][2]);
    add_point(&m, 0, -1, 0);
    add_point(&m, 0, 0, -1);
    add_tet(&m, 0, 1, 2, 3);
    add_tet(&m, 0, 1, 4, 5); /* shares edge 0-1 only */
    expect_fail("two tets sharing an edge", &m, "in 4 hull faces");
    mesh_free(&m);

    memset(&m, 0, sizeof m);
    for (int k = 0; k < 3; k += 2) {
        for (int i = k ? 1 : 0; i < 4; i++)
            add_point(&m, q[k][i][0], q[k][i][1], q[k][i][2]);
    }
    add_tet(&m, 0, 1, 2, 3);
    add_tet(&m, 0, 4, 5, 6); /* shares vertex 0 only */
    expect_fail("two tets sharing a vertex", &m, "hull is not convex");
    mesh_free(&m);
}

/* Tets overlapping across a shared face, and a face in three tets. */
static void test_overlaps(void)
{
    mesh m;
    memset(&m, 0, sizeof m);
    add_point(&m, 0, 0, 0);
    add_point(&m, 4, 0, 0);
    add_point(&m, 0, 4, 0);
    add_point(&m, 1, 1, 1);
    add_point(&m, 1, 1, 2);
    add_point(&m, 1, 1, -1);
    add_tet(&m, 0, 1, 2, 3);
    add_tet(&m, 0, 1, 2, 4); /* 3 and 4 both above face 0 1 2 */
    add_tet(&m, 0, 1, 2, 5);
    expect_fail("face in three tets", &m, "face (0 1 2) is in 3 tets");
    remove_tet(&m, 2);
    m.n = 5; /* drop point 5, now unused */
    expect_fail("overlapping tets", &m, "on the same side");
    brute_nbrs(&m);
    expect_fail("overlapping tets with neighbours", &m, "on the same side");
    mesh_free(&m);
}

int main(void)
{
    test_args();
    test_five_points();
    test_cube_center();
    test_lattice();
    test_random();
    test_covers();
    test_overlaps();
    return test_report("test_check");
}
