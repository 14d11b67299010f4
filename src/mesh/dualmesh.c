/*
 * The Voronoi diagram clipped by a box as one polyhedral mesh (see
 * dualmesh.h; doc/design.md, "The dual as a polyhedral mesh").
 *
 * Everything is keyed by the Delaunay primitive it is dual to, so that a
 * vertex or a face is computed once and every cell that has it names it
 * by the same number:
 *  - a Voronoi vertex is a tet's circumcentre; neighbouring tets whose
 *    five points are cospherical (unperturbed exact insphere = 0) have the
 *    same one, and are merged with a union-find: a lattice's cube is one
 *    vertex, not six at one place;
 *  - a Voronoi face is a Delaunay edge (a, b), a < b: the circumcentres of
 *    the tets about it, counter-clockwise about b - a (so the right-hand
 *    normal points from cell a, the owner, to cell b); a hull edge's face
 *    is open, with a ray out of each of its two hull faces (the ray of a
 *    hull face goes from its tet's circumcentre along the outward normal;
 *    adjacent coplanar hull faces whose tets share a vertex share it);
 *  - each face is clipped by the six walls in turn (Sutherland-Hodgman in
 *    homogeneous coordinates, so the rays and the edge at infinity clip
 *    like segments). Every in/out decision compares a stored coordinate
 *    with the wall's bound, so the faces that share a Voronoi edge decide
 *    alike; the point where a Voronoi edge (a pair of merged vertices) or
 *    a ray crosses a wall is computed once, from the whole edge, and kept
 *    under that key; a point where a face's own clipped edge crosses a
 *    second wall (on a box edge) belongs to that face alone. A crossing's
 *    coordinate on its wall is the bound itself, exactly;
 *  - a face left with fewer than 3 distinct vertices has no area and is
 *    dropped (its cells then share no face);
 *  - a cell's face on a wall is chained from the edges that only one of
 *    the cell's faces uses (turned round), the chains put in the order of
 *    their starts round the wall's rim, with the box corners nearest to
 *    the cell's point; an edge along a box edge goes to the wall the cell
 *    touches there;
 *  - the points are scaled by a power of two (exactly) so that the box is
 *    about 1 wide, the vertices scaled back at the end.
 * The result is checked (fdt_dualmesh_check) before it is handed out: a
 * configuration this cannot number (cells too small for doubles beside
 * the box) is an error, never a broken mesh.
 */
#include "mesh/dualmesh.h"
#include "base/mem.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/diag.h"
#include "base/hash.h"
#include "base/sortu64.h"
#include "geom/predicates.h"
#include "mesh/locate.h"
#include "mesh/result.h"
#include "mesh/voronoi.h"

const char *const fdt_dualmesh_patch[6] = {"xmin", "xmax", "ymin", "ymax", "zmin", "zmax"};

/* ------------------------------------------------------------ small tools */

/* Open addressing from a pair of 64-bit keys to an index. */
typedef struct kmap {
    uint64_t *k;  /* 2 a slot; k[0] == UINT64_MAX: empty */
    int64_t *val;
    size_t cap, count;
} kmap;

static int kmap_init(kmap *m, size_t expect)
{
    m->cap = 64;
    while (m->cap < 2 * expect)
        m->cap *= 2;
    m->count = 0;
    m->k = malloc(2 * m->cap * sizeof *m->k);
    m->val = malloc(m->cap * sizeof *m->val);
    if (!m->k || !m->val)
        return -1;
    memset(m->k, 0xff, 2 * m->cap * sizeof *m->k);
    return 0;
}

static void kmap_free(kmap *m)
{
    free(m->k);
    free(m->val);
    memset(m, 0, sizeof *m);
}

static size_t kmap_slot(const kmap *m, uint64_t a, uint64_t b)
{
    size_t i = (size_t)fdt_mix64(a * 0x9e3779b97f4a7c15ull ^ fdt_mix64(b)) & (m->cap - 1);
    while (m->k[2 * i] != UINT64_MAX && (m->k[2 * i] != a || m->k[2 * i + 1] != b))
        i = (i + 1) & (m->cap - 1);
    return i;
}

/* The value under (a, b), or -1. a is never UINT64_MAX. */
static int64_t kmap_get(const kmap *m, uint64_t a, uint64_t b)
{
    size_t i = kmap_slot(m, a, b);
    return m->k[2 * i] == UINT64_MAX ? -1 : m->val[i];
}

static int kmap_put(kmap *m, uint64_t a, uint64_t b, int64_t v)
{
    if (2 * (m->count + 1) > m->cap) {
        kmap old = *m;
        if (kmap_init(m, old.cap) != 0) {
            kmap_free(m);
            *m = old;
            return -1;
        }
        for (size_t i = 0; i < old.cap; i++)
            if (old.k[2 * i] != UINT64_MAX) {
                size_t j = kmap_slot(m, old.k[2 * i], old.k[2 * i + 1]);
                m->k[2 * j] = old.k[2 * i];
                m->k[2 * j + 1] = old.k[2 * i + 1];
                m->val[j] = old.val[i];
            }
        m->count = old.count;
        kmap_free(&old);
    }
    size_t i = kmap_slot(m, a, b);
    if (m->k[2 * i] == UINT64_MAX)
        m->count++;
    m->k[2 * i] = a;
    m->k[2 * i + 1] = b;
    m->val[i] = v;
    return 0;
}

static int64_t uf_find(int64_t *uf, int64_t x)
{
    while (uf[x] != x) {
        uf[x] = uf[uf[x]];
        x = uf[x];
    }
    return x;
}

/* The lower root becomes the root: the same roots for every order. */
static void uf_union(int64_t *uf, int64_t a, int64_t b)
{
    a = uf_find(uf, a);
    b = uf_find(uf, b);
    if (a < b)
        uf[b] = a;
    else if (b < a)
        uf[a] = b;
}

/* ------------------------------------------------------------ the work */

/* An entry of a face being clipped: a point (homogeneous: h[3] 1 for a
 * point, 0 for a direction at infinity) and the edge to the next entry. */
enum { E_VOR, E_RAY, E_OWN };
typedef struct cv {
    double h[4];
    int64_t id;   /* provisional vertex, or -1 (a Voronoi vertex not yet
                     numbered: root >= 0; or a point at infinity) */
    int64_t root; /* the Voronoi vertex's root tet, or -1 */
    int ekind;    /* the edge to the next entry: a Voronoi edge (ea, eb the
                     roots of its ends), a ray (ea its root hull face), or
                     the face's own (on a wall, or at infinity) */
    int64_t ea, eb;
    fdt_vid tri[3]; /* a Voronoi edge's Delaunay triangle (E_VOR) */
    fdt_tid t0, t1; /* a Voronoi vertex's first and last tets in the ring */
} cv;

typedef struct dwork {
    fdt_result *r;
    const double *X;
    size_t n, T;
    double box[6];
    fdt_locator loc;
    const fdt_tid *nb;
    int64_t *uf;    /* T: cospherical neighbours merged */
    double *cc;     /* 3 a tet: its circumcentre */
    int64_t *rvid;  /* T: a root's provisional vertex, -1 none yet */
    kmap hull;      /* 4 t + i -> hull face */
    size_t nhull;
    int64_t *huf;   /* hull faces merged into rays */
    double *hdir;   /* 3 a hull face: unit outward normal */
    fdt_vid *htri;  /* 3 a hull face: its points */
    int64_t *htet;  /* a hull face's tet */
    kmap cross;     /* a Voronoi edge or ray crossing a wall -> vertex */
    double *vx;     /* provisional vertices */
    size_t nv, capv;
    int64_t *fv;    /* faces' provisional vertices */
    size_t nfv, capfv;
    size_t *fs;     /* nf + 1 starts */
    int32_t *fown, *fnbr; /* fnbr: the neighbour cell, or -1 - wall */
    size_t nf, capf, capfo, capfn;
    int32_t *cell_of;
    int32_t *point_of; /* ncells: a cell's point (owned) */
    size_t ncells;
    cv *poly, *tmp;
    size_t cappoly, captmp;
    fdt_tid *ring;
    size_t capring;
    double *scaled; /* the points times 2^-e (owned; NULL: not scaled) */
    double side;    /* the box's largest side, as scaled (the crossings' slack) */
    char *diag;
    size_t ds;
} dwork;

static int64_t new_vertex(dwork *w, const double x[3])
{
    if (fdt_grow(&w->vx, &w->capv, 3 * (w->nv + 1), sizeof *w->vx) != 0)
        return -1;
    memcpy(w->vx + 3 * w->nv, x, 3 * sizeof *x);
    return (int64_t)w->nv++;
}

/* Wall p: axis p / 2, its upper bound when p is odd. */
static double bound(const dwork *w, int p)
{
    return w->box[(p >> 1) + ((p & 1) ? 3 : 0)];
}

/* > 0: h lies beyond wall p (outside the box), <= 0 inside or on it. */
static double side(const dwork *w, const double h[4], int p)
{
    int k = p >> 1;
    double b = bound(w, p);
    if (h[3] == 0)
        return (p & 1) ? h[k] : -h[k];
    return (p & 1) ? h[k] - b : b - h[k];
}

/* ------------------------------------------------------------ merging */

/*
 * A tet's circumcentre, accurate to a small part of its shortest edge (the
 * vertices of a thin cell, a stretched grid's, must be as good as its
 * thickness): the floating formula relative to the first point where its
 * error bound (16 eps of the terms, over |det|, plus det's own relative
 * error times the result) is within 2^-36 of the shortest edge, else the
 * exact one (fdt_circumcenter_exact). The points in lexicographic order:
 * the same bits however the tet comes. -1 when the tet is flat.
 */
