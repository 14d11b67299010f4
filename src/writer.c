/*
 * Mesh writers (src/writer.h): canonical .tets, TetGen .node/.ele/.face/
 * .neigh, VTK XML .vtu and legacy .vtk.
 *
 * Every file goes to a temporary ".NAME.tmp.XXXXXX" beside its target and
 * is renamed over the target only once every byte of it (and, for TetGen,
 * of all four files) has been written and closed without error. So a
 * failed, full-disk or interrupted run never leaves a truncated mesh that
 * a later stage could mistake for a complete one.
 *
 * Output goes through our own large buffer and is handed to stdio in big
 * chunks: formatting millions of integers with fprintf would cost seconds,
 * while the hand-rolled formatter below writes 6.5M tets in a fraction of
 * one. Every fwrite/fprintf/fflush/fclose result is checked and the first
 * errno is kept for the message.
 *
 * Not thread-safe: the CLI and tests write one mesh at a time.
 */
#include "writer.h"
#include "reader.h" /* FDT_IO_* codes */

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

/* ------------------------------------------------------------------------ */
/* Registry of live temporary files                                         */
/* ------------------------------------------------------------------------ */

/*
 * This registry is the one mutable global of the project, and it has to
 * be: a SIGINT/SIGTERM handler receives no user pointer, yet must find and
 * unlink the temporary files of a write in progress, so their names must
 * live where the handler can reach them. The handler may only read
 * fixed-size buffers and sig_atomic_t flags and call unlink() (all
 * async-signal-safe), hence fixed arrays rather than a malloc'd list.
 *
 * Each slot has a state; the path buffers of a slot are only written while
 * its state is SLOT_FREE, and the state is stored after them (volatile
 * accesses are not reordered against each other), so the handler never
 * sees a half-written name under a live state:
 *   SLOT_TEMP      the temporary exists (or is being created): unlink it.
 *   SLOT_RENAMING  rename(temp, target) may or may not have happened:
 *                  unlink both, so an interrupted run leaves no output.
 *   SLOT_RENAMED   the target is complete, but the rest of its file set
 *                  (TetGen writes four) is not yet: unlink the target.
 * The writer frees every slot before fdt_write_mesh() returns.
 */
#define FDT_IO_SLOTS 8

enum { SLOT_FREE = 0, SLOT_TEMP = 1, SLOT_RENAMING = 2, SLOT_RENAMED = 3 };

static char fdt_io_tmp_path[FDT_IO_SLOTS][FDT_IO_PATH];
static char fdt_io_dst_path[FDT_IO_SLOTS][FDT_IO_PATH];
static volatile sig_atomic_t fdt_io_state[FDT_IO_SLOTS];

void fdt_io_cleanup_temps(void)
{
    for (int i = 0; i < FDT_IO_SLOTS; i++) {
        sig_atomic_t st = fdt_io_state[i];
        if (st == SLOT_TEMP || st == SLOT_RENAMING)
            unlink(fdt_io_tmp_path[i]);
        if (st == SLOT_RENAMING || st == SLOT_RENAMED)
            unlink(fdt_io_dst_path[i]);
        fdt_io_state[i] = SLOT_FREE;
    }
}

/* ------------------------------------------------------------------------ */
/* Buffered output file                                                     */
/* ------------------------------------------------------------------------ */

#define OUT_BUF_SIZE (1u << 20)
/* The longest item put in one go: a %.17g double is at most 24 chars. */
#define OUT_MAX_ITEM 64

typedef struct out_file {
    FILE *f;
    int slot;          /* registry slot, -1 when none */
    const char *path;  /* the target (for messages) */
    char *buf;
    size_t len;
    int err;           /* first errno seen, 0 while all is well */
} out_file;

static void out_fail(out_file *o, int e)
{
    if (o->err == 0)
        o->err = e ? e : EIO;
}

static void out_flush(out_file *o)
{
    if (o->len == 0 || o->err)
        return;
    errno = 0;
    if (fwrite(o->buf, 1, o->len, o->f) != o->len)
        out_fail(o, errno);
    o->len = 0;
}

