/* SPDX-License-Identifier: MIT */
/* eval.c: reading a pane's system BSDF (interpolation in cos theta, the Fourier sum), and
   its error against a finer one (MODEL.md section 6). */
#include <math.h>
#include <stdlib.h>

#include "pane/pane_impl.h"

#define PI 3.14159265358979323846

/* 4-point Lagrange weights at x over the ascending nodes: the stencil's first node in
   *k0 (the nearest four, clamped to the ends, so the ends extrapolate a cubic). */
static void lagrange(const double *nodes, int n, double x, int *k0, double wt[4])
{
    int lo = 0, hi = n - 1;
    while (hi - lo > 1) { /* nodes[lo] <= x < nodes[hi], or an end */
        int mid = (lo + hi) / 2;
        if (nodes[mid] <= x)
            lo = mid;
        else
            hi = mid;
    }
    int k = lo - 1;
    if (k < 0)
        k = 0;
    if (k > n - 4)
        k = n - 4;
    *k0 = k;
    for (int a = 0; a < 4; a++) {
        double v = 1.0;
        for (int b = 0; b < 4; b++)
            if (b != a) /* distinct Gauss nodes: no zero denominator */
                v *= (x - nodes[k + b]) / (nodes[k + a] - nodes[k + b]);
        wt[a] = v;
    }
}

/* The weights of the modes m >= 1 at x: the Lagrange weights, except past the last node,
   where the series reaches the pole (theta = 0). There every mode but m = 0 vanishes (a
   direction on the axis has no azimuth), which a cubic through the last four nodes
   does not know: extrapolated, the modes made the value at the pole depend on phi by
   10 % (n = 1.5, s = 3, ti = 30, to = 180). Near the pole the mode m of a smooth
   function on the sphere goes as sin^m theta, so past the last node mode m is the last
   node's value times r^m, r = sin theta / sin theta_last (*r; 1 before the last node,
   where the Lagrange weights stand). At the last node this is the Lagrange weights. */
static void pole_weights(const double *nodes, int n, double x, const double wt[4],
                         double wp[4], double *r)
{
    double last = nodes[n - 1];
    *r = 1.0;
    if (!(x > last)) {
        for (int a = 0; a < 4; a++)
            wp[a] = wt[a];
        return;
    }
    /* x > last: the stencil is the last four nodes; Gauss nodes lie inside (0, 1), so
       1 - last^2 > 0; x <= 1 (a cosine), and the max keeps rounding above 1 harmless */
    wp[0] = wp[1] = wp[2] = 0.0;
    wp[3] = 1.0;
    double q = (1.0 - x * x) / (1.0 - last * last);
    *r = sqrt(q > 0.0 ? q : 0.0);
}

static int ok_side(btdf_pane_side s) { return s == BTDF_PANE_FRONT || s == BTDF_PANE_BACK; }
static int ok_part(btdf_part p) { return p == BTDF_PART_TRANSMISSION || p == BTDF_PART_REFLECTION; }

/* One value of an array over the incidence nodes, at mu. */
static double interp1(const btdf_pane *P, const double *v, double mu)
{
    int k;
    double wt[4];
    lagrange(P->mu, P->n, mu, &k, wt);
    double s = 0.0;
    for (int a = 0; a < 4; a++)
        s += wt[a] * v[k + a];
    return s;
}

/* The modes b[0 .. P->m) of block (side, part), channel ch, at cosines mui, muo in (0, 1]
   (checked by the callers): the interpolation btdf_pane_get_series describes. */
static void modes_at(const btdf_pane *P, btdf_pane_side side, btdf_part part, int ch,
                     double mui, double muo, double *bm)
{
    const double *c = P->ch[ch].coef[pane_block(side, part)];
    int ki, ko, n = P->n;
    double wi0[4], wo0[4], wi1[4], wo1[4];
    lagrange(P->mu, n, mui, &ki, wi0);
    lagrange(P->mu, n, muo, &ko, wo0);
    double ri, ro;
    pole_weights(P->mu, n, mui, wi0, wi1, &ri);
    pole_weights(P->mu, n, muo, wo0, wo1, &ro);
    size_t oo = (size_t)n * n;
    double rm = 1.0, rr = ri * ro; /* (ri ro)^m, by one product per mode */
    for (int m = 0; m < P->m; m++) {
        const double *cc = c + (size_t)m * oo;
        const double *wi = m ? wi1 : wi0, *wo = m ? wo1 : wo0;
        double v = 0.0;
        for (int a = 0; a < 4; a++) {
            const double *row = cc + (size_t)(ki + a) * n + ko;
            v += wi[a] * (wo[0] * row[0] + wo[1] * row[1] + wo[2] * row[2] + wo[3] * row[3]);
        }
        bm[m] = m ? v * rm : v;
        rm *= rr;
    }
}

