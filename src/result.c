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

/* LSD radix sort of (key, index) records on the 4 x 31-bit key, 16 bits a
 * pass: linear time where qsort's comparator calls dominated. */
typedef struct rec {
    uint32_t k[4];
    uint64_t idx;
} rec;

static int radix_sort(rec *a, size_t n)
{
    rec *b = malloc(n * sizeof *b);
    size_t *cnt = malloc(65536 * sizeof *cnt);
    if (!b || !cnt) {
        free(b);
        free(cnt);
        return FDT_ENOMEM;
    }
    for (int pass = 0; pass < 8; pass++) {
        int word = 3 - pass / 2, shift = (pass & 1) * 16;
        memset(cnt, 0, 65536 * sizeof *cnt);
        for (size_t i = 0; i < n; i++)
            cnt[(a[i].k[word] >> shift) & 0xffff]++;
        size_t sum = 0;
        for (size_t d = 0; d < 65536; d++) {
            size_t c = cnt[d];
            cnt[d] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++)
            b[cnt[(a[i].k[word] >> shift) & 0xffff]++] = a[i];
        rec *t = a;
        a = b;
        b = t;
    }
    /* 8 passes: the sorted data ended up back in the caller's array. */
    free(b);
    free(cnt);
    return FDT_OK;
}

/* The same LSD radix sort applied to the tets themselves when no
 * neighbours need renumbering: 16 bytes of scratch per tet instead of 48,
 * which keeps --hash and .tets output of large meshes inside the memory
 * budget. Keys are read from the orient_sorted form. */
static int radix_sort_tets(fdt_vid *a, size_t n)
{
    fdt_vid *b = malloc((n ? n : 1) * 4 * sizeof *b);
    size_t *cnt = malloc(65536 * sizeof *cnt);
    if (!b || !cnt) {
        free(b);
        free(cnt);
        return FDT_ENOMEM;
    }
    for (int pass = 0; pass < 8; pass++) {
        int word = 3 - pass / 2, shift = (pass & 1) * 16;
        uint32_t k[4];
        memset(cnt, 0, 65536 * sizeof *cnt);
        for (size_t i = 0; i < n; i++) {
            key_of(a + 4 * i, k);
            cnt[(k[word] >> shift) & 0xffff]++;
        }
        size_t sum = 0;
        for (size_t d = 0; d < 65536; d++) {
            size_t c = cnt[d];
            cnt[d] = sum;
            sum += c;
        }
        for (size_t i = 0; i < n; i++) {
            key_of(a + 4 * i, k);
            memcpy(b + 4 * cnt[(k[word] >> shift) & 0xffff]++, a + 4 * i, 4 * sizeof *a);
        }
        fdt_vid *t = a;
        a = b;
        b = t;
    }
    /* An even number of passes leaves the result in the caller's array. */
    free(b);
    free(cnt);
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
        int e = radix_sort_tets(r->tets, n);
        if (e == FDT_OK)
            r->sorted = 1;
        return e;
    }
    rec *a = malloc((n ? n : 1) * sizeof *a);
    if (!a)
        return FDT_ENOMEM;
    for (size_t i = 0; i < n; i++) {
        key_of(r->tets + 4 * i, a[i].k);
        a[i].idx = i;
    }
    int err = radix_sort(a, n);
    if (err) {
        free(a);
        return err;
    }
    /* Apply the permutation: new tet j is old tet a[j].idx. */
    fdt_vid *nt = malloc((n ? n : 1) * 4 * sizeof *nt);
    fdt_tid *nn = r->nbrs ? malloc((n ? n : 1) * 4 * sizeof *nn) : NULL;
    uint64_t *inv = r->nbrs ? malloc((n ? n : 1) * sizeof *inv) : NULL;
    if (!nt || (r->nbrs && (!nn || !inv))) {
        free(a);
        free(nt);
        free(nn);
        free(inv);
        return FDT_ENOMEM;
    }
    for (size_t j = 0; j < n; j++)
        memcpy(nt + 4 * j, r->tets + 4 * a[j].idx, 4 * sizeof *nt);
    if (r->nbrs) {
        for (size_t j = 0; j < n; j++)
            inv[a[j].idx] = j;
        for (size_t j = 0; j < n; j++)
            for (int k = 0; k < 4; k++) {
                fdt_tid o = r->nbrs[4 * a[j].idx + k];
                nn[4 * j + k] = o < 0 ? -1 : (fdt_tid)inv[o];
            }
        free(r->nbrs);
        r->nbrs = nn;
        free(inv);
    }
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
