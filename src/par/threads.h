/*
 * Hardware and threads of the parallel engine: hwloc, pinning, starting
 * the workers, progress while they run, joining them (src/par/threads.c).
 */
#ifndef FDT_THREADS_H
#define FDT_THREADS_H

#include "par/engine.h"

/* The default thread count: physical cores (hwloc), else online CPUs,
 * clamped to [1, 1024]. */
int fdt_threads_default(void);

/* Runs the workers and waits for their loops, then has them gather the
 * mesh and joins them; *t_loops: when the last loop ended. */
int fdt_threads_run(engine *e, const fdt_settings *s, double *t_loops);

#endif