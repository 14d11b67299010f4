/* kd-tree build and range queries; see kdtree.h. */
#include "geom/kdtree.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
/* AVX2 versions of the float-block kernels, chosen at run time: GCC and
 * Clang on x86-64 only (target attribute, __builtin_cpu_supports). */
#if defined(__x86_64__) && defined(__GNUC__) && defined(__SSE2__)
#define FDT_KD_AVX2 1
#include <immintrin.h>
#else
#define FDT_KD_AVX2 0
#endif
#include "base/bits.h"
#include "base/mem.h"

void fdt_kd_free(fdt_kdtree *t)
{
    free(t->nodes);
    free(t->parent);
    free(t->cell);
    free(t->leafof);
    free(t->fl);
    memset(t, 0, sizeof *t);
}

static void swap_pt(double *P, fdt_vid *orig, uint32_t i, uint32_t j)
{
    double x0 = P[3 * (size_t)i], x1 = P[3 * (size_t)i + 1], x2 = P[3 * (size_t)i + 2];
    P[3 * (size_t)i] = P[3 * (size_t)j];
    P[3 * (size_t)i + 1] = P[3 * (size_t)j + 1];
    P[3 * (size_t)i + 2] = P[3 * (size_t)j + 2];
    P[3 * (size_t)j] = x0;
    P[3 * (size_t)j + 1] = x1;
    P[3 * (size_t)j + 2] = x2;
    fdt_vid o = orig[i];
    orig[i] = orig[j];
    orig[j] = o;
}

/*
 * Floyd and Rivest's selection (CACM 18(3), 1975, algorithm SELECT):
 * afterwards the point at k has the k-th smallest coordinate `dim` of
 * [left, right], smaller-or-equal ones before it, greater-or-equal after.
 * Above 600 points it first selects k inside a sample of about n^(2/3)
 * points around k, offset so that k falls just inside the smaller side,
 * so the pivot it partitions on is nearly the answer and one partition
 * pass over the range nearly finishes it: about 1.5 n comparisons for a
 * median, where the three-way quickselect this replaced made about 3.4 n
 * and a swap for every point off the pivot (the kd build was 6 % of a 1M
 * serial run, bench/NOTES.md). Hoare's partition stops on points equal to
 * the pivot from both sides, so runs of equal coordinates (lattices,
 * lidar planes) split evenly and every round narrows the range.
 */
static void select_range(double *P, fdt_vid *orig, int64_t left, int64_t right, int64_t k,
                         int dim)
{
#define SX(i) P[3 * (size_t)(i) + (size_t)dim]
    while (right > left) {
        if (right - left > 600) {
            double n = (double)(right - left + 1), i = (double)(k - left + 1);
            double z = log(n), s = 0.5 * exp(2.0 * z / 3.0);
            double sd = 0.5 * sqrt(z * s * (n - s) / n) * (i < n / 2 ? -1.0 : 1.0);
            int64_t nl = (int64_t)floor((double)k - i * s / n + sd);
            int64_t nr = (int64_t)floor((double)k + (n - i) * s / n + sd);
            select_range(P, orig, nl > left ? nl : left, nr < right ? nr : right, k, dim);
        }
        double t = SX(k);
        int64_t i = left, j = right;
        /* Sentinels: the pivot at left and something >= it at right (or
         * the other way round), so neither scan below leaves the range. */
        swap_pt(P, orig, (uint32_t)left, (uint32_t)k);
        if (SX(right) > t)
            swap_pt(P, orig, (uint32_t)right, (uint32_t)left);
        while (i < j) {
            swap_pt(P, orig, (uint32_t)i, (uint32_t)j);
            i++;
            j--;
            while (SX(i) < t)
                i++;
            while (SX(j) > t)
                j--;
        }
        if (SX(left) == t) {
            swap_pt(P, orig, (uint32_t)left, (uint32_t)j);
        } else {
            j++;
            swap_pt(P, orig, (uint32_t)j, (uint32_t)right);
        }
        /* The pivot is at j, its final place. */
        if (j <= k)
            left = j + 1;
        if (k <= j)
            right = j - 1;
    }
#undef SX
}

/* The k-th smallest coordinate `dim` of [lo, hi) at k (select_range). */
static void select_k(double *P, fdt_vid *orig, uint32_t lo, uint32_t hi, uint32_t k, int dim)
{
    if (hi - lo > 1)
        select_range(P, orig, lo, (int64_t)hi - 1, k, dim);
}

void fdt_kd_select(double *P, fdt_vid *orig, uint32_t lo, uint32_t hi,
                   uint32_t k, int dim)
{
    select_k(P, orig, lo, hi, k, dim);
}

typedef struct build_ctx {
    fdt_kdtree *t;
    double *P;
    fdt_vid *orig;
    uint32_t leaf;
    uint32_t next;         /* the next free node id of this subtree's block */
} build_ctx;

void fdt_points_box(const double *P, uint32_t begin, uint32_t end,
                    double *lo, double *hi)
{
    for (int k = 0; k < 3; k++) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
    }
    uint32_t i = begin;
#if defined(__SSE2__)
    /* Two points (six doubles) a step in three registers, lanes (x0 y0),
     * (z0 x1), (y1 z1): the build scans every point once a level, and
     * the scalar loop was a fifth of the build (perf, 1M). min and max
     * are exact, so the box is the same (up to the sign of a zero). */
    if (end - begin >= 4) {
        __m128d l0 = _mm_set1_pd(INFINITY), l1 = l0, l2 = l0;
        __m128d h0 = _mm_set1_pd(-INFINITY), h1 = h0, h2 = h0;
        for (; i + 2 <= end; i += 2) {
            const double *q = P + 3 * (size_t)i;
            __m128d a = _mm_loadu_pd(q), b = _mm_loadu_pd(q + 2), c = _mm_loadu_pd(q + 4);
            l0 = _mm_min_pd(l0, a);
            h0 = _mm_max_pd(h0, a);
            l1 = _mm_min_pd(l1, b);
            h1 = _mm_max_pd(h1, b);
            l2 = _mm_min_pd(l2, c);
            h2 = _mm_max_pd(h2, c);
        }
        double L[6], H[6];
        _mm_storeu_pd(L, l0);
        _mm_storeu_pd(L + 2, l1);
        _mm_storeu_pd(L + 4, l2);
        _mm_storeu_pd(H, h0);
        _mm_storeu_pd(H + 2, h1);
        _mm_storeu_pd(H + 4, h2);
        /* x: lanes 0 and 3, y: 1 and 4, z: 2 and 5 */
        for (int k = 0; k < 3; k++) {
            lo[k] = L[k] < L[k + 3] ? L[k] : L[k + 3];
            hi[k] = H[k] > H[k + 3] ? H[k] : H[k + 3];
        }
    }
#endif
    for (; i < end; i++)
        for (int k = 0; k < 3; k++) {
            double x = P[3 * (size_t)i + k];
            if (x < lo[k])
                lo[k] = x;
            if (x > hi[k])
                hi[k] = x;
        }
}

/*
 * Where a node over c > leaf points splits: into the leaves it needs,
 * nl = ceil(c / leaf), half of them on each side, rather than into halves
 * of the points: every leaf then holds about c / nl points (at most leaf,
 * at least leaf / 2), close to leaf wherever nl is large, where halving
 * gave anything from leaf / 2 to leaf as n varied (15.3 points a leaf at
 * 1M with leaf 18, 12.2 at 200k). The left child's count.
 */
static inline uint32_t left_count(uint32_t c, uint32_t leaf)
{
    uint32_t nl = (c + leaf - 1) / leaf;
    return (uint32_t)(((uint64_t)c * (nl / 2)) / nl);
}

/* The nodes of a subtree over c >= 1 points, its root included. The left
 * child of a node over c > leaf points gets exactly nl / 2 of its nl
 * leaves and the right one the rest (left_count), so a subtree has
 * ceil(c / leaf) leaves: a function of c alone, which gives a subtree's
 * descendants their block of node ids before it is built (checked
 * against the recursion for every c below 60,000 and leaves 1 to 40). */
static uint32_t subtree_nodes(uint32_t c, uint32_t leaf)
{
    return 2 * (uint32_t)(((uint64_t)c + leaf - 1) / leaf) - 1;
}

/* Fills node `id` over [begin, end) and splits it: its children get ids
 * bc->next and bc->next + 1. The left child's point count, or 0 for a
 * leaf. */
static uint32_t build_node(build_ctx *bc, uint32_t id, uint32_t begin, uint32_t end)
{
    fdt_kdnode *nd = &bc->t->nodes[id];
    nd->begin = begin;
    nd->end = end;
    nd->left = 0;
    nd->dim = 0;
    fdt_points_box(bc->P, begin, end, nd->lo, nd->hi);
    if (end - begin <= bc->leaf)
        return 0;
    int dim = 0;
    double w = nd->hi[0] - nd->lo[0];
    for (int k = 1; k < 3; k++)
        if (nd->hi[k] - nd->lo[k] > w) {
            w = nd->hi[k] - nd->lo[k];
            dim = k;
        }
    uint32_t mid = begin + left_count(end - begin, bc->leaf);
    select_k(bc->P, bc->orig, begin, end, mid, dim);
    nd->left = bc->next;
    bc->next += 2;
    nd->dim = (uint32_t)dim;
    return mid - begin;
}

/* Fills node `id` over [begin, end) and its subtree, the left subtree's
 * nodes numbered before the right's. Recursion depth is log2(n / leaf),
 * at most ~32. */
