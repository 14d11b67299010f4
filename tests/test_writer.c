/*
 * Tests for src/io/write/writer.c: a hand-made mesh (a cube cut into 5 tets, plus
 * an unused duplicate point) written in every format and parsed back here;
 * a large synthetic mesh that crosses the writer's buffer many times;
 * decimal formatting of large ids; refusal of non-canonical .tets; write
 * failures (missing directory, a regular file as directory, read-only
 * directory, target is a directory, file size limit, failing rename in a
 * TetGen set) that must return FDT_IO_EWRITE and leave no temporary file
 * and no partial output; the file set of each output family
 * (fdt_output_files) and file identity by any name (fdt_same_file), which
 * the CLI uses to refuse an output that would overwrite its input.
 * The side files (fdt_wr_side_*), a mesh whose arrays are missing, a
 * polyMesh over a regular file, and text written to a stream that fails
 * (/dev/full) or is refused (binary formats): each refused with its code
 * and a message naming the file, nothing left behind. Commit sets: the
 * outputs of one run renamed together or not at all.
 * src/io/write/outfile.h's buffer on its own, over pipes, where a seek or a pwrite
 * fails (ESPIPE) and a write fails in stdio's flush or in ours (EPIPE,
 * the reader gone): the first errno is kept, nothing more is written, and
 * the text items (integers of either sign, doubles, counts padded to a
 * width) come out as the readers expect them.
 */
#include "io/write/outfile.h"
#include "io/read/reader.h"
#include "io/write/writer.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>
#include "testdir.h"
#include "testutil.h"


/* ------------------------------------------------------------------------ */
/* Helpers                                                                   */
/* ------------------------------------------------------------------------ */

static int file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

static void remove_tree_files(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d)
        return;
    struct dirent *e;
    char p[4096];
    while ((e = readdir(d)) != NULL) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
            continue;
        snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
        struct stat st;
        if (lstat(p, &st) == 0 && S_ISDIR(st.st_mode)) {
            chmod(p, 0755);
            remove_tree_files(p);
            rmdir(p);
        } else {
            unlink(p);
        }
    }
    closedir(d);
}

/* Whitespace-separated token reader over a NUL-terminated buffer. */
typedef struct toks {
    const char *p;
} toks;

static int next_i64(toks *t, long long *v)
{
    char *end;
    errno = 0;
    *v = strtoll(t->p, &end, 10);
    if (end == t->p || errno)
        return 0;
    t->p = end;
    return 1;
}

static int next_double(toks *t, double *v)
{
    char *end;
    *v = strtod(t->p, &end);
    if (end == t->p)
        return 0;
    t->p = end;
    return 1;
}

static int next_word(toks *t, const char *w)
{
    while (*t->p == ' ' || *t->p == '\n' || *t->p == '\t')
        t->p++;
    size_t n = strlen(w);
    if (strncmp(t->p, w, n) != 0)
        return 0;
    t->p += n;
    return 1;
}

static int at_end(toks *t)
{
    while (*t->p == ' ' || *t->p == '\n' || *t->p == '\t')
        t->p++;
    return *t->p == '\0';
}

/* ------------------------------------------------------------------------ */
/* The hand-made mesh                                                        */
/* ------------------------------------------------------------------------ */

#define NP 9
#define NT 5
#define NH 12

typedef struct mesh {
    double xyz[3 * NP];
    fdt_vid tets[4 * NT];
    fdt_tid nbrs[4 * NT];
    fdt_vid hull[3 * NH];
    size_t n_hull;
} mesh;

static double det3(const double *a, const double *b, const double *c,
                   const double *d)
{
    double u[3], v[3], w[3];
    for (int i = 0; i < 3; i++) {
        u[i] = b[i] - a[i];
        v[i] = c[i] - a[i];
        w[i] = d[i] - a[i];
    }
    return u[0] * (v[1] * w[2] - v[2] * w[1]) -
           u[1] * (v[0] * w[2] - v[2] * w[0]) +
           u[2] * (v[0] * w[1] - v[1] * w[0]);
}

static void sorted4(const fdt_vid *t, fdt_vid s[4])
{
    memcpy(s, t, 4 * sizeof *s);
    for (int i = 1; i < 4; i++)
        for (int j = i; j > 0 && s[j] < s[j - 1]; j--) {
            fdt_vid x = s[j];
            s[j] = s[j - 1];
            s[j - 1] = x;
        }
}

static int cmp_tet(const void *a, const void *b)
{
    fdt_vid s[4], r[4];
    sorted4(a, s);
    sorted4(b, r);
    for (int i = 0; i < 4; i++)
        if (s[i] != r[i])
            return s[i] < r[i] ? -1 : 1;
    return 0;
}

/* The three vertices of t other than t[i], sorted. */
static void face_sorted(const fdt_vid *t, int i, fdt_vid f[3])
{
    int k = 0;
    for (int j = 0; j < 4; j++)
        if (j != i)
            f[k++] = t[j];
    for (int a = 1; a < 3; a++)
        for (int b = a; b > 0 && f[b] < f[b - 1]; b--) {
            fdt_vid x = f[b];
            f[b] = f[b - 1];
            f[b - 1] = x;
        }
}

/*
 * A box with corners v = x + 2y + 4z cut into 5 tets: the four corners of
 * odd parity (1, 2, 4, 7) each cut off by its three even neighbours, and
 * the central tet (0, 3, 5, 6). Point 8 duplicates point 0 and is unused.
 * Coordinates are chosen so that %.17g must carry all digits.
 */
static void make_mesh(mesh *m)
{
    const double lo[3] = { -0.1, 1.0 / 3.0, -2.5e-7 };
    const double hi[3] = { 2.0 / 7.0, 12345.678901234567, 1e10 };
    for (int v = 0; v < 8; v++) {
        m->xyz[3 * v] = (v & 1) ? hi[0] : lo[0];
        m->xyz[3 * v + 1] = (v & 2) ? hi[1] : lo[1];
        m->xyz[3 * v + 2] = (v & 4) ? hi[2] : lo[2];
    }
    memcpy(m->xyz + 24, m->xyz, 3 * sizeof(double));
    const fdt_vid raw[NT][4] = {
        { 7, 3, 5, 6 }, { 0, 3, 5, 6 }, { 4, 0, 5, 6 },
        { 1, 0, 3, 5 }, { 2, 0, 3, 6 },
    };
    memcpy(m->tets, raw, sizeof raw);
    for (int t = 0; t < NT; t++) {
        fdt_vid *q = m->tets + 4 * t;
        if (det3(m->xyz + 3 * q[0], m->xyz + 3 * q[1], m->xyz + 3 * q[2],
                 m->xyz + 3 * q[3]) < 0) {
            fdt_vid x = q[2];
            q[2] = q[3];
            q[3] = x;
        }
    }
    qsort(m->tets, NT, 4 * sizeof(fdt_vid), cmp_tet);
    m->n_hull = 0;
    for (int t = 0; t < NT; t++) {
        for (int i = 0; i < 4; i++) {
            fdt_vid f[3], g[3];
            face_sorted(m->tets + 4 * t, i, f);
            m->nbrs[4 * t + i] = -1;
            for (int u = 0; u < NT; u++)
                for (int j = 0; j < 4 && u != t; j++) {
                    face_sorted(m->tets + 4 * u, j, g);
                    if (!memcmp(f, g, sizeof f))
                        m->nbrs[4 * t + i] = u;
                }
            if (m->nbrs[4 * t + i] >= 0)
                continue;
            /* Hull face, outward: the opposite vertex on its negative
             * side. */
            fdt_vid *h = m->hull + 3 * m->n_hull++;
            memcpy(h, f, sizeof f);
            const double *o = m->xyz + 3 * m->tets[4 * t + i];
            if (det3(m->xyz + 3 * h[0], m->xyz + 3 * h[1], m->xyz + 3 * h[2],
                     o) > 0) {
                fdt_vid x = h[1];
                h[1] = h[2];
                h[2] = x;
            }
        }
    }
}

static fdt_mesh_view view_of(const mesh *m)
{
    fdt_mesh_view v = {
        .xyz = m->xyz, .n_points = NP, .tets = m->tets, .n_tets = NT,
        .nbrs = m->nbrs, .hull = m->hull, .n_hull = m->n_hull,
    };
    return v;
}

