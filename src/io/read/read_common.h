/*
 * What the point readers share (src/io/read/reader.c, src/io/read/read_text.c and one
 * module a format: src/io/read/read_xyz.c, src/io/read/read_node.c, src/io/read/read_ply.c).
 * Internal to the readers: the CLI and tests use src/io/read/reader.h.
 *
 * Text point files (.xyz/.txt/.csv) and binary PLY are streamed: they pull
 * their bytes from an rd_src through a bounded buffer (rd_ctx.chunk bytes,
 * RD_CHUNK by default) and keep only the points, so a read's peak memory
 * is the points array (24 bytes a point) and that buffer (issue 18). .node
 * and ASCII PLY, rarely large, are parsed from one NUL-terminated buffer
 * holding the whole input (rd_ctx.buf, loaded by src/io/read/reader.c). Either way
 * a format words its first error with fdt_rd_fail ("PATH:LINE: ..." or
 * "PATH: byte N: ...").
 */
#ifndef FDT_READ_COMMON_H
#define FDT_READ_COMMON_H

#include "io/read/read_types.h"

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#if defined(__GNUC__)
#define RD_PRINTF(f, a) __attribute__((format(printf, f, a)))
#else
#define RD_PRINTF(f, a)
#endif

/* fdt_vid is int32_t: more points cannot be numbered. */
#define RD_MAX_POINTS ((uint64_t)INT32_MAX)

/* Bytes of an offending token quoted in a message. */
#define RD_QUOTE_BYTES 24
#define RD_QUOTE_CAP (RD_QUOTE_BYTES * 4 + 8)

/* Below a megabyte a slice's thread costs about what it saves. */
#define RD_MIN_SLICE ((size_t)1 << 20)

/* The streamed formats' buffer: large enough that a read() or a slice's
 * thread costs nothing beside the parse of its bytes, small beside the
 * points of any file worth streaming (8 MiB: 350,000 text points). With
 * several threads a block holds two slices a thread (src/io/read/read_xyz.c). */
#define RD_CHUNK ((size_t)8 << 20)

/* Bytes a single read() asks for: a bounded request keeps a signal's
 * EINTR cheap and is all the kernel gives a pipe at once anyway. */
#define RD_READ_MAX ((size_t)1 << 30)

/* A streamed read's first buffer when the input's size is not known (a
 * pipe): small inputs stay small; it doubles up to the chunk while the
 * input fills it. */
#define RD_FIRST_CHUNK ((size_t)64 << 10)


/* Where a streamed read's bytes come from: a file descriptor (a file, a
 * pipe, a FIFO) or, for fdt_rd_points_mem, bytes in memory. */
typedef struct rd_src {
    int fd;            /* -1: mem[0..mem_len) */
    const char *mem;
    size_t mem_len;
    size_t pos;        /* bytes delivered so far */
    int eof;           /* a read found the end */
    int bounded;       /* fd: deliver no more than `left` bytes (a range
                          of a file, fdt_rd_text_range) */
    size_t left;
    size_t fail_after; /* mem only, for tests (fdt_rd_opts.fail_after):
                          a read reaching past this many bytes fails as
                          read() would; 0: never */
} rd_src;

typedef struct rd_ctx {
    const char *path;
    char *err;
    size_t errlen;
    const char *buf; /* buffered formats: the whole file, NUL-terminated
                        (owned by the caller) */
    size_t size;     /* bytes in the file (the NUL not counted); while a
                        streamed read goes on, the size fstat gave a
                        regular file, else 0 (not known yet) */
    int size_known;  /* size is the input's (a regular file, memory) */
    rd_src *src;     /* streamed formats: the input */
    size_t chunk;    /* streamed formats: buffer bytes; 0: RD_CHUNK */
    int threads;      /* for .xyz: slices of a block parsed at once */
    size_t min_slice; /* least bytes a slice; 0: RD_MIN_SLICE */
    int col[3];       /* .xyz: 0-based columns of x, y, z */
    int custom_cols;  /* col[] is not 0, 1, 2 (the messages say so) */
    char sep;         /* .xyz: the separator besides blanks (',', ';' or
                         0: blanks only); rd_ctx_start: ',' */
    int sep_guard;    /* .xyz: refuse a line that mixes blank and tight
                         comma separators (the delimiter was not named) */
    int decimal_comma; /* .xyz: ',' is the decimal mark */
    fdt_rd_progress_fn progress; /* NULL on threads other than the caller's */
    void *progress_user;
    size_t progress_scale; /* parsed bytes are reported times this */
} rd_ctx;

