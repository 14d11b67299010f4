/*
 * Voronoi cells streamed from the sweep (src/front/cellstream.c, issue
 * 32): for every tests/gen_points family, the cells handed on part by
 * part, with slabs small enough for many parts, at 1 and 3 threads, in
 * batches of a part's closing points or in chunks of them, are the cells of the whole mesh (fdt_voronoi_compute) to
 * the bit, neighbours and face areas included, each point's exactly once.
 * Through the public fdt_voronoi_stream: every input point once (merged
 * duplicates in the last batch), the same bits, the sink's stop, a point
 * outside the box, an engine that is not the sweep, two points too close.
 *
 * Usage: test_cellstream GEN_POINTS
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "frontdt.h"
#include "front/cellstream.h"
#include "front/sweep.h"
#include "geom/prepare.h"
#include "mesh/voronoi.h"
#include "testutil.h"

#define EXPECT_IS(a, b) EXPECTF((a) == (b), "%s is %d, not %d", #a, (int)(a), (int)(b))

/* The cells collected by input id. */
typedef struct got {
    const fdt_voronoi *ref; /* the whole mesh's cells */
    const double *xyz;      /* the points, as given */
    size_t n;
    int *seen;              /* times each id was handed on */
    size_t bad;             /* rows unlike ref's */
    long first_bad;
    int stop_after;         /* nonzero: return 1 at this call */
    int calls;
} got;

static int same_d(double a, double b)
{
    return !memcmp(&a, &b, sizeof a);
}

/* Row r of batch v against the reference's cell of its id. */
static int same_cell(const fdt_voronoi *v, size_t r, const fdt_voronoi *ref, fdt_vid id)
{
    size_t i = (size_t)id;
    if (!same_d(fdt_voronoi_volumes(v)[r], fdt_voronoi_volumes(ref)[i]) ||
        !same_d(fdt_voronoi_areas(v)[r], fdt_voronoi_areas(ref)[i]) ||
        !same_d(fdt_voronoi_densities(v)[r], fdt_voronoi_densities(ref)[i]) ||
        fdt_voronoi_num_faces(v)[r] != fdt_voronoi_num_faces(ref)[i] ||
        fdt_voronoi_flags(v)[r] != fdt_voronoi_flags(ref)[i])
        return 0;
    for (int k = 0; k < 3; k++)
        if (!same_d(fdt_voronoi_centroids(v)[3 * r + k], fdt_voronoi_centroids(ref)[3 * i + k]))
            return 0;
    size_t c1, c2;
    const fdt_vid *n1, *n2;
    const double *a1, *a2;
    if (fdt_voronoi_neighbors(v, (fdt_vid)r, &c1, &n1, &a1) != FDT_OK ||
        fdt_voronoi_neighbors(ref, id, &c2, &n2, &a2) != FDT_OK || c1 != c2)
        return 0;
    return !memcmp(n1, n2, c1 * sizeof *n1) && !memcmp(a1, a2, c1 * sizeof *a1);
}

static int collect(void *user, const fdt_voronoi *v)
{
    got *g = user;
    const fdt_vid *ids = fdt_voronoi_ids(v);
    CHECK(ids != NULL);
    for (size_t r = 0; r < fdt_voronoi_num_points(v); r++) {
        CHECK(ids[r] >= 0 && (size_t)ids[r] < g->n);
        g->seen[ids[r]]++;
        const double *p = fdt_voronoi_points(v) + 3 * r, *q = g->xyz + 3 * (size_t)ids[r];
        if (g->ref && (!same_cell(v, r, g->ref, ids[r]) || !same_d(p[0], q[0]) ||
                       !same_d(p[1], q[1]) || !same_d(p[2], q[2])) && g->bad++ == 0)
            g->first_bad = ids[r];
    }
    return ++g->calls == g->stop_after;
}