static int tet_circumcentre(const double *a, const double *b, const double *c, const double *d,
                            double x[3])
{
    const double *s[4] = {a, b, c, d};
    for (int i = 1; i < 4; i++)
        for (int j = i; j > 0 && fdt_lex_compare(s[j - 1], s[j]) > 0; j--) {
            const double *t = s[j];
            s[j] = s[j - 1];
            s[j - 1] = t;
        }
    double q[3][3], len[3], emin = INFINITY;
    for (int m = 0; m < 3; m++) {
        for (int k = 0; k < 3; k++)
            q[m][k] = s[m + 1][k] - s[0][k];
        len[m] = sqrt(q[m][0] * q[m][0] + q[m][1] * q[m][1] + q[m][2] * q[m][2]);
        emin = fmin(emin, len[m]);
        for (int n = m + 1; n < 3; n++) {
            double e2 = 0;
            for (int k = 0; k < 3; k++) {
                double dk = s[n + 1][k] - s[m + 1][k];
                e2 += dk * dk;
            }
            emin = fmin(emin, sqrt(e2));
        }
    }
    double cr[3][3]; /* q1 x q2, q2 x q0, q0 x q1 */
    for (int m = 0; m < 3; m++) {
        const double *u = q[(m + 1) % 3], *v = q[(m + 2) % 3];
        cr[m][0] = u[1] * v[2] - u[2] * v[1];
        cr[m][1] = u[2] * v[0] - u[0] * v[2];
        cr[m][2] = u[0] * v[1] - u[1] * v[0];
    }
    double det = q[0][0] * cr[0][0] + q[0][1] * cr[0][1] + q[0][2] * cr[0][2];
    if (det != 0) {
        const double eps = 0x1p-53;
        double l2[3] = {len[0] * len[0], len[1] * len[1], len[2] * len[2]}, r = 0;
        for (int k = 0; k < 3; k++) {
            x[k] = (l2[0] * cr[0][k] + l2[1] * cr[1][k] + l2[2] * cr[2][k]) / (2 * det);
            r += x[k] * x[k];
        }
        double terms = (l2[0] + l2[1] + l2[2]) * (len[1] * len[2] + len[2] * len[0] + len[0] * len[1]);
        double bound = 16 * eps * (terms / fabs(2 * det) + len[0] * len[1] * len[2] / fabs(det) * sqrt(r));
        if (bound <= 0x1p-36 * emin && isfinite(bound)) {
            for (int k = 0; k < 3; k++)
                x[k] += s[0][k];
            return 0;
        }
    }
    double rel[3];
    if (fdt_circumcenter_exact(s[0], s[1], s[2], s[3], rel) != 0)
        return -1;
    for (int k = 0; k < 3; k++)
        x[k] = s[0][k] + rel[k];
    return 0;
}

/* The tets' circumcentres, and neighbours on one sphere merged. */
static int merge_tets(dwork *w)
{
    const fdt_vid *tv = w->r->tets;
    for (size_t t = 0; t < w->T; t++) {
        const fdt_vid *v = tv + 4 * t;
        w->uf[t] = (int64_t)t;
        w->rvid[t] = -1;
        if (tet_circumcentre(w->X + 3 * (size_t)v[0], w->X + 3 * (size_t)v[1],
                             w->X + 3 * (size_t)v[2], w->X + 3 * (size_t)v[3],
                             w->cc + 3 * t) != 0) {
            fdt_diag(w->diag, w->ds, "tet %zu is flat: it has no circumcentre", t);
            return FDT_EINTERNAL;
        }
    }
    for (size_t t = 0; t < w->T; t++) {
        const fdt_vid *v = tv + 4 * t;
        for (int i = 0; i < 4; i++) {
            fdt_tid u = w->nb[4 * t + (size_t)i];
            if (u <= (fdt_tid)t)
                continue;
            const fdt_vid *uv = tv + 4 * (size_t)u;
            int e = 0;
            while (e < 4 && w->nb[4 * (size_t)u + (size_t)e] != (fdt_tid)t)
                e++;
            if (e == 4) {
                fdt_diag(w->diag, w->ds, "tets %zu and %lld are not mutual neighbours", t,
                    (long long)u);
                return FDT_EINTERNAL;
            }
            if (fdt_insphere(w->X + 3 * (size_t)v[0], w->X + 3 * (size_t)v[1],
                             w->X + 3 * (size_t)v[2], w->X + 3 * (size_t)v[3],
                             w->X + 3 * (size_t)uv[e], NULL) == 0)
                uf_union(w->uf, (int64_t)t, (int64_t)u);
        }
    }
    return FDT_OK;
}

/* Positions k, l of tet v's other vertices such that (a, b, k, l) is an
 * even permutation of the tet's: counter-clockwise about b - a, the face
 * without l comes before the tet, the face without k after it. */
static void edge_frame(const fdt_vid *v, fdt_vid a, fdt_vid b, int *pk, int *pl)
{
    int p[4], m = 2;
    for (int i = 0; i < 4; i++) {
        if (v[i] == a)
            p[0] = i;
        else if (v[i] == b)
            p[1] = i;
        else
            p[m++] = i;
    }
    int inv = 0;
    for (int i = 0; i < 4; i++)
        for (int j = i + 1; j < 4; j++)
            inv += p[i] > p[j];
    *pk = p[(inv & 1) ? 3 : 2];
    *pl = p[(inv & 1) ? 2 : 3];
}

/* The tet after t about edge (a, b) (ccw: counter-clockwise about b - a,
 * else clockwise), or -1 with *hull the position of t's hull face. */
static fdt_tid ring_step(const dwork *w, fdt_tid t, fdt_vid a, fdt_vid b, int ccw, int *hull)
{
    int pk, pl;
    edge_frame(w->r->tets + 4 * (size_t)t, a, b, &pk, &pl);
    int q = ccw ? pk : pl;
    fdt_tid u = w->nb[4 * (size_t)t + (size_t)q];
    if (u < 0)
        *hull = q;
    return u;
}

static int64_t hull_face(const dwork *w, fdt_tid t, int q)
{
    return kmap_get(&w->hull, 4 * (uint64_t)t + (uint64_t)q, 0);
}

/* s + e = a + b exactly. */
static void two_sum(double a, double b, double *s, double *e)
{
    *s = a + b;
    double bb = *s - a;
    *e = (a - (*s - bb)) + (b - bb);
}

/* u x v for u = b - a, v = c - a, component k, with the differences and
 * products kept exactly as pairs of doubles and the terms summed with
 * their errors (Neumaier): accurate to about eps |result| + eps^2 |terms|,
 * so a nearly collinear triangle's normal keeps its direction (the plain
 * formula lost all of it on a rotated lattice's hull). */
static double cross_k(const double *a, const double *b, const double *c, int k)
{
    int i = (k + 1) % 3, j = (k + 2) % 3;
    double ui[2], uj[2], vi[2], vj[2];
    two_sum(b[i], -a[i], &ui[0], &ui[1]);
    two_sum(b[j], -a[j], &uj[0], &uj[1]);
    two_sum(c[i], -a[i], &vi[0], &vi[1]);
    two_sum(c[j], -a[j], &vj[0], &vj[1]);
    double t[16];
    int m = 0;
    for (int x = 0; x < 2; x++)
        for (int y = 0; y < 2; y++) {
            double p = ui[x] * vj[y], q = vi[x] * uj[y]; /* ui vj - uj vi */
            t[m++] = p;
            t[m++] = fma(ui[x], vj[y], -p);
            t[m++] = -q;
            t[m++] = -fma(vi[x], uj[y], -q);
        }
    double sum = 0, comp = 0;
    for (int x = 0; x < m; x++) {
        double s2, e2;
        two_sum(sum, t[x], &s2, &e2);
        sum = s2;
        comp += e2;
    }
    return sum + comp;
}

/* The unit normal of triangle (a, b, c) by the right-hand rule. */
static void unit_normal(const double *a, const double *b, const double *c, double d[3])
{
    double big = 0;
    for (int k = 0; k < 3; k++) {
        d[k] = cross_k(a, b, c, k);
        big = fmax(big, fabs(d[k]));
    }
    double len = 0;
    for (int k = 0; k < 3; k++) {
        d[k] /= big; /* no over- or underflow in the squares */
        len += d[k] * d[k];
    }
    len = sqrt(len);
    for (int k = 0; k < 3; k++)
        d[k] /= len;
}

/* The hull faces, their normals, and adjacent coplanar ones whose tets
 * share a Voronoi vertex merged: one ray. */
