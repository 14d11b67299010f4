/*
 * Tests for src/mesh/result.c: the canonical sort and hash against a reference
 * computed here (qsort, snprintf, FNV-1a), on one to four threads, with and
 * without neighbours.
 *
 * - A synthetic tet list (about 400,000 tets, in random order, each tet's
 *   ids in a random order): vertex 0 the lowest of about 200,000 tets
 *   (issue 16: the sort was quadratic in such a group), groups of every
 *   size around the insertion sort's limits, small groups of large ids
 *   (so that the radix digits above the lowest one are used) and a few
 *   tets twice, in both orientations (the sort is stable: those keep their
 *   input order).
 * - The case of issue 16 end to end: 40,000 points on a sphere of radius 1
 *   with radial jitter 1e-7 and the centre as point 0, written to a
 *   temporary .xyz, read back, triangulated, sorted and hashed.
 *
 * `test_result --write-centre FILE` only writes that input (for the bench:
 * `build/frontdt FILE --hash --stats`).
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#endif
#include "base/hash.h"
#include "io/read/reader.h"
#include "mesh/result.h"
#include "testutil.h"

#include <math.h>
#include <stdint.h>
#include <string.h>
#include <unistd.h>

/* ---- deterministic random numbers (splitmix64) ---------------------------- */

static uint64_t rng_state = 0x16u;

static uint64_t rnd(void)
{
    return fdt_splitmix64(&rng_state);
}

/* uniform in [0, m) (the modulo bias is irrelevant here) */
static uint32_t rnd_below(uint32_t m) { return (uint32_t)(rnd() % m); }

/* uniform in [-1, 1] */
static double rnd_sym(void) { return 2.0 * ((double)(rnd() >> 11) * 0x1p-53) - 1.0; }

/* ---- the reference ------------------------------------------------------- */

/* A tet as the sort must leave it, computed independently of src/mesh/result.c:
 * ids ascending, then the last two swapped if that took an odd number of
 * transpositions (so the orientation is kept); key: the ids ascending. */
typedef struct ref_tet {
    fdt_vid oriented[4];
    fdt_vid key[4];
    size_t index; /* position in the input: the tie-break of a stable sort */
} ref_tet;

static void make_ref(const fdt_vid *t, size_t index, ref_tet *r)
{
    fdt_vid s[4] = {t[0], t[1], t[2], t[3]};
    int swaps = 0;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j + 1 < 4 - i; j++)
            if (s[j] > s[j + 1]) {
                fdt_vid x = s[j];
                s[j] = s[j + 1];
                s[j + 1] = x;
                swaps++;
            }
    memcpy(r->key, s, sizeof s);
    memcpy(r->oriented, s, sizeof s);
    if (swaps & 1) {
        r->oriented[2] = s[3];
        r->oriented[3] = s[2];
    }
    r->index = index;
}

static int ref_cmp(const void *x, const void *y)
{
    const ref_tet *a = x, *b = y;
    for (int i = 0; i < 4; i++)
        if (a->key[i] != b->key[i])
            return a->key[i] < b->key[i] ? -1 : 1;
    return a->index < b->index ? -1 : (a->index > b->index);
}

/* The tets of t (n, input order) sorted as the canonical sort must: by key,
 * equal keys in input order. Owned by the caller. */
static ref_tet *reference(const fdt_vid *t, size_t n)
{
    ref_tet *r = malloc((n ? n : 1) * sizeof *r);
    CHECK(r);
    for (size_t i = 0; i < n; i++)
        make_ref(t + 4 * i, i, &r[i]);
    qsort(r, n, sizeof *r, ref_cmp);
    return r;
}

/* fdt_result_hash's definition (include/frontdt.h): FNV-1a 64 over the
 * .tets text, "a b c d\n" with the ids ascending, in sorted order. */
static uint64_t reference_hash(const ref_tet *r, size_t n)
{
    uint64_t h = 14695981039346656037ull;
    for (size_t i = 0; i < n; i++) {
        char line[64];
        int len = snprintf(line, sizeof line, "%d %d %d %d\n", (int)r[i].key[0],
                           (int)r[i].key[1], (int)r[i].key[2], (int)r[i].key[3]);
        for (int j = 0; j < len; j++) {
            h ^= (unsigned char)line[j];
            h *= 1099511628211ull;
        }
    }
    return h;
}

/* ---- checks -------------------------------------------------------------- */

/* A result holding a copy of tets (n) and, if nbrs is not NULL, of nbrs,
 * as the engine hands it over: unsorted. */
