/*
 * fdt_check: independent exact verification that a mesh is the perturbed
 * Delaunay tetrahedralization of a point set.
 *
 * It shares nothing with the triangulator but the predicates
 * (src/geom/predicates.h), so a bug in the front, the kd-tree or the gathering
 * cannot hide itself. Every geometric decision is an exact predicate sign;
 * everything else is integer bookkeeping.
 *
 * What is verified, in this order (the first failure is reported):
 *  1. every coordinate is finite; every tet's ids are in [0, n), distinct,
 *     and each is the first index of its coordinates;
 *  2. every tet is positively oriented (orient3d > 0);
 *     every distinct point is a vertex of some tet;
 *  3. every face (key: its sorted vertex triple) is in one or two tets; two
 *     tets sharing a face induce opposite orientations on it, i.e. their
 *     apexes lie on opposite sides (with 2, this is combinatorial: a
 *     positive tet puts its apex on the positive side of its inward face);
 *     the neighbour links, if given, match the face pairing exactly;
 *  4. the one-tet faces, oriented outward, form a closed surface S (every
 *     hull edge in exactly two hull faces, in opposite directions) that is
 *     convex at every edge (coplanar allowed);
 *  5. S winds exactly once around the interior (see chk_degree()): with
 *     1-4 this makes the tets a triangulation of the convex hull of the
 *     points, covering it exactly once;
 *  6. across every interior face the apex of one tet is outside the other
 *     tet's perturbed circumsphere. By the Delaunay lemma (local implies
 *     global for a triangulation of the convex hull; the perturbation of
 *     Devillers and Teillaud is a genuine infinitesimal lifting, so the
 *     lemma holds for it), the mesh is then THE perturbed Delaunay
 *     tetrahedralization. Local failures are remembered and reported only
 *     after 4 and 5 pass, so structural errors are named first.
 *
 * Why step 5 is not a volume comparison: summing 6*vol over the tets and
 * comparing with the volume enclosed by S cannot fail once step 3 passed.
 * 6*vol(abcd) = sum over its outward faces pqr of det[p q r] is a
 * polynomial identity, and the two copies of a matched face cancel term by
 * term, so both sums are the same polynomial in the coordinates. A double
 * cover has a doubly wound hull and twice the volume on both sides. What
 * does distinguish it is the winding number of S, measured in step 5.
 *
 * Memory (the goal is 10^7 tets): one reference per face-in-tet (4 bytes
 * when 4*ntets < 2^32, else 8), a bucket index of n+1 size_t, one byte of
 * flags per point, plus twice the largest bucket (16 bytes an entry) and
 * the hull. About 130 MB beyond the mesh for 7.7 million tets. The faces are
 * grouped by their smallest vertex with a counting sort (O(n + ntets)),
 * then each small bucket is sorted by the other two vertices.
 */
#include "mesh/check.h"

#include "frontdt.h"
#include "base/bits.h"
#include "geom/predicates.h"

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The face pass reads tets, neighbours and points in bucket order, which is
 * random in memory on big meshes; asking for them a few entries ahead hides
 * most of the cache misses (fdt_prefetch, src/base/bits.h). */
#define CHK_AHEAD 8

/* Per-point flags. */
enum { PT_FIRST = 1, PT_USED = 2 };

/* One entry of a sorted bucket: key says which face (or edge) and how it is
 * oriented, ref says where it comes from. */
typedef struct chk_ent {
    uint64_t key;
    uint64_t ref;
} chk_ent;

/* A local Delaunay failure, kept until the structural checks have passed. */
typedef struct chk_delaunay_fail {
    int found;
    size_t t1, t2;
    fdt_vid face[3];
    fdt_vid apex;
} chk_delaunay_fail;

typedef struct chk {
    const double *xyz;
    size_t n;
    const fdt_vid *tets;
    size_t ntets;
    const fdt_tid *nbrs;
    char *msg;
    size_t len;

    unsigned char *flags; /* n: PT_* */
    size_t *bucket;       /* n + 1: counting-sort bucket bounds */
    void *refs;           /* 4 * ntets face references 4t+i */
    int wide;             /* refs are uint64_t (else uint32_t) */
    chk_ent *scratch;     /* one bucket, sorted, and as much again */
    size_t scratch_cap;
    uint64_t *hull;       /* face references of the hull faces */
    size_t nhull, hull_cap;
    chk_delaunay_fail dfail;
} chk;

