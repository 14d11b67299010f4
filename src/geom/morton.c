/* Points in Morton order: see morton.h. */
#include "geom/morton.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/mem.h"
#include "base/spawn.h"

/*
 * A point's record: its key in the high bits, its index in the low
 * `idbits` (the fewest that hold n - 1), so that a record is 8 bytes
 * whatever the point count and a sort on the key bits alone, stable,
 * leaves ties by index. The key takes `bits` a coordinate, 21 where the
 * index leaves room (up to 2^1 points), else what it leaves: 14 at 1M
 * points (a cell 2^-14 of the box: 4e12 cells for 1e6 points), 12 at
 * 100M, 10 at 2^32. Half the bytes of a 16-byte key and id, and the
 * insertion order only needs nearby points close together (bench/NOTES.md
 * entry 126).
 */
typedef struct layout {
    int idbits, bits;
    uint64_t idmask;
} layout;

static layout layout_of(size_t n)
{
    layout l;
    l.idbits = 1;
    while (l.idbits < 64 && ((uint64_t)(n ? n - 1 : 0) >> l.idbits) != 0)
        l.idbits++;
    l.bits = (64 - l.idbits) / 3 < 21 ? (64 - l.idbits) / 3 : 21;
    l.idmask = l.idbits == 64 ? ~UINT64_C(0) : (UINT64_C(1) << l.idbits) - 1;
    return l;
}

/* The 21 low bits of x spread to every third bit (bit i to bit 3i). */
static inline uint64_t spread3(uint64_t x)
{
    x &= 0x1fffff;
    x = (x | x << 32) & UINT64_C(0x1f00000000ffff);
    x = (x | x << 16) & UINT64_C(0x1f0000ff0000ff);
    x = (x | x << 8) & UINT64_C(0x100f00f00f00f00f);
    x = (x | x << 4) & UINT64_C(0x10c30c30c30c30c3);
    x = (x | x << 2) & UINT64_C(0x1249249249249249);
    return x;
}

/* `bits` bits of each coordinate in the box, interleaved x, y, z from the
 * top (x's bit above y's above z's at each level). */
static uint64_t morton(const double *p, const double box[6], int bits)
{
    uint64_t c[3];
    double top = (double)((UINT64_C(1) << bits) - 1);
    for (int k = 0; k < 3; k++) {
        double w = box[k + 3] - box[k];
        double t = w > 0 ? (p[k] - box[k]) / w : 0;
        t = t > 0 ? (t < 1 ? t : 1) : 0; /* NaN too: 0 */
        c[k] = (uint64_t)(t * top);
    }
    return spread3(c[0]) << 2 | spread3(c[1]) << 1 | spread3(c[2]);
}

/* One stable counting-sort pass of a[0 .. n) into tmp on the digit
 * a[i] >> shift & (nb - 1), count holding nb entries: 1, with count[d]
 * the end of digit d's run in tmp; or 0, nothing moved, when every record
 * has the same digit. */
static int digit_pass(const uint64_t *a, uint64_t *tmp, size_t n, int shift, size_t nb,
                      size_t *count)
{
    memset(count, 0, nb * sizeof *count);
    for (size_t i = 0; i < n; i++)
        count[a[i] >> shift & (nb - 1)]++;
    if (n == 0 || count[a[0] >> shift & (nb - 1)] == n)
        return 0;
    size_t acc = 0;
    for (size_t d = 0; d < nb; d++) {
        size_t c = count[d];
        count[d] = acc;
        acc += c;
    }
    for (size_t i = 0; i < n; i++)
        tmp[count[a[i] >> shift & (nb - 1)]++] = a[i];
    return 1;
}

/* a[0 .. n) sorted on its bits [lo, hi), ties in the order they come:
 * least significant digit first, 11 bits a pass (digit_pass), a pass
 * skipped where every record has the same digit; count: 2^11 entries.
 * tmp: n entries. The sorted array is a or tmp: returned. */
static uint64_t *lsd_sort(uint64_t *a, uint64_t *tmp, size_t n, int lo, int hi, size_t *count)
{
    enum { BITS = 11 };
    for (int shift = lo; shift < hi; shift += BITS) {
        int w = hi - shift < BITS ? hi - shift : BITS;
        if (digit_pass(a, tmp, n, shift, (size_t)1 << w, count)) {
            uint64_t *t = a;
            a = tmp;
            tmp = t;
        }
    }
    return a;
}

/* The sort's threads: each a slice of the records (or of the buckets),
 * run phase by phase with fdt_fork_join. */
enum { BITS = 11, NB = 1 << BITS, NTOP = 1 << 8, SMALL = 32, MAX_T = 16 };
enum { PH_BOX, PH_KEYS, PH_COUNT, PH_SCATTER, PH_BUCKETS, PH_GATHER };

