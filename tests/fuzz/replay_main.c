/*
 * A plain main() for the fuzz targets in tests/fuzz/: replays every file
 * named on the command line (directories: every regular file in them,
 * recursively, in name order) through LLVMFuzzerTestOneInput(), so the
 * corpus runs in the default test suite with any compiler, without
 * libFuzzer. A contract violation aborts inside the target; a path that
 * cannot be read, or a run that replays nothing, fails here.
 *
 * usage: fuzz_replay_X PATH...
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The input being replayed, for the SIGABRT handler: a target reports a
 * violation by abort(), and the log must say which file did it. (The one
 * mutable global here; a signal handler has no other way to reach it.) */
static const char *volatile replay_current;

static void replay_on_abort(int sig)
{
    const char *p = replay_current;
    static const char pre[] = "fuzz replay: the input was ";
    if (p != NULL) {
        ssize_t w = write(STDERR_FILENO, pre, sizeof pre - 1);
        w = write(STDERR_FILENO, p, strlen(p));
        w = write(STDERR_FILENO, "\n", 1);
        (void)w;
    }
    signal(sig, SIG_DFL);
    raise(sig);
}

typedef struct replay {
    size_t files, bytes;
    int failed;
} replay;

static void replay_file(replay *r, const char *path)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        fprintf(stderr, "%s: %s\n", path, strerror(errno));
        r->failed = 1;
        return;
    }
    size_t cap = 4096, len = 0;
    unsigned char *buf = malloc(cap);
    for (;;) {
        if (buf == NULL) {
            fprintf(stderr, "%s: out of memory\n", path);
            r->failed = 1;
            fclose(f);
            return;
        }
        len += fread(buf + len, 1, cap - len, f);
        if (len < cap)
            break;
        cap *= 2;
        unsigned char *nb = realloc(buf, cap);
        if (nb == NULL)
            free(buf);
        buf = nb;
    }
    int bad = ferror(f);
    fclose(f);
    if (bad) {
        fprintf(stderr, "%s: read error\n", path);
        r->failed = 1;
        free(buf);
        return;
    }
    /* An exact-size copy: a read one byte past the input then touches
     * memory the input does not own (caught under ASan), as in libFuzzer. */
    unsigned char *exact = malloc(len ? len : 1);
    if (exact == NULL) {
        fprintf(stderr, "%s: out of memory\n", path);
        r->failed = 1;
        free(buf);
        return;
    }
    memcpy(exact, buf, len);
    free(buf);
    replay_current = path;
    LLVMFuzzerTestOneInput(exact, len);
    replay_current = NULL;
    free(exact);
    r->files++;
    r->bytes += len;
}

static int by_name(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static void replay_path(replay *r, const char *path, int depth)
{
    struct stat st;
    if (stat(path, &st) != 0) {
        fprintf(stderr, "%s: %s\n", path, strerror(errno));
        r->failed = 1;
        return;
    }
    if (S_ISREG(st.st_mode)) {
        replay_file(r, path);
        return;
    }
    if (!S_ISDIR(st.st_mode) || depth > 8)
        return;
    DIR *d = opendir(path);
    if (d == NULL) {
        fprintf(stderr, "%s: %s\n", path, strerror(errno));
        r->failed = 1;
        return;
    }
    char **names = NULL;
    size_t nn = 0, cap = 0;
    struct dirent *de;
    while ((de = readdir(d)) != NULL) {
        if (strcmp(de->d_name, ".") == 0 || strcmp(de->d_name, "..") == 0)
            continue;
        if (nn == cap) {
            cap = cap ? 2 * cap : 64;
            char **nb = realloc(names, cap * sizeof *nb);
            if (nb == NULL)
                break;
            names = nb;
        }
        size_t len = strlen(path) + strlen(de->d_name) + 2;
        names[nn] = malloc(len);
        if (names[nn] == NULL)
            break;
        snprintf(names[nn], len, "%s/%s", path, de->d_name);
        nn++;
    }
    closedir(d);
    if (nn > 0)
        qsort(names, nn, sizeof *names, by_name);
    for (size_t i = 0; i < nn; i++) {
        replay_path(r, names[i], depth + 1);
        free(names[i]);
    }
    free(names);
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: %s PATH...\n", argv[0]);
        return 2;
    }
    signal(SIGABRT, replay_on_abort);
    replay r = {0, 0, 0};
    for (int i = 1; i < argc; i++)
        replay_path(&r, argv[i], 0);
    printf("replayed %zu inputs (%zu bytes)\n", r.files, r.bytes);
    if (r.files == 0) {
        fprintf(stderr, "nothing replayed\n");
        return 1;
    }
    return r.failed ? 1 : 0;
}
