/*
 * Incremental Delaunay insertion (Bowyer 1981, Watson 1981) under the
 * symbolic perturbation of src/geom/predicates.h; see src/mesh/insert.h for the
 * representation and why the front wants it.
 *
 * One insertion: locate the new point p by a visibility walk, grow the
 * cavity (the tets in conflict with p) breadth-first from the tet found,
 * and replace the cavity by the tets joining p to its boundary faces.
 * Because fdt_insphere_perturbed never answers 0, the perturbed points are
 * in general position: the cavity is exactly the set of tets whose
 * perturbed circumsphere holds p, it is connected and star-shaped from p,
 * and the result is the unique perturbed DT whatever the insertion order.
 *
 * Hull. CGAL's convention: an infinite vertex, and one infinite tet over
 * every hull face. The infinite tet over hull face abc (outside on the
 * positive side of abc) is in conflict with p when p is strictly outside
 * that face's plane, or exactly on the plane and inside the circumcircle
 * of abc, with ties on the circle broken by the perturbation. That is
 * Delaunay_triangulation_3::side_of_sphere for an infinite cell with
 * perturb = true (its coplanar_side_of_bounded_circle). We evaluate the
 * coplanar case as fdt_insphere_perturbed(a', b', c', d, p), where
 * (a', b', c', d) is the finite tet on the other side of the hull face
 * (positively oriented, d off the plane). Why that is the same test:
 *   - unperturbed: every sphere through a, b, c meets their plane in the
 *     circumcircle of abc, so for p in the plane, "inside the sphere of
 *     abcd" is "inside the circle of abc";
 *   - on the circle, both rules take the five (four) points in decreasing
 *     lexicographic order and return the sign of the first nonzero
 *     coefficient. p first: outside in both. d: its coefficient is
 *     orient3d(a, b, c, p) = 0 (p on the plane), skipped. A face vertex x:
 *     the 3-D coefficient is orient3d of the tet with x replaced by p; for p
 *     on the plane that is the barycentric coordinate lambda_x(p) in
 *     triangle abc times orient3d(a, b, c, d) > 0, and CGAL's 2-D
 *     coefficient coplanar_orientation(.., p in x's place, ..) times
 *     coplanar_orientation(a, b, c) is the sign of the same lambda_x(p).
 *     So both rules return the same sign at every step.
 * Using the inner tet also makes the two sides of a hull face agree
 * exactly, which keeps the cavity free of flat tets: p on the plane of
 * hull face abc is in conflict with the infinite tet over abc exactly when
 * it is with the finite tet under it, so abc is never a cavity boundary
 * face with p in its plane.
 *
 * Order: BRIO (Amenta, Choi, Rote 2003). Each point falls in a round by a
 * hash of its id (half the points in the last round, a quarter in the one
 * before, ...), rounds go from the smallest to the largest, and within a
 * round the points go in id order, which is spatially coherent (Morton
 * order in the one-part engine, src/geom/morton.h; a part's kd-tree order
 * in the wall engine), so each point is located from the last tet made,
 * nearby.
 *
 * Location: the remembering stochastic visibility walk (Devillers, Pion,
 * Teillaud 2002): from the current tet, cross a face that has p strictly on
 * its far side, trying the faces from a pseudo-random start and never the
 * one just crossed; stop in a tet that holds p (closed) or on reaching an
 * infinite tet (p strictly outside that hull face). In a regular
 * triangulation (the perturbed DT is one) the relation "in front of, seen
 * from p" is acyclic (Edelsbrunner 1990), so any choice of exit face ends,
 * visiting each tet at most once: a walk longer than the number of slots
 * is an internal error.
 */
#include "mesh/insert.h"
#include "mesh/insert_impl.h"

#include <stdlib.h>
#include <string.h>
#include "base/bits.h"
#include "base/mem.h"

/* State of one build that the result does not keep. */
typedef struct build {
    fdt_ins *m;
    fdt_pred_counts *cnt;
    uint8_t *mark;                 /* cap entries */
    uint32_t nfree;                /* slots on the free list */
    uint32_t *cav;                 /* the cavity's tets */
    size_t ncav, cavcap;
    uint32_t *bnd;                 /* its boundary faces, packed (tet, k) */
    size_t nbnd, bndcap;
    uint32_t *outl;                /* tets tested and found not in conflict */
    size_t nout, outcap;
    uint32_t *newt;                /* the new tets' slots */
    size_t newcap;
    ins_local local;               /* links small stars (ins_make_star) */
    ins_edges edges;               /* links the others */
    uint64_t rng;                  /* the walk's choices */
    ins_hull hull;                 /* the hull walks (insert_impl.h) */
} build;

/* ------------------------------------------------------------------ */
/* Slots and scratch. */

/* The conflict marks grown to the tets array's new capacity nc: a zeroed
 * block (its pages first touched where a slot is used, as the tets'
 * are), the marks of the slots in use copied. */
static int set_capacity(build *b, uint64_t nc)
{
    fdt_ins *m = b->m;
    uint8_t *mk = calloc((size_t)nc, 1);
    if (!mk)
        return FDT_ENOMEM;
    memcpy(mk, b->mark, m->nslots);
    free(b->mark);
    b->mark = mk;
    m->cap = (uint32_t)nc;
    return FDT_OK;
}

