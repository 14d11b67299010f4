/*
 * The public API's contract (include/frontdt.h, src/api/api.c, src/mesh/result.c)
 * through the public header alone: settings and their defaults, refused
 * arguments, every error code's text and the diagnostics that name the
 * point, the result getters (NULL-safe), the duplicate map, and the
 * progress callback and cancellation of a serial run (the parallel modes'
 * are in tests/test_parallel.c); and the ABI rules for the structs that
 * may grow (struct_size first, sizes the library does not know refused
 * with FDT_EINVAL and nothing written beyond them), through the installed
 * shared library rather than the internal archive.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "frontdt.h"
#include "testutil.h"

static void test_settings(void)
{
    fdt_settings s;
    memset(&s, 0x5a, sizeof s);
    fdt_default_settings(&s);
    EXPECT(s.mode == FDT_MODE_AUTO && s.n_threads == 0 && s.pin == 0 && s.neighbors == 0);
    EXPECT(s.leaf_size > 0 && s.progress == NULL && s.progress_user == NULL);
    EXPECT(s.search == FDT_SEARCH_AUTO);
    EXPECT(strcmp(fdt_version(), FDT_VERSION_STRING) == 0);

    fdt_context *ctx = (fdt_context *)&s; /* must be set to NULL on failure */
    EXPECT(fdt_open(NULL, &s) == FDT_EINVAL);
    EXPECT(fdt_open(&ctx, NULL) == FDT_EINVAL && ctx == NULL);
    const struct {
        int mode, threads, leaf;
    } bad[] = {{-1, 1, 0}, {FDT_MODE_MESSAGE + 1, 1, 0}, {0, -1, 0}, {0, 1025, 0}, {0, 1, -1}};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        fdt_default_settings(&s);
        s.mode = (fdt_mode)bad[i].mode;
        s.n_threads = bad[i].threads;
        s.leaf_size = bad[i].leaf;
        ctx = (fdt_context *)&s;
        EXPECTF(fdt_open(&ctx, &s) == FDT_EINVAL && ctx == NULL, "bad setting %zu accepted", i);
    }
    fdt_default_settings(&s);
    s.n_threads = 1024;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    EXPECT(ctx != NULL && strcmp(fdt_context_diagnostic(ctx), "") == 0);
    fdt_close(&ctx);
    EXPECT(ctx == NULL);
    fdt_close(&ctx); /* NULL is fine */
    fdt_close(NULL);
    EXPECT(strcmp(fdt_context_diagnostic(NULL), "") == 0);

    /* Every code has its own text; unknown codes too. */
    const int codes[] = {FDT_OK, FDT_EINVAL, FDT_ENOMEM, FDT_EDEGENERATE, FDT_ERANGE,
                         FDT_ETOOBIG, FDT_ECHECK, FDT_ECANCELED, FDT_EINTERNAL, FDT_ETHREAD};
    const int nc = (int)(sizeof codes / sizeof *codes);
    for (int i = 0; i < nc; i++) {
        const char *t = fdt_strerror(codes[i]);
        EXPECTF(t && *t && strcmp(t, fdt_strerror(-100)) != 0, "code %d", codes[i]);
        for (int j = 0; j < i; j++)
            EXPECTF(strcmp(t, fdt_strerror(codes[j])) != 0, "codes %d and %d share a text",
                    codes[i], codes[j]);
    }
    EXPECT(strcmp(fdt_strerror(-100), "unknown error") == 0 && fdt_strerror(1) != NULL);
}

static fdt_context *open_serial(int nbrs, fdt_progress_fn fn, void *user)
{
    fdt_settings s;
    fdt_default_settings(&s);
    s.mode = FDT_MODE_SERIAL;
    s.neighbors = nbrs;
    s.progress = fn;
    s.progress_user = user;
    fdt_context *ctx = NULL;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    return ctx;
}

static void test_errors(void)
{
    fdt_context *ctx = open_serial(0, NULL, NULL);
    fdt_result *r = (fdt_result *)ctx;
    double cube[8 * 3];
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++)
            cube[3 * i + k] = (i >> k) & 1;
    EXPECT(fdt_triangulate(NULL, cube, 8, &r) == FDT_EINVAL);
    EXPECT(fdt_triangulate(ctx, cube, 8, NULL) == FDT_EINVAL);
    EXPECT(fdt_triangulate(ctx, NULL, 8, &r) == FDT_EINVAL);
    /* a NaN names its point and axis; the result stays NULL */
    cube[3 * 5 + 1] = NAN;
    r = (fdt_result *)ctx;
    EXPECT(fdt_triangulate(ctx, cube, 8, &r) == FDT_ERANGE && r == NULL);
    EXPECTF(strstr(fdt_context_diagnostic(ctx), "point 5") != NULL, "diagnostic '%s'",
            fdt_context_diagnostic(ctx));
    cube[3 * 5 + 1] = INFINITY;
    EXPECT(fdt_triangulate(ctx, cube, 8, &r) == FDT_ERANGE && r == NULL);
    cube[3 * 5 + 1] = 0.0;
    /* coplanar: the bottom face four times over */
    double flat[12 * 3];
    for (int i = 0; i < 12; i++) {
        flat[3 * i] = i % 4;
        flat[3 * i + 1] = i / 4;
        flat[3 * i + 2] = 2.0;
    }
    EXPECT(fdt_triangulate(ctx, flat, 12, &r) == FDT_EDEGENERATE && r == NULL);
    EXPECTF(strstr(fdt_context_diagnostic(ctx), "coplanar") != NULL, "diagnostic '%s'",
            fdt_context_diagnostic(ctx));
    EXPECT(fdt_triangulate(ctx, cube, 3, &r) == FDT_EDEGENERATE && r == NULL);
    EXPECT(fdt_triangulate(ctx, cube, 0, &r) == FDT_EDEGENERATE && r == NULL);
    /* a success clears the diagnostic */
    EXPECT(fdt_triangulate(ctx, cube, 8, &r) == FDT_OK && r != NULL);
    EXPECT(strcmp(fdt_context_diagnostic(ctx), "") == 0);
    fdt_result_free(&r);
    EXPECT(r == NULL);
    fdt_result_free(&r);
    fdt_result_free(NULL);
    fdt_close(&ctx);
}

