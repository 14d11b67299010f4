/*
 * The readers' slice entry points (src/io/read/reader.h, "Text slices" and
 * "Binary PLY slices"), which the distributed setup (src/mpi/mpi_setup.c)
 * gives each MPI rank: a file cut into slices at every byte offset (two
 * slices) and into 3 and 7 slices must give, joined in order, exactly the
 * points of the whole read; a bad line must be worded by the slice that
 * holds it, given the lines before it, exactly as the whole read words it;
 * a binary PLY's vertex ranges must be its points.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <errno.h>
#include <math.h>
#include <sys/stat.h>
#include <unistd.h>

#include "io/read/reader.h"
#include "testutil.h"

static void write_file(const char *path, const char *data, size_t len)
{
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL);
    CHECK(fwrite(data, 1, len, f) == len);
    CHECK(fclose(f) == 0);
}

/* The text, its byte order mark, header, comments, blank lines and CRLF
 * ends included: the points of gen_text, n of them. */
static char *gen_text(size_t n, size_t *len)
{
    size_t cap = 64 * n + 256, k = 0;
    char *s = malloc(cap);
    CHECK(s != NULL);
    k += (size_t)snprintf(s + k, cap - k, "\xef\xbb\xbfX,Y,Z\r\n# a comment\r\n\r\n");
    uint64_t seed = 7;
    for (size_t i = 0; i < n; i++) {
        k += (size_t)snprintf(s + k, cap - k, "%.17g,%.17g,%.17g%s\r\n", test_unif(&seed),
                              test_unif(&seed), test_unif(&seed),
                              i % 13 == 0 ? "  # tail" : "");
        if (i % 29 == 0)
            k += (size_t)snprintf(s + k, cap - k, "\r\n# between\r\n");
    }
    *len = k;
    return s;
}

/* Parses path cut into the slices that start at the line starts at or
 * after cuts[0..nc) (each past the head's body) and compares the joined
 * points with want (n of them). */
static void check_cuts(const char *path, const fdt_rd_head *h, const size_t *cuts, int nc,
                       const double *want, size_t n)
{
    size_t at[16];
    CHECK(nc + 2 <= 16);
    at[0] = h->body;
    for (int i = 0; i < nc; i++) {
        char err[256];
        size_t x = cuts[i] < h->body ? h->body : cuts[i];
        CHECK(fdt_rd_text_line_start(path, x, &at[i + 1], err, sizeof err) == FDT_IO_OK);
        if (at[i + 1] < at[i])
            at[i + 1] = at[i];
    }
    at[nc + 1] = h->size;
    size_t got = 0, lines = h->body_line;
    int same = 1;
    fdt_rd_opts o;
    fdt_rd_opts_default(&o);
    for (int i = 0; i <= nc; i++) {
        double *xyz = NULL;
        size_t k = 0, l = 0;
        char err[256];
        int rc = fdt_rd_text_range(path, &o, at[i], at[i + 1], h->ncols, lines, &xyz, &k, &l,
                                   err, sizeof err);
        EXPECTF(rc == FDT_IO_OK, "slice [%zu, %zu): %s", at[i], at[i + 1], err);
        if (rc == FDT_IO_OK && got + k <= n && k > 0)
            same &= memcmp(xyz, want + 3 * got, 3 * k * sizeof *xyz) == 0;
        got += k;
        lines += l;
        free(xyz);
    }
    EXPECTF(got == n && same, "cuts at %zu...: %zu points of %zu, same %d", cuts[0], got, n,
            same);
}

