/* SPDX-License-Identifier: MIT */
/* build.c: the entry points of the SCATFUN builder, their argument and lobe checks, and
   the refinement loop: series and checks, splits, the file's own measurement. */
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

/* Where interval j of the half nodes is checked and split: the midpoint in angle.
   The last interval [P[K-2], 1] is cut at a fraction endr of its angle instead: rho
   moves with sin ti, which is sqrt(1 - mu) near mu = 1, so the spline error there
   only falls like the interval's angle and bisection would need many passes. */
static double split_point(const double *P, size_t K, size_t j, double endr)
{
    double lo = j == 0 ? 0.0 : P[j - 1];
    /* acos of values in [0, 1] */
    double alo = acos(fmin(1.0, lo)), ahi = acos(fmin(1.0, P[j]));
    if (j == K - 1 && K > 1)
        return cos(ahi + (alo - ahi) * endr);
    return cos(0.5 * (alo + ahi));
}


/* Error estimate of one side with a fixed sample (for the build's own loop): the
   file's own evaluation, QUICK_PPA facet points per angle, a seed of the builder's. Test
   angles whose e_L1 exceeds mark_at get their elevation interval marked in split
   (half nodes P[0..K-1]; both sides share them); *nmark counts new marks. */
static double quick_l1(const btdf_scatfun *f, const btdf_params *p, btdf_side side, int threads,
                       uint64_t seed, albedo_memo *memo, const double *P, size_t K,
                       double mark_at, double accept_at, unsigned char *split,
                       size_t *nmark)
{
    btdf_report r;
    memset(&r, 0, sizeof r);
    /* btdf_scatfun_report's work, with T and R remembered from the last measurement;
       e_L1 is all the build reads, and once the first angles fail the acceptance
       (stop_above) their marks are what the build needs: the refinement rounds, which
       look for a larger worst, are left to the next measurement. stop_above is 0 for
       the last measurement (split NULL), which must be whole. */
    est_opts opt = {1, 1, split ? accept_at : 0.0, split ? QUICK_SCREEN_PPA : 0,
                    split ? QUICK_SCREEN_NUNI : 0, SCREEN_SHARE * accept_at, NULL};
    if (sf_report_mis(f, p, side, 24, QUICK_PPA, seed, threads, &opt, memo, &r) !=
        BTDF_OK) {
        free(r.per_ti);
        return HUGE_VAL;
    }
    for (size_t k = 0; split && k < r.test_angles; k++) {
        double mu = cos(r.per_ti[k].ti);
        size_t j = 0; /* interval j is (P[j-1], P[j]], P[-1] = 0 */
        while (j + 1 < K && P[j] < mu)
            j++;
        if (!(r.per_ti[k].e_l1 > mark_at))
            continue;
        if (!split[j]) {
            split[j] = 1;
            ++*nmark;
        }
    }
    free(r.per_ti);
    return r.e_l1_max;
}

/* Bytes the builder holds in series (pairs and check series, double precision) and
   pair records, for the memory cap. */
static size_t state_bytes(const build_ctx *c)
{
    size_t KK = c->K * c->K, b = 0;
    for (int s = 0; s < NBLK; s++) {
        if (!c->want[s])
            continue;
        const pair *arr[3] = {c->pairs[s], c->pcol[s], c->prow[s]};
        for (int a = 0; a < 3; a++) {
            if (!arr[a])
                continue;
            b += KK * sizeof(pair);
            for (size_t i = 0; i < KK; i++)
                b += (size_t)arr[a][i].m * (size_t)c->nst * sizeof(double);
        }
    }
    return b;
}

/* The bytes a kept file holds (its coefficients, cdf and offsets), for the memory cap. */
static size_t snap_bytes(const btdf_scatfun *f)
{
    return f ? (size_t)f->ncoeffs * sizeof(float) + (size_t)f->n * f->n * 12u : 0;
}

BTDF_API btdf_status btdf_scatfun_build(const btdf_params *p, double tolerance,
                                        btdf_side side, int threads, btdf_scatfun **out,
                                        char *msg, size_t msglen)
{
    return btdf_scatfun_build_limits(p, tolerance, side, threads, 0, 0, out, msg, msglen);
}