static void build_rec(build_ctx *bc, uint32_t id, uint32_t begin, uint32_t end)
{
    uint32_t l = build_node(bc, id, begin, end);
    if (l == 0)
        return;
    uint32_t left = bc->t->nodes[id].left;
    build_rec(bc, left, begin, begin + l);
    build_rec(bc, left + 1, begin + l, end);
}

/* Every node's cell from the root's (cell[0]): parents before children,
 * as nodes are numbered, so one pass in index order. */
static void fill_cells(fdt_kdtree *t)
{
    for (uint32_t j = 0; j < t->nnodes; j++) {
        const fdt_kdnode *nd = &t->nodes[j];
        if (!nd->left)
            continue;
        uint32_t l = nd->left, dim = nd->dim;
        memcpy(t->cell[l], t->cell[j], sizeof t->cell[j]);
        memcpy(t->cell[l + 1], t->cell[j], sizeof t->cell[j]);
        t->cell[l][1][dim] = t->nodes[l + 1].lo[dim];
        t->cell[l + 1][0][dim] = t->nodes[l].hi[dim];
    }
}

/*
 * The tables of fdt_apex_search_from's climb. A node's cell is the region
 * its ancestors' splits give it. The split value itself is not stored
 * (the children's later splits reorder their points), but every left
 * point is <= it <= every right point, so the right child's smallest
 * coordinate bounds the left cell from above and the left child's
 * largest bounds the right cell from below: cells a little larger than
 * the true ones, still disjoint from the sibling's points. Nodes are
 * numbered parents before children, so one pass in index order fills
 * them. About 60 bytes a leaf's worth of points (1M points: 13 MB); they
 * replaced a root-to-leaf descent a face (about 400 instructions).
 */
static int climb_tables(fdt_kdtree *t)
{
    t->parent = malloc((size_t)t->nnodes * sizeof *t->parent);
    t->cell = malloc((size_t)t->nnodes * sizeof *t->cell);
    t->leafof = malloc(((size_t)t->n + 1) * sizeof *t->leafof);
    fdt_mem_advise_huge(t->cell, (size_t)t->nnodes * sizeof *t->cell);
    fdt_mem_advise_huge(t->leafof, ((size_t)t->n + 1) * sizeof *t->leafof);
    if (!t->parent || !t->cell || !t->leafof) {
        fdt_kd_free(t);
        return FDT_ENOMEM;
    }
    t->parent[0] = 0;
    for (int k = 0; k < 3; k++) {
        t->cell[0][0][k] = -INFINITY;
        t->cell[0][1][k] = INFINITY;
    }
    for (uint32_t j = 0; j < t->nnodes; j++) {
        const fdt_kdnode *nd = &t->nodes[j];
        if (!nd->left) {
            for (uint32_t i = nd->begin; i < nd->end; i++)
                t->leafof[i - t->base] = j;
            continue;
        }
        uint32_t l = nd->left;
        t->parent[l] = t->parent[l + 1] = j;
    }
    fill_cells(t);
    return FDT_OK;
}

void fdt_kd_set_region(fdt_kdtree *t, const double lo[3], const double hi[3])
{
    if (!t->cell)
        return;
    memcpy(t->cell[0][0], lo, sizeof t->cell[0][0]);
    memcpy(t->cell[0][1], hi, sizeof t->cell[0][1]);
    fill_cells(t);
}

/* ---- float blocks --------------------------------------------------------
 *
 * The apex search tests every point of a visited leaf against a ball, and
 * its first guess computes a quotient for every point of up to three
 * leaves: two thirds of its instructions (callgrind, 50k uniform), in
 * double precision and one point at a time. The float blocks hold each
 * leaf's points again, as floats, four to an SSE register: for the ball
 * test only as a filter that may keep too many points (whose exact
 * decision follows, as before), for the guess only as an order.
 *
 * Floats have 24 bits and a range of 2^+-126, so the coordinates go in a
 * frame of the leaf's own: X = fl32((x - lo) s) per axis, lo the leaf's box
 * corner and s = leaf_scale(), a power of two bringing the box's largest
 * extent into [0.5, 1). Each X is then in [0, 1] and within 2^-23 of
 * (x - lo) s (one double rounding of the difference, one float rounding;
 * underflow below 2^-126 adds at most 2^-149), whatever the cloud's offset
 * or magnitude: a lidar tile at 1e6 and a cloud 1e-150 wide get the same
 * relative resolution. A leaf whose extent is subnormal or beyond
 * 2^+-1000 gets no frame (s = 0), and its tests stay in double.
 *
 * Layout: a leaf of n points has a block of three rows, X, Y and Z, each n
 * rounded up to a multiple of 8 floats (padding zeros), 32-byte aligned,
 * so that SSE reads four lanes and, where the processor has AVX2 (checked
 * at run time, fdt_kdtree.avx2), AVX reads eight; the leaf's dim field
 * gives the block's offset in units of 4 floats.
 * 30 points take 384 bytes, against 720 for their doubles.
 */

/* The leaf's frame scale s (above), or 0 where it has none; a function of
 * the node's box alone, so the build and every query agree on it. */
static inline double leaf_scale(const fdt_kdnode *nd)
{
    double ext = 0.0;
    for (int k = 0; k < 3; k++) {
        double e = nd->hi[k] - nd->lo[k];
        ext = ext > e ? ext : e;
    }
    if (ext == 0.0)
        return 1.0; /* one point, at lo: every X is 0 */
    if (!(ext >= DBL_MIN && ext <= DBL_MAX))
        return 0.0;
    int e = fdt_exp2_normal(ext); /* ext in [2^(e-1), 2^e) */
    return e >= -1000 && e <= 1000 ? fdt_pow2i(-e) : 0.0;
}

/* Rows of a leaf's block are this many floats apart. */
static inline uint32_t block_row(uint32_t n)
{
    return (n + 7) & ~UINT32_C(7);
}

size_t fdt_kd_bytes(const fdt_kdtree *t)
{
    size_t b = (size_t)t->nnodes * sizeof *t->nodes;
    if (t->parent)
        b += (size_t)t->nnodes * (sizeof *t->parent + sizeof *t->cell) +
             ((size_t)t->n + 1) * sizeof *t->leafof;
    if (t->fl)
        for (uint32_t j = 0; j < t->nnodes; j++)
            if (!t->nodes[j].left)
                b += 3 * (size_t)block_row(t->nodes[j].end - t->nodes[j].begin) * sizeof(float);
    return b;
}

static void float_blocks(fdt_kdtree *t)
{
    size_t total = 0; /* in units of 4 floats */
    for (uint32_t j = 0; j < t->nnodes; j++)
        if (!t->nodes[j].left)
            total += 3 * (size_t)(block_row(t->nodes[j].end - t->nodes[j].begin) / 4);
    /* Offsets must fit the 32-bit dim field; beyond that (over a billion
     * points) the tests run in double. */
    if (total == 0 || total > UINT32_MAX)
        return;
    t->fl = aligned_alloc(32, total * 4 * sizeof(float));
    fdt_mem_advise_huge(t->fl, total * 4 * sizeof(float));
    if (!t->fl)
        return; /* an optimisation only: its absence changes no result */
    size_t off = 0;
    for (uint32_t j = 0; j < t->nnodes; j++) {
        fdt_kdnode *nd = &t->nodes[j];
        if (nd->left)
            continue;
        uint32_t n = nd->end - nd->begin, row = block_row(n);
        float *B = t->fl + 4 * off;
        double sl = leaf_scale(nd);
        for (int k = 0; k < 3; k++)
            for (uint32_t i = 0; i < row; i++)
                B[k * (size_t)row + i] =
                    i < n && sl > 0.0 ? (float)((t->P[3 * (size_t)(nd->begin + i) + k] - nd->lo[k]) * sl)
                                      : 0.0f;
        nd->dim = (uint32_t)off;
        off += 3 * (size_t)(row / 4);
    }
#if FDT_KD_AVX2
    t->avx2 = __builtin_cpu_supports("avx2") != 0;
#endif
}

int fdt_kd_begin(fdt_kdtree *t, double *P, fdt_vid *orig, uint32_t base, uint32_t n,
                 int leaf_size, fdt_kd_job *root)
{
    memset(t, 0, sizeof *t);
    if (leaf_size < 1)
        leaf_size = 1;
    /* A node over c > leaf points splits into nl >= 2 leaves' worth, so
     * leaves hold at least leaf/2 points: at most 2n/leaf + 1 leaves,
     * twice that nodes. */
    size_t cap = 4 * ((size_t)n / (size_t)leaf_size + 1) + 4;
    t->nodes = malloc(cap * sizeof *t->nodes);
    fdt_mem_advise_huge(t->nodes, cap * sizeof *t->nodes);
    if (!t->nodes)
        return FDT_ENOMEM;
    t->P = P;
    t->base = base;
    t->n = n;
    t->nnodes = n ? subtree_nodes(n, (uint32_t)leaf_size) : 1; /* n = 0: an empty root */
    *root = (fdt_kd_job){t, P, orig, (uint32_t)leaf_size, 0, base, base + n, 1};
    return FDT_OK;
}

int fdt_kd_run(const fdt_kd_job *job, uint32_t grain, fdt_kd_job kids[2])
{
    build_ctx bc = {job->t, job->P, job->orig, job->leaf, job->next};
    if (job->end - job->begin <= grain) {
        build_rec(&bc, job->node, job->begin, job->end);
        return 0;
    }
    uint32_t l = build_node(&bc, job->node, job->begin, job->end);
    if (l == 0)
        return 0;
    /* The children's descendants in build_rec's order: the left
     * subtree's block first, from bc.next. */
    uint32_t left = bc.next - 2, mid = job->begin + l;
    kids[0] = (fdt_kd_job){job->t, job->P, job->orig, job->leaf, left, job->begin, mid, bc.next};
    kids[1] = (fdt_kd_job){job->t, job->P, job->orig, job->leaf, left + 1, mid, job->end,
                           bc.next + subtree_nodes(l, job->leaf) - 1};
    return 2;
}

