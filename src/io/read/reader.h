/*
 * Point-cloud readers: the internal entry points behind the public
 * fdt_read_points / fdt_read_points_opts (include/frontdt.h, whose adaptor
 * is at the end of src/io/read/reader.c), used directly by the CLI and the tests.
 * Format by extension (case-insensitive): .xyz .txt (x y z per line,
 * whitespace or commas, '#' comments, exponents), .node (TetGen), .ply
 * (ascii, binary_little_endian, binary_big_endian; float or double x y z,
 * other properties and elements skipped).
 *
 * Errors name the file and the line (text) or byte offset (binary), e.g.
 *   "pts.xyz:17: expected 3 numbers, found 2"
 *   "cloud.ply: byte 1032: file ends inside vertex 40 of 1000"
 * Lines and vertices are counted from 1; offending tokens are quoted, cut
 * to 24 bytes, with non-printable bytes as \xHH.
 *
 * Details (src/io/read/read_text.c, src/io/read/read_xyz.c, src/io/read/read_node.c, src/io/read/read_ply.c):
 * - Text numbers: [+-]? (digits [. digits?] | . digits) ([eE] [+-]? digits)?
 *   correctly rounded. Rejected: hex floats, nan/inf/infinity (any case),
 *   literals beyond DBL_MAX, nonzero literals below DBL_MIN (subnormal or
 *   zero). The locale's decimal point does not matter.
 * - .xyz/.txt/.csv: fields separated by blanks and/or at most one comma (a
 *   leading, trailing or doubled comma is an error); '#' to end of line is a
 *   comment; CRLF and a UTF-8 byte order mark are accepted. Columns: x, y, z
 *   are columns 1, 2, 3 (or those of fdt_rd_opts.columns, counted from 1
 *   as cut -f and awk do); other columns (lidar intensity, colour) are
 *   skipped unread. Every point line has the column count of the first
 *   one: a line with fewer or more is an error naming it. A header: the
 *   first line with content is skipped when it is printable ASCII and none
 *   of its fields is a number ("X,Y,Z,Intensity", PDAL's '"X","Y","Z"',
 *   CloudCompare's "//X,Y,Z").
 * - Standard input: the path "-" (messages call it "stdin"); it has no
 *   extension, so fdt_rd_opts.format must name the format. Pipes, FIFOs
 *   and character devices are read to their end like files.
 * - .node: the header may leave out trailing fields as in TetGen (dim 3, 0
 *   attributes, 0 markers); every data line must have exactly index, x, y,
 *   z, the attributes and the marker; indices start at 0 or 1 and are
 *   consecutive; lines beyond the declared count are an error.
 * - .ply: one item per line in ASCII. Elements before and after "vertex"
 *   are walked and checked but not kept; the data must end exactly where
 *   the header's counts say (extra data is an error). x, y, z may be any
 *   scalar type; ASCII values are taken as written (a "float" property is
 *   not rounded to binary32); binary NaN/Inf in x, y, z is refused, in
 *   other properties ignored.
 * - Never more than INT32_MAX points (fdt_vid).
 */
#ifndef FDT_READER_H
#define FDT_READER_H

#include <stddef.h>

#include "frontdt.h"
#include "io/read/read_types.h"

/*
 * Memory: .xyz/.txt/.csv and binary .ply are streamed through a buffer of
 * fdt_rd_opts.chunk bytes (8 MiB; 2 a thread more with several threads),
 * so a read holds the points (24 bytes each) and that buffer, never the
 * file; .node and ASCII .ply are read whole first.
 *
 * Reads all points of path. On success *xyz is a malloc'd array of 3 * *n
 * doubles owned by the caller (free()). On failure *xyz is NULL, *n is 0
 * and err holds a one-line message (NUL-terminated, truncated to errlen).
 * A header count that the file size cannot hold is refused before any
 * allocation.
 */
int fdt_rd_points(const char *path, double **xyz, size_t *n, char *err,
                    size_t errlen);

/*
 * The same parse of len bytes already in memory (data: borrowed, need not
 * be NUL-terminated). name stands in for the path: its extension picks the
 * format and messages start with it. Same results and messages as
 * fdt_rd_points() on a file holding those bytes. For the fuzzers
 * (tests/fuzz/) and for callers that have the bytes already.
 */
int fdt_rd_points_mem(const char *name, const void *data, size_t len,
                        double **xyz, size_t *n, char *err, size_t errlen);

/*
 * The same reads on up to `threads` threads (1 or less: the calling thread
 * alone, as above). A .xyz/.txt text is cut at line ends into slices of at
 * least min_slice bytes (0: one megabyte), parsed at once and joined in
 * file order; the other formats are read on the calling thread. Points,
 * return codes and messages are those of the one-thread read, for every
 * thread count: a file with an error is read again on one thread to find
 * and word its first error.
 */
int fdt_rd_points_threads(const char *path, int threads, size_t min_slice, double **xyz,
                            size_t *n, char *err, size_t errlen);
int fdt_rd_points_mem_threads(const char *name, const void *data, size_t len, int threads,
                                size_t min_slice, double **xyz, size_t *n, char *err,
                                size_t errlen);

/*
 * Values given at the points (src/io/read/read_values.c; the CLI's
 * --values): n rows, k numbers each (k from the first row), into *vals
 * (malloc'd, row after row). FDT_IO_EOPEN, FDT_IO_EFORMAT (err names the
 * line: a bad number, a row of another length, too few or too many rows),
 * FDT_IO_ENOMEM.
 */
int fdt_rd_values(const char *path, size_t n, double **vals, size_t *k, char *err,
                  size_t errlen);

