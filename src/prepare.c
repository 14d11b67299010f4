/* Input validation, duplicate merging and power-of-two scaling. */
#include "prepare.h"

#include "mem.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "bits.h"

/* Bit pattern of a coordinate with -0 folded onto +0, so that the two
 * zeros, which every predicate treats as equal, merge as duplicates. */
static uint64_t coord_bits(double x)
{
    uint64_t u;
    if (x == 0.0)
        x = 0.0;
    memcpy(&u, &x, sizeof u);
    return u;
}

static uint64_t point_hash(const double *q)
{
    uint64_t h = coord_bits(q[0]) * 0x9E3779B97F4A7C15ull;
    h ^= coord_bits(q[1]) + 0x632BE59BD9B4E019ull + (h << 6) + (h >> 2);
    h ^= coord_bits(q[2]) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
    h ^= h >> 31;
    h *= 0xBF58476D1CE4E5B9ull;
    return h ^ (h >> 29);
}

static int same_point(const double *p, const double *q)
{
    return p[0] == q[0] && p[1] == q[1] && p[2] == q[2];
}

void fdt_prepared_free(fdt_prepared *pr)
{
    free(pr->p);
    free(pr->orig);
    free(pr->dupmap);
    memset(pr, 0, sizeof *pr);
}

/*
 * Chooses k so that max|x| * 2^k lies in [0.5, 1) without pushing the
 * smallest nonzero |x| below the normal range (where multiplication by a
 * power of two would round and move points).
 */
static int choose_scale(double maxabs, double minabs)
{
    int emax, emin;
    if (maxabs == 0.0)
        return 0;
    (void)frexp(maxabs, &emax);
    (void)frexp(minabs, &emin);
    int k = -emax;
    /* minabs * 2^k must stay >= 2^-1021 (DBL_MIN is 2^-1022; one bit of
     * slack for the differences the filters form). */
    if (emin - 1 + k < -1021)
        k = -1021 - (emin - 1);
    /* Never scale up so far that maxabs overflows (cannot happen with the
     * clamp above since emax >= emin, but keep the bound explicit). */
    if (emax + k > 1023)
        k = 1023 - emax;
    return k;
}

int fdt_prepare(const double *xyz, size_t n, fdt_prepared *pr, char *diag,
                size_t dlen)
{
    int err = FDT_ENOMEM;
    uint32_t *slots = NULL;
    memset(pr, 0, sizeof *pr);
    if (n > (size_t)FDT_VID_MAX) {
        snprintf(diag, dlen, "%zu points: more than the %d a vertex id holds",
                 n, FDT_VID_MAX);
        return FDT_ETOOBIG;
    }
    double maxabs = 0.0, minabs = INFINITY;
    for (size_t i = 0; i < n; i++) {
        for (int k = 0; k < 3; k++) {
            double x = xyz[3 * i + k];
            if (!isfinite(x)) {
                snprintf(diag, dlen, "point %zu has a non-finite %c coordinate (%g)",
                         i, "xyz"[k], x);
                return FDT_ERANGE;
            }
            double ax = fabs(x);
            if (ax > maxabs)
                maxabs = ax;
            if (ax != 0.0 && ax < minabs)
                minabs = ax;
        }
    }
    pr->dupmap = malloc((n ? n : 1) * sizeof *pr->dupmap);
    pr->p = malloc((n ? n : 1) * 3 * sizeof *pr->p);
    fdt_mem_advise_huge(pr->p, (n ? n : 1) * 3 * sizeof *pr->p);
    pr->orig = malloc((n ? n : 1) * sizeof *pr->orig);
    /* Open addressing at load <= 1/2: slots hold distinct-point numbers. */
    size_t cap = 16;
    while (cap < 2 * n)
        cap <<= 1;
    slots = malloc(cap * sizeof *slots);
    if (!pr->dupmap || !pr->p || !pr->orig || !slots)
        goto fail;
    memset(slots, 0xff, cap * sizeof *slots);
    int k = choose_scale(maxabs, minabs);
    pr->scale_exp = k;
    /* choose_scale keeps every nonzero scaled coordinate a normal double,
     * so multiplying by 2^k is exact, the same as ldexp, whenever 2^k is
     * itself a normal double; the libm call was a third of this loop's
     * time (perf, 1M points). */
    double p2k = k >= -1022 && k <= 1023 ? fdt_pow2i(k) : 0.0;
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        const double *q = xyz + 3 * i;
        /* The table (8 MB at 1M points) is probed at random: ask for the
         * slot a few points ahead so it has arrived when needed. */
        if (i + 8 < n)
            fdt_prefetch(slots + ((size_t)point_hash(xyz + 3 * (i + 8)) & (cap - 1)));
        size_t h = (size_t)point_hash(q) & (cap - 1);
        for (;;) {
            uint32_t s = slots[h];
            if (s == UINT32_MAX) {
                slots[h] = (uint32_t)m;
                /* Scaled copy: exact, see choose_scale. */
                for (int c = 0; c < 3; c++)
                    pr->p[3 * m + c] = p2k != 0.0 ? q[c] * p2k : ldexp(q[c], k);
                pr->orig[m] = (fdt_vid)i;
                pr->dupmap[i] = (fdt_vid)i;
                m++;
                break;
            }
            if (same_point(xyz + 3 * (size_t)pr->orig[s], q)) {
                pr->dupmap[i] = pr->orig[s];
                pr->ndup++;
                break;
            }
            h = (h + 1) & (cap - 1);
        }
    }
    pr->m = m;
    free(slots);
    return FDT_OK;
fail:
    free(slots);
    fdt_prepared_free(pr);
    snprintf(diag, dlen, "out of memory preparing %zu points", n);
    return err;
}
