/* SPDX-License-Identifier: MIT */
/* facet.c: the adaptive facet-space table: slices at incidence angles bisected where
   blending two neighbours misses the tolerance (the scheme in build.h). */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "table/build.h"

typedef struct facet_job {
    const btdf_table_opts *o;
    double frac_slice;
    double U;
    size_t max_nodes;
    const size_t *max_each; /* per slice to build, when not NULL: its own node limit */
    const double *ti;
    slice_out *out;
} facet_job;

/* The part being built (BOTH never reaches the builder: it builds each part). */
int tb_opts_refl(const btdf_table_opts *o)
{
    return o->part == BTDF_PART_REFLECTION;
}

/* T(ti), or R(ti) for the reflection, coarse. */
static double part_coarse(const btdf_table_opts *o, double ti)
{
    return tb_opts_refl(o) ? model_reflectance_coarse(&o->params, ti)
                        : model_transmittance_coarse(&o->params, ti);
}

static double t_floor(const btdf_table_opts *o, double ti)
{
    /* MODEL.md section 6: errors are relative to max(T, 0.01), max(R, 0.01) */
    return fmax(part_coarse(o, ti), 0.01);
}

static void facet_slice_job(void *arg, size_t k)
{
    facet_job *j = arg;
    const btdf_table_opts *o = j->o;
    slice_target tg;
    tg.p = &o->params;
    tg.ti = j->ti[k];
    tg.metric = o->metric;
    tg.U = j->U;
    tg.max_nodes = j->max_each ? j->max_each[k] : j->max_nodes;
    tg.refl = tb_opts_refl(o);
    tg.target = o->tolerance * j->frac_slice *
                (o->metric == BTDF_METRIC_MAX ? 1.0 : t_floor(o, tg.ti));
    tb_build_slice(&tg, &j->out[k]);
    /* The rule's node geometry, for blend_error's interpolation between slices. */
    btdf_table rule;
    memset(&rule, 0, sizeof rule);
    rule.kind = tg.refl ? BTDF_TABLE_FACET_REFLECTION : BTDF_TABLE_FACET;
    rule.rule = tg.refl ? BTDF_RULE_FRESNEL : BTDF_RULE_CHI;
    rule.p = *tg.p; /* the model's node factors too */
    if (!j->out[k].nomem && j->out[k].s.vals && !slice_prepare(&rule, &j->out[k].s)) {
        tb_free_slice_out(&j->out[k]);
        j->out[k].nomem = 1;
    }
}

/* Error of blending slices a and b half-way, measured on slice m's nodes, relative. */
static double blend_error(const btdf_table_opts *o, const slice_out *A, const slice_out *B,
                          const slice_out *M)
{
    btdf_table tmp;
    memset(&tmp, 0, sizeof tmp);
    tslice two[2] = {A->s, B->s};
    int refl = tb_opts_refl(o);
    tmp.kind = refl ? BTDF_TABLE_FACET_REFLECTION : BTDF_TABLE_FACET;
    /* the rule of the table being built (A and B have geo) */
    tmp.rule = refl ? BTDF_RULE_FRESNEL : BTDF_RULE_CHI;
    tmp.p = o->params;
    tmp.ns = 2;
    tmp.cap = 2;
    tmp.s = two;
    const tslice *s = &M->s;
    size_t nch = (size_t)o->params.channels;
    double wa = (B->s.ti - M->s.ti) / (B->s.ti - A->s.ti), vmax = 0.0, dmax = 0.0;
    double ech[BTDF_MAX_CHANNELS] = {0.0, 0.0, 0.0}; /* per channel: the metric takes the worst */
    double g = incident_factor(&o->params, M->s.ti), ga = incident_factor(&o->params, A->s.ti),
           gb = incident_factor(&o->params, B->s.ti);
    double sti = sin(s->ti), cti = cos(s->ti);
    for (size_t i = 0; i < s->nr; i++) {
        double tw = tb_trap(s->rows, s->nr, i), stn = sin(s->rows[i]), ctn = cos(s->rows[i]);
        for (size_t j = 0; j < s->nc; j++) {
            double ca = stn * cos(s->cols[j]) * sti + ctn * cti; /* e_i.h at M's ti */
            for (size_t c = 0; c < nch; c++) {
                double km = rule_factor(tmp.rule, o->params.ior[c], ca) *
                            model_node_factor(&o->params, refl, o->params.ior[c], sti, cti,
                                              stn, ctn, cos(s->cols[j]));
                double bl = km * blend_ti(slice_interp_red(&tmp, 0, s->rows[i], s->cols[j], (int)c),
                                          slice_interp_red(&tmp, 1, s->rows[i], s->cols[j], (int)c),
                                          1.0 - wa, g, ga, gb);
                double tv = s->vals[(i * s->nc + j) * nch + c];
                double d = fabs(bl - tv);
                vmax = fmax(vmax, tv);
                dmax = fmax(dmax, d);
                ech[c] += d * M->w[i * s->nc + j] * tw * tb_trap(s->cols, s->nc, j) * 2.0;
            }
        }
    }
    if (o->metric == BTDF_METRIC_MAX)
        return vmax > 0.0 ? dmax / vmax : 0.0; /* empty slices have no max error */
    return fmax(ech[0], fmax(ech[1], ech[2])) / t_floor(o, M->s.ti);
}

