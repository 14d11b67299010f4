/*
 * The point families of the search-structure tests (tests/test_kdtree.c,
 * tests/test_prepare.c, tests/test_seed.c): uniform, integer lattice,
 * integer points on a sphere (cospherical), a two-layer 2-D grid, a big
 * offset with 1 mm resolution, and mixed magnitudes. One deterministic
 * stream per test program (rnd, urand).
 */
#ifndef FDT_TESTPOINTS_H
#define FDT_TESTPOINTS_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "base/hash.h"

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;
static inline uint64_t rnd(void)
{
    return fdt_splitmix64(&rng_state);
}
static inline double urand(void) { return (double)(rnd() >> 11) * 0x1p-53; }

enum { UNIFORM, LATTICE, SPHERE_INT, GRID2D, OFFSET, MIXED, NFAMILIES };
static const char *family_name[] = {"uniform", "lattice", "intsphere", "grid2d", "offset",
                                    "mixed"};

/* Fills up to n distinct-ish points of a family; returns the count. */
static inline size_t make_points(int fam, size_t n, double *p)
{
    size_t m = 0;
    if (fam == UNIFORM || fam == OFFSET) {
        for (; m < n; m++)
            for (int k = 0; k < 3; k++)
                p[3 * m + k] = fam == UNIFORM ? urand()
                                              : 4.9e6 + floor(urand() * 20000.0) * 1e-3;
    } else if (fam == MIXED) {
        /* leaves of very different sizes side by side: half the points
         * in the unit cube, half in a cube 1e-9 wide inside it, and a
         * few 1e-300 from its corner (the float blocks' frames) */
        for (; m < n; m++)
            for (int k = 0; k < 3; k++)
                p[3 * m + k] = m % 2 == 0 ? urand()
                               : m % 11 == 1 ? 0.25 + urand() * 1e-300
                                             : 0.5 + urand() * 1e-9;
    } else if (fam == LATTICE) {
        int s = (int)cbrt((double)n);
        for (int i = 0; i < s; i++)
            for (int j = 0; j < s; j++)
                for (int k = 0; k < s; k++, m++) {
                    p[3 * m] = i;
                    p[3 * m + 1] = j;
                    p[3 * m + 2] = k;
                }
    } else if (fam == SPHERE_INT) {
        const int r2 = 11 * 11 + 2 * 2; /* many integer points, none redundant */
        for (int i = -12; i <= 12 && m < n; i++)
            for (int j = -12; j <= 12 && m < n; j++)
                for (int k = -12; k <= 12 && m < n; k++)
                    if (i * i + j * j + k * k == r2) {
                        p[3 * m] = i;
                        p[3 * m + 1] = j;
                        p[3 * m + 2] = k;
                        m++;
                    }
    } else {
        int s = (int)sqrt((double)n / 2.0);
        for (int i = 0; i < s; i++)
            for (int j = 0; j < s; j++)
                for (int z = 0; z < 2; z++, m++) {
                    p[3 * m] = i;
                    p[3 * m + 1] = j;
                    p[3 * m + 2] = z;
                }
    }
    return m;
}

#endif
