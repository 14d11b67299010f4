/* Huge-page hints; see mem.h. */
#define _DEFAULT_SOURCE /* madvise and MADV_HUGEPAGE are not POSIX */
#include "base/mem.h"

#include <stdlib.h>
#include <string.h>

#include "frontdt.h"

#include <stdint.h>
#include <stdio.h>
#include <unistd.h>
#if defined(__linux__)
#include <sys/mman.h>
#endif

#define HUGE_PAGE ((uintptr_t)2 << 20)

void fdt_mem_advise_huge(void *p, size_t bytes)
{
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    if (!p || bytes < 2 * HUGE_PAGE)
        return;
    uintptr_t lo = ((uintptr_t)p + HUGE_PAGE - 1) & ~(HUGE_PAGE - 1);
    uintptr_t hi = ((uintptr_t)p + bytes) & ~(HUGE_PAGE - 1);
    if (hi > lo)
        (void)madvise((void *)lo, hi - lo, MADV_HUGEPAGE);
#else
    (void)p;
    (void)bytes;
#endif
}

/* An array under two huge pages, written at once, gets its pages in one
 * call (MADV_POPULATE_WRITE, Linux 5.14; elsewhere, or where it fails,
 * the first writes fault them in as before): a 4 KB fault is a trap,
 * 15-20 us on this project's VM, and at 100k points the merge's and the
 * Morton sort's 1,500 faults were most of their 30 ms (bench/NOTES.md
 * entry 134). Larger arrays take huge pages, a fault every 2 MB. */
static void prefault(void *p, size_t bytes)
{
#if defined(__linux__) && defined(MADV_POPULATE_WRITE)
    const uintptr_t page = 4096;
    uintptr_t lo = ((uintptr_t)p + page - 1) & ~(page - 1);
    uintptr_t hi = ((uintptr_t)p + bytes) & ~(page - 1);
    if (p && hi > lo)
        (void)madvise((void *)lo, hi - lo, MADV_POPULATE_WRITE);
#else
    (void)p;
    (void)bytes;
#endif
}

void *fdt_mem_alloc_huge(size_t n, size_t size, int zero)
{
    if (size && n > SIZE_MAX / size)
        return NULL;
    void *p = zero ? calloc(n, size) : malloc(n * size);
    if (n * size < 2 * HUGE_PAGE)
        prefault(p, n * size);
    else
        fdt_mem_advise_huge(p, n * size);
    return p;
}

void *fdt_mem_realloc_huge(void *p, size_t old_bytes, size_t new_bytes)
{
    void *q = fdt_mem_alloc_huge(new_bytes ? new_bytes : 1, 1, 0);
    if (!q)
        return NULL;
    if (p && old_bytes)
        memcpy(q, p, old_bytes < new_bytes ? old_bytes : new_bytes);
    free(p);
    return q;
}

size_t fdt_mem_available(void)
{
    return fdt_mem_available_at("/proc/meminfo");
}

size_t fdt_mem_available_at(const char *meminfo)
{
    FILE *f = fopen(meminfo, "r");
    if (f) {
        char line[256];
        unsigned long long kib;
        while (fgets(line, sizeof line, f))
            if (sscanf(line, "MemAvailable: %llu kB", &kib) == 1) {
                fclose(f);
                return kib > SIZE_MAX / 1024 ? SIZE_MAX : (size_t)kib * 1024;
            }
        fclose(f);
    }
#if defined(_SC_AVPHYS_PAGES) && defined(_SC_PAGESIZE)
    long pages = sysconf(_SC_AVPHYS_PAGES), size = sysconf(_SC_PAGESIZE);
    if (pages > 0 && size > 0 && (unsigned long)pages <= SIZE_MAX / (unsigned long)size)
        return (size_t)pages * (size_t)size;
#endif
    return SIZE_MAX;
}

int fdt_grow(void *pp, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap)
        return 0;
    size_t c = *cap ? *cap : 64;
    while (c < need)
        c *= 2;
    void *q = realloc(*(void **)pp, c * size);
    if (!q)
        return FDT_ENOMEM;
    *(void **)pp = q;
    *cap = c;
    return 0;
}
