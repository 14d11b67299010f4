/*
 * The insertion mesh's representation (src/mesh/insert.h builds it, the
 * certificate, the front and the wall engine read it): the type and the
 * O(1) accessors, apart from the builds so that the kernel's shared steps
 * (src/mesh/insert_impl.h) need nothing above them.
 *
 * Representation (CGAL's Triangulation_data_structure_3, in flat arrays):
 *   - tet slot t holds T[8t .. 8t+3], its four vertices (global point ids;
 *     FDT_NONE is the infinite vertex), and T[8t+4 .. 8t+7], its four
 *     neighbours: entry 4+k is the neighbour across the face opposite
 *     vertex k, packed as 4 * neighbour + (index of that face in the
 *     neighbour);
 *   - finite tets are positively oriented (fdt_orient3d > 0); an infinite
 *     tet lies over one hull face, and is "positive" in the sense that
 *     putting any point strictly outside that hull face in place of the
 *     infinite vertex gives a positively oriented tet;
 *   - freed slots are recycled (a free list through them): a freed slot
 *     has FDT_NONE as vertex 0 and vertex 1 (a live tet has at most one).
 * Memory: 32 bytes a slot and about 6.7 slots a point (6.5 finite tets a
 * point on uniform points, plus the hull's infinite tets and growth
 * slack), plus 4 bytes a point for the incident-tet table: about 220
 * bytes a point kept. During the build also 1 byte a slot (conflict
 * marks), 4 bytes a point (insertion order), 1 byte a point (the star
 * links' local numbers) and the cavity scratch.
 */
#ifndef FDT_INSMESH_H
#define FDT_INSMESH_H

#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include "frontdt.h"
#include "geom/predicates.h"

/* Work counters of one build (fdt_ins.stats). */
typedef struct fdt_ins_stats {
    size_t inserted;      /* points inserted (n) */
    size_t walk_steps;    /* tets visited by point location */
    size_t hull_walks;    /* locations by the hull walk (insert_impl.h), the workers' too */
    size_t cavity_tets;   /* tets destroyed (sum of the cavity sizes) */
    size_t created_tets;  /* tets created */
    size_t max_cavity;    /* largest cavity */
    size_t moves;         /* times the tets array moved to a bigger block
                           * (src/mesh/insert_impl.h, ins_move_tets) */
    size_t conflict_tests;/* conflict (insphere / hull side) tests */
    size_t deferred;      /* fdt_ins_build_parallel: insertions put off (a tet held
                           * by another thread, or the slots spent) */
    size_t serial_finish; /* fdt_ins_build_parallel: points left to its serial end */
    size_t stolen;        /* fdt_ins_build_parallel: points a worker took from the
                           * end of another's last round */
    /* fdt_ins_build_parallel: thread CPU seconds of its serial start, of
     * its workers (the busiest one, and all together) and of its serial
     * end (finish included). start + workers_max + finish is the wall
     * time with a free core a worker. */
    double cpu_start_s, cpu_workers_max_s, cpu_workers_sum_s, cpu_finish_s;
} fdt_ins_stats;

typedef struct fdt_ins {
    const double *P;      /* borrowed: global coordinates, 3 per id */
    uint32_t base, n;     /* the points: global ids [base, base + n) */
    uint32_t *T;          /* owned: 8 per slot, see above */
    uint32_t nslots;      /* slots in use or freed ([0, nslots) are valid) */
    uint32_t cap;         /* slots allocated */
    uint32_t free_head;   /* first freed slot, FDT_NONE if none */
    uint32_t *vtet;       /* owned: n entries, a live tet holding id base + i */
    double lo[3], hi[3];  /* the points' bounding box */
    fdt_pred_static sf;   /* its semi-static filter bounds (src/geom/predicates.h) */
    size_t nfinite;       /* finite tets */
    size_t ninfinite;     /* infinite tets = hull faces */
    fdt_ins_stats stats;
} fdt_ins;

/* The four vertices of live slot t (FDT_NONE: the infinite vertex). */
static inline const uint32_t *fdt_ins_tet(const fdt_ins *m, uint32_t t)
{
    return m->T + 8 * (size_t)t;
}

/* Whether slot t holds a finite tet (not infinite, not freed). */
static inline int fdt_ins_is_finite(const fdt_ins *m, uint32_t t)
{
    const uint32_t *v = m->T + 8 * (size_t)t;
    return v[0] != FDT_NONE && v[1] != FDT_NONE && v[2] != FDT_NONE && v[3] != FDT_NONE;
}

/* Whether slot t is freed (a free-list slot: FDT_NONE as vertices 0 and
 * 1, which no live tet has). */
static inline int fdt_ins_is_free(const fdt_ins *m, uint32_t t)
{
    const uint32_t *v = m->T + 8 * (size_t)t;
    return v[0] == FDT_NONE && v[1] == FDT_NONE;
}

/* The index of the infinite vertex in the live tet row v, -1 for a
 * finite tet. */
static inline int fdt_ins_inf_index(const uint32_t *v)
{
    return v[0] == FDT_NONE ? 0 : v[1] == FDT_NONE ? 1 : v[2] == FDT_NONE ? 2
         : v[3] == FDT_NONE ? 3 : -1;
}

/* Face k of the positive tet row v (the face opposite vertex k) oriented
 * with v on its open side: fdt_tet_face[k] reversed. For an infinite tet
 * and k its infinite vertex's index, the hull face, outward (a point
 * outside the face in the infinite vertex's place makes the tet
 * positive, so that point is on the negative side of fdt_tet_face[k]). */
static inline void fdt_ins_face_inward(const uint32_t *v, int k, uint32_t f[3])
{
    const int *o = fdt_tet_face[k];
    f[0] = v[o[0]];
    f[1] = v[o[2]];
    f[2] = v[o[1]];
}

/*
 * The neighbour of tet `tet` across its face k (the face opposite vertex
 * k): *ntet gets the neighbour's slot, *nk the index of the shared face in
 * it. Returns the neighbour's vertex nk, the apex of that face seen from
 * tet: a point id, or FDT_NONE when the neighbour is the infinite tet over
 * a hull face (for a finite face). O(1).
 */
static inline uint32_t fdt_ins_across(const fdt_ins *m, uint32_t tet, int k,
                                      uint32_t *ntet, int *nk)
{
    uint32_t r = m->T[8 * (size_t)tet + 4 + (unsigned)k];
    *ntet = r >> 2;
    *nk = (int)(r & 3);
    return m->T[8 * (size_t)(r >> 2) + (r & 3)];
}

/* Frees what m owns and zeroes it; m may be zeroed or freed already. */
static inline void fdt_ins_free(fdt_ins *m)
{
    free(m->T);
    free(m->vtet);
    memset(m, 0, sizeof *m);
}

#endif
