/* The options of both programs; see options.h. */
#include "cli/options.h"

#include <stdlib.h>
#include <string.h>

#include "front/search.h"
#include "geom/kdtree.h"
#include "io/read/reader.h"
#include "io/write/writer.h"

#define STR_(x) #x
#define STR(x) STR_(x)

/* --help's text starts in this column (the names before it) */
#define HELP_COLUMN 25

/* getopt_long's val for a long option: this plus its row (above every
 * letter, so a short and a long name never meet) */
#define GETOPT_VAL 256

#define F FDT_CLI_FRONTDT
#define M FDT_CLI_MPI
#define FM FDT_CLI_BOTH

const fdt_cli_opt fdt_cli_opts[FDT_OPT_END] = {
    [FDT_OPT_OUTPUT] = {"output", 'o', required_argument, "FILE", FM, 0,
        "write the mesh (format by extension); may be\n"
        "given up to " STR(FDT_CLI_MAX_OUTPUTS) " times; '-': standard output.\n"
        "An existing output is replaced (as TetGen and\n"
        "gmsh do); an input never is (exit 1)",
        "write the mesh, gathered to rank 0 (.tets .vtu .vtk\n"
        ".msh .mesh polyMesh; not .ele: no neighbours yet),\n"
        "or a piece a rank, by the extension:\n"
        "BASE.pvtu: BASE_RANK.vtu, and the index BASE.pvtu;\n"
        "BASE.pfdtb: BASE_RANK.fdtb (tets and hull faces,\n"
        "ids numbering the input's points), and the text\n"
        "index BASE.pfdtb; BASE.pele: BASE.node (every rank\n"
        "writes its lines), BASE_RANK.ele and .face (TetGen),\n"
        "and the text index BASE.pele"},
    [FDT_OPT_NO_CLOBBER] = {"no-clobber", 0, no_argument, NULL, F, 0,
        "refuse (exit 5, before any work) when any\n"
        "output file exists (.node of -o m.ele too)", NULL},
    [FDT_OPT_FORMAT] = {"format", 0, required_argument, "NAME", F, 0,
        "format of the next -o (of the last -o when\n"
        "none follows); an -o whose extension names\n"
        "another format is refused; or, named xyz, txt,\n"
        "csv, node or ply, the input's (--input-format).\n"
        "The output formats (and their extensions):", NULL},
    [FDT_OPT_ALL_FACES] = {"all-faces", 0, no_argument, NULL, F, 0,
        "TetGen .face lists every face (TetGen -f)", NULL},
    [FDT_OPT_INPUT_FORMAT] = {"input-format", 0, required_argument, "FMT", FM, 0,
        "xyz (also txt, csv), node or ply: the input's\n"
        "format whatever its name (needed for '-')", NULL},
    [FDT_OPT_COLUMNS] = {"columns", 0, required_argument, "X,Y,Z", F, 0,
        "the columns of x, y and z in .xyz/.txt/.csv,\n"
        "counted from 1 as cut -f and awk do (1,2,3)", NULL},
    [FDT_OPT_DELIMITER] = {"delimiter", 0, required_argument, "C", F, 0,
        "the field separator of .xyz/.txt/.csv besides\n"
        "blanks: ',' (default) or ';'; ' ': blanks only", NULL},
    [FDT_OPT_DECIMAL_COMMA] = {"decimal-comma", 0, no_argument, NULL, F, 0,
        "numbers are written 0,5 (then the delimiter\n"
        "is ';' or blanks: blanks unless given)", NULL},
    [FDT_OPT_MODE] = {"mode", 0, required_argument, "MODE", F, 0,
        "serial, shared, message or auto (default)", NULL},
    [FDT_OPT_SEARCH] = {"search", 0, required_argument, "HOW", FM, 0,
        "how apexes are found, each way giving the same\n"
        "mesh. auto, in memory without --mode: the\n"
        "certified insertion mesh built on the threads\n"
        "is the answer; with --mode, the parts read the\n"
        "mesh of every point where a probe finds the kd\n"
        "search costly, else the kd search. mesh, on\n"
        "threads: each part's own mesh, its inner tets\n"
        "final, fronts at the walls. HOW is one of:",
        "how apexes are found, each way giving the same\n"
        "mesh. auto: the kd search; where it degenerates,\n"
        "every rank reads a replica of the DT of every\n"
        "point. mesh: each rank a mesh of its own points.\n"
        "HOW is one of:"},
    [FDT_OPT_LEAF] = {"leaf", 0, required_argument, "N", FM, 0,
        "kd-tree leaf size (default " STR(FDT_DEFAULT_LEAF) ")", NULL},
    [FDT_OPT_NO_PARK] = {"no-park", 0, no_argument, NULL, M, 0,
        "a face waits for each answer of another rank,\n"
        "as frontdt --mode message does (for comparison)", NULL},
    [FDT_OPT_THREADS] = {"threads", 't', required_argument, "N", F, 0,
        "worker threads (0: one per core)", NULL},
    [FDT_OPT_PIN] = {"pin", 0, no_argument, NULL, F, 0,
        "bind thread i to core i", NULL},
    [FDT_OPT_CHECK] = {"check", 0, no_argument, NULL, F, 0,
        "verify the result exactly (exit 3 if not Delaunay)", NULL},
    [FDT_OPT_STATS] = {"stats", 0, no_argument, NULL, FM, 0,
        "print statistics to stderr",
        "print statistics to stderr: each rank's tets,\n"
        "messages and times, and their totals"},
    [FDT_OPT_STATS_JSON] = {"stats-json", 0, required_argument, "FILE", F, 0,
        "write statistics as JSON ('-': stdout)", NULL},
    [FDT_OPT_HASH] = {"hash", 0, no_argument, NULL, FM, 0,
        "print the canonical hash of the tet set",
        "print the canonical hash of the tet set (equals\n"
        "frontdt's; the mesh is gathered to rank 0)"},
    [FDT_OPT_SET_HASH] = {"set-hash", 0, no_argument, NULL, FM, 0,
        "print the set hash (order-independent, no sort)",
        "print the set hash (order-independent, no sort;\n"
        "equals frontdt's)"},
    [FDT_OPT_VORONOI] = {"voronoi", 0, required_argument, "FILE", FM, 0,
        "write each point's Voronoi cell, clipped by the\n"
        "box: a line a point (.csv: a table)", NULL},
    [FDT_OPT_VORONOI_FORMAT] = {"voronoi-format", 0, required_argument, "F", FM, 0,
        "the line, in voro++'s codes: %i %q %v %F %s\n"
        "%n %f %c %C, and %d (DTFE density), %h (flags)\n"
        "(default '%i %q %v %F %s %n %f')", NULL},
    [FDT_OPT_DENSITY] = {"density", 0, required_argument, "FILE", FM, 0,
        "write each point's DTFE density and flags", NULL},
    [FDT_OPT_BOX] = {"box", 0, required_argument, "X0,Y0,Z0,X1,Y1,Z1", FM, 0,
        "the box that clips the cells (default: the\n"
        "points' bounding box; must hold them), or the\n"
        "periodic box of --periodic",
        "the box that clips the cells (default: the\n"
        "points' bounding box; must hold them)"},
    [FDT_OPT_PERIODIC] = {"periodic", 0, required_argument, "AXES", FM, 0,
        "the points are periodic along AXES (x, y, z, or\n"
        "several: x,z or xyz) with the periods of --box\n"
        "(every point in [X0, X1) there): the Delaunay\n"
        "mesh of the periodic set, every tet once; -o\n"
        "FILE.tets: its 4 ids ascending, then each one's\n"
        "image offset (3 integers) from the first's;\n"
        ".fdtb the same; .vtu, .vtk, .msh with the image\n"
        "vertices and their input ids", NULL},
    [FDT_OPT_DUAL] = {"dual", 0, no_argument, NULL, FM, 0,
        "each OpenFOAM -o (DIR/polyMesh) gets the Voronoi\n"
        "cells clipped by the box instead of the tets:\n"
        "a polyhedral cell a point (duplicates none),\n"
        "the walls patches xmin, xmax, ymin, ymax, zmin,\n"
        "zmax; with --periodic each cell whole, the faces\n"
        "across a period cyclic patch pairs", NULL},
    [FDT_OPT_VALUES] = {"values", 0, required_argument, "FILE", F, 0,
        "values at the points (a line a point, k numbers)", NULL},
    [FDT_OPT_INTERPOLATE] = {"interpolate", 0, required_argument, "Q", F, 0,
        "interpolate them at the points of file Q into", NULL},
    [FDT_OPT_INTERPOLATED] = {"interpolated", 0, required_argument, "OUT", F, 0,
        "(a line a query; nan outside the hull)", NULL},
    [FDT_OPT_METHOD] = {"method", 0, required_argument, "M", F, 0,
        "natural (Sibson, default) or linear", NULL},
    [FDT_OPT_STREAM] = {"stream", 0, no_argument, NULL, F, 0,
        "write the tets as they are built, never holding\n"
        "the mesh (.ele without .neigh, .vtu, .fdtb; no\n"
        "-o: count them); the points are stored once\n"
        "(about 60 bytes a point); refuses an output or\n"
        "option that needs the mesh", NULL},
    [FDT_OPT_NO_STREAM] = {"no-stream", 0, no_argument, NULL, F, 0,
        "keep the whole mesh (default streams when every\n"
        "-o is .vtu or .fdtb and nothing needs the mesh)", NULL},
    [FDT_OPT_MEMORY_LIMIT] = {"memory-limit", 0, required_argument, "B", F, 0,
        "refuse (exit 4) a run whose estimated memory\n"
        "exceeds B bytes (suffixes K, M, G: 2^10..2^30)", NULL},
    [FDT_OPT_QUIET] = {"quiet", 'q', no_argument, NULL, FM, 0,
        "no summary, no progress, no notes",
        "print nothing but errors (and what is asked)"},
    [FDT_OPT_PROGRESS] = {"progress", 0, no_argument, NULL, F, 0,
        "draw the progress line on stderr even when it\n"
        "is not a terminal (it is drawn on terminals)", NULL},
    /* getopt_long's optional value is "--demo=N" alone: main.c's
     * rewrite_demo turns "--demo N" into it */
    [FDT_OPT_DEMO] = {"demo", 0, optional_argument, "[N]", F, 0,
        "triangulate N random points in the unit cube\n"
        "(fixed seed; default " STR(FDT_CLI_DEMO_POINTS) ")", NULL},
    [FDT_OPT_HELP] = {"help", 'h', no_argument, NULL, FM, 0, "this help", NULL},
    [FDT_OPT_VERSION] = {"version", 'V', no_argument, NULL, FM, 0, "version", NULL},
    /* RANK:FACES: rank RANK fails once it advanced FACES faces
     * (tests/test_mpi.sh) */
    [FDT_OPT_INJECT_FAILURE] = {"inject-failure", 0, required_argument, "RANK:FACES", M, 1,
        NULL, NULL},
    /* RANK: rank RANK's piece fails once written, and the others' are
     * then removed (tests/test_mpi.sh) */
    [FDT_OPT_INJECT_WRITE_FAILURE] = {"inject-write-failure", 0, required_argument, "RANK", M,
        1, NULL, NULL},
};

