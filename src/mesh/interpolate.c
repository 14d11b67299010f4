/*
 * Interpolation of values given at the points (issue 32): the public
 * fdt_interpolate, linear (barycentric in the tet holding the query) or
 * natural-neighbour (Sibson).
 *
 * Sibson's coordinates of a query q are the shares of q's Voronoi cell V+,
 * were q inserted, taken from each old cell: w_i = vol(P_i) / vol(V+),
 * P_i = V+ n V(p_i). Its natural neighbours are the points of the cavity:
 * the tets whose circumsphere holds q strictly (exact insphere from the
 * tet holding q). Each P_i is summed from circumcentres, with no cutting
 * (doc/design.md, natural-neighbour coordinates; Watson 1992 and Hiyoshi-
 * Sugihara sum the same pieces):
 *
 * - The vertices of P_i are the circumcentres c_T of the cavity's tets
 *   that hold p_i (old Voronoi vertices q takes over: they lie in V+) and
 *   c_T' of the new tets T' = (q, F), F a face of the cavity's boundary,
 *   that hold p_i. Its faces: the new face dual to the edge (q, i), whose
 *   vertices are the c_T' around that edge, and for each edge (i, j) of a
 *   cavity tet the part of the old face dual to (i, j) inside V+: the c_T
 *   around the edge, closed, if the edge is on the boundary, by the
 *   segment c_T'1 c_T'2 of the new Voronoi edge dual to (q, i, j).
 * - Each face is a polygon in a plane (the bisector of i and j, or of q
 *   and i) whose edges run along Voronoi edges, one per face of the tets
 *   around: an edge of the polygon between the centres of the two tets on
 *   either side of a face G of the tets. Fanned from the foot f of q on
 *   the plane (the midpoint of q and p_i for the new face), and each
 *   polygon edge split at a point s_G on its line, the polygon's cone from
 *   q is a sum of signed tets (q, f, s_G, c_T), each owned by one tet T and
 *   one of its faces G: det(f - q, s_G - q, c_T - q) / 6, added to P_i and
 *   taken from P_j (the face is P_i's outward, P_j's inward). The sign:
 *   about the edge direction p_j - p_i, face (i, j, k) of T comes before
 *   (i, j, l) when (i, j, k, l) is positively oriented (as in voronoi.c).
 *   The identity (X, a, s) + (X, s, b) = (X, a, b) for s on the line ab
 *   holds for signed dets with any apex, so any s_G on the line serves, as
 *   long as both tets on G use the same point.
 * - Old minus new: the cavity tets add their pieces, the new tets take
 *   theirs away (V(p_i) n V+ is p_i's old cell less its new one, and the
 *   tets outside the cavity are in both). The split points: on a face
 *   between two cavity tets, the centre of the first of them in canonical
 *   order (its own piece there is then nothing); on a boundary face F, the
 *   centre of the new tet (q, F) (the old tet keeps the piece from c_T to
 *   c_T', the new tet's is nothing); on a new face (q, i, j), the centre
 *   of the first of its two new tets. Each split point is thus an end of
 *   its segment, so no piece reaches beyond the polygon (pair_new_faces
 *   says what another choice cost).
 *
 * Every point in these sums (feet, split points, centres of the cavity's
 * tets, which lie in V+) lies within V+'s circumradius of q, so the terms
 * are of V+'s size and cancel little; all of them are relative to q. The
 * centres come from fdt_circumcenter (floating, double words, exact by the
 * tet's flatness). Against exact rationals the coordinates are within a
 * few ulps on uniform and lattice points and 5e-14 next to 1e-3 wide
 * clusters (bench/NOTES.md entry 95).
 * A query costs O(cavity): no m^2 cuts.
 *
 * The coordinates reproduce linear functions (sum w_i p_i = q); a query
 * outside the hull or on it gets NaN (its new cell is unbounded), a query
 * at a point that point's value. Every number is computed from the
 * points' ids and coordinates in a canonical order (each tet's points by
 * id, the cavity's tets by those ids), so the values are the same bits for
 * any thread count, query order and numbering of the mesh's tets.
 *
 * The same code answers on a patch of a periodic mesh
 * (src/mesh/periodic_interp.c): a cavity that reaches the patch's edge
 * (FDT_NB_CUT) is reported, not summed, and asked again of a larger one.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/spawn.h"
#include "geom/predicates.h"
#include "mesh/locate.h"
#include "mesh/result.h"
#include "mesh/voronoi.h"

typedef struct ctet ctet;
typedef struct ntet ntet;

/* An entry of the table of tets met (tab_find). */
typedef struct tslot {
    fdt_tid t;      /* a tet, or a boundary edge's negative key */
    uint32_t stamp; /* the query that entered it; 0: never */
    int at;         /* a tet's place in S->cavity, then S->ct (-1: tested
                       outside); an edge's first new tet, 4 b + face */
} tslot;

