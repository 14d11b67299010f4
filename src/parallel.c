/*
 * The parallel engine; see parallel.h.
 *
 * Setup (the calling thread): recursive coordinate bisection into N parts
 * and one kd-tree per part (src/partition.c), one seed tet per part near
 * its centre (src/seed.c over a tree of all points), each seed delivered
 * to its owner. Then one thread per part, and at the end a gather of the
 * threads' tets into one mesh in input numbering, each thread copying its
 * own share (gather_prepare, gather_copy, gather_finish).
 *
 * Ownership (§3.2). The owner of a face or tet is the part holding its
 * lowest global id. A thread advances only faces it owns and builds only
 * tets it owns. Two consequences shape the messages:
 *  - A tet's three faces through its lowest vertex have that vertex as
 *    their lowest too, so they belong to the tet's owner: building a tet
 *    sends at most ONE face away, the one opposite its lowest vertex.
 *  - When the apex p found for a face f makes a tet t = f + p owned by
 *    someone else, p is the lowest id of t (f's lowest is ours), and the
 *    only face of t we own is f itself. We send FACESEND(f, p) to t's
 *    owner, who builds t unless it exists. t can exist only if its owner
 *    built it from one of its own three faces, and it then sent us f
 *    (completing it here). So a duplicate request is possible only for a
 *    tet with a face owned elsewhere (a "boundary" tet), and only those go
 *    into the per-thread set `built` that tells "already built" from "never
 *    seen" (a face table cannot: a completed face has left it).
 *
 * Termination (§4 IAMDONE, §5 "left-over faces"). One atomic counter
 * e->work counts outstanding units: one per thread that holds local work
 * (a nonempty face table, or seeds to build: the thread is "active"), one
 * per FACESEND in flight. We count active threads rather than front faces
 * so the shared counter is touched per message and per activation, not per
 * face (counting front faces would put ~6 atomic RMWs per tet on one cache
 * line shared by every thread). Rules:
 *  (R1) A unit is added BEFORE the work it stands for becomes visible: the
 *       sender adds a FACESEND's unit before posting it; a thread adds its
 *       activity unit before inserting into an empty face table.
 *  (R2) A unit is removed only AFTER its effects are counted: a FACESEND's
 *       unit after the receiver handled it (the tet built, faces inserted
 *       under its activity unit, faces sent under their own units); an
 *       activity unit when the thread's face table is empty and its queue
 *       is exhausted.
 *  (R3) Every add is made by a thread that holds a unit it has not yet
 *       removed (its activity unit, or the unit of the FACESEND it is
 *       handling), so the counter is >= 1 before every add.
 * Hence once the counter is 0 it stays 0 (R3), and at that moment no face
 * table holds a face and no FACESEND is in flight (R1, R2): every face ever
 * created was completed by its second tet or found to be on the hull. The
 * thread whose decrement brings it to 0 sends IAMDONE to all others; every
 * thread exits on IAMDONE (or on abort). No face is lost after IAMDONE:
 * there is none left anywhere, and none can appear (R3). A thread whose
 * table empties early and later receives a face is simply active again
 * (R1), unlike §5 where it had to wait for a synchronisation.
 *
 * No untriangulated pocket remains (§5, figure 2). The paper's pockets came
 * from leaving a placeholder (NN = -1000000 Np) when the apex made a tet
 * owned by another processor, trusting that processor to build it from one
 * of its own faces; a region whose tets all belong to one processor but
 * whose bounding faces all belong to others was then never built. Here no
 * face waits on anybody else's initiative: every front face sits on its
 * owner's queue (pushed when it entered the table) until the owner takes it
 * and either finds it on the hull, builds its tet, or sends the tet to the
 * tet's owner, who builds it (or built it already) and thereby sends the
 * face back completed. So when the counter is 0 every face of every built
 * tet is completed (the tet across it is built) or a hull face. Every
 * built tet is Delaunay (exact apex search), and the perturbed Delaunay
 * tetrahedralization is unique with a connected dual graph. If some of its
 * tets were not built, a path in that graph from a seed to one of them
 * would cross a face g from a built tet to an unbuilt one u; g cannot be
 * completed (the tet across g would be u) nor on the hull (u's fourth
 * vertex lies on g's open side). So no pocket remains. tests/test_parallel.c
 * checks this with 16 and 64 threads on inputs of a few dozen points,
 * where nearly every tet straddles parts.
 *
 * Modes (§4). Shared: the apex search walks the own tree, then every other
 * part's tree whose box may hold a better apex (via the bisection tree, so
 * whole groups of parts are skipped at once, nearest first). Message: the
 * same walk, but for another part it sends NODESEND (face coordinates, best
 * so far) to that part's thread and waits for NODERECV, answering the
 * NODESENDs in its own mailbox meanwhile (so waiting threads cannot
 * deadlock, §4) and deferring FACESENDs until the face is done. Message-mode
 * threads read only their own part's coordinates: a FACESEND carries the
 * coordinates of every id but the lowest (which the receiver owns), and
 * each thread caches the foreign coordinates it has been sent ("ghosts").
 *
 * Neighbours. When a face completes, its owner knows both tets (thread,
 * local tet, face index). Both local: it links them at once. Otherwise it
 * appends the pair to its link list, and the gather, which renumbers the
 * threads' tets into one array anyway, applies the list. This replaces a
 * FACERECV reply carrying the tet id when a face completes (one to two
 * messages per boundary face, and writes into another thread's arrays) by
 * nothing at all; our
 * termination protocol needs no acknowledgement either, and the mailboxes
 * are FIFO per sender, so FACERECV, "returned for synchronization only" in
 * §4, is never sent (its counters stay 0, checked like the others).
 *
 * Errors. A thread that fails records the first error in an atomic, raises
 * the abort flag and kicks every mailbox; every loop and every wait polls
 * the flag, so all threads exit, the caller joins them and returns the
 * error. The progress callback runs on the calling thread, which cancels
 * the same way.
 */
#include "parallel.h"

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#ifdef FDT_HAVE_HWLOC
#include <hwloc.h>
#endif

#include "faceq.h"
#include "facetab.h"
#include "kdtree.h"
#include "mailbox.h"
#include "oracle.h"
#include "partition.h"
#include "seed.h"

/* A worker's result for the main loop: keep going, or the run is over. */
enum { RUN_ON = 0, RUN_DONE = 1 };

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- FACESEND payload ------------------------------------------------- */

/*
 * The mailbox's fdt_msg_facesend (v, apex, tet), followed, in message mode,
 * by the coordinates of the message's ids other than the lowest, in the
 * order v[0], v[1], v[2], apex with the lowest skipped: the receiver owns
 * the lowest (the face's lowest for a face, the tet's lowest for a tet
 * request) and reads it from its own part. The whole payload lives in the
 * message's union (112 bytes) and is moved with memcpy.
 */
typedef struct face_payload {
    fdt_msg_facesend f;
    double xyz[3][3];
} face_payload;

_Static_assert(sizeof(face_payload) <= sizeof(((fdt_msg *)0)->u),
               "a FACESEND with coordinates fits in one message");

/* An unpacked FACESEND, also the element of the deferred queue. */
typedef struct pface {
    face_payload p;
    int sender;
} pface;

/* ---- small per-thread containers --------------------------------------- */

/* Set of boundary tets, keyed on their sorted ids; open addressing, linear
 * probing, no deletion. k[0] == UINT32_MAX marks an empty slot. */
typedef struct tetset {
    uint32_t (*k)[4];
    size_t cap, count;
} tetset;

static size_t key_hash(const uint32_t k[4])
{
    uint64_t h = (uint64_t)k[0] * 0x9E3779B97F4A7C15ull;
    h ^= (uint64_t)k[1] * 0xC2B2AE3D27D4EB4Full + (h >> 29);
    h ^= (uint64_t)k[2] * 0x165667B19E3779F9ull + (h >> 31);
    h ^= (uint64_t)k[3] * 0xD6E8FEB86659FD93ull + (h >> 27);
    h ^= h >> 32;
    h *= 0x94D049BB133111EBull;
    return (size_t)(h ^ (h >> 29));
}

static int tetset_grow(tetset *s)
{
    size_t ncap = s->cap ? s->cap * 2 : 1024;
    uint32_t(*nk)[4] = malloc(ncap * sizeof *nk);
    if (!nk)
        return FDT_ENOMEM;
    for (size_t i = 0; i < ncap; i++)
        nk[i][0] = UINT32_MAX;
    for (size_t i = 0; i < s->cap; i++) {
        if (s->k[i][0] == UINT32_MAX)
            continue;
        size_t h = key_hash(s->k[i]) & (ncap - 1);
        while (nk[h][0] != UINT32_MAX)
            h = (h + 1) & (ncap - 1);
        memcpy(nk[h], s->k[i], sizeof nk[h]);
    }
    free(s->k);
    s->k = nk;
    s->cap = ncap;
    return FDT_OK;
}

/* Inserts k: 1 if it was new, 0 if present, FDT_ENOMEM. */
static int tetset_insert(tetset *s, const uint32_t k[4])
{
    if (2 * (s->count + 1) > s->cap) {
        int err = tetset_grow(s);
        if (err)
            return err;
    }
    size_t mask = s->cap - 1, h = key_hash(k) & mask;
    for (;;) {
        uint32_t *e = s->k[h];
        if (e[0] == UINT32_MAX) {
            memcpy(e, k, 4 * sizeof *k);
            s->count++;
            return 1;
        }
        if (e[0] == k[0] && e[1] == k[1] && e[2] == k[2] && e[3] == k[3])
            return 0;
        h = (h + 1) & mask;
    }
}