BTDF_API btdf_status btdf_scatfun_check(const btdf_params *p, double tolerance,
                                        btdf_side side, char *msg, size_t msglen)
{
    btdf_status st = sf_check_params(p, msg, msglen);
    if (st != BTDF_OK)
        return st;
    if (!(tolerance >= 1e-6 && tolerance <= 0.5))
        return core_say(BTDF_EINVAL, msg, msglen, "tolerance %s: must lie in [1e-6, 0.5]",
                        core_num(tolerance, (char[32]){0}));
    if (p->model == BTDF_MODEL_FULL && p->channels == 3)
        /* a three-channel transmission block is right on the ADJOINT path only (its
           pbrt-v3 fold), which reads the reverse path's tally (report.c) */
        return core_say(BTDF_ENOTSUP, msg, msglen,
                        "model full: a .bsdf of one index only (three channels' "
                        "transmission is read along the reverse path, whose tally is "
                        "another); xu-sun and smith take three");
    if ((int)side < 1 || (int)side > BTDF_SCATFUN_ALL)
        return core_say(BTDF_EINVAL, msg, msglen,
                           "blocks %d: must be a mask of 1 (transmission entering), 2 "
                           "(transmission leaving), 4 (reflection on top), 8 (reflection "
                           "below), from 1 to 15", (int)side);
    return BTDF_OK;
}

static btdf_status build_impl(const btdf_params *p, double tolerance, btdf_side side,
                              int threads, size_t max_coeffs, size_t max_bytes,
                              btdf_progress_fn progress, void *user, btdf_scatfun **out,
                              char *msg, size_t msglen);

BTDF_API btdf_status btdf_scatfun_build_limits(const btdf_params *p, double tolerance,
                                               btdf_side side, int threads, size_t max_coeffs,
                                               size_t max_bytes, btdf_scatfun **out,
                                               char *msg, size_t msglen)
{
    return build_impl(p, tolerance, side, threads, max_coeffs, max_bytes, NULL, NULL, out, msg,
                      msglen);
}

BTDF_API btdf_status btdf_scatfun_build_progress(const btdf_params *p, double tolerance,
                                                 btdf_side side, int threads, size_t max_coeffs,
                                                 size_t max_bytes, btdf_progress_fn progress,
                                                 void *user, btdf_scatfun **out, char *msg,
                                                 size_t msglen)
{
    return build_impl(p, tolerance, side, threads, max_coeffs, max_bytes, progress, user, out,
                      msg, msglen);
}

/* The arguments checked, *max_coeffs set (0: the builder's own cap), and what the
   request needs at least (btdf_scatfun_predict), before any work: a request that
   cannot fit the format's node budget or the caller's budgets is refused with the
   numbers. */
static btdf_status build_fits(const btdf_params *p, double tolerance, btdf_side side,
                              size_t *max_coeffs_io, size_t max_bytes, char *msg, size_t msglen)
{
    btdf_status st = btdf_scatfun_check(p, tolerance, side, msg, msglen);
    if (st != BTDF_OK)
        return st;
    if (*max_coeffs_io == 0 || *max_coeffs_io > MAX_COEFFS_BUILD)
        *max_coeffs_io = MAX_COEFFS_BUILD;
    size_t max_coeffs = *max_coeffs_io;
    btdf_scatfun_need nd;
    st = btdf_scatfun_predict(p, tolerance, side, &nd, msg, msglen);
    if (st != BTDF_OK)
        return st;
    const char *what = nd.half_nodes > BTDF_SCATFUN_MAX_HALF_NODES ? "node"
                       : nd.coeffs > max_coeffs                    ? "coefficient"
                       : max_bytes && nd.build_bytes > max_bytes   ? "memory"
                                                                   : NULL;
    if (what)
        return core_say(BTDF_EBUDGET, msg, msglen,
                        "%s budget, nothing built: the transmitted lobe is about %.3g deg wide "
                        "(n = %.9g, s = %g) and needs nodes %.3g deg apart to meet %g: at "
                        "least %zu half nodes (budget %d), %zu coefficients (budget %zu), "
                        "%.3g MB of file and %.3g MB to build%s; a facet-space table "
                        "(.exr/.csv) holds this material",
                        what, nd.lobe_deg, p->ior[p->channels == 3 ? 1 : 0],
                        p->smoothness, nd.spacing_deg, tolerance, nd.half_nodes,
                        BTDF_SCATFUN_MAX_HALF_NODES, nd.coeffs, max_coeffs,
                        1e-6 * (double)nd.file_bytes, 1e-6 * (double)nd.build_bytes,
                        max_bytes ? " (the budget given)" : "");
    return BTDF_OK;
}

/* The context's fixed part: the material, the blocks asked, each block's index and
   pbrt-v3 fold factors, the azimuth grid bounds and the first error budget. */
