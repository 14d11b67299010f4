/*
 * The parallel engine's entry point; see parallel.h. The engine is split
 * by concern: src/par/engine.c (the per-part step, ownership), src/par/protocol.c
 * (the messages and their handlers), src/par/termination.c (when a run ends,
 * errors), src/par/threads.c (hardware and threads), src/par/gather.c (output),
 * src/par/partsets.c (per-part containers).
 *
 * Setup (the calling thread): recursive coordinate bisection into N parts
 * and one kd-tree per part (src/geom/partition.c), one seed tet per part near
 * its centre (src/front/seed.c over a tree of all points), each seed delivered
 * to its owner. Then one thread per part, and at the end a gather of the
 * threads' tets into one mesh in input numbering, each thread copying its
 * own share (fdt_gather_prepare, fdt_gather_copy, fdt_gather_finish).
 */
#include "par/parallel.h"

#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "base/bits.h"
#include "par/engine.h"
#include "par/gather.h"
#include "base/mem.h"
#include "front/oracle.h"
#include "front/search.h"
#include "front/probe.h"
#include "front/seed.h"
#include "par/termination.h"
#include "par/threads.h"
#include "mesh/certify.h"

static int key_cmp(const void *x, const void *y)
{
    const uint32_t *a = x, *b = y;
    for (int i = 0; i < 4; i++)
        if (a[i] != b[i])
            return a[i] < b[i] ? -1 : 1;
    return 0;
}

/* Sorts the ns tets of key (each a pair: its sorted ids, then the tet)
 * by their ids and writes the distinct tets to sd, their count to *nout. */
static void seeds_distinct(uint32_t (*key)[4], int ns, uint32_t (*sd)[4], int *nout)
{
    qsort(key, (size_t)ns, 2 * sizeof *key, key_cmp);
    int nd = 0;
    for (int i = 0; i < ns; i++) {
        if (nd > 0 && key_cmp(key[2 * i], key[2 * (i - 1)]) == 0)
            continue;
        memcpy(sd[nd++], key[2 * i + 1], sizeof sd[0]);
    }
    *nout = nd;
}

/* key[2 * i]: tet v's ids sorted; key[2 * i + 1]: v itself. */
static void seed_key(uint32_t (*key)[4], int i, const uint32_t v[4])
{
    memcpy(key[2 * i], v, 4 * sizeof *v);
    fdt_sort4_u32(key[2 * i]);
    memcpy(key[2 * i + 1], v, 4 * sizeof *v);
}

/* Seeds: one per nonempty part, the Delaunay tet (src/front/seed.c) at the part's
 * point nearest its box centre, found in a tree over all points (the setup
 * may read every part); identical seeds are dropped. *out gets *nout
 * positively oriented tets (owned by the caller). An MPI run finds its
 * ranks' seeds in src/mpi/mpi_setup.c, from the points each rank is sent. */
static int seeds_by_kd(const fdt_partition *pt, uint32_t (**out)[4], int *nout, fdt_kdq *kq)
{
    fdt_kdtree all;
    int err = fdt_partition_global_tree(pt, &all);
    if (err)
        return err;
    uint32_t(*sd)[4] = malloc((size_t)pt->nparts * sizeof *sd);
    uint32_t(*key)[4] = malloc((size_t)pt->nparts * 2 * sizeof *key);
    if (!sd || !key) {
        err = FDT_ENOMEM;
        goto done;
    }
    int ns = 0;
    for (int p = 0; p < pt->nparts; p++) {
        const fdt_kdtree *t = &pt->trees[p];
        if (!t->n)
            continue;
        double c[3];
        for (int k = 0; k < 3; k++)
            c[k] = t->nodes[0].lo[k] * 0.5 + t->nodes[0].hi[k] * 0.5;
        uint32_t a = fdt_kd_nearest(t, c, FDT_NONE, kq);
        uint32_t v[4];
        if ((err = fdt_seed_tet(&all, a, v, kq)) != FDT_OK)
            goto done;
        seed_key(key, ns++, v);
    }
    seeds_distinct(key, ns, sd, nout);
    *out = sd;
    sd = NULL;
done:
    free(sd);
    free(key);
    fdt_kd_free(&all);
    return err;
}

