/*
 * Tests of the incremental-insertion kernel (src/mesh/insert.c).
 *
 * For every family of tests/gen_points at a small size and for hand-built
 * nasty sets (integer lattice, rotated lattice, exact cylinder, cube
 * corners and face centres, a 2-D grid on two planes, mixed magnitudes),
 * the points go through the library's preparation (merge, scaling) and
 * kd-tree order, as the engine's partitions have them; then:
 *   - the kernel's finite tet set equals the serial advancing front's
 *     (fdt_front_serial: the CGAL-identical reference), and its hull faces
 *     (finite faces next to infinite tets, outward) equal the front's;
 *   - structure: adjacency symmetric and over the same face, every finite
 *     tet positively oriented, every infinite tet's hull face with its
 *     finite tet inside, the perturbed Delaunay condition across every
 *     face (hull faces included, with the coplanar rule), every point a
 *     vertex of its incident tet, fdt_check's independent verdict;
 *   - fdt_ins_find_face agrees with fdt_ins_across on both orientations of
 *     every finite face, and refuses non-faces and foreign vertices;
 *   - the same tets from a shuffled copy (long walks, no spatial order)
 *     and from a sub-range [base, base + n) of a bigger array;
 *   - refusals: fewer than 4 points, collinear and coplanar sets
 *     (FDT_EDEGENERATE), a duplicate point (FDT_EINVAL), each leaving the
 *     structure empty.
 * With --parallel: fdt_ins_build_parallel gives fdt_ins_build's tets and
 * hull faces on the issue-16 families and the lattices, at 1, 2, 3, 5 and
 * 8 threads (oversubscribed on small machines), several runs each, with
 * the structure checks; and its refusals (coplanar, duplicates in either
 * phase) leave the structure empty.
 *
 * Usage: test_insert GEN_POINTS          the default suite
 *        test_insert --parallel GEN_POINTS  the parallel build's tests
 *        test_insert --time FILE.xyz [R [T]] time fdt_ins_build alone (R
 *                                        runs; medians of wall and CPU
 *                                        time) and print a SUMMARY line;
 *                                        T > 0: fdt_ins_build_parallel on
 *                                        T threads (CPU: all threads)
 */
#include <inttypes.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "frontdt.h"
#include "front/front.h"
#include "mesh/insert.h"
#include "mesh/insert_impl.h"
#include "geom/kdtree.h"
#include "geom/predicates.h"
#include "geom/prepare.h"
#include "front/seed.h"

#include "testutil.h"

/* ---- inputs -------------------------------------------------------------- */

typedef struct pts {
    char name[64];
    double *xyz;
    size_t n;
} pts;

static pts pts_alloc(const char *name, size_t n)
{
    pts p;
    snprintf(p.name, sizeof p.name, "%s", name);
    p.n = n;
    p.xyz = malloc((n ? n : 1) * 3 * sizeof *p.xyz);
    CHECK(p.xyz);
    return p;
}

static uint64_t rng_s = 0x2545F4914F6CDD1DULL;
static uint64_t rnext(void)
{
    return test_rand64(&rng_s);
}

static pts gen_family(const char *gen, const char *fam, size_t n, int seed)
{
    char name[64];
    snprintf(name, sizeof name, "%s-%zu", fam, n);
    pts p = pts_alloc(name, 1);
    free(p.xyz);
    p.xyz = test_gen_family(gen, fam, n, seed, &p.n);
    return p;
}

static pts lattice(int s, const char *name)
{
    pts p = pts_alloc(name, (size_t)s * s * s);
    size_t k = 0;
    for (int x = 0; x < s; x++)
        for (int y = 0; y < s; y++)
            for (int z = 0; z < s; z++) {
                p.xyz[k++] = x;
                p.xyz[k++] = y;
                p.xyz[k++] = z;
            }
    return p;
}

/* A lattice turned by a rotation with floating coefficients: nearly
 * cospherical everywhere, rarely exactly. */
static pts rotated_lattice(int s)
{
    pts p = lattice(s, "rotated-lattice");
    const double a = 0.3, b = 0.7;
    const double R[3][3] = {{cos(a), -sin(a) * cos(b), sin(a) * sin(b)},
                            {sin(a), cos(a) * cos(b), -cos(a) * sin(b)},
                            {0.0, sin(b), cos(b)}};
    for (size_t i = 0; i < p.n; i++) {
        double q[3] = {p.xyz[3 * i], p.xyz[3 * i + 1], p.xyz[3 * i + 2]};
        for (int r = 0; r < 3; r++)
            p.xyz[3 * i + r] = R[r][0] * q[0] + R[r][1] * q[1] + R[r][2] * q[2];
    }
    return p;
}

/* Every integer (x, y) with x^2 + y^2 = 65^2 (36 points on a circle) at
 * several heights: exactly on a cylinder, so every two rings lie on one
 * sphere (massively cospherical). */
static pts cylinder(int levels)
{
    size_t cnt = 0;
    int xs[200], ys[200];
    for (int x = -65; x <= 65; x++)
        for (int y = -65; y <= 65; y++)
            if (x * x + y * y == 65 * 65) {
                xs[cnt] = x;
                ys[cnt] = y;
                cnt++;
            }
    pts p = pts_alloc("cylinder", cnt * (size_t)levels);
    size_t k = 0;
    for (int z = 0; z < levels; z++)
        for (size_t i = 0; i < cnt; i++) {
            p.xyz[k++] = xs[i];
            p.xyz[k++] = ys[i];
            p.xyz[k++] = 7.0 * z;
        }
    return p;
}

/* A cube's 8 corners and its 6 face centres. */
static pts cube_faces(void)
{
    pts p = pts_alloc("cube+centres", 14);
    size_t k = 0;
    for (int i = 0; i < 8; i++) {
        p.xyz[k++] = i & 1 ? 2 : 0;
        p.xyz[k++] = i & 2 ? 2 : 0;
        p.xyz[k++] = i & 4 ? 2 : 0;
    }
    for (int ax = 0; ax < 3; ax++)
        for (int side = 0; side < 2; side++) {
            double c[3] = {1, 1, 1};
            c[ax] = 2.0 * side;
            for (int j = 0; j < 3; j++)
                p.xyz[k++] = c[j];
        }
    return p;
}

/* A k x k grid at z = 0 and at z = 1 (coplanar hull facets full of
 * cocircular points). */
static pts two_planes(int g)
{
    pts p = pts_alloc("grid-two-planes", (size_t)2 * g * g);
    size_t j = 0;
    for (int z = 0; z < 2; z++)
        for (int x = 0; x < g; x++)
            for (int y = 0; y < g; y++) {
                p.xyz[j++] = x;
                p.xyz[j++] = y;
                p.xyz[j++] = z;
            }
    return p;
}

/* Points near a sphere (radius jittered: general position) and its
 * centre, which every hull face joins: a star of about 2n tets, over the
 * star search's stack buffer. */
static pts sphere_hub(size_t n)
{
    pts p = pts_alloc("sphere+centre", n + 1);
    for (size_t i = 0; i < n; i++) {
        double z = 1.0 - (2.0 * (double)i + 1.0) / (double)n;
        double r = sqrt(1.0 - z * z), ph = 2.399963229728653 * (double)i;
        double rad = 1.0 + 1e-3 * (double)(rnext() >> 11) * 0x1.0p-53;
        p.xyz[3 * i] = rad * r * cos(ph);
        p.xyz[3 * i + 1] = rad * r * sin(ph);
        p.xyz[3 * i + 2] = rad * z;
    }
    p.xyz[3 * n] = p.xyz[3 * n + 1] = p.xyz[3 * n + 2] = 0.0;
    return p;
}

