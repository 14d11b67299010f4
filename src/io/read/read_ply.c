/*
 * PLY point files, ASCII and binary (src/io/read/reader.h). The header is read
 * line by line from the input; a binary body is then streamed, its x, y, z
 * decoded into the points array and everything else skipped, through a
 * buffer of rd_ctx.chunk bytes (the common layout, three little-endian
 * doubles a vertex, is read straight into the array); an ASCII body is
 * loaded whole and parsed as before.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "io/read/read_common.h"
#include "io/read/reader.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#ifndef O_CLOEXEC
#define O_CLOEXEC 0
#endif

_Static_assert(sizeof(float) == 4 && sizeof(double) == 8,
               "binary PLY decoding assumes IEEE binary32/binary64");

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
    int no_end;      /* the lines ran out before end_header */
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
                 fdt_rd_quote(q, el->name, el->name_len),
                 (unsigned long long)i + 1, (unsigned long long)el->count);
    }
    return out;
}

/* A header line's first five words, how many words it has, its number. */
typedef struct ply_line {
    const char *tk[5];
    size_t tn[5];
    size_t nt;
    size_t ln;
} ply_line;

/* An element declared without properties: the error, once the next
 * element or the end of the header shows it. */
static int ply_check_last_props(const rd_ctx *c, const ply_hdr *h)
{
    char q[RD_QUOTE_CAP];
    if (h->n_elems > 0 && h->elems[h->n_elems - 1].n_props == 0)
        return fdt_rd_fail(c, FDT_IO_EFORMAT, ":%zu: element %s has no properties",
                       h->elems[h->n_elems - 1].line,
                       fdt_rd_quote(q, h->elems[h->n_elems - 1].name,
                                h->elems[h->n_elems - 1].name_len));
    return FDT_IO_OK;
}

/* 'format ascii|binary_little_endian|binary_big_endian 1.0' into h->format. */
static int ply_header_format(const rd_ctx *c, ply_hdr *h, const ply_line *w)
{
    const char *const *tk = w->tk;
    const size_t *tn = w->tn;
    size_t nt = w->nt, ln = w->ln;
    if (h->format >= 0)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
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
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: expected 'format ascii|"
                       "binary_little_endian|binary_big_endian 1.0'",
                       ln);
    h->format = fm;
    return FDT_IO_OK;
}

/* 'element NAME COUNT': a new element of h, the vertex one if so named. */
static int ply_header_element(const rd_ctx *c, ply_hdr *h, const ply_line *w)
{
    const char *const *tk = w->tk;
    const size_t *tn = w->tn;
    size_t nt = w->nt, ln = w->ln;
    char q[RD_QUOTE_CAP];
    if (h->format < 0)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: element before the format line", ln);
    if (nt != 3)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: expected 'element NAME COUNT'", ln);
    uint64_t cnt;
    int st = fdt_rd_parse_count(tk[2], tn[2], &cnt);
    if (st == NUM_OVERFLOW)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: element count %s is too large", ln,
                       fdt_rd_quote(q, tk[2], tn[2]));
    if (st != NUM_OK)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: element count %s is not a non-negative "
                       "integer",
                       ln, fdt_rd_quote(q, tk[2], tn[2]));
    int is_vertex = rd_tok_is(tk[1], tn[1], "vertex");
    if (is_vertex && h->vertex != SIZE_MAX)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: second 'vertex' element", ln);
    int rc = ply_check_last_props(c, h);
    if (rc != FDT_IO_OK)
        return rc;
    if (ply_add_elem(h) != 0)
        return fdt_rd_fail(c, FDT_IO_ENOMEM, ": out of memory");
    ply_elem *el = &h->elems[h->n_elems - 1];
    memset(el, 0, sizeof *el);
    el->name = tk[1];
    el->name_len = tn[1];
    el->count = cnt;
    el->first_prop = h->n_props;
    el->line = ln;
    if (is_vertex)
        h->vertex = h->n_elems - 1;
    return FDT_IO_OK;
}

/* 'property TYPE NAME' or 'property list COUNTTYPE ITEMTYPE NAME': a new
 * property of the last element; x, y, z of the vertex element get their
 * roles. */
static int ply_header_property(const rd_ctx *c, ply_hdr *h, const ply_line *w)
{
    const char *const *tk = w->tk;
    const size_t *tn = w->tn;
    size_t nt = w->nt, ln = w->ln;
    char q[RD_QUOTE_CAP];
    if (h->n_elems == 0)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: property before any element", ln);
    ply_prop p = {0, 0, 0, 0};
    const char *name;
    size_t name_len;
    if (nt == 5 && rd_tok_is(tk[1], tn[1], "list")) {
        int ct = ply_type_lookup(tk[2], tn[2]);
        int it = ply_type_lookup(tk[3], tn[3]);
        if (ct < 0 || it < 0)
            return fdt_rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: unknown property type %s",
                           ln, ct < 0 ? fdt_rd_quote(q, tk[2], tn[2])
                                      : fdt_rd_quote(q, tk[3], tn[3]));
        if (ply_is_float(ct))
            return fdt_rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: list length type %s is not an "
                           "integer type",
                           ln, fdt_rd_quote(q, tk[2], tn[2]));
        p.is_list = 1;
        p.count_type = (unsigned char)ct;
        p.type = (unsigned char)it;
        name = tk[4];
        name_len = tn[4];
    } else if (nt == 3) {
        int t = ply_type_lookup(tk[1], tn[1]);
        if (t < 0)
            return fdt_rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: unknown property type %s", ln,
                           fdt_rd_quote(q, tk[1], tn[1]));
        p.type = (unsigned char)t;
        name = tk[2];
        name_len = tn[2];
    } else {
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
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
                return fdt_rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: second vertex property %s", ln,
                               fdt_rd_quote(q, name, name_len));
        if (p.is_list)
            return fdt_rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: vertex property %s is a list", ln,
                           fdt_rd_quote(q, name, name_len));
        p.role = (unsigned char)role;
    }
    if (ply_add_prop(h) != 0)
        return fdt_rd_fail(c, FDT_IO_ENOMEM, ": out of memory");
    h->props[h->n_props - 1] = p;
    el->n_props++;
    if (p.is_list) {
        el->has_list = 1;
        el->min_bytes += ply_size[p.count_type];
    } else {
        el->n_scalar++;
        el->min_bytes += ply_size[p.type];
    }
    return FDT_IO_OK;
}

