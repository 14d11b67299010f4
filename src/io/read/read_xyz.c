/*
 * .xyz / .txt point files (src/io/read/reader.h): x y z per line, streamed: the
 * input is read in blocks of rd_ctx.chunk bytes cut after their last line
 * end (the partial line is carried to the next block), and each block is
 * parsed in slices on several threads when it is large enough. Only the
 * points and one block are held (issue 18).
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "io/read/read_common.h"
#include "io/read/reader.h"
#include "base/mem.h"
#include "base/spawn.h"

#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------ */
/* .xyz / .txt                                                        */
/* ------------------------------------------------------------------ */

/* A field in double quotes, as spreadsheets and PDAL write CSV (RFC 4180:
 * a quote inside is doubled, separators inside are text). f->p is at the
 * opening quote; on success (1) the text between the quotes is ts[0, tl)
 * and f->p is past the closing quote. 0: no closing quote on the line;
 * -1: something other than a separator right after the closing quote
 * (ts[0, tl): the field from its opening quote up to that point). */
static int rd_quoted(rd_fields *f, const char **ts, size_t *tl)
{
    const char *q = f->p + 1;
    for (;;) {
        q = memchr(q, '"', (size_t)(f->e - q));
        if (q == NULL)
            return 0;
        if (q + 1 < f->e && q[1] == '"') {
            q += 2;
            continue;
        }
        break;
    }
    *ts = f->p + 1;
    *tl = (size_t)(q - *ts);
    if (!fdt_rd_is_sep(f, q + 1)) {
        *ts = f->p;
        *tl = (size_t)(q + 2 - f->p);
        return -1;
    }
    f->p = q + 1;
    f->n++;
    return 1;
}

/* fdt_rd_next_field with quoted fields (rd_quoted): 1 and the field (a
 * quoted one without its quotes), 0 at the end of the line, -1 on an
 * empty field, -2 on a quote that does not close or is followed by text
 * (ts[0, tl): the field as written). */
static int rd_next_field_q(rd_fields *f, const char **ts, size_t *tl)
{
    int r = fdt_rd_skip_sep(f);
    if (r <= 0 || *f->p != '"')
        return r <= 0 ? r : fdt_rd_next_field(f, ts, tl);
    r = rd_quoted(f, ts, tl);
    if (r == 0) {
        *ts = f->p;
        *tl = (size_t)(f->e - f->p);
    }
    return r > 0 ? 1 : -2;
}

/* The error of a quoted field that rd_quoted refused (r: its result). */
static int rd_quote_fail(const rd_ctx *c, size_t line, int r, const char *ts, size_t tl)
{
    char q[RD_QUOTE_CAP];
    fdt_rd_quote(q, ts, tl);
    return r == 0 ? fdt_rd_fail(c, FDT_IO_EFORMAT, ":%zu: a quote that does not close: %s", line, q)
                  : fdt_rd_fail(c, FDT_IO_EFORMAT, ":%zu: text after the closing quote: %s",
                                line, q);
}

/* Whether the first content line s..e is a header: printable ASCII and
 * no field (between blanks and sep, and between ';' too: a line of
 * semicolon-separated numbers is data whose separator is refused, not a
 * header) that reads as a number, finite or not, or starts as one (a
 * digit, after a sign or a point), so that a first line of
 * data, or of binary garbage, is never skipped unseen. */
