/*
 * The face list of Merriam §2 ("the indices of the three nodes that are its
 * vertices, and the index of the tetrahedra on either side"), the edge list
 * and each vertex's neighbours, derived from a result's tets on request.
 *
 * All three are built by one counting sort on the lowest vertex id (a
 * bucket per vertex, O(n + T)) followed by a sort of each bucket, whose
 * expected size is a small constant for the meshes the engine builds (a
 * vertex is the lowest of about 12 faces and 7 edge occurrences on uniform
 * points; a vertex shared by every tet makes one large bucket, sorted by
 * qsort in O(b log b)). The results therefore come out in a canonical
 * order, the same for every thread count and mode once the tets are.
 */
#include "mesh/result.h"

#include <stdlib.h>
#include <string.h>

/* A face of one tet: the other two ids of the face ascending (the lowest
 * is the bucket), and which tet and which face of it (4 t + k: the face
 * opposite vertex k). */
typedef struct face_rec {
    uint32_t b, c;
    uint64_t ref;
} face_rec;

static int face_rec_cmp(const void *x, const void *y)
{
    const face_rec *p = x, *q = y;
    if (p->b != q->b)
        return p->b < q->b ? -1 : 1;
    if (p->c != q->c)
        return p->c < q->c ? -1 : 1;
    return p->ref < q->ref ? -1 : (p->ref > q->ref);
}

static void sort_face_bucket(face_rec *a, size_t m)
{
    if (m > 24) {
        qsort(a, m, sizeof *a, face_rec_cmp);
        return;
    }
    for (size_t i = 1; i < m; i++) {
        face_rec x = a[i];
        size_t j = i;
        for (; j > 0 && face_rec_cmp(&x, &a[j - 1]) < 0; j--)
            a[j] = a[j - 1];
        a[j] = x;
    }
}

/*
 * The face opposite vertex k of a positively oriented tet t (orient3d(t0,
 * t1, t2, t3) > 0), ordered so that t[k] is on its positive side:
 * orient3d(f0, f1, f2, t[k]) > 0. Each row with t[k] appended is an even
 * permutation of (0, 1, 2, 3) (a 3-cycle, or the identity for k = 3),
 * which keeps the sign of the determinant.
 */
static const int face_of[4][3] = {{1, 3, 2}, {0, 2, 3}, {0, 3, 1}, {0, 1, 2}};

/* Sorts three ids ascending. */
static void sort3(uint32_t v[3])
{
    uint32_t x;
    if (v[0] > v[1]) { x = v[0]; v[0] = v[1]; v[1] = x; }
    if (v[1] > v[2]) { x = v[1]; v[1] = v[2]; v[2] = x; }
    if (v[0] > v[1]) { x = v[0]; v[0] = v[1]; v[1] = x; }
}

/* bucket offsets for n vertices from counts in start[0..n-1]: start[v]
 * becomes the first slot of bucket v, start[n] the total. */
static void prefix_sums(size_t *start, size_t n)
{
    size_t sum = 0;
    for (size_t v = 0; v < n; v++) {
        size_t c = start[v];
        start[v] = sum;
        sum += c;
    }
    start[n] = sum;
}

