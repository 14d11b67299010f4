/* The periodic dual from a plain one; see dualperiodic.h. */
#include "mesh/dualperiodic.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "base/diag.h"
#include "base/mem.h"
#include "base/sortu64.h"
#include "geom/images.h"
#include "geom/predicates.h"
#include "mesh/periodic.h"
#include "mesh/result.h"

/* An image's key: its cell above 12 bits, then its three offsets (each
 * within +-2 periods: a tet's vertices lie within one period of its
 * first, so two of them within two of each other) as 4 bits plus 8. */
#define OFF_BIAS 8

static uint64_t image_key(uint32_t cell, const int d[3])
{
    return (uint64_t)cell << 12 | (uint64_t)(d[0] + OFF_BIAS) << 8 |
           (uint64_t)(d[1] + OFF_BIAS) << 4 | (uint64_t)(d[2] + OFF_BIAS);
}

static void key_offsets(uint64_t key, int8_t d[3])
{
    for (int k = 0; k < 3; k++)
        d[k] = (int8_t)((int)(key >> (8 - 4 * k) & 15) - OFF_BIAS);
}

void fdt_dual_images_free(fdt_dual_images *im)
{
    free(im->xyz);
    free(im->src);
    free(im->off);
    free(im->cell_of);
    memset(im, 0, sizeof *im);
}

/* The images a cell's star needs: for each tet and each ordered pair of
 * its vertices (a, b) in different copies, b's image seen from a's copy.
 * Sorted, each once, into *keys. */
static int star_images(const fdt_result *r, const int32_t *cell_of, uint64_t **keys, size_t *nk,
                       char *diag, size_t ds)
{
    size_t cap = 0, k = 0;
    uint64_t *key = NULL;
    for (size_t t = 0; t < r->ntets; t++) {
        const fdt_vid *v = r->tets + 4 * t;
        const int8_t *o = r->tet_off + 12 * t;
        int any = 0;
        for (int i = 3; i < 12; i++)
            any |= o[i];
        if (!any)
            continue; /* one copy: every vertex is a cell's point */
        for (int a = 0; a < 4; a++)
            for (int b = 0; b < 4; b++) {
                int d[3], nz = 0, wide = 0;
                for (int c = 0; c < 3; c++) {
                    d[c] = o[3 * b + c] - o[3 * a + c];
                    nz |= d[c];
                    wide |= d[c] < -2 || d[c] > 2;
                }
                if (!nz)
                    continue;
                if (wide || cell_of[v[b]] < 0) {
                    free(key);
                    fdt_diag(diag, ds, "tet %zu of the periodic mesh spans more than a period, "
                        "or names a merged duplicate", t);
                    return FDT_EINTERNAL;
                }
                if (fdt_grow(&key, &cap, k + 1, sizeof *key) != 0) {
                    free(key);
                    return FDT_ENOMEM;
                }
                key[k++] = image_key((uint32_t)cell_of[v[b]], d);
            }
    }
    if (k)
        fdt_sort_u64(key, k);
    size_t u = 0;
    for (size_t i = 0; i < k; i++)
        if (!u || key[u - 1] != key[i])
            key[u++] = key[i];
    *keys = key;
    *nk = u;
    return FDT_OK;
}

/*
 * The plain dual's box: the periodic box on the axes that are not
 * periodic; on the periodic ones every point of im and every cell's
 * vertices, with an eighth of the span more on each side. A cell's
 * vertices are the circumcentres of its tets, each tet seen from the copy
 * of each of its vertices (the tet laid out from its first vertex, moved
 * back by that vertex's offsets).
 */
