/*
 * Tests of the apex oracle (src/front/oracle.c) through the library: the kd
 * search and the insertion mesh must give the same mesh -- the same
 * canonical hash, tet for tet -- in serial, shared and message modes, for
 * any thread count, on the families where the kd search degenerates (an
 * exact cylinder, rotated and plain lattices, integer points on a sphere,
 * two parallel grid layers whose parts hold one layer each, mixed
 * magnitudes) and on uniform points. And:
 *   - `--search mesh` results pass fdt_check (independent exact check);
 *   - the serial auto run is the one-part engine in memory and the parts
 *     in sweep order streamed, every tet from a certified mesh;
 *   - a part whose points are coplanar, or too few, cannot build a mesh
 *     and falls back to the kd search with the same result;
 *   - FDT_MODE_AUTO with threads is the one-part engine; an explicit mode
 *     builds one mesh of every point for the cylinder (the probe) and its
 *     parts read it;
 *   - in shared mode other parts' meshes answer the faces whose sphere
 *     crosses a cut (thread stats mesh_queries).
 * Usage: test_oracle [--quick]   (--quick: fewer thread counts)
 */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "base/clock.h"
#include "frontdt.h"
#include "front/oracle.h"
#include "front/probe.h"
#include "geom/prepare.h"

#include "testutil.h"

typedef struct rng {
    uint64_t s;
} rng;

static double runif(rng *r)
{
    return test_unif(&r->s);
}

typedef struct pts {
    const char *name;
    double *xyz;
    size_t n;
} pts;

static pts pts_alloc(const char *name, size_t n)
{
    pts p = {name, malloc(3 * n * sizeof(double)), n};
    CHECK(p.xyz);
    return p;
}

static void put(pts *p, size_t i, double x, double y, double z)
{
    p->xyz[3 * i] = x;
    p->xyz[3 * i + 1] = y;
    p->xyz[3 * i + 2] = z;
}

static pts gen_uniform(size_t n, uint64_t seed)
{
    pts p = pts_alloc("uniform", n);
    rng r = {seed};
    for (size_t i = 0; i < n; i++)
        put(&p, i, runif(&r), runif(&r), runif(&r));
    return p;
}

/* Rings of equal angle steps on a cylinder of radius 1, empty inside: a
 * pipe scan. Each ring's points are cocircular, pairs of rings
 * cospherical. */
static pts gen_cylinder(int rings, int per_ring)
{
    pts p = pts_alloc("cylinder", (size_t)rings * (size_t)per_ring);
    size_t i = 0;
    for (int k = 0; k < rings; k++)
        for (int j = 0; j < per_ring; j++) {
            double t = 6.283185307179586 * j / per_ring;
            put(&p, i++, cos(t), sin(t), 0.05 * k);
        }
    return p;
}

/* A k^3 lattice, rotated by (ax, ay, az) about x, then y, then z (0: the
 * exact lattice, where every unit cube is cospherical). */
static pts gen_lattice(const char *name, int k, double ax, double ay, double az)
{
    pts p = pts_alloc(name, (size_t)k * k * k);
    size_t i = 0;
    for (int a = 0; a < k; a++)
        for (int b = 0; b < k; b++)
            for (int c = 0; c < k; c++) {
                double x = a, y = b, z = c, t;
                t = y * cos(ax) - z * sin(ax);
                z = y * sin(ax) + z * cos(ax);
                y = t;
                t = x * cos(ay) + z * sin(ay);
                z = -x * sin(ay) + z * cos(ay);
                x = t;
                t = x * cos(az) - y * sin(az);
                y = x * sin(az) + y * cos(az);
                x = t;
                put(&p, i++, x, y, z);
            }
    return p;
}

/* Integer points with x^2 + y^2 + z^2 = R^2: exactly cospherical. */
static pts gen_intsphere(int R)
{
    size_t n = 0;
    for (int pass = 0; pass < 2; pass++) {
        pts p = pts_alloc("intsphere", n ? n : 1);
        size_t i = 0;
        for (int x = -R; x <= R; x++)
            for (int y = -R; y <= R; y++) {
                int z2 = R * R - x * x - y * y;
                if (z2 < 0)
                    continue;
                int z = (int)lround(sqrt((double)z2));
                if (z * z != z2)
                    continue;
                if (pass)
                    put(&p, i, x, y, z);
                i++;
                if (z) {
                    if (pass)
                        put(&p, i, x, y, -z);
                    i++;
                }
            }
        if (pass)
            return p;
        free(p.xyz);
        n = i;
    }
    abort();
}

