/*
 * The distributed output of frontdt-mpi (issue 19): each rank writes its
 * own piece of the mesh, in input numbering, and rank 0 a small index,
 * with no gather of the mesh to one rank. Built only with MPI.
 *
 *   -o BASE.pvtu   BASE_RANK.vtu (the rank's tets over the points they
 *                  use) and the ParaView index BASE.pvtu
 *   -o BASE.pfdtb  BASE_RANK.fdtb (.fdtb with flag 8: the rank's tets and
 *                  hull faces, no points, ids numbering the input's
 *                  points) and the text index BASE.pfdtb
 *   -o BASE.pele   BASE.node written by every rank at once (each its
 *                  range of input ids, at its byte offset: the serial
 *                  run's .node, byte for byte), BASE_RANK.ele and
 *                  BASE_RANK.face (TetGen rows numbering that .node) and
 *                  the text index BASE.pele
 *
 * The text index (README, "Distributed runs"): a line "frontdt-pieces 1",
 * then "KEY VALUE" lines: format, input, points, duplicates, ranks, node
 * (.pele only), one "piece NAME TETS HULL" a rank in rank order, "total
 * TETS HULL", "set-hash HEX". Names are relative to the index's directory.
 *
 * All or nothing: every file goes through a temporary renamed at its end
 * (src/io/write/writer.c); the index is written last, once every piece is there,
 * and if any rank fails every piece (and the .node) is removed again on
 * every rank. Until then an interrupt removes them: the writer's signal
 * cleanup (fdt_write_cleanup) does, as for its own temporaries.
 */
#ifndef FDT_MPI_OUTPUT_H
#define FDT_MPI_OUTPUT_H

#include <mpi.h>
#include <stddef.h>
#include <stdio.h>
#include <stdint.h>

#include "base/sethash.h"
#include "io/write/formats.h"
#include "io/write/writer.h"
#include "mesh/periodic.h"
#include "mpi/mpi_run.h"
#include "mpi/mpi_setup.h"

enum {
    FDT_MPO_GATHER = 0, /* any other -o: gathered to rank 0 */
    FDT_MPO_VTU,        /* .pvtu */
    FDT_MPO_BIN,        /* .pfdtb */
    FDT_MPO_ELE         /* .pele */
};

/* The kind of output path names, by its extension (case-insensitive). */
int fdt_mpo_kind(const char *path);

/* The k-th file (0..2) a run with size ranks writes for the index path
 * other than the index itself, into out: the pieces in rank order, then
 * (.pele) the .node. 1, 0 when there is no k-th file, or -1 when a name
 * does not fit len. For the CLI's check that none is the input. */
int fdt_mpo_file(const char *path, int size, size_t k, char *out, size_t len);

typedef struct fdt_mpo_args {
    const char *path;       /* the index */
    const char *input;      /* the input as named on the command line */
    int fail_rank;          /* a test's injected failure: this rank's
                               piece write fails after its temporary is
                               written; -1: none */
} fdt_mpo_args;

/*
 * A rank's share of a piece output, whatever run made it (the plain
 * engine's below; a periodic run's, src/cli/mpi_main.c): what the index
 * says of the input and of this rank, and how this rank's piece is
 * written.
 */
typedef struct fdt_mpo_share {
    uint64_t n_input, ndup; /* the input's points and merged duplicates */
    uint64_t ntets, nhull;  /* this rank's rows */
    fdt_sethash hash;       /* rank 0: the run's set hash (the index's) */
    int periodic;           /* the rows are a periodic mesh's: the .vtu
                               pieces carry each point's input id */
    /* Writes this rank's k files (names: the piece, then .pele's .face),
     * each through a temporary renamed at its end; an FDT_ code, the
     * message in diag. */
    int (*piece)(void *user, char (*names)[FDT_IO_PATH], int k, char *diag, size_t dlen);
    /* .pele: the collective .node into name (every rank); NULL refuses
     * .pele (FDT_EINVAL before anything is written). */
    int (*node)(MPI_Comm comm, const char *name, void *user, uint64_t *io, char *diag,
                size_t dlen);
    void *user;
} fdt_mpo_share;

/* A .pfdtb piece into name (src/io/write/formats.h's fdt_put_bin_piece),
 * through a temporary renamed at its end: an FDT_ code, the message in
 * diag. */
int fdt_mpo_bin_piece(const char *name, uint64_t n_input, const fdt_vid *tets, size_t nt,
                      const fdt_vid *hull, size_t nh, const fdt_bin_periodic *per, char *diag,
                      size_t dlen);

/* A periodic run's .vtu piece into name: its nt rows (input ids, offsets)
 * laid out as frontdt lays out a periodic .vtu (src/mesh/periodic.h's
 * fdt_periodic_unfold over the n input points xyz and the box b), with only
 * the points they use, each with its input_id. An FDT_ code, the message
 * in diag. */
int fdt_mpo_periodic_vtu(const char *name, const fdt_vid *tets, const int8_t *off, size_t nt,
                         const double *xyz, size_t n, const fdt_periodic_box *b, char *diag,
                         size_t dlen);

/* The pieces and the index of share s (collective), as fdt_mpo_write. */
int fdt_mpo_write_share(MPI_Comm comm, const fdt_mpo_args *a, const fdt_mpo_share *s, int *mine,
                        uint64_t io[2], char *diag, size_t dlen);

/*
 * Writes the pieces and the index (collective). r: the run's output with
 * keep_own (FDT_MPI_OWN_POINTS for .pvtu, FDT_MPI_OWN_HULL otherwise) and,
 * on rank 0, the reduced set hash; L: the setup's (keep_input for .pele).
 * Returns the same code on every rank: FDT_OK, FDT_ENOMEM or FDT_EIO;
 * *mine is this rank's own error (its message in diag) or FDT_OK when
 * another rank failed. On failure nothing of the output is left. io: the
 * bytes this rank wrote to files, and sent to other ranks (the .node's
 * exchange), for --stats.
 */
int fdt_mpo_write(MPI_Comm comm, const fdt_mpo_args *a, const fdt_mpi_local *L,
                  const fdt_mpi_out *r, int *mine, uint64_t io[2], char *diag, size_t dlen);

/*
 * One text file written by the ranks together (collective): each rank's
 * len bytes, written by put(user, f) to a stream f already at the offset
 * of the ranks' before it (an MPI_Exscan; put returns 0 or an errno, and
 * must write exactly len bytes). Rank 0 creates the temporary
 * (src/io/write/writer.c: the usual rename and signal cleanup), every
 * rank writes into it, and rank 0 renames it to name only once every
 * rank's bytes are in: the file is complete, or nothing is renamed. The
 * same code on every rank (FDT_OK, FDT_EIO, FDT_ENOMEM), the failing
 * rank's message in diag; io[0] gains the bytes this rank wrote. The .node
 * of a .pele, and the Voronoi cells' tables (src/mpi/mpi_cells.h).
 */
int fdt_mpo_text(MPI_Comm comm, const char *name, int (*put)(void *, FILE *), void *user,
                 uint64_t len, uint64_t *io, char *diag, size_t dlen);

#endif
