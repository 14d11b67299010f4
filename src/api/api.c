/* The public entry points: settings, context, the triangulation pipeline
 * (DESIGN.md, Data flow). */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "frontdt.h"
#include "base/clock.h"
#include "base/diag.h"
#include "front/front.h"
#include "geom/kdtree.h"
#include "front/oracle.h"
#include "front/search.h"
#include "front/partmesh.h"
#include "front/sweep.h"
#include "par/parallel.h"
#include "par/threads.h"
#include "geom/morton.h"
#include "geom/prepare.h"
#include "mesh/periodic.h"
#include "mesh/result.h"
#include "mesh/query.h"
#include "mesh/voronoi.h"
#include "front/seed.h"
#include "base/sethash.h"
#include "front/sink.h"
#include "api/parts.h"

struct fdt_context {
    fdt_settings s;
    char diag[512];
};

const char *fdt_strerror(int err)
{
    switch (err) {
    case FDT_OK: return "success";
    case FDT_EINVAL: return "invalid argument";
    case FDT_ENOMEM: return "out of memory";
    case FDT_EDEGENERATE: return "degenerate input (fewer than 4 distinct points, or all coplanar)";
    case FDT_ERANGE: return "a value out of range: a coordinate NaN or infinite, or points "
                            "beyond what doubles hold for the cells (the diagnostic says which)";
    case FDT_ETOOBIG: return "too many points or tetrahedra for the index types";
    case FDT_ECHECK: return "the mesh failed verification";
    case FDT_ECANCELED: return "canceled";
    case FDT_EINTERNAL: return "internal error (a bug: please report it)";
    case FDT_ETHREAD: return "could not create a thread";
    case FDT_EIO: return "a file could not be opened, read, written or renamed";
    case FDT_EFORMAT: return "malformed input file";
    default: return "unknown error";
    }
}

const char *fdt_version(void) { return FDT_VERSION_STRING; }

/* What the library allocates for the caller (fdt_read_points) comes from
 * malloc; freeing it here keeps a caller with another allocator, or a
 * Windows-style split C runtime, from freeing it with the wrong one. */
void fdt_free(void *p) { free(p); }

/*
 * The fdt_settings sizes this library accepts (include/frontdt.h, ABI):
 * this release's, and, once a field is added, each earlier release's
 * (offsetof the first field it lacks), whose missing fields then take
 * their defaults in fdt_open.
 */
/* permute_input took what was padding after search: the first release's
 * size, which ends there, did not change. periodic (issue 33) came after
 * it: a caller of that release gives its size and gets no periodic axis. */
_Static_assert(offsetof(fdt_settings, periodic) ==
                   (offsetof(fdt_settings, search) + sizeof(fdt_search) +
                    _Alignof(fdt_settings) - 1) / _Alignof(fdt_settings) * _Alignof(fdt_settings),
               "permute_input inside the first release's size");

static int settings_size_known(size_t size)
{
    return size == sizeof(fdt_settings) || size == offsetof(fdt_settings, periodic);
}

int fdt_default_settings_sized(fdt_settings *s, size_t struct_size)
{
    if (!s)
        return FDT_EINVAL;
    if (!settings_size_known(struct_size)) {
        /* A caller built against a later header: leave it a size fdt_open
         * refuses, rather than defaults it would take for its own. */
        if (struct_size >= sizeof s->struct_size)
            s->struct_size = 0;
        return FDT_EINVAL;
    }
    fdt_settings d;
    memset(&d, 0, sizeof d);
    d.struct_size = struct_size;
    d.mode = FDT_MODE_AUTO;
    d.n_threads = 0;
    d.leaf_size = FDT_DEFAULT_LEAF;
    memcpy(s, &d, struct_size);
    return FDT_OK;
}

int fdt_open(fdt_context **ctx, const fdt_settings *s)
{
    if (!ctx)
        return FDT_EINVAL;
    *ctx = NULL;
    if (!s || !settings_size_known(s->struct_size))
        return FDT_EINVAL;
    /* The caller's bytes over the defaults: fields of a later release than
     * the caller's keep their defaults. */
    fdt_settings all;
    fdt_default_settings_sized(&all, sizeof all);
    memcpy(&all, s, s->struct_size);
    if (all.n_threads < 0 || all.n_threads > 1024 || all.leaf_size < 0 ||
        all.mode < FDT_MODE_AUTO || all.mode > FDT_MODE_MESSAGE || !fdt_search_row_of(all.search) ||
        (all.periodic & ~7u))
        return FDT_EINVAL;
    fdt_context *c = calloc(1, sizeof *c);
    if (!c)
        return FDT_ENOMEM;
    c->s = all;
    c->s.struct_size = sizeof c->s;
    if (c->s.leaf_size == 0)
        c->s.leaf_size = FDT_DEFAULT_LEAF;
    *ctx = c;
    return FDT_OK;
}

void fdt_close(fdt_context **ctx)
{
    if (!ctx)
        return;
    free(*ctx);
    *ctx = NULL;
}

const char *fdt_context_diagnostic(const fdt_context *ctx)
{
    return ctx ? ctx->diag : "";
}

/* The point whose coordinates are nearest the centre of the root box
 * (§2.1: "a node near the center of the cloud"). */
static uint32_t central_point(const fdt_kdtree *t)
{
    const fdt_kdnode *r = &t->nodes[0];
    double c[3];
    for (int k = 0; k < 3; k++)
        c[k] = r->lo[k] * 0.5 + r->hi[k] * 0.5;
    return fdt_kd_nearest(t, c, FDT_NONE, NULL);
}

/*
 * The pipeline of fdt_triangulate and fdt_triangulate_stream: user NULL
 * keeps the mesh (the in-memory sink: each thread's meshbuf, gathered and
 * renumbered at the end), else every tet and hull face leaves through the
 * caller's sink as it is built (src/front/sink.h) and the result keeps none.
 */
