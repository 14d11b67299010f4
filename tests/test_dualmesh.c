/*
 * Tests for src/mesh/dualmesh.c (the clipped Voronoi diagram as one
 * polyhedral mesh, written as an OpenFOAM polyMesh by --dual), against
 * facts that do not come from the module:
 *  - its own check (fdt_dualmesh_check: every cell closed, each edge once
 *    each way, owner < neighbour, upper-triangular order, every vertex
 *    used) and, here again independently, the orientation: every cell's
 *    volume from its faces equals fdt_voronoi_compute's for its point
 *    (1e-10 relative), and the volumes add up to the box's (1e-12);
 *  - the internal faces are exactly the Voronoi neighbour pairs of
 *    non-zero area (fdt_voronoi_neighbors), one face each;
 *  - every wall face lies on its wall, its normal out of the box, and the
 *    walls' faces add up to the box's surface;
 *  - degenerate inputs: a cubic lattice (cospherical tets merged: unit
 *    cubes, no repeated vertex, 3 k^2 (k - 1) faces), a rotated lattice
 *    (nearly cospherical, nearly collinear hull triangles), duplicate
 *    points (no cell), five points (box corners equidistant from two
 *    points, bisectors through box edges), points on the walls of a given
 *    box, nearly coplanar points, clustered points with needle cells, and
 *    a boundary-layer block (layers 1e-6 thick: exact box volumes to
 *    1e-12), rings of cocircular points (10 and 45 rings: Voronoi edges
 *    through box edges and corners, edges between nearly cospherical
 *    rings);
 *  - refusals: points closer than doubles can hold the cells between
 *    (FDT_ERANGE, the points named, nothing handed out).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "frontdt.h"
#include "mesh/dualmesh.h"
#include "testutil.h"

static int close_to(double a, double b, double rel)
{
    return fabs(a - b) <= rel * fmax(fabs(a), fabs(b)) + 1e-300;
}

/* The dual of xyz (box NULL: the bounding box), checked against the
 * Voronoi cells; returns it for more checks (caller frees). */