static int number_hull(dwork *w)
{
    const fdt_vid *tv = w->r->tets;
    size_t nh = 0;
    for (size_t t = 0; t < w->T; t++)
        for (int q = 0; q < 4; q++)
            nh += w->nb[4 * t + (size_t)q] < 0;
    if (kmap_init(&w->hull, nh) != 0 || !(w->huf = malloc((nh + 1) * sizeof *w->huf)) ||
        !(w->hdir = malloc(3 * (nh + 1) * sizeof *w->hdir)) ||
        !(w->htri = malloc(3 * (nh + 1) * sizeof *w->htri)) ||
        !(w->htet = malloc((nh + 1) * sizeof *w->htet)))
        return FDT_ENOMEM;
    for (size_t t = 0; t < w->T; t++)
        for (int q = 0; q < 4; q++) {
            if (w->nb[4 * t + (size_t)q] >= 0)
                continue;
            const double *p0 = w->X + 3 * (size_t)tv[4 * t + (size_t)fdt_tet_face[q][0]];
            const double *p1 = w->X + 3 * (size_t)tv[4 * t + (size_t)fdt_tet_face[q][1]];
            const double *p2 = w->X + 3 * (size_t)tv[4 * t + (size_t)fdt_tet_face[q][2]];
            unit_normal(p0, p1, p2, w->hdir + 3 * w->nhull);
            for (int k = 0; k < 3; k++)
                w->htri[3 * w->nhull + (size_t)k] = tv[4 * t + (size_t)fdt_tet_face[q][k]];
            w->huf[w->nhull] = (int64_t)w->nhull;
            w->htet[w->nhull] = (int64_t)t;
            if (kmap_put(&w->hull, 4 * (uint64_t)t + (uint64_t)q, 0, (int64_t)w->nhull) != 0)
                return FDT_ENOMEM;
            w->nhull++;
        }
    /* each hull face's three edges: the hull face across it */
    for (size_t h = 0; h < w->nhull; h++) {
        fdt_tid t = w->htet[h];
        const fdt_vid *v = tv + 4 * (size_t)t;
        int q = 0;
        while (hull_face(w, t, q) != (int64_t)h)
            q++;
        for (int e = 0; e < 3; e++) {
            fdt_vid a = v[fdt_tet_face[q][e]], b = v[fdt_tet_face[q][(e + 1) % 3]];
            fdt_vid c = v[fdt_tet_face[q][(e + 2) % 3]];
            /* rotate about (a, b) away from this hull face to the other */
            int pk, pl;
            edge_frame(v, a, b, &pk, &pl);
            int ccw = pl == q; /* the hull face comes before t: walk on ccw */
            fdt_tid u = t, next;
            int hq = -1;
            size_t steps = 0;
            while ((next = ring_step(w, u, a, b, ccw, &hq)) >= 0 && steps++ < w->T)
                u = next;
            if (next >= 0)
                return FDT_EINTERNAL;
            int64_t h2 = hull_face(w, u, hq);
            if (h2 <= (int64_t)h)
                continue;
            if (uf_find(w->uf, (int64_t)t) != uf_find(w->uf, (int64_t)u))
                continue;
            /* coplanar: the other face's far vertex on this one's plane */
            const fdt_vid *uv = tv + 4 * (size_t)u;
            fdt_vid far = -1;
            for (int i = 0; i < 3; i++) {
                fdt_vid x = uv[fdt_tet_face[hq][i]];
                if (x != a && x != b)
                    far = x;
            }
            if (fdt_orient3d(w->X + 3 * (size_t)a, w->X + 3 * (size_t)b, w->X + 3 * (size_t)c,
                             w->X + 3 * (size_t)far, NULL) == 0)
                uf_union(w->huf, (int64_t)h, h2);
        }
    }
    return FDT_OK;
}

/* ------------------------------------------------------------ clipping */

/* The point x on wall p equidistant from the triangle tri's points (where
 * its Voronoi edge meets the wall), solved relative to its first point so
 * that the error scales with the triangle, not with a far circumcentre.
 * 0, or -1 when the edge runs (nearly) along the wall. */
static int wall_point(const dwork *w, const fdt_vid *tri, int p, double x[3])
{
    int k = p >> 1, u = (k + 1) % 3, t = (k + 2) % 3;
    const double *p0 = w->X + 3 * (size_t)tri[0];
    double d1[3], d2[3];
    for (int c = 0; c < 3; c++) {
        d1[c] = w->X[3 * (size_t)tri[1] + (size_t)c] - p0[c];
        d2[c] = w->X[3 * (size_t)tri[2] + (size_t)c] - p0[c];
    }
    double yk = bound(w, p) - p0[k];
    double r1 = 0.5 * (d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2]) - d1[k] * yk;
    double r2 = 0.5 * (d2[0] * d2[0] + d2[1] * d2[1] + d2[2] * d2[2]) - d2[k] * yk;
    double det = d1[u] * d2[t] - d1[t] * d2[u];
    double scale = (fabs(d1[u]) + fabs(d1[t])) * (fabs(d2[u]) + fabs(d2[t]));
    if (!(fabs(det) > 0x1p-20 * scale))
        return -1;
    double yu = (r1 * d2[t] - r2 * d1[t]) / det, yt = (d1[u] * r2 - d2[u] * r1) / det;
    if (!isfinite(yu) || !isfinite(yt))
        return -1;
    x[k] = bound(w, p);
    x[u] = p0[u] + yu;
    x[t] = p0[t] + yt;
    return 0;
}

/* A crossing point pt on wall k's axis moved onto a second wall where it
 * lies within 2^-50 of the box's size of it: a Voronoi edge that meets the
 * wall at a box edge or corner (a corner equidistant from two points, on
 * the face between their cells) comes out a rounding off the other wall,
 * and the cells at the corner then disagree on which walls their faces
 * reach (gen_points `cone`, `torus`: cells not closed). The point is
 * made once under its key, so every face that has it sees it moved. */
static void snap_to_walls(const dwork *w, double pt[3], int k)
{
    for (int c = 0; c < 3; c++) {
        if (c == k)
            continue;
        for (int hi = 0; hi < 2; hi++)
            if (fabs(pt[c] - w->box[c + 3 * hi]) <= 0x1p-50 * w->side)
                pt[c] = w->box[c + 3 * hi];
    }
}

/* The point y (homogeneous) between entries cur (inside wall p) and nxt
 * (beyond it) where their segment, or ray, meets the wall, by
 * interpolation: what a face's own edge uses, and a shared edge's fallback
 * in crossing(). y[3] is 0 where both are at infinity. */
static void between(const dwork *w, const cv *cur, const cv *nxt, int p, double y[4])
{
    double su = side(w, cur->h, p), sv = side(w, nxt->h, p);
    for (int c = 0; c < 4; c++)
        y[c] = cur->h[c] * fabs(sv) + nxt->h[c] * fabs(su);
}

/* Whether pt lies within 2^-40 of the box of the span from cur to nxt
 * (their coordinates' range; from cur on along nxt's direction when nxt
 * is at infinity), off wall axis k. */
static int in_span(const dwork *w, const double pt[3], int k, const cv *cur, const cv *nxt)
{
    double slack = 0x1p-40 * w->side;
    for (int c = 0; c < 3; c++) {
        if (c == k)
            continue;
        double lo = cur->h[c], hi = cur->h[c];
        if (nxt->h[3] != 0) {
            lo = fmin(lo, nxt->h[c]);
            hi = fmax(hi, nxt->h[c]);
        } else if (nxt->h[c] > 0) {
            hi = INFINITY;
        } else if (nxt->h[c] < 0) {
            lo = -INFINITY;
        }
        if (pt[c] < lo - slack || pt[c] > hi + slack)
            return 0;
    }
    return 1;
}

/* The point where the edge labelled (kind, ea, eb) crosses wall p, from
 * the entry cur inside to nxt beyond: a shared Voronoi edge's or ray's is
 * computed from the whole edge and kept under its key, the face's own
 * edge's from the two entries (a point at infinity where both are).
 * Fills *x (id set, or -1 at infinity); 0 or FDT_ENOMEM. */
static int crossing(dwork *w, const cv *cur, const cv *nxt, int p, cv *x)
{
    int k = p >> 1;
    double b = bound(w, p);
    uint64_t ka, kb;
    double pt[3];
    x->root = -1;
    x->h[3] = 1;
    if (cur->ekind == E_OWN) {
        double y[4];
        between(w, cur, nxt, p, y);
        if (y[3] > 0) {
            for (int c = 0; c < 3; c++) {
                pt[c] = y[c] / y[3];
                /* on a wall with both ends (or along it, to infinity):
                 * on it exactly, as the walls' faces find their points */
                const double *f = cur->h[3] != 0 ? cur->h : nxt->h, *g = cur->h[3] != 0 ? nxt->h : cur->h;
                if (g[3] != 0 ? g[c] == f[c] : g[c] == 0)
                    pt[c] = f[c];
            }
            pt[k] = b;
            snap_to_walls(w, pt, k);
            memcpy(x->h, pt, sizeof pt);
            x->id = new_vertex(w, pt);
            return x->id < 0 ? FDT_ENOMEM : FDT_OK;
        }
        double len = sqrt(y[0] * y[0] + y[1] * y[1] + y[2] * y[2]);
        for (int c = 0; c < 3; c++)
            x->h[c] = y[c] / len;
        x->h[k] = 0; /* along the wall */
        x->h[3] = 0;
        x->id = -1;
        return FDT_OK;
    }
    if (cur->ekind == E_VOR) {
        ka = (uint64_t)(cur->ea < cur->eb ? cur->ea : cur->eb);
        kb = ((uint64_t)(cur->ea < cur->eb ? cur->eb : cur->ea) << 3) | (uint64_t)p;
    } else {
        ka = (UINT64_C(1) << 62) | (uint64_t)cur->ea;
        kb = (uint64_t)p;
    }
    int64_t id = kmap_get(&w->cross, ka, kb);
    if (id < 0) {
        const fdt_vid *tri = cur->ekind == E_VOR ? cur->tri : w->htri + 3 * (size_t)cur->ea;
        const double *A, *B = NULL, *d = NULL;
        if (cur->ekind == E_VOR) {
            A = w->cc + 3 * (size_t)(int64_t)ka;
            B = w->cc + 3 * (size_t)(int64_t)(kb >> 3);
        } else {
            A = w->cc + 3 * (size_t)cur->eb;
            d = w->hdir + 3 * (size_t)cur->ea;
        }
        int along = wall_point(w, tri, p, pt) != 0;
        if (!along && cur->h[3] != 0 && !in_span(w, pt, k, cur, nxt)) {
            /* The edge's line meets the wall, by its triangle, beyond the
             * span of it this face keeps (and outside the walls already
             * cut): its ends are rounded circumcentres of nearly
             * cospherical groups (gen_points `cone`). The span is the
             * same in every face that has the edge: from it (cur is
             * finite, so y[3] > 0). */
            double y[4];
            between(w, cur, nxt, p, y);
            for (int c = 0; c < 3; c++)
                pt[c] = y[c] / y[3];
        } else if (along) {
            /* the edge nearly along the wall: from its ends */
            double t;
            if (B) {
                double den = B[k] - A[k];
                t = den != 0 ? (b - A[k]) / den : 0.5;
                t = t < 0 ? 0 : t > 1 ? 1 : t;
            } else {
                t = (b - A[k]) / d[k];
                t = t < 0 ? 0 : t;
            }
            for (int c = 0; c < 3; c++)
                pt[c] = A[c] + t * (B ? B[c] - A[c] : d[c]);
        }
        for (int c = 0; c < 3; c++)
            if (B ? A[c] == B[c] : d[c] == 0)
                pt[c] = A[c]; /* along a wall: on it exactly */
        pt[k] = b;
        snap_to_walls(w, pt, k);
        id = new_vertex(w, pt);
        if (id < 0 || kmap_put(&w->cross, ka, kb, id) != 0)
            return FDT_ENOMEM;
    }
    memcpy(x->h, w->vx + 3 * (size_t)id, 3 * sizeof(double));
    x->id = id;
    return FDT_OK;
}

