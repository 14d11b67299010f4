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
    if (!fdt_mem_fits(n * size))
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
    return fdt_mem_available_in("");
}

/* The first number after `key` at the start of a line of file root/path
 * (key "": the file's first number, "max" read as none): 1 if found. */
static int read_number(const char *root, const char *path, const char *key,
                       unsigned long long *v)
{
    char name[4096];
    if (snprintf(name, sizeof name, "%s%s", root, path) >= (int)sizeof name)
        return 0;
    FILE *f = fopen(name, "r");
    if (!f)
        return 0;
    char line[512];
    size_t kl = strlen(key);
    int found = 0;
    while (!found && fgets(line, sizeof line, f))
        if (strncmp(line, key, kl) == 0 && (kl == 0 || line[kl] == ' ' || line[kl] == ':'))
            found = sscanf(line + kl + (kl != 0), " %llu", v) == 1;
    fclose(f);
    return found;
}

/*
 * The least room left under the memory limits of this process's cgroup
 * and the cgroups above it (v2: memory.max; v1: the memory controller's
 * memory.limit_in_bytes), SIZE_MAX where none is set. A container's
 * limit is not in MemAvailable, and past it the kernel kills the process
 * (a quadratic-size mesh, points on a line and a circle, was killed at 20
 * GB instead of failing cleanly). The room at a level: its limit less its
 * usage, plus the file pages it can drop (inactive_file), as the kernel
 * reclaims those before it kills. Inside a cgroup namespace the process's
 * own path is "/" and the mount's top files are its cgroup's.
 */
static size_t cgroup_room(const char *root)
{
    char name[4096], line[4096], path[4096] = "";
    int v1 = 0;
    if (snprintf(name, sizeof name, "%s/proc/self/cgroup", root) >= (int)sizeof name)
        return SIZE_MAX;
    FILE *f = fopen(name, "r");
    if (!f)
        return SIZE_MAX;
    while (fgets(line, sizeof line, f)) {
        /* hierarchy:controllers:path; v2 is "0::path", v1 lists memory */
        char *c1 = strchr(line, ':'), *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
        if (!c2)
            continue;
        *c2 = '\0';
        int mem = 0;
        char *save = NULL; /* strtok_r: the cells' threads allocate at once */
        for (char *t = strtok_r(c1 + 1, ",", &save); t; t = strtok_r(NULL, ",", &save))
            mem |= strcmp(t, "memory") == 0;
        if (mem || (c1[1] == '\0' && !v1 && strncmp(line, "0:", 2) == 0)) {
            snprintf(path, sizeof path, "%s", c2 + 1);
            path[strcspn(path, "\n")] = '\0';
            v1 = mem;
        }
    }
    fclose(f);
    const char *top = v1 ? "/sys/fs/cgroup/memory" : "/sys/fs/cgroup";
    const char *lim = v1 ? "memory.limit_in_bytes" : "memory.max";
    const char *use = v1 ? "memory.usage_in_bytes" : "memory.current";
    const char *drop = v1 ? "total_inactive_file" : "inactive_file";
    size_t room = SIZE_MAX;
    for (;;) {
        unsigned long long limit, usage, inactive = 0;
        char at[4096];
        size_t pl = strlen(path);
        while (pl > 0 && path[pl - 1] == '/')
            path[--pl] = '\0';
        if (snprintf(at, sizeof at, "%s%s/%s", top, path, lim) < (int)sizeof at &&
            read_number(root, at, "", &limit)) {
            snprintf(at, sizeof at, "%s%s/%s", top, path, use);
            if (read_number(root, at, "", &usage)) {
                snprintf(at, sizeof at, "%s%s/memory.stat", top, path);
                (void)read_number(root, at, drop, &inactive);
                unsigned long long r = (limit > usage ? limit - usage : 0) + inactive;
                if (r < room)
                    room = r > SIZE_MAX ? SIZE_MAX : (size_t)r;
            }
        }
        if (pl == 0)
            break;
        char *slash = strrchr(path, '/');
        *slash = '\0'; /* one level up; "" is the hierarchy's top */
    }
    return room;
}

size_t fdt_mem_available_in(const char *root)
{
    size_t avail = SIZE_MAX;
    unsigned long long kib;
    if (read_number(root, "/proc/meminfo", "MemAvailable", &kib))
        avail = kib > SIZE_MAX / 1024 ? SIZE_MAX : (size_t)kib * 1024;
    else {
#if defined(_SC_AVPHYS_PAGES) && defined(_SC_PAGESIZE)
        long pages = sysconf(_SC_AVPHYS_PAGES), size = sysconf(_SC_PAGESIZE);
        if (pages > 0 && size > 0 && (unsigned long)pages <= SIZE_MAX / (unsigned long)size)
            avail = (size_t)pages * (size_t)size;
#endif
    }
    size_t room = cgroup_room(root);
    return room < avail ? room : avail;
}

int fdt_mem_fits(size_t bytes)
{
    return bytes < FDT_MEM_CHECKED || bytes <= fdt_mem_available();
}

int fdt_grow(void *pp, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap)
        return 0;
    size_t c = *cap ? *cap : 64;
    while (c < need)
        c *= 2;
    if (!fdt_mem_fits((c - *cap) * size))
        return FDT_ENOMEM;
    void *q = realloc(*(void **)pp, c * size);
    if (!q)
        return FDT_ENOMEM;
    *(void **)pp = q;
    *cap = c;
    return 0;
}