/* Makes room for `extra` more tets (free list plus unused capacity). */
static int reserve_slots(build *b, uint32_t extra)
{
    fdt_ins *m = b->m;
    if ((uint64_t)b->nfree + (m->cap - m->nslots) >= extra)
        return FDT_OK;
    uint64_t need = (uint64_t)m->nslots + extra - b->nfree, nc;
    int err = ins_grow_tets(m, need, m->nslots, &nc);
    return err ? err : set_capacity(b, nc);
}

/*
 * The whole build's slots, sized once its first `done` points are in
 * (ins_slots_wanted): the first block holds 6.75 slots a point, which
 * uniform points pass past about a million (6.77 tets a point and the
 * hull), and a growth late in the build holds two blocks at once
 * (bench/NOTES.md entry 117: 497 bytes a point at the peak on 2M uniform
 * points, 283 on 1M). Here the copy is of the few slots in use.
 */
static int size_for_all(build *b, uint32_t done, uint32_t n)
{
    fdt_ins *m = b->m;
    uint64_t want = ins_slots_wanted(m, done, b->nfree, n, 1024);
    if (want <= m->cap)
        return FDT_OK;
    int err = ins_move_tets(m, want, m->nslots);
    return err ? err : set_capacity(b, want);
}

/* A slot for a new tet (reserve_slots first). Freed slots first: they
 * were the last cavity's, in cache and near the next one. */
static inline uint32_t alloc_slot(build *b)
{
    fdt_ins *m = b->m;
    if (m->free_head != FDT_NONE) {
        uint32_t t = m->free_head;
        m->free_head = m->T[8 * (size_t)t + 4];
        b->nfree--;
        return t;
    }
    return m->nslots++;
}

static inline void free_slot(build *b, uint32_t t)
{
    fdt_ins *m = b->m;
    uint32_t *v = m->T + 8 * (size_t)t;
    v[0] = v[1] = INF;
    v[4] = m->free_head;
    m->free_head = t;
    b->nfree++;
}

/* ------------------------------------------------------------------ */
/* Insertion. */

/* walk's return when it stopped at its budget of steps (*out: where) */
#define WALK_LONG 1

/* The walk (see the top) from `start` to the tet holding p, or to the
 * infinite tet over a hull face p is strictly outside, in at most budget
 * steps (SIZE_MAX: no bound; else WALK_LONG at the bound). rng: the walk's
 * pseudo-random choices (the caller's); steps counts the tets crossed
 * (may be NULL). Reads m only, so other threads may walk a built mesh. */
static int walk(const fdt_ins *m, const double *p, uint32_t start, uint64_t *rng,
                const fdt_pred_static *sf, fdt_pred_counts *cnt, size_t budget,
                size_t *steps_out, uint32_t *out)
{
    const uint32_t *T = m->T;
    uint32_t t = start;
    for (int i = 0; i < 4; i++)
        if (T[8 * (size_t)t + i] == INF) { /* start in the finite tet below */
            t = T[8 * (size_t)t + 4 + i] >> 2;
            break;
        }
    int from = -1;
    size_t steps = 0;
    int err = FDT_OK;
    for (;; steps++) {
        if (steps > m->nslots)
            return FDT_EINTERNAL; /* a cycle: impossible in a regular triangulation */
        const uint32_t *v = T + 8 * (size_t)t;
        if (ins_is_infinite(v))
            break; /* located: at any step, the budget's last too */
        if (steps == budget) {
            err = WALK_LONG;
            break;
        }
        int exit = ins_walk_exit(m, v, p, from, rng, sf, cnt);
        if (exit < 0)
            break;
        uint32_t nb = v[4 + exit];
        t = nb >> 2;
        from = (int)(nb & 3);
    }
    if (steps_out)
        *steps_out += steps;
    *out = t;
    return err;
}

/* The tet where the build's walk for p from `start` ends. */
static int locate(build *b, const double *p, uint32_t start, uint32_t *out)
{
    return walk(b->m, p, start, &b->rng, &b->m->sf, b->cnt, SIZE_MAX, &b->m->stats.walk_steps,
                out);
}

/* Whether tet t is in conflict with p (see the top for infinite tets). */
static inline int conflict(build *b, uint32_t t, const double *p)
{
    b->m->stats.conflict_tests++;
    return ins_conflict(b->m, t, p, &b->m->sf, b->cnt);
}

/* The hull walk (insert_impl.h) from the last star's infinite tets to p:
 * 1 with the cavity's start in *t0, 0 with a tet near p for the
 * visibility walk to start from, or -1 (*t0 unchanged) when it gave up:
 * no hull face in the last star, no o, or INS_HULL_WALK_STEPS steps. Out
 * of insert_point's code: most inputs take it for a few points (1M
 * uniform: 188). */