/*
 * The face opposite vertex i of a positively oriented tet (v0 v1 v2 v3),
 * listed so that v_i is on its positive side (inward). Reversing any two
 * entries gives the outward orientation.
 */
static const int chk_face_in[4][3] = {
    {1, 3, 2}, {0, 2, 3}, {0, 3, 1}, {0, 1, 2}
};

static int chk_fail(chk *c, int err, const char *fmt, ...)
{
    if (c->msg && c->len > 0) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(c->msg, c->len, fmt, ap);
        va_end(ap);
    }
    return err;
}

static const double *chk_pt(const chk *c, fdt_vid v)
{
    return c->xyz + 3 * (size_t)v;
}

static const fdt_vid *chk_tet(const chk *c, size_t t)
{
    return c->tets + 4 * t;
}

static uint64_t chk_ref_get(const chk *c, size_t k)
{
    return c->wide ? ((const uint64_t *)c->refs)[k]
                   : ((const uint32_t *)c->refs)[k];
}

static void chk_ref_set(chk *c, size_t k, uint64_t r)
{
    if (c->wide)
        ((uint64_t *)c->refs)[k] = r;
    else
        ((uint32_t *)c->refs)[k] = (uint32_t)r;
}

/* ---- sorting ------------------------------------------------------------ */

static int chk_ent_cmp(const chk_ent *a, const chk_ent *b)
{
    if (a->key != b->key)
        return a->key < b->key ? -1 : 1;
    if (a->ref != b->ref)
        return a->ref < b->ref ? -1 : 1;
    return 0;
}

/*
 * Sorts e[0..m) by (key, ref); tmp has room for m entries. Buckets are small
 * on real meshes (a few dozen entries), so runs of 16 are insertion-sorted,
 * then merged bottom-up: O(m log m) whatever the input (qsort from libc was
 * a sixth of the whole check, mostly call overhead).
 */
static void chk_sort_ents(chk_ent *e, chk_ent *tmp, size_t m)
{
    const size_t run = 16;
    for (size_t lo = 0; lo < m; lo += run) {
        size_t hi = lo + run < m ? lo + run : m;
        for (size_t i = lo + 1; i < hi; i++) {
            chk_ent x = e[i];
            size_t j = i;
            while (j > lo && chk_ent_cmp(&e[j - 1], &x) > 0) {
                e[j] = e[j - 1];
                j--;
            }
            e[j] = x;
        }
    }
    chk_ent *src = e, *dst = tmp;
    for (size_t w = run; w < m; w *= 2) {
        for (size_t lo = 0; lo < m; lo += 2 * w) {
            size_t mid = lo + w < m ? lo + w : m;
            size_t hi = lo + 2 * w < m ? lo + 2 * w : m;
            size_t i = lo, j = mid, k = lo;
            while (i < mid && j < hi)
                dst[k++] = chk_ent_cmp(&src[j], &src[i]) < 0 ? src[j++]
                                                             : src[i++];
            while (i < mid)
                dst[k++] = src[i++];
            while (j < hi)
                dst[k++] = src[j++];
        }
        chk_ent *x = src;
        src = dst;
        dst = x;
    }
    if (src != e)
        memcpy(e, src, m * sizeof *e);
}

/* Stable bottom-up merge sort of point indices by lexicographic order, so
 * equal points stay in index order and the first of a run is the smallest
 * index. (qsort has no context argument in C11, and is not stable.) */
static void chk_sort_points(const double *xyz, fdt_vid *a, fdt_vid *tmp,
                            size_t n)
{
    fdt_vid *src = a, *dst = tmp;
    for (size_t w = 1; w < n; w *= 2) {
        for (size_t lo = 0; lo < n; lo += 2 * w) {
            size_t mid = lo + w < n ? lo + w : n;
            size_t hi = lo + 2 * w < n ? lo + 2 * w : n;
            size_t i = lo, j = mid, k = lo;
            while (i < mid && j < hi) {
                if (fdt_lex_compare(xyz + 3 * (size_t)src[j],
                                    xyz + 3 * (size_t)src[i]) < 0)
                    dst[k++] = src[j++];
                else
                    dst[k++] = src[i++];
            }
            while (i < mid)
                dst[k++] = src[i++];
            while (j < hi)
                dst[k++] = src[j++];
        }
        fdt_vid *s = src;
        src = dst;
        dst = s;
    }
    if (src != a)
        memcpy(a, src, n * sizeof *a);
}

