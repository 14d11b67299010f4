/*
 * What src/mesh/insert.c (the serial build) and src/mesh/insert_par.c (the parallel
 * build) share, inline: the predicates' filters, the growth of the tets
 * array, the walk's step, the conflict rule, the duplicate check, the
 * counters, and the linking of a cavity's new tets. Each lives here once;
 * what differs (the parallel build's locks) stays in its file. The serial
 * phases the parallel build starts and ends with are declared in
 * src/mesh/insert.h. Internal to the insertion kernel; it needs only the
 * representation (src/mesh/insmesh.h).
 */
#ifndef FDT_INSERT_IMPL_H
#define FDT_INSERT_IMPL_H

#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include "base/bits.h"
#include "base/mem.h"
#include "geom/images.h"
#include "mesh/insmesh.h"

/* Neighbour references are 4 * slot + face in 32 bits. */
#define INS_MAX_SLOTS (UINT32_C(1) << 30)
#define PACK(t, k) (((uint32_t)(t) << 2) | (uint32_t)(k))
#define INF FDT_NONE

/* Conflict marks of a build, per slot. */
enum { MARK_NONE = 0, MARK_IN = 1, MARK_OUT = 2 };

static inline const double *ins_pt(const fdt_ins *m, uint32_t v)
{
    return m->P + 3 * (size_t)v;
}

/* The filters (semi-static stage, then dynamic) inline, the exact stages
 * (and the rescaled filters) out of line: most calls end in the filters.
 * sf: the semi-static bounds of a box that holds every point the test
 * reads (fdt_ins.sf for the mesh's own points). Periodic images (sf->img):
 * the semi-static stage alone, with images.h's bounds, then images.h's
 * stages (the dynamic one widened by the images' rounding, out of line,
 * then the exact ones). */
static inline int ins_orient(const double *a, const double *b, const double *c, const double *d,
                             const fdt_pred_static *sf, fdt_pred_counts *cnt)
{
    int s = fdt_orient3d_filter_sf(a, b, c, d, sf);
    if (s != FDT_PRED_UNSURE)
        return s;
    if (__builtin_expect(sf->img != NULL, 0)) /* periodic images (src/geom/images.h) */
        return fdt_images_orient_undecided(sf->img, a, b, c, d, cnt);
    return fdt_orient3d(a, b, c, d, cnt);
}

static inline int ins_insphere(const double *a, const double *b, const double *c,
                               const double *d, const double *e, const fdt_pred_static *sf,
                               fdt_pred_counts *cnt)
{
    int s = fdt_insphere_filter_sf(a, b, c, d, e, sf);
    if (s != FDT_PRED_UNSURE)
        return s;
    if (cnt)
        cnt->insphere_unsure++;
    if (__builtin_expect(sf->img != NULL, 0))
        return fdt_images_insphere_undecided(sf->img, a, b, c, d, e, cnt);
#ifdef FDT_PLANT_INSPHERE
    /* The planted bug of -Dplant=insphere (tests/test_plant.sh; the
     * certificate of src/mesh/certify.h must stop the run): no exact stage
     * and no perturbation, a filter that cannot decide reads as a point on
     * the sphere (not in conflict). */
    return 0;
#else
    return fdt_insphere_perturbed(a, b, c, d, e, cnt);
#endif
}

/*
 * The tets array moved to a new block of nc slots, huge pages asked for
 * before its first write and the block refused past the memory available
 * (fdt_mem_alloc_huge, fdt_mem_fits), its first `used` rows copied (used <= nc: the
 * slots below nslots, or, where other slots were handed out, the whole
 * capacity); the caller grows its own per-slot arrays and then sets
 * m->cap. FDT_ENOMEM (m->T unchanged). Not realloc: the huge-page advice covers a
 * block's 2 MB-aligned interior only (fdt_mem_advise_huge), so the kernel
 * holds the block as three mappings, glibc's mremap of them fails, and
 * realloc then copied into a fresh block without the advice: the rest of
 * the build and the certificate on 4 KB pages (bench/NOTES.md entry 117).
 */