/*
 * The seeds where the mesh of every point is built before the fronts
 * start: one finite tet of it at the middle id of each nonempty part (ids
 * are kd order, so that point is inside the part), its tets being the
 * Delaunay tets, positively oriented as the kd seeds are. fdt_seed_tet's
 * search costs nothing like this where that mesh was wanted: at the
 * centre of a sphere its candidate window holds the whole shell, and the
 * two seeds of a two-thread run took 0.006 s (bench/NOTES.md entry 72).
 * FDT_OK or FDT_ENOMEM.
 */
static int seeds_from_mesh(const fdt_partition *pt, const fdt_ins *gm, uint32_t (**out)[4],
                           int *nout)
{
    uint32_t(*sd)[4] = malloc((size_t)pt->nparts * sizeof *sd);
    uint32_t(*key)[4] = malloc((size_t)pt->nparts * 2 * sizeof *key);
    if (!sd || !key) {
        free(sd);
        free(key);
        return FDT_ENOMEM;
    }
    int ns = 0;
    for (int p = 0; p < pt->nparts; p++) {
        if (pt->start[p] == pt->start[p + 1])
            continue;
        uint32_t a = pt->start[p] + (pt->start[p + 1] - pt->start[p]) / 2;
        uint32_t t = gm->vtet[a - gm->base];
        const uint32_t *v = fdt_ins_tet(gm, t);
        /* an infinite tet: the finite one across its hull face holds a
         * too (a is a vertex of that face) */
        for (int k = 0; k < 4; k++)
            if (v[k] == FDT_NONE) {
                uint32_t nt;
                int nk;
                fdt_ins_across(gm, t, k, &nt, &nk);
                v = fdt_ins_tet(gm, nt);
                break;
            }
        seed_key(key, ns++, v);
    }
    seeds_distinct(key, ns, sd, nout);
    free(key);
    *out = sd;
    return FDT_OK;
}

/* c[k] += k_[k] for every kind k. */
static void msg_counts_add(size_t *c, const uint64_t *k)
{
    for (int i = 0; i < FDT_MSG_KIND_END; i++)
        c[i] += (size_t)k[i];
}

void fdt_par_out_free(fdt_par_out *out)
{
    fdt_meshbuf_free(&out->mb);
    free(out->tstats);
    out->tstats = NULL;
}

void fdt_parallel_fill_stats(const fdt_par_out *o, fdt_mode mode,
                             fdt_stats *st)
{
    const fdt_stats *p = &o->pst;
    memcpy(st->sent, p->sent, sizeof st->sent);
    memcpy(st->received, p->received, sizeof st->received);
    st->remote_queries = p->remote_queries;
    st->remote_answered = p->remote_answered;
    st->remote_improved = p->remote_improved;
    st->tet_requests = p->tet_requests;
    st->duplicate_requests = p->duplicate_requests;
    st->t_idle = p->t_idle;
    st->t_query_wait = p->t_query_wait;
    st->load_imbalance = p->load_imbalance;
    st->pinned = p->pinned;
    st->threads = o->nthreads;
    st->mode = mode;
}

/*
 * With the mesh of every point built before the fronts, the tets each id
 * will own (§3.2: a tet belongs to its lowest vertex's part) are known,
 * and the parts' ranges move to split them evenly (fdt_partition_recut):
 * the bisection cuts the points in half, but a pipe's inner tets span it
 * and all of those across the cut go to the lower part (cylscan 100k:
 * 726k tets against 577k, front thread CPU 0.43 s against 0.28 s;
 * bench/NOTES.md entry 60). Hull faces count as tets do (each is a face
 * advanced): by tets alone the lower part, with 140k of the pipe's 200k
 * hull faces, kept 0.33-0.35 s against 0.29-0.31. One pass over the
 * mesh's slots. FDT_OK or FDT_ENOMEM.
 */