/* Sorts three ids ascending into s; returns the parity of the permutation
 * (0 even, 1 odd). */
static unsigned chk_sort3(const fdt_vid in[3], fdt_vid s[3])
{
    unsigned par = 0;
    s[0] = in[0];
    s[1] = in[1];
    s[2] = in[2];
    fdt_vid x;
    if (s[0] > s[1]) { x = s[0]; s[0] = s[1]; s[1] = x; par ^= 1; }
    if (s[1] > s[2]) { x = s[1]; s[1] = s[2]; s[2] = x; par ^= 1; }
    if (s[0] > s[1]) { x = s[0]; s[0] = s[1]; s[1] = x; par ^= 1; }
    return par;
}

/* The inward triple of face reference r = 4t + i. */
static void chk_face_of(const chk *c, uint64_t r, fdt_vid f[3])
{
    const fdt_vid *v = chk_tet(c, (size_t)(r >> 2));
    const int *k = chk_face_in[r & 3];
    f[0] = v[k[0]];
    f[1] = v[k[1]];
    f[2] = v[k[2]];
}

/* Outward triple of hull face h. */
static void chk_hull_face(const chk *c, size_t h, fdt_vid f[3])
{
    fdt_vid in[3];
    chk_face_of(c, c->hull[h], in);
    f[0] = in[0];
    f[1] = in[2];
    f[2] = in[1];
}

/* Room for a bucket of m entries and the merge sort's buffer. */
static int chk_scratch_reserve(chk *c, size_t m)
{
    if (m <= c->scratch_cap)
        return 0;
    if (m > SIZE_MAX / (2 * sizeof(chk_ent)))
        return FDT_ENOMEM;
    chk_ent *s = realloc(c->scratch, 2 * m * sizeof *s);
    if (!s)
        return FDT_ENOMEM;
    c->scratch = s;
    c->scratch_cap = m;
    return 0;
}

/* ---- steps 1 and 2: points and tets ------------------------------------- */

static int chk_points(chk *c)
{
    for (size_t i = 0; i < 3 * c->n; i++) {
        if (!isfinite(c->xyz[i]))
            return chk_fail(c, FDT_ECHECK,
                            "point %zu has a non-finite coordinate", i / 3);
    }
    return fdt_check_first_points(c->xyz, c->n, c->flags); /* PT_FIRST is 1 */
}

int fdt_check_first_points(const double *xyz, size_t n, uint8_t *first)
{
    if (n == 0)
        return 0;
    fdt_vid *idx = malloc(n * sizeof *idx);
    fdt_vid *tmp = malloc(n * sizeof *tmp);
    if (!idx || !tmp) {
        free(idx);
        free(tmp);
        return FDT_ENOMEM;
    }
    for (size_t i = 0; i < n; i++)
        idx[i] = (fdt_vid)i;
    chk_sort_points(xyz, idx, tmp, n);
    /* fdt_lex_compare compares values, so -0 and +0 fall in one run. */
    first[idx[0]] = 1;
    for (size_t k = 1; k < n; k++) {
        if (fdt_lex_compare(xyz + 3 * (size_t)idx[k - 1], xyz + 3 * (size_t)idx[k]) != 0)
            first[idx[k]] = 1;
    }
    free(idx);
    free(tmp);
    return 0;
}

size_t fdt_check_first_of(const double *xyz, size_t n, size_t v)
{
    for (size_t i = 0; i < n; i++) {
        if (fdt_lex_compare(xyz + 3 * i, xyz + 3 * v) == 0)
            return i;
    }
    return v;
}

#define TET_FMT "tet %zu (%ld %ld %ld %ld)"
#define TET_ARGS(c, t)                                                     \
    (t), (long)chk_tet(c, t)[0], (long)chk_tet(c, t)[1],                  \
        (long)chk_tet(c, t)[2], (long)chk_tet(c, t)[3]