static void got_init(got *g, const fdt_voronoi *ref, const double *xyz, size_t n)
{
    memset(g, 0, sizeof *g);
    g->ref = ref;
    g->xyz = xyz;
    g->n = n;
    g->seen = calloc(n ? n : 1, sizeof *g->seen);
    g->first_bad = -1;
    CHECK(g->seen != NULL);
}

static int run_stream(const double *xyz, size_t n, const fdt_settings *s,
                      const fdt_voronoi_options *o, got *g, fdt_result **r, char *diag,
                      size_t ds)
{
    fdt_context *ctx = NULL;
    CHECK_EQ(fdt_open(&ctx, s), FDT_OK);
    fdt_cell_sink cells = {sizeof cells, collect, g};
    int err = fdt_voronoi_stream(ctx, xyz, n, o, NULL, &cells, r);
    snprintf(diag, ds, "%s", fdt_context_diagnostic(ctx));
    fdt_close(&ctx);
    return err;
}

/* One family through fdt_sweep_emit with the cells, at each slab size
 * and thread count. */
static void test_family(const char *gen, const char *fam, size_t n)
{
    size_t m;
    double *xyz = test_gen_family(gen, fam, n, 3, &m);
    fdt_result *r = NULL;
    fdt_voronoi *ref = test_whole_cells(xyz, m, &r);
    if (!ref) {
        /* the cells refused (a box beyond doubles, points too close): the
         * stream refuses them alike */
        fdt_settings s;
        fdt_default_settings(&s);
        s.n_threads = 1;
        got g;
        got_init(&g, NULL, xyz, m);
        fdt_result *sr = NULL;
        char diag[512];
        int err = run_stream(xyz, m, &s, NULL, &g, &sr, diag, sizeof diag);
        EXPECTF(err == FDT_ERANGE && !sr, "%s: cells refused in memory, streamed %d %s", fam,
                err, diag);
        printf("%s: refused (%s)\n", fam, diag);
        free(g.seen);
        free(xyz);
        return;
    }
    /* the default slab is one part for these sizes: test_api's */
    static const uint32_t slabs[] = {97, 500};
    static const int threads[] = {1, 3};
    for (size_t si = 0; si < sizeof slabs / sizeof *slabs; si++)
        for (size_t ti = 0; ti < sizeof threads / sizeof *threads; ti++) {
            if (slabs[si] == 97 && threads[ti] > 1)
                continue;
            char diag[512] = "";
            fdt_prepared pr;
            CHECK_EQ(fdt_prepare(xyz, m, 1, &pr, diag, sizeof diag), FDT_OK);
            fdt_tsink sink;
            fdt_emit em;
            CHECK_EQ(fdt_tsink_init(&sink, pr.orig, NULL), FDT_OK);
            CHECK_EQ(fdt_emit_init(&em, &sink, NULL), FDT_OK);
            got g;
            got_init(&g, ref, xyz, m);
            fdt_cell_sink cells = {sizeof cells, collect, &g};
            fdt_cellstream cs;
            memset(&cs, 0, sizeof cs);
            cs.neighbors = 1;
            cs.sink = &cells;
            cs.chunk = slabs[si] == 500 && threads[ti] == 1 ? 0 : 211; /* chunked batches */
            cs.p_exp = pr.scale_exp;
            fdt_voronoi_box(ref, cs.box);
            CHECK_EQ(fdt_voronoi_scale(cs.box, &cs.ed, diag, sizeof diag), FDT_OK);
            CHECK_EQ(fdt_cellstream_init(&cs, pr.m), FDT_OK);
            fdt_sweep_stats st;
            memset(&st, 0, sizeof st);
            int err = fdt_sweep_emit(pr.p, pr.orig, (uint32_t)pr.m, slabs[si], threads[ti], &em,
                                     &cs, NULL, NULL, &st, diag, sizeof diag);
            EXPECTF(err == FDT_OK && cs.sh.a < 0, "%s slab %u threads %d: %d %s", fam,
                    slabs[si], threads[ti], err, diag);
            size_t once = 0, merged = 0;
            for (size_t i = 0; i < m; i++) {
                int dup = fdt_voronoi_flags(ref)[i] & FDT_CELL_MERGED;
                merged += dup != 0;
                once += g.seen[i] == (dup ? 0 : 1);
            }
            EXPECTF(once == m, "%s slab %u threads %d: %zu of %zu points' cells handed on once",
                    fam, slabs[si], threads[ti], once, m);
            EXPECTF(g.bad == 0, "%s slab %u threads %d: %zu cells differ, first point %ld", fam,
                    slabs[si], threads[ti], g.bad, g.first_bad);
            EXPECTF(cs.cells + merged == m, "%s: %zu cells counted", fam, cs.cells);
            printf("%s slab %u threads %d: %zu parts, %zu batches, %zu tets held at most\n", fam,
                   slabs[si], threads[ti], st.parts, cs.batches, cs.max_held);
            free(g.seen);
            fdt_cellstream_free(&cs);
            fdt_emit_free(&em);
            fdt_tsink_free(&sink);
            fdt_prepared_free(&pr);
        }
    fdt_voronoi_free(&ref);
    fdt_result_free(&r);
    free(xyz);
}