/* Coordinates of foreign points a message-mode thread has been sent. */
typedef struct ghost {
    uint32_t id;       /* UINT32_MAX: empty */
    double x[3];
} ghost;

typedef struct ghostmap {
    ghost *g;
    size_t cap, count;
} ghostmap;

static size_t id_hash(uint32_t id)
{
    uint64_t h = (uint64_t)id * 0x9E3779B97F4A7C15ull;
    return (size_t)(h ^ (h >> 31));
}

static const double *ghost_find(const ghostmap *gm, uint32_t id)
{
    if (!gm->cap)
        return NULL;
    size_t mask = gm->cap - 1, h = id_hash(id) & mask;
    for (;;) {
        const ghost *e = &gm->g[h];
        if (e->id == id)
            return e->x;
        if (e->id == UINT32_MAX)
            return NULL;
        h = (h + 1) & mask;
    }
}

static int ghost_put(ghostmap *gm, uint32_t id, const double *x)
{
    if (2 * (gm->count + 1) > gm->cap) {
        size_t ncap = gm->cap ? gm->cap * 2 : 1024;
        ghost *ng = malloc(ncap * sizeof *ng);
        if (!ng)
            return FDT_ENOMEM;
        for (size_t i = 0; i < ncap; i++)
            ng[i].id = UINT32_MAX;
        for (size_t i = 0; i < gm->cap; i++) {
            if (gm->g[i].id == UINT32_MAX)
                continue;
            size_t h = id_hash(gm->g[i].id) & (ncap - 1);
            while (ng[h].id != UINT32_MAX)
                h = (h + 1) & (ncap - 1);
            ng[h] = gm->g[i];
        }
        free(gm->g);
        gm->g = ng;
        gm->cap = ncap;
    }
    size_t mask = gm->cap - 1, h = id_hash(id) & mask;
    for (;;) {
        ghost *e = &gm->g[h];
        if (e->id == id)
            return FDT_OK; /* coordinates never change */
        if (e->id == UINT32_MAX) {
            e->id = id;
            memcpy(e->x, x, sizeof e->x);
            gm->count++;
            return FDT_OK;
        }
        h = (h + 1) & mask;
    }
}

/* A completed face whose two tets are not both the owner's: applied by the
 * gather. la, lb are (local tet << 2) | face index in threads ta, tb. */
typedef struct linkrec {
    int32_t ta, tb;
    int64_t la, lb;
} linkrec;

typedef struct linklist {
    linkrec *r;
    size_t n, cap;
} linklist;

static int link_add(linklist *l, int ta, int64_t la, int tb, int64_t lb)
{
    if (l->n == l->cap) {
        size_t ncap = l->cap ? l->cap * 2 : 1024;
        linkrec *nr = realloc(l->r, ncap * sizeof *nr);
        if (!nr)
            return FDT_ENOMEM;
        l->r = nr;
        l->cap = ncap;
    }
    l->r[l->n++] = (linkrec){ta, tb, la, lb};
    return FDT_OK;
}

/* FIFO of FACESENDs that arrived while a message-mode search waited. */
typedef struct pfqueue {
    pface *q;
    size_t head, n, cap;
} pfqueue;

static int pfq_push(pfqueue *q, const pface *f)
{
    if (q->head + q->n == q->cap) {
        if (q->head > 0) {
            memmove(q->q, q->q + q->head, q->n * sizeof *q->q);
            q->head = 0;
        }
        if (q->n == q->cap) {
            size_t ncap = q->cap ? q->cap * 2 : 64;
            pface *nq = realloc(q->q, ncap * sizeof *nq);
            if (!nq)
                return FDT_ENOMEM;
            q->q = nq;
            q->cap = ncap;
        }
    }
    q->q[q->head + q->n++] = *f;
    return FDT_OK;
}

/* ---- the engine and its workers ----------------------------------------- */

struct engine;

typedef struct worker {
    /* Tets built so far, for the calling thread's progress estimate only:
     * written (relaxed) by the owner every few thousand tets, read
     * (relaxed) by the calling thread; an estimate needs no ordering. On
     * its own cache line so those reads do not disturb the owner. */
    alignas(64) atomic_size_t tets_done;
    alignas(64) struct engine *e;
    int id;
    fdt_mailbox *mbox;
    const fdt_kdtree *tree;    /* own part (n == 0: empty part) */
    uint32_t lo, hi;           /* own ids [lo, hi) */
    fdt_facetab ft;            /* own front faces */
    fdt_faceq fq;              /* own faces still to advance (may be stale) */
    fdt_meshbuf out;           /* own tets, global ids; nbrs local ids */
    tetset built;              /* own boundary tets (duplicate requests) */
    ghostmap ghosts;           /* message mode: foreign coordinates */
    linklist links;            /* completed faces between two threads */
    pfqueue deferred;          /* message mode: FACESENDs for later */
    uint32_t (*seeds)[4];      /* seed tets to build first (borrowed) */
    int nseeds;
    int active;                /* holds an activity unit of e->work */
    uint32_t qid;              /* last range query id */
    fdt_kdq kq;
    fdt_oracle orc;            /* kd search or the part's insertion mesh */
    /* 1 once orc's mesh is built, stored with release by this thread after
     * fdt_ins_build wrote the mesh, which is not written again before
     * worker_free (after every thread is joined). Another thread that loads
     * 1 with acquire sees the whole mesh and may read it with no lock
     * (shared mode, search_others). */
    atomic_int mesh_pub;
    int published;             /* mesh_pub stored (this thread's copy) */
    fdt_ins_query iq;          /* scratch of the queries of other meshes */
    uint32_t *qhint;           /* per part: where the last walk ended */
    uint32_t qcache_v;         /* iq answers for this vertex in this part */
    int qcache_part;
    int qcache_big;            /* that region was too large: no answer */
    fdt_thread_stats st;
    size_t report_at;
    pthread_t th;
} worker;

typedef struct engine {
    /* Outstanding units (see the top of this file). Adds are relaxed:
     * each unit's add happens-before its removal (the same thread, or
     * sequenced before a post whose release CAS the receiver's poll
     * acquires), and C11 coherence orders a modification that
     * happens-before another first in the variable's modification order;
     * that is all the counting argument needs. Removals are acq_rel, so the
     * thread that reads the final 1 -> 0 has synchronized with every
     * earlier removal (one release sequence of RMWs): everything any thread
     * did before giving up its units happens-before the IAMDONEs. */
    alignas(64) atomic_llong work;
    /* First error (0: none): a strong CAS from 0, acq_rel, decides the one
     * thread that records err_thread and err_what (plain fields read by the
     * caller after pthread_join, which orders them). */
    alignas(64) atomic_int error;
    /* Abort flag: stored (release) after `error`, then every mailbox is
     * kicked (seq_cst store in fdt_mailbox_kick, consumed by an acquire
     * exchange), so a thread woken by the kick sees the flag. Loops load
     * it with acquire; a stale 0 only delays the exit by one iteration. */
    atomic_int abort;
    /* Set (relaxed) by workers whose core binding was refused; read after
     * join. */
    atomic_int pin_refused;
    alignas(64) int err_thread;
    const char *err_what;
    const fdt_partition *pt;
    const double *P;
    fdt_mode mode;
    int search;                /* fdt_search, for every part's oracle */
    int n;
    int want_nbrs;
    fdt_mailboxes *mbs;
    worker *w;
    /* The calling thread waits here for the workers to finish their
     * loops (finished, under lock), then sets gather (under lock; 1: copy
     * your share of the mesh, -1: do not) and waits for the copies
     * (copied, under lock). Two condition variables, so that a worker's
     * signal never wakes another worker instead of the caller. The mutex
     * orders each worker's tets before the caller's offsets, those and
     * the grown buffers before every copy, and the copies before
     * gather_finish. */
    pthread_mutex_t lock;
    pthread_cond_t cv;         /* the calling thread waits on it */
    pthread_cond_t go;         /* the workers wait on it for gather */
    int finished;
    int gather;
    int copied;
    int pin;
    /* The gather (set by the calling thread before gather = 1): input
     * numbering, and each thread's first tet and hull face in the mesh,
     * whose buffers are thread 0's grown to the totals. */
    const fdt_vid *orig;
    size_t *toff, *hoff;
    uint32_t *gtets, *ghull;
    int64_t *gnbrs;
#ifdef FDT_HAVE_HWLOC
    hwloc_topology_t topo;     /* NULL unless pinning */
    int ncores;
    int numa_nodes;
#endif
} engine;

static void set_error(engine *e, int err, int thread, const char *what)
{
    int expect = 0;
    if (atomic_compare_exchange_strong_explicit(&e->error, &expect, err,
                                                memory_order_acq_rel,
                                                memory_order_acquire)) {
        e->err_thread = thread;
        e->err_what = what;
    }
    atomic_store_explicit(&e->abort, 1, memory_order_release);
    for (int i = 0; i < e->n; i++)
        fdt_mailbox_kick(fdt_mailboxes_at(e->mbs, i));
}

/* acquire: pairs with set_error's release store, so a thread that sees
 * the flag also sees the recorded error (not needed for the exit itself). */
static int aborted(const engine *e)
{
    return atomic_load_explicit(&e->abort, memory_order_acquire);
}

static int is_own(const worker *w, uint32_t id)
{
    return id >= w->lo && id < w->hi;
}

/* Coordinates of id as this thread may read them: shared mode reads the
 * one array; message mode its own part or its ghosts. NULL: unknown (a
 * bug: every foreign id reaches us with its coordinates). */
