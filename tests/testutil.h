/*
 * The helpers every C test shares (issue 20: one CHECK for all).
 * - CHECK and CHECK_EQ end the test at once with the file, line and
 *   failing expression (and both values for CHECK_EQ): for a state the
 *   rest of the test cannot go on from.
 * - EXPECT(cond) and EXPECTF(cond, fmt, ...) record a failure (printed
 *   with file, line and expression, EXPECTF adding a printf message) and
 *   go on, so one run shows every failing case; test_report(name) at the
 *   end of main prints the tally and gives the exit status. Only the first
 *   TEST_PRINT_LIMIT failures are printed, all are counted.
 * - test_note_failure() counts a failure a test prints itself (a point
 *   set, a matrix) and says whether it is still within the print limit.
 * - test_triangulate is fdt_triangulate with the settings a test names
 *   (threads, neighbours), any failure ending the test; test_whole_cells
 *   the cells of its mesh.
 * - now_s is a monotonic clock for watchdogs and timings; test_rand64 and
 *   test_unif a deterministic random stream for inputs.
 * - test_slurp_stream and test_slurp read a stream or a file whole.
 */
#ifndef FDT_TESTUTIL_H
#define FDT_TESTUTIL_H

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "base/hash.h"
#include "frontdt.h"

#define CHECK(cond)                                                          \
    do {                                                                     \
        if (!(cond)) {                                                       \
            fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, \
                    #cond);                                                  \
            exit(1);                                                         \
        }                                                                    \
    } while (0)

