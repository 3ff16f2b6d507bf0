/* SPDX-License-Identifier: MIT */
/* pbrt_route.h: the route pbrt-v3 takes through a SCATFUN file when it samples and evaluates it,
   re-implemented in single precision from the algorithm's description (Physically Based
   Rendering, 3rd edition, sections 8.6 and A.4), with iteration caps so a renderer's endless
   loop shows up here as a counted failure. Used by tests/test_sampler.c and tools/sampler_sweep.c. */
#ifndef BTDF_PBRT_ROUTE_H
#define BTDF_PBRT_ROUTE_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "btdf_scatfun.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* Iterations after which a loop that the renderer runs without bound counts as hung:
   a bracketed Newton-bisection on [0, 1] needs at most about 21 bisection halvings to
   reach the renderer's 1e-6 bracket, plus a few Newton steps. */
#define PR_ITER_CAP 200

typedef struct pr_table {
    int n, nch, mmax;
    float eta;
    const float *mu, *cdf, *coef;
    uint32_t *off, *len; /* n * n each, index slow * n + fast */
    float *a0;           /* n * n: the first coefficient of channel 0 */
    float *recip;        /* mmax: 1 / k */
    float *ak;           /* scratch, nch * mmax */
} pr_table;

typedef struct pr_stats {
    long calls, capped_mu, capped_phi, nonfinite, pole_out;
    int max_iter_mu, max_iter_phi;
} pr_stats;

static inline void pr_table_free(pr_table *t)
{
    free(t->off);
    free(t->len);
    free(t->a0);
    free(t->recip);
    free(t->ak);
    memset(t, 0, sizeof *t);
}

static inline int pr_table_init(pr_table *t, const btdf_scatfun *f)
{
    memset(t, 0, sizeof *t);
    t->n = (int)btdf_scatfun_node_count(f);
    t->nch = btdf_scatfun_channels(f);
    t->mmax = (int)btdf_scatfun_max_order(f);
    t->eta = (float)btdf_scatfun_eta(f);
    t->mu = btdf_scatfun_nodes(f);
    t->cdf = btdf_scatfun_cdf(f);
    t->coef = btdf_scatfun_coeffs(f);
    size_t nn = (size_t)t->n * (size_t)t->n;
    size_t mm = t->mmax > 0 ? (size_t)t->mmax : 1;
    t->off = malloc(nn * sizeof *t->off);
    t->len = malloc(nn * sizeof *t->len);
    t->a0 = malloc(nn * sizeof *t->a0);
    t->recip = malloc(mm * sizeof *t->recip);
    t->ak = malloc((size_t)t->nch * mm * sizeof *t->ak);
    if (!t->off || !t->len || !t->a0 || !t->recip || !t->ak) {
        pr_table_free(t);
        return -1;
    }
    for (size_t i = 0; i < (size_t)t->n; i++)
        for (size_t o = 0; o < (size_t)t->n; o++) {
            size_t off = 0, len = 0;
            btdf_scatfun_pair(f, i, o, &off, &len);
            t->off[i * (size_t)t->n + o] = (uint32_t)off;
            t->len[i * (size_t)t->n + o] = (uint32_t)len;
            t->a0[i * (size_t)t->n + o] = len ? t->coef[off] : 0.0f;
        }
    for (size_t k = 0; k < mm; k++)
        t->recip[k] = k ? 1.0f / (float)k : 0.0f;
    return 0;
}

/* Largest i in [0, size - 2] with pred(i) true, for a predicate true then false. */
typedef int (*pr_pred)(const void *ctx, int i);
static inline int pr_find_interval(int size, pr_pred pred, const void *ctx)
{
    int lo = 0, count = size;
    while (count > 0) {
        int step = count / 2, mid = lo + step;
        if (pred(ctx, mid)) {
            lo = mid + 1;
            count -= step + 1;
        } else {
            count = step;
        }
    }
    int r = lo - 1;
    return r < 0 ? 0 : r > size - 2 ? size - 2 : r;
}

/* Catmull-Rom weights in single precision, as the renderer computes them. 0 when x lies
   outside the nodes. */
