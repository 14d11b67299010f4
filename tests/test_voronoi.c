/*
 * Tests for src/mesh/voronoi.c (fdt_voronoi_compute), against facts that
 * do not come from the module:
 *  - a cubic lattice (every point cospherical with many others): each
 *    cell is a unit cube cut by the box, so volumes 1, 1/2, 1/4, 1/8,
 *    areas and face counts known, the diagonal edges' faces of zero area;
 *  - uniform and clustered points in a box: the volumes add up to the
 *    box's, each interior face has one area seen from both sides, the wall
 *    faces add up to the box's surface, and every cell summed from its tets
 *    equals the same cell cut from the box by its neighbours' bisectors
 *    (src/geom/cell.c, the other method) to 1e-10;
 *  - the same bits for a shuffled input, and for meshes and cells made on
 *    1, 3 and 7 threads;
 *  - DTFE: the points' tet volumes add up to 4 times the hull's volume;
 *  - refusals: a point outside a given box, a streamed result.
 * voro++ itself is compared in tests/voronoi_voro.py (CLI, end to end).
 */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include <gmp.h>

#include "frontdt.h"
#include "geom/cell.h"
#include "testutil.h"

static fdt_voronoi *cells_t(fdt_result *r, const double *xyz, size_t n, const double *box,
                            int threads)
{
    fdt_voronoi_options o;
    fdt_default_voronoi_options(&o);
    o.neighbors = 1;
    o.threads = threads;
    if (box) {
        o.box_given = 1;
        memcpy(o.box, box, sizeof o.box);
    }
    fdt_voronoi *v = NULL;
    char diag[256];
    int err = fdt_voronoi_compute(r, xyz, n, &o, &v, diag, sizeof diag);
    if (err)
        fprintf(stderr, "fdt_voronoi_compute: %s: %s\n", fdt_strerror(err), diag);
    CHECK(err == FDT_OK);
    return v;
}

static fdt_voronoi *cells(fdt_result *r, const double *xyz, size_t n, const double *box)
{
    return cells_t(r, xyz, n, box, 1);
}

static int close_to(double a, double b, double rel)
{
    return fabs(a - b) <= rel * fmax(fabs(a), fabs(b)) + 1e-300;
}

/* k^3 lattice points 0..k-1: cell (i,j,l) is a unit cube halved on each
 * wall it touches. */
static void test_lattice(int k)
{
    size_t n = (size_t)k * k * k;
    double *xyz = malloc(3 * n * sizeof *xyz);
    CHECK(xyz);
    for (size_t i = 0; i < n; i++) {
        xyz[3 * i] = (double)(i % (size_t)k);
        xyz[3 * i + 1] = (double)(i / (size_t)k % (size_t)k);
        xyz[3 * i + 2] = (double)(i / ((size_t)k * k));
    }
    fdt_result *r = test_triangulate(xyz, n, 1, 0);
    fdt_voronoi *v = cells(r, xyz, n, NULL);
    const double *vol = fdt_voronoi_volumes(v), *area = fdt_voronoi_areas(v);
    const int32_t *nf = fdt_voronoi_num_faces(v);
    double sum = 0;
    for (size_t i = 0; i < n; i++) {
        double side[3];
        for (int d = 0; d < 3; d++) {
            double c = xyz[3 * i + d];
            side[d] = c == 0 || c == k - 1 ? 0.5 : 1.0;
        }
        double want_v = side[0] * side[1] * side[2];
        double want_a = 2 * (side[0] * side[1] + side[1] * side[2] + side[0] * side[2]);
        EXPECTF(close_to(vol[i], want_v, 1e-12), "lattice %d point %zu volume %.17g, want %g", k,
                i, vol[i], want_v);
        EXPECTF(close_to(area[i], want_a, 1e-12), "lattice %d point %zu area %.17g, want %g", k,
                i, area[i], want_a);
        EXPECTF(nf[i] == 6, "lattice %d point %zu has %d faces", k, i, (int)nf[i]);
        size_t cnt;
        const fdt_vid *ids;
        const double *fa;
        CHECK(fdt_voronoi_neighbors(v, (fdt_vid)i, &cnt, &ids, &fa) == FDT_OK);
        EXPECT(cnt == 6);
        sum += vol[i];
    }
    EXPECTF(close_to(sum, pow(k - 1, 3), 1e-13), "lattice %d volumes add up to %.17g", k, sum);
    /* Interior points have Delaunay neighbours across face and body
     * diagonals whose Voronoi faces have no area. */
    if (k > 2)
        EXPECT(fdt_voronoi_zero_faces(v) > 0);
    fdt_voronoi_free(&v);
    fdt_result_free(&r);
    free(xyz);
}

