/* The serial advancing front; see front.h. */
#include "front/front.h"

#include <stdlib.h>
#include <string.h>
#include "front/faceq.h"
#include "front/facetab.h"
#include "front/oracle.h"
#include "front/search.h"
#include "front/seed.h"
#include "front/sink.h"


/* Tet tid's face i completes the front face in slot s (§2.2: "the new
 * tetrahedron is the missing neighbor and another triangle is removed
 * from the front"): the neighbours are linked and the face leaves. */
static void complete_face(fdt_facetab *ft, fdt_emit *em, fdt_face *s, int64_t tid, int i)
{
    if (!em->packed) {
        /* with neighbours the link is (tid << 2) | face (src/front/sink.h) */
        fdt_meshbuf *mb = em->mb;
        int64_t other = (int64_t)(s->tet >> 2);
        mb->nbrs[4 * (size_t)other + (s->tet & 3)] = tid;
        mb->nbrs[4 * (size_t)tid + i] = other;
    }
    fdt_facetab_remove(ft, s);
}

/*
 * Hands the four faces of new tet `tid` (vertices v) to the front: a face
 * already in the table is the other side of an existing front face, which
 * the new tet completes; a face not in the table becomes a front face with
 * its open side away from the new tet, linked to it (fdt_emit_link).
 * `advanced` is the slot of the front face the tet was built on, its face
 * 3 (the main loop's tets are (f0, f1, f2, apex), and fdt_tet_face[3] is f
 * reversed), or NULL (the seed): that face is completed through its slot
 * rather than looked up again.
 */
static int add_tet_faces(fdt_facetab *ft, fdt_faceq *fq, fdt_emit *em, const uint32_t v[4],
                         int64_t tid, fdt_face *advanced)
{
    int nf = 4;
    if (advanced) {
        /* First, while the slot is where the pop found it: later inserts
         * may grow the table and removals shift slots. */
        complete_face(ft, em, advanced, tid, 3);
        nf = 3;
    }
    fdt_face fc[4];
    /* All slots are asked for first (fdt_facetab_prefetch): at 1M points
     * the table outgrows the caches, and lookups one after the other
     * would each wait for memory. */
    for (int i = 0; i < nf; i++) {
        fdt_face_canon(v[fdt_tet_face[i][0]], v[fdt_tet_face[i][1]],
                       v[fdt_tet_face[i][2]], fc[i].v);
        fdt_facetab_prefetch(ft, fc[i].v);
    }
    for (int i = 0; i < nf; i++) {
        fdt_face f = fc[i];
        f.aux = 0;
        f.tet = fdt_emit_link(em, tid, i, v[i]);
        int err;
        fdt_face *s = fdt_facetab_find_or_insert(ft, &f, &err);
        if (err)
            return err;
        if (!s) {
            if ((err = fdt_faceq_push(fq, f.v)) != FDT_OK)
                return err;
            continue;
        }
        /* Completed: the stored face is oriented with its open side
         * towards the new tet, i.e. opposite to f. Equal orientation
         * would mean two tets on one side of a face: an overlap. */
        if (s->v[1] == f.v[1])
            return FDT_EINTERNAL;
        complete_face(ft, em, s, tid, i);
    }
    return FDT_OK;
}

/* The serial front, stopped after max_faces faces (SIZE_MAX: the whole
 * triangulation; fdt_front_probe: a few hundred). */
