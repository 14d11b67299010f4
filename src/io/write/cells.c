/* The Voronoi cells as text: see cells.h. Written through the mesh
 * writers' buffer (outfile.h): one stdio call a megabyte, not a number. */
#include "io/write/cells.h"

#include <errno.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "base/spawn.h"
#include "io/write/outfile.h"

static const char codes[] = "ixyzqvFsnfcCdh%";
/* The CSV table's columns, each a code, and its header. */
#define CSV_CODES "iqvFsCdh"
#define CSV_HEADER "id,x,y,z,volume,area,faces,cx,cy,cz,density,flags\n"
/* The density table's row. */
#define DENSITY_FORMAT "%d %h"

int fdt_cells_format_check(const char *fmt, int *needs_nbrs, char *err, size_t errlen)
{
    int nb = 0;
    for (const char *p = fmt; *p; p++) {
        if (*p != '%')
            continue;
        p++;
        if (!*p || !strchr(codes, *p)) {
            snprintf(err, errlen, "'%%%.1s' at byte %zu of the format '%s' is not a cell code "
                     "(%%i %%x %%y %%z %%q %%v %%F %%s %%n %%f %%c %%C %%d %%h %%%%)",
                     *p ? p : "", (size_t)(p - fmt), fmt);
            return -1;
        }
        nb |= *p == 'n' || *p == 'f';
    }
    if (needs_nbrs)
        *needs_nbrs = nb;
    return 0;
}

unsigned fdt_cells_table_skip(const char *fmt, int csv, int density)
{
    unsigned skip = csv ? 0 : FDT_CELLS_NO_CENTROIDS | FDT_CELLS_NO_DENSITIES;
    for (const char *p = csv ? NULL : fmt; p && *p; p++) {
        if (*p != '%')
            continue;
        if (!*++p)
            break; /* a '%' that ends the format (fdt_cells_format_check refuses it) */
        if (*p == 'c' || *p == 'C')
            skip &= ~FDT_CELLS_NO_CENTROIDS;
        if (*p == 'd')
            skip &= ~FDT_CELLS_NO_DENSITIES;
    }
    return density ? skip & ~FDT_CELLS_NO_DENSITIES : skip;
}

/* Whether those tables read only what v holds. */
static int tables_fit(const char *fmt, int csv, int density, const fdt_voronoi *v)
{
    unsigned missing = (fdt_voronoi_centroids(v) ? 0 : FDT_CELLS_NO_CENTROIDS) |
                       (fdt_voronoi_densities(v) ? 0 : FDT_CELLS_NO_DENSITIES);
    return !(missing & ~fdt_cells_table_skip(fmt, csv, density));
}

/* What a table's rows read, fetched from v once a range rather than a
 * call a code of every row. */
typedef struct cells_view {
    const fdt_voronoi *v;
    const fdt_vid *ids;  /* a streamed batch's rows' input ids, or NULL: row i is point i */
    const double *pts;   /* the rows' points: the batch's, else xyz (NULL: no code reads them) */
    const double *vol, *area, *cen, *dens; /* cen, dens NULL where skipped */
    const int32_t *nfaces;
    const uint8_t *flags;
} cells_view;

static cells_view view_of(const fdt_voronoi *v, const double *xyz)
{
    const fdt_vid *ids = fdt_voronoi_ids(v);
    cells_view c = {v,
                    ids,
                    ids ? fdt_voronoi_points(v) : xyz,
                    fdt_voronoi_volumes(v),
                    fdt_voronoi_areas(v),
                    fdt_voronoi_centroids(v),
                    fdt_voronoi_densities(v),
                    fdt_voronoi_num_faces(v),
                    fdt_voronoi_flags(v)};
    return c;
}

/* Point i's neighbours (%n) or face areas (%f), separated by blanks. */
static void list(out_file *o, const fdt_voronoi *v, size_t i, int areas)
{
    size_t cnt = 0;
    const fdt_vid *ids;
    const double *fa;
    if (fdt_voronoi_neighbors(v, (fdt_vid)i, &cnt, &ids, &fa) != FDT_OK)
        return;
    for (size_t e = 0; e < cnt; e++) {
        if (e)
            out_char(o, ' ');
        if (areas)
            out_double(o, fa[e]);
        else
            out_i64(o, ids[e]);
    }
}