static int rd_is_header(const char *s, const char *e, char sep, int decimal_comma)
{
    for (const char *p = s; p < e; p++) {
        unsigned char ch = (unsigned char)*p;
        if (!(ch >= 0x20 && ch < 0x7f) && ch != '\t' && ch != '\r')
            return 0;
    }
    const char *p = s;
    while (p < e) {
        while (p < e && (rd_is_space(*p) || (sep && *p == sep) || *p == ';'))
            p++;
        const char *t = p, *u;
        if (p < e && *p == '"' && (u = memchr(p + 1, '"', (size_t)(e - p - 1))) != NULL) {
            /* a quoted field ("X", or "1.5" on a line of data) is judged
             * by its text */
            t = p + 1;
            p = u;
        } else {
            while (p < e && !rd_is_space(*p) && !(sep && *p == sep) && *p != ';')
                p++;
        }
        if (p > t) {
            double v;
            /* a number, or a field that starts as one ("0,5" or "1.000,5"
             * where ',' is not the separator): data, whose error the
             * parse words */
            size_t tl = (size_t)(p - t);
            const char *d = t + (*t == '+' || *t == '-');
            d += d < p && *d == '.';
            if ((d < p && rd_is_digit(*d)) ||
                (!decimal_comma && fdt_rd_parse_real(t, tl, &v, 0) != NUM_SYNTAX))
                return 0;
        }
        p += p < e && *p == '"'; /* a quoted field's closing quote */
    }
    return 1;
}

/* The first line of [start, end) with content (before a '#' comment):
 * 1 with its bounds and number (1-based), 0 if there is none. */
static int rd_first_content(const char *start, const char *end, const char **s,
                            const char **e, size_t *lineno)
{
    rd_lines L = {start, end, 0};
    while (fdt_rd_next_line(&L, s, e)) {
        *e = fdt_rd_cut_comment(*s, *e);
        if (!fdt_rd_blank(*s, *e)) {
            *lineno = L.lineno;
            return 1;
        }
    }
    return 0;
}

/* Fields of the line s..e (a stray comma's empty field not counted: the
 * parse reports it). */
static size_t rd_count_fields(const char *s, const char *e, char sep)
{
    rd_fields f = {s, e, sep, 0};
    size_t k = 0;
    const char *ts;
    size_t tl;
    int r;
    while ((r = rd_next_field_q(&f, &ts, &tl)) != 0)
        if (r > 0)
            k++;
        else if (r == -2)
            return k + 1; /* the parse refuses the line */
        else
            f.p++;
    return k;
}

/* The separators seen on a line, for the guard against decimal commas
 * (rd_ctx.sep_guard): a blank-only separator between two fields, and a
 * comma with a digit right before and after it ("0,5"). */
enum { RD_SEEN_BLANK = 1, RD_SEEN_TIGHT_COMMA = 2 };

/* What the separator [p0, p) between two fields was: its RD_SEEN_* bit. */
static inline int rd_sep_kind(const char *p0, const char *p)
{
    if (p - p0 == 1) /* the common case: one blank or one comma */
        return *p0 != ',' ? RD_SEEN_BLANK
                          : rd_is_digit(p0[-1]) && rd_is_digit(*p) ? RD_SEEN_TIGHT_COMMA : 0;
    for (; p0 < p; p0++)
        if (*p0 == ',')
            return 0;
    return RD_SEEN_BLANK;
}

/* The refusal of a field that is no number because of its separators or
 * decimal mark: a ';' (no ';' delimiter named), or a ',' inside a field
 * (',' is not the delimiter and no decimal comma was named). s..e: the
 * field's line. 0 when the field has neither, and the caller words the
 * usual error. */
static int rd_sep_fail(const rd_ctx *c, size_t line, const char *ts, size_t tl,
                       const char *s, const char *e)
{
    char q[RD_QUOTE_CAP];
    int semi = c->sep != ';' && memchr(ts, ';', tl) != NULL;
    int comma = !c->decimal_comma && c->sep != ',' && memchr(ts, ',', tl) != NULL;
    if (semi)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: fields separated by ';' in %s: read the file with "
                           "--delimiter ';'%s",
                           line, fdt_rd_quote(q, ts, tl),
                           memchr(s, ',', (size_t)(e - s)) != NULL ? " --decimal-comma (',' is then "
                                                         "the decimal mark)" : "");
    if (comma)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: a comma inside the number %s: pass --decimal-comma if ',' "
                           "is its decimal mark",
                           line, fdt_rd_quote(q, ts, tl));
    return 0;
}