static inline int pr_weights(int n, const float *nodes, float x, int *offset, float w[4])
{
    if (!(x >= nodes[0] && x <= nodes[n - 1]))
        return 0;
    int lo = 0, count = n;
    while (count > 0) {
        int step = count / 2, mid = lo + step;
        if (nodes[mid] <= x) {
            lo = mid + 1;
            count -= step + 1;
        } else {
            count = step;
        }
    }
    int idx = lo - 1 < 0 ? 0 : lo - 1 > n - 2 ? n - 2 : lo - 1;
    *offset = idx - 1;
    float x0 = nodes[idx], x1 = nodes[idx + 1];
    float t = (x - x0) / (x1 - x0), t2 = t * t, t3 = t2 * t;
    w[1] = 2 * t3 - 3 * t2 + 1;
    w[2] = -2 * t3 + 3 * t2;
    if (idx > 0) {
        float w0 = (t3 - 2 * t2 + t) * (x1 - x0) / (x1 - nodes[idx - 1]);
        w[0] = -w0;
        w[2] += w0;
    } else {
        float w0 = t3 - 2 * t2 + t;
        w[0] = 0;
        w[1] -= w0;
        w[2] += w0;
    }
    if (idx + 2 < n) {
        float w3 = (t3 - t2) * (x1 - x0) / (nodes[idx + 2] - x0);
        w[1] -= w3;
        w[3] = w3;
    } else {
        float w3 = t3 - t2;
        w[1] -= w3;
        w[2] += w3;
        w[3] = 0;
    }
    return 1;
}

typedef struct pr_rows {
    const float *arr;
    int size2, offset;
    const float *w;
    float u;
} pr_rows;

static inline float pr_interp(const pr_rows *r, const float *arr, int idx)
{
    float v = 0;
    for (int i = 0; i < 4; i++)
        if (r->w[i] != 0)
            v += arr[(r->offset + i) * r->size2 + idx] * r->w[i];
    return v;
}

static inline int pr_cdf_le(const void *ctx, int i)
{
    const pr_rows *r = ctx;
    return pr_interp(r, r->arr, i) <= r->u;
}

/* The elevation step of the renderer's sampling: picks the fast cosine for slow cosine
   alpha from the cdf rows and the a0 spline, by Newton steps guarded by bisection on the
   spline segment. *iters: loop iterations; returns 0 when capped (the renderer would not
   return), 1 otherwise; *mu_out and *pdf as the renderer computes them. */
static inline int pr_sample_mu(const pr_table *t, float alpha, float u, float *mu_out, float *pdf,
                               int *iters)
{
    int offset;
    float w[4];
    *iters = 0;
    if (!pr_weights(t->n, t->mu, alpha, &offset, w)) {
        *mu_out = 0;
        *pdf = -1; /* the renderer leaves the pdf unset here and returns early */
        return 1;
    }
    pr_rows r = {t->cdf, t->n, offset, w, 0};
    float maximum = pr_interp(&r, t->cdf, t->n - 1);
    u *= maximum;
    r.u = u;
    int idx = pr_find_interval(t->n, pr_cdf_le, &r);
    float f0 = pr_interp(&r, t->a0, idx), f1 = pr_interp(&r, t->a0, idx + 1);
    float x0 = t->mu[idx], x1 = t->mu[idx + 1];
    float width = x1 - x0, d0, d1;
    u = (u - pr_interp(&r, t->cdf, idx)) / width;
    if (idx > 0)
        d0 = width * (f1 - pr_interp(&r, t->a0, idx - 1)) / (x1 - t->mu[idx - 1]);
    else
        d0 = f1 - f0;
    if (idx + 2 < t->n)
        d1 = width * (pr_interp(&r, t->a0, idx + 2) - f0) / (t->mu[idx + 2] - x0);
    else
        d1 = f1 - f0;
    /* first guess: invert the integral of the linear interpolant */
    float tt;
    if (f0 != f1)
        tt = (f0 - sqrtf(fmaxf(0.0f, f0 * f0 + 2 * u * (f1 - f0)))) / (f0 - f1);
    else
        tt = u / f0;
    float a = 0, b = 1, F = 0, fv = 0;
    int ok = 0;
    for (int it = 0; it < PR_ITER_CAP; it++) {
        *iters = it + 1;
        if (!(tt >= a && tt <= b))
            tt = 0.5f * (a + b);
        /* the segment's integral and value in Horner form */
        F = tt * (f0 + tt * (.5f * d0 + tt * ((1.f / 3.f) * (-2 * d0 - d1) + f1 - f0 +
                                               tt * (.25f * (d0 + d1) + .5f * (f0 - f1)))));
        fv = f0 + tt * (d0 + tt * (-2 * d0 - d1 + 3 * (f1 - f0) + tt * (d0 + d1 + 2 * (f0 - f1))));
        if (fabsf(F - u) < 1e-6f || b - a < 1e-6f) {
            ok = 1;
            break;
        }
        if (F - u < 0)
            a = tt;
        else
            b = tt;
        tt -= (F - u) / fv;
    }
    *pdf = fv / maximum;
    *mu_out = x0 + width * tt;
    return ok;
}

