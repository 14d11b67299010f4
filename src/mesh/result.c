/* Result accessors, canonical order and the canonical hash. */
#include "mesh/result.h"

#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "base/bits.h"
#include "base/dtoa.h"
#include "base/sethash.h"
#include "base/spawn.h"

void fdt_result_free(fdt_result **r)
{
    if (!r || !*r)
        return;
    free((*r)->tets);
    free((*r)->nbrs);
    free((*r)->hull);
    free((*r)->dupmap);
    free((*r)->tet_off);
    free((*r)->hull_off);
    free((*r)->tstats);
    fdt_result_drop_derived(*r);
    free(*r);
    *r = NULL;
}

size_t fdt_result_num_tets(const fdt_result *r) { return r ? r->ntets : 0; }
const fdt_vid *fdt_result_tets(const fdt_result *r) { return r ? r->tets : NULL; }
const fdt_tid *fdt_result_neighbors(const fdt_result *r) { return r ? r->nbrs : NULL; }
size_t fdt_result_num_hull_faces(const fdt_result *r) { return r ? r->nhull : 0; }
const fdt_vid *fdt_result_hull_faces(const fdt_result *r) { return r ? r->hull : NULL; }
const fdt_vid *fdt_result_duplicate_map(const fdt_result *r) { return r ? r->dupmap : NULL; }
const int8_t *fdt_result_tet_offsets(const fdt_result *r) { return r ? r->tet_off : NULL; }
const int8_t *fdt_result_hull_offsets(const fdt_result *r) { return r ? r->hull_off : NULL; }

unsigned fdt_result_periodic(const fdt_result *r, double box[6])
{
    if (!r || !r->periodic)
        return 0;
    if (box)
        memcpy(box, r->pbox, sizeof r->pbox);
    return r->periodic;
}
size_t fdt_result_num_duplicates(const fdt_result *r) { return r ? r->ndup : 0; }

/* The sizes of fdt_stats and fdt_thread_stats this library fills
 * (include/frontdt.h, ABI): this release's; earlier releases' join here
 * when a field is added. */
/* This release's fdt_stats, 0.1's (which ended before final_tets) and the
 * first release's, which ended before the memory fields (include/frontdt.h,
 * ABI). */
static int stats_size_known(size_t size)
{
    return size == sizeof(fdt_stats) || size == offsetof(fdt_stats, mem_points) ||
           size == offsetof(fdt_stats, final_tets) ||
           size == offsetof(fdt_stats, ins_conflict_tests) ||
           size == offsetof(fdt_stats, sweep_parts) ||
           size == offsetof(fdt_stats, cell_batches) ||
           size == offsetof(fdt_stats, periodic_images);
}

static int thread_stats_size_known(size_t size)
{
    return size == sizeof(fdt_thread_stats) || size == offsetof(fdt_thread_stats, final_tets);
}

int fdt_result_stats_sized(const fdt_result *r, fdt_stats *st, size_t struct_size)
{
    if (!r || !st || !stats_size_known(struct_size))
        return FDT_EINVAL;
    fdt_stats all = r->stats;
    all.struct_size = struct_size;
    memcpy(st, &all, struct_size);
    return FDT_OK;
}

int fdt_result_thread_stats_sized(const fdt_result *r, int thread, fdt_thread_stats *ts,
                                  size_t struct_size)
{
    if (!r || !ts || thread < 0 || thread >= r->stats.threads ||
        !thread_stats_size_known(struct_size))
        return FDT_EINVAL;
    fdt_thread_stats all;
    if (r->tstats) {
        all = r->tstats[thread];
    } else {
        /* Serial: the one thread did everything. */
        memset(&all, 0, sizeof all);
        all.points = r->stats.vertices;
        all.tets = r->stats.tets;
        all.hull_faces = r->stats.hull_faces;
        all.faces_advanced = r->stats.faces_advanced;
        all.max_front = r->stats.max_front;
        all.core = -1;
    }
    all.struct_size = struct_size;
    memcpy(ts, &all, struct_size);
    return FDT_OK;
}

/*
 * Puts a tet's ids in the form (a, b, c, d) with a < b < c < d if that is
 * an even permutation of the original, else (a, b, d, c): the canonical
 * key is then (t0, t1, min(t2,t3), max(t2,t3)) and the orientation is
 * kept. perm receives, for each new slot, the old slot (for neighbours).
 */
