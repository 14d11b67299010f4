/* Parts in sweep order: src/front/sweep.h. */
#include "front/sweep.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "base/mem.h"
#include "base/spawn.h"
#include "front/cellstream.h"
#include "geom/kdtree.h"
#include "geom/morton.h"
#include "mesh/certify.h"
#include "mesh/insert.h"

#define INF FDT_NONE

/* Per-slot marks of a part's mesh: bits 0-3 a face of B (the tet across
 * it was emitted by an earlier part), then membership of U, finality,
 * and what the certificate's pass found of a finite tet's ball (BALL: it
 * ends before the next slabs; BALL_UNSURE: the cofactors could not tell,
 * ball_slow decides). */
enum { IN_U = 16, FINAL = 32, BALL = 64, BALL_UNSURE = 128 };

uint32_t fdt_sweep_slab(size_t m)
{
    /* 32 c^2 with c the integer cube root of m: m^(2/3) without libm, so
     * the cut is the same on every machine */
    uint64_t c = 0;
    while ((c + 1) * (c + 1) * (c + 1) <= (uint64_t)m)
        c++;
    uint64_t s = 32 * c * c;
    return s < (UINT64_C(1) << 18) ? UINT32_C(1) << 18
           : s > (UINT64_C(1) << 21) ? UINT32_C(1) << 21
                                     : (uint32_t)s;
}

/* The sweep's state between parts, and the parts' scratch. */
typedef struct sweep {
    double *P;
    fdt_vid *orig;
    uint32_t m;
    int axis, dir;       /* the sweep's axis, and its direction: +1 upwards,
                            -1 downwards (the coordinates taken negated) */
    int nthreads;        /* the threads building each part's mesh */
    fdt_emit *em;
    fdt_sweep_stats *st;
    char *diag;
    size_t dlen;
    uint32_t *live;      /* L: global ids */
    size_t nlive, lcap;
    uint32_t *wall;      /* B: 3 global ids a face, oriented so that the
                            live side is the open one (fdt_ins_find_face) */
    size_t nwall, wcap;
    uint32_t *nwalls;    /* the next part's B, built beside the old */
    size_t nnw, nwcap;
    double *Q;           /* the part's points */
    fdt_vid *g;          /* the part's local id -> global id */
    fdt_vid *gin;        /* the part's local id -> input index (orig[g]) */
    size_t qcap, gcap, gincap;
    uint64_t *map;       /* global id + 1 << 32 | local id, of L's points */
    size_t mapcap, mapn; /* allocated, in use (a power of two) */
    int closing;         /* the last part emitted a quarter of its tets or more */
    fdt_cellstream *cs;  /* the streamed cells, or NULL (borrowed) */
    fdt_cellheld held;   /* the sweep's tets held for the cells */
    uint32_t *hullpts;   /* the last part's hull faces' points, for the cells */
    size_t nhullpts, hpcap;
} sweep;

/* The slabs: quickselect along the axis at each boundary b[lo .. hi), the
 * middle one first, so that every point of a slab is <= every point of the
 * slabs after it (in place, no sort array). */
static void cut_slabs(double *P, fdt_vid *orig, uint32_t begin, uint32_t end, const uint32_t *b,
                      size_t lo, size_t hi, int axis)
{
    if (lo >= hi)
        return;
    size_t mid = lo + (hi - lo) / 2;
    fdt_kd_select(P, orig, begin, end, b[mid], axis);
    cut_slabs(P, orig, begin, b[mid], b, lo, mid, axis);
    cut_slabs(P, orig, b[mid], end, b, mid + 1, hi, axis);
}

static uint32_t map_hash(uint32_t key, size_t cap)
{
    return (uint32_t)(((uint64_t)key * UINT64_C(0x9E3779B97F4A7C15)) >> 32) & (uint32_t)(cap - 1);
}

/* The local ids of L's points (the global ids outside the slabs'
 * [begin, end)), for finding B's faces in the part's mesh. */
static int map_build(sweep *sw, size_t nq, uint32_t begin, uint32_t end)
{
    size_t cap = 64;
    while (cap < 2 * sw->nlive + 2)
        cap *= 2;
    if (cap > sw->mapcap) {
        free(sw->map);
        if (!(sw->map = malloc(cap * sizeof *sw->map))) {
            sw->mapcap = 0;
            return FDT_ENOMEM;
        }
        sw->mapcap = cap;
    }
    sw->mapn = cap;
    memset(sw->map, 0, cap * sizeof *sw->map);
    for (size_t i = 0; i < nq; i++) {
        uint32_t gid = (uint32_t)sw->g[i];
        if (gid >= begin && gid < end)
            continue;
        uint32_t h = map_hash(gid, cap);
        while (sw->map[h])
            h = (h + 1) & (uint32_t)(cap - 1);
        sw->map[h] = ((uint64_t)(gid + 1) << 32) | (uint32_t)i;
    }
    return FDT_OK;
}

