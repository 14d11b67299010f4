/*
 * The parallel engine's per-part containers (src/par/partsets.c): the set of
 * boundary tets (duplicate requests answer 0, growth keeps every key),
 * the ghost map of foreign coordinates (first coordinates kept, found
 * across several rehashes, NULL for ids never put, colliding ids on one
 * probe chain) and the link list (records kept in order across growth).
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "frontdt.h"
#include "par/partsets.h"
#include "testutil.h"

/* Tets keyed on sorted ids; the set grows from empty (1,024 slots,
 * doubled at half load), so 5,000 keys go through three growths. */
static void test_tetset(void)
{
    tetset s = {0};
    enum { N = 5000 };
    uint64_t rng = 7;
    static uint32_t keys[N][4];
    for (int i = 0; i < N; i++) {
        /* distinct: the first id is i itself */
        keys[i][0] = (uint32_t)i;
        for (int k = 1; k < 4; k++)
            keys[i][k] = keys[i][k - 1] + 1 + (uint32_t)(test_rand64(&rng) % 1000);
        EXPECTF(fdt_tetset_insert(&s, keys[i]) == 1, "key %d is new", i);
        /* the same key again at once: present */
        EXPECTF(fdt_tetset_insert(&s, keys[i]) == 0, "key %d twice", i);
    }
    CHECK_EQ(s.count, N);
    /* at most half full, a power of two (the probe mask) */
    EXPECT(s.cap >= 2 * (size_t)N && (s.cap & (s.cap - 1)) == 0);
    /* every key still present after the growths */
    for (int i = 0; i < N; i++)
        EXPECTF(fdt_tetset_insert(&s, keys[i]) == 0, "key %d kept across growth", i);
    CHECK_EQ(s.count, N);
    /* keys that differ only in the last id are different tets */
    uint32_t k2[4] = {keys[0][0], keys[0][1], keys[0][2], keys[0][3] + 1};
    EXPECT(fdt_tetset_insert(&s, k2) == 1);
    EXPECT(s.count == N + 1);
    free(s.k);
}

static void test_ghosts(void)
{
    ghostmap gm = {0};
    double x[3] = {1, 2, 3};
    /* the empty map answers NULL without a table */
    EXPECT(fdt_ghost_find(&gm, 5) == NULL);
    enum { N = 3000 };
    /* ids spread out, as a part's foreign neighbours are */
    for (uint32_t i = 0; i < N; i++) {
        double p[3] = {(double)i, -(double)i, 0.5 * i};
        CHECK_EQ(fdt_ghost_put(&gm, 7919u * i + 3, p), FDT_OK);
    }
    CHECK_EQ(gm.count, N);
    EXPECT(gm.cap >= 2 * (size_t)N && (gm.cap & (gm.cap - 1)) == 0);
    for (uint32_t i = 0; i < N; i++) {
        const double *q = fdt_ghost_find(&gm, 7919u * i + 3);
        EXPECTF(q && q[0] == (double)i && q[1] == -(double)i && q[2] == 0.5 * i,
                "ghost %u after rehash", i);
    }
    /* an id never put: NULL (the probe ends at an empty slot) */
    EXPECT(fdt_ghost_find(&gm, 1) == NULL);
    EXPECT(fdt_ghost_find(&gm, 7919u * N + 3) == NULL);
    /* a second put keeps the first coordinates (they never change) */
    CHECK_EQ(fdt_ghost_put(&gm, 3, x), FDT_OK);
    const double *q = fdt_ghost_find(&gm, 3);
    EXPECT(q && q[0] == 0 && q[1] == 0 && q[2] == 0);
    EXPECT(gm.count == N);
    free(gm.g);

    /* Consecutive ids: many share probe chains in a 1,024-slot table;
     * each is found with its own coordinates. */
    ghostmap g2 = {0};
    for (uint32_t i = 0; i < 512; i++) {
        double p[3] = {i + 0.25, 0, 0};
        CHECK_EQ(fdt_ghost_put(&g2, i, p), FDT_OK);
    }
    EXPECT(g2.cap == 1024); /* half of 1,024: no rehash yet */
    for (uint32_t i = 0; i < 512; i++) {
        const double *p = fdt_ghost_find(&g2, i);
        EXPECTF(p && p[0] == i + 0.25, "id %u", i);
    }
    double p[3] = {9, 9, 9};
    CHECK_EQ(fdt_ghost_put(&g2, 512, p), FDT_OK);
    EXPECT(g2.cap == 2048); /* the 513th: doubled */
    for (uint32_t i = 0; i < 512; i++) {
        const double *r = fdt_ghost_find(&g2, i);
        EXPECTF(r && r[0] == i + 0.25, "id %u after the rehash", i);
    }
    free(g2.g);

    /* Coordinates read from the map itself and put under another id at the
     * very put that grows the table (issue 34: the apex of a message-mode
     * face is a ghost, its coordinates point into the map): the new entry
     * gets them, not the freed table's bytes (ASan: heap-use-after-free
     * before the put copied them first). A put of an id already there
     * leaves the table as it is, even at the growth threshold. */
    ghostmap g3 = {0};
    for (uint32_t i = 0; i < 512; i++) {
        double p3[3] = {i + 0.5, 1, 2};
        CHECK_EQ(fdt_ghost_put(&g3, i, p3), FDT_OK);
    }
    const ghost *before = g3.g;
    CHECK_EQ(fdt_ghost_put(&g3, 7, fdt_ghost_find(&g3, 7)), FDT_OK);
    EXPECT(g3.g == before && g3.cap == 1024 && g3.count == 512);
    CHECK_EQ(fdt_ghost_put(&g3, 9999, fdt_ghost_find(&g3, 300)), FDT_OK);
    EXPECT(g3.cap == 2048 && g3.count == 513);
    const double *m = fdt_ghost_find(&g3, 9999);
    EXPECT(m && m[0] == 300.5 && m[1] == 1 && m[2] == 2);
    free(g3.g);
}

static void test_links(void)
{
    linklist l = {0};
    enum { N = 2500 };
    for (int i = 0; i < N; i++)
        CHECK_EQ(fdt_link_add(&l, i % 7, (int64_t)i << 2 | 1, i % 5, (int64_t)i << 2 | 3), FDT_OK);
    CHECK_EQ(l.n, N);
    EXPECT(l.cap >= N);
    for (int i = 0; i < N; i++) {
        const linkrec *r = &l.r[i];
        EXPECTF(r->ta == i % 7 && r->la == ((int64_t)i << 2 | 1) && r->tb == i % 5 &&
                    r->lb == ((int64_t)i << 2 | 3),
                "link %d in order after growth", i);
    }
    free(l.r);
}

int main(void)
{
    test_tetset();
    test_ghosts();
    test_links();
    return test_report("partsets");
}