static void orient_sorted(fdt_vid *t, int perm[4])
{
    int p[4] = {0, 1, 2, 3};
    int odd = 0;
    for (int i = 1; i < 4; i++)
        for (int j = i; j > 0 && t[p[j - 1]] > t[p[j]]; j--) {
            int x = p[j];
            p[j] = p[j - 1];
            p[j - 1] = x;
            odd ^= 1;
        }
    if (odd) {
        int x = p[2];
        p[2] = p[3];
        p[3] = x;
    }
    fdt_vid o[4] = {t[0], t[1], t[2], t[3]};
    for (int i = 0; i < 4; i++) {
        t[i] = o[p[i]];
        perm[i] = p[i];
    }
}

/*
 * orient_sorted without the permutation, for results without neighbours:
 * a sorting network of five compare-exchanges whose swaps are counted for
 * the parity, as selects rather than branches (the insertion sort's
 * branches, a coin toss each, made this loop a third of the sort).
 */
static void orient_sorted_fast(fdt_vid *t)
{
    fdt_vid v0 = t[0], v1 = t[1], v2 = t[2], v3 = t[3], x;
    int odd = 0, c;
#define CSWAP(p, q)                                                            \
    c = p > q;                                                                 \
    odd ^= c;                                                                  \
    x = c ? q : p;                                                             \
    q = c ? p : q;                                                             \
    p = x;
    CSWAP(v0, v1)
    CSWAP(v2, v3)
    CSWAP(v0, v2)
    CSWAP(v1, v3)
    CSWAP(v1, v2)
#undef CSWAP
    t[0] = v0;
    t[1] = v1;
    t[2] = odd ? v3 : v2;
    t[3] = odd ? v2 : v3;
}

static void key_of(const fdt_vid *t, uint32_t k[4])
{
    k[0] = (uint32_t)t[0];
    k[1] = (uint32_t)t[1];
    k[2] = (uint32_t)(t[2] < t[3] ? t[2] : t[3]);
    k[3] = (uint32_t)(t[2] < t[3] ? t[3] : t[2]);
}

/* Records of the canonical sort: a tet in orient_sorted form (4 words:
 * the key is key_of of it), or with neighbours a key and the tet's old
 * index (6 words: key_of of a key is the key itself). */
#define REC_MAX 6
#define RADIX_BITS 11

/* The canonical hash (fdt_result_hash): FNV-1a over the text of a .tets
 * file's tet lines, fed one bucket of sorted records at a time. */
typedef struct text_hash {
    uint64_t h;
} text_hash;

/* Two decimal digits of 0..99, for put_u32. */
static const char digits2[] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

/* x in decimal at buf; returns the length. Two digits a step: the hash's
 * conversions were a third of its time with one division a digit. */
static size_t put_u32(char *buf, uint32_t x)
{
    /* The length from the bit length: floor(log10(2^bits)) digits or
     * one more (1233 / 4096 is log10(2) rounded up, exact enough below
     * 2^32); a division a digit made a chain, nine comparisons cost more. */
    static const uint32_t pow10[10] = {1u, 10u, 100u, 1000u, 10000u, 100000u,
                                       1000000u, 10000000u, 100000000u, 1000000000u};
    unsigned bl = 32u - (unsigned)fdt_clz32(x | 1u), d = (bl * 1233u) >> 12;
    size_t len = d + (x >= pow10[d]) + (x == 0);
    char *p = buf + len;
    while (x >= 100) {
        uint32_t q = x / 100, r = x - 100 * q;
        p -= 2;
        memcpy(p, digits2 + 2 * r, 2);
        x = q;
    }
    if (x >= 10) {
        p -= 2;
        memcpy(p, digits2 + 2 * x, 2);
    } else {
        *--p = (char)('0' + x);
    }
    return len;
}

/* The .tets line of record a (4 words) at buf; returns its length, at
 * most TEXT_LINE_MAX. */
#define TEXT_LINE_MAX 44
static size_t format_record(char *buf, const uint32_t *a)
{
    uint32_t k[4];
    key_of((const fdt_vid *)a, k);
    size_t len = 0;
    for (int j = 0; j < 4; j++) {
        len += put_u32(buf + len, k[j]);
        buf[len++] = j == 3 ? '\n' : ' ';
    }
    return len;
}

static void hash_text(text_hash *th, const char *buf, size_t len)
{
    uint64_t h = th->h;
    /* FNV-1a is one multiply after another: its chain, about four cycles
     * a byte, is the floor of the hash. */
    for (size_t j = 0; j < len; j++) {
        h ^= (unsigned char)buf[j];
        h *= 1099511628211ull;
    }
    th->h = h;
}

