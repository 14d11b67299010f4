/*
 * The per-part step of the parallel engine (src/par/engine.c) through
 * fdt_parallel_run on the mailbox transport, its contract read off the
 * gathered mesh and the per-thread stats:
 * - ownership (§3.2): every tet and hull face a thread output has its
 *   lowest id (tree order) in the thread's own part (parts are
 *   consecutive ranges of tree ids, of tstats[i].points each);
 * - the same tets as the serial engine, in both modes, with and without
 *   the neighbour links, which are symmetric and -1 only on the hull;
 * - messages: a thread sends at most one face per tet it builds plus one
 *   tet request per face it advances; duplicate requests are among the
 *   requests sent; every FACESEND sent is received;
 * - an injected failure of any part, before or after its first faces,
 *   ends the run with FDT_EINTERNAL naming that part, and no mesh;
 * - with the mesh of every point built first, the parts own equal shares
 *   of its tets, and few faces are found by walks;
 * - the collective switch: the mesh of every point is built in the middle
 *   of the run once a majority of the parts votes for it, never on one
 *   part's vote of two, with serial's tets either way.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "frontdt.h"
#include "par/parallel.h"
#include "geom/prepare.h"
#include "testutil.h"

typedef struct input {
    const char *name;
    double *xyz;
    size_t n;
} input;

static input uniform(size_t n, uint64_t seed)
{
    input in = {"uniform", malloc(3 * n * sizeof(double)), n};
    CHECK(in.xyz != NULL);
    for (size_t i = 0; i < 3 * n; i++)
        in.xyz[i] = test_unif(&seed);
    return in;
}

/* k^3 lattice points: every cube's corners cospherical (ties). */
static input lattice(int k)
{
    input in = {"lattice", malloc(3 * (size_t)k * k * k * sizeof(double)), (size_t)k * k * k};
    CHECK(in.xyz != NULL);
    size_t n = 0;
    for (int i = 0; i < k; i++)
        for (int j = 0; j < k; j++)
            for (int l = 0; l < k; l++, n++) {
                in.xyz[3 * n] = i;
                in.xyz[3 * n + 1] = j;
                in.xyz[3 * n + 2] = l;
            }
    return in;
}

static int cmp4(const void *a, const void *b)
{
    return memcmp(a, b, 4 * sizeof(uint32_t));
}

static void sort4(uint32_t *v)
{
    for (int i = 1; i < 4; i++)
        for (int j = i; j > 0 && v[j - 1] > v[j]; j--) {
            uint32_t s = v[j];
            v[j] = v[j - 1];
            v[j - 1] = s;
        }
}

/* The canonical set of n tets in place: each sorted, then the list. */
static void canon_set(uint32_t *c, size_t n)
{
    for (size_t i = 0; i < n; i++)
        sort4(c + 4 * i);
    qsort(c, n, 4 * sizeof *c, cmp4);
}

/* Whether the n tets are the canonical set ref (serial_set), in any
 * order of tets and of each tet's vertices. */
static int same_set(const uint32_t *tets, const uint32_t *ref, size_t n)
{
    uint32_t *c = malloc(n * 4 * sizeof *c + 1);
    CHECK(c != NULL);
    memcpy(c, tets, n * 4 * sizeof *c);
    canon_set(c, n);
    int same = !memcmp(c, ref, n * 4 * sizeof *c);
    free(c);
    return same;
}

/* Tets of the serial run (input numbering), each sorted, then sorted:
 * the canonical set. */
static uint32_t *serial_set(const input *in, size_t *nt)
{
    fdt_settings s;
    fdt_default_settings(&s);
    s.mode = FDT_MODE_SERIAL;
    fdt_context *ctx = NULL;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    fdt_result *r = NULL;
    CHECK_EQ(fdt_triangulate(ctx, in->xyz, in->n, &r), FDT_OK);
    *nt = fdt_result_num_tets(r);
    uint32_t *c = malloc(*nt * 4 * sizeof *c);
    CHECK(c != NULL);
    const fdt_vid *t = fdt_result_tets(r);
    for (size_t i = 0; i < 4 * *nt; i++)
        c[i] = (uint32_t)t[i];
    canon_set(c, *nt);
    fdt_result_free(&r);
    fdt_close(&ctx);
    return c;
}

