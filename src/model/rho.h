/* SPDX-License-Identifier: MIT */
/* rho.h: the accurate evaluator of rho (Eq. 25) and of rho_r, branch-free over the
   elementary functions of model/elemfn.h; vectorised loops give the bits of single calls. */
#ifndef BTDF_MODEL_RHO_H
#define BTDF_MODEL_RHO_H

#include <float.h>
#include <math.h>

#include "model/elemfn.h"

/* The (ti, to) part of rho: sines and cosines, w = e_i + e_o without its azimuth
   term, and the shadowing prefactors. Channel-independent. */
typedef struct bt_io {
    double sti, cti;   /* sin ti, cos ti >= 0 */
    double sto;        /* sin to >= 0 */
    double cto;        /* |cos to| >= 0 */
    double wx0;        /* sin ti - sin to */
    double wz;         /* cos ti - |cos to| */
    double pref;       /* s^2/(4 pi) / (cos ti |cos to|), 0 at grazing (bt_io_pref) */
    double sh;         /* shadowing exponent: V(ti) V(to) = e^-sh */
} bt_io;

/* From sin/cos of ti and of b = pi - to, and sin/cos of p and sin m with
   p = (ti + b)/2, m = (ti - b)/2 = (ti + to - pi)/2 accurate to its own ulps. */
BT_INLINE void bt_io_set(bt_io *io, double sti, double cti, double sto, double cto,
                         double sp, double cp, double sm)
{
    io->sti = sti;
    io->cti = cti;
    io->sto = sto;
    io->cto = cto;
    io->wx0 = 2.0 * cp * sm; /* sin ti - sin b */
    io->wz = -2.0 * sp * sm; /* cos ti - cos b */
    io->pref = 0.0;
    io->sh = 0.0;
}

/* The shadowing prefactor, apart: a caller may skip it where no facet connects. */
BT_INLINE void bt_io_pref(bt_io *io, double s, double k0)
{
    io->pref = s * s / (4.0 * M_PI) * bt_inv_cos(io->cti) * bt_inv_cos(io->cto);
    io->sh = bt_shadow_exponent(io->sti, io->cti, s, k0) +
             bt_shadow_exponent(io->sto, io->cto, s, k0);
}

/* The same prefactor with the Smith term of the same surface (BTDF_MODEL_SMITH):
   V(ti) V(to) = e^-sh becomes G2 = B(1 + Lambda(ti), 1 + Lambda(to)) = e^-sh, Lambda of
   the lower direction from |tan to| (sto, cto >= 0), so that swapping the two sides
   swaps the two Lambdas and the symmetric B keeps the reciprocity of MODEL.md 4. */
BT_INLINE void bt_io_pref_smith_sh(bt_io *io, double s, double sh)
{
    io->pref = s * s / (4.0 * M_PI) * bt_inv_cos(io->cti) * bt_inv_cos(io->cto);
    io->sh = sh;
}
BT_INLINE void bt_io_pref_smith(bt_io *io, double s)
{
    bt_io_pref_smith_sh(io, s, bt_smith_t_exponent(bt_lambda(io->sti, io->cti, s),
                                                   bt_lambda(io->sto, io->cto, s)));
}

/* sin and cos of four reduced arguments at once (the lanes of one vector where the
   target has them): lane by lane the operations of bt_sincos_red. */
BT_INLINE void bt_sincos_red4(const double y[4], const int swap[4], double sn[4],
                              double cs[4])
{
    for (int k = 0; k < 4; k++)
        bt_sincos_red(y[k], swap[k], &sn[k], &cs[k]);
}

/* From the sines and cosines of ti, b = pi - to, p and m (lanes 0 to 3). */
BT_INLINE void bt_io_from4(bt_io *io, const double sn[4], const double cs[4])
{
    double cti = cs[0], sto = sn[1], cto = cs[1];
    bt_io_set(io, sn[0], cti > 0.0 ? cti : 0.0, sto > 0.0 ? sto : 0.0,
              cto > 0.0 ? cto : 0.0, sn[2], cs[2], sn[3]);
}

/* Radians: ti in [0, pi/2], to in [pi/2, pi] (a few ulps beyond are clamped). */
BT_INLINE void bt_io_geom_rad(bt_io *io, double ti, double to)
{
    double b = (BT_PI_HI - to) + BT_PI_LO; /* exact difference: to >= pi/2 */
    b = b > 0.0 ? b : 0.0;
    /* ti + to - pi to a few ulps of itself: the sum's rounding error is kept (Knuth's
       two-sum) and pi is subtracted in two parts; the first step is exact because
       ti + to lies in [pi/2, 3 pi/2] (Sterbenz). |m| <= pi/4. */
    double sum = ti + to, bb = sum - ti, lo = (ti - (sum - bb)) + (to - bb);
    double m = 0.5 * (((sum - BT_PI_HI) + lo) - BT_PI_LO);
    double x[4] = {ti, b, ti - m, m}, y[4], sn[4], cs[4];
    int sw[4];
    for (int k = 0; k < 4; k++) { /* as bt_sincos_rad */
        sw[k] = x[k] > 0.78539816339744828;
        y[k] = sw[k] ? (BT_PIO2_HI - x[k]) + BT_PIO2_LO : x[k];
    }
    bt_sincos_red4(y, sw, sn, cs);
    bt_io_from4(io, sn, cs);
}

