/*
 * Medit .mesh (src/io/write/formats.h), ASCII, as MMG and meshio read it: every
 * input point (reference 0), the tets (reference 1) and the outward hull
 * triangles (reference 1), 1-based. A periodic mesh laid out in space
 * (writer.c): each point's reference is its input id (an image vertex's,
 * the point it is an image of), as the other laid-out formats' input_id.
 */
#include "io/write/formats.h"

static void put_block(out_file *o, const char *kw, const fdt_vid *v, size_t count, int k)
{
    out_str(o, kw);
    out_i64(o, (int64_t)count);
    out_char(o, '\n');
    for (size_t r = 0; r < count && !o->err; r++) {
        for (int c = 0; c < k; c++) {
            out_i64(o, (int64_t)v[(size_t)k * r + (size_t)c] + 1);
            out_char(o, ' ');
        }
        out_str(o, "1\n");
    }
}

int fdt_put_medit(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                  size_t errlen)
{
    (void)prep;
    (void)err;
    (void)errlen;
    /* version 2: coordinates in double precision */
    out_str(o, "MeshVersionFormatted 2\n\nDimension 3\n\nVertices\n");
    out_i64(o, (int64_t)m->n_points);
    out_char(o, '\n');
    for (size_t i = 0; i < m->n_points && !o->err; i++) {
        for (int c = 0; c < 3; c++) {
            out_double(o, m->xyz[3 * i + (size_t)c]);
            out_char(o, ' ');
        }
        out_i64(o, m->point_src ? (int64_t)m->point_src[i] : 0);
        out_char(o, '\n');
    }
    put_block(o, "\nTetrahedra\n", m->tets, m->n_tets, 4);
    put_block(o, "\nTriangles\n", m->hull, m->n_hull, 3);
    out_str(o, "\nEnd\n");
    return FDT_IO_OK;
}
