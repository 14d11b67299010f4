/*
 * src/base/mem.c: the huge-page hint. Where the kernel grants transparent huge
 * pages on request (the "madvise" or "always" setting), memory advised
 * and then written must show up as AnonHugePages in /proc/self/smaps for
 * its range whenever a control range the test advises itself (madvise on
 * its aligned part) gets them too; where the control gets none (other
 * systems, "never", a kernel short of free 2 MB blocks) the test checks
 * only that the hint leaves the memory usable, and says so. Odd
 * alignments and sizes below the threshold must be harmless.
 *
 * fdt_mem_alloc_huge's arrays, small and large, and fdt_mem_realloc_huge's
 * kept bytes (test_alloc_realloc).
 *
 * fdt_mem_available reads MemAvailable from a fake system root of the
 * test's own (fdt_mem_available_in): the value in bytes; a count too big
 * for size_t as SIZE_MAX; a file without the line, or no file, falls back
 * to the free pages (sysconf), the value the test computes itself; then
 * the room under cgroup limits (v2, v1, nested, namespaced, "max"), and
 * fdt_mem_fits refusing, through fdt_mem_alloc_huge and fdt_grow, a
 * block past the real memory available.
 */
#define _DEFAULT_SOURCE
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include "base/mem.h"
#include "frontdt.h"
#include "testutil.h"

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

/* A file of a fake system root (its directories made as needed)
 * holding text; clear_root removes them. */
static char mdir[] = "/tmp/fdt_test_mem_XXXXXX";
static char made[32][160];
static int nmade;

static void put(const char *rel, const char *text)
{
    char path[160];
    snprintf(path, sizeof path, "%s/%s", mdir, rel);
    for (char *s = path + strlen(mdir) + 1; (s = strchr(s, '/')); s++) {
        *s = '\0';
        if (mkdir(path, 0700) == 0) {
            CHECK(nmade < 32);
            snprintf(made[nmade++], sizeof made[0], "%s", path);
        }
        *s = '/';
    }
    int is_new = access(path, F_OK) != 0; /* a file put again is listed once */
    FILE *f = fopen(path, "w");
    CHECK(f);
    CHECK(fputs(text, f) >= 0);
    CHECK(fclose(f) == 0);
    CHECK(nmade < 32);
    if (is_new)
        snprintf(made[nmade++], sizeof made[0], "%s", path);
}

/* Every file and directory put made, the last first. */
static void clear_root(void)
{
    while (nmade > 0)
        CHECK(remove(made[--nmade]) == 0);
}

/* sysconf's free pages in bytes: the fallback, as mem.c computes it. */
static size_t free_pages(void)
{
    long pages = sysconf(_SC_AVPHYS_PAGES), size = sysconf(_SC_PAGESIZE);
    CHECK(pages > 0 && size > 0);
    return (size_t)pages * (size_t)size;
}

/* Within 1/8 of the free pages measured just before and after (they
 * move while the system runs). */
static int near_free_pages(size_t got)
{
    size_t a = free_pages(), b = free_pages();
    size_t lo = (a < b ? a : b), hi = (a > b ? a : b);
    return got >= lo - lo / 8 && got <= hi + hi / 8;
}

