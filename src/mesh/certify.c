/* The certificate of an insertion mesh: src/mesh/certify.h says what is
 * checked and why it proves the mesh is the perturbed DT. */
#include "mesh/certify.h"

#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>

#include "base/bits.h"
#include "geom/images.h"
#include "base/mem.h"
#include "base/spawn.h"

#define INF FDT_NONE

static inline const double *pt(const fdt_ins *m, uint32_t v)
{
    return m->P + 3 * (size_t)v;
}

static inline int is_freed(const uint32_t *v)
{
    return v[0] == INF && v[1] == INF;
}

/* The exact signs, filters first (most calls end there); every point is
 * one of the mesh's, in its box (fdt_ins.sf). */
static inline int orient(const fdt_ins *m, const double *a, const double *b, const double *c,
                         const double *d, fdt_pred_counts *cnt)
{
    int s = fdt_orient3d_filter_sf(a, b, c, d, &m->sf);
    if (s != FDT_PRED_UNSURE)
        return s;
    if (__builtin_expect(m->sf.img != NULL, 0))
        return fdt_images_orient_undecided(m->sf.img, a, b, c, d, cnt);
    return fdt_orient3d(a, b, c, d, cnt);
}

static inline int insphere(const fdt_ins *m, const double *a, const double *b, const double *c,
                           const double *d, const double *e, fdt_pred_counts *cnt)
{
    int s = fdt_insphere_filter_sf(a, b, c, d, e, &m->sf);
    if (s != FDT_PRED_UNSURE)
        return s;
    if (__builtin_expect(m->sf.img != NULL, 0))
        return fdt_images_insphere_undecided(m->sf.img, a, b, c, d, e, cnt);
    return fdt_insphere_perturbed(a, b, c, d, e, cnt);
}

static int fail(fdt_certify_fail *why, uint32_t slot, int face, const char *what)
{
    if (why) {
        why->slot = slot;
        why->face = face;
        why->what = what;
    }
    return FDT_ECHECK;
}

/* orient3d of tet v with its vertex k replaced by point q. */
static int orient_with(const fdt_ins *m, const uint32_t *v, int k, const double *q,
                       fdt_pred_counts *cnt)
{
    const double *p[4];
    for (int i = 0; i < 4; i++)
        p[i] = i == k ? q : pt(m, v[i]);
    return orient(m, p[0], p[1], p[2], p[3], cnt);
}

/* Whether point q, on the plane of infinite tet v's hull face (infinite
 * vertex at index inf), is in conflict with v: the insertion's rule
 * (src/mesh/insert.c, "Hull") for such a point, inside the sphere of the
 * finite tet under the face. */
static int conflicts_coplanar(const fdt_ins *m, const uint32_t *v, int inf, const double *q,
                              fdt_pred_counts *cnt)
{
    const uint32_t *w = m->T + 8 * (size_t)(v[4 + inf] >> 2);
    return insphere(m, pt(m, w[0]), pt(m, w[1]), pt(m, w[2]), pt(m, w[3]), q, cnt) > 0;
}

/*
 * How tets v (face k) and w (face nk) are glued: 0 when they do not share
 * the face's three vertices; else the parity of the permutation taking v,
 * with its vertex k replaced by w's vertex nk, to w: 1 (odd) when the two
 * list the face in opposite orders, -1 (even) when in the same order.
 * With both tets positive (check 2; an infinite one in the sense of
 * src/mesh/insert.h), orient3d of v with w's apex in place of v[k] is that
 * parity times orient3d of w: odd means w's apex lies on the far side of
 * the face from v[k], so the two tets do not fold over each other. That
 * is a geometric fact read off the ids, no predicate needed.
 */
static int glued(const uint32_t *v, int k, const uint32_t *w, int nk)
{
    int pos[4];
    for (int i = 0; i < 4; i++) {
        if (i == k) {
            pos[i] = nk;
            continue;
        }
        pos[i] = -1;
        for (int j = 0; j < 4; j++)
            if (j != nk && w[j] == v[i])
                pos[i] = j;
        if (pos[i] < 0)
            return 0;
    }
    int inv = 0;
    for (int i = 0; i < 4; i++)
        for (int j = i + 1; j < 4; j++)
            inv += pos[i] > pos[j];
    return inv & 1 ? 1 : -1;
}

