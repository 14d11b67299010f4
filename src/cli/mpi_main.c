/*
 * frontdt-mpi: the distributed run (issue 19) under mpirun, one part per
 * rank (src/mpi/mpi_run.h). Each rank reads its slice of the input and the
 * ranks bisect the points by exchanging them (src/mpi/mpi_setup.h); rank 0
 * prints and writes. Exit codes are the CLI's (README, Exit codes), the
 * same on every rank.
 *
 *   mpirun -np 4 frontdt-mpi [-o OUT] [--set-hash] [--stats] [-q] INPUT
 *
 * With --voronoi or --density the ranks then compute the Voronoi cells
 * together (src/mpi/mpi_cells.h) and write the tables, each rank its
 * block of rows.
 */
#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <mpi.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "cli/cli.h"
#include "cli/dual.h"
#include "cli/options.h"
#include "frontdt.h"
#include "mpi/mpi_cells.h"
#include "mpi/mpi_output.h"
#include "mpi/mpi_run.h"
#include "geom/prepare.h"
#include "io/read/reader.h"
#include "io/write/cells.h"
#include "mesh/periodic.h"
#include "mesh/result.h"
#include "api/parts.h"
#include "front/seed.h"
#include "io/write/writer.h"

/* ---- SIGINT / SIGTERM / SIGXFSZ ------------------------------------------
 *
 * mpirun passes an interrupt on to every rank (Open MPI forwards SIGINT
 * and SIGTERM, MPICH's hydra SIGINT). Each rank removes what it is
 * writing, as frontdt does (fdt_write_cleanup: the temporaries of a write
 * in progress, and the files of a distributed output while that output
 * is not complete on every rank, src/mpi/mpi_output.h), so
 * an interrupted run leaves no output, and leaves with exit code 6
 * without waiting for the others (which the same signal ends; a rank
 * that left early keeps the others in fdt_mpo_write's last barrier until
 * mpirun ends them, with the same cleanup). SIGXFSZ is ignored, as in
 * frontdt: a write beyond ulimit -f fails with EFBIG (exit 5, temporaries
 * removed) instead of killing the rank (src/cli/cli.h). */
static void cleanup_outputs(void)
{
    fdt_write_cleanup(); /* async-signal-safe: unlink only */
}

typedef struct opts {
    const char *input, *output, *format;
    int set_hash, hash, stats, quiet, leaf, no_park;
    fdt_search search;   /* --search */
    int fail_rank;
    size_t fail_after;
    int fail_write;      /* --inject-write-failure RANK, -1: none */
    int kind;            /* FDT_MPO_* of -o */
    fdt_cli_dual cells;  /* --voronoi, --voronoi-format, --density, --box */
    const char *vtu;     /* --voronoi FILE.vtu: the polyhedra, made on rank 0
                            from the gathered mesh (cells.voronoi is then NULL) */
    unsigned periodic;   /* --periodic AXES (the periods: --box) */
} opts;

static void usage(FILE *f)
{
    fputs("Usage: mpirun -np N frontdt-mpi [options] INPUT\n"
          "  The Delaunay tetrahedralization of INPUT (.xyz .txt .csv .node .ply),\n"
          "  one part per MPI rank; each rank reads its slice of a .xyz .txt .csv\n"
          "  file or a binary .ply (other inputs: every rank reads them whole;\n"
          "  standard input, -: rank 0 reads it and scatters the slices).\n"
          "\n"
          "Options:\n",
          f);
    fdt_cli_help(f, FDT_CLI_MPI);
}

