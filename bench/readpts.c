/*
 * readpts FILE [THREADS [FORMAT]]
 *
 * Times one fdt_read_points_opts of FILE and prints
 *
 *   READPTS n=N read_s=S fnv=HASH
 *
 * HASH is the 64-bit FNV-1a of the coordinates' bytes, so two builds of
 * the reader can be compared bit for bit; run it under
 * /usr/bin/time -f '%e s %M KiB' for the peak resident set, which is then
 * the reader's alone (no triangulation after it). The streaming input of
 * issue 18 was measured with it (bench/NOTES.md).
 */
#define _POSIX_C_SOURCE 200809L
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "frontdt.h"

int main(int argc, char **argv)
{
    if (argc < 2 || argc > 4) {
        fprintf(stderr, "usage: %s FILE [THREADS [FORMAT]]\n", argv[0]);
        return 1;
    }
    fdt_read_options o;
    fdt_default_read_options(&o);
    o.n_threads = argc > 2 ? atoi(argv[2]) : 1;
    o.format = argc > 3 ? argv[3] : NULL;
    struct timespec a, b;
    clock_gettime(CLOCK_MONOTONIC, &a);
    double *xyz = NULL;
    size_t n = 0;
    char err[1024];
    int rc = fdt_read_points_opts(argv[1], &o, &xyz, &n, err, sizeof err);
    clock_gettime(CLOCK_MONOTONIC, &b);
    if (rc != FDT_OK) {
        fprintf(stderr, "%s\n", err);
        return 2;
    }
    uint64_t h = 1469598103934665603ull;
    const unsigned char *p = (const unsigned char *)xyz;
    for (size_t i = 0; i < 3 * n * sizeof(double); i++)
        h = (h ^ p[i]) * 1099511628211ull;
    printf("READPTS n=%zu read_s=%.3f fnv=%016llx\n", n,
           (double)(b.tv_sec - a.tv_sec) + 1e-9 * (double)(b.tv_nsec - a.tv_nsec),
           (unsigned long long)h);
    free(xyz);
    return 0;
}
