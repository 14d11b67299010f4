/* The periodic Delaunay tetrahedralization; see periodic.h. */
#include "mesh/periodic.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/hash.h"
#include "base/mem.h"
#include "base/sortu64.h"
#include "base/spawn.h"
#include "geom/images.h"
#include "geom/morton.h"
#include "mesh/certify.h"
#include "mesh/check.h"
#include "mesh/insert.h"
#include "mesh/locate.h"
#include "mesh/voronoi.h"

/* ---- step 1: the points and their images within the margin ----------- */

typedef struct ext {
    double *P;       /* rounded images, 3 each */
    uint32_t *src;   /* input index */
    int8_t *off;     /* 3 each */
    uint64_t *vk;    /* each as one integer (vpack), once in Morton order */
    uint8_t *exact;
    uint32_t *rank;  /* an owned point's place in the owned list (morton) */
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
    free(e->rank);
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
    /* written at once, every page: huge pages (a 4 KB fault is a trap on
     * some hosts, src/base/mem.h) */
    const size_t old = e->cap;
    double *P = fdt_mem_realloc_huge(e->P, old * 3 * sizeof *P, cap * 3 * sizeof *P);
    if (P)
        e->P = P;
    uint32_t *src = fdt_mem_realloc_huge(e->src, old * sizeof *src, cap * sizeof *src);
    if (src)
        e->src = src;
    int8_t *off = fdt_mem_realloc_huge(e->off, old * 3 * sizeof *off, cap * 3 * sizeof *off);
    if (off)
        e->off = off;
    uint8_t *ex = fdt_mem_realloc_huge(e->exact, old, cap);
    if (ex)
        e->exact = ex;
    uint64_t *vk = fdt_mem_realloc_huge(e->vk, old * sizeof *vk, cap * sizeof *vk);
    if (vk)
        e->vk = vk;
    if (!P || !src || !off || !ex || !vk)
        return FDT_ENOMEM;
    e->cap = (uint32_t)cap;
    return FDT_OK;
}

/*
 * A part's points and images (fdt_periodic_parts): the points it owns
 * (own[0 .. nown), ascending; all n when own is NULL), then for each of
 * them and of the candidates near it (near[0 .. nnear)) the copies whose
 * every offset is allowed. On periodic axis k, with the part's core
 * [c0, c1) (the box's [lo, hi) on every axis but the slab's): offset 0
 * for an owned point, or a candidate with c0 - m <= x <= c1 + m; +1 when
 * (x - lo) + (hi - c1) <= m[k] (the image lands within m above c1), -1
 * when (hi - x) + (c0 - lo) <= m[k]. Every copy whose exact coordinate
 * lies in (c0 - m', c1 + m') on each periodic axis, m' < m (prove_init's
 * mm), is then present: x + L < c1 + m' means the two nonnegative terms
 * sum below m', and rounding is monotone. With the whole box as the core
 * the tests are the box's: x - lo <= m, hi - x <= m.
 */