/* Unit-cube points, some shrunk to 1e-150 and some blown up to 1e150. */
static pts magnitudes(size_t n)
{
    pts p = pts_alloc("magnitudes", n);
    for (size_t i = 0; i < n; i++) {
        double s = i % 3 == 0 ? 1e-150 : i % 3 == 1 ? 1.0 : 1e150;
        for (int k = 0; k < 3; k++)
            p.xyz[3 * i + k] = s * (double)(rnext() >> 11) * 0x1.0p-53;
    }
    return p;
}

/* ---- the engine's reference -------------------------------------------- */

typedef struct prepped {
    fdt_prepared pr;
    fdt_kdtree tree;
    uint32_t m;
} prepped;

/* Preparation and kd order, as the engine does them. */
static void prep(const pts *p, prepped *pp)
{
    char diag[256];
    memset(pp, 0, sizeof *pp);
    CHECK_EQ(fdt_prepare(p->xyz, p->n, 1, &pp->pr, diag, sizeof diag), FDT_OK);
    pp->m = (uint32_t)pp->pr.m;
    CHECK_EQ(fdt_kd_build(&pp->tree, pp->pr.p, pp->pr.orig, 0, pp->m, FDT_DEFAULT_LEAF), FDT_OK);
}

static void prep_free(prepped *pp)
{
    fdt_kd_free(&pp->tree);
    fdt_prepared_free(&pp->pr);
}

static int quad_cmp(const void *x, const void *y)
{
    const uint32_t *a = x, *b = y;
    for (int i = 0; i < 4; i++)
        if (a[i] != b[i])
            return a[i] < b[i] ? -1 : 1;
    return 0;
}

static int tri_cmp(const void *x, const void *y)
{
    const uint32_t *a = x, *b = y;
    for (int i = 0; i < 3; i++)
        if (a[i] != b[i])
            return a[i] < b[i] ? -1 : 1;
    return 0;
}

static void sort4(uint32_t *v)
{
    for (int i = 1; i < 4; i++)
        for (int j = i; j > 0 && v[j - 1] > v[j]; j--) {
            uint32_t t = v[j];
            v[j] = v[j - 1];
            v[j - 1] = t;
        }
}

/* Rotates a face so its smallest id leads, keeping its orientation. */
static void canon_tri(const uint32_t *f, uint32_t *out)
{
    int k = f[0] < f[1] ? (f[0] < f[2] ? 0 : 2) : (f[1] < f[2] ? 1 : 2);
    for (int j = 0; j < 3; j++)
        out[j] = f[(k + j) % 3];
}

typedef struct meshset {
    uint32_t *tets; /* sorted quadruples, sorted */
    size_t nt;
    uint32_t *hull; /* canonical outward triples, sorted */
    size_t nh;
} meshset;

static void meshset_free(meshset *s)
{
    free(s->tets);
    free(s->hull);
}

static uint32_t central_point(const fdt_kdtree *t)
{
    const fdt_kdnode *r = &t->nodes[0];
    double c[3];
    for (int k = 0; k < 3; k++)
        c[k] = r->lo[k] * 0.5 + r->hi[k] * 0.5;
    return fdt_kd_nearest(t, c, FDT_NONE, NULL);
}

static meshset engine_mesh(const prepped *pp)
{
    fdt_meshbuf mb;
    CHECK_EQ(fdt_meshbuf_init(&mb, 7 * (size_t)pp->m + 64, 0), FDT_OK);
    fdt_front_stats st;
    memset(&st, 0, sizeof st);
    CHECK_EQ(fdt_front_serial(&pp->tree, central_point(&pp->tree), FDT_SEARCH_KD, &mb, NULL, NULL, &st),
             FDT_OK);
    meshset s;
    s.nt = mb.ntets;
    s.tets = malloc((s.nt + 1) * 4 * sizeof *s.tets);
    CHECK(s.tets);
    memcpy(s.tets, mb.tets, s.nt * 4 * sizeof *s.tets);
    for (size_t i = 0; i < s.nt; i++)
        sort4(s.tets + 4 * i);
    qsort(s.tets, s.nt, 4 * sizeof *s.tets, quad_cmp);
    s.nh = mb.nhull;
    s.hull = malloc((s.nh + 1) * 3 * sizeof *s.hull);
    CHECK(s.hull);
    for (size_t i = 0; i < s.nh; i++)
        canon_tri(mb.hull + 3 * i, s.hull + 3 * i);
    qsort(s.hull, s.nh, 3 * sizeof *s.hull, tri_cmp);
    fdt_meshbuf_free(&mb);
    return s;
}

/* The kernel's finite tets and hull faces, ids mapped through map (NULL:
 * ids - base). */
static meshset kernel_mesh(const fdt_ins *m, const uint32_t *map)
{
    meshset s;
    s.nt = m->nfinite;
    s.nh = m->ninfinite;
    s.tets = malloc((s.nt + 1) * 4 * sizeof *s.tets);
    s.hull = malloc((s.nh + 1) * 3 * sizeof *s.hull);
    CHECK(s.tets && s.hull);
    size_t it = 0, ih = 0;
    for (uint32_t t = 0; t < m->nslots; t++) {
        const uint32_t *v = fdt_ins_tet(m, t);
        if (v[0] == FDT_NONE && v[1] == FDT_NONE)
            continue;
        if (fdt_ins_is_finite(m, t)) {
            CHECK(it < s.nt);
            for (int i = 0; i < 4; i++)
                s.tets[4 * it + i] = map ? map[v[i] - m->base] : v[i] - m->base;
            sort4(s.tets + 4 * it);
            it++;
            continue;
        }
        int inf = 0;
        while (v[inf] != FDT_NONE)
            inf++;
        /* The finite tet below; its face there is outward from it. */
        uint32_t nt;
        int nk;
        fdt_ins_across(m, t, inf, &nt, &nk);
        const uint32_t *w = fdt_ins_tet(m, nt);
        uint32_t f[3];
        for (int j = 0; j < 3; j++) {
            uint32_t id = w[fdt_tet_face[nk][j]];
            f[j] = map ? map[id - m->base] : id - m->base;
        }
        CHECK(ih < s.nh);
        canon_tri(f, s.hull + 3 * ih);
        ih++;
    }
    CHECK_EQ(it, s.nt);
    CHECK_EQ(ih, s.nh);
    qsort(s.tets, s.nt, 4 * sizeof *s.tets, quad_cmp);
    qsort(s.hull, s.nh, 3 * sizeof *s.hull, tri_cmp);
    return s;
}

static void same_mesh(const meshset *a, const meshset *b, const char *what)
{
    if (a->nt != b->nt || a->nh != b->nh)
        fprintf(stderr, "%s: %zu tets / %zu hull faces against %zu / %zu\n", what, a->nt, a->nh,
                b->nt, b->nh);
    CHECK_EQ(a->nt, b->nt);
    CHECK_EQ(a->nh, b->nh);
    for (size_t i = 0; i < a->nt; i++)
        if (quad_cmp(a->tets + 4 * i, b->tets + 4 * i) != 0) {
            fprintf(stderr, "%s: tet %zu differs\n", what, i);
            CHECK(0);
        }
    for (size_t i = 0; i < a->nh; i++)
        if (tri_cmp(a->hull + 3 * i, b->hull + 3 * i) != 0) {
            fprintf(stderr, "%s: hull face %zu differs\n", what, i);
            CHECK(0);
        }
}