static const double *coords(const worker *w, uint32_t id)
{
    if (w->e->mode == FDT_MODE_SHARED || is_own(w, id))
        return w->e->P + 3 * (size_t)id;
    return ghost_find(&w->ghosts, id);
}

/* Adds this thread's activity unit before it puts a face in an empty
 * table (R1; R3: the caller holds another unit while doing so). */
static void ensure_active(worker *w)
{
    if (!w->active) {
        /* relaxed: see engine.work; our later removal of this unit is
         * sequenced after it, so it precedes it in work's order. */
        atomic_fetch_add_explicit(&w->e->work, 1, memory_order_relaxed);
        w->active = 1;
    }
}

/* Sends IAMDONE to every other thread: the caller brought work to 0. */
static int broadcast_done(worker *w)
{
    for (int j = 0; j < w->e->n; j++) {
        if (j == w->id)
            continue;
        fdt_msg *m;
        int rc = fdt_mailbox_alloc(w->mbox, &m);
        if (rc)
            return rc;
        m->kind = FDT_MSG_IAMDONE;
        m->u.iamdone.epoch = 1;
        m->u.iamdone.count = 0;
        if ((rc = fdt_mailbox_post(w->mbox, j, m)) < 0)
            return FDT_EINTERNAL;
    }
    return RUN_DONE;
}

/* Removes one unit (R2). RUN_DONE if it was the last (IAMDONEs sent). */
static int release_unit(worker *w)
{
    /* acq_rel: see engine.work. The RMW reads the latest value in work's
     * modification order, so 0 here means no unit is outstanding. */
    long long left = atomic_fetch_sub_explicit(&w->e->work, 1, memory_order_acq_rel) - 1;
    if (left > 0)
        return RUN_ON;
    if (left < 0)
        return FDT_EINTERNAL;
    return broadcast_done(w);
}

/* Posts a FACESEND of face v (and apex, or FDT_NONE) to thread `to`,
 * adding its unit first (R1). */
static int send_face(worker *w, int to, const uint32_t v[3], uint32_t apex,
                     int64_t link)
{
    face_payload fp;
    memset(&fp, 0, sizeof fp);
    memcpy(fp.f.v, v, sizeof fp.f.v);
    fp.f.apex = apex;
    fp.f.tet = link;
    if (w->e->mode == FDT_MODE_MESSAGE) {
        uint32_t ids[4] = {v[0], v[1], v[2], apex};
        int nid = apex == FDT_NONE ? 3 : 4, low = 0;
        for (int i = 1; i < nid; i++)
            if (ids[i] < ids[low])
                low = i;
        int j = 0;
        for (int i = 0; i < nid; i++) {
            if (i == low)
                continue;
            const double *x = coords(w, ids[i]);
            if (!x)
                return FDT_EINTERNAL;
            memcpy(fp.xyz[j++], x, 3 * sizeof *x);
        }
    }
    fdt_msg *m;
    int rc = fdt_mailbox_alloc(w->mbox, &m);
    if (rc)
        return rc;
    m->kind = FDT_MSG_FACESEND;
    memcpy(&m->u, &fp, sizeof fp);
    /* R1, relaxed (see engine.work): sequenced before the post, whose
     * release CAS the receiver's poll acquires before it removes the
     * unit, so the add precedes the removal in work's order. */
    atomic_fetch_add_explicit(&w->e->work, 1, memory_order_relaxed);
    if (fdt_mailbox_post(w->mbox, to, m) < 0)
        return FDT_EINTERNAL;
    return FDT_OK;
}

/*
 * A face of tet link (thread, (tid << 2) | i) arrives at its owner (us):
 * the first arrival makes it a front face, the second completes it
 * (§2.2). v is canonical and oriented outward from that tet. known: the
 * face's slot when the caller holds it (the front face a tet was built
 * on), so it is not looked up again; NULL otherwise.
 */
static int face_arrives(worker *w, const uint32_t v[3], int thread, int64_t link,
                        fdt_face *known)
{
    fdt_face f;
    memcpy(f.v, v, sizeof f.v);
    f.aux = (uint32_t)thread;
    f.tet = (uint64_t)link;
    ensure_active(w);
    int err = FDT_OK;
    fdt_face *s = known ? known : fdt_facetab_find_or_insert(&w->ft, &f, &err);
    if (err)
        return err;
    if (!s) {
        if (w->ft.count > w->st.max_front)
            w->st.max_front = w->ft.count;
        return fdt_faceq_push(&w->fq, f.v);
    }
    /* Completed: the stored face has its open side towards the new tet,
     * so it is oriented opposite to f; equal orientation would mean two
     * tets on one side of a face. */
    if (s->v[1] == f.v[1])
        return FDT_EINTERNAL;
    if (w->e->want_nbrs) {
        int ta = (int)s->aux;
        int64_t la = (int64_t)s->tet;
        if (ta == w->id && thread == w->id) {
            /* (tid << 2) | i is exactly the index of slot i of tet tid. */
            w->out.nbrs[la] = link >> 2;
            w->out.nbrs[link] = la >> 2;
        } else if ((err = link_add(&w->links, ta, la, thread, link)) != FDT_OK) {
            return err;
        }
    }
    fdt_facetab_remove(&w->ft, s);
    return FDT_OK;
}

/*
 * Builds the positively oriented tet v, which we own (its lowest id is
 * ours), and hands its faces to their owners. request: it was asked for by
 * FACESEND, so it may already exist. advanced: the slot of our front face
 * (v0, v1, v2) the tet was built on (its face 3, ours), or NULL.
 */
static int build_tet(worker *w, const uint32_t v[4], int request, fdt_face *advanced)
{
    const fdt_partition *pt = w->e->pt;
    int lowi = 0;
    for (int i = 1; i < 4; i++)
        if (v[i] < v[lowi])
            lowi = i;
    if (!is_own(w, v[lowi]))
        return FDT_EINTERNAL;
    /* The face opposite the lowest vertex is the only one that may belong
     * to another part: its lowest id is the tet's second lowest (a min
     * without branches; sorting all four for it cost mispredictions on
     * every tet, and only tets across a cut need the sorted ids). */
    uint32_t second = UINT32_MAX;
    for (int i = 0; i < 4; i++)
        second = i != lowi && v[i] < second ? v[i] : second;
    int far_owner = is_own(w, second) ? w->id : fdt_partition_owner(pt, second);
    if (far_owner != w->id) {
        uint32_t k[4];
        memcpy(k, v, sizeof k);
        for (int i = 1; i < 4; i++)
            for (int j = i; j > 0 && k[j - 1] > k[j]; j--) {
                uint32_t x = k[j];
                k[j] = k[j - 1];
                k[j - 1] = x;
            }
        int rc = tetset_insert(&w->built, k);
        if (rc < 0)
            return rc;
        if (rc == 0) {
            /* Built before from one of our own faces; that build sent the
             * requester its face, so there is nothing left to do. A local
             * build cannot repeat (its face was completed by the first). */
            if (!request)
                return FDT_EINTERNAL;
            w->st.duplicate_requests++;
            return FDT_OK;
        }
    }
    int64_t tid = fdt_meshbuf_add_tet(&w->out, v);
    if (tid < 0)
        return FDT_ENOMEM;
    uint32_t fc[4][3];
    int nf = 4;
    if (advanced) {
        /* First, while the slot is where the pop found it (later faces
         * may grow or shift the table), as in src/front.c. */
        fdt_face_canon(v[fdt_tet_face[3][0]], v[fdt_tet_face[3][1]],
                       v[fdt_tet_face[3][2]], fc[3]);
        int err = face_arrives(w, fc[3], w->id, (tid << 2) | 3, advanced);
        if (err)
            return err;
        nf = 3;
    }
    /* the other table slots asked for first, as in src/front.c */
    for (int i = 0; i < nf; i++) {
        fdt_face_canon(v[fdt_tet_face[i][0]], v[fdt_tet_face[i][1]],
                       v[fdt_tet_face[i][2]], fc[i]);
        fdt_facetab_prefetch(&w->ft, fc[i]);
    }
    for (int i = 0; i < nf; i++) {
        const uint32_t *fv = fc[i];
        int64_t link = (tid << 2) | i;
        int owner = i == lowi ? far_owner : w->id;
        int err = owner == w->id ? face_arrives(w, fv, w->id, link, NULL)
                                 : send_face(w, owner, fv, FDT_NONE, link);
        if (err)
            return err;
    }
    if (w->out.ntets >= w->report_at) {
        w->report_at = w->out.ntets + 4096;
        /* relaxed: a progress estimate only (see worker.tets_done). */
        atomic_store_explicit(&w->tets_done, w->out.ntets, memory_order_relaxed);
    }
    return FDT_OK;
}

/* Handles one FACESEND; then removes its unit (R2). */
static int handle_face(worker *w, const pface *pf)
{
    const fdt_msg_facesend *f = &pf->p.f;
    if (w->e->mode == FDT_MODE_MESSAGE) {
        uint32_t ids[4] = {f->v[0], f->v[1], f->v[2], f->apex};
        int nid = f->apex == FDT_NONE ? 3 : 4, low = 0;
        for (int i = 1; i < nid; i++)
            if (ids[i] < ids[low])
                low = i;
        int j = 0;
        for (int i = 0; i < nid; i++) {
            if (i == low)
                continue;
            if (!is_own(w, ids[i])) {
                int err = ghost_put(&w->ghosts, ids[i], pf->p.xyz[j]);
                if (err)
                    return err;
            }
            j++;
        }
    }
    int err;
    if (f->apex == FDT_NONE) {
        if (f->v[0] > f->v[1] || f->v[0] > f->v[2] || !is_own(w, f->v[0]))
            return FDT_EINTERNAL;
        err = face_arrives(w, f->v, pf->sender, f->tet, NULL);
    } else {
        uint32_t v[4] = {f->v[0], f->v[1], f->v[2], f->apex};
        err = build_tet(w, v, 1, NULL);
    }
    if (err)
        return err;
    return release_unit(w);
}

