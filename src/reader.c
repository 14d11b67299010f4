/*
 * Point-cloud readers (see src/reader.h for the formats and the contract).
 *
 * The whole file is read into one NUL-terminated buffer and parsed in
 * memory. Every header count is checked against the bytes that follow it
 * before anything proportional to the count is allocated, so a 100-byte
 * file claiming four billion points costs nothing.
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

#include "reader.h"

#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <locale.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#ifndef O_CLOEXEC
#define O_CLOEXEC 0
#endif

#if defined(__GNUC__)
#define RD_PRINTF(f, a) __attribute__((format(printf, f, a)))
#else
#define RD_PRINTF(f, a)
#endif

/* fdt_vid is int32_t: more points cannot be numbered. */
#define RD_MAX_POINTS ((uint64_t)INT32_MAX)

/* Bytes of an offending token quoted in a message. */
#define RD_QUOTE_BYTES 24
#define RD_QUOTE_CAP (RD_QUOTE_BYTES * 4 + 8)

_Static_assert(sizeof(float) == 4 && sizeof(double) == 8,
               "binary PLY decoding assumes IEEE binary32/binary64");

typedef struct rd_ctx {
    const char *path;
    char *err;
    size_t errlen;
    const char *buf; /* the whole file, NUL-terminated (owned by the caller) */
    size_t size;     /* bytes in the file (the NUL not counted) */
    int threads;      /* for .xyz: slices parsed at once (rd_read_xyz) */
    size_t min_slice; /* least bytes a slice; 0: RD_MIN_SLICE */
} rd_ctx;

/* Below a megabyte a slice's thread costs about what it saves. */
#define RD_MIN_SLICE ((size_t)1 << 20)

typedef struct rd_points {
    double *xyz; /* 3 * cap doubles */
    size_t n, cap;
    int fixed;   /* xyz is a slice of another array: it cannot grow */
} rd_points;

/* Writes "PATH" followed by the formatted text; always returns code. */
static int rd_fail(const rd_ctx *c, int code, const char *fmt, ...)
    RD_PRINTF(3, 4);

static int rd_fail(const rd_ctx *c, int code, const char *fmt, ...)
{
    if (c->err == NULL || c->errlen == 0)
        return code;
    int k = snprintf(c->err, c->errlen, "%s", c->path);
    if (k < 0)
        k = 0;
    size_t used = (size_t)k < c->errlen ? (size_t)k : c->errlen - 1;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(c->err + used, c->errlen - used, fmt, ap);
    va_end(ap);
    return code;
}

/*
 * Copies a token into out as 'text', printable ASCII verbatim and anything
 * else as \xHH, so that binary garbage cannot corrupt a terminal; long
 * tokens are cut and marked with "...".
 */
static const char *rd_quote(char out[RD_QUOTE_CAP], const char *s, size_t len)
{
    static const char hex[] = "0123456789abcdef";
    size_t o = 0;
    out[o++] = '\'';
    size_t shown = len < RD_QUOTE_BYTES ? len : RD_QUOTE_BYTES;
    for (size_t i = 0; i < shown; i++) {
        unsigned char ch = (unsigned char)s[i];
        if (ch >= 0x20 && ch < 0x7f && ch != '\'' && ch != '\\') {
            out[o++] = (char)ch;
        } else {
            out[o++] = '\\';
            out[o++] = 'x';
            out[o++] = hex[ch >> 4];
            out[o++] = hex[ch & 15];
        }
    }
    if (shown < len) {
        out[o++] = '.';
        out[o++] = '.';
        out[o++] = '.';
    }
    out[o++] = '\'';
    out[o] = '\0';
    return out;
}

static int rd_is_space(char ch)
{
    return ch == ' ' || ch == '\t' || ch == '\r' || ch == '\v' || ch == '\f';
}

static int rd_is_digit(char ch)
{
    return ch >= '0' && ch <= '9';
}

static char rd_lower(char ch)
{
    return (ch >= 'A' && ch <= 'Z') ? (char)(ch - 'A' + 'a') : ch;
}

/* Case-insensitive comparison of s[0..len) with the lowercase word w. */
static int rd_word_ieq(const char *s, size_t len, const char *w)
{
    size_t wl = strlen(w);
    if (len != wl)
        return 0;
    for (size_t i = 0; i < len; i++)
        if (rd_lower(s[i]) != w[i])
            return 0;
    return 1;
}

static int rd_tok_is(const char *s, size_t len, const char *w)
{
    return len == strlen(w) && memcmp(s, w, len) == 0;
}

/* ------------------------------------------------------------------ */
/* Numbers                                                            */
/* ------------------------------------------------------------------ */

