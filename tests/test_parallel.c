/*
 * Tests of the parallel engine (src/par/parallel.c; the partition has
 * tests/test_partition.c): shared
 * and message modes must give the serial tetrahedralization exactly, for
 * any thread count, on the named hard families (uniform, lattice, integer
 * points on a sphere, extruded 2-D grid, clusters, big offset with 1 mm
 * resolution) and on shuffled copies of them:
 *   - the canonical hash equals serial mode's;
 *   - after canonical sorting the tets, their neighbours and the hull faces
 *     equal serial mode's (so the threads' neighbour links are right);
 *   - every message kind was received as often as it was sent, in total and
 *     summed over the per-thread statistics; IAMDONE went to every other
 *     thread once (message mode: also from each root's tree to part 0);
 *     FACERECV once per FACESEND in message mode, never in shared mode;
 *     ABORT never; NODESEND only in message mode;
 * Then many threads on tiny inputs (where nearly every tet straddles parts:
 * the §5 "pockets"), repeated, and error paths (bad arguments).
 *
 * Usage: test_parallel            the default suite (small inputs)
 *        test_parallel --quick    fewer thread counts (for sanitizers)
 *        test_parallel --long     200k uniform points, N in {1, 2, 4, 8}
 * A hang fails the test through alarm().
 */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "base/hash.h"
#include "frontdt.h"
#include "par/parallel.h"
#include "geom/partition.h"
#include "geom/prepare.h"
#include "mesh/result.h"

#include "testutil.h"

/* ---- inputs --------------------------------------------------------------- */

typedef struct rng {
    uint64_t s;
} rng;

/* splitmix64: plenty for test inputs, identical everywhere. */
static uint64_t rnext(rng *r)
{
    return fdt_splitmix64(&r->s);
}

static double runif(rng *r)
{
    return (double)(rnext(r) >> 11) * 0x1.0p-53;
}

static double rgauss(rng *r)
{
    double u = runif(r), v = runif(r);
    if (u < 1e-300)
        u = 1e-300;
    return sqrt(-2.0 * log(u)) * cos(6.283185307179586 * v);
}

typedef struct pts {
    char name[64];
    double *xyz;
    size_t n;
} pts;

static pts pts_alloc(const char *name, size_t n)
{
    pts p;
    snprintf(p.name, sizeof p.name, "%s", name);
    p.n = n;
    p.xyz = malloc((n ? n : 1) * 3 * sizeof *p.xyz);
    CHECK(p.xyz);
    return p;
}

static pts fam_uniform(size_t n, uint64_t seed)
{
    pts p = pts_alloc("uniform", n);
    rng r = {seed};
    for (size_t i = 0; i < 3 * n; i++)
        p.xyz[i] = runif(&r);
    return p;
}

static pts fam_lattice(int s)
{
    pts p = pts_alloc("lattice", (size_t)s * s * s);
    size_t k = 0;
    for (int x = 0; x < s; x++)
        for (int y = 0; y < s; y++)
            for (int z = 0; z < s; z++) {
                p.xyz[k++] = x;
                p.xyz[k++] = y;
                p.xyz[k++] = z;
            }
    return p;
}

/* Every integer point with x^2 + y^2 + z^2 = r2: all cospherical. */
static pts fam_intsphere(int r2)
{
    int r = (int)sqrt((double)r2) + 1;
    size_t cnt = 0;
    for (int pass = 0; pass < 2; pass++) {
        pts p = pts_alloc("intsphere", cnt);
        size_t k = 0;
        for (int x = -r; x <= r; x++)
            for (int y = -r; y <= r; y++)
                for (int z = -r; z <= r; z++)
                    if (x * x + y * y + z * z == r2) {
                        if (pass) {
                            p.xyz[3 * k] = x;
                            p.xyz[3 * k + 1] = y;
                            p.xyz[3 * k + 2] = z;
                        }
                        k++;
                    }
        if (pass)
            return p;
        cnt = k;
        free(p.xyz);
    }
    return pts_alloc("intsphere", 0);
}

/* A k x k grid in the plane, each (x, y) at z = 0 and at z = 1. */
static pts fam_grid2(int k)
{
    pts p = pts_alloc("grid2d", (size_t)2 * k * k);
    size_t j = 0;
    for (int z = 0; z < 2; z++)
        for (int x = 0; x < k; x++)
            for (int y = 0; y < k; y++) {
                p.xyz[j++] = x;
                p.xyz[j++] = y;
                p.xyz[j++] = z;
            }
    return p;
}

