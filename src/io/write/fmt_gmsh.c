/*
 * gmsh MSH files (src/io/write/formats.h), ASCII: 4.1 (gmsh's own since 4.1, the
 * default for .msh) and 2.2 (--format msh2, for older readers). Node i of
 * the input is node tag i + 1 (every input point, duplicates included, so
 * the numbering stays the input's); the tets are elements 1..T (type 4),
 * the hull triangles (type 2, outward) elements T + 1 .. T + H. Our tet
 * orientation, det(b - a, c - a, d - a) > 0, is gmsh's: its reference
 * tetrahedron (0,0,0), (1,0,0), (0,1,0), (0,0,1) is positive.
 */
#include "io/write/formats.h"

#include <math.h>

static void put_xyz(out_file *o, const double *p)
{
    for (int c = 0; c < 3; c++) {
        if (c)
            out_char(o, ' ');
        out_double(o, p[c]);
    }
}

/* "i a b c ..." with 1-based ids */
static void put_ids(out_file *o, const fdt_vid *v, int k)
{
    for (int c = 0; c < k; c++) {
        out_char(o, ' ');
        out_i64(o, (int64_t)v[c] + 1);
    }
    out_char(o, '\n');
}

static void bbox(const fdt_mesh_view *m, double lo[3], double hi[3])
{
    for (int c = 0; c < 3; c++) {
        lo[c] = m->n_points ? m->xyz[c] : 0;
        hi[c] = lo[c];
    }
    for (size_t i = 0; i < m->n_points; i++)
        for (int c = 0; c < 3; c++) {
            double x = m->xyz[3 * i + (size_t)c];
            lo[c] = x < lo[c] ? x : lo[c];
            hi[c] = x > hi[c] ? x : hi[c];
        }
}

/* A periodic mesh laid out (meshview.h): each node's input id as a
 * node data view "input_id" (the same section in MSH 2.2 and 4.1). */
static void put_node_src(out_file *o, const fdt_mesh_view *m)
{
    if (!m->point_src)
        return;
    out_str(o, "$NodeData\n1\n\"input_id\"\n1\n0\n3\n0\n1\n");
    out_i64(o, (int64_t)m->n_points);
    out_char(o, '\n');
    for (size_t i = 0; i < m->n_points && !o->err; i++) {
        out_i64(o, (int64_t)i + 1);
        out_char(o, ' ');
        out_i64(o, m->point_src[i]);
        out_char(o, '\n');
    }
    out_str(o, "$EndNodeData\n");
}

int fdt_put_msh41(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                  size_t errlen)
{
    (void)prep;
    (void)err;
    (void)errlen;
    double lo[3], hi[3];
    bbox(m, lo, hi);
    /* One surface (the hull, tag 1) bounding one volume (tag 1). */
    out_str(o, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 1 1\n1 ");
    put_xyz(o, lo);
    out_char(o, ' ');
    put_xyz(o, hi);
    out_str(o, " 0 0\n1 ");
    put_xyz(o, lo);
    out_char(o, ' ');
    put_xyz(o, hi);
    out_str(o, " 0 1 1\n$EndEntities\n$Nodes\n");
    /* numEntityBlocks numNodes minNodeTag maxNodeTag; then one block:
     * entityDim entityTag parametric numNodesInBlock, the tags, the
     * coordinates. */
    int64_t n = (int64_t)m->n_points;
    out_str(o, "1 ");
    out_i64(o, n);
    out_str(o, " 1 ");
    out_i64(o, n);
    out_str(o, "\n3 1 0 ");
    out_i64(o, n);
    out_char(o, '\n');
    for (int64_t i = 1; i <= n && !o->err; i++) {
        out_i64(o, i);
        out_char(o, '\n');
    }
    for (size_t i = 0; i < m->n_points && !o->err; i++) {
        put_xyz(o, m->xyz + 3 * i);
        out_char(o, '\n');
    }
    int64_t T = (int64_t)m->n_tets, H = (int64_t)m->n_hull;
    out_str(o, "$EndNodes\n$Elements\n2 ");
    out_i64(o, T + H);
    out_str(o, " 1 ");
    out_i64(o, T + H);
    out_str(o, "\n3 1 4 ");
    out_i64(o, T);
    out_char(o, '\n');
    for (int64_t t = 0; t < T && !o->err; t++) {
        out_i64(o, t + 1);
        put_ids(o, m->tets + 4 * t, 4);
    }
    out_str(o, "2 1 2 ");
    out_i64(o, H);
    out_char(o, '\n');
    for (int64_t f = 0; f < H && !o->err; f++) {
        out_i64(o, T + f + 1);
        put_ids(o, m->hull + 3 * f, 3);
    }
    out_str(o, "$EndElements\n");
    put_node_src(o, m);
    return FDT_IO_OK;
}

int fdt_put_msh22(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                  size_t errlen)
{
    (void)prep;
    (void)err;
    (void)errlen;
    out_str(o, "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n");
    out_i64(o, (int64_t)m->n_points);
    out_char(o, '\n');
    for (size_t i = 0; i < m->n_points && !o->err; i++) {
        out_i64(o, (int64_t)i + 1);
        out_char(o, ' ');
        put_xyz(o, m->xyz + 3 * i);
        out_char(o, '\n');
    }
    int64_t T = (int64_t)m->n_tets, H = (int64_t)m->n_hull;
    out_str(o, "$EndNodes\n$Elements\n");
    out_i64(o, T + H);
    out_char(o, '\n');
    /* "tag type 2 physical elementary ids": physical 1 and elementary 1
     * for the volume, physical 2 and elementary 1 for the hull surface. */
    for (int64_t t = 0; t < T && !o->err; t++) {
        out_i64(o, t + 1);
        out_str(o, " 4 2 1 1");
        put_ids(o, m->tets + 4 * t, 4);
    }
    for (int64_t f = 0; f < H && !o->err; f++) {
        out_i64(o, T + f + 1);
        out_str(o, " 2 2 2 1");
        put_ids(o, m->hull + 3 * f, 3);
    }
    out_str(o, "$EndElements\n");
    put_node_src(o, m);
    return FDT_IO_OK;
}
