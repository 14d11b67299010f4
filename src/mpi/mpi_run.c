/*
 * One rank of a distributed run; see mpi_run.h.
 *
 * The run on a rank is the message-mode worker of src/par/engine.c: an engine
 * whose e->n parts are the ranks, of which this rank fills only its own
 * worker (the others stay zero: message mode never reads another part's
 * worker, it asks that part by message). One difference (e->park): a face
 * that asks another rank is parked until the answer comes, and the rank
 * advances its other faces meanwhile, since a round trip between processes
 * (the other rank's next poll, or its next time slice when ranks share
 * cores) is far longer than a face. Parked faces are work, so a rank with
 * any is never idle in the sense of src/par/termination.c, and the proof there
 * is unchanged. Termination is
 * src/par/termination.c's Dijkstra-Scholten over FACESEND/FACERECV, with IAMDONE
 * epoch 1 (a root's tree finished, to rank 0) and epoch 2 (rank 0: every
 * tree finished, to all); the proof at the top of that file never uses
 * shared memory, so it holds between processes as it does between threads.
 *
 * Errors: a rank whose loop fails sends ABORT to every other rank
 * (fdt_eng_set_error in message mode); a rank that receives ABORT leaves its
 * loop, also while it waits for a NODERECV, so no rank waits for ever on a
 * rank that stopped. Every rank therefore leaves its loop, and only then
 * the ranks meet in collectives: an all-gather of each rank's own error
 * decides the run's error (the lowest failing rank's), the same on every
 * rank, before anything is reduced or gathered. A failed run gathers and
 * writes nothing.
 */
#include "mpi/mpi_run.h"

#include <limits.h>
#include <math.h>
#include <stdalign.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "par/engine.h"
#include "mesh/certify.h"
#include "mesh/insert.h"
#include "geom/kdtree.h"
#include "base/mem.h"
#include "front/oracle.h"
#include "front/search.h"
#include "front/probe.h"
#include "par/parallel.h"
#include "geom/partition.h"
#include "par/termination.h"
#include "mpi/transport_mpi.h"

/* A point in the translation and gathers: coordinates and an id. */
typedef struct xrec {
    double x[3];
    uint64_t id;
} xrec;

static const char *err_what(int err)
{
    return err == FDT_ENOMEM   ? "out of memory"
           : err == FDT_ECHECK ? "a mesh failed its certificate (src/mesh/certify.h)"
                               : "inconsistent front";
}

void fdt_mpi_out_free(fdt_mpi_out *out)
{
    free(out->own_ids);
    free(out->own_xyz);
    free(out->all_xyz);
    free(out->all_dupmap);
    out->own_ids = NULL;
    out->own_xyz = NULL;
    out->all_xyz = NULL;
    out->all_dupmap = NULL;
    free(out->rank_counts);
    free(out->rank_tets);
    free(out->rank_times);
    out->rank_times = NULL;
    free(out->all_tets);
    free(out->all_hull);
    free(out->own_tets);
    out->own_tets = NULL;
    free(out->own_hull);
    out->own_hull = NULL;
    out->rank_counts = NULL;
    out->rank_tets = NULL;
    out->all_tets = NULL;
    out->all_hull = NULL;
}

/* Gathers n records of width `width` ids (this rank's, input numbering) to
 * rank 0 into *all (*nall records). Collective. */
static int gather_ids(MPI_Comm comm, int rank, int size, const fdt_vid *mine, size_t n, int width,
                      fdt_vid **all, size_t *nall)
{
    if ((uint64_t)n * (uint64_t)width > INT_MAX)
        n = SIZE_MAX; /* told to everyone: too big for MPI's int counts */
    long long mycount = n == SIZE_MAX ? -1 : (long long)n * width;
    long long *counts = rank == 0 ? malloc((size_t)size * sizeof *counts) : NULL;
    int *ic = rank == 0 ? malloc((size_t)size * sizeof *ic) : NULL;
    int *disp = rank == 0 ? malloc((size_t)size * sizeof *disp) : NULL;
    int err = FDT_OK;
    if (rank == 0 && (!counts || !ic || !disp))
        err = FDT_ENOMEM;
    MPI_Gather(&mycount, 1, MPI_LONG_LONG, counts, 1, MPI_LONG_LONG, 0, comm);
    long long total = 0;
    if (rank == 0 && !err) {
        for (int r = 0; r < size; r++) {
            if (counts[r] < 0 || total + counts[r] > INT_MAX) {
                err = FDT_ETOOBIG;
                break;
            }
            ic[r] = (int)counts[r];
            disp[r] = (int)total;
            total += counts[r];
        }
        if (!err && !(*all = malloc((size_t)(total ? total : 1) * sizeof **all)))
            err = FDT_ENOMEM;
    }
    /* Everyone learns whether rank 0 can take it before anything moves. */
    MPI_Bcast(&err, 1, MPI_INT, 0, comm);
    if (!err) {
        MPI_Gatherv(mine, (int)mycount, MPI_UINT32_T, rank == 0 ? *all : NULL, ic, disp,
                    MPI_UINT32_T, 0, comm);
        if (rank == 0)
            *nall = (size_t)total / (size_t)width;
    }
    free(counts);
    free(ic);
    free(disp);
    return err;
}