/* Gaussian clusters of very different spreads. */
static pts fam_clusters(size_t n, uint64_t seed)
{
    pts p = pts_alloc("clusters", n);
    rng r = {seed};
    double c[8][4];
    for (int i = 0; i < 8; i++) {
        for (int k = 0; k < 3; k++)
            c[i][k] = runif(&r) * 10.0;
        c[i][3] = pow(10.0, -3.0 * runif(&r));
    }
    for (size_t i = 0; i < n; i++) {
        int j = (int)(rnext(&r) % 8);
        for (int k = 0; k < 3; k++)
            p.xyz[3 * i + k] = c[j][k] + c[j][3] * rgauss(&r);
    }
    return p;
}

/* UTM-like: 5e6 plus a 100 m box at 1 mm resolution (many ties). */
static pts fam_offset(size_t n, uint64_t seed)
{
    pts p = pts_alloc("offset5e6", n);
    rng r = {seed};
    for (size_t i = 0; i < 3 * n; i++)
        p.xyz[i] = 5e6 + (double)(rnext(&r) % 100000) / 1000.0;
    return p;
}

/* A shuffled copy; perm[i] = the original index of point i. */
static pts shuffled(const pts *src, uint64_t seed, size_t **perm_out)
{
    char name[64];
    snprintf(name, sizeof name, "%.50s-shuf", src->name);
    pts p = pts_alloc(name, src->n);
    size_t *perm = malloc((src->n ? src->n : 1) * sizeof *perm);
    CHECK(perm);
    for (size_t i = 0; i < src->n; i++)
        perm[i] = i;
    rng r = {seed};
    for (size_t i = src->n; i > 1; i--) {
        size_t j = (size_t)(rnext(&r) % i);
        size_t t = perm[i - 1];
        perm[i - 1] = perm[j];
        perm[j] = t;
    }
    for (size_t i = 0; i < src->n; i++)
        memcpy(p.xyz + 3 * i, src->xyz + 3 * perm[i], 3 * sizeof *p.xyz);
    *perm_out = perm;
    return p;
}

/* ---- running and comparing ------------------------------------------------ */

static const char *mode_name(fdt_mode m)
{
    switch (m) {
    case FDT_MODE_SERIAL: return "serial";
    case FDT_MODE_SHARED: return "shared";
    case FDT_MODE_MESSAGE: return "message";
    default: return "auto";
    }
}

static fdt_result *run(const pts *p, fdt_mode mode, int nthreads, int nbrs,
                       int expect_err)
{
    fdt_settings s;
    fdt_default_settings(&s);
    s.mode = mode;
    s.n_threads = nthreads;
    s.neighbors = nbrs;
    fdt_context *ctx = NULL;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    fdt_result *r = NULL;
    int err = fdt_triangulate(ctx, p->xyz, p->n, &r);
    if (err != expect_err)
        fprintf(stderr, "%s, %s, %d threads: %s (%s)\n", p->name, mode_name(mode),
                nthreads, fdt_strerror(err), fdt_context_diagnostic(ctx));
    CHECK_EQ(err, expect_err);
    fdt_close(&ctx);
    return r;
}

/* Canonical hull: each face rotated so its smallest id leads (keeps the
 * orientation), faces sorted. */
static int tri_cmp(const void *x, const void *y)
{
    const fdt_vid *a = x, *b = y;
    for (int i = 0; i < 3; i++)
        if (a[i] != b[i])
            return a[i] < b[i] ? -1 : 1;
    return 0;
}

static fdt_vid *canon_hull(const fdt_result *r)
{
    size_t nh = fdt_result_num_hull_faces(r);
    const fdt_vid *h = fdt_result_hull_faces(r);
    fdt_vid *c = malloc((nh ? nh : 1) * 3 * sizeof *c);
    CHECK(c);
    for (size_t i = 0; i < nh; i++) {
        const fdt_vid *f = h + 3 * i;
        int k = f[0] < f[1] ? (f[0] < f[2] ? 0 : 2) : (f[1] < f[2] ? 1 : 2);
        for (int j = 0; j < 3; j++)
            c[3 * i + j] = f[(k + j) % 3];
    }
    qsort(c, nh, 3 * sizeof *c, tri_cmp);
    return c;
}

