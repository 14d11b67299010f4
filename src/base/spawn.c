/* Helper threads started off the caller's core; see spawn.h. */
#if defined(__linux__)
#define _GNU_SOURCE /* sched_getcpu, the CPU_* macros, the affinity calls */
#endif
#include "base/spawn.h"

#include <sched.h>
#include <stdlib.h>

#if defined(__linux__) && defined(CPU_SET) && defined(CPU_COUNT)
#define FDT_SPAWN_AFFINITY 1
#endif

typedef struct start {
    void *(*fn)(void *);
    void *arg;
#ifdef FDT_SPAWN_AFFINITY
    cpu_set_t all; /* the caller's set, given back to the thread */
#endif
} start;

/* The new thread's first steps. pthread_create orders the caller's
 * writes of *p before them. */
static void *trampoline(void *p)
{
    start s = *(start *)p;
    free(p);
#ifdef FDT_SPAWN_AFFINITY
    /* Nothing is lost if this fails: the thread then stays off the
     * caller's core, which is where it was meant to start. */
    (void)pthread_setaffinity_np(pthread_self(), sizeof s.all, &s.all);
#endif
    return s.fn(s.arg);
}

int fdt_spawn(pthread_t *th, size_t stack_bytes, void *(*fn)(void *), void *arg)
{
    pthread_attr_t attr;
    int rc = pthread_attr_init(&attr);
    if (rc != 0)
        return rc;
    if (stack_bytes)
        (void)pthread_attr_setstacksize(&attr, stack_bytes);
#ifdef FDT_SPAWN_AFFINITY
    int cpu = sched_getcpu();
    start *s = malloc(sizeof *s);
    if (s && cpu >= 0 && cpu < CPU_SETSIZE &&
        pthread_getaffinity_np(pthread_self(), sizeof s->all, &s->all) == 0 &&
        CPU_ISSET(cpu, &s->all) && CPU_COUNT(&s->all) > 1) {
        cpu_set_t first = s->all;
        CPU_CLR(cpu, &first);
        if (pthread_attr_setaffinity_np(&attr, sizeof first, &first) == 0) {
            s->fn = fn;
            s->arg = arg;
            if (pthread_create(th, &attr, trampoline, s) == 0) {
                pthread_attr_destroy(&attr);
                return 0;
            }
            /* below: without the placement (it is a hint only) */
            pthread_attr_destroy(&attr);
            if ((rc = pthread_attr_init(&attr)) != 0) {
                free(s);
                return rc;
            }
            if (stack_bytes)
                (void)pthread_attr_setstacksize(&attr, stack_bytes);
        }
    }
    free(s);
#endif
    rc = pthread_create(th, &attr, fn, arg);
    pthread_attr_destroy(&attr);
    return rc;
}

void fdt_fork_join(void *jobs, size_t size, int count, void *(*fn)(void *))
{
    char *j = jobs;
    pthread_t *th = count > 1 ? malloc((size_t)(count - 1) * sizeof *th) : NULL;
    char *started = count > 1 ? calloc((size_t)(count - 1), 1) : NULL;
    if (count > 1 && (!th || !started)) {
        free(th);
        free(started);
        th = NULL;
        started = NULL;
    }
    for (int i = 0; th && i < count - 1; i++)
        started[i] = fdt_spawn(&th[i], 0, fn, j + (size_t)i * size) == 0;
    if (count > 0)
        fn(j + (size_t)(count - 1) * size);
    for (int i = 0; i < count - 1; i++) {
        if (th && started[i])
            pthread_join(th[i], NULL);
        else
            fn(j + (size_t)i * size); /* no thread: on the caller's */
    }
    free(th);
    free(started);
}