/* The lowest rank's nonzero error among every rank's myerr (collective:
 * every rank gets the same), diag naming it and the phase. */
static int first_error(MPI_Comm comm, int size, int myerr, const char *phase, int *err_rank,
                       char *diag, size_t dlen)
{
    int *errs = malloc((size_t)size * sizeof *errs);
    if (!errs) {
        /* cannot take part in the all-gather: end the job */
        snprintf(diag, dlen, "out of memory");
        MPI_Abort(comm, 4);
        return FDT_ENOMEM;
    }
    MPI_Allgather(&myerr, 1, MPI_INT, errs, 1, MPI_INT, comm);
    int err = FDT_OK;
    for (int r = 0; r < size; r++)
        if (errs[r]) {
            err = errs[r];
            *err_rank = r;
            snprintf(diag, dlen, "rank %d failed in the %s: %s", r, phase,
                     err == FDT_EINVAL      ? "invalid setup"
                     : err == FDT_ECANCELED ? "stopped"
                                            : err_what(err));
            break;
        }
    free(errs);
    return err;
}

static int u32_cmp(const void *x, const void *y)
{
    uint32_t a = *(const uint32_t *)x, b = *(const uint32_t *)y;
    return a < b ? -1 : a > b;
}

static int xrec_cmp(const void *x, const void *y)
{
    const xrec *a = x, *b = y;
    return a->id < b->id ? -1 : a->id > b->id;
}

/*
 * Input numbering for cnt global ids src, into dst (collective). A rank
 * knows the input ids of its own points only; those of the other ranks'
 * points its tets use (their vertices across the cuts) it asks their
 * owners for, one MPI_Alltoallv each way, which also brings their
 * coordinates as read. used (may be NULL): every distinct point src uses,
 * by input id ascending, with those coordinates (*nused of them), for a
 * piece of the output.
 */