static void build_ctx_setup(build_ctx *c, const btdf_params *p, btdf_side side, double tolerance)
{
    c->p = p;
    c->nc = p->channels;
    c->nst = p->channels == 3 ? 3 : 1;
    for (int k = 0; k < c->nc; k++) {
        c->ior[BLK_T_ENTER][k] = c->ior[BLK_R_TOP][k] = p->ior[k];
        /* ior >= BTDF_IOR_MIN > 0 (checked) */
        c->ior[BLK_T_LEAVE][k] = c->ior[BLK_R_BOTTOM][k] = 1.0 / p->ior[k];
    }
    for (int b = 0; b < NBLK; b++) {
        c->want[b] = ((int)side & blk_mask[b]) != 0;
        for (int k = 0; k < 3; k++)
            c->fold[b][k] = 1.0;
    }
    if (c->nc == 3) {
        /* pbrt-v3 scales transmission by e^2 with the header's one eta = n_G: reading
           T_LEAVE for light from above gives n_G^2 rho_c(1/n_c; o->i), and the truth is
           n_c^2 rho_c(1/n_c; o->i) (reciprocity), so that block carries (n_c/n_G)^2;
           T_ENTER read for light from below gives rho_c(n_c; o->i)/n_G^2 against
           rho_c(n_c; o->i)/n_c^2, so it carries (n_G/n_c)^2. Reflection has no factor. */
        for (int k = 0; k < 3; k++) {
            double q = p->ior[k] / p->ior[1]; /* ior > 0 (checked) */
            c->fold[BLK_T_LEAVE][k] = q * q;
            c->fold[BLK_T_ENTER][k] = 1.0 / (q * q);
        }
    }
    /* The lobe spans about 2/s rad of facet tilt; a first azimuth grid of about 8 s
       points puts several samples across it, so no lobe falls between samples. The
       narrowest pairs need that; a transmission pair starts on the grid its own lobe
       and edges need (sf_first_grid), at most this. */
    c->nmin = pow2_at_least(fmax(NMIN_PHI, 8.0 * p->smoothness));
    if (c->nmin > BTDF_SCATFUN_MAX_PHI / 2)
        c->nmin = BTDF_SCATFUN_MAX_PHI / 2;
    c->nmax = BTDF_SCATFUN_MAX_PHI;
    c->budget = tolerance;
}

/* The first half nodes into P; returns their count. Initial half nodes: mu = sin of
   equal angle steps, denser towards grazing. */
static size_t first_nodes(double *P)
{
    size_t K0 = 8;
    for (size_t j = 0; j < K0; j++)
        P[j] = to_float_node(sin((double)(j + 1) * M_PI / (2.0 * (double)K0)));
    /* Towards the pole, nodes at angles doubling from the pole node's: an azimuthal
       harmonic m of rho moves like sin^m ti, a square-root cusp in mu = cos ti at the
       pole for m = 1, which a spline in mu follows only on intervals whose angles
       shrink geometrically towards it (n = 1.47, s = 28 at 1e-3 with even splits:
       e_L1 0.03 at ti = 0.1 deg between nodes at 0.02 and 0.19 deg, not met). */
    size_t K = K0 - 1;
    {
        double apole = acos(POLE_NODE), alast = acos(P[K0 - 2]);
        double a[32];
        size_t na = 0;
        for (double t = 2.0 * apole; t < 0.5 * alast && na < 32; t *= 2.0)
            a[na++] = t;
        while (na > 0)
            P[K++] = to_float_node(cos(a[--na]));
    }
    P[K++] = POLE_NODE;
    return K;
}

/* One pass on the half nodes P[0..K): the norms, the pair series and the interval
   checks; *total their coefficients. BTDF_EBUDGET with *limit (and *over_need for the
   coefficients) when the state passes a budget, BTDF_ENOMEM, or BTDF_OK. */