/* Makes room for n more bytes (n <= OUT_BUF_SIZE). */
static inline char *out_room(out_file *o, size_t n)
{
    if (OUT_BUF_SIZE - o->len < n) {
        out_flush(o);
        if (o->err)
            o->len = 0; /* keep going into the bin; the error is final */
    }
    return o->buf + o->len;
}

static void out_bytes(out_file *o, const void *p, size_t n)
{
    const char *s = p;
    while (n > 0) {
        size_t room = OUT_BUF_SIZE - o->len;
        if (room == 0) {
            out_flush(o);
            if (o->err)
                return;
            room = OUT_BUF_SIZE;
        }
        size_t k = n < room ? n : room;
        memcpy(o->buf + o->len, s, k);
        o->len += k;
        s += k;
        n -= k;
    }
}

static void out_str(out_file *o, const char *s)
{
    out_bytes(o, s, strlen(s));
}

/* Two decimal digits per lookup halves the divisions. */
static const char digit_pairs[201] =
    "00010203040506070809101112131415161718192021222324252627282930313233"
    "34353637383940414243444546474849505152535455565758596061626364656667"
    "68697071727374757677787980818283848586878889909192939495969798990";

/* Writes v in decimal at p, returns the number of chars (at most 20). */
static inline size_t fmt_u64(char *p, uint64_t v)
{
    char tmp[20];
    char *e = tmp + sizeof tmp, *s = e;
    while (v >= 100) {
        unsigned r = (unsigned)(v % 100);
        v /= 100;
        s -= 2;
        memcpy(s, digit_pairs + 2 * r, 2);
    }
    if (v >= 10) {
        s -= 2;
        memcpy(s, digit_pairs + 2 * v, 2);
    } else {
        *--s = (char)('0' + v);
    }
    size_t n = (size_t)(e - s);
    memcpy(p, s, n);
    return n;
}

static inline size_t fmt_i64(char *p, int64_t v)
{
    if (v < 0) {
        *p = '-';
        return 1 + fmt_u64(p + 1, (uint64_t)0 - (uint64_t)v);
    }
    return fmt_u64(p, (uint64_t)v);
}

static inline void out_i64(out_file *o, int64_t v)
{
    char *p = out_room(o, 21);
    o->len += fmt_i64(p, v);
}

static inline void out_char(out_file *o, char c)
{
    char *p = out_room(o, 1);
    *p = c;
    o->len++;
}

/* %.17g: enough digits that strtod gives back the very same double. */
static void out_double(out_file *o, double x)
{
    char *p = out_room(o, OUT_MAX_ITEM);
    int k = snprintf(p, OUT_MAX_ITEM, "%.17g", x);
    if (k < 0 || k >= OUT_MAX_ITEM)
        out_fail(o, EINVAL);
    else
        o->len += (size_t)k;
}

/* ------------------------------------------------------------------------ */
/* Errors                                                                    */
/* ------------------------------------------------------------------------ */

static int set_err(char *err, size_t errlen, int code, const char *path,
                   const char *what)
{
    if (err && errlen > 0)
        snprintf(err, errlen, "%s: %s", path ? path : "(null)", what);
    return code;
}

/* An errno as FDT_IO_EWRITE, except ENOMEM (our buffer, or stdio's):
 * running out of memory is not a write failure and the CLI says so. */
static int set_errno_err(char *err, size_t errlen, const char *path, int e)
{
    return set_err(err, errlen, e == ENOMEM ? FDT_IO_ENOMEM : FDT_IO_EWRITE,
                   path, strerror(e ? e : EIO));
}

/* ------------------------------------------------------------------------ */
/* Temporary files                                                           */
/* ------------------------------------------------------------------------ */

static int slot_acquire(void)
{
    for (int i = 0; i < FDT_IO_SLOTS; i++)
        if (fdt_io_state[i] == SLOT_FREE)
            return i;
    return -1;
}

/*
 * Opens a temporary file for target in target's directory (a rename only
 * stays atomic within one file system). Returns 0 or an errno value.
 */
