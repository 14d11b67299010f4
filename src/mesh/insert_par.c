/*
 * The parallel Bowyer-Watson build (fdt_ins_build_parallel, src/mesh/insert.h):
 * the same perturbed DT as fdt_ins_build, built by several threads at once
 * (the design of CGAL's parallel Delaunay_triangulation_3: optimistic
 * insertions under per-tet try-locks; HXT instead gives each thread a
 * region of space, which bench/NOTES.md entry 98 built and measured: no
 * faster on volumes, and no parallelism on a pipe's scan, where every
 * cavity crosses any wall).
 *
 * Phases.
 *   1. Serial start (src/mesh/insert.c): the first BRIO rounds, until about
 *      n/128 points are in (at least the first round), so the mesh is
 *      fine enough that concurrent cavities are small and rarely meet.
 *      It was n/32 until bench/NOTES.md entry 72: on two threads the
 *      deferrals stayed at tens a 100k run, and the serial start fell
 *      from 3-8 % of the build's wall time to under 2 %.
 *   2. Concurrent insertion: the points of the later rounds are split by
 *      id range, and ids are in a spatially coherent order (Morton order
 *      in the one-part engine), so each thread gets one spatial region
 *      (a range of that curve). Each thread inserts
 *      its points round by round, in id order within a round (BRIO kept
 *      per region). Both threads sweep their region in the same direction,
 *      so when thread i is at the cut with thread i + 1, thread i + 1 is at
 *      its far end. A thread done with its own points takes points from
 *      the end of another's last round (struct span).
 *   3. Serial finish: points left deferred (their cavity met another
 *      thread's too often) or left undone (slots ran out) are inserted on
 *      the calling thread, where the arrays may grow.
 * The perturbed DT is unique, so the insertion order (and which thread
 * inserted what) cannot change the result: only the slot numbering.
 *
 * Locks. Every slot has a state byte: its owner in the low six bits (0:
 * free; i + 1: held by worker i) and, above them, the conflict mark of
 * the insertion that holds it (MARK_*, written only by the holder). One
 * byte for both, because the cavity search reads both for every tet it
 * meets, and a second array cost a second cache line a tet: the
 * two-thread build took 2-5 % longer with the two (bench/NOTES.md
 * entry 66).
 * An insertion holds a lock on every tet it reads: the walk goes hand over
 * hand (it locks the next tet before letting the current one go, so the
 * neighbour reference it follows stays valid: whoever destroys or rewires
 * a tet must lock that tet's neighbours too), and the cavity search locks
 * each tet it tests (the cavity's tets, which it destroys, and the outside
 * neighbours, whose neighbour entry it rewrites), plus, for the coplanar
 * rule of a hull face, the finite tet under it. A lock that another
 * thread holds makes the insertion give up before it has written
 * anything: it releases what it holds and defers the point. So every
 * insertion is all-or-nothing under strict two-phase locking, and the
 * concurrent run is equivalent to some serial order of insertions.
 * A freed slot stays locked by the worker that freed it (it is on that
 * worker's free list and will be its next new tet): a stale hint that
 * names it fails to lock, as any slot in use by another thread does, and
 * no thread ever reads a freed slot it does not own.
 *
 * Slots. One capacity, allocated before the threads start (the slots a
 * point the serial rounds used, times 1.35, times n: 9-10 a point on
 * uniform points, 15-19 on a pipe scan; untouched pages cost no memory)
 * and never moved while they run. Fresh slots come in
 * chunks (chunk_of) from one atomic counter; freed slots go to the freeing
 * worker's own list. A worker that finds the capacity spent stops every
 * worker cleanly (before writing anything); phase 3 grows the arrays.
 *
 * Data-race freedom (the TSan suite runs the tests): the tets (m->T) are
 * plain memory, each slot's touched only by the holder of its lock; the
 * lock's acquire on taking it and release on letting it go order every
 * access of one holder before the next holder's. The state bytes are
 * atomics: the holder changes its mark with relaxed stores (it alone
 * writes a held byte; another thread's compare-and-swap expects 0 and
 * fails on any held byte, marked or not).
 * The per-point start hints are relaxed atomics, validated by locking.
 */
#include "mesh/insert.h"
#include "mesh/insert_impl.h"
#include "base/clock.h"
#include "base/mem.h"
#include "base/spawn.h"

#include <pthread.h>
#include <sched.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include "base/bits.h"

enum {
    MAX_WORKERS = 63,  /* owner ids are six bits, 0 meaning free */
    OWNER = 63,        /* the owner's bits of a state byte */
    MARK_SHIFT = 6,    /* the mark's */
    RECENT = 8,        /* recent new tets kept as walk starts */
    HINT_REACH = 16,   /* ids tried each side for a neighbour's hint */
};

/*
 * The fresh slots a worker takes at a time from the shared counter, for n
 * points: n / 64 as a power of two, from 256 to 65536 (16384 at 1M
 * points, 512 KB of tets). Chunks of 256 at every size interleaved the
 * workers' new tets in every huge page, and the two-thread build took
 * about 3 % more CPU (bench/NOTES.md entry 118); a chunk's unused rest is
 * freed slots every later pass reads, so small builds keep small chunks.
 */
static uint32_t chunk_of(uint32_t n)
{
    uint32_t c = 256;
    while (c < 65536 && 2 * (uint64_t)c <= n / 64)
        c *= 2;
    return c;
}

/* What an insertion attempt returns besides FDT_OK and the errors:
 * BUSY, another thread holds a tet it needs; FULL, the slots are spent
 * (phase 2). Either way nothing was written and nothing is held. */
enum { BUSY = 1, FULL = 2 };
/* walk_locked's answer at its budget (the hull walk's turn). */
enum { WALK_LONG = 3 };
/* The last star's infinite tets kept as the hull walk's starts. */
enum { HULL_STARTS = 8 };

/* lock_live's answers besides 0 (another worker holds the tet). */
enum { MINE = 1, TAKEN = 2 };

/*
 * A worker's last round is shared once it reaches it: the points it has
 * not taken yet are the range [front, back) of its list, one 64-bit
 * atomic (front in the high half), on a cache line of its own. The owner
 * takes CLAIM points at a time from the front, in its BRIO order; a
 * worker done with its own points takes CLAIM from the back of the
 * fullest other range (steal). Before, the thread that finished first
 * waited at the join: one region ended 10-30 ms after the other in the
 * collective builds of citylidar 200k and statue 440k (bench/NOTES.md
 * entry 81). The back of a range is the far end of the owner's sweep,
 * beside the start of the next region, which its worker left long ago,
 * so owner and thief rarely meet until the range is nearly spent.
 */
typedef struct span {
    alignas(64) _Atomic uint64_t fb; /* front << 32 | back, indices into pts */
} span;

enum { CLAIM = 16 };