/* One run's state, from the prepared points to the result (run's steps). */
typedef struct run_state {
    fdt_prepared pr;
    fdt_kdtree tree;          /* serial: the one kd-tree */
    fdt_meshbuf mb;           /* the mesh, until the result takes it */
    fdt_par_out par;          /* parallel: the engine's output */
    fdt_tsink sink;
    fdt_emit em;              /* serial: the front's emitter */
    fdt_front_stats fst;
    fdt_partmesh_stats pms;   /* the one-part engine's counters */
    fdt_sweep_stats sws;      /* the sweep's counters */
    fdt_cellstream *cs;       /* streamed Voronoi cells, or NULL */
    int parts;                /* nonzero: the parts' engine ran (src/par) */
    int engine;               /* the fdt_engine that ran */
    size_t mem_tree, mem_mesh, mem_sink;
} run_state;

/* The mode and thread count the settings ask for. AUTO: serial for one
 * thread, shared otherwise; 0 threads: one per physical core. Shared and
 * message run src/par/parallel.c, which fills the same meshbuf (global
 * tree-order ids) and counters. */
static void run_mode(const fdt_settings *s, fdt_mode *mode, int *nthreads)
{
    *mode = s->mode;
    *nthreads = s->n_threads;
    if (*mode != FDT_MODE_SERIAL && *nthreads == 0)
        *nthreads = fdt_threads_default();
    if (*mode == FDT_MODE_AUTO)
        *mode = *nthreads == 1 ? FDT_MODE_SERIAL : FDT_MODE_SHARED;
}

/* The points checked, merged and scaled into pr (src/geom/prepare.h).
 * Without duplicates the map is the identity: dropped for the run (4 bytes
 * a point less at the engine's peak, a streamed 100M run's 400 MB) and
 * made again for the result once the engine's memory is gone
 * (result_dupmap). */
static int run_prepare(fdt_context *ctx, const double *xyz, size_t n, fdt_mode mode,
                       int nthreads, fdt_prepared *pr)
{
    /* The merge runs on the engine's threads in parallel modes; serial
     * mode stays sequential from end to end. */
    long cpus = sysconf(_SC_NPROCESSORS_ONLN);
    /* permute_input: the caller's array becomes the point store (the
     * const was the caller's to give up, include/frontdt.h). */
    int threads = mode == FDT_MODE_SERIAL          ? 1
                  : cpus >= 1 && nthreads > cpus ? (int)cpus
                                                 : nthreads;
    int err = ctx->s.permute_input
                  ? fdt_prepare_inplace((double *)(uintptr_t)xyz, n, threads, pr, ctx->diag,
                                        sizeof ctx->diag)
                  : fdt_prepare(xyz, n, threads, pr, ctx->diag, sizeof ctx->diag);
    if (!err && pr->ndup == 0) {
        free(pr->dupmap);
        pr->dupmap = NULL;
    }
    return err;
}

/* The result's duplicate map: pr's, or the identity run_prepare dropped. */
static int result_dupmap(fdt_prepared *pr, size_t n)
{
    if (pr->dupmap)
        return FDT_OK;
    if (!(pr->dupmap = malloc((n ? n : 1) * sizeof *pr->dupmap)))
        return FDT_ENOMEM;
    for (size_t i = 0; i < n; i++)
        pr->dupmap[i] = (fdt_vid)i;
    return FDT_OK;
}

/* The parallel engine (src/par/parallel.c); *t1: when the preparation
 * ended (partition, trees and seeds count as preparation). */
static int run_parallel(fdt_context *ctx, fdt_mode mode, int nthreads, const fdt_sink *user,
                        run_state *rs, double *t1)
{
    /* With an explicit mode or a stream: --search auto lets the probe
     * choose between the DT of every point, which every part reads its
     * apexes from, and the kd search; --search mesh runs the wall engine
     * (each part's own mesh); --search kd the paper's fronts. Either way
     * the parts, their fronts and their messages stay (src/par/
     * parallel.c, bench/NOTES.md entry 90). */
    fdt_par_opts popt;
    memset(&popt, 0, sizeof popt);
    if (user)
        popt.sink = &rs->sink;
    double tp = fdt_now_s();
    int err = fdt_parallel_run(&rs->pr, &ctx->s, mode, nthreads, &popt, &rs->par, ctx->diag,
                               sizeof ctx->diag);
    if (err)
        return err;
    rs->mb = rs->par.mb;
    memset(&rs->par.mb, 0, sizeof rs->par.mb);
    rs->fst = rs->par.fst;
    rs->parts = 1;
    *t1 = tp + rs->par.t_setup;
    return FDT_OK;
}

/* The public names of the engines (fdt_engine, include/frontdt.h). */
static const struct {
    const char *name, *about;
} engines[] = {
    [FDT_ENGINE_FRONT] = {"front", "one front, the paper's method"},
    [FDT_ENGINE_ONE_PART] = {"one-part", "the insertion mesh of every point is the answer"},
    [FDT_ENGINE_SWEEP] = {"sweep", "parts in sweep order: each slab's mesh, its final tets "
                                   "out, the rest carried"},
    [FDT_ENGINE_PARTS] = {"parts", "parts with fronts and messages, the kd search"},
    [FDT_ENGINE_PARTS_MESH] = {"parts-mesh", "parts with fronts and messages, their apexes "
                                             "from the mesh of every point"},
    [FDT_ENGINE_WALLS] = {"walls", "each part's own mesh, its final tets at once, fronts and "
                                   "messages at the walls"},
    [FDT_ENGINE_PERIODIC] = {"periodic", "the insertion mesh of the points and their images "
                                         "near the box, one copy's tets kept and proved"},
};

const char *fdt_engine_name(int e)
{
    return e >= FDT_ENGINE_FRONT && e <= FDT_ENGINE_PERIODIC ? engines[e].name : NULL;
}

const char *fdt_engine_about(int e)
{
    return e >= FDT_ENGINE_FRONT && e <= FDT_ENGINE_PERIODIC ? engines[e].about : NULL;
}

