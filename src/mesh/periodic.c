/* The periodic Delaunay tetrahedralization; see periodic.h. */
#include "mesh/periodic.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/hash.h"
#include "geom/images.h"
#include "geom/morton.h"
#include "mesh/certify.h"
#include "mesh/insert.h"
#include "mesh/voronoi.h"

/* ---- step 1: the points and their images within the margin ----------- */

typedef struct ext {
    double *P;       /* rounded images, 3 each */
    uint32_t *src;   /* input index */
    int8_t *off;     /* 3 each */
    uint64_t *vk;    /* each as one integer (vpack), once in Morton order */
    uint8_t *exact;
    uint32_t n, cap;
    double err;      /* the largest |exact - rounded| */
} ext;

/*
 * A vertex (input index, offsets) as one integer: the index, then each
 * offset plus 128 in a byte, so that integer order is the order by index,
 * then offsets. VZERO: the offsets of an input point itself.
 */
#define VZERO UINT64_C(0x808080)
#define VOFF UINT64_C(0xffffff)

static inline uint64_t vpack(uint32_t src, const int8_t o[3])
{
    return (uint64_t)src << 24 | (uint64_t)(uint8_t)(o[0] + 128) << 16 |
           (uint64_t)(uint8_t)(o[1] + 128) << 8 | (uint64_t)(uint8_t)(o[2] + 128);
}

static void ext_free(ext *e)
{
    free(e->P);
    free(e->src);
    free(e->off);
    free(e->vk);
    free(e->exact);
    memset(e, 0, sizeof *e);
}

static int ext_grow(ext *e, size_t need)
{
    if (need <= e->cap)
        return FDT_OK;
    if (need > UINT32_MAX - 1)
        return FDT_ETOOBIG;
    size_t cap = e->cap ? e->cap : 1024;
    while (cap < need)
        cap *= 2;
    if (cap > UINT32_MAX - 1)
        cap = UINT32_MAX - 1;
    double *P = realloc(e->P, cap * 3 * sizeof *P);
    if (P)
        e->P = P;
    uint32_t *src = realloc(e->src, cap * sizeof *src);
    if (src)
        e->src = src;
    int8_t *off = realloc(e->off, cap * 3 * sizeof *off);
    if (off)
        e->off = off;
    uint8_t *ex = realloc(e->exact, cap);
    if (ex)
        e->exact = ex;
    uint64_t *vk = realloc(e->vk, cap * sizeof *vk);
    if (vk)
        e->vk = vk;
    if (!P || !src || !off || !ex || !vk)
        return FDT_ENOMEM;
    e->cap = (uint32_t)cap;
    return FDT_OK;
}

/*
 * The points, then for each the images whose every offset is allowed: on
 * periodic axis k, +1 when x - lo <= m[k] (the image lands within m above
 * hi), -1 when hi - x <= m[k]. Every image whose exact coordinate lies in
 * (lo - m', hi + m') on each periodic axis, m' < m (prove_init's mm), is
 * then present: x + L < hi + m' means x - lo < m', and rounding is
 * monotone.
 */
static int make_images(ext *e, const double *X, uint32_t n, const fdt_periodic_box *b,
                       const double m[3])
{
    e->n = 0;
    e->err = 0;
    int err = ext_grow(e, (size_t)n + n / 4 + 64);
    if (err)
        return err;
    for (uint32_t i = 0; i < n; i++) {
        memcpy(e->P + 3 * (size_t)i, X + 3 * (size_t)i, 3 * sizeof(double));
        e->src[i] = i;
        memset(e->off + 3 * (size_t)i, 0, 3);
        e->exact[i] = 1;
    }
    e->n = n;
    for (uint32_t i = 0; i < n; i++) {
        const double *x = X + 3 * (size_t)i;
        int8_t opts[3][3];
        int nopt[3];
        for (int k = 0; k < 3; k++) {
            nopt[k] = 0;
            opts[k][nopt[k]++] = 0;
            if (!(b->axes >> k & 1))
                continue;
            if (x[k] - b->lo[k] <= m[k])
                opts[k][nopt[k]++] = 1;
            if (b->hi[k] - x[k] <= m[k])
                opts[k][nopt[k]++] = -1;
        }
        for (int a = 0; a < nopt[0]; a++)
            for (int c = 0; c < nopt[1]; c++)
                for (int d = 0; d < nopt[2]; d++) {
                    const int8_t o[3] = {opts[0][a], opts[1][c], opts[2][d]};
                    if (!o[0] && !o[1] && !o[2])
                        continue;
                    if ((err = ext_grow(e, (size_t)e->n + 1)) != FDT_OK)
                        return err;
                    uint32_t j = e->n++;
                    double er;
                    e->exact[j] = (uint8_t)fdt_images_round(x, o, b->lo, b->hi,
                                                            e->P + 3 * (size_t)j, &er);
                    e->err = er > e->err ? er : e->err;
                    e->src[j] = i;
                    memcpy(e->off + 3 * (size_t)j, o, 3);
                }
    }
    return FDT_OK;
}

/* The set in Morton order (the insertion's order, as the one-part
 * engine's, src/api/api.c), and its box: the n input points first, then
 * the images, each in Morton order, so that a vertex below n is an input
 * point (the proofs' test, prove_tet, reads no array). */
static int morton(ext *e, uint32_t n, double blo[3], double bhi[3])
{
    for (int k = 0; k < 3; k++)
        blo[k] = bhi[k] = e->P[k];
    for (uint32_t i = 1; i < e->n; i++)
        for (int k = 0; k < 3; k++) {
            double v = e->P[3 * (size_t)i + k];
            blo[k] = v < blo[k] ? v : blo[k];
            bhi[k] = v > bhi[k] ? v : bhi[k];
        }
    const double box[6] = {blo[0], blo[1], blo[2], bhi[0], bhi[1], bhi[2]};
    uint32_t *order = malloc((size_t)e->n * sizeof *order);
    ext s = {0};
    if (!order || ext_grow(&s, e->n) != FDT_OK || fdt_morton_order(e->P, n, box, NULL, order) < 0 ||
        fdt_morton_order(e->P + 3 * (size_t)n, e->n - n, box, NULL, order + n) < 0) {
        free(order);
        ext_free(&s);
        return FDT_ENOMEM;
    }
    for (uint32_t i = 0; i < e->n; i++) {
        uint32_t j = i < n ? order[i] : n + order[i];
        memcpy(s.P + 3 * (size_t)i, e->P + 3 * (size_t)j, 3 * sizeof(double));
        memcpy(s.off + 3 * (size_t)i, e->off + 3 * (size_t)j, 3);
        s.src[i] = e->src[j];
        s.vk[i] = vpack(e->src[j], e->off + 3 * (size_t)j);
        s.exact[i] = e->exact[j];
    }
    s.n = e->n;
    s.err = e->err;
    free(order);
    ext_free(e);
    *e = s;
    return FDT_OK;
}

