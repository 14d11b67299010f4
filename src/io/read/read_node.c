/*
 * TetGen .node point files (src/io/read/reader.h).
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "io/read/read_common.h"

#include <stdint.h>
#include <string.h>

/* ------------------------------------------------------------------ */
/* TetGen .node                                                       */
/* ------------------------------------------------------------------ */

/* The header line's fields and where it is. */
typedef struct node_hdr {
    uint64_t npts, dim, nattr, marker;
    size_t line;
} node_hdr;

/* Reads the header, the first line with a field, into *h. */
static int node_read_header(const rd_ctx *c, rd_lines *L, node_hdr *h)
{
    const char *s, *e, *ts;
    size_t tl;
    char q[RD_QUOTE_CAP];
    int r;

    /* Header: <#points> [<dim> [<#attributes> [<markers>]]]; as in TetGen
     * the trailing fields may be left out (3, 0, 0). */
    *h = (node_hdr){.npts = 0, .dim = 3, .nattr = 0, .marker = 0, .line = 0};
    uint64_t *hv[4] = {&h->npts, &h->dim, &h->nattr, &h->marker};
    while (h->line == 0 && fdt_rd_next_line(L, &s, &e)) {
        rd_fields f = {s, fdt_rd_cut_comment(s, e), ',', 0};
        size_t k = 0;
        while ((r = fdt_rd_next_field(&f, &ts, &tl)) != 0) {
            if (r < 0)
                return fdt_rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: empty field (stray comma)", L->lineno);
            if (k >= 4)
                return fdt_rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: header has more than 4 fields "
                               "(#points dim #attributes markers)",
                               L->lineno);
            int st = fdt_rd_parse_count(ts, tl, hv[k]);
            if (st == NUM_OVERFLOW)
                return fdt_rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: header field %s is too large", L->lineno,
                               fdt_rd_quote(q, ts, tl));
            if (st != NUM_OK)
                return fdt_rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: header field %s is not a non-negative "
                               "integer",
                               L->lineno, fdt_rd_quote(q, ts, tl));
            k++;
        }
        if (k > 0)
            h->line = L->lineno;
    }
    if (h->line == 0)
        return fdt_rd_fail(c, FDT_IO_EFORMAT, ": no points (no header line)");
    return FDT_IO_OK;
}

/* Checks the header's values against what is supported and against the
 * rem bytes after it, then reserves its points. */
static int node_check_header(const rd_ctx *c, const node_hdr *h, size_t rem,
                             rd_points *pb)
{
    uint64_t npts = h->npts, nattr = h->nattr, marker = h->marker;
    size_t hline = h->line;
    if (h->dim != 3)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: dimension is %llu, only 3 is supported", hline,
                       (unsigned long long)h->dim);
    if (marker > 1)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: boundary marker flag is %llu, expected 0 or 1",
                       hline, (unsigned long long)marker);
    if (npts == 0)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ": no points (the header on line %zu declares 0)",
                       hline);

    /* Every data line needs at least 2 bytes per field (a digit and a
     * separator or newline), the last line's newline excepted. */
    uint64_t maxpts = 0;
    if (nattr <= (uint64_t)rem) {
        uint64_t per = 2 * (4 + nattr + marker);
        maxpts = ((uint64_t)rem + 1) / per;
    }
    if (npts > maxpts)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: header declares %llu points but the %zu bytes "
                       "after it can hold at most %llu: refused",
                       hline, (unsigned long long)npts, rem,
                       (unsigned long long)maxpts);
    if (npts > RD_MAX_POINTS)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: header declares %llu points, more than the "
                       "%lld supported",
                       hline, (unsigned long long)npts,
                       (long long)RD_MAX_POINTS);
    if (fdt_rd_points_reserve(pb, (size_t)npts) != 0)
        return fdt_rd_fail(c, FDT_IO_ENOMEM, ": out of memory for %llu points",
                       (unsigned long long)npts);
    return FDT_IO_OK;
}