static inline int ins_move_tets(fdt_ins *m, uint64_t nc, uint64_t used)
{
    uint32_t *t = fdt_mem_alloc_huge((size_t)nc * 8, sizeof *t, 0);
    if (!t)
        return FDT_ENOMEM;
    memcpy(t, m->T, (size_t)used * 8 * sizeof *t);
    free(m->T);
    m->T = t;
    m->stats.moves++;
    return FDT_OK;
}

/*
 * The tets array grown for `need` slots (a build's reserve): the capacity
 * half as much again plus 64, at least need, at most INS_MAX_SLOTS
 * (ins_move_tets, its first `used` rows kept). *nc_out gets the new
 * capacity. FDT_ETOOBIG beyond INS_MAX_SLOTS, FDT_ENOMEM (m->T unchanged).
 */
static inline int ins_grow_tets(fdt_ins *m, uint64_t need, uint64_t used, uint64_t *nc_out)
{
    if (need > INS_MAX_SLOTS)
        return FDT_ETOOBIG;
    uint64_t nc = (uint64_t)m->cap + m->cap / 2 + 64;
    if (nc < need)
        nc = need;
    if (nc > INS_MAX_SLOTS)
        nc = INS_MAX_SLOTS;
    int err = ins_move_tets(m, nc, used);
    if (err)
        return err;
    *nc_out = nc;
    return FDT_OK;
}

/*
 * The slots the whole build of n points will want, from the done points
 * in so far and the slots in use (nslots less the nfree freed ones): the
 * slots a point so far, with a third more (later rounds are denser, and
 * the parallel build's chunks), plus `extra`. Sized once, early, so that
 * the array rarely grows later: its untouched pages cost no memory, and a
 * growth holds the old and new blocks at once.
 */
static inline uint64_t ins_slots_wanted(const fdt_ins *m, uint32_t done, uint32_t nfree,
                                        uint32_t n, uint64_t extra)
{
    uint64_t want = (uint64_t)((double)(m->nslots - nfree) / (double)done * 1.35 * n) + extra;
    return want > INS_MAX_SLOTS ? INS_MAX_SLOTS : want;
}

/*
 * One step's choice of a walk in a tet of points q: the faces are tried
 * from a pseudo-random one on (*rng, a 64-bit LCG, advances once), those
 * whose bit is set in `skip` left out. Returns the first face k whose
 * orientation, p put in place of q[k], has the sign `sign`, or -1 when
 * none has.
 */
static inline int ins_walk_choose(const double *const q[4], const double *p, unsigned skip,
                                  int sign, uint64_t *rng, const fdt_pred_static *sf,
                                  fdt_pred_counts *cnt)
{
    *rng = *rng * UINT64_C(6364136223846793005) + UINT64_C(1442695040888963407);
    uint32_t r = (uint32_t)(*rng >> 61);
    for (uint32_t j = 0; j < 4; j++) {
        int k = (int)((r + j) & 3);
        if (skip >> k & 1)
            continue;
        const double *s[4] = {q[0], q[1], q[2], q[3]};
        s[k] = p;
        if (ins_orient(s[0], s[1], s[2], s[3], sf, cnt) * sign > 0)
            return k;
    }
    return -1;
}

/*
 * One step of the visibility walk (src/mesh/insert.c's walk) in the finite
 * tet v (its four vertex ids), skipping `from`, the face the walk came in
 * by (-1: none): the first face (ins_walk_choose's order) whose plane has
 * p strictly on its far side, or -1 when p is in the closed tet.
 */
static inline int ins_walk_exit(const fdt_ins *m, const uint32_t *v, const double *p, int from,
                                uint64_t *rng, const fdt_pred_static *sf, fdt_pred_counts *cnt)
{
    const double *q[4] = {ins_pt(m, v[0]), ins_pt(m, v[1]), ins_pt(m, v[2]), ins_pt(m, v[3])};
    return ins_walk_choose(q, p, from >= 0 ? 1u << from : 0, -1, rng, sf, cnt);
}

/* Whether p equals one of the finite vertices of tet v (the walk ends in
 * a tet of that vertex): the insertion refuses it (FDT_EINVAL) rather
 * than break the perturbation's precondition, pairwise distinct points. */