typedef struct reference {
    uint64_t hash;
    size_t ntets, nhull;
    fdt_result *r;   /* sorted */
    fdt_vid *hull;   /* canonical */
} reference;

static reference make_ref(const pts *p)
{
    reference ref;
    ref.r = run(p, FDT_MODE_SERIAL, 1, 1, FDT_OK);
    CHECK_EQ(fdt_result_hash(ref.r, &ref.hash), FDT_OK);
    ref.ntets = fdt_result_num_tets(ref.r);
    ref.nhull = fdt_result_num_hull_faces(ref.r);
    ref.hull = canon_hull(ref.r);
    CHECK(ref.ntets > 0);
    /* The reference itself is checked (fdt_check: orientation, links,
     * hull, empty spheres): equal to serial alone would let one bug in
     * both engines through. */
    char msg[256];
    if (fdt_check(p->xyz, p->n, fdt_result_tets(ref.r), ref.ntets, fdt_result_neighbors(ref.r),
                  msg, sizeof msg) != FDT_OK)
        fprintf(stderr, "%s: serial mesh fails fdt_check: %s\n", p->name, msg);
    CHECK(fdt_check(p->xyz, p->n, fdt_result_tets(ref.r), ref.ntets, fdt_result_neighbors(ref.r),
                    msg, sizeof msg) == FDT_OK);
    return ref;
}

static void free_ref(reference *ref)
{
    fdt_result_free(&ref->r);
    free(ref->hull);
}

static void check_stats(const fdt_result *r, fdt_mode mode, int nthreads)
{
    fdt_stats st;
    CHECK_EQ(fdt_result_stats(r, &st), FDT_OK);
    CHECK_EQ(st.threads, nthreads);
    CHECK_EQ(st.mode, mode);
    CHECK_EQ(st.tets, fdt_result_num_tets(r));
    /* Every kind has a name, and was received as often as it was sent. */
    for (int k = 1; k < FDT_MSG_KIND_END; k++) {
        CHECK(strcmp(fdt_msg_kind_name(k), "?") != 0);
        CHECK_EQ(st.sent[k], st.received[k]);
    }
    CHECK(strcmp(fdt_msg_kind_name(0), "?") == 0);
    CHECK(strcmp(fdt_msg_kind_name(FDT_MSG_KIND_END), "?") == 0);
    CHECK_EQ(st.sent[FDT_MSG_ABORT], 0);
    if (mode == FDT_MODE_MESSAGE) {
        /* every FACESEND acknowledged; IAMDONE: the final one to every
         * other part, and at most one a root (part with seeds) to part 0 */
        CHECK_EQ(st.sent[FDT_MSG_FACERECV], st.sent[FDT_MSG_FACESEND]);
        CHECK(st.sent[FDT_MSG_IAMDONE] >= (size_t)nthreads - 1 &&
              st.sent[FDT_MSG_IAMDONE] <= 2 * (size_t)nthreads - 2);
    } else {
        CHECK_EQ(st.sent[FDT_MSG_IAMDONE], nthreads - 1);
        CHECK_EQ(st.sent[FDT_MSG_FACERECV], 0);
    }
    CHECK_EQ(st.sent[FDT_MSG_NODESEND], st.sent[FDT_MSG_NODERECV]);
    CHECK_EQ(st.remote_queries, st.sent[FDT_MSG_NODESEND]);
    CHECK_EQ(st.remote_answered, st.sent[FDT_MSG_NODESEND]);
    CHECK(st.remote_improved <= st.remote_queries);
    CHECK(st.tet_requests <= st.sent[FDT_MSG_FACESEND]);
    CHECK(st.duplicate_requests <= st.tet_requests);
    if (mode == FDT_MODE_SHARED)
        CHECK_EQ(st.sent[FDT_MSG_NODESEND], 0);
    if (nthreads == 1) {
        CHECK_EQ(st.sent[FDT_MSG_FACESEND], 0);
        CHECK_EQ(st.sent[FDT_MSG_NODESEND], 0);
    }
    CHECK(st.load_imbalance >= 1.0 - 1e-12 && st.load_imbalance <= nthreads + 1e-9);
    CHECK_EQ(st.pinned, 0);
    /* Per-thread statistics add up to the totals. */
    size_t s[FDT_MSG_KIND_END] = {0}, rc[FDT_MSG_KIND_END] = {0};
    size_t tets = 0, pts_ = 0, hull = 0, adv = 0, rq = 0, ra = 0;
    for (int i = 0; i < nthreads; i++) {
        fdt_thread_stats ts;
        CHECK_EQ(fdt_result_thread_stats(r, i, &ts), FDT_OK);
        tets += ts.tets;
        pts_ += ts.points;
        hull += ts.hull_faces;
        adv += ts.faces_advanced;
        rq += ts.remote_queries;
        ra += ts.remote_answered;
        for (int k = 0; k < FDT_MSG_KIND_END; k++) {
            s[k] += ts.sent[k];
            rc[k] += ts.received[k];
        }
        CHECK_EQ(ts.core, -1);
        CHECK(ts.t_idle >= 0.0 && ts.t_query_wait >= 0.0 && ts.t_cpu >= 0.0);
        /* Each thread got exactly one IAMDONE, or sent them all (shared
         * mode); message mode: part 0 sends the final ones, every other
         * part gets one and sends at most one (its tree finished). */
        if (mode == FDT_MODE_MESSAGE) {
            if (i == 0) {
                CHECK_EQ(ts.sent[FDT_MSG_IAMDONE], nthreads - 1);
            } else {
                CHECK_EQ(ts.received[FDT_MSG_IAMDONE], 1);
                CHECK(ts.sent[FDT_MSG_IAMDONE] <= 1);
            }
        } else {
            CHECK(ts.received[FDT_MSG_IAMDONE] == 1 ||
                  (ts.received[FDT_MSG_IAMDONE] == 0 &&
                   ts.sent[FDT_MSG_IAMDONE] == (size_t)nthreads - 1));
        }
    }
    fdt_thread_stats ts;
    CHECK_EQ(fdt_result_thread_stats(r, nthreads, &ts), FDT_EINVAL);
    CHECK_EQ(fdt_result_thread_stats(r, -1, &ts), FDT_EINVAL);
    CHECK_EQ(tets, st.tets);
    CHECK_EQ(pts_, st.vertices);
    CHECK_EQ(hull, st.hull_faces);
    CHECK_EQ(adv, st.faces_advanced);
    CHECK_EQ(rq, st.remote_queries);
    CHECK_EQ(ra, st.remote_answered);
    CHECK(memcmp(s, st.sent, sizeof s) == 0);
    CHECK(memcmp(rc, st.received, sizeof rc) == 0);
    /* Hull faces each close one front face: every face advanced is either
     * a hull face or yields a tet (built here or asked of its owner). */
    CHECK(st.faces_advanced >= st.hull_faces);
}