/* ---- step 3: the kept tets and hull faces, normalised ------------------ */

/* A tet (4 vertices) or hull face (3, then UINT64_MAX) as the periodic
 * mesh names it: packed vertices ascending, offsets relative to the
 * first. */
typedef struct key {
    uint64_t v[4];
} key;

static int key_cmp(const void *x, const void *y)
{
    const key *a = x, *b = y;
    for (int j = 0; j < 4; j++)
        if (a->v[j] != b->v[j])
            return a->v[j] < b->v[j] ? -1 : 1;
    return 0;
}

/*
 * The key of the vertices w[0 .. nv) of the extended set: sorted, the
 * least one's offsets subtracted from every one's (a byte at a time
 * without borrows: offsets are -1..1, so every byte stays in 126..130).
 * Returns whether the least vertex is an input point (the copy this mesh
 * keeps); *repeat whether two vertices are images of one point.
 */
static int make_key(const ext *e, const uint32_t *w, int nv, key *k, int *repeat)
{
    uint64_t *a = k->v;
    for (int j = 0; j < nv; j++)
        a[j] = e->vk[w[j]];
    a[3] = nv == 4 ? a[3] : UINT64_MAX;
    for (int i = 1; i < nv; i++) /* insertion sort of 3 or 4 */
        for (int j = i; j > 0 && a[j] < a[j - 1]; j--) {
            uint64_t t = a[j];
            a[j] = a[j - 1];
            a[j - 1] = t;
        }
    uint64_t lo = a[0] & VOFF;
    *repeat = 0;
    for (int j = 0; j < nv; j++) {
        a[j] = a[j] + VZERO - lo;
        *repeat |= j > 0 && a[j] >> 24 == a[j - 1] >> 24;
    }
    return lo == VZERO;
}

/* The kept tets' (or hull faces') keys. */
typedef struct keyset {
    key *keys;
    size_t n, cap;
} keyset;

static void keyset_free(keyset *s)
{
    free(s->keys);
    memset(s, 0, sizeof *s);
}

static int keyset_add(keyset *s, const key *k)
{
    if (s->n == s->cap) {
        size_t cap = s->cap ? 2 * s->cap : 1024;
        key *nk = realloc(s->keys, cap * sizeof *nk);
        if (!nk)
            return FDT_ENOMEM;
        s->keys = nk;
        s->cap = cap;
    }
    s->keys[s->n++] = *k;
    return FDT_OK;
}

/* ---- step 4: the proofs ------------------------------------------------ */

/*
 * How far beyond the box tet v's circumscribed ball reaches on each
 * periodic axis (need[k], 0 when it stays inside), the ball cut to the
 * points' extent [ylo, yhi] on the axes that are not periodic, with room
 * for the circumcentre's error and the images' rounding err, both moved
 * through the tet's condition kappa (edge^3 / |6 volume|). A tet too flat
 * to place reaches the whole period.
 */
static void ball_reach(const ext *e, const uint32_t *v, const fdt_sphere_cof *cof,
                       const fdt_periodic_box *b, const double ylo[3], const double yhi[3],
                       double need[3])
{
    const double *a = e->P + 3 * (size_t)v[0];
    const double *p[3] = {e->P + 3 * (size_t)v[1], e->P + 3 * (size_t)v[2],
                          e->P + 3 * (size_t)v[3]};
    for (int k = 0; k < 3; k++)
        need[k] = b->axes >> k & 1 ? INFINITY : 0;
    /*
     * The centre a + x, x = N / (2 det) from the lifted cofactors
     * (predicates.h's fdt_sphere_cof: det = B . (C x D), N = |B|^2 C x D +
     * ...). Each of N's components is off by at most about 12 eps of its
     * permanent 6 h^4, det by 8 eps of 6 h^3 (h the largest difference), so
     * x by about 2^-53 kappa (h + |x|): for kappa up to 2^12 that is within
     * 2^-40 (h + |x|), which cerr's first term covers with the sums'
     * roundings. A flatter tet (a wall's, whose section the cut below
     * needs to a few ulps) takes fdt_circumcenter's double words. (cof:
     * the certificate's, whose pass this is, src/mesh/certify.h.)
     */
    const double det = cof->det, h = cof->m;
    if (!(fabs(det) > 0) || !(h > 0))
        return;
    double kappa = 64 * h * h * h / fabs(det), x[3];
    if (kappa <= 0x1p12) {
        for (int k = 0; k < 3; k++)
            x[k] = cof->n[k] / (2 * det);
    } else if (fdt_circumcenter(a, p[0], p[1], p[2], x) != 0) {
        return;
    }
    double R = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
    double c[3] = {a[0] + x[0], a[1] + x[1], a[2] + x[2]};
    double cerr = 0x1p-40 * (R + h + fabs(c[0]) + fabs(c[1]) + fabs(c[2])) + kappa * 4 * e->err;
    if (!(cerr <= DBL_MAX))
        return; /* kappa overflowed: too flat to place */
    if (!(cerr < R + h))
        return; /* too flat to place */
    /*
     * The squared radius of the ball's widest section inside the points'
     * extent, R^2 - D^2 (D: the distance from the centre to that extent
     * on the axes that are not periodic), from each vertex p as the sum
     * over the axes of (p_k - c_k)^2, but (p_j - w_j) (p_j + w_j - 2 c_j)
     * on an axis j whose extent's face w_j lies between the points and
     * the centre: no difference of two huge squares (a flat tet by a wall
     * that is not quite flat has its centre far beyond it). Each term is
     * bounded up for the centre's error cerr; an axis within cerr of its
     * face is not cut (the larger section). The largest over the vertices.
     */
    double ext2 = 0;
    const double *vs[4] = {a, p[0], p[1], p[2]};
    for (int q = 0; q < 4; q++) {
        double s2 = 0;
        for (int j = 0; j < 3; j++) {
            double pj = vs[q][j], w = c[j];
            if (!(b->axes >> j & 1) && ylo[j] - c[j] > cerr)
                w = ylo[j];
            else if (!(b->axes >> j & 1) && c[j] - yhi[j] > cerr)
                w = yhi[j];
            if (w != c[j])
                s2 += fabs(pj - w) * (fabs(pj + w - 2 * c[j]) + 2 * cerr);
            else
                s2 += (fabs(pj - c[j]) + cerr) * (fabs(pj - c[j]) + cerr);
        }
        ext2 = s2 > ext2 ? s2 : ext2;
    }
    double extent = sqrt(ext2) * (1 + 0x1p-40) + cerr;
    for (int k = 0; k < 3; k++) {
        if (!(b->axes >> k & 1))
            continue;
        double over = c[k] + extent - b->hi[k], under = b->lo[k] - (c[k] - extent);
        double w = over > under ? over : under;
        need[k] = w > 0 ? w * (1 + 0x1p-40) : 0;
    }
}