__attribute__((noinline, cold)) static int hull_walk(build *b, const double *p, uint32_t *t0)
{
    fdt_ins *m = b->m;
    const uint32_t *T = m->T;
    ins_hull *h = &b->hull;
    /* the last star's hull faces first: in cache, and p, next to the
     * last point, is often outside one of them */
    uint32_t t = FDT_NONE;
    int inf = -1;
    for (size_t i = 0; i < b->nbnd; i++) {
        const uint32_t *w = T + 8 * (size_t)b->newt[i];
        if (!ins_is_infinite(w))
            continue;
        t = b->newt[i];
        if (ins_conflict_local(m, w, p, &m->sf, b->cnt, &inf) == 1) {
            *t0 = t;
            return 1;
        }
    }
    if (t == FDT_NONE)
        return -1;
    const uint32_t *v = T + 8 * (size_t)t;
    if (h->has_o == 0)
        h->has_o = ins_hull_origin(m, T + 8 * (size_t)(v[4 + fdt_ins_inf_index(v)] >> 2), h->o,
                                   &m->sf, b->cnt)
                       ? 1
                       : -1;
    if (h->has_o < 0)
        return -1;
    int from = -1, steps = 0;
    for (;; steps++) {
        if (steps == INS_HULL_WALK_STEPS)
            return -1;
        v = T + 8 * (size_t)t;
        int exit = ins_hull_exit(m, v, h->o, p, from, &b->rng, &m->sf, b->cnt);
        if (exit < 0)
            break;
        uint32_t nb = v[4 + exit];
        t = nb >> 2;
        from = (int)(nb & 3);
    }
    if (ins_conflict_local(m, v, p, &m->sf, b->cnt, &inf) == 1) {
        *t0 = t;
        return 1;
    }
    *t0 = v[4 + fdt_ins_inf_index(v)] >> 2;
    return 0;
}

/* The tet where p's cavity starts: the walk from the last star, and
 * where the last point lay outside the hull and this walk grows long,
 * the hull walk (most of a surface's points never need it: a sphere's
 * random points walk 8 tets, its integer points 140). */
static int locate_from(build *b, const double *p, uint32_t start, uint32_t *t0)
{
    fdt_ins *m = b->m;
    int err = walk(m, p, start, &b->rng, &m->sf, b->cnt, ins_hull_budget(&b->hull, m),
                   &m->stats.walk_steps, t0);
    if (err != WALK_LONG)
        return err;
    int got = hull_walk(b, p, t0);
    ins_hull_count(&b->hull, &m->stats.hull_walks, got);
    return got == 1 ? FDT_OK : locate(b, p, *t0, t0);
}

static int insert_point(build *b, uint32_t pid, uint32_t *last)
{
    fdt_ins *m = b->m;
    const double *p = ins_pt(m, pid);
    uint32_t t0;
    int err = locate_from(b, p, *last, &t0);
    if (err)
        return err;
    b->hull.outside = ins_is_infinite(m->T + 8 * (size_t)t0);
    const uint32_t *v0 = m->T + 8 * (size_t)t0;
    /* A point equal to a vertex lies in the closed tet of that vertex only,
     * so the walk ends in a tet that has it: refuse rather than break the
     * perturbation's precondition (pairwise distinct points). */
    if (ins_is_vertex(m, v0, p))
        return FDT_EINVAL;

    /* The cavity, breadth-first. The walk's tet holds p (closed), and a
     * point of a closed tet other than its vertices is strictly inside its
     * circumsphere; an infinite tet where the walk stops has p strictly
     * outside its hull face. Either way it is in conflict. */
    b->ncav = b->nbnd = b->nout = 0;
    size_t unsure0 = b->cnt->insphere_unsure; /* see ins_star_ok */
    uint8_t *mark = b->mark;
    mark[t0] = MARK_IN;
    b->cav[b->ncav++] = t0;
    ins_prefetch_nbrs(m->T, t0);
    for (size_t ci = 0; ci < b->ncav; ci++) {
        uint32_t c = b->cav[ci];
        /* The faces whose neighbour is not in the cavity yet, listed
         * without a branch: which ones are is a coin flip, and a branch on
         * it mispredicted about twice a cavity tet (bench/NOTES.md entry
         * 93). */
        const uint32_t *nb = m->T + 8 * (size_t)c + 4;
        uint32_t os[4];
        int ks[4], nk = 0;
        for (int k = 0; k < 4; k++) {
            ks[nk] = k;
            os[nk] = nb[k] >> 2;
            nk += mark[os[nk]] != MARK_IN;
        }
        for (int j = 0; j < nk; j++) {
            int k = ks[j];
            uint32_t o = os[j];
            if (mark[o] == MARK_NONE) {
                int cf = conflict(b, o, p);
                if (cf < 0)
                    return cf;
                if (cf) {
                    if (b->ncav == b->cavcap &&
                        (err = ins_grow_u32(&b->cav, &b->cavcap, b->ncav + 1)) != FDT_OK)
                        return err;
                    mark[o] = MARK_IN;
                    b->cav[b->ncav++] = o;
                    ins_prefetch_nbrs(m->T, o); /* tested next */
                    continue;
                }
                if (b->nout == b->outcap &&
                    (err = ins_grow_u32(&b->outl, &b->outcap, b->nout + 1)) != FDT_OK)
                    return err;
                mark[o] = MARK_OUT;
                b->outl[b->nout++] = o;
            }
            if (b->nbnd == b->bndcap &&
                (err = ins_grow_u32(&b->bnd, &b->bndcap, b->nbnd + 1)) != FDT_OK)
                return err;
            b->bnd[b->nbnd++] = PACK(c, k);
        }
    }
    if (b->nbnd > UINT32_MAX / 2)
        return FDT_ETOOBIG;
    if (!ins_star_ok(m, b->bnd, b->nbnd, p, b->cnt, unsure0))
        return FDT_EINTERNAL;
    if ((err = reserve_slots(b, (uint32_t)b->nbnd)) != FDT_OK)
        return err;
    if ((err = ins_grow_u32(&b->newt, &b->newcap, b->nbnd)) != FDT_OK)
        return err;
    mark = b->mark; /* reserve_slots may have moved it */

    /* The new tets (ins_star_tet), allocated before the cavity is freed,
     * so reading it is safe; the cavity's slots serve the next insertion. */
    for (size_t i = 0; i < b->nbnd; i++)
        b->newt[i] = alloc_slot(b);
    if ((err = ins_make_star(&b->local, &b->edges, m->T, b->bnd, b->nbnd, pid, b->newt)) !=
        FDT_OK)
        return err;
    for (size_t i = 0; i < b->ncav; i++) {
        mark[b->cav[i]] = MARK_NONE;
        free_slot(b, b->cav[i]);
    }
    for (size_t i = 0; i < b->nout; i++)
        mark[b->outl[i]] = MARK_NONE;
    ins_count_cavity(&m->stats, b->ncav, b->nbnd);
    *last = b->newt[b->nbnd - 1];
    return FDT_OK;
}

