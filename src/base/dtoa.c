/*
 * "%.17g" without printf's arbitrary precision; see dtoa.h.
 *
 * x = m 2^e (m the 53-bit significand) has 17 significant digits
 * D = round(x 10^k), D in [10^16, 10^17), for k = 16 - X, X the decimal
 * exponent. 10^k = 5^k 2^k, and 5^k fits 64 bits for |k| <= 27, so D is
 * an exact integer computation in 128 bits:
 *  - k >= 0: m 5^k < 2^116, then a shift right by -(e + k) rounded;
 *  - k < 0: m 2^(e + k) (e + k > 0, below 2^121 where D < 2^57), then a
 *    division by 5^-k rounded.
 * Rounding is to nearest, ties to even, as glibc rounds in the default
 * mode (ties occur: 1 + 2^-17 has 18 significant digits, ending in 5).
 * The first estimate of X, from the binary exponent, is low by at most
 * one; D >= 10^17 moves k down. Then the digits are laid out by %g's
 * rule: exponent form when X < -4 or X >= 17, trailing zeros of the
 * fraction dropped, and the point with them when nothing follows it.
 */
#include "base/dtoa.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#if defined(__SIZEOF_INT128__)
typedef unsigned __int128 u128;

static const uint64_t pow5[28] = {
    UINT64_C(1), UINT64_C(5), UINT64_C(25), UINT64_C(125), UINT64_C(625), UINT64_C(3125),
    UINT64_C(15625), UINT64_C(78125), UINT64_C(390625), UINT64_C(1953125), UINT64_C(9765625),
    UINT64_C(48828125), UINT64_C(244140625), UINT64_C(1220703125), UINT64_C(6103515625),
    UINT64_C(30517578125), UINT64_C(152587890625), UINT64_C(762939453125),
    UINT64_C(3814697265625), UINT64_C(19073486328125), UINT64_C(95367431640625),
    UINT64_C(476837158203125), UINT64_C(2384185791015625), UINT64_C(11920928955078125),
    UINT64_C(59604644775390625), UINT64_C(298023223876953125),
    UINT64_C(1490116119384765625), UINT64_C(7450580596923828125)};

/* 10^j for j in [-POW10_LOW, 43], as doubles (rounded outside [0, 22]):
 * the next power above every x the exact path takes, [1e-11, 1e43). */
#define POW10_LOW 11
static const double tens[] = {
    1e-11, 1e-10, 1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1e0, 1e1, 1e2, 1e3,
    1e4,   1e5,   1e6,  1e7,  1e8,  1e9,  1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18,
    1e19,  1e20,  1e21, 1e22, 1e23, 1e24, 1e25, 1e26, 1e27, 1e28, 1e29, 1e30, 1e31, 1e32, 1e33,
    1e34,  1e35,  1e36, 1e37, 1e38, 1e39, 1e40, 1e41, 1e42, 1e43};

#define TEN16 UINT64_C(10000000000000000)
#define TEN17 UINT64_C(100000000000000000)

/* round(m 2^e 10^k), |k| <= 27, for a normal m 2^e within about a factor
 * of 10 of 10^(16 - k); UINT64_MAX where it would not fit 64 bits. */
static uint64_t scaled(uint64_t m, int e, int k)
{
    int s = e + k;
    u128 q;
    if (k >= 0) {
        u128 n = (u128)m * pow5[k];
        if (s >= 0) {
            if (s >= 12)
                return UINT64_MAX; /* m 2^s alone is past 2^64 */
            q = n << s;
        } else if (s <= -128) {
            q = 0;
        } else {
            int r = -s;
            q = n >> r;
            u128 rem = n - (q << r), half = (u128)1 << (r - 1);
            q += rem > half || (rem == half && (q & 1));
        }
    } else {
        if (s < 0 || s > 74)
            return s < 0 ? 0 : UINT64_MAX; /* below 2^53 / 5^27, or past 2^127 */
        u128 n = (u128)m << s;
        uint64_t d = pow5[-k];
        q = n / d;
        u128 rem = n - q * d;
        q += 2 * rem > d || (2 * rem == d && (q & 1));
    }
    return q >> 64 ? UINT64_MAX : (uint64_t)q;
}

/* "00" to "99". */
static const char pairs[201] =
    "0001020304050607080910111213141516171819"
    "2021222324252627282930313233343536373839"
    "4041424344454647484950515253545556575859"
    "6061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

