/*
 * Allocation-failure injection over the library and the file formats.
 *
 * The test is linked with -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,
 * --wrap=aligned_alloc,--wrap=free (tests/meson.build), so every call to
 * these from the static libraries (the files in src/) and from this file goes through
 * the __wrap_ functions below. Allocations made inside libc (fopen, qsort)
 * and GMP are not seen: they cannot be made to fail from here. (GMP aborts
 * on a failed allocation by design; README.md, Limits.)
 *
 * For each scenario (a read, a triangulation, a sort, a hash, a check, a write,
 * a streamed write through fdt_stream_writer_*, the Voronoi cells (in
 * memory and streamed), point
 * location, interpolation) and k = 1, 2, ...:
 *   - "once":  the k-th allocation of the scenario fails, later ones work;
 *   - "from":  the k-th and every later allocation fail (error paths that
 *              allocate while cleaning up fail too);
 * until a run meets no k-th allocation. Every run that hit a failure must
 * return the scenario's out-of-memory code (FDT_ENOMEM / FDT_IO_ENOMEM),
 * or succeed with the reference answer where the code can do without the
 * memory (the readers' final shrinking realloc keeps the larger block), not
 * crash, and free everything it allocated: the count of live blocks is
 * back to its value before the run (and ASan's leak check agrees in the
 * sanitizer build). A run that hit none must succeed and give the
 * reference answer. Results left by a failed fdt_result_sort() or
 * fdt_result_hash() must still hash to the reference, and a failed write
 * must leave its directory empty.
 *
 * The wrappers also record the largest request, so the test can show that
 * no file of the hostile corpus makes a reader allocate in proportion to a
 * count in its header rather than to its size (check_bad_sizes()).
 *
 * usage: test_faults GOOD_DIR BAD_DIR  (tests/good, tests/bad)
 *        test_faults --parallel        (the engine's parallel modes)
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "frontdt.h"
#include "mesh/insert.h"
#include "io/read/reader.h"
#include "io/write/writer.h"

#include <dirent.h>
#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include "testdir.h"
#include "api/dual.h"
#include "testutil.h"

/* ------------------------------------------------------------------ */
/* The allocation hooks                                               */
/* ------------------------------------------------------------------ */

/*
 * The hooks have no context argument, so their state is global: the one
 * place this test keeps mutable globals. Atomics, because a scenario
 * could run engine threads (the serial runs here do not).
 */
static atomic_long fault_seen;  /* allocation calls since fault_arm() */
static atomic_long fault_at;    /* 0: off; k: the k-th call fails */
static atomic_int fault_sticky; /* every call after the k-th fails too */
static atomic_int fault_hit;    /* a failure was injected */
static atomic_long fault_live;  /* blocks handed out and not freed */
static atomic_size_t fault_max; /* largest size asked for since reset */

/* Records the size of a request (for the no-big-allocation check). */
static void fault_note(size_t size)
{
    size_t m = atomic_load(&fault_max);
    while (size > m && !atomic_compare_exchange_weak(&fault_max, &m, size))
        ;
}

void *__real_malloc(size_t size);
void *__real_calloc(size_t nmemb, size_t size);
void *__real_realloc(void *p, size_t size);
void *__real_aligned_alloc(size_t align, size_t size);
void __real_free(void *p);
void *__wrap_malloc(size_t size);
void *__wrap_calloc(size_t nmemb, size_t size);
void *__wrap_realloc(void *p, size_t size);
void *__wrap_aligned_alloc(size_t align, size_t size);
void __wrap_free(void *p);

/* Whether this allocation call is to fail. */
static int fault_now(void)
{
    long at = atomic_load(&fault_at);
    if (at == 0)
        return 0;
    long k = atomic_fetch_add(&fault_seen, 1) + 1;
    if (k == at || (k > at && atomic_load(&fault_sticky))) {
        atomic_store(&fault_hit, 1);
        errno = ENOMEM;
        return 1;
    }
    return 0;
}

void *__wrap_malloc(size_t size)
{
    fault_note(size);
    if (fault_now())
        return NULL;
    void *p = __real_malloc(size);
    if (p != NULL)
        atomic_fetch_add(&fault_live, 1);
    return p;
}

void *__wrap_calloc(size_t nmemb, size_t size)
{
    fault_note(size != 0 && nmemb > SIZE_MAX / size ? SIZE_MAX : nmemb * size);
    if (fault_now())
        return NULL;
    void *p = __real_calloc(nmemb, size);
    if (p != NULL)
        atomic_fetch_add(&fault_live, 1);
    return p;
}

void *__wrap_aligned_alloc(size_t align, size_t size)
{
    fault_note(size);
    if (fault_now())
        return NULL;
    void *p = __real_aligned_alloc(align, size);
    if (p != NULL)
        atomic_fetch_add(&fault_live, 1);
    return p;
}

void *__wrap_realloc(void *p, size_t size)
{
    fault_note(size);
    if (fault_now())
        return NULL; /* like a real failure: p is untouched */
    void *q = __real_realloc(p, size);
    if (p == NULL && q != NULL)
        atomic_fetch_add(&fault_live, 1);
    else if (p != NULL && q == NULL && size == 0)
        atomic_fetch_sub(&fault_live, 1); /* glibc: realloc(p, 0) frees */
    return q;
}

void __wrap_free(void *p)
{
    if (p != NULL)
        atomic_fetch_sub(&fault_live, 1);
    __real_free(p);
}

static void fault_arm(long k, int sticky)
{
    atomic_store(&fault_seen, 0);
    atomic_store(&fault_hit, 0);
    atomic_store(&fault_sticky, sticky);
    atomic_store(&fault_at, k);
}

/* Stops injecting; returns whether a failure was injected. */
static int fault_disarm(void)
{
    atomic_store(&fault_at, 0);
    return atomic_load(&fault_hit);
}

/* ------------------------------------------------------------------ */
/* Test bookkeeping                                                   */
/* ------------------------------------------------------------------ */

static long total_runs, total_injected, total_absorbed;

/* The counts and the verdict at the end of a suite: main's exit status. */
static int report(const char *which)
{
    printf("%ld runs, %ld with an injected failure (%ld absorbed)\n",
           total_runs, total_injected, total_absorbed);
    if (test_failures() == 0)
        printf("all %sfault-injection tests passed\n", which);
    return test_report("test_faults");
}

/*
 * A scenario: one call (or a short sequence) that cleans up after itself
 * whatever happens. Returns its status; *bad may name what went
 * wrong beyond the status (a wrong answer after success, a result left
 * unusable, a file left behind): NULL when all is well.
 */
typedef struct scenario {
    const char *name;
    int enomem; /* the out-of-memory code it must return */
    int (*run)(void *arg, const char **bad);
    void *arg;
} scenario;

/* Runs sc for k = 1, 2, ... in both injection modes. */
static void inject_all(const scenario *sc)
{
    for (int sticky = 0; sticky <= 1; sticky++) {
        long k, absorbed = 0;
        for (k = 1;; k++) {
            long live0 = atomic_load(&fault_live);
            const char *bad = NULL;
            fault_arm(k, sticky);
            int rc = sc->run(sc->arg, &bad);
            int hit = fault_disarm();
            long leaked = atomic_load(&fault_live) - live0;
            total_runs++;
            EXPECTF(leaked == 0, "%s, %s allocation %ld: %ld blocks leaked",
                  sc->name, sticky ? "from" : "only", k, leaked);
            EXPECTF(bad == NULL, "%s, %s allocation %ld failed: %s", sc->name,
                  sticky ? "from" : "only", k, bad ? bad : "");
            if (!hit) {
                EXPECTF(rc == 0, "%s: status %d with no failure injected",
                      sc->name, rc);
                break;
            }
            total_injected++;
            if (k > 100000) {
                EXPECTF(0, "%s: more than 100000 allocations?", sc->name);
                break;
            }
            if (rc == 0) { /* done without the memory: bad says if wrongly */
                absorbed++;
                total_absorbed++;
                continue;
            }
            EXPECTF(rc == sc->enomem,
                  "%s, %s allocation %ld failed: status %d, want %d",
                  sc->name, sticky ? "from" : "only", k, rc, sc->enomem);
        }
        if (!sticky)
            printf("%-34s %3ld allocation sites", sc->name, k - 1);
        if (absorbed)
            printf(" (%s: %ld failure(s) absorbed)", sticky ? "from" : "once",
                   absorbed);
        if (sticky)
            printf("\n");
    }
}

