/* SPDX-License-Identifier: MIT */
/* kernel.h: the Eq. 25 kernel shared by the evaluator, the tables and the estimates: the
   facet-space forms here, the accurate evaluator in model/rho.h (over model/elemfn.h),
   both included. */
#ifndef BTDF_MODEL_IMPL_H
#define BTDF_MODEL_IMPL_H

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "btdf.h"
#include "model/elemfn.h"
#include "model/rho.h"

/* Shadowing V(t) of Eq. 25 from tan t >= 0 and 1/tan^2 t precomputed by the caller.
   V(0) = 1 (MODEL.md 3.4); V(pi/2) = 0. */
static inline double shadow_v(double tan_t, double s, double k0)
{
    if (!(tan_t > 0.0))
        return 1.0; /* t = 0: exp(-s^2/(4 tan^2)) -> 0, so V -> exp(0) */
    if (isinf(tan_t))
        return 0.0; /* grazing: k0 tan/s -> inf, V -> 0 (and avoids inf * 0) */
    double e = exp(-s * s / (4.0 * tan_t * tan_t));
    return exp(-(k0 * tan_t / s) * e);
}

/* Incoming-side quantities that depend on ti only: hoisted out of the inner loop. */
typedef struct rho_in {
    double sin_ti, cos_ti;
    double pref; /* s^2/(4 pi) * V(ti) / cos ti, 0 when cos ti = 0 (xu-sun); without
                    V(ti) for smith, whose G2 goes to the outgoing side whole */
    btdf_model model; /* which shadowing-masking (rho_in_init: xu-sun) */
    double lam;       /* smith: Lambda(ti) */
} rho_in;

/* Outgoing-side quantities that depend on to only. */
typedef struct rho_out {
    double sin_to, cos_to; /* cos_to <= 0 */
    double pref;           /* V(to) / |cos to|, 0 when cos to = 0 */
} rho_out;

static inline void rho_in_init(rho_in *a, double sin_ti, double cos_ti, double s, double k0)
{
    a->sin_ti = sin_ti;
    a->cos_ti = cos_ti;
    a->model = BTDF_MODEL_XU_SUN;
    a->lam = 0.0;
    /* cos ti = 0 is grazing incidence, where rho -> 0 (MODEL.md 3.5): no 1/0. */
    a->pref = cos_ti > 0.0 ? s * s / (4.0 * M_PI) * shadow_v(sin_ti / cos_ti, s, k0) / cos_ti
                           : 0.0;
}

static inline void rho_out_init(rho_out *b, double sin_to, double cos_to, double s, double k0)
{
    b->sin_to = sin_to;
    b->cos_to = cos_to;
    double c = -cos_to;
    /* |cos to| = 0 is a grazing exit, where rho -> 0 (MODEL.md 3.5): no 1/0. */
    b->pref = c > 0.0 ? shadow_v(sin_to / c, s, k0) / c : 0.0;
}

/* The model's outgoing factors of the facet-space evaluators: every place where the
   models differ goes through one of the two switches below (and rho_in_init_m), so a
   model slots in by adding a case to each. The Smith forms are in model/elemfn.h. */

/* rho_in_init in the model m: for smith the incoming prefactor drops V(ti) and keeps
   Lambda(ti) for the outgoing side (G2 does not factor). */
static inline void rho_in_init_m(rho_in *a, double sin_ti, double cos_ti, double s, double k0,
                                 btdf_model m)
{
    switch (m) {
    case BTDF_MODEL_SMITH:
    case BTDF_MODEL_FULL: /* its single scattering; tables add the rest (table.h) */
        a->sin_ti = sin_ti;
        a->cos_ti = cos_ti;
        a->pref = cos_ti > 0.0 ? s * s / (4.0 * M_PI) / cos_ti : 0.0; /* grazing: rho = 0 */
        a->model = BTDF_MODEL_SMITH;
        a->lam = bt_lambda_f(sin_ti, cos_ti > 0.0 ? cos_ti : 0.0, s);
        return;
    default: /* xu-sun (callers have refused the rest) */
        rho_in_init(a, sin_ti, cos_ti, s, k0);
        return;
    }
}

