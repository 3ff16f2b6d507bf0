/* SPDX-License-Identifier: MIT */
/* trace.h: exact ray intersection with a tile's triangles, and one light path through
   the interface with Fresnel's choice at every hit. */
#ifndef SIM_TRACE_H
#define SIM_TRACE_H

#include <stdint.h>

#include "sim/surface.h"

/* Where a path ended. */
enum { SIM_END_R = 0, SIM_END_T = 1, SIM_END_LOST = 2, SIM_END_ABSORBED = 3 };

/* Hits after which a path is stopped and counted lost (none reached it in any run we
   measured: the mean is 1 to 3 hits even at s = 0.5). */
#define SIM_MAX_HITS 4096

typedef struct sim_path {
    int end;        /* SIM_END_* */
    int hits;       /* surface hits */
    double dir[3];  /* outgoing direction (R: z > 0, T: z < 0), unit */
} sim_path;

/* The first hit of the ray o + t d, t in (0, tmax], with the surface seen from above
   (above = 1: the ray is over the surface and a hit takes it below) or below.
   o and d are in grid units horizontally (x / dx) and height units vertically.
   accel = 1 walks the min/max hierarchy, 0 every cell (the baseline). On a hit
   returns 1 with *t and the upward unit normal nrm (in physical units); else 0. */
int sim_first_hit(const sim_surface *s, const double o[3], const double d[3], int above,
                  double tmax, int accel, double *t, double nrm[3]);

/* Fresnel's choice at a hit: dp (unit, towards the surface) meets the facet of unit
   normal nf (on dp's side) from a medium with index ratio eta = (far index) / (near
   index); one uniform draw picks reflection (R of unpolarised light) or refraction.
   dp becomes the outgoing unit direction; returns 1 when it crossed. */
int sim_turn(double dp[3], const double nf[3], double eta, uint64_t *rng);

/* Light through one interface's slab: it enters at a uniformly drawn point of the tile
   on the top of the slab (above = 1, dp pointing down) or on its bottom (above = 0,
   dp pointing up), with unit direction dp in the tile's frame, n = (lower index) /
   (upper index). Returns SIM_END_R when it leaves upward, SIM_END_T downward (so from
   below R is a crossing), SIM_END_LOST after SIM_MAX_HITS hits or a ray that runs
   sideways; dp holds the outgoing direction and *hits the hits. */
int sim_walk(const sim_surface *s, double n, int above, int accel, uint64_t *rng, double dp[3],
             int *hits);

/* One path of light arriving at polar angle ti, given as st = sin(ti) and ct = cos(ti)
   (a batch's rays share them), with its azimuth drawn uniformly, to average the grid's
   axes out (with in_plane, +x or -x only, for a profile along x, so the path stays in
   the x-z plane), on a uniformly drawn point of the tile, for index ratio n. */
void sim_path_run(const sim_surface *s, double n, double st, double ct, int accel, int in_plane,
                  uint64_t *rng, sim_path *out);

#endif
