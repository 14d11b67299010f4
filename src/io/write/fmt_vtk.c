/* VTK: XML .vtu (appended raw, ParaView) and legacy ASCII .vtk
 * (src/io/write/formats.h). */
#include "io/write/formats.h"

static int host_is_little_endian(void)
{
    const uint16_t one = 1;
    unsigned char b;
    memcpy(&b, &one, 1);
    return b == 1;
}

#define VTK_TETRA 10

int fdt_put_vtu(out_file *o, const fdt_mesh_view *m, const void *prep, char *err, size_t errlen)
{
    (void)prep;
    const char *path = o->path;

    /* Appended raw data: each array is a UInt64 byte count followed by the
     * bytes, in host order (byte_order says which); the offset attributes
     * count from the first byte after '_'. */
    uint64_t n = m->n_points, nt = m->n_tets;
    uint64_t sz_pts = 3 * n * sizeof(double);
    uint64_t sz_conn = 4 * nt * sizeof(int64_t);
    uint64_t sz_off = nt * sizeof(int64_t);
    uint64_t sz_typ = nt;
    uint64_t off_pts = 0;
    uint64_t off_conn = off_pts + 8 + sz_pts;
    uint64_t off_off = off_conn + 8 + sz_conn;
    uint64_t off_typ = off_off + 8 + sz_off;
    /* a periodic mesh laid out: each point's input id (meshview.h) */
    uint64_t sz_src = m->point_src ? n * sizeof(int64_t) : 0;
    uint64_t off_src = off_typ + 8 + sz_typ;
    char pdata[256] = "";
    if (m->point_src)
        snprintf(pdata, sizeof pdata,
                 "      <PointData Scalars=\"input_id\">\n"
                 "        <DataArray type=\"Int64\" Name=\"input_id\" "
                 "format=\"appended\" offset=\"%llu\"/>\n"
                 "      </PointData>\n",
                 (unsigned long long)off_src);

    char head[2048];
    int k = snprintf(head, sizeof head,
        "<?xml version=\"1.0\"?>\n"
        "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
        "byte_order=\"%s\" header_type=\"UInt64\">\n"
        "  <UnstructuredGrid>\n"
        "    <Piece NumberOfPoints=\"%llu\" NumberOfCells=\"%llu\">\n"
        "%s"
        "      <Points>\n"
        "        <DataArray type=\"Float64\" Name=\"Points\" "
        "NumberOfComponents=\"3\" format=\"appended\" offset=\"%llu\"/>\n"
        "      </Points>\n"
        "      <Cells>\n"
        "        <DataArray type=\"Int64\" Name=\"connectivity\" "
        "format=\"appended\" offset=\"%llu\"/>\n"
        "        <DataArray type=\"Int64\" Name=\"offsets\" "
        "format=\"appended\" offset=\"%llu\"/>\n"
        "        <DataArray type=\"UInt8\" Name=\"types\" "
        "format=\"appended\" offset=\"%llu\"/>\n"
        "      </Cells>\n"
        "    </Piece>\n"
        "  </UnstructuredGrid>\n"
        "  <AppendedData encoding=\"raw\">\n"
        "   _",
        host_is_little_endian() ? "LittleEndian" : "BigEndian",
        (unsigned long long)n, (unsigned long long)nt, pdata,
        (unsigned long long)off_pts, (unsigned long long)off_conn,
        (unsigned long long)off_off, (unsigned long long)off_typ);
    if (k < 0 || (size_t)k >= sizeof head) {
        return set_errno_err(err, errlen, path, EOVERFLOW);
    }
    out_bytes(o, head, (size_t)k);

    out_bytes(o, &sz_pts, 8);
    out_bytes(o, m->xyz, (size_t)sz_pts);

    out_bytes(o, &sz_conn, 8);
    for (size_t i = 0; i < 4 * m->n_tets && !o->err; i++) {
        int64_t v = m->tets[i];
        char *p = out_room(o, 8);
        memcpy(p, &v, 8);
        o->len += 8;
    }
    out_bytes(o, &sz_off, 8);
    for (size_t t = 0; t < m->n_tets && !o->err; t++) {
        int64_t v = 4 * (int64_t)(t + 1);
        char *p = out_room(o, 8);
        memcpy(p, &v, 8);
        o->len += 8;
    }
    out_bytes(o, &sz_typ, 8);
    for (size_t t = 0; t < m->n_tets && !o->err; t++)
        out_char(o, VTK_TETRA);
    if (m->point_src) {
        out_bytes(o, &sz_src, 8);
        for (size_t i = 0; i < m->n_points && !o->err; i++) {
            int64_t v = m->point_src[i];
            char *p = out_room(o, 8);
            memcpy(p, &v, 8);
            o->len += 8;
        }
    }
    out_str(o, "\n  </AppendedData>\n</VTKFile>\n");
    return FDT_IO_OK;
}