static int g_verbose = 0;

static void compare_run(const pts *p, const reference *ref, fdt_mode mode,
                        int nthreads)
{
    fdt_result *r = run(p, mode, nthreads, 1, FDT_OK);
    uint64_t h;
    CHECK_EQ(fdt_result_hash(r, &h), FDT_OK);
    if (h != ref->hash)
        fprintf(stderr, "%s: %s with %d threads: hash %016" PRIx64 " != serial %016" PRIx64
                " (%zu vs %zu tets)\n", p->name, mode_name(mode), nthreads, h, ref->hash,
                fdt_result_num_tets(r), ref->ntets);
    CHECK(h == ref->hash);
    size_t nt = fdt_result_num_tets(r);
    CHECK_EQ(nt, ref->ntets);
    CHECK_EQ(fdt_result_num_hull_faces(r), ref->nhull);
    /* Both sorted canonically: identical arrays, neighbours included. */
    CHECK(memcmp(fdt_result_tets(r), fdt_result_tets(ref->r), 4 * nt * sizeof(fdt_vid)) == 0);
    CHECK(fdt_result_neighbors(r));
    CHECK(memcmp(fdt_result_neighbors(r), fdt_result_neighbors(ref->r),
                 4 * nt * sizeof(fdt_tid)) == 0);
    fdt_vid *hull = canon_hull(r);
    CHECK(memcmp(hull, ref->hull, 3 * ref->nhull * sizeof *hull) == 0);
    free(hull);
    char msg[256];
    if (fdt_check(p->xyz, p->n, fdt_result_tets(r), nt, fdt_result_neighbors(r), msg,
                  sizeof msg) != FDT_OK)
        fprintf(stderr, "%s: %s with %d threads fails fdt_check: %s\n", p->name,
                mode_name(mode), nthreads, msg);
    CHECK(fdt_check(p->xyz, p->n, fdt_result_tets(r), nt, fdt_result_neighbors(r), msg,
                    sizeof msg) == FDT_OK);
    check_stats(r, mode, nthreads);
    if (g_verbose) {
        fdt_stats st;
        fdt_result_stats(r, &st);
        printf("  %-18s %-7s N=%-3d tets %zu facesend %zu nodesend %zu dup %zu imb %.2f\n",
               p->name, mode_name(mode), nthreads, nt, st.sent[FDT_MSG_FACESEND], st.sent[FDT_MSG_NODESEND],
               st.duplicate_requests, st.load_imbalance);
    }
    fdt_result_free(&r);
}