typedef struct shared {
    fdt_ins *m;
    span *spans;               /* nw: the workers' last rounds */
    struct worker *all;        /* the workers, for stealing */
    int nw;
    atomic_uchar *lock;        /* cap entries: owner | mark << MARK_SHIFT, 0 free */
    atomic_uint_fast64_t next; /* the next fresh slot */
    uint32_t chunk;            /* fresh slots taken at a time (chunk_of) */
    _Atomic uint32_t *hint;    /* n entries: a tet that held point base + i */
    int single;                /* phase 3: one thread, the arrays may grow */
    atomic_int stop;           /* an error or spent slots: every worker stops */
    atomic_int err;            /* the first error (0: none) */
    /* Phase 2's points, which each worker picks from (pick_points): the
     * BRIO order, its rounds r0 .. nrounds - 1, the start's four points. */
    const uint32_t *order;
    const uint32_t *round_end;
    int r0, nrounds;
    uint32_t first[4];
} shared;

typedef struct worker {
    shared *sh;
    unsigned char me;          /* owner id */
    uint32_t own_lo, own_span; /* its region: ids own_lo .. own_lo + own_span - 1 */
    /* What an insertion locks is on one of these lists (see insert_point):
     * the cavity (MARK_IN), the tets outside it met by the search
     * (MARK_OUT), the tets under hull faces the coplanar rule read
     * (unmarked unless met again), the new tets. */
    uint32_t *cav;             /* the cavity's tets */
    size_t ncav, cavcap;
    uint32_t *outl;            /* the tets marked MARK_OUT */
    size_t nout, outcap;
    uint32_t *under;           /* the coplanar rule's tets, locked by it */
    size_t nunder, undercap;
    uint32_t *newt;            /* the new tets */
    size_t newcap;
    uint32_t *bnd;             /* its boundary faces, packed (tet, k) */
    size_t nbnd, bndcap;
    ins_local local;           /* links small stars (ins_make_star) */
    ins_edges edges;           /* links the others */
    uint32_t free_head, nfree; /* this worker's freed slots, all locked by it */
    uint32_t fresh, fresh_end; /* the rest of its chunk of fresh slots */
    uint32_t last;             /* the last tet it made: the next walk's start */
    uint32_t recent[RECENT];   /* more starts, when last is held elsewhere */
    unsigned nrecent;
    uint64_t rng;              /* the walk's choices */
    ins_hull hull;             /* its hull walks (insert_impl.h) */
    /* The last star's infinite tets, when its point lay outside the hull:
     * slot and four vertex ids each, copied while the star was held, so
     * that the next hull walk tests them without a lock. */
    uint32_t hull_slot[HULL_STARTS], hull_ids[HULL_STARTS][4];
    unsigned nhull_start;
    const uint32_t *pts;       /* its points in insertion order */
    size_t npts;
    size_t *round_end;         /* ends of its rounds in pts (borrowed) */
    int nrounds;
    uint32_t *mine;            /* owned: phase 2's points, pick_points */
    int picked;                /* pick_points ran */
    uint32_t *def;             /* deferred points */
    size_t ndef, defcap;
    uint32_t *todo;            /* owned: a later pass's points (pts) */
    size_t todocap;
    fdt_pred_counts cnt;
    fdt_ins_stats st;
    pthread_t th;
    int started;
    double cpu_s;              /* thread CPU seconds in worker_main */
} worker;

/* ------------------------------------------------------------------ */
/* Locks. */

/*
 * Takes slot t if it is free. Acquire on success: the previous holder's
 * release (unlock) happened before, so its writes to the tet and its mark
 * are visible here. Relaxed on failure: nothing is read then.
 */
static inline int lock_free_slot(shared *sh, uint32_t t, unsigned char me)
{
    unsigned char exp = 0;
    return atomic_compare_exchange_strong_explicit(&sh->lock[t], &exp, me, memory_order_acquire,
                                                   memory_order_relaxed);
}

/* Release: every read and write of the tet by this holder happens before
 * the next holder's acquire. */
static inline void unlock_slot(shared *sh, uint32_t t)
{
    atomic_store_explicit(&sh->lock[t], 0, memory_order_release);
}

/*
 * Makes sure w holds live slot t: TAKEN if it took it now (its mark is
 * then MARK_NONE), MINE if this insertion held it already (*mark: its
 * mark), 0 if another worker holds it. "Already held" can be read from a
 * failed CAS: only w writes its own id, and its own earlier write is what
 * the relaxed load then returns. (A slot this worker freed is locked by
 * it too, but a live tet's neighbour is never a freed slot, and only
 * neighbours reach here.)
 */
static inline int lock_live(worker *w, uint32_t t, int *mark)
{
    /* A plain look first (relaxed: the CAS below is what acquires): most
     * neighbours met are this insertion's own cavity tets, and a CAS that
     * fails still takes the cache line. The look gives the mark too. */
    unsigned char exp = atomic_load_explicit(&w->sh->lock[t], memory_order_relaxed);
    if (exp == 0 && atomic_compare_exchange_strong_explicit(&w->sh->lock[t], &exp, w->me,
                                                            memory_order_acquire,
                                                            memory_order_relaxed)) {
        *mark = MARK_NONE;
        return TAKEN;
    }
    *mark = exp >> MARK_SHIFT;
    return (exp & OWNER) == w->me ? MINE : 0;
}

/* A new mark for a slot w holds (relaxed: see Data-race freedom). */
static inline void set_mark(worker *w, uint32_t t, int mark)
{
    atomic_store_explicit(&w->sh->lock[t], (unsigned char)(w->me | mark << MARK_SHIFT),
                          memory_order_relaxed);
}

static void unlock_list(shared *sh, const uint32_t *list, size_t n)
{
    for (size_t i = 0; i < n; i++)
        unlock_slot(sh, list[i]);
}

/* Lets go of the coplanar rule's tets that no list below has: still
 * unmarked, live (a freed cavity slot is unmarked too, but stays w's) and
 * still w's (a list let go of it before, and another worker may hold it
 * since). */
static void unlock_under(worker *w)
{
    shared *sh = w->sh;
    const uint32_t *T = sh->m->T;
    for (size_t i = 0; i < w->nunder; i++) {
        uint32_t t = w->under[i];
        const uint32_t *v = T + 8 * (size_t)t;
        if (atomic_load_explicit(&sh->lock[t], memory_order_relaxed) == w->me &&
            !(v[0] == INF && v[1] == INF))
            unlock_slot(sh, t);
    }
    w->nunder = 0;
}

/* An insertion gives up before writing anything: lets go of every tet it
 * locked (the cavity's too; unlocking clears the marks). */
static void abort_insertion(worker *w)
{
    unlock_list(w->sh, w->cav, w->ncav);
    unlock_list(w->sh, w->outl, w->nout);
    w->ncav = w->nout = 0;
    unlock_under(w);
}

/* ------------------------------------------------------------------ */
/* Slots. */

/* Puts slot t on w's free list (w holds it, and keeps it). */
static inline void free_slot(worker *w, uint32_t t)
{
    uint32_t *v = w->sh->m->T + 8 * (size_t)t;
    v[0] = v[1] = INF;
    v[4] = w->free_head;
    w->free_head = t;
    w->nfree++;
    set_mark(w, t, MARK_NONE);
}

