/* What the command-line programs share; see cli.h. */
#include "cli/cli.h"

#include <errno.h>
#include <signal.h>
#include <string.h>
#include <unistd.h>

/* Set once before the handlers are installed (sigaction orders the
 * writes before any delivery), read only by the handler. */
static void (*cleanup_fn)(void);
static int exit_with;
static char msg[128];
static size_t msg_len;

/* Only async-signal-safe calls: cleanup's unlink()s, write(), _exit(). */
static void on_signal(int sig)
{
    (void)sig;
    cleanup_fn();
    ssize_t w = write(STDERR_FILENO, msg, msg_len);
    (void)w;
    /* No counters' write here even in a coverage build: libgcov's dump is
     * not async-signal-safe and hung on a lock the interrupted run held
     * (tests/test_cli.sh's SIGTERM during a write, session 31). */
    _exit(exit_with);
}

int fdt_cli_signals(const char *prog, void (*cleanup)(void), int exit_code)
{
    static const char tail[] = ": interrupted\n";
    size_t n = strlen(prog);
    if (n > sizeof msg - sizeof tail - 1) {
        errno = EINVAL;
        return -1;
    }
    msg[0] = '\n';
    memcpy(msg + 1, prog, n);
    memcpy(msg + 1 + n, tail, sizeof tail - 1);
    msg_len = 1 + n + sizeof tail - 1;
    cleanup_fn = cleanup;
    exit_with = exit_code;

    struct sigaction ign;
    memset(&ign, 0, sizeof ign);
    ign.sa_handler = SIG_IGN;
    sigemptyset(&ign.sa_mask);
    if (sigaction(SIGXFSZ, &ign, NULL) != 0)
        return -1;
    static const int sigs[2] = {SIGINT, SIGTERM};
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    /* One handler at a time: a SIGTERM during SIGINT's cleanup waits. */
    sigaddset(&sa.sa_mask, SIGINT);
    sigaddset(&sa.sa_mask, SIGTERM);
    for (int i = 0; i < 2; i++) {
        struct sigaction old;
        if (sigaction(sigs[i], NULL, &old) != 0)
            return -1;
        if (old.sa_handler == SIG_IGN)
            continue;
        if (sigaction(sigs[i], &sa, NULL) != 0)
            return -1;
    }
    return 0;
}

int fdt_cli_engine_exit(int err)
{
    switch (err) {
    case FDT_OK:
        return CLI_OK;
    case FDT_EINVAL:
        return CLI_USAGE;
    case FDT_EDEGENERATE:
    case FDT_ERANGE:
        return CLI_INPUT;
    case FDT_ENOMEM:
    case FDT_ETOOBIG:
    case FDT_ETHREAD:
        return CLI_RESOURCES;
    case FDT_ECHECK:
        return CLI_CHECK;
    default: /* FDT_EINTERNAL, and FDT_ECANCELED which we never ask for */
        return CLI_INTERNAL;
    }
}
