/*
 * The per-part step of the parallel engine; see engine.h.
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
 */
#include "par/engine.h"

#include <math.h>
#include <sched.h>
#include <stdlib.h>
#include <string.h>

#include "base/bits.h"
#include "base/mem.h"
#include "par/protocol.h"
#include "par/termination.h"
#include "front/partmesh.h"
#include "front/search.h"
#include "mesh/certify.h"

/*
 * A face of tet link (thread, (tid << 2) | i) arrives at its owner (us):
 * the first arrival makes it a front face, the second completes it
 * (§2.2). v is canonical and oriented outward from that tet. known: the
 * face's slot when the caller holds it (the front face a tet was built
 * on), so it is not looked up again; NULL otherwise.
 */
int fdt_eng_face_arrives(worker *w, const uint32_t v[3], int thread, int64_t link,
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
            /* (tid << 2) | i is exactly the index of slot i of tet tid
             * (with neighbours the links are not packed, src/front/sink.h). */
            w->out.nbrs[la] = link >> 2;
            w->out.nbrs[link] = la >> 2;
        } else if ((err = fdt_link_add(&w->links, ta, la, thread, link)) != FDT_OK) {
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
int fdt_eng_build_tet(worker *w, const uint32_t v[4], int request, fdt_face *advanced)
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
        fdt_sort4_u32(k);
        int rc = fdt_tetset_insert(&w->built, k);
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
    int64_t tid = fdt_emit_tet(&w->em, v);
    if (tid < 0)
        return (int)tid;
    uint32_t fc[4][3];
    int nf = 4;
    if (advanced) {
        /* First, while the slot is where the pop found it (later faces
         * may grow or shift the table), as in src/front/front.c. */
        fdt_face_canon(v[fdt_tet_face[3][0]], v[fdt_tet_face[3][1]],
                       v[fdt_tet_face[3][2]], fc[3]);
        int err = fdt_eng_face_arrives(w, fc[3], w->id,
                                       (int64_t)fdt_emit_link(&w->em, tid, 3, v[3]), advanced);
        if (err)
            return err;
        nf = 3;
    }
    /* the other table slots asked for first, as in src/front/front.c */
    for (int i = 0; i < nf; i++) {
        fdt_face_canon(v[fdt_tet_face[i][0]], v[fdt_tet_face[i][1]],
                       v[fdt_tet_face[i][2]], fc[i]);
        fdt_facetab_prefetch(&w->ft, fc[i]);
    }
    for (int i = 0; i < nf; i++) {
        const uint32_t *fv = fc[i];
        int64_t link = (int64_t)fdt_emit_link(&w->em, tid, i, v[i]);
        int owner = i == lowi ? far_owner : w->id;
        int err = owner == w->id ? fdt_eng_face_arrives(w, fv, w->id, link, NULL)
                                 : fdt_proto_send_face(w, owner, fv, FDT_NONE, link);
        if (err)
            return err;
    }
    size_t nt = (size_t)w->em.ntets;
    if (nt >= w->report_at) {
        w->report_at = nt + 4096;
        /* relaxed: a progress estimate only (see worker.tets_done). */
        atomic_store_explicit(&w->tets_done, nt, memory_order_relaxed);
    }
    return FDT_OK;
}

