/* SPDX-License-Identifier: MIT */
/* report.c: btdf_scatfun_report, the error of a file against Eq. 25 as pbrt-v3 reads it
   (MODEL.md section 6), and sf_report_mis, the measurement the builder calls. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "btdf.h"
#include "btdf_scatfun.h"
#include "core/core.h"
#include "model/kernel.h"
#include "model/facet.h"
#include "estimate/estimate.h"
#include "scatfun/scatfun.h"

/* ------------------------------------------------------------------------- */
/* Error report (MODEL.md section 6)                                         */
/* ------------------------------------------------------------------------- */

typedef struct mis_obj {
    const btdf_scatfun *f;
    btdf_side side; /* the block evaluated (eval_side's side) */
    btdf_scatfun_mode mode;
    int both;             /* 1: mode is DIRECT and the ADJOINT reading comes second */
    albedo_memo *memo;    /* R remembered (refl_angle), or NULL */
    const sf_fixed_read *fr; /* the reading at this angle (mis_prep), or NULL */
    const sf_fixed_read *fa; /* the ADJOINT one when both (NULL: not made) */
} mis_obj;

/* The per-angle context of the estimator: a copy of the reading with its sf_fixed_read. */
static void *mis_prep(const void *obj, double ti)
{
    const mis_obj *m = obj;
    mis_obj *c = malloc(sizeof *c);
    if (!c)
        return NULL;
    *c = *m;
    /* ti in [0, pi/2]: cos ti in [0, 1] */
    double ci = fmin(1.0, fmax(0.0, cos(ti)));
    c->fr = sf_fixed_new(m->f, m->side, m->mode, ci);
    c->fa = m->both ? sf_fixed_new(m->f, m->side, BTDF_SCATFUN_ADJOINT, ci) : NULL;
    if (!c->fr || (m->both && !c->fa)) {
        sf_fixed_free((sf_fixed_read *)c->fr);
        sf_fixed_free((sf_fixed_read *)c->fa);
        free(c);
        return NULL;
    }
    return c;
}

static void mis_done(void *ctx)
{
    mis_obj *c = ctx;
    sf_fixed_free((sf_fixed_read *)c->fr);
    sf_fixed_free((sf_fixed_read *)c->fa);
    free(c);
}

static void mis_eval(const void *obj, double ti, const double *q, double *out)
{
    const mis_obj *m = obj;
    (void)ti;
    /* the estimator's cosines (q: sin ti, cos ti, sin to, cos to, cos phi, sin phi, ...,
       with cos^2 + sin^2 = 1 to rounding), so no angle is turned back into a cosine;
       the clamps keep rounding inside the ranges sf_eval_side_cos takes */
    double ci = fmin(1.0, fmax(0.0, q[1])), co = fmin(1.0, fabs(q[3]));
    double cpd = -fmin(1.0, fmax(-1.0, q[4]));
    uint32_t ch = m->f->channels;
    if (m->fr) {
        const sf_fixed_read *rr[2] = {m->fr, m->fa};
        sf_fixed_eval_n(rr, m->both ? 2 : 1, co, cpd, out);
        return;
    }
    if (sf_eval_side_cos(m->f, m->side, m->mode, ci, co, cpd, out) != BTDF_OK)
        for (uint32_t k = 0; k < ch; k++)
            out[k] = 0.0;
    if (m->both &&
        sf_eval_side_cos(m->f, m->side, BTDF_SCATFUN_ADJOINT, ci, co, cpd, out + ch) != BTDF_OK)
        for (uint32_t k = 0; k < ch; k++)
            out[ch + k] = 0.0;
}

#define U_EST_R 7.0 /* facet slopes beyond u = 7 hold exp(-49) of the distribution */

/* d(omega_h) of a stratum of facet slopes around u (tan tn = 2u/s) stratified in
   w = 1 - exp(-u^2) and psi, doubled for the mirror half: (2/s^2) e^{u^2} q^{-3/2}. */
static double refl_h_measure(double u, double s, double dw, double dpsi)
{
    double rr = 2.0 * u / s, q = 1.0 + rr * rr;
    return (2.0 / (s * s)) * exp(u * u) / (q * sqrt(q)) * dw * dpsi * 2.0;
}

/*
 * One incident angle of a reflection block: integral of |rho_r~ - rho_r| cos tr d(omega_r)
 * over the upper hemisphere of the block's side, by two sample sets combined by the
 * balance heuristic, as the tables' estimator does for transmission:
 *  A: facet normals h stratified in w = 1 - exp(-u^2) (tan th = 2u/s) and psi in
 *     [0, pi], reflected: e_r = 2 (e_i.h) h - e_i, d(omega_r) = 4 (e_i.h) d(omega_h);
 *  B: reflected directions stratified in (cos tr, phi), phi in [0, pi].
 * Both cover the half phi in [0, pi] and count twice (rho_r is even in phi). The
 * norm is max(R(ti), 0.01) (MODEL.md sections 6 and 8).
 */