static int chk_tets(chk *c)
{
    for (size_t t = 0; t < c->ntets; t++) {
        const fdt_vid *v = chk_tet(c, t);
        for (int i = 0; i < 4; i++) {
            if (v[i] < 0 || (size_t)v[i] >= c->n)
                return chk_fail(c, FDT_ECHECK,
                                TET_FMT " has vertex id %ld out of range "
                                "[0, %zu)", TET_ARGS(c, t), (long)v[i], c->n);
        }
        for (int i = 0; i < 4; i++) {
            for (int j = i + 1; j < 4; j++) {
                if (v[i] == v[j])
                    return chk_fail(c, FDT_ECHECK,
                                    TET_FMT " repeats vertex %ld",
                                    TET_ARGS(c, t), (long)v[i]);
            }
        }
        for (int i = 0; i < 4; i++) {
            if (!(c->flags[v[i]] & PT_FIRST))
                return chk_fail(c, FDT_ECHECK,
                                TET_FMT " uses vertex %ld, a duplicate of "
                                "point %zu (tets must use the first index "
                                "of each coordinate)", TET_ARGS(c, t),
                                (long)v[i], fdt_check_first_of(c->xyz, c->n, (size_t)v[i]));
        }
        int o = fdt_orient3d(chk_pt(c, v[0]), chk_pt(c, v[1]),
                             chk_pt(c, v[2]), chk_pt(c, v[3]), NULL);
        if (o <= 0)
            return chk_fail(c, FDT_ECHECK, TET_FMT " is %s", TET_ARGS(c, t),
                            o == 0 ? "flat (orient3d = 0)"
                                   : "not positively oriented");
        for (int i = 0; i < 4; i++)
            c->flags[v[i]] |= PT_USED;
    }
    for (size_t i = 0; i < c->n; i++) {
        if ((c->flags[i] & PT_FIRST) && !(c->flags[i] & PT_USED)) {
            const double *p = chk_pt(c, (fdt_vid)i);
            return chk_fail(c, FDT_ECHECK,
                            "point %zu (%.17g %.17g %.17g) is not a vertex "
                            "of any tet", i, p[0], p[1], p[2]);
        }
    }
    return 0;
}

/* ---- step 3: faces, links, local Delaunay -------------------------------- */

/* The smallest vertex of the face opposite vertex i. */
static fdt_vid chk_face_min(const fdt_vid v[4], int i)
{
    fdt_vid m = FDT_VID_MAX;
    for (int k = 0; k < 4; k++) {
        if (k != i && v[k] < m)
            m = v[k];
    }
    return m;
}

static int chk_hull_push(chk *c, uint64_t r)
{
    if (c->nhull == c->hull_cap) {
        size_t cap = c->hull_cap ? 2 * c->hull_cap : 1024;
        uint64_t *h = realloc(c->hull, cap * sizeof *h);
        if (!h)
            return FDT_ENOMEM;
        c->hull = h;
        c->hull_cap = cap;
    }
    c->hull[c->nhull++] = r;
    return 0;
}

static int chk_link(chk *c, uint64_t r, fdt_tid want, const fdt_vid f[3])
{
    if (!c->nbrs || c->nbrs[r] == want)
        return 0;
    size_t t = (size_t)(r >> 2);
    return chk_fail(c, FDT_ECHECK,
                    TET_FMT ": neighbour across face (%ld %ld %ld) opposite "
                    "vertex %ld is %lld, expected %lld", TET_ARGS(c, t),
                    (long)f[0], (long)f[1], (long)f[2],
                    (long)chk_tet(c, t)[r & 3], (long long)c->nbrs[r],
                    (long long)want);
}

