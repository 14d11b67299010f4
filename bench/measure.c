/*
 * measure [--timeout S] --report FILE -- PROG [ARGS...]
 *
 * Runs PROG as a child and writes one line to FILE once it has ended:
 *
 *   MEASURE exit=N signal=N timed_out=0|1 wall_s=.. user_s=.. sys_s=..
 *           maxrss_kb=..
 *
 * wall_s is CLOCK_MONOTONIC from just before fork() to the child's exit;
 * maxrss_kb, user_s and sys_s come from wait4(). PROG inherits stdin,
 * stdout and stderr.
 *
 * Why a C program rather than bench/run (Python) timing its children
 * itself: Linux carries a process's peak RSS across exec() (the kernel
 * keeps the high-water mark of the image it replaces), so a child forked
 * from a Python runner reports at least the runner's ~18 MiB, far more
 * than frontdt needs for 10^4 points. Forked from this small program the
 * floor is its own few hundred KiB.
 *
 * With --timeout the child gets SIGKILL after S seconds (timed_out=1).
 * Waiting uses sigtimedwait() on a blocked SIGCHLD, so there is no signal
 * handler and no global state.
 *
 * Exit status: the child's exit status (128 + signal if it was killed);
 * 125 usage or report error, 127 PROG could not be executed.
 */
/* wait4() and struct rusage's fields are BSD, outside plain POSIX. */
#define _DEFAULT_SOURCE
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/time.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

enum { EXIT_USAGE = 125, EXIT_NOEXEC = 127 };

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double tv_s(struct timeval tv)
{
    return (double)tv.tv_sec + 1e-6 * (double)tv.tv_usec;
}

static int usage(void)
{
    fprintf(stderr, "usage: measure [--timeout S] --report FILE -- PROG [ARGS...]\n");
    return EXIT_USAGE;
}

int main(int argc, char **argv)
{
    double timeout = 0; /* 0: none */
    const char *report = NULL;
    int i = 1;
    for (; i < argc; i++) {
        if (!strcmp(argv[i], "--")) {
            i++;
            break;
        }
        if (!strcmp(argv[i], "--timeout") && i + 1 < argc) {
            char *end;
            timeout = strtod(argv[++i], &end);
            if (*end || !(timeout >= 0) || timeout > 1e9)
                return usage();
        } else if (!strcmp(argv[i], "--report") && i + 1 < argc) {
            report = argv[++i];
        } else {
            return usage();
        }
    }
    if (!report || i >= argc)
        return usage();
    FILE *rf = fopen(report, "w");
    if (!rf) {
        fprintf(stderr, "measure: %s: %s\n", report, strerror(errno));
        return EXIT_USAGE;
    }

    /* SIGCHLD stays blocked in this process so that sigtimedwait() can
     * collect it; the child gets the original mask back before exec. */
    sigset_t chld, old;
    sigemptyset(&chld);
    sigaddset(&chld, SIGCHLD);
    if (sigprocmask(SIG_BLOCK, &chld, &old) != 0) {
        fprintf(stderr, "measure: sigprocmask: %s\n", strerror(errno));
        return EXIT_USAGE;
    }

    double t0 = now_s();
    pid_t pid = fork();
    if (pid < 0) {
        fprintf(stderr, "measure: fork: %s\n", strerror(errno));
        return EXIT_USAGE;
    }
    if (pid == 0) {
        sigprocmask(SIG_SETMASK, &old, NULL);
        execvp(argv[i], &argv[i]);
        fprintf(stderr, "measure: %s: %s\n", argv[i], strerror(errno));
        _exit(EXIT_NOEXEC);
    }

    int status = 0, timed_out = 0;
    struct rusage ru;
    memset(&ru, 0, sizeof ru);
    double deadline = timeout > 0 ? t0 + timeout : 0;
    double t1 = t0;
    for (;;) {
        pid_t w = wait4(pid, &status, WNOHANG, &ru);
        if (w == pid) {
            t1 = now_s();
            break;
        }
        if (w < 0 && errno != EINTR) {
            fprintf(stderr, "measure: wait4: %s\n", strerror(errno));
            return EXIT_USAGE;
        }
        if (deadline > 0) {
            double left = deadline - now_s();
            if (left <= 0) {
                /* Kill and reap; wall time stops at the deadline's end. */
                timed_out = 1;
                kill(pid, SIGKILL);
                while (wait4(pid, &status, 0, &ru) < 0 && errno == EINTR)
                    ;
                t1 = now_s();
                break;
            }
            struct timespec ts;
            ts.tv_sec = (time_t)left;
            ts.tv_nsec = (long)((left - floor(left)) * 1e9);
            /* EAGAIN (time is up) and EINTR both lead back to wait4(). */
            sigtimedwait(&chld, NULL, &ts);
        } else {
            sigwaitinfo(&chld, NULL);
        }
    }

    int code = 0, sig = 0;
    if (WIFEXITED(status))
        code = WEXITSTATUS(status);
    else if (WIFSIGNALED(status))
        sig = WTERMSIG(status);
    fprintf(rf,
            "MEASURE exit=%d signal=%d timed_out=%d wall_s=%.6f user_s=%.6f "
            "sys_s=%.6f maxrss_kb=%ld\n",
            code, sig, timed_out, t1 - t0, tv_s(ru.ru_utime), tv_s(ru.ru_stime),
            ru.ru_maxrss);
    if (fclose(rf) != 0) {
        fprintf(stderr, "measure: %s: write failed\n", report);
        return EXIT_USAGE;
    }
    return sig ? 128 + sig : code;
}
