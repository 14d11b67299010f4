/*
 * System-call failure injection over the mesh writers (src/io/write/writer.c,
 * src/io/write/writer_stream.c and the out_* helpers of outfile.h), as
 * tests/test_faults.c injects allocation failures (issue 20's coverage
 * debt: the failure paths of the temporaries, renames and commit sets).
 *
 * The test is linked with -Wl,--wrap=mkstemp64,--wrap=fsync,... (every
 * call of the table below; tests/meson.build), so the calls our static
 * libraries and this file make go through the __wrap_ functions here;
 * calls made inside libc are not seen. The names are those glibc's headers
 * give with _FILE_OFFSET_BITS=64 (mkstemp64, open64, lstat64, ftello64,
 * pwrite64), which meson sets on every build.
 *
 * For each scenario (a write of each format family, new or over old
 * files; a side file; streamed writes; commit sets with and without
 * no_clobber), each call S with each errno of the table, and k = 1, 2, ...,
 * the k-th call of S in the scenario fails, until a run meets no k-th call.
 * A run that hit a failure must either
 *   - fail with FDT_IO_EWRITE (FDT_EIO for the streaming API; the
 *     out-of-memory code for ENOMEM) and a message naming a file of the
 *     scenario's folder, and leave that folder byte for byte as it was
 *     before the run: no temporary, backup or journal, every old target
 *     as it was; or
 *   - succeed and leave exactly what a run without failures leaves, where
 *     the table says the failure can be absorbed: a link refused (EPERM,
 *     EXDEV: the file system has no hard links, so the commit set moves
 *     each old target aside instead of linking it), fsync refused for a
 *     folder (EINVAL, EROFS; the journal's own fsync must not fail with
 *     EROFS), a pwrite interrupted (EINTR: retried), getcwd
 *     failing (the journal's cwd line says "?"), a close after the
 *     folder's fsync (its result does not matter), an lstat of a backup
 *     name (taken as "no such file"; the link then tells) or of a new
 *     multi-file output's target (taken as "exists": renamed as a commit
 *     set of its own, which finds it new), an unlink of a backup after
 *     the commit point (the new outputs are all in place; the backup
 *     stays, and is the only file a run may leave).
 * One exception, documented in writer_stream.c: a streamed TetGen set
 * outside a commit set whose stale .neigh cannot be removed after the
 * renames fails (FDT_EIO, the .neigh named) with its new files in place.
 * Every run also closes every descriptor it opened and leaves no commit
 * set open. A run that hit none must succeed with the reference output.
 *
 * Then the writer's own limits, failing the same way (test_limits: the
 * registry's slots, a commit set's size, a name too long, the signal
 * clean-up mid-write, fdt_create_err's messages), and streamed writes
 * whose caller takes no message (test_stream_quiet).
 *
 * Not injected: stat/access (the checks before a write: tests/test_writer.c
 * makes them fail for real), fprintf of the journal (its errors surface in
 * the checked fflush/fclose), and two failures in one run (the clean-up
 * after a failure, rmdir and unlink, then meets none: a failure there
 * would leave its file, which no code can prevent; rmdir is in the table
 * to show that no run calls it but to clean up).
 *
 * It found two bugs, fixed in src/io/write/writer.c: a failed rename in
 * the middle of a TetGen set or a polyMesh written over old files removed
 * the old files already replaced (now such a write is a commit set of its
 * own), and a commit whose journal could not be removed reported success
 * with the journal left (now it rolls back).
 */
#include "frontdt.h"
#include "io/read/read_types.h" /* FDT_IO_* */
#include "io/write/writer.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>
#include "testdir.h"
#include "testutil.h"

/* ------------------------------------------------------------------ */
/* The hooks                                                          */
/* ------------------------------------------------------------------ */

enum {
    C_MKSTEMP, C_MKDTEMP, C_FCHMOD, C_CHMOD, C_FDOPEN, C_FWRITE, C_FFLUSH,
    C_FCLOSE, C_FTELLO, C_PWRITE, C_OPEN, C_FSYNC, C_CLOSE, C_LINK, C_RENAME,
    C_UNLINK, C_RMDIR, C_LSTAT, C_GETCWD, C_COUNT
};

static const char *const call_name[C_COUNT] = {
    "mkstemp", "mkdtemp", "fchmod", "chmod", "fdopen", "fwrite", "fflush",
    "fclose", "ftello", "pwrite", "open", "fsync", "close", "link", "rename",
    "unlink", "rmdir", "lstat", "getcwd",
};

/* One sweep: call c fails with err; absorb: a run may succeed with it. */
typedef struct variant {
    int call;
    int err;
    int absorb;
} variant;

