/* A double in decimal, as printf's "%.17g" writes it (src/base/dtoa.c).
 *
 * Every text writer puts doubles with 17 significant digits, enough that
 * strtod gives back the very same double. glibc's printf computes them in
 * arbitrary precision, about 250 ns a number: most of the time of a
 * Voronoi table with its face areas (bench/NOTES.md entry 102). */
#ifndef FDT_DTOA_H
#define FDT_DTOA_H

#include <stddef.h>

/* The longest text fdt_dtoa17 writes: "-1.2345678901234567e-308". */
#define FDT_DTOA17_MAX 24

/* Writes x at p as snprintf(p, n, "%.17g", x) does in the C locale and
 * the default rounding mode, byte for byte, without the terminating NUL;
 * returns the number of bytes (at most FDT_DTOA17_MAX). Magnitudes from
 * 1e-11 to 1e43 take an exact integer path; the rest, and builds without
 * a 128-bit integer type, take snprintf itself. */
size_t fdt_dtoa17(char *p, double x);

#endif
