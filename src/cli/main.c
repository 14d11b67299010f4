/*
 * frontdt: the command-line tool. Reads a point cloud (src/io/read/reader.h),
 * triangulates it with the library (include/frontdt.h), optionally checks
 * the result and writes it (src/io/write/writer.h).
 *
 * Exit codes (also listed by --help; scripts and tests rely on them):
 *   0  success
 *   1  usage error (bad option or value, missing input, a setting the
 *      library refuses, unknown output extension, an output that would
 *      overwrite the input)
 *   2  bad input: unreadable or malformed file, unknown input extension,
 *      NaN/Inf, fewer than 4 distinct points, all points coplanar
 *   3  --check found the mesh is not the Delaunay tetrahedralization
 *   4  out of resources: memory, index range, threads
 *   5  cannot write the output (also an output that exists, with
 *      --no-clobber)
 *   6  interrupted by SIGINT or SIGTERM (no temporary file left, every
 *      output as before the run: the outputs are renamed all together at
 *      the end, fdt_wr_set_commit)
 *   7  internal error (a bug: please report it)
 *
 * Everything the tool says goes to stderr with a "frontdt: " prefix, except
 * the summary and the --hash line, which go to stdout (to stderr when
 * "--stats-json -" claims stdout for the JSON object alone).
 */
#include "frontdt.h"
#include "cli/cli.h"
#include "cli/dual.h"
#include "cli/options.h"
#include "base/clock.h"
#include "base/hash.h"
#include "cli/progress.h"
#include "front/partmesh.h"
#include "front/sweep.h"
#include "geom/prepare.h"
#include "io/read/reader.h"
#include "io/write/writer.h"

#include <errno.h>
#include <getopt.h>
#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* Fixed so that "--demo N" is the same point set on every run and host. */
#define DEMO_SEED UINT64_C(0x5eed0f0f1992)

typedef struct cli {
    const char *input;      /* NULL with --demo; "-": standard input */
    int input_format;       /* FDT_RD_AUTO: by the input's extension */
    const char *input_format_name; /* --input-format as given, or NULL */
    int columns[3];         /* --columns, from 1; {0, 0, 0}: 1, 2, 3 */
    char delimiter;         /* --delimiter: ',', ';', ' '; 0: not given */
    int decimal_comma;      /* --decimal-comma */
    int progress;           /* --progress: draw even when not a terminal */
    const char *output;     /* the first -o; NULL: triangulate and report only */
    const char *outputs[FDT_CLI_MAX_OUTPUTS]; /* every -o, in order ("-": stdout) */
    const char *out_format[FDT_CLI_MAX_OUTPUTS]; /* its --format, NULL: by extension */
    int n_outputs;
    const char *format;     /* a --format not yet taken by an -o */
    int all_faces;          /* --all-faces: TetGen .face with every face */
    const char *stats_json; /* NULL, a path, or "-" for stdout */
    fdt_mode mode;
    fdt_search search;
    int leaf;               /* --leaf; 0: the library's default */
    int threads;            /* -1: the library's default */
    int pin, check, stats, hash, set_hash, quiet;
    int no_clobber;         /* --no-clobber: refuse to replace any output */
    int stream;             /* --stream 1, --no-stream -1, else 0: when
                               every output can (stream_refusal) */
    unsigned long long memory_limit; /* --memory-limit bytes; 0: none */
    unsigned periodic;      /* --periodic: bit k for axis k */
    fdt_cli_dual dual;      /* --voronoi, --voronoi-format, --density, --box,
                               --values, --interpolate, --interpolated, --method */
    int demo;
    size_t demo_n;
} cli;

static void usage(FILE *f)
{
    fputs("Usage: frontdt [options] INPUT [-o OUTPUT]\n"
          "       frontdt --demo [N] [options] [-o OUTPUT]\n"
          "Exact 3D Delaunay tetrahedralization by the advancing front.\n"
          "\n"
          "INPUT:  .xyz/.txt/.csv (x y z per line; more columns skipped; a first\n"
          "        line of words is a header), .node (TetGen), .ply; '-' is standard\n"
          "        input (needs --input-format)\n"
          "OUTPUT: .tets (canonical sorted text), .ele (TetGen .node/.ele/\n"
          "        .face/.neigh), .vtu (VTK XML, ParaView), .vtk (VTK legacy),\n"
          "        .msh (gmsh 4.1), .mesh (Medit), DIR/polyMesh (OpenFOAM),\n"
          "        .fdtb (frontdt binary)\n"
          "\n"
          "Options:\n",
          f);
    fdt_cli_help(f, FDT_CLI_FRONTDT);
    fputs("\n"
          "Exit codes:\n"
          "  0 success             1 usage error (also '-' without --input-format,\n"
          "                          --columns for .node/.ply)   2 bad input\n"
          "  3 --check failed      4 out of resources (also over --memory-limit)\n"
          "  5 cannot write output (also --no-clobber)\n"
          "  6 interrupted (every output left as it was)\n"
          "  7 internal error\n"
          "Outputs are all or none: each is written to a temporary file, and only\n"
          "when all are complete are they renamed over their names.\n",
          f);
}