static int quad_cmp(const void *x, const void *y)
{
    const fdt_vid *a = x, *b = y;
    for (int i = 0; i < 4; i++)
        if (a[i] != b[i])
            return a[i] < b[i] ? -1 : 1;
    return 0;
}

/* Serial on a shuffled copy, mapped back, is serial on the original. */
static void check_shuffle_invariance(const reference *orig, const reference *sh,
                                     const size_t *perm)
{
    CHECK_EQ(orig->ntets, sh->ntets);
    size_t nt = sh->ntets;
    fdt_vid (*keys)[4] = malloc((nt ? nt : 1) * sizeof *keys);
    CHECK(keys);
    const fdt_vid *t = fdt_result_tets(sh->r);
    for (size_t i = 0; i < nt; i++) {
        fdt_vid k[4];
        for (int j = 0; j < 4; j++)
            k[j] = (fdt_vid)perm[t[4 * i + j]];
        for (int a = 1; a < 4; a++)
            for (int b = a; b > 0 && k[b - 1] > k[b]; b--) {
                fdt_vid x = k[b];
                k[b] = k[b - 1];
                k[b - 1] = x;
            }
        memcpy(keys[i], k, sizeof k);
    }
    qsort(keys, nt, sizeof *keys, quad_cmp);
    const fdt_vid *o = fdt_result_tets(orig->r);
    for (size_t i = 0; i < nt; i++) {
        fdt_vid k[4];
        memcpy(k, o + 4 * i, sizeof k);
        if (k[2] > k[3]) {
            fdt_vid x = k[2];
            k[2] = k[3];
            k[3] = x;
        }
        CHECK(memcmp(k, keys[i], sizeof k) == 0);
    }
    free(keys);
}

static const int k_threads_full[] = {1, 2, 3, 4, 5, 8, 16, 64};
static const int k_threads_quick[] = {1, 2, 3, 5, 16};

static void test_family(pts p, int quick)
{
    const int *tl = quick ? k_threads_quick : k_threads_full;
    int nt = quick ? (int)(sizeof k_threads_quick / sizeof *tl)
                   : (int)(sizeof k_threads_full / sizeof *tl);
    double t0 = now_s();
    size_t *perm;
    pts sp = shuffled(&p, 0x5eed0000ULL + p.n, &perm);
    reference ref = make_ref(&p), sref = make_ref(&sp);
    check_shuffle_invariance(&ref, &sref, perm);
    for (int i = 0; i < nt; i++)
        for (int m = FDT_MODE_SHARED; m <= FDT_MODE_MESSAGE; m++) {
            compare_run(&p, &ref, (fdt_mode)m, tl[i]);
            compare_run(&sp, &sref, (fdt_mode)m, tl[i]);
        }
    printf("%-10s %6zu points %6zu tets: shared and message equal serial for %d thread counts"
           " (%.1f s)\n", p.name, p.n, ref.ntets, nt, now_s() - t0);
    fflush(stdout);
    free_ref(&ref);
    free_ref(&sref);
    free(perm);
    free(sp.xyz);
    free(p.xyz);
}

/* ---- many threads on tiny inputs ------------------------------------------ */

static void test_tiny(int reps)
{
    for (int rep = 0; rep < reps; rep++) {
        pts inputs[4] = {fam_uniform(12 + 9 * (size_t)rep, 100 + (uint64_t)rep),
                         fam_lattice(3 + rep % 2), fam_intsphere(325),
                         fam_grid2(3 + rep % 3)};
        for (int f = 0; f < 4; f++) {
            reference ref = make_ref(&inputs[f]);
            for (int m = FDT_MODE_SHARED; m <= FDT_MODE_MESSAGE; m++) {
                compare_run(&inputs[f], &ref, (fdt_mode)m, 16);
                compare_run(&inputs[f], &ref, (fdt_mode)m, 64);
            }
            free_ref(&ref);
            free(inputs[f].xyz);
        }
    }
    printf("tiny inputs with 16 and 64 threads (pockets), %d rounds: equal serial\n", reps);
}

