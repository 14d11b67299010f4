/*
 * The CLI's uses of the mesh's dual (issue 32), one step of src/cli/main.c's
 * run: the Voronoi cells (--voronoi FILE, --voronoi-format, --density FILE,
 * --box) and interpolation (--values FILE --interpolate QUERIES
 * --interpolated OUT [--method natural|linear]). The numbers come from the
 * library (fdt_voronoi_compute, fdt_interpolate), the text from
 * src/io/write/cells.c; the files go through the run's commit set, so they
 * are renamed with the mesh, all or none.
 */
#ifndef FDT_CLI_DUAL_H
#define FDT_CLI_DUAL_H

#include <stddef.h>

#include "frontdt.h"

typedef struct fdt_cli_dual {
    const char *voronoi; /* --voronoi FILE, or NULL */
    const char *format;  /* --voronoi-format, or NULL: CSV for a .csv file,
                            else FDT_CELLS_DEFAULT_FORMAT */
    const char *density; /* --density FILE, or NULL */
    int threads;         /* the run's threads (0: one per physical core; 1
                            in serial mode), set after the options */
    int box_given;       /* --box given */
    double box[6];       /* xmin, ymin, zmin, xmax, ymax, zmax */
    const char *values;  /* --values FILE, or NULL */
    const char *queries; /* --interpolate QUERIES, or NULL */
    const char *interpolated; /* --interpolated OUT, or NULL */
    int natural;         /* --method: 1 natural (default), 0 linear */
    int dual;            /* --dual: OpenFOAM outputs get the Voronoi cells */
} fdt_cli_dual;

/* --dual's output: the Voronoi cells of res clipped by d's box, as an
 * OpenFOAM polyMesh at path (in the run's commit set). FDT_OK, or the
 * error with the message in err: FDT_EINVAL (a point outside --box),
 * FDT_ENOMEM, FDT_ETOOBIG, FDT_EINTERNAL (a diagram this construction
 * cannot number: nothing written), FDT_EIO. */
int fdt_cli_dual_mesh(const fdt_cli_dual *d, fdt_result *res, const double *xyz, size_t n,
                      const char *path, char *err, size_t errlen);

/* The exit code (src/cli/cli.h) of an error of the cells' or the dual's
 * steps: a file they could not write, a malformed file they read, else as
 * the engine's. */
int fdt_cli_dual_exit(int err);

/* The message of the cells' error r (diag: the library's) into err:
 * "WHAT: the error: diag", or "WHAT: diag" for FDT_ERANGE, where diag says
 * all (the cells', not a coordinate's range). */
void fdt_cli_cells_message(const char *what, int r, const char *diag, char *err, size_t errlen);

/* The cells' table d asks for: 1 when --voronoi names a .vtu file (VTK
 * polyhedra, with neighbours); else 0, *format its text format (NULL:
 * CSV, for a .csv file; --voronoi-format or FDT_CELLS_DEFAULT_FORMAT
 * otherwise) and *neighbors whether that format lists neighbours. *skip:
 * what neither that table nor --density reads (fdt_voronoi_options.skip). */
int fdt_cli_cells_table(const fdt_cli_dual *d, const char **format, int *neighbors,
                        unsigned *skip);

/* Is anything asked for? */
int fdt_cli_dual_wanted(const fdt_cli_dual *d);

/* --box "xmin,ymin,zmin,xmax,ymax,zmax": 0, or -1 (not six finite numbers
 * with each min below its max) with the usage message in err (both
 * programs'). */
int fdt_cli_parse_box(const char *s, double box[6], char *err, size_t errlen);

/* Checks the options before the run (input: the input file, or NULL for
 * --demo or standard input): 0, or -1 with the reason in err (a usage
 * error: a missing partner option, a bad format, an output that is the
 * input or one of the files read). */
int fdt_cli_dual_check(const fdt_cli_dual *d, const char *input, char *err, size_t errlen);

/*
 * Streamed cells (--stream with --voronoi or --density, issue 32): the
 * batches of fdt_voronoi_stream spooled (src/io/write/cells.h), the tables
 * written in input order once the run is whole.
 *
 * fdt_cli_dual_stream_refusal: why d cannot stream (NULL: it can).
 * fdt_cli_cells_open: the spool for n points beside the first table, the
 *   options and the sink to give fdt_voronoi_stream; FDT_OK, or FDT_EIO /
 *   FDT_ENOMEM with err.
 * fdt_cli_cells_failed: nonzero, with err, when the spool failed (the
 *   run then stopped as canceled).
 * fdt_cli_cells_write: the tables into the open commit set, as
 *   fdt_cli_dual_write's.
 */
typedef struct fdt_cli_cells fdt_cli_cells;
const char *fdt_cli_dual_stream_refusal(const fdt_cli_dual *d);
int fdt_cli_cells_open(const fdt_cli_dual *d, size_t n, fdt_cli_cells **out,
                       fdt_voronoi_options *o, fdt_cell_sink *sink, char *err, size_t errlen);
int fdt_cli_cells_failed(const fdt_cli_cells *c, char *err, size_t errlen);
/* The spool itself (src/io/write/cells.h): frontdt-mpi's periodic cells
 * add the other ranks' rows to rank 0's. */
struct fdt_cells_spool *fdt_cli_cells_spool(fdt_cli_cells *c);
int fdt_cli_cells_write(const fdt_cli_dual *d, fdt_cli_cells *c, char *err, size_t errlen);
void fdt_cli_cells_close(fdt_cli_cells **c);

/* Computes the cells of res (the result of triangulating xyz[0 .. 3n))
 * and writes the files into the open commit set. 0, or an FDT_E* code
 * with the message in err: FDT_EINVAL (a point outside --box), FDT_ENOMEM,
 * FDT_EIO (a file could not be written), FDT_EINTERNAL. */
int fdt_cli_dual_write(const fdt_cli_dual *d, const fdt_result *res, const double *xyz, size_t n,
                       char *err, size_t errlen);

/* Interpolation wanted? */
int fdt_cli_interp_wanted(const fdt_cli_dual *d);

/* Reads the values and the queries, interpolates on `threads` threads and
 * writes --interpolated into the open commit set. 0, or FDT_EFORMAT (a
 * file read is malformed), FDT_EIO, FDT_ENOMEM, FDT_EINTERNAL, with the
 * message in err. */
int fdt_cli_interp_write(const fdt_cli_dual *d, fdt_result *res, const double *xyz, size_t n,
                         char *err, size_t errlen);

#endif