/* One thread's scratch, kept from query to query. */
typedef struct sibson {
    const fdt_locator *L;    /* shared, read only */
    fdt_tid *stack, *cavity; /* growable lists of tets (owned) */
    size_t cap_stack, cap_cavity;
    tslot *tab;              /* the tets met (tab_find; owned) */
    size_t tab_mask, tab_used;
    uint32_t stamp;
    ctet *ct;                /* the cavity's tets, canonically (owned) */
    size_t cap_ct;
    ntet *nt;                /* the new tets (owned) */
    size_t cap_nt;
    fdt_vid *nn;             /* natural neighbours (owned) */
    size_t cap_nn;
    double *w;               /* their coordinates (owned) */
    size_t cap_w;
    size_t nc;               /* the last query's cavity tets, in ct */
    double min_edge;         /* the shortest Delaunay edge whose cells
                                doubles hold (FDT_VORONOI_BOX_EXP) */
} sibson;

static int push(void *pp, size_t *cap, size_t n, size_t size)
{
    if (n < *cap)
        return 0;
    size_t nc = *cap ? 2 * *cap : 64;
    void **p = (void **)pp;
    void *q = realloc(*p, nc * size);
    if (!q)
        return -1;
    *p = q;
    *cap = nc;
    return 0;
}

/* The tets the cavity search met, and where: an open-addressing table
 * keyed by tet id, an entry current when its stamp is the query's (no
 * clearing between queries). at: the place in S->cavity, then in S->ct
 * (canonical_cavity renumbers), or -1 for a tet tested and found outside.
 * A cavity's tet has four neighbours, so a linear search of the cavity
 * for each would cost O(cavity^2): a fifth of a query's time. */
static tslot *tab_find(const sibson *S, fdt_tid t)
{
    size_t h = (size_t)(((uint64_t)t * 0x9E3779B97F4A7C15u) >> 32) & S->tab_mask;
    while (S->tab[h].stamp == S->stamp && S->tab[h].t != t)
        h = (h + 1) & S->tab_mask;
    return &S->tab[h];
}

/* Enters t (absent) at `at`, doubling the table beyond half full. 0, or -1
 * out of memory. */
static int tab_put(sibson *S, fdt_tid t, int at)
{
    if (2 * (S->tab_used + 1) > S->tab_mask + 1) {
        size_t size = 2 * (S->tab_mask + 1);
        tslot *old = S->tab, *nt = calloc(size, sizeof *nt);
        if (!nt)
            return -1;
        size_t oldsize = S->tab_mask + 1;
        S->tab = nt;
        S->tab_mask = size - 1;
        for (size_t i = 0; i < oldsize; i++)
            if (old[i].stamp == S->stamp)
                *tab_find(S, old[i].t) = old[i];
        free(old);
    }
    *tab_find(S, t) = (tslot){t, S->stamp, at};
    S->tab_used++;
    return 0;
}

/* A new query's table: a new stamp (the table cleared when they wrap). */
static int tab_begin(sibson *S)
{
    if (!S->tab) {
        S->tab = calloc(256, sizeof *S->tab);
        if (!S->tab)
            return -1;
        S->tab_mask = 255;
    }
    if (++S->stamp == 0) {
        memset(S->tab, 0, (S->tab_mask + 1) * sizeof *S->tab);
        S->stamp = 1;
    }
    S->tab_used = 0;
    return 0;
}