static void run_checked(const input *in, const uint32_t *ref, size_t nref, fdt_mode mode,
                        int nthreads, int nbrs)
{
    fdt_prepared pr;
    char diag[256] = "";
    CHECK_EQ(fdt_prepare(in->xyz, in->n, 1, &pr, diag, sizeof diag), FDT_OK);
    fdt_settings s;
    fdt_default_settings(&s);
    s.neighbors = nbrs;
    fdt_par_out out;
    int err = fdt_parallel_run(&pr, &s, mode, nthreads, NULL, &out, diag, sizeof diag);
    EXPECTF(err == FDT_OK, "%s, mode %d, %d threads: %d %s", in->name, mode, nthreads, err, diag);
    if (err) {
        fdt_prepared_free(&pr);
        return;
    }
    CHECK_EQ(out.nthreads, nthreads);
    /* input index -> tree id */
    uint32_t *tree_id = malloc(in->n * sizeof *tree_id);
    CHECK(tree_id != NULL);
    for (size_t i = 0; i < pr.m; i++)
        tree_id[pr.orig[i]] = (uint32_t)i;
    size_t t0 = 0, h0 = 0, lo = 0, fsent = 0, req = 0, dup = 0;
    for (int i = 0; i < nthreads; i++) {
        const fdt_thread_stats *ts = &out.tstats[i];
        size_t hi = lo + ts->points;
        int bad_t = 0, bad_h = 0;
        for (size_t t = t0; t < t0 + ts->tets; t++) {
            uint32_t m = UINT32_MAX;
            for (int k = 0; k < 4; k++) {
                uint32_t id = tree_id[out.mb.tets[4 * t + k]];
                m = id < m ? id : m;
            }
            bad_t += m < lo || m >= hi;
        }
        for (size_t h = h0; h < h0 + ts->hull_faces; h++) {
            uint32_t m = UINT32_MAX;
            for (int k = 0; k < 3; k++) {
                uint32_t id = tree_id[out.mb.hull[3 * h + k]];
                m = id < m ? id : m;
            }
            bad_h += m < lo || m >= hi;
        }
        EXPECTF(bad_t == 0 && bad_h == 0,
                "%s, mode %d, %d threads: thread %d output %d tets, %d hull faces it does not own",
                in->name, mode, nthreads, i, bad_t, bad_h);
        EXPECTF(ts->sent[FDT_MSG_FACESEND] <= ts->tets + ts->faces_advanced,
                "thread %d: %zu FACESENDs for %zu tets and %zu faces", i,
                ts->sent[FDT_MSG_FACESEND], ts->tets, ts->faces_advanced);
        req += ts->tet_requests; /* counted by the sender */
        dup += ts->duplicate_requests; /* by the receiver */
        fsent += ts->sent[FDT_MSG_FACESEND];
        t0 += ts->tets;
        h0 += ts->hull_faces;
        lo = hi;
    }
    EXPECT(lo == pr.m && t0 == out.mb.ntets && h0 == out.mb.nhull);
    EXPECT(dup <= req && req <= fsent);
    EXPECT(out.pst.sent[FDT_MSG_FACESEND] == fsent &&
           out.pst.received[FDT_MSG_FACESEND] == fsent);
    /* with one part nothing crosses */
    if (nthreads == 1)
        EXPECT(fsent == 0);
    /* the serial engine's tets */
    EXPECT(out.mb.ntets == nref);
    if (out.mb.ntets == nref)
        EXPECTF(same_set(out.mb.tets, ref, nref), "%s, mode %d, %d threads: serial's tets",
                in->name, mode, nthreads);
    /* neighbours: symmetric, -1 exactly on the hull */
    if (nbrs) {
        size_t open = 0, asym = 0;
        for (size_t t = 0; t < out.mb.ntets; t++)
            for (int f = 0; f < 4; f++) {
                int64_t u = out.mb.nbrs[4 * t + f];
                if (u < 0) {
                    open++;
                    continue;
                }
                int back = 0;
                for (int g = 0; g < 4; g++)
                    back += out.mb.nbrs[4 * (size_t)u + g] == (int64_t)t;
                asym += back != 1;
            }
        EXPECTF(open == out.mb.nhull && asym == 0, "%s, mode %d, %d threads: %zu open, %zu hull, %zu one-way",
                in->name, mode, nthreads, open, out.mb.nhull, asym);
    } else {
        EXPECT(out.mb.nbrs == NULL);
    }
    free(tree_id);
    fdt_par_out_free(&out);
    fdt_prepared_free(&pr);
}

