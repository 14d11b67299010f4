/*
 * Tests for src/base/dtoa.c: fdt_dtoa17 against snprintf's "%.17g", byte
 * for byte:
 *  - zeros of both signs, infinities, NaN, the extremes (subnormals, the
 *    largest double);
 *  - powers of ten and their neighbours three ulps either side, where the
 *    decimal exponent and the %g layout change (1e-5 / 1e-4, 1e16 / 1e17)
 *    and where rounding carries into a new digit (0.99999999999999999...);
 *  - a million doubles of random significands at every exponent of the
 *    exact path's range and beyond it, both signs;
 *  - a million random bit patterns.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "base/dtoa.h"
#include "testutil.h"

static long compared;

static void same(double x)
{
    char want[64], got[FDT_DTOA17_MAX + 1];
    snprintf(want, sizeof want, "%.17g", x);
    size_t n = fdt_dtoa17(got, x);
    got[n <= FDT_DTOA17_MAX ? n : FDT_DTOA17_MAX] = 0;
    compared++;
    EXPECTF(n <= FDT_DTOA17_MAX && strcmp(got, want) == 0, "%a: '%s', printf '%s'", x, got, want);
}

static uint64_t rng = 0x2545f4914f6cdd1du;
static uint64_t next(void)
{
    return test_rand64(&rng);
}

static double from_bits(uint64_t b)
{
    double x;
    memcpy(&x, &b, sizeof x);
    return x;
}

int main(void)
{
    const double specials[] = {0.0, -0.0, INFINITY, -INFINITY, NAN, 5e-324,
                               2.2250738585072014e-308, 1.7976931348623157e308, 1, -1, 0.1,
                               1.0 / 3, 2.0 / 3, 123456789012345678.0, 0.99999999999999989,
                               9.9999999999999982e16, 1e-11, 1e43, 0.5, 1e15 + 0.3,
                               1 + 0x1p-17 /* a tie at 17 digits */};
    for (size_t i = 0; i < sizeof specials / sizeof *specials; i++) {
        same(specials[i]);
        same(-specials[i]);
    }
    for (int p = -30; p <= 50; p++) {
        /* three ulps either side: dtoa.c's first guess of the exponent
         * compares with the nearest double of each power */
        double x = pow(10, p), lo = x, hi = x;
        same(x);
        for (int u = 0; u < 3; u++) {
            lo = nextafter(lo, 0);
            hi = nextafter(hi, INFINITY);
            same(lo);
            same(hi);
            same(-hi);
        }
    }
    for (int i = 0; i < 1000000; i++) {
        int ex = (int)(next() % 200) - 100; /* 2^-100 .. 2^100 */
        double x = ldexp(1 + (double)(next() >> 12) * 0x1p-52, ex);
        same(next() & 1 ? -x : x);
    }
    for (int i = 0; i < 1000000; i++)
        same(from_bits(next()));
    printf("dtoa: %ld doubles compared with printf\n", compared);
    return test_report("dtoa");
}