static int out_open(out_file *o, const char *target, mode_t mode)
{
    memset(o, 0, sizeof *o);
    o->slot = -1;
    o->path = target;

    const char *slash = strrchr(target, '/');
    const char *base = slash ? slash + 1 : target;
    size_t dirlen = (size_t)(base - target);
    size_t baselen = strlen(base);
    static const char suffix[] = ".tmp.XXXXXX";
    if (baselen == 0)
        return EISDIR;
    /* Both paths must fit the registry's fixed buffers. */
    if (dirlen + 1 + baselen + sizeof suffix > FDT_IO_PATH ||
        strlen(target) + 1 > FDT_IO_PATH)
        return ENAMETOOLONG;
    int slot = slot_acquire();
    if (slot < 0)
        return EMFILE;
    char *tmp = fdt_io_tmp_path[slot];
    memcpy(tmp, target, dirlen);
    tmp[dirlen] = '.';
    memcpy(tmp + dirlen + 1, base, baselen);
    memcpy(tmp + dirlen + 1 + baselen, suffix, sizeof suffix);
    memcpy(fdt_io_dst_path[slot], target, strlen(target) + 1);
    /* Live before mkstemp creates the file: mkstemp writes the final name
     * into tmp before it opens, so a signal at any point finds either a
     * name that does not exist yet or the file it must remove. */
    fdt_io_state[slot] = SLOT_TEMP;
    o->slot = slot;

    int fd = mkstemp(tmp);
    if (fd < 0) {
        int e = errno;
        fdt_io_state[slot] = SLOT_FREE;
        o->slot = -1;
        return e;
    }
    /* mkstemp creates mode 0600; give the output the permissions a plain
     * fopen would have (the caller passes 0666 & ~umask). */
    if (fchmod(fd, mode) != 0) {
        int e = errno;
        close(fd);
        unlink(tmp);
        fdt_io_state[slot] = SLOT_FREE;
        o->slot = -1;
        return e;
    }
    o->f = fdopen(fd, "wb");
    if (!o->f) {
        int e = errno;
        close(fd);
        unlink(tmp);
        fdt_io_state[slot] = SLOT_FREE;
        o->slot = -1;
        return e;
    }
    o->buf = malloc(OUT_BUF_SIZE);
    if (!o->buf) {
        fclose(o->f);
        o->f = NULL;
        unlink(tmp);
        fdt_io_state[slot] = SLOT_FREE;
        o->slot = -1;
        return ENOMEM;
    }
    return 0;
}

/* Flushes and closes; returns 0 or the first errno of the file's life. */
static int out_close(out_file *o)
{
    if (o->f) {
        out_flush(o);
        errno = 0;
        if (fflush(o->f) != 0)
            out_fail(o, errno);
        if (ferror(o->f))
            out_fail(o, errno);
        errno = 0;
        if (fclose(o->f) != 0) /* reports deferred errors (NFS, ENOSPC) */
            out_fail(o, errno);
        o->f = NULL;
    }
    free(o->buf);
    o->buf = NULL;
    return o->err;
}

/* Abandons the file: closes it, removes the temporary, frees the slot. */
static void out_abandon(out_file *o)
{
    if (o->f) {
        fclose(o->f);
        o->f = NULL;
    }
    free(o->buf);
    o->buf = NULL;
    if (o->slot >= 0) {
        sig_atomic_t st = fdt_io_state[o->slot];
        if (st == SLOT_TEMP || st == SLOT_RENAMING)
            unlink(fdt_io_tmp_path[o->slot]);
        if (st == SLOT_RENAMING || st == SLOT_RENAMED)
            unlink(fdt_io_dst_path[o->slot]);
        fdt_io_state[o->slot] = SLOT_FREE;
        o->slot = -1;
    }
}

/*
 * Closes files[0..k) and renames them over their targets, all or none:
 * if any close or rename fails, every temporary and every target already
 * renamed in this set is removed (a .ele set with a stale .neigh beside a
 * new .ele would be worse than none).
 *
 * rename() replaces the directory entry, never the file behind it: a
 * target that is a symbolic link is replaced by the new file and what it
 * pointed to is left as it was; a target that is one of several hard
 * links leaves the other names with the old contents. We keep it so
 * rather than writing through the link: a link can then never lead the
 * writer to a file other than the name it was given (an input reached
 * through one, a file outside the output directory), and the temporary
 * is made by mkstemp() (O_CREAT | O_EXCL), which never opens an existing
 * file either. So the writer itself cannot destroy an input's bytes
 * except by replacing the input's own name. The CLI refuses that, and
 * also a target that is a link to or another name of its input
 * (fdt_same_file): whoever names it expects the write to go through, and
 * would instead find the link silently turned into a plain file.
 */