static void say(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("frontdt: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
}

static int usage_error(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("frontdt: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    fputs("Try 'frontdt --help' for more information.\n", stderr);
    return CLI_USAGE;
}

/* ------------------------------------------------------------------------ */
/* Signals                                                                   */
/* ------------------------------------------------------------------------ */

/* SIGINT/SIGTERM remove the temporary output files and put back any
 * output the final commit already replaced (fdt_write_cleanup) and leave
 * with exit code 6; SIGXFSZ is ignored (src/cli/cli.h). */

/* ------------------------------------------------------------------------ */
/* Argument parsing                                                          */
/* ------------------------------------------------------------------------ */

static int all_digits(const char *s)
{
    if (!*s)
        return 0;
    for (; *s; s++)
        if (*s < '0' || *s > '9')
            return 0;
    return 1;
}

/* A decimal count: digits only, no sign, no overflow. */
static int parse_count(const char *s, unsigned long long max,
                       unsigned long long *v)
{
    if (!all_digits(s))
        return -1;
    errno = 0;
    char *end;
    unsigned long long x = strtoull(s, &end, 10);
    if (errno || *end || x > max)
        return -1;
    *v = x;
    return 0;
}

/* A byte count for --memory-limit: digits, then K, M or G (binary:
 * 2^10, 2^20, 2^30; any case, an optional trailing B or iB). 0 refused. */
static int parse_bytes(const char *s, unsigned long long *v)
{
    size_t d = 0;
    while (s[d] >= '0' && s[d] <= '9')
        d++;
    if (d == 0 || d > 19)
        return -1;
    errno = 0;
    char *end;
    unsigned long long x = strtoull(s, &end, 10);
    if (errno || x == 0)
        return -1;
    unsigned shift = 0;
    switch (*end) {
    case 'k': case 'K': shift = 10; end++; break;
    case 'm': case 'M': shift = 20; end++; break;
    case 'g': case 'G': shift = 30; end++; break;
    default: break;
    }
    if (shift && *end == 'i')
        end++;
    if (*end == 'b' || *end == 'B')
        end++;
    if (*end || (shift && x > (ULLONG_MAX >> shift)))
        return -1;
    *v = x << shift;
    return 0;
}

/*
 * getopt_long's optional_argument only takes "--demo=N"; "--demo N" with a
 * separate numeric word is rewritten to "--demo=N" before parsing (an
 * input file named by digits alone cannot be meant with --demo, which
 * takes no input). Returns a new argv (strings borrowed or owned by
 * *owned) or NULL when out of memory.
 */
static char **rewrite_demo(int argc, char **argv, int *new_argc,
                           char ***owned, int *n_owned)
{
    char **out = calloc((size_t)argc + 1, sizeof *out);
    char **own = calloc((size_t)argc + 1, sizeof *own);
    if (!out || !own) {
        free(out);
        free(own);
        return NULL;
    }
    int k = 0, no = 0, options_done = 0;
    for (int i = 0; i < argc; i++) {
        if (i > 0 && !options_done && strcmp(argv[i], "--") == 0)
            options_done = 1;
        if (i > 0 && !options_done && strcmp(argv[i], "--demo") == 0 &&
            i + 1 < argc && all_digits(argv[i + 1])) {
            size_t len = strlen(argv[i + 1]) + sizeof "--demo=";
            char *s = malloc(len);
            if (!s) {
                for (int j = 0; j < no; j++)
                    free(own[j]);
                free(own);
                free(out);
                return NULL;
            }
            snprintf(s, len, "--demo=%s", argv[i + 1]);
            own[no++] = s;
            out[k++] = s;
            i++;
            continue;
        }
        out[k++] = argv[i];
    }
    out[k] = NULL;
    *new_argc = k;
    *owned = own;
    *n_owned = no;
    return out;
}

/* Was the option getopt_long just refused a short one ("-x")? Then
 * optopt names it; for long ones we quote the word instead. */
static int short_opt(char **argv, int ind)
{
    return optopt > 0 && optopt < 128 && ind > 0 && argv[ind - 1] &&
           strncmp(argv[ind - 1], "--", 2) != 0;
}

/* "3,4,5": three distinct columns counted from 1 (cut -f, awk, gnuplot's
 * "using 3:4:5"). 0 or -1 on anything else. */
static int parse_columns(const char *s, int cols[3])
{
    for (int k = 0; k < 3; k++) {
        const char *end = strchr(s, ',');
        size_t len = end ? (size_t)(end - s) : strlen(s);
        char word[16];
        unsigned long long v;
        if ((k < 2) != (end != NULL) || len == 0 || len >= sizeof word)
            return -1;
        memcpy(word, s, len);
        word[len] = '\0';
        if (parse_count(word, 1000000, &v) != 0 || v == 0)
            return -1;
        cols[k] = (int)v;
        s = end ? end + 1 : s + len;
    }
    if (cols[0] == cols[1] || cols[0] == cols[2] || cols[1] == cols[2])
        return -1;
    return 0;
}

/* -o FILE: at most FDT_CLI_MAX_OUTPUTS, each named once; it takes the
 * --format given before it. */
static int take_output(cli *c, const char *out)
{
    if (c->n_outputs == FDT_CLI_MAX_OUTPUTS)
        return usage_error("-o given more than %d times", FDT_CLI_MAX_OUTPUTS);
    if (!*out)
        return usage_error("empty output file name");
    for (int i = 0; i < c->n_outputs; i++)
        if (!strcmp(c->outputs[i], out))
            return usage_error("-o %s given twice", out);
    if (!c->output)
        c->output = out;
    c->out_format[c->n_outputs] = c->format;
    c->outputs[c->n_outputs++] = out;
    c->format = NULL; /* --format is one -o's */
    return -1;
}

/* One option names both, as issue 17 asks (--format xyz for standard
 * input, --format msh2 for an output): the input formats' names (xyz,
 * txt, csv, node, ply) and the output formats' never meet, so the name
 * says which is meant. */
static int take_format(cli *c, const char *name)
{
    if (!fdt_format_by_name(name) && fdt_rd_format_by_name(name) != FDT_RD_AUTO) {
        c->input_format = fdt_rd_format_by_name(name);
        c->input_format_name = name;
        return -1;
    }
    if (!fdt_format_by_name(name))
        return usage_error("unknown format '%s' (input: xyz, txt, csv, node, ply; "
                           "output: %s)", name, fdt_format_list());
    c->format = name;
    return -1;
}

static int take_mode(cli *c, const char *name)
{
    if (!strcmp(name, "serial"))
        c->mode = FDT_MODE_SERIAL;
    else if (!strcmp(name, "shared"))
        c->mode = FDT_MODE_SHARED;
    else if (!strcmp(name, "message"))
        c->mode = FDT_MODE_MESSAGE;
    else if (!strcmp(name, "auto"))
        c->mode = FDT_MODE_AUTO;
    else
        return usage_error("unknown mode '%s' (serial, shared, message or auto)", name);
    return -1;
}

/* The options of the Voronoi and interpolation step (src/cli/dual.h). */
static int take_dual(fdt_cli_dual *d, int id, const char *v)
{
    switch (id) {
    case FDT_OPT_VORONOI:
        d->voronoi = v;
        break;
    case FDT_OPT_VORONOI_FORMAT:
        d->format = v;
        break;
    case FDT_OPT_DENSITY:
        d->density = v;
        break;
    case FDT_OPT_DUAL:
        d->dual = 1;
        break;
    case FDT_OPT_BOX: {
        char err[FDT_IO_PATH + 200];
        if (fdt_cli_parse_box(v, d->box, err, sizeof err) != 0)
            return usage_error("%s", err);
        d->box_given = 1;
        break;
    }
    case FDT_OPT_VALUES:
        d->values = v;
        break;
    case FDT_OPT_INTERPOLATE:
        d->queries = v;
        break;
    case FDT_OPT_INTERPOLATED:
        d->interpolated = v;
        break;
    default: /* FDT_OPT_METHOD */
        if (strcmp(v, "natural") && strcmp(v, "linear"))
            return usage_error("--method is natural or linear, not '%s'", v);
        d->natural = !strcmp(v, "natural");
        break;
    }
    return -1;
}

/* --help and --version: 0, or 5 when standard output fails. */
static int help_or_version(int id)
{
    if (id == FDT_OPT_HELP)
        usage(stdout);
    else
        printf("frontdt %s (library %s)\n", FDT_VERSION_STRING, fdt_version());
    /* a help longer than stdio's buffer meets the error in fprintf
     * already: the stream's error flag keeps it (and errno its reason) */
    if (fflush(stdout) != 0 || ferror(stdout)) {
        say("stdout: %s", strerror(errno ? errno : EIO));
        return CLI_WRITE;
    }
    return CLI_OK;
}

/* The options that only switch something on: the field, or NULL. */
static int *flag_of(cli *c, int id)
{
    switch (id) {
    case FDT_OPT_NO_CLOBBER: return &c->no_clobber;
    case FDT_OPT_ALL_FACES: return &c->all_faces;
    case FDT_OPT_DECIMAL_COMMA: return &c->decimal_comma;
    case FDT_OPT_PIN: return &c->pin;
    case FDT_OPT_CHECK: return &c->check;
    case FDT_OPT_STATS: return &c->stats;
    case FDT_OPT_HASH: return &c->hash;
    case FDT_OPT_SET_HASH: return &c->set_hash;
    case FDT_OPT_QUIET: return &c->quiet;
    case FDT_OPT_PROGRESS: return &c->progress;
    default: return NULL;
    }
}

/* One option of the table's (src/cli/options.h) with its value v (NULL
 * when it takes none). -1 to go on, or an exit code. */
static int take_option(cli *c, int id, const char *v)
{
    char err[256];
    unsigned long long n;
    int *flag = flag_of(c, id);
    if (flag) {
        *flag = 1;
        return -1;
    }
    switch (id) {
    case FDT_OPT_OUTPUT:
        return take_output(c, v);
    case FDT_OPT_FORMAT:
        return take_format(c, v);
    case FDT_OPT_INPUT_FORMAT:
        if (fdt_cli_input_format(v, &c->input_format, err, sizeof err) != 0)
            return usage_error("%s", err);
        c->input_format_name = v;
        return -1;
    case FDT_OPT_COLUMNS:
        if (parse_columns(v, c->columns) != 0)
            return usage_error("--columns wants three different column numbers "
                               "from 1, as 3,4,5, not '%s'", v);
        return -1;
    case FDT_OPT_DELIMITER:
        if (strlen(v) != 1 || !strchr(",; ", v[0]))
            return usage_error("--delimiter is ',', ';' or ' ' (blanks only), not '%s'", v);
        c->delimiter = v[0];
        return -1;
    case FDT_OPT_MODE:
        return take_mode(c, v);
    case FDT_OPT_PERIODIC:
        if (fdt_cli_periodic(v, &c->periodic, err, sizeof err) != 0)
            return usage_error("%s", err);
        return -1;
    case FDT_OPT_SEARCH:
        if (fdt_cli_search(v, &c->search, err, sizeof err) != 0)
            return usage_error("%s", err);
        return -1;
    case FDT_OPT_LEAF:
        if (fdt_cli_leaf(v, &c->leaf, err, sizeof err) != 0)
            return usage_error("%s", err);
        return -1;
    case FDT_OPT_THREADS:
        if (parse_count(v, INT_MAX, &n) != 0)
            return usage_error("--threads wants a count, not '%s'", v);
        c->threads = (int)n;
        return -1;
    case FDT_OPT_STATS_JSON:
        if (!*v)
            return usage_error("empty --stats-json file name");
        c->stats_json = v;
        return -1;
    case FDT_OPT_STREAM:
    case FDT_OPT_NO_STREAM:
        if (c->stream != 0 && c->stream != (id == FDT_OPT_STREAM ? 1 : -1))
            return usage_error("--stream and --no-stream together");
        c->stream = id == FDT_OPT_STREAM ? 1 : -1;
        return -1;
    case FDT_OPT_MEMORY_LIMIT:
        if (parse_bytes(v, &c->memory_limit) != 0)
            return usage_error("--memory-limit wants a byte count > 0 (suffix K, M or G), "
                               "not '%s'", v);
        return -1;
    case FDT_OPT_DEMO:
        c->demo = 1;
        if (v) {
            if (parse_count(v, SIZE_MAX, &n) != 0)
                return usage_error("--demo wants a point count, not '%s'", v);
            c->demo_n = (size_t)n;
        }
        return -1;
    case FDT_OPT_VORONOI:
    case FDT_OPT_VORONOI_FORMAT:
    case FDT_OPT_DENSITY:
    case FDT_OPT_BOX:
    case FDT_OPT_DUAL:
    case FDT_OPT_VALUES:
    case FDT_OPT_INTERPOLATE:
    case FDT_OPT_INTERPOLATED:
    case FDT_OPT_METHOD:
        return take_dual(&c->dual, id, v);
    case FDT_OPT_HELP:
    case FDT_OPT_VERSION:
        return help_or_version(id);
    default:
        say("internal error: option row %d has no parser", id);
        return CLI_INTERNAL;
    }
}

/* What getopt_long refused (ch ':' for a missing value, else '?'). */
static int bad_option(int ch, char **argv)
{
    if (ch == ':') {
        if (short_opt(argv, optind))
            return usage_error("option -%c needs a value", optopt);
        return usage_error("option %s needs a value", argv[optind - 1]);
    }
    if (short_opt(argv, optind))
        return usage_error("unknown option -%c", optopt);
    return usage_error("unknown, ambiguous or misused option %s", argv[optind - 1]);
}

/* The input (npos words from pos) and the options that depend on each
 * other, once all are read. -1 to go on, or an exit code. */
static int check_args(cli *c, int npos, char **pos)
{
    /* "-o m.msh --format msh2": a --format after the last -o is that
     * -o's (the others keep their extensions) */
    if (c->format && c->n_outputs > 0 && !c->out_format[c->n_outputs - 1])
        c->out_format[c->n_outputs - 1] = c->format;
    if (c->demo) {
        if (npos > 0)
            return usage_error("--demo takes no input file (got '%s')", pos[0]);
    } else {
        if (npos == 0)
            return usage_error("no input file");
        if (npos > 1)
            return usage_error("one input file only (got '%s' and '%s')", pos[0], pos[1]);
        c->input = pos[0];
        /* "-" has no extension to go by; a format without columns cannot
         * take --columns. Both refused before anything is read. */
        int fmt = c->input_format != FDT_RD_AUTO ? c->input_format
                                                 : fdt_rd_format_of_path(c->input);
        if (!strcmp(c->input, "-") && c->input_format == FDT_RD_AUTO)
            return usage_error("reading standard input ('-') needs --input-format "
                               "xyz, node or ply");
        if (c->columns[0] && fmt != FDT_RD_XYZ && fmt != FDT_RD_AUTO)
            return usage_error("--columns applies to .xyz, .txt and .csv input only");
        if ((c->delimiter || c->decimal_comma) && fmt != FDT_RD_XYZ && fmt != FDT_RD_AUTO)
            return usage_error("--delimiter and --decimal-comma apply to .xyz, .txt and .csv "
                               "input only");
    }
    if (c->decimal_comma && c->delimiter == ',')
        return usage_error("--decimal-comma with --delimiter ',': a comma cannot be both; "
                           "the fields of such a file are separated by ';' or blanks");
    if (c->demo && (c->input_format != FDT_RD_AUTO || c->columns[0] || c->delimiter ||
                    c->decimal_comma))
        return usage_error("--input-format, --columns, --delimiter and --decimal-comma need "
                           "an input file, not --demo");
    if (c->periodic) {
        /* the periodic mesh, in memory unless --stream; every output
         * format (laid out in space but .tets and .fdtb) */
        if (!c->dual.box_given)
            return usage_error("--periodic needs --box X0,Y0,Z0,X1,Y1,Z1: the periods");
        if (c->all_faces)
            return usage_error("--periodic: TetGen's .face lists the hull, not every face "
                               "(--all-faces)");
        if (fdt_cli_interp_wanted(&c->dual) && c->stream > 0)
            return usage_error("--periodic --interpolate needs the mesh in memory (no "
                               "--stream)");
        if (c->stream <= 0) /* in memory unless asked (its slabs: --stream) */
            c->stream = -1;
    }
    /* the dual's threads: the run's */
    c->dual.threads = c->mode == FDT_MODE_SERIAL ? 1 : c->threads < 0 ? 0 : c->threads;
    char derr[512];
    int box_only = c->periodic && c->dual.box_given && !fdt_cli_dual_wanted(&c->dual);
    if (box_only)
        c->dual.box_given = 0; /* the periods, not a clipping box: kept in dual.box */
    if (fdt_cli_dual_check(&c->dual, c->input && strcmp(c->input, "-") ? c->input : NULL, derr,
                           sizeof derr) != 0)
        return usage_error("%s", derr);
    c->dual.box_given |= box_only;
    return -1;
}

/* Returns -1 to go on, or an exit code (0 after --help/--version). */
static int parse_args(int argc, char **argv, cli *c)
{
    memset(c, 0, sizeof *c);
    c->mode = FDT_MODE_AUTO;
    c->threads = -1;
    c->dual.natural = 1;
    c->demo_n = FDT_CLI_DEMO_POINTS;
    struct option longs[FDT_OPT_END + 1];
    char shorts[2 * FDT_OPT_END + 2];
    fdt_cli_getopt_args(FDT_CLI_FRONTDT, longs, shorts);
    opterr = 0; /* we print our own messages */
    optind = 1;
    int ch;
    while ((ch = getopt_long(argc, argv, shorts, longs, NULL)) != -1) {
        int id = fdt_cli_getopt_id(ch);
        int code = id < 0 ? bad_option(ch, argv) : take_option(c, id, optarg);
        if (code >= 0)
            return code;
    }
    return check_args(c, argc - optind, argv + optind);
}

/* ------------------------------------------------------------------------ */
/* Output pre-checks (before the long computation)                          */
/* ------------------------------------------------------------------------ */

/*
 * Refuses, before anything is read, a run that would replace a file it
 * reads: any file of the output's set (names[0..k), from
 * fdt_output_files(), so "-o m.ele" covers m.node too) that is the input,
 * and the --stats-json file, written after the mesh, where it is the
 * input or one of the mesh's files. "Is" means the same file by any name
 * (fdt_same_file: "./x", "d/../x", absolute, symbolic or hard links).
 * Without this "frontdt m.node -o m.ele" rewrote m.node, its attributes,
 * markers, comments and 1-based numbering lost. Returns -1 to go on, or
 * CLI_USAGE after naming both files.
 */
static int refuse_overwrites(const cli *c, const char *output, char names[][FDT_IO_PATH],
                             int k)
{
    const char *json = c->stats_json && strcmp(c->stats_json, "-") != 0
                           ? c->stats_json
                           : NULL;
    /* Standard input is no file of ours to overwrite. */
    const char *in = c->input && strcmp(c->input, "-") != 0 ? c->input : NULL;
    for (int i = 0; i < k; i++) {
        /* The set's other files are named with their -o: the user typed
         * m.ele and should hear why m.node is at stake. */
        char via[FDT_IO_PATH + 32] = "";
        if (strcmp(names[i], output) != 0)
            snprintf(via, sizeof via, " (written with -o %s)", output);
        if (in && fdt_same_file(names[i], in)) {
            say("output %s%s would overwrite the input %s", names[i], via, in);
            return CLI_USAGE;
        }
        if (json && fdt_same_file(names[i], json)) {
            say("--stats-json file %s would overwrite the output %s%s", json,
                names[i], via);
            return CLI_USAGE;
        }
    }
    if (json && in && fdt_same_file(json, in)) {
        say("--stats-json file %s would overwrite the input %s", json, in);
        return CLI_USAGE;
    }
    return -1;
}

/*
 * --no-clobber: refuses, before anything is read, an output any of whose
 * files (names[0..k), so "-o m.ele" covers m.node too) exists, a
 * dangling symbolic link included (the rename would replace the link).
 * Returns -1 to go on, or CLI_WRITE after naming the file. The commit
 * checks again before it renames (fdt_wr_set_begin).
 */
static int refuse_clobber(const cli *c, const char *output, char names[][FDT_IO_PATH], int k)
{
    if (!c->no_clobber)
        return -1;
    for (int i = 0; i < k; i++) {
        struct stat st;
        if (lstat(names[i], &st) != 0)
            continue;
        if (strcmp(names[i], output) != 0)
            say("output %s (written with -o %s) exists; --no-clobber keeps it", names[i],
                output);
        else
            say("output %s exists; --no-clobber keeps it", names[i]);
        return CLI_WRITE;
    }
    return -1;
}

/* Can a file be created at path (fdt_output_dir_check)? Says why not. */
static int output_dir_ok(const char *role, const char *path)
{
    char err[2 * FDT_IO_PATH + 100];
    if (fdt_output_dir_check(role, path, err, sizeof err) == 0)
        return 1;
    say("%s", err);
    return 0;
}

/* ------------------------------------------------------------------------ */
/* Demo points                                                               */
/* ------------------------------------------------------------------------ */

/* splitmix64 (src/base/hash.h) expands the seed into the xoshiro256**
 * state (Blackman and Vigna 2018), which draws the points. */

/* n points uniform in [0, 1)^3, 53 random bits per coordinate. */
static double *demo_points(size_t n)
{
    if (n > SIZE_MAX / (3 * sizeof(double)))
        return NULL;
    double *xyz = malloc(n > 0 ? 3 * n * sizeof *xyz : 1);
    if (!xyz)
        return NULL;
    uint64_t seed = DEMO_SEED, s[4];
    for (int i = 0; i < 4; i++)
        s[i] = fdt_splitmix64(&seed);
    for (size_t i = 0; i < 3 * n; i++)
        xyz[i] = (double)(fdt_xoshiro256ss(s) >> 11) * 0x1.0p-53;
    return xyz;
}

/* Threads for reading a text file: those of the triangulation, at most
 * one an online CPU (more only take turns); one in serial mode, so that
 * mode stays sequential from end to end. */
static int reader_threads(const cli *c)
{
    if (c->mode == FDT_MODE_SERIAL || c->threads == 1)
        return 1;
    long cpus = sysconf(_SC_NPROCESSORS_ONLN);
    if (cpus < 1)
        return 1;
    return c->threads > 1 && c->threads < cpus ? c->threads : (int)(cpus > 64 ? 64 : cpus);
}

/* fdt_read_points_opts: everything but memory is the input's fault (the
 * CLI refuses a bad --input-format, "-" without it and misplaced
 * --columns up front, as usage errors). */
static int exit_for_reader(int err)
{
    return err == FDT_ENOMEM ? CLI_RESOURCES : CLI_INPUT;
}

/* fdt_write_mesh_opts: formats, standard output and neighbours were
 * settled before the run, so FDT_EINVAL here is ours, as FDT_EINTERNAL. */
static int exit_for_writer(int err)
{
    switch (err) {
    case FDT_EIO:
        return CLI_WRITE;
    case FDT_ENOMEM:
        return CLI_RESOURCES;
    default:
        return CLI_INTERNAL;
    }
}

static const char *mode_name(fdt_mode m)
{
    switch (m) {
    case FDT_MODE_SERIAL:
        return "serial";
    case FDT_MODE_SHARED:
        return "shared";
    case FDT_MODE_MESSAGE:
        return "message";
    default:
        return "auto";
    }
}

/* ------------------------------------------------------------------------ */
/* Statistics                                                                */
/* ------------------------------------------------------------------------ */

typedef struct timings {
    double read, triangulate, check, canon, write, voronoi, interpolate;
} timings;

/* The engine's name and line (an unknown value: "unknown"). */
static const char *engine_word(const fdt_stats *st, int about)
{
    const char *w = about ? fdt_engine_about(st->engine) : fdt_engine_name(st->engine);
    return w ? w : "unknown";
}

/* The parts' engines (fdt_engine): their messages and threads' figures. */
static int ran_parts(const fdt_stats *st)
{
    return st->engine == FDT_ENGINE_PARTS || st->engine == FDT_ENGINE_PARTS_MESH ||
           st->engine == FDT_ENGINE_WALLS;
}

/* Per-thread and per-kind figures of a parallel run (§4-§5): what the
 * bench harness and the issue notes report. */
static void print_parallel_stats(const fdt_result *res, const fdt_stats *st)
{
    fprintf(stderr, "  messages          sent / received\n");
    for (int k = 1; k < FDT_MSG_KIND_END; k++)
        fprintf(stderr, "    %-15s %zu / %zu\n", fdt_msg_kind_name(k), st->sent[k],
                st->received[k]);
    fprintf(stderr,
        "  remote queries    %zu made, %zu answered, %zu improved the apex\n"
        "  tet requests      %zu (%zu for tets already built)\n"
        "  idle time         %.3f s (sum over threads), query wait %.3f s\n"
        "  load imbalance    %.3f (max / mean tets per thread)\n"
        "  pinned            %s\n",
        st->remote_queries, st->remote_answered, st->remote_improved,
        st->tet_requests, st->duplicate_requests, st->t_idle, st->t_query_wait,
        st->load_imbalance,
        st->pinned > 0 ? "yes" : st->pinned < 0 ? "refused (ran unpinned)" : "no");
    fprintf(stderr, "  thread  points      tets     final  walls  faces adv  rem.q made/ans"
                    "  FACESEND s/r  idle s  core\n");
    for (int i = 0; i < st->threads; i++) {
        fdt_thread_stats ts;
        if (fdt_result_thread_stats(res, i, &ts) != FDT_OK)
            break;
        fprintf(stderr, "  %6d %7zu %9zu %9zu %6zu %10zu %8zu/%-6zu %7zu/%-6zu %7.3f %5d\n", i,
                ts.points, ts.tets, ts.final_tets, ts.wall_faces, ts.faces_advanced,
                ts.remote_queries, ts.remote_answered, ts.sent[FDT_MSG_FACESEND],
                ts.received[FDT_MSG_FACESEND], ts.t_idle, ts.core);
    }
}

static void print_stats(const fdt_result *res, const fdt_stats *st, size_t dups,
                        const timings *tm)
{
    fprintf(stderr,
        "frontdt: statistics\n"
        "  points            %zu\n"
        "  vertices          %zu (%zu duplicates merged)\n"
        "  tets              %zu\n"
        "  hull faces        %zu\n"
        "  faces advanced    %zu\n"
        "  kd nodes visited  %zu\n"
        "  points tested     %zu\n"
        "  exact orient3d    %zu\n"
        "  exact insphere    %zu\n"
        "  adaptive orient3d %zu\n"
        "  adaptive insphere %zu\n"
        "  largest front     %zu\n"
        "  mesh faces        %zu (%zu parts read a mesh; %.3f s building meshes)\n"
        "  final from mesh   %zu tets (certified %zu in %.3f s)\n"
        "  insertion         %zu conflict tests, %zu deferred, %zu by the serial finish\n"
        "  threads           %d\n"
        "  mode              %s\n"
        "  engine            %s (%s)\n"
        "  time prepare      %.3f s\n"
        "  time front        %.3f s\n"
        "  time finish       %.3f s\n"
        "  time read         %.3f s\n"
        "  time triangulate  %.3f s\n"
        "  time check        %.3f s\n"
        "  time canon+hash   %.3f s\n"
        "  time write        %.3f s\n"
        "  time voronoi      %.3f s\n"
        "  time interpolate  %.3f s\n",
        st->points, st->vertices, dups, st->tets, st->hull_faces,
        st->faces_advanced, st->kd_nodes_visited, st->points_tested,
        st->exact_orient, st->exact_insphere, st->adapt_orient, st->adapt_insphere,
        st->max_front, st->mesh_faces, st->mesh_parts, st->t_mesh, st->final_tets,
        st->certified_tets, st->t_certify, st->ins_conflict_tests, st->ins_deferred,
        st->ins_serial, st->threads, mode_name(st->mode), engine_word(st, 0),
        engine_word(st, 1), st->t_prepare, st->t_front, st->t_finish,
        tm->read, tm->triangulate, tm->check, tm->canon, tm->write, tm->voronoi,
        tm->interpolate);
    /* what only some engines have */
    if (st->engine == FDT_ENGINE_SWEEP)
        fprintf(stderr, "  sweep             %zu parts, %zu points inserted again, at most %zu in "
                        "a part\n",
                st->sweep_parts, st->sweep_reinserted, st->sweep_max_part);
    if (st->engine == FDT_ENGINE_PERIODIC && st->sweep_parts)
        fprintf(stderr, "  periodic          %zu slabs streamed, %zu images with the points, "
                        "at most %zu margin(s) tried in a slab\n",
                st->sweep_parts, st->periodic_images, st->periodic_rounds);
    else if (st->engine == FDT_ENGINE_PERIODIC)
        fprintf(stderr, "  periodic          %zu images with the points, %zu margin(s) tried\n",
                st->periodic_images, st->periodic_rounds);
    if (st->cell_batches)
        fprintf(stderr, "  streamed cells    %zu batches, at most %zu tets held, %.3f s of the "
                        "triangulation\n",
                st->cell_batches, st->cell_held_max, st->t_cells);
    if (ran_parts(st))
        print_parallel_stats(res, st);
}

/* --stats, memory: each structure's bytes, a point and in all, the
 * estimate (--memory-limit's) and the measured peak. */
static void print_memory(const fdt_stats *st, size_t n, unsigned long long estimate,
                         unsigned long long peak)
{
    double pn = n ? (double)n : 1.0;
    const struct {
        const char *name;
        size_t bytes;
    } m[] = {{"points", st->mem_points}, {"merge table", st->mem_merge},
             {"kd-trees", st->mem_tree},  {"front", st->mem_front},
             {"mesh", st->mem_mesh},      {"sink buffers", st->mem_sink}};
    for (size_t i = 0; i < sizeof m / sizeof *m; i++)
        fprintf(stderr, "  memory %-12s %8.1f MiB %6.1f B/point\n", m[i].name,
                (double)m[i].bytes / 1048576.0, (double)m[i].bytes / pn);
    if (st->max_front)
        fprintf(stderr, "  memory a front face %.1f B (largest front %zu faces)\n",
                (double)st->mem_front / (double)st->max_front, st->max_front);
    fprintf(stderr, "  memory estimate     %8.1f MiB %6.1f B/point\n",
            (double)estimate / 1048576.0, (double)estimate / pn);
    if (peak)
        fprintf(stderr, "  memory peak RSS     %8.1f MiB %6.1f B/point (%+.0f%% of the estimate)\n",
                (double)peak / 1048576.0, (double)peak / pn,
                100.0 * ((double)peak - (double)estimate) / (double)estimate);
}

static void json_string(FILE *f, const char *s)
{
    fputc('"', f);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '"' || *p == '\\')
            fprintf(f, "\\%c", *p);
        else if (*p < 0x20)
            fprintf(f, "\\u%04x", *p);
        else
            fputc(*p, f);
    }
    fputc('"', f);
}

