/*
 * Point-cloud readers (see src/reader.h for the formats and the contract):
 * the shared input and the table of formats. The format parsers are
 * src/read_xyz.c, src/read_node.c and src/read_ply.c; numbers, lines and
 * fields of the text formats src/read_text.c.
 *
 * The whole file is read into one NUL-terminated buffer and parsed in
 * memory. Every header count is checked against the bytes that follow it
 * before anything proportional to the count is allocated, so a 100-byte
 * file claiming four billion points costs nothing.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "read_common.h"

#include <errno.h>
#include <fcntl.h>
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

int fdt_rd_fail(const rd_ctx *c, int code, const char *fmt, ...)
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
const char *fdt_rd_quote(char out[RD_QUOTE_CAP], const char *s, size_t len)
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

/* ------------------------------------------------------------------ */
/* Point storage                                                      */
/* ------------------------------------------------------------------ */

int fdt_rd_points_reserve(rd_points *pb, size_t cap)
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
            return fdt_rd_fail(c, FDT_IO_ENOMEM, ": file too large for memory");
        /* one spare byte shows whether the file grew since fstat */
        cap = (size_t)st->st_size + 2;
    }
    char *buf = malloc(cap);
    if (buf == NULL)
        return fdt_rd_fail(c, FDT_IO_ENOMEM,
                       ": out of memory reading %zu bytes", cap - 2);
    size_t len = 0;
    for (;;) {
        if (len == cap - 1) {
            if (cap > SIZE_MAX / 2) {
                free(buf);
                return fdt_rd_fail(c, FDT_IO_ENOMEM, ": file too large for memory");
            }
            char *nb = realloc(buf, cap * 2);
            if (nb == NULL) {
                free(buf);
                return fdt_rd_fail(c, FDT_IO_ENOMEM,
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
                return fdt_rd_fail(c, FDT_IO_EOPEN, ": is a directory");
            return fdt_rd_fail(c, FDT_IO_EOPEN, ": cannot read: %s", strerror(e));
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
        rc = fdt_rd_fail(c, FDT_IO_EFORMAT, ": no points (empty file)");
    } else if (kind == EXT_PLY) {
        rc = fdt_rd_read_ply(c, &pb);
    } else {
        const char *start = c->buf;
        /* a UTF-8 byte order mark, as some Windows tools write */
        if (c->size >= 3 && memcmp(c->buf, "\xef\xbb\xbf", 3) == 0)
            start += 3;
        rc = kind == EXT_NODE ? fdt_rd_read_node(c, start, &pb)
                              : fdt_rd_read_xyz(c, start, &pb);
    }
    if (rc == FDT_IO_OK && pb.n == 0)
        rc = fdt_rd_fail(c, FDT_IO_EFORMAT, ": no points");
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
    return fdt_rd_fail(c, FDT_IO_EEXT,
                   ": unknown extension %s (expected .xyz, .txt, .node or "
                   ".ply)",
                   fdt_rd_quote(q, ext, strlen(ext)));
}

static int rd_read_path(const char *path, int threads, size_t min_slice, double **xyz,
                        size_t *n, char *err, size_t errlen)
{
    rd_ctx c = {path != NULL ? path : "(null)", err, errlen, NULL, 0, threads, min_slice};
    rd_begin(&c, xyz, n);
    if (path == NULL || xyz == NULL || n == NULL)
        return fdt_rd_fail(&c, FDT_IO_EOPEN, ": invalid arguments");

    int fd;
    do
        fd = open(path, O_RDONLY | O_CLOEXEC);
    while (fd < 0 && errno == EINTR);
    if (fd < 0)
        return fdt_rd_fail(&c, FDT_IO_EOPEN, ": cannot open: %s", strerror(errno));
    struct stat st;
    if (fstat(fd, &st) != 0) {
        int e = errno;
        close(fd);
        return fdt_rd_fail(&c, FDT_IO_EOPEN, ": cannot open: %s", strerror(e));
    }
    if (S_ISDIR(st.st_mode)) {
        close(fd);
        return fdt_rd_fail(&c, FDT_IO_EOPEN, ": is a directory");
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
        return fdt_rd_fail(&c, FDT_IO_EOPEN, ": invalid arguments");
    const char *ext;
    int kind = rd_extension(name, &ext);
    if (kind == EXT_NONE)
        return rd_bad_extension(&c, ext);
    /* The parsers expect what rd_slurp gives them: a private copy with a
     * NUL after the last byte. Copying keeps the two entry points one code
     * path (and lets the fuzzers find reads past that NUL). */
    if (len > SIZE_MAX - 1)
        return fdt_rd_fail(&c, FDT_IO_ENOMEM, ": file too large for memory");
    char *buf = malloc(len + 1);
    if (buf == NULL)
        return fdt_rd_fail(&c, FDT_IO_ENOMEM, ": out of memory reading %zu bytes",
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