/* One run of entries with the same face (sorted triple s). */
static int chk_face_run(chk *c, const chk_ent *e, size_t m, const fdt_vid s[3])
{
    if (m == 1) {
        int err = chk_link(c, e[0].ref, -1, s);
        if (err)
            return err;
        return chk_hull_push(c, e[0].ref);
    }
    /* Same apex twice: the same vertex set, i.e. a tet listed twice. (Only
     * looked for in short runs: a face in thousands of tets must not cost
     * millions of steps to report.) */
    for (size_t i = 0; i < m && m <= 16; i++) {
        for (size_t j = i + 1; j < m; j++) {
            fdt_vid ai = chk_tet(c, (size_t)(e[i].ref >> 2))[e[i].ref & 3];
            fdt_vid aj = chk_tet(c, (size_t)(e[j].ref >> 2))[e[j].ref & 3];
            if (ai == aj) {
                size_t t1 = (size_t)(e[i].ref >> 2);
                size_t t2 = (size_t)(e[j].ref >> 2);
                return chk_fail(c, FDT_ECHECK,
                                TET_FMT " and " TET_FMT " are the same tet "
                                "(listed twice)", TET_ARGS(c, t1),
                                TET_ARGS(c, t2));
            }
        }
    }
    if (m > 2) {
        return chk_fail(c, FDT_ECHECK,
                        "face (%ld %ld %ld) is in %zu tets, at most 2 "
                        "allowed: tets %zu, %zu, %zu", (long)s[0], (long)s[1],
                        (long)s[2], m, (size_t)(e[0].ref >> 2),
                        (size_t)(e[1].ref >> 2), (size_t)(e[2].ref >> 2));
    }
    /* Entries are sorted by parity: opposite orientations are 0 then 1. */
    size_t t1 = (size_t)(e[0].ref >> 2), t2 = (size_t)(e[1].ref >> 2);
    if ((e[0].key & 1) == (e[1].key & 1))
        return chk_fail(c, FDT_ECHECK,
                        TET_FMT " and " TET_FMT " are on the same side of "
                        "their shared face (%ld %ld %ld): they overlap",
                        TET_ARGS(c, t1), TET_ARGS(c, t2), (long)s[0],
                        (long)s[1], (long)s[2]);
    int err = chk_link(c, e[0].ref, (fdt_tid)t2, s);
    if (!err)
        err = chk_link(c, e[1].ref, (fdt_tid)t1, s);
    if (err)
        return err;
    if (!c->dfail.found) {
        const fdt_vid *v = chk_tet(c, t1);
        fdt_vid apex = chk_tet(c, t2)[e[1].ref & 3];
        /* t1 passed step 2, so (v0 v1 v2 v3) is positively oriented, and
         * the five ids are distinct first indices: distinct points. One
         * direction suffices: for the (perturbed) lifted points, apex2
         * inside sphere(t1) and apex1 inside sphere(t2) are the same sign
         * of the same 5-point determinant. */
        int s5 = fdt_insphere_perturbed(chk_pt(c, v[0]), chk_pt(c, v[1]),
                                        chk_pt(c, v[2]), chk_pt(c, v[3]),
                                        chk_pt(c, apex), NULL);
        if (s5 > 0) {
            c->dfail.found = 1;
            c->dfail.t1 = t1;
            c->dfail.t2 = t2;
            memcpy(c->dfail.face, s, sizeof c->dfail.face);
            c->dfail.apex = apex;
        }
    }
    return 0;
}

static int chk_faces(chk *c)
{
    size_t *b = c->bucket;
    memset(b, 0, (c->n + 1) * sizeof *b);
    for (size_t t = 0; t < c->ntets; t++) {
        const fdt_vid *v = chk_tet(c, t);
        for (int i = 0; i < 4; i++)
            b[chk_face_min(v, i) + 1]++;
    }
    for (size_t k = 1; k <= c->n; k++)
        b[k] += b[k - 1];
    for (size_t t = 0; t < c->ntets; t++) {
        const fdt_vid *v = chk_tet(c, t);
        for (int i = 0; i < 4; i++)
            chk_ref_set(c, b[chk_face_min(v, i)]++, 4 * (uint64_t)t + i);
    }
    /* Now bucket a is [a ? b[a-1] : 0, b[a]). */
    size_t maxb = 0;
    for (size_t a = 0; a < c->n; a++) {
        size_t lo = a ? b[a - 1] : 0;
        if (b[a] - lo > maxb)
            maxb = b[a] - lo;
    }
    if (chk_scratch_reserve(c, maxb))
        return FDT_ENOMEM;

    for (size_t a = 0; a < c->n; a++) {
        size_t lo = a ? b[a - 1] : 0, m = b[a] - lo;
        chk_ent *e = c->scratch;
        for (size_t k = 0; k < m; k++) {
            if (k + CHK_AHEAD < m) {
                uint64_t ra = chk_ref_get(c, lo + k + CHK_AHEAD);
                fdt_prefetch(chk_tet(c, (size_t)(ra >> 2)));
                if (c->nbrs)
                    fdt_prefetch(c->nbrs + ra);
            }
            uint64_t r = chk_ref_get(c, lo + k);
            fdt_prefetch(chk_pt(c, chk_tet(c, (size_t)(r >> 2))[r & 3]));
            fdt_vid f[3], s[3];
            chk_face_of(c, r, f);
            unsigned par = chk_sort3(f, s);
            e[k].key = ((uint64_t)s[1] << 33) | ((uint64_t)s[2] << 1) | par;
            e[k].ref = r;
        }
        chk_sort_ents(e, e + m, m);
        for (size_t k = 0; k < m;) {
            size_t j = k + 1;
            while (j < m && (e[j].key >> 1) == (e[k].key >> 1))
                j++;
            fdt_vid s[3] = {(fdt_vid)a, (fdt_vid)(e[k].key >> 33),
                            (fdt_vid)((e[k].key >> 1) & 0xffffffffu)};
            int err = chk_face_run(c, e + k, j - k, s);
            if (err)
                return err;
            k = j;
        }
    }
    return 0;
}

