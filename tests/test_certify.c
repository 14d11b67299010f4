/*
 * The certificate of an insertion mesh (src/mesh/certify.c):
 *  - every family's mesh passes it (src/mesh/insert.c is right);
 *  - differentially against fdt_check (src/mesh/check.c, which shares only
 *    the predicates with it): a mesh whose points are moved after the
 *    build is certified exactly when fdt_check accepts its tets, over
 *    many moves on uniform points, a lattice and an integer sphere
 *    (cospherical: the perturbation decides), and both verdicts occur;
 *  - each structural corruption (a flipped tet, a reference that does not
 *    come back, a lost point) is refused with its reason.
 * The run-time half (a bug planted in the insertion's insphere stops the
 * run with exit 3) is tests/test_plant.sh.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "frontdt.h"
#include "mesh/certify.h"
#include "mesh/insert.h"
#include "testpoints.h"
#include "testutil.h"

/* The finite tets of m (ids are m's, base 0). */
static fdt_vid *finite_tets(const fdt_ins *m, size_t *nt)
{
    fdt_vid *t = malloc(4 * (m->nfinite + 1) * sizeof *t);
    CHECK(t != NULL);
    size_t k = 0;
    for (uint32_t s = fdt_ins_next_finite(m, 0); s != FDT_NONE; s = fdt_ins_next_finite(m, s + 1), k++)
        for (int i = 0; i < 4; i++)
            t[4 * k + (size_t)i] = (fdt_vid)fdt_ins_tet(m, s)[i];
    *nt = k;
    return t;
}

static void test_families(void)
{
    /* MIXED repeats points (0.25 + 1e-300 rounds to 0.25): the insertion
     * takes distinct points only, as the pipeline's merge leaves them */
    for (int fam = 0; fam < NFAMILIES; fam++) {
        if (fam == MIXED)
            continue;
        double *p = malloc(3 * 3000 * sizeof *p);
        CHECK(p != NULL);
        size_t n = make_points(fam, 3000, p);
        fdt_ins m;
        memset(&m, 0, sizeof m);
        CHECK_EQ(fdt_ins_build(&m, p, 0, (uint32_t)n, NULL), FDT_OK);
        fdt_certify_fail why = {0, 0, ""};
        int rc = fdt_certify(&m, NULL, &why);
        EXPECTF(rc == FDT_OK, "%s: slot %u face %d: %s", family_name[fam], why.slot, why.face,
                why.what);
        /* the parallel build's mesh too */
        fdt_ins mp;
        memset(&mp, 0, sizeof mp);
        CHECK_EQ(fdt_ins_build_parallel(&mp, p, 0, (uint32_t)n, 3, NULL), FDT_OK);
        rc = fdt_certify(&mp, NULL, &why);
        EXPECTF(rc == FDT_OK, "%s (3 threads): slot %u: %s", family_name[fam], why.slot,
                why.what);
        fdt_ins_free(&mp);
        fdt_ins_free(&m);
        free(p);
    }
}

/* Moves one point of a built mesh by delta along an axis, many times:
 * the certificate's verdict must be fdt_check's. */
static void test_against_check(int fam, size_t want, double delta, int trials)
{
    double *p = malloc(3 * want * sizeof *p), *q = malloc(3 * want * sizeof *q);
    CHECK(p && q);
    size_t n = make_points(fam, want, p);
    fdt_ins m;
    memset(&m, 0, sizeof m);
    CHECK_EQ(fdt_ins_build(&m, p, 0, (uint32_t)n, NULL), FDT_OK);
    size_t nt;
    fdt_vid *tets = finite_tets(&m, &nt);
    int seen_ok = 0, seen_bad = 0;
    char msg[256];
    for (int t = 0; t < trials; t++) {
        memcpy(q, p, 3 * n * sizeof *q);
        size_t i = (size_t)(rnd() % n);
        int axis = (int)(rnd() % 3);
        double d = (rnd() & 1) ? delta : -delta;
        /* On a lattice or a sphere of integer points every move breaks a
         * tie against the perturbation's choice: a quarter of the trials
         * there move nothing, so that both verdicts are seen. */
        if (fam != UNIFORM && rnd() % 4 == 0)
            d = 0;
        q[3 * i + (size_t)axis] += d * (fam == UNIFORM ? urand() : 1.0);
        m.P = q;
        fdt_certify_fail why;
        int c = fdt_certify(&m, NULL, &why);
        int k = fdt_check(q, n, tets, nt, NULL, msg, sizeof msg);
        EXPECTF((c == FDT_OK) == (k == 0), "%s trial %d: certificate %s, fdt_check %s (%s)",
                family_name[fam], t, c == FDT_OK ? "passes" : why.what,
                k == 0 ? "passes" : "fails", msg);
        if (c == FDT_OK)
            seen_ok = 1;
        else
            seen_bad = 1;
    }
    EXPECTF(seen_ok && seen_bad, "%s: moves gave only one verdict (ok %d, bad %d)",
            family_name[fam], seen_ok, seen_bad);
    m.P = p;
    fdt_ins_free(&m);
    free(tets);
    free(p);
    free(q);
}

/* Whether the certificate refuses m on one thread (*why: its failure)
 * and on two, three and eight: each face is checked from one end (its
 * lower slot, src/mesh/certify.c), in whichever range of the space order
 * holds that end, so every corruption must be seen however the ranges
 * fall. */