/* Three values, separated by sep. */
static void three(out_file *o, const double *x, char sep)
{
    for (int k = 0; k < 3; k++) {
        if (k)
            out_char(o, sep);
        out_double(o, x[k]);
    }
}

static void code(out_file *o, char c, const cells_view *cv, size_t i, char sep)
{
    const double *p = cv->pts ? cv->pts + 3 * i : NULL; /* NULL: no code reads it */
    int merged = (cv->flags[i] & FDT_CELL_MERGED) != 0;
    double rel[3];
    switch (c) {
    case 'i': out_i64(o, cv->ids ? (int64_t)cv->ids[i] : (int64_t)i); break;
    case 'x': out_double(o, p[0]); break;
    case 'y': out_double(o, p[1]); break;
    case 'z': out_double(o, p[2]); break;
    case 'q': three(o, p, sep); break;
    case 'v': out_double(o, cv->vol[i]); break;
    case 'F': out_double(o, cv->area[i]); break;
    case 's': out_i64(o, cv->nfaces[i]); break;
    case 'n': list(o, cv->v, i, 0); break;
    case 'f': list(o, cv->v, i, 1); break;
    case 'c':
        for (int k = 0; k < 3; k++)
            rel[k] = merged ? 0 : cv->cen[3 * i + k] - p[k];
        three(o, rel, sep);
        break;
    case 'C': three(o, merged ? p : cv->cen + 3 * i, sep); break;
    case 'd': out_double(o, cv->dens[i]); break;
    case 'h': out_i64(o, cv->flags[i]); break;
    default: out_char(o, '%'); break;
    }
}

/* An output buffer on f (outfile.h); 0 or ENOMEM. */
static int open_out(out_file *o, FILE *f)
{
    memset(o, 0, sizeof *o);
    o->f = f;
    o->slot = -1;
    o->path = "";
    o->buf = malloc(OUT_BUF_SIZE);
    return o->buf ? 0 : ENOMEM;
}

/* Flushes and frees o's buffer: 0 or the errno of the first failure. */
static int close_out(out_file *o)
{
    out_flush(o);
    free(o->buf);
    return o->err;
}

/* Rows [lo, hi) of the table through o. */
static void put_range(out_file *o, const char *fmt, const fdt_voronoi *v, const double *xyz,
                      int csv, size_t lo, size_t hi)
{
    const cells_view cv = view_of(v, xyz);
    for (size_t i = lo; i < hi && !o->err; i++) {
        for (const char *p = fmt; *p; p++) {
            if (csv && p != fmt)
                out_char(o, ',');
            if (csv)
                code(o, *p, &cv, i, ',');
            else if (*p != '%')
                out_char(o, *p);
            else
                code(o, *++p, &cv, i, ' ');
        }
        out_char(o, '\n');
    }
}

/* Rows a block formatted on a thread: with a dozen neighbours and their
 * areas, about 3 MB of text. */
#define ROWS_BLOCK 8192

typedef struct rows_block {
    const char *fmt;
    const fdt_voronoi *v;
    const double *xyz;
    int csv;
    size_t lo, hi;
    char *text; /* the rows (open_memstream's, owned) */
    size_t len;
    int err;
} rows_block;

/* A block's rows into memory (a thread of fdt_fork_join). */
static void *format_block(void *arg)
{
    rows_block *b = arg;
    b->text = NULL;
    b->len = 0;
    b->err = 0;
    FILE *m = open_memstream(&b->text, &b->len);
    out_file o;
    if (!m || open_out(&o, m)) {
        b->err = ENOMEM;
    } else {
        put_range(&o, b->fmt, b->v, b->xyz, b->csv, b->lo, b->hi);
        b->err = close_out(&o);
    }
    if (m && fclose(m) != 0 && !b->err)
        b->err = errno ? errno : ENOMEM;
    return NULL;
}