/* Part `part` fails once it has advanced `after` faces. */
static void run_failing(const input *in, fdt_mode mode, int nthreads, int part, size_t after)
{
    fdt_prepared pr;
    char diag[256] = "";
    CHECK_EQ(fdt_prepare(in->xyz, in->n, 1, &pr, diag, sizeof diag), FDT_OK);
    fdt_settings s;
    fdt_default_settings(&s);
    fdt_par_opts opt;
    memset(&opt, 0, sizeof opt);
    opt.fail = 1;
    opt.fail_part = part;
    opt.fail_after = after;
    fdt_par_out out;
    int err = fdt_parallel_run(&pr, &s, mode, nthreads, &opt, &out, diag, sizeof diag);
    char want[64];
    snprintf(want, sizeof want, "worker thread %d:", part);
    EXPECTF(err == FDT_EINTERNAL && strstr(diag, want) != NULL,
            "mode %d, %d threads, part %d fails after %zu: %d, %s", mode, nthreads, part, after,
            err, diag);
    EXPECT(out.mb.tets == NULL && out.tstats == NULL);
    fdt_prepared_free(&pr);
}

/* An exact pipe: rings of per_ring points about the x axis from x = x0,
 * radius 0.5 about (y, z) = (0.5, 0.5), rings 1/40 apart; the kd search
 * tests hundreds of points a face there (src/front/oracle.c). Appended at in's
 * point `at`. */
static void put_pipe(input *in, size_t at, int rings, int per_ring, double x0)
{
    size_t n = at;
    for (int k = 0; k < rings; k++)
        for (int j = 0; j < per_ring; j++, n++) {
            double t = 6.283185307179586 * j / per_ring;
            in->xyz[3 * n] = x0 + 0.025 * k;
            in->xyz[3 * n + 1] = 0.5 + 0.5 * cos(t);
            in->xyz[3 * n + 2] = 0.5 + 0.5 * sin(t);
        }
}

/*
 * The wall engine (src/par/engine.c, walls_start; bench/NOTES.md entry 90),
 * what a threaded run with --search mesh does (and auto where the mesh of
 * every point does not fit): each part's own mesh, its final tets emitted at
 * once, the fronts from the walls. Serial's tets in both modes; every
 * part built a mesh (mesh_parts), final_tets says how many came straight
 * from them (want_final: some, or none), and each part's wall faces and
 * final tets are in its thread statistics.
 */
