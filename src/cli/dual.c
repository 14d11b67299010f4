/* The CLI's Voronoi outputs: see dual.h. */
#include "cli/dual.h"
#include "api/dual.h"
#include "cli/cli.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/read/reader.h"
#include "io/write/cells.h"
#include "io/write/writer.h"
#include "mesh/dualmesh.h"
#include "mesh/voronoi.h"
#include "par/threads.h"

int fdt_cli_dual_wanted(const fdt_cli_dual *d)
{
    return d->voronoi || d->density;
}

/* 0, or -1: not six finite numbers with each min below its max. */
static int parse_box(const char *s, double box[6])
{
    const char *p = s;
    for (int k = 0; k < 6; k++) {
        char *end;
        errno = 0;
        box[k] = strtod(p, &end);
        if (end == p || errno == ERANGE || !isfinite(box[k]))
            return -1;
        if (k < 5 && *end != ',')
            return -1;
        p = end + (k < 5);
        if (k == 5 && *end)
            return -1;
    }
    for (int k = 0; k < 3; k++)
        if (!(box[k] < box[k + 3]))
            return -1;
    return 0;
}

int fdt_cli_parse_box(const char *s, double box[6], char *err, size_t errlen)
{
    if (parse_box(s, box) == 0)
        return 0;
    snprintf(err, errlen, "--box wants six finite numbers xmin,ymin,zmin,xmax,ymax,zmax with each "
             "min below its max, not '%s'", s);
    return -1;
}

/* Does path end in ext (".csv", ".vtu")? */
static int has_ext(const char *path, const char *ext)
{
    size_t m = strlen(path), e = strlen(ext);
    return m >= e && !strcmp(path + m - e, ext);
}

int fdt_cli_interp_wanted(const fdt_cli_dual *d)
{
    return d->values || d->queries || d->interpolated;
}

int fdt_cli_dual_check(const fdt_cli_dual *d, const char *input, char *err, size_t errlen)
{
    if (fdt_cli_interp_wanted(d) && !(d->values && d->queries && d->interpolated)) {
        snprintf(err, errlen, "interpolation needs all three of --values FILE, --interpolate "
                 "QUERIES and --interpolated OUT");
        return -1;
    }
    const char *outs[3] = {d->voronoi, d->density, d->interpolated};
    const char *ins[3] = {input, d->values, d->queries};
    for (int o = 0; o < 3; o++)
        for (int i = 0; i < 3; i++)
            if (outs[o] && ins[i] && strcmp(ins[i], "-") && fdt_same_file(outs[o], ins[i])) {
                snprintf(err, errlen, "%s would overwrite %s, which this run reads", outs[o],
                         ins[i]);
                return -1;
            }
    for (int o = 0; o < 3; o++)
        for (int p = o + 1; p < 3; p++)
            if (outs[o] && outs[p] && fdt_same_file(outs[o], outs[p])) {
                snprintf(err, errlen, "%s is named for two outputs", outs[o]);
                return -1;
            }
    if (d->format && !d->voronoi) {
        snprintf(err, errlen, "--voronoi-format needs --voronoi FILE");
        return -1;
    }
    if (d->box_given && !fdt_cli_dual_wanted(d) && !d->dual) {
        snprintf(err, errlen, "--box clips the Voronoi cells: it needs --voronoi, --density "
                 "or --dual");
        return -1;
    }
    if (d->format && d->voronoi && has_ext(d->voronoi, ".vtu")) {
        snprintf(err, errlen, "--voronoi-format does not apply to a .vtu file (polyhedra)");
        return -1;
    }
    if (d->format && fdt_cells_format_check(d->format, NULL, err, errlen))
        return -1;
    return 0;
}

/* One file through the commit set: written by fn (0, an errno, or a
 * negative FDT_E* code), renamed with the rest. */
static int write_side(const char *path, int (*fn)(FILE *, const void *, const double *),
                      const void *arg, const double *xyz, char *err, size_t errlen)
{
    fdt_wr_side *side = NULL;
    FILE *f = fdt_wr_side_open(path, &side, err, errlen);
    if (!f)
        return FDT_EIO;
    int e = fn(f, arg, xyz);
    if (e) {
        fdt_wr_side_abandon(side);
        snprintf(err, errlen, "%s: %s", path, e < 0 ? fdt_strerror(e) : strerror(e));
        return e < 0 ? e : FDT_EIO;
    }
    return fdt_wr_side_commit(side, err, errlen) == FDT_IO_OK ? FDT_OK : FDT_EIO;
}

typedef struct cells_job {
    fdt_voronoi *v;
    const char *format; /* NULL: CSV */
    int vtu;            /* VTK polyhedra */
    int threads;        /* the text's (at least 1) */
} cells_job;

static int put_cells(FILE *f, const void *arg, const double *xyz)
{
    const cells_job *j = arg;
    return j->vtu ? fdt_wr_cells_vtu(f, j->v, xyz)
                  : fdt_wr_cells(f, j->format, j->v, xyz, j->threads);
}

