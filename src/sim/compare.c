/* SPDX-License-Identifier: MIT */
/* compare.c: btdf_sim_compare: a simulated tally against a model (Eq. 25 or the
   Walter/Smith BTDF of the same Gaussian surface), e_T and e_L1 of MODEL.md section 6
   with their Monte Carlo noise floors and a chi-square (conventions in btdf_sim.h). */
#include "btdf_sim.h"

#include <math.h>
#include <stdlib.h>

#include "core/core.h"

#define PI 3.14159265358979323846
#define SQRT_2_OVER_PI 0.79788456080286535588 /* E|N(0, 1)| */
#define SUB_MAX 128 /* panels per bin and dimension */

/* Angular width of the model's lobe (radians), for the quadrature's panels: facet
   slopes of RMS 2/s turn the refracted ray by about |1 - 1/n| (from the light side)
   or |1 - n| (from the dense side) of the tilt, a mirror by twice it; 0.05 keeps n
   near 1 from asking for a panel count the cap would cut anyway. */
static double lobe_width(double n, double s, btdf_sim_part part)
{
    double f = part == BTDF_SIM_REFLECTION ? 2.0 : fmax(fabs(1.0 - 1.0 / n), fabs(1.0 - n));
    return (2.0 / s) * fmax(f, 0.05);
}

static int panels(double width, double h)
{
    double k = ceil(width / h);
    return k < 2.0 ? 2 : k > SUB_MAX ? SUB_MAX : (int)k;
}

/* The model's flux in bin (it, ip): integral of rho cos(th) sin(th) dth dphi over the
   bin, both halves of |phi|; th is the polar angle from the hemisphere's mean normal
   (to = pi - th for transmission). Three-point Gauss-Legendre on each of nt panels in
   th, the midpoint rule on np panels in phi (rho is even and smooth in phi). */
static double model_bin(btdf_model m, double n, double s, double k0, btdf_sim_part part,
                        double ti, int tb, int pb, int it, int ip, int nth, int nph)
{
    static const double x[3] = {-0.7745966692414834, 0.0, 0.7745966692414834};
    static const double w[3] = {0.5555555555555556, 0.8888888888888888, 0.5555555555555556};
    double wt = (PI / 2) / tb, wp = PI / pb;
    double a = wt * it, c = wp * ip, ht = wt / nth, hp = wp / nph, sum = 0.0;
    for (int i = 0; i < nth; i++)
        for (int g = 0; g < 3; g++) {
            double th = a + ht * (i + 0.5 + 0.5 * x[g]);
            double inner = 0.0;
            for (int j = 0; j < nph; j++) {
                double phi = c + hp * (j + 0.5);
                inner += part == BTDF_SIM_REFLECTION
                             ? btdf_rho_r_model(m, n, s, k0, ti, th, phi)
                             : btdf_rho_model(m, n, s, k0, ti, PI - th, phi);
            }
            sum += w[g] * 0.5 * ht * inner * hp * cos(th) * sin(th);
        }
    return 2.0 * sum; /* both halves of |phi| */
}

