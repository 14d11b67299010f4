/*
 * Tests for src/mesh/faces.c: fdt_result_faces, fdt_result_edges and
 * fdt_result_vertex_neighbors, on uniform points in a ball, a cospherical
 * lattice (degenerate: the perturbation decides) with duplicates, and the
 * same input on two threads.
 *
 * Checked against the tets and the exact predicates, independently of how
 * src/mesh/faces.c builds the lists: each face's orientation (tets[2i]'s fourth
 * vertex strictly on the positive side, tets[2i+1]'s on the negative
 * side), each tet's four faces listed exactly once, the neighbours of the
 * result agreeing with the face's two tets, the hull faces equal to
 * fdt_result_hull_faces reversed, Euler's V - E + F - T = 1 for a ball,
 * the edges sorted, unique and exactly the tets' edges, every vertex's
 * neighbours ascending and the edges seen from both ends, and the face
 * list rebuilt after fdt_result_sort and identical for two threads.
 */
#include "geom/predicates.h"
#include "mesh/result.h"
#include "testutil.h"

#include <string.h>

static int cmp3(const void *x, const void *y)
{
    const fdt_vid *p = x, *q = y;
    for (int i = 0; i < 3; i++)
        if (p[i] != q[i])
            return p[i] < q[i] ? -1 : 1;
    return 0;
}

/* sort three ids ascending (no qsort for a triple) */
static void sort_ids3(const fdt_vid *in, fdt_vid o[3])
{
    o[0] = in[0];
    o[1] = in[1];
    o[2] = in[2];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j + 1 < 3; j++)
            if (o[j] > o[j + 1]) {
                fdt_vid x = o[j];
                o[j] = o[j + 1];
                o[j + 1] = x;
            }
}

/* the vertex of tet t not on face f, or -1 if the face is not one of t's */
static fdt_vid fourth(const fdt_vid *t, const fdt_vid *f)
{
    int hit = 0;
    fdt_vid other = -1;
    for (int k = 0; k < 4; k++) {
        if (t[k] == f[0] || t[k] == f[1] || t[k] == f[2])
            hit++;
        else
            other = t[k];
    }
    return hit == 3 ? other : -1;
}

static int cmp_edge(const void *x, const void *y)
{
    const fdt_vid *p = x, *q = y;
    if (p[0] != q[0])
        return p[0] < q[0] ? -1 : 1;
    return p[1] < q[1] ? -1 : (p[1] > q[1]);
}