/* Two layers of one jittered 2-D grid at z = 0 and z = 1 (an extruded 2-D
 * CFD grid): cut along z, each part of two holds one plane. */
static pts gen_layers(int k, uint64_t seed)
{
    pts p = pts_alloc("layers", 2 * (size_t)k * (size_t)k);
    rng r = {seed};
    size_t i = 0;
    for (int a = 0; a < k; a++)
        for (int b = 0; b < k; b++) {
            double x = a + 0.3 * runif(&r), y = b + 0.3 * runif(&r);
            put(&p, i++, x, y, 0.0);
            put(&p, i++, x, y, 1.0);
        }
    return p;
}

/* Clusters at 1e-150, 1 and 1e150 scales in one cloud. */
static pts gen_mixed(size_t n, uint64_t seed)
{
    pts p = pts_alloc("mixed", n);
    rng r = {seed};
    static const double sc[3] = {1e-150, 1.0, 1e150};
    for (size_t i = 0; i < n; i++) {
        double s = sc[i % 3];
        put(&p, i, s * runif(&r), s * runif(&r), s * runif(&r));
    }
    return p;
}

static fdt_result *run(const pts *p, fdt_mode mode, int threads, fdt_search search,
                       fdt_stats *st)
{
    fdt_settings s;
    fdt_default_settings(&s);
    s.mode = mode;
    s.n_threads = threads;
    s.search = search;
    fdt_context *ctx = NULL;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    fdt_result *r = NULL;
    int err = fdt_triangulate(ctx, p->xyz, p->n, &r);
    if (err != FDT_OK)
        fprintf(stderr, "%s: %s\n", p->name, fdt_context_diagnostic(ctx));
    CHECK_EQ(err, FDT_OK);
    fdt_close(&ctx);
    CHECK_EQ(fdt_result_stats(r, st), FDT_OK);
    return r;
}

static int drop_tets(void *user, const fdt_vid *t, size_t count)
{
    (void)user;
    (void)t;
    (void)count;
    return 0;
}

/* A streamed serial run (the tets dropped): the parts in sweep order
 * (src/front/sweep.h). */
static fdt_result *run_stream(const pts *p, fdt_stats *st)
{
    fdt_settings s;
    fdt_default_settings(&s);
    s.mode = FDT_MODE_SERIAL;
    fdt_context *ctx = NULL;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    fdt_sink sink = {sizeof sink, drop_tets, NULL, NULL, NULL, NULL};
    fdt_result *r = NULL;
    int err = fdt_triangulate_stream(ctx, p->xyz, p->n, &sink, &r);
    if (err != FDT_OK)
        fprintf(stderr, "%s (streamed): %s\n", p->name, fdt_context_diagnostic(ctx));
    CHECK_EQ(err, FDT_OK);
    fdt_close(&ctx);
    CHECK_EQ(fdt_result_stats(r, st), FDT_OK);
    return r;
}

static uint64_t set_hash_of(const fdt_result *r)
{
    uint64_t h;
    CHECK_EQ(fdt_result_set_hash(r, &h), FDT_OK);
    return h;
}

static uint64_t hash_of(fdt_result *r)
{
    uint64_t h;
    CHECK_EQ(fdt_result_hash(r, &h), FDT_OK);
    return h;
}

/* Every search, mode and thread count against the kd search in serial
 * mode. In memory, serial --search mesh and auto are the one-part engine
 * (src/front/partmesh.h): every tet from the certified mesh, no front.
 * Streamed, they are the parts in sweep order: every tet from a certified
 * part's mesh, no front. */