static inline int ins_is_vertex(const fdt_ins *m, const uint32_t *v, const double *p)
{
    /* Periodic images (src/geom/images.h): two of them can round to one
     * double and still be distinct (the input's points are, and an image
     * never lands on another point: that would lie a period from it, out
     * of the box), so equal stored coordinates say nothing. */
    if (m->sf.img)
        return 0;
    for (int i = 0; i < 4; i++) {
        if (v[i] == INF)
            continue;
        const double *q = ins_pt(m, v[i]);
        if (q[0] == p[0] && q[1] == p[1] && q[2] == p[2])
            return 1;
    }
    return 0;
}

/* Conflict of p with the finite tet v: strictly inside its circumsphere. */
static inline int ins_conflict_finite(const fdt_ins *m, const uint32_t *v, const double *p,
                                      const fdt_pred_static *sf, fdt_pred_counts *cnt)
{
    return ins_insphere(ins_pt(m, v[0]), ins_pt(m, v[1]), ins_pt(m, v[2]), ins_pt(m, v[3]), p,
                        sf, cnt) > 0;
}

/* The return of ins_conflict_local when only the finite tet under the hull
 * face can decide. */
#define INS_CONFLICT_UNDER (-1)

/*
 * Whether tet v (its row of T: ids, then neighbours) is in conflict with
 * p (src/mesh/insert.c's top: a finite tet when p is strictly inside its
 * circumsphere, an infinite one when p is strictly outside its hull
 * face), as far as v alone decides: 1 or 0, or INS_CONFLICT_UNDER when p
 * is on the hull face's plane, where the finite tet under the face, slot
 * v[4 + *inf] >> 2, decides (ins_conflict_finite).
 */
static inline int ins_conflict_local(const fdt_ins *m, const uint32_t *v, const double *p,
                                     const fdt_pred_static *sf, fdt_pred_counts *cnt,
                                     int *inf_out)
{
    int inf = v[0] == INF ? 0 : v[1] == INF ? 1 : v[2] == INF ? 2 : v[3] == INF ? 3 : -1;
    if (inf < 0)
        return ins_conflict_finite(m, v, p, sf, cnt);
    const double *q[4];
    for (int i = 0; i < 4; i++)
        q[i] = i == inf ? p : ins_pt(m, v[i]);
    int o = ins_orient(q[0], q[1], q[2], q[3], sf, cnt);
    if (o != 0)
        return o > 0;
    *inf_out = inf;
    return INS_CONFLICT_UNDER;
}

/* Whether tet v has the infinite vertex. */
static inline int ins_is_infinite(const uint32_t *v)
{
    return v[0] == INF || v[1] == INF || v[2] == INF || v[3] == INF;
}

/*
 * The hull walk (src/mesh/insert.c's hull_walk, and the parallel
 * workers'): where a point outside the hull starts its cavity when the
 * last point lay outside too (every point of a sphere, a cylinder). The
 * visibility walk from the last star to such a point crosses the long
 * tets through the body: every integer point of one sphere (tests/
 * gen_points intsphere) walked 140 tets a point. Seen from a point o
 * strictly inside the hull (a finite tet's centroid: the hull only
 * grows), the hull faces' cones partition space; the walk crosses from
 * hull face to hull face (infinite tet to infinite tet, across the faces
 * that hold the infinite vertex) by the planes through o and each hull
 * edge, to the face whose cone holds p. If p is strictly outside that
 * face, its infinite tet is in conflict, as a walk's end is; otherwise
 * (p inside the hull there, or on a plane) the visibility walk starts
 * from the finite tet under it, near p. A hull walk past
 * INS_HULL_WALK_STEPS steps (a cycle of ties, or sliver faces) gives up,
 * and the visibility walk goes on. Builds with periodic images never
 * take it (their predicates read only the images' own points).
 */
#define INS_HULL_WALK_STEPS 64
/* The steps of the visibility walk before an outside point takes the
 * hull walk. */
#define INS_HULL_AFTER 16
/* The hull walks after which a build (a worker) stops taking them when
 * more than a quarter gave up (a pipe's scan: the hull faces are long
 * slivers, a hull walk crossed 92 of them where the visibility walk
 * crosses 35 tets). */
#define INS_HULL_TRIAL 64