static fdt_dualmesh check_dual_tol(const char *what, const double *xyz, size_t n,
                                   const double *box, double vtol)
{
    fdt_result *r = test_triangulate(xyz, n, 1, 0);
    fdt_voronoi_options o;
    fdt_default_voronoi_options(&o);
    o.neighbors = 1;
    o.threads = 1;
    if (box) {
        o.box_given = 1;
        memcpy(o.box, box, sizeof o.box);
    }
    char diag[512];
    fdt_dualmesh d;
    int err = fdt_dualmesh_build(r, xyz, n, &o, &d, diag, sizeof diag);
    if (err)
        fprintf(stderr, "%s: fdt_dualmesh_build: %s: %s\n", what, fdt_strerror(err), diag);
    CHECK(err == FDT_OK);
    EXPECTF(fdt_dualmesh_check(&d, diag, sizeof diag) == 0, "%s: %s", what, diag);
    fdt_voronoi *v = NULL;
    CHECK(fdt_voronoi_compute(r, xyz, n, &o, &v, diag, sizeof diag) == FDT_OK);
    double b[6];
    fdt_voronoi_box(v, b);
    for (int k = 0; k < 6; k++)
        EXPECT(b[k] == d.box[k]);
    size_t *cs, *cf;
    CHECK(fdt_dualmesh_cell_faces(&d, &cs, &cf) == FDT_OK);
    const double *vol = fdt_voronoi_volumes(v);
    double sum = 0, bvol = (b[3] - b[0]) * (b[4] - b[1]) * (b[5] - b[2]);
    size_t pairs = 0, cells = 0;
    uint8_t *matched = calloc(d.n_internal + 1, 1);
    CHECK(matched);
    for (size_t i = 0; i < n; i++) {
        int32_t c = d.cell_of[i];
        EXPECTF((c < 0) == (fdt_result_duplicate_map(r)[i] != (fdt_vid)i),
                "%s: point %zu cell %d", what, i, c);
        if (c < 0)
            continue;
        cells++;
        double cv = fdt_dualmesh_cell_volume(&d, cs, cf, (size_t)c);
        sum += cv;
        EXPECTF(close_to(cv, vol[i], vtol), "%s: cell %d volume %.17g, Voronoi %.17g", what,
                c, cv, vol[i]);
        size_t cnt;
        const fdt_vid *ids;
        const double *fa;
        CHECK(fdt_voronoi_neighbors(v, (fdt_vid)i, &cnt, &ids, &fa) == FDT_OK);
        for (size_t e = 0; e < cnt; e++)
            if (ids[e] > (fdt_vid)i) {
                /* the pair is a face, found by binary search (upper-triangular order) */
                int32_t ow = c, nb = d.cell_of[ids[e]];
                size_t lo = 0, hi = d.n_internal;
                while (lo < hi) {
                    size_t mid = lo + (hi - lo) / 2;
                    if (d.owner[mid] < ow || (d.owner[mid] == ow && d.neighbour[mid] < nb))
                        lo = mid + 1;
                    else
                        hi = mid;
                }
                int found = lo < d.n_internal && d.owner[lo] == ow && d.neighbour[lo] == nb;
                EXPECTF(found, "%s: Voronoi neighbours %zu and %d share no face", what, i,
                        ids[e]);
                if (found)
                    matched[lo] = 1;
                pairs++;
            }
    }
    EXPECT(cells == d.n_cells);
    EXPECTF(close_to(sum, bvol, 1e-12), "%s: volumes add up to %.17g, box %.17g", what, sum,
            bvol);
    /* the faces beyond those pairs: of no area to 2^-40 of their cells'
     * surface, which fdt_voronoi_neighbors leaves out (nearly cospherical
     * points); none for points in general position */
    const double *surf = fdt_voronoi_areas(v);
    int32_t *point_of = malloc((d.n_cells + 1) * sizeof *point_of);
    CHECK(point_of);
    for (size_t i = 0; i < n; i++)
        if (d.cell_of[i] >= 0)
            point_of[d.cell_of[i]] = (int32_t)i;
    size_t tiny = 0;
    for (size_t f = 0; f < d.n_internal; f++) {
        if (matched[f])
            continue;
        const int32_t *fv = d.fverts + d.fstart[f];
        size_t m = d.fstart[f + 1] - d.fstart[f];
        double nrm[3] = {0, 0, 0};
        const double *x0 = d.xyz + 3 * (size_t)fv[0];
        for (size_t j = 1; j + 1 < m; j++) {
            const double *x = d.xyz + 3 * (size_t)fv[j], *y = d.xyz + 3 * (size_t)fv[j + 1];
            double u[3], t[3];
            for (int k = 0; k < 3; k++) {
                u[k] = x[k] - x0[k];
                t[k] = y[k] - x0[k];
            }
            nrm[0] += 0.5 * (u[1] * t[2] - u[2] * t[1]);
            nrm[1] += 0.5 * (u[2] * t[0] - u[0] * t[2]);
            nrm[2] += 0.5 * (u[0] * t[1] - u[1] * t[0]);
        }
        double area = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        tiny += area <= 0x1p-36 * fmax(surf[point_of[d.owner[f]]], surf[point_of[d.neighbour[f]]]);
    }
    free(point_of);
    free(matched);
    EXPECTF(pairs + tiny == d.n_internal, "%s: %zu internal faces, %zu Voronoi neighbour pairs "
            "and %zu faces of no area", what, d.n_internal, pairs, tiny);
    /* the walls: on their plane, normals out of the box, areas the box's */
    double wall_area[6] = {0, 0, 0, 0, 0, 0};
    for (int p = 0; p < 6; p++)
        for (size_t f = d.patch_start[p]; f < d.patch_start[p] + d.patch_size[p]; f++) {
            int k = p / 2;
            double bnd = b[k + 3 * (p & 1)], nrm = 0;
            const int32_t *fv = d.fverts + d.fstart[f];
            size_t m = d.fstart[f + 1] - d.fstart[f];
            const double *x0 = d.xyz + 3 * (size_t)fv[0];
            for (size_t i = 0; i < m; i++) {
                const double *x = d.xyz + 3 * (size_t)fv[i];
                EXPECT(x[k] == bnd);
                if (i >= 1 && i + 1 < m) {
                    const double *y = d.xyz + 3 * (size_t)fv[i + 1];
                    int u = (k + 1) % 3, t = (k + 2) % 3;
                    nrm += 0.5 * ((x[u] - x0[u]) * (y[t] - x0[t]) - (x[t] - x0[t]) * (y[u] - x0[u]));
                }
            }
            /* a sliver of rounding (no area) may face either way */
            int wu = (k + 1) % 3, wt = (k + 2) % 3;
            double sliver = 0x1p-36 * (b[wu + 3] - b[wu]) * (b[wt + 3] - b[wt]);
            EXPECTF(fabs(nrm) <= sliver || ((p & 1) ? nrm > 0 : nrm < 0),
                    "%s: wall face %zu on %s turned in (area %g)", what, f, fdt_dualmesh_patch[p],
                    nrm);
            wall_area[p] += fabs(nrm);
        }
    for (int p = 0; p < 6; p++) {
        int k = p / 2, u = (k + 1) % 3, t = (k + 2) % 3;
        double want = (b[u + 3] - b[u]) * (b[t + 3] - b[t]);
        EXPECTF(close_to(wall_area[p], want, 1e-12), "%s: wall %s area %.17g of %.17g", what,
                fdt_dualmesh_patch[p], wall_area[p], want);
    }
    free(cs);
    free(cf);
    fdt_voronoi_free(&v);
    fdt_result_free(&r);
    return d;
}