/* The getters on NULL, and the result of a cube with repeated points:
 * the duplicate map sends each copy to the first index of its
 * coordinates (-0 == +0), the tets use first indices only and pass
 * fdt_check, the hull is the cube's 12 triangles. */
static void test_result(void)
{
    EXPECT(fdt_result_num_tets(NULL) == 0 && fdt_result_tets(NULL) == NULL);
    EXPECT(fdt_result_neighbors(NULL) == NULL && fdt_result_num_hull_faces(NULL) == 0);
    EXPECT(fdt_result_hull_faces(NULL) == NULL && fdt_result_duplicate_map(NULL) == NULL);
    EXPECT(fdt_result_num_duplicates(NULL) == 0);
    fdt_stats st;
    fdt_thread_stats ts;
    uint64_t h;
    EXPECT(fdt_result_stats(NULL, &st) == FDT_EINVAL);
    EXPECT(fdt_result_thread_stats(NULL, 0, &ts) == FDT_EINVAL);
    EXPECT(fdt_result_sort(NULL) == FDT_EINVAL);
    EXPECT(fdt_result_hash(NULL, &h) == FDT_EINVAL);

    /* 8 corners, then copies: 8 = 0, 9 = 3 (-0 for 0), 10 = 8's copy, 11 = 7 */
    double xyz[12 * 3];
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++)
            xyz[3 * i + k] = (i >> k) & 1;
    const int src[4] = {0, 3, 0, 7};
    for (int i = 0; i < 4; i++)
        memcpy(xyz + 3 * (8 + i), xyz + 3 * src[i], 3 * sizeof *xyz);
    xyz[3 * 9 + 2] = -0.0;
    const fdt_vid want_map[12] = {0, 1, 2, 3, 4, 5, 6, 7, 0, 3, 0, 7};
    fdt_context *ctx = open_serial(1, NULL, NULL);
    fdt_result *r = NULL;
    CHECK_EQ(fdt_triangulate(ctx, xyz, 12, &r), FDT_OK);
    const fdt_vid *map = fdt_result_duplicate_map(r);
    CHECK(map != NULL);
    EXPECT(memcmp(map, want_map, sizeof want_map) == 0);
    EXPECT(fdt_result_num_duplicates(r) == 4);
    size_t nt = fdt_result_num_tets(r);
    const fdt_vid *t = fdt_result_tets(r);
    EXPECTF(nt >= 5 && nt <= 6, "%zu tets in a cube", nt);
    for (size_t i = 0; i < 4 * nt; i++)
        EXPECTF(t[i] >= 0 && t[i] < 8, "tet vertex %d is not a first index", (int)t[i]);
    char msg[256];
    EXPECTF(fdt_check(xyz, 12, t, nt, fdt_result_neighbors(r), msg, sizeof msg) == FDT_OK, "%s",
            msg);
    EXPECT(fdt_result_num_hull_faces(r) == 12 && fdt_result_hull_faces(r) != NULL);
    CHECK_EQ(fdt_result_stats(r, &st), FDT_OK);
    EXPECT(st.points == 12 && st.vertices == 8 && st.tets == nt && st.hull_faces == 12);
    /* serial in memory: the one-part engine, every tet from the certified
     * mesh and no face advanced (src/front/partmesh.h) */
    EXPECT(st.threads == 1 && st.mode == FDT_MODE_SERIAL && st.faces_advanced == 0);
    EXPECT(st.final_tets == nt && st.certified_tets == nt);
    /* its insertion's counts: conflict tests made, nothing deferred on one
     * thread */
    EXPECT(st.ins_conflict_tests > 0 && st.ins_deferred == 0 && st.ins_serial == 0);
    EXPECT(fdt_result_stats(r, NULL) == FDT_EINVAL);
    EXPECT(fdt_result_thread_stats(r, 0, &ts) == FDT_OK && ts.tets == nt);
    EXPECT(fdt_result_thread_stats(r, 1, &ts) == FDT_EINVAL);
    EXPECT(fdt_result_thread_stats(r, -1, &ts) == FDT_EINVAL);
    /* hash: sorts, is idempotent, and is the FNV-1a of the canonical text */
    uint64_t h2;
    CHECK_EQ(fdt_result_hash(r, &h), FDT_OK);
    CHECK_EQ(fdt_result_hash(r, &h2), FDT_OK);
    EXPECT(h == h2);
    EXPECT(fdt_result_hash(r, NULL) == FDT_EINVAL);
    t = fdt_result_tets(r);
    uint64_t f = 14695981039346656037ull;
    for (size_t i = 0; i < nt; i++) {
        fdt_vid v[4];
        memcpy(v, t + 4 * i, sizeof v);
        for (int a = 1; a < 4; a++)
            for (int k = a; k > 0 && v[k - 1] > v[k]; k--) {
                fdt_vid s = v[k];
                v[k] = v[k - 1];
                v[k - 1] = s;
            }
        char line[64];
        int len = snprintf(line, sizeof line, "%d %d %d %d\n", v[0], v[1], v[2], v[3]);
        for (int k = 0; k < len; k++)
            f = (f ^ (unsigned char)line[k]) * 1099511628211ull;
    }
    EXPECTF(f == h, "hash %016llx, canonical text %016llx", (unsigned long long)h,
            (unsigned long long)f);
    EXPECT(fdt_check(xyz, 12, fdt_result_tets(r), nt, fdt_result_neighbors(r), msg, sizeof msg) ==
           FDT_OK);
    fdt_result_free(&r);

    /* No duplicates: the identity map, never NULL. */
    CHECK_EQ(fdt_triangulate(ctx, xyz, 8, &r), FDT_OK);
    map = fdt_result_duplicate_map(r);
    CHECK(map != NULL);
    for (fdt_vid i = 0; i < 8; i++)
        EXPECT(map[i] == i);
    EXPECT(fdt_result_num_duplicates(r) == 0 && fdt_result_neighbors(r) != NULL);
    fdt_result_free(&r);
    fdt_close(&ctx);
}