static void test_family(pts p, int quick)
{
    fdt_stats st;
    fdt_result *ref = run(&p, FDT_MODE_SERIAL, 1, FDT_SEARCH_KD, &st);
    uint64_t href = hash_of(ref);
    CHECK_EQ(st.mesh_faces, 0);
    CHECK_EQ(st.mesh_parts, 0);

    uint64_t sref = set_hash_of(ref);
    fdt_result *r = run(&p, FDT_MODE_SERIAL, 1, FDT_SEARCH_MESH, &st);
    /* The whole mesh came from the certified insertion mesh, no face was
     * advanced, and it is the Delaunay tetrahedralization. */
    CHECK_EQ(st.mesh_parts, 1);
    CHECK_EQ(st.faces_advanced, 0);
    CHECK_EQ(st.final_tets, st.tets);
    CHECK_EQ(st.certified_tets, st.tets);
    char msg[256];
    int rc = fdt_check(p.xyz, p.n, fdt_result_tets(r), fdt_result_num_tets(r), NULL, msg,
                       sizeof msg);
    if (rc)
        fprintf(stderr, "%s: --search mesh: %s\n", p.name, msg);
    CHECK_EQ(rc, 0);
    CHECK_EQ(hash_of(r), href);
    fdt_result_free(&r);

    r = run(&p, FDT_MODE_SERIAL, 1, FDT_SEARCH_AUTO, &st);
    CHECK_EQ(hash_of(r), href);
    CHECK_EQ(st.final_tets, st.tets);
    fdt_result_free(&r);
    r = run_stream(&p, &st);
    CHECK(set_hash_of(r) == sref);
    CHECK_EQ(st.final_tets, st.tets);
    CHECK_EQ(st.faces_advanced, 0);
    CHECK(st.sweep_parts >= 1 && st.mesh_parts == st.sweep_parts);
    fdt_result_free(&r);

    static const int all_threads[] = {2, 3, 5};
    int nt = quick ? 1 : 3;
    for (int m = 0; m < 2; m++) {
        fdt_mode mode = m ? FDT_MODE_MESSAGE : FDT_MODE_SHARED;
        for (int k = 0; k < nt; k++)
            for (int srch = 0; srch < 3; srch++) {
                fdt_search s = srch == 0 ? FDT_SEARCH_MESH
                             : srch == 1 ? FDT_SEARCH_AUTO : FDT_SEARCH_KD;
                r = run(&p, mode, all_threads[k], s, &st);
                uint64_t h = hash_of(r);
                if (h != href)
                    fprintf(stderr, "%s: mode %d threads %d search %d: hash %016" PRIx64
                            " != %016" PRIx64 "\n", p.name, (int)mode, all_threads[k],
                            (int)s, h, href);
                CHECK_EQ(h, href);
                if (s == FDT_SEARCH_MESH)
                    CHECK(st.mesh_faces > 0 || strcmp(p.name, "layers") == 0);
                /* Shared mode asks the other parts' meshes for the faces
                 * whose sphere crosses a cut (src/par/parallel.c,
                 * offer_from_mesh): on uniform points every part has a
                 * mesh and small conflict regions, so some must be. */
                if (s == FDT_SEARCH_MESH && mode == FDT_MODE_SHARED &&
                    !strcmp(p.name, "uniform")) {
                    size_t mq = 0;
                    for (int i = 0; i < st.threads; i++) {
                        fdt_thread_stats ts;
                        CHECK_EQ(fdt_result_thread_stats(r, i, &ts), FDT_OK);
                        mq += ts.mesh_queries;
                    }
                    CHECK(mq > 0);
                }
                fdt_result_free(&r);
            }
    }
    fdt_result_free(&ref);
    free(p.xyz);
    printf("ok %s (%zu points)\n", p.name, p.n);
}

/* fdt_probe_take copies its samples (an MPI rank's vote for the
 * replica mesh), so the answer is the one on the points as they were when
 * taken: expensive on a rotated lattice, not on uniform points. 74,088 points: both samples (every second point,
 * and a run of consecutive ones). */
