/*
 * Tests for src/mesh/dualcheck.c, the polyMesh check of the dual, on a
 * hand-made mesh: three unit cubes in a row (16 vertices, 2 internal faces,
 * the six walls as patches), which it must pass, and the same mesh broken
 * one way at a time, each of which it must refuse, naming what broke:
 * a face turned over, an owner above its neighbour, internal faces out of
 * upper-triangular order, a vertex in no face, a face naming a vertex that
 * is not there or one vertex twice, an owner that is no cell, patches that
 * do not end at the last face, every cell turned inward (mirrored), a face
 * missing, a wall face off its wall, wall faces overlapping. The same
 * cubes periodic along x (cell 0's face at x = 0 and cell 2's at x = 3 a
 * cyclic pair), which it must pass, and broken: the pair off its
 * translate, listed from another point, shifts that do not mirror, the
 * axis's walls left uncovered, a patch without partner. The check scaled
 * (fdt_dualmesh_check_scaled) on cubes of 2^-500, whose volumes underflow
 * in their own frame. (tests/test_dualmesh.c checks the meshes
 * src/mesh/dualmesh.c builds; this one that the check can fail.)
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mesh/dualmesh.h"
#include "testutil.h"

enum { NV = 16, NF = 16, NC = 3 };

static int32_t vid(int i, int j, int k)
{
    return (int32_t)(i * 4 + j * 2 + k);
}

typedef struct built {
    fdt_dualmesh d;
    double xyz[3 * (NV + 1)];
    size_t fstart[NF + 1];
    int32_t fverts[4 * NF];
    int32_t owner[NF], neighbour[NF];
    int32_t cell_of[NC];
} built;

static void face(built *b, size_t *nf, const int32_t v[4], int32_t own, int32_t nb)
{
    size_t f = (*nf)++;
    memcpy(b->fverts + 4 * f, v, 4 * sizeof *v);
    b->fstart[f + 1] = 4 * (f + 1);
    b->owner[f] = own;
    b->neighbour[f] = nb;
}

/* Each face's vertices counter-clockwise seen from outside its owner. */
static void build(built *b)
{
    memset(b, 0, sizeof *b);
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 2; j++)
            for (int k = 0; k < 2; k++) {
                double *x = b->xyz + 3 * vid(i, j, k);
                x[0] = i;
                x[1] = j;
                x[2] = k;
            }
    size_t nf = 0;
    for (int i = 1; i < 3; i++) /* x = i, +x: from cell i - 1 to cell i */
        face(b, &nf, (int32_t[4]){vid(i, 0, 0), vid(i, 1, 0), vid(i, 1, 1), vid(i, 0, 1)}, i - 1,
             i);
    size_t start[6], size[6] = {1, 1, NC, NC, NC, NC};
    start[0] = nf; /* xmin: -x of cell 0 */
    face(b, &nf, (int32_t[4]){vid(0, 0, 1), vid(0, 1, 1), vid(0, 1, 0), vid(0, 0, 0)}, 0, -1);
    start[1] = nf; /* xmax: +x of cell 2 */
    face(b, &nf, (int32_t[4]){vid(3, 0, 0), vid(3, 1, 0), vid(3, 1, 1), vid(3, 0, 1)}, 2, -1);
    start[2] = nf;
    for (int i = 0; i < NC; i++) /* ymin */
        face(b, &nf, (int32_t[4]){vid(i + 1, 0, 0), vid(i + 1, 0, 1), vid(i, 0, 1), vid(i, 0, 0)},
             i, -1);
    start[3] = nf;
    for (int i = 0; i < NC; i++) /* ymax */
        face(b, &nf, (int32_t[4]){vid(i, 1, 0), vid(i, 1, 1), vid(i + 1, 1, 1), vid(i + 1, 1, 0)},
             i, -1);
    start[4] = nf;
    for (int i = 0; i < NC; i++) /* zmin */
        face(b, &nf, (int32_t[4]){vid(i, 1, 0), vid(i + 1, 1, 0), vid(i + 1, 0, 0), vid(i, 0, 0)},
             i, -1);
    start[5] = nf;
    for (int i = 0; i < NC; i++) /* zmax */
        face(b, &nf, (int32_t[4]){vid(i, 0, 1), vid(i + 1, 0, 1), vid(i + 1, 1, 1), vid(i, 1, 1)},
             i, -1);
    CHECK(nf == NF);
    fdt_dualmesh *d = &b->d;
    d->n_verts = NV;
    d->xyz = b->xyz;
    d->n_cells = NC;
    d->n_faces = NF;
    d->n_internal = 2;
    d->fstart = b->fstart;
    d->fverts = b->fverts;
    d->owner = b->owner;
    d->neighbour = b->neighbour;
    memcpy(d->patch_start, start, sizeof start);
    memcpy(d->patch_size, size, sizeof size);
    d->n_input = NC;
    for (int c = 0; c < NC; c++)
        b->cell_of[c] = c;
    d->cell_of = b->cell_of;
    const double box[6] = {0, 0, 0, 3, 1, 1};
    memcpy(d->box, box, sizeof box);
}