static int recut_by_mesh(fdt_partition *pt, const fdt_ins *gm)
{
    uint32_t *w = calloc(pt->m ? pt->m : 1, sizeof *w);
    if (!w)
        return FDT_ENOMEM;
    uint64_t total = 0;
    for (uint32_t t = 0; t < gm->nslots; t++) {
        const uint32_t *v = fdt_ins_tet(gm, t);
        if (v[0] == FDT_NONE && v[1] == FDT_NONE)
            continue; /* a freed slot */
        /* the lowest id; FDT_NONE (the infinite vertex of a hull face's
         * tet) is above every id, so a hull face counts for its own
         * lowest vertex: a face advanced, as a tet is */
        uint32_t lo = v[0] < v[1] ? v[0] : v[1];
        uint32_t hi = v[2] < v[3] ? v[2] : v[3];
        w[lo < hi ? lo : hi]++;
        total++;
    }
    fdt_partition_recut(pt, w, total);
    free(w);
    return FDT_OK;
}

/* ---- the run's steps (fdt_parallel_run) ----------------------------------- */

/* Partitions the points into nthreads parts, one kd-tree each. On
 * failure pt is zeroed. */
static int partition(fdt_prepared *pr, const fdt_settings *s, int nthreads, fdt_partition *pt)
{
    /* The parts' trees are built on as many threads as there are CPUs
     * (up to one a part): at 1M points on two cores that took a quarter
     * of a second off a setup of 0.9 s. Online CPUs, not hwloc's cores:
     * the topology's load took 3.9 ms, inside the timed run of every
     * `--threads N` (bench/NOTES.md entry 68), and a builder on a second
     * hardware thread of a core costs nothing here. */
    long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
    int cores = ncpu < 1 ? 1 : ncpu > FDT_PARTITION_MAX ? FDT_PARTITION_MAX : (int)ncpu;
    return fdt_partition_build(pt, pr->p, pr->orig, (uint32_t)pr->m, nthreads,
                               s->leaf_size > 0 ? s->leaf_size : FDT_DEFAULT_LEAF,
                               cores < nthreads ? cores : nthreads);
}

/* The engine over the partition pt, its tets going to opt's sink or, when
 * there is none, to mem_sink (set up here, *mem_sink_ok). *ep is set
 * whenever it was allocated, failure or not: engine_free frees it. */
static int engine_start(fdt_prepared *pr, const fdt_settings *s, fdt_mode mode,
                        const fdt_par_opts *opt, fdt_partition *pt, int nthreads,
                        fdt_tsink *mem_sink, int *mem_sink_ok, engine **ep)
{
    engine *e = fdt_eng_new(nthreads);
    *ep = e;
    if (!e)
        return FDT_ENOMEM;
    e->pt = pt;
    e->P = pr->p;
    e->orig = pr->orig;
    if (opt && opt->sink) {
        e->sink = opt->sink;
    } else {
        if (fdt_tsink_init(mem_sink, pr->orig, NULL) != FDT_OK)
            return FDT_ENOMEM;
        *mem_sink_ok = 1;
        e->sink = mem_sink;
    }
    e->mode = mode;
    e->want_nbrs = s->neighbors != 0;
    e->search = (int)s->search;
    e->pin = s->pin != 0;
    return FDT_OK;
}

/*
 * The DT of every point, built here on the run's threads with
 * --search auto where the parts run (an explicit mode, a stream or --pin:
 * in the default mode the one-part engine runs instead, src/api/api.c),
 * or when a test asks (opt->global_mesh), if it fits the
 * memory available (src/front/oracle.h, FDT_ORACLE_MESH_BYTES); then
 * every part reads its faces' apexes from it and asks no other part
 * (bench/NOTES.md entries 54, 90). In message mode it stands for the
 * replica each MPI rank builds for itself (src/mpi/mpi_run.c): immutable
 * once built, so one copy serves every part, and the parts still exchange
 * their faces by FACESEND. Tets are still made and owned by the parts'
 * fronts. Where it is not built the wall engine runs (src/par/engine.c),
 * or with --search kd the paper's fronts. Built before the seeds go to
 * their owners and the workers take their ranges: recut_by_mesh moves
 * those ranges. *t_gm: the build's time.
 */
