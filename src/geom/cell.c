/* A convex cell cut from a box by half-spaces: see cell.h. */
#include "geom/cell.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { IN = 0, ON = 1, OUT = 2 };

/* Grows *pp (elements of `size` bytes, capacity *cap) to hold `need`. */
static int grow(void *pp, int *cap, int need, size_t size)
{
    if (need <= *cap)
        return 0;
    int nc = *cap ? *cap : 16;
    while (nc < need)
        nc *= 2;
    void **p = (void **)pp;
    void *q = realloc(*p, (size_t)nc * size);
    if (!q)
        return -1;
    *p = q;
    *cap = nc;
    return 0;
}

void fdt_cell_init(fdt_cell *c)
{
    memset(c, 0, sizeof *c);
}

void fdt_cell_free(fdt_cell *c)
{
    free(c->p);
    free(c->ring);
    free(c->f);
    free(c->v);
    free(c->ekey);
    free(c->tring);
    free(c->tf);
    free(c->tp);
    free(c->touched);
    free(c->inc_head);
    free(c->inc);
    free(c->stamp);
    free(c->fstamp);
    free(c->queue);
    fdt_cell_init(c);
}

static double norm3(const double x[3])
{
    return sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
}

int fdt_cell_box(fdt_cell *c, const double lo[3], const double hi[3])
{
    /* Vertex i has x = hi if bit 0, y = hi if bit 1, z = hi if bit 2;
     * each ring counter-clockwise seen from outside. */
    static const int faces[6][4] = {
        {0, 4, 6, 2}, /* x-min */
        {1, 3, 7, 5}, /* x-max */
        {0, 1, 5, 4}, /* y-min */
        {2, 6, 7, 3}, /* y-max */
        {0, 2, 3, 1}, /* z-min */
        {4, 5, 7, 6}, /* z-max */
    };
    if (grow(&c->p, &c->capp, 8, sizeof *c->p) || grow(&c->ring, &c->capring, 24, sizeof(int)) ||
        grow(&c->f, &c->capf, 6, sizeof *c->f))
        return -1;
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++)
            c->p[i][k] = (i >> k) & 1 ? hi[k] : lo[k];
    c->np = 8;
    for (int f = 0; f < 6; f++) {
        c->f[f] = (fdt_cell_ring){4 * f, 4, FDT_CELL_WALL(f)};
        memcpy(c->ring + 4 * f, faces[f], sizeof faces[f]);
    }
    c->nf = 6;
    c->nring = c->live_ring = 24;
    c->ndead = 0;
    c->inc_ok = 0;
    c->hint = 0;
    /* Cuts only shrink the cell, and a crossing lies between two
     * vertices up to a rounding: 2^-20 of slack covers any drift. */
    c->l1max = 0;
    for (int i = 0; i < 8; i++) {
        double l1 = fabs(c->p[i][0]) + fabs(c->p[i][1]) + fabs(c->p[i][2]);
        c->l1max = l1 > c->l1max ? l1 : c->l1max;
    }
    c->l1max *= 1 + 0x1p-20;
    return 0;
}

int fdt_cell_copy(fdt_cell *dst, const fdt_cell *src)
{
    if (grow(&dst->p, &dst->capp, src->np, sizeof *dst->p) ||
        grow(&dst->ring, &dst->capring, src->nring, sizeof(int)) ||
        grow(&dst->f, &dst->capf, src->nf, sizeof *dst->f))
        return -1;
    memcpy(dst->p, src->p, (size_t)src->np * sizeof *dst->p);
    memcpy(dst->ring, src->ring, (size_t)src->nring * sizeof(int));
    memcpy(dst->f, src->f, (size_t)src->nf * sizeof *dst->f);
    dst->np = src->np;
    dst->nring = src->nring;
    dst->nf = src->nf;
    dst->live_ring = src->live_ring;
    dst->ndead = src->ndead;
    dst->inc_ok = 0;
    dst->hint = 0;
    dst->l1max = src->l1max;
    return 0;
}

