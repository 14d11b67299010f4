/*
 * The parallel engine (§3-§5; DESIGN.md, Ownership, Termination, The two
 * modes, Mailboxes): one thread per partition, each advancing the front
 * faces it owns, in shared mode (range queries read every partition) or in
 * message mode (range queries on another partition travel as
 * NODESEND/NODERECV). The result equals the serial engine's tet for tet.
 */
#ifndef FDT_PARALLEL_H
#define FDT_PARALLEL_H

#include <stddef.h>
#include <stdint.h>
#include "frontdt.h"
#include "front/front.h"
#include "geom/partition.h"
#include "geom/prepare.h"

typedef struct fdt_par_out {
    fdt_meshbuf mb;            /* every tet, input numbering (pr->orig of the
                                  tree-order ids); neighbours (if asked) in
                                  this meshbuf's tet numbering */
    fdt_front_stats fst;       /* work counters summed over the threads */
    fdt_stats pst;             /* only the parallel fields (sent .. pinned) */
    fdt_thread_stats *tstats;  /* nthreads entries (owned until taken) */
    int nthreads;
    int engine;                /* FDT_ENGINE_PARTS, _PARTS_MESH or _WALLS */
    double t_setup;            /* seconds: partition, kd-trees, seed tets */
    double t_front;            /* seconds: the threads' run */
    double t_gather;           /* seconds: gathering the threads' tets */
} fdt_par_out;

/* How a run is carried out beyond the settings (tests). */
typedef struct fdt_par_opts {
    int shuffle;        /* nonzero: the test transport of src/par/transport.h,
                           which delays and reorders messages across
                           senders, instead of the mailboxes */
    uint64_t seed;      /* its schedule */
    int delay_pct;      /* its delay, 0..90 */
    int fail;           /* nonzero: part fail_part fails (FDT_EINTERNAL)
                           once it has advanced fail_after faces */
    int fail_part;
    size_t fail_after;
    int global_mesh;    /* nonzero: build the DT of every point first
                           (fdt_ins_build_parallel, on nthreads threads)
                           and let every part read its apexes from it
                           (in message mode as a replica), whatever the
                           search; --search auto does it by itself where
                           it fits (src/par/parallel.c, global_mesh) */
    struct fdt_tsink *sink; /* where the tets go (src/front/sink.h); NULL: into
                           out->mb. A sink with a caller's fdt_sink streams:
                           out->mb stays empty, nothing is gathered, and
                           each thread flushes its batches itself */
    int park;           /* message mode: park a face that waits for a
                           NODERECV, as MPI ranks do (src/par/engine.c), so
                           the shuffle tests run that loop too */
} fdt_par_opts;

/*
 * Triangulates the prepared points (pr->p and pr->orig are permuted into
 * partition and tree order, as fdt_kd_build does for the serial engine)
 * with nthreads threads (1..1024) in mode FDT_MODE_SHARED or
 * FDT_MODE_MESSAGE, using s's leaf_size, neighbors, pin and progress, and opt
 * (NULL: none, what it does).
 * Precondition: the points span 3-D space. On success out holds the mesh;
 * on failure out is empty and diag says why. Returns FDT_OK, FDT_EINVAL,
 * FDT_ENOMEM, FDT_ETHREAD, FDT_ECANCELED or FDT_EINTERNAL.
 */
int fdt_parallel_run(fdt_prepared *pr, const fdt_settings *s, fdt_mode mode, int nthreads,
                     const fdt_par_opts *opt, fdt_par_out *out, char *diag, size_t dlen);

/* Copies the parallel fields (sent .. pinned, threads, mode) into st. */
void fdt_parallel_fill_stats(const fdt_par_out *o, fdt_mode mode,
                             fdt_stats *st);

/* Frees what out still owns (mb, tstats). */
void fdt_par_out_free(fdt_par_out *out);

#endif