/* Serial progress: fractions in [0, 1], not decreasing, the last one 1;
 * a nonzero return cancels with FDT_ECANCELED and no result. */
typedef struct prog {
    int calls, stop_at, bad;
    double last;
} prog;

static int prog_cb(void *user, double f)
{
    prog *p = user;
    if (!(f >= p->last && f <= 1.0))
        p->bad = 1;
    p->last = f;
    return ++p->calls == p->stop_at;
}

static void test_progress(void)
{
    const size_t n = 30000; /* about 195,000 tets: reports every 65,536 */
    double *xyz = malloc(3 * n * sizeof *xyz);
    CHECK(xyz);
    uint64_t seed = 21;
    for (size_t i = 0; i < 3 * n; i++)
        xyz[i] = test_unif(&seed);
    prog p = {0, -1, 0, 0.0};
    fdt_context *ctx = open_serial(0, prog_cb, &p);
    fdt_result *r = NULL;
    EXPECT(fdt_triangulate(ctx, xyz, n, &r) == FDT_OK && r != NULL);
    EXPECTF(p.calls >= 3 && !p.bad && p.last == 1.0, "%d reports, last %g, bad %d", p.calls,
            p.last, p.bad);
    fdt_stats st;
    CHECK_EQ(fdt_result_stats(r, &st), FDT_OK);
    EXPECT(st.mode == FDT_MODE_SERIAL);
    fdt_result_free(&r);
    fdt_close(&ctx);
    /* cancel at the first report (a partial mesh is never returned) and
     * at the second */
    for (int stop = 1; stop <= 2; stop++) {
        prog c = {0, stop, 0, 0.0};
        ctx = open_serial(0, prog_cb, &c);
        r = (fdt_result *)ctx;
        EXPECTF(fdt_triangulate(ctx, xyz, n, &r) == FDT_ECANCELED && r == NULL,
                "cancel at report %d", stop);
        EXPECTF(c.calls == stop && c.last < 1.0, "canceled at %d: %d calls, last %g", stop, c.calls,
                c.last);
        /* the context stays usable */
        c.stop_at = -1;
        c.last = 0.0;
        EXPECT(fdt_triangulate(ctx, xyz, 200, &r) == FDT_OK);
        fdt_result_free(&r);
        fdt_close(&ctx);
    }
    free(xyz);
}

/* Every search policy in every mode gives the same mesh (the perturbed
 * Delaunay tetrahedralization is unique), also with more threads than a
 * part can hold points (parts of fewer than 4 points build no mesh). */
