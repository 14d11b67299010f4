/*
 * Tests for src/geom/cell.c: a box cut by half-spaces, measured against
 * closed forms.
 *  - the box alone: volume, area, centroid, six wall faces;
 *  - a cut through the middle halves it; a cut that misses changes
 *    nothing (returns 0); a cut that removes everything is refused (-2);
 *  - planes through vertices and along edges (the degenerate cuts: the
 *    vertices on the plane stay, no sliver face is made): the corner
 *    tet x + y + z <= 1 of the unit cube, volume 1/6, four faces;
 *  - the cube cut by the 14 bisectors of a body-centred lattice's
 *    neighbours: the truncated octahedron, volume 1/2 of the cube's;
 *  - random cuts: the faces stay closed (the vector areas add up to 0)
 *    and the volume equals the divergence-theorem one;
 *  - a cell of thousands of faces (a point above a plane of points): the
 *    cuts that climb to the vertices outside and rewrite only what they
 *    reach give the bits of a cell that classes every vertex and is
 *    compacted after every cut, and fdt_cell_compact leaves every vertex
 *    used.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geom/cell.h"
#include "testutil.h"

static double vol_of(fdt_cell *c, double *area, double cen[3])
{
    double v, a, cc[3];
    fdt_cell_measure(c, &v, &a, cc, NULL);
    if (area)
        *area = a;
    if (cen)
        memcpy(cen, cc, sizeof cc);
    return v;
}

static int near(double a, double b)
{
    return fabs(a - b) <= 1e-13 * fmax(1, fmax(fabs(a), fabs(b)));
}

static void test_box(fdt_cell *c)
{
    const double lo[3] = {-1, -2, -0.5}, hi[3] = {3, 1, 0.5};
    CHECK(fdt_cell_box(c, lo, hi) == 0);
    double a, cen[3];
    double v = vol_of(c, &a, cen);
    EXPECTF(near(v, 12), "box volume %.17g", v);
    EXPECTF(near(a, 2 * (12 + 4 + 3)), "box area %.17g", a);
    EXPECT(near(cen[0], 1) && near(cen[1], -0.5) && near(cen[2], 0));
    fdt_cell_face f[6];
    fdt_cell_measure(c, &v, &a, cen, f);
    for (int k = 0; k < 6; k++)
        EXPECT(f[k].label == FDT_CELL_WALL(k));
    EXPECT(near(f[0].area, 3) && near(f[2].area, 4) && near(f[4].area, 12));
}

static void test_simple_cuts(fdt_cell *c)
{
    const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
    CHECK(fdt_cell_box(c, lo, hi) == 0);
    const double nx[3] = {1, 0, 0};
    EXPECT(fdt_cell_cut(c, nx, 2, 7) == 0); /* misses */
    EXPECT(fdt_cell_cut(c, nx, 1, 7) == 0); /* touches a face */
    EXPECT(fdt_cell_cut(c, nx, 0, 7) == 1);
    EXPECT(near(vol_of(c, NULL, NULL), 4));
    EXPECT(c->nf == 6);
    const double ny[3] = {0, -1, 0};
    EXPECT(fdt_cell_cut(c, ny, -2, 8) == -2); /* y >= 2: nothing left */
    EXPECT(near(vol_of(c, NULL, NULL), 4));   /* and nothing changed */
    /* The corner tet of the unit cube: planes through 3 vertices. */
    const double z0[3] = {0, 0, 0}, z1[3] = {1, 1, 1};
    CHECK(fdt_cell_box(c, z0, z1) == 0);
    const double d[3] = {1, 1, 1};
    EXPECT(fdt_cell_cut(c, d, 1, 9) == 1);
    double a;
    double v = vol_of(c, &a, NULL);
    EXPECTF(near(v, 1.0 / 6), "corner tet volume %.17g", v);
    EXPECTF(c->nf == 4, "corner tet has %d faces", c->nf);
    EXPECT(near(a, 1.5 + sqrt(3) / 2));
    /* A plane along an edge of it: nothing more than a face. */
    const double e[3] = {1, 1, 0};
    EXPECT(fdt_cell_cut(c, e, 1, 10) == 0);
}