static const variant variants[] = {
    {C_MKSTEMP, ENOSPC, 0}, {C_MKDTEMP, ENOSPC, 0}, {C_FCHMOD, EIO, 0},
    {C_CHMOD, EIO, 0},      {C_FDOPEN, ENOMEM, 0},  {C_FWRITE, ENOSPC, 0},
    {C_FFLUSH, ENOSPC, 0},  {C_FCLOSE, EIO, 0},     {C_FTELLO, EOVERFLOW, 0},
    {C_PWRITE, ENOSPC, 0},  {C_PWRITE, EINTR, 1},   {C_OPEN, EACCES, 0},
    {C_FSYNC, EIO, 0},      {C_FSYNC, EINVAL, 1},   {C_FSYNC, EROFS, 1},
    {C_CLOSE, EIO, 1},
    /* stdio failing without an errno: the writer says EIO */
    {C_FFLUSH, 0, 0},       {C_FCLOSE, 0, 0},
    {C_LINK, EPERM, 1},     {C_LINK, EXDEV, 1},     {C_LINK, EEXIST, 0},
    {C_RENAME, EIO, 0},     {C_RENAME, EXDEV, 0},   {C_UNLINK, EIO, 1},
    {C_RMDIR, EIO, 0},      {C_LSTAT, EIO, 1},      {C_GETCWD, ERANGE, 1},
};
#define N_VARIANTS (int)(sizeof variants / sizeof variants[0])

/* The hooks have no context argument: their state is global, and the
 * writers are used from this one thread. */
static int arm_call = -1; /* the call to fail, -1: none */
static long arm_k;        /* its k-th call fails */
static int arm_err;
static long arm_seen;     /* calls of arm_call since fault_arm */
static int arm_hit;
static char refused[FDT_IO_PATH]; /* the name an injected unlink kept */

static void fault_arm(const variant *v, long k)
{
    arm_seen = 0;
    arm_hit = 0;
    refused[0] = '\0';
    arm_k = k;
    arm_err = v->err;
    arm_call = v->call;
}

/* Stops injecting; returns whether a failure was injected. */
static int fault_disarm(void)
{
    arm_call = -1;
    return arm_hit;
}

/* Is this the call to fail? Sets errno when it is. */
static int fail_now(int call)
{
    if (call != arm_call || ++arm_seen != arm_k)
        return 0;
    arm_hit = 1;
    errno = arm_err;
    return 1;
}

int __real_mkstemp64(char *tmpl);
char *__real_mkdtemp(char *tmpl);
int __real_fchmod(int fd, mode_t mode);
int __real_chmod(const char *path, mode_t mode);
FILE *__real_fdopen(int fd, const char *mode);
size_t __real_fwrite(const void *p, size_t size, size_t n, FILE *f);
int __real_fflush(FILE *f);
int __real_fclose(FILE *f);
off_t __real_ftello64(FILE *f);
ssize_t __real_pwrite64(int fd, const void *p, size_t n, off_t at);
int __real_open64(const char *path, int flags, ...);
int __real_fsync(int fd);
int __real_close(int fd);
int __real_link(const char *from, const char *to);
int __real_rename(const char *from, const char *to);
int __real_unlink(const char *path);
int __real_rmdir(const char *path);
int __real_lstat64(const char *path, struct stat *st);
char *__real_getcwd(char *buf, size_t size);

int __wrap_mkstemp64(char *tmpl);
char *__wrap_mkdtemp(char *tmpl);
int __wrap_fchmod(int fd, mode_t mode);
int __wrap_chmod(const char *path, mode_t mode);
FILE *__wrap_fdopen(int fd, const char *mode);
size_t __wrap_fwrite(const void *p, size_t size, size_t n, FILE *f);
int __wrap_fflush(FILE *f);
int __wrap_fclose(FILE *f);
off_t __wrap_ftello64(FILE *f);
ssize_t __wrap_pwrite64(int fd, const void *p, size_t n, off_t at);
int __wrap_open64(const char *path, int flags, ...);
int __wrap_fsync(int fd);
int __wrap_close(int fd);
int __wrap_link(const char *from, const char *to);
int __wrap_rename(const char *from, const char *to);
int __wrap_unlink(const char *path);
int __wrap_rmdir(const char *path);
int __wrap_lstat64(const char *path, struct stat *st);
char *__wrap_getcwd(char *buf, size_t size);

/* A refused call does nothing, as the kernel's would; close and fclose
 * release the descriptor and the stream even when they fail (Linux,
 * glibc), so their wrappers do that first. */
int __wrap_mkstemp64(char *tmpl)
{
    return fail_now(C_MKSTEMP) ? -1 : __real_mkstemp64(tmpl);
}

char *__wrap_mkdtemp(char *tmpl)
{
    return fail_now(C_MKDTEMP) ? NULL : __real_mkdtemp(tmpl);
}

int __wrap_fchmod(int fd, mode_t mode)
{
    return fail_now(C_FCHMOD) ? -1 : __real_fchmod(fd, mode);
}

