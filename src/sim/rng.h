/* SPDX-License-Identifier: MIT */
/* rng.h: the simulator's random numbers. One stream per (seed, purpose, index), so a
   batch of rays or a surface realisation draws the same numbers on any thread. */
#ifndef SIM_RNG_H
#define SIM_RNG_H

#include <math.h>
#include <stdint.h>

#include "core/core.h"

/* The project's one splitmix64 (core/core.h), under the simulator's name. */
static inline uint64_t sim_splitmix64(uint64_t *state)
{
    return core_mix(state);
}

/* The state of stream `index` of kind `purpose` for a run seeded with `seed`: the three
   words go through the mixer one after another, so nearby seeds and indices give
   unrelated streams. */
static inline uint64_t sim_stream(uint64_t seed, uint64_t purpose, uint64_t index)
{
    uint64_t s = seed;
    uint64_t a = sim_splitmix64(&s);
    s = a ^ (purpose * 0xD1B54A32D192ED03ull);
    uint64_t b = sim_splitmix64(&s);
    s = b ^ (index * 0x8CB92BA72F3D8DD7ull);
    return sim_splitmix64(&s);
}

/* Uniform in [0, 1): the top 53 bits. */
static inline double sim_uniform(uint64_t *state)
{
    return (double)(sim_splitmix64(state) >> 11) * 0x1.0p-53;
}

/* Standard normal by Box-Muller; u1 is taken in (0, 1] so log never sees 0. */
static inline double sim_gauss(uint64_t *state)
{
    double u1 = 1.0 - sim_uniform(state);
    double u2 = sim_uniform(state);
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}

/* Two independent standard normals, both of Box-Muller's outputs. */
static inline void sim_gauss2(uint64_t *state, double *a, double *b)
{
    double u1 = 1.0 - sim_uniform(state);
    double u2 = sim_uniform(state);
    double r = sqrt(-2.0 * log(u1)), t = 6.283185307179586 * u2;
    *a = r * cos(t);
    *b = r * sin(t);
}

#endif