/* ---- the driver -------------------------------------------------------- */

typedef struct run {
    const double *X;
    uint32_t n;
    const fdt_periodic_box *b;
    double ylo[3], yhi[3]; /* the points' extent */
    ext e;
    fdt_images im;
    fdt_ins m;
    keyset tets[64], hull[64]; /* the kept ones, a set a job (prove_tet) */
    int nsets;
    double need[3];        /* a failed round: how far the balls reached */
    const int32_t *names;  /* the points' names in messages, or NULL */
    char *diag;
    size_t dsz;
} run;

enum { ROUND_OK = 0, ROUND_AGAIN = 1 };

/* One range's share of a round's proofs (a job of the certificate's
 * pass, src/mesh/certify.h). */
typedef struct prove_job {
    run *r;
    double mm[3], A[3], B[3]; /* the margin a hair under, the region inside */
    keyset tets, hull;   /* the kept ones */
    double need[3];      /* how far the balls reached, where too far */
    int again, err;
    long repeat_id;      /* a kept tet with two images of this point, or -1 */
} prove_job;

typedef struct prove_pass {
    run *r;
    prove_job job[64];
} prove_pass;

/* A job's region for the margin m: (lo - m', hi + m') with m' a hair under
 * the margin (or the period) for the roundings of make_images' tests and
 * of hi - lo, rounded inwards. */
static void prove_init(prove_job *j, run *r, const double m[3])
{
    memset(j, 0, sizeof *j);
    j->r = r;
    j->repeat_id = -1;
    for (int k = 0; k < 3; k++) {
        double L = r->b->hi[k] - r->b->lo[k];
        j->mm[k] = (m[k] < L ? m[k] : L) * (1 - 0x1p-40);
        j->A[k] = nextafter(r->b->lo[k] - j->mm[k], INFINITY);
        j->B[k] = nextafter(r->b->hi[k] + j->mm[k], -INFINITY);
    }
}

/*
 * The proofs (periodic.h) of one tet, certified, with its cofactors (the
 * certificate's pass): every tet with a vertex that is an input point has
 * its ball inside the region where every image is present, (A, B), and
 * every such hull face a normal with no periodic component. Then each
 * input point's star in this mesh is made of tets of the periodic mesh
 * and, a closed neighbourhood of the point, is its whole star there; the
 * kept tets (least vertex an input point) are each star's share, so all
 * of the periodic mesh, once. Once a proof fails the job only gathers how
 * far the balls reach (the next margin).
 */
static void prove_tet(void *user, int job, uint32_t slot, const uint32_t v[4], int inf,
                      const fdt_sphere_cof *cof)
{
    (void)slot;
    prove_job *j = &((prove_pass *)user)->job[job];
    const run *r = j->r;
    const fdt_periodic_box *b = r->b;
    if (j->err)
        return;
    int nv = inf < 0 ? 4 : 3;
    uint32_t w[4];
    if (inf < 0)
        memcpy(w, v, sizeof w);
    else
        fdt_ins_face_inward(v, inf, w);
    int touches = 0; /* an input point (morton: they come first) */
    for (int i = 0; i < nv; i++)
        touches |= w[i] < r->n;
    if (!touches)
        return;
    if (inf < 0) {
        double need[3];
        ball_reach(&r->e, w, cof, b, r->ylo, r->yhi, need);
        /* too far, or too flat to tell from the rounded centre: the
         * whole ball tested exactly (a fit there is a fit of its cut) */
        int far = 0;
        for (int k = 0; k < 3; k++)
            far |= b->axes >> k & 1 && need[k] >= j->mm[k];
        if (far && fdt_images_ball_inside(&r->im, w, j->A, j->B, b->axes))
            need[0] = need[1] = need[2] = 0;
        for (int k = 0; k < 3; k++)
            if (b->axes >> k & 1 && need[k] >= j->mm[k]) {
                j->again = 1;
                j->need[k] = need[k] > j->need[k] ? need[k] : j->need[k];
            }
    } else {
        /* nothing lies beyond a hull face of the periodic set: its
         * normal has no component along a periodic axis */
        for (int a = 0; a < 3; a++)
            if (b->axes >> a & 1 && fdt_images_normal_sign(&r->im, w, a) != 0) {
                j->again = 1;
                j->need[a] = INFINITY;
            }
    }
    if (j->again)
        return;
    key k;
    int rep;
    if (!make_key(&r->e, w, nv, &k, &rep))
        return;
    if (rep && j->repeat_id < 0)
        j->repeat_id = (long)(k.v[0] >> 24);
    j->err = keyset_add(inf < 0 ? &j->tets : &j->hull, &k);
}

/* One round at margin m: ROUND_OK with r->tets and r->hull (a set a
 * thread) the periodic
 * mesh, ROUND_AGAIN when a proof failed, or an error. */
