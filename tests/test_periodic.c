/*
 * The periodic DT (src/mesh/periodic.h, src/geom/images.h; issue 33).
 *
 * - Against an independent reference (the issue's): the points replicated
 *   three times along each periodic axis, triangulated by the public API's
 *   plain engine, and the tets (and hull faces) whose lowest-index vertex
 *   lies in the middle copy kept, offsets relative to it. On points whose
 *   coordinates and box are on a binary grid, so every image is a double
 *   and the plain engine sees the exact images: uniform points, a lattice
 *   (every cell's 8 corners cospherical), a channel (walls of points at
 *   y = 0 and y = 1, a boundary layer between them, periodic in x and z),
 *   periodic in x y z, in x z and in x alone.
 * - Where images are not doubles (a box [0.1, 1.3) and random doubles):
 *   the same mesh at 1 and 3 threads and for a shuffled input, and the
 *   quotient's Euler characteristic (V - E + T = 0 on the 3-torus: every
 *   face is in two tets, V - E + F - T = 0 and F = 2T).
 * - Errors: a point outside the box, a box with no periodic axis, too few
 *   points for one copy of the box (CGAL's 1-sheet condition).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/periodic.h"
#include "mesh/voronoi.h"
#include "testutil.h"

typedef struct vtx {
    uint32_t id;
    int8_t off[3];
} vtx;

static int vtx_cmp(const vtx *a, const vtx *b)
{
    if (a->id != b->id)
        return a->id < b->id ? -1 : 1;
    for (int k = 0; k < 3; k++)
        if (a->off[k] != b->off[k])
            return a->off[k] < b->off[k] ? -1 : 1;
    return 0;
}

/* A tet or face as a sorted row of vertices (offsets relative to the
 * first), nv of them, padded. */
typedef struct row {
    vtx v[4];
} row;

static int row_cmp(const void *x, const void *y)
{
    const row *a = x, *b = y;
    for (int j = 0; j < 4; j++) {
        int c = vtx_cmp(&a->v[j], &b->v[j]);
        if (c)
            return c;
    }
    return 0;
}

/* The row of nv vertices: relative to the least id's offset, sorted by
 * id. Returns whether that vertex has offset 0. */
static int make_row(vtx *v, int nv, row *r)
{
    memset(r, 0, sizeof *r);
    int lo = 0;
    for (int j = 1; j < nv; j++)
        if (v[j].id < v[lo].id)
            lo = j;
    int8_t o0[3];
    memcpy(o0, v[lo].off, 3);
    for (int j = 0; j < nv; j++) {
        r->v[j].id = v[j].id;
        for (int k = 0; k < 3; k++)
            r->v[j].off[k] = (int8_t)(v[j].off[k] - o0[k]);
    }
    for (int a = 1; a < nv; a++)
        for (int j = a; j > 0 && vtx_cmp(&r->v[j], &r->v[j - 1]) < 0; j--) {
            vtx t = r->v[j];
            r->v[j] = r->v[j - 1];
            r->v[j - 1] = t;
        }
    return !o0[0] && !o0[1] && !o0[2];
}

typedef struct rows {
    row *r;
    size_t n;
} rows;

/* The mesh's tets or hull faces as rows, sorted. */
static rows mesh_rows(const uint32_t *ids, const int8_t *off, size_t count, int nv)
{
    rows s = {malloc((count ? count : 1) * sizeof(row)), count};
    CHECK(s.r);
    for (size_t i = 0; i < count; i++) {
        vtx v[4];
        memset(v, 0, sizeof v);
        for (int j = 0; j < nv; j++) {
            v[j].id = ids[(size_t)nv * i + (size_t)j];
            memcpy(v[j].off, off + 3 * ((size_t)nv * i + (size_t)j), 3);
        }
        make_row(v, nv, &s.r[i]);
    }
    qsort(s.r, s.n, sizeof *s.r, row_cmp);
    return s;
}