/* ---- structure --------------------------------------------------------- */

static const double *P_(const fdt_ins *m, uint32_t v)
{
    return m->P + 3 * (size_t)v;
}

/* Whether tet t, finite or infinite, is in conflict with point q (the
 * kernel's rule, restated independently of src/mesh/insert.c). */
static int in_conflict(const fdt_ins *m, uint32_t t, uint32_t q)
{
    const uint32_t *v = fdt_ins_tet(m, t);
    if (fdt_ins_is_finite(m, t))
        return fdt_insphere_perturbed(P_(m, v[0]), P_(m, v[1]), P_(m, v[2]), P_(m, v[3]),
                                      P_(m, q), NULL) > 0;
    int inf = 0;
    while (v[inf] != FDT_NONE)
        inf++;
    const double *s[4];
    for (int i = 0; i < 4; i++)
        s[i] = i == inf ? P_(m, q) : P_(m, v[i]);
    int o = fdt_orient3d(s[0], s[1], s[2], s[3], NULL);
    if (o != 0)
        return o > 0;
    uint32_t nt;
    int nk;
    fdt_ins_across(m, t, inf, &nt, &nk);
    const uint32_t *w = fdt_ins_tet(m, nt);
    return fdt_insphere_perturbed(P_(m, w[0]), P_(m, w[1]), P_(m, w[2]), P_(m, w[3]), P_(m, q),
                                  NULL) > 0;
}

static int has_vertex(const uint32_t *v, uint32_t x)
{
    return v[0] == x || v[1] == x || v[2] == x || v[3] == x;
}

/* The most tets (infinite ones included) around one vertex. */
static size_t max_star(const fdt_ins *m)
{
    uint32_t *deg = calloc(m->n, sizeof *deg);
    CHECK(deg);
    size_t best = 0;
    for (uint32_t t = 0; t < m->nslots; t++) {
        const uint32_t *v = fdt_ins_tet(m, t);
        if (v[0] == FDT_NONE && v[1] == FDT_NONE)
            continue;
        for (int i = 0; i < 4; i++)
            if (v[i] != FDT_NONE && ++deg[v[i] - m->base] > best)
                best = deg[v[i] - m->base];
    }
    free(deg);
    return best;
}

static void check_structure(const fdt_ins *m, const char *what)
{
    size_t live = 0, fin = 0;
    for (uint32_t t = 0; t < m->nslots; t++) {
        const uint32_t *v = fdt_ins_tet(m, t);
        if (v[0] == FDT_NONE && v[1] == FDT_NONE)
            continue;
        live++;
        int ninf = 0;
        for (int i = 0; i < 4; i++) {
            ninf += v[i] == FDT_NONE;
            CHECK(v[i] == FDT_NONE || v[i] - m->base < m->n);
        }
        CHECK(ninf <= 1);
        if (ninf == 0) {
            fin++;
            CHECK(fdt_orient3d(P_(m, v[0]), P_(m, v[1]), P_(m, v[2]), P_(m, v[3]), NULL) > 0);
        }
        for (int k = 0; k < 4; k++) {
            uint32_t nt, nt2;
            int nk, nk2;
            uint32_t apex = fdt_ins_across(m, t, k, &nt, &nk);
            CHECK(nt < m->nslots);
            /* symmetric, over the same three vertices */
            fdt_ins_across(m, nt, nk, &nt2, &nk2);
            CHECK(nt2 == t && nk2 == k);
            const uint32_t *w = fdt_ins_tet(m, nt);
            CHECK(!(w[0] == FDT_NONE && w[1] == FDT_NONE));
            CHECK_EQ(apex, w[nk]);
            for (int i = 0; i < 4; i++)
                if (i != k)
                    CHECK(has_vertex(w, v[i]));
            CHECK(!has_vertex(v, apex));
            /* perturbed Delaunay across the face (the hull's coplanar rule
             * included); a face through the infinite vertex too */
            if (apex != FDT_NONE)
                CHECK(!in_conflict(m, t, apex));
        }
        /* an infinite tet's finite tet below lies inside its hull face */
        if (ninf == 1) {
            int inf = 0;
            while (v[inf] != FDT_NONE)
                inf++;
            uint32_t nt;
            int nk;
            uint32_t apex = fdt_ins_across(m, t, inf, &nt, &nk);
            CHECK(apex != FDT_NONE);
            const double *s[4];
            for (int i = 0; i < 4; i++)
                s[i] = i == inf ? P_(m, apex) : P_(m, v[i]);
            CHECK(fdt_orient3d(s[0], s[1], s[2], s[3], NULL) < 0);
        }
    }
    CHECK_EQ(fin, m->nfinite);
    CHECK_EQ(live, m->nfinite + m->ninfinite);
    /* every point is a vertex of its incident tet */
    for (uint32_t i = 0; i < m->n; i++) {
        uint32_t t = m->vtet[i];
        CHECK(t < m->nslots && has_vertex(fdt_ins_tet(m, t), m->base + i));
    }
    (void)what;
}

/* fdt_ins_find_face against fdt_ins_across, both orientations of every
 * finite face; and its refusals. */
/* fdt_ins_star_vertices: for a spread of vertices, exactly the vertices
 * that share a live tet with it (a brute-force scan of every slot), each
 * once; a vertex outside the mesh and a cap too small give 1. */
static void check_star_vertices(const fdt_ins *m)
{
    fdt_ins_query qs;
    memset(&qs, 0, sizeof qs);
    uint8_t *want = calloc((size_t)m->n, 1);
    CHECK(want != NULL);
    uint32_t step = m->n / 7 + 1;
    for (uint32_t i = 0; i < m->n; i += step) {
        uint32_t a = m->base + i;
        size_t nwant = 0;
        memset(want, 0, m->n);
        for (uint32_t s = 0; s < m->nslots; s++) {
            const uint32_t *w = fdt_ins_tet(m, s);
            if ((w[0] == FDT_NONE && w[1] == FDT_NONE) || !has_vertex(w, a))
                continue;
            for (int k = 0; k < 4; k++)
                if (w[k] != FDT_NONE && w[k] != a && !want[w[k] - m->base]) {
                    want[w[k] - m->base] = 1;
                    nwant++;
                }
        }
        CHECK_EQ(fdt_ins_star_vertices(m, a, SIZE_MAX, &qs), FDT_OK);
        CHECK_EQ(qs.nvs, nwant);
        for (size_t j = 0; j < qs.nvs; j++) {
            uint32_t v = qs.vs[j];
            CHECK(v - m->base < m->n && want[v - m->base] == 1);
            want[v - m->base] = 2; /* each once */
        }
        CHECK_EQ(fdt_ins_star_vertices(m, a, 1, &qs), 1);
    }
    CHECK_EQ(fdt_ins_star_vertices(m, m->base + m->n, SIZE_MAX, &qs), 1);
    free(want);
    fdt_ins_query_free(&qs);
}