int fdt_kd_end(fdt_kdtree *t)
{
    int err = climb_tables(t);
    if (err == FDT_OK)
        float_blocks(t);
    return err;
}

int fdt_kd_build(fdt_kdtree *t, double *P, fdt_vid *orig, uint32_t base,
                 uint32_t n, int leaf_size)
{
    fdt_kd_job root;
    int err = fdt_kd_begin(t, P, orig, base, n, leaf_size, &root);
    if (err)
        return err;
    fdt_kd_job kids[2];
    fdt_kd_run(&root, UINT32_MAX, kids);
    return fdt_kd_end(t);
}

static double dist2(const double *a, const double *b)
{
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return dx * dx + dy * dy + dz * dz;
}

/*
 * Ball tests in scaled units. Squared distances of points 1e-300 apart
 * underflow and of points 1e200 apart overflow, and inputs that mix
 * magnitudes (1e-150 next to 1e150; prepare can only bring the largest
 * near 1) have spheres of both sizes. So a ball of radius rr is stored as
 * sc, a power of two bringing rr near 1, and r2 = (rr sc)^2, and a point
 * d is inside when |(d - c) sc|^2 <= r2: a difference of doubles that is
 * subnormal is exact, scaling by a power of two is exact (a scaled-down
 * value may lose 2^-1075, negligible next to r2 near 1), and the scaled
 * squares are normal numbers, so the usual relative rounding holds. For
 * radii within [2^-400, 2^400] sc is 1 and nothing changes.
 */
static void ball_scale(double rr, double *sc, double *r2)
{
    *sc = 1.0;
    if (!(rr > 0.0) || !(rr < INFINITY)) {
        *r2 = INFINITY; /* unknown: visit everything, the caller decides */
        return;
    }
    if (rr < 0x1p-400 || rr > 0x1p400) {
        /* Clamped: a subnormal radius (below 2^-1022, from points 1e-308
         * apart) would otherwise give 2^1030 = INFINITY, and 0 * INFINITY
         * made the distances of the ball's own centre NaN (found by
         * tests/fuzz/fuzz_mesh); 2^1000 still brings such a radius to a
         * normal r2. */
        int k = -ilogb(rr);
        *sc = ldexp(1.0, k > 1000 ? 1000 : (k < -1000 ? -1000 : k));
    }
    double q = rr * *sc;
    *r2 = q * q;
}

/* The apex search's ball of radius rr: scaled as above, and unscaled for
 * the float blocks' tests (INFINITY wherever r2 is). */
static void set_ball(fdt_apex *s, double rr)
{
    ball_scale(rr, &s->sc, &s->r2);
    s->rad = s->r2 < INFINITY ? rr : INFINITY;
}

static inline double dist2_sc(const double *a, const double *b, double sc)
{
    double dx = (a[0] - b[0]) * sc, dy = (a[1] - b[1]) * sc, dz = (a[2] - b[2]) * sc;
    return dx * dx + dy * dy + dz * dz;
}

double fdt_box_dist2_sc(const double *lo, const double *hi, const double *c, double sc)
{
#if defined(__SSE2__)
    /* The same per-axis max(lo - c, c - hi, 0) as below, x and y in one
     * register: about half the instructions, and this is the walk's most
     * frequent test (35 a face, 50k uniform). maxpd returns its second
     * operand when either is NaN, so a NaN difference gives 0, a node
     * kept, as the scalar form's NaN sum does. */
    __m128d c01 = _mm_loadu_pd(c), c2 = _mm_load_sd(c + 2), z = _mm_setzero_pd();
    __m128d s2 = _mm_set_sd(sc), s01 = _mm_set1_pd(sc);
    __m128d d01 = _mm_max_pd(_mm_sub_pd(_mm_loadu_pd(lo), c01), _mm_sub_pd(c01, _mm_loadu_pd(hi)));
    __m128d d2 = _mm_max_sd(_mm_sub_sd(_mm_load_sd(lo + 2), c2), _mm_sub_sd(c2, _mm_load_sd(hi + 2)));
    d01 = _mm_mul_pd(_mm_max_pd(d01, z), s01);
    d2 = _mm_mul_sd(_mm_max_sd(d2, z), s2);
    d01 = _mm_mul_pd(d01, d01);
    d2 = _mm_mul_sd(d2, d2);
    /* (x^2 + y^2) + z^2, the scalar form's order */
    __m128d sum = _mm_add_sd(d01, _mm_unpackhi_pd(d01, d01));
    return _mm_cvtsd_f64(_mm_add_sd(sum, d2));
#else
    double d2 = 0.0;
    for (int k = 0; k < 3; k++) {
        /* the larger of lo - c, c - hi and 0 (lo <= hi, so at most one
         * difference is positive), by arithmetic, not branches: the
         * branches were mispredicted a third of the time, a fifth of all
         * mispredictions of a run (cachegrind --branch-sim, 200k), and
         * gcc keeps a branch for (d > 0 ? d : 0). d + |d| is 2d or 0
         * exactly (box distances of prepared points are far from
         * overflow), halving is exact. */
        double d = lo[k] - c[k], e = c[k] - hi[k];
        d = d > e ? d : e;
        d = 0.5 * (d + fabs(d)) * sc; /* max(d, 0), exactly */
        d2 += d * d;
    }
    return d2;
#endif
}

/* Depth of a balanced tree with leaves of >= 1 point is < 64: a stack of
 * 2 * 64 entries per walk would do, but walks push both children, so we
 * size it to the node count bound of one root-to-leaf path times 2. */
#define WALK_STACK 256

/*
 * Floating squared distances are only compared where they are far apart:
 * each carries a relative error below 8 eps (three rounded differences,
 * three squares, two sums) plus absolute errors below 2^-1000 where
 * products underflow, so NEAR_REL and NEAR_ABS bound the band in which
 * the floating order may be wrong. Inside it fdt_compare_dist decides
 * exactly, so the result is an exact nearest point (lowest id on exact
 * ties) even when the input mixes magnitudes and every floating distance
 * rounds to the same value: the seed's first edge relies on it (§2.1).
 */
#define NEAR_REL 0x1p-40
#define NEAR_ABS 0x1p-1000

uint32_t fdt_kd_nearest(const fdt_kdtree *t, const double *q,
                        uint32_t exclude, fdt_kdq *kq)
{
    uint32_t stack[WALK_STACK];
    int sp = 0;
    uint32_t best = FDT_NONE;
    double bd = INFINITY;
    stack[sp++] = 0;
    while (sp > 0) {
        const fdt_kdnode *nd = &t->nodes[stack[--sp]];
        if (fdt_box_dist2_sc(nd->lo, nd->hi, q, 1.0) > bd * (1.0 + NEAR_REL) + NEAR_ABS)
            continue;
        if (kq)
            kq->nodes++;
        if (!nd->left) {
            for (uint32_t i = nd->begin; i < nd->end; i++) {
                if (i == exclude)
                    continue;
                const double *p = t->P + 3 * (size_t)i;
                double d = dist2(p, q);
                int take;
                if (best == FDT_NONE || d < bd * (1.0 - NEAR_REL) - NEAR_ABS)
                    take = 1;
                else if (d > bd * (1.0 + NEAR_REL) + NEAR_ABS)
                    take = 0;
                else {
                    int c = fdt_compare_dist(q, p, t->P + 3 * (size_t)best);
                    take = c < 0 || (c == 0 && i < best);
                }
                if (take) {
                    bd = d;
                    best = i;
                }
            }
            continue;
        }
        const fdt_kdnode *l = &t->nodes[nd->left], *r = l + 1;
        double dl = fdt_box_dist2_sc(l->lo, l->hi, q, 1.0), dr = fdt_box_dist2_sc(r->lo, r->hi, q, 1.0);
        /* Push the farther child first so the nearer one is searched first. */
        if (dl <= dr) {
            stack[sp++] = nd->left + 1;
            stack[sp++] = nd->left;
        } else {
            stack[sp++] = nd->left;
            stack[sp++] = nd->left + 1;
        }
    }
    return best;
}

int fdt_kd_ball(const fdt_kdtree *t, const double *c, double r,
                int (*fn)(void *user, uint32_t id), void *user, fdt_kdq *kq)
{
    uint32_t stack[WALK_STACK];
    int sp = 0;
    /* Widen by a relative 1e-12 so rounding in the distances never drops a
     * point the caller would accept exactly; compare in units where the
     * radius is near 1 (ball_scale). */
    double sc, r2;
    ball_scale(r * (1.0 + 1e-12), &sc, &r2);
    stack[sp++] = 0;
    while (sp > 0) {
        const fdt_kdnode *nd = &t->nodes[stack[--sp]];
        if (fdt_box_dist2_sc(nd->lo, nd->hi, c, sc) > r2)
            continue;
        if (kq)
            kq->nodes++;
        if (!nd->left) {
            for (uint32_t i = nd->begin; i < nd->end; i++)
                if (dist2_sc(t->P + 3 * (size_t)i, c, sc) <= r2) {
                    int rc = fn(user, i);
                    if (rc)
                        return rc;
                }
            continue;
        }
        stack[sp++] = nd->left;
        stack[sp++] = nd->left + 1;
    }
    return 0;
}

