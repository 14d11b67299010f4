/*
 * The probe of the kd search's cost, which picks the apex oracle
 * (src/front/oracle.h) for a whole run before it starts. It runs fronts
 * (src/front/front.h, fdt_front_probe), so it sits above them.
 */
#ifndef FDT_PROBE_H
#define FDT_PROBE_H

#include <stddef.h>
#include <stdint.h>

/*
 * Whether the kd search is clearly expensive on these points (a rank's m
 * distinct points P, 3 doubles each): the first faces of a serial front
 * over samples of them, costed as fdt_oracle_tick does, by points tested,
 * never by time. An MPI run's ranks vote with it for the replica mesh
 * (src/mpi/mpi_run.c, replica_mesh): there a face whose sphere crosses a
 * cut asks the other ranks, and a pipe's or a grid's spheres are as wide
 * as the object (bench/NOTES.md, entry 52). take copies the samples (no
 * memory for one: that sample counts as cheap); cost costs them, frees
 * them and returns the larger of their costs a face (0 for a sample that
 * cannot be costed: no memory, a flat sample), stopping once one passes
 * FDT_PROBE_REPLICA.
 */
typedef struct fdt_probe_samples {
    double *S[2]; /* every stride-th point; a run of consecutive points */
    uint32_t k;   /* points in each (0: too few points, not expensive) */
    int leaf_size;
} fdt_probe_samples;
void fdt_probe_take(fdt_probe_samples *ps, const double *P, uint32_t m, int leaf_size);
double fdt_probe_cost(fdt_probe_samples *ps);

/* The probe's cost past which the ranks of an MPI run build the replica
 * mesh, and the threads of a run the mesh of every point
 * (src/par/parallel.c). */
#define FDT_PROBE_REPLICA 500.0
#define FDT_PROBE_SHARED_MESH 135.0

#endif
