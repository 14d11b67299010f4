/*
 * Streaming writers (include/frontdt.h, fdt_stream_writer_*; issue 18):
 * a mesh file filled while the front still builds the tets, so the mesh is
 * never held (DESIGN.md, Output: a tet is final when built). The format
 * lays the bytes out (src/io/write/formats.h, fdt_stream_fmt, in src/fmt_*.c); this
 * module owns the files: the same temporaries beside the targets, the
 * same all-or-none rename at the commit and the same signal cleanup
 * (fdt_write_cleanup) as src/io/write/writer.c, whose registry it uses.
 */
#include "io/write/formats.h"
#include "io/write/writer.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

struct fdt_stream_writer {
    fdt_stream_out s;
    const fdt_format *f;
    int failed;         /* a sink call failed: the commit refuses */
    int code;           /* its FDT_E* code */
    char diag[1024];    /* its message */
    char stale[FDT_IO_PATH]; /* a part the stream does not write, removed
                                at the commit ("" when none) */
    char names[FDT_IO_MAX_FILES][FDT_IO_PATH]; /* the targets, named by
                                the files' messages */
};

static int public_code(int io)
{
    switch (io) {
    case FDT_IO_OK:
        return FDT_OK;
    case FDT_IO_ENOMEM:
        return FDT_ENOMEM;
    case FDT_IO_EEXT:
        return FDT_EINVAL;
    case FDT_IO_EWRITE:
        return FDT_EIO;
    default:
        return FDT_EINTERNAL;
    }
}

static const fdt_format *pick(const char *path, const char *format)
{
    return format ? fdt_format_by_name(format) : fdt_format_by_path(path);
}

int fdt_stream_format_ok(const char *path, const char *format)
{
    const fdt_format *f = pick(path, format);
    if (!f)
        return FDT_EINVAL;
    return f->stream != NULL && f->stream->tets && f->layout != FDT_LAYOUT_DIR;
}

static void abandon_all(fdt_stream_writer *w)
{
    for (int i = 0; i < w->s.nfiles; i++)
        fdt_out_abandon(&w->s.files[i]);
    w->s.nfiles = 0;
}

static void writer_free(fdt_stream_writer *w)
{
    free(w->s.hull);
    free(w->s.runs);
    if (w->s.spool)
        fclose(w->s.spool);
    free(w);
}

int fdt_stream_writer_open(fdt_stream_writer **wp, const char *path, const char *format,
                           const double *xyz, size_t n, int flags, char *diag,
                           size_t diag_size)
{
    if (diag && diag_size > 0)
        diag[0] = '\0';
    if (!wp || !path || (!xyz && n > 0) || (!diag && diag_size > 0))
        return set_err(diag, diag_size, FDT_EINVAL, path, "a NULL argument");
    *wp = NULL;
    const fdt_format *f = pick(path, format);
    if (!f) {
        char what[700];
        snprintf(what, sizeof what, "unknown output format (use %s)", fdt_format_list());
        return set_err(diag, diag_size, FDT_EINVAL, path, what);
    }
    int periodic = (flags & FDT_STREAM_PERIODIC) != 0;
    if (!f->stream || !(periodic ? f->stream->periodic_tets != NULL : f->stream->tets != NULL)) {
        char what[160];
        snprintf(what, sizeof what, "format %s cannot be streamed (%s)", f->name,
                 periodic ? "a periodic run's rows stream to tets" : "tetgen, vtu and bin can");
        return set_err(diag, diag_size, FDT_EINVAL, path, what);
    }
    if (flags & ~(FDT_STREAM_IDS64 | FDT_STREAM_NO_POINTS | FDT_STREAM_PERIODIC))
        return set_err(diag, diag_size, FDT_EINVAL, path, "unknown stream flags");
    fdt_stream_writer *w = calloc(1, sizeof *w);
    if (!w)
        return set_err(diag, diag_size, FDT_ENOMEM, path, "out of memory");
    char (*names)[FDT_IO_PATH] = w->names;
    int k = fdt_output_files_as(path, f, names);
    if (k != f->nparts) {
        free(w);
        return set_err(diag, diag_size, FDT_EIO, path, strerror(ENAMETOOLONG));
    }
    w->f = f;
    w->s.n_points = n;
    w->s.flags = flags;
    w->s.xyz = xyz;
    if (f->stream->nparts < k)
        memcpy(w->stale, names[f->stream->nparts], sizeof w->stale); /* .neigh */
    int rc = FDT_OK;
    fdt_write_lock();
    for (int i = 0; i < f->stream->nparts; i++) {
        int e = fdt_out_open(&w->s.files[i], names[i]);
        if (e) {
            abandon_all(w);
            rc = fdt_create_err(diag, diag_size, "output", names[i], e);
            break;
        }
        w->s.nfiles = i + 1;
    }
    fdt_write_unlock();
    if (rc != FDT_IO_OK) {
        writer_free(w);
        return public_code(rc);
    }
    int r = f->stream->begin(&w->s, diag, diag_size);
    w->s.xyz = NULL;
    int e = 0;
    for (int i = 0; i < w->s.nfiles && !e; i++)
        e = w->s.files[i].err;
    if (r == FDT_IO_OK && e)
        r = set_errno_err(diag, diag_size, w->names[0], e);
    if (r != FDT_IO_OK) {
        fdt_write_lock();
        abandon_all(w);
        fdt_write_unlock();
        writer_free(w);
        return public_code(r);
    }
    *wp = w;
    return FDT_OK;
}