/* ---- the apex search ---------------------------------------------------- */

static double norm3(const double *v)
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

static void cross3(const double *u, const double *v, double *w)
{
    w[0] = u[1] * v[2] - u[2] * v[1];
    w[1] = u[2] * v[0] - u[0] * v[2];
    w[2] = u[0] * v[1] - u[1] * v[0];
}

void fdt_apex_init(fdt_apex *s, const double *a, const double *b,
                   const double *c, uint32_t ia, uint32_t ib, uint32_t ic)
{
    double u[3], v[3];
    s->a = a;
    s->b = b;
    s->c = c;
    s->ia = ia;
    s->ib = ib;
    s->ic = ic;
    for (int k = 0; k < 3; k++) {
        u[k] = b[k] - a[k];
        v[k] = c[k] - a[k];
    }
    cross3(u, v, s->nrm);
    s->nabs[0] = fabs(u[1] * v[2]) + fabs(u[2] * v[1]);
    s->nabs[1] = fabs(u[2] * v[0]) + fabs(u[0] * v[2]);
    s->nabs[2] = fabs(u[0] * v[1]) + fabs(u[1] * v[0]);
    s->best = FDT_NONE;
    s->bp = NULL;
    s->aimed = 0;
    memcpy(s->center, a, sizeof s->center); /* the target once aimed */
    s->sc = 1.0;
    s->r2 = INFINITY;
    s->rad = INFINITY;
    s->ver = 0;
}

/* The target, computed only when a search runs without a candidate: the
 * first guess (offer_likely_apex) nearly always gives one, and the target's
 * three square roots were a tenth of the setup of every face. */
void fdt_apex_aim(fdt_apex *s)
{
    if (s->aimed)
        return;
    s->aimed = 1;
    const double *a = s->a, *b = s->b, *c = s->c;
    double u[3], v[3];
    for (int k = 0; k < 3; k++) {
        u[k] = b[k] - a[k];
        v[k] = c[k] - a[k];
    }
    /* Look first where the apex of a well-shaped tet would be: above the
     * centroid by about half an edge. */
    double nn = norm3(s->nrm);
    double len = (norm3(u) + norm3(v)) * 0.5;
    for (int k = 0; k < 3; k++) {
        double g = (a[k] + b[k] + c[k]) / 3.0;
        s->target[k] = nn > 0 ? g + s->nrm[k] / nn * len * 0.6 : g;
    }
    if (s->best == FDT_NONE)
        memcpy(s->center, s->target, sizeof s->center); /* see apex_walk */
}

/*
 * Side of d relative to the face: +1 open side, 0 coplanar, -1 closed.
 * The floating value s = nrm . (d - a) errs by less than 1e-14 times the
 * permanent nabs . |d - a| (the exact bound is below 16 eps: the rounded
 * differences, the two products and the difference in each nrm component,
 * the three products and two sums of the dot product each add at most one
 * relative eps of their permanent term); outside that band its sign is
 * the exact orient3d sign, inside it we ask the exact predicate. Below a
 * permanent of 2^-800 products may have underflowed and the band itself
 * may round to zero, so such tiny configurations always go exact.
 */
static int open_side(const fdt_apex *s, const double *d, fdt_kdq *kq)
{
    double w0 = d[0] - s->a[0], w1 = d[1] - s->a[1], w2 = d[2] - s->a[2];
    double v = s->nrm[0] * w0 + s->nrm[1] * w1 + s->nrm[2] * w2;
    double perm = s->nabs[0] * fabs(w0) + s->nabs[1] * fabs(w1) + s->nabs[2] * fabs(w2);
    double tol = perm * 1e-14;
    if (perm >= 0x1p-800) {
        if (v > tol)
            return 1;
        if (v < -tol)
            return -1;
    }
    return fdt_orient3d(s->a, s->b, s->c, d, kq ? &kq->pc : NULL);
}

/*
 * Recomputes the conservative search ball after `best` changed. The
 * circumcentre x (relative to a) of the tet (a, b, c, best) is
 *   x = (|u|^2 (v x w) + |v|^2 (w x u) + |w|^2 (u x v)) / (2 u.(v x w)).
 * With K = |u||v||w| / det (>= 1 by Hadamard), the floating result errs by
 * O(eps K^2 L) (L the longest of u, v, w); we widen the radius by
 * 64 eps K (K + 1) L plus an absolute term for the coordinates' rounding,
 * and give up on the ball (infinite radius) when K > 1e6: such slivers
 * have enormous spheres anyway and the open-side test still prunes.
 */
/*
 * The ball of an ill-conditioned tet (K > 1e6: a sliver, or points of
 * very different magnitudes, where the floating bound above would be
 * useless): the centre from exact arithmetic (src/geom/predicates.c), each
 * component of x = centre - a within 2^-51 relative. Then the rounded
 * centre is off by at most 4 eps (amax + 2 xmax) in norm, the rounded
 * radius by 4 eps r, and the distances compared against the ball carry a
 * relative 5 eps: widening by 16 eps (r + amax + 2 xmax) covers all of it.
 * Before this, such tets got an infinite ball and every apex search that
 * met one scanned the whole open side: inputs mixing 1e-150, 1 and 1e150
 * ran in O(n) a face.
 */
static void update_ball_exact(fdt_apex *s)
{
    double x[3];
    if (fdt_circumcenter_exact(s->a, s->b, s->c, s->bp, x) != 0) {
        set_ball(s, INFINITY);
        return;
    }
    double xmax = 0.0, amax = 0.0;
    for (int k = 0; k < 3; k++) {
        s->center[k] = s->a[k] + x[k];
        xmax = fmax(xmax, fabs(x[k]));
        amax = fmax(amax, fabs(s->a[k]));
    }
    /* norm3 of x without overflow or underflow of the squares */
    double r = 0.0;
    if (xmax > 0.0) {
        double y0 = x[0] / xmax, y1 = x[1] / xmax, y2 = x[2] / xmax;
        r = xmax * sqrt(y0 * y0 + y1 * y1 + y2 * y2);
    }
    set_ball(s, r + 16.0 * DBL_EPSILON * (r + amax + 2.0 * xmax));
}

static void update_ball(fdt_apex *s)
{
    const double *a = s->a;
    double u[3], v[3], w[3], vw[3], wu[3], uv[3];
    double big = 0.0;
    for (int k = 0; k < 3; k++) {
        u[k] = s->b[k] - a[k];
        v[k] = s->c[k] - a[k];
        w[k] = s->bp[k] - a[k];
        /* ternaries, not fmax: gcc calls libm's fmax for its NaN rules */
        double m = fabs(u[k]) > fabs(v[k]) ? fabs(u[k]) : fabs(v[k]);
        m = m > fabs(w[k]) ? m : fabs(w[k]);
        big = big > m ? big : m;
    }
    /* Work in units of a power of two near the longest edge (exact), so
     * the degree-5 products below neither underflow nor overflow when the
     * input mixes magnitudes (1e-149 next to 1e151 after scaling). */
    int e;
    if (big >= DBL_MIN && big <= DBL_MAX) { /* normal: read the exponent */
        e = fdt_exp2_normal(big); /* big in [2^(e-1), 2^e) */
    } else {
        (void)frexp(big, &e);
    }
    /* Multiplying by 2^-e is the same exact scaling as ldexp and several
     * times cheaper than the library call (it was 9 % of a run): 2^-e and
     * 2^e are normal doubles for |e| <= 1000, i.e. whenever the longest
     * difference is not itself near the ends of the double range. */
    double down, up;
    if (e >= -1000 && e <= 1000) {
        down = fdt_pow2i(-e);
        up = fdt_pow2i(e);
    } else {
        down = up = 0.0; /* marks the ldexp path */
    }
    for (int k = 0; k < 3; k++) {
        u[k] = up != 0.0 ? u[k] * down : ldexp(u[k], -e);
        v[k] = up != 0.0 ? v[k] * down : ldexp(v[k], -e);
        w[k] = up != 0.0 ? w[k] * down : ldexp(w[k], -e);
    }
    cross3(v, w, vw);
    cross3(w, u, wu);
    cross3(u, v, uv);
    double det = u[0] * vw[0] + u[1] * vw[1] + u[2] * vw[2];
    double nu = norm3(u), nv = norm3(v), nw = norm3(w);
    double prod = nu * nv * nw;
    /* In these units the longest difference is near 1; one shorter than
     * 2^-200 (an edge 1e-164 long next to edges of 0.5, from an input that
     * mixes magnitudes) may have underflowed in its norm, and a zero norm
     * once made K look perfect: the floating centre was then off by 0.02
     * with a tolerance of 1e-16 and a point strictly inside the sphere was
     * missed (found by tests/fuzz/fuzz_mesh). Such tets go exact. */
    double shortest = nu < nv ? (nu < nw ? nu : nw) : (nv < nw ? nv : nw);
    if (!(det > 0.0) || !(prod < 1e6 * det) || !isfinite(prod) || !(shortest >= 0x1p-200)) {
        update_ball_exact(s);
        return;
    }
    double K = prod / det;
    double uu = nu * nu, vv = nv * nv, ww = nw * nw;
    double x[3], xs[3], xmax = 0.0, amax = 0.0;
    for (int k = 0; k < 3; k++) {
        xs[k] = (uu * vw[k] + vv * wu[k] + ww * uv[k]) / (2.0 * det);
        x[k] = up != 0.0 ? xs[k] * up : ldexp(xs[k], e);
        s->center[k] = a[k] + x[k];
        if (fabs(x[k]) > xmax)
            xmax = fabs(x[k]);
        if (fabs(a[k]) > amax)
            amax = fabs(a[k]);
    }
    double L = nu > nv ? (nu > nw ? nu : nw) : (nv > nw ? nv : nw);
    double r = norm3(xs); /* squares in the scaled units */
    L = up != 0.0 ? L * up : ldexp(L, e);
    r = up != 0.0 ? r * up : ldexp(r, e);
    double tol = 64.0 * DBL_EPSILON * K * (K + 1.0) * L + 8.0 * DBL_EPSILON * (amax + xmax);
    set_ball(s, r + tol);
}

