/*
 * The CLI's progress line on stderr (src/cli/main.c): the phase's name, a bar
 * that fits the terminal, the percentage and an estimate of the time left,
 * e.g.
 *   frontdt: triangulate [##########..........]  52% ETA 0:14
 *   frontdt: read 1.2 GB of 3.4 GB [####......]  35% ETA 0:09
 *   frontdt: read 812.0 MB (64.1 MB/s)                 (a pipe: no total)
 *   frontdt: sort 1.3 s                                (no measure of it)
 *   frontdt: write 12.0 MB of ~40.1 MB [###.......]  29% ETA 0:05
 * Phases: read (loading the input), parse, merge (the library's validation,
 * duplicate merge and kd-tree, before its first report), triangulate,
 * check, sort (canonical order and hash), write. Not part of the library.
 *
 * Drawn only when enabled (src/cli/main.c: stderr is a terminal, or --progress,
 * and not --quiet); redrawn at most ten times a second, and at once when a
 * phase starts. The width is the terminal's (TIOCGWINSZ on stderr), else
 * $COLUMNS, else 80. One thread: every call from the thread that runs
 * the CLI (the reader and the library call back on it).
 */
#ifndef FDT_PROGRESS_H
#define FDT_PROGRESS_H

#include <stddef.h>
#include <stdint.h>

typedef struct progress {
    int enabled;
    int fd;            /* where it draws: stderr */
    int width;         /* columns of the line, measured at progress_init */
    const char *phase; /* static string; NULL before the first phase */
    double t_phase;    /* when the phase started */
    double t_drawn;    /* last redraw; a negative value: redraw now */
    int drawn;         /* something is on the line */
    int engine_seen;   /* the library has reported (merge -> triangulate) */
    int approx;        /* the phase's byte total is an estimate: "of ~N" */
} progress;

/* Sets p up; nothing is ever drawn when enabled is 0. */
void progress_init(progress *p, int enabled);

/* Starts a phase (name: a static string) and draws its line at once. */
void progress_phase(progress *p, const char *name);
/* The phase's share done, in [0, 1]. */
void progress_fraction(progress *p, double fraction);
/* Bytes of the phase done of total (total 0: not known, e.g. a pipe). */
void progress_bytes(progress *p, uint64_t done, uint64_t total);
/* Clears the line (before any other message, and at the end). */
void progress_clear(progress *p);

/* Callbacks in the shapes the library wants (user: a progress).
 * progress_engine: fdt_settings.progress; the phase turns from "merge" to
 * "triangulate" at the library's first report. Never cancels.
 * progress_io: fdt_read_options.progress and fdt_write_options.progress;
 * the stage names the phase (read, parse, write), bytes as progress_bytes,
 * a write's total shown as the estimate it is ("12.0 MB of ~40.1 MB"). */
int progress_engine(void *user, double fraction);
void progress_io(void *user, int stage, uint64_t done, uint64_t total);

#endif