static int translate(MPI_Comm comm, MPI_Datatype xt, const fdt_mpi_local *L, const uint32_t *src,
                     size_t cnt, fdt_vid *dst, xrec **used, size_t *nused, uint64_t *bytes,
                     char *diag, size_t dlen)
{
    int rank, size;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    uint32_t lo = L->lo, hi = L->lo + (uint32_t)L->nloc;
    size_t nf = 0;
    for (size_t i = 0; i < cnt; i++)
        nf += src[i] < lo || src[i] >= hi;
    uint32_t *F = malloc((nf + 1) * sizeof *F), *Q = NULL;
    int *c = malloc(4 * (size_t)size * sizeof *c);
    xrec *ans = NULL, *got = NULL;
    unsigned char *mark = used ? calloc(L->nloc + 1, 1) : NULL;
    int err = F && c && (!used || mark) ? FDT_OK : FDT_ENOMEM;
    snprintf(diag, dlen, "out of memory translating ids to input numbering");
    if ((err = fdt_mpi_agree(comm, err, diag, dlen)) != FDT_OK)
        goto done;
    nf = 0;
    for (size_t i = 0; i < cnt; i++)
        if (src[i] < lo || src[i] >= hi)
            F[nf++] = src[i];
        else if (mark)
            mark[src[i] - lo] = 1;
    qsort(F, nf, sizeof *F, u32_cmp);
    size_t k = 0;
    for (size_t i = 0; i < nf; i++)
        if (i == 0 || F[i] != F[k - 1])
            F[k++] = F[i];
    nf = k;
    /* sorted ids group by owner, owners in rank order */
    int *sc = c, *sd = c + size, *rc = c + 2 * size, *rd = c + 3 * size;
    for (int q = 0; q < size; q++)
        sc[q] = 0;
    for (size_t i = 0; i < nf; i++)
        sc[fdt_partition_owner(&L->pt, F[i])]++;
    size_t nq = fdt_mpi_counts(comm, sc, sd, rc, rd, sizeof(uint32_t), bytes);
    Q = malloc((nq + 1) * sizeof *Q);
    ans = malloc((nq + 1) * sizeof *ans);
    got = malloc((nf + 1) * sizeof *got);
    err = Q && ans && got ? FDT_OK : FDT_ENOMEM;
    if ((err = fdt_mpi_agree(comm, err, diag, dlen)) != FDT_OK)
        goto done;
    MPI_Alltoallv(F, sc, sd, MPI_UINT32_T, Q, rc, rd, MPI_UINT32_T, comm);
    for (size_t i = 0; i < nq; i++) {
        uint32_t j = Q[i] - lo; /* ours: every asker asked its owner */
        for (int d = 0; d < 3; d++)
            ans[i].x[d] = ldexp(L->p[3 * (size_t)j + d], -L->scale_exp); /* exact */
        ans[i].id = L->orig[j];
        *bytes += sizeof(xrec);
    }
    MPI_Alltoallv(ans, rc, rd, xt, got, sc, sd, xt, comm);
    for (size_t i = 0; i < cnt; i++) {
        uint32_t g = src[i];
        if (g >= lo && g < hi) {
            dst[i] = L->orig[g - lo];
        } else {
            uint32_t *at = bsearch(&g, F, nf, sizeof *F, u32_cmp);
            dst[i] = (fdt_vid)got[at - F].id;
        }
    }
    if (used) {
        size_t nu = nf;
        for (size_t i = 0; i < L->nloc; i++)
            nu += mark[i];
        xrec *u = malloc((nu + 1) * sizeof *u);
        err = u ? FDT_OK : FDT_ENOMEM;
        if ((err = fdt_mpi_agree(comm, err, diag, dlen)) != FDT_OK)
            goto done;
        size_t j = 0;
        for (size_t i = 0; i < L->nloc; i++)
            if (mark[i]) {
                for (int d = 0; d < 3; d++)
                    u[j].x[d] = ldexp(L->p[3 * i + d], -L->scale_exp);
                u[j++].id = L->orig[i];
            }
        memcpy(u + j, got, nf * sizeof *u);
        qsort(u, nu, sizeof *u, xrec_cmp);
        *used = u;
        *nused = nu;
    }
done:
    free(F);
    free(Q);
    free(c);
    free(ans);
    free(got);
    free(mark);
    return err;
}

/* Every input point's coordinates and vertex to rank 0 (collective). */
static int gather_points(MPI_Comm comm, MPI_Datatype xt, const fdt_mpi_local *L, fdt_mpi_out *out,
                         char *diag, size_t dlen)
{
    int rank, size;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    xrec *mine = malloc((L->nin + 1) * sizeof *mine), *all = NULL;
    int *cnt = rank == 0 ? malloc(2 * (size_t)size * sizeof *cnt) : NULL;
    if (rank == 0) {
        all = malloc((L->n + 1) * sizeof *all);
        out->all_xyz = malloc((3 * L->n + 1) * sizeof *out->all_xyz);
        out->all_dupmap = malloc((L->n + 1) * sizeof *out->all_dupmap);
    }
    int err = mine && (rank != 0 || (cnt && all && out->all_xyz && out->all_dupmap)) ? FDT_OK
                                                                                   : FDT_ENOMEM;
    snprintf(diag, dlen, "out of memory gathering the points to rank 0");
    if ((err = fdt_mpi_agree(comm, err, diag, dlen)) == FDT_OK) {
        for (size_t i = 0; i < L->nin; i++) {
            memcpy(mine[i].x, L->in_xyz + 3 * i, sizeof mine[i].x);
            mine[i].id = (uint64_t)(uint32_t)L->in_id[i] | (uint64_t)(uint32_t)L->in_vertex[i] << 32;
        }
        int myn = (int)L->nin;
        MPI_Gather(&myn, 1, MPI_INT, cnt, 1, MPI_INT, 0, comm);
        if (rank == 0)
            for (int q = 0, at = 0; q < size; q++) {
                cnt[size + q] = at;
                at += cnt[q];
            }
        MPI_Gatherv(mine, myn, xt, all, cnt, cnt ? cnt + size : NULL, xt, 0, comm);
        if (rank == 0) {
            for (size_t i = 0; i < L->n; i++) {
                uint32_t id = (uint32_t)all[i].id;
                memcpy(out->all_xyz + 3 * (size_t)id, all[i].x, sizeof all[i].x);
                out->all_dupmap[id] = (fdt_vid)(uint32_t)(all[i].id >> 32);
            }
            out->n_input = L->n;
            out->ndup = L->ndup;
        }
        diag[0] = '\0';
    }
    free(mine);
    free(all);
    free(cnt);
    return err;
}