/* ------------------------------------------------------------------ */
/* Start: order and the first tetrahedron. */

/* A hash of the id for the BRIO rounds (a murmur-style finalizer). */
static inline uint32_t mix32(uint32_t x)
{
    x ^= x >> 16;
    x *= UINT32_C(0x7feb352d);
    x ^= x >> 15;
    x *= UINT32_C(0x846ca68b);
    x ^= x >> 16;
    return x;
}

/* The squared distance of p from c (inf where it overflows). */
static inline double dist2(const double *p, const double *c)
{
    double dx = p[0] - c[0], dy = p[1] - c[1], dz = p[2] - c[2];
    return dx * dx + dy * dy + dz * dz;
}

/*
 * Moves the point nearest the centre of the points' bounding box to
 * order[0], the first point inserted. A point inside a shell (a scanner's
 * position in its scan, a probe at the centre of a sphere: gen_points
 * `centre`) is a vertex of a cone over the whole shell. Inserted late (it
 * was at 93,735 of 100,000 there), it finds the shell's interior filled
 * with tets spanning the shell, every shell point's cavity runs through
 * them, and its own cavity is all of them: in the parallel build the two
 * workers' cavities met 62k-185k times and the build took 0.30 s CPU;
 * inserted first, the interior is its cone from the start, cavities stay
 * on the shell, and the build takes 0.12 s (bench/NOTES.md entry 55).
 * Elsewhere it is one point out of BRIO order. The DT is unique, so the
 * order changes nothing but the slot numbering.
 */
static void centre_first(const double *P, uint32_t *order, uint32_t n)
{
    double lo[3], hi[3];
    const double *p0 = P + 3 * (size_t)order[0];
    for (int k = 0; k < 3; k++)
        lo[k] = hi[k] = p0[k];
    for (uint32_t i = 1; i < n; i++) {
        const double *p = P + 3 * (size_t)order[i];
        for (int k = 0; k < 3; k++) {
            lo[k] = p[k] < lo[k] ? p[k] : lo[k];
            hi[k] = p[k] > hi[k] ? p[k] : hi[k];
        }
    }
    double c[3];
    for (int k = 0; k < 3; k++)
        c[k] = lo[k] * 0.5 + hi[k] * 0.5; /* no overflow at 1e308 */
    uint32_t best = 0;
    double bd = dist2(p0, c);
    for (uint32_t i = 1; i < n; i++) {
        double d = dist2(P + 3 * (size_t)order[i], c);
        if (d < bd) {
            bd = d;
            best = i;
        }
    }
    uint32_t t = order[0];
    order[0] = order[best];
    order[best] = t;
}

/* order[] = the ids by round (BRIO), the smallest round first, ids
 * ascending within a round but for the point nearest the centre, which
 * goes first (centre_first). Round L (the first) takes the points whose
 * hash has at least L trailing zeros, round l < L those with exactly l:
 * expected sizes n 2^-L, ..., n/4, n/2. L makes the first round about 128
 * to 256 points. */
void fdt_ins_brio(const double *P, uint32_t base, uint32_t n, uint32_t *order,
                  uint32_t *round_end, int *nrounds)
{
    int L = 0;
    while (L < 30 && (n >> (L + 1)) >= 128)
        L++;
    size_t count[32] = {0};
    for (uint32_t i = 0; i < n; i++)
        count[L - fdt_ctz64(mix32(base + i) | (UINT64_C(1) << L))]++;
    size_t pos[32], acc = 0;
    for (int r = 0; r <= L; r++) {
        pos[r] = acc;
        acc += count[r];
        round_end[r] = (uint32_t)acc;
    }
    *nrounds = L + 1;
    for (uint32_t i = 0; i < n; i++)
        order[pos[L - fdt_ctz64(mix32(base + i) | (UINT64_C(1) << L))]++] = base + i;
    if (n > 0)
        centre_first(P, order, n);
}

/*
 * Exactly: are a, b, c collinear? Collinear iff the three projections onto
 * the coordinate planes are degenerate; the projection dropping axis k is
 * degenerate iff orient3d(a, b, c, d) = 0 for d = a moved along axis k
 * (the determinant is the projected doubled area times the move). Every
 * coordinate is a double, so the exact orient3d decides.
 */
static int collinear(const double *a, const double *b, const double *c, fdt_pred_counts *cnt)
{
    for (int k = 0; k < 3; k++) {
        double d[3] = {a[0], a[1], a[2]};
        d[k] = a[k] != 0.0 ? -a[k] : 1.0;
        if (fdt_orient3d(a, b, c, d, cnt) != 0)
            return 0;
    }
    return 1;
}