static btdf_status pass_series(build_ctx *c, const double *P, size_t K, int threads,
                               size_t max_coeffs, size_t max_bytes, const btdf_scatfun *snap,
                               size_t *total, size_t *over_need, const char **limit)
{
    if (sf_set_nodes(c, P, K))
        return BTDF_ENOMEM;
    c->nint = K;
    if (sf_ensure_state(c))
        return BTDF_ENOMEM;
    for (size_t j = 0; j < K; j++)
        /* checked where a split would put the node, so check series become pairs */
        c->mid[j] = to_float_node(split_point(P, K, j, 0.5));
    /* the norms of new nodes and midpoints (each its own job: same values on any
       number of threads) */
    core_parallel_for(threads, K * NBLK * 2, sf_job_norms, c);
    for (size_t j = 0; j < K; j++)
        c->hasTn[j] = c->hasTm[j] = 1;
    if (core_parallel_for_ws(threads, NBLK * K, sf_job_row, c, sf_build_ws_new, sf_build_ws_free) || c->oom)
        return BTDF_ENOMEM;
    size_t n = 0;
    for (int s = 0; s < NBLK; s++)
        for (size_t i = 0; c->want[s] && i < K * K; i++)
            n += c->pairs[s][i].m * (size_t)c->nst;
    *total = n;
    if (n > max_coeffs) {
        *over_need = n;
        *limit = "coefficient";
        return BTDF_EBUDGET;
    }
    if (max_bytes && state_bytes(c) + snap_bytes(snap) > max_bytes) {
        *limit = "memory";
        return BTDF_EBUDGET;
    }
    if (core_parallel_for_ws(threads, NBLK * K, sf_job_colcheck, c, sf_build_ws_new, sf_build_ws_free) ||
        core_parallel_for_ws(threads, NBLK * K, sf_job_rowcheck, c, sf_build_ws_new, sf_build_ws_free) ||
        c->oom)
        return BTDF_ENOMEM;
    if (max_bytes && state_bytes(c) + snap_bytes(snap) > max_bytes) {
        *limit = "memory";
        return BTDF_EBUDGET;
    }
    return BTDF_OK;
}

/* Marks in split the intervals whose checks fail their share, and lowers *endr, the
   cut of the last interval, where its error needs a finer one; -1 when out of memory. */
static int mark_splits(const build_ctx *c, const double *P, size_t K, unsigned char *split,
                       double *endr)
{
    /* The checks bound both readings of every block (norms_at): DIRECT, the light
       in the slow index, integrates the error over the fast one; ADJOINT, the light
       in the fast index, over the slow one. One interval check serves both with the
       axes swapped: the fast-midpoint gaps (errc) summed along a row are the DIRECT
       error there, summed down a column of rows the ADJOINT error of the light at
       that midpoint; the slow-midpoint gaps (gapr) the other way round. A
       three-channel transmission block is read ADJOINT only (sf_pair_norm). */
    double *ea = calloc(K, sizeof *ea);
    if (!ea)
        return -1;
    int rowbad = 0; /* once a row fails, also split the ones close to failing */
    for (int s = 0; s < NBLK; s++) {
        if (!c->want[s])
            continue;
        int direct = !(c->nst == 3 && !blk_refl[s]);
        for (size_t j = 0; direct && j < K; j++)
            rowbad |= c->errr[s][j] > share_row(c);
    }
    for (int s = 0; s < NBLK; s++) {
        if (!c->want[s])
            continue;
        int direct = !(c->nst == 3 && !blk_refl[s]);
        for (size_t r = 0; direct && r < K; r++) {
            double sum = 0.0;
            for (size_t j = 0; j < K; j++) {
                double wid = P[j] - (j == 0 ? 0.0 : P[j - 1]);
                sum += wid * c->errc[s][r * K + j];
            }
            if (sum <= share_col(c))
                continue;
            for (size_t j = 0; j < K; j++) {
                double wid = P[j] - (j == 0 ? 0.0 : P[j - 1]);
                if (wid * c->errc[s][r * K + j] > share_col(c) / (double)K)
                    split[j] = 1;
            }
        }
        for (size_t j = 0; direct && j < K; j++)
            if (c->errr[s][j] > share_row(c) && j == K - 1)
                /* error ~ the last interval's angle: aim at half the share */
                *endr = fmin(*endr, fmax(1.0 / 64.0, 0.5 * share_row(c) / c->errr[s][j]));
        for (size_t j = 0; direct && j < K; j++)
            if (c->errr[s][j] > (rowbad ? 0.7 : 1.0) * share_row(c))
                split[j] = 1;
        /* ADJOINT, light at fast node col: the slow-midpoint gaps down the column */
        for (size_t col = 0; col < K; col++) {
            double sum = 0.0;
            for (size_t j = 0; j < K; j++) {
                double wid = P[j] - (j == 0 ? 0.0 : P[j - 1]);
                /* the camera's cosine, the slow midpoint's: the ADJOINT integral's
                   weight (norms_at) */
                ea[j] = wid * c->mid[j] * c->gapr[s][j * K + col] *
                        sf_adj_ratio(c, c->Tm[j][s], c->Tn[col][s]);
                sum += ea[j];
            }
            if (sum <= share_col(c))
                continue;
            for (size_t j = 0; j < K; j++)
                if (ea[j] > share_col(c) / (double)K)
                    split[j] = 1;
        }
        /* ADJOINT, light at fast midpoint j: the fast-midpoint gaps over the rows */
        for (size_t j = 0; j < K; j++) {
            double tot = 0.0;
            for (size_t r = 0; r < K; r++) {
                double lo = r == 0 ? 0.0 : P[r - 1], hi = r + 1 < K ? P[r + 1] : P[r];
                tot += 0.5 * (hi - lo) * P[r] * c->errc[s][r * K + j] *
                       sf_adj_ratio(c, c->Tn[r][s], c->Tm[j][s]);
            }
            if (tot > share_row(c)) {
                split[j] = 1;
                if (j == K - 1)
                    *endr = fmin(*endr, fmax(1.0 / 64.0, 0.5 * share_row(c) / tot));
            }
        }
    }
    free(ea);
    return 0;
}

