/* Points in Morton order: see morton.h. */
#include "geom/morton.h"

#include <math.h>
#include <stdlib.h>

typedef struct keyed {
    uint64_t key;
    uint32_t id;
} keyed;

static int keyed_cmp(const void *x, const void *y)
{
    const keyed *a = x, *b = y;
    if (a->key != b->key)
        return a->key < b->key ? -1 : 1;
    return a->id < b->id ? -1 : a->id > b->id;
}

/* 21 bits of each coordinate in the box, interleaved. */
static uint64_t morton(const double *p, const double box[6])
{
    uint64_t key = 0;
    uint32_t c[3];
    for (int k = 0; k < 3; k++) {
        double w = box[k + 3] - box[k];
        double t = w > 0 ? (p[k] - box[k]) / w : 0;
        t = t > 0 ? (t < 1 ? t : 1) : 0; /* NaN too: 0 */
        c[k] = (uint32_t)(t * 2097151.0);
    }
    for (int b = 20; b >= 0; b--)
        for (int k = 0; k < 3; k++)
            key = key << 1 | ((c[k] >> b) & 1);
    return key;
}

long fdt_morton_order(const double *pts, size_t n, const double box[6], const uint8_t *skip,
                      uint32_t *order)
{
    keyed *kp = malloc((n ? n : 1) * sizeof *kp);
    if (!kp)
        return -1;
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (!skip || !skip[i])
            kp[m++] = (keyed){morton(pts + 3 * i, box), (uint32_t)i};
    qsort(kp, m, sizeof *kp, keyed_cmp);
    for (size_t i = 0; i < m; i++)
        order[i] = kp[i].id;
    free(kp);
    return (long)m;
}
