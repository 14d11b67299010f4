/*
 * An OpenFOAM polyMesh directory (src/io/write/formats.h): points, faces, owner,
 * neighbour and boundary, ASCII, from the face list of Merriam §2
 * (fdt_result_faces). Each tet is a cell, numbered as in the result.
 *
 * OpenFOAM's rules (its polyMesh description, checked by checkMesh):
 *  - every point is used: the duplicates the engine merged are left out,
 *    the others renumbered in input order (points lists them);
 *  - internal faces first, then the boundary patches' faces;
 *  - owner < neighbour, and the internal faces in upper-triangular order:
 *    by owner, then by neighbour within an owner;
 *  - each face's right-hand normal points out of its owner.
 * Our face list has owner = tets[2i] (the lower tet for an interior face)
 * on the positive side, i.e. the normal points into the owner: each face
 * is written reversed. The hull is one patch, "hull", of type patch.
 *
 * A periodic mesh comes laid out (meshview.h: each tet where its offsets
 * place it, image vertices as points of their own). A face of the
 * periodic mesh whose two tets lie in different copies is then two faces,
 * translates of each other: a pair of cyclic patches (OpenFOAM's
 * translational cyclic), one pair a translation (up to 13: the axes and,
 * where an edge or a corner of the box is crossed, the diagonals). The
 * faces are paired by the periodic neighbours of the laid-out tets
 * (src/mesh/periodic.h, fdt_periodic_unfolded_neighbors: input ids and
 * image offsets, exactly, never coordinates); face i of one patch is the
 * partner of face i of the other, listed from the same point.
 */
#include "io/write/formats.h"
#include "geom/predicates.h"
#include "mesh/dualmesh.h"
#include "mesh/periodic.h"

/* A boundary patch: the hull, or one side of a cyclic pair (partner: the
 * other side's index in the list, its faces' translates at +sep). */
typedef struct foam_patch {
    char name[64];
    size_t n_faces, start;
    int partner;
    double sep[3];
} foam_patch;

typedef struct foam_prep {
    size_t n_internal, n_faces, n_points, n_cells;
    size_t *order;   /* n_faces: face list indices in OpenFOAM order */
    fdt_vid *map;    /* n_points of the input: the new number, -1 unused */
    /* a periodic mesh laid out (foam_prepare_periodic), else NULL:
     * each face's three points (mapped, the normal out of its owner) and
     * owner in OpenFOAM order, the internal faces' neighbours, the patches */
    int32_t *fv, *own, *nbr;
    foam_patch *patch;
    size_t n_patches;
} foam_prep;

static int foam_prepare_periodic(const fdt_mesh_view *m, void **prep, const char *path,
                                 char *err, size_t errlen);

/* The points the tets use, numbered in their order into map (n_points
 * entries; -1 for one no tet uses: a merged duplicate), as OpenFOAM wants
 * every point used. Returns how many. */
static size_t used_points(const fdt_mesh_view *m, fdt_vid *map)
{
    for (size_t i = 0; i < m->n_points; i++)
        map[i] = -1;
    for (size_t i = 0; i < 4 * m->n_tets; i++)
        map[m->tets[i]] = 0;
    size_t k = 0;
    for (size_t i = 0; i < m->n_points; i++)
        if (map[i] == 0)
            map[i] = (fdt_vid)k++;
    return k;
}