/* The local id of L's point gid, FDT_NONE if it is not in the part. */
static uint32_t map_find(const sweep *sw, uint32_t gid)
{
    size_t cap = sw->mapn;
    uint32_t h = map_hash(gid, cap);
    for (;; h = (h + 1) & (uint32_t)(cap - 1)) {
        uint64_t e = sw->map[h];
        if (!e)
            return FDT_NONE;
        if ((uint32_t)(e >> 32) == gid + 1)
            return (uint32_t)e;
    }
}

/*
 * Whether the circumsphere of the positive finite tet v (local ids of
 * Q) ends strictly before `next` along the sweep (coordinates times dir):
 * then no point at or past `next` lies in or on it. Saying no is always
 * safe (the tet waits for a later part); yes must be certain. 1 yes, 0
 * no, -1 where only ball_slow can tell.
 *
 * First from the lifted cofactors c (src/geom/predicates.h, fdt_sphere_cof:
 * with a = v[0] as the origin, det and N; the centre is a + N / (2 det),
 * the radius |N| / (2 det)). Their errors: |det - det~| <= Bd =
 * FDT_O3D_COF_BOUND m^3 (proved there); each component of N is 18
 * monomials of degree 4 in the differences, each through at most 12
 * roundings (its four differences, the lift's product and two sums, the
 * cross product's product and difference, N's product and two sums), so
 * |N - N~| <= gamma_12 18 m^4 < 216.1 eps m^4, under BN = 2^-45 m^4 with
 * room for computing m^4. With det~ > 4 Bd, the centre's offset o = N /
 * (2 det) is off o~ = N~ / (2 det~) by at most
 *   delta = (BN + |N~|max Bd / det~) / (2 (det~ - Bd))
 * a component (|o - o~| <= |N - N~| / 2det + |N~| |det - det~| / 2 det det~),
 * and the radius |o| by at most sqrt(3) delta; 3 delta covers both, and 8
 * eps of the terms' magnitudes the roundings of o~, its norm and the sum.
 * Where that cannot decide (a tet flat next to its size, differences
 * outside [2^-100, 2^100]), the apex search's conservative ball decides
 * (src/geom/kdtree.c: it holds the true sphere, widened by its rounding
 * bound, infinite where the tet is too flat to bound; the cofactors'
 * bound cost 5 % of a streamed run less): ball_by_cof returns -1 for
 * ball_slow. The cofactors are the certificate's, which computes them
 * for each finite tet (ball_visit, bench/NOTES.md entry 136).
 */
static int ball_by_cof(const sweep *sw, const uint32_t *v, const fdt_sphere_cof *c, double next)
{
    const double *Q = sw->Q;
    const double dir = sw->dir;
    const size_t ax = (size_t)sw->axis;
    for (int i = 0; i < 4; i++)
        if (!(dir * Q[3 * (size_t)v[i] + ax] < next))
            return 0; /* the tet itself reaches next: so does its sphere */
    if (fdt_pred_in_range(c->m)) {
        const double m3 = c->m * c->m * c->m, bd = FDT_O3D_COF_BOUND * m3,
                     bn = 0x1p-45 * (m3 * c->m);
        if (c->det > 4.0 * bd) {
            double nmax = fabs(c->n[0]);
            nmax = fabs(c->n[1]) > nmax ? fabs(c->n[1]) : nmax;
            nmax = fabs(c->n[2]) > nmax ? fabs(c->n[2]) : nmax;
            const double delta = (bn + nmax * (bd / c->det)) / (2.0 * (c->det - bd));
            const double h = 0.5 / c->det;
            const double o[3] = {c->n[0] * h, c->n[1] * h, c->n[2] * h};
            const double r = sqrt(o[0] * o[0] + o[1] * o[1] + o[2] * o[2]);
            const double ca = dir * Q[3 * (size_t)v[0] + ax], co = dir * o[ax];
            const double end =
                ca + co + r + 3.0 * delta + 0x1p-50 * (fabs(ca) + fabs(co) + r);
            return end < next;
        }
    }
    return -1;
}