/* The refusal of field ts[0, tl) of line s..e, which did not read as a
 * number (st: the parse's status): its separator's or decimal mark's
 * when that is why (rd_sep_fail), else the number's. */
static int rd_field_fail(const rd_ctx *c, size_t line, int st, const char *ts, size_t tl,
                         const char *s, const char *e)
{
    int rs = st == NUM_SYNTAX ? rd_sep_fail(c, line, ts, tl, s, e) : 0;
    return rs ? rs : fdt_rd_num_fail(c, line, "", st, ts, tl);
}

/* A decimal-comma field ts[0, tl) as a number: the one ',' read as '.'
 * (a '.' in it is refused: 1.000,5 has a thousands separator). */
static int rd_parse_decimal_comma(const char *ts, size_t tl, double *v)
{
    char b[128];
    if (tl >= sizeof b || memchr(ts, '.', tl) != NULL)
        return NUM_SYNTAX;
    memcpy(b, ts, tl);
    char *comma = memchr(b, ',', tl);
    if (comma != NULL) {
        *comma = '.';
        if (memchr(comma + 1, ',', tl - (size_t)(comma + 1 - b)) != NULL)
            return NUM_SYNTAX;
    }
    return fdt_rd_parse_real(b, tl, v, 1);
}

/* The lines in [start, end) (end: the input's end or just after a '\n')
 * appended to pb; line numbers count from line0 + 1. Every line must hold
 * ncols fields (the first point line's count); x, y, z are columns
 * c->col[] and the others are skipped unread. Every line is parsed on its
 * own: nothing carries from one line to the next, which is what lets
 * rd_xyz_block cut a block. */
