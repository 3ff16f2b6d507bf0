/* SPDX-License-Identifier: MIT */
/* build_check.c: the node checks: every pair's series (rows), the interpolation error along
   columns and rows at interval midpoints, and the norms the errors are relative to. */
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
#include "scatfun/spline.h"

/* One slow row of one side: the series of every pair (r, c). */
void sf_job_row(void *vctx, void *vws, size_t idx)
{
    build_ctx *c = vctx;
    build_ws *w = vws;
    int side = (int)(idx / c->K);
    size_t r = idx % c->K;
    if (!c->want[side])
        return;
    double norm[3];
    for (size_t col = 0; col < c->K; col++) {
        pair *pr = &c->pairs[side][r * c->K + col];
        if (pr->done)
            continue;
        sf_pair_norm(c, side, c->Tn[r][side], c->Tn[col][side], norm);
        size_t N = sf_converge(c, w, side, c->P[r], c->P[col], norm, share_alias(c));
        if (N == 0 || sf_keep_series(c, w, side, N, norm, pr))
            goto oom;
    }
    return;
oom:
    pthread_mutex_lock(&c->lock);
    c->oom = 1;
    pthread_mutex_unlock(&c->lock);
}

/* Adds weight * series of pair (r, col) into ia (stride S per channel). */
static void add_pair(const build_ctx *c, int side, size_t r, size_t col, double wgt,
                     double *ia, size_t S, size_t *mlen)
{
    const pair *pr = &c->pairs[side][r * c->K + col];
    for (int k = 0; k < c->nst; k++)
        for (size_t q = 0; q < pr->m; q++)
            ia[k * S + q] += wgt * pr->a[(size_t)k * pr->m + q];
    if (pr->m > *mlen)
        *mlen = pr->m;
}

/* Zeroes ia (stride S per channel) over the longest series of the stencil at off with
   weights wt: the fixed index is the row `fixed` (along = 1, stencil over columns) or
   the column (along = 0, stencil over rows). l1_gap reads no further than that. */
static void zero_stencil(const build_ctx *c, double *ia, size_t S, int side, size_t fixed,
                         long off, const double *wt, int along)
{
    size_t top = 0;
    for (int b = 0; b < 4; b++) {
        long h = half_pos(c, off + b);
        if (h < 0 || wt[b] == 0.0)
            continue;
        size_t idx = along ? fixed * c->K + (size_t)h : (size_t)h * c->K + fixed;
        if (c->pairs[side][idx].m > top)
            top = c->pairs[side][idx].m;
    }
    for (int k = 0; k < c->nst; k++)
        memset(ia + (size_t)k * S, 0, top * sizeof *ia);
}

/* A check whose series was kept from an earlier pass (its midpoint and the budget are
   the same; only a neighbour's split changed its stencil) needs the truth samples
   again, not the series: the samples on the grid they converged on, in w->x, the same
   values sf_converge() left there. Returns that grid, or 0 when the series must be
   computed. */
static size_t truth_again(const build_ctx *c, build_ws *w, int side, double mu_s,
                          double mu_f, const pair *pr)
{
    if (!pr->done || pr->N == 0)
        return 0;
    if (pr->done == 2) { /* dark: the samples sf_converge() wrote, all 0 */
        for (int k = 0; k < c->nst; k++)
            memset(w->x + (size_t)k * (c->nmax + 1), 0, ((size_t)pr->N + 1) * sizeof *w->x);
        return pr->N;
    }
    sf_sample_grid(c, w, side, mu_s, mu_f, pr->N, c->nmax + 1, 1, 0, w->x);
    return pr->N;
}

/* The truth at (mu_s, mu_f) in w->x on a grid of N fits series of up to N + 1 terms;
   when the interpolated stencil is longer (its nodes' series converged on finer grids
   than this pair's), the samples are taken again on the grid that fits it, so that
   l1_gap sees all of it. Returns the grid. */