/* The azimuth step: inverts the integral of the Fourier series ak[0..m-1] on [0, pi]
   in double precision, mirrored for u >= 1/2. Returns 0 when capped. */
static inline int pr_sample_fourier(const float *ak, const float *recip, int m, float u,
                                    float *pdf, float *phi_out, float *val, int *iters)
{
    int flip = u >= 0.5f;
    if (flip)
        u = 1 - 2 * (u - .5f);
    else
        u *= 2;
    double a = 0, b = M_PI, phi = 0.5 * M_PI, F = 0, f = 0;
    int ok = 0;
    *iters = 0;
    for (int it = 0; it < PR_ITER_CAP; it++) {
        *iters = it + 1;
        double c = cos(phi), s = sqrt(fmax(0.0, 1 - c * c));
        double cprev = c, ccur = 1, sprev = -s, scur = 0;
        F = ak[0] * phi;
        f = ak[0];
        for (int k = 1; k < m; k++) {
            double sn = 2 * c * scur - sprev, cn = 2 * c * ccur - cprev;
            sprev = scur;
            scur = sn;
            cprev = ccur;
            ccur = cn;
            F += ak[k] * recip[k] * sn;
            f += ak[k] * cn;
        }
        F -= u * ak[0] * M_PI;
        if (F > 0)
            b = phi;
        else
            a = phi;
        if (fabs(F) < 1e-6f || b - a < 1e-6f) {
            ok = 1;
            break;
        }
        phi -= F / f;
        if (!(phi > a && phi < b))
            phi = 0.5f * (a + b);
    }
    if (flip)
        phi = 2 * M_PI - phi;
    *pdf = (float)(0.5 / M_PI * f / ak[0]);
    *phi_out = (float)phi;
    *val = (float)f;
    return ok;
}

static inline float pr_fourier(const float *ak, int m, double cphi)
{
    double v = 0, cprev = 1, ccur = cphi;
    for (int k = 0; k < m; k++) {
        v += ak[k] * cprev;
        double cn = 2 * cphi * ccur - cprev;
        cprev = ccur;
        ccur = cn;
    }
    return (float)v;
}

/* Sums the weighted series around (muI, muO) into t->ak; returns the longest length, -1
   when a cosine lies outside the nodes. */
static inline int pr_gather(pr_table *t, float muI, float muO)
{
    int oi, oo;
    float wi[4], wo[4];
    if (!pr_weights(t->n, t->mu, muI, &oi, wi) || !pr_weights(t->n, t->mu, muO, &oo, wo))
        return -1;
    memset(t->ak, 0, (size_t)t->nch * (size_t)t->mmax * sizeof *t->ak);
    int mlen = 0;
    for (int b = 0; b < 4; b++)
        for (int a = 0; a < 4; a++) {
            float wgt = wi[a] * wo[b];
            if (wgt == 0)
                continue;
            size_t id = (size_t)(oo + b) * (size_t)t->n + (size_t)(oi + a);
            int m = (int)t->len[id];
            const float *ap = t->coef + t->off[id];
            if (m > mlen)
                mlen = m;
            for (int c = 0; c < t->nch; c++)
                for (int k = 0; k < m; k++)
                    t->ak[c * t->mmax + k] += wgt * ap[c * m + k];
        }
    return mlen;
}

/* The renderer's Sample_f for the file in local coordinates: wo (unit), u[2] in [0, 1);
   radiance != 0 applies the e^2 of radiance transport. Fills wi, the value rgb[3] (one
   channel: rgb[0] only), *pdf (0 = no sample). Counts caps and non-finite results in st.
   Returns 0 when a loop was capped. */