/* The fronts: split marks spread beside the intervals just split (ahead is scratch of
   K bytes); returns the intervals to split. */
static size_t spread_fronts(unsigned char *split, const unsigned char *fresh,
                            unsigned char *ahead, size_t K)
{
    /* Fronts. A new node is also a new row and column of pairs, and the checks sum
       over rows and columns: an interval next to a freshly split one can fail only
       because the new rows now see it (measured for n = 1.5, s = 3 at 1e-3: the
       failing interval moved one step outwards per pass, its check at 3.1, 2.6,
       2.2, 1.7, 1.3 times the share, six passes). When an interval that was not
       just split fails beside one that was, split the next one outwards too: the
       front moves two intervals per pass. */
    for (size_t j = 0; j < K; j++)
        ahead[j] = 0;
    for (size_t j = 0; j < K; j++) {
        if (!split[j] || fresh[j])
            continue;
        if (j > 0 && fresh[j - 1] && j + 1 < K && !fresh[j + 1])
            ahead[j + 1] = 1;
        if (j + 1 < K && fresh[j + 1] && j > 0 && !fresh[j - 1])
            ahead[j - 1] = 1;
    }
    for (size_t j = 0; j < K; j++)
        split[j] |= ahead[j];
    size_t nsplit = 0;
    for (size_t j = 0; j < K; j++)
        nsplit += split[j];
    return nsplit;
}

/* Inserts the split points of the marked intervals into the K = *Kp half nodes P
   (frees split), marks fresh the intervals they make and carries the series over:
   BTDF_OK, BTDF_EBUDGET when float spacing leaves nothing to split, or BTDF_ENOMEM. */
static btdf_status insert_splits(build_ctx *c, double *P, size_t *Kp, unsigned char *split,
                                 unsigned char *fresh, double endr, int threads)
{
    /* insert split points (rounded to float, strictly inside their interval) */
    size_t K = *Kp, KQ = 0;
    double *Q = P + BTDF_SCATFUN_MAX_HALF_NODES;
    unsigned char *ins = calloc(K, 1);
    if (!ins) {
        free(split);
        return BTDF_ENOMEM;
    }
    if (endr > 0.5)
        endr = 0.5;
    for (size_t j = 0; j < K; j++) {
        double lo = j == 0 ? 0.0 : P[j - 1];
        double m = to_float_node(split_point(P, K, j, endr));
        if (split[j] && m > lo && m < P[j]) {
            fresh[KQ] = 1;
            Q[KQ++] = m;
            ins[j] = m == c->mid[j] ? 1 : 2;
            fresh[KQ] = 1;
        } else {
            fresh[KQ] = 0;
        }
        Q[KQ++] = P[j];
    }
    free(split);
    if (KQ == K) {
        free(ins);
        return BTDF_EBUDGET; /* float spacing reached: nothing left to split */
    }
    if (sf_carry_over(c, Q, KQ, ins, threads)) {
        free(ins);
        return BTDF_ENOMEM;
    }
    free(ins);
    memcpy(P, Q, KQ * sizeof *P);
    *Kp = KQ;
    return BTDF_OK;
}

/* e_L1 of the file f over the blocks built (quick_l1 per block, the largest): with
   split, the measurement that marks the test angles above mark_at. */
static double file_l1(const build_ctx *c, const btdf_scatfun *f, int threads, uint64_t seed,
                      albedo_memo *memo, const double *P, size_t K, double mark_at,
                      double accept_at, unsigned char *split, size_t *nmark)
{
    double e = 0.0;
    for (int s = 0; s < NBLK; s++)
        if (c->want[s])
            e = fmax(e, quick_l1(f, c->p, (btdf_side)blk_mask[s], threads, seed, memo, P, K,
                                 mark_at, accept_at, split, nmark));
    return e;
}