BTDF_API int btdf_pane_modes(const btdf_pane *P, btdf_pane_side side, btdf_part part, int ch,
                             double mu_i, double mu_o, double *c)
{
    if (!P || !ok_side(side) || !ok_part(part) || ch < 0 || ch >= P->o.front.channels || !c)
        return 0;
    for (int m = 0; m < P->m; m++)
        c[m] = 0.0;
    if (!(mu_i > 0.0 && mu_i <= 1.0) || !(mu_o > 0.0 && mu_o <= 1.0))
        return P->m; /* grazing or out of range: the BSDF is 0 there */
    modes_at(P, side, part, ch, mu_i, mu_o, c);
    return P->m;
}

BTDF_API void btdf_pane_eval_phis(const btdf_pane *P, btdf_pane_side side, btdf_part part,
                                  int ch, double ti, double to, size_t count, const double *phi,
                                  double *out)
{
    for (size_t k = 0; k < count; k++)
        out[k] = 0.0;
    if (!P || !ok_side(side) || !ok_part(part) || ch < 0 || ch >= P->o.front.channels)
        return;
    if (!(ti >= 0.0 && ti < PI / 2))
        return;
    double muo;
    if (part == BTDF_PART_TRANSMISSION) {
        if (!(to > PI / 2 && to <= PI))
            return;
        muo = -cos(to);
    } else {
        if (!(to >= 0.0 && to < PI / 2))
            return;
        muo = cos(to);
    }
    double mui = cos(ti);
    if (!(mui > 0.0) || !(muo > 0.0))
        return; /* grazing: the BSDF is 0 there, as in btdf.h */
    double bm[BTDF_PANE_MODES_MAX];
    modes_at(P, side, part, ch, mui, muo, bm);
    for (size_t k = 0; k < count; k++) {
        if (!isfinite(phi[k]))
            continue;
        /* cos(m phi) by the recurrence cos((m+1)x) = 2 cos x cos(mx) - cos((m-1)x) */
        double c1 = cos(phi[k]), cm_1 = c1, cm = 1.0, sum = 0.0;
        for (int m = 0; m < P->m; m++) {
            sum += bm[m] * cm;
            double nx = m == 0 ? c1 : 2.0 * c1 * cm - cm_1;
            cm_1 = cm;
            cm = nx;
        }
        /* the truncated series rings a little below 0 far from the lobe: a BSDF is not
           negative */
        out[k] = sum > 0.0 && isfinite(sum) ? sum : 0.0;
    }
}

BTDF_API double btdf_pane_eval(const btdf_pane *P, btdf_pane_side side, btdf_part part, int ch,
                               double ti, double to, double phi)
{
    double v;
    btdf_pane_eval_phis(P, side, part, ch, ti, to, 1, &phi, &v);
    return v;
}

BTDF_API btdf_status btdf_pane_get_series(const btdf_pane *P, btdf_pane_side side,
                                          btdf_part part, int ch, const double **mu,
                                          const double **coef, int *nodes, int *modes)
{
    if (!P || !mu || !coef || !nodes || !modes || !ok_side(side) || !ok_part(part) || ch < 0 ||
        ch >= P->o.front.channels)
        return BTDF_EINVAL;
    *mu = P->mu;
    *coef = P->ch[ch].coef[pane_block(side, part)];
    *nodes = P->n;
    *modes = P->m;
    return BTDF_OK;
}

BTDF_API double btdf_pane_specular(const btdf_pane *P, btdf_pane_side side, btdf_part part,
                                   int ch, double ti)
{
    if (!P || !ok_side(side) || !ok_part(part) || ch < 0 || ch >= P->o.front.channels)
        return 0.0;
    if (!(ti >= 0.0 && ti <= PI / 2))
        return 0.0;
    if (!(P->o.front_smooth && P->o.back_smooth)) {
        /* one flat face: its own mirror, exactly */
        int flat = side == BTDF_PANE_FRONT ? P->o.front_smooth : P->o.back_smooth;
        if (part != BTDF_PART_REFLECTION || !flat)
            return 0.0;
        return btdf_fresnel_r(P->o.front.ior[ch], ti);
    }
    double v = interp1(P, P->ch[ch].spec[pane_block(side, part)], cos(ti));
    return v > 0.0 ? (v < 1.0 ? v : 1.0) : 0.0;
}