/* ------------------------------------------------------------------ */
/* Inputs                                                             */
/* ------------------------------------------------------------------ */

/* xorshift64*: any fixed sequence will do. */
static double rnd01(uint64_t *st)
{
    *st ^= *st >> 12;
    *st ^= *st << 25;
    *st ^= *st >> 27;
    return (double)((*st * 2685821657736338717u) >> 11) * 0x1p-53;
}

/* A point set for the engine scenarios. */
typedef struct ptset {
    const char *name;
    double *xyz; /* 3 * n (owned) */
    size_t n;
} ptset;

static double *alloc_points(size_t n)
{
    double *p = malloc(3 * n * sizeof *p);
    if (p == NULL) {
        fprintf(stderr, "out of memory\n");
        exit(1);
    }
    return p;
}

/*
 * 60 points: 27 on a 3x3x3 lattice (cospherical and coplanar subsets: the
 * exact predicates and the perturbation run), 30 random, 3 duplicates.
 */
static ptset make_lattice(uint64_t *rng)
{
    ptset s = {"lattice", alloc_points(60), 60};
    double *p = s.xyz;
    size_t i = 0;
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++)
            for (int c = 0; c < 3; c++, i++) {
                p[3 * i] = a;
                p[3 * i + 1] = b;
                p[3 * i + 2] = c;
            }
    for (; i < 57; i++)
        for (int k = 0; k < 3; k++)
            p[3 * i + k] = 2.0 * rnd01(rng);
    for (int d = 0; d < 3; d++, i++)
        memcpy(p + 3 * i, p + 3 * (size_t)(d * 17 + 5), 3 * sizeof(double));
    return s;
}

/*
 * 2 x 24 points on two skew lines: about 23^2 tets, far more than the
 * engine's first guess of 6.9 a point, so the tet (and neighbour) arrays
 * grow while the front runs.
 */
static ptset make_skew_lines(uint64_t *rng)
{
    ptset s = {"skew lines", alloc_points(48), 48};
    for (size_t i = 0; i < 24; i++) {
        double t = (double)i + 0.5 * rnd01(rng);
        double u = (double)i + 0.5 * rnd01(rng);
        double *a = s.xyz + 6 * i;
        a[0] = t, a[1] = 0, a[2] = 0;
        a[3] = 0, a[4] = u, a[5] = 8;
    }
    return s;
}

/*
 * 700 points near a sphere and 20 inside: about 1400 hull faces, more than
 * the engine's first hull array holds.
 */
static ptset make_sphere(uint64_t *rng)
{
    ptset s = {"sphere", alloc_points(720), 720};
    for (size_t i = 0; i < 700; i++) {
        /* Fibonacci sphere, radius jittered so no 5 are cospherical */
        double z = 1.0 - (2.0 * (double)i + 1.0) / 700.0;
        double r = sqrt(1.0 - z * z), ph = 2.399963229728653 * (double)i;
        double rad = 1.0 + 1e-3 * rnd01(rng);
        s.xyz[3 * i] = rad * r * cos(ph);
        s.xyz[3 * i + 1] = rad * r * sin(ph);
        s.xyz[3 * i + 2] = rad * z;
    }
    for (size_t i = 700; i < 720; i++)
        for (int k = 0; k < 3; k++)
            s.xyz[3 * i + k] = 0.5 * rnd01(rng) - 0.25;
    return s;
}

/* ------------------------------------------------------------------ */
/* Scenarios: the engine                                              */
/* ------------------------------------------------------------------ */

/* How the engine runs: serial, or a parallel mode with some threads. */
typedef struct engine_cfg {
    fdt_mode mode;
    int threads;
} engine_cfg;

static const engine_cfg serial_cfg = {FDT_MODE_SERIAL, 1};

typedef struct tri_arg {
    const ptset *ps;
    const engine_cfg *cfg;
    int neighbors;
    uint64_t want_hash; /* the reference, from an uninjected run */
    size_t want_tets;
    unsigned periodic;  /* periodic axes in the unit box (issue 33), or 0 */
} tri_arg;

static int triangulate_p(const ptset *ps, const engine_cfg *cfg, int neighbors,
                         unsigned periodic, fdt_result **res)
{
    fdt_settings s;
    fdt_default_settings(&s);
    s.mode = cfg->mode;
    s.n_threads = cfg->threads;
    s.neighbors = neighbors;
    s.periodic = periodic;
    const double unit[6] = {0, 0, 0, 1, 1, 1};
    memcpy(s.periodic_box, unit, sizeof unit);
    fdt_context *ctx = NULL;
    int rc = fdt_open(&ctx, &s);
    if (rc != FDT_OK)
        return rc;
    rc = fdt_triangulate(ctx, ps->xyz, ps->n, res);
    if (rc == FDT_ENOMEM && fdt_context_diagnostic(ctx)[0] == '\0')
        rc = FDT_EINTERNAL; /* FDT_ENOMEM must come with a diagnostic */
    fdt_close(&ctx);
    return rc;
}

static int triangulate(const ptset *ps, const engine_cfg *cfg, int neighbors, fdt_result **res)
{
    return triangulate_p(ps, cfg, neighbors, 0, res);
}

/* fdt_open + fdt_triangulate; the answer is checked after success (the
 * hash is taken with injection off). */
static int sc_triangulate(void *arg, const char **bad)
{
    tri_arg *a = arg;
    fdt_result *r = NULL;
    int rc = triangulate_p(a->ps, a->cfg, a->neighbors, a->periodic, &r);
    if (rc != FDT_OK) {
        if (r != NULL)
            *bad = "a failed fdt_triangulate returned a result";
        fdt_result_free(&r);
        return rc;
    }
    long at = atomic_load(&fault_at);
    atomic_store(&fault_at, 0);
    uint64_t h = 0;
    if (fdt_result_hash(r, &h) != FDT_OK || h != a->want_hash ||
        fdt_result_num_tets(r) != a->want_tets)
        *bad = "wrong mesh";
    if (a->neighbors && fdt_result_neighbors(r) == NULL)
        *bad = "no neighbours";
    atomic_store(&fault_at, at);
    fdt_result_free(&r);
    return rc;
}

/* The cells of a periodic mesh (fdt_voronoi_compute on a result periodic
 * in x, y and z, src/mesh/periodic.c) under injection: the reference's
 * volumes, or a clean FDT_ENOMEM. */
typedef struct pcells_arg {
    fdt_result *r;
    const ptset *ps;
    double want_sum;
} pcells_arg;

static int sc_pcells(void *arg, const char **bad)
{
    pcells_arg *a = arg;
    fdt_voronoi *v = NULL;
    char diag[256];
    int rc = fdt_voronoi_compute(a->r, a->ps->xyz, a->ps->n, NULL, &v, diag, sizeof diag);
    if (rc != FDT_OK) {
        if (v != NULL)
            *bad = "a failed periodic cells call returned cells";
        fdt_voronoi_free(&v);
        return rc;
    }
    double sum = 0;
    for (size_t i = 0; i < a->ps->n; i++)
        sum += fdt_voronoi_volumes(v)[i];
    if (sum != a->want_sum && a->want_sum == a->want_sum)
        *bad = "other periodic cells";
    a->want_sum = sum;
    fdt_voronoi_free(&v);
    return rc;
}

/* The polyhedral dual (src/api/dual.c) under injection: a plain result's
 * clipped by the box, or a periodic one's (the images, their
 * triangulation, the plain dual, the fold): the reference's counts, or a
 * clean FDT_ENOMEM and nothing held. */
typedef struct pdual_arg {
    fdt_result *r;
    const ptset *ps;
    size_t want[3]; /* cells, faces, vertices (0: not yet known) */
} pdual_arg;

static int sc_pdual(void *arg, const char **bad)
{
    pdual_arg *a = arg;
    fdt_dualmesh d;
    char diag[512];
    int rc = fdt_dual_build(a->r, a->ps->xyz, a->ps->n, NULL, 1, &d, diag, sizeof diag);
    if (rc != FDT_OK) {
        if (d.xyz || d.fstart || d.cyclic || d.cell_of)
            *bad = "a failed periodic dual kept arrays";
        return rc;
    }
    size_t got[3] = {d.n_cells, d.n_faces, d.n_verts};
    if (a->want[0] && memcmp(got, a->want, sizeof got))
        *bad = "another periodic dual";
    memcpy(a->want, got, sizeof got);
    fdt_dualmesh_free(&d);
    return rc;
}