static int one_round(run *r, const double m[3], int nthreads, fdt_periodic_mesh *out)
{
    const fdt_periodic_box *b = r->b;
    int err;
    fdt_ins_free(&r->m);
    for (int i = 0; i < r->nsets; i++) {
        keyset_free(&r->tets[i]);
        keyset_free(&r->hull[i]);
    }
    r->nsets = 0;
    if ((err = make_images(&r->e, r->X, r->n, b, m)) != FDT_OK)
        return err;
    double blo[3], bhi[3];
    if ((err = morton(&r->e, r->n, blo, bhi)) != FDT_OK)
        return err;
    out->images = r->e.n - r->n;
    fdt_images *im = &r->im;
    memset(im, 0, sizeof *im);
    im->P = r->e.P;
    im->n = r->e.n;
    im->X = r->X;
    im->src = r->e.src;
    im->off = r->e.off;
    im->exact = r->e.exact;
    memcpy(im->lo, b->lo, sizeof im->lo);
    memcpy(im->hi, b->hi, sizeof im->hi);
    fdt_images_init(im, blo, bhi, r->e.err);
    err = fdt_ins_build_images(&r->m, im, nthreads, &out->pc);
    if (err == FDT_EINVAL) {
        snprintf(r->diag, r->dsz, "two points coincide");
        return err;
    }
    if (err == FDT_EDEGENERATE) {
        snprintf(r->diag, r->dsz, "the points and their images do not span 3-D space");
        return err;
    }
    if (err == FDT_EINTERNAL) {
        fdt_certify_fail why;
        fdt_certify_build_failed(&why);
        fdt_certify_describe(&why, r->diag, r->dsz);
        return FDT_ECHECK;
    }
    if (err)
        return err;
    /* the certificate, and the proofs and kept tets in its pass (on the
     * run's threads, prove_tet) */
    int T = nthreads < 1 ? 1 : nthreads > 64 ? 64 : nthreads;
    prove_pass *pp = malloc(sizeof *pp);
    if (!pp)
        return FDT_ENOMEM;
    pp->r = r;
    T = fdt_certify_jobs(&r->m, T);
    for (int i = 0; i < T; i++)
        prove_init(&pp->job[i], r, m);
    prove_job *jobs = pp->job;
    const fdt_certify_visit vis = {prove_tet, pp};
    fdt_certify_fail why;
    if ((err = fdt_certify_parallel_visit(&r->m, T, &vis, &out->pc, &why)) != FDT_OK) {
        if (err == FDT_ECHECK)
            fdt_certify_describe(&why, r->diag, r->dsz);
        for (int i = 0; i < T; i++) {
            keyset_free(&jobs[i].tets);
            keyset_free(&jobs[i].hull);
        }
        free(pp);
        return err;
    }
    int again = 0;
    long repeat_id = -1;
    for (int k = 0; k < 3; k++)
        r->need[k] = 0;
    for (int i = 0; i < T; i++) {
        err = err ? err : jobs[i].err;
        again |= jobs[i].again;
        if (jobs[i].repeat_id >= 0 && (repeat_id < 0 || jobs[i].repeat_id < repeat_id))
            repeat_id = jobs[i].repeat_id;
        for (int k = 0; k < 3; k++)
            r->need[k] = jobs[i].need[k] > r->need[k] ? jobs[i].need[k] : r->need[k];
    }
    for (int i = 0; i < T; i++) { /* the run frees them */
        r->tets[i] = jobs[i].tets;
        r->hull[i] = jobs[i].hull;
    }
    r->nsets = T;
    free(pp);
    if (err)
        return err;
    if (again)
        return ROUND_AGAIN;
    if (repeat_id >= 0) {
        snprintf(r->diag, r->dsz,
                 "no periodic triangulation in one copy of the box: a tet or hull face joins "
                 "two images of point %ld (the box is too small for the points' spacing: "
                 "more points, or a smaller box)",
                 r->names ? (long)r->names[repeat_id] : repeat_id);
        return FDT_EDEGENERATE;
    }
    return ROUND_OK;
}

/*
 * The keys of the sets s[0 .. ns) (ids below n), sorted, into out's
 * arrays; each set freed once its keys are moved. Counted into buckets by
 * their first id, each bucket (the tets a point is the least vertex of: a
 * few) sorted by insertion, a large one by qsort (qsort of 6.8M keys took
 * a fifth of a 1M-point run).
 */
static int emit(keyset *s, int ns, int nv, size_t n, uint32_t **ids, int8_t **offs,
                size_t *count)
{
    size_t total = 0;
    for (int i = 0; i < ns; i++)
        total += s[i].n;
    size_t *start = calloc(n + 1, sizeof *start);
    key *tmp = malloc((total ? total : 1) * sizeof *tmp);
    if (!start || !tmp) {
        free(start);
        free(tmp);
        return FDT_ENOMEM;
    }
    for (int i = 0; i < ns; i++)
        for (size_t k = 0; k < s[i].n; k++)
            start[(s[i].keys[k].v[0] >> 24) + 1]++;
    for (size_t v = 0; v < n; v++)
        start[v + 1] += start[v];
    for (int i = 0; i < ns; i++) {
        for (size_t k = 0; k < s[i].n; k++)
            tmp[start[s[i].keys[k].v[0] >> 24]++] = s[i].keys[k];
        keyset_free(&s[i]);
    }
    for (size_t v = n; v > 0; v--) /* start[v] was the end of bucket v */
        start[v] = start[v - 1];
    start[0] = 0;
    for (size_t v = 0; v < n; v++) {
        key *a = tmp + start[v];
        size_t c = start[v + 1] - start[v];
        if (c > 32) {
            qsort(a, c, sizeof *a, key_cmp);
            continue;
        }
        for (size_t i = 1; i < c; i++) {
            key x = a[i];
            size_t j = i;
            for (; j > 0 && key_cmp(&x, &a[j - 1]) < 0; j--)
                a[j] = a[j - 1];
            a[j] = x;
        }
    }
    free(start);
    *ids = malloc((total ? total : 1) * (size_t)nv * sizeof **ids);
    *offs = malloc((total ? total : 1) * (size_t)nv * 3);
    if (!*ids || !*offs) {
        free(tmp);
        return FDT_ENOMEM;
    }
    for (size_t i = 0; i < total; i++)
        for (int j = 0; j < nv; j++) {
            uint64_t x = tmp[i].v[j];
            int8_t *o = *offs + 3 * ((size_t)nv * i + (size_t)j);
            (*ids)[(size_t)nv * i + (size_t)j] = (uint32_t)(x >> 24);
            o[0] = (int8_t)((int)(x >> 16 & 255) - 128);
            o[1] = (int8_t)((int)(x >> 8 & 255) - 128);
            o[2] = (int8_t)((int)(x & 255) - 128);
        }
    free(tmp);
    *count = total;
    return FDT_OK;
}

