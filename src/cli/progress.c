/* The CLI's progress line (see src/cli/progress.h). */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "cli/progress.h"
#include "base/clock.h"

#include "frontdt.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <time.h>
#include <unistd.h>

/* Narrower than this, the bar is left out (the text alone remains). */
#define MIN_BAR 10
/* The longest line drawn (a very wide terminal gets no wider bar). */
#define MAX_LINE 160

/* The terminal's columns: TIOCGWINSZ on fd, else $COLUMNS, else 80. */
static int term_width(int fd)
{
#ifdef TIOCGWINSZ
    struct winsize ws;
    if (ioctl(fd, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 0)
        return ws.ws_col;
#endif
    const char *c = getenv("COLUMNS");
    if (c != NULL) {
        char *end;
        long v = strtol(c, &end, 10);
        if (end != c && *end == '\0' && v > 0 && v < 100000)
            return (int)v;
    }
    return 80;
}

void progress_init(progress *p, int enabled)
{
    memset(p, 0, sizeof *p);
    p->enabled = enabled;
    p->fd = STDERR_FILENO;
    p->width = enabled ? term_width(p->fd) : 80;
    if (p->width > MAX_LINE)
        p->width = MAX_LINE;
}

/* Writes the whole line at once with write(2): stderr is unbuffered, and
 * one write keeps the line whole beside anything else on the terminal. */
static void put_line(progress *p, const char *text)
{
    char buf[MAX_LINE + 8];
    /* One column short of the width, so the cursor never wraps. */
    int room = p->width - 1 > 0 ? p->width - 1 : 1;
    int n = snprintf(buf, sizeof buf, "\r%-*.*s", room, room, text);
    if (n < 0)
        return;
    if ((size_t)n >= sizeof buf)
        n = (int)sizeof buf - 1;
    ssize_t w = write(p->fd, buf, (size_t)n);
    (void)w; /* a progress line that cannot be drawn is not an error */
    p->drawn = 1;
}

static void fmt_time(char *out, size_t cap, double s)
{
    if (!(s >= 0) || s > 359999)
        s = 359999;
    long t = (long)(s + 0.5);
    if (t >= 3600)
        snprintf(out, cap, "%ld:%02ld:%02ld", t / 3600, t / 60 % 60, t % 60);
    else
        snprintf(out, cap, "%ld:%02ld", t / 60, t % 60);
}

static void fmt_bytes(char *out, size_t cap, double b)
{
    static const char *const unit[] = {"B", "kB", "MB", "GB", "TB"};
    int u = 0;
    while (b >= 1000 && u < 4) {
        b /= 1000;
        u++;
    }
    snprintf(out, cap, u ? "%.1f %s" : "%.0f %s", b, unit[u]);
}

/* Is a redraw due? At most ten a second, and at once after a phase change. */
static int due(progress *p, double t)
{
    return p->enabled && p->phase != NULL && (p->t_drawn < 0 || t - p->t_drawn >= 0.1);
}

/* Draws "PHASE[ what] [bar] NN% ETA m:ss" fitted to the width; fraction
 * < 0: no bar (unknown), tail then says what it can. */
static void draw(progress *p, double t, const char *what, double fraction, const char *tail)
{
    char head[96], pct[48] = "", line[MAX_LINE + 1];
    snprintf(head, sizeof head, "frontdt: %s%s%s", p->phase, what[0] ? " " : "", what);
    if (fraction >= 0) {
        if (fraction > 1)
            fraction = 1;
        double el = t - p->t_phase;
        char eta[32] = "";
        /* an estimate needs a little history to mean anything */
        if (fraction > 0.01 && fraction < 1 && el > 0.5) {
            char tm[24];
            fmt_time(tm, sizeof tm, el * (1 - fraction) / fraction);
            snprintf(eta, sizeof eta, " ETA %s", tm);
        }
        /* the estimate's room is kept from the start: the bar keeps its
         * width when one appears */
        snprintf(pct, sizeof pct, " %3d%%%-12s", (int)(fraction * 100), eta);
        int room = p->width - 1 - (int)strlen(head) - (int)strlen(pct) - 3;
        if (room >= MIN_BAR) {
            char bar[MAX_LINE + 1];
            if (room > MAX_LINE)
                room = MAX_LINE;
            int full = (int)(fraction * room);
            for (int i = 0; i < room; i++)
                bar[i] = i < full ? '#' : '.';
            bar[room] = '\0';
            snprintf(line, sizeof line, "%s [%s]%s", head, bar, pct);
        } else {
            snprintf(line, sizeof line, "%s%s", head, pct);
        }
    } else {
        snprintf(line, sizeof line, "%s%s%s", head, tail[0] ? " " : "", tail);
    }
    put_line(p, line);
    p->t_drawn = t;
}

void progress_phase(progress *p, const char *name)
{
    if (!p->enabled)
        return;
    p->phase = name;
    p->approx = 0;
    p->t_phase = fdt_now_s();
    p->t_drawn = -1;
    draw(p, p->t_phase, "", -1, "...");
}

void progress_fraction(progress *p, double fraction)
{
    double t = fdt_now_s();
    if (!due(p, t))
        return;
    if (!(fraction >= 0))
        fraction = 0;
    draw(p, t, "", fraction, "");
}

void progress_bytes(progress *p, uint64_t done, uint64_t total)
{
    double t = fdt_now_s();
    if (!due(p, t))
        return;
    char d[32], what[80];
    fmt_bytes(d, sizeof d, (double)done);
    if (total > 0) {
        char tt[32];
        fmt_bytes(tt, sizeof tt, (double)total);
        snprintf(what, sizeof what, "%s of %s%s", d, p->approx ? "~" : "", tt);
        draw(p, t, what, (double)done / (double)total, "");
    } else {
        /* no total (a pipe): the amount and the rate keep it moving */
        double el = t - p->t_phase;
        char rate[48] = "";
        if (el > 0.2) {
            char r[32];
            fmt_bytes(r, sizeof r, (double)done / el);
            snprintf(rate, sizeof rate, "(%s/s)", r);
        }
        snprintf(what, sizeof what, "%s", d);
        draw(p, t, what, -1, rate);
    }
}

void progress_clear(progress *p)
{
    if (!p->drawn)
        return;
    put_line(p, "");
    ssize_t w = write(p->fd, "\r", 1);
    (void)w;
    p->drawn = 0;
}

int progress_engine(void *user, double fraction)
{
    progress *p = user;
    if (!p->engine_seen) {
        /* the library reports only once its front runs: what came before
         * was validation, the duplicate merge and the kd-tree */
        p->engine_seen = 1;
        progress_phase(p, "triangulate");
    }
    progress_fraction(p, fraction);
    return 0;
}

void progress_io(void *user, int stage, uint64_t done, uint64_t total)
{
    progress *p = user;
    const char *want = stage == FDT_STAGE_PARSE ? "parse"
                       : stage == FDT_STAGE_WRITE ? "write"
                                                  : "read";
    if (p->enabled && (p->phase == NULL || strcmp(p->phase, want) != 0))
        progress_phase(p, want);
    /* the writers' total is their estimate (include/frontdt.h) */
    p->approx = stage == FDT_STAGE_WRITE;
    progress_bytes(p, done, total);
}