static void hash_records(text_hash *th, const uint32_t *a, size_t n)
{
    char buf[TEXT_LINE_MAX];
    for (size_t i = 0; i < n; i++)
        hash_text(th, buf, format_record(buf, a + 4 * i));
}

/* One counting-sort pass over n records of `stride` words from src to dst
 * by bits [shift, shift + RADIX_BITS) of the first word. */
static void radix_pass(const uint32_t *src, uint32_t *dst, size_t n, int stride, int shift,
                       size_t *cnt)
{
    size_t bytes = (size_t)stride * sizeof *src;
    memset(cnt, 0, ((size_t)1 << RADIX_BITS) * sizeof *cnt);
    for (size_t i = 0; i < n; i++)
        cnt[(src[stride * i] >> shift) & ((1u << RADIX_BITS) - 1)]++;
    size_t sum = 0;
    for (size_t d = 0; d < ((size_t)1 << RADIX_BITS); d++) {
        size_t c = cnt[d];
        cnt[d] = sum;
        sum += c;
    }
    for (size_t i = 0; i < n; i++)
        memcpy(dst + stride * cnt[(src[stride * i] >> shift) & ((1u << RADIX_BITS) - 1)]++,
               src + stride * i, bytes);
}

/* The rest of a 4-word record's key after its first word: t1 and
 * min(t2, t3) packed into one 64-bit number (*hi), max(t2, t3) for the
 * ties (*lo); comparing (hi, lo) is comparing the key. */
static inline void key_rest(const uint32_t *t, uint64_t *hi, uint32_t *lo)
{
    uint32_t mn = t[2] < t[3] ? t[2] : t[3], mx = t[2] < t[3] ? t[3] : t[2];
    *hi = ((uint64_t)t[1] << 32) | mn;
    *lo = mx;
}

/* Whether record x's key is below record y's, for two records with the
 * same first word: for 4-word records key_rest is the rest of the key,
 * and for 6-word ones (a key and an index) it is the key's words 1-3. */
static inline int rest_less(const uint32_t *x, const uint32_t *y)
{
    uint64_t xh, yh;
    uint32_t xl, yl;
    key_rest(x, &xh, &xl);
    key_rest(y, &yh, &yl);
    return xh < yh || (xh == yh && xl < yl);
}

/* The g records at a (one group) in key order by insertion; stable. For
 * short runs only: quadratic in g. */
static inline void insert_run(uint32_t *a, size_t g, int stride)
{
    size_t bytes = (size_t)stride * sizeof *a;
    for (size_t x = 1; x < g; x++) {
        uint32_t r[REC_MAX];
        memcpy(r, a + stride * x, bytes);
        size_t y = x;
        for (; y > 0 && rest_less(r, a + stride * (y - 1)); y--)
            memcpy(a + stride * y, a + stride * (y - 1), bytes);
        memcpy(a + stride * y, r, bytes);
    }
}

/* Runs [lo, mid) and [mid, hi) of src merged into dst; on equal keys the
 * left run's record first, so the merge sort is stable as the insertion
 * sort it replaces was (equal keys are the same tet twice, possibly in
 * either orientation: the output keeps their input order). */
static inline void merge_runs(const uint32_t *src, uint32_t *dst, size_t lo, size_t mid,
                              size_t hi, int stride)
{
    size_t bytes = (size_t)stride * sizeof *src, i = lo, j = mid, k = lo;
    while (i < mid && j < hi) {
        if (rest_less(src + stride * j, src + stride * i))
            memcpy(dst + stride * k++, src + stride * j++, bytes);
        else
            memcpy(dst + stride * k++, src + stride * i++, bytes);
    }
    memcpy(dst + stride * k, src + stride * i, (mid - i) * bytes);
    k += mid - i;
    memcpy(dst + stride * k, src + stride * j, (hi - j) * bytes);
}

/* Insertion-sorted runs of this many records before the merges. */
#define GROUP_RUN 32

/*
 * One large group (g records at a with the same first word) in key order:
 * insertion-sorted runs of GROUP_RUN, then bottom-up merges between a and
 * tmp (room for g records), O(g log g) and stable. A vertex can be the
 * lowest of tens of thousands of tets (a point at the centre of a sphere
 * of points: every tet; issue 16's wind-study geometry: 67,675), and the
 * insertion sort of such a group took seconds.
 */
