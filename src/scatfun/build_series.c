/* SPDX-License-Identifier: MIT */
/* build_series.c: one pair's series: the workers' scratch, the azimuth grid doubled until the
   series settle, truncation, and the series kept. */
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

void *sf_build_ws_new(void *vctx)
{
    build_ctx *c = vctx;
    build_ws *w = calloc(1, sizeof *w);
    if (!w)
        return NULL;
    size_t len = (size_t)c->nst * (c->nmax + 1);
    w->x = malloc(len * sizeof(double));
    w->a = malloc(len * sizeof(double));
    w->ia = malloc(len * sizeof(double));
    w->y = malloc((c->nmax + 1) * sizeof(double));
    w->rho = malloc(4 * sizeof(double));
    w->cosg = malloc((c->nmax + 1) * sizeof(double));
    w->sing = malloc((c->nmax + 1) * sizeof(double));
    w->h2g = malloc((c->nmax + 1) * sizeof(double));
    if (w->cosg && w->sing && w->h2g) {
        for (size_t j = 0; j <= c->nmax; j++) {
            w->cosg[j] = cos(M_PI * (double)j / (double)c->nmax);
            w->sing[j] = sin(M_PI * (double)j / (double)c->nmax);
            /* 1 + cos phi = 1 - cos phi_d = 2 sin^2(phi_d / 2), without cancellation */
            double sh = sin(0.5 * M_PI * (double)j / (double)c->nmax);
            w->h2g[j] = sh * sh;
        }
        /* exact forward, side and backward planes */
        w->cosg[0] = 1.0, w->sing[0] = 0.0;
        w->cosg[c->nmax] = -1.0, w->sing[c->nmax] = 0.0;
        w->cosg[c->nmax / 2] = 0.0, w->sing[c->nmax / 2] = 1.0;
        w->fb.cosg = w->cosg;
        w->fb.sing = w->sing;
        w->fb.nmax = c->nmax;
    }
    if (!w->cosg || !w->sing || !w->h2g || !w->x || !w->a || !w->ia ||
        !w->y || !w->rho || sf_fft_reserve(&w->fb, c->nmax + 1)) {
        sf_fft_free(&w->fb);
        free(w->x); free(w->a); free(w->ia); free(w->y);
        free(w->rho);
        free(w->cosg);
        free(w->sing);
        free(w->h2g);
        free(w);
        return NULL;
    }
    return w;
}

void sf_build_ws_free(void *vw)
{
    build_ws *w = vw;
    if (!w)
        return;
    sf_fft_free(&w->fb);
    free(w->x); free(w->a); free(w->ia); free(w->y);
    free(w->rho);
    free(w->cosg);
    free(w->sing);
    free(w->h2g);
    free(w);
}
/* Converged coefficients of g at (mu_s, mu_f): doubles the azimuth grid until the
   series of the coarser grid misses the samples of the finer one by less than
   eps_alias (in L1 over the circle, per channel relative to norm[ch]). Leaves w->a
   with stride nmax + 1 holding N + 1 coefficients per stored channel and w->x the
   samples on that grid; returns N (0 on failure). */
