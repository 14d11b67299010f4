/*
 * The serial advancing front (src/front/front.c) on its own, below the public
 * API: over a kd tree of prepared points it must build a mesh that
 * fdt_check accepts (orientation, shared faces, neighbour links both ways,
 * closed convex hull, perturbed empty spheres), the same tets with the kd
 * search and the insertion mesh, report progress and stop when the
 * callback asks, and stop the probe after the faces asked for. The mesh
 * buffer grows from any expected size; fdt_tet_face lists each face with
 * the opposite vertex on its negative side.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "front/front.h"
#include "geom/kdtree.h"
#include "geom/predicates.h"
#include "geom/prepare.h"
#include "testutil.h"
#include "testpoints.h"

typedef struct built {
    fdt_prepared pr;
    fdt_kdtree t;
} built;

static void build(built *b, int fam, size_t want)
{
    double *xyz = malloc(3 * want * sizeof *xyz);
    CHECK(xyz);
    size_t n = make_points(fam, want, xyz);
    char diag[256];
    CHECK_EQ(fdt_prepare(xyz, n, 1, &b->pr, diag, sizeof diag), FDT_OK);
    free(xyz);
    CHECK_EQ(fdt_kd_build(&b->t, b->pr.p, b->pr.orig, 0, (uint32_t)b->pr.m, 18), FDT_OK);
}

static void unbuild(built *b)
{
    fdt_kd_free(&b->t);
    fdt_prepared_free(&b->pr);
}

/* The mesh in tree-order ids, checked against the tree-order points. */
static int check_mesh(const built *b, const fdt_meshbuf *mb, char *msg, size_t len)
{
    return fdt_check(b->pr.p, b->pr.m, (const fdt_vid *)mb->tets, mb->ntets, mb->nbrs, msg, len);
}

static int tet_cmp(const void *x, const void *y)
{
    return memcmp(x, y, 4 * sizeof(uint32_t));
}

/* Sorted copy of the tets, each tet's ids ascending (a set to compare). */
static uint32_t *canon(const fdt_meshbuf *mb)
{
    uint32_t *c = malloc(4 * mb->ntets * sizeof *c + 1);
    CHECK(c);
    for (size_t i = 0; i < mb->ntets; i++) {
        uint32_t *v = c + 4 * i;
        memcpy(v, mb->tets + 4 * i, 4 * sizeof *v);
        for (int a = 1; a < 4; a++)
            for (int k = a; k > 0 && v[k - 1] > v[k]; k--) {
                uint32_t s = v[k];
                v[k] = v[k - 1];
                v[k - 1] = s;
            }
    }
    qsort(c, mb->ntets, 4 * sizeof *c, tet_cmp);
    return c;
}

static void test_families(void)
{
    char msg[512];
    for (int fam = 0; fam < NFAMILIES; fam++) {
        built b;
        build(&b, fam, 600);
        fdt_meshbuf kd, mesh;
        /* expected size 1: the buffers must grow */
        CHECK_EQ(fdt_meshbuf_init(&kd, 1, 1), FDT_OK);
        CHECK_EQ(fdt_meshbuf_init(&mesh, 1, 0), FDT_OK);
        fdt_front_stats st;
        memset(&st, 0, sizeof st);
        EXPECTF(fdt_front_serial(&b.t, 0, FDT_SEARCH_KD, &kd, NULL, NULL, &st) == FDT_OK, "%s kd",
                family_name[fam]);
        EXPECTF(check_mesh(&b, &kd, msg, sizeof msg) == FDT_OK, "%s kd: %s", family_name[fam], msg);
        /* one apex search per tet but the seed and per hull face: a face
         * completed by another tet before its turn is never searched */
        EXPECTF(st.faces_advanced == kd.ntets - 1 + kd.nhull, "%s: %zu faces advanced, %zu tets, "
                "%zu hull faces", family_name[fam], st.faces_advanced, kd.ntets, kd.nhull);
        EXPECTF(st.max_front > 0 && st.mesh_faces == 0, "%s: front %zu, mesh faces %zu",
                family_name[fam], st.max_front, st.mesh_faces);
        memset(&st, 0, sizeof st);
        EXPECTF(fdt_front_serial(&b.t, (uint32_t)(b.pr.m / 2), FDT_SEARCH_MESH, &mesh, NULL, NULL,
                                 &st) == FDT_OK,
                "%s mesh", family_name[fam]);
        EXPECTF(mesh.nbrs == NULL && check_mesh(&b, &mesh, msg, sizeof msg) == FDT_OK,
                "%s mesh search: %s", family_name[fam], msg);
        EXPECTF(st.mesh_parts == 1 && st.mesh_faces > 0, "%s: mesh search unused (%zu faces)",
                family_name[fam], st.mesh_faces);
        /* the perturbed Delaunay mesh is unique: the same tets and hull
         * from another start and another search */
        EXPECTF(kd.ntets == mesh.ntets && kd.nhull == mesh.nhull, "%s: %zu/%zu tets, %zu/%zu hull",
                family_name[fam], kd.ntets, mesh.ntets, kd.nhull, mesh.nhull);
        if (kd.ntets == mesh.ntets) {
            uint32_t *a = canon(&kd), *c = canon(&mesh);
            EXPECTF(memcmp(a, c, 4 * kd.ntets * sizeof *a) == 0, "%s: other tets", family_name[fam]);
            free(a);
            free(c);
        }
        /* a closed triangulated surface has an even number of faces */
        EXPECTF(kd.nhull % 2 == 0 && kd.nhull >= 4, "%s: %zu hull faces", family_name[fam],
                kd.nhull);
        fdt_meshbuf_free(&kd);
        fdt_meshbuf_free(&mesh);
        unbuild(&b);
    }
}