/* The apex search's ball, where ball_by_cof could not tell. */
static int ball_slow(const sweep *sw, const uint32_t *v, double next, fdt_kdq *kq)
{
    const double *Q = sw->Q;
    fdt_apex ap;
    fdt_apex_init(&ap, Q + 3 * (size_t)v[0], Q + 3 * (size_t)v[1], Q + 3 * (size_t)v[2], v[0],
                  v[1], v[2]);
    fdt_apex_offer(&ap, v[3], Q + 3 * (size_t)v[3], kq);
    if (ap.best != v[3] || !(ap.rad < INFINITY))
        return 0;
    double cc = sw->dir * ap.center[sw->axis], rr = ap.rad;
    double end = cc + rr;
    end += (fabs(cc) + rr) * 0x1p-50;
    return end < next;
}

/* The certificate's pass over a part's mesh (fdt_certify_visit), with
 * the cofactors it computed anyway: each slot in use into U, each finite
 * tet's ball tested against the next slabs (not in the last part). Each
 * slot is visited once, by one thread, and writes its own byte only;
 * fdt_fork_join's joins publish the bytes to the caller. */
typedef struct ball_pass {
    const sweep *sw;
    uint8_t *mark;
    double next;
    int last;
} ball_pass;

static void ball_visit(void *user, int job, uint32_t slot, const uint32_t v[4], int inf,
                       const fdt_sphere_cof *cof)
{
    (void)job;
    const ball_pass *b = user;
    uint8_t m = IN_U;
    if (inf < 0 && !b->last) {
        int r = ball_by_cof(b->sw, v, cof, b->next);
        m |= r > 0 ? BALL : r < 0 ? BALL_UNSURE : 0;
    }
    b->mark[slot] = m;
}

static void add_ins_stats(fdt_ins_stats *a, const fdt_ins_stats *b)
{
    a->inserted += b->inserted;
    a->walk_steps += b->walk_steps;
    a->hull_walks += b->hull_walks;
    a->cavity_tets += b->cavity_tets;
    a->created_tets += b->created_tets;
    if (b->max_cavity > a->max_cavity)
        a->max_cavity = b->max_cavity;
    a->conflict_tests += b->conflict_tests;
    a->deferred += b->deferred;
    a->serial_finish += b->serial_finish;
    a->stolen += b->stolen;
}

/* The part's points: L's, then the slab's [begin, end), Morton-sorted
 * with their global ids (the insertion's order, src/mesh/insert.h). */
static int gather(sweep *sw, uint32_t begin, uint32_t end, size_t *nq_out)
{
    size_t nq = sw->nlive + (end - begin);
    if (fdt_grow(&sw->g, &sw->gcap, nq, sizeof *sw->g) ||
        fdt_grow(&sw->gin, &sw->gincap, nq, sizeof *sw->gin) ||
        fdt_grow(&sw->Q, &sw->qcap, nq, 3 * sizeof *sw->Q))
        return FDT_ENOMEM;
    for (size_t i = 0; i < nq; i++) {
        uint32_t gid = i < sw->nlive ? sw->live[i] : begin + (uint32_t)(i - sw->nlive);
        sw->g[i] = (fdt_vid)gid;
        memcpy(sw->Q + 3 * i, sw->P + 3 * (size_t)gid, 3 * sizeof *sw->Q);
    }
    *nq_out = nq;
    if (fdt_morton_sort(sw->Q, sw->g, nq, sw->nthreads))
        return FDT_ENOMEM;
    for (size_t i = 0; i < nq; i++)
        sw->gin[i] = sw->orig[sw->g[i]];
    return FDT_OK;
}

/* The part's mesh, built and certified on the sweep's threads; *mark
 * (nslots bytes, the caller's to free) from the certificate's pass:
 * IN_U on every slot in use, the finite tets' balls against `next`
 * (ball_visit). */
static int build(sweep *sw, fdt_ins *mesh, size_t nq, int last, double next, uint8_t **mark)
{
    *mark = NULL;
    fdt_sweep_stats *st = sw->st;
    double t0 = fdt_now_s();
    int err = sw->nthreads > 1
                  ? fdt_ins_build_parallel(mesh, sw->Q, 0, (uint32_t)nq, sw->nthreads, &st->pc)
                  : fdt_ins_build(mesh, sw->Q, 0, (uint32_t)nq, &st->pc);
    st->t_mesh += fdt_now_s() - t0;
    if (err)
        return err;
    add_ins_stats(&st->ins, &mesh->stats);
    if (!(*mark = calloc(mesh->nslots ? mesh->nslots : 1, 1)))
        return FDT_ENOMEM;
    ball_pass bp = {sw, *mark, next, last};
    const fdt_certify_visit vis = {ball_visit, &bp};
    fdt_certify_fail why;
    double t1 = fdt_now_s();
    err = fdt_certify_parallel_visit(mesh, sw->nthreads, &vis, &st->pc, &why);
    st->t_certify += fdt_now_s() - t1;
    st->certified_tets += mesh->nfinite;
    if (err == FDT_ECHECK)
        fdt_certify_describe(&why, sw->diag, sw->dlen);
    return err;
}