/* A periodic mesh written (fdt_write_mesh: .fdtb with its offsets, .vtu,
 * .msh, TetGen's set and an OpenFOAM polyMesh laid out with its image
 * vertices, src/mesh/periodic.c's fdt_periodic_unfold, the last two with
 * the periodic neighbours) under injection: its files (a TetGen set's
 * four, a polyMesh's directory), or FDT_ENOMEM and none. */
typedef struct pwrite_arg {
    fdt_result *r;
    const ptset *ps;
    const char *dir, *ext;
    int files;
} pwrite_arg;

static void empty_dir(const char *dir);

static int sc_pwrite(void *arg, const char **bad)
{
    pwrite_arg *a = arg;
    char path[1024], diag[512];
    snprintf(path, sizeof path, "%s/%s%s", a->dir, strcmp(a->ext, "polyMesh") ? "per" : "",
             a->ext);
    int rc = fdt_write_mesh(a->r, a->ps->xyz, a->ps->n, path, NULL, diag, sizeof diag);
    if (count_entries(a->dir) != (rc == FDT_OK ? a->files : 0))
        *bad = rc != FDT_OK ? "files left after a failed periodic write"
                            : "no file after a periodic write";
    empty_dir(a->dir);
    return rc;
}

/* The periodic mesh's check (fdt_check_periodic) under injection: FDT_OK
 * or FDT_ENOMEM, never a verdict against the mesh. */
static int sc_pcheck(void *arg, const char **bad)
{
    pwrite_arg *a = arg;
    double box[6];
    unsigned axes = fdt_result_periodic(a->r, box);
    char msg[256];
    int rc = fdt_check_periodic(a->ps->xyz, a->ps->n, fdt_result_tets(a->r),
                                fdt_result_tet_offsets(a->r), fdt_result_num_tets(a->r),
                                fdt_result_hull_faces(a->r), fdt_result_hull_offsets(a->r),
                                fdt_result_num_hull_faces(a->r), axes, box, msg, sizeof msg);
    if (rc == FDT_ECHECK)
        *bad = "the check failed a periodic mesh under injection";
    return rc;
}

/* A periodic run streamed to a .tets (FDT_STREAM_PERIODIC: the rows
 * spooled, merged at the commit) under injection: one file with the
 * in-memory .tets's bytes (want_hash, fdt_result_hash's FNV-1a of them),
 * or an error and no file. */
typedef struct pstream_arg {
    const ptset *ps;
    unsigned periodic;
    const char *dir;
    uint64_t want_hash;
} pstream_arg;

static int sc_pstream(void *arg, const char **bad)
{
    pstream_arg *a = arg;
    fdt_settings s;
    fdt_default_settings(&s);
    s.n_threads = 1;
    s.periodic = a->periodic;
    const double unit[6] = {0, 0, 0, 1, 1, 1};
    memcpy(s.periodic_box, unit, sizeof unit);
    char path[1024], diag[1024] = "";
    snprintf(path, sizeof path, "%s/per.tets", a->dir);
    fdt_context *ctx = NULL;
    int rc = fdt_open(&ctx, &s);
    fdt_stream_writer *w = NULL;
    if (rc == FDT_OK)
        rc = fdt_stream_writer_open(&w, path, NULL, a->ps->xyz, a->ps->n, FDT_STREAM_PERIODIC,
                                    diag, sizeof diag);
    if (rc == FDT_OK) {
        fdt_sink sink;
        fdt_result *r = NULL;
        int e = fdt_stream_writer_sink(w, &sink);
        if (e == FDT_OK)
            e = fdt_triangulate_stream(ctx, a->ps->xyz, a->ps->n, &sink, &r);
        fdt_result_free(&r);
        rc = fdt_stream_writer_close(&w, e == FDT_OK, diag, sizeof diag);
        rc = e != FDT_OK ? e : rc;
    }
    fdt_close(&ctx);
    if (count_entries(a->dir) != (rc == FDT_OK))
        *bad = rc != FDT_OK ? "files left after a failed periodic stream"
                            : "no file after a periodic stream";
    if (rc == FDT_OK) {
        FILE *f = fopen(path, "rb");
        uint64_t h = 14695981039346656037ull;
        for (int c; f && (c = getc(f)) != EOF;)
            h = (h ^ (uint64_t)(unsigned char)c) * 1099511628211ull;
        if (f)
            fclose(f);
        if (h != a->want_hash)
            *bad = "the streamed periodic .tets is not the in-memory one";
    }
    empty_dir(a->dir);
    return rc;
}

/* A streamed run (fdt_triangulate_stream) under injection: it succeeds
 * with the in-memory run's set hash and tet count, or fails with nothing
 * returned; the sink counts what reached it (less than the mesh on a
 * failure is fine: the contract allows a partial stream). */
typedef struct stream_arg {
    const ptset *ps;
    const engine_cfg *cfg;
    uint64_t want_set;
    size_t want_tets;
} stream_arg;

static int count_sink(void *user, const fdt_vid *t, size_t count)
{
    (void)t;
    *(size_t *)user += count;
    return 0;
}

/* A streamed call's status checked and ctx closed: FDT_ENOMEM must come
 * with a diagnostic, and a failed call must leave no result (freed
 * here). */
static int stream_status(fdt_context **ctx, int rc, fdt_result **r, const char *failed,
                         const char **bad)
{
    if (rc == FDT_ENOMEM && fdt_context_diagnostic(*ctx)[0] == '\0')
        *bad = "FDT_ENOMEM without a diagnostic";
    fdt_close(ctx);
    if (rc != FDT_OK) {
        if (*r != NULL)
            *bad = failed;
        fdt_result_free(r);
    }
    return rc;
}

static int sc_stream(void *arg, const char **bad)
{
    stream_arg *a = arg;
    fdt_settings s;
    fdt_default_settings(&s);
    s.mode = a->cfg->mode;
    s.n_threads = a->cfg->threads;
    fdt_context *ctx = NULL;
    int rc = fdt_open(&ctx, &s);
    if (rc != FDT_OK)
        return rc;
    size_t got = 0;
    fdt_sink sink = {sizeof sink, count_sink, NULL, &got, NULL, NULL};
    fdt_result *r = NULL;
    rc = fdt_triangulate_stream(ctx, a->ps->xyz, a->ps->n, &sink, &r);
    if (stream_status(&ctx, rc, &r, "a failed fdt_triangulate_stream returned a result", bad))
        return rc;
    uint64_t h = 0;
    if (fdt_result_set_hash(r, &h) != FDT_OK || h != a->want_set || got != a->want_tets)
        *bad = "wrong streamed mesh";
    fdt_result_free(&r);
    return rc;
}

/* The streamed cells (fdt_voronoi_stream, issue 32): every point's cell
 * once, neighbours kept, the tets dropped; the volumes summed in the
 * batches' order (the same order and bits in every whole run). */
typedef struct vstream_arg {
    const ptset *ps;
    double want_sum; /* NaN: not known yet */
    double got_sum;
} vstream_arg;

static int sum_cells(void *user, const fdt_voronoi *v)
{
    double *acc = user; /* the volumes' sum, the cells */
    for (size_t i = 0; i < fdt_voronoi_num_points(v); i++)
        acc[0] += fdt_voronoi_volumes(v)[i];
    acc[1] += (double)fdt_voronoi_num_points(v);
    return 0;
}

static int sc_vstream(void *arg, const char **bad)
{
    vstream_arg *a = arg;
    fdt_settings s;
    fdt_default_settings(&s);
    s.n_threads = 1;
    fdt_context *ctx = NULL;
    int rc = fdt_open(&ctx, &s);
    if (rc != FDT_OK)
        return rc;
    double acc[2] = {0, 0};
    fdt_cell_sink cells = {sizeof cells, sum_cells, acc};
    fdt_voronoi_options o;
    fdt_default_voronoi_options(&o);
    o.neighbors = 1;
    fdt_result *r = NULL;
    rc = fdt_voronoi_stream(ctx, a->ps->xyz, a->ps->n, &o, NULL, &cells, &r);
    if (stream_status(&ctx, rc, &r, "a failed fdt_voronoi_stream returned a result", bad))
        return rc;
    a->got_sum = acc[0];
    if (acc[1] != (double)a->ps->n || (!isnan(a->want_sum) && acc[0] != a->want_sum))
        *bad = "wrong streamed cells";
    fdt_result_free(&r);
    return rc;
}