static int commit_all(out_file *files, int k, char *err, size_t errlen)
{
    for (int i = 0; i < k; i++) {
        int e = out_close(&files[i]);
        if (e) {
            for (int j = 0; j < k; j++)
                out_abandon(&files[j]);
            return set_errno_err(err, errlen, files[i].path, e);
        }
    }
    for (int i = 0; i < k; i++) {
        int slot = files[i].slot;
        fdt_io_state[slot] = SLOT_RENAMING;
        if (rename(fdt_io_tmp_path[slot], fdt_io_dst_path[slot]) != 0) {
            int e = errno;
            /* The target was not replaced: only the temporary goes. */
            fdt_io_state[slot] = SLOT_TEMP;
            for (int j = 0; j < k; j++)
                out_abandon(&files[j]);
            return set_errno_err(err, errlen, files[i].path, e);
        }
        fdt_io_state[slot] = SLOT_RENAMED;
    }
    for (int i = 0; i < k; i++) {
        fdt_io_state[files[i].slot] = SLOT_FREE;
        files[i].slot = -1;
    }
    return FDT_IO_OK;
}

static mode_t creation_mode(void)
{
    /* The only portable way to read the umask is to set it and put it
     * back; the writer runs in the CLI's main thread, nothing else is
     * creating files at that moment. */
    mode_t mask = umask(0);
    umask(mask);
    return (mode_t)(0666 & ~mask);
}

/* ------------------------------------------------------------------------ */
/* Mesh validation                                                           */
/* ------------------------------------------------------------------------ */

/* Every tet id in [0, n_points); hull too; neighbours in [-1, n_tets). */
static int validate(const char *path, const fdt_mesh_view *m, char *err,
                    size_t errlen)
{
    char what[160];
    if ((m->n_tets > 0 && !m->tets) || (m->n_hull > 0 && !m->hull) ||
        (m->n_points > 0 && !m->xyz))
        return set_err(err, errlen, FDT_IO_EFORMAT, path,
                       "mesh arrays missing");
    for (size_t i = 0; i < 4 * m->n_tets; i++) {
        fdt_vid v = m->tets[i];
        if (v < 0 || (size_t)v >= m->n_points) {
            snprintf(what, sizeof what,
                     "tet %zu uses vertex %ld, outside 0..%zu", i / 4,
                     (long)v, m->n_points);
            return set_err(err, errlen, FDT_IO_EFORMAT, path, what);
        }
    }
    for (size_t i = 0; i < 3 * m->n_hull; i++) {
        fdt_vid v = m->hull[i];
        if (v < 0 || (size_t)v >= m->n_points) {
            snprintf(what, sizeof what,
                     "hull face %zu uses vertex %ld, outside 0..%zu", i / 3,
                     (long)v, m->n_points);
            return set_err(err, errlen, FDT_IO_EFORMAT, path, what);
        }
    }
    if (m->nbrs) {
        for (size_t i = 0; i < 4 * m->n_tets; i++) {
            fdt_tid t = m->nbrs[i];
            if (t < -1 || (t >= 0 && (uint64_t)t >= m->n_tets)) {
                snprintf(what, sizeof what,
                         "tet %zu has neighbour %lld, outside -1..%zu", i / 4,
                         (long long)t, m->n_tets);
                return set_err(err, errlen, FDT_IO_EFORMAT, path, what);
            }
        }
    }
    return FDT_IO_OK;
}

/* ------------------------------------------------------------------------ */
/* .tets                                                                      */
/* ------------------------------------------------------------------------ */

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