/* The node checks pass: the state's file, measured (*e), marking in split the
   intervals of the test angles that miss (*nmark of them); kept as *best when it meets
   the acceptance and beats *best_err, else as *snap. */
static btdf_status measure_state(build_ctx *c, double tolerance, int threads, uint64_t seed,
                                 albedo_memo *memo, const double *P, size_t K,
                                 unsigned char *split, size_t *nmark, double *e,
                                 btdf_scatfun **best, double *best_err, btdf_scatfun **snap,
                                 char *msg, size_t msglen)
{
    btdf_scatfun *f = NULL;
    btdf_status st = sf_assemble(c, &f, msg, msglen);
    if (st != BTDF_OK)
        return st;
    *e = file_l1(c, f, threads, seed, memo, P, K, MARK_SHARE * tolerance,
                 ACCEPT_SHARE * tolerance, split, nmark);
    /* A failing measurement may have skipped its refinement (stop_above): its
       e is a lower bound, so such a file is not kept as the best; should the
       budget run out, the last file is measured whole below. */
    if (*e < *best_err && *e <= ACCEPT_SHARE * tolerance) {
        btdf_scatfun_free(*best);
        *best = f;
        *best_err = *e;
    } else {
        btdf_scatfun_free(*snap); /* within the budgets (checked above) */
        *snap = f;
    }
    return BTDF_OK;
}

/* The budget splitting nsplit of K intervals would pass, or NULL: the node budget, or
   one that the growth alone passes, as the next pass holds (K + nsplit)^2 pairs, each
   new row and column with series like its neighbours'. */
static const char *growth_limit(const build_ctx *c, size_t K, size_t nsplit, size_t total,
                                size_t max_coeffs, size_t max_bytes)
{
    if (K + nsplit > BTDF_SCATFUN_MAX_HALF_NODES)
        return "node";
    double g = (double)(K + nsplit) * (double)(K + nsplit) / ((double)K * (double)K);
    if (g * (double)total > (double)max_coeffs ||
        (max_bytes && g * (double)state_bytes(c) > (double)max_bytes))
        return g * (double)total > (double)max_coeffs ? "coefficient" : "memory";
    return NULL;
}

/* The finest file reached, measured whole, as *best when there is none or it is better:
   after a budget, the last file within them (*snap, taken); else the state's own. */
static void keep_finest(build_ctx *c, int threads, uint64_t seed, albedo_memo *memo, int over,
                        btdf_scatfun **snap, btdf_scatfun **best, double *best_err, char *msg,
                        size_t msglen)
{
    btdf_scatfun *f = NULL;
    btdf_status a = BTDF_OK;
    if (over) { /* the state passed a budget: the last file within them */
        f = *snap;
        *snap = NULL;
    } else if (c->pairs[0] || c->pairs[1] || c->pairs[2] || c->pairs[3]) {
        a = sf_assemble(c, &f, msg, msglen);
    }
    if (f) {
        if (a == BTDF_OK) {
            double e = file_l1(c, f, threads, seed, memo, NULL, 0, 0.0, 0.0, NULL, NULL);
            if (e < *best_err || !*best) {
                btdf_scatfun_free(*best);
                *best = f;
                *best_err = e;
            } else {
                btdf_scatfun_free(f);
            }
        }
    }
}

/* The builder's working memory and its lock. */
static void free_work(build_ctx *c, double *P, unsigned char *fresh, unsigned char *ahead)
{
    sf_free_state(c);
    sf_free_tallies(c->own); /* the files hold their own copies (sf_assemble) */
    free(c->P);
    free(c->full);
    free(P);
    free(fresh);
    free(ahead);
    pthread_mutex_destroy(&c->lock);
}

/* Even the first pass passed a budget: nothing built. */
static btdf_status first_pass_over(size_t K, size_t over_need, size_t max_coeffs,
                                   size_t max_bytes, char *msg, size_t msglen)
{
    if (over_need)
        return core_say(BTDF_EBUDGET, msg, msglen,
                        "coefficient budget, nothing built: the first pass (%zu half "
                        "nodes) already holds %zu coefficients, more than %zu",
                        K, over_need, max_coeffs);
    return core_say(BTDF_EBUDGET, msg, msglen,
                    "memory budget, nothing built: the first pass (%zu half nodes) "
                    "already needs more than %zu bytes", K, max_bytes);
}