static int build_faces(fdt_result *r)
{
    size_t n = r->n, T = r->ntets;
    if (T > (SIZE_MAX / 4) / sizeof(face_rec))
        return FDT_ETOOBIG;
    size_t nrec = 4 * T;
    size_t *start = calloc(n + 1, sizeof *start);
    size_t *fill = malloc((n + 1) * sizeof *fill);
    face_rec *rec = malloc((nrec ? nrec : 1) * sizeof *rec);
    fdt_vid *fv = NULL;
    fdt_tid *ft = NULL;
    int err = FDT_ENOMEM;
    if (!start || !fill || !rec)
        goto fail;
    for (size_t t = 0; t < T; t++)
        for (int k = 0; k < 4; k++) {
            uint32_t v[3];
            for (int j = 0; j < 3; j++)
                v[j] = (uint32_t)r->tets[4 * t + (size_t)face_of[k][j]];
            sort3(v);
            start[v[0]]++;
        }
    prefix_sums(start, n);
    memcpy(fill, start, (n + 1) * sizeof *fill);
    for (size_t t = 0; t < T; t++)
        for (int k = 0; k < 4; k++) {
            uint32_t v[3];
            for (int j = 0; j < 3; j++)
                v[j] = (uint32_t)r->tets[4 * t + (size_t)face_of[k][j]];
            sort3(v);
            face_rec *p = &rec[fill[v[0]]++];
            p->b = v[1];
            p->c = v[2];
            p->ref = 4 * (uint64_t)t + (uint64_t)k;
        }
    free(fill);
    fill = NULL;
    /* Each face is one record (hull) or two (interior): F = (4T + H) / 2
     * in a valid mesh; count them first to allocate exactly. */
    size_t nf = 0;
    for (size_t v = 0; v < n; v++) {
        face_rec *a = rec + start[v];
        size_t m = start[v + 1] - start[v];
        sort_face_bucket(a, m);
        for (size_t i = 0; i < m;) {
            size_t j = i + 1;
            while (j < m && a[j].b == a[i].b && a[j].c == a[i].c)
                j++;
            if (j - i > 2) {
                err = FDT_EINTERNAL; /* a face in three tets: not a mesh */
                goto fail;
            }
            nf++;
            i = j;
        }
    }
    fv = malloc((nf ? nf : 1) * 3 * sizeof *fv);
    ft = malloc((nf ? nf : 1) * 2 * sizeof *ft);
    if (!fv || !ft)
        goto fail;
    size_t f = 0;
    for (size_t v = 0; v < n; v++) {
        face_rec *a = rec + start[v];
        size_t m = start[v + 1] - start[v];
        for (size_t i = 0; i < m;) {
            size_t j = i + 1;
            while (j < m && a[j].b == a[i].b && a[j].c == a[i].c)
                j++;
            /* the records are in ref order within a face: the lower tet
             * first, and it is the one the face is oriented towards */
            size_t t = (size_t)(a[i].ref >> 2);
            int k = (int)(a[i].ref & 3);
            const fdt_vid *tt = r->tets + 4 * t;
            fdt_vid o[3] = {tt[face_of[k][0]], tt[face_of[k][1]], tt[face_of[k][2]]};
            /* rotate (an even permutation) so the lowest id is first */
            int lo = o[1] < o[0] ? (o[2] < o[1] ? 2 : 1) : (o[2] < o[0] ? 2 : 0);
            for (int q = 0; q < 3; q++)
                fv[3 * f + (size_t)q] = o[(lo + q) % 3];
            ft[2 * f] = (fdt_tid)t;
            ft[2 * f + 1] = j - i == 2 ? (fdt_tid)(a[i + 1].ref >> 2) : -1;
            f++;
            i = j;
        }
    }
    free(rec);
    free(start);
    r->face_verts = fv;
    r->face_tets = ft;
    r->nfaces = nf;
    return FDT_OK;
fail:
    free(start);
    free(fill);
    free(rec);
    free(fv);
    free(ft);
    return err;
}

int fdt_result_faces(fdt_result *r, size_t *n_faces, const fdt_vid **verts,
                     const fdt_tid **tets)
{
    if (!r || !n_faces || !verts || !tets || r->periodic)
        return FDT_EINVAL;
    if (!r->face_verts) {
        int err = build_faces(r);
        if (err)
            return err;
    }
    *n_faces = r->nfaces;
    *verts = r->face_verts;
    *tets = r->face_tets;
    return FDT_OK;
}

static int u32_cmp(const void *x, const void *y)
{
    uint32_t p = *(const uint32_t *)x, q = *(const uint32_t *)y;
    return p < q ? -1 : (p > q);
}

/* The 6 edges of each tet bucketed by their lower end, each bucket sorted
 * and deduplicated (an edge is in about five tets). */