static void test_text(const char *dir)
{
    char path[512];
    snprintf(path, sizeof path, "%s/slices.csv", dir);
    size_t len, n;
    char *text = gen_text(300, &len);
    write_file(path, text, len);
    double *want = NULL;
    char err[256];
    CHECK(fdt_rd_points(path, &want, &n, err, sizeof err) == FDT_IO_OK);
    CHECK_EQ(n, 300);
    fdt_rd_head h;
    CHECK(fdt_rd_text_head(path, &h, err, sizeof err) == FDT_IO_OK);
    CHECK_EQ(h.ncols, 3);
    CHECK_EQ(h.body_line, 1); /* the header is line 1 */
    CHECK_EQ(h.size, len);
    /* two slices, cut at every byte */
    for (size_t x = 0; x <= len; x++)
        check_cuts(path, &h, &x, 1, want, n);
    /* 3 and 7 slices at even shares, as the ranks cut */
    for (int p = 3; p <= 7; p += 4) {
        size_t cuts[8];
        for (int r = 1; r < p; r++)
            cuts[r - 1] = h.body + (len - h.body) * (size_t)r / (size_t)p;
        check_cuts(path, &h, cuts, p - 1, want, n);
    }
    free(want);

    /* A bad line: the slice holding it, given the lines before it, words
     * it as the whole read does, wherever the cut falls. */
    char *bad = strstr(text + len / 2, "\r\n");
    CHECK(bad != NULL);
    memcpy(bad - 3, "x", 1); /* a number's last digits become 'x..' */
    write_file(path, text, len);
    char whole[256];
    double *none = NULL;
    CHECK(fdt_rd_points(path, &none, &n, whole, sizeof whole) == FDT_IO_EFORMAT);
    fdt_rd_opts o;
    fdt_rd_opts_default(&o);
    for (size_t x = h.body; x <= len; x += 7) {
        size_t cut;
        CHECK(fdt_rd_text_line_start(path, x, &cut, err, sizeof err) == FDT_IO_OK);
        double *xyz = NULL;
        size_t k = 0, l1 = 0, l2 = 0;
        int rc1 = fdt_rd_text_range(path, &o, h.body, cut, 3, h.body_line, &xyz, &k, &l1, err,
                                    sizeof err);
        free(xyz);
        if (rc1 != FDT_IO_OK) { /* the first slice holds it */
            EXPECTF(strcmp(err, whole) == 0, "cut %zu: '%s', whole read '%s'", cut, err, whole);
            continue;
        }
        rc1 = fdt_rd_text_range(path, &o, cut, len, 3, h.body_line + l1, &xyz, &k, &l2, err,
                                sizeof err);
        free(xyz);
        EXPECTF(rc1 == FDT_IO_EFORMAT && strcmp(err, whole) == 0, "cut %zu: '%s', whole '%s'",
                cut, err, whole);
    }
    free(text);
    remove(path);
}

static void test_ply(const char *dir)
{
    char path[512];
    snprintf(path, sizeof path, "%s/slices.ply", dir);
    /* big-endian float x, y, z and a colour after a fixed element */
    size_t n = 257;
    char head[256];
    int hl = snprintf(head, sizeof head,
                      "ply\nformat binary_big_endian 1.0\nelement camera 1\nproperty int id\n"
                      "element vertex %zu\nproperty uchar red\nproperty float x\n"
                      "property float y\nproperty float z\nend_header\n",
                      n);
    size_t len = (size_t)hl + 4 + 13 * n;
    unsigned char *b = malloc(len);
    CHECK(b != NULL);
    memcpy(b, head, (size_t)hl);
    memset(b + hl, 0, 4);
    uint64_t seed = 3;
    for (size_t i = 0; i < n; i++) {
        unsigned char *r = b + hl + 4 + 13 * i;
        r[0] = 9;
        for (int k = 0; k < 3; k++) {
            float f = (float)test_unif(&seed);
            uint32_t u;
            memcpy(&u, &f, 4);
            for (int j = 0; j < 4; j++)
                r[1 + 4 * k + j] = (unsigned char)(u >> (24 - 8 * j));
        }
    }
    write_file(path, (const char *)b, len);
    double *want = NULL;
    size_t wn;
    char err[256];
    CHECK(fdt_rd_points(path, &want, &wn, err, sizeof err) == FDT_IO_OK);
    CHECK_EQ(wn, n);
    fdt_rd_ply_layout lay;
    CHECK_EQ(fdt_rd_ply_find_layout(path, &lay, err, sizeof err), 1);
    CHECK_EQ(lay.count, n);
    CHECK_EQ(lay.rec, 13);
    for (size_t a = 0; a < n; a += 31) {
        size_t k = n - a < 40 ? n - a : 40;
        double *xyz = NULL;
        CHECK(fdt_rd_ply_range(path, &lay, a, k, &xyz, err, sizeof err) == FDT_IO_OK);
        EXPECTF(memcmp(xyz, want + 3 * a, 3 * k * sizeof *xyz) == 0, "vertices %zu..%zu", a,
                a + k);
        free(xyz);
    }
    /* one byte more than the header says: not sliceable (the whole read
     * words the error) */
    write_file(path, (const char *)b, len - 1);
    EXPECT(fdt_rd_ply_find_layout(path, &lay, err, sizeof err) == 0);
    free(want);
    free(b);
    remove(path);
}

