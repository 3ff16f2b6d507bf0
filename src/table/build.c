/* SPDX-License-Identifier: MIT */
/* build.c: tables from Eq. 25, a uniform grid (grid.c) or facet-space nodes refined to a
   tolerance (slice.c, facet.c): the options, their checks, and the parts. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "table/build.h"

BTDF_API void btdf_table_opts_default(btdf_table_opts *o)
{
    memset(o, 0, sizeof *o);
    btdf_params_default(&o->params);
    o->ti_min = 0.0;
    o->ti_max = M_PI / 2;
    o->kind = BTDF_TABLE_FACET;
    o->tolerance = 1e-3;
    o->metric = BTDF_METRIC_L1;
    o->grid_ti = 90;
    o->grid_to = 90;
    o->grid_phi = 181;
    o->max_samples = 0;
    o->max_bytes = 0;
    o->threads = 0;
    o->to_min = M_PI / 2;
    o->to_max = M_PI;
    o->phi_min = 0.0;
    o->phi_max = M_PI;
    o->part = BTDF_PART_TRANSMISSION;
}


static btdf_status check_opts(const btdf_table_opts *o, char *msg, size_t msglen)
{
    btdf_params single = table_single_params(&o->params); /* full: smith's parameters */
    btdf_status st = btdf_params_check(&single, msg, msglen);
    if (st != BTDF_OK)
        return st;
    if (!(o->ti_min >= 0.0 && o->ti_min <= M_PI / 2))
        return core_say(BTDF_EINVAL, msg, msglen, "theta-i start %g deg: must lie in [0, 90]",
                   o->ti_min * 180 / M_PI);
    if (!(o->ti_max >= o->ti_min && o->ti_max <= M_PI / 2))
        return core_say(BTDF_EINVAL, msg, msglen, "theta-i end %g deg: must lie in [start, 90]",
                   o->ti_max * 180 / M_PI);
    if (o->kind == BTDF_TABLE_GRID) {
        if (o->grid_ti < 1 || o->grid_ti > 100000)
            return core_say(BTDF_EINVAL, msg, msglen, "grid theta-i count %lld: must lie in [1, 100000]",
                           (long long)o->grid_ti);
        if (o->grid_to < 2 || o->grid_to > 100000)
            return core_say(BTDF_EINVAL, msg, msglen, "grid theta-o count %lld: must lie in [2, 100000]",
                           (long long)o->grid_to);
        if (o->grid_phi < 2 || o->grid_phi > 100000)
            return core_say(BTDF_EINVAL, msg, msglen, "grid phi count %lld: must lie in [2, 100000]",
                           (long long)o->grid_phi);
        if (!(o->to_min >= M_PI / 2 && o->to_min < o->to_max && o->to_max <= M_PI))
            return core_say(BTDF_EINVAL, msg, msglen, "theta-o range starting at %g deg: need 90 <= A < B <= 180",
                       o->to_min * 180 / M_PI);
        if (!(o->phi_min >= 0.0 && o->phi_min < o->phi_max && o->phi_max <= M_PI))
            return core_say(BTDF_EINVAL, msg, msglen, "phi range starting at %g deg: need 0 <= A < B <= 180 "
                                    "(rho depends on cos phi only)", o->phi_min * 180 / M_PI);
        if (o->grid_ti > 1 && !(o->ti_max > o->ti_min))
            return core_say(BTDF_EINVAL, msg, msglen, "theta-i range of width %g: several grid slices need "
                                    "start < end", o->ti_max - o->ti_min);
    } else if (o->kind == BTDF_TABLE_FACET || o->kind == BTDF_TABLE_FACET_RECIPROCAL) {
        if (!(o->tolerance >= 1e-7 && o->tolerance <= 1.0))
            return core_say(BTDF_EINVAL, msg, msglen, "tolerance %s: must lie in [1e-7, 1]",
                            core_num(o->tolerance, (char[32]){0}));
        if (o->estimate != BTDF_ESTIMATE_FULL && o->estimate != BTDF_ESTIMATE_FAST &&
            o->estimate != BTDF_ESTIMATE_NONE)
            return core_say(BTDF_EINVAL, msg, msglen, "estimate mode %lld: must be full (0), fast (1) or none (2)",
                           (long long)o->estimate);
        if (o->metric != BTDF_METRIC_L1 && o->metric != BTDF_METRIC_MAX)
            return core_say(BTDF_EINVAL, msg, msglen, "metric %lld: must be l1 (0) or max (1)",
                           (long long)o->metric);
    } else {
        return core_say(BTDF_EINVAL, msg, msglen, "table kind %lld: must be facet (0) or grid (1)",
                       (long long)o->kind);
    }
    if (o->threads < 0 || o->threads > 256)
        return core_say(BTDF_EINVAL, msg, msglen, "threads %lld: must lie in [0, 256]", (long long)o->threads);
    /* part 0 (a zeroed struct) is the transmission, as before the field existed */
    if (o->part != 0 && o->part != BTDF_PART_TRANSMISSION && o->part != BTDF_PART_REFLECTION &&
        o->part != BTDF_PART_BOTH)
        return core_say(BTDF_EINVAL, msg, msglen, "part %lld: must be transmission (1), reflection (2) or both (3)",
                       (long long)o->part);
    if (o->kind == BTDF_TABLE_GRID && o->part != 0 && o->part != BTDF_PART_TRANSMISSION)
        return core_say(BTDF_EINVAL, msg, msglen, "part %lld: grid tables hold the transmission only; the "
                                    "reflection needs a facet table", (long long)o->part);
    /* full's tally is added to facet slices at the query (table/full.c); a grid of
       full would need the tally in its nodes and its own estimate */
    if (o->params.model == BTDF_MODEL_FULL && o->kind == BTDF_TABLE_GRID)
        return core_say(BTDF_ENOTSUP, msg, msglen, "kind grid with model full: not available "
                        "in this build (facet tables take full)");
    return BTDF_OK;
}