void tb_free_slice_out(slice_out *s)
{
    free(s->s.geo);
    free(s->s.rows);
    free(s->s.cols);
    free(s->s.vals);
    free(s->w);
    memset(s, 0, sizeof *s);
}

static int cmp_ti(const void *a, const void *b)
{
    double x = ((const slice_out *)a)->s.ti, y = ((const slice_out *)b)->s.ti;
    return (x > y) - (x < y);
}

/* The node budget of an adaptive build, a bound at every moment of it: max_samples
   nodes, and max_bytes at (channels + 1) doubles a node (the values and the measure
   weight held while building). */
size_t tb_node_cap(const btdf_table_opts *o)
{
    size_t max_samples = o->max_samples ? o->max_samples : DEFAULT_MAX_SAMPLES;
    size_t max_bytes = o->max_bytes ? o->max_bytes : DEFAULT_MAX_BYTES;
    size_t cap = max_bytes / (((size_t)o->params.channels + 1) * sizeof(double));
    return cap < max_samples ? cap : max_samples;
}

/* Which limit facet_node_cap is: the memory cap or the sample budget. */
static int facet_limit(const btdf_table_opts *o)
{
    size_t max_samples = o->max_samples ? o->max_samples : DEFAULT_MAX_SAMPLES;
    return tb_node_cap(o) < max_samples ? BUDGET_MEMORY : BUDGET_SAMPLES;
}

/* Incidence slices of the first pass, at most 5 degrees apart. */
size_t tb_first_slices(const btdf_table_opts *o)
{
    double span = o->ti_max - o->ti_min;
    return span > 0.0 ? (size_t)ceil(span / (5.0 * M_PI / 180.0)) + 1 : 1;
}

/* The state of one adaptive build (build_facet_pass): the slices so far, sorted by ti,
   which intervals between them are still open, and the nodes they hold. */
typedef struct facet_pass {
    const btdf_table_opts *o;
    double frac_ti;
    size_t node_cap;
    facet_job j;
    slice_out *sl;
    size_t ns;
    unsigned char *open; /* open[k]: the interval (k, k + 1) may still be split */
    size_t nodes;
    int *budget_hit;
    size_t *evals;
} facet_pass;

/* One round of incidence refinement: nt candidate slices at the midpoints mt of the
   intervals at[], their errors and the node room each may take. */
typedef struct facet_round {
    size_t nt, nalloc;
    double *mt;
    size_t *at;
    slice_out *cand;
    double *ecand;
    unsigned char *taken;
    size_t *need;
} facet_round;

static void round_free(facet_round *r)
{
    for (size_t q = 0; r->cand && q < r->nalloc; q++)
        tb_free_slice_out(&r->cand[q]);
    free(r->cand);
    free(r->ecand);
    free(r->taken);
    free(r->need);
    free(r->mt);
    free(r->at);
    memset(r, 0, sizeof *r);
}

