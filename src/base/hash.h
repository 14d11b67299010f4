/* 64-bit mixing: SplitMix64 (Steele, Lea, Flood, "Fast splittable
 * pseudorandom number generators", OOPSLA 2014), its finaliser for hashes
 * (src/base/sethash.h) and its generator for deterministic streams (the
 * shuffling test transport of src/par/transport.c, the test inputs of
 * tests/). One copy, so every stream is the same everywhere. */
#ifndef FDT_HASH_H
#define FDT_HASH_H

#include <stdint.h>

/* The finaliser of SplitMix64: every input bit flips each output bit with
 * probability close to 1/2. */
static inline uint64_t fdt_mix64(uint64_t z)
{
    z ^= z >> 30;
    z *= 0xBF58476D1CE4E5B9ull;
    z ^= z >> 27;
    z *= 0x94D049BB133111EBull;
    z ^= z >> 31;
    return z;
}

/* The next value of the SplitMix64 stream whose state is *state (any start
 * value): the state advances by the golden-ratio increment and is mixed. */
static inline uint64_t fdt_splitmix64(uint64_t *state)
{
    return fdt_mix64(*state += 0x9E3779B97F4A7C15ull);
}

#endif