static void unpack_face(const fdt_msg *m, pface *pf)
{
    memcpy(&pf->p, &m->u, sizeof pf->p);
    pf->sender = m->sender;
}

/* ---- range queries -------------------------------------------------------- */

/* Answers a NODESEND: the apex search over our own tree with the asker's
 * state rebuilt from the message (the face's and the best point's
 * coordinates; offering the asker's best to a fresh state reproduces its
 * conservative ball exactly, the same arithmetic on the same doubles). */
static int answer_query(worker *w, const fdt_msg *m)
{
    const fdt_msg_nodesend *q = &m->u.nodesend;
    double a[3], b[3], c[3], bx[3];
    memcpy(a, q->xyz[0], sizeof a);
    memcpy(b, q->xyz[1], sizeof b);
    memcpy(c, q->xyz[2], sizeof c);
    memcpy(bx, q->best_xyz, sizeof bx);
    fdt_apex s;
    fdt_apex_init(&s, a, b, c, q->v[0], q->v[1], q->v[2]);
    if (q->best != FDT_MSG_NONE) {
        fdt_apex_offer(&s, q->best, bx, &w->kq);
        if (s.best != q->best)
            return FDT_EINTERNAL;
    }
    size_t tested = w->kq.points;
    if (w->tree->n)
        fdt_apex_search(&s, w->tree, &w->kq);
    fdt_msg *r;
    int rc = fdt_mailbox_alloc(w->mbox, &r);
    if (rc)
        return rc;
    r->kind = FDT_MSG_NODERECV;
    r->tag = m->tag;
    r->u.noderecv.tested = (uint32_t)(w->kq.points - tested);
    if (s.best != q->best) {
        r->u.noderecv.best = s.best;
        memcpy(r->u.noderecv.best_xyz, s.bp, sizeof r->u.noderecv.best_xyz);
    } else {
        r->u.noderecv.best = FDT_MSG_NONE;
    }
    w->st.remote_answered++;
    if (fdt_mailbox_post(w->mbox, m->sender, r) < 0)
        return FDT_EINTERNAL;
    return FDT_OK;
}

/* Blocks until the mailbox holds something (or a kick), after a short
 * spin: a range query's answer usually takes microseconds. */
static int wait_mail(worker *w, int spin, double *acc)
{
    for (int i = 0; i < spin; i++) {
        if (fdt_mailbox_pending(w->mbox) || aborted(w->e))
            return FDT_OK;
        sched_yield();
    }
    double t = now_s();
    int rc = fdt_mailbox_wait(w->mbox, -1);
    *acc += now_s() - t;
    return rc < 0 ? FDT_EINTERNAL : FDT_OK;
}

/* Coordinates of the best point when it came from another part: two
 * buffers, so the state's bp (the old best) stays valid while the new
 * candidate is offered. */
typedef struct qbuf {
    double x[2][3];
    int next;
} qbuf;

/* Message mode: asks part j whether it holds a better apex than s's. */
static int remote_query(worker *w, fdt_apex *s, int j, qbuf *qb)
{
    fdt_msg *m;
    int rc = fdt_mailbox_alloc(w->mbox, &m);
    if (rc)
        return rc;
    uint32_t qid = ++w->qid;
    m->kind = FDT_MSG_NODESEND;
    m->tag = qid;
    fdt_msg_nodesend *q = &m->u.nodesend;
    memcpy(q->xyz[0], s->a, sizeof q->xyz[0]);
    memcpy(q->xyz[1], s->b, sizeof q->xyz[1]);
    memcpy(q->xyz[2], s->c, sizeof q->xyz[2]);
    q->v[0] = s->ia;
    q->v[1] = s->ib;
    q->v[2] = s->ic;
    q->best = s->best == FDT_NONE ? FDT_MSG_NONE : s->best;
    if (s->best != FDT_NONE)
        memcpy(q->best_xyz, s->bp, sizeof q->best_xyz);
    w->st.remote_queries++;
    if (fdt_mailbox_post(w->mbox, j, m) < 0)
        return FDT_EINTERNAL;
    double t0 = now_s(), waited = 0.0;
    for (;;) {
        if (aborted(w->e))
            return FDT_ECANCELED; /* someone else's error is reported */
        fdt_msg in;
        if (!fdt_mailbox_poll(w->mbox, &in)) {
            if ((rc = wait_mail(w, 64, &waited)) != FDT_OK)
                return rc;
            continue;
        }
        switch (in.kind) {
        case FDT_MSG_NODERECV:
            if (in.tag != qid || in.sender != j)
                return FDT_EINTERNAL;
            w->st.t_query_wait += now_s() - t0;
            if (in.u.noderecv.best != FDT_MSG_NONE) {
                double *x = qb->x[qb->next];
                qb->next ^= 1;
                memcpy(x, in.u.noderecv.best_xyz, 3 * sizeof *x);
                fdt_apex_offer(s, in.u.noderecv.best, x, &w->kq);
                /* The same exact tests accepted it over there. */
                if (s->best != in.u.noderecv.best)
                    return FDT_EINTERNAL;
                w->st.remote_improved++;
            }
            return FDT_OK;
        case FDT_MSG_NODESEND:
            if ((rc = answer_query(w, &in)) != FDT_OK)
                return rc;
            break;
        case FDT_MSG_FACESEND: {
            pface pf;
            unpack_face(&in, &pf);
            if ((rc = pfq_push(&w->deferred, &pf)) != FDT_OK)
                return rc;
            break;
        }
        default:
            /* IAMDONE cannot come while we hold a face; FACERECV is never
             * sent. */
            return FDT_EINTERNAL;
        }
    }
}

/*
 * Continues the apex search over the other parts: walks the bisection
 * tree, skipping our own part, empty parts, and every subtree whose box
 * cannot hold a better apex (§4.1), nearer child first. In message mode a
 * part's bounding box is all we test before asking it: we tried testing
 * the boxes of the top six levels of its kd-tree (setup data, like the
 * bounding box), and even its leaf boxes, and they removed only 1% and 14%
 * of the queries (200k uniform points, 2 threads): a search ball that
 * crosses the cut nearly always reaches a box next to it.
 */
/*
 * Shared mode, part j's mesh published: the first of j's points in the
 * pencil of the face (ia, ib, ic) is a neighbour that ia would have in
 * the DT of j's points and ia (fdt_ins_conflict_vertices: every front face
 * is a face of the DT of all points, so of the DT of j's points and the
 * face's vertices, where the first point is joined to ia, and adding the
 * other vertices takes edges from ia, never gives it new ones). Offering
 * those few to the search state replaces the kd search of j, which on
 * cylinders and cospherical sets tests thousands of points a face. The
 * faces come in runs with the same lowest vertex (the bucket order of
 * src/faceq.c), so the last answer is kept.
 */
/* Conflict regions larger than this are not used: a point just outside a
 * part's large flat hull facet (the cut of a grid) is in conflict with
 * every infinite tet over it, and walking them all for each query cost
 * more than the kd search (an O-grid of 40k points on two threads: 2.6 s
 * CPU with the kd search of the other part, 15.5 s with whole regions). */
#define MESH_QUERY_MAX_TETS 256

static int offer_from_mesh(worker *w, fdt_apex *s, int part)
{
    const fdt_ins *m = &w->e->w[part].orc.mesh;
    if (w->qcache_part != part || w->qcache_v != s->ia) {
        if (!w->qhint) {
            w->qhint = malloc((size_t)w->e->n * sizeof *w->qhint);
            if (!w->qhint)
                return FDT_ENOMEM;
            memset(w->qhint, 0xff, (size_t)w->e->n * sizeof *w->qhint);
        }
        w->qcache_part = -1;
        int rc = fdt_ins_conflict_vertices(m, s->a, &w->qhint[part], MESH_QUERY_MAX_TETS,
                                           &w->iq, &w->kq.pc);
        if (rc < 0)
            return rc;
        w->qcache_part = part;
        w->qcache_v = s->ia;
        w->qcache_big = rc == 1;
    }
    if (w->qcache_big) {
        fdt_apex_search(s, &w->e->pt->trees[part], &w->kq);
        return FDT_OK;
    }
    const double *P = w->e->P;
    for (size_t i = 0; i < w->iq.nvs; i++)
        fdt_apex_offer(s, w->iq.vs[i], P + 3 * (size_t)w->iq.vs[i], &w->kq);
    w->st.mesh_queries++;
    return FDT_OK;
}

