/*
 * The streaming writers (src/io/write/writer_stream.c, include/frontdt.h's
 * fdt_stream_writer_*), through the public API:
 * - each streaming format, fed by fdt_triangulate_stream, commits a file
 *   whose tets are the in-memory run's set (the .fdtb parsed back here and
 *   set-hashed with src/base/sethash.h's rule, as fdt_result_set_hash);
 * - a writer fed in batches in any order (hull first, tets split) gives
 *   the same .fdtb as fdt_write_mesh for the same tets;
 * - a batch naming a point that is not there stops the run (the sink
 *   returns FDT_EINVAL, the run returns it), and the close then removes
 *   every temporary and leaves the target as it was; so does close(0);
 * - formats that cannot stream are refused at open, nothing created;
 * - .fdtb's flags: 64-bit ids and no points, the header and arrays read
 *   back; hull batches larger than the first growth of its buffer and
 *   than its second;
 * - refusals at open (NULL arguments, unknown format or flags, a path
 *   too long, every temporary slot taken in the middle of a TetGen set)
 *   and bad batches (NULL, a hull face's id out of range): EINVAL or EIO,
 *   nothing left on disk, every later call refused with the first error;
 * - writes failing part-way (a file size limit, EFBIG, as a full disk's
 *   ENOSPC): in the header's points at open, in a batch of tets (the sink
 *   returns FDT_EIO), in the final flush and count patch at the commit;
 *   a rename that fails at the commit (the target a non-empty
 *   directory), in the middle of a TetGen set too: FDT_EIO with the file
 *   and the reason named, no temporary left, the old targets intact
 *   where the rename never reached them; a stale .neigh removed at the
 *   commit, and a .neigh that cannot be removed reported.
 * The CLI's streamed files against its in-memory ones, and interrupted
 * streamed writes, are tests/stream_readback.py's.
 */
#include "frontdt.h"
#include "base/sethash.h"
#include "testutil.h"
#include "testdir.h"

#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
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
    int n = count_entries(dir);
    CHECK(n >= 0);
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

/* Whether the file at path holds exactly text. */
static int holds(const char *path, const char *text)
{
    size_t len;
    unsigned char *b = slurp(path, &len);
    int ok = b && len == strlen(text) && memcmp(b, text, len) == 0;
    free(b);
    return ok;
}

/* .fdtb with FDT_STREAM_IDS64, with and without the points: the flags,
 * the counts and the arrays in their 64-bit little-endian form; a hull
 * batch bigger than the buffer's first growth (3 x 4096 ids). */