/* The point where the plane crosses edge (a, b), a inside and b outside:
 * made once per edge and shared by the two faces along it, and computed
 * from the inside end for both. -1 when out of memory. */
static int crossing(fdt_cell *c, int a, int b)
{
    for (int i = 0; i < c->ne; i++)
        if (c->ekey[3 * i] == a && c->ekey[3 * i + 1] == b)
            return c->ekey[3 * i + 2];
    if (grow(&c->ekey, &c->cape, 3 * (c->ne + 1), sizeof(int)) ||
        grow(&c->p, &c->capp, c->np + 1, sizeof *c->p) ||
        grow(&c->v, &c->capv, c->np + 1, sizeof *c->v))
        return -1;
    double t = c->v[a].s / (c->v[a].s - c->v[b].s);
    int x = c->np++;
    for (int k = 0; k < 3; k++)
        c->p[x][k] = c->p[a][k] + t * (c->p[b][k] - c->p[a][k]);
    c->v[x] = (fdt_cell_scratch){0, ON, -1, -1};
    c->ekey[3 * c->ne] = a;
    c->ekey[3 * c->ne + 1] = b;
    c->ekey[3 * c->ne + 2] = x;
    c->ne++;
    return x;
}

/* The scratch faces' entries and faces, in the room cut_tol made for a
 * cut's most (room_for_cut): one entry or face a call, with no test. */
static inline void push_ring(fdt_cell *c, int v)
{
    c->tring[c->ntring++] = v;
}

static inline void push_face(fdt_cell *c, int start, long label)
{
    c->tf[c->ntf++] = (fdt_cell_ring){start, c->ntring - start, label};
}

/* Room for a cut's scratch faces: a face's entries are at most its
 * vertices and a crossing an edge (a convex face keeps at most one more
 * than it had, but a cut among vertices closer than their rounding can
 * cross a face's edges several times before cut_tol finds it not convex),
 * the cap's one a face and one more before an open chain stops it, and
 * the faces at most one more. 0 or -1. */
static int room_for_cut(fdt_cell *c)
{
    return grow(&c->tring, &c->captring, 2 * c->nring + c->nf + 1, sizeof(int)) ||
                   grow(&c->tf, &c->captf, c->nf + 1, sizeof *c->tf)
               ? -1
               : 0;
}

/* Face f cut by the plane: its kept part goes to the scratch faces, and
 * its one crossing of the plane, entry -> exit as the cap runs it, into
 * next[] (the face runs exit -> entry; the cap shares that edge, so it
 * runs it the other way). Returns the entry, -1 for no crossing, -2 when
 * out of memory, -3 for a second crossing (not convex). */
static int cut_face(fdt_cell *c, const fdt_cell_ring *f)
{
    const int *r = c->ring + f->start;
    int k = f->count, start = c->ntring, entry = -1, exitp = -1;
    for (int j = 0; j < k; j++) {
        int a = r[j], b = j + 1 < k ? r[j + 1] : r[0];
        int sa = c->v[a].side, sb = c->v[b].side;
        if (sa != OUT)
            push_ring(c, a);
        if (sa != OUT && sb == OUT) {
            exitp = a;
            if (sa == IN) {
                if ((exitp = crossing(c, a, b)) < 0)
                    return -2;
                push_ring(c, exitp);
            }
        } else if (sa == OUT && sb != OUT) {
            entry = b;
            if (sb == IN) {
                if ((entry = crossing(c, b, a)) < 0)
                    return -2;
                push_ring(c, entry);
            }
        }
    }
    if (c->ntring - start >= 3)
        push_face(c, start, f->label);
    if (c->ntring - start < 3) /* nothing of the face is left */
        c->ntring = start;
    if (entry < 0 || exitp < 0 || entry == exitp)
        return -1;
    if (c->v[entry].next >= 0)
        return -3;
    c->v[entry].next = exitp;
    return entry;
}

/* The new vertex array: the vertices the scratch faces use, renumbered in
 * first use; the scratch faces become the cell's. */