/* The rows through a buffer on f; 0 or the errno of the first failure.
 * With threads, blocks of rows are formatted side by side in memory and
 * written in order, one round of blocks at a time (the numbers' digits
 * are most of a table's time). */
static int put_rows(FILE *f, const char *fmt, const fdt_voronoi *v, const double *xyz, int csv,
                    int threads)
{
    out_file o;
    if (open_out(&o, f))
        return ENOMEM;
    size_t n = fdt_voronoi_num_points(v);
    if (csv)
        out_str(&o, CSV_HEADER);
    rows_block *b = threads > 1 && n > ROWS_BLOCK ? calloc((size_t)threads, sizeof *b) : NULL;
    if (!b) {
        put_range(&o, fmt, v, xyz, csv, 0, n);
        return close_out(&o);
    }
    for (size_t at = 0; at < n && !o.err;) {
        int k = 0;
        for (; k < threads && at < n; k++) {
            rows_block x = {fmt, v, xyz, csv, at, n - at > ROWS_BLOCK ? at + ROWS_BLOCK : n,
                            NULL, 0, 0};
            b[k] = x;
            at = x.hi;
        }
        fdt_fork_join(b, sizeof *b, k, format_block);
        for (int t = 0; t < k; t++) {
            if (b[t].err)
                out_fail(&o, b[t].err);
            else
                out_bytes(&o, b[t].text, b[t].len);
            free(b[t].text);
        }
    }
    free(b);
    return close_out(&o);
}

int fdt_wr_cells(FILE *f, const char *fmt, const fdt_voronoi *v, const double *xyz, int threads)
{
    if (!tables_fit(fmt, !fmt, 0, v))
        return EINVAL;
    return fmt ? put_rows(f, fmt, v, xyz, 0, threads) : put_rows(f, CSV_CODES, v, xyz, 1, threads);
}

int fdt_wr_density(FILE *f, const fdt_voronoi *v, int threads)
{
    if (!tables_fit(NULL, 0, 1, v))
        return EINVAL;
    return put_rows(f, DENSITY_FORMAT, v, NULL, 0, threads);
}

/* ---------------------------------------------------------------- spool */

struct fdt_cells_spool {
    size_t base, n;   /* the input ids [base, base + n) */
    const char *fmt;  /* the cells' table: its format, or NULL for none */
    int csv;          /* fmt is CSV_CODES */
    int density;      /* the density table too */
    FILE *f;          /* the spool: a record a row (unlinked temporary) */
    uint64_t pos;     /* its length so far */
    uint64_t *off;    /* by input id: its record's offset, UINT64_MAX none */
    uint64_t text[2]; /* the two tables' bytes so far (no header) */
};

void fdt_cells_dir(const char *path, char *dir, size_t len)
{
    const char *slash = strrchr(path, '/');
    snprintf(dir, len, "%.*s", slash ? (int)(slash - path) + (slash == path) : 1,
             slash ? path : ".");
}

FILE *fdt_cells_temp(const char *dir)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/.frontdt-spool.XXXXXX", dir);
    int fd = mkstemp(path);
    if (fd < 0)
        return NULL;
    unlink(path); /* gone with the process, whatever happens */
    FILE *f = fdopen(fd, "w+b");
    if (!f) {
        int e = errno;
        close(fd);
        errno = e;
    }
    return f;
}

int fdt_cells_spool_open(fdt_cells_spool **sp, size_t base, size_t n, const char *fmt, int csv,
                         int density, const char *dir)
{
    fdt_cells_spool *s = calloc(1, sizeof *s);
    *sp = NULL;
    if (!s)
        return ENOMEM;
    s->base = base;
    s->n = n;
    s->fmt = csv ? CSV_CODES : fmt;
    s->csv = csv;
    s->density = density;
    s->off = malloc((n ? n : 1) * sizeof *s->off);
    s->f = s->off ? fdt_cells_temp(dir) : NULL;
    int e = !s->off ? ENOMEM : !s->f ? (errno ? errno : EIO) : 0;
    if (e) {
        free(s->off);
        free(s);
        return e;
    }
    for (size_t i = 0; i < n; i++)
        s->off[i] = UINT64_MAX;
    *sp = s;
    return 0;
}

