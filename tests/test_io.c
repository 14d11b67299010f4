/*
 * The public file formats of include/frontdt.h, through the installed
 * shared library as a C user links it (tests/meson.build: frontdt_dep):
 * fdt_read_points / fdt_read_points_opts (columns, header line, threads,
 * progress, every refusal and its FDT_E* code and diagnostic),
 * fdt_write_mesh / fdt_write_mesh_opts in every format on a small mesh
 * (TetGen and .tets read back; gmsh 4.1 and 2.2 counts and node numbering,
 * Medit counts, OpenFOAM counts, owner < neighbour and upper-triangular
 * order, VTK counts), the write progress, write failures that leave no
 * temporary, the ABI sizes of the options, and fdt_free.
 *
 * Usage: test_io SCRATCH_DIR (made if missing, emptied of our files).
 */
#include "frontdt.h"
#include "testdir.h"
#include "testutil.h"

#include <dirent.h>
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

static char dir[1024];

static const char *at(const char *name)
{
    static char buf[4][2048];
    static int k;
    k = (k + 1) % 4;
    snprintf(buf[k], sizeof buf[k], "%s/%s", dir, name);
    return buf[k];
}

static void put_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL);
    CHECK(fputs(text, f) >= 0);
    CHECK(fclose(f) == 0);
}

/* The text after the first line equal to key (key without its newline). */
static const char *after_line(const char *text, const char *key)
{
    size_t k = strlen(key);
    for (const char *p = text; p && *p; p = strchr(p, '\n'), p = p ? p + 1 : NULL)
        if (strncmp(p, key, k) == 0 && p[k] == '\n')
            return p + k + 1;
    return NULL;
}

/* Reads the next count integers of *p (any separators but digits and '-'). */
static void ints(const char **p, long long *out, int count)
{
    for (int i = 0; i < count; i++) {
        char *end;
        while (**p && !(**p == '-' || (**p >= '0' && **p <= '9')))
            (*p)++;
        out[i] = strtoll(*p, &end, 10);
        CHECK(end != *p);
        *p = end;
    }
}

static const char *skip_lines(const char *p, size_t k)
{
    for (size_t i = 0; i < k && p; i++) {
        p = strchr(p, '\n');
        p = p ? p + 1 : NULL;
    }
    CHECK(p != NULL);
    return p;
}

/* ------------------------------------------------------------------------ */
/* Reading                                                                   */
/* ------------------------------------------------------------------------ */

typedef struct seen {
    int calls[3];
    uint64_t first_total[3], last_done[3], last_total[3];
    int backwards;
} seen;

static void on_progress(void *user, int stage, uint64_t done, uint64_t total)
{
    seen *s = user;
    CHECK(stage >= FDT_STAGE_LOAD && stage <= FDT_STAGE_WRITE);
    if (s->calls[stage] > 0 && done < s->last_done[stage])
        s->backwards = 1;
    if (s->calls[stage] == 0)
        s->first_total[stage] = total;
    s->calls[stage]++;
    s->last_done[stage] = done;
    s->last_total[stage] = total;
    CHECK(total == 0 || total >= done);
}