BTDF_API btdf_status btdf_table_opts_check(const btdf_table_opts *o, char *msg, size_t msglen)
{
    if (!o) {
        if (msg && msglen)
            snprintf(msg, msglen, "no options (NULL)");
        return BTDF_EINVAL;
    }
    return check_opts(o, msg, msglen);
}


static void table_clear(btdf_table *t)
{
    for (size_t k = 0; k < t->ns; k++) {
        free(t->s[k].rows);
        free(t->s[k].cols);
        free(t->s[k].vals);
        free(t->s[k].geo);
    }
    t->ns = 0;
}

/* The builder checks itself with the estimate btdftab reports (its seed, the default
   angles and points): the check sees every slice interval and refines where the error
   changes fast (estimate.c), so tuning to its points cannot hide an error between
   them, and a table the builder calls met is reported met, bit for bit. An independent
   dense scan (tools/densescan.c) checks both against the truth. */
#define BUILD_CHECK_SEED 20081231u

static void budget_text(char *msg, size_t msglen, int which, const btdf_table_opts *o,
                        size_t samples, double e, double tol)
{
    size_t ms = o->max_samples ? o->max_samples : DEFAULT_MAX_SAMPLES;
    size_t mb = o->max_bytes ? o->max_bytes : DEFAULT_MAX_BYTES;
    const char *what = (which & BUDGET_MEMORY) ? "the memory cap"
                       : (which & BUDGET_SAMPLES) ? "the sample budget"
                                                  : "the per-slice share of the sample budget";
    if (!msg || !msglen)
        return;
    int w = snprintf(msg, msglen,
                     "%s (%zu samples, %zu MiB) stopped refinement: the table holds %zu "
                     "samples (%.0f%% of the budget)",
                     what, ms, mb >> 20, samples,
                     100.0 * (double)samples / (double)tb_node_cap(o));
    if (w > 0 && (size_t)w < msglen && isfinite(e)) /* e is NaN when not estimated */
        snprintf(msg + w, msglen - (size_t)w, " and reached %.3g, %.2f times the tolerance %g",
                 e, e / tol, tol);
}