static void check_find_face(const fdt_ins *m)
{
    for (uint32_t t = fdt_ins_next_finite(m, 0); t != FDT_NONE; t = fdt_ins_next_finite(m, t + 1)) {
        const uint32_t *v = fdt_ins_tet(m, t);
        for (int k = 0; k < 4; k++) {
            uint32_t a = v[fdt_tet_face[k][0]], b = v[fdt_tet_face[k][1]],
                     c = v[fdt_tet_face[k][2]];
            /* outward from t: the open side is the neighbour's */
            uint32_t nt, ft;
            int nk, fk;
            fdt_ins_across(m, t, k, &nt, &nk);
            CHECK_EQ(fdt_ins_find_face(m, a, b, c, &ft, &fk), 1);
            CHECK(ft == nt && fk == nk);
            CHECK_EQ(fdt_ins_find_face(m, b, c, a, &ft, &fk), 1);
            CHECK(ft == nt && fk == nk);
            /* reversed: t itself */
            CHECK_EQ(fdt_ins_find_face(m, a, c, b, &ft, &fk), 1);
            CHECK(ft == t && fk == k);
        }
    }
    uint32_t t = fdt_ins_next_finite(m, 0);
    const uint32_t *v = fdt_ins_tet(m, t);
    uint32_t ft;
    int fk;
    /* a foreign vertex */
    CHECK_EQ(fdt_ins_find_face(m, v[0], v[1], m->base + m->n, &ft, &fk), 0);
    if (m->base > 0)
        CHECK_EQ(fdt_ins_find_face(m, m->base - 1, v[1], v[2], &ft, &fk), 0);
    CHECK_EQ(fdt_ins_find_face(m, v[0], v[0], v[2], &ft, &fk), 0);
    /* a triangle that is not a face: a vertex with two far ones */
    uint32_t a = v[0], far1 = FDT_NONE, far2 = FDT_NONE;
    for (uint32_t i = 0; i < m->n && far2 == FDT_NONE; i++) {
        uint32_t x = m->base + i;
        if (x == a)
            continue;
        /* far: not a neighbour of a */
        int adj = 0;
        for (uint32_t s = 0; s < m->nslots && !adj; s++) {
            const uint32_t *w = fdt_ins_tet(m, s);
            if (!(w[0] == FDT_NONE && w[1] == FDT_NONE) && has_vertex(w, a) && has_vertex(w, x))
                adj = 1;
        }
        if (!adj) {
            if (far1 == FDT_NONE)
                far1 = x;
            else
                far2 = x;
        }
    }
    if (far2 != FDT_NONE)
        CHECK_EQ(fdt_ins_find_face(m, a, far1, far2, &ft, &fk), 0);
}

/* fdt_check on the kernel's finite tets, in the numbering of P + 3 base. */
static void check_independent(const fdt_ins *m, const char *what)
{
    fdt_vid *tets = malloc((m->nfinite + 1) * 4 * sizeof *tets);
    CHECK(tets);
    size_t i = 0;
    for (uint32_t t = fdt_ins_next_finite(m, 0); t != FDT_NONE; t = fdt_ins_next_finite(m, t + 1)) {
        const uint32_t *v = fdt_ins_tet(m, t);
        for (int k = 0; k < 4; k++)
            tets[4 * i + k] = (fdt_vid)(v[k] - m->base);
        i++;
    }
    char msg[512];
    int rc = fdt_check(m->P + 3 * (size_t)m->base, m->n, tets, i, NULL, msg, sizeof msg);
    if (rc != FDT_OK)
        fprintf(stderr, "%s: fdt_check: %s\n", what, msg);
    CHECK_EQ(rc, FDT_OK);
    free(tets);
}

/* ---- one point set ----------------------------------------------------- */

static double t_kernel, t_engine;

static void test_set(pts p, int extra)
{
    prepped pp;
    prep(&p, &pp);
    double t0 = now_s();
    meshset ref = engine_mesh(&pp);
    double t1 = now_s();
    fdt_ins m;
    fdt_pred_counts cnt = {0};
    CHECK_EQ(fdt_ins_build(&m, pp.pr.p, 0, pp.m, &cnt), FDT_OK);
    double t2 = now_s();
    t_engine += t1 - t0;
    t_kernel += t2 - t1;
    meshset got = kernel_mesh(&m, NULL);
    same_mesh(&got, &ref, p.name);
    check_structure(&m, p.name);
    check_find_face(&m);
    check_star_vertices(&m);
    check_independent(&m, p.name);
    printf("%-22s %6u points %7zu tets %5zu hull  star max %zu  cavity avg %.1f max %zu  "
           "walk %.1f  exact o/i %zu/%zu\n",
           p.name, pp.m, m.nfinite, m.ninfinite, max_star(&m),
           (double)m.stats.cavity_tets / (double)(pp.m - 4), m.stats.max_cavity,
           (double)m.stats.walk_steps / (double)(pp.m - 4), cnt.orient_exact, cnt.insphere_exact);
    fflush(stdout);
    meshset_free(&got);
    fdt_ins_free(&m);

    if (extra) {
        /* The same points shuffled (no spatial order): the same tets. */
        uint32_t n = pp.m;
        double *Q = malloc((size_t)n * 3 * sizeof *Q);
        uint32_t *perm = malloc((size_t)n * sizeof *perm);
        CHECK(Q && perm);
        for (uint32_t i = 0; i < n; i++)
            perm[i] = i;
        for (uint32_t i = n; i > 1; i--) {
            uint32_t j = (uint32_t)(rnext() % i), tmp = perm[i - 1];
            perm[i - 1] = perm[j];
            perm[j] = tmp;
        }
        for (uint32_t i = 0; i < n; i++)
            memcpy(Q + 3 * (size_t)i, pp.pr.p + 3 * (size_t)perm[i], 3 * sizeof *Q);
        CHECK_EQ(fdt_ins_build(&m, Q, 0, n, NULL), FDT_OK);
        got = kernel_mesh(&m, perm);
        char nm[96];
        snprintf(nm, sizeof nm, "%s shuffled", p.name);
        same_mesh(&got, &ref, nm);
        check_structure(&m, nm);
        meshset_free(&got);
        fdt_ins_free(&m);

        /* A sub-range [base, base + len) of the kd-ordered array: global
         * ids in the tets, an independent check, and equal to the kernel
         * on a copy of the range at base 0. */
        uint32_t base = n / 3, len = n - n / 3 - n / 5;
        if (fdt_ins_build(&m, pp.pr.p, base, len, NULL) == FDT_OK) {
            check_structure(&m, "sub-range");
            check_find_face(&m);
            check_independent(&m, "sub-range");
            fdt_ins m0;
            CHECK_EQ(fdt_ins_build(&m0, pp.pr.p + 3 * (size_t)base, 0, len, NULL), FDT_OK);
            meshset a = kernel_mesh(&m, NULL), b = kernel_mesh(&m0, NULL);
            same_mesh(&a, &b, "sub-range");
            meshset_free(&a);
            meshset_free(&b);
            fdt_ins_free(&m0);
            fdt_ins_free(&m);
        }
        free(Q);
        free(perm);
    }
    meshset_free(&ref);
    prep_free(&pp);
    free(p.xyz);
}

/* ---- the hull walk ---------------------------------------------------- */

/*
 * Points of a surface lie outside the hull of those before them, and on
 * some the visibility walk between neighbours crosses hundreds of long
 * tets: every integer point of one sphere (140 a point). The build then
 * locates by the hull walk (src/mesh/insert.c, hull_walk). Each mesh is
 * checked by fdt_check and by its structure, and the points shuffled
 * (other walks, other starts) give the same tets; on the integer sphere
 * the hull walk must have run, and the walks must stay short.
 */