/*
 * glued(v, k, w, nk) == 1, without its branches: the face of v opposite k
 * in outward order (fdt_tet_face) is a rotation of the reverse of w's
 * face nk in outward order (the same three ids, listed the other way
 * round). Branch-free: one test a face, taken nearly always (bench/NOTES.md
 * entry 93: glued's loops mispredicted 4 times a tet); glued names what
 * failed when this says no.
 */
static inline int glued_opposite(const uint32_t *v, int k, const uint32_t *w, int nk)
{
    const int *f = fdt_tet_face[k], *g = fdt_tet_face[nk];
    uint32_t a0 = v[f[0]], a1 = v[f[1]], a2 = v[f[2]];
    uint32_t b0 = w[g[0]], b1 = w[g[1]], b2 = w[g[2]];
    return ((b0 == a0) & (b1 == a2) & (b2 == a1)) | ((b0 == a1) & (b1 == a0) & (b2 == a2)) |
           ((b0 == a2) & (b1 == a1) & (b2 == a0));
}

/* The pair checks of face k of an infinite tet v (infinite vertex at
 * index inf) and face nk of its neighbour w: the geometric half of checks
 * 2-3 that involve both. NULL if they pass, else what failed. (A finite
 * v's are in certify_range.) */
static const char *check_pair_infinite(const fdt_ins *m, const uint32_t *v, int k, int inf,
                                       const uint32_t *w, int nk, fdt_pred_counts *cnt)
{
    uint32_t p = v[k], q = w[nk];
    int winf = w[0] == INF ? 0 : w[1] == INF ? 1 : w[2] == INF ? 2 : w[3] == INF ? 3 : -1;
    /* A hull face (the finite face of an infinite tet) over its finite tet:
     * that tet's apex is on the inner side, since the two are glued in
     * opposite orders (glued). */
    if (p == INF || q == INF)
        return NULL;
    if (winf < 0)
        return "a finite face between a finite and an infinite tet";
    /*
     * Two hull faces through an edge: convex, or coplanar and locally
     * Delaunay in their plane. In the insertion's rule (src/mesh/insert.c,
     * "Hull") q conflicts with v when strictly outside v's hull face, or on
     * its plane and inside the sphere of the finite tet under it; likewise
     * p with w. The two outside tests are one: v with q for its infinite
     * vertex and w with p for its are the same four points, and their
     * orders differ by an even permutation. (v is an even permutation of
     * (f0, f2, f1, p) for f its face k in outward order, w of (g0, g2,
     * g1, q) for g a rotation of f reversed, as glued_opposite checked;
     * with the infinite vertex at f2, they read (f0, q, f1, p) and (f0,
     * f1, p, q): a 3-cycle.) So one exact orient3d decides both sides,
     * which halves the tests of a hull-heavy set's certificate (every
     * point on a sphere); on the plane each side's sphere still decides.
     */
    int o = orient_with(m, v, inf, pt(m, q), cnt);
    if (o > 0 || (o == 0 && (conflicts_coplanar(m, v, inf, pt(m, q), cnt) ||
                             conflicts_coplanar(m, w, winf, pt(m, p), cnt))))
        return "the hull is not convex (or not Delaunay in a plane)";
    return NULL;
}

/* The pair check of face k of a finite, positive tet v (its cofactors
 * cof) whose neighbour across it is glued to it with apex q: a hull face
 * (q infinite: w's finite face is v's, so w's infinite vertex can only
 * be its apex) or two finite tets on opposite sides of their face, and
 * then q outside the sphere of v (which, for a pair, is p outside w's). */
static inline const char *check_pair_finite(const fdt_ins *m, const uint32_t *v,
                                            const fdt_sphere_cof *cof, uint32_t q,
                                            fdt_pred_counts *cnt)
{
    if (q == INF)
        return NULL;
    int s = fdt_sphere_cof_insphere(cof, pt(m, q));
    if (s == FDT_PRED_UNSURE)
        s = insphere(m, pt(m, v[0]), pt(m, v[1]), pt(m, v[2]), pt(m, v[3]), pt(m, q), cnt);
    return s > 0 ? "a face is not locally Delaunay" : NULL;
}

