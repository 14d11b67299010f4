/*
 * The certificate of an insertion mesh (issue 31 item 6): before a run
 * trusts a mesh built by src/mesh/insert.c or src/mesh/insert_par.c (its
 * tets go straight to the sink, or a front reads its apexes from it), a
 * linear pass proves that the mesh is the perturbed Delaunay
 * tetrahedralization of its points. A bug in the insertion (a wrong
 * predicate, a broken cavity, a lost point) then stops the run with
 * FDT_ECHECK (the CLI's exit 3) instead of printing a wrong mesh.
 *
 * What is checked, every slot once, with exact predicates only:
 *  1. structure: each live slot has at most one infinite vertex; each
 *     neighbour reference is a live slot that refers back through the
 *     same face, and the two tets share that face's three vertices, listed
 *     in opposite orders (with check 2 that puts the two tets on opposite
 *     sides of the face, hull faces included);
 *  2. orientation: every finite tet is positively oriented (orient3d > 0);
 *  3. local Delaunay: across every face, the vertex of the neighbour is
 *     not in conflict with the tet, under the rule of the insertion itself
 *     (src/mesh/insert.c, "Hull"): for a finite tet the perturbed insphere,
 *     for an infinite tet the side of its hull face's plane and, on the
 *     plane, the perturbed insphere of the finite tet under it;
 *  4. every point of the mesh is a vertex of a live tet (vtet).
 * Why that suffices: tets of one orientation glued face to face with no
 * boundary (the infinite tets close it) cover the hull a whole number of
 * times; the local Delaunay condition with a convex hull makes that cover
 * a Delaunay triangulation (Delaunay's lemma, which holds under the
 * symbolic perturbation since the perturbed points are in general
 * position), and with every point a vertex it is the unique perturbed DT.
 *
 * The checks use fdt_orient3d and fdt_insphere_perturbed from
 * src/geom/predicates.h directly, never the insertion's inlined wrappers,
 * so a bug planted in the insertion's predicate cannot hide itself
 * (tests/test_certify.c, meson option plant).
 *
 * Cost: about one orient3d and two insphere filters a tet, read-only,
 * the tets visited in space order (by their least vertex: their
 * neighbours' rows and points then mostly in cache); ranges of that order
 * may be certified on several threads at once.
 */
#ifndef FDT_CERTIFY_H
#define FDT_CERTIFY_H

#include <stddef.h>
#include <stdint.h>

#include "geom/predicates.h"
#include "mesh/insert.h"

/* What failed, for the message: the slot, its face (-1: the tet itself)
 * and which check of the list above. */
typedef struct fdt_certify_fail {
    uint32_t slot;
    int face;
    const char *what;  /* a static string */
} fdt_certify_fail;

/* Check 4: each of m's points is a vertex of its vtet slot. */
int fdt_certify_vertices(const fdt_ins *m, fdt_certify_fail *why);

/* The whole certificate on the calling thread: checks 1-4. FDT_OK, or
 * FDT_ECHECK with *why filled (why may be NULL). cnt (may be NULL) counts
 * the exact predicate calls. */
int fdt_certify(const fdt_ins *m, fdt_pred_counts *cnt, fdt_certify_fail *why);

/* The same on nthreads threads (the caller's one of them; fdt_certify_jobs
 * ranges of equal size of the space order, each taken by the next thread free, each face
 * checked in the range of one of its slots; a helper that cannot start
 * leaves its ranges to the others): FDT_OK, FDT_ECHECK (*why: the failure
 * of the lowest range that failed), or FDT_ENOMEM. cnt gets the sum of
 * the threads' counts. */
int fdt_certify_parallel(const fdt_ins *m, int nthreads, fdt_pred_counts *cnt,
                         fdt_certify_fail *why);

/*
 * A pass of the caller's over the tets, fused with the certificate's, which
 * has just read their rows and points (the periodic proofs,
 * src/mesh/periodic.c): tet() for each tet in use, once its own checks
 * passed, with its lifted cofactors when it is finite (cof NULL and inf
 * the infinite vertex's index otherwise); job is the range's index, below
 * fdt_certify_jobs(m, nthreads), each range's calls on one thread in the
 * certificate's order. A tet's call says nothing of the tets after it:
 * the caller uses its results only when the certificate passed.
 */
typedef struct fdt_certify_visit {
    void (*tet)(void *user, int job, uint32_t slot, const uint32_t v[4], int inf,
                const fdt_sphere_cof *cof);
    void *user;
} fdt_certify_visit;

/* How many ranges fdt_certify_parallel_visit splits m into (1 for a small
 * mesh or one thread; at most FDT_CERTIFY_MAX_JOBS): a function of the
 * slots and the thread count alone. */
#define FDT_CERTIFY_MAX_JOBS 64
int fdt_certify_jobs(const fdt_ins *m, int nthreads);

/* fdt_certify_parallel with vis's pass beside it (vis NULL: none). */
int fdt_certify_parallel_visit(const fdt_ins *m, int nthreads, const fdt_certify_visit *vis,
                               fdt_pred_counts *cnt, fdt_certify_fail *why);

/* "mesh certificate failed: tet slot S face F: WHAT" into buf (without
 * the slot when it is FDT_NONE). */
void fdt_certify_describe(const fdt_certify_fail *why, char *buf, size_t len);

/* A failure with no slot: a build's own checks of its mesh failed (a walk
 * that cycles, a cavity that is not a ball: FDT_EINTERNAL from
 * src/mesh/insert.h's builds), so the mesh is wrong, and a run reports
 * it as the certificate's failure (FDT_ECHECK). */
void fdt_certify_build_failed(fdt_certify_fail *why);

#endif
