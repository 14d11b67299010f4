/*
 * src/mem.c: the huge-page hint. Where the kernel grants transparent huge
 * pages on request (the "madvise" or "always" setting), memory advised
 * and then written must show up as AnonHugePages in /proc/self/smaps for
 * its range; elsewhere (other systems, "never") the test checks only that
 * the hint leaves the memory usable, and says so. Odd alignments and
 * sizes below the threshold must be harmless.
 */
#define _DEFAULT_SOURCE
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mem.h"

static int failures;
#define CHECK(cond, ...)                                                     \
    do {                                                                     \
        if (!(cond)) {                                                       \
            fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__);             \
            fprintf(stderr, __VA_ARGS__);                                    \
            fputc('\n', stderr);                                             \
            failures++;                                                      \
        }                                                                    \
    } while (0)

/* The kernel's setting: 1 if it grants huge pages on request. */
static int thp_on_request(void)
{
    FILE *f = fopen("/sys/kernel/mm/transparent_hugepage/enabled", "r");
    if (!f)
        return 0;
    char buf[128] = {0};
    size_t got = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[got] = '\0';
    return strstr(buf, "[madvise]") != NULL || strstr(buf, "[always]") != NULL;
}

/* kB of AnonHugePages in the mappings that overlap [p, p + bytes). */
static long huge_kb(const void *p, size_t bytes)
{
    FILE *f = fopen("/proc/self/smaps", "r");
    if (!f)
        return -1;
    char line[512];
    long kb = 0;
    int in = 0;
    uintptr_t lo = (uintptr_t)p, hi = lo + bytes;
    while (fgets(line, sizeof line, f)) {
        unsigned long a, b;
        if (sscanf(line, "%lx-%lx ", &a, &b) == 2 && strchr(line, '-') < strchr(line, ' ')) {
            in = a < hi && b > lo;
            continue;
        }
        long v;
        if (in && sscanf(line, "AnonHugePages: %ld kB", &v) == 1)
            kb += v;
    }
    fclose(f);
    return kb;
}

int main(void)
{
    /* Harmless anywhere: NULL, tiny, unaligned. */
    fdt_mem_advise_huge(NULL, 1 << 30);
    char small[100];
    fdt_mem_advise_huge(small, sizeof small);
    memset(small, 1, sizeof small);

    size_t bytes = (size_t)16 << 20;
    unsigned char *p = malloc(bytes);
    CHECK(p != NULL, "malloc");
    if (!p)
        return 1;
    fdt_mem_advise_huge(p + 3, bytes - 3);
    for (size_t i = 0; i < bytes; i++)
        p[i] = (unsigned char)(i * 7);
    size_t bad = 0;
    for (size_t i = 0; i < bytes; i++)
        bad += p[i] != (unsigned char)(i * 7);
    CHECK(bad == 0, "%zu bytes changed", bad);
    long kb = huge_kb(p, bytes);
    if (thp_on_request() && kb >= 0) {
        /* 16 MB hold at least six aligned 2 MB pages; the kernel may
         * fall back to small pages when memory is fragmented, so one
         * huge page is the proof asked for. */
        CHECK(kb >= 2048, "no huge page over an advised 16 MB range (%ld kB)", kb);
        printf("mem: %ld kB of huge pages over 16 MB advised\n", kb);
    } else {
        printf("mem: transparent huge pages not granted on request here; usability only\n");
    }
    free(p);
    if (failures) {
        fprintf(stderr, "%d failures\n", failures);
        return 1;
    }
    printf("mem: all passed\n");
    return 0;
}
