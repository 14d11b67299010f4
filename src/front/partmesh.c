/* A part's own mesh, built, certified and handed to the sink:
 * src/front/partmesh.h. */
#include "front/partmesh.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "base/clock.h"
#include "mesh/certify.h"

#define INF FDT_NONE

static int report(fdt_progress_fn progress, void *puser, double fraction)
{
    return progress && progress(puser, fraction) ? FDT_ECANCELED : FDT_OK;
}

/* The insertion's progress as the first half of the run's. */
typedef struct half_progress {
    fdt_progress_fn fn;
    void *user;
} half_progress;

static int build_progress(void *user, double fraction)
{
    const half_progress *h = user;
    return h->fn(h->user, 0.5 * fraction);
}

/* Tet ids in slot order (tid[s] for each finite slot s), then the
 * neighbours of each finite tet from the mesh's adjacency into nbrs (4 a
 * tet from index `first`; entry k across the face opposite vertex k, -1 on
 * the hull, as src/front/meshbuf.h's meshbuf keeps them). */
static void link_neighbours(const fdt_ins *mesh, const uint32_t *tid, int64_t first,
                            int64_t *nbrs)
{
    for (uint32_t s = 0; s < mesh->nslots; s++) {
        if (!fdt_ins_is_finite(mesh, s))
            continue;
        int64_t *o = nbrs + 4 * (size_t)(first + tid[s]);
        for (int k = 0; k < 4; k++) {
            uint32_t nt;
            int nk;
            uint32_t apex = fdt_ins_across(mesh, s, k, &nt, &nk);
            o[k] = apex == INF ? -1 : first + (int64_t)tid[nt];
        }
    }
}

/* Every hull face: the infinite tets' finite faces, outward. */
static int emit_hull(const fdt_ins *mesh, fdt_emit *em)
{
    for (uint32_t s = 0; s < mesh->nslots; s++) {
        const uint32_t *v = fdt_ins_tet(mesh, s);
        int inf = fdt_ins_inf_index(v);
        if (inf < 0 || fdt_ins_is_free(mesh, s))
            continue;
        uint32_t h[3];
        fdt_ins_face_inward(v, inf, h);
        int err = fdt_emit_hull(em, h);
        if (err)
            return err;
    }
    return FDT_OK;
}

/*
 * The one-part engine runs in memory only (a streamed run keeps the
 * front), into an empty meshbuf: the mesh's own tet array becomes the
 * meshbuf's, each finite slot's four vertices moved down to its tet id's
 * place (tid <= slot, and a slot's 8 words hold a tet's 4, so a vertex is
 * read before its words are written over). The output then costs no copy:
 * without this the mesh (32 bytes a slot) and the output (16 a tet) were
 * held together, 419 bytes a point at the peak on 1M uniform points
 * against the kd front's 200 (bench/NOTES.md entry 87).
 */
static int hand_over(fdt_ins *mesh, fdt_emit *em, size_t *emitted)
{
    fdt_meshbuf *mb = em->mb;
    if (!mb || mb->ntets != 0)
        return FDT_EINTERNAL; /* a caller's mistake, src/api/api.c calls it so */
    uint32_t *tid = NULL;
    if (mb->nbrs) {
        if (!(tid = malloc((size_t)mesh->nslots * sizeof *tid)))
            return FDT_ENOMEM;
        uint32_t k = 0;
        for (uint32_t s = 0; s < mesh->nslots; s++)
            if (fdt_ins_is_finite(mesh, s))
                tid[s] = k++;
        size_t need = mesh->nfinite + 1;
        if (need > mb->tcap) {
            int64_t *nn = realloc(mb->nbrs, need * 4 * sizeof *nn);
            if (!nn) {
                free(tid);
                return FDT_ENOMEM;
            }
            mb->nbrs = nn;
        }
        link_neighbours(mesh, tid, 0, mb->nbrs);
        free(tid);
    }
    int err = emit_hull(mesh, em);
    if (err)
        return err;
    uint32_t *T = mesh->T;
    size_t k = 0;
    for (uint32_t s = 0; s < mesh->nslots; s++)
        if (fdt_ins_is_finite(mesh, s)) {
            memmove(T + 4 * k, T + 8 * (size_t)s, 4 * sizeof *T);
            k++;
        }
    uint32_t *shrunk = realloc(T, (k + 1) * 4 * sizeof *T);
    mesh->T = NULL; /* the meshbuf owns it now; fdt_ins_free leaves it */
    free(mb->tets);
    mb->tets = shrunk ? shrunk : T;
    mb->ntets = k;
    mb->tcap = k + 1;
    em->ntets = (int64_t)k;
    *emitted = k;
    return FDT_OK;
}

size_t fdt_partmesh_final(const fdt_ins *m, const fdt_kdtree *t, uint8_t *final)
{
    size_t count = 0;
    int everything = t->cell == NULL;
    fdt_kdq kq;
    memset(&kq, 0, sizeof kq);
    for (uint32_t s = 0; s < m->nslots; s++) {
        final[s] = 0;
        if (!fdt_ins_is_finite(m, s))
            continue;
        if (!everything) {
            /* The ball of the tet as the apex search keeps it: face
             * (v0, v1, v2) with v3 on its open side (a positive tet). */
            const uint32_t *v = fdt_ins_tet(m, s);
            const double *P = m->P;
            fdt_apex ap;
            fdt_apex_init(&ap, P + 3 * (size_t)v[0], P + 3 * (size_t)v[1],
                          P + 3 * (size_t)v[2], v[0], v[1], v[2]);
            fdt_apex_offer(&ap, v[3], P + 3 * (size_t)v[3], &kq);
            if (ap.best != v[3] || !fdt_apex_inside_region(&ap, t))
                continue;
        }
        final[s] = 1;
        count++;
    }
    return count;
}

int fdt_partmesh_emit_all(const double *P, uint32_t m, int nthreads, fdt_emit *em,
                          fdt_progress_fn progress, void *puser, fdt_partmesh_stats *st,
                          char *diag, size_t dlen)
{
    fdt_ins mesh;
    double t0 = fdt_now_s();
    half_progress hp = {progress, puser};
    int err = nthreads > 1
                  ? fdt_ins_build_parallel(&mesh, P, 0, m, nthreads, &st->pc)
                  : fdt_ins_build_progress(&mesh, P, 0, m, &st->pc,
                                           progress ? build_progress : NULL, &hp);
    st->t_mesh = fdt_now_s() - t0;
    if (!err)
        st->ins = mesh.stats;
    fdt_certify_fail why;
    if (err == FDT_EDEGENERATE || err == FDT_EINVAL || err == FDT_EINTERNAL) {
        /* The caller merged duplicates and checked the dimension, so each
         * is the insertion's own check of its mesh failing. */
        fdt_certify_build_failed(&why);
        fdt_certify_describe(&why, diag, dlen);
        err = FDT_ECHECK;
    }
    if (!err)
        err = report(progress, puser, 0.5);
    if (!err) {
        /* No tet leaves before the whole mesh is proved (certify.h). */
        double t1 = fdt_now_s();
        err = nthreads > 1 ? fdt_certify_parallel(&mesh, nthreads, &st->pc, &why)
                           : fdt_certify(&mesh, &st->pc, &why);
        st->t_certify = fdt_now_s() - t1;
        st->certified_tets = mesh.nfinite;
        if (err == FDT_ECHECK)
            fdt_certify_describe(&why, diag, dlen);
    }
    if (!err)
        err = report(progress, puser, 0.6);
    if (!err)
        err = hand_over(&mesh, em, &st->final_tets);
    fdt_ins_free(&mesh);
    return err;
}