int fdt_put_vtk(out_file *o, const fdt_mesh_view *m, const void *prep, char *err, size_t errlen)
{
    (void)prep;
    (void)err;
    (void)errlen;

    out_str(o, "# vtk DataFile Version 3.0\n"
                "frontdt Delaunay tetrahedralization\n"
                "ASCII\n"
                "DATASET UNSTRUCTURED_GRID\n"
                "POINTS ");
    out_i64(o, (int64_t)m->n_points);
    out_str(o, " double\n");
    for (size_t i = 0; i < m->n_points && !o->err; i++) {
        out_double(o, m->xyz[3 * i]);
        out_char(o, ' ');
        out_double(o, m->xyz[3 * i + 1]);
        out_char(o, ' ');
        out_double(o, m->xyz[3 * i + 2]);
        out_char(o, '\n');
    }
    /* CELLS <cells> <list size>: each cell is its count then its ids. */
    out_str(o, "CELLS ");
    out_i64(o, (int64_t)m->n_tets);
    out_char(o, ' ');
    out_i64(o, 5 * (int64_t)m->n_tets);
    out_char(o, '\n');
    for (size_t t = 0; t < m->n_tets && !o->err; t++) {
        out_char(o, '4');
        for (int c = 0; c < 4; c++) {
            out_char(o, ' ');
            out_i64(o, m->tets[4 * t + (size_t)c]);
        }
        out_char(o, '\n');
    }
    out_str(o, "CELL_TYPES ");
    out_i64(o, (int64_t)m->n_tets);
    out_char(o, '\n');
    for (size_t t = 0; t < m->n_tets && !o->err; t++)
        out_str(o, "10\n");
    if (m->point_src) { /* a periodic mesh laid out: each point's input id */
        out_str(o, "POINT_DATA ");
        out_i64(o, (int64_t)m->n_points);
        out_str(o, "\nSCALARS input_id long 1\nLOOKUP_TABLE default\n");
        for (size_t i = 0; i < m->n_points && !o->err; i++) {
            out_i64(o, m->point_src[i]);
            out_char(o, '\n');
        }
    }
    return FDT_IO_OK;
}


/* ------------------------------------------------------------------------ */
/* Streaming .vtu (src/io/write/formats.h)                                           */
/* ------------------------------------------------------------------------ */

/*
 * The same file as fdt_put_vtu, laid out for a tet count known only at
 * the end: the points (known) first, then the connectivity as the tets
 * come, then the offsets and types (arithmetic: 4(t+1) and 10, written at
 * the end from the count). What depends on the count (NumberOfCells, the
 * offset attributes of the last two arrays, the connectivity's byte
 * count) is written as a fixed-width placeholder and patched: each number
 * in a field of VTU_NUM_FIELD bytes that holds its decimal digits, the
 * attribute's closing quote, then blanks (offset="4750800"      />); the
 * byte count as its 8 raw bytes.
 *
 * The blanks lie between the attribute and what follows, where XML allows
 * any whitespace, so the attribute's value is the bare number both readers
 * expect: VTK parses it as a number, but meshio 5 finds each appended
 * array by comparing offset="..." as a string with the decimal offset it
 * has counted to, so a value padded with zeros or blanks inside the
 * quotes ("00000000000000000200", "200 ") is not found (issue 34 item 4;
 * tests/vtu_readback.py reads the streamed file with both).
 */
#define VTU_NUM_FIELD 21 /* UINT64_MAX's 20 digits and the closing quote */

/* Fills field[0..VTU_NUM_FIELD) with v's digits, '"' and blanks. */
static void vtu_num_field(char field[VTU_NUM_FIELD + 1], uint64_t v)
{
    int k = snprintf(field, VTU_NUM_FIELD + 1, "%llu\"", (unsigned long long)v);
    memset(field + k, ' ', (size_t)(VTU_NUM_FIELD - k));
    field[VTU_NUM_FIELD] = '\0';
}

/* Puts "<prefix>" then the field of 0, and remembers where the field is. */
static void vtu_placeholder(out_file *o, const char *prefix, uint64_t *mark)
{
    char field[VTU_NUM_FIELD + 1];
    out_str(o, prefix);
    *mark = out_tell(o);
    vtu_num_field(field, 0);
    out_bytes(o, field, VTU_NUM_FIELD);
}