/* The public call: a clustered cloud with duplicates, 1 and 3 threads,
 * every input point once and the same bits; then its refusals. */
static void test_api(void)
{
    size_t n = 4000;
    double *xyz = test_cloud(n, 1, 7);
    for (size_t i = 3000; i < n; i += 7) /* duplicates of earlier points */
        memcpy(xyz + 3 * i, xyz + 3 * (i - 2000), 3 * sizeof *xyz);
    fdt_result *r = NULL;
    fdt_voronoi *ref = test_whole_cells(xyz, n, &r);
    CHECK(ref != NULL);
    fdt_voronoi_options o;
    fdt_default_voronoi_options(&o);
    o.neighbors = 1;
    char diag[512];
    for (int t = 1; t <= 3; t += 2) {
        fdt_settings s;
        fdt_default_settings(&s);
        s.n_threads = t;
        got g;
        got_init(&g, ref, xyz, n);
        fdt_result *sr = NULL;
        int err = run_stream(xyz, n, &s, &o, &g, &sr, diag, sizeof diag);
        EXPECTF(err == FDT_OK, "fdt_voronoi_stream at %d threads: %d %s", t, err, diag);
        size_t once = 0;
        for (size_t i = 0; i < n; i++)
            once += g.seen[i] == 1;
        EXPECTF(once == n && g.bad == 0, "%d threads: %zu of %zu once, %zu differ", t, once, n,
                g.bad);
        uint64_t h1 = 0, h2 = 1;
        CHECK_EQ(fdt_result_set_hash(sr, &h1), FDT_OK);
        CHECK_EQ(fdt_result_set_hash(r, &h2), FDT_OK);
        EXPECTF(h1 == h2, "the stream's tets: set hash %llx against %llx",
                (unsigned long long)h1, (unsigned long long)h2);
        fdt_result_free(&sr);
        free(g.seen);
    }
    fdt_settings s;
    fdt_default_settings(&s);
    s.n_threads = 1;
    got g;
    /* the sink's nonzero return stops the run */
    got_init(&g, ref, xyz, n);
    g.stop_after = 1;
    fdt_result *sr = NULL;
    EXPECT_IS(run_stream(xyz, n, &s, &o, &g, &sr, diag, sizeof diag), FDT_ECANCELED);
    EXPECT(sr == NULL && g.calls == 1);
    free(g.seen);
    /* arguments refused: nothing run, no result */
    {
        fdt_context *ctx = NULL;
        CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
        fdt_cell_sink good = {sizeof good, collect, &g}, small = {1, collect, &g},
                      none = {sizeof none, NULL, &g};
        fdt_sink notets = {sizeof notets, NULL, NULL, NULL, NULL, NULL};
        fdt_voronoi_options osz = o;
        osz.struct_size = 1;
        EXPECT_IS(fdt_voronoi_stream(NULL, xyz, n, &o, NULL, &good, &sr), FDT_EINVAL);
        EXPECT_IS(fdt_voronoi_stream(ctx, NULL, n, &o, NULL, &good, &sr), FDT_EINVAL);
        EXPECT_IS(fdt_voronoi_stream(ctx, xyz, n, &o, NULL, NULL, &sr), FDT_EINVAL);
        EXPECT_IS(fdt_voronoi_stream(ctx, xyz, n, &o, NULL, &small, &sr), FDT_EINVAL);
        EXPECT_IS(fdt_voronoi_stream(ctx, xyz, n, &o, NULL, &none, &sr), FDT_EINVAL);
        EXPECT_IS(fdt_voronoi_stream(ctx, xyz, n, &osz, NULL, &good, &sr), FDT_EINVAL);
        EXPECT_IS(fdt_voronoi_stream(ctx, xyz, n, &o, &notets, &good, &sr), FDT_EINVAL);
        EXPECT_IS(fdt_voronoi_stream(ctx, xyz, n, &o, NULL, &good, NULL), FDT_EINVAL);
        fdt_close(&ctx);
        fdt_settings sn = s;
        sn.neighbors = 1;
        CHECK_EQ(fdt_open(&ctx, &sn), FDT_OK);
        EXPECT_IS(fdt_voronoi_stream(ctx, xyz, n, &o, NULL, &good, &sr), FDT_EINVAL);
        EXPECT(strstr(fdt_context_diagnostic(ctx), "no neighbours") != NULL && sr == NULL);
        fdt_close(&ctx);
        EXPECT(fdt_voronoi_ids(NULL) == NULL && fdt_voronoi_points(NULL) == NULL);
        EXPECT(fdt_voronoi_ids(ref) == NULL && fdt_voronoi_points(ref) == NULL);
    }
    /* a given box that leaves a point out: refused before any cell */
    got_init(&g, ref, xyz, n);
    fdt_voronoi_options ob = o;
    ob.box_given = 1;
    const double box[6] = {0.1, 0, 0, 1, 1, 1};
    memcpy(ob.box, box, sizeof box);
    EXPECT_IS(run_stream(xyz, n, &s, &ob, &g, &sr, diag, sizeof diag), FDT_EINVAL);
    EXPECTF(strstr(diag, "outside the box") && g.calls == 0, "box: %s", diag);
    free(g.seen);
    /* the kd fronts say nothing of when a point's last tet is out */
    got_init(&g, ref, xyz, n);
    s.search = FDT_SEARCH_KD;
    EXPECT_IS(run_stream(xyz, n, &s, &o, &g, &sr, diag, sizeof diag), FDT_EINVAL);
    EXPECTF(strstr(diag, "sweep order") != NULL, "kd: %s", diag);
    free(g.seen);
    fdt_voronoi_free(&ref);
    fdt_result_free(&r);
    /* two points too close for the cells: the message of the whole
     * mesh's cells, after the run */
    xyz[3] = xyz[0] + 1e-16;
    xyz[4] = xyz[1];
    xyz[5] = xyz[2];
    r = test_triangulate(xyz, n, 1, 0);
    char want[512];
    fdt_voronoi *v = NULL;
    EXPECT_IS(fdt_voronoi_compute(r, xyz, n, &o, &v, want, sizeof want), FDT_ERANGE);
    s.search = FDT_SEARCH_AUTO;
    got_init(&g, NULL, xyz, n);
    g.stop_after = -1;
    EXPECT_IS(run_stream(xyz, n, &s, &o, &g, &sr, diag, sizeof diag), FDT_ERANGE);
    EXPECTF(!strcmp(diag, want), "too close: \"%s\" against \"%s\"", diag, want);
    free(g.seen);
    fdt_result_free(&r);
    free(xyz);
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: test_cellstream GEN_POINTS\n");
        return 2;
    }
    int families = test_each_family(argv[1], 2000, test_family);
    EXPECTF(families > 30, "only %d families listed", families);
    test_api();
    return test_report("cellstream");
}