static inline void sort_group(uint32_t *a, size_t g, int stride, uint32_t *tmp)
{
    for (size_t s = 0; s < g; s += GROUP_RUN)
        insert_run(a + stride * s, g - s < GROUP_RUN ? g - s : GROUP_RUN, stride);
    uint32_t *src = a, *dst = tmp;
    for (size_t w = GROUP_RUN; w < g; w *= 2) {
        for (size_t lo = 0; lo < g; lo += 2 * w) {
            size_t mid = g - lo < w ? g : lo + w, hi = g - lo < 2 * w ? g : lo + 2 * w;
            merge_runs(src, dst, lo, mid, hi, stride);
        }
        uint32_t *t = src;
        src = dst;
        dst = t;
    }
    if (src != a)
        memcpy(a, src, g * (size_t)stride * sizeof *a);
}

/* Records with the same first word (the lowest vertex: about seven, the
 * tets at which that vertex is lowest, for uniform points) in key order:
 * groups of at most 64 by insertion, for 4-word records on keys computed
 * once a record rather than twice a comparison; larger ones by sort_group
 * with tmp (room for n records) as its scratch. */
static void finish_groups(uint32_t *a, size_t n, int stride, uint32_t *tmp)
{
    for (size_t i = 0; i < n;) {
        size_t j = i + 1;
        while (j < n && a[stride * j] == a[stride * i])
            j++;
        size_t g = j - i;
        if (stride == 4 && g <= 64) {
            uint64_t kh[64];
            uint32_t kl[64], rec[64][4];
            for (size_t x = 0; x < g; x++) {
                uint64_t h;
                uint32_t l;
                key_rest(a + 4 * (i + x), &h, &l);
                size_t y = x;
                for (; y > 0 && (kh[y - 1] > h || (kh[y - 1] == h && kl[y - 1] > l)); y--) {
                    kh[y] = kh[y - 1];
                    kl[y] = kl[y - 1];
                    memcpy(rec[y], rec[y - 1], sizeof rec[y]);
                }
                kh[y] = h;
                kl[y] = l;
                memcpy(rec[y], a + 4 * (i + x), sizeof rec[y]);
            }
            memcpy(a + 4 * i, rec, g * sizeof rec[0]);
        } else if (g <= 64) {
            insert_run(a + stride * i, g, 6); /* stride 6: with neighbours */
        } else if (stride == 4) {
            sort_group(a + 4 * i, g, 4, tmp); /* constant strides: inlined twice */
        } else {
            sort_group(a + 6 * i, g, 6, tmp);
        }
        i = j;
    }
}

/* ---- the sort on several threads ------------------------------------------
 *
 * Phases, each run by T workers (the caller is worker 0) and joined
 * before the next, so pthread_create and pthread_join order every phase's
 * writes before the next phase's reads:
 *   A. each worker's slice of the records: orient (4-word records) and
 *      the largest first word;
 *   B. each slice's histogram of the top digit;
 *   C. each slice scattered from a to b at its own offsets (from the
 *      histograms, by the caller between B and C);
 *   D. the buckets, taken in order from a shared counter: the bits below
 *      the top digit, the vertex groups, and the hash, which only worker 0
 *      computes, bucket after bucket in key order, sorting buckets itself
 *      while the next one to hash is not ready. Workers with no bucket
 *      left to sort write the text of buckets ahead of worker 0 (at most
 *      TEXT_AHEAD of them), so that worker 0 only runs the FNV chain over
 *      it: the chain is the hash's floor (0.21 s at 1M), the formatting
 *      beside it another 0.1 s (bench/NOTES.md, entry 47), and with the
 *      hash on the critical path of phase D the other workers were idle.
 */
#define TEXT_AHEAD 32
#define NBUCKETS ((size_t)1 << RADIX_BITS)