/* --search's list under its text: a line a row of src/front/search.c, so
 * a new search is listed by its row alone. */
static void help_searches(FILE *f)
{
    int width = 0;
    for (int s = 0; fdt_search_row_of((fdt_search)s); s++) {
        int k = (int)strlen(fdt_search_row_of((fdt_search)s)->name);
        width = k > width ? k : width;
    }
    for (int s = 0; fdt_search_row_of((fdt_search)s); s++) {
        const fdt_search_row *r = fdt_search_row_of((fdt_search)s);
        fprintf(f, "\n%*s  %-*s  %s", HELP_COLUMN, "", width, r->name, r->help);
    }
}

/* --format's list under its text: the writers' table (src/io/write/
 * writer.c), so a new format is listed by its row alone; wrapped at
 * the help's width. */
static void help_formats(FILE *f)
{
    const char *p = fdt_format_list();
    int col = HELP_COLUMN + 48;
    int x = col; /* start a line at once */
    while (*p) {
        const char *e = strchr(p, ',');
        int len = e ? (int)(e - p) + 1 : (int)strlen(p);
        if (x + 1 + len > col) {
            fprintf(f, "\n%*s", HELP_COLUMN, "");
            x = HELP_COLUMN;
        } else {
            fputc(' ', f);
            x++;
        }
        fprintf(f, "%.*s", len, p);
        x += len;
        p += len;
        while (*p == ' ')
            p++;
    }
}

