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

/* The fast path needs 128-bit integers and stores the digits as
 * little-endian words. */
#if defined(__SIZEOF_INT128__) && defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
#define DTOA_FAST 1
#endif

#if DTOA_FAST
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

/* v < 10^8 as 8 ASCII digits in one word, the first digit in its lowest
 * byte (so that a little-endian store writes them in order), by SIMD
 * within the word: v split into two halves of 4 digits (one a 32-bit
 * lane), each into two of 2 digits (16-bit lanes), each into two digits
 * (bytes). The quotients by 100 and 10 are multiplications: v 10486 / 2^20
 * is floor(v / 100) for v < 10^4 (the error v 2.4e-7 stays under the
 * fraction's gap 0.01), v 103 / 2^10 is floor(v / 10) for v < 100 (error
 * under 0.06); each lane's product stays below the next lane, and the
 * masks drop what the shifts bring down from it. Written digit by digit
 * (two-byte stores read back by the layout's copies), the digits stalled
 * store forwarding: a third of the function's cycles (bench/NOTES.md
 * entry 130). */
static inline uint64_t digits8(uint32_t v)
{
    uint64_t x = (uint64_t)(v / 10000) | (uint64_t)(v % 10000) << 32;
    uint64_t h = ((x * 10486) >> 20) & UINT64_C(0x0000007f0000007f);
    x = h | (x - 100 * h) << 16;
    uint64_t t = ((x * 103) >> 10) & UINT64_C(0x000f000f000f000f);
    x = t | (x - 10 * t) << 8;
    return x | UINT64_C(0x3030303030303030);
}

static inline void put64(char *p, uint64_t w)
{
    memcpy(p, &w, sizeof w);
}

/* D = d (17 digits, d in [10^16, 10^17)) times 10^(X - 16) at p, laid out
 * by %g: exponent form when X < -4 or X >= 17, trailing zeros of the
 * fraction dropped, and the point with them when nothing follows it.
 * The digits go from registers straight to their places: the first digit
 * L, then ab, the other 16 as one 128-bit word (a the low 8). Stores may
 * run past the text's end, never past p + FDT_DTOA17_MAX. */
static size_t layout(char *p, int neg, uint64_t d, int x)
{
    char *o = p + neg;
    p[0] = '-';
    uint64_t rest = d % TEN16;
    char lead = (char)('0' + d / TEN16);
    uint64_t a = digits8((uint32_t)(rest / 100000000)), b = digits8((uint32_t)(rest % 100000000));
    /* the trailing zeros: the top bytes of ab that are '0' */
    const uint64_t zeros = UINT64_C(0x3030303030303030);
    int tz = (b ^ zeros) ? __builtin_clzll(b ^ zeros) / 8
             : (a ^ zeros) ? 8 + __builtin_clzll(a ^ zeros) / 8
                           : 16;
    int last = 16 - tz; /* the last digit kept, 0 the first */
    if (x < -4 || x >= 17) {
        o[0] = lead;
        o[1] = '.';
        put64(o + 2, a);
        put64(o + 10, b);
        o += last > 0 ? 2 + last : 1;
        int ax = x < 0 ? -x : x;
        *o++ = 'e';
        *o++ = x < 0 ? '-' : '+';
        if (ax >= 100) {
            *o++ = (char)('0' + ax / 100);
            ax %= 100;
        }
        *o++ = (char)('0' + ax / 10);
        *o++ = (char)('0' + ax % 10);
        return (size_t)(o - p);
    }
    if (x < 0) { /* 0.000ddd: "0." and -x - 1 zeros (at most 3) */
        put64(o, UINT64_C(0x3030303030302e30)); /* "0.000000" */
        o += 1 - x;
        o[0] = lead;
        put64(o + 1, a);
        put64(o + 9, b);
        return (size_t)(o + 1 + last - p);
    }
    o[0] = lead;
    if (last <= x) { /* an integer: x + 1 digits, no point */
        put64(o + 1, a);
        put64(o + 9, b);
        return (size_t)(o + 1 + x - p);
    }
    /* the point after the first x + 1 digits, x <= 15: ab's bytes from x
     * on move up one, the top one out to o[17] */
    u128 ab = (u128)b << 64 | a, low = ((u128)1 << (8 * x)) - 1;
    u128 r = (ab & low) | (u128)'.' << (8 * x) | (ab & ~low) << 8;
    put64(o + 1, (uint64_t)r);
    put64(o + 9, (uint64_t)(r >> 64));
    o[17] = (char)(b >> 56);
    return (size_t)(o + 2 + last - p);
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
    return layout(p, neg, d, 16 - k);
}
#endif

size_t fdt_dtoa17(char *p, double x)
{
#if DTOA_FAST
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