int fdt_periodic_check(const double *X, size_t n, const fdt_periodic_box *b, char *diag,
                       size_t dsz)
{
    if (!(b->axes & 7) || (b->axes & ~7u)) {
        snprintf(diag, dsz, "a periodic box needs one to three periodic axes");
        return FDT_EINVAL;
    }
    for (int k = 0; k < 3; k++) {
        if (!(b->axes >> k & 1))
            continue;
        double L = b->hi[k] - b->lo[k];
        if (!(fabs(b->lo[k]) <= 0x1p500 && fabs(b->hi[k]) <= 0x1p500 && L > 0)) {
            snprintf(diag, dsz, "the periodic box's %c side [%.17g, %.17g] is empty or beyond "
                     "2^500", "xyz"[k], b->lo[k], b->hi[k]);
            return FDT_EINVAL;
        }
    }
    /* a coordinate that is not finite is the merge's to name (FDT_ERANGE,
     * as in any run) */
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++)
            if (b->axes >> k & 1 && isfinite(X[3 * i + k]) &&
                !(X[3 * i + k] >= b->lo[k] && X[3 * i + k] < b->hi[k])) {
                snprintf(diag, dsz, "point %zu has %c = %.17g, outside the periodic box's "
                         "[%.17g, %.17g)", i, "xyz"[k], X[3 * i + k], b->lo[k], b->hi[k]);
                return FDT_EINVAL;
            }
    return FDT_OK;
}

int fdt_periodic_renumber(fdt_periodic_mesh *m, const int32_t *orig, size_t n)
{
    /* orig increasing (src/geom/prepare.h keeps first occurrences in
     * input order): the rows keep their order and their least vertex */
    for (size_t i = 1; i < n; i++)
        if (orig[i] <= orig[i - 1])
            return FDT_EINTERNAL;
    for (size_t i = 0; i < 4 * m->ntets; i++)
        m->tets[i] = (uint32_t)orig[m->tets[i]];
    for (size_t i = 0; i < 3 * m->nhull; i++)
        m->hull[i] = (uint32_t)orig[m->hull[i]];
    return FDT_OK;
}

int fdt_periodic_build(const double *X, uint32_t n, const int32_t *names,
                       const fdt_periodic_box *b, int nthreads, fdt_periodic_mesh *out,
                       char *diag, size_t diag_size)
{
    memset(out, 0, sizeof *out);
    char own[8];
    if (!diag || !diag_size) {
        diag = own;
        diag_size = sizeof own;
    }
    diag[0] = 0;
    int err = fdt_periodic_check(X, n, b, diag, diag_size);
    if (err)
        return err;
    if (n < 1) {
        snprintf(diag, diag_size, "no points");
        return FDT_EDEGENERATE;
    }
    run r;
    memset(&r, 0, sizeof r);
    r.X = X;
    r.n = n;
    r.names = names;
    r.b = b;
    r.diag = diag;
    r.dsz = diag_size;
    for (int k = 0; k < 3; k++)
        r.ylo[k] = r.yhi[k] = X[k];
    for (uint32_t i = 1; i < n; i++)
        for (int k = 0; k < 3; k++) {
            double v = X[3 * (size_t)i + k];
            r.ylo[k] = v < r.ylo[k] ? v : r.ylo[k];
            r.yhi[k] = v > r.yhi[k] ? v : r.yhi[k];
        }
    /* The first margin: three mean spacings, (volume / n)^(1/3). */
    double vol = 1;
    for (int k = 0; k < 3; k++) {
        double s = b->axes >> k & 1 ? b->hi[k] - b->lo[k] : r.yhi[k] - r.ylo[k];
        vol *= s > 0 ? s : 1;
    }
    double m0 = 3 * cbrt(vol / n), m[3] = {0, 0, 0};
    for (int k = 0; k < 3; k++)
        if (b->axes >> k & 1)
            m[k] = m0 < b->hi[k] - b->lo[k] ? m0 : b->hi[k] - b->lo[k];
    for (;;) {
        out->rounds++;
        err = one_round(&r, m, nthreads, out);
        if (err != ROUND_AGAIN)
            break;
        /* The next margin: what the balls reached, and a quarter more (a
         * face that was not flat: twice the margin), at most the period. */
        int grew = 0;
        for (int k = 0; k < 3; k++) {
            double L = b->hi[k] - b->lo[k];
            if (!(b->axes >> k & 1) || !(r.need[k] > 0) || m[k] >= L)
                continue;
            double w = isfinite(r.need[k]) ? 1.25 * r.need[k] : 2 * m[k];
            w = w > 1.25 * m[k] ? w : 1.25 * m[k];
            m[k] = w < L ? w : L;
            grew = 1;
        }
        if (!grew) {
            snprintf(diag, diag_size,
                     "no periodic triangulation in one copy of the box: with every point's "
                     "neighbouring images the mesh still reaches past them (the box is too "
                     "small for the points' spacing, or the points' extent across the axes "
                     "that are not periodic is not flat at its ends: more points, or walls "
                     "of points there)");
            err = FDT_EDEGENERATE;
            break;
        }
    }
    memcpy(out->margin, m, sizeof m);
    /* the mesh and the images go before the output is made */
    fdt_ins_free(&r.m);
    ext_free(&r.e);
    if (err == FDT_OK &&
        ((err = emit(r.tets, r.nsets, 4, n, &out->tets, &out->tet_off, &out->ntets)) ||
         (err = emit(r.hull, r.nsets, 3, n, &out->hull, &out->hull_off, &out->nhull))))
        snprintf(diag, diag_size, "out of memory");
    for (int i = 0; i < r.nsets; i++) {
        keyset_free(&r.tets[i]);
        keyset_free(&r.hull[i]);
    }
    if (err) {
        fdt_pred_counts pc = out->pc;
        fdt_periodic_free(out);
        out->pc = pc;
    }
    return err;
}