enum {
    NUM_OK = 0,
    NUM_SYNTAX,    /* not a number of our grammar */
    NUM_NONFINITE, /* nan, inf, infinity */
    NUM_OVERFLOW,  /* beyond DBL_MAX (or, for integers, beyond int64) */
    NUM_UNDERFLOW, /* nonzero literal that rounds to a subnormal or zero */
    NUM_NOMEM
};

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
static int rd_scan_real(const char *s, size_t len, double *out,
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

/* The literal s[0..len), all of it (see rd_scan_real). */
static int rd_parse_real(const char *s, size_t len, double *out,
                         int check_range)
{
    size_t used;
    return rd_scan_real(s, len, out, check_range, 1, &used);
}

/* A decimal integer with optional sign; NUM_OVERFLOW beyond int64. */
static int rd_parse_int(const char *s, size_t len, int64_t *out)
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
static int rd_parse_count(const char *s, size_t len, uint64_t *out)
{
    if (len == 0 || !rd_is_digit(s[0]))
        return NUM_SYNTAX;
    int64_t v;
    int st = rd_parse_int(s, len, &v);
    if (st == NUM_OK)
        *out = (uint64_t)v;
    return st;
}

/*
 * Reports a bad number: "PATH:LINE: [what: ]problem 'token'". Returns the
 * error code to give back.
 */
static int rd_num_fail(const rd_ctx *c, size_t line, const char *what,
                       int status, const char *s, size_t len)
{
    char q[RD_QUOTE_CAP];
    rd_quote(q, s, len);
    const char *sep = what[0] != '\0' ? ": " : "";
    switch (status) {
    case NUM_NONFINITE:
        return rd_fail(c, FDT_IO_EFORMAT, ":%zu: %s%snot a finite number: %s",
                       line, what, sep, q);
    case NUM_OVERFLOW:
        return rd_fail(c, FDT_IO_EFORMAT, ":%zu: %s%s%s overflows a double",
                       line, what, sep, q);
    case NUM_UNDERFLOW:
        return rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: %s%s%s underflows a double (nonzero literal "
                       "below the smallest normal double)",
                       line, what, sep, q);
    case NUM_NOMEM:
        return rd_fail(c, FDT_IO_ENOMEM, ":%zu: out of memory", line);
    default:
        return rd_fail(c, FDT_IO_EFORMAT, ":%zu: %s%snot a number: %s", line,
                       what, sep, q);
    }
}

/* ------------------------------------------------------------------ */
/* Lines and fields                                                   */
/* ------------------------------------------------------------------ */

typedef struct rd_lines {
    const char *p, *end;
    size_t lineno; /* number of the line last returned (1-based) */
} rd_lines;

static int rd_next_line(rd_lines *L, const char **s, const char **e)
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
static const char *rd_cut_comment(const char *s, const char *e)
{
    const char *h = memchr(s, '#', (size_t)(e - s));
    return h != NULL ? h : e;
}

static int rd_blank(const char *s, const char *e)
{
    for (; s < e; s++)
        if (!rd_is_space(*s))
            return 0;
    return 1;
}

typedef struct rd_fields {
    const char *p, *e;
    int commas; /* ',' separates fields (text point formats) */
    size_t n;   /* fields returned so far */
} rd_fields;

/*
 * Next field of a line: 1 and the field, 0 at the end of the line, -1 on an
 * empty field (a comma at the start or end of the line, or two commas with
 * nothing between). Fields are separated by whitespace and, when commas is
 * set, by at most one comma.
 */
/* Moves f->p to the start of the next field; same results as below. */
static int rd_skip_sep(rd_fields *f)
{
    const char *p = f->p, *e = f->e;
    while (p < e && rd_is_space(*p))
        p++;
    if (f->commas && p < e && *p == ',') {
        if (f->n == 0) {
            f->p = p;
            return -1;
        }
        p++;
        while (p < e && rd_is_space(*p))
            p++;
        if (p == e || *p == ',') {
            f->p = p;
            return -1;
        }
    }
    f->p = p;
    return p < e;
}

static int rd_is_sep(const rd_fields *f, const char *p)
{
    return p == f->e || rd_is_space(*p) || (f->commas && *p == ',');
}

static int rd_next_field(rd_fields *f, const char **ts, size_t *tl)
{
    int r = rd_skip_sep(f);
    if (r <= 0)
        return r;
    const char *s = f->p, *p = s;
    while (!rd_is_sep(f, p))
        p++;
    f->p = p;
    f->n++;
    *ts = s;
    *tl = (size_t)(p - s);
    return 1;
}

/* Fields left on the line (for "found N" messages); -1 on an empty one. */
static size_t rd_count_rest(rd_fields *f)
{
    const char *ts;
    size_t tl, k = 0;
    int r;
    while ((r = rd_next_field(f, &ts, &tl)) != 0)
        if (r > 0)
            k++;
    return k;
}

/* ------------------------------------------------------------------ */
/* Point storage                                                      */
/* ------------------------------------------------------------------ */

static int rd_points_reserve(rd_points *pb, size_t cap)
{
    if (cap <= pb->cap)
        return 0;
    if (pb->fixed)
        return -1;
    if (cap > SIZE_MAX / (3 * sizeof(double)))
        return -1;
    double *x = realloc(pb->xyz, cap * 3 * sizeof(double));
    if (x == NULL)
        return -1;
    pb->xyz = x;
    pb->cap = cap;
    return 0;
}

/* ------------------------------------------------------------------ */
/* .xyz / .txt                                                        */
/* ------------------------------------------------------------------ */

/* The lines in [start, end) (end: c->buf + c->size or just after a '\n')
 * appended to pb. Every line is parsed on its own: nothing carries from
 * one line to the next, which is what lets rd_read_xyz cut the file. */
static int rd_read_xyz_lines(const rd_ctx *c, const char *start, const char *end,
                             rd_points *pb)
{
    /* A guess from typical line lengths; the array doubles as needed. */
    size_t guess = (size_t)(end - start) / 24 + 16;
    if (guess > RD_MAX_POINTS) /* the growth below checks the limit at cap */
        guess = (size_t)RD_MAX_POINTS;
    if (!pb->fixed && rd_points_reserve(pb, guess) != 0)
        return rd_fail(c, FDT_IO_ENOMEM, ": out of memory");
    rd_lines L = {start, end, 0};
    const char *s, *e;
    while (rd_next_line(&L, &s, &e)) {
        rd_fields f = {s, rd_cut_comment(s, e), 1, 0};
        double v[3];
        size_t k = 0;
        const char *ts;
        size_t tl;
        int r;
        while ((r = rd_skip_sep(&f)) != 0) {
            if (r < 0)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: empty field (stray comma)", L.lineno);
            if (k >= 3) {
                /* only counted, for the message */
                rd_next_field(&f, &ts, &tl);
                k++;
                continue;
            }
            /* Scan and convert in one pass; the field is a number only if
             * a separator follows the literal. */
            size_t used = 0;
            ts = f.p;
            int st = rd_scan_real(ts, (size_t)(f.e - ts), &v[k], 1, 0, &used);
            if (!rd_is_sep(&f, ts + used)) {
                rd_next_field(&f, &ts, &tl);
                st = rd_parse_real(ts, tl, &v[k], 1);
                if (st == NUM_OK) /* cannot happen: the scan stopped early */
                    st = NUM_SYNTAX;
                return rd_num_fail(c, L.lineno, "", st, ts, tl);
            }
            if (st != NUM_OK)
                return rd_num_fail(c, L.lineno, "", st, ts, used);
            f.p = ts + used;
            f.n++;
            k++;
        }
        if (k == 0)
            continue; /* blank or comment line */
        if (k != 3)
            return rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: expected 3 numbers, found %zu", L.lineno, k);
        if (pb->n == pb->cap) {
            if (pb->n >= RD_MAX_POINTS)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: more than %lld points", L.lineno,
                               (long long)RD_MAX_POINTS);
            size_t cap = pb->cap * 2;
            if (cap > RD_MAX_POINTS)
                cap = (size_t)RD_MAX_POINTS;
            if (rd_points_reserve(pb, cap) != 0)
                return rd_fail(c, FDT_IO_ENOMEM,
                               ":%zu: out of memory after %zu points",
                               L.lineno, pb->n);
        }
        memcpy(pb->xyz + 3 * pb->n, v, sizeof v);
        pb->n++;
    }
    return FDT_IO_OK;
}

/*
 * .xyz on several threads: the text is cut into slices at line ends, one a
 * thread. Each slice first counts its lines that hold anything but blanks
 * and a comment (each is a point, or the file has an error); the counts
 * place every slice's points in one array of the file's total, and each
 * slice then parses straight into its place. One array, written once:
 * parsing into an array per slice and joining them cost a copy, and
 * freeing the per-slice arrays raised glibc's mmap threshold (it follows
 * the size of freed blocks up to 32 MB), so that the setup's later arrays
 * came from the heap and stayed in the resident set (46 MB more peak RSS
 * at 1M points).
 *
 * The slices see no messages (their rd_ctx has no buffer, and their line
 * numbers would count from the slice): if any slice fails, or parses
 * another number of points than it counted, the whole text is parsed
 * again on the calling thread, which finds the first error of the file
 * and words it exactly as a one-thread read does. So results and messages
 * never depend on the thread count, and bad files, rare and usually
 * caught early, pay for a second pass.
 */
#define RD_SLICES_MAX 64

typedef struct rd_slice {
    rd_ctx c; /* no message buffer */
    const char *start, *end;
    size_t count; /* lines with content (pass 1) */
    rd_points pb; /* its place in the joint array (pass 2) */
    int pass, rc;
} rd_slice;

/* Lines of [s, e) with a byte before their comment that is not a blank:
 * the lines rd_read_xyz_lines turns into points (or refuses). */
static size_t rd_count_content_lines(const char *s, const char *e)
{
    size_t k = 0;
    while (s < e) {
        const char *nl = memchr(s, '\n', (size_t)(e - s)), *le = nl ? nl : e;
        /* the usual line starts with its first number */
        if (rd_is_digit(*s) || *s == '-' || *s == '.') {
            k++;
        } else {
            for (const char *p = s; p < le && *p != '#'; p++)
                if (!rd_is_space(*p)) {
                    k++;
                    break;
                }
        }
        s = le + 1;
    }
    return k;
}