static int internal(sweep *sw, const char *what)
{
    snprintf(sw->diag, sw->dlen, "internal error: the sweep's parts disagree: %s", what);
    return FDT_EINTERNAL;
}

/* Slot t out of U, queued for the flood fill, if it was in U. */
static int take_out(uint8_t *mark, uint32_t t, uint32_t **queue, size_t *n, size_t *cap)
{
    if (!(mark[t] & IN_U))
        return FDT_OK;
    mark[t] &= (uint8_t)~IN_U;
    if (fdt_grow(queue, cap, *n + 1, sizeof **queue))
        return FDT_ENOMEM;
    (*queue)[(*n)++] = t;
    return FDT_OK;
}

/*
 * U: every live slot, less the region of tets over what earlier parts
 * emitted (when they emitted anything). That region is bounded by B's
 * faces and the hull, so a flood fill from the far side of each face of B
 * (found in the mesh and marked) that never crosses one reaches all of it;
 * it holds only tets whose vertices are all old live ones, far fewer than
 * U's (filling U itself from B cost 3.5 % of a 1M run). mark[]: build's,
 * IN_U on every slot in use.
 */
static int region(sweep *sw, const fdt_ins *mesh, uint8_t *mark, uint32_t begin, uint32_t end,
                  size_t nq)
{
    if (sw->nwall == 0)
        return FDT_OK;
    if (map_build(sw, nq, begin, end))
        return FDT_ENOMEM;
    uint32_t *queue = NULL, *side = malloc(sw->nwall * sizeof *side);
    size_t nqueue = 0, qcap = 0;
    if (!side)
        return FDT_ENOMEM;
    int err = FDT_OK;
    for (size_t w = 0; w < sw->nwall && !err; w++) {
        uint32_t l[3];
        for (int i = 0; i < 3 && !err; i++)
            if ((l[i] = map_find(sw, sw->wall[3 * w + i])) == FDT_NONE)
                err = internal(sw, "a vertex of the emitted tets' boundary is not live");
        uint32_t t;
        int k;
        if (!err && !fdt_ins_find_face(mesh, l[0], l[1], l[2], &t, &k))
            err = internal(sw, "a face of the emitted tets' boundary is not in the next mesh");
        if (err)
            break;
        side[w] = t;
        mark[t] |= (uint8_t)(1u << k);
        uint32_t r = fdt_ins_tet(mesh, t)[4 + k], o = r >> 2;
        mark[o] |= (uint8_t)(1u << (r & 3)); /* the face seen from the far side */
        err = take_out(mark, o, &queue, &nqueue, &qcap);
    }
    for (size_t qi = 0; qi < nqueue && !err; qi++) {
        uint32_t t = queue[qi];
        const uint32_t *v = fdt_ins_tet(mesh, t);
        /* The emitted region lies inside the hull of the points so far,
         * whose vertices are all live, so the mesh covers it with finite
         * tets: an infinite one here says the parts disagree. */
        if (!fdt_ins_is_finite(mesh, t))
            err = internal(sw, "the emitted region reaches past the hull");
        for (int k = 0; k < 4 && !err; k++)
            if (!(mark[t] & (1u << k)))
                err = take_out(mark, v[4 + k] >> 2, &queue, &nqueue, &qcap);
    }
    /* B separates the two regions: a fill that reached a live side crossed
     * a face missing from B, and would drop live tets unseen. */
    for (size_t w = 0; w < sw->nwall && !err; w++)
        if (!(mark[side[w]] & IN_U))
            err = internal(sw, "the emitted region reaches a live tet");
    free(queue);
    free(side);
    return err;
}

/* Emits U's final tets (and, in the last part, U's hull faces) in slot
 * order, marking them FINAL. */