static int global_mesh(engine *e, fdt_prepared *pr, const fdt_settings *s,
                       const fdt_par_opts *opt, double probe, int nthreads, fdt_partition *pt,
                       fdt_kdq *kq0, double *t_gm, char *diag, size_t dlen)
{
    int want = fdt_search_row_of(s->search)->probe && probe > FDT_PROBE_SHARED_MESH &&
               FDT_ORACLE_MESH_BYTES * (double)pr->m <= (double)fdt_mem_available();
    if (!want && !(opt && opt->global_mesh))
        return FDT_OK;
    double tg = fdt_now_s();
    int gerr = fdt_ins_build_parallel(&e->gmesh, pr->p, 0, (uint32_t)pr->m, nthreads, &kq0->pc);
    *t_gm = fdt_now_s() - tg;
    if (gerr == FDT_OK) {
        /* proved before any part reads it (issue 31 item 6) */
        fdt_certify_fail why;
        double tc = fdt_now_s();
        int err = fdt_certify_parallel(&e->gmesh, nthreads, &kq0->pc, &why);
        e->gm_t_certify = fdt_now_s() - tc;
        if (err == FDT_OK)
            e->gm_certified = e->gmesh.nfinite;
        if (err != FDT_OK) {
            if (err == FDT_ECHECK)
                fdt_certify_describe(&why, diag, dlen);
            return err;
        }
        e->gmesh_ok = 1;
        return nthreads > 1 ? recut_by_mesh(pt, &e->gmesh) : FDT_OK;
    }
    if (gerr == FDT_ENOMEM || gerr == FDT_EDEGENERATE)
        return FDT_OK;
    if (gerr == FDT_EINTERNAL) {
        fdt_certify_fail why;
        fdt_certify_build_failed(&why);
        fdt_certify_describe(&why, diag, dlen);
        return FDT_ECHECK;
    }
    return gerr;
}

/* The transport between the parts and the engine's lock and conditions
 * (*sync_ok once they all exist). */
static int engine_sync_init(engine *e, const fdt_par_opts *opt, int nthreads, int *sync_ok)
{
    int err;
    if (opt && opt->shuffle)
        err = fdt_transport_shuffle(&e->tp, nthreads + 1, opt->seed, opt->delay_pct);
    else
        err = fdt_transport_mailbox(&e->tp, nthreads + 1);
    if (err) {
        /* FDT_EINVAL: a bad test option; otherwise out of memory (a mutex
         * that cannot be made counts as that, as before) */
        return err != FDT_EINVAL ? FDT_ENOMEM : err;
    }
    if (pthread_mutex_init(&e->lock, NULL) != 0)
        return FDT_ENOMEM;
    if (pthread_cond_init(&e->cv, NULL) != 0) {
        pthread_mutex_destroy(&e->lock);
        return FDT_ENOMEM;
    }
    if (pthread_cond_init(&e->go, NULL) != 0) {
        pthread_cond_destroy(&e->cv);
        pthread_mutex_destroy(&e->lock);
        return FDT_ENOMEM;
    }
    *sync_ok = 1;
    return FDT_OK;
}

/* With pinning: the machine's cores and NUMA nodes (hwloc), or pinning
 * refused where they cannot be read. */