static int make_images(ext *e, const double *X, uint32_t n, const uint32_t *own, uint32_t nown,
                       const uint32_t *near, uint32_t nnear, const fdt_periodic_box *b,
                       const double c0[3], const double c1[3], const double m[3])
{
    if (!own)
        nown = n;
    e->n = 0;
    e->err = 0;
    int err = ext_grow(e, (size_t)nown + nown / 4 + 64);
    if (err)
        return err;
    for (uint32_t q = 0; q < nown; q++) {
        uint32_t i = own ? own[q] : q;
        memcpy(e->P + 3 * (size_t)q, X + 3 * (size_t)i, 3 * sizeof(double));
        e->src[q] = i;
        memset(e->off + 3 * (size_t)q, 0, 3);
        e->exact[q] = 1;
    }
    e->n = nown;
    for (uint32_t q = 0; q < nown + nnear; q++) {
        int owned = q < nown;
        uint32_t i = owned ? (own ? own[q] : q) : near[q - nown];
        const double *x = X + 3 * (size_t)i;
        int8_t opts[3][3];
        int nopt[3];
        for (int k = 0; k < 3; k++) {
            nopt[k] = 0;
            if (!(b->axes >> k & 1)) {
                opts[k][nopt[k]++] = 0;
                continue;
            }
            if (owned || (x[k] - c1[k] <= m[k] && c0[k] - x[k] <= m[k]))
                opts[k][nopt[k]++] = 0;
            if ((x[k] - b->lo[k]) + (b->hi[k] - c1[k]) <= m[k])
                opts[k][nopt[k]++] = 1;
            if ((b->hi[k] - x[k]) + (c0[k] - b->lo[k]) <= m[k])
                opts[k][nopt[k]++] = -1;
        }
        for (int a = 0; a < nopt[0]; a++)
            for (int c = 0; c < nopt[1]; c++)
                for (int d = 0; d < nopt[2]; d++) {
                    const int8_t o[3] = {opts[0][a], opts[1][c], opts[2][d]};
                    if (owned && !o[0] && !o[1] && !o[2])
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
 * engine's, src/api/api.c), and its box: the n owned points first, then
 * the other copies, each in Morton order, so that a vertex below n is an
 * owned point (the proofs' test, prove_tet, reads no array). */
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
    /* order[i] for i < n: the place in the owned list of the point now
     * at i (the kept tets' buckets, emit) */
    s.rank = realloc(order, (n ? n : 1) * sizeof *order);
    if (!s.rank) {
        free(order);
        ext_free(&s);
        return FDT_ENOMEM;
    }
    ext_free(e);
    *e = s;
    return FDT_OK;
}

/* ---- step 3: the kept tets and hull faces, normalised ------------------ */

/*
 * A tet (4 vertices) or hull face (3) as the periodic mesh names it, in 20
 * bytes: the vertices ascending (by input index, then offsets), offsets
 * relative to the first, whose own are then 0 and not stored. w[0] is the
 * first vertex's index; w[1..4] a 128-bit string, most significant word
 * first, of each other vertex's index (32 bits) and offsets (3 bits an
 * axis, the offset + 2: the images' offsets are -1..1, so relative ones
 * -2..2), 41 bits a vertex, a hull face's missing fourth all ones. Word by
 * word it compares as the vertices do. Keys of 4 x 8 bytes made the kept
 * tets' sets 36 bytes a tet with their ranks (244 MB of fresh pages on
 * 1M points, bench/NOTES.md entry 130).
 */
typedef struct key {
    uint32_t w[5];
} key;

/* A vertex's offsets (each -2..2) as 9 bits, order kept. */
#define OFF_CODE_NONE 0x1ffu

static int key_cmp(const void *x, const void *y)
{
    const key *a = x, *b = y;
    for (int j = 0; j < 5; j++)
        if (a->w[j] != b->w[j])
            return a->w[j] < b->w[j] ? -1 : 1;
    return 0;
}

/* k from the vertices a[0 .. 4) packed as vpack makes them, ascending,
 * a[0]'s offsets zero (VZERO), the others' within -2..2; a missing
 * fourth (a hull face's) is UINT64_MAX. */
static void key_pack(const uint64_t a[4], key *k)
{
    uint64_t f[4]; /* f[1 .. 3]: a vertex's index and offsets, 41 bits */
    for (int j = 1; j < 4; j++) {
        uint64_t code = OFF_CODE_NONE;
        if (a[j] != UINT64_MAX)
            code = ((a[j] >> 16 & 255) - 126) << 6 | ((a[j] >> 8 & 255) - 126) << 3 |
                   ((a[j] & 255) - 126);
        f[j] = (uint64_t)(uint32_t)(a[j] >> 24) << 9 | code; /* all ones when missing */
    }
    /* the string's two 64-bit halves: f1 in bits 63..23 of hi, f2 across
     * the halves (23 + 18 bits), f3 in bits 45..5 of lo */
    const uint64_t hi = f[1] << 23 | f[2] >> 18;
    const uint64_t lo = (f[2] & ((UINT64_C(1) << 18) - 1)) << 46 | f[3] << 5;
    k->w[0] = (uint32_t)(a[0] >> 24);
    k->w[1] = (uint32_t)(hi >> 32);
    k->w[2] = (uint32_t)hi;
    k->w[3] = (uint32_t)(lo >> 32);
    k->w[4] = (uint32_t)lo;
}

/* Vertex j (0 .. 3) of k: its index and offsets. */
static void key_vertex(const key *k, int j, uint32_t *id, int8_t o[3])
{
    if (j == 0) {
        *id = k->w[0];
        o[0] = o[1] = o[2] = 0;
        return;
    }
    const uint64_t hi = (uint64_t)k->w[1] << 32 | k->w[2], lo = (uint64_t)k->w[3] << 32 | k->w[4];
    const uint64_t m41 = (UINT64_C(1) << 41) - 1;
    const uint64_t x = j == 1   ? hi >> 23
                       : j == 2 ? ((hi & ((UINT64_C(1) << 23) - 1)) << 18 | lo >> 46)
                                : (lo >> 5) & m41;
    *id = (uint32_t)(x >> 9);
    o[0] = (int8_t)((int)(x >> 6 & 7) - 2);
    o[1] = (int8_t)((int)(x >> 3 & 7) - 2);
    o[2] = (int8_t)((int)(x & 7) - 2);
}

/*
 * The key of the vertices w[0 .. nv) of the extended set: sorted, the
 * least one's offsets subtracted from every one's (a byte at a time
 * without borrows: offsets are -1..1, so every byte stays in 126..130).
 * Returns the least vertex's index in the set (the copy a part keeps is
 * the one whose least vertex is an owned point: an index below its owned
 * count); *repeat the least point two of whose images are vertices, or -1.
 */
static uint32_t make_key(const ext *e, const uint32_t *w, int nv, key *k, long *repeat)
{
    uint64_t a[4];
    uint32_t least = w[0];
    for (int j = 0; j < nv; j++) {
        a[j] = e->vk[w[j]];
        least = a[j] < e->vk[least] ? w[j] : least;
    }
    a[3] = nv == 4 ? a[3] : UINT64_MAX;
    for (int i = 1; i < nv; i++) /* insertion sort of 3 or 4 */
        for (int j = i; j > 0 && a[j] < a[j - 1]; j--) {
            uint64_t t = a[j];
            a[j] = a[j - 1];
            a[j - 1] = t;
        }
    uint64_t lo = a[0] & VOFF;
    *repeat = -1;
    for (int j = 0; j < nv; j++) {
        a[j] = a[j] + VZERO - lo;
        if (j > 0 && a[j] >> 24 == a[j - 1] >> 24 && *repeat < 0)
            *repeat = (long)(a[j] >> 24); /* sorted: the first is the least */
    }
    key_pack(a, k);
    return least;
}

/* The kept tets' (or hull faces') keys, each with its least vertex's
 * place in the owned list (emit's bucket). */
typedef struct keyset {
    key *keys;
    uint32_t *rank;
    size_t n, cap;
} keyset;

static void keyset_free(keyset *s)
{
    free(s->keys);
    free(s->rank);
    memset(s, 0, sizeof *s);
}

static int keyset_add(keyset *s, const key *k, uint32_t rank)
{
    if (s->n == s->cap) {
        size_t cap = s->cap ? 2 * s->cap : 1024;
        key *nk = realloc(s->keys, cap * sizeof *nk);
        if (nk)
            s->keys = nk;
        uint32_t *nr = realloc(s->rank, cap * sizeof *nr);
        if (nr)
            s->rank = nr;
        if (!nk || !nr)
            return FDT_ENOMEM;
        s->cap = cap;
    }
    s->keys[s->n] = *k;
    s->rank[s->n++] = rank;
    return FDT_OK;
}

/*
 * An empty set with room for cap keys, on huge pages: the kept tets' sets
 * are some hundreds of MB on 1M points, written once. Grown by doubling
 * from nothing they took a page fault every 4 KB and, where the kernel
 * could not move a block (advised blocks are several mappings), a copy
 * each time (bench/NOTES.md entry 123). FDT_OK or FDT_ENOMEM.
 */
static int keyset_reserve(keyset *s, size_t cap)
{
    if (cap < 1024)
        return FDT_OK; /* keyset_add's first room */
    s->keys = malloc(cap * sizeof *s->keys);
    s->rank = malloc(cap * sizeof *s->rank);
    if (!s->keys || !s->rank) {
        keyset_free(s);
        return FDT_ENOMEM;
    }
    fdt_mem_advise_huge(s->keys, cap * sizeof *s->keys);
    fdt_mem_advise_huge(s->rank, cap * sizeof *s->rank);
    s->cap = cap;
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
     * Most balls lie well inside the core: the whole ball, uncut, settles
     * them without the sections below (about a third of the proofs'
     * instructions on 200k uniform points). The true radius is at most
     * R (1 + 2^-50) + cerr (from vertex a, the centre off by cerr), the
     * true centre within cerr of c, and a third cerr (at least 2^-40 |c|)
     * covers the comparison's rounding.
     */
    const double rr = (R + 3 * cerr) * (1 + 0x1p-40);
    int inside = 1;
    for (int k = 0; k < 3; k++)
        if (b->axes >> k & 1)
            inside &= c[k] - rr > b->lo[k] && c[k] + rr < b->hi[k];
    if (inside) {
        need[0] = need[1] = need[2] = 0;
        return;
    }
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
    const fdt_periodic_parts *parts;
    uint32_t part;         /* the part built */
    fdt_periodic_box core; /* its core: the box, its slab on the slabs' axis */
    const uint32_t *own;   /* the points it owns, ascending (NULL: all n) */
    uint32_t nown;
    uint32_t *near;        /* the other points the round's margin may need */
    uint32_t nnear;
    double ylo[3], yhi[3]; /* the points' extent */
    ext e;
    fdt_images im;
    fdt_ins m;
    /* the kept ones, a set a job (prove_tet) */
    keyset tets[FDT_CERTIFY_MAX_JOBS], hull[FDT_CERTIFY_MAX_JOBS];
    int stars;             /* also gather every tet and hull face with an owned
                              vertex (the owned points' stars: their cells) */
    keyset star[FDT_CERTIFY_MAX_JOBS], star_hull[FDT_CERTIFY_MAX_JOBS];
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
    keyset star, star_hull; /* those with an owned vertex (run.stars) */
    double need[3];      /* how far the balls reached, where too far */
    int again, err;
    long repeat_id;      /* the least point two of whose images are vertices of
                            a kept tet, or -1: the least over all of them, so
                            the error names the same point whatever the
                            threads' shares */
} prove_job;

typedef struct prove_pass {
    run *r;
    prove_job job[FDT_CERTIFY_MAX_JOBS];
} prove_pass;

/* A job's region for the margin m: (c0 - m', c1 + m') around the part's
 * core with m' a hair under the margin (or the period) for the roundings
 * of make_images' tests and of hi - lo, rounded inwards. */
static void prove_init(prove_job *j, run *r, const double m[3])
{
    memset(j, 0, sizeof *j);
    j->r = r;
    j->repeat_id = -1;
    for (int k = 0; k < 3; k++) {
        double L = r->b->hi[k] - r->b->lo[k];
        j->mm[k] = (m[k] < L ? m[k] : L) * (1 - 0x1p-40);
        j->A[k] = nextafter(r->core.lo[k] - j->mm[k], INFINITY);
        j->B[k] = nextafter(r->core.hi[k] + j->mm[k], -INFINITY);
    }
}

/* Part of x on the slabs' axis: the number of inner cuts at or below it. */
static uint32_t part_of(const fdt_periodic_parts *p, double x)
{
    uint32_t lo = 1, hi = p->nparts; /* the answer is in [lo - 1, hi - 1] */
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (p->cut[mid] <= x)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo - 1;
}

/* Whether the run's part owns input point i (its slab's). */
static int owns(const run *r, uint32_t i)
{
    const fdt_periodic_parts *p = r->parts;
    return !r->own || part_of(p, r->X[3 * (size_t)i + (size_t)p->axis]) == r->part;
}

/*
 * Whether this copy of a tet (or hull face) with an owned vertex is the one
 * the stars keep: the copy in which the least of its owned points (by id)
 * is the point itself, not an image. A periodic tet has copies in the
 * part's mesh around each of its owned points (the same key, make_key's),
 * and exactly one of them holds that point itself: the point's star is
 * whole in the mesh (the proofs) and holds the tet once.
 */
static int star_copy(const run *r, const uint32_t *w, int nv)
{
    uint32_t self = UINT32_MAX;
    for (int i = 0; i < nv; i++)
        if (w[i] < r->nown && r->e.src[w[i]] < self)
            self = r->e.src[w[i]];
    for (int i = 0; i < nv; i++)
        if (w[i] >= r->nown && r->e.src[w[i]] < self && owns(r, r->e.src[w[i]]))
            return 0;
    return 1;
}

/* Whether a tet of the mesh (positive, certified on the exact images), its
 * vertices w, is positive with them in its key's order (make_key's sort):
 * an even permutation. A star's tets then need no orientation test. */
static uint32_t key_positive(const ext *e, const uint32_t w[4])
{
    int inv = 0;
    for (int a = 0; a < 4; a++)
        for (int b = a + 1; b < 4; b++)
            inv += e->vk[w[a]] > e->vk[w[b]];
    return !(inv & 1);
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
    int touches = 0; /* an owned point (morton: they come first) */
    for (int i = 0; i < nv; i++)
        touches |= w[i] < r->nown;
    if (!touches)
        return;
    if (inf < 0) {
        double need[3];
        ball_reach(&r->e, w, cof, &r->core, r->ylo, r->yhi, need);
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
    long rep;
    uint32_t least = make_key(&r->e, w, nv, &k, &rep);
    /* the owned points' stars, for their cells: every tet and hull face
     * with an owned vertex, proved like the kept ones, once */
    if (r->stars && star_copy(r, w, nv) &&
        (j->err = keyset_add(inf < 0 ? &j->star : &j->star_hull, &k,
                             inf < 0 ? key_positive(&r->e, w) : 0)) != FDT_OK)
        return;
    if (least >= r->nown)
        return;
    if (rep >= 0 && (j->repeat_id < 0 || rep < j->repeat_id))
        j->repeat_id = rep;
    /* the least vertex's place among the owned points: its id when a
     * part owns them all (no load: that array's misses were an eighth of
     * this function's time on 1M points) */
    uint32_t rank = r->own ? r->e.rank[least] : k.w[0];
    j->err = keyset_add(inf < 0 ? &j->tets : &j->hull, &k, rank);
}

/*
 * The other points a round at margin m may need (make_images tests each
 * copy): those of every part whose slab lies within m of this part's core
 * on the slabs' axis, going up and down from it (wrapping round the
 * period), with a hair of room for the roundings of the slabs' bounds;
 * every other part's once the core is the whole box there.
 */
static int part_near(run *r, const double m[3])
{
    const fdt_periodic_parts *p = r->parts;
    r->nnear = 0;
    if (!p || p->nparts < 2)
        return FDT_OK;
    const int a = p->axis;
    const uint32_t K = p->nparts, j = r->part;
    const double L = r->b->hi[a] - r->b->lo[a];
    const int whole = r->core.lo[a] == r->b->lo[a] && r->core.hi[a] == r->b->hi[a];
    const double reach = m[a] * (1 + 0x1p-30) + 0x1p-50 * L;
    uint8_t *take = calloc(K, 1);
    if (!take)
        return FDT_ENOMEM;
    for (uint32_t d = 1; d < K; d++) { /* upwards: part j + d's lower side */
        uint32_t q = (j + d) % K;
        double low = j + d < K ? p->cut[j + d] : p->cut[j + d - K] + L;
        if (!whole && low - r->core.hi[a] > reach)
            break;
        take[q] = 1;
    }
    for (uint32_t d = 1; d < K; d++) { /* downwards: part j - d's upper side */
        uint32_t q = (j + K - d) % K;
        double up = d <= j ? p->cut[j - d + 1] : p->cut[q + 1] - L;
        if (!whole && r->core.lo[a] - up > reach)
            break;
        take[q] = 1;
    }
    take[j] = 0;
    size_t c = 0;
    for (uint32_t q = 0; q < K; q++)
        c += take[q] ? p->start[q + 1] - p->start[q] : 0;
    free(r->near);
    r->near = malloc((c ? c : 1) * sizeof *r->near);
    if (!r->near) {
        free(take);
        return FDT_ENOMEM;
    }
    for (uint32_t q = 0; q < K; q++)
        if (take[q])
            for (uint32_t i = p->start[q]; i < p->start[q + 1]; i++)
                r->near[r->nnear++] = p->idx[i];
    free(take);
    return FDT_OK;
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
        keyset_free(&r->star[i]);
        keyset_free(&r->star_hull[i]);
    }
    r->nsets = 0;
    if ((err = part_near(r, m)) != FDT_OK ||
        (err = make_images(&r->e, r->X, r->n, r->own, r->nown, r->near, r->nnear, b, r->core.lo,
                           r->core.hi, m)) != FDT_OK)
        return err;
    double blo[3], bhi[3];
    if ((err = morton(&r->e, r->nown, blo, bhi)) != FDT_OK)
        return err;
    out->images = r->e.n - r->nown;
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
    int T = nthreads < 1 ? 1 : nthreads;
    prove_pass *pp = malloc(sizeof *pp);
    if (!pp)
        return FDT_ENOMEM;
    pp->r = r;
    int nj = fdt_certify_jobs(&r->m, T); /* its ranges: a set each */
    /* each job's kept tets: at most its share of the finite tets, and a
     * tenth more. Its range of the certificate's order (space order) may
     * lie wholly in the core, where nearly every tet is kept: room for
     * only the owned points' share of them (0.84 on 1M uniform points)
     * made the core's ranges grow their sets by realloc, a copy and fresh
     * pages, a fifth of the proofs' time on two threads. Room never
     * written is never mapped. */
    const size_t keep = (size_t)((double)r->m.nfinite / nj * 1.1) + 1024;
    for (int i = 0; i < nj; i++) {
        prove_init(&pp->job[i], r, m);
        if (!err)
            err = keyset_reserve(&pp->job[i].tets, keep);
    }
    prove_job *jobs = pp->job;
    const fdt_certify_visit vis = {prove_tet, pp};
    fdt_certify_fail why;
    if (err || (err = fdt_certify_parallel_visit(&r->m, T, &vis, &out->pc, &why)) != FDT_OK) {
        if (err == FDT_ECHECK)
            fdt_certify_describe(&why, r->diag, r->dsz);
        for (int i = 0; i < nj; i++) {
            keyset_free(&jobs[i].tets);
            keyset_free(&jobs[i].hull);
            keyset_free(&jobs[i].star);
            keyset_free(&jobs[i].star_hull);
        }
        free(pp);
        return err;
    }
    int again = 0;
    long repeat_id = -1;
    for (int k = 0; k < 3; k++)
        r->need[k] = 0;
    for (int i = 0; i < nj; i++) {
        err = err ? err : jobs[i].err;
        again |= jobs[i].again;
        if (jobs[i].repeat_id >= 0 && (repeat_id < 0 || jobs[i].repeat_id < repeat_id))
            repeat_id = jobs[i].repeat_id;
        for (int k = 0; k < 3; k++)
            r->need[k] = jobs[i].need[k] > r->need[k] ? jobs[i].need[k] : r->need[k];
    }
    for (int i = 0; i < nj; i++) { /* the run frees them */
        r->tets[i] = jobs[i].tets;
        r->hull[i] = jobs[i].hull;
        r->star[i] = jobs[i].star;
        r->star_hull[i] = jobs[i].star_hull;
    }
    r->nsets = nj;
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

/* count keys of nv vertices each back into rows: ids, 3 offsets a vertex. */
static void unpack(const key *k, size_t count, int nv, uint32_t *ids, int8_t *off)
{
    for (size_t i = 0; i < count; i++)
        for (int j = 0; j < nv; j++)
            key_vertex(&k[i], j, &ids[(size_t)nv * i + (size_t)j],
                       off + 3 * ((size_t)nv * i + (size_t)j));
}

/* A thread's share of emit: the ranks [lo, hi), whose keys it counts
 * (pass 0), places in their buckets (1), and sorts and unpacks (2). Each
 * writes only its ranks' entries of start and its buckets' of tmp, ids
 * and offs; fdt_fork_join's joins order each pass before the next. */
typedef struct emit_job {
    const keyset *s;
    int ns, nv, pass;
    uint32_t lo, hi;
    size_t *start;
    key *tmp;
    uint32_t *ids;
    int8_t *offs;
} emit_job;

static void *emit_pass(void *arg)
{
    emit_job *j = arg;
    size_t *start = j->start;
    if (j->pass < 2) {
        /* the sets in order, each in its order: a bucket's keys come as
         * one thread's pass would place them */
        for (int i = 0; i < j->ns; i++)
            for (size_t k = 0; k < j->s[i].n; k++) {
                const uint32_t r = j->s[i].rank[k];
                if (r < j->lo || r >= j->hi)
                    continue;
                if (j->pass == 0)
                    start[r + 1]++;
                else
                    j->tmp[start[r]++] = j->s[i].keys[k];
            }
        return NULL;
    }
    for (size_t v = j->lo; v < j->hi; v++) {
        key *a = j->tmp + start[v];
        size_t c = start[v + 1] - start[v];
        if (c > 32) {
            qsort(a, c, sizeof *a, key_cmp);
            continue;
        }
        for (size_t i = 1; i < c; i++) {
            key x = a[i];
            size_t y = i;
            for (; y > 0 && key_cmp(&x, &a[y - 1]) < 0; y--)
                a[y] = a[y - 1];
            a[y] = x;
        }
    }
    const size_t b = start[j->lo];
    unpack(j->tmp + b, start[j->hi] - b, j->nv, j->ids + (size_t)j->nv * b,
           j->offs + 3 * (size_t)j->nv * b);
    return NULL;
}

/* The most threads emit takes: a range of ranks each. */
#define EMIT_MAX_THREADS 64

/*
 * The keys of the sets s[0 .. ns), sorted, into out's arrays; the sets
 * freed. Counted into buckets by their least vertex's place among the n
 * owned points (ascending ids, so the buckets' order is the ids'), each
 * bucket (the tets a point is the least vertex of: a few) sorted by
 * insertion, a large one by qsort (qsort of 6.8M keys took a fifth of a
 * 1M-point run); on up to nthreads threads, each a range of ranks (the
 * same rows for any count). The buckets go in scratch (scratch_bytes;
 * NULL: a new array) and the rows' ids in the first set's keys when they
 * fit: memory every page of which is already mapped (a fresh array's
 * first touch, a page fault every 4 KB, was half of what this took on 1M
 * points; bench/NOTES.md entry 123).
 */
static int emit(keyset *s, int ns, int nv, size_t n, int nthreads, void *scratch,
                size_t scratch_bytes, uint32_t **ids, int8_t **offs, size_t *count)
{
    size_t total = 0;
    for (int i = 0; i < ns; i++)
        total += s[i].n;
    const size_t id_bytes = (total ? total : 1) * (size_t)nv * sizeof **ids;
    size_t *start = calloc(n + 1, sizeof *start);
    key *tmp = scratch && total * sizeof *tmp <= scratch_bytes
                   ? scratch
                   : malloc((total ? total : 1) * sizeof *tmp);
    int T = nthreads < 1 || total < 4096 ? 1 : nthreads > EMIT_MAX_THREADS ? EMIT_MAX_THREADS
                                                                            : nthreads;
    emit_job job[EMIT_MAX_THREADS];
    if (!start || !tmp) {
        free(start);
        if (tmp != scratch)
            free(tmp);
        return FDT_ENOMEM;
    }
    for (int t = 0; t < T; t++)
        job[t] = (emit_job){s, ns, nv, 0, (uint32_t)(n * (size_t)t / (size_t)T),
                            (uint32_t)(n * (size_t)(t + 1) / (size_t)T), start, tmp, NULL, NULL};
    fdt_fork_join(job, sizeof *job, T, emit_pass);
    for (size_t v = 0; v < n; v++)
        start[v + 1] += start[v];
    for (int t = 0; t < T; t++)
        job[t].pass = 1;
    fdt_fork_join(job, sizeof *job, T, emit_pass);
    void *reuse = NULL;
    for (int i = 0; i < ns; i++) {
        if (!reuse && s[i].cap * sizeof *s[i].keys >= id_bytes) {
            reuse = s[i].keys;
            s[i].keys = NULL;
        }
        keyset_free(&s[i]);
    }
    for (size_t v = n; v > 0; v--) /* start[v] was the end of bucket v */
        start[v] = start[v - 1];
    start[0] = 0;
    if (reuse) { /* shrunk where it is */
        void *shrunk = realloc(reuse, id_bytes);
        *ids = shrunk ? shrunk : reuse;
    } else {
        *ids = malloc(id_bytes);
        fdt_mem_advise_huge(*ids, id_bytes);
    }
    *offs = malloc((total ? total : 1) * (size_t)nv * 3);
    fdt_mem_advise_huge(*offs, total * (size_t)nv * 3);
    int err = *ids && *offs ? FDT_OK : FDT_ENOMEM;
    if (!err) {
        /* Pass 2's ranges hold about total / T keys each: a tet's bucket
         * is its least vertex's, and the least of four ids is a low one
         * (a fifteenth of 1M uniform points' tets had it in the upper
         * half of the ids), so equal ranges of ranks left one thread
         * nearly all the sorting and writing. The rows are the same for
         * any split. */
        for (int t = 1; t < T; t++) {
            size_t want = total * (size_t)t / (size_t)T, lo = job[t - 1].lo, hi = n;
            while (lo < hi) { /* the first rank whose bucket starts at or past want */
                size_t mid = lo + (hi - lo) / 2;
                if (start[mid] < want)
                    lo = mid + 1;
                else
                    hi = mid;
            }
            job[t - 1].hi = job[t].lo = (uint32_t)lo;
        }
        job[T - 1].hi = (uint32_t)n;
        for (int t = 0; t < T; t++) {
            job[t].pass = 2;
            job[t].ids = *ids;
            job[t].offs = *offs;
        }
        fdt_fork_join(job, sizeof *job, T, emit_pass);
    }
    free(start);
    if (tmp != scratch)
        free(tmp);
    *count = total;
    return err;
}

/* The keys of the sets s[0 .. ns) into rows, in no order (the stars),
 * and with pos each one's rank (key_positive's), each set freed once its
 * keys are moved. */
static int gather(keyset *s, int ns, int nv, uint32_t **ids, int8_t **offs, uint8_t **pos,
                  size_t *count)
{
    size_t total = 0;
    for (int i = 0; i < ns; i++)
        total += s[i].n;
    *ids = malloc((total ? total : 1) * (size_t)nv * sizeof **ids);
    *offs = malloc((total ? total : 1) * (size_t)nv * 3);
    if (pos)
        *pos = malloc(total ? total : 1);
    if (!*ids || !*offs || (pos && !*pos))
        return FDT_ENOMEM;
    size_t at = 0;
    for (int i = 0; i < ns; i++) {
        unpack(s[i].keys, s[i].n, nv, *ids + (size_t)nv * at, *offs + 3 * (size_t)nv * at);
        for (size_t k = 0; pos && k < s[i].n; k++)
            (*pos)[at + k] = (uint8_t)s[i].rank[k];
        at += s[i].n;
        keyset_free(&s[i]);
    }
    *count = total;
    return FDT_OK;
}

int fdt_periodic_sort_rows(uint32_t **ids, int8_t **off, size_t count, int nv, size_t n)
{
    /* emit's buckets, each row's least id its bucket */
    keyset s = {malloc((count ? count : 1) * sizeof(key)),
                malloc((count ? count : 1) * sizeof(uint32_t)), count, count};
    if (!s.keys || !s.rank) {
        keyset_free(&s);
        return FDT_ENOMEM;
    }
    for (size_t i = 0; i < count; i++) {
        uint64_t a[4];
        int ok = 1;
        for (int j = 0; j < 4; j++) {
            const int8_t *o = *off + 3 * ((size_t)nv * i + (size_t)j);
            a[j] = j < nv ? vpack((*ids)[(size_t)nv * i + (size_t)j], o) : UINT64_MAX;
            for (int d = 0; j < nv && d < 3; d++) /* canonical: key_pack's range */
                ok &= j ? o[d] >= -2 && o[d] <= 2 : o[d] == 0;
        }
        key_pack(a, &s.keys[i]);
        s.rank[i] = (*ids)[(size_t)nv * i];
        if (s.rank[i] >= n || !ok) {
            keyset_free(&s);
            return FDT_EINVAL;
        }
    }
    uint32_t *ni = NULL;
    int8_t *no = NULL;
    size_t got;
    int err = emit(&s, 1, nv, n, 1, NULL, 0, &ni, &no, &got);
    if (err) {
        keyset_free(&s);
        free(ni);
        free(no);
        return err;
    }
    free(*ids);
    free(*off);
    *ids = ni;
    *off = no;
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
    /* n increasing ids from 0 that end at n - 1 are 0 .. n - 1: no
     * duplicate was merged, and the rows are in input ids already (a
     * pass of random reads over every tet's vertices less) */
    if (n == 0 || (orig[0] == 0 && (size_t)orig[n - 1] == n - 1))
        return FDT_OK;
    for (size_t i = 0; i < 4 * m->ntets; i++)
        m->tets[i] = (uint32_t)orig[m->tets[i]];
    for (size_t i = 0; i < 3 * m->nhull; i++)
        m->hull[i] = (uint32_t)orig[m->hull[i]];
    return FDT_OK;
}

/* The caller's diagnostic buffer, or own when it gave none; emptied. */
static void diag_init(char **diag, size_t *ds, char *own, size_t osz)
{
    if (!*diag || !*ds) {
        *diag = own;
        *ds = osz;
    }
    (*diag)[0] = 0;
}

/* The points' extent (every axis; the proofs read the axes that are not
 * periodic). */
static void extent(const double *X, uint32_t n, double lo[3], double hi[3])
{
    for (int k = 0; k < 3; k++)
        lo[k] = hi[k] = n ? X[k] : 0;
    for (uint32_t i = 1; i < n; i++)
        for (int k = 0; k < 3; k++) {
            double v = X[3 * (size_t)i + k];
            lo[k] = v < lo[k] ? v : lo[k];
            hi[k] = v > hi[k] ? v : hi[k];
        }
}

int fdt_periodic_parts_make(const double *X, uint32_t n, const fdt_periodic_box *b,
                            uint32_t part_points, fdt_periodic_parts *p)
{
    memset(p, 0, sizeof *p);
    p->axis = -1;
    p->nparts = 1;
    extent(X, n, p->ylo, p->yhi);
    uint64_t want = part_points ? ((uint64_t)n + part_points - 1) / part_points : 1;
    int a = -1;
    for (int k = 0; k < 3; k++)
        if (b->axes >> k & 1 && (a < 0 || b->hi[k] - b->lo[k] > b->hi[a] - b->lo[a]))
            a = k;
    enum { NB = 1 << 16 };
    if (want > NB / 4)
        want = NB / 4;
    p->cut = malloc((size_t)(want + 1) * sizeof *p->cut);
    if (!p->cut)
        return FDT_ENOMEM;
    p->cut[0] = a >= 0 ? b->lo[a] : 0;
    if (want > 1 && a >= 0) {
        /* the cuts at bins' edges where the running count passes t n / K:
         * about n / K points a slab, by a histogram rather than a sort */
        const double lo = b->lo[a], hi = b->hi[a], L = hi - lo;
        uint32_t *bin = calloc(NB, sizeof *bin);
        if (!bin)
            return FDT_ENOMEM;
        for (uint32_t i = 0; i < n; i++) {
            double t = (X[3 * (size_t)i + a] - lo) / L * NB;
            bin[t < 0 ? 0 : t >= NB ? NB - 1 : (uint32_t)t]++;
        }
        uint64_t seen = 0;
        uint32_t K = 1;
        for (uint32_t q = 0; q + 1 < NB && K < want; q++) {
            seen += bin[q];
            if (seen * want < (uint64_t)K * n)
                continue;
            double c = lo + L * (double)(q + 1) / NB;
            if (c > p->cut[K - 1] && c < hi) /* one cut a bin at most */
                p->cut[K++] = c;
        }
        free(bin);
        p->nparts = K;
    }
    if (p->nparts > 1) {
        p->axis = a;
        p->cut[p->nparts] = b->hi[a];
        p->start = calloc((size_t)p->nparts + 1, sizeof *p->start);
        p->idx = malloc((n ? n : 1) * sizeof *p->idx);
        if (!p->start || !p->idx) {
            fdt_periodic_parts_free(p);
            return FDT_ENOMEM;
        }
        for (uint32_t i = 0; i < n; i++)
            p->start[part_of(p, X[3 * (size_t)i + a]) + 1]++;
        for (uint32_t q = 0; q < p->nparts; q++)
            p->start[q + 1] += p->start[q];
        uint32_t *fill = malloc((size_t)p->nparts * sizeof *fill);
        if (!fill) {
            fdt_periodic_parts_free(p);
            return FDT_ENOMEM;
        }
        memcpy(fill, p->start, (size_t)p->nparts * sizeof *fill);
        for (uint32_t i = 0; i < n; i++) /* ascending within each part */
            p->idx[fill[part_of(p, X[3 * (size_t)i + a])]++] = i;
        free(fill);
    }
    return FDT_OK;
}

void fdt_periodic_parts_free(fdt_periodic_parts *p)
{
    free(p->cut);
    free(p->start);
    free(p->idx);
    memset(p, 0, sizeof *p);
}

uint32_t fdt_periodic_part_points(const fdt_periodic_parts *p, uint32_t k, uint32_t n)
{
    return p->nparts < 2 ? n : p->start[k + 1] - p->start[k];
}

int fdt_periodic_build_part(const double *X, uint32_t n, const int32_t *names,
                            const fdt_periodic_box *b, const fdt_periodic_parts *parts,
                            uint32_t part, int nthreads, int stars, fdt_periodic_mesh *out,
                            char *diag, size_t diag_size)
{
    memset(out, 0, sizeof *out);
    char owndiag[8];
    diag_init(&diag, &diag_size, owndiag, sizeof owndiag);
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
    r.parts = parts;
    r.part = part;
    r.stars = stars;
    r.core = *b;
    r.nown = n;
    int a = parts->nparts > 1 ? parts->axis : -1;
    if (a >= 0) {
        r.core.lo[a] = parts->cut[part];
        r.core.hi[a] = parts->cut[part + 1];
        r.own = parts->idx + parts->start[part];
        r.nown = parts->start[part + 1] - parts->start[part];
        if (!r.nown)
            return FDT_OK; /* an empty slab owns no tet */
    }
    memcpy(r.ylo, parts->ylo, sizeof r.ylo);
    memcpy(r.yhi, parts->yhi, sizeof r.yhi);
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
    int err;
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
        /* A slab whose balls reach half a period away: its core becomes the
         * whole box on that axis (the region, and so the proofs, of the
         * one-part build; its own points still the slab's), so that a part
         * fails only where the whole box would. */
        if (a >= 0 && r.core.hi[a] - r.core.lo[a] < b->hi[a] - b->lo[a] &&
            m[a] >= 0.5 * (b->hi[a] - b->lo[a])) {
            r.core.lo[a] = b->lo[a];
            r.core.hi[a] = b->hi[a];
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
    /* the mesh and the images go before the output is made; the mesh's
     * slots, every page of them written, are emit's scratch */
    void *scratch = r.m.T;
    const size_t scratch_bytes = (size_t)r.m.nslots * 8 * sizeof *r.m.T;
    r.m.T = NULL;
    fdt_ins_free(&r.m);
    ext_free(&r.e);
    free(r.near);
    if (err == FDT_OK &&
        ((err = emit(r.tets, r.nsets, 4, r.nown, nthreads, scratch, scratch_bytes, &out->tets,
                     &out->tet_off, &out->ntets)) ||
         (err = emit(r.hull, r.nsets, 3, r.nown, nthreads, scratch, scratch_bytes, &out->hull,
                     &out->hull_off, &out->nhull)) ||
         (stars && ((err = gather(r.star, r.nsets, 4, &out->star_tets, &out->star_off,
                                  &out->star_pos, &out->nstar)) ||
                    (err = gather(r.star_hull, r.nsets, 3, &out->star_hull,
                                  &out->star_hull_off, NULL, &out->nstar_hull))))))
        snprintf(diag, diag_size, "out of memory");
    free(scratch);
    for (int i = 0; i < r.nsets; i++) {
        keyset_free(&r.tets[i]);
        keyset_free(&r.hull[i]);
        keyset_free(&r.star[i]);
        keyset_free(&r.star_hull[i]);
    }
    if (err) {
        fdt_pred_counts pc = out->pc;
        fdt_periodic_free(out);
        out->pc = pc;
    }
    return err;
}

int fdt_periodic_build(const double *X, uint32_t n, const int32_t *names,
                       const fdt_periodic_box *b, int nthreads, fdt_periodic_mesh *out,
                       char *diag, size_t diag_size)
{
    memset(out, 0, sizeof *out);
    char own[8];
    diag_init(&diag, &diag_size, own, sizeof own);
    int err = fdt_periodic_check(X, n, b, diag, diag_size);
    if (err)
        return err;
    fdt_periodic_parts p;
    if ((err = fdt_periodic_parts_make(X, n, b, 0, &p)) != FDT_OK) {
        snprintf(diag, diag_size, "out of memory");
        return err;
    }
    err = fdt_periodic_build_part(X, n, names, b, &p, 0, nthreads, 0, out, diag, diag_size);
    fdt_periodic_parts_free(&p);
    return err;
}

void fdt_periodic_free(fdt_periodic_mesh *m)
{
    free(m->tets);
    free(m->tet_off);
    free(m->hull);
    free(m->hull_off);
    free(m->star_tets);
    free(m->star_off);
    free(m->star_pos);
    free(m->star_hull);
    free(m->star_hull_off);
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

/* Up to five vertices (input id, offsets) as rounded images with their
 * exact flags, for images.h's exact predicates on them (im points into
 * the struct: use it in place). */
typedef struct few {
    double P[15];
    uint32_t id[5];
    int8_t off[15];
    uint8_t exact[5];
    fdt_images im;
} few;

static void few_init(few *f, int k, const uint32_t *id, const int8_t *off, const double *X,
                     const fdt_periodic_box *b)
{
    double err = 0, e, lo[3], hi[3];
    for (int j = 0; j < k; j++) {
        f->id[j] = id[j];
        memcpy(f->off + 3 * j, off + 3 * j, 3);
        f->exact[j] = (uint8_t)fdt_images_round(X + 3 * (size_t)id[j], off + 3 * j, b->lo, b->hi,
                                                f->P + 3 * j, &e);
        err = e > err ? e : err;
    }
    for (int c = 0; c < 3; c++) {
        lo[c] = hi[c] = f->P[c];
        for (int j = 1; j < k; j++) {
            lo[c] = f->P[3 * j + c] < lo[c] ? f->P[3 * j + c] : lo[c];
            hi[c] = f->P[3 * j + c] > hi[c] ? f->P[3 * j + c] : hi[c];
        }
    }
    memset(&f->im, 0, sizeof f->im);
    f->im.P = f->P;
    f->im.n = (uint32_t)k;
    f->im.X = X;
    f->im.src = f->id;
    f->im.off = f->off;
    f->im.exact = f->exact;
    memcpy(f->im.lo, b->lo, sizeof f->im.lo);
    memcpy(f->im.hi, b->hi, sizeof f->im.hi);
    fdt_images_init(&f->im, lo, hi, err);
}

/* The exact orient3d (k 4: CGAL's sign, as fdt_orient3d) or perturbed
 * insphere (k 5) of k vertices (id, offsets) for their exact images: the
 * input points' own predicates when no vertex is an image, else the
 * rounded images' filters and images.h's exact stages. */
static int exact_sign(const double *X, const fdt_periodic_box *b, int k, const uint32_t *id,
                    const int8_t *o)
{
    int moved = 0;
    for (int j = 0; j < 3 * k; j++)
        moved |= o[j];
    if (!moved) {
        const double *p[5];
        for (int j = 0; j < k; j++)
            p[j] = X + 3 * (size_t)id[j];
        return k == 4 ? fdt_orient3d(p[0], p[1], p[2], p[3], NULL)
                      : fdt_insphere_perturbed(p[0], p[1], p[2], p[3], p[4], NULL);
    }
    few f;
    few_init(&f, k, id, o, X, b);
    const double *P = f.P;
    return k == 4 ? fdt_images_orient(&f.im, P, P + 3, P + 6, P + 9, NULL)
                  : fdt_images_insphere(&f.im, P, P + 3, P + 6, P + 9, P + 12, NULL);
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
    free(u->off);
    free(u->tets);
    free(u->hull);
    memset(u, 0, sizeof *u);
}

/*
 * Face k of laid-out tet t as the periodic mesh names it, wherever this
 * copy lies, in three words: its input ids ascending (fk[0] the first
 * two, fk[1] the third and the top of the rest), the offsets of the
 * second and third point from the first's (6 bytes: the low half of
 * fk[1], then fk[2]'s top 16 bits), and 4 t + k (fk[2]'s low 32 bits:
 * 4 ntets < 2^32, checked). Sorting the keys brings a face's two tets
 * together.
 */
static void unfolded_face_key(const fdt_periodic_unfolded *u, uint64_t r, uint64_t fk[3])
{
    const fdt_vid *t = u->tets + 4 * (size_t)(r >> 2);
    const int *f = fdt_tet_face[r & 3]; /* out of the tet: any order would do */
    fdt_vid v[3] = {t[f[0]], t[f[1]], t[f[2]]};
    for (int i = 1; i < 3; i++) /* by input id */
        for (int j = i; j > 0 && u->src[v[j]] < u->src[v[j - 1]]; j--) {
            fdt_vid x = v[j];
            v[j] = v[j - 1];
            v[j - 1] = x;
        }
    uint64_t rel = 0;
    for (int i = 1; i < 3; i++)
        for (int c = 0; c < 3; c++)
            rel = rel << 8 | (uint8_t)(u->off[3 * (size_t)v[i] + (size_t)c] -
                                       u->off[3 * (size_t)v[0] + (size_t)c]);
    fk[0] = (uint64_t)(uint32_t)u->src[v[0]] << 32 | (uint32_t)u->src[v[1]];
    fk[1] = (uint64_t)(uint32_t)u->src[v[2]] << 32 | rel >> 16;
    fk[2] = (rel & 0xffff) << 48 | r;
}

static int key3_cmp(const void *x, const void *y)
{
    const uint64_t *a = x, *b = y;
    for (int i = 0; i < 3; i++)
        if (a[i] != b[i])
            return a[i] < b[i] ? -1 : 1;
    return 0;
}

int fdt_periodic_unfolded_neighbors(const fdt_periodic_unfolded *u, fdt_tid **nbrs)
{
    *nbrs = NULL;
    size_t R = 4 * u->ntets, N = u->n;
    if (R >= (UINT64_C(1) << 32))
        return FDT_ETOOBIG;
    uint64_t *fk = malloc((R ? R : 1) * 3 * sizeof *fk);
    size_t *start = calloc(N + 2, sizeof *start);
    fdt_tid *nb = malloc((R ? R : 1) * sizeof *nb);
    int err = FDT_OK;
    if (!fk || !start || !nb) {
        err = FDT_ENOMEM;
        goto done;
    }
    /* the keys by their lowest input id (a counting sort), then each
     * bucket sorted */
    for (uint64_t r = 0; r < R; r++) {
        const fdt_vid *t = u->tets + 4 * (size_t)(r >> 2);
        fdt_vid lo = INT32_MAX;
        for (int i = 0; i < 3; i++) {
            fdt_vid s = u->src[t[fdt_tet_face[r & 3][i]]];
            lo = s < lo ? s : lo;
        }
        start[(size_t)lo + 1]++;
    }
    for (size_t i = 0; i < N; i++)
        start[i + 1] += start[i];
    for (uint64_t r = 0; r < R; r++) {
        uint64_t k[3];
        unfolded_face_key(u, r, k);
        memcpy(fk + 3 * start[k[0] >> 32]++, k, sizeof k);
    }
    for (size_t i = N; i > 0; i--) /* start[i] was the end of bucket i */
        start[i] = start[i - 1];
    start[0] = 0;
    for (size_t i = 0; i < N; i++)
        qsort(fk + 3 * start[i], start[i + 1] - start[i], 3 * sizeof *fk, key3_cmp);
    for (size_t i = 0; i < R;) {
        const uint64_t *a = fk + 3 * i;
        size_t j = i + 1;
        while (j < R && fk[3 * j] == a[0] && fk[3 * j + 1] == a[1] &&
               fk[3 * j + 2] >> 48 == a[2] >> 48)
            j++;
        uint32_t ra = (uint32_t)a[2];
        if (j - i == 1) {
            nb[ra] = -1;
        } else if (j - i == 2) {
            uint32_t rb = (uint32_t)a[5];
            nb[ra] = (fdt_tid)(rb >> 2);
            nb[rb] = (fdt_tid)(ra >> 2);
        } else {
            err = FDT_EINTERNAL;
            goto done;
        }
        i = j;
    }
    *nbrs = nb;
    nb = NULL;
done:
    free(fk);
    free(start);
    free(nb);
    return err;
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
        if (exact_sign(X, b, 4, id, o) < 0) {
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
        if (exact_sign(X, b, 4, q, qo) > 0) {
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
        if (!(u->src = malloc((m.n ? m.n : 1) * sizeof *u->src)) ||
            !(u->off = malloc((m.n ? m.n : 1) * 3)))
            err = FDT_ENOMEM;
        for (size_t i = 0; !err && i < m.n; i++) {
            u->src[i] = (fdt_vid)m.label[i];
            for (int a = 0; a < 3; a++) /* vpack's bytes, 128 up */
                u->off[3 * i + (size_t)a] = (int8_t)((int)(m.vk[i] >> (16 - 8 * a) & 0xff) - 128);
        }
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

/* ---- a patch: the laid-out tets and their translates around the box ---- */

void fdt_periodic_patch_free(fdt_periodic_patch *p)
{
    free(p->xyz);
    free(p->src);
    free(p->tets);
    free(p->nbrs);
    free(p->row);
    memset(p, 0, sizeof *p);
}

/* The translates of one laid-out tet in a patch: k[d] from kmin[d], kn[d]
 * of them along axis d (1 on an axis that is not periodic), the first of
 * them the patch's tet base. */
typedef struct pcopies {
    size_t base;
    int8_t kmin[3];
    uint8_t kn[3];
} pcopies;

/* The patch's tet of c's translate k, or FDT_NB_CUT when k is not one of
 * them. */
static fdt_tid patch_tet(const pcopies *c, const int k[3])
{
    size_t at = 0;
    for (int d = 0; d < 3; d++) {
        int i = k[d] - c->kmin[d];
        if (i < 0 || i >= c->kn[d])
            return FDT_NB_CUT;
        at = at * c->kn[d] + (size_t)i;
    }
    return (fdt_tid)(c->base + at);
}

/* The i-th translate of c (in patch_tet's order). */
static void patch_k(const pcopies *c, size_t i, int k[3])
{
    for (int d = 2; d >= 0; d--) {
        k[d] = c->kmin[d] + (int)(i % c->kn[d]);
        i /= c->kn[d];
    }
}

static int u64_lower(const uint64_t *a, size_t n, uint64_t x)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (a[mid] < x)
            lo = mid + 1;
        else
            hi = mid;
    }
    return (int)lo;
}

int fdt_periodic_patch_make(const fdt_periodic_unfolded *u, const fdt_tid *unb, const double *X,
                            const fdt_periodic_box *b, const double margin[3],
                            fdt_periodic_patch *p)
{
    memset(p, 0, sizeof *p);
    vmap m;
    memset(&m, 0, sizeof m);
    uint64_t *keys = NULL;
    uint32_t *rank = NULL;
    pcopies *cp = malloc((u->ntets + 1) * sizeof *cp);
    int err = cp ? FDT_OK : FDT_ENOMEM;
    /* which translates of each tet: those whose box meets the box grown by
     * the margin (rounding may add one more: harmless) */
    size_t total = 0;
    for (size_t t = 0; t < u->ntets && !err; t++) {
        size_t cnt = 1;
        for (int d = 0; d < 3; d++) {
            const double L = fdt_periodic_period(b, d);
            cp[t].kmin[d] = 0;
            cp[t].kn[d] = 1;
            if (L == 0)
                continue;
            double lo, hi;
            fdt_periodic_unfolded_span(u, t, d, &lo, &hi);
            const double a = ceil((b->lo[d] - margin[d] - hi) / L),
                         z = floor((b->hi[d] + margin[d] - lo) / L);
            if (!(a >= -64 && z <= 64)) {
                err = FDT_ETOOBIG;
                break;
            }
            cp[t].kmin[d] = (int8_t)a;
            cp[t].kn[d] = (uint8_t)(z >= a ? z - a + 1 : 0);
            cnt *= cp[t].kn[d];
        }
        cp[t].base = total;
        total += cnt;
    }
    if (!err && total > (size_t)INT32_MAX)
        err = FDT_ETOOBIG;
    if (!err && (!(p->tets = malloc((4 * total + 1) * sizeof *p->tets)) ||
                 !(p->nbrs = malloc((4 * total + 1) * sizeof *p->nbrs)) ||
                 !(p->row = malloc((total + 1) * sizeof *p->row))))
        err = FDT_ENOMEM;
    /* the translates' points (each image once: u's points first, so that
     * the untranslated copies, most of the patch, take theirs as they
     * are) and neighbours */
    for (size_t i = 0; i < u->n && !err; i++)
        if (vmap_get(&m, (uint32_t)u->src[i], u->off + 3 * i, X, b) < 0)
            err = FDT_ENOMEM;
    for (size_t t = 0; t < u->ntets && !err; t++) {
        const fdt_vid *tv = u->tets + 4 * t;
        const size_t cnt = (size_t)cp[t].kn[0] * cp[t].kn[1] * cp[t].kn[2];
        for (size_t i = 0; i < cnt && !err; i++) {
            int k[3];
            patch_k(&cp[t], i, k);
            const size_t pt = cp[t].base + i;
            p->row[pt] = (uint32_t)t;
            for (int v = 0; v < 4 && !err; v++) {
                if (!k[0] && !k[1] && !k[2]) {
                    p->tets[4 * pt + (size_t)v] = tv[v];
                    continue;
                }
                int8_t o[3];
                for (int d = 0; d < 3; d++)
                    o[d] = (int8_t)(u->off[3 * (size_t)tv[v] + (size_t)d] + k[d]);
                long x = vmap_get(&m, (uint32_t)u->src[tv[v]], o, X, b);
                if (x < 0)
                    err = FDT_ENOMEM;
                p->tets[4 * pt + (size_t)v] = (fdt_vid)x;
            }
            for (int f = 0; f < 4; f++) {
                const fdt_tid nt = unb[4 * t + (size_t)f];
                if (nt < 0) {
                    p->nbrs[4 * pt + (size_t)f] = -1;
                    continue;
                }
                /* the frames of t and nt differ by what the offsets of one
                 * point of the face differ by (the faces of a 1-sheet
                 * mesh's tets name distinct points) */
                const fdt_vid a = tv[f == 0];
                int kn[3] = {k[0], k[1], k[2]};
                for (int j = 0; j < 4; j++) {
                    const fdt_vid c = u->tets[4 * (size_t)nt + (size_t)j];
                    if (u->src[c] != u->src[a])
                        continue;
                    for (int d = 0; d < 3; d++)
                        kn[d] += u->off[3 * (size_t)a + (size_t)d] -
                                 u->off[3 * (size_t)c + (size_t)d];
                }
                p->nbrs[4 * pt + (size_t)f] = patch_tet(&cp[nt], kn);
            }
        }
    }
    if (!err && m.n > (size_t)INT32_MAX)
        err = FDT_ETOOBIG;
    /* the points numbered in the order of their (id, offsets) */
    if (!err && (!(keys = malloc((m.n + 1) * sizeof *keys)) ||
                 !(rank = malloc((m.n + 1) * sizeof *rank)) ||
                 !(p->xyz = malloc((3 * m.n + 1) * sizeof *p->xyz)) ||
                 !(p->src = malloc((m.n + 1) * sizeof *p->src))))
        err = FDT_ENOMEM;
    if (!err) {
        memcpy(keys, m.vk, m.n * sizeof *keys);
        fdt_sort_u64(keys, m.n);
        for (size_t i = 0; i < m.n; i++) {
            const int r = u64_lower(keys, m.n, m.vk[i]);
            rank[i] = (uint32_t)r;
            memcpy(p->xyz + 3 * (size_t)r, m.xyz + 3 * i, 3 * sizeof *p->xyz);
            p->src[r] = (fdt_vid)m.label[i];
        }
        for (size_t i = 0; i < 4 * total; i++)
            p->tets[i] = (fdt_vid)rank[p->tets[i]];
        p->n = m.n;
        p->ntets = total;
    }
    if (err)
        fdt_periodic_patch_free(p);
    vmap_free(&m);
    free(keys);
    free(rank);
    free(cp);
    return err;
}

/* ---- the independent check of a periodic mesh --------------------------- */


static int chk_fail(char *msg, size_t len, const char *fmt, ...)
{
    if (msg && len) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg, len, fmt, ap);
        va_end(ap);
    }
    return FDT_ECHECK;
}

/* A row's k vertices (ids distinct) sorted by id, offsets with them. */
static void chk_sort(int k, const int32_t *ids, const int8_t *off, uint32_t *id, int8_t *o)
{
    for (int j = 0; j < k; j++) {
        int m = j;
        uint32_t x = (uint32_t)ids[j];
        for (; m > 0 && id[m - 1] > x; m--) {
            id[m] = id[m - 1];
            memcpy(o + 3 * m, o + 3 * (m - 1), 3);
        }
        id[m] = x;
        memcpy(o + 3 * m, off + 3 * j, 3);
    }
}

/* The hull edges of the check: key, then up to two hull faces, each with
 * its third vertex (id, offsets relative to the key's first). */
typedef struct cslot {
    uint64_t k[3];
    uint32_t who[2], apex[2];
    int8_t aoff[2][3];
    uint8_t cnt;
} cslot;

typedef struct ctab {
    cslot *s;
    size_t mask;
} ctab;

static int ctab_init(ctab *t, size_t n)
{
    size_t size = 16;
    while (size < 2 * n)
        size *= 2;
    t->mask = size - 1;
    t->s = calloc(size, sizeof *t->s);
    return t->s ? FDT_OK : FDT_ENOMEM;
}

/* The slot of key k, claimed when new. */
static cslot *ctab_get(ctab *t, const uint64_t k[3])
{
    size_t h = face_hash(k, t->mask);
    while (t->s[h].cnt && memcmp(t->s[h].k, k, sizeof t->s[h].k))
        h = (h + 1) & t->mask;
    if (!t->s[h].cnt)
        memcpy(t->s[h].k, k, sizeof t->s[h].k);
    return &t->s[h];
}

/* A face of a tet or of the hull, filed under its least vertex: the other
 * two ids ascending, their offsets relative to the least (3 bits a
 * component, plus 2: a face's vertices are at most two periods apart; bits
 * 0-17 of offs), who holds it (tet << 2 | the vertex it leaves out, or the
 * hull face) and, for a tet, that vertex (apex, its offsets in bits 18-26). */
typedef struct finc {
    uint32_t id1, id2, offs, who, apex;
} finc;

#define FINC_KEY 0x3ffffu /* the face's own bits of offs */

static int finc_cmp(const finc *a, const finc *b)
{
    if (a->id1 != b->id1)
        return a->id1 < b->id1 ? -1 : 1;
    if (a->id2 != b->id2)
        return a->id2 < b->id2 ? -1 : 1;
    uint32_t x = a->offs & FINC_KEY, y = b->offs & FINC_KEY;
    return x < y ? -1 : x > y;
}

/* Row k (nv vertices, ids distinct after the range check) sorted by id;
 * face j's incidence (the vertex j left out; j = 3 for a hull row) and its
 * least vertex. 0 when two vertices are more than two periods apart. */
static int finc_make(const uint32_t *id, const int8_t *o, int nv, int j, uint32_t who,
                     finc *f, uint32_t *least)
{
    uint32_t fid[3];
    const int8_t *fo[3];
    for (int i = 0, c = 0; i < nv; i++)
        if (i != j || nv == 3) {
            fid[c] = id[i];
            fo[c++] = o + 3 * i;
        }
    *least = fid[0];
    f->id1 = fid[1];
    f->id2 = fid[2];
    f->offs = 0;
    for (int c = 1; c < 4; c++) /* c = 3: the apex */
        for (int a = 0; a < 3 && (c < 3 || nv == 4); a++) {
            int r = (c < 3 ? fo[c][a] : o[3 * j + a]) - fo[0][a] + 2;
            if (r < 0 || r > 4)
                return 0;
            f->offs |= (uint32_t)r << (3 * (3 * (c - 1) + a));
        }
    f->who = who;
    f->apex = nv == 4 ? id[j] : UINT32_MAX;
    return 1;
}

/* The face's vertices (least, then f's two, then its tet's apex) with
 * their offsets in the face's frame. */
static void finc_face(uint32_t least, const finc *f, uint32_t id[4], int8_t o[12])
{
    id[0] = least;
    id[1] = f->id1;
    id[2] = f->id2;
    id[3] = f->apex;
    memset(o, 0, 3);
    for (int c = 1; c < 4; c++)
        for (int a = 0; a < 3; a++)
            o[3 * c + a] = (int8_t)((int)(f->offs >> (3 * (3 * (c - 1) + a)) & 7) - 2);
}

/* The sorted vertices of tet t (or hull face h, nv 3); nonzero when an id
 * is out of range or repeated (msg written). */
static int chk_row(const int32_t *rows, const int8_t *offs, size_t r, int nv, size_t n,
                   uint32_t *id, int8_t *o, char *msg, size_t len)
{
    const char *what = nv == 4 ? "tet" : "hull face";
    for (int j = 0; j < nv; j++)
        if (rows[(size_t)nv * r + (size_t)j] < 0 || (size_t)rows[(size_t)nv * r + (size_t)j] >= n)
            return chk_fail(msg, len, "%s %zu names point %ld, not one of the %zu", what, r,
                            (long)rows[(size_t)nv * r + (size_t)j], n);
    chk_sort(nv, rows + (size_t)nv * r, offs + 3 * (size_t)nv * r, id, o);
    for (int j = 1; j < nv; j++)
        if (id[j] == id[j - 1])
            return chk_fail(msg, len, "%s %zu joins two images of point %u", what, r, id[j]);
    return FDT_OK;
}

int fdt_periodic_check_mesh(const double *X, size_t n, const int32_t *tets, const int8_t *off,
                            size_t ntets, const int32_t *hull, const int8_t *hoff, size_t nhull,
                            const fdt_periodic_box *b, char *msg, size_t len)
{
    if (msg && len)
        msg[0] = 0;
    if (ntets > (SIZE_MAX >> 3) / sizeof(finc) || n > UINT32_MAX || ntets > UINT32_MAX / 4)
        return FDT_ENOMEM;
    ctab et = {0};
    uint8_t *used = calloc(n ? n : 1, 1);
    size_t *start = calloc(n + 2, sizeof *start), *hstart = calloc(n + 2, sizeof *hstart);
    finc *inc = malloc((4 * ntets + 1) * sizeof *inc), *hinc = malloc((nhull + 1) * sizeof *hinc);
    uint32_t *hapex = malloc((nhull + 1) * sizeof *hapex); /* a hull face's tet's other vertex */
    int8_t *haoff = malloc(3 * nhull + 3);                   /* its offsets in the face's frame */
    int err = !used || !start || !hstart || !inc || !hinc || !hapex || !haoff ||
                      ctab_init(&et, 3 * nhull)
                  ? FDT_ENOMEM : FDT_OK;
    /* The volumes below in units of a power of two an axis near its
     * extent (the period, or the points' extent across an axis that is
     * not periodic): exact, and a box of 1e150 (gen_points mixed) neither
     * overflows (the volumes inf and nan: a sound mesh reported broken)
     * nor, at 1e-150, underflows to a sum of zeros that any tets match. */
    double sc[3], lo[3], hi[3];
    extent(X, (uint32_t)n, lo, hi);
    for (int a = 0; a < 3; a++) {
        double side = b->axes >> a & 1 ? b->hi[a] - b->lo[a] : hi[a] - lo[a];
        int e = 0;
        if (side > 0 && isfinite(side))
            (void)frexp(side, &e);
        sc[a] = ldexp(1, -e);
    }
    double vol = 0;
    /* every tet: ids in range and distinct, not flat, its volume; its
     * faces counted under their least vertices (then filed, below) */
    for (int pass = 0; pass < 2 && !err; pass++) {
        for (size_t t = 0; t < ntets && !err; t++) {
            uint32_t id[4];
            int8_t o[12];
            if ((err = chk_row(tets, off, t, 4, n, id, o, msg, len)) != FDT_OK)
                break;
            if (pass == 0) {
                if (exact_sign(X, b, 4, id, o) == 0) {
                    err = chk_fail(msg, len, "tet %zu is flat", t);
                    break;
                }
                double P[12];
                for (int j = 0; j < 4; j++)
                    (void)fdt_images_round(X + 3 * (size_t)id[j], o + 3 * j, b->lo, b->hi,
                                           P + 3 * j, NULL);
                double u[3][3];
                for (int r = 0; r < 3; r++)
                    for (int a = 0; a < 3; a++)
                        u[r][a] = (P[3 * (r + 1) + a] - P[a]) * sc[a];
                vol += fabs(u[0][0] * (u[1][1] * u[2][2] - u[1][2] * u[2][1]) -
                            u[0][1] * (u[1][0] * u[2][2] - u[1][2] * u[2][0]) +
                            u[0][2] * (u[1][0] * u[2][1] - u[1][1] * u[2][0])) / 6;
            }
            for (int j = 0; j < 4 && !err; j++) {
                finc f;
                uint32_t least;
                used[id[j]] = 1;
                if (!finc_make(id, o, 4, j, (uint32_t)(t << 2 | (size_t)j), &f, &least))
                    err = chk_fail(msg, len, "tet %zu spans more than two periods", t);
                else if (pass == 0)
                    start[least + 1]++;
                else
                    inc[start[least]++] = f;
            }
        }
        if (pass == 0) /* start[v]: where bucket v begins */
            for (size_t v = 0; v < n; v++)
                start[v + 1] += start[v];
        else /* start[v] moved to the end of bucket v: back by one */
            for (size_t v = n; v > 0; v--)
                start[v] = start[v - 1];
        start[0] = 0;
    }
    /* the hull faces likewise, each normal to no periodic axis */
    for (int pass = 0; pass < 2 && !err; pass++) {
        for (size_t h = 0; h < nhull && !err; h++) {
            uint32_t id[3];
            int8_t o[9];
            finc f;
            uint32_t least;
            if ((err = chk_row(hull, hoff, h, 3, n, id, o, msg, len)) != FDT_OK)
                break;
            if (!finc_make(id, o, 3, 3, (uint32_t)h, &f, &least))
                err = chk_fail(msg, len, "hull face %zu spans more than two periods", h);
            else if (pass == 0)
                hstart[least + 1]++;
            else
                hinc[hstart[least]++] = f;
            if (pass || err)
                continue;
            few q;
            int8_t ro[9];
            for (int j = 0; j < 9; j++)
                ro[j] = (int8_t)(o[j] - o[j % 3]);
            few_init(&q, 3, id, ro, X, b);
            const uint32_t i3[3] = {0, 1, 2};
            for (int a = 0; a < 3 && !err; a++)
                if (b->axes >> a & 1 && fdt_images_normal_sign(&q.im, i3, a) != 0)
                    err = chk_fail(msg, len, "hull face %zu crosses periodic axis %c", h,
                                   "xyz"[a]);
        }
        if (pass == 0)
            for (size_t v = 0; v < n; v++)
                hstart[v + 1] += hstart[v];
        else
            for (size_t v = n; v > 0; v--)
                hstart[v] = hstart[v - 1];
        hstart[0] = 0;
    }
    /* every point a vertex, but a duplicate of an earlier one (which the
     * tets must name instead): fdt_check's first occurrences */
    uint8_t *first = err ? NULL : calloc(n ? n : 1, 1);
    if (!err && (!first || fdt_check_first_points(X, n, first) != 0))
        err = FDT_ENOMEM;
    for (size_t i = 0; i < n && !err; i++) {
        if (first[i] && !used[i])
            err = chk_fail(msg, len, "point %zu is in no tet", i);
        else if (!first[i] && used[i])
            err = chk_fail(msg, len, "point %zu is a duplicate of point %zu, which the tets "
                           "must name instead", i, fdt_check_first_of(X, n, i));
    }
    free(first);
    /* each least vertex's faces: two tets on the two sides of each, the
     * one's apex outside the other's sphere, or one tet and a hull face */
    for (size_t v = 0; v < n && !err; v++) {
        finc *a = inc + start[v], *ha = hinc + hstart[v];
        size_t m = start[v + 1] - start[v], hm = hstart[v + 1] - hstart[v], hk = 0;
        for (size_t i = 1; i < m; i++) /* a few dozen: insertion */
            for (size_t k = i; k > 0 && finc_cmp(&a[k], &a[k - 1]) < 0; k--) {
                finc x = a[k];
                a[k] = a[k - 1];
                a[k - 1] = x;
            }
        for (size_t i = 1; i < hm; i++)
            for (size_t k = i; k > 0 && finc_cmp(&ha[k], &ha[k - 1]) < 0; k--) {
                finc x = ha[k];
                ha[k] = ha[k - 1];
                ha[k - 1] = x;
            }
        for (size_t i = 0; i < m && !err;) {
            size_t r = 1;
            while (i + r < m && !finc_cmp(&a[i + r], &a[i]))
                r++;
            /* the face, and each holder's other vertex in its frame */
            uint32_t id[5], id2[4];
            int8_t o[15], o2[12];
            finc_face((uint32_t)v, &a[i], id, o);
            if (r > 1) {
                finc_face((uint32_t)v, &a[i + 1], id2, o2);
                id[4] = id2[3];
                memcpy(o + 12, o2 + 9, 3);
            }
            while (hk < hm && finc_cmp(&ha[hk], &a[i]) < 0)
                hk++;
            int on_hull = hk < hm && !finc_cmp(&ha[hk], &a[i]);
            if (r > 2) {
                err = chk_fail(msg, len, "a face (points %u %u %u) is in %zu tets", id[0], id[1],
                               id[2], r);
            } else if (r == 1 && !on_hull) {
                err = chk_fail(msg, len, "a face of tet %u (points %u %u %u) is in no other tet "
                               "and no hull face", a[i].who >> 2, id[0], id[1], id[2]);
            } else if (r == 2 && on_hull) {
                err = chk_fail(msg, len, "hull face %u (points %u %u %u) is not the face of one "
                               "tet alone", ha[hk].who, id[0], id[1], id[2]);
            } else if (r == 1) { /* a hull face: its tet's other vertex, for the checks below */
                hapex[ha[hk].who] = id[3];
                memcpy(haoff + 3 * (size_t)ha[hk].who, o + 9, 3);
                ha[hk].who |= 0x80000000u; /* matched */
            } else {
                int s0 = exact_sign(X, b, 4, id, o);
                uint32_t id1[4] = {id[0], id[1], id[2], id[4]};
                int8_t o1[12];
                memcpy(o1, o, 9);
                memcpy(o1 + 9, o + 12, 3);
                int s1 = exact_sign(X, b, 4, id1, o1);
                if (s0 == s1) {
                    err = chk_fail(msg, len, "tets %u and %u lie on the same side of their face "
                                   "(points %u %u %u)", a[i].who >> 2, a[i + 1].who >> 2, id[0],
                                   id[1], id[2]);
                } else {
                    if (s0 < 0) { /* the first tet positive: swap its face's first two */
                        uint32_t x = id[0];
                        id[0] = id[1];
                        id[1] = x;
                        int8_t y[3];
                        memcpy(y, o, 3);
                        memcpy(o, o + 3, 3);
                        memcpy(o + 3, y, 3);
                    }
                    if (exact_sign(X, b, 5, id, o) > 0)
                        err = chk_fail(msg, len, "tets %u and %u are not locally Delaunay: "
                                       "point %u's image is in the other's sphere",
                                       a[i].who >> 2, a[i + 1].who >> 2, id[4]);
                }
            }
            i += r;
        }
        for (size_t k = 0; k < hm && !err; k++)
            if (!(ha[k].who & 0x80000000u))
                err = chk_fail(msg, len, "hull face %u is the face of no tet, or listed twice",
                               ha[k].who);
    }
    /* the hull closed and convex: each edge in two hull faces, the one's
     * third vertex not outside the other; and what it encloses */
    double flux = 0;
    for (size_t h = 0; h < nhull && !err; h++) {
        uint32_t id[3];
        int8_t o[9];
        (void)chk_row(hull, hoff, h, 3, n, id, o, NULL, 0);
        for (int j = 0; j < 9; j++)
            o[j] = (int8_t)(o[j] - o[j % 3]);
        for (int j = 0; j < 3 && !err; j++) {
            uint64_t ek[3];
            int e0 = j == 0 ? 1 : 0, e1 = j == 2 ? 1 : 2;
            ek[0] = vpack(id[e0], (const int8_t[3]){0, 0, 0});
            const int8_t r1[3] = {(int8_t)(o[3 * e1] - o[3 * e0]),
                                  (int8_t)(o[3 * e1 + 1] - o[3 * e0 + 1]),
                                  (int8_t)(o[3 * e1 + 2] - o[3 * e0 + 2])};
            ek[1] = vpack(id[e1], r1);
            const int8_t ao[3] = {(int8_t)(o[3 * j] - o[3 * e0]), (int8_t)(o[3 * j + 1] - o[3 * e0 + 1]),
                                  (int8_t)(o[3 * j + 2] - o[3 * e0 + 2])};
            ek[2] = UINT64_MAX;
            cslot *c = ctab_get(&et, ek);
            if (c->cnt >= 2) {
                err = chk_fail(msg, len, "a hull edge (points %u %u) is in three hull faces",
                               id[e0], id[e1]);
                break;
            }
            c->who[c->cnt] = (uint32_t)h;
            c->apex[c->cnt] = id[j];
            memcpy(c->aoff[c->cnt], ao, 3);
            c->cnt++;
        }
        if (err)
            break;
        /* the flux of (x_a - lo_a) over the axes a that are not periodic:
         * the outward area vector is -+N / 2, N = (p1 - p0) x (p2 - p0),
         * outward away from the tet's other vertex */
        uint32_t q[4] = {id[0], id[1], id[2], hapex[h]};
        int8_t qo[12];
        memcpy(qo, o, 9);
        memcpy(qo + 9, haoff + 3 * h, 3);
        int s = exact_sign(X, b, 4, q, qo);
        double P[9], u[3], w[3];
        for (int k = 0; k < 3; k++)
            (void)fdt_images_round(X + 3 * (size_t)id[k], o + 3 * k, b->lo, b->hi, P + 3 * k,
                                   NULL);
        for (int a = 0; a < 3; a++) {
            u[a] = (P[3 + a] - P[a]) * sc[a];
            w[a] = (P[6 + a] - P[a]) * sc[a];
        }
        const double nrm[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2],
                               u[0] * w[1] - u[1] * w[0]};
        for (int a = 0; a < 3; a++)
            if (!(b->axes >> a & 1))
                flux += (s > 0 ? -1 : 1) *
                        ((P[a] + P[3 + a] + P[6 + a]) / 3 - b->lo[a]) * sc[a] * nrm[a] / 2;
    }
    for (size_t h = 0; h <= et.mask && !err; h++) {
        cslot *c = &et.s[h];
        if (!c->cnt)
            continue;
        uint32_t e0 = (uint32_t)(c->k[0] >> 24), e1 = (uint32_t)(c->k[1] >> 24);
        if (c->cnt != 2) {
            err = chk_fail(msg, len, "the hull is not closed at the edge of points %u %u", e0,
                           e1);
            break;
        }
        /* in the edge's frame: the edge, face who[0]'s third vertex, its
         * tet's other vertex (the inside), face who[1]'s third vertex */
        uint32_t f = c->who[0], fid[3];
        int8_t fo[9];
        (void)chk_row(hull, hoff, f, 3, n, fid, fo, NULL, 0);
        int l = 0;
        while (fid[l] != e0)
            l++;
        uint32_t id[5] = {e0, e1, c->apex[0], hapex[f], c->apex[1]};
        int8_t o[15] = {0};
        for (int a = 0; a < 3; a++) {
            o[3 + a] = (int8_t)((int)(c->k[1] >> (16 - 8 * a) & 255) - 128);
            o[6 + a] = c->aoff[0][a];
            /* haoff is relative to face f's least vertex, fid[0] */
            o[9 + a] = (int8_t)(haoff[3 * (size_t)f + (size_t)a] - (fo[3 * l + a] - fo[a]));
            o[12 + a] = c->aoff[1][a];
        }
        int si = exact_sign(X, b, 4, id, o);
        uint32_t id2[4] = {e0, e1, c->apex[0], c->apex[1]};
        int8_t o2[12];
        memcpy(o2, o, 9);
        memcpy(o2 + 9, o + 12, 3);
        int sv = exact_sign(X, b, 4, id2, o2);
        if (sv != 0 && sv != si)
            err = chk_fail(msg, len, "the hull is not convex at the edge of points %u %u", e0,
                           e1);
    }
    /* the tets cover the domain once: their volumes sum to the box's (x,
     * y and z periodic), or to what the hull encloses in one period: by
     * the divergence theorem, the flux of the field (x_a - lo_a) over the
     * d axes a that are not periodic, through the hull faces (none
     * crosses the periods' cuts), over d */
    if (!err && ntets) {
        double want = 1;
        int d = 0;
        for (int a = 0; a < 3; a++)
            if (b->axes >> a & 1)
                want *= (b->hi[a] - b->lo[a]) * sc[a];
            else
                d++;
        if (d)
            want = flux / d;
        if (!(fabs(vol - want) <= 1e-9 * fabs(want)))
            err = chk_fail(msg, len, "the tets' volumes sum to %.17g, the domain's is %.17g: "
                           "they do not cover it once", vol, want);
    }
    if (!err && !ntets)
        err = chk_fail(msg, len, "no tets");
    free(used);
    free(start);
    free(hstart);
    free(inc);
    free(hinc);
    free(hapex);
    free(haoff);
    free(et.s);
    return err;
}

/*
 * The cells of the points own[0 .. nown) (X's ids, distinct) from tets
 * (ids in X, 12 offsets each relative to any vertex; positive[t], when
 * given, whether tet t is positive in that order, else an exact test
 * says) that hold every tet of their stars, and the hull faces' points
 * hull[0 .. 3 nhull): a batch
 * (src/mesh/voronoi.h), row i own[i]'s cell, its id names[own[i]] (names
 * NULL: the ids themselves). X is the input's points times 2^x_exp, and b
 * its box likewise. Each tet is taken once for each offset among its
 * vertices, moved so that the vertices with that offset are the points
 * themselves: every star around its point. FDT_ERANGE for an edge too
 * short for the cells (*sh, the least one, diag not written); else the
 * batch's errors with diag.
 */
static int star_batch(const uint32_t *tets, const int8_t *off, const uint8_t *positive,
                      size_t ntets, const uint32_t *hull,
                      size_t nhull, const double *X, int x_exp, const int32_t *names,
                      const uint32_t *own_ids, size_t nown_ids, const fdt_periodic_box *b,
                      int threads, int neighbors, unsigned skip, struct fdt_voronoi **out,
                      fdt_vshort *sh, double box[6], char *diag, size_t ds)
{
    *out = NULL;
    vmap m;
    memset(&m, 0, sizeof m);
    uint32_t *own = NULL, *st = NULL;
    uint8_t *own_hull = NULL;
    size_t nst = 0, stcap = 0, nown = 0;
    int err = FDT_OK;
    static const int8_t zero[3] = {0, 0, 0};
    /* the points themselves first, rows 0 .. nown of the batch, in Morton
     * order: the cells' passes then meet a tet's points near the last
     * one's (in input order, add_tet read points all over the batch:
     * bench/NOTES.md entry 112) */
    double *pts = malloc(3 * (nown_ids ? nown_ids : 1) * sizeof *pts);
    uint32_t *order = malloc((nown_ids ? nown_ids : 1) * sizeof *order);
    if (!pts || !order)
        err = FDT_ENOMEM;
    double ob[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < nown_ids && !err; i++) {
        const double *x = X + 3 * (size_t)(own_ids ? own_ids[i] : i);
        for (int k = 0; k < 3; k++) {
            pts[3 * i + (size_t)k] = x[k];
            ob[k] = x[k] < ob[k] ? x[k] : ob[k];
            ob[k + 3] = x[k] > ob[k + 3] ? x[k] : ob[k + 3];
        }
    }
    if (!err && nown_ids && fdt_morton_order(pts, nown_ids, ob, NULL, order) < 0)
        err = FDT_ENOMEM;
    for (size_t i = 0; i < nown_ids && !err; i++) {
        uint32_t q = order[i];
        if (vmap_get(&m, own_ids ? own_ids[q] : q, zero, X, b) < 0)
            err = FDT_ENOMEM;
    }
    free(pts);
    free(order);
    nown = m.n;
    for (size_t t = 0; t < ntets && !err; t++) {
        const uint32_t *id = tets + 4 * t;
        const int8_t *o = off + 12 * t;
        int pos = positive ? positive[t] : exact_sign(X, b, 4, id, o) > 0;
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
        long x = vmap_get(&m, hull[f], zero, X, b);
        if (x < 0)
            err = FDT_ENOMEM;
        else if ((size_t)x < nown)
            own_hull[x] = 1;
    }
    /* the box (fdt_periodic_cells_box): on a periodic axis the period box
     * with three periods on each side, which holds every image and
     * circumcentre of the points' stars, whichever stars a batch has, so
     * that the cells' frame and grids, and their bits, are the same in
     * every batch (a box grown to each batch's farthest image would not
     * be); on the others the box's sides, where cells are cut. Grown
     * where an image lies beyond (the proofs keep every star inside). */
    fdt_vbatch vb;
    memset(&vb, 0, sizeof vb);
    fdt_periodic_cells_box(b, vb.box);
    for (int k = 0; k < 3 && !err; k++) {
        if (!(b->axes >> k & 1))
            continue;
        for (size_t i = 0; i < m.n; i++) {
            double v = m.xyz[3 * i + k];
            vb.box[k] = v < vb.box[k] ? v : vb.box[k];
            vb.box[k + 3] = v > vb.box[k + 3] ? v : vb.box[k + 3];
        }
    }
    for (int k = 0; k < 6; k++) /* the input's frame, exactly */
        box[k] = vb.box[k] = ldexp(vb.box[k], -x_exp);
    for (size_t i = 0; names && i < m.n; i++) /* the rows' and neighbours' ids */
        m.label[i] = (uint32_t)names[m.label[i]];
    if (!err)
        err = fdt_voronoi_scale(vb.box, &vb.ed, diag, ds);
    struct fdt_voronoi *v = NULL;
    if (!err) {
        vb.xyz = m.xyz;
        vb.xyz_exp = x_exp;
        vb.label = (const fdt_vid *)m.label;
        vb.own = own;
        vb.nown = nown;
        vb.own_hull = own_hull;
        vb.tets = st;
        vb.ntets = nst / 4;
        vb.neighbors = neighbors;
        vb.skip = skip;
        vb.periodic = b->axes;
        err = fdt_voronoi_batch(&vb, threads, &v, sh, diag, ds);
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
    if (err)
        fdt_voronoi_free(&v);
    *out = v;
    vmap_free(&m);
    free(own);
    free(own_hull);
    free(st);
    return err;
}

int fdt_periodic_cells(const int32_t *tets, const int8_t *off, size_t ntets, const int32_t *hull,
                       size_t nhull, const double *X, size_t n, const int32_t *dupmap,
                       const fdt_periodic_box *b, int threads, int neighbors, unsigned skip,
                       fdt_voronoi **out, char *diag, size_t ds)
{
    *out = NULL;
    int err = fdt_periodic_cells_check(X, n, b, diag, ds);
    if (err)
        return err;
    uint32_t *own = malloc((n ? n : 1) * sizeof *own);
    if (!own)
        return FDT_ENOMEM;
    size_t nown = 0;
    for (size_t i = 0; i < n; i++)
        if (dupmap[i] == (int32_t)i)
            own[nown++] = (uint32_t)i;
    fdt_vshort sh = {-1, -1, INFINITY};
    fdt_voronoi *v = NULL;
    double box[6];
    err = star_batch((const uint32_t *)tets, off, NULL, ntets, (const uint32_t *)hull, nhull, X, 0,
                     NULL, own, nown, b, threads, neighbors, skip, &v, &sh, box, diag, ds);
    free(own);
    if (err == FDT_ERANGE && sh.a >= 0)
        err = fdt_voronoi_too_close(&sh, box, diag, ds);
    if (!err)
        err = fdt_voronoi_spread(&v, n);
    if (!err)
        fdt_voronoi_set_periodic(v, b->axes, b->lo, b->hi);
    if (err)
        fdt_voronoi_free(&v);
    *out = v;
    return err;
}

int fdt_periodic_cells_check(const double *X, size_t n, const fdt_periodic_box *b, char *diag,
                             size_t ds)
{
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
    return FDT_OK;
}

void fdt_periodic_cells_box(const fdt_periodic_box *b, double box[6])
{
    /* A star's tets have their balls inside the proofs' region, the core
     * grown by a margin of at most a period (so at most three periods
     * wide): moved so that one vertex is the point itself, in the box, the
     * others and the centre lie within three periods of it. */
    for (int k = 0; k < 3; k++) {
        double L = b->axes >> k & 1 ? 3 * (b->hi[k] - b->lo[k]) : 0;
        box[k] = b->lo[k] - L;
        box[k + 3] = b->hi[k] + L;
    }
}

int fdt_periodic_part_cells(const fdt_periodic_mesh *pm, const double *X, uint32_t n, int x_exp,
                            const int32_t *names, const fdt_periodic_parts *parts, uint32_t part,
                            const fdt_periodic_box *b, int threads, int neighbors, unsigned skip,
                            fdt_voronoi **out, fdt_vshort *sh, char *diag, size_t ds)
{
    int one = parts->nparts < 2;
    const uint32_t *own = one ? NULL : parts->idx + parts->start[part];
    size_t nown = one ? n : parts->start[part + 1] - parts->start[part];
    double box[6];
    return star_batch(pm->star_tets, pm->star_off, pm->star_pos, pm->nstar, pm->star_hull,
                      pm->nstar_hull, X, x_exp, names, own, nown, b, threads, neighbors, skip,
                      out, sh, box, diag, ds);
}
