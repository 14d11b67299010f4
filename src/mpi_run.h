/*
 * One rank of a distributed run (issue 19; Merriam §3-§5): the message-mode
 * engine's per-part loop (src/engine.c) on one part, the other parts on the
 * other ranks of the communicator, nothing shared but messages (the MPI
 * transport, src/transport_mpi.c). Built only with MPI.
 *
 * Setup, first stage: every rank holds the whole prepared input and
 * computes the same deterministic partition (coordinate bisection, one part
 * per rank), the same kd-trees and the same seeds (src/parallel.c's
 * fdt_par_make_seeds), but triangulates only its own part: its search reads
 * its own points alone, and other parts' points reach it only in
 * NODESEND/NODERECV/FACESEND payloads, exactly as message mode between
 * threads. The setup of §3.1 (each rank reading a slice, bisection by
 * exchanging points between rank pairs, seeds without a global tree) is
 * the next stage; only the setup changes then, not the run.
 */
#ifndef FDT_MPI_RUN_H
#define FDT_MPI_RUN_H

#include <mpi.h>
#include <stddef.h>
#include <stdint.h>

#include "frontdt.h"
#include "prepare.h"
#include "sethash.h"

typedef struct fdt_mpi_opts {
    int leaf_size;       /* 0: the default */
    int search;          /* fdt_search */
    int gather;          /* nonzero: every tet and hull face to rank 0 */
    int keep_own;        /* nonzero (not with gather): this rank's tets in
                            input numbering stay in out->own_tets */
    int fail_rank;       /* a test's injected failure: rank fail_rank fails
                            (FDT_EINTERNAL) once it advanced fail_after
                            faces; -1: none */
    size_t fail_after;
    int no_park;         /* nonzero: a face waits for each NODERECV (the
                            threaded message mode's loop) instead of
                            being parked (src/engine.c) */
} fdt_mpi_opts;

enum { FDT_MPI_NTIMES = 5 };

typedef struct fdt_mpi_out {
    /* On every rank: */
    int err_rank;        /* the failing rank (lowest), -1: none */
    size_t tets;         /* this rank's tets */
    uint64_t sent[FDT_MSG_KIND_END], received[FDT_MSG_KIND_END]; /* this rank */
    double t_setup, t_front, t_out; /* seconds, this rank */
    fdt_vid *own_tets;     /* keep_own: 4 per tet, input numbering (owned) */
    size_t own_ntets;
    /* On rank 0 only (reduced over the ranks): */
    fdt_sethash hash;
    uint64_t all_sent[FDT_MSG_KIND_END], all_received[FDT_MSG_KIND_END];
    uint64_t *rank_counts; /* size * 2 * FDT_MSG_KIND_END: each rank's sent
                              then received (owned) */
    size_t *rank_tets;     /* size (owned) */
    double *rank_times;    /* size * FDT_MPI_NTIMES (owned): each rank's
                              front wall and CPU seconds, seconds blocked
                              idle and blocked with faces waiting on
                              answers, faces advanced (owned) */
    fdt_vid *all_tets;     /* gather: 4 per tet, input numbering (owned) */
    size_t ntets;
    fdt_vid *all_hull;     /* gather: 3 per hull face, outward (owned) */
    size_t nhull;
} fdt_mpi_out;

/*
 * Triangulates pr (the same prepared points on every rank; permuted in
 * place into partition order) with one part per rank of comm. Collective:
 * every rank calls it and every rank returns the same code: FDT_OK, or the
 * failing rank's error (FDT_ENOMEM, FDT_EINTERNAL, FDT_ETOOBIG for a gather
 * beyond MPI's int counts), with diag saying which rank and why. On
 * failure out holds nothing and no rank has output.
 */
int fdt_mpi_run(MPI_Comm comm, fdt_prepared *pr, const fdt_mpi_opts *o, fdt_mpi_out *out,
                char *diag, size_t dlen);
void fdt_mpi_out_free(fdt_mpi_out *out);

#endif