static void engine_topology(engine *e)
{
#ifdef FDT_HAVE_HWLOC
    if (e->pin) {
        if (hwloc_topology_init(&e->topo) == 0 && hwloc_topology_load(e->topo) == 0) {
            e->ncores = hwloc_get_nbobjs_by_type(e->topo, HWLOC_OBJ_CORE);
            e->numa_nodes = hwloc_get_nbobjs_by_type(e->topo, HWLOC_OBJ_NUMANODE);
        }
        if (e->ncores <= 0) {
            if (e->topo)
                hwloc_topology_destroy(e->topo);
            e->topo = NULL;
            atomic_store_explicit(&e->pin_refused, 1, memory_order_relaxed);
        }
    }
#else
    if (e->pin)
        atomic_store_explicit(&e->pin_refused, 1, memory_order_relaxed);
#endif
}

/* Each worker's part: its tree and its range of ids. */
static void workers_init(engine *e, fdt_partition *pt, int nthreads)
{
    for (int i = 0; i < nthreads; i++) {
        worker *w = &e->w[i];
        atomic_init(&w->tets_done, 0);
        w->e = e;
        w->id = i;
        w->tree = &pt->trees[i];
        w->lo = pt->start[i];
        w->hi = pt->start[i + 1];
        w->st.points = w->hi - w->lo;
        w->st.core = -1;
        w->report_at = 4096;
    }
}

/* Seeds to their owners: *seeds regrouped by owner (a counting sort, the
 * owners' in owner order; nseeds <= nthreads, a scan is fine), each
 * worker's seeds pointing into the new array, which replaces *seeds. */
static int seeds_to_owners(engine *e, const fdt_partition *pt, uint32_t (**seeds)[4],
                           int nseeds, int nthreads)
{
    uint32_t(*by)[4] = malloc(((size_t)nseeds + 1) * sizeof *by);
    int *cnt = calloc((size_t)nthreads + 1, sizeof *cnt);
    if (!by || !cnt) {
        free(by);
        free(cnt);
        return FDT_ENOMEM;
    }
    int *own = malloc(((size_t)nseeds + 1) * sizeof *own);
    if (!own) {
        free(by);
        free(cnt);
        return FDT_ENOMEM;
    }
    uint32_t(*sd)[4] = *seeds;
    for (int i = 0; i < nseeds; i++) {
        uint32_t lo = sd[i][0];
        for (int k = 1; k < 4; k++)
            if (sd[i][k] < lo)
                lo = sd[i][k];
        own[i] = fdt_partition_owner(pt, lo);
        cnt[own[i] + 1]++;
    }
    for (int i = 0; i < nthreads; i++)
        cnt[i + 1] += cnt[i];
    for (int i = 0; i < nthreads; i++) {
        e->w[i].seeds = by + cnt[i];
        e->w[i].nseeds = cnt[i + 1] - cnt[i];
    }
    for (int i = 0; i < nseeds; i++)
        memcpy(by[cnt[own[i]]++], sd[i], sizeof by[0]);
    free(own);
    free(cnt);
    free(sd);
    *seeds = by;
    return FDT_OK;
}

/* Message mode: a seed's foreign vertices are delivered with it, as a
 * FACESEND would carry them (the setup may read every part). */
static int seed_ghosts(engine *e, const fdt_prepared *pr, int nthreads)
{
    for (int i = 0; i < nthreads; i++) {
        worker *w = &e->w[i];
        for (int j = 0; j < w->nseeds; j++)
            for (int k = 0; k < 4; k++) {
                uint32_t id = w->seeds[j][k];
                if (!is_own(w, id) &&
                    fdt_ghost_put(&w->ghosts, id, pr->p + 3 * (size_t)id) != FDT_OK)
                    return FDT_ENOMEM;
            }
    }
    return FDT_OK;
}

/* Termination's starting state. Shared mode: every part with seeds holds
 * an activity unit. Message mode: every part with seeds is a root of
 * Dijkstra-Scholten, engaged with no parent (src/par/termination.c).
 * Returns the activity units held (shared mode). */
