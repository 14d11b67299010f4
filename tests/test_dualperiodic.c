/*
 * Tests for src/mesh/dualperiodic.c (the Voronoi cells of a periodic
 * result as one polyhedral mesh) and its entry src/api/dual.c:
 *  - fdt_dual_images_make: the cells' points first, in input order (a
 *    merged duplicate has none); each image once, of a cell's point, its
 *    offsets within two periods, none all zero, its coordinates the
 *    rounded translate (fdt_images_round); the box the periodic box on
 *    the axes that are not periodic and holding every point on the others;
 *  - fdt_dual_build on uniform points periodic in x, y, z (a box of
 *    periods 1.2, 1, 1.5) and on a channel (x, z periodic, walls of grid
 *    points across y): a cell a point, each cell's volume from its faces
 *    equal to fdt_voronoi_compute's (1e-10), the volumes adding up to the
 *    box's (1e-12), no face on the walls of a periodic axis, cyclic pairs
 *    (the check passed inside), the same bytes on 1 and 3 threads;
 *  - fdt_dualmesh_fold refusing a plain dual that is not of its images
 *    (FDT_EINTERNAL), and one whose faces across a period no longer match
 *    (a vertex of one moved: FDT_ERANGE, what the images' rounding does
 *    to ties), leaving nothing allocated.
 * tests/dual_e2e.py checks the CLI's files and OpenFOAM's checkMesh.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "api/dual.h"
#include "frontdt.h"
#include "geom/images.h"
#include "mesh/dualmesh.h"
#include "mesh/dualperiodic.h"
#include "testutil.h"

/* The periodic mesh, sorted (the dual numbers its cells' faces in the
 * tets' order, as the CLI's). */
static fdt_result *periodic_mesh(const double *xyz, size_t n, unsigned axes, const double box[6])
{
    fdt_result *r = test_periodic_mesh(xyz, n, axes, box);
    CHECK(fdt_result_sort(r) == FDT_OK);
    return r;
}

/* Uniform points in box, the first repeated at the end (a duplicate). */
static double *cube_points(size_t n, const double box[6], uint64_t seed)
{
    double *p = malloc(3 * (n + 1) * sizeof *p);
    CHECK(p != NULL);
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            p[3 * i + (size_t)k] = box[k] + (box[k + 3] - box[k]) * test_unif(&seed);
    memcpy(p + 3 * n, p, 3 * sizeof *p);
    return p;
}

/* A channel in box: walls of g x g grid points 1e-3 inside the y sides,
 * n random points between. *m: the points. */
static double *channel_points(size_t n, int g, const double box[6], uint64_t seed, size_t *m)
{
    double *p = malloc(3 * (n + 2 * (size_t)(g * g)) * sizeof *p);
    CHECK(p != NULL);
    size_t k = 0;
    for (int side = 0; side < 2; side++)
        for (int i = 0; i < g; i++)
            for (int j = 0; j < g; j++, k++) {
                p[3 * k] = box[0] + (box[3] - box[0]) * (i + 0.5) / g;
                p[3 * k + 1] = side ? box[4] - 1e-3 : box[1] + 1e-3;
                p[3 * k + 2] = box[2] + (box[5] - box[2]) * (j + 0.5) / g;
            }
    for (size_t i = 0; i < n; i++, k++) {
        p[3 * k] = box[0] + (box[3] - box[0]) * test_unif(&seed);
        p[3 * k + 1] = box[1] + 0.02 + (box[4] - box[1] - 0.04) * test_unif(&seed);
        p[3 * k + 2] = box[2] + (box[5] - box[2]) * test_unif(&seed);
    }
    *m = k;
    return p;
}