/* JSON numbers cannot be NaN or infinite; times never are, but be safe. */
static double finite_or_zero(double x)
{
    return (x == x && x - x == 0) ? x : 0;
}

/* The counts by kind as {"iamdone": n, ...}: each kind's name in lower
 * case. */
static void json_msgs(FILE *f, const char *key, const size_t *m)
{
    fprintf(f, ", \"%s\": {", key);
    for (int k = 1; k < FDT_MSG_KIND_END; k++) {
        fprintf(f, "%s\"", k > 1 ? ", " : "");
        for (const char *c = fdt_msg_kind_name(k); *c; c++)
            fputc(*c >= 'A' && *c <= 'Z' ? *c - 'A' + 'a' : *c, f);
        fprintf(f, "\": %zu", m[k]);
    }
    fputc('}', f);
}

static void write_stats_json(FILE *f, const cli *c, const fdt_result *res,
                             const fdt_stats *st, size_t dups, const timings *tm,
                             int have_hash, uint64_t hash)
{
    fputs("{\"input\": ", f);
    if (c->input)
        json_string(f, c->input);
    else
        fputs("null", f);
    if (c->demo)
        fprintf(f, ", \"demo\": %zu", c->demo_n);
    fprintf(f,
        ", \"points\": %zu, \"vertices\": %zu, \"duplicates\": %zu"
        ", \"tets\": %zu, \"hull_faces\": %zu, \"faces_advanced\": %zu"
        ", \"kd_nodes_visited\": %zu, \"points_tested\": %zu"
        ", \"exact_orient\": %zu, \"exact_insphere\": %zu"
        ", \"adapt_orient\": %zu, \"adapt_insphere\": %zu"
        ", \"max_front\": %zu, \"mesh_faces\": %zu, \"mesh_parts\": %zu"
        ", \"t_mesh\": %.9g, \"final_tets\": %zu, \"certified_tets\": %zu"
        ", \"t_certify\": %.9g, \"ins_conflict_tests\": %zu, \"ins_deferred\": %zu"
        ", \"ins_serial\": %zu, \"sweep_parts\": %zu, \"sweep_reinserted\": %zu"
        ", \"sweep_max_part\": %zu, \"cell_batches\": %zu, \"cell_held_max\": %zu"
        ", \"t_cells\": %.9g, \"threads\": %d, \"mode\": \"%s\", \"engine\": \"%s\""
        ", \"t_prepare\": %.9g, \"t_front\": %.9g, \"t_finish\": %.9g"
        ", \"t_read\": %.9g, \"t_triangulate\": %.9g, \"t_check\": %.9g"
        ", \"t_canon\": %.9g, \"t_write\": %.9g, \"t_voronoi\": %.9g"
        ", \"t_interpolate\": %.9g, \"periodic_images\": %zu, \"periodic_rounds\": %zu",
        st->points, st->vertices, dups, st->tets, st->hull_faces,
        st->faces_advanced, st->kd_nodes_visited, st->points_tested,
        st->exact_orient, st->exact_insphere, st->adapt_orient, st->adapt_insphere,
        st->max_front, st->mesh_faces, st->mesh_parts, finite_or_zero(st->t_mesh),
        st->final_tets, st->certified_tets, finite_or_zero(st->t_certify),
        st->ins_conflict_tests, st->ins_deferred, st->ins_serial, st->sweep_parts,
        st->sweep_reinserted, st->sweep_max_part, st->cell_batches, st->cell_held_max,
        finite_or_zero(st->t_cells), st->threads, mode_name(st->mode),
        engine_word(st, 0), finite_or_zero(st->t_prepare),
        finite_or_zero(st->t_front), finite_or_zero(st->t_finish),
        finite_or_zero(tm->read), finite_or_zero(tm->triangulate),
        finite_or_zero(tm->check), finite_or_zero(tm->canon), finite_or_zero(tm->write),
        finite_or_zero(tm->voronoi), finite_or_zero(tm->interpolate), st->periodic_images,
        st->periodic_rounds);
    json_msgs(f, "sent", st->sent);
    json_msgs(f, "received", st->received);
    fprintf(f,
        ", \"remote_queries\": %zu, \"remote_answered\": %zu, \"remote_improved\": %zu"
        ", \"tet_requests\": %zu, \"duplicate_requests\": %zu, \"t_idle\": %.9g"
        ", \"t_query_wait\": %.9g, \"load_imbalance\": %.9g, \"pinned\": %d",
        st->remote_queries, st->remote_answered, st->remote_improved, st->tet_requests,
        st->duplicate_requests, finite_or_zero(st->t_idle), finite_or_zero(st->t_query_wait),
        finite_or_zero(st->load_imbalance), st->pinned);
    fputs(", \"per_thread\": [", f);
    for (int i = 0; i < st->threads; i++) {
        fdt_thread_stats ts;
        if (fdt_result_thread_stats(res, i, &ts) != FDT_OK)
            break;
        fprintf(f, "%s{\"points\": %zu, \"tets\": %zu, \"final_tets\": %zu"
                   ", \"wall_faces\": %zu, \"faces_advanced\": %zu"
                   ", \"remote_queries\": %zu, \"remote_answered\": %zu"
                   ", \"t_idle\": %.9g, \"t_cpu\": %.9g, \"core\": %d",
                i ? ", " : "", ts.points, ts.tets, ts.final_tets, ts.wall_faces,
                ts.faces_advanced, ts.remote_queries, ts.remote_answered,
                finite_or_zero(ts.t_idle), finite_or_zero(ts.t_cpu), ts.core);
        json_msgs(f, "sent", ts.sent);
        json_msgs(f, "received", ts.received);
        fputc('}', f);
    }
    fputc(']', f);
    if (c->check)
        fputs(", \"check\": \"passed\"", f);
    if (have_hash)
        fprintf(f, ", \"hash\": \"%016" PRIx64 "\"", hash);
    fputs("}\n", f);
}