static long long engine_roles(engine *e, fdt_mode mode, const fdt_par_opts *opt, int nthreads)
{
    long long active = 0;
    e->msg_term = mode == FDT_MODE_MESSAGE;
    e->park = mode == FDT_MODE_MESSAGE && opt && opt->park;
    e->fail_part = opt && opt->fail ? opt->fail_part : -1;
    e->fail_after = opt ? opt->fail_after : 0;
    for (int i = 0; i < nthreads; i++) {
        worker *w = &e->w[i];
        w->parent = -1;
        w->aborted_by = -1;
        w->root = w->nseeds > 0 || (e->walls && w->hi > w->lo);
        if (!w->root)
            continue;
        if (e->msg_term) {
            w->engaged = 1;
            e->roots++;
        } else {
            w->active = 1;
            active++;
        }
    }
    return active;
}

/* The workers' first error, after they are joined, its message in diag. */
static int workers_error(engine *e, int nthreads, char *diag, size_t dlen)
{
    /* After pthread_join: any order would do; acquire documents that the
     * recorded err_thread/err_what are read after the CAS that chose them. */
    int werr = e->msg_term ? fdt_term_error(e, &e->err_thread, &e->err_what)
                           : atomic_load_explicit(&e->error, memory_order_acquire);
    if (werr == FDT_ENOMEM)
        snprintf(diag, dlen, "out of memory in worker thread %d", e->err_thread);
    else if (werr == FDT_EINTERNAL)
        snprintf(diag, dlen, "internal error in worker thread %d: %s", e->err_thread,
                 e->err_what ? e->err_what : "?");
    else if (werr == FDT_ETHREAD)
        snprintf(diag, dlen, "could not create thread %d of %d", e->err_thread, nthreads);
    else if (werr == FDT_ECHECK)
        snprintf(diag, dlen, "mesh certificate failed in worker thread %d: %s", e->err_thread,
                 e->err_what ? e->err_what : "?");
    return werr;
}

/* The threads' statistics into out (tstats, pst, fst), with the setup's
 * kd queries kq0 and the global mesh's build time t_gm. */
static int collect_stats(engine *e, const fdt_partition *pt, int nthreads, const fdt_kdq *kq0,
                         double t_gm, fdt_par_out *out)
{
    out->tstats = calloc((size_t)nthreads, sizeof *out->tstats);
    if (!out->tstats)
        return FDT_ENOMEM;
    fdt_stats *ps = &out->pst;
    size_t maxt = 0, sumt = 0;
    for (int i = 0; i < nthreads; i++) {
        worker *w = &e->w[i];
        fdt_thread_stats *ts = &out->tstats[i];
        fdt_mailbox_counts mc;
        fdt_tp_counts(e->tp, i, &mc);
        *ts = w->st;
        ts->tets = (size_t)w->em.ntets;
        ps->mem_tree += fdt_kd_bytes(&pt->trees[i]);
        ps->mem_front += fdt_front_bytes(&w->ft, &w->fq);
        ps->mem_mesh += fdt_meshbuf_bytes(&w->out);
        ps->mem_sink += fdt_emit_bytes(&w->em);
        msg_counts_add(ts->sent, mc.sent);
        msg_counts_add(ts->received, mc.received);
        msg_counts_add(ps->sent, mc.sent);
        msg_counts_add(ps->received, mc.received);
        ps->remote_queries += ts->remote_queries;
        ps->remote_answered += ts->remote_answered;
        ps->remote_improved += ts->remote_improved;
        ps->tet_requests += ts->tet_requests;
        ps->duplicate_requests += ts->duplicate_requests;
        ps->t_idle += ts->t_idle;
        ps->t_query_wait += ts->t_query_wait;
        out->fst.faces_advanced += ts->faces_advanced;
        /* The sum of the threads' largest fronts: an upper bound on the
         * largest total front, which no thread observes. */
        out->fst.max_front += ts->max_front;
        out->fst.kq.nodes += w->kq.nodes;
        out->fst.kq.points += w->kq.points;
        out->fst.kq.pc.orient_exact += w->kq.pc.orient_exact;
        out->fst.kq.pc.insphere_exact += w->kq.pc.insphere_exact;
        out->fst.mesh_faces += w->orc.mesh_faces;
        out->fst.star_walks += w->orc.star_walks;
        out->fst.mesh_parts += w->orc.switched_at != 0 || w->orc.gm;
        out->fst.t_mesh += w->orc.t_mesh;
        out->fst.certified_tets += w->orc.certified;
        out->fst.final_tets += w->st.final_tets;
        out->fst.t_certify += w->orc.t_certify;
        out->fst.kq.pc.orient_adapt += w->kq.pc.orient_adapt;
        out->fst.kq.pc.insphere_adapt += w->kq.pc.insphere_adapt;
        if (ts->tets > maxt)
            maxt = ts->tets;
        sumt += ts->tets;
    }
    out->fst.t_mesh += t_gm;
    out->fst.certified_tets += e->gm_certified;
    out->fst.t_certify += e->gm_t_certify;
    out->fst.kq.nodes += kq0->nodes;
    out->fst.kq.points += kq0->points;
    fdt_pred_counts_add(&out->fst.kq.pc, &kq0->pc);
    ps->load_imbalance = sumt ? (double)maxt * nthreads / (double)sumt : 1.0;
    ps->pinned = e->pin ? (atomic_load_explicit(&e->pin_refused, memory_order_relaxed) ? -1 : 1) : 0;
    return FDT_OK;
}