static int compact(fdt_cell *c)
{
    int m = 0;
    for (int i = 0; i < c->np; i++)
        c->v[i].map = -1;
    for (int i = 0; i < c->ntring; i++)
        if (c->v[c->tring[i]].map < 0)
            c->v[c->tring[i]].map = m++;
    /* tp as large as p: after the swap below, the next crossings find
     * room without a realloc */
    if (grow(&c->tp, &c->captp, m > c->capp ? m : c->capp, sizeof *c->tp) ||
        grow(&c->ring, &c->capring, c->ntring, sizeof(int)) ||
        grow(&c->f, &c->capf, c->ntf, sizeof *c->f))
        return -1;
    for (int i = 0; i < c->np; i++)
        if (c->v[i].map >= 0)
            memcpy(c->tp[c->v[i].map], c->p[i], sizeof c->tp[0]);
    double(*t)[3] = c->p; /* swap the vertex arrays */
    int tc = c->capp;
    c->p = c->tp;
    c->capp = c->captp;
    c->tp = t;
    c->captp = tc;
    c->np = m;
    for (int i = 0; i < c->ntring; i++)
        c->ring[i] = c->v[c->tring[i]].map;
    memcpy(c->f, c->tf, (size_t)c->ntf * sizeof *c->f);
    c->nring = c->ntring;
    c->nf = c->ntf;
    c->inc_ok = 0;
    c->hint = 0;
    return 0;
}

/* The live faces' rings copied to the scratch, then compact: the
 * vertices and entries no face uses dropped. */
int fdt_cell_compact(fdt_cell *c)
{
    if (c->ndead == 0 && c->live_ring == c->nring)
        return 0;
    c->ntring = c->ntf = 0;
    if (grow(&c->tring, &c->captring, c->live_ring, sizeof(int)) ||
        grow(&c->tf, &c->captf, c->nf, sizeof *c->tf) ||
        grow(&c->v, &c->capv, c->np, sizeof *c->v))
        return -1;
    for (int f = 0; f < c->nf; f++) {
        int start = c->ntring;
        for (int j = 0; j < c->f[f].count; j++)
            push_ring(c, c->ring[c->f[f].start + j]);
        push_face(c, start, c->f[f].label);
    }
    if (compact(c))
        return -1;
    c->live_ring = c->nring;
    c->ndead = 0;
    return 0;
}

/* ------------------------------------------------------------------ */
/* Each vertex's faces, for the climb                                  */
/* ------------------------------------------------------------------ */

/* The vertices from which a cut climbs (climb()) rather than classing
 * them all: a cell clipped by the box has a few dozen (most cut cells:
 * the vertices' faces cost more than the classing there, a terrain
 * scan's cells took 20 % longer), an outlier's thousands. */
#define CLIMB_MIN_VERTICES 64

/* Vertex v is entry pos of face f's ring. */
static int inc_add(fdt_cell *c, int v, int f, int pos)
{
    if (grow(&c->inc, &c->capinc, 3 * (c->ninc + 1), sizeof(int)))
        return -1;
    c->inc[3 * c->ninc] = f;
    c->inc[3 * c->ninc + 1] = pos;
    c->inc[3 * c->ninc + 2] = c->inc_head[v];
    c->inc_head[v] = c->ninc++;
    return 0;
}

/* Vertex v is now entry pos of face f's rewritten ring. */
static int inc_move(fdt_cell *c, int v, int f, int pos)
{
    for (int e = c->inc_head[v]; e >= 0; e = c->inc[3 * e + 2])
        if (c->inc[3 * e] == f) {
            c->inc[3 * e + 1] = pos;
            return 0;
        }
    return inc_add(c, v, f, pos);
}