/* What coordinates() and the steps under it return besides a count:
 * COORD_ROUNDING, a tet of points that stand for others (a patch's rounded
 * images: the locator's rounded) flat in them, where the points they stand
 * for are not (gen_points cone periodic on x and y: four points on two
 * circles across the periods, 2e-20 thick with the exact images). */
enum { COORD_NOMEM = -1, COORD_BUG = -2, COORD_CUT = -3, COORD_ROUNDING = -4 };

/* Whether the face of cavity tet t opposite its vertex i, shared with tet
 * u, is Delaunay in the locator's points: u's other vertex not strictly
 * inside t's sphere. A periodic patch's tets are the Delaunay mesh of the
 * exact images; where rounding them breaks that (points on circles or a
 * grid across the periods), a cavity found in the rounded ones is not the
 * Delaunay one of either (gen_points ogrid periodic in x, y, z: values 4 %
 * off the replicated mesh's). */
static int face_delaunay(const sibson *S, fdt_tid t, fdt_tid u)
{
    const double *X = S->L->xyz;
    const fdt_vid *tv = S->L->tets + 4 * (size_t)t, *uv = S->L->tets + 4 * (size_t)u;
    for (int k = 0; k < 4; k++)
        if (uv[k] != tv[0] && uv[k] != tv[1] && uv[k] != tv[2] && uv[k] != tv[3])
            return fdt_insphere(X + 3 * (size_t)tv[0], X + 3 * (size_t)tv[1],
                                X + 3 * (size_t)tv[2], X + 3 * (size_t)tv[3],
                                X + 3 * (size_t)uv[k], NULL) <= 0;
    return 0;
}

/* The cavity of q from tet t0 (which holds q): every tet reached across
 * faces whose circumsphere holds q strictly. Returns its size, or
 * COORD_NOMEM, or COORD_CUT when it meets a patch's edge, or (rounded
 * points) COORD_ROUNDING when a face of a cavity tet is not Delaunay in
 * them. */
static long cavity(sibson *S, fdt_tid t0, const double *q)
{
    const double *X = S->L->xyz;
    size_t nc = 0, ns = 0;
    if (tab_begin(S) || tab_put(S, t0, 0) ||
        push(&S->cavity, &S->cap_cavity, 0, sizeof *S->cavity) ||
        push(&S->stack, &S->cap_stack, 0, sizeof *S->stack))
        return COORD_NOMEM;
    S->cavity[nc++] = t0;
    S->stack[ns++] = t0;
    while (ns) {
        fdt_tid t = S->stack[--ns];
        for (int i = 0; i < 4; i++) {
            fdt_tid u = S->L->nbrs[4 * (size_t)t + (size_t)i];
            if (u == FDT_NB_CUT)
                return COORD_CUT;
            if (u >= 0 && S->L->rounded && !face_delaunay(S, t, u))
                return COORD_ROUNDING;
            if (u < 0 || tab_find(S, u)->stamp == S->stamp)
                continue; /* the hull, or met before */
            const fdt_vid *tv = S->L->tets + 4 * (size_t)u;
            int in = fdt_insphere(X + 3 * (size_t)tv[0], X + 3 * (size_t)tv[1],
                                  X + 3 * (size_t)tv[2], X + 3 * (size_t)tv[3], q, NULL) > 0;
            if (tab_put(S, u, in ? (int)nc : -1))
                return -1;
            if (!in)
                continue;
            if (push(&S->cavity, &S->cap_cavity, nc, sizeof *S->cavity) ||
                push(&S->stack, &S->cap_stack, ns, sizeof *S->stack))
                return -1;
            S->cavity[nc++] = u;
            S->stack[ns++] = u;
        }
    }
    return (long)nc;
}

/* A cavity tet in canonical order: its points by ascending id, so that
 * every number computed from it is the same whichever way round the mesh
 * stores it (that may change with the triangulation's thread count). */
struct ctet {
    fdt_tid t;
    fdt_vid v[4];  /* ascending */
    int at[4];     /* v's places among the natural neighbours */
    int mi[4];     /* v's places in the mesh's tet */
    int sigma;     /* the orientation of (v0, v1, v2, v3): +1 or -1 */
    int split[4];  /* the face opposite v[m]: where its Voronoi edge is
                      split (the file's comment) */
    double c[3];   /* circumcentre, relative to q */
};