/* The face in w->poly (*m entries) clipped by wall p (Sutherland-
 * Hodgman; a point on the wall counts as inside and makes no crossing). */
static int clip_wall(dwork *w, size_t *m, int p)
{
    size_t cnt = *m, out = 0, nin = 0;
    for (size_t i = 0; i < cnt; i++)
        nin += side(w, w->poly[i].h, p) <= 0;
    if (nin == cnt)
        return FDT_OK;
    if (nin == 0) {
        *m = 0;
        return FDT_OK;
    }
    if (fdt_grow(&w->tmp, &w->captmp, 2 * cnt, sizeof *w->tmp) != 0)
        return FDT_ENOMEM;
    for (size_t i = 0; i < cnt; i++) {
        const cv *cur = &w->poly[i], *nxt = &w->poly[(i + 1) % cnt];
        double sc = side(w, cur->h, p), sn = side(w, nxt->h, p);
        if (sc <= 0) {
            w->tmp[out] = *cur;
            if (sn > 0) {
                if (sc < 0) {
                    cv x;
                    int e = crossing(w, cur, nxt, p, &x);
                    if (e)
                        return e;
                    out++;
                    w->tmp[out] = x;
                }
                w->tmp[out].ekind = E_OWN; /* on the wall, to where it comes back */
                w->tmp[out].ea = w->tmp[out].eb = -1;
            }
            out++;
        } else if (sn < 0) {
            cv x;
            int e = crossing(w, cur, nxt, p, &x);
            if (e)
                return e;
            x.ekind = cur->ekind;
            x.ea = cur->ea;
            x.eb = cur->eb;
            memcpy(x.tri, cur->tri, sizeof x.tri);
            w->tmp[out++] = x;
        }
    }
    cv *t = w->poly;
    size_t ct = w->cappoly;
    w->poly = w->tmp;
    w->cappoly = w->captmp;
    w->tmp = t;
    w->captmp = ct;
    *m = out;
    return FDT_OK;
}

/* Appends a face (fnbr: a cell, or -1 - wall) of vertices ids[0 .. m). */
static int append_face(dwork *w, const int64_t *ids, size_t m, int32_t own, int32_t nbr)
{
    if (fdt_grow(&w->fv, &w->capfv, w->nfv + m, sizeof *w->fv) != 0 ||
        fdt_grow(&w->fs, &w->capf, w->nf + 2, sizeof *w->fs) != 0 ||
        fdt_grow(&w->fown, &w->capfo, w->nf + 1, sizeof *w->fown) != 0 ||
        fdt_grow(&w->fnbr, &w->capfn, w->nf + 1, sizeof *w->fnbr) != 0)
        return FDT_ENOMEM;
    if (ids != w->fv + w->nfv)
        memcpy(w->fv + w->nfv, ids, m * sizeof *ids);
    w->fs[w->nf] = w->nfv;
    w->nfv += m;
    w->fs[w->nf + 1] = w->nfv;
    w->fown[w->nf] = own;
    w->fnbr[w->nf] = nbr;
    w->nf++;
    return FDT_OK;
}

/* The clipped face in w->poly[0 .. m), numbered (its Voronoi vertices
 * get their numbers now), added when 3 distinct vertices are left. */
static int put_face(dwork *w, size_t m, int32_t own, int32_t nbr)
{
    if (fdt_grow(&w->fv, &w->capfv, w->nfv + m, sizeof *w->fv) != 0)
        return FDT_ENOMEM;
    int64_t *ids = w->fv + w->nfv;
    size_t k = 0;
    for (size_t i = 0; i < m; i++) {
        const cv *e = &w->poly[i];
        int64_t id = e->id;
        if (e->h[3] == 0) {
            fdt_diag(w->diag, w->ds, "the face of cells %d and %d keeps a point at infinity "
                "after the box cut it", own, nbr);
            return FDT_EINTERNAL;
        }
        if (id < 0) {
            if (w->rvid[e->root] < 0 && (w->rvid[e->root] = new_vertex(w, e->h)) < 0)
                return FDT_ENOMEM;
            id = w->rvid[e->root];
        }
        if (k == 0 || ids[k - 1] != id)
            ids[k++] = id;
    }
    while (k > 1 && ids[k - 1] == ids[0])
        k--;
    return k < 3 ? FDT_OK : append_face(w, ids, k, own, nbr);
}

static void entry_vertex(dwork *w, cv *e, int64_t root)
{
    memcpy(e->h, w->cc + 3 * (size_t)root, 3 * sizeof(double));
    e->h[3] = 1;
    e->id = -1;
    e->root = root;
}

static void entry_ray(dwork *w, cv *e, int64_t ray)
{
    memcpy(e->h, w->hdir + 3 * (size_t)ray, 3 * sizeof(double));
    e->h[3] = 0;
    e->id = -1;
    e->root = -1;
}

/* The face of edge (a, b) from the tets ring[0 .. nr) counter-clockwise
 * about it, rays out of hull faces hin (before ring[0]) and hout (after
 * the last) when open (-1 when closed): clipped and, when it keeps an
 * area, added. */
static int add_face(dwork *w, fdt_vid a, fdt_vid b, size_t nr, int64_t hin, int64_t hout)
{
    if (fdt_grow(&w->poly, &w->cappoly, nr + 2, sizeof *w->poly) != 0)
        return FDT_ENOMEM;
    size_t m = 0;
    int64_t rin = hin >= 0 ? uf_find(w->huf, hin) : -1;
    int64_t rout = hout >= 0 ? uf_find(w->huf, hout) : -1;
    if (rin >= 0) {
        entry_ray(w, &w->poly[m], rin);
        w->poly[m].ekind = E_RAY;
        w->poly[m].ea = rin;
        m++;
    }
    size_t first = m;
    for (size_t i = 0; i < nr; i++) {
        int64_t root = uf_find(w->uf, (int64_t)w->ring[i]);
        if (m > first && w->poly[m - 1].root == root) {
            w->poly[m - 1].t1 = w->ring[i];
            continue;
        }
        entry_vertex(w, &w->poly[m], root);
        w->poly[m].t0 = w->poly[m].t1 = w->ring[i];
        m++;
    }
    if (rin < 0 && m - first > 1 && w->poly[m - 1].root == w->poly[first].root)
        w->poly[first].t0 = w->poly[--m].t0;
    for (size_t i = first; i < m; i++) {
        cv *e = &w->poly[i];
        if (i + 1 < m || rin < 0) {
            /* the triangle between this run's last tet and the next's first */
            int pk, pl;
            edge_frame(w->r->tets + 4 * (size_t)e->t1, a, b, &pk, &pl);
            e->ekind = E_VOR;
            e->ea = e->root;
            e->eb = w->poly[i + 1 < m ? i + 1 : first].root;
            e->tri[0] = a;
            e->tri[1] = b;
            e->tri[2] = w->r->tets[4 * (size_t)e->t1 + (size_t)pl];
        } else {
            e->ekind = E_RAY;
            e->ea = rout;
        }
    }
    if (rin >= 0) {
        w->poly[first - 1].eb = w->poly[first].root;
        w->poly[m - 1].eb = w->poly[m - 1].root;
        if (rin == rout)
            return FDT_OK; /* one ray there and back: no area */
        entry_ray(w, &w->poly[m], rout);
        w->poly[m].ekind = E_OWN;
        w->poly[m].ea = w->poly[m].eb = -1;
        m++;
    }
    if (m < 3)
        return FDT_OK;
    for (int p = 0; p < 6 && m > 0; p++) {
        int e = clip_wall(w, &m, p);
        if (e)
            return e;
    }
    return m ? put_face(w, m, w->cell_of[a], w->cell_of[b]) : FDT_OK;
}

/* Edge (a, b) of tet t, a < b: when t is the lowest tet about it, its
 * face (the tets in counter-clockwise order, from the hull when open). */
