/*
 * Partitioning for the parallel engine (§3.1): recursive coordinate
 * bisection of the prepared points into exactly N parts, each a contiguous
 * range of global ids in the one shared coordinate array (DESIGN.md, Data
 * flow), then one kd-tree per part.
 *
 * The bisection tree is kept: its nodes carry the exact bounding box of
 * their points, so a search can skip whole groups of parts whose box
 * cannot hold a better apex (§4.1) in O(log N) box tests instead of N.
 * Everything here is immutable after fdt_partition_build, so any thread may
 * read it without locks.
 */
#ifndef FDT_PARTITION_H
#define FDT_PARTITION_H

#include <stddef.h>
#include <stdint.h>
#include "frontdt.h"
#include "geom/kdtree.h"

/* The most parts (threads) the engine supports; fdt_open allows 1024. */
#define FDT_PARTITION_MAX 1024

typedef struct fdt_pnode {
    double lo[3], hi[3];   /* exact bounding box; lo > hi when empty */
    uint32_t begin, end;   /* global ids [begin, end) */
    int32_t left;          /* first child (right is left + 1); -1: a part */
    int32_t part;          /* the part of a leaf; -1 for inner nodes */
    int32_t dim;           /* split dimension of an inner node */
} fdt_pnode;

typedef struct fdt_partition {
    int nparts;
    uint32_t m;            /* points over all parts */
    uint32_t *start;       /* nparts + 1 entries (owned): part p holds ids
                              [start[p], start[p + 1]) */
    fdt_pnode *nodes;      /* 2 nparts - 1 nodes (owned); nodes[0] is the root */
    int nnodes;
    fdt_kdtree *trees;     /* nparts trees (owned); an empty part's tree has
                              n == 0 and no nodes */
} fdt_partition;

/* The most threads fdt_partition_build builds trees with. */
#define FDT_BUILDERS_MAX 64

/*
 * Splits ids [0, m) of P (3 doubles per id, permuted together with orig,
 * indexed by global id) into nparts parts (1 <= nparts <=
 * FDT_PARTITION_MAX) and builds each part's kd-tree with leaf_size, on up
 * to nworkers threads (the caller's included; at most FDT_BUILDERS_MAX,
 * 1 or less: the calling thread alone). A part is empty only when m <
 * nparts. FDT_OK, FDT_EINVAL or FDT_ENOMEM (pt is then zeroed).
 */
int fdt_partition_build(fdt_partition *pt, double *P, fdt_vid *orig,
                        uint32_t m, int nparts, int leaf_size, int nworkers);
void fdt_partition_free(fdt_partition *pt);

/* The part whose id range holds id (id < m). */
int fdt_partition_owner(const fdt_partition *pt, uint32_t id);

/*
 * Moves the parts' id ranges (start) so that each owns an equal share of
 * the weight w (m entries, w[id] the work that id's part will do for it;
 * total their sum): start[p] becomes the first id whose prefix sum reaches
 * p * total / nparts. Only ownership moves (fdt_partition_owner, the
 * workers' ranges): the kd-trees and the bisection's nodes keep theirs, so
 * a part's tree may then hold ids it does not own and miss ids it does.
 * For runs where every apex comes from one mesh of every point
 * (src/par/parallel.c), whose parts never search their own trees alone.
 */
void fdt_partition_recut(fdt_partition *pt, const uint32_t *w, uint64_t total);

/*
 * One kd-tree over all m points: the bisection tree on top (empty parts
 * left out), each part's tree below it, nodes copied (out owns them; free
 * with fdt_kd_free). It reads every part's points, so only the setup phase
 * may use it (the seed tets). FDT_OK or FDT_ENOMEM.
 */
int fdt_partition_global_tree(const fdt_partition *pt, fdt_kdtree *out);

/*
 * For a partition made elsewhere (src/mpi/mpi_setup.c: the bisection by
 * exchange between MPI ranks, each holding one part): the points the
 * bisection moves from the left side of a cut to the right for the tets
 * across it (node nd's box, nleft of its count points on the left, w its
 * extent on the cut's axis, a parts on the left), as fdt_partition_build
 * does; and, once start, nodes and nnodes are filled as
 * fdt_partition_build fills them and trees is nparts zeroed trees, the
 * kd-tree of part `part` alone, with its region, over ids [start[part],
 * start[part + 1]) of P and orig (indexed by global id). FDT_OK or
 * FDT_ENOMEM.
 */
uint32_t fdt_partition_work_shift(const fdt_pnode *nd, uint32_t nleft, uint64_t count, double w,
                                  int a);
int fdt_partition_build_own(fdt_partition *pt, double *P, fdt_vid *orig, int part,
                            int leaf_size);

#endif