static void run_walls(const input *in, const uint32_t *ref, size_t nref, int nthreads,
                      fdt_mode mode, int want_final)
{
    fdt_prepared pr;
    char diag[256] = "";
    CHECK_EQ(fdt_prepare(in->xyz, in->n, 1, &pr, diag, sizeof diag), FDT_OK);
    fdt_settings s;
    fdt_default_settings(&s);
    s.search = FDT_SEARCH_MESH;
    fdt_par_out out;
    int err = fdt_parallel_run(&pr, &s, mode, nthreads, NULL, &out, diag, sizeof diag);
    EXPECTF(err == FDT_OK, "%s, walls, %d threads: %d %s", in->name, nthreads, err, diag);
    if (err) {
        fdt_prepared_free(&pr);
        return;
    }
    EXPECTF((int)out.fst.mesh_parts == nthreads, "%s, walls, %d threads: %zu parts built a mesh",
            in->name, nthreads, out.fst.mesh_parts);
    size_t fin = 0, walls = 0;
    for (int i = 0; i < nthreads; i++) {
        fin += out.tstats[i].final_tets;
        walls += out.tstats[i].wall_faces;
    }
    EXPECT(fin == out.fst.final_tets);
    EXPECTF(want_final ? fin > 0 && fin < nref && walls > 0 : fin == 0,
            "%s, walls, %d threads: %zu final of %zu, %zu wall faces", in->name, nthreads, fin,
            nref, walls);
    /* the same path again: each part's final tets and wall faces are a
     * function of its points, never of timing */
    fdt_par_out again;
    CHECK_EQ(fdt_parallel_run(&pr, &s, mode, nthreads, NULL, &again, diag, sizeof diag), FDT_OK);
    for (int i = 0; i < nthreads; i++)
        EXPECTF(again.tstats[i].final_tets == out.tstats[i].final_tets &&
                    again.tstats[i].wall_faces == out.tstats[i].wall_faces,
                "%s, walls, %d threads: part %d's final tets or walls changed", in->name,
                nthreads, i);
    fdt_par_out_free(&again);
    /* the fronts built the rest */
    EXPECT(out.fst.faces_advanced > 0);
    EXPECT(out.mb.ntets == nref);
    if (out.mb.ntets == nref)
        EXPECTF(same_set(out.mb.tets, ref, nref), "%s, walls, %d threads: serial's tets",
                in->name, nthreads);
    fdt_par_out_free(&out);
    fdt_prepared_free(&pr);
}

/*
 * The mesh of every point built before the fronts (global_mesh 1): the
 * parts' ranges are moved so that each owns as many of its tets and hull
 * faces (src/par/parallel.c, recut_by_mesh), where the bisection's halves of
 * a pipe gave the lower part every tet across the cut; and a tet built on
 * another part's request has its mesh slot noted (the request carries
 * it), so its faces are not found by walks around a vertex. Serial's
 * tets, tets a thread within 10 % (the hull faces count too), and under
 * 2 % of the faces found by a walk.
 */
static void test_recut(void)
{
    /* a pipe scan as tests/gen_points cylscan makes it: 71 rings of 71
     * points at jittered angles, rings 2 pi / 71 apart, radius 1 */
    const int m = 71;
    input pipe = {"pipe scan", malloc(3 * (size_t)m * m * sizeof(double)), (size_t)m * m};
    CHECK(pipe.xyz != NULL);
    uint64_t seed = 29;
    for (int j = 0, n = 0; j < m; j++)
        for (int i = 0; i < m; i++, n++) {
            double a = 6.283185307179586 * (i + 0.9 * test_unif(&seed) - 0.45) / m;
            pipe.xyz[3 * n] = cos(a);
            pipe.xyz[3 * n + 1] = sin(a);
            pipe.xyz[3 * n + 2] = j * 6.283185307179586 / m;
        }
    size_t nref;
    uint32_t *ref = serial_set(&pipe, &nref);
    fdt_prepared pr;
    char diag[256] = "";
    CHECK_EQ(fdt_prepare(pipe.xyz, pipe.n, 1, &pr, diag, sizeof diag), FDT_OK);
    fdt_settings s;
    fdt_default_settings(&s);
    fdt_par_opts opt;
    memset(&opt, 0, sizeof opt);
    opt.global_mesh = 1;
    fdt_par_out out;
    CHECK_EQ(fdt_parallel_run(&pr, &s, FDT_MODE_SHARED, 2, &opt, &out, diag, sizeof diag), FDT_OK);
    EXPECT(out.mb.ntets == nref);
    EXPECTF(out.pst.load_imbalance < 1.1, "pipe, mesh first: load imbalance %.3f (tets %zu, %zu)",
            out.pst.load_imbalance, out.tstats[0].tets, out.tstats[1].tets);
    EXPECTF(out.fst.star_walks * 50 < out.fst.faces_advanced, "pipe: %zu of %zu faces by a walk",
            out.fst.star_walks, out.fst.faces_advanced);
    if (out.mb.ntets == nref)
        EXPECT(same_set(out.mb.tets, ref, nref));
    fdt_par_out_free(&out);
    /* Message mode reads the same mesh as a replica (src/api/api.c; an MPI
     * rank builds its own, src/mpi/mpi_run.c): no part asks another, and the
     * tets are serial's. Before, each part kept a mesh of its own points
     * and asked the others, whose kd searches degenerate on a pipe. */
    fdt_prepared_free(&pr);
    for (int t = 2; t <= 3; t++) {
        CHECK_EQ(fdt_prepare(pipe.xyz, pipe.n, 1, &pr, diag, sizeof diag), FDT_OK);
        CHECK_EQ(fdt_parallel_run(&pr, &s, FDT_MODE_MESSAGE, t, &opt, &out, diag, sizeof diag),
                 FDT_OK);
        EXPECTF(out.pst.remote_queries == 0 && out.pst.sent[FDT_MSG_NODESEND] == 0,
                "pipe, message mode, %d threads: %zu remote queries", t, out.pst.remote_queries);
        EXPECT(out.pst.sent[FDT_MSG_FACESEND] > 0);
        EXPECT(out.mb.ntets == nref);
        if (out.mb.ntets == nref)
            EXPECTF(same_set(out.mb.tets, ref, nref), "pipe, message mode, %d threads", t);
        fdt_par_out_free(&out);
        fdt_prepared_free(&pr);
    }
    fdt_prepared_free(&pr);
    free(ref);
    free(pipe.xyz);
    printf("mesh first: a pipe's tets split evenly, requests carry their mesh slot\n");
}

