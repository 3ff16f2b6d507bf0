/* SPDX-License-Identifier: MIT */
/* facet.c: the facet-space geometry of Eq. 25: the facet that refracts or mirrors e_i
   into a direction, and the direction and rho a facet gives. */
#include <math.h>

#include "model/facet.h"

int facet_eval(double n, double s, double k0, const rho_in *a, double stn, double ctn,
               double cpsi, double spsi, facet_geo *g)
{
    g->rho = 0.0;
    g->weight = 0.0;
    facet_ray r;
    if (!facet_refract(n, a->sin_ti, a->cos_ti, stn, ctn, cpsi, spsi, &r))
        return 0;
    double st = sqrt(r.ox * r.ox + r.oy * r.oy);
    g->sin_to = st;
    g->cos_to = r.oz;
    /* e_o on the axis: phi is undefined and does not matter, take phi = 0. */
    g->cos_phi = st > 0.0 ? r.ox / st : 1.0;
    g->sin_phi = st > 0.0 ? r.oy / st : 0.0;
    rho_out b;
    rho_out_init_m(&b, st, r.oz, s, k0, a); /* a's model */
    g->rho = rho_kernel(n, s, a, &b, g->cos_phi, g->sin_phi);
    double d = r.ca - n * r.cb; /* |v| with v = e_i + n e_o = (ca - n cb) h; != 0 for n != 1 */
    g->weight = -r.oz * d * d / (n * n * r.cb);
    return 1;
}

int facet_eval_r(double n, double s, double k0, const rho_in *a, double stn, double ctn,
                 double cpsi, double spsi, facet_geo *g)
{
    g->rho = 0.0;
    g->weight = 0.0;
    double ca, rx, ry, rz;
    if (!facet_mirror(a, stn, ctn, cpsi, spsi, &ca, &rx, &ry, &rz))
        return 0; /* no reflected direction in the upper medium */
    double st = sqrt(rx * rx + ry * ry);
    g->sin_to = st;
    g->cos_to = rz;
    /* e_r on the axis: phi is undefined and does not matter, take phi = 0. */
    g->cos_phi = st > 0.0 ? rx / st : 1.0;
    g->sin_phi = st > 0.0 ? ry / st : 0.0;
    /* rho_r from the model's own evaluator at e_r's angles, not from this geometry */
    g->rho = btdf_rho_r_model(a->model, n, s, k0, atan2(a->sin_ti, a->cos_ti), atan2(st, rz),
                        atan2(g->sin_phi, g->cos_phi));
    g->weight = rz * 4.0 * ca; /* d(omega_r) = 4 (e_i.h) d(omega_h) */
    return 1;
}

int facet_of_r(double sti, double cti, double str, double ctr, double cph, double sph,
               double *tn, double *psi, double *ca)
{
    double hx = sti + str * cph, hy = str * sph, hz = cti + ctr;
    if (!(hz > 0.0))
        return 0; /* both directions graze: no facet, and rho_r is 0 there */
    hy = fabs(hy);
    *ca = 0.5 * sqrt(hx * hx + hy * hy + hz * hz);
    *tn = atan2(sqrt(hx * hx + hy * hy), hz);
    *psi = atan2(hy, hx);
    return 1;
}

int facet_of(double n, double sti, double cti, double sto, double cto, double cph,
             double sph, double *tn, double *psi)
{
    return facet_of_ca(n, sti, cti, sto, cto, cph, sph, tn, psi, NULL);
}

int facet_of_ca(double n, double sti, double cti, double sto, double cto, double cph,
                double sph, double *tn, double *psi, double *ca_out)
{
    double vx = sti + n * sto * cph, vy = n * sto * sph, vz = cti + n * cto;
    double sg = vz < 0.0 ? -1.0 : 1.0; /* h = sg v / |v| has h_z >= 0 */
    double ca = sg * (sti * vx + cti * vz);
    double cb = -sg * (sto * (cph * vx + sph * vy) + cto * vz);
    if (!(ca > 0.0 && cb > 0.0) || vz == 0.0)
        return 0; /* no facet refracts e_i into e_o */
    double hx = sg * vx, hy = fabs(vy), hz = sg * vz;
    *tn = atan2(sqrt(hx * hx + hy * hy), hz);
    *psi = atan2(hy, hx);
    if (ca_out) {
        /* |v| > 0: vz != 0 was checked above */
        double len = sqrt(hx * hx + hy * hy + hz * hz);
        *ca_out = fmin(1.0, ca / len);
    }
    return 1;
}
