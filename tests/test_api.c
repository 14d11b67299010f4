/*
 * The public API through the installed shared library (not the internal
 * archive): the ABI rules of include/frontdt.h for the structs that may
 * grow (struct_size first, sizes the library does not know refused with
 * FDT_EINVAL and nothing written beyond them).
 */
#include "frontdt.h"
#include "testutil.h"

#include <string.h>

/* A struct followed by canary bytes, to see what a call writes. */
#define CANARY 0xa5
#define PAD 64

static int canary_intact(const unsigned char *p, size_t from, size_t to)
{
    for (size_t i = from; i < to; i++)
        if (p[i] != CANARY)
            return 0;
    return 1;
}

static void test_settings(void)
{
    fdt_settings s;
    fdt_default_settings(&s);
    CHECK_EQ(s.struct_size, sizeof s);
    CHECK_EQ(s.mode, FDT_MODE_AUTO);
    CHECK(s.leaf_size > 0);

    /* A size the library does not know: refused, only struct_size (0)
     * written, never a byte beyond the size given. */
    unsigned char buf[sizeof(fdt_settings) + PAD];
    size_t bad[] = {sizeof(fdt_settings) + 8, sizeof(fdt_settings) - 1,
                    sizeof(fdt_settings) - sizeof(size_t), sizeof(size_t), 0};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        memset(buf, CANARY, sizeof buf);
        CHECK_EQ(fdt_default_settings_sized((fdt_settings *)buf, bad[k]), FDT_EINVAL);
        size_t written = bad[k] >= sizeof(size_t) ? sizeof(size_t) : 0;
        CHECK(canary_intact(buf, written, sizeof buf));
        if (written) {
            size_t z;
            memcpy(&z, buf, sizeof z);
            CHECK_EQ(z, 0);
        }
    }
    memset(buf, CANARY, sizeof buf);
    CHECK_EQ(fdt_default_settings_sized((fdt_settings *)buf, sizeof(fdt_settings)), FDT_OK);
    CHECK(canary_intact(buf, sizeof(fdt_settings), sizeof buf));
    CHECK_EQ(fdt_default_settings_sized(NULL, sizeof(fdt_settings)), FDT_EINVAL);

    /* fdt_open checks the size: zeroed by hand, too small, too large. */
    fdt_context *ctx = (fdt_context *)&ctx; /* must be set to NULL */
    fdt_settings z;
    memset(&z, 0, sizeof z);
    CHECK_EQ(fdt_open(&ctx, &z), FDT_EINVAL);
    CHECK(ctx == NULL);
    size_t sizes[] = {sizeof s - 1, sizeof s - sizeof(size_t), sizeof s + 8, 1};
    for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
        fdt_default_settings(&s);
        s.struct_size = sizes[k];
        CHECK_EQ(fdt_open(&ctx, &s), FDT_EINVAL);
        CHECK(ctx == NULL);
    }
    fdt_default_settings(&s);
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    CHECK(ctx != NULL);
    fdt_close(&ctx);
}

static void test_stats(void)
{
    /* The unit cube's corners and its centre: 12 tets. */
    static const double xyz[] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0, 0, 0, 1,
                                 1, 0, 1, 0, 1, 1, 1, 1, 1, 0.5, 0.5, 0.5};
    fdt_settings s;
    fdt_default_settings(&s);
    s.n_threads = 1;
    fdt_context *ctx;
    fdt_result *r;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    CHECK_EQ(fdt_triangulate(ctx, xyz, 9, &r), FDT_OK);
    CHECK_EQ(fdt_result_num_tets(r), 12);

    fdt_stats st;
    memset(&st, 0, sizeof st);
    CHECK_EQ(fdt_result_stats(r, &st), FDT_OK);
    CHECK_EQ(st.struct_size, sizeof st);
    CHECK_EQ(st.tets, 12);
    CHECK_EQ(st.points, 9);

    unsigned char buf[sizeof(fdt_stats) + sizeof(fdt_thread_stats) + PAD];
    size_t bad[] = {sizeof(fdt_stats) + 8, sizeof(fdt_stats) - 8, 0};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        memset(buf, CANARY, sizeof buf);
        CHECK_EQ(fdt_result_stats_sized(r, (fdt_stats *)buf, bad[k]), FDT_EINVAL);
        CHECK(canary_intact(buf, 0, sizeof buf));
    }
    memset(buf, CANARY, sizeof buf);
    CHECK_EQ(fdt_result_stats_sized(r, (fdt_stats *)buf, sizeof(fdt_stats)), FDT_OK);
    CHECK(canary_intact(buf, sizeof(fdt_stats), sizeof buf));

    fdt_thread_stats ts;
    CHECK_EQ(fdt_result_thread_stats(r, 0, &ts), FDT_OK);
    CHECK_EQ(ts.struct_size, sizeof ts);
    CHECK_EQ(ts.tets, 12);
    CHECK_EQ(fdt_result_thread_stats(r, 1, &ts), FDT_EINVAL);
    size_t tbad[] = {sizeof(fdt_thread_stats) + 8, sizeof(fdt_thread_stats) - 8, 0};
    for (size_t k = 0; k < sizeof tbad / sizeof tbad[0]; k++) {
        memset(buf, CANARY, sizeof buf);
        CHECK_EQ(fdt_result_thread_stats_sized(r, 0, (fdt_thread_stats *)buf, tbad[k]),
                 FDT_EINVAL);
        CHECK(canary_intact(buf, 0, sizeof buf));
    }
    fdt_result_free(&r);
    fdt_close(&ctx);
}

int main(void)
{
    test_settings();
    test_stats();
    printf("api: ok\n");
    return 0;
}