void fdt_periodic_free(fdt_periodic_mesh *m)
{
    free(m->tets);
    free(m->tet_off);
    free(m->hull);
    free(m->hull_off);
    memset(m, 0, sizeof *m);
}

/* ---- the Voronoi cells of a periodic mesh ------------------------------ */

/* A map from packed vertices (vpack) to their index in a list of
 * vertices with coordinates: open addressing, grown at half full. */
typedef struct vmap {
    uint64_t *key;   /* UINT64_MAX: empty */
    uint32_t *val;
    size_t mask, n;
    uint64_t *vk;    /* the vertices in order, and their rounded images */
    double *xyz;
    uint32_t *label;
    size_t cap;
} vmap;

static void vmap_free(vmap *m)
{
    free(m->key);
    free(m->val);
    free(m->vk);
    free(m->xyz);
    free(m->label);
    memset(m, 0, sizeof *m);
}

static int vmap_rehash(vmap *m, size_t size)
{
    uint64_t *keys = malloc(size * sizeof *keys);
    uint32_t *val = malloc(size * sizeof *val);
    if (!keys || !val) {
        free(keys);
        free(val);
        return FDT_ENOMEM;
    }
    memset(keys, 0xff, size * sizeof *keys);
    for (size_t i = 0; i < m->n; i++) {
        size_t h = (size_t)fdt_mix64(m->vk[i]) & (size - 1);
        while (keys[h] != UINT64_MAX)
            h = (h + 1) & (size - 1);
        keys[h] = m->vk[i];
        val[h] = (uint32_t)i;
    }
    free(m->key);
    free(m->val);
    m->key = keys;
    m->val = val;
    m->mask = size - 1;
    return FDT_OK;
}

/* The index of vertex (id, o), added (its image rounded) when new; -1
 * when out of memory. */
static long vmap_get(vmap *m, uint32_t id, const int8_t o[3], const double *X,
                     const fdt_periodic_box *b)
{
    uint64_t k = vpack(id, o);
    if (m->key) {
        for (size_t h = (size_t)fdt_mix64(k) & m->mask; m->key[h] != UINT64_MAX;
             h = (h + 1) & m->mask)
            if (m->key[h] == k)
                return (long)m->val[h];
    }
    if (2 * (m->n + 1) > m->mask + 1 && vmap_rehash(m, m->key ? 2 * (m->mask + 1) : 1024))
        return -1;
    if (m->n == m->cap) {
        size_t cap = m->cap ? 2 * m->cap : 1024;
        uint64_t *vk = realloc(m->vk, cap * sizeof *vk);
        if (vk)
            m->vk = vk;
        double *xyz = realloc(m->xyz, 3 * cap * sizeof *xyz);
        if (xyz)
            m->xyz = xyz;
        uint32_t *label = realloc(m->label, cap * sizeof *label);
        if (label)
            m->label = label;
        if (!vk || !xyz || !label)
            return -1;
        m->cap = cap;
    }
    size_t i = m->n++;
    m->vk[i] = k;
    m->label[i] = id;
    (void)fdt_images_round(X + 3 * (size_t)id, o, b->lo, b->hi, m->xyz + 3 * i, NULL);
    size_t h = (size_t)fdt_mix64(k) & m->mask;
    while (m->key[h] != UINT64_MAX)
        h = (h + 1) & m->mask;
    m->key[h] = k;
    m->val[h] = (uint32_t)i;
    return (long)i;
}

/* The orientation of periodic tet (id[4], off[12]) for its exact images:
 * the rounded images' determinant where it is clear of their error, else
 * GMP (src/geom/images.h). */
static int tet_orient(const double *X, const uint32_t id[4], const int8_t off[12],
                      const fdt_periodic_box *b)
{
    double P[12], err = 0, e;
    uint8_t exact[4] = {0, 0, 0, 0};
    for (int j = 0; j < 4; j++) {
        exact[j] = (uint8_t)fdt_images_round(X + 3 * (size_t)id[j], off + 3 * j, b->lo, b->hi,
                                             P + 3 * j, &e);
        err = e > err ? e : err;
    }
    double lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = hi[k] = P[k];
        for (int j = 1; j < 4; j++) {
            lo[k] = P[3 * j + k] < lo[k] ? P[3 * j + k] : lo[k];
            hi[k] = P[3 * j + k] > hi[k] ? P[3 * j + k] : hi[k];
        }
    }
    fdt_images im;
    memset(&im, 0, sizeof im);
    im.P = P;
    im.n = 4;
    im.X = X;
    im.src = id;
    im.off = off;
    im.exact = exact;
    memcpy(im.lo, b->lo, sizeof im.lo);
    memcpy(im.hi, b->hi, sizeof im.hi);
    fdt_images_init(&im, lo, hi, err);
    return fdt_images_orient(&im, P, P + 3, P + 6, P + 9, NULL);
}

/* The key of a face (3 vertices, ids ascending with their offsets, as
 * the mesh names a hull face): relative to its first vertex. */
static void face_key(const uint32_t id[3], const int8_t *o[3], uint64_t k[3])
{
    for (int j = 0; j < 3; j++) {
        const int8_t r[3] = {(int8_t)(o[j][0] - o[0][0]), (int8_t)(o[j][1] - o[0][1]),
                             (int8_t)(o[j][2] - o[0][2])};
        k[j] = vpack(id[j], r);
    }
}

static size_t face_hash(const uint64_t k[3], size_t mask)
{
    return (size_t)fdt_mix64(k[0] ^ fdt_mix64(k[1] ^ fdt_mix64(k[2]))) & mask;
}

void fdt_periodic_unfolded_free(fdt_periodic_unfolded *u)
{
    free(u->xyz);
    free(u->src);
    free(u->tets);
    free(u->hull);
    memset(u, 0, sizeof *u);
}