static void check_result(fdt_result *r, const double *xyz, size_t n)
{
    size_t T = fdt_result_num_tets(r), H = fdt_result_num_hull_faces(r);
    const fdt_vid *tets = fdt_result_tets(r);
    const fdt_tid *nb = fdt_result_neighbors(r);
    CHECK(nb != NULL);
    size_t F;
    const fdt_vid *fv;
    const fdt_tid *ft;
    CHECK_EQ(fdt_result_faces(r, &F, &fv, &ft), FDT_OK);
    CHECK_EQ(2 * F, 4 * T + H);

    /* orientation, order, and each tet's faces once */
    unsigned char *seen = calloc(4 * T, 1);
    fdt_vid *hull_from_faces = malloc((H ? H : 1) * 3 * sizeof *hull_from_faces);
    CHECK(seen && hull_from_faces);
    size_t nh = 0;
    fdt_vid prev[3] = {-1, -1, -1};
    for (size_t i = 0; i < F; i++) {
        const fdt_vid *f = fv + 3 * i;
        CHECK(f[0] < f[1] && f[0] < f[2]); /* lowest first */
        fdt_vid s[3];
        sort_ids3(f, s);
        CHECK(cmp3(prev, s) < 0); /* ascending, each face once */
        memcpy(prev, s, sizeof s);
        for (int side = 0; side < 2; side++) {
            fdt_tid t = ft[2 * i + side];
            if (side == 1 && t == -1) {
                memcpy(hull_from_faces + 3 * nh++, f, 3 * sizeof *f);
                continue;
            }
            CHECK(t >= 0 && (size_t)t < T);
            fdt_vid x = fourth(tets + 4 * t, f);
            CHECK(x >= 0);
            int o = fdt_orient3d(xyz + 3 * f[0], xyz + 3 * f[1], xyz + 3 * f[2], xyz + 3 * x,
                                 NULL);
            CHECK_EQ(o, side == 0 ? 1 : -1);
            int k = 0;
            while (tets[4 * t + k] != x)
                k++;
            CHECK(!seen[4 * t + k]);
            seen[4 * t + k] = 1;
            /* the result's own neighbour across that face */
            CHECK_EQ(nb[4 * t + k], ft[2 * i + 1 - side]);
        }
        if (ft[2 * i + 1] != -1)
            CHECK(ft[2 * i] < ft[2 * i + 1]);
    }
    for (size_t j = 0; j < 4 * T; j++)
        CHECK(seen[j]);
    free(seen);

    /* hull faces: fdt_result_hull_faces reversed, as a set */
    CHECK_EQ(nh, H);
    const fdt_vid *hull = fdt_result_hull_faces(r);
    fdt_vid *a = malloc((H ? H : 1) * 3 * sizeof *a), *b = hull_from_faces;
    CHECK(a);
    for (size_t i = 0; i < H; i++) {
        /* reverse, then rotate the lowest first */
        fdt_vid rv[3] = {hull[3 * i], hull[3 * i + 2], hull[3 * i + 1]};
        int lo = rv[1] < rv[0] ? (rv[2] < rv[1] ? 2 : 1) : (rv[2] < rv[0] ? 2 : 0);
        for (int q = 0; q < 3; q++)
            a[3 * i + q] = rv[(lo + q) % 3];
    }
    qsort(a, H, 3 * sizeof *a, cmp3);
    qsort(b, H, 3 * sizeof *b, cmp3);
    CHECK(memcmp(a, b, H * 3 * sizeof *a) == 0);
    free(a);
    free(b);

    /* edges: sorted, unique, exactly the tets' edges */
    size_t E;
    const fdt_vid *e;
    CHECK_EQ(fdt_result_edges(r, &E, &e), FDT_OK);
    for (size_t i = 0; i < E; i++) {
        CHECK(e[2 * i] < e[2 * i + 1]);
        if (i)
            CHECK(cmp_edge(e + 2 * (i - 1), e + 2 * i) < 0);
    }
    unsigned char *used = calloc(E ? E : 1, 1);
    CHECK(used);
    for (size_t t = 0; t < T; t++)
        for (int p = 0; p < 4; p++)
            for (int q = p + 1; q < 4; q++) {
                fdt_vid u = tets[4 * t + p], v = tets[4 * t + q];
                fdt_vid key[2] = {u < v ? u : v, u < v ? v : u};
                const fdt_vid *hit = bsearch(key, e, E, 2 * sizeof *e, cmp_edge);
                CHECK(hit != NULL);
                used[(size_t)(hit - e) / 2] = 1;
            }
    for (size_t i = 0; i < E; i++)
        CHECK(used[i]);
    free(used);

    /* Euler characteristic of a ball: V - E + F - T = 1 */
    size_t V = n - fdt_result_num_duplicates(r);
    CHECK_EQ((long long)V - (long long)E + (long long)F - (long long)T, 1);

    /* vertex neighbours: ascending, both ends of every edge, 2E in all */
    size_t total = 0;
    const fdt_vid *dup = fdt_result_duplicate_map(r);
    for (size_t v = 0; v < n; v++) {
        size_t c;
        const fdt_vid *ids;
        CHECK_EQ(fdt_result_vertex_neighbors(r, (fdt_vid)v, &c, &ids), FDT_OK);
        if (dup[v] != (fdt_vid)v)
            CHECK_EQ(c, 0);
        else
            CHECK(c >= 3);
        for (size_t j = 0; j < c; j++) {
            if (j)
                CHECK(ids[j - 1] < ids[j]);
            fdt_vid u = (fdt_vid)v, w = ids[j];
            fdt_vid key[2] = {u < w ? u : w, u < w ? w : u};
            CHECK(bsearch(key, e, E, 2 * sizeof *e, cmp_edge) != NULL);
        }
        total += c;
    }
    CHECK_EQ(total, 2 * E);
    size_t c;
    const fdt_vid *ids;
    CHECK_EQ(fdt_result_vertex_neighbors(r, -1, &c, &ids), FDT_EINVAL);
    CHECK_EQ(fdt_result_vertex_neighbors(r, (fdt_vid)n, &c, &ids), FDT_EINVAL);
    CHECK_EQ(fdt_result_faces(NULL, &F, &fv, &ft), FDT_EINVAL);
    CHECK_EQ(fdt_result_edges(r, NULL, &e), FDT_EINVAL);
}

