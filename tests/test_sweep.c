/*
 * Parts in sweep order (src/front/sweep.c, issue 31): for every
 * tests/gen_points family, the sweep's tets and hull faces, with slabs
 * small enough for many parts (and the default), at 1 and 3 threads, are
 * exactly the Delaunay mesh of all the points built in one piece
 * (src/mesh/insert.c); with the smallest slabs every family's run must
 * have more than one part. A progress callback's nonzero return cancels.
 *
 * Usage: test_sweep GEN_POINTS
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "frontdt.h"
#include "front/sweep.h"
#include "geom/prepare.h"
#include "mesh/certify.h"
#include "testutil.h"

typedef struct key4 {
    uint32_t v[4];
} key4;

static int key_cmp(const void *a, const void *b)
{
    return memcmp(a, b, sizeof(key4));
}

static void sort_ids(uint32_t *v, int n)
{
    for (int i = 1; i < n; i++)
        for (int j = i; j > 0 && v[j - 1] > v[j]; j--) {
            uint32_t t = v[j];
            v[j] = v[j - 1];
            v[j - 1] = t;
        }
}

/* A hull face's key: its ids rotated so the least is first (the
 * orientation kept), then a fourth slot of FDT_NONE. */
static key4 face_key(const uint32_t *f)
{
    int i = f[0] < f[1] ? (f[0] < f[2] ? 0 : 2) : (f[1] < f[2] ? 1 : 2);
    key4 k = {{f[i], f[(i + 1) % 3], f[(i + 2) % 3], FDT_NONE}};
    return k;
}

/* The tets (sorted ids) and hull faces (face_key) of m, sorted. */
static key4 *reference(const fdt_ins *m, size_t *n)
{
    key4 *k = malloc((m->nslots + 1) * sizeof *k);
    CHECK(k != NULL);
    size_t c = 0;
    for (uint32_t s = 0; s < m->nslots; s++) {
        const uint32_t *v = fdt_ins_tet(m, s);
        int inf = v[0] == FDT_NONE ? 0 : v[1] == FDT_NONE ? 1 : v[2] == FDT_NONE ? 2
                : v[3] == FDT_NONE ? 3 : -1;
        if (inf < 0) {
            memcpy(k[c].v, v, sizeof k[c].v);
            sort_ids(k[c++].v, 4);
        } else if (!(v[0] == FDT_NONE && v[1] == FDT_NONE)) {
            const int *f = fdt_tet_face[inf];
            uint32_t h[3] = {v[f[0]], v[f[2]], v[f[1]]};
            k[c++] = face_key(h);
        }
    }
    qsort(k, c, sizeof *k, key_cmp);
    *n = c;
    return k;
}

/* The sweep's output, from the in-memory sink (tree-order ids). */
static key4 *swept(const fdt_meshbuf *mb, size_t *n)
{
    key4 *k = malloc((mb->ntets + mb->nhull + 1) * sizeof *k);
    CHECK(k != NULL);
    size_t c = 0;
    for (size_t t = 0; t < mb->ntets; t++) {
        memcpy(k[c].v, mb->tets + 4 * t, sizeof k[c].v);
        sort_ids(k[c++].v, 4);
    }
    for (size_t h = 0; h < mb->nhull; h++)
        k[c++] = face_key(mb->hull + 3 * h);
    qsort(k, c, sizeof *k, key_cmp);
    *n = c;
    return k;
}

/* One family: the sweep at each slab size and thread count against the
 * whole mesh. */
