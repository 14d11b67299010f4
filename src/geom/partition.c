/* Recursive coordinate bisection into N parts; see partition.h. */
#include "geom/partition.h"
#include "base/spawn.h"

#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

void fdt_partition_free(fdt_partition *pt)
{
    if (pt->trees)
        for (int p = 0; p < pt->nparts; p++)
            fdt_kd_free(&pt->trees[p]);
    free(pt->trees);
    free(pt->nodes);
    free(pt->start);
    memset(pt, 0, sizeof *pt);
}

typedef struct rcb_ctx {
    fdt_partition *pt;
    double *P;
    fdt_vid *orig;
} rcb_ctx;

/*
 * Points to move from the left side of a cut to the right so that both
 * build the same share of tets rather than hold the same share of points.
 * The left side owns every tet across the cut (§3.2: the lowest id
 * decides, and the left side's ids are the lower ones), about
 * 7.8 A lambda^(2/3) of them for a cut of area A through lambda points a
 * unit volume: measured at 1M uniform points, where a cube cut in half
 * had 78k tets across it, a half cube's cut 40k and a quarter's 19k, and
 * the first part built 2.3 % more tets than the last of two, 7 % more of
 * eight. Half of that surplus, at 6.75 tets a point, is
 * 0.578 n^(2/3) V^(1/3) / w points for n points in a box of volume V cut
 * across its extent w. Where the density is far from uniform the estimate
 * is only a guess, so it moves at most a sixteenth of the left side; a
 * flat box (V = 0) and parts of fewer than 64 points move nothing.
 */
static uint32_t work_shift(const fdt_pnode *nd, uint32_t nleft, uint64_t count, double w,
                           int a)
{
    double v = (nd->hi[0] - nd->lo[0]) * (nd->hi[1] - nd->lo[1]) * (nd->hi[2] - nd->lo[2]);
    /* parts of fewer than 64 points: leave their counts as they are */
    if (!(v > 0.0 && w > 0.0) || nleft / (uint32_t)a < 64)
        return 0;
    double c = (double)count, shift = 0.578 * cbrt(c * c * v) / w;
    double most = (double)(nleft / 16);
    return (uint32_t)(shift < most ? shift : most);
}

/*
 * Fills node `id` with ids [begin, end) shared by parts [p0, p0 + k).
 * The paper splits at the mean and alternates x, y, z (§3.1); we split at
 * an exact count (selection) along the widest extent, which gives equal
 * parts for any k (not only powers of two) and keeps parts compact on
 * flat or elongated clouds. With k = a + b, a = k / 2, the first a parts
 * get round(count * a / k) points, less work_shift's share for the tets
 * across the cut that they own. Depth is log2(k) <= 10.
 */
static void rcb(rcb_ctx *rc, int id, uint32_t begin, uint32_t end, int p0,
                int k)
{
    fdt_partition *pt = rc->pt;
    fdt_pnode *nd = &pt->nodes[id];
    fdt_points_box(rc->P, begin, end, nd->lo, nd->hi);
    nd->begin = begin;
    nd->end = end;
    if (k == 1) {
        nd->dim = 0;
        nd->left = -1;
        nd->part = p0;
        pt->start[p0] = begin;
        return;
    }
    nd->part = -1;
    nd->dim = 0;
    int a = k / 2;
    uint64_t count = end - begin;
    /* round(count * a / k), in integers: count < 2^32, a < 2^10. */
    uint32_t nleft = (uint32_t)((2 * count * (uint64_t)a + (uint64_t)k) / (2 * (uint64_t)k));
    if (nleft > 0 && nleft < count) {
        int dim = 0;
        double w = nd->hi[0] - nd->lo[0];
        for (int d = 1; d < 3; d++)
            if (nd->hi[d] - nd->lo[d] > w) {
                w = nd->hi[d] - nd->lo[d];
                dim = d;
            }
        nleft -= work_shift(nd, nleft, count, w, a);
        fdt_kd_select(rc->P, rc->orig, begin, end, begin + nleft, dim);
        nd->dim = dim;
    }
    int left = pt->nnodes;
    pt->nnodes += 2;
    nd->left = left;
    rcb(rc, left, begin, begin + nleft, p0, a);
    rcb(rc, left + 1, begin + nleft, end, p0 + a, k - a);
}

