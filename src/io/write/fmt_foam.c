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
 */
#include "io/write/formats.h"
#include "mesh/dualmesh.h"

typedef struct foam_prep {
    size_t n_internal, n_faces, n_points, n_cells;
    size_t *order;   /* n_faces: face list indices in OpenFOAM order */
    fdt_vid *map;    /* n_points of the input: the new number, -1 unused */
} foam_prep;

int fdt_foam_prepare(const fdt_mesh_view *m, void **prep, const char *path, char *err,
                     size_t errlen)
{
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
    p->order = (size_t *)(p + 1);
    p->map = (fdt_vid *)(p->order + F);
    p->n_faces = F;
    p->n_cells = T;
    /* points: the used ones, in input order */
    for (size_t i = 0; i < N; i++)
        p->map[i] = -1;
    for (size_t i = 0; i < 4 * T; i++)
        p->map[m->tets[i]] = 0;
    size_t k = 0;
    for (size_t i = 0; i < N; i++)
        if (p->map[i] == 0)
            p->map[i] = (fdt_vid)k++;
    p->n_points = k;
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

/* One point of a vectorField: "(x y z)" on a line. */
static void put_point(out_file *o, const double *x)
{
    out_char(o, '(');
    for (int c = 0; c < 3; c++) {
        if (c)
            out_char(o, ' ');
        out_double(o, x[c]);
    }
    out_str(o, ")\n");
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
    for (size_t i = 0; i < p->n_faces && !o->err; i++) {
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
    for (size_t i = 0; i < count && !o->err; i++) {
        out_i64(o, (int64_t)m->face_tets[2 * p->order[i] + (size_t)side]);
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

int fdt_put_foam_boundary(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                          size_t errlen)
{
    (void)m;
    (void)err;
    (void)errlen;
    const foam_prep *p = prep;
    header(o, "polyBoundaryMesh", "boundary", p);
    out_str(o, "1\n(\n");
    put_patch(o, "hull", p->n_faces - p->n_internal, p->n_internal);
    out_str(o, ")\n");
    return FDT_IO_OK;
}

/* ------------------------------------------------------------------ */
/* The Voronoi dual (src/mesh/dualmesh.h): prep is the fdt_dualmesh, the
 * view unused. Its faces are in OpenFOAM's order and turned already. */

#define DUAL_WHAT "Voronoi cells clipped by a box, a cell a point"

static void dual_header(out_file *o, const char *cls, const char *object,
                        const fdt_dualmesh *d)
{
    size_t counts[4] = {d->n_verts, d->n_cells, d->n_faces, d->n_internal};
    header_of(o, DUAL_WHAT, cls, object, counts);
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
    out_str(o, "6\n(\n");
    for (int p = 0; p < 6; p++)
        put_patch(o, fdt_dualmesh_patch[p], d->patch_size[p], d->patch_start[p]);
    out_str(o, ")\n");
    return FDT_IO_OK;
}