/* The callback sees fractions in [0, 0.99], increasing; nonzero stops the
 * front with FDT_ECANCELED at once. */
typedef struct prog {
    int calls, stop_at;
    double last;
    int bad;
} prog;

static int prog_cb(void *user, double f)
{
    prog *p = user;
    if (!(f >= p->last && f <= 0.99))
        p->bad = 1;
    p->last = f;
    return ++p->calls >= p->stop_at;
}

static void test_progress(void)
{
    built b;
    build(&b, UNIFORM, 24000); /* about 150,000 tets: two reports */
    fdt_meshbuf mb;
    CHECK_EQ(fdt_meshbuf_init(&mb, 1000, 0), FDT_OK);
    fdt_front_stats st;
    memset(&st, 0, sizeof st);
    prog p = {0, 1000, 0.0, 0};
    EXPECT(fdt_front_serial(&b.t, 0, FDT_SEARCH_KD, &mb, prog_cb, &p, &st) == FDT_OK);
    EXPECTF(p.calls >= 2 && !p.bad && p.last > 0.5, "%d reports, last %g", p.calls, p.last);
    size_t full = mb.ntets;
    fdt_meshbuf_free(&mb);
    CHECK_EQ(fdt_meshbuf_init(&mb, 1000, 0), FDT_OK);
    memset(&st, 0, sizeof st);
    prog c = {0, 1, 0.0, 0};
    EXPECT(fdt_front_serial(&b.t, 0, FDT_SEARCH_KD, &mb, prog_cb, &c, &st) == FDT_ECANCELED);
    EXPECTF(c.calls == 1 && mb.ntets < full, "cancel: %d calls, %zu of %zu tets", c.calls,
            mb.ntets, full);
    fdt_meshbuf_free(&mb);
    /* the probe: exactly the faces asked for */
    memset(&st, 0, sizeof st);
    EXPECT(fdt_front_probe(&b.t, 0, 256, NULL, &st) == FDT_OK);
    EXPECTF(st.faces_advanced == 256, "probe advanced %zu faces", st.faces_advanced);
    /* with a budget: it stops at the first face that starts with the
     * budget spent (not an error), having spent just over it */
    double full_cost = (double)st.kq.points;
    memset(&st, 0, sizeof st);
    fdt_probe_budget bud = {full_cost / 4, 0.0};
    EXPECT(fdt_front_probe(&b.t, 0, 256, &bud, &st) == FDT_OK);
    EXPECTF(st.faces_advanced > 0 && st.faces_advanced < 256 && (double)st.kq.points > bud.cost,
            "budgeted probe: %zu faces, %zu points tested (budget %g)", st.faces_advanced,
            st.kq.points, bud.cost);
    /* a budget never reached changes nothing */
    memset(&st, 0, sizeof st);
    bud.cost = 2 * full_cost;
    EXPECT(fdt_front_probe(&b.t, 0, 256, &bud, &st) == FDT_OK);
    EXPECTF(st.faces_advanced == 256 && (double)st.kq.points == full_cost,
            "unreached budget: %zu faces", st.faces_advanced);
    unbuild(&b);
}

static void test_meshbuf(void)
{
    fdt_meshbuf mb;
    CHECK_EQ(fdt_meshbuf_init(&mb, 0, 1), FDT_OK);
    for (uint32_t i = 0; i < 5000; i++) {
        uint32_t v[4] = {i, i + 1, i + 2, i + 3}, h[3] = {i, i + 2, i + 1};
        EXPECT(fdt_meshbuf_add_tet(&mb, v) == (int64_t)i);
        EXPECT(fdt_meshbuf_add_hull(&mb, h) == FDT_OK);
    }
    EXPECT(mb.ntets == 5000 && mb.nhull == 5000);
    int ok = 1;
    for (size_t i = 0; i < 5000; i++) {
        ok &= mb.tets[4 * i + 3] == i + 3 && mb.hull[3 * i + 1] == i + 2;
        for (int k = 0; k < 4; k++)
            ok &= mb.nbrs[4 * i + k] == -1; /* no neighbour until linked */
    }
    EXPECT(ok);
    fdt_meshbuf_free(&mb);
    EXPECT(mb.tets == NULL && mb.nbrs == NULL && mb.hull == NULL);
    /* fdt_tet_face: face i omits vertex i and is outward (vertex i on its
     * negative side) for the positive unit tet. */
    const double P[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    CHECK(fdt_orient3d(P[0], P[1], P[2], P[3], NULL) > 0);
    for (int i = 0; i < 4; i++) {
        const int *f = fdt_tet_face[i];
        EXPECTF(f[0] != i && f[1] != i && f[2] != i && f[0] != f[1] && f[1] != f[2] && f[0] != f[2],
                "face %d", i);
        EXPECTF(fdt_orient3d(P[f[0]], P[f[1]], P[f[2]], P[i], NULL) < 0, "face %d not outward", i);
    }
}

int main(void)
{
    test_meshbuf();
    test_families();
    test_progress();
    return test_report("test_front");
}