static inline int pr_sample_f(pr_table *t, const float wo[3], const float u[2], int radiance,
                              float wi[3], float rgb[3], float *pdf, pr_stats *st)
{
    int itm = 0, itp = 0, ok = 1;
    float muO = wo[2], pdfMu, muI, pdfPhi = 0, phi = 0, Y;
    *pdf = 0; /* set by the caller in the renderer */
    rgb[0] = rgb[1] = rgb[2] = 0;
    wi[0] = wi[1] = 0;
    wi[2] = 1;
    st->calls++;
    if (wo[2] == 0)
        return 1;
    if (!pr_sample_mu(t, muO, u[1], &muI, &pdfMu, &itm)) {
        st->capped_mu++;
        ok = 0;
    }
    if (itm > st->max_iter_mu)
        st->max_iter_mu = itm;
    int mlen = pr_gather(t, muI, muO);
    if (mlen < 0) {
        st->pole_out++;
        return ok;
    }
    if (!pr_sample_fourier(t->ak, t->recip, mlen, u[0], &pdfPhi, &phi, &Y, &itp)) {
        st->capped_phi++;
        ok = 0;
    }
    if (itp > st->max_iter_phi)
        st->max_iter_phi = itp;
    float prod = pdfPhi * pdfMu;
    *pdf = prod > 0 ? prod : 0; /* max(0, x) returns 0 for NaN x as the renderer's does */
    float sin2i = fmaxf(0.0f, 1 - muI * muI);
    float sin2o = fmaxf(0.0f, 1 - wo[2] * wo[2]);
    float norm = sqrtf(sin2i / sin2o);
    if (isinf(norm))
        norm = 0;
    float sp = sinf(phi), cp = cosf(phi);
    wi[0] = -(norm * (cp * wo[0] - sp * wo[1]));
    wi[1] = -(norm * (sp * wo[0] + cp * wo[1]));
    wi[2] = -muI;
    float l = sqrtf(wi[0] * wi[0] + wi[1] * wi[1] + wi[2] * wi[2]);
    wi[0] /= l;
    wi[1] /= l;
    wi[2] /= l;
    float scale = muI != 0 ? 1 / fabsf(muI) : 0;
    if (radiance && muI * muO > 0) {
        float e = muI > 0 ? 1 / t->eta : t->eta;
        scale *= e * e;
    }
    if (t->nch == 1) {
        rgb[0] = Y * scale;
    } else {
        float R = pr_fourier(t->ak + t->mmax, mlen, cp);
        float B = pr_fourier(t->ak + 2 * t->mmax, mlen, cp);
        float G = 1.39829f * Y - 0.100913f * B - 0.297375f * R;
        rgb[0] = fmaxf(0.0f, R * scale);
        rgb[1] = fmaxf(0.0f, G * scale);
        rgb[2] = fmaxf(0.0f, B * scale);
    }
    /* what reaches the integrator: a sample with pdf > 0 and its direction and value */
    int bad = !isfinite(*pdf);
    if (*pdf > 0) {
        bad |= !isfinite(wi[0]) || !isfinite(wi[1]) || !isfinite(wi[2]);
        for (int c = 0; c < 3; c++)
            bad |= !isfinite(rgb[c]);
    }
    if (bad)
        st->nonfinite++;
    return ok;
}

/* The same elevation step with every quantity in double precision, as a renderer built
   with 64-bit floats (pbrt-v3's PBRT_FLOAT_AS_DOUBLE) runs it. Returns 0 when capped. */
