/* Input validation, duplicate merging and power-of-two scaling. */
#include "geom/prepare.h"

#include "base/mem.h"
#include "base/spawn.h"

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "base/bits.h"

/* Bit pattern of a coordinate with -0 folded onto +0, so that the two
 * zeros, which every predicate treats as equal, merge as duplicates. */
static uint64_t coord_bits(double x)
{
    uint64_t u;
    if (x == 0.0)
        x = 0.0;
    memcpy(&u, &x, sizeof u);
    return u;
}

static uint64_t point_hash(const double *q)
{
    uint64_t h = coord_bits(q[0]) * 0x9E3779B97F4A7C15ull;
    h ^= coord_bits(q[1]) + 0x632BE59BD9B4E019ull + (h << 6) + (h >> 2);
    h ^= coord_bits(q[2]) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
    h ^= h >> 31;
    h *= 0xBF58476D1CE4E5B9ull;
    return h ^ (h >> 29);
}

static int same_point(const double *p, const double *q)
{
    return p[0] == q[0] && p[1] == q[1] && p[2] == q[2];
}

void fdt_prepared_free(fdt_prepared *pr)
{
    if (!pr->p_borrowed)
        free(pr->p);
    pr->p = NULL;
    free(pr->orig);
    free(pr->dupmap);
    memset(pr, 0, sizeof *pr);
}

/*
 * Chooses k so that max|x| * 2^k lies in [0.5, 1) without pushing the
 * smallest nonzero |x| below the normal range (where multiplication by a
 * power of two would round and move points).
 */
static int choose_scale(double maxabs, double minabs)
{
    int emax, emin;
    if (maxabs == 0.0)
        return 0;
    (void)frexp(maxabs, &emax);
    (void)frexp(minabs, &emin);
    int k = -emax;
    /* minabs * 2^k must stay >= 2^-1021 (DBL_MIN is 2^-1022; one bit of
     * slack for the differences the filters form). */
    if (emin - 1 + k < -1021)
        k = -1021 - (emin - 1);
    /* Never scale up so far that maxabs overflows (cannot happen with the
     * clamp above since emax >= emin, but keep the bound explicit). */
    if (emax + k > 1023)
        k = 1023 - emax;
    return k;
}

/* ---- the merge on several threads -----------------------------------------
 *
 * The same result as the loop in fdt_prepare, bit for bit: vertex numbers
 * in order of first occurrence, each class merged into its first input
 * index. Phases, each run by T workers on their slice of the input (the
 * caller is worker 0) and joined before the next, so pthread_create and
 * pthread_join order every phase's writes before the next phase's reads:
 *   A. the coordinate check and extremes, and the insertion of every point
 *      into one shared table of input indices; the table slot of point i
 *      is noted in dupmap[i];
 *   B. dupmap[i] = the index its slot holds (the least index of i's
 *      class), and each slice's count of first occurrences;
 *   C. each slice's first occurrences scaled into p and orig, from the
 *      slice's offset (the counts of the slices before it).
 */
#define PREP_SLICES_MAX 64
#define PREP_EMPTY UINT32_MAX

typedef struct prep_slice {
    double maxabs, minabs;
    size_t bad; /* first non-finite point of the slice, or SIZE_MAX */
    int badk;
    size_t firsts, m0;
} prep_slice;

typedef struct prep_job {
    const double *xyz;
    size_t n, cap;
    int T, phase;
    /* Input indices; PREP_EMPTY in a free slot. A slot goes from empty to
     * an index once (compare-exchange) and then only to smaller indices of
     * the same point (compare-exchange in a loop), so every point of a
     * class probes the same slots and finds the class where the first of
     * them put it, and after phase A the slot holds the class's least
     * index. relaxed: a slot publishes nothing but its own value; the
     * coordinates it leads to were written before the workers started and
     * are only read, and phase B reads the slots after pthread_join. */
    _Atomic uint32_t *slots;
    fdt_prepared *pr;
    double p2k;
    int k;
    prep_slice sl[PREP_SLICES_MAX];
} prep_job;

typedef struct prep_arg {
    prep_job *j;
    int t;
} prep_arg;