/* The message balance: every message sent was received, kind by kind.
 * IAMDONE: shared mode, one to every other part; message mode also one
 * from each root but part 0 to part 0 (its tree finished). FACERECV: one
 * for each FACESEND in message mode, none in shared mode. */
static int check_balance(const engine *e, const fdt_stats *ps, int nthreads, char *diag,
                         size_t dlen)
{
    size_t iamdones = (size_t)nthreads - 1 +
                      (e->msg_term ? (size_t)e->roots - (e->w[0].root != 0) : 0);
    if (memcmp(ps->sent, ps->received, sizeof ps->sent) != 0 ||
        ps->remote_queries != ps->remote_answered ||
        ps->sent[FDT_MSG_NODESEND] != ps->remote_queries ||
        ps->sent[FDT_MSG_IAMDONE] != iamdones || ps->sent[FDT_MSG_ABORT] != 0 ||
        ps->sent[FDT_MSG_FACERECV] != (e->msg_term ? ps->sent[FDT_MSG_FACESEND] : 0)) {
        snprintf(diag, dlen, "internal error: messages sent and received differ");
        return FDT_EINTERNAL;
    }
    return FDT_OK;
}

/* Frees the engine (NULL: nothing) and what it holds; sync_ok: its lock
 * and conditions exist. */
static void engine_free(engine *e, int nthreads, int sync_ok)
{
    if (!e)
        return;
    for (int i = 0; i < nthreads; i++)
        fdt_eng_worker_free(&e->w[i]);
    fdt_ins_free(&e->gmesh);
    fdt_transport_destroy(&e->tp);
    if (sync_ok) {
        pthread_cond_destroy(&e->go);
        pthread_cond_destroy(&e->cv);
        pthread_mutex_destroy(&e->lock);
    }
    free(e->toff);
    free(e->hoff);
#ifdef FDT_HAVE_HWLOC
    if (e->topo)
        hwloc_topology_destroy(e->topo);
#endif
    fdt_eng_delete(e);
}