static void test_probe_samples(void)
{
    size_t n = 42 * 42 * 42;
    /* a rotated lattice: its sample costs thousands of points a face
     * (bench/NOTES.md entry 55), uniform points' ~90 */
    pts cyl = gen_lattice("rotlattice", 42, 0.3, 0.5, 0.7), uni = gen_uniform(n, 7);
    fdt_prepared a, b; /* scaled as the engine sees them */
    char diag[256];
    CHECK_EQ(fdt_prepare(cyl.xyz, n, 1, &a, diag, sizeof diag), FDT_OK);
    CHECK_EQ(fdt_prepare(uni.xyz, n, 1, &b, diag, sizeof diag), FDT_OK);
    CHECK(a.m == n && b.m == n);
    double *save = malloc(3 * n * sizeof *save);
    CHECK(save);
    memcpy(save, a.p, 3 * n * sizeof *save);
    fdt_probe_samples ps;
    fdt_probe_take(&ps, b.p, (uint32_t)n, 0);
    CHECK(fdt_probe_cost(&ps) < FDT_PROBE_SHARED_MESH);
    fdt_probe_take(&ps, a.p, (uint32_t)n, 0);
    memcpy(a.p, b.p, 3 * n * sizeof *save); /* changed after the take */
    CHECK(fdt_probe_cost(&ps) > FDT_PROBE_REPLICA);
    fdt_probe_take(&ps, a.p, (uint32_t)n, 0);
    memcpy(a.p, save, 3 * n * sizeof *save);
    CHECK(fdt_probe_cost(&ps) < FDT_PROBE_SHARED_MESH);
    CHECK(ps.S[0] == NULL && ps.S[1] == NULL); /* decide frees them */
    free(save);
    fdt_prepared_free(&a);
    fdt_prepared_free(&b);
    free(cyl.xyz);
    free(uni.xyz);
    printf("ok probe samples taken before the points change\n");
}

/* Two layers, two threads: the bisection cuts z (the widest extent is
 * made z by stretching), so a part within one layer is one plane and
 * cannot build a mesh; the kd search answers there instead, with the same
 * result. */
static void test_flat_parts(void)
{
    pts p = gen_layers(12, 7);
    for (size_t i = 0; i < p.n; i++)
        p.xyz[3 * i + 2] *= 100.0;
    fdt_stats st;
    fdt_result *ref = run(&p, FDT_MODE_SERIAL, 1, FDT_SEARCH_KD, &st);
    fdt_result *r = run(&p, FDT_MODE_SHARED, 2, FDT_SEARCH_MESH, &st);
    CHECK_EQ(hash_of(r), hash_of(ref));
    /* The first cut is moved off the median by the work its lower side
     * owns (src/geom/partition.c), so the lower part holds part of the z = 0
     * layer only: flat, no mesh; the upper part has both layers. */
    CHECK(st.mesh_parts < 2);
    fdt_result_free(&r);
    fdt_result_free(&ref);
    free(p.xyz);
    printf("ok flat parts\n");
}

/* A cylinder's points as the engine sees them and their kd-tree: what
 * the tests that drive an oracle directly start from. */
typedef struct cyl_tree {
    pts p;
    fdt_prepared pr;
    fdt_kdtree t;
} cyl_tree;

static void cyl_tree_make(cyl_tree *c, int rings, int per_ring)
{
    char diag[256];
    c->p = gen_cylinder(rings, per_ring);
    CHECK_EQ(fdt_prepare(c->p.xyz, c->p.n, 1, &c->pr, diag, sizeof diag), FDT_OK);
    memset(&c->t, 0, sizeof c->t);
    CHECK_EQ(fdt_kd_build(&c->t, c->pr.p, c->pr.orig, 0, (uint32_t)c->pr.m, 18), FDT_OK);
}

static void cyl_tree_free(cyl_tree *c)
{
    fdt_kd_free(&c->t);
    fdt_prepared_free(&c->pr);
    free(c->p.xyz);
}

/* The mesh policy over a part of 3 points: no mesh, the kd search. */
static void test_small_part(void)
{
    cyl_tree cy;
    cyl_tree_make(&cy, 20, 32);
    fdt_kd_free(&cy.t);
    CHECK_EQ(fdt_kd_build(&cy.t, cy.pr.p, cy.pr.orig, 0, 3, 18), FDT_OK);
    fdt_oracle o;
    fdt_kdq kq;
    memset(&kq, 0, sizeof kq);
    fdt_oracle_init(&o, &cy.t, FDT_ORACLE_MESH);
    fdt_oracle_tick(&o, 0, &kq);
    EXPECT(o.state == -1);
    fdt_oracle_free(&o);
    cyl_tree_free(&cy);
    printf("ok a part too small for a mesh\n");
}