/* The first error of any file, as an FDT_E* code with its message kept. */
static int check_files(fdt_stream_writer *w)
{
    if (w->failed)
        return w->code;
    for (int i = 0; i < w->s.nfiles; i++) {
        int e = w->s.files[i].err;
        if (e) {
            w->failed = 1;
            w->code = public_code(set_errno_err(w->diag, sizeof w->diag, w->s.files[i].path, e));
            return w->code;
        }
    }
    return FDT_OK;
}

/* Ids outside 0..n-1 are a caller's bug; refuse rather than write a file
 * that names points it does not have. */
static int ids_ok(fdt_stream_writer *w, const fdt_vid *v, size_t count, const char *what)
{
    for (size_t i = 0; i < count; i++) {
        if (v[i] < 0 || (size_t)v[i] >= w->s.n_points) {
            char m[160];
            snprintf(m, sizeof m, "%s uses vertex %ld, outside 0..%zu", what, (long)v[i],
                     w->s.n_points);
            w->failed = 1;
            w->code = FDT_EINVAL;
            set_err(w->diag, sizeof w->diag, 0, w->s.files[0].path, m);
            return 0;
        }
    }
    return 1;
}

/* A batch the writer cannot take: NULL, or rows of the other kind (a
 * periodic run's to a plain writer, or the reverse). */
static int batch_ok(fdt_stream_writer *w, const void *rows, size_t count, int periodic,
                    const char *what)
{
    const char *why = count > 0 && !rows ? "is NULL"
                      : periodic != ((w->s.flags & FDT_STREAM_PERIODIC) != 0)
                          ? (periodic ? "of a periodic run, to a writer opened without "
                                        "FDT_STREAM_PERIODIC"
                                      : "without offsets, to a writer opened with "
                                        "FDT_STREAM_PERIODIC")
                          : NULL;
    if (!why)
        return 1;
    char m[160];
    snprintf(m, sizeof m, "a batch of %s %s", what, why);
    w->failed = 1;
    w->code = FDT_EINVAL;
    set_err(w->diag, sizeof w->diag, 0, w->s.files[0].path, m);
    return 0;
}

static int sink_tets(void *user, const fdt_vid *tets, size_t count)
{
    fdt_stream_writer *w = user;
    if (w->failed)
        return w->code;
    if (!batch_ok(w, tets, count, 0, "tets") || !ids_ok(w, tets, 4 * count, "a tet"))
        return w->code;
    w->f->stream->tets(&w->s, tets, count);
    w->s.n_tets += count;
    return check_files(w);
}