static int write_tets(const char *path, const fdt_mesh_view *m, char *err,
                      size_t errlen)
{
    out_file o;
    int e = out_open(&o, path, creation_mode());
    if (e)
        return set_errno_err(err, errlen, path, e);

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
            out_abandon(&o);
            return set_err(err, errlen, FDT_IO_EFORMAT, path, what);
        }
        if (t > 0 && cmp4(prev, s) >= 0) {
            snprintf(what, sizeof what,
                     "tets are not in canonical order at tet %zu "
                     "(call fdt_result_sort first)", t);
            out_abandon(&o);
            return set_err(err, errlen, FDT_IO_EFORMAT, path, what);
        }
        memcpy(prev, s, sizeof s);
        /* 4 ids of at most 10 digits, 3 spaces and a newline. */
        char *p = out_room(&o, 48);
        size_t k = fmt_u64(p, (uint64_t)s[0]);
        p[k++] = ' ';
        k += fmt_u64(p + k, (uint64_t)s[1]);
        p[k++] = ' ';
        k += fmt_u64(p + k, (uint64_t)s[2]);
        p[k++] = ' ';
        k += fmt_u64(p + k, (uint64_t)s[3]);
        p[k++] = '\n';
        o.len += k;
    }
    return commit_all(&o, 1, err, errlen);
}

/* ------------------------------------------------------------------------ */
/* File sets and file identity                                               */
/* ------------------------------------------------------------------------ */

/* Case-insensitive "does s end with ext" (ext lowercase, with the dot). */
static int has_ext(const char *s, const char *ext)
{
    size_t ls = strlen(s), le = strlen(ext);
    if (ls <= le)
        return 0;
    const char *p = s + ls - le;
    for (size_t i = 0; i < le; i++) {
        char c = p[i];
        if (c >= 'A' && c <= 'Z')
            c = (char)(c - 'A' + 'a');
        if (c != ext[i])
            return 0;
    }
    /* "dir/.ele" has an empty base name: not a mesh file name. */
    return p[-1] != '/';
}

int fdt_output_files(const char *path,
                     char names[FDT_IO_MAX_FILES][FDT_IO_PATH])
{
    size_t len = strlen(path);
    if (has_ext(path, ".tets") || has_ext(path, ".vtu") ||
        has_ext(path, ".vtk")) {
        if (len + 1 > FDT_IO_PATH)
            return -1;
        memcpy(names[0], path, len + 1);
        return 1;
    }
    if (!has_ext(path, ".ele"))
        return 0;
    static const char *const exts[4] = { ".node", ".ele", ".face",
                                         ".neigh" };
    size_t baselen = len - 4;
    for (int i = 0; i < 4; i++) {
        if (baselen + strlen(exts[i]) + 1 > FDT_IO_PATH)
            return -1;
        memcpy(names[i], path, baselen);
        if (i == 1) /* keep the user's spelling of the .ele name itself */
            memcpy(names[i] + baselen, path + baselen, 5);
        else
            memcpy(names[i] + baselen, exts[i], strlen(exts[i]) + 1);
    }
    return 4;
}

/*
 * What a path reaches (fdt_same_file): an existing file, or a name in a
 * directory where opening it would create one.
 */
enum { ID_UNKNOWN = 0, ID_FILE = 1, ID_NEW = 2 };

typedef struct file_id {
    int kind;
    dev_t dev;                /* ID_FILE: the file's; ID_NEW: its directory's */
    ino_t ino;
    char name[FDT_IO_PATH];   /* ID_NEW: the last component */
} file_id;

/* At most this many dangling links in a row, like the kernel's own limit
 * on links followed in one lookup (Linux: 40). */
#define FDT_IO_MAX_HOPS 40