int __wrap_chmod(const char *path, mode_t mode)
{
    return fail_now(C_CHMOD) ? -1 : __real_chmod(path, mode);
}

FILE *__wrap_fdopen(int fd, const char *mode)
{
    return fail_now(C_FDOPEN) ? NULL : __real_fdopen(fd, mode);
}

size_t __wrap_fwrite(const void *p, size_t size, size_t n, FILE *f)
{
    return fail_now(C_FWRITE) ? 0 : __real_fwrite(p, size, n, f);
}

int __wrap_fflush(FILE *f)
{
    return fail_now(C_FFLUSH) ? EOF : __real_fflush(f);
}

int __wrap_fclose(FILE *f)
{
    int r = __real_fclose(f);
    return fail_now(C_FCLOSE) ? EOF : r; /* a deferred error (NFS, ENOSPC) */
}

off_t __wrap_ftello64(FILE *f)
{
    return fail_now(C_FTELLO) ? -1 : __real_ftello64(f);
}

ssize_t __wrap_pwrite64(int fd, const void *p, size_t n, off_t at)
{
    return fail_now(C_PWRITE) ? -1 : __real_pwrite64(fd, p, n, at);
}

int __wrap_open64(const char *path, int flags, ...)
{
    mode_t mode = 0;
    if (flags & O_CREAT) {
        va_list ap;
        va_start(ap, flags);
        mode = (mode_t)va_arg(ap, int);
        va_end(ap);
    }
    return fail_now(C_OPEN) ? -1 : __real_open64(path, flags, mode);
}

int __wrap_fsync(int fd)
{
    return fail_now(C_FSYNC) ? -1 : __real_fsync(fd);
}

int __wrap_close(int fd)
{
    int r = __real_close(fd);
    return fail_now(C_CLOSE) ? -1 : r;
}

int __wrap_link(const char *from, const char *to)
{
    return fail_now(C_LINK) ? -1 : __real_link(from, to);
}

int __wrap_rename(const char *from, const char *to)
{
    return fail_now(C_RENAME) ? -1 : __real_rename(from, to);
}

int __wrap_unlink(const char *path)
{
    if (!fail_now(C_UNLINK))
        return __real_unlink(path);
    snprintf(refused, sizeof refused, "%s", path);
    return -1;
}

int __wrap_rmdir(const char *path)
{
    return fail_now(C_RMDIR) ? -1 : __real_rmdir(path);
}

int __wrap_lstat64(const char *path, struct stat *st)
{
    return fail_now(C_LSTAT) ? -1 : __real_lstat64(path, st);
}

char *__wrap_getcwd(char *buf, size_t size)
{
    return fail_now(C_GETCWD) ? NULL : __real_getcwd(buf, size);
}

/* ------------------------------------------------------------------ */
/* A folder's state, byte for byte                                    */
/* ------------------------------------------------------------------ */

typedef struct buf {
    char *p;
    size_t len, cap;
} buf;

static void buf_add(buf *b, const void *p, size_t n)
{
    if (b->len + n + 1 > b->cap) {
        b->cap = 2 * (b->len + n + 1);
        b->p = realloc(b->p, b->cap);
        CHECK(b->p);
    }
    memcpy(b->p + b->len, p, n);
    b->len += n;
    b->p[b->len] = '\0';
}

static int cmp_names(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* Appends every entry under dir (relative name, size and mode, and with
 * bytes its contents), sorted by name so the state does not depend on the
 * order readdir gives. */
static void snap_into(buf *b, const char *dir, const char *rel, int bytes)
{
    DIR *d = opendir(dir);
    CHECK(d);
    char *names[256];
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") && strcmp(e->d_name, "..")) {
            CHECK(n < 256);
            names[n++] = strdup(e->d_name);
        }
    closedir(d);
    qsort(names, (size_t)n, sizeof *names, cmp_names);
    for (int i = 0; i < n; i++) {
        char path[FDT_IO_PATH], sub[FDT_IO_PATH];
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        snprintf(sub, sizeof sub, "%s%s", rel, names[i]);
        struct stat st;
        CHECK(lstat(path, &st) == 0);
        buf_add(b, sub, strlen(sub));
        if (S_ISDIR(st.st_mode)) {
            buf_add(b, "/\n", 2);
            strcat(sub, "/");
            snap_into(b, path, sub, bytes);
        } else {
            char head[64];
            snprintf(head, sizeof head, " %lld bytes, mode %o\n", (long long)st.st_size,
                     (unsigned)(st.st_mode & 07777));
            buf_add(b, head, strlen(head));
            if (!bytes) {
                free(names[i]);
                continue;
            }
            FILE *f = fopen(path, "rb");
            CHECK(f);
            char chunk[4096];
            size_t k;
            while ((k = fread(chunk, 1, sizeof chunk, f)) > 0)
                buf_add(b, chunk, k);
            fclose(f);
        }
        free(names[i]);
    }
}

