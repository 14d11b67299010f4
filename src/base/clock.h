/*
 * The two clocks the library and the CLI time themselves with (shared,
 * so each module does not carry its own copy).
 */
#ifndef FDT_CLOCK_H
#define FDT_CLOCK_H

#include <time.h>

/* Seconds on CLOCK_MONOTONIC: wall time between two calls, immune to
 * changes of the system clock. */
static inline double fdt_now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* CPU seconds used by the calling thread so far (0 if the clock is
 * missing): the work of one thread without the time other processes or
 * threads held its core, the steadier figure on a loaded machine. */
static inline double fdt_thread_cpu_s(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) != 0)
        return 0.0;
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#endif