/* How many tets ahead the loop prefetches its neighbours: the neighbour
 * slots are where the time goes (perf: more than half of it in the load
 * of a neighbour's first vertex, a cache miss). */
#define AHEAD 8

/*
 * The order the certificate visits the slots in (bench/NOTES.md entry
 * 130): by the least vertex of their tet, a bucket of 2^BUCKET_SHIFT
 * consecutive point ids at a time, slot order inside a bucket; freed
 * slots left out. The point ids are in space order (the kd order, as
 * insert.h asks), so a bucket's tets lie together, and the neighbours and
 * points a tet reads were mostly read for the tets just before it. In
 * slot order they were 2^20-2^23 slots apart: a slot is reused where its
 * tet died, and each BRIO round lays its own sweep over the slots (the
 * neighbours' rows were more than half of the certificate's time).
 */
#define BUCKET_SHIFT 9

/* The bucket of live tet row v; a vertex id outside the mesh's (a broken
 * mesh, which the checks then name) goes to bucket 0. */
static inline uint32_t bucket_of(const fdt_ins *m, const uint32_t *v)
{
    uint32_t a = v[0] < v[1] ? v[0] : v[1], b = v[2] < v[3] ? v[2] : v[3];
    uint32_t x = (a < b ? a : b) - m->base; /* finite: one infinite vertex at most */
    return x < m->n ? x >> BUCKET_SHIFT : 0;
}

/* A thread's part of the counting sort: the slots [lo, hi), counted into
 * cnt (pass 0), then placed at cnt's places (pass 1). */
typedef struct order_job {
    const fdt_ins *m;
    uint32_t lo, hi;
    uint32_t *cnt;   /* a count, then the next place, a bucket */
    uint32_t *order;
    int pass;
} order_job;

static void *order_pass(void *arg)
{
    order_job *j = arg;
    const fdt_ins *m = j->m;
    for (uint32_t t = j->lo; t < j->hi; t++) {
        const uint32_t *v = m->T + 8 * (size_t)t;
        if (is_freed(v))
            continue;
        uint32_t b = bucket_of(m, v);
        if (j->pass == 0)
            j->cnt[b]++;
        else
            j->order[j->cnt[b]++] = t;
    }
    return NULL;
}

/* The live slots in the certificate's order into *order (*len of them),
 * sorted on up to nthreads threads: each bucket's slots come from the
 * threads' slot ranges in turn, so the order is the same for any thread
 * count. FDT_OK or FDT_ENOMEM. */
static int order_slots(const fdt_ins *m, int nthreads, uint32_t **order, uint32_t *len)
{
    uint32_t nb = (m->n >> BUCKET_SHIFT) + 1;
    int nj = nthreads < 1 || m->nslots < 65536 ? 1 : nthreads > 64 ? 64 : nthreads;
    order_job *j = calloc((size_t)nj, sizeof *j);
    uint32_t *cnt = calloc((size_t)nj * nb, sizeof *cnt);
    *order = NULL;
    if (!j || !cnt) {
        free(j);
        free(cnt);
        return FDT_ENOMEM;
    }
    for (int i = 0; i < nj; i++)
        j[i] = (order_job){m, (uint32_t)((uint64_t)m->nslots * (uint64_t)i / (uint64_t)nj),
                           (uint32_t)((uint64_t)m->nslots * (uint64_t)(i + 1) / (uint64_t)nj),
                           cnt + (size_t)i * nb, NULL, 0};
    /* the joins order each pass's writes before the next reads */
    fdt_fork_join(j, sizeof *j, nj, order_pass);
    uint32_t run = 0;
    for (uint32_t b = 0; b < nb; b++)
        for (int i = 0; i < nj; i++) {
            uint32_t x = j[i].cnt[b];
            j[i].cnt[b] = run;
            run += x;
        }
    *order = fdt_mem_alloc_huge(run ? run : 1, sizeof **order, 0);
    if (*order) {
        for (int i = 0; i < nj; i++) {
            j[i].order = *order;
            j[i].pass = 1;
        }
        fdt_fork_join(j, sizeof *j, nj, order_pass);
    }
    *len = run;
    free(j);
    free(cnt);
    return *order ? FDT_OK : FDT_ENOMEM;
}

