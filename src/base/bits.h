/* Small helpers shared by modules: bit scans (src/geom/kdtree.c, src/front/faceq.c,
 * src/mesh/result.c), powers of two from a double's bits (src/geom/kdtree.c,
 * src/geom/prepare.c), a prefetch hint (src/front/facetab.h, src/geom/prepare.c,
 * src/mesh/check.c) and four ids in ascending order (src/par/engine.c,
 * src/par/parallel.c). */
#ifndef FDT_BITS_H
#define FDT_BITS_H

#include <stdint.h>
#include <string.h>

/* 2^k for -1022 <= k <= 1023, built from its bits: exact, and several
 * times cheaper than ldexp(1.0, k). */
static inline double fdt_pow2i(int k)
{
    uint64_t b = (uint64_t)(k + 1023) << 52;
    double x;
    memcpy(&x, &b, sizeof x);
    return x;
}

/* For a normal x > 0 (DBL_MIN <= x <= DBL_MAX): the e with x in
 * [2^(e-1), 2^e), frexp's exponent, read from the bits. */
static inline int fdt_exp2_normal(double x)
{
    uint64_t b;
    memcpy(&b, &x, sizeof b);
    return (int)((b >> 52) & 0x7ff) - 1022;
}

/* s[0..3] in ascending order (a 5-comparator sorting network, as
 * src/io/write/fmt_tets.c's sort4 for its signed ids). */
static inline void fdt_sort4_u32(uint32_t s[4])
{
    static const int ij[5][2] = {{0, 1}, {2, 3}, {0, 2}, {1, 3}, {1, 2}};
    for (int c = 0; c < 5; c++) {
        uint32_t x = s[ij[c][0]], y = s[ij[c][1]];
        s[ij[c][0]] = x < y ? x : y;
        s[ij[c][1]] = x < y ? y : x;
    }
}

/* Index of the lowest set bit of m != 0. */
static inline int fdt_ctz64(uint64_t m)
{
#if defined(__GNUC__)
    return __builtin_ctzll(m);
#else
    int k = 0;
    while (!(m & 1)) {
        m >>= 1;
        k++;
    }
    return k;
#endif
}

/* Number of leading zero bits of x != 0. */
static inline int fdt_clz32(uint32_t x)
{
#if defined(__GNUC__)
    return __builtin_clz(x);
#else
    int k = 0;
    while (!(x & 0x80000000u)) {
        x <<= 1;
        k++;
    }
    return k;
#endif
}

/* Asks the memory system for the line at p; a hint only, no effect on
 * results. always_inline is not a detail: GCC counts __builtin_prefetch
 * as free of side effects, so its IPA pass (local-pure-const) found an
 * out-of-line copy of a wrapper like this "const", and the calls, whose
 * result is void, were deleted as dead code (GCC 12, -O1 and up): no
 * prefetcht0 was in the object code of src/front/front.c or src/par/parallel.c until
 * the attribute (bench/NOTES.md, entry 16; `objdump -d` shows them now).
 * Its callers that wrap it must be always_inline too. */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline void fdt_prefetch(const void *p)
{
#if defined(__GNUC__)
    __builtin_prefetch(p);
#else
    (void)p;
#endif
}

#endif
