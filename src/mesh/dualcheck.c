/*
 * The check of a dual polyhedral mesh (src/mesh/dualmesh.h), on its own:
 * it reads only the finished fdt_dualmesh, none of the construction's
 * work, so that src/mesh/dualmesh.c's output is judged by rules it does
 * not share (OpenFOAM's: tests/dual_e2e.py runs checkMesh as well).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/sortu64.h"
#include "base/diag.h"
#include "mesh/dualmesh.h"
#include "mesh/voronoi.h"

static int u64_cmp(const void *x, const void *y)
{
    uint64_t a = *(const uint64_t *)x, b = *(const uint64_t *)y;
    return a < b ? -1 : a > b;
}

/* *buf holds at least need keys (doubling); 0 or -1. */
static int grow(uint64_t **buf, size_t *cap, size_t need)
{
    if (need <= *cap)
        return 0;
    size_t c = *cap ? *cap : 64;
    while (c < need)
        c *= 2;
    uint64_t *q = realloc(*buf, c * sizeof *q);
    if (!q)
        return -1;
    *buf = q;
    *cap = c;
    return 0;
}

int fdt_dualmesh_cell_faces(const fdt_dualmesh *d, size_t **start, size_t **faces)
{
    size_t *s = calloc(d->n_cells + 2, sizeof *s);
    size_t *f = malloc((2 * d->n_faces + 1) * sizeof *f);
    if (!s || !f) {
        free(s);
        free(f);
        return FDT_ENOMEM;
    }
    for (size_t i = 0; i < d->n_faces; i++) {
        s[d->owner[i] + 2]++;
        if (i < d->n_internal)
            s[d->neighbour[i] + 2]++;
    }
    for (size_t c = 0; c < d->n_cells; c++)
        s[c + 2] += s[c + 1];
    for (size_t i = 0; i < d->n_faces; i++) {
        f[s[d->owner[i] + 1]++] = i;
        if (i < d->n_internal)
            f[s[d->neighbour[i] + 1]++] = i;
    }
    *start = s;
    *faces = f;
    return FDT_OK;
}

double fdt_dualmesh_cell_volume(const fdt_dualmesh *d, const size_t *cs, const size_t *cf,
                                size_t c)
{
    if (cs[c] == cs[c + 1])
        return 0;
    const double *ref = d->xyz + 3 * (size_t)d->fverts[d->fstart[cf[cs[c]]]];
    double vol = 0;
    for (size_t j = cs[c]; j < cs[c + 1]; j++) {
        size_t f = cf[j];
        double sg = d->owner[f] == (int32_t)c ? 1 : -1, sum = 0;
        const int32_t *v = d->fverts + d->fstart[f];
        size_t m = d->fstart[f + 1] - d->fstart[f];
        double a[3];
        for (int k = 0; k < 3; k++)
            a[k] = d->xyz[3 * (size_t)v[0] + (size_t)k] - ref[k];
        for (size_t i = 1; i + 1 < m; i++) {
            double b[3], e[3];
            for (int k = 0; k < 3; k++) {
                b[k] = d->xyz[3 * (size_t)v[i] + (size_t)k] - ref[k];
                e[k] = d->xyz[3 * (size_t)v[i + 1] + (size_t)k] - ref[k];
            }
            sum += a[0] * (b[1] * e[2] - b[2] * e[1]) + a[1] * (b[2] * e[0] - b[0] * e[2]) +
                   a[2] * (b[0] * e[1] - b[1] * e[0]);
        }
        vol += sg * sum / 6;
    }
    return vol;
}

