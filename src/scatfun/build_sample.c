/* SPDX-License-Identifier: MIT */
/* build_sample.c: Eq. 25 on a pair's azimuth grid (the samples the series are made from), and the
   pairs no facet connects (dark pairs). */
#include <math.h>
#include <pthread.h>
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
#include "scatfun/build.h"

/* Stored channel values of g = rho * |mu_f| (rho_r * |mu_f| for a reflection block) at
   one azimuth, from the model channels, each times the block's fold factor. */
static void stored_values(const build_ctx *c, int b, const rho_in *ri, const rho_out *ro,
                          const bt_ir *ir, double mu_f, double cph, double sph, double *out)
{
    double v[3];
    for (int k = 0; k < c->nc; k++) {
        double n = c->ior[b][k];
        if (blk_refl[b])
            /* h2 = (1 + cos phi)/2 = sin^2(phi_d/2), MODEL.md 8's azimuth part */
            v[k] = bt_rho_r(n, n - 1.0, c->p->smoothness, ir, 0.5 * (1.0 + cph), sph) * mu_f;
        else
            v[k] = rho_kernel(n, c->p->smoothness, ri, ro, cph, sph) * mu_f;
    }
    if (c->nst == 1) {
        out[0] = v[0];
    } else {
        for (int k = 0; k < 3; k++)
            v[k] *= c->fold[b][k];
        out[0] = LUM_R * v[0] + LUM_G * v[1] + LUM_B * v[2];
        out[1] = v[0];
        out[2] = v[2];
    }
}

/* sf_sample_grid for a one-channel transmission block: Eq. 25 in its branch-free form
   (bt_rho, the public entry points' kernel, which the compiler vectorises) along the
   azimuth row; the same function as rho_kernel's to rounding. */
BT_CLONES static void sample_grid_t1(const build_ctx *c, const build_ws *w, int b,
                                     double mu_s, double mu_f, size_t N, size_t step,
                                     size_t phase, double *x)
{
    /* |mu| <= 1 for every node and midpoint; fmax guards rounding */
    double ss = sqrt(fmax(0.0, 1.0 - mu_s * mu_s)), sf = sqrt(fmax(0.0, 1.0 - mu_f * mu_f));
    /* ti = acos mu_s and b = pi - to = acos mu_f, both in [0, pi/2] */
    double ti = atan2(ss, mu_s), bb = atan2(sf, mu_f);
    double sp = sin(0.5 * (ti + bb)), cp = cos(0.5 * (ti + bb)), sm = sin(0.5 * (ti - bb));
    bt_io io;
    bt_io_set(&io, ss, mu_s, sf, mu_f, sp, cp, sm);
    double n = c->ior[b][0], d = n - 1.0, s = c->p->smoothness;
    if (c->p->model != BTDF_MODEL_XU_SUN) /* smith's shadowing-masking (kernel.h); full's
                                             single scattering is smith's */
        bt_io_pref_smith(&io, s);
    else
        bt_io_pref(&io, s, c->p->k0);
    double f = mu_f; /* one channel: no fold (stored_values) */
    size_t g = c->nmax / N; /* N divides nmax: both are powers of two */
    const double *h2 = w->h2g, *sn = w->sing;
    /* a counted loop (the vectoriser needs the trip count): j = phase + t step */
    long cnt = phase <= N ? (long)((N - phase) / step) + 1 : 0, sg = (long)(step * g);
    const double *h2p = h2 + phase * g, *snp = sn + phase * g;
    double *xp = x + phase;
    for (long t = 0; t < cnt; t++)
        xp[t * (long)step] = bt_rho(n, d, s, &io, h2p[t * sg], snp[t * sg]) * f;
}

/* sf_sample_grid for a one-channel reflection block: rho_r (bt_rho_r, branch-free) along
   the azimuth row in a counted loop the compiler vectorises, with the operations of
   stored_values in the same order, so the same samples to the bit. */