/* ------------------------------------------------------------------------ */
/* The run                                                                   */
/* ------------------------------------------------------------------------ */

/* ------------------------------------------------------------------------ */
/* Streaming (issue 18)                                                      */
/* ------------------------------------------------------------------------ */

/* Why this command cannot stream, or NULL: every -o a file in a format
 * with a streaming writer, and nothing that needs the whole mesh. In the
 * default mode a TetGen output is not streamed either: its .neigh needs
 * the neighbours, so only --stream (which drops .neigh) streams it. */
static const char *stream_refusal(const cli *c, const fdt_format *const *fmts, int forced,
                                  char *why, size_t len)
{
    if (c->check)
        return "--check needs the whole mesh";
    if (c->hash)
        return "--hash sorts the whole mesh (--set-hash needs no sort)";
    if (c->all_faces)
        return "--all-faces needs the face list of the whole mesh";
    const char *dual = fdt_cli_dual_stream_refusal(&c->dual);
    if (dual)
        return dual;
    /* the cells stream where asked to; else they take the whole mesh */
    if (fdt_cli_dual_wanted(&c->dual) && !forced)
        return "--voronoi and --density stream with --stream only";
    if (c->dual.dual)
        return "--dual needs the whole mesh";
    for (int o = 0; o < c->n_outputs; o++) {
        if (!strcmp(c->outputs[o], "-"))
            return "-o - (standard output) cannot stream";
        const char *name = fdt_format_name(fmts[o]);
        if (c->periodic && !fdt_format_periodic_stream(fmts[o])) {
            snprintf(why, len, "-o %s: a periodic run streams its rows to .tets only (format "
                     "%s needs the whole mesh)", c->outputs[o], name);
            return why;
        }
        if (c->periodic)
            continue;
        if (fdt_stream_format_ok(c->outputs[o], name) != 1 ||
            (!forced && !strcmp(name, "tetgen"))) {
            snprintf(why, len, "-o %s: format %s needs the whole mesh (tetgen, vtu and bin "
                     "stream)", c->outputs[o], name);
            return why;
        }
    }
    return NULL;
}