/* The offer past its first test (below): out of line, so that the walk's
 * loop, which calls the test for every point, stays small and inlined. */
static void offer_inside(fdt_apex *s, uint32_t id, const double *d, fdt_kdq *kq)
{
    if ((id == s->ia) | (id == s->ib) | (id == s->ic) | (id == s->best))
        return;
    if (open_side(s, d, kq) <= 0)
        return;
    if (s->best != FDT_NONE &&
        fdt_insphere_perturbed(s->a, s->b, s->c, s->bp, d, kq ? &kq->pc : NULL) <= 0)
        return;
    s->best = id;
    s->bp = d;
    s->ver++;
    update_ball(s);
}

/* The ball first: most points fail it, and the face's vertices (on the
 * sphere) nearly always pass it. */
static inline void offer(fdt_apex *s, uint32_t id, const double *d, fdt_kdq *kq)
{
    if (s->best != FDT_NONE && dist2_sc(d, s->center, s->sc) > s->r2)
        return;
    offer_inside(s, id, d, kq);
}

void fdt_apex_offer(fdt_apex *s, uint32_t id, const double *d, fdt_kdq *kq)
{
    offer(s, id, d, kq);
}

/*
 * The exact half of the open-side box test, for boxes that touch the
 * face's plane within rounding: planar data (lidar ground, the layers of
 * an extruded grid, lattice faces) puts whole subtrees exactly in the
 * plane of hull faces, and without an exact answer every such face would
 * visit all of them. The plane function is linear, so its maximum over
 * the box is at the corner that takes hi[k] where the normal's component
 * k is positive and lo[k] where it is negative; a component whose sign the
 * rounding (at most 3 eps of its permanent) leaves open tries both. The
 * corners are coordinates of input points, so orient3d is exact on them.
 */
static int box_touches_open_side(const fdt_apex *s, const double *lo, const double *hi)
{
    int choice[3]; /* 1: hi, -1: lo, 0: both */
    for (int k = 0; k < 3; k++) {
        double tol = s->nabs[k] * 1e-15;
        choice[k] = s->nrm[k] > tol ? 1 : (s->nrm[k] < -tol ? -1 : 0);
    }
    for (int m = 0; m < 8; m++) {
        double q[3];
        int skip = 0;
        for (int k = 0; k < 3 && !skip; k++) {
            int bit = (m >> k) & 1;
            if (choice[k] != 0 && bit)
                skip = 1; /* only the 0 bit is used for a decided axis */
            q[k] = choice[k] == 1 ? hi[k] : choice[k] == -1 ? lo[k] : (bit ? hi[k] : lo[k]);
        }
        if (!skip && fdt_orient3d(s->a, s->b, s->c, q, NULL) > 0)
            return 1;
    }
    return 0;
}

/* The half-space half of fdt_apex_box_useful: whether the box reaches
 * the open side of the face's plane. */
static int box_open_bounded(const fdt_apex *s, const double *lo, const double *hi)
{
    /* Largest value of nrm . (x - a) over the box, against a margin for
     * rounding in the same spirit as open_side's. */
    /* Per axis the larger of the two corner terms, from the differences
     * hi - a and lo - a, each within one rounding of its own size (a box
     * midpoint would carry an error relative to the coordinates, not to
     * the differences, which voids the margin on tiny clouds far from the
     * origin: found on points 2^-12 apart at 2^40). */
    double mx = 0.0, perm = 0.0;
    for (int k = 0; k < 3; k++) {
        double dl = lo[k] - s->a[k], dh = hi[k] - s->a[k];
        double tl = s->nrm[k] * dl, th = s->nrm[k] * dh;
        mx += tl > th ? tl : th;
        perm += s->nabs[k] * (fabs(dl) > fabs(dh) ? fabs(dl) : fabs(dh));
    }
    if (perm >= 0x1p-800) {
        if (mx < -perm * 1e-13)
            return 0;
        if (mx > perm * 1e-13)
            return 1;
    }
    /* Near the plane, or so small that underflow voids the bound. */
    return box_touches_open_side(s, lo, hi);
}

static inline int box_open(const fdt_apex *s, const double *lo, const double *hi)
{
    /* The common answer first, and cheaply: answering 1 is always safe
     * (it only costs a visit), so a positive floating value at the
     * corner farthest along the normal settles it without error bounds.
     * The walk's boxes nearly all reach the open side (98 % of nodes,
     * 200k uniform points). */
    const double *n = s->nrm, *a = s->a;
    double q = 0.0;
    for (int k = 0; k < 3; k++) {
        double th = n[k] * (hi[k] - a[k]), tl = n[k] * (lo[k] - a[k]);
        q += th > tl ? th : tl; /* a maximum, not a branch on n's sign */
    }
    return q > 0.0 || box_open_bounded(s, lo, hi);
}

int fdt_apex_box_useful(const fdt_apex *s, const double *lo, const double *hi)
{
    if (s->best != FDT_NONE && fdt_box_dist2_sc(lo, hi, s->center, s->sc) > s->r2)
        return 0;
    return box_open(s, lo, hi);
}

/* c ? x : y by bit masks. gcc 12 compiled the walk's ternary on the
 * nearer child's distance to a branch, mispredicted at every other inner
 * node (8 % of a run's mispredictions, cachegrind --branch-sim, 50k). */
static inline double pick(uint32_t c, double x, double y)
{
    uint64_t m = (uint64_t)0 - (uint64_t)c, xb, yb;
    memcpy(&xb, &x, sizeof xb);
    memcpy(&yb, &y, sizeof yb);
    xb = (xb & m) | (yb & ~m);
    memcpy(&x, &xb, sizeof x);
    return x;
}

/* Bit (id - begin) if id is in the leaf [begin, begin + n), n <= 64, else 0. */
static inline uint64_t leaf_bit(uint32_t id, uint32_t begin, uint32_t n)
{
    uint32_t o = id - begin;
    return (uint64_t)(o < n) << (o & 63);
}

/* All of a leaf's n <= 64 points, as a mask. */
static inline uint64_t low_bits(uint32_t n)
{
    return n >= 64 ? ~UINT64_C(0) : (UINT64_C(1) << n) - 1;
}

/*
 * The mask of the points of leaf nd (n <= 64 points, a float block) that
 * may lie in the ball (s->center, s->rad): it holds every point whose
 * exact distance to the centre is at most rad, and so (the ball holds the
 * sphere) every point that can improve s; it may hold more, which the
 * exact offer turns away.
 *
 * Why the margins suffice, in the leaf's frame (units of 1/sl): each X is
 * within 2^-23 of the scaled difference (float blocks, above), each of
 * the centre's C = fl32((c - lo) sl) within 2^-23 M (M its largest
 * |component|), so with eps = 2^-23 (1 + M) each float difference X - C
 * is within eps + 2^-24 |X - C| of (x - c) sl. A point at distance at
 * most R = rad sl then has |X - C| (1 - 2^-24) <= R + sqrt(3) eps, and
 * the float sum of squares (four roundings, each relative 2^-24, plus
 * underflow below 2^-146) is at most (R + 2 eps)^2 (1 + 2^-21) + 2^-146:
 * below the threshold T, which adds a relative 2^-19 to cover its own
 * rounding to float too. Balls 2^40 times the leaf or centres that far
 * away keep every point (T would lose nothing worth the arithmetic);
 * every comparison is "not greater", so a NaN keeps its point.
 */
/* The kernels of leaf_mask_fl: bit j set where (X_j - C)^2 is not above T,
 * for j < n rounded up to the lanes (the caller masks the padding). The
 * same float operations lane by lane in every version (no FMA: the
 * build's -ffp-contract=off, and the AVX2 target does not enable it). */
static uint64_t mask_sse(const float *B, uint32_t row, uint32_t n, const float C[3], float T)
{
    uint64_t m = 0;
#if defined(__SSE2__)
    __m128 C0 = _mm_set1_ps(C[0]), C1 = _mm_set1_ps(C[1]), C2 = _mm_set1_ps(C[2]);
    __m128 TT = _mm_set1_ps(T);
    for (uint32_t j = 0; j < n; j += 4) {
        __m128 dx = _mm_sub_ps(_mm_load_ps(B + j), C0);
        __m128 dy = _mm_sub_ps(_mm_load_ps(B + row + j), C1);
        __m128 dz = _mm_sub_ps(_mm_load_ps(B + 2 * row + j), C2);
        __m128 d2 = _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)),
                               _mm_mul_ps(dz, dz));
        m |= (uint64_t)_mm_movemask_ps(_mm_cmpngt_ps(d2, TT)) << j;
    }
#else
    for (uint32_t j = 0; j < n; j++) {
        float dx = B[j] - C[0], dy = B[row + j] - C[1], dz = B[2 * row + j] - C[2];
        float d2 = dx * dx + dy * dy + dz * dz;
        m |= (uint64_t)!(d2 > T) << j;
    }