/* A table of the part's kind and o's parameters (for model full smith's: the passes
   build smith's slices, and each is given the tally only to be checked, since the
   builder's own measures compare the table with smith's kernel). */
static btdf_status part_table_new(btdf_table_kind kind, const btdf_table_opts *o,
                                  btdf_table **out, char *msg, size_t msglen)
{
    btdf_params single = table_single_params(&o->params);
    return btdf_table_new(kind, &single, out, msg, msglen);
}

/* One part: the transmission, or the reflection when o->part is REFLECTION; ms: model
   full's tally of each channel, else NULL. */
static btdf_status build_part(const btdf_table_opts *o, const btdf_full *const *ms,
                              btdf_table **out, char *msg, size_t msglen)
{
    int refl = tb_opts_refl(o);
    btdf_table_kind kind = refl ? BTDF_TABLE_FACET_REFLECTION : o->kind;
    btdf_table *t;
    btdf_status st = part_table_new(kind, o, &t, msg, msglen);
    if (st != BTDF_OK)
        return st;
    if (o->kind != BTDF_TABLE_GRID)
        t->rule = refl ? BTDF_RULE_FRESNEL : BTDF_RULE_CHI; /* btdf.h: adaptive tables interpolate rho / K */
    if (o->kind == BTDF_TABLE_GRID) {
        st = tb_build_grid(o, t, msg, msglen);
        if (st != BTDF_OK) {
            btdf_table_free(t);
            return st;
        }
        *out = t;
        return BTDF_OK;
    }
    /* Light leaving the dense medium (every n < 1) is tabulated through reciprocity as
       the table of 1/n over all incident angles, whose facet space is well conditioned
       (btdf.h, BTDF_TABLE_FACET_RECIPROCAL). Errors are still measured for n. */
    btdf_table_opts ob = *o;
    ob.params = table_single_params(&o->params); /* full: the passes are smith's */
    btdf_params pmat = ob.params; /* the material's, as the table keeps them */
    int recip = !refl; /* the reflection's facet space is well conditioned for every n */
    for (int c = 0; c < o->params.channels; c++)
        recip = recip && o->params.ior[c] < 1.0;
    if (recip) {
        for (int c = 0; c < o->params.channels; c++)
            ob.params.ior[c] = 1.0 / o->params.ior[c];
        ob.ti_min = 0.0;
        ob.ti_max = M_PI / 2;
    }
    /* A budget below the first pass's coarsest slices cannot hold any table. */
    size_t first = tb_first_slices(&ob) * SLICE_MIN_NODES;
    if (first > tb_node_cap(&ob)) {
        btdf_table_free(t);
        if (msg && msglen)
            snprintf(msg, msglen, "the budget (%zu samples, %zu bytes at %d channel%s) is below "
                                  "the %zu nodes of the coarsest table: nothing was built",
                     o->max_samples ? o->max_samples : DEFAULT_MAX_SAMPLES,
                     o->max_bytes ? o->max_bytes : DEFAULT_MAX_BYTES, o->params.channels,
                     o->params.channels == 1 ? "" : "s", first);
        return BTDF_EBUDGET;
    }
    /* Split the tolerance between slice interpolation and incidence blending, check
       the result with the estimate, and tighten while it falls short; keep the best
       table of the passes (a pass the budget stops can be worse than the one before). */
    double fs = 0.8, ft = 0.6;
    int budget_hit = 0, best_budget = 0;
    double best_e = INFINITY;
    btdf_table *best = NULL;
    size_t evals = 0; /* Eq. 25 evaluations of every pass, kept with the table */
    for (int pass = 0; pass < 6; pass++) {
        if (pass > 0 && o->progress) /* the check fell short: a tighter pass, at most 6 */
            o->progress(o->progress_user, "tighter pass", (size_t)pass, (size_t)(6 - pass));
        table_clear(t);
        table_strip_full(t);
        /* the pass's own kind: its slices' model factors (slice_prepare) are the
           reflection's for a reflection, and the refraction's in n for the others */
        t->kind = refl ? BTDF_TABLE_FACET_REFLECTION : BTDF_TABLE_FACET;
        t->p = ob.params;
        budget_hit = 0;
        st = tb_facet_pass(&ob, fs, ft, t, &budget_hit, &evals);
        t->kind = recip ? BTDF_TABLE_FACET_RECIPROCAL : kind;
        t->p = pmat;
        if (st == BTDF_OK && ms) /* full: checked, and kept, with its tally */
            st = table_make_full(t, ms, msg, msglen);
        if (st != BTDF_OK)
            break;
        if (o->estimate == BTDF_ESTIMATE_NONE) { /* one pass, unchecked */
            best = t;
            t = NULL;
            best_e = 0.0;
            best_budget = budget_hit;
            break;
        }
        size_t angles = o->estimate == BTDF_ESTIMATE_FAST ? 16 : 0;
        size_t ppa = o->estimate == BTDF_ESTIMATE_FAST ? 2048 : 0;
        btdf_report r;
        memset(&r, 0, sizeof r);
        st = btdf_table_estimate(t, o->ti_min, o->ti_max, angles, ppa, BUILD_CHECK_SEED,
                                 o->threads, &r);
        double e = o->metric == BTDF_METRIC_MAX ? r.e_max_max : r.e_l1_max;
        if (st != BTDF_OK)
            break;
        btdf_report_clear(&t->check);
        t->check = r; /* kept for the caller's estimate of the same request */
        t->check_valid = 1;
        t->check_ti0 = o->ti_min;
        t->check_ti1 = o->ti_max;
        t->check_angles = angles;
        t->check_ppa = ppa;
        t->check_seed = BUILD_CHECK_SEED;
        if (e < best_e) {
            btdf_table *fresh = NULL;
            st = part_table_new(kind, o, &fresh, msg, msglen);
            if (st != BTDF_OK)
                break;
            fresh->rule = refl ? BTDF_RULE_FRESNEL : BTDF_RULE_CHI;
            btdf_table_free(best);
            best = t;
            t = fresh;
            best_e = e;
            best_budget = budget_hit;
        }
        /* A margin below the tolerance: the estimate samples, the truth is a supremum. */
        if (e <= 0.8 * o->tolerance || budget_hit)
            break;
        /* Tighten by what the error asks for, gently: each pass costs a whole build. */
        double f = fmax(0.2, fmin(0.85, 0.75 * o->tolerance / e));
        fs *= f;
        ft *= f;
    }
    btdf_table_free(t); /* NULL or the last pass that was not the best */
    if (st != BTDF_OK && st != BTDF_EBUDGET) {
        btdf_table_free(best);
        return st;
    }
    if (!best)
        return BTDF_ENOMEM;
    best->build_evals = evals;
    *out = best;
    if (o->estimate == BTDF_ESTIMATE_NONE) {
        if (best_budget && msg && msglen)
            budget_text(msg, msglen, best_budget, o, btdf_table_node_count(best), NAN,
                        o->tolerance);
        return BTDF_OK; /* not checked: the caller says so */
    }
    if (best_e > o->tolerance) {
        if (best_budget) {
            budget_text(msg, msglen, best_budget, o, btdf_table_node_count(best), best_e,
                        o->tolerance);
            return BTDF_EBUDGET;
        }
        if (msg && msglen)
            snprintf(msg, msglen, "refinement ended at %.3g, %.2f times the tolerance %g, "
                     "without reaching the budget", best_e, best_e / o->tolerance, o->tolerance);
        return BTDF_EBUDGET;
    }
    return BTDF_OK;
}