static void file_id_of(const char *path, file_id *id)
{
    id->kind = ID_UNKNOWN;
    char cur[FDT_IO_PATH];
    size_t len = strlen(path);
    if (len + 1 > sizeof cur)
        return;
    memcpy(cur, path, len + 1);
    for (int hop = 0; hop < FDT_IO_MAX_HOPS; hop++) {
        struct stat st;
        if (stat(cur, &st) == 0) {
            id->kind = ID_FILE;
            id->dev = st.st_dev;
            id->ino = st.st_ino;
            return;
        }
        if (errno != ENOENT)
            return;
        char *slash = strrchr(cur, '/');
        /* A dangling link: fopen(path, "w") creates the file it names
         * (that is how --stats-json is written), so that file is the one
         * to compare. A relative target counts from the link's directory. */
        if (lstat(cur, &st) == 0 && S_ISLNK(st.st_mode)) {
            char target[FDT_IO_PATH];
            ssize_t k = readlink(cur, target, sizeof target - 1);
            if (k <= 0)
                return;
            target[k] = '\0';
            size_t dirlen = (target[0] == '/' || !slash)
                                ? 0
                                : (size_t)(slash - cur) + 1;
            if (dirlen + (size_t)k + 1 > sizeof cur)
                return;
            memmove(cur + dirlen, target, (size_t)k + 1);
            continue;
        }
        /* Not there: the directory it would be made in, and its name. */
        const char *base = slash ? slash + 1 : cur;
        if (!*base)
            return;
        size_t baselen = strlen(base) + 1;
        memmove(id->name, base, baselen);
        if (!slash)
            memcpy(cur, ".", 2);
        else if (slash == cur)
            cur[1] = '\0'; /* "/name": the root directory */
        else
            *slash = '\0';
        if (stat(cur, &st) != 0 || !S_ISDIR(st.st_mode))
            return;
        id->kind = ID_NEW;
        id->dev = st.st_dev;
        id->ino = st.st_ino;
        return;
    }
}

int fdt_same_file(const char *a, const char *b)
{
    if (strcmp(a, b) == 0)
        return 1;
    file_id ia, ib;
    file_id_of(a, &ia);
    file_id_of(b, &ib);
    int same = ia.kind != ID_UNKNOWN && ia.kind == ib.kind &&
               ia.dev == ib.dev && ia.ino == ib.ino &&
               (ia.kind == ID_FILE || strcmp(ia.name, ib.name) == 0);
    return same;
}

/* ------------------------------------------------------------------------ */
/* TetGen .node / .ele / .face / .neigh                                       */
/* ------------------------------------------------------------------------ */

static void put_node(out_file *o, const fdt_mesh_view *m)
{
    /* "<points> <dimension> <attributes> <boundary markers>", then
     * "<index> <x> <y> <z>", first index 0 (TetGen accepts either base
     * and follows the first index it reads). */
    out_i64(o, (int64_t)m->n_points);
    out_str(o, " 3 0 0\n");
    for (size_t i = 0; i < m->n_points && !o->err; i++) {
        out_i64(o, (int64_t)i);
        for (int c = 0; c < 3; c++) {
            out_char(o, ' ');
            out_double(o, m->xyz[3 * i + (size_t)c]);
        }
        out_char(o, '\n');
    }
}

/* "<count><header>", then "<index> <v_1> ... <v_k>" a row, the values
 * from vid or, where vid is NULL, from tid: the bodies of .ele, .face
 * and .neigh. */
static void put_rows(out_file *o, size_t count, const char *header, int k,
                     const fdt_vid *vid, const fdt_tid *tid)
{
    out_i64(o, (int64_t)count);
    out_str(o, header);
    for (size_t r = 0; r < count && !o->err; r++) {
        out_i64(o, (int64_t)r);
        for (size_t at = (size_t)k * r; at < (size_t)k * (r + 1); at++) {
            out_char(o, ' ');
            out_i64(o, vid ? (int64_t)vid[at] : (int64_t)tid[at]);
        }
        out_char(o, '\n');
    }
}

static void put_ele(out_file *o, const fdt_mesh_view *m)
{
    /* "<tets> <nodes per tet> <region attribute>", then
     * "<index> <v0> <v1> <v2> <v3>" in the tet's own order. Our positive
     * orientation, det(b-a, c-a, d-a) > 0, is TetGen's too (checked
     * against libtet's output), as are outward hull faces and neighbour i
     * opposite vertex i: TetGen readers need no conversion. */
    put_rows(o, m->n_tets, " 4 0\n", 4, m->tets, NULL);
}

static void put_face(out_file *o, const fdt_mesh_view *m)
{
    /* "<faces> <boundary marker>", then "<index> <v0> <v1> <v2>". */
    put_rows(o, m->n_hull, " 0\n", 3, m->hull, NULL);
}

static void put_neigh(out_file *o, const fdt_mesh_view *m)
{
    /* "<tets> 4", then "<index> <n0> <n1> <n2> <n3>": neighbour i is
     * opposite vertex i (TetGen's convention and ours), -1 on the hull. */
    put_rows(o, m->n_tets, " 4\n", 4, NULL, m->nbrs);
}