static void test_read(void)
{
    char diag[512];
    double *xyz = NULL;
    size_t n = 99;

    /* A header line, five columns, comments: x y z from columns 1-3. */
    put_file(at("a.csv"), "X,Y,Z,I,C\n1,2,3,40,50\n4,5,6,41,51 # note\n\n7,8,9,42,52\n");
    CHECK_EQ(fdt_read_points(at("a.csv"), NULL, &xyz, &n, diag, sizeof diag), FDT_OK);
    CHECK_EQ(n, 3);
    CHECK(diag[0] == '\0');
    for (int i = 0; i < 9; i++)
        CHECK(xyz[i] == (double)(i + 1));
    fdt_free(xyz);

    /* Columns 3,4,5 and a named format whatever the extension, with the
     * progress callback and threads. */
    fdt_read_options o;
    fdt_default_read_options(&o);
    CHECK_EQ(o.struct_size, sizeof o);
    CHECK(o.format == NULL && o.columns[0] == 0 && o.n_threads == 0 && o.progress == NULL);
    o.columns[0] = 3;
    o.columns[1] = 4;
    o.columns[2] = 5;
    o.format = "CSV";
    o.n_threads = 2;
    seen s;
    memset(&s, 0, sizeof s);
    o.progress = on_progress;
    o.progress_user = &s;
    put_file(at("a.dat"), "X,Y,Z,I,C\n1,2,3,40,50\n4,5,6,41,51 # note\n\n7,8,9,42,52\n");
    CHECK_EQ(fdt_read_points_opts(at("a.dat"), &o, &xyz, &n, diag, sizeof diag), FDT_OK);
    CHECK_EQ(n, 3);
    CHECK(xyz[0] == 3 && xyz[1] == 40 && xyz[2] == 50 && xyz[8] == 52);
    fdt_free(xyz);
    CHECK(s.calls[FDT_STAGE_PARSE] >= 1);
    CHECK(s.last_done[FDT_STAGE_PARSE] == s.last_total[FDT_STAGE_PARSE]);
    CHECK(s.last_done[FDT_STAGE_PARSE] > 0);
    CHECK(!s.backwards);

    /* TetGen .node, 1-based, with an attribute and a marker. */
    put_file(at("b.node"), "# c\n4 3 1 1\n1 0 0 0 7 1\n2 1 0 0 7 1\n3 0 1 0 7 1\n"
                           "4 0 0 1 7 1\n");
    CHECK_EQ(fdt_read_points(at("b.node"), NULL, &xyz, &n, diag, sizeof diag), FDT_OK);
    CHECK_EQ(n, 4);
    CHECK(xyz[3] == 1 && xyz[7] == 1 && xyz[11] == 1);
    fdt_free(xyz);

    /* Refusals: the code, *xyz NULL, *n 0, a diagnostic naming the file
     * and, for bad content, the line. */
    xyz = (double *)&n;
    n = 5;
    CHECK_EQ(fdt_read_points(at("missing.xyz"), NULL, &xyz, &n, diag, sizeof diag), FDT_EIO);
    CHECK(xyz == NULL && n == 0);
    CHECK(strstr(diag, "missing.xyz") != NULL);
    CHECK_EQ(fdt_read_points(dir, "xyz", &xyz, &n, diag, sizeof diag), FDT_EIO);
    CHECK(strstr(diag, "directory") != NULL);

    put_file(at("bad.xyz"), "0 0 0\n1 0 0\n0 1 x\n0 0 1\n");
    CHECK_EQ(fdt_read_points(at("bad.xyz"), NULL, &xyz, &n, diag, sizeof diag), FDT_EFORMAT);
    CHECK(strstr(diag, "bad.xyz:3:") != NULL);
    CHECK(xyz == NULL && n == 0);
    put_file(at("nan.xyz"), "0 0 0\n1 0 0\n0 1 0\nnan 0 1\n");
    CHECK_EQ(fdt_read_points(at("nan.xyz"), NULL, &xyz, &n, diag, sizeof diag), FDT_EFORMAT);
    CHECK(strstr(diag, "nan.xyz:4:") != NULL);
    put_file(at("short.ply"), "ply\nformat binary_little_endian 1.0\nelement vertex 9\n"
                              "property double x\nproperty double y\nproperty double z\n"
                              "end_header\n0123456789");
    CHECK_EQ(fdt_read_points(at("short.ply"), NULL, &xyz, &n, diag, sizeof diag), FDT_EFORMAT);
    CHECK(strstr(diag, "short.ply") != NULL);
    put_file(at("empty.xyz"), "");
    CHECK_EQ(fdt_read_points(at("empty.xyz"), NULL, &xyz, &n, diag, sizeof diag), FDT_EFORMAT);

    /* The caller's mistakes: FDT_EINVAL, nothing read. */
    CHECK_EQ(fdt_read_points(at("a.csv"), "las", &xyz, &n, diag, sizeof diag), FDT_EINVAL);
    CHECK(strstr(diag, "unknown format") != NULL);
    put_file(at("c.weird"), "0 0 0\n");
    CHECK_EQ(fdt_read_points(at("c.weird"), NULL, &xyz, &n, diag, sizeof diag), FDT_EINVAL);
    CHECK(strstr(diag, "c.weird") != NULL && strstr(diag, "extension") != NULL);
    CHECK_EQ(fdt_read_points("-", NULL, &xyz, &n, diag, sizeof diag), FDT_EINVAL);
    CHECK(strncmp(diag, "stdin:", 6) == 0);
    fdt_default_read_options(&o);
    o.columns[0] = 2;
    o.columns[1] = 3;
    o.columns[2] = 4;
    CHECK_EQ(fdt_read_points_opts(at("b.node"), &o, &xyz, &n, diag, sizeof diag), FDT_EINVAL);
    CHECK(strstr(diag, "columns") != NULL);
    o.columns[0] = 0;
    CHECK_EQ(fdt_read_points_opts(at("a.csv"), &o, &xyz, &n, diag, sizeof diag), FDT_EINVAL);
    CHECK_EQ(fdt_read_points(NULL, NULL, &xyz, &n, diag, sizeof diag), FDT_EINVAL);
    CHECK_EQ(fdt_read_points(at("a.csv"), NULL, NULL, &n, diag, sizeof diag), FDT_EINVAL);
    CHECK_EQ(fdt_read_points(at("a.csv"), NULL, &xyz, NULL, NULL, 0), FDT_EINVAL);
    /* NULL diagnostics are fine, a short one is cut and terminated */
    CHECK_EQ(fdt_read_points(at("bad.xyz"), NULL, &xyz, &n, NULL, 0), FDT_EFORMAT);
    char tiny[6];
    CHECK_EQ(fdt_read_points(at("bad.xyz"), NULL, &xyz, &n, tiny, sizeof tiny), FDT_EFORMAT);
    CHECK(strlen(tiny) == sizeof tiny - 1);

    /* ABI: sizes this library does not know are refused. */
    fdt_read_options big[2];
    CHECK_EQ(fdt_default_read_options_sized(&big[0], sizeof big[0] + 8), FDT_EINVAL);
    CHECK_EQ(big[0].struct_size, 0);
    CHECK_EQ(fdt_read_points_opts(at("a.csv"), &big[0], &xyz, &n, diag, sizeof diag),
             FDT_EINVAL);
    CHECK(strstr(diag, "size") != NULL);
    CHECK_EQ(fdt_default_read_options_sized(NULL, sizeof o), FDT_EINVAL);
    /* 0.1's size, which ended before delimiter, is still read (with the
     * default separators); this release's reads a decimal comma. */
    put_file(at("eu.xyz"), "0,5 0 0\n1 0 0\n0 1 0\n0 0 1\n");
    fdt_read_options old;
    memset(&old, 0x5a, sizeof old); /* the bytes a 0.1 caller does not have */
    CHECK_EQ(fdt_default_read_options_sized(&old, offsetof(fdt_read_options, delimiter)),
             FDT_OK);
    CHECK_EQ(fdt_read_points_opts(at("a.csv"), &old, &xyz, &n, diag, sizeof diag), FDT_OK);
    CHECK_EQ(n, 3);
    fdt_free(xyz);
    CHECK_EQ(fdt_read_points_opts(at("eu.xyz"), &old, &xyz, &n, diag, sizeof diag),
             FDT_EFORMAT);
    CHECK(strstr(diag, "eu.xyz:1:") != NULL && strstr(diag, "--decimal-comma") != NULL);
    fdt_default_read_options(&o);
    o.decimal_comma = 1;
    CHECK_EQ(fdt_read_points_opts(at("eu.xyz"), &o, &xyz, &n, diag, sizeof diag), FDT_OK);
    CHECK(n == 4 && xyz[0] == 0.5);
    fdt_free(xyz);
    o.delimiter = ',';
    CHECK_EQ(fdt_read_points_opts(at("eu.xyz"), &o, &xyz, &n, diag, sizeof diag), FDT_EINVAL);
    CHECK(strstr(diag, "decimal comma cannot also separate") != NULL);
    o.decimal_comma = 0;
    o.delimiter = '|';
    CHECK_EQ(fdt_read_points_opts(at("eu.xyz"), &o, &xyz, &n, diag, sizeof diag), FDT_EINVAL);
    CHECK(strstr(diag, "the delimiter is") != NULL);
    /* NULL options: the defaults */
    CHECK_EQ(fdt_read_points_opts(at("a.csv"), NULL, &xyz, &n, diag, sizeof diag), FDT_OK);
    CHECK_EQ(n, 3);
    fdt_free(xyz);
    fdt_free(NULL);
}