static btdf_status build_parts(const btdf_table_opts *o, const btdf_full *const *ms,
                               btdf_table **out, char *msg, size_t msglen);

BTDF_API btdf_status btdf_table_build(const btdf_table_opts *o, btdf_table **out, char *msg,
                                      size_t msglen)
{
    if (!o || !out) {
        if (msg && msglen)
            snprintf(msg, msglen, "%s",
                     !o ? "no options (NULL)" : "no place for the table (out is NULL)");
        return BTDF_EINVAL;
    }
    btdf_status st = check_opts(o, msg, msglen);
    if (st != BTDF_OK)
        return st;
    /* Model full: its tally, once for the material (each channel's), on o's threads;
       the slices then follow smith and the table adds the tally (table/full.c). */
    btdf_model_ctx *ctx = NULL;
    const btdf_full *ms[BTDF_MAX_CHANNELS] = {NULL, NULL, NULL};
    if (o->params.model == BTDF_MODEL_FULL) {
        if (o->progress)
            o->progress(o->progress_user, "multiple scattering tally", 0, 1);
        btdf_full_opts fo;
        btdf_full_opts_default(&fo);
        fo.threads = o->threads;
        st = btdf_model_ctx_new(&o->params, &fo, &ctx, msg, msglen);
        if (st != BTDF_OK)
            return st;
        for (int c = 0; c < o->params.channels; c++)
            ms[c] = btdf_model_ctx_full(ctx, c);
    }
    st = build_parts(o, ctx ? ms : NULL, out, msg, msglen);
    btdf_model_ctx_free(ctx); /* the tables keep copies */
    return st;
}