/* v < 10^8 as 8 digits at p: two digits a step from pairs, in two
 * independent halves (digit by digit, D's 17 divisions by ten were one
 * chain: 5 % of a --voronoi run's samples at 1M points, bench/NOTES.md
 * entry 112). */
static inline void digits8(char *p, uint32_t v)
{
    uint32_t a = v / 10000, b = v % 10000;
    memcpy(p, pairs + 2 * (a / 100), 2);
    memcpy(p + 2, pairs + 2 * (a % 100), 2);
    memcpy(p + 4, pairs + 2 * (b / 100), 2);
    memcpy(p + 6, pairs + 2 * (b % 100), 2);
}

/* D's 17 digits at p (D < 10^17). */
static inline void digits17(char *p, uint64_t d)
{
    uint64_t hi = d / 100000000;
    uint32_t lo = (uint32_t)(d % 100000000);
    p[0] = (char)('0' + hi / 100000000);
    digits8(p + 1, (uint32_t)(hi % 100000000));
    digits8(p + 9, lo);
}

/* The digits of D = dig (17 of them) times 10^(X - 16), laid out by %g. */
static size_t layout(char *p, int neg, const char *dig, int x)
{
    char *o = p;
    if (neg)
        *o++ = '-';
    int last = 16; /* the last digit kept: trailing zeros go */
    while (last > 0 && dig[last] == '0')
        last--;
    if (x < -4 || x >= 17) {
        *o++ = dig[0];
        if (last > 0) {
            *o++ = '.';
            memcpy(o, dig + 1, (size_t)last);
            o += last;
        }
        int ax = x < 0 ? -x : x;
        *o++ = 'e';
        *o++ = x < 0 ? '-' : '+';
        if (ax >= 100) {
            *o++ = (char)('0' + ax / 100);
            ax %= 100;
        }
        *o++ = (char)('0' + ax / 10);
        *o++ = (char)('0' + ax % 10);
    } else if (x >= 0) {
        memcpy(o, dig, (size_t)x + 1);
        o += x + 1;
        if (last > x) {
            *o++ = '.';
            memcpy(o, dig + x + 1, (size_t)(last - x));
            o += last - x;
        }
    } else {
        *o++ = '0';
        *o++ = '.';
        for (int i = 0; i < -x - 1; i++)
            *o++ = '0';
        memcpy(o, dig, (size_t)last + 1);
        o += last + 1;
    }
    return (size_t)(o - p);
}

static size_t fast(char *p, double x)
{
    uint64_t b;
    memcpy(&b, &x, sizeof b);
    int neg = (int)(b >> 63);
    if (x == 0) {
        p[0] = '-';
        p[neg] = '0';
        return 1 + (size_t)neg;
    }
    double ax = fabs(x);
    if (!(ax >= 1e-11 && ax < 1e43))
        return 0;
    uint64_t m = (b & ((UINT64_C(1) << 52) - 1)) | UINT64_C(1) << 52;
    int e = (int)((b >> 52) & 0x7ff) - 1075;
    /* floor((e + 52) log10 2) as 78913 / 2^18 (exact for |e + 52| < 1650;
     * baseline x86-64 has no rounding instruction, so floor() was a dozen
     * SSE2 operations), low by at most one; then raised where x is above
     * the next power of ten's nearest double, so above the power itself
     * (the next double up from a rounded power is past it): never too
     * high, which the correction below could not see (a D rounded up to
     * 10^16 from a lower exponent reads as a valid D). One computation of
     * D instead of two on about a third of the numbers. */
    int est = ((e + 52) * 78913) >> 18;
    est += ax > tens[est + 1 + POW10_LOW];
    int k = 16 - est;
    if (k < -27 || k > 27)
        return 0;
    uint64_t d = scaled(m, e, k);
    if (d >= TEN17 && k > -27)
        d = scaled(m, e, --k);
    else if (d < TEN16 && k < 27)
        d = scaled(m, e, ++k);
    if (d < TEN16 || d >= TEN17)
        return 0;
    char dig[17];
    digits17(dig, d);
    return layout(p, neg, dig, 16 - k);
}
#endif

size_t fdt_dtoa17(char *p, double x)
{
#if defined(__SIZEOF_INT128__)
    size_t n = fast(p, x);
    if (n)
        return n;
#endif
    char buf[32];
    int n2 = snprintf(buf, sizeof buf, "%.17g", x);
    if (n2 < 0 || n2 > FDT_DTOA17_MAX)
        n2 = 0; /* not for any double in the C locale */
    memcpy(p, buf, (size_t)n2);
    return (size_t)n2;
}
