/*
 * Point-cloud readers (see src/io/read/reader.h for the formats and the contract):
 * the table of formats and the entry points; the messages, point storage
 * and streamed input every parser uses are src/io/read/read_common.c. The format parsers are
 * src/io/read/read_xyz.c, src/io/read/read_node.c and src/io/read/read_ply.c; numbers, lines and
 * fields of the text formats src/io/read/read_text.c.
 *
 * Text point files and binary PLY stream from an rd_src (a descriptor or,
 * for the _mem entry points, the caller's bytes) through a bounded buffer
 * (src/io/read/read_xyz.c, src/io/read/read_ply.c); .node and ASCII PLY are read into one
 * NUL-terminated buffer and parsed in memory. Nothing proportional to a
 * header count is allocated before the bytes that back it are seen, so a
 * 100-byte file claiming four billion points costs nothing.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "io/read/reader.h"
#include "io/read/read_common.h"
#include "base/abi.h"

#include <errno.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#ifndef O_CLOEXEC
#define O_CLOEXEC 0
#endif

/* ------------------------------------------------------------------ */
/* Files                                                              */
/* ------------------------------------------------------------------ */

/*
 * The formats, one row each: the names that choose it (extensions, and
 * --input-format words) and its parser. A parser gets the text after a
 * UTF-8 byte order mark (PLY, binary, gets the whole buffer).
 */
typedef struct rd_format {
    int id;                 /* FDT_RD_* */
    const char *names[4];   /* lowercase, NULL-terminated */
    int (*parse)(const rd_ctx *c, const char *start, rd_points *pb);
    /* streamed formats (parse NULL): reads c->src; may leave a buffer it
     * loaded in *owned */
    int (*stream)(rd_ctx *c, rd_points *pb, char **owned);
    int has_columns;        /* fdt_rd_opts.columns applies */
} rd_format;

static int rd_stream_xyz(rd_ctx *c, rd_points *pb, char **owned)
{
    (void)owned;
    return fdt_rd_stream_xyz(c, pb);
}

static const rd_format rd_formats[] = {
    {FDT_RD_XYZ, {"xyz", "txt", "csv", NULL}, NULL, rd_stream_xyz, 1},
    {FDT_RD_NODE, {"node", NULL, NULL, NULL}, fdt_rd_read_node, NULL, 0},
    {FDT_RD_PLY, {"ply", NULL, NULL, NULL}, NULL, fdt_rd_stream_ply, 0},
};
#define RD_N_FORMATS (sizeof rd_formats / sizeof rd_formats[0])

static const rd_format *rd_format_row(int id)
{
    for (size_t i = 0; i < RD_N_FORMATS; i++)
        if (rd_formats[i].id == id)
            return &rd_formats[i];
    return NULL;
}

int fdt_rd_format_by_name(const char *name)
{
    if (name == NULL)
        return FDT_RD_AUTO;
    size_t len = strlen(name);
    for (size_t i = 0; i < RD_N_FORMATS; i++)
        for (const char *const *w = rd_formats[i].names; *w != NULL; w++)
            if (rd_word_ieq(name, len, *w))
                return rd_formats[i].id;
    return FDT_RD_AUTO;
}

/* The extension of path's last component ("" if none): *ext. */
static const char *rd_ext(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *base = slash != NULL ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    return dot != NULL ? dot : "";
}

int fdt_rd_format_of_path(const char *path)
{
    if (path == NULL)
        return FDT_RD_AUTO;
    const char *ext = rd_ext(path);
    return ext[0] == '.' ? fdt_rd_format_by_name(ext + 1) : FDT_RD_AUTO;
}

void fdt_rd_opts_default(fdt_rd_opts *o)
{
    memset(o, 0, sizeof *o);
    o->format = FDT_RD_AUTO;
    o->threads = 1;
}

/* Bytes read between two loading reports (and a read's largest request
 * when someone watches: one read() of a whole file would say nothing
 * until the end). */
