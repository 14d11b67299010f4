/*
 * The per-part step of the parallel engine (src/engine.c) through
 * fdt_parallel_run on the mailbox transport, its contract read off the
 * gathered mesh and the per-thread stats:
 * - ownership (§3.2): every tet and hull face a thread output has its
 *   lowest id (tree order) in the thread's own part (parts are
 *   consecutive ranges of tree ids, of tstats[i].points each);
 * - the same tets as the serial engine, in both modes, with and without
 *   the neighbour links, which are symmetric and -1 only on the hull;
 * - messages: a thread sends at most one face per tet it builds plus one
 *   tet request per face it advances; duplicate requests are among the
 *   requests sent; every FACESEND sent is received;
 * - an injected failure of any part, before or after its first faces,
 *   ends the run with FDT_EINTERNAL naming that part, and no mesh.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "frontdt.h"
#include "parallel.h"
#include "prepare.h"
#include "testutil.h"

typedef struct input {
    const char *name;
    double *xyz;
    size_t n;
} input;

static input uniform(size_t n, uint64_t seed)
{
    input in = {"uniform", malloc(3 * n * sizeof(double)), n};
    CHECK(in.xyz != NULL);
    for (size_t i = 0; i < 3 * n; i++)
        in.xyz[i] = test_unif(&seed);
    return in;
}

/* k^3 lattice points: every cube's corners cospherical (ties). */
static input lattice(int k)
{
    input in = {"lattice", malloc(3 * (size_t)k * k * k * sizeof(double)), (size_t)k * k * k};
    CHECK(in.xyz != NULL);
    size_t n = 0;
    for (int i = 0; i < k; i++)
        for (int j = 0; j < k; j++)
            for (int l = 0; l < k; l++, n++) {
                in.xyz[3 * n] = i;
                in.xyz[3 * n + 1] = j;
                in.xyz[3 * n + 2] = l;
            }
    return in;
}

static int cmp4(const void *a, const void *b)
{
    return memcmp(a, b, 4 * sizeof(uint32_t));
}

static void sort4(uint32_t *v)
{
    for (int i = 1; i < 4; i++)
        for (int j = i; j > 0 && v[j - 1] > v[j]; j--) {
            uint32_t s = v[j];
            v[j] = v[j - 1];
            v[j - 1] = s;
        }
}

/* Tets of the serial run (input numbering), each sorted, then sorted:
 * the canonical set. */
static uint32_t *serial_set(const input *in, size_t *nt)
{
    fdt_settings s;
    fdt_default_settings(&s);
    s.mode = FDT_MODE_SERIAL;
    fdt_context *ctx = NULL;
    CHECK_EQ(fdt_open(&ctx, &s), FDT_OK);
    fdt_result *r = NULL;
    CHECK_EQ(fdt_triangulate(ctx, in->xyz, in->n, &r), FDT_OK);
    *nt = fdt_result_num_tets(r);
    uint32_t *c = malloc(*nt * 4 * sizeof *c);
    CHECK(c != NULL);
    const fdt_vid *t = fdt_result_tets(r);
    for (size_t i = 0; i < 4 * *nt; i++)
        c[i] = (uint32_t)t[i];
    for (size_t i = 0; i < *nt; i++)
        sort4(c + 4 * i);
    qsort(c, *nt, 4 * sizeof *c, cmp4);
    fdt_result_free(&r);
    fdt_close(&ctx);
    return c;
}