/* Phase 3 only (one thread): more capacity. */
static int grow_arrays(shared *sh, uint64_t need)
{
    fdt_ins *m = sh->m;
    uint64_t nc;
    /* every slot below the capacity: the workers' chunks of phase 3 lie
     * past nslots, which is set at its end */
    int err = ins_grow_tets(m, need, m->cap, &nc);
    if (err)
        return err;
    atomic_uchar *lk = malloc((size_t)nc * sizeof *lk);
    if (!lk)
        return FDT_ENOMEM;
    /* One thread runs: relaxed copies. */
    for (uint32_t i = 0; i < m->cap; i++)
        atomic_init(&lk[i], atomic_load_explicit(&sh->lock[i], memory_order_relaxed));
    for (uint64_t i = m->cap; i < nc; i++)
        atomic_init(&lk[i], 0);
    free(sh->lock);
    sh->lock = lk;
    m->cap = (uint32_t)nc;
    return FDT_OK;
}

/*
 * Makes room for `need` new tets in w's free list and chunk: FDT_OK,
 * FULL when the capacity is spent (phase 2: the caller stops everyone),
 * or an error.
 */
static int reserve(worker *w, size_t need)
{
    shared *sh = w->sh;
    while ((size_t)w->nfree + (w->fresh_end - w->fresh) < need) {
        /* The chunk's rest goes to the free list, so chunks need not be
         * contiguous. Nobody else has seen these slots: plain stores of
         * the owner id are enough (relaxed: published, if ever, through
         * the release of a lock taken on them later). */
        for (; w->fresh < w->fresh_end; w->fresh++) {
            atomic_store_explicit(&sh->lock[w->fresh], w->me, memory_order_relaxed);
            free_slot(w, w->fresh);
        }
        /* Relaxed: the counter only hands out distinct ranges; the slots'
         * contents are published through their locks. */
        uint64_t x = atomic_fetch_add_explicit(&sh->next, sh->chunk, memory_order_relaxed);
        uint32_t cap = sh->m->cap;
        /* Phase 2 takes a chunk's part below the capacity (the counter
         * then ends past it, and nslots is cut back to it); phase 3 grows
         * to fit the whole chunk, so no slot below nslots is left out. */
        if (x >= cap && !sh->single)
            return FULL;
        if (x + sh->chunk > cap && sh->single) {
            int err = grow_arrays(sh, x + sh->chunk);
            if (err)
                return err;
            cap = sh->m->cap;
        }
        w->fresh = (uint32_t)x;
        w->fresh_end = x + sh->chunk < cap ? (uint32_t)(x + sh->chunk) : cap;
    }
    return FDT_OK;
}

/* A slot for a new tet, locked by w (reserve first). */
static inline uint32_t alloc_slot(worker *w)
{
    uint32_t t;
    if (w->free_head != FDT_NONE) {
        t = w->free_head;
        w->free_head = w->sh->m->T[8 * (size_t)t + 4];
        w->nfree--;
    } else {
        t = w->fresh++;
        /* Never seen by another thread: see reserve. */
        atomic_store_explicit(&w->sh->lock[t], w->me, memory_order_relaxed);
    }
    return t;
}

/* ------------------------------------------------------------------ */
/* One insertion. */

/*
 * Hand-over-hand visibility walk (src/mesh/insert.c's walk) from `start`,
 * which this worker has just locked, in at most `budget` steps. On 0
 * (located) and on WALK_LONG (the budget spent) *out is locked (the
 * caller's to let go); on BUSY nothing is held.
 */
static int walk_locked(worker *w, const double *p, uint32_t start, size_t budget, uint32_t *out)
{
    shared *sh = w->sh;
    const fdt_ins *m = sh->m;
    const uint32_t *T = m->T;
    uint32_t t = start;
    for (int i = 0; i < 4; i++)
        if (T[8 * (size_t)t + i] == INF) { /* start in the finite tet below */
            uint32_t nb = T[8 * (size_t)t + 4 + i] >> 2;
            if (!lock_free_slot(sh, nb, w->me)) {
                unlock_slot(sh, t);
                return BUSY;
            }
            unlock_slot(sh, t);
            t = nb;
            break;
        }
    int from = -1;
    size_t steps = 0;
    int err = FDT_OK;
    for (;; steps++) {
        if (steps > m->cap) { /* a cycle: impossible in a regular triangulation */
            unlock_slot(sh, t);
            return sh->single ? FDT_EINTERNAL : BUSY;
        }
        const uint32_t *v = T + 8 * (size_t)t;
        if (ins_is_infinite(v))
            break; /* located: at any step, the budget's last too */
        if (steps == budget) { /* held: WALK_LONG's tet is finite */
            err = WALK_LONG;
            break;
        }
        int exit = ins_walk_exit(m, v, p, from, &w->rng, &m->sf, &w->cnt);
        if (exit < 0)
            break;
        uint32_t nb = v[4 + exit];
        /* t is held, so its neighbour nb >> 2 is live and stays so until
         * t is let go: take it first. */
        if (!lock_free_slot(sh, nb >> 2, w->me)) {
            unlock_slot(sh, t);
            return BUSY;
        }
        unlock_slot(sh, t);
        t = nb >> 2;
        from = (int)(nb & 3);
    }
    w->st.walk_steps += steps;
    *out = t;
    return err;
}

/* Whether this worker now holds slot t as the infinite tet with the ids
 * v (a start copied from the last star): a lock taken on a slot handed
 * out is on a live tet, which may since have become another one. */
static int take_start(worker *w, uint32_t t, const uint32_t v[4])
{
    shared *sh = w->sh;
    if (!lock_free_slot(sh, t, w->me))
        return 0;
    if (memcmp(sh->m->T + 8 * (size_t)t, v, 4 * sizeof *v) == 0)
        return 1;
    unlock_slot(sh, t);
    return 0;
}

/*
 * The hull walk (insert_impl.h) of a worker, hand over hand like
 * walk_locked, while the visibility walk's tet `held` stays locked: the
 * last star's infinite tets first, as the serial build tests them, here
 * from their copies (without a lock: a lock and a test each cost the
 * workers more than they saved, bench/NOTES.md entry 133), and only the
 * one p is outside of taken; else from the first that can be taken,
 * across hull faces. Returns 1 with the cavity's start in *out (locked;
 * held let go), 0 with a tet near p for the visibility walk in *out
 * (locked; held let go unless it is *out), or -1 when it gave up (a lock
 * held elsewhere, no start, no o, or INS_HULL_WALK_STEPS steps): only
 * held is held then.
 */
