/*
 * .xyz / .txt point files (src/reader.h): x y z per line; parsed in slices
 * on several threads for large files.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "read_common.h"

#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------------ */
/* .xyz / .txt                                                        */
/* ------------------------------------------------------------------ */

/* Whether the first content line s..e is a header: printable ASCII and
 * no field (between blanks and commas) that reads as a number, finite or
 * not, so that a first line of data, or of binary garbage, is never
 * skipped unseen. */
static int rd_is_header(const char *s, const char *e)
{
    for (const char *p = s; p < e; p++) {
        unsigned char ch = (unsigned char)*p;
        if (!(ch >= 0x20 && ch < 0x7f) && ch != '\t' && ch != '\r')
            return 0;
    }
    const char *p = s;
    while (p < e) {
        while (p < e && (rd_is_space(*p) || *p == ','))
            p++;
        const char *t = p;
        while (p < e && !rd_is_space(*p) && *p != ',')
            p++;
        if (p > t) {
            double v;
            if (fdt_rd_parse_real(t, (size_t)(p - t), &v, 0) != NUM_SYNTAX)
                return 0;
        }
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
static size_t rd_count_fields(const char *s, const char *e)
{
    rd_fields f = {s, e, 1, 0};
    size_t k = 0;
    const char *ts;
    size_t tl;
    int r;
    while ((r = fdt_rd_next_field(&f, &ts, &tl)) != 0)
        if (r > 0)
            k++;
        else
            f.p++;
    return k;
}

/* The lines in [start, end) (end: c->buf + c->size or just after a '\n')
 * appended to pb; line numbers count from line0 + 1. Every line must hold
 * ncols fields (the first point line's count); x, y, z are columns
 * c->col[] and the others are skipped unread. Every line is parsed on its
 * own: nothing carries from one line to the next, which is what lets
 * fdt_rd_read_xyz cut the file. */
static int rd_read_xyz_lines(const rd_ctx *c, const char *start, const char *end, size_t line0,
                             size_t ncols, rd_points *pb)
{
    /* A guess from typical line lengths; the array doubles as needed. */
    size_t guess = (size_t)(end - start) / 24 + 16;
    if (guess > RD_MAX_POINTS) /* the growth below checks the limit at cap */
        guess = (size_t)RD_MAX_POINTS;
    if (!pb->fixed && fdt_rd_points_reserve(pb, guess) != 0)
        return fdt_rd_fail(c, FDT_IO_ENOMEM, ": out of memory");
    const size_t c0 = (size_t)c->col[0], c1 = (size_t)c->col[1], c2 = (size_t)c->col[2];
    size_t need = (c0 > c1 ? c0 : c1);
    need = (need > c2 ? need : c2) + 1;
    rd_lines L = {start, end, line0};
    const char *s, *e;
    while (fdt_rd_next_line(&L, &s, &e)) {
        if ((L.lineno & (RD_PROGRESS_EVERY - 1)) == 0)
            fdt_rd_progress(c, (size_t)(L.p - start));
        rd_fields f = {s, fdt_rd_cut_comment(s, e), 1, 0};
        double v[3];
        size_t k = 0;
        const char *ts;
        size_t tl = 0; /* set by fdt_rd_next_field before any use */
        int r;
        while ((r = fdt_rd_skip_sep(&f)) != 0) {
            if (r < 0)
                return fdt_rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: empty field (stray comma)", L.lineno);
            int which = k == c0 ? 0 : k == c1 ? 1 : k == c2 ? 2 : -1;
            if (which < 0) {
                /* not a coordinate: skipped, only counted */
                fdt_rd_next_field(&f, &ts, &tl);
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
                return fdt_rd_num_fail(c, L.lineno, "", st, ts, tl);
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
    size_t ncols; /* fields a line (the file's first point line's) */
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
        /* line numbers only matter in messages, which slices do not give */
        sl->rc = rd_read_xyz_lines(&sl->c, sl->start, sl->end, 0, sl->ncols, &sl->pb);
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

int fdt_rd_read_xyz(const rd_ctx *c, const char *start, rd_points *pb)
{
    const char *end = c->buf + c->size;
    /* A header line (rd_is_header) is skipped; the first point line then
     * sets the column count of every line, which the slices need before
     * they start. */
    size_t line0 = 0, ncols = 3;
    const char *fs, *fe;
    size_t fl;
    if (rd_first_content(start, end, &fs, &fe, &fl)) {
        if (rd_is_header(fs, fe)) {
            const char *nl = memchr(fe, '\n', (size_t)(end - fe));
            start = nl != NULL ? nl + 1 : end;
            line0 = fl;
            if (!rd_first_content(start, end, &fs, &fe, &fl))
                fs = fe = NULL;
        }
        if (fs != NULL)
            ncols = rd_count_fields(fs, fe);
    }
    size_t len = (size_t)(end - start);
    size_t min_slice = c->min_slice ? c->min_slice : RD_MIN_SLICE;
    size_t T = c->threads > 1 ? (size_t)c->threads : 1;
    if (T > RD_SLICES_MAX)
        T = RD_SLICES_MAX;
    if (T > len / min_slice)
        T = len / min_slice;
    if (T < 2)
        return rd_read_xyz_lines(c, start, end, line0, ncols, pb);

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
        /* Progress only from the calling thread's slice 0, scaled to the
         * whole: the slices are of about equal size. */
        sl[t].c.progress_scale = T;
        if (t > 0)
            sl[t].c.progress = NULL;
        sl[t].ncols = ncols;
        sl[t].start = cut;
        sl[t].end = stop;
        cut = stop;
    }
    rd_slices_pass(sl, T, 0);
    size_t total = 0;
    for (size_t t = 0; t < T; t++)
        total += sl[t].count;
    if (total == 0 || total > RD_MAX_POINTS) /* the one-thread read words it */
        return rd_read_xyz_lines(c, start, end, line0, ncols, pb);
    rd_points all = {NULL, 0, 0, 0};
    if (fdt_rd_points_reserve(&all, total) != 0)
        return rd_read_xyz_lines(c, start, end, line0, ncols, pb); /* which may need less */
    for (size_t t = 0, at = 0; t < T; t++) {
        sl[t].pb = (rd_points){all.xyz + 3 * at, 0, sl[t].count, 1};
        at += sl[t].count;
    }
    rd_slices_pass(sl, T, 1);
    for (size_t t = 0; t < T; t++)
        if (sl[t].rc != FDT_IO_OK) {
            free(all.xyz);
            return rd_read_xyz_lines(c, start, end, line0, ncols, pb);
        }
    all.n = total;
    free(pb->xyz);
    *pb = all;
    return FDT_IO_OK;
}
