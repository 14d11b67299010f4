/*
 * The CLI's option table (src/cli/options.c), which both programs parse
 * with and print their --help from:
 * - every row a program accepts is found by its long and short spelling
 *   in that program's parser (frontdt-mpi's, fdt_cli_find) and by the
 *   getopt arguments frontdt builds, and no row the program refuses;
 * - --help lists exactly the rows a program accepts and does not hide,
 *   each with its value's name, the searches of src/front/search.c and
 *   the writers' formats under theirs;
 * - the shared value checks (--search, --leaf, --input-format) accept the
 *   good values and word the refusal of a bad one.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "frontdt.h"
#include "cli/options.h"
#include "testutil.h"

/* prog's --help as a string (static buffer). */
static const char *help_of(unsigned prog)
{
    static char buf[32768];
    FILE *f = tmpfile();
    CHECK(f != NULL);
    fdt_cli_help(f, prog);
    long n = ftell(f);
    CHECK(n > 0 && (size_t)n < sizeof buf);
    rewind(f);
    CHECK(fread(buf, 1, (size_t)n, f) == (size_t)n);
    buf[n] = '\0';
    fclose(f);
    return buf;
}

static void test_find(void)
{
    const unsigned progs[2] = {FDT_CLI_FRONTDT, FDT_CLI_MPI};
    for (int p = 0; p < 2; p++)
        for (int i = 0; i < FDT_OPT_END; i++) {
            const fdt_cli_opt *o = &fdt_cli_opts[i];
            char word[64];
            snprintf(word, sizeof word, "--%s", o->name);
            int takes = (o->progs & progs[p]) != 0;
            EXPECT(fdt_cli_find(word, progs[p]) == (takes ? i : -1));
            if (o->letter) {
                snprintf(word, sizeof word, "-%c", o->letter);
                EXPECT(fdt_cli_find(word, progs[p]) == (takes ? i : -1));
            }
        }
    EXPECT(fdt_cli_find("input.xyz", FDT_CLI_MPI) == -1); /* not an option */
    EXPECT(fdt_cli_find("--quie", FDT_CLI_MPI) == -1);     /* no abbreviation */
    EXPECT(fdt_cli_find("-qq", FDT_CLI_MPI) == -1);        /* no bundling */
    EXPECT(fdt_cli_find("--demo", FDT_CLI_MPI) == -1);     /* frontdt's alone */
    EXPECT(fdt_cli_find("--no-park", FDT_CLI_FRONTDT) == -1);
}

static void test_getopt_args(void)
{
    struct option longs[FDT_OPT_END + 1];
    char shorts[2 * FDT_OPT_END + 2];
    fdt_cli_getopt_args(FDT_CLI_FRONTDT, longs, shorts);
    int n = 0;
    for (; longs[n].name; n++) {
        int id = fdt_cli_getopt_id(longs[n].val);
        CHECK(id >= 0 && id < FDT_OPT_END);
        EXPECT(!strcmp(longs[n].name, fdt_cli_opts[id].name));
        EXPECT(fdt_cli_opts[id].progs & FDT_CLI_FRONTDT);
        EXPECT(longs[n].has_arg == fdt_cli_opts[id].arg);
    }
    int accepted = 0;
    for (int i = 0; i < FDT_OPT_END; i++)
        accepted += (fdt_cli_opts[i].progs & FDT_CLI_FRONTDT) != 0;
    EXPECT(n == accepted);
    /* a short letter maps to its row, with ':' after one that takes a value */
    for (const char *s = shorts; *s; s++) {
        if (*s == ':')
            continue;
        int id = fdt_cli_getopt_id(*s);
        CHECK(id >= 0);
        EXPECT(fdt_cli_opts[id].letter == *s);
        EXPECT((s[1] == ':') == (fdt_cli_opts[id].arg == required_argument));
    }
    EXPECT(fdt_cli_getopt_id('Z') == -1);
}

static void test_help(void)
{
    const unsigned progs[2] = {FDT_CLI_FRONTDT, FDT_CLI_MPI};
    for (int p = 0; p < 2; p++) {
        const char *h = help_of(progs[p]);
        for (int i = 0; i < FDT_OPT_END; i++) {
            const fdt_cli_opt *o = &fdt_cli_opts[i];
            char word[64];
            snprintf(word, sizeof word, "--%s%s%s", o->name, o->value ? " " : "",
                     o->value ? o->value : "");
            const char *at = strstr(h, word);
            /* a name is listed where it is followed by a space or a line end */
            int listed = 0;
            for (; at; at = strstr(at + 1, word))
                listed |= at[strlen(word)] == ' ' || at[strlen(word)] == '\n';
            EXPECT(listed == ((o->progs & progs[p]) && !o->hidden));
        }
        for (int s = 0; fdt_search_name((fdt_search)s); s++)
            EXPECT(strstr(h, fdt_search_name((fdt_search)s)) != NULL);
    }
    const char *h = help_of(FDT_CLI_FRONTDT);
    EXPECT(strstr(h, "openfoam (polyMesh)") != NULL); /* the writers' table */
    EXPECT(strstr(h, "vtu (.vtu)") != NULL);
    for (const char *l = h; *l; l = strchr(l, '\n') ? strchr(l, '\n') + 1 : l + strlen(l)) {
        const char *e = strchr(l, '\n');
        EXPECT((e ? (size_t)(e - l) : strlen(l)) <= 79); /* fits a terminal */
    }
}

static void test_values(void)
{
    char err[256];
    fdt_search s;
    for (int i = 0; fdt_search_name((fdt_search)i); i++) {
        EXPECT(fdt_cli_search(fdt_search_name((fdt_search)i), &s, err, sizeof err) == 0);
        EXPECT(s == (fdt_search)i);
    }
    EXPECT(fdt_cli_search("kdtree", &s, err, sizeof err) == -1);
    EXPECT(!strcmp(err, "unknown search 'kdtree' (auto, kd or mesh)"));
    int leaf = 0;
    EXPECT(fdt_cli_leaf("30", &leaf, err, sizeof err) == 0 && leaf == 30);
    EXPECT(fdt_cli_leaf("1000000", &leaf, err, sizeof err) == 0 && leaf == 1000000);
    const char *bad[] = {"0", "-3", "1000001", "12x", "", "x"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        EXPECT(fdt_cli_leaf(bad[i], &leaf, err, sizeof err) == -1);
        EXPECT(strstr(err, "--leaf wants 1..1000000") != NULL);
    }
    int fmt = -1;
    const char *good[] = {"xyz", "txt", "csv", "node", "ply"};
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++)
        EXPECT(fdt_cli_input_format(good[i], &fmt, err, sizeof err) == 0);
    EXPECT(fdt_cli_input_format("vtu", &fmt, err, sizeof err) != 0);
    EXPECT(strstr(err, "vtu") != NULL);
}

int main(void)
{
    test_find();
    test_getopt_args();
    test_help();
    test_values();
    return test_report("test_options");
}