/* The reference: three copies along each periodic axis. */
static void reference(const double *X, size_t n, const fdt_periodic_box *b, rows *tets,
                      rows *hull)
{
    int cnt[3];
    for (int k = 0; k < 3; k++)
        cnt[k] = b->axes >> k & 1 ? 3 : 1;
    size_t copies = (size_t)cnt[0] * cnt[1] * cnt[2];
    double *R = malloc(copies * n * 3 * sizeof *R);
    vtx *who = malloc(copies * n * sizeof *who);
    CHECK(R && who);
    size_t m = 0;
    for (int a = 0; a < cnt[0]; a++)
        for (int c = 0; c < cnt[1]; c++)
            for (int d = 0; d < cnt[2]; d++) {
                int8_t o[3] = {(int8_t)(cnt[0] == 3 ? a - 1 : 0), (int8_t)(cnt[1] == 3 ? c - 1 : 0),
                               (int8_t)(cnt[2] == 3 ? d - 1 : 0)};
                for (size_t i = 0; i < n; i++, m++) {
                    for (int k = 0; k < 3; k++) {
                        R[3 * m + k] = X[3 * i + k] + o[k] * (b->hi[k] - b->lo[k]);
                        /* the binary-grid inputs make that exact */
                        CHECK(R[3 * m + k] - o[k] * (b->hi[k] - b->lo[k]) == X[3 * i + k]);
                    }
                    who[m].id = (uint32_t)i;
                    memcpy(who[m].off, o, 3);
                }
            }
    fdt_result *res = test_triangulate(R, m, 1, 0);
    size_t nt = fdt_result_num_tets(res), nh = fdt_result_num_hull_faces(res);
    const fdt_vid *T = fdt_result_tets(res), *H = fdt_result_hull_faces(res);
    tets->r = malloc((nt ? nt : 1) * sizeof(row));
    hull->r = malloc((nh ? nh : 1) * sizeof(row));
    CHECK(tets->r && hull->r);
    tets->n = hull->n = 0;
    for (size_t t = 0; t < nt; t++) {
        vtx v[4];
        for (int j = 0; j < 4; j++)
            v[j] = who[T[4 * t + (size_t)j]];
        if (make_row(v, 4, &tets->r[tets->n]))
            tets->n++;
    }
    for (size_t t = 0; t < nh; t++) {
        vtx v[4];
        memset(v, 0, sizeof v);
        for (int j = 0; j < 3; j++)
            v[j] = who[H[3 * t + (size_t)j]];
        if (make_row(v, 3, &hull->r[hull->n]))
            hull->n++;
    }
    qsort(tets->r, tets->n, sizeof(row), row_cmp);
    qsort(hull->r, hull->n, sizeof(row), row_cmp);
    fdt_result_free(&res);
    free(R);
    free(who);
}

static int same_rows(const rows *a, const rows *b)
{
    return a->n == b->n && (a->n == 0 || !memcmp(a->r, b->r, a->n * sizeof(row)));
}

static fdt_periodic_mesh build(const double *X, size_t n, const fdt_periodic_box *b, int threads,
                               const char *name)
{
    fdt_periodic_mesh pm;
    char diag[512];
    int err = fdt_periodic_build(X, (uint32_t)n, NULL, b, threads, &pm, diag, sizeof diag);
    EXPECTF(err == FDT_OK, "%s: fdt_periodic_build: %d (%s)", name, err, diag);
    CHECK(err == FDT_OK);
    return pm;
}

/* V - E + T over the quotient: the distinct edges, offsets relative to
 * their lower id. */
static long euler_vet(const fdt_periodic_mesh *pm, size_t nverts)
{
    size_t ne = 0;
    row *e = malloc(pm->ntets * 6 * sizeof *e);
    CHECK(e);
    for (size_t t = 0; t < pm->ntets; t++)
        for (int a = 0; a < 4; a++)
            for (int c = a + 1; c < 4; c++) {
                vtx v[4];
                memset(v, 0, sizeof v);
                v[0].id = pm->tets[4 * t + (size_t)a];
                memcpy(v[0].off, pm->tet_off + 12 * t + 3 * (size_t)a, 3);
                v[1].id = pm->tets[4 * t + (size_t)c];
                memcpy(v[1].off, pm->tet_off + 12 * t + 3 * (size_t)c, 3);
                make_row(v, 2, &e[ne++]);
            }
    qsort(e, ne, sizeof *e, row_cmp);
    size_t edges = ne ? 1 : 0;
    for (size_t i = 1; i < ne; i++)
        edges += row_cmp(&e[i], &e[i - 1]) != 0;
    free(e);
    return (long)nverts - (long)edges + (long)pm->ntets;
}

/* Points on the grid of 2^-20 in [0, 1)^3: exact images in a unit box. */
static double grid_unif(uint64_t *s)
{
    return floor(test_unif(s) * 0x1p20) * 0x1p-20;
}

static double *uniform(size_t n, uint64_t seed)
{
    double *X = malloc(n * 3 * sizeof *X);
    CHECK(X);
    uint64_t s = seed;
    for (size_t i = 0; i < 3 * n; i++)
        X[i] = grid_unif(&s);
    return X;
}

static double *lattice(int g, size_t *n)
{
    *n = (size_t)g * g * g;
    double *X = malloc(*n * 3 * sizeof *X);
    CHECK(X);
    size_t m = 0;
    for (int i = 0; i < g; i++)
        for (int j = 0; j < g; j++)
            for (int k = 0; k < g; k++, m++) {
                X[3 * m] = i / 16.0;
                X[3 * m + 1] = j / 16.0;
                X[3 * m + 2] = k / 16.0;
            }
    return X;
}

/* A wall-normal coordinate: a wall of points at 0 or 1 (a quarter of
 * the points), the rest crowded towards the walls (s^2 from the nearer
 * one); on the 2^-20 grid. */
static double wall_normal(size_t i, uint64_t *s)
{
    double u = test_unif(s);
    double y = i % 8 == 0 ? 0 : i % 8 == 1 ? 1
             : u < 0.5    ? 2 * u * 2 * u * 0.5
                          : 1 - (2 - 2 * u) * (2 - 2 * u) * 0.5;
    return floor(y * 0x1p20) * 0x1p-20;
}