/*
 * Which engine a run takes (issue 31), a function of the settings alone.
 * The insertion engines run where the search's row lets them
 * (src/front/search.c): on one thread, or on several with the default
 * mode and no --pin (which binds the parts' threads). In memory that is
 * the one-part engine (the insertion mesh of every point, built on the
 * run's threads and certified, is the answer: no front re-derives it,
 * bench/NOTES.md entry 91); streamed, whose memory must stay bounded, the
 * parts in sweep order (src/front/sweep.h, entry 104). Every other run
 * takes the fronts: serial, or the parts' engine (src/par/parallel.c). The
 * rule's answer is an fdt_engine: FDT_ENGINE_FRONT for the fronts, which
 * on threads the parts' engine then names (fdt_par_out.engine).
 */

static fdt_engine pick_engine(const fdt_settings *s, fdt_mode mode, int streamed)
{
    const fdt_search_row *r = fdt_search_row_of(s->search);
    int insertion = mode == FDT_MODE_SERIAL
                        ? r->one_part_serial
                        : r->one_part_threads && s->mode == FDT_MODE_AUTO && !s->pin;
    return !insertion ? FDT_ENGINE_FRONT : streamed ? FDT_ENGINE_SWEEP : FDT_ENGINE_ONE_PART;
}

/* The Voronoi cells (src/mesh/voronoi.c) on the threads the options ask
 * for. */
/* Whether o asks for a box other than the periodic run's pbox, whose own
 * cells take its box alone (in memory and streamed); diag says so. */
static int periodic_box_other(const fdt_voronoi_options *o, const double pbox[6], char *diag,
                              size_t ds)
{
    if (!o->box_given || !memcmp(o->box, pbox, sizeof o->box))
        return 0;
    fdt_diag(diag, ds, "a periodic mesh's cells take its own box (the periods, and the walls "
             "across the axes that are not periodic)");
    return 1;
}

int fdt_voronoi_compute(const fdt_result *r, const double *xyz, size_t n, const fdt_voronoi_options *o,
                        fdt_voronoi **out, char *diag, size_t diag_size)
{
    fdt_voronoi_options full;
    if (diag && diag_size)
        diag[0] = 0;
    if (!o) {
        fdt_default_voronoi_options(&full);
        o = &full;
    }
    if (!r || !xyz || !out || fdt_voronoi_options_read(o, &full) != FDT_OK)
        return FDT_EINVAL;
    o = &full;
    if (o->threads < 0 || o->threads > 1024)
        return FDT_EINVAL;
    int threads = o->threads ? o->threads : fdt_threads_default();
    if (r->periodic) { /* the cells of the periodic set: its box's walls */
        if (n != r->n)
            return FDT_EINVAL;
        if (periodic_box_other(o, r->pbox, diag, diag_size))
            return FDT_EINVAL;
        fdt_periodic_box b = fdt_periodic_box_of(r->periodic, r->pbox);
        return fdt_periodic_cells(r->tets, r->tet_off, r->ntets, r->hull, r->nhull, xyz, n,
                                  r->dupmap, &b, threads, o->neighbors, o->skip, out,
                                  diag ? diag : (char[8]){0},
                                  diag ? diag_size : 8);
    }
    return fdt_voronoi_build(r, xyz, n, o, threads, out, diag, diag_size);
}

int fdt_check_periodic(const double *xyz, size_t n, const fdt_vid *tets, const int8_t *offsets,
                       size_t ntets, const fdt_vid *hull, const int8_t *hull_offsets,
                       size_t nhull, unsigned periodic, const double box[6], char *msg,
                       size_t len)
{
    const fdt_periodic_box b = {periodic, {box ? box[0] : 0, box ? box[1] : 0, box ? box[2] : 0},
                                {box ? box[3] : 0, box ? box[4] : 0, box ? box[5] : 0}};
    if (!xyz || !box || (ntets && (!tets || !offsets)) || (nhull && (!hull || !hull_offsets)) ||
        fdt_periodic_check(NULL, 0, &b, msg, len) != FDT_OK)
        return FDT_EINVAL;
    return fdt_periodic_check_mesh(xyz, n, tets, offsets, ntets, hull, hull_offsets, nhull, &b,
                                   msg, len);
}

/* Point location and interpolation (src/mesh/locate.c, interpolate.c) on
 * the threads asked for. */
int fdt_locate(fdt_result *r, const double *xyz, size_t n, const double *q, size_t nq,
               fdt_tid *tet, double *bary, int threads)
{
    if (threads < 0 || threads > 1024)
        return FDT_EINVAL;
    return fdt_locate_build(r, xyz, n, q, nq, tet, bary,
                            threads ? threads : fdt_threads_default());
}

int fdt_interpolate(fdt_result *r, const double *xyz, size_t n, const double *values,
                    size_t nv, const double *q, size_t nq, fdt_interp method, int threads,
                    double *out, char *diag, size_t diag_size)
{
    if (threads < 0 || threads > 1024)
        return FDT_EINVAL;
    return fdt_interpolate_build(r, xyz, n, values, nv, q, nq, method,
                                 threads ? threads : fdt_threads_default(), out, diag,
                                 diag_size);
}

int fdt_engine_one_part(const fdt_settings *s, int streamed)
{
    if (!s || !fdt_search_row_of(s->search))
        return 0;
    fdt_mode mode;
    int nthreads;
    run_mode(s, &mode, &nthreads);
    return pick_engine(s, mode, streamed) != FDT_ENGINE_FRONT;
}

/* The points put in order (the one-part engine: Morton order, which its
 * BRIO rounds keep and whose ranges are its threads' regions; the sweep:
 * its slabs; the serial front: its kd-tree's), then that engine on
 * nthreads threads (the front: one); *t1: when the preparation ended. */
