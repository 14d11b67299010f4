/*
 * frontdt's compact binary mesh (.fdtb, src/io/write/formats.h; README, "Binary
 * mesh"): what a program needs to load a huge streamed mesh with one read
 * per array, nothing to parse. Little-endian throughout:
 *   bytes  0..7   magic "FDTMESH\0"
 *          8..11  uint32 version, 1
 *         12..15  uint32 flags: 1 ids are int64 (else int32), 2 the points
 *                 follow the header, 4 the hull faces follow the tets,
 *                 8 a piece: one rank's share of a distributed mesh
 *                 (frontdt-mpi -o BASE.pfdtb), no points, the ids number
 *                 the input file's points (in input order, a duplicate's
 *                 tets name its first occurrence), "points" is how many
 *                 the input has; 16 a periodic mesh (--periodic): the
 *                 tets and hull faces are ids ascending (not oriented),
 *                 their offsets follow (a piece may have both: 8 | 16)
 *         16..23  uint64 points
 *         24..31  uint64 tets      (a streamed file: patched at the end)
 *         32..39  uint64 hull faces (the same)
 *         40..63  zero (reserved); with flag 16 the periods, 3 float64
 *                 (max - min of --box rounded, 0 on an axis that is not
 *                 periodic)
 *   then the points (3 float64 each) if flag 2, the tets (4 ids each,
 *   positively oriented, input numbering), the hull faces (3 ids each,
 *   outward) if flag 4; with flag 16 each tet's 12 offsets (int8: x, y, z
 *   of each vertex in periods, relative to the first, as in .tets), then
 *   each hull face's 9.
 * A streamed file keeps the hull faces in memory until the end (a few
 * percent of the tets' bytes) so that each array stays contiguous.
 */
#include "io/write/formats.h"

#define BIN_HEADER 64
#define BIN_VERSION 1u
enum { BIN_IDS64 = 1, BIN_POINTS = 2, BIN_HULL = 4, BIN_PIECE = 8, BIN_PERIODIC = 16 };

static void put_le(unsigned char *p, uint64_t v, int bytes)
{
    for (int i = 0; i < bytes; i++)
        p[i] = (unsigned char)(v >> (8 * i));
}

static void bin_header(unsigned char h[BIN_HEADER], uint32_t flags, uint64_t n, uint64_t nt,
                       uint64_t nh)
{
    memset(h, 0, BIN_HEADER);
    memcpy(h, "FDTMESH", 8); /* the NUL is the eighth byte */
    put_le(h + 8, BIN_VERSION, 4);
    put_le(h + 12, flags, 4);
    put_le(h + 16, n, 8);
    put_le(h + 24, nt, 8);
    put_le(h + 32, nh, 8);
}

static int host_le(void)
{
    const uint16_t one = 1;
    unsigned char b;
    memcpy(&b, &one, 1);
    return b == 1;
}

static void put_points(out_file *o, const double *xyz, size_t n)
{
    if (host_le()) {
        out_bytes(o, xyz, 3 * n * sizeof(double));
        return;
    }
    for (size_t i = 0; i < 3 * n && !o->err; i++) {
        uint64_t u;
        memcpy(&u, &xyz[i], 8);
        unsigned char b[8];
        put_le(b, u, 8);
        out_bytes(o, b, 8);
    }
}

/* count * k ids as int32 or int64, little-endian. */
static void put_ids(out_file *o, const fdt_vid *v, size_t count, int ids64)
{
    size_t w = ids64 ? 8 : 4;
    if (!ids64 && host_le() && sizeof(fdt_vid) == 4) {
        out_bytes(o, v, count * 4);
        return;
    }
    for (size_t i = 0; i < count && !o->err; i++) {
        char *p = out_room(o, w);
        put_le((unsigned char *)p, (uint64_t)(int64_t)v[i], (int)w);
        o->len += w;
    }
}

/* The periods in the header's reserved bytes (flag 16). */
static void put_periods(unsigned char h[BIN_HEADER], const double period[3])
{
    for (int k = 0; k < 3; k++) {
        uint64_t u;
        memcpy(&u, &period[k], 8);
        put_le(h + 40 + 8 * k, u, 8);
    }
}

/* A periodic mesh's offsets after its ids: each tet's 12, each hull face's
 * 9 (a NULL array of none is not memcpy's). */
