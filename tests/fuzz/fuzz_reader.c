/*
 * libFuzzer target for the point readers (src/io/read/reader.c), one build per
 * format: FDT_FUZZ_FORMAT is 1 (.xyz), 2 (.node) or 3 (.ply). The input
 * bytes are the file; fdt_rd_points_mem() parses them exactly as
 * fdt_rd_points() would parse a file holding them.
 *
 * Beyond "no crash, no leak, no undefined behaviour" (the sanitizers'
 * part), every outcome is checked against the reader's contract
 * (src/io/read/reader.h) and a violation aborts, which libFuzzer reports as a
 * crash with the input saved:
 *  - success: points returned, 1 <= n, at least 3 bytes per point (a
 *    binary PLY of int8 coordinates is the densest encoding), every
 *    coordinate finite;
 *  - failure: FDT_IO_EFORMAT only (these inputs are small: no other code
 *    is possible), no points, and a message that starts with the name
 *    followed by ':' and is one line of printable ASCII (offending bytes
 *    are quoted as \xHH, so garbage cannot reach a terminal).
 *
 * Built two ways by tests/fuzz/meson.build: with -fsanitize=fuzzer (clang,
 * option -Dfuzzing=true) and, always, with tests/fuzz/replay_main.c as a
 * plain program that replays the corpus in the default test suite.
 */
#include "io/read/reader.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if !defined(FDT_FUZZ_FORMAT) || FDT_FUZZ_FORMAT < 1 || FDT_FUZZ_FORMAT > 3
#error "define FDT_FUZZ_FORMAT as 1 (.xyz), 2 (.node) or 3 (.ply)"
#endif

static const char *const fuzz_names[4] = {"", "fuzz.xyz", "fuzz.node",
                                          "fuzz.ply"};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void fuzz_violation(const char *what, const char *err)
{
    fprintf(stderr, "fuzz_reader (%s): contract violated: %s\n  message: %s\n",
            fuzz_names[FDT_FUZZ_FORMAT], what, err);
    abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *name = fuzz_names[FDT_FUZZ_FORMAT];
    static double sentinel;
    double *xyz = &sentinel; /* the reader must overwrite it */
    size_t n = 12345;
    char err[512];
    memset(err, 'Z', sizeof err);
    int rc = fdt_rd_points_mem(name, data, size, &xyz, &n, err, sizeof err);
    if (memchr(err, '\0', sizeof err) == NULL)
        fuzz_violation("message not NUL-terminated", "(unterminated)");
    /* The sliced read (slices of a byte and up, so every input is cut)
     * must give the same code, points and message. */
    double *pxyz = NULL;
    size_t pn = 0;
    char perr[512];
    int prc = fdt_rd_points_mem_threads(name, data, size, 3, 1, &pxyz, &pn, perr, sizeof perr);
    if (prc != rc || pn != (rc == FDT_IO_OK ? n : 0) || strcmp(perr, err) != 0 ||
        (rc == FDT_IO_OK && memcmp(pxyz, xyz, 3 * n * sizeof *xyz) != 0))
        fuzz_violation("the sliced read differs from the one-thread read", perr);
    free(pxyz);
    if (rc == FDT_IO_OK) {
        if (xyz == NULL || n == 0)
            fuzz_violation("success without points", err);
        if (n > size / 3)
            fuzz_violation("more points than the bytes can encode", err);
        for (size_t i = 0; i < 3 * n; i++)
            if (!isfinite(xyz[i]))
                fuzz_violation("a coordinate is not finite", err);
        free(xyz);
        return 0;
    }
    if (rc != FDT_IO_EFORMAT)
        fuzz_violation("error code other than FDT_IO_EFORMAT", err);
    if (xyz != NULL || n != 0)
        fuzz_violation("failure left points behind", err);
    size_t nl = strlen(name);
    if (strncmp(err, name, nl) != 0 || err[nl] != ':' || err[nl + 1] == '\0')
        fuzz_violation("message does not start with 'NAME:'", err);
    for (const char *p = err; *p != '\0'; p++)
        if ((unsigned char)*p < 0x20 || (unsigned char)*p >= 0x7f)
            fuzz_violation("non-printable byte in the message", err);
    return 0;
}