static int edge_face(dwork *w, fdt_tid t, fdt_vid a, fdt_vid b)
{
    size_t nr = 0;
    fdt_tid u = t, next;
    int hq = -1, closed = 0;
    for (;;) {
        if (fdt_grow(&w->ring, &w->capring, nr + 1, sizeof *w->ring) != 0)
            return FDT_ENOMEM;
        w->ring[nr++] = u;
        next = ring_step(w, u, a, b, 1, &hq);
        if (next < 0)
            break;
        if (next == t) {
            closed = 1;
            break;
        }
        if (next < t || nr > w->T)
            return nr > w->T ? FDT_EINTERNAL : FDT_OK;
        u = next;
    }
    int64_t hin = -1, hout = -1;
    if (!closed) {
        hout = hull_face(w, u, hq);
        /* back from t to the hull: those tets come first */
        size_t nback = 0;
        u = t;
        while ((next = ring_step(w, u, a, b, 0, &hq)) >= 0) {
            if (next < t || nr + nback > w->T)
                return nr + nback > w->T ? FDT_EINTERNAL : FDT_OK;
            if (fdt_grow(&w->ring, &w->capring, nr + nback + 1, sizeof *w->ring) != 0)
                return FDT_ENOMEM;
            w->ring[nr + nback++] = next;
            u = next;
        }
        hin = hull_face(w, u, hq);
        /* ring: [t .. last, back1 .. backk]: rotate to [backk .. back1, t .. last] */
        if (nback) {
            fdt_tid *tmp = malloc((nr + nback) * sizeof *tmp);
            if (!tmp)
                return FDT_ENOMEM;
            for (size_t i = 0; i < nback; i++)
                tmp[i] = w->ring[nr + nback - 1 - i];
            memcpy(tmp + nback, w->ring, nr * sizeof *tmp);
            memcpy(w->ring, tmp, (nr + nback) * sizeof *tmp);
            free(tmp);
            nr += nback;
        }
        if (hin < 0 || hout < 0)
            return FDT_EINTERNAL;
    }
    return add_face(w, a, b, nr, hin, hout);
}

/* Every Delaunay edge's face, once (from its lowest tet). */
static int all_faces(dwork *w)
{
    for (size_t t = 0; t < w->T; t++) {
        const fdt_vid *v = w->r->tets + 4 * t;
        for (int e = 0; e < 6; e++) {
            fdt_vid a = v[fdt_tet_edge[e][0]], b = v[fdt_tet_edge[e][1]];
            int err = edge_face(w, (fdt_tid)t, a < b ? a : b, a < b ? b : a);
            if (err) {
                if (err == FDT_EINTERNAL && !w->diag[0])
                    fdt_diag(w->diag, w->ds, "the tets about edge (%d, %d) do not close", a, b);
                return err;
            }
        }
    }
    return FDT_OK;
}

/* ------------------------------------------------------------ walls */

/* Whether point x lies on one of the box's walls. */
static int on_wall(const dwork *w, const double x[3])
{
    for (int p = 0; p < 6; p++)
        if (x[p >> 1] == bound(w, p))
            return 1;
    return 0;
}

/* Whether point x lies on two walls or more: a box edge or corner. */
static int on_box_edge(const dwork *w, const double x[3])
{
    int n = 0;
    for (int p = 0; p < 6; p++)
        n += x[p >> 1] == bound(w, p);
    return n >= 2;
}

/* A vertex on a wall, sorted by place. */
typedef struct wallvx {
    double x[3];
    int64_t id;
} wallvx;

static int wallvx_cmp(const void *p, const void *q)
{
    const wallvx *a = p, *b = q;
    for (int k = 0; k < 3; k++)
        if (a->x[k] != b->x[k])
            return a->x[k] < b->x[k] ? -1 : 1;
    return (a->id > b->id) - (a->id < b->id);
}

/* Faces cut out of others (split_loops), to be appended. */
typedef struct loops {
    int64_t *v;       /* their vertices */
    size_t nv, capv;
    size_t *at;       /* face i: v[at[2i] .. at[2i] + at[2i + 1]) */
    size_t n, capat;
    int32_t *cells;   /* face i's owner and neighbour: 2i, 2i + 1 */
    size_t capcells;
} loops;

/*
 * A face's cycle of *m vertex ids after the box edges' vertices were
 * merged, made simple in place: walking it, a vertex met again closes a
 * loop, which is cut out: kept in *lp as a face of its own between the
 * same cells own and nbr when it has 3 vertices or more; dropped when it
 * has 1 or 2 (a repeat, or a spike A, B, A that runs out and back and
 * has no area). *m becomes the count left. Merging makes them: crossings
 * of two Voronoi edges with a box edge that round to one place become
 * one vertex, and a face through both, with a vertex within rounding of
 * the wall between them, runs out to it and back, or pinches into two
 * loops there (HCP crystals in their bounding box: Voronoi vertices
 * 2e-16 from a wall). Cutting a spike takes its edge out once each way;
 * a loop cut out keeps its edges: both cells of the face stay closed.
 */
static int split_loops(int64_t *f, size_t *m, loops *lp, int32_t own, int32_t nbr)
{
    size_t np = 0;
    for (size_t i = 0; i < *m; i++) {
        int64_t v = f[i];
        size_t q = np;
        while (q > 0 && f[q - 1] != v)
            q--;
        if (q == 0) {
            f[np++] = v; /* np <= i: in place */
            continue;
        }
        size_t k = np - (q - 1); /* the loop f[q - 1 .. np) */
        if (k >= 3) {
            if (fdt_grow(&lp->v, &lp->capv, lp->nv + k, sizeof *lp->v) != 0 ||
                fdt_grow(&lp->at, &lp->capat, 2 * lp->n + 2, sizeof *lp->at) != 0 ||
                fdt_grow(&lp->cells, &lp->capcells, 2 * lp->n + 2, sizeof *lp->cells) != 0)
                return FDT_ENOMEM;
            memcpy(lp->v + lp->nv, f + q - 1, k * sizeof *f);
            lp->at[2 * lp->n] = lp->nv;
            lp->at[2 * lp->n + 1] = k;
            lp->cells[2 * lp->n] = own;
            lp->cells[2 * lp->n + 1] = nbr;
            lp->n++;
            lp->nv += k;
        }
        np = q;
    }
    *m = np;
    return FDT_OK;
}

/*
 * Vertices on the box's edges and corners at the same place made one
 * (the lowest), and the faces made simple (split_loops). Crossings of
 * different Voronoi edges snapped onto a box edge or corner
 * (snap_to_walls), and a face's own edge along one wall crossing the
 * next (crossing: computed for each face), land on the same doubles: two
 * vertices there, and the cells meeting at the place would each use one
 * of them and not close (gen_points `torus` 16: two crossings at the
 * corner (4, -4, 1), one in each of two faces of one cell). Only there:
 * a crossing inside one wall is a Voronoi edge's, made once under its
 * key for every face that has it, and two edges' crossings that round to
 * one place are two vertices as two spheres' centres are (merge_tets).
 * Merging those too (as this did at first) joined faces that share no
 * edge: an HCP crystal's cell then used one edge twice each way
 * (bench/NOTES.md entry 129).
 */
static int merge_wall_vertices(dwork *w)
{
    size_t m = 0;
    for (size_t v = 0; v < w->nv; v++)
        m += (size_t)on_box_edge(w, w->vx + 3 * v);
    wallvx *s = malloc((m + 1) * sizeof *s);
    int64_t *to = malloc((w->nv + 1) * sizeof *to);
    if (!s || !to) {
        free(s);
        free(to);
        return FDT_ENOMEM;
    }
    m = 0;
    for (size_t v = 0; v < w->nv; v++) {
        to[v] = (int64_t)v;
        if (on_box_edge(w, w->vx + 3 * v)) {
            memcpy(s[m].x, w->vx + 3 * v, sizeof s[m].x);
            s[m++].id = (int64_t)v;
        }
    }
    qsort(s, m, sizeof *s, wallvx_cmp);
    size_t same = 0;
    for (size_t i = 1; i < m; i++) /* as the sort compares: -0 and +0 one place */
        if (s[i].x[0] == s[i - 1].x[0] && s[i].x[1] == s[i - 1].x[1] &&
            s[i].x[2] == s[i - 1].x[2]) {
            to[s[i].id] = to[s[i - 1].id];
            same++;
        }
    free(s);
    if (same == 0 || w->nf == 0) {
        free(to);
        return FDT_OK;
    }
    /* in place: a face's entries only move down; the loops cut out
     * appended after */
    size_t nf = 0, nfv = 0;
    loops lp = {0};
    int err = FDT_OK;
    for (size_t f = 0; f < w->nf && !err; f++) {
        size_t a = w->fs[f], b = w->fs[f + 1], k0 = nfv, k = b - a;
        for (size_t i = a; i < b; i++)
            w->fv[nfv++] = to[w->fv[i]];
        err = split_loops(w->fv + k0, &k, &lp, w->fown[f], w->fnbr[f]);
        nfv = k0 + k;
        if (k < 3) {
            nfv = k0;
            continue;
        }
        w->fs[nf] = k0;
        w->fown[nf] = w->fown[f];
        w->fnbr[nf++] = w->fnbr[f];
    }
    w->fs[nf] = nfv;
    w->nf = nf;
    w->nfv = nfv;
    for (size_t i = 0; i < lp.n && !err; i++)
        err = append_face(w, lp.v + lp.at[2 * i], lp.at[2 * i + 1], lp.cells[2 * i],
                          lp.cells[2 * i + 1]);
    free(lp.v);
    free(lp.at);
    free(lp.cells);
    free(to);
    return err;
}

/* The box corner c (bit k: the upper bound in axis k) and the cell of the
 * point nearest to it, -1 on a tie (then the corner lies on a face, which
 * brings it). */
static int32_t corner_cell(const dwork *w, int c, double x[3])
{
    for (int k = 0; k < 3; k++)
        x[k] = w->box[k + ((c >> k) & 1 ? 3 : 0)];
    size_t best = SIZE_MAX;
    int tie = 0;
    double bd = INFINITY;
    for (size_t i = 0; i < w->n; i++) {
        if (w->cell_of[i] < 0)
            continue;
        const double *p = w->X + 3 * i;
        double d = (p[0] - x[0]) * (p[0] - x[0]) + (p[1] - x[1]) * (p[1] - x[1]) +
                   (p[2] - x[2]) * (p[2] - x[2]);
        if (d > bd * (1 + 1e-12))
            continue;
        int s = best == SIZE_MAX ? -1 : fdt_compare_dist(x, p, w->X + 3 * best);
        if (s < 0) {
            best = i;
            bd = d;
            tie = 0;
        } else if (s == 0) {
            tie = 1;
        }
    }
    return tie || best == SIZE_MAX ? -1 : w->cell_of[best];
}

