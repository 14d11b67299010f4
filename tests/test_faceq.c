/*
 * The front's face queue (src/front/faceq.c) against a plain model: random
 * pushes and pops over id ranges of several sizes and bases, checking
 * that every pop returns a face of the lowest nonempty bucket, the last
 * one pushed into it, that nothing is lost or duplicated, that the
 * look-ahead names what the pops then return, and that clear, reuse and
 * out-of-range ids behave as faceq.h says.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/hash.h"
#include "front/faceq.h"
#include "frontdt.h"
#include "testutil.h"

static uint64_t rng_state = 0x2545F4914F6CDD1Dull;
static uint64_t rnd(void)
{
    return fdt_splitmix64(&rng_state);
}

/* The model: every queued face with its push serial number. */
typedef struct mface {
    uint32_t v[3];
    uint64_t serial;
} mface;

typedef struct model {
    mface *f;
    size_t n, cap;
    uint64_t serial;
} model;

static void model_push(model *m, const uint32_t v[3])
{
    if (m->n == m->cap) {
        m->cap = m->cap ? 2 * m->cap : 256;
        m->f = realloc(m->f, m->cap * sizeof *m->f);
        if (!m->f) {
            fprintf(stderr, "out of memory\n");
            exit(1);
        }
    }
    memcpy(m->f[m->n].v, v, sizeof m->f[m->n].v);
    m->f[m->n++].serial = m->serial++;
}

/* The face the queue must return: lowest bucket, then latest pushed. */
static size_t model_next(const model *m, uint32_t base)
{
    size_t best = SIZE_MAX;
    for (size_t i = 0; i < m->n; i++) {
        if (best == SIZE_MAX)
            best = i;
        else {
            uint32_t bi = (m->f[i].v[0] - base) >> FDT_FACEQ_SHIFT;
            uint32_t bb = (m->f[best].v[0] - base) >> FDT_FACEQ_SHIFT;
            if (bi < bb || (bi == bb && m->f[i].serial > m->f[best].serial))
                best = i;
        }
    }
    return best;
}

static void random_face(uint32_t base, uint32_t nids, uint32_t v[3])
{
    /* Mostly ids near the low end, as a sweeping front makes them, with
     * jumps anywhere: exercises cur moving down and long empty runs. */
    uint32_t off = (rnd() % 4 == 0) ? (uint32_t)(rnd() % nids)
                                    : (uint32_t)(rnd() % (nids < 200 ? nids : 200));
    v[0] = base + off;
    v[1] = v[0] + 1 + (uint32_t)(rnd() % 1000);
    v[2] = v[0] + 1 + (uint32_t)(rnd() % 1000);
}

static void run_case(uint32_t base, uint32_t nids, int steps)
{
    fdt_faceq q;
    model m = {0};
    EXPECTF(fdt_faceq_init(&q, base, nids) == FDT_OK, "init %u %u", base, nids);
    for (int round = 0; round < 2; round++) {
        for (int s = 0; s < steps; s++) {
            int push = m.n == 0 || rnd() % 100 < 55;
            if (push) {
                uint32_t v[3];
                random_face(base, nids, v);
                EXPECTF(fdt_faceq_push(&q, v) == FDT_OK, "push");
                model_push(&m, v);
                continue;
            }
            size_t want = model_next(&m, base);
            const uint32_t *ahead = fdt_faceq_ahead(&q, 0);
            uint32_t got[3];
            EXPECTF(fdt_faceq_pop(&q, got) == 1, "pop from a queue of %zu", m.n);
            EXPECTF(memcmp(got, m.f[want].v, sizeof got) == 0,
                  "base %u nids %u: popped (%u %u %u), expected (%u %u %u)", base, nids,
                  got[0], got[1], got[2], m.f[want].v[0], m.f[want].v[1], m.f[want].v[2]);
            if (ahead)
                EXPECTF(memcmp(ahead, got, sizeof got) == 0, "ahead(0) named another face");
            m.f[want] = m.f[--m.n];
            EXPECTF(q.count == m.n, "count %zu, model %zu", q.count, m.n);
        }
        if (round == 0) {
            /* drain: every face comes back exactly once, in order */
            uint32_t got[3];
            const uint32_t *a2 = fdt_faceq_ahead(&q, 2);
            uint32_t a2v[3] = {0, 0, 0};
            int have_a2 = a2 != NULL;
            if (have_a2)
                memcpy(a2v, a2, sizeof a2v);
            int k = 0;
            while (m.n) {
                size_t want = model_next(&m, base);
                EXPECTF(fdt_faceq_pop(&q, got) == 1, "drain pop");
                EXPECTF(memcmp(got, m.f[want].v, sizeof got) == 0, "drain order");
                if (k == 2 && have_a2)
                    EXPECTF(memcmp(got, a2v, sizeof got) == 0, "ahead(2) named another face");
                m.f[want] = m.f[--m.n];
                k++;
            }
            EXPECTF(fdt_faceq_pop(&q, got) == 0, "pop from an empty queue");
            EXPECTF(q.count == 0, "count after drain");
        } else {
            fdt_faceq_clear(&q);
            m.n = 0;
            uint32_t got[3];
            EXPECTF(fdt_faceq_pop(&q, got) == 0, "pop after clear");
            EXPECTF(q.count == 0, "count after clear");
            /* usable again after clear */
            uint32_t v[3] = {base + nids - 1, base + nids, base + nids + 1};
            EXPECTF(fdt_faceq_push(&q, v) == FDT_OK, "push after clear");
            EXPECTF(fdt_faceq_pop(&q, got) == 1 && got[0] == v[0], "pop after clear and push");
        }
    }
    /* ids outside [base, base + nids) are a caller's bug, refused */
    uint32_t lowv[3] = {base - 1, base, base + 1}, highv[3] = {base + nids, base + nids + 1, base + nids + 2};
    if (base > 0)
        EXPECTF(fdt_faceq_push(&q, lowv) == FDT_EINTERNAL, "id below the range accepted");
    EXPECTF(fdt_faceq_push(&q, highv) == FDT_EINTERNAL, "id above the range accepted");
    EXPECTF(q.count == 0, "a refused push was counted");
    fdt_faceq_free(&q);
    fdt_faceq_free(&q); /* freeing twice is harmless: the struct is zeroed */
    free(m.f);
}

int main(void)
{
    /* one bucket; one word of bits; several summary words (2^12 buckets
     * a summary word: 300k ids span 3); a part starting at a high id */
    run_case(0, 1, 200);
    run_case(0, 31, 2000);
    run_case(0, 5000, 20000);
    run_case(0, 300000, 20000);
    run_case(1000000, 70000, 20000);
    run_case(UINT32_MAX - 100000, 99990, 5000);
    return test_report("test_faceq");
}