static void test_walls(void)
{
    /* uniform points: most tets final at once, in both modes */
    input uni = uniform(3000, 23);
    size_t nref;
    uint32_t *ref = serial_set(&uni, &nref);
    for (int t = 2; t <= 5; t += 3) {
        run_walls(&uni, ref, nref, t, FDT_MODE_SHARED, 1);
        run_walls(&uni, ref, nref, t, FDT_MODE_MESSAGE, 1);
    }
    free(ref);
    /* a pipe on 3 parts: its tets span the parts (circumspheres as wide
     * as the pipe), so no tet is final; the seeds start the fronts */
    input pipe = {"pipe", malloc(3 * 40 * 64 * sizeof(double)), 40 * 64};
    CHECK(pipe.xyz != NULL);
    put_pipe(&pipe, 0, 40, 64, 0.0);
    ref = serial_set(&pipe, &nref);
    run_walls(&pipe, ref, nref, 2, FDT_MODE_SHARED, 0);
    run_walls(&pipe, ref, nref, 3, FDT_MODE_MESSAGE, 0);
    free(ref);
    free(pipe.xyz);
    free(uni.xyz);
    printf("walls: uniform points final at once on 2 and 5 parts, a pipe from its seeds, "
           "serial's tets\n");
}

int main(void)
{
    setvbuf(stdout, NULL, _IOLBF, 0);
    alarm(600);
    input ins[2] = {uniform(2000, 5), lattice(7)};
    for (int f = 0; f < 2; f++) {
        size_t nref;
        uint32_t *ref = serial_set(&ins[f], &nref);
        static const int nts[] = {1, 2, 3, 5, 8};
        for (int m = FDT_MODE_SHARED; m <= FDT_MODE_MESSAGE; m++)
            for (int i = 0; i < 5; i++)
                run_checked(&ins[f], ref, nref, (fdt_mode)m, nts[i], i % 2);
        printf("%s, %zu points: ownership, serial's tets, neighbours, messages on 1-8 threads\n",
               ins[f].name, ins[f].n);
        free(ref);
    }
    for (int m = FDT_MODE_SHARED; m <= FDT_MODE_MESSAGE; m++)
        for (int part = 0; part < 3; part++) {
            run_failing(&ins[0], (fdt_mode)m, 3, part, 0);
            run_failing(&ins[0], (fdt_mode)m, 3, part, 25);
        }
    printf("injected failures: every part, both modes, named\n");
    test_walls();
    test_recut();
    for (int f = 0; f < 2; f++)
        free(ins[f].xyz);
    return test_report("engine");
}