/* The faces of every vertex, from the rings; the stamps cleared. */
static int inc_build(fdt_cell *c)
{
    if (grow(&c->inc_head, &c->capinchead, c->np, sizeof(int)) ||
        grow(&c->stamp, &c->capstamp, c->np, sizeof *c->stamp) ||
        grow(&c->fstamp, &c->capfstamp, c->nf + 1, sizeof *c->fstamp))
        return -1;
    c->ninc = 0;
    for (int i = 0; i < c->np; i++) {
        c->inc_head[i] = -1;
        c->stamp[i] = 0;
    }
    for (int f = 0; f < c->nf; f++) {
        c->fstamp[f] = 0;
        for (int j = 0; j < c->f[f].count; j++)
            if (inc_add(c, c->ring[c->f[f].start + j], f, j))
                return -1;
    }
    c->cutno = 0;
    c->inc_ok = 1;
    return 0;
}

/* The plane of one cut and its classing of a vertex. Each vertex has
 * its own tolerance, the size of the rounding in its s: a far vertex's
 * is coarse, a near one's fine, so a small cell cut from a large box
 * keeps its precision (one tolerance for all, scaled by the box, cost a
 * cell 1e-6 of the box 1e-7 of its volume). */
typedef struct plane {
    double n[3], h, n1, tol;
} plane;

static inline int class_of(const plane *pl, const double *p, double *s)
{
    *s = pl->n[0] * p[0] + pl->n[1] * p[1] + pl->n[2] * p[2] - pl->h;
    double eps = pl->tol * (pl->n1 * (fabs(p[0]) + fabs(p[1]) + fabs(p[2])) + fabs(pl->h));
    return *s > eps ? OUT : *s < -eps ? IN : ON;
}

/* Vertex v classed for this cut (once: the stamp). */
static inline void class_once(fdt_cell *c, const plane *pl, int v)
{
    if (c->stamp[v] == c->cutno)
        return;
    double s;
    int side = class_of(pl, c->p[v], &s);
    c->v[v] = (fdt_cell_scratch){s, side, -1, -1};
    c->stamp[v] = c->cutno;
}

/* The neighbour before (k = 0) or after (k = 1) the vertex of incidence
 * entry e in its face's ring. */
static inline int ring_neighbour(const fdt_cell *c, int e, int k)
{
    const fdt_cell_ring *f = &c->f[c->inc[3 * e]];
    int j = c->inc[3 * e + 1] + (k ? 1 : f->count - 1);
    return c->ring[f->start + (j >= f->count ? j - f->count : j)];
}

/*
 * The vertices outside the plane found without classing the others:
 * from the hint, climb to a neighbour farther out while there is one (on
 * a convex cell the last is the farthest vertex), then walk the outside
 * region from it through neighbours. 1 with the region in queue[0 ..
 * *nq), 0 when no vertex is outside, -1 out of memory, 2 when the climb
 * cannot tell (the farthest vertex within the largest tolerance of the
 * plane, or no vertex inside met): the caller classes every vertex.
 */
static int climb(fdt_cell *c, const plane *pl, int *nq)
{
    if (!c->inc_ok && inc_build(c))
        return -1;
    if (grow(&c->v, &c->capv, c->np, sizeof *c->v) ||
        grow(&c->queue, &c->capqueue, c->np, sizeof(int)))
        return -1;
    if (++c->cutno == 0) { /* the stamps wrapped: start again */
        if (inc_build(c))
            return -1;
        c->cutno = 1;
    }
    int cur = c->hint;
    if (cur < 0 || cur >= c->np || c->inc_head[cur] < 0 || isnan(c->p[cur][0]))
        cur = c->ring[c->f[0].start];
    class_once(c, pl, cur);
    for (int moved = 1; moved;) {
        moved = 0;
        for (int e = c->inc_head[cur]; e >= 0 && !moved; e = c->inc[3 * e + 2])
            for (int k = 0; k < 2 && !moved; k++) {
                int u = ring_neighbour(c, e, k);
                class_once(c, pl, u);
                if (c->v[u].s > c->v[cur].s) {
                    cur = u;
                    moved = 1;
                }
            }
    }
    double epsmax = pl->tol * (pl->n1 * c->l1max + fabs(pl->h));
    if (c->v[cur].s < -epsmax)
        return 0; /* every vertex farther in than any tolerance */
    if (c->v[cur].side != OUT || c->v[cur].s <= epsmax)
        return 2;
    int n = 0, in = 0;
    c->queue[n++] = cur;
    c->v[cur].map = 1; /* queued (map is only compact's) */
    for (int q = 0; q < n; q++) {
        int v = c->queue[q];
        for (int e = c->inc_head[v]; e >= 0; e = c->inc[3 * e + 2])
            for (int k = 0; k < 2; k++) {
                int u = ring_neighbour(c, e, k);
                class_once(c, pl, u);
                if (c->v[u].side == OUT && c->v[u].map != 1) {
                    c->v[u].map = 1;
                    c->queue[n++] = u;
                }
                in |= c->v[u].side == IN;
            }
    }
    *nq = n;
    return in ? 1 : 2;
}