static int put_density(FILE *f, const void *arg, const double *xyz)
{
    (void)xyz;
    const cells_job *j = arg;
    return fdt_wr_density(f, j->v, j->threads);
}

/* The cells' options and tables d asks for (job's format NULL and vtu 0
 * with d->voronoi set: CSV). */
int fdt_cli_cells_table(const fdt_cli_dual *d, const char **format, int *neighbors,
                        unsigned *skip)
{
    int vtu = d->voronoi && has_ext(d->voronoi, ".vtu");
    const char *f = d->format;
    if (d->voronoi && !f && !vtu && !has_ext(d->voronoi, ".csv"))
        f = FDT_CELLS_DEFAULT_FORMAT;
    int nb = vtu;
    char err[256];
    if (f && !vtu)
        (void)fdt_cells_format_check(f, &nb, err, sizeof err);
    *format = vtu ? NULL : f;
    *neighbors = nb;
    /* the polyhedra read their volumes alone */
    *skip = fdt_cells_table_skip(vtu ? "" : f, d->voronoi && !vtu && !f, d->density != NULL);
    return vtu;
}

static void cells_setup(const fdt_cli_dual *d, fdt_voronoi_options *o, cells_job *job)
{
    fdt_default_voronoi_options(o);
    o->box_given = d->box_given;
    o->threads = d->threads;
    memcpy(o->box, d->box, sizeof o->box);
    cells_job j = {NULL, NULL, 0, d->threads ? d->threads : fdt_threads_default()};
    j.vtu = fdt_cli_cells_table(d, &j.format, &o->neighbors, &o->skip);
    *job = j;
}

void fdt_cli_cells_message(const char *what, int r, const char *diag, char *err, size_t errlen)
{
    /* FDT_ERANGE: not a coordinate's value but the cells' (diag says) */
    snprintf(err, errlen, "%s: %s%s%s", what, r == FDT_ERANGE && *diag ? "" : fdt_strerror(r),
             r == FDT_ERANGE || !*diag ? "" : ": ", diag);
}

int fdt_cli_dual_write(const fdt_cli_dual *d, const fdt_result *res, const double *xyz, size_t n,
                       char *err, size_t errlen)
{
    fdt_voronoi_options o;
    cells_job job;
    cells_setup(d, &o, &job);
    fdt_voronoi *v = NULL;
    char diag[512];
    int r = fdt_voronoi_compute(res, xyz, n, &o, &v, diag, sizeof diag);
    if (r != FDT_OK) {
        fdt_cli_cells_message("Voronoi cells", r, diag, err, errlen);
        return r;
    }
    job.v = v;
    if (job.vtu && (r = fdt_voronoi_vertices_check(v, xyz, diag, sizeof diag)) != FDT_OK) {
        snprintf(err, errlen, "Voronoi cells as polyhedra (%s): %s", d->voronoi, diag);
        fdt_voronoi_free(&v);
        return r;
    }
    if (d->voronoi)
        r = write_side(d->voronoi, put_cells, &job, xyz, err, errlen);
    if (r == FDT_OK && d->density)
        r = write_side(d->density, put_density, &job, xyz, err, errlen);
    fdt_voronoi_free(&v);
    return r;
}

const char *fdt_cli_dual_stream_refusal(const fdt_cli_dual *d)
{
    if (fdt_cli_interp_wanted(d))
        return "--interpolate needs the whole mesh";
    const char *f;
    int nb;
    unsigned skip;
    if (fdt_cli_cells_table(d, &f, &nb, &skip))
        return "--voronoi FILE.vtu (the cells as polyhedra) needs the whole mesh";
    return NULL;
}

struct fdt_cli_cells {
    fdt_voronoi_options o;
    cells_job job;
    fdt_cells_spool *sp;
    int err; /* the spool's first errno */
};

/* The batch's rows into the spool (an fdt_cell_sink's call). */
static int spool_batch(void *user, const fdt_voronoi *v)
{
    fdt_cli_cells *c = user;
    c->err = fdt_cells_spool_add(c->sp, v);
    return c->err != 0;
}

int fdt_cli_cells_open(const fdt_cli_dual *d, size_t n, fdt_cli_cells **out,
                       fdt_voronoi_options *o, fdt_cell_sink *sink, char *err, size_t errlen)
{
    fdt_cli_cells *c = calloc(1, sizeof *c);
    *out = NULL;
    if (!c) {
        snprintf(err, errlen, "out of memory");
        return FDT_ENOMEM;
    }
    cells_setup(d, &c->o, &c->job);
    /* the spool beside the first table: the same file system, which
     * must hold the tables anyway */
    char dir[FDT_IO_PATH];
    fdt_cells_dir(d->voronoi ? d->voronoi : d->density, dir, sizeof dir);
    int e = fdt_cells_spool_open(&c->sp, 0, n, d->voronoi ? c->job.format : NULL,
                                 d->voronoi && !c->job.format, d->density != NULL, dir);
    if (e) {
        snprintf(err, errlen, "%s: a temporary file for the cells: %s", dir, strerror(e));
        free(c);
        return e == ENOMEM ? FDT_ENOMEM : FDT_EIO;
    }
    *o = c->o;
    fdt_cell_sink cs = {sizeof cs, spool_batch, c};
    *sink = cs;
    *out = c;
    return FDT_OK;
}