static void test_truncated_octahedron(fdt_cell *c)
{
    /* The Voronoi cell of a bcc lattice point (spacing 2): its 8 body
     * diagonal neighbours (+-1, +-1, +-1) and 6 axis ones (+-2, 0, 0). */
    const double lo[3] = {-3, -3, -3}, hi[3] = {3, 3, 3};
    CHECK(fdt_cell_box(c, lo, hi) == 0);
    int label = 0;
    for (int s = 0; s < 8; s++) {
        double n[3] = {s & 1 ? 1 : -1, s & 2 ? 1 : -1, s & 4 ? 1 : -1};
        CHECK(fdt_cell_cut(c, n, 1.5, label++) >= 0);
    }
    for (int k = 0; k < 6; k++) {
        double n[3] = {0, 0, 0};
        n[k / 2] = k & 1 ? 2 : -2;
        CHECK(fdt_cell_cut(c, n, 2, label++) >= 0);
    }
    double a;
    double v = vol_of(c, &a, NULL);
    EXPECTF(near(v, 4), "truncated octahedron volume %.17g", v); /* 8 / 2 points a cube */
    EXPECTF(c->nf == 14, "truncated octahedron has %d faces", c->nf);
    /* Volume 8 sqrt(2) a^3 = 4 gives the edge a = sqrt(2) / 2; the
     * area is (6 + 12 sqrt(3)) a^2. */
    double el = sqrt(2) / 2;
    EXPECTF(near(a, (6 + 12 * sqrt(3)) * el * el), "area %.17g", a);
}

static void test_random_cuts(fdt_cell *c)
{
    uint64_t s = 5;
    for (int round = 0; round < 200; round++) {
        const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
        CHECK(fdt_cell_box(c, lo, hi) == 0);
        double prev = 8;
        for (int k = 0; k < 30; k++) {
            double n[3];
            for (int d = 0; d < 3; d++)
                n[d] = 2 * test_unif(&s) - 1;
            double h = 0.05 + 0.5 * test_unif(&s);
            int got = fdt_cell_cut(c, n, h, k);
            CHECK(got >= 0);
            double v = vol_of(c, NULL, NULL);
            EXPECT(v <= prev * (1 + 1e-14) && v > 0);
            prev = v;
        }
        /* Closed: the faces' vector areas add up to zero. */
        double sum[3] = {0, 0, 0}, tot = 0;
        for (int f = 0; f < c->nf; f++) {
            const int *r = c->ring + c->f[f].start;
            for (int j = 0; j < c->f[f].count; j++) {
                const double *p = c->p[r[j]], *q = c->p[r[(j + 1) % c->f[f].count]];
                double x[3] = {p[1] * q[2] - p[2] * q[1], p[2] * q[0] - p[0] * q[2],
                               p[0] * q[1] - p[1] * q[0]};
                for (int d = 0; d < 3; d++) {
                    sum[d] += x[d];
                    tot += fabs(x[d]);
                }
            }
        }
        EXPECTF(fabs(sum[0]) + fabs(sum[1]) + fabs(sum[2]) <= 1e-13 * tot,
                "round %d: the faces do not close (%g %g %g)", round, sum[0], sum[1], sum[2]);
    }
}

/*
 * A cell of many faces, every cut leaving one: the site 1 above a plane
 * of 3,000 random points (a scan's outlier above it), cut by their
 * bisectors nearest first, as src/mesh/voronoi.c cuts a hull point's cell.
 * The cuts find the vertices outside by climbing and rewrite only the
 * faces they reach, leaving the rest of the arrays for a later
 * compaction (bench/NOTES.md entry 129); a twin that classes every
 * vertex at every cut and is compacted after each (what every cut did
 * before) must measure the same to the last bit, have the same faces in
 * the same order, and, compacted, the same vertices. Then every vertex
 * of the compacted cell is used, none is NaN, and each face's vertices
 * lie on its plane.
 */
