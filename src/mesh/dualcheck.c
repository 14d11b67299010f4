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
        at += d->patch_size[p];
    }
    if (at != d->n_faces) {
        fdt_diag(diag, ds, "the patches end at face %zu of %zu", at, d->n_faces);
        return -1;
    }
    uint8_t *used = calloc(d->n_verts + 1, 1);
    if (!used) {
        fdt_diag(diag, ds, "out of memory");
        return -1;
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
                                 (d->owner[f - 1] == o && d->neighbour[f - 1] >= nb))) {
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
            return -1;
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

int fdt_dualmesh_check(const fdt_dualmesh *d, char *diag, size_t ds)
{
    fdt_diag(diag, ds, "%s", "");
    if (check_faces(d, diag, ds) != 0)
        return -1;
    size_t *cs = NULL, *cf = NULL;
    if (fdt_dualmesh_cell_faces(d, &cs, &cf) != FDT_OK) {
        fdt_diag(diag, ds, "out of memory");
        return -1;
    }
    uint64_t *buf = NULL;
    size_t cap = 0;
    int bad = 0;
    for (size_t c = 0; c < d->n_cells && !bad; c++)
        bad = check_cell(d, cs, cf, c, &buf, &cap, diag, ds) != 0;
    if (!bad)
        bad = check_walls(d, diag, ds) != 0;
    free(buf);
    free(cs);
    free(cf);
    return bad ? -1 : 0;
}