/* The sink of a streamed run: each batch to every -o's writer in turn;
 * counts what went by (the summary's tets and hull faces). */
typedef struct fanout {
    fdt_stream_writer *w[FDT_CLI_MAX_OUTPUTS];
    fdt_sink sink[FDT_CLI_MAX_OUTPUTS];
    int n;
    int failed;      /* the writer that refused a batch, -1: none */
    uint64_t tets, hull;
} fanout;

static int fanout_tets(void *user, const fdt_vid *t, size_t count)
{
    fanout *fo = user;
    for (int i = 0; i < fo->n; i++) {
        int r = fo->sink[i].tets(fo->sink[i].user, t, count);
        if (r) {
            fo->failed = i;
            return r;
        }
    }
    fo->tets += count;
    return 0;
}

static int fanout_hull(void *user, const fdt_vid *f, size_t count)
{
    fanout *fo = user;
    for (int i = 0; i < fo->n; i++) {
        int r = fo->sink[i].hull(fo->sink[i].user, f, count);
        if (r) {
            fo->failed = i;
            return r;
        }
    }
    fo->hull += count;
    return 0;
}

/* A periodic run's rows, as fanout_tets and fanout_hull. */
static int fanout_periodic_tets(void *user, const fdt_vid *t, const int8_t *off, size_t count)
{
    fanout *fo = user;
    for (int i = 0; i < fo->n; i++) {
        int r = fo->sink[i].periodic_tets(fo->sink[i].user, t, off, count);
        if (r) {
            fo->failed = i;
            return r;
        }
    }
    fo->tets += count;
    return 0;
}

static int fanout_periodic_hull(void *user, const fdt_vid *f, const int8_t *off, size_t count)
{
    fanout *fo = user;
    for (int i = 0; i < fo->n; i++) {
        int r = fo->sink[i].periodic_hull(fo->sink[i].user, f, off, count);
        if (r) {
            fo->failed = i;
            return r;
        }
    }
    fo->hull += count;
    return 0;
}

/* Closes every writer: commits them all when commit is set and each
 * commit succeeds, else removes what is left. Returns the exit code. */
static int fanout_close(fanout *fo, int commit)
{
    int code = CLI_OK;
    for (int i = 0; i < fo->n; i++) {
        char err[1024];
        int r = fdt_stream_writer_close(&fo->w[i], commit && code == CLI_OK, err, sizeof err);
        if (r != FDT_OK && code == CLI_OK && (commit || i == fo->failed)) {
            say("%s", err);
            code = exit_for_writer(r);
        }
    }
    return code;
}

/*
 * The bytes a run on n points is expected to need at its peak (for
 * --memory-limit, and printed by --stats beside the measured peak): the
 * points as read (24 a point, the CLI's array; a streamed run prepares
 * them in it, fdt_settings.permute_input), the library's own copy (24
 * otherwise), input indices and duplicate map (8), the merge's table
 * (4 bytes a slot, src/geom/prepare.h's fdt_prepare_merge_slots, freed
 * before the trees), the kd-trees (about 26 a point with leaves of 30: 24.5
 * measured on 1M uniform points), the front (the queue's buckets, 1 a
 * point, and 110 bytes a front face, for 8 n^(2/3) faces: a front is a
 * surface; 1M uniform points measured 34k faces serial, 50k on two
 * threads, 3.6 bytes a point in all) and, in memory, the tets: 6.5 a
 * point, 16 bytes each and 32 more with neighbours, twice over in the
 * parallel gather's worst case (thread 0's buffer grown to the whole mesh
 * while the others still hold theirs), plus the writers' and the face
 * list's needs, which this does not count. Streamed: a 1 MiB batch a
 * thread. Plus 16 MiB for the program, its libraries and stacks.
 */
static unsigned long long memory_estimate(size_t n, int stream, int threads, int nbrs,
                                          int one_part)
{
    double pts = 24.0 * (double)n;
    double own = stream ? 0.0 : 24.0 * (double)n;
    double idx = 8.0 * (double)n;
    double merge = 4.0 * (double)fdt_prepare_merge_slots(n);
    double tree = 26.0 * (double)n;
    double front = 1.0 * (double)n + 110.0 * 8.0 * cbrt((double)n) * cbrt((double)n);
    double mesh = 0.0;
    if (!stream) {
        mesh = 6.5 * (double)n * (16.0 + (nbrs ? 32.0 : 0.0));
        if (threads > 1)
            mesh *= 2.0;
    }
    double sinks = stream ? (double)(threads > 1 ? threads : 1) * 1.2 * 1048576.0 : 0.0;
    double during_merge = pts + own + idx + merge;
    double during_front = pts + own + idx + tree + front + mesh + sinks;
    if (one_part && stream) {
        /* Parts in sweep order (src/front/sweep.h): the points and a
         * part's copy of its points and mesh, a part about a slab and a
         * half (what a part carries in) and, with threads, one a half of
         * the sweep at once. Where nothing closes (surfaces) parts grow
         * up to every point: the estimate is the usual case's. */
        double part = 1.5 * (double)fdt_sweep_slab(n) * (threads > 1 ? 2.0 : 1.0);
        if (part > (double)n)
            part = (double)n;
        during_front = pts + idx + FDT_SWEEP_PART_BYTES * part + sinks;
    } else if (one_part) {
        /* The one-part engine (src/api/api.c's pick_engine):
         * the insertion mesh instead of the tree and the front, whose tet
         * array becomes the output's (src/front/partmesh.h); neighbours
         * are written beside it. 1M uniform points: 289 bytes a point
         * measured at the peak. */
        during_front = pts + own + idx +
                       FDT_PARTMESH_BYTES * (threads > 1 ? FDT_PARTMESH_PAR : 1.0) * (double)n +
                       (nbrs ? 6.5 * 32.0 * (double)n : 0.0);
    }
    double peak = during_merge > during_front ? during_merge : during_front;
    return (unsigned long long)(peak + 16.0 * 1048576.0);
}