/*
 * The first tetrahedron, from the start of the order, and the four
 * infinite tets over its faces. FDT_EDEGENERATE if the points do not span
 * 3-D space. first[] gets the four ids used.
 */
static int start_simplex(build *b, const uint32_t *order, uint32_t n, uint32_t first[4])
{
    fdt_ins *m = b->m;
    if (n < 4)
        return FDT_EDEGENERATE;
    uint32_t a = order[0], c0 = order[1], c = FDT_NONE, d = FDT_NONE;
    for (uint32_t i = 2; i < n && c == FDT_NONE; i++)
        if (!collinear(ins_pt(m, a), ins_pt(m, c0), ins_pt(m, order[i]), b->cnt))
            c = order[i];
    if (c == FDT_NONE)
        return FDT_EDEGENERATE; /* all collinear */
    int o = 0;
    for (uint32_t i = 2; i < n && d == FDT_NONE; i++) {
        if (order[i] == c)
            continue;
        o = ins_orient(ins_pt(m, a), ins_pt(m, c0), ins_pt(m, c), ins_pt(m, order[i]), &m->sf,
                       b->cnt);
        if (o != 0)
            d = order[i];
    }
    if (d == FDT_NONE)
        return FDT_EDEGENERATE; /* all coplanar */
    uint32_t v[4] = {a, c0, c, d};
    if (o < 0) {
        v[0] = c0;
        v[1] = a;
    }
    memcpy(first, v, sizeof v);
    int err = reserve_slots(b, 5);
    if (err)
        return err;
    if ((err = ins_edges_begin(&b->edges, 12)) != FDT_OK)
        return err;
    uint32_t *T = m->T;
    uint32_t t0 = alloc_slot(b);
    memcpy(T + 8 * (size_t)t0, v, sizeof v);
    /* Over face k (outward order fdt_tet_face[k]: v[k] on its negative
     * side, the outside on its positive side) the infinite tet (face, INF),
     * positive in the sense of src/mesh/insmesh.h, its vertices reordered
     * by ins_to_front as a star tet's: (INF, f2, f1, f0). */
    uint32_t hull[4];
    for (int k = 0; k < 4; k++) {
        uint32_t s = hull[k] = alloc_slot(b);
        uint32_t *w = T + 8 * (size_t)s;
        w[0] = INF;
        for (int j = 0; j < 3; j++)
            w[1 + j] = v[fdt_tet_face[k][2 - j]];
        w[4] = PACK(t0, k);
        T[8 * (size_t)t0 + 4 + k] = PACK(s, 0);
    }
    /* The four are the star of the infinite vertex over t0's faces. */
    return ins_link_star(&b->edges, T, hull, 4);
}

/* The points' bounding box and its semi-static filter bounds. */
static void ins_bounds(fdt_ins *m)
{
    const double *p0 = ins_pt(m, m->base);
    for (int k = 0; k < 3; k++)
        m->lo[k] = m->hi[k] = p0[k];
    for (uint32_t i = 1; i < m->n; i++) {
        const double *p = ins_pt(m, m->base + i);
        for (int k = 0; k < 3; k++) {
            m->lo[k] = p[k] < m->lo[k] ? p[k] : m->lo[k];
            m->hi[k] = p[k] > m->hi[k] ? p[k] : m->hi[k];
        }
    }
    fdt_pred_static_init(&m->sf, m->lo, m->hi);
}

/* ------------------------------------------------------------------ */

static void build_free(build *b)
{
    free(b->mark);
    free(b->cav);
    free(b->bnd);
    free(b->outl);
    free(b->newt);
    free(b->edges.eh);
    free(b->local.lid);
}

int fdt_ins_build_prefix(fdt_ins *m, const double *P, uint32_t base, uint32_t n,
                         const uint32_t *order, uint32_t prefix, uint64_t slots,
                         uint32_t first[4], const fdt_images *img, fdt_pred_counts *cnt,
                         fdt_progress_fn progress, void *puser)
{
    memset(m, 0, sizeof *m);
    m->P = P;
    m->base = base;
    m->n = n;
    m->free_head = FDT_NONE;
    if (n < 4)
        return FDT_EDEGENERATE;
    ins_bounds(m);
    if (img) /* the filters' bounds for rounded images (src/geom/images.h) */
        m->sf = fdt_images_static(img);
    build b;
    memset(&b, 0, sizeof b);
    b.m = m;
    fdt_pred_counts own = {0}; /* the insertion reads its counts (ins_star_ok) */
    b.cnt = cnt ? cnt : &own;
    b.rng = UINT64_C(0x853c49e6748fea9b);
    int err = FDT_ENOMEM;
    if (slots > INS_MAX_SLOTS)
        slots = INS_MAX_SLOTS;
    if (slots < 64)
        slots = 64;
    m->T = malloc((size_t)slots * 8 * sizeof *m->T);
    b.mark = calloc((size_t)slots, 1);
    b.local.lid = calloc((size_t)n + 1, 1);
    b.local.base = base;
    b.local.n = n;
    if (!m->T || !b.mark || !b.local.lid)
        goto fail;
    fdt_mem_advise_huge(m->T, (size_t)slots * 8 * sizeof *m->T);
    m->cap = (uint32_t)slots;
    if ((err = ins_grow_u32(&b.cav, &b.cavcap, 64)) != FDT_OK ||
        (err = ins_grow_u32(&b.bnd, &b.bndcap, 256)) != FDT_OK ||
        (err = ins_grow_u32(&b.outl, &b.outcap, 256)) != FDT_OK)
        goto fail;
    if ((err = start_simplex(&b, order, n, first)) != FDT_OK)
        goto fail;
    uint32_t last = 0;
    /* The whole build sizes its slots once, after the first 1/128 of its
     * points (size_for_all); the parallel build sizes for its workers
     * after its prefix instead (src/mesh/insert_par.c). */
    uint32_t size_at = prefix == n && n >= 65536 ? n / 128 : UINT32_MAX;
    for (uint32_t i = 0; i < prefix; i++) {
        if (i == size_at && (err = size_for_all(&b, i, n)) != FDT_OK)
            goto fail;
        uint32_t id = order[i];
        if (id == first[0] || id == first[1] || id == first[2] || id == first[3])
            continue;
        if ((err = insert_point(&b, id, &last)) != FDT_OK)
            goto fail;
        if (progress && (i & 0xffff) == 0xffff &&
            progress(puser, (double)i / (double)prefix) != 0) {
            err = FDT_ECANCELED;
            goto fail;
        }
    }
    build_free(&b);
    return FDT_OK;
fail:
    build_free(&b);
    fdt_ins_free(m);
    return err;
}