/* The intervals to split (*split, K bytes, *nsplit of them set: mark_splits and the
   fronts) and the last interval's cut *endr; -1 when out of memory. */
static int plan_splits(const build_ctx *c, const double *P, size_t K,
                       const unsigned char *fresh, unsigned char *ahead,
                       unsigned char **split, size_t *nsplit, double *endr)
{
    *split = calloc(K, 1);
    if (!*split)
        return -1;
    if (mark_splits(c, P, K, *split, endr)) {
        free(*split);
        *split = NULL;
        return -1;
    }
    *nsplit = spread_fronts(*split, fresh, ahead, K);
    /* no interval below the grazing floor is split (scatfun.h, SF_TI_TOP): nodes
       ascend, so those are the first ones */
    for (size_t j = 0; j < K && P[j] <= SF_MU_FLOOR; j++)
        if ((*split)[j]) {
            (*split)[j] = 0;
            --*nsplit;
        }
    return 0;
}

/* The answer: best stamped with its tolerance and build time (since t0), the measured
   T and R handed over, into *out; st BTDF_EBUDGET says which budget stopped it. */
static btdf_status hand_over(btdf_scatfun *best, albedo_memo *memo, double tolerance,
                             double t0, btdf_status st, const char *limit, double best_err,
                             btdf_scatfun **out, char *msg, size_t msglen)
{
    best->tolerance = tolerance;
    best->seconds_build = core_now() - t0;
    if (memo) { /* the file's reports test the same knot midpoints: hand over T and R */
        albedo_memo_free(best->memo);
        best->memo = memo;
    }
    *out = best;
    if (st == BTDF_EBUDGET)
        return core_say(BTDF_EBUDGET, msg, msglen,
                   "%s budget reached (%u nodes, %u coefficients, mMax %u); its own "
                   "estimate e_L1 %.3g > tolerance %g",
                   limit, best->n, best->ncoeffs, best->mmax, best_err, tolerance);
    return BTDF_OK;
}

/* The builder: checks (build_fits), context and fold factors (build_ctx_setup), the
   first nodes, then the refinement loop: one pass of series and checks (pass_series),
   split marks and fronts (plan_splits), the file's own measurement that accepts,
   splits locally or tightens (measure_state), the budgets (growth_limit), splits
   inserted (insert_splits); then the best file kept (keep_finest, hand_over). Long:
   the loop's decisions stay here, as they share the counters tighten, local, stall
   and last_err and one cleanup path (model full's tallies, sf_make_tallies, are
   freed on it too). */