/*
 * The region of every part below node id, whose own region is [lo, hi]:
 * as the kd-tree's cells (src/geom/kdtree.c, climb_tables), the left child's
 * region ends at the right child's smallest coordinate on the split axis
 * and the right child's begins at the left child's largest, so each part's
 * region holds its points and no other part's point inside it (they may
 * lie on its boundary). An empty child's box (lo > hi) leaves its
 * sibling's region unbounded on that side.
 */
static void regions(const fdt_partition *pt, int id, const double lo[3], const double hi[3],
                    double (*out)[2][3])
{
    const fdt_pnode *nd = &pt->nodes[id];
    if (nd->left < 0) {
        memcpy(out[nd->part][0], lo, 3 * sizeof *lo);
        memcpy(out[nd->part][1], hi, 3 * sizeof *hi);
        return;
    }
    const fdt_pnode *l = &pt->nodes[nd->left], *r = l + 1;
    int d = nd->dim;
    double llo[3], lhi[3], rlo[3], rhi[3];
    memcpy(llo, lo, sizeof llo);
    memcpy(lhi, hi, sizeof lhi);
    memcpy(rlo, lo, sizeof rlo);
    memcpy(rhi, hi, sizeof rhi);
    if (r->begin < r->end && r->lo[d] < lhi[d])
        lhi[d] = r->lo[d];
    if (l->begin < l->end && l->hi[d] > rlo[d])
        rlo[d] = l->hi[d];
    regions(pt, nd->left, llo, lhi, out);
    regions(pt, nd->left + 1, rlo, rhi, out);
}

/*
 * The parts' trees are independent (each permutes only its own id range
 * of P and orig), and each is built in jobs (fdt_kd_run): a job over more
 * than `grain` points builds its node and leaves its two halves as jobs,
 * a smaller one builds its whole subtree. So the builders share every
 * tree's work, not only whole trees: with one tree a builder, the second
 * of two builders started 4 ms late (the probe's thread, src/par/parallel.c,
 * held the other core) and its tree ended 4 ms after the first
 * (bench/NOTES.md entry 76). The jobs wait on a stack under a mutex:
 * about 2 n / grain of them, each a few hundred microseconds of work.
 */
typedef struct tree_jobs {
    fdt_partition *pt;
    double (*region)[2][3]; /* each part's (regions()) */
    uint32_t grain;
    pthread_mutex_t mu;     /* guards stack, nstack, busy */
    fdt_kd_job *stack;
    size_t nstack;
    size_t busy;            /* jobs taken and not yet done */
    /* The next part to end (fdt_kd_end). Relaxed: the counter only hands
     * out each index once; what a builder wrote is published to the
     * caller by pthread_join. */
    atomic_int next_end;
    /* Set (relaxed) by a builder that ran out of memory; read after the
     * joins, which order it. */
    atomic_int failed;
} tree_jobs;

/* Takes a job (1), or 0 once every job is done. Waits while the stack is
 * empty and others still run jobs that may leave more. */
static int take_job(tree_jobs *j, fdt_kd_job *job)
{
    pthread_mutex_lock(&j->mu);
    while (j->nstack == 0 && j->busy > 0) {
        pthread_mutex_unlock(&j->mu);
        sched_yield();
        pthread_mutex_lock(&j->mu);
    }
    int got = j->nstack > 0;
    if (got) {
        *job = j->stack[--j->nstack];
        j->busy++;
    }
    pthread_mutex_unlock(&j->mu);
    return got;
}

/* A job is done, leaving nk more (kids); the stack has room for every
 * job there will ever be (fdt_partition_build). */
static void done_job(tree_jobs *j, const fdt_kd_job *kids, int nk)
{
    pthread_mutex_lock(&j->mu);
    for (int i = 0; i < nk; i++)
        j->stack[j->nstack++] = kids[i];
    j->busy--;
    pthread_mutex_unlock(&j->mu);
}

static void *build_trees(void *arg)
{
    tree_jobs *j = arg;
    fdt_partition *pt = j->pt;
    fdt_kd_job job, kids[2];
    while (take_job(j, &job))
        done_job(j, kids, fdt_kd_run(&job, j->grain, kids));
    for (;;) {
        int p = atomic_fetch_add_explicit(&j->next_end, 1, memory_order_relaxed);
        if (p >= pt->nparts)
            return NULL;
        if (pt->start[p + 1] == pt->start[p] || !pt->trees[p].nodes)
            continue; /* empty, or its fdt_kd_begin failed (failed is set) */
        if (fdt_kd_end(&pt->trees[p]) != FDT_OK)
            atomic_store_explicit(&j->failed, 1, memory_order_relaxed);
        else
            fdt_kd_set_region(&pt->trees[p], j->region[p][0], j->region[p][1]);
    }
}