/* err holds want (a substring), and names the file. */
static void expect_msg(int line, const char *err, const char *name, const char *want)
{
    EXPECTF(strstr(err, name) != NULL && strstr(err, want) != NULL,
            "line %d: '%s' should name %s and say '%s'", line, err, name, want);
}

/* The text head and line starts at the edges: missing files, directories,
 * empty and point-less files, heads longer than the first read. */
static void test_text_edges(const char *dir)
{
    char path[512], err[256];
    fdt_rd_head h;
    size_t at;
    snprintf(path, sizeof path, "%s/missing.xyz", dir);
    EXPECT(fdt_rd_text_head(path, &h, err, sizeof err) == FDT_IO_EOPEN);
    expect_msg(__LINE__, err, "missing.xyz", "cannot open");
    EXPECT(fdt_rd_text_line_start(path, 5, &at, err, sizeof err) == FDT_IO_EOPEN);
    expect_msg(__LINE__, err, "missing.xyz", "cannot open");
    EXPECT(fdt_rd_text_head(dir, &h, err, sizeof err) == FDT_IO_EOPEN);
    expect_msg(__LINE__, err, dir, "not a regular file");

    /* empty: no columns, nothing to cut */
    snprintf(path, sizeof path, "%s/edge.xyz", dir);
    write_file(path, "", 0);
    EXPECT(fdt_rd_text_head(path, &h, err, sizeof err) == FDT_IO_OK && h.ncols == 0 &&
           h.size == 0 && h.body == 0);
    EXPECT(fdt_rd_text_line_start(path, 0, &at, err, sizeof err) == FDT_IO_OK && at == 0);
    EXPECT(fdt_rd_text_line_start(path, 9, &at, err, sizeof err) == FDT_IO_OK && at == 0);
    /* comments only, a header only, a lone partial byte order mark */
    write_file(path, "# a\n\n# b\n", 9);
    EXPECT(fdt_rd_text_head(path, &h, err, sizeof err) == FDT_IO_OK && h.ncols == 0 &&
           h.size == 9);
    write_file(path, "\xef\xbb\xbfX Y Z\n# none\n", 16);
    EXPECT(fdt_rd_text_head(path, &h, err, sizeof err) == FDT_IO_OK && h.ncols == 0 &&
           h.body == 9 && h.body_line == 1);
    /* two bytes of a mark at the end: not a mark, a non-printable
     * point line of one field (the range read words it) */
    write_file(path, "\xef\xbb", 2);
    EXPECT(fdt_rd_text_head(path, &h, err, sizeof err) == FDT_IO_OK && h.ncols == 1 &&
           h.body == 0);
    write_file(path, "X Y Z", 5); /* a header without a line end */
    EXPECT(fdt_rd_text_head(path, &h, err, sizeof err) == FDT_IO_OK && h.ncols == 0 &&
           h.body == 5);

    /* a comment and a header line longer than the first read (64 KiB):
     * the head reads on until its lines are whole */
    size_t big = (size_t)200 << 10, len = 0;
    char *s = malloc(big + 64);
    CHECK(s != NULL);
    s[len++] = '#';
    memset(s + len, 'c', big / 2);
    len += big / 2;
    s[len++] = '\n';
    memset(s + len, 'H', big / 2);
    len += big / 2;
    len += (size_t)snprintf(s + len, 64, "\n1 2 3 4\n5 6 7 8");
    write_file(path, s, len);
    EXPECT(fdt_rd_text_head(path, &h, err, sizeof err) == FDT_IO_OK && h.ncols == 4 &&
           h.body_line == 2 && h.body == len - 15 && h.size == len);
    /* a line start searched across a line longer than one block */
    EXPECT(fdt_rd_text_line_start(path, 10, &at, err, sizeof err) == FDT_IO_OK &&
           at == big / 2 + 2);
    EXPECT(fdt_rd_text_line_start(path, big / 2 + 2, &at, err, sizeof err) == FDT_IO_OK &&
           at == big / 2 + 2);
    EXPECT(fdt_rd_text_line_start(path, 0, &at, err, sizeof err) == FDT_IO_OK && at == 0);
    /* in the last line, which has no end: the file's size */
    EXPECT(fdt_rd_text_line_start(path, len - 3, &at, err, sizeof err) == FDT_IO_OK &&
           at == len);
    EXPECT(fdt_rd_text_line_start(path, len + 7, &at, err, sizeof err) == FDT_IO_OK &&
           at == len);
    /* the range after the head: the two points, 4 columns */
    fdt_rd_opts o;
    fdt_rd_opts_default(&o);
    double *xyz = NULL;
    size_t n = 0, lines = 0;
    EXPECT(fdt_rd_text_range(path, &o, h.body, h.size, h.ncols, h.body_line, &xyz, &n, &lines,
                             err, sizeof err) == FDT_IO_OK &&
           n == 2 && xyz != NULL && xyz[3] == 5 && xyz[5] == 7);
    free(xyz);
    /* columns 4, 2, 1 of the same range */
    o.columns[0] = 4;
    o.columns[1] = 2;
    o.columns[2] = 1;
    xyz = NULL;
    EXPECT(fdt_rd_text_range(path, &o, h.body, h.size, h.ncols, h.body_line, &xyz, &n, &lines,
                             err, sizeof err) == FDT_IO_OK &&
           n == 2 && xyz != NULL && xyz[0] == 4 && xyz[1] == 2 && xyz[2] == 1 && xyz[3] == 8);
    free(xyz);
    free(s);
    remove(path);
}