static int run_single(fdt_context *ctx, const fdt_sink *user, fdt_engine eng, int nthreads,
                      run_state *rs, double *t1)
{
    fdt_prepared *pr = &rs->pr;
    if (eng == FDT_ENGINE_ONE_PART) {
        if (fdt_morton_sort(pr->p, pr->orig, pr->m, nthreads) != 0)
            return FDT_ENOMEM;
    } else if (eng == FDT_ENGINE_FRONT) {
        if (fdt_kd_build(&rs->tree, pr->p, pr->orig, 0, (uint32_t)pr->m, ctx->s.leaf_size) !=
            FDT_OK)
            return FDT_ENOMEM;
        rs->mem_tree = fdt_kd_bytes(&rs->tree);
    }
    if (!user &&
        fdt_meshbuf_init(&rs->mb, (size_t)(6.9 * (double)pr->m) + 64, ctx->s.neighbors) != FDT_OK)
        return FDT_ENOMEM;
    if (fdt_emit_init(&rs->em, &rs->sink, &rs->mb) != FDT_OK)
        return FDT_ENOMEM;
    *t1 = fdt_now_s();
    int err;
    if (eng == FDT_ENGINE_ONE_PART) {
        err = fdt_partmesh_emit_all(pr->p, (uint32_t)pr->m, nthreads, &rs->em,
                                    ctx->s.progress, ctx->s.progress_user, &rs->pms, ctx->diag,
                                    sizeof ctx->diag);
    } else if (eng == FDT_ENGINE_SWEEP) {
        err = fdt_sweep_emit(pr->p, pr->orig, (uint32_t)pr->m, 0, nthreads, &rs->em, rs->cs,
                             ctx->s.progress, ctx->s.progress_user, &rs->sws, ctx->diag,
                             sizeof ctx->diag);
    } else
        err = fdt_front_emit(&rs->tree, central_point(&rs->tree), ctx->s.search, &rs->em,
                             ctx->s.progress, ctx->s.progress_user, &rs->fst);
    if (!err)
        err = fdt_emit_flush(&rs->em);
    rs->mem_mesh = fdt_meshbuf_bytes(&rs->mb);
    rs->mem_sink = fdt_emit_bytes(&rs->em);
    if (err == FDT_ENOMEM) {
        /* The points' memory is known before the run, the tets' is not:
         * a mesh can be quadratic in its points (src/base/mem.h,
         * fdt_mem_fits). The one-part engine hands no tet out before its
         * mesh is whole. */
        char out[64] = "";
        if (rs->em.ntets)
            snprintf(out, sizeof out, " after %lld tetrahedra out", (long long)rs->em.ntets);
        snprintf(ctx->diag, sizeof ctx->diag,
                 "out of memory: the mesh of %zu points outgrew the memory available%s (points "
                 "on lines or circles can have a mesh of up to n^2/4 tetrahedra)",
                 pr->m, out);
    } else if (err == FDT_ECHECK && !ctx->diag[0])
        snprintf(ctx->diag, sizeof ctx->diag, "mesh certificate failed: %s",
                 rs->fst.cert_what ? rs->fst.cert_what : "?");
    else if (err == FDT_EINTERNAL && !ctx->diag[0])
        snprintf(ctx->diag, sizeof ctx->diag,
                 "internal error: the front became inconsistent after %lld tetrahedra",
                 (long long)rs->em.ntets);
    return err;
}

/* The mesh into r, in the caller's numbering (the sink's one rule,
 * fdt_sink_renumber; same width, so the buffers are reused). The parallel
 * engine's threads did that as they gathered the mesh; a streamed run's
 * tets were renumbered as they left. r takes the buffers and the
 * duplicate map. */
static void result_take(fdt_result *r, run_state *rs, const fdt_sink *user, size_t n)
{
    fdt_meshbuf *mb = &rs->mb;
    fdt_vid *tets = (fdt_vid *)mb->tets;
    fdt_vid *hull = (fdt_vid *)mb->hull;
    if (!rs->parts && !user) {
        fdt_sink_renumber(rs->pr.orig, tets, mb->tets, 4 * mb->ntets);
        fdt_sink_renumber(rs->pr.orig, hull, mb->hull, 3 * mb->nhull);
    }
    if (user) {
        r->streamed = 1;
        r->set_hash = fdt_sethash_value(&rs->sink.hash);
    }
    r->tets = tets;
    r->ntets = mb->ntets;
    r->nbrs = mb->nbrs;
    r->hull = hull;
    r->nhull = mb->nhull;
    r->dupmap = rs->pr.dupmap;
    rs->pr.dupmap = NULL;
    r->n = n;
    r->ndup = rs->pr.ndup;
    memset(mb, 0, sizeof *mb);
}

/* The run's statistics into r->stats (r->tstats takes the threads'):
 * t0, t1, t2 the start, the end of the preparation and of the front. */