__attribute__((noinline, cold)) static int hull_walk_locked(worker *w, const double *p,
                                                            uint32_t held, uint32_t *out)
{
    shared *sh = w->sh;
    const fdt_ins *m = sh->m;
    const uint32_t *T = m->T;
    ins_hull *h = &w->hull;
    int inf = -1;
    for (unsigned i = 0; i < w->nhull_start; i++)
        if (ins_conflict_local(m, w->hull_ids[i], p, &m->sf, &w->cnt, &inf) == 1 &&
            take_start(w, w->hull_slot[i], w->hull_ids[i])) {
            unlock_slot(sh, held);
            *out = w->hull_slot[i];
            return 1;
        }
    uint32_t t = FDT_NONE;
    for (unsigned i = 0; i < w->nhull_start && t == FDT_NONE; i++)
        if (take_start(w, w->hull_slot[i], w->hull_ids[i]))
            t = w->hull_slot[i];
    if (t == FDT_NONE)
        return -1;
    const uint32_t *v = T + 8 * (size_t)t;
    if (h->has_o == 0) {
        /* o from the finite tet under the start: it must be held to be
         * read (held itself, or locked now) */
        uint32_t u = v[4 + fdt_ins_inf_index(v)] >> 2;
        int mine = u == held || lock_free_slot(sh, u, w->me);
        if (mine) {
            h->has_o = ins_hull_origin(m, T + 8 * (size_t)u, h->o, &m->sf, &w->cnt) ? 1 : -1;
            if (u != held)
                unlock_slot(sh, u);
        }
    }
    if (h->has_o <= 0) {
        unlock_slot(sh, t);
        return -1;
    }
    int from = -1;
    for (int steps = 0;; steps++) {
        if (steps == INS_HULL_WALK_STEPS) {
            unlock_slot(sh, t);
            return -1;
        }
        v = T + 8 * (size_t)t;
        int exit = ins_hull_exit(m, v, h->o, p, from, &w->rng, &m->sf, &w->cnt);
        if (exit < 0)
            break;
        uint32_t nb = v[4 + exit];
        /* t is held, so nb >> 2 is live until t is let go: take it first */
        if (!lock_free_slot(sh, nb >> 2, w->me)) {
            unlock_slot(sh, t);
            return -1;
        }
        unlock_slot(sh, t);
        t = nb >> 2;
        from = (int)(nb & 3);
    }
    if (ins_conflict_local(m, v, p, &m->sf, &w->cnt, &inf) == 1) {
        unlock_slot(sh, held);
        *out = t;
        return 1;
    }
    uint32_t u = v[4 + fdt_ins_inf_index(v)] >> 2;
    if (u != held && !lock_free_slot(sh, u, w->me)) {
        unlock_slot(sh, t);
        return -1;
    }
    unlock_slot(sh, t);
    if (u != held)
        unlock_slot(sh, held);
    *out = u;
    return 0;
}

/* The walk from `start` (locked by this worker) to p: the visibility walk,
 * and where the last point lay outside the hull and that walk grows long,
 * the hull walk (src/mesh/insert.c's locate_from). On 0 *out is locked;
 * on BUSY nothing is held. A worker's trial (ins_hull_budget) counts its
 * own hull walks, whose points depend on the threads' shares: a choice of
 * route, which cannot change the mesh (the perturbed DT is unique). */
static int walk_from(worker *w, const double *p, uint32_t start, uint32_t *out)
{
    const fdt_ins *m = w->sh->m;
    int err = walk_locked(w, p, start, ins_hull_budget(&w->hull, m), out);
    if (err != WALK_LONG)
        return err;
    uint32_t t;
    int got = hull_walk_locked(w, p, *out, &t);
    ins_hull_count(&w->hull, &w->st.hull_walks, got);
    if (got == 1) {
        *out = t;
        return FDT_OK;
    }
    return walk_locked(w, p, got == 0 ? t : *out, SIZE_MAX, out);
}

/* Takes a start for the walk to p (id pid) and walks: the last tet made,
 * the recent ones, the hints of the points next in id order, and in
 * phase 3 any free slot. */
static int locate(worker *w, uint32_t pid, const double *p, uint32_t *out)
{
    shared *sh = w->sh;
    const fdt_ins *m = sh->m;
    /* last, recent and the hints name slots that were handed out, so
     * each is live or freed (and then locked): a lock taken is on a live
     * tet. Slots never handed out are never named. */
    if (w->last != FDT_NONE && lock_free_slot(sh, w->last, w->me))
        return walk_from(w, p, w->last, out);
    for (unsigned i = 0; i < RECENT && i < w->nrecent; i++) {
        uint32_t t = w->recent[(w->nrecent - 1 - i) % RECENT];
        if (lock_free_slot(sh, t, w->me))
            return walk_from(w, p, t, out);
    }
    uint32_t i0 = pid - m->base;
    for (uint32_t d = 1; d <= HINT_REACH; d++) {
        for (int side = 0; side < 2; side++) {
            if (side ? i0 + d >= m->n : i0 < d)
                continue;
            uint32_t j = side ? i0 + d : i0 - d;
            /* Relaxed: a hint is only where to try a lock; the lock's
             * acquire is what makes the tet's contents readable, and a
             * locked slot is always live (freed slots stay locked). */
            uint32_t t = atomic_load_explicit(&sh->hint[j], memory_order_relaxed);
            if (t != FDT_NONE && lock_free_slot(sh, t, w->me))
                return walk_from(w, p, t, out);
        }
    }
    if (sh->single) { /* [0, nslots) was handed out before phase 3 */
        for (uint32_t t = 0; t < m->nslots; t++)
            if (lock_free_slot(sh, t, w->me))
                return walk_from(w, p, t, out);
        return FDT_EINTERNAL;
    }
    return BUSY;
}

/* Whether tet t (held) is in conflict with p: src/mesh/insert.c's rule. The
 * coplanar case reads the finite tet under a hull face: taken too. */
static inline int conflict(worker *w, uint32_t t, const double *p)
{
    const fdt_ins *m = w->sh->m;
    const uint32_t *v = m->T + 8 * (size_t)t;
    w->st.conflict_tests++;
    int inf = -1, c = ins_conflict_local(m, v, p, &m->sf, &w->cnt, &inf);
    if (c != INS_CONFLICT_UNDER)
        return c;
    uint32_t u = v[4 + inf] >> 2;
    int umark, r = lock_live(w, u, &umark);
    if (r == 0)
        return -BUSY;
    if (r == TAKEN) {
        if (w->nunder == w->undercap &&
            ins_grow_u32(&w->under, &w->undercap, w->nunder + 1) != FDT_OK) {
            unlock_slot(w->sh, u);
            return FDT_ENOMEM;
        }
        w->under[w->nunder++] = u;
    }
    return ins_conflict_under(m, m->T + 8 * (size_t)u, p, &m->sf, &w->cnt);
}

/*
 * Inserts point pid: FDT_OK, BUSY (nothing changed, nothing held), or an
 * error (nothing held). Every tet it locks is on one of w's lists from
 * the moment it is locked to its release: the walk's last tet and the
 * cavity on cav, the tets outside met by the search on outl, the tets the
 * coplanar rule locked on under, the new tets on newt. So releasing is a
 * pass over the lists (the cavity's slots, freed, stay locked), as the
 * serial build clears its marks, instead of a list of every lock taken:
 * bench/NOTES.md entry 78.
 */