BT_CLONES static void sample_grid_r1(const build_ctx *c, const build_ws *w, int b,
                                     double mu_s, double mu_f, size_t N, size_t step,
                                     size_t phase, double *x)
{
    /* |mu| <= 1 for every node and midpoint; fmax guards rounding */
    double ss = sqrt(fmax(0.0, 1.0 - mu_s * mu_s)), sf = sqrt(fmax(0.0, 1.0 - mu_f * mu_f));
    bt_ir ir;
    memset(&ir, 0, sizeof ir);
    /* ti = acos mu_s, tr = acos mu_f, both in [0, pi/2] */
    bt_ir_rad_m(&ir, atan2(ss, mu_s), atan2(sf, mu_f), c->p->smoothness, c->p->k0,
                c->p->model != BTDF_MODEL_XU_SUN);
    double n = c->ior[b][0], d = n - 1.0, s = c->p->smoothness;
    size_t g = c->nmax / N; /* N divides nmax: both are powers of two */
    long cnt = phase <= N ? (long)((N - phase) / step) + 1 : 0, sg = (long)(step * g);
    const double *cg = w->cosg + phase * g, *sn = w->sing + phase * g;
    double *xp = x + phase;
    for (long t = 0; t < cnt; t++) {
        /* phi_d = j pi / N, phi = pi - phi_d: cos phi = -cos phi_d (sf_sample_grid) */
        double cph = -cg[t * sg];
        xp[t * (long)step] = bt_rho_r(n, d, s, &ir, 0.5 * (1.0 + cph), sn[t * sg]) * mu_f;
    }
}

/* Along the azimuth each of bt_rho's three conditions (BT_RHO_GEOMETRY: e_i.v > 0,
   e_o.v > 0 with the facet's side, and the slope below the exponential's underflow)
   is linear in h2 = sin^2(phi_d/2) in [0, 1]: with w = e_i + e_o, |w|^2 = wx0^2 + wz^2
   + 4 sto (wx0 + sto) h2, so e_i.v and e_o.v are linear in h2; v_z = wz - d cto does
   not depend on phi; and rxy^2 = (A + B h2)^2 + 4 n^2 sto^2 h2 (1 - h2) with A = wx0 -
   d sto, B = 2 n sto, whose h2^2 terms cancel. So is the exponent E = (s^2/4) rxy^2 /
   v_z^2: the Gaussian factor is e^-E0 e^-(G/2) e^((G/2) cos phi_d), G = dE/dh2, a von
   Mises shape whose cosine coefficients fall like exp(-k^2 / |G|).
   For one channel of index n: 0 when the conditions, each relaxed by 1e-9 of its scale
   (far above the kernel's rounding), hold nowhere on [0, 1]; else 1, with *kappa =
   |G|/2 and *width the angle phi_d spanned by the h2 where they all hold; -1 when v_z
   is too close to 0 to tell its sign. */
static int pair_azimuth(double n, double s, const bt_io *io, double *kappa, double *width)
{
    double d = n - 1.0;
    double vz = io->wz - d * io->cto;
    if (!(fabs(vz) > 1e-12))
        return -1;
    double sg = vz < 0.0 ? -1.0 : 1.0, vz2 = vz * vz;
    double w0 = io->wx0 * io->wx0 + io->wz * io->wz, w1 = 4.0 * io->sto * (io->wx0 + io->sto);
    double A = io->wx0 - d * io->sto, B = 2.0 * n * io->sto;
    /* f(h2) = al + be h2 > 0 for sg e_i.v = sg (n |w|^2/2 - d), -sg e_o.v =
       -sg (d + |w|^2/2) and CUT vz^2 - (s^2/4) rxy^2 */
    double al[3] = {sg * (0.5 * n * w0 - d), -sg * (d + 0.5 * w0),
                    BTDF_EXP_CUT * vz2 - 0.25 * s * s * A * A};
    double be[3] = {sg * 0.5 * n * w1, -sg * 0.5 * w1, -0.25 * s * s * (2.0 * A * B + B * B)};
    double lo = 0.0, hi = 1.0;
    for (int i = 0; i < 3; i++) {
        double scale = fabs(al[i]) + fabs(be[i]) + (i == 2 ? BTDF_EXP_CUT * vz2 : 1.0);
        double a = al[i] + 1e-9 * scale; /* relaxed: f > -1e-9 scale */
        if (be[i] > 0.0)
            lo = fmax(lo, -a / be[i]); /* be != 0 */
        else if (be[i] < 0.0)
            hi = fmin(hi, -a / be[i]); /* be != 0 */
        else if (!(a > 0.0))
            lo = 2.0; /* f <= -1e-9 scale at every azimuth */
    }
    if (!(lo < hi))
        return 0;
    /* lo, hi in [0, 1] here, so the sqrt and asin arguments are too */
    *width = 2.0 * (asin(sqrt(fmin(hi, 1.0))) - asin(sqrt(fmax(lo, 0.0))));
    *kappa = 0.5 * fabs(-be[2] / vz2); /* vz2 > 1e-24 */
    return 1;
}

