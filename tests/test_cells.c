/*
 * Tests for src/io/write/cells.c's spool: the tables of a streamed run,
 * written in input order from batches that come in any order.
 *  - spools fed the batches of fdt_voronoi_stream (the run's sweep order,
 *    not input order) put the cells' table, its CSV (with the header) and
 *    the densities byte for byte as fdt_wr_cells and fdt_wr_density write
 *    the whole set's cells, with the bytes announced by
 *    fdt_cells_spool_bytes;
 *  - the records of a spool (fdt_cells_spool_each) copied one by one into
 *    another (fdt_cells_spool_add_row), as frontdt-mpi's periodic ranks
 *    send theirs to rank 0, put the same bytes; each hands the rows in
 *    input order and stops at its callback's first nonzero return;
 *  - a row twice and a row outside the spool's ids are refused (EINVAL),
 *    and so is a table put before every row came;
 *  - cells computed without the centroids and densities (options.skip, as
 *    fdt_cells_table_skip gives it for a table) write the tables that do
 *    not read them byte for byte, and the writers and the spool refuse
 *    (EINVAL) those that do.
 */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "io/write/cells.h"
#include "testutil.h"

#define FMT "%i %v %F %s %n %f %c"

/* Table `table` of sp (0 the cells', 1 the densities) as a string; its
 * length checked against fdt_cells_spool_bytes. */
static char *put(fdt_cells_spool *sp, int table, size_t *len)
{
    FILE *f = tmpfile();
    CHECK(f != NULL);
    CHECK_EQ(fdt_cells_spool_put(sp, table, 1, f), 0);
    CHECK(fflush(f) == 0);
    rewind(f);
    char *s = test_slurp_stream(f, len);
    fclose(f);
    EXPECT(*len == fdt_cells_spool_bytes(sp, table, 1));
    return s;
}

/* What the whole set's writers write: the cells in fmt (NULL: CSV), or
 * the densities. */
static char *whole(const fdt_voronoi *v, const double *xyz, int density, const char *fmt,
                   size_t *len)
{
    FILE *f = tmpfile();
    CHECK(f != NULL);
    CHECK_EQ(density ? fdt_wr_density(f, v, 1) : fdt_wr_cells(f, fmt, v, xyz, 2), 0);
    CHECK(fflush(f) == 0);
    rewind(f);
    char *s = test_slurp_stream(f, len);
    fclose(f);
    return s;
}

static void expect_same(const char *a, size_t la, const char *b, size_t lb, const char *what)
{
    EXPECTF(la == lb && memcmp(a, b, la) == 0, "%s: %zu bytes against %zu", what, la, lb);
}

/* The stream's batches into both spools (an fdt_cell_sink). */
typedef struct two {
    fdt_cells_spool *text, *csv;
    int batches;
} two;

static int spool_both(void *user, const fdt_voronoi *batch)
{
    two *t = user;
    t->batches++;
    return fdt_cells_spool_add(t->text, batch) || fdt_cells_spool_add(t->csv, batch);
}

/* fdt_cells_spool_each's callback: each record into another spool, the
 * ids checked ascending; stop_at (nonzero) ends it there with 77. */
typedef struct copier {
    fdt_cells_spool *to;
    long last;
    size_t calls, stop_at;
} copier;

static int copy_row(void *user, size_t id, const uint32_t l[2], const char *text)
{
    copier *c = user;
    EXPECT((long)id > c->last);
    c->last = (long)id;
    if (++c->calls == c->stop_at)
        return 77;
    return c->to ? fdt_cells_spool_add_row(c->to, id, l, text) : 0;
}

