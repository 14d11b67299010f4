/* Hardware and threads of the parallel engine; see threads.h. */
#include "par/threads.h"
#include "base/clock.h"

#include <errno.h>
#include <stdlib.h>
#include <unistd.h>

#include "par/gather.h"
#include "base/spawn.h"
#include "par/termination.h"

static void pin_thread(worker *w)
{
#ifdef FDT_HAVE_HWLOC
    engine *e = w->e;
    if (!e->topo)
        return;
    hwloc_obj_t core = hwloc_get_obj_by_type(e->topo, HWLOC_OBJ_CORE,
                                             (unsigned)(w->id % e->ncores));
    if (!core || hwloc_set_cpubind(e->topo, core->cpuset, HWLOC_CPUBIND_THREAD) != 0) {
        /* relaxed: read only after pthread_join, which orders it. */
        atomic_store_explicit(&e->pin_refused, 1, memory_order_relaxed);
        return;
    }
    w->st.core = w->id % e->ncores;
    /* First touch: the thread's own tables are allocated after this, by
     * itself. Its part's coordinates were written by the setup, so on a
     * machine with several memory nodes we move them next to the core
     * (best effort: a refusal only costs remote reads). */
    if (e->numa_nodes > 1 && w->hi > w->lo) {
        (void)hwloc_set_area_membind(e->topo, e->P + 3 * (size_t)w->lo,
                                     3 * sizeof(double) * (size_t)(w->hi - w->lo),
                                     core->cpuset, HWLOC_MEMBIND_BIND,
                                     HWLOC_MEMBIND_MIGRATE);
        (void)hwloc_set_area_membind(e->topo, w->tree->nodes,
                                     w->tree->nnodes * sizeof *w->tree->nodes,
                                     core->cpuset, HWLOC_MEMBIND_BIND,
                                     HWLOC_MEMBIND_MIGRATE);
    }
#else
    (void)w;
#endif
}

/* A worker's run: its setup and loop, then its count in `finished`. */
static void worker_run(worker *w)
{
    engine *e = w->e;
    double cpu0 = fdt_thread_cpu_s();
    if (e->pin)
        pin_thread(w);
    int rc = fdt_eng_worker_setup(w);
    if (rc == FDT_OK)
        rc = fdt_eng_worker_loop(w);
    /* A streamed run's last partial batch goes to the caller's sink from
     * here, under the sink's lock (src/front/sink.h), unless the run failed. */
    if (rc >= 0 && !aborted(e)) {
        int frc = fdt_emit_flush(&w->em);
        if (frc)
            rc = frc;
    }
    if (rc < 0)
        fdt_eng_set_error(e, rc, w->id,
                          rc == FDT_ENOMEM      ? "out of memory"
                          : rc == FDT_EINTERNAL ? "inconsistent front"
                          : rc == FDT_ECHECK    ? (w->orc.err_what ? w->orc.err_what : "?")
                                                : "the sink stopped the run");
    /* relaxed: a progress estimate only. */
    atomic_store_explicit(&w->tets_done, (size_t)w->em.ntets, memory_order_relaxed);
    w->st.t_cpu = fdt_thread_cpu_s() - cpu0;
    pthread_mutex_lock(&e->lock);
    e->finished++;
    pthread_cond_signal(&e->cv);
    pthread_mutex_unlock(&e->lock);
}

/* Its part of the gather, once fdt_threads_run said whether there is one. */
static void worker_gather(worker *w)
{
    engine *e = w->e;
    pthread_mutex_lock(&e->lock);
    while (e->gather == 0)
        pthread_cond_wait(&e->go, &e->lock);
    int copy = e->gather > 0;
    pthread_mutex_unlock(&e->lock);
    if (copy) {
        fdt_gather_copy(w);
        pthread_mutex_lock(&e->lock);
        e->copied++;
        pthread_cond_signal(&e->cv);
        pthread_mutex_unlock(&e->lock);
    }
}

static void *worker_main(void *arg)
{
    worker_run(arg);
    worker_gather(arg);
    return NULL;
}

int fdt_threads_default(void)
{
    long n = 0;
#ifdef FDT_HAVE_HWLOC
    hwloc_topology_t t;
    if (hwloc_topology_init(&t) == 0) {
        if (hwloc_topology_load(t) == 0)
            n = hwloc_get_nbobjs_by_type(t, HWLOC_OBJ_CORE);
        hwloc_topology_destroy(t);
    }
#endif
    if (n <= 0)
        n = sysconf(_SC_NPROCESSORS_ONLN);
    if (n < 1)
        n = 1;
    if (n > FDT_PARTITION_MAX)
        n = FDT_PARTITION_MAX;
    return (int)n;
}