/* Point i's cell cut from the box, the other method. */
static void cut_cell(const double *xyz, fdt_result *r, fdt_vid i, const double box[6],
                     double *vol, double *area)
{
    fdt_cell c;
    fdt_cell_init(&c);
    const double *p = xyz + 3 * (size_t)i;
    double lo[3], hi[3];
    for (int d = 0; d < 3; d++) {
        lo[d] = box[d] - p[d];
        hi[d] = box[d + 3] - p[d];
    }
    CHECK(fdt_cell_box(&c, lo, hi) == 0);
    size_t cnt;
    const fdt_vid *ids;
    CHECK(fdt_result_vertex_neighbors(r, i, &cnt, &ids) == FDT_OK);
    for (size_t e = 0; e < cnt; e++) {
        double nrm[3];
        for (int d = 0; d < 3; d++)
            nrm[d] = xyz[3 * (size_t)ids[e] + d] - p[d];
        CHECK(fdt_cell_cut(&c, nrm, 0.5 * (nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]),
                           ids[e]) >= 0);
    }
    double cen[3];
    fdt_cell_measure(&c, vol, area, cen, NULL);
    fdt_cell_free(&c);
}

static void test_box_sums(size_t n, int clustered, uint64_t seed)
{
    double *xyz = test_cloud(n, clustered, seed);
    const double box[6] = {-0.25, 0, -0.5, 1, 1.5, 1};
    double bvol = 1.25 * 1.5 * 1.5, bsurf = 2 * (1.25 * 1.5 + 1.5 * 1.5 + 1.25 * 1.5);
    fdt_result *r = test_triangulate(xyz, n, 1, 0);
    fdt_voronoi *v = cells(r, xyz, n, box);
    const double *vol = fdt_voronoi_volumes(v), *area = fdt_voronoi_areas(v);
    const double *cen = fdt_voronoi_centroids(v);
    const uint8_t *fl = fdt_voronoi_flags(v);
    double sum = 0, walls = 0;
    size_t summed = 0, clipped = 0;
    for (size_t i = 0; i < n; i++) {
        sum += vol[i];
        EXPECT(vol[i] > 0);
        for (int d = 0; d < 3; d++)
            EXPECT(cen[3 * i + d] >= box[d] && cen[3 * i + d] <= box[d + 3]);
        size_t cnt;
        const fdt_vid *ids;
        const double *fa;
        CHECK(fdt_voronoi_neighbors(v, (fdt_vid)i, &cnt, &ids, &fa) == FDT_OK);
        double asum = 0;
        for (size_t e = 0; e < cnt; e++) {
            asum += fa[e];
            if (ids[e] < 0) {
                walls += fa[e];
                continue;
            }
            /* The same face seen from the other side. */
            size_t c2;
            const fdt_vid *i2;
            const double *f2;
            CHECK(fdt_voronoi_neighbors(v, ids[e], &c2, &i2, &f2) == FDT_OK);
            size_t m = 0;
            while (m < c2 && i2[m] != (fdt_vid)i)
                m++;
            /* a face below the noise may be listed by one side only */
            double scale = fmax(area[i], area[ids[e]]);
            EXPECTF(m < c2 ? fabs(fa[e] - f2[m]) <= 1e-10 * scale : fa[e] <= 1e-10 * scale,
                    "face %zu-%d: area %.17g, from the other side %.17g", i, (int)ids[e], fa[e],
                    m < c2 ? f2[m] : -1.0);
        }
        EXPECTF(close_to(asum, area[i], 1e-12), "point %zu: faces add to %.17g, area %.17g", i,
                asum, area[i]);
        double cv, ca;
        cut_cell(xyz, r, (fdt_vid)i, box, &cv, &ca);
        EXPECTF(close_to(cv, vol[i], 1e-10) && close_to(ca, area[i], 1e-10),
                "point %zu (%s): volume %.17g area %.17g, cut from the box %.17g %.17g", i,
                fl[i] & FDT_CELL_CLIPPED ? "clipped" : "summed", vol[i], area[i], cv, ca);
        if (fl[i] & FDT_CELL_CLIPPED)
            clipped++;
        else
            summed++;
    }
    EXPECT(summed > n / 4 && clipped > 0);
    EXPECTF(close_to(sum, bvol, 1e-12), "volumes add up to %.17g, box %.17g", sum, bvol);
    EXPECTF(close_to(walls, bsurf, 1e-12), "wall faces add up to %.17g, box %.17g", walls, bsurf);
    /* DTFE: each tet's volume goes to its 4 points. */
    const double *rho = fdt_voronoi_densities(v);
    double dsum = 0, tsum = 0;
    for (size_t i = 0; i < n; i++)
        dsum += 4 / rho[i];
    const fdt_vid *t = fdt_result_tets(r);
    for (size_t j = 0; j < fdt_result_num_tets(r); j++) {
        const double *a = xyz + 3 * (size_t)t[4 * j];
        double e[3][3];
        for (int m = 0; m < 3; m++)
            for (int d = 0; d < 3; d++)
                e[m][d] = xyz[3 * (size_t)t[4 * j + 1 + m] + d] - a[d];
        tsum += (e[0][0] * (e[1][1] * e[2][2] - e[1][2] * e[2][1]) -
                 e[0][1] * (e[1][0] * e[2][2] - e[1][2] * e[2][0]) +
                 e[0][2] * (e[1][0] * e[2][1] - e[1][1] * e[2][0])) / 6;
    }
    EXPECTF(close_to(dsum, 4 * tsum, 1e-12), "DTFE volumes %.17g, 4 x tets %.17g", dsum, 4 * tsum);
    fdt_voronoi_free(&v);
    fdt_result_free(&r);
    free(xyz);
}