static int search_others(worker *w, fdt_apex *s, qbuf *qb)
{
    const fdt_partition *pt = w->e->pt;
    int stack[64];
    int sp = 0;
    stack[sp++] = 0;
    while (sp > 0) {
        const fdt_pnode *nd = &pt->nodes[stack[--sp]];
        if (nd->begin == nd->end || nd->part == w->id)
            continue;
        if (!fdt_apex_box_useful(s, nd->lo, nd->hi))
            continue;
        if (nd->left < 0) {
            if (w->e->mode == FDT_MODE_SHARED) {
                /* acquire: pairs with the owner's release (mesh_pub) */
                if (atomic_load_explicit(&w->e->w[nd->part].mesh_pub, memory_order_acquire)) {
                    int rc = offer_from_mesh(w, s, nd->part);
                    if (rc)
                        return rc;
                } else {
                    fdt_apex_search(s, &pt->trees[nd->part], &w->kq);
                }
            } else {
                int rc = remote_query(w, s, nd->part, qb);
                if (rc)
                    return rc;
            }
            continue;
        }
        const fdt_pnode *l = &pt->nodes[nd->left], *r = l + 1;
        int ball = s->best != FDT_NONE && isfinite(s->r2);
        if (!ball)
            fdt_apex_aim(s);
        const double *q = ball ? s->center : s->target;
        double sc = ball ? s->sc : 1.0;
        double dl = l->begin < l->end ? fdt_box_dist2_sc(l->lo, l->hi, q, sc) : INFINITY;
        double dr = r->begin < r->end ? fdt_box_dist2_sc(r->lo, r->hi, q, sc) : INFINITY;
        if (dl <= dr) {
            stack[sp++] = nd->left + 1;
            stack[sp++] = nd->left;
        } else {
            stack[sp++] = nd->left;
            stack[sp++] = nd->left + 1;
        }
    }
    return FDT_OK;
}

/* Advances one own front face. Returns 1 if it did, 0 if the queue held
 * no live face, or an error. */
static int advance_one(worker *w)
{
    fdt_face *s = NULL;
    uint32_t f[3];
    uint32_t fv[3];
    while (fdt_faceq_pop(&w->fq, fv)) {
        /* the slot of a face that may come up soon, as in src/front.c */
        const uint32_t *ahead = fdt_faceq_ahead(&w->fq, 8);
        if (ahead)
            fdt_facetab_prefetch(&w->ft, ahead);
        s = fdt_facetab_find(&w->ft, fv);
        /* Faces completed since they were queued are skipped here. */
        if (s && s->v[1] == fv[1])
            break;
        s = NULL;
    }
    if (!s)
        return 0;
    memcpy(f, s->v, sizeof f);
    w->st.faces_advanced++;
    double a[3], b[3], c[3];
    const double *pa = coords(w, f[0]), *pb = coords(w, f[1]), *pc = coords(w, f[2]);
    if (!pa || !pb || !pc)
        return FDT_EINTERNAL;
    memcpy(a, pa, sizeof a);
    memcpy(b, pb, sizeof b);
    memcpy(c, pc, sizeof c);
    fdt_apex ap;
    fdt_apex_init(&ap, a, b, c, f[0], f[1], f[2]);
    fdt_oracle_tick(&w->orc, w->st.faces_advanced - 1, &w->kq);
    if (w->orc.state == 1 && !w->published) {
        /* release: see mesh_pub */
        atomic_store_explicit(&w->mesh_pub, 1, memory_order_release);
        w->published = 1;
    }
    /* Our part's insertion mesh, where the oracle switched to it: its
     * answer is the first of our points in the pencil of spheres through
     * f's circle (src/oracle.h), so only another part's point can come
     * earlier, and only inside that sphere: the candidate is offered to
     * the search state and the others are asked exactly as after our own
     * kd search. The closed-side tet is ours when we built it (aux). */
    int64_t ctid = s->aux == (uint32_t)w->id ? (int64_t)(s->tet >> 2) : -1;
    uint32_t mapex = FDT_NONE, mtet = FDT_NONE;
    int inside;
    if (fdt_oracle_apex(&w->orc, f, ctid, ctid >= 0 ? w->out.tets[s->tet] : FDT_NONE,
                        &mapex, &mtet)) {
        if (mapex != FDT_NONE) {
            fdt_apex_offer(&ap, mapex, coords(w, mapex), &w->kq);
            /* The mesh's apex is on the open side by construction; an
             * offer refused would mean the mesh and the search disagree. */
            if (ap.best != mapex)
                return FDT_EINTERNAL;
        }
        fdt_facetab_prefetch_tet(&w->ft, f, mapex);
        inside = fdt_apex_inside_region(&ap, w->tree);
    } else {
        /* Our own tree first, climbing from the leaf of f[0] (ours): the
         * apex is nearly always near the face. When the final ball lies
         * inside our part's region (src/partition.c, regions()), no other
         * part's point can be in it and the others are not asked at all;
         * otherwise their bounding boxes rule most of them out. */
        fdt_apex_guess(&ap, w->tree, f[0], &w->kq);
        /* the guessed tet's face slots, as in src/front.c */
        fdt_facetab_prefetch_tet(&w->ft, f, ap.best);
        inside = fdt_apex_verify_from(&ap, w->tree, f[0], &w->kq);
    }
    qbuf qb = {{{0}}, 0};
    int err = inside ? FDT_OK : search_others(w, &ap, &qb);
    if (err)
        return err;
    if (ap.best == FDT_NONE) {
        /* Nothing on the open side: a hull face, already outward. The
         * search changed no table (message mode deferred its FACESENDs). */
        fdt_face *live = fdt_facetab_find(&w->ft, f);
        if (!live)
            return FDT_EINTERNAL;
        if ((err = fdt_meshbuf_add_hull(&w->out, f)) != FDT_OK)
            return err;
        w->st.hull_faces++;
        fdt_facetab_remove(&w->ft, live);
        return 1;
    }
    uint32_t p = ap.best;
    uint32_t v[4] = {f[0], f[1], f[2], p};
    /* f[0] is the face's lowest id, and ours. */
    int owner = p > f[0] || is_own(w, p) ? w->id : fdt_partition_owner(w->e->pt, p);
    if (owner == w->id) {
        if (w->e->mode == FDT_MODE_MESSAGE && !is_own(w, p) &&
            (err = ghost_put(&w->ghosts, p, ap.bp)) != FDT_OK)
            return err;
        /* The search changed no table (above), so s still holds f. A
         * local build always adds a tet (build_tet), the last of out; its
         * mesh tet is known when the mesh gave its apex. */
        err = build_tet(w, v, 0, s);
        if (!err)
            err = fdt_oracle_note(&w->orc, (int64_t)w->out.ntets - 1,
                                  p == mapex ? mtet : FDT_NONE);
    } else {
        /* p is the tet's lowest id: the owner reads its coordinates
         * itself, the message carries f's. */
        w->st.tet_requests++;
        err = send_face(w, owner, f, p, -1);
    }
    return err ? err : 1;
}

/* ---- the worker ------------------------------------------------------------ */

static int worker_setup(worker *w)
{
    size_t np = w->hi - w->lo;
    /* A part of n points owns about 6.5 n tets and a front of a few
     * n^(2/3) faces; these are only first sizes. */
    size_t expect = (size_t)(7.0 * (double)np) + 64;
    if (fdt_meshbuf_init(&w->out, expect, w->e->want_nbrs) != FDT_OK)
        return FDT_ENOMEM;
    if (fdt_facetab_init(&w->ft, 1024) != FDT_OK)
        return FDT_ENOMEM;
    /* Own faces have an own lowest id (the ownership rule above). */
    if (fdt_faceq_init(&w->fq, w->lo, w->hi - w->lo) != FDT_OK)
        return FDT_ENOMEM;
    /* The part's mesh, if it comes to one, is built by this thread: its
     * pages are first touched here, near the core that reads them. */
    fdt_oracle_init(&w->orc, w->tree, w->e->search);
    w->qcache_part = -1;
    return FDT_OK;
}

static int worker_loop(worker *w)
{
    int rc;
    for (int i = 0; i < w->nseeds; i++)
        if ((rc = build_tet(w, w->seeds[i], 0, NULL)) != FDT_OK)
            return rc;
    for (;;) {
        if (aborted(w->e))
            return FDT_OK;
        /* FACESENDs deferred by a search are older than the mailbox. */
        while (w->deferred.n > 0) {
            pface pf = w->deferred.q[w->deferred.head];
            w->deferred.head++;
            w->deferred.n--;
            if ((rc = handle_face(w, &pf)) != RUN_ON)
                return rc;
        }
        fdt_msg m;
        while (fdt_mailbox_poll(w->mbox, &m)) {
            switch (m.kind) {
            case FDT_MSG_FACESEND: {
                pface pf;
                unpack_face(&m, &pf);
                rc = handle_face(w, &pf);
                break;
            }
            case FDT_MSG_NODESEND:
                rc = answer_query(w, &m);
                break;
            case FDT_MSG_IAMDONE:
                /* Work is 0: we hold nothing. */
                rc = w->active || w->ft.count || w->deferred.n ? FDT_EINTERNAL : RUN_DONE;
                break;
            default:
                rc = FDT_EINTERNAL;
                break;
            }
            if (rc != RUN_ON)
                return rc;
        }
        if ((rc = advance_one(w)) < 0)
            return rc;
        if (rc == 1 || w->deferred.n > 0)
            continue;
        if (w->active && w->ft.count == 0) {
            /* Queue exhausted and table empty: give up our unit (R2). */
            w->active = 0;
            if ((rc = release_unit(w)) != RUN_ON)
                return rc;
        }
        if ((rc = wait_mail(w, 0, &w->st.t_idle)) != FDT_OK)
            return rc;
    }
}