typedef struct msort msort;
typedef struct mjob {
    msort *s;
    int t;
    size_t lo, hi;       /* its records (PH_BUCKETS: its buckets) */
    double box[6];       /* PH_BOX: its points' */
    size_t count[NB];    /* PH_COUNT: its digits; then where each goes */
} mjob;

struct msort {
    const double *pts;
    const fdt_vid *orig;
    double *p2;
    fdt_vid *o2;
    uint64_t *a, *tmp;  /* the records, and as many more */
    size_t n;
    layout l;
    double box[6];
    int phase, shift;
    size_t nb;          /* this pass's digits */
    size_t start[NTOP]; /* the top pass's buckets' ends (in tmp) */
    int lo, top;        /* the buckets' bits [lo, top) */
    int T;
    mjob job[MAX_T];
};

/* Sorts tmp's buckets [j->lo, j->hi) (of the top pass) on the bits below
 * the top, each back into tmp (a's same rows as scratch). */
static void sort_buckets(msort *s, mjob *j)
{
    uint64_t kmask = ~((UINT64_C(1) << s->lo) - 1);
    size_t *count = j->count;
    for (size_t d = j->lo; d < j->hi; d++) {
        size_t b0 = d ? s->start[d - 1] : 0, m = s->start[d] - b0;
        uint64_t *b = s->tmp + b0;
        if (m <= SMALL) {
            for (size_t i = 1; i < m; i++) {
                uint64_t x = b[i];
                size_t k = i;
                for (; k > 0 && (b[k - 1] & kmask) > (x & kmask); k--)
                    b[k] = b[k - 1];
                b[k] = x;
            }
            continue;
        }
        uint64_t *got = lsd_sort(b, s->a + b0, m, s->lo, s->top, count);
        if (got != b)
            memcpy(b, got, m * sizeof *b);
    }
}

static void *msort_run(void *arg)
{
    mjob *j = arg;
    msort *s = j->s;
    switch (s->phase) {
    case PH_BOX:
        for (size_t i = j->lo; i < j->hi; i++)
            for (int k = 0; k < 3; k++) {
                double x = s->pts[3 * i + (size_t)k];
                if (i == j->lo || x < j->box[k])
                    j->box[k] = x;
                if (i == j->lo || x > j->box[k + 3])
                    j->box[k + 3] = x;
            }
        break;
    case PH_KEYS:
        for (size_t i = j->lo; i < j->hi; i++)
            s->a[i] = morton(s->pts + 3 * i, s->box, s->l.bits) << s->l.idbits | (uint64_t)i;
        break;
    case PH_COUNT:
        memset(j->count, 0, s->nb * sizeof *j->count);
        for (size_t i = j->lo; i < j->hi; i++)
            j->count[s->a[i] >> s->shift & (s->nb - 1)]++;
        break;
    case PH_SCATTER:
        for (size_t i = j->lo; i < j->hi; i++)
            s->tmp[j->count[s->a[i] >> s->shift & (s->nb - 1)]++] = s->a[i];
        break;
    case PH_BUCKETS:
        sort_buckets(s, j);
        break;
    case PH_GATHER:
        for (size_t i = j->lo; i < j->hi; i++) {
            size_t k = (size_t)(s->a[i] & s->l.idmask);
            const double *q = s->pts + 3 * k;
            s->p2[3 * i] = q[0];
            s->p2[3 * i + 1] = q[1];
            s->p2[3 * i + 2] = q[2];
            s->o2[i] = s->orig[k];
        }
        break;
    }
    return NULL;
}

static void msort_phase(msort *s, int phase)
{
    s->phase = phase;
    fdt_fork_join(s->job, sizeof *s->job, s->T, msort_run);
}

/*
 * One stable counting-sort pass of s->a into s->tmp on the digit of nb
 * values at `shift`, the threads' slices in order (thread t's records of
 * a digit after thread t - 1's): 1 and swapped, or 0, nothing moved, when
 * every record has the same digit. With the top pass (nb NTOP), s->start
 * gets the buckets' ends.
 */
static int msort_pass(msort *s, int shift, size_t nb)
{
    s->shift = shift;
    s->nb = nb;
    msort_phase(s, PH_COUNT);
    size_t acc = 0, full = 0;
    for (size_t d = 0; d < nb; d++) {
        size_t before = acc;
        for (int t = 0; t < s->T; t++) {
            size_t c = s->job[t].count[d];
            s->job[t].count[d] = acc;
            acc += c;
        }
        full |= acc - before == s->n;
        if (nb == NTOP)
            s->start[d] = acc;
    }
    if (full)
        return 0;
    msort_phase(s, PH_SCATTER);
    uint64_t *x = s->a;
    s->a = s->tmp;
    s->tmp = x;
    return 1;
}