int fdt_eng_build_requested(worker *w, const uint32_t v[4], int64_t mtet)
{
    int64_t before = (int64_t)w->em.ntets;
    int err = fdt_eng_build_tet(w, v, 1, NULL);
    /* built (not a duplicate): its mesh slot, when the sender knew it */
    if (!err && mtet >= 0 && w->orc.gm && (int64_t)w->em.ntets > before)
        err = fdt_oracle_note(&w->orc, (int64_t)w->em.ntets - 1, (uint32_t)mtet);
    return err;
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
/* The walk stopped: a parked face's NODESEND is out (engine.park). */
enum { WALK_PARKED = 2 };

/* Sends parked face pk's query to pk->part: the slot in the tag's low
 * bits, a sequence number above them (a stale answer cannot match a
 * reused slot). WALK_PARKED or an error. */
static int post_parked(worker *w, parked *pk)
{
    uint32_t tag = (++w->qid << 6) | (uint32_t)(pk - w->pk);
    int rc = fdt_proto_post_query(w, &pk->ap, pk->part, tag);
    if (rc)
        return rc;
    pk->qid = tag;
    pk->held = 0;
    return WALK_PARKED;
}

/*
 * Whether another parked face with pk's lowest vertex has its query out.
 * Faces with one lowest vertex come off the queue together (src/front/faceq.c)
 * and are often faces of one tet: once a parked face's tet is built, its
 * siblings are complete and need no query. So a face whose search must ask
 * another rank while a sibling asks is held, its query not sent, until the
 * sibling is done (release_held); stage 3's first measurement parked
 * without this and sent 40 % more NODESENDs than waiting for each answer
 * (1M uniform points, 2 ranks: 168k against 120k). Invariant: every held
 * slot has a sibling whose query is out, so a held face is not held for
 * ever (that sibling's answer comes, and its end releases one).
 */
static int sibling_asking(const worker *w, const parked *pk)
{
    for (int i = 0; i < FDT_PARK_MAX; i++) {
        const parked *q = &w->pk[i];
        if (q != pk && q->used && !q->held && q->f[0] == pk->f[0])
            return 1;
    }
    return 0;
}

/* A parked face with lowest vertex v ended (finished or dropped): held
 * siblings that left the front are dropped, and if none of v's faces
 * asks any more, the first held one sends its query (the invariant
 * above). FDT_OK or an error. */
static int release_held(worker *w, uint32_t v)
{
    for (int i = 0; i < FDT_PARK_MAX; i++) {
        const parked *q = &w->pk[i];
        if (q->used && !q->held && q->f[0] == v)
            return FDT_OK;
    }
    for (int i = 0; i < FDT_PARK_MAX; i++) {
        parked *q = &w->pk[i];
        if (!q->used || !q->held || q->f[0] != v)
            continue;
        fdt_face *s = fdt_facetab_find(&w->ft, q->f);
        if (!s || s->v[1] != q->f[1]) {
            q->used = 0; /* completed meanwhile: see fdt_eng_resume */
            q->held = 0;
            w->npk--;
            continue;
        }
        int rc = post_parked(w, q);
        return rc == WALK_PARKED ? FDT_OK : rc;
    }
    return FDT_OK;
}

/* Walks from stack[0..*sp) (the root alone to start). In park mode a part
 * to ask gets a NODESEND tagged with slot pk and the walk stops there
 * (WALK_PARKED), the stack saved in *sp; fdt_eng_resume goes on from it
 * once the answer has been offered. Otherwise the part is asked and
 * waited for, as message mode does. */
static int walk_others(worker *w, fdt_apex *s, qbuf *qb, int *stack, int *sp, parked *pk)
{
    const fdt_partition *pt = w->e->pt;
    while (*sp > 0) {
        const fdt_pnode *nd = &pt->nodes[stack[--*sp]];
        if (nd->begin == nd->end || nd->part == w->id)
            continue;
        if (!fdt_apex_box_useful(s, nd->lo, nd->hi))
            continue;
        if (nd->left < 0) {
            if (w->e->mode == FDT_MODE_SHARED) {
                /* acquire: pairs with the owner's release (mesh_pub) */
                int pub = atomic_load_explicit(&w->e->w[nd->part].mesh_pub, memory_order_acquire);
                /* The wall engine: every part publishes, soon (walls_start
                 * waits on nobody), so wait and read the same answer every
                 * run. An abort (its part failed) ends the wait. */
                while (w->e->walls && pub == 0) {
                    if (aborted(w->e))
                        return FDT_ECANCELED;
                    sched_yield();
                    pub = atomic_load_explicit(&w->e->w[nd->part].mesh_pub, memory_order_acquire);
                }
                if (pub == 1) {
                    int rc = fdt_proto_offer_from_mesh(w, s, nd->part);
                    if (rc)
                        return rc;
                } else {
                    fdt_apex_search(s, &pt->trees[nd->part], &w->kq);
                }
            } else if (pk) {
                pk->part = nd->part;
                if (sibling_asking(w, pk)) {
                    pk->held = 1;
                    return WALK_PARKED;
                }
                return post_parked(w, pk);
            } else {
                int rc = fdt_proto_remote_query(w, s, nd->part, qb);
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
            stack[(*sp)++] = nd->left + 1;
            stack[(*sp)++] = nd->left;
        } else {
            stack[(*sp)++] = nd->left;
            stack[(*sp)++] = nd->left + 1;
        }
    }
    return FDT_OK;
}

/* The end of a face's advance once every part that could hold a better
 * apex was searched: a hull face, a local tet, or a FACESEND to the tet's
 * owner. s: f's live slot. Returns 1 or an error. */
static int finish_face(worker *w, const uint32_t f[3], fdt_face *s, fdt_apex *ap,
                       uint32_t mapex, uint32_t mtet)
{
    int err;
    if (ap->best == FDT_NONE) {
        /* Nothing on the open side: a hull face, already outward. The
         * search changed no table (message mode deferred its FACESENDs;
         * a parked face's slot was looked up again). */
        if ((err = fdt_emit_hull(&w->em, f)) != FDT_OK)
            return err;
        w->st.hull_faces++;
        fdt_facetab_remove(&w->ft, s);
        return 1;
    }
    uint32_t p = ap->best;
    uint32_t v[4] = {f[0], f[1], f[2], p};
    /* f[0] is the face's lowest id, and ours. */
    int owner = p > f[0] || is_own(w, p) ? w->id : fdt_partition_owner(w->e->pt, p);
    if (owner == w->id) {
        if (w->e->mode == FDT_MODE_MESSAGE && !is_own(w, p) &&
            (err = fdt_ghost_put(&w->ghosts, p, ap->bp)) != FDT_OK)
            return err;
        /* The search changed no table (above), so s still holds f. A
         * local build always adds a tet (fdt_eng_build_tet), the last of out; its
         * mesh tet is known when the mesh gave its apex. */
        err = fdt_eng_build_tet(w, v, 0, s);
        if (!err)
            err = fdt_oracle_note(&w->orc, (int64_t)w->em.ntets - 1,
                                  p == mapex ? mtet : FDT_NONE);
    } else {
        /* p is the tet's lowest id: the owner reads its coordinates
         * itself, the message carries f's. */
        w->st.tet_requests++;
        /* With the mesh of every point (read by every part) the request
         * carries the tet's mesh slot in its unused link, so the owner
         * notes it and later reads the apexes of the tet's faces from the
         * mesh; without it each was found by a walk around a vertex
         * (cylscan 100k, two threads: 30k walks on the lower part,
         * which receives the 54k requests; bench/NOTES.md entry 60). */
        int64_t mlink = w->orc.gm && p == mapex && mtet != FDT_NONE ? (int64_t)mtet : -1;
        err = fdt_proto_send_face(w, owner, f, p, mlink);
    }
    return err ? err : 1;
}

/* Advances one own front face. Returns 1 if it did (or parked it), 0 if
 * the queue held no live face, or an error. In park mode the caller
 * leaves a slot free. */
static int advance_one(worker *w)
{
    fdt_face *s = NULL;
    uint32_t fv[3];
    while (fdt_faceq_pop(&w->fq, fv)) {
        /* the slot of a face that may come up soon, as in src/front/front.c */
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
    /* The search state: on the stack, or in a free slot where it can
     * wait for an answer (park mode). */
    parked local, *pk = &local;
    if (w->e->park) {
        if (!w->pk && !(w->pk = calloc(FDT_PARK_MAX, sizeof *w->pk)))
            return FDT_ENOMEM;
        int k = 0;
        while (k < FDT_PARK_MAX && w->pk[k].used)
            k++;
        if (k == FDT_PARK_MAX)
            return FDT_EINTERNAL; /* the loop leaves a slot free */
        pk = &w->pk[k];
    }
    uint32_t *f = pk->f;
    memcpy(f, s->v, sizeof pk->f);
    w->st.faces_advanced++;
    const double *pa = coords(w, f[0]), *pb = coords(w, f[1]), *pc = coords(w, f[2]);
    if (!pa || !pb || !pc)
        return FDT_EINTERNAL;
    /* The search state keeps pointers to the face's coordinates
     * (fdt_apex): in shared mode into the one array, which nothing writes
     * while the fronts run; in message mode copies in the slot, as a ghost
     * table may grow while the face waits for an answer. The copies in
     * shared mode loaded three points a face that the mesh of every point
     * never reads: 18 % of this loop's samples on statue 440k (bench/NOTES.md
     * entry 82). */
    if (w->e->mode != FDT_MODE_SHARED) {
        memcpy(pk->a, pa, sizeof pk->a);
        memcpy(pk->b, pb, sizeof pk->b);
        memcpy(pk->c, pc, sizeof pk->c);
        pa = pk->a;
        pb = pk->b;
        pc = pk->c;
    }
    fdt_oracle_tick(&w->orc, w->st.faces_advanced - 1, &w->kq);
    if (w->orc.err)
        return w->orc.err; /* its mesh failed the certificate */
    if (w->orc.state == 1 && !w->orc.gm && !w->published) {
        /* release: see mesh_pub */
        atomic_store_explicit(&w->mesh_pub, 1, memory_order_release);
        w->published = 1;
    }
    /* The step shared with src/front/front.c (fdt_front_apex). Our part's
     * insertion mesh, where the oracle switched to it: its answer is the
     * first of our points in the pencil of spheres through f's circle
     * (src/front/oracle.h), so only another part's point can come earlier, and
     * only inside that sphere: the candidate is offered to the search
     * state and the others are asked exactly as after our own kd search.
     * Else our own tree, climbing from the leaf of f[0] (ours): the apex
     * is nearly always near the face. When the final ball lies inside our
     * part's region (src/geom/partition.c, regions()), no other part's point
     * can be in it and the others are not asked at all; otherwise their
     * bounding boxes rule most of them out. The closed-side tet is ours
     * when we built it (aux); then its link names it and its vertex
     * opposite f (fdt_emit_unlink). */
    int64_t ctid = -1;
    uint32_t copp = FDT_NONE;
    if (s->aux == (uint32_t)w->id)
        fdt_emit_unlink(&w->em, s->tet, &ctid, &copp);
    pk->mapex = FDT_NONE;
    pk->mtet = FDT_NONE;
    int inside = 0;
    int err = fdt_front_apex(&w->orc, w->tree, &w->ft, f, pa, pb, pc, ctid, copp, 1,
                             &pk->ap, &inside, &pk->mapex, &pk->mtet, &w->kq);
    if (err)
        return err;
    /* fdt_front_apex sets mapex to the kd search's answer when the mesh
     * was not asked; the mesh tet (mtet) stays FDT_NONE then. */
    pk->qb.next = 0;
    if (!inside) {
        pk->sp = 0;
        pk->stack[pk->sp++] = 0;
        err = walk_others(w, &pk->ap, &pk->qb, pk->stack, &pk->sp, w->e->park ? pk : NULL);
        if (err == WALK_PARKED) {
            pk->used = 1;
            w->npk++;
            return 1;
        }
        if (err)
            return err;
    }
    /* Message mode deferred the FACESENDs that came while it waited, so
     * s still holds f. */
    return finish_face(w, f, s, &pk->ap, pk->mapex, pk->mtet);
}

/*
 * A parked face's answer (engine.park). While the face waited, this rank
 * went on with its other faces and its mail, so the face table may have
 * changed: f is looked up again. If it left the front, a tet on its open
 * side was built meanwhile (by us, completing f, or by the tet's owner,
 * who sent us f back); that tet is the one this search would find (the
 * tet on a face's open side is unique: the same rules decide it whoever
 * searches), so the face is dropped. A face cannot come back once gone
 * (a face belongs to two tets at most), nor be queued twice.
 */
int fdt_eng_resume(worker *w, const fdt_msg *m)
{
    uint32_t k = m->tag & (FDT_PARK_MAX - 1);
    if (!w->pk || !w->pk[k].used || w->pk[k].held || w->pk[k].qid != m->tag ||
        w->pk[k].part != m->sender)
        return FDT_EINTERNAL;
    parked *pk = &w->pk[k];
    int err = fdt_proto_take_answer(w, m, &pk->ap, &pk->qb);
    if (!err)
        err = walk_others(w, &pk->ap, &pk->qb, pk->stack, &pk->sp, pk);
    if (err == WALK_PARKED)
        return RUN_ON; /* asking again, or held behind a sibling that asks */
    pk->used = 0;
    w->npk--;
    if (err)
        return err;
    fdt_face *s = fdt_facetab_find(&w->ft, pk->f);
    if (s && s->v[1] == pk->f[1] && (err = finish_face(w, pk->f, s, &pk->ap, pk->mapex,
                                                        pk->mtet)) < 0)
        return err;
    /* The slot is free but keeps its face: its siblings may go on. */
    return release_held(w, pk->f[0]);
}

int fdt_eng_worker_setup(worker *w)
{
    size_t np = w->hi - w->lo;
    /* A part of n points owns about 6.5 n tets and a front of a few
     * n^(2/3) faces; these are only first sizes. */
    size_t expect = (size_t)(7.0 * (double)np) + 64;
    if (!w->e->sink->user &&
        fdt_meshbuf_init(&w->out, expect, w->e->want_nbrs) != FDT_OK)
        return FDT_ENOMEM;
    if (fdt_emit_init(&w->em, w->e->sink, &w->out) != FDT_OK)
        return FDT_ENOMEM;
    if (fdt_facetab_init(&w->ft, 1024) != FDT_OK)
        return FDT_ENOMEM;
    /* Own faces have an own lowest id (the ownership rule above). */
    if (fdt_faceq_init(&w->fq, w->lo, w->hi - w->lo) != FDT_OK)
        return FDT_ENOMEM;
    /* The part's mesh, if it comes to one, is built by this thread: its
     * pages are first touched here, near the core that reads them. */
    /* The search's part_oracle (src/front/search.c says why --search
     * auto's parts keep the kd search), unless the parts share the mesh
     * of every point. */
    fdt_oracle_init(&w->orc, w->tree, fdt_search_row_of(w->e->search)->part_oracle);
    if (w->e->gmesh_ok)
        fdt_oracle_share(&w->orc, &w->e->gmesh);
    w->qcache_part = -1;
    return FDT_OK;
}

/* Whether seed tet v (positive, global ids) is final slot of our mesh:
 * all its vertices ours and its slot marked (final). */
static int seed_is_final(const worker *w, const uint32_t v[4], const uint8_t *final)
{
    for (int i = 0; i < 4; i++)
        if (!is_own(w, v[i]))
            return 0;
    uint32_t nt;
    int nk;
    /* v3 is on the open side of face (v0, v1, v2) of a positive tet. */
    return fdt_ins_find_face(&w->orc.mesh, v[0], v[1], v[2], &nt, &nk) &&
           fdt_ins_tet(&w->orc.mesh, nt)[nk] == v[3] && final[nt];
}

/*
 * The final tets of our certified mesh (final[], src/front/partmesh.h) to
 * the sink, in slot order; then each one's faces: toward another final
 * tet, the two are neighbours (linked here when neighbours are kept);
 * toward anything else (a tet that is not final, the part's hull), a face
 * of the DT of every point whose other side is not known yet: a wall
 * face, our first front. Every vertex is ours, so we own every such face.
 */
static int emit_final(worker *w, const uint8_t *final)
{
    const fdt_ins *m = &w->orc.mesh;
    uint32_t *tid = malloc((size_t)m->nslots * sizeof *tid);
    if (!tid)
        return FDT_ENOMEM;
    int err = FDT_OK;
    int64_t first = w->em.ntets;
    for (uint32_t t = 0; t < m->nslots && !err; t++) {
        if (!final[t])
            continue;
        int64_t id = fdt_emit_tet(&w->em, fdt_ins_tet(m, t));
        if (id < 0)
            err = (int)id;
        else if ((err = fdt_oracle_note(&w->orc, id, t)) == FDT_OK)
            tid[t] = (uint32_t)(id - first);
    }
    int64_t *nbrs = w->e->want_nbrs ? w->out.nbrs : NULL;
    for (uint32_t t = 0; t < m->nslots && !err; t++) {
        if (!final[t])
            continue;
        const uint32_t *v = fdt_ins_tet(m, t);
        int64_t id = first + tid[t];
        for (int i = 0; i < 4 && !err; i++) {
            uint32_t nt;
            int nk;
            fdt_ins_across(m, t, i, &nt, &nk);
            if (final[nt]) {
                if (nbrs)
                    nbrs[4 * id + i] = first + tid[nt];
                continue;
            }
            uint32_t fc[3];
            fdt_face_canon(v[fdt_tet_face[i][0]], v[fdt_tet_face[i][1]], v[fdt_tet_face[i][2]],
                           fc);
            w->st.wall_faces++;
            err = fdt_eng_face_arrives(w, fc, w->id, (int64_t)fdt_emit_link(&w->em, id, i, v[i]),
                                       NULL);
        }
    }
    w->st.final_tets += (size_t)(w->em.ntets - first);
    free(tid);
    return err;
}

/*
 * The wall engine's start (issue 31; bench/NOTES.md entry 90). Our points
 * are triangulated privately, no lock and no other part involved (the
 * oracle's mesh, certified before it is read), and published for the
 * other parts' queries. Its tets whose circumsphere lies inside our cell
 * are final at once (emit_final); the rest of the DT near our cell is
 * what the fronts build from the walls, asking our mesh for our points
 * and the other parts for theirs, exactly as the paper's front does from
 * a seed. The seeds stay: a part without final tets (a surface's points,
 * thin parts) starts from its seed, and a seed that is a final tet is
 * skipped (it was emitted). A part whose points do not span 3-D, or whose
 * mesh does not fit, keeps the kd search and its seed.
 */
static int walls_start(worker *w)
{
    int rc = fdt_oracle_build(&w->orc, &w->kq);
    if (rc)
        return rc; /* the certificate failed: the run stops */
    /* release: everything the build wrote happens before a reader's
     * acquire of mesh_pub (walk_others); 2: no mesh, the kd search */
    atomic_store_explicit(&w->mesh_pub, w->orc.state == 1 ? 1 : 2, memory_order_release);
    w->published = 1;
    uint8_t *final = NULL;
    if (w->orc.state == 1) {
        final = malloc(w->orc.mesh.nslots ? w->orc.mesh.nslots : 1);
        if (!final)
            return FDT_ENOMEM;
        fdt_partmesh_final(&w->orc.mesh, w->tree, final);
        if ((rc = emit_final(w, final)) != FDT_OK) {
            free(final);
            return rc;
        }
    }
    for (int i = 0; i < w->nseeds && !rc; i++)
        if (!final || !seed_is_final(w, w->seeds[i], final))
            rc = fdt_eng_build_tet(w, w->seeds[i], 0, NULL);
    free(final);
    return rc;
}

int fdt_eng_worker_loop(worker *w)
{
    int rc;
    if (w->e->walls) {
        if ((rc = walls_start(w)) != FDT_OK)
            return rc;
    } else {
        for (int i = 0; i < w->nseeds; i++)
            if ((rc = fdt_eng_build_tet(w, w->seeds[i], 0, NULL)) != FDT_OK)
                return rc;
    }
    for (;;) {
        if (aborted(w->e))
            return FDT_OK;
        /* FACESENDs deferred by a search are older than the mailbox. */
        while (w->deferred.n > 0) {
            pface pf = w->deferred.q[w->deferred.head];
            w->deferred.head++;
            w->deferred.n--;
            if ((rc = fdt_proto_handle_face(w, &pf)) != RUN_ON)
                return rc;
        }
        fdt_msg m;
        while (fdt_tp_poll(w->e->tp, w->id, &m)) {
            rc = fdt_proto_dispatch(w, &m, NULL);
            if (rc != RUN_ON)
                return rc;
        }
        /* Park mode: a full table of parked faces waits for answers. */
        rc = w->npk < FDT_PARK_MAX ? advance_one(w) : 0;
        if (rc < 0)
            return rc;
        if (w->id == w->e->fail_part && w->st.faces_advanced >= w->e->fail_after)
            return FDT_EINTERNAL; /* a test's injected failure (fdt_par_opts) */
        if (rc == 1 || w->deferred.n > 0)
            continue;
        if (w->npk > 0) {
            /* Not idle: parked faces are work (src/par/termination.c's
             * detach needs none left); their answers are mail. */
            if ((rc = fdt_proto_wait_mail(w, 0, &w->st.t_query_wait)) != FDT_OK)
                return rc;
            continue;
        }
        /* Nothing to do: shared mode gives up its unit, message mode
         * may detach (src/par/termination.c). */
        if ((rc = fdt_term_idle(w)) != RUN_ON)
            return rc;
        if ((rc = fdt_proto_wait_mail(w, 0, &w->st.t_idle)) != FDT_OK)
            return rc;
    }
}

void fdt_eng_worker_free(worker *w)
{
    fdt_oracle_free(&w->orc);
    fdt_ins_query_free(&w->iq);
    free(w->qhint);
    fdt_facetab_free(&w->ft);
    fdt_faceq_free(&w->fq);
    fdt_meshbuf_free(&w->out);
    fdt_emit_free(&w->em);
    free(w->built.k);
    free(w->ghosts.g);
    free(w->links.r);
    free(w->deferred.q);
    free(w->pk);
}

const fdt_proto_ops fdt_eng_ops = {
    .face_arrives = fdt_eng_face_arrives,
    .build_requested = fdt_eng_build_requested,
    .resume = fdt_eng_resume,
};

engine *fdt_eng_new(int n)
{
    /* The engine holds atomics and 64-aligned workers: aligned_alloc
     * wants a size that is a multiple of the alignment. */
    size_t esz = (sizeof(engine) + alignof(engine) - 1) / alignof(engine) * alignof(engine);
    engine *e = aligned_alloc(alignof(engine), esz);
    if (!e)
        return NULL;
    memset(e, 0, sizeof *e);
    atomic_init(&e->work, 0);
    atomic_init(&e->error, 0);
    atomic_init(&e->abort, 0);
    atomic_init(&e->pin_refused, 0);
    e->n = n;
    e->ops = &fdt_eng_ops;
    e->w = aligned_alloc(alignof(worker), (size_t)n * sizeof(worker));
    if (!e->w) {
        free(e);
        return NULL;
    }
    memset(e->w, 0, (size_t)n * sizeof(worker));
    for (int i = 0; i < n; i++) {
        atomic_init(&e->w[i].tets_done, 0);
        atomic_init(&e->w[i].mesh_pub, 0);
    }
    return e;
}

void fdt_eng_delete(engine *e)
{
    if (!e)
        return;
    free(e->w);
    free(e);
}