BT_INLINE void bt_io_rad(bt_io *io, double ti, double to, double s, double k0)
{
    bt_io_geom_rad(io, ti, to);
    bt_io_pref(io, s, k0);
}

/* Degrees: ti in [0, 90], to in [90, 180]; exact at multiples of 90. */
BT_INLINE void bt_io_geom_deg(bt_io *io, double ti, double to)
{
    double sum = ti + to, bb = sum - ti, lo = (ti - (sum - bb)) + (to - bb);
    double md = 0.5 * ((sum - 180.0) + lo); /* (ti + to - 180) / 2, Sterbenz as above */
    double x[3] = {ti, 180.0 - to, ti - md}, y[4], sn[4], cs[4]; /* 180 - to: exact */
    int sw[4];
    for (int k = 0; k < 3; k++) { /* as bt_sincos_deg */
        sw[k] = x[k] > 45.0;
        y[k] = (sw[k] ? 90.0 - x[k] : x[k]) * BT_DEG;
    }
    sw[3] = 0;
    y[3] = md * BT_DEG;
    bt_sincos_red4(y, sw, sn, cs);
    bt_io_from4(io, sn, cs);
}

/* The azimuth part: h2 = sin^2(c/2) and sphi = sin c = |sin phi|, where c = pi - |phi|
   (folded to [0, pi]) is the angle from the forward plane: 1 + cos phi = 2 h2. */
typedef struct bt_az {
    double h2, sphi;
} bt_az;

BT_INLINE void bt_az_half(bt_az *az, double sh, double ch)
{
    az->h2 = sh * sh;
    az->sphi = 2.0 * sh * ch;
}

/* Folds any finite phi (radians) to c = |pi - (|phi| mod 2 pi)| in [0, pi], exactly
   where it matters (near the forward plane). */
BT_INLINE double bt_fold_rad(double phi)
{
    double x = fabs(phi);
    if (x > 2.0 * BT_PI_HI)
        x = fmod(x, 2.0 * BT_PI_HI); /* beyond one turn: modulo the double nearest 2 pi */
    double c = (x - BT_PI_HI) - BT_PI_LO;
    return fabs(c);
}

BT_INLINE double bt_fold_deg(double phi)
{
    double x = fabs(phi);
    if (x >= 360.0)
        x = fmod(x, 360.0); /* exact */
    return fabs(x - 180.0);
}

BT_INLINE void bt_az_rad(bt_az *az, double c)
{
    double sh, ch;
    bt_sincos_rad(0.5 * c, &sh, &ch);
    bt_az_half(az, sh, ch);
}

BT_INLINE void bt_az_deg(bt_az *az, double cdeg)
{
    double sh, ch;
    bt_sincos_deg(0.5 * cdeg, &sh, &ch);
    bt_az_half(az, sh, ch);
}

/* Eq. 25 for index n = 1 + d from the parts above; branch-free (MODEL.md section 2,
   the algebra in the comment of rho_kernel_v). 0 where no facet connects the two
   directions, and below the smallest normal double. */
/* The geometry of v = w + d e_o shared by bt_rho and bt_rho_one. */
#define BT_RHO_GEOMETRY                                                                 \
    double cph = 2.0 * h2 - 1.0;                                                        \
    double wx = io->wx0 + io->sto * (2.0 * h2); /* sin ti + sin to cos phi */         \
    double wy = io->sto * sphi;                                                         \
    double wz = io->wz;                                                                 \
    double w2 = wx * wx + wy * wy + wz * wz; /* |e_i + e_o|^2 = 2 + 2 e_i.e_o */       \
    double vx = wx + d * io->sto * cph;                                                 \
    double vy = n * wy;                                                                 \
    double vz = wz - d * io->cto;                                                       \
    double ei_v = n * (0.5 * w2) - d; /* 1 + n e_i.e_o */                              \
    double eo_v = d + 0.5 * w2;       /* e_i.e_o + n */                                \
    double rxy2 = vx * vx + vy * vy, vz2 = vz * vz, len2 = rxy2 + vz2;                  \
    double sg = vz < 0.0 ? -1.0 : 1.0;                                                  \
    double ca_l = sg * ei_v, cb_l = -sg * eo_v;                                         \
    double e = 0.25 * s * s * rxy2;                                                     \
    /* cut where exp underflows (this also keeps v_z = 0 out, MODEL.md 3.5), and where \
       no facet refracts e_i into e_o (MODEL.md 2, 3.7); & rather than &&: no branch */ \
    int ok = (ca_l > 0.0) & (cb_l > 0.0) & (e < BTDF_EXP_CUT * vz2)

