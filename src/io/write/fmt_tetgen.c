/* TetGen .node / .ele / .face / .neigh (src/io/write/formats.h), 0-based. */
#include "io/write/formats.h"

int fdt_put_tetgen_node(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                        size_t errlen)
{
    (void)prep;
    (void)err;
    (void)errlen;
    /* "<points> <dimension> <attributes> <boundary markers>", then
     * "<index> <x> <y> <z>", first index 0 (TetGen accepts either base
     * and follows the first index it reads). A periodic mesh laid out
     * (meshview.h) gives each point four attributes: its input id and
     * its image's offsets in periods (0 0 0 for the input points, the
     * first ones), the map back that .vtu's input_id is. */
    int laid = m->point_src != NULL;
    out_i64(o, (int64_t)m->n_points);
    out_str(o, laid ? " 3 4 0\n" : " 3 0 0\n");
    for (size_t i = 0; i < m->n_points && !o->err; i++) {
        out_i64(o, (int64_t)i);
        for (int c = 0; c < 3; c++) {
            out_char(o, ' ');
            out_double(o, m->xyz[3 * i + (size_t)c]);
        }
        if (laid) {
            out_char(o, ' ');
            out_i64(o, m->point_src[i]);
            for (int c = 0; c < 3; c++) {
                out_char(o, ' ');
                out_i64(o, m->point_off[3 * i + (size_t)c]);
            }
        }
        out_char(o, '\n');
    }
    return FDT_IO_OK;
}

/* "<count><header>", then "<index> <v_1> ... <v_k>" a row, the values
 * from vid or, where vid is NULL, from tid: the bodies of .ele, .face
 * and .neigh. */
static void put_rows(out_file *o, size_t count, const char *header, int k,
                     const fdt_vid *vid, const fdt_tid *tid)
{
    out_i64(o, (int64_t)count);
    out_str(o, header);
    for (size_t r = 0; r < count && !o->err; r++) {
        out_i64(o, (int64_t)r);
        for (size_t at = (size_t)k * r; at < (size_t)k * (r + 1); at++) {
            out_char(o, ' ');
            out_i64(o, vid ? (int64_t)vid[at] : (int64_t)tid[at]);
        }
        out_char(o, '\n');
    }
}

int fdt_put_tetgen_ele(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                       size_t errlen)
{
    (void)prep;
    (void)err;
    (void)errlen;
    /* "<tets> <nodes per tet> <region attribute>", then
     * "<index> <v0> <v1> <v2> <v3>" in the tet's own order. Our positive
     * orientation, det(b-a, c-a, d-a) > 0, is TetGen's too (checked
     * against libtet's output), as are outward hull faces and neighbour i
     * opposite vertex i: TetGen readers need no conversion. */
    put_rows(o, m->n_tets, " 4 0\n", 4, m->tets, NULL);
    return FDT_IO_OK;
}

int fdt_put_tetgen_face(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                        size_t errlen)
{
    (void)prep;
    (void)err;
    (void)errlen;
    if (!m->all_faces) {
        /* "<faces> <boundary marker>", then "<index> <v0> <v1> <v2>". */
        put_rows(o, m->n_hull, " 0\n", 3, m->hull, NULL);
        return FDT_IO_OK;
    }
    /* Every face (TetGen -f): "<faces> 1", then "<index> <v0> <v1> <v2>
     * <marker>", marker 1 on the hull and 0 inside, as TetGen marks them.
     * The face list (fdt_result_faces) has its first tet on the positive
     * side; reversed, a hull face is outward as in the hull-only .face,
     * and an interior face points out of its lower-numbered tet. */
    out_i64(o, (int64_t)m->n_faces);
    out_str(o, " 1\n");
    for (size_t f = 0; f < m->n_faces && !o->err; f++) {
        const fdt_vid *v = m->faces + 3 * f;
        out_i64(o, (int64_t)f);
        out_char(o, ' ');
        out_i64(o, v[0]);
        out_char(o, ' ');
        out_i64(o, v[2]);
        out_char(o, ' ');
        out_i64(o, v[1]);
        out_str(o, m->face_tets[2 * f + 1] < 0 ? " 1\n" : " 0\n");
    }
    return FDT_IO_OK;
}

int fdt_put_tetgen_neigh(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                         size_t errlen)
{
    (void)prep;
    (void)err;
    (void)errlen;
    /* "<tets> 4", then "<index> <n0> <n1> <n2> <n3>": neighbour i is
     * opposite vertex i (TetGen's convention and ours), -1 on the hull.
     * A periodic mesh's: across a periodic side, the tet on the other
     * side, which lies in another copy (its face a translate of this
     * one's). */
    put_rows(o, m->n_tets, " 4\n", 4, NULL, m->nbrs);
    return FDT_IO_OK;
}


/* ------------------------------------------------------------------------ */
/* Streaming (src/io/write/formats.h): .node at the start, .ele and .face rows as    */
/* they come, their counts patched at the end                               */
/* ------------------------------------------------------------------------ */

/* A count placeholder: as wide as the largest count (2^64 - 1). TetGen and
 * the other readers split the first line on blanks, so the padding is
 * harmless. */
#define TG_COUNT_WIDTH 20

static void tg_count_line(out_file *o, uint64_t *mark, const char *rest)
{
    *mark = out_tell(o);
    char *p = out_room(o, TG_COUNT_WIDTH);
    fmt_u64_width(p, 0, TG_COUNT_WIDTH);
    o->len += TG_COUNT_WIDTH;
    out_str(o, rest);
}

static int tg_begin(fdt_stream_out *s, char *err, size_t errlen)
{
    fdt_mesh_view v = {.xyz = s->xyz, .n_points = s->n_points};
    int r = fdt_put_tetgen_node(&s->files[0], &v, NULL, err, errlen);
    tg_count_line(&s->files[1], &s->mark[0], " 4 0\n");
    tg_count_line(&s->files[2], &s->mark[1], " 0\n");
    return r;
}

/* Rows "<index> <v_1> ... <v_k>", the index going on from first. */
static void tg_rows(out_file *o, uint64_t first, const fdt_vid *v, size_t count, int k)
{
    for (size_t r = 0; r < count && !o->err; r++) {
        char *p = out_room(o, 21 + (size_t)k * 12 + 1);
        char *q = p + fdt_utoa(p, first + r);
        for (int c = 0; c < k; c++) {
            *q++ = ' ';
            q += fdt_itoa(q, v[(size_t)k * r + (size_t)c]);
        }
        *q++ = '\n';
        o->len += (size_t)(q - p);
    }
}

static void tg_tets(fdt_stream_out *s, const fdt_vid *t, size_t count)
{
    tg_rows(&s->files[1], s->n_tets, t, count, 4);
}

static void tg_hull(fdt_stream_out *s, const fdt_vid *f, size_t count)
{
    tg_rows(&s->files[2], s->n_hull, f, count, 3);
}

static int tg_finish(fdt_stream_out *s, char *err, size_t errlen)
{
    (void)err;
    (void)errlen;
    char p[TG_COUNT_WIDTH];
    fmt_u64_width(p, s->n_tets, TG_COUNT_WIDTH);
    out_patch(&s->files[1], s->mark[0], p, TG_COUNT_WIDTH);
    fmt_u64_width(p, s->n_hull, TG_COUNT_WIDTH);
    out_patch(&s->files[2], s->mark[1], p, TG_COUNT_WIDTH);
    return FDT_IO_OK;
}

const fdt_stream_fmt fdt_stream_tetgen = {3, tg_begin, tg_tets, tg_hull, tg_finish, NULL};
