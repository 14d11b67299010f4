/*
 * Tests for the point readers (src/io/read/reader.c).
 *
 *   test_reader BAD_DIR GOOD_DIR   unit tests, then replays the tables
 *                                  tests/bad/EXPECTED.txt and
 *                                  tests/good/EXPECTED.txt
 *   test_reader --data DATA_DIR    reads the real clouds listed in
 *                                  DATA_DIR/README.md (exit 77 if absent)
 *
 * Valid inputs of every format are written to a private temporary directory
 * and must read back bit for bit; hostile inputs must fail with the right
 * code and a message naming the file and the line or byte offset.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "base/hash.h"
#include "io/read/read_common.h"
#include "io/read/reader.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <locale.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>
#include "testutil.h"

#define SKIP_CODE 77

typedef struct tctx {
    char dir[512];   /* private temporary directory */
    uint64_t rng;    /* splitmix64 state: deterministic inputs */
} tctx;

static void fail_at(tctx *t, int line, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static void fail_at(tctx *t, int line, const char *fmt, ...)
{
    (void)t;
    va_list ap;
    va_start(ap, fmt);
    test_failv_(__FILE__, line, NULL, fmt, ap);
    va_end(ap);
}

static uint64_t rnd(tctx *t)
{
    return fdt_splitmix64(&t->rng);
}

static uint64_t rnd_below(tctx *t, uint64_t n)
{
    return rnd(t) % n;
}

/* ------------------------------------------------------------------ */
/* Byte buffers and files                                             */
/* ------------------------------------------------------------------ */

typedef struct bbuf {
    unsigned char *p;
    size_t n, cap;
} bbuf;

static void bb_put(bbuf *b, const void *data, size_t len)
{
    if (b->n + len > b->cap) {
        size_t cap = b->cap ? b->cap : 256;
        while (cap < b->n + len)
            cap *= 2;
        unsigned char *x = realloc(b->p, cap);
        if (x == NULL) {
            fprintf(stderr, "test_reader: out of memory\n");
            exit(1);
        }
        b->p = x;
        b->cap = cap;
    }
    if (len > 0)
        memcpy(b->p + b->n, data, len);
    b->n += len;
}

static void bb_printf(bbuf *b, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static void bb_printf(bbuf *b, const char *fmt, ...)
{
    char tmp[1024];
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (k < 0 || (size_t)k >= sizeof tmp) {
        fprintf(stderr, "test_reader: bb_printf overflow\n");
        exit(1);
    }
    bb_put(b, tmp, (size_t)k);
}

static void bb_free(bbuf *b)
{
    free(b->p);
    b->p = NULL;
    b->n = b->cap = 0;
}

/* Writes data to DIR/name; path receives the full name. */
static void write_file(tctx *t, const char *name, const void *data,
                       size_t len, char *path, size_t pathlen)
{
    snprintf(path, pathlen, "%s/%s", t->dir, name);
    FILE *f = fopen(path, "wb");
    if (f == NULL || (len > 0 && fwrite(data, 1, len, f) != len) ||
        fclose(f) != 0) {
        fprintf(stderr, "test_reader: cannot write %s\n", path);
        exit(1);
    }
}

static void remove_tree(const char *dir)
{
    DIR *d = opendir(dir);
    if (d == NULL)
        return;
    struct dirent *de;
    char path[1024];
    while ((de = readdir(d)) != NULL) {
        if (strcmp(de->d_name, ".") == 0 || strcmp(de->d_name, "..") == 0)
            continue;
        snprintf(path, sizeof path, "%s/%s", dir, de->d_name);
        struct stat st;
        if (lstat(path, &st) == 0 && S_ISDIR(st.st_mode))
            remove_tree(path);
        else
            unlink(path);
    }
    closedir(d);
    rmdir(dir);
}

/* ------------------------------------------------------------------ */
/* Expectations                                                       */
/* ------------------------------------------------------------------ */

static const char *code_name(int rc)
{
    switch (rc) {
    case FDT_IO_OK: return "OK";
    case FDT_IO_EOPEN: return "EOPEN";
    case FDT_IO_EFORMAT: return "EFORMAT";
    case FDT_IO_ENOMEM: return "ENOMEM";
    case FDT_IO_EWRITE: return "EWRITE";
    case FDT_IO_EEXT: return "EEXT";
    default: return "?";
    }
}

/* Reads path and checks the points bit for bit (want == NULL: only n). */
static void check_read_ok(tctx *t, int line, const char *path,
                          const double *want, size_t n)
{
    double *xyz = (double *)&xyz; /* must be overwritten */
    size_t got = 12345;
    char err[512];
    int rc = fdt_rd_points(path, &xyz, &got, err, sizeof err);
    test_count_checks(1);
    if (rc != FDT_IO_OK) {
        fail_at(t, line, "%s: expected OK, got %s: %s", path, code_name(rc),
                err);
        return;
    }
    if (got != n) {
        fail_at(t, line, "%s: expected %zu points, got %zu", path, n, got);
    } else if (want != NULL) {
        for (size_t i = 0; i < 3 * n; i++) {
            if (memcmp(&xyz[i], &want[i], sizeof(double)) != 0) {
                fail_at(t, line,
                        "%s: point %zu coordinate %zu: got %.17g, want %.17g",
                        path, i / 3, i % 3, xyz[i], want[i]);
                break;
            }
        }
    }
    /* Sliced reads (src/io/read/reader.c, rd_read_xyz): slices of a byte and up,
     * so that even these small files are cut, give the same points. */
    static const int threads[] = {2, 3, 7};
    for (size_t k = 0; k < sizeof threads / sizeof *threads && got == n; k++) {
        double *px = NULL;
        size_t pn = 0;
        int prc = fdt_rd_points_threads(path, threads[k], 1, &px, &pn, err, sizeof err);
        test_count_checks(1);
        if (prc != FDT_IO_OK || pn != n || memcmp(px, xyz, 3 * n * sizeof *xyz) != 0)
            fail_at(t, line, "%s: %d threads read %s (%zu points), not what one thread read",
                    path, threads[k], code_name(prc), pn);
        free(px);
    }
    free(xyz);
}

/* Reads path and checks the code, the outputs and the message. */
static void check_read_err(tctx *t, int line, const char *path, int code,
                           const char *substr)
{
    double *xyz = (double *)&xyz;
    size_t n = 12345;
    char err[512];
    memset(err, 'X', sizeof err);
    int rc = fdt_rd_points(path, &xyz, &n, err, sizeof err);
    test_count_checks(1);
    if (rc != code) {
        fail_at(t, line, "%s: expected %s, got %s: %.*s", path,
                code_name(code), code_name(rc), (int)sizeof err - 1, err);
        if (rc == FDT_IO_OK)
            free(xyz);
        return;
    }
    if (xyz != NULL || n != 0)
        fail_at(t, line, "%s: outputs not cleared on failure", path);
    if (memchr(err, '\0', sizeof err) == NULL) {
        fail_at(t, line, "%s: message not terminated", path);
        return;
    }
    if (strncmp(err, path, strlen(path)) != 0)
        fail_at(t, line, "%s: message does not start with the path: %s", path,
                err);
    if (strchr(err, '\n') != NULL)
        fail_at(t, line, "%s: message is not one line: %s", path, err);
    if (substr != NULL && strstr(err, substr) == NULL)
        fail_at(t, line, "%s: message lacks \"%s\": %s", path, substr, err);
    /* Sliced reads: the same code and the very same message. */
    static const int threads[] = {2, 3, 7};
    for (size_t k = 0; k < sizeof threads / sizeof *threads; k++) {
        double *px = (double *)&px;
        size_t pn = 12345;
        char perr[512];
        int prc = fdt_rd_points_threads(path, threads[k], 1, &px, &pn, perr, sizeof perr);
        test_count_checks(1);
        if (prc != rc || px != NULL || pn != 0 || strcmp(perr, err) != 0) {
            fail_at(t, line, "%s: %d threads: %s \"%s\", one thread: %s \"%s\"", path,
                    threads[k], code_name(prc), prc == FDT_IO_OK ? "" : perr, code_name(rc),
                    err);
            if (prc == FDT_IO_OK)
                free(px);
        }
    }
}

#define EXPECT_OK(t, path, want, n) check_read_ok((t), __LINE__, path, want, n)
#define EXPECT_ERR(t, path, code, sub)                                        \
    check_read_err((t), __LINE__, path, code, sub)

/* Writes a text file and expects an EFORMAT error with a message. */
static void text_err(tctx *t, int line, const char *name, const char *text,
                     const char *substr)
{
    char path[1024], full[600];
    write_file(t, name, text, strlen(text), path, sizeof path);
    snprintf(full, sizeof full, "%s%s", name, substr);
    check_read_err(t, line, path, FDT_IO_EFORMAT, full);
}

#define TEXT_ERR(t, name, text, sub) text_err((t), __LINE__, name, text, sub)

/* ------------------------------------------------------------------ */
/* .xyz / .txt                                                        */
/* ------------------------------------------------------------------ */

/* Expected values: what glibc's correctly rounded strtod makes of them. */
static void parse_expected(const char *const *lits, size_t n, double *out)
{
    for (size_t i = 0; i < n; i++)
        out[i] = strtod(lits[i], NULL);
}

static void test_xyz_good(tctx *t)
{
    static const char *const lits[] = {
        "0", "-0", "+1.5",
        ".5", "5.", "1E+5",
        "1e-3", "-2.5E-0", "123456789012345678901234567890",
        "0.1", "0.2", "0.30000000000000004",
        "1.7976931348623157e308", "2.2250738585072014e-308", "-4.9e-300",
        "9007199254740993", "0.000000000000000000000000000001",
        "1e22", "1e23", "123456.789e-22", "8.5e-23", "3.14159265358979323846264338327950288419716939937510582097494459230781640628620899862803482534211706798214808651328230664709384460955058223172535940812848111745028410270193852110555964462294895493038196",
        "0e999", "-0.0e-999", "000000000000000000000000000012.5",
        "-1e-22", "4.35e+15",
        /* the 128-bit path: exact ties (to even: 2^52, 2^52 + 2, 2^53 + 4),
         * %.17g round trips, 19 digits at the ends of |e10| <= 19 */
        "4503599627370496.5", "4503599627370497.5", "9007199254740995",
        "0.70292183315885048", "637795.56999999995", "-0.071045216069212325",
        "9999999999999999999e19", "1.000000000000000001e-1", "9999999999999999999e-19",
        /* just above a tie, by less than the quotient's dropped bits can
         * show: only the division's remainder rounds them up */
        "4905581301898155611e-19", "6418770770843949536e-19", "-8622674343440708822e-19"};
    const size_t n = sizeof lits / sizeof lits[0];
    _Static_assert(sizeof lits / sizeof lits[0] % 3 == 0, "3 per point");
    double want[sizeof lits / sizeof lits[0]];
    parse_expected(lits, n, want);

    /* comments, blank lines, tabs, commas, CRLF, a BOM, no final newline */
    bbuf b = {0};
    bb_printf(&b, "\xef\xbb\xbf# header comment\r\n\r\n");
    for (size_t i = 0; i < n; i += 3) {
        switch ((i / 3) % 4) {
        case 0:
            bb_printf(&b, "%s %s %s\n", lits[i], lits[i + 1], lits[i + 2]);
            break;
        case 1:
            bb_printf(&b, "  %s,%s ,\t%s # trailing\r\n", lits[i],
                      lits[i + 1], lits[i + 2]);
            break;
        case 2:
            bb_printf(&b, "\t%s\t%s\t%s#no space before the comment\n"
                      "   \t  \n#\n",
                      lits[i], lits[i + 1], lits[i + 2]);
            break;
        default:
            bb_printf(&b, "%s, %s, %s", lits[i], lits[i + 1], lits[i + 2]);
            if (i + 3 < n)
                bb_printf(&b, "\r\n");
            break;
        }
    }
    char path[1024];
    write_file(t, "good.xyz", b.p, b.n, path, sizeof path);
    EXPECT_OK(t, path, want, n / 3);
    /* the extension is case-insensitive; .txt is the same format */
    write_file(t, "good.XyZ", b.p, b.n, path, sizeof path);
    EXPECT_OK(t, path, want, n / 3);
    write_file(t, "good.TXT", b.p, b.n, path, sizeof path);
    EXPECT_OK(t, path, want, n / 3);
    /* the file name may contain dots */
    write_file(t, "my.points.v2.txt", b.p, b.n, path, sizeof path);
    EXPECT_OK(t, path, want, n / 3);
    bb_free(&b);

    /* fewer than 4 points is the library's business, not the reader's */
    write_file(t, "one.xyz", "1 2 3", 5, path, sizeof path);
    double one[3] = {1, 2, 3};
    EXPECT_OK(t, path, one, 1);
}

/* A random decimal literal inside the range of normal doubles. */
static void random_literal(tctx *t, char *out, size_t cap)
{
    for (;;) {
        size_t o = 0;
        int shape = (int)rnd_below(t, 5);
        if (rnd_below(t, 2))
            out[o++] = rnd_below(t, 2) ? '-' : '+';
        if (shape == 0) {
            /* round trip of a random double */
            double v;
            do {
                uint64_t bits = rnd(t);
                memcpy(&v, &bits, sizeof v);
            } while (!isfinite(v) || fabs(v) < DBL_MIN);
            snprintf(out + o, cap - o, "%.*g", 1 + (int)rnd_below(t, 17),
                     fabs(v));
        } else if (shape == 4) {
            /* the 128-bit path of src/io/read/reader.c (rd_exact_small): 16..19
             * significant digits, a decimal point anywhere, |e10| <= 19
             * and a little beyond, digits often ending in 5 (near ties) */
            int nd = 16 + (int)rnd_below(t, 4), point = (int)rnd_below(t, (uint64_t)nd + 1);
            for (int i = 0; i < nd; i++) {
                if (i == point)
                    out[o++] = '.';
                int dig = (int)rnd_below(t, 10);
                if (i == 0 && dig == 0)
                    dig = 1;
                if (i == nd - 1 && rnd_below(t, 2))
                    dig = 5;
                out[o++] = (char)('0' + dig);
            }
            if (rnd_below(t, 2))
                o += (size_t)snprintf(out + o, cap - o, "e%d", (int)rnd_below(t, 43) - 21);
            out[o] = '\0';
        } else {
            /* random digits around the fast path's limits (15..19 digits,
             * powers of ten up to 22) and beyond */
            int nint = (int)rnd_below(t, shape == 1 ? 8 : 24);
            int nfrac = (int)rnd_below(t, shape == 1 ? 12 : 24);
            if (nint + nfrac == 0)
                nint = 1;
            for (int i = 0; i < nint; i++)
                out[o++] = (char)('0' + rnd_below(t, 10));
            if (nfrac > 0 || rnd_below(t, 4) == 0) {
                out[o++] = '.';
                for (int i = 0; i < nfrac; i++)
                    out[o++] = (char)('0' + rnd_below(t, 10));
            }
            if (shape == 3 || rnd_below(t, 3) == 0) {
                int e = (int)rnd_below(t, shape == 3 ? 640 : 60) -
                        (shape == 3 ? 320 : 30);
                o += (size_t)snprintf(out + o, cap - o, "%c%d",
                                      rnd_below(t, 2) ? 'e' : 'E', e);
            }
            out[o] = '\0';
        }
        double v = strtod(out, NULL);
        if (isfinite(v) && (v == 0 || fabs(v) >= DBL_MIN)) {
            /* a zero must come from an all-zero literal to be valid */
            if (v != 0)
                return;
            int nonzero = 0;
            for (const char *p = out; *p && *p != 'e' && *p != 'E'; p++)
                if (*p >= '1' && *p <= '9')
                    nonzero = 1;
            if (!nonzero)
                return;
        }
    }
}

/* Many random literals against strtod, bit for bit; written and checked
 * in the C locale, read in read_locale (NULL: the current one). */
static void test_xyz_random(tctx *t, const char *tag, size_t npts,
                            const char *read_locale)
{
    bbuf b = {0};
    double *want = malloc(3 * npts * sizeof *want);
    if (want == NULL)
        exit(1);
    char lit[128];
    for (size_t i = 0; i < 3 * npts; i++) {
        random_literal(t, lit, sizeof lit);
        want[i] = strtod(lit, NULL);
        bb_printf(&b, "%s%s", lit, i % 3 == 2 ? "\n" : (i & 1 ? ", " : " "));
    }
    char path[1024], name[64];
    snprintf(name, sizeof name, "random_%s.xyz", tag);
    write_file(t, name, b.p, b.n, path, sizeof path);
    if (read_locale != NULL)
        setlocale(LC_NUMERIC, read_locale);
    EXPECT_OK(t, path, want, npts);
    if (read_locale != NULL)
        setlocale(LC_NUMERIC, "C");
    bb_free(&b);
    free(want);
}

/* A text of several megabytes read in slices at the default slice size
 * (src/io/read/reader.c, rd_read_xyz): the same points for every thread count,
 * and for errors anywhere (first line, slice ends, last line, two at
 * once) the one-thread message with the file's own line number. */
static void test_xyz_sliced(tctx *t)
{
    enum { NPTS = 60000 };
    bbuf b = {0};
    size_t *line_at = malloc((NPTS + 1) * sizeof *line_at);
    double *want = malloc(3 * (size_t)NPTS * sizeof *want);
    if (want == NULL || line_at == NULL)
        exit(1);
    char lit[128];
    for (size_t i = 0; i < NPTS; i++) {
        line_at[i] = b.n;
        if (i % 1000 == 7) /* comments and blank lines shift line numbers */
            bb_printf(&b, "# comment %zu\n\r\n", i);
        for (int k = 0; k < 3; k++) {
            random_literal(t, lit, sizeof lit);
            want[3 * i + (size_t)k] = strtod(lit, NULL);
            bb_printf(&b, "%s%s", lit, k == 2 ? (i & 1 ? "\r\n" : "\n") : " ");
        }
    }
    line_at[NPTS] = b.n;
    char path[1024];
    write_file(t, "sliced.xyz", b.p, b.n, path, sizeof path);
    for (int T = 1; T <= 8; T *= 2) {
        double *xyz = NULL;
        size_t n = 0;
        char err[512];
        int rc = fdt_rd_points_threads(path, T, 0, &xyz, &n, err, sizeof err);
        test_count_checks(1);
        if (rc != FDT_IO_OK || n != NPTS || memcmp(xyz, want, sizeof(double) * 3 * NPTS) != 0)
            fail_at(t, __LINE__, "%s: %d threads: %s, %zu points", path, T, code_name(rc), n);
        free(xyz);
    }
    /* Line numbers: point i's line is i + 1 plus two for each comment
     * block before it (including its own). */
    static const size_t bad_at[] = {0, NPTS / 4, NPTS / 2 - 1, NPTS / 2, NPTS / 2 + 1, NPTS - 1};
    for (size_t k = 0; k <= sizeof bad_at / sizeof *bad_at; k++) {
        size_t i = k < sizeof bad_at / sizeof *bad_at ? bad_at[k] : NPTS - 2;
        char *text = malloc(b.n);
        if (text == NULL)
            exit(1);
        memcpy(text, b.p, b.n);
        /* the first byte of the point's numbers becomes a letter (after
         * the comment block if the point has one) */
        size_t at = line_at[i];
        if (i % 1000 == 7)
            at = (size_t)((char *)memchr(text + at, '\r', b.n - at) - text) + 2;
        text[at] = 'q';
        size_t lineno = i + 1 + 2 * ((i + 993) / 1000);
        if (k == sizeof bad_at / sizeof *bad_at) { /* a second error later on */
            text[line_at[NPTS - 1]] = 'q';
        }
        char name[64], sub[64];
        snprintf(name, sizeof name, "sliced_bad%zu.xyz", k);
        write_file(t, name, text, b.n, path, sizeof path);
        snprintf(sub, sizeof sub, ":%zu: ", lineno);
        EXPECT_ERR(t, path, FDT_IO_EFORMAT, sub);
        free(text);
    }
    bb_free(&b);
    free(want);
    free(line_at);
}

static void test_xyz_bad(tctx *t)
{
    char path[1024];
    write_file(t, "empty.xyz", "", 0, path, sizeof path);
    EXPECT_ERR(t, path, FDT_IO_EFORMAT, "empty.xyz: no points");
    TEXT_ERR(t, "comments.xyz", "# only\n\n  # comments\r\n", ": no points");
    TEXT_ERR(t, "blank.xyz", "\n\n \t \r\n", ": no points");

    static const struct {
        const char *line; /* placed on line 3 */
        const char *msg;
    } cases[] = {
        {"1 2", ":3: expected 3 numbers, found 2"},
        {"1", ":3: expected 3 numbers, found 1"},
        {"1 2 3 4", ":3: expected 3 numbers, found 4"},
        {"1 2 3 # 4", NULL}, /* valid: the comment hides the 4 */
        {"1 2 x", ":3: not a number: 'x'"},
        {"1 2 3x", ":3: not a number: '3x'"},
        {"1 abc 3", ":3: not a number: 'abc'"},
        {"nan 2 3", ":3: not a finite number: 'nan'"},
        {"1 NAN 3", ":3: not a finite number: 'NAN'"},
        {"1 2 -nan", ":3: not a finite number: '-nan'"},
        {"nan(0x7) 2 3", ":3: not a finite number: 'nan(0x7)'"},
        {"inf 2 3", ":3: not a finite number: 'inf'"},
        {"1 +Inf 3", ":3: not a finite number: '+Inf'"},
        {"1 2 -INFINITY", ":3: not a finite number: '-INFINITY'"},
        {"1 2 infinit", ":3: not a number: 'infinit'"},
        {"1e999 2 3", ":3: '1e999' overflows a double"},
        {"1 -1e999 3", ":3: '-1e999' overflows a double"},
        {"1 2 1.8e308", ":3: '1.8e308' overflows a double"},
        {"1e-400 2 3", ":3: '1e-400' underflows a double"},
        {"1 -2e-310 3", ":3: '-2e-310' underflows a double"},
        {"1 2 0.00000000000000000000000000000000000000000000000000000000000"
         "00000000000000000000000000000000000000000000000000000000000000000"
         "00000000000000000000000000000000000000000000000000000000000000000"
         "00000000000000000000000000000000000000000000000000000000000000000"
         "00000000000000000000000000000000000000000000000000000000000000000"
         "000001",
         ":3: '0.0000000000000000000000...' underflows a double"},
        {"1e 2 3", ":3: not a number: '1e'"},
        {"1e+ 2 3", ":3: not a number: '1e+'"},
        {". 2 3", ":3: not a number: '.'"},
        {"+ 2 3", ":3: not a number: '+'"},
        {"1 - 3", ":3: not a number: '-'"},
        {"1..2 2 3", ":3: not a number: '1..2'"},
        {"1.2.3 2 3", ":3: not a number: '1.2.3'"},
        {"--1 2 3", ":3: not a number: '--1'"},
        {"1e5.5 2 3", ":3: not a number: '1e5.5'"},
        {"0x10 2 3", ":3: not a number: '0x10'"},
        {"0x1p3 2 3", ":3: not a number: '0x1p3'"},
        {"1_000 2 3", ":3: not a number: '1_000'"},
        {"1 2 \xd9\xa1", ":3: not a number: '\\xd9\\xa1'"},
        {"1,,2,3", ":3: empty field (stray comma)"},
        {",1,2,3", ":3: empty field (stray comma)"},
        {"1,2,3,", ":3: empty field (stray comma)"},
        {"1, ,2,3", ":3: empty field (stray comma)"},
        {",", ":3: empty field (stray comma)"},
        {"1;2;3", ":3: fields separated by ';' in '1;2;3': read the file with --delimiter ';'"},
        {"1 2 3\r4", ":3: expected 3 numbers, found 4"},
        {"1 2 33333333333333333333333333333333333333333333333333x",
         ":3: not a number: '333333333333333333333333...'"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char text[1024], name[64], path2[1024];
        snprintf(text, sizeof text, "0 0 0\n# two\n%s\n1 1 1\n",
                 cases[i].line);
        snprintf(name, sizeof name, "bad%zu.xyz", i);
        if (cases[i].msg == NULL) {
            write_file(t, name, text, strlen(text), path2, sizeof path2);
            EXPECT_OK(t, path2, NULL, 3);
        } else {
            text_err(t, __LINE__, name, text, cases[i].msg);
        }
    }
    /* a NUL byte inside a number */
    static const char nul[] = "0 0 0\n1 2 3\n4 5\0006\n";
    write_file(t, "nul.xyz", nul, sizeof nul - 1, path, sizeof path);
    EXPECT_ERR(t, path, FDT_IO_EFORMAT, "nul.xyz:3: not a number: '5\\x006'");
    /* an error on the last line without a newline */
    TEXT_ERR(t, "last.xyz", "0 0 0\n1 1 1\n2 2", ":3: expected 3 numbers");
    /* line numbers keep counting through comments and CRLF */
    TEXT_ERR(t, "crlf.txt", "# a\r\n\r\n1 2 3\r\n4 5 6\r\n# b\r\n7 8\r\n",
             ":6: expected 3 numbers, found 2");
}

/* ------------------------------------------------------------------ */
/* .node                                                              */
/* ------------------------------------------------------------------ */

static void test_node(tctx *t)
{
    char path[1024];
    static const double four[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1.25};
    static const char n0[] =
        "# TetGen node file, 0-based\n"
        "4 3 0 0 # points dim attributes markers\n"
        "\n"
        "0 0 0 0\n"
        "1 1.0 0 0\r\n"
        "# a comment between points\n"
        "2 0 1e0 0\n"
        "3   0,0,1.25  # trailing\n";
    write_file(t, "zero.node", n0, sizeof n0 - 1, path, sizeof path);
    EXPECT_OK(t, path, four, 4);
    static const char n1[] =
        "4 3 2 1\n"
        "1 0 0 0 0.5 -7 1\n"
        "2 1 0 0 nan 1e999 0\n" /* ignored attributes need only be numbers */
        "3 0 1 0 0 0 -1\n"
        "4 0 0 1.25 0 0 0\n";
    write_file(t, "one.NODE", n1, sizeof n1 - 1, path, sizeof path);
    EXPECT_OK(t, path, four, 4);
    /* TetGen's defaults for missing header fields: dim 3, no attributes,
     * no markers */
    static const char n2[] = "4\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1.25\n";
    write_file(t, "short.node", n2, sizeof n2 - 1, path, sizeof path);
    EXPECT_OK(t, path, four, 4);

    TEXT_ERR(t, "empty.node", "# nothing\n", ": no points");
    TEXT_ERR(t, "zero.node", "0 3 0 0\n", ": no points");
    TEXT_ERR(t, "dim2.node", "#\n4 2 0 0\n0 0 0\n",
             ":2: dimension is 2, only 3 is supported");
    TEXT_ERR(t, "marker2.node", "4 3 0 2\n", ":1: boundary marker flag is 2");
    TEXT_ERR(t, "hdr5.node", "4 3 0 0 9\n", ":1: header has more than 4");
    TEXT_ERR(t, "hdrneg.node", "-4 3 0 0\n",
             ":1: header field '-4' is not a non-negative integer");
    TEXT_ERR(t, "hdrfloat.node", "4.0 3 0 0\n",
             ":1: header field '4.0' is not a non-negative integer");
    TEXT_ERR(t, "hdrbig.node", "18446744073709551616 3 0 0\n0 0 0 0\n",
             ":1: header field '18446744073709551616' is too large");
    /* counts the file cannot hold: refused before allocating */
    TEXT_ERR(t, "huge.node",
             "4000000000 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n",
             ":1: header declares 4000000000 points but the 32 bytes after it "
             "can hold at most 4: refused");
    TEXT_ERR(t, "hugeattr.node", "1 3 4000000000 0\n0 0 0 0\n",
             ":1: header declares 1 points but the 8 bytes after it can hold "
             "at most 0: refused");
    /* header count disagreeing with the data, both ways */
    TEXT_ERR(t, "high.node",
             "5 3 0 0\n0 0.0 0.0 0.0\n1 1.0 0.0 0.0\n2 0.0 1.0 0.0\n"
             "3 0.0 0.0 1.0\n# end\n",
             ":6: file ends after 4 of the 5 points declared on line 1");
    TEXT_ERR(t, "low.node",
             "3 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n# comment\n\n3 0 0 1\n",
             ":7: extra data after the 3 points declared on line 1");
    TEXT_ERR(t, "first.node", "2 3 0 0\n2 0 0 0\n3 1 0 0\n",
             ":2: first point index is 2, expected 0 or 1");
    TEXT_ERR(t, "gap.node", "3 3 0 0\n1 0 0 0\n2 1 0 0\n4 0 1 0\n",
             ":4: point index 4, expected 3");
    TEXT_ERR(t, "repeat.node", "3 3 0 0\n0 0 0 0\n0 1 0 0\n2 0 1 0\n",
             ":3: point index 0, expected 1");
    TEXT_ERR(t, "idx.node", "2 3 0 0\n0 0 0 0\n1.0 1 0 0\n",
             ":3: point index '1.0' is not an integer");
    TEXT_ERR(t, "fields.node", "2 3 1 1\n0 0 0 0 0.5 1\n1 1 0 0 0.5\n",
             ":3: expected 6 fields (index, x, y, z, 1 attributes, 1 markers), "
             "found 5");
    TEXT_ERR(t, "fields2.node", "2 3 0 0\n0 0 0 0\n1 1 0 0 7\n",
             ":3: expected 4 fields");
    TEXT_ERR(t, "attr.node", "2 3 1 0\n0 0 0 0 x\n1 1 0 0 0\n",
             ":2: attribute: not a number: 'x'");
    TEXT_ERR(t, "mark.node", "2 3 0 1\n0 0 0 0 b\n1 1 0 0 0\n",
             ":2: boundary marker 'b' is not an integer");
    TEXT_ERR(t, "nan.node", "2 3 0 0\n0 0 0 0\n1 1 NaN 0\n",
             ":3: not a finite number: 'NaN'");
    TEXT_ERR(t, "over.node", "2 3 0 0\n0 0 0 0\n1 1 0 -1e400\n",
             ":3: '-1e400' overflows a double");
    TEXT_ERR(t, "under.node", "2 3 0 0\n0 0 0 0\n1 1 0 1e-320\n",
             ":3: '1e-320' underflows a double");
}

/* ------------------------------------------------------------------ */
/* PLY                                                                */
/* ------------------------------------------------------------------ */

enum { F_ASCII, F_LE, F_BE };

typedef struct tprop {
    const char *type;  /* scalar type, or a list's item type */
    const char *ctype; /* a list's length type, NULL for a scalar */
    const char *name;
} tprop;

typedef struct telem {
    const char *name;
    size_t count;
    const tprop *props;
    size_t nprops;
} telem;

/* strcmp, written out: GCC 12 folds strcmp against the inlined literals
 * into a bogus -Wstring-compare warning. */
static int streq(const char *a, const char *b)
{
    while (*a != '\0' && *a == *b) {
        a++;
        b++;
    }
    return *a == *b;
}

static int type_size(const char *ty)
{
    static const struct {
        const char *n;
        int s;
    } tab[] = {{"char", 1},   {"uchar", 1},   {"int8", 1},    {"uint8", 1},
               {"short", 2},  {"ushort", 2},  {"int16", 2},   {"uint16", 2},
               {"int", 4},    {"uint", 4},    {"int32", 4},   {"uint32", 4},
               {"float", 4},  {"float32", 4}, {"double", 8},  {"float64", 8}};
    for (size_t i = 0; i < sizeof tab / sizeof tab[0]; i++)
        if (streq(tab[i].n, ty))
            return tab[i].s;
    return 0;
}

static int type_is_float(const char *ty)
{
    return strncmp(ty, "float", 5) == 0 || strcmp(ty, "double") == 0;
}

static int type_is_signed(const char *ty)
{
    return ty[0] != 'u';
}

/* Stores v as type ty in the byte order of fmt. */
static void put_scalar(bbuf *b, const char *ty, double v, int fmt)
{
    unsigned char raw[8];
    int sz = type_size(ty);
    uint64_t u;
    if (type_is_float(ty) && sz == 4) {
        float f = (float)v;
        uint32_t w;
        memcpy(&w, &f, 4);
        u = w;
    } else if (type_is_float(ty)) {
        memcpy(&u, &v, 8);
    } else {
        u = (uint64_t)(int64_t)v;
    }
    for (int i = 0; i < sz; i++) {
        int shift = fmt == F_BE ? 8 * (sz - 1 - i) : 8 * i;
        raw[i] = (unsigned char)(u >> shift);
    }
    bb_put(b, raw, (size_t)sz);
}

/* A value that type ty holds exactly, for the filler properties. */
static double filler(tctx *t, const char *ty)
{
    int sz = type_size(ty);
    if (type_is_float(ty))
        return (double)(float)((double)(int64_t)rnd_below(t, 2000001) / 64.0 -
                               15625.0);
    uint64_t span = sz == 4 ? 100000 : (sz == 2 ? 60000 : 250);
    int64_t v = (int64_t)rnd_below(t, span);
    if (type_is_signed(ty))
        v -= (int64_t)span / 2;
    return (double)v;
}

static void put_value(bbuf *b, const char *ty, double v, int fmt)
{
    if (fmt != F_ASCII)
        put_scalar(b, ty, v, fmt);
    else if (type_is_float(ty))
        bb_printf(b, "%.17g", v);
    else
        bb_printf(b, "%lld", (long long)v);
}

/*
 * Writes a PLY file of the given elements. The coordinates of the vertex
 * element come from xyz (values its types hold exactly); every other value
 * is random. coord_off (when not NULL) receives the byte offset of every
 * coordinate, item_off the offset where each vertex begins, and data_off
 * the offset of the first data byte.
 */
static void build_ply(tctx *t, bbuf *b, int fmt, const telem *els,
                      size_t nels, const double *xyz, size_t *coord_off,
                      size_t *item_off, size_t *data_off, int crlf)
{
    const char *nl = crlf ? "\r\n" : "\n";
    static const char *const fmts[] = {"ascii", "binary_little_endian",
                                       "binary_big_endian"};
    bb_printf(b, "ply%sformat %s 1.0%scomment written by test_reader.c%s",
              nl, fmts[fmt], nl, nl);
    bb_printf(b, "obj_info nothing to see%s", nl);
    for (size_t e = 0; e < nels; e++) {
        bb_printf(b, "element %s %zu%s", els[e].name, els[e].count, nl);
        for (size_t p = 0; p < els[e].nprops; p++) {
            const tprop *pr = &els[e].props[p];
            if (pr->ctype != NULL)
                bb_printf(b, "property list %s %s %s%s", pr->ctype, pr->type,
                          pr->name, nl);
            else
                bb_printf(b, "property %s %s%s", pr->type, pr->name, nl);
        }
    }
    bb_printf(b, "end_header%s", nl);
    if (data_off != NULL)
        *data_off = b->n;
    for (size_t e = 0; e < nels; e++) {
        int is_vertex = strcmp(els[e].name, "vertex") == 0;
        for (size_t i = 0; i < els[e].count; i++) {
            if (is_vertex && item_off != NULL)
                item_off[i] = b->n;
            for (size_t p = 0; p < els[e].nprops; p++) {
                const tprop *pr = &els[e].props[p];
                if (fmt == F_ASCII && p > 0)
                    bb_printf(b, " ");
                if (pr->ctype != NULL) {
                    size_t len = (size_t)rnd_below(t, 5);
                    put_value(b, pr->ctype, (double)len, fmt);
                    for (size_t j = 0; j < len; j++) {
                        if (fmt == F_ASCII)
                            bb_printf(b, " ");
                        put_value(b, pr->type, filler(t, pr->type), fmt);
                    }
                    continue;
                }
                int role = -1;
                if (is_vertex && pr->name[1] == '\0' && pr->name[0] >= 'x' &&
                    pr->name[0] <= 'z')
                    role = pr->name[0] - 'x';
                if (role >= 0) {
                    if (coord_off != NULL)
                        coord_off[3 * i + (size_t)role] = b->n;
                    put_value(b, pr->type, xyz[3 * i + (size_t)role], fmt);
                } else {
                    put_value(b, pr->type, filler(t, pr->type), fmt);
                }
            }
            if (fmt == F_ASCII)
                bb_printf(b, "%s", nl);
        }
    }
}

/* Random coordinates that type ty holds exactly (incl. -0, extremes). */
static void random_coords(tctx *t, const char *ty, double *xyz, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        double v;
        if (!type_is_float(ty)) {
            v = filler(t, ty);
        } else {
            int k = (int)rnd_below(t, 20);
            if (k == 0)
                v = -0.0;
            else if (k == 1)
                v = type_size(ty) == 4 ? FLT_MAX : DBL_MAX;
            else if (k == 2)
                v = type_size(ty) == 4 ? -FLT_MIN : -DBL_MIN;
            else
                v = ldexp((double)(int64_t)(rnd(t) >> 11) /
                              9007199254740992.0,
                          (int)rnd_below(t, 120) - 60) *
                    (rnd_below(t, 2) ? 1 : -1);
            if (type_size(ty) == 4)
                v = (double)(float)v;
        }
        xyz[i] = v;
    }
}

static void test_ply_good(tctx *t)
{
    static const char *const coord_types[] = {
        "float", "double", "float32", "float64", "int", "short", "uchar",
        "char", "uint", "int16", "uint16", "int32", "int8", "uint32"};
    char path[1024], name[128];
    for (int fmt = F_ASCII; fmt <= F_BE; fmt++) {
        for (size_t ti = 0; ti < sizeof coord_types / sizeof *coord_types;
             ti++) {
            const char *ty = coord_types[ti];
            for (int variant = 0; variant < 3; variant++) {
                /* variant 0: vertex only, x y z in order
                 * variant 1: elements before and after, extra properties,
                 *            coordinates out of order
                 * variant 2: a list inside the vertex element, CRLF header */
                tprop vprops[8];
                size_t nv = 0;
                if (variant == 0) {
                    vprops[nv++] = (tprop){ty, NULL, "x"};
                    vprops[nv++] = (tprop){ty, NULL, "y"};
                    vprops[nv++] = (tprop){ty, NULL, "z"};
                } else if (variant == 1) {
                    vprops[nv++] = (tprop){"uchar", NULL, "red"};
                    vprops[nv++] = (tprop){ty, NULL, "z"};
                    vprops[nv++] = (tprop){"double", NULL, "nx"};
                    vprops[nv++] = (tprop){ty, NULL, "x"};
                    vprops[nv++] = (tprop){"short", NULL, "s"};
                    vprops[nv++] = (tprop){ty, NULL, "y"};
                    vprops[nv++] = (tprop){"float", NULL, "xx"};
                } else {
                    vprops[nv++] = (tprop){ty, NULL, "x"};
                    vprops[nv++] = (tprop){"int", "uchar", "tags"};
                    vprops[nv++] = (tprop){ty, NULL, "y"};
                    vprops[nv++] = (tprop){"float", "ushort", "w"};
                    vprops[nv++] = (tprop){ty, NULL, "z"};
                }
                static const tprop cam[] = {{"float", NULL, "fx"},
                                            {"short", "uint", "k"},
                                            {"double", NULL, "fy"}};
                static const tprop face[] = {
                    {"int", "uchar", "vertex_indices"}, {"uchar", NULL, "f"}};
                size_t n = 1 + (size_t)rnd_below(t, 40);
                telem els[3];
                size_t ne = 0;
                if (variant == 1)
                    els[ne++] = (telem){"camera", 3, cam, 3};
                els[ne++] = (telem){"vertex", n, vprops, nv};
                if (variant == 1)
                    els[ne++] = (telem){"face", 5, face, 2};
                double *xyz = malloc(3 * n * sizeof *xyz);
                if (xyz == NULL)
                    exit(1);
                random_coords(t, ty, xyz, 3 * n);
                bbuf b = {0};
                build_ply(t, &b, fmt, els, ne, xyz, NULL, NULL, NULL,
                          variant == 2);
                snprintf(name, sizeof name, "good_%d_%s_%d.ply", fmt, ty,
                         variant);
                write_file(t, name, b.p, b.n, path, sizeof path);
                EXPECT_OK(t, path, xyz, n);
                bb_free(&b);
                free(xyz);
            }
        }
    }
}

/* Binary and ASCII files with NaN/Inf coordinates, errors at the offset. */
static void test_ply_nonfinite(tctx *t)
{
    static const tprop vf[] = {{"float", NULL, "x"},
                               {"uchar", NULL, "c"},
                               {"float", NULL, "y"},
                               {"float", NULL, "z"}};
    static const tprop vd[] = {{"double", NULL, "x"},
                               {"double", NULL, "y"},
                               {"int", "uchar", "l"},
                               {"double", NULL, "z"}};
    char path[1024], name[64], msg[256];
    for (int fmt = F_LE; fmt <= F_BE; fmt++) {
        for (int dbl = 0; dbl < 2; dbl++) {
            for (int k = 0; k < 6; k++) {
                const size_t n = 7;
                double xyz[21];
                random_coords(t, dbl ? "double" : "float", xyz, 21);
                size_t bad = 3 * (size_t)(k + 1) + (size_t)(k % 3);
                xyz[bad] = k < 3 ? NAN : (k & 1 ? -INFINITY : INFINITY);
                telem el = {"vertex", n, dbl ? vd : vf, 4};
                size_t off[21];
                bbuf b = {0};
                build_ply(t, &b, fmt, &el, 1, xyz, off, NULL, NULL, 0);
                snprintf(name, sizeof name, "nonfinite_%d_%d_%d.ply", fmt,
                         dbl, k);
                write_file(t, name, b.p, b.n, path, sizeof path);
                snprintf(msg, sizeof msg, "%s: byte %zu: vertex %zu of %zu: "
                         "%c is %s",
                         name, off[bad], bad / 3 + 1, n, (int)('x' + bad % 3),
                         k < 3 ? "NaN" : "infinite");
                EXPECT_ERR(t, path, FDT_IO_EFORMAT, msg);
                bb_free(&b);
            }
        }
    }
    /* ignored properties may be NaN: only x, y, z are checked */
    double xyz[3] = {1, 2, 3};
    bbuf b = {0};
    bb_printf(&b, "ply\nformat binary_little_endian 1.0\nelement vertex 1\n"
                  "property float x\nproperty float y\nproperty float z\n"
                  "property float nx\nend_header\n");
    for (int i = 0; i < 3; i++)
        put_scalar(&b, "float", xyz[i], F_LE);
    put_scalar(&b, "float", NAN, F_LE);
    write_file(t, "ignored_nan.ply", b.p, b.n, path, sizeof path);
    EXPECT_OK(t, path, xyz, 1);
    bb_free(&b);
    static const char asc[] =
        "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
        "property float y\nproperty float z\nproperty float nx\nend_header\n"
        "1 2 3 nan\n1 2 3 -inf\n";
    double two[6] = {1, 2, 3, 1, 2, 3};
    write_file(t, "ignored_nan_ascii.ply", asc, sizeof asc - 1, path,
               sizeof path);
    EXPECT_OK(t, path, two, 2);
}

/*
 * Cuts a binary file (elements before and after the vertex element) at
 * every length: each prefix must fail, inside the data with the exact
 * byte offset and the element where the data ends.
 */
static void test_ply_truncation(tctx *t)
{
    static const tprop cam[] = {{"float", NULL, "f"},
                                {"short", "uchar", "k"}};
    static const tprop vp[] = {{"double", NULL, "x"},
                               {"float", NULL, "y"},
                               {"uchar", NULL, "q"},
                               {"double", NULL, "z"}};
    static const tprop face[] = {{"int", "uchar", "vertex_indices"}};
    const size_t n = 6, stride = 8 + 4 + 1 + 8;
    telem els[3] = {{"camera", 2, cam, 2}, {"vertex", n, vp, 4},
                    {"face", 3, face, 1}};
    double xyz[18];
    for (int i = 0; i < 18; i++)
        xyz[i] = (double)(float)(i * 0.75 - 3);
    char path[1024], msg[256];
    for (int fmt = F_LE; fmt <= F_BE; fmt++) {
        bbuf b = {0};
        size_t item_off[6], data_off;
        build_ply(t, &b, fmt, els, 3, xyz, NULL, item_off, &data_off, 0);
        size_t vstart = item_off[0], vend = vstart + n * stride;
        write_file(t, "cut_full.ply", b.p, b.n, path, sizeof path);
        EXPECT_OK(t, path, xyz, n);
        for (size_t len = 0; len < b.n; len++) {
            write_file(t, "cut.ply", b.p, len, path, sizeof path);
            const char *sub = NULL;
            if (len == 0) {
                sub = "cut.ply: no points";
            } else if (len < data_off) {
                sub = "cut.ply:"; /* some header error, with a line */
            } else if (len < vstart) {
                snprintf(msg, sizeof msg,
                         "cut.ply: byte %zu: file ends inside element "
                         "'camera' item ",
                         len);
                sub = msg;
            } else if (len < vend) {
                size_t k = (len - vstart) / stride;
                snprintf(msg, sizeof msg,
                         "cut.ply: byte %zu: file ends %s vertex %zu of %zu",
                         len, (len - vstart) % stride ? "inside" : "before",
                         k + 1, n);
                sub = msg;
            } else {
                snprintf(msg, sizeof msg,
                         "cut.ply: byte %zu: file ends inside element 'face' "
                         "item ",
                         len);
                sub = msg;
            }
            EXPECT_ERR(t, path, FDT_IO_EFORMAT, sub);
        }
        /* data beyond what the header declares */
        bb_put(&b, "\0\0\0", 3);
        write_file(t, "long.ply", b.p, b.n, path, sizeof path);
        snprintf(msg, sizeof msg,
                 "long.ply: byte %zu: 3 bytes of extra data after the last "
                 "element",
                 b.n - 3);
        EXPECT_ERR(t, path, FDT_IO_EFORMAT, msg);
        bb_free(&b);
    }
}

static void test_ply_bad(tctx *t)
{
    char path[1024];
    static const char *const H3 = "property float x\nproperty float y\n"
                                  "property float z\n";
    char text[2048];
#define PLY_ERR(name, body, sub)                                              \
    do {                                                                      \
        TEXT_ERR(t, name, body, sub);                                         \
    } while (0)
    PLY_ERR("e.ply", "\n", ":1: not a PLY file");
    PLY_ERR("e2.ply", "ply2\n", ":1: not a PLY file (the first line is "
                                "'ply2', expected 'ply')");
    PLY_ERR("e3.ply", "ply\n", ":1: the header has no end_header line");
    PLY_ERR("fmt.ply", "ply\nformat ascii 2.0\n", ":2: expected 'format");
    PLY_ERR("fmt2.ply", "ply\nformat ascii\n", ":2: expected 'format");
    PLY_ERR("fmt3.ply", "ply\nformat ascii 1.0\nformat ascii 1.0\n",
            ":3: second format line");
    PLY_ERR("nofmt.ply", "ply\nelement vertex 1\n",
            ":2: element before the format line");
    PLY_ERR("nofmt2.ply", "ply\nend_header\n",
            ": the header has no format line");
    PLY_ERR("prop.ply", "ply\nformat ascii 1.0\nproperty float x\n",
            ":3: property before any element");
    PLY_ERR("kw.ply", "ply\nformat ascii 1.0\nelemnt vertex 3\n",
            ":3: unknown header keyword 'elemnt'");
    PLY_ERR("eh.ply", "ply\nformat ascii 1.0\nend_header now\n",
            ":3: unexpected text after end_header");
    snprintf(text, sizeof text,
             "ply\nformat ascii 1.0\nelement vertex 1\n%s", H3);
    PLY_ERR("noend.ply", text, ":6: the header has no end_header line");
    PLY_ERR("novertex.ply",
            "ply\nformat ascii 1.0\nelement face 1\nproperty uchar a\n"
            "end_header\n1\n",
            ": no points (the header has no 'vertex' element)");
    snprintf(text, sizeof text,
             "ply\nformat ascii 1.0\nelement vertex 0\n%send_header\n", H3);
    PLY_ERR("zero.ply", text, ": no points");
    PLY_ERR("noy.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
            "property float z\nend_header\n1 2\n",
            ":3: the vertex element has no 'y' property");
    PLY_ERR("dupx.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
            "property double x\n",
            ":5: second vertex property 'x'");
    PLY_ERR("dupv.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
            "element vertex 1\n",
            ":5: second 'vertex' element");
    PLY_ERR("noprops.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nelement face 1\n",
            ":3: element 'vertex' has no properties");
    PLY_ERR("noprops2.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
            "property float y\nproperty float z\nelement face 0\nend_header\n",
            ":7: element 'face' has no properties");
    PLY_ERR("type.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty real x\n",
            ":4: unknown property type 'real'");
    PLY_ERR("ltype.ply",
            "ply\nformat ascii 1.0\nelement f 1\nproperty list float int i\n",
            ":4: list length type 'float' is not an integer type");
    PLY_ERR("ltype2.ply",
            "ply\nformat ascii 1.0\nelement f 1\nproperty list uchar foo i\n",
            ":4: unknown property type 'foo'");
    PLY_ERR("pshape.ply",
            "ply\nformat ascii 1.0\nelement f 1\nproperty float\n",
            ":4: expected 'property TYPE NAME'");
    PLY_ERR("eshape.ply", "ply\nformat ascii 1.0\nelement vertex\n",
            ":3: expected 'element NAME COUNT'");
    PLY_ERR("ecount.ply", "ply\nformat ascii 1.0\nelement vertex 1e3\n",
            ":3: element count '1e3' is not a non-negative integer");
    PLY_ERR("ecount2.ply",
            "ply\nformat ascii 1.0\nelement vertex 18446744073709551616\n",
            ":3: element count '18446744073709551616' is too large");

    /* counts that the file cannot hold, refused before allocation */
    snprintf(text, sizeof text,
             "ply\nformat ascii 1.0\nelement vertex 4000000000\n%s"
             "end_header\n0 0 0\n1 1 1\n",
             H3);
    PLY_ERR("huge_ascii.ply", text,
            ":3: the header declares 4000000000 vertices but the 12 bytes "
            "left can hold at most 2: refused");
    bbuf b = {0};
    bb_printf(&b, "ply\nformat binary_little_endian 1.0\n"
                  "element vertex 4000000000\n%send_header\n", H3);
    size_t hdr = b.n;
    for (int i = 0; i < 9; i++)
        put_scalar(&b, "float", i, F_LE);
    write_file(t, "huge_bin.ply", b.p, b.n, path, sizeof path);
    char msg[256];
    snprintf(msg, sizeof msg,
             "huge_bin.ply: byte %zu: file ends before vertex 4 of 4000000000 "
             "(the header declares 4000000000 vertices of 12 bytes, 36 bytes "
             "follow it)",
             hdr + 36);
    EXPECT_ERR(t, path, FDT_IO_EFORMAT, msg);
    bb_free(&b);
    /* lists in the vertex element: the minimum size is checked first */
    bb_printf(&b, "ply\nformat binary_big_endian 1.0\n"
                  "element vertex 1000000\n%sproperty list uint int l\n"
                  "end_header\n", H3);
    hdr = b.n;
    for (int i = 0; i < 30; i++)
        put_scalar(&b, "uchar", 0, F_BE);
    write_file(t, "huge_list.ply", b.p, b.n, path, sizeof path);
    snprintf(msg, sizeof msg,
             "huge_list.ply: byte %zu: the header declares 1000000 vertices "
             "of at least 16 bytes, only 30 bytes follow: refused",
             hdr);
    EXPECT_ERR(t, path, FDT_IO_EFORMAT, msg);
    bb_free(&b);
    /* a huge list length in an element before the vertices */
    bb_printf(&b, "ply\nformat binary_little_endian 1.0\nelement f 1\n"
                  "property list uint double v\nelement vertex 1\n%s"
                  "end_header\n", H3);
    hdr = b.n;
    put_scalar(&b, "uint", 4000000000.0, F_LE);
    for (int i = 0; i < 3; i++)
        put_scalar(&b, "float", i, F_LE);
    write_file(t, "huge_len.ply", b.p, b.n, path, sizeof path);
    snprintf(msg, sizeof msg,
             "huge_len.ply: byte %zu: file ends inside element 'f' item 1 of 1",
             b.n);
    EXPECT_ERR(t, path, FDT_IO_EFORMAT, msg);
    bb_free(&b);
    /* and a huge count of an element before the vertices */
    bb_printf(&b, "ply\nformat binary_little_endian 1.0\n"
                  "element f 18446744073709551615\nproperty uchar a\n"
                  "element vertex 1\n%send_header\n", H3);
    write_file(t, "huge_elem.ply", b.p, b.n, path, sizeof path);
    EXPECT_ERR(t, path, FDT_IO_EFORMAT,
               "huge_elem.ply:3: element count '18446744073709551615' is too "
               "large");
    bb_free(&b);
    bb_printf(&b, "ply\nformat binary_little_endian 1.0\n"
                  "element f 9223372036854775807\nproperty uchar a\n"
                  "element vertex 1\n%send_header\n", H3);
    hdr = b.n;
    bb_put(&b, "abcdefghijklmnop", 16);
    write_file(t, "huge_elem2.ply", b.p, b.n, path, sizeof path);
    snprintf(msg, sizeof msg,
             "huge_elem2.ply: byte %zu: file ends before element 'f' item 17 "
             "of 9223372036854775807",
             hdr + 16);
    EXPECT_ERR(t, path, FDT_IO_EFORMAT, msg);
    bb_free(&b);
    /* a negative list length */
    bb_printf(&b, "ply\nformat binary_big_endian 1.0\nelement vertex 2\n%s"
                  "property list char int l\nend_header\n", H3);
    for (int i = 0; i < 3; i++)
        put_scalar(&b, "float", i, F_BE);
    put_scalar(&b, "char", 1, F_BE);
    put_scalar(&b, "int", 7, F_BE);
    for (int i = 0; i < 3; i++)
        put_scalar(&b, "float", i, F_BE);
    size_t neg_at = b.n;
    put_scalar(&b, "char", -1, F_BE);
    write_file(t, "neglist.ply", b.p, b.n, path, sizeof path);
    snprintf(msg, sizeof msg,
             "neglist.ply: byte %zu: vertex 2 of 2: negative list length",
             neg_at);
    EXPECT_ERR(t, path, FDT_IO_EFORMAT, msg);
    bb_free(&b);

    /* ASCII data errors name the line */
    snprintf(text, sizeof text,
             "ply\nformat ascii 1.0\nelement vertex 3\n%s"
             "property list uchar int l\nend_header\n"
             "0.0 0.0 0.0 0\n1.0 0.0 0.0 2 5 6\n0.0 1.0 0.0 1 7\n",
             H3);
    write_file(t, "ascii_ok.ply", text, strlen(text), path, sizeof path);
    EXPECT_OK(t, path, NULL, 3);
    static const struct {
        const char *line3; /* the data line of vertex 2 (line 10) */
        const char *msg;
    } cases[] = {
        {"1.0 0.0", ":10: vertex 2 of 3: too few values (found 2)"},
        {"1.0 0.0 0.0", ":10: vertex 2 of 3: too few values (found 3)"},
        {"1.0 0.0 0.0 2 5", ":10: vertex 2 of 3: too few values (found 5)"},
        {"1.0 0.0 0.0 1 5 6", ":10: vertex 2 of 3: expected 5 values, found 6"},
        {"1.0 0.0 0.0 -1", ":10: vertex 2 of 3: list length '-1' is not a valid"},
        {"1.0 0.0 0.0 256", ":10: vertex 2 of 3: list length '256' is not a"},
        {"1.0 0.0 0.0 1 5.5", ":10: vertex 2 of 3: '5.5' is not a valid int"},
        {"1.0 zero 0.0 0", ":10: vertex 2 of 3: not a number: 'zero'"},
        {"1.0 0.0 NaN 0", ":10: vertex 2 of 3: not a finite number: 'NaN'"},
        {"1.0 0.0 inf 0", ":10: vertex 2 of 3: not a finite number: 'inf'"},
        {"1e999 0.0 0.0 0", ":10: vertex 2 of 3: '1e999' overflows a double"},
        {"1e-999 0.0 0.0 0", ":10: vertex 2 of 3: '1e-999' underflows a double"},
        {"1.0,0.0,0.0 0", ":10: vertex 2 of 3: not a number: '1.0,0.0,0.0'"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char name[64];
        snprintf(text, sizeof text,
                 "ply\nformat ascii 1.0\nelement vertex 3\n%s"
                 "property list uchar int l\nend_header\n"
                 "0.0 0.0 0.0 0\n%s\n0.0 1.0 0.0 1 7\n",
                 H3, cases[i].line3);
        snprintf(name, sizeof name, "ascii_bad%zu.ply", i);
        text_err(t, __LINE__, name, text, cases[i].msg);
    }
    /* integer coordinates out of the declared type's range */
    PLY_ERR("range.ply",
            "ply\nformat ascii 1.0\nelement vertex 1\nproperty uchar x\n"
            "property uchar y\nproperty uchar z\nend_header\n1 256 3\n",
            ":8: vertex 1 of 1: '256' is not a valid uchar");
    /* header counts and data disagreeing, both ways */
    snprintf(text, sizeof text,
             "ply\nformat ascii 1.0\nelement vertex 4\n%send_header\n"
             "0.0 0.0 0.0\n1.0 0.0 0.0\n\n0.0 1.0 0.0\n",
             H3);
    PLY_ERR("few.ply", text, ":11: file ends before vertex 4 of 4");
    snprintf(text, sizeof text,
             "ply\nformat ascii 1.0\nelement vertex 2\n%send_header\n"
             "0.0 0.0 0.0\n1.0 0.0 0.0\n0.0 1.0 0.0\n",
             H3);
    PLY_ERR("many.ply", text, ":10: extra data after the last element");
    snprintf(text, sizeof text,
             "ply\nformat ascii 1.0\nelement vertex 2\n%s"
             "element face 1\nproperty list uchar int v\nend_header\n"
             "0.0 0.0 0.0\n1.0 0.0 0.0\n0.0 1.0 0.0\n3 0 1 2\n",
             H3);
    PLY_ERR("many2.ply", text,
            ":12: element 'face' item 1 of 1: list length '0.0' is not a "
            "valid count");
    /* trailing blank lines after ASCII data are fine */
    snprintf(text, sizeof text,
             "ply\r\nformat ascii 1.0\r\nelement vertex 1\r\n"
             "property float x\r\nproperty float y\r\nproperty float z\r\n"
             "end_header\r\n1 2 3\r\n\r\n \n");
    write_file(t, "trail.ply", text, strlen(text), path, sizeof path);
    double p123[3] = {1, 2, 3};
    EXPECT_OK(t, path, p123, 1);
#undef PLY_ERR
}

/* ------------------------------------------------------------------ */
/* Robustness: random bytes and mutated files never crash             */
/* ------------------------------------------------------------------ */

static void test_fuzz(tctx *t)
{
    static const char *const exts[] = {"xyz", "node", "ply"};
    char path[1024], name[64];
    unsigned char buf[600];
    for (int i = 0; i < 150; i++) {
        size_t len = 1 + (size_t)rnd_below(t, sizeof buf);
        for (size_t k = 0; k < len; k++)
            buf[k] = (unsigned char)rnd(t);
        if (i % 3 == 2)
            memcpy(buf, "ply\n", len < 4 ? len : 4);
        snprintf(name, sizeof name, "random%d.%s", i, exts[i % 3]);
        write_file(t, name, buf, len, path, sizeof path);
        EXPECT_ERR(t, path, FDT_IO_EFORMAT, name);
    }
    /* mutated valid files: any outcome but a crash; success must give
     * finite points, failure a well-formed message */
    static const tprop vp[] = {{"float", NULL, "x"},
                               {"int", "uchar", "l"},
                               {"double", NULL, "y"},
                               {"float", NULL, "z"}};
    static const tprop fp[] = {{"int", "uchar", "v"}};
    double xyz[30];
    random_coords(t, "float", xyz, 30);
    for (int fmt = F_ASCII; fmt <= F_BE; fmt++) {
        telem els[3] = {{"face", 2, fp, 1}, {"vertex", 10, vp, 4},
                        {"face2", 2, fp, 1}};
        bbuf b = {0};
        build_ply(t, &b, fmt, els, 3, xyz, NULL, NULL, NULL, 0);
        unsigned char *m = malloc(b.n);
        if (m == NULL)
            exit(1);
        for (int it = 0; it < 300; it++) {
            memcpy(m, b.p, b.n);
            int flips = 1 + (int)rnd_below(t, 3);
            for (int f = 0; f < flips; f++) {
                size_t at = (size_t)rnd_below(t, b.n);
                static const char interesting[] = "0123456789 \n-+.eE#,\r\xff";
                m[at] = rnd_below(t, 2)
                            ? (unsigned char)rnd(t)
                            : (unsigned char)interesting[rnd_below(
                                  t, sizeof interesting - 1)];
            }
            snprintf(name, sizeof name, "mut%d.ply", fmt);
            write_file(t, name, m, b.n, path, sizeof path);
            double *pts = NULL;
            size_t n = 0;
            char err[256];
            int rc = fdt_rd_points(path, &pts, &n, err, sizeof err);
            test_count_checks(1);
            if (rc == FDT_IO_OK) {
                int finite = n > 0;
                for (size_t k = 0; k < 3 * n; k++)
                    finite = finite && isfinite(pts[k]);
                EXPECTF(finite, "%s: accepted with bad points", path);
                free(pts);
            } else {
                EXPECTF(rc == FDT_IO_EFORMAT && pts == NULL && n == 0 &&
                             strncmp(err, path, strlen(path)) == 0,
                      "%s: bad failure %s: %s", path, code_name(rc), err);
            }
        }
        free(m);
        bb_free(&b);
    }
}

/* ------------------------------------------------------------------ */
/* Opening, arguments, messages                                       */
/* ------------------------------------------------------------------ */

static void test_open(tctx *t)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/missing.xyz", t->dir);
    EXPECT_ERR(t, path, FDT_IO_EOPEN,
               "missing.xyz: cannot open: No such file or directory");
    snprintf(path, sizeof path, "%s/nodir/x.ply", t->dir);
    EXPECT_ERR(t, path, FDT_IO_EOPEN, "x.ply: cannot open: ");
    snprintf(path, sizeof path, "%s/sub.xyz", t->dir);
    if (mkdir(path, 0700) != 0) {
        fprintf(stderr, "test_reader: cannot mkdir %s\n", path);
        exit(1);
    }
    EXPECT_ERR(t, path, FDT_IO_EOPEN, "sub.xyz: is a directory");
    snprintf(path, sizeof path, "%s/sub.xyz/", t->dir);
    EXPECT_ERR(t, path, FDT_IO_EOPEN, "sub.xyz/: is a directory");
    EXPECT_ERR(t, t->dir, FDT_IO_EOPEN, ": is a directory");

    /* A file that opens but cannot be read: /proc/self/mem at offset 0
     * (unmapped) fails read() with EIO, through a link of each format's
     * name: the streamed readers and the buffered one report it. */
    if (access("/proc/self/mem", R_OK) == 0) {
        const char *names[] = {"mem.xyz", "mem.ply", "mem.node"};
        for (int i = 0; i < 3; i++) {
            snprintf(path, sizeof path, "%s/%s", t->dir, names[i]);
            if (symlink("/proc/self/mem", path) != 0) {
                fail_at(t, __LINE__, "symlink %s: %s", path, strerror(errno));
                continue;
            }
            char want[64];
            snprintf(want, sizeof want, "%s: cannot read: %s", names[i], strerror(EIO));
            EXPECT_ERR(t, path, FDT_IO_EOPEN, want);
            unlink(path);
        }
    }

    write_file(t, "locked.xyz", "0 0 0\n", 6, path, sizeof path);
    if (geteuid() != 0) { /* root reads anything */
        chmod(path, 0);
        EXPECT_ERR(t, path, FDT_IO_EOPEN,
                   "locked.xyz: cannot open: Permission denied");
        chmod(path, 0600);
    }
    write_file(t, "points.las", "0 0 0\n", 6, path, sizeof path);
    EXPECT_ERR(t, path, FDT_IO_EEXT,
               "points.las: unknown extension '.las' (expected .xyz, .txt, "
               ".csv, .node or .ply)");
    write_file(t, "points", "0 0 0\n", 6, path, sizeof path);
    EXPECT_ERR(t, path, FDT_IO_EEXT, "points: unknown extension ''");
    write_file(t, "points.xyz.gz", "0 0 0\n", 6, path, sizeof path);
    EXPECT_ERR(t, path, FDT_IO_EEXT, "unknown extension '.gz'");

    /* arguments, and messages cut to the buffer */
    double *xyz = (double *)&xyz;
    size_t n = 7;
    char err[64];
    EXPECTF(fdt_rd_points(NULL, &xyz, &n, err, sizeof err) ==
                 FDT_IO_EOPEN && xyz == NULL && n == 0,
          "NULL path accepted");
    write_file(t, "fine.xyz", "0 0 0\n", 6, path, sizeof path);
    EXPECTF(fdt_rd_points(path, NULL, &n, err, sizeof err) == FDT_IO_EOPEN,
          "NULL xyz accepted");
    EXPECTF(fdt_rd_points(path, &xyz, NULL, err, sizeof err) ==
                 FDT_IO_EOPEN,
          "NULL n accepted");
    write_file(t, "bad.xyz", "0 0\n", 4, path, sizeof path);
    EXPECTF(fdt_rd_points(path, &xyz, &n, NULL, 0) == FDT_IO_EFORMAT,
          "no message buffer");
    char tiny[8];
    memset(tiny, 'X', sizeof tiny);
    EXPECTF(fdt_rd_points(path, &xyz, &n, tiny, sizeof tiny) ==
                     FDT_IO_EFORMAT &&
                 tiny[7] == '\0' && strncmp(tiny, path, 7) == 0,
          "message not cut to the buffer");
    char big[512];
    EXPECTF(fdt_rd_points(path, &xyz, &n, big, sizeof big) ==
                     FDT_IO_EFORMAT &&
                 strstr(big, "bad.xyz:1: expected 3 numbers, found 2") != NULL,
          "full message: %s", big);
    /* the _with and _mem_with entry points' arguments; formats of names */
    fdt_rd_opts o;
    fdt_rd_opts_default(&o);
    EXPECT(fdt_rd_format_by_name(NULL) == FDT_RD_AUTO);
    EXPECT(fdt_rd_format_by_name("PLY") == FDT_RD_PLY);
    EXPECT(fdt_rd_format_of_path(NULL) == FDT_RD_AUTO);
    EXPECT(fdt_rd_format_of_path("d.xyz/points") == FDT_RD_AUTO); /* the dot is the dir's */
    EXPECT(fdt_rd_format_of_path("d/p.Node") == FDT_RD_NODE);
    EXPECTF(fdt_rd_points_with(path, NULL, &xyz, &n, big, sizeof big) == FDT_IO_EOPEN &&
                strstr(big, "invalid arguments") != NULL,
            "NULL options: %s", big);
    EXPECTF(fdt_rd_points_mem_with(NULL, "0 0 0\n", 6, &o, &xyz, &n, big, sizeof big) ==
                    FDT_IO_EOPEN &&
                strstr(big, "(null): invalid arguments") != NULL,
            "NULL name: %s", big);
    EXPECT(fdt_rd_points_mem_with("m.xyz", NULL, 6, &o, &xyz, &n, big, sizeof big) ==
           FDT_IO_EOPEN);
    EXPECT(fdt_rd_points_mem_with("m.xyz", "0 0 0\n", 6, NULL, &xyz, &n, big, sizeof big) ==
           FDT_IO_EOPEN);
    EXPECT(fdt_rd_points_mem_with("m.xyz", "0 0 0\n", 6, &o, NULL, &n, big, sizeof big) ==
           FDT_IO_EOPEN);
    EXPECTF(fdt_rd_points_mem_with("m.xyz", "0 0 0\n", SIZE_MAX, &o, &xyz, &n, big,
                                   sizeof big) == FDT_IO_ENOMEM &&
                strstr(big, "too large") != NULL && xyz == NULL && n == 0,
            "SIZE_MAX bytes: %s", big);
    /* an empty buffer with no data pointer is an empty file */
    EXPECT(fdt_rd_points_mem_with("m.xyz", NULL, 0, &o, &xyz, &n, big, sizeof big) !=
           FDT_IO_EOPEN);
    free(xyz);
    xyz = NULL;
    /* a successful read clears the message */
    write_file(t, "fine.xyz", "0 0 0\n", 6, path, sizeof path);
    EXPECTF(fdt_rd_points(path, &xyz, &n, big, sizeof big) == FDT_IO_OK &&
                 n == 1 && big[0] == '\0',
          "successful read");
    free(xyz);
}

/* The integer parsers of src/io/read/read_text.c (.node and .ply headers): the
 * int64 range exactly, signs, and what is not an integer. */
static void test_parse_int(tctx *t)
{
    (void)t;
    static const struct {
        const char *s;
        int st;
        int64_t v;
    } cases[] = {
        {"0", NUM_OK, 0},
        {"+17", NUM_OK, 17},
        {"-17", NUM_OK, -17},
        {"9223372036854775807", NUM_OK, INT64_MAX},
        {"-9223372036854775808", NUM_OK, INT64_MIN},
        {"9223372036854775808", NUM_OVERFLOW, 0},
        {"-9223372036854775809", NUM_OVERFLOW, 0},
        {"18446744073709551616", NUM_OVERFLOW, 0}, /* past uint64 too */
        {"123456789012345678901234567890", NUM_OVERFLOW, 0},
        {"", NUM_SYNTAX, 0},
        {"-", NUM_SYNTAX, 0},
        {"+", NUM_SYNTAX, 0},
        {"12a", NUM_SYNTAX, 0},
        {"1.0", NUM_SYNTAX, 0},
        {"--1", NUM_SYNTAX, 0},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        int64_t v = 42;
        int st = fdt_rd_parse_int(cases[i].s, strlen(cases[i].s), &v);
        EXPECTF(st == cases[i].st && (st != NUM_OK || v == cases[i].v), "'%s': %d, %lld",
                cases[i].s, st, (long long)v);
    }
    /* counts: digits only, no sign */
    uint64_t u = 7;
    EXPECT(fdt_rd_parse_count("123", 3, &u) == NUM_OK && u == 123);
    EXPECT(fdt_rd_parse_count("+1", 2, &u) == NUM_SYNTAX);
    EXPECT(fdt_rd_parse_count("-1", 2, &u) == NUM_SYNTAX);
    EXPECT(fdt_rd_parse_count("", 0, &u) == NUM_SYNTAX);
    EXPECT(fdt_rd_parse_count("99999999999999999999", 20, &u) == NUM_OVERFLOW);
}

/* Numbers do not depend on the locale's decimal point. */
static void test_locale(tctx *t)
{
    static const char *const names[] = {"de_DE.UTF-8", "de_DE.utf8",
                                        "fr_FR.UTF-8", "fr_FR.utf8",
                                        "ru_RU.UTF-8", "nl_NL.UTF-8"};
    const char *got = NULL;
    for (size_t i = 0; i < sizeof names / sizeof names[0] && got == NULL; i++)
        if (setlocale(LC_NUMERIC, names[i]) != NULL)
            got = names[i]; /* setlocale's own string dies with the next call */
    if (got == NULL || strcmp(localeconv()->decimal_point, ".") == 0) {
        setlocale(LC_NUMERIC, "C");
        /* scripts/bootstrap.sh generates de_DE.UTF-8: in CI (CI=true, set
         * by .ci/run's caller) a missing locale is a failure, not a skip. */
        const char *ci = getenv("CI");
        if (ci != NULL && strcmp(ci, "true") == 0)
            fail_at(t, __LINE__, "CI=true and no locale with a decimal comma "
                                 "(scripts/bootstrap.sh generates de_DE.UTF-8)");
        else
            printf("note: no locale with a decimal comma installed; locale "
                   "test skipped (run scripts/bootstrap.sh)\n");
        return;
    }
    /* expected values come from strtod in the C locale */
    setlocale(LC_NUMERIC, "C");
    static const char *const lits[] = {
        "0.1", "2.5e-3", "123456789012345678901.5",
        "1.00000000000000000000000000001", "-7.25", "9.999999999999999999e22"};
    double want[6];
    parse_expected(lits, 6, want);
    setlocale(LC_NUMERIC, got);
    char path[1024];
    bbuf b = {0};
    bb_printf(&b, "%s %s %s\n%s %s %s\n", lits[0], lits[1], lits[2], lits[3],
              lits[4], lits[5]);
    write_file(t, "locale.xyz", b.p, b.n, path, sizeof path);
    EXPECT_OK(t, path, want, 2);
    bb_free(&b);
    setlocale(LC_NUMERIC, "C");
    test_xyz_random(t, "locale", 3000, got);
    printf("locale %s: numbers read as in the C locale\n", got);
}

/* ------------------------------------------------------------------ */
/* Tables in tests/bad and tests/good                                 */
/* ------------------------------------------------------------------ */

/* Splits "FILE  FIELD  REST" (blanks between); returns 0 for comments. */
/* A file the reader must accept, whatever its points. */
static void check_read_some(tctx *t, int line, const char *path)
{
    double *xyz = NULL;
    size_t n = 0;
    char err[512];
    int rc = fdt_rd_points(path, &xyz, &n, err, sizeof err);
    test_count_checks(1);
    if (rc != FDT_IO_OK)
        fail_at(t, line, "%s: expected OK, got %s: %s", path, code_name(rc),
                err);
    else if (n == 0 || xyz == NULL)
        fail_at(t, line, "%s: OK without points", path);
    free(xyz);
}

/*
 * fdt_rd_points_mem() on the bytes of path, named by its base name, must
 * give what fdt_rd_points() gives on path: the same code, the same
 * points, the same message after the name. Directories and missing files
 * have no bytes: skipped.
 */
static void check_mem_same(tctx *t, const char *path, const char *name)
{
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISREG(st.st_mode))
        return;
    FILE *f = fopen(path, "rb");
    EXPECTF(f != NULL, "cannot open %s", path);
    if (f == NULL)
        return;
    size_t len = (size_t)st.st_size;
    char *buf = malloc(len ? len : 1);
    if (buf == NULL)
        exit(1);
    size_t got = fread(buf, 1, len, f);
    fclose(f);
    EXPECTF(got == len, "short read of %s", path);
    double *a = NULL, *b = NULL;
    size_t na = 0, nb = 0;
    char ea[512], eb[512];
    int ra = fdt_rd_points(path, &a, &na, ea, sizeof ea);
    int rb = fdt_rd_points_mem(name, buf, got, &b, &nb, eb, sizeof eb);
    test_count_checks(1);
    size_t lp = strlen(path), ln = strlen(name);
    if (ra != rb)
        fail_at(t, __LINE__, "%s: file %s, memory %s", path, code_name(ra),
                code_name(rb));
    else if (ra == FDT_IO_OK &&
             (na != nb || memcmp(a, b, 3 * na * sizeof *a) != 0))
        fail_at(t, __LINE__, "%s: file and memory give other points", path);
    else if (ra != FDT_IO_OK &&
             (strncmp(ea, path, lp) != 0 || strncmp(eb, name, ln) != 0 ||
              strcmp(ea + lp, eb + ln) != 0))
        fail_at(t, __LINE__, "%s: messages differ: '%s' / '%s'", path, ea, eb);
    free(a);
    free(b);
    free(buf);
}

static int split_row(char *line, char **file, char **field, char **rest)
{
    size_t len = strlen(line);
    while (len > 0 && (line[len - 1] == '\n' || line[len - 1] == '\r'))
        line[--len] = '\0';
    char *p = line;
    while (*p == ' ' || *p == '\t')
        p++;
    if (*p == '\0' || *p == '#')
        return 0;
    *file = p;
    while (*p && *p != ' ' && *p != '\t')
        p++;
    if (*p)
        *p++ = '\0';
    while (*p == ' ' || *p == '\t')
        p++;
    *field = p;
    while (*p && *p != ' ' && *p != '\t')
        p++;
    if (*p)
        *p++ = '\0';
    while (*p == ' ' || *p == '\t')
        p++;
    *rest = p;
    return 1;
}

static void replay_bad(tctx *t, const char *dir)
{
    char table[1024], line[1024], path[1024];
    snprintf(table, sizeof table, "%s/EXPECTED.txt", dir);
    FILE *f = fopen(table, "r");
    EXPECTF(f != NULL, "cannot open %s", table);
    if (f == NULL)
        return;
    char listed[128][64];
    size_t nlisted = 0, rows = 0;
    while (fgets(line, sizeof line, f) != NULL) {
        char *file, *code, *msg;
        if (!split_row(line, &file, &code, &msg))
            continue;
        rows++;
        EXPECTF(strcmp(code, "2") == 0 && *msg != '\0',
              "%s: bad row for %s", table, file);
        int want = FDT_IO_EFORMAT;
        if (strstr(msg, "cannot open") || strstr(msg, "is a directory"))
            want = FDT_IO_EOPEN;
        else if (strstr(msg, "unknown extension"))
            want = FDT_IO_EEXT;
        else if (strstr(msg, "distinct point"))
            want = FDT_IO_OK; /* refused by the library, not the reader */
        snprintf(path, sizeof path, "%s/%s", dir, file);
        if (want == FDT_IO_OK)
            check_read_some(t, __LINE__, path);
        else
            check_read_err(t, __LINE__, path, want, msg);
        check_mem_same(t, path, file);
        if (nlisted < 128)
            snprintf(listed[nlisted++], sizeof listed[0], "%s", file);
    }
    fclose(f);
    EXPECTF(rows >= 40, "%s: only %zu rows", table, rows);
    /* every file in the corpus has a row */
    DIR *d = opendir(dir);
    EXPECTF(d != NULL, "cannot list %s", dir);
    if (d == NULL)
        return;
    struct dirent *de;
    while ((de = readdir(d)) != NULL) {
        const char *nm = de->d_name;
        if (nm[0] == '.' || strcmp(nm, "EXPECTED.txt") == 0 ||
            strcmp(nm, "generate.py") == 0)
            continue;
        int found = 0;
        for (size_t i = 0; i < nlisted; i++)
            found |= strcmp(listed[i], nm) == 0;
        EXPECTF(found, "%s/%s has no row in EXPECTED.txt", dir, nm);
    }
    closedir(d);
    printf("replayed %zu hostile inputs from %s\n", rows, dir);
}

static void replay_good(tctx *t, const char *dir)
{
    /* the points every sample holds (tests/good/EXPECTED.txt) */
    static const double cube10[30] = {
        0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1, 1, 1, 1,
        0.5, 0.25, 0.75, 0.25, -0.125, 1.5};
    char table[1024], line[1024], path[1024];
    snprintf(table, sizeof table, "%s/EXPECTED.txt", dir);
    FILE *f = fopen(table, "r");
    EXPECTF(f != NULL, "cannot open %s", table);
    if (f == NULL)
        return;
    size_t rows = 0;
    while (fgets(line, sizeof line, f) != NULL) {
        char *file, *count, *rest;
        if (!split_row(line, &file, &count, &rest))
            continue;
        rows++;
        snprintf(path, sizeof path, "%s/%s", dir, file);
        size_t n = (size_t)strtoul(count, NULL, 10);
        EXPECTF(n == 10, "%s: count %s", table, count);
        check_read_ok(t, __LINE__, path, n == 10 ? cube10 : NULL, n);
        check_mem_same(t, path, file);
    }
    fclose(f);
    EXPECTF(rows >= 7, "%s: only %zu rows", table, rows);
    printf("replayed %zu valid samples from %s\n", rows, dir);
}

/* ------------------------------------------------------------------ */
/* Real data                                                          */
/* ------------------------------------------------------------------ */

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Reads every "| `NAME.xyz` | COUNT |" row of DIR/README.md. */
static int run_data(const char *dir)
{
    char readme[1024], line[2048], path[1024];
    snprintf(readme, sizeof readme, "%s/README.md", dir);
    FILE *f = fopen(readme, "r");
    if (f == NULL) {
        printf("%s not found: real-data test skipped\n", readme);
        return SKIP_CODE;
    }
    int failures = 0, files = 0;
    while (fgets(line, sizeof line, f) != NULL) {
        char name[256];
        char count[64];
        if (sscanf(line, "| `%255[^`]` | %63[0-9,] |", name, count) != 2)
            continue;
        size_t want = 0;
        for (const char *c = count; *c; c++)
            if (*c != ',')
                want = want * 10 + (size_t)(*c - '0');
        snprintf(path, sizeof path, "%s/%s", dir, name);
        if (access(path, R_OK) != 0) {
            printf("%s absent: real-data test skipped\n", path);
            fclose(f);
            return SKIP_CODE;
        }
        double *xyz = NULL;
        size_t n = 0;
        char err[512];
        double t0 = now();
        int rc = fdt_rd_points(path, &xyz, &n, err, sizeof err);
        double dt = now() - t0;
        files++;
        if (rc != FDT_IO_OK) {
            fprintf(stderr, "FAIL: %s\n", err);
            failures++;
            continue;
        }
        int finite = 1;
        for (size_t i = 0; i < 3 * n; i++)
            finite &= isfinite(xyz[i]) != 0;
        if (n != want || !finite) {
            fprintf(stderr, "FAIL: %s: %zu points (README: %zu)%s\n", path, n,
                    want, finite ? "" : ", not all finite");
            failures++;
        }
        printf("%s: %zu points in %.3f s\n", name, n, dt);
        free(xyz);
    }
    fclose(f);
    if (files < 3) {
        fprintf(stderr, "FAIL: %s lists %d files, expected 3\n", readme,
                files);
        failures++;
    }
    return failures ? 1 : 0;
}

/* ------------------------------------------------------------------ */
/* Columns, headers, standard input, pipes and progress (issue 17)    */
/* ------------------------------------------------------------------ */

/* Reads text named name through fdt_rd_points_mem_with with the options
 * base (NULL: the defaults) and columns cols (NULL: base's) on `threads`
 * threads (slices of a byte); returns the code, the points in *xyz
 * (caller frees) and the message. */
static int read_cols(const char *name, const char *text, const fdt_rd_opts *base,
                     const int *cols, int threads, double **xyz, size_t *n, char *err,
                     size_t errlen)
{
    fdt_rd_opts o;
    fdt_rd_opts_default(&o);
    if (base != NULL)
        o = *base;
    if (cols != NULL)
        memcpy(o.columns, cols, sizeof o.columns);
    o.threads = threads;
    o.min_slice = 1;
    return fdt_rd_points_mem_with(name, text, strlen(text), &o, xyz, n, err, errlen);
}

/* The text must read as want[0..3n) on 1 and 3 threads. */
#define COLS_OK(t, name, text, cols, want, nw) \
    cols_ok((t), __LINE__, name, text, NULL, cols, want, nw)
static void cols_ok(tctx *t, int line, const char *name, const char *text,
                    const fdt_rd_opts *base, const int *cols, const double *want, size_t nw)
{
    for (int T = 1; T <= 3; T += 2) {
        double *xyz = NULL;
        size_t n = 0;
        char err[256];
        int rc = read_cols(name, text, base, cols, T, &xyz, &n, err, sizeof err);
        test_count_checks(1);
        if (rc != FDT_IO_OK || n != nw || memcmp(xyz, want, 3 * nw * sizeof *want) != 0)
            fail_at(t, line, "%s (%d threads): %s, %zu points: %s", name, T, code_name(rc), n,
                    rc ? err : "wrong coordinates");
        free(xyz);
    }
}

/* The text must be refused with a message holding sub, on 1 and 3 threads. */
#define COLS_ERR(t, name, text, cols, sub) cols_err((t), __LINE__, name, text, NULL, cols, sub)
static void cols_err(tctx *t, int line, const char *name, const char *text,
                     const fdt_rd_opts *base, const int *cols, const char *sub)
{
    for (int T = 1; T <= 3; T += 2) {
        double *xyz = NULL;
        size_t n = 0;
        char err[256];
        int rc = read_cols(name, text, base, cols, T, &xyz, &n, err, sizeof err);
        test_count_checks(1);
        if (rc == FDT_IO_OK || strstr(err, sub) == NULL)
            fail_at(t, line, "%s (%d threads): want an error with \"%s\", got %s: %s", name, T,
                    sub, code_name(rc), err);
        free(xyz);
    }
}

/* Decimal commas and semicolons (issue 34): a European export is read
 * as written when its separator and decimal mark are named, and refused,
 * naming its line and what to pass, when they are not; never read as
 * other numbers. On 1 and 3 threads (the slices' refusals are worded by
 * the one-thread read). */
#define SEP_OK(t, name, text, delim, dc, want, nw) \
    cols_ok((t), __LINE__, name, text, sep_opts(&o, delim, dc), NULL, want, nw)
#define SEP_ERR(t, name, text, delim, dc, sub) \
    cols_err((t), __LINE__, name, text, sep_opts(&o, delim, dc), NULL, sub)
static const fdt_rd_opts *sep_opts(fdt_rd_opts *o, char delim, int dc)
{
    fdt_rd_opts_default(o);
    o->delimiter = delim;
    o->decimal_comma = dc;
    return o;
}

static void test_separators(tctx *t)
{
    fdt_rd_opts o;
    static const double eu[] = {64.4067, 58.7253, 78.2371, 0.5, 0.25, 2, 1, 0, 0, 0, 1, 0};
    static const double half[] = {0.5, 0.1, 0.2, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    static const double sq[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    const char *eu_blank = "64,4067 58,7253 78,2371\n0,5 0,25 2\n1 0 0\n0 1 0\n";
    /* A decimal comma and blanks: refused by default (it read as x=64,
     * y=4067, z=58), read with --decimal-comma. */
    SEP_ERR(t, "eu.xyz", eu_blank, 0, 0,
            "eu.xyz:1: commas between digits and blanks between fields: pass --decimal-comma");
    SEP_OK(t, "eu.xyz", eu_blank, 0, 1, eu, 4);
    SEP_OK(t, "eu.xyz", "x y z\n64,4067 58,7253 78,2371\n0,5\t0,25\t2\n1 0 0\n0 1 0\n", 0, 1, eu,
           4);
    /* Every point on one line before ("0,5 0,1 0,2": 0 5 0): refused on
     * the line that first mixes them. */
    SEP_ERR(t, "half.xyz", "1 0 0\n0,5 0,1 0,2\n", 0, 0, "half.xyz:2: commas between digits");
    SEP_ERR(t, "late.xyz", "1 0 0\n0 1 0\n0 0 1\n7 8,5 9\n", 0, 0, "late.xyz:4:");
    /* Semicolons: refused, naming the line (not taken as a header), with
     * the option to pass, and --decimal-comma when the line has commas. */
    SEP_ERR(t, "semi.csv", "0;0;0\n1;0;0\n0;1;0\n0;0;1\n", 0, 0,
            "semi.csv:1: fields separated by ';' in '0;0;0': read the file with --delimiter ';'");
    SEP_ERR(t, "semih.csv", "x;y;z\n0;0;0\n1;0;0\n0;1;0\n0;0;1\n", 0, 0,
            "semih.csv:2: fields separated by ';'");
    SEP_ERR(t, "semid.csv", "0,5;0,1;0,2\n", 0, 0, "--delimiter ';' --decimal-comma");
    SEP_OK(t, "semi.csv", "x;y;z\n0;0;0\n1;0;0\n0 ;1; 0\n0;0;1\n", ';', 0, sq, 4);
    SEP_OK(t, "semid.csv", "0,5;0,1;0,2\n1;0;0\n0;1;0\n0;0;1\n", ';', 1, half, 4);
    SEP_ERR(t, "semid.csv", "0,5;0,1;0,2\n", ';', 0,
            "semid.csv:1: a comma inside the number '0,5': pass --decimal-comma");
    SEP_ERR(t, "semie.csv", "0;;0\n", ';', 0, "semie.csv:1: empty field (stray semicolon)");
    /* What stays as it was: commas alone, commas with blanks around them,
     * blanks alone; a named ',' delimiter reads mixed lines as before. */
    SEP_OK(t, "c.csv", "0,0,0\n1,0,0\n0,1,0\n0,0,1\n", 0, 0, sq, 4);
    SEP_OK(t, "cs.csv", "0, 0, 0\n1 ,0 ,0\n0 , 1 , 0\n0,0,1\n", 0, 0, sq, 4);
    SEP_OK(t, "b.xyz", "0 0 0\n1 0 0\n0 1 0\n0 0 1\n", 0, 0, sq, 4);
    static const double mixed[] = {0, 5, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    SEP_OK(t, "m.xyz", "0,5 0,1 0,2\n1 0 0 0 0 0\n0 1 0 0 0 0\n0 0 1 0 0 0\n", ',', 0, mixed, 4);
    /* Blanks only: a comma is then inside a field. */
    SEP_ERR(t, "bc.xyz", "0,0,0\n", ' ', 0, "bc.xyz:1: a comma inside the number '0,0,0'");
    /* A decimal comma with a thousands separator or two commas: refused. */
    SEP_ERR(t, "k.xyz", "1.000,5 0 0\n", 0, 1, "k.xyz:1: not a number: '1.000,5'");
    SEP_ERR(t, "cc.xyz", "1,0,5 0 0\n", 0, 1, "cc.xyz:1: not a number: '1,0,5'");
    /* a decimal-comma field too long for any double's digits, and one
     * that overflows */
    char longf[200];
    memset(longf, '1', 150);
    memcpy(longf + 150, ",5 0 0\n", 8);
    SEP_ERR(t, "long.xyz", longf, 0, 1, "long.xyz:1: not a number");
    SEP_ERR(t, "big.xyz", "1e999,5 0 0\n", 0, 1, "big.xyz:1: not a number");
    SEP_ERR(t, "ovf.xyz", "0 1,5e999 0\n", 0, 1, "ovf.xyz:1: '1,5e999' overflows a double");
    /* separators of several characters between fields: a comma among
     * blanks is no tight comma, blanks alone are */
    SEP_OK(t, "wide.xyz", "0  ,  0 ,\t0\n1\t\t0  0\n0 1 0\n0 0 1\n", 0, 0, sq, 4);
    /* Refused options: a comma both ways; another character; a format
     * without fields. */
    SEP_ERR(t, "both.xyz", "0 0 0\n", ',', 1, "a decimal comma cannot also separate fields");
    SEP_ERR(t, "x.xyz", "0 0 0\n", 'x', 0, "the delimiter is ',', ';' or ' '");
    SEP_ERR(t, "p.node", "1 3 0 0\n0 0 0 0\n", ';', 0,
            "a delimiter or decimal comma applies to .xyz, .txt and .csv only");
}

/* Quoted fields (RFC 4180, as spreadsheets and PDAL write CSV): the
 * text between the quotes is the field; a doubled quote and separators
 * inside are text; the header may be quoted too. A quote that does not
 * close, or text after the closing quote, is refused naming the line. */
static void test_quoted(tctx *t)
{
    fdt_rd_opts o;
    static const double sq[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    static const double half[] = {0.5, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    SEP_OK(t, "q.csv", "\"X\",\"Y\",\"Z\"\n\"0\",\"0\",\"0\"\n\"1\",\"0\",\"0\"\n"
           "0,\"1\",0\n\"0\", \"0\" ,\"1\"\n", 0, 0, sq, 4);
    /* no header: a first line of quoted numbers is data */
    SEP_OK(t, "qn.csv", "\"0\",\"0\",\"0\"\n\"1\",\"0\",\"0\"\n\"0\",\"1\",\"0\"\n"
           "\"0\",\"0\",\"1\"\n", 0, 0, sq, 4);
    /* a skipped text column with commas and doubled quotes inside, and a
     * header naming it "dist, m" (its ", m" is no number either) */
    SEP_OK(t, "qt.csv", "\"x\",\"y\",\"z\",\"dist, 2\"\n0,0,0,\"a, b\"\n1,0,0,\"say \"\"hi\"\"\"\n"
           "0,1,0,\"\"\n0,0,1,c\n", 0, 0, sq, 4);
    /* quoted decimal commas with ';' between fields */
    SEP_OK(t, "qd.csv", "\"0,5\";\"0\";\"0\"\n1;0;0\n0;1;0\n0;0;1\n", ';', 1, half, 4);
    SEP_ERR(t, "qo.csv", "0,0,0\n\"1,0,0\n", 0, 0, "qo.csv:2: a quote that does not close: '\"1,0,0'");
    SEP_ERR(t, "qa.csv", "0,0,0\n\"1\"x,0,0\n", 0, 0,
            "qa.csv:2: text after the closing quote: '\"1\"x'");
    SEP_ERR(t, "qx.csv", "0,0,0\n\"1x\",0,0\n", 0, 0, "qx.csv:2: not a number: '1x'");
    SEP_ERR(t, "qc.csv", "0,0,0\n1,\"0,5\",0\n", 0, 0,
            "qc.csv:2: a comma inside the quoted number '0,5': a decimal comma is read only");
    /* a line of data that is quoted and short is still refused */
    SEP_ERR(t, "qs.csv", "0,0,0\n\"1\",\"0\"\n", 0, 0, "qs.csv:2: expected 3 numbers, found 2");
}

static void test_columns(tctx *t)
{
    static const double sq[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    /* Lidar exports: x y z intensity r g b; extra columns skipped unread
     * (even words), with blanks or commas. */
    COLS_OK(t, "lidar.xyz",
            "0 0 0 17 255 0 0\n1 0 0 3 0 255 0\n0 1 0 9 0 0 255\n0 0 1 1 nan x y\n", NULL, sq, 4);
    COLS_OK(t, "lidar.csv", "0,0,0,17\n1,0,0,3\n0,1,0,9\n0,0,1,1\n", NULL, sq, 4);
    COLS_OK(t, "lidar.txt", "0 0 0 a\n# note\n\n1 0 0 b\n0 1 0 c\n0 0 1 d\n", NULL, sq, 4);
    /* Every line has the first line's count. */
    COLS_ERR(t, "short.xyz", "0 0 0 1\n1 0 0 1\n0 1 0\n0 0 1 1\n", NULL,
             "short.xyz:3: expected 4 columns as on the first line, found 3");
    COLS_ERR(t, "long.xyz", "0 0 0\n1 0 0 1\n", NULL, "long.xyz:2: expected 3 numbers, found 4");
    COLS_ERR(t, "two.xyz", "0 0\n1 0\n", NULL, "two.xyz:1: expected 3 numbers, found 2");
    /* A bad number in a coordinate column still names its line. */
    COLS_ERR(t, "badnum.xyz", "0 0 0 1\n1 0 q 1\n", NULL, "badnum.xyz:2: not a number: 'q'");

    /* --columns 3,4,5 (from 1): x, y, z wherever they are, in any order. */
    static const int c345[3] = {3, 4, 5}, c321[3] = {3, 2, 1};
    COLS_OK(t, "id.csv", "7,a,0,0,0\n8,b,1,0,0\n9,c,0,1,0\n10,d,0,0,1\n", c345, sq, 4);
    COLS_OK(t, "rev.xyz", "0 0 0\n0 0 1\n0 1 0\n1 0 0\n", c321, sq, 4);
    COLS_ERR(t, "few.csv", "1,2,3,4,5\n1,2,3\n", c345,
             "few.csv:2: columns 3,4,5 need 5 fields, found 3");
    COLS_ERR(t, "few1.csv", "1,2,3\n", c345, "few1.csv:1: columns 3,4,5 need 5 fields, found 3");
    static const int c0[3] = {0, 1, 2};
    COLS_ERR(t, "zero.xyz", "0 0 0\n", c0, "zero.xyz: column 0 is not a column");
    COLS_ERR(t, "pts.node", "1 3 0 0\n0 0 0 0\n", c345,
             "pts.node: columns apply to .xyz, .txt and .csv only");
    COLS_ERR(t, "pts.ply", "ply\n", c345, "pts.ply: columns apply to .xyz, .txt and .csv only");
    /* 1,2,3 spelled out is the default, .node included. */
    static const int c123[3] = {1, 2, 3};
    COLS_OK(t, "n.node", "4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 1 0\n3 0 0 1\n", c123, sq, 4);

    /* Headers: a first content line of printable words, none a number. */
    COLS_OK(t, "hdr.csv", "X,Y,Z,Intensity\n0,0,0,1\n1,0,0,1\n0,1,0,1\n0,0,1,1\n", NULL, sq, 4);
    COLS_OK(t, "pdal.txt", "\"X\",\"Y\",\"Z\"\n0,0,0\n1,0,0\n0,1,0\n0,0,1\n", NULL, sq, 4);
    COLS_OK(t, "cc.txt", "# exported\n\n//X,Y,Z,R,G,B\n0,0,0,1,2,3\n1,0,0,1,2,3\n0,1,0,1,2,3\n"
                         "0,0,1,1,2,3\n", NULL, sq, 4);
    COLS_OK(t, "hdr345.csv", "id,name,x,y,z\n1,a,0,0,0\n2,b,1,0,0\n3,c,0,1,0\n4,d,0,0,1\n", c345,
            sq, 4);
    /* Line numbers after a header stay those of the file. */
    COLS_ERR(t, "hdrbad.csv", "X,Y,Z\n0,0,0\n1,0,q\n", NULL, "hdrbad.csv:3: not a number: 'q'");
    /* Only the first content line; a second one is an error. */
    COLS_ERR(t, "hdr2.csv", "X,Y,Z\nX,Y,Z\n0,0,0\n", NULL, "hdr2.csv:2: not a number: 'X'");
    /* Not headers: a number among the words, nan, non-printable bytes. */
    COLS_ERR(t, "mixed.csv", "X,1,Z\n0,0,0\n", NULL, "mixed.csv:1: not a number: 'X'");
    COLS_ERR(t, "nanfirst.xyz", "nan nan nan\n0 0 0\n", NULL,
             "nanfirst.xyz:1: not a finite number: 'nan'");
    COLS_ERR(t, "bin.xyz", "X\x01 Y Z\n0 0 0\n", NULL, "bin.xyz:1: not a number: 'X\\x01'");
    COLS_ERR(t, "hdronly.csv", "X,Y,Z\n", NULL, "hdronly.csv: no points");

    /* Larger, on several threads with real slices: header and columns. */
    bbuf b = {0};
    bb_printf(&b, "a,b,x,y,z\n");
    enum { NP = 5000 };
    double *want = malloc(3 * NP * sizeof *want);
    if (want == NULL)
        exit(1);
    for (size_t i = 0; i < NP; i++) {
        for (int k = 0; k < 3; k++)
            want[3 * i + (size_t)k] = (double)(rnd(t) % 100000) / 64;
        bb_printf(&b, "%zu,w%zu,%.17g,%.17g,%.17g\n", i, i, want[3 * i], want[3 * i + 1],
                  want[3 * i + 2]);
    }
    bb_put(&b, "", 1);
    COLS_OK(t, "big.csv", (const char *)b.p, c345, want, NP);
    bb_free(&b);
    free(want);
}

/* A writer thread for a pipe or FIFO: writes len bytes of data to fd (or,
 * with path set, opens path for writing first) and closes it. */
typedef struct pipe_writer {
    const char *path;
    int fd;
    const void *data;
    size_t len;
} pipe_writer;

static void *pipe_writer_run(void *arg)
{
    pipe_writer *w = arg;
    int fd = w->path != NULL ? open(w->path, O_WRONLY) : w->fd;
    const char *p = w->data;
    size_t left = w->len;
    while (fd >= 0 && left > 0) {
        ssize_t k = write(fd, p, left);
        if (k <= 0)
            break;
        p += k;
        left -= (size_t)k;
    }
    if (fd >= 0)
        close(fd);
    return NULL;
}

/* Reads data with options o through a pipe standing in for standard
 * input ("-"), written by a thread of its own. */
static int read_stdin_with(const void *data, size_t len, const fdt_rd_opts *o, double **xyz,
                           size_t *n, char *err, size_t errlen)
{
    int fds[2];
    if (pipe(fds) != 0)
        exit(1);
    int saved = dup(STDIN_FILENO);
    if (saved < 0 || dup2(fds[0], STDIN_FILENO) < 0)
        exit(1);
    close(fds[0]);
    pipe_writer w = {NULL, fds[1], data, len};
    pthread_t tid;
    if (pthread_create(&tid, NULL, pipe_writer_run, &w) != 0)
        exit(1);
    int rc = fdt_rd_points_with("-", o, xyz, n, err, errlen);
    pthread_join(tid, NULL);
    dup2(saved, STDIN_FILENO);
    close(saved);
    return rc;
}

/* The same with the default options and format. */
static int read_stdin(const void *data, size_t len, int format, double **xyz, size_t *n,
                      char *err, size_t errlen)
{
    fdt_rd_opts o;
    fdt_rd_opts_default(&o);
    o.format = format;
    return read_stdin_with(data, len, &o, xyz, n, err, errlen);
}

typedef struct prog_log {
    size_t calls[2], last_done[2], last_total[2];
    size_t zero_total; /* reports with total 0 */
    int backwards;
} prog_log;

static void prog_cb(void *user, int stage, size_t done, size_t total)
{
    prog_log *l = user;
    if (stage < 0 || stage > 1)
        return;
    if (l->calls[stage] > 0 && done < l->last_done[stage])
        l->backwards = 1;
    l->calls[stage]++;
    l->zero_total += total == 0;
    l->last_done[stage] = done;
    l->last_total[stage] = total;
}

static void test_stdin(tctx *t)
{
    /* Text, larger than a pipe's buffer, so the reader must wait for it. */
    bbuf b = {0};
    enum { NP = 20000 };
    double *want = malloc(3 * NP * sizeof *want);
    if (want == NULL)
        exit(1);
    for (size_t i = 0; i < NP; i++) {
        for (int k = 0; k < 3; k++)
            want[3 * i + (size_t)k] = (double)(rnd(t) % 1000000) / 128;
        bb_printf(&b, "%.17g %.17g %.17g\n", want[3 * i], want[3 * i + 1], want[3 * i + 2]);
    }
    double *xyz = NULL;
    size_t n = 0;
    char err[256];
    int rc = read_stdin(b.p, b.n, FDT_RD_XYZ, &xyz, &n, err, sizeof err);
    EXPECTF(rc == FDT_IO_OK && n == NP && memcmp(xyz, want, 3 * NP * sizeof *want) == 0,
          "stdin xyz: %s, %zu points: %s", code_name(rc), n, err);
    free(xyz);

    /* Binary PLY (little endian doubles) through the pipe. */
    bbuf p = {0};
    bb_printf(&p, "ply\nformat binary_little_endian 1.0\nelement vertex %d\n"
                  "property double x\nproperty double y\nproperty double z\nend_header\n", NP);
    for (size_t i = 0; i < 3 * (size_t)NP; i++) {
        uint64_t u;
        memcpy(&u, &want[i], 8);
        unsigned char le[8];
        for (int k = 0; k < 8; k++)
            le[k] = (unsigned char)(u >> (8 * k));
        bb_put(&p, le, 8);
    }
    rc = read_stdin(p.p, p.n, FDT_RD_PLY, &xyz, &n, err, sizeof err);
    EXPECTF(rc == FDT_IO_OK && n == NP && memcmp(xyz, want, 3 * NP * sizeof *want) == 0,
          "stdin ply: %s, %zu points: %s", code_name(rc), n, err);
    free(xyz);

    /* .node, read whole (not streamed): from a pipe its size is unknown,
     * the buffer grows from 64 KiB as the bytes come. */
    bbuf nd = {0};
    bb_printf(&nd, "%d 3 0 0\n", NP);
    for (size_t i = 0; i < NP; i++)
        bb_printf(&nd, "%zu %.17g %.17g %.17g\n", i, want[3 * i], want[3 * i + 1],
                  want[3 * i + 2]);
    rc = read_stdin(nd.p, nd.n, FDT_RD_NODE, &xyz, &n, err, sizeof err);
    EXPECTF(nd.n > 4 * 65536 && rc == FDT_IO_OK && n == NP &&
                memcmp(xyz, want, 3 * NP * sizeof *want) == 0,
            "stdin node (%zu bytes): %s, %zu points: %s", nd.n, code_name(rc), n, err);
    free(xyz);
    bb_free(&nd);

    /* Messages name stdin; without a format it is refused. */
    rc = read_stdin("0 0 0\n1 0 q\n", 12, FDT_RD_XYZ, &xyz, &n, err, sizeof err);
    EXPECTF(rc == FDT_IO_EFORMAT && strcmp(err, "stdin:2: not a number: 'q'") == 0,
          "stdin error: %s: %s", code_name(rc), err);
    rc = read_stdin("0 0 0\n", 6, FDT_RD_AUTO, &xyz, &n, err, sizeof err);
    EXPECTF(rc == FDT_IO_EEXT && strstr(err, "stdin: standard input needs its format") == err,
          "stdin without a format: %s: %s", code_name(rc), err);

    /* A named pipe, by a path with no extension and the format named. */
    char fifo[1024];
    snprintf(fifo, sizeof fifo, "%s/cloud_fifo", t->dir);
    if (mkfifo(fifo, 0600) != 0) {
        fprintf(stderr, "test_reader: mkfifo %s: %s\n", fifo, strerror(errno));
        exit(1);
    }
    pipe_writer w = {fifo, -1, b.p, b.n};
    pthread_t tid;
    if (pthread_create(&tid, NULL, pipe_writer_run, &w) != 0)
        exit(1);
    fdt_rd_opts o;
    fdt_rd_opts_default(&o);
    o.format = FDT_RD_XYZ;
    prog_log lg;
    memset(&lg, 0, sizeof lg);
    o.progress = prog_cb;
    o.progress_user = &lg;
    o.chunk = 65536; /* several blocks: reports while the size is unknown */
    rc = fdt_rd_points_with(fifo, &o, &xyz, &n, err, sizeof err);
    pthread_join(tid, NULL);
    EXPECTF(rc == FDT_IO_OK && n == NP && memcmp(xyz, want, 3 * NP * sizeof *want) == 0,
          "fifo: %s, %zu points: %s", code_name(rc), n, err);
    free(xyz);
    /* Progress from a pipe: the text is streamed, so it is parsed as it
     * is read: parsing reports with no total (a pipe's size is unknown)
     * until the last, which has it; nothing is loaded first. */
    EXPECTF(lg.calls[FDT_RD_LOADING] == 0 && lg.calls[FDT_RD_PARSING] >= 3 &&
                 lg.zero_total > 0 && lg.last_done[FDT_RD_PARSING] == b.n &&
                 lg.last_total[FDT_RD_PARSING] == b.n && !lg.backwards,
          "fifo progress: loading %zu calls, parsing %zu calls (%zu without a total), last %zu "
          "of %zu",
          lg.calls[0], lg.calls[1], lg.zero_total, lg.last_done[1], lg.last_total[1]);

    /* A regular file, on 1 and 3 threads, in blocks of 4 KiB: the total
     * known from the start, parsing never backwards, a report a block. */
    char path[1024];
    write_file(t, "progress.xyz", b.p, b.n, path, sizeof path);
    for (int T = 1; T <= 3; T += 2) {
        memset(&lg, 0, sizeof lg);
        o.format = FDT_RD_AUTO;
        o.threads = T;
        o.min_slice = 1024;
        o.chunk = 4096;
        rc = fdt_rd_points_with(path, &o, &xyz, &n, err, sizeof err);
        EXPECTF(rc == FDT_IO_OK && n == NP && memcmp(xyz, want, 3 * NP * sizeof *want) == 0,
              "progress.xyz: %s: %s", code_name(rc), err);
        free(xyz);
        EXPECTF(lg.calls[FDT_RD_LOADING] == 0 && lg.calls[FDT_RD_PARSING] >= b.n / 4096 &&
                     lg.zero_total == 0 && lg.last_done[FDT_RD_PARSING] == b.n && !lg.backwards,
              "progress.xyz (%d threads): parsing %zu calls, %zu without a total", T,
              lg.calls[1], lg.zero_total);
    }
    bb_free(&b);
    bb_free(&p);
    free(want);
}

/* ------------------------------------------------------------------ */
/* Chunk boundaries (issue 18: streamed .xyz and binary .ply)         */
/* ------------------------------------------------------------------ */

/* Reads len bytes named name in blocks of chunk bytes (0: the default,
 * one block for these inputs) on threads threads (slices of a byte and
 * up): from memory, or, with pipe set, through a pipe as standard input
 * (format from name's extension; messages then start "stdin"). */
static int read_chunked(const char *name, const void *data, size_t len, size_t chunk,
                        int threads, int pipe_in, double **xyz, size_t *n, char *err,
                        size_t errlen)
{
    fdt_rd_opts o;
    fdt_rd_opts_default(&o);
    o.chunk = chunk;
    o.threads = threads;
    o.min_slice = 1;
    if (!pipe_in)
        return fdt_rd_points_mem_with(name, data, len, &o, xyz, n, err, errlen);
    o.format = fdt_rd_format_of_path(name);
    return read_stdin_with(data, len, &o, xyz, n, err, errlen);
}

/*
 * The input read in blocks of every size from 1 byte to past its length,
 * on 1 and 3 threads, from memory and (for some sizes) through a pipe,
 * gives the points want (nw of them) or, when msg is not NULL, exactly
 * the code and message msg (as for the name; "stdin" through a pipe),
 * as the one-block read does. Small blocks put a block boundary inside
 * every line, number, CRLF pair, comment, header line and PLY item.
 */
static void chunk_case(tctx *t, int line, const char *name, const void *data, size_t len,
                       int code, const char *msg, const double *want, size_t nw)
{
    size_t last = len + 2;
    for (size_t chunk = 0; chunk <= last; chunk++) {
        for (int threads = 1; threads <= 3; threads += 2) {
            for (int via = 0; via < 2; via++) {
                if (via == 1 && !(chunk == 1 || chunk == 5 || chunk == 17 || chunk == last))
                    continue; /* pipes cost a thread each: a few sizes */
                double *xyz = NULL;
                size_t n = 0;
                char err[512];
                err[0] = '\0';
                int rc = read_chunked(name, data, len, chunk, threads, via, &xyz, &n, err,
                                      sizeof err);
                char wmsg[600];
                if (msg != NULL)
                    snprintf(wmsg, sizeof wmsg, "%s%s", via ? "stdin" : name,
                             msg + strlen(name));
                if (msg == NULL && (rc != FDT_IO_OK || n != nw ||
                                    memcmp(xyz, want, 3 * nw * sizeof *want) != 0))
                    fail_at(t, line, "%s, chunk %zu, %d threads%s: %s, %zu points (want %zu): %s",
                            name, chunk, threads, via ? ", pipe" : "", code_name(rc), n, nw,
                            err);
                if (msg != NULL && (rc != code || strcmp(err, wmsg) != 0 || xyz != NULL))
                    fail_at(t, line, "%s, chunk %zu, %d threads%s: %s '%s', want %s '%s'",
                            name, chunk, threads, via ? ", pipe" : "", code_name(rc), err,
                            code_name(code), wmsg);
                free(xyz);
            }
        }
    }
}
/*
 * A read() that fails part-way (fdt_rd_opts.fail_after: the memory
 * source fails with EIO as soon as a read reaches past that byte), at
 * every byte of the input, in blocks of several sizes, on 1 and 3
 * threads: always FDT_IO_EOPEN with "NAME: cannot read: ..." and the
 * outputs cleared, never a partial point set; a limit at or past the end
 * changes nothing.
 */
static void fail_sweep(tctx *t, int line, const char *name, const void *data, size_t len,
                       const double *want, size_t nw)
{
    static const size_t chunks[] = {0, 1, 7, 64};
    char wmsg[300];
    snprintf(wmsg, sizeof wmsg, "%s: cannot read: %s", name, strerror(EIO));
    for (size_t ci = 0; ci < sizeof chunks / sizeof chunks[0]; ci++) {
        for (int threads = 1; threads <= 3; threads += 2) {
            for (size_t at = 1; at <= len + 1; at++) {
                fdt_rd_opts o;
                fdt_rd_opts_default(&o);
                o.chunk = chunks[ci];
                o.threads = threads;
                o.min_slice = 1;
                o.fail_after = at;
                double *xyz = (double *)&xyz;
                size_t n = 7;
                char err[512] = "";
                int rc = fdt_rd_points_mem_with(name, data, len, &o, &xyz, &n, err, sizeof err);
                test_count_checks(1);
                if (at < len && (rc != FDT_IO_EOPEN || strcmp(err, wmsg) != 0 || xyz != NULL ||
                                 n != 0))
                    fail_at(t, line, "%s, chunk %zu, %d threads, failing after %zu of %zu "
                                     "bytes: %s '%s'", name, chunks[ci], threads, at, len,
                            code_name(rc), err);
                if (at >= len && (rc != FDT_IO_OK || n != nw ||
                                  memcmp(xyz, want, 3 * nw * sizeof *want) != 0))
                    fail_at(t, line, "%s, chunk %zu, %d threads, a limit of %zu past %zu "
                                     "bytes: %s '%s'", name, chunks[ci], threads, at, len,
                            code_name(rc), err);
                if (rc == FDT_IO_OK)
                    free(xyz);
            }
        }
    }
}

#define CHUNK_OK(t, name, text, want)                                                  \
    chunk_case((t), __LINE__, name, text, strlen(text), FDT_IO_OK, NULL, want,            \
               sizeof(want) / sizeof(want)[0] / 3)
#define CHUNK_ERR(t, name, text, code, msg)                                            \
    chunk_case((t), __LINE__, name, text, strlen(text), code, msg, NULL, 0)

/* A binary little-endian PLY header for nv vertices of three doubles
 * (+ extra lines before end_header). */
static void ply_le_header(bbuf *b, size_t nv, const char *props, const char *more)
{
    bb_printf(b, "ply\nformat binary_little_endian 1.0\ncomment chunks\nelement vertex %zu\n%s%s"
                 "end_header\n",
              nv, props, more);
}

static void put_le(bbuf *b, const void *v, size_t size)
{
    unsigned char out[8];
    uint64_t u = 0;
    memcpy(&u, v, size); /* little-endian hosts only: see below */
    for (size_t i = 0; i < size; i++)
        out[i] = (unsigned char)(u >> (8 * i));
    bb_put(b, out, size);
}

static void test_chunks(tctx *t)
{
    /* a read that stops at an error leaves its pipe's writer with bytes
     * no one reads: EPIPE for it, not a signal for the test */
    signal(SIGPIPE, SIG_IGN);
    static const double w9[] = {1, 2, 3, 4.5, 50, -6, 7, 8, 9};
    /* lines, numbers and exponents split at every byte */
    CHUNK_OK(t, "split.xyz", "1 2 3\n4.5 5e1 -6\n7 8 9\n", w9);
    const char *hdr_csv = "\xef\xbb\xbf# a comment\n\n  X, Y, Z\n1,2,3\n# c\n4.5,5e1,-6\n7,8,9";
    fail_sweep(t, __LINE__, "fail.csv", hdr_csv, strlen(hdr_csv), w9, 3);
    const char *ascii_ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\n"
                            "property double y\nproperty double z\nend_header\n"
                            "1 2 3\n4.5 5e1 -6\n7 8 9\n";
    fail_sweep(t, __LINE__, "fail_ascii.ply", ascii_ply, strlen(ascii_ply), w9, 3);
    /* CRLF: a boundary between '\r' and '\n' */
    CHUNK_OK(t, "crlf.xyz", "1 2 3\r\n4.5 5e1 -6\r\n7 8 9\r\n", w9);
    /* the last line without its newline */
    CHUNK_OK(t, "nolf.xyz", "1 2 3\n4.5 5e1 -6\n7 8 9", w9);
    CHUNK_OK(t, "nolfcr.csv", "1,2,3\r\n4.5,5e1,-6\r\n7,8,9\r", w9);
    /* a byte order mark, a comment and a header line longer than small
     * blocks, blank lines, comments between points */
    CHUNK_OK(t, "header.csv",
             "\xef\xbb\xbf# exported by a scanner, a comment line\n\n  X, Y, Z  # names\n"
             "1,2,3\n# between\n\n4.5,5e1,-6 # trailing\n7,8,9\n",
             w9);
    /* a line longer than every small block (blanks and a skipped column) */
    CHUNK_OK(t, "long.xyz",
             "1                                                  2 3\n"
             "4.5 5e1 -6\n7 8 9\n",
             w9);
    /* errors after boundaries keep their line numbers */
    CHUNK_ERR(t, "bad.xyz", "1 2 3\r\n# c\n\n4 5 6\n7 8 q9\n", FDT_IO_EFORMAT,
              "bad.xyz:5: not a number: 'q9'");
    CHUNK_ERR(t, "hdrbad.xyz", "X Y Z\n\n1 2 3\n4 5\n", FDT_IO_EFORMAT,
              "hdrbad.xyz:4: expected 3 numbers, found 2");
    CHUNK_ERR(t, "cols.xyz", "1 2 3 4\n5 6 7 8\n9 10 11\n", FDT_IO_EFORMAT,
              "cols.xyz:3: expected 4 columns as on the first line, found 3");
    CHUNK_ERR(t, "comma.csv", "1,2,3\n4,,6\n", FDT_IO_EFORMAT,
              "comma.csv:2: empty field (stray comma)");
    CHUNK_ERR(t, "empty.xyz", "", FDT_IO_EFORMAT, "empty.xyz: no points (empty file)");
    CHUNK_ERR(t, "comments.xyz", "# nothing\n\n   \n# here\n", FDT_IO_EFORMAT,
              "comments.xyz: no points");
    CHUNK_ERR(t, "onlyhdr.csv", "x,y,z\n", FDT_IO_EFORMAT, "onlyhdr.csv: no points");

#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    /* Binary PLY: three doubles a vertex (read straight into the array). */
    bbuf b = {0};
    ply_le_header(&b, 3, "property double x\nproperty double y\nproperty double z\n", "");
    for (size_t i = 0; i < 9; i++)
        put_le(&b, &w9[i], 8);
    chunk_case(t, __LINE__, "le.ply", b.p, b.n, FDT_IO_OK, NULL, w9, 3);
    fail_sweep(t, __LINE__, "fail_le.ply", b.p, b.n, w9, 3);
    /* a short body: the error names the byte where the data ends */
    size_t hdr = b.n - 72;
    char msg[300];
    snprintf(msg, sizeof msg,
             "short.ply: byte %zu: file ends inside vertex 3 of 3 (the header declares 3 "
             "vertices of 24 bytes, 50 bytes follow it)",
             hdr + 50);
    chunk_case(t, __LINE__, "short.ply", b.p, hdr + 50, FDT_IO_EFORMAT, msg, NULL, 0);
    snprintf(msg, sizeof msg,
             "before.ply: byte %zu: file ends before vertex 3 of 3 (the header declares 3 "
             "vertices of 24 bytes, 48 bytes follow it)",
             hdr + 48);
    chunk_case(t, __LINE__, "before.ply", b.p, hdr + 48, FDT_IO_EFORMAT, msg, NULL, 0);
    /* extra bytes after the last element */
    bb_put(&b, "xyz", 3);
    snprintf(msg, sizeof msg,
             "extra.ply: byte %zu: 3 bytes of extra data after the last element (the header's "
             "counts are too small?)",
             hdr + 72);
    chunk_case(t, __LINE__, "extra.ply", b.p, b.n, FDT_IO_EFORMAT, msg, NULL, 0);
    /* a NaN in the middle: its byte, and a short body still wins, as the
     * buffered reader refused it before reading a vertex */
    b.n = hdr;
    double nan = NAN;
    for (size_t i = 0; i < 9; i++)
        put_le(&b, i == 4 ? &nan : &w9[i], 8);
    snprintf(msg, sizeof msg, "nan.ply: byte %zu: vertex 2 of 3: y is NaN", hdr + 32);
    chunk_case(t, __LINE__, "nan.ply", b.p, b.n, FDT_IO_EFORMAT, msg, NULL, 0);
    snprintf(msg, sizeof msg,
             "nanshort.ply: byte %zu: file ends inside vertex 3 of 3 (the header declares 3 "
             "vertices of 24 bytes, 60 bytes follow it)",
             hdr + 60);
    chunk_case(t, __LINE__, "nanshort.ply", b.p, hdr + 60, FDT_IO_EFORMAT, msg, NULL, 0);

    /* float x, y, z with a colour, then faces with a list: decoded through
     * the buffer, items cut at every byte */
    bb_free(&b);
    ply_le_header(&b, 3,
                  "property float x\nproperty uchar red\nproperty float y\nproperty float z\n",
                  "element face 2\nproperty list uchar int vertex_indices\n");
    for (size_t i = 0; i < 3; i++) {
        for (int k = 0; k < 3; k++) {
            float f = (float)w9[3 * i + (size_t)k];
            put_le(&b, &f, 4);
            if (k == 0)
                bb_put(&b, "\x7f", 1);
        }
    }
    for (int f = 0; f < 2; f++) {
        bb_put(&b, "\x03", 1);
        for (int32_t v = 0; v < 3; v++)
            put_le(&b, &v, 4);
    }
    chunk_case(t, __LINE__, "mixed.ply", b.p, b.n, FDT_IO_OK, NULL, w9, 3);
    fail_sweep(t, __LINE__, "fail_mixed.ply", b.p, b.n, w9, 3);
    hdr = b.n - 3 * 13 - 2 * 13;
    snprintf(msg, sizeof msg, "mixedshort.ply: byte %zu: file ends inside element 'face' item "
                              "2 of 2", b.n - 1);
    chunk_case(t, __LINE__, "mixedshort.ply", b.p, b.n - 1, FDT_IO_EFORMAT, msg, NULL, 0);
    /* a vertex with a list: read item by item, a negative length named */
    bb_free(&b);
    ply_le_header(&b, 2,
                  "property double x\nproperty list char short n\nproperty double y\n"
                  "property double z\n",
                  "");
    hdr = b.n;
    for (size_t i = 0; i < 2; i++) {
        put_le(&b, &w9[3 * i], 8);
        bb_put(&b, i == 0 ? "\x02" : "\xff", 1);
        if (i == 0)
            bb_put(&b, "\x01\x00\x02\x00", 4);
        put_le(&b, &w9[3 * i + 1], 8);
        put_le(&b, &w9[3 * i + 2], 8);
    }
    snprintf(msg, sizeof msg, "neglist.ply: byte %zu: vertex 2 of 2: negative list length",
             hdr + 29 + 8);
    chunk_case(t, __LINE__, "neglist.ply", b.p, b.n, FDT_IO_EFORMAT, msg, NULL, 0);
    bb_free(&b);
#endif
    /* ASCII PLY and a header cut anywhere, with or without its end */
    CHUNK_OK(t, "ascii.ply",
             "ply\nformat ascii 1.0\ncomment a comment longer than a small block\n"
             "element vertex 3\nproperty double x\nproperty double y\nproperty double z\n"
             "end_header\n1 2 3\n4.5 5e1 -6\n7 8 9\n",
             w9);
    CHUNK_ERR(t, "noend.ply",
              "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty double x\n",
              FDT_IO_EFORMAT, "noend.ply:4: the header has no end_header line");
    CHUNK_ERR(t, "notply.ply", "plyx\nformat ascii 1.0\n", FDT_IO_EFORMAT,
              "notply.ply:1: not a PLY file (the first line is 'plyx', expected 'ply')");
}

int main(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "--data") == 0)
        return run_data(argv[2]);
    if (argc != 3) {
        fprintf(stderr, "usage: test_reader BAD_DIR GOOD_DIR\n"
                        "       test_reader --data DATA_DIR\n");
        return 2;
    }
    tctx t;
    memset(&t, 0, sizeof t);
    t.rng = 0x5eed1234abcdull;
    const char *tmp = getenv("TMPDIR");
    snprintf(t.dir, sizeof t.dir, "%s/fdt_test_reader_XXXXXX",
             tmp != NULL && tmp[0] != '\0' ? tmp : "/tmp");
    if (mkdtemp(t.dir) == NULL) {
        fprintf(stderr, "test_reader: mkdtemp %s: %s\n", t.dir,
                strerror(errno));
        return 1;
    }
    test_xyz_good(&t);
    test_xyz_random(&t, "c", 20000, NULL);
    test_xyz_bad(&t);
    test_xyz_sliced(&t);
    test_node(&t);
    test_ply_good(&t);
    test_ply_nonfinite(&t);
    test_ply_truncation(&t);
    test_ply_bad(&t);
    test_fuzz(&t);
    test_open(&t);
    test_locale(&t);
    test_parse_int(&t);
    test_columns(&t);
    test_separators(&t);
    test_quoted(&t);
    test_stdin(&t);
    test_chunks(&t);
    replay_bad(&t, argv[1]);
    replay_good(&t, argv[2]);
    remove_tree(t.dir);
    return test_report("test_reader");
}