static void pair_io(double mu_s, double mu_f, bt_io *io)
{
    /* as sample_grid_t1: |mu| <= 1, fmax guards rounding */
    double ss = sqrt(fmax(0.0, 1.0 - mu_s * mu_s)), sf = sqrt(fmax(0.0, 1.0 - mu_f * mu_f));
    double ti = atan2(ss, mu_s), bb = atan2(sf, mu_f);
    double sp = sin(0.5 * (ti + bb)), cp = cos(0.5 * (ti + bb)), sm = sin(0.5 * (ti - bb));
    bt_io_set(io, ss, mu_s, sf, mu_f, sp, cp, sm);
}

/* Declared in scatfun/scatfun.h: pair_azimuth finds no azimuth for any channel. */
int sf_unreachable(const double *ior, int channels, double s, double mu_s,
                        double mu_f)
{
    bt_io io;
    pair_io(mu_s, mu_f, &io);
    for (int k = 0; k < channels; k++) {
        double kappa, width;
        if (pair_azimuth(ior[k], s, &io, &kappa, &width) != 0)
            return 0; /* this channel reaches some azimuth, or may */
    }
    return 1;
}

/* The first azimuth grid of a transmission pair. sf_converge() never accepts a grid
   before comparing it with its double, so the first grid is half of what the accepted
   one must hold: 3 sqrt(kappa) harmonics and 2 points across the azimuths any facet
   reaches, so that the doubled grid has 6 sqrt(kappa) (where the von Mises factor's
   coefficients have fallen to e^-18 of the first) and 4 points across; at least
   FIRST_MIN_PHI (the doubled grid NMIN_PHI) and at most the material's nmin (8 s, for
   the narrowest pairs; also where a channel's v_z is too close to 0 to tell). Until
   this version the first grid held the 6 sqrt(kappa) and 4 points itself: files of
   n = 1.5 (s = 3, 20 at 1e-3; s = 100 at 1e-2), 2.4 (s = 1) and 1.33 (s = 5, four
   blocks) have the same nodes and e_L1 to 3 digits either way, and s = 100 builds in
   13 s instead of 29. 0 when every channel is dark (sf_unreachable's answer). */
#define FIRST_MIN_PHI 16.0
size_t sf_first_grid(const build_ctx *c, int b, double mu_s, double mu_f)
{
    bt_io io;
    pair_io(mu_s, mu_f, &io);
    double want = 0.0;
    for (int k = 0; k < c->nc; k++) {
        double kappa = 0.0, width = 0.0;
        int r = pair_azimuth(c->ior[b][k], c->p->smoothness, &io, &kappa, &width);
        if (r < 0)
            return c->nmin;
        if (r == 0)
            continue;
        want = fmax(want, fmax(FIRST_MIN_PHI, 3.0 * sqrt(kappa)));
        /* width > 0 when reached; 2 pi / width (2 points across) may be huge: capped
           below */
        want = fmax(want, width > 0.0 ? 2.0 * M_PI / width : HUGE_VAL);
    }
    if (want == 0.0 && c->ms[b][0])
        return pow2_at_least(FIRST_MIN_PHI); /* full: light scattered more than once
                                                 reaches every pair; five modes */
    if (want == 0.0)
        return 0; /* no channel reaches any azimuth */
    return want >= (double)c->nmin ? c->nmin : pow2_at_least(want);
}

/* Model full (one channel): the multiply scattered part, times mu_f, added to the
   samples sf_sample_grid made of smith's single scattering.
   Its five modes are formed once for the pair (full_ms_modes), then summed at each
   azimuth with the cosines by Chebyshev's recurrence and clipped at 0, as full_ms
   clips its series. Light or view in the surface (mu 0) carries no flux (MODEL.md
   3.5): nothing is added there, as btdf_full_rho adds nothing. */