static void result_stats(fdt_result *r, run_state *rs, fdt_mode mode, int nthreads,
                         const fdt_sink *user, size_t n, double t0, double t1, double t2)
{
    const fdt_prepared *pr = &rs->pr;
    const fdt_front_stats *fst = &rs->fst;
    const fdt_partmesh_stats *pms = &rs->pms;
    fdt_stats *st = &r->stats;
    st->points = n;
    st->vertices = pr->m;
    st->tets = user ? rs->sink.ntets : r->ntets;
    st->hull_faces = user ? rs->sink.nhull : r->nhull;
    st->faces_advanced = fst->faces_advanced;
    st->kd_nodes_visited = fst->kq.nodes;
    st->points_tested = fst->kq.points;
    st->exact_orient = fst->kq.pc.orient_exact;
    st->exact_insphere = fst->kq.pc.insphere_exact;
    st->adapt_orient = fst->kq.pc.orient_adapt;
    st->adapt_insphere = fst->kq.pc.insphere_adapt;
    st->max_front = fst->max_front;
    st->mesh_faces = fst->mesh_faces;
    const fdt_sweep_stats *sws = &rs->sws;
    st->mesh_parts = fst->mesh_parts + (pms->final_tets > 0) + sws->parts;
    st->t_mesh = fst->t_mesh + pms->t_mesh + sws->t_mesh;
    st->final_tets = pms->final_tets + fst->final_tets + sws->final_tets;
    st->certified_tets = pms->certified_tets + fst->certified_tets + sws->certified_tets;
    st->t_certify = pms->t_certify + fst->t_certify + sws->t_certify;
    st->ins_conflict_tests = pms->ins.conflict_tests + sws->ins.conflict_tests;
    st->ins_deferred = pms->ins.deferred + sws->ins.deferred;
    st->ins_serial = pms->ins.serial_finish + sws->ins.serial_finish;
    st->exact_orient += pms->pc.orient_exact + sws->pc.orient_exact;
    st->exact_insphere += pms->pc.insphere_exact + sws->pc.insphere_exact;
    st->adapt_orient += pms->pc.orient_adapt + sws->pc.orient_adapt;
    st->adapt_insphere += pms->pc.insphere_adapt + sws->pc.insphere_adapt;
    st->sweep_parts = sws->parts;
    st->sweep_reinserted = sws->reinserted;
    st->sweep_max_part = sws->max_part;
    if (rs->cs) {
        st->cell_batches = rs->cs->batches;
        st->cell_held_max = rs->cs->max_held;
        st->t_cells = sws->t_cells;
    }
    st->threads = nthreads;
    st->mode = mode;
    st->engine = rs->engine;
    /* Memory (include/frontdt.h): the points' three arrays, then each
     * structure at its largest. */
    st->mem_points = pr->m * (3 * sizeof *pr->p + sizeof *pr->orig) +
                     (pr->ndup ? n * sizeof *pr->dupmap : 0);
    st->mem_merge = pr->merge_bytes;
    st->mem_tree = rs->mem_tree;
    st->mem_front = fst->mem_front;
    st->mem_mesh = rs->mem_mesh > rs->sws.mem_part ? rs->mem_mesh : rs->sws.mem_part;
    st->mem_sink = rs->mem_sink;
    st->t_prepare = t1 - t0;
    st->t_front = t2 - t1;
    st->t_finish = fdt_now_s() - t2;
    if (rs->parts) {
        fdt_parallel_fill_stats(&rs->par, mode, st);
        st->t_front = rs->par.t_front;
        st->t_finish += rs->par.t_gather;
        r->tstats = rs->par.tstats;
        rs->par.tstats = NULL;
        st->mem_tree = rs->par.pst.mem_tree;
        st->mem_front = rs->par.pst.mem_front;
        st->mem_mesh = rs->par.pst.mem_mesh;
        st->mem_sink = rs->par.pst.mem_sink;
    }
}

/* The streamed cells' state for the prepared points, when the engine is
 * the sweep (the one whose parts say when a point's last tet is out). */
static int cells_setup(fdt_context *ctx, fdt_cellstream *cs, fdt_engine eng,
                       const fdt_prepared *pr)
{
    if (eng != FDT_ENGINE_SWEEP) {
        snprintf(ctx->diag, sizeof ctx->diag, "streamed Voronoi cells need the parts in sweep "
                 "order: search auto, mode auto or serial, no pin");
        return FDT_EINVAL;
    }
    cs->p_exp = pr->scale_exp;
    return fdt_cellstream_init(cs, pr->m);
}

/* A streamed run's cells over: the least edge too short for them, if any. */
static int cells_done(fdt_context *ctx, const fdt_cellstream *cs)
{
    if (cs->sh.a < 0)
        return FDT_OK;
    return fdt_voronoi_too_close(&cs->sh, cs->box, ctx->diag, sizeof ctx->diag);
}

/* The box of a periodic run scaled as the prepared points were (by a
 * power of two: exact unless it leaves the doubles' range). */
static int periodic_box_scaled(fdt_context *ctx, int e, fdt_periodic_box *b)
{
    for (int k = 0; k < 3; k++) {
        if (!(b->axes >> k & 1)) {
            /* a wall of the cells (the mesh has none there): the points'
             * scale, exactly where it holds (else the cells' box is out
             * of range and refused) */
            b->lo[k] = ldexp(b->lo[k], e);
            b->hi[k] = ldexp(b->hi[k], e);
            continue;
        }
        double lo = ldexp(b->lo[k], e), hi = ldexp(b->hi[k], e);
        if (ldexp(lo, -e) != b->lo[k] || ldexp(hi, -e) != b->hi[k] || !isfinite(hi - lo)) {
            snprintf(ctx->diag, sizeof ctx->diag, "the periodic box's %c side [%.17g, %.17g) "
                     "is too far from the points' scale", "xyz"[k], b->lo[k], b->hi[k]);
            return FDT_ERANGE;
        }
        b->lo[k] = lo;
        b->hi[k] = hi;
    }
    return FDT_OK;
}

/*
 * A periodic run streamed: the slabs of fdt_periodic_parts, the sweep's
 * points a slab (fdt_sweep_slab), each part's rows renumbered to input
 * ids, hashed and handed to the sink, and with cells (cs) its points'
 * cells from their stars in its mesh (fdt_periodic_part_cells) handed to
 * cs's sink, then freed; the progress after each part. *sum gets the
 * counts (images summed, the most rounds, rows).
 */