/* The threads' slices of n records (or buckets), in order. */
static void msort_slices(msort *s, size_t n)
{
    for (int t = 0; t < s->T; t++) {
        s->job[t].s = s;
        s->job[t].t = t;
        s->job[t].lo = n * (size_t)t / (size_t)s->T;
        s->job[t].hi = n * (size_t)(t + 1) / (size_t)s->T;
    }
}

/*
 * s->a sorted on its bits [lo, hi), ties in the order they come (s->a
 * then holds them). Up to SPLIT records, least significant digit first
 * over the whole array, 11 bits a pass, a pass skipped where every record
 * has the same digit. Past it the top 8 of those bits first (one pass of
 * a counting sort: each bucket a cell of the box, 39k points a bucket at
 * 10M uniform), then each bucket on the bits below, the passes inside the
 * cache, the buckets shared among the threads by their records: the
 * passes of the whole array through memory were the sort's time there,
 * while on fewer points the buckets' own counts would cost more than they
 * save (bench/NOTES.md entry 118).
 */
static void msort_radix(msort *s, int lo, int hi)
{
    const size_t SPLIT = (size_t)1 << 21;
    s->lo = lo;
    s->top = hi - 8;
    if (s->n >= SPLIT && s->top > lo && msort_pass(s, s->top, NTOP)) {
        /* s->a holds the buckets: sort them in place, each thread a run
         * of buckets holding about its share of the records */
        uint64_t *x = s->a;
        s->a = s->tmp;
        s->tmp = x;
        size_t d = 0;
        for (int t = 0; t < s->T; t++) {
            size_t want = s->n * (size_t)(t + 1) / (size_t)s->T;
            s->job[t].lo = d;
            while (d < NTOP && (t == s->T - 1 || s->start[d] <= want))
                d++;
            s->job[t].hi = d;
        }
        msort_phase(s, PH_BUCKETS);
        x = s->a;
        s->a = s->tmp;
        s->tmp = x;
        msort_slices(s, s->n);
        return;
    }
    for (int shift = lo; shift < hi; shift += BITS)
        msort_pass(s, shift, (size_t)1 << (hi - shift < BITS ? hi - shift : BITS));
}

/*
 * Runs of more than REFINE records with one key, each sorted again on keys
 * of its own points' box, and so on down (ties by index in the end): the
 * order of a Morton curve refined where the points are dense. A fixed grid
 * puts a cluster 1e-6 wide of a unit box (gen_points `clusters`) in one
 * cell of 2^-15, and its 18k points then came in input order: the
 * insertion's walks crossed the cluster each time, and its mesh took
 * twice as long as with 21 bits a coordinate (bench/NOTES.md entry 126).
 * Each level's box lies in one cell of the level above, 2^bits times
 * smaller on every axis, so a run of points that are not all equal comes
 * apart within a few hundred levels, and equal points (possible in
 * fdt_morton_order's inputs) end it at once.
 */
enum { REFINE = 32 };

static void refine(const double *pts, uint64_t *a, uint64_t *tmp, size_t n, layout l,
                   size_t *count);

static void refine_run(const double *pts, uint64_t *r, uint64_t *tmp, size_t m, layout l,
                       size_t *count)
{
    /* the box of the finite coordinates (queries may be NaN or infinite:
     * fdt_queries_begin orders them too) */
    double box[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < m; i++) {
        const double *q = pts + 3 * (size_t)(r[i] & l.idmask);
        for (int k = 0; k < 3; k++)
            if (isfinite(q[k])) {
                box[k] = fmin(box[k], q[k]);
                box[k + 3] = fmax(box[k + 3], q[k]);
            }
    }
    for (int k = 0; k < 3; k++)
        if (box[k] > box[k + 3])
            box[k] = box[k + 3] = 0;
    if (box[0] == box[3] && box[1] == box[4] && box[2] == box[5])
        return; /* one point, repeated: the index order stays */
    for (size_t i = 0; i < m; i++) {
        uint64_t id = r[i] & l.idmask;
        r[i] = morton(pts + 3 * (size_t)id, box, l.bits) << l.idbits | id;
    }
    uint64_t *got = lsd_sort(r, tmp, m, l.idbits, l.idbits + 3 * l.bits, count);
    if (got != r)
        memcpy(r, got, m * sizeof *r);
    /* Down only where this level split the run: every level then works
     * on fewer records, whatever the coordinates (finite ones always
     * split: the box's lowest and highest points take the first and last
     * cell of an axis). */
    if ((r[0] & ~l.idmask) != (r[m - 1] & ~l.idmask))
        refine(pts, r, tmp, m, l, count);
}

