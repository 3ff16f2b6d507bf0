/* SPDX-License-Identifier: MIT */
/* facet.h: the facet-space geometry of Eq. 25, shared by the table builder, the
   estimator and the .bsdf reports. */
#ifndef BTDF_FACET_H
#define BTDF_FACET_H

#include "model/kernel.h"

/* Refraction of e_i(ti) through the facet of tilt tn and azimuth psi (psi = 0 leans
   towards e_i). On success (1) fills the outgoing geometry and rho; 0 where the
   facet cannot refract e_i into the lower hemisphere, and rho = 0 there. */
typedef struct facet_geo {
    double sin_to, cos_to, cos_phi, sin_phi; /* e_o in MODEL.md's angles */
    double rho;                              /* Eq. 25 at (ti, e_o) */
    double weight;                           /* |cos to| / chi: d(omega_o) = weight d(omega_h) */
} facet_geo;

int facet_eval(double n, double s, double k0, const rho_in *a, double tn_sin, double tn_cos,
               double cpsi, double spsi, facet_geo *g);

/* The mirror direction of e_i = (sin ti, 0, cos ti) on the facet h = (stn cpsi,
   stn spsi, ctn): ca = e_i.h and e_r = 2 ca h - e_i = (rx, ry, rz). 0 when the facet
   faces away from e_i (ca <= 0) or mirrors it into the lower medium (rz <= 0). */
static inline int facet_mirror(const rho_in *a, double stn, double ctn, double cpsi,
                               double spsi, double *ca, double *rx, double *ry, double *rz)
{
    *ca = stn * cpsi * a->sin_ti + ctn * a->cos_ti;
    if (!(*ca > 0.0))
        return 0;
    *rx = 2.0 * *ca * stn * cpsi - a->sin_ti;
    *ry = 2.0 * *ca * stn * spsi;
    *rz = 2.0 * *ca * ctn - a->cos_ti;
    return *rz > 0.0;
}

/* The same for reflection: the facet (tn, psi) mirrors e_i into e_r = 2 (e_i.h) h - e_i;
   g gets e_r (sin_to, cos_to = cos tr > 0), rho_r, and weight = cos tr 4 (e_i.h), so
   that cos tr d(omega_r) = weight d(omega_h). 0 where e_r would leave the upper
   hemisphere (rho_r = 0 there). */
int facet_eval_r(double n, double s, double k0, const rho_in *a, double tn_sin,
                 double tn_cos, double cpsi, double spsi, facet_geo *g);

/* The facet (tn, psi) that mirrors e_i into e_r (h along e_i + e_r) and its
   ca = e_i.h = |e_i + e_r|/2; 0 if none (both grazing). */
int facet_of_r(double sti, double cti, double str, double ctr, double cph, double sph,
               double *tn, double *psi, double *ca);

/* The facet (tn, psi) that refracts e_i into e_o for index n; 0 if none. */
int facet_of(double n, double sti, double cti, double sto, double cto, double cph,
             double sph, double *tn, double *psi);
/* The same, also giving ca = e_i . h of that facet. */
int facet_of_ca(double n, double sti, double cti, double sto, double cto, double cph,
                double sph, double *tn, double *psi, double *ca);

#endif
