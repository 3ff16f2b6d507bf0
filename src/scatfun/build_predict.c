/* SPDX-License-Identifier: MIT */
/* build_predict.c: what a SCATFUN request needs at least, before any work: the
   elevation nodes the narrowest transmitted lobe asks of the Catmull-Rom spline, and
   the pairs, bytes and builder memory those nodes imply (btdf_scatfun_predict). */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "btdf.h"
#include "btdf_scatfun.h"
#include "core/core.h"
#include "scatfun/scatfun.h"
#include "scatfun/build.h"

/* Relative L1 error of a unit-area Gaussian of standard deviation 1 interpolated by a
   uniform Catmull-Rom spline through samples spaced r apart, averaged over OFFSETS grid
   phases (the nodes fall anywhere on a lobe). The Gaussian's tails beyond 8 (1e-15)
   are left out; PTS points per interval integrate the cubic's difference by the
   midpoint rule (the difference is smooth inside an interval). */
#define CR_OFFSETS 8
#define CR_PTS 24
double sf_cr_gauss_l1(double r)
{
    const double norm = 1.0 / sqrt(2.0 * M_PI);
    double tot = 0.0;
    for (int o = 0; o < CR_OFFSETS; o++) {
        double u = ((double)o + 0.5) / CR_OFFSETS;
        /* nodes x_k = (k + u) r, k from k0 to k1 covering [-8, 8] */
        long k0 = (long)floor(-8.0 / r - u) - 1, k1 = (long)ceil(8.0 / r - u) + 1;
        double e = 0.0;
        for (long k = k0; k < k1; k++) {
            double x1 = ((double)k + u) * r;
            double p0 = norm * exp(-0.5 * (x1 - r) * (x1 - r));
            double p1 = norm * exp(-0.5 * x1 * x1);
            double p2 = norm * exp(-0.5 * (x1 + r) * (x1 + r));
            double p3 = norm * exp(-0.5 * (x1 + 2 * r) * (x1 + 2 * r));
            for (int j = 0; j < CR_PTS; j++) {
                double t = ((double)j + 0.5) / CR_PTS, x = x1 + t * r;
                double cr = 0.5 * (2 * p1 + (p2 - p0) * t +
                                   (2 * p0 - 5 * p1 + 4 * p2 - p3) * t * t +
                                   (3 * p1 - p0 - 3 * p2 + p3) * t * t * t);
                e += fabs(cr - norm * exp(-0.5 * x * x));
            }
        }
        tot += e * r / CR_PTS;
    }
    return tot / CR_OFFSETS;
}

/* The widest spacing (in standard deviations) whose error is at most tol: bisection on
   [1e-3, 4] (the error grows with the spacing; 1e-3 holds 1e-12, below any tolerance). */