static void check_images(const fdt_result *r, const double *xyz, size_t n, unsigned axes,
                         const double box[6])
{
    fdt_dual_images im;
    char diag[512];
    EXPECTF(fdt_dual_images_make(r, xyz, n, &im, diag, sizeof diag) == FDT_OK, "images: %s",
            diag);
    const fdt_vid *dup = fdt_result_duplicate_map(r);
    size_t c = 0;
    for (size_t i = 0; i < n; i++) {
        EXPECT(im.cell_of[i] == (dup[i] == (fdt_vid)i ? (int32_t)c : -1));
        if (dup[i] == (fdt_vid)i) {
            EXPECT(!memcmp(im.xyz + 3 * c, xyz + 3 * i, 3 * sizeof *xyz));
            c++;
        }
    }
    EXPECT(c == im.ncells && im.m > im.ncells);
    const double lo[3] = {box[0], box[1], box[2]}, hi[3] = {box[3], box[4], box[5]};
    size_t bad = 0;
    for (size_t s = im.ncells; s < im.m; s++) {
        const int8_t *o = im.off + 3 * s;
        int nz = 0;
        for (int k = 0; k < 3; k++) {
            nz |= o[k];
            bad += o[k] < -2 || o[k] > 2 || (o[k] && !(axes >> k & 1));
        }
        bad += !nz || im.src[s] >= im.ncells;
        /* each once: sorted by (cell, offsets) */
        if (s > im.ncells && im.src[s] == im.src[s - 1]) {
            const int8_t *q = im.off + 3 * (s - 1);
            int k = 0;
            while (k < 2 && q[k] == o[k])
                k++;
            bad += q[k] >= o[k];
        }
        double want[3];
        size_t p = 0;
        while (p < n && im.cell_of[p] != (int32_t)im.src[s])
            p++;
        CHECK(p < n);
        fdt_images_round(xyz + 3 * p, o, lo, hi, want, NULL);
        bad += memcmp(want, im.xyz + 3 * s, sizeof want) != 0;
    }
    EXPECTF(bad == 0, "%zu images out of place", bad);
    for (int k = 0; k < 3; k++) {
        if (!(axes >> k & 1)) {
            EXPECT(im.box[k] == box[k] && im.box[k + 3] == box[k + 3]);
            continue;
        }
        for (size_t s = 0; s < im.m; s++)
            EXPECT(im.box[k] < im.xyz[3 * s + (size_t)k] && im.xyz[3 * s + (size_t)k] < im.box[k + 3]);
    }
    fdt_dual_images_free(&im);
}

/* The dual of r: the cells against fdt_voronoi_compute, the box's volume,
 * the walls of periodic axes empty; *bytes a copy of its arrays (for the
 * threads' comparison). */
static void check_dual(fdt_result *r, const double *xyz, size_t n, unsigned axes,
                       const double box[6], int threads, fdt_dualmesh *d)
{
    char diag[512];
    int rc = fdt_dual_build(r, xyz, n, NULL, threads, d, diag, sizeof diag);
    EXPECTF(rc == FDT_OK, "the dual: %d %s", rc, diag);
    if (rc)
        return;
    fdt_voronoi_options o;
    fdt_default_voronoi_options(&o);
    o.threads = 1;
    fdt_voronoi *v = NULL;
    CHECK(fdt_voronoi_compute(r, xyz, n, &o, &v, diag, sizeof diag) == FDT_OK);
    size_t *cs = NULL, *cf = NULL;
    CHECK(fdt_dualmesh_cell_faces(d, &cs, &cf) == FDT_OK);
    const double *vol = fdt_voronoi_volumes(v);
    double sum = 0, worst = 0;
    EXPECT(d->n_input == n && d->periodic == axes && d->n_cyclic >= 2 && d->n_cyclic % 2 == 0);
    CHECK(fdt_voronoi_num_points(v) == n); /* row i: point i */
    for (size_t i = 0; i < n; i++) {
        int32_t c = d->cell_of[i];
        if (c < 0)
            continue;
        double x = fdt_dualmesh_cell_volume(d, cs, cf, (size_t)c);
        sum += x;
        worst = fmax(worst, fabs(x - vol[i]) / vol[i]);
    }
    double bv = (box[3] - box[0]) * (box[4] - box[1]) * (box[5] - box[2]);
    EXPECTF(worst < 1e-10, "a cell's volume %.3g off the cells'", worst);
    EXPECTF(fabs(sum - bv) < 1e-12 * bv, "the cells add up to %.17g, the box %.17g", sum, bv);
    for (int p = 0; p < 6; p++)
        EXPECT(!(axes >> (p / 2) & 1) || d->patch_size[p] == 0);
    free(cs);
    free(cf);
    fdt_voronoi_free(&v);
}