/* The first slices, at most 5 degrees apart; when they alone overrun the budget, again
   with each a share of it. */
static btdf_status facet_first(facet_pass *fp, double *tis)
{
    const btdf_table_opts *o = fp->o;
    size_t n0 = fp->ns;
    double span = o->ti_max - o->ti_min;
    for (size_t k = 0; k < n0; k++)
        tis[k] = n0 > 1 ? o->ti_min + span * (double)k / (double)(n0 - 1) : o->ti_min;
    fp->j.ti = tis;
    fp->j.out = fp->sl;
    if (o->progress)
        o->progress(o->progress_user, "slices", 0, n0);
    core_parallel_for(o->threads, n0, facet_slice_job, &fp->j);
    btdf_status st = BTDF_OK;
    size_t nodes = 0;
    for (size_t k = 0; k < n0; k++)
        nodes += fp->sl[k].s.nr * fp->sl[k].s.nc;
    if (nodes > fp->node_cap) { /* the first slices alone overran: again, each a share */
        for (size_t k = 0; k < n0; k++) {
            *fp->evals += fp->sl[k].evals;
            tb_free_slice_out(&fp->sl[k]);
        }
        fp->j.max_nodes = fp->node_cap / n0;
        *fp->budget_hit |= facet_limit(o);
        core_parallel_for(o->threads, n0, facet_slice_job, &fp->j);
    }
    nodes = 0;
    for (size_t k = 0; k < n0; k++) {
        *fp->evals += fp->sl[k].evals;
        if (fp->sl[k].nomem)
            st = BTDF_ENOMEM;
        *fp->budget_hit |= fp->sl[k].budget_hit;
        nodes += fp->sl[k].s.nr * fp->sl[k].s.nc;
    }
    fp->nodes = nodes;
    return st;
}

/* The round's candidates: the midpoints of the open intervals wider than 2 min_gap,
   with the room each may take. Returns 1 when the room left is too small for a
   candidate slice (the budget is spent). */
static int round_pick(facet_pass *fp, facet_round *r, double min_gap)
{
    const slice_out *sl = fp->sl;
    size_t q = 0, nt = r->nt;
    for (size_t k = 0; k + 1 < fp->ns; k++)
        if (fp->open[k] && sl[k + 1].s.ti - sl[k].s.ti > 2 * min_gap) {
            r->mt[q] = 0.5 * (sl[k].s.ti + sl[k + 1].s.ti);
            r->at[q++] = k;
        }
    double *mt = r->mt;
    size_t *at = r->at, *need = r->need;
    /* Room for the candidates, each by its neighbours' sizes: a slice between two
       others needs about as many nodes as the larger of them (a quarter more, for
       what lies between). When the room left cannot hold every candidate so, test
       only those it can, the widest intervals first (the others stay open): equal
       shares too small for some would stop them short and end refinement with the
       budget far from spent. What room is left over is shared in proportion. */
    size_t left = fp->nodes < fp->node_cap ? fp->node_cap - fp->nodes : 0;
    double total = 0.0;
    for (q = 0; q < nt; q++) {
        size_t a = sl[at[q]].s.nr * sl[at[q]].s.nc, b = sl[at[q] + 1].s.nr * sl[at[q] + 1].s.nc;
        size_t m = a > b ? a : b;
        m += m / 4;
        m = m < SLICE_MIN_NODES ? SLICE_MIN_NODES : m;
        need[q] = m < fp->j.max_nodes ? m : fp->j.max_nodes;
        total += (double)need[q];
    }
    if (nt > 1 && total > (double)left) {
        size_t fit = 0;
        double used = 0.0;
        for (size_t a2 = 0; a2 < nt; a2++) { /* selection of the widest first */
            size_t w = a2;
            for (size_t b2 = a2 + 1; b2 < nt; b2++)
                if (sl[at[b2] + 1].s.ti - sl[at[b2]].s.ti > sl[at[w] + 1].s.ti - sl[at[w]].s.ti)
                    w = b2;
            double tm = mt[a2];
            size_t ta = at[a2], tn = need[a2];
            mt[a2] = mt[w];
            at[a2] = at[w];
            need[a2] = need[w];
            mt[w] = tm;
            at[w] = ta;
            need[w] = tn;
            if (used + (double)need[a2] > (double)left)
                break;
            used += (double)need[a2];
            fit++;
        }
        nt = fit ? fit : 1; /* none fits whole: the widest gets what is left */
        total = fit ? used : (double)left;
        if (!fit)
            need[0] = left;
    }
    int short_room = 0;
    for (q = 0; q < nt; q++) {
        /* total > 0: every need is at least SLICE_MIN_NODES or all of left */
        double share = total > 0.0 ? (double)need[q] * (double)left / total : 0.0;
        size_t rr = share < (double)fp->j.max_nodes ? (size_t)share : fp->j.max_nodes;
        need[q] = rr;
        short_room |= rr < SLICE_MIN_NODES;
    }
    r->nt = nt;
    return short_room;
}

