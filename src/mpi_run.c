/*
 * One rank of a distributed run; see mpi_run.h.
 *
 * The run on a rank is the message-mode worker of src/engine.c: an engine
 * whose e->n parts are the ranks, of which this rank fills only its own
 * worker (the others stay zero: message mode never reads another part's
 * worker, it asks that part by message). One difference (e->park): a face
 * that asks another rank is parked until the answer comes, and the rank
 * advances its other faces meanwhile, since a round trip between processes
 * (the other rank's next poll, or its next time slice when ranks share
 * cores) is far longer than a face. Parked faces are work, so a rank with
 * any is never idle in the sense of src/termination.c, and the proof there
 * is unchanged. Termination is
 * src/termination.c's Dijkstra-Scholten over FACESEND/FACERECV, with IAMDONE
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
#include "mpi_run.h"

#include <limits.h>
#include <stdalign.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "clock.h"
#include "engine.h"
#include "parallel.h"
#include "partition.h"
#include "termination.h"
#include "transport_mpi.h"

static const char *err_what(int err)
{
    return err == FDT_ENOMEM ? "out of memory" : "inconsistent front";
}

void fdt_mpi_out_free(fdt_mpi_out *out)
{
    free(out->rank_counts);
    free(out->rank_tets);
    free(out->rank_times);
    out->rank_times = NULL;
    free(out->all_tets);
    free(out->all_hull);
    free(out->own_tets);
    out->own_tets = NULL;
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

int fdt_mpi_run(MPI_Comm comm, fdt_prepared *pr, const fdt_mpi_opts *o, fdt_mpi_out *out,
                char *diag, size_t dlen)
{
    memset(out, 0, sizeof *out);
    out->err_rank = -1;
    int rank, size;
    MPI_Comm_rank(comm, &rank);
    MPI_Comm_size(comm, &size);
    double t0 = fdt_now_s();
    fdt_partition pt;
    memset(&pt, 0, sizeof pt);
    engine *e = NULL;
    uint32_t(*seeds)[4] = NULL;
    int nseeds = 0;
    fdt_kdq kq0;
    memset(&kq0, 0, sizeof kq0);
    fdt_vid *mine = NULL;
    /* The rank's tets stay in its meshbuf (tree-order ids) for the output
     * below: the in-memory sink (src/sink.h). */
    fdt_tsink mem_sink;
    int mem_sink_ok = 0;
    int err = FDT_OK;
    if (size > FDT_PARTITION_MAX || size > FDT_MAILBOX_MAX_THREADS || pr->m < 4 ||
        pr->m > UINT32_MAX - 1)
        err = FDT_EINVAL;
    /* The setup is deterministic (the same points, the same partition,
     * trees and seeds on every rank: mpi_run.h), so it fails alike on every
     * rank but for memory; its errors join the run's below. */
    if (!err)
        err = fdt_partition_build(&pt, pr->p, pr->orig, (uint32_t)pr->m, size,
                                  o->leaf_size > 0 ? o->leaf_size : FDT_DEFAULT_LEAF, 1);
    if (!err)
        err = fdt_par_make_seeds(&pt, &seeds, &nseeds, &kq0);
    if (!err) {
        err = fdt_tsink_init(&mem_sink, pr->orig, NULL);
        mem_sink_ok = err == FDT_OK;
    }
    if (!err && !(e = fdt_eng_new(size)))
        err = FDT_ENOMEM;
    worker *w = NULL;
    if (!err) {
        e->pt = &pt;
        e->P = pr->p;
        e->orig = pr->orig;
        e->sink = &mem_sink;
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
            x->tree = &pt.trees[i];
            x->lo = pt.start[i];
            x->hi = pt.start[i + 1];
            x->parent = -1;
            x->aborted_by = -1;
        }
        w = &e->w[rank];
        w->st.points = w->hi - w->lo;
        w->st.core = -1;
        w->report_at = 4096;
        /* Our seeds (owner: the part of the lowest id), their foreign
         * vertices delivered with them as a FACESEND would carry them. Every
         * part holding a seed is a root of Dijkstra-Scholten
         * (src/termination.c); every rank counts the roots alike. */
        w->seeds = malloc(((size_t)nseeds + 1) * sizeof *w->seeds);
        if (!w->seeds)
            err = FDT_ENOMEM;
        int *has = calloc((size_t)size, sizeof *has);
        if (!has)
            err = FDT_ENOMEM;
        for (int i = 0; !err && i < nseeds; i++) {
            uint32_t lo = seeds[i][0];
            for (int k = 1; k < 4; k++)
                if (seeds[i][k] < lo)
                    lo = seeds[i][k];
            int own = fdt_partition_owner(&pt, lo);
            if (!has[own]++)
                e->roots++;
            if (own != rank)
                continue;
            memcpy(w->seeds[w->nseeds++], seeds[i], sizeof seeds[i]);
            for (int k = 0; k < 4; k++)
                if (!is_own(w, seeds[i][k]) &&
                    fdt_ghost_put(&w->ghosts, seeds[i][k], pr->p + 3 * (size_t)seeds[i][k]))
                    err = FDT_ENOMEM;
        }
        free(has);
        w->engaged = w->nseeds > 0;
    }
    /* The transport is made by every rank (MPI_Comm_dup is collective). */
    fdt_transport *tp = NULL;
    int terr = fdt_transport_mpi(&tp, comm);
    if (e)
        e->tp = tp;
    if (!err && terr)
        err = terr;
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

    /* Statistics: this rank's counts; their sums and every rank's to rank
     * 0, which checks the balance (every kind sent was received). */
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
        err = FDT_ENOMEM;
        snprintf(diag, dlen, "rank 0: out of memory for the statistics");
        goto done;
    }
    MPI_Gather(both, 2 * FDT_MSG_KIND_END, MPI_UINT64_T, out->rank_counts,
               2 * FDT_MSG_KIND_END, MPI_UINT64_T, 0, comm);
    /* Where each rank's front time went (--stats): the wait timers of
     * src/protocol.c (t_idle: nothing to do; t_query_wait: blocked on
     * answers) beside its CPU time. */
    double tm[FDT_MPI_NTIMES] = {t2 - t1, c2 - c1, w->st.t_idle, w->st.t_query_wait,
                                 (double)w->st.faces_advanced};
    MPI_Gather(tm, FDT_MPI_NTIMES, MPI_DOUBLE, out->rank_times, FDT_MPI_NTIMES, MPI_DOUBLE, 0,
               comm);
    uint64_t nt = w->out.ntets, *rt = NULL;
    if (rank == 0 && !(rt = malloc((size_t)size * sizeof *rt)))
        MPI_Abort(comm, 4);
    MPI_Gather(&nt, 1, MPI_UINT64_T, rt, 1, MPI_UINT64_T, 0, comm);
    if (rank == 0) {
        for (int r = 0; r < size; r++)
            out->rank_tets[r] = (size_t)rt[r];
        free(rt);
    }
    MPI_Reduce(mc.sent, out->all_sent, FDT_MSG_KIND_END, MPI_UINT64_T, MPI_SUM, 0, comm);
    MPI_Reduce(mc.received, out->all_received, FDT_MSG_KIND_END, MPI_UINT64_T, MPI_SUM, 0,
               comm);

    /* Our tets in input numbering (pr->orig, permuted with the points):
     * the set hash, whose partial sums add over ranks (src/sethash.h), and
     * the gather. */
    size_t n4 = 4 * w->out.ntets, n3 = 3 * w->out.nhull;
    mine = malloc((n4 > n3 ? n4 : n3) * sizeof *mine + 1);
    int merr = mine ? FDT_OK : FDT_ENOMEM, any = 0;
    MPI_Allreduce(&merr, &any, 1, MPI_INT, MPI_MIN, comm);
    if (any) {
        err = FDT_ENOMEM;
        snprintf(diag, dlen, "out of memory renumbering the tets");
        goto done;
    }
    fdt_sink_renumber(pr->orig, mine, w->out.tets, n4);
    fdt_sethash h = {0, 0};
    fdt_sethash_add_n(&h, (const uint32_t *)mine, w->out.ntets);
    uint64_t hv[2] = {h.sum, h.count}, hs[2] = {0, 0};
    /* Sums mod 2^64: MPI_SUM on unsigned integers wraps as C's does. */
    MPI_Reduce(hv, hs, 2, MPI_UINT64_T, MPI_SUM, 0, comm);
    out->hash.sum = hs[0];
    out->hash.count = hs[1];
    if (o->keep_own && !o->gather) {
        out->own_tets = mine;
        out->own_ntets = w->out.ntets;
        mine = NULL;
    } else if (o->gather) {
        err = gather_ids(comm, rank, size, mine, w->out.ntets, 4, &out->all_tets, &out->ntets);
        if (!err) {
            fdt_sink_renumber(pr->orig, mine, w->out.hull, n3);
            err = gather_ids(comm, rank, size, mine, w->out.nhull, 3, &out->all_hull,
                             &out->nhull);
        }
        if (err)
            snprintf(diag, dlen, "%s gathering the mesh to rank 0",
                     err == FDT_ETOOBIG ? "too many tets (MPI int counts)" : "out of memory");
    }
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
        fdt_eng_delete(e);
    }
    fdt_transport_destroy(&tp);
    if (mem_sink_ok)
        fdt_tsink_free(&mem_sink);
    free(seeds);
    fdt_partition_free(&pt);
    if (err)
        fdt_mpi_out_free(out);
    return err;
}