int fdt_ins_finish(fdt_ins *m)
{
    /* The incident-tet table, the counts and the free list, from one pass
     * over the slots: cheaper than keeping them current through the
     * insertions (and the parallel build has one free list a thread). */
    m->stats.inserted = m->n;
    m->nfinite = m->ninfinite = 0;
    m->free_head = FDT_NONE;
    m->vtet = malloc((size_t)m->n * sizeof *m->vtet);
    if (!m->vtet) {
        fdt_ins_free(m);
        return FDT_ENOMEM;
    }
    for (uint32_t i = 0; i < m->n; i++)
        m->vtet[i] = FDT_NONE;
    for (uint32_t t = m->nslots; t-- > 0;) {
        uint32_t *v = m->T + 8 * (size_t)t;
        if (v[0] == INF && v[1] == INF) { /* freed */
            v[4] = m->free_head;
            m->free_head = t;
            continue;
        }
        int inf = 0;
        for (int i = 0; i < 4; i++) {
            if (v[i] == INF)
                inf = 1;
            else
                m->vtet[v[i] - m->base] = t;
        }
        if (inf)
            m->ninfinite++;
        else
            m->nfinite++;
    }
    for (uint32_t i = 0; i < m->n; i++)
        if (m->vtet[i] == FDT_NONE) {
            fdt_ins_free(m);
            return FDT_EINTERNAL; /* every point is a vertex of its DT */
        }
    return FDT_OK;
}

int fdt_ins_build(fdt_ins *m, const double *P, uint32_t base, uint32_t n,
                  fdt_pred_counts *cnt)
{
    return fdt_ins_build_progress(m, P, base, n, cnt, NULL, NULL);
}

int fdt_ins_build_progress(fdt_ins *m, const double *P, uint32_t base, uint32_t n,
                           fdt_pred_counts *cnt, fdt_progress_fn progress, void *puser)
{
    return fdt_ins_build_serial(m, P, base, n, NULL, cnt, progress, puser);
}

int fdt_ins_build_serial(fdt_ins *m, const double *P, uint32_t base, uint32_t n,
                         const fdt_images *img, fdt_pred_counts *cnt, fdt_progress_fn progress,
                         void *puser)
{
    if (ins_begin(m, P, base, n) != FDT_OK)
        return FDT_EDEGENERATE;
    uint32_t *order = malloc((size_t)n * sizeof *order);
    if (!order)
        return FDT_ENOMEM;
    uint32_t round_end[32], first[4];
    int nrounds;
    fdt_ins_brio(P, base, n, order, round_end, &nrounds);
    /* About 6.5 tets a point on uniform points, plus the hull: growing by
     * realloc stays possible for inputs with more. */
    int err = fdt_ins_build_prefix(m, P, base, n, order, n, (uint64_t)n * 27 / 4 + 64, first,
                                   img, cnt, progress, puser);
    free(order);
    if (err)
        return err;
    return fdt_ins_finish(m);
}

uint32_t fdt_ins_next_finite(const fdt_ins *m, uint32_t t)
{
    for (; t < m->nslots; t++)
        if (fdt_ins_is_finite(m, t))
            return t;
    return FDT_NONE;
}

/* ------------------------------------------------------------------ */
/* Queries. */

/*
 * If tet t (vertices v) has the vertices a, b, c, the tet on the open side
 * of (a, b, c) and the index of that face in it: t itself when (a, b, c,
 * v[k]) is an even permutation of t's order (then it is positive, so
 * v[k] is on the open side), else t's neighbour across that face.
 */
static int face_in_tet(const fdt_ins *m, uint32_t t, uint32_t a, uint32_t b, uint32_t c,
                       uint32_t *tet, int *k)
{
    const uint32_t *v = m->T + 8 * (size_t)t;
    int pa = -1, pb = -1, pc = -1;
    for (int i = 0; i < 4; i++) {
        if (v[i] == a)
            pa = i;
        else if (v[i] == b)
            pb = i;
        else if (v[i] == c)
            pc = i;
    }
    if (pa < 0 || pb < 0 || pc < 0)
        return 0;
    int pk = 6 - pa - pb - pc;
    int perm[4] = {pa, pb, pc, pk}, inv = 0;
    for (int i = 0; i < 4; i++)
        for (int j = i + 1; j < 4; j++)
            inv += perm[i] > perm[j];
    if (inv % 2 == 0) {
        *tet = t;
        *k = pk;
    } else {
        uint32_t r = v[4 + pk];
        *tet = r >> 2;
        *k = (int)(r & 3);
    }
    return 1;
}