/* The canonical text, built independently with snprintf. */
static char *canonical_text(const fdt_vid *tets, size_t nt)
{
    size_t cap = nt * 48 + 1, len = 0;
    char *s = malloc(cap);
    s[0] = '\0';
    for (size_t t = 0; t < nt; t++) {
        fdt_vid q[4];
        sorted4(tets + 4 * t, q);
        len += (size_t)snprintf(s + len, cap - len, "%d %d %d %d\n",
                                (int)q[0], (int)q[1], (int)q[2], (int)q[3]);
    }
    return s;
}

/* ------------------------------------------------------------------------ */
/* Format checks                                                             */
/* ------------------------------------------------------------------------ */

static void check_tets_file(const char *path, const fdt_vid *tets, size_t nt)
{
    size_t len;
    char *got = test_slurp(path, &len);
    char *want = canonical_text(tets, nt);
    EXPECT(got != NULL);
    if (got) {
        EXPECT(len == strlen(want));
        EXPECT(strcmp(got, want) == 0);
    }
    free(got);
    free(want);
}

static void check_node_file(const char *path, const double *xyz, size_t n)
{
    size_t len;
    char *s = test_slurp(path, &len);
    EXPECT(s != NULL);
    if (!s)
        return;
    toks t = { s };
    long long a, b, c, d;
    EXPECT(next_i64(&t, &a) && a == (long long)n);
    EXPECT(next_i64(&t, &b) && b == 3);
    EXPECT(next_i64(&t, &c) && c == 0);
    EXPECT(next_i64(&t, &d) && d == 0);
    for (size_t i = 0; i < n; i++) {
        long long idx;
        EXPECT(next_i64(&t, &idx) && idx == (long long)i);
        for (int k = 0; k < 3; k++) {
            double x;
            EXPECT(next_double(&t, &x));
            /* Bit-exact round trip through %.17g. */
            EXPECT(memcmp(&x, &xyz[3 * i + (size_t)k], sizeof x) == 0);
        }
    }
    EXPECT(at_end(&t));
    free(s);
}

/* Header h0 h1 [h2], then n rows "index v0 .. v(k-1)" equal to want. */
static void check_table_file(const char *path, const long long *hdr,
                             int nhdr, size_t rows, int k,
                             const fdt_vid *want32, const fdt_tid *want64)
{
    size_t len;
    char *s = test_slurp(path, &len);
    EXPECT(s != NULL);
    if (!s)
        return;
    toks t = { s };
    for (int i = 0; i < nhdr; i++) {
        long long v;
        EXPECT(next_i64(&t, &v) && v == hdr[i]);
    }
    for (size_t r = 0; r < rows; r++) {
        long long idx;
        EXPECT(next_i64(&t, &idx) && idx == (long long)r);
        for (int c = 0; c < k; c++) {
            long long v;
            long long w = want32 ? (long long)want32[r * (size_t)k + (size_t)c]
                                 : (long long)want64[r * (size_t)k + (size_t)c];
            EXPECT(next_i64(&t, &v) && v == w);
        }
    }
    EXPECT(at_end(&t));
    free(s);
}

static void check_vtk_file(const char *path, const double *xyz, size_t n,
                           const fdt_vid *tets, size_t nt)
{
    size_t len;
    char *s = test_slurp(path, &len);
    EXPECT(s != NULL);
    if (!s)
        return;
    EXPECT(strncmp(s, "# vtk DataFile Version 3.0\n", 27) == 0);
    const char *p = strstr(s, "\nASCII\nDATASET UNSTRUCTURED_GRID\n");
    EXPECT(p != NULL);
    toks t = { p ? p : s };
    EXPECT(next_word(&t, "ASCII"));
    EXPECT(next_word(&t, "DATASET UNSTRUCTURED_GRID"));
    EXPECT(next_word(&t, "POINTS"));
    long long v;
    EXPECT(next_i64(&t, &v) && v == (long long)n);
    EXPECT(next_word(&t, "double"));
    for (size_t i = 0; i < 3 * n; i++) {
        double x;
        EXPECT(next_double(&t, &x) && memcmp(&x, &xyz[i], sizeof x) == 0);
    }
    EXPECT(next_word(&t, "CELLS"));
    EXPECT(next_i64(&t, &v) && v == (long long)nt);
    EXPECT(next_i64(&t, &v) && v == 5 * (long long)nt);
    for (size_t c = 0; c < nt; c++) {
        EXPECT(next_i64(&t, &v) && v == 4);
        for (int k = 0; k < 4; k++)
            EXPECT(next_i64(&t, &v) && v == tets[4 * c + (size_t)k]);
    }
    EXPECT(next_word(&t, "CELL_TYPES"));
    EXPECT(next_i64(&t, &v) && v == (long long)nt);
    for (size_t c = 0; c < nt; c++)
        EXPECT(next_i64(&t, &v) && v == 10);
    EXPECT(at_end(&t));
    free(s);
}

static long long attr_offset(const char *s, const char *name)
{
    char key[128];
    snprintf(key, sizeof key, "Name=\"%s\"", name);
    const char *p = strstr(s, key);
    if (!p)
        return -1;
    p = strstr(p, "offset=\"");
    if (!p)
        return -1;
    return strtoll(p + 8, NULL, 10);
}

static void check_vtu_file(const char *path, const double *xyz, size_t n,
                           const fdt_vid *tets, size_t nt)
{
    size_t len;
    char *s = test_slurp(path, &len);
    EXPECT(s != NULL);
    if (!s)
        return;
    const uint16_t one = 1;
    unsigned char lb;
    memcpy(&lb, &one, 1);
    EXPECT(strstr(s, lb == 1 ? "byte_order=\"LittleEndian\""
                            : "byte_order=\"BigEndian\"") != NULL);
    EXPECT(strstr(s, "header_type=\"UInt64\"") != NULL);
    EXPECT(strstr(s, "version=\"0.1\"") != NULL);
    char piece[128];
    snprintf(piece, sizeof piece, "NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\"",
             n, nt);
    EXPECT(strstr(s, piece) != NULL);
    const char *ad = strstr(s, "<AppendedData encoding=\"raw\">");
    EXPECT(ad != NULL);
    if (!ad) {
        free(s);
        return;
    }
    const char *us = strchr(ad, '_');
    EXPECT(us != NULL);
    const unsigned char *base = (const unsigned char *)us + 1;
    size_t avail = len - (size_t)((const char *)base - s);

    long long o_pts = attr_offset(s, "Points");
    long long o_con = attr_offset(s, "connectivity");
    long long o_off = attr_offset(s, "offsets");
    long long o_typ = attr_offset(s, "types");
    EXPECT(o_pts == 0);
    uint64_t sz;
    /* Points */
    EXPECT((size_t)o_con <= avail);
    memcpy(&sz, base + o_pts, 8);
    EXPECT(sz == 3 * n * sizeof(double));
    EXPECT(memcmp(base + o_pts + 8, xyz, 3 * n * sizeof(double)) == 0);
    EXPECT(o_con == o_pts + 8 + (long long)sz);
    /* connectivity */
    memcpy(&sz, base + o_con, 8);
    EXPECT(sz == 4 * nt * 8);
    EXPECT(o_off == o_con + 8 + (long long)sz);
    EXPECT((size_t)o_off <= avail);
    for (size_t i = 0; i < 4 * nt && (size_t)o_off <= avail; i++) {
        int64_t v;
        memcpy(&v, base + o_con + 8 + 8 * i, 8);
        if (v != tets[i]) {
            EXPECT(v == tets[i]);
            break;
        }
    }
    /* offsets */
    memcpy(&sz, base + o_off, 8);
    EXPECT(sz == nt * 8);
    EXPECT(o_typ == o_off + 8 + (long long)sz);
    EXPECT((size_t)o_typ + 8 + nt <= avail);
    for (size_t i = 0; i < nt && (size_t)o_typ <= avail; i++) {
        int64_t v;
        memcpy(&v, base + o_off + 8 + 8 * i, 8);
        if (v != 4 * (int64_t)(i + 1)) {
            EXPECT(v == 4 * (int64_t)(i + 1));
            break;
        }
    }
    /* types */
    if ((size_t)o_typ + 8 + nt <= avail) {
        memcpy(&sz, base + o_typ, 8);
        EXPECT(sz == nt);
        for (size_t i = 0; i < nt; i++)
            if (base[o_typ + 8 + (long long)i] != 10) {
                EXPECT(base[o_typ + 8 + (long long)i] == 10);
                break;
            }
        const char *tail = (const char *)base + o_typ + 8 + nt;
        EXPECT(strstr(tail, "</AppendedData>") != NULL);
        EXPECT(strstr(tail, "</VTKFile>") != NULL);
    }
    free(s);
}