static void prep_insert(prep_job *j, size_t i, uint32_t *pos)
{
    const double *q = j->xyz + 3 * i;
    size_t h = (size_t)point_hash(q) & (j->cap - 1);
    for (;;) {
        uint32_t s = atomic_load_explicit(&j->slots[h], memory_order_relaxed);
        if (s == PREP_EMPTY &&
            atomic_compare_exchange_strong_explicit(&j->slots[h], &s, (uint32_t)i,
                                                    memory_order_relaxed, memory_order_relaxed))
            break;
        /* s: the index in the slot (the winner's if the exchange failed) */
        if (same_point(j->xyz + 3 * (size_t)s, q)) {
            while ((uint32_t)i < s &&
                   !atomic_compare_exchange_weak_explicit(&j->slots[h], &s, (uint32_t)i,
                                                          memory_order_relaxed,
                                                          memory_order_relaxed))
                ;
            break;
        }
        h = (h + 1) & (j->cap - 1);
    }
    pos[i] = (uint32_t)h;
}

static void *prep_worker(void *arg)
{
    prep_arg *a = arg;
    prep_job *j = a->j;
    prep_slice *sl = &j->sl[a->t];
    size_t lo = j->n * (size_t)a->t / (size_t)j->T, hi = j->n * (size_t)(a->t + 1) / (size_t)j->T;
    fdt_prepared *pr = j->pr;
    /* dupmap holds slot numbers between A and B: uint32_t may alias the
     * int32_t array, and a table of up to 2^32 slots needs all 32 bits. */
    uint32_t *pos = (uint32_t *)pr->dupmap;
    if (j->phase == 0) {
        sl->maxabs = 0.0;
        sl->minabs = INFINITY;
        sl->bad = SIZE_MAX;
        for (size_t i = lo; i < hi; i++) {
            for (int k = 0; k < 3; k++) {
                double ax = fabs(j->xyz[3 * i + (size_t)k]);
                if (!(ax <= DBL_MAX) && sl->bad == SIZE_MAX) {
                    sl->bad = i;
                    sl->badk = k;
                }
                if (ax > sl->maxabs)
                    sl->maxabs = ax;
                if (ax != 0.0 && ax < sl->minabs)
                    sl->minabs = ax;
            }
            if (i + 8 < hi)
                fdt_prefetch(j->slots + ((size_t)point_hash(j->xyz + 3 * (i + 8)) & (j->cap - 1)));
            prep_insert(j, i, pos);
        }
    } else if (j->phase == 1) {
        size_t c = 0;
        for (size_t i = lo; i < hi; i++) {
            uint32_t first = atomic_load_explicit(&j->slots[pos[i]], memory_order_relaxed);
            pr->dupmap[i] = (fdt_vid)first;
            c += first == (uint32_t)i;
        }
        sl->firsts = c;
    } else {
        size_t m = sl->m0;
        for (size_t i = lo; i < hi; i++) {
            if (pr->dupmap[i] != (fdt_vid)i)
                continue;
            const double *q = j->xyz + 3 * i;
            for (int c = 0; c < 3; c++)
                pr->p[3 * m + (size_t)c] = j->p2k != 0.0 ? q[c] * j->p2k : ldexp(q[c], j->k);
            pr->orig[m] = (fdt_vid)i;
            m++;
        }
    }
    return NULL;
}

/* Runs phase `phase` on the T workers; a worker whose thread cannot be
 * created runs on the caller after the others (phase A's inserts are
 * safe in any order, B and C only touch the slice's own entries). */
static void prep_phase(prep_job *j, int phase, prep_arg *args)
{
    pthread_t tid[PREP_SLICES_MAX];
    int made[PREP_SLICES_MAX];
    j->phase = phase;
    for (int t = 1; t < j->T; t++)
        made[t] = fdt_spawn(&tid[t], 0, prep_worker, &args[t]) == 0;
    prep_worker(&args[0]);
    for (int t = 1; t < j->T; t++) {
        if (made[t])
            pthread_join(tid[t], NULL);
        else
            prep_worker(&args[t]);
    }
}

/* fdt_prepare's merge and scaling on T > 1 threads (pr's arrays are
 * allocated, slots is cap entries of PREP_EMPTY). */