/* btdf_table_build after its checks and model full's tally. */
static btdf_status build_parts(const btdf_table_opts *o, const btdf_full *const *ms,
                               btdf_table **out, char *msg, size_t msglen)
{
    btdf_status st;
    if (o->part != BTDF_PART_BOTH)
        return build_part(o, ms, out, msg, msglen);
    /* Both parts: each its own table, refined to the tolerance with the whole budget;
       the reflection is attached to the transmission. A part the budget stopped makes
       the whole BTDF_EBUDGET, with that part's message. */
    btdf_table_opts ot = *o, orr = *o;
    ot.part = BTDF_PART_TRANSMISSION;
    orr.part = BTDF_PART_REFLECTION;
    char mt[512] = "", mr[512] = "";
    btdf_table *t = NULL, *r = NULL;
    btdf_status st_t = build_part(&ot, ms, &t, mt, sizeof mt);
    if (st_t != BTDF_OK && st_t != BTDF_EBUDGET) {
        if (msg && msglen)
            snprintf(msg, msglen, "transmission: %s", mt);
        return st_t;
    }
    btdf_status st_r = build_part(&orr, ms, &r, mr, sizeof mr);
    if (st_r != BTDF_OK && st_r != BTDF_EBUDGET) {
        btdf_table_free(t);
        if (msg && msglen)
            snprintf(msg, msglen, "reflection: %s", mr);
        return st_r;
    }
    st = btdf_table_attach_reflection(t, r, msg, msglen);
    if (st != BTDF_OK) {
        btdf_table_free(t);
        btdf_table_free(r);
        return st;
    }
    *out = t;
    if (msg && msglen) {
        msg[0] = 0;
        if (mt[0] && mr[0])
            snprintf(msg, msglen, "transmission: %s; reflection: %s", mt, mr);
        else if (mt[0] || mr[0])
            snprintf(msg, msglen, "%s: %s", mt[0] ? "transmission" : "reflection",
                     mt[0] ? mt : mr);
    }
    return st_t != BTDF_OK ? st_t : st_r;
}
