/*
 * Large allocations and the kernel's huge pages. The apex search reads
 * the coordinates, the kd-tree and the float blocks all over tens of MB
 * (1M points: 24 MB of coordinates alone), and with 4 KB pages nearly
 * every node or leaf it visits is on a page the TLB does not hold; 2 MB
 * pages cover the same data with a few dozen entries. Linux gives them to
 * anonymous memory marked MADV_HUGEPAGE where transparent huge pages are
 * set to "madvise" (Debian's default) or "always".
 */
#ifndef FDT_MEM_H
#define FDT_MEM_H

#include <stddef.h>

/* Asks for huge pages over the 2 MB-aligned part of [p, p + bytes) when
 * it spans at least 4 MB; a hint only (no error, no effect elsewhere).
 * Best called before the memory is first written, so that the first
 * touch already gets a huge page. */
void fdt_mem_advise_huge(void *p, size_t bytes);

/* n elements of `size` bytes (zeroed when `zero`: calloc), huge pages
 * asked for before the first write (fdt_mem_advise_huge), or under 4 MB
 * every page mapped at once: for arrays written at once (every page of
 * them), where each 4 KB fault costs (a trap on a host that hands pages
 * over late, bench/NOTES.md entries 128, 134) and random reads and adds
 * miss the TLB. NULL when out of memory, past fdt_mem_fits or when n *
 * size overflows. */
void *fdt_mem_alloc_huge(size_t n, size_t size, int zero);

/* realloc for such arrays: the block p (NULL: none), whose first
 * old_bytes are kept, moved into a new block of new_bytes from
 * fdt_mem_alloc_huge, so that its pages are asked for before the copy
 * writes them (realloc's copy of a grown block faulted it in 4 KB at a
 * time, before any advice could apply: bench/NOTES.md entry 134). NULL,
 * p untouched, when out of memory. */
void *fdt_mem_realloc_huge(void *p, size_t old_bytes, size_t new_bytes);

/* Grows the array *pp of elements of `size` bytes, holding *cap, to hold
 * at least need (doubling from 64): 0, or FDT_ENOMEM (*pp and *cap
 * unchanged; also when the added bytes fail fdt_mem_fits). */
int fdt_grow(void *pp, size_t *cap, size_t need, size_t size);

/* The memory the system can still give without swapping, in bytes: the
 * kernel's MemAvailable (free memory plus the page cache it can drop),
 * else the free pages, else SIZE_MAX (unknown: no limit), and no more
 * than the room under the memory limits of the process's cgroup and the
 * cgroups above it (v1 or v2; a container's limit, which MemAvailable
 * does not show). */
size_t fdt_mem_available(void);
/* The same with the kernel's files under the directory root ("" for the
 * system's own: root/proc/meminfo, root/proc/self/cgroup,
 * root/sys/fs/cgroup/...): lets tests/test_mem.c give it files of its own. */
size_t fdt_mem_available_in(const char *root);

/*
 * Whether a block of `bytes` may be taken: a block under FDT_MEM_CHECKED
 * always, a larger one only within fdt_mem_available(). Past what the
 * system (or the cgroup) can give, the pages would be taken from other
 * programs by swapping, or the kernel would kill the run (a Delaunay
 * mesh can be quadratic in the points: 50,000 on a line and 50,000 on a
 * circle around it have 2.5e9 tets); refusing the block makes the run
 * fail with FDT_ENOMEM and a message instead. fdt_mem_alloc_huge,
 * fdt_mem_realloc_huge and fdt_grow ask it; so does any other growth of
 * an array that scales with the tets. A failure never changes a result:
 * the run stops.
 */
#define FDT_MEM_CHECKED ((size_t)64 << 20)
int fdt_mem_fits(size_t bytes);

#endif