/* One build's (or worker's) hull walks. */
typedef struct ins_hull {
    int outside;       /* the last point lay outside the hull (its cavity
                          began at an infinite tet) */
    int has_o;         /* o: 0 not yet, 1 set, -1 none (ins_hull_origin) */
    double o[3];
    uint32_t tries, capped; /* hull walks, and those that gave up */
} ins_hull;

/* The visibility walk's budget before the hull walk: INS_HULL_AFTER when
 * the last point lay outside and the hull walks still pay, else none. */
static inline size_t ins_hull_budget(const ins_hull *h, const fdt_ins *m)
{
    int take = h->outside && !m->sf.img &&
               !(h->tries >= INS_HULL_TRIAL && 4 * h->capped > h->tries);
    return take ? INS_HULL_AFTER : SIZE_MAX;
}

/* One hull walk taken (ins_hull_budget's trial reads the counts): its
 * answer got, -1 when it gave up; *walks the build's stats. */
static inline void ins_hull_count(ins_hull *h, size_t *walks, int got)
{
    (*walks)++;
    h->tries++;
    h->capped += got < 0;
}

/* o: the centroid of the finite tet v (its four ids), checked strictly
 * inside it (exact predicates); 0 if it is not (a flat tet, or one so
 * small that the quarters underflow). Each coordinate is quartered
 * before the sum, which then stays finite for any finite points. */
static inline int ins_hull_origin(const fdt_ins *m, const uint32_t *v, double o[3],
                                  const fdt_pred_static *sf, fdt_pred_counts *cnt)
{
    const double *q[4] = {ins_pt(m, v[0]), ins_pt(m, v[1]), ins_pt(m, v[2]), ins_pt(m, v[3])};
    for (int k = 0; k < 3; k++)
        o[k] = 0.25 * q[0][k] + 0.25 * q[1][k] + 0.25 * q[2][k] + 0.25 * q[3][k];
    for (int k = 0; k < 4; k++) {
        const double *s[4] = {q[0], q[1], q[2], q[3]};
        s[k] = o;
        if (ins_orient(s[0], s[1], s[2], s[3], sf, cnt) <= 0)
            return 0;
    }
    return 1;
}

/* One step of the hull walk in the infinite tet v (its ids), come in by
 * face `from` (-1: none): the face to cross next, or -1 when p's cone is
 * v's. v's finite vertices with o for the infinite one: o is below the
 * hull face, so the tuple is negative; p past the plane through o and the
 * edge opposite k makes it positive. */
static inline int ins_hull_exit(const fdt_ins *m, const uint32_t *v, const double *o,
                                const double *p, int from, uint64_t *rng,
                                const fdt_pred_static *sf, fdt_pred_counts *cnt)
{
    int inf = fdt_ins_inf_index(v);
    const double *q[4];
    for (int i = 0; i < 4; i++)
        q[i] = i == inf ? o : ins_pt(m, v[i]);
    unsigned skip = 1u << inf | (from >= 0 ? 1u << from : 0);
    return ins_walk_choose(q, p, skip, 1, rng, sf, cnt);
}

/*
 * The coplanar rule's second half: the tet u under a hull face decides
 * (ins_conflict_finite). u is finite in a valid mesh; one that is not
 * says the mesh is already broken (a wrong predicate, tests/test_plant.sh),
 * and reading its infinite vertex as a point would read past the points:
 * FDT_EINTERNAL then.
 */
static inline int ins_conflict_under(const fdt_ins *m, const uint32_t *u, const double *p,
                                     const fdt_pred_static *sf, fdt_pred_counts *cnt)
{
    if (ins_is_infinite(u))
        return FDT_EINTERNAL;
    return ins_conflict_finite(m, u, p, sf, cnt);
}

/* Whether tet t is in conflict with p, in a mesh nobody else changes
 * meanwhile (the serial build, and queries of a built mesh): 1, 0, or
 * FDT_EINTERNAL (ins_conflict_under). */
static inline int ins_conflict(const fdt_ins *m, uint32_t t, const double *p,
                               const fdt_pred_static *sf, fdt_pred_counts *cnt)
{
    const uint32_t *v = m->T + 8 * (size_t)t;
    int inf = -1, c = ins_conflict_local(m, v, p, sf, cnt, &inf);
    if (c != INS_CONFLICT_UNDER)
        return c;
    return ins_conflict_under(m, m->T + 8 * (size_t)(v[4 + inf] >> 2), p, sf, cnt);
}