/*
 * The replica mesh (bench/NOTES.md entry 63): on inputs where the kd
 * search degenerates (pipes, cones, spheres: the empty spheres are as
 * wide as the object), nearly every face's sphere crosses a cut, and the
 * rank that owns it asks the others, who answer with their own degenerate
 * kd searches: a cone of 20,000 points took 20 s on 2 ranks against 0.3 s
 * serial. There every rank builds the DT of every point from an
 * all-gather of the coordinates and reads its faces' apexes from it, as
 * the threads of shared mode read the one mesh they built together
 * (src/par/parallel.c): the ranks still own their points, faces and tets, and
 * still send FACESENDs; no NODESEND is needed. Chosen when a majority of
 * the ranks' probes (fdt_probe_take and _cost over each rank's own points) find
 * the kd search clearly expensive and the replica fits the memory of every
 * node (its ranks counted by MPI_Comm_split_type), a single rank too (its
 * kd search alone is exhaustive on such sets: a sphere of 14,374 points
 * over 2 minutes on one rank, 1.4 s with the mesh); a search whose row
 * does not probe (src/front/search.c: --search kd, mesh) never builds one. A rank that cannot build it (no memory) goes on with
 * its kd search and asks the others: the answers are the same either way
 * (the perturbed DT is unique), so the ranks need not agree after the
 * vote. Collective over comm up to the build: a rank that failed before
 * (e NULL) takes part, voting no and refusing the gather. *P_all gets
 * the gathered coordinates (which e->gmesh borrows) or NULL; *built 1
 * when e->gmesh holds the mesh. Returns FDT_OK (no replica is not an
 * error) or FDT_EINTERNAL (an inconsistent build: a bug).
 */