static int write_tetgen(const char *path, const fdt_mesh_view *m, char *err,
                        size_t errlen)
{
    if (!m->nbrs)
        return set_err(err, errlen, FDT_IO_EFORMAT, path,
                       ".ele output needs tet neighbours "
                       "(settings.neighbors)");
    void (*const put[4])(out_file *, const fdt_mesh_view *) = {
        put_node, put_ele, put_face, put_neigh
    };
    /* fdt_output_files() lists .node, .ele, .face, .neigh in this order. */
    char names[FDT_IO_MAX_FILES][FDT_IO_PATH];
    if (fdt_output_files(path, names) != 4)
        return set_errno_err(err, errlen, path, ENAMETOOLONG);

    out_file files[4];
    mode_t mode = creation_mode();
    int opened = 0;
    for (int i = 0; i < 4; i++) {
        int e = out_open(&files[i], names[i], mode);
        if (e) {
            for (int j = 0; j < opened; j++)
                out_abandon(&files[j]);
            return set_errno_err(err, errlen, names[i], e);
        }
        opened++;
        put[i](&files[i], m);
        /* Stop at the first write error instead of formatting on. */
        if (files[i].err) {
            int e2 = files[i].err;
            for (int j = 0; j < opened; j++)
                out_abandon(&files[j]);
            return set_errno_err(err, errlen, names[i], e2);
        }
    }
    /* files[i].path points into names[], which outlives commit_all. */
    return commit_all(files, 4, err, errlen);
}

/* ------------------------------------------------------------------------ */
/* VTK                                                                        */
/* ------------------------------------------------------------------------ */

static int host_is_little_endian(void)
{
    const uint16_t one = 1;
    unsigned char b;
    memcpy(&b, &one, 1);
    return b == 1;
}

#define VTK_TETRA 10

static int write_vtu(const char *path, const fdt_mesh_view *m, char *err,
                     size_t errlen)
{
    out_file o;
    int e = out_open(&o, path, creation_mode());
    if (e)
        return set_errno_err(err, errlen, path, e);

    /* Appended raw data: each array is a UInt64 byte count followed by the
     * bytes, in host order (byte_order says which); the offset attributes
     * count from the first byte after '_'. */
    uint64_t n = m->n_points, nt = m->n_tets;
    uint64_t sz_pts = 3 * n * sizeof(double);
    uint64_t sz_conn = 4 * nt * sizeof(int64_t);
    uint64_t sz_off = nt * sizeof(int64_t);
    uint64_t sz_typ = nt;
    uint64_t off_pts = 0;
    uint64_t off_conn = off_pts + 8 + sz_pts;
    uint64_t off_off = off_conn + 8 + sz_conn;
    uint64_t off_typ = off_off + 8 + sz_off;

    char head[2048];
    int k = snprintf(head, sizeof head,
        "<?xml version=\"1.0\"?>\n"
        "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
        "byte_order=\"%s\" header_type=\"UInt64\">\n"
        "  <UnstructuredGrid>\n"
        "    <Piece NumberOfPoints=\"%llu\" NumberOfCells=\"%llu\">\n"
        "      <Points>\n"
        "        <DataArray type=\"Float64\" Name=\"Points\" "
        "NumberOfComponents=\"3\" format=\"appended\" offset=\"%llu\"/>\n"
        "      </Points>\n"
        "      <Cells>\n"
        "        <DataArray type=\"Int64\" Name=\"connectivity\" "
        "format=\"appended\" offset=\"%llu\"/>\n"
        "        <DataArray type=\"Int64\" Name=\"offsets\" "
        "format=\"appended\" offset=\"%llu\"/>\n"
        "        <DataArray type=\"UInt8\" Name=\"types\" "
        "format=\"appended\" offset=\"%llu\"/>\n"
        "      </Cells>\n"
        "    </Piece>\n"
        "  </UnstructuredGrid>\n"
        "  <AppendedData encoding=\"raw\">\n"
        "   _",
        host_is_little_endian() ? "LittleEndian" : "BigEndian",
        (unsigned long long)n, (unsigned long long)nt,
        (unsigned long long)off_pts, (unsigned long long)off_conn,
        (unsigned long long)off_off, (unsigned long long)off_typ);
    if (k < 0 || (size_t)k >= sizeof head) {
        out_abandon(&o);
        return set_errno_err(err, errlen, path, EOVERFLOW);
    }
    out_bytes(&o, head, (size_t)k);

    out_bytes(&o, &sz_pts, 8);
    out_bytes(&o, m->xyz, (size_t)sz_pts);

    out_bytes(&o, &sz_conn, 8);
    for (size_t i = 0; i < 4 * m->n_tets && !o.err; i++) {
        int64_t v = m->tets[i];
        char *p = out_room(&o, 8);
        memcpy(p, &v, 8);
        o.len += 8;
    }
    out_bytes(&o, &sz_off, 8);
    for (size_t t = 0; t < m->n_tets && !o.err; t++) {
        int64_t v = 4 * (int64_t)(t + 1);
        char *p = out_room(&o, 8);
        memcpy(p, &v, 8);
        o.len += 8;
    }
    out_bytes(&o, &sz_typ, 8);
    for (size_t t = 0; t < m->n_tets && !o.err; t++)
        out_char(&o, VTK_TETRA);
    out_str(&o, "\n  </AppendedData>\n</VTKFile>\n");
    return commit_all(&o, 1, err, errlen);
}