/* ---- step 4: the hull is a closed surface, convex at every edge --------- */

static int chk_hull_edges(chk *c)
{
    /* Impossible after step 3 (positive tets enclose a positive volume,
     * which needs a boundary), but everything below assumes a hull. */
    if (c->nhull == 0)
        return chk_fail(c, FDT_ECHECK, "the mesh has no hull faces");
    size_t *b = c->bucket;
    memset(b, 0, (c->n + 1) * sizeof *b);
    for (size_t h = 0; h < c->nhull; h++) {
        fdt_vid f[3];
        chk_hull_face(c, h, f);
        for (int k = 0; k < 3; k++) {
            fdt_vid u = f[k], w = f[(k + 1) % 3];
            b[(u < w ? u : w) + 1]++;
        }
    }
    for (size_t k = 1; k <= c->n; k++)
        b[k] += b[k - 1];
    uint64_t *er = malloc(3 * c->nhull * sizeof *er);
    if (!er)
        return FDT_ENOMEM;
    for (size_t h = 0; h < c->nhull; h++) {
        fdt_vid f[3];
        chk_hull_face(c, h, f);
        for (int k = 0; k < 3; k++) {
            fdt_vid u = f[k], w = f[(k + 1) % 3];
            er[b[u < w ? u : w]++] = 3 * (uint64_t)h + (uint64_t)k;
        }
    }
    size_t maxb = 0;
    for (size_t a = 0; a < c->n; a++) {
        size_t lo = a ? b[a - 1] : 0;
        if (b[a] - lo > maxb)
            maxb = b[a] - lo;
    }
    int err = chk_scratch_reserve(c, maxb);
    for (size_t a = 0; !err && a < c->n; a++) {
        size_t lo = a ? b[a - 1] : 0, m = b[a] - lo;
        chk_ent *e = c->scratch;
        for (size_t k = 0; k < m; k++) {
            uint64_t r = er[lo + k];
            fdt_vid f[3];
            chk_hull_face(c, (size_t)(r / 3), f);
            fdt_vid u = f[r % 3], w = f[(r % 3 + 1) % 3];
            /* dir 0: the face runs a -> other; dir 1: other -> a. */
            e[k].key = u == (fdt_vid)a ? ((uint64_t)w << 1)
                                       : ((uint64_t)u << 1) | 1;
            e[k].ref = r;
        }
        chk_sort_ents(e, e + m, m);
        for (size_t k = 0; !err && k < m;) {
            size_t j = k + 1;
            while (j < m && (e[j].key >> 1) == (e[k].key >> 1))
                j++;
            long u = (long)a, w = (long)(e[k].key >> 1);
            fdt_vid f1[3], f2[3];
            size_t h1 = (size_t)(e[k].ref / 3);
            size_t h2 = (size_t)(e[j - 1].ref / 3);
            chk_hull_face(c, h1, f1);
            chk_hull_face(c, h2, f2);
            /* After step 3 the directions at an edge balance (the hull is
             * the boundary of the tets), so what can go wrong here is an
             * edge where several sheets meet. */
            if (j - k != 2 || (e[k].key & 1) == (e[k + 1].key & 1)) {
                err = chk_fail(c, FDT_ECHECK,
                               "hull is not a closed surface: hull edge "
                               "(%ld %ld) is in %zu hull faces, e.g. (%ld %ld "
                               "%ld) of tet %zu and (%ld %ld %ld) of tet %zu",
                               u, w, j - k, (long)f1[0], (long)f1[1],
                               (long)f1[2], (size_t)(c->hull[h1] >> 2),
                               (long)f2[0], (long)f2[1], (long)f2[2],
                               (size_t)(c->hull[h2] >> 2));
                break;
            }
            /* f1 holds the edge as a -> w, f2 as w -> a. Convex at the edge
             * iff f2's third vertex is not strictly outside f1 (outward
             * orientation: the interior is on the negative side). The test
             * is symmetric in f1 and f2: both are the sign of one
             * determinant. */
            fdt_vid x2 = f2[(e[k + 1].ref % 3 + 2) % 3];
            int o = fdt_orient3d(chk_pt(c, f1[0]), chk_pt(c, f1[1]),
                                 chk_pt(c, f1[2]), chk_pt(c, x2), NULL);
            if (o > 0) {
                err = chk_fail(c, FDT_ECHECK,
                               "hull is not convex at edge (%ld %ld): vertex "
                               "%ld of hull face (%ld %ld %ld) is outside "
                               "hull face (%ld %ld %ld)", u, w, (long)x2,
                               (long)f2[0], (long)f2[1], (long)f2[2],
                               (long)f1[0], (long)f1[1], (long)f1[2]);
                break;
            }
            k = j;
        }
    }
    free(er);
    return err;
}