static int replica_mesh(MPI_Comm comm, const fdt_mpi_local *L, const fdt_mpi_opts *o, engine *e,
                        double **P_all, int *built, double *t_build)
{
    *P_all = NULL;
    *built = 0;
    *t_build = 0.0;
    int size;
    MPI_Comm_size(comm, &size);
    if (!fdt_search_row_of(o->search)->probe || 3 * L->m > (size_t)INT_MAX)
        return FDT_OK;
    int vote = 0, votes = 0;
    if (e) {
        fdt_probe_samples ps;
        fdt_probe_take(&ps, L->p, (uint32_t)L->nloc,
                              o->leaf_size > 0 ? o->leaf_size : FDT_DEFAULT_LEAF);
        vote = fdt_probe_cost(&ps) > FDT_PROBE_REPLICA;
    }
    MPI_Allreduce(&vote, &votes, 1, MPI_INT, MPI_SUM, comm);
    if (2 * votes <= size)
        return FDT_OK;
    /* Every rank of a node holds a replica: the node's MemAvailable
     * shared among them must hold the coordinates and the mesh. */
    MPI_Comm node;
    int on_node = 1;
    if (MPI_Comm_split_type(comm, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node) ==
        MPI_SUCCESS) {
        MPI_Comm_size(node, &on_node);
        MPI_Comm_free(&node);
    }
    size_t avail = fdt_mem_available();
    double need = (24.0 + FDT_ORACLE_MESH_BYTES) * (double)L->m * (double)on_node;
    double *all = NULL;
    int ok = e && (avail == SIZE_MAX || need <= (double)avail);
    if (ok && !(all = malloc(3 * L->m * sizeof *all)))
        ok = 0;
    int *cnt = ok ? malloc(2 * (size_t)size * sizeof *cnt) : NULL;
    if (ok && !cnt)
        ok = 0;
    int all_ok = 0;
    MPI_Allreduce(&ok, &all_ok, 1, MPI_INT, MPI_MIN, comm);
    if (!all_ok) {
        free(all);
        free(cnt);
        return FDT_OK;
    }
    /* Ids are contiguous by rank (src/mpi/mpi_setup.h: rank q holds [start[q],
     * start[q + 1])), so the gather in rank order is the global array. */
    for (int q = 0; q < size; q++) {
        cnt[q] = (int)(3 * (size_t)(L->pt.start[q + 1] - L->pt.start[q]));
        cnt[size + q] = (int)(3 * (size_t)L->pt.start[q]);
    }
    MPI_Allgatherv(L->p, (int)(3 * L->nloc), MPI_DOUBLE, all, cnt, cnt + size, MPI_DOUBLE,
                   comm);
    free(cnt);
    double t0 = fdt_now_s();
    fdt_pred_counts pc;
    memset(&pc, 0, sizeof pc);
    int err = fdt_ins_build(&e->gmesh, all, 0, (uint32_t)L->m, &pc);
    if (err == FDT_OK) {
        /* proved before this rank reads it (issue 31 item 6) */
        fdt_certify_fail why;
        if ((err = fdt_certify(&e->gmesh, &pc, &why)) != FDT_OK) {
            fdt_ins_free(&e->gmesh);
            *t_build = fdt_now_s() - t0;
            free(all);
            return err;
        }
    }
    *t_build = fdt_now_s() - t0;
    if (err == FDT_OK) {
        *P_all = all;
        *built = 1;
        return FDT_OK;
    }
    free(all);
    /* no memory, or (a bug) an inconsistent build: this rank asks the
     * others as before; FDT_EINTERNAL is still an error */
    return err == FDT_EINTERNAL ? err : FDT_OK;
}

/* This rank's engine e (fdt_eng_new'd, every rank's part known, only
 * this rank's worker *w set up): the message mode of src/par, its tets
 * into sink, its seeds. */
static int rank_engine(engine *e, fdt_mpi_local *L, const fdt_mpi_opts *o, int rank, int size,
                       double *P, fdt_vid *orig, fdt_tsink *sink, worker **wp)
{
    fdt_partition *pt = &L->pt;
    int err = FDT_OK;
    e->pt = pt;
    e->P = P;
    e->orig = orig;
    e->sink = sink;
    e->mode = FDT_MODE_MESSAGE;
    e->search = o->search;
    e->msg_term = 1;
    e->park = !o->no_park; /* a round trip crosses processes: park, go on */
    e->fail_part = o->fail_rank;
    e->fail_after = o->fail_after;
    for (int i = 0; i < size; i++) {
        worker *x = &e->w[i];
        x->e = e;
        x->id = i;
        x->tree = &pt->trees[i];
        x->lo = pt->start[i];
        x->hi = pt->start[i + 1];
        x->parent = -1;
        x->aborted_by = -1;
    }
    worker *w = &e->w[rank];
    *wp = w;
    w->st.points = w->hi - w->lo;
    w->st.core = -1;
    w->report_at = 4096;
    /* Our seeds (owner: the part of the lowest id), their foreign
     * vertices delivered with them as a FACESEND would carry them
     * (mpi_setup.c found every seed with its coordinates). Every part
     * holding a seed is a root of Dijkstra-Scholten
     * (src/par/termination.c); every rank counts the roots alike. */
    w->seeds = malloc(((size_t)L->nseeds + 1) * sizeof *w->seeds);
    if (!w->seeds)
        err = FDT_ENOMEM;
    int *has = calloc((size_t)size, sizeof *has);
    if (!has)
        err = FDT_ENOMEM;
    for (int i = 0; !err && i < L->nseeds; i++) {
        const uint32_t *sd = L->seeds[i];
        uint32_t lo = sd[0];
        for (int k = 1; k < 4; k++)
            if (sd[k] < lo)
                lo = sd[k];
        int own = fdt_partition_owner(pt, lo);
        if (!has[own]++)
            e->roots++;
        if (own != rank)
            continue;
        memcpy(w->seeds[w->nseeds++], sd, sizeof w->seeds[0]);
        for (int k = 0; k < 4; k++)
            if (!is_own(w, sd[k]) && fdt_ghost_put(&w->ghosts, sd[k], L->seed_xyz[i] + 3 * k))
                err = FDT_ENOMEM;
    }
    free(has);
    w->engaged = w->nseeds > 0;
    return err;
}