typedef struct sort_job {
    uint32_t *a, *b;
    size_t n;
    int stride, orient, T, shift, phase;
    uint32_t *tops;        /* T: each slice's largest first word (A) */
    size_t *hist;          /* T x NBUCKETS: counts (B), then offsets (C) */
    size_t *start, *end;   /* NBUCKETS: each bucket's range in b (D) */
    text_hash *th;         /* NULL: no hash */
    /* Next bucket to sort (D). relaxed: each bucket number is handed out
     * once by the read-modify-write; nothing else is published by it. */
    atomic_size_t next;
    /* done[d] != 0 once bucket d is final in a (D). Stored with release
     * by the worker that sorted it, after the bucket's last write; worker
     * 0 and the text writers load it with acquire before reading the
     * bucket, so they read the final records. */
    atomic_uchar *done;
    /* Bucket d's text (D, with a hash): TEXT_FREE, then claimed by one
     * compare-exchange, by a text writer (TEXT_BUSY) or by worker 0, which
     * then hashes the records itself (TEXT_OWN). A writer stores
     * TEXT_READY with release after writing text[d] and tlen[d]; worker 0
     * loads the state with acquire before reading them, and frees text[d]
     * once chained. The claims are relaxed: the claim itself publishes
     * nothing, and each state's data is ordered by the READY store. */
    atomic_uchar *tstate;
    char **text;
    size_t *tlen;
    /* The bucket worker 0 hashes next: writers stay within TEXT_AHEAD of
     * it. relaxed: it only bounds how far ahead they write. */
    atomic_size_t hpos;
} sort_job;

enum { TEXT_FREE, TEXT_BUSY, TEXT_READY, TEXT_OWN };

typedef struct sort_arg {
    sort_job *j;
    int t;
} sort_arg;

/* The bits below the top digit, the groups and (from worker 0's hash
 * loop only) nothing else: bucket d made final in a. inner: NBUCKETS
 * counts of the worker's own. */
static void sort_bucket(sort_job *j, size_t d, size_t *inner)
{
    size_t lo = j->start[d], m = j->end[d] - lo, bytes = (size_t)j->stride * sizeof *j->a;
    if (m == 0)
        return;
    /* Least significant first between b and a over the bucket's range; an
     * odd number of passes leaves it in a, an even one (none included)
     * copies it there. */
    uint32_t *src = j->b + (size_t)j->stride * lo, *dst = j->a + (size_t)j->stride * lo;
    for (int sh = 0; sh < j->shift; sh += RADIX_BITS) {
        radix_pass(src, dst, m, j->stride, sh, inner);
        uint32_t *t = src;
        src = dst;
        dst = t;
    }
    if (src != j->a + (size_t)j->stride * lo)
        memcpy(j->a + (size_t)j->stride * lo, src, m * bytes);
    /* the bucket's range of b is free now: scratch for large groups */
    finish_groups(j->a + (size_t)j->stride * lo, m, j->stride, j->b + (size_t)j->stride * lo);
}

/* Worker 0: hashes every bucket from hnext on that is sorted, in order,
 * from the text a writer left or from the records; returns the first
 * bucket it could not hash yet. */
static size_t hash_ready(sort_job *j, size_t hnext)
{
    while (hnext < NBUCKETS && atomic_load_explicit(&j->done[hnext], memory_order_acquire)) {
        unsigned char want = TEXT_FREE;
        if (atomic_compare_exchange_strong_explicit(&j->tstate[hnext], &want, TEXT_OWN,
                                                    memory_order_relaxed,
                                                    memory_order_relaxed)) {
            hash_records(j->th, j->a + (size_t)j->stride * j->start[hnext],
                         j->end[hnext] - j->start[hnext]);
        } else {
            /* a writer has it: wait for its text (it needs no lock we
             * hold, and its bucket is sorted) */
            while (atomic_load_explicit(&j->tstate[hnext], memory_order_acquire) != TEXT_READY)
                sched_yield();
            hash_text(j->th, j->text[hnext], j->tlen[hnext]);
            free(j->text[hnext]);
            j->text[hnext] = NULL;
        }
        hnext++;
        atomic_store_explicit(&j->hpos, hnext, memory_order_relaxed);
    }
    return hnext;
}

/* A worker with no bucket left to sort: writes the text of sorted
 * buckets ahead of worker 0 until worker 0 is done. Without memory for a
 * text it stops; worker 0 then hashes those buckets from their records. */
static void write_texts(sort_job *j)
{
    char *buf = NULL;
    size_t cap = 0;
    size_t d = 0;
    for (;;) {
        size_t h = atomic_load_explicit(&j->hpos, memory_order_relaxed);
        if (h >= NBUCKETS)
            break;
        if (d <= h)
            d = h + 1; /* worker 0 is at h (or past it): start beyond */
        if (d >= NBUCKETS)
            break;
        if (d >= h + TEXT_AHEAD || !atomic_load_explicit(&j->done[d], memory_order_acquire)) {
            sched_yield(); /* too far ahead, or d not sorted yet */
            continue;
        }
        size_t m = j->end[d] - j->start[d];
        if (cap < m * TEXT_LINE_MAX + 1) {
            free(buf);
            cap = m * TEXT_LINE_MAX + 1;
            buf = malloc(cap);
            if (!buf)
                break;
        }
        unsigned char want = TEXT_FREE;
        if (atomic_compare_exchange_strong_explicit(&j->tstate[d], &want, TEXT_BUSY,
                                                    memory_order_relaxed,
                                                    memory_order_relaxed)) {
            const uint32_t *r = j->a + (size_t)j->stride * j->start[d];
            size_t len = 0;
            for (size_t i = 0; i < m; i++)
                len += format_record(buf + len, r + 4 * i);
            j->text[d] = buf;
            j->tlen[d] = len;
            atomic_store_explicit(&j->tstate[d], TEXT_READY, memory_order_release);
            buf = NULL;
            cap = 0;
        }
        d++;
    }
    free(buf);
}