int fdt_foam_prepare(const fdt_mesh_view *m, void **prep, const char *path, char *err,
                     size_t errlen)
{
    if (m->point_src)
        return foam_prepare_periodic(m, prep, path, err, errlen);
    size_t T = m->n_tets, F = m->n_faces, N = m->n_points;
    if (T > (size_t)INT32_MAX || F > (size_t)INT32_MAX)
        return set_err(err, errlen, FDT_IO_EFORMAT, path,
                       "too many cells or faces for OpenFOAM's 32-bit labels");
    size_t bytes = sizeof(foam_prep) + F * sizeof(size_t) + N * sizeof(fdt_vid);
    foam_prep *p = malloc(bytes);
    size_t *start = calloc(T + 2, sizeof *start);
    if (!p || !start) {
        free(p);
        free(start);
        return set_errno_err(err, errlen, path, ENOMEM);
    }
    memset(p, 0, sizeof *p);
    p->order = (size_t *)(p + 1);
    p->map = (fdt_vid *)(p->order + F);
    p->n_faces = F;
    p->n_cells = T;
    p->n_points = used_points(m, p->map); /* in input order */
    /* faces: a counting sort by owner, internal faces first (keys 0..T-1)
     * then boundary ones (keys T..2T-1, by owner too): start[] holds the
     * counts of the internal faces per owner, and the boundary faces
     * follow them all. */
    size_t n_int = 0;
    for (size_t f = 0; f < F; f++)
        if (m->face_tets[2 * f + 1] >= 0) {
            start[m->face_tets[2 * f]]++;
            n_int++;
        }
    size_t sum = 0;
    for (size_t c = 0; c <= T; c++) {
        size_t x = start[c];
        start[c] = sum;
        sum += x;
    }
    size_t nb = n_int;
    for (size_t f = 0; f < F; f++) {
        if (m->face_tets[2 * f + 1] >= 0)
            p->order[start[m->face_tets[2 * f]]++] = f;
        else
            p->order[nb++] = f; /* the face list's own order: ascending ids */
    }
    /* within an owner (at most four faces) by neighbour */
    for (size_t i = 1; i < n_int; i++) {
        size_t x = p->order[i], j = i;
        fdt_tid ox = m->face_tets[2 * x], nx = m->face_tets[2 * x + 1];
        while (j > 0 && m->face_tets[2 * p->order[j - 1]] == ox &&
               m->face_tets[2 * p->order[j - 1] + 1] > nx) {
            p->order[j] = p->order[j - 1];
            j--;
        }
        p->order[j] = x;
    }
    free(start);
    p->n_internal = n_int;
    *prep = p;
    return FDT_IO_OK;
}

/* ------------------------------------------------------------------ */
/* A periodic mesh laid out: the faces paired by input ids and offsets. */

/* Face r = 4 t + k of the laid-out tets: its points, out of tet t. */
static void pface_points(const fdt_mesh_view *m, uint64_t r, fdt_vid v[3])
{
    const fdt_vid *t = m->tets + 4 * (size_t)(r >> 2);
    for (int i = 0; i < 3; i++)
        v[i] = t[fdt_tet_face[r & 3][i]];
}

/* A cyclic pair of faces: r on the side whose partner q lies at +s
 * periods (the shift's first nonzero component positive). */
typedef struct cyc {
    uint64_t r, q;
    int s[3];
} cyc;

/* An internal face: its owner's face r, owner below neighbour. */
typedef struct intf {
    int32_t own, nbr;
    uint64_t r;
} intf;

static int intf_cmp(const void *x, const void *y)
{
    const intf *a = x, *b = y;
    if (a->own != b->own)
        return a->own < b->own ? -1 : 1;
    return (a->nbr > b->nbr) - (a->nbr < b->nbr);
}

/* "periodic_p1_0_m1": the translation to the partner, p for plus, m for
 * minus (OpenFOAM's words take neither sign). */
static void shift_name(const int s[3], char *buf, size_t len)
{
    snprintf(buf, len, "periodic_%s%d_%s%d_%s%d", s[0] > 0 ? "p" : s[0] < 0 ? "m" : "",
             abs(s[0]), s[1] > 0 ? "p" : s[1] < 0 ? "m" : "", abs(s[1]),
             s[2] > 0 ? "p" : s[2] < 0 ? "m" : "", abs(s[2]));
}

/* Face f of the output: laid-out face r (out of its tet, which owns it),
 * turned (an even permutation: the orientation kept) to start at the point
 * whose input id is first_src (-1: as it is). */
static void put_face(foam_prep *p, size_t f, const fdt_mesh_view *m, uint64_t r,
                     long first_src)
{
    fdt_vid v[3];
    pface_points(m, r, v);
    int z = 0;
    while (first_src >= 0 && z < 2 && (long)m->point_src[v[z]] != first_src)
        z++;
    for (int c = 0; c < 3; c++)
        p->fv[3 * f + (size_t)c] = (int32_t)p->map[v[(z + c) % 3]];
    p->own[f] = (int32_t)(r >> 2);
}

/*
 * Where face r of the laid-out tets is across its neighbour m->nbrs[r]
 * (the periodic mesh's: fdt_periodic_unfolded_neighbors): *q the
 * neighbour's face (its vertex with the input id that r's face lacks is
 * the one opposite), and whether the two lie in one copy (the same
 * points), else *s the translation from r's copy to q's, in periods.
 */
