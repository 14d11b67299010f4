/*
 * tetshash FILE.tets
 *
 * Prints one line for bench/run:
 *
 *   TETSHASH tets=N hash=0123456789abcdef canonical=1|0
 *
 * hash is the FNV-1a 64 of the file's bytes, which for a canonical .tets
 * (one tet per line, its four 0-based input indices ascending, lines in
 * ascending order, "a b c d\n") is the hash that frontdt --hash and the
 * CGAL comparator print. canonical says whether the file has that form, so
 * a peer's file in another order or format is never called "differs" when
 * only its text is off.
 *
 * Why a C program: the peers (HXT, Geogram; ../shared/peers) write their
 * tets as text rather than print a hash, and at 10^6 points that text is
 * ~200 MB, which a byte loop in Python takes minutes to hash.
 *
 * Exit status: 0 read, 1 cannot read FILE, 2 usage.
 */
#include <inttypes.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

enum { BUF = 1 << 16 };

/* The reader of one line's four integers, fed a byte at a time, so the
 * check runs in the same pass as the hash. */
typedef struct canon {
    uint64_t cur[4], prev[4];
    int field, digits, lines, ok;
} canon;

static void canon_byte(canon *c, unsigned char b)
{
    if (!c->ok)
        return;
    if (b >= '0' && b <= '9') {
        if (c->field > 3 || c->digits > 18) {
            c->ok = 0;
            return;
        }
        c->cur[c->field] = 10 * c->cur[c->field] + (uint64_t)(b - '0');
        c->digits++;
        return;
    }
    /* A separator: one space between fields, '\n' after the fourth. */
    if (c->digits == 0 || (b == ' ' && c->field >= 3) ||
        (b == '\n' && c->field != 3) || (b != ' ' && b != '\n')) {
        c->ok = 0;
        return;
    }
    if (c->field > 0 && c->cur[c->field] <= c->cur[c->field - 1]) {
        c->ok = 0;
        return;
    }
    c->digits = 0;
    if (b == ' ') {
        c->field++;
        return;
    }
    if (c->lines > 0) {
        int cmp = 0;
        for (int i = 0; i < 4 && !cmp; i++)
            cmp = c->cur[i] < c->prev[i] ? -1 : c->cur[i] > c->prev[i];
        if (cmp <= 0) {
            c->ok = 0;
            return;
        }
    }
    memcpy(c->prev, c->cur, sizeof c->prev);
    memset(c->cur, 0, sizeof c->cur);
    c->field = 0;
    c->lines++;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: tetshash FILE.tets\n");
        return 2;
    }
    FILE *f = fopen(argv[1], "rb");
    if (!f) {
        perror(argv[1]);
        return 1;
    }
    static unsigned char buf[BUF];
    uint64_t h = 14695981039346656037ULL, lines = 0;
    canon c = {{0}, {0}, 0, 0, 0, 1};
    size_t got;
    while ((got = fread(buf, 1, sizeof buf, f)) > 0)
        for (size_t i = 0; i < got; i++) {
            h = (h ^ buf[i]) * 1099511628211ULL;
            lines += buf[i] == '\n';
            canon_byte(&c, buf[i]);
        }
    int bad = ferror(f);
    fclose(f);
    if (bad) {
        perror(argv[1]);
        return 1;
    }
    /* A last line without its '\n' is not canonical. */
    if (c.field != 0 || c.digits != 0)
        c.ok = 0;
    printf("TETSHASH tets=%" PRIu64 " hash=%016" PRIx64 " canonical=%d\n", lines, h, c.ok);
    return 0;
}