typedef struct post_arg {
    const ptset *ps;
    int neighbors;
    int what; /* 0: sort, 1: hash, 2: check, 3: faces, edges and a
                 vertex's neighbours (src/mesh/faces.c) */
    uint64_t want_hash;
} post_arg;

/* The faces, the edges and vertex 0's neighbours of r (under injection),
 * each compared with those of a result made without it; a failed call
 * must leave r able to answer once the memory is back. */
static int derived(fdt_result *r, const post_arg *a, const char **bad)
{
    size_t nf = 0, ne = 0, nv = 0;
    const fdt_vid *f = NULL, *e = NULL, *v = NULL;
    const fdt_tid *ft = NULL, *ftr = NULL;
    int rc = fdt_result_faces(r, &nf, &f, &ft);
    if (rc == FDT_OK)
        rc = fdt_result_edges(r, &ne, &e);
    if (rc == FDT_OK)
        rc = fdt_result_vertex_neighbors(r, 0, &nv, &v);
    long at = atomic_load(&fault_at);
    atomic_store(&fault_at, 0);
    fdt_result *ref = NULL;
    size_t rf = 0, re = 0, rv = 0;
    const fdt_vid *fr = NULL, *er = NULL, *vr = NULL;
    if (triangulate(a->ps, &serial_cfg, a->neighbors, &ref) != FDT_OK ||
        fdt_result_faces(ref, &rf, &fr, &ftr) != FDT_OK ||
        fdt_result_edges(ref, &re, &er) != FDT_OK ||
        fdt_result_vertex_neighbors(ref, 0, &rv, &vr) != FDT_OK) {
        *bad = "cannot make the reference faces";
    } else {
        if (rc != FDT_OK) {
            /* the memory is back: r answers now */
            if (fdt_result_faces(r, &nf, &f, &ft) != FDT_OK ||
                fdt_result_edges(r, &ne, &e) != FDT_OK ||
                fdt_result_vertex_neighbors(r, 0, &nv, &v) != FDT_OK)
                *bad = "no faces after a failed call";
        }
        if (!*bad && (nf != rf || ne != re || nv != rv || memcmp(f, fr, 3 * nf * sizeof *f) ||
                      memcmp(ft, ftr, 2 * nf * sizeof *ft) ||
                      memcmp(e, er, 2 * ne * sizeof *e) || memcmp(v, vr, nv * sizeof *v)))
            *bad = "faces, edges or neighbours differ from the reference";
    }
    fdt_result_free(&ref);
    atomic_store(&fault_at, at);
    return rc;
}

/* The dual (issue 32) under injection: the Voronoi cells on two threads
 * (their volumes' sum compared), point location and both interpolations
 * (compared with a run without injection), on a result made without it. */
typedef struct dual_arg {
    const ptset *ps;
    int what;      /* 0: cells, 1: locate, 2: linear, 3: natural */
    double *want;  /* the answer without injection */
} dual_arg;

enum { DUAL_Q = 40 };

static int dual_run(fdt_result *r, const dual_arg *a, double *got)
{
    double q[3 * DUAL_Q];
    for (int k = 0; k < DUAL_Q; k++) /* between pairs of points: inside the hull */
        for (int d = 0; d < 3; d++)
            q[3 * k + d] = 0.5 * (a->ps->xyz[3 * (size_t)(k % a->ps->n) + (size_t)d] +
                                  a->ps->xyz[3 * (size_t)((7 * k + 3) % a->ps->n) + (size_t)d]);
    if (a->what == 0) {
        fdt_voronoi_options o;
        fdt_default_voronoi_options(&o);
        o.neighbors = 1;
        o.threads = 2;
        fdt_voronoi *v = NULL;
        int rc = fdt_voronoi_compute(r, a->ps->xyz, a->ps->n, &o, &v, NULL, 0);
        got[0] = 0;
        for (size_t i = 0; rc == FDT_OK && i < a->ps->n; i++)
            got[0] += fdt_voronoi_volumes(v)[i];
        fdt_voronoi_free(&v);
        return rc;
    }
    if (a->what == 1) {
        fdt_tid t[DUAL_Q];
        int rc = fdt_locate(r, a->ps->xyz, a->ps->n, q, DUAL_Q, t, got, 2);
        return rc;
    }
    double *val = malloc(a->ps->n * sizeof *val);
    if (!val)
        return FDT_ENOMEM;
    for (size_t i = 0; i < a->ps->n; i++)
        val[i] = a->ps->xyz[3 * i] - 2 * a->ps->xyz[3 * i + 2];
    int rc = fdt_interpolate(r, a->ps->xyz, a->ps->n, val, 1, q, DUAL_Q,
                             a->what == 2 ? FDT_INTERP_LINEAR : FDT_INTERP_NATURAL, 2, got,
                             NULL, 0);
    free(val);
    return rc;
}

static int sc_dual(void *arg, const char **bad)
{
    dual_arg *a = arg;
    long at = atomic_load(&fault_at);
    atomic_store(&fault_at, 0);
    fdt_result *r = NULL;
    double got[4 * DUAL_Q];
    if (triangulate(a->ps, &serial_cfg, 0, &r) != FDT_OK) {
        *bad = "cannot make the result";
        return FDT_OK;
    }
    atomic_store(&fault_at, at);
    int rc = dual_run(r, a, got);
    atomic_store(&fault_at, 0);
    size_t m = a->what == 0 ? 1 : a->what == 1 ? 4 * DUAL_Q : DUAL_Q;
    if (rc == FDT_OK && memcmp(got, a->want, m * sizeof *got) != 0)
        *bad = "a different answer";
    fdt_result_free(&r);
    atomic_store(&fault_at, at);
    return rc;
}

/* A result made without injection, then sort/hash/check under it. */
static int sc_post(void *arg, const char **bad)
{
    post_arg *a = arg;
    long at = atomic_load(&fault_at);
    atomic_store(&fault_at, 0);
    fdt_result *r = NULL;
    if (triangulate(a->ps, &serial_cfg, a->neighbors, &r) != FDT_OK) {
        *bad = "cannot make the result";
        return FDT_OK;
    }
    atomic_store(&fault_at, at);
    int rc;
    if (a->what == 0) {
        rc = fdt_result_sort(r);
    } else if (a->what == 1) {
        uint64_t h = 0;
        rc = fdt_result_hash(r, &h);
        if (rc == FDT_OK && h != a->want_hash)
            *bad = "wrong hash";
    } else if (a->what == 3) {
        rc = derived(r, a, bad);
    } else {
        char msg[256];
        rc = fdt_check(a->ps->xyz, a->ps->n, fdt_result_tets(r),
                       fdt_result_num_tets(r),
                       fdt_result_neighbors(r), msg, sizeof msg);
        if (rc == FDT_ENOMEM && msg[0] == '\0')
            *bad = "FDT_ENOMEM from fdt_check without a message";
    }
    /* Whatever happened, the result must still be whole. */
    atomic_store(&fault_at, 0);
    uint64_t h = 0;
    if (fdt_result_hash(r, &h) != FDT_OK || h != a->want_hash)
        *bad = "the result is damaged after the failure";
    char msg[256];
    if (fdt_check(a->ps->xyz, a->ps->n, fdt_result_tets(r),
                  fdt_result_num_tets(r),
                  fdt_result_neighbors(r), msg, sizeof msg) != FDT_OK)
        *bad = "the result fails fdt_check after the failure";
    atomic_store(&fault_at, at);
    fdt_result_free(&r);
    return rc;
}

/* ------------------------------------------------------------------ */
/* Scenarios: the insertion kernel (src/mesh/insert.c)                     */
/* ------------------------------------------------------------------ */

typedef struct ins_arg {
    const double *xyz;  /* n distinct points */
    uint32_t n;
    size_t want_tets;   /* finite tets, from an uninjected build */
    uint32_t hub;       /* sc_find_face: a vertex with a star over 512 tets */
} ins_arg;

/* fdt_ins_build: FDT_ENOMEM with nothing kept, or the reference count. */
static int sc_insert(void *arg, const char **bad)
{
    ins_arg *a = arg;
    fdt_ins m;
    int rc = fdt_ins_build(&m, a->xyz, 0, a->n, NULL);
    if (rc != FDT_OK) {
        if (m.T != NULL || m.vtet != NULL)
            *bad = "a failed fdt_ins_build kept its arrays";
    } else if (m.nfinite != a->want_tets) {
        *bad = "wrong number of tets";
    }
    fdt_ins_free(&m);
    return rc;
}