static int front_run(const fdt_kdtree *t, uint32_t start, fdt_oracle_policy policy, fdt_emit *out,
                     fdt_progress_fn progress, void *puser, fdt_front_stats *st,
                     size_t max_faces, const fdt_probe_budget *budget)
{
    fdt_facetab ft;
    fdt_faceq fq;
    fdt_oracle orc;
    uint32_t seed[4];
    int err = fdt_seed_tet(t, start, seed, &st->kq);
    if (err)
        return err;
    fdt_oracle_init(&orc, t, policy);
    if ((err = fdt_facetab_init(&ft, 4096)) != FDT_OK)
        return err;
    if ((err = fdt_faceq_init(&fq, t->base, t->n)) != FDT_OK) {
        fdt_facetab_free(&ft);
        return err;
    }
    const double *P = t->P;
    int64_t tid = fdt_emit_tet(out, seed);
    if (tid < 0) {
        err = (int)tid;
        goto done;
    }
    if ((err = add_tet_faces(&ft, &fq, out, seed, tid, NULL)) != FDT_OK)
        goto done;
    /* A Delaunay tetrahedralization of n random points has about 6.5n
     * tets; the estimate only drives the progress bar. */
    double expect = 6.5 * (double)t->n + 1.0;
    size_t next_report = 1u << 16;
    uint32_t fv[3];
    int over = 0; /* the probe's budget was spent */
    while (st->faces_advanced < max_faces && fdt_faceq_pop(&fq, fv)) {
        if (budget && (double)st->kq.points +
                              budget->exact_weight *
                                  (double)(st->kq.pc.orient_exact + st->kq.pc.insphere_exact) >
                          budget->cost) {
            over = 1;
            break;
        }
        /* the slot of the face 8 below the top of the current bucket:
         * a guess at a face that comes up soon (faces pushed meanwhile
         * come first), which costs one prefetch when wrong */
        const uint32_t *ahead = fdt_faceq_ahead(&fq, 8);
        if (ahead)
            fdt_facetab_prefetch(&ft, ahead);
        fdt_face *s = fdt_facetab_find(&ft, fv);
        /* Faces completed since they were pushed are skipped here rather
         * than searched for in the queue when they complete. */
        if (!s || s->v[1] != fv[1])
            continue;
        if (ft.count > st->max_front)
            st->max_front = ft.count;
        uint32_t f[3] = {s->v[0], s->v[1], s->v[2]};
        fdt_oracle_tick(&orc, st->faces_advanced, &st->kq);
        if (orc.err) {
            err = orc.err;
            st->cert_what = orc.err_what;
            goto done;
        }
        st->faces_advanced++;
        /* The insertion mesh first, where the oracle switched to it: it
         * holds every point, so its answer is the apex (or, FDT_NONE, a
         * hull face). s->tet links the tet on the closed side: its id
         * and its vertex opposite f (fdt_emit_unlink). */
        uint32_t apex, mtet = FDT_NONE, copp;
        int64_t ctid;
        fdt_emit_unlink(out, s->tet, &ctid, &copp);
        fdt_apex ap;
        if ((err = fdt_front_apex(&orc, t, &ft, f, P + 3 * (size_t)f[0], P + 3 * (size_t)f[1],
                                  P + 3 * (size_t)f[2], ctid, copp, 0, &ap, NULL, &apex, &mtet,
                                  &st->kq)) != FDT_OK)
            goto done;
        if (apex == FDT_NONE) {
            /* Nothing on the open side: a convex-hull face (§2.2). Its
             * open side is the outside, so f is already outward. */
            if ((err = fdt_emit_hull(out, f)) != FDT_OK)
                goto done;
            fdt_facetab_remove(&ft, s);
            continue;
        }
        /* (f0, f1, f2, apex) is positively oriented: the apex is on the
         * open side, orient3d > 0. */
        uint32_t v[4] = {f[0], f[1], f[2], apex};
        if ((tid = fdt_emit_tet(out, v)) < 0) {
            err = (int)tid;
            goto done;
        }
        if (fdt_oracle_note(&orc, tid, mtet) != FDT_OK) {
            err = FDT_ENOMEM;
            goto done;
        }
        /* The search left the table alone, so s still holds f. */
        if ((err = add_tet_faces(&ft, &fq, out, v, tid, s)) != FDT_OK)
            goto done;
        if ((size_t)out->ntets >= next_report) {
            next_report += 1u << 16;
            if (progress) {
                double fr = (double)out->ntets / expect;
                if (progress(puser, fr > 0.99 ? 0.99 : fr)) {
                    err = FDT_ECANCELED;
                    goto done;
                }
            }
        }
    }
    if (ft.count != 0 && st->faces_advanced < max_faces && !over)
        err = FDT_EINTERNAL;
done:
    st->mem_front = fdt_front_bytes(&ft, &fq);
    st->mesh_faces = orc.mesh_faces;
    st->star_walks = orc.star_walks;
    st->mesh_parts = orc.switched_at != 0;
    st->t_mesh = orc.t_mesh;
    st->certified_tets = orc.certified;
    st->t_certify = orc.t_certify;
    fdt_oracle_free(&orc);
    fdt_facetab_free(&ft);
    fdt_faceq_free(&fq);
    return err;
}

size_t fdt_front_bytes(const fdt_facetab *ft, const fdt_faceq *fq)
{
    size_t b = ft->cap * sizeof *ft->slots;
    b += fq->nb * (sizeof *fq->face + sizeof *fq->n + sizeof *fq->cap) +
         fq->nwords * sizeof *fq->bits + (fq->nwords + 63) / 64 * sizeof *fq->summary;
    for (size_t k = 0; k < fq->nb; k++)
        if (fq->face[k])
            b += (size_t)fq->cap[k] * 3 * sizeof(uint32_t);
    return b;
}

int fdt_front_emit(const fdt_kdtree *t, uint32_t start, fdt_search search, fdt_emit *out,
                   fdt_progress_fn progress, void *puser, fdt_front_stats *st)
{
    return front_run(t, start, fdt_search_row_of(search)->front_oracle, out, progress, puser, st,
                     SIZE_MAX, NULL);
}

int fdt_front_serial(const fdt_kdtree *t, uint32_t start, fdt_search search, fdt_meshbuf *out,
                     fdt_progress_fn progress, void *puser, fdt_front_stats *st)
{
    fdt_tsink s;
    fdt_emit em;
    int err = fdt_tsink_init(&s, NULL, NULL);
    if (err)
        return err;
    if ((err = fdt_emit_init(&em, &s, out)) == FDT_OK)
        err = front_run(t, start, fdt_search_row_of(search)->front_oracle, &em, progress, puser,
                        st, SIZE_MAX, NULL);
    fdt_emit_free(&em);
    fdt_tsink_free(&s);
    return err;
}

int fdt_front_probe(const fdt_kdtree *t, uint32_t start, size_t faces,
                    const fdt_probe_budget *budget, fdt_front_stats *st)
{
    /* The tets are dropped as built: the sink keeps nothing. */
    fdt_tsink s;
    fdt_emit em;
    int err = fdt_tsink_init(&s, NULL, NULL);
    if (err)
        return err;
    if ((err = fdt_emit_init(&em, &s, NULL)) == FDT_OK)
        err = front_run(t, start, FDT_ORACLE_KD, &em, NULL, NULL, st, faces, budget);
    fdt_emit_free(&em);
    fdt_tsink_free(&s);
    return err;
}