static int rd_read_xyz_lines(const rd_ctx *c, const char *start, const char *end, size_t line0,
                             size_t ncols, rd_points *pb, size_t *lines)
{
    /* A guess from typical line lengths; the array doubles as needed. */
    size_t guess = (size_t)(end - start) / 24 + 16;
    if (guess > RD_MAX_POINTS - pb->n) /* the growth below checks the limit */
        guess = (size_t)RD_MAX_POINTS - pb->n;
    if (!pb->fixed && fdt_rd_points_room(pb, guess) != 0)
        return fdt_rd_fail(c, FDT_IO_ENOMEM, ": out of memory");
    const size_t c0 = (size_t)c->col[0], c1 = (size_t)c->col[1], c2 = (size_t)c->col[2];
    size_t need = (c0 > c1 ? c0 : c1);
    need = (need > c2 ? need : c2) + 1;
    rd_lines L = {start, end, line0};
    const char *s, *e;
    while (fdt_rd_next_line(&L, &s, &e)) {
        if ((L.lineno & (RD_PROGRESS_EVERY - 1)) == 0)
            fdt_rd_progress(c, (size_t)(L.p - start));
        rd_fields f = {s, fdt_rd_cut_comment(s, e), c->sep, 0};
        double v[3];
        size_t k = 0;
        const char *ts = NULL;
        size_t tl = 0; /* both set by fdt_rd_next_field before any use */
        int r, seen = 0;
        for (;;) {
            const char *p0 = f.p;
            if ((r = fdt_rd_skip_sep(&f)) == 0)
                break;
            if (r < 0)
                return fdt_rd_fail(c, FDT_IO_EFORMAT, ":%zu: empty field (stray %s)", L.lineno,
                                   c->sep == ';' ? "semicolon" : "comma");
            /* A line of "0,5 1,25 2" read with ',' as the separator would
             * be other numbers: refused unless a delimiter was named. */
            if (c->sep_guard && k > 0 &&
                (seen |= rd_sep_kind(p0, f.p)) == (RD_SEEN_BLANK | RD_SEEN_TIGHT_COMMA))
                return fdt_rd_fail(c, FDT_IO_EFORMAT,
                                   ":%zu: commas between digits and blanks between fields: "
                                   "pass --decimal-comma if ',' is the decimal mark, "
                                   "--delimiter ',' if commas separate fields",
                                   L.lineno);
            int which = k == c0 ? 0 : k == c1 ? 1 : k == c2 ? 2 : -1;
            if (*f.p == '"') {
                /* quoted: the text between the quotes is the field */
                if ((r = rd_quoted(&f, &ts, &tl)) <= 0) {
                    if (r == 0)
                        tl = (size_t)(f.e - (ts = f.p));
                    return rd_quote_fail(c, L.lineno, r, ts, tl);
                }
                if (which >= 0) {
                    int st = c->decimal_comma ? rd_parse_decimal_comma(ts, tl, &v[which])
                                              : fdt_rd_parse_real(ts, tl, &v[which], 1);
                    if (st == NUM_SYNTAX && c->sep == ',' && memchr(ts, ',', tl) != NULL) {
                        char q[RD_QUOTE_CAP];
                        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                                           ":%zu: a comma inside the quoted number %s: a decimal "
                                           "comma is read only with another delimiter between "
                                           "fields (--decimal-comma --delimiter ';' or ' ')",
                                           L.lineno, fdt_rd_quote(q, ts, tl));
                    }
                    if (st != NUM_OK)
                        return rd_field_fail(c, L.lineno, st, ts, tl, s, e);
                }
                k++;
                continue;
            }
            if (which < 0) {
                /* not a coordinate: skipped, only counted */
                fdt_rd_next_field(&f, &ts, &tl);
                k++;
                continue;
            }
            if (c->decimal_comma) {
                fdt_rd_next_field(&f, &ts, &tl);
                int st = rd_parse_decimal_comma(ts, tl, &v[which]);
                if (st != NUM_OK)
                    return rd_field_fail(c, L.lineno, st, ts, tl, s, e);
                k++;
                continue;
            }
            /* Scan and convert in one pass; the field is a number only if
             * a separator follows the literal. */
            size_t used = 0;
            ts = f.p;
            int st = fdt_rd_scan_real(ts, (size_t)(f.e - ts), &v[which], 1, 0, &used);
            if (!fdt_rd_is_sep(&f, ts + used)) {
                fdt_rd_next_field(&f, &ts, &tl);
                st = fdt_rd_parse_real(ts, tl, &v[which], 1);
                if (st == NUM_OK) /* cannot happen: the scan stopped early */
                    st = NUM_SYNTAX;
                return rd_field_fail(c, L.lineno, st, ts, tl, s, e);
            }
            if (st != NUM_OK)
                return fdt_rd_num_fail(c, L.lineno, "", st, ts, used);
            f.p = ts + used;
            f.n++;
            k++;
        }
        if (k == 0)
            continue; /* blank or comment line */
        if (k < need && c->custom_cols)
            return fdt_rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: columns %d,%d,%d need %zu fields, found %zu", L.lineno,
                               c->col[0] + 1, c->col[1] + 1, c->col[2] + 1, need, k);
        if (k < 3 || (k != ncols && ncols == 3))
            return fdt_rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: expected 3 numbers, found %zu", L.lineno, k);
        if (k != ncols)
            return fdt_rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: expected %zu columns as on the first line, found %zu",
                               L.lineno, ncols, k);
        if (pb->n == pb->cap) {
            if (pb->n >= RD_MAX_POINTS)
                return fdt_rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: more than %lld points", L.lineno,
                               (long long)RD_MAX_POINTS);
            size_t cap = pb->cap * 2;
            if (cap > RD_MAX_POINTS)
                cap = (size_t)RD_MAX_POINTS;
            if (fdt_rd_points_reserve(pb, cap) != 0)
                return fdt_rd_fail(c, FDT_IO_ENOMEM,
                               ":%zu: out of memory after %zu points",
                               L.lineno, pb->n);
        }
        memcpy(pb->xyz + 3 * pb->n, v, sizeof v);
        pb->n++;
    }
    if (lines != NULL)
        *lines = L.lineno - line0;
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
    size_t lines; /* line ends (pass 1) */
    rd_points pb; /* its place in the joint array (pass 2) */
    size_t ncols; /* fields a line (the file's first point line's) */
    int pass, rc;
} rd_slice;