static int insert_point(worker *w, uint32_t pid)
{
    shared *sh = w->sh;
    fdt_ins *m = sh->m;
    const double *p = ins_pt(m, pid);
    uint32_t t0;
    int err = locate(w, pid, p, &t0);
    if (err)
        return err;
    const uint32_t *v0 = m->T + 8 * (size_t)t0;
    const int outside = ins_is_infinite(v0);
    if (ins_is_vertex(m, v0, p)) { /* see src/mesh/insert.c: a duplicate */
        unlock_slot(sh, t0);
        return FDT_EINVAL;
    }
    w->ncav = w->nbnd = w->nout = w->nunder = 0;
    size_t unsure0 = w->cnt.insphere_unsure; /* see ins_star_ok */
    set_mark(w, t0, MARK_IN);
    w->cav[w->ncav++] = t0;
    ins_prefetch_nbrs(m->T, t0);
    for (size_t ci = 0; ci < w->ncav; ci++) {
        uint32_t c = w->cav[ci];
        for (int k = 0; k < 4; k++) {
            uint32_t o = m->T[8 * (size_t)c + 4 + k] >> 2;
            int mk, r = lock_live(w, o, &mk);
            if (r == 0) {
                err = BUSY;
                goto abort;
            }
            if (mk == MARK_IN)
                continue;
            if (mk == MARK_NONE) {
                /* Room on both lists first, so o is on one before
                 * anything else can fail; until then a failure lets go
                 * of o here if it was taken now (else it is on under). */
                if ((w->ncav == w->cavcap &&
                     (err = ins_grow_u32(&w->cav, &w->cavcap, w->ncav + 1)) != FDT_OK) ||
                    (w->nout == w->outcap &&
                     (err = ins_grow_u32(&w->outl, &w->outcap, w->nout + 1)) != FDT_OK)) {
                    if (r == TAKEN)
                        unlock_slot(sh, o);
                    goto abort;
                }
                int cf = conflict(w, o, p);
                if (cf < 0) {
                    if (r == TAKEN)
                        unlock_slot(sh, o);
                    err = cf == -BUSY ? BUSY : cf;
                    goto abort;
                }
                if (cf) {
                    set_mark(w, o, MARK_IN);
                    w->cav[w->ncav++] = o;
                    /* its neighbours are tested next: ask for them now */
                    const uint32_t *on = m->T + 8 * (size_t)o + 4;
                    for (int j = 0; j < 4; j++) {
                        fdt_prefetch(m->T + 8 * (size_t)(on[j] >> 2));
                        fdt_prefetch(&sh->lock[on[j] >> 2]);
                    }
                    continue;
                }
                set_mark(w, o, MARK_OUT);
                w->outl[w->nout++] = o;
            }
            if (w->nbnd == w->bndcap &&
                (err = ins_grow_u32(&w->bnd, &w->bndcap, w->nbnd + 1)) != FDT_OK)
                goto abort;
            w->bnd[w->nbnd++] = PACK(c, k);
        }
    }
    /* Everything read is held: from here on the insertion cannot fail
     * for another thread's sake, only for want of slots or memory, or
     * when the star would not be a triangulation (ins_star_ok: nothing
     * is written then). */
    if (!ins_star_ok(m, w->bnd, w->nbnd, p, &w->cnt, unsure0)) {
        err = FDT_EINTERNAL;
        goto abort;
    }
    if ((err = reserve(w, w->nbnd)) != FDT_OK ||
        (err = ins_grow_u32(&w->newt, &w->newcap, w->nbnd)) != FDT_OK)
        goto abort;

    /* The new tets (ins_make_star), as in src/mesh/insert.c. */
    for (size_t i = 0; i < w->nbnd; i++)
        w->newt[i] = alloc_slot(w);
    if ((err = ins_make_star(&w->local, &w->edges, m->T, w->bnd, w->nbnd, pid, w->newt)) !=
        FDT_OK)
        return err; /* the build fails: what stays locked does not matter */
    for (size_t i = 0; i < w->ncav; i++)
        free_slot(w, w->cav[i]);
    ins_count_cavity(&w->st, w->ncav, w->nbnd);
    /* p outside the hull: its star's infinite tets, read while held, are
     * the next hull walk's starts */
    w->hull.outside = outside;
    w->nhull_start = 0;
    for (size_t i = 0; outside && i < w->nbnd && w->nhull_start < HULL_STARTS; i++) {
        const uint32_t *nv = m->T + 8 * (size_t)w->newt[i];
        if (ins_is_infinite(nv)) {
            w->hull_slot[w->nhull_start] = w->newt[i];
            memcpy(w->hull_ids[w->nhull_start++], nv, 4 * sizeof *nv);
        }
    }
    /* Release: every write above happens before the next holder's
     * acquire. The coplanar rule's tets first: a freed cavity slot is
     * told from them by its tet (unlock_under). */
    unlock_under(w);
    unlock_list(sh, w->outl, w->nout);
    unlock_list(sh, w->newt, w->nbnd);
    uint32_t s = w->newt[w->nbnd - 1];
    w->last = s;
    w->recent[w->nrecent++ % RECENT] = s;
    /* Relaxed: a hint only, validated by locking (see locate). */
    atomic_store_explicit(&sh->hint[pid - m->base], s, memory_order_relaxed);
    return FDT_OK;
abort:
    abort_insertion(w);
    return err;
}

/* ------------------------------------------------------------------ */
/* Workers. */

static int defer(worker *w, uint32_t pid)
{
    w->st.deferred++;
    if (w->ndef == w->defcap && ins_grow_u32(&w->def, &w->defcap, w->ndef + 1) != FDT_OK)
        return FDT_ENOMEM;
    w->def[w->ndef++] = pid;
    return FDT_OK;
}

/* Records the first error and stops every worker. Relaxed: the caller
 * reads err after joining the threads (the join orders it). */
static void fail_all(shared *sh, int err)
{
    int zero = 0;
    atomic_compare_exchange_strong_explicit(&sh->err, &zero, err, memory_order_relaxed,
                                            memory_order_relaxed);
    atomic_store_explicit(&sh->stop, 1, memory_order_relaxed);
}

/* One pass over the deferred points: those that fail again stay. */
static int retry_deferred(worker *w, size_t *done)
{
    size_t keep = 0;
    *done = 0;
    for (size_t i = 0; i < w->ndef; i++) {
        uint32_t pid = w->def[i];
        if (atomic_load_explicit(&w->sh->stop, memory_order_relaxed)) {
            w->def[keep++] = pid;
            continue;
        }
        int r = insert_point(w, pid);
        if (r == BUSY || r == FULL) {
            w->st.deferred++;
            w->def[keep++] = pid;
            if (r == FULL)
                atomic_store_explicit(&w->sh->stop, 1, memory_order_relaxed);
        } else if (r != FDT_OK) {
            w->ndef = keep; /* the rest does not matter: the build fails */
            return r;
        } else {
            (*done)++;
        }
    }
    w->ndef = keep;
    return FDT_OK;
}

/*
 * Phase 2's points of w's region, by round in BRIO order (ids ascending
 * within a round), from the shared order: each worker picks its own, at
 * the same time (one pass over the order each, two compares a point; on
 * the calling thread the split took 2 ms at 440k points, a division a
 * point, bench/NOTES.md entry 76).
 */
static void pick_points(worker *w)
{
    const shared *sh = w->sh;
    size_t k = 0;
    for (int r = sh->r0; r < sh->nrounds; r++) {
        for (uint32_t j = sh->round_end[r - 1]; j < sh->round_end[r]; j++) {
            uint32_t id = sh->order[j];
            if (id - w->own_lo < w->own_span && id != sh->first[0] && id != sh->first[1] &&
                id != sh->first[2] && id != sh->first[3])
                w->mine[k++] = id;
        }
        w->round_end[r - sh->r0] = k;
    }
    w->pts = w->mine;
    w->npts = k;
    w->picked = 1;
    w->nrounds = sh->nrounds - sh->r0;
}

/* Inserts pts[a .. b) in order, deferring what meets another worker's
 * tets; once the workers are stopped (slots spent, an error) the rest is
 * deferred to phase 3 unread. */
