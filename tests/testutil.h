/*
 * Helpers shared by the threaded tests (tests/test_mailbox.c,
 * tests/test_parallel.c): CHECK and CHECK_EQ end the test with the file,
 * line and failing expression (and both values for CHECK_EQ); now_s is a
 * monotonic clock for watchdogs and timings; test_rand64 and test_unif a
 * deterministic random stream for inputs.
 */
#ifndef FDT_TESTUTIL_H
#define FDT_TESTUTIL_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

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

/* splitmix64: a deterministic stream for test inputs, the same everywhere;
 * state *s, any start value. */
static inline uint64_t test_rand64(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/* Uniform in [0, 1), 53 bits. */
static inline double test_unif(uint64_t *s)
{
    return (double)(test_rand64(s) >> 11) * 0x1.0p-53;
}

static inline double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#endif
