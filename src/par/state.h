/*
 * The parallel engine's shared state (src/par/parallel.c sets it up): the
 * engine, one worker per part, what a part holds of its messages, and the
 * reads every module of the engine makes of them. The modules that act on
 * it, from the bottom up: src/par/termination.c (when the run ends,
 * errors), src/par/protocol.c (messages and handlers), src/par/engine.c
 * (the per-part step), src/par/gather.c (the output), src/par/threads.c
 * (hardware, threads).
 */
#ifndef FDT_STATE_H
#define FDT_STATE_H

#include <pthread.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>
#include <time.h>

#ifdef FDT_HAVE_HWLOC
#include <hwloc.h>
#endif

#include "base/clock.h"
#include "front/faceq.h"
#include "front/facetab.h"
#include "front/front.h"
#include "geom/kdtree.h"
#include "par/mailbox.h"
#include "front/oracle.h"
#include "geom/partition.h"
#include "par/partsets.h"
#include "front/sink.h"
#include "par/transport.h"

/* A worker's result for the main loop: keep going, or the run is over. */
enum { RUN_ON = 0, RUN_DONE = 1 };

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


/* FIFO of FACESENDs that arrived while a message-mode search waited. */
typedef struct pfqueue {
    pface *q;
    size_t head, n, cap;
} pfqueue;

/* Coordinates of the best point when it came from another part: two
 * buffers, so the state's bp (the old best) stays valid while the new
 * candidate is offered. */
typedef struct qbuf {
    double x[2][3];
    int next;
} qbuf;

/* ---- the engine and its workers ----------------------------------------- */

struct engine;

/* How many faces an MPI rank may keep parked (a power of two: the slot is
 * the low bits of its NODESEND's tag). */
#define FDT_PARK_MAX 64

/* A face whose apex search waits for another rank's NODERECV (MPI ranks,
 * engine.park; src/par/engine.c, advance_one): the search state, in a slot
 * that does not move (ap points to a, b, c, copied in message mode, and
 * into qb), and the bisection walk's stack where it stopped. */
typedef struct parked {
    uint32_t f[3];
    double a[3], b[3], c[3];
    fdt_apex ap;
    qbuf qb;
    uint32_t mapex, mtet;      /* the own mesh's answer (fdt_front_apex) */
    uint32_t qid;              /* the query out (its tag) */
    int part;                  /* asked, or to ask (held) */
    int used;
    int held;                  /* the query is not sent yet: a face with
                                  the same lowest vertex is asking */
    int sp;
    int stack[64];
} parked;