void fdt_cells_spool_close(fdt_cells_spool **sp)
{
    if (!sp || !*sp)
        return;
    if ((*sp)->f)
        fclose((*sp)->f);
    free((*sp)->off);
    free(*sp);
    *sp = NULL;
}

static void no_report(void *user, int stage, uint64_t done, uint64_t total)
{
    (void)user;
    (void)stage;
    (void)done;
    (void)total;
}

/* Input id's row, its two tables' text (l[0] and l[1] bytes at text),
 * appended to the spool as a record: the lengths, then the text. 0 or an
 * errno: EINVAL for an id outside the spool's or one spooled already. */
static int spool_row(fdt_cells_spool *s, size_t id, const uint32_t l[2], const char *text)
{
    size_t j = id - s->base;
    if (id < s->base || j >= s->n)
        return EINVAL; /* not a row of this spool's ids */
    if (s->off[j] != UINT64_MAX)
        return EINVAL; /* a row twice */
    s->off[j] = s->pos;
    s->text[0] += l[0];
    s->text[1] += l[1];
    size_t len = (size_t)l[0] + l[1];
    errno = 0;
    if (fwrite(l, 2 * sizeof *l, 1, s->f) != 1 || fwrite(text, 1, len, s->f) != len)
        return errno ? errno : EIO;
    s->pos += 2 * sizeof *l + len;
    return 0;
}

/* Rows a chunk of a batch formatted in memory before it is spooled. */
#define SPOOL_CHUNK 4096

/* Rows [lo, hi) of v into the spool: for each a record of the two
 * tables' lengths (uint32 each) and their text. 0 or an errno. */
static int spool_chunk(fdt_cells_spool *s, const fdt_voronoi *v, size_t lo, size_t hi)
{
    char *text = NULL;
    size_t len = 0;
    size_t *cut = malloc(2 * (hi - lo) * sizeof *cut); /* each row's two ends */
    FILE *m = cut ? open_memstream(&text, &len) : NULL;
    out_meter mt = {no_report, NULL, 0, 0};
    out_file o;
    int e = 0;
    if (!m || open_out(&o, m)) {
        e = ENOMEM;
    } else {
        o.meter = &mt; /* mt.done: the bytes flushed to m so far */
        for (size_t r = lo; r < hi; r++) {
            if (s->fmt)
                put_range(&o, s->fmt, v, NULL, s->csv, r, r + 1);
            cut[2 * (r - lo)] = (size_t)mt.done + o.len;
            if (s->density)
                put_range(&o, DENSITY_FORMAT, v, NULL, 0, r, r + 1);
            cut[2 * (r - lo) + 1] = (size_t)mt.done + o.len;
        }
        e = close_out(&o);
    }
    if (m && fclose(m) != 0 && !e)
        e = errno ? errno : ENOMEM;
    const fdt_vid *ids = fdt_voronoi_ids(v);
    for (size_t r = lo, at = 0; !e && r < hi; r++) {
        size_t mid = cut[2 * (r - lo)], end = cut[2 * (r - lo) + 1];
        uint32_t l[2] = {(uint32_t)(mid - at), (uint32_t)(end - mid)};
        e = mid - at > UINT32_MAX || end - mid > UINT32_MAX ? EFBIG
                                                            : spool_row(s, (size_t)ids[r], l, text + at);
        at = end;
    }
    free(text);
    free(cut);
    return e;
}

int fdt_cells_spool_add(fdt_cells_spool *s, const fdt_voronoi *v)
{
    size_t n = fdt_voronoi_num_points(v);
    int e = tables_fit(s->csv ? NULL : s->fmt, s->csv, s->density, v) ? 0 : EINVAL;
    for (size_t lo = 0; lo < n && !e; lo += SPOOL_CHUNK)
        e = spool_chunk(s, v, lo, n - lo > SPOOL_CHUNK ? lo + SPOOL_CHUNK : n);
    return e;
}