static int emit(sweep *sw, const fdt_ins *mesh, uint8_t *mark, int last, double next)
{
    fdt_kdq kq;
    memset(&kq, 0, sizeof kq);
    int err = FDT_OK;
    for (uint32_t s = 0; s < mesh->nslots && !err; s++) {
        if (!(mark[s] & IN_U))
            continue;
        const uint32_t *v = fdt_ins_tet(mesh, s);
        int inf = fdt_ins_inf_index(v);
        if (inf < 0) {
            if (!last && !(mark[s] & BALL) &&
                !((mark[s] & BALL_UNSURE) && ball_slow(sw, v, next, &kq)))
                continue;
            uint32_t t[4];
            fdt_vid in[4];
            for (int i = 0; i < 4; i++) {
                t[i] = (uint32_t)sw->g[v[i]];
                in[i] = sw->gin[v[i]];
            }
            int64_t id = fdt_emit_tet_known(sw->em, t, in);
            if (id < 0)
                err = (int)id;
            sw->st->final_tets++;
            uint32_t *c = sw->cs ? fdt_cellheld_add(&sw->held, 1) : NULL;
            if (c)
                memcpy(c, t, sizeof t);
            else if (sw->cs && !err)
                err = FDT_ENOMEM;
        } else {
            if (!last)
                continue;
            uint32_t h[3];
            fdt_ins_face_inward(v, inf, h); /* the hull face, outward */
            for (int i = 0; i < 3; i++)
                h[i] = (uint32_t)sw->g[h[i]];
            err = fdt_emit_hull(sw->em, h);
            if (sw->cs && !err) {
                if (fdt_grow(&sw->hullpts, &sw->hpcap, sw->nhullpts + 3, sizeof *sw->hullpts))
                    err = FDT_ENOMEM;
                else
                    for (int i = 0; i < 3; i++)
                        sw->hullpts[sw->nhullpts++] = h[i];
            }
        }
        mark[s] |= FINAL;
    }
    fdt_pred_counts_add(&sw->st->pc, &kq.pc);
    return err;
}

/* What U keeps for the next part: L, the vertices of its tets not
 * emitted, and B, their faces whose other side is emitted (an earlier
 * part's wall, or a tet final now), oriented towards the live tet. */
static int carry(sweep *sw, const fdt_ins *mesh, const uint8_t *mark, size_t nq)
{
    uint8_t *seen = calloc(nq ? nq : 1, 1);
    if (!seen)
        return FDT_ENOMEM;
    sw->nlive = 0;
    sw->nnw = 0;
    int err = FDT_OK;
    for (uint32_t s = 0; s < mesh->nslots && !err; s++) {
        if ((mark[s] & (IN_U | FINAL)) != IN_U)
            continue;
        const uint32_t *v = fdt_ins_tet(mesh, s);
        for (int k = 0; k < 4 && !err; k++) {
            if (v[k] != INF && !seen[v[k]]) {
                seen[v[k]] = 1;
                if ((err = fdt_grow(&sw->live, &sw->lcap, sw->nlive + 1, sizeof *sw->live)))
                    break;
                sw->live[sw->nlive++] = (uint32_t)sw->g[v[k]];
            }
            uint32_t n = v[4 + k] >> 2;
            if (!(mark[s] & (1u << k)) && !(mark[n] & FINAL))
                continue;
            uint32_t f[3];
            fdt_ins_face_inward(v, k, f); /* open towards s */
            if (f[0] == INF || f[1] == INF || f[2] == INF) {
                err = internal(sw, "an emitted tet across a face with the infinite vertex");
                break;
            }
            if ((err = fdt_grow(&sw->nwalls, &sw->nwcap, 3 * (sw->nnw + 1),
                            sizeof *sw->nwalls)))
                break;
            uint32_t *o = sw->nwalls + 3 * sw->nnw++;
            for (int i = 0; i < 3; i++)
                o[i] = (uint32_t)sw->g[f[i]];
        }
    }
    free(seen);
    if (err)
        return err;
    uint32_t *t = sw->wall;
    size_t tc = sw->wcap;
    sw->wall = sw->nwalls;
    sw->wcap = sw->nwcap;
    sw->nwall = sw->nnw;
    sw->nwalls = t;
    sw->nwcap = tc;
    return FDT_OK;
}

/* One part: the slabs' points [begin, end) with L; next: the first
 * coordinate along the sweep of the slabs after them (last: none). */