static void *rd_slice_run(void *arg)
{
    rd_slice *sl = arg;
    if (sl->pass == 0) {
        sl->count = rd_count_content_lines(sl->start, sl->end);
    } else {
        sl->rc = rd_read_xyz_lines(&sl->c, sl->start, sl->end, &sl->pb);
        if (sl->rc == FDT_IO_OK && sl->pb.n != sl->count)
            sl->rc = FDT_IO_EFORMAT; /* cannot happen: the counts are exact */
    }
    return NULL;
}

/* Runs the pass on every slice, slice 0 on this thread; a slice whose
 * thread cannot be created runs here after it (only slower). pthread_join
 * orders each slice's writes before the caller's reads. */
static void rd_slices_pass(rd_slice *sl, size_t T, int pass)
{
    pthread_t tid[RD_SLICES_MAX];
    int made[RD_SLICES_MAX];
    for (size_t t = 0; t < T; t++)
        sl[t].pass = pass;
    for (size_t t = 1; t < T; t++)
        made[t] = pthread_create(&tid[t], NULL, rd_slice_run, &sl[t]) == 0;
    rd_slice_run(&sl[0]);
    for (size_t t = 1; t < T; t++) {
        if (made[t])
            pthread_join(tid[t], NULL);
        else
            rd_slice_run(&sl[t]);
    }
}

static int rd_read_xyz(const rd_ctx *c, const char *start, rd_points *pb)
{
    const char *end = c->buf + c->size;
    size_t len = (size_t)(end - start);
    size_t min_slice = c->min_slice ? c->min_slice : RD_MIN_SLICE;
    size_t T = c->threads > 1 ? (size_t)c->threads : 1;
    if (T > RD_SLICES_MAX)
        T = RD_SLICES_MAX;
    if (T > len / min_slice)
        T = len / min_slice;
    if (T < 2)
        return rd_read_xyz_lines(c, start, end, pb);

    rd_slice sl[RD_SLICES_MAX];
    const char *cut = start;
    for (size_t t = 0; t < T; t++) {
        /* Slice t ends at the first line end at or after its share. */
        const char *want = start + len * (t + 1) / T, *stop = end;
        if (t + 1 < T && want > cut) {
            const char *nl = memchr(want - 1, '\n', (size_t)(end - want + 1));
            stop = nl != NULL ? nl + 1 : end;
        } else if (t + 1 < T) {
            stop = cut;
        }
        memset(&sl[t], 0, sizeof sl[t]);
        sl[t].c = *c;
        sl[t].c.err = NULL;
        sl[t].c.errlen = 0;
        sl[t].start = cut;
        sl[t].end = stop;
        cut = stop;
    }
    rd_slices_pass(sl, T, 0);
    size_t total = 0;
    for (size_t t = 0; t < T; t++)
        total += sl[t].count;
    if (total == 0 || total > RD_MAX_POINTS) /* the one-thread read words it */
        return rd_read_xyz_lines(c, start, end, pb);
    rd_points all = {NULL, 0, 0, 0};
    if (rd_points_reserve(&all, total) != 0)
        return rd_read_xyz_lines(c, start, end, pb); /* which may need less */
    for (size_t t = 0, at = 0; t < T; t++) {
        sl[t].pb = (rd_points){all.xyz + 3 * at, 0, sl[t].count, 1};
        at += sl[t].count;
    }
    rd_slices_pass(sl, T, 1);
    for (size_t t = 0; t < T; t++)
        if (sl[t].rc != FDT_IO_OK) {
            free(all.xyz);
            return rd_read_xyz_lines(c, start, end, pb);
        }
    all.n = total;
    free(pb->xyz);
    *pb = all;
    return FDT_IO_OK;
}

/* ------------------------------------------------------------------ */
/* TetGen .node                                                       */
/* ------------------------------------------------------------------ */

static int rd_read_node(const rd_ctx *c, const char *start, rd_points *pb)
{
    rd_lines L = {start, c->buf + c->size, 0};
    const char *s, *e, *ts;
    size_t tl;
    char q[RD_QUOTE_CAP];
    int r;

    /* Header: <#points> [<dim> [<#attributes> [<markers>]]]; as in TetGen
     * the trailing fields may be left out (3, 0, 0). */
    uint64_t hv[4] = {0, 3, 0, 0};
    size_t hline = 0;
    while (hline == 0 && rd_next_line(&L, &s, &e)) {
        rd_fields f = {s, rd_cut_comment(s, e), 1, 0};
        size_t k = 0;
        while ((r = rd_next_field(&f, &ts, &tl)) != 0) {
            if (r < 0)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: empty field (stray comma)", L.lineno);
            if (k >= 4)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: header has more than 4 fields "
                               "(#points dim #attributes markers)",
                               L.lineno);
            int st = rd_parse_count(ts, tl, &hv[k]);
            if (st == NUM_OVERFLOW)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: header field %s is too large", L.lineno,
                               rd_quote(q, ts, tl));
            if (st != NUM_OK)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: header field %s is not a non-negative "
                               "integer",
                               L.lineno, rd_quote(q, ts, tl));
            k++;
        }
        if (k > 0)
            hline = L.lineno;
    }
    if (hline == 0)
        return rd_fail(c, FDT_IO_EFORMAT, ": no points (no header line)");
    uint64_t npts = hv[0], nattr = hv[2], marker = hv[3];
    if (hv[1] != 3)
        return rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: dimension is %llu, only 3 is supported", hline,
                       (unsigned long long)hv[1]);
    if (marker > 1)
        return rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: boundary marker flag is %llu, expected 0 or 1",
                       hline, (unsigned long long)marker);
    if (npts == 0)
        return rd_fail(c, FDT_IO_EFORMAT,
                       ": no points (the header on line %zu declares 0)",
                       hline);

    /* Every data line needs at least 2 bytes per field (a digit and a
     * separator or newline), the last line's newline excepted. */
    size_t rem = (size_t)(L.end - L.p);
    uint64_t maxpts = 0;
    if (nattr <= (uint64_t)rem) {
        uint64_t per = 2 * (4 + nattr + marker);
        maxpts = ((uint64_t)rem + 1) / per;
    }
    if (npts > maxpts)
        return rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: header declares %llu points but the %zu bytes "
                       "after it can hold at most %llu: refused",
                       hline, (unsigned long long)npts, rem,
                       (unsigned long long)maxpts);
    if (npts > RD_MAX_POINTS)
        return rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: header declares %llu points, more than the "
                       "%lld supported",
                       hline, (unsigned long long)npts,
                       (long long)RD_MAX_POINTS);
    if (rd_points_reserve(pb, (size_t)npts) != 0)
        return rd_fail(c, FDT_IO_ENOMEM, ": out of memory for %llu points",
                       (unsigned long long)npts);

    uint64_t nfields = 4 + nattr + marker;
    int64_t base = 0;
    while (rd_next_line(&L, &s, &e)) {
        rd_fields f = {s, rd_cut_comment(s, e), 1, 0};
        if (rd_blank(f.p, f.e))
            continue;
        if (pb->n == npts)
            return rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: extra data after the %llu points declared "
                           "on line %zu",
                           L.lineno, (unsigned long long)npts, hline);
        double v[3];
        uint64_t k = 0;
        while ((r = rd_next_field(&f, &ts, &tl)) != 0) {
            if (r < 0)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: empty field (stray comma)", L.lineno);
            int st;
            if (k == 0) {
                int64_t idx;
                st = rd_parse_int(ts, tl, &idx);
                if (st != NUM_OK)
                    return rd_fail(c, FDT_IO_EFORMAT,
                                   ":%zu: point index %s is not an integer",
                                   L.lineno, rd_quote(q, ts, tl));
                if (pb->n == 0 && idx != 0 && idx != 1)
                    return rd_fail(c, FDT_IO_EFORMAT,
                                   ":%zu: first point index is %lld, "
                                   "expected 0 or 1",
                                   L.lineno, (long long)idx);
                if (pb->n == 0)
                    base = idx;
                else if (idx != base + (int64_t)pb->n)
                    return rd_fail(c, FDT_IO_EFORMAT,
                                   ":%zu: point index %lld, expected %lld "
                                   "(indices must be consecutive)",
                                   L.lineno, (long long)idx,
                                   (long long)(base + (int64_t)pb->n));
            } else if (k <= 3) {
                st = rd_parse_real(ts, tl, &v[k - 1], 1);
                if (st != NUM_OK)
                    return rd_num_fail(c, L.lineno, "", st, ts, tl);
            } else if (k < 4 + nattr) {
                double dummy;
                st = rd_parse_real(ts, tl, &dummy, 0);
                if (st != NUM_OK && st != NUM_NONFINITE)
                    return rd_num_fail(c, L.lineno, "attribute", st, ts, tl);
            } else if (k < nfields) {
                int64_t m;
                if (rd_parse_int(ts, tl, &m) != NUM_OK)
                    return rd_fail(c, FDT_IO_EFORMAT,
                                   ":%zu: boundary marker %s is not an "
                                   "integer",
                                   L.lineno, rd_quote(q, ts, tl));
            }
            k++;
        }
        if (k != nfields)
            return rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: expected %llu fields (index, x, y, z, %llu "
                           "attributes, %llu markers), found %llu",
                           L.lineno, (unsigned long long)nfields,
                           (unsigned long long)nattr,
                           (unsigned long long)marker, (unsigned long long)k);
        memcpy(pb->xyz + 3 * pb->n, v, sizeof v);
        pb->n++;
    }
    if (pb->n != npts)
        return rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: file ends after %zu of the %llu points declared "
                       "on line %zu",
                       L.lineno, pb->n, (unsigned long long)npts, hline);
    return FDT_IO_OK;
}