static void *sort_worker(void *arg)
{
    sort_arg *sa = arg;
    sort_job *j = sa->j;
    int t = sa->t, st = j->stride;
    size_t lo = j->n * (size_t)t / (size_t)j->T, hi = j->n * (size_t)(t + 1) / (size_t)j->T;
    size_t *h = j->hist + NBUCKETS * (size_t)t;
    if (j->phase == 0) {
        uint32_t top = 0;
        for (size_t i = lo; i < hi; i++) {
            if (j->orient)
                orient_sorted_fast((fdt_vid *)j->a + 4 * i);
            top = j->a[st * i] > top ? j->a[st * i] : top;
        }
        j->tops[t] = top;
    } else if (j->phase == 1) {
        memset(h, 0, NBUCKETS * sizeof *h);
        for (size_t i = lo; i < hi; i++)
            h[(j->a[st * i] >> j->shift) & (NBUCKETS - 1)]++;
    } else if (j->phase == 2) {
        size_t bytes = (size_t)st * sizeof *j->a;
        for (size_t i = lo; i < hi; i++)
            memcpy(j->b + st * h[(j->a[st * i] >> j->shift) & (NBUCKETS - 1)]++, j->a + st * i,
                   bytes);
    } else {
        size_t inner[NBUCKETS];
        size_t hnext = 0;
        for (;;) {
            if (t == 0 && j->th) {
                hnext = hash_ready(j, hnext);
                if (hnext == NBUCKETS)
                    break;
            }
            size_t d = atomic_fetch_add_explicit(&j->next, 1, memory_order_relaxed);
            if (d >= NBUCKETS) {
                if (t != 0 || !j->th) {
                    if (t != 0 && j->th)
                        write_texts(j);
                    break;
                }
                /* Worker 0 with buckets still to hash that others are
                 * sorting or writing: give them the core (machines run
                 * more threads than cores in the tests). */
                sched_yield();
                continue;
            }
            sort_bucket(j, d, inner);
            atomic_store_explicit(&j->done[d], 1, memory_order_release);
        }
    }
    return NULL;
}

/* Runs phase `phase` on workers 0..T-1, worker 0 on the calling thread.
 * A worker whose thread cannot be created runs here after the others
 * (phases A-C split the work by slice; in D any worker finishes all). */
static void run_phase(sort_job *j, int phase, sort_arg *args, pthread_t *tid, int *made)
{
    j->phase = phase;
    for (int t = 1; t < j->T; t++)
        made[t] = fdt_spawn(&tid[t], 0, sort_worker, &args[t]) == 0;
    sort_worker(&args[0]);
    for (int t = 1; t < j->T; t++)
        if (made[t])
            pthread_join(tid[t], NULL);
    if (phase < 3)
        for (int t = 1; t < j->T; t++)
            if (!made[t])
                sort_worker(&args[t]);
}

/*
 * Sorts the n records of `stride` words at a into key order on T threads,
 * orienting 4-word records first if `orient`, and feeds them to th in that
 * order if th is not NULL.
 *
 * Most significant digit first: one pass scatters the records into 2^11
 * buckets by the top bits of the lowest vertex id, then each bucket (about
 * 3,300 records, 53 KB, at 1M points) is finished while it sits in the
 * cache: least significant passes on the bits below, the sort of each
 * vertex's group (finish_groups), and the hash. The least-significant-first sort
 * before this read and wrote the whole array once more, and the hash then
 * read it again from memory: sort and hash were 1.2 s of a 9.5 s run at 1M
 * (bench/NOTES.md, entry 33). 2048 buckets keep the scatter's write streams
 * inside the cache (16-bit digits on all four words made eight passes
 * whose 65536 streams missed on nearly every write). The scratch is as
 * large as the input, as before.
 */
