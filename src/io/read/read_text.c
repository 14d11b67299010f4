/*
 * Numbers, lines and fields of the text formats (.xyz, .node, ASCII .ply).
 *
 * Numbers in text are matched against a strict decimal grammar
 *     [+-]? (digits [. digits?] | . digits) ([eE] [+-]? digits)?
 * and then converted with correct rounding: Clinger's fast path when the
 * digits fit in 53 bits and the power of ten is exact (one IEEE operation,
 * hence correctly rounded), glibc's correctly rounded strtod otherwise.
 * Hex floats, "nan", "inf" and "infinity" are rejected; so are literals
 * that overflow a double and nonzero literals that round to a subnormal or
 * to zero (they would carry less precision than the input claims).
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "io/read/read_common.h"

#include <float.h>
#include <locale.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------ */
/* Numbers                                                            */
/* ------------------------------------------------------------------ */

/* 10^0 .. 10^22 are exactly representable doubles. */
static const double rd_pow10[23] = {
    1e0,  1e1,  1e2,  1e3,  1e4,  1e5,  1e6,  1e7,  1e8,  1e9,  1e10, 1e11,
    1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

#if defined(__SIZEOF_INT128__)
#define RD_HAVE_U128 1
__extension__ typedef unsigned __int128 rd_u128;

/* 10^0 .. 10^19, the powers of ten below 2^64. */
static const uint64_t rd_pow10_u64[20] = {
    1ull, 10ull, 100ull, 1000ull, 10000ull, 100000ull, 1000000ull, 10000000ull,
    100000000ull, 1000000000ull, 10000000000ull, 100000000000ull,
    1000000000000ull, 10000000000000ull, 100000000000000ull,
    1000000000000000ull, 10000000000000000ull, 100000000000000000ull,
    1000000000000000000ull, 10000000000000000000ull};

static int rd_bits128(rd_u128 x)
{
    uint64_t hi = (uint64_t)(x >> 64), lo = (uint64_t)x;
    return hi ? 128 - __builtin_clzll(hi) : (lo ? 64 - __builtin_clzll(lo) : 0);
}

/*
 * The double nearest to (q + f) 2^e2, ties to even, where q > 0 is an
 * integer and 0 <= f < 1 is a fraction known only by whether it is zero
 * (sticky). Exact integer work: the 53 leading bits of q are kept, and
 * the bits below them with f decide the rounding. The caller keeps the
 * result in the normal range, so the final scaling by a power of two is
 * exact; q has more than 53 bits whenever f may be nonzero.
 */
static double rd_round_u128(rd_u128 q, int sticky, int e2)
{
    int nb = rd_bits128(q);
    if (nb <= 53)
        return ldexp((double)(uint64_t)q, e2);
    int drop = nb - 53;
    uint64_t mant = (uint64_t)(q >> drop);
    rd_u128 rest = q & (((rd_u128)1 << drop) - 1), half = (rd_u128)1 << (drop - 1);
    if (rest > half || (rest == half && (sticky || (mant & 1))))
        mant++; /* 2^53 at most: still exact */
    return ldexp((double)mant, e2 + drop);
}

/*
 * w 10^e10 correctly rounded, for w < 2^64 and |e10| <= 19, in 128-bit
 * integers: the 17-digit literals that printf("%.17g") writes (every
 * coordinate a round trip produces) are beyond Clinger's fast path, and
 * strtod took more than half of the time to read them. For e10 >= 0 the
 * product w 10^e10 < 2^128 is exact. For e10 < 0, w 2^s (s puts its top
 * bit at 2^126) divided by 10^-e10 gives a quotient of at least 62 bits
 * and a remainder, which is the sticky fraction. The results lie in
 * [1e-19, 2^64 1e19]: normal doubles.
 */
static double rd_exact_small(uint64_t w, int e10)
{
    if (e10 >= 0)
        return rd_round_u128((rd_u128)w * rd_pow10_u64[e10], 0, 0);
    int s = 127 - rd_bits128(w);
    rd_u128 n = (rd_u128)w << s;
    uint64_t d = rd_pow10_u64[-e10];
    rd_u128 q = n / d;
    return rd_round_u128(q, n - q * d != 0, -s);
}
#endif

/* Whether s[0..len) spells nan, inf or infinity (any case, optional sign). */
static int rd_is_nonfinite_word(const char *s, size_t len)
{
    if (len > 0 && (s[0] == '+' || s[0] == '-')) {
        s++;
        len--;
    }
    if (rd_word_ieq(s, len, "nan") || rd_word_ieq(s, len, "inf") ||
        rd_word_ieq(s, len, "infinity"))
        return 1;
    /* glibc's strtod also accepts nan(chars) */
    return len >= 4 && rd_word_ieq(s, 4, "nan(");
}

/*
 * Converts the decimal literal at s to the nearest double. With full set,
 * all of s[0..len) must be the literal; otherwise the longest literal at s
 * is taken and *used says how long it is (the caller checks what follows).
 * With check_range = 0 only the syntax is checked (ignored fields).
 */
int fdt_rd_scan_real(const char *s, size_t len, double *out,
                        int check_range, int full, size_t *used)
{
    size_t i = 0;
    int neg = 0;
    if (i < len && (s[i] == '+' || s[i] == '-')) {
        neg = s[i] == '-';
        i++;
    }
    /* Every digit goes into w; with more than 19 digits w may wrap and is
     * not used (the slow path takes over). */
    uint64_t w = 0;
    size_t d0 = i;
    for (; i < len && rd_is_digit(s[i]); i++)
        w = w * 10 + (uint64_t)(s[i] - '0');
    size_t nint = i - d0, nfrac = 0;
    if (i < len && s[i] == '.') {
        size_t f0 = ++i;
        for (; i < len && rd_is_digit(s[i]); i++)
            w = w * 10 + (uint64_t)(s[i] - '0');
        nfrac = i - f0;
    }
    size_t ndig = nint + nfrac, mend = i;
    if (ndig == 0) {
        *used = i;
        return rd_is_nonfinite_word(s, len) ? NUM_NONFINITE : NUM_SYNTAX;
    }
    int slow = ndig > 19;
    long long e10 = -(long long)(nfrac < 1000000 ? nfrac : 1000000);
    if (i < len && (s[i] == 'e' || s[i] == 'E')) {
        i++;
        int eneg = 0;
        if (i < len && (s[i] == '+' || s[i] == '-')) {
            eneg = s[i] == '-';
            i++;
        }
        if (i == len || !rd_is_digit(s[i])) {
            *used = i;
            return NUM_SYNTAX;
        }
        long long ex = 0;
        for (; i < len && rd_is_digit(s[i]); i++)
            if (ex < 1000000) /* saturate: far beyond any double */
                ex = ex * 10 + (s[i] - '0');
        e10 += eneg ? -ex : ex;
    }
    if (full && i != len)
        return NUM_SYNTAX;
    *used = i;
    len = i;
    int nonzero = w != 0;
    if (slow) {
        nonzero = 0;
        for (size_t k = d0; k < mend; k++)
            if (s[k] >= '1' && s[k] <= '9')
                nonzero = 1;
    }
    if (!nonzero) {
        *out = neg ? -0.0 : 0.0;
        return NUM_OK;
    }
    if (!check_range) {
        *out = 0.0;
        return NUM_OK;
    }
#if defined(FLT_EVAL_METHOD) && FLT_EVAL_METHOD == 0
    /* Clinger's fast path: w and 10^|e10| are exact doubles, so the one
     * rounding of the multiply or divide is the correct rounding. It needs
     * operations evaluated in double (not x87 extended) precision. */
    if (!slow && w <= ((uint64_t)1 << 53) && e10 >= -22 && e10 <= 22) {
        double v = (double)w;
        v = e10 < 0 ? v / rd_pow10[-e10] : v * rd_pow10[e10];
        *out = neg ? -v : v;
        return NUM_OK;
    }
#else
    (void)slow;
#endif
#ifdef RD_HAVE_U128
    if (!slow && e10 >= -19 && e10 <= 19) {
        double v = rd_exact_small(w, (int)e10);
        *out = neg ? -v : v;
        return NUM_OK;
    }
#endif
    /* strtod needs a terminated copy, and the current locale's decimal
     * point in place of '.' (the CLI may have called setlocale). */
    const char *dp = localeconv()->decimal_point;
    size_t dpl = (dp != NULL && dp[0] != '\0') ? strlen(dp) : 1;
    if (dp == NULL || dp[0] == '\0')
        dp = ".";
    char small[128];
    size_t need = len + dpl + 1;
    char *tmp = need <= sizeof small ? small : malloc(need);
    if (tmp == NULL)
        return NUM_NOMEM;
    size_t o = 0;
    for (size_t k = 0; k < len; k++) {
        if (s[k] == '.') {
            memcpy(tmp + o, dp, dpl);
            o += dpl;
        } else {
            tmp[o++] = s[k];
        }
    }
    tmp[o] = '\0';
    char *endp = NULL;
    double v = strtod(tmp, &endp);
    int ok = endp == tmp + o;
    if (tmp != small)
        free(tmp);
    if (!ok)
        return NUM_SYNTAX;
    if (isinf(v))
        return NUM_OVERFLOW;
    if (fabs(v) < DBL_MIN)
        return NUM_UNDERFLOW;
    *out = v;
    return NUM_OK;
}

/* The literal s[0..len), all of it (see fdt_rd_scan_real). */
int fdt_rd_parse_real(const char *s, size_t len, double *out,
                         int check_range)
{
    size_t used;
    return fdt_rd_scan_real(s, len, out, check_range, 1, &used);
}

/* A decimal integer with optional sign; NUM_OVERFLOW beyond int64. */
int fdt_rd_parse_int(const char *s, size_t len, int64_t *out)
{
    size_t i = 0;
    int neg = 0;
    if (i < len && (s[i] == '+' || s[i] == '-')) {
        neg = s[i] == '-';
        i++;
    }
    if (i == len)
        return NUM_SYNTAX;
    uint64_t v = 0;
    int over = 0;
    for (; i < len; i++) {
        if (!rd_is_digit(s[i]))
            return NUM_SYNTAX;
        unsigned d = (unsigned)(s[i] - '0');
        if (v > (UINT64_MAX - d) / 10)
            over = 1;
        else
            v = v * 10 + d;
    }
    if (over || v > (uint64_t)INT64_MAX + (neg ? 1u : 0u))
        return NUM_OVERFLOW;
    if (neg)
        *out = v == (uint64_t)INT64_MAX + 1u ? INT64_MIN : -(int64_t)v;
    else
        *out = (int64_t)v;
    return NUM_OK;
}

/* A count: digits only, no sign. */
int fdt_rd_parse_count(const char *s, size_t len, uint64_t *out)
{
    if (len == 0 || !rd_is_digit(s[0]))
        return NUM_SYNTAX;
    int64_t v;
    int st = fdt_rd_parse_int(s, len, &v);
    if (st == NUM_OK)
        *out = (uint64_t)v;
    return st;
}

/*
 * Reports a bad number: "PATH:LINE: [what: ]problem 'token'". Returns the
 * error code to give back.
 */
int fdt_rd_num_fail(const rd_ctx *c, size_t line, const char *what,
                       int status, const char *s, size_t len)
{
    char q[RD_QUOTE_CAP];
    fdt_rd_quote(q, s, len);
    const char *sep = what[0] != '\0' ? ": " : "";
    switch (status) {
    case NUM_NONFINITE:
        return fdt_rd_fail(c, FDT_IO_EFORMAT, ":%zu: %s%snot a finite number: %s",
                       line, what, sep, q);
    case NUM_OVERFLOW:
        return fdt_rd_fail(c, FDT_IO_EFORMAT, ":%zu: %s%s%s overflows a double",
                       line, what, sep, q);
    case NUM_UNDERFLOW:
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: %s%s%s underflows a double (nonzero literal "
                       "below the smallest normal double)",
                       line, what, sep, q);
    case NUM_NOMEM:
        return fdt_rd_fail(c, FDT_IO_ENOMEM, ":%zu: out of memory", line);
    default:
        return fdt_rd_fail(c, FDT_IO_EFORMAT, ":%zu: %s%snot a number: %s", line,
                       what, sep, q);
    }
}

/* ------------------------------------------------------------------ */
/* Lines and fields                                                   */
/* ------------------------------------------------------------------ */

int fdt_rd_next_line(rd_lines *L, const char **s, const char **e)
{
    if (L->p >= L->end)
        return 0;
    const char *nl = memchr(L->p, '\n', (size_t)(L->end - L->p));
    *s = L->p;
    *e = nl != NULL ? nl : L->end;
    L->p = nl != NULL ? nl + 1 : L->end;
    L->lineno++;
    return 1;
}

/* Cuts a line at '#' (comment to the end of the line). */
const char *fdt_rd_cut_comment(const char *s, const char *e)
{
    const char *h = memchr(s, '#', (size_t)(e - s));
    return h != NULL ? h : e;
}

int fdt_rd_blank(const char *s, const char *e)
{
    for (; s < e; s++)
        if (!rd_is_space(*s))
            return 0;
    return 1;
}

/* Fields left on the line (for "found N" messages); -1 on an empty one. */
size_t fdt_rd_count_rest(rd_fields *f)
{
    const char *ts;
    size_t tl, k = 0;
    int r;
    while ((r = fdt_rd_next_field(f, &ts, &tl)) != 0)
        if (r > 0)
            k++;
    return k;
}