/* AUTO with several threads runs shared mode; errors are refused. */
static void test_api(void)
{
    pts p = fam_uniform(300, 3);
    reference ref = make_ref(&p);
    fdt_result *r = run(&p, FDT_MODE_AUTO, 3, 1, FDT_OK);
    fdt_stats st;
    CHECK_EQ(fdt_result_stats(r, &st), FDT_OK);
    CHECK_EQ(st.mode, FDT_MODE_SHARED);
    CHECK_EQ(st.threads, 3);
    uint64_t h;
    CHECK_EQ(fdt_result_hash(r, &h), FDT_OK);
    CHECK(h == ref.hash);
    fdt_result_free(&r);
    r = run(&p, FDT_MODE_AUTO, 1, 0, FDT_OK);
    CHECK_EQ(fdt_result_stats(r, &st), FDT_OK);
    CHECK_EQ(st.mode, FDT_MODE_SERIAL);
    fdt_thread_stats ts;
    CHECK_EQ(fdt_result_thread_stats(r, 0, &ts), FDT_OK);
    CHECK_EQ(ts.tets, st.tets);
    CHECK_EQ(fdt_result_thread_stats(r, 1, &ts), FDT_EINVAL);
    fdt_result_free(&r);
    /* Every point twice: merged before partitioning, same mesh. */
    {
        pts d = pts_alloc("uniform-twice", 2 * p.n);
        memcpy(d.xyz, p.xyz, 3 * p.n * sizeof *d.xyz);
        memcpy(d.xyz + 3 * p.n, p.xyz, 3 * p.n * sizeof *d.xyz);
        for (int m = FDT_MODE_SHARED; m <= FDT_MODE_MESSAGE; m++) {
            r = run(&d, (fdt_mode)m, 3 + m, 0, FDT_OK);
            CHECK_EQ(fdt_result_num_duplicates(r), p.n);
            CHECK_EQ(fdt_result_hash(r, &h), FDT_OK);
            CHECK(h == ref.hash);
            fdt_result_free(&r);
        }
        free(d.xyz);
    }
    /* Neighbours off: no neighbour array. */
    r = run(&p, FDT_MODE_SHARED, 4, 0, FDT_OK);
    CHECK(fdt_result_neighbors(r) == NULL);
    fdt_result_free(&r);
    /* The work shift balances tets, not points: on uniform points the
     * first part, owner of every tet across the cuts (§3.2), built 2.3 %
     * more tets than the last of two and 7 % more of eight without it. */
    {
        pts u = fam_uniform(60000, 11);
        const int nts[] = {2, 8};
        for (int i = 0; i < 2; i++) {
            fdt_result *ru = run(&u, FDT_MODE_SHARED, nts[i], 0, FDT_OK);
            CHECK_EQ(fdt_result_stats(ru, &st), FDT_OK);
            printf("uniform 60k, %d threads: load imbalance %.4f\n", nts[i], st.load_imbalance);
            CHECK(st.load_imbalance < 1.015);
            fdt_result_free(&ru);
        }
        free(u.xyz);
    }
    /* Degenerate input is refused before any thread starts. */
    pts flat = fam_grid2(5);
    for (size_t i = 0; i < flat.n; i++)
        flat.xyz[3 * i + 2] = 0.0; /* duplicates merge: one plane */
    r = run(&flat, FDT_MODE_SHARED, 4, 0, FDT_EDEGENERATE);
    CHECK(r == NULL);
    free(flat.xyz);
    fdt_settings s;
    fdt_default_settings(&s);
    s.n_threads = 1025;
    fdt_context *ctx = NULL;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_EINVAL);
    free_ref(&ref);
    free(p.xyz);
    printf("api: auto mode, thread count 0, no neighbours, refusals\n");
}

/* fdt_parallel_run's refusals: a mode that is not a parallel one, a
 * thread count outside 1..1024, fewer than four distinct points; each
 * FDT_EINVAL with an empty output. And the settings' leaf size reaches
 * the parts' trees: any leaf size, the same mesh. */