/* ------------------------------------------------------------------------ */
/* Writing                                                                   */
/* ------------------------------------------------------------------------ */

/* The unit cube's corners, its centre and a copy of corner 0 (a duplicate,
 * merged into 0 and left out of OpenFOAM's points). */
static const double cube[] = {
    0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1, 1, 1, 1,
    0.5, 0.5, 0.5, 0, 0, 0,
};
#define CUBE_N 10

/* Does the tet (a b c d) appear in r, as a set of ids? */
static int has_tet(const fdt_result *r, const long long *v)
{
    const fdt_vid *t = fdt_result_tets(r);
    for (size_t i = 0; i < fdt_result_num_tets(r); i++) {
        int hit = 0;
        for (int a = 0; a < 4; a++)
            for (int b = 0; b < 4; b++)
                hit += t[4 * i + a] == v[b];
        if (hit == 4)
            return 1;
    }
    return 0;
}

static uint64_t fnv1a(const char *s, size_t len)
{
    uint64_t h = 14695981039346656037ULL;
    for (size_t i = 0; i < len; i++) {
        h ^= (unsigned char)s[i];
        h *= 1099511628211ULL;
    }
    return h;
}

static void test_write_formats(void)
{
    char diag[1024];
    fdt_result *r = test_triangulate(cube, CUBE_N, 1, 1);
    size_t T = fdt_result_num_tets(r), H = fdt_result_num_hull_faces(r);
    CHECK(T >= 12 && H == 12); /* the centre cones each of 12 triangles */
    CHECK_EQ(fdt_result_num_duplicates(r), 1);

    /* .tets: the canonical bytes, whose FNV-1a is fdt_result_hash. */
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, at("m.tets"), NULL, diag, sizeof diag), FDT_OK);
    CHECK(diag[0] == '\0');
    size_t len;
    char *text = test_slurp(at("m.tets"), &len);
    CHECK(text != NULL);
    uint64_t h;
    CHECK_EQ(fdt_result_hash(r, &h), FDT_OK);
    CHECK(fnv1a(text, len) == h);
    size_t lines = 0;
    for (size_t i = 0; i < len; i++)
        lines += text[i] == '\n';
    CHECK_EQ(lines, T);
    free(text);

    /* TetGen: BASE.node read back by fdt_read_points gives every input
     * point; BASE.ele holds the result's tets, 0-based, in its order. */
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, at("m.ele"), NULL, diag, sizeof diag), FDT_OK);
    double *xyz = NULL;
    size_t n = 0;
    CHECK_EQ(fdt_read_points(at("m.node"), NULL, &xyz, &n, diag, sizeof diag), FDT_OK);
    CHECK_EQ(n, CUBE_N);
    CHECK(memcmp(xyz, cube, sizeof cube) == 0);
    fdt_free(xyz);
    text = test_slurp(at("m.ele"), NULL);
    CHECK(text != NULL);
    const char *p = text;
    while (*p == '#')
        p = skip_lines(p, 1);
    long long hdr[3];
    ints(&p, hdr, 3);
    CHECK(hdr[0] == (long long)T && hdr[1] == 4 && hdr[2] == 0);
    const fdt_vid *tets = fdt_result_tets(r);
    for (size_t t = 0; t < T; t++) {
        long long row[5];
        ints(&p, row, 5);
        CHECK_EQ(row[0], t);
        for (int k = 0; k < 4; k++)
            CHECK_EQ(row[1 + k], tets[4 * t + (size_t)k]);
    }
    free(text);
    CHECK(access(at("m.face"), F_OK) == 0 && access(at("m.neigh"), F_OK) == 0);

    /* gmsh 4.1: nodes 1..n (every input point), tets then hull triangles,
     * ids + 1. */
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, at("m.msh"), NULL, diag, sizeof diag), FDT_OK);
    text = test_slurp(at("m.msh"), NULL);
    CHECK(strncmp(text, "$MeshFormat\n4.1 0 8\n", 20) == 0);
    p = after_line(text, "$Nodes");
    CHECK(p != NULL);
    long long nb[8];
    ints(&p, nb, 8); /* blocks, nodes, min tag, max tag; dim, tag, param, count */
    CHECK(nb[0] == 1 && nb[1] == CUBE_N && nb[2] == 1 && nb[3] == CUBE_N);
    CHECK(nb[4] == 3 && nb[7] == CUBE_N);
    for (long long i = 1; i <= CUBE_N; i++) {
        long long tag;
        ints(&p, &tag, 1);
        CHECK_EQ(tag, i);
    }
    p = after_line(text, "$Elements");
    CHECK(p != NULL);
    long long eb[4];
    ints(&p, eb, 4);
    CHECK(eb[0] == 2 && eb[1] == (long long)(T + H) && eb[2] == 1 &&
          eb[3] == (long long)(T + H));
    long long blk[4];
    ints(&p, blk, 4);
    CHECK(blk[0] == 3 && blk[2] == 4 && blk[3] == (long long)T);
    for (size_t t = 0; t < T; t++) {
        long long row[5];
        ints(&p, row, 5);
        CHECK_EQ(row[0], t + 1);
        for (int k = 0; k < 4; k++)
            CHECK_EQ(row[1 + k] - 1, tets[4 * t + (size_t)k]);
    }
    ints(&p, blk, 4);
    CHECK(blk[0] == 2 && blk[2] == 2 && blk[3] == (long long)H);
    free(text);

    /* gmsh 2.2 (by name only): "i x y z" nodes, "id type 2 phys elem ids". */
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, at("m2.msh"), "msh2", diag, sizeof diag), FDT_OK);
    text = test_slurp(at("m2.msh"), NULL);
    CHECK(strncmp(text, "$MeshFormat\n2.2 0 8\n", 20) == 0);
    p = after_line(text, "$Nodes");
    long long cnt;
    ints(&p, &cnt, 1);
    CHECK_EQ(cnt, CUBE_N);
    for (long long i = 1; i <= CUBE_N; i++) {
        long long tag;
        ints(&p, &tag, 1);
        CHECK_EQ(tag, i);
        p = skip_lines(p, 1);
    }
    p = after_line(text, "$Elements");
    ints(&p, &cnt, 1);
    CHECK_EQ(cnt, T + H);
    const fdt_vid *hull = fdt_result_hull_faces(r);
    for (size_t e = 0; e < T + H; e++) {
        long long row[9];
        int tet = e < T;
        ints(&p, row, tet ? 9 : 8);
        CHECK_EQ(row[0], e + 1);
        CHECK_EQ(row[1], tet ? 4 : 2);
        CHECK_EQ(row[2], 2);
        for (int k = 0; k < (tet ? 4 : 3); k++)
            CHECK_EQ(row[5 + k] - 1, tet ? tets[4 * e + (size_t)k] : hull[3 * (e - T) + (size_t)k]);
    }
    free(text);

    /* Medit: counts, 1-based tets. */
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, at("m.mesh"), NULL, diag, sizeof diag), FDT_OK);
    text = test_slurp(at("m.mesh"), NULL);
    p = after_line(text, "Vertices");
    CHECK(p != NULL);
    ints(&p, &cnt, 1);
    CHECK_EQ(cnt, CUBE_N);
    p = after_line(text, "Tetrahedra");
    CHECK(p != NULL);
    ints(&p, &cnt, 1);
    CHECK_EQ(cnt, T);
    for (size_t t = 0; t < T; t++) {
        long long row[5];
        ints(&p, row, 5);
        for (int k = 0; k < 4; k++)
            CHECK_EQ(row[k] - 1, tets[4 * t + (size_t)k]);
        CHECK_EQ(row[4], 1);
    }
    p = after_line(text, "Triangles");
    CHECK(p != NULL);
    ints(&p, &cnt, 1);
    CHECK_EQ(cnt, H);
    CHECK(strstr(text, "\nEnd\n") != NULL);
    free(text);

    /* VTK legacy and XML: the counts in their headers. */
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, at("m.vtk"), NULL, diag, sizeof diag), FDT_OK);
    text = test_slurp(at("m.vtk"), NULL);
    char want[128];
    snprintf(want, sizeof want, "POINTS %d double", CUBE_N);
    CHECK(strstr(text, want) != NULL);
    snprintf(want, sizeof want, "CELLS %zu %zu", T, 5 * T);
    CHECK(strstr(text, want) != NULL);
    free(text);
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, at("m.vtu"), NULL, diag, sizeof diag), FDT_OK);
    text = test_slurp(at("m.vtu"), NULL);
    snprintf(want, sizeof want, "NumberOfPoints=\"%d\" NumberOfCells=\"%zu\"", CUBE_N, T);
    CHECK(strstr(text, want) != NULL);
    free(text);

    /* OpenFOAM: the used points only; every face once; owner < neighbour;
     * internal faces in upper-triangular order (by owner, then
     * neighbour), then the hull patch. */
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, at("case/polyMesh"), NULL, diag, sizeof diag),
             FDT_EIO); /* case/ does not exist */
    CHECK(strstr(diag, "case/polyMesh") != NULL);
    CHECK(mkdir(at("case"), 0777) == 0);
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, at("case/polyMesh"), NULL, diag, sizeof diag),
             FDT_OK);
    size_t F = (4 * T + H) / 2, I = F - H;
    text = test_slurp(at("case/polyMesh/points"), NULL);
    p = strstr(text, "}\n");
    CHECK(p != NULL);
    ints(&p, &cnt, 1);
    CHECK_EQ(cnt, CUBE_N - 1);
    free(text);
    text = test_slurp(at("case/polyMesh/faces"), NULL);
    p = strstr(text, "}\n");
    ints(&p, &cnt, 1);
    CHECK_EQ(cnt, F);
    free(text);
    char *own = test_slurp(at("case/polyMesh/owner"), NULL);
    char *nei = test_slurp(at("case/polyMesh/neighbour"), NULL);
    CHECK(own != NULL && nei != NULL);
    const char *po = strstr(own, "}\n"), *pn = strstr(nei, "}\n");
    ints(&po, &cnt, 1);
    CHECK_EQ(cnt, F);
    ints(&pn, &cnt, 1);
    CHECK_EQ(cnt, I);
    long long prev_o = -1, prev_n = -1;
    for (size_t i = 0; i < I; i++) {
        long long o, nb1;
        ints(&po, &o, 1);
        ints(&pn, &nb1, 1);
        CHECK(o >= 0 && o < nb1 && nb1 < (long long)T);
        CHECK(o > prev_o || (o == prev_o && nb1 > prev_n));
        prev_o = o;
        prev_n = nb1;
    }
    for (size_t i = I; i < F; i++) {
        long long o;
        ints(&po, &o, 1);
        CHECK(o >= 0 && o < (long long)T);
    }
    free(own);
    free(nei);
    text = test_slurp(at("case/polyMesh/boundary"), NULL);
    snprintf(want, sizeof want, "nFaces          %zu;", H);
    CHECK(strstr(text, want) != NULL);
    snprintf(want, sizeof want, "startFace       %zu;", I);
    CHECK(strstr(text, want) != NULL);
    free(text);

    /* TetGen -f: every face in .face. */
    fdt_write_options wo;
    fdt_default_write_options(&wo);
    CHECK_EQ(wo.struct_size, sizeof wo);
    wo.all_faces = 1;
    CHECK_EQ(fdt_write_mesh_opts(r, cube, CUBE_N, at("f.ele"), &wo, diag, sizeof diag), FDT_OK);
    text = test_slurp(at("f.face"), NULL);
    p = text;
    while (*p == '#')
        p = skip_lines(p, 1);
    ints(&p, &cnt, 1);
    CHECK_EQ(cnt, F);
    free(text);
    CHECK_EQ(count_temps(dir), 0);
    CHECK_EQ(count_temps(at("case/polyMesh")), 0);
    fdt_result_free(&r);
}

