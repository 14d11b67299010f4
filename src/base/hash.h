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

/* xoshiro256** (Blackman and Vigna 2018): the next draw of state s (seed
 * it with fdt_splitmix64). The CLI's demo points and tests/gen_points. */
static inline uint64_t fdt_xoshiro256ss(uint64_t s[4])
{
    uint64_t x = s[1] * 5;
    uint64_t r = ((x << 7) | (x >> 57)) * 9;
    uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = (s[3] << 45) | (s[3] >> 19);
    return r;
}

#endif