int fdt_cells_spool_add_row(fdt_cells_spool *s, size_t id, const uint32_t l[2], const char *text)
{
    return spool_row(s, id, l, text);
}

/* The spool's records readable at *base (NULL when it is empty): its
 * stream flushed and the file mapped. 0 or an errno. */
static int spool_map(fdt_cells_spool *s, const char **base)
{
    *base = NULL;
    errno = 0;
    if (fflush(s->f) != 0)
        return errno ? errno : EIO;
    if (!s->pos)
        return 0;
    void *mp = mmap(NULL, (size_t)s->pos, PROT_READ, MAP_PRIVATE, fileno(s->f), 0);
    if (mp == MAP_FAILED)
        return errno;
    *base = mp;
    return 0;
}

static void spool_unmap(const fdt_cells_spool *s, const char *base)
{
    if (base)
        munmap((void *)(uintptr_t)base, (size_t)s->pos);
}

int fdt_cells_spool_each(fdt_cells_spool *s,
                         int (*fn)(void *user, size_t id, const uint32_t l[2], const char *text),
                         void *user)
{
    const char *base;
    int e = spool_map(s, &base);
    for (size_t i = 0; i < s->n && !e; i++) {
        if (s->off[i] == UINT64_MAX)
            continue;
        const char *rec = base + s->off[i];
        uint32_t l[2];
        memcpy(l, rec, sizeof l);
        e = fn(user, s->base + i, l, rec + sizeof l);
    }
    spool_unmap(s, base);
    return e;
}

uint64_t fdt_cells_spool_bytes(const fdt_cells_spool *s, int table, int header)
{
    return s->text[table] + (table == 0 && s->csv && header ? strlen(CSV_HEADER) : 0);
}

int fdt_cells_spool_put(fdt_cells_spool *s, int table, int header, FILE *f)
{
    for (size_t i = 0; i < s->n; i++)
        if (s->off[i] == UINT64_MAX)
            return EINVAL; /* a row never came: the run was not whole */
    const char *base;
    int e = spool_map(s, &base);
    if (e)
        return e;
    out_file o;
    e = open_out(&o, f);
    if (!e && table == 0 && s->csv && header)
        out_str(&o, CSV_HEADER);
    for (size_t i = 0; i < s->n && !e && !o.err; i++) {
        const char *rec = base + s->off[i];
        uint32_t l[2];
        memcpy(l, rec, sizeof l);
        out_bytes(&o, rec + sizeof l + (table ? l[0] : 0), l[table]);
    }
    if (!e)
        e = close_out(&o);
    spool_unmap(s, base);
    return e;
}

int fdt_wr_rows(FILE *f, const double *v, size_t rows, size_t k)
{
    out_file o;
    if (open_out(&o, f))
        return ENOMEM;
    for (size_t i = 0; i < rows && !o.err; i++) {
        for (size_t c = 0; c < k; c++) {
            if (c)
                out_char(&o, ' ');
            out_double(&o, v[k * i + c]);
        }
        out_char(&o, '\n');
    }
    return close_out(&o);
}

/* A growable array of bytes. */
typedef struct bytes {
    unsigned char *p;
    size_t len, cap;
} bytes;

static int put_bytes(bytes *b, const void *x, size_t n)
{
    if (b->len + n > b->cap) {
        size_t nc = b->cap ? 2 * b->cap : 4096;
        while (nc < b->len + n)
            nc *= 2;
        unsigned char *q = realloc(b->p, nc);
        if (!q)
            return -1;
        b->p = q;
        b->cap = nc;
    }
    memcpy(b->p + b->len, x, n);
    b->len += n;
    return 0;
}

static int put_i64(bytes *b, int64_t x)
{
    return put_bytes(b, &x, sizeof x);
}