/* The cubes periodic along x (a period of 3): cell 0's face at x = 0 and
 * cell 2's at x = 3 become a cyclic pair, the first (its partner at +3)
 * as it was, the second turned to start at the first's first point moved;
 * the walls of x empty, the other walls as before. */
static fdt_dual_cyclic cyc[2];

static void build_periodic(built *b)
{
    build(b);
    size_t f0 = b->d.patch_start[0], f1 = b->d.patch_start[1]; /* 2 and 3 */
    int32_t a[4], c[4];
    memcpy(a, b->fverts + 4 * f0, sizeof a);
    memcpy(c, b->fverts + 4 * f1, sizeof c);
    int32_t oa = b->owner[f0], oc = b->owner[f1];
    /* the y and z walls' faces two places up */
    memmove(b->fverts + 4 * f0, b->fverts + 4 * (f0 + 2), 4 * (NF - f0 - 2) * sizeof *b->fverts);
    memmove(b->owner + f0, b->owner + f0 + 2, (NF - f0 - 2) * sizeof *b->owner);
    for (int p = 2; p < 6; p++)
        b->d.patch_start[p] -= 2;
    b->d.patch_start[0] = b->d.patch_start[1] = f0;
    b->d.patch_size[0] = b->d.patch_size[1] = 0;
    /* a's first point (0, 0, 1) moved by 3 is c's last: c from there on */
    CHECK(c[3] == vid(3, 0, 1) && a[0] == vid(0, 0, 1));
    int32_t turned[4] = {c[3], c[0], c[1], c[2]};
    memcpy(b->fverts + 4 * (NF - 2), a, sizeof a);
    memcpy(b->fverts + 4 * (NF - 1), turned, sizeof turned);
    b->owner[NF - 2] = oa;
    b->owner[NF - 1] = oc;
    cyc[0] = (fdt_dual_cyclic){{1, 0, 0}, {3, 0, 0}, NF - 2, 1};
    cyc[1] = (fdt_dual_cyclic){{-1, 0, 0}, {-3, 0, 0}, NF - 1, 1};
    b->d.periodic = 1;
    b->d.n_cyclic = 2;
    b->d.cyclic = cyc;
}

/* The check on b refuses it with a message holding want. */
static void refused(const built *b, const char *want, const char *what)
{
    char diag[256] = "";
    int r = fdt_dualmesh_check(&b->d, diag, sizeof diag);
    EXPECTF(r != 0 && strstr(diag, want) != NULL, "%s: got %d \"%s\", want \"%s\"", what, r,
            diag, want);
}