/* A channel (walls at y = 0 and 1, x and z uniform), or a duct (walls
 * in z too). */
static double *channel(size_t n, uint64_t seed, int duct)
{
    double *X = malloc(n * 3 * sizeof *X);
    CHECK(X);
    uint64_t s = seed;
    for (size_t i = 0; i < n; i++) {
        X[3 * i] = grid_unif(&s);
        X[3 * i + 1] = wall_normal(i, &s);
        X[3 * i + 2] = duct ? wall_normal(i / 8 + i, &s) : grid_unif(&s);
    }
    return X;
}

/* Whether row r of batch a (a part's cells) is row want_row of w (the
 * whole set's): every quantity to the bit, the neighbours and their face
 * areas too. */
static int same_cell(const fdt_voronoi *a, size_t r, const fdt_voronoi *w, size_t want_row)
{
    int same = !memcmp(&fdt_voronoi_volumes(a)[r], &fdt_voronoi_volumes(w)[want_row], 8) &&
               !memcmp(&fdt_voronoi_areas(a)[r], &fdt_voronoi_areas(w)[want_row], 8) &&
               !memcmp(&fdt_voronoi_centroids(a)[3 * r], &fdt_voronoi_centroids(w)[3 * want_row],
                       24) &&
               !memcmp(&fdt_voronoi_densities(a)[r], &fdt_voronoi_densities(w)[want_row], 8) &&
               fdt_voronoi_num_faces(a)[r] == fdt_voronoi_num_faces(w)[want_row] &&
               fdt_voronoi_flags(a)[r] == fdt_voronoi_flags(w)[want_row];
    size_t ca, cw;
    const fdt_vid *ia, *iw;
    const double *aa, *aw;
    CHECK(fdt_voronoi_neighbors(a, (fdt_vid)r, &ca, &ia, &aa) == FDT_OK);
    CHECK(fdt_voronoi_neighbors(w, (fdt_vid)want_row, &cw, &iw, &aw) == FDT_OK);
    return same && ca == cw && (!ca || (!memcmp(ia, iw, ca * sizeof *ia) &&
                                        !memcmp(aa, aw, ca * sizeof *aa)));
}

/*
 * The mesh in parts (fdt_periodic_parts_make with part_points a part, each
 * part built on threads): every part's rows sorted and each part's least
 * vertices its own points; all of them together, sorted, equal want's
 * (the one-part build's rows, tets then hull faces). Where the points'
 * cells can be cut by the box (fdt_periodic_cells accepts it), each part's
 * cells from its stars (fdt_periodic_part_cells, a streamed run's) are
 * the whole set's to the bit, and every point is in one part's.
 */
