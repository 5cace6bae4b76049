/*
 * mf_rng.h -- random and low-discrepancy numbers.
 *
 *  - PCG32 (O'Neill 2014, "PCG: A Family of Simple Fast Space-Efficient Statistically Good
 *    Algorithms for Random Number Generation", pcg32 = PCG-XSH-RR 64/32): a seeded stream whose
 *    output depends only on (seed, stream), never on a clock or a thread.
 *  - Deterministic point sets for quadrature: the van der Corput radical inverse in base 2,
 *    the Hammersley set, and the first two dimensions of the Sobol sequence (a (0,2)-sequence
 *    in base 2), with an optional XOR scramble.
 *
 * Every uniform double is in [0, 1): 53-bit or 32-bit values scaled by a power of two, so they
 * are exact and reproducible across platforms.
 */
#ifndef MF_RNG_H
#define MF_RNG_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mf_pcg32 {
    uint64_t state;
    uint64_t inc; /* odd */
} mf_pcg32;

/* Seeds the generator; different `stream` values give independent sequences. */
void mf_pcg32_seed(mf_pcg32 *rng, uint64_t seed, uint64_t stream);
uint32_t mf_pcg32_next_u32(mf_pcg32 *rng);
/* Uniform double in [0, 1) with 53 random bits. */
double mf_pcg32_next_double(mf_pcg32 *rng);
/* Standard normal deviate (Box-Muller, both uniforms strictly inside (0, 1)). */
double mf_pcg32_next_normal(mf_pcg32 *rng);

/* Base-2 radical inverse of i (van der Corput), in [0, 1). */
double mf_radical_inverse2(uint32_t i);
/* Point i of the n-point Hammersley set: ((i + 0.5) / n, radical_inverse2(i)). */
void mf_hammersley(uint32_t i, uint32_t n, double out[2]);
/* Point i of the 2D Sobol sequence, XOR-scrambled with (scramble_x, scramble_y); pass 0, 0
 * for the plain sequence.  Any power-of-two prefix is a (0, m, 2)-net. */
void mf_sobol2(uint32_t i, uint32_t scramble_x, uint32_t scramble_y, double out[2]);

#ifdef __cplusplus
}
#endif
#endif /* MF_RNG_H */