static void add_ms(const build_ctx *c, const build_ws *w, int b, double mu_s, double mu_f,
                   size_t N, size_t step, size_t phase, double *x)
{
    if (!(mu_s > 0.0 && mu_f > 0.0))
        return;
    /* |mu| <= 1 for every node and midpoint; fmax guards rounding; ti in [0, 90) deg */
    double ti_deg = atan2(sqrt(fmax(0.0, 1.0 - mu_s * mu_s)), mu_s) * (180.0 / M_PI);
    double a[FULL_M];
    full_ms_modes(c->ms[b][0], blk_refl[b], ti_deg, mu_f, a);
    size_t g = c->nmax / N; /* N divides nmax: both are powers of two */
    for (size_t j = phase; j <= N; j += step)
        /* phi_d = j pi / N; phi = pi - phi_d, so cos phi = -cos phi_d (sf_sample_grid) */
        x[j] += full_ms_at(a, -w->cosg[j * g]) * mu_f;
}

static void sample_single(const build_ctx *c, const build_ws *w, int b, double mu_s,
                          double mu_f, size_t N, size_t stride, size_t step, size_t phase,
                          double *x);

/* Fills samples x (stride N2 + 1 per stored channel, N2 = the grid wanted) for the grid
   j pi / N, only at indices j with j % step == phase (step 1: all, 2: odd ones).
   mu_s, mu_f are the block's cosines as magnitudes, in [0, 1]: the model's single
   scattering, and for full the multiply scattered part on top. */
void sf_sample_grid(const build_ctx *c, const build_ws *w, int b, double mu_s,
                    double mu_f, size_t N, size_t stride, size_t step, size_t phase,
                    double *x)
{
    sample_single(c, w, b, mu_s, mu_f, N, stride, step, phase, x);
    /* full is one index only (btdf_scatfun_check): one stored channel */
    if (c->ms[b][0])
        add_ms(c, w, b, mu_s, mu_f, N, step, phase, x);
}

/* Fills samples x (stride N2 + 1 per stored channel, N2 = the grid wanted) for the grid
   j pi / N, only at indices j with j % step == phase (step 1: all, 2: odd ones).
   mu_s, mu_f are the block's cosines as magnitudes, in [0, 1]; the single scattering
   of the model (smith's for full). */
static void sample_single(const build_ctx *c, const build_ws *w, int b, double mu_s,
                          double mu_f, size_t N, size_t stride, size_t step, size_t phase,
                          double *x)
{
    if (!blk_refl[b] && c->nc == 1) {
        sample_grid_t1(c, w, b, mu_s, mu_f, N, step, phase, x);
        return;
    }
    if (blk_refl[b] && c->nc == 1) {
        sample_grid_r1(c, w, b, mu_s, mu_f, N, step, phase, x);
        return;
    }
    rho_in ri;
    rho_out ro;
    bt_ir ir;
    memset(&ri, 0, sizeof ri); /* only the block's kind of geometry is used */
    memset(&ro, 0, sizeof ro);
    memset(&ir, 0, sizeof ir);
    /* |mu| <= 1 holds for every node and midpoint, so the sqrt arguments are >= 0;
       fmax guards rounding. */
    double ss = sqrt(fmax(0.0, 1.0 - mu_s * mu_s)), sf = sqrt(fmax(0.0, 1.0 - mu_f * mu_f));
    if (blk_refl[b]) {
        /* ti = acos mu_s, tr = acos mu_f, both in [0, pi/2] */
        double ti = atan2(ss, mu_s), tr = atan2(sf, mu_f);
        bt_ir_rad_m(&ir, ti, tr, c->p->smoothness, c->p->k0, c->p->model != BTDF_MODEL_XU_SUN);
    } else {
        rho_in_init_m(&ri, ss, mu_s, c->p->smoothness, c->p->k0, c->p->model);
        rho_out_init_m(&ro, sf, -mu_f, c->p->smoothness, c->p->k0, &ri);
    }
    double v[3];
    size_t g = c->nmax / N; /* N divides nmax: both are powers of two */
    for (size_t j = phase; j <= N; j += step) {
        /* phi_d = j pi / N; phi = pi - phi_d, so cos phi = -cos phi_d. */
        stored_values(c, b, &ri, &ro, &ir, mu_f, -w->cosg[j * g], w->sing[j * g], v);
        for (int k = 0; k < c->nst; k++)
            x[k * stride + j] = v[k];
    }
}
