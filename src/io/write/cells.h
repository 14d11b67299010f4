/*
 * The Voronoi cells as text (issue 32; the CLI's --voronoi and --density):
 * one line a point, in input order, from an fdt_voronoi (include/frontdt.h)
 * or from a stream's batches.
 *
 * A --voronoi-format string is voro++'s custom output (its -c option):
 * text, with these codes replaced for each point (doc/reference.md):
 *   %i the point's index (0-based input order)  %x %y %z %q its coordinates
 *   %v volume  %F surface area  %s number of faces  %n neighbours (walls
 *   -1..-6)  %f the faces' areas, in %n's order  %c centroid relative to
 *   the point  %C centroid  %d DTFE density  %h flags (1 clipped, 2 hull,
 *   4 merged duplicate)  %% a percent sign
 * Numbers are written with 17 significant digits (they read back exactly).
 */
#ifndef FDT_CELLS_H
#define FDT_CELLS_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "frontdt.h"

/* The format used when none is given. */
#define FDT_CELLS_DEFAULT_FORMAT "%i %q %v %F %s %n %f"

/* 0 when fmt is a valid format; else -1 and a message in err. *needs_nbrs
 * (may be NULL) says whether it lists neighbours (%n, %f). */
int fdt_cells_format_check(const char *fmt, int *needs_nbrs, char *err, size_t errlen);

/* The quantities the tables do not read, as fdt_voronoi_options.skip
 * bits: FDT_CELLS_NO_CENTROIDS unless the cells' table is CSV (csv) or its
 * format fmt (NULL: no cells' table) has %c or %C; FDT_CELLS_NO_DENSITIES
 * unless it is CSV, fmt has %d, or the densities' table is written too
 * (density). The writers refuse (EINVAL) a table that reads what the
 * cells left out. */
unsigned fdt_cells_table_skip(const char *fmt, int csv, int density);

/* Writes the cells in format fmt (checked), or as CSV (fmt NULL: a header
 * line, then id,x,y,z,volume,area,faces,cx,cy,cz,density,flags), the
 * text formatted on `threads` threads (1: the caller's alone). Returns 0,
 * or the errno of a failed write (the stream's error flag set). */
int fdt_wr_cells(FILE *f, const char *fmt, const fdt_voronoi *v, const double *xyz, int threads);

/* Writes the DTFE density of each point: "density flags" a line (flags as
 * %h: a hull point's density counts only the tets it has), as
 * fdt_wr_cells does. */
int fdt_wr_density(FILE *f, const fdt_voronoi *v, int threads);

/* The directory of path into dir ("." for a bare name): where the
 * temporaries of a table at path go, on the file system that must hold
 * the table anyway. */
void fdt_cells_dir(const char *path, char *dir, size_t len);
/* An unlinked temporary file in dir, open for reading and writing (gone
 * with the process, whatever happens): the tables' spools, and a periodic
 * stream's .tets rows (src/io/write/fmt_tets.c); NULL with errno. */
FILE *fdt_cells_temp(const char *dir);

/*
 * The tables of a streamed run (fdt_voronoi_stream's batches, in any
 * order), or of one MPI rank's block of input ids (src/mpi/mpi_cells.c),
 * written in input order at the end: each batch's rows formatted as they
 * come into a spool (an unlinked temporary in dir: a record a row, the
 * two tables' text) with each input id's offset (8 bytes a point), then
 * each table copied out in input order. The spool holds the rows of the
 * input ids [base, base + n); fmt: the cells' format (NULL: none), csv:
 * CSV instead; density: the density table too. The calls return 0 or an
 * errno; EINVAL when a batch has a row outside [base, base + n) or one
 * already spooled, or lacks what the tables read (fdt_cells_table_skip), or, from
 * fdt_cells_spool_put, when a point's row never came.
 */
typedef struct fdt_cells_spool fdt_cells_spool;
int fdt_cells_spool_open(fdt_cells_spool **sp, size_t base, size_t n, const char *fmt, int csv,
                         int density, const char *dir);
int fdt_cells_spool_add(fdt_cells_spool *sp, const fdt_voronoi *v);
/* table 0: the cells' (fmt or CSV, its header line first when header is
 * nonzero); 1: the densities. */
int fdt_cells_spool_put(fdt_cells_spool *sp, int table, int header, FILE *f);
/* The spooled rows in input order, each handed to fn as a record: its
 * input id and its two tables' text, l[0] and l[1] bytes one after the
 * other at text (valid during the call). Stops at fn's first nonzero
 * return, which it returns; else 0, or an errno. For frontdt-mpi's
 * periodic cells, whose ranks send their rows to rank 0. */
int fdt_cells_spool_each(fdt_cells_spool *sp,
                         int (*fn)(void *user, size_t id, const uint32_t l[2], const char *text),
                         void *user);
/* A record as fdt_cells_spool_each hands it, spooled: 0 or an errno
 * (EINVAL as fdt_cells_spool_add's). */
int fdt_cells_spool_add_row(fdt_cells_spool *sp, size_t id, const uint32_t l[2], const char *text);
/* The bytes fdt_cells_spool_put writes of that table (every row come). */
uint64_t fdt_cells_spool_bytes(const fdt_cells_spool *sp, int table, int header);
void fdt_cells_spool_close(fdt_cells_spool **sp);

/* The cells as VTK polyhedra (a .vtu file, VTK_POLYHEDRON cells with
 * their faces, ParaView's reader): one cell a distinct point, cell data
 * "point" (its index) and "volume". v needs its neighbours
 * (options.neighbors). All polyhedra are made first (about 2 KB a cell),
 * then written as appended raw arrays. 0, an errno of the write, or a
 * negative FDT_E* code of fdt_voronoi_polyhedron. */
int fdt_wr_cells_vtu(FILE *f, fdt_voronoi *v, const double *xyz);

/* rows lines of k numbers each (NaN as "nan"): the interpolated values. */
int fdt_wr_rows(FILE *f, const double *v, size_t rows, size_t k);

#endif
