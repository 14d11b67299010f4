/*
 * Tests for src/base/fixsum.h: order-independent sums on a fixed grid,
 * against exact integers (GMP).
 *  - each term's grid value round(x 2^-e) (ties to even) for terms at
 *    every scale from below the grid's step to 2^125 steps, both signs,
 *    powers of two, halves (the ties) and neighbours of 2^52, 2^62, 2^63
 *    and 2^64 steps, where the conversion's pieces meet;
 *  - the 128-bit sum of a hundred thousand terms equals the exact sum,
 *    the same bits in reversed and shuffled orders and when summed in
 *    pieces and merged;
 *  - the sum's value as a double within 2^-52 relative of the exact sum.
 */
#include <gmp.h>
#include <math.h>
#include <string.h>

#include "base/fixsum.h"
#include "testutil.h"

/* a's value as an exact integer */
static void fix_to_mpz(mpz_t z, fdt_fix a)
{
    mpz_set_si(z, (long)a.hi); /* long is 64 bits on every port we build */
    mpz_mul_2exp(z, z, 64);
    mpz_t lo;
    mpz_init(lo);
    mpz_set_ui(lo, (unsigned long)(a.lo >> 32));
    mpz_mul_2exp(lo, lo, 32);
    mpz_add_ui(lo, lo, (unsigned long)(a.lo & 0xffffffffu));
    mpz_add(z, z, lo);
    mpz_clear(lo);
}

/* round(x 2^-e), ties to even, exactly: y = x 2^-e is exact (a power of
 * two); below 2^52 its rounding is rint's, above it is an integer. */
static void grid_value(mpz_t z, double x, int e)
{
    double y = ldexp(x, -e);
    mpz_set_d(z, fabs(y) < 0x1p52 ? nearbyint(y) : y);
}

static uint64_t rng = 0x9e3779b97f4a7c15u;
static uint64_t next(void)
{
    return test_rand64(&rng);
}

/* A term of about 2^(k) grid steps, k in [-4, 125), either sign. */
static double term(int e)
{
    int k = (int)(next() % 129) - 4;
    double m = 1 + (double)(next() >> 11) * 0x1p-53; /* [1, 2) */
    if (next() & 1)
        m = -m;
    if ((next() & 7) == 0)
        m = m < 0 ? -1 : 1; /* a power of two */
    if ((next() & 7) == 1 && k >= 0 && k < 51) /* a tie: n + 1/2 steps, n < 2^52 */
        return ldexp((floor(ldexp(fabs(m), k)) + 0.5) * (m < 0 ? -1 : 1), e);
    return ldexp(m, k + e);
}

static void test_terms(void)
{
    mpz_t want, got;
    mpz_init(want);
    mpz_init(got);
    const int es[] = {-95, -1022 + 60, 0, 40};
    const double edges[] = {0x1p52, 0x1p62, 0x1p63, 0x1p64, 0x1p125};
    for (size_t g = 0; g < sizeof es / sizeof *es; g++) {
        int e = es[g];
        fdt_fix_grid grid = fdt_fix_grid_of(e);
        for (int t = 0; t < 200000; t++) {
            double x = term(e);
            if (t < 40) { /* the pieces' edges, their neighbours, both signs */
                double y = edges[t % 5];
                y = (t / 5) % 2 ? nextafter(y, 0) : (t / 10) % 2 ? nextafter(y, INFINITY) : y;
                x = ldexp((t / 20) % 2 ? -y : y, e);
                if (fabs(ldexp(x, -e)) >= 0x1p126)
                    continue;
            }
            fdt_fix a = {0, 0};
            fdt_fix_add(&a, x, grid);
            fix_to_mpz(got, a);
            grid_value(want, x, e);
            EXPECTF(mpz_cmp(got, want) == 0, "2^%d grid: %a gave the wrong grid value", e, x);
        }
    }
    mpz_clear(want);
    mpz_clear(got);
}