static fdt_dualmesh check_dual(const char *what, const double *xyz, size_t n, const double *box)
{
    return check_dual_tol(what, xyz, n, box, 1e-10);
}

/* k^3 lattice points: unit cubes halved at the walls; every vertex once. */
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
    fdt_dualmesh d = check_dual("lattice", xyz, n, NULL);
    EXPECT(d.n_internal == 3 * (size_t)k * k * (k - 1));
    EXPECT(d.n_verts == (size_t)(k + 1) * (k + 1) * (k + 1)); /* 0, 1/2, 3/2 .. k - 1 */
    for (size_t f = 0; f < d.n_faces; f++)
        EXPECT(d.fstart[f + 1] - d.fstart[f] == 4);
    fdt_dualmesh_free(&d);
    /* a box through the cells' middles: Voronoi vertices on the walls */
    double box[6] = {-0.5, -0.5, -0.25, k - 0.5, k - 1, k - 0.5};
    d = check_dual("lattice, box through the cells", xyz, n, box);
    fdt_dualmesh_free(&d);
    free(xyz);
}

/* A k^3 lattice turned by (0.3, 0.5, 0.7) rad (gen_points rotlattice):
 * nearly cospherical groups, nearly collinear hull triangles whose rays
 * need their normals to the last bit (a plain cross product sent them
 * astray by 0.1 rad and a cell's volume by 2e-3). */
static void test_rotated_lattice(int k)
{
    size_t n = (size_t)k * k * k;
    double *xyz = malloc(3 * n * sizeof *xyz);
    CHECK(xyz);
    double a = 0.3, b = 0.5, c = 0.7;
    for (size_t i = 0; i < n; i++) {
        double x = (double)(i % (size_t)k), y = (double)(i / (size_t)k % (size_t)k),
               z = (double)(i / ((size_t)k * k));
        double y1 = y * cos(a) - z * sin(a), z1 = y * sin(a) + z * cos(a);
        double x2 = x * cos(b) + z1 * sin(b), z2 = -x * sin(b) + z1 * cos(b);
        xyz[3 * i] = x2 * cos(c) - y1 * sin(c);
        xyz[3 * i + 1] = x2 * sin(c) + y1 * cos(c);
        xyz[3 * i + 2] = z2;
    }
    fdt_dualmesh d = check_dual("rotated lattice", xyz, n, NULL);
    fdt_dualmesh_free(&d);
    free(xyz);
}

