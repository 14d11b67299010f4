/*
 * The CLI's progress line (src/cli/progress.c), drawn into a temporary file
 * instead of stderr and read back:
 * - nothing at all when disabled;
 * - the width: $COLUMNS (stderr is no terminal here), 80 when unset or
 *   not a positive number, at most 160; every line one column short;
 * - a phase draws at once; redraws at most ten a second;
 * - the bar and percentage, the estimate of the time left (once 0.5 s
 *   have passed and 1 % is done; h:mm:ss past an hour, capped at
 *   99:59:59), fractions above 1 or not a number clamped, the bar left
 *   out when the line is too narrow;
 * - bytes: "done of total" in B/kB/MB/GB/TB, a write's total as the
 *   estimate it is ("of ~"), no total (a pipe): the amount and the rate;
 * - the library's callbacks: the first engine report starts
 *   "triangulate", each I/O stage names its phase;
 * - clearing blanks the line and returns the cursor, once.
 * Phase times are moved back by hand (t_phase) rather than slept through.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

#include "frontdt.h"
#include "cli/progress.h"
#include "testutil.h"

static int g_fd = -1;

/* What was drawn since the last call (the file emptied). */
static const char *take(void)
{
    static char buf[4096];
    off_t n = lseek(g_fd, 0, SEEK_CUR);
    CHECK(n >= 0 && (size_t)n < sizeof buf);
    ssize_t got = pread(g_fd, buf, (size_t)n, 0);
    CHECK(got == (ssize_t)n);
    buf[got] = '\0';
    CHECK(ftruncate(g_fd, 0) == 0);
    CHECK(lseek(g_fd, 0, SEEK_SET) == 0);
    return buf;
}

static void start(progress *p, int enabled, const char *columns)
{
    if (columns)
        setenv("COLUMNS", columns, 1);
    else
        unsetenv("COLUMNS");
    progress_init(p, enabled);
    p->fd = g_fd;
    take();
}

/* Allows the next redraw at once. */
static void later(progress *p)
{
    p->t_drawn -= 1.0;
}

static size_t count(const char *s, char c)
{
    size_t n = 0;
    for (; *s; s++)
        n += *s == c;
    return n;
}

static void test_disabled(void)
{
    progress p;
    start(&p, 0, "60");
    EXPECT(p.width == 80); /* not even measured */
    progress_phase(&p, "read");
    progress_fraction(&p, 0.5);
    progress_bytes(&p, 10, 100);
    progress_io(&p, FDT_STAGE_LOAD, 10, 100);
    progress_engine(&p, 0.5);
    progress_clear(&p);
    EXPECT(take()[0] == '\0' && !p.drawn);
}

static void test_width(void)
{
    progress p;
    start(&p, 1, "60");
    EXPECT(p.width == 60);
    start(&p, 1, "1000");
    EXPECT(p.width == 160);
    start(&p, 1, "7x");
    EXPECT(p.width == 80);
    start(&p, 1, "0");
    EXPECT(p.width == 80);
    start(&p, 1, NULL);
    EXPECT(p.width == 80);
    /* a line is '\r' and width - 1 columns, padded */
    start(&p, 1, "40");
    progress_phase(&p, "sort");
    const char *s = take();
    EXPECTF(s[0] == '\r' && strlen(s) == 40 && !strncmp(s, "\rfrontdt: sort ...", 18),
            "[%s]", s);
    /* a width of 1 still draws one column */
    start(&p, 1, "1");
    progress_phase(&p, "sort");
    s = take();
    EXPECTF(!strcmp(s, "\rf"), "[%s]", s);
}

static void test_fraction(void)
{
    progress p;
    start(&p, 1, "80");
    /* before any phase nothing is due */
    progress_fraction(&p, 0.5);
    EXPECT(take()[0] == '\0');
    progress_phase(&p, "check");
    take();
    /* at once after the phase line: too soon */
    progress_fraction(&p, 0.25);
    EXPECT(take()[0] == '\0');
    later(&p);
    progress_fraction(&p, 0.25);
    const char *s = take();
    /* no estimate yet (under 0.5 s into the phase): its room is kept */
    EXPECTF(strstr(s, "frontdt: check [") && strstr(s, "]  25%") && !strstr(s, "ETA"), "[%s]",
            s);
    size_t bar = count(s, '#') + count(s, '.');
    EXPECTF(bar >= 10 && count(s, '#') == (size_t)(0.25 * (double)bar), "[%s]", s);
    EXPECT(strlen(s) == 80);
    /* 10 s into the phase, half done: 10 s left */
    p.t_phase -= 10;
    later(&p);
    progress_fraction(&p, 0.5);
    s = take();
    EXPECTF(strstr(s, " 50% ETA 0:10"), "[%s]", s);
    /* 100 s for 2 %: 4,900 s left */
    p.t_phase -= 90;
    later(&p);
    progress_fraction(&p, 0.02);
    s = take();
    EXPECTF(strstr(s, "  2% ETA 1:21:40"), "[%s]", s);
    /* capped at 99:59:59 */
    p.t_phase -= 1e7;
    later(&p);
    progress_fraction(&p, 0.02);
    s = take();
    EXPECTF(strstr(s, "ETA 99:59:59"), "[%s]", s);
    /* done, or more than done: 100 %, a full bar, no estimate */
    later(&p);
    progress_fraction(&p, 1.5);
    s = take();
    EXPECTF(strstr(s, "] 100%") && !strstr(s, "ETA") && count(s, '.') == 0, "[%s]", s);
    /* under 1 % done: no estimate; not a number: 0 */
    later(&p);
    progress_fraction(&p, 0.005);
    s = take();
    EXPECTF(strstr(s, "   0%") && !strstr(s, "ETA"), "[%s]", s);
    later(&p);
    progress_fraction(&p, NAN);
    s = take();
    EXPECTF(strstr(s, "   0%") && count(s, '#') == 0, "[%s]", s);
    /* too narrow for a bar: the text alone */
    start(&p, 1, "30");
    progress_phase(&p, "check");
    take();
    later(&p);
    progress_fraction(&p, 0.5);
    s = take();
    EXPECTF(strstr(s, "frontdt: check  50%") && !strchr(s, '['), "[%s]", s);
    EXPECT(strlen(s) == 30);
}