/* fdt_ins_build_parallel on 2 threads (3 when the set is the uniform
 * one, so an allocation can fail on a worker thread too): FDT_ENOMEM with
 * nothing kept, or the serial build's count. */
static int sc_insert_par(void *arg, const char **bad)
{
    ins_arg *a = arg;
    fdt_ins m;
    int rc = fdt_ins_build_parallel(&m, a->xyz, 0, a->n, 3, NULL);
    if (rc != FDT_OK) {
        if (m.T != NULL || m.vtet != NULL)
            *bad = "a failed fdt_ins_build_parallel kept its arrays";
    } else if (m.nfinite != a->want_tets) {
        *bad = "wrong number of tets";
    }
    fdt_ins_free(&m);
    return rc;
}

/* fdt_ins_find_face on faces around a big star, whose search takes a heap
 * buffer: when that allocation fails it must still answer, and rightly. */
static int sc_find_face(void *arg, const char **bad)
{
    ins_arg *a = arg;
    long at = atomic_load(&fault_at);
    atomic_store(&fault_at, 0);
    fdt_ins m;
    if (fdt_ins_build(&m, a->xyz, 0, a->n, NULL) != FDT_OK) {
        *bad = "cannot build the kernel";
        return FDT_OK;
    }
    atomic_store(&fault_at, at);
    static const int face[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};
    int asked = 0;
    for (uint32_t t = fdt_ins_next_finite(&m, 0); t != FDT_NONE && asked < 6;
         t = fdt_ins_next_finite(&m, t + 1)) {
        const uint32_t *v = fdt_ins_tet(&m, t);
        for (int k = 0; k < 4 && asked < 6; k++) {
            if (v[k] == a->hub)
                continue;
            uint32_t x = v[face[k][0]], y = v[face[k][1]], z = v[face[k][2]];
            if (x != a->hub && y != a->hub && z != a->hub)
                continue;
            /* the hub first, so its star is the one searched */
            while (x != a->hub) {
                uint32_t tmp = x;
                x = y;
                y = z;
                z = tmp;
            }
            uint32_t nt, ft;
            int nk, fk;
            fdt_ins_across(&m, t, k, &nt, &nk);
            if (fdt_ins_find_face(&m, x, y, z, &ft, &fk) != 1 || ft != nt || fk != nk)
                *bad = "fdt_ins_find_face disagrees with fdt_ins_across";
            asked++;
        }
    }
    if (asked < 6)
        *bad = "too few faces around the hub";
    atomic_store(&fault_at, 0);
    fdt_ins_free(&m);
    atomic_store(&fault_at, at);
    return FDT_OK;
}

/* 600 points near a sphere and its centre, joined to every hull face:
 * a star of about 1200 tets. */
static ptset make_hub(uint64_t *rng)
{
    ptset s = {"hub", alloc_points(601), 601};
    for (size_t i = 0; i < 600; i++) {
        double z = 1.0 - (2.0 * (double)i + 1.0) / 600.0;
        double r = sqrt(1.0 - z * z), ph = 2.399963229728653 * (double)i;
        double rad = 1.0 + 1e-3 * rnd01(rng);
        s.xyz[3 * i] = rad * r * cos(ph);
        s.xyz[3 * i + 1] = rad * r * sin(ph);
        s.xyz[3 * i + 2] = rad * z;
    }
    s.xyz[1800] = s.xyz[1801] = s.xyz[1802] = 0.0;
    return s;
}

/* Every allocation of fdt_ins_build on the engine's sets (distinct points
 * only) and the hub, then the star search's. */
static void test_insert_faults(const ptset *sets, int nsets, uint64_t *rng)
{
    ptset hub = make_hub(rng);
    for (int si = 0; si <= nsets; si++) {
        const ptset *ps = si < nsets ? &sets[si] : &hub;
        /* make_lattice ends with 3 duplicates: the kernel wants distinct
         * points (fdt_ins_build refuses the others with FDT_EINVAL) */
        uint32_t n = (uint32_t)(strcmp(ps->name, "lattice") == 0 ? ps->n - 3 : ps->n);
        fdt_ins m;
        int rc = fdt_ins_build(&m, ps->xyz, 0, n, NULL);
        EXPECTF(rc == FDT_OK, "%s: reference fdt_ins_build: %s", ps->name, fdt_strerror(rc));
        if (rc != FDT_OK)
            continue;
        ins_arg ia = {ps->xyz, n, m.nfinite, n - 1};
        fdt_ins_free(&m);
        char nm[96];
        snprintf(nm, sizeof nm, "fdt_ins_build %s", ps->name);
        scenario sc = {nm, FDT_ENOMEM, sc_insert, &ia};
        inject_all(&sc);
        snprintf(nm, sizeof nm, "fdt_ins_build_parallel %s", ps->name);
        scenario sp = {nm, FDT_ENOMEM, sc_insert_par, &ia};
        inject_all(&sp);
        if (ps == &hub) {
            scenario sf = {"fdt_ins_find_face hub", FDT_ENOMEM, sc_find_face, &ia};
            inject_all(&sf);
        }
    }
    /* Enough points for the parallel build's threads to run (its first
     * BRIO round alone is serial). */
    ptset u = {"uniform 3000", alloc_points(3000), 3000};
    for (size_t i = 0; i < 3 * u.n; i++)
        u.xyz[i] = rnd01(rng);
    fdt_ins m;
    EXPECTF(fdt_ins_build(&m, u.xyz, 0, (uint32_t)u.n, NULL) == FDT_OK, "uniform 3000");
    ins_arg ua = {u.xyz, (uint32_t)u.n, m.nfinite, 0};
    fdt_ins_free(&m);
    scenario sp = {"fdt_ins_build_parallel uniform 3000", FDT_ENOMEM, sc_insert_par, &ua};
    inject_all(&sp);
    free(u.xyz);
    free(hub.xyz);
}

/* ------------------------------------------------------------------ */
/* Scenarios: readers and writers                                     */
/* ------------------------------------------------------------------ */

typedef struct read_arg {
    const char *path;
    const char *data; /* non-NULL: fdt_rd_points_mem on these bytes */
    size_t len;
    size_t want_n;
    double *want; /* 3 * want_n coordinates (read without injection) */
    int threads;  /* > 1: the sliced read, slices of a byte and up */
} read_arg;

static int sc_read(void *arg, const char **bad)
{
    read_arg *a = arg;
    double *xyz = NULL;
    size_t n = 0;
    char err[512];
    int rc = a->threads > 1
                 ? (a->data != NULL
                        ? fdt_rd_points_mem_threads(a->path, a->data, a->len, a->threads, 1,
                                                      &xyz, &n, err, sizeof err)
                        : fdt_rd_points_threads(a->path, a->threads, 1, &xyz, &n, err,
                                                  sizeof err))
             : a->data != NULL
                 ? fdt_rd_points_mem(a->path, a->data, a->len, &xyz, &n,
                                       err, sizeof err)
                 : fdt_rd_points(a->path, &xyz, &n, err, sizeof err);
    if (rc == FDT_OK && (n != a->want_n || a->want == NULL ||
                         memcmp(xyz, a->want, 3 * n * sizeof *xyz) != 0))
        *bad = "wrong points";
    if (rc != FDT_OK && (xyz != NULL || n != 0 || err[0] == '\0'))
        *bad = "failure with points left or without a message";
    if (rc == FDT_IO_ENOMEM && strstr(err, "out of memory") == NULL)
        *bad = "FDT_IO_ENOMEM without 'out of memory' in the message";
    free(xyz);
    return rc;
}

/* The reference points of a read, without injection. */
static void reference_read(read_arg *a)
{
    size_t n = 0;
    char err[512];
    int rc = a->data != NULL
                 ? fdt_rd_points_mem(a->path, a->data, a->len, &a->want, &n,
                                       err, sizeof err)
                 : fdt_rd_points(a->path, &a->want, &n, err, sizeof err);
    EXPECTF(rc == FDT_IO_OK && n == a->want_n, "%s: %s (%zu points)", a->path,
          rc == FDT_IO_OK ? "read" : err, n);
}

typedef struct write_arg {
    const ptset *ps;
    const char *dir;
    const char *ext;
    fdt_result *res; /* sorted, with neighbours */
} write_arg;