/* Lines of [s, e) with a byte before their comment that is not a blank:
 * the lines rd_read_xyz_lines turns into points (or refuses); *lines:
 * the line ends among them. */
static size_t rd_count_content_lines(const char *s, const char *e, size_t *lines)
{
    size_t k = 0, nl_count = 0;
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
        nl_count += nl != NULL;
        s = le + 1;
    }
    *lines = nl_count;
    return k;
}

static void *rd_slice_run(void *arg)
{
    rd_slice *sl = arg;
    if (sl->pass == 0) {
        sl->count = rd_count_content_lines(sl->start, sl->end, &sl->lines);
    } else {
        /* line numbers only matter in messages, which slices do not give */
        sl->rc = rd_read_xyz_lines(&sl->c, sl->start, sl->end, 0, sl->ncols, &sl->pb, NULL);
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
        made[t] = fdt_spawn(&tid[t], 0, rd_slice_run, &sl[t]) == 0;
    rd_slice_run(&sl[0]);
    for (size_t t = 1; t < T; t++) {
        if (made[t])
            pthread_join(tid[t], NULL);
        else
            rd_slice_run(&sl[t]);
    }
}

/*
 * The complete lines [start, end) of a block (end: just after a '\n', or
 * the input's end), whose first line is line line0 + 1, appended to pb on
 * up to c->threads threads; *lines: the line ends among them. A block's
 * slices see no messages: when one fails, the block is parsed again on the
 * calling thread, which words its first error exactly as a one-thread read
 * does (every block before it was read without error).
 */
static int rd_xyz_block(const rd_ctx *c, const char *start, const char *end, size_t line0,
                        size_t ncols, rd_points *pb, size_t *lines)
{
    size_t len = (size_t)(end - start);
    size_t min_slice = c->min_slice ? c->min_slice : RD_MIN_SLICE;
    size_t T = c->threads > 1 ? (size_t)c->threads : 1;
    if (T > RD_SLICES_MAX)
        T = RD_SLICES_MAX;
    if (T > len / min_slice)
        T = len / min_slice;
    if (T < 2)
        return rd_read_xyz_lines(c, start, end, line0, ncols, pb, lines);

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
        sl[t].c.progress = NULL; /* the block's driver reports */
        sl[t].ncols = ncols;
        sl[t].start = cut;
        sl[t].end = stop;
        cut = stop;
    }
    rd_slices_pass(sl, T, 0);
    size_t total = 0, nls = 0;
    for (size_t t = 0; t < T; t++) {
        total += sl[t].count;
        nls += sl[t].lines;
    }
    if (total == 0 || fdt_rd_points_room(pb, total) != 0) /* the one-thread read words it */
        return rd_read_xyz_lines(c, start, end, line0, ncols, pb, lines);
    for (size_t t = 0, at = pb->n; t < T; t++) {
        sl[t].pb = (rd_points){pb->xyz + 3 * at, 0, sl[t].count, 1};
        at += sl[t].count;
    }
    rd_slices_pass(sl, T, 1);
    for (size_t t = 0; t < T; t++)
        if (sl[t].rc != FDT_IO_OK)
            return rd_read_xyz_lines(c, start, end, line0, ncols, pb, lines);
    pb->n += total;
    *lines = nls;
    return FDT_IO_OK;
}

/* Line ends in [s, e). */
static size_t rd_count_newlines(const char *s, const char *e)
{
    size_t k = 0;
    for (const char *nl; s < e && (nl = memchr(s, '\n', (size_t)(e - s))) != NULL; s = nl + 1)
        k++;
    return k;
}