static void test_bin_flags(const double *xyz, size_t n, const fdt_result *mem)
{
    char diag[1024];
    const fdt_vid *tets = fdt_result_tets(mem);
    size_t t = fdt_result_num_tets(mem), h = fdt_result_num_hull_faces(mem);
    /* the hull faces repeated: 10000 in one batch */
    size_t hb = 10000;
    fdt_vid *hull = malloc(3 * hb * sizeof *hull);
    CHECK(hull);
    for (size_t i = 0; i < 3 * hb; i++)
        hull[i] = fdt_result_hull_faces(mem)[i % (3 * h)];
    for (int pts = 0; pts < 2; pts++) {
        int flags = FDT_STREAM_IDS64 | (pts ? 0 : FDT_STREAM_NO_POINTS);
        const char *name = pts ? "w64.fdtb" : "np64.fdtb";
        fdt_stream_writer *w = NULL;
        CHECK(fdt_stream_writer_open(&w, path_in(name), NULL, xyz, n, flags, diag,
                                     sizeof diag) == FDT_OK);
        fdt_sink sink;
        CHECK(fdt_stream_writer_sink(w, &sink) == FDT_OK);
        EXPECT(sink.tets(sink.user, tets, t) == FDT_OK);
        EXPECT(sink.hull(sink.user, hull, hb) == FDT_OK);
        EXPECT(sink.hull(sink.user, NULL, 0) == FDT_OK); /* an empty batch */
        EXPECT(sink.hull(sink.user, hull, hb) == FDT_OK); /* the buffer doubles */
        EXPECT(fdt_stream_writer_close(&w, 1, diag, sizeof diag) == FDT_OK);
        size_t len;
        unsigned char *b = slurp(path_in(name), &len);
        size_t at = 64 + (pts ? 24 * n : 0);
        CHECK(b);
        EXPECTF(len == at + 32 * t + 48 * hb, "%s: %zu bytes", name, len);
        if (len != at + 32 * t + 48 * hb) {
            free(b);
            continue;
        }
        EXPECT(memcmp(b, "FDTMESH", 8) == 0 && get_u64(b + 8) == (1 | (uint64_t)(1 | 4 | 2 * pts) << 32));
        EXPECT(get_u64(b + 16) == n && get_u64(b + 24) == t && get_u64(b + 32) == 2 * hb);
        if (pts)
            EXPECT(memcmp(b + 64, xyz, 24 * n) == 0);
        size_t bad = 0;
        for (size_t i = 0; i < 4 * t; i++)
            bad += get_u64(b + at + 8 * i) != (uint64_t)tets[i];
        for (size_t i = 0; i < 6 * hb; i++)
            bad += get_u64(b + at + 32 * t + 8 * i) != (uint64_t)hull[i % (3 * hb)];
        EXPECTF(bad == 0, "%s: %zu ids differ", name, bad);
        free(b);
        unlink(path_in(name));
    }
    free(hull);
}