/* A boundary-layer block (gen_points blayer): layers 1e-6 .. 1 thick
 * over a unit grid. Every cell is a box between the midplanes, so its
 * volume is known exactly; the vertices keep it to 1e-12 (the tets are
 * flat: their circumcentres come from exact arithmetic). */
static void test_stretched(void)
{
    const int m = 4;
    double z[8] = {0};
    for (int k = 1; k < 8; k++)
        z[k] = z[k - 1] + pow(10.0, k - 7);
    size_t n = (size_t)m * m * 8;
    double *xyz = malloc(3 * n * sizeof *xyz);
    CHECK(xyz);
    for (size_t i = 0; i < n; i++) {
        xyz[3 * i] = (double)(i / 8 / (size_t)m);
        xyz[3 * i + 1] = (double)(i / 8 % (size_t)m);
        xyz[3 * i + 2] = z[i % 8];
    }
    /* fdt_voronoi_compute's own sums keep these thin cells to 1e-7 only */
    fdt_dualmesh d = check_dual_tol("boundary layer", xyz, n, NULL, 1e-6);
    size_t *cs, *cf;
    CHECK(fdt_dualmesh_cell_faces(&d, &cs, &cf) == FDT_OK);
    for (size_t i = 0; i < n; i++) {
        double ext[3];
        for (int k = 0; k < 2; k++) {
            double x = xyz[3 * i + k];
            ext[k] = (x == 0 || x == m - 1) ? 0.5 : 1.0;
        }
        int l = (int)(i % 8);
        double lo = l ? 0.5 * (z[l - 1] + z[l]) : z[0], hi = l < 7 ? 0.5 * (z[l] + z[l + 1]) : z[7];
        double want = ext[0] * ext[1] * (hi - lo);
        double got = fdt_dualmesh_cell_volume(&d, cs, cf, (size_t)d.cell_of[i]);
        EXPECTF(close_to(got, want, 1e-12), "boundary layer cell %zu: %.17g, exactly %.17g", i,
                got, want);
    }
    free(cs);
    free(cf);
    fdt_dualmesh_free(&d);
    free(xyz);
}

static void test_random(size_t n, int clustered, uint64_t seed)
{
    double *xyz = test_cloud(n, clustered, seed);
    fdt_dualmesh d = check_dual(clustered ? "clustered" : "uniform", xyz, n, NULL);
    fdt_dualmesh_free(&d);
    const double box[6] = {-0.25, 0, -0.5, 1, 1.5, 1};
    d = check_dual(clustered ? "clustered, given box" : "uniform, given box", xyz, n, box);
    fdt_dualmesh_free(&d);
    free(xyz);
}

/* Duplicates have no cell; the cells keep the input order. */
static void test_duplicates(void)
{
    size_t n = 300;
    double *xyz = test_cloud(n, 0, 7);
    for (size_t i = 0; i < 40; i++)
        memcpy(xyz + 3 * (200 + i), xyz + 3 * (5 * i), 3 * sizeof *xyz);
    fdt_dualmesh d = check_dual("duplicates", xyz, n, NULL);
    EXPECT(d.n_cells == n - 40);
    for (size_t i = 0; i < n; i++)
        EXPECT((d.cell_of[i] < 0) == (i >= 200 && i < 240));
    fdt_dualmesh_free(&d);
    free(xyz);
}