static void test_hull_walk(const char *gen)
{
    static const char *fams[] = {"intsphere", "sphere", "cylscan", "cone"};
    for (size_t f = 0; f < sizeof fams / sizeof fams[0]; f++) {
        pts p = gen_family(gen, fams[f], 12000, 2);
        prepped pp;
        prep(&p, &pp);
        fdt_ins m, m2;
        CHECK_EQ(fdt_ins_build(&m, pp.pr.p, 0, pp.m, NULL), FDT_OK);
        check_structure(&m, fams[f]);
        check_independent(&m, fams[f]);
        double walk = (double)m.stats.walk_steps / (double)pp.m;
        printf("hull walk %-10s %6u points  %zu hull walks  walk %.1f\n", fams[f], pp.m,
               m.stats.hull_walks, walk);
        if (f == 0) {
            CHECK(m.stats.hull_walks > pp.m / 2);
            CHECK(walk < 40); /* 16 and a few; 140 without the hull walk */
        }
        /* reversed order: every walk another */
        double *Q = malloc((size_t)pp.m * 3 * sizeof *Q);
        uint32_t *perm = malloc((size_t)pp.m * sizeof *perm);
        CHECK(Q && perm);
        for (uint32_t i = 0; i < pp.m; i++) {
            perm[i] = pp.m - 1 - i;
            memcpy(Q + 3 * (size_t)i, pp.pr.p + 3 * (size_t)perm[i], 3 * sizeof *Q);
        }
        CHECK_EQ(fdt_ins_build(&m2, Q, 0, pp.m, NULL), FDT_OK);
        meshset a = kernel_mesh(&m, NULL), b = kernel_mesh(&m2, perm);
        same_mesh(&a, &b, fams[f]);
        meshset_free(&a);
        meshset_free(&b);
        fdt_ins_free(&m);
        fdt_ins_free(&m2);
        free(Q);
        free(perm);
        prep_free(&pp);
        free(p.xyz);
    }
}

/* ---- the tets array's size ----------------------------------------------- */

/*
 * A serial build sizes its tets array once, after the first 1/128 of its
 * points (src/mesh/insert.c, size_for_all), for the tets a point the
 * family has: a uniform cloud (6.7 slots a point), a pipe's scan (15) and
 * a cylinder's rings move it once and never grow it late, where a late
 * growth holds the old block and the new one at once (bench/NOTES.md
 * entry 117). Without the sizing the pipe's first block (6.75 slots a
 * point) grew by half again three times at 2^17 points, each move a copy
 * of everything built so far.
 */
static void test_slot_sizing(const char *gen)
{
    static const char *fams[] = {"uniform", "cylscan", "cylinder"};
    for (size_t f = 0; f < sizeof fams / sizeof fams[0]; f++) {
        pts p = gen_family(gen, fams[f], (size_t)1 << 17, 1);
        prepped pp;
        prep(&p, &pp);
        fdt_ins m;
        CHECK_EQ(fdt_ins_build(&m, pp.pr.p, 0, pp.m, NULL), FDT_OK);
        printf("%-22s %6u points %8u slots, capacity %8u, moved %zu time(s)\n", p.name, pp.m,
               m.nslots, m.cap, m.stats.moves);
        if (pp.m >= 65536)
            CHECK(m.stats.moves <= 1);
        CHECK(m.nslots <= m.cap);
        fdt_ins_free(&m);
        prep_free(&pp);
        free(p.xyz);
    }
}

/* ---- refusals ---------------------------------------------------------- */

static void expect_refusal(const double *xyz, uint32_t n, int want, const char *what)
{
    fdt_ins m;
    int rc = fdt_ins_build(&m, xyz, 0, n, NULL);
    if (rc != want)
        fprintf(stderr, "%s: status %d, want %d\n", what, rc, want);
    CHECK_EQ(rc, want);
    CHECK(m.T == NULL && m.vtet == NULL && m.nslots == 0);
    fdt_ins_free(&m);
}

/* fdt_ins_brio: a permutation of the ids by round, with the point nearest
 * the centre of the bounding box first wherever its id falls (a hub inside
 * a shell inserted late makes every cavity span the shell: src/mesh/insert.c,
 * centre_first). */
static void test_brio_order(void)
{
    enum { N = 3000, BASE = 7 };
    static double P[3 * (BASE + N)];
    static uint32_t order[N];
    uint64_t s = 12345;
    for (int at = 0; at < N; at += 499) {
        for (int i = 0; i < BASE + N; i++)
            for (int k = 0; k < 3; k++) {
                s = s * 6364136223846793005u + 1442695040888963407u;
                /* a shell of radius 1 around (2, 2, 2), well away from it */
                P[3 * i + k] = (double)(s >> 11) * 0x1p-53 < 0.5 ? 1.0 : 3.0;
                P[3 * i + k] += 1e-3 * ((double)(s >> 20) * 0x1p-44);
            }
        double *c = P + 3 * (BASE + at);
        c[0] = 2.0005, c[1] = 2.0, c[2] = 2.0; /* the nearest to the box centre */
        uint32_t round_end[32];
        int nr = 0;
        fdt_ins_brio(P, BASE, N, order, round_end, &nr);
        EXPECTF(order[0] == (uint32_t)(BASE + at), "brio: centre id %d at order[0] = %u", BASE + at,
                order[0]);
        EXPECT(nr >= 1 && nr <= 32 && round_end[nr - 1] == N);
        static unsigned char seen[N];
        memset(seen, 0, sizeof seen);
        int ok = 1;
        for (int j = 0; j < N; j++) {
            uint32_t id = order[j];
            ok &= id >= BASE && id < BASE + N && !seen[id - BASE];
            if (id >= BASE && id < BASE + N)
                seen[id - BASE] = 1;
        }
        EXPECTF(ok, "brio: not a permutation (centre at %d)", at);
    }
}

static void test_refusals(void)
{
    double xyz[3 * 400];
    /* fewer than 4 points */
    for (int i = 0; i < 9; i++)
        xyz[i] = (double)(i * i % 7);
    expect_refusal(xyz, 0, FDT_EDEGENERATE, "0 points");
    expect_refusal(xyz, 3, FDT_EDEGENERATE, "3 points");
    /* collinear: points k (1, 2, 3) + offset, mixed magnitudes */
    for (int i = 0; i < 100; i++) {
        double s = i % 2 ? 1e-120 * i : (double)i;
        xyz[3 * i] = 5.0 + s;
        xyz[3 * i + 1] = 5.0 + 2 * s;
        xyz[3 * i + 2] = 5.0 + 3 * s;
    }
    expect_refusal(xyz, 100, FDT_EDEGENERATE, "collinear");
    /* coplanar: a 10 x 10 grid in the plane x + y + z = 30 */
    for (int i = 0; i < 100; i++) {
        xyz[3 * i] = i % 10;
        xyz[3 * i + 1] = i / 10;
        xyz[3 * i + 2] = 30.0 - (i % 10) - (i / 10);
    }
    expect_refusal(xyz, 100, FDT_EDEGENERATE, "coplanar");
    /* coplanar, the first three collinear */
    for (int i = 0; i < 100; i++) {
        xyz[3 * i] = i < 3 ? i : (double)(rnext() % 1000);
        xyz[3 * i + 1] = i < 3 ? 0 : (double)(rnext() % 1000);
        xyz[3 * i + 2] = 1e100;
    }
    expect_refusal(xyz, 100, FDT_EDEGENERATE, "coplanar 2");
    /* a duplicate (the precondition broken) is refused, not triangulated */
    for (int i = 0; i < 100; i++)
        for (int k = 0; k < 3; k++)
            xyz[3 * i + k] = (double)(rnext() >> 11) * 0x1.0p-53;
    memcpy(xyz + 3 * 77, xyz + 3 * 31, 3 * sizeof *xyz);
    expect_refusal(xyz, 100, FDT_EINVAL, "duplicate");
    /* the 4 spanning points at the end of an otherwise coplanar set */
    for (int i = 0; i < 100; i++) {
        xyz[3 * i] = i % 10;
        xyz[3 * i + 1] = i / 10;
        xyz[3 * i + 2] = i == 99 ? 1.0 : 0.0;
    }
    fdt_ins m;
    CHECK_EQ(fdt_ins_build(&m, xyz, 0, 100, NULL), FDT_OK);
    check_structure(&m, "plane + 1");
    check_find_face(&m);
    check_independent(&m, "plane + 1");
    fdt_ins_free(&m);
}