/* The process's peak resident set in bytes (0 if unknown). */
static unsigned long long peak_rss_bytes(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0)
        return 0;
    return (unsigned long long)ru.ru_maxrss * 1024ull; /* Linux: KiB */
}

/* What the run's steps hand on to each other. */
typedef struct run_state {
    const char *name;     /* the input in messages: its path, "stdin" or "demo" */
    progress prog;        /* the progress line (src/cli/progress.h) */
    int json_stdout;      /* "--stats-json -" */
    FILE *info;           /* the summary and the hashes: stdout, unless the
                             JSON object or the mesh claims it */
    const fdt_format *fmts[FDT_CLI_MAX_OUTPUTS]; /* each -o's format */
    int need;             /* FDT_NEED_* of all the outputs */
    int to_stdout;        /* an -o - */
    int streaming;        /* the tets go to the outputs as they are built */
    double *xyz;          /* the points (owned), n of them */
    size_t n;
    fdt_context *ctx;
    fdt_result *res;
    fanout fo;            /* a streamed run's writers */
    fdt_cli_cells *cells; /* a streamed run's cells, spooled (src/cli/dual.h) */
    unsigned long long estimate; /* memory_estimate's bytes */
    size_t nt;            /* tets made */
    size_t dups;          /* duplicate points merged */
    uint64_t hash, set_hash;
    timings tm;
} run_state;

/* Refuses one -o's doomed or destructive output before anything is read:
 * its format, its files against the input, the --stats-json file and the
 * earlier -o's files. CLI_OK, or the exit code. */
static int plan_output(const cli *c, run_state *rs, int o)
{
    const fdt_format **fmts = rs->fmts;
    const char *out = c->outputs[o];
    if (!strcmp(out, "-")) {
        /* standard output: text only, the canonical .tets by default */
        fmts[o] = fdt_format_by_name(c->out_format[o] ? c->out_format[o] : "tets");
        if (!fdt_format_is_text(fmts[o]) || !strcmp(fdt_format_name(fmts[o]), "tetgen") ||
            !strcmp(fdt_format_name(fmts[o]), "openfoam"))
            return usage_error("-o -: format %s cannot go to standard output "
                               "(one text file only: tets, vtk, msh, msh2, medit)",
                               fdt_format_name(fmts[o]));
        if (rs->json_stdout)
            return usage_error("-o - and --stats-json - both want standard output");
        rs->to_stdout = 1;
        rs->need |= fdt_format_needs(fmts[o], c->all_faces);
        return CLI_OK;
    }
    fmts[o] = c->out_format[o] ? fdt_format_by_name(c->out_format[o]) : fdt_format_by_path(out);
    if (!fmts[o])
        return usage_error("%s: unknown output format (use %s, or --format)", out,
                           fdt_format_list());
    /* "-o m.vtu --format msh2" would write gmsh into m.vtu */
    const fdt_format *by_ext = fdt_format_contradicted(out, fmts[o]);
    if (by_ext)
        return usage_error("--format %s contradicts the extension of %s (%s)",
                           fdt_format_name(fmts[o]), out, fdt_format_name(by_ext));
    rs->need |= fdt_format_needs(fmts[o], c->all_faces);
    char names[FDT_IO_MAX_FILES][FDT_IO_PATH];
    int n_names = fdt_output_files_as(out, fmts[o], names);
    if (n_names <= 0) {
        say("%s: %s", out, strerror(ENAMETOOLONG));
        return CLI_WRITE;
    }
    int code = refuse_overwrites(c, out, names, n_names);
    if (code >= 0)
        return code;
    code = refuse_clobber(c, out, names, n_names);
    if (code >= 0)
        return code;
    for (int p = 0; p < o; p++) {
        if (!strcmp(c->outputs[p], "-"))
            continue;
        char other[FDT_IO_MAX_FILES][FDT_IO_PATH];
        int k = fdt_output_files_as(c->outputs[p], fmts[p], other);
        for (int i = 0; i < n_names; i++)
            for (int j = 0; j < k; j++)
                if (fdt_same_file(names[i], other[j])) {
                    say("output %s (-o %s) is also written by -o %s", names[i], out,
                        c->outputs[p]);
                    return CLI_USAGE;
                }
    }
    /* a directory format's path may be an existing directory: then its
     * files are what must be creatable */
    struct stat dst;
    const char *probe = fmts[o] == fdt_format_by_name("openfoam") && stat(out, &dst) == 0 &&
                                S_ISDIR(dst.st_mode)
                            ? names[0]
                            : out;
    if (!output_dir_ok("output", probe))
        return CLI_WRITE;
    return CLI_OK;
}

/* Refuses doomed or destructive outputs before reading or computing
 * anything (each -o, the --stats-json file) and settles where things go:
 * streamed or not, the summary on stdout or stderr. CLI_OK, or the exit
 * code. */
static int plan_outputs(const cli *c, run_state *rs)
{
    for (int o = 0; o < c->n_outputs; o++) {
        int code = plan_output(c, rs, o);
        if (code != CLI_OK)
            return code;
    }
    int foam = 0;
    for (int o = 0; o < c->n_outputs; o++)
        foam |= rs->fmts[o] == fdt_format_by_name("openfoam");
    if (c->dual.dual && !foam)
        return usage_error("--dual writes the Voronoi cells as an OpenFOAM polyMesh: it needs "
                           "an -o CASE/constant/polyMesh");
    /* the dual numbers its vertices and faces in the tets' order: the
     * canonical one makes them the same for every mode and thread count */
    if (c->dual.dual)
        rs->need |= FDT_NEED_SORTED;
    char none[1][FDT_IO_PATH];
    int code = refuse_overwrites(c, "", none, 0); /* --stats-json vs the input */
    if (code >= 0)
        return code;
    /* Stream (the tets go to the files as they are built) when asked, or
     * when every output can and nothing needs the mesh. */
    char why[FDT_IO_PATH + 200];
    const char *refusal = stream_refusal(c, rs->fmts, c->stream > 0, why, sizeof why);
    if (c->stream > 0 && refusal)
        return usage_error("--stream: %s", refusal);
    rs->streaming = c->stream > 0 || (c->stream == 0 && !refusal && c->n_outputs > 0);
    if (c->stats_json && !rs->json_stdout &&
        !output_dir_ok("--stats-json file", c->stats_json))
        return CLI_WRITE;
    /* a device or a pipe is written in place, not replaced (write_stats) */
    struct stat jst0;
    if (c->no_clobber && c->stats_json && !rs->json_stdout && lstat(c->stats_json, &jst0) == 0 &&
        (stat(c->stats_json, &jst0) != 0 || S_ISREG(jst0.st_mode))) {
        say("--stats-json file %s exists; --no-clobber keeps it", c->stats_json);
        return CLI_WRITE;
    }
    /* the summary goes to stderr when the mesh goes to stdout */
    if (rs->to_stdout)
        rs->info = stderr;
    return CLI_OK;
}

/* The points: --demo's, or the input file's. */
static int read_points(const cli *c, run_state *rs)
{
    double t0 = fdt_now_s();
    if (c->demo) {
        rs->n = c->demo_n;
        rs->xyz = demo_points(rs->n);
        if (!rs->xyz) {
            say("demo: no memory for %zu points", rs->n);
            return CLI_RESOURCES;
        }
    } else {
        char err[1024];
        fdt_read_options ro;
        fdt_default_read_options(&ro);
        ro.format = c->input_format_name;
        memcpy(ro.columns, c->columns, sizeof ro.columns);
        ro.delimiter = c->delimiter;
        ro.decimal_comma = c->decimal_comma;
        ro.n_threads = reader_threads(c);
        if (rs->prog.enabled) {
            ro.progress = progress_io;
            ro.progress_user = &rs->prog;
        }
        progress_phase(&rs->prog, "read");
        int r = fdt_read_points_opts(c->input, &ro, &rs->xyz, &rs->n, err, sizeof err);
        progress_clear(&rs->prog);
        if (r != FDT_OK) {
            say("%s", err);
            return exit_for_reader(r);
        }
    }
    rs->tm.read = fdt_now_s() - t0;
    return CLI_OK;
}

/* The library's settings for this run, and its memory estimate against
 * --memory-limit; then the context. */
