/*
 * Mesh writers (src/io/write/writer.h): the table of output formats, one row per
 * format (the writer functions are in src/fmt_*.c), the temporary files
 * and their renames, and the identity of files for the never-overwrite-
 * an-input check.
 *
 * Every file goes to a temporary ".NAME.tmp.XXXXXX" beside its target and
 * is renamed over the target only once every byte of it (and, for TetGen,
 * of all four files; in a commit set, of every output of the run) has
 * been written and closed without error. So a failed, full-disk or
 * interrupted run never leaves a truncated mesh that a later stage could
 * mistake for a complete one, nor (in a set) a mix of new and old outputs.
 *
 * Output goes through our own large buffer (src/io/write/outfile.h) and is handed
 * to stdio in big chunks. Every fwrite/fflush/fclose result is checked and
 * the first errno is kept for the message.
 *
 * The internal entry points are not thread-safe (the CLI and tests write
 * one mesh at a time); the public fdt_write_mesh takes a lock.
 */
#include "io/write/writer.h"
#include "base/abi.h"
#include "io/write/formats.h"
#include "mesh/periodic.h"
#include "mesh/result.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
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
 *   SLOT_GUARDED   a file of a set written outside this writer (a rank's
 *                  piece of an MPI output, src/mpi/mpi_output.c) that is
 *                  not complete yet: unlink the target (fdt_io_guard).
 * The writer frees every slot before fdt_wr_mesh() returns.
 */
/* 32: eight -o outputs streamed at once, three files each, and a
 * --stats-json beside them. */
#define FDT_IO_SLOTS 32

enum { SLOT_FREE = 0, SLOT_TEMP = 1, SLOT_RENAMING = 2, SLOT_RENAMED = 3, SLOT_GUARDED = 4 };

static char fdt_io_tmp_path[FDT_IO_SLOTS][FDT_IO_PATH];
static char fdt_io_dst_path[FDT_IO_SLOTS][FDT_IO_PATH];
static volatile sig_atomic_t fdt_io_state[FDT_IO_SLOTS];
/* The temporary directory of a directory format (an OpenFOAM polyMesh)
 * being filled: written only while the flag is 0, removed by the handler
 * after the files in it (the slots above) while the flag is 1. */
static char fdt_io_tmpdir[FDT_IO_PATH];
static volatile sig_atomic_t fdt_io_tmpdir_live;

static void set_cleanup(void);

