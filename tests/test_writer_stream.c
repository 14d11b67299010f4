/*
 * The streaming writers (src/writer_stream.c, include/frontdt.h's
 * fdt_stream_writer_*), through the public API:
 * - each streaming format, fed by fdt_triangulate_stream, commits a file
 *   whose tets are the in-memory run's set (the .fdtb parsed back here and
 *   set-hashed with src/sethash.h's rule, as fdt_result_set_hash);
 * - a writer fed in batches in any order (hull first, tets split) gives
 *   the same .fdtb as fdt_write_mesh for the same tets;
 * - a batch naming a point that is not there stops the run (the sink
 *   returns FDT_EINVAL, the run returns it), and the close then removes
 *   every temporary and leaves the target as it was; so does close(0);
 * - formats that cannot stream are refused at open, nothing created.
 * The CLI's streamed files against its in-memory ones, and interrupted
 * streamed writes, are tests/stream_readback.py's.
 */
#include "frontdt.h"
#include "sethash.h"
#include "testutil.h"

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char dir[] = "/tmp/fdt_test_writer_stream_XXXXXX";

static char *path_in(const char *name)
{
    static char p[4][512];
    static int k;
    k = (k + 1) % 4;
    snprintf(p[k], sizeof p[k], "%s/%s", dir, name);
    return p[k];
}

/* Entries in dir, "." and ".." aside. */
static int entries(void)
{
    DIR *d = opendir(dir);
    CHECK(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        n += strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0;
    closedir(d);
    return n;
}

static unsigned char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *b = malloc((size_t)n + 1);
    CHECK(b && fread(b, 1, (size_t)n, f) == (size_t)n);
    fclose(f);
    *len = (size_t)n;
    return b;
}

static uint64_t get_u64(const unsigned char *p)
{
    uint64_t v = 0;
    for (int i = 7; i >= 0; i--)
        v = v << 8 | p[i];
    return v;
}

/* The set hash of a .fdtb's tets (int32 ids, points present), and its
 * counts; 0 tets on a malformed file. */
static uint64_t fdtb_set_hash(const char *path, uint64_t *nt, uint64_t *nh)
{
    size_t len;
    unsigned char *b = slurp(path, &len);
    *nt = *nh = 0;
    if (!b || len < 64 || memcmp(b, "FDTMESH", 8) != 0) {
        free(b);
        return 0;
    }
    uint64_t n = get_u64(b + 16), t = get_u64(b + 24), h = get_u64(b + 32);
    if (len != 64 + 24 * n + 16 * t + 12 * h) {
        free(b);
        return 0;
    }
    fdt_sethash s = {0, 0};
    for (uint64_t i = 0; i < t; i++) {
        uint32_t v[4];
        for (int k = 0; k < 4; k++)
            v[k] = (uint32_t)get_u64(b + 64 + 24 * n + 16 * i + 4 * (uint64_t)k) & 0xffffffffu;
        fdt_sethash_add(&s, v);
    }
    free(b);
    *nt = t;
    *nh = h;
    return fdt_sethash_value(&s);
}

static int write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f)
        return 0;
    fputs(text, f);
    return fclose(f) == 0;
}

/* A sink that passes batches on to a writer's but poisons the k-th tet
 * batch with an id out of range. */
typedef struct poison {
    fdt_sink inner;
    int k, seen;
} poison;

static int poison_tets(void *user, const fdt_vid *t, size_t count)
{
    poison *p = user;
    if (p->seen++ == p->k && count > 0) {
        fdt_vid bad[4] = {t[0], t[1], t[2], 1 << 30};
        return p->inner.tets(p->inner.user, bad, 1);
    }
    return p->inner.tets(p->inner.user, t, count);
}

static int poison_hull(void *user, const fdt_vid *f, size_t count)
{
    poison *p = user;
    return p->inner.hull(p->inner.user, f, count);
}