/* The folder's state (bytes: 1) or its listing for a message (0). */
static buf snap(const char *dir, int bytes)
{
    buf b = {NULL, 0, 0};
    buf_add(&b, "", 0);
    snap_into(&b, dir, "", bytes);
    return b;
}

static int same_state(const buf *a, const buf *b)
{
    return a->len == b->len && memcmp(a->p, b->p, a->len) == 0;
}

static void remove_tree(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d)
        return;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
            continue;
        char p[FDT_IO_PATH];
        snprintf(p, sizeof p, "%s/%s", dir, e->d_name);
        struct stat st;
        if (lstat(p, &st) == 0 && S_ISDIR(st.st_mode))
            remove_tree(p);
        else
            unlink(p);
    }
    closedir(d);
    rmdir(dir);
}

/* Open descriptors of this process (a run must close what it opens). */
static int count_fds(void)
{
    DIR *d = opendir("/proc/self/fd");
    if (!d)
        return -1;
    int n = 0;
    while (readdir(d) != NULL)
        n++;
    closedir(d);
    return n;
}

static void put_file(const char *dir, const char *name, const char *text)
{
    char p[FDT_IO_PATH];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    FILE *f = fopen(p, "wb");
    CHECK(f);
    CHECK(fputs(text, f) >= 0);
    CHECK(fclose(f) == 0);
}

/* ------------------------------------------------------------------ */
/* The mesh and the scenarios                                         */
/* ------------------------------------------------------------------ */

/* A cube's corners and one point inside: a few tets, every part of every
 * format (neighbours, hull, faces) present. */
static const double cube_xyz[3 * 9] = {
    0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 1, 1, 0, 1, 0, 1, 1, 1, 1, 1, 0.3, 0.4, 0.6,
};
static fdt_mesh_view mesh; /* sorted, with neighbours and faces */

static void make_mesh(fdt_result **r)
{
    *r = test_triangulate(cube_xyz, 9, 1, 1);
    CHECK_EQ(fdt_result_sort(*r), FDT_OK);
    size_t nf;
    const fdt_vid *faces;
    const fdt_tid *face_tets;
    CHECK_EQ(fdt_result_faces(*r, &nf, &faces, &face_tets), FDT_OK);
    fdt_mesh_view v = {
        .xyz = cube_xyz, .n_points = 9, .tets = fdt_result_tets(*r),
        .n_tets = fdt_result_num_tets(*r), .nbrs = fdt_result_neighbors(*r),
        .hull = fdt_result_hull_faces(*r), .n_hull = fdt_result_num_hull_faces(*r),
        .faces = faces, .face_tets = face_tets, .n_faces = nf,
    };
    mesh = v;
}

static void path_in(char out[FDT_IO_PATH], const char *dir, const char *name)
{
    size_t ld = strlen(dir), ln = strlen(name);
    CHECK(ld + 1 + ln + 1 <= FDT_IO_PATH);
    memcpy(out, dir, ld);
    out[ld] = '/';
    memcpy(out + ld + 1, name, ln + 1);
}

static int write_mesh(const char *dir, const char *name, char *err, size_t errlen)
{
    char p[FDT_IO_PATH];
    path_in(p, dir, name);
    return fdt_wr_mesh(p, &mesh, err, errlen);
}

/* The streaming API's code as the writer's (FDT_IO_*), so one check
 * serves both; any other code stays distinct and fails it. */
static int io_code(int rc)
{
    return rc == FDT_OK ? FDT_IO_OK : rc == FDT_EIO ? FDT_IO_EWRITE
           : rc == FDT_ENOMEM ? FDT_IO_ENOMEM : -1000 + rc;
}

/* fdt_stream_writer_* fed the tets in two batches and the hull between,
 * then committed (as tests/test_faults.c's sc_stream_write). */
static int stream_mesh(const char *dir, const char *name, char *err, size_t errlen)
{
    char p[FDT_IO_PATH];
    path_in(p, dir, name);
    fdt_stream_writer *w = NULL;
    int rc = fdt_stream_writer_open(&w, p, NULL, mesh.xyz, mesh.n_points, 0, err, errlen);
    if (rc != FDT_OK)
        return io_code(rc);
    fdt_sink sink;
    size_t t = mesh.n_tets;
    int e = fdt_stream_writer_sink(w, &sink);
    if (e == FDT_OK)
        e = sink.tets(sink.user, mesh.tets, t / 2);
    if (e == FDT_OK)
        e = sink.hull(sink.user, mesh.hull, mesh.n_hull);
    if (e == FDT_OK)
        e = sink.tets(sink.user, mesh.tets + 4 * (t / 2), t - t / 2);
    rc = fdt_stream_writer_close(&w, 1, err, errlen);
    if (e != FDT_OK && rc != e)
        return -2000; /* the commit forgot a sink's error */
    return io_code(rc);
}