int fdt_wr_cells_vtu(FILE *f, fdt_voronoi *v, const double *xyz)
{
    /* The arrays, in their order in the file: points, connectivity,
     * offsets, types, faces, faceoffsets, volume, point. */
    enum { NARR = 8 };
    bytes a[NARR];
    memset(a, 0, sizeof a);
    size_t n = fdt_voronoi_num_points(v), nv_all = 0, ncells = 0;
    int64_t conn_end = 0;
    int err = 0;
    for (size_t i = 0; i < n && !err; i++) {
        size_t nv, nf;
        const double *vs;
        const int32_t *fs;
        int rc = fdt_voronoi_polyhedron(v, xyz, (fdt_vid)i, &nv, &vs, &nf, &fs);
        if (rc != FDT_OK) {
            err = rc;
            break;
        }
        if (nv == 0)
            continue; /* a merged duplicate */
        const unsigned char type = 42; /* VTK_POLYHEDRON */
        int bad = put_bytes(&a[0], vs, 3 * nv * sizeof *vs);
        for (size_t j = 0; j < nv && !bad; j++)
            bad = put_i64(&a[1], (int64_t)(nv_all + j));
        conn_end += (int64_t)nv;
        bad = bad || put_i64(&a[2], conn_end) || put_bytes(&a[3], &type, 1) ||
              put_i64(&a[4], (int64_t)nf);
        for (size_t k = 0, o = 0; k < nf && !bad; k++) {
            int32_t cnt = fs[o++];
            bad = put_i64(&a[4], cnt);
            for (int32_t j = 0; j < cnt && !bad; j++)
                bad = put_i64(&a[4], (int64_t)nv_all + fs[o++]);
        }
        bad = bad || put_i64(&a[5], (int64_t)(a[4].len / sizeof(int64_t))) ||
              put_bytes(&a[6], &fdt_voronoi_volumes(v)[i], sizeof(double)) ||
              put_i64(&a[7], (int64_t)i);
        if (bad)
            err = FDT_ENOMEM;
        nv_all += nv;
        ncells++;
    }
    if (!err) {
        static const char *const what[NARR] = {
            "<Points>\n        <DataArray type=\"Float64\" NumberOfComponents=\"3\"",
            "</Points>\n      <Cells>\n        <DataArray type=\"Int64\" Name=\"connectivity\"",
            "        <DataArray type=\"Int64\" Name=\"offsets\"",
            "        <DataArray type=\"UInt8\" Name=\"types\"",
            "        <DataArray type=\"Int64\" Name=\"faces\"",
            "        <DataArray type=\"Int64\" Name=\"faceoffsets\"",
            ("</Cells>\n      <CellData Scalars=\"volume\">\n" /* one element, two lines */
             "        <DataArray type=\"Float64\" Name=\"volume\""),
            "        <DataArray type=\"Int64\" Name=\"point\"",
        };
        uint16_t one = 1;
        unsigned char little;
        memcpy(&little, &one, 1);
        errno = 0;
        fprintf(f, "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
                   "byte_order=\"%s\" header_type=\"UInt64\">\n  <UnstructuredGrid>\n"
                   "    <Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">\n",
                little ? "LittleEndian" : "BigEndian", nv_all, ncells);
        uint64_t off = 0;
        for (int k = 0; k < NARR; k++) {
            const char *w = what[k];
            if (*w != ' ')
                fputs("      ", f);
            fprintf(f, "%s format=\"appended\" offset=\"%llu\"/>\n", w,
                    (unsigned long long)off);
            off += sizeof(uint64_t) + a[k].len;
        }
        fputs("      </CellData>\n    </Piece>\n  </UnstructuredGrid>\n"
              "  <AppendedData encoding=\"raw\">\n_", f);
        for (int k = 0; k < NARR; k++) {
            uint64_t len = a[k].len;
            fwrite(&len, sizeof len, 1, f);
            if (len)
                fwrite(a[k].p, 1, a[k].len, f);
        }
        fputs("\n  </AppendedData>\n</VTKFile>\n", f);
        if (ferror(f))
            err = errno ? errno : EIO;
    }
    for (int k = 0; k < NARR; k++)
        free(a[k].p);
    return err;
}