/* ---- step 5: the hull winds once ---------------------------------------- */

/*
 * Let O be a point strictly inside tet 0, and G a point strictly inside hull
 * face f0. If O is strictly on the inner side of every hull face, central
 * projection from O maps each hull face onto a positively oriented
 * spherical triangle, and (S being closed, step 4) it is a branched covering
 * of the sphere whose degree d is the number of hull faces the ray O->G
 * meets: around a vertex where S winds k times, or where several sheets
 * touch, every nearby direction has k or more preimages. So d = 1 means S is
 * embedded and star-shaped from O; being convex at every edge, it is then
 * the boundary of a convex polytope (a closed connected locally convex set
 * is convex, Tietze-Nakajima), traversed once. The tets' boundary is S
 * (matched faces cancel), so the number of tets covering a point is the
 * winding number of S around it: 1 inside, 0 outside. (This is the convexity
 * certificate of Mehlhorn et al., "Checking geometric programs or
 * verification of geometric structures", 1999.)
 *
 * O and G are not doubles, so they are symbolic points expressed through
 * double vertices, and only fdt_orient3d on input points is needed:
 *   O = x0 + d (x1 - x0) + d^2 (x2 - x0) + d^3 (x3 - x0)    (x: tet 0)
 *   G = y0 + e (y1 - y0) + e^2 (y2 - y0)                    (y: face f0)
 * with 0 < e << d << 1 (e smaller than any power of d); both lie in the
 * open tet and face. orient3d is affine in each argument, so
 * orient3d(O, u, v, G) = sum_ij lambda_i mu_j orient3d(x_i, u, v, y_j) with
 * barycentric weights lambda, mu; expanding in monomials d^i e^j (ordered by
 * j, then i), the coefficient of each monomial is orient3d(x_i, u, v, y_j)
 * once all earlier ones vanish. Its sign is therefore the first nonzero
 * orient3d(x_i, u, v, y_j) in that order. It cannot be 0 for all twelve:
 * that needs every y_j on the line uv (x spans space), but f0 is not flat.
 */
static int chk_sign_o(const chk *c, const fdt_vid f[3], const fdt_vid x[4])
{
    for (int i = 0; i < 4; i++) {
        int s = fdt_orient3d(chk_pt(c, f[0]), chk_pt(c, f[1]),
                             chk_pt(c, f[2]), chk_pt(c, x[i]), NULL);
        if (s)
            return s;
    }
    return 0;
}

static int chk_sign_og(const chk *c, fdt_vid u, fdt_vid v, const fdt_vid x[4],
                       const fdt_vid y[3])
{
    for (int j = 0; j < 3; j++) {
        for (int i = 0; i < 4; i++) {
            int s = fdt_orient3d(chk_pt(c, x[i]), chk_pt(c, u), chk_pt(c, v),
                                 chk_pt(c, y[j]), NULL);
            if (s)
                return s;
        }
    }
    return 0;
}