static fdt_result *make_result(const fdt_vid *tets, const fdt_tid *nbrs, size_t n,
                               size_t nverts, int threads)
{
    fdt_result *r = calloc(1, sizeof *r);
    CHECK(r);
    r->tets = malloc((n ? n : 1) * 4 * sizeof *r->tets);
    CHECK(r->tets);
    memcpy(r->tets, tets, n * 4 * sizeof *tets);
    if (nbrs) {
        r->nbrs = malloc((n ? n : 1) * 4 * sizeof *r->nbrs);
        CHECK(r->nbrs);
        memcpy(r->nbrs, nbrs, n * 4 * sizeof *nbrs);
    }
    r->ntets = n;
    r->n = nverts;
    r->stats.threads = threads;
    r->stats.tets = n;
    return r;
}

/*
 * Sorts and hashes a copy of tets (with a copy of nbrs if not NULL) on
 * `threads` threads and checks the order, the orientation, the hash and
 * the neighbours against the reference ref (sorted tets; the input's
 * tets, nbrs, n).
 */
static void check_sort(const fdt_vid *tets, const fdt_tid *nbrs, size_t n, size_t nverts,
                       const ref_tet *ref, uint64_t ref_hash, int threads)
{
    fdt_result *r = make_result(tets, nbrs, n, nverts, threads);
    uint64_t h = 0;
    CHECK_EQ(fdt_result_hash_threads(r, threads, &h), FDT_OK);
    if (h != ref_hash)
        fprintf(stderr, "hash %016llx, reference %016llx (%d threads, %s)\n",
                (unsigned long long)h, (unsigned long long)ref_hash, threads,
                nbrs ? "neighbours" : "no neighbours");
    CHECK(h == ref_hash);
    CHECK(r->sorted);
    CHECK_EQ(fdt_result_num_tets(r), n);
    const fdt_vid *t = fdt_result_tets(r);
    for (size_t j = 0; j < n; j++)
        for (int k = 0; k < 4; k++)
            if (t[4 * j + k] != ref[j].oriented[k]) {
                fprintf(stderr, "tet %zu: %d %d %d %d, reference %d %d %d %d (%d threads)\n",
                        j, (int)t[4 * j], (int)t[4 * j + 1], (int)t[4 * j + 2],
                        (int)t[4 * j + 3], (int)ref[j].oriented[0], (int)ref[j].oriented[1],
                        (int)ref[j].oriented[2], (int)ref[j].oriented[3], threads);
                CHECK(0);
            }
    if (nbrs) {
        /* New tet j is input tet ref[j].index; the neighbour across the
         * face opposite vertex v must be the input's, renumbered. */
        size_t *inv = malloc((n ? n : 1) * sizeof *inv);
        CHECK(inv);
        for (size_t j = 0; j < n; j++)
            inv[ref[j].index] = j;
        const fdt_tid *nn = fdt_result_neighbors(r);
        CHECK(nn);
        for (size_t j = 0; j < n; j++) {
            size_t old = ref[j].index;
            for (int k = 0; k < 4; k++) {
                int s = 0;
                while (s < 4 && tets[4 * old + s] != t[4 * j + k])
                    s++;
                CHECK(s < 4);
                fdt_tid o = nbrs[4 * old + s];
                fdt_tid want = o < 0 ? -1 : (fdt_tid)inv[o];
                if (nn[4 * j + k] != want)
                    fprintf(stderr, "tet %zu slot %d: neighbour %lld, want %lld\n", j, k,
                            (long long)nn[4 * j + k], (long long)want);
                CHECK_EQ(nn[4 * j + k], want);
            }
        }
        free(inv);
    }
    /* Sorted already: the hash again, from the sorted records. */
    uint64_t h2 = 0;
    CHECK_EQ(fdt_result_hash_threads(r, threads, &h2), FDT_OK);
    CHECK(h2 == ref_hash);
    fdt_result_free(&r);
}

/* ---- the synthetic tet list ---------------------------------------------- */

typedef struct tet_list {
    fdt_vid *t;
    size_t n, cap;
} tet_list;

static void push(tet_list *l, fdt_vid a, fdt_vid b, fdt_vid c, fdt_vid d)
{
    if (l->n == l->cap) {
        l->cap = l->cap ? 2 * l->cap : 1024;
        l->t = realloc(l->t, l->cap * 4 * sizeof *l->t);
        CHECK(l->t);
    }
    fdt_vid *t = l->t + 4 * l->n++;
    t[0] = a;
    t[1] = b;
    t[2] = c;
    t[3] = d;
}

/* g tets with lowest vertex v and the others drawn from (v, v + span],
 * no two with the same vertices (for g well below span^3 / 6). */