static int across(const fdt_mesh_view *m, uint64_t r, uint64_t *q, int s[3])
{
    fdt_vid v[3], w[3];
    pface_points(m, r, v);
    uint64_t t2 = (uint64_t)m->nbrs[r];
    const fdt_vid *u = m->tets + 4 * (size_t)t2;
    int k2 = 0;
    for (int i = 0; i < 4; i++)
        if (m->point_src[u[i]] != m->point_src[v[0]] && m->point_src[u[i]] != m->point_src[v[1]] &&
            m->point_src[u[i]] != m->point_src[v[2]])
            k2 = i;
    *q = 4 * t2 + (uint64_t)k2;
    pface_points(m, *q, w);
    int z = 0;
    while (z < 2 && m->point_src[w[z]] != m->point_src[v[0]])
        z++;
    for (int c = 0; c < 3; c++)
        s[c] = m->point_off[3 * (size_t)w[z] + (size_t)c] - m->point_off[3 * (size_t)v[0] + (size_t)c];
    return w[z] == v[0];
}

static int foam_prepare_periodic(const fdt_mesh_view *m, void **prep, const char *path,
                                 char *err, size_t errlen)
{
    size_t T = m->n_tets, N = m->n_points;
    uint64_t R = 4 * (uint64_t)T;
    if (T > (size_t)INT32_MAX / 3 || N > (size_t)INT32_MAX)
        return set_err(err, errlen, FDT_IO_EFORMAT, path,
                       "too many cells or faces for OpenFOAM's 32-bit labels");
    int rc = FDT_IO_OK;
    intf *in = NULL;
    cyc *cy = NULL;
    uint64_t *hull = NULL;
    int (*shifts)[3] = NULL;
    foam_prep *p = NULL;
    size_t n_in = 0, n_cy = 0, n_hull = 0, n_sh = 0;
    /* each face once, from the lower tet (an internal one, or a cyclic
     * pair's two copies), or the hull: counted, then listed */
    for (int pass = 0; pass < 2; pass++) {
        if (pass && (!(in = malloc((n_in + 1) * sizeof *in)) ||
                     !(cy = malloc((n_cy + 1) * sizeof *cy)) ||
                     !(hull = malloc((n_hull + 1) * sizeof *hull)))) {
            rc = set_errno_err(err, errlen, path, ENOMEM);
            goto done;
        }
        n_in = n_cy = n_hull = 0;
        for (uint64_t r = 0; r < R; r++) {
            if (m->nbrs[r] < 0) {
                if (pass)
                    hull[n_hull] = r;
                n_hull++;
                continue;
            }
            /* each face listed from its lower record: one whose neighbour
             * is a lower tet was listed there, so across() runs only from
             * the lower tet (or, the same tet on both sides, from both) */
            if ((uint64_t)m->nbrs[r] < (r >> 2))
                continue;
            uint64_t q;
            int sh[3];
            int same = across(m, r, &q, sh);
            if (q < r)
                continue;
            if (same) {
                if (pass)
                    in[n_in] = (intf){(int32_t)(r >> 2), (int32_t)(q >> 2), r};
                n_in++;
                continue;
            }
            if (pass) {
                int neg = sh[0] < 0 || (sh[0] == 0 && (sh[1] < 0 || (sh[1] == 0 && sh[2] < 0)));
                cyc c = {neg ? q : r, neg ? r : q, {sh[0], sh[1], sh[2]}};
                for (int k = 0; neg && k < 3; k++)
                    c.s[k] = -c.s[k];
                cy[n_cy] = c;
            }
            n_cy++;
        }
    }
    qsort(in, n_in, sizeof *in, intf_cmp);
    /* the translations, ascending: a pair of patches each */
    if (!(shifts = malloc((n_cy + 1) * sizeof *shifts))) {
        rc = set_errno_err(err, errlen, path, ENOMEM);
        goto done;
    }
    for (size_t i = 0; i < n_cy; i++) /* at most 13 */
        fdt_shift_add(shifts, &n_sh, cy[i].s);
    size_t F = n_in + 2 * n_cy + n_hull, P = 2 * n_sh + (n_hull > 0);
    size_t bytes = sizeof(foam_prep) + N * sizeof(fdt_vid) + P * sizeof(foam_patch) +
                   (3 * F + F + n_in) * sizeof(int32_t);
    if (!(p = malloc(bytes))) {
        rc = set_errno_err(err, errlen, path, ENOMEM);
        goto done;
    }
    memset(p, 0, sizeof *p);
    p->patch = (foam_patch *)(p + 1); /* the 8-byte members first */
    p->map = (fdt_vid *)(p->patch + P);
    p->fv = (int32_t *)(p->map + N);
    p->own = p->fv + 3 * F;
    p->nbr = p->own + F;
    p->n_faces = F;
    p->n_internal = n_in;
    p->n_cells = T;
    p->n_patches = P;
    p->n_points = used_points(m, p->map); /* in the laid-out order: input points first */
    size_t f = 0;
    for (size_t i = 0; i < n_in; i++) {
        put_face(p, f++, m, in[i].r, -1);
        p->nbr[i] = in[i].nbr;
    }
    for (size_t k = 0; k < n_sh; k++) {
        int neg[3] = {-shifts[k][0], -shifts[k][1], -shifts[k][2]};
        for (int side = 0; side < 2; side++) {
            foam_patch *pa = &p->patch[2 * k + (size_t)side];
            shift_name(side ? neg : shifts[k], pa->name, sizeof pa->name);
            pa->start = f;
            pa->partner = (int)(2 * k + (size_t)!side);
            for (int c = 0; c < 3; c++)
                pa->sep[c] = (side ? -1 : 1) * shifts[k][c] * m->period[c];
            for (size_t i = 0; i < n_cy; i++) {
                if (fdt_shift_cmp(cy[i].s, shifts[k]))
                    continue;
                if (!side) {
                    put_face(p, f++, m, cy[i].r, -1);
                    continue;
                }
                /* from the same input point as the r side's face: its first */
                fdt_vid v0[3];
                pface_points(m, cy[i].r, v0);
                put_face(p, f++, m, cy[i].q, (long)m->point_src[v0[0]]);
            }
            pa->n_faces = f - pa->start;
        }
    }
    if (n_hull) {
        foam_patch *pa = &p->patch[P - 1];
        snprintf(pa->name, sizeof pa->name, "hull");
        pa->start = f;
        pa->partner = -1;
        for (size_t i = 0; i < n_hull; i++)
            put_face(p, f++, m, hull[i], -1);
        pa->n_faces = f - pa->start;
    }
    *prep = p;
    p = NULL;
done:
    free(p);
    free(in);
    free(cy);
    free(hull);
    free(shifts);
    return rc;
}