/* The same bits for a shuffled input and for 1 and 3 threads. */
static void test_same_bits(size_t n)
{
    double *xyz = test_cloud(n, 1, 7);
    size_t *perm;
    double *sh = test_shuffle(xyz, n, 99, &perm);
    fdt_result *r1 = test_triangulate(xyz, n, 1, 0), *r3 = test_triangulate(xyz, n, 3, 0);
    fdt_result *rs = test_triangulate(sh, n, 2, 0);
    /* the mesh of 1 and 3 threads, the cells on 1 and 3 threads */
    fdt_voronoi *v1 = cells(r1, xyz, n, NULL), *v3 = cells_t(r3, xyz, n, NULL, 3);
    fdt_voronoi *vs = cells_t(rs, sh, n, NULL, 7);
    const double *a1 = fdt_voronoi_volumes(v1), *a3 = fdt_voronoi_volumes(v3);
    const double *as = fdt_voronoi_volumes(vs);
    const double *c1 = fdt_voronoi_centroids(v1), *cs = fdt_voronoi_centroids(vs);
    size_t diff3 = 0, diffs = 0;
    for (size_t i = 0; i < n; i++) {
        diff3 += memcmp(&a1[i], &a3[i], sizeof a1[i]) != 0;
        diff3 += memcmp(&fdt_voronoi_areas(v1)[i], &fdt_voronoi_areas(v3)[i], sizeof(double)) != 0;
        diffs += memcmp(&a1[perm[i]], &as[i], sizeof a1[i]) != 0;
        diffs += memcmp(c1 + 3 * perm[i], cs + 3 * i, 3 * sizeof *c1) != 0;
        diffs += fdt_voronoi_num_faces(v1)[perm[i]] != fdt_voronoi_num_faces(vs)[i];
        diff3 += memcmp(&fdt_voronoi_densities(v1)[i], &fdt_voronoi_densities(v3)[i],
                        sizeof(double)) != 0;
        diffs += memcmp(&fdt_voronoi_densities(v1)[perm[i]], &fdt_voronoi_densities(vs)[i],
                        sizeof(double)) != 0;
    }
    EXPECTF(diff3 == 0, "%zu values differ between 1 and 3 threads", diff3);
    EXPECTF(diffs == 0, "%zu values differ for the shuffled input", diffs);
    fdt_voronoi_free(&v1);
    fdt_voronoi_free(&v3);
    fdt_voronoi_free(&vs);
    fdt_result_free(&r1);
    fdt_result_free(&r3);
    fdt_result_free(&rs);
    free(xyz);
    free(sh);
    free(perm);
}

/* The cells of points scaled by 2^k are the cells scaled, bit for bit
 * (volumes 2^3k, areas 2^2k, centroids 2^k, densities 2^-3k), wherever the
 * volumes and densities are doubles; beyond, refused (points 1e-151 apart
 * came out volume 0 with no faces, 1e149 apart NaN). */