/* Where a point lies on the rim of wall p (the rectangle's boundary),
 * going round it counter-clockwise in the wall's (u, t) axes: the side
 * (0 t = tmin, 1 u = umax, 2 t = tmax, 3 u = umin) and the position along
 * it; side -1 off the rim. Compared exactly: near-equal points keep
 * their order. */
typedef struct rimkey {
    int side;
    double pos;
} rimkey;

static rimkey rim_key(const dwork *w, int p, const double *x)
{
    int k = p >> 1, u = (k + 1) % 3, t = (k + 2) % 3;
    double u0 = w->box[u], u1 = w->box[u + 3], t0 = w->box[t], t1 = w->box[t + 3];
    rimkey r = {-1, 0};
    if (x[t] == t0 && x[u] != u1)
        r = (rimkey){0, x[u]};
    else if (x[u] == u1 && x[t] != t1)
        r = (rimkey){1, x[t]};
    else if (x[t] == t1 && x[u] != u0)
        r = (rimkey){2, -x[u]};
    else if (x[u] == u0)
        r = (rimkey){3, -x[t]};
    return r;
}

/* A piece of a wall face: a chain of the cell's edges on the wall (from
 * the edge at `at`), or a box corner (at == SIZE_MAX). */
typedef struct wallitem {
    rimkey key;
    size_t at;
    int64_t corner;
} wallitem;

static int item_cmp(const void *x, const void *y)
{
    const wallitem *a = x, *b = y;
    if (a->key.side != b->key.side)
        return a->key.side < b->key.side ? -1 : 1;
    return a->key.pos < b->key.pos ? -1 : a->key.pos > b->key.pos;
}

static int u64_cmp(const void *x, const void *y)
{
    uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return a < b ? -1 : a > b;
}

/* The index of the edge leaving vertex v in e[0 .. m) (sorted, from in
 * the high half), or SIZE_MAX. */
static size_t edge_from(const uint64_t *e, size_t m, uint64_t v)
{
    size_t lo = 0, hi = m;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if ((e[mid] >> 32) < v)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < m && (e[lo] >> 32) == v ? lo : SIZE_MAX;
}

typedef struct hedge hedge;
typedef struct wallwork {
    hedge *he;       /* the cell's half-edges, then its wall edges */
    size_t caphe;
    uint64_t *we;    /* one wall's edges (from << 32 | to), sorted */
    size_t capwe;
    wallitem *it;
    size_t capit;
    uint64_t *to;    /* one wall's edges' ends, sorted */
    size_t capto;
    uint8_t *done;   /* which of the wall's edges a chain took */
    size_t capdone;
    int64_t *ids;    /* the face from the rim's chains and corners */
    size_t capids;
    int64_t *path;   /* walk_edges' path */
    size_t cappath;
} wallwork;

/* The first of the wall's edges e[0 .. m) (sorted) from vertex v that no
 * chain took yet, or SIZE_MAX. */
static size_t unused_from(const wallwork *ww, size_t m, uint64_t v)
{
    const uint64_t *e = ww->we;
    for (size_t at = edge_from(e, m, v); at < m && (e[at] >> 32) == v; at++)
        if (!ww->done[at])
            return at;
    return SIZE_MAX;
}

/*
 * The walk along cell c's unused edges on wall p from vertex v until none
 * leaves the vertex reached. A vertex met again closes a loop, cut out at
 * once as a face of its own (one of two vertices, an edge there and back,
 * adds nothing: the cell's other faces use the edge both ways); so the
 * walk's path stays simple, and is appended to ids[*k ...] when `open`
 * (a chain from the rim to the rim), else must have come back to v.
 */
static int walk_edges(dwork *w, wallwork *ww, int32_t c, int p, size_t m, uint64_t v, int open,
                      int64_t *ids, size_t *k)
{
    const uint64_t *e = ww->we;
    int64_t *path = ww->path;
    size_t np = 0, at;
    path[np++] = (int64_t)v;
    while ((at = unused_from(ww, m, v)) != SIZE_MAX) {
        ww->done[at] = 1;
        v = e[at] & 0xffffffffu;
        size_t q = np;
        while (q > 0 && path[q - 1] != (int64_t)v)
            q--;
        if (q == 0) {
            path[np++] = (int64_t)v;
            continue;
        }
        if (np - (q - 1) >= 3) { /* the loop path[q - 1 .. np) */
            int err = append_face(w, path + q - 1, np - (q - 1), c, -1 - p);
            if (err)
                return err;
        }
        np = q;
    }
    if (!open)
        return np == 1 ? FDT_OK : FDT_EINTERNAL;
    memcpy(ids + *k, path, np * sizeof *path);
    *k += np;
    return FDT_OK;
}

/* Cell c's face on wall p: its edges e[0 .. m) on the wall (each the
 * reverse of an edge its other faces use once), chained, and the box
 * corners it holds there, put in the order of their chains' starts round
 * the rim (the face is convex: its rim points come in the rim's order).
 * Where rounding leaves slivers (an HCP lattice in its bounding box:
 * vertices within 4e-16 of each other, where nearly cospherical Voronoi
 * vertices meet the wall), a chain can meet a vertex twice or edges
 * can close a loop inside the wall: each such loop is a face of its own
 * (walk_edges), as is a whole face inside the wall. The cell's other
 * faces use those edges, so without them it would not close. */
static int wall_face(dwork *w, wallwork *ww, int32_t c, int p, size_t m, const int64_t *corners,
                     int nc)
{
    uint64_t *e = ww->we;
    fdt_sort_u64(e, m);
    if (fdt_grow(&ww->it, &ww->capit, m + (size_t)nc + 1, sizeof *ww->it) != 0 ||
        fdt_grow(&ww->ids, &ww->capids, 2 * m + (size_t)nc + 1, sizeof *ww->ids) != 0 ||
        fdt_grow(&ww->path, &ww->cappath, m + 1, sizeof *ww->path) != 0 ||
        fdt_grow(&ww->to, &ww->capto, m + 1, sizeof *ww->to) != 0 ||
        fdt_grow(&ww->done, &ww->capdone, m + 1, sizeof *ww->done) != 0)
        return FDT_ENOMEM;
    for (size_t i = 0; i < m; i++) {
        ww->to[i] = e[i] & 0xffffffffu;
        ww->done[i] = 0;
    }
    fdt_sort_u64(ww->to, m);
    /* the chains' starts: a vertex with more edges out than in, once for
     * each more, on the rim */
    size_t ni = 0;
    for (size_t i = 0, j; i < m; i = j) {
        uint64_t from = e[i] >> 32;
        for (j = i + 1; j < m && (e[j] >> 32) == from; j++)
            ;
        size_t lo = 0, hi = m;
        while (lo < hi) { /* the first end >= from */
            size_t mid = lo + (hi - lo) / 2;
            if (ww->to[mid] < from)
                lo = mid + 1;
            else
                hi = mid;
        }
        size_t in = 0;
        while (lo + in < m && ww->to[lo + in] == from)
            in++;
        for (size_t r = in; r < j - i; r++) {
            ww->it[ni] = (wallitem){rim_key(w, p, w->vx + 3 * from), i, -1};
            if (ww->it[ni++].key.side < 0)
                goto bad;
        }
    }
    for (int k = 0; k < nc; k++)
        ww->it[ni++] = (wallitem){rim_key(w, p, w->vx + 3 * (size_t)corners[k]), SIZE_MAX,
                                  corners[k]};
    qsort(ww->it, ni, sizeof *ww->it, item_cmp);
    int64_t *ids = ww->ids;
    size_t k = 0;
    int err = FDT_OK;
    for (size_t a = 0; a < ni && !err; a++) {
        const wallitem *x = &ww->it[(p & 1) ? a : ni - 1 - a];
        if (x->at == SIZE_MAX)
            ids[k++] = x->corner;
        else
            err = walk_edges(w, ww, c, p, m, e[x->at] >> 32, 1, ids, &k);
    }
    if (!err && k >= 3)
        err = append_face(w, ids, k, c, -1 - p);
    for (size_t i = 0; i < m && !err; i++) /* the loops left */
        if (!ww->done[i])
            err = walk_edges(w, ww, c, p, m, e[i] >> 32, 0, NULL, NULL);
    if (err != FDT_EINTERNAL)
        return err;
bad:
    fdt_diag(w->diag, w->ds, "the face of cell %d on wall %s does not chain (%zu edges)", c,
        fdt_dualmesh_patch[p], m);
    return FDT_EINTERNAL;
}

/* A half-edge of a cell's face, turned out of the cell, and the cell
 * on the face's other side. */
typedef struct hedge {
    uint64_t key; /* from << 32 | to */
    int32_t other;
    int wall;
} hedge;

static int hedge_cmp(const void *x, const void *y)
{
    return u64_cmp(&((const hedge *)x)->key, &((const hedge *)y)->key);
}

/* The wall the reverse of cell c's half-edge h lies on: the one both its
 * ends are on; along a box edge (two walls p, q), the one the cell
 * touches there: p when the face's normal out of c (its point towards
 * the other cell's) leans out through q. -1 when on none. */
static int hedge_wall(const dwork *w, int32_t c, const hedge *h)
{
    const double *a = w->vx + 3 * (h->key >> 32), *b = w->vx + 3 * (h->key & 0xffffffffu);
    int on[2], n = 0;
    for (int p = 0; p < 6 && n < 2; p++)
        if (a[p >> 1] == bound(w, p) && b[p >> 1] == bound(w, p))
            on[n++] = p;
    if (n < 2)
        return n ? on[0] : -1;
    const double *x = w->X + 3 * (size_t)w->point_of[c];
    const double *y = w->X + 3 * (size_t)w->point_of[h->other];
    int q = on[1], kq = q >> 1; /* does y - x lean out through q? */
    int out = (q & 1) ? y[kq] > x[kq] : y[kq] < x[kq];
    return out ? on[0] : on[1];
}