static void test_run_args(void)
{
    pts p = fam_uniform(400, 41);
    reference ref = make_ref(&p);
    fdt_prepared pr;
    char diag[256] = "";
    CHECK_EQ(fdt_prepare(p.xyz, p.n, 1, &pr, diag, sizeof diag), FDT_OK);
    fdt_settings s;
    fdt_default_settings(&s);
    fdt_par_out out;
    const struct { fdt_mode mode; int threads; } bad[] = {
        {FDT_MODE_SERIAL, 2}, {FDT_MODE_AUTO, 2}, {FDT_MODE_SHARED, 0},
        {FDT_MODE_MESSAGE, 1025}, {FDT_MODE_SHARED, -3}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        memset(&out, 0x55, sizeof out);
        EXPECTF(fdt_parallel_run(&pr, &s, bad[i].mode, bad[i].threads, NULL, &out, diag,
                                 sizeof diag) == FDT_EINVAL,
                "mode %d, %d threads", (int)bad[i].mode, bad[i].threads);
        EXPECT(out.mb.tets == NULL && out.tstats == NULL && out.nthreads == 0);
    }
    size_t m = pr.m;
    pr.m = 3;
    EXPECT(fdt_parallel_run(&pr, &s, FDT_MODE_SHARED, 2, NULL, &out, diag, sizeof diag) ==
           FDT_EINVAL);
    pr.m = m;
    fdt_prepared_free(&pr);
    for (int leaf = 1; leaf <= 64; leaf *= 64)
        for (int mode = FDT_MODE_SHARED; mode <= FDT_MODE_MESSAGE; mode++) {
            fdt_default_settings(&s);
            s.mode = (fdt_mode)mode;
            s.n_threads = 3;
            s.leaf_size = leaf;
            fdt_context *ctx = NULL;
            CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
            fdt_result *r = NULL;
            CHECK_EQ(fdt_triangulate(ctx, p.xyz, p.n, &r), FDT_OK);
            uint64_t h;
            CHECK_EQ(fdt_result_hash(r, &h), FDT_OK);
            EXPECTF(h == ref.hash, "leaf size %d, mode %d", leaf, mode);
            fdt_result_free(&r);
            fdt_close(&ctx);
        }
    free_ref(&ref);
    free(p.xyz);
    printf("fdt_parallel_run: bad modes, thread counts and point counts refused; leaf sizes\n");
}

/* The canonical sort of src/mesh/result.c runs on the triangulation's threads
 * (one a core) above 65,536 tets: 15,000 points make about 100,000. With
 * and without neighbours (6- and 4-word records), its order and hash must
 * be serial mode's, and the tets strictly increasing in canonical key. */