/*
 * Whether the star of p over the cavity's boundary faces bnd[0 .. nbnd)
 * (packed: cavity tet c, face opposite its vertex k; each new tet is the
 * face with p in place of vertex k) is a triangulation: every new finite
 * tet positively oriented. Delaunay's cavity is star-shaped from p, so
 * with exact predicates this always holds (the certificate of
 * src/mesh/certify.c asks the same of every finite tet); a cavity that is
 * not (a wrong insphere: tests/test_plant.sh) would link a star that is no
 * triangulation, and later walks and cavities would then read anything.
 * A region whose boundary faces all face away from p is star-shaped from
 * it (a ray from p crosses that boundary once), so the test on each face
 * stops such a star before it is written. It runs only when one of the
 * insertion's insphere filters could not decide (cnt->insphere_unsure
 * moved past unsure0, its value when the insertion began): what the
 * filters decide is the exact sign, so a cavity found by them alone is
 * Delaunay's, and most insertions skip the test (bench/NOTES.md entry 89:
 * all of them cost 9 % of a serial build). An infinite new tet is not
 * tested (no point of the mesh stands for its infinite vertex); the
 * certificate checks the hull at the end.
 */
static inline int ins_star_ok(const fdt_ins *m, const uint32_t *bnd, size_t nbnd,
                              const double *p, fdt_pred_counts *cnt, size_t unsure0)
{
    if (cnt->insphere_unsure == unsure0)
        return 1;
    for (size_t j = 0; j < nbnd; j++) {
        const uint32_t *cv = m->T + 8 * (size_t)(bnd[j] >> 2);
        int k = (int)(bnd[j] & 3), inf = 0;
        const double *q[4];
        for (int i = 0; i < 4; i++) {
            inf |= i != k && cv[i] == INF;
            q[i] = i == k ? p : cv[i] == INF ? p : ins_pt(m, cv[i]);
        }
        if (!inf && ins_orient(q[0], q[1], q[2], q[3], &m->sf, cnt) <= 0)
            return 0;
    }
    return 1;
}

/* Asks for the four neighbours of tet t: the cavity search tests them
 * next. */
static inline void ins_prefetch_nbrs(const uint32_t *T, uint32_t t)
{
    const uint32_t *nb = T + 8 * (size_t)t + 4;
    for (int j = 0; j < 4; j++)
        fdt_prefetch(T + 8 * (size_t)(nb[j] >> 2));
}

/* A build's start: m emptied for the points [base, base + n) of P.
 * FDT_EDEGENERATE when n < 4 (m then names the points and holds no tet),
 * else FDT_OK. */
static inline int ins_begin(fdt_ins *m, const double *P, uint32_t base, uint32_t n)
{
    memset(m, 0, sizeof *m);
    if (n >= 4)
        return FDT_OK;
    m->P = P;
    m->base = base;
    m->n = n;
    m->free_head = FDT_NONE;
    return FDT_EDEGENERATE;
}

/* An insertion's counts: its cavity of ncav tets and its nnew new ones. */
static inline void ins_count_cavity(fdt_ins_stats *st, size_t ncav, size_t nnew)
{
    st->cavity_tets += ncav;
    st->created_tets += nnew;
    if (ncav > st->max_cavity)
        st->max_cavity = ncav;
}

static inline int ins_grow_u32(uint32_t **a, size_t *cap, size_t need)
{
    if (need <= *cap)
        return FDT_OK;
    size_t nc = *cap ? *cap : 64;
    while (nc < need)
        nc += nc / 2 + 1;
    uint32_t *p = realloc(*a, nc * sizeof *p);
    if (!p)
        return FDT_ENOMEM;
    *a = p;
    *cap = nc;
    return FDT_OK;
}

