/* Order-independent sums of doubles (src/mesh/voronoi.c, issue 32).
 *
 * A Voronoi cell's volume is the sum of its tets' shares, and the tets
 * arrive in an order that depends on the thread count, the mode and the
 * input order. Floating sums, even compensated ones, round differently in
 * each order. Here every term is first rounded onto one fixed grid, 2^e
 * (e chosen by the caller from the domain's size), and the grid values are
 * summed as 128-bit integers: integer addition is associative, so the sum
 * is the same bits in every order, and partial sums (threads, ranks) are
 * merged by adding them.
 *
 * Range: a term rounds to round(x 2^-e) and must stay below 2^126 in
 * magnitude, as must every partial sum: the caller picks e so that its
 * largest term is about 2^100 grid steps (src/mesh/voronoi.c: e =
 * exponent of diameter^k - 100), which leaves 2^26 terms of headroom and
 * 2^-100 of the domain's scale as the grid step. Two 64-bit words rather
 * than a compiler's __int128, so that it builds on every Debian port.
 */
#ifndef FDT_FIXSUM_H
#define FDT_FIXSUM_H

#include <math.h>
#include <stdint.h>

typedef struct fdt_fix {
    uint64_t lo;
    int64_t hi; /* two's complement: value = hi 2^64 + lo */
} fdt_fix;

/* acc += round(x 2^-e), x finite with |x 2^-e| < 2^126. The rounding is
 * llrint's (the current mode, to nearest by default) for |x 2^-e| < 2^62;
 * above that x 2^-e is an integer already (53 bits of significand). */
static inline void fdt_fix_add(fdt_fix *acc, double x, int e)
{
    double y = ldexp(x, -e);
    uint64_t lo;
    int64_t hi;
    if (fabs(y) < 0x1p62) {
        int64_t q = llrint(y);
        lo = (uint64_t)q;
        hi = q < 0 ? -1 : 0;
    } else {
        /* y is an integer; y = h 2^64 + l with h = floor(y 2^-64) and
         * 0 <= l < 2^64: l keeps the bits of y below 2^64, so it is exact. */
        double h = floor(ldexp(y, -64));
        double l = y - ldexp(h, 64);
        hi = (int64_t)h;
        lo = (uint64_t)l;
    }
    uint64_t s = acc->lo + lo;
    acc->hi += hi + (s < lo);
    acc->lo = s;
}

/* acc += b (merging partial sums). */
static inline void fdt_fix_merge(fdt_fix *acc, fdt_fix b)
{
    uint64_t s = acc->lo + b.lo;
    acc->hi += b.hi + (s < b.lo);
    acc->lo = s;
}

/* The sum times 2^e, as a double: the magnitude's two words are converted
 * apart and added (both nonnegative, so no cancellation), which rounds at
 * most twice: within 2^-52 relative of the exact sum, and the same bits for
 * the same sum. */
static inline double fdt_fix_value(fdt_fix a, int e)
{
    int neg = a.hi < 0;
    if (neg) { /* two's complement negation of the 128-bit value */
        a.lo = ~a.lo + 1;
        a.hi = (int64_t)(~(uint64_t)a.hi + (a.lo == 0));
    }
    double m = ldexp((double)(uint64_t)a.hi, 64) + (double)a.lo;
    return ldexp(neg ? -m : m, e);
}

#endif
