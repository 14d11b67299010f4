/*
 * Hardware and threads of the parallel engine (src/par/threads.c), through the
 * public API:
 * - the default thread count: hwloc's cores (a synthetic topology set by
 *   HWLOC_SYNTHETIC stands in for the machine: 3 cores, and 2,000 cores
 *   clamped to 1,024), else the online CPUs; n_threads 0 runs that many;
 * - pinning: on this machine bound or refused (either way the same mesh);
 *   bound on a synthetic two-node topology (the memory-binding path);
 *   refused when the topology's cores are processors this machine lacks
 *   (pinned -1, no thread on a core, the same mesh);
 * - progress while the workers run, in both modes: fractions in
 *   [0, 0.99] that never go back, then the library's 1, the mesh
 *   unchanged; a callback that cancels stops the run
 *   with FDT_ECANCELED and no result, in both modes.
 * Built with -DTEST_HWLOC when the library has hwloc.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "frontdt.h"
#include "par/parallel.h"
#include "par/threads.h"
#include "testutil.h"

static double *uniform(size_t n, uint64_t seed)
{
    double *p = malloc(3 * n * sizeof *p);
    CHECK(p != NULL);
    for (size_t i = 0; i < 3 * n; i++)
        p[i] = test_unif(&seed);
    return p;
}

/* Triangulates; returns the error, the hash and stats through *h, *st
 * and, for thread i < 8, its core in core[i]. */
typedef struct outcome {
    int err;
    uint64_t hash;
    fdt_stats st;
    int core[8];
} outcome;

static outcome run(const double *p, size_t n, fdt_mode mode, int nthreads, int pin,
                   fdt_progress_fn progress, void *user)
{
    outcome o;
    memset(&o, 0, sizeof o);
    fdt_settings s;
    fdt_default_settings(&s);
    s.mode = mode;
    s.n_threads = nthreads;
    s.pin = pin;
    s.progress = progress;
    s.progress_user = user;
    fdt_context *ctx = NULL;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    fdt_result *r = (fdt_result *)ctx; /* must be set to NULL on failure */
    o.err = fdt_triangulate(ctx, p, n, &r);
    if (o.err == FDT_OK) {
        CHECK_EQ(fdt_result_hash(r, &o.hash), FDT_OK);
        CHECK_EQ(fdt_result_stats(r, &o.st), FDT_OK);
        for (int i = 0; i < 8 && i < o.st.threads; i++) {
            fdt_thread_stats ts;
            CHECK_EQ(fdt_result_thread_stats(r, i, &ts), FDT_OK);
            o.core[i] = ts.core;
        }
        fdt_result_free(&r);
    } else {
        CHECK(r == NULL);
    }
    fdt_close(&ctx);
    return o;
}

static void test_default_threads(const double *p, size_t n, uint64_t ref)
{
    long online = sysconf(_SC_NPROCESSORS_ONLN);
    int d = fdt_threads_default();
    EXPECT(d >= 1 && d <= 1024 && d <= (online > 1 ? online : 1));
#ifdef TEST_HWLOC
    setenv("HWLOC_SYNTHETIC", "core:3 pu:1", 1);
    EXPECT(fdt_threads_default() == 3);
    /* n_threads 0: that many, in either mode, the same mesh */
    for (int m = FDT_MODE_SHARED; m <= FDT_MODE_MESSAGE; m++) {
        outcome o = run(p, n, (fdt_mode)m, 0, 0, NULL, NULL);
        EXPECT(o.err == FDT_OK && o.st.threads == 3 && o.hash == ref);
    }
    setenv("HWLOC_SYNTHETIC", "core:2000 pu:1", 1);
    EXPECT(fdt_threads_default() == 1024);
    unsetenv("HWLOC_SYNTHETIC");
#else
    (void)p;
    (void)n;
    (void)ref;
    EXPECT(d == (online < 1 ? 1 : online > 1024 ? 1024 : online));
#endif
    printf("default threads: %d here\n", d);
}