/* The outgoing shadowing of a transmission to the direction (sin to, |cos to| > 0):
   V(to) for xu-sun, G2 = B(1 + Lambda(ti), 1 + Lambda(to)) for smith. */
static inline double rho_out_shadow(const rho_in *a, double sin_to, double abs_cos_to,
                                    double s, double k0)
{
    switch (a->model) {
    case BTDF_MODEL_SMITH:
        return bt_smith_t_factor(a->lam, bt_lambda_f(sin_to, abs_cos_to, s));
    default:
        return shadow_v(sin_to / abs_cos_to, s, k0);
    }
}

/* The same for a reflection to (sin tr, cos tr > 0): V(tr), or 1/(1 + Lambda(ti) +
   Lambda(tr)) for smith. */
static inline double rho_out_shadow_r(const rho_in *a, double sin_tr, double cos_tr,
                                      double s, double k0)
{
    switch (a->model) {
    case BTDF_MODEL_SMITH:
        return bt_smith_r_factor(a->lam, bt_lambda_f(sin_tr, cos_tr, s));
    default:
        return shadow_v(sin_tr / cos_tr, s, k0);
    }
}

/* rho_out_init with the outgoing factor of a's model. */
static inline void rho_out_init_m(rho_out *b, double sin_to, double cos_to, double s,
                                  double k0, const rho_in *a)
{
    if (a->model == BTDF_MODEL_XU_SUN) {
        rho_out_init(b, sin_to, cos_to, s, k0); /* the bits of every xu-sun output */
        return;
    }
    b->sin_to = sin_to;
    b->cos_to = cos_to;
    double c = -cos_to;
    /* |cos to| = 0 is a grazing exit, where rho -> 0 (MODEL.md 3.5): no 1/0. */
    b->pref = c > 0.0 ? rho_out_shadow(a, sin_to, c, s, k0) / c : 0.0;
}

/* Eq. 25 (MODEL.md section 2) for one channel, from hoisted incoming and outgoing
   terms and v = e_i + n e_o with e_i.v and e_o.v; rho_kernel below computes those
   from (cos phi, sin phi). The tables' kernel: it returns early where no facet
   connects the directions, so its loops are scalar; bt_rho below is the branch-free,
   vectorised form of the public entry points, accurate near n = 1 as well.
   With v = e_i + n e_o, the facet normal is h = sg v/|v| with sg = sign(v_z), and
     cos a = sg (e_i.v)/|v|,  cos b = -sg (e_o.v)/|v|,  cos tn = |v_z|/|v|,
     (n cos b - cos a)^2 = |v|^2 exactly,  so chi = n^2 cos b / |v|^2,
     1/cos^2 tn = 1 + tan^2 tn = |v|^2 / v_z^2,
     Ft = 2 n ca cb (1/(ca + n cb)^2 + 1/(n ca + cb)^2)   (1 - R without cancellation). */