static void empty_dir(const char *dir)
{
    DIR *d = opendir(dir);
    if (d == NULL)
        return;
    struct dirent *de;
    char p[1024];
    while ((de = readdir(d)) != NULL) {
        if (strcmp(de->d_name, ".") == 0 || strcmp(de->d_name, "..") == 0)
            continue;
        snprintf(p, sizeof p, "%s/%s", dir, de->d_name);
        if (unlink(p) != 0) { /* a directory (a polyMesh): its files, then it */
            empty_dir(p);
            rmdir(p);
        }
    }
    closedir(d);
}

static int sc_write(void *arg, const char **bad)
{
    write_arg *a = arg;
    char path[1024], err[512];
    snprintf(path, sizeof path, "%s/mesh%s", a->dir, a->ext);
    fdt_mesh_view v = {
        .xyz = a->ps->xyz, .n_points = a->ps->n,
        .tets = fdt_result_tets(a->res),
        .n_tets = fdt_result_num_tets(a->res),
        .nbrs = fdt_result_neighbors(a->res),
        .hull = fdt_result_hull_faces(a->res),
        .n_hull = fdt_result_num_hull_faces(a->res),
    };
    int rc = fdt_wr_mesh(path, &v, err, sizeof err);
    int left = count_entries(a->dir);
    int want = rc != FDT_IO_OK ? 0 : strcmp(a->ext, ".ele") == 0 ? 4 : 1;
    if (left != want)
        *bad = rc != FDT_IO_OK ? "files left after a failed write"
                               : "wrong number of files after the write";
    if (rc != FDT_IO_OK && strncmp(err, a->dir, strlen(a->dir)) != 0)
        *bad = "failed write without a message naming the file";
    empty_dir(a->dir);
    return rc;
}

/* The streaming writer (src/io/write/writer_stream.c) fed the mesh in two tets
 * batches and one hull batch, then committed: a failed allocation (the
 * writer, a file's buffer, .fdtb's hull buffer) ends it with FDT_ENOMEM,
 * a message naming the file and no file left. */
static int sc_stream_write(void *arg, const char **bad)
{
    write_arg *a = arg;
    char path[1024], diag[1024] = "";
    snprintf(path, sizeof path, "%s/mesh%s", a->dir, a->ext);
    fdt_stream_writer *w = NULL;
    int rc = fdt_stream_writer_open(&w, path, NULL, a->ps->xyz, a->ps->n, 0, diag,
                                    sizeof diag);
    if (rc == FDT_OK) {
        fdt_sink sink;
        size_t t = fdt_result_num_tets(a->res);
        const fdt_vid *tets = fdt_result_tets(a->res);
        int e = fdt_stream_writer_sink(w, &sink);
        if (e == FDT_OK)
            e = sink.tets(sink.user, tets, t / 2);
        if (e == FDT_OK)
            e = sink.hull(sink.user, fdt_result_hull_faces(a->res),
                          fdt_result_num_hull_faces(a->res));
        if (e == FDT_OK)
            e = sink.tets(sink.user, tets + 4 * (t / 2), t - t / 2);
        rc = fdt_stream_writer_close(&w, 1, diag, sizeof diag);
        if (e != FDT_OK && rc != e)
            *bad = "the commit forgot a sink's error";
    }
    int left = count_entries(a->dir);
    int want = rc != FDT_OK ? 0 : strcmp(a->ext, ".ele") == 0 ? 3 : 1;
    if (left != want)
        *bad = rc != FDT_OK ? "files left after a failed write"
                            : "wrong number of files after the write";
    if (rc != FDT_OK && strncmp(diag, a->dir, strlen(a->dir)) != 0)
        *bad = "failed write without a message naming the file";
    empty_dir(a->dir);
    return rc;
}

/* ------------------------------------------------------------------ */
/* Inputs on disk                                                     */
/* ------------------------------------------------------------------ */

static int write_file(const char *path, const char *data, size_t len)
{
    FILE *f = fopen(path, "wb");
    if (f == NULL)
        return -1;
    size_t w = fwrite(data, 1, len, f);
    return (fclose(f) != 0 || w != len) ? -1 : 0;
}

/* A binary little-endian PLY with a face element (lists) before and after
 * the vertices: the header tables and list walking allocate and run. */
static size_t make_ply_le(char *buf, size_t cap)
{
    static const char hdr[] =
        "ply\nformat binary_little_endian 1.0\ncomment fault test\n"
        "element face 1\nproperty list uchar int vertex_indices\n"
        "element vertex 5\nproperty float x\nproperty double y\n"
        "property float z\nproperty uchar red\n"
        "element edge 2\nproperty int a\nproperty int b\nend_header\n";
    size_t o = sizeof hdr - 1;
    if (cap < o + 64 + 5 * 17 + 8)
        return 0;
    memcpy(buf, hdr, o);
    unsigned char three = 3;
    memcpy(buf + o++, &three, 1);
    for (int32_t i = 0; i < 3; i++, o += 4)
        memcpy(buf + o, &i, 4); /* the host is little-endian (checked) */
    static const float xs[5] = {0, 1, 0, 0, 0.25f};
    static const double ys[5] = {0, 0, 1, 0, 0.25};
    static const float zs[5] = {0, 0, 0, 1, 0.25f};
    for (int i = 0; i < 5; i++) {
        memcpy(buf + o, &xs[i], 4);
        o += 4;
        memcpy(buf + o, &ys[i], 8);
        o += 8;
        memcpy(buf + o, &zs[i], 4);
        o += 4;
        buf[o++] = 7;
    }
    memset(buf + o, 0, 16);
    return o + 16;
}

/*
 * --parallel: fdt_triangulate in the shared and message modes with 2 and 3
 * threads. The allocation order varies from run to run (threads), so the
 * k-th allocation is a different site each time; every run must still
 * either succeed with the serial answer or return FDT_ENOMEM with nothing
 * leaked and no thread left behind (a worker that fails must stop the
 * others, not leave them waiting for its messages).
 */
static int run_parallel(void)
{
    uint64_t rng = 0x9e3779b97f4a7c15u;
    ptset sets[2] = {make_lattice(&rng), make_sphere(&rng)};
    static const engine_cfg cfgs[4] = {{FDT_MODE_SHARED, 2},
                                       {FDT_MODE_SHARED, 3},
                                       {FDT_MODE_MESSAGE, 2},
                                       {FDT_MODE_MESSAGE, 3}};
    static const char *const cfg_name[4] = {"shared -t 2", "shared -t 3",
                                            "message -t 2", "message -t 3"};
    for (int si = 0; si < 2; si++) {
        for (int nb = 0; nb <= 1; nb++) {
            fdt_result *r = NULL;
            int rc = triangulate(&sets[si], &serial_cfg, nb, &r);
            EXPECTF(rc == FDT_OK, "%s: reference: %s", sets[si].name,
                  fdt_strerror(rc));
            uint64_t h = 0;
            if (rc == FDT_OK)
                EXPECTF(fdt_result_hash(r, &h) == FDT_OK, "reference hash");
            size_t nt = fdt_result_num_tets(r);
            fdt_result_free(&r);
            if (rc != FDT_OK)
                continue;
            for (int c = 0; c < 4; c++) {
                char nm[96];
                snprintf(nm, sizeof nm, "triangulate %s %s%s", sets[si].name,
                         cfg_name[c], nb ? " (nbrs)" : "");
                tri_arg ta = {&sets[si], &cfgs[c], nb, h, nt, 0};
                scenario sc = {nm, FDT_ENOMEM, sc_triangulate, &ta};
                inject_all(&sc);
            }
            if (nb)
                continue;
            /* streamed: the same mesh or a clean failure */
            rc = triangulate(&sets[si], &serial_cfg, 0, &r);
            uint64_t sh = 0;
            if (rc == FDT_OK)
                EXPECT(fdt_result_set_hash(r, &sh) == FDT_OK);
            fdt_result_free(&r);
            for (int c = 0; c < 4 && rc == FDT_OK; c++) {
                char nm[96];
                snprintf(nm, sizeof nm, "stream %s %s", sets[si].name, cfg_name[c]);
                stream_arg sa = {&sets[si], &cfgs[c], sh, nt};
                scenario sc = {nm, FDT_ENOMEM, sc_stream, &sa};
                inject_all(&sc);
            }
        }
    }
    for (int si = 0; si < 2; si++)
        free(sets[si].xyz);
    return report("parallel ");
}

