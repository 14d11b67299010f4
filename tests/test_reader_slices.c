/*
 * The readers' slice entry points (src/reader.h, "Text slices" and
 * "Binary PLY slices"), which the distributed setup (src/mpi_setup.c)
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
#include <unistd.h>

#include "reader.h"
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

int main(void)
{
    const char *tmp = getenv("TMPDIR");
    char dir[256];
    int k = snprintf(dir, sizeof dir, "%s/fdt-test-slices.XXXXXX", tmp && *tmp ? tmp : "/tmp");
    CHECK(k > 0 && (size_t)k < sizeof dir);
    CHECK(mkdtemp(dir) != NULL);
    test_text(dir);
    test_ply(dir);
    rmdir(dir);
    return test_report("reader_slices");
}