#endif
    return m;
}

#if FDT_KD_AVX2
__attribute__((target("avx2"))) static uint64_t mask_avx2(const float *B, uint32_t row, uint32_t n,
                                                          const float C[3], float T)
{
    uint64_t m = 0;
    __m256 C0 = _mm256_set1_ps(C[0]), C1 = _mm256_set1_ps(C[1]), C2 = _mm256_set1_ps(C[2]);
    __m256 TT = _mm256_set1_ps(T);
    for (uint32_t j = 0; j < n; j += 8) {
        __m256 dx = _mm256_sub_ps(_mm256_load_ps(B + j), C0);
        __m256 dy = _mm256_sub_ps(_mm256_load_ps(B + row + j), C1);
        __m256 dz = _mm256_sub_ps(_mm256_load_ps(B + 2 * row + j), C2);
        __m256 d2 = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(dx, dx), _mm256_mul_ps(dy, dy)),
                                  _mm256_mul_ps(dz, dz));
        m |= (uint64_t)(uint32_t)_mm256_movemask_ps(_mm256_cmp_ps(d2, TT, _CMP_NGT_UQ)) << j;
    }
    return m;
}
#endif

static uint64_t leaf_mask_fl(const fdt_apex *s, const fdt_kdtree *t, const fdt_kdnode *nd,
                             uint32_t n)
{
    double sl = leaf_scale(nd);
    double R = s->rad * sl;
    double c0 = (s->center[0] - nd->lo[0]) * sl, c1 = (s->center[1] - nd->lo[1]) * sl,
           c2 = (s->center[2] - nd->lo[2]) * sl;
    double M = fabs(c0) > fabs(c1) ? fabs(c0) : fabs(c1);
    M = M > fabs(c2) ? M : fabs(c2);
    if (!(sl > 0.0) || !(R <= 0x1p40) || !(M <= 0x1p40))
        return low_bits(n);
    double eps = 0x1p-23 * (1.0 + M);
    double T = (R + 2.0 * eps) * (R + 2.0 * eps) * (1.0 + 0x1p-19) + 0x1p-140;
    const float *B = t->fl + 4 * (size_t)nd->dim;
    float C[3] = {(float)c0, (float)c1, (float)c2};
#if FDT_KD_AVX2
    if (t->avx2)
        return mask_avx2(B, block_row(n), n, C, (float)T) & low_bits(n);
#endif
    return mask_sse(B, block_row(n), n, C, (float)T) & low_bits(n);
}

/* Top-down walk of the subtree at `root`, nearer child first, pruning
 * every node whose box cannot hold an improvement. A child's distance to
 * the ball, computed to order it, is kept with it on the stack and
 * reused when it is popped if the ball has not changed since (s->ver):
 * recomputing it was a fifth of the box tests' cost. */
static void apex_walk(fdt_apex *s, const fdt_kdtree *t, uint32_t root,
                      double root_d2, fdt_kdq *kq)
{
    uint32_t stack[WALK_STACK], sver[WALK_STACK];
    double sd2[WALK_STACK];
    int sp = 0;
    if (s->best == FDT_NONE)
        fdt_apex_aim(s); /* order the children by the target */
    /* root_d2: the root's distance to the current ball, from the caller */
    stack[sp] = root;
    sd2[sp] = root_d2;
    sver[sp++] = s->ver;
    /* The tests below are written to compile to selects and arithmetic
     * where their outcome is a coin toss: mispredicted branches were a
     * third of a run's cycles (cachegrind --branch-sim, 200k uniform:
     * 156 M mispredictions against 13.4 G instructions). While best is
     * FDT_NONE, r2 is INFINITY and center is the target, so the ball
     * tests pass everything without a test of their own. */
    while (sp > 0) {
        sp--;
        const fdt_kdnode *nd = &t->nodes[stack[sp]];
        double d2 = sver[sp] == s->ver ? sd2[sp] : fdt_box_dist2_sc(nd->lo, nd->hi, s->center, s->sc);
        /* The open-side test rejects only about 1.5 % of the inner nodes
         * a finite ball leaves (200k uniform), so inner nodes take it
         * only while there is no finite ball (hull faces, the first
         * candidates), where it is the only pruning; leaves always. */
        if (d2 > s->r2 || ((!nd->left | !(s->r2 < INFINITY)) && !box_open(s, nd->lo, nd->hi)))
            continue;
        kq->nodes++;
        if (!nd->left) {
            uint32_t n = nd->end - nd->begin;
            const double *P = t->P + 3 * (size_t)nd->begin;
            kq->points += n;
            if (s->best == FDT_NONE || n > 64) {
                for (uint32_t j = 0; j < n; j++)
                    offer(s, nd->begin + j, P + 3 * (size_t)j, kq);
                continue;
            }
            /* Which points are inside the ball, as a mask (no branch a
             * point); the few inside are offered in order. A ball that
             * shrinks meanwhile only loses points (the pencil argument
             * below), and offer tests each against the current one.
             * Every ball test here and below is written "not outside",
             * !(d2 > r2), as offer's is: a NaN distance must keep the
             * point or node, never drop it. */
            uint64_t m = 0;
            if (t->fl)
                m = leaf_mask_fl(s, t, nd, n);
            else
                for (uint32_t j = 0; j < n; j++)
                    m |= (uint64_t)!(dist2_sc(P + 3 * (size_t)j, s->center, s->sc) > s->r2) << j;
            /* a, b and c lie on every sphere of the pencil and best on
             * the current one, so they pass the ball test, to be turned
             * away by offer's id test: a branch mispredicted about twice
             * a face (cachegrind, 50k). Their bits go here instead. */
            m &= ~(leaf_bit(s->ia, nd->begin, n) | leaf_bit(s->ib, nd->begin, n) |
                   leaf_bit(s->ic, nd->begin, n) | leaf_bit(s->best, nd->begin, n));
            while (m) {
                uint32_t j = (uint32_t)fdt_ctz64(m);
                m &= m - 1;
                offer(s, nd->begin + j, P + 3 * (size_t)j, kq);
            }
            continue;
        }
        const fdt_kdnode *l = &t->nodes[nd->left], *r = l + 1;
        /* Without a best yet, center is the target (fdt_apex_init) and
         * ver 0, which no later ball has: the distances order the
         * children by the target and are never reused against a ball. */
        double dl = fdt_box_dist2_sc(l->lo, l->hi, s->center, s->sc);
        double dr = fdt_box_dist2_sc(r->lo, r->hi, s->center, s->sc);
        /* A child outside the current ball is dropped at once rather than
         * when popped: later balls are spheres of the same pencil through
         * a, b, c with a smaller parameter, whose open-side part lies
         * inside this one's, so such a child can never become useful.
         * The nearer child is pushed last, so it is popped first. */
        uint32_t sw = dr < dl;
        uint32_t near = nd->left + sw, far = nd->left + 1 - sw;
        double dnear = pick(sw, dr, dl), dfar = pick(sw, dl, dr);
        stack[sp] = far;
        sd2[sp] = dfar;
        sver[sp] = s->ver;
        sp += !(dfar > s->r2);
        stack[sp] = near;
        sd2[sp] = dnear;
        sver[sp] = s->ver;
        sp += !(dnear > s->r2);
    }
}

void fdt_apex_search(fdt_apex *s, const fdt_kdtree *t, fdt_kdq *kq)
{
    const fdt_kdnode *rt = &t->nodes[0];
    apex_walk(s, t, 0, fdt_box_dist2_sc(rt->lo, rt->hi, s->center, s->sc), kq);
}

/* The kernels of guess_leaf_fl: the least quotient (|W|^2 - G.W) / (N.W)
 * over the usable lanes (N.W > 0, in the leaf, not b or c), as *bt and its
 * offset *bi (-1, INFINITY if none). F holds A, G and N, 3 each. */