/* The visited set of the star search: an open-addressing table of slot
 * ids (FDT_NONE: empty) and the BFS queue, which lists every tet seen. */
typedef struct star_buf {
    uint32_t *queue, *set;
    size_t cap;      /* queue capacity; the set has 2 cap slots */
} star_buf;

static int star_insert(star_buf *s, uint32_t t)
{
    size_t mask = 2 * s->cap - 1;
    size_t h = (size_t)((t * UINT64_C(0x9E3779B97F4A7C15)) >> 20) & mask;
    for (;; h = (h + 1) & mask) {
        if (s->set[h] == t)
            return 0;
        if (s->set[h] == FDT_NONE) {
            s->set[h] = t;
            return 1;
        }
    }
}

static int scan_all(const fdt_ins *m, uint32_t a, uint32_t b, uint32_t c, uint32_t *tet, int *k)
{
    for (uint32_t t = 0; t < m->nslots; t++) {
        const uint32_t *v = m->T + 8 * (size_t)t;
        if (v[0] == INF && v[1] == INF)
            continue;
        if (face_in_tet(m, t, a, b, c, tet, k))
            return 1;
    }
    return 0;
}

int fdt_ins_find_face(const fdt_ins *m, uint32_t a, uint32_t b, uint32_t c,
                      uint32_t *tet, int *k)
{
    if (!m->vtet || a - m->base >= m->n || b - m->base >= m->n || c - m->base >= m->n ||
        a == b || b == c || a == c)
        return 0;
    enum { LOCAL = 512 };
    uint32_t lq[LOCAL], ls[2 * LOCAL];
    star_buf s = {lq, ls, LOCAL};
    for (size_t i = 0; i < 2 * LOCAL; i++)
        ls[i] = FDT_NONE;
    int found = 0;
    size_t nq = 0;
    uint32_t t0 = m->vtet[a - m->base];
    star_insert(&s, t0);
    s.queue[nq++] = t0;
    for (size_t qi = 0; qi < nq; qi++) {
        uint32_t t = s.queue[qi];
        if (face_in_tet(m, t, a, b, c, tet, k)) {
            found = 1;
            break;
        }
        const uint32_t *v = m->T + 8 * (size_t)t;
        for (int j = 0; j < 4; j++) {
            if (v[j] == a)
                continue; /* the faces through a lead to a's other tets */
            uint32_t o = v[4 + j] >> 2;
            if (nq == s.cap) { /* a big star: a bigger buffer, or the scan */
                size_t nc = 4 * s.cap;
                uint32_t *q = malloc(3 * nc * sizeof *q);
                if (!q) {
                    found = scan_all(m, a, b, c, tet, k);
                    goto done;
                }
                memcpy(q, s.queue, nq * sizeof *q);
                if (s.queue != lq)
                    free(s.queue);
                s.queue = q;
                s.set = q + nc;
                s.cap = nc;
                for (size_t i = 0; i < 2 * nc; i++)
                    s.set[i] = FDT_NONE;
                for (size_t i = 0; i < nq; i++)
                    star_insert(&s, s.queue[i]);
            }
            if (star_insert(&s, o))
                s.queue[nq++] = o;
        }
    }
done:
    if (s.queue != lq)
        free(s.queue);
    return found;
}

/* ------------------------------------------------------------------ */
/* Read-only queries by another thread: the conflict region of a point
 * that is not in the mesh. */

/* Adds x to the open-addressing set (2 cap slots, FDT_NONE empty) and to
 * the list behind it; 1 if new, 0 if there, FDT_ENOMEM. */
static int qset_add(uint32_t **list, uint32_t **set, size_t *n, size_t *cap, uint32_t x)
{
    if (*n == *cap) {
        size_t nc = *cap ? 2 * *cap : 64;
        uint32_t *l = realloc(*list, nc * sizeof *l);
        if (!l)
            return FDT_ENOMEM;
        *list = l;
        uint32_t *s = malloc(2 * nc * sizeof *s);
        if (!s)
            return FDT_ENOMEM;
        free(*set);
        *set = s;
        *cap = nc;
        memset(s, 0xff, 2 * nc * sizeof *s);
        for (size_t i = 0; i < *n; i++) {
            size_t h = (size_t)((l[i] * UINT64_C(0x9E3779B97F4A7C15)) >> 20) & (2 * nc - 1);
            while (s[h] != FDT_NONE)
                h = (h + 1) & (2 * nc - 1);
            s[h] = l[i];
        }
    }
    size_t mask = 2 * *cap - 1;
    size_t h = (size_t)((x * UINT64_C(0x9E3779B97F4A7C15)) >> 20) & mask;
    for (;; h = (h + 1) & mask) {
        if ((*set)[h] == x)
            return 0;
        if ((*set)[h] == FDT_NONE)
            break;
    }
    (*set)[h] = x;
    (*list)[(*n)++] = x;
    return 1;
}