/*
 * Checks 1-3 for the slots order[lo, hi) of m. Each face is checked once,
 * from its lower slot: both ends are visited close together in the order,
 * so the other end's row is in cache whichever it is, and ranges of the
 * order (space) get equal shares of their faces with other ranges (slot
 * numbers are not in space order). That end checks the geometry and
 * the other end's reference back; the other end only counts its reference
 * (*skipped: four a tet in use, less the ones it checked) and the
 * checking end counts the pair (*pairs). Over the whole mesh every
 * skipped reference must be the back half of a checked pair, so the two
 * sums must be equal (the caller compares them): a reference with no way
 * back breaks the equality even when its target is consistent with
 * someone else. Each neighbour slot is read once a face, where the
 * neighbour reads are most of the time.
 */
static int certify_range(const fdt_ins *m, const uint32_t *order, uint32_t lo, uint32_t hi,
                         const fdt_certify_visit *vis, int job, fdt_pred_counts *cnt,
                         fdt_certify_fail *why, size_t *skipped, size_t *pairs)
{
    size_t used = 0, npairs = 0; /* tets in use, pairs checked */
    const double dev = m->sf.img ? m->sf.img->err : 0;
    for (uint32_t i = lo; i < hi; i++) {
        const uint32_t t = order[i];
        if (i + 3 * AHEAD < hi) /* the row: in the order, slots are far apart */
            __builtin_prefetch(m->T + 8 * (size_t)order[i + 3 * AHEAD]);
        if (i + 2 * AHEAD < hi) { /* its neighbours, mostly in cache already */
            const uint32_t *a = m->T + 8 * (size_t)order[i + 2 * AHEAD];
            for (int k = 0; k < 4; k++) {
                uint32_t nu = a[4 + k] >> 2;
                __builtin_prefetch(m->T + 8 * (size_t)(nu < m->nslots ? nu : 0));
            }
        }
        if (i + AHEAD < hi) { /* the points those tets will read, their rows now in cache */
            const uint32_t *a = m->T + 8 * (size_t)order[i + AHEAD];
            for (int k = 0; k < 4; k++) {
                uint32_t nu = a[4 + k] >> 2, r = a[4 + k] & 3;
                uint32_t q = m->T[8 * (size_t)(nu < m->nslots ? nu : 0) + r], x = a[k];
                __builtin_prefetch(m->P + 3 * (size_t)(q < m->base + m->n ? q : m->base));
                __builtin_prefetch(m->P + 3 * (size_t)(x < m->base + m->n ? x : m->base));
            }
        }
        const uint32_t *v = m->T + 8 * (size_t)t;
        int ninf = (v[0] == INF) + (v[1] == INF) + (v[2] == INF) + (v[3] == INF);
        if (ninf > 1)
            return fail(why, t, -1, "more than one infinite vertex");
        int inf = !ninf ? -1 : v[0] == INF ? 0 : v[1] == INF ? 1 : v[2] == INF ? 2 : 3;
        /* A finite tet's lifted cofactors serve its orientation and the
         * spheres of the faces it checks (fdt_sphere_cof). */
        fdt_sphere_cof cof = {0}; /* read only where inf < 0 */
        if (inf < 0) {
            fdt_sphere_cof_init(&cof, pt(m, v[0]), pt(m, v[1]), pt(m, v[2]), pt(m, v[3]));
            /* rounded periodic images: the bounds widened by their
             * rounding (src/geom/images.h) */
            cof.dev = dev;
            int o = fdt_sphere_cof_orient(&cof);
            if (o == FDT_PRED_UNSURE)
                o = orient(m, pt(m, v[0]), pt(m, v[1]), pt(m, v[2]), pt(m, v[3]), cnt);
            if (o <= 0)
                return fail(why, t, -1, "a finite tet is not positively oriented");
        }
        /* Which faces this end checks, as bits: one loop over them instead
         * of a coin-flip branch a face. */
        unsigned here = 0, bad = 0;
        for (int k = 0; k < 4; k++) {
            uint32_t nt = v[4 + k] >> 2;
            bad |= (unsigned)((nt >= m->nslots) | (nt == t)) << k;
            here |= (unsigned)(t < nt) << k;
        }
        if (bad)
            return fail(why, t, fdt_ctz64(bad), "a neighbour reference past the slots, or to itself");
        used++;
        for (; here; here &= here - 1) {
            int k = fdt_ctz64(here);
            uint32_t r = v[4 + k], nt = r >> 2;
            int nk = (int)(r & 3);
            const uint32_t *w = m->T + 8 * (size_t)nt;
            if (is_freed(w))
                return fail(why, t, k, "a neighbour is a freed slot");
            if (w[4 + nk] != ((t << 2) | (uint32_t)k))
                return fail(why, t, k, "the neighbour does not refer back");
            if (!glued_opposite(v, k, w, nk))
                return fail(why, t, k,
                            glued(v, k, w, nk) == 0
                                ? "the neighbours do not share the face"
                                : "two tets on the same side of their face");
            npairs++;
            const char *bad_pair = inf < 0 ? check_pair_finite(m, v, &cof, w[nk], cnt)
                                           : check_pair_infinite(m, v, k, inf, w, nk, cnt);
            if (bad_pair)
                return fail(why, t, k, bad_pair);
        }
        if (vis)
            vis->tet(vis->user, job, t, v, inf, inf < 0 ? &cof : NULL);
    }
    *skipped += 4 * used - npairs;
    *pairs += npairs;
    return FDT_OK;
}

