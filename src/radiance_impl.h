/* SPDX-License-Identifier: MIT */
/* radiance_impl.h: what src/radiance.c, src/ttree.c and src/klems.c share. */
#ifndef BTDF_RADIANCE_IMPL_H
#define BTDF_RADIANCE_IMPL_H

#include "model_impl.h"
#include "radiance.h"
#include "table_impl.h"

/* Radiance's first tree coordinate from the sine of the incident polar angle. */
double rad_u0_of_sin(double sin_ti);

/* Radiance's tree descent: the leaf holding (u0, a, b); no interpolation. */
double rad_tree_lookup(const rad_node *nodes, double u0, double a, double b);

/* One adaptive tree for index n, values times scale (ttree.c): cells are split while
   their share of a slice's e_L1 is above eps. BTDF_EBUDGET when max_nodes would be
   passed. */
btdf_status rad_tree_build(const btdf_params *p, double n, double scale, double eps,
                           int threads, size_t max_nodes, rad_block *blk, char *msg,
                           size_t msglen);

/* One Klems matrix for index n, values times scale (klems.c). */
btdf_status rad_klems_build(const btdf_params *p, double n, double scale,
                            const rad_klems_basis *kb, int threads, rad_block *blk, char *msg,
                            size_t msglen);

/* Radiance's Klems patch of a direction given by its polar angle (degrees, [0, 90])
   and azimuth (degrees); -1 at theta = 90 or beyond. */
int rad_klems_patch(const rad_klems_basis *kb, double theta_deg, double phi_deg);

#endif