static int periodic_stream(fdt_context *ctx, const fdt_prepared *pr, const fdt_periodic_box *b,
                           int nthreads, const fdt_sink *user, fdt_cellstream *cs,
                           const unsigned share[2], fdt_periodic_mesh *sum, fdt_sethash *h,
                           size_t *nparts)
{
    fdt_periodic_parts parts;
    /* a share of the parts (frontdt-mpi): at least a part a sharer */
    uint64_t slab = fdt_sweep_slab(pr->m), each = (pr->m + share[1] - 1) / share[1];
    int err = fdt_periodic_parts_make(pr->p, (uint32_t)pr->m, b,
                                      (uint32_t)(each && each < slab ? each : slab), &parts);
    if (err)
        return err;
    *nparts = parts.nparts;
    for (uint32_t k = share[0]; k < parts.nparts && !err; k += share[1]) {
        fdt_periodic_mesh pm;
        err = fdt_periodic_build_part(pr->p, (uint32_t)pr->m, pr->orig, b, &parts, k, nthreads,
                                      cs != NULL, &pm, ctx->diag, sizeof ctx->diag);
        if (!err && cs) {
            fdt_voronoi *v = NULL;
            fdt_vshort sh = {-1, -1, 0};
            err = fdt_periodic_part_cells(&pm, pr->p, (uint32_t)pr->m, pr->scale_exp, pr->orig,
                                          &parts, k, b, nthreads, cs->neighbors, cs->skip, &v, &sh,
                                          ctx->diag, sizeof ctx->diag);
            err = fdt_cellstream_give(cs, err, v, &sh);
            fdt_voronoi_free(&v);
        }
        if (!err)
            err = fdt_periodic_renumber(&pm, pr->orig, pr->m);
        if (!err) {
            fdt_sethash_add_periodic(h, pm.tets, pm.tet_off, pm.ntets);
            int u = pm.ntets ? user->periodic_tets(user->user, (const fdt_vid *)pm.tets,
                                                   pm.tet_off, pm.ntets)
                             : 0;
            if (!u && pm.nhull && user->periodic_hull)
                u = user->periodic_hull(user->user, (const fdt_vid *)pm.hull, pm.hull_off,
                                        pm.nhull);
            err = u ? fdt_sink_code(u) : FDT_OK;
        }
        sum->images += pm.images;
        sum->rounds = pm.rounds > sum->rounds ? pm.rounds : sum->rounds;
        sum->ntets += pm.ntets;
        sum->nhull += pm.nhull;
        fdt_pred_counts_add(&sum->pc, &pm.pc);
        fdt_periodic_free(&pm);
        if (!err && ctx->s.progress &&
            ctx->s.progress(ctx->s.progress_user, (double)(k + 1) / parts.nparts))
            err = FDT_ECANCELED;
    }
    fdt_periodic_parts_free(&parts);
    return err;
}

/*
 * A periodic run (settings.periodic, src/mesh/periodic.h), as a list of
 * steps: the box and the points in it (named by input index), the merge
 * and scaling every run does, the periodic mesh of the distinct points
 * (in memory: one part, renumbered to input indices; streamed: slab after
 * slab to the sink).
 */
static int run_periodic(fdt_context *ctx, const double *xyz, size_t n, const fdt_sink *user,
                        fdt_cellstream *cs, const unsigned share[2], fdt_result **out)
{
    fdt_mode mode;
    int nthreads;
    run_mode(&ctx->s, &mode, &nthreads);
    if (mode == FDT_MODE_SERIAL)
        nthreads = 1;
    double t0 = fdt_now_s();
    const double *bx = ctx->s.periodic_box;
    fdt_periodic_box b = fdt_periodic_box_of(ctx->s.periodic, bx);
    fdt_prepared pr;
    memset(&pr, 0, sizeof pr);
    fdt_periodic_mesh pm;
    memset(&pm, 0, sizeof pm);
    fdt_sethash h = {0, 0};
    size_t nparts = 1;
    fdt_result *r = NULL;
    int err = fdt_periodic_check(xyz, n, &b, ctx->diag, sizeof ctx->diag);
    if (!err)
        err = run_prepare(ctx, xyz, n, mode, nthreads, &pr);
    if (!err && pr.m > UINT32_MAX / 2)
        err = FDT_ETOOBIG;
    if (!err)
        err = periodic_box_scaled(ctx, pr.scale_exp, &b);
    double t1 = fdt_now_s();
    if (!err && cs && !(err = fdt_cellstream_init(cs, pr.m)))
        cs->p_exp = pr.scale_exp;
    if (!err && user) {
        err = periodic_stream(ctx, &pr, &b, nthreads, user, cs, share, &pm, &h, &nparts);
    } else if (!err) {
        err = fdt_periodic_build(pr.p, (uint32_t)pr.m, pr.orig, &b, nthreads, &pm, ctx->diag,
                                 sizeof ctx->diag);
        if (!err)
            err = fdt_periodic_renumber(&pm, pr.orig, pr.m);
    }
    /* the cells' end: the least edge too short for them, if any, then the
     * merged duplicates' rows, the last batch */
    if (!err && cs)
        err = cells_done(ctx, cs);
    if (!err && cs && pr.dupmap && (!share || share[0] == 0))
        err = fdt_cellstream_merged(cs, pr.dupmap, n, pr.p, pr.orig, pr.m);
    double t2 = fdt_now_s();
    if (!err)
        err = result_dupmap(&pr, n);
    if (!err && !(r = calloc(1, sizeof *r)))
        err = FDT_ENOMEM;
    if (err) {
        if (err == FDT_ENOMEM && !ctx->diag[0])
            snprintf(ctx->diag, sizeof ctx->diag, "out of memory triangulating %zu points", n);
        if (err == FDT_ECANCELED && !ctx->diag[0])
            snprintf(ctx->diag, sizeof ctx->diag, "canceled");
        fdt_periodic_free(&pm);
        fdt_prepared_free(&pr);
        return err;
    }
    r->periodic = ctx->s.periodic;
    memcpy(r->pbox, ctx->s.periodic_box, sizeof r->pbox);
    r->sorted = 1;
    r->streamed = user != NULL;
    r->set_hash = fdt_sethash_value(&h);
    r->tets = (fdt_vid *)pm.tets;
    r->tet_off = pm.tet_off;
    r->ntets = user ? 0 : pm.ntets;
    r->hull = (fdt_vid *)pm.hull;
    r->hull_off = pm.hull_off;
    r->nhull = user ? 0 : pm.nhull;
    r->dupmap = pr.dupmap;
    pr.dupmap = NULL;
    r->n = n;
    r->ndup = pr.ndup;
    fdt_stats *st = &r->stats;
    st->points = n;
    st->vertices = pr.m;
    st->tets = pm.ntets;
    st->hull_faces = pm.nhull;
    st->exact_orient = pm.pc.orient_exact;
    st->exact_insphere = pm.pc.insphere_exact;
    st->threads = nthreads;
    st->mode = mode;
    st->engine = FDT_ENGINE_PERIODIC;
    st->periodic_images = pm.images;
    st->periodic_rounds = (size_t)pm.rounds;
    st->sweep_parts = user ? nparts : 0;
    st->mem_points = pr.m * (3 * sizeof *pr.p + sizeof *pr.orig) +
                     (pr.ndup ? n * sizeof *pr.dupmap : 0);
    st->mem_merge = pr.merge_bytes;
    st->t_prepare = t1 - t0;
    st->t_front = t2 - t1;
    st->t_finish = fdt_now_s() - t2;
    fdt_prepared_free(&pr);
    if (ctx->s.progress)
        ctx->s.progress(ctx->s.progress_user, 1.0);
    *out = r;
    return FDT_OK;
}