/* fdt_rd_text_range's refusals, empty and clamped ranges, bad lines
 * (numbered from the lines before the range), NaN and inf, and the
 * threaded and small-buffer parses giving the same points. */
static void test_text_range(const char *dir)
{
    char path[512], err[256];
    fdt_rd_opts o;
    fdt_rd_opts_default(&o);
    double *xyz = (double *)&o; /* must come back NULL */
    size_t n = 9, lines = 9;
    snprintf(path, sizeof path, "%s/range.ply", dir);
    write_file(path, "0 0 0\n", 6);
    EXPECT(fdt_rd_text_range(path, &o, 0, 6, 3, 0, &xyz, &n, &lines, err, sizeof err) ==
               FDT_IO_EFORMAT &&
           xyz == NULL && n == 0 && lines == 0);
    expect_msg(__LINE__, err, "range.ply", "not a text point format");
    remove(path);
    snprintf(path, sizeof path, "%s/range.las", dir);
    EXPECT(fdt_rd_text_range(path, &o, 0, 6, 3, 0, &xyz, &n, &lines, err, sizeof err) ==
           FDT_IO_EEXT);
    expect_msg(__LINE__, err, "range.las", "");
    snprintf(path, sizeof path, "%s/range.xyz", dir);
    EXPECT(fdt_rd_text_range(path, &o, 0, 6, 3, 0, &xyz, &n, &lines, err, sizeof err) ==
           FDT_IO_EOPEN);
    expect_msg(__LINE__, err, "range.xyz", "cannot open");
    EXPECT(fdt_rd_text_range(dir, &o, 0, 6, 3, 0, &xyz, &n, &lines, err, sizeof err) !=
           FDT_IO_OK);

    /* 20 lines "i i+0.5 -i\n", line 1 a header */
    char text[1024];
    size_t len = (size_t)snprintf(text, sizeof text, "x y z\n");
    size_t start[22];
    for (int i = 0; i < 20; i++) {
        start[i] = len;
        len += (size_t)snprintf(text + len, sizeof text - len, "%d %d.5 -%d\n", i, i, i);
    }
    start[20] = len;
    write_file(path, text, len);
    /* empty ranges: at the body, at the end, begin past end, past the size */
    size_t cuts[][2] = {{start[0], start[0]}, {len, len}, {start[5], start[3]},
                        {len + 10, len + 20}};
    for (int i = 0; i < 4; i++) {
        xyz = (double *)&o;
        EXPECTF(fdt_rd_text_range(path, &o, cuts[i][0], cuts[i][1], 3, 1, &xyz, &n, &lines,
                                  err, sizeof err) == FDT_IO_OK &&
                    xyz == NULL && n == 0 && lines == 0,
                "empty range %d: n %zu lines %zu", i, n, lines);
    }
    /* the last line alone; the end clamped to the size */
    EXPECT(fdt_rd_text_range(path, &o, start[19], len + 100, 3, 20, &xyz, &n, &lines, err,
                             sizeof err) == FDT_IO_OK &&
           n == 1 && lines == 1 && xyz[0] == 19 && xyz[1] == 19.5 && xyz[2] == -19);
    free(xyz);
    /* a name with no extension, told the format */
    char other[512];
    snprintf(other, sizeof other, "%s/range.dat", dir);
    write_file(other, text, len);
    o.format = FDT_RD_XYZ;
    EXPECT(fdt_rd_text_range(other, &o, start[2], start[4], 3, 3, &xyz, &n, &lines, err,
                             sizeof err) == FDT_IO_OK &&
           n == 2 && lines == 2 && xyz[0] == 2 && xyz[5] == -3);
    free(xyz);
    remove(other);
    o.format = FDT_RD_AUTO;
    /* a 4-byte buffer (every line straddles refills) and 3 threads on
     * slices of 8 bytes: the same 20 points */
    for (int v = 0; v < 2; v++) {
        fdt_rd_opts_default(&o);
        if (v == 0)
            o.chunk = 4;
        else {
            o.threads = 3;
            o.min_slice = 8;
            o.chunk = 64;
        }
        EXPECT(fdt_rd_text_range(path, &o, start[0], len, 3, 1, &xyz, &n, &lines, err,
                                 sizeof err) == FDT_IO_OK);
        int same = n == 20 && lines == 20;
        for (size_t i = 0; same && i < 20; i++)
            same = xyz[3 * i] == (double)i && xyz[3 * i + 1] == (double)i + 0.5 &&
                   xyz[3 * i + 2] == -(double)i;
        EXPECTF(same, "variant %d: %zu points, %zu lines", v, n, lines);
        free(xyz);
    }
    fdt_rd_opts_default(&o);

    /* bad lines inside a range: numbered from line0 */
    const char *bad[] = {"7 nan 7\n", "7 7 inf\n", "7 7\n", "7 7 7 7\n", "7 7 1e999\n"};
    const char *said[] = {"'nan'", "'inf'", "expected 3 numbers, found 2",
                          "expected 3 numbers, found 4", "'1e999'"};
    for (int b = 0; b < 5; b++) {
        char t2[1024];
        size_t l2 = start[7];
        memcpy(t2, text, l2);
        l2 += (size_t)snprintf(t2 + l2, sizeof t2 - l2, "%s", bad[b]);
        size_t tail = len - start[8];
        memcpy(t2 + l2, text + start[8], tail);
        l2 += tail;
        write_file(path, t2, l2);
        char whole[256];
        double *none = NULL;
        size_t wn;
        CHECK(fdt_rd_points(path, &none, &wn, whole, sizeof whole) == FDT_IO_EFORMAT);
        xyz = (double *)&o;
        /* the range from line 6 (start[5]): the bad line is line 9 */
        int rc = fdt_rd_text_range(path, &o, start[5], start[7] + strlen(bad[b]), 3, 6, &xyz,
                                   &n, &lines, err, sizeof err);
        EXPECTF(rc == FDT_IO_EFORMAT && xyz == NULL && n == 0 && strcmp(err, whole) == 0 &&
                    strstr(err, "range.xyz:9:") != NULL && strstr(err, said[b]) != NULL,
                "bad line %d: rc %d '%s', whole '%s'", b, rc, err, whole);
        /* the range before it is fine */
        EXPECT(fdt_rd_text_range(path, &o, start[5], start[7], 3, 6, &xyz, &n, &lines, err,
                                 sizeof err) == FDT_IO_OK &&
               n == 2 && lines == 2);
        free(xyz);
    }
    remove(path);
}

