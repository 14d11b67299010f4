/*
 * The distributed setup of a run over MPI (issue 19; Merriam §3.1): each
 * rank reads its slice of the input, the ranks bisect the points by
 * exchanging them (recursive coordinate bisection, any rank count), merge
 * their duplicates where the exchange brought them together, and each
 * rank builds its own part's kd-tree and finds its seed without any
 * global structure. What a rank holds afterwards is its own part alone
 * (and the bisection's boxes, a few per rank): the input of src/mpi/mpi_run.c.
 * Built only with MPI.
 */
#ifndef FDT_MPI_SETUP_H
#define FDT_MPI_SETUP_H

#include <mpi.h>
#include <stddef.h>
#include <stdint.h>

#include "frontdt.h"
#include "geom/partition.h"

typedef struct fdt_mpi_setup_opts {
    const char *input;   /* the path ("-": standard input) */
    const char *format;  /* --input-format, or NULL: by extension */
    int leaf_size;       /* 0: the default */
    int keep_input;      /* nonzero: keep every input point this rank held
                            after the exchange (for -o's gather) */
} fdt_mpi_setup_opts;

/* Phases of the setup, timed on each rank (fdt_mpi_local.t). */
enum {
    FDT_MPI_T_READ,
    FDT_MPI_T_EXCHANGE,
    FDT_MPI_T_MERGE,
    FDT_MPI_T_TREES,
    FDT_MPI_T_SEEDS,
    FDT_MPI_T_END
};

typedef struct fdt_mpi_local {
    /* This rank's part: its distinct points, scaled by 2^scale_exp, in
     * its tree's order; global id lo + i is p[3 i..3 i + 2], input point
     * orig[i]. */
    double *p;           /* 3 nloc (owned) */
    fdt_vid *orig;       /* nloc (owned) */
    size_t nloc;
    uint32_t lo;         /* start of this rank's ids: pt.start[rank] */
    fdt_partition pt;    /* every part's id range and box; this rank's
                            tree only (the others are empty) */
    /* Every rank's seed (deduplicated, the same list on every rank), the
     * coordinates of its four vertices (scaled) beside it. */
    uint32_t (*seeds)[4];
    double (*seed_xyz)[12];
    int nseeds;
    size_t n;            /* input points, all ranks */
    size_t m;            /* distinct points, all ranks */
    size_t ndup;         /* input points merged into an earlier one */
    int scale_exp;
    int sliced;          /* how the input was read: 1 each rank its byte
                            range of a text file, 2 its vertices of a
                            binary PLY, 3 rank 0 standard input (scattered),
                            0 every rank the whole input (other formats) */
    /* keep_input: every input point this rank held after the exchange,
     * duplicates included: its input id, its vertex (the input id it was
     * merged into, itself if none) and its coordinates as read. */
    fdt_vid *in_id, *in_vertex;
    double *in_xyz;
    size_t nin;
    double t[FDT_MPI_T_END]; /* seconds of each phase, this rank */
    uint64_t bytes_sent; /* bytes this rank sent in the setup's exchanges */
} fdt_mpi_local;

/*
 * The setup, collective over comm: every rank returns the same code,
 * FDT_OK or the lowest failing rank's error (FDT_EINVAL: a usage error
 * such as an unknown extension; FDT_EIO, FDT_EFORMAT: the input, naming
 * the file and line; FDT_EDEGENERATE: fewer than 4 distinct points, or
 * all of them collinear or coplanar; FDT_ENOMEM, FDT_ETOOBIG; FDT_EINTERNAL),
 * with that rank's message in diag on every rank. On failure L holds
 * nothing.
 */
int fdt_mpi_setup(MPI_Comm comm, const fdt_mpi_setup_opts *o, fdt_mpi_local *L, char *diag,
                  size_t dlen);
void fdt_mpi_local_free(fdt_mpi_local *L);

/* The lowest rank's nonzero err over comm, its diag copied to every rank
 * (collective). */
int fdt_mpi_agree(MPI_Comm comm, int err, char *diag, size_t dlen);

/* The counts of an MPI_Alltoallv over comm (collective): from the send
 * counts sc (records to each rank), the send displacements sd and, through
 * an MPI_Alltoall, the receive counts rc and displacements rd, each
 * displacement the prefix sum in rank order. Adds to *bytes the bytes
 * sent to the other ranks, rec_size a record. Returns the records
 * received (the sum of rc). */
size_t fdt_mpi_counts(MPI_Comm comm, const int *sc, int *sd, int *rc, int *rd, size_t rec_size,
                      uint64_t *bytes);

/* The blocks of input ids by which the ranks write input-ordered files
 * (a .pele's .node, the Voronoi cells' tables): rank q takes the ids
 * [n q / size, n (q + 1) / size) of the n input points. The start of q's
 * block, and the rank whose block holds id (id < n). */
size_t fdt_mpi_block_start(uint64_t n, int size, int q);
int fdt_mpi_block_owner(uint64_t n, int size, uint64_t id);

#endif