/* What a complete header must have: a format line, properties in its last
 * element, a vertex element with x, y and z and a nonzero count. */
static int ply_header_complete(const rd_ctx *c, const ply_hdr *h)
{
    char q2[RD_QUOTE_CAP];
    if (h->format < 0)
        return fdt_rd_fail(c, FDT_IO_EFORMAT, ": the header has no format line");
    int rc = ply_check_last_props(c, h);
    if (rc != FDT_IO_OK)
        return rc;
    if (h->vertex == SIZE_MAX)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ": no points (the header has no 'vertex' element)");
    const ply_elem *v = &h->elems[h->vertex];
    int have[4] = {0, 0, 0, 0};
    for (size_t i = 0; i < v->n_props; i++)
        have[h->props[v->first_prop + i].role] = 1;
    for (int k = 1; k <= 3; k++)
        if (!have[k]) {
            char nm[2] = {(char)('x' + k - 1), '\0'};
            return fdt_rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: the vertex element has no %s property",
                           v->line, fdt_rd_quote(q2, nm, 1));
        }
    if (v->count == 0)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ": no points (the vertex element on line %zu has "
                       "count 0)",
                       v->line);
    return FDT_IO_OK;
}

/* The header in c->buf into *h: the 'ply' line, then each line's keyword
 * dispatched to its step, up to end_header; then the checks of the whole. */
static int ply_parse_header(const rd_ctx *c, ply_hdr *h)
{
    rd_lines L = {c->buf, c->buf + c->size, 0};
    const char *s = c->buf, *e = c->buf, *ts;
    size_t tl;
    char q[RD_QUOTE_CAP];

    h->format = -1;
    h->vertex = SIZE_MAX;
    if (fdt_rd_next_line(&L, &s, &e)) {
        rd_fields f = {s, e, 0, 0};
        int r = fdt_rd_next_field(&f, &ts, &tl);
        if (r <= 0 || !rd_tok_is(ts, tl, "ply") || fdt_rd_count_rest(&f) != 0)
            return fdt_rd_fail(c, FDT_IO_EFORMAT,
                           ":1: not a PLY file (the first line is %s, "
                           "expected 'ply')",
                           fdt_rd_quote(q, s, (size_t)(e - s)));
    }
    int ended = 0;
    while (!ended && fdt_rd_next_line(&L, &s, &e)) {
        rd_fields f = {s, e, 0, 0};
        ply_line w = {{0}, {0}, 0, 0};
        const char *const *tk = w.tk;
        const size_t *tn = w.tn;
        while (w.nt < 5 && fdt_rd_next_field(&f, &w.tk[w.nt], &w.tn[w.nt]) > 0)
            w.nt++;
        if (w.nt == 0)
            continue;
        if (rd_tok_is(tk[0], tn[0], "comment") ||
            rd_tok_is(tk[0], tn[0], "obj_info"))
            continue;
        w.nt += fdt_rd_count_rest(&f);
        w.ln = L.lineno;
        int rc;
        if (rd_tok_is(tk[0], tn[0], "format")) {
            rc = ply_header_format(c, h, &w);
        } else if (rd_tok_is(tk[0], tn[0], "element")) {
            rc = ply_header_element(c, h, &w);
        } else if (rd_tok_is(tk[0], tn[0], "property")) {
            rc = ply_header_property(c, h, &w);
        } else if (rd_tok_is(tk[0], tn[0], "end_header")) {
            if (w.nt != 1)
                return fdt_rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: unexpected text after end_header", w.ln);
            rc = FDT_IO_OK;
            ended = 1;
        } else {
            /* a number here is data: the end_header line is missing */
            int data = rd_is_digit(tk[0][0]) || tk[0][0] == '-' ||
                       tk[0][0] == '+' || tk[0][0] == '.';
            return fdt_rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: unknown header keyword %s%s", w.ln,
                           fdt_rd_quote(q, tk[0], tn[0]),
                           data ? " (no end_header line before the data?)"
                                : "");
        }
        if (rc != FDT_IO_OK)
            return rc;
    }
    if (!ended) {
        h->no_end = 1;
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: the header has no end_header line", L.lineno);
    }
    h->data_off = (size_t)(L.p - c->buf);
    h->data_line = L.lineno;
    return ply_header_complete(c, h);
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