/* btdf_scatfun_eval_side(m->f, m->side, mode, ti, tr, phi, out), through fr when there
   is one (the reading of mode at ti's angle). */
static btdf_status refl_read(const mis_obj *m, btdf_scatfun_mode mode, const sf_fixed_read *fr,
                             double ti, double tr, double phi, double *out)
{
    if (!fr)
        return btdf_scatfun_eval_side(m->f, m->side, mode, ti, tr, phi, out);
    sf_fixed_eval_n(&fr, 1, fabs(cos(tr)), -cos(phi), out); /* as eval_side passes them */
    return BTDF_OK;
}

/* Both readings (nr of them, m->mode then ADJOINT) of channel c at (tr, phi) against
   rho, with weight wgt. */
static void refl_both(const mis_obj *m, const sf_fixed_read *const *fr, int nr, int c,
                      double ti, double tr, double phi, double rho, double wgt,
                      est_acc *acc)
{
    double tab[2 * BTDF_MAX_CHANNELS];
    if (nr <= 2 && fr[0] && (nr < 2 || fr[1])) { /* both at once (sf_fixed_eval_n) */
        uint32_t ch = m->f->channels;
        sf_fixed_eval_n(fr, nr, fabs(cos(tr)), -cos(phi), tab); /* as eval_side passes them */
        for (int e = 0; e < nr; e++)
            est_add(&acc[e], tab[(size_t)e * ch + (size_t)c], rho, wgt);
        return;
    }
    for (int e = 0; e < nr; e++) {
        if (refl_read(m, e ? BTDF_SCATFUN_ADJOINT : m->mode, fr[e], ti, tr, phi, tab) !=
            BTDF_OK)
            tab[c] = 0.0;
        est_add(&acc[e], tab[c], rho, wgt);
    }
}