/* ---- the parallel build ------------------------------------------------ */

/* fdt_ins_build_parallel against fdt_ins_build (the same tets and hull
 * faces: the perturbed DT is unique), for several thread counts, each
 * several times (the schedule, hence who inserts what and which points
 * are deferred, differs from run to run); full structure checks on the
 * first run of each count. */
static size_t serial_finished; /* points of the parallel builds' serial ends */
static size_t stolen_points;   /* points taken from another worker's last round */

/* The serial build's tets of pp: what every parallel build must give. */
static meshset serial_reference(const prepped *pp)
{
    fdt_ins m;
    CHECK_EQ(fdt_ins_build(&m, pp->pr.p, 0, pp->m, NULL), FDT_OK);
    meshset ref = kernel_mesh(&m, NULL);
    fdt_ins_free(&m);
    return ref;
}

static void test_parallel_set(pts p, int reps)
{
    prepped pp;
    prep(&p, &pp);
    fdt_ins m;
    meshset ref = serial_reference(&pp);
    static const int threads[] = {1, 2, 3, 5, 8};
    for (size_t ti = 0; ti < sizeof threads / sizeof threads[0]; ti++) {
        for (int r = 0; r < reps; r++) {
            fdt_pred_counts cnt = {0};
            double t0 = now_s();
            /* the second run with room for 1.5 or 0.25 slots a point at
             * first: the workers run out, the arrays grow between their
             * passes (1.5) or, after 8 passes, in the serial finish */
            double spp = r == 1 ? (ti % 2 ? 0.25 : 1.5) : 0.0;
            CHECK_EQ(fdt_ins_build_parallel_slots(&m, pp.pr.p, 0, pp.m, threads[ti], spp, &cnt),
                     FDT_OK);
            if (spp > 0.0)
                CHECK(m.stats.deferred > 0); /* the slots did run out */
            serial_finished += m.stats.serial_finish;
            stolen_points += m.stats.stolen;
            t_kernel += now_s() - t0;
            char nm[96];
            snprintf(nm, sizeof nm, "%s parallel t%d run %d", p.name, threads[ti], r);
            meshset got = kernel_mesh(&m, NULL);
            same_mesh(&got, &ref, nm);
            CHECK_EQ(m.stats.inserted, (size_t)pp.m);
            if (r == 0) {
                check_structure(&m, nm);
                if (pp.m <= 5000)
                    check_find_face(&m);
            }
            meshset_free(&got);
            fdt_ins_free(&m);
        }
    }
    /* A sub-range [base, base + len): global ids, the same tets as the
     * serial build of that range. */
    uint32_t base = pp.m / 3, len = pp.m - pp.m / 3 - pp.m / 5;
    fdt_ins m0;
    if (fdt_ins_build(&m0, pp.pr.p, base, len, NULL) == FDT_OK) {
        CHECK_EQ(fdt_ins_build_parallel(&m, pp.pr.p, base, len, 3, NULL), FDT_OK);
        check_structure(&m, "parallel sub-range");
        meshset a = kernel_mesh(&m, NULL), b = kernel_mesh(&m0, NULL);
        same_mesh(&a, &b, "parallel sub-range");
        meshset_free(&a);
        meshset_free(&b);
        fdt_ins_free(&m);
        fdt_ins_free(&m0);
    }
    printf("parallel %-22s %6u points %7zu tets: same as serial for 1, 2, 3, 5, 8 threads x %d\n",
           p.name, pp.m, ref.nt, reps);
    fflush(stdout);
    meshset_free(&ref);
    prep_free(&pp);
    free(p.xyz);
}

static void expect_refusal_par(const double *xyz, uint32_t n, int want, const char *what)
{
    for (int t = 1; t <= 4; t++) {
        fdt_ins m;
        int rc = fdt_ins_build_parallel(&m, xyz, 0, n, t, NULL);
        if (rc != want)
            fprintf(stderr, "%s (parallel, %d threads): status %d, want %d\n", what, t, rc, want);
        CHECK_EQ(rc, want);
        CHECK(m.T == NULL && m.vtet == NULL && m.nslots == 0);
        fdt_ins_free(&m);
    }
}

static void test_parallel_refusals(const char *gen)
{
    double xyz[3 * 400] = {0};
    expect_refusal_par(xyz, 3, FDT_EDEGENERATE, "3 points");
    for (int i = 0; i < 400; i++) { /* coplanar: a grid in x + y + z = 30 */
        xyz[3 * i] = i % 20;
        xyz[3 * i + 1] = i / 20;
        xyz[3 * i + 2] = 30.0 - (i % 20) - (i / 20);
    }
    expect_refusal_par(xyz, 400, FDT_EDEGENERATE, "coplanar");
    /* duplicates, early (in the serial rounds) and late (in the threads'
     * rounds): every point's copy, so some copy falls in each phase */
    pts u = gen_family(gen, "uniform", 20000, 3);
    size_t n = u.n;
    double *d = malloc(2 * n * 3 * sizeof *d);
    CHECK(d);
    memcpy(d, u.xyz, n * 3 * sizeof *d);
    for (size_t k = 0; k < 3; k++) {
        /* one duplicate at a time, at spread positions */
        size_t src = (k * 7919) % n, dst = n - 1 - k * 4001;
        memcpy(d, u.xyz, n * 3 * sizeof *d);
        memcpy(d + 3 * dst, d + 3 * src, 3 * sizeof *d);
        char nm[64];
        snprintf(nm, sizeof nm, "duplicate %zu of %zu", dst, src);
        expect_refusal_par(d, (uint32_t)n, FDT_EINVAL, nm);
    }
    free(d);
    free(u.xyz);
}

/* The parallel build of pp on `threads` threads into *m, checked: the
 * serial build's tets (ref) and a sound structure; the caller reads its
 * stats and frees it. */
static void build_parallel_checked(const prepped *pp, const meshset *ref, int threads,
                                   const char *nm, fdt_ins *m)
{
    CHECK_EQ(fdt_ins_build_parallel(m, pp->pr.p, 0, pp->m, threads, NULL), FDT_OK);
    meshset got = kernel_mesh(m, NULL);
    same_mesh(&got, ref, nm);
    check_structure(m, nm);
    meshset_free(&got);
}

/* More threads than a lock byte can name (63, src/mesh/insert_par.c): the
 * build runs on 63 workers and gives the same tets. */