/* The last '\n' of [s, e), or NULL. */
static const char *rd_last_newline(const char *s, const char *e)
{
    while (e > s)
        if (*--e == '\n')
            return e;
    return NULL;
}

/*
 * The stream of c->src from the state a whole file starts in (whole: look
 * for a byte order mark and the header, refuse an empty input) or, for a
 * range of a file (src/io/read/reader.c, fdt_rd_text_range), from the middle of
 * the point lines: no byte order mark, no header, every line with ncols0
 * fields, the first line numbered first_line + 1. *lines_out (may be NULL):
 * the line ends read.
 */
static int rd_xyz_stream_from(rd_ctx *c, rd_points *pb, int whole, size_t ncols0, size_t line0,
                              size_t *lines_out);

int fdt_rd_stream_xyz(rd_ctx *c, rd_points *pb)
{
    return rd_xyz_stream_from(c, pb, 1, 3, 0, NULL);
}

int fdt_rd_stream_xyz_range(rd_ctx *c, rd_points *pb, size_t ncols, size_t line0, size_t *lines)
{
    return rd_xyz_stream_from(c, pb, 0, ncols, line0, lines);
}

static int rd_xyz_stream_from(rd_ctx *c, rd_points *pb, int whole, size_t ncols0,
                              size_t first_line, size_t *lines_out)
{
    size_t T = c->threads > 1 ? (size_t)c->threads : 1;
    if (T > RD_SLICES_MAX)
        T = RD_SLICES_MAX;
    size_t chunk = c->chunk ? c->chunk : RD_CHUNK;
    if (c->chunk == 0 && T > 2 && chunk / 2 / T < RD_MIN_SLICE)
        chunk = 2 * T * RD_MIN_SLICE; /* two slices a thread of a megabyte each */
    if (chunk < 4)
        chunk = 4; /* room to tell a byte order mark */
    /* a known size + 1: the read that finds the end fits */
    size_t cap = fdt_rd_first_cap(c, chunk, c->size < chunk ? c->size + 1 : chunk);
    if (cap < 4)
        cap = 4;
    char *buf = fdt_mem_alloc_huge(cap + 1, 1, 0); /* each read fills it */
    if (buf == NULL)
        return fdt_rd_fail(c, FDT_IO_ENOMEM, ": out of memory");
    /* Lines before the first content line are blank or comments; the
     * first content line may be a header (rd_is_header), skipped; the
     * first point line then sets the column count of every line. */
    enum { FIND_FIRST, FIND_COLUMNS, PARSE } st = whole ? FIND_FIRST : PARSE;
    size_t ncols = ncols0;
    size_t len = 0;     /* bytes in buf: a carried partial line, then new ones */
    size_t done = 0;    /* input bytes before buf[0] */
    size_t lineno = first_line; /* lines before buf[0] */
    int rc = FDT_IO_OK, first = whole;
    size_t bom = 0; /* bytes of a byte order mark at buf[0], until parsed */
    for (;;) {
        ptrdiff_t r = fdt_rd_src_read(c, buf + len, cap - len);
        if (r < 0) {
            rc = FDT_IO_EOPEN;
            break;
        }
        len += (size_t)r;
        int eof = c->src->eof;
        buf[len] = '\0';
        if (first) {
            if (len == 0) {
                rc = fdt_rd_fail(c, FDT_IO_EFORMAT, ": no points (empty file)");
                break;
            }
            /* a UTF-8 byte order mark, as some Windows tools write */
            if (len >= 3 && memcmp(buf, "\xef\xbb\xbf", 3) == 0)
                bom = 3;
            else if (len < 3 && !eof && memcmp(buf, "\xef\xbb\xbf", len) == 0)
                continue; /* cannot tell yet */
            first = 0;
        }
        const char *s = buf + bom;
        const char *end = buf + len;
        if (!eof) {
            const char *nl = rd_last_newline(s, end);
            if (nl == NULL || (len == cap && cap < chunk)) {
                /* one line longer than the buffer, or a pipe that fills
                 * its first buffer: make room */
                if (len == cap) {
                    if (cap > (SIZE_MAX - 1) / 2) {
                        rc = fdt_rd_fail(c, FDT_IO_ENOMEM, ": out of memory");
                        break;
                    }
                    size_t ncap = nl != NULL && 2 * cap > chunk ? chunk : 2 * cap;
                    char *nb = realloc(buf, ncap + 1);
                    if (nb == NULL) {
                        rc = fdt_rd_fail(c, FDT_IO_ENOMEM, ": out of memory");
                        break;
                    }
                    buf = nb;
                    cap = ncap;
                }
                continue;
            }
            end = nl + 1;
        }
        size_t line0 = lineno;
        const char *fs, *fe;
        size_t fl;
        if (st == FIND_FIRST && rd_first_content(s, end, &fs, &fe, &fl)) {
            if (rd_is_header(fs, fe, c->sep, c->decimal_comma)) {
                const char *nl = memchr(fe, '\n', (size_t)(end - fe));
                line0 += fl;
                s = nl != NULL ? nl + 1 : end;
                st = FIND_COLUMNS;
            } else {
                ncols = rd_count_fields(fs, fe, c->sep);
                st = PARSE;
            }
        }
        if (st == FIND_COLUMNS && rd_first_content(s, end, &fs, &fe, &fl)) {
            ncols = rd_count_fields(fs, fe, c->sep);
            st = PARSE;
        }
        size_t lines = 0;
        if (st == PARSE) {
            /* progress is reported by block, below: a block's own reports
             * would count from its start */
            rd_ctx bc = *c;
            bc.progress = NULL;
            rc = rd_xyz_block(&bc, s, end, line0, ncols, pb, &lines);
            if (rc != FDT_IO_OK)
                break;
        } else {
            lines = rd_count_newlines(s, end); /* blank lines, comments */
        }
        lineno = line0 + lines;
        size_t used = (size_t)(end - buf);
        done += used;
        fdt_rd_progress(c, done);
        if (eof)
            break;
        memmove(buf, end, len - used);
        len -= used;
        bom = 0;
    }
    free(buf);
    if (lines_out != NULL)
        *lines_out = lineno - first_line;
    return rc;
}

