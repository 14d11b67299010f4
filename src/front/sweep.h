/*
 * Parts in sweep order (issue 31 item 4; bench/NOTES.md entry 104): the
 * insertion's speed in bounded memory, for streamed runs.
 *
 * The points are cut into slabs along the longest side of their box and
 * taken in that order, one part a slab. Part k triangulates S_k, the live
 * vertices L carried from the part before plus the slab's points, by
 * insertion (src/mesh/insert.h), certifies that mesh (src/mesh/certify.h),
 * and hands to the sink every tet of its region U (the tets not emitted
 * before) whose circumsphere ends strictly before the next slab begins: no
 * later point can lie in or on it, so it is a tet of the perturbed DT of
 * all the points. The rest of U is carried over as L (its vertices) and B
 * (its faces whose other side was emitted), and the mesh is freed. The
 * last part emits what is left, with the hull faces.
 *
 * U, the region: a vertex all of whose tets were emitted has a closed star
 * of DT(P)'s tets and belongs to no other tet of DT(P), so every tet of
 * DT(P_<=k) not yet emitted has its vertices in S_k and, its sphere empty
 * of P_<=k, is a tet of DT(S_k); those tets fill the region bounded by B
 * and the hull: the rest of the mesh, over what was emitted, is what a
 * flood fill from the far side of B's faces that never crosses one
 * reaches. A face of B that is not a face of the next part's mesh, or a
 * fill that reaches a live side, is an internal error, so a wrong
 * emission cannot pass unseen.
 *
 * With two or more threads and slabs, two sweeps meet: the lower half of
 * the slabs swept upwards and the upper half downwards, each on a thread
 * of its own with its own meshes, then one meeting part of both halves'
 * L and B (a tet one sweep emits shares no vertex with the other's).
 */
#ifndef FDT_SWEEP_H
#define FDT_SWEEP_H

#include <stddef.h>
#include <stdint.h>
#include "frontdt.h"
#include "front/cellstream.h"
#include "front/sink.h"
#include "geom/predicates.h"
#include "mesh/insert.h"

/* Bytes a point a streamed sweep holds at its peak besides the points,
 * for the CLI's --memory-limit estimate: the part's copy of its points
 * and its mesh (FDT_PARTMESH_BYTES a point of the part) spread over the
 * points; the rule below bounds the part (entry 104). */
#define FDT_SWEEP_PART_BYTES 280.0

/* What the sweep did, for fdt_stats. */
typedef struct fdt_sweep_stats {
    size_t parts;          /* parts (meshes built) */
    size_t reinserted;     /* live vertices inserted again by a later part */
    size_t max_live;       /* the most live vertices carried into a part */
    size_t max_part;       /* the most points in one part's mesh */
    size_t mem_part;       /* the most bytes one part held: its points'
                              copy, its mesh and marks */
    size_t final_tets;     /* tets emitted */
    size_t certified_tets; /* finite tets the certificates checked */
    double t_mesh;         /* seconds building the parts' meshes */
    double t_certify;      /* seconds certifying them */
    double t_cells;        /* seconds computing the streamed cells */
    fdt_pred_counts pc;    /* exact predicate calls of both */
    fdt_ins_stats ins;     /* the builds' counts, summed */
} fdt_sweep_stats;

/* The slab size for m points, a function of m alone: 32 m^(2/3) (the live
 * layer a part carries over is a few point layers of the cross-section,
 * about 3 m^(2/3) on well-spread points, so about a tenth of the points
 * are inserted twice), at least 2^18 (a smaller input is one part, the
 * one-part engine's mesh: a first slab of a surface, where nothing closes,
 * would be meshed twice for no memory worth saving), at most 2^21 (a
 * part's mesh about 0.5 GB: 64 m^(2/3) up to 2^22 was 10 % faster on 10M
 * uniform points at two threads and took twice the memory, bench/NOTES.md
 * entry 104). */
uint32_t fdt_sweep_slab(size_t m);

/*
 * The DT of the points [0, m) of P (3 doubles each; distinct, spanning
 * 3-D: the caller checked) in parts in sweep order, every tet and hull
 * face handed to em (tree-order ids: the points' indices after this call,
 * which permutes P and orig together into slab order). slab: points a
 * slab (0: fdt_sweep_slab(m)); a part takes more slabs while the live
 * vertices it carries are over half of them, and all that are left once a
 * part emitted under a quarter of its tets (a surface: its spheres span
 * the object, so no later part would do better). nthreads: the threads of
 * the run (two sweeps that meet, each building its parts on half of them;
 * the meeting part, or a single sweep, on all). progress (may be NULL) is
 * called after each part with the fraction of points passed; nonzero
 * cancels. cs (may be NULL): the Voronoi cells, each handed on when its
 * point's last tet is out (src/front/cellstream.h; its P and orig are
 * this call's).
 * Returns FDT_OK, FDT_ECHECK (a certificate failed: diag says where),
 * FDT_ENOMEM, FDT_ETOOBIG, FDT_EINTERNAL, FDT_ECANCELED or the sink's stop
 * code.
 */
int fdt_sweep_emit(double *P, fdt_vid *orig, uint32_t m, uint32_t slab, int nthreads,
                   fdt_emit *em, fdt_cellstream *cs, fdt_progress_fn progress, void *puser,
                   fdt_sweep_stats *st, char *diag, size_t dlen);

#endif