/* A PLY scalar of type t (char uchar short ushort int uint float double,
 * as src/io/read/read_ply.c's order) at p. */
static const char *const ply_tname[8] = {"char", "uchar", "short", "ushort",
                                         "int",  "uint",  "float", "double"};
static const size_t ply_tsize[8] = {1, 1, 2, 2, 4, 4, 4, 8};

static void ply_put(unsigned char *p, int t, double v, int big)
{
    uint64_t u = 0;
    switch (t) {
    case 0: u = (uint8_t)(int8_t)v; break;
    case 1: u = (uint8_t)v; break;
    case 2: u = (uint16_t)(int16_t)v; break;
    case 3: u = (uint16_t)v; break;
    case 4: u = (uint32_t)(int32_t)v; break;
    case 5: u = (uint32_t)v; break;
    case 6: {
        float f = (float)v;
        uint32_t w;
        memcpy(&w, &f, 4);
        u = w;
        break;
    }
    default: memcpy(&u, &v, 8); break;
    }
    size_t sz = ply_tsize[t];
    for (size_t j = 0; j < sz; j++)
        p[big ? sz - 1 - j : j] = (unsigned char)(u >> (8 * j));
}

/* The value vertex i's axis a holds for type t: in the type's range,
 * negative for the signed ones, a fraction for the floats. */