static void pin_thread(worker *w)
{
#ifdef FDT_HAVE_HWLOC
    engine *e = w->e;
    if (!e->topo)
        return;
    hwloc_obj_t core = hwloc_get_obj_by_type(e->topo, HWLOC_OBJ_CORE,
                                             (unsigned)(w->id % e->ncores));
    if (!core || hwloc_set_cpubind(e->topo, core->cpuset, HWLOC_CPUBIND_THREAD) != 0) {
        /* relaxed: read only after pthread_join, which orders it. */
        atomic_store_explicit(&e->pin_refused, 1, memory_order_relaxed);
        return;
    }
    w->st.core = w->id % e->ncores;
    /* First touch: the thread's own tables are allocated after this, by
     * itself. Its part's coordinates were written by the setup, so on a
     * machine with several memory nodes we move them next to the core
     * (best effort: a refusal only costs remote reads). */
    if (e->numa_nodes > 1 && w->hi > w->lo) {
        (void)hwloc_set_area_membind(e->topo, e->P + 3 * (size_t)w->lo,
                                     3 * sizeof(double) * (size_t)(w->hi - w->lo),
                                     core->cpuset, HWLOC_MEMBIND_BIND,
                                     HWLOC_MEMBIND_MIGRATE);
        (void)hwloc_set_area_membind(e->topo, w->tree->nodes,
                                     w->tree->nnodes * sizeof *w->tree->nodes,
                                     core->cpuset, HWLOC_MEMBIND_BIND,
                                     HWLOC_MEMBIND_MIGRATE);
    }
#else
    (void)w;
#endif
}

/* CPU seconds used by the calling thread so far (0 if the clock is
 * missing): with the idle and wait times it tells, on a loaded machine,
 * what the run would take with a core per thread. */
static double thread_cpu_s(void)
{
    struct timespec ts;
    if (clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) != 0)
        return 0.0;
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Slice k of n of [lo, hi). */
static void slice_of(size_t lo, size_t hi, size_t k, size_t n, size_t *a, size_t *b)
{
    *a = lo + (hi - lo) * k / n;
    *b = lo + (hi - lo) * (k + 1) / n;
}

/*
 * The worker's share of the gather, on its own thread once the calling
 * thread has grown thread 0's buffers to the whole mesh (gather_prepare):
 * its slice of thread 0's tets and hull faces, renumbered where they lie
 * into input numbering (tree-order id i is input point orig[i]), and its
 * slice of the other threads' ones, copied after them the same way, with
 * the neighbours shifted by their thread's first tet. Two slices, not a
 * thread its own part: the copies write fresh pages, and with two threads
 * the copying one took 31-40 ms of page faults while thread 0 took 6.
 */
static void gather_copy(worker *w)
{
    const engine *e = w->e;
    const fdt_vid *orig = e->orig;
    size_t k = (size_t)w->id, n = (size_t)e->n;
    size_t ta[2], tb[2], ha[2], hb[2]; /* [0]: thread 0's, [1]: the rest */
    slice_of(0, e->toff[1], k, n, &ta[0], &tb[0]);
    slice_of(e->toff[1], e->toff[n], k, n, &ta[1], &tb[1]);
    slice_of(0, e->hoff[1], k, n, &ha[0], &hb[0]);
    slice_of(e->hoff[1], e->hoff[n], k, n, &ha[1], &hb[1]);
    for (size_t i = 0; i < n; i++) {
        const fdt_meshbuf *o = &e->w[i].out;
        int r = i > 0;
        /* thread 0's part already lies in the mesh's buffers */
        const uint32_t *st = r ? o->tets : e->gtets, *sh = r ? o->hull : e->ghull;
        size_t t0 = e->toff[i], h0 = e->hoff[i];
        size_t a = ta[r] > t0 ? ta[r] : t0, b = tb[r] < e->toff[i + 1] ? tb[r] : e->toff[i + 1];
        for (size_t j = 4 * a; j < 4 * b; j++)
            e->gtets[j] = (uint32_t)orig[st[j - 4 * t0]];
        if (e->gnbrs && r)
            for (size_t j = 4 * a; j < 4 * b; j++) {
                int64_t x = o->nbrs[j - 4 * t0];
                e->gnbrs[j] = x < 0 ? -1 : x + (int64_t)t0;
            }
        a = ha[r] > h0 ? ha[r] : h0;
        b = hb[r] < e->hoff[i + 1] ? hb[r] : e->hoff[i + 1];
        for (size_t j = 3 * a; j < 3 * b; j++)
            e->ghull[j] = (uint32_t)orig[sh[j - 3 * h0]];
    }
}

static void *worker_main(void *arg)
{
    worker *w = arg;
    engine *e = w->e;
    double cpu0 = thread_cpu_s();
    if (e->pin)
        pin_thread(w);
    int rc = worker_setup(w);
    if (rc == FDT_OK)
        rc = worker_loop(w);
    if (rc < 0)
        set_error(e, rc, w->id, rc == FDT_ENOMEM ? "out of memory" : "inconsistent front");
    /* relaxed: a progress estimate only. */
    atomic_store_explicit(&w->tets_done, w->out.ntets, memory_order_relaxed);
    w->st.t_cpu = thread_cpu_s() - cpu0;
    pthread_mutex_lock(&e->lock);
    e->finished++;
    pthread_cond_signal(&e->cv);
    while (e->gather == 0)
        pthread_cond_wait(&e->go, &e->lock);
    int copy = e->gather > 0;
    pthread_mutex_unlock(&e->lock);
    if (copy) {
        gather_copy(w);
        pthread_mutex_lock(&e->lock);
        e->copied++;
        pthread_cond_signal(&e->cv);
        pthread_mutex_unlock(&e->lock);
    }
    return NULL;
}

static void worker_free(worker *w)
{
    fdt_oracle_free(&w->orc);
    fdt_ins_query_free(&w->iq);
    free(w->qhint);
    fdt_facetab_free(&w->ft);
    fdt_faceq_free(&w->fq);
    fdt_meshbuf_free(&w->out);
    free(w->built.k);
    free(w->ghosts.g);
    free(w->links.r);
    free(w->deferred.q);
}

/* ---- setup, run, gather ------------------------------------------------- */

int fdt_parallel_default_threads(void)
{
    long n = 0;
#ifdef FDT_HAVE_HWLOC
    hwloc_topology_t t;
    if (hwloc_topology_init(&t) == 0) {
        if (hwloc_topology_load(t) == 0)
            n = hwloc_get_nbobjs_by_type(t, HWLOC_OBJ_CORE);
        hwloc_topology_destroy(t);
    }
#endif
    if (n <= 0)
        n = sysconf(_SC_NPROCESSORS_ONLN);
    if (n < 1)
        n = 1;
    if (n > FDT_PARTITION_MAX)
        n = FDT_PARTITION_MAX;
    return (int)n;
}

static int key_cmp(const void *x, const void *y)
{
    const uint32_t *a = x, *b = y;
    for (int i = 0; i < 4; i++)
        if (a[i] != b[i])
            return a[i] < b[i] ? -1 : 1;
    return 0;
}

/* Seeds: one per nonempty part, the Delaunay tet (src/seed.c) at the part's
 * point nearest its box centre, found in a tree over all points (the setup
 * may read every part); identical seeds are dropped. *out gets *nout
 * positively oriented tets (owned by the caller). */
static int make_seeds(const fdt_partition *pt, uint32_t (**out)[4], int *nout,
                      fdt_kdq *kq)
{
    fdt_kdtree all;
    int err = fdt_partition_global_tree(pt, &all);
    if (err)
        return err;
    uint32_t(*sd)[4] = malloc((size_t)pt->nparts * sizeof *sd);
    uint32_t(*key)[4] = malloc((size_t)pt->nparts * 2 * sizeof *key);
    if (!sd || !key) {
        err = FDT_ENOMEM;
        goto done;
    }
    int ns = 0;
    for (int p = 0; p < pt->nparts; p++) {
        const fdt_kdtree *t = &pt->trees[p];
        if (!t->n)
            continue;
        double c[3];
        for (int k = 0; k < 3; k++)
            c[k] = t->nodes[0].lo[k] * 0.5 + t->nodes[0].hi[k] * 0.5;
        uint32_t a = fdt_kd_nearest(t, c, FDT_NONE, kq);
        uint32_t v[4];
        if ((err = fdt_seed_tet(&all, a, v, kq)) != FDT_OK)
            goto done;
        /* key: sorted ids, then the oriented ids (to recover them). */
        uint32_t *kk = key[2 * ns];
        memcpy(kk, v, sizeof v);
        for (int i = 1; i < 4; i++)
            for (int j = i; j > 0 && kk[j - 1] > kk[j]; j--) {
                uint32_t x = kk[j];
                kk[j] = kk[j - 1];
                kk[j - 1] = x;
            }
        memcpy(key[2 * ns + 1], v, sizeof v);
        ns++;
    }
    /* Sort pairs (key, tet) by key: qsort on 32-byte records. */
    qsort(key, (size_t)ns, 2 * sizeof *key, key_cmp);
    int nd = 0;
    for (int i = 0; i < ns; i++) {
        if (nd > 0 && key_cmp(key[2 * i], key[2 * (i - 1)]) == 0)
            continue;
        memcpy(sd[nd++], key[2 * i + 1], sizeof sd[0]);
    }
    *out = sd;
    *nout = nd;
    sd = NULL;
done:
    free(sd);
    free(key);
    fdt_kd_free(&all);
    return err;
}

/*
 * The gather, first half (calling thread, every worker done and waiting):
 * each thread's offsets (and the totals at [n]), and thread 0's buffers
 * grown to the totals, so that the other parts are copied after it and
 * then freed: the peak is one mesh plus the other parts rather than two
 * meshes. The copies run on the workers (gather_copy).
 */