static int part(sweep *sw, uint32_t begin, uint32_t end, int last, double next)
{
    fdt_sweep_stats *st = sw->st;
    size_t nq;
    int err = gather(sw, begin, end, &nq);
    if (err)
        return err;
    st->parts++;
    st->reinserted += sw->nlive;
    if (sw->nlive > st->max_live)
        st->max_live = sw->nlive;
    if (nq > st->max_part)
        st->max_part = nq;
    fdt_ins mesh;
    uint8_t *mark;
    err = build(sw, &mesh, nq, last, next, &mark);
    if (err == FDT_EDEGENERATE && !last && sw->nwall == 0) {
        /* The points so far are flat (a first slab on one plane): nothing
         * can be emitted yet, so all of them are live. */
        if (fdt_grow(&sw->live, &sw->lcap, nq, sizeof *sw->live))
            return FDT_ENOMEM;
        for (size_t i = 0; i < nq; i++)
            sw->live[i] = (uint32_t)sw->g[i];
        sw->nlive = nq;
        sw->closing = 1; /* no sign of spheres that stay open yet */
        return FDT_OK; /* the build failed: no mark, no mesh */
    }
    if (err == FDT_EDEGENERATE || err == FDT_EINVAL || err == FDT_EINTERNAL) {
        /* the caller merged duplicates and checked the dimension: the
         * insertion's own checks failed (src/front/partmesh.c) */
        fdt_certify_fail why;
        fdt_certify_build_failed(&why);
        fdt_certify_describe(&why, sw->diag, sw->dlen);
        err = FDT_ECHECK;
    }
    size_t bytes = nq * (3 * sizeof *sw->Q + 2 * sizeof *sw->g + sizeof *mesh.vtet) +
                   (size_t)mesh.cap * (8 * sizeof *mesh.T + 1);
    if (!err && bytes > st->mem_part)
        st->mem_part = bytes;
    if (!err)
        err = region(sw, &mesh, mark, begin, end, nq);
    size_t before = st->final_tets;
    if (!err)
        err = emit(sw, &mesh, mark, last, next);
    sw->closing = 4 * (st->final_tets - before) >= mesh.nfinite;
    if (!err && !last)
        err = carry(sw, &mesh, mark, nq);
    free(mark);
    fdt_ins_free(&mesh);
    if (!err && sw->cs) {
        /* the part's points that are not live close: their cells */
        double t0 = fdt_now_s();
        err = fdt_cellstream_part(sw->cs, &sw->held, sw->g, nq, sw->live, last ? 0 : sw->nlive,
                                  sw->hullpts, sw->nhullpts, sw->nthreads, sw->diag, sw->dlen);
        st->t_cells += fdt_now_s() - t0;
        sw->nhullpts = 0;
    }
    return err;
}

/* The points of the sweep's slabs j .. e - 1 (counted along the sweep
 * over the slabs [j0, j1)). */
static uint64_t slab_points(const uint32_t *b, size_t j0, size_t j1, int dir, size_t j, size_t e)
{
    return dir > 0 ? (uint64_t)b[j0 + e] - b[j0 + j] : (uint64_t)b[j1 - j] - b[j1 - e];
}

/* The least coordinate along the sweep (times dir) of the points
 * [begin, end). */
static double least(const sweep *sw, uint32_t begin, uint32_t end)
{
    double lo[3], hi[3];
    fdt_points_box(sw->P, begin, end, lo, hi);
    return sw->dir > 0 ? lo[sw->axis] : -hi[sw->axis];
}

/* A half sweep's slabs from the j-th on (along the sweep) left, as live
 * points, to the meeting part: as if that part took those slabs. */
static int carry_rest(sweep *sw, const uint32_t *b, size_t j0, size_t j1, size_t j)
{
    uint32_t lo = sw->dir > 0 ? b[j0 + j] : b[j0], hi = sw->dir > 0 ? b[j1] : b[j1 - j];
    if (fdt_grow(&sw->live, &sw->lcap, sw->nlive + (hi - lo), sizeof *sw->live))
        return FDT_ENOMEM;
    for (uint32_t i = lo; i < hi; i++)
        sw->live[sw->nlive++] = i;
    return FDT_OK;
}

/*
 * The sweep over the slabs [j0, j1) of b (boundaries, nslabs slabs in
 * all), upwards from j0 when sw->dir is +1, downwards from j1 when -1; a
 * part takes slabs until its new points are twice the live ones carried
 * in (entry 104: the points inserted again stay under the points
 * themselves, however little is final). finish: the sweep's last part is
 * the run's last (it emits everything); else what is left stays in L and
 * B for the meeting part.
 */