/* The FoamFile header of one file; counts (points, cells, faces, internal
 * faces) go into owner's note, which some utilities (decomposePar) read
 * instead of counting. */
static void header_of(out_file *o, const char *what, const char *cls, const char *object,
                      const size_t counts[4])
{
    out_str(o, "/* written by frontdt " FDT_VERSION_STRING ": ");
    out_str(o, what);
    out_str(o, " */\nFoamFile\n{\n"
               "    version     2.0;\n    format      ascii;\n    class       ");
    out_str(o, cls);
    out_str(o, ";\n");
    if (counts && !strcmp(object, "owner")) {
        static const char *const names[4] = {"nPoints:", " nCells:", " nFaces:",
                                             " nInternalFaces:"};
        out_str(o, "    note        \"");
        for (int i = 0; i < 4; i++) {
            out_str(o, names[i]);
            out_i64(o, (int64_t)counts[i]);
        }
        out_str(o, "\";\n");
    }
    out_str(o, "    location    \"constant/polyMesh\";\n    object      ");
    out_str(o, object);
    out_str(o, ";\n}\n\n");
}

static void header(out_file *o, const char *cls, const char *object, const foam_prep *p)
{
    size_t counts[4] = {p->n_points, p->n_cells, p->n_faces, p->n_internal};
    header_of(o, "Delaunay tetrahedralization", cls, object, counts);
}

/* A vector: "(x y z)". */
static void put_vector(out_file *o, const double *x)
{
    out_char(o, '(');
    for (int c = 0; c < 3; c++) {
        if (c)
            out_char(o, ' ');
        out_double(o, x[c]);
    }
    out_char(o, ')');
}

/* One point of a vectorField: "(x y z)" on a line. */
static void put_point(out_file *o, const double *x)
{
    put_vector(o, x);
    out_char(o, '\n');
}

int fdt_put_foam_points(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                        size_t errlen)
{
    (void)err;
    (void)errlen;
    const foam_prep *p = prep;
    header(o, "vectorField", "points", p);
    out_i64(o, (int64_t)p->n_points);
    out_str(o, "\n(\n");
    for (size_t i = 0; i < m->n_points && !o->err; i++) {
        if (p->map[i] < 0)
            continue;
        put_point(o, m->xyz + 3 * i);
    }
    out_str(o, ")\n");
    return FDT_IO_OK;
}