static fdt_result *run(const double *xyz, size_t n, int threads)
{
    fdt_settings s;
    fdt_default_settings(&s);
    s.neighbors = 1;
    s.n_threads = threads;
    s.mode = threads > 1 ? FDT_MODE_SHARED : FDT_MODE_SERIAL;
    fdt_context *ctx = NULL;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    fdt_result *r = NULL;
    CHECK_EQ(fdt_triangulate(ctx, xyz, n, &r), FDT_OK);
    fdt_close(&ctx);
    return r;
}

/* faces as arrays, for comparing two results */
static void copy_faces(fdt_result *r, size_t *F, fdt_vid **fv, fdt_tid **ft)
{
    const fdt_vid *v;
    const fdt_tid *t;
    CHECK_EQ(fdt_result_faces(r, F, &v, &t), FDT_OK);
    *fv = malloc(*F * 3 * sizeof **fv);
    *ft = malloc(*F * 2 * sizeof **ft);
    CHECK(*fv && *ft);
    memcpy(*fv, v, *F * 3 * sizeof **fv);
    memcpy(*ft, t, *F * 2 * sizeof **ft);
}

int main(void)
{
    uint64_t rng = 17;
    /* uniform in a ball */
    size_t n = 3000;
    double *xyz = malloc(3 * n * sizeof *xyz);
    CHECK(xyz);
    for (size_t i = 0; i < n;) {
        double p[3] = {2 * test_unif(&rng) - 1, 2 * test_unif(&rng) - 1, 2 * test_unif(&rng) - 1};
        if (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] <= 1) {
            memcpy(xyz + 3 * i, p, sizeof p);
            i++;
        }
    }
    fdt_result *r1 = run(xyz, n, 1);
    check_result(r1, xyz, n);
    fdt_result *r2 = run(xyz, n, 2);
    check_result(r2, xyz, n);
    /* after the sort: rebuilt with the new tet numbers, the same for both */
    CHECK_EQ(fdt_result_sort(r1), FDT_OK);
    CHECK_EQ(fdt_result_sort(r2), FDT_OK);
    check_result(r1, xyz, n);
    check_result(r2, xyz, n);
    size_t F1, F2;
    fdt_vid *v1, *v2;
    fdt_tid *t1, *t2;
    copy_faces(r1, &F1, &v1, &t1);
    copy_faces(r2, &F2, &v2, &t2);
    CHECK_EQ(F1, F2);
    CHECK(memcmp(v1, v2, F1 * 3 * sizeof *v1) == 0);
    CHECK(memcmp(t1, t2, F1 * 2 * sizeof *t1) == 0);
    free(v1);
    free(v2);
    free(t1);
    free(t2);
    fdt_result_free(&r1);
    fdt_result_free(&r2);
    free(xyz);

    /* a 6x6x6 lattice (cospherical everywhere) with its first 20 points
     * repeated at the end */
    size_t m = 216, nd = m + 20;
    xyz = malloc(3 * nd * sizeof *xyz);
    CHECK(xyz);
    for (size_t i = 0; i < m; i++) {
        xyz[3 * i] = (double)(i % 6);
        xyz[3 * i + 1] = (double)(i / 6 % 6);
        xyz[3 * i + 2] = (double)(i / 36);
    }
    memcpy(xyz + 3 * m, xyz, 20 * 3 * sizeof *xyz);
    fdt_result *r = run(xyz, nd, 1);
    CHECK_EQ(fdt_result_num_duplicates(r), 20);
    check_result(r, xyz, nd);
    fdt_result_free(&r);
    free(xyz);
    printf("faces: ok\n");
    return 0;
}