static btdf_status build_impl(const btdf_params *p, double tolerance, btdf_side side,
                              int threads, size_t max_coeffs, size_t max_bytes,
                              btdf_progress_fn progress, void *user, btdf_scatfun **out,
                              char *msg, size_t msglen)
{
    if (!out)
        return core_say(BTDF_EINVAL, msg, msglen, "output pointer missing");
    btdf_status st = build_fits(p, tolerance, side, &max_coeffs, max_bytes, msg, msglen);
    if (st != BTDF_OK)
        return st;
    double t0 = core_now();
    build_ctx c;
    memset(&c, 0, sizeof c);
    if (pthread_mutex_init(&c.lock, NULL) != 0)
        return core_say(BTDF_ENOMEM, msg, msglen, "cannot create a mutex");
    build_ctx_setup(&c, p, side, tolerance);
    st = sf_make_tallies(&c, threads, progress, user, msg, msglen);
    if (st != BTDF_OK) {
        pthread_mutex_destroy(&c.lock);
        return st;
    }

    btdf_scatfun *best = NULL;
    double best_err = HUGE_VAL;
    /* The last file assembled within every budget: what a build stopped by a budget
       answers with, never a state that already exceeded one. over: the current state
       exceeded a budget (it is not assembled). */
    btdf_scatfun *snap = NULL;
    int over = 0;
    size_t over_need = 0; /* the coefficients of a state that passed max_coeffs */
    /* T and R of the test angles, kept across the measurements (NULL: computed each time) */
    albedo_memo *memo = albedo_memo_new();
    double *P = malloc(BTDF_SCATFUN_MAX_HALF_NODES * 2 * sizeof *P);
    /* fresh[j]: interval j was made by the last pass's split; ahead: fronts (below) */
    unsigned char *fresh = calloc(BTDF_SCATFUN_MAX_HALF_NODES * 2, 1);
    unsigned char *ahead = calloc(BTDF_SCATFUN_MAX_HALF_NODES, 1);
    if (!P || !fresh || !ahead) {
        st = BTDF_ENOMEM;
        goto done;
    }
    size_t K = first_nodes(P);
    int tighten = 0, local = 0, stall = 0;
    double last_err = HUGE_VAL; /* the previous measurement, for stall */
    const char *limit = "node"; /* which budget stopped refinement */
    for (;;) {
        size_t total = 0;
        st = pass_series(&c, P, K, threads, max_coeffs, max_bytes, snap, &total, &over_need,
                         &limit);
        if (st == BTDF_ENOMEM)
            goto done;
        if (st == BTDF_EBUDGET) {
            over = 1;
            break;
        }
        /* mark intervals to split */
        unsigned char *split = NULL;
        size_t nsplit = 0;
        double endr = 1.0;
        if (plan_splits(&c, P, K, fresh, ahead, &split, &nsplit, &endr)) {
            st = BTDF_ENOMEM;
            goto done;
        }
        if (progress) /* K nodes checked, nsplit intervals to split */
            progress(user, tighten ? "series (tighter)" : "elevation nodes", K, nsplit);
        if (nsplit == 0) {
            /* The node checks pass: measure the file itself. Where it misses, split the
               elevation intervals of the test angles that miss (the checks run at
               interval midpoints only; the report hunts for the worst angles), keeping
               every series; only when that finds nothing to split, halve the shares
               and recompute everything. */
            double e = 0.0;
            size_t nmark = 0;
            st = measure_state(&c, tolerance, threads, QUICK_SEED + (uint64_t)local, memo, P,
                               K, split, &nmark, &e, &best, &best_err, &snap, msg, msglen);
            if (st != BTDF_OK) {
                free(split);
                goto done;
            }
            if (e <= ACCEPT_SHARE * tolerance && !c.capped) {
                free(split);
                st = BTDF_OK;
                break;
            }
            /* Splits that do not lower the error (two measurements in a row above 0.9 of
               the one before) point at the series, not at the nodes: tighten. */
            stall = e > 0.9 * last_err ? stall + 1 : 0;
            last_err = e;
            if (nmark > 0 && local < LOCAL_ROUNDS && stall < 2 && !c.capped) {
                local++;
                nsplit = nmark; /* on to the insertion below */
            } else {
                if (++tighten > 6 || c.capped) {
                    free(split);
                    st = BTDF_EBUDGET;
                    break;
                }
                c.budget *= 0.5;
                memset(fresh, 0, K);
                stall = 0;
                last_err = HUGE_VAL;
                free(split);
                sf_free_state(&c); /* every series and check depends on the budget */
                continue;       /* same nodes, tighter series and checks */
            }
        }
        /* The node budget, and the next pass's growth: when that alone passes a budget,
           stop on this state (within every budget) rather than build a pass to discard. */
        const char *grown = growth_limit(&c, K, nsplit, total, max_coeffs, max_bytes);
        if (grown) {
            limit = grown;
            free(split);
            st = BTDF_EBUDGET;
            break;
        }
        /* this state is within every budget: keep its file, should the next pass
           pass one after all (series grow faster than the pairs when they tighten) */
        if (!over) {
            btdf_scatfun *f = NULL;
            st = sf_assemble(&c, &f, msg, msglen);
            if (st != BTDF_OK) {
                free(split);
                goto done;
            }
            btdf_scatfun_free(snap);
            snap = f;
        }
        st = insert_splits(&c, P, &K, split, fresh, endr, threads);
        if (st == BTDF_EBUDGET)
            break;
        if (st != BTDF_OK)
            goto done;
    }
    if (st == BTDF_EBUDGET || !best) {
        /* keep the finest file reached as the answer, measured honestly */
        keep_finest(&c, threads, QUICK_SEED + (uint64_t)local, memo, over, &snap, &best,
                    &best_err, msg, msglen);
        if (!best && over) {
            /* even the first pass passed the budget */
            free_work(&c, P, fresh, ahead);
            albedo_memo_free(memo);
            return first_pass_over(K, over_need, max_coeffs, max_bytes, msg, msglen);
        }
        if (!best) {
            st = BTDF_ENOMEM;
            goto done;
        }
        if (best_err <= tolerance)
            st = BTDF_OK;
    }
done:
    btdf_scatfun_free(snap);
    free_work(&c, P, fresh, ahead);
    if (st != BTDF_OK && st != BTDF_EBUDGET) {
        albedo_memo_free(memo);
        btdf_scatfun_free(best);
        return st;
    }
    return hand_over(best, memo, tolerance, t0, st, limit, best_err, out, msg, msglen);
}
