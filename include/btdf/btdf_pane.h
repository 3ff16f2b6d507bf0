/* SPDX-License-Identifier: MIT */
/* btdf_pane.h: the system BSDF of a pane in air (a rough front face, a smooth or rough
   back face, a thickness and an absorption), by adding-doubling (docs/pane.md). */
#ifndef BTDF_PANE_H
#define BTDF_PANE_H

#include <stddef.h>

#include "btdf.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * A pane: air, the front face, a slab of index n and thickness d, the back face, air.
 * Both faces are interfaces of index n (air to glass) of the chosen model; the front
 * has smoothness front.smoothness, the back is flat or rough with its own smoothness.
 * Inside, light is attenuated by exp(-a d / cos theta_inside) on each crossing
 * (Beer-Lambert). The pane is laterally infinite and thin for a renderer: where light
 * leaves the pane is not recorded, only its direction.
 *
 * Sides: light FRONT falls on the front face (from the air in front), BACK on the back
 * face. The angles follow btdf.h for either side, in the frame of the face the light
 * falls on: ti in [0, pi/2] from that face's normal; a transmitted direction has
 * to in [pi/2, pi], a reflected one tr in [0, pi/2]; phi = pi is the forward plane
 * (straight through, or the mirror direction). Values are a BSDF in 1/sr without a
 * cosine factor, air to air, so reciprocal in the plain sense:
 *   f_T(FRONT; ti, to, phi) = f_T(BACK; pi - to, pi - ti, phi),
 *   f_R(side; ti, tr, phi) = f_R(side; tr, ti, phi).
 *
 * A flat face makes parts of the system a delta (a flat back reflects light from the
 * back as a mirror; two flat faces make every part a delta): btdf_pane_eval gives the
 * spread part only, btdf_pane_specular the delta's weight (its share of the incident
 * power, in the mirror or straight-through direction); btdf_pane_albedo counts both.
 *
 * Method: each face as reflection and transmission operators for both sides, per
 * Fourier mode in azimuth over a Gauss-Legendre quadrature in cos theta (the inside
 * nodes of the escape cone are the air nodes refracted, so a flat face is a diagonal
 * operator, exact); the slab as a diagonal attenuation; the adding equations per mode.
 * Evaluation interpolates the mode coefficients in cos theta (4-point Lagrange).
 */

typedef enum { BTDF_PANE_FRONT = 1, BTDF_PANE_BACK = 2 } btdf_pane_side;

#define BTDF_PANE_NODES_MAX 512
#define BTDF_PANE_MODES_MAX 512
#define BTDF_PANE_THICKNESS_MAX 1e4  /* mm */
#define BTDF_PANE_ABSORPTION_MAX 1e3 /* per mm */

typedef struct btdf_pane_opts {
    btdf_params front;        /* the front face (and the index n > 1 of the slab) */
    int front_smooth;         /* 1: the front face is flat (front.smoothness unused) */
    int back_smooth;          /* 1: the back face is flat (the default) */
    double back_smoothness;   /* the back face's s when it is rough */
    double thickness_mm;      /* d >= 0 */
    double absorption_per_mm; /* a >= 0; a d is what matters */
    int nodes;  /* Gauss-Legendre nodes in cos theta in air; 0: chosen from s (docs) */
    int modes;  /* Fourier modes in azimuth; 0: chosen from s */
    int threads; /* 0: all cores; the result does not depend on it */
    const btdf_full_opts *full; /* model full: its tallies' options (NULL: defaults) */
} btdf_pane_opts;

/* A flat back, no thickness and no absorption, the front btdf_params_default. */
BTDF_API void btdf_pane_opts_default(btdf_pane_opts *o);

/* BTDF_OK, or BTDF_EINVAL naming the value and what is allowed (n <= 1 in any channel,
   a smoothness outside [BTDF_S_MIN, BTDF_S_MAX], thickness or absorption negative,
   non-finite or above the limits, nodes or modes out of range). */
BTDF_API btdf_status btdf_pane_opts_check(const btdf_pane_opts *o, char *msg, size_t msglen);

typedef struct btdf_pane btdf_pane;

/* Builds the system. BTDF_EINVAL (options), BTDF_ENOMEM, or the model's status. */
BTDF_API btdf_status btdf_pane_new(const btdf_pane_opts *o, btdf_pane **out, char *msg,
                                   size_t msglen);