static int chk_degree(chk *c)
{
    const fdt_vid *x = chk_tet(c, 0);
    fdt_vid y[3];
    chk_hull_face(c, 0, y);
    size_t count = 0;
    for (size_t h = 0; h < c->nhull; h++) {
        fdt_vid f[3];
        chk_hull_face(c, h, f);
        /* The vertices of tet 0 lie on the inner side of a convex hull's
         * faces, strictly so for at least one of them. */
        if (chk_sign_o(c, f, x) >= 0)
            return chk_fail(c, FDT_ECHECK,
                            "hull is not convex: tet 0 (%ld %ld %ld %ld) is "
                            "not inside hull face (%ld %ld %ld) of tet %zu",
                            (long)x[0], (long)x[1], (long)x[2], (long)x[3],
                            (long)f[0], (long)f[1], (long)f[2],
                            (size_t)(c->hull[h] >> 2));
        /* The ray O->G meets face f iff G is in the cone from O over f:
         * with O on f's inner side that is orient3d(O, u, v, G) >= 0 for
         * each edge (u v) of f, and never 0 here (see above). */
        if (chk_sign_og(c, f[0], f[1], x, y) > 0 &&
            chk_sign_og(c, f[1], f[2], x, y) > 0 &&
            chk_sign_og(c, f[2], f[0], x, y) > 0)
            count++;
    }
    if (count != 1)
        return chk_fail(c, FDT_ECHECK,
                        "the hull surface winds %zu times around the inside "
                        "of tet 0 (ray through hull face (%ld %ld %ld)): the "
                        "tets cover their hull %zu times, not once", count,
                        (long)y[0], (long)y[1], (long)y[2], count);
    return 0;
}

/* ---- entry point --------------------------------------------------------- */

int fdt_check(const double *xyz, size_t n, const fdt_vid *tets, size_t ntets,
              const fdt_tid *nbrs, char *msg, size_t len)
{
    chk c;
    memset(&c, 0, sizeof c);
    c.xyz = xyz;
    c.n = n;
    c.tets = tets;
    c.ntets = ntets;
    c.nbrs = nbrs;
    c.msg = msg;
    c.len = len;
    if (msg && len > 0)
        msg[0] = '\0';

    if ((n > 0 && !xyz) || (ntets > 0 && !tets))
        return chk_fail(&c, FDT_EINVAL, "NULL array with a nonzero count");
    if (n > (size_t)FDT_VID_MAX)
        return chk_fail(&c, FDT_EINVAL, "%zu points: more than FDT_VID_MAX",
                        n);
    /* 4 * ntets face references must fit size_t and fdt_tid. */
    if (ntets > SIZE_MAX / 16 || ntets > (uint64_t)FDT_TID_MAX / 4)
        return chk_fail(&c, FDT_EINVAL, "%zu tets: too many", ntets);
    if (ntets == 0)
        return chk_fail(&c, FDT_ECHECK, "no tetrahedra");

    int err = FDT_ENOMEM;
    c.flags = calloc(n ? n : 1, 1);
    c.bucket = malloc((n + 1) * sizeof *c.bucket);
    c.wide = 4 * (uint64_t)ntets > UINT32_MAX;
    c.refs = malloc(4 * ntets * (c.wide ? sizeof(uint64_t)
                                        : sizeof(uint32_t)));
    if (!c.flags || !c.bucket || !c.refs)
        goto done;

    err = chk_points(&c);
    if (!err)
        err = chk_tets(&c);
    if (!err)
        err = chk_faces(&c);
    /* The face references are not needed past this point. */
    free(c.refs);
    c.refs = NULL;
    if (!err)
        err = chk_hull_edges(&c);
    if (!err)
        err = chk_degree(&c);
    if (!err && c.dfail.found) {
        const chk_delaunay_fail *d = &c.dfail;
        err = chk_fail(&c, FDT_ECHECK,
                       "face (%ld %ld %ld) between " TET_FMT " and " TET_FMT
                       " is not Delaunay: vertex %ld is inside the "
                       "(perturbed) circumsphere of tet %zu",
                       (long)d->face[0], (long)d->face[1], (long)d->face[2],
                       TET_ARGS(&c, d->t1), TET_ARGS(&c, d->t2),
                       (long)d->apex, d->t1);
    }

done:
    if (err == FDT_ENOMEM)
        chk_fail(&c, FDT_ENOMEM, "out of memory");
    free(c.flags);
    free(c.bucket);
    free(c.refs);
    free(c.scratch);
    free(c.hull);
    return err;
}