static void test_many_faces(void)
{
    enum { NPTS = 3000 };
    static double q[NPTS][3], d2[NPTS];
    uint64_t s = 11;
    for (int i = 0; i < NPTS; i++) {
        q[i][0] = 4 * test_unif(&s) - 2;
        q[i][1] = 4 * test_unif(&s) - 2;
        q[i][2] = -1;
        d2[i] = q[i][0] * q[i][0] + q[i][1] * q[i][1] + 1;
    }
    for (int i = 1; i < NPTS; i++) /* nearest first */
        for (int j = i; j > 0 && d2[j - 1] > d2[j]; j--) {
            double t = d2[j];
            d2[j] = d2[j - 1];
            d2[j - 1] = t;
            for (int k = 0; k < 3; k++) {
                t = q[j][k];
                q[j][k] = q[j - 1][k];
                q[j - 1][k] = t;
            }
        }
    fdt_cell lazy, eager;
    fdt_cell_init(&lazy);
    fdt_cell_init(&eager);
    const double lo[3] = {-3, -3, -2}, hi[3] = {3, 3, 1};
    CHECK(fdt_cell_box(&lazy, lo, hi) == 0 && fdt_cell_box(&eager, lo, hi) == 0);
    eager.classify_all = 1;
    int cut = 0;
    for (int i = 0; i < NPTS; i++) {
        double h = 0.5 * d2[i];
        int a = fdt_cell_cut(&lazy, q[i], h, i), b = fdt_cell_cut(&eager, q[i], h, i);
        CHECK(a >= 0 && a == b);
        CHECK(fdt_cell_compact(&eager) == 0);
        cut += a;
    }
    EXPECTF(lazy.nf > 1000, "%d faces from %d cuts that cut", lazy.nf, cut);
    double va, aa, ca[3], vb, ab, cb[3];
    fdt_cell_measure(&lazy, &va, &aa, ca, NULL);
    fdt_cell_measure(&eager, &vb, &ab, cb, NULL);
    EXPECTF(va == vb && aa == ab && ca[0] == cb[0] && ca[1] == cb[1] && ca[2] == cb[2],
            "lazy %.17g %.17g, eager %.17g %.17g", va, aa, vb, ab);
    CHECK(fdt_cell_compact(&lazy) == 0);
    CHECK(lazy.nf == eager.nf && lazy.np == eager.np && lazy.nring == eager.nring);
    for (int f = 0; f < lazy.nf; f++)
        EXPECT(lazy.f[f].label == eager.f[f].label && lazy.f[f].count == eager.f[f].count);
    EXPECT(memcmp(lazy.ring, eager.ring, (size_t)lazy.nring * sizeof(int)) == 0);
    EXPECT(memcmp(lazy.p, eager.p, (size_t)lazy.np * sizeof lazy.p[0]) == 0);
    /* compacted: every vertex used and finite, each face on its plane */
    char *used = calloc((size_t)lazy.np, 1);
    CHECK(used);
    for (int f = 0; f < lazy.nf; f++) {
        long l = lazy.f[f].label;
        for (int j = 0; j < lazy.f[f].count; j++) {
            const double *x = lazy.p[lazy.ring[lazy.f[f].start + j]];
            used[lazy.ring[lazy.f[f].start + j]] = 1;
            EXPECT(isfinite(x[0]) && isfinite(x[1]) && isfinite(x[2]));
            if (l >= 0) {
                double on = q[l][0] * x[0] + q[l][1] * x[1] + q[l][2] * x[2] - 0.5 * d2[l];
                EXPECTF(fabs(on) <= 1e-12, "face %d vertex %d off its plane by %g", f, j, on);
            }
        }
    }
    for (int i = 0; i < lazy.np; i++)
        EXPECTF(used[i], "vertex %d of %d unused after the compaction", i, lazy.np);
    free(used);
    fdt_cell_free(&lazy);
    fdt_cell_free(&eager);
}

int main(void)
{
    fdt_cell c;
    fdt_cell_init(&c);
    test_box(&c);
    test_simple_cuts(&c);
    test_truncated_octahedron(&c);
    test_random_cuts(&c);
    fdt_cell_free(&c);
    test_many_faces();
    return test_report("cell");
}