static void test_scales(void)
{
    size_t n = 2000;
    double *xyz = test_cloud(n, 1, 5), *xs = malloc(3 * n * sizeof *xs);
    CHECK(xs);
    fdt_result *r = test_triangulate(xyz, n, 1, 0);
    fdt_voronoi *v = cells(r, xyz, n, NULL);
    const int ks[] = {-280, -120, 60, 200, 330, -300, 350};
    for (size_t c = 0; c < sizeof ks / sizeof *ks; c++) {
        int k = ks[c];
        for (size_t i = 0; i < 3 * n; i++)
            xs[i] = ldexp(xyz[i], k);
        fdt_result *rk = test_triangulate(xs, n, 2, 0);
        if (k < -290 || k > 340) {
            fdt_voronoi_options o;
            fdt_default_voronoi_options(&o);
            fdt_voronoi *vk = NULL;
            char diag[256];
            int err = fdt_voronoi_compute(rk, xs, n, &o, &vk, diag, sizeof diag);
            EXPECTF(err == FDT_ERANGE && strstr(diag, "would leave what doubles hold"),
                    "2^%d: %s (%s)", k, fdt_strerror(err), diag);
            fdt_result_free(&rk);
            continue;
        }
        fdt_voronoi *vk = cells_t(rk, xs, n, NULL, 3);
        size_t diff = 0;
        for (size_t i = 0; i < n; i++) {
            diff += ldexp(fdt_voronoi_volumes(v)[i], 3 * k) != fdt_voronoi_volumes(vk)[i];
            diff += ldexp(fdt_voronoi_areas(v)[i], 2 * k) != fdt_voronoi_areas(vk)[i];
            diff += ldexp(fdt_voronoi_densities(v)[i], -3 * k) != fdt_voronoi_densities(vk)[i];
            for (int d = 0; d < 3; d++)
                diff += ldexp(fdt_voronoi_centroids(v)[3 * i + d], k) !=
                        fdt_voronoi_centroids(vk)[3 * i + d];
            size_t c1, ck;
            const fdt_vid *id1, *idk;
            const double *a1, *ak;
            CHECK(fdt_voronoi_neighbors(v, (fdt_vid)i, &c1, &id1, &a1) == FDT_OK);
            CHECK(fdt_voronoi_neighbors(vk, (fdt_vid)i, &ck, &idk, &ak) == FDT_OK);
            diff += c1 != ck;
            for (size_t f = 0; f < c1 && f < ck; f++)
                diff += id1[f] != idk[f] || ldexp(a1[f], 2 * k) != ak[f];
        }
        EXPECTF(diff == 0, "2^%d: %zu values are not the unscaled ones scaled", k, diff);
        fdt_voronoi_free(&vk);
        fdt_result_free(&rk);
    }
    fdt_voronoi_free(&v);
    fdt_result_free(&r);
    free(xyz);
    free(xs);
}

static int count_tets(void *user, const fdt_vid *t, size_t count)
{
    (void)user;
    (void)t;
    (void)count;
    return 0;
}

static void test_refusals(void)
{
    size_t n = 200;
    double *xyz = test_cloud(n, 0, 3);
    fdt_result *r = test_triangulate(xyz, n, 1, 0);
    fdt_voronoi_options o;
    fdt_default_voronoi_options(&o);
    o.box_given = 1;
    const double box[6] = {0, 0, 0, 1, 1, 0.5};
    memcpy(o.box, box, sizeof box);
    fdt_voronoi *v = NULL;
    char diag[256];
    EXPECT(fdt_voronoi_compute(r, xyz, n, &o, &v, diag, sizeof diag) == FDT_EINVAL);
    EXPECTF(v == NULL && strstr(diag, "outside the box"), "diag: %s", diag);
    o.box[5] = -1;
    EXPECT(fdt_voronoi_compute(r, xyz, n, &o, &v, diag, sizeof diag) == FDT_EINVAL);
    EXPECTF(strstr(diag, "box is empty"), "diag: %s", diag);
    EXPECT(fdt_voronoi_compute(r, xyz, n - 1, NULL, &v, diag, sizeof diag) == FDT_EINVAL);
    size_t cnt;
    const fdt_vid *ids;
    const double *fa;
    fdt_default_voronoi_options(&o);
    o.threads = -1;
    EXPECT(fdt_voronoi_compute(r, xyz, n, &o, &v, diag, sizeof diag) == FDT_EINVAL);
    o.threads = 0;
    o.struct_size = 8;
    EXPECT(fdt_voronoi_compute(r, xyz, n, &o, &v, diag, sizeof diag) == FDT_EINVAL);
    EXPECT(fdt_voronoi_compute(r, xyz, n, NULL, NULL, diag, sizeof diag) == FDT_EINVAL);
    EXPECT(fdt_default_voronoi_options_sized(&o, 3) == FDT_EINVAL);
    /* a streamed result keeps no tets */
    fdt_settings st;
    fdt_default_settings(&st);
    fdt_context *ctx = NULL;
    CHECK(fdt_open(&ctx, &st) == FDT_OK);
    fdt_result *sr = NULL;
    fdt_sink sink = {sizeof sink, count_tets, NULL, NULL, NULL, NULL};
    CHECK(fdt_triangulate_stream(ctx, xyz, n, &sink, &sr) == FDT_OK);
    fdt_close(&ctx);
    EXPECT(fdt_voronoi_compute(sr, xyz, n, NULL, &v, diag, sizeof diag) == FDT_EINVAL);
    EXPECTF(strstr(diag, "with its tets"), "diag: %s", diag);
    double q[3] = {0.5, 0.5, 0.5}, out;
    fdt_tid t;
    EXPECT(fdt_locate(sr, xyz, n, q, 1, &t, NULL, 1) == FDT_EINVAL);
    EXPECT(fdt_interpolate(sr, xyz, n, xyz, 1, q, 1, FDT_INTERP_LINEAR, 1, &out, NULL, 0) ==
           FDT_EINVAL);
    fdt_result_free(&sr);
    CHECK(fdt_voronoi_compute(r, xyz, n, NULL, &v, NULL, 0) == FDT_OK);
    EXPECT(fdt_voronoi_neighbors(v, 0, &cnt, &ids, &fa) == FDT_EINVAL); /* not kept */
    size_t nv, nf;
    const double *vs;
    const int32_t *fs;
    EXPECT(fdt_voronoi_polyhedron(v, xyz, 0, &nv, &vs, &nf, &fs) == FDT_EINVAL);
    double vbox[6];
    fdt_voronoi_box(v, vbox);
    EXPECT(vbox[0] >= 0 && vbox[3] <= 1 && vbox[0] < vbox[3]);
    EXPECT(fdt_voronoi_num_points(v) == n && fdt_voronoi_num_points(NULL) == 0);
    fdt_voronoi_free(&v);
    fdt_result_free(&r);
    free(xyz);
}