static void test_available(void)
{
    CHECK(mkdtemp(mdir));
    put("proc/meminfo", "MemTotal:       16000000 kB\n"
                        "MemFree:         1000000 kB\n"
                        "MemAvailable:    1234567 kB\n"
                        "Buffers:           10000 kB\n");
    EXPECT(fdt_mem_available_in(mdir) == (size_t)1234567 * 1024);
    clear_root();
    /* the first line already */
    put("proc/meminfo", "MemAvailable: 7 kB\n");
    EXPECT(fdt_mem_available_in(mdir) == 7 * 1024);
    clear_root();
    /* 2^64 - 1 kB: more than size_t holds in bytes */
    put("proc/meminfo", "MemAvailable: 18446744073709551615 kB\n");
    EXPECT(fdt_mem_available_in(mdir) == SIZE_MAX);
    clear_root();
    /* no MemAvailable line (kernels before 3.14): the free pages */
    put("proc/meminfo", "MemTotal: 16000000 kB\nMemFree: 5 kB\n");
    size_t got = fdt_mem_available_in(mdir);
    EXPECTF(got != 5 * 1024 && near_free_pages(got), "%zu bytes", got);
    clear_root();
    /* no file at all */
    got = fdt_mem_available_in(mdir);
    EXPECTF(near_free_pages(got), "%zu bytes", got);

    /* cgroup v2: the room under the process's cgroup's limit, its usage
     * less the file pages it can drop: 1,000,000 - 400,000 + 50,000 */
    put("proc/meminfo", "MemAvailable: 1000000 kB\n");
    put("proc/self/cgroup", "0::/a/b\n");
    put("sys/fs/cgroup/a/b/memory.max", "1000000\n");
    put("sys/fs/cgroup/a/b/memory.current", "400000\n");
    put("sys/fs/cgroup/a/b/memory.stat", "anon 350000\ninactive_file 50000\nfile 60000\n");
    EXPECT(fdt_mem_available_in(mdir) == 650000);
    /* a parent's limit with less room left decides */
    put("sys/fs/cgroup/a/memory.max", "500000\n");
    put("sys/fs/cgroup/a/memory.current", "480000\n");
    EXPECT(fdt_mem_available_in(mdir) == 20000);
    clear_root();
    /* no limit ("max"): MemAvailable */
    put("proc/meminfo", "MemAvailable: 1000 kB\n");
    put("proc/self/cgroup", "0::/a\n");
    put("sys/fs/cgroup/a/memory.max", "max\n");
    put("sys/fs/cgroup/a/memory.current", "400000\n");
    EXPECT(fdt_mem_available_in(mdir) == 1000 * 1024);
    clear_root();
    /* inside a cgroup namespace ("0::/"): the mount's top files */
    put("proc/meminfo", "MemAvailable: 1000 kB\n");
    put("proc/self/cgroup", "0::/\n");
    put("sys/fs/cgroup/memory.max", "123456\n");
    put("sys/fs/cgroup/memory.current", "23456\n");
    EXPECT(fdt_mem_available_in(mdir) == 100000);
    /* usage past the limit: only the file pages are left */
    put("sys/fs/cgroup/memory.stat", "inactive_file 99\n");
    put("sys/fs/cgroup/memory.current", "200000\n");
    EXPECT(fdt_mem_available_in(mdir) == 99);
    clear_root();
    /* cgroup v1 (a hybrid system lists both): the memory controller's
     * files, its total_inactive_file (inactive_file is the cgroup's own) */
    put("proc/meminfo", "MemAvailable: 1000000 kB\n");
    put("proc/self/cgroup", "5:cpu,cpuacct:/q\n4:memory:/x\n0::/\n");
    put("sys/fs/cgroup/memory/x/memory.limit_in_bytes", "3000000\n");
    put("sys/fs/cgroup/memory/x/memory.usage_in_bytes", "1000000\n");
    put("sys/fs/cgroup/memory/x/memory.stat", "inactive_file 99999\ntotal_inactive_file 7\n");
    put("sys/fs/cgroup/memory.max", "1\n"); /* the v2 files are not the memory's */
    put("sys/fs/cgroup/memory.current", "0\n");
    EXPECT(fdt_mem_available_in(mdir) == 2000007);
    clear_root();
    CHECK(rmdir(mdir) == 0);

    /* the real one: some memory, and what fdt_mem_available says */
    size_t real = fdt_mem_available();
    EXPECT(real > 0 && real != SIZE_MAX);

    /* fdt_mem_fits: small blocks always; a block past the memory
     * available is refused by fdt_mem_alloc_huge and fdt_grow, though
     * malloc would hand it out (Linux overcommits up to about the RAM,
     * and kills the process when the pages run out) */
    EXPECT(fdt_mem_fits(FDT_MEM_CHECKED - 1));
    size_t past = real + real / 16 + FDT_MEM_CHECKED;
    EXPECT(!fdt_mem_fits(past));
    void *p = fdt_mem_alloc_huge(past, 1, 0);
    EXPECT(p == NULL);
    free(p);
    char *g = NULL;
    size_t cap = 0;
    EXPECT(fdt_grow(&g, &cap, past, 1) == FDT_ENOMEM && g == NULL && cap == 0);
    EXPECT(fdt_grow(&g, &cap, 1000, 1) == 0 && g && cap >= 1000);
    free(g);
}

