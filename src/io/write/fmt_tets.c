/* The canonical .tets text (src/io/write/formats.h): one tet per line, its four ids
 * ascending, lines ascending; the bytes fdt_result_hash hashes. */
#include "io/write/formats.h"
#include "mesh/result.h"

static inline void sort4(fdt_vid s[4])
{
    /* A 5-comparator sorting network. */
#define FDT_CSWAP(i, j)                                                      \
    do {                                                                     \
        if (s[j] < s[i]) {                                                   \
            fdt_vid t_ = s[i];                                               \
            s[i] = s[j];                                                     \
            s[j] = t_;                                                       \
        }                                                                    \
    } while (0)
    FDT_CSWAP(0, 1);
    FDT_CSWAP(2, 3);
    FDT_CSWAP(0, 2);
    FDT_CSWAP(1, 3);
    FDT_CSWAP(1, 2);
#undef FDT_CSWAP
}

/* -1, 0, 1 as a < b, a == b, a > b (4-tuples). */
static inline int cmp4(const fdt_vid *a, const fdt_vid *b)
{
    for (int i = 0; i < 4; i++)
        if (a[i] != b[i])
            return a[i] < b[i] ? -1 : 1;
    return 0;
}

/* A periodic mesh's lines (src/mesh/result.h): rows already canonical
 * (ids ascending, offsets relative to the first, rows ascending). */
static int put_periodic(out_file *o, const fdt_mesh_view *m)
{
    for (size_t t = 0; t < m->n_tets; t++) {
        char *p = out_room(o, FDT_PERIODIC_ROW_MAX);
        o->len += fdt_periodic_row_text(p, (const uint32_t *)m->tets + 4 * t, m->tet_off + 12 * t);
    }
    return FDT_IO_OK;
}

int fdt_put_tets(out_file *o, const fdt_mesh_view *m, const void *prep, char *err,
                 size_t errlen)
{
    (void)prep;
    const char *path = o->path;
    if (m->tet_off)
        return put_periodic(o, m);

    fdt_vid prev[4] = { -1, -1, -1, -1 };
    char what[160];
    for (size_t t = 0; t < m->n_tets; t++) {
        fdt_vid s[4];
        memcpy(s, m->tets + 4 * t, sizeof s);
        sort4(s);
        /* Distinct ids within the tet and a strictly increasing line
         * order: what fdt_result_sort() guarantees. We check instead of
         * sorting so a caller who forgot to sort hears about it. */
        if (s[0] == s[1] || s[1] == s[2] || s[2] == s[3]) {
            snprintf(what, sizeof what, "tet %zu repeats vertex %ld", t,
                     (long)(s[0] == s[1] ? s[1] : s[1] == s[2] ? s[2] : s[3]));
            return set_err(err, errlen, FDT_IO_EFORMAT, path, what);
        }
        if (t > 0 && cmp4(prev, s) >= 0) {
            snprintf(what, sizeof what,
                     "tets are not in canonical order at tet %zu "
                     "(call fdt_result_sort first)", t);
            return set_err(err, errlen, FDT_IO_EFORMAT, path, what);
        }
        memcpy(prev, s, sizeof s);
        /* 4 ids of at most 10 digits, 3 spaces and a newline. */
        char *p = out_room(o, 48);
        size_t k = fdt_utoa(p, (uint64_t)s[0]);
        p[k++] = ' ';
        k += fdt_utoa(p + k, (uint64_t)s[1]);
        p[k++] = ' ';
        k += fdt_utoa(p + k, (uint64_t)s[2]);
        p[k++] = ' ';
        k += fdt_utoa(p + k, (uint64_t)s[3]);
        p[k++] = '\n';
        o->len += k;
    }
    return FDT_IO_OK;
}

