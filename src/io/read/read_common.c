/*
 * What every point reader uses (see read_common.h): the wording of errors
 * and tokens, the growing point array, and the streamed input's reads.
 */
#include "io/read/read_common.h"
#include "base/mem.h"

#include <errno.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

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
    /* Written at once, every page up to the count (5,900 4 KB faults, about
     * 0.1 s, filled a binary PLY's 1M points; realloc's copy of the text
     * reader's array took 6,800: bench/NOTES.md entry 134). All of the old
     * block is kept, as realloc keeps it: a binary PLY's bytes run past n. */
    double *x = fdt_mem_realloc_huge(pb->xyz, pb->cap * 3 * sizeof(double),
                                     cap * 3 * sizeof(double));
    if (x == NULL)
        return -1;
    pb->xyz = x;
    pb->cap = cap;
    return 0;
}

int fdt_rd_points_room(rd_points *pb, size_t more)
{
    if (more > RD_MAX_POINTS || pb->n > RD_MAX_POINTS - more)
        return -1;
    size_t want = pb->n + more;
    if (want <= pb->cap)
        return 0;
    size_t dbl = pb->cap > RD_MAX_POINTS / 2 ? (size_t)RD_MAX_POINTS : 2 * pb->cap;
    return fdt_rd_points_reserve(pb, want > dbl ? want : dbl);
}

/* ------------------------------------------------------------------ */
/* Streamed input                                                     */
/* ------------------------------------------------------------------ */

ptrdiff_t fdt_rd_src_read(const rd_ctx *c, void *dst, size_t len)
{
    rd_src *s = c->src;
    if (len > (size_t)PTRDIFF_MAX)
        len = (size_t)PTRDIFF_MAX;
    if (s->fd < 0) {
        size_t k = s->mem_len - s->pos < len ? s->mem_len - s->pos : len;
        if (s->fail_after != 0 && k > 0 && s->pos + k > s->fail_after) {
            fdt_rd_fail(c, FDT_IO_EOPEN, ": cannot read: %s", strerror(EIO));
            return -1;
        }
        if (k > 0)
            memcpy(dst, s->mem + s->pos, k);
        s->pos += k;
        if (k < len)
            s->eof = 1;
        return (ptrdiff_t)k;
    }
    size_t got = 0;
    if (s->bounded && len > s->left) {
        len = s->left; /* the range's end is its end of file */
        if (len == 0)
            s->eof = 1;
    }
    while (got < len && !s->eof) {
        size_t want = len - got < RD_READ_MAX ? len - got : RD_READ_MAX;
        ssize_t r = read(s->fd, (char *)dst + got, want);
        if (r == 0) {
            s->eof = 1;
            break;
        }
        if (r < 0) {
            if (errno == EINTR)
                continue;
            int e = errno;
            if (e == EISDIR)
                fdt_rd_fail(c, FDT_IO_EOPEN, ": is a directory");
            else
                fdt_rd_fail(c, FDT_IO_EOPEN, ": cannot read: %s", strerror(e));
            return -1;
        }
        got += (size_t)r;
        s->pos += (size_t)r;
        if (s->bounded) {
            s->left -= (size_t)r;
            if (s->left == 0)
                s->eof = 1;
        }
    }
    return (ptrdiff_t)got;
}