/* The getters' and the lists' refusals, and a merged duplicate's cell. */
static void test_getters(void)
{
    size_t n = 300;
    double *xyz = test_cloud(n, 0, 8);
    memcpy(xyz + 3 * (n - 1), xyz, 3 * sizeof *xyz); /* the last is the first again */
    fdt_result *r = test_triangulate(xyz, n, 1, 0);
    fdt_voronoi *v = cells(r, xyz, n, NULL);
    size_t cnt, nv, nf;
    const fdt_vid *ids;
    const double *fa, *vs;
    const int32_t *fs;
    EXPECT(fdt_voronoi_neighbors(v, -1, &cnt, &ids, &fa) == FDT_EINVAL);
    EXPECT(fdt_voronoi_neighbors(v, (fdt_vid)n, &cnt, &ids, &fa) == FDT_EINVAL);
    EXPECT(fdt_voronoi_neighbors(v, 0, NULL, &ids, &fa) == FDT_EINVAL);
    EXPECT(fdt_voronoi_neighbors(NULL, 0, &cnt, &ids, &fa) == FDT_EINVAL);
    EXPECT(fdt_voronoi_polyhedron(v, xyz, -1, &nv, &vs, &nf, &fs) == FDT_EINVAL);
    EXPECT(fdt_voronoi_polyhedron(v, NULL, 0, &nv, &vs, &nf, &fs) == FDT_EINVAL);
    EXPECT(fdt_voronoi_polyhedron(v, xyz, (fdt_vid)(n - 1), &nv, &vs, &nf, &fs) == FDT_OK &&
           nv == 0 && nf == 0);
    EXPECT(fdt_voronoi_flags(v)[n - 1] == FDT_CELL_MERGED && fdt_voronoi_volumes(v)[n - 1] == 0);
    EXPECT(fdt_voronoi_neighbors(v, (fdt_vid)(n - 1), &cnt, &ids, &fa) == FDT_OK && cnt == 0);
    EXPECT(fdt_voronoi_polyhedron(v, xyz, 0, &nv, &vs, &nf, &fs) == FDT_OK && nv >= 4 && nf >= 4);
    EXPECT(!fdt_voronoi_volumes(NULL) && !fdt_voronoi_areas(NULL) && !fdt_voronoi_centroids(NULL) &&
           !fdt_voronoi_num_faces(NULL) && !fdt_voronoi_densities(NULL) &&
           !fdt_voronoi_flags(NULL) && fdt_voronoi_zero_faces(NULL) == 0);
    fdt_voronoi_box(NULL, NULL);
    fdt_voronoi_free(&v);
    fdt_voronoi_free(&v); /* NULL: nothing */
    fdt_voronoi_free(NULL);
    fdt_result_free(&r);
    free(xyz);
}

/* Two clusters w wide among 2,000 uniform points in the unit cube, one
 * at 0.25, one at the origin: each cell positive (the box's fixed grid
 * summed those of w = 1e-10 to 0), the volumes adding up to the box's,
 * the clusters' DTFE densities those of their tets' exact volumes (GMP
 * rationals) to 1e-6 (1e-4 at w = 1e-12, whose tets are slivers of points
 * a few thousand doubles apart; the box's grid gave 0, and tets of three clustered
 * points and a far one, taken from the far one, came out 1e2 times too
 * large, either sign; long double is not enough for a reference here);
 * below 2^-48 of the box, refused (FDT_ERANGE, the cells could not be
 * cut). */