/* Formats (fdt_rd_opts.format). */
enum {
    FDT_RD_AUTO = 0, /* by the name's extension */
    FDT_RD_XYZ = 1,  /* .xyz .txt .csv */
    FDT_RD_NODE = 2, /* .node */
    FDT_RD_PLY = 3   /* .ply */
};

typedef struct fdt_rd_opts {
    int format;        /* FDT_RD_AUTO (by extension), or FDT_RD_XYZ/NODE/PLY */
    int columns[3];    /* x, y, z columns of the text point formats,
                          counted from 1; {0, 0, 0}: 1, 2, 3 */
    int threads;       /* as fdt_rd_points_threads */
    size_t min_slice;  /* as fdt_rd_points_threads; 0: a megabyte */
    size_t chunk;      /* bytes of the streamed reads' buffer (.xyz/.txt/
                          .csv, binary .ply); 0: 8 MiB. Results do not
                          depend on it: the tests make it tiny so that
                          lines and items straddle many refills */
    char delimiter;    /* text point formats: the character that separates
                          fields besides blanks: ',' or ';'; ' ': blanks
                          only; 0 (the default): ',', and a line that
                          mixes blank and comma separators, as decimal
                          commas do ("0,5 1,25 2"), is refused */
    int decimal_comma; /* text point formats: ',' is the decimal mark
                          ("0,5"); needs a delimiter other than ',' (its
                          default then: blanks only) */
    fdt_rd_progress_fn progress; /* may be NULL */
    void *progress_user;
    size_t fail_after; /* tests only, fdt_rd_points_mem_with's streamed
                          formats: a read reaching past this many bytes
                          fails with EIO, as read() can in the middle of
                          a file; 0 (the default): never */
} fdt_rd_opts;

/* Defaults: by extension, columns 1, 2, 3, one thread, no progress. */
void fdt_rd_opts_default(fdt_rd_opts *o);

/* The format of a name ("xyz", "txt", "csv", "node", "ply"; any case), or
 * FDT_RD_AUTO when it is none of them. */
int fdt_rd_format_by_name(const char *name);
/* The format path's extension gives, FDT_RD_AUTO if none ("-": none). */
int fdt_rd_format_of_path(const char *path);

/*
 * The reads above with options: path "-" is standard input. Columns other
 * than 1, 2, 3 with a format that has no columns (.node, .ply) are refused
 * with FDT_IO_EFORMAT. Same results and messages otherwise.
 */
int fdt_rd_points_with(const char *path, const fdt_rd_opts *o, double **xyz, size_t *n,
                         char *err, size_t errlen);
int fdt_rd_points_mem_with(const char *name, const void *data, size_t len,
                             const fdt_rd_opts *o, double **xyz, size_t *n, char *err,
                             size_t errlen);

/*
 * Text slices, for a read shared by the ranks of a distributed run
 * (src/mpi/mpi_setup.c): each rank parses its own byte range of a .xyz/.txt/
 * .csv file with the same parser as above, so its points and messages are
 * those of the whole read (line numbers given the lines before its range).
 */
typedef struct fdt_rd_head {
    size_t body;      /* the first byte that may start a point line: after
                         a byte order mark and a header line */
    size_t body_line; /* lines before body (the header's number, or 0) */
    size_t ncols;     /* fields of the first point line; 0: none (the file
                         has no points) */
    size_t size;      /* the file's bytes */
} fdt_rd_head;

/* What the head of a regular file path says (reads only until it knows). */
int fdt_rd_text_head(const char *path, fdt_rd_head *h, char *err, size_t errlen);
/* The first line start at or after byte at (at itself when it is 0, or
 * follows a '\n'; the file's size when no line starts there). */
int fdt_rd_text_line_start(const char *path, size_t at, size_t *out, char *err,
                           size_t errlen);
/*
 * Parses bytes [begin, end) of path (begin and end line starts at or
 * after the head's body, or the file's size) as point lines of ncols
 * fields whose first line is line line0 + 1; *lines: the lines in the
 * range (a last line with no line end, which only the file's last range
 * can hold, counts too, so the next range's line0 is never off). The format must be a text point format (o->format or the
 * extension); o->threads parse a block at once as above. A range with no
 * points gives *n = 0 and FDT_IO_OK; *xyz is then NULL.
 */
int fdt_rd_text_range(const char *path, const fdt_rd_opts *o, size_t begin, size_t end,
                      size_t ncols, size_t line0, double **xyz, size_t *n, size_t *lines,
                      char *err, size_t errlen);

/*
 * Binary PLY slices (the same use): a file whose elements all have a fixed
 * size and whose size is what its header says has vertex i at byte
 * vertex_off + i rec. fdt_rd_ply_find_layout: 1 and *lay for such a file, 0 for
 * any other (ASCII, lists, a bad header or size: read it whole, which
 * words what is wrong), or an FDT_IO error opening it.
 * fdt_rd_ply_range: vertices [first, first + count) into *xyz (3 doubles
 * each, malloc'd); FDT_IO_EFORMAT if a coordinate is NaN or infinite
 * (the whole read words that error as a whole read does).
 */
typedef struct fdt_rd_ply_layout {
    size_t vertex_off;  /* byte of vertex 0 */
    size_t rec;         /* bytes a vertex */
    unsigned long long count; /* vertices */
    size_t off[3];      /* bytes of x, y, z into a vertex */
    int type[3];        /* their types (src/io/read/read_ply.c) */
    int big;            /* big-endian */
} fdt_rd_ply_layout;

int fdt_rd_ply_find_layout(const char *path, fdt_rd_ply_layout *lay, char *err, size_t errlen);
int fdt_rd_ply_range(const char *path, const fdt_rd_ply_layout *lay, unsigned long long first,
                     size_t count, double **xyz, char *err, size_t errlen);

#endif