static int gather_prepare(engine *e)
{
    size_t nt = 0, nh = 0;
    e->toff = malloc(((size_t)e->n + 1) * sizeof *e->toff);
    e->hoff = malloc(((size_t)e->n + 1) * sizeof *e->hoff);
    if (!e->toff || !e->hoff)
        return FDT_ENOMEM;
    for (int i = 0; i <= e->n; i++) {
        e->toff[i] = nt;
        e->hoff[i] = nh;
        if (i < e->n) {
            nt += e->w[i].out.ntets;
            nh += e->w[i].out.nhull;
        }
    }
    fdt_meshbuf *mb = &e->w[0].out;
    size_t tcap = nt > mb->tcap ? nt : mb->tcap;
    uint32_t *tt = realloc(mb->tets, tcap * 4 * sizeof *tt);
    if (tt)
        mb->tets = tt;
    int64_t *nn = mb->nbrs ? realloc(mb->nbrs, tcap * 4 * sizeof *nn) : NULL;
    if (nn)
        mb->nbrs = nn;
    size_t hcap = nh > mb->hcap ? nh : mb->hcap;
    uint32_t *hh = realloc(mb->hull, hcap * 3 * sizeof *hh);
    if (hh)
        mb->hull = hh;
    if (!tt || (mb->nbrs && !nn) || !hh)
        return FDT_ENOMEM;
    mb->tcap = tcap;
    mb->hcap = hcap;
    e->gtets = mb->tets;
    e->gnbrs = mb->nbrs;
    e->ghull = mb->hull;
    return FDT_OK;
}

/* The gather, second half (calling thread, after every gather_copy): the
 * mesh moves out of thread 0, the other parts are freed, and the
 * neighbours across threads are linked from the threads' link lists. */
static int gather_finish(engine *e, fdt_meshbuf *mb)
{
    size_t nt = e->toff[e->n], nh = e->hoff[e->n];
    *mb = e->w[0].out;
    memset(&e->w[0].out, 0, sizeof e->w[0].out);
    mb->ntets = nt;
    mb->nhull = nh;
    for (int i = 1; i < e->n; i++)
        fdt_meshbuf_free(&e->w[i].out);
    if (!e->want_nbrs)
        return FDT_OK;
    const size_t *off = e->toff;
    for (int i = 0; i < e->n; i++) {
        const linklist *l = &e->w[i].links;
        for (size_t j = 0; j < l->n; j++) {
            const linkrec *r = &l->r[j];
            size_t ia = 4 * off[r->ta] + (size_t)r->la;
            size_t ib = 4 * off[r->tb] + (size_t)r->lb;
            mb->nbrs[ia] = (int64_t)(off[r->tb] + (size_t)(r->lb >> 2));
            mb->nbrs[ib] = (int64_t)(off[r->ta] + (size_t)(r->la >> 2));
        }
    }
    /* Every tet slot is linked except the hull faces'. */
    size_t open = 0;
    for (size_t j = 0; j < 4 * nt; j++)
        open += mb->nbrs[j] < 0;
    return open != nh ? FDT_EINTERNAL : FDT_OK;
}

static void msg_counts_add(fdt_msg_counts *c, const uint64_t *k)
{
    c->iamdone += (size_t)k[FDT_MSG_IAMDONE];
    c->nodesend += (size_t)k[FDT_MSG_NODESEND];
    c->noderecv += (size_t)k[FDT_MSG_NODERECV];
    c->facesend += (size_t)k[FDT_MSG_FACESEND];
    c->facerecv += (size_t)k[FDT_MSG_FACERECV];
}

void fdt_par_out_free(fdt_par_out *out)
{
    fdt_meshbuf_free(&out->mb);
    free(out->tstats);
    out->tstats = NULL;
}

void fdt_parallel_fill_stats(const fdt_par_out *o, fdt_mode mode,
                             fdt_stats *st)
{
    const fdt_stats *p = &o->pst;
    st->sent = p->sent;
    st->received = p->received;
    st->remote_queries = p->remote_queries;
    st->remote_answered = p->remote_answered;
    st->remote_improved = p->remote_improved;
    st->tet_requests = p->tet_requests;
    st->duplicate_requests = p->duplicate_requests;
    st->t_idle = p->t_idle;
    st->t_query_wait = p->t_query_wait;
    st->load_imbalance = p->load_imbalance;
    st->pinned = p->pinned;
    st->threads = o->nthreads;
    st->mode = mode;
}

/* Runs the workers and waits for their loops, then has them gather the
 * mesh (gather_prepare, gather_copy) and joins them; *t_loops: when the
 * last loop ended. The calling thread reports progress meanwhile (and
 * cancels through the abort path). */
static int run_threads(engine *e, const fdt_settings *s, double *t_loops)
{
    pthread_attr_t attr;
    if (pthread_attr_init(&attr) != 0)
        return FDT_ETHREAD;
    /* 1024 threads at the default 8 MiB would reserve 8 GiB of address
     * space; a worker's deepest stack is a few KiB of walk stacks. */
    (void)pthread_attr_setstacksize(&attr, (size_t)1 << 20);
    int created = 0, err = FDT_OK;
    for (; created < e->n; created++)
        if (pthread_create(&e->w[created].th, &attr, worker_main, &e->w[created]) != 0) {
            err = FDT_ETHREAD;
            set_error(e, FDT_ETHREAD, created, "could not create a thread");
            break;
        }
    pthread_attr_destroy(&attr);
    double expect = 6.5 * (double)e->pt->m + 1.0;
    pthread_mutex_lock(&e->lock);
    while (e->finished < created) {
        if (!s->progress || err) {
            pthread_cond_wait(&e->cv, &e->lock);
            continue;
        }
        struct timespec dl;
        clock_gettime(CLOCK_REALTIME, &dl);
        dl.tv_nsec += 50 * 1000 * 1000;
        if (dl.tv_nsec >= 1000000000) {
            dl.tv_sec++;
            dl.tv_nsec -= 1000000000;
        }
        int rc = pthread_cond_timedwait(&e->cv, &e->lock, &dl);
        if (rc != ETIMEDOUT || e->finished >= created)
            continue;
        pthread_mutex_unlock(&e->lock);
        size_t built = 0;
        for (int i = 0; i < e->n; i++) /* relaxed: an estimate */
            built += atomic_load_explicit(&e->w[i].tets_done, memory_order_relaxed);
        double fr = (double)built / expect;
        if (s->progress(s->progress_user, fr > 0.99 ? 0.99 : fr))
            set_error(e, FDT_ECANCELED, -1, "canceled");
        pthread_mutex_lock(&e->lock);
    }
    *t_loops = now_s();
    /* Every worker waits on `go` now. Gather only a complete run: with an
     * error (relaxed is enough: a worker's set_error precedes its
     * finished++ under the lock we hold) the workers just exit. */
    int go = -1;
    if (!err && atomic_load_explicit(&e->error, memory_order_relaxed) == 0) {
        err = gather_prepare(e);
        go = err ? -1 : 1;
    }
    e->gather = go;
    pthread_cond_broadcast(&e->go);
    while (go > 0 && e->copied < e->n)
        pthread_cond_wait(&e->cv, &e->lock);
    pthread_mutex_unlock(&e->lock);
    for (int i = 0; i < created; i++)
        pthread_join(e->w[i].th, NULL);
    return err;
}

