/*
 * The Voronoi cells of a distributed run (issue 32; frontdt-mpi --voronoi
 * and --density). A point's cell needs its whole star, and under MPI a
 * star's tets are built by several ranks, so each rank sends every tet it
 * built, with the points it uses, to the ranks that own its vertices.
 * Rank q owns the input ids of its block (fdt_mpi_block_start: the block
 * a .pele's .node is written by), computes their cells from their stars
 * with the streamed cells' batches (src/mesh/voronoi.h, fdt_voronoi_batch:
 * a cell from its own tets alone, the bits of frontdt's in-memory cells),
 * and the ranks write each table together, each its block's rows at its
 * offset (fdt_mpo_text, src/mpi/mpi_output.h). No rank holds more than its
 * own tets, its block's stars and a spool of its block's rows. Built only
 * with MPI.
 */
#ifndef FDT_MPI_CELLS_H
#define FDT_MPI_CELLS_H

#include <mpi.h>
#include <stddef.h>
#include <stdint.h>

#include "mpi/mpi_run.h"
#include "mpi/mpi_setup.h"

typedef struct fdt_mpi_cells_opts {
    const char *voronoi; /* the cells' table, or NULL */
    const char *format;  /* its --voronoi-format (checked); NULL: CSV */
    const char *density; /* the densities' table, or NULL */
    int box_given;       /* clip by box, not the points' bounding box */
    double box[6];
    int neighbors;       /* the format lists neighbours (%n, %f) */
    unsigned skip;       /* what the tables do not read (fdt_voronoi_options.skip) */
} fdt_mpi_cells_opts;

typedef struct fdt_mpi_cells_stats {
    double t;            /* seconds, this rank: the exchange, the cells, the tables */
    size_t star_tets;    /* tets this rank's block's stars hold */
    uint64_t bytes_sent; /* to other ranks */
    uint64_t bytes_written;
} fdt_mpi_cells_stats;

/*
 * The tables of o (collective). L: the setup's, with keep_input (each
 * input point's vertex and coordinates); r: the run's, with keep_own
 * FDT_MPI_OWN_POINTS | FDT_MPI_OWN_HULL. Every rank returns the same code,
 * the failing rank's message in diag: FDT_OK; FDT_EINVAL (a point outside
 * o's box: the least such input id, as frontdt names it); FDT_ERANGE (the
 * cells are beyond doubles, or a Delaunay edge is too short for them: the
 * least such edge over all ranks, frontdt's message); FDT_ENOMEM;
 * FDT_ETOOBIG (more records for a rank than MPI's int counts); FDT_EIO
 * (a table not written: nothing of it is left); FDT_EINTERNAL.
 */
int fdt_mpi_cells(MPI_Comm comm, const fdt_mpi_local *L, const fdt_mpi_out *r,
                  const fdt_mpi_cells_opts *o, fdt_mpi_cells_stats *st, char *diag, size_t dlen);

#endif