static void check_tetgen_set(const char *dir, const char *base,
                             const fdt_mesh_view *v)
{
    char p[4096];
    snprintf(p, sizeof p, "%s/%s.node", dir, base);
    check_node_file(p, v->xyz, v->n_points);
    snprintf(p, sizeof p, "%s/%s.ele", dir, base);
    long long he[3] = { (long long)v->n_tets, 4, 0 };
    check_table_file(p, he, 3, v->n_tets, 4, v->tets, NULL);
    snprintf(p, sizeof p, "%s/%s.face", dir, base);
    long long hf[2] = { (long long)v->n_hull, 0 };
    check_table_file(p, hf, 2, v->n_hull, 3, v->hull, NULL);
    snprintf(p, sizeof p, "%s/%s.neigh", dir, base);
    long long hn[2] = { (long long)v->n_tets, 4 };
    check_table_file(p, hn, 2, v->n_tets, 4, NULL, v->nbrs);
}

/* ------------------------------------------------------------------------ */
/* Tests                                                                     */
/* ------------------------------------------------------------------------ */

static void test_small_mesh(const char *dir)
{
    mesh m;
    make_mesh(&m);
    EXPECT(m.n_hull == NH);
    /* The central tet touches the other four, each corner tet has three
     * hull faces. */
    int interior = 0;
    for (int i = 0; i < 4 * NT; i++)
        interior += m.nbrs[i] >= 0;
    EXPECT(interior == 8);
    fdt_mesh_view v = view_of(&m);
    char p[4096], err[512];

    snprintf(p, sizeof p, "%s/cube.tets", dir);
    EXPECT(fdt_wr_mesh(p, &v, err, sizeof err) == FDT_IO_OK);
    check_tets_file(p, m.tets, NT);

    snprintf(p, sizeof p, "%s/cube.ele", dir);
    EXPECT(fdt_wr_mesh(p, &v, err, sizeof err) == FDT_IO_OK);
    check_tetgen_set(dir, "cube", &v);

    snprintf(p, sizeof p, "%s/cube.vtk", dir);
    EXPECT(fdt_wr_mesh(p, &v, err, sizeof err) == FDT_IO_OK);
    check_vtk_file(p, m.xyz, NP, m.tets, NT);

    snprintf(p, sizeof p, "%s/cube.vtu", dir);
    EXPECT(fdt_wr_mesh(p, &v, err, sizeof err) == FDT_IO_OK);
    check_vtu_file(p, m.xyz, NP, m.tets, NT);

    /* Upper-case extensions are recognised; the TetGen companions get the
     * lower-case extensions, the .ele keeps the caller's spelling. */
    snprintf(p, sizeof p, "%s/upper.ELE", dir);
    EXPECT(fdt_wr_mesh(p, &v, err, sizeof err) == FDT_IO_OK);
    snprintf(p, sizeof p, "%s/upper.node", dir);
    EXPECT(file_exists(p));
    snprintf(p, sizeof p, "%s/upper.ELE", dir);
    EXPECT(file_exists(p));

    EXPECT(count_temps(dir) == 0);
    /* cube.tets, 4 TetGen files, .vtk, .vtu, 4 upper.* files */
    EXPECT(count_entries(dir) == 11);

    /* Overwriting replaces the content and gives 0666 & ~umask. */
    mode_t old = umask(022);
    snprintf(p, sizeof p, "%s/cube.tets", dir);
    FILE *f = fopen(p, "w");
    fputs("stale\n", f);
    fclose(f);
    chmod(p, 0600);
    EXPECT(fdt_wr_mesh(p, &v, err, sizeof err) == FDT_IO_OK);
    check_tets_file(p, m.tets, NT);
    struct stat st;
    EXPECT(stat(p, &st) == 0 && (st.st_mode & 0777) == 0644);
    umask(old);
}

/* Every refusal leaves the directory as it was. */
static void expect_fail(const char *dir, const char *path,
                        const fdt_mesh_view *v, int code, const char *msg)
{
    char err[512] = "untouched";
    int before = count_entries(dir);
    int r = fdt_wr_mesh(path, v, err, sizeof err);
    if (r != code || !strstr(err, msg))
        fprintf(stderr, "  %s: got %d \"%s\", want %d \"%s\"\n", path, r, err,
                code, msg);
    EXPECT(r == code);
    EXPECT(strstr(err, msg) != NULL);
    EXPECT(count_temps(dir) == 0);
    EXPECT(count_entries(dir) == before);
}

