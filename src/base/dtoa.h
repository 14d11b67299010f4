/* A double in decimal, as printf's "%.17g" writes it (src/base/dtoa.c),
 * and integers in decimal.
 *
 * Every text writer puts doubles with 17 significant digits, enough that
 * strtod gives back the very same double. glibc's printf computes them in
 * arbitrary precision, about 250 ns a number: most of the time of a
 * Voronoi table with its face areas (bench/NOTES.md entry 102). */
#ifndef FDT_DTOA_H
#define FDT_DTOA_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

/* The longest text fdt_dtoa17 writes: "-1.2345678901234567e-308". */
#define FDT_DTOA17_MAX 24

/* Writes x at p as snprintf(p, n, "%.17g", x) does in the C locale and
 * the default rounding mode, byte for byte, without the terminating NUL;
 * returns the number of bytes (at most FDT_DTOA17_MAX). p must have room
 * for FDT_DTOA17_MAX bytes: those past the text may be written too.
 * Magnitudes from 1e-11 to 1e43 take an exact integer path; the rest, and
 * builds without a 128-bit integer type or on big-endian machines, take
 * snprintf itself. */
size_t fdt_dtoa17(char *p, double x);

/* Two decimal digits per lookup halves the divisions. */
static const char fdt_digit_pairs[201] =
    "00010203040506070809101112131415161718192021222324252627282930313233"
    "34353637383940414243444546474849505152535455565758596061626364656667"
    "68697071727374757677787980818283848586878889909192939495969798990";

/* Writes v in decimal at p (printf's "%llu" without the NUL), returns
 * the number of chars (at most 20). */
static inline size_t fdt_utoa(char *p, uint64_t v)
{
    char tmp[20];
    char *e = tmp + sizeof tmp, *s = e;
    while (v >= 100) {
        unsigned r = (unsigned)(v % 100);
        v /= 100;
        s -= 2;
        memcpy(s, fdt_digit_pairs + 2 * r, 2);
    }
    if (v >= 10) {
        s -= 2;
        memcpy(s, fdt_digit_pairs + 2 * v, 2);
    } else {
        *--s = (char)('0' + v);
    }
    size_t n = (size_t)(e - s);
    memcpy(p, s, n);
    return n;
}

/* The same for a signed v ("%lld"): at most 20 chars. */
static inline size_t fdt_itoa(char *p, int64_t v)
{
    if (v < 0) {
        *p = '-';
        return 1 + fdt_utoa(p + 1, (uint64_t)0 - (uint64_t)v);
    }
    return fdt_utoa(p, (uint64_t)v);
}

#endif