/* .tets of a result not yet sorted: the writer sorts it (documented). */
static void test_write_sorts(void)
{
    enum { N = 300 };
    double *pts = malloc(3 * N * sizeof *pts);
    CHECK(pts != NULL);
    uint64_t seed = 7;
    for (int i = 0; i < 3 * N; i++)
        pts[i] = test_unif(&seed);
    fdt_result *r = test_triangulate(pts, N, 1, 0);
    char diag[512];
    /* tetgen needs neighbours: refused before any file is made */
    CHECK_EQ(fdt_write_mesh(r, pts, N, at("nn.ele"), NULL, diag, sizeof diag), FDT_EINVAL);
    CHECK(strstr(diag, "neighbours") != NULL);
    CHECK(access(at("nn.node"), F_OK) != 0 && access(at("nn.ele"), F_OK) != 0);
    CHECK_EQ(fdt_write_mesh(r, pts, N, at("s.tets"), NULL, diag, sizeof diag), FDT_OK);
    char *text = test_slurp(at("s.tets"), NULL);
    const char *p = text;
    long long prev[4] = {-1, -1, -1, -1};
    const fdt_vid *t = fdt_result_tets(r); /* again: the write sorted r */
    for (size_t i = 0; i < fdt_result_num_tets(r); i++) {
        long long v[4];
        ints(&p, v, 4);
        CHECK(v[0] < v[1] && v[1] < v[2] && v[2] < v[3]);
        CHECK(memcmp(prev, v, sizeof v) < 0 || prev[0] < v[0] ||
              (prev[0] == v[0] && (prev[1] < v[1] || (prev[1] == v[1] && (prev[2] < v[2] ||
              (prev[2] == v[2] && prev[3] < v[3]))))));
        CHECK(has_tet(r, v));
        long long mine[4] = {t[4 * i], t[4 * i + 1], t[4 * i + 2], t[4 * i + 3]};
        CHECK(has_tet(r, mine));
        memcpy(prev, v, sizeof v);
    }
    free(text);
    fdt_result_free(&r);
    free(pts);
}

