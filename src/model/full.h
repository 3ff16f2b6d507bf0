/* SPDX-License-Identifier: MIT */
/* full.h: the object of the model full (full.c) as the library's own code sees it: its
   layout, the multiply scattered part alone, and the record by which a table file keeps
   it (full_store.c). */
#ifndef BTDF_MODEL_FULL_H
#define BTDF_MODEL_FULL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "btdf.h"

#define FULL_NODES_MAX 33 /* the ladder's 25 angles and 8 about the critical angle */
#define FULL_K 8          /* polynomials in mu = |cos t| of degree 0..7 */
#define FULL_M 5          /* cos(m phi), m = 0..4 */
#define FULL_NB (FULL_K * FULL_M)
#define FULL_SUB 8        /* points per ladder interval of the clipping's energy factor */
#define FULL_CHUNK 8192u  /* paths per work item (its own random stream) */
#define FULL_MAX_EVENTS 4096 /* a path longer than this is counted lost */

struct btdf_full {
    double n, s, alpha;
    uint64_t paths, seed;
    int nodes;
    double node_deg[FULL_NODES_MAX]; /* increasing */
    /* q_km(mu) = sum_j poly[m][k][j] mu^j: sin^m t q_km(mu), k < FULL_K, orthonormal for
       the weight mu dmu on [0, 1] (so the series is smooth at the pole, where a term
       cos(m phi) must vanish as sin^m t) */
    double poly[FULL_M][FULL_K][FULL_K];
    /* per node: the coefficients of the multiply scattered rho, [T/R][k][m] */
    double coef[FULL_NODES_MAX][2][FULL_K][FULL_M];
    /* per node: tallied energies, order 1 and 2+, T and R, and their standard errors */
    double e1[FULL_NODES_MAX][2], ems[FULL_NODES_MAX][2], ems_se[FULL_NODES_MAX][2];
    double lost[FULL_NODES_MAX];
    /* per ladder interval k (nodes k, k + 1), at the weights w = j / FULL_SUB of its
       upper end, T and R: the factor <= 1 that gives the clipped series (max(0,
       series)) of the interpolated coefficients the energy of that series itself, the
       tallied one (full_set_clip_scale); linear in w between them */
    double cscale[FULL_NODES_MAX][FULL_SUB + 1][2];
    double seconds;
};

/* The orthonormal polynomials of the series (the same bits every time). */
void full_make_poly(double poly[FULL_M][FULL_K][FULL_K]);
/* Sets f->cscale from f's coefficients (btdf_full_new and full_from_text call it):
   a truncated series dips below 0 where its lobe is near 0, and clipping the dips adds
   their energy (up to 10 % of the multiply scattered part at grazing incidence, 2 % of
   R + T: docs/model.md section 12); the clipped series is scaled back to the series'
   own energy, the tallied one, at FULL_SUB + 1 points of each ladder interval. */
bool full_set_clip_scale(btdf_full *f); /* false: out of memory */
/* That factor at the ladder interval k and weight w of full_locate, side h. */
static inline double full_clip_factor(const btdf_full *f, int k, double w, int h)
{
    double x = w * FULL_SUB; /* w in [0, 1] */
    int j = (int)x;
    j = j < FULL_SUB ? j : FULL_SUB - 1;
    double t = x - j;
    return (1.0 - t) * f->cscale[k][j][h] + t * f->cscale[k][j + 1][h];
}
/* The ladder interval of ti (degrees) and the weight of its upper end. */
int full_locate(const btdf_full *f, double ti_deg, double *w);
/* The multiply scattered rho alone, side h (0 transmission, 1 reflection), at incidence
   ti_deg (degrees), mu = |cos| of the outgoing direction, cphi = cos phi; >= 0. */
double full_ms(const btdf_full *f, int h, double ti_deg, double mu, double cphi);
/* The modes of the multiply scattered part of side h at incidence ti_deg and outgoing
   |cos| mu: a[m] = sin^m t sum_k q_km(mu) c_km(ti), m < FULL_M, so that the part at
   azimuth phi is max(0, sum_m a[m] cos(m phi)) (full_ms's value, summed in another
   order). */
void full_ms_modes(const btdf_full *f, int h, double ti_deg, double mu, double *a);
/* The multiply scattered part at azimuth phi from the modes a of full_ms_modes, given
   cos phi: max(0, sum_m a[m] cos(m phi)), the cosines by Chebyshev's recurrence (a dip
   of the truncated series below 0 is clipped, as full_ms). */
static inline double full_ms_at(const double *a, double cp)
{
    double cm[FULL_M];
    cm[0] = 1.0;
    cm[1] = cp;
    for (int m = 2; m < FULL_M; m++)
        cm[m] = 2.0 * cp * cm[m - 1] - cm[m - 2]; /* Chebyshev: cos(m phi) */
    double v = 0.0;
    for (int m = 0; m < FULL_M; m++)
        v += a[m] * cm[m];
    return v > 0.0 ? v : 0.0;
}
/* rho of full on side h (0: transmission, to in [90, 180]; 1: reflection, to = tr in
   [0, 90]) at the np azimuths 180 p / (np - 1) degrees, p = 0..np-1: smith's value at
   each plus the multiply scattered part, its modes formed once for the pair (a row of
   btdf_full_rho_deg / btdf_full_rho_r_deg to a few ulps of the series, 5 times faster). */
void full_rho_row_deg(const btdf_full *f, int h, double ti, double to, int np, double *out);

/* The tallied energy of orders 2+ on side h at ti (radians), interpolated as the
   coefficients are, and its binomial standard error (the larger of the two nodes'). */
double full_ms_energy(const btdf_full *f, int h, double ti, double *se);
/* The largest standard error of the tally on side h over the ladder nodes whose
   interval meets [ti0, ti1] (radians): the noise floor of anything made from it. */
double full_ms_noise(const btdf_full *f, int h, double ti0, double ti1);

/* A copy (NULL when out of memory). */
btdf_full *full_clone(const btdf_full *f);

/* One ladder node as a line of text, as table files keep it: "deg e1_T ems_T se_T e1_R
   ems_R se_R lost" then the 40 coefficients of T and the 40 of R (k major), each %.17g,
   so it reads back to the same bits. Returns the length written (snprintf's rule). */
#define FULL_NODE_TEXT_MAX 4096
int full_node_text(const btdf_full *f, int node, char *buf, size_t len);
/* The object of index n and smoothness s from `nodes` lines of full_node_text (in
   increasing angle), with the tally's paths and seed; BTDF_EFORMAT naming the node and
   what is wrong, BTDF_ENOMEM. */
btdf_status full_from_text(double n, double s, uint64_t paths, uint64_t seed,
                           const char *const *lines, int nodes, btdf_full **out, char *msg,
                           size_t msglen);

#endif