static int insert_range(worker *w, const uint32_t *pts, size_t a, size_t b)
{
    for (size_t j = a; j < b; j++) {
        /* Relaxed: a flag polled to stop early; what it reports is read
         * after the join. */
        if (atomic_load_explicit(&w->sh->stop, memory_order_relaxed)) {
            for (; j < b; j++)
                if (defer(w, pts[j]) != FDT_OK)
                    return FDT_ENOMEM;
            return FDT_OK;
        }
        int rc = insert_point(w, pts[j]);
        if (rc == FULL) /* stop everyone; phase 3 grows the arrays */
            atomic_store_explicit(&w->sh->stop, 1, memory_order_relaxed);
        if (rc == BUSY || rc == FULL)
            rc = defer(w, pts[j]);
        if (rc != FDT_OK)
            return rc;
    }
    return FDT_OK;
}

/* The owner's next CLAIM points of its last round (span, above): 0 when
 * none is left. Relaxed: the owner wrote its own list; the thieves' CAS
 * only moves back. */
static int claim_own(worker *w, size_t *a, size_t *b)
{
    _Atomic uint64_t *fb = &w->sh->spans[w->me - 1].fb;
    uint64_t cur = atomic_load_explicit(fb, memory_order_relaxed);
    for (;;) {
        uint32_t f = (uint32_t)(cur >> 32), k = (uint32_t)cur;
        if (f >= k)
            return 0;
        uint32_t nf = k - f > CLAIM ? f + CLAIM : k;
        if (atomic_compare_exchange_weak_explicit(fb, &cur, (uint64_t)nf << 32 | k,
                                                  memory_order_relaxed, memory_order_relaxed)) {
            *a = f;
            *b = nf;
            return 1;
        }
    }
}

/* CLAIM points from the back of the fullest other last round with more
 * than CLAIM left (the owner keeps its last few): *v's pts[*a .. *b).
 * Acquire, on the load and the exchange: pairs with the owner's release
 * store that published the range (worker_main), so its list, written
 * before, is read here; the owner's claims are read-modify-writes and
 * continue that release sequence. */
static int steal(worker *w, worker **v, size_t *a, size_t *b)
{
    shared *sh = w->sh;
    while (!atomic_load_explicit(&sh->stop, memory_order_relaxed)) {
        int best = -1;
        uint32_t most = CLAIM;
        uint64_t bcur = 0;
        for (int i = 0; i < sh->nw; i++) {
            if (i == w->me - 1)
                continue;
            uint64_t cur = atomic_load_explicit(&sh->spans[i].fb, memory_order_acquire);
            uint32_t f = (uint32_t)(cur >> 32), k = (uint32_t)cur;
            if (k > f && k - f > most) {
                most = k - f;
                best = i;
                bcur = cur;
            }
        }
        if (best < 0)
            return 0;
        uint32_t f = (uint32_t)(bcur >> 32), k = (uint32_t)bcur;
        if (atomic_compare_exchange_strong_explicit(&sh->spans[best].fb, &bcur,
                                                    (uint64_t)f << 32 | (k - CLAIM),
                                                    memory_order_acquire, memory_order_relaxed)) {
            *v = &sh->all[best];
            *a = k - CLAIM;
            *b = k;
            return 1;
        }
    }
    return 0;
}

static void *worker_main(void *arg)
{
    worker *w = arg;
    shared *sh = w->sh;
    double c0 = fdt_thread_cpu_s();
    if (!w->picked)
        pick_points(w);
    size_t i = 0, done, a, b;
    int err = FDT_OK;
    for (int r = 0; r + 1 < w->nrounds && !err; r++) {
        err = insert_range(w, w->pts, i, w->round_end[r]);
        i = w->round_end[r];
        if (!err)
            err = retry_deferred(w, &done);
    }
    /* release: publishes the list to thieves (steal). Only now: a
     * thief's points inserted before the owner's earlier rounds there
     * would break the BRIO order (larger cavities, longer walks). */
    atomic_store_explicit(&sh->spans[w->me - 1].fb, (uint64_t)i << 32 | w->npts,
                          memory_order_release);
    while (!err && claim_own(w, &a, &b))
        err = insert_range(w, w->pts, a, b);
    if (!err)
        err = retry_deferred(w, &done);
    worker *v;
    while (!err && steal(w, &v, &a, &b)) {
        w->st.stolen += b - a;
        err = insert_range(w, v->pts, a, b);
    }
    /* The last deferred points, while others still work: back off when a
     * pass makes no progress; phase 3 takes what is left. */
    for (int idle = 0; !err && w->ndef && idle < 8;) {
        err = retry_deferred(w, &done);
        if (done == 0) {
            idle++;
            sched_yield();
        }
        if (atomic_load_explicit(&sh->stop, memory_order_relaxed))
            break;
    }
    if (err)
        fail_all(sh, err);
    w->cpu_s += fdt_thread_cpu_s() - c0;
    return NULL;
}

/* ------------------------------------------------------------------ */

static void worker_free(worker *w)
{
    free(w->outl);
    free(w->under);
    free(w->newt);
    free(w->cav);
    free(w->bnd);
    free(w->edges.eh);
    free(w->local.lid);
    free(w->def);
    free(w->todo);
    free(w->mine);
}

static int worker_init(worker *w, shared *sh, int id, int nw, uint32_t base, uint32_t n,
                       size_t *round_end)
{
    memset(w, 0, sizeof *w);
    w->sh = sh;
    w->me = (unsigned char)(id + 1);
    /* Its region: the ids i with (i - base) * nw / n == id. */
    uint64_t lo = ((uint64_t)id * n + (uint64_t)nw - 1) / (uint64_t)nw;
    uint64_t hi = ((uint64_t)(id + 1) * n + (uint64_t)nw - 1) / (uint64_t)nw;
    w->own_lo = base + (uint32_t)lo;
    w->own_span = (uint32_t)(hi - lo);
    w->round_end = round_end;
    if (!(w->mine = malloc(((size_t)w->own_span + 1) * sizeof *w->mine)))
        return FDT_ENOMEM;
    w->free_head = FDT_NONE;
    w->rng = UINT64_C(0x853c49e6748fea9b) ^ ((uint64_t)id * UINT64_C(0x9E3779B97F4A7C15));
    /* A byte a point for the star links' local numbers: calloc's pages are
     * touched only where this worker's stars lie. */
    w->local.base = base;
    w->local.n = n;
    if (!(w->local.lid = calloc((size_t)n + 1, 1)) ||
        ins_grow_u32(&w->outl, &w->outcap, 256) != FDT_OK ||
        ins_grow_u32(&w->newt, &w->newcap, 256) != FDT_OK ||
        ins_grow_u32(&w->cav, &w->cavcap, 64) != FDT_OK ||
        ins_grow_u32(&w->bnd, &w->bndcap, 256) != FDT_OK)
        return FDT_ENOMEM;
    return FDT_OK;
}

int fdt_ins_build_parallel(fdt_ins *m, const double *P, uint32_t base, uint32_t n, int nthreads,
                           fdt_pred_counts *cnt)
{
    return fdt_ins_build_parallel_slots(m, P, base, n, nthreads, 0.0, cnt);
}

