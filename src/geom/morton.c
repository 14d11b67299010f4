/* Points in Morton order: see morton.h. */
#include "geom/morton.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

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

/*
 * a[0 .. n) sorted on its bits [lo, hi), ties in the order they come. Up
 * to SPLIT records, least significant digit first over the whole array
 * (lsd_sort). Past it the top 8 of those bits first (one pass of a
 * counting sort: each bucket a cell of the box, 39k points a bucket at
 * 10M uniform), then each bucket on the bits below, the passes inside the
 * cache: the passes of the whole array through memory were the sort's
 * time there, while on fewer points the buckets' own counts would cost
 * more than they save (bench/NOTES.md entry 118). tmp: n entries. The
 * sorted array is a or tmp: returned; NULL when out of memory.
 */
static uint64_t *radix_sort(uint64_t *a, uint64_t *tmp, size_t n, int lo, int hi)
{
    enum { BITS = 11, B = 1 << BITS, NTOP = 1 << 8, SMALL = 32 };
    const size_t SPLIT = (size_t)1 << 21;
    int top = hi - 8;
    size_t *count = malloc((B + NTOP) * sizeof *count), *start = count + B;
    if (!count)
        return NULL;
    if (n < SPLIT || top <= lo || !digit_pass(a, tmp, n, top, NTOP, start)) {
        uint64_t *r = lsd_sort(a, tmp, n, lo, n < SPLIT || top <= lo ? hi : top, count);
        free(count);
        return r;
    }
    /* start[d] is now bucket d's end; tmp holds the buckets */
    uint64_t kmask = ~((UINT64_C(1) << lo) - 1);
    for (size_t d = 0, b0 = 0; d < NTOP; b0 = start[d], d++) {
        size_t m = start[d] - b0;
        uint64_t *b = tmp + b0;
        if (m <= SMALL) {
            for (size_t i = 1; i < m; i++) {
                uint64_t x = b[i];
                size_t j = i;
                for (; j > 0 && (b[j - 1] & kmask) > (x & kmask); j--)
                    b[j] = b[j - 1];
                b[j] = x;
            }
            continue;
        }
        uint64_t *got = lsd_sort(b, a + b0, m, lo, top, count);
        if (got != b)
            memcpy(b, got, m * sizeof *b);
    }
    free(count);
    return tmp;
}

/* The records of the points not skipped, sorted by key (index ascending
 * within a key); *m: how many. NULL when out of memory; the caller frees
 * *block. */
static uint64_t *sorted_records(const double *pts, size_t n, const double box[6],
                                const uint8_t *skip, layout l, size_t *m, uint64_t **block)
{
    uint64_t *r = malloc(2 * (n ? n : 1) * sizeof *r);
    *block = r;
    if (!r)
        return NULL;
    size_t k = 0;
    for (size_t i = 0; i < n; i++)
        if (!skip || !skip[i])
            r[k++] = morton(pts + 3 * i, box, l.bits) << l.idbits | (uint64_t)i;
    *m = k;
    return radix_sort(r, r + (n ? n : 1), k, l.idbits, l.idbits + 3 * l.bits);
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

int fdt_morton_sort(double *pts, fdt_vid *orig, size_t n)
{
    double box[6] = {0, 0, 0, 0, 0, 0};
    for (size_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) {
            double x = pts[3 * i + k];
            if (i == 0 || x < box[k])
                box[k] = x;
            if (i == 0 || x > box[k + 3])
                box[k + 3] = x;
        }
    size_t m;
    layout l = layout_of(n);
    uint64_t *block, *s = sorted_records(pts, n, box, NULL, l, &m, &block);
    if (!s) {
        free(block);
        return -1;
    }
    /* The points gathered into a new array (independent loads: an
     * in-place walk of the permutation's cycles, each load waiting for
     * the last, took twice as long: entry 126); their indices into the
     * records' other half, free now (4 bytes of its 8 a point). */
    double *p2 = malloc((n ? n : 1) * 3 * sizeof *p2);
    if (!p2) {
        free(block);
        return -1;
    }
    fdt_vid *o2 = (fdt_vid *)(s == block ? block + (n ? n : 1) : block);
    for (size_t i = 0; i < n; i++) {
        size_t k = (size_t)(s[i] & l.idmask);
        const double *q = pts + 3 * k;
        p2[3 * i] = q[0];
        p2[3 * i + 1] = q[1];
        p2[3 * i + 2] = q[2];
        o2[i] = orig[k];
    }
    memcpy(pts, p2, n * 3 * sizeof *pts);
    memcpy(orig, o2, n * sizeof *orig);
    free(p2);
    free(block);
    return 0;
}