/* ------------------------------------------------------------------ */
/* PLY                                                                */
/* ------------------------------------------------------------------ */

enum {
    PT_INT8,
    PT_UINT8,
    PT_INT16,
    PT_UINT16,
    PT_INT32,
    PT_UINT32,
    PT_FLOAT32,
    PT_FLOAT64,
    PT_COUNT
};

static const unsigned char ply_size[PT_COUNT] = {1, 1, 2, 2, 4, 4, 4, 8};
static const int64_t ply_min[PT_COUNT] = {-128, 0, -32768, 0, INT32_MIN, 0,
                                          0, 0};
static const int64_t ply_max[PT_COUNT] = {127, 255, 32767, 65535, INT32_MAX,
                                          UINT32_MAX, 0, 0};

/* The first eight entries are in PT_ order: messages index them by type. */
static const struct {
    const char *name;
    int type;
} ply_type_names[] = {
    {"char", PT_INT8},     {"uchar", PT_UINT8},    {"short", PT_INT16},
    {"ushort", PT_UINT16}, {"int", PT_INT32},      {"uint", PT_UINT32},
    {"float", PT_FLOAT32}, {"double", PT_FLOAT64}, {"int8", PT_INT8},
    {"uint8", PT_UINT8},   {"int16", PT_INT16},    {"uint16", PT_UINT16},
    {"int32", PT_INT32},   {"uint32", PT_UINT32},  {"float32", PT_FLOAT32},
    {"float64", PT_FLOAT64},
};

static int ply_is_float(int t)
{
    return t == PT_FLOAT32 || t == PT_FLOAT64;
}

static int ply_type_lookup(const char *s, size_t len)
{
    for (size_t i = 0; i < sizeof ply_type_names / sizeof ply_type_names[0];
         i++)
        if (rd_tok_is(s, len, ply_type_names[i].name))
            return ply_type_names[i].type;
    return -1;
}

enum { PLY_ASCII, PLY_LE, PLY_BE };

typedef struct ply_prop {
    unsigned char type;       /* scalar type, or the item type of a list */
    unsigned char count_type; /* a list's length type */
    unsigned char is_list;
    unsigned char role; /* 1, 2, 3: x, y, z of the vertex element */
} ply_prop;

typedef struct ply_elem {
    const char *name; /* points into the file buffer */
    size_t name_len;
    uint64_t count;
    size_t first_prop, n_props;
    size_t line;      /* header line that declares it */
    int has_list;
    size_t min_bytes; /* binary bytes per item with every list empty */
    size_t n_scalar;  /* scalar properties */
} ply_elem;

typedef struct ply_hdr {
    int format;
    ply_elem *elems;
    size_t n_elems, cap_elems;
    ply_prop *props;
    size_t n_props, cap_props;
    size_t vertex;   /* index of the vertex element */
    size_t data_off; /* first byte after end_header's newline */
    size_t data_line;
} ply_hdr;

static void ply_hdr_free(ply_hdr *h)
{
    free(h->elems);
    free(h->props);
}

/* Makes room for one more item in the growable array *arr (item size
 * `size`, *n items, capacity *cap, first capacity `first`) and counts it;
 * 0 or -1 when out of memory (the array is then unchanged). */
static int grow_one(void **arr, size_t size, size_t *n, size_t *cap, size_t first)
{
    if (*n == *cap) {
        size_t ncap = *cap ? 2 * *cap : first;
        void *x = realloc(*arr, ncap * size);
        if (x == NULL)
            return -1;
        *arr = x;
        *cap = ncap;
    }
    (*n)++;
    return 0;
}

static int ply_add_elem(ply_hdr *h)
{
    void *a = h->elems;
    int rc = grow_one(&a, sizeof *h->elems, &h->n_elems, &h->cap_elems, 8);
    h->elems = a;
    return rc;
}

static int ply_add_prop(ply_hdr *h)
{
    void *a = h->props;
    int rc = grow_one(&a, sizeof *h->props, &h->n_props, &h->cap_props, 16);
    h->props = a;
    return rc;
}

/* Text for messages: "vertex 3 of 10" or "element 'face' item 3 of 10",
 * counting from 1. */
static const char *ply_item_label(char *out, size_t cap, const ply_hdr *h,
                                  const ply_elem *el, uint64_t i)
{
    if (el == &h->elems[h->vertex]) {
        snprintf(out, cap, "vertex %llu of %llu", (unsigned long long)i + 1,
                 (unsigned long long)el->count);
    } else {
        char q[RD_QUOTE_CAP];
        snprintf(out, cap, "element %s item %llu of %llu",
                 rd_quote(q, el->name, el->name_len),
                 (unsigned long long)i + 1, (unsigned long long)el->count);
    }
    return out;
}

