/* The Voronoi cells as text: see cells.h. */
#include "io/write/cells.h"

#include <errno.h>
#include <string.h>

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

static void num(FILE *f, double x)
{
    fprintf(f, "%.17g", x);
}

/* Point i's neighbours (%n) or face areas (%f), space separated. */
static void list(FILE *f, const fdt_voronoi *v, size_t i, int areas)
{
    size_t cnt = 0;
    const fdt_vid *ids;
    const double *fa;
    if (fdt_voronoi_neighbors(v, (fdt_vid)i, &cnt, &ids, &fa) != FDT_OK)
        return;
    for (size_t e = 0; e < cnt; e++) {
        if (e)
            fputc(' ', f);
        if (areas)
            num(f, fa[e]);
        else
            fprintf(f, "%d", (int)ids[e]);
    }
}

static void code(FILE *f, char c, const fdt_voronoi *v, const double *xyz, size_t i)
{
    const double *p = xyz + 3 * i, *cen = fdt_voronoi_centroids(v) + 3 * i;
    int merged = (fdt_voronoi_flags(v)[i] & FDT_CELL_MERGED) != 0;
    switch (c) {
    case 'i': fprintf(f, "%zu", i); break;
    case 'x': num(f, p[0]); break;
    case 'y': num(f, p[1]); break;
    case 'z': num(f, p[2]); break;
    case 'q': num(f, p[0]); fputc(' ', f); num(f, p[1]); fputc(' ', f); num(f, p[2]); break;
    case 'v': num(f, fdt_voronoi_volumes(v)[i]); break;
    case 'F': num(f, fdt_voronoi_areas(v)[i]); break;
    case 's': fprintf(f, "%d", (int)fdt_voronoi_num_faces(v)[i]); break;
    case 'n': list(f, v, i, 0); break;
    case 'f': list(f, v, i, 1); break;
    case 'c':
        for (int k = 0; k < 3; k++) {
            if (k)
                fputc(' ', f);
            num(f, merged ? 0 : cen[k] - p[k]);
        }
        break;
    case 'C':
        for (int k = 0; k < 3; k++) {
            if (k)
                fputc(' ', f);
            num(f, merged ? p[k] : cen[k]);
        }
        break;
    case 'd': num(f, fdt_voronoi_densities(v)[i]); break;
    case 'h': fprintf(f, "%d", (int)fdt_voronoi_flags(v)[i]); break;
    default: fputc('%', f); break;
    }
}

static int status(FILE *f)
{
    return ferror(f) ? (errno ? errno : EIO) : 0;
}

int fdt_wr_cells(FILE *f, const char *fmt, const fdt_voronoi *v, const double *xyz)
{
    size_t n = fdt_voronoi_num_points(v);
    errno = 0;
    if (!fmt) {
        fputs("id,x,y,z,volume,area,faces,cx,cy,cz,density,flags\n", f);
        static const char row[] = "ixyzvFsCdh";
        for (size_t i = 0; i < n && !ferror(f); i++) {
            for (const char *c = row; *c; c++) {
                if (c != row)
                    fputc(',', f);
                if (*c == 'C')
                    for (int k = 0; k < 3; k++) {
                        if (k)
                            fputc(',', f);
                        num(f, fdt_voronoi_centroids(v)[3 * i + (size_t)k]);
                    }
                else
                    code(f, *c, v, xyz, i);
            }
            fputc('\n', f);
        }
        return status(f);
    }
    for (size_t i = 0; i < n && !ferror(f); i++) {
        for (const char *p = fmt; *p; p++) {
            if (*p != '%')
                fputc(*p, f);
            else
                code(f, *++p, v, xyz, i);
        }
        fputc('\n', f);
    }
    return status(f);
}

int fdt_wr_density(FILE *f, const fdt_voronoi *v)
{
    size_t n = fdt_voronoi_num_points(v);
    errno = 0;
    for (size_t i = 0; i < n && !ferror(f); i++) {
        num(f, fdt_voronoi_densities(v)[i]);
        fprintf(f, " %d\n", (int)fdt_voronoi_flags(v)[i]);
    }
    return status(f);
}