static void test_pinning(const double *p, size_t n, uint64_t ref)
{
    /* this machine: bound (each thread on a core) or refused */
    outcome o = run(p, n, FDT_MODE_SHARED, 3, 1, NULL, NULL);
    EXPECT(o.err == FDT_OK && o.hash == ref);
    EXPECT(o.st.pinned == 1 || o.st.pinned == -1);
    if (o.st.pinned == 1)
        for (int i = 0; i < 3; i++)
            EXPECTF(o.core[i] >= 0, "thread %d on a core", i);
    printf("pin: %s\n", o.st.pinned == 1 ? "threads bound to cores" : "binding refused, ran unpinned");
    /* unpinned: no thread on a core */
    o = run(p, n, FDT_MODE_MESSAGE, 2, 0, NULL, NULL);
    EXPECT(o.err == FDT_OK && o.st.pinned == 0 && o.core[0] == -1 && o.core[1] == -1);
#ifdef TEST_HWLOC
    /* a synthetic topology of two memory nodes (not this system: hwloc
     * accepts every binding): threads on cores id mod 4, memory moved */
    setenv("HWLOC_SYNTHETIC", "numa:2 core:2 pu:1", 1);
    o = run(p, n, FDT_MODE_SHARED, 5, 1, NULL, NULL);
    EXPECT(o.err == FDT_OK && o.hash == ref && o.st.pinned == 1);
    for (int i = 0; i < 5; i++)
        EXPECTF(o.core[i] == i % 4, "thread %d on core %d", i, o.core[i]);
    /* the same topology declared this system, its processors numbered
     * beyond any machine's: every binding refused, the run goes on */
    setenv("HWLOC_SYNTHETIC", "numa:2 core:2 pu:1(indexes=4000,4001,4002,4003)", 1);
    setenv("HWLOC_THISSYSTEM", "1", 1);
    for (int m = FDT_MODE_SHARED; m <= FDT_MODE_MESSAGE; m++) {
        o = run(p, n, (fdt_mode)m, 3, 1, NULL, NULL);
        EXPECT(o.err == FDT_OK && o.hash == ref && o.st.pinned == -1);
        for (int i = 0; i < 3; i++)
            EXPECTF(o.core[i] == -1, "thread %d refused, core %d", i, o.core[i]);
    }
    unsetenv("HWLOC_THISSYSTEM");
    unsetenv("HWLOC_SYNTHETIC");
#endif
}

/* Records every fraction reported; cancels at report `cancel_at` (0:
 * never). */
typedef struct reports {
    int calls, cancel_at, bad;
    double last;
} reports;

/* While the workers run: in [0, 0.99] and never back (tets only add up);
 * the library's final report is 1. */
static int record(void *user, double f)
{
    reports *r = user;
    r->calls++;
    if (!(f >= 0 && (f <= 0.99 || f == 1.0) && f >= r->last))
        r->bad++;
    r->last = f;
    return r->cancel_at && r->calls >= r->cancel_at;
}

/* Progress: the calling thread reports every 50 ms while the workers run.
 * 150,000 points take longer than that on every thread count here. */
static void test_progress(void)
{
    size_t n = 150000;
    double *p = uniform(n, 31);
    outcome serial = run(p, n, FDT_MODE_SERIAL, 1, 0, NULL, NULL);
    CHECK_EQ(serial.err, FDT_OK);
    for (int m = FDT_MODE_SHARED; m <= FDT_MODE_MESSAGE; m++) {
        reports r = {0, 0, 0, 0};
        outcome o = run(p, n, (fdt_mode)m, 2, 0, record, &r);
        EXPECT(o.err == FDT_OK && o.hash == serial.hash);
        EXPECTF(r.calls >= 2 && r.bad == 0 && r.last == 1.0,
                "mode %d: %d reports, %d out of [0, 0.99] or back, last %g", m, r.calls, r.bad,
                r.last);
        printf("progress, mode %d: %d reports, last %.2f\n", m, r.calls, r.last);
    }
    free(p);
}

/* Cancellation of a parallel run, in both modes: the first report (after
 * 50 ms) cancels. 400,000 points take seconds on every thread count here,
 * so the run cannot finish first: FDT_OK would mean the callback's answer
 * was ignored. */
static void test_cancel(void)
{
    size_t n = 400000;
    double *p = uniform(n, 11);
    for (int m = FDT_MODE_SHARED; m <= FDT_MODE_MESSAGE; m++) {
        reports r = {0, 1, 0, 0};
        double t0 = now_s();
        outcome o = run(p, n, (fdt_mode)m, 3, 0, record, &r);
        double dt = now_s() - t0;
        EXPECT(o.err == FDT_ECANCELED);
        EXPECT(r.calls >= 1); /* reports go on until the workers stop */
        printf("cancel: progress callback stops a mode %d run after %.2f s\n", m, dt);
    }
    free(p);
}

int main(void)
{
    setvbuf(stdout, NULL, _IOLBF, 0);
    /* A lost wakeup or a deadlock must fail, not hang. */
    alarm(1200);
    size_t n = 3000;
    double *p = uniform(n, 3);
    outcome serial = run(p, n, FDT_MODE_SERIAL, 1, 0, NULL, NULL);
    CHECK_EQ(serial.err, FDT_OK);
    test_default_threads(p, n, serial.hash);
    test_pinning(p, n, serial.hash);
    free(p);
    test_progress();
    test_cancel();
    return test_report("threads");
}