static int sort_records(uint32_t *a, size_t n, int stride, int orient, text_hash *th, int T)
{
    if (T < 1 || n < ((size_t)1 << 16))
        T = 1; /* small inputs: threads would cost more than they save */
    size_t bytes = (size_t)stride * sizeof *a;
    sort_job j;
    memset(&j, 0, sizeof j);
    j.a = a;
    j.n = n;
    j.stride = stride;
    j.orient = orient;
    j.T = T;
    j.th = th;
    j.b = malloc((n ? n : 1) * bytes);
    j.tops = malloc((size_t)T * sizeof *j.tops);
    j.hist = malloc((size_t)T * NBUCKETS * sizeof *j.hist);
    j.start = malloc(2 * NBUCKETS * sizeof *j.start);
    j.done = malloc(NBUCKETS * sizeof *j.done);
    j.tstate = malloc(NBUCKETS * sizeof *j.tstate);
    j.text = calloc(NBUCKETS, sizeof *j.text);
    j.tlen = malloc(NBUCKETS * sizeof *j.tlen);
    sort_arg *args = malloc((size_t)T * sizeof *args);
    pthread_t *tid = malloc((size_t)T * sizeof *tid);
    int *made = calloc((size_t)T, sizeof *made);
    int err = FDT_ENOMEM;
    if (!j.b || !j.tops || !j.hist || !j.start || !j.done || !j.tstate || !j.text || !j.tlen ||
        !args || !tid || !made)
        goto out;
    err = FDT_OK;
    j.end = j.start + NBUCKETS;
    for (size_t d = 0; d < NBUCKETS; d++) {
        atomic_init(&j.done[d], 0);
        atomic_init(&j.tstate[d], TEXT_FREE);
    }
    atomic_init(&j.next, 0);
    atomic_init(&j.hpos, 0);
    for (int t = 0; t < T; t++) {
        args[t].j = &j;
        args[t].t = t;
    }
    run_phase(&j, 0, args, tid, made);
    uint32_t top = 0;
    for (int t = 0; t < T; t++)
        top = j.tops[t] > top ? j.tops[t] : top;
    int bits = 0;
    while (bits < 32 && (top >> bits) != 0)
        bits++;
    j.shift = bits > RADIX_BITS ? bits - RADIX_BITS : 0;
    run_phase(&j, 1, args, tid, made);
    /* Offsets: bucket d of slice t starts after all records of smaller
     * buckets and after bucket d's records in slices before t. */
    size_t sum = 0;
    for (size_t d = 0; d < NBUCKETS; d++) {
        j.start[d] = sum;
        for (int t = 0; t < T; t++) {
            size_t c = j.hist[NBUCKETS * (size_t)t + d];
            j.hist[NBUCKETS * (size_t)t + d] = sum;
            sum += c;
        }
        j.end[d] = sum;
    }
    run_phase(&j, 2, args, tid, made);
    run_phase(&j, 3, args, tid, made);
out:
    free(j.b);
    free(j.tops);
    free(j.hist);
    free(j.start);
    free(j.done);
    free(j.tstate);
    if (j.text)
        for (size_t d = 0; d < NBUCKETS; d++)
            free(j.text[d]); /* none left unless a phase could not run */
    free(j.text);
    free(j.tlen);
    free(args);
    free(tid);
    free(made);
    return err;
}

/* Threads for the sort: those of the triangulation (1 in serial mode, so
 * that mode stays sequential from end to end), at most one a core. */
static int sort_threads(const fdt_result *r)
{
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    int T = r->stats.threads;
    if (cores >= 1 && T > cores)
        T = (int)cores;
    return T < 1 ? 1 : (T > 64 ? 64 : T);
}

/* fdt_result_sort, hashing on the way when th is not NULL (done in the
 * sort's buckets where the records are the tets, after it otherwise). */