/* fdt_mem_alloc_huge under 4 MB (its pages mapped at once) and over,
 * zeroed when asked; fdt_mem_realloc_huge keeps the old block's bytes
 * (all of them when growing, the first new_bytes when shrinking), starts
 * from NULL, and the result is freed with free(). */
static void test_alloc_realloc(void)
{
    static const size_t sizes[] = {1, 4095, 4096, 100000, (size_t)3 << 20, (size_t)5 << 20};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        size_t n = sizes[k];
        unsigned char *z = fdt_mem_alloc_huge(n, 1, 1);
        EXPECTF(z != NULL, "alloc %zu", n);
        size_t nz = 0;
        for (size_t i = 0; z && i < n; i++)
            nz += z[i] != 0;
        EXPECTF(nz == 0, "%zu of %zu zeroed bytes not zero", nz, n);
        free(z);
        unsigned char *a = fdt_mem_realloc_huge(NULL, 0, n);
        EXPECTF(a != NULL, "realloc from NULL, %zu", n);
        if (!a)
            continue;
        for (size_t i = 0; i < n; i++)
            a[i] = (unsigned char)(i * 13 + 1);
        unsigned char *b = fdt_mem_realloc_huge(a, n, 2 * n + 7); /* grown */
        EXPECTF(b != NULL, "grow %zu", n);
        size_t bad = 0;
        for (size_t i = 0; b && i < n; i++)
            bad += b[i] != (unsigned char)(i * 13 + 1);
        EXPECTF(bad == 0, "grow %zu: %zu bytes lost", n, bad);
        unsigned char *c = b ? fdt_mem_realloc_huge(b, 2 * n + 7, n / 2 + 1) : NULL; /* shrunk */
        for (size_t i = 0; c && i < n / 2 + 1; i++)
            bad += c[i] != (unsigned char)(i * 13 + 1);
        EXPECTF(c && bad == 0, "shrink %zu: %zu bytes lost", n, bad);
        free(c);
    }
}

int main(void)
{
    test_available();
    test_alloc_realloc();

    /* Harmless anywhere: NULL, tiny, unaligned. */
    fdt_mem_advise_huge(NULL, 1 << 30);
    char small[100];
    fdt_mem_advise_huge(small, sizeof small);
    memset(small, 1, sizeof small);

    size_t bytes = (size_t)16 << 20;
    /* mmap, not malloc: meson's MALLOC_PERTURB_ makes malloc write the
     * memory it returns, and a page written before the hint stays small */
    unsigned char *p = mmap(NULL, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    unsigned char *ctl = mmap(NULL, bytes, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
    EXPECTF(p != MAP_FAILED && ctl != MAP_FAILED, "mmap");
    if (p == MAP_FAILED || ctl == MAP_FAILED)
        return 1;
    fdt_mem_advise_huge(p + 3, bytes - 3);
    uintptr_t clo = ((uintptr_t)ctl + (2u << 20) - 1) & ~(uintptr_t)((2u << 20) - 1);
    (void)madvise((void *)clo, 8u << 20, MADV_HUGEPAGE);
    for (size_t i = 0; i < bytes; i++) {
        p[i] = (unsigned char)(i * 7);
        ctl[i] = (unsigned char)i;
    }
    size_t bad = 0;
    for (size_t i = 0; i < bytes; i++)
        bad += p[i] != (unsigned char)(i * 7);
    EXPECTF(bad == 0, "%zu bytes changed", bad);
    long kb = huge_kb(p, bytes), ckb = huge_kb(ctl, bytes);
    if (thp_on_request() && kb >= 0 && ckb >= 2048) {
        /* The kernel granted the control's request: it must grant ours
         * (16 MB hold at least six aligned 2 MB pages). */
        EXPECTF(kb >= 2048, "no huge page over an advised 16 MB range (%ld kB; control %ld kB)",
              kb, ckb);
        printf("mem: %ld kB of huge pages over 16 MB advised (control %ld kB)\n", kb, ckb);
    } else {
        printf("mem: no huge pages granted on request here (control %ld kB); usability only\n",
               ckb);
    }
    munmap(p, bytes);
    munmap(ctl, bytes);
    return test_report("test_mem");
}