/*
 * Every file of the hostile corpus (tests/bad), read without injection:
 * no request may be larger than 8 bytes per byte of the file plus 64 KiB
 * (the reader's first buffer for files of unknown size). A header that
 * declares billions of points in a few bytes must be refused before
 * anything proportional to its count is allocated.
 */
static void check_bad_sizes(const char *bad)
{
    DIR *d = opendir(bad);
    EXPECTF(d != NULL, "cannot open %s", bad);
    if (d == NULL)
        return;
    int files = 0;
    size_t worst = 0;
    struct dirent *de;
    while ((de = readdir(d)) != NULL) {
        char p[1100];
        snprintf(p, sizeof p, "%s/%s", bad, de->d_name);
        struct stat st;
        if (de->d_name[0] == '.' || stat(p, &st) != 0 || !S_ISREG(st.st_mode))
            continue;
        size_t limit = 8 * (size_t)st.st_size + 65536;
        atomic_store(&fault_max, 0);
        double *xyz = NULL;
        size_t n = 0;
        char err[512];
        fdt_rd_points(p, &xyz, &n, err, sizeof err);
        free(xyz);
        size_t got = atomic_load(&fault_max);
        EXPECTF(got <= limit, "%s (%lld bytes): an allocation of %zu bytes", p,
              (long long)st.st_size, got);
        if (got > worst)
            worst = got;
        files++;
    }
    closedir(d);
    EXPECTF(files >= 40, "only %d files in %s", files, bad);
    printf("hostile corpus: %d files read, largest allocation %zu bytes\n",
           files, worst);
}