/* What open refuses, and bad batches: nothing is left behind. */
static void test_refusals(const double *xyz, size_t n, const fdt_result *mem)
{
    char diag[1024];
    fdt_stream_writer *w = (fdt_stream_writer *)diag; /* set to NULL on failure */
    int before = entries();
    EXPECT(fdt_stream_writer_open(NULL, path_in("r.fdtb"), NULL, xyz, n, 0, diag,
                                  sizeof diag) == FDT_EINVAL && strstr(diag, "NULL"));
    EXPECT(fdt_stream_writer_open(&w, NULL, NULL, xyz, n, 0, diag, sizeof diag) == FDT_EINVAL);
    EXPECT(fdt_stream_writer_open(&w, path_in("r.fdtb"), NULL, NULL, n, 0, diag,
                                  sizeof diag) == FDT_EINVAL);
    EXPECT(fdt_stream_writer_open(&w, path_in("r.fdtb"), NULL, xyz, n, 0, NULL, 8) ==
           FDT_EINVAL);
    w = (fdt_stream_writer *)diag;
    EXPECT(fdt_stream_writer_open(&w, path_in("r.fdtb"), "nope", xyz, n, 0, diag,
                                  sizeof diag) == FDT_EINVAL && w == NULL &&
           strstr(diag, "unknown output format") && strstr(diag, "bin"));
    EXPECT(fdt_stream_writer_open(&w, path_in("r.fdtb"), NULL, xyz, n, 8, diag,
                                  sizeof diag) == FDT_EINVAL && strstr(diag, "flags"));
    /* a path whose temporary name cannot fit */
    static char longp[5000];
    memset(longp, 'x', sizeof longp - 6);
    memcpy(longp + sizeof longp - 6, ".fdtb", 6);
    static char ldiag[6000]; /* the message holds the path */
    EXPECT(fdt_stream_writer_open(&w, longp, NULL, xyz, n, 0, ldiag, sizeof ldiag) == FDT_EIO &&
           strstr(ldiag, strerror(ENAMETOOLONG)));
    /* a missing directory: the temporary's error, the file named */
    char p[600];
    snprintf(p, sizeof p, "%s/no/such.vtu", dir);
    EXPECT(fdt_stream_writer_open(&w, p, NULL, xyz, n, 0, diag, sizeof diag) == FDT_EIO &&
           strstr(diag, "cannot create output ") && strstr(diag, "no/such.vtu: folder ") &&
           strstr(diag, "/no does not exist"));
    /* the NULLs of the other calls */
    fdt_sink sink;
    EXPECT(fdt_stream_writer_sink(NULL, &sink) == FDT_EINVAL);
    EXPECT(fdt_stream_writer_close(NULL, 1, diag, sizeof diag) == FDT_EINVAL);
    w = NULL;
    EXPECT(fdt_stream_writer_close(&w, 1, diag, sizeof diag) == FDT_EINVAL);
    uint64_t a = 7, b = 7;
    fdt_stream_writer_counts(NULL, &a, &b);
    EXPECT(a == 0 && b == 0);
    EXPECT(entries() == before);

    /* no message buffer at all is fine: the codes alone; the sink and the
     * counts want somewhere to write */
    CHECK(fdt_stream_writer_open(&w, path_in("q.fdtb"), NULL, xyz, n, 0, NULL, 0) == FDT_OK);
    EXPECT(fdt_stream_writer_sink(w, NULL) == FDT_EINVAL);
    CHECK(fdt_stream_writer_sink(w, &sink) == FDT_OK);
    EXPECT(sink.tets(sink.user, NULL, 0) == FDT_OK);
    fdt_stream_writer_counts(w, NULL, NULL);
    fdt_vid neg[4] = {0, 1, 2, -1};
    EXPECT(sink.tets(sink.user, neg, 1) == FDT_EINVAL);
    EXPECT(fdt_stream_writer_close(&w, 1, NULL, 0) == FDT_EINVAL && w == NULL);
    EXPECT(entries() == before);

    /* Every temporary slot taken: ten TetGen sets hold 30 of the 32, the
     * eleventh gets its .node and .ele and fails at its .face; its two
     * temporaries go, the others stay until closed. */
    fdt_stream_writer *ws[10];
    for (int i = 0; i < 10; i++) {
        char name[32];
        snprintf(name, sizeof name, "slot%d.ele", i);
        CHECK(fdt_stream_writer_open(&ws[i], path_in(name), NULL, xyz, n, 0, diag,
                                     sizeof diag) == FDT_OK);
    }
    EXPECT(entries() == before + 30);
    EXPECT(fdt_stream_writer_open(&w, path_in("slotx.ele"), NULL, xyz, n, 0, diag,
                                  sizeof diag) == FDT_EIO && w == NULL &&
           strstr(diag, "slotx.face: ") && strstr(diag, strerror(EMFILE)));
    EXPECTF(entries() == before + 30, "%d entries", entries());
    for (int i = 0; i < 10; i++)
        EXPECT(fdt_stream_writer_close(&ws[i], 0, diag, sizeof diag) == FDT_OK);
    EXPECT(entries() == before);

    /* Bad batches: a NULL one, a hull face out of range; the first error
     * stays, later batches and the commit are refused with it. */
    const fdt_vid *tets = fdt_result_tets(mem);
    for (int k = 0; k < 3; k++) {
        CHECK(fdt_stream_writer_open(&w, path_in("bad.fdtb"), NULL, xyz, n, 0, diag,
                                     sizeof diag) == FDT_OK);
        CHECK(fdt_stream_writer_sink(w, &sink) == FDT_OK);
        const char *want;
        if (k == 0) {
            EXPECT(sink.tets(sink.user, NULL, 1) == FDT_EINVAL);
            want = "a batch of tets is NULL";
        } else if (k == 1) {
            EXPECT(sink.hull(sink.user, NULL, 2) == FDT_EINVAL);
            want = "a batch of hull faces is NULL";
        } else {
            fdt_vid f[3] = {0, 1, (fdt_vid)n};
            EXPECT(sink.hull(sink.user, f, 1) == FDT_EINVAL);
            want = "a hull face uses vertex";
        }
        EXPECT(sink.tets(sink.user, tets, 1) == FDT_EINVAL);
        EXPECT(sink.hull(sink.user, tets, 1) == FDT_EINVAL);
        uint64_t nt = 9, nh = 9;
        fdt_stream_writer_counts(w, &nt, &nh);
        EXPECT(nt == 0 && nh == 0);
        EXPECTF(fdt_stream_writer_close(&w, 1, diag, sizeof diag) == FDT_EINVAL &&
                    strstr(diag, "bad.fdtb: ") && strstr(diag, want),
                "%d: [%s]", k, diag);
        EXPECT(entries() == before);
    }
}