/* The faces' own rules: sizes, ranges, repeats, order, every vertex used. */
static int check_faces(const fdt_dualmesh *d, char *diag, size_t ds)
{
    size_t at = d->n_internal;
    for (int p = 0; p < 6; p++) {
        if (d->patch_start[p] != at) {
            fdt_diag(diag, ds, "patch %s starts at face %zu, not %zu", fdt_dualmesh_patch[p],
                d->patch_start[p], at);
            return -1;
        }
        if (d->periodic >> (p / 2) & 1 && d->patch_size[p]) {
            fdt_diag(diag, ds, "wall %s of a periodic axis has %zu faces", fdt_dualmesh_patch[p],
                d->patch_size[p]);
            return -1;
        }
        at += d->patch_size[p];
    }
    for (size_t c = 0; c < d->n_cyclic; c++) {
        const fdt_dual_cyclic *y = &d->cyclic[c];
        if (y->start != at || (c & 1 && y->size != d->cyclic[c - 1].size) ||
            (c & 1 && (y->shift[0] != -d->cyclic[c - 1].shift[0] ||
                       y->shift[1] != -d->cyclic[c - 1].shift[1] ||
                       y->shift[2] != -d->cyclic[c - 1].shift[2]))) {
            fdt_diag(diag, ds, "cyclic patch %zu (faces %zu to %zu) does not follow on, or does "
                "not mirror its partner", c, y->start, y->start + y->size);
            return -1;
        }
        at += y->size;
    }
    if (d->n_cyclic & 1) {
        fdt_diag(diag, ds, "cyclic patch %zu has no partner", d->n_cyclic - 1);
        return -1;
    }
    if (at != d->n_faces) {
        fdt_diag(diag, ds, "the patches end at face %zu of %zu", at, d->n_faces);
        return -1;
    }
    uint8_t *used = calloc(d->n_verts + 1, 1);
    if (!used) {
        fdt_diag(diag, ds, "out of memory");
        return FDT_ENOMEM;
    }
    int bad = 0;
    for (size_t f = 0; f < d->n_faces && !bad; f++) {
        size_t m = d->fstart[f + 1] - d->fstart[f];
        const int32_t *v = d->fverts + d->fstart[f];
        if (d->fstart[f + 1] < d->fstart[f] || m < 3) {
            fdt_diag(diag, ds, "face %zu has %zu vertices", f, m);
            bad = 1;
        }
        for (size_t i = 0; i < m && !bad; i++) {
            if (v[i] < 0 || (size_t)v[i] >= d->n_verts) {
                fdt_diag(diag, ds, "face %zu names vertex %d of %zu", f, v[i], d->n_verts);
                bad = 1;
                break;
            }
            used[v[i]] = 1;
            for (size_t j = 0; j < i; j++)
                if (v[j] == v[i]) {
                    fdt_diag(diag, ds, "face %zu has vertex %d twice", f, v[i]);
                    bad = 1;
                }
        }
        int32_t o = d->owner[f];
        if (!bad && (o < 0 || (size_t)o >= d->n_cells)) {
            fdt_diag(diag, ds, "face %zu's owner %d is no cell", f, o);
            bad = 1;
        }
        if (!bad && f < d->n_internal) {
            int32_t nb = d->neighbour[f];
            if (nb <= o || (size_t)nb >= d->n_cells) {
                fdt_diag(diag, ds, "face %zu: owner %d, neighbour %d", f, o, nb);
                bad = 1;
            } else if (f > 0 && (d->owner[f - 1] > o ||
                                 (d->owner[f - 1] == o && d->neighbour[f - 1] > nb))) {
                fdt_diag(diag, ds, "face %zu (%d, %d) is out of upper-triangular order", f, o, nb);
                bad = 1;
            }
        }
    }
    for (size_t v = 0; v < d->n_verts && !bad; v++)
        if (!used[v]) {
            fdt_diag(diag, ds, "vertex %zu is in no face", v);
            bad = 1;
        }
    free(used);
    return bad ? -1 : 0;
}

/* Cell c closed: its faces turned outward name each edge once each way. */
static int check_cell(const fdt_dualmesh *d, const size_t *cs, const size_t *cf, size_t c,
                      uint64_t **buf, size_t *cap, char *diag, size_t ds)
{
    size_t m = 0;
    for (size_t j = cs[c]; j < cs[c + 1]; j++) {
        size_t f = cf[j], k = d->fstart[f + 1] - d->fstart[f];
        const int32_t *v = d->fverts + d->fstart[f];
        int out = d->owner[f] == (int32_t)c;
        if (grow(buf, cap, m + k) != 0) {
            fdt_diag(diag, ds, "out of memory");
            return FDT_ENOMEM;
        }
        for (size_t i = 0; i < k; i++) {
            uint64_t a = (uint32_t)v[i], b = (uint32_t)v[(i + 1) % k];
            (*buf)[m++] = out ? a << 32 | b : b << 32 | a;
        }
    }
    if (m == 0) {
        fdt_diag(diag, ds, "cell %zu has no faces", c);
        return -1;
    }
    fdt_sort_u64(*buf, m);
    for (size_t i = 0; i < m; i++) {
        uint64_t e = (*buf)[i], r = (e << 32) | (e >> 32);
        if (i > 0 && (*buf)[i - 1] == e) {
            fdt_diag(diag, ds, "cell %zu has edge %u-%u twice the same way round", c,
                (unsigned)(e >> 32), (unsigned)e);
            return -1;
        }
        if (!bsearch(&r, *buf, m, sizeof **buf, u64_cmp)) {
            fdt_diag(diag, ds, "cell %zu is not closed at edge %u-%u", c, (unsigned)(e >> 32),
                (unsigned)e);
            return -1;
        }
    }
    double vol = fdt_dualmesh_cell_volume(d, cs, cf, c);
    if (!(vol > 0)) {
        fdt_diag(diag, ds, "cell %zu has volume %g (turned inward, or too small for doubles "
            "beside the box)", c, vol);
        return -1;
    }
    return 0;
}

