/*
 * Mesh writers for the CLI and tests (not part of the library API).
 * Every file is written to a temporary file in the same directory and
 * renamed over the target only when complete: an interrupted or failed run
 * leaves no partial output. fdt_io_cleanup_temps() is async-signal-safe and
 * removes every temporary file still open (for SIGINT/SIGTERM handlers).
 */
#ifndef FDT_WRITER_H
#define FDT_WRITER_H

#include <stddef.h>
#include "frontdt.h"

typedef struct fdt_mesh_view {
    const double *xyz;       /* 3 * n_points input coordinates (borrowed) */
    size_t n_points;         /* input points, duplicates included */
    const fdt_vid *tets;     /* 4 per tet, input numbering, positive */
    size_t n_tets;
    const fdt_tid *nbrs;     /* 4 per tet or NULL (required for .ele) */
    const fdt_vid *hull;     /* 3 per hull face, outward */
    size_t n_hull;
} fdt_mesh_view;

/*
 * Writes the mesh in the format given by path's extension:
 *   .tets  canonical text: one tet per line, its 4 ids ascending, lines in
 *          ascending order. The tets must already be in canonical order
 *          (fdt_result_sort); this is verified, not assumed.
 *   .ele   TetGen: BASE.node, BASE.ele, BASE.face, BASE.neigh, 0-based.
 *   .vtu   VTK XML UnstructuredGrid (ParaView), every input point.
 *   .vtk   VTK legacy unstructured grid.
 * Returns FDT_IO_OK or an FDT_IO_* code with a message in err.
 */
int fdt_write_mesh(const char *path, const fdt_mesh_view *m, char *err,
                   size_t errlen);

/* Removes every temporary output file not yet renamed. Async-signal-safe. */
void fdt_io_cleanup_temps(void);

#endif