/*
 * A cut's faces made the cell's (cut_tol, once it has them all in the
 * scratch): each kept face reached by the cut gets its new ring at the
 * end of ring[] (its old one left there unused), a face cut away goes
 * (the others keep their order), the cap (if any: the scratch's last
 * face) comes last, and the vertices cut off, out[0 .. nout), become
 * NaN. The faces of each vertex follow. np0: the vertices before the cut's crossings. 0, or -1 when
 * out of memory (the cell is then as before the cut but for unused
 * room).
 */
static int apply_cut(fdt_cell *c, int nt, int np0, const int *out, int nout)
{
    if (grow(&c->ring, &c->capring, c->nring + c->ntring, sizeof(int)) ||
        grow(&c->f, &c->capf, c->nf + 1, sizeof *c->f) ||
        (c->inc_ok && (grow(&c->inc_head, &c->capinchead, c->np, sizeof(int)) ||
                       grow(&c->stamp, &c->capstamp, c->np, sizeof *c->stamp) ||
                       grow(&c->fstamp, &c->capfstamp, c->nf + 1, sizeof *c->fstamp))))
        return -1;
    for (int x = np0; c->inc_ok && x < c->np; x++) {
        c->inc_head[x] = -1;
        c->stamp[x] = 0;
    }
    int t = 0, gone = 0;
    for (int i = 0; i < nt; i++) {
        int f = c->touched[i];
        if (f < 0) {
            f = -1 - f;
            c->live_ring -= c->f[f].count;
            c->f[f].count = 0;
            gone++;
            continue;
        }
        const fdt_cell_ring *src = &c->tf[t++];
        memcpy(c->ring + c->nring, c->tring + src->start, (size_t)src->count * sizeof(int));
        for (int j = 0; c->inc_ok && j < src->count; j++) {
            int v = c->tring[src->start + j];
            if (v >= np0 ? inc_add(c, v, f, j) : inc_move(c, v, f, j))
                c->inc_ok = 0; /* out of memory: rebuilt at the next cut */
        }
        c->live_ring += src->count - c->f[f].count;
        c->f[f].start = c->nring;
        c->f[f].count = src->count;
        c->nring += src->count;
    }
    if (gone) { /* the faces' numbers move: their vertices' lists rebuilt */
        int m = 0;
        for (int f = 0; f < c->nf; f++)
            if (c->f[f].count > 0)
                c->f[m++] = c->f[f];
        c->nf = m;
        c->inc_ok = 0;
    }
    if (t < c->ntf) { /* the cap */
        const fdt_cell_ring *src = &c->tf[t];
        memcpy(c->ring + c->nring, c->tring + src->start, (size_t)src->count * sizeof(int));
        for (int j = 0; c->inc_ok && j < src->count; j++)
            if (inc_add(c, c->tring[src->start + j], c->nf, j))
                c->inc_ok = 0;
        if (c->inc_ok)
            c->fstamp[c->nf] = 0;
        c->hint = c->tring[src->start];
        c->f[c->nf++] = (fdt_cell_ring){c->nring, src->count, src->label};
        c->nring += src->count;
        c->live_ring += src->count;
    }
    for (int i = 0; i < nout; i++)
        c->p[out[i]][0] = c->p[out[i]][1] = c->p[out[i]][2] = NAN;
    c->ndead += nout;
    /* the space left unused, once it is as large as what is used (out
     * of memory there leaves it for later: the cell is whole either way) */
    if (c->nring > 2 * c->live_ring + 256 || 2 * c->ndead > c->np + 256)
        (void)fdt_cell_compact(c);
    return 0;
}

