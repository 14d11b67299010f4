/* Small bit helpers shared by modules (src/kdtree.c, src/faceq.c). */
#ifndef FDT_BITS_H
#define FDT_BITS_H

#include <stdint.h>

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

#endif