static size_t refl_angle(const void *obj, const btdf_params *p, double ti, uint64_t rng,
                         size_t ppa, size_t nuni, btdf_ti_error *res)
{
    const mis_obj *m = obj;
    double s = p->smoothness, sti = sin(ti), cti = cos(ti);
    const size_t npsi = 32, nu = (ppa + 31) / 32, nmu = nuni, nphi = nuni;
    double wmax = -expm1(-U_EST_R * U_EST_R);
    double dw = wmax / (double)nu, dpsi = M_PI / (double)npsi;
    double dmu = 1.0 / (double)nmu, dphi = M_PI / (double)nphi;
    double R[BTDF_MAX_CHANNELS];
    if (albedo_memo_get(m->memo, p, 1, ti, R) != BTDF_OK)
        for (int c = 0; c < p->channels; c++)
            R[c] = 0.0;
    size_t pts = 0;
    /* the light's index combined once for the angle (NULL when out of memory: the
       plain evaluation, the same values) */
    int nr = m->both ? 2 : 1;
    const sf_fixed_read *fr[2] = {NULL, NULL};
    fr[0] = sf_fixed_new(m->f, m->side, m->mode, fmin(1.0, fmax(0.0, cti)));
    if (m->both)
        fr[1] = sf_fixed_new(m->f, m->side, BTDF_SCATFUN_ADJOINT, fmin(1.0, fmax(0.0, cti)));
    btdf_ti_error rr[2]; /* per reading; the angle's result is the worse */
    memset(rr, 0, sizeof rr);
    for (int c = 0; c < p->channels; c++) {
        double n = p->ior[c];
        est_acc acc[2];
        memset(acc, 0, sizeof acc);
        for (size_t iu = 0; iu < nu; iu++) {
            for (size_t ip = 0; ip < npsi; ip++) {
                double w = wmax * ((double)iu + core_unif(&rng)) / (double)nu;
                double psi = M_PI * ((double)ip + core_unif(&rng)) / (double)npsi;
                double u = sqrt(-log1p(-w)); /* w < 1: finite */
                double rr = 2.0 * u / s;     /* s > 0 (checked) */
                double cth = 1.0 / sqrt(1.0 + rr * rr), sth = rr * cth;
                double hx = sth * cos(psi), hy = sth * sin(psi), hz = cth;
                double ca = sti * hx + cti * hz; /* e_i = (sin ti, 0, cos ti) */
                pts++;
                if (!(ca > 0.0))
                    continue; /* the facet faces away: no reflection from it */
                double rx = 2.0 * ca * hx - sti, ry = 2.0 * ca * hy, rz = 2.0 * ca * hz - cti;
                if (!(rz > 0.0))
                    continue; /* reflected into the other medium: rho_r is 0 there */
                double tr = atan2(sqrt(rx * rx + ry * ry), rz), phi = atan2(ry, rx);
                double va = rz * 4.0 * ca * refl_h_measure(u, s, dw, dpsi);
                double vb = rz * dmu * dphi * 2.0;
                double rho = btdf_rho_r_model(p->model, n, s, p->k0, ti, tr, phi);
                /* va, vb > 0 */
                refl_both(m, fr, nr, c, ti, tr, phi, rho, va * vb / (va + vb), acc);
            }
        }
        for (size_t im = 0; im < nmu; im++) {
            for (size_t ip = 0; ip < nphi; ip++) {
                double mu = ((double)im + core_unif(&rng)) / (double)nmu; /* cos tr */
                double ph = M_PI * ((double)ip + core_unif(&rng)) / (double)nphi;
                double sr = sqrt(fmax(0.0, 1.0 - mu * mu));
                double rx = sr * cos(ph), ry = sr * sin(ph), rz = mu;
                double vb = mu * dmu * dphi * 2.0, share = vb;
                pts++;
                /* the facet that reflects e_i into e_r: h = (e_i + e_r)/|e_i + e_r| */
                double ux = sti + rx, uy = ry, uz = cti + rz;
                double ul = sqrt(ux * ux + uy * uy + uz * uz);
                if (uz > 0.0 && ul > 0.0) {
                    double ca = (sti * ux + cti * uz) / ul;
                    double u = 0.5 * s * sqrt(ux * ux + uy * uy) / uz; /* tan th = |u_xy|/u_z */
                    if (u < U_EST_R && ca > 0.0) {
                        double va = rz * 4.0 * ca * refl_h_measure(u, s, dw, dpsi);
                        if (va > 0.0)
                            share = va * vb / (va + vb);
                    }
                }
                double tr = atan2(sr, mu), phi = ph;
                double rho = btdf_rho_r_model(p->model, n, s, p->k0, ti, tr, phi);
                refl_both(m, fr, nr, c, ti, tr, phi, rho, share, acc);
            }
        }
        for (int e = 0; e < nr; e++) /* R in T's place: MODEL.md sections 6 and 8 */
            est_fold(&rr[e], &acc[e], R[c], c);
    }
    est_worse(rr, nr, res); /* the worse reading, as est_angle's */
    sf_fixed_free((sf_fixed_read *)fr[0]);
    sf_fixed_free((sf_fixed_read *)fr[1]);
    return pts;
}

/* One reading of a file against the truth, or both (both = 1, mode DIRECT): then
   every point's truth serves the two, and each test angle keeps the worse.
   btdf_scatfun_eval_side's side names the light's side in both modes (DIRECT reads that
   block, ADJOINT the block whose fast index holds that light: the other transmission
   block, the same reflection block). */
static btdf_status report_reading(const btdf_scatfun *f, const btdf_params *p, int b,
                                  btdf_scatfun_mode mode, int both, size_t angles, size_t ppa,
                                  uint64_t seed, int threads, const est_opts *o,
                                  albedo_memo *memo, btdf_report *r)
{
    mis_obj m = {f, (btdf_side)b, mode, both, memo, NULL, NULL};
    est_opts opt = {0, 1, 0.0, 0, 0, 0.0, NULL};
    if (o)
        opt = *o;
    opt.nread = both ? 2 : 1;
    int refl = b == BTDF_SCATFUN_R_TOP || b == BTDF_SCATFUN_R_BOTTOM;
    int below = b == BTDF_SCATFUN_T_LEAVE || b == BTDF_SCATFUN_R_BOTTOM;
    btdf_params q = *p;
    if (below)
        for (int k = 0; k < q.channels; k++)
            q.ior[k] = 1.0 / p->ior[k];
    /* Knots: the incident angles of the elevation nodes (both indices share them), so
       every interval between nodes gets its midpoint tested (a band between two nodes
       can hold the largest error: docs/scatfun.md, "Error report"). */
    double *knots = malloc((f->n + 1) * sizeof *knots);
    if (!knots)
        return BTDF_ENOMEM;
    size_t nk = 0;
    knots[nk++] = 0.0;
    for (uint32_t i = f->n; i-- > 0;)
        if (f->xd[i] > 0.0 && f->xd[i] < 1.0)
            knots[nk++] = acos(f->xd[i]); /* ascending in ti as mu descends */
    knots[nk++] = M_PI / 2;
    btdf_status st;
    if (refl)
        st = btdf_estimate_angles(&q, 0.0, M_PI / 2, angles, ppa, seed, threads, knots, nk,
                                  refl_angle, &m, &opt, memo, r);
    else
        st = btdf_estimate_knots_prep(&q, 0.0, M_PI / 2, angles, ppa, seed, threads, knots,
                                      nk, mis_eval, mis_prep, mis_done, &m, &opt, memo, r);
    free(knots);
    return st;
}

