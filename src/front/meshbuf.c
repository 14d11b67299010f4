/* The growable output of a front; see meshbuf.h. */
#include "front/meshbuf.h"

#include <stdlib.h>
#include <string.h>

#include "base/mem.h"

int fdt_meshbuf_init(fdt_meshbuf *mb, size_t expected_tets, int want_nbrs)
{
    memset(mb, 0, sizeof *mb);
    mb->tcap = expected_tets < 64 ? 64 : expected_tets;
    mb->tets = malloc(mb->tcap * 4 * sizeof *mb->tets);
    if (want_nbrs)
        mb->nbrs = malloc(mb->tcap * 4 * sizeof *mb->nbrs);
    mb->hcap = 1024;
    mb->hull = malloc(mb->hcap * 3 * sizeof *mb->hull);
    if (!mb->tets || !mb->hull || (want_nbrs && !mb->nbrs)) {
        fdt_meshbuf_free(mb);
        return FDT_ENOMEM;
    }
    return FDT_OK;
}

void fdt_meshbuf_free(fdt_meshbuf *mb)
{
    free(mb->tets);
    free(mb->nbrs);
    free(mb->hull);
    memset(mb, 0, sizeof *mb);
}

size_t fdt_meshbuf_bytes(const fdt_meshbuf *mb)
{
    size_t b = mb->tets ? mb->tcap * 4 * sizeof *mb->tets : 0;
    if (mb->nbrs)
        b += mb->tcap * 4 * sizeof *mb->nbrs;
    if (mb->hull)
        b += mb->hcap * 3 * sizeof *mb->hull;
    return b;
}

int64_t fdt_meshbuf_add_tet(fdt_meshbuf *mb, const uint32_t v[4])
{
    if (mb->ntets == mb->tcap) {
        size_t ncap = mb->tcap + mb->tcap / 2;
        if (!fdt_mem_fits((ncap - mb->tcap) * 4 *
                          (sizeof *mb->tets + (mb->nbrs ? sizeof *mb->nbrs : 0))))
            return -1;
        uint32_t *nt = realloc(mb->tets, ncap * 4 * sizeof *nt);
        if (!nt)
            return -1;
        mb->tets = nt;
        if (mb->nbrs) {
            int64_t *nn = realloc(mb->nbrs, ncap * 4 * sizeof *nn);
            if (!nn)
                return -1;
            mb->nbrs = nn;
        }
        mb->tcap = ncap;
    }
    memcpy(mb->tets + 4 * mb->ntets, v, 4 * sizeof *v);
    if (mb->nbrs)
        for (int k = 0; k < 4; k++)
            mb->nbrs[4 * mb->ntets + k] = -1;
    return (int64_t)mb->ntets++;
}

int fdt_meshbuf_add_hull(fdt_meshbuf *mb, const uint32_t v[3])
{
    if (mb->nhull == mb->hcap) {
        size_t ncap = mb->hcap * 2;
        uint32_t *nh = realloc(mb->hull, ncap * 3 * sizeof *nh);
        if (!nh)
            return FDT_ENOMEM;
        mb->hull = nh;
        mb->hcap = ncap;
    }
    memcpy(mb->hull + 3 * mb->nhull, v, 3 * sizeof *v);
    mb->nhull++;
    return FDT_OK;
}