static void vtu_patch_num(out_file *o, uint64_t mark, uint64_t v)
{
    char field[VTU_NUM_FIELD + 1];
    vtu_num_field(field, v);
    out_patch(o, mark, field, VTU_NUM_FIELD);
}

static int vtu_begin(fdt_stream_out *s, char *err, size_t errlen)
{
    out_file *o = &s->files[0];
    uint64_t n = s->n_points;
    uint64_t sz_pts = 3 * n * sizeof(double);
    char line[512];
    int k = snprintf(line, sizeof line,
        "<?xml version=\"1.0\"?>\n"
        "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
        "byte_order=\"%s\" header_type=\"UInt64\">\n"
        "  <UnstructuredGrid>\n"
        "    <Piece NumberOfPoints=\"%llu\"",
        host_is_little_endian() ? "LittleEndian" : "BigEndian", (unsigned long long)n);
    if (k < 0 || (size_t)k >= sizeof line)
        return set_errno_err(err, errlen, o->path, EOVERFLOW);
    out_bytes(o, line, (size_t)k);
    vtu_placeholder(o, " NumberOfCells=\"", &s->mark[0]);
    out_str(o, ">\n"
               "      <Points>\n"
               "        <DataArray type=\"Float64\" Name=\"Points\" "
               "NumberOfComponents=\"3\" format=\"appended\" offset=\"0\"/>\n"
               "      </Points>\n"
               "      <Cells>\n"
               "        <DataArray type=\"Int64\" Name=\"connectivity\" "
               "format=\"appended\" offset=\"");
    out_i64(o, (int64_t)(8 + sz_pts));
    vtu_placeholder(o, "\"/>\n        <DataArray type=\"Int64\" Name=\"offsets\" "
                       "format=\"appended\" offset=\"", &s->mark[1]);
    vtu_placeholder(o, "/>\n        <DataArray type=\"UInt8\" Name=\"types\" "
                       "format=\"appended\" offset=\"", &s->mark[2]);
    out_str(o, "/>\n"
               "      </Cells>\n"
               "    </Piece>\n"
               "  </UnstructuredGrid>\n"
               "  <AppendedData encoding=\"raw\">\n"
               "   _");
    /* the appended offsets count from the byte after '_' */
    s->mark[3] = out_tell(o);
    out_bytes(o, &sz_pts, 8);
    out_bytes(o, s->xyz, (size_t)sz_pts);
    uint64_t zero = 0; /* the connectivity's byte count, patched */
    out_bytes(o, &zero, 8);
    return FDT_IO_OK;
}

static void vtu_tets(fdt_stream_out *s, const fdt_vid *t, size_t count)
{
    out_file *o = &s->files[0];
    for (size_t i = 0; i < 4 * count && !o->err; i++) {
        int64_t v = t[i];
        char *p = out_room(o, 8);
        memcpy(p, &v, 8);
        o->len += 8;
    }
}

static int vtu_finish(fdt_stream_out *s, char *err, size_t errlen)
{
    (void)err;
    (void)errlen;
    out_file *o = &s->files[0];
    uint64_t nt = s->n_tets, n = s->n_points;
    uint64_t sz_pts = 3 * n * sizeof(double);
    uint64_t sz_conn = 4 * nt * sizeof(int64_t), sz_off = nt * sizeof(int64_t);
    uint64_t off_off = 8 + sz_pts + 8 + sz_conn, off_typ = off_off + 8 + sz_off;
    out_bytes(o, &sz_off, 8);
    for (uint64_t t = 0; t < nt && !o->err; t++) {
        int64_t v = 4 * (int64_t)(t + 1);
        char *p = out_room(o, 8);
        memcpy(p, &v, 8);
        o->len += 8;
    }
    out_bytes(o, &nt, 8); /* the types' byte count: one a cell */
    for (uint64_t t = 0; t < nt && !o->err; t++)
        out_char(o, VTK_TETRA);
    out_str(o, "\n  </AppendedData>\n</VTKFile>\n");
    vtu_patch_num(o, s->mark[0], nt);
    vtu_patch_num(o, s->mark[1], off_off);
    vtu_patch_num(o, s->mark[2], off_typ);
    out_patch(o, s->mark[3] + 8 + sz_pts, &sz_conn, 8);
    return FDT_IO_OK;
}

const fdt_stream_fmt fdt_stream_vtu = {1, vtu_begin, vtu_tets, NULL, vtu_finish, NULL};