/* The CLI's --stats-json: a side file written with stdio. */
static int side_file(const char *dir, const char *name, char *err, size_t errlen)
{
    char p[FDT_IO_PATH];
    path_in(p, dir, name);
    fdt_wr_side *side;
    FILE *f = fdt_wr_side_open(p, &side, err, errlen);
    if (!f) /* the open's code is not returned: its message tells */
        return strstr(err, strerror(ENOMEM)) ? FDT_IO_ENOMEM : FDT_IO_EWRITE;
    fprintf(f, "{\"tets\": %zu}\n", mesh.n_tets);
    return fdt_wr_side_commit(side, err, errlen);
}

static void old_vtu(const char *dir) { put_file(dir, "m.vtu", "an old mesh\n"); }
static void old_side(const char *dir) { put_file(dir, "s.json", "{\"old\": 1}\n"); }

static void old_tetgen(const char *dir, const char *base)
{
    static const char *const ext[] = {".node", ".ele", ".face", ".neigh"};
    for (int i = 0; i < 4; i++) {
        char name[64], text[80];
        snprintf(name, sizeof name, "%s%s", base, ext[i]);
        snprintf(text, sizeof text, "old %s\n", name);
        put_file(dir, name, text);
    }
}

static void old_foam(const char *dir, const char *sub)
{
    static const char *const part[] = {"points", "faces", "owner", "neighbour", "boundary"};
    char p[FDT_IO_PATH];
    path_in(p, dir, sub);
    CHECK(mkdir(p, 0755) == 0);
    strcat(p, "/polyMesh");
    CHECK(mkdir(p, 0755) == 0);
    for (int i = 0; i < 5; i++)
        put_file(p, part[i], part[i]);
}

static void setup_tetgen(const char *dir) { old_tetgen(dir, "m"); }
static void setup_foam(const char *dir) { old_foam(dir, "old"); }

static void setup_new_foam(const char *dir)
{
    char p[FDT_IO_PATH];
    path_in(p, dir, "new");
    CHECK(mkdir(p, 0755) == 0);
}

static int sc_tets(const char *d, char *e, size_t n) { return write_mesh(d, "m.tets", e, n); }
static int sc_vtu(const char *d, char *e, size_t n) { return write_mesh(d, "m.vtu", e, n); }
static int sc_ele(const char *d, char *e, size_t n) { return write_mesh(d, "m.ele", e, n); }
static int sc_side(const char *d, char *e, size_t n) { return side_file(d, "s.json", e, n); }
static int sc_st_ele(const char *d, char *e, size_t n) { return stream_mesh(d, "m.ele", e, n); }
static int sc_st_vtu(const char *d, char *e, size_t n) { return stream_mesh(d, "m.vtu", e, n); }
static int sc_st_bin(const char *d, char *e, size_t n) { return stream_mesh(d, "m.fdtb", e, n); }

static int sc_foam_new(const char *d, char *e, size_t n)
{
    return write_mesh(d, "new/polyMesh", e, n);
}

static int sc_foam_old(const char *d, char *e, size_t n)
{
    return write_mesh(d, "old/polyMesh", e, n);
}

/* Commit sets, as the CLI runs one: every output into the set, the set
 * abandoned at the first failure, else committed. */
#define SET_STEP(call)                  \
    do {                                \
        int r_ = (call);                \
        if (r_ != FDT_IO_OK) {          \
            fdt_wr_set_abandon();       \
            return r_;                  \
        }                               \
    } while (0)

/* Over old files: a file, a TetGen set streamed over one with a .neigh
 * (removed at the commit), a polyMesh into its folder and a new one, a
 * new TetGen set, the side file. */
static int sc_set(const char *d, char *e, size_t n)
{
    if (fdt_wr_set_begin(0) != 0)
        return -3000;
    SET_STEP(write_mesh(d, "m.vtu", e, n));
    SET_STEP(stream_mesh(d, "b.ele", e, n));
    SET_STEP(write_mesh(d, "old/polyMesh", e, n));
    SET_STEP(write_mesh(d, "new/polyMesh", e, n));
    SET_STEP(write_mesh(d, "c.ele", e, n));
    SET_STEP(side_file(d, "s.json", e, n));
    return fdt_wr_set_commit(e, n);
}

static void setup_set(const char *dir)
{
    old_vtu(dir);
    old_tetgen(dir, "b");
    setup_foam(dir);
    setup_new_foam(dir);
    old_side(dir);
}

/* --no-clobber, every target new: nothing to back up. */
static int sc_set_new(const char *d, char *e, size_t n)
{
    if (fdt_wr_set_begin(1) != 0)
        return -3000;
    SET_STEP(write_mesh(d, "m.tets", e, n));
    SET_STEP(write_mesh(d, "new/polyMesh", e, n));
    SET_STEP(stream_mesh(d, "b.ele", e, n));
    SET_STEP(stream_mesh(d, "m.fdtb", e, n));
    SET_STEP(side_file(d, "s.json", e, n));
    return fdt_wr_set_commit(e, n);
}

