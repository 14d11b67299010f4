/*
 * The Voronoi diagram of a result's points clipped by a box, as one
 * polyhedral mesh with shared vertices and faces (issue 32: the dual
 * written as an OpenFOAM polyMesh, src/io/write/fmt_foam.c). Built by
 * src/mesh/dualmesh.c from the tets; doc/design.md, "The dual as a
 * polyhedral mesh".
 *
 * One cell per point that is not a merged duplicate, numbered in input
 * order (cell_of); a face per pair of cells whose Voronoi face has an
 * area inside the box, and a face per cell and box wall it touches.
 * OpenFOAM's order: the internal faces first, by owner then neighbour
 * (owner < neighbour), each face's vertices counter-clockwise seen from
 * its neighbour (the right-hand normal points out of the owner); then the
 * six walls' faces (patches xmin, xmax, ymin, ymax, zmin, zmax), each by
 * owner, their normals out of the box.
 */
#ifndef FDT_DUALMESH_H
#define FDT_DUALMESH_H

#include <stddef.h>
#include <stdint.h>

#include "frontdt.h"

/* A cyclic patch of a periodic dual (src/mesh/dualperiodic.h): its faces'
 * translates by sep (shift periods) are its partner's faces, face i of one
 * the partner of face i of the other, listed from the same point. */
typedef struct fdt_dual_cyclic {
    int shift[3];         /* periods to the partner */
    double sep[3];        /* the translation to the partner */
    size_t start, size;   /* its faces */
} fdt_dual_cyclic;

typedef struct fdt_dualmesh {
    size_t n_verts;
    double *xyz;          /* 3 a vertex (owned) */
    size_t n_cells;
    size_t n_faces, n_internal;
    size_t *fstart;       /* n_faces + 1 offsets into fverts (owned) */
    int32_t *fverts;      /* owned */
    int32_t *owner;       /* n_faces (owned) */
    int32_t *neighbour;   /* n_internal (owned) */
    size_t patch_start[6], patch_size[6];
    size_t n_input;
    int32_t *cell_of;     /* n_input: a point's cell, -1 for a merged
                             duplicate (owned) */
    double box[6];        /* xmin, ymin, zmin, xmax, ymax, zmax */
    /* A periodic dual: the axes without walls (bit k: axis k; their two
     * walls' patches are empty and not written), and after the walls'
     * faces the cyclic patches, partners in pairs (2k, 2k + 1). 0 and
     * none for a dual clipped by a box. */
    unsigned periodic;
    size_t n_cyclic;
    fdt_dual_cyclic *cyclic; /* owned */
} fdt_dualmesh;

/* The patches' names, in the order of the walls: xmin, xmax, ymin, ... */
extern const char *const fdt_dualmesh_patch[6];

/*
 * The dual of r (the result of fdt_triangulate on the n points xyz, with
 * its tets; not changed: a face list derived for the neighbours when r
 * keeps none is dropped again, as r had none), clipped
 * by o's box rule (fdt_voronoi_box_of; o not NULL). On success *d is
 * filled and owned by the caller (fdt_dualmesh_free) and has passed
 * fdt_dualmesh_check. FDT_EINVAL (a streamed result, n not r's, a bad
 * box or a point outside it), FDT_ERANGE (two points closer than doubles
 * can hold the cells between: under 2^-40 of their coordinates or 2^-300
 * of the box), FDT_ETOOBIG (more than OpenFOAM's 32-bit
 * labels hold), FDT_ENOMEM, FDT_EINTERNAL (the clipped diagram came out
 * failing fdt_dualmesh_check: a configuration this construction cannot
 * number, never written; diag says which cell and edge), each with diag
 * written ("" on success).
 */
int fdt_dualmesh_build(fdt_result *r, const double *xyz, size_t n,
                       const fdt_voronoi_options *o, fdt_dualmesh *d, char *diag,
                       size_t diag_size);
/* The same without the check, for a dual that is checked once folded
 * (fdt_dualmesh_fold, src/mesh/dualperiodic.h: the check was a quarter of
 * a periodic --dual's time, bench/NOTES.md entry 124). */
int fdt_dualmesh_build_unchecked(fdt_result *r, const double *xyz, size_t n,
                                 const fdt_voronoi_options *o, fdt_dualmesh *d, char *diag,
                                 size_t diag_size);
void fdt_dualmesh_free(fdt_dualmesh *d);

/*
 * The check (src/mesh/dualcheck.c, sharing nothing with the construction):
 * an independent check of a dual's numbering: every vertex used and every
 * index in range, no face with fewer than 3 or repeated vertices, owner <
 * neighbour, the internal faces in upper-triangular order (two faces of
 * one pair of cells side by side, as OpenFOAM allows: a face pinched by
 * rounding is cut in two, src/mesh/dualmesh.c's split_loops), the patches
 * contiguous after them by owner, every cell closed (each of its edges in
 * two of its faces, once each way round when the faces are turned out of
 * the cell) and of positive volume, every wall face on its wall and each
 * wall's faces covering it once (their areas, turned out of the box, add
 * up to the wall's to 1e-9); in a periodic dual, the walls of its periodic
 * axes empty and each cyclic pair's faces translates of each other, from
 * the same point, turned the other way (to 1e-6 of the face's size). 0,
 * -1 with the first fault in diag, or FDT_ENOMEM (nothing was checked).
 */
int fdt_dualmesh_check(const fdt_dualmesh *d, char *diag, size_t diag_size);

/* fdt_dualmesh_check in a frame scaled by a power of two in which the
 * box's largest side is about 1 (cells of 1e-150 wide sets have volumes
 * beyond doubles in their own), d moved back after it exactly. */
int fdt_dualmesh_check_scaled(fdt_dualmesh *d, char *diag, size_t diag_size);

/* Whether face g (gv[0 .. gm), read from position z) is face f (fv[0 ..
 * m)) moved by sep, from the same point and turned the other way (each a
 * face turned out of its own cell), its vertices within 1e-6 of f's size
 * and the two areas within 1e-5 of each other: what OpenFOAM's
 * translational cyclic patches need (they match to 1e-4). */
int fdt_dual_faces_match(const double *xyz, const int32_t *fv, size_t m, const int32_t *gv,
                         size_t gm, size_t z, const double sep[3]);

/* Cell c's volume from its faces (the divergence theorem on the faces'
 * fans), for checks. */
double fdt_dualmesh_cell_volume(const fdt_dualmesh *d, const size_t *cell_faces_start,
                                const size_t *cell_faces, size_t c);

/* The faces of each cell: *start (n_cells + 1 offsets) into *faces
 * (malloc'd both; free them). FDT_OK or FDT_ENOMEM. */
int fdt_dualmesh_cell_faces(const fdt_dualmesh *d, size_t **start, size_t **faces);

#endif