int fdt_periodic_unfold(const int32_t *tets, const int8_t *off, size_t ntets, const int32_t *hull,
                        const int8_t *hoff, size_t nhull, const double *X, size_t n,
                        const fdt_periodic_box *b, fdt_periodic_unfolded *u)
{
    memset(u, 0, sizeof *u);
    if (n > UINT32_MAX / 2)
        return FDT_ETOOBIG;
    vmap m;
    memset(&m, 0, sizeof m);
    uint64_t *hk = NULL;   /* the hull faces' keys, by hash: 3 each */
    uint32_t *hslot = NULL, *apex = NULL;
    int8_t *aoff = NULL;   /* each hull face's apex offsets, from its first vertex */
    size_t hmask = 0;
    int err = FDT_OK;
    static const int8_t zero[3] = {0, 0, 0};
    for (size_t i = 0; i < n && !err; i++) /* the input points first: their ids */
        if (vmap_get(&m, (uint32_t)i, zero, X, b) < 0)
            err = FDT_ENOMEM;
    if (!err && !(u->tets = malloc((4 * ntets + 1) * sizeof *u->tets)))
        err = FDT_ENOMEM;
    /* each tet where its offsets place it, positively oriented */
    for (size_t t = 0; t < ntets && !err; t++) {
        const uint32_t *id = (const uint32_t *)tets + 4 * t;
        const int8_t *o = off + 12 * t;
        for (int k = 0; k < 4 && !err; k++) {
            long x = vmap_get(&m, id[k], o + 3 * k, X, b);
            if (x < 0)
                err = FDT_ENOMEM;
            u->tets[4 * t + (size_t)k] = (fdt_vid)x;
        }
        if (tet_orient(X, id, o, b) < 0) {
            fdt_vid tmp = u->tets[4 * t];
            u->tets[4 * t] = u->tets[4 * t + 1];
            u->tets[4 * t + 1] = tmp;
        }
    }
    /* each hull face outward: its tet's fourth vertex (the apex) on the
     * negative side; the tet found by the face's key among its four */
    if (!err && nhull) {
        size_t size = 16;
        while (size < 2 * nhull)
            size *= 2;
        hmask = size - 1;
        if (!(hk = malloc(3 * size * sizeof *hk)) || !(hslot = malloc(size * sizeof *hslot)) ||
            !(apex = malloc(nhull * sizeof *apex)) || !(aoff = malloc(3 * nhull)))
            err = FDT_ENOMEM;
        for (size_t h = 0; !err && h <= hmask; h++)
            hslot[h] = UINT32_MAX;
        for (size_t f = 0; !err && f < nhull; f++) {
            const uint32_t *id = (const uint32_t *)hull + 3 * f;
            const int8_t *o[3] = {hoff + 9 * f, hoff + 9 * f + 3, hoff + 9 * f + 6};
            uint64_t k[3];
            face_key(id, o, k);
            size_t h = face_hash(k, hmask);
            while (hslot[h] != UINT32_MAX)
                h = (h + 1) & hmask;
            hslot[h] = (uint32_t)f;
            memcpy(hk + 3 * h, k, sizeof k);
            apex[f] = UINT32_MAX;
        }
        for (size_t t = 0; !err && t < ntets; t++) {
            const uint32_t *id = (const uint32_t *)tets + 4 * t;
            const int8_t *o = off + 12 * t;
            for (int j = 0; j < 4; j++) {
                uint32_t fid[3];
                const int8_t *fo[3];
                for (int i = 0, c = 0; i < 4; i++)
                    if (i != j) {
                        fid[c] = id[i];
                        fo[c++] = o + 3 * i;
                    }
                uint64_t k[3];
                face_key(fid, fo, k);
                for (size_t h = face_hash(k, hmask); hslot[h] != UINT32_MAX; h = (h + 1) & hmask)
                    if (!memcmp(hk + 3 * h, k, sizeof k)) {
                        uint32_t f = hslot[h];
                        apex[f] = id[j];
                        for (int a = 0; a < 3; a++)
                            aoff[3 * f + (size_t)a] = (int8_t)(o[3 * j + a] - fo[0][a]);
                        break;
                    }
            }
        }
    }
    if (!err && !(u->hull = malloc((3 * nhull + 1) * sizeof *u->hull)))
        err = FDT_ENOMEM;
    for (size_t f = 0; f < nhull && !err; f++) {
        const uint32_t *id = (const uint32_t *)hull + 3 * f;
        const int8_t *o = hoff + 9 * f;
        if (apex[f] == UINT32_MAX) { /* every hull face is a tet's */
            err = FDT_EINTERNAL;
            break;
        }
        for (int k = 0; k < 3 && !err; k++) {
            long x = vmap_get(&m, id[k], o + 3 * k, X, b);
            if (x < 0)
                err = FDT_ENOMEM;
            u->hull[3 * f + (size_t)k] = (fdt_vid)x;
        }
        const uint32_t q[4] = {id[0], id[1], id[2], apex[f]};
        int8_t qo[12];
        memcpy(qo, o, 9);
        memcpy(qo + 9, aoff + 3 * f, 3);
        if (tet_orient(X, q, qo, b) > 0) {
            fdt_vid tmp = u->hull[3 * f];
            u->hull[3 * f] = u->hull[3 * f + 1];
            u->hull[3 * f + 1] = tmp;
        }
    }
    if (!err && m.n > (size_t)INT32_MAX)
        err = FDT_ETOOBIG;
    if (!err) {
        u->n = m.n;
        u->ntets = ntets;
        u->nhull = nhull;
        u->xyz = m.xyz;
        m.xyz = NULL;
        if (!(u->src = malloc((m.n ? m.n : 1) * sizeof *u->src)))
            err = FDT_ENOMEM;
        for (size_t i = 0; !err && i < m.n; i++)
            u->src[i] = (fdt_vid)m.label[i];
    }
    if (err)
        fdt_periodic_unfolded_free(u);
    vmap_free(&m);
    free(hk);
    free(hslot);
    free(apex);
    free(aoff);
    return err;
}

