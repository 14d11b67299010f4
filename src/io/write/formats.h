/*
 * The output formats as one table (src/io/write/writer.c, fdt_formats): each row
 * names a format, the extensions that choose it, whether it is text, how
 * its files are laid out and one writer function per file. The writer
 * functions live in one module per format family (src/fmt_NAME.c); the
 * table, the temporary files and the renames live in src/io/write/writer.c alone.
 */
#ifndef FDT_FORMATS_H
#define FDT_FORMATS_H

#include "io/write/meshview.h"
#include "io/write/outfile.h"

/* Writes one file of a format into o (a temporary the caller renames).
 * prep is what the row's prepare made (NULL without one). Returns
 * FDT_IO_OK or an FDT_IO_* code with its message in err; write errors are
 * left in o->err for the caller. */
typedef int (*fdt_put_fn)(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                          size_t errlen);

/* How a row's files are named from the output path. */
typedef enum fdt_layout {
    FDT_LAYOUT_FILE,   /* the path itself */
    FDT_LAYOUT_FAMILY, /* the path's base name with each part's extension */
    FDT_LAYOUT_DIR     /* a directory: the path, each part a file in it */
} fdt_layout;

/*
 * Streaming (issue 18): a writer that takes the tets while the front is
 * still building them, for the formats that can be laid out without the
 * whole mesh: the points are known up front, the tets and hull faces come
 * in batches, in any order, and the counts a format must state before its
 * data are left as fixed-width placeholders patched at the end
 * (out_patch). src/io/write/writer_stream.c owns the files (temporaries renamed
 * at the end, as every writer); the format fills them.
 */
typedef struct fdt_stream_out {
    out_file files[FDT_IO_MAX_FILES];
    int nfiles;              /* the row's first stream->nparts parts */
    const double *xyz;       /* during begin only */
    size_t n_points;
    uint64_t n_tets, n_hull; /* what has come so far */
    int flags;               /* FDT_STREAM_* of include/frontdt.h */
    uint64_t mark[4];        /* the format's byte offsets to patch */
    fdt_vid *hull;           /* a format that writes the hull after the
                                tets (binary) keeps it here, 3 a face */
    size_t hull_cap;
    /* A periodic run's rows spooled (.tets, src/io/write/fmt_tets.c):
     * ascending runs of 28-byte records, where each run starts, and the
     * last record's key. */
    FILE *spool;
    uint64_t *runs;
    size_t nruns, runs_cap;
    uint64_t last[4];
} fdt_stream_out;

typedef struct fdt_stream_fmt {
    int nparts; /* files written: the row's parts [0, nparts) */
    /* Writes what comes before the tets. FDT_IO_OK or a code with err. */
    int (*begin)(fdt_stream_out *s, char *err, size_t errlen);
    /* Append a batch (ids already checked in range); errors go to the
     * files' err. n_tets / n_hull count the batch only after the call. */
    void (*tets)(fdt_stream_out *s, const fdt_vid *t, size_t count);
    void (*hull)(fdt_stream_out *s, const fdt_vid *f, size_t count);
    /* Writes what follows and patches the counts; the caller closes and
     * renames. FDT_IO_OK or a code with err. */
    int (*finish)(fdt_stream_out *s, char *err, size_t errlen);
    /* A periodic run's rows (FDT_STREAM_PERIODIC): NULL where the format
     * takes none; tets NULL where it takes nothing else. */
    void (*periodic_tets)(fdt_stream_out *s, const fdt_vid *t, const int8_t *off, size_t count);
} fdt_stream_fmt;

typedef struct fdt_format {
    const char *name;                  /* --format NAME */
    const char *exts[3];               /* lowercase, with the dot; for a
                                          directory its last component.
                                          Rows may share one: the first
                                          row with it is the one a path
                                          chooses (msh before msh2) */
    const char *what;                  /* one line for --help */
    int binary;                        /* 0: text, may go to stdout */
    fdt_layout layout;
    int needs;                         /* FDT_NEED_* */
    int nparts;
    const char *parts[FDT_IO_MAX_FILES]; /* FAMILY: extensions; DIR: names */
    fdt_put_fn put[FDT_IO_MAX_FILES];
    /* Optional: computes what every part shares (NULL: nothing), freed by
     * free(). Returns FDT_IO_OK or an FDT_IO_* code with err. */
    int (*prepare)(const fdt_mesh_view *m, void **prep, const char *path, char *err,
                   size_t errlen);
    /* NULL: the format needs the whole mesh (sorted order, neighbours,
     * a face list, or counts it cannot patch); else how it streams. */
    const fdt_stream_fmt *stream;
} fdt_format;

/* The table, terminated by a row whose name is NULL. */
extern const fdt_format fdt_formats[];