BTDF_API void btdf_pane_free(btdf_pane *p);
BTDF_API const btdf_pane_opts *btdf_pane_get_opts(const btdf_pane *p);
/* The quadrature actually used. */
BTDF_API void btdf_pane_size(const btdf_pane *p, int *nodes, int *modes);
BTDF_API double btdf_pane_seconds_build(const btdf_pane *p);

/* The spread part of the system's BSDF, channel ch, light on `side`, part TRANSMISSION
   (to in [pi/2, pi]) or REFLECTION (to is tr in [0, pi/2]); radians. 0 out of range or
   at grazing; never negative, NaN or inf. */
BTDF_API double btdf_pane_eval(const btdf_pane *p, btdf_pane_side side, btdf_part part, int ch,
                               double ti, double to, double phi);
/* btdf_pane_eval at count azimuths phi[k] for one (ti, to), into out[count]: the
   interpolation in cos theta done once (what a Klems or tree builder needs). */
BTDF_API void btdf_pane_eval_phis(const btdf_pane *p, btdf_pane_side side, btdf_part part,
                                  int ch, double ti, double to, size_t count, const double *phi,
                                  double *out);
/* The series btdf_pane_eval sums, for a renderer that evaluates the pane itself (the
   Mitsuba 3 plugin's thin-sheet mode): for light on `side`, part and channel ch,
     f(mu_i, mu_o, phi) = max(0, sum_{m < modes} c_m(mu_i, mu_o) cos(m phi)),
   mu_i = cos ti, mu_o = |cos to|, c_m interpolated from
   coef[(m * nodes + j) * nodes + o] (incidence node j, outgoing node o) at the
   ascending nodes mu[0 .. nodes) by 4-point Lagrange, first over j at mu_i, then over
   o at mu_o; the stencil is the four nodes from k = (the last node <= x) - 1, clamped to
   [0, nodes - 4]. Past the last node (x > mu[nodes - 1], towards the pole) the modes
   m >= 1 take instead the weights (0, 0, 0, r^m) on that stencil, r = sqrt((1 - x^2) /
   (1 - mu[nodes - 1]^2)) (sin theta over the last node's): they vanish on the axis,
   where a direction has no azimuth, as sin^m theta; m = 0 keeps the Lagrange weights.
   0 where mu_i or mu_o is not in (0, 1]. The pointers are the pane's,
   valid until btdf_pane_free. BTDF_EINVAL for a NULL pointer, a side, part or channel
   out of range. */
BTDF_API btdf_status btdf_pane_get_series(const btdf_pane *p, btdf_pane_side side,
                                          btdf_part part, int ch, const double **mu,
                                          const double **coef, int *nodes, int *modes);
/* The modes of that series at cosines mu_i, mu_o (the interpolation just described):
   c[m] for m < modes (c holds at least modes doubles, BTDF_PANE_MODES_MAX suffices),
   all 0 where mu_i or mu_o is not in (0, 1]. Returns modes, or 0 (c untouched) for a
   NULL pointer, a side, part or channel out of range. */
BTDF_API int btdf_pane_modes(const btdf_pane *p, btdf_pane_side side, btdf_part part, int ch,
                             double mu_i, double mu_o, double *c);
/* The weight of the delta part at ti (0 when there is none). */
BTDF_API double btdf_pane_specular(const btdf_pane *p, btdf_pane_side side, btdf_part part,
                                   int ch, double ti);
/* Hemispherical T and R (delta parts included) at ti for channel ch. */
BTDF_API void btdf_pane_albedo(const btdf_pane *p, btdf_pane_side side, int ch, double ti,
                               double *T, double *R);

/* The error of a against a reference ref (the same pane, finer) by MODEL.md section 6 on
   channel 0: over nti incidences (0: 24) on [0, ti_max], the largest e_L1 and e_T of
   every side and part (relative to max(T or R of ref, 0.01)), from an outgoing grid of
   nto x nphi cells (0: 96 x 96) in cos theta and phi. Delta parts are compared by
   their weights (e_T). */
typedef struct btdf_pane_error {
    double e_l1, e_t;   /* the worst of every side, part and incidence */
    double e_l1_ti;     /* where e_l1 is worst (radians) */
    int side;           /* its side */
    btdf_part part;     /* its part */
} btdf_pane_error;
BTDF_API btdf_status btdf_pane_compare(const btdf_pane *a, const btdf_pane *ref, double ti_max,
                                       size_t nti, size_t nto, size_t nphi,
                                       btdf_pane_error *out);

#ifdef __cplusplus
}
#endif

#endif
