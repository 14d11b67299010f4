/*
 * Tests for src/mesh/locate.c (fdt_locate), against facts computed here:
 *  - every query found in a tet holds it (exact orient3d of the tet's four
 *    faces, none with the query beyond), and every query reported outside
 *    is held by no tet (a scan of all of them), on random points with
 *    queries inside, outside and at the points;
 *  - the barycentric coordinates add up to 1 and rebuild the query to
 *    1e-12 of the box;
 *  - a lattice (cospherical points, queries on faces, edges and vertices);
 *  - the same answers with and without the result's neighbours (the
 *    locator derives them from the face list), and a non-finite query;
 *  - the scan that backs the walk up, forced.
 */
#include <math.h>
#include <string.h>

#include "frontdt.h"
#include "geom/predicates.h"
#include "mesh/locate.h"
#include "testutil.h"

static int holds(const fdt_result *r, const double *xyz, size_t t, const double *q)
{
    const fdt_vid *tv = fdt_result_tets(r) + 4 * t;
    for (int i = 0; i < 4; i++)
        if (fdt_orient3d(xyz + 3 * (size_t)tv[fdt_tet_face[i][0]],
                         xyz + 3 * (size_t)tv[fdt_tet_face[i][1]],
                         xyz + 3 * (size_t)tv[fdt_tet_face[i][2]], q, NULL) > 0)
            return 0;
    return 1;
}

static int held_by_any(const fdt_result *r, const double *xyz, const double *q)
{
    for (size_t t = 0; t < fdt_result_num_tets(r); t++)
        if (holds(r, xyz, t, q))
            return 1;
    return 0;
}

static void check_queries(fdt_result *r, const double *xyz, size_t n, const double *q, size_t nq,
                          int threads, const char *what)
{
    fdt_tid *tet = malloc(nq * sizeof *tet);
    double *b = malloc(4 * nq * sizeof *b);
    CHECK(tet && b);
    CHECK(fdt_locate(r, xyz, n, q, nq, tet, b, threads) == FDT_OK);
    const fdt_vid *tv = fdt_result_tets(r);
    size_t inside = 0;
    for (size_t k = 0; k < nq; k++) {
        const double *qk = q + 3 * k;
        if (tet[k] < 0) {
            EXPECTF(!held_by_any(r, xyz, qk), "%s: query %zu reported outside but held", what, k);
            continue;
        }
        inside++;
        EXPECTF(holds(r, xyz, (size_t)tet[k], qk), "%s: query %zu not in tet %lld", what, k,
                (long long)tet[k]);
        double sum = 0, x[3] = {0, 0, 0};
        for (int i = 0; i < 4; i++) {
            sum += b[4 * k + (size_t)i];
            for (int d = 0; d < 3; d++)
                x[d] += b[4 * k + (size_t)i] * xyz[3 * (size_t)tv[4 * (size_t)tet[k] + (size_t)i] + d];
        }
        EXPECTF(fabs(sum - 1) < 1e-12, "%s: query %zu: coordinates add to %.17g", what, k, sum);
        for (int d = 0; d < 3; d++)
            EXPECTF(fabs(x[d] - qk[d]) < 1e-12, "%s: query %zu: rebuilt %.17g, not %.17g", what,
                    k, x[d], qk[d]);
    }
    EXPECT(inside > 0);
    free(tet);
    free(b);
}