/* Whether x is in the set (cap 0: nothing is). */
static int qset_has(const uint32_t *set, size_t cap, uint32_t x)
{
    if (!cap)
        return 0;
    size_t mask = 2 * cap - 1;
    size_t h = (size_t)((x * UINT64_C(0x9E3779B97F4A7C15)) >> 20) & mask;
    for (;; h = (h + 1) & mask) {
        if (set[h] == x)
            return 1;
        if (set[h] == FDT_NONE)
            return 0;
    }
}

/* Empties a set by its list (the set's slots are found again by hash). */
static void qset_clear(uint32_t *list, uint32_t *set, size_t *n, size_t cap)
{
    if (*n * 8 > cap) {
        memset(set, 0xff, 2 * cap * sizeof *set);
    } else {
        size_t mask = 2 * cap - 1;
        for (size_t i = 0; i < *n; i++) {
            size_t h = (size_t)((list[i] * UINT64_C(0x9E3779B97F4A7C15)) >> 20) & mask;
            while (set[h] != list[i])
                h = (h + 1) & mask;
            set[h] = FDT_NONE;
        }
        /* Backward-shift deletion is not needed: the whole set empties,
         * and every probe chain of the set's members is emptied with it. */
    }
    *n = 0;
}

void fdt_ins_query_free(fdt_ins_query *qs)
{
    free(qs->tq);
    free(qs->tset);
    free(qs->vs);
    free(qs->vset);
    memset(qs, 0, sizeof *qs);
}

int fdt_ins_conflict_vertices(const fdt_ins *m, const double *q, uint32_t *hint,
                              size_t max_tets, fdt_ins_query *qs, fdt_pred_counts *cnt)
{
    const uint32_t *T = m->T;
    if (qs->tset)
        qset_clear(qs->tq, qs->tset, &qs->ntq, qs->tcap);
    if (qs->vset)
        qset_clear(qs->vs, qs->vset, &qs->nvs, qs->vcap);
    /* The walk, from the hint if it is a live slot. */
    uint32_t t = *hint;
    if (t >= m->nslots || (T[8 * (size_t)t] == INF && T[8 * (size_t)t + 1] == INF))
        t = m->vtet[0];
    /* q is not one of the mesh's points: the semi-static bounds of the box
     * that holds both. */
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = q[k] < m->lo[k] ? q[k] : m->lo[k];
        hi[k] = q[k] > m->hi[k] ? q[k] : m->hi[k];
    }
    fdt_pred_static sf;
    fdt_pred_static_init(&sf, lo, hi);
    int err = walk(m, q, t, &qs->rng, &sf, cnt, SIZE_MAX, NULL, &t);
    if (err)
        return err;
    *hint = t;
    /* q is not a vertex (the caller's point belongs to another part, and
     * the points are pairwise distinct), so the tet found is in conflict
     * (see insert_point); the region is connected: breadth-first. */
    int rc = qset_add(&qs->tq, &qs->tset, &qs->ntq, &qs->tcap, t);
    if (rc < 0)
        return rc;
    for (size_t i = 0; i < qs->ntq; i++) {
        if (i >= max_tets)
            return 1;
        uint32_t c = qs->tq[i];
        const uint32_t *v = T + 8 * (size_t)c;
        for (int k = 0; k < 4; k++) {
            if (v[k] != INF &&
                (rc = qset_add(&qs->vs, &qs->vset, &qs->nvs, &qs->vcap, v[k])) < 0)
                return rc;
            uint32_t o = v[4 + k] >> 2;
            /* Tets found not in conflict are tested again if met again:
             * the region's boundary is small next to the work saved by
             * not keeping a second set. */
            if (qset_has(qs->tset, qs->tcap, o))
                continue;
            int cf = ins_conflict(m, o, q, &sf, cnt);
            if (cf < 0)
                return cf;
            if (cf && (rc = qset_add(&qs->tq, &qs->tset, &qs->ntq, &qs->tcap, o)) < 0)
                return rc;
        }
    }
    return FDT_OK;
}

int fdt_ins_star_vertices(const fdt_ins *m, uint32_t a, size_t max_tets, fdt_ins_query *qs)
{
    if (!m->vtet || a - m->base >= m->n)
        return 1;
    const uint32_t *T = m->T;
    if (qs->tset)
        qset_clear(qs->tq, qs->tset, &qs->ntq, qs->tcap);
    if (qs->vset)
        qset_clear(qs->vs, qs->vset, &qs->nvs, qs->vcap);
    /* a's star, breadth-first from its incident tet through the faces
     * that hold a (as fdt_ins_find_face walks it) */
    int rc = qset_add(&qs->tq, &qs->tset, &qs->ntq, &qs->tcap, m->vtet[a - m->base]);
    if (rc < 0)
        return rc;
    for (size_t i = 0; i < qs->ntq; i++) {
        if (i >= max_tets)
            return 1;
        const uint32_t *v = T + 8 * (size_t)qs->tq[i];
        for (int k = 0; k < 4; k++) {
            if (v[k] == a)
                continue; /* the face opposite a leaves the star */
            if (v[k] != INF &&
                (rc = qset_add(&qs->vs, &qs->vset, &qs->nvs, &qs->vcap, v[k])) < 0)
                return rc;
            if ((rc = qset_add(&qs->tq, &qs->tset, &qs->ntq, &qs->tcap, v[4 + k] >> 2)) < 0)
                return rc;
        }
    }
    return FDT_OK;
}