btdf_status sf_report_reading(const btdf_scatfun *f, const btdf_params *p,
                                   btdf_side side, btdf_scatfun_mode mode, int both,
                                   size_t angles, size_t ppa, uint64_t seed, int threads,
                                   btdf_report *r)
{
    return report_reading(f, p, (int)side, mode, both, angles, ppa, seed, threads, NULL, NULL,
                          r);
}

/* The report of one block, as renderers read it: light tracers (pbrt-v3's importance
   mode, DIRECT: the light in the slow index) and path tracers' camera rays (radiance
   mode, ADJOINT: the light in the fast index) read the same stored series along
   different axes and with different norms, so both readings are measured and the worse
   kept at every test angle (each sample's Eq. 25 serves the two; each mean is over the
   stratified angles of that worse reading). A three-channel transmission block's fold is right on the
   radiance path only (build_impl): there the light side's report is that block's
   ADJOINT reading. */
btdf_status sf_report_mis(const btdf_scatfun *f, const btdf_params *p, btdf_side side,
                               size_t angles, size_t ppa, uint64_t seed, int threads,
                               const est_opts *opt, albedo_memo *memo, btdf_report *r)
{
    int b = (int)side;
    int refl = b == BTDF_SCATFUN_R_TOP || b == BTDF_SCATFUN_R_BOTTOM;
    /* the other transmission block, which ADJOINT reads for this side's light */
    int tb = b == BTDF_SCATFUN_T_ENTER ? BTDF_SCATFUN_T_LEAVE : BTDF_SCATFUN_T_ENTER;
    int has_adj = refl || (f->sides & tb) != 0;
    if (f->channels == 3 && !refl)
        /* a file of this one block: its ADJOINT reading is the other side's light */
        return report_reading(f, p, has_adj ? b : tb, BTDF_SCATFUN_ADJOINT, 0, angles, ppa,
                              seed, threads, opt, memo, r);
    /* both readings at once where the file has both (one truth per point for the two) */
    return report_reading(f, p, b, BTDF_SCATFUN_DIRECT, has_adj, angles, ppa, seed, threads,
                          opt, memo, r);
}

BTDF_API btdf_status btdf_scatfun_report(const btdf_scatfun *f, const btdf_params *p,
                                         btdf_side side, size_t test_angles,
                                         size_t points_per_angle, uint64_t seed,
                                         int threads, btdf_report *r)
{
    if (!f || !r ||
        ((int)side != BTDF_SCATFUN_T_ENTER && (int)side != BTDF_SCATFUN_T_LEAVE &&
         (int)side != BTDF_SCATFUN_R_TOP && (int)side != BTDF_SCATFUN_R_BOTTOM))
        return BTDF_EINVAL;
    if (btdf_params_check(p, NULL, 0) != BTDF_OK)
        return BTDF_EINVAL;
    if ((p->channels == 3) != (f->channels == 3))
        return BTDF_EINVAL; /* the truth must have the file's channels */
    if (test_angles == 0)
        test_angles = 24;
    if (points_per_angle == 0)
        points_per_angle = 8192;
    if (test_angles > 100000 || points_per_angle > ((size_t)1 << 26))
        return BTDF_EINVAL;
    /* The estimator tables use (src/estimate/estimate.c): facet-space samples that follow the
       lobe combined with uniform (cos to, phi) samples by the balance heuristic. An
       earlier sampler of this file, uniform in (mu_f, phi) only, missed the error
       near grazing incidence (1.9e-3 at ti = 86.7 deg for s = 3, where a
       1500 x 1500 brute-force integral agrees with this estimator). */
    btdf_status st = sf_report_mis(f, p, side, test_angles, points_per_angle, seed,
                                        threads, NULL, f->memo, r);
    if (st != BTDF_OK)
        return st;
    r->slices = f->n;
    r->samples = f->ncoeffs;
    r->seconds_build = f->built ? f->seconds_build : 0.0;
    r->tolerance = f->built ? f->tolerance : 0.0;
    r->metric = BTDF_METRIC_L1;
    r->peak_bytes = (size_t)f->ncoeffs * 4 + (size_t)f->n * f->n * 12;
    r->met = r->tolerance > 0.0 ? r->e_l1_max <= r->tolerance : 0;
    return BTDF_OK;
}
