/*
 * The face table (src/front/facetab.c): canonical rotation keeps the
 * orientation, a face is found from its reverse, and backward-shift
 * deletion in random order keeps every other face findable.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "front/facetab.h"
#include "frontdt.h"
#include "testutil.h"

static void test_facetab(void)
{
    /* Insert many faces, find both orientations, remove in random order
     * (backward-shift deletion must keep every other face findable). */
    enum { N = 20000 };
    uint64_t rng = 0x9E3779B97F4A7C15ull;
    fdt_facetab ft;
    EXPECTF(fdt_facetab_init(&ft, 16) == FDT_OK, "init");
    static uint32_t faces[N][3];
    static uint8_t live[N];
    for (int i = 0; i < N; i++) {
        uint32_t a = (uint32_t)(3 * i), b = (uint32_t)(test_rand64(&rng) % 100000 + 300000), c = (uint32_t)(test_rand64(&rng) % 100000 + 500000);
        fdt_face f;
        fdt_face_canon(b, a, c, f.v);
        EXPECTF(f.v[0] == a && f.v[1] == c && f.v[2] == b, "canon keeps orientation");
        f.aux = 0;
        f.tet = (uint64_t)i;
        int err;
        EXPECTF(fdt_facetab_find_or_insert(&ft, &f, &err) == NULL && err == 0, "insert %d", i);
        memcpy(faces[i], f.v, sizeof f.v);
        live[i] = 1;
    }
    EXPECTF(ft.count == N, "count");
    for (int round = 0; round < 3 * N; round++) {
        int i = (int)(test_rand64(&rng) % N);
        uint32_t rev[3] = {faces[i][0], faces[i][2], faces[i][1]};
        fdt_face *s = fdt_facetab_find(&ft, rev);
        EXPECTF((s != NULL) == live[i], "find %d (live %d)", i, live[i]);
        if (s) {
            EXPECTF(s->tet == (uint64_t)i && s->v[1] == faces[i][1], "slot content %d", i);
            fdt_facetab_remove(&ft, s);
            live[i] = 0;
        }
    }
    size_t nlive = 0;
    for (int i = 0; i < N; i++) {
        nlive += live[i];
        EXPECTF((fdt_facetab_find(&ft, faces[i]) != NULL) == live[i], "final find %d", i);
    }
    EXPECTF(ft.count == nlive, "count after removals");
    fdt_facetab_free(&ft);
}

int main(void)
{
    test_facetab();
    return test_report("test_facetab");
}