size_t sf_converge(build_ctx *c, build_ws *w, int side, double mu_s, double mu_f,
                       const double *norm, double eps_alias)
{
    size_t S = c->nmax + 1;
    size_t N = blk_refl[side] ? c->nmin : sf_first_grid(c, side, mu_s, mu_f);
    w->dark = N == 0;
    if (N == 0) {
        /* No facet connects the pair at any azimuth (n = 1.5, s = 20 at 1e-3: 880,000
           of 1.86 million series): what the samples below would find on the material's
           grids, 0 (2 nmin <= nmax: build_impl), without sampling. */
        N = 2 * c->nmin;
        for (int k = 0; k < c->nst; k++) {
            memset(w->x + (size_t)k * S, 0, (N + 1) * sizeof *w->x);
            memset(w->a + (size_t)k * S, 0, (N + 1) * sizeof *w->a);
        }
        return N;
    }
    sf_sample_grid(c, w, side, mu_s, mu_f, N, S, 1, 0, w->x);
    for (int k = 0; k < c->nst; k++)
        if (sf_dct_forward(&w->fb, w->x + k * S, N, w->a + k * S))
            return 0;
    int zero = 1;
    for (int k = 0; k < c->nst && zero; k++)
        for (size_t j = 0; j <= N && zero; j++)
            zero = w->x[k * S + j] == 0.0;
    for (;;) {
        if (2 * N > c->nmax) {
            pthread_mutex_lock(&c->lock);
            c->capped = 1;
            pthread_mutex_unlock(&c->lock);
            return N;
        }
        size_t N2 = 2 * N;
        /* spread the old samples onto the finer grid from the top down */
        for (int k = 0; k < c->nst; k++)
            for (size_t j = N + 1; j-- > 0;)
                w->x[k * S + 2 * j] = w->x[k * S + j];
        sf_sample_grid(c, w, side, mu_s, mu_f, N2, S, 2, 1, w->x);
        if (zero) {
            /* no transmission on either grid (an unreachable pair): all zero */
            for (int k = 0; k < c->nst && zero; k++)
                for (size_t j = 1; j <= N2 && zero; j += 2)
                    zero = w->x[k * S + j] == 0.0;
            if (zero) {
                /* the N2 + 1 coefficients the caller reads, not the whole stride (nmax
                   + 1: zeroing 128 KiB per unreachable pair was 4% of a build) */
                for (int k = 0; k < c->nst; k++)
                    memset(w->a + (size_t)k * S, 0, (N2 + 1) * sizeof *w->a);
                return N2;
            }
        }
        double worst = 0.0;
        for (int k = 0; k < c->nst; k++) {
            /* The measured L1 over the circle of the coarse series against the new
               samples (the points it did not see) is its error, not a bound on it.
               Until this version transmission used the bound 2 pi sum |a'_q - a_q|
               (a' the finer grid's): where g has a kink or an edge in phi (reflection
               below the dense side, where facets start to reflect totally, Fresnel ~
               1 - sqrt; transmission, where the facets needed turn away or pass the
               critical angle) the coefficients decay like q^-1.5 or slower and the
               bound kept doubling the grid: n = 1.5, s = 3 at 1e-3 converged 50,534
               series at N = 1024 to 4096; measured, none needs more than 512, with
               the same nodes and the same measured e_L1 of the file. */
            double l1 = sf_series_l1(&w->fb, w->a + k * S, N + 1, N2, w->x + k * S, w->y);
            if (l1 < 0.0)
                return 0;
            double d = l1 / norm[k]; /* norm >= T_FLOOR */
            if (d > worst)
                worst = d;
            if (sf_dct_forward(&w->fb, w->x + k * S, N2, w->a + k * S))
                return 0;
        }
        N = N2;
        if (worst <= eps_alias)
            return N;
    }
}

/* Shortest length m whose dropped tail costs at most eps_trunc (L1 over the circle,
   relative to norm[ch]) in every stored channel. */
enum { TRUNC_BLOCK = 64 };

BT_CLONES static size_t truncate_len(const build_ctx *c, const double *a, size_t S, size_t N,
                           const double *norm, double eps_trunc)
{
    size_t m = 0;
    for (int k = 0; k < c->nst; k++) {
        const double *ak = a + k * S;
        /* integral over the circle of |sum_{q>=m} a_q cos q phi| <= 4 sum |a_q| for
           q >= 1, and 2 pi |a_0| */
        double tail = 0.0;
        size_t q = N + 1;
        int stop = 0;
        /* In blocks of TRUNC_BLOCK from the top (the one-at-a-time loop waited on a
           division per coefficient, over thousands of coefficients per series: 8 % of
           an s = 20 build). A block whose terms, summed in four lanes, keep the tail
           below eps_trunc by more than their rounding (64 terms >= 0: at most 64 ulps
           of the sum) cannot stop the walk anywhere inside, so it is taken whole; the
           block where the tail would reach eps_trunc is walked term by term. Terms
           are multiplied by 1/norm rather than divided. The same m as the
           one-at-a-time walk with divisions except where the tail ties eps_trunc to
           about 1e-12 (the files compared were byte for byte the same). */
        double inv = 1.0 / norm[k]; /* norm >= T_FLOOR > 0 */
        while (q > 0 && !stop) {
            size_t nb = q < TRUNC_BLOCK ? q : TRUNC_BLOCK, lo = q - nb;
            double add[TRUNC_BLOCK];
            for (size_t i = 0; i < nb; i++)
                add[i] = 4.0 * fabs(ak[lo + i]) * inv;
            if (lo == 0)
                add[0] = 2.0 * M_PI * fabs(ak[0]) * inv;
            if (nb == TRUNC_BLOCK) {
                double b4[4] = {0.0, 0.0, 0.0, 0.0};
                for (size_t i4 = 0; i4 < TRUNC_BLOCK; i4 += 4)
                    for (int v = 0; v < 4; v++)
                        b4[v] += add[i4 + v];
                double bs = (b4[0] + b4[1]) + (b4[2] + b4[3]);
                if (tail + bs <= eps_trunc * (1.0 - 1e-12)) {
                    tail += bs;
                    q = lo;
                    continue;
                }
            }
            for (size_t i = nb; i-- > 0;) {
                if (tail + add[i] > eps_trunc) {
                    stop = 1;
                    break;
                }
                tail += add[i];
                q--;
            }
        }
        if (q > m)
            m = q;
    }
    return m;
}

