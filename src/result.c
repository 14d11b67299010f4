/* Result accessors, canonical order and the canonical hash. */
#include "result.h"

#include <stdlib.h>
#include <string.h>

void fdt_result_free(fdt_result **r)
{
    if (!r || !*r)
        return;
    free((*r)->tets);
    free((*r)->nbrs);
    free((*r)->hull);
    free((*r)->dupmap);
    free((*r)->tstats);
    free(*r);
    *r = NULL;
}

size_t fdt_result_num_tets(const fdt_result *r) { return r ? r->ntets : 0; }
const fdt_vid *fdt_result_tets(const fdt_result *r) { return r ? r->tets : NULL; }
const fdt_tid *fdt_result_neighbors(const fdt_result *r) { return r ? r->nbrs : NULL; }
size_t fdt_result_num_hull_faces(const fdt_result *r) { return r ? r->nhull : 0; }
const fdt_vid *fdt_result_hull_faces(const fdt_result *r) { return r ? r->hull : NULL; }
const fdt_vid *fdt_result_duplicate_map(const fdt_result *r) { return r ? r->dupmap : NULL; }
size_t fdt_result_num_duplicates(const fdt_result *r) { return r ? r->ndup : 0; }

int fdt_result_stats(const fdt_result *r, fdt_stats *st)
{
    if (!r || !st)
        return FDT_EINVAL;
    *st = r->stats;
    return FDT_OK;
}

int fdt_result_thread_stats(const fdt_result *r, int thread,
                            fdt_thread_stats *ts)
{
    if (!r || !ts || thread < 0 || thread >= r->stats.threads)
        return FDT_EINVAL;
    if (r->tstats) {
        *ts = r->tstats[thread];
        return FDT_OK;
    }
    /* Serial: the one thread did everything. */
    memset(ts, 0, sizeof *ts);
    ts->points = r->stats.vertices;
    ts->tets = r->stats.tets;
    ts->hull_faces = r->stats.hull_faces;
    ts->faces_advanced = r->stats.faces_advanced;
    ts->max_front = r->stats.max_front;
    ts->core = -1;
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

static void key_of(const fdt_vid *t, uint32_t k[4])
{
    k[0] = (uint32_t)t[0];
    k[1] = (uint32_t)t[1];
    k[2] = (uint32_t)(t[2] < t[3] ? t[2] : t[3]);
    k[3] = (uint32_t)(t[2] < t[3] ? t[3] : t[2]);
}

static int key_cmp(const uint32_t *x, const uint32_t *y)
{
    uint32_t a[4], b[4];
    key_of((const fdt_vid *)x, a);
    key_of((const fdt_vid *)y, b);
    for (int i = 0; i < 4; i++)
        if (a[i] != b[i])
            return a[i] < b[i] ? -1 : 1;
    return 0;
}

/* Records of the canonical sort: a tet in orient_sorted form (4 words:
 * the key is key_of of it), or with neighbours a key and the tet's old
 * index (6 words: key_of of a key is the key itself). */
#define REC_MAX 6

/*
 * Sorts the n records of `stride` words at *pa into key order. An LSD
 * radix sort on the first word only (the lowest vertex id), 11 bits a
 * pass: 2048 buckets keep the scatter's write streams inside the cache
 * (16-bit digits on all four words made eight passes whose 65536 streams
 * missed on nearly every write: the sort was 7 % of a 1M run). Records
 * with the same lowest vertex, about seven (the tets at which that vertex
 * is lowest), then get an insertion sort on the whole key. With an odd
 * number of passes the sorted records are in the scratch array, which
 * replaces *pa. The scratch is as large as the input, as before.
 */
static int sort_records(uint32_t **pa, size_t n, int stride)
{
    uint32_t *a = *pa, top = 0;
    for (size_t i = 0; i < n; i++)
        top = a[stride * i] > top ? a[stride * i] : top;
    int passes = 0;
    for (uint32_t m = top; m; m >>= 11)
        passes++;
    size_t bytes = (size_t)stride * sizeof *a;
    uint32_t *b = malloc((n ? n : 1) * bytes);
    if (!b)
        return FDT_ENOMEM;
    size_t cnt[2048];
    for (int pass = 0; pass < passes; pass++) {
        int shift = 11 * pass;
        memset(cnt, 0, sizeof cnt);
        for (size_t i = 0; i < n; i++)
            cnt[(a[stride * i] >> shift) & 2047]++;
        size_t sum = 0;
        for (int d = 0; d < 2048; d++) {
            size_t c = cnt[d];
            cnt[d] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++)
            memcpy(b + stride * cnt[(a[stride * i] >> shift) & 2047]++, a + stride * i, bytes);
        uint32_t *t = a;
        a = b;
        b = t;
    }
    free(b); /* the input (odd passes) or the scratch (even) */
    *pa = a;
    for (size_t i = 0; i < n;) {
        size_t j = i + 1;
        while (j < n && a[stride * j] == a[stride * i])
            j++;
        for (size_t x = i + 1; x < j; x++) {
            uint32_t r[REC_MAX];
            memcpy(r, a + stride * x, bytes);
            size_t y = x;
            for (; y > i && key_cmp(a + stride * (y - 1), r) > 0; y--)
                memcpy(a + stride * y, a + stride * (y - 1), bytes);
            memcpy(a + stride * y, r, bytes);
        }
        i = j;
    }
    return FDT_OK;
}

int fdt_result_sort(fdt_result *r)
{
    if (!r)
        return FDT_EINVAL;
    if (r->sorted)
        return FDT_OK;
    size_t n = r->ntets;
    for (size_t i = 0; i < n; i++) {
        int perm[4];
        orient_sorted(r->tets + 4 * i, perm);
        if (r->nbrs) {
            fdt_tid o[4];
            memcpy(o, r->nbrs + 4 * i, sizeof o);
            for (int k = 0; k < 4; k++)
                r->nbrs[4 * i + k] = o[perm[k]];
        }
    }
    if (!r->nbrs) {
        uint32_t *t = (uint32_t *)r->tets; /* ids are non-negative */
        int e = sort_records(&t, n, 4);
        r->tets = (fdt_vid *)t;
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
    int err = sort_records(&a, n, 6);
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
    return FDT_OK;
}

int fdt_result_hash(fdt_result *r, uint64_t *hash)
{
    if (!r || !hash)
        return FDT_EINVAL;
    int err = fdt_result_sort(r);
    if (err)
        return err;
    uint64_t h = 14695981039346656037ull;
    char buf[64];
    for (size_t i = 0; i < r->ntets; i++) {
        uint32_t k[4];
        key_of(r->tets + 4 * i, k);
        size_t len = 0;
        for (int j = 0; j < 4; j++) {
            char d[12];
            int nd = 0;
            uint32_t x = k[j];
            do {
                d[nd++] = (char)('0' + x % 10);
                x /= 10;
            } while (x);
            while (nd)
                buf[len++] = d[--nd];
            buf[len++] = j == 3 ? '\n' : ' ';
        }
        for (size_t j = 0; j < len; j++) {
            h ^= (unsigned char)buf[j];
            h *= 1099511628211ull;
        }
    }
    *hash = h;
    return FDT_OK;
}