static int prepare_threads(const double *xyz, size_t n, int T, fdt_prepared *pr,
                           uint32_t *slots, size_t cap, char *diag, size_t dlen)
{
    prep_job j;
    memset(&j, 0, sizeof j);
    j.xyz = xyz;
    j.n = n;
    j.cap = cap;
    j.T = T;
    j.pr = pr;
    /* _Atomic uint32_t has uint32_t's size and representation here
     * (checked below), so the table is filled with memset as before. */
    _Static_assert(sizeof(_Atomic uint32_t) == sizeof(uint32_t), "atomic slot size");
    j.slots = (_Atomic uint32_t *)slots;
    prep_arg args[PREP_SLICES_MAX];
    for (int t = 0; t < T; t++) {
        args[t].j = &j;
        args[t].t = t;
    }
    prep_phase(&j, 0, args);
    double maxabs = 0.0, minabs = INFINITY;
    for (int t = 0; t < T; t++) {
        if (j.sl[t].bad != SIZE_MAX) {
            size_t i = j.sl[t].bad;
            int k = j.sl[t].badk;
            snprintf(diag, dlen, "point %zu has a non-finite %c coordinate (%g)", i, "xyz"[k],
                     xyz[3 * i + (size_t)k]);
            return FDT_ERANGE;
        }
        maxabs = j.sl[t].maxabs > maxabs ? j.sl[t].maxabs : maxabs;
        minabs = j.sl[t].minabs < minabs ? j.sl[t].minabs : minabs;
    }
    prep_phase(&j, 1, args);
    size_t m = 0;
    for (int t = 0; t < T; t++) {
        j.sl[t].m0 = m;
        m += j.sl[t].firsts;
    }
    j.k = choose_scale(maxabs, minabs);
    j.p2k = j.k >= -1022 && j.k <= 1023 ? fdt_pow2i(j.k) : 0.0;
    if (pr->p_borrowed && m != n) {
        /* In place with duplicates: slice t writes from its m0, below its
         * own points, over slice t - 1's, which must be read first: the
         * slices in order, on this thread, as the serial merge would. */
        j.phase = 2;
        for (int t = 0; t < T; t++)
            prep_worker(&args[t]);
    } else {
        prep_phase(&j, 2, args); /* in place with no duplicate: each over its own points */
    }
    pr->scale_exp = j.k;
    pr->m = m;
    pr->ndup = n - m;
    return FDT_OK;
}

size_t fdt_prepare_merge_slots(size_t n)
{
    size_t cap = 16;
    while (3 * cap < 4 * n)
        cap <<= 1;
    return cap;
}

/* pr's arrays for n points and the merge's table of *cap empty slots
 * (all bits set), open addressing (fdt_prepare_merge_slots). On failure
 * the caller frees what was allocated (fdt_prepared_free, free(*slots)). */
static int prep_alloc(fdt_prepared *pr, size_t n, uint32_t **slots, size_t *cap)
{
    size_t n1 = n ? n : 1;
    /* every array fresh and written at once: huge pages (a 4 KB fault is
     * a trap on some hosts, bench/NOTES.md entry 128) */
    pr->dupmap = fdt_mem_alloc_huge(n1, sizeof *pr->dupmap, 0);
    if (!pr->p_borrowed)
        pr->p = fdt_mem_alloc_huge(n1 * 3, sizeof *pr->p, 0);
    pr->orig = fdt_mem_alloc_huge(n1, sizeof *pr->orig, 0);
    *cap = fdt_prepare_merge_slots(n);
    pr->merge_bytes = *cap * sizeof **slots;
    *slots = fdt_mem_alloc_huge(*cap, sizeof **slots, 0);
    if (!pr->dupmap || !pr->p || !pr->orig || !*slots)
        return FDT_ENOMEM;
    memset(*slots, 0xff, *cap * sizeof **slots);
    return FDT_OK;
}

/* Threads for the merge: one below 64k points, where starting threads
 * costs more than it saves. */
static int prepare_threads_for(size_t n, int threads)
{
    int T = threads > PREP_SLICES_MAX ? PREP_SLICES_MAX : threads;
    return n < ((size_t)1 << 16) || T < 1 ? 1 : T;
}