static void test_search(void)
{
    const size_t sizes[2] = {300, 20};
    for (int z = 0; z < 2; z++) {
        size_t n = sizes[z];
        double *xyz = malloc(3 * n * sizeof *xyz);
        CHECK(xyz);
        uint64_t seed = 5 + (uint64_t)z;
        for (size_t i = 0; i < 3 * n; i++)
            xyz[i] = test_unif(&seed);
        uint64_t ref = 0;
        for (int si = 0; fdt_search_name((fdt_search)si); si++)
            for (int mode = FDT_MODE_SERIAL; mode <= FDT_MODE_MESSAGE; mode++)
                for (int threads = 1; threads <= 16; threads *= 4) {
                    if (mode == FDT_MODE_SERIAL && threads > 1)
                        continue;
                    fdt_settings s;
                    fdt_default_settings(&s);
                    s.mode = (fdt_mode)mode;
                    s.n_threads = threads;
                    s.search = (fdt_search)si;
                    fdt_context *ctx = NULL;
                    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
                    fdt_result *r = NULL;
                    uint64_t h = 1;
                    EXPECTF(fdt_triangulate(ctx, xyz, n, &r) == FDT_OK &&
                                fdt_result_hash(r, &h) == FDT_OK,
                            "%zu points, search %d, mode %d, %d threads: %s", n, (int)s.search,
                            mode, threads, fdt_context_diagnostic(ctx));
                    if (ref == 0)
                        ref = h;
                    EXPECTF(h == ref, "%zu points, search %d, mode %d, %d threads: another mesh",
                            n, (int)s.search, mode, threads);
                    /* the engine that ran, as fdt_stats says (the parts'
                     * auto search: the probe picks the kd search or the
                     * mesh of every point) */
                    fdt_stats st;
                    int e = r && fdt_result_stats(r, &st) == FDT_OK ? st.engine : -1;
                    int want = mode == FDT_MODE_SERIAL
                                   ? (si == FDT_SEARCH_KD ? FDT_ENGINE_FRONT : FDT_ENGINE_ONE_PART)
                               : si == FDT_SEARCH_KD   ? FDT_ENGINE_PARTS
                               : si == FDT_SEARCH_MESH ? FDT_ENGINE_WALLS
                                                       : -1;
                    EXPECTF(want < 0 ? e == FDT_ENGINE_PARTS || e == FDT_ENGINE_PARTS_MESH
                                     : e == want,
                            "%zu points, search %d, mode %d, %d threads: engine %d", n,
                            (int)s.search, mode, threads, e);
                    fdt_result_free(&r);
                    fdt_close(&ctx);
                }
        free(xyz);
    }
}

/* The searches' names (the table of src/front/search.c): values from 0
 * without a gap, each name back to its value, and a value past them or an
 * unknown name refused. */
static void test_search_names(void)
{
    int n = 0;
    while (fdt_search_name((fdt_search)n))
        n++;
    EXPECT(n >= 3 && strcmp(fdt_search_name(FDT_SEARCH_AUTO), "auto") == 0 &&
           strcmp(fdt_search_name(FDT_SEARCH_KD), "kd") == 0 &&
           strcmp(fdt_search_name(FDT_SEARCH_MESH), "mesh") == 0);
    for (int i = 0; i < n; i++) {
        fdt_search s = (fdt_search)-1;
        EXPECTF(fdt_search_from_name(fdt_search_name((fdt_search)i), &s) == FDT_OK &&
                    s == (fdt_search)i,
                "search %d", i);
    }
    for (int i = n; i < n + 64; i++)
        EXPECTF(fdt_search_name((fdt_search)i) == NULL, "a gap before search %d", i);
    EXPECT(fdt_search_name((fdt_search)-1) == NULL);
    fdt_search s = FDT_SEARCH_KD;
    EXPECT(fdt_search_from_name("fast", &s) == FDT_EINVAL && s == FDT_SEARCH_KD);
    EXPECT(fdt_search_from_name("", &s) == FDT_EINVAL && s == FDT_SEARCH_KD);
    EXPECT(fdt_search_from_name("Auto", &s) == FDT_EINVAL && s == FDT_SEARCH_KD);
    EXPECT(fdt_search_from_name(NULL, &s) == FDT_EINVAL);
    EXPECT(fdt_search_from_name("auto", NULL) == FDT_EINVAL);

    fdt_settings st;
    fdt_default_settings(&st);
    st.search = (fdt_search)n;
    fdt_context *ctx = (fdt_context *)&st;
    EXPECT(fdt_open(&ctx, &st) == FDT_EINVAL && ctx == NULL);
    EXPECT(fdt_engine_one_part(&st, 0) == 0);
    st.search = (fdt_search)-1;
    EXPECT(fdt_open(&ctx, &st) == FDT_EINVAL && ctx == NULL);
}

/* A struct followed by canary bytes, to see what a call writes. */
#define CANARY 0xa5
#define PAD 64

static int canary_intact(const unsigned char *p, size_t from, size_t to)
{
    for (size_t i = from; i < to; i++)
        if (p[i] != CANARY)
            return 0;
    return 1;
}