static double ply_val(int t, size_t i, int a)
{
    double k = (double)((i * 37 + (size_t)a * 11) % 101);
    if (t == 6 || t == 7)
        return (double)(float)(k / 8 - 6.25);
    return t % 2 == 0 && t < 6 ? k - 50 : k;
}

/* Writes a binary PLY of n vertices (x, y, z of types tx, ty, tz, a
 * ushort between x and y, a leading fixed element) to path; its bytes. */
static size_t write_ply(const char *path, int big, const int ty[3], size_t n)
{
    char head[512];
    int hl = snprintf(head, sizeof head,
                      "ply\nformat binary_%s_endian 1.0\ncomment slices\nelement cam 2\n"
                      "property double f\nelement vertex %zu\nproperty %s x\n"
                      "property ushort pad\nproperty %s y\nproperty %s z\nelement tail 1\n"
                      "property char c\nend_header\n",
                      big ? "big" : "little", n, ply_tname[ty[0]], ply_tname[ty[1]],
                      ply_tname[ty[2]]);
    size_t rec = ply_tsize[ty[0]] + 2 + ply_tsize[ty[1]] + ply_tsize[ty[2]];
    size_t len = (size_t)hl + 16 + n * rec + 1;
    unsigned char *b = calloc(len, 1);
    CHECK(b != NULL);
    memcpy(b, head, (size_t)hl);
    for (size_t i = 0; i < n; i++) {
        unsigned char *r = b + hl + 16 + i * rec;
        ply_put(r, ty[0], ply_val(ty[0], i, 0), big);
        r += ply_tsize[ty[0]] + 2;
        ply_put(r, ty[1], ply_val(ty[1], i, 1), big);
        r += ply_tsize[ty[1]];
        ply_put(r, ty[2], ply_val(ty[2], i, 2), big);
    }
    write_file(path, (const char *)b, len);
    free(b);
    return len;
}

/* Every property type in every axis, both byte orders, through the range
 * reader: the values written, equal to the whole read's, at the ends and
 * in empty ranges; ranges past the count refused. */
static void test_ply_types(const char *dir)
{
    char path[512], err[256];
    snprintf(path, sizeof path, "%s/types.ply", dir);
    const size_t n = 41;
    for (int big = 0; big < 2; big++)
        for (int t = 0; t < 8; t++) {
            int ty[3] = {t, (t + 3) % 8, (t + 6) % 8};
            write_ply(path, big, ty, n);
            double *want = NULL;
            size_t wn = 0;
            EXPECTF(fdt_rd_points(path, &want, &wn, err, sizeof err) == FDT_IO_OK && wn == n,
                    "whole read: %s", err);
            fdt_rd_ply_layout lay;
            int found = fdt_rd_ply_find_layout(path, &lay, err, sizeof err);
            EXPECTF(found == 1 && lay.count == n && lay.big == big &&
                        lay.rec == ply_tsize[ty[0]] + 2 + ply_tsize[ty[1]] + ply_tsize[ty[2]] &&
                        lay.off[1] == ply_tsize[ty[0]] + 2,
                    "layout of %s %s: %d", big ? "big" : "little", ply_tname[t], found);
            if (found != 1 || want == NULL) {
                free(want);
                continue;
            }
            size_t ranges[][2] = {{0, n}, {0, 1}, {n - 1, 1}, {17, 9}, {0, 0}, {n, 0}};
            for (int r = 0; r < 6; r++) {
                size_t a = ranges[r][0], k = ranges[r][1];
                double *xyz = NULL;
                int rc = fdt_rd_ply_range(path, &lay, a, k, &xyz, err, sizeof err);
                int same = rc == FDT_IO_OK && xyz != NULL &&
                           (k == 0 || memcmp(xyz, want + 3 * a, 3 * k * sizeof *xyz) == 0);
                for (size_t i = 0; same && i < k; i++)
                    for (int ax = 0; ax < 3; ax++)
                        same &= xyz[3 * i + (size_t)ax] == ply_val(ty[ax], a + i, ax);
                EXPECTF(same, "%s-endian %s/%s/%s, vertices [%zu, +%zu): rc %d",
                        big ? "big" : "little", ply_tname[ty[0]], ply_tname[ty[1]],
                        ply_tname[ty[2]], a, k, rc);
                free(xyz);
            }
            double *xyz = (double *)&lay;
            EXPECT(fdt_rd_ply_range(path, &lay, n, 1, &xyz, err, sizeof err) ==
                       FDT_IO_EFORMAT &&
                   xyz == NULL);
            expect_msg(__LINE__, err, "types.ply", "beyond the header's count");
            EXPECT(fdt_rd_ply_range(path, &lay, n + 1, 0, &xyz, err, sizeof err) ==
                   FDT_IO_EFORMAT);
            EXPECT(fdt_rd_ply_range(path, &lay, 3, n, &xyz, err, sizeof err) ==
                   FDT_IO_EFORMAT);
            free(want);
        }
    remove(path);
}