/*
 * The directed edges of a star's outer surface, which link its tets.
 * Every tet of a star has the centre (the new point, or the infinite
 * vertex around the first tetrahedron) and is positively oriented, so the
 * faces opposite the centre, each in its tet's outward order
 * (fdt_tet_face), form a consistently oriented closed surface: each of
 * its edges is walked once in each direction, by the two faces through
 * it. The face of tet s through the centre and the directed edge xy is
 * the one opposite s's third outer vertex; its neighbour is the face
 * through the centre and yx. So one pass puts every directed edge in the
 * table and a second looks up each edge's reverse: no branch on which of
 * two faces comes first, no ordering of the two ids (bench/NOTES.md entry
 * 91: the one-pass table that did both cost two mispredicted branches a
 * face).
 */
typedef struct ins_edge_slot {
    uint64_t key;     /* the directed edge: tail id << 32 | head id */
    uint32_t val;     /* packed face (tet, index) through it and the centre */
    uint32_t stamp;   /* valid when equal to the table's current stamp */
} ins_edge_slot;

typedef struct ins_edges {
    ins_edge_slot *eh;
    uint32_t bits;    /* 2^bits slots (0: none yet) */
    uint32_t stamp;
} ins_edges;

/* A table with room for `edges` keys at most half full, emptied: a new
 * stamp invalidates every slot at once. */
static inline int ins_edges_begin(ins_edges *e, size_t edges)
{
    uint32_t bits = e->bits ? e->bits : 6;
    while (((size_t)1 << bits) < 2 * edges)
        bits++;
    if (bits != e->bits) {
        ins_edge_slot *s = calloc((size_t)1 << bits, sizeof *s);
        if (!s)
            return FDT_ENOMEM;
        free(e->eh);
        e->eh = s;
        e->bits = bits;
        e->stamp = 0;
    }
    if (++e->stamp == 0) { /* wrapped: old stamps would read as valid */
        memset(e->eh, 0, ((size_t)1 << e->bits) * sizeof *e->eh);
        e->stamp = 1;
    }
    return FDT_OK;
}

static inline uint32_t ins_edge_hash(const ins_edges *e, uint64_t key)
{
    return (uint32_t)((key * UINT64_C(0x9E3779B97F4A7C15)) >> (64 - e->bits));
}

/* For a star tet, its centre at index 0 (ins_star_tet), the faces through
 * the centre: j = 0, 1, 2 gives {tail, head, face}, the directed outer edge
 * (tail -> head, in the outward order fdt_tet_face[0] of the face opposite
 * the centre) and the index of the face through the centre and that edge
 * (the outer face's third vertex). tests/test_insert.c derives it from
 * fdt_tet_face. */
static const uint8_t ins_star_edge[3][3] = {{2, 3, 1}, {3, 1, 2}, {1, 2, 3}};

/*
 * Links the tets slots[0 .. n) of a star (see ins_edges), each with its
 * centre at index 0, the table emptied for 3n keys by ins_edges_begin:
 * every face through the centre gets its neighbour. FDT_EINTERNAL, with some links written, when the
 * outer faces are not a closed surface walked once each way (a directed
 * edge twice, or one whose reverse is missing): a cavity that is no ball,
 * which a wrong predicate can make (tests/test_plant.sh).
 */
static inline int ins_link_star(ins_edges *e, uint32_t *T, const uint32_t *slots, size_t n)
{
    uint32_t mask = (UINT32_C(1) << e->bits) - 1, stamp = e->stamp;
    for (size_t i = 0; i < n; i++) {
        const uint32_t *v = T + 8 * (size_t)slots[i];
        const uint8_t(*se)[3] = ins_star_edge;
        for (int j = 0; j < 3; j++) {
            uint64_t key = ((uint64_t)v[se[j][0]] << 32) | v[se[j][1]];
            uint32_t h = ins_edge_hash(e, key);
            while (e->eh[h].stamp == stamp) {
                if (e->eh[h].key == key)
                    return FDT_EINTERNAL;
                h = (h + 1) & mask;
            }
            e->eh[h] = (ins_edge_slot){key, PACK(slots[i], se[j][2]), stamp};
        }
    }
    for (size_t i = 0; i < n; i++) {
        uint32_t *v = T + 8 * (size_t)slots[i];
        const uint8_t(*se)[3] = ins_star_edge;
        for (int j = 0; j < 3; j++) {
            uint64_t key = ((uint64_t)v[se[j][1]] << 32) | v[se[j][0]];
            uint32_t h = ins_edge_hash(e, key);
            for (;; h = (h + 1) & mask) {
                if (e->eh[h].stamp != stamp)
                    return FDT_EINTERNAL;
                if (e->eh[h].key == key)
                    break;
            }
            v[4 + se[j][2]] = e->eh[h].val;
        }
    }
    return FDT_OK;
}