static void parts_equal(const char *name, const double *X, size_t n, const fdt_periodic_box *pb,
                        uint32_t part_points, int threads, const fdt_periodic_mesh *one,
                        const rows *want, const rows *wanth)
{
    fdt_periodic_parts p;
    CHECK(fdt_periodic_parts_make(X, (uint32_t)n, pb, part_points, &p) == FDT_OK);
    /* the box's walls across the axes that are not periodic (which the
     * mesh ignores) at the points' extent, so that the cells are cut there */
    fdt_periodic_box wb = *pb;
    const fdt_periodic_box *b = &wb;
    for (int k = 0; k < 3; k++)
        if (!(pb->axes >> k & 1)) {
            wb.lo[k] = p.ylo[k];
            wb.hi[k] = p.yhi[k];
        }
    size_t cap = 1024, nt = 0, nh = 0, owned = 0;
    uint32_t *ids = malloc(cap * 4 * sizeof *ids), *hids = malloc(cap * 3 * sizeof *hids);
    int8_t *off = malloc(cap * 12), *hoff = malloc(cap * 9);
    CHECK(ids && hids && off && hoff);
    /* the whole set's cells (one: the one-part build's mesh), where the
     * box holds them */
    fdt_voronoi *whole = NULL;
    {
        char d[512];
        int32_t *dup = malloc(n * sizeof *dup);
        CHECK(dup);
        for (size_t i = 0; i < n; i++)
            dup[i] = (int32_t)i;
        if (fdt_periodic_cells((const int32_t *)one->tets, one->tet_off, one->ntets,
                               (const int32_t *)one->hull, one->nhull, X, n, dup, b, threads, 1,
                               0, &whole, d, sizeof d) != FDT_OK)
            whole = NULL; /* a point outside a wall's box: no cells to compare */
        free(dup);
    }
    size_t celled = 0, cells_off = 0;
    for (uint32_t k = 0; k < p.nparts; k++) {
        fdt_periodic_mesh pm;
        char diag[512];
        int err = fdt_periodic_build_part(X, (uint32_t)n, NULL, b, &p, k, threads, whole != NULL,
                                          &pm, diag, sizeof diag);
        EXPECTF(err == FDT_OK, "%s: part %u of %u: %d (%s)", name, k, p.nparts, err, diag);
        CHECK(err == FDT_OK);
        if (whole) {
            fdt_voronoi *c = NULL;
            fdt_vshort sh = {-1, -1, INFINITY};
            err = fdt_periodic_part_cells(&pm, X, (uint32_t)n, 0, NULL, &p, k, b, threads, 1, 0,
                                          &c, &sh, diag, sizeof diag);
            EXPECTF(err == FDT_OK, "%s: part %u's cells: %d (%s)", name, k, err, diag);
            CHECK(err == FDT_OK);
            const fdt_vid *cid = fdt_voronoi_ids(c);
            for (size_t r = 0; r < fdt_voronoi_num_points(c); r++)
                cells_off += !same_cell(c, r, whole, (size_t)cid[r]);
            celled += fdt_voronoi_num_points(c);
            fdt_voronoi_free(&c);
        }
        owned += fdt_periodic_part_points(&p, k, (uint32_t)n);
        size_t bad = 0;
        for (size_t i = 0; i < pm.ntets; i++) {
            const uint32_t *t = pm.tets + 4 * i;
            bad += i && t[-4] > t[0]; /* sorted by least vertex */
            if (p.nparts > 1) {
                double x = X[3 * (size_t)t[0] + p.axis];
                bad += !(x >= p.cut[k] && x < p.cut[k + 1]); /* its own */
            }
        }
        EXPECTF(!bad, "%s: part %u of %u: %zu tets unsorted or not its own", name, k, p.nparts,
                bad);
        while (nt + pm.ntets > cap || nh + pm.nhull > cap) {
            cap *= 2;
            CHECK((ids = realloc(ids, cap * 4 * sizeof *ids)) &&
                  (hids = realloc(hids, cap * 3 * sizeof *hids)) &&
                  (off = realloc(off, cap * 12)) && (hoff = realloc(hoff, cap * 9)));
        }
        if (pm.ntets) { /* an empty slab's arrays are NULL */
            memcpy(ids + 4 * nt, pm.tets, pm.ntets * 4 * sizeof *ids);
            memcpy(off + 12 * nt, pm.tet_off, pm.ntets * 12);
        }
        if (pm.nhull) {
            memcpy(hids + 3 * nh, pm.hull, pm.nhull * 3 * sizeof *hids);
            memcpy(hoff + 9 * nh, pm.hull_off, pm.nhull * 9);
        }
        nt += pm.ntets;
        nh += pm.nhull;
        fdt_periodic_free(&pm);
    }
    EXPECTF(owned == n, "%s: the parts own %zu of %zu points", name, owned, n);
    if (whole) {
        EXPECTF(celled == n && !cells_off,
                "%s: %u parts: %zu cells of %zu points, %zu not the whole set's", name, p.nparts,
                celled, n, cells_off);
        fdt_voronoi_free(&whole);
    }
    rows got = mesh_rows(ids, off, nt, 4), goth = mesh_rows(hids, hoff, nh, 3);
    EXPECTF(same_rows(&got, want) && same_rows(&goth, wanth),
            "%s: %u parts of %u points, %d threads: %zu tets, %zu hull faces, one part %zu, %zu",
            name, p.nparts, part_points, threads, got.n, goth.n, want->n, wanth->n);
    free(got.r);
    free(goth.r);
    free(ids);
    free(off);
    free(hids);
    free(hoff);
    fdt_periodic_parts_free(&p);
}

/* Each axis's extent of the n points X onto [0, 0.999) (a flat one to
 * 0.5): inside the unit periodic box, its extreme points 0.001 apart
 * across the box's sides. */
static void to_unit_box(double *X, size_t n)
{
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++)
        lo[k] = hi[k] = X[k];
    for (size_t i = 0; i < 3 * n; i++) {
        lo[i % 3] = X[i] < lo[i % 3] ? X[i] : lo[i % 3];
        hi[i % 3] = X[i] > hi[i % 3] ? X[i] : hi[i % 3];
    }
    for (size_t i = 0; i < 3 * n; i++) {
        double w = hi[i % 3] - lo[i % 3];
        X[i] = w > 0 ? (X[i] - lo[i % 3]) / w * 0.999 : 0.5;
    }
}

/*
 * A shell as wide as the periodic cube: a point's neighbour across
 * the shell's inside and the same point's image across the box's side are
 * both its neighbours, so its list holds one input id twice; in parts, the
 * cells' neighbour lists must still be the whole set's (ties in the
 * images' coordinates, not the batch's numbering).
 */
static void shell_parts(size_t n)
{
    double *X = malloc(n * 3 * sizeof *X);
    CHECK(X);
    uint64_t s = 11;
    for (size_t i = 0; i < n; i++) {
        double z = 2 * test_unif(&s) - 1, phi = 6.283185307179586 * test_unif(&s),
               r = sqrt(1 - z * z);
        X[3 * i] = r * cos(phi);
        X[3 * i + 1] = r * sin(phi);
        X[3 * i + 2] = z;
    }
    to_unit_box(X, n); /* the extreme points 0.001 apart across the box's sides */
    fdt_periodic_box b = {7, {0, 0, 0}, {1, 1, 1}};
    fdt_periodic_mesh pm = build(X, n, &b, 1, "shell");
    rows want = mesh_rows(pm.tets, pm.tet_off, pm.ntets, 4);
    rows wanth = mesh_rows(pm.hull, pm.hull_off, pm.nhull, 3);
    parts_equal("shell", X, n, &b, (uint32_t)(n / 6), 2, &pm, &want, &wanth);
    printf("shell: %zu points, %zu tets: the same cells in parts of %zu\n", n, pm.ntets, n / 6);
    free(want.r);
    free(wanth.r);
    fdt_periodic_free(&pm);
    free(X);
}