static int ply_parse_header(const rd_ctx *c, ply_hdr *h)
{
    rd_lines L = {c->buf, c->buf + c->size, 0};
    const char *s = c->buf, *e = c->buf, *ts;
    size_t tl;
    char q[RD_QUOTE_CAP], q2[RD_QUOTE_CAP];

    h->format = -1;
    h->vertex = SIZE_MAX;
    if (rd_next_line(&L, &s, &e)) {
        rd_fields f = {s, e, 0, 0};
        int r = rd_next_field(&f, &ts, &tl);
        if (r <= 0 || !rd_tok_is(ts, tl, "ply") || rd_count_rest(&f) != 0)
            return rd_fail(c, FDT_IO_EFORMAT,
                           ":1: not a PLY file (the first line is %s, "
                           "expected 'ply')",
                           rd_quote(q, s, (size_t)(e - s)));
    }
    int ended = 0;
    while (!ended && rd_next_line(&L, &s, &e)) {
        rd_fields f = {s, e, 0, 0};
        const char *tk[5] = {0};
        size_t tn[5] = {0};
        size_t nt = 0;
        while (nt < 5 && rd_next_field(&f, &tk[nt], &tn[nt]) > 0)
            nt++;
        if (nt == 0)
            continue;
        if (rd_tok_is(tk[0], tn[0], "comment") ||
            rd_tok_is(tk[0], tn[0], "obj_info"))
            continue;
        nt += rd_count_rest(&f);
        size_t ln = L.lineno;
        if (rd_tok_is(tk[0], tn[0], "format")) {
            if (h->format >= 0)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: second format line", ln);
            int fm = -1;
            if (nt == 3 && rd_tok_is(tk[1], tn[1], "ascii"))
                fm = PLY_ASCII;
            else if (nt == 3 &&
                     rd_tok_is(tk[1], tn[1], "binary_little_endian"))
                fm = PLY_LE;
            else if (nt == 3 && rd_tok_is(tk[1], tn[1], "binary_big_endian"))
                fm = PLY_BE;
            if (fm < 0 || !rd_tok_is(tk[2], tn[2], "1.0"))
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: expected 'format ascii|"
                               "binary_little_endian|binary_big_endian 1.0'",
                               ln);
            h->format = fm;
        } else if (rd_tok_is(tk[0], tn[0], "element")) {
            if (h->format < 0)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: element before the format line", ln);
            if (nt != 3)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: expected 'element NAME COUNT'", ln);
            uint64_t cnt;
            int st = rd_parse_count(tk[2], tn[2], &cnt);
            if (st == NUM_OVERFLOW)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: element count %s is too large", ln,
                               rd_quote(q, tk[2], tn[2]));
            if (st != NUM_OK)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: element count %s is not a non-negative "
                               "integer",
                               ln, rd_quote(q, tk[2], tn[2]));
            int is_vertex = rd_tok_is(tk[1], tn[1], "vertex");
            if (is_vertex && h->vertex != SIZE_MAX)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: second 'vertex' element", ln);
            if (h->n_elems > 0 && h->elems[h->n_elems - 1].n_props == 0)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: element %s has no properties",
                               h->elems[h->n_elems - 1].line,
                               rd_quote(q, h->elems[h->n_elems - 1].name,
                                        h->elems[h->n_elems - 1].name_len));
            if (ply_add_elem(h) != 0)
                return rd_fail(c, FDT_IO_ENOMEM, ": out of memory");
            ply_elem *el = &h->elems[h->n_elems - 1];
            memset(el, 0, sizeof *el);
            el->name = tk[1];
            el->name_len = tn[1];
            el->count = cnt;
            el->first_prop = h->n_props;
            el->line = ln;
            if (is_vertex)
                h->vertex = h->n_elems - 1;
        } else if (rd_tok_is(tk[0], tn[0], "property")) {
            if (h->n_elems == 0)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: property before any element", ln);
            ply_prop p = {0, 0, 0, 0};
            const char *name;
            size_t name_len;
            if (nt == 5 && rd_tok_is(tk[1], tn[1], "list")) {
                int ct = ply_type_lookup(tk[2], tn[2]);
                int it = ply_type_lookup(tk[3], tn[3]);
                if (ct < 0 || it < 0)
                    return rd_fail(c, FDT_IO_EFORMAT,
                                   ":%zu: unknown property type %s",
                                   ln, ct < 0 ? rd_quote(q, tk[2], tn[2])
                                              : rd_quote(q, tk[3], tn[3]));
                if (ply_is_float(ct))
                    return rd_fail(c, FDT_IO_EFORMAT,
                                   ":%zu: list length type %s is not an "
                                   "integer type",
                                   ln, rd_quote(q, tk[2], tn[2]));
                p.is_list = 1;
                p.count_type = (unsigned char)ct;
                p.type = (unsigned char)it;
                name = tk[4];
                name_len = tn[4];
            } else if (nt == 3) {
                int t = ply_type_lookup(tk[1], tn[1]);
                if (t < 0)
                    return rd_fail(c, FDT_IO_EFORMAT,
                                   ":%zu: unknown property type %s", ln,
                                   rd_quote(q, tk[1], tn[1]));
                p.type = (unsigned char)t;
                name = tk[2];
                name_len = tn[2];
            } else {
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: expected 'property TYPE NAME' or "
                               "'property list COUNTTYPE ITEMTYPE NAME'",
                               ln);
            }
            ply_elem *el = &h->elems[h->n_elems - 1];
            if (h->vertex == h->n_elems - 1 && name_len == 1 &&
                name[0] >= 'x' && name[0] <= 'z') {
                int role = name[0] - 'x' + 1;
                for (size_t i = el->first_prop; i < h->n_props; i++)
                    if (h->props[i].role == role)
                        return rd_fail(c, FDT_IO_EFORMAT,
                                       ":%zu: second vertex property %s", ln,
                                       rd_quote(q, name, name_len));
                if (p.is_list)
                    return rd_fail(c, FDT_IO_EFORMAT,
                                   ":%zu: vertex property %s is a list", ln,
                                   rd_quote(q, name, name_len));
                p.role = (unsigned char)role;
            }
            if (ply_add_prop(h) != 0)
                return rd_fail(c, FDT_IO_ENOMEM, ": out of memory");
            h->props[h->n_props - 1] = p;
            el->n_props++;
            if (p.is_list) {
                el->has_list = 1;
                el->min_bytes += ply_size[p.count_type];
            } else {
                el->n_scalar++;
                el->min_bytes += ply_size[p.type];
            }
        } else if (rd_tok_is(tk[0], tn[0], "end_header")) {
            if (nt != 1)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: unexpected text after end_header", ln);
            ended = 1;
        } else {
            /* a number here is data: the end_header line is missing */
            int data = rd_is_digit(tk[0][0]) || tk[0][0] == '-' ||
                       tk[0][0] == '+' || tk[0][0] == '.';
            return rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: unknown header keyword %s%s", ln,
                           rd_quote(q, tk[0], tn[0]),
                           data ? " (no end_header line before the data?)"
                                : "");
        }
    }
    if (!ended)
        return rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: the header has no end_header line", L.lineno);
    h->data_off = (size_t)(L.p - c->buf);
    h->data_line = L.lineno;
    if (h->format < 0)
        return rd_fail(c, FDT_IO_EFORMAT, ": the header has no format line");
    if (h->n_elems > 0 && h->elems[h->n_elems - 1].n_props == 0)
        return rd_fail(c, FDT_IO_EFORMAT, ":%zu: element %s has no properties",
                       h->elems[h->n_elems - 1].line,
                       rd_quote(q, h->elems[h->n_elems - 1].name,
                                h->elems[h->n_elems - 1].name_len));
    if (h->vertex == SIZE_MAX)
        return rd_fail(c, FDT_IO_EFORMAT,
                       ": no points (the header has no 'vertex' element)");
    const ply_elem *v = &h->elems[h->vertex];
    int have[4] = {0, 0, 0, 0};
    for (size_t i = 0; i < v->n_props; i++)
        have[h->props[v->first_prop + i].role] = 1;
    for (int k = 1; k <= 3; k++)
        if (!have[k]) {
            char nm[2] = {(char)('x' + k - 1), '\0'};
            return rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: the vertex element has no %s property",
                           v->line, rd_quote(q2, nm, 1));
        }
    if (v->count == 0)
        return rd_fail(c, FDT_IO_EFORMAT,
                       ": no points (the vertex element on line %zu has "
                       "count 0)",
                       v->line);
    return FDT_IO_OK;
}