/* ---- the build's steps (fdt_ins_build_parallel_slots) --------------------- */

/*
 * After phase 1 (prefix points in): the tets array grown for the workers
 * to the slots a point the serial rounds used, with a third more (later
 * rounds are denser; the chunks): a family with more tets a point than
 * uniform points' 6.5 (a pipe scan: 13) then rarely stops the workers for
 * more. Not when the tests force the capacity (slots_a_point > 0).
 */
static int grow_for_workers(fdt_ins *m, uint32_t prefix, uint32_t n, int nw,
                            double slots_a_point)
{
    uint32_t nfree = 0;
    for (uint32_t t = m->free_head; t != FDT_NONE; t = m->T[8 * (size_t)t + 4])
        nfree++;
    uint64_t want = ins_slots_wanted(m, prefix, nfree, n, (uint64_t)nw * 2 * chunk_of(n) + 1024);
    if (want > m->cap && slots_a_point <= 0.0) {
        /* Only the slots in use copied (ins_move_tets), not the whole
         * capacity: the prefix used ~2.5 % of it (statue 100k: 19,921 of
         * 762,224 slots), and the workers fault in the pages they use,
         * both at once (bench/NOTES.md entry 56), on huge pages (without
         * them a fault a 4 KB page first written, entry 69). Every slot
         * the prefix used, its free list included, is below nslots. */
        int err = ins_move_tets(m, want, m->nslots);
        if (err)
            return err;
        m->cap = (uint32_t)want;
    }
    return FDT_OK;
}

/* The shared state of phase 2 (locks, hints, spans) and the nw workers
 * ws, rend their rounds' ends (32 a worker). */
static int shared_init(shared *sh, worker *ws, int nw, uint32_t base, uint32_t n, size_t *rend)
{
    fdt_ins *m = sh->m;
    /* All bytes zero: every lock free (an atomic_uchar's 0 is all zero
     * bits). calloc leaves the zeroing to the pages' first touch, in the
     * workers, where atomic_init a byte took 2.9 ms at 440k points on
     * this thread (bench/NOTES.md entry 76). */
    sh->chunk = chunk_of(n);
    sh->lock = calloc((size_t)m->cap, sizeof *sh->lock);
    sh->hint = malloc((size_t)n * sizeof *sh->hint);
    sh->spans = aligned_alloc(alignof(span), (size_t)nw * sizeof *sh->spans);
    if (!sh->lock || !sh->hint || !sh->spans)
        return FDT_ENOMEM;
    sh->all = ws;
    sh->nw = nw;
    for (uint32_t i = 0; i < n; i++)
        atomic_init(&sh->hint[i], FDT_NONE);
    atomic_init(&sh->next, m->nslots);
    atomic_init(&sh->stop, 0);
    atomic_init(&sh->err, 0);
    for (int i = 0; i < nw; i++) {
        int err = worker_init(&ws[i], sh, i, nw, base, n, rend + 32 * (size_t)i);
        if (err != FDT_OK)
            return err;
    }
    return FDT_OK;
}

/* Starts: the hints of the points in, and each worker's first walk from a
 * tet of a point of its own region; phase 1's free list becomes worker
 * 0's. */
static void hand_out_starts(shared *sh, worker *ws, int nw, uint32_t base, uint32_t n)
{
    fdt_ins *m = sh->m;
    for (int i = 0; i < nw; i++)
        ws[i].last = FDT_NONE;
    uint32_t anylive = FDT_NONE;
    for (uint32_t t = 0; t < m->nslots; t++) {
        const uint32_t *v = m->T + 8 * (size_t)t;
        if (v[0] == INF && v[1] == INF) {
            /* phase 1's free list becomes worker 0's, locked by it */
            atomic_init(&sh->lock[t], ws[0].me);
            continue;
        }
        anylive = t;
        for (int k = 0; k < 4; k++) {
            if (v[k] == INF)
                continue;
            uint32_t i = v[k] - base;
            atomic_init(&sh->hint[i], t);
            int reg = (int)((uint64_t)i * (uint64_t)nw / n);
            if (ws[reg].last == FDT_NONE)
                ws[reg].last = t;
        }
    }
    ws[0].free_head = m->free_head;
    for (uint32_t t = m->free_head; t != FDT_NONE; t = m->T[8 * (size_t)t + 4])
        ws[0].nfree++;
    m->free_head = FDT_NONE;
    for (int i = 0; i < nw; i++)
        if (ws[i].last == FDT_NONE)
            ws[i].last = anylive;
}

/* Phase 2. pthread_create orders everything before it before the
 * workers; a worker that cannot start leaves its points to phase 3.
 * When the slots run out, the workers stop, the arrays grow here (no
 * thread runs) and the workers go on with what they left. */
static int phase2(shared *sh, worker *ws, int nw, size_t *rend)
{
    fdt_ins *m = sh->m;
    int err;
    for (int pass = 0;; pass++) {
        /* Every last round empty until its owner publishes it: a worker
         * that does not start is never stolen from. */
        for (int i = 0; i < nw; i++)
            atomic_init(&sh->spans[i].fb, 0);
        for (int i = 1; i < nw; i++)
            ws[i].started = fdt_spawn(&ws[i].th, 0, worker_main, &ws[i]) == 0;
        worker_main(&ws[0]);
        for (int i = 1; i < nw; i++)
            if (ws[i].started)
                pthread_join(ws[i].th, NULL);
        /* The joins order the workers' writes before what follows. A
         * worker that did not start leaves its points to phase 3. */
        for (int i = 1; i < nw; i++)
            if (!ws[i].picked)
                pick_points(&ws[i]);
        if ((err = atomic_load_explicit(&sh->err, memory_order_relaxed)) != 0)
            return err;
        uint64_t next = atomic_load_explicit(&sh->next, memory_order_relaxed);
        int started = 1;
        for (int i = 1; i < nw; i++)
            started &= ws[i].started;
        if (next < m->cap || !started || pass >= 8)
            return FDT_OK; /* not stopped for slots (or give up: phase 3 grows) */
        /* Every slot below the capacity was handed out: go on above it. */
        atomic_store_explicit(&sh->next, m->cap, memory_order_relaxed);
        if ((err = grow_arrays(sh, (uint64_t)m->cap + m->cap / 2)) != FDT_OK)
            return err;
        atomic_store_explicit(&sh->stop, 0, memory_order_relaxed);
        for (int i = 0; i < nw; i++) { /* the deferred points are the new list */
            worker *w = &ws[i];
            uint32_t *t = w->todo;
            size_t c = w->todocap;
            w->todo = w->def;
            w->todocap = w->defcap;
            w->pts = w->todo;
            w->npts = w->ndef;
            w->def = t;
            w->defcap = c;
            w->ndef = 0;
            rend[32 * (size_t)i] = w->npts;
            w->nrounds = 1;
        }
    }
}

/* Phase 3 on this thread, as worker 0 (sh->single set): every freed or
 * unused slot becomes its own (locked by it), every other lock is free,
 * and it inserts every point left. */
