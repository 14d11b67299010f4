/*
 * One rank of a distributed run (issue 19; Merriam §3-§5): the message-mode
 * engine's per-part loop (src/par/engine.c) on one part, the other parts on the
 * other ranks of the communicator, nothing shared but messages (the MPI
 * transport, src/mpi/transport_mpi.c). Built only with MPI.
 *
 * Setup: src/mpi/mpi_setup.c (§3.1): each rank holds its own part alone (its
 * points, ids [lo, lo + nloc) in partition order, its kd-tree), the
 * bisection's boxes and every seed, and triangulates only its own part:
 * other parts' points reach it only in NODESEND/NODERECV/FACESEND
 * payloads, exactly as message mode between threads. After the run a
 * rank translates its tets' ids to input numbering by asking the owners
 * of their foreign vertices (translate() in mpi_run.c).
 */
#ifndef FDT_MPI_RUN_H
#define FDT_MPI_RUN_H

#include <mpi.h>
#include <stddef.h>
#include <stdint.h>

#include "frontdt.h"
#include "mpi/mpi_setup.h"
#include "base/sethash.h"

typedef struct fdt_mpi_opts {
    int leaf_size;       /* 0: the default */
    int search;          /* fdt_search */
    int gather;          /* nonzero: every tet and hull face to rank 0 */
    int keep_own;        /* FDT_MPI_OWN_* (not with gather): this rank's
                            tets in input numbering stay in out->own_tets,
                            with the points they use (.vtu pieces) or
                            with its hull faces (.fdtb and .ele pieces) */
    int fail_rank;       /* a test's injected failure: rank fail_rank fails
                            (FDT_EINTERNAL) once it advanced fail_after
                            faces; -1: none */
    size_t fail_after;
    int no_park;         /* nonzero: a face waits for each NODERECV (the
                            threaded message mode's loop) instead of
                            being parked (src/par/engine.c) */
} fdt_mpi_opts;

enum { FDT_MPI_NTIMES = 5 };
enum { FDT_MPI_OWN_POINTS = 1, FDT_MPI_OWN_HULL = 2 };

typedef struct fdt_mpi_out {
    /* On every rank: */
    int err_rank;        /* the failing rank (lowest), -1: none */
    size_t tets;         /* this rank's tets */
    uint64_t sent[FDT_MSG_KIND_END], received[FDT_MSG_KIND_END]; /* this rank */
    double t_setup, t_front, t_out; /* seconds, this rank */
    double t_replica;    /* seconds building the replica mesh (0: none;
                            src/mpi/mpi_run.c, replica_mesh) */
    fdt_vid *own_tets;     /* keep_own: 4 per tet, input numbering (owned) */
    size_t own_ntets;
    fdt_vid *own_ids;      /* keep_own: the input ids of the points those
                              tets use, ascending (owned) */
    double *own_xyz;       /* keep_own: their coordinates as read, 3 each
                              (owned) */
    size_t own_npts;
    fdt_vid *own_hull;     /* keep_own & FDT_MPI_OWN_HULL: this rank's hull
                              faces, 3 each, outward, input numbering
                              (owned) */
    size_t own_nhull;
    uint64_t bytes_out;    /* bytes this rank sent translating ids */
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
    double *all_xyz;       /* gather: every input point as read, 3 each
                              (owned) */
    fdt_vid *all_dupmap;   /* gather: each input point's vertex (owned) */
    size_t n_input, ndup;
} fdt_mpi_out;

/*
 * Triangulates the points of the ranks of comm, each rank's part being
 * its L (src/mpi/mpi_setup.h; its tree's arrays are read, not changed).
 * Collective: every rank calls it and every rank returns the same code:
 * FDT_OK, or the failing rank's error (FDT_ENOMEM, FDT_EINTERNAL,
 * FDT_ETOOBIG for a gather beyond MPI's int counts), with diag saying
 * which rank and why. On failure out holds nothing and no rank has output.
 */
int fdt_mpi_run(MPI_Comm comm, fdt_mpi_local *L, const fdt_mpi_opts *o, fdt_mpi_out *out,
                char *diag, size_t dlen);
void fdt_mpi_out_free(fdt_mpi_out *out);

#endif