static void test_bytes(void)
{
    progress p;
    start(&p, 1, "120");
    progress_io(&p, FDT_STAGE_LOAD, 0, 3000000);
    const char *s = take();
    /* the phase line, then (not due yet) nothing more */
    EXPECTF(strstr(s, "frontdt: read ...") && !strstr(s, "MB"), "[%s]", s);
    later(&p);
    progress_io(&p, FDT_STAGE_LOAD, 1500000, 3000000);
    s = take();
    EXPECTF(strstr(s, "frontdt: read 1.5 MB of 3.0 MB [") && strstr(s, " 50%"), "[%s]", s);
    later(&p);
    progress_bytes(&p, 999, 2500000000000000ull);
    s = take();
    EXPECTF(strstr(s, "read 999 B of 2500.0 TB"), "[%s]", s);
    later(&p);
    progress_bytes(&p, 12345, 4200000000ull);
    s = take();
    EXPECTF(strstr(s, "read 12.3 kB of 4.2 GB"), "[%s]", s);
    /* a unit is 1,000 of the one below */
    later(&p);
    progress_bytes(&p, 1010, 1000);
    s = take();
    EXPECTF(strstr(s, "read 1.0 kB of 1.0 kB"), "[%s]", s);
    /* the same stage again: no new phase line */
    later(&p);
    progress_io(&p, FDT_STAGE_LOAD, 2000000, 3000000);
    s = take();
    EXPECTF(!strstr(s, "read ...") && strstr(s, "2.0 MB of 3.0 MB"), "[%s]", s);
    /* a write: its own phase, its total an estimate */
    progress_io(&p, FDT_STAGE_WRITE, 0, 40100000);
    s = take();
    EXPECTF(strstr(s, "frontdt: write ..."), "[%s]", s);
    later(&p);
    progress_io(&p, FDT_STAGE_WRITE, 12000000, 40100000);
    s = take();
    EXPECTF(strstr(s, "write 12.0 MB of ~40.1 MB"), "[%s]", s);
    /* parsing a pipe: no total, the amount; the rate once 0.2 s passed */
    progress_io(&p, FDT_STAGE_PARSE, 0, 0);
    s = take();
    EXPECTF(strstr(s, "frontdt: parse ..."), "[%s]", s);
    later(&p);
    progress_io(&p, FDT_STAGE_PARSE, 812000000, 0);
    s = take();
    EXPECTF(strstr(s, "frontdt: parse 812.0 MB") && !strstr(s, "/s") && !strchr(s, '%'),
            "[%s]", s);
    p.t_phase -= 10;
    later(&p);
    progress_io(&p, FDT_STAGE_PARSE, 812000000, 0);
    s = take();
    EXPECTF(strstr(s, "frontdt: parse 812.0 MB (81.2 MB/s)"), "[%s]", s);
}

static void test_engine_and_clear(void)
{
    progress p;
    start(&p, 1, "80");
    progress_phase(&p, "merge");
    take();
    /* the library's first report: the merge is over */
    EXPECT(progress_engine(&p, 0.0) == 0);
    const char *s = take();
    EXPECTF(strstr(s, "frontdt: triangulate ..."), "[%s]", s);
    p.t_phase -= 2;
    later(&p);
    EXPECT(progress_engine(&p, 0.75) == 0);
    s = take();
    EXPECTF(strstr(s, "frontdt: triangulate [") && strstr(s, " 75% ETA 0:01"), "[%s]", s);
    EXPECT(!strstr(s, "triangulate ..."));
    EXPECT(p.drawn);
    progress_clear(&p);
    s = take();
    /* a blank line, then the cursor back */
    EXPECTF(strlen(s) == 81 && s[0] == '\r' && s[80] == '\r' && count(s, ' ') == 79, "[%s]", s);
    EXPECT(!p.drawn);
    progress_clear(&p);
    EXPECT(take()[0] == '\0');
}

int main(void)
{
    /* the width is asked of stderr first: it must not be a terminal */
    if (isatty(STDERR_FILENO)) {
        fprintf(stderr, "test_progress: stderr is a terminal; run it with 2>FILE\n");
        return 77;
    }
    char path[] = "/tmp/test_progress.XXXXXX";
    g_fd = mkstemp(path);
    CHECK(g_fd >= 0);
    unlink(path);
    test_disabled();
    test_width();
    test_fraction();
    test_bytes();
    test_engine_and_clear();
    close(g_fd);
    return test_report("progress");
}