static void push_group(tet_list *l, fdt_vid v, size_t g, uint32_t span)
{
    size_t first = l->n;
    while (l->n - first < g) {
        fdt_vid o[3];
        for (int i = 0; i < 3; i++)
            o[i] = v + 1 + (fdt_vid)rnd_below(span);
        if (o[0] == o[1] || o[0] == o[2] || o[1] == o[2])
            continue;
        int dup = 0;
        for (size_t i = first; i < l->n && !dup; i++) {
            const fdt_vid *t = l->t + 4 * i;
            int same = 0;
            for (int a = 1; a < 4; a++)
                same += t[a] == o[0] || t[a] == o[1] || t[a] == o[2];
            dup = same == 3;
        }
        if (!dup)
            push(l, v, o[0], o[1], o[2]);
    }
}

/* Each tet's ids in a random order (any permutation: both orientations)
 * and the tets in a random order. */
static void shuffle(tet_list *l)
{
    for (size_t i = 0; i < l->n; i++) {
        fdt_vid *t = l->t + 4 * i;
        for (int k = 3; k > 0; k--) {
            int s = (int)rnd_below((uint32_t)k + 1);
            fdt_vid x = t[k];
            t[k] = t[s];
            t[s] = x;
        }
    }
    for (size_t i = l->n; i > 1; i--) {
        size_t s = (size_t)(rnd() % i);
        fdt_vid x[4];
        memcpy(x, l->t + 4 * (i - 1), sizeof x);
        memcpy(l->t + 4 * (i - 1), l->t + 4 * s, sizeof x);
        memcpy(l->t + 4 * s, x, sizeof x);
    }
}

static void test_synthetic(void)
{
    tet_list l = {0};
    /* Vertex 0 the lowest of about 200,000 tets: each triple of 1..119
     * with probability 3/4, so that many share their second and third
     * ids (the key's parts compared after the first). */
    for (fdt_vid b = 1; b < 120; b++)
        for (fdt_vid c = b + 1; c < 120; c++)
            for (fdt_vid d = c + 1; d < 120; d++)
                if (rnd_below(4) != 0)
                    push(&l, 0, b, c, d);
    size_t big = l.n;
    CHECK(big > 190000);
    /* Groups around the limits of the insertion sorts (64 records, runs
     * of 32) and a few larger ones. */
    static const size_t sizes[] = {31, 32, 33, 63, 64, 65, 66, 96, 97, 128, 129, 1000, 4097};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++)
        push_group(&l, (fdt_vid)(130 + 10 * i), sizes[i], 5000);
    /* Small groups of large ids: 1 to 12 tets each, as for uniform points. */
    for (fdt_vid v = 300000; v < 320000; v++)
        push_group(&l, v, 1 + rnd_below(12), 1u << 20);
    /* 500 tets of vertex 0 twice; as the ids are shuffled below, the
     * copies come in either orientation. */
    for (size_t i = 0; i < 500; i++) {
        const fdt_vid *t = l.t + 4 * (size_t)rnd_below((uint32_t)big);
        push(&l, t[0], t[1], t[2], t[3]);
    }
    shuffle(&l);
    size_t n = l.n, nverts = 320000 + (1u << 20) + 1;

    /* Neighbours: a random tet or -1 (the hull) in each slot; the sort only
     * moves and renumbers them. */
    fdt_tid *nbrs = malloc(n * 4 * sizeof *nbrs);
    CHECK(nbrs);
    for (size_t i = 0; i < 4 * n; i++)
        nbrs[i] = rnd_below(8) == 0 ? -1 : (fdt_tid)(rnd() % n);

    ref_tet *ref = reference(l.t, n);
    uint64_t ref_hash = reference_hash(ref, n);
    size_t g0 = 0;
    while (g0 < n && ref[g0].key[0] == 0)
        g0++;
    CHECK_EQ(g0, big + 500);
    for (int threads = 1; threads <= 4; threads++) {
        check_sort(l.t, NULL, n, nverts, ref, ref_hash, threads);
        check_sort(l.t, nbrs, n, nverts, ref, ref_hash, threads);
    }
    printf("synthetic: %zu tets, %zu with lowest vertex 0: ok\n", n, g0);
    free(ref);
    free(nbrs);
    free(l.t);
}

/* ---- the centre of a sphere ---------------------------------------------- */

#define CENTRE_POINTS 40000

/* Issue 16's input: the centre (point 0, so that it is the lowest vertex
 * of all its tets) and CENTRE_POINTS points in uniform random directions
 * at radius 1 + 1e-7 u, u uniform in [-1, 1]. Returns 0 on success. */
static int write_centre(const char *path)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return -1;
    fprintf(f, "0 0 0\n");
    for (int i = 0; i < CENTRE_POINTS; i++) {
        double x, y, z, s;
        do {
            x = rnd_sym();
            y = rnd_sym();
            z = rnd_sym();
            s = x * x + y * y + z * z;
        } while (s > 1.0 || s < 1e-12);
        double k = (1.0 + 1e-7 * rnd_sym()) / sqrt(s);
        fprintf(f, "%.17g %.17g %.17g\n", k * x, k * y, k * z);
    }
    return fclose(f) == 0 ? 0 : -1;
}