typedef struct worker {
    /* Tets built so far, for the calling thread's progress estimate only:
     * written (relaxed) by the owner every few thousand tets, read
     * (relaxed) by the calling thread; an estimate needs no ordering. On
     * its own cache line so those reads do not disturb the owner. */
    alignas(64) atomic_size_t tets_done;
    alignas(64) struct engine *e;
    int id;
    const fdt_kdtree *tree;    /* own part (n == 0: empty part) */
    uint32_t lo, hi;           /* own ids [lo, hi) */
    fdt_facetab ft;            /* own front faces */
    fdt_faceq fq;              /* own faces still to advance (may be stale) */
    fdt_meshbuf out;           /* in memory: own tets, global ids; nbrs
                                  local ids (empty when streaming) */
    fdt_emit em;               /* where own tets go (src/front/sink.h) */
    tetset built;              /* own boundary tets (duplicate requests) */
    ghostmap ghosts;           /* message mode: foreign coordinates */
    linklist links;            /* completed faces between two threads */
    pfqueue deferred;          /* message mode: FACESENDs for later */
    parked *pk;                /* engine.park: FDT_PARK_MAX slots */
    int npk;                   /* slots in use */
    uint32_t (*seeds)[4];      /* seed tets to build first (borrowed) */
    int nseeds;
    int root;                  /* starts with work: seeds, or (walls) a
                                  nonempty part */
    int active;                /* shared mode: holds an activity unit of
                                  e->work */
    /* Message mode (src/par/termination.c): Dijkstra-Scholten over FACESEND
     * and its FACERECV. All plain: only this worker's thread uses them. */
    int engaged;               /* in a tree of the computation */
    int parent;                /* whose FACESEND engaged us (-1: a root) */
    long long deficit;         /* our FACESENDs not yet acknowledged */
    int trees_done;            /* part 0: trees reported finished */
    int err;                   /* message mode: our own failure (0: none) */
    int aborted_by;            /* message mode: ABORT received from (-1) */
    uint32_t qid;              /* last range query id */
    fdt_kdq kq;
    fdt_oracle orc;            /* kd search or the part's insertion mesh */
    /* 1 once orc's mesh is built, stored with release by this thread after
     * fdt_ins_build wrote the mesh, which is not written again before
     * fdt_eng_worker_free (after every thread is joined). Another thread that loads
     * 1 with acquire sees the whole mesh and may read it with no lock
     * (shared mode, walk_others). The wall engine stores 2 when the part
     * has no mesh (too few points, flat, no memory): its readers wait
     * for 1 or 2, so what answers a query never depends on timing. */
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
     * kicked (fdt_tp_kick; the mailbox's seq_cst store in fdt_mailbox_kick, consumed by an acquire
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
    fdt_tsink *sink;           /* the run's sink (src/front/sink.h) */
    /* The engine's step, which the message handlers call back
     * (src/par/protocol.h; fdt_eng_new sets src/par/engine.c's). */
    const struct fdt_proto_ops *ops;
    fdt_mode mode;
    int search;                /* fdt_search, for every part's oracle */
    int walls;                 /* the wall engine: each part's own mesh
                                  first, its final tets at once, the
                                  fronts from the walls (engine.c,
                                  walls_start) */
    fdt_ins gmesh;             /* the DT of every point, when gmesh_ok:
                                  built before the threads start, read-only
                                  after (thread creation publishes it) */
    int gmesh_ok;
    size_t gm_certified;       /* the setup's mesh of every point: finite */
    double gm_t_certify;       /* tets certified, and the seconds it took */
    int n;
    int want_nbrs;
    fdt_transport *tp;         /* messages between the parts: endpoints
                                  0..n-1 the parts, n the calling thread */
    int msg_term;              /* message mode: termination and abort by
                                  messages alone (src/par/termination.c) */
    int roots;                 /* message mode: parts holding seeds */
    int park;                  /* message mode on MPI ranks: a face waiting
                                  for a NODERECV is parked, not waited on */
    int fail_part;             /* a test's injected failure (-1: none) */
    size_t fail_after;
    int ctl_err;               /* message mode: the calling thread's error
                                  (plain: written and read by it alone) */
    worker *w;
    /* The calling thread waits here for the workers to finish their
     * loops (finished, under lock), then sets gather (under lock; 1: copy
     * your share of the mesh, -1: do not) and waits for the copies
     * (copied, under lock). Two condition variables, so that a worker's
     * signal never wakes another worker instead of the caller. The mutex
     * orders each worker's tets before the caller's offsets, those and
     * the grown buffers before every copy, and the copies before
     * fdt_gather_finish. */
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

/* acquire: pairs with fdt_eng_set_error's release store, so a thread that sees
 * the flag also sees the recorded error (not needed for the exit itself). */
static inline int aborted(const engine *e)
{
    return atomic_load_explicit(&e->abort, memory_order_acquire);
}

static inline int is_own(const worker *w, uint32_t id)
{
    return id >= w->lo && id < w->hi;
}

/* Coordinates of id as this thread may read them: shared mode reads the
 * one array; message mode its own part or its ghosts. NULL: unknown (a
 * bug: every foreign id reaches us with its coordinates). */
static inline const double *coords(const worker *w, uint32_t id)
{
    if (w->e->mode == FDT_MODE_SHARED || is_own(w, id))
        return w->e->P + 3 * (size_t)id;
    return fdt_ghost_find(&w->ghosts, id);
}

#endif