static int write_vtk(const char *path, const fdt_mesh_view *m, char *err,
                     size_t errlen)
{
    out_file o;
    int e = out_open(&o, path, creation_mode());
    if (e)
        return set_errno_err(err, errlen, path, e);

    out_str(&o, "# vtk DataFile Version 3.0\n"
                "frontdt Delaunay tetrahedralization\n"
                "ASCII\n"
                "DATASET UNSTRUCTURED_GRID\n"
                "POINTS ");
    out_i64(&o, (int64_t)m->n_points);
    out_str(&o, " double\n");
    for (size_t i = 0; i < m->n_points && !o.err; i++) {
        out_double(&o, m->xyz[3 * i]);
        out_char(&o, ' ');
        out_double(&o, m->xyz[3 * i + 1]);
        out_char(&o, ' ');
        out_double(&o, m->xyz[3 * i + 2]);
        out_char(&o, '\n');
    }
    /* CELLS <cells> <list size>: each cell is its count then its ids. */
    out_str(&o, "CELLS ");
    out_i64(&o, (int64_t)m->n_tets);
    out_char(&o, ' ');
    out_i64(&o, 5 * (int64_t)m->n_tets);
    out_char(&o, '\n');
    for (size_t t = 0; t < m->n_tets && !o.err; t++) {
        out_char(&o, '4');
        for (int c = 0; c < 4; c++) {
            out_char(&o, ' ');
            out_i64(&o, m->tets[4 * t + (size_t)c]);
        }
        out_char(&o, '\n');
    }
    out_str(&o, "CELL_TYPES ");
    out_i64(&o, (int64_t)m->n_tets);
    out_char(&o, '\n');
    for (size_t t = 0; t < m->n_tets && !o.err; t++)
        out_str(&o, "10\n");
    return commit_all(&o, 1, err, errlen);
}

/* ------------------------------------------------------------------------ */

int fdt_write_mesh(const char *path, const fdt_mesh_view *m, char *err,
                   size_t errlen)
{
    if (err && errlen > 0)
        err[0] = '\0';
    if (!path || !m)
        return set_err(err, errlen, FDT_IO_EFORMAT, path,
                       "no path or no mesh");
    int r = validate(path, m, err, errlen);
    if (r != FDT_IO_OK)
        return r;
    if (has_ext(path, ".tets"))
        return write_tets(path, m, err, errlen);
    if (has_ext(path, ".ele"))
        return write_tetgen(path, m, err, errlen);
    if (has_ext(path, ".vtu"))
        return write_vtu(path, m, err, errlen);
    if (has_ext(path, ".vtk"))
        return write_vtk(path, m, err, errlen);
    return set_err(err, errlen, FDT_IO_EEXT, path,
                   "unknown output format (use .tets, .ele, .vtu or .vtk)");
}
