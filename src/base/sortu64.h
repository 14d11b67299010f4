/*
 * Sorting 64-bit keys in place, for arrays sorted a great many times
 * (src/mesh/dualmesh.c and src/mesh/dualcheck.c sort each cell's ~90
 * half-edges): a quicksort on the keys themselves, no comparator calls
 * (qsort's cost 13 % of a --dual run).
 */
#ifndef FDT_SORTU64_H
#define FDT_SORTU64_H

#include <stddef.h>
#include <stdint.h>

/* Sorts a[0 .. m) ascending (median of three, the smaller part first so
 * the recursion stays shallow; insertion sort below 17 keys). */
static inline void fdt_sort_u64(uint64_t *a, size_t m)
{
    while (m > 16) {
        uint64_t x = a[0], y = a[m / 2], z = a[m - 1];
        uint64_t piv = x < y ? (y < z ? y : (x < z ? z : x)) : (x < z ? x : (y < z ? z : y));
        size_t i = 0, j = m - 1;
        for (;;) {
            while (a[i] < piv)
                i++;
            while (a[j] > piv)
                j--;
            if (i >= j)
                break;
            uint64_t t = a[i];
            a[i++] = a[j];
            a[j--] = t;
        }
        /* [0, j] <= piv <= [j + 1, m): recurse on the smaller part */
        if (j + 1 < m - j - 1) {
            fdt_sort_u64(a, j + 1);
            a += j + 1;
            m -= j + 1;
        } else {
            fdt_sort_u64(a + j + 1, m - j - 1);
            m = j + 1;
        }
    }
    for (size_t i = 1; i < m; i++) {
        uint64_t x = a[i];
        size_t j = i;
        while (j > 0 && a[j - 1] > x) {
            a[j] = a[j - 1];
            j--;
        }
        a[j] = x;
    }
}

#endif