static int sink_periodic_tets(void *user, const fdt_vid *tets, const int8_t *offsets,
                              size_t count)
{
    fdt_stream_writer *w = user;
    if (w->failed)
        return w->code;
    if (!batch_ok(w, tets, count, 1, "tets") || !batch_ok(w, offsets, count, 1, "offsets") ||
        !ids_ok(w, tets, 4 * count, "a tet"))
        return w->code;
    w->f->stream->periodic_tets(&w->s, tets, offsets, count);
    w->s.n_tets += count;
    return check_files(w);
}

/* A periodic run's hull faces: counted (.tets has no place for them). */
static int sink_periodic_hull(void *user, const fdt_vid *faces, const int8_t *offsets,
                              size_t count)
{
    fdt_stream_writer *w = user;
    if (w->failed)
        return w->code;
    if (!batch_ok(w, faces, count, 1, "hull faces") ||
        !batch_ok(w, offsets, count, 1, "offsets") || !ids_ok(w, faces, 3 * count, "a hull face"))
        return w->code;
    w->s.n_hull += count;
    return FDT_OK;
}

static int sink_hull(void *user, const fdt_vid *faces, size_t count)
{
    fdt_stream_writer *w = user;
    if (w->failed)
        return w->code;
    if (!batch_ok(w, faces, count, 0, "hull faces") || !ids_ok(w, faces, 3 * count, "a hull face"))
        return w->code;
    if (w->f->stream->hull)
        w->f->stream->hull(&w->s, faces, count);
    w->s.n_hull += count;
    return check_files(w);
}

int fdt_stream_writer_sink(fdt_stream_writer *w, fdt_sink *sink)
{
    if (!w || !sink)
        return FDT_EINVAL;
    memset(sink, 0, sizeof *sink);
    sink->struct_size = sizeof *sink;
    sink->tets = sink_tets;
    sink->hull = sink_hull;
    sink->user = w;
    sink->periodic_tets = sink_periodic_tets;
    sink->periodic_hull = sink_periodic_hull;
    return FDT_OK;
}

void fdt_stream_writer_counts(const fdt_stream_writer *w, uint64_t *tets, uint64_t *hull)
{
    if (tets)
        *tets = w ? w->s.n_tets : 0;
    if (hull)
        *hull = w ? w->s.n_hull : 0;
}

int fdt_stream_writer_close(fdt_stream_writer **wp, int commit, char *diag, size_t diag_size)
{
    if (diag && diag_size > 0)
        diag[0] = '\0';
    if (!wp || !*wp)
        return FDT_EINVAL;
    fdt_stream_writer *w = *wp;
    *wp = NULL;
    int rc = FDT_OK;
    if (w->failed) {
        rc = w->code;
        if (diag && diag_size > 0)
            snprintf(diag, diag_size, "%s", w->diag);
        commit = 0;
    }
    if (commit) {
        int r = w->f->stream->finish(&w->s, diag, diag_size);
        if (r == FDT_IO_OK && (rc = check_files(w)) != FDT_OK) {
            if (diag && diag_size > 0)
                snprintf(diag, diag_size, "%s", w->diag);
            commit = 0;
        } else if (r != FDT_IO_OK) {
            rc = public_code(r);
            commit = 0;
        }
    }
    fdt_write_lock();
    if (commit) {
        char err[1024];
        int r = fdt_out_commit(w->s.files, w->s.nfiles, err, sizeof err);
        if (r != FDT_IO_OK) {
            rc = public_code(r);
            if (diag && diag_size > 0)
                snprintf(diag, diag_size, "%s", err);
        } else if (w->stale[0] &&
                   fdt_out_remove_at_commit(w->stale, err, sizeof err) != FDT_IO_OK) {
            /* the new .ele stands beside an old .neigh: say so, as a
             * failed write (the mesh files themselves are complete) */
            rc = FDT_EIO;
            if (diag && diag_size > 0)
                snprintf(diag, diag_size, "%s", err);
        }
    } else {
        abandon_all(w);
    }
    fdt_write_unlock();
    writer_free(w);
    return rc;
}