/* Runs the workers and waits for their loops, then has them gather the
 * mesh (fdt_gather_prepare, fdt_gather_copy) and joins them; *t_loops: when the
 * last loop ended. Where progress is reported (and a cancel taken through
 * the abort path) or threads are pinned, the calling thread does that
 * meanwhile and every worker has a thread of its own; otherwise the
 * calling thread is worker 0. With a new thread for every worker, one of
 * two started 2-5 ms after the other in about half the runs on this
 * two-core machine, while the insertion build's second thread, whose
 * caller is its worker 0, started within 0.1 ms (bench/NOTES.md entry 73;
 * entry 85 found why a new thread sometimes starts late: the kernel put it
 * on its creator's core, which fdt_spawn now avoids). A pinned worker 0
 * would leave the caller's thread pinned. */
int fdt_threads_run(engine *e, const fdt_settings *s, double *t_loops)
{
    int inline0 = !s->progress && !e->pin;
    int created = inline0, err = FDT_OK;
    /* 1024 threads at the default 8 MiB would reserve 8 GiB of address
     * space; a worker's deepest stack is a few KiB of walk stacks. */
    for (; created < e->n; created++)
        if (fdt_spawn(&e->w[created].th, (size_t)1 << 20, worker_main, &e->w[created]) != 0) {
            err = FDT_ETHREAD;
            fdt_term_ctl_fail(e, FDT_ETHREAD, created, "could not create a thread");
            break;
        }
    /* created counts worker 0 when it runs here: every one of them
     * finishes its loop (a thread that could not be made stopped the
     * others through the error). */
    if (inline0)
        worker_run(&e->w[0]);
    double expect = 6.5 * (double)e->pt->m + 1.0;
    pthread_mutex_lock(&e->lock);
    while (e->finished < created) {
        if (!s->progress || err) {
            pthread_cond_wait(&e->cv, &e->lock);
            continue;
        }
        struct timespec dl;
        clock_gettime(CLOCK_REALTIME, &dl);
        dl.tv_nsec += 50 * 1000 * 1000;
        if (dl.tv_nsec >= 1000000000) {
            dl.tv_sec++;
            dl.tv_nsec -= 1000000000;
        }
        int rc = pthread_cond_timedwait(&e->cv, &e->lock, &dl);
        if (rc != ETIMEDOUT || e->finished >= created)
            continue;
        pthread_mutex_unlock(&e->lock);
        size_t built = 0;
        for (int i = 0; i < e->n; i++) /* relaxed: an estimate */
            built += atomic_load_explicit(&e->w[i].tets_done, memory_order_relaxed);
        double fr = (double)built / expect;
        if (s->progress(s->progress_user, fr > 0.99 ? 0.99 : fr))
            fdt_term_ctl_fail(e, FDT_ECANCELED, -1, "canceled");
        pthread_mutex_lock(&e->lock);
    }
    *t_loops = fdt_now_s();
    /* Every worker waits on `go` now. Gather only a complete run: with an
     * error (relaxed is enough: a worker's fdt_eng_set_error precedes its
     * finished++ under the lock we hold; message mode: the workers'
     * own error fields, written before finished++ too) the workers just
     * exit. */
    int go = -1;
    int wt;
    const char *ww;
    int failed = e->msg_term ? fdt_term_error(e, &wt, &ww) != 0
                             : atomic_load_explicit(&e->error, memory_order_relaxed) != 0;
    /* A streamed run's tets have all left: nothing to gather. */
    if (!err && !failed && !e->sink->user) {
        err = fdt_gather_prepare(e);
        go = err ? -1 : 1;
    }
    e->gather = go;
    pthread_cond_broadcast(&e->go);
    pthread_mutex_unlock(&e->lock);
    if (inline0)
        worker_gather(&e->w[0]);
    pthread_mutex_lock(&e->lock);
    while (go > 0 && e->copied < e->n)
        pthread_cond_wait(&e->cv, &e->lock);
    pthread_mutex_unlock(&e->lock);
    for (int i = inline0; i < created; i++)
        pthread_join(e->w[i].th, NULL);
    return err;
}