/* A non-empty directory at path: no rename can replace it. */
static void block_with_dir(const char *path)
{
    char keep[600];
    CHECK(mkdir(path, 0755) == 0);
    snprintf(keep, sizeof keep, "%s/keep", path);
    CHECK(write_file(keep, "k\n"));
}

static void unblock(const char *path)
{
    char keep[600];
    snprintf(keep, sizeof keep, "%s/keep", path);
    unlink(keep);
    rmdir(path);
}

/* Writes that fail part-way, renames that fail at the commit. */
static void test_write_errors(const double *xyz, size_t n, const fdt_result *mem)
{
    char diag[1024];
    const fdt_vid *tets = fdt_result_tets(mem);
    size_t t = fdt_result_num_tets(mem);
    fdt_stream_writer *w = NULL;
    fdt_sink sink;
    int before = entries();
    const char *outs[] = {"f.fdtb", "f.vtu", "f.ele"};
    for (int o = 0; o < 3; o++)
        CHECK(write_file(path_in(outs[o]), "old\n"));
    before += 3;

    /* A file size limit of 200 kB (SIGXFSZ ignored, as the CLI does): a
     * write past it fails with EFBIG. */
    struct rlimit old_lim, lim;
    CHECK(getrlimit(RLIMIT_FSIZE, &old_lim) == 0);
    void (*old_h)(int) = signal(SIGXFSZ, SIG_IGN);
    lim = old_lim;
    lim.rlim_cur = 200000;
    CHECK(setrlimit(RLIMIT_FSIZE, &lim) == 0);

    /* In the header's points at open: 50,000 points are 1.2 MB, more than
     * the buffer, so begin already writes. */
    size_t nb = 50000;
    double *big = calloc(3 * nb, sizeof *big);
    CHECK(big);
    EXPECTF(fdt_stream_writer_open(&w, path_in("f.fdtb"), NULL, big, nb, 0, diag,
                                   sizeof diag) == FDT_EIO && w == NULL &&
                strstr(diag, "f.fdtb: ") && strstr(diag, strerror(EFBIG)),
            "[%s]", diag);
    free(big);
    EXPECT(entries() == before && holds(path_in("f.fdtb"), "old\n"));

    /* In a batch of tets: the same batch fed until the bytes pass the
     * buffer (1 MiB) and the limit; the sink says FDT_EIO, and so does
     * every later call, the commit too. */
    for (int o = 0; o < 3; o++) {
        CHECK(fdt_stream_writer_open(&w, path_in(outs[o]), NULL, xyz, n, 0, diag,
                                     sizeof diag) == FDT_OK);
        CHECK(fdt_stream_writer_sink(w, &sink) == FDT_OK);
        int rc = FDT_OK, k = 0;
        while (rc == FDT_OK && k < 100) {
            rc = sink.tets(sink.user, tets, t);
            k++;
        }
        EXPECTF(rc == FDT_EIO && k > 1, "%s: %d after %d batches", outs[o], rc, k);
        EXPECT(sink.tets(sink.user, tets, 1) == FDT_EIO);
        EXPECT(sink.hull(sink.user, tets, 1) == FDT_EIO);
        /* .ele: the .ele itself is the file that fails (the .node is
         * still in its buffer) */
        EXPECTF(fdt_stream_writer_close(&w, 1, diag, sizeof diag) == FDT_EIO &&
                    strstr(diag, outs[o]) && strstr(diag, strerror(EFBIG)),
                "%s: [%s]", outs[o], diag);
        EXPECTF(entries() == before && holds(path_in(outs[o]), "old\n"), "%s", outs[o]);
    }

    /* At the commit: the tets fit the buffer, not the limit; the final
     * flush before the count patch fails. */
    for (int o = 0; o < 2; o++) {
        CHECK(fdt_stream_writer_open(&w, path_in(outs[o]), NULL, xyz, n, 0, diag,
                                     sizeof diag) == FDT_OK);
        CHECK(fdt_stream_writer_sink(w, &sink) == FDT_OK);
        EXPECT(sink.tets(sink.user, tets, t) == FDT_OK);
        EXPECTF(fdt_stream_writer_close(&w, 1, diag, sizeof diag) == FDT_EIO &&
                    strstr(diag, outs[o]) && strstr(diag, strerror(EFBIG)),
                "%s: [%s]", outs[o], diag);
        EXPECTF(entries() == before && holds(path_in(outs[o]), "old\n"), "%s", outs[o]);
    }
    CHECK(setrlimit(RLIMIT_FSIZE, &old_lim) == 0);
    signal(SIGXFSZ, old_h);

    /* A rename that fails: the target is a non-empty directory. */
    block_with_dir(path_in("d.fdtb"));
    CHECK(fdt_stream_writer_open(&w, path_in("d.fdtb"), NULL, xyz, n, 0, diag, sizeof diag) ==
          FDT_OK);
    CHECK(fdt_stream_writer_sink(w, &sink) == FDT_OK);
    EXPECT(sink.tets(sink.user, tets, t) == FDT_OK);
    EXPECTF(fdt_stream_writer_close(&w, 1, diag, sizeof diag) == FDT_EIO &&
                strstr(diag, "d.fdtb: ") && strstr(diag, strerror(EISDIR)),
            "[%s]", diag);
    unblock(path_in("d.fdtb"));
    EXPECT(entries() == before);
    /* ... in the middle of a TetGen set: the .node and .ele already
     * renamed go too (all or none) */
    block_with_dir(path_in("s.face"));
    CHECK(fdt_stream_writer_open(&w, path_in("s.ele"), NULL, xyz, n, 0, diag, sizeof diag) ==
          FDT_OK);
    CHECK(fdt_stream_writer_sink(w, &sink) == FDT_OK);
    EXPECT(sink.tets(sink.user, tets, t) == FDT_OK);
    EXPECTF(fdt_stream_writer_close(&w, 1, diag, sizeof diag) == FDT_EIO &&
                strstr(diag, "s.face: "), "[%s]", diag);
    EXPECT(access(path_in("s.node"), F_OK) != 0 && access(path_in("s.ele"), F_OK) != 0);
    unblock(path_in("s.face"));
    EXPECT(entries() == before);

    /* The stale .neigh of an older set is removed at the commit; one
     * that cannot be (a non-empty directory) is reported, the new set
     * in place. */
    CHECK(write_file(path_in("n.neigh"), "old\n"));
    CHECK(fdt_stream_writer_open(&w, path_in("n.ele"), NULL, xyz, n, 0, diag, sizeof diag) ==
          FDT_OK);
    CHECK(fdt_stream_writer_sink(w, &sink) == FDT_OK);
    EXPECT(sink.tets(sink.user, tets, t) == FDT_OK);
    EXPECT(fdt_stream_writer_close(&w, 1, diag, sizeof diag) == FDT_OK);
    EXPECT(access(path_in("n.neigh"), F_OK) != 0 && access(path_in("n.ele"), F_OK) == 0);
    block_with_dir(path_in("n.neigh"));
    CHECK(fdt_stream_writer_open(&w, path_in("n.ele"), NULL, xyz, n, 0, diag, sizeof diag) ==
          FDT_OK);
    CHECK(fdt_stream_writer_sink(w, &sink) == FDT_OK);
    EXPECT(sink.tets(sink.user, tets, t) == FDT_OK);
    EXPECTF(fdt_stream_writer_close(&w, 1, diag, sizeof diag) == FDT_EIO &&
                strstr(diag, "n.neigh: "), "[%s]", diag);
    EXPECT(access(path_in("n.ele"), F_OK) == 0);
    unblock(path_in("n.neigh"));
    const char *ns[] = {"n.node", "n.ele", "n.face"};
    for (int i = 0; i < 3; i++)
        unlink(path_in(ns[i]));
    for (int o = 0; o < 3; o++)
        unlink(path_in(outs[o]));
}