int fdt_put_foam_faces(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                       size_t errlen)
{
    (void)err;
    (void)errlen;
    const foam_prep *p = prep;
    header(o, "faceList", "faces", p);
    out_i64(o, (int64_t)p->n_faces);
    out_str(o, "\n(\n");
    for (size_t i = 0; p->fv && i < p->n_faces && !o->err; i++) {
        const int32_t *v = p->fv + 3 * i; /* turned already */
        out_str(o, "3(");
        for (int c = 0; c < 3; c++) {
            if (c)
                out_char(o, ' ');
            out_i64(o, v[c]);
        }
        out_str(o, ")\n");
    }
    for (size_t i = 0; !p->fv && i < p->n_faces && !o->err; i++) {
        const fdt_vid *v = m->faces + 3 * p->order[i];
        /* reversed: the normal out of the owner */
        out_str(o, "3(");
        out_i64(o, p->map[v[0]]);
        out_char(o, ' ');
        out_i64(o, p->map[v[2]]);
        out_char(o, ' ');
        out_i64(o, p->map[v[1]]);
        out_str(o, ")\n");
    }
    out_str(o, ")\n");
    return FDT_IO_OK;
}

static void put_labels(out_file *o, const fdt_mesh_view *m, const foam_prep *p, size_t count,
                       int side)
{
    out_i64(o, (int64_t)count);
    out_str(o, "\n(\n");
    const int32_t *laid = side ? p->nbr : p->own; /* a periodic mesh's */
    for (size_t i = 0; i < count && !o->err; i++) {
        out_i64(o, p->fv ? (int64_t)laid[i] : (int64_t)m->face_tets[2 * p->order[i] + (size_t)side]);
        out_char(o, '\n');
    }
    out_str(o, ")\n");
}

int fdt_put_foam_owner(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                       size_t errlen)
{
    (void)err;
    (void)errlen;
    const foam_prep *p = prep;
    header(o, "labelList", "owner", p);
    put_labels(o, m, p, p->n_faces, 0);
    return FDT_IO_OK;
}

int fdt_put_foam_neighbour(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                           size_t errlen)
{
    (void)err;
    (void)errlen;
    const foam_prep *p = prep;
    header(o, "labelList", "neighbour", p);
    put_labels(o, m, p, p->n_internal, 1);
    return FDT_IO_OK;
}

/* One patch of the boundary file, of type patch. */
static void put_patch(out_file *o, const char *name, size_t n_faces, size_t start)
{
    out_str(o, "    ");
    out_str(o, name);
    out_str(o, "\n    {\n        type            patch;\n        nFaces          ");
    out_i64(o, (int64_t)n_faces);
    out_str(o, ";\n        startFace       ");
    out_i64(o, (int64_t)start);
    out_str(o, ";\n    }\n");
}

/* One side of a cyclic pair: its faces' translates by sep are its partner
 * patch's (OpenFOAM's translational cyclic). */
static void put_cyclic(out_file *o, const char *name, size_t n_faces, size_t start,
                       const char *partner, const double sep[3])
{
    out_str(o, "    ");
    out_str(o, name);
    out_str(o, "\n    {\n        type            cyclic;\n        inGroups        "
               "List<word> 1(cyclic);\n        nFaces          ");
    out_i64(o, (int64_t)n_faces);
    out_str(o, ";\n        startFace       ");
    out_i64(o, (int64_t)start);
    out_str(o, ";\n        matchTolerance  0.0001;\n        transform       translational;\n"
               "        neighbourPatch  ");
    out_str(o, partner);
    out_str(o, ";\n        separationVector ");
    put_vector(o, sep);
    out_str(o, ";\n    }\n");
}

int fdt_put_foam_boundary(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                          size_t errlen)
{
    (void)m;
    (void)err;
    (void)errlen;
    const foam_prep *p = prep;
    header(o, "polyBoundaryMesh", "boundary", p);
    if (!p->fv) {
        out_str(o, "1\n(\n");
        put_patch(o, "hull", p->n_faces - p->n_internal, p->n_internal);
        out_str(o, ")\n");
        return FDT_IO_OK;
    }
    out_i64(o, (int64_t)p->n_patches);
    out_str(o, "\n(\n");
    for (size_t i = 0; i < p->n_patches; i++) {
        const foam_patch *pa = &p->patch[i];
        if (pa->partner < 0) {
            put_patch(o, pa->name, pa->n_faces, pa->start);
            continue;
        }
        put_cyclic(o, pa->name, pa->n_faces, pa->start, p->patch[pa->partner].name, pa->sep);
    }
    out_str(o, ")\n");
    return FDT_IO_OK;
}