static void test_abi_settings(void)
{
    fdt_settings s;
    fdt_default_settings(&s);
    CHECK_EQ(s.struct_size, sizeof s);
    CHECK_EQ(s.mode, FDT_MODE_AUTO);
    CHECK(s.leaf_size > 0);

    /* A size the library does not know: refused, only struct_size (0)
     * written, never a byte beyond the size given. */
    unsigned char buf[sizeof(fdt_settings) + PAD];
    size_t bad[] = {sizeof(fdt_settings) + 8, sizeof(fdt_settings) - 1,
                    sizeof(fdt_settings) - sizeof(size_t), sizeof(size_t), 0};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        memset(buf, CANARY, sizeof buf);
        CHECK_EQ(fdt_default_settings_sized((fdt_settings *)buf, bad[k]), FDT_EINVAL);
        size_t written = bad[k] >= sizeof(size_t) ? sizeof(size_t) : 0;
        CHECK(canary_intact(buf, written, sizeof buf));
        if (written) {
            size_t z;
            memcpy(&z, buf, sizeof z);
            CHECK_EQ(z, 0);
        }
    }
    memset(buf, CANARY, sizeof buf);
    CHECK_EQ(fdt_default_settings_sized((fdt_settings *)buf, sizeof(fdt_settings)), FDT_OK);
    CHECK(canary_intact(buf, sizeof(fdt_settings), sizeof buf));
    CHECK_EQ(fdt_default_settings_sized(NULL, sizeof(fdt_settings)), FDT_EINVAL);

    /* fdt_open checks the size: zeroed by hand, too small, too large. */
    fdt_context *ctx = (fdt_context *)&ctx; /* must be set to NULL */
    fdt_settings z;
    memset(&z, 0, sizeof z);
    CHECK_EQ(fdt_open(&ctx, &z), FDT_EINVAL);
    CHECK(ctx == NULL);
    size_t sizes[] = {sizeof s - 1, sizeof s - sizeof(size_t), sizeof s + 8, 1};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        fdt_default_settings(&s);
        s.struct_size = sizes[k];
        CHECK_EQ(fdt_open(&ctx, &s), FDT_EINVAL);
        CHECK(ctx == NULL);
    }
    fdt_default_settings(&s);
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    CHECK(ctx != NULL);
    fdt_close(&ctx);
}

static void test_abi_stats(void)
{
    /* The unit cube's corners and its centre: 12 tets. */
    static const double xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 1,
                                 1, 0, 1, 0, 1, 1, 1, 1, 1, 0.5, 0.5, 0.5};
    fdt_settings s;
    fdt_default_settings(&s);
    s.n_threads = 1;
    fdt_context *ctx;
    fdt_result *r;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    CHECK_EQ(fdt_triangulate(ctx, xyz, 9, &r), FDT_OK);
    CHECK_EQ(fdt_result_num_tets(r), 12);

    fdt_stats st;
    memset(&st, 0, sizeof st);
    CHECK_EQ(fdt_result_stats(r, &st), FDT_OK);
    CHECK_EQ(st.struct_size, sizeof st);
    CHECK_EQ(st.tets, 12);
    CHECK_EQ(st.points, 9);

    unsigned char buf[sizeof(fdt_stats) + sizeof(fdt_thread_stats) + PAD];
    size_t bad[] = {sizeof(fdt_stats) + 8, sizeof(fdt_stats) - 8, 0};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        memset(buf, CANARY, sizeof buf);
        CHECK_EQ(fdt_result_stats_sized(r, (fdt_stats *)buf, bad[k]), FDT_EINVAL);
        CHECK(canary_intact(buf, 0, sizeof buf));
    }
    memset(buf, CANARY, sizeof buf);
    CHECK_EQ(fdt_result_stats_sized(r, (fdt_stats *)buf, sizeof(fdt_stats)), FDT_OK);
    CHECK(canary_intact(buf, sizeof(fdt_stats), sizeof buf));

    fdt_thread_stats ts;
    CHECK_EQ(fdt_result_thread_stats(r, 0, &ts), FDT_OK);
    CHECK_EQ(ts.struct_size, sizeof ts);
    CHECK_EQ(ts.tets, 12);
    CHECK_EQ(fdt_result_thread_stats(r, 1, &ts), FDT_EINVAL);
    size_t tbad[] = {sizeof(fdt_thread_stats) + 8, sizeof(fdt_thread_stats) - 8, 0};
    for (size_t k = 0; k < sizeof tbad / sizeof tbad[0]; k++) {
        memset(buf, CANARY, sizeof buf);
        CHECK_EQ(fdt_result_thread_stats_sized(r, 0, (fdt_thread_stats *)buf, tbad[k]),
                 FDT_EINVAL);
        CHECK(canary_intact(buf, 0, sizeof buf));
    }
    fdt_result_free(&r);
    fdt_close(&ctx);
}

/* fdt_engine_one_part: the insertion engine (in memory the one-part
 * engine, streamed the parts in sweep order) with --search auto (serial,
 * or threads in the default mode without pinning) and mesh (serial only);
 * never with kd, an explicit parallel mode or pinning. The runs of
 * test_search and tests/test_oracle.c check that the engine that ran is
 * the one it names. */
/* The engines' names (fdt_engine): each value from FDT_ENGINE_FRONT to
 * FDT_ENGINE_PERIODIC has a distinct name and a line, the others none. */