static void test_refusals(const char *dir)
{
    mesh m;
    make_mesh(&m);
    fdt_mesh_view v = view_of(&m);
    char p[4096], q[8192];

    /* Non-canonical order: swapped lines, a repeated line, a repeated id. */
    mesh bad = m;
    memcpy(bad.tets, m.tets + 4, 4 * sizeof(fdt_vid));
    memcpy(bad.tets + 4, m.tets, 4 * sizeof(fdt_vid));
    fdt_mesh_view bv = view_of(&bad);
    snprintf(p, sizeof p, "%s/order.tets", dir);
    expect_fail(dir, p, &bv, FDT_IO_EFORMAT, "canonical order at tet 1");
    bad = m;
    memcpy(bad.tets + 8, bad.tets + 4, 4 * sizeof(fdt_vid));
    bv = view_of(&bad);
    expect_fail(dir, p, &bv, FDT_IO_EFORMAT, "canonical order at tet 2");
    bad = m;
    bad.tets[4 * 4 + 1] = bad.tets[4 * 4 + 2];
    bv = view_of(&bad);
    expect_fail(dir, p, &bv, FDT_IO_EFORMAT, "tet 4 repeats vertex");
    /* Reversed order is refused too, although each line is fine. */
    bad = m;
    for (int t = 0; t < NT; t++)
        memcpy(bad.tets + 4 * t, m.tets + 4 * (NT - 1 - t),
               4 * sizeof(fdt_vid));
    bv = view_of(&bad);
    expect_fail(dir, p, &bv, FDT_IO_EFORMAT, "canonical order at tet 1");

    /* Ids out of range, for every format. */
    bad = m;
    bad.tets[7] = NP;
    bv = view_of(&bad);
    snprintf(p, sizeof p, "%s/range.vtu", dir);
    expect_fail(dir, p, &bv, FDT_IO_EFORMAT, "tet 1 uses vertex 9");
    bad = m;
    bad.hull[5] = -1;
    bv = view_of(&bad);
    snprintf(p, sizeof p, "%s/range.vtk", dir);
    expect_fail(dir, p, &bv, FDT_IO_EFORMAT, "hull face 1 uses vertex -1");
    bad = m;
    bad.nbrs[3] = NT;
    bv = view_of(&bad);
    snprintf(p, sizeof p, "%s/range.ele", dir);
    expect_fail(dir, p, &bv, FDT_IO_EFORMAT, "tet 0 has neighbour 5");

    /* The other end of each range, and missing arrays. */
    bad = m;
    bad.tets[2] = -1;
    bv = view_of(&bad);
    expect_fail(dir, p, &bv, FDT_IO_EFORMAT, "tet 0 uses vertex -1");
    bad = m;
    bad.hull[3] = NP;
    bv = view_of(&bad);
    expect_fail(dir, p, &bv, FDT_IO_EFORMAT, "hull face 1 uses vertex 9");
    bad = m;
    bad.nbrs[6] = -2;
    bv = view_of(&bad);
    expect_fail(dir, p, &bv, FDT_IO_EFORMAT, "tet 1 has neighbour -2");
    for (int k = 0; k < 3; k++) {
        fdt_mesh_view mv = v;
        if (k == 0)
            mv.tets = NULL;
        else if (k == 1)
            mv.hull = NULL;
        else
            mv.xyz = NULL;
        snprintf(p, sizeof p, "%s/missing%d.vtu", dir, k);
        expect_fail(dir, p, &mv, FDT_IO_EFORMAT, "mesh arrays missing");
    }
    /* A repeated id in each position of the sorted tet is named. */
    snprintf(p, sizeof p, "%s/order.tets", dir);
    for (int k = 0; k < 3; k++) {
        bad = m;
        fdt_vid s4[4];
        memcpy(s4, m.tets + 4 * 4, sizeof s4);
        /* the tet's ids in ascending order, then two made equal */
        for (int a = 1; a < 4; a++)
            for (int b = a; b > 0 && s4[b - 1] > s4[b]; b--) {
                fdt_vid x = s4[b];
                s4[b] = s4[b - 1];
                s4[b - 1] = x;
            }
        s4[k + 1] = s4[k];
        memcpy(bad.tets + 4 * 4, s4, sizeof s4);
        bv = view_of(&bad);
        char want[64];
        snprintf(want, sizeof want, "tet 4 repeats vertex %ld", (long)s4[k]);
        expect_fail(dir, p, &bv, FDT_IO_EFORMAT, want);
    }

    /* .ele without neighbours. */
    fdt_mesh_view nv = v;
    nv.nbrs = NULL;
    snprintf(p, sizeof p, "%s/nonbrs.ele", dir);
    expect_fail(dir, p, &nv, FDT_IO_EFORMAT, "needs tet neighbours");
    /* ... while the other formats do not need them. */
    snprintf(p, sizeof p, "%s/nonbrs.vtk", dir);
    EXPECT(fdt_wr_mesh(p, &nv, q, sizeof q) == FDT_IO_OK);
    unlink(p);

    /* Unknown or missing extension. */
    snprintf(p, sizeof p, "%s/mesh.obj", dir);
    expect_fail(dir, p, &v, FDT_IO_EEXT, "unknown output format");
    snprintf(p, sizeof p, "%s/tets", dir);
    expect_fail(dir, p, &v, FDT_IO_EEXT, "unknown output format");
    snprintf(p, sizeof p, "%s/.tets", dir);
    expect_fail(dir, p, &v, FDT_IO_EEXT, "unknown output format");

    /* Missing directory: the message says which folder is missing (issue
     * 34 item 8). */
    snprintf(p, sizeof p, "%s/no/such/dir/out.tets", dir);
    snprintf(q, sizeof q, "cannot create output %s: folder %s/no/such/dir does not exist", p,
             dir);
    expect_fail(dir, p, &v, FDT_IO_EWRITE, q);
    snprintf(p, sizeof p, "%s/no/such/dir/out.ele", dir);
    expect_fail(dir, p, &v, FDT_IO_EWRITE, "/no/such/dir does not exist");

    /* A regular file where the directory should be (fails even as root). */
    snprintf(q, sizeof q, "%s/plain", dir);
    FILE *f = fopen(q, "w");
    fputs("x\n", f);
    fclose(f);
    snprintf(p, sizeof p, "%s/plain/out.vtu", dir);
    expect_fail(dir, p, &v, FDT_IO_EWRITE, "/plain is not a folder");

    /* The target is a directory. */
    snprintf(p, sizeof p, "%s/isdir.vtk", dir);
    EXPECT(mkdir(p, 0755) == 0);
    expect_fail(dir, p, &v, FDT_IO_EWRITE, strerror(EISDIR));

    /* TetGen set whose last file cannot be renamed into place (a directory
     * named BASE.neigh, non-empty so rename() cannot replace it): none of
     * the four files may appear. */
    snprintf(p, sizeof p, "%s/set.neigh", dir);
    EXPECT(mkdir(p, 0755) == 0);
    snprintf(q, sizeof q, "%s/set.neigh/keep", dir);
    f = fopen(q, "w");
    fclose(f);
    snprintf(p, sizeof p, "%s/set.ele", dir);
    expect_fail(dir, p, &v, FDT_IO_EWRITE, "set.neigh: ");
    snprintf(p, sizeof p, "%s/set.node", dir);
    EXPECT(!file_exists(p));

    /* A read-only directory (root ignores the permission bits). */
    if (geteuid() != 0) {
        char ro[2048];
        snprintf(ro, sizeof ro, "%s/ro", dir);
        EXPECT(mkdir(ro, 0555) == 0);
        snprintf(p, sizeof p, "%s/out.tets", ro);
        expect_fail(ro, p, &v, FDT_IO_EWRITE, strerror(EACCES));
        snprintf(p, sizeof p, "%s/out.ele", ro);
        expect_fail(ro, p, &v, FDT_IO_EWRITE, strerror(EACCES));
        chmod(ro, 0755);
    }

    /* Writes failing part-way (file size limit: EFBIG, like ENOSPC it only
     * shows on a write): EWRITE, no temporary, the old target intact. */
    struct rlimit old_lim, lim;
    EXPECT(getrlimit(RLIMIT_FSIZE, &old_lim) == 0);
    void (*old_h)(int) = signal(SIGXFSZ, SIG_IGN);
    snprintf(p, sizeof p, "%s/keep.vtk", dir);
    f = fopen(p, "w");
    fputs("old content\n", f);
    fclose(f);
    lim = old_lim;
    lim.rlim_cur = 30; /* below the smallest file: cube.tets, 40 bytes */
    EXPECT(setrlimit(RLIMIT_FSIZE, &lim) == 0);
    const char *fmts[] = { "keep.vtk", "big.vtu", "big.ele", "big.tets" };
    for (int i = 0; i < 4; i++) {
        snprintf(p, sizeof p, "%s/%s", dir, fmts[i]);
        expect_fail(dir, p, &v, FDT_IO_EWRITE, strerror(EFBIG));
    }
    EXPECT(setrlimit(RLIMIT_FSIZE, &old_lim) == 0);
    signal(SIGXFSZ, old_h);
    size_t len;
    snprintf(p, sizeof p, "%s/keep.vtk", dir);
    char *s = test_slurp(p, &len);
    EXPECT(s && strcmp(s, "old content\n") == 0);
    free(s);
}

/* Decimal formatting at digit-count boundaries, up to FDT_VID_MAX - 1. */
static void test_big_ids(const char *dir)
{
    static const fdt_vid ids[] = {
        0, 1, 2, 9, 10, 11, 99, 100, 101, 999, 1000, 9999, 10000, 99999,
        100000, 999999, 1000000, 9999999, 10000000, 99999999, 100000000,
        999999999, 1000000000, 2147483644, 2147483645, 2147483646,
    };
    size_t nid = sizeof ids / sizeof ids[0];
    size_t nt = nid - 3;
    fdt_vid *tets = malloc(4 * nt * sizeof *tets);
    for (size_t t = 0; t < nt; t++) {
        /* Written out of order within the tet on purpose. */
        tets[4 * t] = ids[t + 2];
        tets[4 * t + 1] = ids[t];
        tets[4 * t + 2] = ids[t + 3];
        tets[4 * t + 3] = ids[t + 1];
    }
    double dummy[3] = { 0, 0, 0 };
    fdt_mesh_view v = { .xyz = dummy, .n_points = (size_t)FDT_VID_MAX,
                        .tets = tets, .n_tets = nt };
    char p[4096], err[256];
    snprintf(p, sizeof p, "%s/big_ids.tets", dir);
    EXPECT(fdt_wr_mesh(p, &v, err, sizeof err) == FDT_IO_OK);
    check_tets_file(p, tets, nt);
    unlink(p);
    free(tets);
}