/* Cell c's faces on the walls: the reverses of the edges its faces use
 * once, by wall, and the corners it holds. */
static int cell_walls(dwork *w, wallwork *ww, int32_t c, const size_t *cs, const size_t *cf,
                      const int64_t corner_id[8], const int32_t corner_of[8])
{
    size_t m = 0;
    for (size_t j = cs[c]; j < cs[c + 1]; j++) {
        size_t f = cf[j], k = w->fs[f + 1] - w->fs[f];
        const int64_t *v = w->fv + w->fs[f];
        int own = w->fown[f] == c;
        if (fdt_grow(&ww->he, &ww->caphe, m + k, sizeof *ww->he) != 0)
            return FDT_ENOMEM;
        for (size_t i = 0; i < k; i++) {
            uint64_t a = (uint64_t)v[i], b = (uint64_t)v[(i + 1) % k];
            ww->he[m].key = own ? a << 32 | b : b << 32 | a;
            ww->he[m++].other = own ? w->fnbr[f] : w->fown[f];
        }
    }
    qsort(ww->he, m, sizeof *ww->he, hedge_cmp);
    /* the unmatched ones, reversed, after the first m: as many as an edge
     * is used more one way than the other (a face pinched or collapsed
     * by rounding can use it more than once: three faces of one cell of
     * an HCP crystal between two wall vertices 4e-16 apart, twice one way
     * and once the other) */
    size_t nw = 0;
    if (fdt_grow(&ww->he, &ww->caphe, 2 * m + 1, sizeof *ww->he) != 0)
        return FDT_ENOMEM;
    for (size_t i = 0, j; i < m; i = j) {
        for (j = i + 1; j < m && ww->he[j].key == ww->he[i].key; j++)
            ;
        hedge r = ww->he[i];
        r.key = (r.key << 32) | (r.key >> 32);
        size_t lo = 0, hi = m; /* the reverse's run: from the first key >= r's */
        while (lo < hi) {
            size_t mid = lo + (hi - lo) / 2;
            if (ww->he[mid].key < r.key)
                lo = mid + 1;
            else
                hi = mid;
        }
        size_t back = 0;
        while (lo + back < m && ww->he[lo + back].key == r.key)
            back++;
        if (j - i <= back)
            continue;
        r.wall = hedge_wall(w, c, &r);
        if (r.wall < 0) {
            fdt_diag(w->diag, w->ds, "cell %d is open at edge %llu-%llu, on no wall", c,
                (unsigned long long)(r.key >> 32), (unsigned long long)(r.key & 0xffffffffu));
            return FDT_EINTERNAL;
        }
        for (size_t x = back; x < j - i; x++)
            ww->he[m + nw++] = r;
    }
    for (int p = 0; p < 6; p++) {
        int64_t corners[4];
        int nc = 0;
        for (int k = 0; k < 8; k++)
            if (corner_of[k] == c && ((k >> (p >> 1)) & 1) == (p & 1))
                corners[nc++] = corner_id[k];
        size_t me = 0;
        if (fdt_grow(&ww->we, &ww->capwe, nw + 1, sizeof *ww->we) != 0)
            return FDT_ENOMEM;
        for (size_t i = 0; i < nw; i++)
            if (ww->he[m + i].wall == p)
                ww->we[me++] = ww->he[m + i].key;
        if (me == 0 && nc == 0)
            continue;
        int err = wall_face(w, ww, c, p, me, corners, nc);
        if (err)
            return err;
    }
    return FDT_OK;
}

/* touch[c] = 1 for each cell with a vertex on a wall or a box corner
 * (the others have no wall face: their edges all pair up). 0 or
 * FDT_ENOMEM. */
static int touching_cells(const dwork *w, const int32_t corner_of[8], uint8_t *touch)
{
    uint8_t *on = malloc(w->nv + 1);
    if (!on)
        return FDT_ENOMEM;
    for (size_t v = 0; v < w->nv; v++)
        on[v] = (uint8_t)on_wall(w, w->vx + 3 * v);
    memset(touch, 0, w->ncells);
    for (size_t f = 0; f < w->nf; f++)
        for (size_t i = w->fs[f]; i < w->fs[f + 1]; i++)
            if (on[w->fv[i]]) {
                touch[w->fown[f]] = 1;
                touch[w->fnbr[f]] = 1;
                break;
            }
    for (int k = 0; k < 8; k++)
        if (corner_of[k] >= 0)
            touch[corner_of[k]] = 1;
    free(on);
    return FDT_OK;
}

/* The box corners that are vertices of faces already (bit c: corner c,
 * as corner_cell numbers them): a crossing snapped onto a corner
 * (snap_to_walls) puts the corner on the face between the two cells
 * nearest to it, a tie to within roundings. The faces then bring the
 * corner, as at an exact tie: a corner vertex of its own beside it would
 * be a second vertex at the same place, and the cell holding it would
 * not close there (gen_points `torus` 12: its point (4, 0, 0) and the
 * point at 7e-16 off x = 0 both 4 from corner (4, -4, z)). */
static unsigned corners_made(const dwork *w)
{
    unsigned made = 0;
    for (size_t v = 0; v < w->nv; v++) {
        const double *x = w->vx + 3 * v;
        int c = 0, k = 0;
        for (; k < 3; k++) {
            if (x[k] == w->box[k + 3])
                c |= 1 << k;
            else if (x[k] != w->box[k])
                break;
        }
        if (k == 3)
            made |= 1u << c;
    }
    return made;
}

/* Every cell's faces on the walls. */
static int all_walls(dwork *w)
{
    fdt_dualmesh tmp;
    memset(&tmp, 0, sizeof tmp);
    tmp.n_cells = w->ncells;
    tmp.n_faces = tmp.n_internal = w->nf;
    tmp.owner = w->fown;
    tmp.neighbour = w->fnbr;
    size_t *cs = NULL, *cf = NULL;
    if (w->nv >= (UINT64_C(1) << 31)) {
        fdt_diag(w->diag, w->ds, "too many vertices for OpenFOAM's 32-bit labels");
        return FDT_ETOOBIG;
    }
    if (fdt_dualmesh_cell_faces(&tmp, &cs, &cf) != FDT_OK)
        return FDT_ENOMEM;
    int64_t corner_id[8];
    int32_t corner_of[8];
    int err = FDT_OK;
    unsigned made = corners_made(w);
    for (int c = 0; c < 8 && !err; c++) {
        double x[3];
        corner_of[c] = (made >> c) & 1 ? -1 : corner_cell(w, c, x);
        corner_id[c] = corner_of[c] >= 0 ? new_vertex(w, x) : 0;
        if (corner_id[c] < 0)
            err = FDT_ENOMEM;
    }
    wallwork ww;
    memset(&ww, 0, sizeof ww);
    uint8_t *touch = malloc(w->ncells + 1);
    if (!err && !touch)
        err = FDT_ENOMEM;
    if (!err)
        err = touching_cells(w, corner_of, touch);
    for (size_t c = 0; c < w->ncells && !err; c++)
        if (touch[c])
            err = cell_walls(w, &ww, (int32_t)c, cs, cf, corner_id, corner_of);
    free(touch);
    free(ww.he);
    free(ww.to);
    free(ww.we);
    free(ww.it);
    free(ww.done);
    free(ww.ids);
    free(ww.path);
    free(cs);
    free(cf);
    return err;
}

/* ------------------------------------------------------------ assembly */

/* OpenFOAM's order into d: the internal faces by owner then neighbour,
 * then the walls' by wall (each by owner, as made); the vertices that
 * are used, numbered by first use. */
