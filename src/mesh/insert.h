/*
 * The perturbed Delaunay tetrahedralization of one partition's points by
 * incremental (Bowyer-Watson) insertion: the second apex oracle of the
 * front. Where the kd search must test thousands of points to certify a
 * face's apex (scans, CFD grids, cylinders, near-cospherical sets), the
 * front reads the apex from this DT's adjacency instead. The perturbed DT
 * is unique (src/geom/predicates.h), so this kernel and the kd search give the
 * same apex for every face and the two can be mixed face by face.
 *
 * Representation: src/mesh/insmesh.h.
 *
 * Threads: fdt_ins_build runs on one thread, fdt_ins_build_parallel on
 * several; afterwards the structure is immutable and any thread may query
 * it.
 */
#ifndef FDT_INSERT_H
#define FDT_INSERT_H

#include <stddef.h>
#include <stdint.h>
#include "frontdt.h"
#include "geom/images.h"
#include "geom/kdtree.h"
#include "geom/predicates.h"
#include "mesh/insmesh.h"

/*
 * Builds the perturbed DT of the points with global ids [base, base + n)
 * of P (3 doubles per id; borrowed, and it must outlive m). The points must
 * be pairwise distinct; they should be in a spatially coherent order (the
 * kd-tree's), which the insertion order (BRIO) keeps within its rounds.
 * cnt (may be NULL) counts the predicate calls that needed exact
 * arithmetic.
 * Returns FDT_OK; FDT_EDEGENERATE when the points do not span 3-D space
 * (n < 4, all collinear or all coplanar): a clean refusal, the caller keeps
 * its kd search; FDT_EINVAL when two points coincide (found when the second
 * is inserted); FDT_ETOOBIG when the tets would not fit the packed 30-bit
 * neighbour references; FDT_ENOMEM; FDT_EINTERNAL if an invariant failed
 * (a bug). On any error m holds nothing (fdt_ins_free is still allowed).
 */
int fdt_ins_build(fdt_ins *m, const double *P, uint32_t base, uint32_t n,
                  fdt_pred_counts *cnt);
/* The same, calling progress (may be NULL) every 64k insertions with the
 * fraction inserted; a nonzero return cancels the build (FDT_ECANCELED,
 * m holds nothing). */
int fdt_ins_build_progress(fdt_ins *m, const double *P, uint32_t base, uint32_t n,
                           fdt_pred_counts *cnt, fdt_progress_fn progress, void *puser);
/*
 * The same DT as fdt_ins_build (the same set of tets and hull faces; the
 * slot numbering differs), built by nthreads threads (src/mesh/insert_par.c):
 * the first BRIO rounds serially, then the threads insert the rest
 * concurrently, each from its own region of the id (kd) order, under
 * per-tet try-locks; points whose cavities keep meeting another thread's
 * are inserted at the end on the calling thread. nthreads < 1 counts as
 * 1, over 63 as 63; the caller's thread is one of them. Same arguments,
 * results and errors as fdt_ins_build; on any error m holds nothing.
 * Memory: the slots are reserved up front from the serial rounds' slots
 * a point (x1.35, so about 300 bytes a point kept on uniform points,
 * against fdt_ins_build's 220), plus during the build 1 byte a slot
 * (its lock and conflict mark), 4 bytes a point (start hints) and up to
 * 1 byte a point a thread (the star links' local numbers).
 */
int fdt_ins_build_parallel(fdt_ins *m, const double *P, uint32_t base, uint32_t n,
                           int nthreads, fdt_pred_counts *cnt);

/*
 * The perturbed DT of the rounded periodic images img->P[0 .. img->n)
 * (src/geom/images.h; src/mesh/periodic.h makes them), every predicate
 * decided for the exact images: fdt_ins_build_parallel's build on
 * nthreads threads, fdt_ins_build's on one, with their results and
 * errors. img must outlive m.
 */
int fdt_ins_build_images(fdt_ins *m, const fdt_images *img, int nthreads, fdt_pred_counts *cnt);

/* The first finite tet in a slot >= t, FDT_NONE if none: iterate with
 * for (t = fdt_ins_next_finite(m, 0); t != FDT_NONE;
 *      t = fdt_ins_next_finite(m, t + 1)). */
uint32_t fdt_ins_next_finite(const fdt_ins *m, uint32_t t);

/*
 * For the oriented face (a, b, c), whose open side is where
 * fdt_orient3d(a, b, c, x) > 0, finds the tet of the DT on the open side
 * that has abc as a face: *tet gets its slot and *k the index of face abc
 * in it, so that vertex k of *tet is the apex (FDT_NONE when abc is a hull
 * face whose open side is the outside). Returns 1 if found; 0 if abc is
 * not a face of this DT, or a vertex lies outside [base, base + n) (the
 * front also holds faces with vertices of other partitions).
 * Cost: a breadth-first search of a's star (the tets incident to a) until
 * it meets a tet with face abc: O(degree of a), about 25 tets on uniform
 * points, but up to O(n) for a vertex joined to most points (cospherical
 * sets: the perturbation makes one vertex's star hold most tets). Stars
 * over 512 tets take a heap buffer; if that allocation fails the search
 * falls back to a scan of all slots, so the answer is always right. Where
 * the caller already holds a neighbouring tet, fdt_ins_across is O(1).
 */