static void test_tiny_cells(double w)
{
    size_t n = 2060;
    double *xyz = test_cloud(n, 0, 9);
    uint64_t s = 77;
    for (size_t i = 2000; i < n; i++)
        for (int d = 0; d < 3; d++)
            xyz[3 * i + d] = (i < 2030 ? 0.25 : 0.0) + w * test_unif(&s);
    fdt_result *r = test_triangulate(xyz, n, 1, 0);
    fdt_voronoi_options o;
    fdt_default_voronoi_options(&o);
    fdt_voronoi *v = NULL;
    char diag[256];
    int err = fdt_voronoi_compute(r, xyz, n, &o, &v, diag, sizeof diag);
    if (w < 0x1p-48) {
        EXPECTF(err == FDT_ERANGE && strstr(diag, "beyond what doubles hold"),
                "w = %g: %s (%s)", w, fdt_strerror(err), diag);
        /* the same two points named from another result's tets on
         * three threads (the least edge too short, whatever the order) */
        fdt_result *r3 = test_triangulate(xyz, n, 3, 0);
        char diag3[256];
        o.threads = 3;
        int err3 = fdt_voronoi_compute(r3, xyz, n, &o, &v, diag3, sizeof diag3);
        EXPECTF(err3 == FDT_ERANGE && strcmp(diag, diag3) == 0, "w = %g: '%s' at one thread, "
                "'%s' at three", w, diag, diag3);
        fdt_result_free(&r3);
        fdt_result_free(&r);
        free(xyz);
        return;
    }
    CHECK(err == FDT_OK);
    const double *vol = fdt_voronoi_volumes(v), *den = fdt_voronoi_densities(v);
    double b[6], sum = 0;
    fdt_voronoi_box(v, b);
    for (size_t i = 0; i < n; i++) {
        EXPECTF(vol[i] > 0, "w = %g: cell %zu has volume %g", w, i, vol[i]);
        sum += vol[i];
    }
    double bvol = (b[3] - b[0]) * (b[4] - b[1]) * (b[5] - b[2]);
    EXPECTF(close_to(sum, bvol, 1e-12), "w = %g: cells %.17g, box %.17g", w, sum, bvol);
    mpq_t *tv = malloc(n * sizeof *tv), q[3][3], t1, t2, v6;
    CHECK(tv);
    for (size_t i = 0; i < n; i++)
        mpq_init(tv[i]);
    for (int m = 0; m < 9; m++)
        mpq_init(q[m / 3][m % 3]);
    mpq_inits(t1, t2, v6, NULL);
    const fdt_vid *t = fdt_result_tets(r);
    for (size_t k = 0; k < fdt_result_num_tets(r); k++) {
        const fdt_vid *tk = t + 4 * k;
        if (tk[0] < 2000 && tk[1] < 2000 && tk[2] < 2000 && tk[3] < 2000)
            continue; /* only the clusters' densities are checked */
        for (int m = 0; m < 3; m++)
            for (int d = 0; d < 3; d++) {
                mpq_set_d(t1, xyz[3 * (size_t)tk[m + 1] + d]);
                mpq_set_d(t2, xyz[3 * (size_t)tk[0] + d]);
                mpq_sub(q[m][d], t1, t2);
            }
        mpq_set_ui(v6, 0, 1);
        for (int d = 0; d < 3; d++) { /* q0 . (q1 x q2) */
            int e = (d + 1) % 3, f = (d + 2) % 3;
            mpq_mul(t1, q[1][e], q[2][f]);
            mpq_mul(t2, q[1][f], q[2][e]);
            mpq_sub(t1, t1, t2);
            mpq_mul(t1, t1, q[0][d]);
            mpq_add(v6, v6, t1);
        }
        mpq_abs(v6, v6);
        for (int m = 0; m < 4; m++)
            mpq_add(tv[tk[m]], tv[tk[m]], v6);
    }
    for (size_t i = 2000; i < n; i++) {
        double want = 24 / mpq_get_d(tv[i]); /* 4 / (sum of 6 volumes / 6) */
        EXPECTF(close_to(den[i], want, w >= 1e-10 ? 1e-6 : 1e-4), "w = %g: point %zu's density "
                "%.17g, from its "
                "tets %.17g", w, i, den[i], want);
    }
    for (size_t i = 0; i < n; i++)
        mpq_clear(tv[i]);
    for (int m = 0; m < 9; m++)
        mpq_clear(q[m / 3][m % 3]);
    mpq_clears(t1, t2, v6, NULL);
    free(tv);
    fdt_voronoi_free(&v);
    fdt_result_free(&r);
    free(xyz);
}