/* The end of checks 1-3: every reference skipped was a checked pair's. */
static int certify_balance(const fdt_ins *m, size_t skipped, size_t pairs,
                           fdt_certify_fail *why)
{
    return skipped == pairs ? FDT_OK
                            : fail(why, m->nslots, -1, "a neighbour reference with no way back");
}

int fdt_certify_vertices(const fdt_ins *m, fdt_certify_fail *why)
{
    for (uint32_t i = 0; i < m->n; i++) {
        uint32_t s = m->vtet[i], id = m->base + i;
        if (s >= m->nslots)
            return fail(why, s, -1, "a point is in no tet");
        const uint32_t *v = m->T + 8 * (size_t)s;
        if (is_freed(v) || (v[0] != id && v[1] != id && v[2] != id && v[3] != id))
            return fail(why, s, -1, "a point is not a vertex of its tet");
    }
    return FDT_OK;
}

/* The whole certificate on the calling thread, with vis's pass. */
static int certify_serial(const fdt_ins *m, const fdt_certify_visit *vis, fdt_pred_counts *cnt,
                          fdt_certify_fail *why)
{
    size_t skipped = 0, pairs = 0;
    uint32_t *order, len;
    int err = order_slots(m, 1, &order, &len);
    if (!err)
        err = certify_range(m, order, 0, len, vis, 0, cnt, why, &skipped, &pairs);
    free(order);
    if (!err)
        err = certify_balance(m, skipped, pairs, why);
    return err ? err : fdt_certify_vertices(m, why);
}

int fdt_certify(const fdt_ins *m, fdt_pred_counts *cnt, fdt_certify_fail *why)
{
    return certify_serial(m, NULL, cnt, why);
}

typedef struct cert_job {
    const fdt_ins *m;
    const uint32_t *order;
    const fdt_certify_visit *vis;
    int index;
    uint32_t lo, hi;
    fdt_pred_counts pc;
    fdt_certify_fail why;
    size_t skipped, pairs;
    int rc;
} cert_job;

/* The ranges of a parallel certificate and the next one to take. */
typedef struct cert_pool {
    cert_job *jobs;
    int njobs;
    /* relaxed: a taker only needs a range no other taker got (the
     * counter's own modification order); what a range's check wrote is
     * published to the caller by fdt_fork_join's joins. */
    atomic_int next;
} cert_pool;

/* A thread's loop (arg: a cert_pool * of fdt_fork_join's array, every one
 * the same pool): the next range, until none is left. */
