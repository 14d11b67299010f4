/* Points in Morton order: see morton.h. */
#include "geom/morton.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct keyed {
    uint64_t key;
    uint32_t id;
} keyed;

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

/* 21 bits of each coordinate in the box, interleaved x, y, z from the
 * top (x's bit above y's above z's at each level). */
static uint64_t morton(const double *p, const double box[6])
{
    uint64_t c[3];
    for (int k = 0; k < 3; k++) {
        double w = box[k + 3] - box[k];
        double t = w > 0 ? (p[k] - box[k]) / w : 0;
        t = t > 0 ? (t < 1 ? t : 1) : 0; /* NaN too: 0 */
        c[k] = (uint64_t)(t * 2097151.0);
    }
    return spread3(c[0]) << 2 | spread3(c[1]) << 1 | spread3(c[2]);
}

/* One stable counting-sort pass of a[0 .. n) into tmp on the digit
 * key >> shift & (nb - 1), count holding nb entries: 1, with count[d] the
 * end of digit d's run in tmp; or 0, nothing moved, when every key has
 * the same digit. */
static int digit_pass(const keyed *a, keyed *tmp, size_t n, int shift, size_t nb,
                      size_t *count)
{
    memset(count, 0, nb * sizeof *count);
    for (size_t i = 0; i < n; i++)
        count[a[i].key >> shift & (nb - 1)]++;
    if (n == 0 || count[a[0].key >> shift & (nb - 1)] == n)
        return 0;
    size_t acc = 0;
    for (size_t d = 0; d < nb; d++) {
        size_t c = count[d];
        count[d] = acc;
        acc += c;
    }
    for (size_t i = 0; i < n; i++)
        tmp[count[a[i].key >> shift & (nb - 1)]++] = a[i];
    return 1;
}

/* a[0 .. n) sorted by key on the bits below `bits`, ties in the order
 * they come: least significant digit first, 11 bits a pass (digit_pass),
 * a pass skipped where every key has the same digit; count: 2^11
 * entries. tmp: n entries. The sorted array is a or tmp: returned. */
static keyed *lsd_sort(keyed *a, keyed *tmp, size_t n, int bits, size_t *count)
{
    enum { BITS = 11 };
    for (int shift = 0; shift < bits; shift += BITS)
        if (digit_pass(a, tmp, n, shift, (size_t)1 << BITS, count)) {
            keyed *t = a;
            a = tmp;
            tmp = t;
        }
    return a;
}

/*
 * a[0 .. n) sorted by its 63-bit keys, ties in the order they come (ids
 * ascending when they came so). Up to SPLIT points, least significant
 * digit first over the whole array (lsd_sort). Past it the top 8 bits
 * first (one pass of a counting sort: each bucket a cell of the box,
 * 39k points a bucket at 10M uniform), then each bucket on the 55 bits
 * below, five passes inside the cache: six passes of the whole array
 * through memory were the sort's time there, while on fewer points the
 * buckets' own counts would cost more than they save (bench/NOTES.md
 * entry 118). tmp: n entries. The sorted array is a or tmp: returned.
 */
static keyed *radix_sort(keyed *a, keyed *tmp, size_t n)
{
    enum { BITS = 11, B = 1 << BITS, TOP = 55, NTOP = 1 << (63 - TOP), SMALL = 32 };
    const size_t SPLIT = (size_t)1 << 21;
    size_t *count = malloc((B + NTOP) * sizeof *count), *start = count + B;
    if (!count)
        return NULL;
    if (n < SPLIT || !digit_pass(a, tmp, n, TOP, NTOP, start)) {
        keyed *r = lsd_sort(a, tmp, n, n < SPLIT ? 63 : TOP, count);
        free(count);
        return r;
    }
    /* start[d] is now bucket d's end; tmp holds the buckets */
    for (size_t d = 0, lo = 0; d < NTOP; lo = start[d], d++) {
        size_t m = start[d] - lo;
        keyed *b = tmp + lo;
        if (m <= SMALL) {
            for (size_t i = 1; i < m; i++) {
                keyed x = b[i];
                size_t j = i;
                for (; j > 0 && b[j - 1].key > x.key; j--)
                    b[j] = b[j - 1];
                b[j] = x;
            }
            continue;
        }
        keyed *got = lsd_sort(b, a + lo, m, TOP, count);
        if (got != b)
            memcpy(b, got, m * sizeof *b);
    }
    free(count);
    return tmp;
}

/* The keys of the points not skipped, sorted (ids ascending within a key);
 * *m: how many. NULL when out of memory; the caller frees *block. */
static keyed *sorted_keys(const double *pts, size_t n, const double box[6], const uint8_t *skip,
                          size_t *m, keyed **block)
{
    keyed *kp = malloc(2 * (n ? n : 1) * sizeof *kp);
    *block = kp;
    if (!kp)
        return NULL;
    size_t k = 0;
    for (size_t i = 0; i < n; i++)
        if (!skip || !skip[i])
            kp[k++] = (keyed){morton(pts + 3 * i, box), (uint32_t)i};
    *m = k;
    return radix_sort(kp, kp + (n ? n : 1), k);
}

long fdt_morton_order(const double *pts, size_t n, const double box[6], const uint8_t *skip,
                      uint32_t *order)
{
    size_t m;
    keyed *block, *s = sorted_keys(pts, n, box, skip, &m, &block);
    if (s)
        for (size_t i = 0; i < m; i++)
            order[i] = s[i].id;
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
    keyed *block, *s = sorted_keys(pts, n, box, NULL, &m, &block);
    double *p2 = s ? malloc((n ? n : 1) * 3 * sizeof *p2) : NULL;
    fdt_vid *o2 = p2 ? malloc((n ? n : 1) * sizeof *o2) : NULL;
    if (!o2) {
        free(p2);
        free(block);
        return -1;
    }
    for (size_t i = 0; i < n; i++) {
        const double *q = pts + 3 * (size_t)s[i].id;
        p2[3 * i] = q[0];
        p2[3 * i + 1] = q[1];
        p2[3 * i + 2] = q[2];
        o2[i] = orig[s[i].id];
    }
    memcpy(pts, p2, n * 3 * sizeof *pts);
    memcpy(orig, o2, n * sizeof *orig);
    free(o2);
    free(p2);
    free(block);
    return 0;
}