static int sort_impl(fdt_result *r, text_hash *th, int T)
{
    size_t n = r->ntets;
    fdt_result_drop_faces(r); /* it names tets by their old numbers */
    for (size_t i = 0; i < n && r->nbrs; i++) {
        int perm[4];
        orient_sorted(r->tets + 4 * i, perm);
        fdt_tid o[4];
        memcpy(o, r->nbrs + 4 * i, sizeof o);
        for (int k = 0; k < 4; k++)
            r->nbrs[4 * i + k] = o[perm[k]];
    }
    if (!r->nbrs) {
        /* ids are non-negative */
        int e = sort_records((uint32_t *)r->tets, n, 4, 1, th, T);
        if (e == FDT_OK)
            r->sorted = 1;
        return e;
    }
    uint32_t *a = malloc((n ? n : 1) * 6 * sizeof *a);
    if (!a)
        return FDT_ENOMEM;
    for (size_t i = 0; i < n; i++) {
        key_of(r->tets + 4 * i, a + 6 * i);
        a[6 * i + 4] = (uint32_t)i;
        a[6 * i + 5] = (uint32_t)((uint64_t)i >> 32);
    }
    int err = sort_records(a, n, 6, 0, NULL, T);
    if (err) {
        free(a);
        return err;
    }
    /* Apply the permutation: new tet j is old tet idx(j). */
    fdt_vid *nt = malloc((n ? n : 1) * 4 * sizeof *nt);
    fdt_tid *nn = malloc((n ? n : 1) * 4 * sizeof *nn);
    uint64_t *inv = malloc((n ? n : 1) * sizeof *inv);
    if (!nt || !nn || !inv) {
        free(a);
        free(nt);
        free(nn);
        free(inv);
        return FDT_ENOMEM;
    }
    for (size_t j = 0; j < n; j++) {
        size_t old = (size_t)a[6 * j + 4] | (size_t)((uint64_t)a[6 * j + 5] << 32);
        memcpy(nt + 4 * j, r->tets + 4 * old, 4 * sizeof *nt);
        inv[old] = j;
    }
    for (size_t j = 0; j < n; j++) {
        size_t old = (size_t)a[6 * j + 4] | (size_t)((uint64_t)a[6 * j + 5] << 32);
        for (int k = 0; k < 4; k++) {
            fdt_tid o = r->nbrs[4 * old + k];
            nn[4 * j + k] = o < 0 ? -1 : (fdt_tid)inv[o];
        }
    }
    free(r->nbrs);
    r->nbrs = nn;
    free(inv);
    free(r->tets);
    r->tets = nt;
    free(a);
    r->sorted = 1;
    if (th)
        hash_records(th, (const uint32_t *)r->tets, n);
    return FDT_OK;
}

int fdt_result_sort(fdt_result *r)
{
    if (!r)
        return FDT_EINVAL;
    return r->sorted ? FDT_OK : sort_impl(r, NULL, sort_threads(r));
}

int fdt_result_hash(fdt_result *r, uint64_t *hash)
{
    return fdt_result_hash_threads(r, r ? sort_threads(r) : 1, hash);
}

int fdt_result_hash_threads(fdt_result *r, int threads, uint64_t *hash)
{
    if (!r || !hash)
        return FDT_EINVAL;
    text_hash th = {14695981039346656037ull};
    if (r->periodic) { /* sorted as built: the .tets lines' bytes */
        char buf[FDT_PERIODIC_ROW_MAX];
        for (size_t i = 0; i < r->ntets; i++)
            hash_text(&th, buf, fdt_periodic_row_text(buf, (const uint32_t *)r->tets + 4 * i,
                                                      r->tet_off + 12 * i));
        *hash = th.h;
        return FDT_OK;
    }
    if (!r->sorted) {
        int err = sort_impl(r, &th, threads < 1 ? 1 : (threads > 64 ? 64 : threads));
        if (err)
            return err;
    } else {
        hash_records(&th, (const uint32_t *)r->tets, r->ntets);
    }
    *hash = th.h;
    return FDT_OK;
}

int fdt_result_set_hash(const fdt_result *r, uint64_t *hash)
{
    if (!r || !hash)
        return FDT_EINVAL;
    if (r->streamed) {
        *hash = r->set_hash;
        return FDT_OK;
    }
    fdt_sethash h = {0, 0};
    if (r->periodic)
        fdt_sethash_add_periodic(&h, (const uint32_t *)r->tets, r->tet_off, r->ntets);
    else
        fdt_sethash_add_n(&h, (const uint32_t *)r->tets, r->ntets);
    *hash = fdt_sethash_value(&h);
    return FDT_OK;
}

size_t fdt_periodic_row_text(char *buf, const uint32_t id[4], const int8_t off[12])
{
    size_t k = 0;
    for (int j = 0; j < 4; j++) {
        if (j)
            buf[k++] = ' ';
        k += fdt_utoa(buf + k, id[j]);
    }
    for (int j = 0; j < 12; j++) {
        buf[k++] = ' ';
        k += fdt_itoa(buf + k, off[j]);
    }
    buf[k++] = '\n';
    return k;
}