/* Face f cut (cut_face) into the scratch, its fate in touched[*nt]:
 * 1 with its entry (or -1), or -2 / -3 as cut_face. */
static int cut_one(fdt_cell *c, int f, int *nt, int *first, int *edges)
{
    int tf0 = c->ntf;
    int e = cut_face(c, &c->f[f]);
    if (e == -2 || e == -3)
        return e;
    c->touched[(*nt)++] = c->ntf > tf0 ? f : -1 - f;
    if (e >= 0) {
        (*edges)++;
        if (*first < 0)
            *first = e;
    }
    return 1;
}

static int int_cmp(const void *x, const void *y)
{
    int a = *(const int *)x, b = *(const int *)y;
    return (a > b) - (a < b);
}

/*
 * fdt_cell_cut with the ON tolerance tol (FDT_CELL_TOL, or coarser).
 * The vertices outside come from a climb and a walk (climb()), the
 * faces they are on from each vertex's faces, and only those faces are
 * cut and rewritten: a cut costs about what it changes. Where the climb
 * cannot tell, every vertex is classed and every face looked at, as
 * before. Rebuilding every face at every cut took k^2 / 2 ring copies
 * for a cell of k faces (a scan's outlier above it, thousands of
 * Delaunay neighbours: bench/NOTES.md entry 129).
 */
static int cut_tol(fdt_cell *c, const double n[3], double h, long label, double tol)
{
    plane pl = {{n[0], n[1], n[2]}, h, fabs(n[0]) + fabs(n[1]) + fabs(n[2]), tol};
    int nq = 0;
    /* a small cell is classed whole: quicker than its faces' lists */
    int got = c->np >= CLIMB_MIN_VERTICES && !c->classify_all ? climb(c, &pl, &nq) : 2;
    if (got < 0)
        return -1;
    if (got == 0)
        return 0;
    int full = got == 2;
    if (full) {
        /* Each vertex classed once; a crossing point is ON by construction.
         * The ones outside listed as the climb lists them. */
        if (grow(&c->v, &c->capv, c->np, sizeof *c->v) ||
            grow(&c->queue, &c->capqueue, c->np, sizeof(int)))
            return -1;
        int nin = 0;
        nq = 0; /* an undecided walk's list discarded */
        for (int i = 0; i < c->np; i++) {
            double s;
            int side = class_of(&pl, c->p[i], &s);
            c->v[i] = (fdt_cell_scratch){s, side, -1, -1};
            if (side == OUT)
                c->queue[nq++] = i;
            nin += side == IN;
        }
        if (nq == 0)
            return 0;
        if (nin == 0)
            return -2;
    }

    int np0 = c->np, nt = 0, m = 0;
    c->ne = c->ntring = c->ntf = 0;
    if (room_for_cut(c) || grow(&c->touched, &c->captouched, c->nf, sizeof(int)))
        return -1;
    /* The faces with a vertex outside, in their order (the others are
     * wholly kept: left as they are). */
    if (full) {
        for (int f = 0; f < c->nf; f++) {
            const int *r = c->ring + c->f[f].start;
            int out = 0;
            for (int j = 0; j < c->f[f].count; j++)
                out |= c->v[r[j]].side == OUT;
            if (out)
                c->touched[m++] = f;
        }
    } else {
        /* the faces of the vertices outside, every vertex of each classed */
        for (int q = 0; q < nq; q++)
            for (int e = c->inc_head[c->queue[q]]; e >= 0; e = c->inc[3 * e + 2]) {
                int f = c->inc[3 * e];
                if (c->fstamp[f] != c->cutno) {
                    c->fstamp[f] = c->cutno;
                    c->touched[m++] = f;
                }
            }
        qsort(c->touched, (size_t)m, sizeof(int), int_cmp);
        for (int i = 0; i < m; i++)
            for (int j = 0; j < c->f[c->touched[i]].count; j++)
                class_once(c, &pl, c->ring[c->f[c->touched[i]].start + j]);
    }
    int first = -1, edges = 0;
    for (int i = 0; i < m; i++) {
        /* touched[nt] is written as touched[i] is read: nt <= i */
        int e = cut_one(c, c->touched[i], &nt, &first, &edges);
        if (e < 0) {
            c->np = np0; /* the crossings made so far unmade */
            return e == -2 ? -1 : -3;
        }
    }
    /* The cap: from an entry, round the next[] chain to it again. */
    if (edges >= 3) {
        int start = c->ntring, v = first, steps = 0;
        do {
            push_ring(c, v);
            v = c->v[v].next;
            if (v < 0 || ++steps > edges) {
                c->np = np0;
                return -3; /* an open chain: not a convex cell */
            }
        } while (v != first);
        push_face(c, start, label);
    }
    return apply_cut(c, nt, np0, c->queue, nq) ? -1 : 1;
}

