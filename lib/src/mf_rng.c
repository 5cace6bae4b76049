/* mf_rng.c -- PCG32 and low-discrepancy points (see mf_rng.h). */
#include "mfkit/mf_rng.h"
#include "mfkit/mf_core.h"

#define PCG32_MULT 6364136223846793005ULL

void mf_pcg32_seed(mf_pcg32 *rng, uint64_t seed, uint64_t stream)
{
    /* pcg32_srandom_r of the reference implementation. */
    rng->state = 0u;
    rng->inc = (stream << 1u) | 1u;
    (void)mf_pcg32_next_u32(rng);
    rng->state += seed;
    (void)mf_pcg32_next_u32(rng);
}

uint32_t mf_pcg32_next_u32(mf_pcg32 *rng)
{
    uint64_t old = rng->state;
    rng->state = old * PCG32_MULT + rng->inc;
    uint32_t xorshifted = (uint32_t)(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = (uint32_t)(old >> 59u);
    return (xorshifted >> rot) | (xorshifted << ((-rot) & 31u));
}

double mf_pcg32_next_double(mf_pcg32 *rng)
{
    uint64_t hi = mf_pcg32_next_u32(rng) >> 5;  /* 27 bits */
    uint64_t lo = mf_pcg32_next_u32(rng) >> 6;  /* 26 bits */
    return (double)((hi << 26) | lo) * 0x1.0p-53;
}

double mf_pcg32_next_normal(mf_pcg32 *rng)
{
    /* Box-Muller; u1 in (0, 1] so that log(u1) is finite. */
    double u1 = 1.0 - mf_pcg32_next_double(rng);
    double u2 = mf_pcg32_next_double(rng);
    return sqrt(-2.0 * log(u1)) * cos(2.0 * MF_PI * u2);
}

static uint32_t reverse_bits32(uint32_t v)
{
    v = ((v >> 1) & 0x55555555u) | ((v & 0x55555555u) << 1);
    v = ((v >> 2) & 0x33333333u) | ((v & 0x33333333u) << 2);
    v = ((v >> 4) & 0x0F0F0F0Fu) | ((v & 0x0F0F0F0Fu) << 4);
    v = ((v >> 8) & 0x00FF00FFu) | ((v & 0x00FF00FFu) << 8);
    return (v >> 16) | (v << 16);
}

double mf_radical_inverse2(uint32_t i)
{
    return (double)reverse_bits32(i) * 0x1.0p-32;
}

void mf_hammersley(uint32_t i, uint32_t n, double out[2])
{
    out[0] = ((double)i + 0.5) / (double)n;
    out[1] = mf_radical_inverse2(i);
}

void mf_sobol2(uint32_t i, uint32_t scramble_x, uint32_t scramble_y, double out[2])
{
    /* Dimension 0: van der Corput.  Dimension 1: Sobol's second generator matrix, whose
     * columns are v_k = v_{k-1} ^ (v_{k-1} >> 1) starting at 1 << 31 (primitive polynomial x + 1). */
    uint32_t x = reverse_bits32(i) ^ scramble_x;
    uint32_t y = scramble_y;
    for (uint32_t v = 1u << 31; i; i >>= 1, v ^= v >> 1)
        if (i & 1u)
            y ^= v;
    out[0] = (double)x * 0x1.0p-32;
    out[1] = (double)y * 0x1.0p-32;
}