static int ply_check_count(const rd_ctx *c, const ply_elem *el,
                           rd_points *pb)
{
    if (el->count > RD_MAX_POINTS)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: the vertex element declares %llu points, more "
                       "than the %lld supported",
                       el->line, (unsigned long long)el->count,
                       (long long)RD_MAX_POINTS);
    if (fdt_rd_points_reserve(pb, (size_t)el->count) != 0)
        return fdt_rd_fail(c, FDT_IO_ENOMEM, ": out of memory for %llu points",
                       (unsigned long long)el->count);
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
            if (fdt_rd_next_field(&f, &ts, &tl) <= 0)
                goto too_few;
            found++;
            int64_t len;
            if (fdt_rd_parse_int(ts, tl, &len) != NUM_OK || len < 0 ||
                len > ply_max[p->count_type])
                return fdt_rd_fail(c, FDT_IO_EFORMAT,
                               ":%zu: %s: list length %s is not a valid %s",
                               line, ply_item_label(lab, sizeof lab, h, el,
                                                    idx),
                               fdt_rd_quote(q, ts, tl), "count");
            nvals = (uint64_t)len;
        }
        for (uint64_t j = 0; j < nvals; j++) {
            if (fdt_rd_next_field(&f, &ts, &tl) <= 0)
                goto too_few;
            found++;
            double v = 0.0;
            int st;
            if (ply_is_float(type)) {
                st = fdt_rd_parse_real(ts, tl, &v, p->role != 0);
                /* ignored properties may hold nan/inf (normals often do) */
                if (p->role == 0 && st == NUM_NONFINITE)
                    st = NUM_OK;
            } else {
                int64_t iv;
                st = fdt_rd_parse_int(ts, tl, &iv);
                if (st == NUM_OK && (iv < ply_min[type] || iv > ply_max[type]))
                    st = NUM_OVERFLOW;
                if (st != NUM_OK)
                    return fdt_rd_fail(c, FDT_IO_EFORMAT,
                                   ":%zu: %s: %s is not a valid %s", line,
                                   ply_item_label(lab, sizeof lab, h, el,
                                                  idx),
                                   fdt_rd_quote(q, ts, tl),
                                   ply_type_names[type].name);
                v = (double)iv;
            }
            if (st != NUM_OK)
                return fdt_rd_num_fail(c, line,
                                   ply_item_label(lab, sizeof lab, h, el,
                                                  idx),
                                   st, ts, tl);
            if (p->role && dst != NULL)
                dst[p->role - 1] = v;
        }
    }
    if (fdt_rd_next_field(&f, &ts, &tl) > 0) {
        size_t extra = 1 + fdt_rd_count_rest(&f);
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: %s: expected %zu values, found %zu", line,
                       ply_item_label(lab, sizeof lab, h, el, idx), found,
                       found + extra);
    }
    return FDT_IO_OK;