/* A cut that finds the cell not convex has met vertices closer together
 * than their rounding, classed on both sides of a plane that passes among
 * them: where many nearly cospherical points' cells meet (gen_points
 * sphere12 at 20,000 points, seed 3: a point with 57 Delaunay neighbours,
 * its 21st cut; another whose cell already had edges 1e-14 long, a vertex
 * on the plane entered from two faces). The cell is unchanged by such a
 * cut, so it is tried again with coarser tolerances, which put a cluster
 * on the plane, and last with none (signs alone: every vertex off the
 * plane, a crossing for each change of sign), which cut the second. */
int fdt_cell_cut(fdt_cell *c, const double n[3], double h, long label)
{
    int got = cut_tol(c, n, h, label, FDT_CELL_TOL);
    for (double tol = FDT_CELL_TOL * 0x1p8; got == -3 && tol <= FDT_CELL_TOL_MAX; tol *= 0x1p8)
        got = cut_tol(c, n, h, label, tol);
    if (got == -3)
        got = cut_tol(c, n, h, label, 0);
    return got;
}

void fdt_cell_measure(const fdt_cell *c, double *volume, double *area, double centroid[3],
                      fdt_cell_face *faces)
{
    double vol = 0, ar = 0, mom[3] = {0, 0, 0};
    for (int f = 0; f < c->nf; f++) {
        const int *r = c->ring + c->f[f].start;
        int k = c->f[f].count;
        const double *p0 = c->p[r[0]];
        double nv[3] = {0, 0, 0};
        for (int j = 1; j + 1 < k; j++) {
            const double *p1 = c->p[r[j]], *p2 = c->p[r[j + 1]];
            double u[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
            double w[3] = {p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]};
            nv[0] += u[1] * w[2] - u[2] * w[1];
            nv[1] += u[2] * w[0] - u[0] * w[2];
            nv[2] += u[0] * w[1] - u[1] * w[0];
            /* The tet (site, p0, p1, p2), the site at the origin: six
             * times its volume, and its centroid times 4. */
            double v6 = p0[0] * (p1[1] * p2[2] - p1[2] * p2[1]) -
                        p0[1] * (p1[0] * p2[2] - p1[2] * p2[0]) +
                        p0[2] * (p1[0] * p2[1] - p1[1] * p2[0]);
            vol += v6;
            for (int d = 0; d < 3; d++)
                mom[d] += v6 * (p0[d] + p1[d] + p2[d]);
        }
        double a = 0.5 * norm3(nv);
        ar += a;
        if (faces)
            faces[f] = (fdt_cell_face){c->f[f].label, a};
    }
    *volume = vol / 6;
    *area = ar;
    for (int d = 0; d < 3; d++)
        centroid[d] = vol != 0 ? mom[d] / (4 * vol) : 0;
}