typedef struct scenario {
    const char *tag;
    void (*setup)(const char *dir); /* the old outputs; NULL: none */
    int (*run)(const char *dir, char *err, size_t errlen);
    /* A streamed TetGen set outside a commit set removes a stale .neigh
     * after the renames; when that unlink fails the write says so
     * (FDT_EIO, .neigh named; writer_stream.c), its new files in place. */
    int unlink_after;
} scenario;

static const scenario scenarios[] = {
    {"tets", NULL, sc_tets, 0},
    {"vtu-over-old", old_vtu, sc_vtu, 0},
    {"tetgen", NULL, sc_ele, 0},
    {"tetgen-over-old", setup_tetgen, sc_ele, 0},
    {"polymesh", setup_new_foam, sc_foam_new, 0},
    {"polymesh-over-old", setup_foam, sc_foam_old, 0},
    {"side-over-old", old_side, sc_side, 0},
    {"stream-tetgen", NULL, sc_st_ele, 1},
    {"stream-vtu-over-old", old_vtu, sc_st_vtu, 0},
    {"stream-bin", NULL, sc_st_bin, 0},
    {"set-over-old", setup_set, sc_set, 0},
    {"set-no-clobber", setup_new_foam, sc_set_new, 0},
};
#define N_SCENARIOS (int)(sizeof scenarios / sizeof scenarios[0])

/* ------------------------------------------------------------------ */
/* The driver                                                         */
/* ------------------------------------------------------------------ */

static void fresh(const scenario *sc, const char *dir)
{
    remove_tree(dir);
    CHECK(mkdir(dir, 0755) == 0);
    if (sc->setup)
        sc->setup(dir);
}

typedef struct sweep_state {
    const scenario *sc;
    char dir[FDT_IO_PATH];
    buf before, after; /* the folder before a run and after a clean one */
    long runs, injected, absorbed;
} sweep_state;

/* What a failed run must have left and returned. */
static void check_failed(sweep_state *s, const variant *v, long k, int rc, const char *err,
                         const buf *now)
{
    const char *call = call_name[v->call];
    int want = v->err == ENOMEM ? FDT_IO_ENOMEM : FDT_IO_EWRITE;
    EXPECTF(rc == want, "%s, %s %ld (%s): status %d, want %d [%s]", s->sc->tag, call, k,
            strerror(v->err), rc, want, err);
    EXPECTF(strstr(err, s->dir) != NULL, "%s, %s %ld (%s): message without the file: [%s]",
            s->sc->tag, call, k, strerror(v->err), err);
    const buf *state = s->sc->unlink_after && v->call == C_UNLINK && strstr(err, ".neigh: ")
                           ? &s->after
                           : &s->before;
    if (!same_state(now, state)) {
        buf l = snap(s->dir, 0);
        EXPECTF(0, "%s, %s %ld (%s) [%s]: the folder changed; it holds:\n%s", s->sc->tag,
                call, k, strerror(v->err), err, l.p);
        free(l.p);
    }
}

/* One run with the k-th call of v failing; 1 when it met no k-th call. */
static int one_run(sweep_state *s, const variant *v, long k)
{
    char err[2 * FDT_IO_PATH] = "";
    const char *call = call_name[v->call];
    fresh(s->sc, s->dir);
    int fds = count_fds();
    fault_arm(v, k);
    int rc = s->sc->run(s->dir, err, sizeof err);
    int hit = fault_disarm();
    s->runs++;
    EXPECTF(!fdt_wr_set_active(), "%s, %s %ld: a commit set left open", s->sc->tag, call, k);
    fdt_wr_set_abandon();
    EXPECTF(count_fds() == fds, "%s, %s %ld (%s): %d descriptors leaked", s->sc->tag, call, k,
            strerror(v->err), count_fds() - fds);
    /* A backup whose unlink failed after the commit point: the one file
     * a successful run may leave (never the journal: while it exists the
     * commit is not done). */
    if (refused[0] && rc == FDT_IO_OK && strstr(refused, ".old."))
        __real_unlink(refused);
    buf now = snap(s->dir, 1);
    if (!hit) {
        EXPECTF(rc == FDT_IO_OK && same_state(&now, &s->after),
                "%s, %s: status %d [%s] or other files with no failure injected", s->sc->tag,
                call, rc, err);
        free(now.p);
        return 1;
    }
    s->injected++;
    if (rc == FDT_IO_OK) {
        s->absorbed++;
        EXPECTF(v->absorb, "%s, %s %ld (%s): succeeded despite the failure", s->sc->tag, call,
                k, strerror(v->err));
        if (!same_state(&now, &s->after)) {
            buf l = snap(s->dir, 0);
            EXPECTF(0, "%s, %s %ld (%s): succeeded with other files; the folder holds:\n%s",
                    s->sc->tag, call, k, strerror(v->err), l.p);
            free(l.p);
        }
    } else {
        check_failed(s, v, k, rc, err, &now);
    }
    free(now.p);
    return 0;
}