int main(void)
{
    CHECK(mkdtemp(dir));
    uint64_t seed = 18;
    size_t n = 4000;
    double *xyz = malloc(3 * n * sizeof *xyz);
    CHECK(xyz);
    for (size_t i = 0; i < 3 * n; i++)
        xyz[i] = test_unif(&seed);

    fdt_settings s;
    fdt_default_settings(&s);
    s.n_threads = 2;
    fdt_context *ctx = NULL;
    CHECK(fdt_open(&ctx, &s) == FDT_OK);
    fdt_result *mem = NULL;
    CHECK(fdt_triangulate(ctx, xyz, n, &mem) == FDT_OK);
    uint64_t want = 0;
    CHECK(fdt_result_set_hash(mem, &want) == FDT_OK);
    char diag[1024];

    /* Which formats stream. */
    EXPECT(fdt_stream_format_ok("a.vtu", NULL) == 1);
    EXPECT(fdt_stream_format_ok("a.ELE", NULL) == 1);
    EXPECT(fdt_stream_format_ok("a.fdtb", NULL) == 1);
    EXPECT(fdt_stream_format_ok("a.x", "bin") == 1);
    EXPECT(fdt_stream_format_ok("a.tets", NULL) == 0);
    EXPECT(fdt_stream_format_ok("a.msh", NULL) == 0);
    EXPECT(fdt_stream_format_ok("c/polyMesh", NULL) == 0);
    EXPECT(fdt_stream_format_ok("a.x", NULL) == FDT_EINVAL);
    fdt_stream_writer *w = NULL;
    EXPECT(fdt_stream_writer_open(&w, path_in("a.tets"), NULL, xyz, n, 0, diag,
                                  sizeof diag) == FDT_EINVAL && !w && strstr(diag, "stream"));
    EXPECT(entries() == 0);

    /* Every streaming format through fdt_triangulate_stream: the .fdtb
     * holds the in-memory set; the others commit their files. */
    const char *outs[] = {"a.fdtb", "a.vtu", "a.ele"};
    for (int o = 0; o < 3; o++) {
        CHECK(fdt_stream_writer_open(&w, path_in(outs[o]), NULL, xyz, n, 0, diag,
                                     sizeof diag) == FDT_OK);
        fdt_sink sink;
        CHECK(fdt_stream_writer_sink(w, &sink) == FDT_OK);
        fdt_result *sr = NULL;
        EXPECTF(fdt_triangulate_stream(ctx, xyz, n, &sink, &sr) == FDT_OK, "%s", outs[o]);
        uint64_t nt = 0, nh = 0, sh = 0;
        fdt_stream_writer_counts(w, &nt, &nh);
        EXPECT(nt == fdt_result_num_tets(mem) && nh == fdt_result_num_hull_faces(mem));
        EXPECT(fdt_result_set_hash(sr, &sh) == FDT_OK && sh == want);
        EXPECTF(fdt_stream_writer_close(&w, 1, diag, sizeof diag) == FDT_OK, "%s", diag);
        EXPECT(w == NULL);
        fdt_result_free(&sr);
    }
    uint64_t nt, nh;
    EXPECT(fdtb_set_hash(path_in("a.fdtb"), &nt, &nh) == want);
    EXPECT(nt == fdt_result_num_tets(mem) && nh == fdt_result_num_hull_faces(mem));
    /* .vtu, .node, .ele, .face; a.fdtb: 5 files, no temporary */
    EXPECTF(entries() == 5, "%d entries", entries());

    /* Batches in any order (hull first, tets in two pieces) give the
     * in-memory writer's bytes for the same tets. */
    CHECK(fdt_write_mesh(mem, xyz, n, path_in("m.fdtb"), NULL, diag, sizeof diag) == FDT_OK);
    CHECK(fdt_stream_writer_open(&w, path_in("b.fdtb"), NULL, xyz, n, 0, diag, sizeof diag) ==
          FDT_OK);
    fdt_sink sink;
    CHECK(fdt_stream_writer_sink(w, &sink) == FDT_OK);
    size_t t = fdt_result_num_tets(mem), h = fdt_result_num_hull_faces(mem);
    const fdt_vid *tets = fdt_result_tets(mem);
    EXPECT(sink.hull(sink.user, fdt_result_hull_faces(mem), h) == 0);
    EXPECT(sink.tets(sink.user, tets, t / 3) == 0);
    EXPECT(sink.tets(sink.user, tets + 4 * (t / 3), t - t / 3) == 0);
    EXPECT(fdt_stream_writer_close(&w, 1, diag, sizeof diag) == FDT_OK);
    size_t la, lb;
    unsigned char *a = slurp(path_in("m.fdtb"), &la), *b = slurp(path_in("b.fdtb"), &lb);
    EXPECT(a && b && la == lb && memcmp(a, b, la) == 0);
    free(a);
    free(b);

    /* A bad batch stops the run; nothing is left, the target stays. */
    int before = entries();
    for (int o = 0; o < 3; o++) {
        CHECK(write_file(path_in(outs[o]), "old\n"));
        CHECK(fdt_stream_writer_open(&w, path_in(outs[o]), NULL, xyz, n, 0, diag,
                                     sizeof diag) == FDT_OK);
        poison p = {.k = 0};
        CHECK(fdt_stream_writer_sink(w, &p.inner) == FDT_OK);
        fdt_sink ps = {sizeof ps, poison_tets, poison_hull, &p};
        fdt_result *sr = NULL;
        EXPECT(fdt_triangulate_stream(ctx, xyz, n, &ps, &sr) == FDT_EINVAL && sr == NULL);
        EXPECT(fdt_stream_writer_close(&w, 1, diag, sizeof diag) == FDT_EINVAL &&
               strstr(diag, "outside"));
        size_t len;
        unsigned char *old = slurp(path_in(outs[o]), &len);
        EXPECTF(old && len == 4 && memcmp(old, "old\n", 4) == 0, "%s", outs[o]);
        free(old);
        EXPECTF(entries() == before, "%s: %d entries, %d before", outs[o], entries(), before);
    }
    /* close(0): an abandoned write leaves nothing. */
    CHECK(fdt_stream_writer_open(&w, path_in("c.vtu"), NULL, xyz, n, 0, diag, sizeof diag) ==
          FDT_OK);
    EXPECT(entries() == before + 1); /* its temporary */
    EXPECT(fdt_stream_writer_close(&w, 0, diag, sizeof diag) == FDT_OK);
    EXPECT(entries() == before);
    EXPECT(access(path_in("c.vtu"), F_OK) != 0);

    fdt_result_free(&mem);
    fdt_close(&ctx);
    free(xyz);
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0)
        fprintf(stderr, "could not remove %s\n", dir);
    return test_report("writer_stream");
}