static int dual_box(const fdt_result *r, const double *xyz, const fdt_periodic_box *b,
                    fdt_dual_images *im, char *diag, size_t ds)
{
    double lo[3], hi[3], L[3];
    for (int k = 0; k < 3; k++) {
        lo[k] = b->lo[k];
        hi[k] = b->hi[k];
        L[k] = fdt_periodic_period(b, k);
    }
    for (size_t i = 0; i < im->m; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], im->xyz[3 * i + (size_t)k]);
            hi[k] = fmax(hi[k], im->xyz[3 * i + (size_t)k]);
        }
    for (size_t t = 0; t < r->ntets; t++) {
        const fdt_vid *v = r->tets + 4 * t;
        const int8_t *o = r->tet_off + 12 * t;
        double p[4][3], c[3];
        for (int i = 0; i < 4; i++)
            fdt_images_round(xyz + 3 * (size_t)v[i], o + 3 * i, b->lo, b->hi, p[i], NULL);
        if (fdt_circumcenter(p[0], p[1], p[2], p[3], c) != 0) {
            fdt_diag(diag, ds, "tet %zu of the periodic mesh (points %u, %u, %u, %u) is flat "
                "in doubles, or its circumcentre beyond them: its Voronoi vertex cannot be "
                "placed", t, (unsigned)v[0],
                (unsigned)v[1], (unsigned)v[2], (unsigned)v[3]);
            return FDT_ERANGE;
        }
        for (int k = 0; k < 3; k++) {
            if (!(b->axes >> k & 1))
                continue;
            double x = p[0][k] + c[k];
            for (int a = 0; a < 4; a++) {
                lo[k] = fmin(lo[k], x - o[3 * a + k] * L[k]);
                hi[k] = fmax(hi[k], x - o[3 * a + k] * L[k]);
            }
        }
    }
    for (int k = 0; k < 3; k++) {
        if (!(b->axes >> k & 1)) {
            im->box[k] = b->lo[k];
            im->box[k + 3] = b->hi[k];
            continue;
        }
        double pad = (hi[k] - lo[k]) / 8;
        im->box[k] = lo[k] - pad;
        im->box[k + 3] = hi[k] + pad;
        if (!isfinite(im->box[k]) || !isfinite(im->box[k + 3])) {
            fdt_diag(diag, ds, "the Voronoi vertices of the periodic mesh lie beyond doubles");
            return FDT_ERANGE;
        }
    }
    return FDT_OK;
}

int fdt_dual_images_make(const fdt_result *r, const double *xyz, size_t n, fdt_dual_images *im,
                         char *diag, size_t ds)
{
    memset(im, 0, sizeof *im);
    if (!r || !xyz || !r->periodic || r->streamed || n != r->n || !r->ntets) {
        fdt_diag(diag, ds, "the periodic dual needs the periodic result of fdt_triangulate on "
            "the same %zu points, with its tets", n);
        return FDT_EINVAL;
    }
    const fdt_periodic_box b = fdt_periodic_box_of(r->periodic, r->pbox);
    im->n = n;
    uint32_t *point_of = malloc((n + 1) * sizeof *point_of);
    im->cell_of = malloc((n + 1) * sizeof *im->cell_of);
    uint64_t *key = NULL;
    size_t nk = 0;
    int err = !point_of || !im->cell_of ? FDT_ENOMEM : FDT_OK;
    for (size_t i = 0; !err && i < n; i++) {
        im->cell_of[i] = r->dupmap[i] == (fdt_vid)i ? (int32_t)im->ncells : -1;
        if (im->cell_of[i] >= 0)
            point_of[im->ncells++] = (uint32_t)i;
    }
    if (!err)
        err = star_images(r, im->cell_of, &key, &nk, diag, ds);
    im->m = im->ncells + nk;
    if (!err && (!(im->xyz = malloc((3 * im->m + 1) * sizeof *im->xyz)) ||
                 !(im->src = malloc((im->m + 1) * sizeof *im->src)) ||
                 !(im->off = malloc((3 * im->m + 1) * sizeof *im->off))))
        err = FDT_ENOMEM;
    for (size_t c = 0; !err && c < im->ncells; c++) {
        memcpy(im->xyz + 3 * c, xyz + 3 * (size_t)point_of[c], 3 * sizeof *xyz);
        im->src[c] = (uint32_t)c;
        memset(im->off + 3 * c, 0, 3);
    }
    for (size_t i = 0; !err && i < nk; i++) {
        size_t s = im->ncells + i;
        uint32_t c = (uint32_t)(key[i] >> 12);
        im->src[s] = c;
        key_offsets(key[i], im->off + 3 * s);
        fdt_images_round(xyz + 3 * (size_t)point_of[c], im->off + 3 * s, b.lo, b.hi,
                         im->xyz + 3 * s, NULL);
    }
    free(key);
    free(point_of);
    if (!err)
        err = dual_box(r, xyz, &b, im, diag, ds);
    if (err == FDT_ENOMEM)
        fdt_diag(diag, ds, "out of memory");
    if (err)
        fdt_dual_images_free(im);
    return err;
}