/* The error of an interval by its candidate: the blend of its ends against the slice
   at its midpoint, raised where the midpoint test is known to miss the peak. */
static double round_error(const facet_pass *fp, size_t k, const slice_out *cand)
{
    const btdf_table_opts *o = fp->o;
    const slice_out *sl = fp->sl;
    double e = blend_error(o, &sl[k], &sl[k + 1], cand);
    /* Where the floor max(T, 0.01) changes by more than a factor 1.5 over an interval
       (the last degrees before grazing, past a critical angle), the error relative to
       it is far from symmetric about the midpoint, and the midpoint test misses the
       peak: such intervals are split regardless. */
    if (o->metric == BTDF_METRIC_L1) {
        double fa = t_floor(o, sl[k].s.ti), fb = t_floor(o, sl[k + 1].s.ti);
        if (fmax(fa, fb) > 1.5 * fmin(fa, fb))
            e = fmax(e, 2.0 * o->tolerance * fp->frac_ti);
    }
    /* Next to a slice whose incident factor is 0 (ti = 90 deg) the table holds the
       other end's reduced value (table.c, blend_ti); that is off by up to the whole of
       T there, and the error peaks well before the midpoint. Bound it by T at the other
       end over the floor (L1), or by whether e_max is defined there at all (max), and
       split until the bound is met. */
    int za = !(incident_factor(&o->params, sl[k].s.ti) > 0.0);
    int zb = !(incident_factor(&o->params, sl[k + 1].s.ti) > 0.0);
    if (za != zb) {
        double tother = part_coarse(o, sl[za ? k + 1 : k].s.ti);
        double bound = o->metric == BTDF_METRIC_L1 ? tother / 0.01
                                                     : (tother >= 0.01 ? 1.0 : 0.0);
        e = fmax(e, bound);
    }
    return e;
}

/* Builds the round's candidates and keeps those whose interval misses the tolerance
   (the others close their interval); when the kept ones do not all fit the budget,
   the worst intervals' while they fit. Sets *keep. */
