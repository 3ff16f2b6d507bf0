/* SPDX-License-Identifier: MIT */
/* surface.h: one periodic tile of a Gaussian random height field, its triangles'
   bounds hierarchy, and its realised statistics. */
#ifndef SIM_SURFACE_H
#define SIM_SURFACE_H

#include <stddef.h>
#include <stdint.h>

/* Hierarchy: level 0 is the grid cell; level k > 0 groups 4^k cells (blocks of
   (1 << 2k) cells per side). Levels stop while at least two blocks fit per side. */
#define SIM_MAX_LEVELS 8

typedef struct sim_surface {
    int n;          /* grid points along x, a power of two; also the cells along x */
    int log2n;
    uint64_t ymask; /* rows - 1: n - 1 for a square tile, 0 for a profile's strip (one
                       row, periodic in y with period one cell: z does not vary in y) */
    double dx;      /* spacing, in units of sigma */
    double *h;      /* rows * n heights, h[j * n + i] at (i dx, j dx); periodic */
    double hmin, hmax;
    int levels;                    /* 1 + block levels */
    int shift[SIM_MAX_LEVELS];     /* log2 of the cells per side of a unit of level k */
    double *lo[SIM_MAX_LEVELS];    /* per unit: lowest and highest height of its */
    double *hi[SIM_MAX_LEVELS];    /* triangles, [(j >> shift) * side + (i >> shift)] */
} sim_surface;

/* What one realisation measured. */
typedef struct sim_surface_stats {
    double rms_height;  /* about the tile's mean */
    double rms_slope;   /* of the triangles, area weighted */
    double corr_length; /* where the autocorrelation along x and y falls to 1/e */
} sim_surface_stats;

/* A generator for one grid: FFTW plans and the filter's transform. It is made and
   freed from one thread (FFTW's planner is not thread-safe); once made, any number of
   threads may use it at once, each with its own scratch (FFTW's new-array execute
   functions are thread-safe). */
typedef struct sim_gen sim_gen;
typedef struct sim_scratch sim_scratch;

/* n points per side (power of two), spacing dx, correlation length tau (sigma = 1).
   NULL when out of memory. */
sim_gen *sim_gen_new(int n, double dx, double tau);
/* The same for a profile: a strip of n points along x (a 1D transform of 1D noise
   filtered by exp(-2 x^2 / tau^2): C(x) = exp(-x^2 / tau^2)). */
sim_gen *sim_gen_new_profile(int n, double dx, double tau);
void sim_gen_free(sim_gen *g);
sim_scratch *sim_scratch_new(const sim_gen *g);
void sim_scratch_free(sim_scratch *w);
/* Bytes of one scratch of a generator of rows x n points (rows n or 1). */
size_t sim_scratch_bytes(int n, int rows);

/* Fills s (allocating its arrays) with the realisation of white-noise stream state
   `stream`, and its statistics in st (may be NULL). 0 on success, -1 out of memory. */
int sim_gen_surface(const sim_gen *g, sim_scratch *w, uint64_t stream, sim_surface *s,
                    sim_surface_stats *st);

/* The same from a profile's generator (sim_gen_new_profile): z = h(x), a strip
   constant along y; the statistics are those of the profile (slope along x, of RMS
   sqrt(2)/s, and the correlation length along x). */
int sim_gen_profile(const sim_gen *g, sim_scratch *w, uint64_t stream, sim_surface *s,
                    sim_surface_stats *st);

void sim_surface_free(sim_surface *s);

/* Bytes one tile of rows x n points with its hierarchy takes. */
size_t sim_surface_bytes(int n, int rows);

#endif