fdt_cells_spool *fdt_cli_cells_spool(fdt_cli_cells *c)
{
    return c->sp;
}

int fdt_cli_cells_failed(const fdt_cli_cells *c, char *err, size_t errlen)
{
    if (!c->err)
        return 0;
    snprintf(err, errlen, "the cells' temporary file: %s", strerror(c->err));
    return 1;
}

/* One table of the spool (write_side's writer). */
typedef struct spooled {
    const fdt_cli_cells *c;
    int table; /* 0 the cells', 1 the densities */
} spooled;

static int put_spooled(FILE *f, const void *arg, const double *xyz)
{
    (void)xyz;
    const spooled *t = arg;
    return fdt_cells_spool_put(t->c->sp, t->table, 1, f);
}

int fdt_cli_cells_write(const fdt_cli_dual *d, fdt_cli_cells *c, char *err, size_t errlen)
{
    int r = FDT_OK;
    const spooled cells = {c, 0}, density = {c, 1};
    if (d->voronoi)
        r = write_side(d->voronoi, put_spooled, &cells, NULL, err, errlen);
    if (r == FDT_OK && d->density)
        r = write_side(d->density, put_spooled, &density, NULL, err, errlen);
    return r;
}

void fdt_cli_cells_close(fdt_cli_cells **c)
{
    if (!c || !*c)
        return;
    fdt_cells_spool_close(&(*c)->sp);
    free(*c);
    *c = NULL;
}

typedef struct rows_job {
    const double *v;
    size_t rows, k;
} rows_job;

static int put_table(FILE *f, const void *arg, const double *xyz)
{
    (void)xyz;
    const rows_job *j = arg;
    return fdt_wr_rows(f, j->v, j->rows, j->k);
}

int fdt_cli_interp_write(const fdt_cli_dual *d, fdt_result *res, const double *xyz, size_t n,
                         char *err, size_t errlen)
{
    double *vals = NULL, *q = NULL, *out = NULL;
    size_t k = 0, nq = 0;
    int r = fdt_rd_values(d->values, n, &vals, &k, err, errlen);
    if (r != FDT_IO_OK)
        return r == FDT_IO_ENOMEM ? FDT_ENOMEM : FDT_EFORMAT;
    r = fdt_rd_points(d->queries, &q, &nq, err, errlen);
    if (r != FDT_IO_OK) {
        free(vals);
        return r == FDT_IO_ENOMEM ? FDT_ENOMEM : FDT_EFORMAT;
    }
    out = malloc((nq && k ? nq * k : 1) * sizeof *out);
    if (!out) {
        r = FDT_ENOMEM;
        snprintf(err, errlen, "interpolation: out of memory");
    } else {
        char diag[512];
        r = fdt_interpolate(res, xyz, n, vals, k, q, nq,
                            d->natural ? FDT_INTERP_NATURAL : FDT_INTERP_LINEAR, d->threads, out,
                            diag, sizeof diag);
        if (r != FDT_OK)
            snprintf(err, errlen, "interpolation: %s%s%s", fdt_strerror(r), *diag ? ": " : "",
                     diag);
    }
    if (r == FDT_OK) {
        rows_job job = {out, nq, k};
        r = write_side(d->interpolated, put_table, &job, xyz, err, errlen);
    }
    free(vals);
    free(q);
    free(out);
    return r;
}

int fdt_cli_dual_exit(int err)
{
    return err == FDT_EIO ? CLI_WRITE : err == FDT_EFORMAT ? CLI_INPUT : fdt_cli_engine_exit(err);
}

int fdt_cli_dual_mesh(const fdt_cli_dual *d, fdt_result *res, const double *xyz, size_t n,
                      const char *path, char *err, size_t errlen)
{
    fdt_voronoi_options o;
    fdt_default_voronoi_options(&o);
    o.box_given = d->box_given;
    memcpy(o.box, d->box, sizeof o.box);
    fdt_dualmesh dm;
    char diag[512];
    int r = fdt_dual_build(res, xyz, n, &o, d->threads, &dm, diag, sizeof diag);
    if (r != FDT_OK) {
        char what[FDT_IO_PATH + 64];
        snprintf(what, sizeof what, "%s: the Voronoi cells as a polyMesh (--dual)", path);
        fdt_cli_cells_message(what, r, diag, err, errlen);
        return r;
    }
    r = fdt_wr_dual_polymesh(path, &dm, err, errlen) == FDT_IO_OK ? FDT_OK : FDT_EIO;
    fdt_dualmesh_free(&dm);
    return r;
}
