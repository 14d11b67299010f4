/*
 * A part's own mesh, built, certified and handed to the sink (issue 31,
 * "one engine"; bench/NOTES.md entry 87).
 *
 * The part triangulates its points by incremental insertion
 * (src/mesh/insert.c), proves the result is their perturbed Delaunay
 * tetrahedralization (src/mesh/certify.h), and emits its tets at once:
 * a tet is final when no point outside the part can lie in or on its
 * circumsphere. With one part (src/api/api.c's one_part: a serial run of
 * --search auto or mesh, or a threaded one of --search auto in the
 * default mode, whose threads build the mesh together) that is every tet:
 * the mesh is the answer, and no front re-derives it. The hull faces are
 * the faces of the infinite tets, outward.
 *
 * With several parts (the wall engine, --search mesh on threads:
 * src/par/engine.c) the tets whose circumsphere stays in the part go out
 * at once and the fronts stitch the walls between parts.
 */
#ifndef FDT_PARTMESH_H
#define FDT_PARTMESH_H

#include <stddef.h>
#include <stdint.h>

#include "front/sink.h"
#include "geom/kdtree.h"
#include "mesh/insert.h"

/* Bytes a point the one-part engine holds at its peak besides the points:
 * the insertion mesh (32 bytes a slot, about 6.7 slots a point, and its
 * incident-tet table) with the build's scratch; the output tets reuse the
 * mesh's array. The CLI's --memory-limit estimate uses it. */
#define FDT_PARTMESH_BYTES 235.0
/* The factor on it when the mesh is built on several threads: their slots
 * are reserved up front (src/mesh/insert.h), though not all touched; 1M
 * uniform points at two threads peaked at 1.05 times the serial run. */
#define FDT_PARTMESH_PAR 1.1

/* What the one-part engine did, for fdt_stats. */
typedef struct fdt_partmesh_stats {
    size_t final_tets;     /* tets emitted straight from the mesh */
    size_t certified_tets; /* finite tets the certificate checked */
    double t_mesh;         /* seconds building the mesh */
    double t_certify;      /* seconds certifying it */
    fdt_pred_counts pc;    /* exact predicate calls of both */
    fdt_ins_stats ins;     /* the build's counts */
} fdt_partmesh_stats;

/*
 * Marks the final tets of a part's certified mesh m: the finite tets whose
 * circumsphere (a conservative ball, src/geom/kdtree.c) lies strictly
 * inside the region of the part's tree t, the part's bisection cell
 * (fdt_kd_set_region; infinite on the hull's sides). No point of another
 * part lies in such a cell's interior, so none lies in or on the sphere:
 * the tet is a tet of the perturbed DT of all the points, final before
 * any other part is looked at. final[s] = 1 for such a slot s, else 0
 * (m->nslots bytes, the caller's). Returns how many. A tree without a
 * region (no climb tables) has all of space as its region: every finite
 * tet is final, as for a run of one part.
 */
size_t fdt_partmesh_final(const fdt_ins *m, const fdt_kdtree *t, uint8_t *final);

/*
 * The whole run as one part: the DT of the points [0, m) of P (tree order,
 * distinct, spanning 3-D: the caller checked), built and certified on
 * nthreads threads (above one fdt_ins_build_parallel and
 * fdt_certify_parallel: the same DT), every tet and hull face handed to
 * em, whose meshbuf must be empty (in memory only: the mesh's own array
 * becomes the meshbuf's; neighbours too when it keeps them).
 * progress (may be NULL) is called between the phases with an estimated
 * fraction, and on one thread also every 64k points inserted; nonzero
 * cancels (FDT_ECANCELED).
 * Returns FDT_OK, FDT_ECHECK (the certificate failed: diag says where),
 * FDT_ENOMEM, FDT_ETOOBIG, FDT_EINTERNAL, or the sink's stop code.
 */
int fdt_partmesh_emit_all(const double *P, uint32_t m, int nthreads, fdt_emit *em,
                          fdt_progress_fn progress, void *puser, fdt_partmesh_stats *st,
                          char *diag, size_t dlen);

#endif