/* Large enough to cross the 1 MiB output buffer many times. */
static void test_large(const char *dir)
{
    const size_t n = 200000, nt = n - 3;
    double *xyz = malloc(3 * n * sizeof *xyz);
    fdt_vid *tets = malloc(4 * nt * sizeof *tets);
    fdt_tid *nbrs = malloc(4 * nt * sizeof *nbrs);
    fdt_vid *hull = malloc(3 * nt * sizeof *hull);
    uint64_t x = 0x9e3779b97f4a7c15u;
    for (size_t i = 0; i < 3 * n; i++) {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        xyz[i] = (double)(x >> 11) * 0x1.0p-53 * 1e3 - 500.0;
    }
    for (size_t t = 0; t < nt; t++) {
        fdt_vid a = (fdt_vid)t;
        /* Canonical order by sorted tuple, vertex order varying. */
        fdt_vid q[4] = { a + 3, a + 1, a, a + 2 };
        if (t % 3 == 1) {
            q[0] = a;
            q[2] = a + 3;
        }
        memcpy(tets + 4 * t, q, sizeof q);
        for (int k = 0; k < 4; k++)
            nbrs[4 * t + (size_t)k] =
                (t + (size_t)k) % 5 == 0 ? -1 : (fdt_tid)((t * 7 + (size_t)k) % nt);
        hull[3 * t] = a;
        hull[3 * t + 1] = a + 2;
        hull[3 * t + 2] = a + 1;
    }
    fdt_mesh_view v = { .xyz = xyz, .n_points = n, .tets = tets,
                        .n_tets = nt, .nbrs = nbrs, .hull = hull,
                        .n_hull = nt };
    char p[4096], err[256];
    snprintf(p, sizeof p, "%s/large.tets", dir);
    EXPECT(fdt_wr_mesh(p, &v, err, sizeof err) == FDT_IO_OK);
    check_tets_file(p, tets, nt);
    snprintf(p, sizeof p, "%s/large.ele", dir);
    EXPECT(fdt_wr_mesh(p, &v, err, sizeof err) == FDT_IO_OK);
    check_tetgen_set(dir, "large", &v);
    snprintf(p, sizeof p, "%s/large.vtk", dir);
    EXPECT(fdt_wr_mesh(p, &v, err, sizeof err) == FDT_IO_OK);
    check_vtk_file(p, xyz, n, tets, nt);
    snprintf(p, sizeof p, "%s/large.vtu", dir);
    EXPECT(fdt_wr_mesh(p, &v, err, sizeof err) == FDT_IO_OK);
    check_vtu_file(p, xyz, n, tets, nt);
    EXPECT(count_temps(dir) == 0);
    free(xyz);
    free(tets);
    free(nbrs);
    free(hull);
}

/* fdt_output_files: the set of each family, as the writer writes it. */
static void test_output_files(const char *dir)
{
    char names[FDT_IO_MAX_FILES][FDT_IO_PATH];
    EXPECT(fdt_output_files("a/m.tets", names) == 1);
    EXPECT(!strcmp(names[0], "a/m.tets"));
    EXPECT(fdt_output_files("m.VTU", names) == 1);
    EXPECT(!strcmp(names[0], "m.VTU"));
    EXPECT(fdt_output_files("m.vtk", names) == 1);
    EXPECT(fdt_output_files("d/m.ELE", names) == 4);
    EXPECT(!strcmp(names[0], "d/m.node"));
    EXPECT(!strcmp(names[1], "d/m.ELE"));
    EXPECT(!strcmp(names[2], "d/m.face"));
    EXPECT(!strcmp(names[3], "d/m.neigh"));
    EXPECT(fdt_output_files("m.face", names) == 0);
    EXPECT(fdt_output_files("m.node", names) == 0);
    EXPECT(fdt_output_files("d/.ele", names) == 0);
    EXPECT(fdt_output_files("ele", names) == 0);
    /* A .ele name that fits while "BASE.neigh" would not. */
    static char longp[FDT_IO_PATH];
    memset(longp, 'x', FDT_IO_PATH - 1);
    memcpy(longp + FDT_IO_PATH - 6, ".ele", 5);
    EXPECT(fdt_output_files(longp, names) == -1);

    /* The writer writes exactly that set (and nothing else). */
    int before = count_entries(dir);
    double xyz[12] = { 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1 };
    fdt_vid tet[4] = { 0, 1, 2, 3 };
    fdt_tid nb[4] = { -1, -1, -1, -1 };
    fdt_vid hull[12] = { 1, 2, 3, 0, 3, 2, 0, 1, 3, 0, 2, 1 };
    fdt_mesh_view v = { .xyz = xyz, .n_points = 4, .tets = tet, .n_tets = 1,
                        .nbrs = nb, .hull = hull, .n_hull = 4 };
    char p[4096], e[256];
    snprintf(p, sizeof p, "%s/set.Ele", dir);
    EXPECT(fdt_wr_mesh(p, &v, e, sizeof e) == FDT_IO_OK);
    EXPECT(fdt_output_files(p, names) == 4);
    for (int i = 0; i < 4; i++) {
        struct stat st;
        EXPECT(stat(names[i], &st) == 0 && S_ISREG(st.st_mode));
    }
    EXPECT(count_entries(dir) == before + 4);
}

static void touch(const char *path)
{
    FILE *f = fopen(path, "w");
    EXPECT(f != NULL);
    if (f) {
        fputs("0 0 0\n", f);
        fclose(f);
    }
}

/* fdt_same_file: every way of naming one file, and the near misses. */
static void test_same_file(const char *dir)
{
    char a[4096], b[4096], c[4096], cwd[4096];
    EXPECT(getcwd(cwd, sizeof cwd) != NULL);
    EXPECT(chdir(dir) == 0);
    mkdir("sub", 0755);
    touch("in.node");
    touch("other.node");

    EXPECT(fdt_same_file("in.node", "in.node"));
    EXPECT(fdt_same_file("in.node", "./in.node"));
    EXPECT(fdt_same_file("sub/../in.node", "in.node"));
    snprintf(a, sizeof a, "%s/in.node", dir);
    EXPECT(fdt_same_file(a, "in.node"));
    EXPECT(fdt_same_file("in.node", a));
    EXPECT(!fdt_same_file("in.node", "other.node"));
    EXPECT(!fdt_same_file("in.node", "sub"));

    /* Links: a symbolic link (relative or absolute target, through a
     * linked directory) and a hard link all reach the file. */
    EXPECT(symlink("in.node", "sym.tets") == 0);
    EXPECT(fdt_same_file("sym.tets", "in.node"));
    EXPECT(symlink(a, "sub/abs.vtk") == 0);
    EXPECT(fdt_same_file("sub/abs.vtk", "./in.node"));
    EXPECT(symlink("..", "sub/up") == 0);
    EXPECT(fdt_same_file("sub/up/in.node", "in.node"));
    EXPECT(link("in.node", "hard.vtu") == 0);
    EXPECT(fdt_same_file("hard.vtu", "in.node"));
    EXPECT(!fdt_same_file("hard.vtu", "other.node"));

    /* Names not there yet: same directory and name, however spelled. */
    EXPECT(fdt_same_file("new.neigh", "./new.neigh"));
    EXPECT(fdt_same_file("sub/../new.neigh", "new.neigh"));
    snprintf(b, sizeof b, "%s/new.neigh", dir);
    EXPECT(fdt_same_file(b, "sub/up/new.neigh"));
    EXPECT(!fdt_same_file("new.neigh", "new.face"));
    EXPECT(!fdt_same_file("new.neigh", "sub/new.neigh"));
    /* A missing name is not an existing file. */
    EXPECT(!fdt_same_file("new.neigh", "in.node"));

    /* A dangling link stands for the file that writing through it would
     * create, relative to the link's own directory, chains included. */
    EXPECT(symlink("../new.neigh", "sub/dangle.json") == 0);
    EXPECT(fdt_same_file("sub/dangle.json", "new.neigh"));
    EXPECT(!fdt_same_file("sub/dangle.json", "sub/new.neigh"));
    EXPECT(symlink("sub/dangle.json", "chain.json") == 0);
    EXPECT(fdt_same_file("chain.json", "./new.neigh"));
    snprintf(c, sizeof c, "%s/new.face", dir);
    EXPECT(symlink(c, "absdangle.json") == 0);
    EXPECT(fdt_same_file("absdangle.json", "new.face"));

    /* Unresolvable paths match only their own string. */
    EXPECT(symlink("loop.b", "loop.a") == 0);
    EXPECT(symlink("loop.a", "loop.b") == 0);
    EXPECT(fdt_same_file("loop.a", "loop.a"));
    EXPECT(!fdt_same_file("loop.a", "loop.b"));
    EXPECT(!fdt_same_file("no/such/x.tets", "no/such/../such/x.tets"));
    EXPECT(!fdt_same_file("in.node/x", "in.node"));
    /* a name with nothing after its slash, not there: unresolvable */
    EXPECT(!fdt_same_file("gone/", "./gone/"));
    /* a name in the root directory, however many slashes */
    EXPECT(fdt_same_file("/fdt_same_file_none", "//fdt_same_file_none"));
    /* a path longer than any the writer takes */
    static char longp[FDT_IO_PATH + 8];
    memset(longp, 'x', sizeof longp - 1);
    EXPECT(fdt_same_file(longp, longp) && !fdt_same_file(longp, "in.node"));
    /* a dangling link whose target no longer fits beside its directory */
    static char target[FDT_IO_PATH];
    memset(target, 'y', FDT_IO_PATH - 2);
    target[FDT_IO_PATH - 2] = '\0';
    if (symlink(target, "sub/far") == 0) {
        EXPECT(!fdt_same_file("sub/far", "sub/./far"));
        unlink("sub/far");
    }
    /* A path is looked up at most 40 times (FDT_IO_MAX_HOPS, like the
     * kernel's limit on links): hop0 -> hop1 -> ... -> hop45, not there.
     * From hop6, 39 links and the missing name: within the limit; from
     * hop5, 40 links: unresolvable. */
    for (int i = 0; i < 45; i++) {
        snprintf(a, sizeof a, "hop%d", i);
        snprintf(b, sizeof b, "hop%d", i + 1);
        EXPECT(symlink(b, a) == 0);
    }
    EXPECT(fdt_same_file("hop10", "./hop45") && fdt_same_file("hop6", "hop45"));
    EXPECT(!fdt_same_file("hop5", "hop45") && !fdt_same_file("hop0", "hop45"));

    EXPECT(chdir(cwd) == 0);
}

