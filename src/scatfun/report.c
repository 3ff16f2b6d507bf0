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
#include "model/full.h"
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
    mis_obj m = {f, (btdf_side)b, mode, both, NULL, NULL};
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
    /* full: the truth is smith plus the tally of the light's index (est_opts.full) */
    if (p->model == BTDF_MODEL_FULL) {
        for (int k = 0; k < q.channels; k++)
            if (!f->ms[below][k])
                return BTDF_ENOTSUP; /* a file read back keeps no tally */
        opt.full = (btdf_full *const *)f->ms[below];
    }
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
    /* the top test angle (scatfun.h, SF_TI_TOP): xu-sun's rho vanishes towards
       grazing with V(ti), so its files are tested at 90 deg, where truth and file are
       0, and keep the reports they always had */
    double top = p->model == BTDF_MODEL_XU_SUN ? M_PI / 2 : SF_TI_TOP;
    knots[nk++] = top;
    /* a reflection block is measured against rho_r over its side's upper hemisphere,
       relative to max(R(ti), 0.01), by the estimator's own sample sets (MODEL.md
       sections 6 and 8); mis_eval reads tr's cosine where a transmission's is to's */
    btdf_status st = est_knots_prep_part(&q, refl, 0.0, top, angles, ppa, seed, threads,
                                         knots, nk, mis_eval, mis_prep, mis_done, &m, &opt,
                                         memo, r);
    free(knots);
    /* full: the tally's noise floor over the range tested (table/full.c's rule) */
    r->ms_noise = 0.0;
    for (int k = 0; st == BTDF_OK && opt.full && k < q.channels; k++)
        r->ms_noise = fmax(r->ms_noise, full_ms_noise(opt.full[k], refl, 0.0, top));
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
    /* Model full is not reciprocal to the bit: each index has its own tally, whose
       orders 2+ are a fit. The file keeps each block's own (its DIRECT reading); an
       ADJOINT reading returns the reverse path's tally, apart from this block's by the
       model's own reciprocity gap, which no file of separate blocks can close (measured
       in docs/scatfun.md, "Files of full"). So full's files are measured DIRECT. */
    if (p->model == BTDF_MODEL_FULL)
        has_adj = 0;
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
    if (sf_check_params(p, NULL, 0) != BTDF_OK)
        return BTDF_EINVAL;
    if (p->model == BTDF_MODEL_FULL && !f->ms[0][p->channels == 3 ? 1 : 0] &&
        !f->ms[1][p->channels == 3 ? 1 : 0])
        return BTDF_ENOTSUP; /* full's truth needs the tally: a built file's */
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
