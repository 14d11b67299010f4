/*
 * The buffered output file of the mesh writers (src/io/write/writer.c) and the
 * helpers the format modules (src/fmt_*.c) put their bytes with. A format
 * never opens, renames or removes a file: src/io/write/writer.c opens every file of
 * a format's set as a temporary, hands it to the format's writer functions
 * and renames the set at the end (all or none).
 *
 * Output goes through our own large buffer and is handed to stdio in big
 * chunks: formatting millions of integers with fprintf would cost seconds.
 * Every write error is kept (the first errno) and ends the output.
 */
#ifndef FDT_OUTFILE_H
#define FDT_OUTFILE_H

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

#include "base/dtoa.h"
#include "frontdt.h"
#include "io/read/read_types.h" /* FDT_IO_* codes */

#define OUT_BUF_SIZE (1u << 20)
/* The longest item put in one go: a %.17g double is at most
 * FDT_DTOA17_MAX (24) chars. */
#define OUT_MAX_ITEM 64

/*
 * Bytes written so far by one output (all of its files) and whom to tell:
 * every byte passes through out_flush, which reports them (the write
 * progress of include/frontdt.h, FDT_STAGE_WRITE). total is an estimate.
 */
typedef struct out_meter {
    fdt_io_progress_fn fn;
    void *user;
    uint64_t done;
    uint64_t total;
} out_meter;

typedef struct out_file {
    FILE *f;
    out_meter *meter;  /* NULL: nobody watches */
    int slot;          /* registry slot, -1 when none */
    const char *path;  /* the target (for messages) */
    char *buf;
    size_t len;
    int err;           /* first errno seen, 0 while all is well */
} out_file;

static inline void out_fail(out_file *o, int e)
{
    if (o->err == 0)
        o->err = e ? e : EIO;
}

static inline void out_flush(out_file *o)
{
    if (o->len == 0 || o->err)
        return;
    errno = 0;
    if (fwrite(o->buf, 1, o->len, o->f) != o->len)
        out_fail(o, errno);
    else if (o->meter != NULL && o->meter->fn != NULL) {
        out_meter *mt = o->meter;
        mt->done += o->len;
        /* an estimate: never below what is done */
        mt->fn(mt->user, FDT_STAGE_WRITE, mt->done,
               mt->total > mt->done ? mt->total : mt->done);
    }
    o->len = 0;
}

/* Makes room for n more bytes (n <= OUT_BUF_SIZE). */
static inline char *out_room(out_file *o, size_t n)
{
    if (OUT_BUF_SIZE - o->len < n) {
        out_flush(o);
        if (o->err)
            o->len = 0; /* keep going into the bin; the error is final */
    }
    return o->buf + o->len;
}

static inline void out_bytes(out_file *o, const void *p, size_t n)
{
    const char *s = p;
    while (n > 0) {
        size_t room = OUT_BUF_SIZE - o->len;
        if (room == 0) {
            out_flush(o);
            if (o->err)
                return;
            room = OUT_BUF_SIZE;
        }
        size_t k = n < room ? n : room;
        memcpy(o->buf + o->len, s, k);
        o->len += k;
        s += k;
        n -= k;
    }
}

static inline void out_str(out_file *o, const char *s)
{
    out_bytes(o, s, strlen(s));
}

static inline void out_i64(out_file *o, int64_t v)
{
    char *p = out_room(o, 21);
    o->len += fdt_itoa(p, v);
}

static inline void out_char(out_file *o, char c)
{
    char *p = out_room(o, 1);
    *p = c;
    o->len++;
}

/* %.17g: enough digits that strtod gives back the very same double. */
static inline void out_double(out_file *o, double x)
{
    char *p = out_room(o, FDT_DTOA17_MAX);
    o->len += fdt_dtoa17(p, x);
}

/* The byte offset the next byte put goes to. */
static inline uint64_t out_tell(out_file *o)
{
    off_t at = ftello(o->f);
    if (at < 0) {
        out_fail(o, errno);
        return 0;
    }
    return (uint64_t)at + o->len;
}

/* Rewrites n bytes at offset at, already written or still in the buffer
 * (a count left as a placeholder by a streaming writer). Flushes first,
 * so the bytes are in the file, then writes in place with pwrite: the
 * stream's own position is left at the end. */
static inline void out_patch(out_file *o, uint64_t at, const void *p, size_t n)
{
    out_flush(o);
    if (o->err)
        return;
    errno = 0;
    if (fflush(o->f) != 0) {
        out_fail(o, errno);
        return;
    }
    const char *s = p;
    while (n > 0) {
        ssize_t k = pwrite(fileno(o->f), s, n, (off_t)at);
        if (k < 0 && errno == EINTR)
            continue;
        if (k <= 0) {
            out_fail(o, k < 0 ? errno : EIO);
            return;
        }
        s += k;
        n -= (size_t)k;
        at += (uint64_t)k;
    }
}

/* A count as exactly w decimal characters, right-aligned in blanks (the
 * placeholders of the streamed text formats: readers split on blanks). */
static inline void fmt_u64_width(char *p, uint64_t v, size_t w)
{
    char tmp[24];
    size_t k = fdt_utoa(tmp, v);
    memset(p, ' ', w - k);
    memcpy(p + w - k, tmp, k);
}

static inline int set_err(char *err, size_t errlen, int code, const char *path,
                   const char *what)
{
    if (err && errlen > 0)
        snprintf(err, errlen, "%s: %s", path ? path : "(null)", what);
    return code;
}

/* An errno as FDT_IO_EWRITE, except ENOMEM (our buffer, or stdio's):
 * running out of memory is not a write failure and the CLI says so. */
static inline int set_errno_err(char *err, size_t errlen, const char *path, int e)
{
    return set_err(err, errlen, e == ENOMEM ? FDT_IO_ENOMEM : FDT_IO_EWRITE,
                   path, strerror(e ? e : EIO));
}

#endif