/* ------------------------------------------------------------------ */
/* The Voronoi dual (src/mesh/dualmesh.h): prep is the fdt_dualmesh, the
 * view unused. Its faces are in OpenFOAM's order and turned already. */

#define DUAL_WHAT "Voronoi cells clipped by a box, a cell a point"
#define DUAL_WHAT_PERIODIC "periodic Voronoi cells, whole, across cyclic patches, a cell a point"

static void dual_header(out_file *o, const char *cls, const char *object,
                        const fdt_dualmesh *d)
{
    size_t counts[4] = {d->n_verts, d->n_cells, d->n_faces, d->n_internal};
    header_of(o, d->periodic ? DUAL_WHAT_PERIODIC : DUAL_WHAT, cls, object, counts);
}

int fdt_put_foam_dual_points(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                             size_t errlen)
{
    (void)m;
    (void)err;
    (void)errlen;
    const fdt_dualmesh *d = prep;
    dual_header(o, "vectorField", "points", d);
    out_i64(o, (int64_t)d->n_verts);
    out_str(o, "\n(\n");
    for (size_t i = 0; i < d->n_verts && !o->err; i++) {
        put_point(o, d->xyz + 3 * i);
    }
    out_str(o, ")\n");
    return FDT_IO_OK;
}

int fdt_put_foam_dual_faces(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                            size_t errlen)
{
    (void)m;
    (void)err;
    (void)errlen;
    const fdt_dualmesh *d = prep;
    dual_header(o, "faceList", "faces", d);
    out_i64(o, (int64_t)d->n_faces);
    out_str(o, "\n(\n");
    for (size_t f = 0; f < d->n_faces && !o->err; f++) {
        out_i64(o, (int64_t)(d->fstart[f + 1] - d->fstart[f]));
        out_char(o, '(');
        for (size_t i = d->fstart[f]; i < d->fstart[f + 1]; i++) {
            if (i > d->fstart[f])
                out_char(o, ' ');
            out_i64(o, d->fverts[i]);
        }
        out_str(o, ")\n");
    }
    out_str(o, ")\n");
    return FDT_IO_OK;
}

static void put_list(out_file *o, const int32_t *v, size_t count)
{
    out_i64(o, (int64_t)count);
    out_str(o, "\n(\n");
    for (size_t i = 0; i < count && !o->err; i++) {
        out_i64(o, v[i]);
        out_char(o, '\n');
    }
    out_str(o, ")\n");
}

int fdt_put_foam_dual_owner(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                            size_t errlen)
{
    (void)m;
    (void)err;
    (void)errlen;
    const fdt_dualmesh *d = prep;
    dual_header(o, "labelList", "owner", d);
    put_list(o, d->owner, d->n_faces);
    return FDT_IO_OK;
}

int fdt_put_foam_dual_neighbour(out_file *o, const fdt_mesh_view *m, const void *prep,
                                char *err, size_t errlen)
{
    (void)m;
    (void)err;
    (void)errlen;
    const fdt_dualmesh *d = prep;
    dual_header(o, "labelList", "neighbour", d);
    put_list(o, d->neighbour, d->n_internal);
    return FDT_IO_OK;
}

int fdt_put_foam_dual_boundary(out_file *o, const fdt_mesh_view *m, const void *prep,
                               char *err, size_t errlen)
{
    (void)m;
    (void)err;
    (void)errlen;
    const fdt_dualmesh *d = prep;
    dual_header(o, "polyBoundaryMesh", "boundary", d);
    /* the walls of the axes that are not periodic, then the cyclic pairs */
    int walls = 0;
    for (int p = 0; p < 6; p++)
        walls += !(d->periodic >> (p / 2) & 1);
    out_i64(o, (int64_t)(walls + (int)d->n_cyclic));
    out_str(o, "\n(\n");
    for (int p = 0; p < 6; p++)
        if (!(d->periodic >> (p / 2) & 1))
            put_patch(o, fdt_dualmesh_patch[p], d->patch_size[p], d->patch_start[p]);
    for (size_t c = 0; c < d->n_cyclic; c++) {
        const fdt_dual_cyclic *y = &d->cyclic[c];
        char name[64], partner[64];
        shift_name(y->shift, name, sizeof name);
        shift_name(d->cyclic[c ^ 1].shift, partner, sizeof partner);
        put_cyclic(o, name, y->size, y->start, partner, y->sep);
    }
    out_str(o, ")\n");
    return FDT_IO_OK;
}