static int assemble(dwork *w, fdt_dualmesh *d)
{
    size_t nf = w->nf, nint = 0;
    size_t *order = malloc((nf + 1) * sizeof *order);
    size_t *cnt = calloc(w->ncells + 8, sizeof *cnt);
    int64_t *newid = malloc((w->nv + 1) * sizeof *newid);
    if (!order || !cnt || !newid) {
        free(order);
        free(cnt);
        free(newid);
        return FDT_ENOMEM;
    }
    /* two stable counting sorts: by neighbour, then by owner for an
     * internal face and ncells + wall for a wall face */
    size_t *first = malloc((nf + 1) * sizeof *first);
    if (!first) {
        free(order);
        free(cnt);
        free(newid);
        return FDT_ENOMEM;
    }
    for (size_t f = 0; f < nf; f++)
        cnt[(w->fnbr[f] >= 0 ? (size_t)w->fnbr[f] : 0) + 1]++;
    for (size_t k = 0; k < w->ncells + 6; k++)
        cnt[k + 1] += cnt[k];
    for (size_t f = 0; f < nf; f++)
        first[cnt[w->fnbr[f] >= 0 ? (size_t)w->fnbr[f] : 0]++] = f;
    memset(cnt, 0, (w->ncells + 8) * sizeof *cnt);
    for (size_t f = 0; f < nf; f++) {
        size_t key = w->fnbr[f] >= 0 ? (size_t)w->fown[f] : w->ncells + (size_t)(-1 - w->fnbr[f]);
        cnt[key + 1]++;
        nint += w->fnbr[f] >= 0;
    }
    for (size_t k = 0; k < w->ncells + 6; k++)
        cnt[k + 1] += cnt[k];
    for (size_t p = 0; p < 6; p++) {
        d->patch_start[p] = cnt[w->ncells + p];
        d->patch_size[p] = cnt[w->ncells + p + 1] - cnt[w->ncells + p];
    }
    for (size_t i = 0; i < nf; i++) {
        size_t f = first[i];
        size_t key = w->fnbr[f] >= 0 ? (size_t)w->fown[f] : w->ncells + (size_t)(-1 - w->fnbr[f]);
        order[cnt[key]++] = f;
    }
    free(first);
    free(cnt);
    d->n_cells = w->ncells;
    d->n_faces = nf;
    d->n_internal = nint;
    d->fstart = malloc((nf + 1) * sizeof *d->fstart);
    d->fverts = malloc((w->nfv + 1) * sizeof *d->fverts);
    d->owner = malloc((nf + 1) * sizeof *d->owner);
    d->neighbour = malloc((nint + 1) * sizeof *d->neighbour);
    int err = FDT_OK;
    if (!d->fstart || !d->fverts || !d->owner || !d->neighbour) {
        err = FDT_ENOMEM;
        goto out;
    }
    for (size_t v = 0; v < w->nv; v++)
        newid[v] = -1;
    size_t nv = 0, k = 0;
    for (size_t i = 0; i < nf; i++) {
        size_t f = order[i];
        d->fstart[i] = k;
        d->owner[i] = w->fown[f];
        if (i < nint)
            d->neighbour[i] = w->fnbr[f];
        for (size_t j = w->fs[f]; j < w->fs[f + 1]; j++) {
            int64_t v = w->fv[j];
            if (newid[v] < 0)
                newid[v] = (int64_t)nv++;
            d->fverts[k++] = (int32_t)newid[v];
        }
    }
    d->fstart[nf] = k;
    d->n_verts = nv;
    d->xyz = malloc((3 * nv + 1) * sizeof *d->xyz);
    if (!d->xyz) {
        err = FDT_ENOMEM;
        goto out;
    }
    for (size_t v = 0; v < w->nv; v++)
        if (newid[v] >= 0)
            memcpy(d->xyz + 3 * (size_t)newid[v], w->vx + 3 * v, 3 * sizeof *d->xyz);
out:
    free(order);
    free(newid);
    return err;
}

/* ------------------------------------------------------------ entry */

void fdt_dualmesh_free(fdt_dualmesh *d)
{
    free(d->xyz);
    free(d->fstart);
    free(d->fverts);
    free(d->owner);
    free(d->neighbour);
    free(d->cell_of);
    free(d->cyclic);
    memset(d, 0, sizeof *d);
}

static void free_work(dwork *w)
{
    fdt_locator_free(&w->loc);
    free(w->uf);
    free(w->cc);
    free(w->rvid);
    kmap_free(&w->hull);
    free(w->huf);
    free(w->hdir);
    free(w->htri);
    free(w->htet);
    kmap_free(&w->cross);
    free(w->vx);
    free(w->fv);
    free(w->fs);
    free(w->fown);
    free(w->fnbr);
    free(w->poly);
    free(w->tmp);
    free(w->ring);
    free(w->scaled);
    free(w->point_of);
}

/* The cells: the points that are not merged duplicates, in input order. */
static int number_cells(dwork *w, fdt_dualmesh *d)
{
    d->n_input = w->n;
    d->cell_of = malloc((w->n + 1) * sizeof *d->cell_of);
    if (!d->cell_of)
        return FDT_ENOMEM;
    w->point_of = malloc((w->n + 1) * sizeof *w->point_of);
    if (!w->point_of)
        return FDT_ENOMEM;
    for (size_t i = 0; i < w->n; i++) {
        d->cell_of[i] = w->r->dupmap[i] == (fdt_vid)i ? (int32_t)w->ncells++ : -1;
        if (d->cell_of[i] >= 0)
            w->point_of[d->cell_of[i]] = (int32_t)i;
    }
    w->cell_of = d->cell_of;
    return FDT_OK;
}

/* The points and the box scaled by a power of two so that the box's
 * largest side is about 1 (1e-150 and 1e150 wide sets: no squared
 * length under- or overflows), when every coordinate scales exactly;
 * the exponent to scale the vertices back by (0: not scaled), INT_MIN when
 * out of memory. Signs of predicates and order along the walls do not
 * change. */
static int scale_points(dwork *w)
{
    double side = 0;
    for (int k = 0; k < 3; k++)
        side = fmax(side, w->box[k + 3] - w->box[k]);
    int e;
    (void)frexp(side, &e);
    if (e > -4 && e < 4)
        return 0;
    for (size_t i = 0; i < 3 * w->n; i++)
        if (ldexp(ldexp(w->X[i], -e), e) != w->X[i])
            return 0;
    w->scaled = malloc((3 * w->n + 1) * sizeof *w->scaled);
    if (!w->scaled)
        return INT_MIN;
    for (size_t i = 0; i < 3 * w->n; i++)
        w->scaled[i] = ldexp(w->X[i], -e);
    for (int k = 0; k < 6; k++)
        w->box[k] = ldexp(w->box[k], -e);
    w->X = w->scaled;
    return e;
}

static int build(fdt_result *r, const double *xyz, size_t n, const fdt_voronoi_options *o,
                 fdt_dualmesh *d, int check, char *diag, size_t diag_size)
{
    char own[256];
    if (!diag || !diag_size) {
        diag = own;
        diag_size = sizeof own;
    }
    diag[0] = 0;
    memset(d, 0, sizeof *d);
    if (!r || !xyz || !o || r->streamed || n != r->n || r->ntets == 0) {
        fdt_diag(diag, diag_size, "the dual needs the result of fdt_triangulate on the same %zu "
            "points, with its tets", n);
        return FDT_EINVAL;
    }
    if (r->ntets > (size_t)INT32_MAX || n > (size_t)INT32_MAX) {
        fdt_diag(diag, diag_size, "too many points or tets for OpenFOAM's 32-bit labels");
        return FDT_ETOOBIG;
    }
    dwork w;
    memset(&w, 0, sizeof w);
    w.r = r;
    w.X = xyz;
    w.n = n;
    w.T = r->ntets;
    w.diag = diag;
    w.ds = diag_size;
    /* The vertices are written as absolute coordinates: those of points
     * closer than 2^-40 of theirs would be noise (fdt_voronoi_resolution). */
    int err = fdt_voronoi_box_of(xyz, NULL, n, o, w.box, diag, diag_size);
    if (!err)
        err = fdt_voronoi_resolution(r, xyz, w.box, -300, 1, diag, diag_size);
    int had_faces = r->face_verts != NULL;
    if (!err)
        err = fdt_locator_init(&w.loc, r, xyz, n);
    if (!had_faces)
        fdt_result_drop_faces(r); /* the neighbours are derived: 28 bytes a face back */
    if (err)
        goto done;
    memcpy(d->box, w.box, sizeof w.box);
    int ex = scale_points(&w);
    if (ex == INT_MIN) {
        err = FDT_ENOMEM;
        goto done;
    }
    w.side = fdt_box_side(w.box);
    w.nb = w.loc.nbrs;
    w.uf = malloc(w.T * sizeof *w.uf);
    w.cc = malloc(3 * w.T * sizeof *w.cc);
    w.rvid = malloc(w.T * sizeof *w.rvid);
    if (!w.uf || !w.cc || !w.rvid || kmap_init(&w.cross, 1024) != 0) {
        err = FDT_ENOMEM;
        goto done;
    }
    err = number_cells(&w, d);
    if (!err)
        err = merge_tets(&w);
    if (!err)
        err = number_hull(&w);
    if (!err)
        err = all_faces(&w);
    if (!err)
        err = merge_wall_vertices(&w);
    if (!err)
        err = all_walls(&w);
    if (!err && (w.nv > (size_t)INT32_MAX || w.nf > (size_t)INT32_MAX ||
                 w.nfv > (size_t)INT32_MAX)) {
        fdt_diag(diag, diag_size, "too many vertices or faces for OpenFOAM's 32-bit labels");
        err = FDT_ETOOBIG;
    }
    /* what the faces were built from goes before the mesh is copied out */
    fdt_locator_free(&w.loc);
    free(w.uf);
    free(w.cc);
    free(w.rvid);
    w.uf = w.rvid = NULL;
    w.cc = NULL;
    kmap_free(&w.cross);
    if (!err)
        err = assemble(&w, d);
    /* The check in the scaled frame (the volumes of 1e-150 wide cells
     * underflow in the points' own), with the box scaled alike; then back
     * to the points' scale (exact: a power of two). */
    double box[6];
    memcpy(box, d->box, sizeof box);
    memcpy(d->box, w.box, sizeof box);
    int bad = !err && check ? fdt_dualmesh_check(d, diag, diag_size) : 0;
    if (bad)
        err = bad == FDT_ENOMEM ? FDT_ENOMEM : FDT_EINTERNAL;
    memcpy(d->box, box, sizeof box);
    for (size_t i = 0; !err && ex && i < 3 * d->n_verts; i++)
        d->xyz[i] = ldexp(d->xyz[i], ex);
done:
    if (err == FDT_ENOMEM && !diag[0])
        fdt_diag(diag, diag_size, "out of memory");
    free_work(&w);
    if (err) {
        char keep[512];
        snprintf(keep, sizeof keep, "%s", diag);
        fdt_dualmesh_free(d);
        fdt_diag(diag, diag_size, "%s", keep);
    }
    return err;
}

int fdt_dualmesh_build(fdt_result *r, const double *xyz, size_t n,
                       const fdt_voronoi_options *o, fdt_dualmesh *d, char *diag,
                       size_t diag_size)
{
    return build(r, xyz, n, o, d, 1, diag, diag_size);
}

int fdt_dualmesh_build_unchecked(fdt_result *r, const double *xyz, size_t n,
                                 const fdt_voronoi_options *o, fdt_dualmesh *d, char *diag,
                                 size_t diag_size)
{
    return build(r, xyz, n, o, d, 0, diag, diag_size);
}