/* Failures: the code, the file named, nothing left behind. */
static void test_write_errors(void)
{
    char diag[1024];
    fdt_result *r = test_triangulate(cube, CUBE_N, 1, 1);
    /* a missing directory */
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, at("nodir/m.vtu"), NULL, diag, sizeof diag),
             FDT_EIO);
    CHECK(strstr(diag, "nodir/m.vtu") != NULL);
    /* the message says what is missing (issue 34 item 8) */
    CHECK(strstr(diag, "cannot create output ") != NULL &&
          strstr(diag, "nodir does not exist") != NULL);
    /* a regular file where a directory should be */
    put_file(at("plain"), "x");
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, at("plain/m.msh"), NULL, diag, sizeof diag),
             FDT_EIO);
    CHECK(strstr(diag, "plain/m.msh") != NULL);
    /* a directory no one may write into (root may: then only the rest) */
    CHECK(mkdir(at("ro"), 0555) == 0 || errno == EEXIST);
    CHECK(chmod(at("ro"), 0555) == 0);
    if (geteuid() != 0) {
        CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, at("ro/m.ele"), NULL, diag, sizeof diag),
                 FDT_EIO);
        CHECK(strstr(diag, "ro/m.") != NULL);
        CHECK_EQ(count_temps(at("ro")), 0);
        CHECK(access(at("ro/m.node"), F_OK) != 0);
    }
    CHECK(chmod(at("ro"), 0755) == 0);
    /* the target is an existing directory */
    CHECK(mkdir(at("isdir.tets"), 0777) == 0 || errno == EEXIST);
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, at("isdir.tets"), NULL, diag, sizeof diag),
             FDT_EIO);
    CHECK_EQ(count_temps(dir), 0);
    /* a new polyMesh whose temporary directory's name cannot fit a path
     * (the target itself still would): ENAMETOOLONG, nothing made */
    static char longp[4200], ldiag[4400];
    int w = snprintf(longp, sizeof longp, "%s", dir);
    while (w < 4080)
        w += snprintf(longp + w, sizeof longp - (size_t)w, "/%.*s", 4080 - w > 200 ? 200 : 4080 - w,
                      "dddddddddddddddddddddddddddddddddddddddddddddddddddddddddddddddddddddddddddd"
                      "dddddddddddddddddddddddddddddddddddddddddddddddddddddddddddddddddddddddddddd"
                      "dddddddddddddddddddddddddddddddddddddddddddddddd");
    snprintf(longp + w, sizeof longp - (size_t)w, "/polyMesh");
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, longp, "openfoam", ldiag, sizeof ldiag), FDT_EIO);
    CHECK(strstr(ldiag, strerror(ENAMETOOLONG)) != NULL);
    CHECK_EQ(count_temps(dir), 0);

    /* the caller's mistakes: FDT_EINVAL, no file made */
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, at("m.stl"), NULL, diag, sizeof diag), FDT_EINVAL);
    CHECK(strstr(diag, "m.stl") != NULL && strstr(diag, "unknown output format") != NULL);
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, at("m.x"), "stl", diag, sizeof diag), FDT_EINVAL);
    CHECK(strstr(diag, "unknown format") != NULL);
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N - 1, at("m2.vtk"), NULL, diag, sizeof diag),
             FDT_EINVAL);
    CHECK(access(at("m2.vtk"), F_OK) != 0);
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, "-", "vtu", diag, sizeof diag), FDT_EINVAL);
    CHECK(strstr(diag, "stdout") != NULL);
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, "-", NULL, diag, sizeof diag), FDT_EINVAL);
    CHECK_EQ(fdt_write_mesh(NULL, cube, CUBE_N, at("m.vtk"), NULL, diag, sizeof diag),
             FDT_EINVAL);
    CHECK_EQ(fdt_write_mesh(r, NULL, CUBE_N, at("m.vtk"), NULL, diag, sizeof diag), FDT_EINVAL);
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, NULL, NULL, diag, sizeof diag), FDT_EINVAL);
    fdt_write_options big;
    CHECK_EQ(fdt_default_write_options_sized(&big, sizeof big - 1), FDT_EINVAL);
    CHECK_EQ(big.struct_size, 0);
    CHECK_EQ(fdt_write_mesh_opts(r, cube, CUBE_N, at("m.vtk"), &big, diag, sizeof diag),
             FDT_EINVAL);
    CHECK(strstr(diag, "size") != NULL);
    CHECK(strcmp(fdt_strerror(FDT_EIO), "unknown error") != 0);
    CHECK(strcmp(fdt_strerror(FDT_EFORMAT), "unknown error") != 0);
    CHECK_EQ(count_temps(dir), 0);

    /* An existing target is replaced; a symbolic link at the target is
     * replaced by the file, and what it pointed to is left alone. */
    put_file(at("old.vtk"), "old");
    put_file(at("keep.txt"), "keep");
    unlink(at("link.vtk"));
    CHECK(symlink("keep.txt", at("link.vtk")) == 0);
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, at("old.vtk"), NULL, diag, sizeof diag), FDT_OK);
    CHECK_EQ(fdt_write_mesh(r, cube, CUBE_N, at("link.vtk"), NULL, diag, sizeof diag), FDT_OK);
    char *text = test_slurp(at("keep.txt"), NULL);
    CHECK(strcmp(text, "keep") == 0);
    free(text);
    text = test_slurp(at("old.vtk"), NULL);
    CHECK(strncmp(text, "# vtk DataFile", 14) == 0);
    free(text);
    struct stat st;
    CHECK(lstat(at("link.vtk"), &st) == 0 && S_ISREG(st.st_mode));
    fdt_result_free(&r);
}