int fdt_partition_build(fdt_partition *pt, double *P, fdt_vid *orig,
                        uint32_t m, int nparts, int leaf_size, int nworkers)
{
    memset(pt, 0, sizeof *pt);
    if (nparts < 1 || nparts > FDT_PARTITION_MAX)
        return FDT_EINVAL;
    pt->nparts = nparts;
    pt->m = m;
    pt->start = malloc(((size_t)nparts + 1) * sizeof *pt->start);
    pt->nodes = malloc((2 * (size_t)nparts - 1) * sizeof *pt->nodes);
    pt->trees = calloc((size_t)nparts, sizeof *pt->trees);
    if (!pt->start || !pt->nodes || !pt->trees) {
        fdt_partition_free(pt);
        return FDT_ENOMEM;
    }
    pt->nnodes = 1;
    rcb_ctx rc = {pt, P, orig};
    rcb(&rc, 0, 0, m, 0, nparts);
    pt->start[nparts] = m;
    double(*region)[2][3] = malloc((size_t)nparts * sizeof *region);
    if (!region) {
        fdt_partition_free(pt);
        return FDT_ENOMEM;
    }
    const double all_lo[3] = {-INFINITY, -INFINITY, -INFINITY};
    const double all_hi[3] = {INFINITY, INFINITY, INFINITY};
    regions(pt, 0, all_lo, all_hi, region);
    tree_jobs j;
    memset(&j, 0, sizeof j);
    j.pt = pt;
    j.region = region;
    /* Jobs of 4,096 points at least (a few hundred microseconds), and
     * some 16 a builder where the points allow. */
    j.grain = m / (16 * (uint32_t)(nworkers > 0 ? nworkers : 1));
    if (j.grain < 4096)
        j.grain = 4096;
    /* Room for every job: the roots and two a split. A split job holds
     * more than grain points, those of one depth are disjoint, so at most
     * m / grain of them a depth (and m / grain <= 16 nworkers); a split
     * leaves its larger half at most 2/3 of its points (left_count in
     * src/geom/kdtree.c), so the splits go at most log_{3/2}(m / grain) + 1 deep,
     * under 20 for 64 builders: 64 depths is room to spare. */
    size_t cap = (size_t)nparts + 2 * 64 * ((size_t)m / j.grain + 1);
    j.stack = malloc(cap * sizeof *j.stack);
    if (!j.stack || pthread_mutex_init(&j.mu, NULL) != 0) {
        free(j.stack);
        free(region);
        fdt_partition_free(pt);
        return FDT_ENOMEM;
    }
    atomic_init(&j.next_end, 0);
    atomic_init(&j.failed, 0);
    /* The roots, the last part's first (the stack is taken from the top). */
    for (int p = nparts - 1; p >= 0; p--) {
        uint32_t n = pt->start[p + 1] - pt->start[p];
        if (n == 0)
            continue;
        if (fdt_kd_begin(&pt->trees[p], P, orig, pt->start[p], n, leaf_size,
                         &j.stack[j.nstack]) != FDT_OK) {
            atomic_store_explicit(&j.failed, 1, memory_order_relaxed);
            continue;
        }
        j.nstack++;
    }
    if (nworkers > FDT_BUILDERS_MAX)
        nworkers = FDT_BUILDERS_MAX;
    pthread_t th[FDT_BUILDERS_MAX];
    int started = 0;
    /* Helpers that cannot be started are not an error: the calling thread
     * builds whatever is left. */
    while (started < nworkers - 1 && fdt_spawn(&th[started], 0, build_trees, &j) == 0)
        started++;
    build_trees(&j);
    for (int i = 0; i < started; i++)
        pthread_join(th[i], NULL);
    pthread_mutex_destroy(&j.mu);
    free(j.stack);
    free(region);
    if (atomic_load_explicit(&j.failed, memory_order_relaxed)) {
        fdt_partition_free(pt);
        return FDT_ENOMEM;
    }
    return FDT_OK;
}

void fdt_partition_recut(fdt_partition *pt, const uint32_t *w, uint64_t total)
{
    uint64_t sum = 0;
    uint32_t id = 0;
    for (int p = 1; p < pt->nparts; p++) {
        /* total * p / nparts without overflow: total < 2^32 * 2^32 */
        uint64_t goal = total / (uint64_t)pt->nparts * (uint64_t)p +
                        total % (uint64_t)pt->nparts * (uint64_t)p / (uint64_t)pt->nparts;
        while (id < pt->m && sum < goal)
            sum += w[id++];
        pt->start[p] = id;
    }
}

