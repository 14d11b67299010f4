/* Whether the kd search is expensive on a set of points; see probe.h. */
#include "front/probe.h"

#include <stdlib.h>
#include <string.h>

#include "front/front.h"
#include "front/seed.h"

/*
 * A sample, not all points: its tree costs a few milliseconds where the
 * whole input's would cost a tenth of a second at 1M. The structures that
 * make the kd search expensive (a surface, rings, lattice planes,
 * cospherical shells) survive taking every k-th point, and
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
 * run). Either above PROBE_SURE is clearly expensive: the ranks of an MPI
 * run build the replica mesh (src/mpi/mpi_run.c). Measured (bench/NOTES.md
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
#define PROBE_SURE FDT_PROBE_REPLICA

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
    const fdt_probe_budget budget = {(double)PROBE_SURE * PROBE_FACES, FDT_ORACLE_EXACT_WEIGHT};
    if (fdt_front_probe(&t, k / 2, PROBE_FACES, &budget, &st) != FDT_OK)
        goto done;
    double work = (double)st.kq.points +
                  FDT_ORACLE_EXACT_WEIGHT *
                      (double)(st.kq.pc.orient_exact + st.kq.pc.insphere_exact);
    /* The budget spent, even before the first face (the seed's own search
     * on points of one sphere: intsphere 2,500 cost it all, and a cost of
     * "unknown" sent such an input to the kd search, 7.6 s where the mesh
     * takes 0.1 s): clearly expensive. */
    if (work > budget.cost)
        cost = work / PROBE_FACES;
    else if (st.faces_advanced > 0)
        cost = work / (double)st.faces_advanced;
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
void fdt_probe_take(fdt_probe_samples *ps, const double *P, uint32_t m, int leaf_size)
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

double fdt_probe_cost(fdt_probe_samples *ps)
{
    double cost = 0.0;
    for (int i = 0; i < 2 && cost <= PROBE_SURE; i++) {
        if (!ps->S[i])
            continue;
        double c = probe_cost(ps->S[i], ps->k, ps->leaf_size);
        if (c > cost)
            cost = c;
    }
    free(ps->S[0]);
    free(ps->S[1]);
    ps->S[0] = ps->S[1] = NULL;
    return cost;
}