/* The walls' faces: each on its wall's plane, and per wall their areas,
 * turned out of the box, add up to the wall's: a face turned in, or two
 * overlapping (a closed cell can still have both, its volume right),
 * does not. */
static int check_walls(const fdt_dualmesh *d, char *diag, size_t ds)
{
    for (int p = 0; p < 6; p++) {
        if (d->periodic >> (p / 2) & 1)
            continue; /* no wall: its patch is empty (check_faces) */
        int k = p / 2, u = (k + 1) % 3, t = (k + 2) % 3;
        double bnd = d->box[k + 3 * (p & 1)], out = 0, all = 0;
        for (size_t f = d->patch_start[p]; f < d->patch_start[p] + d->patch_size[p]; f++) {
            const int32_t *fv = d->fverts + d->fstart[f];
            size_t m = d->fstart[f + 1] - d->fstart[f];
            const double *x0 = d->xyz + 3 * (size_t)fv[0];
            double a = 0;
            for (size_t i = 0; i < m; i++) {
                const double *x = d->xyz + 3 * (size_t)fv[i];
                if (x[k] != bnd) {
                    fdt_diag(diag, ds, "face %zu on wall %s has vertex %d off the wall", f,
                        fdt_dualmesh_patch[p], fv[i]);
                    return -1;
                }
                if (i >= 1 && i + 1 < m) {
                    const double *y = d->xyz + 3 * (size_t)fv[i + 1];
                    a += 0.5 * ((x[u] - x0[u]) * (y[t] - x0[t]) - (x[t] - x0[t]) * (y[u] - x0[u]));
                }
            }
            out += (p & 1) ? a : -a;
            all += fabs(a);
        }
        double want = (d->box[u + 3] - d->box[u]) * (d->box[t + 3] - d->box[t]);
        if (!(fabs(out - want) <= 1e-9 * want && fabs(all - want) <= 1e-9 * want)) {
            fdt_diag(diag, ds, "the faces on wall %s cover %.17g of its %.17g (%.17g turned "
                "out)", fdt_dualmesh_patch[p], all, want, out);
            return -1;
        }
    }
    return 0;
}

/* Twice the area vector of the polygon v[0 .. m) read from position z on,
 * fanned from its first vertex, in units of size (no square of a 1e-150
 * or 1e150 wide face under- or overflows). */
static void area2(const double *xyz, const int32_t *v, size_t m, size_t z, double size,
                  double a[3])
{
    const double *o = xyz + 3 * (size_t)v[z % m];
    a[0] = a[1] = a[2] = 0;
    for (size_t i = 1; i + 1 < m; i++) {
        const double *p = xyz + 3 * (size_t)v[(z + i) % m], *q = xyz + 3 * (size_t)v[(z + i + 1) % m];
        double u[3] = {(p[0] - o[0]) / size, (p[1] - o[1]) / size, (p[2] - o[2]) / size};
        double w[3] = {(q[0] - o[0]) / size, (q[1] - o[1]) / size, (q[2] - o[2]) / size};
        a[0] += u[1] * w[2] - u[2] * w[1];
        a[1] += u[2] * w[0] - u[0] * w[2];
        a[2] += u[0] * w[1] - u[1] * w[0];
    }
}