static int phase3(shared *sh, worker *ws, int nw)
{
    fdt_ins *m = sh->m;
    worker *w0 = &ws[0];
    for (int i = 0; i < nw; i++) {
        worker *w = &ws[i];
        if (i > 0) {
            while (w->free_head != FDT_NONE) {
                uint32_t t = w->free_head;
                w->free_head = m->T[8 * (size_t)t + 4];
                atomic_store_explicit(&sh->lock[t], w0->me, memory_order_relaxed);
                free_slot(w0, t);
            }
        }
        for (; w->fresh < w->fresh_end; w->fresh++) {
            atomic_store_explicit(&sh->lock[w->fresh], w0->me, memory_order_relaxed);
            free_slot(w0, w->fresh);
        }
        if (!w->started && i > 0) {
            for (size_t j = 0; j < w->npts; j++)
                if (defer(w0, w->pts[j]) != FDT_OK)
                    return FDT_ENOMEM;
        } else if (i > 0) {
            for (size_t j = 0; j < w->ndef; j++)
                if (defer(w0, w->def[j]) != FDT_OK)
                    return FDT_ENOMEM;
        }
    }
    {
        /* The counter may have run past the capacity (a worker found it
         * spent): the slots handed out end at the capacity then. */
        uint64_t next = atomic_load_explicit(&sh->next, memory_order_relaxed);
        m->nslots = next < m->cap ? (uint32_t)next : m->cap;
        atomic_store_explicit(&sh->next, m->nslots, memory_order_relaxed);
    }
    m->stats.serial_finish = w0->ndef;
    for (size_t j = 0; j < w0->ndef; j++) {
        int rc = insert_point(w0, w0->def[j]);
        if (rc != FDT_OK) {
            /* nothing else holds a lock now, and the capacity grows */
            return rc == BUSY || rc == FULL ? FDT_EINTERNAL : rc;
        }
    }
    {
        uint64_t next = atomic_load_explicit(&sh->next, memory_order_relaxed);
        m->nslots = next < m->cap ? (uint32_t)next : m->cap;
    }
    /* A chunk's unused rest: freed slots, found by fdt_ins_finish. */
    for (; w0->fresh < w0->fresh_end; w0->fresh++) {
        uint32_t *v = m->T + 8 * (size_t)w0->fresh;
        v[0] = v[1] = INF;
    }
    return FDT_OK;
}

/* The workers' counters into m->stats and cnt (may be NULL). */
static void sum_worker_stats(fdt_ins *m, const worker *ws, int nw, fdt_pred_counts *cnt)
{
    for (int i = 0; i < nw; i++) {
        const fdt_ins_stats *s = &ws[i].st;
        m->stats.walk_steps += s->walk_steps;
        m->stats.cavity_tets += s->cavity_tets;
        m->stats.created_tets += s->created_tets;
        m->stats.conflict_tests += s->conflict_tests;
        m->stats.deferred += s->deferred;
        m->stats.stolen += s->stolen;
        m->stats.hull_walks += s->hull_walks;
        if (s->max_cavity > m->stats.max_cavity)
            m->stats.max_cavity = s->max_cavity;
        if (cnt)
            fdt_pred_counts_add(cnt, &ws[i].cnt);
    }
}

static int build_parallel(fdt_ins *m, const double *P, uint32_t base, uint32_t n, int nthreads,
                          double slots_a_point, const fdt_images *img, fdt_pred_counts *cnt)
{
    if (nthreads < 1)
        nthreads = 1;
    if (nthreads > MAX_WORKERS)
        nthreads = MAX_WORKERS;
    if (ins_begin(m, P, base, n) != FDT_OK)
        return FDT_EDEGENERATE;
    int nw = nthreads;
    uint32_t *order = malloc((size_t)n * sizeof *order);
    size_t *rend = malloc((size_t)nw * 32 * sizeof *rend);
    worker *ws = calloc((size_t)nw, sizeof *ws);
    shared sh;
    memset(&sh, 0, sizeof sh);
    sh.m = m;
    int err = FDT_ENOMEM;
    if (!order || !rend || !ws) {
        free(order);
        free(rend);
        free(ws);
        return FDT_ENOMEM;
    }
    uint32_t round_end[32], first[4];
    int nrounds;
    fdt_ins_brio(P, base, n, order, round_end, &nrounds);
    /* Phase 1: the first rounds up to n/128 points (at least one round). */
    int r0 = 1;
    while (r0 < nrounds && round_end[r0 - 1] < n / 128)
        r0++;
    uint32_t prefix = round_end[r0 - 1];
    uint64_t slots = slots_a_point > 0.0 ? (uint64_t)(slots_a_point * n) + 64
                                         : (uint64_t)n * 8 + (uint64_t)nw * 2 * chunk_of(n) + 1024;
    double c0 = fdt_thread_cpu_s();
    err = fdt_ins_build_prefix(m, P, base, n, order, prefix, slots, first, img, cnt, NULL, NULL);
    if (err)
        goto out;
    double c1 = fdt_thread_cpu_s();
    if ((err = grow_for_workers(m, prefix, n, nw, slots_a_point)) != FDT_OK ||
        (err = shared_init(&sh, ws, nw, base, n, rend)) != FDT_OK)
        goto fail;
    hand_out_starts(&sh, ws, nw, base, n);
    /* Phase 2's points: each worker picks its region's (pick_points). */
    sh.order = order;
    sh.round_end = round_end;
    sh.r0 = r0;
    sh.nrounds = nrounds;
    memcpy(sh.first, first, sizeof sh.first);
    if ((err = phase2(&sh, ws, nw, rend)) != FDT_OK)
        goto fail;
    double c2 = fdt_thread_cpu_s();
    sh.single = 1;
    if ((err = phase3(&sh, ws, nw)) != FDT_OK)
        goto fail;
    sum_worker_stats(m, ws, nw, cnt);
    err = fdt_ins_finish(m);
    if (err == FDT_OK) {
        m->stats.cpu_start_s = c1 - c0;
        m->stats.cpu_finish_s = fdt_thread_cpu_s() - c2;
        for (int i = 0; i < nw; i++) {
            m->stats.cpu_workers_sum_s += ws[i].cpu_s;
            if (ws[i].cpu_s > m->stats.cpu_workers_max_s)
                m->stats.cpu_workers_max_s = ws[i].cpu_s;
        }
    }
    goto out;
fail:
    fdt_ins_free(m);
out:
    for (int i = 0; i < nw; i++)
        worker_free(&ws[i]);
    free(sh.lock);
    free(sh.hint);
    free(sh.spans);
    free(order);
    free(rend);
    free(ws);
    return err;
}

int fdt_ins_build_parallel_slots(fdt_ins *m, const double *P, uint32_t base, uint32_t n,
                                 int nthreads, double slots_a_point, fdt_pred_counts *cnt)
{
    return build_parallel(m, P, base, n, nthreads, slots_a_point, NULL, cnt);
}

int fdt_ins_build_images(fdt_ins *m, const fdt_images *img, int nthreads, fdt_pred_counts *cnt)
{
    /* one thread: the serial kernel, as the plain engine's (src/front/
     * partmesh.c), not the workers' with their locks and hints (bench/
     * NOTES.md entry 113) */
    if (nthreads <= 1)
        return fdt_ins_build_serial(m, img->P, 0, img->n, img, cnt, NULL, NULL);
    return build_parallel(m, img->P, 0, img->n, nthreads, 0.0, img, cnt);
}