too_few:
    if (!el->has_list)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                       ":%zu: %s: expected %zu values, found %zu", line,
                       ply_item_label(lab, sizeof lab, h, el, idx),
                       el->n_scalar, found);
    return fdt_rd_fail(c, FDT_IO_EFORMAT, ":%zu: %s: too few values (found %zu)",
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
                return fdt_rd_fail(c, FDT_IO_EFORMAT,
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
            if ((i & (RD_PROGRESS_EVERY - 1)) == 0)
                fdt_rd_progress(c, (size_t)(L.p - c->buf));
            int got = 0;
            while ((got = fdt_rd_next_line(&L, &s, &e)) != 0 && fdt_rd_blank(s, e))
                ;
            if (!got)
                return fdt_rd_fail(c, FDT_IO_EFORMAT,
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
    while (fdt_rd_next_line(&L, &s, &e))
        if (!fdt_rd_blank(s, e))
            return fdt_rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: extra data after the last element (the "
                           "header's counts are too small?)",
                           L.lineno);
    return FDT_IO_OK;
}

/* An ASCII PLY in c->buf (fdt_rd_stream_ply loads it there). */
static int ply_read_buffered(const rd_ctx *c, rd_points *pb)
{
    ply_hdr h;
    memset(&h, 0, sizeof h);
    int rc = ply_parse_header(c, &h);
    if (rc == FDT_IO_OK && h.format != PLY_ASCII) /* cannot happen: the header was read */
        rc = fdt_rd_fail(c, FDT_IO_EFORMAT, ": the format changed while it was read");
    if (rc == FDT_IO_OK)
        rc = ply_read_ascii(c, &h, pb);
    ply_hdr_free(&h);
    return rc;
}

/* ------------------------------------------------------------------ */
/* Streamed binary PLY                                                */
/* ------------------------------------------------------------------ */

/*
 * The body's bytes: a window buf[lo..hi) of the input, whose first byte is
 * at input offset off. Every check of the buffered reader above that needs
 * the input's size (a fixed-size element's count against the bytes left,
 * the vertices' count before the array is allocated) is made once the size
 * is known: when the data ends, or, on a pipe, at the first error, after
 * reading the rest (ply_total). So a pipe, a file and memory give the same
 * messages, and a header's count costs memory only as its data arrives.
 */
typedef struct ply_in {
    rd_ctx *c;
    unsigned char *buf;
    size_t cap, lo, hi;
    size_t off; /* input offset of buf[lo] */
    int failed; /* a read failed (the message is in c->err) */
} ply_in;

/* At least n (<= cap) bytes in the window, unless the input ends first:
 * whether they are there. */
static int ply_need(ply_in *in, size_t n)
{
    if (in->hi - in->lo >= n)
        return 1;
    if (in->failed || in->c->src->eof)
        return 0;
    if (in->lo > 0) {
        memmove(in->buf, in->buf + in->lo, in->hi - in->lo);
        in->hi -= in->lo;
        in->lo = 0;
    }
    ptrdiff_t r = fdt_rd_src_read(in->c, in->buf + in->hi, in->cap - in->hi);
    if (r < 0) {
        in->failed = 1;
        return 0;
    }
    in->hi += (size_t)r;
    return in->hi - in->lo >= n;
}

static void ply_take(ply_in *in, size_t n)
{
    in->lo += n;
    in->off += n;
}

/* Skips n bytes: the bytes skipped (fewer at the input's end). */
static uint64_t ply_skip(ply_in *in, uint64_t n)
{
    uint64_t left = n;
    while (left > 0) {
        if (in->hi == in->lo && !ply_need(in, 1))
            break;
        size_t k = in->hi - in->lo;
        if ((uint64_t)k > left)
            k = (size_t)left;
        ply_take(in, k);
        left -= k;
    }
    return n - left;
}

/* The input's size: reads (and drops) what is left of it, the window
 * included (only an error's message needs it). */
static size_t ply_total(ply_in *in)
{
    in->off += in->hi - in->lo;
    in->lo = in->hi = 0;
    while (!in->failed && !in->c->src->eof) {
        ptrdiff_t r = fdt_rd_src_read(in->c, in->buf, in->cap);
        if (r < 0)
            in->failed = 1;
        else
            in->off += (size_t)r;
    }
    return in->off;
}

/* A failed read's code (its message is written), else 0. */
#define PLY_READ_FAILED(in) ((in)->failed ? FDT_IO_EOPEN : 0)

/* The size check of the buffered reader (ply_bin_skip) for an element
 * without lists starting at start, the input being total bytes. */
static int ply_fixed_short(const rd_ctx *c, const ply_hdr *h, const ply_elem *el, size_t start,
                           size_t total)
{
    char lab[160];
    size_t rem = total - start;
    uint64_t fit = rem / el->min_bytes;
    return fdt_rd_fail(c, FDT_IO_EFORMAT, ": byte %zu: file ends %s %s", total,
                       rem % el->min_bytes ? "inside" : "before",
                       ply_item_label(lab, sizeof lab, h, el, fit));
}

/* Walks one item with lists from the window (the streamed ply_bin_item):
 * 0, 1 when the data ends inside it, 2 on a negative list length (*at:
 * its offset). x, y, z go to dst when it is not NULL; their offsets to
 * roff. */
static int ply_st_item(ply_in *in, const ply_hdr *h, const ply_elem *el, int big,
                       double *dst, size_t roff[3], size_t *at)
{
    for (size_t i = 0; i < el->n_props; i++) {
        const ply_prop *p = &h->props[el->first_prop + i];
        if (!p->is_list) {
            size_t sz = ply_size[p->type];
            if (!ply_need(in, sz))
                return 1;
            if (p->role && dst != NULL) {
                roff[p->role - 1] = in->off;
                dst[p->role - 1] = ply_get(in->buf + in->lo, p->type, big);
            }
            ply_take(in, sz);
            continue;
        }
        size_t csz = ply_size[p->count_type];
        if (!ply_need(in, csz))
            return 1;
        int64_t len = ply_get_int(in->buf + in->lo, p->count_type, big);
        if (len < 0) {
            *at = in->off;
            return 2;
        }
        ply_take(in, csz);
        uint64_t isz = ply_size[p->type];
        if ((uint64_t)len > UINT64_MAX / isz ||
            ply_skip(in, (uint64_t)len * isz) != (uint64_t)len * isz)
            return 1;
    }
    return 0;
}

/* An element that is not read (the streamed ply_bin_skip). */
static int ply_st_skip(ply_in *in, const ply_hdr *h, const ply_elem *el, int big)
{
    const rd_ctx *c = in->c;
    char lab[160];
    size_t start = in->off;
    if (!el->has_list) {
        uint64_t want = el->count > UINT64_MAX / el->min_bytes ? UINT64_MAX
                                                                 : el->count * el->min_bytes;
        if (ply_skip(in, want) == want)
            return FDT_IO_OK;
        if (in->failed)
            return FDT_IO_EOPEN;
        return ply_fixed_short(c, h, el, start, ply_total(in));
    }
    for (uint64_t i = 0; i < el->count; i++) {
        if ((i & (RD_PROGRESS_EVERY - 1)) == 0)
            fdt_rd_progress(c, in->off);
        size_t at = 0;
        int r = ply_st_item(in, h, el, big, NULL, NULL, &at);
        if (in->failed)
            return FDT_IO_EOPEN;
        if (r == 1)
            return fdt_rd_fail(c, FDT_IO_EFORMAT, ": byte %zu: file ends inside %s",
                               ply_total(in), ply_item_label(lab, sizeof lab, h, el, i));
        if (r == 2)
            return fdt_rd_fail(c, FDT_IO_EFORMAT, ": byte %zu: %s: negative list length", at,
                               ply_item_label(lab, sizeof lab, h, el, i));
    }
    return FDT_IO_OK;
}

/*
 * The checks the buffered ply_bin_vertex makes before it allocates, for
 * the vertex element that starts at start of an input of total bytes:
 * FDT_IO_OK when they pass. The streamed read makes them at its first
 * error, whose message they take over as they do in the buffered read.
 */
static int ply_vertex_precheck(const rd_ctx *c, const ply_hdr *h, const ply_elem *el,
                               size_t start, size_t total)
{
    char lab[160];
    size_t rem = total - start;
    uint64_t fit = rem / el->min_bytes;
    if (el->count > fit) {
        if (!el->has_list)
            return fdt_rd_fail(c, FDT_IO_EFORMAT,
                               ": byte %zu: file ends %s %s (the header declares "
                               "%llu vertices of %zu bytes, %zu bytes follow it)",
                               total, rem % el->min_bytes ? "inside" : "before",
                               ply_item_label(lab, sizeof lab, h, el, fit),
                               (unsigned long long)el->count, el->min_bytes, rem);
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                           ": byte %zu: the header declares %llu vertices of at "
                           "least %zu bytes, only %zu bytes follow: refused",
                           start, (unsigned long long)el->count, el->min_bytes, rem);
    }
    if (el->count > RD_MAX_POINTS)
        return fdt_rd_fail(c, FDT_IO_EFORMAT,
                           ":%zu: the vertex element declares %llu points, more "
                           "than the %lld supported",
                           el->line, (unsigned long long)el->count, (long long)RD_MAX_POINTS);
    return FDT_IO_OK;
}

/* Points reserved first when the header's count is not yet backed by
 * bytes (a pipe, or a file shorter than the count); the array then
 * doubles as vertices arrive, so it never holds more than twice them. */
#define PLY_GROW ((size_t)1 << 10)

/* Room for vertex i (counting from 0) of the count: the whole count when
 * the input's known size holds it, else growing as the data comes. */
static int ply_vertex_room(rd_points *pb, uint64_t count, size_t i)
{
    if (i < pb->cap)
        return 0;
    size_t want = pb->cap * 2 > PLY_GROW ? pb->cap * 2 : PLY_GROW;
    if ((uint64_t)want > count)
        want = (size_t)count;
    return fdt_rd_points_reserve(pb, want);
}

/* Whether el is three little-endian doubles x, y, z and nothing else, on
 * a little-endian machine: then its bytes are the points array's. */
static int ply_plain_doubles(const ply_hdr *h, const ply_elem *el, int big)
{
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    if (big || el->n_props != 3 || el->has_list)
        return 0;
    for (size_t k = 0; k < 3; k++) {
        const ply_prop *p = &h->props[el->first_prop + k];
        if (p->type != PT_FLOAT64 || p->role != k + 1)
            return 0;
    }
    return 1;
#else
    (void)h;
    (void)el;
    (void)big;
    return 0;
#endif
}

/* The first error of a streamed vertex read, kept to be worded once the
 * input's size is known (ply_st_vertex_fail). */
typedef struct ply_vbad {
    int rc;     /* FDT_IO_ENOMEM; 1: the data ends inside vertex i; 2: a
                   negative list length at byte `at`; FDT_IO_OK: none, or
                   (k >= 0) coordinate k of vertex i, v at byte `at`, is not
                   finite */
    int k;
    uint64_t i;
    size_t at;
    double v;
} ply_vbad;

/* Room for the vertices before they are read: FDT_IO_OK to read them. */
static int ply_st_vertex_reserve(ply_in *in, const ply_hdr *h, const ply_elem *el, size_t start,
                                 rd_points *pb)
{
    const rd_ctx *c = in->c;
    /* A count the file's known size holds is allocated at once (the
     * usual file); otherwise the array grows as vertices arrive. */
    if (c->size > start && el->count <= (c->size - start) / el->min_bytes &&
        el->count <= RD_MAX_POINTS) {
        if (fdt_rd_points_reserve(pb, (size_t)el->count) != 0)
            return fdt_rd_fail(c, FDT_IO_ENOMEM, ": out of memory for %llu points",
                               (unsigned long long)el->count);
    } else if (el->count > RD_MAX_POINTS) {
        if (in->failed)
            return FDT_IO_EOPEN;
        int rc = ply_vertex_precheck(c, h, el, start, ply_total(in));
        return in->failed ? FDT_IO_EOPEN : rc;
    }
    return FDT_IO_OK;
}

/* Vertices that are three little-endian doubles (ply_plain_doubles) from
 * byte start: FDT_IO_EOPEN when a read fails, else FDT_IO_OK with the
 * first error, if any, in *bad. */
static int ply_st_plain(ply_in *in, const ply_elem *el, size_t start, rd_points *pb,
                        ply_vbad *bad)
{
    const rd_ctx *c = in->c;
    /* Straight into the array: the window's bytes first, then read()
     * into place, a buffer's worth at a time (progress, growth). */
    unsigned char *dst = (unsigned char *)pb->xyz;
    uint64_t bytes = el->count * 24, got = 0;
    while (got < bytes) {
        if (ply_vertex_room(pb, el->count, (size_t)(got / 24)) != 0) {
            bad->rc = FDT_IO_ENOMEM;
            break;
        }
        dst = (unsigned char *)pb->xyz;
        size_t room = pb->cap * 24 - (size_t)got, k;
        if (room > in->cap)
            room = in->cap;
        if (in->hi > in->lo) {
            k = in->hi - in->lo < room ? in->hi - in->lo : room;
            memcpy(dst + got, in->buf + in->lo, k);
            in->lo += k;
        } else {
            ptrdiff_t r = in->failed ? -1 : fdt_rd_src_read(c, dst + got, room);
            if (r < 0) {
                in->failed = 1;
                return FDT_IO_EOPEN;
            }
            k = (size_t)r;
        }
        /* every double now complete is checked, in file order */
        for (uint64_t v = got / 8; v < (got + k) / 8; v++) {
            double x = pb->xyz[v];
            if (!isfinite(x)) {
                bad->at = start + (size_t)v * 8;
                bad->k = (int)(v % 3);
                bad->v = x;
                bad->i = v / 3;
                break;
            }
        }
        got += k;
        in->off += k;
        fdt_rd_progress(c, in->off);
        if (bad->k >= 0 || k == 0)
            break;
    }
    if (bad->k < 0 && bad->rc == FDT_IO_OK && got != bytes)
        bad->rc = 1; /* the data ended inside vertex got / 24 */
    if (bad->k < 0)
        bad->i = got / 24;
    return FDT_IO_OK;
}

/* Vertices of any other layout, one at a time through the window: as
 * ply_st_plain. */
static int ply_st_fields(ply_in *in, const ply_hdr *h, const ply_elem *el, int big,
                         rd_points *pb, ply_vbad *bad)
{
    const rd_ctx *c = in->c;
    int type[3] = {0, 0, 0};
    size_t fixed_off[3] = {0, 0, 0};
    for (size_t j = 0, o = 0; j < el->n_props; j++) {
        const ply_prop *p = &h->props[el->first_prop + j];
        if (p->role) {
            type[p->role - 1] = p->type;
            fixed_off[p->role - 1] = o;
        }
        o += ply_size[p->type];
    }
    int r = 0;
    uint64_t i = 0;
    for (; i < el->count; i++) {
        if ((i & (RD_PROGRESS_EVERY - 1)) == 0)
            fdt_rd_progress(c, in->off);
        if (ply_vertex_room(pb, el->count, (size_t)i) != 0) {
            bad->rc = FDT_IO_ENOMEM;
            break;
        }
        double *d = pb->xyz + 3 * i;
        size_t roff[3];
        if (el->has_list) {
            r = ply_st_item(in, h, el, big, d, roff, &bad->at);
        } else if (!ply_need(in, el->min_bytes)) {
            r = 1;
        } else {
            for (int k = 0; k < 3; k++) {
                roff[k] = in->off + fixed_off[k];
                d[k] = ply_get(in->buf + in->lo + fixed_off[k], type[k], big);
            }
            ply_take(in, el->min_bytes);
        }
        if (in->failed)
            return FDT_IO_EOPEN;
        if (r != 0) {
            bad->rc = r; /* 1: ends inside; 2: negative list length at bad->at */
            break;
        }
        for (int k = 0; k < 3 && bad->k < 0; k++)
            if (!isfinite(d[k])) {
                bad->k = k;
                bad->at = roff[k];
                bad->v = d[k];
            }
        if (bad->k >= 0)
            break;
    }
    bad->i = i;
    return FDT_IO_OK;
}

/* The message of the first error *bad of the vertex element that starts
 * at byte start. */
static int ply_st_vertex_fail(ply_in *in, const ply_hdr *h, const ply_elem *el, size_t start,
                              const ply_vbad *bad)
{
    const rd_ctx *c = in->c;
    char lab[160];
    /* The size checks come first, as in the buffered read, which makes
     * them before it reads a vertex. */
    size_t total = ply_total(in);
    if (in->failed)
        return FDT_IO_EOPEN;
    int pre = ply_vertex_precheck(c, h, el, start, total);
    if (pre != FDT_IO_OK)
        return pre;
    if (bad->rc == FDT_IO_ENOMEM)
        return fdt_rd_fail(c, FDT_IO_ENOMEM, ": out of memory for %llu points",
                           (unsigned long long)el->count);
    if (bad->rc == 1)
        return fdt_rd_fail(c, FDT_IO_EFORMAT, ": byte %zu: file ends inside %s", total,
                           ply_item_label(lab, sizeof lab, h, el, bad->i));
    if (bad->rc == 2)
        return fdt_rd_fail(c, FDT_IO_EFORMAT, ": byte %zu: %s: negative list length", bad->at,
                           ply_item_label(lab, sizeof lab, h, el, bad->i));
    return fdt_rd_fail(c, FDT_IO_EFORMAT, ": byte %zu: %s: %c is %s", bad->at,
                       ply_item_label(lab, sizeof lab, h, el, bad->i), 'x' + bad->k,
                       isnan(bad->v) ? "NaN" : "infinite");
}

/* The vertex element (the streamed ply_bin_vertex): room for it, its
 * vertices read by the step for their layout, the first error worded. */
static int ply_st_vertex(ply_in *in, const ply_hdr *h, const ply_elem *el, int big,
                         rd_points *pb)
{
    size_t start = in->off;
    int rc = ply_st_vertex_reserve(in, h, el, start, pb);
    if (rc != FDT_IO_OK)
        return rc;
    ply_vbad bad = {FDT_IO_OK, -1, 0, 0, 0.0};
    rc = ply_plain_doubles(h, el, big) ? ply_st_plain(in, el, start, pb, &bad)
                                       : ply_st_fields(in, h, el, big, pb, &bad);
    if (rc != FDT_IO_OK)
        return rc;
    if (bad.rc == FDT_IO_OK && bad.k < 0) {
        pb->n = (size_t)el->count;
        return FDT_IO_OK;
    }
    return ply_st_vertex_fail(in, h, el, start, &bad);
}

/* The body of a binary PLY whose header h was read; in holds the bytes
 * read after it. */
static int ply_st_binary(ply_in *in, const ply_hdr *h, rd_points *pb)
{
    int big = h->format == PLY_BE;
    for (size_t ei = 0; ei < h->n_elems; ei++) {
        const ply_elem *el = &h->elems[ei];
        int rc = ei == h->vertex ? ply_st_vertex(in, h, el, big, pb)
                                 : ply_st_skip(in, h, el, big);
        if (rc != FDT_IO_OK)
            return rc;
    }
    size_t off = in->off;
    if (ply_need(in, 1)) {
        size_t total = ply_total(in);
        if (in->failed)
            return FDT_IO_EOPEN;
        return fdt_rd_fail(in->c, FDT_IO_EFORMAT,
                           ": byte %zu: %zu bytes of extra data after the last "
                           "element (the header's counts are too small?)",
                           off, total - off);
    }
    return PLY_READ_FAILED(in);
}

/* An ASCII PLY whose first len bytes are in hb (cap + 1 bytes, owned):
 * the rest loaded too, and the whole parsed as a buffer (the header
 * again: its names point into the buffer, which grows); the buffer is
 * handed to *owned. */
static int ply_load_ascii(rd_ctx *c, char *hb, size_t len, size_t cap, rd_points *pb,
                          char **owned)
{
    while (!c->src->eof) {
        if (len == cap) {
            if (cap > (SIZE_MAX - 1) / 2) {
                free(hb);
                return fdt_rd_fail(c, FDT_IO_ENOMEM, ": file too large for memory");
            }
            char *nb = realloc(hb, 2 * cap + 1);
            if (nb == NULL) {
                free(hb);
                return fdt_rd_fail(c, FDT_IO_ENOMEM, ": out of memory reading the file");
            }
            hb = nb;
            cap *= 2;
        }
        ptrdiff_t r = fdt_rd_src_read(c, hb + len, cap - len);
        if (r < 0) {
            free(hb);
            return FDT_IO_EOPEN;
        }
        len += (size_t)r;
        if (c->progress != NULL)
            c->progress(c->progress_user, FDT_RD_LOADING, len, c->size > len ? c->size : 0);
    }
    hb[len] = '\0';
    *owned = hb;
    c->buf = hb;
    c->size = len;
    return ply_read_buffered(c, pb);
}

/* The body of a binary PLY of header h, read from the input through a
 * buffer of its own, after the len - h->data_off bytes of it that hb (the
 * header's buffer, len bytes) holds. */
static int ply_stream_body(rd_ctx *c, const ply_hdr *h, const char *hb, size_t len,
                           rd_points *pb)
{
    ply_in in;
    memset(&in, 0, sizeof in);
    in.c = c;
    size_t chunk = c->chunk ? c->chunk : RD_CHUNK;
    in.cap = fdt_rd_first_cap(c, chunk, c->size > h->data_off ? c->size - h->data_off + 1 : 1);
    if (in.cap < 8)
        in.cap = 8; /* the largest scalar */
    for (size_t ei = 0; ei < h->n_elems; ei++)
        if (in.cap < h->elems[ei].min_bytes)
            in.cap = h->elems[ei].min_bytes; /* a whole item without lists */
    size_t extra = len - h->data_off;
    if (in.cap < extra)
        in.cap = extra;
    in.buf = malloc(in.cap);
    int rc;
    if (in.buf == NULL) {
        rc = fdt_rd_fail(c, FDT_IO_ENOMEM, ": out of memory");
    } else {
        memcpy(in.buf, hb + h->data_off, extra);
        in.hi = extra;
        in.off = h->data_off;
        rc = ply_st_binary(&in, h, pb);
    }
    free(in.buf);
    return rc;
}

int fdt_rd_stream_ply(rd_ctx *c, rd_points *pb, char **owned)
{
    /* The header: complete lines read until one is end_header. Its parse
     * sees only whole lines, so that a line cut by the buffer's end is
     * never taken for a bad one; running out of lines before end_header
     * means reading more (or, at the end of the input, the error). */
    size_t cap = c->chunk ? c->chunk : RD_CHUNK, len = 0;
    if (cap > ((size_t)64 << 10))
        cap = (size_t)64 << 10; /* headers are short; the body gets its own buffer */
    if (cap < 16)
        cap = 16;
    char *hb = NULL;
    ply_hdr h;
    memset(&h, 0, sizeof h);
    int rc;
    for (;;) {
        /* h holds the previous pass's parse (a header cut short) from the
         * second pass on: every exit frees it */
        char *nb = realloc(hb, cap + 1);
        if (nb == NULL) {
            ply_hdr_free(&h);
            free(hb);
            return fdt_rd_fail(c, FDT_IO_ENOMEM, ": out of memory");
        }
        hb = nb;
        ptrdiff_t r = fdt_rd_src_read(c, hb + len, cap - len);
        if (r < 0) {
            ply_hdr_free(&h);
            free(hb);
            return FDT_IO_EOPEN;
        }
        len += (size_t)r;
        hb[len] = '\0';
        if (len == 0) {
            free(hb);
            return fdt_rd_fail(c, FDT_IO_EFORMAT, ": no points (empty file)");
        }
        int eof = c->src->eof;
        size_t lines = len;
        if (!eof) {
            while (lines > 0 && hb[lines - 1] != '\n')
                lines--;
        }
        rd_ctx hc = *c;
        hc.buf = hb;
        hc.size = lines;
        ply_hdr_free(&h);
        memset(&h, 0, sizeof h);
        rc = ply_parse_header(&hc, &h);
        if (rc == FDT_IO_OK || eof || !h.no_end)
            break;
        if (cap > (SIZE_MAX - 1) / 2) {
            rc = fdt_rd_fail(c, FDT_IO_ENOMEM, ": out of memory");
            break;
        }
        cap *= 2; /* more lines of header */
    }
    if (rc != FDT_IO_OK) {
        ply_hdr_free(&h);
        free(hb);
        return rc;
    }
    if (h.format == PLY_ASCII) {
        ply_hdr_free(&h);
        return ply_load_ascii(c, hb, len, cap, pb, owned);
    }
    /* Binary: the header's buffer stays (the elements' names point into
     * it); the body streams through its own. */
    rc = ply_stream_body(c, &h, hb, len, pb);
    ply_hdr_free(&h);
    free(hb);
    return rc;
}

/* ------------------------------------------------------------------ */
/* Binary PLY slices (src/io/read/reader.h; src/mpi/mpi_setup.c)                  */
/* ------------------------------------------------------------------ */

int fdt_rd_ply_find_layout(const char *path, fdt_rd_ply_layout *lay, char *err, size_t errlen)
{
    rd_ctx c;
    rd_ctx_start(&c, path, err, errlen);
    memset(lay, 0, sizeof *lay);
    int fd;
    do
        fd = open(path, O_RDONLY | O_CLOEXEC);
    while (fd < 0 && errno == EINTR);
    if (fd < 0)
        return fdt_rd_fail(&c, FDT_IO_EOPEN, ": cannot open: %s", strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        close(fd);
        return 0; /* the whole read says what it is */
    }
    uint64_t size = (uint64_t)st.st_size;
    rd_src src = {.fd = fd};
    c.src = &src;
    size_t cap = (size_t)64 << 10, len = 0;
    char *hb = NULL;
    ply_hdr h;
    memset(&h, 0, sizeof h);
    int rc = 0, parsed = 0;
    /* the header's complete lines, read until one is end_header (as
     * fdt_rd_stream_ply); any failure: not sliceable, the whole read
     * words it */
    for (;;) {
        char *nb = realloc(hb, cap + 1);
        if (nb == NULL) {
            rc = fdt_rd_fail(&c, FDT_IO_ENOMEM, ": out of memory");
            break;
        }
        hb = nb;
        ptrdiff_t r = fdt_rd_src_read(&c, hb + len, cap - len);
        if (r < 0) {
            rc = FDT_IO_EOPEN;
            break;
        }
        len += (size_t)r;
        hb[len] = '\0';
        size_t lines = len;
        if (!src.eof)
            while (lines > 0 && hb[lines - 1] != '\n')
                lines--;
        rd_ctx hc = c;
        hc.buf = hb;
        hc.size = lines;
        hc.err = NULL;
        hc.errlen = 0;
        ply_hdr_free(&h);
        memset(&h, 0, sizeof h);
        int pr = len == 0 ? FDT_IO_EFORMAT : ply_parse_header(&hc, &h);
        if (pr == FDT_IO_OK) {
            parsed = 1;
            break;
        }
        if (src.eof || !h.no_end || cap > (SIZE_MAX - 1) / 2)
            break;
        cap *= 2;
    }
    close(fd);
    if (parsed && (h.format == PLY_LE || h.format == PLY_BE) && h.vertex != SIZE_MAX) {
        /* every element of fixed size, and the file exactly as long as
         * the header says: then vertex i is at a known byte */
        uint64_t at = h.data_off, vat = 0;
        int ok = 1;
        for (size_t ei = 0; ei < h.n_elems && ok; ei++) {
            const ply_elem *el = &h.elems[ei];
            if (el->has_list || (el->min_bytes && el->count > (UINT64_MAX - at) / el->min_bytes))
                ok = 0;
            else {
                if (ei == h.vertex)
                    vat = at;
                at += el->count * el->min_bytes;
            }
        }
        const ply_elem *v = &h.elems[h.vertex];
        if (ok && at == size && v->count <= RD_MAX_POINTS && v->min_bytes > 0) {
            lay->vertex_off = (size_t)vat;
            lay->rec = v->min_bytes;
            lay->count = v->count;
            lay->big = h.format == PLY_BE;
            for (size_t j = 0, o = 0; j < v->n_props; j++) {
                const ply_prop *p = &h.props[v->first_prop + j];
                if (p->role) {
                    lay->type[p->role - 1] = p->type;
                    lay->off[p->role - 1] = o;
                }
                o += ply_size[p->type];
            }
            rc = 1;
        }
    }
    ply_hdr_free(&h);
    free(hb);
    return rc;
}

int fdt_rd_ply_range(const char *path, const fdt_rd_ply_layout *lay, unsigned long long first,
                     size_t count, double **xyz, char *err, size_t errlen)
{
    rd_ctx c;
    rd_ctx_start(&c, path, err, errlen);
    *xyz = NULL;
    if (first > lay->count || count > lay->count - first)
        return fdt_rd_fail(&c, FDT_IO_EFORMAT, ": vertices beyond the header's count");
    int fd;
    do
        fd = open(path, O_RDONLY | O_CLOEXEC);
    while (fd < 0 && errno == EINTR);
    if (fd < 0)
        return fdt_rd_fail(&c, FDT_IO_EOPEN, ": cannot open: %s", strerror(errno));
    double *d = malloc((3 * count + 1) * sizeof *d);
    size_t per = RD_CHUNK / lay->rec + 1;
    unsigned char *buf = malloc(per * lay->rec);
    int rc = d && buf ? FDT_IO_OK : fdt_rd_fail(&c, FDT_IO_ENOMEM, ": out of memory");
    for (size_t i = 0; rc == FDT_IO_OK && i < count; i += per) {
        size_t k = count - i < per ? count - i : per, want = k * lay->rec, got = 0;
        size_t off = lay->vertex_off + (size_t)(first + i) * lay->rec;
        while (got < want) {
            ssize_t r = pread(fd, buf + got, want - got, (off_t)(off + got));
            if (r < 0 && errno == EINTR)
                continue;
            if (r <= 0) {
                rc = fdt_rd_fail(&c, FDT_IO_EOPEN, ": cannot read: %s",
                                 r < 0 ? strerror(errno) : "the file shrank");
                break;
            }
            got += (size_t)r;
        }
        for (size_t j = 0; rc == FDT_IO_OK && j < k; j++)
            for (int a = 0; a < 3; a++) {
                double x = ply_get(buf + j * lay->rec + lay->off[a], lay->type[a], lay->big);
                if (!isfinite(x)) /* the whole read words it */
                    rc = fdt_rd_fail(&c, FDT_IO_EFORMAT, ": vertex %llu: not finite",
                                     (unsigned long long)(first + i + j + 1));
                d[3 * (i + j) + a] = x;
            }
    }
    close(fd);
    free(buf);
    if (rc != FDT_IO_OK) {
        free(d);
        return rc;
    }
    *xyz = d;
    return FDT_IO_OK;
}