/* A sink that takes a periodic run's rows. */
static int periodic_sink_ok(const fdt_sink *sink)
{
    return sink->struct_size >= sizeof(fdt_sink) && sink->periodic_tets;
}

static int run(fdt_context *ctx, const double *xyz, size_t n, const fdt_sink *user,
               fdt_cellstream *cs, fdt_result **out)
{
    if (!ctx || !out || (!xyz && n))
        return FDT_EINVAL;
    *out = NULL;
    ctx->diag[0] = '\0';
    if (user && ctx->s.neighbors) { /* a streamed run keeps no tet to link */
        snprintf(ctx->diag, sizeof ctx->diag, "a streamed run has no neighbours");
        return FDT_EINVAL;
    }
    if (ctx->s.periodic) {
        if (ctx->s.neighbors || (user && !periodic_sink_ok(user))) {
            snprintf(ctx->diag, sizeof ctx->diag, "%s",
                     ctx->s.neighbors ? "a periodic run has no neighbours"
                                      : "a periodic run streams to a sink with periodic_tets set");
            return FDT_EINVAL;
        }
        static const unsigned all[2] = {0, 1};
        return run_periodic(ctx, xyz, n, user, cs, all, out);
    }
    if (user && !user->tets) {
        snprintf(ctx->diag, sizeof ctx->diag, "the sink has no tets callback");
        return FDT_EINVAL;
    }
    fdt_mode mode;
    int nthreads;
    run_mode(&ctx->s, &mode, &nthreads);
    double t0 = fdt_now_s();
    run_state rs;
    memset(&rs, 0, sizeof rs);
    fdt_result *r = NULL;
    if (fdt_tsink_init(&rs.sink, NULL, user) != FDT_OK)
        return FDT_ENOMEM;
    int err = run_prepare(ctx, xyz, n, mode, nthreads, &rs.pr);
    if (err) {
        fdt_tsink_free(&rs.sink);
        return err;
    }
    rs.sink.orig = rs.pr.orig;
    if ((err = fdt_seed_check_dimension(rs.pr.p, rs.pr.orig, (uint32_t)rs.pr.m, ctx->diag,
                                        sizeof ctx->diag)) != FDT_OK)
        goto fail;
    double t1 = 0.0;
    fdt_engine eng = pick_engine(&ctx->s, mode, user != NULL);
    if (mode == FDT_MODE_SERIAL)
        nthreads = 1;
    if (cs && (err = cells_setup(ctx, cs, eng, &rs.pr)) != FDT_OK)
        goto fail;
    rs.cs = cs;
    err = eng != FDT_ENGINE_FRONT || mode == FDT_MODE_SERIAL
              ? run_single(ctx, user, eng, nthreads, &rs, &t1)
              : run_parallel(ctx, mode, nthreads, user, &rs, &t1);
    rs.engine = rs.parts ? rs.par.engine : (int)eng;
    if (!err && cs)
        err = cells_done(ctx, cs);
    if (err)
        goto fail;
    /* the merged duplicates' rows, the cells' last batch */
    if (cs && rs.pr.dupmap &&
        (err = fdt_cellstream_merged(cs, rs.pr.dupmap, n, rs.pr.p, rs.pr.orig, rs.pr.m)))
        goto fail;
    double t2 = fdt_now_s();
    if ((err = result_dupmap(&rs.pr, n)) != FDT_OK)
        goto fail;
    err = FDT_ENOMEM;
    r = calloc(1, sizeof *r);
    if (!r)
        goto fail;
    result_take(r, &rs, user, n);
    result_stats(r, &rs, mode, nthreads, user, n, t0, t1, t2);
    fdt_emit_free(&rs.em);
    fdt_tsink_free(&rs.sink);
    fdt_kd_free(&rs.tree);
    fdt_prepared_free(&rs.pr);
    if (ctx->s.progress)
        ctx->s.progress(ctx->s.progress_user, 1.0);
    *out = r;
    return FDT_OK;
fail:
    if (err == FDT_ENOMEM && !ctx->diag[0])
        snprintf(ctx->diag, sizeof ctx->diag, "out of memory triangulating %zu points", n);
    if (err == FDT_ECANCELED && !ctx->diag[0])
        snprintf(ctx->diag, sizeof ctx->diag, "canceled");
    fdt_emit_free(&rs.em);
    fdt_tsink_free(&rs.sink);
    fdt_meshbuf_free(&rs.mb);
    fdt_par_out_free(&rs.par);
    fdt_kd_free(&rs.tree);
    fdt_prepared_free(&rs.pr);
    fdt_result_free(&r);
    return err;
}

int fdt_triangulate(fdt_context *ctx, const double *xyz, size_t n, fdt_result **out)
{
    return run(ctx, xyz, n, NULL, NULL, out);
}