static void against_reference(const char *name, const double *X, size_t n, unsigned axes,
                              const double lo[3], const double hi[3])
{
    fdt_periodic_box b = {axes, {lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
    fdt_periodic_mesh pm = build(X, n, &b, 1, name);
    rows got = mesh_rows(pm.tets, pm.tet_off, pm.ntets, 4);
    rows goth = mesh_rows(pm.hull, pm.hull_off, pm.nhull, 3);
    rows want, wanth;
    reference(X, n, &b, &want, &wanth);
    EXPECTF(same_rows(&got, &want), "%s: %zu tets, the reference %zu", name, got.n, want.n);
    EXPECTF(same_rows(&goth, &wanth), "%s: %zu hull faces, the reference %zu", name, goth.n,
            wanth.n);
    char msg[256];
    EXPECTF(fdt_periodic_check_mesh(X, n, (const int32_t *)pm.tets, pm.tet_off, pm.ntets,
                                    (const int32_t *)pm.hull, pm.hull_off, pm.nhull, &b, msg,
                                    sizeof msg) == FDT_OK,
            "%s: the check: %s", name, msg);
    /* the output is sorted and normalised already */
    EXPECT(got.n == pm.ntets);
    /* the rows shuffled and sorted again (frontdt-mpi's gather) */
    uint32_t *sid = malloc(pm.ntets * 4 * sizeof *sid);
    int8_t *soff = malloc(pm.ntets * 12);
    CHECK(sid && soff);
    for (size_t i = 0; i < pm.ntets; i++) {
        size_t from = (i * 7919) % pm.ntets; /* a permutation: 7919 is prime, above n */
        memcpy(sid + 4 * i, pm.tets + 4 * from, 4 * sizeof *sid);
        memcpy(soff + 12 * i, pm.tet_off + 12 * from, 12);
    }
    EXPECT(pm.ntets % 7919 != 0);
    EXPECT(fdt_periodic_sort_rows(&sid, &soff, pm.ntets, 4, n) == FDT_OK);
    EXPECTF(!memcmp(sid, pm.tets, pm.ntets * 4 * sizeof *sid) &&
            !memcmp(soff, pm.tet_off, pm.ntets * 12), "%s: the rows sorted again differ", name);
    EXPECT(fdt_periodic_sort_rows(&sid, &soff, pm.ntets, 4, pm.tets[4 * (pm.ntets - 1)]) ==
           FDT_EINVAL);
    free(sid);
    free(soff);
    fdt_periodic_mesh p3 = build(X, n, &b, 3, name);
    rows got3 = mesh_rows(p3.tets, p3.tet_off, p3.ntets, 4);
    EXPECTF(same_rows(&got, &got3), "%s: 3 threads differ", name);
    if (axes == 7)
        EXPECTF(euler_vet(&pm, n) == 0, "%s: V - E + T = %ld", name, euler_vet(&pm, n));
    /* in parts (streamed, MPI): slabs of a fifth, a seventeenth and 97
     * points (the margin of a thin slab reaching over many of them) */
    const uint32_t sizes[3] = {(uint32_t)(n / 5), (uint32_t)(n / 17), 97};
    for (int t = 0; t < 3; t++)
        parts_equal(name, X, n, &b, sizes[t], 1 + 2 * (t == 1), &pm, &got, &goth);
    printf("%s (axes %u): %zu tets, %zu hull faces, %zu images, %d round(s): as the reference\n",
           name, axes, pm.ntets, pm.nhull, pm.images, pm.rounds);
    free(got.r);
    free(goth.r);
    free(want.r);
    free(wanth.r);
    free(got3.r);
    fdt_periodic_free(&pm);
    fdt_periodic_free(&p3);
}

/* The check of a periodic mesh (fdt_periodic_check_mesh) refuses each
 * corruption with its reason; a copy of the mesh's arrays a case. */
static int check_case(const double *X, size_t n, const fdt_periodic_mesh *pm,
                      const fdt_periodic_box *b, int what, const char *want)
{
    size_t nt = pm->ntets, nh = pm->nhull;
    int32_t *T = malloc((4 * nt + 4) * sizeof *T), *H = malloc((3 * nh + 3) * sizeof *H);
    int8_t *O = malloc(12 * nt + 12), *HO = malloc(9 * nh + 9);
    CHECK(T && H && O && HO);
    memcpy(T, pm->tets, 4 * nt * sizeof *T);
    memcpy(O, pm->tet_off, 12 * nt);
    if (nh) {
        memcpy(H, pm->hull, 3 * nh * sizeof *H);
        memcpy(HO, pm->hull_off, 9 * nh);
    }
    switch (what) {
    case 1: nt--; break;                                    /* a tet dropped */
    case 2: memcpy(T, T + 4, 4 * sizeof *T);                /* a tet twice */
            memcpy(O, O + 12, 12); break;
    case 3: O[3 * 1] = (int8_t)(O[3 * 1] + 1); break;       /* an offset off */
    case 4: T[1] = T[0]; break;                             /* two images of a point */
    case 5: T[2] = (int32_t)n; break;                       /* past the points */
    case 6: nh--; break;                                    /* a hull face dropped */
    case 7: memcpy(H + 3 * nh, T, 3 * sizeof *T);           /* an inner face on the hull */
            memcpy(HO + 9 * nh, O, 9); nh++; break;
    case 8: n++; break;                                     /* a point in no tet */
    case 9: memcpy(T + 4 * nt, T, 4 * sizeof *T);           /* a tet listed twice */
            memcpy(O + 12 * nt, O, 12); nt++; break;
    case 10: memcpy(H + 3 * nh, H, 3 * sizeof *H);          /* a hull face twice */
             memcpy(HO + 9 * nh, HO, 9); nh++; break;
    default: break;
    }
    char msg[256] = "";
    int rc = fdt_periodic_check_mesh(X, n, T, O, nt, H, HO, nh, b, msg, sizeof msg);
    int ok = want ? rc == FDT_ECHECK && strstr(msg, want) != NULL : rc == FDT_OK;
    EXPECTF(ok, "check case %d: %d, \"%s\" (want %s)", what, rc, msg, want ? want : "OK");
    free(T);
    free(H);
    free(O);
    free(HO);
    return ok;
}

static void check_corruptions(void)
{
    size_t n = 800;
    double *U = uniform(n + 2, 9);
    memcpy(U + 3 * n, U, 3 * sizeof *U); /* a duplicate of point 0, then one more point */
    fdt_periodic_box b = {7, {0, 0, 0}, {1, 1, 1}};
    fdt_periodic_mesh pm = build(U, n, &b, 1, "check uniform");
    check_case(U, n + 1, &pm, &b, 0, NULL); /* the duplicate, merged: fine */
    check_case(U, n, &pm, &b, 1, "no other tet");
    check_case(U, n, &pm, &b, 2, "same side");
    check_case(U, n, &pm, &b, 3, "");
    check_case(U, n, &pm, &b, 4, "two images of point");
    check_case(U, n, &pm, &b, 9, "in 3 tets");
    check_case(U, n, &pm, &b, 5, "not one of the");
    check_case(U, n + 1, &pm, &b, 8, "point 801 is in no tet");
    /* the same points and box times 2^500 and 2^-500 (the same mesh: every
     * predicate's sign is the same): the volumes' sum neither overflows
     * (it was inf, nan: the mesh refused) nor underflows */
    for (int e = -500; e <= 500; e += 1000) {
        double *S = malloc(3 * (n + 2) * sizeof *S);
        CHECK(S);
        for (size_t i = 0; i < 3 * (n + 2); i++)
            S[i] = ldexp(U[i], e);
        fdt_periodic_box bs = {7, {0, 0, 0}, {ldexp(1, e), ldexp(1, e), ldexp(1, e)}};
        check_case(S, n, &pm, &bs, 0, NULL);
        check_case(S, n, &pm, &bs, 1, "no other tet");
        free(S);
    }
    /* a point moved by half the spacing: the old tets are no longer its
     * Delaunay mesh (or fold over) */
    U[3 * 5] += 0.05;
    U[3 * 5 + 1] += 0.03;
    char msg[256];
    EXPECT(fdt_periodic_check_mesh(U, n, (const int32_t *)pm.tets, pm.tet_off, pm.ntets, NULL,
                                   NULL, 0, &b, msg, sizeof msg) == FDT_ECHECK);
    fdt_periodic_free(&pm);
    free(U);
    /* x and z periodic: the hull */
    double *C = channel(n, 7, 0);
    b.axes = 5;
    pm = build(C, n, &b, 1, "check channel");
    check_case(C, n, &pm, &b, 0, NULL);
    check_case(C, n, &pm, &b, 6, "no other tet");
    check_case(C, n, &pm, &b, 7, "crosses periodic axis");
    check_case(C, n, &pm, &b, 10, "listed twice");
    fdt_periodic_free(&pm);
    free(C);
    printf("check: a valid mesh passes, each corruption refused with its reason\n");
}

/* Random doubles in a box whose images are not doubles: threads and a
 * shuffle agree, and the Euler characteristic. */
static void inexact_box(size_t n)
{
    const double lo[3] = {0.1, -0.7, 3.3}, hi[3] = {1.3, 0.35, 4.1};
    double *X = malloc(n * 3 * sizeof *X);
    CHECK(X);
    uint64_t s = 99;
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) {
            X[3 * i + k] = lo[k] + test_unif(&s) * (hi[k] - lo[k]);
            if (X[3 * i + k] >= hi[k])
                X[3 * i + k] = lo[k];
        }
    fdt_periodic_box b = {7, {lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
    fdt_periodic_mesh p1 = build(X, n, &b, 1, "inexact"), p3 = build(X, n, &b, 3, "inexact t3");
    rows r1 = mesh_rows(p1.tets, p1.tet_off, p1.ntets, 4);
    rows r3 = mesh_rows(p3.tets, p3.tet_off, p3.ntets, 4);
    EXPECT(same_rows(&r1, &r3));
    EXPECTF(euler_vet(&p1, n) == 0, "inexact: V - E + T = %ld", euler_vet(&p1, n));
    EXPECT(p1.nhull == 0);
    /* shuffled: the same tets under the permutation */
    size_t *perm;
    double *Y = test_shuffle(X, n, s, &perm); /* Y[i] = X[perm[i]] */
    fdt_periodic_mesh ps = build(Y, n, &b, 2, "inexact shuffled");
    uint32_t *ids = malloc(ps.ntets * 4 * sizeof *ids);
    CHECK(ids);
    for (size_t i = 0; i < 4 * ps.ntets; i++)
        ids[i] = (uint32_t)perm[ps.tets[i]];
    rows rs = mesh_rows(ids, ps.tet_off, ps.ntets, 4);
    EXPECT(same_rows(&r1, &rs));
    printf("inexact box: %zu tets, %zu images (%zu exact calls), shuffled and 3 threads the "
           "same\n", p1.ntets, p1.images, p1.pc.orient_exact + p1.pc.insphere_exact);
    free(ids);
    free(rs.r);
    free(r1.r);
    free(r3.r);
    free(perm);
    free(Y);
    free(X);
    fdt_periodic_free(&p1);
    fdt_periodic_free(&p3);
    fdt_periodic_free(&ps);
}

static void errors(void)
{
    double X[3 * 8];
    uint64_t s = 5;
    for (int i = 0; i < 24; i++)
        X[i] = test_unif(&s);
    fdt_periodic_mesh pm;
    char diag[512];
    fdt_periodic_box b = {7, {0, 0, 0}, {1, 1, 1}};
    X[3 * 5 + 1] = 1.0; /* on the upper wall: outside [0, 1) */
    EXPECT(fdt_periodic_build(X, 8, NULL, &b, 1, &pm, diag, sizeof diag) == FDT_EINVAL);
    EXPECTF(strstr(diag, "point 5 has y = 1") != NULL, "%s", diag);
    X[3 * 5 + 1] = 0.5;
    fdt_periodic_box none = {0, {0, 0, 0}, {1, 1, 1}};
    EXPECT(fdt_periodic_build(X, 8, NULL, &none, 1, &pm, diag, sizeof diag) == FDT_EINVAL);
    fdt_periodic_box empty = {1, {0, 0, 0}, {0, 1, 1}};
    EXPECT(fdt_periodic_build(X, 8, NULL, &empty, 1, &pm, diag, sizeof diag) == FDT_EINVAL);
    /* 8 points in a periodic cube: the mesh needs images of one point in
     * a tet */
    int err = fdt_periodic_build(X, 8, NULL, &b, 1, &pm, diag, sizeof diag);
    EXPECTF(err == FDT_EDEGENERATE && strstr(diag, "one copy of the box"), "%d %s", err, diag);
    printf("errors: %s\n", diag);
    /* a flat set periodic in x and y: no 3-D mesh, with its images or not */
    double F[3 * 40];
    for (int i = 0; i < 40; i++) {
        F[3 * i] = test_unif(&s);
        F[3 * i + 1] = test_unif(&s);
        F[3 * i + 2] = 0.5;
    }
    fdt_periodic_box bxy = {3, {0, 0, 0}, {1, 1, 1}};
    err = fdt_periodic_build(F, 40, NULL, &bxy, 1, &pm, diag, sizeof diag);
    EXPECTF(err == FDT_EDEGENERATE && strstr(diag, "3-D"), "flat x y: %d %s", err, diag);
    /* the same periodic in z too: a point's z-images are its neighbours */
    err = fdt_periodic_build(F, 40, NULL, &b, 1, &pm, diag, sizeof diag);
    EXPECTF(err == FDT_EDEGENERATE && strstr(diag, "one copy of the box"), "flat x y z: %d %s",
            err, diag);
    fdt_periodic_box huge = {2, {0, -0x1p600, 0}, {1, 1, 1}};
    EXPECT(fdt_periodic_build(X, 8, NULL, &huge, 1, &pm, diag, sizeof diag) == FDT_EINVAL &&
           strstr(diag, "2^500"));
    /* renumbering needs the merge's increasing first indices */
    fdt_periodic_mesh one = {0};
    int32_t orig[3] = {0, 2, 1};
    EXPECT(fdt_periodic_renumber(&one, orig, 3) == FDT_EINTERNAL);
}

/* Coordinates, then index: the order that puts a point's copies side by
 * side, its first occurrence first. */
static const double *dedup_pts;
static int dedup_cmp(const void *x, const void *y)
{
    uint32_t a = *(const uint32_t *)x, b = *(const uint32_t *)y;
    int c = 0;
    for (int k = 0; k < 3 && !c; k++) {
        double u = dedup_pts[3 * (size_t)a + k], v = dedup_pts[3 * (size_t)b + k];
        c = u < v ? -1 : u > v;
    }
    return c ? c : a < b ? -1 : a > b;
}

/* A gen_points family scaled into [0, 0.999)^3 (distinct points, first
 * occurrences in input order), periodic in x, y and z: the parts of 300
 * points on 3 threads and of 40 on one give the one-part build's rows. */
static void family_parts(const char *gen, const char *fam, size_t n)
{
    size_t got;
    double *X = test_gen_family(gen, fam, n, 3, &got);
    to_unit_box(X, got);
    uint32_t *ord = malloc((got ? got : 1) * sizeof *ord);
    uint8_t *keep = calloc(got ? got : 1, 1);
    CHECK(ord && keep);
    for (size_t i = 0; i < got; i++)
        ord[i] = (uint32_t)i;
    dedup_pts = X;
    qsort(ord, got, sizeof *ord, dedup_cmp);
    for (size_t i = 0; i < got; i++)
        keep[ord[i]] = i == 0 || X[3 * (size_t)ord[i]] != X[3 * (size_t)ord[i - 1]] ||
                       X[3 * (size_t)ord[i] + 1] != X[3 * (size_t)ord[i - 1] + 1] ||
                       X[3 * (size_t)ord[i] + 2] != X[3 * (size_t)ord[i - 1] + 2];
    size_t m = 0;
    for (size_t i = 0; i < got; i++)
        if (keep[i])
            memmove(X + 3 * m++, X + 3 * i, 3 * sizeof *X);
    free(ord);
    free(keep);
    fdt_periodic_box b = {7, {0, 0, 0}, {1, 1, 1}};
    fdt_periodic_mesh pm;
    char diag[512];
    int err = fdt_periodic_build(X, (uint32_t)m, NULL, &b, 2, &pm, diag, sizeof diag);
    EXPECTF(err == FDT_OK, "%s: the one-part build: %d (%s)", fam, err, diag);
    if (err == FDT_OK) {
        rows want = mesh_rows(pm.tets, pm.tet_off, pm.ntets, 4);
        rows wanth = mesh_rows(pm.hull, pm.hull_off, pm.nhull, 3);
        parts_equal(fam, X, m, &b, 300, 3, &pm, &want, &wanth);
        parts_equal(fam, X, m, &b, 40, 1, &pm, &want, &wanth);
        printf("%s: %zu points, %zu tets: the same in parts of 300 and 40\n", fam, m,
               pm.ntets);
        free(want.r);
        free(wanth.r);
        fdt_periodic_free(&pm);
    }
    free(X);
}

int main(int argc, char **argv)
{
    /* suite long: every gen_points family in parts (argv[1]: gen_points) */
    if (argc > 1) {
        int families = test_each_family(argv[1], 3000, family_parts);
        EXPECTF(families > 30, "%d families", families);
        return test_report("periodic families");
    }
    const double lo[3] = {0, 0, 0}, hi[3] = {1, 1, 1};
    size_t n = 3000;
    double *U = uniform(n, 1);
    against_reference("uniform", U, n, 7, lo, hi);
    /* periodic in x and z only, uniform points have a single lowest
     * point: the periodic set's hull is the lattice of its images, and
     * its tets join images of one point (no 1-sheet triangulation) */
    fdt_periodic_mesh pm;
    char diag[512];
    fdt_periodic_box bxz = {5, {0, 0, 0}, {1, 1, 1}};
    int err = fdt_periodic_build(U, (uint32_t)n, NULL, &bxz, 2, &pm, diag, sizeof diag);
    EXPECTF(err == FDT_EDEGENERATE && strstr(diag, "not flat"), "%d %s", err, diag);
    free(U);
    size_t nl;
    double *L = lattice(8, &nl); /* 8^3 points, spacing 1/16, box [0, 1/2) */
    const double lhi[3] = {0.5, 0.5, 0.5};
    against_reference("lattice", L, nl, 7, lo, lhi);
    against_reference("lattice", L, nl, 5, lo, lhi);
    free(L);
    double *C = channel(n, 3, 0);
    against_reference("channel", C, n, 5, lo, hi);
    free(C);
    C = channel(n, 4, 1);
    against_reference("duct", C, n, 1, lo, hi);
    free(C);
    /* walls not quite flat (the wall points moved by up to 2^-30): flat
     * tets on them with spheres far beyond (periodic.c's ball_reach) */
    C = channel(n, 5, 0);
    uint64_t bs = 6;
    for (size_t i = 0; i < n; i++)
        if (C[3 * i + 1] == 0.0 || C[3 * i + 1] == 1.0)
            C[3 * i + 1] += (C[3 * i + 1] == 0.0 ? 1 : -1) * floor(test_unif(&bs) * 4) * 0x1p-30;
    against_reference("bumpy channel", C, n, 5, lo, hi);
    free(C);
    shell_parts(1500);
    inexact_box(4000);
    check_corruptions();
    errors();
    return test_report("periodic");
}