/* Parses the fields f of the data line `line` (index, x, y, z, attributes,
 * marker) and appends its point to pb; *base is the first index, set by
 * the first point. */
static int node_read_point(const rd_ctx *c, const node_hdr *h, size_t line,
                           rd_fields *f, int64_t *base, rd_points *pb)
{
    const char *ts;
    size_t tl;
    char q[RD_QUOTE_CAP];
    int r;
    uint64_t nattr = h->nattr, marker = h->marker;
    uint64_t nfields = 4 + nattr + marker;
    double v[3];
    uint64_t k = 0;
    while ((r = fdt_rd_next_field(f, &ts, &tl)) != 0) {
        if (r < 0)
            return fdt_rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: empty field (stray comma)", line);
        int st;
        if (k == 0) {
            int64_t idx;
            st = fdt_rd_parse_int(ts, tl, &idx);
            if (st != NUM_OK)
                return fdt_rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: point index %s is not an integer",
                               line, fdt_rd_quote(q, ts, tl));
            if (pb->n == 0 && idx != 0 && idx != 1)
                return fdt_rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: first point index is %lld, "
                               "expected 0 or 1",
                               line, (long long)idx);
            if (pb->n == 0)
                *base = idx;
            else if (idx != *base + (int64_t)pb->n)
                return fdt_rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: point index %lld, expected %lld "
                               "(indices must be consecutive)",
                               line, (long long)idx,
                               (long long)(*base + (int64_t)pb->n));
        } else if (k <= 3) {
            st = fdt_rd_parse_real(ts, tl, &v[k - 1], 1);
            if (st != NUM_OK)
                return fdt_rd_num_fail(c, line, "", st, ts, tl);
        } else if (k < 4 + nattr) {
            double dummy;
            st = fdt_rd_parse_real(ts, tl, &dummy, 0);
            if (st != NUM_OK && st != NUM_NONFINITE)
                return fdt_rd_num_fail(c, line, "attribute", st, ts, tl);
        } else if (k < nfields) {
            int64_t m;
            if (fdt_rd_parse_int(ts, tl, &m) != NUM_OK)
                return fdt_rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: boundary marker %s is not an "
                               "integer",
                               line, fdt_rd_quote(q, ts, tl));
        }
        k++;
    }
    if (k != nfields)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: expected %llu fields (index, x, y, z, %llu "
                       "attributes, %llu markers), found %llu",
                       line, (unsigned long long)nfields,
                       (unsigned long long)nattr,
                       (unsigned long long)marker, (unsigned long long)k);
    memcpy(pb->xyz + 3 * pb->n, v, sizeof v);
    pb->n++;
    return FDT_IO_OK;
}

int fdt_rd_read_node(const rd_ctx *c, const char *start, rd_points *pb)
{
    rd_lines L = {start, c->buf + c->size, 0};
    const char *s, *e;
    node_hdr h;
    int rc = node_read_header(c, &L, &h);
    if (rc == FDT_IO_OK)
        rc = node_check_header(c, &h, (size_t)(L.end - L.p), pb);
    if (rc != FDT_IO_OK)
        return rc;

    int64_t base = 0;
    while (fdt_rd_next_line(&L, &s, &e)) {
        if ((L.lineno & (RD_PROGRESS_EVERY - 1)) == 0)
            fdt_rd_progress(c, (size_t)(L.p - c->buf));
        rd_fields f = {s, fdt_rd_cut_comment(s, e), ',', 0};
        if (fdt_rd_blank(f.p, f.e))
            continue;
        if (pb->n == h.npts)
            return fdt_rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: extra data after the %llu points declared "
                           "on line %zu",
                           L.lineno, (unsigned long long)h.npts, h.line);
        rc = node_read_point(c, &h, L.lineno, &f, &base, pb);
        if (rc != FDT_IO_OK)
            return rc;
    }
    if (pb->n != h.npts)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: file ends after %zu of the %llu points declared "
                       "on line %zu",
                       L.lineno, pb->n, (unsigned long long)h.npts, h.line);
    return FDT_IO_OK;
}