static int open_engine(const cli *c, run_state *rs)
{
    fdt_settings s;
    fdt_default_settings(&s);
    s.mode = c->mode;
    s.search = c->search;
    s.leaf_size = c->leaf;
    if (c->threads >= 0)
        s.n_threads = c->threads;
    s.pin = c->pin;
    s.periodic = c->periodic;
    memcpy(s.periodic_box, c->dual.box, sizeof s.periodic_box);
    s.neighbors = !c->periodic && !rs->streaming && (c->check || (rs->need & FDT_NEED_NBRS) || fdt_cli_interp_wanted(&c->dual));
    if (rs->prog.enabled) {
        s.progress = progress_engine;
        s.progress_user = &rs->prog;
    }
    /* A streamed run prepares the points in the array we read them into
     * (the writers took what they need of it when they were opened,
     * before the run): the points are stored once. */
    s.permute_input = rs->streaming;
    int run_threads = c->mode == FDT_MODE_SERIAL ? 1
                      : c->threads > 0           ? c->threads
                                                 : (int)sysconf(_SC_NPROCESSORS_ONLN);
    rs->estimate = memory_estimate(rs->n, rs->streaming, run_threads, s.neighbors,
                                   fdt_engine_one_part(&s, rs->streaming));
    /* --dual's polyhedral mesh, built after the tets beside them: 1,425
     * bytes a point at the peak for 1M uniform points (bench/NOTES.md
     * entry 97); a periodic one's from the points and their images beside
     * the periodic mesh, 1,743 (entry 124) */
    unsigned long long dual =
        c->dual.dual ? (c->periodic ? 1800ull : 1500ull) * rs->n + (16ull << 20) : 0;
    if (dual > rs->estimate)
        rs->estimate = dual;
    /* a periodic run: the mesh of the points and their images, then the
     * kept tets' keys and their sort, 605-622 MiB at the peak for 1M
     * uniform points (bench/NOTES.md entry 108); --check's faces after it,
     * 790 MiB (entry 109); streamed, the points and one slab's build
     * (222 MiB for 1M in slabs of 320k, entry 110). With the cells: 1,239
     * MiB in memory, and streamed the spool's index and a slab's stars and
     * cells besides, 701 MiB on two threads, 395 on one (entry 112) */
    int pcells = fdt_cli_dual_wanted(&c->dual);
    unsigned long long slab = rs->n < fdt_sweep_slab(rs->n) ? rs->n : fdt_sweep_slab(rs->n);
    unsigned long long periodic =
        !c->periodic    ? 0
        : rs->streaming ? (pcells ? 72ull : 64ull) * rs->n +
                              (pcells ? (run_threads > 1 ? 2200ull : 1100ull) : 900ull) * slab +
                              (16ull << 20)
                        : (pcells ? 1300ull : c->check ? 850ull : 700ull) * rs->n +
                              (16ull << 20);
    if (periodic > rs->estimate)
        rs->estimate = periodic;
    if (c->memory_limit && rs->estimate > c->memory_limit) {
        say("%s: %zu points need about %llu MiB (%s%s%s%s), more than --memory-limit %llu MiB",
            rs->name, rs->n, rs->estimate >> 20, rs->streaming ? "streamed" : "in memory",
            s.neighbors ? ", with neighbours" : "", c->dual.dual ? ", --dual" : "",
            c->periodic ? ", periodic" : "",
            c->memory_limit >> 20);
        return CLI_RESOURCES;
    }
    int r = fdt_open(&rs->ctx, &s);
    if (r != FDT_OK) {
        say("cannot use these settings: %s", fdt_strerror(r));
        return fdt_cli_engine_exit(r);
    }
    return CLI_OK;
}

/* A streamed run's writers, one an -o, opened before the run. */
static int open_stream_writers(const cli *c, run_state *rs)
{
    fanout *fo = &rs->fo;
    for (int o = 0; o < c->n_outputs; o++) {
        char err[1024];
        int r = fdt_stream_writer_open(&fo->w[o], c->outputs[o], fdt_format_name(rs->fmts[o]),
                                       rs->xyz, rs->n, c->periodic ? FDT_STREAM_PERIODIC : 0,
                                       err, sizeof err);
        if (r != FDT_OK) {
            say("%s", err);
            (void)fanout_close(fo, 0);
            return exit_for_writer(r);
        }
        fo->n = o + 1;
        (void)fdt_stream_writer_sink(fo->w[o], &fo->sink[o]);
    }
    return CLI_OK;
}

/* The library's run: the mesh in memory, or streamed to the writers. */
static int triangulate(const cli *c, run_state *rs)
{
    int code = open_engine(c, rs);
    if (code != CLI_OK)
        return code;
    rs->fo.failed = -1;
    if (rs->streaming && (code = open_stream_writers(c, rs)) != CLI_OK)
        return code;
    double t0 = fdt_now_s();
    progress_phase(&rs->prog, "merge"); /* "triangulate" at the library's first report */
    int r;
    char derr[FDT_IO_PATH + 600];
    fdt_sink sink = {sizeof sink, fanout_tets, fanout_hull, &rs->fo, fanout_periodic_tets,
                     fanout_periodic_hull};
    if (rs->streaming && fdt_cli_dual_wanted(&c->dual)) {
        /* the cells as their points' last tets leave, spooled */
        fdt_voronoi_options o;
        fdt_cell_sink cells;
        if ((r = fdt_cli_cells_open(&c->dual, rs->n, &rs->cells, &o, &cells, derr,
                                    sizeof derr)) != FDT_OK) {
            say("%s", derr);
            (void)fanout_close(&rs->fo, 0);
            return fdt_cli_dual_exit(r);
        }
        r = fdt_voronoi_stream(rs->ctx, rs->xyz, rs->n, &o, &sink, &cells, &rs->res);
    } else if (rs->streaming) {
        r = fdt_triangulate_stream(rs->ctx, rs->xyz, rs->n, &sink, &rs->res);
    } else {
        r = fdt_triangulate(rs->ctx, rs->xyz, rs->n, &rs->res);
    }
    rs->tm.triangulate = fdt_now_s() - t0;
    progress_clear(&rs->prog);
    if (rs->streaming) {
        /* the writers end with the run: committed (counts patched, all
         * renamed) after a whole run, removed after a failed one */
        t0 = fdt_now_s();
        int wcode = fanout_close(&rs->fo, r == FDT_OK);
        rs->tm.write = fdt_now_s() - t0;
        if (rs->fo.failed >= 0)
            return wcode; /* the run stopped for the writer's error */
        if (r == FDT_OK && wcode != CLI_OK)
            return wcode;
    }
    if (r != FDT_OK && rs->cells && fdt_cli_cells_failed(rs->cells, derr, sizeof derr)) {
        say("%s: %s", rs->name, derr);
        return CLI_WRITE;
    }
    if (r != FDT_OK) {
        const char *diag = fdt_context_diagnostic(rs->ctx);
        say("%s: %s", rs->name, diag && *diag ? diag : fdt_strerror(r));
        return fdt_cli_engine_exit(r);
    }
    /* No engine threads may outlive this point: the signal handler then
     * runs on the thread that is writing, never beside it. */
    fdt_close(&rs->ctx);

    rs->dups = fdt_result_num_duplicates(rs->res);
    if (rs->dups > 0 && !c->quiet)
        say("%s: merged %zu duplicate points", rs->name, rs->dups);
    /* --pin where the system refuses a binding (or hwloc is missing): the
     * run went on unpinned, which the user who asked should hear once. */
    fdt_stats pst;
    if (c->pin && !c->quiet && fdt_result_stats(rs->res, &pst) == FDT_OK && pst.pinned < 0)
        say("--pin: a thread could not be bound to its core; ran unpinned");
    rs->nt = rs->streaming ? (size_t)rs->fo.tets : fdt_result_num_tets(rs->res);
    return CLI_OK;
}

/* --check: the mesh against the definition, exactly. */
static int check_mesh(const cli *c, run_state *rs)
{
    if (!c->check)
        return CLI_OK;
    char msg[1024];
    double t0 = fdt_now_s();
    progress_phase(&rs->prog, "check");
    double box[6];
    unsigned axes = fdt_result_periodic(rs->res, box);
    int r = axes ? fdt_check_periodic(rs->xyz, rs->n, fdt_result_tets(rs->res),
                                      fdt_result_tet_offsets(rs->res), rs->nt,
                                      fdt_result_hull_faces(rs->res),
                                      fdt_result_hull_offsets(rs->res),
                                      fdt_result_num_hull_faces(rs->res), axes, box, msg,
                                      sizeof msg)
                 : fdt_check(rs->xyz, rs->n, fdt_result_tets(rs->res), rs->nt,
                             fdt_result_neighbors(rs->res), msg, sizeof msg);
    progress_clear(&rs->prog);
    rs->tm.check = fdt_now_s() - t0;
    if (r != FDT_OK) {
        if (r == FDT_ECHECK)
            say("%s: check failed: %s", rs->name, msg);
        else
            say("%s: check could not run: %s", rs->name, fdt_strerror(r));
        return fdt_cli_engine_exit(r);
    }
    return CLI_OK;
}

/* The hashes, and the canonical order: it makes .tets and the hash
 * independent of thread count and mode; the other formats do not need
 * it. */
static int canonical_order(const cli *c, run_state *rs)
{
    double t0 = fdt_now_s();
    if (c->set_hash)
        (void)fdt_result_set_hash(rs->res, &rs->set_hash); /* res is not NULL: cannot fail */
    if (c->hash || (rs->need & FDT_NEED_SORTED))
        progress_phase(&rs->prog, "sort");
    if (c->hash) {
        /* sorts too, hashing each part of the sort while it is in cache */
        int r = fdt_result_hash(rs->res, &rs->hash);
        progress_clear(&rs->prog);
        if (r != FDT_OK) {
            say("%s: sorting and hashing the tets failed: %s", rs->name, fdt_strerror(r));
            return fdt_cli_engine_exit(r);
        }
    } else if (rs->need & FDT_NEED_SORTED) {
        int r = fdt_result_sort(rs->res);
        progress_clear(&rs->prog);
        if (r != FDT_OK) {
            say("%s: sorting the tets failed: %s", rs->name, fdt_strerror(r));
            return fdt_cli_engine_exit(r);
        }
    }
    progress_clear(&rs->prog);
    rs->tm.canon = fdt_now_s() - t0;
    return CLI_OK;
}