/* The run's statistics (collective): this rank's counts and tets into
 * out; their sums and every rank's, with its front's wall and CPU times,
 * to rank 0, which checks the balance (every kind sent was received). */
static int rank_stats(MPI_Comm comm, int rank, int size, engine *e, worker *w, double wall,
                      double cpu, fdt_mpi_out *out, char *diag, size_t dlen)
{
    fdt_mailbox_counts mc;
    fdt_tp_counts(e->tp, rank, &mc);
    memcpy(out->sent, mc.sent, sizeof out->sent);
    memcpy(out->received, mc.received, sizeof out->received);
    out->tets = w->out.ntets;
    uint64_t both[2 * FDT_MSG_KIND_END];
    memcpy(both, mc.sent, sizeof mc.sent);
    memcpy(both + FDT_MSG_KIND_END, mc.received, sizeof mc.received);
    if (rank == 0) {
        out->rank_counts = malloc((size_t)size * sizeof both);
        out->rank_tets = malloc((size_t)size * sizeof *out->rank_tets);
        out->rank_times = malloc((size_t)size * FDT_MPI_NTIMES * sizeof *out->rank_times);
    }
    int oom = rank == 0 && (!out->rank_counts || !out->rank_tets || !out->rank_times);
    MPI_Bcast(&oom, 1, MPI_INT, 0, comm);
    if (oom) {
        snprintf(diag, dlen, "rank 0: out of memory for the statistics");
        return FDT_ENOMEM;
    }
    MPI_Gather(both, 2 * FDT_MSG_KIND_END, MPI_UINT64_T, out->rank_counts,
               2 * FDT_MSG_KIND_END, MPI_UINT64_T, 0, comm);
    /* Where each rank's time went (--stats): the setup's phases
     * (src/mpi/mpi_setup.h), then the front: the wait timers of
     * src/par/protocol.c (t_idle: nothing to do; t_query_wait: blocked on
     * answers) beside its CPU time. */
    double tm[FDT_MPI_NTIMES] = {wall, cpu, w->st.t_idle, w->st.t_query_wait,
                                 (double)w->st.faces_advanced};
    MPI_Gather(tm, FDT_MPI_NTIMES, MPI_DOUBLE, out->rank_times, FDT_MPI_NTIMES, MPI_DOUBLE, 0,
               comm);
    uint64_t nt = w->out.ntets, *rt = NULL;
    if (rank == 0 && !(rt = malloc((size_t)size * sizeof *rt)))
        MPI_Abort(comm, 4);
    MPI_Gather(&nt, 1, MPI_UINT64_T, rt, 1, MPI_UINT64_T, 0, comm);
    if (rank == 0) {
        for (size_t r = 0; r < (size_t)size; r++)
            out->rank_tets[r] = (size_t)rt[r];
        free(rt);
    }
    MPI_Reduce(mc.sent, out->all_sent, FDT_MSG_KIND_END, MPI_UINT64_T, MPI_SUM, 0, comm);
    MPI_Reduce(mc.received, out->all_received, FDT_MSG_KIND_END, MPI_UINT64_T, MPI_SUM, 0,
               comm);
    return FDT_OK;
}

/* This rank's tets in input numbering (collective): the set hash, whose
 * partial sums add over ranks (src/base/sethash.h), and the outputs: the
 * rank's own tets (o->keep_own: a piece, the Voronoi cells), the mesh
 * gathered to rank 0 (o->gather), or both. *minep: the renumbered tets,
 * the caller's to free unless out->own_tets took them (then NULL). */
