/* The choice of apex oracle; see oracle.h and bench/NOTES.md, entry 51. */
#include "front/oracle.h"
#include "base/clock.h" /* fdt_now_s: the mesh build's time, for --stats */

#include "mesh/certify.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

/*
 * No rule here reads a clock or chooses: the policy (the search's row)
 * says whether a front reads a mesh. The cost rule that switched the
 * serial front from the kd search to its mesh by windows of faces (and its
 * memory cap) went with issue 31, when the insertion engines took every
 * run it served (bench/NOTES.md entries 87, 91, 104); the time rule and
 * the threaded runs' collective vote before it picked meshes from timings
 * on a loaded machine and switched the wrong way in some runs (entries
 * 53-61, 79, 86, 90).
 */

void fdt_oracle_init(fdt_oracle *o, const fdt_kdtree *t, fdt_oracle_policy policy)
{
    memset(o, 0, sizeof *o);
    o->t = t;
    o->state = policy == FDT_ORACLE_KD ? -1 : 0;
}

void fdt_oracle_free(fdt_oracle *o)
{
    fdt_ins_query_free(&o->sq);
    if (o->state == 1 && !o->gm)
        fdt_ins_free(&o->mesh);
    free(o->mt);
    memset(o, 0, sizeof *o);
    o->state = -1;
}

static void build_mesh(fdt_oracle *o, size_t faces, fdt_kdq *kq)
{
    double t0 = fdt_now_s();
    int err = fdt_ins_build(&o->mesh, o->t->P, o->t->base, o->t->n, &kq->pc);
    if (err == FDT_OK || err == FDT_EINTERNAL) {
        /* No answer is read before the mesh is proved (issue 31 item 6);
         * an insertion whose own checks broke is a wrong mesh too. */
        fdt_certify_fail why;
        fdt_certify_build_failed(&why);
        double tc = fdt_now_s();
        if (err == FDT_OK)
            err = fdt_certify(&o->mesh, &kq->pc, &why);
        o->t_certify += fdt_now_s() - tc;
        if (err) {
            fdt_ins_free(&o->mesh);
            o->err = FDT_ECHECK;
            o->err_what = why.what;
            err = FDT_ECHECK;
        } else {
            o->certified += o->mesh.nfinite;
        }
    }
    o->t_mesh += fdt_now_s() - t0;
    /* FDT_EDEGENERATE (a part whose points are coplanar: one layer of an
     * extruded grid) or FDT_ENOMEM: the kd search is always right, only
     * slower, so the front goes on with it. */
    o->state = err == FDT_OK ? 1 : -1;
    if (o->state == 1)
        o->switched_at = faces ? faces : 1;
}

int fdt_oracle_build(fdt_oracle *o, fdt_kdq *kq)
{
    if (o->t->n < 4) {
        o->state = -1;
        return FDT_OK;
    }
    build_mesh(o, 1, kq);
    return o->err;
}

void fdt_oracle_tick(fdt_oracle *o, size_t faces, fdt_kdq *kq)
{
    if (o->state != 0) /* the kd search for good, or the mesh built */
        return;
    if (o->t->n >= 4)
        build_mesh(o, faces, kq);
    else
        o->state = -1;
}

void fdt_oracle_share(fdt_oracle *o, const fdt_ins *gm)
{
    o->gm = gm;
    o->state = 1;
}

int fdt_oracle_note(fdt_oracle *o, int64_t tid, uint32_t mtet)
{
    if (o->state != 1 || tid < 0)
        return FDT_OK;
    size_t i = (size_t)tid;
    if (i >= o->mtcap) {
        size_t ncap = o->mtcap ? o->mtcap : 4096;
        while (ncap <= i)
            ncap += ncap / 2;
        uint32_t *nm = realloc(o->mt, ncap * sizeof *nm);
        if (!nm)
            return FDT_ENOMEM;
        /* Tets built before the mesh, or by the kd search since, have no
         * mesh tet: their faces are found by a walk. */
        memset(nm + o->mtcap, 0xff, (ncap - o->mtcap) * sizeof *nm);
        o->mt = nm;
        o->mtcap = ncap;
    }
    o->mt[i] = mtet;
    return FDT_OK;
}

int fdt_oracle_apex(fdt_oracle *o, const uint32_t f[3], int64_t ctid, uint32_t copp,
                    uint32_t *apex, uint32_t *mtet)
{
    if (o->state != 1)
        return 0;
    const fdt_ins *mesh = o->gm ? o->gm : &o->mesh;
    uint32_t m = ctid >= 0 && (size_t)ctid < o->mtcap ? o->mt[ctid] : FDT_NONE;
    uint32_t nt;
    int nk;
    if (m != FDT_NONE) {
        /* The closed-side tet is mesh tet m (same vertex set): f is its
         * face opposite copp, and the tet across it holds the apex. */
        const uint32_t *mv = fdt_ins_tet(mesh, m);
        for (int k = 0; k < 4; k++)
            if (mv[k] == copp) {
                *apex = fdt_ins_across(mesh, m, k, &nt, &nk);
                *mtet = *apex == FDT_NONE ? FDT_NONE : nt;
                o->mesh_faces++;
                return 1;
            }
        /* Not reached: the noted tet has the output tet's vertices. The
         * walk below answers anyway. */
    }
    if (!fdt_ins_find_face(mesh, f[0], f[1], f[2], &nt, &nk))
        return 0;
    *apex = fdt_ins_tet(mesh, nt)[nk];
    *mtet = *apex == FDT_NONE ? FDT_NONE : nt;
    o->mesh_faces++;
    o->star_walks++;
    return 1;
}

/* A star this large is left to the kd search: a vertex joined to most
 * points of a cospherical set (the perturbation's doing) would offer
 * them all for every face. */
#define STAR_MAX_TETS 512

int fdt_oracle_offer_star(fdt_oracle *o, const uint32_t f[3], fdt_apex *ap, fdt_kdq *kq)
{
    if (o->state != 1 || o->gm)
        return 0;
    int rc = fdt_ins_star_vertices(&o->mesh, f[0], STAR_MAX_TETS, &o->sq);
    if (rc)
        return rc == 1 ? 0 : rc;
    const double *P = o->mesh.P;
    for (size_t i = 0; i < o->sq.nvs; i++) {
        uint32_t v = o->sq.vs[i];
        if (v != f[1] && v != f[2])
            fdt_apex_offer(ap, v, P + 3 * (size_t)v, kq);
    }
    o->star_offers++;
    return 1;
}