/* ------------------------------------------------------------ the fold */

/* A face of the plain dual between cell a and an image: the image's cell
 * j and offsets d, and the face's index there. Its partner is the face
 * between cell j and a's image at -d, the same face moved by -d periods. */
typedef struct cface {
    uint32_t a, j;
    int8_t d[3];
    size_t f;
} cface;

static int cface_cmp(const void *x, const void *y)
{
    const cface *p = x, *q = y;
    if (p->a != q->a)
        return p->a < q->a ? -1 : 1;
    if (p->j != q->j)
        return p->j < q->j ? -1 : 1;
    for (int k = 0; k < 3; k++)
        if (p->d[k] != q->d[k])
            return p->d[k] < q->d[k] ? -1 : 1;
    return 0;
}

/* The sign of d's first nonzero offset. */
static int first_sign(const int8_t d[3])
{
    for (int k = 0; k < 3; k++)
        if (d[k])
            return d[k] > 0 ? 1 : -1;
    return 0;
}

/* The input id of cell c, for the messages (a scan: errors only). */
static size_t input_of(const fdt_dual_images *im, size_t c)
{
    for (size_t i = 0; i < im->n; i++)
        if (im->cell_of[i] == (int32_t)c)
            return i;
    return c;
}

typedef struct fold {
    const fdt_dualmesh *P;
    fdt_dualmesh *d;
    int64_t *newid; /* P's vertices: the new number, -1 unused */
    size_t nv, k;   /* vertices numbered; fverts written */
} fold;

/* Face f of P as face i of d, its vertices from position z on. */
static void put_face(fold *w, size_t i, size_t f, size_t z, int32_t own)
{
    const fdt_dualmesh *P = w->P;
    size_t m = P->fstart[f + 1] - P->fstart[f];
    w->d->fstart[i] = w->k;
    w->d->owner[i] = own;
    for (size_t j = 0; j < m; j++) {
        int32_t v = P->fverts[P->fstart[f] + (z + j) % m];
        if (w->newid[v] < 0)
            w->newid[v] = (int64_t)w->nv++;
        w->d->fverts[w->k++] = (int32_t)w->newid[v];
    }
}

/* Where face g of P starts to be listed from the point of face f's first
 * moved by sep: its vertex nearest there (in the largest coordinate
 * difference: no square of a 1e-160 wide set's underflows). */
static size_t nearest_start(const fdt_dualmesh *P, size_t f, size_t g, const double sep[3])
{
    const double *x = P->xyz + 3 * (size_t)P->fverts[P->fstart[f]];
    size_t best = 0;
    double bd = INFINITY;
    for (size_t j = 0; j < P->fstart[g + 1] - P->fstart[g]; j++) {
        const double *y = P->xyz + 3 * (size_t)P->fverts[P->fstart[g] + j];
        double dd = 0;
        for (int k = 0; k < 3; k++)
            dd = fmax(dd, fabs(x[k] + sep[k] - y[k]));
        if (dd < bd) {
            bd = dd;
            best = j;
        }
    }
    return best;
}