static void test_random(void)
{
    size_t n = 2000, nq = 600;
    double *xyz = malloc(3 * n * sizeof *xyz), *q = malloc(3 * nq * sizeof *q);
    CHECK(xyz && q);
    uint64_t s = 3;
    for (size_t i = 0; i < 3 * n; i++)
        xyz[i] = test_unif(&s);
    for (size_t k = 0; k < nq; k++)
        for (int d = 0; d < 3; d++)
            q[3 * k + d] = k % 5 == 4 ? xyz[3 * (k * 7 % n) + (size_t)d] /* at a point */
                                      : 1.4 * test_unif(&s) - 0.2; /* some outside */
    fdt_result *with = test_triangulate(xyz, n, 1, 1);
    fdt_result *without = test_triangulate(xyz, n, 1, 0);
    check_queries(with, xyz, n, q, nq, 1, "random, neighbours kept");
    check_queries(with, xyz, n, q, nq, 3, "random, neighbours kept, 3 threads");
    check_queries(without, xyz, n, q, nq, 2, "random, neighbours derived");
    /* the same tets where a query is strictly inside one */
    fdt_tid *a = malloc(nq * sizeof *a), *b = malloc(nq * sizeof *b);
    CHECK(a && b);
    CHECK(fdt_locate(with, xyz, n, q, nq, a, NULL, 1) == FDT_OK);
    CHECK(fdt_locate(without, xyz, n, q, nq, b, NULL, 2) == FDT_OK);
    size_t same = 0;
    for (size_t k = 0; k < nq; k++)
        same += (a[k] < 0) == (b[k] < 0);
    EXPECTF(same == nq, "inside/outside differs for %zu queries", nq - same);
    double bad[3] = {NAN, 0.5, 0.5};
    fdt_tid t;
    CHECK(fdt_locate(with, xyz, n, bad, 1, &t, NULL, 0) == FDT_OK);
    EXPECT(t == -1);
    EXPECT(fdt_locate(with, xyz, n - 1, q, 1, &t, NULL, 1) == FDT_EINVAL);
    EXPECT(fdt_locate(with, xyz, n, q, 1, &t, NULL, -1) == FDT_EINVAL);
    EXPECT(fdt_locate(NULL, xyz, n, q, 1, &t, NULL, 1) == FDT_EINVAL);
    EXPECT(fdt_locate(with, xyz, n, NULL, 1, &t, NULL, 1) == FDT_EINVAL);
    EXPECT(fdt_locate(with, xyz, n, q, 0, NULL, NULL, 1) == FDT_OK); /* no queries */
    fdt_result_free(&with);
    fdt_result_free(&without);
    free(xyz);
    free(q);
    free(a);
    free(b);
}

static void test_lattice(void)
{
    int k = 5;
    size_t n = (size_t)k * k * k, nq = 0;
    double *xyz = malloc(3 * n * sizeof *xyz), *q = malloc(3 * 2000 * sizeof *q);
    CHECK(xyz && q);
    for (size_t i = 0; i < n; i++) {
        xyz[3 * i] = (double)(i % (size_t)k);
        xyz[3 * i + 1] = (double)(i / (size_t)k % (size_t)k);
        xyz[3 * i + 2] = (double)(i / ((size_t)k * k));
    }
    /* queries on the half-integer grid: vertices, edges, faces, centres */
    for (int x = 0; x <= 2 * (k - 1); x++)
        for (int y = 0; y <= 2 * (k - 1); y += 3)
            for (int z = 0; z <= 2 * (k - 1); z += 2) {
                q[3 * nq] = x / 2.0;
                q[3 * nq + 1] = y / 2.0;
                q[3 * nq + 2] = z / 2.0;
                nq++;
            }
    fdt_result *r = test_triangulate(xyz, n, 1, 0);
    check_queries(r, xyz, n, q, nq, 2, "lattice");
    fdt_result_free(&r);
    free(xyz);
    free(q);
}

/* The scan that backs the walk up: a locator whose walks give way to it
 * at once finds the same containing tets. */
static void test_scan(void)
{
    size_t n = 300, nq = 100;
    double *xyz = malloc(3 * n * sizeof *xyz), *q = malloc(3 * nq * sizeof *q);
    CHECK(xyz && q);
    uint64_t s = 11;
    for (size_t i = 0; i < 3 * n; i++)
        xyz[i] = test_unif(&s);
    for (size_t i = 0; i < 3 * nq; i++)
        q[i] = 1.2 * test_unif(&s) - 0.1;
    fdt_result *r = test_triangulate(xyz, n, 1, 1);
    fdt_locator L;
    CHECK(fdt_locator_init(&L, r, xyz, n) == FDT_OK);
    L.cap = 0;
    size_t hint = 0, found = 0;
    for (size_t k = 0; k < nq; k++) {
        fdt_tid t = fdt_locate_one(&L, &hint, q + 3 * k);
        if (t >= 0) {
            found++;
            EXPECTF(holds(r, xyz, (size_t)t, q + 3 * k), "scan: query %zu not in tet %lld", k,
                    (long long)t);
        } else {
            EXPECTF(!held_by_any(r, xyz, q + 3 * k), "scan: query %zu held but not found", k);
        }
    }
    EXPECT(found > 0 && found < nq);
    fdt_locator_free(&L);
    fdt_result_free(&r);
    free(xyz);
    free(q);
}

int main(void)
{
    test_scan();
    test_random();
    test_lattice();
    return test_report("locate");
}