/* Files the layout refuses (read whole instead), NaN/inf in a range, a
 * file that shrinks under the range reader, a header past one read, and
 * files that open but cannot be read. */
static void test_ply_refusals(const char *dir)
{
    char path[512], err[256];
    fdt_rd_ply_layout lay;
    snprintf(path, sizeof path, "%s/refuse.ply", dir);
    EXPECT(fdt_rd_ply_find_layout(path, &lay, err, sizeof err) == FDT_IO_EOPEN);
    expect_msg(__LINE__, err, "refuse.ply", "cannot open");
    EXPECT(fdt_rd_ply_find_layout(dir, &lay, err, sizeof err) == 0);
    double *xyz = (double *)&lay;
    fdt_rd_ply_layout fake = {.vertex_off = 0, .rec = 12, .count = 4, .type = {6, 6, 6}};
    EXPECT(fdt_rd_ply_range(path, &fake, 0, 4, &xyz, err, sizeof err) == FDT_IO_EOPEN &&
           xyz == NULL);
    expect_msg(__LINE__, err, "refuse.ply", "cannot open");

    const char *not_sliceable[] = {
        "", /* empty */
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
        "property float z\nend_header\n0 0 0\n",
        "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\n"
        "property float y\nproperty float z\nelement face 0\n"
        "property list uchar int vertex_indices\nend_header\n",
        "ply\nformat binary_little_endian 1.0\nelement point 0\nproperty float x\n"
        "end_header\n",                                   /* no vertex element */
        "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\n", /* no end */
        "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n"
        "property float y\nproperty float z\nend_header\n\1\2\3", /* short */
        "ply\nformat binary_little_endian 1.0\nelement vertex 3000000000\nproperty float x\n"
        "property float y\nproperty float z\nend_header\n", /* beyond INT32_MAX points */
        "ply\nformat binary_little_endian 1.0\nelement vertex 3000000000000000000\n"
        "property float x\nproperty float y\nproperty float z\nend_header\n", /* overflows */
        "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty flot x\n"
        "end_header\n", /* a bad header */
        "ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty list uchar float x\n"
        "end_header\n\0", /* x a list */
    };
    for (size_t i = 0; i < sizeof not_sliceable / sizeof *not_sliceable; i++) {
        write_file(path, not_sliceable[i], strlen(not_sliceable[i]));
        EXPECTF(fdt_rd_ply_find_layout(path, &lay, err, sizeof err) == 0,
                "file %zu should not be sliceable", i);
    }

    /* NaN and inf of floats and doubles: refused naming the vertex */
    int ty[3] = {6, 7, 6};
    size_t len = write_ply(path, 0, ty, 12);
    CHECK(fdt_rd_ply_find_layout(path, &lay, err, sizeof err) == 1);
    size_t at[2] = {lay.vertex_off + 5 * lay.rec + lay.off[1],
                    lay.vertex_off + 9 * lay.rec + lay.off[2]};
    FILE *f = fopen(path, "r+b");
    CHECK(f != NULL);
    double nan_d = NAN;
    float inf_f = INFINITY;
    CHECK(fseek(f, (long)at[0], SEEK_SET) == 0 && fwrite(&nan_d, 8, 1, f) == 1);
    CHECK(fseek(f, (long)at[1], SEEK_SET) == 0 && fwrite(&inf_f, 4, 1, f) == 1);
    CHECK(fclose(f) == 0);
    EXPECT(fdt_rd_ply_range(path, &lay, 0, 5, &xyz, err, sizeof err) == FDT_IO_OK);
    free(xyz);
    EXPECT(fdt_rd_ply_range(path, &lay, 10, 2, &xyz, err, sizeof err) == FDT_IO_OK);
    free(xyz);
    EXPECT(fdt_rd_ply_range(path, &lay, 3, 4, &xyz, err, sizeof err) == FDT_IO_EFORMAT &&
           xyz == NULL);
    expect_msg(__LINE__, err, "refuse.ply", "vertex 6: not finite");
    EXPECT(fdt_rd_ply_range(path, &lay, 7, 5, &xyz, err, sizeof err) == FDT_IO_EFORMAT);
    expect_msg(__LINE__, err, "refuse.ply", "vertex 10: not finite");

    /* the file shrinks after its layout was found */
    CHECK(truncate(path, (off_t)(len - 1 - 6 * lay.rec)) == 0);
    EXPECT(fdt_rd_ply_range(path, &lay, 0, 3, &xyz, err, sizeof err) == FDT_IO_OK);
    free(xyz);
    EXPECT(fdt_rd_ply_range(path, &lay, 4, 4, &xyz, err, sizeof err) == FDT_IO_EOPEN &&
           xyz == NULL);
    expect_msg(__LINE__, err, "refuse.ply", "the file shrank");

    /* a header longer than one read (64 KiB of comments) */
    size_t nc = 3000, hl = 0;
    char *h = malloc(nc * 40 + ((size_t)80 << 10));
    CHECK(h != NULL);
    hl += (size_t)sprintf(h, "ply\nformat binary_little_endian 1.0\n");
    for (size_t i = 0; i < nc; i++)
        hl += (size_t)sprintf(h + hl, "comment %026zu\n", i);
    hl += (size_t)sprintf(h + hl, "element vertex 2\nproperty double x\nproperty double y\n"
                                  "property double z\nend_header\n");
    double pts[6] = {1.5, -2, 3, 4, 5.25, -6};
    memcpy(h + hl, pts, sizeof pts);
    write_file(path, h, hl + sizeof pts);
    EXPECT(fdt_rd_ply_find_layout(path, &lay, err, sizeof err) == 1 && lay.vertex_off == hl &&
           lay.count == 2 && lay.rec == 24);
    EXPECT(fdt_rd_ply_range(path, &lay, 0, 2, &xyz, err, sizeof err) == FDT_IO_OK &&
           memcmp(xyz, pts, sizeof pts) == 0);
    free(xyz);
    /* one comment longer than the first read: no line end in it */
    hl = (size_t)sprintf(h, "ply\nformat binary_little_endian 1.0\ncomment ");
    memset(h + hl, 'k', (size_t)70 << 10);
    hl += (size_t)70 << 10;
    hl += (size_t)sprintf(h + hl, "\nelement vertex 2\nproperty double x\n"
                                  "property double y\nproperty double z\nend_header\n");
    memcpy(h + hl, pts, sizeof pts);
    write_file(path, h, hl + sizeof pts);
    EXPECT(fdt_rd_ply_find_layout(path, &lay, err, sizeof err) == 1 && lay.vertex_off == hl);
    EXPECT(fdt_rd_ply_range(path, &lay, 1, 1, &xyz, err, sizeof err) == FDT_IO_OK &&
           memcmp(xyz, pts + 3, 3 * sizeof *pts) == 0);
    free(xyz);
    free(h);
    remove(path);

    /* opens but cannot be read: /proc/self/mem at offset 0 (unmapped)
     * fails pread with EIO */
    if (access("/proc/self/mem", R_OK) == 0) {
        EXPECT(fdt_rd_ply_find_layout("/proc/self/mem", &lay, err, sizeof err) ==
               FDT_IO_EOPEN);
        expect_msg(__LINE__, err, "mem", strerror(EIO));
        fake.vertex_off = 0;
        EXPECT(fdt_rd_ply_range("/proc/self/mem", &fake, 0, 4, &xyz, err, sizeof err) ==
               FDT_IO_EOPEN);
        expect_msg(__LINE__, err, "mem", "cannot read");
        fdt_rd_head hd;
        EXPECT(fdt_rd_text_head("/proc/self/mem", &hd, err, sizeof err) == FDT_IO_EOPEN);
        expect_msg(__LINE__, err, "mem", "cannot read");
    }
}

int main(void)
{
    const char *tmp = getenv("TMPDIR");
    char dir[256];
    int k = snprintf(dir, sizeof dir, "%s/fdt-test-slices.XXXXXX", tmp && *tmp ? tmp : "/tmp");
    CHECK(k > 0 && (size_t)k < sizeof dir);
    CHECK(mkdtemp(dir) != NULL);
    test_text(dir);
    test_ply(dir);
    test_text_edges(dir);
    test_text_range(dir);
    test_ply_types(dir);
    test_ply_refusals(dir);
    rmdir(dir);
    return test_report("reader_slices");
}