static int same_dual(const fdt_dualmesh *a, const fdt_dualmesh *b)
{
    return a->n_verts == b->n_verts && a->n_faces == b->n_faces && a->n_cyclic == b->n_cyclic &&
           !memcmp(a->xyz, b->xyz, 3 * a->n_verts * sizeof *a->xyz) &&
           !memcmp(a->fstart, b->fstart, (a->n_faces + 1) * sizeof *a->fstart) &&
           !memcmp(a->fverts, b->fverts, a->fstart[a->n_faces] * sizeof *a->fverts) &&
           !memcmp(a->owner, b->owner, a->n_faces * sizeof *a->owner) &&
           !memcmp(a->cyclic, b->cyclic, a->n_cyclic * sizeof *a->cyclic);
}

static void test_set(const char *name, const double *xyz, size_t n, unsigned axes,
                     const double box[6])
{
    fdt_result *r = periodic_mesh(xyz, n, axes, box);
    check_images(r, xyz, n, axes, box);
    fdt_dualmesh d1, d3;
    check_dual(r, xyz, n, axes, box, 1, &d1);
    check_dual(r, xyz, n, axes, box, 3, &d3);
    EXPECTF(same_dual(&d1, &d3), "%s: the dual on 1 and 3 threads differs", name);
    fdt_dualmesh_free(&d1);
    fdt_dualmesh_free(&d3);
    fdt_result_free(&r);
}

/* The fold's refusals, on the plain dual of a uniform set's images. */
static void test_refusals(void)
{
    const double box[6] = {0, 0, 0, 1, 1, 1};
    const size_t n = 400;
    double *xyz = cube_points(n, box, 5);
    fdt_result *r = periodic_mesh(xyz, n, 7, box);
    fdt_dual_images im;
    char diag[512];
    CHECK(fdt_dual_images_make(r, xyz, n, &im, diag, sizeof diag) == FDT_OK);
    fdt_context *ctx = NULL;
    fdt_result *pr = NULL;
    fdt_settings s;
    fdt_default_settings(&s);
    CHECK(fdt_open(&ctx, &s) == FDT_OK);
    CHECK(fdt_triangulate(ctx, im.xyz, im.m, &pr) == FDT_OK);
    fdt_close(&ctx);
    fdt_voronoi_options o;
    fdt_default_voronoi_options(&o);
    o.box_given = 1;
    memcpy(o.box, im.box, sizeof o.box);
    fdt_dualmesh P, d;
    CHECK(fdt_dualmesh_build_unchecked(pr, im.xyz, im.m, &o, &P, diag, sizeof diag) == FDT_OK);
    EXPECTF(fdt_dualmesh_fold(&P, &im, box, 7, &d, diag, sizeof diag) == FDT_OK, "fold: %s",
            diag);
    fdt_dualmesh_free(&d);
    /* not of these images: one point fewer */
    im.m--;
    EXPECT(fdt_dualmesh_fold(&P, &im, box, 7, &d, diag, sizeof diag) == FDT_EINTERNAL &&
           d.xyz == NULL);
    im.m++;
    /* a vertex of a face between a cell and an image moved by a tenth of
     * the box: the face and its copy differ */
    size_t f = 0;
    while (f < P.n_internal && (size_t)P.neighbour[f] < im.ncells)
        f++;
    CHECK(f < P.n_internal && (size_t)P.owner[f] < im.ncells);
    P.xyz[3 * (size_t)P.fverts[P.fstart[f]]] += 0.1;
    int rc = fdt_dualmesh_fold(&P, &im, box, 7, &d, diag, sizeof diag);
    EXPECTF(rc == FDT_ERANGE && strstr(diag, "cannot be matched") && d.xyz == NULL &&
                d.cyclic == NULL,
            "a moved vertex: %d %s", rc, diag);
    fdt_dualmesh_free(&P);
    fdt_result_free(&pr);
    fdt_dual_images_free(&im);
    fdt_result_free(&r);
    free(xyz);
}

int main(void)
{
    const double cube[6] = {-0.5, 0.25, 1, 0.7, 1.25, 2.5}; /* periods 1.2, 1, 1.5 */
    double *u = cube_points(1200, cube, 3);
    test_set("uniform", u, 1201, 7, cube);
    free(u);
    const double chan[6] = {0, -0.5, 0, 2.1, 0.5, 1.3};
    size_t m;
    double *c = channel_points(1000, 6, chan, 9, &m);
    test_set("channel", c, m, 5, chan);
    free(c);
    test_refusals();
    return test_report("dualperiodic");
}