void fdt_io_cleanup_temps(void)
{
    set_cleanup(); /* first: it may rename a temporary the slots name */
    for (int i = 0; i < FDT_IO_SLOTS; i++) {
        sig_atomic_t st = fdt_io_state[i];
        if (st == SLOT_TEMP || st == SLOT_RENAMING)
            unlink(fdt_io_tmp_path[i]);
        if (st == SLOT_RENAMING || st == SLOT_RENAMED || st == SLOT_GUARDED)
            unlink(fdt_io_dst_path[i]);
        fdt_io_state[i] = SLOT_FREE;
    }
    if (fdt_io_tmpdir_live) {
        rmdir(fdt_io_tmpdir); /* empty now, unless renamed already */
        fdt_io_tmpdir_live = 0;
    }
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

int fdt_io_guard(const char *target)
{
    if (strlen(target) + 1 > FDT_IO_PATH)
        return -1;
    int slot = slot_acquire();
    if (slot < 0)
        return -1;
    /* the name first, then the state that publishes it to the handler */
    memcpy(fdt_io_dst_path[slot], target, strlen(target) + 1);
    fdt_io_state[slot] = SLOT_GUARDED;
    return slot;
}

void fdt_io_unguard(int slot)
{
    if (slot >= 0 && fdt_io_state[slot] == SLOT_GUARDED)
        fdt_io_state[slot] = SLOT_FREE;
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

/* ------------------------------------------------------------------------ */
/* Why a file cannot be created (issue 34 item 8)                            */
/* ------------------------------------------------------------------------ */

/* path's folder ("." when it names none, "/" for "/name") into dir. */
static void folder_of(const char *path, char *dir, size_t len)
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        snprintf(dir, len, ".");
    else if (slash == path)
        snprintf(dir, len, "/");
    else
        snprintf(dir, len, "%.*s", (int)(slash - path), path);
}

int fdt_create_err(char *err, size_t errlen, const char *role, const char *path, int e)
{
    char dir[FDT_IO_PATH];
    folder_of(path, dir, sizeof dir);
    int code = e == ENOMEM ? FDT_IO_ENOMEM : FDT_IO_EWRITE;
    if (!err || errlen == 0)
        return code;
    switch (e) {
    case ENOENT:
        snprintf(err, errlen, "cannot create %s %s: folder %s does not exist", role, path, dir);
        break;
    case ENOTDIR:
        snprintf(err, errlen, "cannot create %s %s: %s is not a folder", role, path, dir);
        break;
    case EACCES:
    case EPERM:
    case EROFS:
        snprintf(err, errlen, "cannot create %s %s: folder %s is not writable (%s)", role, path,
                 dir, strerror(e));
        break;
    case EISDIR:
        snprintf(err, errlen, "cannot create %s %s: a folder has that name", role, path);
        break;
    default: /* not the folder's fault (no memory, no space): as every write error */
        return set_errno_err(err, errlen, path, e);
    }
    return code;
}

int fdt_output_dir_check(const char *role, const char *path, char *err, size_t errlen)
{
    char dir[FDT_IO_PATH];
    if (strlen(path) + 1 > sizeof dir) {
        fdt_create_err(err, errlen, role, path, ENAMETOOLONG);
        return ENAMETOOLONG;
    }
    folder_of(path, dir, sizeof dir);
    struct stat st;
    int e = 0;
    if (stat(dir, &st) != 0)
        e = errno;
    else if (!S_ISDIR(st.st_mode))
        e = ENOTDIR;
    else if (access(dir, W_OK | X_OK) != 0)
        e = errno;
    else if (stat(path, &st) == 0 && S_ISDIR(st.st_mode))
        e = EISDIR;
    if (e)
        fdt_create_err(err, errlen, role, path, e);
    return e;
}

/* ------------------------------------------------------------------------ */
/* Commit sets: the outputs of one run renamed together (issue 34 item 3)   */
/* ------------------------------------------------------------------------ */

/*
 * Between fdt_wr_set_begin() and fdt_wr_set_commit() a commit renames
 * nothing: the closed, complete temporaries join the set, in the order
 * they were committed (the CLI's -o order, each output's files in its
 * format's order), and fdt_wr_set_commit() renames them all at the end:
 *
 *   1. backups: each target that exists gets a hard link beside it,
 *      ".NAME.old.PID.I" (where the file system has no links, the old
 *      target is renamed to that name at its turn, just before the new
 *      file takes its place);
 *   2. the journal ".frontdt-commit-PID" in the first target's folder,
 *      listing every TEMP -> FINAL pair and its backup, written and
 *      fsync'd (with its folder) before the first rename (not for a set
 *      of one file, whose one rename is the commit point);
 *   3. the renames, in the set's order;
 *   4. the commit point: the journal is removed; then the backups.
 *
 * A failure or SIGINT/SIGTERM anywhere before the commit point rolls the
 * set back: every backup is renamed over its target, a new target that
 * had none is removed, the temporaries and the journal are removed, so
 * every output is as it was before the run. After the commit point every
 * output is new (a signal then only removes the backups). A crash or
 * SIGKILL between 2 and 4 leaves the journal, which says how to undo the
 * renames by hand.
 *
 * Each step (its system call and the recorded state) runs with SIGINT
 * and SIGTERM blocked, so the handler (fdt_io_cleanup_temps) always finds
 * a state that says what is on disk; it rolls back with rename(),
 * unlink() and rmdir() alone, all async-signal-safe, on these fixed
 * buffers (written only while their entry is not yet counted in set_n).
 */
/* Eight polyMesh outputs (five files and their directory each) and a
 * --stats-json. */
#define FDT_SET_MAX 64

enum {
    ENT_FILE = 1,   /* a temporary renamed over its target (a polyMesh's
                       files: to their names in the temporary directory) */
    ENT_DIR = 2,    /* a temporary directory renamed to its target, after
                       its files */
    ENT_REMOVE = 3  /* a target the run removes (a streamed TetGen set's
                       stale .neigh) */
};
enum { STEP_WAIT = 0, STEP_LINKED, STEP_MOVED, STEP_PLACED };
enum { BAK_NONE = 0, BAK_LINK, BAK_MOVE };
enum { PHASE_OFF = 0, PHASE_OPEN, PHASE_COMMITTED };

static char set_tmp[FDT_SET_MAX][FDT_IO_PATH];
static char set_dst[FDT_SET_MAX][FDT_IO_PATH];
static char set_bak[FDT_SET_MAX][FDT_IO_PATH];
static volatile sig_atomic_t set_kind[FDT_SET_MAX];
static volatile sig_atomic_t set_step[FDT_SET_MAX];
static volatile sig_atomic_t set_bakmode[FDT_SET_MAX];
static volatile sig_atomic_t set_n;
static volatile sig_atomic_t set_phase;
static char set_journal[FDT_IO_PATH];
static volatile sig_atomic_t set_journal_live;
static int set_no_clobber;

/* Undoes whatever the entries' steps say was done, newest first, then
 * removes the temporaries and the journal. Async-signal-safe. */
static void set_rollback(void)
{
    int n = (int)set_n;
    for (int i = n - 1; i >= 0; i--) {
        sig_atomic_t k = set_kind[i], st = set_step[i];
        if (k == ENT_DIR && st == STEP_PLACED)
            rename(set_dst[i], set_tmp[i]);
        else if (st == STEP_PLACED || st == STEP_MOVED) {
            if (set_bakmode[i] != BAK_NONE)
                rename(set_bak[i], set_dst[i]);
            else
                unlink(set_dst[i]);
        } else if (st == STEP_LINKED)
            unlink(set_bak[i]);
        set_step[i] = STEP_WAIT;
    }
    for (int i = 0; i < n; i++)
        if (set_kind[i] == ENT_FILE)
            unlink(set_tmp[i]);
    for (int i = 0; i < n; i++)
        if (set_kind[i] == ENT_DIR)
            rmdir(set_tmp[i]);
    if (set_journal_live) {
        unlink(set_journal);
        set_journal_live = 0;
    }
}

/* After the commit point: the backups go. Async-signal-safe. */
static void set_finish(void)
{
    for (int i = 0; i < (int)set_n; i++)
        if (set_bakmode[i] != BAK_NONE)
            unlink(set_bak[i]);
    if (set_journal_live) {
        unlink(set_journal);
        set_journal_live = 0;
    }
}

static void set_clear(void)
{
    int n = (int)set_n;
    set_n = 0;
    for (int i = 0; i < n; i++) {
        set_kind[i] = 0;
        set_step[i] = STEP_WAIT;
        set_bakmode[i] = BAK_NONE;
    }
    set_phase = PHASE_OFF;
}

/* The signal handler's part (fdt_io_cleanup_temps). */
static void set_cleanup(void)
{
    if (set_phase == PHASE_COMMITTED)
        set_finish();
    else if (set_phase == PHASE_OPEN)
        set_rollback();
    else
        return;
    set_clear();
}

static void block_signals(sigset_t *old)
{
    sigset_t s;
    sigemptyset(&s);
    sigaddset(&s, SIGINT);
    sigaddset(&s, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &s, old);
}

static void restore_signals(const sigset_t *old)
{
    pthread_sigmask(SIG_SETMASK, old, NULL);
}

/* Adds an entry (its buffers first, then the count). 0 or an errno. */
static int set_add(int kind, const char *tmp, const char *dst)
{
    int i = (int)set_n;
    if (i >= FDT_SET_MAX)
        return EMFILE;
    size_t lt = tmp ? strlen(tmp) : 0, ld = strlen(dst);
    if (lt + 1 > FDT_IO_PATH || ld + 1 > FDT_IO_PATH)
        return ENAMETOOLONG;
    memcpy(set_tmp[i], tmp ? tmp : "", lt + 1);
    memcpy(set_dst[i], dst, ld + 1);
    set_bak[i][0] = '\0';
    set_step[i] = STEP_WAIT;
    set_bakmode[i] = BAK_NONE;
    set_kind[i] = kind;
    set_n = i + 1;
    return 0;
}

int fdt_wr_set_begin(int no_clobber)
{
    if (set_phase != PHASE_OFF)
        return -1;
    set_no_clobber = no_clobber;
    set_phase = PHASE_OPEN;
    return 0;
}

int fdt_wr_set_active(void)
{
    return set_phase == PHASE_OPEN;
}

void fdt_wr_set_abandon(void)
{
    if (set_phase == PHASE_OFF)
        return;
    sigset_t old;
    block_signals(&old);
    set_cleanup();
    restore_signals(&old);
}

/*
 * The test hook (tests/test_cli.sh): FDT_TEST_COMMIT_FAULT=K:fail makes
 * step K of the commit (counted from 1: each backup, the journal, each
 * rename, the commit point, the step after it) fail as with EIO;
 * K:signal raises SIGTERM just before it. Each step it reaches is named on
 * stderr so the test knows which state to expect.
 */
typedef struct set_fault {
    long at;     /* 0: none */
    int signal;  /* else fail */
    long step;
} set_fault;

static void fault_init(set_fault *f)
{
    memset(f, 0, sizeof *f);
    const char *e = getenv("FDT_TEST_COMMIT_FAULT");
    char *end;
    if (!e)
        return;
    long k = strtol(e, &end, 10);
    if (k > 0 && *end == ':') {
        f->at = k;
        f->signal = strcmp(end + 1, "signal") == 0;
    }
}

/* 1 when this step is to fail (a signal does not come back). */
static int fault_here(set_fault *f, const char *what)
{
    f->step++;
    if (f->at == 0 || f->step != f->at)
        return 0;
    fprintf(stderr, "frontdt: test fault (%s) at commit step %ld: %s\n",
            f->signal ? "signal" : "fail", f->step, what);
    fflush(stderr);
    if (f->signal) {
        raise(SIGTERM);
        return 0; /* a caller that handles SIGTERM goes on */
    }
    return 1;
}

/* ".NAME.old.PID.I" beside path. 0 or an errno. */
static int backup_name(char *out, const char *path, int i)
{
    const char *slash = strrchr(path, '/');
    int dirlen = slash ? (int)(slash + 1 - path) : 0;
    int w = snprintf(out, FDT_IO_PATH, "%.*s.%s.old.%ld.%d", dirlen, path, path + dirlen,
                     (long)getpid(), i);
    return w < 0 || w >= FDT_IO_PATH ? ENAMETOOLONG : 0;
}

/* fsync of a folder (the entries made in it); errors other than the
 * folder refusing fsync count. */
static int sync_dir(const char *dir)
{
    int fd = open(dir, O_RDONLY);
    if (fd < 0)
        return errno;
    int e = fsync(fd) != 0 && errno != EINVAL && errno != EROFS ? errno : 0;
    close(fd);
    return e;
}

static const char *kind_word(int k)
{
    return k == ENT_FILE ? "file" : k == ENT_DIR ? "dir" : "remove";
}

/* Is entry i a file inside a directory of the set still to be renamed
 * (a new polyMesh's)? */
static int in_set_dir(int i)
{
    for (int j = 0; j < (int)set_n; j++) {
        size_t l = strlen(set_tmp[j]);
        if (set_kind[j] == ENT_DIR && strncmp(set_dst[i], set_tmp[j], l) == 0 &&
            set_dst[i][l] == '/')
            return 1;
    }
    return 0;
}

/* Step 2: the journal, in the first target's folder (a new directory's
 * files are not there yet: its own folder). 0 or an errno. */
static int write_journal(void)
{
    int i0 = 0;
    while (i0 + 1 < (int)set_n && in_set_dir(i0))
        i0++;
    const char *first = set_dst[i0];
    const char *slash = strrchr(first, '/');
    int dirlen = slash ? (int)(slash - first) : 0;
    char dir[FDT_IO_PATH];
    if (!slash)
        snprintf(dir, sizeof dir, ".");
    else if (dirlen == 0)
        snprintf(dir, sizeof dir, "/");
    else
        snprintf(dir, sizeof dir, "%.*s", dirlen, first);
    char path[FDT_IO_PATH];
    int w = snprintf(path, sizeof path, "%s/.frontdt-commit-%ld", dir, (long)getpid());
    if (w < 0 || w >= (int)sizeof path)
        return ENAMETOOLONG;
    memcpy(set_journal, path, (size_t)w + 1);
    set_journal_live = 1; /* before it exists: the handler may remove it */
    int fd = open(path, O_WRONLY | O_CREAT | O_EXCL, 0644);
    if (fd < 0) {
        int e = errno;
        set_journal_live = 0; /* never ours: not to be removed */
        return e;
    }
    FILE *f = fdopen(fd, "w");
    if (!f) {
        int e = errno;
        close(fd);
        return e;
    }
    char cwd[FDT_IO_PATH];
    fprintf(f,
            "# frontdt commit journal (process %ld): the outputs of one run, renamed\n"
            "# together. While this file exists the renames may be partly done. To undo\n"
            "# them: rename each BACKUP to its FINAL ('-': remove FINAL if TEMP is gone);\n"
            "# for a dir line rename FINAL back to TEMP; then remove every TEMP. Fields are\n"
            "# tab-separated: KIND TEMP FINAL BACKUP, paths relative to the cwd line.\n",
            (long)getpid());
    fprintf(f, "cwd\t%s\n", getcwd(cwd, sizeof cwd) ? cwd : "?");
    for (int i = 0; i < (int)set_n; i++)
        fprintf(f, "%s\t%s\t%s\t%s\n", kind_word((int)set_kind[i]),
                set_tmp[i][0] ? set_tmp[i] : "-", set_dst[i],
                set_bakmode[i] != BAK_NONE ? set_bak[i] : "-");
    int e = 0;
    if (fflush(f) != 0 || ferror(f))
        e = errno ? errno : EIO;
    if (!e && fsync(fd) != 0 && errno != EINVAL)
        e = errno;
    if (fclose(f) != 0 && !e)
        e = errno ? errno : EIO;
    if (!e)
        e = sync_dir(dir);
    return e;
}

/* Step 1 of fdt_wr_set_commit: each existing target checked and backed
 * up (a hard link, or BAK_MOVE where links fail); 0, or an errno with
 * the entry (*at) and what failed. */
static int set_backups(set_fault *fault, int *at, const char **what)
{
    int n = (int)set_n, e = 0;
    sigset_t old;
    for (int i = 0; i < n && !e; i++) {
        struct stat st;
        if (lstat(set_dst[i], &st) != 0) {
            if (errno != ENOENT) {
                e = errno, *at = i, *what = "cannot check";
            }
            continue;
        }
        if (set_kind[i] == ENT_DIR) {
            e = EEXIST, *at = i, *what = "appeared while the mesh was computed";
            break;
        }
        if (S_ISDIR(st.st_mode)) {
            e = EISDIR, *at = i, *what = "cannot replace";
            break;
        }
        if (set_no_clobber) {
            e = EEXIST, *at = i, *what = "--no-clobber";
            break;
        }
        if ((e = backup_name(set_bak[i], set_dst[i], i)) != 0) {
            *at = i, *what = "cannot back up";
            break;
        }
        if (lstat(set_bak[i], &st) == 0) {
            e = EEXIST, *at = i, *what = "cannot back up";
            break;
        }
        if (set_kind[i] == ENT_REMOVE) {
            set_bakmode[i] = BAK_MOVE; /* the removal is the move */
            continue;
        }
        if (fault_here(fault, "backup")) {
            e = EIO, *at = i, *what = "cannot back up";
            break;
        }
        block_signals(&old);
        if (link(set_dst[i], set_bak[i]) == 0) {
            set_bakmode[i] = BAK_LINK;
            set_step[i] = STEP_LINKED;
        } else if (errno == EEXIST) {
            e = EEXIST, *at = i, *what = "cannot back up";
        } else {
            set_bakmode[i] = BAK_MOVE; /* no links here: moved at its turn */
        }
        restore_signals(&old);
    }
    return e;
}

int fdt_wr_set_commit(char *err, size_t errlen)
{
    if (set_phase != PHASE_OPEN)
        return FDT_IO_OK;
    set_fault fault;
    fault_init(&fault);
    sigset_t old;
    int n = (int)set_n, e = 0, at = -1;
    const char *what = "";
    if (n == 0) {
        set_clear();
        return FDT_IO_OK;
    }
    /* A set of one file needs no journal: its rename(2) is atomic, so a
     * crash leaves the old file or the new one, never a mix to undo.
     * Without it, the journal's fsync waited for the kernel to write out
     * the output just written (0.2 s after a 514 MB Voronoi table). */
    int journal = !(n == 1 && set_kind[0] == ENT_FILE);
    /* 1. backups (and the checks that need no change on disk) */
    e = set_backups(&fault, &at, &what);
    /* 2. the journal */
    if (!e && journal && fault_here(&fault, "journal"))
        e = EIO, at = -1, what = "cannot write the commit journal";
    if (!e && journal && (e = write_journal()) != 0)
        at = -1, what = "cannot write the commit journal";
    /* 3. the renames */
    for (int i = 0; i < n && !e; i++) {
        int k = (int)set_kind[i];
        if (k == ENT_REMOVE && set_bakmode[i] == BAK_NONE)
            continue;
        if (set_bakmode[i] == BAK_MOVE) {
            if (fault_here(&fault, "rename")) {
                e = EIO, at = i, what = "cannot move aside";
                break;
            }
            block_signals(&old);
            if (rename(set_dst[i], set_bak[i]) == 0)
                set_step[i] = STEP_MOVED;
            else
                e = errno, at = i, what = "cannot move aside";
            restore_signals(&old);
            if (e || k == ENT_REMOVE)
                continue;
        }
        if (fault_here(&fault, "rename")) {
            e = EIO, at = i, what = "cannot rename into place";
            break;
        }
        block_signals(&old);
        if (rename(set_tmp[i], set_dst[i]) == 0)
            set_step[i] = STEP_PLACED;
        else
            e = errno, at = i, what = "cannot rename into place";
        restore_signals(&old);
    }
    /* 4. the commit point */
    if (!e && journal && fault_here(&fault, "commit"))
        e = EIO, at = -1, what = "cannot commit";
    if (!e) {
        /* The commit point is the journal's removal: a journal left
         * behind would tell whoever finds it to undo renames of a commit
         * reported done, so one that cannot be removed rolls the set back.
         * (A lone file's commit point was its rename; a signal since then
         * has put the old file back.) */
        block_signals(&old);
        if (!journal) {
            set_phase = PHASE_COMMITTED;
        } else if (unlink(set_journal) == 0) {
            set_journal_live = 0;
            set_phase = PHASE_COMMITTED;
        } else {
            e = errno, at = -1, what = "cannot remove the commit journal";
        }
        restore_signals(&old);
    }
    if (e) {
        block_signals(&old);
        set_rollback();
        set_clear();
        restore_signals(&old);
        char msg[FDT_IO_PATH + 200];
        if (e == EEXIST && !strcmp(what, "--no-clobber"))
            snprintf(msg, sizeof msg, "exists (--no-clobber); no output written");
        else
            snprintf(msg, sizeof msg, "%s (%s); every output left as it was", what,
                     strerror(e));
        return set_err(err, errlen, e == ENOMEM ? FDT_IO_ENOMEM : FDT_IO_EWRITE,
                       at >= 0 ? set_dst[at] : set_journal, msg);
    }
    (void)fault_here(&fault, "committed");
    block_signals(&old);
    set_finish();
    set_clear();
    restore_signals(&old);
    return FDT_IO_OK;
}

/*
 * Closes files[0..k) and renames them over their targets, all or none:
 * if any close fails, every temporary is removed; several targets of
 * which some exist are renamed as a commit set of their own
 * (commit_own_set), so a failed rename puts every target back as it was
 * (a .ele set with a stale .neigh beside a new .ele would be worse than
 * none, and removing the old set would lose it). New targets, and a fresh
 * polyMesh's files (KEEP_RENAMED, renamed inside their temporary folder),
 * are renamed one by one here, and all removed if one rename fails.
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
/* What commit_all does with the slots once renamed: KEEP_NONE frees them;
 * KEEP_RENAMED leaves them live (SLOT_RENAMED) for a directory still to
 * be renamed. With a commit set open nothing is renamed: the files join
 * the set and their slots are freed. */
enum { KEEP_NONE = 0, KEEP_RENAMED = 1 };

/* The closed files[0..k) join the open commit set; their slots are freed
 * (the set removes the temporaries from now on). */
static int defer_all(out_file *files, int k, char *err, size_t errlen)
{
    for (int i = 0; i < k; i++) {
        int slot = files[i].slot;
        int e = set_add(ENT_FILE, fdt_io_tmp_path[slot], fdt_io_dst_path[slot]);
        if (e) {
            for (int j = i; j < k; j++)
                out_abandon(&files[j]);
            return set_errno_err(err, errlen, files[i].path, e);
        }
        fdt_io_state[slot] = SLOT_FREE;
        files[i].slot = -1;
    }
    return FDT_IO_OK;
}

/* Does any of files[0..k)'s targets exist (or cannot tell)? */
static int any_target(const out_file *files, int k)
{
    struct stat st;
    for (int i = 0; i < k; i++)
        if (lstat(fdt_io_dst_path[files[i].slot], &st) == 0 || errno != ENOENT)
            return 1;
    return 0;
}

/* Several targets (a TetGen set, a polyMesh's files in its folder), some
 * of them there already, with no commit set open: renamed as a set of
 * their own, so a rename that fails part-way puts back the targets
 * renamed before it (backed up) instead of removing them with the old
 * files they replaced. (All new, removing them loses nothing: no journal
 * then, and no backups.) */
static int commit_own_set(out_file *files, int k, char *err, size_t errlen)
{
    fdt_wr_set_begin(0); /* none is open: cannot fail */
    int r = defer_all(files, k, err, errlen);
    if (r != FDT_IO_OK) {
        fdt_wr_set_abandon();
        return r;
    }
    return fdt_wr_set_commit(err, errlen);
}

static int commit_all(out_file *files, int k, char *err, size_t errlen, int keep)
{
    for (int i = 0; i < k; i++) {
        int e = out_close(&files[i]);
        if (e) {
            for (int j = 0; j < k; j++)
                out_abandon(&files[j]);
            return set_errno_err(err, errlen, files[i].path, e);
        }
    }
    if (set_phase == PHASE_OPEN)
        return defer_all(files, k, err, errlen);
    if (k > 1 && !keep && any_target(files, k))
        return commit_own_set(files, k, err, errlen);
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
    if (keep)
        return FDT_IO_OK; /* the caller frees the slots */
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

/* For the streaming writers (src/io/write/writer_stream.c, src/io/write/formats.h): the
 * same temporaries, commit and cleanup as every other output. */
int fdt_out_open(out_file *o, const char *target)
{
    return out_open(o, target, creation_mode());
}

void fdt_out_abandon(out_file *o)
{
    out_abandon(o);
}

int fdt_out_commit(out_file *files, int k, char *err, size_t errlen)
{
    return commit_all(files, k, err, errlen, 0);
}

int fdt_out_remove_at_commit(const char *target, char *err, size_t errlen)
{
    if (set_phase == PHASE_OPEN) {
        int e = set_add(ENT_REMOVE, NULL, target);
        return e ? set_errno_err(err, errlen, target, e) : FDT_IO_OK;
    }
    if (unlink(target) != 0 && errno != ENOENT)
        return set_errno_err(err, errlen, target, errno);
    return FDT_IO_OK;
}

const char *fdt_out_temp(const out_file *o)
{
    return o->slot >= 0 ? fdt_io_tmp_path[o->slot] : NULL;
}

/* ------------------------------------------------------------------------ */
/* Side files (the CLI's --stats-json)                                       */
/* ------------------------------------------------------------------------ */

struct fdt_wr_side {
    out_file o;
};

FILE *fdt_wr_side_open(const char *target, fdt_wr_side **side, char *err, size_t errlen)
{
    *side = calloc(1, sizeof **side);
    if (!*side) {
        snprintf(err, errlen, "%s: out of memory", target);
        return NULL;
    }
    int e = out_open(&(*side)->o, target, creation_mode());
    if (e) {
        free(*side);
        *side = NULL;
        fdt_create_err(err, errlen, "output", target, e);
        return NULL;
    }
    /* The caller writes with stdio: the buffer of out_file is not used. */
    return (*side)->o.f;
}

int fdt_wr_side_commit(fdt_wr_side *side, char *err, size_t errlen)
{
    int r = commit_all(&side->o, 1, err, errlen, 0);
    free(side);
    return r;
}

void fdt_wr_side_abandon(fdt_wr_side *side)
{
    if (!side)
        return;
    out_abandon(&side->o);
    free(side);
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
    if (m->faces) {
        if (!m->face_tets)
            return set_err(err, errlen, FDT_IO_EFORMAT, path, "face list without its tets");
        for (size_t i = 0; i < m->n_faces; i++) {
            int bad = 0;
            for (int k = 0; k < 3; k++)
                bad |= m->faces[3 * i + k] < 0 || (size_t)m->faces[3 * i + k] >= m->n_points;
            for (int k = 0; k < 2; k++) {
                fdt_tid t = m->face_tets[2 * i + k];
                bad |= t < -(fdt_tid)k || (t >= 0 && (uint64_t)t >= m->n_tets);
            }
            if (bad) {
                snprintf(what, sizeof what, "face %zu has a vertex or tet out of range", i);
                return set_err(err, errlen, FDT_IO_EFORMAT, path, what);
            }
        }
    }
    return FDT_IO_OK;
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

/* The extension of f's that path ends with, or NULL. A directory
 * format matches path's last component (trailing slashes ignored). */
static const char *matching_ext(const char *path, const fdt_format *f)
{
    for (int i = 0; i < 3 && f->exts[i]; i++) {
        if (f->layout != FDT_LAYOUT_DIR) {
            if (has_ext(path, f->exts[i]))
                return f->exts[i];
            continue;
        }
        size_t len = strlen(path), le = strlen(f->exts[i]);
        while (len > 1 && path[len - 1] == '/')
            len--;
        if (len < le || (len > le && path[len - le - 1] != '/'))
            continue;
        const char *p = path + len - le;
        size_t k = 0;
        while (k < le && (p[k] | 0x20) == (f->exts[i][k] | 0x20))
            k++;
        if (k == le)
            return f->exts[i];
    }
    return NULL;
}

const fdt_format *fdt_format_by_name(const char *name)
{
    for (const fdt_format *f = fdt_formats; name && f->name; f++)
        if (strcmp(f->name, name) == 0)
            return f;
    return NULL;
}

const fdt_format *fdt_format_by_path(const char *path)
{
    for (const fdt_format *f = fdt_formats; path && f->name; f++)
        if (matching_ext(path, f))
            return f;
    return NULL;
}

const fdt_format *fdt_format_contradicted(const char *path, const fdt_format *f)
{
    const fdt_format *by = fdt_format_by_path(path);
    if (!f || !by || by == f || matching_ext(path, f))
        return NULL;
    return by;
}

const char *fdt_format_name(const fdt_format *f) { return f ? f->name : NULL; }
int fdt_format_is_text(const fdt_format *f) { return f && !f->binary; }

int fdt_format_needs(const fdt_format *f, int all_faces)
{
    int n = f ? f->needs : 0;
    if (all_faces && f && f->put[0] == fdt_put_tetgen_node)
        n |= FDT_NEED_FACES;
    return n;
}

const char *fdt_format_list(void)
{
    static char list[512];
    if (list[0])
        return list;
    size_t k = 0;
    for (const fdt_format *f = fdt_formats; f->name; f++) {
        int w = snprintf(list + k, sizeof list - k, "%s%s", k ? ", " : "", f->name);
        if (w < 0 || (size_t)w >= sizeof list - k)
            break;
        k += (size_t)w;
        for (int i = 0; i < 3 && f->exts[i]; i++) {
            w = snprintf(list + k, sizeof list - k, "%s%s", i ? " " : " (",
                         f->exts[i]);
            if (w < 0 || (size_t)w >= sizeof list - k)
                break;
            k += (size_t)w;
        }
        if (f->exts[0] && k + 1 < sizeof list)
            list[k++] = ')';
        list[k] = '\0';
    }
    return list;
}

int fdt_output_files_as(const char *path, const fdt_format *f,
                        char names[FDT_IO_MAX_FILES][FDT_IO_PATH])
{
    if (!f)
        f = fdt_format_by_path(path);
    if (!f)
        return 0;
    size_t len = strlen(path);
    if (f->layout == FDT_LAYOUT_FILE) {
        if (len + 1 > FDT_IO_PATH)
            return -1;
        memcpy(names[0], path, len + 1);
        return 1;
    }
    if (f->layout == FDT_LAYOUT_DIR) {
        while (len > 1 && path[len - 1] == '/')
            len--;
        for (int i = 0; i < f->nparts; i++) {
            size_t pl = strlen(f->parts[i]);
            if (len + 1 + pl + 1 > FDT_IO_PATH)
                return -1;
            memcpy(names[i], path, len);
            names[i][len] = '/';
            memcpy(names[i] + len + 1, f->parts[i], pl + 1);
        }
        return f->nparts;
    }
    /* A family: the base name and each part's extension. The part the
     * path names keeps the user's spelling of its extension; the siblings'
     * are lowercase. A path without the format's extension (chosen by
     * --format) is the base name itself. */
    const char *ext = matching_ext(path, f);
    size_t baselen = ext ? len - strlen(ext) : len;
    for (int i = 0; i < f->nparts; i++) {
        size_t pl = strlen(f->parts[i]);
        if (baselen + pl + 1 > FDT_IO_PATH)
            return -1;
        memcpy(names[i], path, baselen);
        if (ext && strcmp(f->parts[i], ext) == 0)
            memcpy(names[i] + baselen, path + baselen, pl + 1);
        else
            memcpy(names[i] + baselen, f->parts[i], pl + 1);
    }
    return f->nparts;
}

int fdt_output_files(const char *path,
                     char names[FDT_IO_MAX_FILES][FDT_IO_PATH])
{
    return fdt_output_files_as(path, NULL, names);
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


/* ------------------------------------------------------------------------ */
/* The table                                                                  */
/* ------------------------------------------------------------------------ */

const fdt_format fdt_formats[] = {
    {"tets", {".tets"}, "canonical sorted text, one tet a line (the hash's bytes)", 0,
     FDT_LAYOUT_FILE, FDT_NEED_SORTED, 1, {NULL}, {fdt_put_tets}, NULL, &fdt_stream_tets},
    {"tetgen", {".ele"}, "TetGen .node/.ele/.face/.neigh, 0-based", 0, FDT_LAYOUT_FAMILY,
     FDT_NEED_NBRS, 4, {".node", ".ele", ".face", ".neigh"},
     {fdt_put_tetgen_node, fdt_put_tetgen_ele, fdt_put_tetgen_face, fdt_put_tetgen_neigh},
     NULL, &fdt_stream_tetgen},
    {"vtu", {".vtu"}, "VTK XML unstructured grid (ParaView), appended raw", 1,
     FDT_LAYOUT_FILE, 0, 1, {NULL}, {fdt_put_vtu}, NULL, &fdt_stream_vtu},
    {"bin", {".fdtb"}, "frontdt binary: header, points, int32/int64 tets, hull", 1,
     FDT_LAYOUT_FILE, 0, 1, {NULL}, {fdt_put_bin}, NULL, &fdt_stream_bin},
    {"vtk", {".vtk"}, "VTK legacy ASCII unstructured grid", 0, FDT_LAYOUT_FILE, 0, 1,
     {NULL}, {fdt_put_vtk}, NULL, NULL},
    {"msh", {".msh"}, "gmsh MSH 4.1 ASCII: tets and hull triangles", 0, FDT_LAYOUT_FILE, 0,
     1, {NULL}, {fdt_put_msh41}, NULL, NULL},
    {"msh2", {".msh"}, "gmsh MSH 2.2 ASCII (--format msh2)", 0, FDT_LAYOUT_FILE, 0, 1,
     {NULL}, {fdt_put_msh22}, NULL, NULL},
    {"medit", {".mesh"}, "Medit .mesh (MMG, meshio): tets and hull triangles", 0,
     FDT_LAYOUT_FILE, 0, 1, {NULL}, {fdt_put_medit}, NULL, NULL},
    {"openfoam", {"polyMesh"},
     "OpenFOAM polyMesh directory, the hull one patch (periodic sides: cyclic pairs)", 0,
     FDT_LAYOUT_DIR, FDT_NEED_FACES, 5,
     {"points", "faces", "owner", "neighbour", "boundary"},
     {fdt_put_foam_points, fdt_put_foam_faces, fdt_put_foam_owner, fdt_put_foam_neighbour,
      fdt_put_foam_boundary},
     fdt_foam_prepare, NULL},
    {NULL, {NULL}, NULL, 0, FDT_LAYOUT_FILE, 0, 0, {NULL}, {NULL}, NULL, NULL},
};

/* ------------------------------------------------------------------------ */
/* Dispatch                                                                   */
/* ------------------------------------------------------------------------ */

/* What the row needs that the view lacks, as a message; NULL if nothing. */
static const char *missing(const fdt_format *f, const fdt_mesh_view *m)
{
    int needs = fdt_format_needs(f, m->all_faces);
    if ((needs & FDT_NEED_NBRS) && !m->nbrs)
        return "this format needs tet neighbours (settings.neighbors)";
    /* a periodic mesh laid out (point_src): the OpenFOAM writer pairs its
     * faces from the periodic neighbours instead */
    if ((needs & FDT_NEED_FACES) && !m->faces && m->n_tets > 0 && !(m->point_src && m->nbrs))
        return "this format needs the face list (fdt_result_faces)";
    return NULL;
}

/* Opens names[0..k) as temporaries, writes part i with put[i] and commits
 * them all or none; keep: KEEP_* of commit_all. */
static int write_parts(const fdt_format *f, char names[FDT_IO_MAX_FILES][FDT_IO_PATH],
                       int k, const fdt_mesh_view *m, const void *prep, out_file *files,
                       out_meter *meter, char *err, size_t errlen, int keep)
{
    mode_t mode = creation_mode();
    for (int i = 0; i < k; i++) {
        int e = out_open(&files[i], names[i], mode);
        if (e) {
            for (int j = 0; j < i; j++)
                out_abandon(&files[j]);
            return fdt_create_err(err, errlen, "output", names[i], e);
        }
        files[i].meter = meter;
        int r = f->put[i](&files[i], m, prep, err, errlen);
        /* Stop at the first error instead of formatting on. */
        if (r != FDT_IO_OK || files[i].err) {
            int e2 = files[i].err;
            for (int j = 0; j <= i; j++)
                out_abandon(&files[j]);
            return r != FDT_IO_OK ? r : set_errno_err(err, errlen, names[i], e2);
        }
    }
    return commit_all(files, k, err, errlen, keep);
}

/* The directory of a fresh polyMesh: made as ".NAME.tmp.XXXXXX" beside
 * path, filled, renamed to path. */
static int write_new_dir(const fdt_format *f, const char *path, const fdt_mesh_view *m,
                         const void *prep, out_meter *meter, char *err, size_t errlen)
{
    size_t len = strlen(path);
    while (len > 1 && path[len - 1] == '/')
        len--;
    char target[FDT_IO_PATH];
    if (len + 1 > sizeof target)
        return set_errno_err(err, errlen, path, ENAMETOOLONG);
    memcpy(target, path, len);
    target[len] = '\0';
    const char *slash = strrchr(target, '/');
    size_t dirlen = slash ? (size_t)(slash + 1 - target) : 0;
    static const char suffix[] = ".tmp.XXXXXX";
    if (len + 1 + sizeof suffix > FDT_IO_PATH)
        return set_errno_err(err, errlen, path, ENAMETOOLONG);
    /* the handler may read fdt_io_tmpdir only while the flag is set */
    memcpy(fdt_io_tmpdir, target, dirlen);
    fdt_io_tmpdir[dirlen] = '.';
    memcpy(fdt_io_tmpdir + dirlen + 1, target + dirlen, len - dirlen);
    memcpy(fdt_io_tmpdir + len + 1, suffix, sizeof suffix);
    if (!mkdtemp(fdt_io_tmpdir))
        return fdt_create_err(err, errlen, "output", path, errno);
    fdt_io_tmpdir_live = 1;
    int r = FDT_IO_OK;
    /* mkdtemp makes mode 0700: give it a plain mkdir's mode */
    if (chmod(fdt_io_tmpdir, creation_mode() | 0111) != 0) {
        r = set_errno_err(err, errlen, path, errno);
        goto out;
    }
    char names[FDT_IO_MAX_FILES][FDT_IO_PATH];
    int k = fdt_output_files_as(fdt_io_tmpdir, f, names);
    if (k != f->nparts) {
        r = set_errno_err(err, errlen, path, ENAMETOOLONG);
        goto out;
    }
    out_file files[FDT_IO_MAX_FILES];
    int deferred = set_phase == PHASE_OPEN;
    r = write_parts(f, names, k, m, prep, files, meter, err, errlen, KEEP_RENAMED);
    if (r != FDT_IO_OK) {
        if (deferred)
            fdt_wr_set_abandon(); /* the parts already in the set go too */
        goto out;
    }
    if (deferred) {
        /* the files are in the set: the directory joins it after them,
         * and the set removes it from now on */
        int e = set_add(ENT_DIR, fdt_io_tmpdir, target);
        if (e) {
            fdt_wr_set_abandon();
            r = set_errno_err(err, errlen, path, e);
            goto out;
        }
        fdt_io_tmpdir_live = 0;
        return FDT_IO_OK;
    }
    if (rename(fdt_io_tmpdir, target) != 0) {
        r = set_errno_err(err, errlen, path, errno);
        for (int i = 0; i < k; i++)
            out_abandon(&files[i]); /* unlinks the renamed parts */
        goto out;
    }
    /* Renamed: the parts' names in the registry are gone with the
     * temporary directory; free the slots, then the directory's. */
    for (int i = 0; i < k; i++) {
        fdt_io_state[files[i].slot] = SLOT_FREE;
        files[i].slot = -1;
    }
    fdt_io_tmpdir_live = 0;
    return FDT_IO_OK;
out:
    rmdir(fdt_io_tmpdir);
    fdt_io_tmpdir_live = 0;
    return r;
}

/* Row f's files for path from m and what its prepare made: a new
 * directory for a directory format whose path does not exist yet, else
 * the files themselves (all or none). */
static int write_prepared(const char *path, const fdt_format *f, const fdt_mesh_view *m,
                          const void *prep, out_meter *mt, char *err, size_t errlen)
{
    int r;
    struct stat st;
    if (f->layout == FDT_LAYOUT_DIR && stat(path, &st) != 0 && errno == ENOENT) {
        r = write_new_dir(f, path, m, prep, mt, err, errlen);
    } else if (f->layout == FDT_LAYOUT_DIR && stat(path, &st) == 0 && !S_ISDIR(st.st_mode)) {
        r = set_errno_err(err, errlen, path, ENOTDIR);
    } else {
        char names[FDT_IO_MAX_FILES][FDT_IO_PATH];
        int k = fdt_output_files_as(path, f, names);
        out_file files[FDT_IO_MAX_FILES];
        if (k != f->nparts)
            r = set_errno_err(err, errlen, path, ENAMETOOLONG);
        else
            r = write_parts(f, names, k, m, prep, files, mt, err, errlen, KEEP_NONE);
    }
    return r;
}

int fdt_wr_mesh_as(const char *path, const fdt_format *f, const fdt_mesh_view *m,
                      char *err, size_t errlen)
{
    return fdt_wr_mesh_ex(path, f, m, NULL, NULL, err, errlen);
}

int fdt_wr_mesh_ex(const char *path, const fdt_format *f, const fdt_mesh_view *m,
                   fdt_io_progress_fn progress, void *progress_user, char *err, size_t errlen)
{
    if (err && errlen > 0)
        err[0] = '\0';
    if (!path || !m)
        return set_err(err, errlen, FDT_IO_EFORMAT, path, "no path or no mesh");
    if (!f)
        f = fdt_format_by_path(path);
    if (!f) {
        char what[700];
        snprintf(what, sizeof what, "unknown output format (use %s)", fdt_format_list());
        return set_err(err, errlen, FDT_IO_EEXT, path, what);
    }
    int r = validate(path, m, err, errlen);
    if (r != FDT_IO_OK)
        return r;
    const char *lack = missing(f, m);
    if (lack)
        return set_err(err, errlen, FDT_IO_EFORMAT, path, lack);
    void *prep = NULL;
    if (f->prepare && (r = f->prepare(m, &prep, path, err, errlen)) != FDT_IO_OK)
        return r;
    out_meter meter = {progress, progress_user, 0, fdt_wr_estimate(f, m)};
    r = write_prepared(path, f, m, prep, progress ? &meter : NULL, err, errlen);
    free(prep);
    return r;
}

/* The OpenFOAM row of the Voronoi dual: not in the table (no -o path
 * chooses it; --dual does). */
static const fdt_format dual_foam = {
    "openfoam", {"polyMesh"}, "OpenFOAM polyMesh of the Voronoi cells", 0, FDT_LAYOUT_DIR, 0, 5,
    {"points", "faces", "owner", "neighbour", "boundary"},
    {fdt_put_foam_dual_points, fdt_put_foam_dual_faces, fdt_put_foam_dual_owner,
     fdt_put_foam_dual_neighbour, fdt_put_foam_dual_boundary},
    NULL, NULL};

int fdt_wr_dual_polymesh(const char *path, const fdt_dualmesh *d, char *err, size_t errlen)
{
    if (err && errlen > 0)
        err[0] = '\0';
    if (!path || !d)
        return set_err(err, errlen, FDT_IO_EFORMAT, path, "no path or no mesh");
    fdt_mesh_view none;
    memset(&none, 0, sizeof none);
    return write_prepared(path, &dual_foam, &none, d, NULL, err, errlen);
}

int fdt_wr_mesh(const char *path, const fdt_mesh_view *m, char *err,
                   size_t errlen)
{
    return fdt_wr_mesh_as(path, NULL, m, err, errlen);
}

int fdt_wr_mesh_stream(FILE *stream, const char *name, const fdt_format *f,
                          const fdt_mesh_view *m, char *err, size_t errlen)
{
    return fdt_wr_mesh_stream_ex(stream, name, f, m, NULL, NULL, err, errlen);
}

int fdt_wr_mesh_stream_ex(FILE *stream, const char *name, const fdt_format *f,
                          const fdt_mesh_view *m, fdt_io_progress_fn progress,
                          void *progress_user, char *err, size_t errlen)
{
    if (err && errlen > 0)
        err[0] = '\0';
    if (!stream || !f || !m)
        return set_err(err, errlen, FDT_IO_EFORMAT, name, "no stream, format or mesh");
    if (f->binary || f->layout != FDT_LAYOUT_FILE)
        return set_err(err, errlen, FDT_IO_EEXT, name,
                       "only a single-file text format can go to a stream");
    int r = validate(name, m, err, errlen);
    if (r != FDT_IO_OK)
        return r;
    const char *lack = missing(f, m);
    if (lack)
        return set_err(err, errlen, FDT_IO_EFORMAT, name, lack);
    out_file o;
    memset(&o, 0, sizeof o);
    o.f = stream;
    o.slot = -1;
    o.path = name;
    out_meter meter = {progress, progress_user, 0, fdt_wr_estimate(f, m)};
    o.meter = progress ? &meter : NULL;
    o.buf = malloc(OUT_BUF_SIZE);
    if (!o.buf)
        return set_errno_err(err, errlen, name, ENOMEM);
    r = f->put[0](&o, m, NULL, err, errlen);
    out_flush(&o);
    errno = 0;
    if (fflush(stream) != 0 || ferror(stream))
        out_fail(&o, errno);
    free(o.buf);
    if (r == FDT_IO_OK && o.err)
        r = set_errno_err(err, errlen, name, o.err);
    return r;
}

/* ------------------------------------------------------------------------ */
/* The progress total                                                        */
/* ------------------------------------------------------------------------ */

/* Characters of the decimal ids below count, and a separator. */
static uint64_t id_chars(uint64_t count)
{
    uint64_t d = 1;
    for (uint64_t v = count; v >= 10; v /= 10)
        d++;
    return d + 1;
}

/* One file's bytes, roughly: a text coordinate is about 20 characters
 * ("%.17g" of a value in [0, 1) is 19 and a separator), an id as many as
 * the largest id has; binary VTU is exact but for its XML. */
static uint64_t part_estimate(fdt_put_fn put, const fdt_mesh_view *m)
{
    uint64_t n = m->n_points, t = m->n_tets, h = m->n_hull;
    uint64_t f = m->n_faces ? m->n_faces : (4 * t + h) / 2;
    uint64_t dv = id_chars(n), dt = id_chars(t), xyz = 3 * 20;
    if (put == fdt_put_tets)
        return 4 * dv * t;
    if (put == fdt_put_tetgen_node)
        return n * (dv + xyz);
    if (put == fdt_put_tetgen_ele)
        return t * (dt + 4 * dv);
    if (put == fdt_put_tetgen_face)
        return (m->all_faces ? f : h) * (id_chars(f) + 3 * dv + 2);
    if (put == fdt_put_tetgen_neigh)
        return t * 5 * dt;
    if (put == fdt_put_vtu)
        return 24 * n + (32 + 8 + 1) * t + 1024;
    if (put == fdt_put_bin)
        return 64 + 24 * n + 16 * t + 12 * h;
    if (put == fdt_put_vtk)
        return n * xyz + t * (2 + 4 * dv) + 3 * t;
    if (put == fdt_put_msh41 || put == fdt_put_msh22)
        return n * (dv + xyz) + (t + h) * (id_chars(t + h) + 4 * dv + 8);
    if (put == fdt_put_medit)
        return n * (xyz + 2) + t * (4 * dv + 2) + h * (3 * dv + 2);
    if (put == fdt_put_foam_points)
        return n * (xyz + 2);
    if (put == fdt_put_foam_faces)
        return f * (3 + 3 * dv);
    if (put == fdt_put_foam_owner)
        return f * dt;
    if (put == fdt_put_foam_neighbour)
        return (f > h ? f - h : 0) * dt;
    return 1024; /* headers and the OpenFOAM boundary */
}

uint64_t fdt_wr_estimate(const fdt_format *f, const fdt_mesh_view *m)
{
    uint64_t sum = 0;
    for (int i = 0; f && m && i < f->nparts; i++)
        sum += part_estimate(f->put[i], m);
    return sum;
}

/* ------------------------------------------------------------------------ */
/* The public writer (include/frontdt.h)                                     */
/* ------------------------------------------------------------------------ */

/* The fdt_write_options sizes this library accepts (ABI): this release's. */
static int write_options_size_known(size_t size)
{
    return size == sizeof(fdt_write_options);
}

int fdt_default_write_options_sized(fdt_write_options *o, size_t struct_size)
{
    return fdt_abi_reset(o, struct_size, write_options_size_known(struct_size));
}

/* How a format writes a periodic mesh: its rows and offsets (.tets,
 * .fdtb), or, every other one, laid out in space with its image vertices
 * and their input ids (fdt_periodic_unfold). */
static int periodic_laid_out(const fdt_format *f)
{
    return strcmp(f->name, "tets") && strcmp(f->name, "bin");
}

int fdt_format_periodic_stream(const fdt_format *f)
{
    return f->stream && f->stream->periodic_tets;
}

/* One public write at a time: the temporary-file registry above (and the
 * one temporary directory) are process-wide, and creation_mode() sets the
 * umask for an instant. */
static pthread_mutex_t write_lock = PTHREAD_MUTEX_INITIALIZER;

void fdt_write_lock(void)
{
    pthread_mutex_lock(&write_lock);
}

void fdt_write_unlock(void)
{
    pthread_mutex_unlock(&write_lock);
}

static int wr_public_code(int io)
{
    switch (io) {
    case FDT_IO_OK:
        return FDT_OK;
    case FDT_IO_EWRITE:
        return FDT_EIO;
    case FDT_IO_ENOMEM:
        return FDT_ENOMEM;
    case FDT_IO_EEXT:
        return FDT_EINVAL;
    default:
        /* FDT_IO_EFORMAT: the writer refused the mesh a result gave it
         * (out-of-range ids, .tets out of order): ours, not the caller's */
        return FDT_EINTERNAL;
    }
}

static int wr_write_locked(fdt_result *r, const double *xyz, size_t n, const char *path,
                           const fdt_write_options *o, char *diag, size_t diag_size)
{
    int to_stdout = strcmp(path, "-") == 0;
    const char *name = to_stdout ? "stdout" : path;
    const fdt_format *f = o->format ? fdt_format_by_name(o->format) : NULL;
    char what[700];
    if (o->format && !f) {
        snprintf(what, sizeof what, "unknown format '%.40s' (use %s)", o->format,
                 fdt_format_list());
        return set_err(diag, diag_size, FDT_EINVAL, name, what);
    }
    if (!f && !to_stdout)
        f = fdt_format_by_path(path);
    if (!f) {
        snprintf(what, sizeof what, "unknown output format (use %s)", fdt_format_list());
        return set_err(diag, diag_size, FDT_EINVAL, name, what);
    }
    if (to_stdout && (f->binary || f->layout != FDT_LAYOUT_FILE)) {
        snprintf(what, sizeof what, "format %s cannot go to standard output "
                 "(one text file only: tets, vtk, msh, msh2, medit)", f->name);
        return set_err(diag, diag_size, FDT_EINVAL, name, what);
    }
    if (n != r->n) {
        snprintf(what, sizeof what, "%zu points given for a mesh of %zu", n, r->n);
        return set_err(diag, diag_size, FDT_EINVAL, name, what);
    }
    /* a periodic mesh: its rows and offsets (.tets, .fdtb), or laid out
     * with its image vertices and their input ids (periodic_laid_out) */
    int laid_out = r->tet_off && periodic_laid_out(f);
    int needs = fdt_format_needs(f, o->all_faces);
    if (laid_out && o->all_faces) {
        snprintf(what, sizeof what, "a periodic mesh's TetGen .face lists its hull, not every "
                 "face (--all-faces)");
        return set_err(diag, diag_size, FDT_EINVAL, name, what);
    }
    if ((needs & FDT_NEED_NBRS) && !r->nbrs && !laid_out) {
        snprintf(what, sizeof what, "format %s needs tet neighbours (fdt_settings.neighbors)",
                 f->name);
        return set_err(diag, diag_size, FDT_EINVAL, name, what);
    }
    int e;
    if ((needs & FDT_NEED_SORTED) && (e = fdt_result_sort(r)) != FDT_OK)
        return set_err(diag, diag_size, e, name, fdt_strerror(e));
    fdt_mesh_view v = {
        .xyz = xyz, .n_points = n, .tets = r->tets, .n_tets = r->ntets, .nbrs = r->nbrs,
        .hull = r->hull, .n_hull = r->nhull, .all_faces = o->all_faces,
    };
    fdt_periodic_unfolded u = {0};
    fdt_tid *laid_nbrs = NULL; /* the laid-out tets' periodic neighbours */
    if (laid_out) {
        const fdt_periodic_box b = {r->periodic, {r->pbox[0], r->pbox[1], r->pbox[2]},
                                    {r->pbox[3], r->pbox[4], r->pbox[5]}};
        if ((e = fdt_periodic_unfold(r->tets, r->tet_off, r->ntets, r->hull, r->hull_off,
                                     r->nhull, xyz, n, &b, &u)) != FDT_OK)
            return set_err(diag, diag_size, e, name, fdt_strerror(e));
        /* TetGen's .neigh lists them, OpenFOAM's cyclic pairs come from them */
        if ((needs & (FDT_NEED_NBRS | FDT_NEED_FACES)) &&
            (e = fdt_periodic_unfolded_neighbors(&u, &laid_nbrs)) != FDT_OK) {
            fdt_periodic_unfolded_free(&u);
            return set_err(diag, diag_size, e, name, fdt_strerror(e));
        }
        v = (fdt_mesh_view){.xyz = u.xyz, .n_points = u.n, .tets = u.tets, .n_tets = u.ntets,
                            .nbrs = laid_nbrs, .hull = u.hull, .n_hull = u.nhull,
                            .point_src = u.src, .point_off = u.off};
    } else if (r->tet_off) {
        v.tet_off = r->tet_off;
        v.hull_off = r->hull_off;
    }
    const fdt_periodic_box pb = fdt_periodic_box_of(r->periodic, r->pbox);
    for (int k = 0; r->tet_off && k < 3; k++)
        v.period[k] = fdt_periodic_period(&pb, k);
    /* after the sort: the face list names tets by their numbers (a
     * periodic OpenFOAM mesh pairs its faces from the laid-out tets'
     * periodic neighbours instead) */
    if ((needs & FDT_NEED_FACES) && !laid_out &&
        (e = fdt_result_faces(r, &v.n_faces, &v.faces, &v.face_tets)) != FDT_OK)
        return set_err(diag, diag_size, e, name, fdt_strerror(e));
    int io = to_stdout ? fdt_wr_mesh_stream_ex(stdout, name, f, &v, o->progress,
                                               o->progress_user, diag, diag_size)
                       : fdt_wr_mesh_ex(path, f, &v, o->progress, o->progress_user, diag,
                                        diag_size);
    fdt_periodic_unfolded_free(&u);
    free(laid_nbrs);
    return wr_public_code(io);
}

int fdt_write_mesh_opts(fdt_result *r, const double *xyz, size_t n, const char *path,
                        const fdt_write_options *o, char *diag, size_t diag_size)
{
    if (diag && diag_size > 0)
        diag[0] = '\0';
    fdt_write_options defaults;
    if (!o) {
        fdt_default_write_options(&defaults);
        o = &defaults;
    }
    if (!r || !path || (!xyz && n > 0) || (!diag && diag_size > 0))
        return set_err(diag, diag_size, FDT_EINVAL, path, "a NULL argument");
    if (!write_options_size_known(o->struct_size))
        return set_err(diag, diag_size, FDT_EINVAL, path,
                       "fdt_write_options of an unknown size (fdt_default_write_options "
                       "sets it)");
    pthread_mutex_lock(&write_lock);
    int rc = wr_write_locked(r, xyz, n, path, o, diag, diag_size);
    pthread_mutex_unlock(&write_lock);
    return rc;
}

void fdt_write_cleanup(void)
{
    fdt_io_cleanup_temps();
}

int fdt_write_mesh(fdt_result *r, const double *xyz, size_t n, const char *path,
                   const char *format, char *diag, size_t diag_size)
{
    fdt_write_options o;
    fdt_default_write_options(&o);
    o.format = format;
    return fdt_write_mesh_opts(r, xyz, n, path, &o, diag, diag_size);
}