static btdf_status round_judge(facet_pass *fp, facet_round *r, size_t *keep_out)
{
    const btdf_table_opts *o = fp->o;
    size_t nt = r->nt, q;
    btdf_status st = BTDF_OK;
    fp->j.ti = r->mt;
    fp->j.out = r->cand;
    size_t saved_max = fp->j.max_nodes;
    fp->j.max_each = r->need;
    core_parallel_for(o->threads, nt, facet_slice_job, &fp->j);
    fp->j.max_nodes = saved_max;
    fp->j.max_each = NULL;
    size_t keep = 0;
    for (q = 0; q < nt; q++)
        *fp->evals += r->cand[q].evals;
    for (q = 0; q < nt; q++) {
        if (r->cand[q].nomem) {
            st = BTDF_ENOMEM;
            continue;
        }
        size_t k = r->at[q];
        double e = round_error(fp, k, &r->cand[q]);
        r->ecand[q] = e;
        if (e > o->tolerance * fp->frac_ti)
            keep++;
        else {
            fp->open[k] = 0;
            tb_free_slice_out(&r->cand[q]);
        }
    }
    if (st == BTDF_OK && keep) {
        size_t add_nodes = 0;
        for (q = 0; q < nt; q++)
            add_nodes += r->cand[q].s.nr * r->cand[q].s.nc;
        if (fp->nodes + add_nodes > fp->node_cap) {
            /* Not all fit: add the worst intervals' slices while they fit, so the
               budget goes where the error is, and close the others. */
            *fp->budget_hit |= facet_limit(o);
            size_t room = fp->nodes < fp->node_cap ? fp->node_cap - fp->nodes : 0;
            keep = 0;
            for (;;) {
                size_t best = nt;
                for (q = 0; q < nt; q++)
                    if (r->cand[q].s.vals && !r->taken[q] &&
                        (best == nt || r->ecand[q] > r->ecand[best]))
                        best = q;
                if (best == nt)
                    break;
                r->taken[best] = 1;
                size_t m = r->cand[best].s.nr * r->cand[best].s.nc;
                if (m <= room) {
                    room -= m;
                    keep++;
                } else {
                    fp->open[r->at[best]] = 0;
                    tb_free_slice_out(&r->cand[best]);
                }
            }
        }
    }
    *keep_out = keep;
    return st;
}

/* Adds the keep candidates left in the round to the slices, sorted by ti, and marks
   which intervals remain open: one of whose ends was just added, or one open and not
   tested this round. */
static btdf_status round_merge(facet_pass *fp, facet_round *r, size_t keep)
{
    size_t ns = fp->ns;
    slice_out *ns_sl = realloc(fp->sl, (ns + keep) * sizeof *fp->sl);
    unsigned char *no = ns_sl ? realloc(fp->open, ns + keep) : NULL;
    if (ns_sl)
        fp->sl = ns_sl;
    if (!ns_sl || !no)
        return BTDF_ENOMEM;
    fp->open = no;
    slice_out *sl = fp->sl;
    unsigned char *open = fp->open;
    /* Intervals still open (not tested this round: the room held only some candidates)
       stay open; the left end names each, as none was split. */
    double *still = malloc(ns * sizeof(double));
    size_t nst = 0;
    for (size_t k = 0; k + 1 < ns && still; k++)
        if (open[k])
            still[nst++] = sl[k].s.ti;
    /* Old intervals that were split stay open as their two halves. */
    for (size_t q = 0; q < r->nt; q++) {
        if (r->cand[q].s.vals) {
            sl[ns] = r->cand[q];
            *fp->budget_hit |= r->cand[q].budget_hit;
            fp->nodes += r->cand[q].s.nr * r->cand[q].s.nc;
            memset(&r->cand[q], 0, sizeof r->cand[q]);
            ns++;
        }
    }
    fp->ns = ns;
    double *fresh = malloc(ns * sizeof(double));
    size_t nf = 0;
    for (size_t k = ns - keep; k < ns && fresh; k++)
        fresh[nf++] = sl[k].s.ti;
    qsort(sl, ns, sizeof *sl, cmp_ti);
    for (size_t k = 0; k + 1 < ns; k++) {
        open[k] = 0;
        for (size_t f = 0; f < nf; f++)
            if (sl[k].s.ti == fresh[f] || sl[k + 1].s.ti == fresh[f])
                open[k] = 1;
        for (size_t f = 0; f < nst && !open[k]; f++)
            if (sl[k].s.ti == still[f])
                open[k] = 1;
    }
    free(fresh);
    free(still);
    return fresh && still ? BTDF_OK : BTDF_ENOMEM;
}

/* One adaptive build with the given shares of the tolerance: the first slices, then
   rounds that test the midpoint of every open incidence interval with a slice built
   there and keep it where blending the ends misses the tolerance. */