/* fdt_io_cleanup_temps() with nothing live is harmless. */
static void test_cleanup_idle(const char *dir)
{
    int before = count_entries(dir);
    fdt_io_cleanup_temps();
    EXPECT(count_entries(dir) == before);
}

/* The format table's lookups (src/io/write/writer.c): by name, by path (a
 * directory format by its last component, trailing slashes and case
 * ignored), the list for messages, what each needs, and every layout's
 * file names (a directory's parts, a family without its extension as
 * --format gives it, names too long). */
static void test_format_table(const char *dir)
{
    (void)dir;
    EXPECT(fdt_format_by_name(NULL) == NULL && fdt_format_by_name("nope") == NULL);
    const fdt_format *msh2 = fdt_format_by_name("msh2"), *foam = fdt_format_by_name("openfoam"),
                     *tg = fdt_format_by_name("tetgen"), *vtu = fdt_format_by_name("vtu"),
                     *tets = fdt_format_by_name("tets"), *vtk = fdt_format_by_name("vtk");
    CHECK(msh2 && foam && tg && vtu && tets && vtk);
    EXPECT(!strcmp(fdt_format_name(msh2), "msh2") && fdt_format_name(NULL) == NULL);
    EXPECT(fdt_format_by_path(NULL) == NULL);
    EXPECT(fdt_format_by_path("case/polyMesh") == foam);
    EXPECT(fdt_format_by_path("case/polyMesh//") == foam);
    EXPECT(fdt_format_by_path("case/POLYMESH") == foam);
    EXPECT(fdt_format_by_path("polyMesh") == foam);
    EXPECT(fdt_format_by_path("case/xpolyMesh") == NULL);
    EXPECT(fdt_format_by_path("case/polyMes") == NULL);
    EXPECT(fdt_format_by_path("m.msh") != msh2); /* .msh chooses msh, the first row */
    /* --format against the extension (issue 34 item 5): the row the
     * extension names when it is another; NULL when it agrees or names
     * none */
    EXPECT(fdt_format_contradicted("m.vtu", msh2) == vtu);
    EXPECT(fdt_format_contradicted("m.msh", msh2) == NULL);
    EXPECT(fdt_format_contradicted("m.MSH", msh2) == NULL);
    EXPECT(fdt_format_contradicted("m.ele", tg) == NULL);
    EXPECT(fdt_format_contradicted("m.dat", vtu) == NULL);
    EXPECT(fdt_format_contradicted("m", foam) == NULL);
    EXPECT(fdt_format_contradicted("case/polyMesh", vtu) == foam);
    EXPECT(fdt_format_contradicted("m.ele", vtk) == tg);
    EXPECT(fdt_format_contradicted("m.vtu", NULL) == NULL);
    EXPECT(fdt_format_is_text(tets) && !fdt_format_is_text(vtu) && !fdt_format_is_text(NULL));
    /* all_faces adds the faces to TetGen's set alone */
    EXPECT(fdt_format_needs(NULL, 1) == 0);
    EXPECT((fdt_format_needs(tg, 1) & FDT_NEED_FACES) && !(fdt_format_needs(tg, 0) & FDT_NEED_FACES));
    EXPECT(fdt_format_needs(tg, 0) & FDT_NEED_NBRS);
    EXPECT(fdt_format_needs(vtk, 1) == fdt_format_needs(vtk, 0));
    const char *list = fdt_format_list();
    EXPECTF(strstr(list, "tets (.tets)") && strstr(list, "openfoam (polyMesh)") &&
                strstr(list, ", msh2 (.msh), ") && strstr(list, "tetgen (.ele)"),
            "[%s]", list);
    EXPECT(fdt_format_list() == list); /* built once */

    char names[FDT_IO_MAX_FILES][FDT_IO_PATH];
    /* a directory: its parts inside it, trailing slashes dropped */
    EXPECT(fdt_output_files_as("case/polyMesh//", NULL, names) == 5);
    EXPECT(!strcmp(names[0], "case/polyMesh/points") && !strcmp(names[4], "case/polyMesh/boundary"));
    /* --format openfoam on any directory name */
    EXPECT(fdt_output_files_as("out", foam, names) == 5 && !strcmp(names[1], "out/faces"));
    /* --format tetgen on a name without .ele: the base name itself */
    EXPECT(fdt_output_files_as("d/m", tg, names) == 4);
    EXPECT(!strcmp(names[0], "d/m.node") && !strcmp(names[1], "d/m.ele"));
    /* unknown format and no --format: none */
    EXPECT(fdt_output_files_as("m.xyz", NULL, names) == 0);
    /* too long for a path, each layout */
    static char longp[FDT_IO_PATH + 8];
    memset(longp, 'x', sizeof longp - 1);
    EXPECT(fdt_output_files_as(longp, tets, names) == -1);
    EXPECT(fdt_output_files_as(longp, tg, names) == -1);
    memset(longp, 'x', FDT_IO_PATH - 4);
    longp[FDT_IO_PATH - 4] = '\0';
    EXPECT(fdt_output_files_as(longp, foam, names) == -1); /* "/points" does not fit */
    EXPECT(fdt_output_files_as(longp, tets, names) == 1);
}

