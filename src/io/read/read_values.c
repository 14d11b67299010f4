/*
 * Values given at the points (the CLI's --values, issue 32): one line a
 * point, in input order, k numbers a line (k from the first line; blanks
 * or a comma between them), '#' to the end of a line a comment, blank
 * lines skipped. Numbers as the point readers take them (read_text.c's
 * grammar: no NaN, no Inf). Errors name the file and line.
 */
#include <errno.h>
#include <sys/types.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/read/read_common.h"
#include "io/read/reader.h"

static int fail(char *err, size_t errlen, const char *path, size_t line, const char *msg)
{
    if (line)
        snprintf(err, errlen, "%s:%zu: %s", path, line, msg);
    else
        snprintf(err, errlen, "%s: %s", path, msg);
    return line ? FDT_IO_EFORMAT : FDT_IO_EOPEN;
}

int fdt_rd_values(const char *path, size_t n, double **vals, size_t *k, char *err,
                  size_t errlen)
{
    *vals = NULL;
    *k = 0;
    FILE *f = fopen(path, "rb");
    if (!f)
        return fail(err, errlen, path, 0, strerror(errno));
    char *line = NULL;
    size_t cap = 0, row = 0, lineno = 0, room = 0;
    double *v = NULL;
    int rc = FDT_IO_OK;
    ssize_t got;
    while (rc == FDT_IO_OK && (got = getline(&line, &cap, f)) >= 0) {
        lineno++;
        char *s = line, *e = line + got, *hash = memchr(line, '#', (size_t)got);
        if (hash)
            e = hash;
        size_t cols = 0;
        while (rc == FDT_IO_OK) {
            while (s < e && (*s == ' ' || *s == '\t' || *s == '\r' || *s == '\n' || *s == ','))
                s++;
            if (s == e)
                break;
            char *t = s;
            while (t < e && !(*t == ' ' || *t == '\t' || *t == '\r' || *t == '\n' || *t == ','))
                t++;
            if (row >= n) {
                rc = fail(err, errlen, path, lineno, "more rows than points");
                break;
            }
            if (*k && cols == *k) {
                char msg[96];
                snprintf(msg, sizeof msg, "more than the %zu values of the first row", *k);
                rc = fail(err, errlen, path, lineno, msg);
                break;
            }
            if (row * (*k ? *k : cols + 1) + cols + 1 > room) {
                size_t nr = room ? 2 * room : 1024;
                double *q = realloc(v, nr * sizeof *q);
                if (!q) {
                    rc = FDT_IO_ENOMEM;
                    snprintf(err, errlen, "%s: out of memory", path);
                    break;
                }
                v = q;
                room = nr;
            }
            double x;
            int st = fdt_rd_parse_real(s, (size_t)(t - s), &x, 1);
            if (st != NUM_OK) {
                char msg[96];
                snprintf(msg, sizeof msg, "value %zu is not a finite number: '%.*s'", cols + 1,
                         (int)(t - s < 24 ? t - s : 24), s);
                rc = fail(err, errlen, path, lineno, msg);
                break;
            }
            v[row * (*k ? *k : cols + 1) + cols] = x;
            cols++;
            s = t;
        }
        if (rc != FDT_IO_OK || cols == 0)
            continue;
        if (!*k)
            *k = cols;
        else if (cols != *k) {
            char msg[96];
            snprintf(msg, sizeof msg, "%zu values, the first row had %zu", cols, *k);
            rc = fail(err, errlen, path, lineno, msg);
            break;
        }
        row++;
    }
    if (rc == FDT_IO_OK && ferror(f))
        rc = fail(err, errlen, path, 0, strerror(errno ? errno : EIO));
    if (rc == FDT_IO_OK && row != n) {
        snprintf(err, errlen, "%s: %zu rows of values for %zu points", path, row, n);
        rc = FDT_IO_EFORMAT;
    }
    free(line);
    fclose(f);
    if (rc != FDT_IO_OK) {
        free(v);
        *k = 0;
        return rc;
    }
    *vals = v;
    return FDT_IO_OK;
}