static void test_centre(void)
{
    const char *tmp = getenv("TMPDIR");
    char dir[4096], path[4200];
    snprintf(dir, sizeof dir, "%s/fdt_test_result_XXXXXX", tmp && *tmp ? tmp : "/tmp");
    CHECK(mkdtemp(dir) != NULL);
    snprintf(path, sizeof path, "%s/centre.xyz", dir);
    CHECK_EQ(write_centre(path), 0);
    double *xyz = NULL;
    size_t np = 0;
    char err[256];
    int e = fdt_rd_points(path, &xyz, &np, err, sizeof err);
    unlink(path);
    rmdir(dir);
    if (e != 0)
        fprintf(stderr, "%s\n", err);
    CHECK_EQ(e, 0);
    CHECK_EQ(np, CENTRE_POINTS + 1);

    fdt_settings s;
    fdt_default_settings(&s);
    s.mode = FDT_MODE_SERIAL;
    s.n_threads = 1;
    s.neighbors = 1;
    fdt_context *ctx = NULL;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    fdt_result *r = NULL;
    e = fdt_triangulate(ctx, xyz, np, &r);
    if (e != FDT_OK)
        fprintf(stderr, "centre: %s (%s)\n", fdt_strerror(e), fdt_context_diagnostic(ctx));
    CHECK_EQ(e, FDT_OK);
    fdt_close(&ctx);
    free(xyz);

    size_t n = fdt_result_num_tets(r);
    ref_tet *ref = reference(fdt_result_tets(r), n);
    uint64_t ref_hash = reference_hash(ref, n);
    size_t g0 = 0;
    while (g0 < n && ref[g0].key[0] == 0)
        g0++;
    /* The centre is a vertex of nearly every tet (each hull face's cone). */
    CHECK(g0 > (size_t)CENTRE_POINTS);
    for (int threads = 1; threads <= 3; threads += 2) {
        check_sort(fdt_result_tets(r), NULL, n, np, ref, ref_hash, threads);
        check_sort(fdt_result_tets(r), fdt_result_neighbors(r), n, np, ref, ref_hash, threads);
    }
    printf("centre: %zu points, %zu tets, %zu at the centre: ok\n", np, n, g0);
    free(ref);
    fdt_result_free(&r);
}

/* The accessors' refusals and clamps: thread stats of a thread that is
 * not there, NULL arguments, sizes the library does not know; the hash on
 * a thread count below 1 or above 64 is the same hash. */
static void test_refusals(void)
{
    double xyz[3 * 60];
    uint64_t seed = 3;
    for (int i = 0; i < 3 * 60; i++)
        xyz[i] = test_unif(&seed);
    fdt_settings s;
    fdt_default_settings(&s);
    s.mode = FDT_MODE_SERIAL;
    fdt_context *ctx = NULL;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    fdt_result *r = NULL;
    CHECK_EQ(fdt_triangulate(ctx, xyz, 60, &r), FDT_OK);
    fdt_thread_stats ts;
    CHECK_EQ(fdt_result_thread_stats(r, 0, &ts), FDT_OK);
    CHECK_EQ(ts.tets, fdt_result_num_tets(r));
    CHECK_EQ(fdt_result_thread_stats(NULL, 0, &ts), FDT_EINVAL);
    CHECK_EQ(fdt_result_thread_stats(r, 0, NULL), FDT_EINVAL);
    CHECK_EQ(fdt_result_thread_stats(r, -1, &ts), FDT_EINVAL);
    CHECK_EQ(fdt_result_thread_stats(r, 1, &ts), FDT_EINVAL);
    CHECK_EQ(fdt_result_thread_stats_sized(r, 0, &ts, 3), FDT_EINVAL);
    CHECK_EQ(fdt_result_num_tets(NULL), 0);
    uint64_t h1, h0, h99;
    CHECK_EQ(fdt_result_hash(r, &h1), FDT_OK);
    CHECK_EQ(fdt_result_hash_threads(r, 0, &h0), FDT_OK);
    CHECK_EQ(fdt_result_hash_threads(r, 99, &h99), FDT_OK);
    CHECK(h0 == h1 && h99 == h1);
    fdt_result_free(&r);
    fdt_close(&ctx);
    printf("refusals: thread stats, NULLs, sizes; hash threads clamped\n");
}

int main(int argc, char **argv)
{
    if (argc == 3 && strcmp(argv[1], "--write-centre") == 0) {
        if (write_centre(argv[2]) != 0) {
            fprintf(stderr, "cannot write %s\n", argv[2]);
            return 1;
        }
        return 0;
    }
    test_refusals();
    test_synthetic();
    test_centre();
    return 0;
}