BTDF_API void btdf_pane_albedo(const btdf_pane *P, btdf_pane_side side, int ch, double ti,
                               double *T, double *R)
{
    double t = 0.0, r = 0.0;
    if (P && ok_side(side) && ch >= 0 && ch < P->o.front.channels && ti >= 0.0 &&
        ti <= PI / 2) {
        const pane_ch *pc = &P->ch[ch];
        double mu = cos(ti);
        int bt = pane_block(side, BTDF_PART_TRANSMISSION), br = pane_block(side, BTDF_PART_REFLECTION);
        if (P->o.front_smooth && P->o.back_smooth) {
            t = btdf_pane_specular(P, side, BTDF_PART_TRANSMISSION, ch, ti);
            r = btdf_pane_specular(P, side, BTDF_PART_REFLECTION, ch, ti);
        } else {
            /* the spread part interpolated, the exact delta added */
            double sr = btdf_pane_specular(P, side, BTDF_PART_REFLECTION, ch, ti);
            double spr[BTDF_PANE_NODES_MAX];
            for (int j = 0; j < P->n; j++)
                spr[j] = pc->alb[br][j] - pc->spec[br][j];
            t = interp1(P, pc->alb[bt], mu);
            r = interp1(P, spr, mu) + sr;
        }
        t = t > 0.0 ? t : 0.0;
        r = r > 0.0 ? r : 0.0;
    }
    if (T)
        *T = t;
    if (R)
        *R = r;
}

/* e_L1 and e_T of one side and part at ti (channel 0). */
static void compare_one(const btdf_pane *a, const btdf_pane *ref, btdf_pane_side side,
                        btdf_part part, double ti, size_t nto, size_t nphi, double *el1,
                        double *et)
{
    double ta, ra, tr, rr;
    btdf_pane_albedo(a, side, 0, ti, &ta, &ra);
    btdf_pane_albedo(ref, side, 0, ti, &tr, &rr);
    double A = part == BTDF_PART_TRANSMISSION ? ta : ra;
    double Ar = part == BTDF_PART_TRANSMISSION ? tr : rr;
    double fl = Ar > 0.01 ? Ar : 0.01;
    /* midpoint cells in mu_o and phi over [0, pi] (the other half is its mirror) */
    double s = 0.0, dmu = 1.0 / (double)nto, dph = PI / (double)nphi;
    for (size_t i = 0; i < nto; i++) {
        double mu = (i + 0.5) * dmu;
        double to = part == BTDF_PART_TRANSMISSION ? PI - acos(mu) : acos(mu);
        for (size_t k = 0; k < nphi; k++) {
            double ph = (k + 0.5) * dph;
            double d = btdf_pane_eval(a, side, part, 0, ti, to, ph) -
                       btdf_pane_eval(ref, side, part, 0, ti, to, ph);
            s += fabs(d) * mu;
        }
    }
    s *= 2.0 * dmu * dph;
    s += fabs(btdf_pane_specular(a, side, part, 0, ti) - btdf_pane_specular(ref, side, part, 0, ti));
    *el1 = s / fl;
    *et = fabs(A - Ar) / fl;
}

BTDF_API btdf_status btdf_pane_compare(const btdf_pane *a, const btdf_pane *ref, double ti_max,
                                       size_t nti, size_t nto, size_t nphi,
                                       btdf_pane_error *out)
{
    if (!a || !ref || !out || !(ti_max > 0.0 && ti_max <= PI / 2))
        return BTDF_EINVAL;
    if (!nti)
        nti = 24;
    if (!nto)
        nto = 96;
    if (!nphi)
        nphi = 96;
    btdf_pane_error e = {0, 0, 0, BTDF_PANE_FRONT, BTDF_PART_TRANSMISSION};
    for (int sd = 1; sd <= 2; sd++)
        for (int pt = 1; pt <= 2; pt++)
            for (size_t k = 0; k < nti; k++) {
                /* stratified midpoints: between the Gauss nodes, as a test should be */
                double ti = ti_max * (k + 0.5) / (double)nti, l1, t;
                compare_one(a, ref, (btdf_pane_side)sd, (btdf_part)pt, ti, nto, nphi, &l1, &t);
                if (l1 > e.e_l1) {
                    e.e_l1 = l1;
                    e.e_l1_ti = ti;
                    e.side = sd;
                    e.part = (btdf_part)pt;
                }
                if (t > e.e_t)
                    e.e_t = t;
            }
    *out = e;
    return BTDF_OK;
}