static void put_offsets(out_file *o, const int8_t *tet_off, size_t nt, const int8_t *hull_off,
                        size_t nh)
{
    if (nt)
        out_bytes(o, tet_off, 12 * nt);
    if (nh)
        out_bytes(o, hull_off, 9 * nh);
}

int fdt_put_bin(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                size_t errlen)
{
    (void)prep;
    (void)err;
    (void)errlen;
    unsigned char h[BIN_HEADER];
    bin_header(h, BIN_POINTS | BIN_HULL | (m->tet_off ? BIN_PERIODIC : 0), m->n_points,
               m->n_tets, m->n_hull);
    if (m->tet_off)
        put_periods(h, m->period);
    out_bytes(o, h, sizeof h);
    put_points(o, m->xyz, m->n_points);
    put_ids(o, m->tets, 4 * m->n_tets, 0);
    put_ids(o, m->hull, 3 * m->n_hull, 0);
    if (m->tet_off)
        put_offsets(o, m->tet_off, m->n_tets, m->hull_off, m->n_hull);
    return FDT_IO_OK;
}

int fdt_put_bin_piece(out_file *o, uint64_t n_input, const fdt_vid *tets, size_t nt,
                      const fdt_vid *hull, size_t nh, const fdt_bin_periodic *per)
{
    /* int64 ids only when int32 cannot number the input */
    int ids64 = n_input > (uint64_t)INT32_MAX;
    unsigned char h[BIN_HEADER];
    bin_header(h, BIN_PIECE | BIN_HULL | (ids64 ? BIN_IDS64 : 0) | (per ? BIN_PERIODIC : 0),
               n_input, nt, nh);
    if (per)
        put_periods(h, per->period);
    out_bytes(o, h, sizeof h);
    put_ids(o, tets, 4 * nt, ids64);
    put_ids(o, hull, 3 * nh, ids64);
    if (per)
        put_offsets(o, per->tet_off, nt, per->hull_off, nh);
    return FDT_IO_OK;
}

static uint32_t stream_flags(const fdt_stream_out *s)
{
    uint32_t f = BIN_HULL;
    if (s->flags & FDT_STREAM_IDS64)
        f |= BIN_IDS64;
    if (!(s->flags & FDT_STREAM_NO_POINTS))
        f |= BIN_POINTS;
    return f;
}

static int bin_begin(fdt_stream_out *s, char *err, size_t errlen)
{
    (void)err;
    (void)errlen;
    out_file *o = &s->files[0];
    unsigned char h[BIN_HEADER];
    uint32_t fl = stream_flags(s);
    bin_header(h, fl, s->n_points, 0, 0); /* the counts: at finish */
    out_bytes(o, h, sizeof h);
    if (fl & BIN_POINTS)
        put_points(o, s->xyz, s->n_points);
    return FDT_IO_OK;
}

static void bin_tets(fdt_stream_out *s, const fdt_vid *t, size_t count)
{
    put_ids(&s->files[0], t, 4 * count, (s->flags & FDT_STREAM_IDS64) != 0);
}

static void bin_hull(fdt_stream_out *s, const fdt_vid *f, size_t count)
{
    if (count == 0)
        return; /* an empty batch may come with no array (memcpy's NULL) */
    size_t need = 3 * (size_t)s->n_hull + 3 * count;
    if (need > s->hull_cap) {
        size_t cap = s->hull_cap ? 2 * s->hull_cap : 3 * 4096;
        while (cap < need)
            cap *= 2;
        fdt_vid *p = realloc(s->hull, cap * sizeof *p);
        if (!p) {
            out_fail(&s->files[0], ENOMEM);
            return;
        }
        s->hull = p;
        s->hull_cap = cap;
    }
    memcpy(s->hull + 3 * (size_t)s->n_hull, f, 3 * count * sizeof *f);
}

static int bin_finish(fdt_stream_out *s, char *err, size_t errlen)
{
    (void)err;
    (void)errlen;
    out_file *o = &s->files[0];
    put_ids(o, s->hull, 3 * (size_t)s->n_hull, (s->flags & FDT_STREAM_IDS64) != 0);
    unsigned char c[16];
    put_le(c, s->n_tets, 8);
    put_le(c + 8, s->n_hull, 8);
    out_patch(o, 24, c, sizeof c);
    return FDT_IO_OK;
}

const fdt_stream_fmt fdt_stream_bin = {1, bin_begin, bin_tets, bin_hull, bin_finish, NULL};