static int run_sweep(sweep *sw, const uint32_t *b, size_t nslabs, size_t j0, size_t j1,
                     int finish, fdt_progress_fn progress, void *puser)
{
    int err = FDT_OK;
    size_t done = 0;
    sw->closing = 1;
    for (size_t j = 0; j < j1 - j0 && !err;) {
        size_t e = j + 1;
        while (e < j1 - j0 && slab_points(b, j0, j1, sw->dir, j, e) < 2 * (uint64_t)sw->nlive)
            e++;
        if (!sw->closing) {
            /* Under a quarter of the last part's tets closed (a surface,
             * whose spheres span the object): every part after would mesh
             * its live vertices again for little, so the rest goes in one
             * part (the meeting part, for a half sweep). */
            if (!finish)
                return carry_rest(sw, b, j0, j1, j);
            e = j1 - j0;
        }
        int last = finish && e == j1 - j0;
        /* the slabs of the part, and the one after it along the sweep */
        size_t lo = sw->dir > 0 ? j0 + j : j1 - e, hi = sw->dir > 0 ? j0 + e : j1 - j;
        size_t after = sw->dir > 0 ? hi : lo - 1;
        double next = last || (sw->dir > 0 ? after >= nslabs : lo == 0)
                          ? INFINITY
                          : least(sw, b[after], b[after + 1]);
        err = part(sw, b[lo], b[hi], last, next);
        done += b[hi] - b[lo];
        j = e;
        if (!err && progress && progress(puser, (double)done / (double)sw->m))
            err = FDT_ECANCELED;
    }
    return err;
}

static void sweep_free(sweep *sw)
{
    fdt_cellheld_free(&sw->held);
    free(sw->hullpts);
    free(sw->live);
    free(sw->wall);
    free(sw->nwalls);
    free(sw->Q);
    free(sw->g);
    free(sw->gin);
    free(sw->map);
}

/* One of the two sweeps that meet (fdt_sweep_emit on threads), on a
 * thread of its own. */
typedef struct half {
    sweep sw;
    const uint32_t *b;
    size_t nslabs, j0, j1;
    fdt_emit em;
    fdt_meshbuf mb;
    fdt_sweep_stats st;
    char diag[512];
    int err;
} half;

static void *half_run(void *arg)
{
    half *h = arg;
    h->err = run_sweep(&h->sw, h->b, h->nslabs, h->j0, h->j1, 0, NULL, NULL);
    if (!h->err)
        h->err = fdt_emit_flush(&h->em);
    return NULL;
}

static void add_stats(fdt_sweep_stats *a, const fdt_sweep_stats *b)
{
    a->parts += b->parts;
    a->reinserted += b->reinserted;
    a->max_live = a->max_live > b->max_live ? a->max_live : b->max_live;
    a->max_part = a->max_part > b->max_part ? a->max_part : b->max_part;
    /* the two halves run at once: their largest parts add up */
    a->mem_part += b->mem_part;
    a->final_tets += b->final_tets;
    a->certified_tets += b->certified_tets;
    a->t_mesh += b->t_mesh;
    a->t_certify += b->t_certify;
    a->t_cells += b->t_cells;
    fdt_pred_counts_add(&a->pc, &b->pc);
    add_ins_stats(&a->ins, &b->ins);
}

/* Appends what the second half kept in memory (the in-memory sink's
 * meshbuf, tests only) to the caller's emitter. */
static int append(fdt_emit *em, const fdt_meshbuf *mb)
{
    for (size_t t = 0; t < mb->ntets; t++) {
        int64_t id = fdt_emit_tet(em, mb->tets + 4 * t);
        if (id < 0)
            return (int)id;
    }
    for (size_t f = 0; f < mb->nhull; f++) {
        int err = fdt_emit_hull(em, mb->hull + 3 * f);
        if (err)
            return err;
    }
    return FDT_OK;
}

/*
 * Two sweeps that meet (two or more threads and two or more slabs): the
 * lower half of the slabs swept upwards, the upper half downwards, each on
 * a thread of its own with its own meshes (no lock; the build threads
 * shared between them), then one meeting part whose points are both
 * halves' live vertices and whose B is both halves' boundaries. A tet the
 * lower sweep emits has its sphere below the upper half's points and one
 * the upper sweep emits above the lower half's, so the two never share a
 * vertex: the two boundaries are disjoint, and the meeting part's region
 * is the rest of the mesh (fdt_sweep.h's argument with both in B).
 */
