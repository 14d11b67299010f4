/*
 * What the mesh writers' interface (src/io/write/writer.h) and the formats
 * (src/io/write/formats.h) share: the mesh a writer is given, and the
 * limits of one output's set of files.
 */
#ifndef FDT_MESHVIEW_H
#define FDT_MESHVIEW_H

#include <stddef.h>
#include <stdint.h>
#include "frontdt.h"

typedef struct fdt_mesh_view {
    const double *xyz;       /* 3 * n_points input coordinates (borrowed) */
    size_t n_points;         /* input points, duplicates included */
    const fdt_vid *tets;     /* 4 per tet, input numbering, positive */
    size_t n_tets;
    const fdt_tid *nbrs;     /* 4 per tet or NULL (required for .ele) */
    const fdt_vid *hull;     /* 3 per hull face, outward */
    size_t n_hull;
    /* The face list of fdt_result_faces, or NULL (required by the formats
     * whose row needs FDT_NEED_FACES, and by all_faces). */
    const fdt_vid *faces;    /* 3 per face, tets[2i] on the positive side */
    const fdt_tid *face_tets;/* 2 per face, -1 on the hull */
    size_t n_faces;
    int all_faces;           /* TetGen .face: every face (TetGen -f) */
    /* A periodic mesh (fdt_result_tet_offsets), or NULL: 12 offsets a
     * tet and 9 a hull face, whose rows are then ids ascending, not
     * oriented, and the periods (hi - lo rounded; 0 on an axis that is not
     * periodic); .tets and .fdtb. */
    const int8_t *tet_off, *hull_off;
    double period[3];
    /* A periodic mesh laid out in space (fdt_periodic_unfold), or NULL:
     * point i's input id, the formats' map back (.vtu, .vtk, .msh), and
     * its image offsets (3 a point), which pair an OpenFOAM mesh's cyclic
     * faces; period as above. */
    const fdt_vid *point_src;
    const int8_t *point_off;
} fdt_mesh_view;

/* The longest path the writer takes (its temporary names live in fixed
 * buffers a signal handler can read), and the most files one output
 * family writes (an OpenFOAM polyMesh: five). */
#define FDT_IO_PATH 4096
#define FDT_IO_MAX_FILES 5

#endif