static void test_engine_names(void)
{
    EXPECT(fdt_engine_name(0) == NULL && fdt_engine_about(0) == NULL);
    EXPECT(fdt_engine_name(FDT_ENGINE_PERIODIC + 1) == NULL && fdt_engine_name(-1) == NULL);
    for (int e = FDT_ENGINE_FRONT; e <= FDT_ENGINE_PERIODIC; e++) {
        EXPECTF(fdt_engine_name(e) && fdt_engine_about(e) && *fdt_engine_about(e),
                "engine %d has no name", e);
        for (int f = FDT_ENGINE_FRONT; f < e; f++)
            EXPECTF(strcmp(fdt_engine_name(e), fdt_engine_name(f)) != 0,
                    "engines %d and %d have one name", f, e);
    }
    EXPECT(strcmp(fdt_engine_name(FDT_ENGINE_ONE_PART), "one-part") == 0);
}

static void test_engine_rule(void)
{
    fdt_settings s;
    fdt_default_settings(&s);
    EXPECT(fdt_engine_one_part(&s, 0) == 1);
    EXPECT(fdt_engine_one_part(&s, 1) == 1);
    EXPECT(fdt_engine_one_part(NULL, 0) == 0);
    s.n_threads = 4;
    EXPECT(fdt_engine_one_part(&s, 0) == 1);
    s.pin = 1;
    EXPECT(fdt_engine_one_part(&s, 0) == 0);
    s.pin = 0;
    s.mode = FDT_MODE_SHARED;
    EXPECT(fdt_engine_one_part(&s, 0) == 0);
    s.mode = FDT_MODE_MESSAGE;
    EXPECT(fdt_engine_one_part(&s, 0) == 0);
    s.mode = FDT_MODE_SERIAL;
    EXPECT(fdt_engine_one_part(&s, 0) == 1);
    s.search = FDT_SEARCH_MESH;
    EXPECT(fdt_engine_one_part(&s, 0) == 1);
    s.search = FDT_SEARCH_KD;
    EXPECT(fdt_engine_one_part(&s, 0) == 0);
    s.mode = FDT_MODE_AUTO;
    s.search = FDT_SEARCH_MESH;
    EXPECT(fdt_engine_one_part(&s, 0) == 0);
    s.n_threads = 1;
    EXPECT(fdt_engine_one_part(&s, 0) == 1);
}

static int sink_count(void *user, const fdt_vid *tets, size_t count)
{
    (void)user;
    (void)tets;
    (void)count;
    return 0;
}

/* A periodic run's rows streamed: counted, each batch checked ascending
 * by least vertex; stop_after batches, then a stop. */
typedef struct periodic_rows {
    size_t rows, unsorted, stop_after;
} periodic_rows;

static int periodic_count(void *user, const fdt_vid *t, const int8_t *off, size_t count)
{
    periodic_rows *p = user;
    (void)off;
    for (size_t i = 1; i < count; i++)
        p->unsorted += t[4 * i - 4] > t[4 * i];
    p->rows += count;
    return p->stop_after && p->rows ? 1 : 0;
}

/* Streamed cells gathered by id: volumes and densities, each id once. */
typedef struct cells_by_id {
    double *vol, *dens;
    size_t n, seen, twice;
} cells_by_id;

static int take_cells(void *user, const fdt_voronoi *b)
{
    cells_by_id *c = user;
    const fdt_vid *ids = fdt_voronoi_ids(b);
    for (size_t i = 0; i < fdt_voronoi_num_points(b); i++) {
        size_t id = (size_t)ids[i];
        if (id >= c->n || c->vol[id] != -1) {
            c->twice++;
            continue;
        }
        c->vol[id] = fdt_voronoi_volumes(b)[i];
        c->dens[id] = fdt_voronoi_densities(b)[i];
        c->seen++;
    }
    return 0;
}

/* A periodic run through the API (issue 33; its meshes are tested in
 * tests/test_periodic.c and tests/periodic_e2e.py): the first release's
 * settings size runs plain; periodic bits beyond z are refused; the result
 * has offsets, the engine and its figures; what cannot take a periodic
 * result refuses it; a point outside the box is named. */