static int rank_output(MPI_Comm comm, MPI_Datatype xt, const fdt_mpi_local *L,
                       const fdt_mpi_opts *o, worker *w, int rank, int size, fdt_vid **minep,
                       fdt_mpi_out *out, char *diag, size_t dlen)
{
    size_t n4 = 4 * w->out.ntets, n3 = 3 * w->out.nhull;
    fdt_vid *mine = *minep = malloc((n4 > n3 ? n4 : n3) * sizeof *mine + 1);
    int merr = mine ? FDT_OK : FDT_ENOMEM, any = 0;
    MPI_Allreduce(&merr, &any, 1, MPI_INT, MPI_MIN, comm);
    if (any) {
        snprintf(diag, dlen, "out of memory renumbering the tets");
        return FDT_ENOMEM;
    }
    xrec *used = NULL;
    size_t nused = 0;
    int with_pts = (o->keep_own & FDT_MPI_OWN_POINTS) != 0;
    int err = translate(comm, xt, L, w->out.tets, n4, mine, with_pts ? &used : NULL, &nused,
                        &out->bytes_out, diag, dlen);
    if (err)
        return err;
    fdt_sethash h = {0, 0};
    fdt_sethash_add_n(&h, (const uint32_t *)mine, w->out.ntets);
    uint64_t hv[2] = {h.sum, h.count}, hs[2] = {0, 0};
    /* Sums mod 2^64: MPI_SUM on unsigned integers wraps as C's does. */
    MPI_Reduce(hv, hs, 2, MPI_UINT64_T, MPI_SUM, 0, comm);
    out->hash.sum = hs[0];
    out->hash.count = hs[1];
    if (o->gather) {
        err = gather_ids(comm, rank, size, mine, w->out.ntets, 4, &out->all_tets, &out->ntets);
        if (err) {
            free(used);
            snprintf(diag, dlen, "%s gathering the mesh to rank 0",
                     err == FDT_ETOOBIG ? "too many tets (MPI int counts)" : "out of memory");
            return err;
        }
    }
    if (o->keep_own) {
        out->own_tets = mine;
        out->own_ntets = w->out.ntets;
        *minep = NULL;
        err = FDT_OK;
        if (with_pts) {
            /* the points those tets use (.vtu pieces, the cells) */
            out->own_ids = malloc((nused + 1) * sizeof *out->own_ids);
            out->own_xyz = malloc((3 * nused + 1) * sizeof *out->own_xyz);
            err = out->own_ids && out->own_xyz ? FDT_OK : FDT_ENOMEM;
            for (size_t i = 0; !err && i < nused; i++) {
                out->own_ids[i] = (fdt_vid)used[i].id;
                memcpy(out->own_xyz + 3 * i, used[i].x, sizeof used[i].x);
            }
            out->own_npts = nused;
        }
        if (!err && (o->keep_own & FDT_MPI_OWN_HULL)) /* .fdtb, .ele pieces, the cells */
            err = (out->own_hull = malloc((n3 + 1) * sizeof *out->own_hull)) ? FDT_OK
                                                                               : FDT_ENOMEM;
        free(used);
        snprintf(diag, dlen, "out of memory for this rank's own tets");
        if ((err = fdt_mpi_agree(comm, err, diag, dlen)) != FDT_OK)
            return err;
        if (o->keep_own & FDT_MPI_OWN_HULL) {
            err = translate(comm, xt, L, w->out.hull, n3, out->own_hull, NULL, NULL,
                            &out->bytes_out, diag, dlen);
            out->own_nhull = w->out.nhull;
            if (err)
                return err;
        }
    } else {
        free(used);
    }
    if (o->gather) {
        /* the hull faces: translated above, else into mine while it is
         * still ours, else into a buffer of their own */
        fdt_vid *hb = out->own_hull ? out->own_hull : !o->keep_own ? mine : NULL;
        fdt_vid *tmp = NULL;
        if (!hb) {
            tmp = malloc((n3 + 1) * sizeof *tmp);
            err = tmp ? FDT_OK : FDT_ENOMEM;
            snprintf(diag, dlen, "out of memory gathering the mesh to rank 0");
            if ((err = fdt_mpi_agree(comm, err, diag, dlen)) != FDT_OK)
                return err;
            hb = tmp;
        }
        if (!out->own_hull)
            err = translate(comm, xt, L, w->out.hull, n3, hb, NULL, NULL, &out->bytes_out, diag,
                            dlen);
        if (!err)
            err = gather_ids(comm, rank, size, hb, w->out.nhull, 3, &out->all_hull,
                             &out->nhull);
        free(tmp);
        if (err)
            snprintf(diag, dlen, "%s gathering the mesh to rank 0",
                     err == FDT_ETOOBIG ? "too many tets (MPI int counts)" : "out of memory");
        if (!err)
            err = gather_points(comm, xt, L, out, diag, dlen);
    }
    return err;
}