/*
 * A periodic run's rows (FDT_STREAM_PERIODIC): streamed in memory-sized
 * runs (rows dealt to five runs, each ascending, the runs in turn, so the
 * merge has five cursors), and through fdt_triangulate_stream, the .tets
 * is fdt_write_mesh's byte for byte; the kinds do not mix.
 */
static void test_periodic(const double *xyz, size_t n)
{
    fdt_settings s;
    fdt_default_settings(&s);
    s.periodic = 7;
    const double box[6] = {0, 0, 0, 1, 1, 1};
    memcpy(s.periodic_box, box, sizeof box);
    fdt_context *ctx = NULL;
    CHECK(fdt_open(&ctx, &s) == FDT_OK);
    fdt_result *mem = NULL;
    CHECK(fdt_triangulate(ctx, xyz, n, &mem) == FDT_OK);
    char diag[1024];
    CHECK(fdt_write_mesh(mem, xyz, n, path_in("p_mem.tets"), NULL, diag, sizeof diag) == FDT_OK);
    size_t want_len, got_len;
    unsigned char *want = slurp(path_in("p_mem.tets"), &want_len);
    const fdt_vid *t = fdt_result_tets(mem);
    const int8_t *off = fdt_result_tet_offsets(mem);
    size_t nt = fdt_result_num_tets(mem);
    CHECK(want && t && off && nt > 100);

    fdt_stream_writer *w = NULL;
    EXPECT(fdt_stream_writer_open(&w, path_in("p.vtu"), NULL, xyz, n, FDT_STREAM_PERIODIC, diag,
                                  sizeof diag) == FDT_EINVAL && !w && strstr(diag, "periodic"));
    CHECK(fdt_stream_writer_open(&w, path_in("p.tets"), NULL, xyz, n, FDT_STREAM_PERIODIC, diag,
                                 sizeof diag) == FDT_OK);
    fdt_sink sink;
    CHECK(fdt_stream_writer_sink(w, &sink) == FDT_OK);
    fdt_vid *rt = malloc(nt * 4 * sizeof *rt);
    int8_t *ro = malloc(nt * 12);
    CHECK(rt && ro);
    for (int run = 0; run < 5; run++) {
        size_t k = 0;
        for (size_t i = run; i < nt; i += 5, k++) {
            memcpy(rt + 4 * k, t + 4 * i, 4 * sizeof *rt);
            memcpy(ro + 12 * k, off + 12 * i, 12);
        }
        /* each run in two batches */
        EXPECT(sink.periodic_tets(sink.user, rt, ro, k / 2) == 0);
        EXPECT(sink.periodic_tets(sink.user, rt + 4 * (k / 2), ro + 12 * (k / 2), k - k / 2) ==
               0);
    }
    EXPECTF(fdt_stream_writer_close(&w, 1, diag, sizeof diag) == FDT_OK, "%s", diag);
    unsigned char *got = slurp(path_in("p.tets"), &got_len);
    EXPECTF(got && got_len == want_len && !memcmp(got, want, want_len),
            "the merged rows: %zu bytes, fdt_write_mesh %zu", got_len, want_len);
    free(got);

    /* the run streamed (one slab at this size: test_periodic.c has parts) */
    CHECK(fdt_stream_writer_open(&w, path_in("p2.tets"), NULL, xyz, n, FDT_STREAM_PERIODIC,
                                 diag, sizeof diag) == FDT_OK);
    CHECK(fdt_stream_writer_sink(w, &sink) == FDT_OK);
    fdt_result *sr = NULL;
    EXPECT(fdt_triangulate_stream(ctx, xyz, n, &sink, &sr) == FDT_OK);
    uint64_t h1 = 0, h2 = 1;
    EXPECT(fdt_result_set_hash(mem, &h1) == FDT_OK && fdt_result_set_hash(sr, &h2) == FDT_OK &&
           h1 == h2);
    fdt_stats st;
    EXPECT(fdt_result_num_tets(sr) == 0 && fdt_result_stats(sr, &st) == FDT_OK && st.tets == nt);
    EXPECTF(fdt_stream_writer_close(&w, 1, diag, sizeof diag) == FDT_OK, "%s", diag);
    got = slurp(path_in("p2.tets"), &got_len);
    EXPECT(got && got_len == want_len && !memcmp(got, want, want_len));
    free(got);
    fdt_result_free(&sr);

    /* the kinds do not mix: a plain batch to a periodic writer, a periodic
     * one to a plain writer, a plain sink to a periodic run */
    CHECK(fdt_stream_writer_open(&w, path_in("p3.tets"), NULL, xyz, n, FDT_STREAM_PERIODIC,
                                 diag, sizeof diag) == FDT_OK);
    CHECK(fdt_stream_writer_sink(w, &sink) == FDT_OK);
    EXPECT(sink.tets(sink.user, t, 1) == FDT_EINVAL);
    EXPECT(fdt_stream_writer_close(&w, 1, diag, sizeof diag) == FDT_EINVAL &&
           strstr(diag, "without offsets"));
    EXPECT(access(path_in("p3.tets"), F_OK) != 0);
    CHECK(fdt_stream_writer_open(&w, path_in("p3.vtu"), NULL, xyz, n, 0, diag, sizeof diag) ==
          FDT_OK);
    CHECK(fdt_stream_writer_sink(w, &sink) == FDT_OK);
    EXPECT(sink.periodic_tets(sink.user, t, off, 1) == FDT_EINVAL);
    EXPECT(fdt_stream_writer_close(&w, 1, diag, sizeof diag) == FDT_EINVAL &&
           strstr(diag, "periodic"));
    fdt_sink plain = sink;
    plain.periodic_tets = NULL;
    EXPECT(fdt_triangulate_stream(ctx, xyz, n, &plain, &sr) == FDT_EINVAL && !sr);
    plain.periodic_tets = sink.periodic_tets;
    plain.struct_size = offsetof(fdt_sink, periodic_tets); /* an older caller */
    EXPECT(fdt_triangulate_stream(ctx, xyz, n, &plain, &sr) == FDT_EINVAL && !sr);
    free(rt);
    free(ro);
    free(want);
    fdt_result_free(&mem);
    fdt_close(&ctx);
    EXPECT(unlink(path_in("p_mem.tets")) == 0 && unlink(path_in("p.tets")) == 0 &&
           unlink(path_in("p2.tets")) == 0);
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
        fdt_sink ps = {sizeof ps, poison_tets, poison_hull, &p, NULL, NULL};
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

    test_bin_flags(xyz, n, mem);
    test_refusals(xyz, n, mem);
    test_write_errors(xyz, n, mem);
    test_periodic(xyz, n);

    fdt_result_free(&mem);
    fdt_close(&ctx);
    free(xyz);
    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0)
        fprintf(stderr, "could not remove %s\n", dir);
    return test_report("writer_stream");
}
