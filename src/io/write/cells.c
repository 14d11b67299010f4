/* The Voronoi cells as text: see cells.h. Written through the mesh
 * writers' buffer (outfile.h): one stdio call a megabyte, not a number. */
#include "io/write/cells.h"

#include <errno.h>
#include <string.h>

#include "io/write/outfile.h"

static const char codes[] = "ixyzqvFsnfcCdh%";

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

static void code(out_file *o, char c, const fdt_voronoi *v, const double *xyz, size_t i,
                 char sep)
{
    const double *p = xyz ? xyz + 3 * i : NULL; /* NULL: no code reads it */
    const double *cen = fdt_voronoi_centroids(v) + 3 * i;
    int merged = (fdt_voronoi_flags(v)[i] & FDT_CELL_MERGED) != 0;
    double rel[3];
    switch (c) {
    case 'i': out_i64(o, (int64_t)i); break;
    case 'x': out_double(o, p[0]); break;
    case 'y': out_double(o, p[1]); break;
    case 'z': out_double(o, p[2]); break;
    case 'q': three(o, p, sep); break;
    case 'v': out_double(o, fdt_voronoi_volumes(v)[i]); break;
    case 'F': out_double(o, fdt_voronoi_areas(v)[i]); break;
    case 's': out_i64(o, fdt_voronoi_num_faces(v)[i]); break;
    case 'n': list(o, v, i, 0); break;
    case 'f': list(o, v, i, 1); break;
    case 'c':
        for (int k = 0; k < 3; k++)
            rel[k] = merged ? 0 : cen[k] - p[k];
        three(o, rel, sep);
        break;
    case 'C': three(o, merged ? p : cen, sep); break;
    case 'd': out_double(o, fdt_voronoi_densities(v)[i]); break;
    case 'h': out_i64(o, fdt_voronoi_flags(v)[i]); break;
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

/* The rows through a buffer on f; 0 or the errno of the first failure. */
static int put_rows(FILE *f, const char *fmt, const fdt_voronoi *v, const double *xyz, int csv)
{
    out_file o;
    if (open_out(&o, f))
        return ENOMEM;
    size_t n = fdt_voronoi_num_points(v);
    if (csv)
        out_str(&o, "id,x,y,z,volume,area,faces,cx,cy,cz,density,flags\n");
    for (size_t i = 0; i < n && !o.err; i++) {
        for (const char *p = fmt; *p; p++) {
            if (csv && p != fmt)
                out_char(&o, ',');
            if (csv)
                code(&o, *p, v, xyz, i, ',');
            else if (*p != '%')
                out_char(&o, *p);
            else
                code(&o, *++p, v, xyz, i, ' ');
        }
        out_char(&o, '\n');
    }
    return close_out(&o);
}

int fdt_wr_cells(FILE *f, const char *fmt, const fdt_voronoi *v, const double *xyz)
{
    /* CSV: the table's columns, each a code */
    return fmt ? put_rows(f, fmt, v, xyz, 0) : put_rows(f, "iqvFsCdh", v, xyz, 1);
}

int fdt_wr_density(FILE *f, const fdt_voronoi *v)
{
    return put_rows(f, "%d %h", v, NULL, 0);
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