int fdt_rd_xyz_head(const char *buf, size_t len, int eof, char sep, fdt_rd_head *h)
{
    size_t bom = len >= 3 && memcmp(buf, "\xef\xbb\xbf", 3) == 0 ? 3 : 0;
    if (!eof && len < 3 && memcmp(buf, "\xef\xbb\xbf", len) == 0)
        return 0; /* cannot tell a byte order mark yet */
    const char *s = buf + bom, *end = buf + len;
    if (!eof) {
        /* only complete lines: the last one may go on */
        const char *nl = rd_last_newline(s, end);
        end = nl != NULL ? nl + 1 : s;
    }
    memset(h, 0, sizeof *h);
    h->body = bom;
    const char *fs, *fe;
    size_t fl;
    if (!rd_first_content(s, end, &fs, &fe, &fl))
        return eof; /* no content: no points at all, or more to read */
    if (!rd_is_header(fs, fe, sep, 0)) {
        h->ncols = rd_count_fields(fs, fe, sep);
        return 1;
    }
    /* a header: the points start on the line after it, and the next
     * content line sets the column count (as fdt_rd_stream_xyz) */
    const char *nl = memchr(fe, '\n', (size_t)(end - fe));
    const char *after = nl != NULL ? nl + 1 : end;
    h->body = (size_t)(after - buf);
    h->body_line = fl;
    if (rd_first_content(after, end, &fs, &fe, &fl)) {
        h->ncols = rd_count_fields(fs, fe, sep);
        return 1;
    }
    return eof;
}