int fdt_parallel_triangulate(fdt_prepared *pr, const fdt_settings *s,
                             fdt_mode mode, int nthreads, fdt_par_out *out,
                             char *diag, size_t dlen)
{
    memset(out, 0, sizeof *out);
    if ((mode != FDT_MODE_SHARED && mode != FDT_MODE_MESSAGE) || nthreads < 1 ||
        nthreads > FDT_PARTITION_MAX || pr->m < 4 || pr->m > UINT32_MAX - 1)
        return FDT_EINVAL;
    double t0 = now_s();
    fdt_partition pt;
    engine *e = NULL;
    uint32_t(*seeds)[4] = NULL;
    int nseeds = 0, sync_ok = 0;
    fdt_kdq kq0;
    memset(&kq0, 0, sizeof kq0);
    /* The parts' trees are built on as many threads as there are cores
     * (up to one a part): at 1M points on two cores that took a quarter
     * of a second off a setup of 0.9 s. */
    int cores = fdt_parallel_default_threads();
    int err = fdt_partition_build(&pt, pr->p, pr->orig, (uint32_t)pr->m, nthreads,
                                  s->leaf_size > 0 ? s->leaf_size : FDT_DEFAULT_LEAF,
                                  cores < nthreads ? cores : nthreads);
    if (err)
        return err;
    if ((err = make_seeds(&pt, &seeds, &nseeds, &kq0)) != FDT_OK) {
        if (err == FDT_EINTERNAL)
            snprintf(diag, dlen, "internal error: no seed tetrahedron found");
        goto fail;
    }
    /* The engine holds atomics and 64-aligned workers. */
    err = FDT_ENOMEM;
    e = aligned_alloc(alignof(engine), (sizeof(engine) + alignof(engine) - 1) /
                                           alignof(engine) * alignof(engine));
    if (!e)
        goto fail;
    memset(e, 0, sizeof *e);
    atomic_init(&e->error, 0);
    atomic_init(&e->abort, 0);
    atomic_init(&e->pin_refused, 0);
    e->pt = &pt;
    e->P = pr->p;
    e->orig = pr->orig;
    e->mode = mode;
    e->n = nthreads;
    e->want_nbrs = s->neighbors != 0;
    e->search = (int)s->search;
    e->pin = s->pin != 0;
    e->w = aligned_alloc(alignof(worker), (size_t)nthreads * sizeof(worker));
    if (!e->w)
        goto fail;
    memset(e->w, 0, (size_t)nthreads * sizeof(worker));
    for (int i = 0; i < nthreads; i++)
        atomic_init(&e->w[i].mesh_pub, 0);
    if (fdt_mailboxes_create(&e->mbs, nthreads, 0, 0) != 0)
        goto fail;
    if (pthread_mutex_init(&e->lock, NULL) != 0)
        goto fail;
    if (pthread_cond_init(&e->cv, NULL) != 0) {
        pthread_mutex_destroy(&e->lock);
        goto fail;
    }
    if (pthread_cond_init(&e->go, NULL) != 0) {
        pthread_cond_destroy(&e->cv);
        pthread_mutex_destroy(&e->lock);
        goto fail;
    }
    sync_ok = 1;
#ifdef FDT_HAVE_HWLOC
    if (e->pin) {
        if (hwloc_topology_init(&e->topo) == 0 && hwloc_topology_load(e->topo) == 0) {
            e->ncores = hwloc_get_nbobjs_by_type(e->topo, HWLOC_OBJ_CORE);
            e->numa_nodes = hwloc_get_nbobjs_by_type(e->topo, HWLOC_OBJ_NUMANODE);
        }
        if (e->ncores <= 0) {
            if (e->topo)
                hwloc_topology_destroy(e->topo);
            e->topo = NULL;
            atomic_store_explicit(&e->pin_refused, 1, memory_order_relaxed);
        }
    }
#else
    if (e->pin)
        atomic_store_explicit(&e->pin_refused, 1, memory_order_relaxed);
#endif
    /* Seeds to their owners: sorted by key, so each owner's are adjacent
     * in owner order once grouped; nseeds <= nthreads, a scan is fine. */
    long long active = 0;
    for (int i = 0; i < nthreads; i++) {
        worker *w = &e->w[i];
        atomic_init(&w->tets_done, 0);
        w->e = e;
        w->id = i;
        w->mbox = fdt_mailboxes_at(e->mbs, i);
        w->tree = &pt.trees[i];
        w->lo = pt.start[i];
        w->hi = pt.start[i + 1];
        w->st.points = w->hi - w->lo;
        w->st.core = -1;
        w->report_at = 4096;
    }
    /* Regroup seeds by owner in place: counting sort. */
    {
        uint32_t(*by)[4] = malloc(((size_t)nseeds + 1) * sizeof *by);
        int *cnt = calloc((size_t)nthreads + 1, sizeof *cnt);
        if (!by || !cnt) {
            free(by);
            free(cnt);
            goto fail;
        }
        int *own = malloc(((size_t)nseeds + 1) * sizeof *own);
        if (!own) {
            free(by);
            free(cnt);
            goto fail;
        }
        for (int i = 0; i < nseeds; i++) {
            uint32_t lo = seeds[i][0];
            for (int k = 1; k < 4; k++)
                if (seeds[i][k] < lo)
                    lo = seeds[i][k];
            own[i] = fdt_partition_owner(&pt, lo);
            cnt[own[i] + 1]++;
        }
        for (int i = 0; i < nthreads; i++)
            cnt[i + 1] += cnt[i];
        for (int i = 0; i < nthreads; i++) {
            e->w[i].seeds = by + cnt[i];
            e->w[i].nseeds = cnt[i + 1] - cnt[i];
        }
        for (int i = 0; i < nseeds; i++)
            memcpy(by[cnt[own[i]]++], seeds[i], sizeof by[0]);
        free(own);
        free(cnt);
        free(seeds);
        seeds = by;
    }
    /* Message mode: a seed's foreign vertices are delivered with it, as a
     * FACESEND would carry them (the setup may read every part). */
    if (mode == FDT_MODE_MESSAGE)
        for (int i = 0; i < nthreads; i++) {
            worker *w = &e->w[i];
            for (int j = 0; j < w->nseeds; j++)
                for (int k = 0; k < 4; k++) {
                    uint32_t id = w->seeds[j][k];
                    if (!is_own(w, id) &&
                        ghost_put(&w->ghosts, id, pr->p + 3 * (size_t)id) != FDT_OK)
                        goto fail;
                }
        }
    for (int i = 0; i < nthreads; i++)
        if (e->w[i].nseeds > 0) {
            e->w[i].active = 1;
            active++;
        }
    /* Every thread with seeds starts holding its activity unit. Thread
     * creation orders this before everything the workers do. */
    atomic_init(&e->work, active);
    double t1 = now_s();
    double t2 = t1;
    err = run_threads(e, s, &t2);
    /* After pthread_join: any order would do; acquire documents that the
     * recorded err_thread/err_what are read after the CAS that chose them. */
    int werr = atomic_load_explicit(&e->error, memory_order_acquire);
    if (werr) {
        err = werr;
        if (werr == FDT_ENOMEM)
            snprintf(diag, dlen, "out of memory in worker thread %d", e->err_thread);
        else if (werr == FDT_EINTERNAL)
            snprintf(diag, dlen, "internal error in worker thread %d: %s", e->err_thread,
                     e->err_what ? e->err_what : "?");
        else if (werr == FDT_ETHREAD)
            snprintf(diag, dlen, "could not create thread %d of %d", e->err_thread, nthreads);
        goto fail;
    }
    if (err)
        goto fail;

    /* Statistics, and the message balance: every message sent was
     * received, kind by kind. */
    out->tstats = calloc((size_t)nthreads, sizeof *out->tstats);
    err = FDT_ENOMEM;
    if (!out->tstats)
        goto fail;
    fdt_stats *ps = &out->pst;
    size_t maxt = 0, sumt = 0;
    for (int i = 0; i < nthreads; i++) {
        worker *w = &e->w[i];
        fdt_thread_stats *ts = &out->tstats[i];
        fdt_mailbox_counts mc;
        fdt_mailbox_counts_get(w->mbox, &mc);
        *ts = w->st;
        ts->tets = w->out.ntets;
        msg_counts_add(&ts->sent, mc.sent);
        msg_counts_add(&ts->received, mc.received);
        msg_counts_add(&ps->sent, mc.sent);
        msg_counts_add(&ps->received, mc.received);
        ps->remote_queries += ts->remote_queries;
        ps->remote_answered += ts->remote_answered;
        ps->remote_improved += ts->remote_improved;
        ps->tet_requests += ts->tet_requests;
        ps->duplicate_requests += ts->duplicate_requests;
        ps->t_idle += ts->t_idle;
        ps->t_query_wait += ts->t_query_wait;
        out->fst.faces_advanced += ts->faces_advanced;
        /* The sum of the threads' largest fronts: an upper bound on the
         * largest total front, which no thread observes. */
        out->fst.max_front += ts->max_front;
        out->fst.kq.nodes += w->kq.nodes;
        out->fst.kq.points += w->kq.points;
        out->fst.kq.pc.orient_exact += w->kq.pc.orient_exact;
        out->fst.kq.pc.insphere_exact += w->kq.pc.insphere_exact;
        out->fst.mesh_faces += w->orc.mesh_faces;
        out->fst.star_walks += w->orc.star_walks;
        out->fst.mesh_parts += w->orc.switched_at != 0;
        out->fst.t_mesh += w->orc.t_mesh;
        out->fst.kq.pc.orient_adapt += w->kq.pc.orient_adapt;
        out->fst.kq.pc.insphere_adapt += w->kq.pc.insphere_adapt;
        if (ts->tets > maxt)
            maxt = ts->tets;
        sumt += ts->tets;
    }
    out->fst.kq.nodes += kq0.nodes;
    out->fst.kq.points += kq0.points;
    out->fst.kq.pc.orient_exact += kq0.pc.orient_exact;
    out->fst.kq.pc.insphere_exact += kq0.pc.insphere_exact;
    out->fst.kq.pc.orient_adapt += kq0.pc.orient_adapt;
    out->fst.kq.pc.insphere_adapt += kq0.pc.insphere_adapt;
    ps->load_imbalance = sumt ? (double)maxt * nthreads / (double)sumt : 1.0;
    ps->pinned = e->pin ? (atomic_load_explicit(&e->pin_refused, memory_order_relaxed) ? -1 : 1) : 0;
    if (memcmp(&ps->sent, &ps->received, sizeof ps->sent) != 0 ||
        ps->remote_queries != ps->remote_answered ||
        ps->sent.nodesend != ps->remote_queries || ps->sent.iamdone != (size_t)nthreads - 1) {
        snprintf(diag, dlen, "internal error: messages sent and received differ");
        err = FDT_EINTERNAL;
        goto fail;
    }
    err = gather_finish(e, &out->mb);
    if (err) {
        if (err == FDT_EINTERNAL)
            snprintf(diag, dlen, "internal error: a face between threads was not linked");
        goto fail;
    }
    out->nthreads = nthreads;
    out->t_setup = t1 - t0;
    out->t_front = t2 - t1;
    out->t_gather = now_s() - t2;
fail:
    if (e) {
        if (e->w)
            for (int i = 0; i < nthreads; i++)
                worker_free(&e->w[i]);
        free(e->w);
        fdt_mailboxes_destroy(&e->mbs);
        if (sync_ok) {
            pthread_cond_destroy(&e->go);
            pthread_cond_destroy(&e->cv);
            pthread_mutex_destroy(&e->lock);
        }
        free(e->toff);
        free(e->hoff);
#ifdef FDT_HAVE_HWLOC
        if (e->topo)
            hwloc_topology_destroy(e->topo);
#endif
        free(e);
    }
    free(seeds);
    fdt_partition_free(&pt);
    if (err)
        fdt_par_out_free(out);
    return err;
}