static void test_family(const char *gen, const char *fam, size_t n)
{
    size_t got;
    double *xyz = test_gen_family(gen, fam, n, 3, &got);
    char diag[512];
    fdt_prepared pr;
    int err = fdt_prepare(xyz, got, 1, &pr, diag, sizeof diag);
    free(xyz);
    if (err) { /* tiny, huge: refused by the preparation, not the sweep's */
        printf("%s: prepare refused (%d), skipped\n", fam, err);
        return;
    }
    fdt_ins whole;
    if (fdt_ins_build(&whole, pr.p, 0, (uint32_t)pr.m, NULL) != FDT_OK) {
        printf("%s: not 3-D, skipped\n", fam);
        fdt_ins_free(&whole);
        fdt_prepared_free(&pr);
        return;
    }
    static const uint32_t slabs[] = {97, 500, 0};
    static const int threads[] = {1, 3};
    for (size_t si = 0; si < sizeof slabs / sizeof *slabs; si++)
        for (size_t ti = 0; ti < sizeof threads / sizeof *threads; ti++) {
            if (slabs[si] == 97 && threads[ti] > 1)
                continue; /* tiny parts on threads: the other sizes cover it */
            fdt_tsink sink;
            fdt_meshbuf mb;
            fdt_emit em;
            CHECK_EQ(fdt_tsink_init(&sink, pr.orig, NULL), FDT_OK);
            CHECK_EQ(fdt_meshbuf_init(&mb, 64, 0), FDT_OK);
            CHECK_EQ(fdt_emit_init(&em, &sink, &mb), FDT_OK);
            fdt_sweep_stats st;
            memset(&st, 0, sizeof st);
            /* the sweep permutes the points: the reference is rebuilt on
             * its order */
            err = fdt_sweep_emit(pr.p, pr.orig, (uint32_t)pr.m, slabs[si], threads[ti], &em, NULL,
                                 NULL, NULL, &st, diag, sizeof diag);
            EXPECTF(err == FDT_OK, "%s slab %u threads %d: %d %s", fam, slabs[si], threads[ti],
                    err, diag);
            if (err == FDT_OK) {
                fdt_ins_free(&whole);
                CHECK_EQ(fdt_ins_build(&whole, pr.p, 0, (uint32_t)pr.m, NULL), FDT_OK);
                size_t nr, ns;
                key4 *r = reference(&whole, &nr), *s = swept(&mb, &ns);
                EXPECTF(nr == ns && !memcmp(r, s, nr * sizeof *r),
                        "%s slab %u threads %d: %zu tets and faces against %zu", fam,
                        slabs[si], threads[ti], ns, nr);
                if (slabs[si] == 97 && pr.m > 400) /* dupheavy: 54 distinct points */
                    EXPECTF(st.parts > 1, "%s: one part only", fam);
                printf("%s slab %u threads %d: %zu parts, %zu tets, %zu reinserted, largest "
                       "part %zu\n",
                       fam, slabs[si], threads[ti], st.parts, mb.ntets, st.reinserted,
                       st.max_part);
                free(r);
                free(s);
            }
            fdt_emit_free(&em);
            fdt_meshbuf_free(&mb);
            fdt_tsink_free(&sink);
        }
    fdt_ins_free(&whole);
    fdt_prepared_free(&pr);
}

static int cancel_now(void *user, double fraction)
{
    (void)fraction;
    ++*(int *)user;
    return 1;
}

/* A progress callback's nonzero return stops the sweep after the part it
 * follows, one sweep or two that meet: FDT_ECANCELED. */
static void test_cancel(const char *gen)
{
    size_t got;
    double *xyz = test_gen_family(gen, "uniform", 3000, 3, &got);
    char diag[512];
    fdt_prepared pr;
    CHECK_EQ(fdt_prepare(xyz, got, 1, &pr, diag, sizeof diag), FDT_OK);
    free(xyz);
    for (int threads = 1; threads <= 2; threads++) {
        fdt_tsink sink;
        fdt_emit em;
        CHECK_EQ(fdt_tsink_init(&sink, pr.orig, NULL), FDT_OK);
        CHECK_EQ(fdt_emit_init(&em, &sink, NULL), FDT_OK);
        fdt_sweep_stats st;
        memset(&st, 0, sizeof st);
        int calls = 0;
        int err = fdt_sweep_emit(pr.p, pr.orig, (uint32_t)pr.m, 500, threads, &em, NULL, cancel_now,
                                 &calls, &st, diag, sizeof diag);
        EXPECTF(err == FDT_ECANCELED && calls == 1,
                "cancel at %d threads: %d after %d calls, %zu parts", threads, err, calls,
                st.parts);
        fdt_emit_free(&em);
        fdt_tsink_free(&sink);
    }
    fdt_prepared_free(&pr);
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: test_sweep GEN_POINTS\n");
        return 2;
    }
    int families = test_each_family(argv[1], 3000, test_family);
    EXPECTF(families > 30, "only %d families listed", families);
    test_cancel(argv[1]);
    return test_report("sweep");
}