/* Loads an unsigned integer of sz bytes in the file's byte order. */
static uint64_t ply_load(const unsigned char *b, size_t sz, int big)
{
    uint64_t u = 0;
    if (big) {
        for (size_t i = 0; i < sz; i++)
            u = (u << 8) | b[i];
    } else {
        for (size_t i = sz; i-- > 0;)
            u = (u << 8) | b[i];
    }
    return u;
}

/* Sign-extends the low 8*sz bits of u (no implementation-defined casts). */
static int64_t ply_signed(uint64_t u, size_t sz)
{
    uint64_t sign = (uint64_t)1 << (8 * sz - 1);
    if (u & sign)
        return -(int64_t)((sign << 1) - u);
    return (int64_t)u;
}

static int64_t ply_get_int(const unsigned char *b, int type, int big)
{
    size_t sz = ply_size[type];
    uint64_t u = ply_load(b, sz, big);
    if (type == PT_INT8 || type == PT_INT16 || type == PT_INT32)
        return ply_signed(u, sz);
    return (int64_t)u;
}

static double ply_get(const unsigned char *b, int type, int big)
{
    if (type == PT_FLOAT32) {
        uint32_t w = (uint32_t)ply_load(b, 4, big);
        float f;
        memcpy(&f, &w, sizeof f);
        return (double)f;
    }
    if (type == PT_FLOAT64) {
        uint64_t w = ply_load(b, 8, big);
        double d;
        memcpy(&d, &w, sizeof d);
        return d;
    }
    return (double)ply_get_int(b, type, big);
}

/*
 * Walks one binary item of el from *off. Fills roff[0..2] with the offsets
 * of x, y, z when roff is not NULL. Returns 0, 1 when the data ends inside
 * the item (*off then tells where the shortfall was found), or 2 on a
 * negative list length (*off at that length).
 */
static int ply_bin_item(const rd_ctx *c, const ply_hdr *h, const ply_elem *el,
                        size_t *off, int big, size_t roff[3])
{
    const unsigned char *b = (const unsigned char *)c->buf;
    size_t o = *off;
    for (size_t i = 0; i < el->n_props; i++) {
        const ply_prop *p = &h->props[el->first_prop + i];
        if (!p->is_list) {
            size_t sz = ply_size[p->type];
            if (c->size - o < sz)
                return 1;
            if (p->role && roff != NULL)
                roff[p->role - 1] = o;
            o += sz;
            continue;
        }
        size_t csz = ply_size[p->count_type];
        if (c->size - o < csz)
            return 1;
        int64_t len = ply_get_int(b + o, p->count_type, big);
        if (len < 0) {
            *off = o;
            return 2;
        }
        o += csz;
        size_t isz = ply_size[p->type];
        if ((uint64_t)len > (c->size - o) / isz)
            return 1;
        o += (size_t)len * isz;
    }
    *off = o;
    return 0;
}

/* Walks the binary items of an element that is not read. */
static int ply_bin_skip(const rd_ctx *c, const ply_hdr *h, const ply_elem *el,
                        size_t *off, int big)
{
    char lab[160];
    if (!el->has_list) {
        size_t rem = c->size - *off;
        uint64_t fit = rem / el->min_bytes;
        if (el->count > fit)
            return rd_fail(c, FDT_IO_EFORMAT,
                           ": byte %zu: file ends %s %s", c->size,
                           rem % el->min_bytes ? "inside" : "before",
                           ply_item_label(lab, sizeof lab, h, el, fit));
        *off += (size_t)el->count * el->min_bytes;
        return FDT_IO_OK;
    }
    for (uint64_t i = 0; i < el->count; i++) {
        int r = ply_bin_item(c, h, el, off, big, NULL);
        if (r == 1)
            return rd_fail(c, FDT_IO_EFORMAT,
                           ": byte %zu: file ends inside %s", c->size,
                           ply_item_label(lab, sizeof lab, h, el, i));
        if (r == 2)
            return rd_fail(c, FDT_IO_EFORMAT,
                           ": byte %zu: %s: negative list length", *off,
                           ply_item_label(lab, sizeof lab, h, el, i));
    }
    return FDT_IO_OK;
}

static int ply_check_count(const rd_ctx *c, const ply_elem *el,
                           rd_points *pb)
{
    if (el->count > RD_MAX_POINTS)
        return rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: the vertex element declares %llu points, more "
                       "than the %lld supported",
                       el->line, (unsigned long long)el->count,
                       (long long)RD_MAX_POINTS);
    if (rd_points_reserve(pb, (size_t)el->count) != 0)
        return rd_fail(c, FDT_IO_ENOMEM, ": out of memory for %llu points",
                       (unsigned long long)el->count);
    return FDT_IO_OK;
}

static int ply_bin_vertex(const rd_ctx *c, const ply_hdr *h,
                          const ply_elem *el, size_t *off, int big,
                          rd_points *pb)
{
    char lab[160];
    size_t rem = c->size - *off;
    uint64_t fit = rem / el->min_bytes;
    /* Refuse before allocating: the header's count must fit the bytes
     * left (exactly for fixed-size vertices, at least for ones with lists). */
    if (el->count > fit) {
        if (!el->has_list)
            return rd_fail(c, FDT_IO_EFORMAT,
                           ": byte %zu: file ends %s %s (the header declares "
                           "%llu vertices of %zu bytes, %zu bytes follow it)",
                           c->size, rem % el->min_bytes ? "inside" : "before",
                           ply_item_label(lab, sizeof lab, h, el, fit),
                           (unsigned long long)el->count, el->min_bytes, rem);
        return rd_fail(c, FDT_IO_EFORMAT,
                       ": byte %zu: the header declares %llu vertices of at "
                       "least %zu bytes, only %zu bytes follow: refused",
                       *off, (unsigned long long)el->count, el->min_bytes,
                       rem);
    }
    int rc = ply_check_count(c, el, pb);
    if (rc != FDT_IO_OK)
        return rc;
    const unsigned char *b = (const unsigned char *)c->buf;
    int type[3];
    size_t roff[3] = {0, 0, 0};
    for (size_t i = 0; i < el->n_props; i++) {
        const ply_prop *p = &h->props[el->first_prop + i];
        if (p->role)
            type[p->role - 1] = p->type;
    }
    size_t fixed_off[3] = {0, 0, 0};
    if (!el->has_list) {
        size_t o = 0;
        for (size_t i = 0; i < el->n_props; i++) {
            const ply_prop *p = &h->props[el->first_prop + i];
            if (p->role)
                fixed_off[p->role - 1] = o;
            o += ply_size[p->type];
        }
    }
    for (uint64_t i = 0; i < el->count; i++) {
        if (el->has_list) {
            int r = ply_bin_item(c, h, el, off, big, roff);
            if (r == 1)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ": byte %zu: file ends inside %s", c->size,
                               ply_item_label(lab, sizeof lab, h, el, i));
            if (r == 2)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ": byte %zu: %s: negative list length", *off,
                               ply_item_label(lab, sizeof lab, h, el, i));
        } else {
            for (int k = 0; k < 3; k++)
                roff[k] = *off + fixed_off[k];
            *off += el->min_bytes;
        }
        double *dst = pb->xyz + 3 * pb->n;
        for (int k = 0; k < 3; k++) {
            double v = ply_get(b + roff[k], type[k], big);
            if (!isfinite(v))
                return rd_fail(c, FDT_IO_EFORMAT,
                               ": byte %zu: %s: %c is %s", roff[k],
                               ply_item_label(lab, sizeof lab, h, el, i),
                               'x' + k, isnan(v) ? "NaN" : "infinite");
            dst[k] = v;
        }
        pb->n++;
    }
    return FDT_IO_OK;
}