BTDF_API btdf_status btdf_sim_compare(const btdf_sim_result *r, size_t k, btdf_sim_part part,
                                      int one_hit, btdf_model m, double k0, btdf_sim_cmp *out,
                                      char *msg, size_t msglen)
{
    if (!r || !out || k >= r->count)
        return core_say(BTDF_EINVAL, msg, msglen, "case %zu: the result has %zu", k,
                        r ? r->count : 0);
    if (part != BTDF_SIM_TRANSMISSION && part != BTDF_SIM_REFLECTION)
        return core_say(BTDF_EINVAL, msg, msglen, "part %d: transmission (0) or reflection (1)",
                        (int)part);
    if (r->profile)
        return core_say(BTDF_EINVAL, msg, msglen,
                        "a 1D profile run: Eq. 25 and Smith describe 2D surfaces");
    if (r->pane)
        return core_say(BTDF_EINVAL, msg, msglen,
                        "a pane run: Eq. 25 and Smith describe one interface");
    if (m != BTDF_MODEL_XU_SUN && m != BTDF_MODEL_SMITH)
        return core_say(BTDF_EINVAL, msg, msglen, "model %d: xu-sun (0) or smith (1)", (int)m);
    const btdf_sim_tally *t = &r->tally[k];
    btdf_params p;
    btdf_params_default(&p);
    p.ior[0] = t->ior;
    p.smoothness = r->smoothness;
    p.k0 = k0;
    p.model = m;
    btdf_status st = btdf_params_check(&p, msg, msglen);
    if (st != BTDF_OK)
        return st;
    btdf_sim_cmp c = {0};
    const btdf_sim_est *tot = part == BTDF_SIM_REFLECTION ? (one_hit ? &t->R_order[0] : &t->R)
                                                           : (one_hit ? &t->T_order[0] : &t->T);
    c.total = tot->mean;
    c.total_se = tot->se;
    st = part == BTDF_SIM_REFLECTION ? btdf_reflectance(&p, t->theta_i, &c.model_total)
                                     : btdf_transmittance(&p, t->theta_i, &c.model_total);
    if (st != BTDF_OK)
        return core_say(st, msg, msglen, "the model's %s at %g deg failed",
                        part == BTDF_SIM_REFLECTION ? "R" : "T", t->theta_i * 180.0 / PI);
    double norm = fmax(c.total, 0.01); /* MODEL.md section 6: the floor of 0.01 */
    c.e_T = fabs(c.model_total - c.total) / norm;
    c.e_T_floor = SQRT_2_OVER_PI * c.total_se / norm;
    const btdf_sim_est *h = part == BTDF_SIM_REFLECTION ? (one_hit ? t->hist_R1 : t->hist_R)
                                                         : (one_hit ? t->hist_T1 : t->hist_T);
    int tb = r->theta_bins, pb = r->phi_bins;
    if (h && tb > 0 && pb > 0) {
        /* 10 panels per lobe width: 4 left the far tails in |phi| 11 % low at s = 30
           (0.25 degree bins), 40 moved no bin by more than 1 % */
        double lw = lobe_width(t->ior, r->smoothness, part) / 10.0;
        int nth = panels((PI / 2) / tb, lw);
        double rays = (double)t->rays;
        for (int it = 0; it < tb; it++) {
            /* in phi the lobe is wider by 1 / sin th; near the normal a bin of |phi| is
               short in angle, so the panels follow the arc sin(th) dphi */
            double sth = sin((PI / 2) / tb * (it + 1));
            int nph = panels(sth * PI / pb, lw);
            for (int ip = 0; ip < pb; ip++) {
                const btdf_sim_est *e = &h[(size_t)it * (size_t)pb + (size_t)ip];
                double mb = model_bin(m, t->ior, r->smoothness, k0, part, t->theta_i, tb, pb,
                                      it, ip, nth, nph);
                c.model_in_bins += mb;
                c.e_L1 += fabs(e->mean - mb);
                /* the bin's noise alone: normal with the batch-means error, or, where
                   that is smaller (few or no paths: an empty bin has se = 0), the paths'
                   Poisson count of mean lam = M rays, whose mean absolute deviation is
                   2 e^-lam lam^(k+1) / k!, k = floor(lam) (formed in logs; lam > 0) */
                double fl = SQRT_2_OVER_PI * e->se, var = (1.0 - 2.0 / PI) * e->se * e->se;
                double lam = mb * rays;
                if (lam > 0.0) {
                    double kf = floor(lam);
                    double mad = 2.0 * exp(-lam + (kf + 1.0) * log(lam) - lgamma(kf + 1.0)) / rays;
                    if (mad > fl) {
                        fl = mad;
                        var = fmax(lam / (rays * rays) - mad * mad, 0.0); /* E(X - lam)^2 = lam */
                    }
                }
                c.e_L1_floor += fl;
                c.e_L1_floor_sd += var;
                if (mb * rays >= 50.0) {
                    /* se = 0: no batch had a path; the binomial error of the model's
                       fraction stands in (mb >= 50 / rays > 0, so it is positive) */
                    double se = e->se > 0.0 ? e->se : sqrt(mb * fabs(1.0 - mb) / rays);
                    if (se > 0.0) {
                        c.chi2 += (e->mean - mb) * (e->mean - mb) / (se * se);
                        c.dof++;
                    }
                }
            }
        }
        c.e_L1 /= norm;
        c.e_L1_floor /= norm;
        c.e_L1_floor_sd = sqrt(c.e_L1_floor_sd) / norm;
    }
    *out = c;
    return BTDF_OK;
}

BTDF_API btdf_status btdf_sim_model_bins(const btdf_sim_result *r, size_t k, btdf_sim_part part,
                                         btdf_model m, double k0, double *out, char *msg,
                                         size_t msglen)
{
    if (!r || !out || k >= r->count || r->theta_bins < 1 || r->phi_bins < 1)
        return core_say(BTDF_EINVAL, msg, msglen, "case %zu: no such case with histograms", k);
    if (r->profile)
        return core_say(BTDF_EINVAL, msg, msglen,
                        "a 1D profile run: Eq. 25 and Smith describe 2D surfaces");
    if (r->pane)
        return core_say(BTDF_EINVAL, msg, msglen,
                        "a pane run: Eq. 25 and Smith describe one interface");
    if (m != BTDF_MODEL_XU_SUN && m != BTDF_MODEL_SMITH)
        return core_say(BTDF_EINVAL, msg, msglen, "model %d: xu-sun (0) or smith (1)", (int)m);
    const btdf_sim_tally *t = &r->tally[k];
    int tb = r->theta_bins, pb = r->phi_bins;
    double lw = lobe_width(t->ior, r->smoothness, part) / 10.0; /* as in btdf_sim_compare */
    int nth = panels((PI / 2) / tb, lw);
    for (int it = 0; it < tb; it++) {
        int nph = panels(sin((PI / 2) / tb * (it + 1)) * PI / pb, lw);
        for (int ip = 0; ip < pb; ip++)
            out[(size_t)it * (size_t)pb + (size_t)ip] =
                model_bin(m, t->ior, r->smoothness, k0, part, t->theta_i, tb, pb, it, ip, nth,
                          nph);
    }
    return BTDF_OK;
}