btdf_status tb_facet_pass(const btdf_table_opts *o, double frac_slice,
                                    double frac_ti, btdf_table *t, int *budget_hit,
                                    size_t *evals)
{
    facet_pass fp;
    memset(&fp, 0, sizeof fp);
    fp.o = o;
    fp.frac_ti = frac_ti;
    fp.node_cap = tb_node_cap(o);
    fp.budget_hit = budget_hit;
    fp.evals = evals;
    size_t node_cap = fp.node_cap;
    /* Tail: facets with u > U carry a fraction exp(-U^2) of the facet distribution; U
       puts that below a tenth of the tolerance. */
    double U = sqrt(log(10.0 / o->tolerance)) + 1.0;
    size_t per_slice = node_cap / 8 > 1000 ? node_cap / 8 : 1000;
    facet_job j = {o, frac_slice, U, per_slice < node_cap ? per_slice : node_cap, NULL, NULL,
                   NULL};
    fp.j = j;
    size_t n0 = tb_first_slices(o); /* btdf_table_build checked n0 slices fit */
    fp.ns = n0;
    fp.sl = calloc(n0, sizeof *fp.sl);
    double *tis = malloc(n0 * sizeof(double));
    if (!fp.sl || !tis) {
        free(fp.sl);
        free(tis);
        return BTDF_ENOMEM;
    }
    btdf_status st = facet_first(&fp, tis);
    /* Incidence refinement in rounds: test the midpoint of every open interval. */
    fp.open = malloc(fp.ns ? fp.ns : 1);
    if (!fp.open)
        st = BTDF_ENOMEM;
    for (size_t k = 0; k + 1 < fp.ns && fp.open; k++)
        fp.open[k] = 1;
    /* rad: finer incidence steps buy nothing a renderer can see, except where V(ti)
       falls from 1 to 0 before grazing, over a width of order 1/s rad */
    double min_gap = fmin(1e-4, 1e-2 / o->params.smoothness);
    while (st == BTDF_OK) {
        size_t nt = 0;
        for (size_t k = 0; k + 1 < fp.ns; k++)
            if (fp.open[k] && fp.sl[k + 1].s.ti - fp.sl[k].s.ti > 2 * min_gap)
                nt++;
        if (nt == 0)
            break;
        if (o->progress) /* ns slices built, nt midpoints to test now */
            o->progress(o->progress_user, "incidence angles", fp.ns, nt);
        facet_round r;
        memset(&r, 0, sizeof r);
        r.nt = r.nalloc = nt;
        r.mt = malloc(nt * sizeof(double));
        r.at = malloc(nt * sizeof(size_t));
        r.cand = calloc(nt, sizeof *r.cand);
        r.ecand = calloc(nt, sizeof *r.ecand);
        r.taken = calloc(nt, 1);
        r.need = malloc(nt * sizeof(size_t));
        if (!r.mt || !r.at || !r.cand || !r.ecand || !r.taken || !r.need) {
            round_free(&r);
            st = BTDF_ENOMEM;
            break;
        }
        /* The candidates are held beside the slices: together they stay in the budget. */
        if (round_pick(&fp, &r, min_gap)) {
            *budget_hit |= facet_limit(o);
            round_free(&r);
            break;
        }
        size_t keep = 0;
        st = round_judge(&fp, &r, &keep);
        if (st == BTDF_OK && keep) {
            st = round_merge(&fp, &r, keep);
        } else if (st == BTDF_OK && !keep && *budget_hit) {
            for (size_t k = 0; k + 1 < fp.ns; k++)
                fp.open[k] = 0;
        }
        round_free(&r);
    }
    free(fp.open);
    for (size_t k = 0; k < fp.ns; k++) {
        free(fp.sl[k].w);
        fp.sl[k].w = NULL;
        if (st == BTDF_OK) {
            if (table_push_slice(t, &fp.sl[k].s) != BTDF_OK) {
                st = BTDF_ENOMEM;
                tb_free_slice_out(&fp.sl[k]);
            }
        } else {
            tb_free_slice_out(&fp.sl[k]);
        }
    }
    free(fp.sl);
    free(tis);
    return st;
}