/* a[0 .. n) sorted by key, ties by index: its long runs refined. tmp: n
 * records of scratch; count: 2^11 entries. */
static void refine(const double *pts, uint64_t *a, uint64_t *tmp, size_t n, layout l,
                   size_t *count)
{
    uint64_t kmask = ~l.idmask;
    for (size_t i = 0, j; i < n; i = j) {
        for (j = i + 1; j < n && (a[j] & kmask) == (a[i] & kmask); j++)
            ;
        if (j - i > REFINE)
            refine_run(pts, a + i, tmp + i, j - i, l, count);
    }
}

/* The records of the points not skipped, sorted by key (index ascending
 * within a key); *m: how many. NULL when out of memory; the caller frees
 * *block. One thread (the cells' and queries' orders). */
static uint64_t *sorted_records(const double *pts, size_t n, const double box[6],
                                const uint8_t *skip, layout l, size_t *m, uint64_t **block)
{
    uint64_t *r = fdt_mem_alloc_huge(2 * (n ? n : 1), sizeof *r, 0);
    *block = r;
    if (!r)
        return NULL;
    size_t k = 0;
    for (size_t i = 0; i < n; i++)
        if (!skip || !skip[i])
            r[k++] = morton(pts + 3 * i, box, l.bits) << l.idbits | (uint64_t)i;
    *m = k;
    msort *s = calloc(1, sizeof *s);
    if (!s)
        return NULL;
    s->a = r;
    s->tmp = r + (n ? n : 1);
    s->n = k;
    s->T = 1;
    msort_slices(s, k);
    msort_radix(s, l.idbits, l.idbits + 3 * l.bits);
    refine(pts, s->a, s->tmp, k, l, s->job[0].count);
    uint64_t *sorted = s->a;
    free(s);
    return sorted;
}

long fdt_morton_order(const double *pts, size_t n, const double box[6], const uint8_t *skip,
                      uint32_t *order)
{
    size_t m;
    layout l = layout_of(n);
    uint64_t *block, *s = sorted_records(pts, n, box, skip, l, &m, &block);
    if (s)
        for (size_t i = 0; i < m; i++)
            order[i] = (uint32_t)(s[i] & l.idmask);
    free(block);
    return s ? (long)m : -1;
}

int fdt_morton_sort(double *pts, fdt_vid *orig, size_t n, int threads)
{
    msort *s = calloc(1, sizeof *s);
    uint64_t *block = fdt_mem_alloc_huge(2 * (n ? n : 1), sizeof *block, 0);
    /* The points gathered into a new array (independent loads: an in-place
     * walk of the permutation's cycles, each load waiting for the last,
     * took twice as long: entry 126); their indices into the records'
     * other half, free by then (4 bytes of its 8 a point). Both arrays
     * fresh, on huge pages (a 4 KB fault is a trap on some hosts: entry
     * 128). */
    double *p2 = fdt_mem_alloc_huge((n ? n : 1) * 3, sizeof *p2, 0);
    if (!s || !block || !p2) {
        free(s);
        free(block);
        free(p2);
        return -1;
    }
    s->pts = pts;
    s->orig = orig;
    s->n = n;
    s->l = layout_of(n);
    s->a = block;
    s->tmp = block + (n ? n : 1);
    s->p2 = p2;
    /* a thread for every 32k points at least: below, starting one costs
     * more than its share */
    s->T = threads < 1 ? 1 : threads > MAX_T ? MAX_T : threads;
    while (s->T > 1 && n / (size_t)s->T < ((size_t)1 << 15))
        s->T--;
    msort_slices(s, n);
    msort_phase(s, PH_BOX);
    for (int t = 0; t < s->T; t++)
        for (int k = 0; k < 3; k++)
            if (s->job[t].hi > s->job[t].lo) {
                const double *b = s->job[t].box;
                s->box[k] = t == 0 || b[k] < s->box[k] ? b[k] : s->box[k];
                s->box[k + 3] = t == 0 || b[k + 3] > s->box[k + 3] ? b[k + 3] : s->box[k + 3];
            }
    msort_phase(s, PH_KEYS);
    msort_radix(s, s->l.idbits, s->l.idbits + 3 * s->l.bits);
    refine(pts, s->a, s->tmp, n, s->l, s->job[0].count);
    s->o2 = (fdt_vid *)s->tmp;
    msort_phase(s, PH_GATHER);
    memcpy(pts, p2, n * 3 * sizeof *pts);
    memcpy(orig, s->o2, n * sizeof *orig);
    free(p2);
    free(block);
    free(s);
    return 0;
}