/* Rank 0 says it (the ranks all parse the same words: one says why). */
static void say0(int rank, const char *fmt, ...)
{
    if (rank != 0)
        return;
    va_list ap;
    va_start(ap, fmt);
    fputs("frontdt-mpi: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}

/* One option of the table's (src/cli/options.h) with its value v (NULL
 * when it takes none): -1 to go on, or an exit code. */
static int take_option(opts *o, int id, const char *v, int rank)
{
    char err[256], *end;
    long r;
    int fmt; /* checked here; the setup reads o->format by name */
    switch (id) {
    case FDT_OPT_HELP:
        if (rank == 0)
            usage(stdout);
        return CLI_OK;
    case FDT_OPT_VERSION:
        if (rank == 0)
            printf("frontdt-mpi %s (library %s)\n", FDT_VERSION_STRING, fdt_version());
        return CLI_OK;
    case FDT_OPT_OUTPUT:
        o->output = v;
        return -1;
    case FDT_OPT_INPUT_FORMAT:
        if (fdt_cli_input_format(v, &fmt, err, sizeof err) != 0) {
            say0(rank, "%s", err);
            return CLI_USAGE;
        }
        o->format = v;
        return -1;
    case FDT_OPT_SET_HASH:
        o->set_hash = 1;
        return -1;
    case FDT_OPT_HASH:
        o->hash = 1;
        return -1;
    case FDT_OPT_STATS:
        o->stats = 1;
        return -1;
    case FDT_OPT_QUIET:
        o->quiet = 1;
        return -1;
    case FDT_OPT_NO_PARK:
        o->no_park = 1;
        return -1;
    case FDT_OPT_SEARCH:
        if (fdt_cli_search(v, &o->search, err, sizeof err) != 0) {
            say0(rank, "%s", err);
            return CLI_USAGE;
        }
        return -1;
    case FDT_OPT_LEAF:
        if (fdt_cli_leaf(v, &o->leaf, err, sizeof err) != 0) {
            say0(rank, "%s", err);
            return CLI_USAGE;
        }
        return -1;
    case FDT_OPT_INJECT_FAILURE: {
        r = strtol(v, &end, 10);
        unsigned long long f = *end == ':' ? strtoull(end + 1, &end, 10) : 0;
        if (*end || r < 0 || r > INT_MAX) {
            say0(rank, "--inject-failure wants RANK:FACES");
            return CLI_USAGE;
        }
        o->fail_rank = (int)r;
        o->fail_after = (size_t)f;
        return -1;
    }
    case FDT_OPT_VORONOI:
        o->cells.voronoi = v;
        return -1;
    case FDT_OPT_VORONOI_FORMAT:
        o->cells.format = v;
        return -1;
    case FDT_OPT_DENSITY:
        o->cells.density = v;
        return -1;
    case FDT_OPT_DUAL:
        o->cells.dual = 1;
        return -1;
    case FDT_OPT_BOX:
        if (fdt_cli_parse_box(v, o->cells.box, err, sizeof err) != 0) {
            say0(rank, "%s", err);
            return CLI_USAGE;
        }
        o->cells.box_given = 1;
        return -1;
    case FDT_OPT_PERIODIC:
        if (fdt_cli_periodic(v, &o->periodic, err, sizeof err) != 0) {
            say0(rank, "%s", err);
            return CLI_USAGE;
        }
        return -1;
    case FDT_OPT_INJECT_WRITE_FAILURE:
        r = strtol(v, &end, 10);
        if (*end || r < 0 || r > INT_MAX) {
            say0(rank, "--inject-write-failure wants RANK");
            return CLI_USAGE;
        }
        o->fail_write = (int)r;
        return -1;
    default:
        say0(rank, "internal error: option row %d has no parser", id);
        return CLI_INTERNAL;
    }
}

/* --dual on rank 0: the gathered mesh res's Voronoi cells as frontdt
 * writes them (src/cli/dual.h), its tets sorted first so that the files are
 * frontdt's bytes whatever the ranks; the triangulation a periodic dual
 * runs takes one thread, as a rank's work does. An exit code. */
static int write_dual(const opts *o, fdt_result *res, const double *xyz, size_t n)
{
    char err[FDT_IO_PATH + 600];
    fdt_cli_dual d = o->cells;
    d.threads = 1;
    int r = fdt_result_sort(res);
    if (r == FDT_OK)
        r = fdt_cli_dual_mesh(&d, res, xyz, n, o->output, err, sizeof err);
    else
        snprintf(err, sizeof err, "%s: out of memory sorting the tets", o->output);
    if (r == FDT_OK)
        return CLI_OK;
    fprintf(stderr, "frontdt-mpi: %s\n", err);
    return fdt_cli_dual_exit(r);
}

/* --voronoi FILE.vtu on rank 0: the gathered mesh res's cells as VTK
 * polyhedra, as frontdt writes them (src/cli/dual.h). An exit code. */
static int write_vtu_cells(const opts *o, const fdt_result *res, const double *xyz, size_t n)
{
    char err[FDT_IO_PATH + 600];
    fdt_cli_dual d = o->cells;
    d.voronoi = o->vtu;
    d.density = NULL; /* the ranks' table */
    d.threads = 1;
    int r = fdt_cli_dual_write(&d, res, xyz, n, err, sizeof err);
    if (r == FDT_OK)
        return CLI_OK;
    fprintf(stderr, "frontdt-mpi: %s\n", err);
    return fdt_cli_dual_exit(r);
}

/* The cells' options (frontdt's rules, src/cli/dual.h), and what only
 * frontdt does: -1 to go on, or an exit code. */
static int check_cells(opts *o, int rank)
{
    char err[FDT_IO_PATH + 200];
    if (fdt_cli_dual_check(&o->cells, o->input, err, sizeof err) != 0) {
        say0(rank, "%s", err);
        return CLI_USAGE;
    }
    const char *v = o->cells.voronoi, *fmt;
    int nb;
    unsigned skip;
    if (fdt_cli_cells_table(&o->cells, &fmt, &nb, &skip)) {
        /* the polyhedra need every cell's neighbours' points: made on rank
         * 0 from the gathered mesh, as frontdt makes them */
        if (o->output && fdt_mpo_kind(o->output) != FDT_MPO_GATHER) {
            say0(rank, "--voronoi FILE.vtu (the cells as polyhedra) is made on rank 0 from the "
                       "gathered mesh: not beside an -o of pieces");
            return CLI_USAGE;
        }
        o->vtu = v;
        o->cells.voronoi = NULL; /* the ranks' tables: --density alone */
    }
    if (o->output && fdt_cli_dual_wanted(&o->cells))
        for (int k = 0; k < 2; k++) {
            const char *t = k ? o->cells.density : v;
            if (t && fdt_same_file(t, o->output)) {
                say0(rank, "%s is named for two outputs", t);
                return CLI_USAGE;
            }
        }
    return -1;
}

/* -o against the input and the other options, once all are read: -1 to go
 * on, or an exit code. */
static int check_output(opts *o, int rank, int size)
{
    o->kind = o->output ? fdt_mpo_kind(o->output) : FDT_MPO_GATHER;
    if (o->kind != FDT_MPO_GATHER && o->hash) {
        say0(rank, "--hash gathers the mesh to rank 0, which a piece output ('%s') does not: "
                   "use --set-hash", o->output);
        return CLI_USAGE;
    }
    if (o->kind != FDT_MPO_GATHER) {
        /* pieces: none of them (nor the .node, nor the index) may be the
         * input */
        char name[FDT_IO_PATH];
        for (size_t k = 0;; k++) {
            int got = fdt_mpo_file(o->output, size, k, name, sizeof name);
            if (got < 0) {
                say0(rank, "'%s': piece names too long", o->output);
                return CLI_USAGE;
            }
            const char *x = got ? name : o->output;
            if (fdt_same_file(x, o->input)) {
                say0(rank, "output '%s' is the input '%s'", x, o->input);
                return CLI_USAGE;
            }
            if (!got)
                break;
        }
    } else if (o->output) {
        const fdt_format *f = fdt_format_by_path(o->output);
        char names[FDT_IO_MAX_FILES][FDT_IO_PATH];
        int nf = fdt_output_files(o->output, names);
        if (!f || nf <= 0) {
            say0(rank, "unknown output extension: '%s'", o->output);
            return CLI_USAGE;
        }
        if (fdt_format_needs(f, 0) & FDT_NEED_NBRS) {
            say0(rank, "%s needs tet neighbours, which the MPI run does not gather yet; use "
                       "frontdt, or -o BASE.pele for\nTetGen pieces without neighbours",
                 fdt_format_name(f));
            return CLI_USAGE;
        }
        for (int k = 0; k < nf; k++)
            if (fdt_same_file(names[k], o->input)) {
                say0(rank, "output '%s' is the input '%s'", names[k], o->input);
                return CLI_USAGE;
            }
    }
    return -1;
}

/* -1: go on; else an exit code. Only rank 0 prints. */
static int parse(int argc, char **argv, opts *o, int rank, int size)
{
    memset(o, 0, sizeof *o);
    o->fail_rank = -1;
    o->fail_write = -1;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        int id = fdt_cli_find(a, FDT_CLI_MPI);
        int takes = id >= 0 && fdt_cli_opts[id].arg != no_argument;
        if (id >= 0 && (!takes || i + 1 < argc)) {
            int rc = take_option(o, id, takes ? argv[++i] : NULL, rank);
            if (rc >= 0)
                return rc;
        } else if (a[0] == '-' && a[1]) {
            say0(rank, "unknown option or missing value: '%s'", a);
            if (rank == 0)
                usage(stderr);
            return CLI_USAGE;
        } else if (!o->input) {
            o->input = a;
        } else {
            say0(rank, "one input only ('%s')", a);
            return CLI_USAGE;
        }
    }
    if (!o->input) {
        say0(rank, "no input file");
        if (rank == 0)
            usage(stderr);
        return CLI_USAGE;
    }
    /* --dual: the gathered mesh's cells, written on rank 0 as frontdt
     * writes them */
    if (o->cells.dual && (!o->output || fdt_mpo_kind(o->output) != FDT_MPO_GATHER ||
                          fdt_format_by_path(o->output) != fdt_format_by_name("openfoam"))) {
        say0(rank, "--dual writes the Voronoi cells as an OpenFOAM polyMesh: it needs an -o "
                   "CASE/constant/polyMesh (gathered to rank 0)");
        return CLI_USAGE;
    }
    if (o->periodic) {
        /* the rows gathered to rank 0 and written by frontdt's writers, or
         * a piece a rank (.pvtu, .pfdtb: periodic_pieces) */
        const fdt_format *f = o->output ? fdt_format_by_path(o->output) : NULL;
        int kind = o->output ? fdt_mpo_kind(o->output) : FDT_MPO_GATHER;
        if (!o->cells.box_given) {
            say0(rank, "--periodic needs --box X0,Y0,Z0,X1,Y1,Z1: the periods");
            return CLI_USAGE;
        }
        if (kind == FDT_MPO_ELE || (kind == FDT_MPO_GATHER && o->output && !f)) {
            say0(rank, "--periodic under MPI writes -o in one of frontdt's formats (gathered "
                       "to rank 0) or pieces as BASE.pvtu or BASE.pfdtb; not .pele (a periodic "
                       "TetGen set's .node holds its images: -o BASE.ele gathers it)");
            return CLI_USAGE;
        }
        int rc = kind == FDT_MPO_GATHER ? -1 : check_output(o, rank, size);
        /* --box is the periods: the cells' options checked when asked */
        return rc >= 0 ? rc : fdt_cli_dual_wanted(&o->cells) ? check_cells(o, rank) : -1;
    }
    int rc = check_cells(o, rank);
    return rc >= 0 ? rc : check_output(o, rank, size);
}

/* A share's rows (src/api/parts.h's sink): nv ids and 3 nv offsets each. */
typedef struct rowbuf {
    int nv;
    fdt_vid *ids;
    int8_t *off;
    size_t n, cap;
} rowbuf;

static int setup_exit_code(int err);

/* The rows sorted as .tets sorts them (tets, then hull faces), ids below
 * n: FDT_OK, FDT_ENOMEM, or FDT_EINVAL for a row that is not canonical
 * (a bug). */
static int sort_rows(rowbuf rows[2], size_t n)
{
    int err = FDT_OK;
    for (int k = 0; k < 2 && !err; k++) {
        uint32_t *ids = (uint32_t *)rows[k].ids; /* replaced by the sort */
        err = fdt_periodic_sort_rows(&ids, &rows[k].off, rows[k].n, rows[k].nv, n);
        rows[k].ids = (fdt_vid *)ids;
        rows[k].cap = rows[k].n;
    }
    return err;
}

/* A periodic run's pieces: the rank's rows and what its .vtu piece is
 * written from (periodic_piece). */
typedef struct periodic_share {
    int kind;              /* FDT_MPO_VTU or FDT_MPO_BIN */
    fdt_result *res;       /* the rank's result: its box, duplicates */
    const rowbuf *rows;    /* tets, hull faces: sorted */
    const double *xyz;     /* every input point (each rank read them) */
    size_t n;
} periodic_share;

/* One rank's piece of a periodic mesh (src/mpi/mpi_output.h): its rows laid
 * out as frontdt lays out a periodic .vtu (the points and images its tets
 * use, each point's input id), or as a periodic .fdtb piece (flags 8 |
 * 16). */
static int periodic_piece(void *user, char (*names)[FDT_IO_PATH], int k, char *diag,
                          size_t dlen)
{
    (void)k;
    const periodic_share *p = user;
    fdt_result *r = p->res;
    const rowbuf *t = &p->rows[0], *h = &p->rows[1];
    const fdt_periodic_box b = fdt_periodic_box_of(r->periodic, r->pbox);
    if (p->kind == FDT_MPO_BIN) {
        fdt_bin_periodic per = {t->off, h->off, {0, 0, 0}};
        for (int a = 0; a < 3; a++)
            per.period[a] = fdt_periodic_period(&b, a);
        return fdt_mpo_bin_piece(names[0], p->n, t->ids, t->n, h->ids, h->n, &per, diag, dlen);
    }
    return fdt_mpo_periodic_vtu(names[0], t->ids, t->off, t->n, p->xyz, p->n, &b, diag, dlen);
}

/*
 * A periodic run's pieces (-o BASE.pvtu or BASE.pfdtb): each rank sorts
 * its slabs' rows and writes them as its piece, rank 0 the index, with
 * the set hash of the ranks' partial sums (the same as the gathered
 * mesh's). No row goes to rank 0. *hash: rank 0's set hash. A code
 * (CLI_) the same on every rank.
 */
static int periodic_pieces(const opts *o, int rank, fdt_result *res, rowbuf rows[2],
                           const double *xyz, size_t n, uint64_t *hash)
{
    char diag[1024] = "";
    int err = sort_rows(rows, n);
    int bad = err == FDT_OK ? 0 : err == FDT_ENOMEM ? 1 : 2, worst;
    MPI_Allreduce(&bad, &worst, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    if (worst) {
        if (rank == 0)
            fprintf(stderr, worst == 1 ? "frontdt-mpi: out of memory sorting a piece's rows\n"
                                       : "frontdt-mpi: a piece's periodic rows are not canonical "
                                         "(a bug: please report)\n");
        return worst == 1 ? CLI_RESOURCES : CLI_INTERNAL;
    }
    fdt_sethash h = {0, 0};
    fdt_sethash_add_periodic(&h, (const uint32_t *)rows[0].ids, rows[0].off, rows[0].n);
    uint64_t mine[2] = {h.sum, h.count}, all[2] = {0, 0};
    MPI_Reduce(mine, all, 2, MPI_UINT64_T, MPI_SUM, 0, MPI_COMM_WORLD);
    h.sum = all[0];
    h.count = all[1];
    *hash = fdt_sethash_value(&h);
    periodic_share ps = {fdt_mpo_kind(o->output), res, rows, xyz, n};
    const fdt_mpo_share s = {n,    res->ndup,      rows[0].n, rows[1].n, h, 1,
                             periodic_piece, NULL, &ps};
    fdt_mpo_args oa = {o->output, o->input, o->fail_write};
    int me = FDT_OK;
    uint64_t io[2];
    err = fdt_mpo_write_share(MPI_COMM_WORLD, &oa, &s, &me, io, diag, sizeof diag);
    if (me)
        fprintf(stderr, "frontdt-mpi: rank %d: %s\n", rank, diag);
    return err == FDT_OK ? CLI_OK : err == FDT_ENOMEM ? CLI_RESOURCES : CLI_WRITE;
}

/* Room for want rows. */
static int rows_reserve(rowbuf *b, size_t want)
{
    if (want <= b->cap)
        return FDT_OK;
    size_t cap = b->cap ? b->cap : 4096;
    while (cap < want)
        cap *= 2;
    fdt_vid *i2 = realloc(b->ids, cap * (size_t)b->nv * sizeof *i2);
    if (i2)
        b->ids = i2;
    int8_t *o2 = realloc(b->off, cap * 3 * (size_t)b->nv);
    if (o2)
        b->off = o2;
    if (!i2 || !o2)
        return FDT_ENOMEM;
    b->cap = cap;
    return FDT_OK;
}

static int rows_put(rowbuf *b, const fdt_vid *ids, const int8_t *off, size_t count)
{
    if (rows_reserve(b, b->n + count) != FDT_OK)
        return FDT_ENOMEM;
    memcpy(b->ids + (size_t)b->nv * b->n, ids, count * (size_t)b->nv * sizeof *ids);
    memcpy(b->off + 3 * (size_t)b->nv * b->n, off, count * 3 * (size_t)b->nv);
    b->n += count;
    return FDT_OK;
}

static int put_tets(void *user, const fdt_vid *t, const int8_t *off, size_t count)
{
    return rows_put(&((rowbuf *)user)[0], t, off, count);
}

static int put_hull(void *user, const fdt_vid *f, const int8_t *off, size_t count)
{
    return rows_put(&((rowbuf *)user)[1], f, off, count);
}

/* Every rank's rows into rank 0's b (its own first; others': appended);
 * FDT_ETOOBIG when a count passes MPI's int. Collective. */
static int gather_rows(rowbuf *b, int rank, int size)
{
    unsigned long long mine = b->n, *all = rank == 0 ? calloc((size_t)size, sizeof *all) : NULL;
    MPI_Gather(&mine, 1, MPI_UNSIGNED_LONG_LONG, all, 1, MPI_UNSIGNED_LONG_LONG, 0,
               MPI_COMM_WORLD);
    int err = FDT_OK;
    int *cnt = NULL, *dsp = NULL;
    size_t total = 0;
    if (rank == 0) {
        cnt = calloc((size_t)size, sizeof *cnt);
        dsp = calloc((size_t)size, sizeof *dsp);
        err = all && cnt && dsp ? FDT_OK : FDT_ENOMEM;
        for (int q = 0; q < size && !err; q++)
            total += all[q];
        if (!err && total * 3 * (size_t)b->nv > INT_MAX)
            err = FDT_ETOOBIG;
        if (!err)
            err = rows_reserve(b, total ? total : 1);
    }
    MPI_Bcast(&err, 1, MPI_INT, 0, MPI_COMM_WORLD);
    if (!err) {
        for (int pass = 0; pass < 2; pass++) {
            int w = pass ? 3 * b->nv : b->nv, at = 0;
            for (int q = 0; rank == 0 && q < size; q++) {
                cnt[q] = (int)all[q] * w;
                dsp[q] = at;
                at += cnt[q];
            }
            if (pass == 0)
                MPI_Gatherv(rank ? b->ids : MPI_IN_PLACE, (int)b->n * w, MPI_INT32_T, b->ids,
                            cnt, dsp, MPI_INT32_T, 0, MPI_COMM_WORLD);
            else
                MPI_Gatherv(rank ? b->off : MPI_IN_PLACE, (int)b->n * w, MPI_INT8_T, b->off,
                            cnt, dsp, MPI_INT8_T, 0, MPI_COMM_WORLD);
        }
        if (rank == 0)
            b->n = total;
    }
    free(all);
    free(cnt);
    free(dsp);
    return err;
}

/* A periodic run's cells' rows on their way to rank 0: records of an
 * input id (8 bytes), the two tables' lengths (4 bytes each) and their
 * text, a message at most CELLS_CHUNK bytes (a record longer than that,
 * a cell of some 400,000 faces, is refused: EFBIG), an empty message the
 * last. */
#define CELLS_CHUNK (16u << 20)
#define CELLS_TAG 33

typedef struct cells_msg {
    char *b; /* CELLS_CHUNK bytes, or NULL */
    size_t len;
} cells_msg;

static void cells_send(cells_msg *m)
{
    MPI_Send(m->b, (int)m->len, MPI_BYTE, 0, CELLS_TAG, MPI_COMM_WORLD);
    m->len = 0;
}

/* One spooled row into the message (fdt_cells_spool_each's call), which
 * goes when the row would not fit. */
static int cells_pack(void *user, size_t id, const uint32_t l[2], const char *text)
{
    cells_msg *m = user;
    size_t need = 16 + (size_t)l[0] + l[1];
    if (need > CELLS_CHUNK)
        return EFBIG;
    if (m->len + need > CELLS_CHUNK)
        cells_send(m);
    if (!m->b && !(m->b = malloc(CELLS_CHUNK)))
        return ENOMEM;
    uint64_t id64 = id;
    memcpy(m->b + m->len, &id64, 8);
    memcpy(m->b + m->len + 8, l, 8);
    memcpy(m->b + m->len + 16, text, need - 16);
    m->len += need;
    return 0;
}

/* A message's records into rank 0's spool: 0 or an errno (EINVAL for a
 * record cut short). */
static int cells_unpack(fdt_cells_spool *sp, const char *b, size_t len)
{
    int e = 0;
    for (size_t at = 0; at < len && !e; ) {
        uint64_t id;
        uint32_t l[2];
        if (len - at < 16)
            return EINVAL;
        memcpy(&id, b + at, 8);
        memcpy(l, b + at + 8, 8);
        size_t text = (size_t)l[0] + l[1];
        if (len - at - 16 < text)
            return EINVAL;
        e = fdt_cells_spool_add_row(sp, (size_t)id, l, b + at + 16);
        at += 16 + text;
    }
    return e;
}

/* Every rank's cells' rows into rank 0's spool (collective): rank 0's
 * buffer first (every rank told if it failed, before anything is sent),
 * then each other rank sends its rows in messages and rank 0 takes them
 * rank by rank, every message taken whatever failed. The same code on
 * every rank: FDT_OK, FDT_ENOMEM, or FDT_EIO with the message in diag. */
static int cells_to_root(fdt_cli_cells *cells, int rank, int size, char *diag, size_t dlen)
{
    fdt_cells_spool *sp = fdt_cli_cells_spool(cells);
    cells_msg m = {rank == 0 && size > 1 ? malloc(CELLS_CHUNK) : NULL, 0};
    int e = rank == 0 && size > 1 && !m.b ? ENOMEM : 0;
    if (e)
        snprintf(diag, dlen, "out of memory for the cells' rows");
    if (fdt_mpi_agree(MPI_COMM_WORLD, e ? FDT_ENOMEM : FDT_OK, diag, dlen) != FDT_OK) {
        free(m.b);
        return FDT_ENOMEM;
    }
    if (rank != 0) {
        e = fdt_cells_spool_each(sp, cells_pack, &m);
        if (m.len)
            cells_send(&m);
        cells_send(&m); /* the end */
    } else {
        for (int q = 1; q < size; q++)
            for (;;) {
                MPI_Status st;
                int count;
                MPI_Recv(m.b, (int)CELLS_CHUNK, MPI_BYTE, q, CELLS_TAG, MPI_COMM_WORLD, &st);
                MPI_Get_count(&st, MPI_BYTE, &count);
                if (!count)
                    break;
                if (!e)
                    e = cells_unpack(sp, m.b, (size_t)count);
            }
    }
    free(m.b);
    int err = e == 0 ? FDT_OK : e == ENOMEM ? FDT_ENOMEM : FDT_EIO;
    if (e)
        snprintf(diag, dlen, "the cells' rows to rank 0: %s", strerror(e));
    return fdt_mpi_agree(MPI_COMM_WORLD, err, diag, dlen);
}

/*
 * A periodic run (--periodic; issue 33, src/api/parts.h): every rank reads
 * the whole input and builds its share of the box's slabs (slab k on rank
 * k mod size) with the library's periodic engine on one thread; the rows
 * go to rank 0, which sorts them into the one mesh (the same rows for any
 * rank count) and hashes and writes it as frontdt does. With --voronoi or
 * --density each rank computes its slabs' points' cells as they are built
 * (frontdt --stream's batches, spooled as text), and rank 0 gathers the
 * rows into its spool and writes the tables: the same bytes as frontdt's.
 * The first rank that failed says why; every rank leaves with its code.
 */
static int periodic_run(const opts *o, int rank, int size)
{
    char diag[1024] = "";
    double *xyz = NULL;
    size_t n = 0;
    fdt_context *ctx = NULL;
    fdt_result *res = NULL;
    rowbuf rows[2] = {{4, NULL, NULL, 0, 0}, {3, NULL, NULL, 0, 0}};
    fdt_cli_cells *cells = NULL;
    int err = fdt_read_points(o->input, o->format, &xyz, &n, diag, sizeof diag), rc;
    int named = err != FDT_OK; /* a read's message names the file */
    rc = err ? setup_exit_code(err) : CLI_OK;
    fdt_voronoi_options vo;
    fdt_cell_sink cs;
    if (!err && fdt_cli_dual_wanted(&o->cells) &&
        (err = fdt_cli_cells_open(&o->cells, n, &cells, &vo, &cs, diag, sizeof diag)) != FDT_OK) {
        named = 1; /* the message names the spool's folder */
        rc = err == FDT_ENOMEM ? CLI_RESOURCES : CLI_WRITE;
    }
    if (!err) {
        fdt_settings s;
        fdt_default_settings(&s);
        s.n_threads = 1;
        s.periodic = o->periodic;
        memcpy(s.periodic_box, o->cells.box, sizeof s.periodic_box);
        fdt_sink sink = {sizeof sink, NULL, NULL, rows, put_tets, put_hull};
        err = fdt_open(&ctx, &s);
        if (!err)
            err = fdt_triangulate_stream_parts(ctx, xyz, n, &sink, cells ? &vo : NULL,
                                               cells ? &cs : NULL, (unsigned)rank,
                                               (unsigned)size, &res);
        if (err)
            snprintf(diag, sizeof diag, "%s", ctx ? fdt_context_diagnostic(ctx) : "");
        rc = fdt_cli_engine_exit(err);
        if (err && cells && fdt_cli_cells_failed(cells, diag, sizeof diag))
            rc = CLI_WRITE;
    }
    /* the first rank that failed names it */
    int first, me = rc ? rank : size;
    MPI_Allreduce(&me, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
    if (first < size) {
        if (rank == first && named)
            fprintf(stderr, "frontdt-mpi: %s\n", diag);
        else if (rank == first)
            fprintf(stderr, "frontdt-mpi: %s: %s\n", o->input, diag[0] ? diag : fdt_strerror(err));
        MPI_Bcast(&rc, 1, MPI_INT, first, MPI_COMM_WORLD);
        goto out;
    }
    if (o->stats) {
        /* each rank's share: its slabs' rows, images and seconds */
        fdt_stats st;
        double mine[3] = {0, 0, 0}, *all = rank == 0 ? malloc(3 * (size_t)size * sizeof *all)
                                                     : NULL;
        if (fdt_result_stats(res, &st) == FDT_OK) {
            mine[0] = (double)st.tets;
            mine[1] = (double)st.periodic_images;
            mine[2] = st.t_front;
        }
        MPI_Gather(mine, 3, MPI_DOUBLE, all, 3, MPI_DOUBLE, 0, MPI_COMM_WORLD);
        if (rank == 0 && all) {
            fprintf(stderr, "  rank         rows       images   slabs s\n");
            for (int q = 0; q < size; q++)
                fprintf(stderr, "  %4d %12.0f %12.0f %9.3f\n", q, all[3 * q], all[3 * q + 1],
                        all[3 * q + 2]);
        }
        free(all);
    }
    /* the rows: a piece a rank (no gather), or gathered to rank 0 */
    int pieces = o->output && fdt_mpo_kind(o->output) != FDT_MPO_GATHER;
    uint64_t piece_hash = 0;
    if (pieces && (rc = periodic_pieces(o, rank, res, rows, xyz, n, &piece_hash)) != CLI_OK)
        goto out;
    for (int k = 0; k < 2 && !err && !pieces; k++)
        err = gather_rows(&rows[k], rank, size);
    if (!err && cells && (err = cells_to_root(cells, rank, size, diag, sizeof diag)) != FDT_OK) {
        if (rank == 0)
            fprintf(stderr, "frontdt-mpi: %s\n", diag);
        rc = err == FDT_ENOMEM ? CLI_RESOURCES : CLI_WRITE;
        goto out;
    }
    if (rank == 0 && !err && !pieces && (err = sort_rows(rows, n)) == FDT_EINVAL) {
        fprintf(stderr, "frontdt-mpi: the gathered periodic rows are not canonical (a bug: "
                        "please report)\n");
        err = FDT_EINTERNAL;
    }
    rc = err ? fdt_cli_engine_exit(err) : CLI_OK;
    if (rank == 0 && !err && pieces && o->set_hash) /* the pieces are written */
        printf("set-hash: %016" PRIx64 "\n", piece_hash);
    if (rank == 0 && !err && !pieces) {
        /* rank 0's result, the gathered rows in it: one periodic mesh */
        res->streamed = 0;
        res->sorted = 1;
        res->tets = rows[0].ids;
        res->tet_off = rows[0].off;
        res->ntets = rows[0].n;
        res->hull = rows[1].ids;
        res->hull_off = rows[1].off;
        res->nhull = rows[1].n;
        memset(rows, 0, sizeof rows);
        uint64_t h;
        if (o->set_hash && fdt_result_set_hash(res, &h) == FDT_OK)
            printf("set-hash: %016" PRIx64 "\n", h);
        if (o->hash && fdt_result_hash(res, &h) == FDT_OK)
            printf("hash: %016" PRIx64 "\n", h);
        if (o->output && o->cells.dual)
            rc = write_dual(o, res, xyz, n);
        else if (o->output &&
                 (err = fdt_write_mesh(res, xyz, n, o->output, NULL, diag, sizeof diag)) !=
                     FDT_OK) {
            fprintf(stderr, "frontdt-mpi: %s\n", diag);
            rc = err == FDT_ENOMEM ? CLI_RESOURCES : CLI_WRITE;
        }
        if (rc == CLI_OK && o->vtu)
            rc = write_vtu_cells(o, res, xyz, n);
    }
    if (rank == 0 && !err) {
        if (rc == CLI_OK && cells &&
            (err = fdt_cli_cells_write(&o->cells, cells, diag, sizeof diag)) != FDT_OK) {
            fprintf(stderr, "frontdt-mpi: %s\n", diag);
            rc = err == FDT_ENOMEM ? CLI_RESOURCES : CLI_WRITE;
        }
        if (!o->quiet && pieces)
            fprintf(stderr, "frontdt-mpi: %zu points, periodic pieces on %d ranks\n", n, size);
        else if (!o->quiet)
            fprintf(stderr, "frontdt-mpi: %zu points, %zu periodic tets on %d ranks\n", n,
                    res->ntets, size);
        fflush(stdout);
    }
    MPI_Bcast(&rc, 1, MPI_INT, 0, MPI_COMM_WORLD);
out:
    for (int k = 0; k < 2; k++) {
        free(rows[k].ids);
        free(rows[k].off);
    }
    fdt_cli_cells_close(&cells);
    fdt_result_free(&res);
    fdt_close(&ctx);
    free(xyz);
    return rc;
}

static int exit_code(int err)
{
    switch (err) {
    case FDT_OK:
        return CLI_OK;
    case FDT_ENOMEM:
    case FDT_ETOOBIG:
        return CLI_RESOURCES;
    default:
        return CLI_INTERNAL;
    }
}

/* The setup's errors (src/mpi/mpi_setup.h): the CLI's codes for the input. */
static int setup_exit_code(int err)
{
    switch (err) {
    case FDT_EINVAL:
        return CLI_USAGE;
    case FDT_ENOMEM:
    case FDT_ETOOBIG:
        return CLI_RESOURCES;
    case FDT_EINTERNAL:
        return CLI_INTERNAL;
    default: /* FDT_EIO, FDT_EFORMAT, FDT_EDEGENERATE */
        return CLI_INPUT;
    }
}

/* The setup's phases on every rank (rank 0 prints; collective). */
static void setup_stats(const fdt_mpi_local *L, int rank, int size, int print)
{
    double mine[FDT_MPI_T_END + 1];
    memcpy(mine, L->t, sizeof L->t);
    mine[FDT_MPI_T_END] = (double)L->bytes_sent;
    double *all = rank == 0 ? malloc((size_t)size * sizeof mine) : NULL;
    int ok = rank != 0 || all;
    MPI_Bcast(&ok, 1, MPI_INT, 0, MPI_COMM_WORLD);
    if (!ok)
        return;
    MPI_Gather(mine, FDT_MPI_T_END + 1, MPI_DOUBLE, all, FDT_MPI_T_END + 1, MPI_DOUBLE, 0,
               MPI_COMM_WORLD);
    if (rank == 0 && print) {
        fprintf(stderr, "  setup: %s; %zu points, %zu duplicates merged\n",
                L->sliced == 1   ? "each rank read its slice of the file"
                : L->sliced == 2 ? "each rank read its vertices of the binary PLY"
                : L->sliced == 3 ? "rank 0 read standard input and scattered it"
                                 : "every rank read the whole input (.node, ASCII PLY or PLY "
                                   "with lists)",
                L->n, L->ndup);
        fprintf(stderr, "  rank    read s  exchange s   merge s   trees s   seeds s   bytes sent\n");
        for (int q = 0; q < size; q++) {
            const double *t = all + (size_t)q * (FDT_MPI_T_END + 1);
            fprintf(stderr, "  %4d %9.3f %11.3f %9.3f %9.3f %9.3f %12.0f\n", q, t[0], t[1], t[2],
                    t[3], t[4], t[5]);
        }
    }
    free(all);
}

static void print_stats(const fdt_mpi_out *r, int size, double t_read)
{
    fprintf(stderr, "frontdt-mpi: %d ranks\n  rank        tets", size);
    for (int k = 1; k < FDT_MSG_KIND_END; k++)
        fprintf(stderr, "  %s sent/recv", fdt_msg_kind_name(k));
    fputc('\n', stderr);
    for (int q = 0; q < size; q++) {
        const uint64_t *c = r->rank_counts + (size_t)q * 2 * FDT_MSG_KIND_END;
        fprintf(stderr, "  %4d %11zu", q, r->rank_tets[q]);
        for (int k = 1; k < FDT_MSG_KIND_END; k++)
            fprintf(stderr, "  %*" PRIu64 "/%-*" PRIu64, (int)strlen(fdt_msg_kind_name(k)), c[k],
                    9, c[FDT_MSG_KIND_END + k]);
        fputc('\n', stderr);
    }
    fprintf(stderr, "  rank   front s     cpu s    idle s  q-wait s      faces  msgs/face\n");
    for (int q = 0; q < size; q++) {
        const double *t = r->rank_times + (size_t)q * FDT_MPI_NTIMES;
        const uint64_t *c = r->rank_counts + (size_t)q * 2 * FDT_MSG_KIND_END;
        uint64_t msgs = 0;
        for (int k = 1; k < FDT_MSG_KIND_END; k++)
            msgs += c[k];
        fprintf(stderr, "  %4d %9.3f %9.3f %9.3f %9.3f %10.0f %10.4f\n", q, t[0], t[1], t[2],
                t[3], t[4], t[4] > 0 ? (double)msgs / t[4] : 0.0);
    }
    fprintf(stderr, "  messages          sent / received (all ranks)\n");
    for (int k = 1; k < FDT_MSG_KIND_END; k++)
        fprintf(stderr, "    %-15s %" PRIu64 " / %" PRIu64 "\n", fdt_msg_kind_name(k),
                r->all_sent[k], r->all_received[k]);
    fprintf(stderr, "  time (rank 0)     setup %.3f s, run's setup %.3f s, front %.3f s, output %.3f s\n",
            t_read, r->t_setup, r->t_front, r->t_out);
    if (r->t_replica > 0.0)
        fprintf(stderr, "  replica mesh      the DT of every point on every rank, rank 0's built "
                        "in %.3f s (src/mpi/mpi_run.c)\n", r->t_replica);
}

/* The Voronoi cells' tables (src/mpi/mpi_cells.h), after the mesh: the
 * same exit code on every rank, frontdt's for the same error. */
static int cells_step(const opts *o, const fdt_mpi_local *L, const fdt_mpi_out *r, int rank,
                      int size)
{
    const fdt_cli_dual *d = &o->cells;
    fdt_mpi_cells_opts co = {d->voronoi, NULL, d->density, d->box_given, {0}, 0, 0};
    memcpy(co.box, d->box, sizeof co.box);
    /* .vtu: refused before */
    (void)fdt_cli_cells_table(d, &co.format, &co.neighbors, &co.skip);
    fdt_mpi_cells_stats st;
    char diag[512], msg[1024];
    int e = fdt_mpi_cells(MPI_COMM_WORLD, L, r, &co, &st, diag, sizeof diag);
    if (e && rank == 0) {
        if (e == FDT_EIO)
            snprintf(msg, sizeof msg, "%s", diag); /* it names the file */
        else
            fdt_cli_cells_message("Voronoi cells", e, diag, msg, sizeof msg);
        fprintf(stderr, "frontdt-mpi: %s: %s\n", o->input, msg);
    }
    if (o->stats) {
        double mine[4] = {st.t, (double)st.star_tets, (double)st.bytes_sent,
                          (double)st.bytes_written};
        double *all = rank == 0 ? malloc(4 * (size_t)size * sizeof *all) : NULL;
        MPI_Gather(mine, 4, MPI_DOUBLE, all, 4, MPI_DOUBLE, 0, MPI_COMM_WORLD);
        if (rank == 0 && all) {
            fprintf(stderr, "  Voronoi cells (each rank its block of input ids)\n"
                            "  rank   cells s   star tets   bytes sent   bytes written\n");
            for (int q = 0; q < size; q++)
                fprintf(stderr, "  %4d %9.3f %11.0f %12.0f %15.0f\n", q, all[4 * q],
                        all[4 * q + 1], all[4 * q + 2], all[4 * q + 3]);
        }
        free(all);
    }
    switch (e) {
    case FDT_OK: return CLI_OK;
    case FDT_EINVAL: return CLI_USAGE;
    case FDT_ERANGE: return CLI_INPUT;
    case FDT_EIO: return CLI_WRITE;
    case FDT_ENOMEM:
    case FDT_ETOOBIG: return CLI_RESOURCES;
    default: return CLI_INTERNAL;
    }
}

/* The run after MPI_Init; every rank returns the same code. */
static int run(int argc, char **argv, int rank, int size)
{
    opts o;
    int rc = parse(argc, argv, &o, rank, size);
    if (rc >= 0)
        return rc;
    if (o.periodic)
        return periodic_run(&o, rank, size);
    char diag[512] = "";
    double t0 = MPI_Wtime();
    fdt_mpi_local L;
    memset(&L, 0, sizeof L);
    fdt_mpi_out r;
    memset(&r, 0, sizeof r);
    fdt_result *res = NULL;
    int pieces = o.kind != FDT_MPO_GATHER;
    /* The setup (src/mpi/mpi_setup.h) returns the same code on every rank,
     * with the lowest failing rank's message. */
    /* the gather (-o to rank 0, --hash) takes the points along */
    int cells = fdt_cli_dual_wanted(&o.cells);
    fdt_mpi_setup_opts so = {o.input, o.format, o.leaf,
                             (o.output && !pieces) || o.hash || o.kind == FDT_MPO_ELE || cells ||
                                 o.vtu};
    int err = fdt_mpi_setup(MPI_COMM_WORLD, &so, &L, diag, sizeof diag);
    double t_read = MPI_Wtime() - t0;
    if (err) {
        if (rank == 0)
            fprintf(stderr, "frontdt-mpi: %s\n", diag);
        rc = setup_exit_code(err);
        goto out;
    }
    setup_stats(&L, rank, size, o.stats);
    int own = !pieces ? 0 : o.kind == FDT_MPO_VTU ? FDT_MPI_OWN_POINTS : FDT_MPI_OWN_HULL;
    if (cells) /* a star's tets with their points, and the hull */
        own |= FDT_MPI_OWN_POINTS | FDT_MPI_OWN_HULL;
    int gather = (o.output && !pieces) || o.hash || o.vtu;
    fdt_mpi_opts mo = {o.leaf, o.search, gather, own, o.fail_rank, o.fail_after, o.no_park};
    err = fdt_mpi_run(MPI_COMM_WORLD, &L, &mo, &r, diag, sizeof diag);
    if (err) {
        if (rank == 0)
            fprintf(stderr, "frontdt-mpi: %s (%s)\n", diag, fdt_strerror(err));
        rc = exit_code(err);
        goto out;
    }
    rc = CLI_OK;
    if (rank == 0) {
        /* The balance over all ranks: every message sent was received, one
         * FACERECV per FACESEND (src/par/termination.c), no ABORT. */
        for (int k = 1; k < FDT_MSG_KIND_END; k++)
            if (r.all_sent[k] != r.all_received[k])
                rc = CLI_INTERNAL;
        if (r.all_sent[FDT_MSG_FACERECV] != r.all_sent[FDT_MSG_FACESEND] ||
            r.all_sent[FDT_MSG_ABORT] != 0)
            rc = CLI_INTERNAL;
        if (rc)
            fprintf(stderr, "frontdt-mpi: internal error: messages sent and received differ\n");
        if (o.stats)
            print_stats(&r, size, t_read);
        if (!o.quiet)
            fprintf(stderr, "frontdt-mpi: %zu points, %zu vertices, %" PRIu64 " tets on %d ranks\n",
                    L.n, L.m, r.hash.count, size);
        if (o.set_hash)
            printf("set-hash: %016" PRIx64 "\n", fdt_sethash_value(&r.hash));
        if (!rc && gather) {
            /* Gathered to rank 0 in input numbering: one result, hashed
             * as frontdt hashes its own, and written by the CLI's writers
             * (temporary file, renamed at the end). */
            res = calloc(1, sizeof *res);
            if (!res) {
                rc = CLI_RESOURCES;
            } else {
                res->tets = r.all_tets;
                res->ntets = r.ntets;
                res->hull = r.all_hull;
                res->nhull = r.nhull;
                res->dupmap = r.all_dupmap;
                res->n = r.n_input;
                res->ndup = r.ndup;
                r.all_tets = NULL;
                r.all_hull = NULL;
                r.all_dupmap = NULL;
                uint64_t h;
                if (o.hash) {
                    if (fdt_result_hash(res, &h) == FDT_OK)
                        printf("hash: %016" PRIx64 "\n", h);
                    else
                        rc = CLI_RESOURCES;
                }
                if (!rc && o.output && o.cells.dual) {
                    rc = write_dual(&o, res, r.all_xyz, r.n_input);
                } else {
                    err = rc || !o.output ? FDT_OK
                                          : fdt_write_mesh(res, r.all_xyz, r.n_input, o.output,
                                                           NULL, diag, sizeof diag);
                    if (err) {
                        fprintf(stderr, "frontdt-mpi: %s\n", diag);
                        rc = err == FDT_ENOMEM ? CLI_RESOURCES : CLI_WRITE;
                    }
                }
                if (!rc && o.vtu)
                    rc = write_vtu_cells(&o, res, r.all_xyz, r.n_input);
            }
        }
        fflush(stdout);
    }
    MPI_Bcast(&rc, 1, MPI_INT, 0, MPI_COMM_WORLD);
    if (!rc && pieces) {
        /* Each rank its piece, rank 0 the index (src/mpi/mpi_output.h): all or
         * nothing, the same code on every rank; the rank that failed says
         * why. */
        double tw = MPI_Wtime();
        fdt_mpo_args oa = {o.output, o.input, o.fail_write};
        int mine = FDT_OK;
        uint64_t io[2];
        err = fdt_mpo_write(MPI_COMM_WORLD, &oa, &L, &r, &mine, io, diag, sizeof diag);
        if (mine)
            fprintf(stderr, "frontdt-mpi: rank %d: %s\n", rank, diag);
        rc = err == FDT_OK ? CLI_OK : err == FDT_ENOMEM ? CLI_RESOURCES : CLI_WRITE;
        if (o.stats) {
            double t[3] = {MPI_Wtime() - tw, (double)io[0], (double)io[1]};
            double *all = rank == 0 ? malloc(3 * (size_t)size * sizeof *all) : NULL;
            MPI_Gather(t, 3, MPI_DOUBLE, all, 3, MPI_DOUBLE, 0, MPI_COMM_WORLD);
            if (rank == 0 && all) {
                fprintf(stderr, "  rank  pieces s   bytes written   bytes sent\n");
                for (int q = 0; q < size; q++)
                    fprintf(stderr, "  %4d %9.3f %15.0f %12.0f\n", q, all[3 * q],
                            all[3 * q + 1], all[3 * q + 2]);
            }
            free(all);
        }
    }
    if (!rc && cells)
        rc = cells_step(&o, &L, &r, rank, size);
out:
    fdt_result_free(&res);
    fdt_mpi_out_free(&r);
    fdt_mpi_local_free(&L);
    return rc;
}

int main(int argc, char **argv)
{
    if (MPI_Init(&argc, &argv) != MPI_SUCCESS) {
        fprintf(stderr, "frontdt-mpi: MPI_Init failed\n");
        return CLI_INTERNAL;
    }
    int rank = 0, size = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    if (fdt_cli_signals("frontdt-mpi", cleanup_outputs, CLI_SIGNAL) != 0)
        fprintf(stderr, "frontdt-mpi: cannot install signal handlers\n"); /* runs on */
    int rc = run(argc, argv, rank, size);
    MPI_Finalize();
    return rc;
}