static void test_parallel_many_threads(const char *gen)
{
    pts p = gen_family(gen, "clusters", 3000, 7);
    prepped pp;
    prep(&p, &pp);
    fdt_ins m;
    meshset ref = serial_reference(&pp);
    static const int many[] = {63, 64, 100};
    for (size_t i = 0; i < sizeof many / sizeof many[0]; i++) {
        char nm[64];
        snprintf(nm, sizeof nm, "clusters-3000 parallel t%d", many[i]);
        build_parallel_checked(&pp, &ref, many[i], nm, &m);
        fdt_ins_free(&m);
    }
    printf("parallel clusters-3000: same as serial for 63, 64 and 100 threads\n");
    meshset_free(&ref);
    prep_free(&pp);
    free(p.xyz);
}

/* The workers take the hull walk too (src/mesh/insert_par.c,
 * hull_walk_locked): on the integer points of a sphere, where every point
 * lies outside the hull before it, most points are located by it, and
 * the tets are the serial build's. */
static void test_parallel_hull_walk(const char *gen)
{
    pts p = gen_family(gen, "intsphere", 12000, 2);
    prepped pp;
    prep(&p, &pp);
    meshset ref = serial_reference(&pp);
    static const int threads[] = {2, 3, 5};
    for (size_t ti = 0; ti < sizeof threads / sizeof threads[0]; ti++) {
        fdt_ins m;
        char nm[64];
        snprintf(nm, sizeof nm, "intsphere parallel hull walk t%d", threads[ti]);
        build_parallel_checked(&pp, &ref, threads[ti], nm, &m);
        printf("%s: %u points, %zu hull walks, %zu deferred\n", nm, pp.m, m.stats.hull_walks,
               m.stats.deferred);
        CHECK(m.stats.hull_walks > pp.m / 4); /* the serial start has 1/128 of them */
        fdt_ins_free(&m);
    }
    meshset_free(&ref);
    prep_free(&pp);
    free(p.xyz);
}

static void run_parallel(const char *gen)
{
    test_parallel_refusals(gen);
    test_parallel_many_threads(gen);
    test_parallel_hull_walk(gen);
    static const struct {
        const char *fam;
        size_t n;
        int reps;
    } fams[] = {
        {"uniform", 2000, 3},    {"uniform", 50000, 2},   {"clusters", 20000, 2},
        {"lattice", 8000, 2},    {"cylinder", 20000, 2},  {"cylscan", 20000, 2},
        {"rotlattice", 8000, 2}, {"sphere12", 5000, 2},   {"grid2d", 10000, 2},
        {"citylidar", 20000, 2}, {"clusters", 2000, 3},   {"citylidar", 2000, 3},
    };
    for (size_t i = 0; i < sizeof fams / sizeof fams[0]; i++)
        test_parallel_set(gen_family(gen, fams[i].fam, fams[i].n, (int)i + 1), fams[i].reps);
    test_parallel_set(lattice(12, "lattice-12^3"), 2);
    test_parallel_set(rotated_lattice(14), 2);
    test_parallel_set(cylinder(60), 2);
    test_parallel_set(two_planes(40), 2);
    /* the serial finish (and its growing arrays) was reached */
    CHECK(serial_finished > 0);
    /* and workers took points from others' last rounds (8 threads on
     * fewer cores finish their regions far apart) */
    CHECK(stolen_points > 0);
    printf("test_insert --parallel: all checks passed (parallel kernel %.3f s, %zu points "
           "by the serial finishes, %zu stolen)\n", t_kernel, serial_finished, stolen_points);
}

/* ---- timing driver ----------------------------------------------------- */

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return a < b ? -1 : a > b;
}

/* CPU seconds of this thread: on a loaded machine, less noisy than the
 * wall clock (it leaves out the time spent waiting for a core). */