int fdt_periodic_cells(const int32_t *tets, const int8_t *off, size_t ntets, const int32_t *hull,
                       size_t nhull, const double *X, size_t n, const int32_t *dupmap,
                       const fdt_periodic_box *b, int threads, int neighbors, fdt_voronoi **out,
                       char *diag, size_t ds)
{
    *out = NULL;
    /* the walls across the axes that are not periodic: the box's sides,
     * which hold every point */
    for (int k = 0; k < 3; k++) {
        if (b->axes >> k & 1)
            continue;
        if (!(b->lo[k] < b->hi[k]) || !isfinite(b->lo[k]) || !isfinite(b->hi[k])) {
            snprintf(diag, ds, "the box is empty or not finite in %c, which is not periodic: "
                     "its cells are cut there", "xyz"[k]);
            return FDT_EINVAL;
        }
        for (size_t i = 0; i < n; i++)
            if (!(X[3 * i + k] >= b->lo[k] && X[3 * i + k] <= b->hi[k])) {
                snprintf(diag, ds, "point %zu (%.17g %.17g %.17g) lies outside the box",
                         i, X[3 * i], X[3 * i + 1], X[3 * i + 2]);
                return FDT_EINVAL;
            }
    }
    vmap m;
    memset(&m, 0, sizeof m);
    uint32_t *own = NULL, *st = NULL;
    uint8_t *own_hull = NULL;
    size_t nst = 0, stcap = 0, nown = 0;
    int err = FDT_OK;
    static const int8_t zero[3] = {0, 0, 0};
    /* the points themselves first: rows 0 .. nown of the batch */
    for (size_t i = 0; i < n && !err; i++)
        if (dupmap[i] == (int32_t)i && vmap_get(&m, (uint32_t)i, zero, X, b) < 0)
            err = FDT_ENOMEM;
    nown = m.n;
    /* each tet once for each offset among its vertices, moved so that
     * vertices with that offset are the points themselves: every star */
    for (size_t t = 0; t < ntets && !err; t++) {
        const uint32_t *id = (const uint32_t *)tets + 4 * t;
        const int8_t *o = off + 12 * t;
        int pos = tet_orient(X, id, o, b) > 0;
        for (int j = 0; j < 4 && !err; j++) {
            int seen = 0;
            for (int i = 0; i < j; i++)
                seen |= !memcmp(o + 3 * i, o + 3 * j, 3);
            if (seen)
                continue;
            if (nst + 4 > stcap) {
                size_t cap = stcap ? 2 * stcap : 4096;
                uint32_t *ns = realloc(st, cap * sizeof *ns);
                if (!ns) {
                    err = FDT_ENOMEM;
                    break;
                }
                st = ns;
                stcap = cap;
            }
            uint32_t w[4];
            for (int k = 0; k < 4 && !err; k++) {
                int8_t r[3] = {(int8_t)(o[3 * k] - o[3 * j]), (int8_t)(o[3 * k + 1] - o[3 * j + 1]),
                               (int8_t)(o[3 * k + 2] - o[3 * j + 2])};
                long x = vmap_get(&m, id[k], r, X, b);
                if (x < 0)
                    err = FDT_ENOMEM;
                w[k] = (uint32_t)x;
            }
            if (!pos) {
                uint32_t tmp = w[0];
                w[0] = w[1];
                w[1] = tmp;
            }
            memcpy(st + nst, w, sizeof w);
            nst += 4;
        }
    }
    if (!err && (!(own = malloc((nown ? nown : 1) * sizeof *own)) ||
                 !(own_hull = calloc(nown ? nown : 1, 1))))
        err = FDT_ENOMEM;
    for (size_t i = 0; !err && i < nown; i++)
        own[i] = (uint32_t)i;
    /* the hull's points (across an axis that is not periodic): their
     * cells are unbounded, cut by the box */
    for (size_t f = 0; !err && f < 3 * nhull; f++) {
        long x = vmap_get(&m, (uint32_t)hull[f], zero, X, b);
        if (x < 0)
            err = FDT_ENOMEM;
        else if ((size_t)x < nown)
            own_hull[x] = 1;
    }
    /* the box: on a periodic axis the period box with a period on each
     * side, which holds every image and the circumcentres of the points'
     * stars; on the others the box's sides, where cells are cut */
    fdt_vbatch vb;
    memset(&vb, 0, sizeof vb);
    for (int k = 0; k < 3 && !err; k++) {
        if (!(b->axes >> k & 1)) {
            vb.box[k] = b->lo[k];
            vb.box[k + 3] = b->hi[k];
            continue;
        }
        double L = b->hi[k] - b->lo[k];
        vb.box[k] = b->lo[k] - L;
        vb.box[k + 3] = b->hi[k] + L;
        for (size_t i = 0; i < m.n; i++) {
            double v = m.xyz[3 * i + k];
            vb.box[k] = v < vb.box[k] ? v : vb.box[k];
            vb.box[k + 3] = v > vb.box[k + 3] ? v : vb.box[k + 3];
        }
    }
    if (!err)
        err = fdt_voronoi_scale(vb.box, &vb.ed, diag, ds);
    fdt_voronoi *v = NULL;
    if (!err) {
        vb.xyz = m.xyz;
        vb.xyz_exp = 0;
        vb.label = (const fdt_vid *)m.label;
        vb.own = own;
        vb.nown = nown;
        vb.own_hull = own_hull;
        vb.tets = st;
        vb.ntets = nst / 4;
        vb.neighbors = neighbors;
        fdt_vshort sh = {-1, -1, INFINITY};
        err = fdt_voronoi_batch(&vb, threads, &v, &sh, diag, ds);
        if (err == FDT_ERANGE)
            err = fdt_voronoi_too_close(&sh, vb.box, diag, ds);
    }
    /* no cell of a set periodic on every axis is clipped: one that is
     * reached past its neighbouring images (a bug) */
    const uint8_t *fl = v ? fdt_voronoi_flags(v) : NULL;
    for (size_t i = 0; !err && b->axes == 7 && i < nown; i++)
        if (fl[i] & FDT_CELL_CLIPPED) {
            snprintf(diag, ds, "the periodic cell of point %u reaches past its images",
                     m.label[own[i]]);
            err = FDT_EINTERNAL;
        }
    if (!err)
        err = fdt_voronoi_spread(&v, n);
    if (err)
        fdt_voronoi_free(&v);
    *out = v;
    vmap_free(&m);
    free(own);
    free(own_hull);
    free(st);
    return err;
}