int main(void)
{
    static built b;
    char diag[256];
    build(&b);
    EXPECTF(fdt_dualmesh_check(&b.d, diag, sizeof diag) == 0, "the cubes: %s", diag);

    build(&b); /* the first internal face turned over */
    int32_t *v = b.fverts;
    int32_t t = v[1];
    v[1] = v[3];
    v[3] = t;
    refused(&b, "cell 0 is not closed", "a face turned over");

    build(&b);
    b.owner[0] = 1;
    b.neighbour[0] = 0;
    refused(&b, "owner 1, neighbour 0", "owner above neighbour");

    build(&b); /* the internal faces swapped: (1, 2) before (0, 1) */
    int32_t f0[4];
    memcpy(f0, b.fverts, sizeof f0);
    memcpy(b.fverts, b.fverts + 4, sizeof f0);
    memcpy(b.fverts + 4, f0, sizeof f0);
    b.owner[0] = 1, b.neighbour[0] = 2, b.owner[1] = 0, b.neighbour[1] = 1;
    refused(&b, "upper-triangular", "internal faces out of order");

    build(&b);
    b.d.n_verts = NV + 1; /* one more vertex, in no face */
    refused(&b, "vertex 16 is in no face", "an unused vertex");

    build(&b);
    b.fverts[4 * 5 + 2] = 99;
    refused(&b, "names vertex 99", "a vertex that is not there");

    build(&b);
    b.fverts[4 * 5 + 2] = b.fverts[4 * 5];
    refused(&b, "twice", "a vertex twice in a face");

    build(&b);
    b.owner[7] = 5;
    refused(&b, "is no cell", "an owner that is no cell");

    build(&b);
    b.d.patch_size[5] = NC - 1; /* zmax one face short */
    refused(&b, "the patches end at face", "patches short of the faces");

    build(&b); /* mirrored: every face now turns into its owner */
    for (int i = 0; i < NV; i++)
        b.xyz[3 * i] = -b.xyz[3 * i];
    refused(&b, "volume", "cells turned inward");

    build(&b); /* the last face dropped: cell 2 open */
    b.d.n_faces = NF - 1;
    b.d.patch_size[5] = NC - 1;
    refused(&b, "not closed", "a face missing");

    build(&b); /* the box's xmin beyond the cells' */
    b.d.box[0] = -1;
    refused(&b, "off the wall", "a wall face off its wall");

    build(&b); /* the top of the first internal face moved to x = -0.5: every
                * cell still closed and of positive volume (cell 0 is 1 wide
                * at the bottom, -0.5 at the top), but cell 0's faces on the
                * walls there are turned into the box and cell 1's overlap them */
    b.xyz[3 * vid(1, 0, 1)] = -0.5;
    b.xyz[3 * vid(1, 1, 1)] = -0.5;
    refused(&b, "cover", "wall faces overlapping");

    /* periodic along x: passes; then a cyclic pair broken each way */
    build_periodic(&b);
    EXPECTF(fdt_dualmesh_check(&b.d, diag, sizeof diag) == 0, "the periodic cubes: %s", diag);
    build_periodic(&b);
    cyc[0].sep[0] = 2.9; /* the partner not at the translate */
    refused(&b, "is not face", "a cyclic face off its partner");
    build_periodic(&b); /* the partner from another point */
    int32_t *g = b.fverts + 4 * (NF - 1), g0 = g[0];
    memmove(g, g + 1, 3 * sizeof *g);
    g[3] = g0;
    refused(&b, "is not face", "a cyclic face listed from another point");
    build_periodic(&b);
    cyc[1].shift[0] = 1;
    refused(&b, "mirror its partner", "partners whose shifts do not mirror");
    build_periodic(&b);
    b.d.periodic = 0; /* x not periodic: its walls uncovered */
    refused(&b, "cover", "the walls of an axis that is not periodic left empty");
    build_periodic(&b);
    b.d.n_cyclic = 1;
    b.d.n_faces = NF - 1;
    refused(&b, "no partner", "a cyclic patch alone");

    /* 2^-500 of the cubes: their volumes underflow, which the scaled check
     * does not see; the mesh the same bits after it */
    build(&b);
    for (int i = 0; i < 3 * NV; i++)
        b.xyz[i] = ldexp(b.xyz[i], -500);
    for (int k = 0; k < 6; k++)
        b.d.box[k] = ldexp(b.d.box[k], -500);
    double keep[3 * NV];
    memcpy(keep, b.xyz, sizeof keep);
    refused(&b, "volume", "cubes of 2^-500 in their own frame");
    EXPECTF(fdt_dualmesh_check_scaled(&b.d, diag, sizeof diag) == 0, "scaled: %s", diag);
    EXPECT(!memcmp(keep, b.xyz, sizeof keep) && b.d.box[3] == ldexp(3, -500));
    return test_report("dualcheck");
}