static void sweep(const scenario *sc, const char *root)
{
    CHECK(strlen(root) + strlen(sc->tag) + 2 <= FDT_IO_PATH);
    sweep_state s = {.sc = sc};
    memcpy(s.dir, root, strlen(root));
    s.dir[strlen(root)] = '/';
    memcpy(s.dir + strlen(root) + 1, sc->tag, strlen(sc->tag) + 1);
    char err[2 * FDT_IO_PATH] = "";
    fresh(sc, s.dir);
    s.before = snap(s.dir, 1);
    int rc = sc->run(s.dir, err, sizeof err);
    EXPECTF(rc == FDT_IO_OK, "%s: the run without failures: %d [%s]", sc->tag, rc, err);
    s.after = snap(s.dir, 1);
    EXPECTF(!same_state(&s.before, &s.after), "%s: the run changed nothing", sc->tag);
    if (rc == FDT_IO_OK) {
        for (int i = 0; i < N_VARIANTS; i++)
            for (long k = 1; !one_run(&s, &variants[i], k); k++)
                if (k >= 10000) {
                    EXPECTF(0, "%s: more than 10000 calls of %s?", sc->tag,
                            call_name[variants[i].call]);
                    break;
                }
    }
    printf("%-20s %4ld runs, %4ld with a failure injected (%ld absorbed)\n", sc->tag, s.runs,
           s.injected, s.absorbed);
    remove_tree(s.dir);
    free(s.before.p);
    free(s.after.p);
}

/* ------------------------------------------------------------------ */
/* The writer's own limits                                            */
/* ------------------------------------------------------------------ */

/* Resources of the writer itself rather than the system's, failing the
 * same way: every registry slot taken (EMFILE), a commit set full
 * (EMFILE), a name too long for the registry (ENAMETOOLONG); the
 * signal handler's clean-up run in the middle of a write; the messages
 * of fdt_create_err. Each failure returns FDT_IO_EWRITE naming the file
 * and leaves the folder as it was. */
static void test_limits(const char *root)
{
    char dir[FDT_IO_PATH], p[FDT_IO_PATH], err[2 * FDT_IO_PATH];
    snprintf(dir, sizeof dir, "%s/limits", root);
    CHECK(mkdir(dir, 0755) == 0);
    char *longp = malloc(FDT_IO_PATH + 8);
    CHECK(longp);
    memset(longp, 'a', FDT_IO_PATH + 7);
    memcpy(longp + FDT_IO_PATH + 7 - 5, ".tets", 6);
    EXPECT(fdt_io_guard(longp) == -1);
    EXPECT(fdt_wr_mesh(longp, &mesh, err, sizeof err) == FDT_IO_EWRITE);
    free(longp);

    /* every slot guarded: no temporary can be made; then clean-up removes
     * the guarded targets, as the signal handler does */
    int slots[64], ng = 0;
    path_in(p, dir, "guarded");
    put_file(dir, "guarded", "a piece\n");
    while (ng < 64 && (slots[ng] = fdt_io_guard(p)) >= 0)
        ng++;
    EXPECT(ng > 0 && ng < 64);
    EXPECT(write_mesh(dir, "m.tets", err, sizeof err) == FDT_IO_EWRITE &&
           strstr(err, strerror(EMFILE)));
    fdt_io_unguard(-1);
    fdt_io_unguard(slots[ng - 1]);
    fdt_io_unguard(slots[ng - 1]); /* not guarded any more: nothing */
    fdt_io_cleanup_temps();
    EXPECT(access(p, F_OK) != 0 && count_entries(dir) == 0);

    /* a commit set holds 64 files: the 65th write fails, the set goes */
    EXPECT(fdt_wr_set_commit(err, sizeof err) == FDT_IO_OK); /* none open */
    EXPECT(fdt_wr_set_begin(0) == 0);
    int r = FDT_IO_OK, k;
    for (k = 0; k < 70 && r == FDT_IO_OK; k++) {
        char name[32];
        snprintf(name, sizeof name, "s%d.json", k);
        r = side_file(dir, name, err, sizeof err);
    }
    EXPECTF(r == FDT_IO_EWRITE && k == 65 && strstr(err, dir), "%d at %d [%s]", r, k, err);
    fdt_wr_set_abandon();
    EXPECT(count_entries(dir) == 0);

    /* the signal handler's clean-up in the middle of a set and a file */
    EXPECT(fdt_wr_set_begin(0) == 0);
    EXPECT(write_mesh(dir, "m.ele", err, sizeof err) == FDT_IO_OK);
    fdt_wr_side *side;
    path_in(p, dir, "s.json");
    EXPECT(fdt_wr_side_open(p, &side, err, sizeof err) != NULL);
    fdt_io_cleanup_temps();
    EXPECT(!fdt_wr_set_active() && count_entries(dir) == 0);
    fdt_wr_side_abandon(side);

    /* a commit fault hook that names no step is ignored */
    setenv("FDT_TEST_COMMIT_FAULT", "2", 1);
    EXPECT(fdt_wr_set_begin(0) == 0);
    EXPECT(write_mesh(dir, "m.tets", err, sizeof err) == FDT_IO_OK);
    EXPECT(fdt_wr_set_commit(err, sizeof err) == FDT_IO_OK);
    unsetenv("FDT_TEST_COMMIT_FAULT");
    path_in(p, dir, "m.tets");
    EXPECT(unlink(p) == 0);

    /* why a file cannot be created, as the CLI says it */
    static const int errs[] = {ENOENT, ENOTDIR, EACCES, EPERM, EROFS, EISDIR, ENOSPC, ENOMEM};
    for (int i = 0; i < 8; i++) {
        int want = errs[i] == ENOMEM ? FDT_IO_ENOMEM : FDT_IO_EWRITE;
        EXPECT(fdt_create_err(err, sizeof err, "output", "/m.vtu", errs[i]) == want &&
               strstr(err, "/m.vtu"));
        EXPECT(fdt_create_err(NULL, 0, "output", "m.vtu", errs[i]) == want);
    }
    EXPECT(fdt_create_err(err, sizeof err, "output", "m.vtu", ENOENT) == FDT_IO_EWRITE &&
           strstr(err, "folder . does not exist"));
    rmdir(dir);
}