static void run_checked(const input *in, const uint32_t *ref, size_t nref, fdt_mode mode,
                        int nthreads, int nbrs)
{
    fdt_prepared pr;
    char diag[256] = "";
    CHECK_EQ(fdt_prepare(in->xyz, in->n, 1, &pr, diag, sizeof diag), FDT_OK);
    fdt_settings s;
    fdt_default_settings(&s);
    s.neighbors = nbrs;
    fdt_par_out out;
    int err = fdt_parallel_run(&pr, &s, mode, nthreads, NULL, &out, diag, sizeof diag);
    EXPECTF(err == FDT_OK, "%s, mode %d, %d threads: %d %s", in->name, mode, nthreads, err, diag);
    if (err) {
        fdt_prepared_free(&pr);
        return;
    }
    CHECK_EQ(out.nthreads, nthreads);
    /* input index -> tree id */
    uint32_t *tree_id = malloc(in->n * sizeof *tree_id);
    CHECK(tree_id != NULL);
    for (size_t i = 0; i < pr.m; i++)
        tree_id[pr.orig[i]] = (uint32_t)i;
    size_t t0 = 0, h0 = 0, lo = 0, fsent = 0, req = 0, dup = 0;
    for (int i = 0; i < nthreads; i++) {
        const fdt_thread_stats *ts = &out.tstats[i];
        size_t hi = lo + ts->points;
        int bad_t = 0, bad_h = 0;
        for (size_t t = t0; t < t0 + ts->tets; t++) {
            uint32_t m = UINT32_MAX;
            for (int k = 0; k < 4; k++) {
                uint32_t id = tree_id[out.mb.tets[4 * t + k]];
                m = id < m ? id : m;
            }
            bad_t += m < lo || m >= hi;
        }
        for (size_t h = h0; h < h0 + ts->hull_faces; h++) {
            uint32_t m = UINT32_MAX;
            for (int k = 0; k < 3; k++) {
                uint32_t id = tree_id[out.mb.hull[3 * h + k]];
                m = id < m ? id : m;
            }
            bad_h += m < lo || m >= hi;
        }
        EXPECTF(bad_t == 0 && bad_h == 0,
                "%s, mode %d, %d threads: thread %d output %d tets, %d hull faces it does not own",
                in->name, mode, nthreads, i, bad_t, bad_h);
        EXPECTF(ts->sent[FDT_MSG_FACESEND] <= ts->tets + ts->faces_advanced,
                "thread %d: %zu FACESENDs for %zu tets and %zu faces", i,
                ts->sent[FDT_MSG_FACESEND], ts->tets, ts->faces_advanced);
        req += ts->tet_requests; /* counted by the sender */
        dup += ts->duplicate_requests; /* by the receiver */
        fsent += ts->sent[FDT_MSG_FACESEND];
        t0 += ts->tets;
        h0 += ts->hull_faces;
        lo = hi;
    }
    EXPECT(lo == pr.m && t0 == out.mb.ntets && h0 == out.mb.nhull);
    EXPECT(dup <= req && req <= fsent);
    EXPECT(out.pst.sent[FDT_MSG_FACESEND] == fsent &&
           out.pst.received[FDT_MSG_FACESEND] == fsent);
    /* with one part nothing crosses */
    if (nthreads == 1)
        EXPECT(fsent == 0);
    /* the serial engine's tets */
    EXPECT(out.mb.ntets == nref);
    if (out.mb.ntets == nref) {
        uint32_t *c = malloc(nref * 4 * sizeof *c);
        CHECK(c != NULL);
        memcpy(c, out.mb.tets, nref * 4 * sizeof *c);
        for (size_t i = 0; i < nref; i++)
            sort4(c + 4 * i);
        qsort(c, nref, 4 * sizeof *c, cmp4);
        EXPECTF(!memcmp(c, ref, nref * 4 * sizeof *c), "%s, mode %d, %d threads: serial's tets",
                in->name, mode, nthreads);
        free(c);
    }
    /* neighbours: symmetric, -1 exactly on the hull */
    if (nbrs) {
        size_t open = 0, asym = 0;
        for (size_t t = 0; t < out.mb.ntets; t++)
            for (int f = 0; f < 4; f++) {
                int64_t u = out.mb.nbrs[4 * t + f];
                if (u < 0) {
                    open++;
                    continue;
                }
                int back = 0;
                for (int g = 0; g < 4; g++)
                    back += out.mb.nbrs[4 * (size_t)u + g] == (int64_t)t;
                asym += back != 1;
            }
        EXPECTF(open == out.mb.nhull && asym == 0, "%s, mode %d, %d threads: %zu open, %zu hull, %zu one-way",
                in->name, mode, nthreads, open, out.mb.nhull, asym);
    } else {
        EXPECT(out.mb.nbrs == NULL);
    }
    free(tree_id);
    fdt_par_out_free(&out);
    fdt_prepared_free(&pr);
}

/* Part `part` fails once it has advanced `after` faces. */
static void run_failing(const input *in, fdt_mode mode, int nthreads, int part, size_t after)
{
    fdt_prepared pr;
    char diag[256] = "";
    CHECK_EQ(fdt_prepare(in->xyz, in->n, 1, &pr, diag, sizeof diag), FDT_OK);
    fdt_settings s;
    fdt_default_settings(&s);
    fdt_par_opts opt;
    memset(&opt, 0, sizeof opt);
    opt.fail = 1;
    opt.fail_part = part;
    opt.fail_after = after;
    fdt_par_out out;
    int err = fdt_parallel_run(&pr, &s, mode, nthreads, &opt, &out, diag, sizeof diag);
    char want[64];
    snprintf(want, sizeof want, "worker thread %d:", part);
    EXPECTF(err == FDT_EINTERNAL && strstr(diag, want) != NULL,
            "mode %d, %d threads, part %d fails after %zu: %d, %s", mode, nthreads, part, after,
            err, diag);
    EXPECT(out.mb.tets == NULL && out.tstats == NULL);
    fdt_prepared_free(&pr);
}

int main(void)
{
    setvbuf(stdout, NULL, _IOLBF, 0);
    alarm(600);
    input ins[2] = {uniform(2000, 5), lattice(7)};
    for (int f = 0; f < 2; f++) {
        size_t nref;
        uint32_t *ref = serial_set(&ins[f], &nref);
        static const int nts[] = {1, 2, 3, 5, 8};
        for (int m = FDT_MODE_SHARED; m <= FDT_MODE_MESSAGE; m++)
            for (int i = 0; i < 5; i++)
                run_checked(&ins[f], ref, nref, (fdt_mode)m, nts[i], i % 2);
        printf("%s, %zu points: ownership, serial's tets, neighbours, messages on 1-8 threads\n",
               ins[f].name, ins[f].n);
        free(ref);
    }
    for (int m = FDT_MODE_SHARED; m <= FDT_MODE_MESSAGE; m++)
        for (int part = 0; part < 3; part++) {
            run_failing(&ins[0], (fdt_mode)m, 3, part, 0);
            run_failing(&ins[0], (fdt_mode)m, 3, part, 25);
        }
    printf("injected failures: every part, both modes, named\n");
    for (int f = 0; f < 2; f++)
        free(ins[f].xyz);
    return test_report("engine");
}