/* options.skip: the centroids and densities left out (NULL), every other
 * value the same bits as the whole computation's, at 1 and 3 threads;
 * the options' size before skip accepted (nothing skipped), unknown bits
 * refused. A clustered cloud with a duplicate: summed, cut and clipped
 * cells, and a merged row. */
static void test_skip(size_t n)
{
    double *xyz = test_cloud(n, 1, 11);
    memcpy(xyz + 3 * (n - 1), xyz + 3, 3 * sizeof *xyz);
    fdt_result *r = test_triangulate(xyz, n, 2, 0);
    fdt_voronoi *all = cells(r, xyz, n, NULL);
    for (unsigned skip = 1; skip <= 3; skip++)
        for (int threads = 1; threads <= 3; threads += 2) {
            fdt_voronoi_options o;
            fdt_default_voronoi_options(&o);
            o.neighbors = 1;
            o.threads = threads;
            o.skip = skip;
            fdt_voronoi *v = NULL;
            CHECK(fdt_voronoi_compute(r, xyz, n, &o, &v, NULL, 0) == FDT_OK);
            EXPECT(!fdt_voronoi_centroids(v) == !!(skip & FDT_CELLS_NO_CENTROIDS));
            EXPECT(!fdt_voronoi_densities(v) == !!(skip & FDT_CELLS_NO_DENSITIES));
            size_t diff = 0;
            for (size_t i = 0; i < n; i++) {
                diff += memcmp(&fdt_voronoi_volumes(v)[i], &fdt_voronoi_volumes(all)[i], 8) != 0;
                diff += memcmp(&fdt_voronoi_areas(v)[i], &fdt_voronoi_areas(all)[i], 8) != 0;
                diff += fdt_voronoi_num_faces(v)[i] != fdt_voronoi_num_faces(all)[i];
                diff += fdt_voronoi_flags(v)[i] != fdt_voronoi_flags(all)[i];
                if (fdt_voronoi_centroids(v))
                    diff += memcmp(&fdt_voronoi_centroids(v)[3 * i],
                                   &fdt_voronoi_centroids(all)[3 * i], 24) != 0;
                if (fdt_voronoi_densities(v))
                    diff += memcmp(&fdt_voronoi_densities(v)[i],
                                   &fdt_voronoi_densities(all)[i], 8) != 0;
                size_t c1, c2;
                const fdt_vid *i1, *i2;
                const double *a1, *a2;
                CHECK(fdt_voronoi_neighbors(v, (fdt_vid)i, &c1, &i1, &a1) == FDT_OK);
                CHECK(fdt_voronoi_neighbors(all, (fdt_vid)i, &c2, &i2, &a2) == FDT_OK);
                diff += c1 != c2 || memcmp(i1, i2, c1 * sizeof *i1) ||
                        memcmp(a1, a2, c1 * sizeof *a1);
            }
            EXPECTF(diff == 0, "skip %u, %d threads: %zu values differ", skip, threads, diff);
            fdt_voronoi_free(&v);
        }
    EXPECT(fdt_voronoi_flags(all)[n - 1] == FDT_CELL_MERGED);
    fdt_voronoi_options o;
    /* a caller compiled before skip */
    size_t old = offsetof(fdt_voronoi_options, skip);
    CHECK(fdt_default_voronoi_options_sized(&o, old) == FDT_OK && o.struct_size == old);
    o.neighbors = 1;
    o.skip = 3; /* past the caller's struct: not read */
    fdt_voronoi *v = NULL;
    CHECK(fdt_voronoi_compute(r, xyz, n, &o, &v, NULL, 0) == FDT_OK);
    EXPECT(fdt_voronoi_centroids(v) && fdt_voronoi_densities(v) &&
           !memcmp(fdt_voronoi_densities(v), fdt_voronoi_densities(all), n * sizeof(double)));
    fdt_voronoi_free(&v);
    fdt_default_voronoi_options(&o);
    o.skip = 4;
    EXPECT(fdt_voronoi_compute(r, xyz, n, &o, &v, NULL, 0) == FDT_EINVAL && !v);
    fdt_voronoi_free(&all);
    fdt_result_free(&r);
    free(xyz);
}

/* A periodic set's cells as polyhedra (fdt_voronoi_polyhedron): each
 * one's volume from its faces (fans from its point) its cell's to 1e-9,
 * and together the box's. Uniform points periodic on every axis in a box
 * of unequal sides, a channel (periodic in x and z, walls of points at
 * y = 0 and 1) and a sparse set, whose cells reach across the box and
 * meet two images of one point. */
