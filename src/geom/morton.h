/* Points in Morton (Z) order of their coordinates: the order in which
 * src/mesh/voronoi.c numbers its points, src/mesh/interpolate.c takes
 * its queries and the one-part engine inserts its points, so that
 * consecutive ones lie close together. Keys are sorted by radix. */
#ifndef FDT_MORTON_H
#define FDT_MORTON_H

#include <stddef.h>
#include <stdint.h>
#include "frontdt.h"

/* Writes to order[] the indices i < n of the points pts (3 doubles each)
 * with skip[i] 0 (skip NULL: every point), sorted by their Morton key in
 * box (xmin, ymin, zmin, xmax, ymax, zmax; points outside count as on its
 * walls); each run of more than 32 points with one key sorted again by
 * their keys in their own bounding box, and so on down to runs of equal
 * points; ties by index. The key has 21 bits a coordinate, or fewer where
 * an index of n - 1 and the key must share 64 bits: (64 - b) / 3 for b
 * the bits of n - 1 (14 at a million points). Returns how many, or -1
 * when out of memory. */
long fdt_morton_order(const double *pts, size_t n, const double box[6], const uint8_t *skip,
                      uint32_t *order);

/* Puts the n points pts (3 doubles each) and their input indices orig in
 * the Morton order of their bounding box (the key as fdt_morton_order's),
 * ties by their current index: the insertion order of the one-part engine
 * (src/api/api.c), whose BRIO rounds keep it. On up to `threads` threads
 * (one for every 32k points at least); the same order for any count. 0,
 * or -1 when out of memory (nothing moved then). */
int fdt_morton_sort(double *pts, fdt_vid *orig, size_t n, int threads);

#endif