#define RD_LOAD_CHUNK ((size_t)16 << 20)

/* Reads the whole of fd into a NUL-terminated buffer. */
static int rd_slurp(rd_ctx *c, int fd, const struct stat *st, char **out)
{
    size_t cap = 1 << 16, total = 0;
    if (S_ISREG(st->st_mode)) {
        if ((uintmax_t)st->st_size > (uintmax_t)SIZE_MAX - 2)
            return fdt_rd_fail(c, FDT_IO_ENOMEM, ": file too large for memory");
        /* one spare byte shows whether the file grew since fstat */
        cap = (size_t)st->st_size + 2;
        total = (size_t)st->st_size;
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
        size_t want = cap - 1 - len;
        if (c->progress != NULL && want > RD_LOAD_CHUNK)
            want = RD_LOAD_CHUNK;
        ssize_t r = read(fd, buf + len, want);
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
        if (c->progress != NULL)
            c->progress(c->progress_user, FDT_RD_LOADING, len, total > len ? total : len * (total > 0));
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
 * Finishes a parse that gave rc and the points in pb: on success sets *xyz
 * and *n (the array cut to its points); on failure frees pb and leaves them
 * alone (the message is in c->err).
 */
static int rd_finish(rd_ctx *c, int rc, rd_points *pb, double **xyz, size_t *n)
{
    if (rc == FDT_IO_OK && pb->n == 0)
        rc = fdt_rd_fail(c, FDT_IO_EFORMAT, ": no points");
    if (rc != FDT_IO_OK) {
        free(pb->xyz);
        return rc;
    }
    if (c->progress != NULL)
        c->progress(c->progress_user, FDT_RD_PARSING, c->size, c->size);
    if (pb->cap > pb->n) {
        double *x = realloc(pb->xyz, pb->n * 3 * sizeof(double));
        if (x != NULL) /* shrinking cannot lose data; keep the old block */
            pb->xyz = x;
    }
    *xyz = pb->xyz;
    *n = pb->n;
    return FDT_IO_OK;
}

/*
 * Parses c->buf (c->size bytes and a NUL, owned by the caller) as a file of
 * a buffered format f. On success *xyz and *n are set; on failure they are
 * left alone and the message is in c->err.
 */
static int rd_parse(rd_ctx *c, const rd_format *f, double **xyz, size_t *n)
{
    rd_points pb = {NULL, 0, 0, 0};
    int rc;
    if (c->size == 0) {
        rc = fdt_rd_fail(c, FDT_IO_EFORMAT, ": no points (empty file)");
    } else {
        const char *start = c->buf;
        /* a UTF-8 byte order mark, as some Windows tools write */
        if (c->size >= 3 && memcmp(c->buf, "\xef\xbb\xbf", 3) == 0)
            start += 3;
        rc = f->parse(c, start, &pb);
    }
    return rd_finish(c, rc, &pb, xyz, n);
}

/*
 * Streams src as a file of a streamed format f. c->size holds the size of
 * a regular file (0 when not known); it is the bytes read at the end.
 */
static int rd_stream(rd_ctx *c, const rd_format *f, rd_src *src, double **xyz, size_t *n)
{
    rd_points pb = {NULL, 0, 0, 0};
    char *owned = NULL;
    c->src = src;
    int rc = f->stream(c, &pb, &owned);
    free(owned);
    c->buf = NULL;
    c->size = src->pos;
    c->size_known = 1;
    c->src = NULL;
    return rd_finish(c, rc, &pb, xyz, n);
}

/* Why a delimiter and decimal mark cannot be read together, or NULL. */
static const char *rd_sep_refusal(char delimiter, int decimal_comma)
{
    if (delimiter != 0 && delimiter != ',' && delimiter != ';' && delimiter != ' ')
        return "the delimiter is ',', ';' or ' ' (blanks only)";
    if (decimal_comma && delimiter == ',')
        return "a decimal comma cannot also separate fields (delimiter ';' or ' ')";
    return NULL;
}

/*
 * Sets up c from the options and picks the format: the one the options
 * name, else the name's extension's. NULL after wording the refusal (an
 * unknown extension, columns for a format without them) in c->err.
 */
static const rd_format *rd_setup(rd_ctx *c, const char *name, const fdt_rd_opts *o, int *rc)
{
    c->threads = o->threads;
    c->min_slice = o->min_slice;
    c->chunk = o->chunk;
    c->progress = o->progress;
    c->progress_user = o->progress_user;
    c->progress_scale = 1;
    int custom = o->columns[0] != 0 || o->columns[1] != 0 || o->columns[2] != 0;
    for (int k = 0; k < 3; k++) {
        if (custom && o->columns[k] < 1) {
            *rc = fdt_rd_fail(c, FDT_IO_EFORMAT, ": column %d is not a column (they count from 1)",
                              o->columns[k]);
            return NULL;
        }
        c->col[k] = custom ? o->columns[k] - 1 : k;
    }
    c->custom_cols = custom && !(c->col[0] == 0 && c->col[1] == 1 && c->col[2] == 2);
    /* The separator and the decimal mark (README, "Separators"). */
    const char *why = rd_sep_refusal(o->delimiter, o->decimal_comma);
    if (why != NULL) {
        *rc = fdt_rd_fail(c, FDT_IO_EFORMAT, ": %s", why);
        return NULL;
    }
    c->decimal_comma = o->decimal_comma != 0;
    c->sep_guard = o->delimiter == 0 && !o->decimal_comma;
    c->sep = o->delimiter == ' ' ? 0 : o->delimiter != 0 ? o->delimiter : o->decimal_comma ? 0 : ',';
    int id = o->format != FDT_RD_AUTO ? o->format : fdt_rd_format_of_path(name);
    const rd_format *f = rd_format_row(id);
    if (f == NULL) {
        char q[RD_QUOTE_CAP];
        const char *ext = rd_ext(name);
        if (strcmp(name, "-") == 0)
            *rc = fdt_rd_fail(c, FDT_IO_EEXT, ": standard input needs its format named "
                                              "(xyz, node or ply)");
        else
            *rc = fdt_rd_fail(c, FDT_IO_EEXT,
                              ": unknown extension %s (expected .xyz, .txt, .csv, .node or "
                              ".ply)",
                              fdt_rd_quote(q, ext, strlen(ext)));
        return NULL;
    }
    if (c->custom_cols && !f->has_columns) {
        *rc = fdt_rd_fail(c, FDT_IO_EFORMAT, ": columns apply to .xyz, .txt and .csv only");
        return NULL;
    }
    if ((o->delimiter != 0 || o->decimal_comma) && !f->has_columns) {
        *rc = fdt_rd_fail(c, FDT_IO_EFORMAT,
                          ": a delimiter or decimal comma applies to .xyz, .txt and .csv only");
        return NULL;
    }
    return f;
}

int fdt_rd_points_with(const char *path, const fdt_rd_opts *o, double **xyz, size_t *n,
                         char *err, size_t errlen)
{
    int is_stdin = path != NULL && strcmp(path, "-") == 0;
    rd_ctx c;
    rd_ctx_start(&c, path == NULL ? "(null)" : is_stdin ? "stdin" : path, err, errlen);
    rd_begin(&c, xyz, n);
    if (path == NULL || o == NULL || xyz == NULL || n == NULL)
        return fdt_rd_fail(&c, FDT_IO_EOPEN, ": invalid arguments");

    int fd = STDIN_FILENO;
    if (!is_stdin) {
        do
            fd = open(path, O_RDONLY | O_CLOEXEC);
        while (fd < 0 && errno == EINTR);
        if (fd < 0)
            return fdt_rd_fail(&c, FDT_IO_EOPEN, ": cannot open: %s", strerror(errno));
    }
    struct stat st;
    int rc = FDT_IO_OK;
    const rd_format *f = NULL;
    char *buf = NULL;
    if (fstat(fd, &st) != 0)
        rc = fdt_rd_fail(&c, FDT_IO_EOPEN, ": cannot open: %s", strerror(errno));
    else if (S_ISDIR(st.st_mode))
        rc = fdt_rd_fail(&c, FDT_IO_EOPEN, ": is a directory");
    else if ((f = rd_setup(&c, path, o, &rc)) != NULL && f->stream == NULL)
        rc = rd_slurp(&c, fd, &st, &buf);
    if (rc == FDT_IO_OK && f != NULL && f->stream != NULL) {
        rd_src src = {.fd = fd};
        if (S_ISREG(st.st_mode)) /* a hint for readahead: failure is harmless */
            (void)posix_fadvise(fd, 0, 0, POSIX_FADV_SEQUENTIAL);
        c.size_known = S_ISREG(st.st_mode) && (uintmax_t)st.st_size <= SIZE_MAX;
        c.size = c.size_known ? (size_t)st.st_size : 0;
        rc = rd_stream(&c, f, &src, xyz, n);
        if (!is_stdin)
            close(fd);
        return rc;
    }
    if (!is_stdin)
        close(fd);
    if (rc != FDT_IO_OK)
        return rc;
    rc = rd_parse(&c, f, xyz, n);
    free(buf);
    return rc;
}

int fdt_rd_points_mem_with(const char *name, const void *data, size_t len,
                             const fdt_rd_opts *o, double **xyz, size_t *n, char *err,
                             size_t errlen)
{
    rd_ctx c;
    rd_ctx_start(&c, name != NULL ? name : "(null)", err, errlen);
    rd_begin(&c, xyz, n);
    if (name == NULL || o == NULL || (data == NULL && len > 0) || xyz == NULL || n == NULL)
        return fdt_rd_fail(&c, FDT_IO_EOPEN, ": invalid arguments");
    /* No object is larger than PTRDIFF_MAX bytes (C11 6.5.6): a longer
     * length is a caller's mistake, refused before any byte is read. */
    if (len > PTRDIFF_MAX)
        return fdt_rd_fail(&c, FDT_IO_ENOMEM, ": file too large for memory");
    int rc = FDT_IO_OK;
    const rd_format *f = rd_setup(&c, name, o, &rc);
    if (f == NULL)
        return rc;
    if (f->stream != NULL) {
        /* the streamed formats copy the bytes chunk by chunk, as they
         * would read them from a file */
        rd_src src = {.fd = -1, .mem = data, .mem_len = len, .fail_after = o->fail_after};
        c.size = len;
        c.size_known = 1;
        return rd_stream(&c, f, &src, xyz, n);
    }
    /* The buffered parsers expect what rd_slurp gives them: a private copy with a
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
    rc = rd_parse(&c, f, xyz, n);
    free(buf);
    return rc;
}

int fdt_rd_points(const char *path, double **xyz, size_t *n, char *err,
                    size_t errlen)
{
    return fdt_rd_points_threads(path, 1, 0, xyz, n, err, errlen);
}

int fdt_rd_points_threads(const char *path, int threads, size_t min_slice, double **xyz,
                            size_t *n, char *err, size_t errlen)
{
    fdt_rd_opts o;
    fdt_rd_opts_default(&o);
    o.threads = threads;
    o.min_slice = min_slice;
    return fdt_rd_points_with(path, &o, xyz, n, err, errlen);
}

int fdt_rd_points_mem(const char *name, const void *data, size_t len,
                        double **xyz, size_t *n, char *err, size_t errlen)
{
    return fdt_rd_points_mem_threads(name, data, len, 1, 0, xyz, n, err, errlen);
}

int fdt_rd_points_mem_threads(const char *name, const void *data, size_t len, int threads,
                                size_t min_slice, double **xyz, size_t *n, char *err,
                                size_t errlen)
{
    fdt_rd_opts o;
    fdt_rd_opts_default(&o);
    o.threads = threads;
    o.min_slice = min_slice;
    return fdt_rd_points_mem_with(name, data, len, &o, xyz, n, err, errlen);
}

/* ------------------------------------------------------------------ */
/* The public reader (include/frontdt.h): an adaptor over the above    */
/* ------------------------------------------------------------------ */

/* The fdt_read_options sizes this library accepts (include/frontdt.h,
 * ABI): this release's, and 0.1's, which ended before delimiter. */
#define READ_OPTIONS_0_1_SIZE offsetof(fdt_read_options, delimiter)
static int read_options_size_known(size_t size)
{
    return size == sizeof(fdt_read_options) || size == READ_OPTIONS_0_1_SIZE;
}

int fdt_default_read_options_sized(fdt_read_options *o, size_t struct_size)
{
    return fdt_abi_reset(o, struct_size, read_options_size_known(struct_size));
}

/* The public callback behind the reader's own (sizes widened). */
typedef struct rd_public_progress {
    fdt_io_progress_fn fn;
    void *user;
} rd_public_progress;

static void rd_progress_adaptor(void *user, int stage, size_t done, size_t total)
{
    const rd_public_progress *p = user;
    p->fn(p->user, stage == FDT_RD_LOADING ? FDT_STAGE_LOAD : FDT_STAGE_PARSE,
          (uint64_t)done, (uint64_t)total);
}

/* A refusal of the public reader before any file is touched. */
static int rd_refuse(char *diag, size_t diag_size, const char *path, const char *fmt,
                     const char *arg)
{
    if (diag != NULL && diag_size > 0) {
        char q[RD_QUOTE_CAP];
        const char *shown = arg != NULL ? fdt_rd_quote(q, arg, strlen(arg)) : "";
        int k = snprintf(diag, diag_size, "%s: ",
                         path == NULL ? "(null)" : strcmp(path, "-") == 0 ? "stdin" : path);
        size_t used = k < 0 ? 0 : (size_t)k < diag_size ? (size_t)k : diag_size - 1;
        snprintf(diag + used, diag_size - used, fmt, shown);
    }
    return FDT_EINVAL;
}

int fdt_read_points_opts(const char *path, const fdt_read_options *o, double **xyz, size_t *n,
                         char *diag, size_t diag_size)
{
    if (xyz != NULL)
        *xyz = NULL;
    if (n != NULL)
        *n = 0;
    if (diag != NULL && diag_size > 0)
        diag[0] = '\0';
    fdt_read_options defaults;
    if (o == NULL) {
        fdt_default_read_options(&defaults);
        o = &defaults;
    }
    if (path == NULL || xyz == NULL || n == NULL || (diag == NULL && diag_size > 0))
        return rd_refuse(diag, diag_size, path, "a NULL argument%s", NULL);
    if (!read_options_size_known(o->struct_size))
        return rd_refuse(diag, diag_size, path,
                         "fdt_read_options of an unknown size (fdt_default_read_options "
                         "sets it)%s", NULL);
    fdt_rd_opts ro;
    fdt_rd_opts_default(&ro);
    if (o->format != NULL) {
        ro.format = fdt_rd_format_by_name(o->format);
        if (ro.format == FDT_RD_AUTO)
            return rd_refuse(diag, diag_size, path,
                             "unknown format %s (xyz, txt, csv, node or ply)", o->format);
    }
    /* The refusals the internal reader words as malformed input are the
     * caller's argument here: say them first, as FDT_EINVAL. */
    int custom = o->columns[0] != 0 || o->columns[1] != 0 || o->columns[2] != 0;
    for (int k = 0; k < 3 && custom; k++)
        if (o->columns[k] < 1)
            return rd_refuse(diag, diag_size, path,
                             "a column below 1 (they count from 1)%s", NULL);
    int id = ro.format != FDT_RD_AUTO ? ro.format : fdt_rd_format_of_path(path);
    if (custom && !(o->columns[0] == 1 && o->columns[1] == 2 && o->columns[2] == 3) &&
        id != FDT_RD_AUTO && id != FDT_RD_XYZ)
        return rd_refuse(diag, diag_size, path,
                         "columns apply to .xyz, .txt and .csv only%s", NULL);
    memcpy(ro.columns, o->columns, sizeof ro.columns);
    if (o->struct_size > READ_OPTIONS_0_1_SIZE) {
        ro.delimiter = o->delimiter;
        ro.decimal_comma = o->decimal_comma;
        const char *why = rd_sep_refusal(ro.delimiter, ro.decimal_comma);
        if (why != NULL)
            return rd_refuse(diag, diag_size, path, why, NULL); /* no % in why */
    }
    ro.threads = o->n_threads > 1 ? o->n_threads : 1;
    rd_public_progress pp = {o->progress, o->progress_user};
    if (o->progress != NULL) {
        ro.progress = rd_progress_adaptor;
        ro.progress_user = &pp;
    }
    int rc = fdt_rd_points_with(path, &ro, xyz, n, diag, diag_size);
    switch (rc) {
    case FDT_IO_OK:
        return FDT_OK;
    case FDT_IO_EOPEN:
        return FDT_EIO;
    case FDT_IO_ENOMEM:
        return FDT_ENOMEM;
    case FDT_IO_EEXT:
        return FDT_EINVAL;
    default: /* FDT_IO_EFORMAT */
        return FDT_EFORMAT;
    }
}

int fdt_read_points(const char *path, const char *format, double **xyz, size_t *n, char *diag,
                    size_t diag_size)
{
    fdt_read_options o;
    fdt_default_read_options(&o);
    o.format = format;
    return fdt_read_points_opts(path, &o, xyz, n, diag, diag_size);
}

/* ------------------------------------------------------------------ */
/* Text slices (src/io/read/reader.h; src/mpi/mpi_setup.c)                        */
/* ------------------------------------------------------------------ */

/* Opens path for a slice read: the descriptor, or -1 with c's message. */
static int rd_open_regular(rd_ctx *c, const char *path, struct stat *st)
{
    int fd;
    do
        fd = open(path, O_RDONLY | O_CLOEXEC);
    while (fd < 0 && errno == EINTR);
    if (fd < 0) {
        fdt_rd_fail(c, FDT_IO_EOPEN, ": cannot open: %s", strerror(errno));
        return -1;
    }
    if (fstat(fd, st) != 0 || !S_ISREG(st->st_mode) || (uintmax_t)st->st_size > SIZE_MAX) {
        fdt_rd_fail(c, FDT_IO_EOPEN, ": not a regular file");
        close(fd);
        return -1;
    }
    return fd;
}

/* pread until len bytes or the end; the bytes read, or -1 (message). */
static ptrdiff_t rd_pread_all(rd_ctx *c, int fd, char *dst, size_t len, size_t off)
{
    size_t got = 0;
    while (got < len) {
        size_t want = len - got < RD_READ_MAX ? len - got : RD_READ_MAX;
        ssize_t r = pread(fd, dst + got, want, (off_t)(off + got));
        if (r == 0)
            break;
        if (r < 0) {
            if (errno == EINTR)
                continue;
            fdt_rd_fail(c, FDT_IO_EOPEN, ": cannot read: %s", strerror(errno));
            return -1;
        }
        got += (size_t)r;
    }
    return (ptrdiff_t)got;
}

int fdt_rd_text_head(const char *path, fdt_rd_head *h, char *err, size_t errlen)
{
    rd_ctx c;
    rd_ctx_start(&c, path, err, errlen);
    rd_begin(&c, NULL, NULL);
    memset(h, 0, sizeof *h);
    struct stat st;
    int fd = rd_open_regular(&c, path, &st);
    if (fd < 0)
        return FDT_IO_EOPEN;
    size_t size = (size_t)st.st_size, cap = RD_FIRST_CHUNK, len = 0;
    char *buf = NULL;
    int rc = FDT_IO_OK;
    /* The head is a few lines: read more only while they are not whole. */
    for (;;) {
        char *nb = realloc(buf, cap);
        if (nb == NULL) {
            rc = fdt_rd_fail(&c, FDT_IO_ENOMEM, ": out of memory");
            break;
        }
        buf = nb;
        ptrdiff_t r = rd_pread_all(&c, fd, buf + len, cap - len, len);
        if (r < 0) {
            rc = FDT_IO_EOPEN;
            break;
        }
        len += (size_t)r;
        int eof = len >= size || len < cap;
        if (fdt_rd_xyz_head(buf, len, eof, c.sep, h))
            break;
        if (cap > SIZE_MAX / 2) {
            rc = fdt_rd_fail(&c, FDT_IO_ENOMEM, ": out of memory");
            break;
        }
        cap *= 2;
    }
    h->size = size;
    free(buf);
    close(fd);
    return rc;
}

int fdt_rd_text_line_start(const char *path, size_t at, size_t *out, char *err, size_t errlen)
{
    rd_ctx c;
    rd_ctx_start(&c, path, err, errlen);
    rd_begin(&c, NULL, NULL);
    struct stat st;
    int fd = rd_open_regular(&c, path, &st);
    if (fd < 0)
        return FDT_IO_EOPEN;
    size_t size = (size_t)st.st_size;
    int rc = FDT_IO_OK;
    if (at == 0 || at >= size) {
        *out = at < size ? at : size;
        close(fd);
        return rc;
    }
    /* from the byte before at: a '\n' there makes at a line start */
    char buf[1 << 16];
    size_t pos = at - 1;
    *out = size;
    while (pos < size) {
        ptrdiff_t r = rd_pread_all(&c, fd, buf, sizeof buf, pos);
        if (r <= 0) {
            rc = r < 0 ? FDT_IO_EOPEN : FDT_IO_OK;
            break;
        }
        const char *nl = memchr(buf, '\n', (size_t)r);
        if (nl != NULL) {
            *out = pos + (size_t)(nl - buf) + 1;
            break;
        }
        pos += (size_t)r;
    }
    close(fd);
    return rc;
}

int fdt_rd_text_range(const char *path, const fdt_rd_opts *o, size_t begin, size_t end,
                      size_t ncols, size_t line0, double **xyz, size_t *n, size_t *lines,
                      char *err, size_t errlen)
{
    rd_ctx c;
    rd_ctx_start(&c, path, err, errlen);
    rd_begin(&c, xyz, n);
    *lines = 0;
    int rc = FDT_IO_OK;
    const rd_format *f = rd_setup(&c, path, o, &rc);
    if (f == NULL)
        return rc;
    if (f->id != FDT_RD_XYZ)
        return fdt_rd_fail(&c, FDT_IO_EFORMAT, ": not a text point format");
    c.progress = NULL;
    struct stat st;
    int fd = rd_open_regular(&c, path, &st);
    if (fd < 0)
        return FDT_IO_EOPEN;
    if (end > (size_t)st.st_size)
        end = (size_t)st.st_size;
    if (begin > end)
        begin = end;
    if (lseek(fd, (off_t)begin, SEEK_SET) < 0) {
        rc = fdt_rd_fail(&c, FDT_IO_EOPEN, ": cannot seek: %s", strerror(errno));
        close(fd);
        return rc;
    }
    rd_src src = {.fd = fd, .eof = end == begin, .bounded = 1, .left = end - begin};
    c.src = &src;
    c.size = end - begin;
    c.size_known = 1;
    rd_points pb = {NULL, 0, 0, 0};
    rc = fdt_rd_stream_xyz_range(&c, &pb, ncols, line0, lines);
    close(fd);
    if (rc != FDT_IO_OK || pb.n == 0) {
        free(pb.xyz);
        return rc;
    }
    *xyz = pb.xyz;
    *n = pb.n;
    return FDT_IO_OK;
}