/* Few points; points on the given box's walls; nearly coplanar points. */
static void test_small_and_flat(void)
{
    const double five[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0.3, 0.3, 0.3};
    fdt_dualmesh d = check_dual("five points", five, 5, NULL);
    EXPECT(d.n_cells == 5);
    fdt_dualmesh_free(&d);
    const double box[6] = {0, 0, 0, 1, 1, 1};
    d = check_dual("five points, unit box", five, 5, box);
    fdt_dualmesh_free(&d);
    size_t n = 400;
    double *xyz = test_cloud(n, 0, 11);
    for (size_t i = 0; i < n; i++)
        if (i % 3 == 0)
            xyz[3 * i + (i % 2)] = (i % 4) ? 0.0 : 1.0; /* on a wall */
    d = check_dual("points on the walls", xyz, n, box);
    fdt_dualmesh_free(&d);
    for (size_t i = 0; i < n; i++)
        xyz[3 * i + 2] = i < 4 ? (double)(i & 1) : 1e-6 * xyz[3 * i + 2];
    d = check_dual("nearly coplanar", xyz, n, NULL);
    fdt_dualmesh_free(&d);
    free(xyz);
}

/* m rings of 2m cocircular points, as an axisymmetric CAD part's
 * vertices (gen_points `cone`): at 10 rings the corner of the box at the
 * top of the diagonal x = y is equidistant from two points, and the
 * Voronoi edges there crossed a wall at a box edge a rounding inside the
 * other wall (cells left open); at 45, the line of a Voronoi edge between
 * nearly cospherical rings met a wall far outside the part of the edge
 * its faces keep (a cell's wall face would not chain). */
static void test_rings(size_t m)
{
    double *xyz = malloc(2 * m * m * 3 * sizeof *xyz);
    CHECK(xyz);
    size_t n = 0;
    for (size_t i = 1; i <= m; i++)
        for (size_t j = 0; j < 2 * m; j++) {
            double a = 6.283185307179586 * (double)j / (double)(2 * m), r = 0.01 * (double)i;
            xyz[3 * n] = r * cos(a);
            xyz[3 * n + 1] = r * sin(a);
            xyz[3 * n + 2] = 0.02 * (double)i;
            n++;
        }
    char what[64];
    snprintf(what, sizeof what, "%zu cocircular rings", m);
    fdt_dualmesh d = check_dual(what, xyz, n, NULL);
    fdt_dualmesh_free(&d);
    free(xyz);
}

/* A torus (R 3, r 1) on its nu x nv parameter grid (gen_points `torus`):
 * every point on the box's walls and corners 7e-16 off where they would
 * be. At 4 x 3 the box corner (4, -4, z) is 4 from two points but for
 * a rounding: it came as a vertex of the face between their cells and as
 * a corner of its own (cell 0 not closed); at 4 x 4 two Voronoi edges'
 * crossings snapped onto one corner as two vertices (an edge twice). */
static void test_torus(size_t nu, size_t nv)
{
    double *xyz = malloc(nu * nv * 3 * sizeof *xyz);
    CHECK(xyz);
    size_t n = 0;
    for (size_t i = 0; i < nu; i++)
        for (size_t j = 0; j < nv; j++) {
            double u = 6.283185307179586 * (double)i / (double)nu;
            double v = 6.283185307179586 * (double)j / (double)nv, w = 3.0 + cos(v);
            xyz[3 * n] = w * cos(u);
            xyz[3 * n + 1] = w * sin(u);
            xyz[3 * n + 2] = sin(v);
            n++;
        }
    char what[64];
    snprintf(what, sizeof what, "a %zu x %zu torus", nu, nv);
    fdt_dualmesh d = check_dual(what, xyz, n, NULL);
    fdt_dualmesh_free(&d);
    free(xyz);
}