int fdt_mpi_run(MPI_Comm comm, fdt_mpi_local *L, const fdt_mpi_opts *o, fdt_mpi_out *out,
                char *diag, size_t dlen)
{
    memset(out, 0, sizeof *out);
    out->err_rank = -1;
    int rank, size;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    double t0 = fdt_now_s();
    engine *e = NULL;
    fdt_vid *mine = NULL;
    double *P_all = NULL; /* the replica mesh's coordinates (replica_mesh) */
    MPI_Datatype xt;
    MPI_Type_contiguous((int)sizeof(xrec), MPI_BYTE, &xt);
    MPI_Type_commit(&xt);
    /* This rank's points by global id (mpi_setup.c: it holds ids [lo, lo
     * + nloc) only, and nothing reads another id of P or orig). */
    double *P = L->p - 3 * (size_t)L->lo;
    fdt_vid *orig = L->orig - L->lo;
    /* The rank's tets stay in its meshbuf (tree-order ids) for the output
     * below: the in-memory sink (src/front/sink.h). */
    fdt_tsink mem_sink;
    int mem_sink_ok = 0;
    int err = FDT_OK;
    if (size > FDT_PARTITION_MAX || size > FDT_MAILBOX_MAX_THREADS || L->m < 4 ||
        L->m > UINT32_MAX - 1)
        err = FDT_EINVAL;
    if (!err) {
        err = fdt_tsink_init(&mem_sink, orig, NULL);
        mem_sink_ok = err == FDT_OK;
    }
    if (!err && !(e = fdt_eng_new(size)))
        err = FDT_ENOMEM;
    worker *w = NULL;
    if (!err)
        err = rank_engine(e, L, o, rank, size, P, orig, &mem_sink, &w);
    /* The transport is made by every rank (MPI_Comm_dup is collective). */
    fdt_transport *tp = NULL;
    int terr = fdt_transport_mpi(&tp, comm);
    if (e)
        e->tp = tp;
    if (!err && terr)
        err = terr;
    /* Collective: every rank takes part (one that failed votes no). */
    int replica = 0;
    int rerr = replica_mesh(comm, L, o, err ? NULL : e, &P_all, &replica, &out->t_replica);
    if (!err)
        err = rerr;
    if (!err && replica)
        e->gmesh_ok = 1;
    if (!err)
        err = fdt_eng_worker_setup(w);
    /* Every rank's setup succeeded, or no rank runs: a rank whose setup
     * failed could not answer the others' NODESENDs. */
    err = first_error(comm, size, err, "setup", &out->err_rank, diag, dlen);
    double t1 = fdt_now_s(), c1 = fdt_thread_cpu_s();
    if (!err) {
        int rc = fdt_eng_worker_loop(w);
        /* ABORT to every other rank, unless an ABORT stopped us */
        if (rc < 0)
            fdt_eng_set_error(e, rc, rank, err_what(rc));
        /* Every rank has left its loop (top of file): the run's error,
         * our own (recorded by fdt_eng_set_error) or 0. */
        err = first_error(comm, size, w->err, "run", &out->err_rank, diag, dlen);
    }
    double t2 = fdt_now_s(), c2 = fdt_thread_cpu_s();
    if (err) {
        if (tp)
            fdt_transport_mpi_abandon(tp);
        goto done;
    }
    if ((err = rank_stats(comm, rank, size, e, w, t2 - t1, c2 - c1, out, diag, dlen)) != FDT_OK)
        goto done;
    err = rank_output(comm, xt, L, o, w, rank, size, &mine, out, diag, dlen);
done:
    out->t_setup = t1 - t0;
    out->t_front = t2 - t1;
    out->t_out = fdt_now_s() - t2;
    free(mine);
    if (e) {
        if (w) {
            /* the only worker set up; the others are zero */
            fdt_eng_worker_free(w);
            free(w->seeds);
        }
        fdt_ins_free(&e->gmesh);
        fdt_eng_delete(e);
    }
    free(P_all);
    fdt_transport_destroy(&tp);
    if (mem_sink_ok)
        fdt_tsink_free(&mem_sink);
    MPI_Type_free(&xt);
    if (err)
        fdt_mpi_out_free(out);
    return err;
}