/* A context for reading `path` (named so in messages), its errors worded
 * into err[errlen]; every other field zero. */
static inline void rd_ctx_start(rd_ctx *c, const char *path, char *err, size_t errlen)
{
    memset(c, 0, sizeof *c);
    c->path = path;
    c->err = err;
    c->errlen = errlen;
    c->sep = ',';
    c->sep_guard = 1;
}

/* The buffer to start a streamed read of c with: the chunk, or less when
 * the input is known to be smaller or its size is not known. */
static inline size_t fdt_rd_first_cap(const rd_ctx *c, size_t chunk, size_t left)
{
    if (c->size_known)
        return left < chunk ? left : chunk;
    return RD_FIRST_CHUNK < chunk ? RD_FIRST_CHUNK : chunk;
}

/* Reports done bytes parsed (times c->progress_scale, at most c->size
 * when the size is known; total 0 while it is not, as from a pipe). */
static inline void fdt_rd_progress(const rd_ctx *c, size_t done)
{
    if (c->progress == NULL)
        return;
    size_t s = c->progress_scale > 1 ? c->progress_scale : 1;
    if (c->size > 0)
        done = done > c->size / s ? c->size : done * s;
    else
        done = done > SIZE_MAX / s ? SIZE_MAX : done * s;
    c->progress(c->progress_user, FDT_RD_PARSING, done, c->size);
}

/* Lines or items between two progress reports. */
#define RD_PROGRESS_EVERY 8192

typedef struct rd_points {
    double *xyz; /* 3 * cap doubles */
    size_t n, cap;
    int fixed;   /* xyz is a slice of another array: it cannot grow */
} rd_points;

/* src/io/read/read_common.c: messages, point storage, streamed input. */

/* Writes "PATH" followed by the formatted text; always returns code. */
int fdt_rd_fail(const rd_ctx *c, int code, const char *fmt, ...) RD_PRINTF(3, 4);
/* The token s[0..len) as 'text' for a message (see src/io/read/read_common.c). */
const char *fdt_rd_quote(char out[RD_QUOTE_CAP], const char *s, size_t len);
/* Grows pb to cap points; -1 when out of memory or pb is fixed. */
int fdt_rd_points_reserve(rd_points *pb, size_t cap);
/* Room for more points beyond pb->n: grows to at least pb->n + more,
 * doubling (a large array grows by mremap, its untouched tail never
 * resident); -1 when out of memory, fixed, or beyond RD_MAX_POINTS. */
int fdt_rd_points_room(rd_points *pb, size_t more);
/*
 * Reads up to len bytes of the input into dst, fewer only at its end
 * (then c->src->eof is set): the count, or -1 after wording a read error
 * in c (as the buffered read words it: ": cannot read: ...").
 */
ptrdiff_t fdt_rd_src_read(const rd_ctx *c, void *dst, size_t len);

/* src/io/read/read_text.c: numbers, lines and fields of the text formats. */

enum {
    NUM_OK = 0,
    NUM_SYNTAX,    /* not a number of our grammar */
    NUM_NONFINITE, /* nan, inf, infinity */
    NUM_OVERFLOW,  /* beyond DBL_MAX (or, for integers, beyond int64) */
    NUM_UNDERFLOW, /* nonzero literal that rounds to a subnormal or zero */
    NUM_NOMEM
};

/* The literal s[0..len) (or, without full, its longest prefix: *used). */
int fdt_rd_scan_real(const char *s, size_t len, double *out, int check_range, int full,
                     size_t *used);
int fdt_rd_parse_real(const char *s, size_t len, double *out, int check_range);
int fdt_rd_parse_int(const char *s, size_t len, int64_t *out);
int fdt_rd_parse_count(const char *s, size_t len, uint64_t *out);
/* "PATH:LINE: [what: ]problem 'token'"; returns the code to give back. */
int fdt_rd_num_fail(const rd_ctx *c, size_t line, const char *what, int status, const char *s,
                    size_t len);

typedef struct rd_lines {
    const char *p, *end;
    size_t lineno; /* number of the line last returned (1-based) */
} rd_lines;