/*
 * A star tet's vertices put with the new point first: an even permutation
 * (so the orientation stays) taking index k to index 0. Every tet of a
 * star then has its centre at index 0, its outer face at 1, 2, 3 in
 * outward order and its outer neighbour at 4, so the star is linked
 * through fixed indices (ins_make_star).
 */
static const uint8_t ins_to_front[4][4] = {
    {0, 1, 2, 3}, {1, 0, 3, 2}, {2, 3, 0, 1}, {3, 2, 1, 0}};

/*
 * One tet of an insertion's star, in slot s: the cavity's boundary face
 * bnd (packed: cavity tet c, face opposite its vertex k) with pid in place
 * of vertex k, on the same side of the face as c's vertex k was (the
 * cavity is star-shaped), so positively oriented; its vertices reordered
 * by ins_to_front, pid at index 0. It takes over c's neighbour across the
 * face; ins_link_star(_local) links its three other faces. c must still
 * be readable (its slot is freed after the star is built).
 */
static inline void ins_star_tet(uint32_t *T, uint32_t bnd, uint32_t pid, uint32_t s)
{
    uint32_t c = bnd >> 2;
    int k = (int)(bnd & 3);
    uint32_t *nw = T + 8 * (size_t)s;
    const uint32_t *cv = T + 8 * (size_t)c;
    const uint8_t *f = ins_to_front[k];
    nw[0] = pid;
    nw[1] = cv[f[1]];
    nw[2] = cv[f[2]];
    nw[3] = cv[f[3]];
    uint32_t o = cv[4 + k];
    nw[4] = o;
    T[8 * (size_t)(o >> 2) + 4 + (o & 3)] = PACK(s, 0);
}

/*
 * A small star is linked through local numbers of its outer vertices
 * instead of the edge table (HXT's small-cavity adjacency, Marot,
 * Pellerin and Remacle 2019): the directed outer edge x -> y is the cell
 * x * INS_LOCAL_N + y of a table (ins_make_star).
 */
#define INS_LOCAL_N 32
#define INS_LOCAL_MAXF (2 * (INS_LOCAL_N - 6))

typedef struct ins_local {
    uint8_t *lid;                /* n + 1 bytes: point id - base, the infinite vertex n;
                                    0 outside a star */
    uint32_t base, n;
    uint32_t cell[INS_LOCAL_N * INS_LOCAL_N]; /* packed face of a directed edge */
    uint32_t vert[INS_LOCAL_N];  /* the lid entries numbered, to clear after */
    uint8_t loc[3 * INS_LOCAL_MAXF]; /* each star tet's outer vertices' numbers */
} ins_local;

/*
 * The star of point pid over the cavity's boundary faces bnd[0 .. n), in
 * the slots slots[0 .. n) (allocated, none of them a cavity tet), made and
 * linked: each tet written as ins_star_tet writes it, its outer vertices
 * numbered and its outer edges put in the table of directed edges while
 * its row is in registers; then each tet reads its three reverse edges.
 * Outer vertices, the infinite one included, get local numbers 0 ..
 * INS_LOCAL_N - 1 (in lid, a byte a point, 0 meaning unnumbered, so
 * stored plus one). A star of F outer faces has F / 2 + 2 vertices (a
 * closed triangulated sphere), so one of up to INS_LOCAL_MAXF faces has
 * at most INS_LOCAL_N - 4, and the numbering's guard (a tet brings at
 * most three new ones) never stops such a star (on uniform points 27
 * faces on average). A bigger star, or more vertices than a star that
 * size has (then it is no star), is linked by the edge table e instead
 * (ins_link_star, which checks every edge) once its tets are made.
 *
 * The local table is not cleared between stars and not checked edge by
 * edge (a stamp a cell and its tests cost 3 % of a serial build, bench/
 * NOTES.md entry 94): a star-shaped cavity's boundary is a closed
 * surface, so every cell read was written by this star, and that the
 * cavity is star-shaped is what the exact predicates (and ins_star_ok,
 * where a filter could not decide) guarantee. What is checked here is
 * the star's Euler count (F = 2 V - 4, a sphere's), the cheap symptom of
 * a bug that made it otherwise, and the certificate (src/mesh/certify.c)
 * checks every link of the finished mesh. The numbering has no branch on
 * whether a vertex is new (about one read in five is, at random) or on
 * the infinite vertex. FDT_OK, FDT_EINTERNAL, or FDT_ENOMEM (the edge
 * table). bench/NOTES.md entries 93 and 94.
 */