static void periodic_polyhedra(const char *name, const double *xyz, size_t n, unsigned axes,
                               const double box[6])
{
    fdt_settings s;
    fdt_default_settings(&s);
    s.n_threads = 2;
    s.periodic = axes;
    memcpy(s.periodic_box, box, sizeof s.periodic_box);
    fdt_context *ctx = NULL;
    fdt_result *r = NULL;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    int err = fdt_triangulate(ctx, xyz, n, &r);
    EXPECTF(err == FDT_OK, "%s: %s", name, fdt_context_diagnostic(ctx));
    fdt_close(&ctx);
    if (err)
        return;
    fdt_voronoi *v = cells(r, xyz, n, box);
    double sum = 0, worst = 0;
    size_t two_images = 0;
    for (size_t i = 0; i < n; i++) {
        size_t nv, nf, cnt;
        const double *vs, *fa;
        const int32_t *fs;
        const fdt_vid *ids;
        CHECK_EQ(fdt_voronoi_polyhedron(v, xyz, (fdt_vid)i, &nv, &vs, &nf, &fs), FDT_OK);
        CHECK_EQ(fdt_voronoi_neighbors(v, (fdt_vid)i, &cnt, &ids, &fa), FDT_OK);
        for (size_t e = 1; e < cnt; e++)
            two_images += ids[e] == ids[e - 1];
        const double *p = xyz + 3 * i;
        double vol = 0;
        for (size_t f = 0, o = 0; f < nf; f++) {
            int32_t k = fs[o++];
            const double *a = vs + 3 * (size_t)fs[o];
            for (int32_t j = 1; j + 1 < k; j++) {
                const double *b = vs + 3 * (size_t)fs[o + j], *c = vs + 3 * (size_t)fs[o + j + 1];
                double u[3], w[3], x[3];
                for (int d = 0; d < 3; d++) {
                    u[d] = a[d] - p[d];
                    w[d] = b[d] - p[d];
                    x[d] = c[d] - p[d];
                }
                vol += (u[0] * (w[1] * x[2] - w[2] * x[1]) - u[1] * (w[0] * x[2] - w[2] * x[0]) +
                        u[2] * (w[0] * x[1] - w[1] * x[0])) / 6;
            }
            o += (size_t)k;
        }
        double want = fdt_voronoi_volumes(v)[i];
        worst = fmax(worst, fabs(vol - want) / want);
        sum += vol;
    }
    double bv = (box[3] - box[0]) * (box[4] - box[1]) * (box[5] - box[2]);
    EXPECTF(worst < 1e-9, "%s: a polyhedron's volume is %.3g off its cell's", name, worst);
    EXPECTF(fabs(sum - bv) < 1e-9 * bv, "%s: the polyhedra sum to %.17g, the box %.17g", name,
            sum, bv);
    if (n < 50)
        EXPECTF(two_images > 0, "%s: no cell meets two images of one point", name);
    fdt_voronoi_free(&v);
    fdt_result_free(&r);
}

static void test_periodic_polyhedra(void)
{
    const double unequal[6] = {0, 0, 0, 2, 1, 0.5}, unit[6] = {0, 0, 0, 1, 1, 1};
    size_t n = 600;
    double *xyz = test_cloud(n, 0, 5);
    for (size_t i = 0; i < n; i++) {
        xyz[3 * i] *= 2;
        xyz[3 * i + 2] *= 0.5;
    }
    periodic_polyhedra("uniform xyz", xyz, n, 7, unequal);
    uint64_t seed = 9;
    for (size_t i = 0; i < n; i++) /* a channel: an eighth of the points on each wall */
        xyz[3 * i + 1] = i % 8 == 0 ? 0 : i % 8 == 1 ? 1 : test_unif(&seed);
    for (size_t i = 0; i < n; i++)
        xyz[3 * i] *= 0.5;
    for (size_t i = 0; i < n; i++)
        xyz[3 * i + 2] *= 2;
    periodic_polyhedra("channel xz", xyz, n, 5, unit);
    free(xyz);
    n = 12;
    xyz = test_cloud(n, 0, 21);
    periodic_polyhedra("sparse xyz", xyz, n, 7, unit);
    free(xyz);
}

int main(void)
{
    test_tiny_cells(1e-8);
    test_tiny_cells(1e-10);
    test_tiny_cells(1e-12);
    test_tiny_cells(1e-16);
    test_getters();
    test_lattice(2);
    test_lattice(5);
    test_box_sums(3000, 0, 1);
    test_box_sums(3000, 1, 2);
    test_box_sums(3000, 2, 4);
    test_same_bits(4000);
    test_scales();
    test_refusals();
    test_skip(3000);
    test_periodic_polyhedra();
    return test_report("voronoi");
}