static size_t truth_for(const build_ctx *c, build_ws *w, int side, double mu_s, double mu_f,
                        size_t N, size_t mlen)
{
    if (mlen <= N + 1 || N >= c->nmax)
        return N;
    size_t N2 = N;
    while (N2 + 1 < mlen && N2 < c->nmax)
        N2 *= 2;
    sf_sample_grid(c, w, side, mu_s, mu_f, N2, c->nmax + 1, 1, 0, w->x);
    return N2;
}

/* L1 over the circle, per stored channel relative to norm, of (interpolated series
   in w->ia, length mlen) minus the truth sampled in w->x on the grid of N. */
static double l1_gap(build_ctx *c, build_ws *w, size_t N, size_t mlen, const double *norm)
{
    size_t S = c->nmax + 1;
    double worst = 0.0;
    if (mlen > N + 1)
        mlen = N + 1; /* higher harmonics alias on this grid; the truth converged on it */
    for (int k = 0; k < c->nst; k++) {
        double l1 = sf_series_l1(&w->fb, w->ia + k * S, mlen, N, w->x + k * S, w->y);
        if (l1 < 0.0)
            return HUGE_VAL;
        l1 /= norm[k]; /* norm >= T_FLOOR */
        if (l1 > worst)
            worst = l1;
    }
    return worst;
}

/* Column check for one (side, slow row r): truth at every interval midpoint of the
   fast axis against the spline across the columns. */
void sf_job_colcheck(void *vctx, void *vws, size_t idx)
{
    build_ctx *c = vctx;
    build_ws *w = vws;
    int side = (int)(idx / c->K);
    size_t r = idx % c->K;
    if (!c->want[side])
        return;
    size_t S = c->nmax + 1;
    size_t nfull = 2 * c->K + 2;
    double norm[3];
    for (size_t j = 0; j < c->nint; j++) {
        if (c->okc[side][r * c->nint + j])
            continue; /* same row, same stencil, same budget as last pass */
        double x = c->mid[j];
        size_t N = truth_again(c, w, side, c->P[r], x, &c->pcol[side][r * c->K + j]);
        if (N == 0) {
            sf_pair_norm(c, side, c->Tn[r][side], c->Tm[j][side], norm);
            N = sf_converge(c, w, side, c->P[r], x, norm, share_alias(c));
            if (N == 0 || sf_keep_series(c, w, side, N, norm, &c->pcol[side][r * c->K + j]))
                goto oom;
        }
        long off;
        double wt[4];
        size_t mlen = 0;
        /* the positive-half stencil; the negative half is its mirror image */
        if (cr_weights(c->full, nfull, x, &off, wt)) {
            zero_stencil(c, w->ia, S, side, r, off, wt, 1);
            for (int b = 0; b < 4; b++) {
                long h = half_pos(c, off + b);
                if (h >= 0 && wt[b] != 0.0)
                    add_pair(c, side, r, (size_t)h, wt[b], w->ia, S, &mlen);
            }
        }
        N = truth_for(c, w, side, c->P[r], x, N, mlen);
        /* relative to the DIRECT norm; the ADJOINT reading rescales (sf_adj_ratio) */
        c->errc[side][r * c->nint + j] = l1_gap(c, w, N, mlen, c->Tn[r][side]);
    }
    return;
oom:
    pthread_mutex_lock(&c->lock);
    c->oom = 1;
    pthread_mutex_unlock(&c->lock);
}

/* Row check for one (side, interval j): truth at the slow midpoint against the
   spline across the rows, integrated over the fast nodes (trapezoid weights). */