int main(void)
{
    size_t n = 3000;
    double *xyz = malloc(3 * n * sizeof *xyz);
    CHECK(xyz != NULL);
    uint64_t seed = 32;
    for (size_t i = 0; i < 3 * n; i++)
        xyz[i] = test_unif(&seed);
    memcpy(xyz + 3 * 17, xyz + 3 * 5, 3 * sizeof *xyz); /* a merged duplicate */

    /* the whole set's cells and tables */
    fdt_result *r = NULL;
    fdt_voronoi *v = test_whole_cells(xyz, n, &r);
    CHECK(v != NULL);
    size_t lc, lv, ld;
    char *want_cells = whole(v, xyz, 0, FMT, &lc), *want_csv = whole(v, xyz, 0, NULL, &lv),
         *want_dens = whole(v, xyz, 1, NULL, &ld);

    /* the streamed run's batches spooled */
    two t = {NULL, NULL, 0};
    CHECK_EQ(fdt_cells_spool_open(&t.text, 0, n, FMT, 0, 1, "."), 0);
    CHECK_EQ(fdt_cells_spool_open(&t.csv, 0, n, NULL, 1, 0, "."), 0);
    fdt_voronoi_options o; /* as test_whole_cells's */
    fdt_default_voronoi_options(&o);
    o.neighbors = 1;
    o.threads = 1;
    fdt_settings s;
    fdt_default_settings(&s);
    s.n_threads = 2;
    fdt_context *ctx = NULL;
    fdt_result *sr = NULL;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    fdt_cell_sink sink = {sizeof sink, spool_both, &t};
    CHECK_EQ(fdt_voronoi_stream(ctx, xyz, n, &o, NULL, &sink, &sr), FDT_OK);
    EXPECT(t.batches >= 2); /* the points' own batches and the duplicate's */
    size_t l;
    char *got = put(t.text, 0, &l);
    expect_same(got, l, want_cells, lc, "the spooled cells");
    free(got);
    got = put(t.csv, 0, &l);
    expect_same(got, l, want_csv, lv, "the spooled CSV");
    free(got);
    got = put(t.text, 1, &l);
    expect_same(got, l, want_dens, ld, "the spooled densities");
    free(got);

    /* the records copied one by one into another spool */
    fdt_cells_spool *copy = NULL;
    CHECK_EQ(fdt_cells_spool_open(&copy, 0, n, FMT, 0, 1, "."), 0);
    copier c = {copy, -1, 0, 0};
    CHECK_EQ(fdt_cells_spool_each(t.text, copy_row, &c), 0);
    EXPECT(c.calls == n);
    got = put(copy, 0, &l);
    expect_same(got, l, want_cells, lc, "the copied cells");
    free(got);
    got = put(copy, 1, &l);
    expect_same(got, l, want_dens, ld, "the copied densities");
    free(got);
    copier stop = {NULL, -1, 0, 10};
    EXPECT(fdt_cells_spool_each(t.text, copy_row, &stop) == 77 && stop.calls == 10);

    /* refusals: a row twice, a row outside the ids, a table not whole */
    const char row[] = "5 x\n5 y\n";
    uint32_t ls[2] = {4, 4};
    EXPECT(fdt_cells_spool_add_row(copy, 5, ls, row) == EINVAL);
    fdt_cells_spool *part = NULL;
    CHECK_EQ(fdt_cells_spool_open(&part, 100, 50, FMT, 0, 1, "."), 0);
    EXPECT(fdt_cells_spool_add_row(part, 99, ls, row) == EINVAL);
    EXPECT(fdt_cells_spool_add_row(part, 150, ls, row) == EINVAL);
    EXPECT(fdt_cells_spool_add_row(part, 120, ls, row) == 0);
    FILE *f = tmpfile();
    CHECK(f != NULL);
    EXPECT(fdt_cells_spool_put(part, 0, 1, f) == EINVAL);
    fclose(f);
    copier one = {NULL, -1, 0, 0};
    EXPECT(fdt_cells_spool_each(part, copy_row, &one) == 0 && one.calls == 1 && one.last == 120);

    /* what the tables read, and cells without the rest */
    EXPECT(fdt_cells_table_skip("%i %v %F %n", 0, 0) ==
           (FDT_CELLS_NO_CENTROIDS | FDT_CELLS_NO_DENSITIES));
    EXPECT(fdt_cells_table_skip("%i %c", 0, 0) == FDT_CELLS_NO_DENSITIES);
    EXPECT(fdt_cells_table_skip("%C %d", 0, 0) == 0);
    EXPECT(fdt_cells_table_skip("%v %%c", 0, 1) == FDT_CELLS_NO_CENTROIDS);
    EXPECT(fdt_cells_table_skip(NULL, 1, 0) == 0);
    EXPECT(fdt_cells_table_skip(NULL, 0, 1) == FDT_CELLS_NO_CENTROIDS);
    EXPECT(fdt_cells_table_skip("%c %", 0, 0) == FDT_CELLS_NO_DENSITIES);
    o.skip = fdt_cells_table_skip("%i %v %F %s %n %f", 0, 0);
    fdt_voronoi *lean = NULL;
    CHECK_EQ(fdt_voronoi_compute(r, xyz, n, &o, &lean, NULL, 0), FDT_OK);
    size_t ll, lw;
    char *a = whole(lean, xyz, 0, "%i %v %F %s %n %f %h", &ll);
    char *b = whole(v, xyz, 0, "%i %v %F %s %n %f %h", &lw);
    expect_same(a, ll, b, lw, "the cells without centroids and densities");
    free(a);
    free(b);
    f = tmpfile();
    CHECK(f != NULL);
    EXPECT(fdt_wr_cells(f, FMT, lean, xyz, 1) == EINVAL);
    EXPECT(fdt_wr_cells(f, NULL, lean, xyz, 1) == EINVAL);
    EXPECT(fdt_wr_density(f, lean, 1) == EINVAL);
    fclose(f);
    fdt_cells_spool *wants = NULL;
    CHECK_EQ(fdt_cells_spool_open(&wants, 0, n, FMT, 0, 0, "."), 0);
    EXPECT(fdt_cells_spool_add(wants, lean) == EINVAL);
    fdt_cells_spool_close(&wants);
    fdt_voronoi_free(&lean);

    fdt_cells_spool_close(&part);
    fdt_cells_spool_close(&copy);
    fdt_cells_spool_close(&t.text);
    fdt_cells_spool_close(&t.csv);
    fdt_result_free(&sr);
    fdt_close(&ctx);
    free(want_cells);
    free(want_csv);
    free(want_dens);
    fdt_voronoi_free(&v);
    fdt_result_free(&r);
    free(xyz);
    return test_report("cells");
}