static int meet(sweep *base, const uint32_t *b, size_t nslabs, fdt_progress_fn progress,
                void *puser)
{
    half h[2];
    memset(h, 0, sizeof h);
    size_t mid = nslabs / 2;
    int err = FDT_OK;
    for (int i = 0; i < 2 && !err; i++) {
        h[i].sw = *base;
        h[i].sw.dir = i == 0 ? 1 : -1;
        h[i].sw.nthreads = i == 0 ? (base->nthreads + 1) / 2 : base->nthreads / 2;
        h[i].sw.st = &h[i].st;
        h[i].sw.diag = h[i].diag;
        h[i].sw.dlen = sizeof h[i].diag;
        h[i].b = b;
        h[i].nslabs = nslabs;
        h[i].j0 = i == 0 ? 0 : mid;
        h[i].j1 = i == 0 ? mid : nslabs;
        int inmem = base->em->mb != NULL;
        if (i == 0)
            h[i].sw.em = base->em;
        else if ((inmem && fdt_meshbuf_init(&h[i].mb, 64, 0)) ||
                 fdt_emit_init(&h[i].em, base->em->s, inmem ? &h[i].mb : NULL))
            err = FDT_ENOMEM;
        else
            h[i].sw.em = &h[i].em;
    }
    if (!err) {
        /* the lower half on this thread: its emitter is the caller's */
        h[0].em = *base->em;
        h[0].sw.em = &h[0].em;
        fdt_fork_join(h, sizeof h[0], 2, half_run);
        *base->em = h[0].em;
        err = h[0].err ? h[0].err : h[1].err;
        const char *d = h[0].err ? h[0].diag : h[1].diag;
        if (err && d[0])
            snprintf(base->diag, base->dlen, "%s", d);
    }
    for (int i = 0; i < 2; i++) {
        add_stats(base->st, &h[i].st);
        if (!err && base->cs && fdt_cellheld_take(&base->held, &h[i].sw.held))
            err = FDT_ENOMEM;
    }
    if (!err && base->em->mb)
        err = append(base->em, &h[1].mb);
    if (!err && progress && progress(puser, 0.95))
        err = FDT_ECANCELED;
    /* the meeting part: both halves' live vertices and boundaries */
    size_t nl = h[0].sw.nlive + h[1].sw.nlive, nw = h[0].sw.nwall + h[1].sw.nwall;
    if (!err && (fdt_grow(&base->live, &base->lcap, nl, sizeof *base->live) ||
                 fdt_grow(&base->wall, &base->wcap, 3 * nw, sizeof *base->wall)))
        err = FDT_ENOMEM;
    if (!err) {
        for (int i = 0, l = 0, w = 0; i < 2; i++) {
            /* a half may end with no live vertex or no boundary: its
               arrays are then NULL, which memcpy may not take even for 0 */
            if (h[i].sw.nlive)
                memcpy(base->live + l, h[i].sw.live, h[i].sw.nlive * sizeof *base->live);
            if (h[i].sw.nwall)
                memcpy(base->wall + w, h[i].sw.wall, 3 * h[i].sw.nwall * sizeof *base->wall);
            l += (int)h[i].sw.nlive;
            w += 3 * (int)h[i].sw.nwall;
        }
        base->nlive = nl;
        base->nwall = nw;
        err = part(base, 0, 0, 1, INFINITY);
    }
    for (int i = 0; i < 2; i++)
        sweep_free(&h[i].sw);
    fdt_emit_free(&h[1].em);
    fdt_meshbuf_free(&h[1].mb);
    return err;
}

int fdt_sweep_emit(double *P, fdt_vid *orig, uint32_t m, uint32_t slab, int nthreads,
                   fdt_emit *em, fdt_cellstream *cs, fdt_progress_fn progress, void *puser,
                   fdt_sweep_stats *st, char *diag, size_t dlen)
{
    sweep sw;
    memset(&sw, 0, sizeof sw);
    sw.P = P;
    sw.orig = orig;
    sw.m = m;
    sw.dir = 1;
    sw.nthreads = nthreads < 1 ? 1 : nthreads;
    sw.em = em;
    sw.cs = cs;
    if (cs) {
        cs->P = P;
        cs->orig = orig;
    }
    sw.st = st;
    sw.diag = diag;
    sw.dlen = dlen;
    if (!slab)
        slab = fdt_sweep_slab(m);
    double lo[3], hi[3];
    fdt_points_box(P, 0, m, lo, hi);
    for (int k = 1; k < 3; k++)
        if (hi[k] - lo[k] > hi[sw.axis] - lo[sw.axis])
            sw.axis = k;
    size_t nslabs = m / slab + (m % slab != 0);
    if (nslabs < 1)
        nslabs = 1;
    uint32_t *b = malloc((nslabs + 1) * sizeof *b);
    if (!b)
        return FDT_ENOMEM;
    for (size_t j = 0; j <= nslabs; j++)
        b[j] = (uint32_t)((uint64_t)j * m / nslabs);
    cut_slabs(P, orig, 0, m, b, 1, nslabs, sw.axis);
    int err = sw.nthreads > 1 && nslabs > 1
                  ? meet(&sw, b, nslabs, progress, puser)
                  : run_sweep(&sw, b, nslabs, 0, nslabs, 1, progress, puser);
    free(b);
    sweep_free(&sw);
    return err;
}
