/* SPDX-License-Identifier: MIT */
/* radiance_impl.h: what src/radiance/radiance.c, src/radiance/ttree.c and src/radiance/klems.c share. */
#ifndef BTDF_RADIANCE_IMPL_H
#define BTDF_RADIANCE_IMPL_H

#include "model/kernel.h"
#include "radiance/radiance.h"
#include "core/core.h"
#include "estimate/estimate.h"
#include "model/facet.h"

/* Radiance's first tree coordinate from the sine of the incident polar angle. */
double rad_u0_of_sin(double sin_ti);

/* Radiance's tree descent: the leaf holding (u0, a, b); no interpolation. */
double rad_tree_lookup(const rad_node *nodes, double u0, double a, double b);
/* The same descent: the leaf's index in nodes. */
size_t rad_tree_leaf(const rad_node *nodes, double u0, double a, double b);

/* The adaptive tree of one block (ttree.c): cells are split while their largest share
   of one light's e_L1, as Radiance reads the block, is above eps. A builder grows the
   tree to a threshold (again to a smaller one, keeping what it has) and cuts it at
   any threshold at or above the last one. With three channels (p->channels == 3) the
   builder samples each channel at its own index (blk's block for p->ior[c]), gives each
   leaf each channel's own value and splits a cell while the worst channel's share is
   above eps; the tree then carries blk->cv (CIE Y in the nodes, u', v' beside). */
typedef struct rad_tb rad_tb;
rad_tb *rad_tb_new(const btdf_params *p, const rad_block *blk, int threads);
/* BTDF_EBUDGET when the builder would hold more than max_nodes nodes (it keeps what
   it has: extracting at the same eps gives a valid, coarser tree). */
btdf_status rad_tb_grow(rad_tb *t, double eps, size_t max_nodes);
size_t rad_tb_nodes(const rad_tb *t);
/* The tree cut at eps (>= the last grow's) into blk->nodes, nnodes, leaves, depth. */
btdf_status rad_tb_extract(const rad_tb *t, double eps, rad_block *blk);
/* The same with one threshold per channel (colour: a cell is split while some channel's
   share is above its own eps; one channel: eps[0]); grow again to go below. */
btdf_status rad_tb_grow3(rad_tb *t, const double eps[3], size_t max_nodes);
btdf_status rad_tb_extract3(const rad_tb *t, const double eps[3], rad_block *blk);
void rad_tb_free(rad_tb *t);
/* new, grow and extract at one eps. */
btdf_status rad_tree_build(const btdf_params *p, double eps, int threads, size_t max_nodes,
                           rad_block *blk, char *msg, size_t msglen);

/* One Klems matrix for index n, values times scale (klems.c): Eq. 25, or rho_r when
   blk->reflect is set. */
btdf_status rad_klems_build(const btdf_params *p, double n, double scale,
                            const rad_klems_basis *kb, int threads, rad_block *blk, char *msg,
                            size_t msglen);

/* The same matrix in double, before it is rounded for the file (*out: malloc'd). */
btdf_status rad_klems_acc(const btdf_params *p, double n, double scale, int reflect,
                          const rad_klems_basis *kb, int threads, double **out, char *msg,
                          size_t msglen);
/* A Klems value exactly as the file holds it (6 significant digits, as a float). */
float rad_klems_value(double v);

/* Block k (0-3, radiance.h) for the index nc: label, sides, n, scale, n_light. */
void rad_block_of(int k, double nc, rad_block *b);
/* Block k of a three-channel Klems file r (r->p.ior[0..2], r->kb set): CIE X, Y, Z
   matrices from the channels' exact averages combined linearly, each then rounded. */
btdf_status rad_klems_colour(btdf_rad *r, int k, int threads, char *msg, size_t msglen);

/* Radiance's Klems patch of a direction given by its polar angle (degrees, [0, 90])
   and azimuth (degrees); -1 at theta = 90 or beyond. */
int rad_klems_patch(const rad_klems_basis *kb, double theta_deg, double phi_deg);

#endif