/* A streamed write whose caller takes no message (diag NULL, size 0):
 * the same codes, nothing written where the message would go; a variant
 * v's k-th call failing (k 0: none). */
static int quiet_stream(const char *dir, const variant *v, long k)
{
    char p[FDT_IO_PATH];
    path_in(p, dir, "q.ele");
    fdt_stream_writer *w = NULL;
    if (k)
        fault_arm(v, k);
    int rc = fdt_stream_writer_open(&w, p, NULL, mesh.xyz, mesh.n_points, 0, NULL, 0);
    if (rc == FDT_OK) {
        fdt_sink sink;
        fdt_stream_writer_sink(w, &sink);
        sink.tets(sink.user, mesh.tets, mesh.n_tets);
        sink.hull(sink.user, mesh.hull, mesh.n_hull);
        rc = fdt_stream_writer_close(&w, 1, NULL, 0);
    }
    fault_disarm();
    return rc;
}

static void test_stream_quiet(const char *root)
{
    char dir[FDT_IO_PATH];
    snprintf(dir, sizeof dir, "%s/quiet", root);
    CHECK(mkdir(dir, 0755) == 0);
    EXPECT(fdt_stream_format_ok("case/polyMesh", NULL) == 0);
    EXPECT(fdt_stream_format_ok("m.vtk", NULL) == 0);
    EXPECT(quiet_stream(dir, NULL, 0) == FDT_OK && count_entries(dir) == 3);
    remove_tree(dir);
    CHECK(mkdir(dir, 0755) == 0);
    static const variant fails[] = {{C_FWRITE, ENOSPC, 0}, {C_RENAME, EIO, 0},
                                    {C_FTELLO, EOVERFLOW, 0}};
    for (int i = 0; i < 3; i++) {
        EXPECTF(quiet_stream(dir, &fails[i], 1) == FDT_EIO, "%s", call_name[fails[i].call]);
        EXPECTF(count_entries(dir) == 0, "%s", call_name[fails[i].call]);
    }
    /* the stale .neigh that cannot be removed after the renames */
    static const variant unl = {C_UNLINK, EIO, 0};
    EXPECT(quiet_stream(dir, &unl, 1) == FDT_EIO && count_entries(dir) == 3);
    remove_tree(dir);
}

int main(void)
{
    /* Every commit set fsyncs its journal and folder, a few thousand
     * times in all: on a busy disk that takes many seconds, in memory
     * (/dev/shm, where there is one) none. TMPDIR still wins. */
    const char *tmp = getenv("TMPDIR");
    if (!tmp || !*tmp)
        tmp = access("/dev/shm", W_OK | X_OK) == 0 ? "/dev/shm" : "/tmp";
    char root[FDT_IO_PATH];
    snprintf(root, sizeof root, "%s/fdt_writer_faults_XXXXXX", tmp);
    CHECK(mkdtemp(root) != NULL);
    fdt_result *r;
    make_mesh(&r);
    for (int i = 0; i < N_SCENARIOS; i++)
        sweep(&scenarios[i], root);
    test_limits(root);
    test_stream_quiet(root);
    remove_tree(root);
    fdt_result_free(&r);
    return test_report("test_writer_faults");
}
