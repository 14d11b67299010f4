/*
 * Doubles as scaled GMP integers: the exact stages' conversion
 * (src/geom/predicates.c), shared with the periodic images' exact
 * predicates (src/geom/images.c), whose coordinates are sums of doubles.
 */
#ifndef FDT_EXACT_GMP_H
#define FDT_EXACT_GMP_H

#include <gmp.h>

/* The exponent k of x = m 2^k with |m| < 2^53 an integer (x != 0). */
int fdt_int_exponent(double x);

/* z = x 2^-kmin, an integer because kmin <= fdt_int_exponent(x) (x may
 * be 0). */
void fdt_mpz_set_scaled(mpz_t z, double x, int kmin);

/* r = det[u; v; w] for integer rows; t is scratch. */
void fdt_mpz_det3(mpz_t r, mpz_t *const u, mpz_t *const v, mpz_t *const w, mpz_t t);

#endif