static int build_edges(fdt_result *r)
{
    size_t n = r->n, T = r->ntets;
    if (T > (SIZE_MAX / 6) / sizeof(uint32_t))
        return FDT_ETOOBIG;
    static const int ends[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
    size_t *start = calloc(n + 1, sizeof *start);
    size_t *fill = malloc((n + 1) * sizeof *fill);
    uint32_t *other = malloc((T ? 6 * T : 1) * sizeof *other);
    fdt_vid *e = NULL;
    int err = FDT_ENOMEM;
    if (!start || !fill || !other)
        goto fail;
    for (size_t t = 0; t < T; t++)
        for (int k = 0; k < 6; k++) {
            fdt_vid a = r->tets[4 * t + (size_t)ends[k][0]], b = r->tets[4 * t + (size_t)ends[k][1]];
            start[a < b ? a : b]++;
        }
    prefix_sums(start, n);
    memcpy(fill, start, (n + 1) * sizeof *fill);
    for (size_t t = 0; t < T; t++)
        for (int k = 0; k < 6; k++) {
            fdt_vid a = r->tets[4 * t + (size_t)ends[k][0]], b = r->tets[4 * t + (size_t)ends[k][1]];
            other[fill[a < b ? a : b]++] = (uint32_t)(a < b ? b : a);
        }
    free(fill);
    fill = NULL;
    size_t ne = 0;
    for (size_t v = 0; v < n; v++) {
        uint32_t *a = other + start[v];
        size_t m = start[v + 1] - start[v];
        if (m > 64) { /* about 39 a bucket: insertion sort up to 64 */
            qsort(a, m, sizeof *a, u32_cmp);
        } else {
            for (size_t i = 1; i < m; i++) {
                uint32_t x = a[i];
                size_t j = i;
                for (; j > 0 && a[j - 1] > x; j--)
                    a[j] = a[j - 1];
                a[j] = x;
            }
        }
        for (size_t i = 0; i < m; i++)
            ne += i == 0 || a[i] != a[i - 1];
    }
    e = malloc((ne ? ne : 1) * 2 * sizeof *e);
    if (!e)
        goto fail;
    size_t k = 0;
    for (size_t v = 0; v < n; v++) {
        uint32_t *a = other + start[v];
        size_t m = start[v + 1] - start[v];
        for (size_t i = 0; i < m; i++)
            if (i == 0 || a[i] != a[i - 1]) {
                e[2 * k] = (fdt_vid)v;
                e[2 * k + 1] = (fdt_vid)a[i];
                k++;
            }
    }
    free(other);
    free(start);
    r->edges = e;
    r->nedges = ne;
    return FDT_OK;
fail:
    free(start);
    free(fill);
    free(other);
    free(e);
    return err;
}

int fdt_result_edges(fdt_result *r, size_t *n_edges, const fdt_vid **verts)
{
    if (!r || !n_edges || !verts || r->periodic)
        return FDT_EINVAL;
    if (!r->edges) {
        int err = build_edges(r);
        if (err)
            return err;
    }
    *n_edges = r->nedges;
    *verts = r->edges;
    return FDT_OK;
}

/* Every vertex's neighbours from the sorted edge list, as one array with
 * offsets. Taking the edges in their order (a, b) ascending appends, to
 * vertex v's list, first the a < v of the edges (a, v) in ascending a,
 * then the b > v of the edges (v, b) in ascending b: each list comes out
 * ascending without a sort. */
static int build_adjacency(fdt_result *r)
{
    size_t n = r->n;
    size_t ne;
    const fdt_vid *e;
    int err = fdt_result_edges(r, &ne, &e);
    if (err)
        return err;
    size_t *start = calloc(n + 1, sizeof *start);
    size_t *fill = malloc((n + 1) * sizeof *fill);
    fdt_vid *adj = malloc((ne ? 2 * ne : 1) * sizeof *adj);
    if (!start || !fill || !adj) {
        free(start);
        free(fill);
        free(adj);
        return FDT_ENOMEM;
    }
    for (size_t i = 0; i < ne; i++) {
        start[e[2 * i]]++;
        start[e[2 * i + 1]]++;
    }
    prefix_sums(start, n);
    memcpy(fill, start, (n + 1) * sizeof *fill);
    for (size_t i = 0; i < ne; i++) {
        adj[fill[e[2 * i]]++] = e[2 * i + 1];
        adj[fill[e[2 * i + 1]]++] = e[2 * i];
    }
    free(fill);
    r->adj_start = start;
    r->adj = adj;
    return FDT_OK;
}

int fdt_result_vertex_neighbors(fdt_result *r, fdt_vid v, size_t *count,
                                const fdt_vid **ids)
{
    if (!r || !count || !ids || v < 0 || (size_t)v >= r->n || r->periodic)
        return FDT_EINVAL;
    if (!r->adj) {
        int err = build_adjacency(r);
        if (err)
            return err;
    }
    *count = r->adj_start[v + 1] - r->adj_start[v];
    *ids = r->adj + r->adj_start[v];
    return FDT_OK;
}

void fdt_result_drop_faces(fdt_result *r)
{
    free(r->face_verts);
    free(r->face_tets);
    r->face_verts = NULL;
    r->face_tets = NULL;
    r->nfaces = 0;
}

void fdt_result_drop_derived(fdt_result *r)
{
    fdt_result_drop_faces(r);
    free(r->edges);
    free(r->adj_start);
    free(r->adj);
    r->edges = NULL;
    r->adj_start = NULL;
    r->adj = NULL;
    r->nedges = 0;
}