static inline double rho_kernel_v(double n, double s, const rho_in *a, const rho_out *b,
                                  double vx, double vy, double vz, double ei_v, double eo_v)
{
    double rxy2 = vx * vx + vy * vy;
    double vz2 = vz * vz;
    double len2 = rxy2 + vz2;
    /* The exponent s^2 tan^2 tn / 4 written without dividing by vz2, which may be 0
       (a facet standing vertical): cut when the exponential underflows. */
    if (!(0.25 * s * s * rxy2 < BTDF_EXP_CUT * vz2))
        return 0.0;
    double sg = vz < 0.0 ? -1.0 : 1.0; /* h = sg v / |v| has h_z > 0 */
    double ca_l = sg * ei_v;  /* cos a * |v| */
    double cb_l = -sg * eo_v; /* cos b * |v| */
    if (!(ca_l > 0.0 && cb_l > 0.0))
        return 0.0; /* no facet refracts e_i into e_o (MODEL.md 2, 3.7) */
    /* len2 >= (1 - n)^2 > 0 for n != 1 (validated), and vz2 > 0 after the cut. */
    double inv_len = 1.0 / sqrt(len2);
    double ca = ca_l * inv_len, cb = cb_l * inv_len;
    double t2 = rxy2 / vz2;        /* tan^2 tn, finite after the cut */
    double sec2 = len2 / vz2;      /* 1 / cos^2 tn */
    double d1 = ca + n * cb, d2 = n * ca + cb; /* both > 0 since ca, cb > 0 */
    double ft = 2.0 * n * ca * cb * (1.0 / (d1 * d1) + 1.0 / (d2 * d2));
    double chi = n * n * cb / len2;
    double r = a->pref * b->pref * ca * ft * chi * sec2 * sec2 * exp(-0.25 * s * s * t2);
    /* Results below the smallest normal double are 0 (MODEL.md 3.6). */
    return r >= DBL_MIN ? r : 0.0;
}

static inline double rho_kernel(double n, double s, const rho_in *a, const rho_out *b,
                                double cos_phi, double sin_phi)
{
    double vx = a->sin_ti + n * b->sin_to * cos_phi;
    double vy = n * b->sin_to * sin_phi;
    double vz = a->cos_ti + n * b->cos_to;
    double ei_v = a->sin_ti * vx + a->cos_ti * vz; /* e_i . v */
    double eo_v = b->sin_to * (cos_phi * vx + sin_phi * vy) + b->cos_to * vz;
    return rho_kernel_v(n, s, a, b, vx, vy, vz, ei_v, eo_v);
}

/* Refraction of e_i = (sin ti, 0, cos ti) through the facet with normal
   h = (sin tn cos psi, sin tn sin psi, cos tn): e_o = -e_i/n + (cos a/n - cos b) h.
   1 with the two cosines and e_o when the facet refracts e_i into the lower
   hemisphere; 0 when it faces away (cos a <= 0), reflects totally (sin a >= n), or
   sends the ray back up (e_o,z >= 0). */
typedef struct facet_ray {
    double ca, cb, ox, oy, oz;
} facet_ray;

static inline int facet_refract(double n, double sti, double cti, double stn, double ctn,
                                double cpsi, double spsi, facet_ray *r)
{
    double ca = stn * cpsi * sti + ctn * cti;
    if (!(ca > 0.0))
        return 0; /* the facet faces away from e_i */
    double sb2 = (1.0 - ca * ca) / (n * n);
    if (!(sb2 < 1.0))
        return 0; /* total internal reflection on this facet */
    double cb = sqrt(1.0 - sb2);
    if (!(cb > 0.0))
        return 0; /* grazing on the facet: no transmitted direction */
    double g = ca / n - cb;
    r->ca = ca;
    r->cb = cb;
    r->ox = -sti / n + g * stn * cpsi;
    r->oy = g * stn * spsi;
    r->oz = -cti / n + g * ctn;
    return r->oz < 0.0; /* refracted back into the upper hemisphere otherwise */
}

void model_sincos_deg(double deg, double *s, double *c);

/* min over channels of T(ti) from a coarse quadrature (within 2.8e-3 absolute, worst
   near the critical angle for n < 1: model_transmittance_coarse). */
double model_transmittance_coarse(const btdf_params *p, double ti);

/* T(ti) (refl = 0) or R(ti) (refl = 1) per channel, with the given panels of the
   facet-slope and azimuth quadratures (16 x 12 is btdf_transmittance's converged rule);
   ti in [0, pi/2] and p checked by the caller. */
void bt_albedo_panels(const btdf_params *p, int refl, double ti, int u_panels,
                      int psi_panels, double *out);

/* min over channels of R(ti) from the same coarse quadrature. */
double model_reflectance_coarse(const btdf_params *p, double ti);

#endif