static inline int pr_sample_mu_d(const pr_table *t, double alpha, double u, double *mu_out,
                                 int *iters)
{
    int n = t->n;
    *iters = 0;
    *mu_out = 0;
    if (!(alpha >= t->mu[0] && alpha <= t->mu[n - 1]))
        return 1;
    int lo = 0, count = n;
    while (count > 0) {
        int step = count / 2, mid = lo + step;
        if (t->mu[mid] <= alpha) {
            lo = mid + 1;
            count -= step + 1;
        } else {
            count = step;
        }
    }
    int id = lo - 1 < 0 ? 0 : lo - 1 > n - 2 ? n - 2 : lo - 1, offset = id - 1;
    double x0 = t->mu[id], x1 = t->mu[id + 1], w[4];
    double s = (alpha - x0) / (x1 - x0), s2 = s * s, s3 = s2 * s;
    w[1] = 2 * s3 - 3 * s2 + 1;
    w[2] = -2 * s3 + 3 * s2;
    if (id > 0) {
        double w0 = (s3 - 2 * s2 + s) * (x1 - x0) / (x1 - t->mu[id - 1]);
        w[0] = -w0;
        w[2] += w0;
    } else {
        double w0 = s3 - 2 * s2 + s;
        w[0] = 0;
        w[1] -= w0;
        w[2] += w0;
    }
    if (id + 2 < n) {
        double w3 = (s3 - s2) * (x1 - x0) / (t->mu[id + 2] - x0);
        w[1] -= w3;
        w[3] = w3;
    } else {
        double w3 = s3 - s2;
        w[1] -= w3;
        w[2] += w3;
        w[3] = 0;
    }
#define PR_IP(arr, j) (((w[0] != 0) ? (double)(arr)[(offset + 0) * n + (j)] * w[0] : 0) + \
                       ((w[1] != 0) ? (double)(arr)[(offset + 1) * n + (j)] * w[1] : 0) + \
                       ((w[2] != 0) ? (double)(arr)[(offset + 2) * n + (j)] * w[2] : 0) + \
                       ((w[3] != 0) ? (double)(arr)[(offset + 3) * n + (j)] * w[3] : 0))
    double maximum = PR_IP(t->cdf, n - 1);
    u *= maximum;
    lo = 0;
    count = n;
    while (count > 0) {
        int step = count / 2, mid = lo + step;
        if (PR_IP(t->cdf, mid) <= u) {
            lo = mid + 1;
            count -= step + 1;
        } else {
            count = step;
        }
    }
    int idx = lo - 1 < 0 ? 0 : lo - 1 > n - 2 ? n - 2 : lo - 1;
    double f0 = PR_IP(t->a0, idx), f1 = PR_IP(t->a0, idx + 1);
    double y0 = t->mu[idx], y1 = t->mu[idx + 1], width = y1 - y0, d0, d1;
    u = (u - PR_IP(t->cdf, idx)) / width;
    d0 = idx > 0 ? width * (f1 - PR_IP(t->a0, idx - 1)) / (y1 - t->mu[idx - 1]) : f1 - f0;
    d1 = idx + 2 < n ? width * (PR_IP(t->a0, idx + 2) - f0) / (t->mu[idx + 2] - y0) : f1 - f0;
#undef PR_IP
    double tt = f0 != f1 ? (f0 - sqrt(fmax(0.0, f0 * f0 + 2 * u * (f1 - f0)))) / (f0 - f1)
                         : u / f0;
    double a = 0, b = 1;
    for (int it = 0; it < PR_ITER_CAP; it++) {
        *iters = it + 1;
        if (!(tt >= a && tt <= b))
            tt = 0.5 * (a + b);
        double F = tt * (f0 + tt * (.5 * d0 + tt * ((1. / 3.) * (-2 * d0 - d1) + f1 - f0 +
                                                    tt * (.25 * (d0 + d1) + .5 * (f0 - f1)))));
        double fv = f0 + tt * (d0 + tt * (-2 * d0 - d1 + 3 * (f1 - f0) + tt * (d0 + d1 + 2 * (f0 - f1))));
        if (fabs(F - u) < 1e-6 || b - a < 1e-6) {
            *mu_out = y0 + width * tt;
            return 1;
        }
        if (F - u < 0)
            a = tt;
        else
            b = tt;
        tt -= (F - u) / fv;
    }
    *mu_out = y0 + width * tt;
    return 0;
}

/* Largest first coefficient (channel 0) stored: the scale of the values a renderer's
   elevation sampler inverts. */
static inline double pr_a0_peak(const pr_table *t)
{
    double peak = 0;
    for (int i = 0; i < t->n; i++)
        for (int o = 0; o < t->n; o++)
            peak = fmax(peak, fabs((double)t->a0[i * t->n + o]));
    return peak;
}

#endif /* BTDF_PBRT_ROUTE_H */