static void guess_sse(const float *B, uint32_t row, uint32_t n, const float F[9], int32_t xb,
                      int32_t xc, float *bt, int32_t *bi)
{
    float lt[4];
    int32_t li[4];
#if defined(__SSE2__)
    __m128 A0 = _mm_set1_ps(F[0]), A1 = _mm_set1_ps(F[1]), A2 = _mm_set1_ps(F[2]);
    __m128 G0 = _mm_set1_ps(F[3]), G1 = _mm_set1_ps(F[4]), G2 = _mm_set1_ps(F[5]);
    __m128 N0 = _mm_set1_ps(F[6]), N1 = _mm_set1_ps(F[7]), N2 = _mm_set1_ps(F[8]);
    __m128 inf = _mm_set1_ps(INFINITY), zero = _mm_setzero_ps(), vbt = inf;
    __m128i lane = _mm_set_epi32(3, 2, 1, 0), vbi = _mm_set1_epi32(-1), four = _mm_set1_epi32(4);
    __m128i vn = _mm_set1_epi32((int32_t)n), vb = _mm_set1_epi32(xb), vc = _mm_set1_epi32(xc);
    for (uint32_t j = 0; j < n; j += 4) {
        __m128 wx = _mm_sub_ps(_mm_load_ps(B + j), A0);
        __m128 wy = _mm_sub_ps(_mm_load_ps(B + row + j), A1);
        __m128 wz = _mm_sub_ps(_mm_load_ps(B + 2 * row + j), A2);
        __m128 ww = _mm_add_ps(_mm_add_ps(_mm_mul_ps(wx, wx), _mm_mul_ps(wy, wy)), _mm_mul_ps(wz, wz));
        __m128 gw = _mm_add_ps(_mm_add_ps(_mm_mul_ps(G0, wx), _mm_mul_ps(G1, wy)), _mm_mul_ps(G2, wz));
        __m128 h = _mm_add_ps(_mm_add_ps(_mm_mul_ps(N0, wx), _mm_mul_ps(N1, wy)), _mm_mul_ps(N2, wz));
        __m128 q = _mm_div_ps(_mm_sub_ps(ww, gw), h);
        /* usable: h > 0, in the leaf (padding lanes are not), not b or c */
        __m128i bad = _mm_or_si128(_mm_cmpeq_epi32(lane, vb), _mm_cmpeq_epi32(lane, vc));
        bad = _mm_or_si128(bad, _mm_xor_si128(_mm_cmpgt_epi32(vn, lane), _mm_set1_epi32(-1)));
        __m128 ok = _mm_andnot_ps(_mm_castsi128_ps(bad), _mm_cmpgt_ps(h, zero));
        q = _mm_or_ps(_mm_and_ps(ok, q), _mm_andnot_ps(ok, inf));
        __m128i take = _mm_castps_si128(_mm_cmplt_ps(q, vbt));
        vbt = _mm_min_ps(q, vbt);
        vbi = _mm_or_si128(_mm_and_si128(take, lane), _mm_andnot_si128(take, vbi));
        lane = _mm_add_epi32(lane, four);
    }
    _mm_storeu_ps(lt, vbt);
    _mm_storeu_si128((__m128i *)li, vbi);
#else
    for (int l = 0; l < 4; l++) {
        lt[l] = INFINITY;
        li[l] = -1;
    }
    for (uint32_t j = 0; j < n; j++) {
        float wx = B[j] - F[0], wy = B[row + j] - F[1], wz = B[2 * row + j] - F[2];
        float ww = wx * wx + wy * wy + wz * wz;
        float gw = F[3] * wx + F[4] * wy + F[5] * wz;
        float h = F[6] * wx + F[7] * wy + F[8] * wz;
        if (!(h > 0.0f) || (int32_t)j == xb || (int32_t)j == xc)
            continue;
        float q = (ww - gw) / h;
        if (q < lt[j & 3]) {
            lt[j & 3] = q;
            li[j & 3] = (int32_t)j;
        }
    }
#endif
    int lb = 0;
    for (int l = 1; l < 4; l++)
        if (lt[l] < lt[lb])
            lb = l;
    *bt = lt[lb];
    *bi = li[lb];
}

#if FDT_KD_AVX2
__attribute__((target("avx2"))) static void guess_avx2(const float *B, uint32_t row, uint32_t n,
                                                       const float F[9], int32_t xb, int32_t xc,
                                                       float *bt, int32_t *bi)
{
    float lt[8];
    int32_t li[8];
    __m256 A0 = _mm256_set1_ps(F[0]), A1 = _mm256_set1_ps(F[1]), A2 = _mm256_set1_ps(F[2]);
    __m256 G0 = _mm256_set1_ps(F[3]), G1 = _mm256_set1_ps(F[4]), G2 = _mm256_set1_ps(F[5]);
    __m256 N0 = _mm256_set1_ps(F[6]), N1 = _mm256_set1_ps(F[7]), N2 = _mm256_set1_ps(F[8]);
    __m256 inf = _mm256_set1_ps(INFINITY), zero = _mm256_setzero_ps(), vbt = inf;
    __m256i lane = _mm256_set_epi32(7, 6, 5, 4, 3, 2, 1, 0), vbi = _mm256_set1_epi32(-1);
    __m256i eight = _mm256_set1_epi32(8), ones = _mm256_set1_epi32(-1);
    __m256i vn = _mm256_set1_epi32((int32_t)n), vb = _mm256_set1_epi32(xb), vc = _mm256_set1_epi32(xc);
    for (uint32_t j = 0; j < n; j += 8) {
        __m256 wx = _mm256_sub_ps(_mm256_load_ps(B + j), A0);
        __m256 wy = _mm256_sub_ps(_mm256_load_ps(B + row + j), A1);
        __m256 wz = _mm256_sub_ps(_mm256_load_ps(B + 2 * row + j), A2);
        __m256 ww = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(wx, wx), _mm256_mul_ps(wy, wy)),
                                  _mm256_mul_ps(wz, wz));
        __m256 gw = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(G0, wx), _mm256_mul_ps(G1, wy)),
                                  _mm256_mul_ps(G2, wz));
        __m256 h = _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(N0, wx), _mm256_mul_ps(N1, wy)),
                                 _mm256_mul_ps(N2, wz));
        __m256 q = _mm256_div_ps(_mm256_sub_ps(ww, gw), h);
        __m256i bad = _mm256_or_si256(_mm256_cmpeq_epi32(lane, vb), _mm256_cmpeq_epi32(lane, vc));
        bad = _mm256_or_si256(bad, _mm256_xor_si256(_mm256_cmpgt_epi32(vn, lane), ones));
        __m256 ok = _mm256_andnot_ps(_mm256_castsi256_ps(bad), _mm256_cmp_ps(h, zero, _CMP_GT_OQ));
        q = _mm256_blendv_ps(inf, q, ok);
        __m256 take = _mm256_cmp_ps(q, vbt, _CMP_LT_OQ);
        vbt = _mm256_min_ps(q, vbt);
        vbi = _mm256_castps_si256(
            _mm256_blendv_ps(_mm256_castsi256_ps(vbi), _mm256_castsi256_ps(lane), take));
        lane = _mm256_add_epi32(lane, eight);
    }
    _mm256_storeu_ps(lt, vbt);
    _mm256_storeu_si256((__m256i *)li, vbi);
    int lb = 0;
    for (int l = 1; l < 8; l++)
        if (lt[l] < lt[lb])
            lb = l;
    *bt = lt[lb];
    *bi = li[lb];
}
#endif

/*
 * The least tau over leaf nd's points from its float block, in the units
 * of tau_c(x) = (|x - a|^2 - g.(x - a)) / (N.(x - a)) (g = 2 (cc - a); a
 * positive multiple of tau): *best and *tau, or FDT_NONE and INFINITY.
 * In the leaf's frame W = X - A and G = g sl are the differences scaled by
 * sl, and ns is N times 2^-en (its largest component in [0.5, 1), so the
 * floats neither overflow nor underflow), which makes the float quotient
 * tau_c sl 2^en. Returns 0, and leaves the leaf to the double scan, where
 * the leaf has no frame or a or the circumcentre is 2^40 leaf sizes
 * away. The id and sign masks are those of the double scan below.
 */
static int guess_leaf_fl(const fdt_apex *s, const fdt_kdtree *t, const fdt_kdnode *nd,
                         const double *g, const double *ns, double inv_en,
                         uint32_t *best, double *tau)
{
    double sl = leaf_scale(nd), M = 0.0;
    float F[9];
    for (int k = 0; k < 3; k++) {
        double A = (s->a[k] - nd->lo[k]) * sl, G = g[k] * sl;
        M = M > fabs(A) ? M : fabs(A);
        M = M > fabs(G) ? M : fabs(G);
        F[k] = (float)A;
        F[3 + k] = (float)G;
        F[6 + k] = (float)ns[k];
    }
    if (!(sl > 0.0) || !(M <= 0x1p40))
        return 0;
    uint32_t n = nd->end - nd->begin, row = block_row(n);
    const float *B = t->fl + 4 * (size_t)nd->dim;
    /* b and c as offsets in the leaf: anything from 0 to n - 1 only if
     * they are in it (the unsigned difference wraps otherwise) */
    int32_t xb = (int32_t)(s->ib - nd->begin), xc = (int32_t)(s->ic - nd->begin);
    float bt;
    int32_t bi;
#if FDT_KD_AVX2
    if (t->avx2)
        guess_avx2(B, row, n, F, xb, xc, &bt, &bi);
    else
#endif
        guess_sse(B, row, n, F, xb, xc, &bt, &bi);
    *best = bi >= 0 && bt < INFINITY ? nd->begin + (uint32_t)bi : FDT_NONE;
    /* sl = 2^(s - 1), s = fdt_exp2_normal(sl), so 1 / sl = 2^(1 - s),
     * exactly and without a division */
    double inv_sl = fdt_pow2i(1 - fdt_exp2_normal(sl));
    *tau = *best != FDT_NONE ? (double)bt * inv_sl * inv_en : INFINITY;
    return 1;
}

/* The same from the doubles, one point at a time. */
static void guess_leaf_d(const fdt_apex *s, const fdt_kdtree *t, const fdt_kdnode *nd,
                         const double *g, uint32_t *best, double *tau)
{
    const double *a = s->a, *N = s->nrm;
    double best_tau = INFINITY;
    uint32_t bi = FDT_NONE;
    for (uint32_t i = nd->begin; i < nd->end; i++) {
        const double *x = t->P + 3 * (size_t)i;
        double w0 = x[0] - a[0], w1 = x[1] - a[1], w2 = x[2] - a[2];
        double h = N[0] * w0 + N[1] * w1 + N[2] * w2;
        double q = (w0 * w0 + w1 * w1 + w2 * w2) - (g[0] * w0 + g[1] * w1 + g[2] * w2);
        /* tau = h > 0 ? q / h : INFINITY, with the sign of h (and
         * the ids of b and c) as a bit mask: written as a select or
         * as conditions of `take`, gcc 12 branched on them, on the
         * sign a coin toss a point (perf, 1M uniform), on the ids a
         * miss at b and at c (cachegrind, 50k). Where the mask is 0
         * the quotient (inf, NaN, anything) is discarded; an
         * overflowing one only spoils the order, never the result. */
        double tq = q / h;
        uint64_t tb, pos = (uint64_t)0 - (uint64_t)((h > 0.0) & (i != s->ib) & (i != s->ic));
        memcpy(&tb, &tq, sizeof tb);
        tb = (tb & pos) | (UINT64_C(0x7ff0000000000000) & ~pos);
        memcpy(&tq, &tb, sizeof tq);
        int take = tq < best_tau;
        bi = take ? i : bi;
        best_tau = take ? tq : best_tau;
    }
    *best = bi;
    *tau = best_tau;
}