int fdt_rd_next_line(rd_lines *L, const char **s, const char **e);
const char *fdt_rd_cut_comment(const char *s, const char *e);
int fdt_rd_blank(const char *s, const char *e);

typedef struct rd_fields {
    const char *p, *e;
    char sep;   /* separates fields besides blanks (',' in the text point
                   formats by default; ';'); 0: blanks only */
    size_t n;   /* fields returned so far */
} rd_fields;

/* fdt_rd_skip_sep, fdt_rd_is_sep, fdt_rd_next_field: inline, below (the
 * .xyz loop calls them for every field). */
size_t fdt_rd_count_rest(rd_fields *f);

/* The formats (one module each). start: the text after a byte order mark.
 * The streamed ones (fdt_rd_stream_*) read c->src themselves; an ASCII
 * PLY is loaded whole into *owned (freed by the caller, c->buf points to
 * it) and parsed there. */
int fdt_rd_stream_xyz(rd_ctx *c, rd_points *pb);
/* A range of a text point file (fdt_rd_text_range): its lines are point
 * lines of ncols fields, the first numbered line0 + 1; *lines: the line
 * ends it read (may be NULL). */
int fdt_rd_stream_xyz_range(rd_ctx *c, rd_points *pb, size_t ncols, size_t line0, size_t *lines);
/* The head of a text point file in buf[0, len) (eof: the file ends there):
 * 1 when it is enough to tell fdt_rd_text_head's answers, set in *h; 0
 * when more bytes are needed. */
struct fdt_rd_head; /* src/io/read/reader.h */
int fdt_rd_xyz_head(const char *buf, size_t len, int eof, char sep, struct fdt_rd_head *h);
int fdt_rd_stream_ply(rd_ctx *c, rd_points *pb, char **owned);
int fdt_rd_read_node(const rd_ctx *c, const char *start, rd_points *pb);

/* Small helpers of every parser. */

static inline int rd_is_space(char ch)
{
    return ch == ' ' || ch == '\t' || ch == '\r' || ch == '\v' || ch == '\f';
}

static inline int rd_is_digit(char ch)
{
    return ch >= '0' && ch <= '9';
}

static inline char rd_lower(char ch)
{
    return (ch >= 'A' && ch <= 'Z') ? (char)(ch - 'A' + 'a') : ch;
}

/* Case-insensitive comparison of s[0..len) with the lowercase word w. */
static inline int rd_word_ieq(const char *s, size_t len, const char *w)
{
    size_t wl = strlen(w);
    if (len != wl)
        return 0;
    for (size_t i = 0; i < len; i++)
        if (rd_lower(s[i]) != w[i])
            return 0;
    return 1;
}

static inline int rd_tok_is(const char *s, size_t len, const char *w)
{
    return len == strlen(w) && memcmp(s, w, len) == 0;
}

/* The fields of a line (inline: the parsers' innermost loop). */

/*
 * Next field of a line: 1 and the field, 0 at the end of the line, -1 on an
 * empty field (a separator at the start or end of the line, or two with
 * nothing between). Fields are separated by whitespace and, when sep is
 * set, by at most one sep.
 */
/* Moves f->p to the start of the next field; same results as below. */
static inline int fdt_rd_skip_sep(rd_fields *f)
{
    const char *p = f->p, *e = f->e;
    while (p < e && rd_is_space(*p))
        p++;
    if (f->sep && p < e && *p == f->sep) {
        if (f->n == 0) {
            f->p = p;
            return -1;
        }
        p++;
        while (p < e && rd_is_space(*p))
            p++;
        if (p == e || *p == f->sep) {
            f->p = p;
            return -1;
        }
    }
    f->p = p;
    return p < e;
}

static inline int fdt_rd_is_sep(const rd_fields *f, const char *p)
{
    return p == f->e || rd_is_space(*p) || (f->sep && *p == f->sep);
}

static inline int fdt_rd_next_field(rd_fields *f, const char **ts, size_t *tl)
{
    int r = fdt_rd_skip_sep(f);
    if (r <= 0)
        return r;
    const char *s = f->p, *p = s;
    while (!fdt_rd_is_sep(f, p))
        p++;
    f->p = p;
    f->n++;
    *ts = s;
    *tl = (size_t)(p - s);
    return 1;
}

#endif