/*
 * An HCP crystal (hexagonal layers, every other one shifted; irrational
 * coordinates: sqrt(3) / 2, sqrt(2 / 3)) in its bounding box: Voronoi
 * vertices within rounding of the walls and of each other. 5 x 5 x 6 left
 * a face running out to a vertex 2 ulps under zmax and back (a spike
 * after two crossings merged); 3 x 3 x 7 a loop of three wall edges
 * 4e-16 across beside the cell's wall face; 20 x 20 x 3 an internal face
 * pinched at a merged wall vertex, and a wall face through one vertex
 * twice: all were refused as internal errors ("has vertex twice", "does
 * not chain"). (tests/dual_e2e.py has `gen_points hcp 729`, whose cells
 * did not close while crossings inside a wall were merged.)
 */
static void test_hcp(int ni, int nl)
{
    double *xyz = malloc((size_t)ni * (size_t)ni * (size_t)nl * 3 * sizeof *xyz);
    CHECK(xyz);
    size_t n = 0;
    for (int l = 0; l < nl; l++)
        for (int i = 0; i < ni; i++)
            for (int j = 0; j < ni; j++) {
                xyz[3 * n] = i + 0.5 * (j % 2) + (l % 2 ? 0.5 : 0);
                xyz[3 * n + 1] = j * sqrt(3.0) / 2 + (l % 2 ? sqrt(3.0) / 6 : 0);
                xyz[3 * n + 2] = l * sqrt(2.0 / 3.0);
                n++;
            }
    char what[64];
    snprintf(what, sizeof what, "an HCP crystal %d x %d x %d", ni, ni, nl);
    fdt_dualmesh d = check_dual(what, xyz, n, NULL);
    fdt_dualmesh_free(&d);
    free(xyz);
}

/* Points closer than doubles can hold the cells between: refused with
 * FDT_ERANGE naming them, nothing handed out. */
static void expect_beyond_doubles(const char *what, const double *xyz, size_t n)
{
    fdt_result *r = test_triangulate(xyz, n, 1, 0);
    fdt_voronoi_options o;
    fdt_default_voronoi_options(&o);
    char diag[512];
    fdt_dualmesh d;
    int err = fdt_dualmesh_build(r, xyz, n, &o, &d, diag, sizeof diag);
    EXPECTF(err == FDT_ERANGE, "%s: %s (%s)", what, fdt_strerror(err), diag);
    EXPECTF(strstr(diag, "beyond what doubles hold") != NULL, "%s: %s", what, diag);
    EXPECT(d.xyz == NULL && d.fverts == NULL && d.n_cells == 0);
    fdt_dualmesh_free(&d);
    fdt_result_free(&r);
}

static void test_beyond_doubles(void)
{
    size_t n = 200;
    double *xyz = test_cloud(n, 0, 13);
    /* two points 2^-45 apart at coordinates near 0.75 (under 2^-40 of them) */
    for (int k = 0; k < 3; k++)
        xyz[3 * 7 + (size_t)k] = 0.75;
    memcpy(xyz + 3 * 8, xyz + 3 * 7, 3 * sizeof *xyz);
    xyz[3 * 8] += 0x1p-45;
    expect_beyond_doubles("2^-45 apart near 0.75", xyz, n);
    free(xyz);
    /* a cluster 1e-100 wide in a unit box (its cells' volumes underflow) */
    xyz = test_cloud(n, 0, 17);
    for (size_t i = 0; i < 20; i++)
        for (int k = 0; k < 3; k++)
            xyz[3 * i + (size_t)k] = 1e-100 * xyz[3 * i + (size_t)k];
    expect_beyond_doubles("a 1e-100 cluster", xyz, n);
    free(xyz);
}

int main(void)
{
    test_rings(10);
    test_rings(45);
    test_torus(4, 3);
    test_torus(4, 4);
    test_torus(5, 4);
    test_hcp(5, 6);
    test_hcp(3, 7);
    test_hcp(20, 3);
    test_beyond_doubles();
    test_small_and_flat();
    test_lattice(2);
    test_lattice(5);
    test_duplicates();
    test_rotated_lattice(6);
    test_stretched();
    test_random(3000, 0, 1);
    test_random(3000, 1, 2);
    test_random(3000, 2, 3);
    return test_report("dualmesh");
}