static void test_sort_threads(void)
{
    pts p = fam_uniform(15000, 17);
    for (int nbrs = 0; nbrs <= 1; nbrs++) {
        fdt_result *ref = run(&p, FDT_MODE_SERIAL, 1, nbrs, FDT_OK);
        uint64_t href, h;
        CHECK_EQ(fdt_result_hash(ref, &href), FDT_OK);
        size_t nt = fdt_result_num_tets(ref);
        CHECK(nt > 65536);
        const fdt_vid *t = fdt_result_tets(ref);
        for (size_t i = 1; i < nt; i++) {
            fdt_vid a[4], b[4];
            for (int k = 0; k < 4; k++) {
                a[k] = t[4 * (i - 1) + k];
                b[k] = t[4 * i + k];
            }
            /* key: the first two, then the last two in increasing order */
            for (fdt_vid *x = a; x; x = x == a ? b : NULL)
                if (x[2] > x[3]) {
                    fdt_vid y = x[2];
                    x[2] = x[3];
                    x[3] = y;
                }
            CHECK(a[0] < a[1] && a[1] < a[2] && a[2] < a[3]);
            CHECK(memcmp(a, b, sizeof a) != 0);
            int lt = 0;
            for (int k = 0; k < 4; k++)
                if (a[k] != b[k]) {
                    lt = a[k] < b[k];
                    break;
                }
            CHECK(lt);
        }
        for (int nthreads = 2; nthreads <= 5; nthreads += 3) {
            fdt_result *r = run(&p, FDT_MODE_SHARED, nthreads, nbrs, FDT_OK);
            CHECK_EQ(fdt_result_sort(r), FDT_OK);
            CHECK_EQ(fdt_result_num_tets(r), nt);
            CHECK(memcmp(fdt_result_tets(r), t, 4 * nt * sizeof *t) == 0);
            if (nbrs)
                CHECK(memcmp(fdt_result_neighbors(r), fdt_result_neighbors(ref),
                             4 * nt * sizeof(fdt_tid)) == 0);
            CHECK_EQ(fdt_result_hash(r, &h), FDT_OK);
            CHECK(h == href);
            fdt_result_free(&r);
        }
        fdt_result_free(&ref);
    }
    free(p.xyz);
    /* The hash while sorting (src/mesh/result.c, phase D): worker 0 chains the
     * texts the other sort threads wrote ahead of it, on more threads than
     * cores too. Buckets of a few hundred tets, so that worker 0 is still
     * hashing when the sorting runs out and the writers start. */
    p = fam_uniform(60000, 19);
    fdt_result *ref = run(&p, FDT_MODE_SERIAL, 1, 0, FDT_OK);
    uint64_t href, h;
    CHECK_EQ(fdt_result_hash(ref, &href), FDT_OK);
    for (int sorters = 2; sorters <= 9; sorters += 7) {
        fdt_result *r = run(&p, FDT_MODE_SHARED, 2, 0, FDT_OK);
        CHECK_EQ(fdt_result_hash_threads(r, sorters, &h), FDT_OK);
        CHECK(h == href);
        CHECK(memcmp(fdt_result_tets(r), fdt_result_tets(ref),
                     4 * fdt_result_num_tets(ref) * sizeof(fdt_vid)) == 0);
        fdt_result_free(&r);
    }
    fdt_result_free(&ref);
    free(p.xyz);
}

/* Message mode caches foreign coordinates in a per-thread ghost map of
 * 1,024 slots at first, doubled at half load (src/par/parallel.c, ghost_put).
 * The small families never fill it; 40,000 uniform points cut in two or
 * four give each part a layer of thousands of foreign points, so the map
 * is rehashed several times during the run: the mesh must still be
 * serial mode's. */
static void test_ghost_rehash(void)
{
    pts p = fam_uniform(40000, 23);
    reference ref = make_ref(&p);
    compare_run(&p, &ref, FDT_MODE_MESSAGE, 2);
    compare_run(&p, &ref, FDT_MODE_MESSAGE, 4);
    free_ref(&ref);
    free(p.xyz);
    printf("message mode, 40000 points, 2 and 4 threads (ghost map rehashed): equal serial\n");
}

static void test_long(void)
{
    pts p = fam_uniform(200000, 2024);
    reference ref = make_ref(&p);
    const int tl[] = {1, 2, 4, 8};
    for (int i = 0; i < 4; i++)
        for (int m = FDT_MODE_SHARED; m <= FDT_MODE_MESSAGE; m++)
            compare_run(&p, &ref, (fdt_mode)m, tl[i]);
    printf("uniform %zu points, %zu tets: shared and message equal serial for N = 1, 2, 4, 8\n",
           p.n, ref.ntets);
    free_ref(&ref);
    free(p.xyz);
}

int main(int argc, char **argv)
{
    int quick = 0, lng = 0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--quick"))
            quick = 1;
        else if (!strcmp(argv[i], "--long"))
            lng = 1;
        else if (!strcmp(argv[i], "-v"))
            g_verbose = 1;
        else {
            fprintf(stderr, "usage: test_parallel [--quick] [--long] [-v]\n");
            return 2;
        }
    }
    setvbuf(stdout, NULL, _IOLBF, 0);
    /* A lost wakeup or a deadlock must fail, not hang. */
    alarm(lng ? 3000 : 1200);
    if (lng) {
        test_long();
        return 0;
    }
    test_api();
    test_run_args();
    test_family(fam_uniform(quick ? 600 : 2000, 1), quick);
    test_family(fam_lattice(quick ? 6 : 9), quick);
    test_family(fam_intsphere(quick ? 325 : 725), quick);
    test_family(fam_grid2(quick ? 10 : 16), quick);
    test_family(fam_clusters(quick ? 600 : 1500, 5), quick);
    test_family(fam_offset(quick ? 600 : 1500, 9), quick);
    test_tiny(quick ? 2 : 4);
    test_sort_threads();
    test_ghost_rehash();
    return test_report("parallel");
}