void sf_job_rowcheck(void *vctx, void *vws, size_t idx)
{
    build_ctx *c = vctx;
    build_ws *w = vws;
    int side = (int)(idx / c->nint);
    size_t j = idx % c->nint;
    if (!c->want[side])
        return;
    size_t S = c->nmax + 1;
    size_t nfull = 2 * c->K + 2;
    double x = c->mid[j];
    double norm[3];
    long off = 0; /* read only when ok; the 0 quiets a maybe-uninitialized warning */
    double wt[4];
    int ok = cr_weights(c->full, nfull, x, &off, wt);
    double total = 0.0;
    for (size_t col = 0; col < c->K; col++) {
        double lo = col == 0 ? 0.0 : c->P[col - 1];
        double hi = col + 1 < c->K ? c->P[col + 1] : c->P[col];
        double *gap = &c->gapr[side][j * c->K + col];
        if (c->okr[side][j * c->K + col]) {
            total += 0.5 * (hi - lo) * *gap;
            continue;
        }
        size_t N = truth_again(c, w, side, x, c->P[col], &c->prow[side][j * c->K + col]);
        if (N == 0) {
            sf_pair_norm(c, side, c->Tm[j][side], c->Tn[col][side], norm);
            N = sf_converge(c, w, side, x, c->P[col], norm, share_alias(c));
            if (N == 0 || sf_keep_series(c, w, side, N, norm, &c->prow[side][j * c->K + col]))
                goto oom;
        }
        size_t mlen = 0;
        if (ok) {
            zero_stencil(c, w->ia, S, side, col, off, wt, 0);
            for (int a = 0; a < 4; a++) {
                long h = half_pos(c, off + a);
                if (h >= 0 && wt[a] != 0.0)
                    add_pair(c, side, (size_t)h, col, wt[a], w->ia, S, &mlen);
            }
        }
        N = truth_for(c, w, side, x, c->P[col], N, mlen);
        *gap = l1_gap(c, w, N, mlen, c->Tm[j][side]); /* DIRECT norm, as errc */
        total += 0.5 * (hi - lo) * *gap;
    }
    c->errr[side][j] = total;
    return;
oom:
    pthread_mutex_lock(&c->lock);
    c->oom = 1;
    pthread_mutex_unlock(&c->lock);
}

/* The norms of one block at cosine mu (a node or a midpoint), in the stored values'
   units, per stored channel:
   out[0..2], DIRECT (the slow index is the light's): max(T, floor) for the light at
     mu (max(R, floor) for a reflection block), times the block's fold factor, so
     that an error relative to it is the unfolded error;
   out[4..6], ADJOINT (the fast index is the light's, pbrt-v3's radiance mode, what a
     path tracer's camera rays read): the error of light at mu, integrated over the
     camera's slow index, is (e^2/mu) times the integral of |error of the stored value|
     cos(camera), with e^2 the radiance factor (1/eta^2 for T_ENTER, whose light comes
     from below, eta^2 for T_LEAVE, 1 for reflection) and normalised by max(T', floor)
     of that light (T' of the other side's index; R of the same block for
     reflection). So one pair's series may err by max(T', floor) mu / e^2 in the
     stored units; cos(camera) <= 1 leaves a factor 2 of margin. */
/* The norms only set the shares the node checks allow (what decides is the file's own
   measurement, with T and R converged to about 3e-7), so T and R come from a coarser
   rule: 8 x 3 panels differ from the converged ones by at most 6.9e-4 of max(T, 0.01)
   (n = 1/2.4, s = 20, past the critical angle) and 1.9e-5 of max(R, 0.01), over n in
   {1.5, 1.33, 2.4, 1.1, 1.0001} and their inverses, s in {0.5, 1, 3, 10, 20, 100,
   1000}, ti in 0.5-degree steps, for a quarter of T's cost and an eighth of R's. */
#define NORM_U_PANELS 8
#define NORM_PSI_PANELS 3