/* Every -o of a run in memory (a streamed run wrote them as it went). */
static int write_meshes(const cli *c, run_state *rs)
{
    if (c->n_outputs == 0 || rs->streaming)
        return CLI_OK;
    double t0 = fdt_now_s();
    char err[1024];
    /* The public writer computes the face list where a format needs it
     * (after the sort above: it names tets by their numbers) and reports
     * its bytes (progress_io: the write phase moves). */
    fdt_write_options wo;
    fdt_default_write_options(&wo);
    wo.all_faces = c->all_faces;
    if (rs->prog.enabled) {
        wo.progress = progress_io;
        wo.progress_user = &rs->prog;
    }
    progress_phase(&rs->prog, "write");
    int code = CLI_OK;
    for (int o = 0; o < c->n_outputs && code == CLI_OK; o++) {
        wo.format = fdt_format_name(rs->fmts[o]);
        if (c->dual.dual && rs->fmts[o] == fdt_format_by_name("openfoam")) {
            int r = fdt_cli_dual_mesh(&c->dual, rs->res, rs->xyz, rs->n, c->outputs[o], err,
                                      sizeof err);
            if (r != FDT_OK) {
                progress_clear(&rs->prog);
                say("%s", err);
                code = fdt_cli_dual_exit(r);
            }
            continue;
        }
        int r = fdt_write_mesh_opts(rs->res, rs->xyz, rs->n, c->outputs[o], &wo, err, sizeof err);
        if (r != FDT_OK) {
            progress_clear(&rs->prog);
            say("%s", err);
            code = exit_for_writer(r);
        }
    }
    progress_clear(&rs->prog);
    rs->tm.write = fdt_now_s() - t0;
    return code;
}

/* The Voronoi cells and the interpolation (src/cli/dual.h), each when
 * asked. */
static int dual_steps(const cli *c, run_state *rs)
{
    char derr[FDT_IO_PATH + 600];
    if (fdt_cli_dual_wanted(&c->dual)) {
        double t0 = fdt_now_s();
        progress_phase(&rs->prog, "voronoi");
        /* streamed: computed during the run, written from the spool */
        int r = rs->cells ? fdt_cli_cells_write(&c->dual, rs->cells, derr, sizeof derr)
                          : fdt_cli_dual_write(&c->dual, rs->res, rs->xyz, rs->n, derr,
                                               sizeof derr);
        progress_clear(&rs->prog);
        rs->tm.voronoi = fdt_now_s() - t0;
        if (r != FDT_OK) {
            say("%s: %s", rs->name, derr);
            return fdt_cli_dual_exit(r);
        }
    }
    if (fdt_cli_interp_wanted(&c->dual)) {
        double t0 = fdt_now_s();
        progress_phase(&rs->prog, "interpolate");
        int r = fdt_cli_interp_write(&c->dual, rs->res, rs->xyz, rs->n, derr, sizeof derr);
        progress_clear(&rs->prog);
        rs->tm.interpolate = fdt_now_s() - t0;
        if (r != FDT_OK) {
            say("%s", derr);
            return fdt_cli_dual_exit(r);
        }
    }
    return CLI_OK;
}

/* --stats-json's object to its file or stdout. A file goes through a
 * temporary renamed at the end, as the mesh does: a failed or interrupted
 * write leaves what was there. A device or a pipe (named, or reached
 * through a link) is written in place: renaming over it would replace a
 * /dev node or a FIFO someone reads with a plain file. */
static int write_stats_file(const cli *c, run_state *rs, const fdt_stats *st)
{
    char jerr[1024];
    fdt_wr_side *side = NULL;
    struct stat jst;
    int json_stdout = rs->json_stdout;
    int in_place = json_stdout || (stat(c->stats_json, &jst) == 0 && !S_ISREG(jst.st_mode));
    FILE *f = json_stdout ? stdout
              : in_place  ? fopen(c->stats_json, "w")
                          : fdt_wr_side_open(c->stats_json, &side, jerr, sizeof jerr);
    if (!f) {
        if (in_place)
            say("%s: %s", c->stats_json, strerror(errno));
        else
            say("%s", jerr);
        return CLI_WRITE;
    }
    errno = 0;
    write_stats_json(f, c, rs->res, st, rs->dups, &rs->tm, c->hash, rs->hash);
    int e = ferror(f) ? (errno ? errno : EIO) : 0;
    if (in_place) {
        if ((json_stdout ? fflush(f) : fclose(f)) != 0 && !e)
            e = errno ? errno : EIO;
        if (e) {
            say("%s: %s", json_stdout ? "stdout" : c->stats_json, strerror(e));
            return CLI_WRITE;
        }
    } else if (e) {
        fdt_wr_side_abandon(side);
        say("%s: %s", c->stats_json, strerror(e));
        return CLI_WRITE;
    } else if (fdt_wr_side_commit(side, jerr, sizeof jerr) != FDT_IO_OK) {
        say("%s", jerr);
        return CLI_WRITE;
    }
    return CLI_OK;
}

/* --stats on stderr, --stats-json to its file. */
static int write_stats(const cli *c, run_state *rs)
{
    fdt_stats st;
    memset(&st, 0, sizeof st);
    int r = fdt_result_stats(rs->res, &st);
    if (r != FDT_OK && (c->stats || c->stats_json)) {
        say("%s: no statistics: %s", rs->name, fdt_strerror(r));
        return fdt_cli_engine_exit(r);
    }
    if (c->stats) {
        print_stats(rs->res, &st, rs->dups, &rs->tm);
        print_memory(&st, rs->n, rs->estimate, peak_rss_bytes());
    }
    return c->stats_json ? write_stats_file(c, rs, &st) : CLI_OK;
}

/* Every file of the run, complete in its temporary, renamed over its name
 * at once (fdt_wr_set_commit). */
static int commit_outputs(const cli *c, run_state *rs)
{
    (void)c;
    (void)rs;
    char cerr[FDT_IO_PATH + 300];
    if (fdt_wr_set_commit(cerr, sizeof cerr) != FDT_IO_OK) {
        say("%s", cerr);
        return CLI_WRITE;
    }
    return CLI_OK;
}

/* The hashes and, unless --quiet, the summary. */
static int print_summary(const cli *c, run_state *rs)
{
    FILE *info = rs->info;
    if (c->hash)
        fprintf(info, "hash: %016" PRIx64 "\n", rs->hash);
    if (c->set_hash)
        fprintf(info, "set-hash: %016" PRIx64 "\n", rs->set_hash);
    if (!c->quiet) {
        size_t nh = rs->streaming ? (size_t)rs->fo.hull : fdt_result_num_hull_faces(rs->res);
        if (c->demo)
            fprintf(info, "demo: %zu random points in the unit cube\n", rs->n);
        else
            fprintf(info, "input: %s\n", c->input);
        fprintf(info, "points: %zu", rs->n);
        if (rs->dups)
            fprintf(info, " (%zu duplicates merged)", rs->dups);
        fprintf(info, "\ntets: %zu\nhull faces: %zu\n", rs->nt, nh);
        fprintf(info, "time: %.3f s\n", rs->tm.triangulate);
        fprintf(info, "tets/s: %.0f\n",
                rs->tm.triangulate > 0 ? (double)rs->nt / rs->tm.triangulate : 0.0);
        if (c->check)
            fprintf(info, "check: passed\n");
        if (c->output)
            fprintf(info, "output: %s\n", c->output);
    }
    if (fflush(stdout) != 0) {
        say("stdout: %s", strerror(errno));
        return CLI_WRITE;
    }
    return CLI_OK;
}

static int run(const cli *c)
{
    run_state rs;
    memset(&rs, 0, sizeof rs);
    rs.name = !c->input ? "demo" : strcmp(c->input, "-") ? c->input : "stdin";
    /* The progress line (src/cli/progress.h): on a terminal, or asked for. */
    progress_init(&rs.prog, !c->quiet && (c->progress || isatty(STDERR_FILENO)));
    rs.json_stdout = c->stats_json && !strcmp(c->stats_json, "-");
    /* stdout carries the JSON object alone when asked to. */
    rs.info = rs.json_stdout ? stderr : stdout;
    int code = plan_outputs(c, &rs);
    if (code != CLI_OK)
        return code;
    /* Every file output of the run (the meshes, streamed or not, the
     * dual's files and the --stats-json file) waits complete in its
     * temporary until all are, then all are renamed together
     * (commit_outputs): all new, or, after any failure or signal, all as
     * they were. */
    if (fdt_wr_set_begin(c->no_clobber) != 0) {
        say("internal error: a commit set is already open");
        return CLI_INTERNAL;
    }
    /* Each step in turn, until one fails: its exit code. */
    static int (*const steps[])(const cli *, run_state *) = {
        read_points, triangulate, check_mesh, canonical_order, write_meshes,
        dual_steps, write_stats, commit_outputs, print_summary,
    };
    for (size_t i = 0; i < sizeof steps / sizeof *steps && code == CLI_OK; i++)
        code = steps[i](c, &rs);
    fdt_wr_set_abandon(); /* after a failure: every temporary goes */
    fdt_result_free(&rs.res);
    fdt_cli_cells_close(&rs.cells);
    fdt_close(&rs.ctx);
    free(rs.xyz);
    return code;
}

int main(int argc, char **argv)
{
    if (fdt_cli_signals("frontdt", fdt_write_cleanup, CLI_SIGNAL) != 0) {
        say("cannot install signal handlers: %s", strerror(errno));
        return CLI_INTERNAL;
    }
    int nargc = 0, n_owned = 0;
    char **owned = NULL;
    char **nargv = rewrite_demo(argc, argv, &nargc, &owned, &n_owned);
    if (!nargv) {
        say("out of memory");
        return CLI_RESOURCES;
    }
    cli c;
    int code = parse_args(nargc, nargv, &c);
    if (code < 0)
        code = run(&c);
    for (int i = 0; i < n_owned; i++)
        free(owned[i]);
    free(owned);
    free(nargv);
    return code;
}
