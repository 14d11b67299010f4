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
 * largest term is about 2^102 grid steps (src/mesh/voronoi.c: terms up to
 * about 16 D^k for the box's largest side D, e = k exponent(D) - 98),
 * which leaves 2^24 terms of headroom and 2^-98 of D^k as the grid step. Two 64-bit words rather
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

/* The grid 2^e's two scales: inv = 2^-e and step = 2^e (-1022 <= e <=
 * 1023 and the terms' range as above, so that x inv is exact or, below
 * 2^-1022, rounds to the same 0 as the grid would). */
typedef struct fdt_fix_grid {
    double inv, step;
} fdt_fix_grid;

static inline fdt_fix_grid fdt_fix_grid_of(int e)
{
    fdt_fix_grid g = {ldexp(1.0, -e), ldexp(1.0, e)};
    return g;
}

/* acc += b (merging partial sums). */
static inline void fdt_fix_merge(fdt_fix *acc, fdt_fix b)
{
    uint64_t s = acc->lo + b.lo;
    acc->hi += b.hi + (s < b.lo);
    acc->lo = s;
}

/* acc += round(x 2^-e), x finite with |x 2^-e| < 2^126. y = x 2^-e is
 * split exactly as h 2^63 + r: h = trunc(y 2^-63) (a scaling by a power of
 * two, then a truncation: |h| < 2^63), r = y - h 2^63 (exact: 2^63 times
 * the fraction of y 2^-63, which a double holds; |r| < 2^63). Where y
 * has bits below 1 (|y| < 2^52), h = 0 and r = y is rounded by llrint,
 * in the current mode (to nearest by default); elsewhere r is an integer
 * already. No branch: the terms' signs are a coin flip. */
static inline void fdt_fix_add(fdt_fix *acc, double x, fdt_fix_grid g)
{
    double y = x * g.inv;
    int64_t h = (int64_t)(y * 0x1p-63);
    int64_t r = llrint(y - (double)h * 0x1p63);
    /* h 2^63 is (h >> 1) 2^64 + (h & 1) 2^63 (>> rounds down); r is
     * sign-extended */
    uint64_t lo = (uint64_t)h << 63, s = lo + (uint64_t)r;
    fdt_fix term = {s, (h >> 1) + (r >> 63) + (s < lo)};
    fdt_fix_merge(acc, term);
}

/* The sum times 2^e, as a double: the magnitude's two words are converted
 * apart and added (both nonnegative, so no cancellation), which rounds at
 * most twice: within 2^-52 relative of the exact sum, and the same bits for
 * the same sum. The low word is converted as two exact 32-bit halves whose
 * sum rounds once, as (double)lo does: baseline x86-64 converts only
 * signed words, and its unsigned conversion branches on the top bit, a
 * coin flip here (a fifth of the Voronoi cells' summing pass); the high
 * word's top bit is clear for every sum in range, a branch predicted. */
static inline double fdt_fix_value(fdt_fix a, fdt_fix_grid g)
{
    int neg = a.hi < 0;
    if (neg) { /* two's complement negation of the 128-bit value */
        a.lo = ~a.lo + 1;
        a.hi = (int64_t)(~(uint64_t)a.hi + (a.lo == 0));
    }
    double lo = (double)(int64_t)(a.lo >> 32) * 0x1p32 + (double)(int64_t)(a.lo & 0xffffffffu);
    double m = (double)(uint64_t)a.hi * 0x1p64 + lo;
    return (neg ? -m : m) * g.step;
}

#endif
