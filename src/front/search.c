/* The apex searches; see search.h. */
#include "front/search.h"

#include <string.h>

/* Indexed by fdt_search, from 0 without gaps (fdt_search_name's promise;
 * tests/test_api.c checks it). */
static const fdt_search_row searches[] = {
    /* The paths of fdt_search's comment in include/frontdt.h: the
     * insertion engines wherever they may run (src/api/api.c's
     * pick_engine: every serial run, so the serial front never runs with
     * auto), elsewhere the probe's choice of the mesh of every point; a
     * part keeps the kd search unless the probe gave it that mesh: a part
     * that switched to its own mesh alone still asked the other part's
     * tree about every face near the cut (37M points tested on citylidar
     * 100k where the kd search tests 1.4M; bench/NOTES.md entry 90). */
    [FDT_SEARCH_AUTO] = {.name = "auto", .help = "the default: insertion meshes or the kd search",
                         .one_part_serial = 1, .one_part_threads = 1, .probe = 1,
                         .front_oracle = FDT_ORACLE_KD, .part_oracle = FDT_ORACLE_KD},
    [FDT_SEARCH_KD] = {.name = "kd", .help = "the kd search alone: the paper's fronts",
                       .front_oracle = FDT_ORACLE_KD, .part_oracle = FDT_ORACLE_KD},
    /* On one thread the one-part engine is the one part's own mesh. */
    [FDT_SEARCH_MESH] = {.name = "mesh", .help = "insertion meshes from the start",
                         .one_part_serial = 1, .walls = 1,
                         .front_oracle = FDT_ORACLE_MESH, .part_oracle = FDT_ORACLE_MESH},
};

#define N_SEARCHES (sizeof searches / sizeof searches[0])

const fdt_search_row *fdt_search_row_of(fdt_search s)
{
    /* unsigned: a negative value is out of the table too */
    if ((unsigned)s >= N_SEARCHES)
        return NULL;
    return &searches[s];
}

const char *fdt_search_name(fdt_search s)
{
    const fdt_search_row *r = fdt_search_row_of(s);
    return r ? r->name : NULL;
}

int fdt_search_from_name(const char *name, fdt_search *out)
{
    if (!name || !out)
        return FDT_EINVAL;
    for (size_t i = 0; i < N_SEARCHES; i++)
        if (!strcmp(name, searches[i].name)) {
            *out = (fdt_search)i;
            return FDT_OK;
        }
    return FDT_EINVAL;
}