static int refused(const fdt_ins *m, fdt_certify_fail *why)
{
    fdt_certify_fail w2;
    int ok = fdt_certify(m, NULL, why) == FDT_ECHECK;
    for (int t = 2; t <= 8; t += t == 3 ? 5 : 1)
        ok &= fdt_certify_parallel(m, t, NULL, &w2) == FDT_ECHECK;
    return ok;
}

static void test_corruptions(void)
{
    double *p = malloc(3 * 2000 * sizeof *p);
    CHECK(p != NULL);
    size_t n = make_points(UNIFORM, 2000, p);
    fdt_ins m;
    memset(&m, 0, sizeof m);
    CHECK_EQ(fdt_ins_build(&m, p, 0, (uint32_t)n, NULL), FDT_OK);
    uint32_t s = fdt_ins_next_finite(&m, 0);
    CHECK(s != FDT_NONE);
    uint32_t *v = m.T + 8 * (size_t)s;
    fdt_certify_fail why;
    /* two vertices swapped: negatively oriented (and the faces' gluing) */
    uint32_t keep[8];
    memcpy(keep, v, sizeof keep);
    v[0] = keep[1];
    v[1] = keep[0];
    EXPECT(refused(&m, &why));
    memcpy(v, keep, sizeof keep);
    /* a neighbour reference that does not come back */
    v[4] ^= 4; /* another slot, same face index */
    EXPECT(refused(&m, &why));
    memcpy(v, keep, sizeof keep);
    /* a point whose tet does not hold it */
    uint32_t kv = m.vtet[5];
    m.vtet[5] = s == m.vtet[5] ? fdt_ins_next_finite(&m, s + 1) : s;
    uint32_t *w = m.T + 8 * (size_t)m.vtet[5];
    if (w[0] != 5 && w[1] != 5 && w[2] != 5 && w[3] != 5) {
        EXPECT(refused(&m, &why));
        EXPECT(strstr(why.what, "point") != NULL);
    }
    m.vtet[5] = kv;
    EXPECT(fdt_certify(&m, NULL, &why) == FDT_OK);
    /* a reference to the slot itself, and past the slots */
    v[4] = (s << 2) | 0;
    EXPECT(fdt_certify(&m, NULL, &why) == FDT_ECHECK && strstr(why.what, "itself"));
    v[4] = (m.nslots + 5) << 2;
    EXPECT(refused(&m, &why));
    memcpy(v, keep, sizeof keep);
    /* a second infinite vertex */
    v[1] = FDT_NONE;
    EXPECT(refused(&m, &why));
    memcpy(v, keep, sizeof keep);
    /* a neighbour that is a freed slot (marked so in place) */
    uint32_t nt = v[4] >> 2, *wn = m.T + 8 * (size_t)nt, wkeep[8];
    memcpy(wkeep, wn, sizeof wkeep);
    wn[0] = wn[1] = FDT_NONE;
    EXPECT(refused(&m, &why));
    memcpy(wn, wkeep, sizeof wkeep);
    /* a vertex replaced by another point: the faces no longer match, or
     * the geometry fails; every such change is refused */
    for (int k = 0; k < 4; k++) {
        v[k] = keep[k] == 0 ? 1 : 0;
        EXPECT(refused(&m, &why));
        memcpy(v, keep, sizeof keep);
    }
    /* an infinite tet's hull face turned inside out */
    for (uint32_t t = 0; t < m.nslots; t++) {
        uint32_t *h = m.T + 8 * (size_t)t;
        if ((h[0] == FDT_NONE) + (h[1] == FDT_NONE) + (h[2] == FDT_NONE) + (h[3] == FDT_NONE) != 1)
            continue;
        int i = h[0] == FDT_NONE ? 1 : 0, j = i + 1 + (h[i + 1] == FDT_NONE);
        uint32_t hk[8];
        memcpy(hk, h, sizeof hk);
        uint32_t x = h[i];
        h[i] = h[j];
        h[j] = x;
        EXPECT(refused(&m, &why));
        memcpy(h, hk, sizeof hk);
        break;
    }
    /* the whole mesh, on one and on three threads, passes again */
    EXPECT(fdt_certify(&m, NULL, &why) == FDT_OK);
    fdt_pred_counts pc = {0};
    EXPECT(fdt_certify_parallel(&m, 3, &pc, &why) == FDT_OK);
    char buf[160];
    why.slot = 7;
    why.face = 2;
    why.what = "x";
    fdt_certify_describe(&why, buf, sizeof buf);
    EXPECT(strcmp(buf, "mesh certificate failed: tet slot 7 face 2: x") == 0);
    why.face = -1;
    fdt_certify_describe(&why, buf, sizeof buf);
    EXPECT(strcmp(buf, "mesh certificate failed: tet slot 7: x") == 0);
    fdt_certify_build_failed(&why);
    fdt_certify_describe(&why, buf, sizeof buf);
    EXPECT(strcmp(buf, "mesh certificate failed: the insertion's own consistency checks "
                       "failed") == 0);
    fdt_ins_free(&m);
    free(p);
}

int main(void)
{
    test_families();
    test_corruptions();
    test_against_check(UNIFORM, 400, 2e-2, 300);
    test_against_check(LATTICE, 343, 1e-9, 300);
    test_against_check(SPHERE_INT, 500, 1e-9, 300);
    return test_report("certify");
}
