/*
 * The apex searches, one row each (issue 35): the name users type, the
 * line --help shows, and what the engine's rules ask of a search. Every
 * place that chooses an engine or an oracle by the search reads its row,
 * so a new search is its method plus one row of src/front/search.c
 * (doc/design.md, "Add an apex search").
 */
#ifndef FDT_SEARCH_H
#define FDT_SEARCH_H

#include "frontdt.h"
#include "front/oracle.h"

typedef struct fdt_search_row {
    const char *name;     /* as users type it: --search NAME, search='NAME'
                             (fdt_search_from_name) */
    const char *help;     /* its line in --help's list (src/cli/options.c) */
    /* In memory, the one-part engine (src/api/api.c, one_part: the
     * certified insertion mesh of every point is the answer) runs in the
     * fronts' place: on one thread (one_part_serial); on several with the
     * default mode and no --pin (one_part_threads). */
    int one_part_serial, one_part_threads;
    /* A probe of the input chooses between the kd search and the mesh of
     * every point: the threads' (src/par/parallel.c, global_mesh) and the
     * MPI ranks' replica (src/mpi/mpi_run.c, replica_mesh). */
    int probe;
    /* With threads, every part builds its own mesh before its front: the
     * wall engine (src/par/engine.c), unless the mesh of every point was
     * built. */
    int walls;
    fdt_oracle_policy front_oracle; /* the serial front's oracle (src/front/front.c) */
    fdt_oracle_policy part_oracle;  /* each part's oracle (src/par/engine.c) */
} fdt_search_row;

/* The row of search s, or NULL when s is not a search (fdt_open refuses
 * such settings, so the engine's callers may take the row as found). */
const fdt_search_row *fdt_search_row_of(fdt_search s);

#endif