static int ply_read_binary(const rd_ctx *c, const ply_hdr *h, rd_points *pb)
{
    int big = h->format == PLY_BE;
    size_t off = h->data_off;
    for (size_t ei = 0; ei < h->n_elems; ei++) {
        const ply_elem *el = &h->elems[ei];
        int rc = ei == h->vertex ? ply_bin_vertex(c, h, el, &off, big, pb)
                                 : ply_bin_skip(c, h, el, &off, big);
        if (rc != FDT_IO_OK)
            return rc;
    }
    if (off != c->size)
        return rd_fail(c, FDT_IO_EFORMAT,
                       ": byte %zu: %zu bytes of extra data after the last "
                       "element (the header's counts are too small?)",
                       off, c->size - off);
    return FDT_IO_OK;
}

/*
 * Reads one ASCII item (one line) of el. For the vertex element, dst
 * receives x, y, z.
 */
static int ply_ascii_item(const rd_ctx *c, const ply_hdr *h,
                          const ply_elem *el, uint64_t idx, size_t line,
                          const char *s, const char *e, double *dst)
{
    char lab[160], q[RD_QUOTE_CAP];
    rd_fields f = {s, e, 0, 0};
    const char *ts;
    size_t tl, found = 0;
    for (size_t i = 0; i < el->n_props; i++) {
        const ply_prop *p = &h->props[el->first_prop + i];
        uint64_t nvals = 1;
        int type = p->type;
        if (p->is_list) {
            if (rd_next_field(&f, &ts, &tl) <= 0)
                goto too_few;
            found++;
            int64_t len;
            if (rd_parse_int(ts, tl, &len) != NUM_OK || len < 0 ||
                len > ply_max[p->count_type])
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: %s: list length %s is not a valid %s",
                               line, ply_item_label(lab, sizeof lab, h, el,
                                                    idx),
                               rd_quote(q, ts, tl), "count");
            nvals = (uint64_t)len;
        }
        for (uint64_t j = 0; j < nvals; j++) {
            if (rd_next_field(&f, &ts, &tl) <= 0)
                goto too_few;
            found++;
            double v = 0.0;
            int st;
            if (ply_is_float(type)) {
                st = rd_parse_real(ts, tl, &v, p->role != 0);
                /* ignored properties may hold nan/inf (normals often do) */
                if (p->role == 0 && st == NUM_NONFINITE)
                    st = NUM_OK;
            } else {
                int64_t iv;
                st = rd_parse_int(ts, tl, &iv);
                if (st == NUM_OK && (iv < ply_min[type] || iv > ply_max[type]))
                    st = NUM_OVERFLOW;
                if (st != NUM_OK)
                    return rd_fail(c, FDT_IO_EFORMAT,
                                   ":%zu: %s: %s is not a valid %s", line,
                                   ply_item_label(lab, sizeof lab, h, el,
                                                  idx),
                                   rd_quote(q, ts, tl),
                                   ply_type_names[type].name);
                v = (double)iv;
            }
            if (st != NUM_OK)
                return rd_num_fail(c, line,
                                   ply_item_label(lab, sizeof lab, h, el,
                                                  idx),
                                   st, ts, tl);
            if (p->role && dst != NULL)
                dst[p->role - 1] = v;
        }
    }
    if (rd_next_field(&f, &ts, &tl) > 0) {
        size_t extra = 1 + rd_count_rest(&f);
        return rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: %s: expected %zu values, found %zu", line,
                       ply_item_label(lab, sizeof lab, h, el, idx), found,
                       found + extra);
    }
    return FDT_IO_OK;
too_few:
    if (!el->has_list)
        return rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: %s: expected %zu values, found %zu", line,
                       ply_item_label(lab, sizeof lab, h, el, idx),
                       el->n_scalar, found);
    return rd_fail(c, FDT_IO_EFORMAT, ":%zu: %s: too few values (found %zu)",
                   line, ply_item_label(lab, sizeof lab, h, el, idx), found);
}

static int ply_read_ascii(const rd_ctx *c, const ply_hdr *h, rd_points *pb)
{
    char lab[160];
    rd_lines L = {c->buf + h->data_off, c->buf + c->size, h->data_line};
    const char *s, *e;
    for (size_t ei = 0; ei < h->n_elems; ei++) {
        const ply_elem *el = &h->elems[ei];
        int is_vertex = ei == h->vertex;
        if (is_vertex) {
            /* Each item is a line of at least 2 bytes per field. */
            size_t rem = (size_t)(L.end - L.p);
            uint64_t per = 2 * (uint64_t)(el->n_scalar +
                                          (el->n_props - el->n_scalar));
            uint64_t maxn = ((uint64_t)rem + 1) / per;
            if (el->count > maxn)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: the header declares %llu vertices but "
                               "the %zu bytes left can hold at most %llu: "
                               "refused",
                               el->line, (unsigned long long)el->count, rem,
                               (unsigned long long)maxn);
            int rc = ply_check_count(c, el, pb);
            if (rc != FDT_IO_OK)
                return rc;
        }
        for (uint64_t i = 0; i < el->count; i++) {
            int got = 0;
            while ((got = rd_next_line(&L, &s, &e)) != 0 && rd_blank(s, e))
                ;
            if (!got)
                return rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: file ends before %s", L.lineno,
                               ply_item_label(lab, sizeof lab, h, el, i));
            double *dst = is_vertex ? pb->xyz + 3 * pb->n : NULL;
            int rc = ply_ascii_item(c, h, el, i, L.lineno, s, e, dst);
            if (rc != FDT_IO_OK)
                return rc;
            if (is_vertex)
                pb->n++;
        }
    }
    while (rd_next_line(&L, &s, &e))
        if (!rd_blank(s, e))
            return rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: extra data after the last element (the "
                           "header's counts are too small?)",
                           L.lineno);
    return FDT_IO_OK;
}

static int rd_read_ply(const rd_ctx *c, rd_points *pb)
{
    ply_hdr h;
    memset(&h, 0, sizeof h);
    int rc = ply_parse_header(c, &h);
    if (rc == FDT_IO_OK)
        rc = h.format == PLY_ASCII ? ply_read_ascii(c, &h, pb)
                                   : ply_read_binary(c, &h, pb);
    ply_hdr_free(&h);
    return rc;
}

/* ------------------------------------------------------------------ */
/* Files                                                              */
/* ------------------------------------------------------------------ */

enum { EXT_NONE, EXT_XYZ, EXT_NODE, EXT_PLY };

static int rd_extension(const char *path, const char **ext)
{
    const char *slash = strrchr(path, '/');
    const char *base = slash != NULL ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    *ext = dot != NULL ? dot : "";
    if (dot == NULL)
        return EXT_NONE;
    size_t len = strlen(dot + 1);
    if (rd_word_ieq(dot + 1, len, "xyz") || rd_word_ieq(dot + 1, len, "txt"))
        return EXT_XYZ;
    if (rd_word_ieq(dot + 1, len, "node"))
        return EXT_NODE;
    if (rd_word_ieq(dot + 1, len, "ply"))
        return EXT_PLY;
    return EXT_NONE;
}