static void test_periodic_api(void)
{
    enum { N = 600 };
    static double xyz[3 * N];
    uint64_t seed = 11;
    for (int i = 0; i < 3 * N; i++)
        xyz[i] = test_unif(&seed);
    fdt_settings s;
    fdt_default_settings(&s);
    fdt_context *ctx = NULL;
    fdt_result *r = NULL;
    s.struct_size = offsetof(fdt_settings, periodic);
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    CHECK_EQ(fdt_triangulate(ctx, xyz, N, &r), FDT_OK);
    EXPECT(fdt_result_tet_offsets(r) == NULL && fdt_result_hull_offsets(r) == NULL &&
           fdt_result_periodic(r, NULL) == 0);
    fdt_result_free(&r);
    fdt_close(&ctx);
    fdt_default_settings(&s);
    s.periodic = 8;
    EXPECT(fdt_open(&ctx, &s) == FDT_EINVAL && ctx == NULL);
    s.periodic = 7;
    const double box[6] = {0, 0, 0, 1, 1, 1};
    memcpy(s.periodic_box, box, sizeof box);
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    CHECK_EQ(fdt_triangulate(ctx, xyz, N, &r), FDT_OK);
    fdt_stats st;
    CHECK_EQ(fdt_result_stats(r, &st), FDT_OK);
    EXPECT(st.engine == FDT_ENGINE_PERIODIC && st.periodic_images > 0 && st.periodic_rounds >= 1);
    EXPECT(fdt_result_tet_offsets(r) != NULL && fdt_result_num_tets(r) > 6 * N &&
           fdt_result_num_hull_faces(r) == 0);
    uint64_t h;
    EXPECT(fdt_result_hash(r, &h) == FDT_OK && fdt_result_sort(r) == FDT_OK);
    uint64_t set_hash = 0;
    EXPECT(fdt_result_set_hash(r, &set_hash) == FDT_OK);
    size_t ntets = fdt_result_num_tets(r);
    size_t cnt;
    const fdt_vid *fv, *ids;
    const fdt_tid *ft;
    EXPECT(fdt_result_faces(r, &cnt, &fv, &ft) == FDT_EINVAL);
    EXPECT(fdt_result_edges(r, &cnt, &fv) == FDT_EINVAL);
    EXPECT(fdt_result_vertex_neighbors(r, 0, &cnt, &ids) == FDT_EINVAL);
    /* the cells of a periodic set: its box's volume, no cell clipped */
    fdt_voronoi *v = NULL;
    EXPECT(fdt_voronoi_compute(r, xyz, N, NULL, &v, NULL, 0) == FDT_OK);
    double sum = 0;
    for (size_t i = 0; v && i < N; i++) {
        sum += fdt_voronoi_volumes(v)[i];
        EXPECT(fdt_voronoi_flags(v)[i] == 0);
    }
    EXPECTF(fabs(sum - 1) < 1e-12, "periodic cells: %.17g", sum);
    fdt_voronoi_free(&v);
    /* located in the periodic mesh (tests/test_periodic_interp.c): a
     * point's own coordinate 1 in a row that holds it */
    fdt_tid tet = -1;
    double bary[4] = {0, 0, 0, 0};
    EXPECT(fdt_locate(r, xyz, N, xyz, 1, &tet, bary, 1) == FDT_OK && tet >= 0 &&
           (size_t)tet < ntets);
    for (int i = 0; tet >= 0 && (size_t)tet < ntets && i < 4; i++)
        if (fdt_result_tets(r)[4 * tet + i] == 0)
            EXPECTF(fabs(bary[i] - 1) < 1e-12, "point 0's coordinate %.17g", bary[i]);
    fdt_result_free(&r);
    /* streamed: a sink without periodic_tets is refused; with it, the
     * rows come ascending in each batch, the set hash is the in-memory
     * run's; a nonzero return stops the run */
    fdt_sink sink = {sizeof sink, sink_count, NULL, NULL, NULL, NULL};
    EXPECT(fdt_triangulate_stream(ctx, xyz, N, &sink, &r) == FDT_EINVAL && !r);
    periodic_rows pr = {0, 0, 0};
    fdt_sink ps = {sizeof ps, NULL, NULL, &pr, periodic_count, NULL};
    EXPECT(fdt_triangulate_stream(ctx, xyz, N, &ps, &r) == FDT_OK);
    uint64_t sh = 0;
    EXPECT(pr.rows == ntets && !pr.unsorted && fdt_result_set_hash(r, &sh) == FDT_OK &&
           sh == set_hash && fdt_result_num_tets(r) == 0);
    EXPECT(fdt_locate(r, xyz, N, xyz, 1, &tet, bary, 1) == FDT_EINVAL); /* no mesh kept */
    fdt_result_free(&r);
    pr.stop_after = 1;
    EXPECT(fdt_triangulate_stream(ctx, xyz, N, &ps, &r) == FDT_ECANCELED && !r);
    fdt_close(&ctx);
    /* periodic in x and z only: the walls y = 0 and y = 1 cut the cells
     * that reach them, the hull's points' among them */
    for (int i = 0; i < N; i++)
        xyz[3 * i + 1] = i % 4 == 0 ? 0.0 : i % 4 == 1 ? 1.0 : xyz[3 * i + 1];
    s.periodic = 5;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    CHECK_EQ(fdt_triangulate(ctx, xyz, N, &r), FDT_OK);
    EXPECT(fdt_result_num_hull_faces(r) > 0 && fdt_result_hull_offsets(r) != NULL);
    char vd[256];
    CHECK_EQ(fdt_voronoi_compute(r, xyz, N, NULL, &v, vd, sizeof vd), FDT_OK);
    size_t hull_cells = 0;
    sum = 0;
    for (size_t i = 0; i < N; i++) {
        sum += fdt_voronoi_volumes(v)[i];
        hull_cells += (fdt_voronoi_flags(v)[i] & FDT_CELL_HULL) != 0;
        /* a wall point's cell is cut by its wall; no other is unbounded */
        EXPECTF(!(fdt_voronoi_flags(v)[i] & FDT_CELL_HULL) == (i % 4 > 1), "cell %zu", i);
    }
    EXPECTF(fabs(sum - 1) < 1e-12 && hull_cells == N / 2, "x-z cells: %.17g, %zu hull",
            sum, hull_cells);
    /* streamed (fdt_voronoi_stream): every point's cell once, to the bit */
    double cv[N], cd[N];
    for (size_t i = 0; i < N; i++)
        cv[i] = cd[i] = -1;
    cells_by_id cb = {cv, cd, N, 0, 0};
    fdt_cell_sink csink = {sizeof csink, take_cells, &cb};
    fdt_result *rs = NULL;
    CHECK_EQ(fdt_voronoi_stream(ctx, xyz, N, NULL, NULL, &csink, &rs), FDT_OK);
    EXPECT(cb.seen == N && !cb.twice && fdt_result_num_tets(rs) == 0);
    EXPECT(!memcmp(cv, fdt_voronoi_volumes(v), sizeof cv) &&
           !memcmp(cd, fdt_voronoi_densities(v), sizeof cd));
    fdt_result_free(&rs);
    fdt_voronoi_free(&v);
    /* its own check; a bad axis set or box refused */
    double pb[6];
    EXPECT(fdt_result_periodic(r, pb) == 5 && pb[3] == 1);
    EXPECT(fdt_check_periodic(xyz, N, fdt_result_tets(r), fdt_result_tet_offsets(r),
                              fdt_result_num_tets(r), fdt_result_hull_faces(r),
                              fdt_result_hull_offsets(r), fdt_result_num_hull_faces(r), 5, pb,
                              vd, sizeof vd) == FDT_OK);
    EXPECT(fdt_check_periodic(xyz, N, fdt_result_tets(r), fdt_result_tet_offsets(r),
                              fdt_result_num_tets(r), NULL, NULL, 0, 8, pb, vd, sizeof vd) ==
           FDT_EINVAL);
    EXPECT(fdt_check_periodic(xyz, N, NULL, NULL, 1, NULL, NULL, 0, 5, pb, vd, sizeof vd) ==
           FDT_EINVAL);
    /* its own box only */
    fdt_voronoi_options vo;
    fdt_default_voronoi_options(&vo);
    vo.box_given = 1;
    memcpy(vo.box, box, sizeof vo.box);
    EXPECT(fdt_voronoi_compute(r, xyz, N, &vo, &v, vd, sizeof vd) == FDT_OK);
    fdt_voronoi_free(&v);
    vo.box[4] = 2;
    EXPECT(fdt_voronoi_compute(r, xyz, N, &vo, &v, vd, sizeof vd) == FDT_EINVAL &&
           strstr(vd, "its own box") != NULL && v == NULL);
    EXPECT(fdt_voronoi_stream(ctx, xyz, N, &vo, NULL, &csink, &rs) == FDT_EINVAL && !rs &&
           strstr(fdt_context_diagnostic(ctx), "its own box") != NULL);
    fdt_result_free(&r);
    /* the box's wall below the points (a side that is not periodic: the
     * mesh does not read it, the cells do) */
    fdt_close(&ctx);
    s.periodic_box[4] = 0.75;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    CHECK_EQ(fdt_triangulate(ctx, xyz, N, &r), FDT_OK);
    EXPECT(fdt_voronoi_compute(r, xyz, N, NULL, &v, vd, sizeof vd) == FDT_EINVAL &&
           strstr(vd, "point 1 (") != NULL && v == NULL);
    cb.seen = 0;
    EXPECT(fdt_voronoi_stream(ctx, xyz, N, NULL, NULL, &csink, &rs) == FDT_EINVAL && !rs &&
           !cb.seen && strstr(fdt_context_diagnostic(ctx), "point 1 (") != NULL);
    fdt_result_free(&r);
    fdt_close(&ctx);
    s.periodic_box[4] = -1; /* empty across y: no walls to cut the cells */
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    CHECK_EQ(fdt_triangulate(ctx, xyz, N, &r), FDT_OK);
    EXPECT(fdt_voronoi_compute(r, xyz, N, NULL, &v, vd, sizeof vd) == FDT_EINVAL &&
           strstr(vd, "empty or not finite in y") != NULL && v == NULL);
    fdt_result_free(&r);
    xyz[3 * 5 + 2] = NAN; /* the merge names it, as in any run */
    EXPECT(fdt_triangulate(ctx, xyz, N, &r) == FDT_ERANGE);
    xyz[3 * 5 + 2] = 1.0;
    EXPECT(fdt_triangulate(ctx, xyz, N, &r) == FDT_EINVAL &&
           strstr(fdt_context_diagnostic(ctx), "point 5 has z = 1") != NULL);
    fdt_close(&ctx);
}

int main(void)
{
    test_abi_settings();
    test_abi_stats();
    test_settings();
    test_errors();
    test_result();
    test_progress();
    test_search();
    test_search_names();
    test_engine_rule();
    test_engine_names();
    test_periodic_api();
    return test_report("test_api");
}