/* The write progress: bytes through every flush, moving forward, ending at
 * the files' size, within the estimate's reach. */
static void test_write_progress(void)
{
    enum { N = 20000 };
    double *pts = malloc(3 * N * sizeof *pts);
    CHECK(pts != NULL);
    uint64_t seed = 11;
    for (int i = 0; i < 3 * N; i++)
        pts[i] = test_unif(&seed);
    fdt_result *r = test_triangulate(pts, N, 1, 1);
    const char *fmts[] = {"tets", "tetgen", "vtu", "vtk", "msh", "msh2", "medit", "openfoam"};
    const char *names[] = {"p.tets", "p.ele", "p.vtu", "p.vtk", "p.msh", "p2.msh", "p.mesh",
                           "pcase/polyMesh"};
    const char *files[][5] = {
        {"p.tets"}, {"p.node", "p.ele", "p.face", "p.neigh"}, {"p.vtu"}, {"p.vtk"},
        {"p.msh"}, {"p2.msh"}, {"p.mesh"},
        {"pcase/polyMesh/points", "pcase/polyMesh/faces", "pcase/polyMesh/owner",
         "pcase/polyMesh/neighbour", "pcase/polyMesh/boundary"}};
    CHECK(mkdir(at("pcase"), 0777) == 0 || errno == EEXIST);
    for (int f = 0; f < 8; f++) {
        fdt_write_options wo;
        fdt_default_write_options(&wo);
        wo.format = fmts[f];
        seen s;
        memset(&s, 0, sizeof s);
        wo.progress = on_progress;
        wo.progress_user = &s;
        char diag[512];
        CHECK_EQ(fdt_write_mesh_opts(r, pts, N, at(names[f]), &wo, diag, sizeof diag), FDT_OK);
        uint64_t bytes = 0;
        for (int k = 0; k < 5 && files[f][k]; k++) {
            struct stat st;
            CHECK(stat(at(files[f][k]), &st) == 0);
            bytes += (uint64_t)st.st_size;
        }
        CHECK(s.calls[FDT_STAGE_WRITE] >= 2); /* every file is over 1 MiB or so */
        CHECK(s.calls[FDT_STAGE_LOAD] == 0 && s.calls[FDT_STAGE_PARSE] == 0);
        CHECK(!s.backwards);
        CHECK_EQ(s.last_done[FDT_STAGE_WRITE], bytes);
        /* the estimate (as first reported, before any correction to
         * what is done): within a factor two of the truth */
        uint64_t est = s.first_total[FDT_STAGE_WRITE];
        CHECK(est >= bytes / 2 && est <= 2 * bytes);
        CHECK(s.last_total[FDT_STAGE_WRITE] >= bytes);
        fprintf(stderr, "write progress %s: %d calls, %llu bytes, estimate %llu\n", fmts[f],
                s.calls[FDT_STAGE_WRITE], (unsigned long long)bytes,
                (unsigned long long)est);
    }
    fdt_result_free(&r);
    free(pts);
}