/* Side files, missing arrays, streams. */
static void test_misc(const char *dir)
{
    char p[4096], err[512];
    fdt_wr_side *side = NULL;
    /* side files: a name that is a directory, too long, in a missing
     * directory: NULL, the reason, nothing created */
    snprintf(p, sizeof p, "%s/", dir);
    EXPECT(fdt_wr_side_open(p, &side, err, sizeof err) == NULL && side == NULL &&
           strstr(err, "a folder has that name"));
    static char longp[FDT_IO_PATH + 8];
    memset(longp, 'x', sizeof longp - 1);
    static char lerr[FDT_IO_PATH + 256]; /* the message holds the path */
    EXPECT(fdt_wr_side_open(longp, &side, lerr, sizeof lerr) == NULL &&
           strstr(lerr, strerror(ENAMETOOLONG)));
    snprintf(p, sizeof p, "%s/no/side.json", dir);
    EXPECT(fdt_wr_side_open(p, &side, err, sizeof err) == NULL &&
           strstr(err, "no/side.json: folder ") && strstr(err, "/no does not exist"));
    fdt_wr_side_abandon(NULL);
    snprintf(p, sizeof p, "%s/side.json", dir);
    FILE *f = fdt_wr_side_open(p, &side, err, sizeof err);
    CHECK(f && side);
    fputs("{}\n", f);
    EXPECT(count_entries(dir) == 1 && count_temps(dir) == 1);
    fdt_wr_side_abandon(side);
    EXPECT(count_entries(dir) == 0);
    f = fdt_wr_side_open(p, &side, err, sizeof err);
    CHECK(f && side);
    fputs("{}\n", f);
    EXPECT(fdt_wr_side_commit(side, err, sizeof err) == FDT_IO_OK);
    size_t len;
    char *back = test_slurp(p, &len);
    EXPECT(back && strcmp(back, "{}\n") == 0 && count_temps(dir) == 0);
    free(back);
    unlink(p);

    /* arrays missing from the view */
    mesh m;
    make_mesh(&m);
    fdt_mesh_view v = view_of(&m);
    fdt_mesh_view bad = v;
    bad.tets = NULL;
    snprintf(p, sizeof p, "%s/m.tets", dir);
    expect_fail(dir, p, &bad, FDT_IO_EFORMAT, "m.tets: mesh arrays missing");
    bad = v;
    bad.hull = NULL;
    expect_fail(dir, p, &bad, FDT_IO_EFORMAT, "mesh arrays missing");
    bad = v;
    bad.faces = m.hull; /* any face list, without its tets */
    bad.n_faces = 1;
    expect_fail(dir, p, &bad, FDT_IO_EFORMAT, "face list without its tets");
    EXPECT(fdt_wr_mesh_ex(NULL, NULL, &v, NULL, NULL, err, sizeof err) == FDT_IO_EFORMAT &&
           strstr(err, "no path or no mesh"));
    EXPECT(fdt_wr_mesh(p, NULL, err, sizeof err) == FDT_IO_EFORMAT);

    /* streams: refused without one, or for a binary format; a full
     * device reports ENOSPC under the name given */
    const fdt_format *tets = fdt_format_by_name("tets"), *vtu = fdt_format_by_name("vtu");
    CHECK(tets && vtu);
    EXPECT(fdt_wr_mesh_stream(NULL, "stdout", tets, &v, err, sizeof err) == FDT_IO_EFORMAT);
    EXPECT(fdt_wr_mesh_stream(stderr, "stdout", NULL, &v, err, sizeof err) == FDT_IO_EFORMAT);
    EXPECT(fdt_wr_mesh_stream(stderr, "stdout", vtu, &v, err, sizeof err) == FDT_IO_EEXT &&
           strstr(err, "single-file text format"));
    bad = v;
    bad.tets = NULL;
    EXPECT(fdt_wr_mesh_stream(stderr, "stdout", tets, &bad, err, sizeof err) ==
           FDT_IO_EFORMAT && strstr(err, "mesh arrays missing"));
    FILE *full = fopen("/dev/full", "w");
    if (full) {
        EXPECTF(fdt_wr_mesh_stream(full, "stdout", tets, &v, err, sizeof err) ==
                    FDT_IO_EWRITE && strstr(err, "stdout: ") && strstr(err, strerror(ENOSPC)),
                "[%s]", err);
        fclose(full);
    } else {
        printf("misc: no /dev/full, its case skipped\n");
    }
    EXPECT(count_entries(dir) == 0);
}

/* ------------------------------------------------------------------------ */
/* src/io/write/outfile.h alone                                                       */
/* ------------------------------------------------------------------------ */

typedef struct meter_log {
    int calls;
    uint64_t done, total;
} meter_log;

static void meter_fn(void *user, int stage, uint64_t done, uint64_t total)
{
    meter_log *l = user;
    l->calls += stage == FDT_STAGE_WRITE;
    l->done = done;
    l->total = total;
}

/* An out_file over the write end of a new pipe; its read end in *rd. */
static void pipe_out(out_file *o, int *rd)
{
    int fds[2];
    CHECK(pipe(fds) == 0);
    memset(o, 0, sizeof *o);
    o->slot = -1;
    o->path = "pipe";
    o->f = fdopen(fds[1], "wb");
    o->buf = malloc(OUT_BUF_SIZE);
    CHECK(o->f && o->buf);
    *rd = fds[0];
}

static void pipe_close(out_file *o, int rd)
{
    fclose(o->f);
    free(o->buf);
    if (rd >= 0)
        close(rd);
}

/* What the pipe holds now (at most 255 bytes), as a string. */
static const char *pipe_text(int rd)
{
    static char b[256];
    int fl = fcntl(rd, F_GETFL);
    fcntl(rd, F_SETFL, fl | O_NONBLOCK);
    ssize_t k = read(rd, b, sizeof b - 1);
    fcntl(rd, F_SETFL, fl);
    b[k > 0 ? k : 0] = '\0';
    return b;
}

static void test_outfile(const char *dir)
{
    out_file o;
    int rd;
    meter_log ml = {0, 0, 0};
    out_meter mt = {meter_fn, &ml, 0, 5}; /* an estimate below what comes */

    /* Text items, flushed through the meter. */
    pipe_out(&o, &rd);
    o.meter = &mt;
    out_i64(&o, -123);
    out_char(&o, ' ');
    out_i64(&o, INT64_MIN);
    out_char(&o, ' ');
    out_i64(&o, 0);
    out_char(&o, ' ');
    out_double(&o, 0.1);
    out_char(&o, ' ');
    char *p = out_room(&o, 6);
    fmt_u64_width(p, 42, 6);
    o.len += 6;
    out_str(&o, "|");
    out_flush(&o);
    EXPECT(o.err == 0 && o.len == 0);
    CHECK(fflush(o.f) == 0);
    const char *want = "-123 -9223372036854775808 0 0.10000000000000001     42|";
    const char *got = pipe_text(rd);
    EXPECTF(strcmp(got, want) == 0, "[%s]", got);
    /* the meter saw every byte, its total never below them */
    EXPECTF(ml.calls == 1 && ml.done == strlen(want) && ml.total == ml.done,
            "%d calls, %" PRIu64 " of %" PRIu64, ml.calls, ml.done, ml.total);
    out_flush(&o); /* nothing buffered: no call */
    EXPECT(ml.calls == 1);

    /* A pipe has no offset: out_tell fails with ESPIPE (and returns 0),
     * and the error is final. */
    out_str(&o, "abc");
    EXPECT(out_tell(&o) == 0 && o.err == ESPIPE);
    out_flush(&o);
    EXPECT(o.len == 3); /* an output in error is not written */
    o.err = 0;
    /* out_patch flushes ours and stdio's, then pwrite fails (ESPIPE):
     * the bytes before it are out, the patch is not */
    out_patch(&o, 0, "X", 1);
    EXPECT(o.err == ESPIPE);
    got = pipe_text(rd);
    EXPECTF(strcmp(got, "abc") == 0, "[%s]", got);
    /* With the error kept, a patch writes nothing at all. */
    out_str(&o, "def");
    out_patch(&o, 0, "X", 1);
    EXPECT(o.err == ESPIPE && o.len == 3 && pipe_text(rd)[0] == '\0');
    /* out_room into an output in error: the bytes go to the bin, the
     * buffer never overflows */
    o.len = OUT_BUF_SIZE - 2;
    out_i64(&o, 1234567);
    EXPECT(o.len == 7 && o.err == ESPIPE);
    pipe_close(&o, rd);

    /* The reader gone (EPIPE; SIGPIPE ignored as the CLI's writes meet
     * it): a few bytes pass our flush into stdio's buffer and fail in
     * fflush, inside out_patch. */
    void (*old)(int) = signal(SIGPIPE, SIG_IGN);
    pipe_out(&o, &rd);
    close(rd);
    out_str(&o, "abc");
    out_patch(&o, 0, "X", 1);
    EXPECTF(o.err == EPIPE, "%s", strerror(o.err));
    pipe_close(&o, -1);
    /* More than our buffer in one out_bytes: its first flush fails and
     * the rest is dropped, the error kept. */
    pipe_out(&o, &rd);
    close(rd);
    size_t big = 3 * (size_t)OUT_BUF_SIZE;
    char *junk = calloc(1, big);
    CHECK(junk);
    out_bytes(&o, junk, big);
    EXPECT(o.err == EPIPE && o.len == 0);
    free(junk);
    /* out_fail keeps the first errno, and a failure without one is EIO */
    out_fail(&o, ENOSPC);
    EXPECT(o.err == EPIPE);
    o.err = 0;
    out_fail(&o, 0);
    EXPECT(o.err == EIO);
    pipe_close(&o, -1);
    signal(SIGPIPE, old);

    /* A patch in a regular file lands in place, the stream's position
     * left at the end; after an error it writes nothing. */
    char path[4096];
    snprintf(path, sizeof path, "%s/patch", dir);
    memset(&o, 0, sizeof o);
    o.f = fopen(path, "wb");
    o.buf = malloc(OUT_BUF_SIZE);
    CHECK(o.f && o.buf);
    out_str(&o, "0123456789");
    EXPECT(out_tell(&o) == 10);
    out_patch(&o, 2, "ab", 2);
    out_str(&o, "!");
    o.err = ENOSPC; /* as a failed write would leave it */
    out_patch(&o, 5, "Z", 1);
    o.err = 0;
    out_flush(&o);
    fclose(o.f);
    free(o.buf);
    size_t len;
    char *back = test_slurp(path, &len);
    EXPECTF(back && strcmp(back, "01ab456789!") == 0, "[%s]", back ? back : "");
    free(back);
    unlink(path);

    /* The messages: the path named, ENOMEM not a write failure, no errno
     * read as EIO, no buffer no message. */
    char err[128];
    EXPECT(set_errno_err(err, sizeof err, "a.vtu", ENOSPC) == FDT_IO_EWRITE &&
           strstr(err, "a.vtu: ") == err && strstr(err, strerror(ENOSPC)));
    EXPECT(set_errno_err(err, sizeof err, "a.vtu", ENOMEM) == FDT_IO_ENOMEM);
    EXPECT(set_errno_err(err, sizeof err, NULL, 0) == FDT_IO_EWRITE &&
           strstr(err, "(null): ") == err && strstr(err, strerror(EIO)));
    EXPECT(set_err(NULL, 0, FDT_IO_EFORMAT, "x", "y") == FDT_IO_EFORMAT);
}

