/*
 * Coordinate-bisection kd-tree (Bentley 1975; Merriam §4: "the
 * partitioning continues until only a few nodes (typically 18) occupy each
 * partition") over one coordinate array permuted into tree order, so every
 * node is a contiguous run of ids, and the range queries the advancing
 * front needs.
 *
 * A tree covers the ids [base, base + n) of a global coordinate array; a
 * partition of the parallel engine is one such tree. Trees are immutable
 * after fdt_kd_build, so any thread may query any tree without locks.
 */
#ifndef FDT_KDTREE_H
#define FDT_KDTREE_H

#include <stddef.h>
#include <stdint.h>
#include "frontdt.h"
#include "geom/predicates.h"

#define FDT_NONE UINT32_MAX

/* Points a leaf. The paper's 18 (§4) suited leaves tested one double at a
 * time; with the float blocks (src/geom/kdtree.c) a leaf costs less than the
 * nodes above it, and 24 to 40 ran alike and about 5 % faster than 18 at
 * 1M and 9 % at 200k (bench/NOTES.md, entry 32). */
#define FDT_DEFAULT_LEAF 30

typedef struct fdt_kdnode {
    double lo[3], hi[3];   /* exact bounding box of the node's points */
    uint32_t begin, end;   /* global ids [begin, end) */
    uint32_t left;         /* first child (right is left + 1); 0: a leaf */
    uint32_t dim;          /* split dimension; in a leaf of a tree with
                            * float blocks (fl below), the offset of its
                            * block in fl, in units of 4 floats */
} fdt_kdnode;

typedef struct fdt_kdtree {
    fdt_kdnode *nodes;     /* owned; nodes[0] is the root */
    uint32_t nnodes;
    const double *P;       /* borrowed: global coordinates, 3 per id */
    uint32_t base, n;
    /* Owned, set by fdt_kd_build (NULL in other trees): for the climb of
     * fdt_apex_search_from, each node's parent and cell ([0]: lo, [1]:
     * hi; how cells are bounded: climb_tables in src/geom/kdtree.c) and each
     * point's leaf (by id - base). */
    uint32_t *parent;
    double (*cell)[2][3];
    uint32_t *leafof;
    /* Owned, set by fdt_kd_build when the offsets fit (NULL otherwise and
     * in other trees): every leaf's points again as floats in a frame of
     * the leaf's own, for the apex search's first, conservative tests
     * (src/geom/kdtree.c, "Float blocks"). */
    float *fl;
    int avx2;              /* the float-block kernels may use AVX2 */
} fdt_kdtree;

/* Per-thread counters of the queries' work (owned by the querying thread). */
typedef struct fdt_kdq {
    size_t nodes, points;
    fdt_pred_counts pc;
} fdt_kdq;

/*
 * Builds the tree over ids [base, base + n) of P (3 doubles per id),
 * permuting P's points in that range and the parallel array orig (indexed
 * by global id) into tree order. leaf_size > 0. FDT_OK or FDT_ENOMEM.
 */
int fdt_kd_build(fdt_kdtree *t, double *P, fdt_vid *orig, uint32_t base,
                 uint32_t n, int leaf_size);

/*
 * fdt_kd_build in jobs, for several threads (src/geom/partition.c): the same
 * tree, node for node. fdt_kd_begin allocates the nodes and gives the
 * root's job; fdt_kd_run builds a job's subtree whole when it holds at
 * most `grain` points (returns 0), else only its node, and returns its
 * two children's jobs in kids (returns 2). Jobs of one tree may run on
 * different threads at once (they touch disjoint nodes and ids); once
 * every job has run, fdt_kd_end builds the climb tables and the float
 * blocks. Each job's node ids were given before it runs, so the
 * numbering is fdt_kd_build's whatever the order.
 */
typedef struct fdt_kd_job {
    fdt_kdtree *t;
    double *P;                 /* the tree's points, permuted by the build */
    fdt_vid *orig;
    uint32_t leaf;
    uint32_t node, begin, end; /* the subtree's root and its ids */
    uint32_t next;             /* the first id of its descendants' block */
} fdt_kd_job;

int fdt_kd_begin(fdt_kdtree *t, double *P, fdt_vid *orig, uint32_t base, uint32_t n,
                 int leaf_size, fdt_kd_job *root);
int fdt_kd_run(const fdt_kd_job *job, uint32_t grain, fdt_kd_job kids[2]);
int fdt_kd_end(fdt_kdtree *t);
void fdt_kd_free(fdt_kdtree *t);
/* The bytes t owns (nodes, climb tables, float blocks): fdt_stats.mem_tree. */
size_t fdt_kd_bytes(const fdt_kdtree *t);

/* Quickselect on coordinate dim (0..2) over ids [lo, hi), lo <= k < hi:
 * afterwards the point at k has the (k - lo)-th smallest coordinate, the
 * points before it are <= it and those after are >= it; P and orig are
 * permuted together. Used by the partitioner (src/geom/partition.c). */
void fdt_kd_select(double *P, fdt_vid *orig, uint32_t lo, uint32_t hi,
                   uint32_t k, int dim);