/* The value from BT_RHO_GEOMETRY's quantities and the prefactor pref. */
#define BT_RHO_VALUE(pref)                                                              \
    /* On the discarded branch every divisor is replaced by 1: no 1/0, no NaN. */      \
    vz2 = ok ? vz2 : 1.0;                                                               \
    len2 = ok ? len2 : 1.0;                                                             \
    ca_l = ok ? ca_l : 1.0;                                                             \
    cb_l = ok ? cb_l : 1.0;                                                             \
    double inv_len = 1.0 / sqrt(len2); /* len2 >= d^2 > 0 */                            \
    double inv_vz2 = 1.0 / vz2;                                                         \
    double ca = ca_l * inv_len, cb = cb_l * inv_len;                                    \
    double sec2 = len2 * inv_vz2;                                                       \
    double d1 = ca + n * cb, d2 = n * ca + cb; /* > 0 */                                \
    double q1 = d1 * d1, q2 = d2 * d2;                                                  \
    double ft = 2.0 * n * ca * cb * ((q1 + q2) / (q1 * q2));                            \
    double chi = n * n * cb * (inv_len * inv_len);                                      \
    double r = bt_exp_mul(-(e * inv_vz2 + io->sh), (pref) * ca * ft * chi * (sec2 * sec2)); \
    r = (ok & (r >= DBL_MIN)) ? r : 0.0

/* Eq. 25 for index n = 1 + d from the parts above; branch-free (MODEL.md section 2,
   the algebra in the comment of rho_kernel_v). 0 where no facet connects the two
   directions, and below the smallest normal double. */
BT_INLINE double bt_rho(double n, double d, double s, const bt_io *io, double h2,
                        double sphi)
{
    BT_RHO_GEOMETRY;
    BT_RHO_VALUE(io->pref);
    return r;
}

/* The same for one evaluation: the shadowing prefactor (four exponentials) is only
   formed where some facet connects the directions; the same operations, the same
   bits. */
BT_INLINE double bt_rho_one(double n, double d, double s, double k0, bt_io *io, double h2,
                            double sphi)
{
    BT_RHO_GEOMETRY;
    if (!ok)
        return 0.0;
    bt_io_pref(io, s, k0);
    BT_RHO_VALUE(io->pref);
    return r;
}

/* bt_rho_one with the Smith term (bt_io_pref_smith): the same operations otherwise. */
BT_INLINE double bt_rho_one_smith(double n, double d, double s, bt_io *io, double h2,
                                  double sphi)
{
    BT_RHO_GEOMETRY;
    if (!ok)
        return 0.0;
    bt_io_pref_smith(io, s);
    BT_RHO_VALUE(io->pref);
    return r;
}

/* The reflection of the same facets (MODEL.md section 8): the (ti, tr) part, with
   u = e_i + e_r, tr in [0, pi/2]. */
typedef struct bt_ir {
    double str;  /* sin tr */
    double ux0;  /* sin ti - sin tr = 2 cos p sin m, p = (ti + tr)/2, m = (ti - tr)/2 */
    double uz;   /* cos ti + cos tr = 2 cos p cos m */
    double pref; /* s^2/(16 pi) / (cos ti cos tr), 0 at grazing */
    double sh;   /* shadowing exponent: V(ti) V(tr) = e^-sh */
} bt_ir;

BT_INLINE void bt_ir_set(bt_ir *ir, double sti, double cti, double str, double ctr,
                         double cp, double sm, double cm, double s, double k0)
{
    ir->str = str;
    ir->ux0 = 2.0 * cp * sm;
    ir->uz = 2.0 * cp * cm;
    ir->pref = s * s / (16.0 * M_PI) * bt_inv_cos(cti) * bt_inv_cos(ctr);
    ir->sh = bt_shadow_exponent(sti, cti, s, k0) + bt_shadow_exponent(str, ctr, s, k0);
}

/* The Smith term of reflection in place of V(ti) V(tr) (BTDF_MODEL_SMITH):
   e^-sh = 1/(1 + Lambda(ti) + Lambda(tr)); sti, cti, str, ctr >= 0. */
BT_INLINE void bt_ir_smith(bt_ir *ir, double sti, double cti, double str, double ctr,
                           double s)
{
    ir->sh = bt_smith_r_exponent(bt_lambda(sti, cti, s), bt_lambda(str, ctr, s));
}