int fdt_dualmesh_fold(const fdt_dualmesh *P, const fdt_dual_images *im, const double pbox[6],
                      unsigned periodic, fdt_dualmesh *d, char *diag, size_t ds)
{
    memset(d, 0, sizeof *d);
    const size_t C = im->ncells;
    if (P->n_input != im->m || P->n_cells < C) {
        fdt_diag(diag, ds, "the plain dual is not of the images' points");
        return FDT_EINTERNAL;
    }
    const fdt_periodic_box b = fdt_periodic_box_of(periodic, pbox);
    double L[3];
    for (int k = 0; k < 3; k++)
        L[k] = fdt_periodic_period(&b, k);
    fold w = {P, d, NULL, 0, 0};
    size_t *img_of = malloc((P->n_cells - C + 1) * sizeof *img_of);
    cface *cf = malloc((P->n_faces + 1) * sizeof *cf);
    int (*shifts)[3] = NULL;
    size_t ncf = 0, nint = 0, nwall = 0, nfv = 0, nsh = 0;
    int err = !img_of || !cf ? FDT_ENOMEM : FDT_OK;
    /* every point a cell of its own, the cells' points first and in order
     * (an image rounded onto another point would stand in for it) */
    for (size_t s = 0; !err && s < im->m; s++) {
        int32_t c = P->cell_of[s];
        if (c < 0 || (s < C && (size_t)c != s)) {
            fdt_diag(diag, ds, "an image of point %zu rounds onto another point: the periodic "
                "cells cannot be told apart in doubles", input_of(im, im->src[s]));
            err = FDT_ERANGE;
        } else if (s >= C)
            img_of[(size_t)c - C] = s;
    }
    /* the faces kept: between two cells, a cell's on a wall, a cell's
     * with an image (the cells have the lower numbers: owners) */
    for (size_t f = 0; !err && f < P->n_internal; f++) {
        size_t o = (size_t)P->owner[f], nb = (size_t)P->neighbour[f];
        if (nb < C) {
            nint++;
            nfv += P->fstart[f + 1] - P->fstart[f];
        } else if (o < C) {
            size_t s = img_of[nb - C];
            cf[ncf] = (cface){(uint32_t)o, im->src[s], {0, 0, 0}, f};
            memcpy(cf[ncf++].d, im->off + 3 * s, 3);
            nfv += P->fstart[f + 1] - P->fstart[f];
        }
    }
    for (int p = 0; !err && p < 6; p++)
        for (size_t f = P->patch_start[p]; !err && f < P->patch_start[p] + P->patch_size[p];
             f++) {
            if ((size_t)P->owner[f] >= C)
                continue;
            if (periodic >> (p / 2) & 1) {
                fdt_diag(diag, ds, "the cell of point %zu reaches the images' box",
                    input_of(im, (size_t)P->owner[f]));
                err = FDT_EINTERNAL;
            }
            nwall++;
            nfv += P->fstart[f + 1] - P->fstart[f];
        }
    if (!err && ncf)
        qsort(cf, ncf, sizeof *cf, cface_cmp);
    /* each face whose partner lies at +s (s = -d, its first offset
     * positive) finds it; as many the other way */
    size_t npos = 0;
    if (!err && !(shifts = malloc((ncf + 1) * sizeof *shifts)))
        err = FDT_ENOMEM;
    for (size_t i = 0; !err && i < ncf; i++) {
        if (first_sign(cf[i].d) > 0)
            continue;
        npos++;
        cface want = {cf[i].j, cf[i].a, {(int8_t)-cf[i].d[0], (int8_t)-cf[i].d[1],
                                         (int8_t)-cf[i].d[2]}, 0};
        const cface *g = bsearch(&want, cf, ncf, sizeof *cf, cface_cmp);
        size_t f = cf[i].f;
        int s[3] = {-cf[i].d[0], -cf[i].d[1], -cf[i].d[2]};
        double sep[3] = {s[0] * L[0], s[1] * L[1], s[2] * L[2]};
        if (!g || !fdt_dual_faces_match(P->xyz, P->fverts + P->fstart[f],
                                        P->fstart[f + 1] - P->fstart[f],
                                        P->fverts + P->fstart[g->f],
                                        P->fstart[g->f + 1] - P->fstart[g->f],
                                        nearest_start(P, f, g->f, sep), sep)) {
            fdt_diag(diag, ds, "the Voronoi face of points %zu and %zu across a period cannot be "
                "matched with its copy on the other side in doubles: the images of the points "
                "are rounded (their coordinates plus a period are not doubles) and the face is "
                "too small or too near a cospherical tie to survive it (a period that adds "
                "exactly to the coordinates, e.g. a power of two on a grid of its ulp, keeps "
                "the copies exact)", input_of(im, cf[i].a), input_of(im, cf[i].j));
            err = FDT_ERANGE;
            break;
        }
        fdt_shift_add(shifts, &nsh, s);
    }
    if (!err && 2 * npos != ncf) {
        fdt_diag(diag, ds, "%zu faces across a period have no copy on the other side",
            ncf - 2 * npos);
        err = FDT_ERANGE;
    }
    size_t nf = nint + nwall + ncf;
    if (!err && (nf > (size_t)INT32_MAX || nfv > (size_t)INT32_MAX)) {
        fdt_diag(diag, ds, "too many faces for OpenFOAM's 32-bit labels");
        err = FDT_ETOOBIG;
    }
    if (!err && (!(d->fstart = malloc((nf + 1) * sizeof *d->fstart)) ||
                 !(d->fverts = malloc((nfv + 1) * sizeof *d->fverts)) ||
                 !(d->owner = malloc((nf + 1) * sizeof *d->owner)) ||
                 !(d->neighbour = malloc((nint + 1) * sizeof *d->neighbour)) ||
                 !(d->cyclic = calloc(2 * nsh + 1, sizeof *d->cyclic)) ||
                 !(d->cell_of = malloc((im->n + 1) * sizeof *d->cell_of)) ||
                 !(w.newid = malloc((P->n_verts + 1) * sizeof *w.newid))))
        err = FDT_ENOMEM;
    if (!err) {
        for (size_t v = 0; v < P->n_verts; v++)
            w.newid[v] = -1;
        size_t i = 0;
        for (size_t f = 0; f < P->n_internal; f++)
            if ((size_t)P->neighbour[f] < C) {
                d->neighbour[i] = P->neighbour[f];
                put_face(&w, i++, f, 0, P->owner[f]);
            }
        for (int p = 0; p < 6; p++) {
            d->patch_start[p] = i;
            for (size_t f = P->patch_start[p]; f < P->patch_start[p] + P->patch_size[p]; f++)
                if ((size_t)P->owner[f] < C)
                    put_face(&w, i++, f, 0, P->owner[f]);
            d->patch_size[p] = i - d->patch_start[p];
        }
        for (size_t k = 0; k < nsh; k++)
            for (int side = 0; side < 2; side++) {
                fdt_dual_cyclic *y = &d->cyclic[2 * k + (size_t)side];
                y->start = i;
                for (int c = 0; c < 3; c++) {
                    y->shift[c] = side ? -shifts[k][c] : shifts[k][c];
                    y->sep[c] = y->shift[c] * L[c];
                }
                for (size_t j = 0; j < ncf; j++) {
                    int s[3] = {-cf[j].d[0], -cf[j].d[1], -cf[j].d[2]};
                    if (first_sign(cf[j].d) > 0 || fdt_shift_cmp(s, shifts[k]))
                        continue;
                    if (!side) {
                        put_face(&w, i++, cf[j].f, 0, (int32_t)cf[j].a);
                        continue;
                    }
                    cface want = {cf[j].j, cf[j].a, {(int8_t)s[0], (int8_t)s[1], (int8_t)s[2]},
                                  0};
                    const cface *g = bsearch(&want, cf, ncf, sizeof *cf, cface_cmp);
                    put_face(&w, i++, g->f, nearest_start(P, cf[j].f, g->f, d->cyclic[2 * k].sep),
                             (int32_t)g->a);
                }
                y->size = i - y->start;
            }
        d->fstart[nf] = w.k;
        d->n_faces = nf;
        d->n_internal = nint;
        d->n_cells = C;
        d->n_cyclic = 2 * nsh;
        d->n_verts = w.nv;
        if (!(d->xyz = malloc((3 * w.nv + 1) * sizeof *d->xyz)))
            err = FDT_ENOMEM;
    }
    if (!err) {
        for (size_t v = 0; v < P->n_verts; v++)
            if (w.newid[v] >= 0)
                memcpy(d->xyz + 3 * (size_t)w.newid[v], P->xyz + 3 * v, 3 * sizeof *d->xyz);
        memcpy(d->cell_of, im->cell_of, im->n * sizeof *d->cell_of);
        d->n_input = im->n;
        memcpy(d->box, pbox, sizeof d->box);
        d->periodic = periodic;
        int bad = fdt_dualmesh_check_scaled(d, diag, ds);
        if (bad)
            err = bad == FDT_ENOMEM ? FDT_ENOMEM : FDT_EINTERNAL;
    }
    if (err == FDT_ENOMEM)
        fdt_diag(diag, ds, "out of memory");
    free(img_of);
    free(cf);
    free(shifts);
    free(w.newid);
    if (err) {
        char keep[512];
        fdt_diag(keep, sizeof keep, "%s", diag);
        fdt_dualmesh_free(d);
        fdt_diag(diag, ds, "%s", keep);
    }
    return err;
}
