/* The canonical .tets text (src/io/write/formats.h): one tet per line, its four ids
 * ascending, lines ascending; the bytes fdt_result_hash hashes. */
#include "io/write/formats.h"

#include <errno.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>

#include "io/write/cells.h"
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


/*
 * A periodic run's rows streamed (FDT_STREAM_PERIODIC): a row is a tet's
 * 4 ids and 12 offsets, canonical, and a batch's rows come ascending
 * (include/frontdt.h, fdt_sink), batches in any order. Each goes to the
 * spool as a 28-byte record; a record below the one before starts a new
 * run. At the end the runs are merged (a heap of cursors, each reading its
 * run through a buffer) into the canonical text: the bytes fdt_put_tets
 * writes for the same mesh held in memory.
 */
enum { ROW_BYTES = 28 };

/* A row's order as the mesh's (src/mesh/periodic.c's packed vertices):
 * each vertex's id, then its three offsets, vertex after vertex. */
static void row_key(const uint8_t *rec, uint64_t k[4])
{
    for (int j = 0; j < 4; j++) {
        uint32_t id;
        memcpy(&id, rec + 4 * j, 4);
        const int8_t *o = (const int8_t *)rec + 16 + 3 * j;
        k[j] = (uint64_t)id << 24 | (uint64_t)(uint8_t)(o[0] + 128) << 16 |
               (uint64_t)(uint8_t)(o[1] + 128) << 8 | (uint64_t)(uint8_t)(o[2] + 128);
    }
}

static int key_less(const uint64_t a[4], const uint64_t b[4])
{
    for (int j = 0; j < 4; j++)
        if (a[j] != b[j])
            return a[j] < b[j];
    return 0;
}

static int tets_begin(fdt_stream_out *s, char *err, size_t errlen)
{
    char dir[FDT_IO_PATH];
    fdt_cells_dir(s->files[0].path, dir, sizeof dir);
    if (!(s->spool = fdt_cells_temp(dir)))
        return set_errno_err(err, errlen, s->files[0].path, errno);
    return FDT_IO_OK;
}

static void tets_periodic(fdt_stream_out *s, const fdt_vid *t, const int8_t *off, size_t count)
{
    for (size_t i = 0; i < count && !s->files[0].err; i++) {
        uint8_t rec[ROW_BYTES];
        for (int j = 0; j < 4; j++) {
            uint32_t id = (uint32_t)t[4 * i + (size_t)j];
            memcpy(rec + 4 * j, &id, 4);
        }
        memcpy(rec + 16, off + 12 * i, 12);
        uint64_t k[4];
        row_key(rec, k);
        if (s->n_tets + i == 0 || key_less(k, s->last)) {
            if (s->nruns == s->runs_cap) {
                size_t cap = s->runs_cap ? 2 * s->runs_cap : 64;
                uint64_t *r = realloc(s->runs, cap * sizeof *r);
                if (!r) {
                    out_fail(&s->files[0], ENOMEM);
                    return;
                }
                s->runs = r;
                s->runs_cap = cap;
            }
            s->runs[s->nruns++] = s->n_tets + i;
        }
        memcpy(s->last, k, sizeof k);
        if (fwrite(rec, ROW_BYTES, 1, s->spool) != 1)
            out_fail(&s->files[0], errno);
    }
}

/* A run's cursor: its next record, and what is left in the spool. */
typedef struct cursor {
    uint64_t key[4];
    uint64_t next, end; /* records */
    uint8_t *buf;
    size_t at, have;    /* records in buf */
} cursor;

static int cursor_load(FILE *f, cursor *c, size_t cap)
{
    if (c->at == c->have) {
        size_t want = c->end - c->next < cap ? (size_t)(c->end - c->next) : cap;
        if (fseeko(f, (off_t)(c->next * ROW_BYTES), SEEK_SET) != 0 ||
            fread(c->buf, ROW_BYTES, want, f) != want)
            return errno ? errno : EIO;
        c->next += want;
        c->at = 0;
        c->have = want;
    }
    row_key(c->buf + c->at * ROW_BYTES, c->key);
    return 0;
}

static int heap_less(cursor *const *h, size_t a, size_t b)
{
    return key_less(h[a]->key, h[b]->key);
}

static void heap_down(cursor **h, size_t n, size_t i)
{
    for (;;) {
        size_t l = 2 * i + 1, m = i;
        if (l < n && heap_less(h, l, m))
            m = l;
        if (l + 1 < n && heap_less(h, l + 1, m))
            m = l + 1;
        if (m == i)
            return;
        cursor *t = h[i];
        h[i] = h[m];
        h[m] = t;
        i = m;
    }
}

static int tets_finish(fdt_stream_out *s, char *err, size_t errlen)
{
    out_file *o = &s->files[0];
    size_t k = s->nruns;
    int e = o->err;
    cursor *c = calloc(k ? k : 1, sizeof *c);
    cursor **h = malloc((k ? k : 1) * sizeof *h);
    /* the buffers: 64 MB in all, at least 4 KB a run */
    size_t cap = k ? (64u << 20) / ROW_BYTES / k : 1;
    cap = cap < 4096 / ROW_BYTES ? 4096 / ROW_BYTES : cap;
    if (!c || !h)
        e = ENOMEM;
    else if (fflush(s->spool) != 0)
        e = errno;
    size_t live = 0;
    for (size_t i = 0; i < k && !e; i++) {
        c[i].next = s->runs[i];
        c[i].end = i + 1 < k ? s->runs[i + 1] : s->n_tets;
        if (!(c[i].buf = malloc(cap * ROW_BYTES)))
            e = ENOMEM;
        else if (!(e = cursor_load(s->spool, &c[i], cap)))
            h[live++] = &c[i];
    }
    for (size_t i = live / 2; i-- > 0;)
        heap_down(h, live, i);
    while (live && !e && !o->err) {
        cursor *t = h[0];
        const uint8_t *rec = t->buf + t->at * ROW_BYTES;
        uint32_t id[4];
        memcpy(id, rec, 16);
        char *p = out_room(o, FDT_PERIODIC_ROW_MAX);
        o->len += fdt_periodic_row_text(p, id, (const int8_t *)rec + 16);
        if (++t->at == t->have && t->next == t->end)
            h[0] = h[--live];
        else
            e = cursor_load(s->spool, t, cap);
        heap_down(h, live, 0);
    }
    for (size_t i = 0; i < k && c; i++)
        free(c[i].buf);
    free(c);
    free(h);
    fclose(s->spool);
    s->spool = NULL;
    free(s->runs);
    s->runs = NULL;
    return e ? set_errno_err(err, errlen, o->path, e) : FDT_IO_OK;
}

const fdt_stream_fmt fdt_stream_tets = {1, tets_begin, NULL, NULL, tets_finish, tets_periodic};