int fdt_parallel_run(fdt_prepared *pr, const fdt_settings *s, fdt_mode mode, int nthreads,
                     const fdt_par_opts *opt, fdt_par_out *out, char *diag, size_t dlen)
{
    memset(out, 0, sizeof *out);
    if ((mode != FDT_MODE_SHARED && mode != FDT_MODE_MESSAGE) || nthreads < 1 ||
        nthreads > FDT_PARTITION_MAX || pr->m < 4 || pr->m > UINT32_MAX - 1)
        return FDT_EINVAL;
    double t0 = fdt_now_s();
    fdt_partition pt;
    engine *e = NULL;
    uint32_t(*seeds)[4] = NULL;
    int nseeds = 0, sync_ok = 0;
    fdt_tsink mem_sink;
    int mem_sink_ok = 0;
    fdt_kdq kq0;
    memset(&kq0, 0, sizeof kq0);
    double t_gm = 0.0;
    /* A search that probes (--search auto): the probe's count of points
     * tested a face on samples of the points (src/front/probe.h), taken
     * before the partition permutes them, chooses the mesh of every point
     * (global_mesh). */
    const fdt_search_row *sr = fdt_search_row_of(s->search);
    double probe = 0.0;
    if (sr->probe) {
        fdt_probe_samples ps;
        fdt_probe_take(&ps, pr->p, (uint32_t)pr->m, s->leaf_size);
        probe = fdt_probe_cost(&ps);
    }
    int err = partition(pr, s, nthreads, &pt);
    if (err != FDT_OK)
        return err; /* pt is zeroed */
    if ((err = engine_start(pr, s, mode, opt, &pt, nthreads, &mem_sink, &mem_sink_ok, &e)) !=
            FDT_OK ||
        (err = global_mesh(e, pr, s, opt, probe, nthreads, &pt, &kq0, &t_gm, diag, dlen)) !=
            FDT_OK)
        goto fail;
    /* A search with walls (--search mesh): the wall engine (src/par/
     * engine.c, walls_start). One that probes (--search auto): the mesh
     * of every point, or the kd search where the probe found it cheap;
     * the input, the settings and the memory decide, never a clock
     * (bench/NOTES.md entry 90). */
    e->walls = sr->walls && !e->gmesh_ok;
    out->engine = e->walls ? FDT_ENGINE_WALLS : e->gmesh_ok ? FDT_ENGINE_PARTS_MESH
                                                            : FDT_ENGINE_PARTS;
    /* The seeds, after the mesh of every point where it was built: its
     * tets are Delaunay tets already (seeds_from_mesh). */
    err = e->gmesh_ok ? seeds_from_mesh(&pt, &e->gmesh, &seeds, &nseeds)
                      : seeds_by_kd(&pt, &seeds, &nseeds, &kq0);
    if (err != FDT_OK) {
        if (err == FDT_EINTERNAL)
            snprintf(diag, dlen, "internal error: no seed tetrahedron found");
        goto fail;
    }
    if ((err = engine_sync_init(e, opt, nthreads, &sync_ok)) != FDT_OK)
        goto fail;
    engine_topology(e);
    workers_init(e, &pt, nthreads);
    if ((err = seeds_to_owners(e, &pt, &seeds, nseeds, nthreads)) != FDT_OK ||
        (mode == FDT_MODE_MESSAGE && (err = seed_ghosts(e, pr, nthreads)) != FDT_OK))
        goto fail;
    /* Every thread with seeds starts holding its activity unit. Thread
     * creation orders this before everything the workers do. */
    atomic_init(&e->work, engine_roles(e, mode, opt, nthreads));
    double t1 = fdt_now_s();
    double t2 = t1;
    err = fdt_threads_run(e, s, &t2);
    int werr = workers_error(e, nthreads, diag, dlen);
    if (werr)
        err = werr;
    if (err || (err = collect_stats(e, &pt, nthreads, &kq0, t_gm, out)) != FDT_OK ||
        (err = check_balance(e, &out->pst, nthreads, diag, dlen)) != FDT_OK)
        goto fail;
    err = e->sink->user ? FDT_OK : fdt_gather_finish(e, &out->mb);
    if (err) {
        if (err == FDT_EINTERNAL)
            snprintf(diag, dlen, "internal error: a face between threads was not linked");
        goto fail;
    }
    out->nthreads = nthreads;
    out->t_setup = t1 - t0;
    out->t_front = t2 - t1;
    out->t_gather = fdt_now_s() - t2;
fail:
    engine_free(e, nthreads, sync_ok);
    free(seeds);
    fdt_partition_free(&pt);
    if (mem_sink_ok)
        fdt_tsink_free(&mem_sink);
    if (err)
        fdt_par_out_free(out);
    return err;
}