/* Bounding box of points [begin, end) of P (also the partitioner's). */
void fdt_points_box(const double *P, uint32_t begin, uint32_t end,
                    double *lo, double *hi);

/* Squared distance from c to the box [lo, hi] (0 inside), with each
 * difference scaled by the power of two sc first (1 for plain distances;
 * an apex search passes its ball's sc, see fdt_apex). */
double fdt_box_dist2_sc(const double *lo, const double *hi, const double *c, double sc);

/* An exactly nearest point to q other than id `exclude` (the lowest id on
 * exact ties; floating distances, fdt_compare_dist on near-ties),
 * FDT_NONE if the tree holds no other point. */
uint32_t fdt_kd_nearest(const fdt_kdtree *t, const double *q,
                        uint32_t exclude, fdt_kdq *kq);

/* Calls fn(user, id) for every point whose distance to c may be <= r
 * (a superset within rounding: the caller decides exactly). */
int fdt_kd_ball(const fdt_kdtree *t, const double *c, double r,
                int (*fn)(void *user, uint32_t id), void *user, fdt_kdq *kq);

/*
 * The apex search (§2.2). For the oriented face (a, b, c), the "open side"
 * is fdt_orient3d(a, b, c, x) > 0. Among the points strictly on the open
 * side, the apex is the one whose sphere through a, b, c holds no other
 * open-side point under the perturbed insphere; the pencil of spheres
 * through the circle abc orders the open-side points totally, and the apex
 * is its first element. A search state may be run over several trees
 * (partitions) in turn; the result is the apex over their union.
 */
typedef struct fdt_apex {
    const double *a, *b, *c;
    uint32_t ia, ib, ic;
    double nrm[3];       /* (b-a) x (c-a): points to the open side */
    double nabs[3];      /* |components| permanent for the side filter */
    double target[3];    /* where the search looks first, once aimed */
    int aimed;           /* target set (fdt_apex_aim) */
    uint32_t best;       /* FDT_NONE until a candidate is found */
    const double *bp;    /* coordinates of best */
    double center[3];    /* conservative search ball of the best sphere */
    double sc;           /* a power of two: the ball test compares */
    double r2;           /* |(d - center) sc|^2 with r2 = (radius sc)^2, */
                         /* INFINITY while unknown or ill-conditioned */
    double rad;          /* that radius, unscaled (INFINITY likewise) */
    uint32_t ver;        /* counts changes of best (and so of the ball) */
} fdt_apex;

void fdt_apex_init(fdt_apex *s, const double *a, const double *b,
                   const double *c, uint32_t ia, uint32_t ib, uint32_t ic);
/* Sets s->target (and the centre while there is no candidate): done by
 * the searches when they need it; callers that read target call it. */
void fdt_apex_aim(fdt_apex *s);
/* Offers one point (global id, coordinates) to the search: used by the
 * tree walk and by answers that arrive from other partitions. */
void fdt_apex_offer(fdt_apex *s, uint32_t id, const double *d, fdt_kdq *kq);
void fdt_apex_search(fdt_apex *s, const fdt_kdtree *t, fdt_kdq *kq);
/* The same search over tree t, starting from the leaf that holds point
 * `start` (in t) and climbing: cheaper when the apex is near `start`.
 * Returns 1 when the final ball lies strictly inside a cell of t, and so
 * inside t's region (fdt_kd_set_region): no point outside that region can
 * then improve s; 0 otherwise. */
int fdt_apex_search_from(fdt_apex *s, const fdt_kdtree *t, uint32_t start, fdt_kdq *kq);

/* fdt_apex_search_from in two halves, for callers with work to start in
 * between: the first candidate from the leaves of the face's vertices
 * (the apex for most faces), then the climb that verifies or improves it.
 * fdt_apex_verify_from returns what fdt_apex_search_from does. */
void fdt_apex_guess(fdt_apex *s, const fdt_kdtree *t, uint32_t start, fdt_kdq *kq);
int fdt_apex_verify_from(fdt_apex *s, const fdt_kdtree *t, uint32_t start, fdt_kdq *kq);

/* Sets the region of tree t, the box [lo, hi] that holds its points and
 * no point of any other tree searched with it (a part's cell of the
 * coordinate bisection; points of other parts may lie on its boundary,
 * not inside). Default: all of space. The climb's cells are bounded by it. */
void fdt_kd_set_region(fdt_kdtree *t, const double lo[3], const double hi[3]);
/* 1 when s has a candidate whose ball lies strictly inside the region of
 * tree t (fdt_kd_set_region): no point outside the region can improve s
 * (what fdt_apex_verify_from returns after a whole search, for a candidate
 * found another way: src/front/oracle.h). */
int fdt_apex_inside_region(const fdt_apex *s, const fdt_kdtree *t);
/* Whether the box [lo, hi] could hold a point that improves s. */
int fdt_apex_box_useful(const fdt_apex *s, const double *lo, const double *hi);

/* A point of the tree strictly inside the perturbed circumsphere of the
 * positively oriented tet (a,b,c,d) other than its vertices, or FDT_NONE. */
uint32_t fdt_kd_any_inside(const fdt_kdtree *t, const uint32_t v[4],
                           fdt_kdq *kq);

#endif