static inline int ins_make_star(ins_local *L, ins_edges *e, uint32_t *T, const uint32_t *bnd,
                                size_t n, uint32_t pid, const uint32_t *slots)
{
    /* Locals, not L's fields: the byte stores below may alias anything, and
     * would make the compiler reload every field after each. */
    uint8_t *const lid = L->lid, *const loc = L->loc;
    uint32_t *const vert = L->vert, *const cell = L->cell;
    const uint32_t base = L->base, ninf = L->n;
    int local = n <= INS_LOCAL_MAXF;
    uint32_t nv = 0;
    for (size_t i = 0; i < n; i++) {
        /* ins_star_tet, its outer vertices kept in registers (the byte
         * stores below would make the compiler read the row back) */
        const uint32_t sl = slots[i], bd = bnd[i];
        const uint32_t *cv = T + 8 * (size_t)(bd >> 2);
        const uint8_t *f = ins_to_front[bd & 3];
        const uint32_t x[3] = {cv[f[1]], cv[f[2]], cv[f[3]]}, o = cv[4 + (bd & 3)];
        uint32_t *nw = T + 8 * (size_t)sl;
        nw[0] = pid;
        nw[1] = x[0];
        nw[2] = x[1];
        nw[3] = x[2];
        nw[4] = o;
        T[8 * (size_t)(o >> 2) + 4 + (o & 3)] = PACK(sl, 0);
        if (!local)
            continue;
        if (nv > INS_LOCAL_N - 3) { /* the next three might not fit */
            for (uint32_t q = 0; q < nv; q++)
                lid[vert[q]] = 0;
            local = 0;
            continue;
        }
        uint32_t id[3];
        for (int q = 0; q < 3; q++) {
            const uint32_t ix = x[q] == INF ? ninf : x[q] - base;
            const uint32_t old = lid[ix], fresh = old == 0;
            vert[nv] = ix;
            nv += fresh;
            const uint32_t cur = fresh ? nv : old; /* the number plus one */
            lid[ix] = (uint8_t)cur;
            id[q] = cur - 1;
        }
        /* Tet (p, a, b, c): its outer face's edges a -> b, b -> c, c -> a
         * are in its faces 3, 1, 2 (the ones without c, a, b). */
        const uint32_t a = id[0], b = id[1], c = id[2], s4 = sl << 2;
        cell[a * INS_LOCAL_N + b] = s4 | 3;
        cell[b * INS_LOCAL_N + c] = s4 | 1;
        cell[c * INS_LOCAL_N + a] = s4 | 2;
        loc[3 * i] = (uint8_t)a;
        loc[3 * i + 1] = (uint8_t)b;
        loc[3 * i + 2] = (uint8_t)c;
    }
    if (!local) {
        int err = ins_edges_begin(e, 3 * n);
        return err ? err : ins_link_star(e, T, slots, n);
    }
    for (uint32_t q = 0; q < nv; q++)
        lid[vert[q]] = 0;
    if (n != 2 * (size_t)nv - 4)
        return FDT_EINTERNAL; /* not a sphere's count: no star (nothing linked) */
    for (size_t i = 0; i < n; i++) {
        const uint32_t a = loc[3 * i], b = loc[3 * i + 1], c = loc[3 * i + 2];
        uint32_t *v = T + 8 * (size_t)slots[i];
        v[4 + 3] = cell[b * INS_LOCAL_N + a];
        v[4 + 1] = cell[c * INS_LOCAL_N + b];
        v[4 + 2] = cell[a * INS_LOCAL_N + c];
    }
    return FDT_OK;
}

#endif
