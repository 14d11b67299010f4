/* The choice of apex oracle; see oracle.h and bench/NOTES.md, entry 51. */
#include "front/oracle.h"
#include "base/mem.h"
#include "base/clock.h" /* fdt_now_s: the mesh build's time, for --stats */

#include "mesh/certify.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

/*
 * The switching rule. A window's cost a face is estimated in units of one
 * point tested by the kd search: cost = points + FDT_ORACLE_EXACT_WEIGHT *
 * exact tests, per face. A point test costs ~8 ns inside the walk (uniform
 * 1M: 0.77 us a face for 92 points and the nodes above them), an exact test
 * that leaves the filter 0.3 us (expansions) to 2 us (GMP), so one exact
 * test weighs as ~150 points. The mesh costs about one insertion per
 * point, ~6.5 faces a point: CGAL's 4.5 us a point at 1M is 0.7 us a
 * face, ~90 point units; ours may be slower on degenerate input, where
 * insertion needs exact tests too. Uniform clouds (92 units a face)
 * must never switch, and the gain must be large where we do: the
 * threshold is three times uniform's cost.
 */
#define SWITCH_COST 300
/* The mesh is paid once for the whole part, the kd search only for the
 * faces still to come (about 6.5 a point in all): a window seen late in
 * the run must be worse to pay for it. At the start the threshold is
 * SWITCH_COST a face; with half the faces left, twice that less the
 * mesh's own cost a face (~20 units once built). Without this, the
 * bunny (../shared/data) switched with most faces done and took 0.65 s
 * CPU for the kd search's 0.33 s. */
#define FACES_PER_POINT 6.5
#define MESH_FACE_COST 20
/* The first decision comes early: on a 12-digit sphere of 20,950 points
 * a face costs ~6,700 points tested, so a first window of 2,048 faces
 * took 0.25 s of a 0.39 s run, one of 256 faces 0.03 s. The windows then
 * double up to WINDOW: a rotated lattice's first 256 faces (around the
 * seed) cost 98 points a face and the next ones 3,030, and a fixed second
 * window of 16,384 faces spent 2.1 s of a 2.9 s run before the switch
 * (100k points; 0.7 s with doubling windows, bench/NOTES.md entry 53). */
#define FIRST_WINDOW 256
#define WINDOW 16384

/*
 * No rule here reads a clock: the switch is a function of the input and
 * the settings (issue 31). The time rule (TIME_MARGIN over thread CPU)
 * and the threaded runs' collective vote that stood here until session 20
 * picked the same meshes from timings on a loaded machine and switched
 * the wrong way in some runs (bench/NOTES.md entries 53-61, 79, 86, 90).
 */

/* The window's work so far is measured in these units. */
static inline size_t work_units(const fdt_kdq *kq)
{
    return kq->points + FDT_ORACLE_EXACT_WEIGHT * (kq->pc.orient_exact + kq->pc.insphere_exact);
}

/*
 * The work at which a window that started at work w0 and ends after len
 * faces, at faces_end, has already decided to switch: its cost a face at
 * the end is at least (work now - w0) / len, and the rule in
 * fdt_oracle_tick switches when that exceeds MESH_FACE_COST + (SWITCH_COST
 * - MESH_FACE_COST) * total / left, with left the faces left at the end,
 * known now. So passing it mid-window gives the window's own decision,
 * only earlier: a 12-digit sphere of 100k points tests ~42,000 points a
 * face, and its first window of 256 faces took 0.17 s of a 0.44 s run
 * where the mesh path takes 0.27 s (bench/NOTES.md entry 55).
 */
static size_t window_budget(const fdt_oracle *o, size_t w0, size_t faces_end, size_t len)
{
    double total = FACES_PER_POINT * (double)o->t->n;
    double left = total - (double)faces_end;
    if (left <= 0.0)
        return SIZE_MAX;
    double b = (double)w0 + (double)len * (MESH_FACE_COST +
                                           (SWITCH_COST - MESH_FACE_COST) * total / left);
    return b < (double)SIZE_MAX / 2 ? (size_t)b : SIZE_MAX;
}

void fdt_oracle_init(fdt_oracle *o, const fdt_kdtree *t, fdt_oracle_policy policy)
{
    memset(o, 0, sizeof *o);
    o->t = t;
    o->policy = policy;
    o->state = policy == FDT_ORACLE_KD ? -1 : 0;
    o->next_check = policy == FDT_ORACLE_MESH ? 0 : FIRST_WINDOW;
    o->w_budget = policy == FDT_ORACLE_SWITCH ? window_budget(o, 0, FIRST_WINDOW, FIRST_WINDOW)
                                              : SIZE_MAX;
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

size_t fdt_oracle_mem_share(int parts)
{
    size_t avail = fdt_mem_available();
    return avail == SIZE_MAX ? 0 : avail / (size_t)(parts > 0 ? parts : 1);
}

static void build_mesh(fdt_oracle *o, size_t faces, fdt_kdq *kq)
{
    if (o->policy == FDT_ORACLE_SWITCH && o->mem_cap &&
        FDT_ORACLE_MESH_BYTES * (double)o->t->n > (double)o->mem_cap) {
        o->state = -1;
        o->mesh_refused = 1;
        return;
    }
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
    if (o->state != 0)
        return;
    if (faces < o->next_check) {
        if (work_units(kq) > o->w_budget)
            build_mesh(o, faces, kq);
        return;
    }
    if (o->policy == FDT_ORACLE_MESH || o->t->n == 0) {
        if (o->t->n >= 4)
            build_mesh(o, faces, kq);
        else
            o->state = -1;
        return;
    }
    size_t df = faces - o->w_faces;
    size_t points = kq->points - o->w_points;
    size_t exact = kq->pc.orient_exact + kq->pc.insphere_exact - o->w_exact;
    double cost = df > 0 ? ((double)points + FDT_ORACLE_EXACT_WEIGHT * (double)exact) / (double)df
                         : 0.0;
    double total = FACES_PER_POINT * (double)o->t->n;
    double left = total > (double)faces ? total - (double)faces : 0.0;
    if (df > 0 && (cost - MESH_FACE_COST) * left > (SWITCH_COST - MESH_FACE_COST) * total) {
        build_mesh(o, faces, kq);
        return;
    }
    o->w_faces = faces;
    o->w_points = kq->points;
    o->w_exact = kq->pc.orient_exact + kq->pc.insphere_exact;
    size_t win = faces < FIRST_WINDOW ? FIRST_WINDOW : faces < WINDOW ? faces : WINDOW;
    o->next_check = faces + win;
    o->w_budget = window_budget(o, work_units(kq), o->next_check, win);
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
