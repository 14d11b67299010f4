/*
 * The gather of a parallel run (src/par/gather.c) on a hand-built run of
 * three parts (tests/enginefix.h): part 0 with a few tets, part 1 with
 * more than part 0's buffers hold (so they grow), part 2 empty. Checked:
 * - the tets and hull faces come out in part order, renumbered into input
 *   numbering through orig, whichever worker copies which slice;
 * - part 1's own neighbour links are shifted by part 0's tet count, hull
 *   slots stay -1, and the link lists join tets across parts (both
 *   directions);
 * - a missing cross-part link leaves one slot open more than there are
 *   hull faces: FDT_EINTERNAL;
 * - without neighbours the mesh has none and no links are applied.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "enginefix.h"
#include "par/gather.h"

enum { K0 = 3, K1 = 100, NT = K0 + K1, NP = 4 * NT, NH = 2 * NT + 2 };

static fdt_vid g_orig[NP];

/* Tet k (global order) has tree ids 4k .. 4k+3; hull face h has ids
 * h, h+1, h+2. Within a part, tet i's face 0 meets tet i+1's face 3; part
 * 0's last tet's face 1 meets part 1's first tet's face 2 (a link of part
 * `linker`, or none if linker < 0). */
static engine *make_run(int want_nbrs, int linker)
{
    engine *e = fix_engine(3, FDT_MODE_SHARED, NULL, 1);
    e->want_nbrs = want_nbrs;
    e->orig = g_orig;
    const int cnt[3] = {K0, K1, 0};
    int k = 0, h = 0;
    for (int p = 0; p < 3; p++) {
        fdt_meshbuf *mb = &e->w[p].out;
        CHECK_EQ(fdt_meshbuf_init(mb, 4, want_nbrs), FDT_OK);
        for (int i = 0; i < cnt[p]; i++, k++) {
            uint32_t v[4] = {4u * k, 4u * k + 1, 4u * k + 2, 4u * k + 3};
            int64_t t = fdt_meshbuf_add_tet(mb, v);
            CHECK_EQ(t, i);
            if (want_nbrs) {
                for (int f = 0; f < 4; f++)
                    mb->nbrs[4 * t + f] = -1;
                if (i > 0) {
                    mb->nbrs[4 * (t - 1) + 0] = t;
                    mb->nbrs[4 * t + 3] = t - 1;
                }
            }
        }
        /* part p's hull faces, one per open slot: 2 K0 + 1, 2 K1 + 1, 0 */
        for (int j = 0; j < (cnt[p] ? 2 * cnt[p] + 1 : 0); j++, h++) {
            uint32_t f[3] = {(uint32_t)h, (uint32_t)h + 1, (uint32_t)h + 2};
            CHECK_EQ(fdt_meshbuf_add_hull(mb, f), FDT_OK);
        }
    }
    CHECK_EQ(k, NT);
    CHECK_EQ(h, NH);
    if (linker >= 0) {
        /* the same record whichever part holds it */
        CHECK_EQ(fdt_link_add(&e->w[linker].links, 1, (int64_t)0 << 2 | 2, 0,
                              (int64_t)(K0 - 1) << 2 | 1),
                 FDT_OK);
    }
    return e;
}

/* The gather as src/par/threads.c runs it: prepare, each worker's copy (in
 * reverse here: the slices do not depend on the order), finish. */
static int gather(engine *e, fdt_meshbuf *mb)
{
    CHECK_EQ(fdt_gather_prepare(e), FDT_OK);
    for (int i = e->n - 1; i >= 0; i--)
        fdt_gather_copy(&e->w[i]);
    return fdt_gather_finish(e, mb);
}

static void check_vertices(const fdt_meshbuf *mb)
{
    CHECK_EQ(mb->ntets, NT);
    CHECK_EQ(mb->nhull, NH);
    for (int k = 0; k < NT; k++)
        for (int j = 0; j < 4; j++)
            EXPECTF(mb->tets[4 * k + j] == (uint32_t)g_orig[4 * k + j], "tet %d vertex %d", k, j);
    for (int h = 0; h < NH; h++)
        for (int j = 0; j < 3; j++)
            EXPECTF(mb->hull[3 * h + j] == (uint32_t)g_orig[h + j], "hull face %d vertex %d", h, j);
}

static void test_gather(void)
{
    for (int i = 0; i < NP; i++)
        g_orig[i] = (fdt_vid)((7919u * (unsigned)i + 13) % NP);
    for (int linker = 0; linker <= 1; linker++) {
        engine *e = make_run(1, linker);
        fdt_meshbuf mb;
        EXPECT(gather(e, &mb) == FDT_OK);
        EXPECT(e->toff[0] == 0 && e->toff[1] == K0 && e->toff[2] == NT && e->toff[3] == NT);
        EXPECT(e->hoff[1] == 2 * K0 + 1 && e->hoff[3] == NH);
        check_vertices(&mb);
        /* the parts' buffers are the mesh's or freed */
        EXPECT(e->w[0].out.tets == NULL && e->w[1].out.tets == NULL);
        for (int k = 0; k < NT; k++) {
            int64_t want[4] = {-1, -1, -1, -1};
            if (k != K0 - 1 && k != NT - 1)
                want[0] = k + 1; /* the next tet in its own part */
            if (k != 0 && k != K0)
                want[3] = k - 1;
            if (k == K0 - 1)
                want[1] = K0; /* across the parts */
            if (k == K0)
                want[2] = K0 - 1;
            for (int f = 0; f < 4; f++)
                EXPECTF(mb.nbrs[4 * k + f] == want[f], "linker %d: tet %d face %d: %lld, want %lld",
                        linker, k, f, (long long)mb.nbrs[4 * k + f], (long long)want[f]);
        }
        fdt_meshbuf_free(&mb);
        fix_free(e);
    }
    /* the cross link lost: one open slot more than the hull's */
    engine *e = make_run(1, -1);
    fdt_meshbuf mb;
    EXPECT(gather(e, &mb) == FDT_EINTERNAL);
    check_vertices(&mb);
    fdt_meshbuf_free(&mb);
    fix_free(e);
    /* no neighbours: none out, the links not needed */
    e = make_run(0, -1);
    EXPECT(gather(e, &mb) == FDT_OK);
    EXPECT(mb.nbrs == NULL);
    check_vertices(&mb);
    fdt_meshbuf_free(&mb);
    fix_free(e);
}

int main(void)
{
    test_gather();
    return test_report("gather");
}
