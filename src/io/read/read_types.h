/*
 * What the point readers' interface (src/io/read/reader.h) and their
 * parsers (src/io/read/read_common.h) share: the FDT_IO_* status codes,
 * which the mesh writers (src/io/write) return too, and the progress
 * callback with its stages.
 */
#ifndef FDT_READ_TYPES_H
#define FDT_READ_TYPES_H

#include <stddef.h>

enum {
    FDT_IO_OK = 0,
    FDT_IO_EOPEN = -101,   /* missing file, a directory, no permission */
    FDT_IO_EFORMAT = -102, /* malformed content, NaN/Inf, count mismatch */
    FDT_IO_ENOMEM = -103,  /* allocation failed */
    FDT_IO_EWRITE = -104,  /* writing or renaming output failed */
    FDT_IO_EEXT = -105     /* unknown file extension */
};

/* Progress stages (fdt_rd_progress_fn). */
enum {
    FDT_RD_LOADING = 0, /* bytes read from the file or pipe */
    FDT_RD_PARSING = 1  /* bytes parsed */
};

/*
 * Called now and then on the calling thread while a read goes on: done
 * bytes of total (total 0 while reading a pipe, whose size is not known
 * until its end). The streamed formats (.xyz/.txt/.csv, binary .ply) parse
 * as they read and report FDT_RD_PARSING only, a block at a time; .node and
 * ASCII .ply report FDT_RD_LOADING, then FDT_RD_PARSING.
 */
typedef void (*fdt_rd_progress_fn)(void *user, int stage, size_t done, size_t total);

#endif