int main(int argc, char **argv)
{
    if (argc == 2 && strcmp(argv[1], "--parallel") == 0)
        return run_parallel();
    if (argc != 3) {
        fprintf(stderr, "usage: %s GOOD_DIR BAD_DIR | --parallel\n", argv[0]);
        return 2;
    }
    const char *good = argv[1];
    check_bad_sizes(argv[2]);
    uint16_t one = 1;
    unsigned char lo;
    memcpy(&lo, &one, 1);

    char dir[] = "/tmp/fdt_test_faults.XXXXXX";
    if (mkdtemp(dir) == NULL) {
        perror("mkdtemp");
        return 1;
    }
    char outdir[1100];
    snprintf(outdir, sizeof outdir, "%s/out", dir);
    if (mkdir(outdir, 0700) != 0) {
        perror("mkdir");
        return 1;
    }

    /* --- readers --- */
    char p_xyz[1100], p_node[1100], p_aply[1100], p_bply[1100];
    snprintf(p_xyz, sizeof p_xyz, "%s/long.xyz", dir);
    snprintf(p_node, sizeof p_node, "%s/attr.node", dir);
    snprintf(p_aply, sizeof p_aply, "%s/ascii.ply", dir);
    snprintf(p_bply, sizeof p_bply, "%s/bin.ply", dir);
    /* A literal longer than the reader's stack buffer: its heap copy. */
    char longlit[400];
    memset(longlit, 0, sizeof longlit);
    strcpy(longlit, "0.");
    memset(longlit + 2, '3', 300);
    char xyz_text[1024];
    int xl = snprintf(xyz_text, sizeof xyz_text,
                      "# x y z\n0 0 0\n1,0,0\n0 1 0\n0 0 %s\n1e-3 2E+1 -0.5\n",
                      longlit);
    static const char node_text[] = "5 3 1 1\n1 0 0 0 0.5 1\n2 1 0 0 0.5 0\n"
                                    "3 0 1 0 nan 1\n4 0 0 1 0.5 0\n"
                                    "5 .5 .5 .5 1 1\n";
    static const char aply_text[] =
        "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\n"
        "property double y\nproperty double z\nproperty float nx\n"
        "element face 1\nproperty list uchar int vertex_indices\n"
        "end_header\n0 0 0 nan\n1 0 0 1\n0 1 0 1\n0 0 1 1\n3 0 1 2\n";
    char bply[512];
    size_t bl = make_ply_le(bply, sizeof bply);
    EXPECTF(write_file(p_xyz, xyz_text, (size_t)xl) == 0, "write %s", p_xyz);
    EXPECTF(write_file(p_node, node_text, sizeof node_text - 1) == 0, "node");
    EXPECTF(write_file(p_aply, aply_text, sizeof aply_text - 1) == 0, "aply");
    EXPECTF(lo == 1 && bl > 0 && write_file(p_bply, bply, bl) == 0, "bply");

    read_arg reads[] = {
        {p_xyz, NULL, 0, 5, NULL, 1},
        {p_node, NULL, 0, 5, NULL, 1},
        {p_aply, NULL, 0, 4, NULL, 1},
        {p_bply, NULL, 0, 5, NULL, 1},
        {"mem.xyz", xyz_text, (size_t)xl, 5, NULL, 1},
        {"mem.ply", bply, bl, 5, NULL, 1},
        {p_xyz, NULL, 0, 5, NULL, 3},
        {"mem.xyz", xyz_text, (size_t)xl, 5, NULL, 4},
    };
    static const char *const reads_name[] = {
        "read .xyz (long literal)", "read .node (attributes)",
        "read ascii .ply (lists)", "read binary .ply (lists)",
        "read_mem .xyz", "read_mem binary .ply",
        "read .xyz in 3 slices", "read_mem .xyz in 4 slices"};
    for (size_t i = 0; i < sizeof reads / sizeof reads[0]; i++) {
        reference_read(&reads[i]);
        scenario sc = {reads_name[i], FDT_IO_ENOMEM, sc_read, &reads[i]};
        inject_all(&sc);
        free(reads[i].want);
    }
    /* Every sample in tests/good (10 points each). */
    DIR *d = opendir(good);
    EXPECTF(d != NULL, "cannot open %s", good);
    int ngood = 0;
    if (d != NULL) {
        struct dirent *de;
        while ((de = readdir(d)) != NULL) {
            if (de->d_name[0] == '.' || strcmp(de->d_name, "EXPECTED.txt") == 0)
                continue;
            char p[1100], nm[300];
            snprintf(p, sizeof p, "%s/%s", good, de->d_name);
            snprintf(nm, sizeof nm, "read good/%s", de->d_name);
            read_arg ra = {p, NULL, 0, 10, NULL, 1};
            reference_read(&ra);
            scenario sc = {nm, FDT_IO_ENOMEM, sc_read, &ra};
            inject_all(&sc);
            free(ra.want);
            ngood++;
        }
        closedir(d);
    }
    EXPECTF(ngood >= 5, "only %d samples in %s", ngood, good);

    /* --- the engine --- */
    uint64_t rng = 0x9e3779b97f4a7c15u;
    ptset sets[3] = {make_lattice(&rng), make_skew_lines(&rng),
                     make_sphere(&rng)};
    for (int si = 0; si < 3; si++) {
        const ptset *ps = &sets[si];
        for (int nb = 0; nb <= 1; nb++) {
            fdt_result *r = NULL;
            int rc = triangulate(ps, &serial_cfg, nb, &r);
            EXPECTF(rc == FDT_OK, "%s: reference triangulation: %s", ps->name,
                  fdt_strerror(rc));
            if (rc != FDT_OK)
                continue;
            uint64_t h = 0;
            EXPECTF(fdt_result_hash(r, &h) == FDT_OK, "reference hash");
            size_t nt = fdt_result_num_tets(r);
            fdt_result_free(&r);

            static const char *const what[5] = {"triangulate", "result_sort",
                                                "result_hash", "check", "faces"};
            char nm[5][96];
            for (int w = 0; w < 5; w++)
                snprintf(nm[w], sizeof nm[w], "%s %s%s", what[w], ps->name,
                         nb ? " (nbrs)" : "");
            tri_arg ta = {ps, &serial_cfg, nb, h, nt, 0};
            scenario sc = {nm[0], FDT_ENOMEM, sc_triangulate, &ta};
            inject_all(&sc);
            if (!nb) {
                /* streamed: the same mesh or a clean failure */
                uint64_t sh = 0;
                CHECK_EQ(triangulate(ps, &serial_cfg, 0, &r), FDT_OK);
                EXPECT(fdt_result_set_hash(r, &sh) == FDT_OK);
                fdt_result_free(&r);
                char snm[96];
                snprintf(snm, sizeof snm, "stream %s", ps->name);
                stream_arg sa = {ps, &serial_cfg, sh, nt};
                scenario ss = {snm, FDT_ENOMEM, sc_stream, &sa};
                inject_all(&ss);
                if (si != 1) {
                    /* the reference: a run with no failure */
                    vstream_arg va = {ps, NAN, 0};
                    const char *vbad = NULL;
                    EXPECTF(sc_vstream(&va, &vbad) == FDT_OK && !vbad, "voronoi stream %s: "
                            "reference", ps->name);
                    va.want_sum = va.got_sum;
                    snprintf(snm, sizeof snm, "voronoi stream %s", ps->name);
                    scenario sv = {snm, FDT_ENOMEM, sc_vstream, &va};
                    inject_all(&sv);
                }
            }
            for (int w = 0; w < 4; w++) {
                post_arg pa = {ps, nb, w, h};
                scenario post = {nm[w + 1], FDT_ENOMEM, sc_post, &pa};
                inject_all(&post);
            }
            /* periodic (the lattice set wrapped into the unit box, its
             * duplicates merged): x y z, and x z (a wall of points at
             * y = 0 and y = 1 keeps the ends flat) */
            for (int pa_i = 0; pa_i < 2 && !nb && si == 0; pa_i++) {
                ptset w = {"wrapped", alloc_points(ps->n + 32), ps->n + 32};
                uint64_t wr = 77;
                for (size_t i = 0; i < ps->n; i++)
                    for (int k = 0; k < 3; k++) {
                        double v = ps->xyz[3 * i + k] / 2.0;
                        w.xyz[3 * i + k] = v - floor(v);
                    }
                for (size_t i = ps->n; i < w.n; i++) {
                    w.xyz[3 * i] = rnd01(&wr);
                    w.xyz[3 * i + 1] = i % 2 ? 0.0 : 0.9999;
                    w.xyz[3 * i + 2] = rnd01(&wr);
                }
                for (size_t i = 0; i < ps->n; i++) /* the walls bound y */
                    w.xyz[3 * i + 1] = 0.0001 + 0.999 * w.xyz[3 * i + 1];
                static const engine_cfg two = {FDT_MODE_AUTO, 2};
                tri_arg pa = {&w, &serial_cfg, 0, 0, 0, pa_i ? 5u : 7u};
                fdt_result *pr = NULL;
                CHECK_EQ(triangulate_p(&w, &serial_cfg, 0, pa.periodic, &pr), FDT_OK);
                EXPECT(fdt_result_hash(pr, &pa.want_hash) == FDT_OK);
                pa.want_tets = fdt_result_num_tets(pr);
                fdt_result_free(&pr);
                char pn[96];
                snprintf(pn, sizeof pn, "periodic %s %s", pa_i ? "x z" : "x y z", ps->name);
                scenario sp = {pn, FDT_ENOMEM, sc_triangulate, &pa};
                inject_all(&sp);
                pa.cfg = &two;
                snprintf(pn, sizeof pn, "periodic %s %s 2 threads", pa_i ? "x z" : "x y z",
                         ps->name);
                inject_all(&sp);
                /* the periodic cells (the walls cut the x z set's) and the
                 * outputs with offsets or image vertices */
                CHECK_EQ(triangulate_p(&w, &serial_cfg, 0, pa.periodic, &pr), FDT_OK);
                pcells_arg ca = {pr, &w, NAN};
                const char *cbad = NULL;
                EXPECT(sc_pcells(&ca, &cbad) == FDT_OK && !cbad);
                snprintf(pn, sizeof pn, "periodic cells %s %s", pa_i ? "x z" : "x y z",
                         ps->name);
                scenario sv = {pn, FDT_ENOMEM, sc_pcells, &ca};
                inject_all(&sv);
                pwrite_arg ka = {pr, &w, outdir, "", 1};
                snprintf(pn, sizeof pn, "periodic check %s %s", pa_i ? "x z" : "x y z", ps->name);
                scenario sk = {pn, FDT_ENOMEM, sc_pcheck, &ka};
                inject_all(&sk);
                pstream_arg sa = {&w, pa.periodic, outdir, pa.want_hash};
                snprintf(pn, sizeof pn, "periodic stream %s %s", pa_i ? "x z" : "x y z",
                         ps->name);
                scenario ss = {pn, FDT_ENOMEM, sc_pstream, &sa};
                inject_all(&ss);
                static const char *const pext[5] = {".fdtb", ".vtu", ".msh", ".ele", "polyMesh"};
                static const int pfiles[5] = {1, 1, 1, 4, 1};
                for (int e = 0; e < 5 && pa_i; e++) {
                    pwrite_arg wa = {pr, &w, outdir, pext[e], pfiles[e]};
                    snprintf(pn, sizeof pn, "periodic write %s %s", pext[e], ps->name);
                    scenario sw = {pn, FDT_ENOMEM, sc_pwrite, &wa};
                    inject_all(&sw);
                }
                CHECK_EQ(fdt_result_sort(pr), FDT_OK);
                pdual_arg pda = {pr, &w, {0, 0, 0}};
                EXPECT(sc_pdual(&pda, &cbad) == FDT_OK && !cbad);
                snprintf(pn, sizeof pn, "periodic dual %s %s", pa_i ? "x z" : "x y z", ps->name);
                scenario sdu = {pn, FDT_ENOMEM, sc_pdual, &pda};
                inject_all(&sdu);
                fdt_result_free(&pr);
                free(w.xyz);
            }
            /* the dual: neighbours derived (the longer path), two sets */
            static const char *const dual_what[4] = {"voronoi", "locate", "interpolate linear",
                                                     "interpolate natural"};
            for (int w = 0; w < 4 && !nb && si != 1; w++) {
                char dn[96];
                double want[4 * DUAL_Q];
                dual_arg da = {ps, w, want};
                CHECK_EQ(triangulate(ps, &serial_cfg, 0, &r), FDT_OK);
                EXPECTF(dual_run(r, &da, want) == FDT_OK, "%s: reference", dual_what[w]);
                fdt_result_free(&r);
                snprintf(dn, sizeof dn, "%s %s", dual_what[w], ps->name);
                scenario sd = {dn, FDT_ENOMEM, sc_dual, &da};
                inject_all(&sd);
            }
            if (!nb && si != 1) { /* the polyhedral dual (--dual), clipped by the box */
                char dn[96];
                CHECK_EQ(triangulate(ps, &serial_cfg, 0, &r), FDT_OK);
                CHECK_EQ(fdt_result_sort(r), FDT_OK);
                pdual_arg pda = {r, ps, {0, 0, 0}};
                const char *dbad = NULL;
                EXPECT(sc_pdual(&pda, &dbad) == FDT_OK && !dbad);
                snprintf(dn, sizeof dn, "dual polyMesh %s", ps->name);
                scenario sd = {dn, FDT_ENOMEM, sc_pdual, &pda};
                inject_all(&sd);
                fdt_result_free(&r);
            }
        }
    }

    /* --- the insertion kernel --- */
    test_insert_faults(sets, 3, &rng);

    /* --- writers --- */
    fdt_result *r = NULL;
    int rc = triangulate(&sets[0], &serial_cfg, 1, &r);
    EXPECTF(rc == FDT_OK && fdt_result_sort(r) == FDT_OK, "mesh for writing");
    if (rc == FDT_OK) {
        static const char *const exts[4] = {".tets", ".ele", ".vtu", ".vtk"};
        for (int i = 0; i < 4; i++) {
            char nm[64];
            snprintf(nm, sizeof nm, "write %s", exts[i]);
            write_arg wa = {&sets[0], outdir, exts[i], r};
            scenario sc = {nm, FDT_IO_ENOMEM, sc_write, &wa};
            inject_all(&sc);
        }
        static const char *const sexts[3] = {".fdtb", ".vtu", ".ele"};
        for (int i = 0; i < 3; i++) {
            char nm[64];
            snprintf(nm, sizeof nm, "stream write %s", sexts[i]);
            write_arg wa = {&sets[0], outdir, sexts[i], r};
            scenario sc = {nm, FDT_ENOMEM, sc_stream_write, &wa};
            inject_all(&sc);
        }
    }
    fdt_result_free(&r);
    for (int si = 0; si < 3; si++)
        free(sets[si].xyz);

    empty_dir(outdir);
    rmdir(outdir);
    empty_dir(dir);
    rmdir(dir);
    return report("");
}
