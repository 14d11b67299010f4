/*
 * The output formats as one table (src/writer.c, fdt_formats): each row
 * names a format, the extensions that choose it, whether it is text, how
 * its files are laid out and one writer function per file. The writer
 * functions live in one module per format family (src/fmt_NAME.c); the
 * table, the temporary files and the renames live in src/writer.c alone.
 */
#ifndef FDT_FORMATS_H
#define FDT_FORMATS_H

#include "outfile.h"
#include "writer.h"

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

typedef struct fdt_format {
    const char *name;                  /* --format NAME */
    const char *exts[3];               /* lowercase, with the dot; for a
                                          directory its last component */
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
} fdt_format;

/* The table, terminated by a row whose name is NULL. */
extern const fdt_format fdt_formats[];

/* src/fmt_tets.c */
int fdt_put_tets(out_file *o, const fdt_mesh_view *m, const void *prep, char *err, size_t errlen);
/* src/fmt_tetgen.c */
int fdt_put_tetgen_node(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                        size_t errlen);
int fdt_put_tetgen_ele(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                       size_t errlen);
int fdt_put_tetgen_face(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                        size_t errlen);
int fdt_put_tetgen_neigh(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                         size_t errlen);
/* src/fmt_vtk.c */
int fdt_put_vtu(out_file *o, const fdt_mesh_view *m, const void *prep, char *err, size_t errlen);
int fdt_put_vtk(out_file *o, const fdt_mesh_view *m, const void *prep, char *err, size_t errlen);
/* src/fmt_gmsh.c */
int fdt_put_msh41(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                  size_t errlen);
int fdt_put_msh22(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                  size_t errlen);
/* src/fmt_medit.c */
int fdt_put_medit(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                  size_t errlen);
/* src/fmt_foam.c: prepare builds the cell-ordered faces and the compact
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

#endif
