/* The choice of apex oracle; see oracle.h and bench/NOTES.md, entry 51. */
#include "front/oracle.h"
#include "base/mem.h"
#include "base/clock.h"

#include "front/front.h"
#include "front/seed.h"
#include "mesh/certify.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

/*
 * The switching rule. A window's cost a face is estimated in units of one
 * point tested by the kd search: cost = points + EXACT_WEIGHT * exact
 * tests, per face. A point test costs ~8 ns inside the walk (uniform 1M:
 * 0.77 us a face for 92 points and the nodes above them), an exact test
 * that leaves the filter 0.3 us (expansions) to 2 us (GMP), so one exact
 * test weighs as ~150 points. The mesh costs about one insertion per
 * point, ~6.5 faces a point: CGAL's 4.5 us a point at 1M is 0.7 us a
 * face, ~90 point units; ours may be slower on degenerate input, where
 * insertion needs exact tests too. Uniform clouds (92 units a face)
 * must never switch, and the gain must be large where we do: the
 * threshold is three times uniform's cost.
 */
#define EXACT_WEIGHT 150
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
 * The second rule measures time, because points tested do not say what a
 * point costs: a city model's flat roofs and walls make the walk open
 * more nodes for its points, 0.9-1.05 us a face (thread CPU, this loaded
 * 2-core machine) at ~130 points and ~22 kd nodes a face, where airborne
 * lidar (autzen, lonestar in ../shared/data) takes 0.6-0.8 us at ~120
 * points and ~15 nodes, and uniform clouds 0.55 us at 95 points and 10
 * nodes (bench/NOTES.md entry 53). The mesh costs about MESH_BUILD_US a
 * point to build (uniform 1M: 3.1 s) and MESH_WALK_US a face to read, so
 * the kd search's remaining cost, c a face for `left` faces, pays for it
 * when c * left > MESH_BUILD_US * n + MESH_WALK_US * left. The rule takes
 * c and the nodes a face over all faces since the first TIMED_FROM (cold
 * caches: uniform's first 256 faces take twice its later ones), once
 * TIMED_MIN more have passed, and switches when c exceeds TIME_MARGIN
 * times that and the walk visited SLOW_NODES nodes a face or more. A time
 * alone is noisy on a shared machine, the node count alone does not
 * separate the city from the lidar (1.2x), and single windows do not
 * either: lonestar has a dense region of windows at 220 points, 27 nodes
 * and 1 us a face, after which the mesh cost it 3.2-3.5 s against the kd
 * search's 2.3 s. The rule only moves the switch; the mesh and the kd
 * search give the same apex, so the output never depends on timing. On a
 * faster machine the kd search looks cheaper against these constants and
 * the switch comes later: the safe direction. TIME_MARGIN was 1.25; city
 * lidar at 25k points (seed 1) stayed on the kd search with its checks at
 * 1.18-1.23 times the mesh's predicted cost and took 0.16 s CPU where the
 * mesh takes 0.12-0.13 s (CGAL 0.11 s). At 1.15 no other switch moves
 * over 15 gen_points families at 25k and 100k and ../shared/data (lonestar
 * and autzen stay below SLOW_NODES), and the constants hold: the mesh
 * reads a face in 0.18-0.23 us and builds in 2.9-3.5 us a point on the
 * city, uniform and bunny (bench/NOTES.md entry 55). The machine got
 * faster, and the same city measured 1.14-1.16 at its one check (16,384
 * faces, 20 nodes a face), so it stayed on the kd search in most runs:
 * 0.154 s against 0.10-0.11 s with the mesh (1.74x CGAL's CPU in one
 * bench run). The prediction is the kd search's side that is low: its
 * later faces cost more than the measured ones (statue 25k: 0.96 predicted
 * where the kd search took 1.2 times the mesh's time). 1.05 since; over
 * every family at 5k-440k and ../shared/data, only checks of the city had
 * 17 nodes a face or more and a ratio above 0.9, so no other switch moves
 * (bench/NOTES.md entry 86). The collective parts' dense-walk margin stays
 * 1.15 (DENSE_MARGIN, below).
 */
#define MESH_BUILD_US 3.0
#define MESH_WALK_US 0.2
#define TIME_MARGIN 1.05
#define SLOW_NODES 18.0
#define TIMED_FROM 4096
#define TIMED_MIN 8192

/*
 * A collective part (fdt_oracle.collective: a part of a two-thread auto
 * run, src/par/engine.c) votes for the mesh of every point instead of
 * building its own, and that mesh is built once a majority voted. A vote
 * by points tested alone, under COLLECTIVE_SURE units a face, needs the
 * window's walk to have visited SLOW_NODES nodes a face too, the time
 * rule's own condition: the first windows of an extruded grid's flat
 * layers and of the wind-study city cost 280-430 units at 2-15 nodes a
 * face (bench/NOTES.md entry 59). Once another part voted, a part also votes
 * early, on its thread CPU since COLLECTIVE_TIMED_FROM faces measured over
 * COLLECTIVE_TIMED_MIN more, when the kd search's remaining cost is over
 * COLLECTIVE_CLEAR times the mesh's predicted cost, or over
 * COLLECTIVE_MARGIN times with SLOW_NODES nodes a face: without it the
 * second part of an O-grid or a cubed sphere waited for its first full
 * time check (16,384 or 32,768 faces at 1.7-3 us a face, +0.10 and +0.15
 * s CPU of 0.9 and 0.7); at 4,096-8,192 faces the early measure gave
 * 2.2-3.6 there, 1.8 on the statue, and 1.1-1.3 on autzen's part 1 and on
 * lonestar's part 0 (12-19 nodes a face), which must not vote. The
 * margins are above the serial TIME_MARGIN because a window this short
 * is noisier and a collective mesh costs every part; DENSE_MARGIN (the
 * serial margin until entry 86) holds where the walk visits DENSE_NODES
 * nodes a face, which the airborne
 * scans' parts never averaged (autzen 12-19, lonestar's part 0 8-16) and
 * the statue (33) and bunny (24-29) do: the measured times, and so the
 * ratios, fall on a quieter machine against the fixed MESH_BUILD_US, and
 * the statue's 1.8 (bunny's 1.3-1.5) should not then drop under
 * COLLECTIVE_MARGIN to wait for the 16,384-face check. The same margins
 * hold at a collective part's later time checks (from TIMED_FROM):
 * autzen's part 1 measured 1.11-1.26 there at 17-19 nodes a face, over
 * the serial 1.15 in some runs, and the mesh was built (1 run in 6) once
 * its part 0 had voted on its first faces (67 nodes a face over 189
 * faces). COLLECTIVE_MARGIN lies between those and citylidar's part 0
 * (1.5-1.6 at 18-22 nodes): at 1.5 that part stayed on the kd search in 3
 * runs of 6 (bench/NOTES.md entry 61). All of these were measured on this
 * loaded 2-core machine: the margins are thin. On a quieter machine the
 * same part measured 1.35-1.46 (its first check at 17.6 nodes a face, its
 * second at 21), and at 1.35 half the runs of one quiet hour stayed on the
 * kd search (0.64 s where the mesh takes 0.24 s): the margin is 1.30 since,
 * under citylidar's quiet values and over autzen's loaded ones (entry 79).
 */
#define DENSE_MARGIN 1.15
#define COLLECTIVE_SURE 1000.0
#define COLLECTIVE_TIMED_FROM 1024
#define COLLECTIVE_TIMED_MIN 2048
#define COLLECTIVE_MARGIN 1.30
#define COLLECTIVE_CLEAR 2.0
#define DENSE_NODES 25.0

/* The window's work so far is measured in these units. */
static inline size_t work_units(const fdt_kdq *kq)
{
    return kq->points + EXACT_WEIGHT * (kq->pc.orient_exact + kq->pc.insphere_exact);
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

void fdt_oracle_init(fdt_oracle *o, const fdt_kdtree *t, int policy)
{
    memset(o, 0, sizeof *o);
    o->t = t;
    o->policy = policy;
    o->state = policy == FDT_SEARCH_KD ? -1 : 0;
    o->next_check = policy == FDT_SEARCH_MESH ? 0 : FIRST_WINDOW;
    o->w_budget = policy == FDT_SEARCH_AUTO ? window_budget(o, 0, FIRST_WINDOW, FIRST_WINDOW)
                                            : SIZE_MAX;
}

void fdt_oracle_free(fdt_oracle *o)
{
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
    if (o->collective) {
        o->state = 2;
        return;
    }
    if (o->policy == FDT_SEARCH_AUTO && o->mem_cap &&
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
        fdt_certify_fail why = {0, -1, "the insertion's own consistency checks failed"};
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

/* Whether a switch chosen by points tested (a window's cost a face, the
 * window since w_faces) stands (see collective, oracle.h). */
static int count_switch_stands(const fdt_oracle *o, size_t faces, const fdt_kdq *kq, double cost)
{
    if (!o->collective || cost >= COLLECTIVE_SURE)
        return 1;
    size_t df = faces - o->w_faces;
    double nodes = df ? (double)(kq->nodes - o->w_nodes) / (double)df : 0.0;
    return nodes >= SLOW_NODES;
}

/* A collective part's time rule (above): the kd search's remaining cost
 * is ratio times the mesh's predicted cost, the walk visits nodes a face. */
static int collective_time_vote(double ratio, double nodes)
{
    return ratio > COLLECTIVE_CLEAR || (nodes >= SLOW_NODES && ratio > COLLECTIVE_MARGIN) ||
           (nodes >= DENSE_NODES && ratio > DENSE_MARGIN);
}

void fdt_oracle_tick(fdt_oracle *o, size_t faces, fdt_kdq *kq)
{
    if (o->state != 0)
        return;
    if (faces < o->next_check) {
        if (work_units(kq) > o->w_budget) {
            size_t df = faces > o->w_faces ? faces - o->w_faces : 1;
            double cost = (double)(work_units(kq) - o->w_points - EXACT_WEIGHT * o->w_exact) /
                          (double)df;
            if (count_switch_stands(o, faces, kq, cost))
                build_mesh(o, faces, kq);
            else
                o->w_budget = SIZE_MAX; /* the window's end decides */
        }
        return;
    }
    if (o->policy == FDT_SEARCH_MESH || o->t->n == 0) {
        if (o->t->n >= 4)
            build_mesh(o, faces, kq);
        else
            o->state = -1;
        return;
    }
    size_t df = faces - o->w_faces;
    size_t points = kq->points - o->w_points;
    size_t exact = kq->pc.orient_exact + kq->pc.insphere_exact - o->w_exact;
    double cost = df > 0 ? ((double)points + EXACT_WEIGHT * (double)exact) / (double)df : 0.0;
    double total = FACES_PER_POINT * (double)o->t->n;
    double left = total > (double)faces ? total - (double)faces : 0.0;
    if (df > 0 && (cost - MESH_FACE_COST) * left > (SWITCH_COST - MESH_FACE_COST) * total &&
        count_switch_stands(o, faces, kq, cost)) {
        build_mesh(o, faces, kq);
        return;
    }
    /* The time rule over everything since TIMED_FROM faces (see above). */
    double now = fdt_thread_cpu_s();
    /* A collective part's early opinion, once another part voted. */
    if (o->collective && o->c_faces == 0 && faces >= COLLECTIVE_TIMED_FROM && now > 0.0) {
        o->c_faces = faces;
        o->c_cpu = now;
        o->c_nodes = kq->nodes;
    } else if (o->collective == 2 && o->c_faces > 0 &&
               faces >= o->c_faces + COLLECTIVE_TIMED_MIN && now > 0.0) {
        double nf = (double)(faces - o->c_faces);
        double us = 1e6 * (now - o->c_cpu) / nf;
        double nodes = (double)(kq->nodes - o->c_nodes) / nf;
        double ratio = us * left / (MESH_BUILD_US * (double)o->t->n + MESH_WALK_US * left);
        if (collective_time_vote(ratio, nodes)) {
            build_mesh(o, faces, kq);
            return;
        }
    }
    if (o->t_faces == 0 && faces >= TIMED_FROM && now > 0.0) {
        o->t_faces = faces;
        o->t_cpu = now;
        o->t_nodes = kq->nodes;
    } else if (o->t_faces > 0 && faces >= o->t_faces + TIMED_MIN && now > 0.0) {
        double nf = (double)(faces - o->t_faces);
        double us = 1e6 * (now - o->t_cpu) / nf;
        double nodes = (double)(kq->nodes - o->t_nodes) / nf;
        double ratio = us * left / (MESH_BUILD_US * (double)o->t->n + MESH_WALK_US * left);
        if (o->collective ? collective_time_vote(ratio, nodes)
                          : nodes >= SLOW_NODES && ratio > TIME_MARGIN) {
            build_mesh(o, faces, kq);
            return;
        }
    }
    o->w_faces = faces;
    o->w_points = kq->points;
    o->w_exact = kq->pc.orient_exact + kq->pc.insphere_exact;
    o->w_nodes = kq->nodes;
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

/*
 * The probe (oracle.h). A sample, not all points: its tree costs a few
 * milliseconds where the whole input's would cost a tenth of a second at
 * 1M. The structures that make the kd search expensive (a surface, rings,
 * lattice planes, cospherical shells) survive taking every k-th point, and
 * the cost a face on them still grows with the points, so 32,768 of them
 * show it: an exact cylinder of 100k points tests thousands of points a
 * face, its every third point still over a thousand, uniform points ~90.
 */
#define PROBE_POINTS 32768
#define PROBE_FACES 256

/*
 * Two samples: every k-th point (the whole object at a lower density: a
 * pipe's rings, a sphere's shell survive it) and a run of consecutive
 * input points (the local density of files written in scan or grid
 * order: an O-grid's boundary layer, an extruded grid's planes, which
 * thinning hides: 111 and 44 points a face thinned, 198 and 365 in a
 * run). Either above PROBE_SURE is clearly expensive: the threads build
 * the mesh of every point before the fronts start. Below it the parts
 * start on the kd search and measure it at the full density, and a
 * majority of them decides the same mesh (the collective switch,
 * src/par/engine.c), because no threshold on these samples separates the
 * inputs that want the mesh from those that do not. Measured (bench/NOTES.md
 * entries 54 and 59), thinned / run: uniform 89 / 69, lonestar 128 / 124,
 * citylidar 147 / 116, ogrid 111 / 198, cubedsphere 184 / 141, bunny 167,
 * autzen 180 / 256, statue 165 / 301, windcity 316 / 235, extruded 44 /
 * 365; on two threads autzen and lonestar run faster on the kd search,
 * the others on the mesh. Centre of a sphere 918 / 1,113, pipes, rotated
 * lattices and 12-digit spheres above 1,000: for them the first faces
 * measured would only delay the build. The probe stops once its running
 * cost passes PROBE_SURE x PROBE_FACES (the average can then only end
 * above it).
 */
#define PROBE_SURE 500

/* The kd search's cost a face (as fdt_oracle_tick costs it) over the k
 * points of S (a copy, which the kd build permutes); -1 if it cannot be
 * measured (no memory, a flat sample). */
static double probe_cost(double *S, uint32_t k, int leaf_size)
{
    double cost = -1.0;
    fdt_vid *orig = malloc((size_t)k * sizeof *orig);
    fdt_kdtree t = {0};
    if (!orig)
        goto done;
    for (uint32_t i = 0; i < k; i++)
        orig[i] = (fdt_vid)i;
    char diag[8];
    if (fdt_seed_check_dimension(S, orig, k, diag, sizeof diag) != FDT_OK)
        goto done;
    if (fdt_kd_build(&t, S, orig, 0, k, leaf_size > 0 ? leaf_size : FDT_DEFAULT_LEAF) != FDT_OK)
        goto done;
    fdt_front_stats st;
    memset(&st, 0, sizeof st);
    /* The decision is "above PROBE_SURE a face on average": once the
     * running cost passes PROBE_SURE * PROBE_FACES, the average over
     * however many faces the front would still run (at most PROBE_FACES)
     * can only end above it, so the front stops there with the same
     * answer. A rotated lattice's sample costs 12,392 units a face: 3 faces
     * instead of 256, 0.19 s of CPU on one thread saved before the build
     * (bench/NOTES.md entry 55). */
    const fdt_probe_budget budget = {(double)PROBE_SURE * PROBE_FACES, EXACT_WEIGHT};
    if (fdt_front_probe(&t, k / 2, PROBE_FACES, &budget, &st) != FDT_OK || st.faces_advanced == 0)
        goto done;
    double work = (double)st.kq.points +
                  EXACT_WEIGHT * (double)(st.kq.pc.orient_exact + st.kq.pc.insphere_exact);
    cost = work > budget.cost ? work / PROBE_FACES : work / (double)st.faces_advanced;
done:
    fdt_kd_free(&t);
    free(orig);
    return cost;
}

/* P[first + i * stride], i < k, copied; NULL without memory. */
static double *probe_sample(const double *P, size_t first, uint32_t stride, uint32_t k)
{
    double *S = malloc(3 * (size_t)k * sizeof *S);
    if (S)
        for (uint32_t i = 0; i < k; i++)
            memcpy(S + 3 * (size_t)i, P + 3 * (first + (size_t)i * stride), 3 * sizeof *S);
    return S;
}

/* Both samples, the first that is expensive decides (above); the run
 * only where thinning dropped points (stride > 1). */
void fdt_oracle_probe_take(fdt_probe_samples *ps, const double *P, uint32_t m, int leaf_size)
{
    uint32_t stride = m > PROBE_POINTS ? m / PROBE_POINTS : 1;
    uint32_t k = m / stride;
    ps->S[0] = ps->S[1] = NULL;
    ps->k = k < 4 ? 0 : k;
    ps->leaf_size = leaf_size;
    if (ps->k == 0)
        return;
    ps->S[0] = probe_sample(P, 0, stride, k);
    if (stride > 1)
        ps->S[1] = probe_sample(P, (size_t)(m - k) / 2, 1, k);
}

int fdt_oracle_probe_decide(fdt_probe_samples *ps)
{
    int expensive = 0;
    for (int i = 0; i < 2 && !expensive; i++)
        if (ps->S[i])
            expensive = probe_cost(ps->S[i], ps->k, ps->leaf_size) > PROBE_SURE;
    free(ps->S[0]);
    free(ps->S[1]);
    ps->S[0] = ps->S[1] = NULL;
    return expensive;
}

int fdt_oracle_probe(const double *P, uint32_t m, int leaf_size)
{
    fdt_probe_samples ps;
    fdt_oracle_probe_take(&ps, P, m, leaf_size);
    return fdt_oracle_probe_decide(&ps);
}