int main(int argc, char **argv)
{
    int quick = argc > 1 && !strcmp(argv[1], "--quick");
    alarm(600);
    test_small_part();
    test_flat_parts();
    test_probe_samples();
    test_family(gen_uniform(3000, 1), quick);
    test_family(gen_cylinder(60, 64), quick);
    test_family(gen_lattice("lattice", 9, 0, 0, 0), quick);
    test_family(gen_lattice("rotlattice", 10, 0.3, 0.5, 0.7), quick);
    test_family(gen_intsphere(25), quick);
    test_family(gen_layers(25, 3), quick);
    test_family(gen_mixed(600, 5), quick);
    /* FDT_MODE_AUTO with threads and --search auto: the one-part engine
     * (src/api/api.c, one_part), the mesh of every point built on the
     * threads is the answer, no front, no part, no message; an explicit
     * shared or message mode runs the parts, which read one mesh of every
     * point, and --search kd keeps the queries. Same hashes as the kd
     * search in serial. */
    {
        pts p = gen_cylinder(60, 64);
        fdt_stats st;
        fdt_result *ref = run(&p, FDT_MODE_SERIAL, 1, FDT_SEARCH_KD, &st);
        for (int t = 2; t <= 7; t++) {
            fdt_result *r = run(&p, FDT_MODE_AUTO, t, FDT_SEARCH_AUTO, &st);
            CHECK_EQ(st.mode, FDT_MODE_SHARED);
            CHECK_EQ(st.threads, t);
            CHECK_EQ(st.mesh_parts, 1);
            CHECK_EQ(st.faces_advanced, 0);
            CHECK_EQ(st.final_tets, st.tets);
            CHECK_EQ(st.certified_tets, st.tets);
            CHECK_EQ(st.remote_queries, 0);
            CHECK_EQ(hash_of(r), hash_of(ref));
            fdt_result_free(&r);
        }
        fdt_result *r;
        /* an explicit shared mode reads the same mesh of every point
         * (src/api/api.c): the search is --search auto's choice, not the
         * mode's; message mode reads it as a replica (an MPI rank's own
         * copy, src/mpi/mpi_run.c), and --search kd keeps the queries */
        for (int t = 1; t <= 3; t++) {
            r = run(&p, FDT_MODE_SHARED, t, FDT_SEARCH_AUTO, &st);
            CHECK_EQ(st.mode, FDT_MODE_SHARED);
            CHECK_EQ(st.mesh_parts, (size_t)t);
            CHECK_EQ(st.remote_queries, 0);
            CHECK_EQ(hash_of(r), hash_of(ref));
            fdt_result_free(&r);
        }
        r = run(&p, FDT_MODE_MESSAGE, 2, FDT_SEARCH_AUTO, &st);
        CHECK_EQ(st.mode, FDT_MODE_MESSAGE);
        CHECK_EQ(st.mesh_parts, 2);
        CHECK_EQ(st.remote_queries, 0);
        CHECK_EQ(hash_of(r), hash_of(ref));
        fdt_result_free(&r);
        r = run(&p, FDT_MODE_MESSAGE, 2, FDT_SEARCH_KD, &st);
        CHECK(st.remote_queries > 0);
        CHECK_EQ(hash_of(r), hash_of(ref));
        fdt_result_free(&r);
        fdt_result_free(&ref);
        free(p.xyz);
        p = gen_uniform(20000, 13);
        r = run(&p, FDT_MODE_AUTO, 2, FDT_SEARCH_AUTO, &st);
        CHECK_EQ(st.mode, FDT_MODE_SHARED);
        CHECK_EQ(st.final_tets, st.tets);
        fdt_result_free(&r);
        free(p.xyz);
        printf("ok auto mode: the one-part engine on threads; explicit modes: the parts\n");
    }
    return test_report("oracle");
}