/*
 * Offers first the point of the face vertices' leaves that floating point
 * says is the apex: every sphere through a, b, c has its centre at
 * cc + t N (cc the triangle's circumcentre, N its normal), and a point x
 * on the open side
 * lies inside the one with t > tau(x) = (|x - cc|^2 - |a - cc|^2) /
 * (2 N.(x - a)), so the apex is the point of least tau. Offered in index
 * order, the leaf's points improved the best candidate about 7 times a
 * face, each time recomputing the ball (update_ball) and leaving a larger
 * ball than necessary for the climb. This is only an ordering: the offer
 * decides exactly, as for every other point.
 *
 * The candidates are the points of the leaves of all three face vertices
 * that lie in t (one to three distinct leaves), not of `leaf` alone: on
 * 200k uniform points the apex is in a's leaf for 34 % of the faces and in
 * one of the three leaves for 63 %, and wherever it is there the least
 * tau finds it, so the first ball is the final one that often. b and c
 * are left out by id: on the sphere, their floating h and q are rounding
 * noise, and either could pose as the least tau (a's h is exactly 0).
 */
static void offer_likely_apex(fdt_apex *s, const fdt_kdtree *t, uint32_t leaf,
                              fdt_kdq *kq)
{
    uint32_t leaves[3] = {leaf, leaf, leaf};
    int nl = 1;
    const uint32_t other[2] = {s->ib, s->ic};
    for (int k = 0; k < 2; k++) {
        /* In the parallel engine b and c may belong to other parts,
         * whose points this tree does not hold. */
        if (other[k] - t->base >= t->n)
            continue;
        uint32_t l = t->leafof[other[k] - t->base];
        if (l != leaves[0] && l != leaves[1])
            leaves[nl++] = l;
    }
    const double *a = s->a, *N = s->nrm;
    double u[3], v[3], m[3], cc[3], g[3];
    for (int k = 0; k < 3; k++) {
        u[k] = s->b[k] - a[k];
        v[k] = s->c[k] - a[k];
    }
    double nn = N[0] * N[0] + N[1] * N[1] + N[2] * N[2];
    if (!(nn > 0.0) || !(nn < INFINITY))
        return;
    double uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
    double vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    for (int k = 0; k < 3; k++)
        m[k] = uu * v[k] - vv * u[k];
    cross3(m, N, cc); /* 2 nn (cc - a) */
    for (int k = 0; k < 3; k++)
        g[k] = cc[k] / nn; /* 2 (cc - a): |x - cc|^2 - |a - cc|^2 = |w|^2 - g.w */
    /* N scaled by 2^-en for the float scan (guess_leaf_fl) */
    double nmax = fabs(N[0]) > fabs(N[1]) ? fabs(N[0]) : fabs(N[1]);
    nmax = nmax > fabs(N[2]) ? nmax : fabs(N[2]);
    double ns[3] = {0.0, 0.0, 0.0}, inv_en = 0.0;
    if (t->fl && nmax >= DBL_MIN && nmax <= DBL_MAX) {
        int en = fdt_exp2_normal(nmax);
        if (en >= -1000 && en <= 1000) {
            inv_en = fdt_pow2i(-en);
            for (int k = 0; k < 3; k++)
                ns[k] = N[k] * inv_en;
        }
    }
    double best_tau = INFINITY;
    uint32_t best = FDT_NONE;
    for (int li = 0; li < nl; li++) {
        const fdt_kdnode *nd = &t->nodes[leaves[li]];
        uint32_t lb;
        double lt;
        if (!(inv_en > 0.0) || !guess_leaf_fl(s, t, nd, g, ns, inv_en, &lb, &lt))
            guess_leaf_d(s, t, nd, g, &lb, &lt);
        if (lt < best_tau) {
            best_tau = lt;
            best = lb;
        }
    }
    if (best != FDT_NONE)
        fdt_apex_offer(s, best, t->P + 3 * (size_t)best, kq);
}

/*
 * Bottom-up variant. The apex lies near the face, so we start in the leaf
 * holding `start` (a face vertex) and climb. Each node's *cell* -- the
 * region its ancestors' split planes give it, not its points' bounding
 * box -- holds every point of the tree inside it that is not in a sibling
 * subtree; left children take coordinates <= the split value, right ones
 * >= it. Once the search ball lies strictly inside the current node's
 * cell, no point outside the node can be inside the ball, so the climb
 * stops. Otherwise the sibling subtree is walked top-down and we go up.
 * On uniform clouds this skips most of the root-to-leaf descent and its
 * box tests. The leaf, the parents and the cells come from the tables of
 * climb_tables.
 */
/* Whether the ball of s lies strictly inside the cell of node. */
static inline int ball_inside_cell(const fdt_apex *s, const fdt_kdtree *t, uint32_t node)
{
    if (s->best == FDT_NONE || !isfinite(s->r2))
        return 0;
    double r = s->rad; /* the ball itself, unscaled */
    const double *c = s->center, (*cl)[3] = t->cell[node];
    return (c[0] - r > cl[0][0]) & (c[0] + r < cl[1][0]) & (c[1] - r > cl[0][1]) &
           (c[1] + r < cl[1][1]) & (c[2] - r > cl[0][2]) & (c[2] + r < cl[1][2]);
}

int fdt_apex_inside_region(const fdt_apex *s, const fdt_kdtree *t)
{
    /* The root's cell is the region (climb_tables); a tree without climb
     * tables has no region but all of space. */
    return t->cell ? ball_inside_cell(s, t, 0) : 0;
}

void fdt_apex_guess(fdt_apex *s, const fdt_kdtree *t, uint32_t start, fdt_kdq *kq)
{
    if (t->leafof)
        offer_likely_apex(s, t, t->leafof[start - t->base], kq);
}

int fdt_apex_search_from(fdt_apex *s, const fdt_kdtree *t, uint32_t start, fdt_kdq *kq)
{
    fdt_apex_guess(s, t, start, kq);
    return fdt_apex_verify_from(s, t, start, kq);
}

int fdt_apex_verify_from(fdt_apex *s, const fdt_kdtree *t, uint32_t start, fdt_kdq *kq)
{
    if (!t->leafof) { /* not a tree of fdt_kd_build: no climb tables */
        fdt_apex_search(s, t, kq);
        return 0;
    }
    uint32_t node = t->leafof[start - t->base];
    const fdt_kdnode *nd = &t->nodes[node];
    apex_walk(s, t, node, fdt_box_dist2_sc(nd->lo, nd->hi, s->center, s->sc), kq);
    while (node != 0) {
        if (ball_inside_cell(s, t, node))
            return 1;
        uint32_t parent = t->parent[node], l = t->nodes[parent].left;
        uint32_t sib = l + (node == l);
        /* The sibling's ball test here rather than in a walk of its own:
         * most siblings of the climb lie outside the ball (4.9 sibling
         * walks a face, 50k uniform), and a walk costs a call and a
         * stack before its first test. */
        nd = &t->nodes[sib];
        double d2 = fdt_box_dist2_sc(nd->lo, nd->hi, s->center, s->sc);
        if (!(d2 > s->r2))
            apex_walk(s, t, sib, d2, kq);
        node = parent;
    }
    /* The whole tree is searched; the root's cell is its region
     * (fdt_kd_set_region; all of space unless set). */
    return ball_inside_cell(s, t, 0);
}

typedef struct inside_ctx {
    const fdt_kdtree *t;
    const uint32_t *v;
    const double *p[4];
    fdt_kdq *kq;
    uint32_t found;
} inside_ctx;

static int inside_cb(void *user, uint32_t id)
{
    inside_ctx *ic = user;
    for (int k = 0; k < 4; k++)
        if (id == ic->v[k])
            return 0;
    const double *d = ic->t->P + 3 * (size_t)id;
    if (fdt_insphere_perturbed(ic->p[0], ic->p[1], ic->p[2], ic->p[3], d,
                               ic->kq ? &ic->kq->pc : NULL) > 0) {
        ic->found = id;
        return 1;
    }
    return 0;
}

uint32_t fdt_kd_any_inside(const fdt_kdtree *t, const uint32_t v[4], fdt_kdq *kq)
{
    inside_ctx ic = {t, v, {0}, kq, FDT_NONE};
    for (int k = 0; k < 4; k++)
        ic.p[k] = t->P + 3 * (size_t)v[k];
    /* Reuse the apex machinery's conservative ball for (a, b, c, d). */
    fdt_apex s;
    fdt_apex_init(&s, ic.p[0], ic.p[1], ic.p[2], v[0], v[1], v[2]);
    s.best = v[3];
    s.bp = ic.p[3];
    update_ball(&s);
    double r = isfinite(s.r2) ? sqrt(s.r2) / s.sc : INFINITY;
    if (!isfinite(r)) {
        for (uint32_t i = t->base; i < t->base + t->n; i++)
            if (inside_cb(&ic, i))
                break;
        return ic.found;
    }
    fdt_kd_ball(t, s.center, r, inside_cb, &ic, kq);
    return ic.found;
}