static void *cert_take(void *arg)
{
    cert_pool *p = *(cert_pool **)arg;
    int i;
    while ((i = atomic_fetch_add_explicit(&p->next, 1, memory_order_relaxed)) < p->njobs) {
        cert_job *j = &p->jobs[i];
        j->rc = certify_range(j->m, j->order, j->lo, j->hi, j->vis, j->index, &j->pc, &j->why,
                              &j->skipped, &j->pairs);
    }
    return NULL;
}

/* Ranges a thread: ranges can cost unequally (in slot order, before
 * entry 130, the lower slots' neighbours lay far apart and halves left one
 * thread idle a third of the time, bench/NOTES.md entry 126), so threads
 * take the next range as they finish one. */
#define RANGES_A_THREAD 4

int fdt_certify_jobs(const fdt_ins *m, int nthreads)
{
    if (nthreads <= 1 || m->nslots < 4096)
        return 1;
    int r = nthreads * RANGES_A_THREAD;
    return r > FDT_CERTIFY_MAX_JOBS ? FDT_CERTIFY_MAX_JOBS : r;
}

int fdt_certify_parallel(const fdt_ins *m, int nthreads, fdt_pred_counts *cnt,
                         fdt_certify_fail *why)
{
    return fdt_certify_parallel_visit(m, nthreads, NULL, cnt, why);
}

int fdt_certify_parallel_visit(const fdt_ins *m, int nthreads, const fdt_certify_visit *vis,
                               fdt_pred_counts *cnt, fdt_certify_fail *why)
{
    int nj = fdt_certify_jobs(m, nthreads);
    if (nj == 1)
        return certify_serial(m, vis, cnt, why);
    if (nthreads > nj)
        nthreads = nj;
    cert_job *j = calloc((size_t)nj, sizeof *j);
    cert_pool **take = malloc((size_t)nthreads * sizeof *take);
    uint32_t *order = NULL, len = 0;
    if (!j || !take || order_slots(m, nthreads, &order, &len) != FDT_OK) {
        free(j);
        free(take);
        return FDT_ENOMEM;
    }
    for (int i = 0; i < nj; i++) {
        j[i].m = m;
        j[i].order = order;
        j[i].vis = vis;
        j[i].index = i;
        j[i].lo = (uint32_t)((uint64_t)len * (uint64_t)i / (uint64_t)nj);
        j[i].hi = (uint32_t)((uint64_t)len * (uint64_t)(i + 1) / (uint64_t)nj);
    }
    cert_pool pool = {.jobs = j, .njobs = nj};
    atomic_init(&pool.next, 0);
    for (int i = 0; i < nthreads; i++)
        take[i] = &pool;
    /* a thread that cannot start leaves its ranges to the others */
    fdt_fork_join(take, sizeof *take, nthreads, cert_take);
    free(take);
    free(order);
    int err = FDT_OK;
    /* The joins publish each range's fields to this thread; the lowest
     * failing range is the one reported, whoever checked it. */
    size_t skipped = 0, pairs = 0;
    for (int i = 0; i < nj && !err; i++) {
        if (j[i].rc) {
            err = j[i].rc;
            if (why)
                *why = j[i].why;
        }
        skipped += j[i].skipped;
        pairs += j[i].pairs;
    }
    if (!err)
        err = certify_balance(m, skipped, pairs, why);
    if (cnt)
        for (int i = 0; i < nj; i++)
            fdt_pred_counts_add(cnt, &j[i].pc);
    free(j);
    return err ? err : fdt_certify_vertices(m, why);
}

void fdt_certify_build_failed(fdt_certify_fail *why)
{
    why->slot = FDT_NONE;
    why->face = -1;
    why->what = "the insertion's own consistency checks failed";
}

void fdt_certify_describe(const fdt_certify_fail *why, char *buf, size_t len)
{
    if (why->slot == FDT_NONE)
        snprintf(buf, len, "mesh certificate failed: %s", why->what);
    else if (why->face >= 0)
        snprintf(buf, len, "mesh certificate failed: tet slot %u face %d: %s", why->slot,
                 why->face, why->what);
    else
        snprintf(buf, len, "mesh certificate failed: tet slot %u: %s", why->slot, why->what);
}