static double cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double proc_cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* threads 0: fdt_ins_build; else fdt_ins_build_parallel with that many
 * (CPU time is then the whole process's, all threads). */
static int time_file(const char *path, int reps, int threads)
{
    pts p = pts_alloc(path, 1);
    free(p.xyz);
    p.xyz = test_read_xyz(path, &p.n);
    prepped pp;
    double t0 = now_s();
    prep(&p, &pp);
    double t_prep = now_s() - t0;
    double ts[64], cs[64];
    if (reps < 1)
        reps = 1;
    if (reps > 64)
        reps = 64;
    fdt_ins m;
    fdt_pred_counts cnt = {0};
    for (int r = 0; r < reps; r++) {
        memset(&cnt, 0, sizeof cnt);
        double a = now_s(), ca = threads ? proc_cpu_now() : cpu_now();
        int rc = threads ? fdt_ins_build_parallel(&m, pp.pr.p, 0, pp.m, threads, &cnt)
                         : fdt_ins_build(&m, pp.pr.p, 0, pp.m, &cnt);
        ts[r] = now_s() - a;
        cs[r] = (threads ? proc_cpu_now() : cpu_now()) - ca;
        if (rc != FDT_OK) {
            fprintf(stderr, "fdt_ins_build: %s\n", fdt_strerror(rc));
            return 1;
        }
        if (r + 1 < reps)
            fdt_ins_free(&m);
    }
    double sorted[64];
    memcpy(sorted, ts, (size_t)reps * sizeof *ts);
    qsort(sorted, (size_t)reps, sizeof *sorted, cmp_double);
    double med = sorted[reps / 2];
    qsort(cs, (size_t)reps, sizeof *cs, cmp_double);
    printf("SUMMARY code=insert threads=%d file=%s points=%u tets=%zu hull=%zu build_s=%.4f min_s=%.4f "
           "max_s=%.4f cpu_s=%.4f reps=%d prep_kd_s=%.4f walk_steps=%zu cavity_tets=%zu max_cavity=%zu "
           "conflict_tests=%zu deferred=%zu stolen=%zu serial_finish=%zu cpu_start=%.3f cpu_workers_max=%.3f cpu_workers_sum=%.3f cpu_finish=%.3f exact_orient=%zu exact_insphere=%zu slots=%u bytes_per_point=%.1f\n",
           threads, path, pp.m, m.nfinite, m.ninfinite, med, sorted[0], sorted[reps - 1], cs[reps / 2],
           reps, t_prep,
           m.stats.walk_steps, m.stats.cavity_tets, m.stats.max_cavity, m.stats.conflict_tests,
           m.stats.deferred, m.stats.stolen, m.stats.serial_finish, m.stats.cpu_start_s, m.stats.cpu_workers_max_s,
           m.stats.cpu_workers_sum_s, m.stats.cpu_finish_s, cnt.orient_exact, cnt.insphere_exact, m.nslots,
           ((double)m.cap * 32.0 + (double)m.n * 4.0) / (double)m.n);
    fdt_ins_free(&m);
    prep_free(&pp);
    free(p.xyz);
    return 0;
}

/* ins_star_edge (src/mesh/insert_impl.h) is fdt_tet_face[0] read as the
 * star's directed outer edges (every star tet has its centre at index 0):
 * for j = 0..2, the tail and head are the outward face's vertices after
 * f[j], the face index f[j] itself. */
static void test_star_edges(void)
{
    const int *f = fdt_tet_face[0];
    for (int j = 0; j < 3; j++) {
        CHECK(ins_star_edge[j][0] == f[(j + 1) % 3]);
        CHECK(ins_star_edge[j][1] == f[(j + 2) % 3]);
        CHECK(ins_star_edge[j][2] == f[j]);
    }
}

/* A bipyramid's boundary as the cavity of point 0 (ids 1 .. r the ring,
 * r + 1 the top, the bottom `bottom`: an id or FDT_NONE, the infinite
 * vertex): cavity tet i in slot i of T is (Z, a, b, c) with its outer
 * face abc consistently oriented and its neighbour across it the outer
 * tet in slot n + i (which refers back), and the star is to go in slots
 * 2n + i. bnd[i] = the face opposite vertex 0 of slot i. */
static size_t bipyramid_cavity(uint32_t *T, uint32_t *bnd, uint32_t *slots, uint32_t r,
                               uint32_t bottom)
{
    size_t n = 2 * (size_t)r;
    for (size_t i = 0; i < 3 * n; i++)
        for (int j = 0; j < 8; j++)
            T[8 * i + j] = FDT_NONE;
    for (uint32_t i = 0; i < r; i++) {
        uint32_t a = 1 + i, b = 1 + (i + 1) % r;
        uint32_t top[3] = {r + 1, a, b}, bot[3] = {bottom, b, a};
        for (int h = 0; h < 2; h++) {
            size_t c = 2 * (size_t)i + (size_t)h;
            uint32_t *v = T + 8 * c;
            const uint32_t *f = h ? bot : top;
            v[0] = 9999; /* the vertex the new point replaces */
            v[1] = f[0];
            v[2] = f[1];
            v[3] = f[2];
            v[4] = (uint32_t)((n + c) << 2);
            T[8 * (n + c) + 4] = (uint32_t)(c << 2);
            bnd[c] = (uint32_t)(c << 2);
            slots[c] = (uint32_t)(2 * n + c);
        }
    }
    return n;
}

/* ins_make_star (src/mesh/insert_impl.h) makes a star as ins_star_tet
 * does and links it as the edge table does, by local numbers up to
 * INS_LOCAL_MAXF faces and by the table past them (or past the local
 * numbers' reach), and refuses a star whose faces do not count as a
 * sphere's, or (the edge table) are not a closed surface walked once each
 * way. */
static void test_star_links(void)
{
    enum { R = 40, MAXN = 2 * R };
    static uint32_t T1[8 * 3 * MAXN], T2[8 * 3 * MAXN];
    uint32_t bnd[MAXN], slots[MAXN];
    uint8_t lid[R + 3] = {0}; /* ids 0 .. R + 1, the infinite vertex R + 2 */
    static ins_local L; /* the cells: 8 KiB */
    ins_edges e = {0};
    L.lid = lid;
    L.base = 0;
    L.n = R + 2;
    /* every ring size to past the local numbers' reach, the bottom a
     * point (id r + 2) or the infinite vertex */
    for (uint32_t r = 3; r < R; r++) {
        for (int inf = 0; inf < 2; inf++) {
            size_t n = bipyramid_cavity(T1, bnd, slots, r, inf ? FDT_NONE : r + 2);
            memcpy(T2, T1, sizeof T1);
            CHECK(ins_make_star(&L, &e, T1, bnd, n, 0, slots) == FDT_OK);
            for (size_t i = 0; i < n; i++)
                ins_star_tet(T2, bnd[i], 0, slots[i]);
            CHECK(ins_edges_begin(&e, 3 * n) == FDT_OK);
            CHECK(ins_link_star(&e, T2, slots, n) == FDT_OK);
            CHECK(memcmp(T1, T2, 8 * 3 * n * sizeof *T1) == 0);
            for (size_t i = 0; i < n; i++) /* the outer tets refer to the star */
                CHECK(T1[8 * (n + i) + 4] == (uint32_t)((2 * n + i) << 2));
            for (size_t i = 0; i < sizeof lid; i++)
                CHECK(lid[i] == 0); /* the numbers cleared after */
            /* one cavity face missing: not a sphere's count */
            bipyramid_cavity(T1, bnd, slots, r, inf ? FDT_NONE : r + 2);
            CHECK(ins_make_star(&L, &e, T1, bnd + 1, n - 1, 0, slots + 1) == FDT_EINTERNAL);
            for (size_t i = 0; i < sizeof lid; i++)
                CHECK(lid[i] == 0);
            /* one face turned over: the edge table sees two directed edges
             * twice (the local numbers do not look: the certificate
             * checks every link of the finished mesh) */
            bipyramid_cavity(T1, bnd, slots, r, inf ? FDT_NONE : r + 2);
            size_t j = n / 2;
            uint32_t t = T1[8 * j + 2];
            T1[8 * j + 2] = T1[8 * j + 3];
            T1[8 * j + 3] = t;
            for (size_t i = 0; i < n; i++)
                ins_star_tet(T1, bnd[i], 0, slots[i]);
            CHECK(ins_edges_begin(&e, 3 * n) == FDT_OK);
            CHECK(ins_link_star(&e, T1, slots, n) == FDT_EINTERNAL);
        }
    }
    /* Faces of distinct vertices, fewer than INS_LOCAL_MAXF: the numbers
     * run out mid-star, the edge table takes it and finds no surface. */
    uint8_t lid2[3 * 30 + 2] = {0};
    L.lid = lid2;
    L.n = 3 * 30 + 1;
    size_t n = bipyramid_cavity(T1, bnd, slots, 15, 17);
    for (size_t i = 0; i < n; i++)
        for (int q = 0; q < 3; q++)
            T1[8 * i + 1 + q] = (uint32_t)(1 + 3 * i + (size_t)q);
    CHECK(ins_make_star(&L, &e, T1, bnd, n, 0, slots) == FDT_EINTERNAL);
    for (size_t i = 0; i < sizeof lid2; i++)
        CHECK(lid2[i] == 0);
    free(e.eh);
}

int main(int argc, char **argv)
{
    if (argc >= 3 && strcmp(argv[1], "--time") == 0)
        return time_file(argv[2], argc > 3 ? atoi(argv[3]) : 3, argc > 4 ? atoi(argv[4]) : 0);
    if (argc == 3 && strcmp(argv[1], "--parallel") == 0) {
        run_parallel(argv[2]);
        return 0;
    }
    if (argc != 2) {
        fprintf(stderr, "usage: %s GEN_POINTS | --parallel GEN_POINTS | --time FILE.xyz [REPS "
                        "[THREADS]]\n", argv[0]);
        return 2;
    }
    const char *gen = argv[1];
    test_refusals();
    test_brio_order();
    test_star_edges();
    test_star_links();
    test_slot_sizing(gen);
    test_hull_walk(gen);

    /* Every family of gen_points; sizes keep the reference (the front,
     * quadratic on cospherical sets) within a few seconds. */
    static const struct {
        const char *fam;
        size_t n;
    } fams[] = {
        {"uniform", 3000},  {"ball", 2000},     {"sphere", 300},     {"gaussian", 2000},
        {"clusters", 2000}, {"lattice", 1000},  {"intsphere", 300},  {"grid2d", 1500},
        {"offset", 2000},   {"tiny", 1500},     {"huge", 1500},      {"neardup", 2000},
        {"dup", 2000},      {"cfdgrid", 3000},  {"lidar", 3000},     {"dupheavy", 2000},
        {"mixed", 600},     {"ulpgrid", 2000},
    };
    for (size_t i = 0; i < sizeof fams / sizeof fams[0]; i++)
        test_set(gen_family(gen, fams[i].fam, fams[i].n, 1), i % 3 == 0);

    test_set(lattice(5, "lattice-5x5x5"), 1);
    test_set(rotated_lattice(8), 1);
    test_set(cylinder(5), 1);
    test_set(cube_faces(), 1);
    test_set(two_planes(12), 1);
    test_set(magnitudes(1500), 1);
    test_set(sphere_hub(700), 0);
    printf("test_insert: all checks passed (kernel %.3f s, reference front %.3f s)\n", t_kernel,
           t_engine);
    return 0;
}