/* A new tet: q and a face (v0, v1, v2) of the cavity's boundary. */
struct ntet {
    fdt_vid v[3];  /* ascending */
    int at[3];
    int sigma;     /* the orientation of (q, v0, v1, v2) */
    int split[4];  /* the face opposite vertex f (0: q, 1..3: v[f - 1]):
                      the new tet whose centre splits its Voronoi edge */
    double c[3];   /* circumcentre, relative to q */
};

static double det3(const double *a, const double *b, const double *c)
{
    return a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) +
           a[2] * (b[0] * c[1] - b[1] * c[0]);
}

/* The foot of q on the bisector plane of a and b, relative to q: the
 * centre of the fan of that plane's polygon (ids a < b: the same bits for
 * every tet around the edge). */
static void foot(const double *a, const double *b, const double *q, double f[3])
{
    double d[3], s[3];
    for (int k = 0; k < 3; k++) {
        d[k] = b[k] - a[k];
        s[k] = (a[k] - q[k]) + (b[k] - q[k]);
    }
    double t = 0.5 * (s[0] * d[0] + s[1] * d[1] + s[2] * d[2]) /
               (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    for (int k = 0; k < 3; k++)
        f[k] = t * d[k];
}

static int vid_less4(const fdt_vid *a, const fdt_vid *b)
{
    for (int k = 0; k < 4; k++)
        if (a[k] != b[k])
            return a[k] < b[k];
    return 0;
}

/* qsort's orders: cavity tets by their ids (distinct tets, so never
 * equal), point ids */
static int ctet_cmp(const void *x, const void *y)
{
    const ctet *a = x, *b = y;
    return vid_less4(a->v, b->v) ? -1 : vid_less4(b->v, a->v) ? 1 : 0;
}

static int vid_cmp(const void *x, const void *y)
{
    fdt_vid a = *(const fdt_vid *)x, b = *(const fdt_vid *)y;
    return (a > b) - (a < b);
}

/* place of id among the m natural neighbours (ascending; it is there) */
static int nn_at(const fdt_vid *nn, long m, fdt_vid id)
{
    long lo = 0, hi = m - 1;
    while (lo < hi) {
        long mid = (lo + hi) / 2;
        if (nn[mid] < id)
            lo = mid + 1;
        else
            hi = mid;
    }
    return (int)lo;
}

/* The cavity's tets in canonical order (their ids ascending, the tets by
 * those ids), their circumcentres, and the natural neighbours (their
 * points, ascending) into S->nn. Returns m, or -1 out of memory, -2 a flat
 * tet (a bug; COORD_ROUNDING where the points stand for others). */
static long canonical_cavity(sibson *S, size_t nc, const double *q)
{
    const double *X = S->L->xyz;
    while (S->cap_ct < nc)
        if (push(&S->ct, &S->cap_ct, S->cap_ct, sizeof *S->ct))
            return -1;
    for (size_t a = 0; a < nc; a++) {
        ctet T;
        T.t = S->cavity[a];
        const fdt_vid *tv = S->L->tets + 4 * (size_t)T.t;
        T.sigma = 1;
        for (int x = 0; x < 4; x++) {
            int y = x;
            for (; y > 0 && T.v[y - 1] > tv[x]; y--) {
                T.v[y] = T.v[y - 1];
                T.mi[y] = T.mi[y - 1];
                T.sigma = -T.sigma;
            }
            T.v[y] = tv[x];
            T.mi[y] = x;
        }
        S->ct[a] = T;
    }
    /* Sorted, not inserted one by one: a cavity holds some tens of tets
     * inside a cloud, but all of a curve's (gen_points helix: 20k tets,
     * a minute a query when both sorts were insertions). */
    qsort(S->ct, nc, sizeof *S->ct, ctet_cmp);
    for (size_t a = 0; a < nc; a++)
        tab_find(S, S->ct[a].t)->at = (int)a;
    while (S->cap_nn < 4 * nc)
        if (push(&S->nn, &S->cap_nn, S->cap_nn, sizeof *S->nn))
            return -1;
    for (size_t a = 0; a < nc; a++)
        memcpy(S->nn + 4 * a, S->ct[a].v, sizeof S->ct[a].v);
    qsort(S->nn, 4 * nc, sizeof *S->nn, vid_cmp);
    long m = 0;
    for (size_t k = 0; k < 4 * nc; k++)
        if (m == 0 || S->nn[m - 1] != S->nn[k])
            S->nn[m++] = S->nn[k];
    for (size_t a = 0; a < nc; a++) {
        ctet *T = &S->ct[a];
        const double *p[4];
        for (int i = 0; i < 4; i++) {
            T->at[i] = nn_at(S->nn, m, T->v[i]);
            p[i] = X + 3 * (size_t)T->v[i];
        }
        double cc[3];
        if (fdt_circumcenter(p[0], p[1], p[2], p[3], cc))
            return S->L->rounded ? COORD_ROUNDING : -2;
        for (int k = 0; k < 3; k++)
            T->c[k] = (p[0][k] - q[k]) + cc[k];
    }
    return m;
}

/* Where the Voronoi edge of each face of each cavity tet is split
 * (split[m]): a face between two cavity tets at the centre of the first
 * of them in canonical order (that one's own share along it is then
 * nothing), a face of the boundary at the centre of its new tet, which is
 * made here (split -1 - its index). Returns the number of new tets, or -1
 * out of memory, -2 a flat new tet inside the hull (a bug; COORD_ROUNDING
 * where the points stand for others), -3 q on the hull (in the plane of a
 * hull face). */
static long boundary(sibson *S, size_t nc, const double *q)
{
    const double *X = S->L->xyz;
    size_t nb = 0;
    for (size_t a = 0; a < nc; a++) {
        ctet *T = &S->ct[a];
        for (int m = 0; m < 4; m++) {
            fdt_tid u = S->L->nbrs[4 * (size_t)T->t + (size_t)T->mi[m]];
            /* The search met every neighbour of the cavity (tested in or
             * out); the stamp check only guards that. */
            const tslot *e = u < 0 ? NULL : tab_find(S, u);
            int b = e && e->stamp == S->stamp ? e->at : -1;
            if (b >= 0) {
                T->split[m] = (int)a < b ? (int)a : b;
                continue;
            }
            if (push(&S->nt, &S->cap_nt, nb, sizeof *S->nt))
                return -1;
            ntet *N = &S->nt[nb];
            for (int i = 0, y = 0; i < 4; i++)
                if (i != m) {
                    N->v[y] = T->v[i];
                    N->at[y++] = T->at[i];
                }
            /* q lies on the cavity's side of the face, as T's vertex m
             * does: (q, face) has T's orientation once q, put where v[m]
             * was, moves to the front (m transpositions). */
            N->sigma = m % 2 ? -T->sigma : T->sigma;
            if (fdt_circumcenter(q, X + 3 * (size_t)N->v[0], X + 3 * (size_t)N->v[1],
                                 X + 3 * (size_t)N->v[2], N->c))
                return u < 0 ? -3 : S->L->rounded ? COORD_ROUNDING : -2;
            T->split[m] = -1 - (int)nb;
            nb++;
        }
    }
    return (long)nb;
}

/* The new tets across each new face (q, x, y): the two whose boundary
 * faces share the edge (x, y) (the boundary is a closed surface, each edge
 * on two faces). Found through the table of tets, keyed by the edge's two
 * local numbers as a negative id (tets' are not), so a query costs O(new
 * tets). The split point of the Voronoi edge between them is the centre
 * of the first in order: an end of the segment, so no piece reaches
 * beyond it (a triangle's circumcentre, the first choice, lies on the
 * line anywhere and cancelled 3e4 times a long thin cell's volume near
 * clusters, 3e-13 off). 0, -1 out of memory, -2 an edge without its pair
 * (a bug). */
static int pair_new_faces(sibson *S, size_t nb)
{
    for (size_t b = 0; b < nb; b++) {
        ntet *N = &S->nt[b];
        N->split[0] = (int)b; /* the boundary face: the old tet's piece */
        for (int f = 1; f < 4; f++) {
            N->split[f] = -1;
            int x = f == 1 ? 1 : 0, y = f == 3 ? 1 : 2; /* the edge: v[x], v[y] */
            fdt_tid key = -1 - (((fdt_tid)N->at[x] << 31) | N->at[y]);
            tslot *e = tab_find(S, key);
            if (e->stamp != S->stamp) {
                if (tab_put(S, key, 4 * (int)b + f))
                    return -1;
                continue;
            }
            int p = e->at / 4, first = p < (int)b ? p : (int)b;
            N->split[f] = first;
            S->nt[p].split[e->at % 4] = first;
        }
    }
    for (size_t b = 0; b < nb; b++)
        for (int f = 1; f < 4; f++)
            if (S->nt[b].split[f] < 0)
                return -2;
    return 0;
}

/* Each natural neighbour's stolen volume (times 6) into S->w[0 .. m),
 * summed as the file's comment derives: the cavity tets add their shares,
 * the new tets take theirs away. */
static void sibson_shares(sibson *S, size_t nc, size_t nb, long m, const double *q)
{
    const double *X = S->L->xyz;
    for (long k = 0; k < m; k++)
        S->w[k] = 0;
    for (size_t a = 0; a < nc; a++) {
        const ctet *T = &S->ct[a];
        const double *sp[4];
        for (int f = 0; f < 4; f++)
            sp[f] = T->split[f] == (int)a ? NULL
                    : T->split[f] >= 0   ? S->ct[T->split[f]].c
                                         : S->nt[-1 - T->split[f]].c;
        for (int e = 0; e < 6; e++) {
            const int *te = fdt_tet_edge[e];
            int i = te[0], j = te[1], k = te[2], l = te[3];
            double f[3], v = 0;
            foot(X + 3 * (size_t)T->v[i], X + 3 * (size_t)T->v[j], q, f);
            if (sp[l])
                v += det3(f, sp[l], T->c);
            if (sp[k])
                v -= det3(f, sp[k], T->c);
            v *= T->sigma * te[4];
            S->w[T->at[i]] += v;
            S->w[T->at[j]] -= v;
        }
    }
    for (size_t b = 0; b < nb; b++) {
        const ntet *N = &S->nt[b];
        /* g[f]: where the Voronoi edge of the face opposite vertex f is
         * split (pair_new_faces), NULL at the tet's own centre. Vertex 0
         * is q, 1..3 N->v. */
        const double *g[4];
        for (int f = 0; f < 4; f++)
            g[f] = N->split[f] == (int)b ? NULL : S->nt[N->split[f]].c;
        const double *p[4] = {q, X + 3 * (size_t)N->v[0], X + 3 * (size_t)N->v[1],
                              X + 3 * (size_t)N->v[2]};
        for (int e = 0; e < 6; e++) {
            const int *te = fdt_tet_edge[e];
            int i = te[0], j = te[1], k = te[2], l = te[3];
            double f[3], v = 0;
            if (i == 0)
                for (int d = 0; d < 3; d++)
                    f[d] = 0.5 * (p[j][d] - q[d]);
            else
                foot(p[i], p[j], q, f);
            if (g[l])
                v += det3(f, g[l], N->c);
            if (g[k])
                v -= det3(f, g[k], N->c);
            v *= -N->sigma * te[4];
            if (i != 0)
                S->w[N->at[i - 1]] += v;
            S->w[N->at[j - 1]] -= v;
        }
    }
}

/* Sibson's coordinates of q (held by tet t0) into S->w over S->nn[0..m).
 * Returns m, 0 when q lies on the hull (its new cell is unbounded),
 * COORD_NOMEM, COORD_BUG (a computation that failed), COORD_CUT. */
static long coordinates(sibson *S, fdt_tid t0, const double *q)
{
    const double *X = S->L->xyz;
    const fdt_vid *tv = S->L->tets + 4 * (size_t)t0;
    for (int i = 0; i < 4; i++) /* q at a point: that point alone */
        if (X[3 * (size_t)tv[i]] == q[0] && X[3 * (size_t)tv[i] + 1] == q[1] &&
            X[3 * (size_t)tv[i] + 2] == q[2]) {
            if (push(&S->nn, &S->cap_nn, 0, sizeof *S->nn) ||
                push(&S->w, &S->cap_w, 0, sizeof *S->w))
                return COORD_NOMEM;
            S->nn[0] = tv[i];
            S->w[0] = 1;
            return 1;
        }
    long nc = cavity(S, t0, q);
    if (nc < 0)
        return nc;
    S->nc = (size_t)nc; /* canonical_cavity fills ct before it can fail */
    long m = canonical_cavity(S, (size_t)nc, q);
    if (m < 0)
        return m;
    long nb = boundary(S, (size_t)nc, q);
    if (nb == -3)
        return 0;
    if (nb < 0)
        return nb;
    int got = pair_new_faces(S, (size_t)nb);
    if (got < 0)
        return got;
    while (S->cap_w < (size_t)m)
        if (push(&S->w, &S->cap_w, S->cap_w, sizeof *S->w))
            return COORD_NOMEM;
    sibson_shares(S, (size_t)nc, (size_t)nb, m, q);
    double total = 0;
    for (long k = 0; k < m; k++)
        total += S->w[k];
    if (!(total > 0))
        return COORD_BUG;
    for (long k = 0; k < m; k++)
        S->w[k] /= total;
    return m;
}

/* Why a query's coordinates could not be computed: FDT_ERANGE when its
 * cavity has a Delaunay edge shorter than the cells of its points can be
 * (fdt_voronoi_resolution's rule, FDT_VORONOI_BOX_EXP: gen_points mixed,
 * points 1e-150 and 1e150 apart, failed so), *a and *b the least such
 * edge's points; else FDT_EINTERNAL (a bug). */
static int too_close(const sibson *S, fdt_vid *a, fdt_vid *b)
{
    const double *X = S->L->xyz;
    *a = *b = -1;
    for (size_t c = 0; c < S->nc; c++)
        for (int e = 0; e < 6; e++) {
            fdt_vid u = S->ct[c].v[fdt_tet_edge[e][0]], v = S->ct[c].v[fdt_tet_edge[e][1]];
            if (fdt_cheb(X + 3 * (size_t)u, X + 3 * (size_t)v) < S->min_edge &&
                (*a < 0 || fdt_edge_less(u, v, *a, *b))) {
                *a = u < v ? u : v;
                *b = u < v ? v : u;
            }
        }
    return *a < 0 ? FDT_EINTERNAL : FDT_ERANGE;
}

/* One thread's run of the queries. */
typedef struct ijob {
    fdt_query_run run; /* first: fdt_queries_begin fills it */
    sibson S;
    const fdt_vid *src;       /* each point's row of values (NULL: its own) */
    const double *values;
    size_t nv;
    fdt_interp method;
    double *out;
    uint8_t *cut;             /* the queries whose cavity met a patch's edge */
    int err;
    size_t bad;               /* the query that failed */
    fdt_vid short_a, short_b; /* FDT_ERANGE: the edge too short (too_close) */
    int rounding;             /* FDT_ERANGE: a tet flat by rounding (COORD_ROUNDING) */
} ijob;

/* Point v's row of values. */
static size_t row_of(const ijob *j, fdt_vid v)
{
    return j->src ? (size_t)j->src[v] : (size_t)v;
}

static void *interpolate_run(void *arg)
{
    ijob *j = arg;
    sibson *S = &j->S;
    size_t hint = 0, nv = j->nv;
    for (size_t i = 0; i < j->run.count && !j->err; i++) {
        size_t k = j->run.order[i];
        const double *qk = j->run.q + 3 * k;
        double *o = j->out + nv * k;
        for (size_t c = 0; c < nv; c++)
            o[c] = NAN;
        fdt_tid t = fdt_locate_one(S->L, &hint, qk);
        if (t < 0)
            continue;
        const fdt_vid *tv = S->L->tets + 4 * (size_t)t;
        if (j->method == FDT_INTERP_LINEAR) {
            double b[4];
            fdt_barycentric(S->L, t, qk, b);
            for (size_t c = 0; c < nv; c++) {
                o[c] = 0;
                for (int v = 0; v < 4; v++)
                    o[c] += b[v] * j->values[nv * row_of(j, tv[v]) + c];
            }
            continue;
        }
        long m = coordinates(S, t, qk);
        if (m == 0)
            continue; /* on the hull: NaN */
        if (m == COORD_CUT && j->cut) {
            j->cut[k] = 1;
            continue;
        }
        if (m < 0) {
            j->rounding = m == COORD_ROUNDING;
            j->err = m == COORD_NOMEM  ? FDT_ENOMEM
                     : j->rounding ? FDT_ERANGE
                                   : too_close(S, &j->short_a, &j->short_b);
            j->bad = k;
            break;
        }
        for (size_t c = 0; c < nv; c++) {
            o[c] = 0;
            for (long v = 0; v < m; v++)
                o[c] += S->w[v] * j->values[nv * row_of(j, S->nn[v]) + c];
        }
    }
    return NULL;
}

int fdt_interpolate_frame(const double *xyz, size_t n, fdt_interp method, double *min_edge)
{
    /* Sibson's coordinates are ratios of volumes, products of up to six
     * coordinate differences in the circumcentres: for points whose box
     * is outside 2^-100 .. 2^100 (1e-151 and 1e149 apart: an internal
     * error) they are computed on the points and queries scaled. */
    fdt_voronoi_options vo;
    fdt_default_voronoi_options(&vo);
    double box[6], side = 0;
    int e = 0;
    if (method == FDT_INTERP_NATURAL && fdt_voronoi_box_of(xyz, NULL, n, &vo, box, NULL, 0) == FDT_OK)
        side = fdt_box_side(box);
    if (side > 0)
        (void)frexp(side, &e);
    if (e >= -100 && e <= 100)
        e = 0;
    *min_edge = ldexp(side, FDT_VORONOI_BOX_EXP - e);
    return e;
}

int fdt_interpolate_with(const fdt_locator *L, const fdt_vid *src, const double *values,
                         size_t nv, const double *q, size_t nq, fdt_interp method, int threads,
                         double *out, uint8_t *cut, double min_edge, const double *q_named,
                         char *diag, size_t diag_size)
{
    uint32_t *order;
    void *jp;
    int err = fdt_queries_begin(L, q, nq, &threads, &order, sizeof(ijob), &jp);
    if (err)
        return err;
    ijob *jobs = jp;
    for (int t = 0; t < threads; t++) {
        ijob *j = &jobs[t];
        j->S.L = L;
        j->src = src;
        j->values = values;
        j->nv = nv;
        j->method = method;
        j->out = out;
        j->cut = cut;
        j->S.min_edge = min_edge;
    }
    fdt_fork_join(jobs, sizeof *jobs, threads, interpolate_run);
    for (int t = 0; t < threads; t++) {
        ijob *j = &jobs[t];
        if (j->err && !err) {
            err = j->err;
            const double *qk = q_named + 3 * j->bad;
            if (err == FDT_EINTERNAL && diag && diag_size)
                snprintf(diag, diag_size, "natural-neighbour coordinates of query %zu "
                         "(%.17g %.17g %.17g) could not be computed (a bug: please report)",
                         j->bad, qk[0], qk[1], qk[2]);
            if (err == FDT_ERANGE && j->rounding && diag && diag_size)
                snprintf(diag, diag_size, "natural-neighbour coordinates of query %zu "
                         "(%.17g %.17g %.17g) need a part of the periodic mesh that is not "
                         "Delaunay in the images rounded to doubles (points on a grid, circles "
                         "or spheres across the periods; exact images, and so no such part, "
                         "where the box's sides and the points are binary fractions of the "
                         "periods): --method linear answers there", j->bad, qk[0], qk[1], qk[2]);
            else if (err == FDT_ERANGE && diag && diag_size)
                snprintf(diag, diag_size, "natural-neighbour coordinates of query %zu "
                         "(%.17g %.17g %.17g) need the Voronoi cells of points %zu and %zu, "
                         "closer than doubles can hold the cells between (a Delaunay edge must "
                         "be at least 2^%d of the box)", j->bad, qk[0], qk[1], qk[2],
                         row_of(j, j->short_a), row_of(j, j->short_b), FDT_VORONOI_BOX_EXP);
        }
        free(j->S.ct);
        free(j->S.nt);
        free(j->S.tab);
        free(j->S.stack);
        free(j->S.cavity);
        free(j->S.nn);
        free(j->S.w);
    }
    fdt_queries_end(order, jobs);
    return err;
}