/* Keeps the truncated series of the converged coefficients in w->a as pair pr. */
/* For a reflection block: the shortest length m <= m0 whose dropped tail, measured as
   the L1 over the circle of the tail series on the grid of N (not bounded by 4 sum
   |a_q|, far too pessimistic for the k^-1.5 decay of a cusp), costs at most eps_trunc
   in every stored channel. Bisection: the measured tail shrinks with m. */
static size_t truncate_len_measured(const build_ctx *c, build_ws *w, size_t N, size_t m0,
                                    const double *norm, double eps_trunc)
{
    size_t S = c->nmax + 1, lo = 0, hi = m0; /* hi passes (the bound holds there) */
    /* A bracket from the coefficients alone, without transforms. With the trapezoid
       sum Tr over the grid of N (weights summing to pi) and the discrete orthogonality
       of cos(q phi) on it, Tr(t^2) = sum c_q a_q^2 (c_q = pi for q = 0 and N, pi/2
       otherwise), so by Cauchy-Schwarz the measured tail 2 Tr(|t|) is at most
       2 sqrt(pi Tr(t^2)): where that is within eps_trunc, m passes. And 2 Tr(|t|) >=
       2 |Tr(t cos r phi)| = 2 c_r |a_r| for every r >= m: where that exceeds it, m
       fails. The bisection then runs inside the bracket only (fewer inverse transforms,
       same rule). */
    {
        size_t up = 0, low = 0; /* up passes in every channel; below low some fails */
        for (int k = 0; k < c->nst; k++) {
            const double *ak = w->a + k * S;
            double lim = eps_trunc * norm[k]; /* norm >= T_FLOOR > 0 */
            double t2 = 0.0;
            size_t q = m0, upk = m0, lowk = 0;
            /* tail sums from the top: every q > m0 - 1 was dropped by the bound */
            for (size_t r = m0; r <= N; r++) {
                double cr = (r == 0 || r == N) ? M_PI : 0.5 * M_PI;
                t2 += cr * ak[r] * ak[r];
            }
            while (q > 0) {
                double cr = (q - 1 == 0 || q - 1 == N) ? M_PI : 0.5 * M_PI;
                double a = ak[q - 1];
                if (2.0 * cr * fabs(a) > lim) {
                    lowk = q; /* m = q - 1 and below keep a_{q-1} in the tail: fail */
                    break;
                }
                t2 += cr * a * a;
                if (2.0 * sqrt(M_PI * t2) <= lim)
                    upk = q - 1;
                q--;
            }
            if (upk > up)
                up = upk;
            if (lowk > low)
                low = lowk;
        }
        if (up < hi)
            hi = up;
        lo = low < hi ? low : hi;
    }
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        int pass = 1;
        for (int k = 0; k < c->nst && pass; k++) {
            /* tail coefficients a_q for q >= mid, in w->ia (mid <= m0 <= N + 1) */
            memset(w->ia, 0, mid * sizeof *w->ia);
            memcpy(w->ia + mid, w->a + k * S + mid, (N + 1 - mid) * sizeof *w->ia);
            double l1 = sf_series_l1(&w->fb, w->ia, N + 1, N, NULL, w->y);
            if (l1 < 0.0)
                return m0;
            pass = l1 / norm[k] <= eps_trunc; /* norm >= T_FLOOR */
        }
        if (pass)
            hi = mid;
        else
            lo = mid + 1;
    }
    return hi;
}

int sf_keep_series(build_ctx *c, build_ws *w, int side, size_t N, const double *norm,
                       pair *pr)
{
    (void)side; /* every block: the bound first, then the measured tail */
    size_t S = c->nmax + 1;
    size_t m = truncate_len(c, w->a, S, N, norm, share_trunc(c));
    if (m > 0)
        m = truncate_len_measured(c, w, N, m, norm, share_trunc(c));
    free(pr->a);
    pr->a = NULL;
    pr->m = (uint32_t)m;
    pr->N = (uint16_t)N; /* N <= nmax = 16384 */
    pr->done = 0;
    if (m) {
        pr->a = malloc((size_t)c->nst * m * sizeof(double));
        if (!pr->a) {
            pr->m = 0;
            return -1;
        }
        for (int k = 0; k < c->nst; k++)
            memcpy(pr->a + (size_t)k * m, w->a + k * S, m * sizeof(double));
    }
    pr->done = w->dark ? 2 : 1; /* w->dark: set by the sf_converge() of these coefficients */
    return 0;
}