/* Commit sets (issue 34 item 3): outputs written in a set stay in their
 * temporaries until fdt_wr_set_commit renames them all; abandoned, a
 * --no-clobber refusal, or a failure at any step of the commit
 * (FDT_TEST_COMMIT_FAULT) leaves every old file as it was, and nothing
 * else in the folder. */
static int same_bytes(const char *path, const char *want, size_t wlen)
{
    size_t len;
    char *got = test_slurp(path, &len);
    int same = got && len == wlen && memcmp(got, want, len) == 0;
    free(got);
    return same;
}

static void test_commit_set(const char *dir)
{
    mesh m;
    make_mesh(&m);
    fdt_mesh_view v = view_of(&m), old = v;
    old.n_tets = NT - 1; /* the previous run's mesh: other bytes */
    old.nbrs = NULL;     /* (they would name the tet left out) */
    char a[4096], b[4096], err[8192];
    snprintf(a, sizeof a, "%s/a.vtk", dir);
    snprintf(b, sizeof b, "%s/a.msh", dir);
    size_t la = 0, lb = 0, na = 0, nb = 0;
    char *olda, *oldb, *newa, *newb;
    /* the new and the old bytes */
    EXPECT(fdt_wr_mesh(a, &v, err, sizeof err) == FDT_IO_OK);
    EXPECT(fdt_wr_mesh(b, &v, err, sizeof err) == FDT_IO_OK);
    newa = test_slurp(a, &na);
    newb = test_slurp(b, &nb);
    EXPECT(fdt_wr_mesh(a, &old, err, sizeof err) == FDT_IO_OK);
    EXPECT(fdt_wr_mesh(b, &old, err, sizeof err) == FDT_IO_OK);
    olda = test_slurp(a, &la);
    oldb = test_slurp(b, &lb);
    CHECK(newa && newb && olda && oldb);
    EXPECT(la != na || memcmp(olda, newa, la) != 0);

    /* committed: nothing changes before the commit, all after it */
    EXPECT(fdt_wr_set_begin(0) == 0 && fdt_wr_set_active());
    EXPECT(fdt_wr_set_begin(0) == -1); /* one at a time */
    EXPECT(fdt_wr_mesh(a, &v, err, sizeof err) == FDT_IO_OK);
    EXPECT(fdt_wr_mesh(b, &v, err, sizeof err) == FDT_IO_OK);
    EXPECT(same_bytes(a, olda, la) && same_bytes(b, oldb, lb));
    EXPECT(count_temps(dir) == 2);
    EXPECT(fdt_wr_set_commit(err, sizeof err) == FDT_IO_OK && !fdt_wr_set_active());
    EXPECT(same_bytes(a, newa, na) && same_bytes(b, newb, nb));
    EXPECT(count_entries(dir) == 2); /* no temporary, backup or journal */

    /* abandoned: the old files stay, the temporaries go */
    EXPECT(fdt_wr_mesh(a, &old, err, sizeof err) == FDT_IO_OK);
    EXPECT(fdt_wr_mesh(b, &old, err, sizeof err) == FDT_IO_OK);
    EXPECT(fdt_wr_set_begin(0) == 0);
    EXPECT(fdt_wr_mesh(a, &v, err, sizeof err) == FDT_IO_OK);
    EXPECT(fdt_wr_mesh(b, &v, err, sizeof err) == FDT_IO_OK);
    fdt_wr_set_abandon();
    EXPECT(!fdt_wr_set_active());
    EXPECT(same_bytes(a, olda, la) && same_bytes(b, oldb, lb) && count_entries(dir) == 2);

    /* --no-clobber: the commit refuses an existing target, changes nothing */
    EXPECT(fdt_wr_set_begin(1) == 0);
    EXPECT(fdt_wr_mesh(a, &v, err, sizeof err) == FDT_IO_OK);
    EXPECT(fdt_wr_set_commit(err, sizeof err) == FDT_IO_EWRITE);
    EXPECTF(strstr(err, "a.vtk: exists (--no-clobber)") != NULL, "[%s]", err);
    EXPECT(same_bytes(a, olda, la) && count_entries(dir) == 2);

    /* a failure at every step: two backups, the journal, two renames, the
     * commit point; after it (step 7) the commit is done */
    for (int k = 1; k <= 8; k++) {
        char fault[32];
        snprintf(fault, sizeof fault, "%d:fail", k);
        EXPECT(fdt_wr_set_begin(0) == 0);
        EXPECT(fdt_wr_mesh(a, &v, err, sizeof err) == FDT_IO_OK);
        EXPECT(fdt_wr_mesh(b, &v, err, sizeof err) == FDT_IO_OK);
        setenv("FDT_TEST_COMMIT_FAULT", fault, 1);
        int r = fdt_wr_set_commit(err, sizeof err);
        unsetenv("FDT_TEST_COMMIT_FAULT");
        if (k <= 6) {
            EXPECTF(r == FDT_IO_EWRITE && strstr(err, "every output left as it was"),
                    "step %d: %d [%s]", k, r, err);
            EXPECTF(same_bytes(a, olda, la) && same_bytes(b, oldb, lb), "step %d", k);
        } else {
            EXPECTF(r == FDT_IO_OK, "step %d: %d [%s]", k, r, err);
            EXPECTF(same_bytes(a, newa, na) && same_bytes(b, newb, nb), "step %d", k);
            EXPECT(fdt_wr_mesh(a, &old, err, sizeof err) == FDT_IO_OK);
            EXPECT(fdt_wr_mesh(b, &old, err, sizeof err) == FDT_IO_OK);
        }
        EXPECTF(count_entries(dir) == 2, "step %d: %d entries", k, count_entries(dir));
    }
    unlink(a);
    unlink(b);
    free(olda);
    free(oldb);
    free(newa);
    free(newb);
}

int main(void)
{
    const char *tmp = getenv("TMPDIR");
    char dir[2048];
    snprintf(dir, sizeof dir, "%s/fdt_test_writer_XXXXXX",
             tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    char sub[4096];
    const char *names[] = { "small", "refuse", "ids", "large", "files",
                            "same", "table", "outfile", "misc", "commit" };
    void (*fns[])(const char *) = { test_small_mesh, test_refusals,
                                    test_big_ids, test_large,
                                    test_output_files, test_same_file,
                                    test_format_table, test_outfile, test_misc,
                                    test_commit_set };
    for (int i = 0; i < 10; i++) {
        snprintf(sub, sizeof sub, "%s/%s", dir, names[i]);
        mkdir(sub, 0755);
        long before = test_failures();
        fns[i](sub);
        fprintf(stderr, "%-8s %s\n", names[i],
                test_failures() == before ? "ok" : "FAILED");
    }
    test_cleanup_idle(dir);
    remove_tree_files(dir);
    rmdir(dir);
    return test_report("test_writer");
}