int fdt_ins_find_face(const fdt_ins *m, uint32_t a, uint32_t b, uint32_t c,
                      uint32_t *tet, int *k);

/*
 * Scratch of fdt_ins_conflict_vertices, owned by the querying thread:
 * zero it to start, free it with fdt_ins_query_free.
 */
typedef struct fdt_ins_query {
    uint32_t *tq, *tset;  /* the conflict region's tets, and their set */
    size_t ntq, tcap;
    uint32_t *vs, *vset;  /* the answer: its distinct finite vertices */
    size_t nvs, vcap;
    uint64_t rng;         /* the walk's choices */
} fdt_ins_query;

/*
 * The vertices of the tets of m in conflict with the point q, which is not
 * one of m's points: with m the DT of a point set S, they are the
 * neighbours q would have in the DT of S + {q} (the cavity is star-shaped
 * from q, so every vertex of a cavity tet is on its boundary). Adding more
 * points never gives q a neighbour in S it did not have, so for a face
 * (q, b, c) of the DT of any superset, the first point of S in the pencil
 * of spheres through the face's circle is among them (src/par/parallel.c asks
 * another part's mesh this way). Read-only on m: any number of threads may
 * query one mesh at once, each with its own qs and hint (a slot to start
 * the walk from, updated to where it ended; any value to start).
 * On FDT_OK qs->vs[0 .. qs->nvs) holds the vertices; 1 when the region
 * holds more than max_tets tets (no answer: a point just outside a large
 * flat hull facet of m sees all of it); FDT_ENOMEM; FDT_EINTERNAL (a walk
 * cycle, impossible in a regular triangulation). Cost: the walk plus the
 * conflict region, a few dozen tets on well-spread points.
 */
int fdt_ins_conflict_vertices(const fdt_ins *m, const double *q, uint32_t *hint,
                              size_t max_tets, fdt_ins_query *qs, fdt_pred_counts *cnt);
void fdt_ins_query_free(fdt_ins_query *qs);

/*
 * The vertices joined to vertex a of m (the finite vertices of its star)
 * into qs->vs[0 .. qs->nvs). With m the DT of a point set S that holds a,
 * for a face (a, b, c) of the DT of any superset of S, the first point of
 * S in the pencil of spheres through the face's circle is among them: its
 * sphere with the face is empty, so it is joined to a in the DT of S and
 * the face's vertices, and points added to S only take edges away (the
 * argument of fdt_ins_conflict_vertices). The wall engine asks its own
 * mesh this way for faces with another part's vertices (src/front/
 * front.h). Read-only on m. FDT_OK; 1 when a is not a vertex of m or its
 * star holds more than max_tets tets (no answer); FDT_ENOMEM.
 */
int fdt_ins_star_vertices(const fdt_ins *m, uint32_t a, size_t max_tets, fdt_ins_query *qs);

/* The kernel's own phases, for src/mesh/insert_par.c and the tests. */

/*
 * order[] = the ids [base, base + n) of P's points by BRIO round
 * (src/mesh/insert.c), the first round first, the point nearest the centre of
 * their bounding box at order[0]; round_end[r] (r = 0 .. *nrounds - 1) is
 * the end of round r in order[]. round_end has room for 32 entries.
 */
void fdt_ins_brio(const double *P, uint32_t base, uint32_t n, uint32_t *order,
                  uint32_t *round_end, int *nrounds);

/*
 * The serial start of a build: m is set up for the points [base, base +
 * n) of P with room for `slots` tets (more if the serial phase needs it),
 * the first tetrahedron is found in order[0 .. n) (first[] gets its four
 * ids) and order[0 .. prefix) is inserted, first[] skipped. progress
 * (may be NULL) is called every 64k insertions with the fraction done;
 * nonzero cancels (FDT_ECANCELED). img: the points' periodic images
 * (fdt_ins_build_images), or NULL. On error m holds nothing.
 */
int fdt_ins_build_prefix(fdt_ins *m, const double *P, uint32_t base, uint32_t n,
                         const uint32_t *order, uint32_t prefix, uint64_t slots,
                         uint32_t first[4], const fdt_images *img, fdt_pred_counts *cnt,
                         fdt_progress_fn progress, void *puser);

/*
 * fdt_ins_build_progress's build, with img the points' periodic images
 * (fdt_ins_build_images on one thread) or NULL.
 */
int fdt_ins_build_serial(fdt_ins *m, const double *P, uint32_t base, uint32_t n,
                         const fdt_images *img, fdt_pred_counts *cnt, fdt_progress_fn progress,
                         void *puser);

/*
 * The end of a build, once every point is in: the incident-tet table, the
 * finite and infinite counts, and the free list rebuilt through every
 * freed slot of [0, nslots). FDT_EINTERNAL if a point is in no tet,
 * FDT_ENOMEM; on error m holds nothing.
 */
int fdt_ins_finish(fdt_ins *m);

/*
 * fdt_ins_build_parallel with the slots' first capacity forced to
 * slots_a_point a point (0: its own estimate): the tests make it small,
 * so the workers run out of slots and the arrays grow between passes,
 * then in the serial finish.
 */
int fdt_ins_build_parallel_slots(fdt_ins *m, const double *P, uint32_t base, uint32_t n,
                                 int nthreads, double slots_a_point, fdt_pred_counts *cnt);

#endif