static double cr_spacing(double tol)
{
    double lo = 1e-3, hi = 4.0;
    if (sf_cr_gauss_l1(hi) <= tol)
        return hi;
    for (int it = 0; it < 40; it++) {
        double mid = 0.5 * (lo + hi);
        if (sf_cr_gauss_l1(mid) <= tol)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* The transmitted lobe's spread (rad) in the angle theta of one axis, light crossing
   into the relative index rel = n_t / n_i: a facet tilted by delta turns the refracted
   direction by (1 - cos ti / (rel cos tt)) delta (Snell's law differentiated at fixed
   ti), the incident angle at fixed tt by the inverse ratio; facet tilts spread by
   sqrt(2)/s per axis (slopes of RMS 2/s over two axes, MODEL.md 2). theta is the
   transmitted angle (axis 0) or the incident one (axis 1); 0 where no light crosses
   (beyond the critical angle). */
static double lobe_width(double rel, double theta, int axis, double sigma)
{
    double st, ci, ct;
    if (axis == 0) {
        st = sin(theta);
        double si = rel * st;
        if (si >= 1.0)
            return 0.0;
        ci = sqrt(1.0 - si * si);
        ct = cos(theta);
    } else {
        st = sin(theta) / rel; /* rel > 0 (checked) */
        if (st >= 1.0)
            return 0.0;
        ct = sqrt(1.0 - st * st);
        ci = cos(theta);
    }
    if (ct <= 0.0)
        return HUGE_VAL; /* grazing transmitted direction: the lobe opens without bound */
    double d = fabs(1.0 - ci / (rel * ct)); /* dtt/ddelta; 0 only for rel = 1 (refused) */
    if (axis == 1)
        d = ci > 0.0 ? d * rel * ct / ci : HUGE_VAL; /* dti/ddelta = (dtt/ddelta) dti/dtt */
    return d * sigma;
}

#define PRED_STEPS 4096

BTDF_API btdf_status btdf_scatfun_predict(const btdf_params *p, double tolerance,
                                          btdf_side side, btdf_scatfun_need *need,
                                          char *msg, size_t msglen)
{
    if (!need)
        return core_say(BTDF_EINVAL, msg, msglen, "need pointer missing");
    btdf_status st = btdf_scatfun_check(p, tolerance, side, msg, msglen);
    if (st != BTDF_OK)
        return st;
    memset(need, 0, sizeof *need);
    double r = cr_spacing(tolerance);
    double sigma = sqrt(2.0) / p->smoothness; /* s > 0 (checked) */
    int nb = 0, nt = 0;
    for (int b = 0; b < NBLK; b++)
        if ((int)side & blk_mask[b]) {
            nb++;
            nt += !blk_refl[b];
        }
    /* the node density each transmission block asks at every angle, on both axes; the
       node set is shared, so the densest need at each angle counts */
    double nodes = 0.0, narrow = HUGE_VAL;
    double dth = (M_PI / 2) / PRED_STEPS;
    for (int j = 0; nt && j < PRED_STEPS; j++) {
        double th = ((double)j + 0.5) * dth, dens = 0.0;
        for (int b = 0; b < 2; b++) {
            if (!((int)side & blk_mask[b]))
                continue;
            for (int k = 0; k < p->channels; k++) {
                double rel = b == BLK_T_ENTER ? p->ior[k] : 1.0 / p->ior[k];
                for (int axis = 0; axis < 2; axis++) {
                    double w = lobe_width(rel, th, axis, sigma);
                    if (w > 0.0 && w < HUGE_VAL) {
                        dens = fmax(dens, 1.0 / (r * w));
                        narrow = fmin(narrow, w);
                    }
                }
            }
        }
        nodes += dens * dth;
    }
    /* the builder starts from 8 half nodes and keeps them */
    double K = fmax(8.0, ceil(nodes));
    need->lobe_deg = narrow < HUGE_VAL ? narrow * 180.0 / M_PI : 0.0;
    need->spacing_deg = narrow < HUGE_VAL ? r * narrow * 180.0 / M_PI : 0.0;
    need->half_nodes = K < 1e9 ? (size_t)K : (size_t)1e9;
    double Kd = (double)need->half_nodes, n = 2.0 * Kd + 2.0;
    int nst = p->channels == 3 ? 3 : 1;
    /* every pair a transmission lobe covers (+-2 of its widths, 4 / r nodes of the other
       index per node) holds at least one coefficient per stored channel */
    double coeffs = (double)nt * Kd * fmin(Kd, ceil(4.0 / r)) * nst;
    /* the file: 64-byte header, n nodes, n^2 cdf and offset entries of 12 bytes, 4 per
       coefficient (formats/bsdf.c) */
    double file = 64.0 + 4.0 * n + 12.0 * n * n + 4.0 * coeffs;
    /* the builder: a pair record for every pair, check series at the column and row
       midpoints (three arrays per block, state_bytes in build.c), each coefficient in
       double precision in all three, and the file's float copy */
    double state = (double)nb * 3.0 * Kd * Kd * (double)sizeof(pair) + 3.0 * 8.0 * coeffs;
    need->coeffs = (size_t)fmin(coeffs, 1e15);
    need->file_bytes = (size_t)fmin(file, 1e15);
    need->build_bytes = (size_t)fmin(state + file, 1e15);
    return BTDF_OK;
}