int fdt_partition_owner(const fdt_partition *pt, uint32_t id)
{
    /* The last p with start[p] <= id: its range [start[p], start[p + 1])
     * holds id because start[p + 1] > id. Empty parts (start[p] ==
     * start[p + 1]) are never the last such p. */
    int lo = 0, hi = pt->nparts - 1;
    while (lo < hi) {
        int mid = lo + (hi - lo + 1) / 2;
        if (pt->start[mid] <= id)
            lo = mid;
        else
            hi = mid - 1;
    }
    return lo;
}

/* Copies node j of src and its subtree into dst->nodes[slot]. */
static void copy_subtree(const fdt_kdtree *src, uint32_t j, fdt_kdtree *dst,
                         uint32_t slot)
{
    dst->nodes[slot] = src->nodes[j];
    if (!src->nodes[j].left)
        return;
    uint32_t l = dst->nnodes;
    dst->nnodes += 2;
    dst->nodes[slot].left = l;
    copy_subtree(src, src->nodes[j].left, dst, l);
    copy_subtree(src, src->nodes[j].left + 1, dst, l + 1);
}

/* Fills dst->nodes[slot] from bisection node id, skipping empty halves
 * (a kd node must have two children or none). */
static void compose(const fdt_partition *pt, int id, fdt_kdtree *dst,
                    uint32_t slot)
{
    const fdt_pnode *nd = &pt->nodes[id];
    if (nd->left < 0) {
        copy_subtree(&pt->trees[nd->part], 0, dst, slot);
        return;
    }
    const fdt_pnode *l = &pt->nodes[nd->left], *r = l + 1;
    if (l->begin == l->end) {
        compose(pt, nd->left + 1, dst, slot);
        return;
    }
    if (r->begin == r->end) {
        compose(pt, nd->left, dst, slot);
        return;
    }
    fdt_kdnode *k = &dst->nodes[slot];
    memcpy(k->lo, nd->lo, sizeof k->lo);
    memcpy(k->hi, nd->hi, sizeof k->hi);
    k->begin = nd->begin;
    k->end = nd->end;
    k->dim = 0;
    uint32_t c = dst->nnodes;
    dst->nnodes += 2;
    k->left = c;
    compose(pt, nd->left, dst, c);
    compose(pt, nd->left + 1, dst, c + 1);
}

int fdt_partition_global_tree(const fdt_partition *pt, fdt_kdtree *out)
{
    memset(out, 0, sizeof *out);
    size_t cap = 2 * (size_t)pt->nparts;
    const double *P = NULL;
    for (int p = 0; p < pt->nparts; p++) {
        cap += pt->trees[p].nnodes;
        if (pt->trees[p].n)
            P = pt->trees[p].P;
    }
    out->nodes = malloc(cap * sizeof *out->nodes);
    if (!out->nodes)
        return FDT_ENOMEM;
    out->P = P;
    out->base = 0;
    out->n = pt->m;
    out->nnodes = 1;
    compose(pt, 0, out, 0);
    return FDT_OK;
}

/* ---- a distributed partition (src/mpi/mpi_setup.c) --------------------------- */

uint32_t fdt_partition_work_shift(const fdt_pnode *nd, uint32_t nleft, uint64_t count, double w,
                                  int a)
{
    return work_shift(nd, nleft, count, w, a);
}

int fdt_partition_build_own(fdt_partition *pt, double *P, fdt_vid *orig, int part, int leaf_size)
{
    double(*region)[2][3] = malloc((size_t)pt->nparts * sizeof *region);
    if (!region)
        return FDT_ENOMEM;
    const double all_lo[3] = {-INFINITY, -INFINITY, -INFINITY};
    const double all_hi[3] = {INFINITY, INFINITY, INFINITY};
    regions(pt, 0, all_lo, all_hi, region);
    int err = FDT_OK;
    uint32_t n = pt->start[part + 1] - pt->start[part];
    if (n > 0) {
        err = fdt_kd_build(&pt->trees[part], P, orig, pt->start[part], n, leaf_size);
        if (!err)
            fdt_kd_set_region(&pt->trees[part], region[part][0], region[part][1]);
    }
    free(region);
    return err;
}
