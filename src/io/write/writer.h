/*
 * Mesh writers: the internal entry points behind the public fdt_write_mesh
 * (include/frontdt.h; its adaptor is at the end of src/io/write/writer.c), used
 * directly by the CLI and the tests.
 * Every file is written to a temporary file in the same directory and
 * renamed over the target only when complete: an interrupted or failed run
 * leaves no partial output. fdt_io_cleanup_temps() is async-signal-safe and
 * removes every temporary file still open (for SIGINT/SIGTERM handlers).
 */
#ifndef FDT_WRITER_H
#define FDT_WRITER_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include "frontdt.h"
#include "io/write/meshview.h"

typedef struct fdt_format fdt_format; /* a row of src/io/write/formats.h's table */

/* What a row needs in the fdt_mesh_view beyond points and tets. */
enum {
    FDT_NEED_NBRS = 1,  /* tet neighbours */
    FDT_NEED_FACES = 2, /* the face list (fdt_result_faces) */
    FDT_NEED_SORTED = 4 /* canonical tet order (fdt_result_sort) */
};


/* The row named name (--format), or NULL. */
const fdt_format *fdt_format_by_name(const char *name);
/* The row path's extension chooses (a directory format: its last
 * component, "polyMesh"), or NULL. */
const fdt_format *fdt_format_by_path(const char *path);
/* When a path's extension names another format than f (--format msh2
 * with m.vtu): the row the extension chooses; NULL when it agrees (one
 * of f's extensions: msh2 shares .msh with msh) or names no format. */
const fdt_format *fdt_format_contradicted(const char *path, const fdt_format *f);
/* The row's name and whether it is text (may go to standard output). */
const char *fdt_format_name(const fdt_format *f);
int fdt_format_is_text(const fdt_format *f);
/* Whether writing with f needs tet neighbours, the face list, canonical
 * order (FDT_NEED_* of src/io/write/formats.h, or'ed). */
int fdt_format_needs(const fdt_format *f, int all_faces);
/* Whether f streams a periodic run's rows (FDT_STREAM_PERIODIC: .tets). */
int fdt_format_periodic_stream(const fdt_format *f);
/* "name (.ext, .ext)" of every row, comma separated, for messages. */
const char *fdt_format_list(void);

/*
 * Writes the mesh in the format given by path's extension:
 *   .tets  canonical text: one tet per line, its 4 ids ascending, lines in
 *          ascending order. The tets must already be in canonical order
 *          (fdt_result_sort); this is verified, not assumed.
 *   .ele   TetGen: BASE.node, BASE.ele, BASE.face, BASE.neigh, 0-based.
 *   .vtu   VTK XML UnstructuredGrid (ParaView), every input point.
 *   .vtk   VTK legacy unstructured grid.
 * Returns FDT_IO_OK or an FDT_IO_* code with a message in err.
 */
int fdt_wr_mesh(const char *path, const fdt_mesh_view *m, char *err,
                   size_t errlen);
/* The same in format f (NULL: by path's extension). A directory format
 * (OpenFOAM polyMesh) is written to a temporary directory beside path and
 * renamed to path at the end when path does not exist yet; when path is an
 * existing directory, each of its files is replaced by its own
 * temporary-and-rename, all or none (other files there are left alone). */
int fdt_wr_mesh_as(const char *path, const fdt_format *f, const fdt_mesh_view *m,
                      char *err, size_t errlen);
/* fdt_wr_mesh_as reporting the bytes written through progress (NULL:
 * none), stage FDT_STAGE_WRITE, done of an estimated total
 * (fdt_wr_estimate) summed over the output's files. */
int fdt_wr_mesh_ex(const char *path, const fdt_format *f, const fdt_mesh_view *m,
                   fdt_io_progress_fn progress, void *progress_user, char *err, size_t errlen);
/* The Voronoi dual d (src/mesh/dualmesh.h) as an OpenFOAM polyMesh at
 * path (a directory), as fdt_wr_mesh_as writes one: a new directory
 * renamed into place, or an existing one's five files replaced, all or
 * none; in the commit set when one is open. FDT_IO_OK or a code with err. */
typedef struct fdt_dualmesh fdt_dualmesh;
int fdt_wr_dual_polymesh(const char *path, const fdt_dualmesh *d, char *err, size_t errlen);
/* An estimate of the bytes format f writes for m, all files together:
 * the progress total. Within a few tens of percent for the text formats
 * (coordinates taken as 20 characters each). */
uint64_t fdt_wr_estimate(const fdt_format *f, const fdt_mesh_view *m);
/* A text format written to an open stream (standard output: no temporary,
 * nothing renamed). Only single-file text formats. */
int fdt_wr_mesh_stream(FILE *stream, const char *name, const fdt_format *f,
                          const fdt_mesh_view *m, char *err, size_t errlen);
int fdt_wr_mesh_stream_ex(FILE *stream, const char *name, const fdt_format *f,
                          const fdt_mesh_view *m, fdt_io_progress_fn progress,
                          void *progress_user, char *err, size_t errlen);