static void norms_at(const build_ctx *c, int side, double mu, double *out)
{
    btdf_params q = *c->p;
    if (q.model == BTDF_MODEL_FULL) /* its single scattering; the tally's energy below */
        q.model = BTDF_MODEL_SMITH;
    for (int k = 0; k < c->nc; k++)
        q.ior[k] = c->ior[side][k];
    double T[3] = {0, 0, 0};
    /* acos of a value in [0, 1] is in [0, pi/2], the accepted range */
    double ti = acos(fmin(1.0, fmax(0.0, mu)));
    bt_albedo_panels(&q, blk_refl[side], ti, NORM_U_PANELS, NORM_PSI_PANELS, T);
    for (int k = 0; c->ms[side][0] && k < c->nc; k++) /* full: orders 2+ as tallied */
        T[k] += full_ms_energy(c->ms[side][k], blk_refl[side], ti, NULL);
    if (c->nst == 1) {
        out[0] = fmax(T[0], T_FLOOR);
    } else {
        const double *fo = c->fold[side];
        out[0] = fmax(LUM_R * T[0] * fo[0] + LUM_G * T[1] * fo[1] + LUM_B * T[2] * fo[2],
                      T_FLOOR);
        out[1] = fmax(T[0], T_FLOOR) * fo[0];
        out[2] = fmax(T[2], T_FLOOR) * fo[2];
    }
    /* the adjoint light's index: the other transmission block's, or this block's */
    double e2 = 1.0, eta = c->p->ior[c->nc == 3 ? 1 : 0]; /* the header's eta */
    if (!blk_refl[side]) {
        int other = side == BLK_T_ENTER ? BLK_T_LEAVE : BLK_T_ENTER;
        for (int k = 0; k < c->nc; k++)
            q.ior[k] = c->ior[other][k];
        bt_albedo_panels(&q, 0, ti, NORM_U_PANELS, NORM_PSI_PANELS, T);
        for (int k = 0; c->ms[other][0] && k < c->nc; k++)
            T[k] += full_ms_energy(c->ms[other][k], 0, ti, NULL);
        e2 = side == BLK_T_ENTER ? 1.0 / (eta * eta) : eta * eta; /* eta > 0 (checked) */
    }
    /* mu >= the first node or midpoint > 0; the floor keeps the norm positive should
       a node ever sit on the grazing cosine 0 */
    double w = fmax(mu, 1e-9) / e2;
    if (c->nst == 1) {
        out[4] = fmax(T[0], T_FLOOR) * w;
    } else {
        out[4] = fmax(LUM_R * T[0] + LUM_G * T[1] + LUM_B * T[2], T_FLOOR) * w;
        out[5] = fmax(T[0], T_FLOOR) * w;
        out[6] = fmax(T[2], T_FLOOR) * w;
    }
}

/* Job k of K * NBLK * 2: the norms of node or midpoint k / (2 NBLK) for one block,
   unless carried from the last pass. */
void sf_job_norms(void *vctx, size_t k)
{
    build_ctx *c = vctx;
    size_t j = k / (2 * NBLK);
    int s = (int)(k / 2 % NBLK), at_mid = (int)(k % 2);
    if (!c->want[s])
        return;
    if (at_mid && !c->hasTm[j])
        norms_at(c, s, c->mid[j], c->Tm[j][s]);
    else if (!at_mid && !c->hasTn[j])
        norms_at(c, s, c->P[j], c->Tn[j][s]);
}

/* The norm of the series at (slow node with norms ns, fast node with norms nf): it
   must serve both readings, DIRECT (relative to the slow node's light) and ADJOINT
   (relative to the fast node's light), so the smaller of the two. A three-channel
   transmission block is read ADJOINT only: its fold makes the DIRECT reading off by
   (n_c/n_G)^2 by design (build_impl). */
void sf_pair_norm(const build_ctx *c, int side, const double *ns, const double *nf,
                      double *out)
{
    for (int k = 0; k < c->nst; k++)
        out[k] = c->nst == 3 && !blk_refl[side] ? nf[4 + k] : fmin(ns[k], nf[4 + k]);
}

/* A gap measured relative to the slow node's DIRECT norms ns, times this, bounds it
   relative to the fast node's ADJOINT norms nf (the worst channel of each). */
double sf_adj_ratio(const build_ctx *c, const double *ns, const double *nf)
{
    double r = 0.0;
    for (int k = 0; k < c->nst; k++)
        r = fmax(r, ns[k] / nf[4 + k]); /* norms > 0 (norms_at) */
    return r;
}
