/*
 * What the two command-line programs (frontdt, src/cli/main.c; frontdt-mpi,
 * src/cli/mpi_main.c) share, so they cannot drift apart: their signal
 * handling and exit codes (their options: src/cli/options.h). Not part of the library,
 * which never installs handlers.
 */
#ifndef FDT_CLI_H
#define FDT_CLI_H

#include "frontdt.h"

/* The exit codes of both programs (doc/reference.md, "Exit codes";
 * doc/frontdt.1). */
enum {
    CLI_OK = 0,
    CLI_USAGE = 1,     /* bad options or arguments */
    CLI_INPUT = 2,     /* the input cannot be read or parsed */
    CLI_CHECK = 3,     /* --check, or the mesh certificate, failed */
    CLI_RESOURCES = 4, /* out of memory, or too many points */
    CLI_WRITE = 5,     /* an output cannot be written */
    CLI_SIGNAL = 6,    /* interrupted (SIGINT, SIGTERM) */
    CLI_INTERNAL = 7   /* a bug */
};

/*
 * SIGINT and SIGTERM call cleanup (not NULL; async-signal-safe: it
 * removes the temporaries of the outputs in progress), print "\nPROG: interrupted\n"
 * on standard error and leave with exit_code. A signal ignored at startup
 * stays ignored (the Unix convention: the shell ignores SIGINT for
 * background jobs, and nohup and friends mean it). SIGXFSZ is ignored, so
 * a write beyond RLIMIT_FSIZE (ulimit -f) fails with EFBIG and reaches the
 * writer, which reports it like a full disk and removes its temporaries,
 * instead of killing the process with them left behind. Call once, before
 * any thread starts. 0, or -1 with errno set.
 */
int fdt_cli_signals(const char *prog, void (*cleanup)(void), int exit_code);

/* The exit code of a library error from the engine (an FDT_E* code), the
 * same in frontdt and frontdt-mpi: a refused argument or box is usage,
 * input that has no mesh is input, memory and size are resources, a
 * failed certificate is a check, the rest internal. */
int fdt_cli_engine_exit(int err);

#endif