/* A file that cannot grow past a few hundred bytes (RLIMIT_FSIZE, SIGXFSZ
 * ignored: write(2) fails with EFBIG), in every format: FDT_EIO naming
 * the file, no temporary left, no target made (a TetGen set or an
 * OpenFOAM directory not half written either). 20,000 points: every
 * format writes several MB, past the writer's 1 MiB buffer, so the first
 * flush fails inside a format's loops and the loops after it see the
 * error (3,000 points fit the buffer: the error came only at close). */
static void test_write_full(void)
{
    enum { N = 20000 };
    static double pts[3 * N];
    uint64_t seed = 77;
    for (size_t i = 0; i < 3 * N; i++)
        pts[i] = test_unif(&seed);
    fdt_result *r = test_triangulate(pts, N, 1, 1);
    static const char *const fmts[][2] = {{"tets", "full.tets"},   {"vtk", "full.vtk"},
                                          {"vtu", "full.vtu"},     {"msh", "full.msh"},
                                          {"msh2", "full2.msh"},   {"medit", "full.mesh"},
                                          {"tetgen", "full.ele"},  {"openfoam", "fullfoam"}};
    CHECK(mkdir(at("full"), 0777) == 0 || errno == EEXIST);
    void (*old)(int) = signal(SIGXFSZ, SIG_IGN);
    struct rlimit lim0, lim;
    CHECK(getrlimit(RLIMIT_FSIZE, &lim0) == 0);
    for (size_t i = 0; i < sizeof fmts / sizeof fmts[0]; i++) {
        char path[64], diag[1024] = "";
        snprintf(path, sizeof path, "full/%s", fmts[i][1]);
        lim = lim0;
        lim.rlim_cur = 300;
        CHECK(setrlimit(RLIMIT_FSIZE, &lim) == 0);
        int rc = fdt_write_mesh(r, pts, N, at(path), fmts[i][0], diag, sizeof diag);
        CHECK(setrlimit(RLIMIT_FSIZE, &lim0) == 0);
        EXPECTF(rc == FDT_EIO && strstr(diag, "full/") != NULL,
                "%s under a 300-byte file limit: %d, %s", fmts[i][0], rc, diag);
        EXPECTF(count_temps(at("full")) == 0 && count_entries(at("full")) == 0,
                "%s: files left after the failure", fmts[i][0]);
    }
    signal(SIGXFSZ, old);
    fdt_result_free(&r);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: test_io SCRATCH_DIR\n");
        return 2;
    }
    /* a fresh directory of our own under the scratch directory */
    CHECK(mkdir(argv[1], 0777) == 0 || errno == EEXIST);
    snprintf(dir, sizeof dir, "%s/ioXXXXXX", argv[1]);
    CHECK(mkdtemp(dir) != NULL);
    test_read();
    test_write_formats();
    test_write_sorts();
    test_write_errors();
    test_write_full();
    test_write_progress();
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    CHECK(system(cmd) == 0);
    return test_report("test_io");
}