#define CHECK_EQ(a, b)                                                       \
    do {                                                                     \
        long long va_ = (long long)(a), vb_ = (long long)(b);                \
        if (va_ != vb_) {                                                    \
            fprintf(stderr, "%s:%d: check failed: %s == %s (%lld != %lld)\n", \
                    __FILE__, __LINE__, #a, #b, va_, vb_);                   \
            exit(1);                                                         \
        }                                                                    \
    } while (0)

#define TEST_PRINT_LIMIT 50

/* The tally of EXPECT checks and failures of this test program. A static
 * inside a static inline function: one per program, no unused-variable
 * warning in tests that use only CHECK. */
typedef struct test_tally {
    long checks;
    long failures;
} test_tally;

static inline test_tally *test_tally_(void)
{
    static test_tally t;
    return &t;
}

/* Counts checks made without EXPECT (a test that compares several
 * answers at once). */
static inline void test_count_checks(long n) { test_tally_()->checks += n; }
static inline long test_failures(void) { return test_tally_()->failures; }

/* Counts one failure; nonzero while it should still be printed. */
static inline int test_note_failure(void)
{
    return ++test_tally_()->failures <= TEST_PRINT_LIMIT;
}

/* Counts a failure and prints "FILE:LINE: check failed: COND: MESSAGE"
 * (COND and MESSAGE each may be NULL) while within the print limit. */
static inline void test_failv_(const char *file, int line, const char *cond, const char *fmt,
                               va_list ap)
{
    if (!test_note_failure())
        return;
    fprintf(stderr, "%s:%d: check failed", file, line);
    if (cond)
        fprintf(stderr, ": %s", cond);
    if (fmt) {
        fputs(": ", stderr);
        vfprintf(stderr, fmt, ap);
    }
    fputc('\n', stderr);
}

#if defined(__GNUC__)
__attribute__((format(printf, 4, 5)))
#endif
static inline void test_fail_(const char *file, int line, const char *cond, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    test_failv_(file, line, cond, fmt, ap);
    va_end(ap);
}

#define EXPECT(cond)                                                         \
    do {                                                                     \
        test_tally_()->checks++;                                             \
        if (!(cond))                                                         \
            test_fail_(__FILE__, __LINE__, #cond, NULL);                     \
    } while (0)

#define EXPECTF(cond, ...)                                                   \
    do {                                                                     \
        test_tally_()->checks++;                                             \
        if (!(cond))                                                         \
            test_fail_(__FILE__, __LINE__, #cond, __VA_ARGS__);              \
    } while (0)

/* The end of main: the tally on stdout (failures on stderr); the exit
 * status, 1 if any EXPECT failed. */
static inline int test_report(const char *name)
{
    const test_tally *t = test_tally_();
    if (t->failures) {
        fprintf(stderr, "%s: %ld of %ld checks failed\n", name, t->failures, t->checks);
        return 1;
    }
    if (t->checks)
        printf("%s: %ld checks passed\n", name, t->checks);
    else
        printf("%s: passed\n", name);
    return 0;
}

/* splitmix64: a deterministic stream for test inputs, the same everywhere;
 * state *s, any start value. */
static inline uint64_t test_rand64(uint64_t *s)
{
    return fdt_splitmix64(s);
}

/* Uniform in [0, 1), 53 bits. */
static inline double test_unif(uint64_t *s)
{
    return (double)(test_rand64(s) >> 11) * 0x1.0p-53;
}

/* n points (3 doubles each, malloc'd: the caller frees them) from seed:
 * uniform in the unit cube (clustered 0), or 8 tight clusters (0.05 wide;
 * 1e-3 for clustered 2, whose Voronoi cells are needles and slivers beside
 * the background's) and a uniform background: the Voronoi and dual tests'
 * clouds. */
static inline double *test_cloud(size_t n, int clustered, uint64_t seed)
{
    double *xyz = malloc(3 * (n ? n : 1) * sizeof *xyz);
    CHECK(xyz);
    uint64_t s = seed;
    for (size_t i = 0; i < n; i++) {
        int c = clustered ? (int)(test_rand64(&s) % 10) : 9;
        double wd = clustered == 2 ? 1e-3 : 0.05;
        for (int d = 0; d < 3; d++) {
            double u = test_unif(&s);
            xyz[3 * i + d] = c < 8 ? 0.2 + 0.6 * ((c >> d) & 1) + wd * (u - 0.5) : u;
        }
    }
    return xyz;
}

/* The periodic mesh of xyz (settings.periodic axes, periodic_box box), by
 * default settings; any failure ends the test. */
static inline fdt_result *test_periodic_mesh(const double *xyz, size_t n, unsigned axes,
                                             const double box[6])
{
    fdt_settings s;
    fdt_default_settings(&s);
    s.periodic = axes;
    memcpy(s.periodic_box, box, sizeof s.periodic_box);
    fdt_context *ctx = NULL;
    fdt_result *r = NULL;
    CHECK(fdt_open(&ctx, &s) == FDT_OK);
    CHECK(fdt_triangulate(ctx, xyz, n, &r) == FDT_OK);
    fdt_close(&ctx);
    return r;
}

/* The mesh of xyz on `threads` threads (1: serial mode), with the tets'
 * neighbours when `neighbors`; any failure ends the test. */
static inline fdt_result *test_triangulate(const double *xyz, size_t n, int threads,
                                           int neighbors)
{
    fdt_settings s;
    fdt_default_settings(&s);
    s.mode = threads == 1 ? FDT_MODE_SERIAL : FDT_MODE_AUTO;
    s.n_threads = threads;
    s.neighbors = neighbors;
    fdt_context *ctx = NULL;
    fdt_result *r = NULL;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    CHECK_EQ(fdt_triangulate(ctx, xyz, n, &r), FDT_OK);
    fdt_close(&ctx);
    return r;
}

/* The Voronoi cells of xyz (fdt_voronoi_compute, neighbours kept, one
 * thread, in the points' bounding box) from *r, their mesh on one thread;
 * NULL, with *r freed, when the cells are refused. */
static inline fdt_voronoi *test_whole_cells(const double *xyz, size_t n, fdt_result **r)
{
    *r = test_triangulate(xyz, n, 1, 0);
    fdt_voronoi_options o;
    fdt_default_voronoi_options(&o);
    o.neighbors = 1;
    o.threads = 1;
    fdt_voronoi *v = NULL;
    char diag[512];
    int err = fdt_voronoi_compute(*r, xyz, n, &o, &v, diag, sizeof diag);
    if (err != FDT_OK) {
        fdt_result_free(r);
        return NULL;
    }
    return v;
}

/* Reads "x y z" lines (what tests/gen_points writes, %.17g: exact) into
 * a new array; *n the points. */
static inline double *test_read_xyz(const char *path, size_t *n)
{
    FILE *f = fopen(path, "r");
    CHECK(f != NULL);
    size_t cap = 1024, c = 0;
    double *p = malloc(cap * 3 * sizeof *p);
    CHECK(p != NULL);
    double x, y, z;
    while (fscanf(f, "%lf %lf %lf", &x, &y, &z) == 3) {
        if (c == cap) {
            cap *= 2;
            p = realloc(p, cap * 3 * sizeof *p);
            CHECK(p != NULL);
        }
        p[3 * c] = x;
        p[3 * c + 1] = y;
        p[3 * c + 2] = z;
        c++;
    }
    fclose(f);
    *n = c;
    return p;
}

/* n scaled by FDT_TEST_SIZE_SCALE (a factor in (0, 1]; unset: 1), at
 * least 100 points: .ci/run's ThreadSanitizer step halves the generated
 * families, whose races do not need the size and whose instrumented
 * runs took most of its 13 minutes (cellstream 397 s, insert_parallel
 * 355 s on 2 cores). */
static inline size_t test_size(size_t n)
{
    const char *e = getenv("FDT_TEST_SIZE_SCALE");
    double s = e && *e ? atof(e) : 1.0;
    if (!(s > 0.0 && s <= 1.0) || n <= 100)
        return n;
    size_t m = (size_t)((double)n * s);
    return m < 100 ? 100 : m;
}

/* n points (test_size(n)) of tests/gen_points family fam (gen: its path)
 * with seed, read back through a temporary file; *got the points. */
static inline double *test_gen_family(const char *gen, const char *fam, size_t n, int seed,
                                      size_t *got)
{
    n = test_size(n);
    char tmp[] = "/tmp/fdt_test_family.XXXXXX";
    int fd = mkstemp(tmp);
    CHECK(fd >= 0);
    close(fd);
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "'%s' %s %zu %d %s", gen, fam, n, seed, tmp);
    CHECK(system(cmd) == 0);
    double *p = test_read_xyz(tmp, got);
    unlink(tmp);
    return p;
}

/* fn(gen, family, n) for every family `gen --list` names; how many (a
 * test expects the list it knows, e.g. more than 30). */
static inline int test_each_family(const char *gen, size_t n,
                                   void (*fn)(const char *, const char *, size_t))
{
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "'%s' --list", gen);
    FILE *f = popen(cmd, "r");
    CHECK(f != NULL);
    char fam[64];
    int families = 0;
    while (fscanf(f, "%63s", fam) == 1) {
        fn(gen, fam, n);
        families++;
    }
    pclose(f);
    return families;
}

/* A shuffled copy of the n points xyz: row i is point (*perm)[i] (perm
 * a new array, Fisher-Yates from seed). */
static inline double *test_shuffle(const double *xyz, size_t n, uint64_t seed, size_t **perm)
{
    double *y = malloc(3 * (n ? n : 1) * sizeof *y);
    size_t *p = malloc((n ? n : 1) * sizeof *p);
    CHECK(y && p);
    for (size_t i = 0; i < n; i++)
        p[i] = i;
    for (size_t i = n ? n - 1 : 0; i > 0; i--) {
        size_t j = (size_t)(test_rand64(&seed) % (i + 1)), t = p[i];
        p[i] = p[j];
        p[j] = t;
    }
    for (size_t i = 0; i < n; i++)
        memcpy(y + 3 * i, xyz + 3 * p[i], 3 * sizeof *y);
    *perm = p;
    return y;
}

/* The rest of stream f, from where it stands to its end, in a new
 * NUL-terminated string; *len (when len is not NULL) its bytes. */
static inline char *test_slurp_stream(FILE *f, size_t *len)
{
    size_t cap = 1 << 16, n = 0;
    char *buf = malloc(cap + 1);
    CHECK(buf != NULL);
    for (size_t k = 1; k > 0; n += k) {
        if (n == cap) {
            cap *= 2;
            buf = realloc(buf, cap + 1);
            CHECK(buf != NULL);
        }
        k = fread(buf + n, 1, cap - n, f);
    }
    buf[n] = '\0';
    if (len)
        *len = n;
    return buf;
}

/* The file at path whole (test_slurp_stream), or NULL when it cannot be
 * opened. */
static inline char *test_slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    char *buf = test_slurp_stream(f, len);
    fclose(f);
    return buf;
}

static inline double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#endif
