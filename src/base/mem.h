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
 * miss the TLB. NULL when out of memory or n * size overflows. */
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
 * unchanged). */
int fdt_grow(void *pp, size_t *cap, size_t need, size_t size);

/* The memory the system can still give without swapping, in bytes: the
 * kernel's MemAvailable (free memory plus the page cache it can drop),
 * else the free pages, else SIZE_MAX (unknown: no limit). For choices
 * that may trade memory for speed (the mesh of every point of an explicit
 * --mode, src/par/parallel.c; an MPI rank's replica) only, never for
 * correctness. */
size_t fdt_mem_available(void);
/* The same with the kernel's file at meminfo (fdt_mem_available passes
 * "/proc/meminfo"): lets tests/test_mem.c feed it a file of its own. */
size_t fdt_mem_available_at(const char *meminfo);

#endif