/*
 * The files fdt_wr_mesh(path, ...) writes, in the order it writes them,
 * into names[0..count): path alone for .tets, .vtu and .vtk; for .ele,
 * BASE.node, path itself, BASE.face and BASE.neigh (BASE is path without
 * ".ele"; the siblings' extensions are lowercase whatever the case of
 * ".ele"). The writer builds its file set from this list, so a check made
 * on it covers every file a run will replace. Returns the count, 0 for an
 * unknown extension, -1 when a name would not fit FDT_IO_PATH.
 */
int fdt_output_files(const char *path,
                     char names[FDT_IO_MAX_FILES][FDT_IO_PATH]);
/* The same for format f (NULL: by extension); a directory format lists
 * the files in the directory path. */
int fdt_output_files_as(const char *path, const fdt_format *f,
                        char names[FDT_IO_MAX_FILES][FDT_IO_PATH]);

/*
 * Creating a file at path (issue 34 item 8): its folder must exist, be a
 * folder and be writable, and path must not be a folder. Returns 0, or
 * an errno with "cannot create ROLE PATH: folder DIR does not exist" (or
 * "...: DIR is not a folder", "folder DIR is not writable (...)", "a
 * folder has that name") in err: a cheap early answer, so a doomed run
 * fails in milliseconds rather than after the triangulation; the writer
 * still checks every step for real. role names what the file is for
 * ("output", "--stats-json file").
 */
int fdt_output_dir_check(const char *role, const char *path, char *err, size_t errlen);
/* The same message for errno e met creating path, when the folder is
 * why (ENOENT, ENOTDIR, EACCES, EPERM, EROFS, EISDIR); else "PATH:
 * strerror" as every write error. Returns FDT_IO_EWRITE (FDT_IO_ENOMEM
 * for ENOMEM). */
int fdt_create_err(char *err, size_t errlen, const char *role, const char *path, int e);

/*
 * Do paths a and b reach the same file? 1 if so, else 0. Each path stands
 * for the file that opening it would read or create, symbolic links
 * followed (a dangling link stands for the file it would create):
 *   - an existing file is known by (st_dev, st_ino), so "./x", "d/../x",
 *     an absolute path, a symbolic link and a hard link all match it;
 *   - a name not there yet is known by its directory's (st_dev, st_ino)
 *     and its last component, compared byte for byte (a case-insensitive
 *     file system's "A" and "a" are not matched while neither exists).
 * Equal strings always match. A path that cannot be resolved (a missing
 * directory, no permission, a loop of links) matches only its own string:
 * whatever then tries to use it fails on its own.
 */
int fdt_same_file(const char *a, const char *b);

/*
 * A small file written with stdio through the same temporary-and-rename
 * (and signal cleanup) as the mesh: the CLI's --stats-json. open returns
 * the stream of the temporary (NULL and a message in err on failure);
 * commit closes it and renames it over target (FDT_IO_OK or a writer
 * code, the message in err, the temporary removed); abandon removes it.
 * Either frees side.
 */
typedef struct fdt_wr_side fdt_wr_side;
FILE *fdt_wr_side_open(const char *target, fdt_wr_side **side, char *err, size_t errlen);
int fdt_wr_side_commit(fdt_wr_side *side, char *err, size_t errlen);
void fdt_wr_side_abandon(fdt_wr_side *side);

/*
 * Commit sets (issue 34 item 3): the outputs of one run, all new or all
 * as they were. After fdt_wr_set_begin() every commit of this module
 * (fdt_wr_mesh*, the streaming writers' close, fdt_wr_side_commit) only
 * closes its complete temporaries and adds them to the set;
 * fdt_wr_set_commit() then renames them all, in the order they came,
 * backing up the targets it replaces and keeping a journal
 * ".frontdt-commit-PID" in the first target's folder while it renames
 * (src/io/write/writer.c, "Commit sets", says how). Any failure, or
 * SIGINT/SIGTERM (fdt_io_cleanup_temps), before its end puts every
 * output back as it was and removes every temporary; FDT_IO_OK or
 * FDT_IO_EWRITE with the file named in err. no_clobber: the commit
 * refuses (and changes nothing) when a target exists. fdt_wr_set_abandon()
 * removes the set's temporaries. One set at a time, from one thread:
 * begin returns -1 while one is open. fdt_wr_set_active(): is one open?
 */
int fdt_wr_set_begin(int no_clobber);
int fdt_wr_set_commit(char *err, size_t errlen);
void fdt_wr_set_abandon(void);
int fdt_wr_set_active(void);

/* Removes every temporary output file not yet renamed (and rolls back a
 * commit set not yet committed), and every guarded target (fdt_io_guard).
 * Async-signal-safe. */
void fdt_io_cleanup_temps(void);

/* Guards target, a file of an output written outside this writer's
 * temporaries (the pieces, .node and index of an MPI output): until
 * fdt_io_unguard, an interrupt (fdt_io_cleanup_temps) removes it, whether
 * it exists yet or not. The caller holds fdt_write_lock (the registry's
 * slots are process-wide). Returns the slot, or -1 when the name is too
 * long or every slot is taken (then nothing guards it). */
int fdt_io_guard(const char *target);
/* Ends the guard of slot (-1: none); the file stays. */
void fdt_io_unguard(int slot);

#endif