void fdt_cli_help(FILE *f, unsigned prog)
{
    for (int i = 0; i < FDT_OPT_END; i++) {
        const fdt_cli_opt *o = &fdt_cli_opts[i];
        if (!(o->progs & prog) || o->hidden)
            continue;
        int k = o->letter ? fprintf(f, "  -%c, --%s", o->letter, o->name)
                          : fprintf(f, "      --%s", o->name);
        if (o->value)
            k += fprintf(f, " %s", o->value);
        /* a name too wide for the column: its text starts below it */
        if (k >= HELP_COLUMN) {
            fputc('\n', f);
            k = 0;
        }
        fprintf(f, "%*s", HELP_COLUMN - k, "");
        const char *text = prog == FDT_CLI_MPI && o->help_mpi ? o->help_mpi : o->help;
        for (const char *p = text; *p; p++) {
            fputc(*p, f);
            if (*p == '\n')
                fprintf(f, "%*s", HELP_COLUMN, "");
        }
        if (i == FDT_OPT_SEARCH)
            help_searches(f);
        if (i == FDT_OPT_FORMAT)
            help_formats(f);
        fputc('\n', f);
    }
}

void fdt_cli_getopt_args(unsigned prog, struct option *longs, char *shorts)
{
    size_t nl = 0, ns = 0;
    shorts[ns++] = ':'; /* a missing value answers ':', apart from '?' */
    for (int i = 0; i < FDT_OPT_END; i++) {
        const fdt_cli_opt *o = &fdt_cli_opts[i];
        if (!(o->progs & prog))
            continue;
        longs[nl++] = (struct option){o->name, o->arg, NULL, GETOPT_VAL + i};
        if (o->letter) {
            shorts[ns++] = o->letter;
            if (o->arg == required_argument)
                shorts[ns++] = ':';
        }
    }
    longs[nl] = (struct option){NULL, 0, NULL, 0};
    shorts[ns] = '\0';
}