/* smith: 1 for the Smith term (k0 is then unused). */
BT_INLINE void bt_ir_rad_m(bt_ir *ir, double ti, double tr, double s, double k0, int smith)
{
    double sti, cti, str, ctr, sp, cp, sm, cm;
    bt_sincos_rad(ti, &sti, &cti);
    bt_sincos_rad(tr, &str, &ctr);
    bt_sincos_rad(0.5 * (ti + tr), &sp, &cp);
    bt_sincos_red(0.5 * (ti - tr), 0, &sm, &cm);
    cti = cti > 0.0 ? cti : 0.0;
    ctr = ctr > 0.0 ? ctr : 0.0;
    bt_ir_set(ir, sti, cti, str, ctr, cp, sm, cm, s, k0);
    if (smith)
        bt_ir_smith(ir, sti, cti, str, ctr, s);
}

BT_INLINE void bt_ir_rad(bt_ir *ir, double ti, double tr, double s, double k0)
{
    bt_ir_rad_m(ir, ti, tr, s, k0, 0);
}

BT_INLINE void bt_ir_deg_m(bt_ir *ir, double ti, double tr, double s, double k0, int smith)
{
    double sti, cti, str, ctr, sp, cp, sm, cm;
    bt_sincos_deg(ti, &sti, &cti);
    bt_sincos_deg(tr, &str, &ctr);
    bt_sincos_deg(0.5 * (ti + tr), &sp, &cp);
    bt_sincos_red(0.5 * (ti - tr) * BT_DEG, 0, &sm, &cm);
    bt_ir_set(ir, sti, cti, str, ctr, cp, sm, cm, s, k0);
    if (smith)
        bt_ir_smith(ir, sti, cti, str, ctr, s);
}

BT_INLINE void bt_ir_deg(bt_ir *ir, double ti, double tr, double s, double k0)
{
    bt_ir_deg_m(ir, ti, tr, s, k0, 0);
}

/* Fresnel reflectance of a facet at incidence cosine ca > 0 for n = 1 + d, without
   the cancellation of 1 - Ft: with dd = n^2 - 1 = d (2 + d) and n^2 cos^2 b = dd + ca^2,
     ca - n cb = -dd / (ca + n cb),
     n ca - cb = dd ((n^2 + 1) ca^2 - 1) / (n^2 (n ca + cb)),
   so Rs and Rp keep their relative accuracy when n is near 1. 1 past the critical
   angle (total internal reflection, n < 1). */
BT_INLINE double bt_fresnel_r(double n, double d, double ca)
{
    double dd = d * (2.0 + d);
    double g2 = dd + ca * ca; /* n^2 cos^2 b */
    int tir = !(g2 > 0.0);
    double ncb = sqrt(tir ? 0.0 : g2);
    double s1 = ca + ncb;           /* > 0 for ca > 0 */
    double p1 = n * ca + ncb / n;   /* > 0 */
    double rs = dd / (s1 * s1);
    double rp = dd * ((n * n + 1.0) * ca * ca - 1.0) / (n * n * p1 * p1);
    return tir ? 1.0 : 0.5 * (rs * rs + rp * rp);
}

/* rho_r of MODEL.md section 8; branch-free like bt_rho. h = u/|u|, cos a = |u|/2,
   tan^2 tn = (ux^2 + uy^2)/uz^2, 1/cos^2 tn = |u|^2/uz^2. */
BT_INLINE double bt_rho_r(double n, double d, double s, const bt_ir *ir, double h2,
                              double sphi)
{
    double ux = ir->ux0 + ir->str * (2.0 * h2); /* sin ti + sin tr cos phi */
    double uy = ir->str * sphi;
    double uz = ir->uz;
    double rxy2 = ux * ux + uy * uy, uz2 = uz * uz, u2 = rxy2 + uz2;
    double e = 0.25 * s * s * rxy2;
    /* uz = 0 only when both directions graze (where pref is 0 anyway); the cut also
       drops the underflowing tail */
    int ok = (uz > 0.0) & (e < BTDF_EXP_CUT * uz2);
    uz2 = ok ? uz2 : 1.0;
    u2 = ok ? u2 : 1.0;
    double ca = 0.5 * sqrt(u2);
    double fr = bt_fresnel_r(n, d, ca);
    double sec2 = u2 / uz2;
    double r = bt_exp_mul(-(e / uz2 + ir->sh), ir->pref * fr * (sec2 * sec2));
    return (ok & (r >= DBL_MIN)) ? r : 0.0;
}

/* sin and cos of an angle in degrees, exact at multiples of 90 degrees, for tools
   and tests that speak degrees: reduces to [-45, 45] before converting. */

#endif