/* A caller's tet sink as compiled against this header or a later one, or
 * against the release before periodic_tets (ABI: the smaller size): tets
 * set, or periodic_tets (run refuses what does not fit the settings). */
static int sink_ok(const fdt_sink *sink)
{
    return sink->struct_size >= offsetof(fdt_sink, periodic_tets) &&
           (sink->tets || periodic_sink_ok(sink));
}

int fdt_triangulate_stream(fdt_context *ctx, const double *xyz, size_t n,
                           const fdt_sink *sink, fdt_result **out)
{
    if (!ctx || !out || !sink || !sink_ok(sink))
        return FDT_EINVAL;
    *out = NULL;
    return run(ctx, xyz, n, sink, NULL, out);
}

/* The tets of a cells-only stream: counted and hashed by the sink, then
 * dropped. */
static int drop_tets(void *user, const fdt_vid *tets, size_t count)
{
    (void)user;
    (void)tets;
    (void)count;
    return 0;
}

static int drop_rows(void *user, const fdt_vid *rows, const int8_t *offsets, size_t count)
{
    (void)offsets;
    return drop_tets(user, rows, count);
}

/* A periodic run's cells' box (fdt_periodic_cells_box of its periods) into
 * cs, after the points' checks (the run's against the periods first, then
 * the walls'); o's box, when given, must be the periodic box (as
 * fdt_voronoi_compute asks). */
static int periodic_cells_box(fdt_context *ctx, const double *xyz, size_t n,
                              const fdt_voronoi_options *o, fdt_cellstream *cs)
{
    const double *bx = ctx->s.periodic_box;
    if (periodic_box_other(o, bx, ctx->diag, sizeof ctx->diag))
        return FDT_EINVAL;
    fdt_periodic_box b = fdt_periodic_box_of(ctx->s.periodic, bx);
    int err = fdt_periodic_check(xyz, n, &b, ctx->diag, sizeof ctx->diag);
    if (!err)
        err = fdt_periodic_cells_check(xyz, n, &b, ctx->diag, sizeof ctx->diag);
    if (err)
        return err;
    fdt_periodic_cells_box(&b, cs->box);
    return fdt_voronoi_scale(cs->box, &cs->ed, ctx->diag, sizeof ctx->diag);
}

/* A cells stream's state for o and cells (checked), its box and scale
 * before any work (xyz is the caller's still: a permuted input is moved
 * by the run). The bounding box of the distinct points is that of all of
 * them. */
static int cells_open(fdt_context *ctx, const double *xyz, size_t n, const fdt_voronoi_options *o,
                      const fdt_cell_sink *cells, fdt_cellstream *cs)
{
    memset(cs, 0, sizeof *cs);
    cs->neighbors = o->neighbors;
    cs->skip = o->skip;
    cs->sink = cells;
    int err = FDT_OK;
    if (ctx->s.periodic) {
        err = periodic_cells_box(ctx, xyz, n, o, cs);
    } else {
        err = fdt_voronoi_box_of(xyz, NULL, n, o, cs->box, ctx->diag, sizeof ctx->diag);
        /* no finite point: the run refuses the input, with its own message */
        if (!err && cs->box[0] <= cs->box[3])
            err = fdt_voronoi_scale(cs->box, &cs->ed, ctx->diag, sizeof ctx->diag);
    }
    return err;
}

/* o (NULL: the defaults) and cells as fdt_voronoi_stream takes them:
 * usable, with *o then full, this library's whole struct. */
static int cells_ok(const fdt_voronoi_options **o, fdt_voronoi_options *full,
                    const fdt_cell_sink *cells)
{
    if (!*o)
        fdt_default_voronoi_options(full);
    else if (fdt_voronoi_options_read(*o, full) != FDT_OK)
        return 0;
    *o = full;
    return cells->struct_size >= sizeof(fdt_cell_sink) && cells->cells;
}

int fdt_triangulate_stream_parts(fdt_context *ctx, const double *xyz, size_t n,
                                 const fdt_sink *sink, const fdt_voronoi_options *o,
                                 const fdt_cell_sink *cells, unsigned first, unsigned stride,
                                 fdt_result **out)
{
    fdt_voronoi_options full;
    if (!ctx || !out || !sink || (!xyz && n) || !stride || first >= stride ||
        (cells && !cells_ok(&o, &full, cells)))
        return FDT_EINVAL;
    *out = NULL;
    ctx->diag[0] = '\0';
    if (!ctx->s.periodic || ctx->s.neighbors || !periodic_sink_ok(sink)) {
        snprintf(ctx->diag, sizeof ctx->diag, "a share of the parts is a periodic run's, "
                 "streamed to periodic_tets");
        return FDT_EINVAL;
    }
    const unsigned share[2] = {first, stride};
    fdt_cellstream cs;
    int err = cells ? cells_open(ctx, xyz, n, o, cells, &cs) : FDT_OK;
    if (!err)
        err = run_periodic(ctx, xyz, n, sink, cells ? &cs : NULL, share, out);
    if (cells)
        fdt_cellstream_free(&cs);
    return err;
}

int fdt_voronoi_stream(fdt_context *ctx, const double *xyz, size_t n,
                       const fdt_voronoi_options *o, const fdt_sink *sink,
                       const fdt_cell_sink *cells, fdt_result **out)
{
    fdt_voronoi_options full;
    if (!ctx || !out || (!xyz && n) || !cells || !cells_ok(&o, &full, cells) ||
        (sink && !sink_ok(sink)))
        return FDT_EINVAL;
    *out = NULL;
    ctx->diag[0] = '\0';
    fdt_sink dropped = {sizeof dropped, drop_tets, NULL, NULL, drop_rows, NULL};
    fdt_cellstream cs;
    int err = cells_open(ctx, xyz, n, o, cells, &cs);
    if (!err)
        err = run(ctx, xyz, n, sink ? sink : &dropped, &cs, out);
    fdt_cellstream_free(&cs);
    return err;
}