int fdt_cli_getopt_id(int ch)
{
    if (ch >= GETOPT_VAL && ch < GETOPT_VAL + FDT_OPT_END)
        return ch - GETOPT_VAL;
    for (int i = 0; i < FDT_OPT_END; i++)
        if (fdt_cli_opts[i].letter && fdt_cli_opts[i].letter == ch)
            return i;
    return -1;
}

int fdt_cli_find(const char *word, unsigned prog)
{
    if (word[0] != '-')
        return -1;
    for (int i = 0; i < FDT_OPT_END; i++) {
        const fdt_cli_opt *o = &fdt_cli_opts[i];
        if (!(o->progs & prog))
            continue;
        if (word[1] == '-' ? !strcmp(word + 2, o->name)
                           : o->letter && word[1] == o->letter && !word[2])
            return i;
    }
    return -1;
}

int fdt_cli_search(const char *name, fdt_search *out, char *err, size_t len)
{
    if (fdt_search_from_name(name, out) == FDT_OK)
        return 0;
    /* the table's names, "auto, kd or mesh" */
    char names[128] = "";
    for (int s = 0; fdt_search_name((fdt_search)s); s++) {
        size_t used = strlen(names);
        const char *sep = s == 0 ? "" : fdt_search_name((fdt_search)(s + 1)) ? ", " : " or ";
        snprintf(names + used, sizeof names - used, "%s%s", sep, fdt_search_name((fdt_search)s));
    }
    snprintf(err, len, "unknown search '%s' (%s)", name, names);
    return -1;
}

int fdt_cli_leaf(const char *s, int *out, char *err, size_t len)
{
    char *end;
    long x = strtol(s, &end, 10);
    if (*end || x < 1 || x > 1000000) {
        snprintf(err, len, "--leaf wants 1..1000000, not '%s'", s);
        return -1;
    }
    *out = (int)x;
    return 0;
}

int fdt_cli_periodic(const char *v, unsigned *axes, char *err, size_t len)
{
    unsigned a = 0;
    for (const char *q = v; *q; q++) {
        const char *ax = strchr("xyz", *q);
        if (*q == ',' && q != v && q[1])
            continue;
        if (!ax || (a >> (ax - "xyz") & 1)) {
            snprintf(err, len, "--periodic takes axes x, y, z, once each (x,z or xyz), not '%s'",
                     v);
            return -1;
        }
        a |= 1u << (ax - "xyz");
    }
    if (!a) {
        snprintf(err, len, "--periodic takes axes x, y, z (x,z or xyz), not '%s'", v);
        return -1;
    }
    *axes = a;
    return 0;
}

int fdt_cli_input_format(const char *name, int *out, char *err, size_t len)
{
    int f = fdt_rd_format_by_name(name);
    if (f == FDT_RD_AUTO) {
        snprintf(err, len, "unknown input format '%s' (xyz, txt, csv, node or ply)", name);
        return -1;
    }
    *out = f;
    return 0;
}
