/*
 * Starting a helper thread on another core than the caller's.
 *
 * Every parallel phase here starts its helpers with pthread_create right
 * after the previous phase's joins, and the calling thread works as
 * worker 0 at once. On the two-vCPU VM this project is measured on, Linux
 * sometimes put the new thread on the caller's own core while the other
 * core idled; the idle core pulled it only at its next balancing tick, so
 * the helper started about 3 ms late (250 Hz) and the two shared one core
 * meanwhile. It came in spells: in a test of 100 create-work-join rounds
 * (5 ms of work each side), 96 or 100 rounds of a run were late in some
 * runs and 1-8 in the others; with the helper's first CPU set excluding
 * the caller's core, 0-3 in every run (bench/NOTES.md entry 85).
 *
 * fdt_spawn starts the thread on the caller's allowed CPUs less the one
 * the caller runs on, and the thread gives itself the caller's whole set
 * back before it runs fn: a placement hint for its start only, never a
 * pin (where the caller is pinned, as with --pin, the child inherits the
 * pin, exactly as with pthread_create). Where the set has one CPU, or
 * Linux's calls are missing, it is pthread_create.
 */
#ifndef FDT_SPAWN_H
#define FDT_SPAWN_H

#include <pthread.h>
#include <stddef.h>

/* pthread_create(th, attr, fn, arg) with a stack of stack_bytes (0: the
 * default), placed as above. Returns pthread_create's result. */
int fdt_spawn(pthread_t *th, size_t stack_bytes, void *(*fn)(void *), void *arg);

/* fn(jobs + i size) for every i < count, each on a thread of its own
 * started by fdt_spawn, the last on the caller's (a job whose thread could
 * not start runs on the caller's too, afterwards); returns when all are
 * done. pthread_create and pthread_join order each job's writes after
 * the caller's before and before the caller's after. */
void fdt_fork_join(void *jobs, size_t size, int count, void *(*fn)(void *));

#endif