static int prepare_any(const double *xyz, double *into, size_t n, int threads,
                       fdt_prepared *pr, char *diag, size_t dlen)
{
    int err = FDT_ENOMEM;
    uint32_t *slots = NULL;
    memset(pr, 0, sizeof *pr);
    if (into) {
        pr->p = into;
        pr->p_borrowed = 1;
    }
    if (n > (size_t)FDT_VID_MAX) {
        snprintf(diag, dlen, "%zu points: more than the %d a vertex id holds",
                 n, FDT_VID_MAX);
        return FDT_ETOOBIG;
    }
    int T = prepare_threads_for(n, threads);
    if (T > 1) {
        size_t cap;
        if (prep_alloc(pr, n, &slots, &cap) != FDT_OK)
            goto fail;
        err = prepare_threads(xyz, n, T, pr, slots, cap, diag, dlen);
        free(slots);
        if (err != FDT_OK)
            fdt_prepared_free(pr);
        return err;
    }
    double maxabs = 0.0, minabs = INFINITY;
    for (size_t i = 0; i < n; i++) {
        for (int k = 0; k < 3; k++) {
            double x = xyz[3 * i + k];
            if (!isfinite(x)) {
                snprintf(diag, dlen, "point %zu has a non-finite %c coordinate (%g)",
                         i, "xyz"[k], x);
                return FDT_ERANGE;
            }
            double ax = fabs(x);
            if (ax > maxabs)
                maxabs = ax;
            if (ax != 0.0 && ax < minabs)
                minabs = ax;
        }
    }
    /* slots hold distinct-point numbers here */
    size_t cap;
    if (prep_alloc(pr, n, &slots, &cap) != FDT_OK)
        goto fail;
    int k = choose_scale(maxabs, minabs);
    pr->scale_exp = k;
    /* choose_scale keeps every nonzero scaled coordinate a normal double,
     * so multiplying by 2^k is exact, the same as ldexp, whenever 2^k is
     * itself a normal double; the libm call was a third of this loop's
     * time (perf, 1M points). */
    double p2k = k >= -1022 && k <= 1023 ? fdt_pow2i(k) : 0.0;
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        /* Read before any write: in place (into), p[m] with m <= i is
         * written over the input, at or before point i, never after. */
        const double q[3] = {xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]};
        /* The table (8 MB at 1M points) is probed at random: ask for the
         * slot a few points ahead so it has arrived when needed. */
        if (i + 8 < n)
            fdt_prefetch(slots + ((size_t)point_hash(xyz + 3 * (i + 8)) & (cap - 1)));
        size_t h = (size_t)point_hash(q) & (cap - 1);
        double sq[3];
        /* Scaled copy: exact, see choose_scale. */
        for (int c = 0; c < 3; c++)
            sq[c] = p2k != 0.0 ? q[c] * p2k : ldexp(q[c], k);
        for (;;) {
            uint32_t s = slots[h];
            if (s == UINT32_MAX) {
                slots[h] = (uint32_t)m;
                memcpy(pr->p + 3 * m, sq, sizeof sq);
                pr->orig[m] = (fdt_vid)i;
                pr->dupmap[i] = (fdt_vid)i;
                m++;
                break;
            }
            /* Compared scaled (the input's copy may be overwritten in
             * place): scaling by 2^k is exact and one-to-one on these
             * values, and -0 == +0 either way. */
            if (same_point(pr->p + 3 * (size_t)s, sq)) {
                pr->dupmap[i] = pr->orig[s];
                pr->ndup++;
                break;
            }
            h = (h + 1) & (cap - 1);
        }
    }
    pr->m = m;
    free(slots);
    return FDT_OK;
fail:
    free(slots);
    fdt_prepared_free(pr);
    snprintf(diag, dlen, "out of memory preparing %zu points", n);
    return err;
}

int fdt_prepare(const double *xyz, size_t n, int threads, fdt_prepared *pr, char *diag,
                size_t dlen)
{
    return prepare_any(xyz, NULL, n, threads, pr, diag, dlen);
}

int fdt_prepare_inplace(double *xyz, size_t n, int threads, fdt_prepared *pr, char *diag,
                        size_t dlen)
{
    return prepare_any(xyz, xyz, n, threads, pr, diag, dlen);
}

int fdt_prepare_scale_exp(double maxabs, double minabs)
{
    return choose_scale(maxabs, minabs);
}
