/* SPDX-License-Identifier: MIT */
/* radiance_impl.h: what src/radiance/radiance.c, src/radiance/ttree.c and src/radiance/klems.c share. */
#ifndef BTDF_RADIANCE_IMPL_H
#define BTDF_RADIANCE_IMPL_H

#include "model/kernel.h"
#include "radiance/radiance.h"
#include "core/core.h"
#include "estimate/estimate.h"
#include "model/facet.h"
#include "model/full.h"

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
/* Model full: ms[ch] is channel ch's tally at the block's own index (its values add its
   multiply scattered part), ms_light[ch] at the light's (its floor adds that part's
   energy); both NULL for the other models. */
rad_tb *rad_tb_new(const btdf_params *p, const rad_block *blk, btdf_full *const *ms,
                   btdf_full *const *ms_light, int threads);
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
                            const rad_klems_basis *kb, const btdf_full *ms, int threads,
                            rad_block *blk, char *msg, size_t msglen);

/* The same matrix in double, before it is rounded for the file (*out: malloc'd). */
/* ms: model full, the tally at index n, whose multiply scattered part is added (patch
   averages of its series); NULL for the other models. */
btdf_status rad_klems_acc(const btdf_params *p, double n, double scale, int reflect,
                          const rad_klems_basis *kb, const btdf_full *ms, int threads,
                          double **out, char *msg, size_t msglen);
/* A Klems value exactly as the file holds it (6 significant digits, as a float). */
float rad_klems_value(double v);

/* Block k of a three-channel Klems file r (r->p.ior[0..2], r->kb set): CIE X, Y, Z
   matrices from the channels' exact averages combined linearly, each then rounded. */
btdf_status rad_klems_colour(btdf_rad *r, int k, int threads, char *msg, size_t msglen);

/* Radiance's Klems patch of a direction given by its polar angle (degrees, [0, 90])
   and azimuth (degrees); -1 at theta = 90 or beyond. */
int rad_klems_patch(const rad_klems_basis *kb, double theta_deg, double phi_deg);

/* ---- shared by radiance.c (build, probes), lookup.c and report.c ---- */

/* Model full: channel c's tally at index n (ior[c] or its inverse), else NULL. */
btdf_full *rad_ms(const btdf_rad *r, int c, double n);
/* The parameters the kernels take: smith's for full (its single scattering). */
btdf_params rad_single(const btdf_params *p);
/* full.c: each channel's tallies of a file of full into r->ms (BTDF_OK at once for the
   other models), with progress; and block k's tallies per channel at its own index
   (ms) and at its light's (ms_light): 1 for full, else 0 with all NULL. */
btdf_status rad_make_ms(btdf_rad *r, int threads, btdf_progress_fn progress, void *user,
                        char *msg, size_t msglen);
int rad_block_ms(const btdf_rad *r, int k, btdf_full *ms[3], btdf_full *ms_light[3]);

/* The index of the light block k serves, in channel c. */
double rad_n_light(const btdf_rad *r, int k, int c);
/* Channel c (-1: Y) of leaf i of tree block b: chosen = 1, in a colour tree, the value
   the builder chose (cv), else as Radiance reads the file back. */
double rad_tree_value(const btdf_rad *r, const rad_block *b, size_t i, int c, int chosen);
/* The view p and light q of block k (Radiance's frame) for the light at ti in its own
   MODEL.md frame and a view at (to, phi) in it. */
void rad_render_dirs(const btdf_rad *r, int k, double ti, double to, double phi, double p[3],
                     double q[3]);

/* Stratified probes of one block as a render reads it: m light angles, kv views each
   (stratified in sin^2 of the view's polar angle and its azimuth: equal projected solid
   angle), with the tree coordinates of each (view, light) pair and Eq. 25 (or rho_r) for
   the light. */
typedef struct rad_probes {
    size_t m, ns, nphi, kv;
    double ti_max;
    double *ti, *T, *fl; /* per angle: light angle, T (or R) of the light, max(T, 0.01) */
    double *u0, *a, *b, *f;
    const btdf_rad *r;
    int k, c;       /* block, channel (0 for one channel) */
    int chosen;     /* a colour tree's channel as the builder chose it (rad_tree_value) */
    double n_light; /* the index of the light the block serves, in channel c */
    btdf_full *ms;  /* model full: the tally at n_light, else NULL */
    const rad_block *tree; /* the tree under test; NULL for a Klems block, whose value
                              as Radiance reads it is stored in u0 (a, b unused) */
    btdf_ti_error *res;
} rad_probes;

void rad_probes_free(rad_probes *pr);
/* m light angles up to ti_max, ns x nphi views each, for block k, channel c. */
btdf_status rad_probes_make(const btdf_rad *r, int k, int c, double ti_max, size_t m,
                            size_t ns, size_t nphi, uint64_t seed, int threads,
                            rad_probes *pr);
/* The probes' errors of tree (NULL: a Klems block) into res[m]. */
void rad_probes_eval(rad_probes *pr, const rad_block *tree, int threads, btdf_ti_error *res);

/* lookup.c: the tree coordinates of the incident direction p and the outgoing q
   (Radiance frame). */
void rad_tree_coords(const double p[3], const double q[3], double *u0, double *a, double *b);
/* Channel c (0-2; -1: Y) of the file at (p, q); chosen: a colour tree's
   channel as its builder chose it. */
double rad_lookup_ch(const btdf_rad *r, int k, int c, int chosen, const double p[3],
                     const double q[3]);
/* The file's value as a render reads it, the light on side `light` at ti. */
double rad_render(const btdf_rad *r, btdf_side light, int c, int chosen, double ti, double to,
                  double phi);

/* report.c: btdf_rad_report_channel; chosen: a colour tree's channels as its builder
   chose them (the builder's own check). */
btdf_status rad_report_ch(const btdf_rad *r, int k, int c, int chosen, size_t test_angles,
                          size_t points_per_angle, uint64_t seed, int threads,
                          btdf_report *rep);

#endif