/* src/io/write/writer.c, for src/io/write/writer_stream.c: a temporary for target (0 or
 * an errno), its removal, and the all-or-none close and rename of a set
 * (FDT_IO_OK or a code with err; on failure every file is abandoned). */
int fdt_out_open(out_file *o, const char *target);
void fdt_out_abandon(out_file *o);
int fdt_out_commit(out_file *files, int k, char *err, size_t errlen);
/* Removes target (a file the set no longer has: a streamed TetGen set's
 * old .neigh), with the commit when a commit set is open (writer.h),
 * else now. FDT_IO_OK (also when there is none) or a code with err. */
int fdt_out_remove_at_commit(const char *target, char *err, size_t errlen);
/* The temporary's path of a file fdt_out_open opened (NULL if none): for
 * frontdt-mpi's collective .node, which the other ranks fill with pwrite
 * before rank 0 commits it (src/mpi/mpi_output.c). */
const char *fdt_out_temp(const out_file *o);
/* The lock of the public writers (the registry of temporaries is
 * process-wide). */
void fdt_write_lock(void);
void fdt_write_unlock(void);

/* src/io/write/fmt_tets.c */
int fdt_put_tets(out_file *o, const fdt_mesh_view *m, const void *prep, char *err, size_t errlen);
/* src/io/write/fmt_tetgen.c */
int fdt_put_tetgen_node(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                        size_t errlen);
int fdt_put_tetgen_ele(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                       size_t errlen);
int fdt_put_tetgen_face(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                        size_t errlen);
int fdt_put_tetgen_neigh(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                         size_t errlen);
/* src/io/write/fmt_vtk.c */
int fdt_put_vtu(out_file *o, const fdt_mesh_view *m, const void *prep, char *err, size_t errlen);
int fdt_put_vtk(out_file *o, const fdt_mesh_view *m, const void *prep, char *err, size_t errlen);
extern const fdt_stream_fmt fdt_stream_vtu;
/* src/io/write/fmt_tets.c: a periodic run's rows, merged at the end */
extern const fdt_stream_fmt fdt_stream_tets;
/* src/io/write/fmt_tetgen.c: .node, .ele, .face (no .neigh: no neighbours) */
extern const fdt_stream_fmt fdt_stream_tetgen;
/* src/io/write/fmt_bin.c: the compact binary format (README, "Binary mesh") */
int fdt_put_bin(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                size_t errlen);
/* A periodic piece's offsets (12 a tet, 9 a hull face) and periods. */
typedef struct fdt_bin_periodic {
    const int8_t *tet_off, *hull_off;
    double period[3];
} fdt_bin_periodic;
/* One rank's piece of a distributed mesh (src/mpi/mpi_output.c,
 * src/cli/mpi_main.c): the header with flag 8 (a piece, no points: ids
 * number the n_input input points), its nt tets and nh hull faces; int64
 * ids when n_input needs them; per (or NULL): a periodic mesh's rows, flag
 * 16, the periods and offsets as in a whole periodic .fdtb. */
int fdt_put_bin_piece(out_file *o, uint64_t n_input, const fdt_vid *tets, size_t nt,
                      const fdt_vid *hull, size_t nh, const fdt_bin_periodic *per);
extern const fdt_stream_fmt fdt_stream_bin;
/* src/io/write/fmt_gmsh.c */
int fdt_put_msh41(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                  size_t errlen);
int fdt_put_msh22(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                  size_t errlen);
/* src/io/write/fmt_medit.c */
int fdt_put_medit(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                  size_t errlen);
/* src/io/write/fmt_foam.c: prepare builds the cell-ordered faces and the compact
 * point numbering the five files share. */
int fdt_foam_prepare(const fdt_mesh_view *m, void **prep, const char *path, char *err,
                     size_t errlen);
int fdt_put_foam_points(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                        size_t errlen);
int fdt_put_foam_faces(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                       size_t errlen);
int fdt_put_foam_owner(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                       size_t errlen);
int fdt_put_foam_neighbour(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                           size_t errlen);
int fdt_put_foam_boundary(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                          size_t errlen);
/* The Voronoi dual's five files (fdt_wr_dual_polymesh): prep is a
 * const fdt_dualmesh * (src/mesh/dualmesh.h), m is not read. */
int fdt_put_foam_dual_points(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                             size_t errlen);
int fdt_put_foam_dual_faces(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                            size_t errlen);
int fdt_put_foam_dual_owner(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                            size_t errlen);
int fdt_put_foam_dual_neighbour(out_file *o, const fdt_mesh_view *m, const void *prep,
                                char *err, size_t errlen);
int fdt_put_foam_dual_boundary(out_file *o, const fdt_mesh_view *m, const void *prep,
                               char *err, size_t errlen);

#endif