int fdt_dual_faces_match(const double *xyz, const int32_t *fv, size_t m, const int32_t *gv,
                         size_t gm, size_t z, const double sep[3])
{
    if (gm != m || m < 3)
        return 0;
    double size = 0;
    for (size_t j = 1; j < m; j++)
        for (int k = 0; k < 3; k++)
            size = fmax(size, fabs(xyz[3 * (size_t)fv[j] + (size_t)k] - xyz[3 * (size_t)fv[0] + (size_t)k]));
    for (size_t j = 0; j < m; j++) {
        const double *x = xyz + 3 * (size_t)fv[(m - j) % m];
        const double *y = xyz + 3 * (size_t)gv[(z + j) % m];
        for (int k = 0; k < 3; k++)
            if (!(fabs(x[k] + sep[k] - y[k]) <= 1e-6 * size))
                return 0;
    }
    if (!(size > 0))
        return 0;
    double a[3], b[3];
    area2(xyz, fv, m, 0, size, a);
    area2(xyz, gv, m, z, size, b);
    double na = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    double nb = sqrt(b[0] * b[0] + b[1] * b[1] + b[2] * b[2]);
    return fabs(na - nb) <= 1e-5 * (na + nb) / 2;
}

/* The cyclic pairs: face i of patch 2k and face i of patch 2k + 1 match
 * (fdt_dual_faces_match, from their first points). */
static int check_cyclic(const fdt_dualmesh *d, char *diag, size_t ds)
{
    for (size_t c = 0; c + 1 < d->n_cyclic; c += 2) {
        const fdt_dual_cyclic *a = &d->cyclic[c], *b = &d->cyclic[c + 1];
        for (size_t i = 0; i < a->size; i++) {
            size_t f = a->start + i, g = b->start + i;
            if (!fdt_dual_faces_match(d->xyz, d->fverts + d->fstart[f], d->fstart[f + 1] - d->fstart[f],
                                      d->fverts + d->fstart[g], d->fstart[g + 1] - d->fstart[g], 0,
                                      a->sep)) {
                fdt_diag(diag, ds, "cyclic face %zu is not face %zu moved by (%g, %g, %g)", g, f,
                    a->sep[0], a->sep[1], a->sep[2]);
                return -1;
            }
        }
    }
    return 0;
}

/* d moved to a frame scaled by 2^-e, sep too, or back (e negated):
 * exact, a power of two. */
static void scale_dual(fdt_dualmesh *d, int e)
{
    for (size_t i = 0; i < 3 * d->n_verts; i++)
        d->xyz[i] = ldexp(d->xyz[i], -e);
    for (int k = 0; k < 6; k++)
        d->box[k] = ldexp(d->box[k], -e);
    for (size_t c = 0; c < d->n_cyclic; c++)
        for (int k = 0; k < 3; k++)
            d->cyclic[c].sep[k] = ldexp(d->cyclic[c].sep[k], -e);
}

int fdt_dualmesh_check_scaled(fdt_dualmesh *d, char *diag, size_t ds)
{
    int e;
    (void)frexp(fdt_box_side(d->box), &e);
    for (size_t i = 0; i < 3 * d->n_verts && e; i++)
        if (ldexp(ldexp(d->xyz[i], -e), e) != d->xyz[i])
            e = 0; /* a vertex would lose bits: checked as it is */
    for (int k = 0; k < 6 && e; k++)
        if (ldexp(ldexp(d->box[k], -e), e) != d->box[k])
            e = 0;
    for (size_t i = 0; i < 3 * d->n_cyclic && e; i++)
        if (ldexp(ldexp(d->cyclic[i / 3].sep[i % 3], -e), e) != d->cyclic[i / 3].sep[i % 3])
            e = 0;
    if (e)
        scale_dual(d, e);
    int rc = fdt_dualmesh_check(d, diag, ds);
    if (e)
        scale_dual(d, -e);
    return rc;
}

int fdt_dualmesh_check(const fdt_dualmesh *d, char *diag, size_t ds)
{
    fdt_diag(diag, ds, "%s", "");
    int rc = check_faces(d, diag, ds);
    if (rc != 0)
        return rc;
    size_t *cs = NULL, *cf = NULL;
    if (fdt_dualmesh_cell_faces(d, &cs, &cf) != FDT_OK) {
        fdt_diag(diag, ds, "out of memory");
        return FDT_ENOMEM;
    }
    uint64_t *buf = NULL;
    size_t cap = 0;
    for (size_t c = 0; c < d->n_cells && !rc; c++)
        rc = check_cell(d, cs, cf, c, &buf, &cap, diag, ds);
    if (!rc)
        rc = check_walls(d, diag, ds);
    if (!rc)
        rc = check_cyclic(d, diag, ds);
    free(buf);
    free(cs);
    free(cf);
    return rc;
}
