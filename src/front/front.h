/*
 * The serial advancing front (§2.2): the reference every parallel mode
 * must equal.
 */
#ifndef FDT_FRONT_H
#define FDT_FRONT_H

#include <stddef.h>
#include <stdint.h>
#include "frontdt.h"
#include "front/facetab.h"
#include "front/meshbuf.h"
#include "geom/kdtree.h"
#include "front/oracle.h"

/* Work counters filled by the front. */
typedef struct fdt_front_stats {
    size_t faces_advanced, max_front;
    fdt_kdq kq;
    /* The insertion mesh (src/front/oracle.h): faces it answered, of those found
     * by a walk around a vertex, fronts (parts) that built one, and the
     * seconds they took. */
    size_t mesh_faces, star_walks, mesh_parts;
    double t_mesh;
    const char *cert_what; /* a mesh failed its certificate: which check */
    size_t certified_tets; /* finite tets of the meshes certified */
    size_t final_tets;     /* tets emitted straight from a part's mesh
                              (the wall engine, src/par/engine.c) */
    double t_certify;      /* seconds certifying them */
    size_t mem_front;   /* bytes of the face table (its largest capacity)
                           and of the face queue (at the end) */
} fdt_front_stats;

/* The bytes of a face table and a face queue (fdt_front_stats.mem_front). */
struct fdt_faceq;
size_t fdt_front_bytes(const fdt_facetab *ft, const struct fdt_faceq *fq);

/* Triangulates all points of tree t (ids [t->base, t->base + t->n)),
 * starting from a seed near point `start`; the front's oracle is its
 * search's front_oracle (src/front/search.h: how each face's apex is
 * found). The tets and hull faces go to `out` (tree-order ids: an
 * in-memory meshbuf, with neighbours if it keeps them). */
int fdt_front_serial(const fdt_kdtree *t, uint32_t start, fdt_search search, fdt_meshbuf *out,
                     fdt_progress_fn progress, void *puser,
                     fdt_front_stats *st);

/* The same, every tet and hull face emitted through em (src/front/sink.h: kept
 * in memory, streamed to a caller's sink or dropped) as it is built. */
struct fdt_emit;
int fdt_front_emit(const fdt_kdtree *t, uint32_t start, fdt_search search, struct fdt_emit *em,
                   fdt_progress_fn progress, void *puser, fdt_front_stats *st);

/* A cap on the probe's work: it stops before the next face once
 * points tested + exact_weight * exact tests exceed cost. */
typedef struct fdt_probe_budget {
    double cost, exact_weight;
} fdt_probe_budget;

/* The kd search's first `faces` faces of the front over tree t, for their
 * work counters in st only (the tets are dropped): what src/front/oracle.c's
 * probe measures. With a budget (NULL: none) it may stop earlier, with
 * st->faces_advanced < faces and the budget spent. */
int fdt_front_probe(const fdt_kdtree *t, uint32_t start, size_t faces,
                    const fdt_probe_budget *budget, fdt_front_stats *st);


/*
 * The apex of front face f (§2.2), the step the serial front and a part of
 * the parallel engine share: the oracle's insertion mesh where it switched
 * to it (src/front/oracle.h: ctid, copp are the closed-side tet and its vertex
 * opposite f, or -1 and FDT_NONE), else the kd search of t from f[0]'s
 * leaf. Between the kd guess and the climb (or after the mesh's answer)
 * the table slots of the faces the apex's tet would add are asked for
 * (fdt_facetab_prefetch_tet): the search hides their latency.
 * keep == 0 (serial: t holds every point): *apex is the apex (FDT_NONE: a
 * hull face); ap is scratch, initialized only where the kd search runs.
 * keep != 0 (a part of the parallel engine): ap is initialized from a, b, c
 * and left holding the search state so far, which other parts may still
 * improve; *inside says whether its ball lies inside t's region (then no
 * other part need be asked). *mtet: the mesh tet of a mesh answer
 * (fdt_oracle_note). Static inline so each caller gets its own copy with
 * keep constant (the serial loop pays for nothing it does not use).
 * Returns FDT_OK, or FDT_EINTERNAL if the mesh's apex is refused by the
 * search state (the mesh and the exact tests disagree).
 */
static inline int fdt_front_apex(fdt_oracle *orc, const fdt_kdtree *t, fdt_facetab *ft,
                                 const uint32_t f[3], const double *a, const double *b,
                                 const double *c, int64_t ctid, uint32_t copp, int keep,
                                 fdt_apex *ap, int *inside, uint32_t *apex, uint32_t *mtet,
                                 fdt_kdq *kq)
{
    int from_mesh = fdt_oracle_apex(orc, f, ctid, copp, apex, mtet);
    if (from_mesh && keep && orc->gm) {
        /* A mesh of every point (fdt_oracle_share) gives the apex itself:
         * nothing to search or offer (its sphere is not even needed: on a
         * pipe, offering it cost a circumcentre, often in GMP, a face),
         * and the search state needs only its answer (the caller reads
         * best and bp; fdt_apex_init's normal was 3 % of a two-thread
         * front on the mesh, bench/NOTES.md entry 67). The coordinates
         * come from the mesh's own array: t holds only this part's points
         * where a rank of frontdt-mpi reads the replica mesh (t->P + 3 *
         * apex was past the rank's points for a foreign apex). */
        ap->best = *apex;
        ap->bp = *apex != FDT_NONE ? orc->gm->P + 3 * (size_t)*apex : NULL;
        fdt_facetab_prefetch_tet(ft, f, *apex);
        *inside = 1;
        return FDT_OK;
    }
    if (keep)
        fdt_apex_init(ap, a, b, c, f[0], f[1], f[2]);
    if (from_mesh) {
        /* The mesh's answer is the first of t's points in the pencil of
         * spheres through f's circle: with keep it is offered to the
         * search state, where only another part's point can beat it. */
        if (keep && *apex != FDT_NONE) {
            fdt_apex_offer(ap, *apex, t->P + 3 * (size_t)*apex, kq);
            /* on the open side by construction: a refusal is a bug */
            if (ap->best != *apex)
                return FDT_EINTERNAL;
        }
        fdt_facetab_prefetch_tet(ft, f, *apex);
        if (keep)
            *inside = fdt_apex_inside_region(ap, t);
        return FDT_OK;
    }
    if (!keep)
        fdt_apex_init(ap, a, b, c, f[0], f[1], f[2]);
    /* A face with another part's vertex: the mesh's neighbours of f0 hold
     * the first of t's points (fdt_oracle_offer_star). */
    int star = keep ? fdt_oracle_offer_star(orc, f, ap, kq) : 0;
    if (star < 0)
        return star;
    if (star) {
        *apex = ap->best;
        fdt_facetab_prefetch_tet(ft, f, ap->best);
        *inside = fdt_apex_inside_region(ap, t);
        return FDT_OK;
    }
    /* Start in f0's leaf and climb (src/geom/kdtree.c): the apex is near, and
     * the guess is the apex for most faces. */
    fdt_apex_guess(ap, t, f[0], kq);
    fdt_facetab_prefetch_tet(ft, f, ap->best);
    int in = fdt_apex_verify_from(ap, t, f[0], kq);
    if (keep)
        *inside = in;
    *apex = ap->best;
    return FDT_OK;
}

#endif