/* Reads the whole of fd into a NUL-terminated buffer. */
static int rd_slurp(rd_ctx *c, int fd, const struct stat *st, char **out)
{
    size_t cap = 1 << 16;
    if (S_ISREG(st->st_mode)) {
        if ((uintmax_t)st->st_size > (uintmax_t)SIZE_MAX - 2)
            return rd_fail(c, FDT_IO_ENOMEM, ": file too large for memory");
        /* one spare byte shows whether the file grew since fstat */
        cap = (size_t)st->st_size + 2;
    }
    char *buf = malloc(cap);
    if (buf == NULL)
        return rd_fail(c, FDT_IO_ENOMEM,
                       ": out of memory reading %zu bytes", cap - 2);
    size_t len = 0;
    for (;;) {
        if (len == cap - 1) {
            if (cap > SIZE_MAX / 2) {
                free(buf);
                return rd_fail(c, FDT_IO_ENOMEM, ": file too large for memory");
            }
            char *nb = realloc(buf, cap * 2);
            if (nb == NULL) {
                free(buf);
                return rd_fail(c, FDT_IO_ENOMEM,
                               ": out of memory reading the file");
            }
            buf = nb;
            cap *= 2;
        }
        ssize_t r = read(fd, buf + len, cap - 1 - len);
        if (r == 0)
            break;
        if (r < 0) {
            if (errno == EINTR)
                continue;
            int e = errno;
            free(buf);
            if (e == EISDIR)
                return rd_fail(c, FDT_IO_EOPEN, ": is a directory");
            return rd_fail(c, FDT_IO_EOPEN, ": cannot read: %s", strerror(e));
        }
        len += (size_t)r;
    }
    buf[len] = '\0';
    *out = buf;
    c->buf = buf;
    c->size = len;
    return FDT_IO_OK;
}

/* Starts a read: clears the outputs and the message. */
static void rd_begin(rd_ctx *c, double **xyz, size_t *n)
{
    if (xyz != NULL)
        *xyz = NULL;
    if (n != NULL)
        *n = 0;
    if (c->err != NULL && c->errlen > 0)
        c->err[0] = '\0';
}

/*
 * Parses c->buf (c->size bytes and a NUL, owned by the caller) as a file of
 * the given kind. On success *xyz and *n are set; on failure they are left
 * alone and the message is in c->err.
 */
static int rd_parse(rd_ctx *c, int kind, double **xyz, size_t *n)
{
    rd_points pb = {NULL, 0, 0, 0};
    int rc;
    if (c->size == 0) {
        rc = rd_fail(c, FDT_IO_EFORMAT, ": no points (empty file)");
    } else if (kind == EXT_PLY) {
        rc = rd_read_ply(c, &pb);
    } else {
        const char *start = c->buf;
        /* a UTF-8 byte order mark, as some Windows tools write */
        if (c->size >= 3 && memcmp(c->buf, "\xef\xbb\xbf", 3) == 0)
            start += 3;
        rc = kind == EXT_NODE ? rd_read_node(c, start, &pb)
                              : rd_read_xyz(c, start, &pb);
    }
    if (rc == FDT_IO_OK && pb.n == 0)
        rc = rd_fail(c, FDT_IO_EFORMAT, ": no points");
    if (rc != FDT_IO_OK) {
        free(pb.xyz);
        return rc;
    }
    if (pb.cap > pb.n) {
        double *x = realloc(pb.xyz, pb.n * 3 * sizeof(double));
        if (x != NULL) /* shrinking cannot lose data; keep the old block */
            pb.xyz = x;
    }
    *xyz = pb.xyz;
    *n = pb.n;
    return FDT_IO_OK;
}

/* The "unknown extension" refusal shared by both entry points. */
static int rd_bad_extension(const rd_ctx *c, const char *ext)
{
    char q[RD_QUOTE_CAP];
    return rd_fail(c, FDT_IO_EEXT,
                   ": unknown extension %s (expected .xyz, .txt, .node or "
                   ".ply)",
                   rd_quote(q, ext, strlen(ext)));
}

static int rd_read_path(const char *path, int threads, size_t min_slice, double **xyz,
                        size_t *n, char *err, size_t errlen)
{
    rd_ctx c = {path != NULL ? path : "(null)", err, errlen, NULL, 0, threads, min_slice};
    rd_begin(&c, xyz, n);
    if (path == NULL || xyz == NULL || n == NULL)
        return rd_fail(&c, FDT_IO_EOPEN, ": invalid arguments");

    int fd;
    do
        fd = open(path, O_RDONLY | O_CLOEXEC);
    while (fd < 0 && errno == EINTR);
    if (fd < 0)
        return rd_fail(&c, FDT_IO_EOPEN, ": cannot open: %s", strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0) {
        int e = errno;
        close(fd);
        return rd_fail(&c, FDT_IO_EOPEN, ": cannot open: %s", strerror(e));
    }
    if (S_ISDIR(st.st_mode)) {
        close(fd);
        return rd_fail(&c, FDT_IO_EOPEN, ": is a directory");
    }
    const char *ext;
    int kind = rd_extension(path, &ext);
    if (kind == EXT_NONE) {
        close(fd);
        return rd_bad_extension(&c, ext);
    }
    char *buf = NULL;
    int rc = rd_slurp(&c, fd, &st, &buf);
    close(fd);
    if (rc != FDT_IO_OK)
        return rc;
    rc = rd_parse(&c, kind, xyz, n);
    free(buf);
    return rc;
}

static int rd_read_mem(const char *name, const void *data, size_t len, int threads,
                       size_t min_slice, double **xyz, size_t *n, char *err, size_t errlen)
{
    rd_ctx c = {name != NULL ? name : "(null)", err, errlen, NULL, 0, threads, min_slice};
    rd_begin(&c, xyz, n);
    if (name == NULL || (data == NULL && len > 0) || xyz == NULL || n == NULL)
        return rd_fail(&c, FDT_IO_EOPEN, ": invalid arguments");
    const char *ext;
    int kind = rd_extension(name, &ext);
    if (kind == EXT_NONE)
        return rd_bad_extension(&c, ext);
    /* The parsers expect what rd_slurp gives them: a private copy with a
     * NUL after the last byte. Copying keeps the two entry points one code
     * path (and lets the fuzzers find reads past that NUL). */
    if (len > SIZE_MAX - 1)
        return rd_fail(&c, FDT_IO_ENOMEM, ": file too large for memory");
    char *buf = malloc(len + 1);
    if (buf == NULL)
        return rd_fail(&c, FDT_IO_ENOMEM, ": out of memory reading %zu bytes",
                       len);
    if (len > 0)
        memcpy(buf, data, len);
    buf[len] = '\0';
    c.buf = buf;
    c.size = len;
    int rc = rd_parse(&c, kind, xyz, n);
    free(buf);
    return rc;
}

int fdt_read_points(const char *path, double **xyz, size_t *n, char *err,
                    size_t errlen)
{
    return rd_read_path(path, 1, 0, xyz, n, err, errlen);
}

int fdt_read_points_threads(const char *path, int threads, size_t min_slice, double **xyz,
                            size_t *n, char *err, size_t errlen)
{
    return rd_read_path(path, threads, min_slice, xyz, n, err, errlen);
}

int fdt_read_points_mem(const char *name, const void *data, size_t len,
                        double **xyz, size_t *n, char *err, size_t errlen)
{
    return rd_read_mem(name, data, len, 1, 0, xyz, n, err, errlen);
}

int fdt_read_points_mem_threads(const char *name, const void *data, size_t len, int threads,
                                size_t min_slice, double **xyz, size_t *n, char *err,
                                size_t errlen)
{
    return rd_read_mem(name, data, len, threads, min_slice, xyz, n, err, errlen);
}
