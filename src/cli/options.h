/*
 * The options of both command-line programs in one table (issue 35):
 * frontdt (src/cli/main.c) builds its getopt_long arguments from it,
 * frontdt-mpi (src/cli/mpi_main.c) looks each word up in it, and each
 * program's --help lists the rows it accepts. So an option both accept is
 * spelled the same in both, and the values both check are checked here,
 * once, with one message.
 */
#ifndef FDT_CLI_OPTIONS_H
#define FDT_CLI_OPTIONS_H

#include <getopt.h>
#include <stddef.h>
#include <stdio.h>

#include "frontdt.h"

/* Which program accepts a row: bits of fdt_cli_opt.progs. */
enum { FDT_CLI_FRONTDT = 1, FDT_CLI_MPI = 2, FDT_CLI_BOTH = 3 };

/* -o given more often than this is a usage error (frontdt's parse, and
 * its --help says so) */
#define FDT_CLI_MAX_OUTPUTS 8
/* --demo without N (frontdt's parse, and its --help says so) */
#define FDT_CLI_DEMO_POINTS 1000000

/* The rows, in --help's order; the table is indexed by them. */
typedef enum fdt_cli_opt_id {
    FDT_OPT_OUTPUT,
    FDT_OPT_NO_CLOBBER,
    FDT_OPT_FORMAT,
    FDT_OPT_ALL_FACES,
    FDT_OPT_INPUT_FORMAT,
    FDT_OPT_COLUMNS,
    FDT_OPT_DELIMITER,
    FDT_OPT_DECIMAL_COMMA,
    FDT_OPT_MODE,
    FDT_OPT_SEARCH,
    FDT_OPT_LEAF,
    FDT_OPT_NO_PARK,
    FDT_OPT_THREADS,
    FDT_OPT_PIN,
    FDT_OPT_CHECK,
    FDT_OPT_STATS,
    FDT_OPT_STATS_JSON,
    FDT_OPT_HASH,
    FDT_OPT_SET_HASH,
    FDT_OPT_VORONOI,
    FDT_OPT_VORONOI_FORMAT,
    FDT_OPT_DENSITY,
    FDT_OPT_BOX,
    FDT_OPT_PERIODIC,
    FDT_OPT_DUAL,
    FDT_OPT_VALUES,
    FDT_OPT_INTERPOLATE,
    FDT_OPT_INTERPOLATED,
    FDT_OPT_METHOD,
    FDT_OPT_STREAM,
    FDT_OPT_NO_STREAM,
    FDT_OPT_MEMORY_LIMIT,
    FDT_OPT_QUIET,
    FDT_OPT_PROGRESS,
    FDT_OPT_DEMO,
    FDT_OPT_HELP,
    FDT_OPT_VERSION,
    FDT_OPT_INJECT_FAILURE,
    FDT_OPT_INJECT_WRITE_FAILURE,
    FDT_OPT_END
} fdt_cli_opt_id;

typedef struct fdt_cli_opt {
    const char *name;     /* the long name, without "--" */
    char letter;          /* the short name ('o' for -o), or 0 */
    int arg;              /* getopt's no_argument, required_argument or
                             optional_argument (--demo's "=N" alone) */
    const char *value;    /* the value's name in --help ("FILE"), or NULL */
    unsigned progs;       /* FDT_CLI_FRONTDT | FDT_CLI_MPI: who accepts it */
    int hidden;           /* accepted but not in --help: for the tests */
    const char *help;     /* --help's text, lines split by '\n' */
    const char *help_mpi; /* frontdt-mpi's text where it differs, or NULL */
} fdt_cli_opt;

extern const fdt_cli_opt fdt_cli_opts[FDT_OPT_END];

/* The option lines of prog's --help (FDT_CLI_FRONTDT or FDT_CLI_MPI): a
 * row it accepts and that is not hidden, in the table's order; --search's
 * text is followed by a line a search (src/front/search.c). */
void fdt_cli_help(FILE *f, unsigned prog);

/* getopt_long's arguments for prog's rows: longs gets FDT_OPT_END + 1
 * entries at most (the last zeroed), shorts ":" and each letter (with
 * ':' where it takes a value), 2 * FDT_OPT_END + 2 bytes at most. */
void fdt_cli_getopt_args(unsigned prog, struct option *longs, char *shorts);

/* What getopt_long returned for an option of fdt_cli_getopt_args: the
 * row's id, or -1 (':', '?'). */
int fdt_cli_getopt_id(int ch);

/* The row prog accepts under word ("-q" or "--quiet", exactly), or -1. */
int fdt_cli_find(const char *word, unsigned prog);

/*
 * The values both programs check, with one message each (in err, without
 * the program's name): 0, or -1. --search NAME (fdt_search_from_name), --leaf
 * N (1 .. 1000000), --input-format NAME (an FDT_RD_* of
 * src/io/read/reader.h, not FDT_RD_AUTO), --periodic AXES.
 */
int fdt_cli_search(const char *name, fdt_search *out, char *err, size_t len);
int fdt_cli_leaf(const char *s, int *out, char *err, size_t len);
int fdt_cli_input_format(const char *name, int *out, char *err, size_t len);
/* --periodic AXES: x, y, z, once each, optionally comma separated (x,z,
 * xyz); *axes gets bit k for axis k. */
int fdt_cli_periodic(const char *v, unsigned *axes, char *err, size_t len);

#endif