static void test_sums(void)
{
    enum { N = 100000, E = -95 };
    fdt_fix_grid grid = fdt_fix_grid_of(E);
    static double x[N];
    mpz_t want, got, v;
    mpz_init(want);
    mpz_init(got);
    mpz_init(v);
    for (int i = 0; i < N; i++) {
        double t = term(E);
        while (fabs(ldexp(t, -E)) >= 0x1p108) /* N terms stay below 2^126 */
            t = ldexp(t, -20);
        x[i] = t;
        grid_value(v, x[i], E);
        mpz_add(want, want, v);
    }
    fdt_fix fwd = {0, 0}, rev = {0, 0}, shuf = {0, 0}, parts[7] = {{0, 0}};
    for (int i = 0; i < N; i++) {
        fdt_fix_add(&fwd, x[i], grid);
        fdt_fix_add(&rev, x[N - 1 - i], grid);
        fdt_fix_add(&parts[i % 7], x[i], grid);
    }
    for (int i = N - 1; i > 0; i--) {
        int k = (int)(next() % (uint64_t)(i + 1));
        double t = x[i];
        x[i] = x[k];
        x[k] = t;
    }
    for (int i = 0; i < N; i++)
        fdt_fix_add(&shuf, x[i], grid);
    fdt_fix merged = {0, 0};
    for (int p = 0; p < 7; p++)
        fdt_fix_merge(&merged, parts[p]);
    fix_to_mpz(got, fwd);
    EXPECTF(mpz_cmp(got, want) == 0, "the sum of %d terms is not the exact one", N);
    EXPECTF(memcmp(&fwd, &rev, sizeof fwd) == 0, "reversed order: other bits");
    EXPECTF(memcmp(&fwd, &shuf, sizeof fwd) == 0, "shuffled order: other bits");
    EXPECTF(memcmp(&fwd, &merged, sizeof fwd) == 0, "merged pieces: other bits");
    /* the value: within 2^-52 relative of the exact sum times 2^E */
    mpf_t exact, diff;
    mpf_init2(exact, 256);
    mpf_init2(diff, 256);
    mpf_set_z(exact, want);
    mpf_div_2exp(exact, exact, (mp_bitcnt_t)-E);
    mpf_set_d(diff, fdt_fix_value(fwd, grid));
    mpf_sub(diff, diff, exact);
    mpf_abs(diff, diff);
    mpf_abs(exact, exact);
    mpf_div_2exp(exact, exact, 52);
    EXPECTF(mpf_cmp(diff, exact) <= 0, "the sum's double is off by more than 2^-52");
    mpf_clear(exact);
    mpf_clear(diff);
    mpz_clear(want);
    mpz_clear(got);
    mpz_clear(v);
}

/* fdt_fix_value's low word, converted as two 32-bit halves, against the
 * compiler's rounding of the whole unsigned word: the same double for
 * every sum, of either sign, whatever its low word's top bits (the
 * halves' sum rounds once, as the conversion does). */
static void test_values(void)
{
    fdt_fix_grid grid = fdt_fix_grid_of(0);
    for (int i = 0; i < 1000000; i++) {
        fdt_fix a = {next(), (int64_t)(next() >> (2 + next() % 62))};
        if (i % 3 == 0)
            a.lo &= UINT64_C(0xffffffff) << (next() % 33); /* low halves of zeros */
        if (next() & 1) { /* negative: two's complement */
            a.lo = ~a.lo + 1;
            a.hi = (int64_t)(~(uint64_t)a.hi + (a.lo == 0));
        }
        fdt_fix m = a;
        int neg = m.hi < 0;
        if (neg) {
            m.lo = ~m.lo + 1;
            m.hi = (int64_t)(~(uint64_t)m.hi + (m.lo == 0));
        }
        double want = (double)(uint64_t)m.hi * 0x1p64 + (double)m.lo;
        want = neg ? -want : want;
        double got = fdt_fix_value(a, grid);
        EXPECTF(memcmp(&got, &want, sizeof got) == 0, "value %d: %.17g, not %.17g", i, got, want);
    }
}

int main(void)
{
    test_terms();
    test_sums();
    test_values();
    return test_report("fixsum");
}
