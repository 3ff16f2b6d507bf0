/* SPDX-License-Identifier: MIT */
/* build.c: tables from Eq. 25, a uniform grid or facet-space nodes refined to a tolerance. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "table/table.h"

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

#define DEFAULT_MAX_SAMPLES ((size_t)8000000)
/* Which limit stopped refinement (bits of budget_hit). */
#define BUDGET_SAMPLES 1 /* the table's node budget */
#define BUDGET_MEMORY 2  /* the memory cap */
#define BUDGET_SLICE 4   /* one slice reached its share, an eighth of the smaller of the two */
#define DEFAULT_MAX_BYTES ((size_t)256 << 20)

static btdf_status check_opts(const btdf_table_opts *o, char *msg, size_t msglen)
{
    btdf_status st = btdf_params_check(&o->params, msg, msglen);
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
            return core_say(BTDF_EINVAL, msg, msglen, "tolerance %g: must lie in [1e-7, 1]", o->tolerance);
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
    /* Smith's reflection keeps a finite value up to the horizon (G2 ~ cos tr there) where
       the builder's nodes stop: measured at n = 1.5, s = 3, a 5e-2 table misses 8 % of
       R with e_max 1, so it is refused rather than written short */
    if (o->params.model == BTDF_MODEL_SMITH && o->part != 0 && o->part != BTDF_PART_TRANSMISSION)
        return core_say(BTDF_ENOTSUP, msg, msglen, "part %s with model smith: reflection tables "
                        "of this model are not available in this build (the transmission is)",
                        btdf_part_name(o->part));
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

/* ------------------------------------------------------------------------- */
/* Uniform grid                                                              */
/* ------------------------------------------------------------------------- */

typedef struct grid_job {
    const btdf_table_opts *o;
    tslice *s;
} grid_job;

static void grid_slice(void *arg, size_t k)
{
    grid_job *g = arg;
    const btdf_params *p = &g->o->params;
    tslice *s = &g->s[k];
    size_t nr = s->nr, nc = s->nc, nch = (size_t)p->channels;
    double *cph = malloc(nc * sizeof(double)), *sph = malloc(nc * sizeof(double));
    double *row = malloc(nc * sizeof(double));
    if (!cph || !sph || !row) {
        free(cph);
        free(sph);
        free(row);
        s->nr = 0; /* reported as BTDF_ENOMEM by the caller */
        return;
    }
    for (size_t j = 0; j < nc; j++) {
        cph[j] = cos(s->cols[j]);
        sph[j] = sin(s->cols[j]);
    }
    rho_in a;
    for (size_t c = 0; c < nch; c++) {
        double n = p->ior[c];
        rho_in_init_m(&a, sin(s->ti), cos(s->ti), p->smoothness, p->k0, p->model);
        for (size_t i = 0; i < nr; i++) {
            rho_out b;
            rho_out_init_m(&b, sin(s->rows[i]), fmin(cos(s->rows[i]), 0.0), p->smoothness,
                           p->k0, &a);
            /* The inner loop has no per-sample trigonometry and no calls: it vectorises. */
            for (size_t j = 0; j < nc; j++)
                row[j] = rho_kernel(n, p->smoothness, &a, &b, cph[j], sph[j]);
            for (size_t j = 0; j < nc; j++)
                s->vals[(i * nc + j) * nch + c] = row[j];
        }
    }
    free(cph);
    free(sph);
    free(row);
}

static btdf_status build_grid(const btdf_table_opts *o, btdf_table *t, char *msg,
                              size_t msglen)
{
    size_t nt = o->grid_ti, nr = o->grid_to, nc = o->grid_phi, nch = (size_t)o->params.channels;
    size_t max_samples = o->max_samples ? o->max_samples : DEFAULT_MAX_SAMPLES;
    size_t max_bytes = o->max_bytes ? o->max_bytes : DEFAULT_MAX_BYTES;
    /* counts are <= 1e5 each: nt * nr * nc < 1e15 fits size_t; bytes checked below */
    size_t total = nt * nr * nc;
    if (total > max_samples || total > max_bytes / (nch * sizeof(double))) {
        if (msg && msglen)
            snprintf(msg, msglen,
                     "grid of %zu x %zu x %zu = %zu samples exceeds the budget of %zu samples "
                     "or %zu bytes",
                     nt, nr, nc, total, max_samples, max_bytes);
        return BTDF_EBUDGET;
    }
    tslice *s = calloc(nt, sizeof *s);
    if (!s)
        return BTDF_ENOMEM;
    btdf_status st = BTDF_OK;
    for (size_t k = 0; k < nt && st == BTDF_OK; k++) {
        s[k].ti = nt > 1 ? o->ti_min + (o->ti_max - o->ti_min) * (double)k / (double)(nt - 1)
                         : o->ti_min;
        s[k].nr = nr;
        s[k].nc = nc;
        s[k].rows = malloc(nr * sizeof(double));
        s[k].cols = malloc(nc * sizeof(double));
        s[k].vals = malloc(nr * nc * nch * sizeof(double));
        if (!s[k].rows || !s[k].cols || !s[k].vals) {
            st = BTDF_ENOMEM;
            break;
        }
        for (size_t i = 0; i < nr; i++)
            s[k].rows[i] = o->to_min + (o->to_max - o->to_min) * (double)i / (double)(nr - 1);
        for (size_t j = 0; j < nc; j++)
            s[k].cols[j] = o->phi_min + (o->phi_max - o->phi_min) * (double)j / (double)(nc - 1);
    }
    if (st == BTDF_OK) {
        grid_job g = {o, s};
        core_parallel_for(o->threads, nt, grid_slice, &g);
        for (size_t k = 0; k < nt; k++)
            if (s[k].nr == 0)
                st = BTDF_ENOMEM;
    }
    for (size_t k = 0; k < nt; k++) {
        if (st == BTDF_OK && table_push_slice(t, &s[k]) != BTDF_OK)
            st = BTDF_ENOMEM;
        if (st != BTDF_OK) {
            free(s[k].rows);
            free(s[k].cols);
            free(s[k].vals);
        }
    }
    free(s);
    return st;
}

/* ------------------------------------------------------------------------- */
/* Adaptive facet-space table                                                */
/* ------------------------------------------------------------------------- */

/*
 * Nodes: a slice at ti holds rho at facet normals h(tn, psi). Rows start uniform in
 * u = (s/2) tan tn, the facet slope in units where the Beckmann factor is exp(-u^2),
 * so the same nodes suit every s; columns start uniform in psi. Each pass compares
 * the linear interpolant with Eq. 25 at the midpoint of every row and column
 * interval, weighted by the outgoing measure |cos to| d(omega_o) = |cos to|/chi
 * d(omega_h), and bisects the intervals whose share of the error exceeds the
 * average allowed share. Incidence nodes are bisected the same way, by comparing
 * the blend of two neighbouring slices with a slice built at their midpoint.
 */

typedef struct slice_target {
    const btdf_params *p;
    double ti;
    double target; /* allowed error: absolute L1 (already times max(T, 0.01)) or relative max */
    btdf_metric metric;
    double U; /* last row at u = U */
    size_t max_nodes;
    int refl; /* the reflection's lobe (facet_rho_r) instead of the transmission's */
} slice_target;

typedef struct slice_out {
    tslice s;
    double *w; /* measure weight per node (channel 0), for incidence refinement */
    int budget_hit;
    int nomem;
    size_t evals; /* Eq. 25 evaluations made building it */
} slice_out;

/* Eq. 25 written in facet space for the builder, with the Beckmann factor hoisted per
   row: rho = [s^2/(4 pi) V(ti)/cos ti] e^{-s^2 t^2/4} (1 + t^2)^2 ca Ft chi V(to)/|cos to|,
   t = tan tn, chi = n^2 cb / (ca - n cb)^2. The error estimate evaluates the same
   directions through the kernel of model/kernel.h, so the two check each other.
   Returns rho and sets *w to the measure weight |cos to|/chi * sin tn. In the smith
   model a->pref lacks V(ti) and V(to) becomes G2 (rho_out_shadow: the same product). */
static double facet_rho(double n, double s, double k0, const rho_in *a, double stn,
                        double ctn, double cpsi, double spsi, double beck, double *w)
{
    *w = 0.0;
    facet_ray fr;
    if (!facet_refract(n, a->sin_ti, a->cos_ti, stn, ctn, cpsi, spsi, &fr))
        return 0.0;
    double ca = fr.ca, cb = fr.cb, ox = fr.ox, oy = fr.oy, oz = fr.oz;
    double d = ca - n * cb; /* |v|; nonzero for n != 1 */
    double d1 = ca + n * cb, d2 = n * ca + cb;
    double ft = 2.0 * n * ca * cb * (1.0 / (d1 * d1) + 1.0 / (d2 * d2));
    double chi = n * n * cb / (d * d);
    double st = sqrt(ox * ox + oy * oy);
    double vo = rho_out_shadow(a, st, -oz, s, k0); /* -oz > 0 checked above */
    *w = -oz / chi * stn;
    double r = a->pref * beck * ca * ft * chi * vo / -oz;
    return r >= DBL_MIN ? r : 0.0; /* MODEL.md 3.6 */
}

/* The same for the reflection (MODEL.md section 8) at the facet that mirrors e_i into
   e_r = 2 ca h - e_i: rho_r = [s^2/(4 pi) V(ti)/cos ti] e^{-s^2 t^2/4} (1 + t^2)^2
   Fr V(tr) / (4 cos tr). tn = 0 is the mirror direction, so the nodes that follow the
   refracted lobe in facet space follow the specular lobe here. *w = cos tr 4 ca sin tn
   (d(omega_r) = 4 ca d(omega_h)). */
static double facet_rho_r(double n, double s, double k0, const rho_in *a, double stn,
                          double ctn, double cpsi, double spsi, double beck, double *w)
{
    *w = 0.0;
    double ca, rx, ry, rz;
    if (!facet_mirror(a, stn, ctn, cpsi, spsi, &ca, &rx, &ry, &rz))
        return 0.0; /* no reflected direction in the upper medium */
    double vo = rho_out_shadow_r(a, sqrt(rx * rx + ry * ry), rz, s, k0); /* rz > 0 checked */
    *w = rz * 4.0 * ca * stn;
    double r = a->pref * beck * bt_fresnel_r(n, n - 1.0, ca) * vo / (4.0 * rz);
    return r >= DBL_MIN ? r : 0.0; /* MODEL.md 3.6 */
}

/* Evaluates rho (rho_r when refl; all channels) and the channel-0 measure weight on
   rows x cols. */
static int eval_nodes(const btdf_params *p, int refl, const rho_in *a, const double *rows,
                      size_t nr, const double *cols, size_t nc, double *vals, double *w)
{
    size_t nch = (size_t)p->channels;
    double s = p->smoothness;
    double *cc = malloc(nc * 2 * sizeof(double));
    if (!cc)
        return 0;
    for (size_t j = 0; j < nc; j++) {
        cc[2 * j] = cos(cols[j]);
        cc[2 * j + 1] = sin(cols[j]);
    }
    for (size_t i = 0; i < nr; i++) {
        double stn = sin(rows[i]), ctn = cos(rows[i]);
        /* rows lie in [0, pi/2): ctn > 0; the exponent is cut where exp underflows */
        double t2 = stn * stn / (ctn * ctn), x = 0.25 * s * s * t2;
        double beck = x < BTDF_EXP_CUT ? exp(-x) * (1.0 + t2) * (1.0 + t2) : 0.0;
        for (size_t j = 0; j < nc; j++) {
            for (size_t c = 0; c < nch; c++) {
                double wt;
                vals[(i * nc + j) * nch + c] =
                    !(beck > 0.0) ? (wt = 0.0)
                    : refl ? facet_rho_r(p->ior[c], s, p->k0, a, stn, ctn, cc[2 * j],
                                         cc[2 * j + 1], beck, &wt)
                           : facet_rho(p->ior[c], s, p->k0, a, stn, ctn, cc[2 * j],
                                       cc[2 * j + 1], beck, &wt);
                if (c == 0 && w)
                    w[i * nc + j] = wt;
            }
        }
    }
    free(cc);
    return 1;
}

/* The measure weight an interval's midpoint check uses: the midpoint's own, but at
   least the mean of its ends'. Where the interval crosses the edge of the reachable
   directions (a reflection mirrored below the horizon, a refraction past the critical
   angle) the midpoint can lie beyond it with weight 0 while the part before it, where
   the interpolant is wrong, has weight: the (1/1.5, 3) reflection kept 90% of its
   error in the last 4.5 deg before the horizon, unseen by the checks, and missed 1e-3
   at every pass. */
static double mid_weight(double wmid, double wa, double wb)
{
    return fmax(wmid, 0.5 * (wa + wb));
}

/* Trapezoid weight of node i on a non-uniform axis. */
static double trap(const double *a, size_t m, size_t i)
{
    double lo = i > 0 ? a[i] - a[i - 1] : 0.0, hi = i + 1 < m ? a[i + 1] - a[i] : 0.0;
    return 0.5 * (lo + hi);
}

/* The new node set after bisecting the marked intervals of one axis: for each new
   index, the old index (kind 0) or the interval whose midpoint it is (kind 1). */
typedef struct axis_map {
    size_t *idx;
    unsigned char *mid;
    size_t m;
} axis_map;

static int axis_refine(const double *a, size_t m, const unsigned char *mark, double **out,
                       axis_map *map)
{
    size_t add = 0;
    for (size_t i = 0; i + 1 < m; i++)
        add += mark[i] != 0;
    double *na = malloc((m + add) * sizeof(double));
    map->idx = malloc((m + add) * sizeof(size_t));
    map->mid = malloc(m + add);
    if (!na || !map->idx || !map->mid) {
        free(na);
        return 0;
    }
    size_t k = 0;
    for (size_t i = 0; i < m; i++) {
        map->idx[k] = i;
        map->mid[k] = 0;
        na[k++] = a[i];
        if (i + 1 < m && mark[i]) {
            map->idx[k] = i;
            map->mid[k] = 1;
            na[k++] = 0.5 * (a[i] + a[i + 1]);
        }
    }
    map->m = k;
    *out = na;
    return 1;
}

/* A node's reduced value rho / K; K = 0 where the facet refracts nothing, and rho = 0. */
static double red(double v, double k)
{
    return k > 0.0 ? v / k : 0.0;
}

static void build_slice(const slice_target *tg, slice_out *o)
{
    const btdf_params *p = tg->p;
    size_t nch = (size_t)p->channels;
    memset(o, 0, sizeof *o);
    o->s.ti = tg->ti;
    rho_in a;
    rho_in_init_m(&a, sin(tg->ti), cos(tg->ti), p->smoothness, p->k0, p->model);
    int is_max = tg->metric == BTDF_METRIC_MAX;
    size_t nr = 17, nc = 13, evals = 0; /* evals: points where Eq. 25 was evaluated */
    double *rows = malloc(nr * sizeof(double)), *cols = malloc(nc * sizeof(double));
    double *vals = malloc(nr * nc * nch * sizeof(double)), *w = malloc(nr * nc * sizeof(double));
    /* per pass: midpoints of row intervals x columns (vr, wr) and rows x midpoints of
       column intervals (vc, wc); errors per interval; marks */
    double *vr = NULL, *wr = NULL, *vc = NULL, *wc = NULL, *rm = NULL, *cm = NULL;
    double *er = NULL, *ec = NULL;
    unsigned char *mr = NULL, *mc = NULL;
    if (!rows || !cols || !vals || !w)
        goto nomem;
    for (size_t i = 0; i < nr; i++)
        rows[i] = atan(2.0 * tg->U * (double)i / (double)(nr - 1) / p->smoothness);
    for (size_t j = 0; j < nc; j++)
        cols[j] = M_PI * (double)j / (double)(nc - 1);
    if (!eval_nodes(p, tg->refl, &a, rows, nr, cols, nc, vals, w))
        goto nomem;
    evals = nr * nc;
    for (;;) {
        rm = malloc((nr - 1) * sizeof(double));
        cm = malloc((nc - 1) * sizeof(double));
        vr = malloc((nr - 1) * nc * nch * sizeof(double));
        wr = malloc((nr - 1) * nc * sizeof(double));
        vc = malloc(nr * (nc - 1) * nch * sizeof(double));
        wc = malloc(nr * (nc - 1) * sizeof(double));
        er = calloc(nr, sizeof(double));
        ec = calloc(nc, sizeof(double));
        mr = calloc(nr, 1);
        mc = calloc(nc, 1);
        if (!rm || !cm || !vr || !wr || !vc || !wc || !er || !ec || !mr || !mc)
            goto nomem;
        for (size_t i = 0; i + 1 < nr; i++)
            rm[i] = 0.5 * (rows[i] + rows[i + 1]);
        for (size_t j = 0; j + 1 < nc; j++)
            cm[j] = 0.5 * (cols[j] + cols[j + 1]);
        if (!eval_nodes(p, tg->refl, &a, rm, nr - 1, cols, nc, vr, wr) ||
            !eval_nodes(p, tg->refl, &a, rows, nr, cm, nc - 1, vc, wc))
            goto nomem;
        evals += (nr - 1) * nc + nr * (nc - 1);
        /* The table's rule (BTDF_RULE_CHI) interpolates rho / K, K = chi_shape(n, e_i.h):
           the error of an interval is that of the reduced values, times K at the midpoint.
           The reflection's (BTDF_RULE_FRESNEL) has K = Fr(e_i.h). */
        btdf_table_rule rl = tg->refl ? BTDF_RULE_FRESNEL : BTDF_RULE_CHI;
        double *sr = malloc((2 * nr + nc + 2 * (nr - 1) + (nc - 1)) * sizeof(double));
        if (!sr)
            goto nomem;
        double *cr = sr + nr, *cp = cr + nr, *smr = cp + nc, *cmr = smr + (nr - 1),
               *cpm = cmr + (nr - 1);
        for (size_t i = 0; i < nr; i++) {
            sr[i] = sin(rows[i]);
            cr[i] = cos(rows[i]);
        }
        for (size_t i = 0; i + 1 < nr; i++) {
            smr[i] = sin(rm[i]);
            cmr[i] = cos(rm[i]);
        }
        for (size_t j = 0; j < nc; j++)
            cp[j] = cos(cols[j]);
        for (size_t j = 0; j + 1 < nc; j++)
            cpm[j] = cos(cm[j]);
        double sti = a.sin_ti, cti = a.cos_ti;
        /* the model's node factors beside K (table.h; 1 for xu-sun, so its bits stay) */
#define NODE_F(stn_, ctn_, cpsi_)                                                          \
    (smodel ? model_node_factor(p, tg->refl, n, sti, cti, (stn_), (ctn_), (cpsi_)) : 1.0)
        int smodel = p->model != BTDF_MODEL_XU_SUN;
        double vmax = 0.0;
        for (size_t q = 0; q < nr * nc * nch; q++)
            vmax = fmax(vmax, vals[q]);
        /* vmax = 0 means the slice is empty (grazing incidence): nothing to refine. */
        double norm = is_max ? (vmax > 0.0 ? 1.0 / vmax : 0.0) : 1.0;
        double total = 0.0, worst = 0.0;
        /* Per interval, the worst channel (the metric's, MODEL.md 6), not their sum. */
        for (size_t i = 0; i + 1 < nr; i++) {
            double ech[BTDF_MAX_CHANNELS] = {0.0, 0.0, 0.0};
            for (size_t j = 0; j < nc; j++)
                for (size_t c = 0; c < nch; c++) {
                    double n = p->ior[c];
                    double k0 = rule_factor(rl, n, sr[i] * cp[j] * sti + cr[i] * cti) *
                                NODE_F(sr[i], cr[i], cp[j]);
                    double k1 = rule_factor(rl, n, sr[i + 1] * cp[j] * sti + cr[i + 1] * cti) *
                                NODE_F(sr[i + 1], cr[i + 1], cp[j]);
                    double km = rule_factor(rl, n, smr[i] * cp[j] * sti + cmr[i] * cti) *
                                NODE_F(smr[i], cmr[i], cp[j]);
                    double lin = 0.5 * km * (red(vals[(i * nc + j) * nch + c], k0) +
                                             red(vals[((i + 1) * nc + j) * nch + c], k1));
                    double d = fabs(vr[(i * nc + j) * nch + c] - lin);
                    if (is_max)
                        ech[c] = fmax(ech[c], d * norm);
                    else
                        ech[c] += d * mid_weight(wr[i * nc + j], w[i * nc + j], w[(i + 1) * nc + j]) *
                                  trap(cols, nc, j) * (rows[i + 1] - rows[i]) * 2.0;
                }
            double e = fmax(ech[0], fmax(ech[1], ech[2]));
            er[i] = e;
            total += e;
            worst = fmax(worst, e);
        }
        for (size_t j = 0; j + 1 < nc; j++) {
            double ech[BTDF_MAX_CHANNELS] = {0.0, 0.0, 0.0};
            for (size_t i = 0; i < nr; i++)
                for (size_t c = 0; c < nch; c++) {
                    double n = p->ior[c];
                    double k0 = rule_factor(rl, n, sr[i] * cp[j] * sti + cr[i] * cti) *
                                NODE_F(sr[i], cr[i], cp[j]);
                    double k1 = rule_factor(rl, n, sr[i] * cp[j + 1] * sti + cr[i] * cti) *
                                NODE_F(sr[i], cr[i], cp[j + 1]);
                    double km = rule_factor(rl, n, sr[i] * cpm[j] * sti + cr[i] * cti) *
                                NODE_F(sr[i], cr[i], cpm[j]);
                    double lin = 0.5 * km * (red(vals[(i * nc + j) * nch + c], k0) +
                                             red(vals[(i * nc + j + 1) * nch + c], k1));
                    double d = fabs(vc[(i * (nc - 1) + j) * nch + c] - lin);
                    if (is_max)
                        ech[c] = fmax(ech[c], d * norm);
                    else
                        ech[c] += d * mid_weight(wc[i * (nc - 1) + j], w[i * nc + j], w[i * nc + j + 1]) *
                                  trap(rows, nr, i) * (cols[j + 1] - cols[j]) * 2.0;
                }
            double e = fmax(ech[0], fmax(ech[1], ech[2]));
            ec[j] = e;
            total += e;
            worst = fmax(worst, e);
        }
        free(sr);
        if ((is_max ? worst : total) <= tg->target)
            break;
        /* Bisect every interval above its average share (for max: above the target). */
        double thresh = is_max ? tg->target : tg->target / (double)(nr - 1 + nc - 1);
        size_t add_r = 0, add_c = 0;
        for (size_t i = 0; i + 1 < nr; i++)
            if (er[i] > thresh && rows[i + 1] - rows[i] > 1e-12) {
                mr[i] = 1;
                add_r++;
            }
        for (size_t j = 0; j + 1 < nc; j++)
            if (ec[j] > thresh && cols[j + 1] - cols[j] > 1e-12) {
                mc[j] = 1;
                add_c++;
            }
        if (add_r + add_c == 0)
            break; /* intervals at 1e-12 rad: finer nodes cannot be told apart */
        if ((nr + add_r) * (nc + add_c) > tg->max_nodes) {
            o->budget_hit = BUDGET_SLICE; /* cannot refine further within the budget */
            break;
        }
        /* The new grid reuses every value already computed: old nodes, and the
           midpoints just evaluated; only (new row, new column) crossings are new. */
        axis_map ra = {0}, ca = {0};
        double *nrows = NULL, *ncols = NULL;
        int ok = axis_refine(rows, nr, mr, &nrows, &ra) && axis_refine(cols, nc, mc, &ncols, &ca);
        size_t NR = ra.m, NC = ca.m;
        double *nv = ok ? malloc(NR * NC * nch * sizeof(double)) : NULL;
        double *nw = ok ? malloc(NR * NC * sizeof(double)) : NULL;
        double *cross = ok ? malloc(nch * sizeof(double)) : NULL;
        if (!nv || !nw || !cross) {
            free(ra.idx); free(ra.mid); free(ca.idx); free(ca.mid);
            free(nrows); free(ncols); free(nv); free(nw); free(cross);
            goto nomem;
        }
        for (size_t I = 0; I < NR; I++) {
            size_t i = ra.idx[I];
            for (size_t J = 0; J < NC; J++) {
                size_t j = ca.idx[J];
                const double *src;
                double sw = 0.0;
                if (!ra.mid[I] && !ca.mid[J]) {
                    src = vals + (i * nc + j) * nch;
                    sw = w[i * nc + j];
                } else if (ra.mid[I] && !ca.mid[J]) {
                    src = vr + (i * nc + j) * nch;
                    sw = wr[i * nc + j];
                } else if (!ra.mid[I]) {
                    src = vc + (i * (nc - 1) + j) * nch;
                    sw = wc[i * (nc - 1) + j];
                } else {
                    eval_nodes(p, tg->refl, &a, &nrows[I], 1, &ncols[J], 1, cross, &sw); /* no alloc fail: nc = 1 */
                    evals++;
                    src = cross;
                }
                memcpy(nv + (I * NC + J) * nch, src, nch * sizeof(double));
                nw[I * NC + J] = sw;
            }
        }
        free(ra.idx); free(ra.mid); free(ca.idx); free(ca.mid); free(cross);
        free(rows); free(cols); free(vals); free(w);
        rows = nrows; cols = ncols; vals = nv; w = nw;
        nr = NR; nc = NC;
        free(rm); free(cm); free(vr); free(wr); free(vc); free(wc);
        free(er); free(ec); free(mr); free(mc);
        rm = cm = vr = wr = vc = wc = er = ec = NULL;
        mr = mc = NULL;
    }
    free(rm); free(cm); free(vr); free(wr); free(vc); free(wc);
    free(er); free(ec); free(mr); free(mc);
    o->s.nr = nr;
    o->s.nc = nc;
    o->s.rows = rows;
    o->s.cols = cols;
    o->s.vals = vals;
    o->w = w;
    o->evals = evals;
    return;
nomem:
    free(rows); free(cols); free(vals); free(w);
    free(rm); free(cm); free(vr); free(wr); free(vc); free(wc);
    free(er); free(ec); free(mr); free(mc);
    memset(o, 0, sizeof *o);
    o->nomem = 1;
}
#undef NODE_F

typedef struct facet_job {
    const btdf_table_opts *o;
    double frac_slice;
    double U;
    size_t max_nodes;
    const size_t *max_each; /* per slice to build, when not NULL: its own node limit */
    const double *ti;
    slice_out *out;
} facet_job;

static void free_slice_out(slice_out *s);

/* The part being built (BOTH never reaches the builder: it builds each part). */
static int opts_refl(const btdf_table_opts *o)
{
    return o->part == BTDF_PART_REFLECTION;
}

/* T(ti), or R(ti) for the reflection, coarse. */
static double part_coarse(const btdf_table_opts *o, double ti)
{
    return opts_refl(o) ? btdf_reflectance_coarse(&o->params, ti)
                        : btdf_transmittance_coarse(&o->params, ti);
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
    tg.refl = opts_refl(o);
    tg.target = o->tolerance * j->frac_slice *
                (o->metric == BTDF_METRIC_MAX ? 1.0 : t_floor(o, tg.ti));
    build_slice(&tg, &j->out[k]);
    /* The rule's node geometry, for blend_error's interpolation between slices. */
    btdf_table rule;
    memset(&rule, 0, sizeof rule);
    rule.kind = tg.refl ? BTDF_TABLE_FACET_REFLECTION : BTDF_TABLE_FACET;
    rule.rule = tg.refl ? BTDF_RULE_FRESNEL : BTDF_RULE_CHI;
    rule.p = *tg.p; /* the model's node factors too */
    if (!j->out[k].nomem && j->out[k].s.vals && !slice_prepare(&rule, &j->out[k].s)) {
        free_slice_out(&j->out[k]);
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
    int refl = opts_refl(o);
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
        double tw = trap(s->rows, s->nr, i), stn = sin(s->rows[i]), ctn = cos(s->rows[i]);
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
                ech[c] += d * M->w[i * s->nc + j] * tw * trap(s->cols, s->nc, j) * 2.0;
            }
        }
    }
    if (o->metric == BTDF_METRIC_MAX)
        return vmax > 0.0 ? dmax / vmax : 0.0; /* empty slices have no max error */
    return fmax(ech[0], fmax(ech[1], ech[2])) / t_floor(o, M->s.ti);
}

static void free_slice_out(slice_out *s)
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

/* build_slice's first grid: no slice has fewer nodes. */
#define SLICE_MIN_NODES ((size_t)17 * 13)

/* The node budget of an adaptive build, a bound at every moment of it: max_samples
   nodes, and max_bytes at (channels + 1) doubles a node (the values and the measure
   weight held while building). */
static size_t facet_node_cap(const btdf_table_opts *o)
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
    return facet_node_cap(o) < max_samples ? BUDGET_MEMORY : BUDGET_SAMPLES;
}

/* Incidence slices of the first pass, at most 5 degrees apart. */
static size_t facet_first_slices(const btdf_table_opts *o)
{
    double span = o->ti_max - o->ti_min;
    return span > 0.0 ? (size_t)ceil(span / (5.0 * M_PI / 180.0)) + 1 : 1;
}

/* One adaptive build with the given shares of the tolerance. */
static btdf_status build_facet_pass(const btdf_table_opts *o, double frac_slice,
                                    double frac_ti, btdf_table *t, int *budget_hit,
                                    size_t *evals)
{
    size_t node_cap = facet_node_cap(o);
    /* Tail: facets with u > U carry a fraction exp(-U^2) of the facet distribution; U
       puts that below a tenth of the tolerance. */
    double U = sqrt(log(10.0 / o->tolerance)) + 1.0;
    size_t per_slice = node_cap / 8 > 1000 ? node_cap / 8 : 1000;
    facet_job j = {o, frac_slice, U, per_slice < node_cap ? per_slice : node_cap, NULL, NULL,
                   NULL};
    double span = o->ti_max - o->ti_min;
    size_t n0 = facet_first_slices(o); /* btdf_table_build checked n0 slices fit */
    size_t cap = n0, ns = n0;
    slice_out *sl = calloc(cap, sizeof *sl);
    double *tis = malloc(cap * sizeof(double));
    if (!sl || !tis) {
        free(sl);
        free(tis);
        return BTDF_ENOMEM;
    }
    for (size_t k = 0; k < n0; k++)
        tis[k] = n0 > 1 ? o->ti_min + span * (double)k / (double)(n0 - 1) : o->ti_min;
    j.ti = tis;
    j.out = sl;
    if (o->progress)
        o->progress(o->progress_user, "slices", 0, n0);
    core_parallel_for(o->threads, n0, facet_slice_job, &j);
    btdf_status st = BTDF_OK;
    size_t nodes = 0;
    for (size_t k = 0; k < ns; k++)
        nodes += sl[k].s.nr * sl[k].s.nc;
    if (nodes > node_cap) { /* the first slices alone overran: again, each a share */
        for (size_t k = 0; k < ns; k++) {
            *evals += sl[k].evals;
            free_slice_out(&sl[k]);
        }
        j.max_nodes = node_cap / n0;
        *budget_hit |= facet_limit(o);
        core_parallel_for(o->threads, n0, facet_slice_job, &j);
    }
    nodes = 0;
    for (size_t k = 0; k < ns; k++) {
        *evals += sl[k].evals;
        if (sl[k].nomem)
            st = BTDF_ENOMEM;
        *budget_hit |= sl[k].budget_hit;
        nodes += sl[k].s.nr * sl[k].s.nc;
    }
    /* Incidence refinement in rounds: test the midpoint of every open interval. */
    unsigned char *open = malloc(ns ? ns : 1);
    if (!open)
        st = BTDF_ENOMEM;
    for (size_t k = 0; k + 1 < ns && open; k++)
        open[k] = 1;
    /* rad: finer incidence steps buy nothing a renderer can see, except where V(ti)
       falls from 1 to 0 before grazing, over a width of order 1/s rad */
    double min_gap = fmin(1e-4, 1e-2 / o->params.smoothness);
    while (st == BTDF_OK) {
        size_t nt = 0;
        for (size_t k = 0; k + 1 < ns; k++)
            if (open[k] && sl[k + 1].s.ti - sl[k].s.ti > 2 * min_gap)
                nt++;
        if (nt == 0)
            break;
        if (o->progress) /* ns slices built, nt midpoints to test now */
            o->progress(o->progress_user, "incidence angles", ns, nt);
        double *mt = malloc(nt * sizeof(double));
        size_t *at = malloc(nt * sizeof(size_t));
        slice_out *cand = calloc(nt, sizeof *cand);
        double *ecand = calloc(nt, sizeof *ecand);
        unsigned char *taken = calloc(nt, 1);
        size_t *need = malloc(nt * sizeof(size_t));
        if (!mt || !at || !cand || !ecand || !taken || !need) {
            free(need);
            free(mt);
            free(at);
            free(cand);
            free(ecand);
            free(taken);
            st = BTDF_ENOMEM;
            break;
        }
        size_t q = 0;
        for (size_t k = 0; k + 1 < ns; k++)
            if (open[k] && sl[k + 1].s.ti - sl[k].s.ti > 2 * min_gap) {
                mt[q] = 0.5 * (sl[k].s.ti + sl[k + 1].s.ti);
                at[q++] = k;
            }
        /* Room for the candidates, each by its neighbours' sizes: a slice between two
           others needs about as many nodes as the larger of them (a quarter more, for
           what lies between). When the room left cannot hold every candidate so, test
           only those it can, the widest intervals first (the others stay open): equal
           shares too small for some would stop them short and end refinement with the
           budget far from spent. What room is left over is shared in proportion. */
        size_t left = nodes < node_cap ? node_cap - nodes : 0;
        double total = 0.0;
        for (q = 0; q < nt; q++) {
            size_t a = sl[at[q]].s.nr * sl[at[q]].s.nc, b = sl[at[q] + 1].s.nr * sl[at[q] + 1].s.nc;
            size_t m = a > b ? a : b;
            m += m / 4;
            m = m < SLICE_MIN_NODES ? SLICE_MIN_NODES : m;
            need[q] = m < j.max_nodes ? m : j.max_nodes;
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
            size_t r = share < (double)j.max_nodes ? (size_t)share : j.max_nodes;
            need[q] = r;
            short_room |= r < SLICE_MIN_NODES;
        }
        j.ti = mt;
        j.out = cand;
        /* The candidates are held beside the slices: together they stay in the budget. */
        if (short_room) {
            *budget_hit |= facet_limit(o);
            free(mt);
            free(at);
            free(cand);
            free(ecand);
            free(taken);
            free(need);
            break;
        }
        size_t saved_max = j.max_nodes;
        j.max_each = need;
        core_parallel_for(o->threads, nt, facet_slice_job, &j);
        j.max_nodes = saved_max;
        j.max_each = NULL;
        size_t keep = 0;
        for (q = 0; q < nt; q++)
            *evals += cand[q].evals;
        for (q = 0; q < nt; q++) {
            if (cand[q].nomem) {
                st = BTDF_ENOMEM;
                continue;
            }
            size_t k = at[q];
            double e = blend_error(o, &sl[k], &sl[k + 1], &cand[q]);
            /* Where the floor max(T, 0.01) changes by more than a factor 1.5 over an
               interval (the last degrees before grazing, past a critical angle), the
               error relative to it is far from symmetric about the midpoint, and the
               midpoint test misses the peak: such intervals are split regardless. */
            if (o->metric == BTDF_METRIC_L1) {
                double fa = t_floor(o, sl[k].s.ti), fb = t_floor(o, sl[k + 1].s.ti);
                if (fmax(fa, fb) > 1.5 * fmin(fa, fb))
                    e = fmax(e, 2.0 * o->tolerance * frac_ti);
            }
            /* Next to a slice whose incident factor is 0 (ti = 90 deg) the table holds the
               other end's reduced value (table.c, blend_ti); that is off by up to the
               whole of T there, and the error peaks well before the midpoint. Bound it
               by T at the other end over the floor (L1), or by whether e_max is defined
               there at all (max), and split until the bound is met. */
            int za = !(incident_factor(&o->params, sl[k].s.ti) > 0.0);
            int zb = !(incident_factor(&o->params, sl[k + 1].s.ti) > 0.0);
            if (za != zb) {
                double tother = part_coarse(o, sl[za ? k + 1 : k].s.ti);
                double bound = o->metric == BTDF_METRIC_L1 ? tother / 0.01
                                                             : (tother >= 0.01 ? 1.0 : 0.0);
                e = fmax(e, bound);
            }
            ecand[q] = e;
            if (e > o->tolerance * frac_ti)
                keep++;
            else {
                open[k] = 0;
                free_slice_out(&cand[q]);
            }
        }
        if (st == BTDF_OK && keep) {
            size_t add_nodes = 0;
            for (q = 0; q < nt; q++)
                add_nodes += cand[q].s.nr * cand[q].s.nc;
            if (nodes + add_nodes > node_cap) {
                /* Not all fit: add the worst intervals' slices while they fit, so the
                   budget goes where the error is, and close the others. */
                *budget_hit |= facet_limit(o);
                size_t room = nodes < node_cap ? node_cap - nodes : 0;
                keep = 0;
                for (;;) {
                    size_t best = nt;
                    for (q = 0; q < nt; q++)
                        if (cand[q].s.vals && !taken[q] &&
                            (best == nt || ecand[q] > ecand[best]))
                            best = q;
                    if (best == nt)
                        break;
                    taken[best] = 1;
                    size_t m = cand[best].s.nr * cand[best].s.nc;
                    if (m <= room) {
                        room -= m;
                        keep++;
                    } else {
                        open[at[best]] = 0;
                        free_slice_out(&cand[best]);
                    }
                }
            }
        }
        if (st == BTDF_OK && keep) {
            slice_out *ns_sl = realloc(sl, (ns + keep) * sizeof *sl);
            unsigned char *no = ns_sl ? realloc(open, ns + keep) : NULL;
            if (ns_sl)
                sl = ns_sl;
            if (!ns_sl || !no) {
                st = BTDF_ENOMEM;
            } else {
                open = no;
                /* Intervals still open (not tested this round: the room held only some
                   candidates) stay open; the left end names each, as none was split. */
                double *still = malloc(ns * sizeof(double));
                size_t nst = 0;
                for (size_t k = 0; k + 1 < ns && still; k++)
                    if (open[k])
                        still[nst++] = sl[k].s.ti;
                /* Old intervals that were split stay open as their two halves. */
                for (q = 0; q < nt; q++) {
                    if (cand[q].s.vals) {
                        sl[ns] = cand[q];
                        *budget_hit |= cand[q].budget_hit;
                        nodes += cand[q].s.nr * cand[q].s.nc;
                        memset(&cand[q], 0, sizeof cand[q]);
                        ns++;
                    }
                }
                /* Re-sort by ti and mark which intervals remain open: an interval is
                   open when one of its ends was just added, or it was open and untested. */
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
                if (!fresh || !still)
                    st = BTDF_ENOMEM;
            }
        } else if (st == BTDF_OK && !keep) {
            for (q = 0; q < nt; q++)
                free_slice_out(&cand[q]);
            if (*budget_hit)
                for (size_t k = 0; k + 1 < ns; k++)
                    open[k] = 0;
        }
        for (q = 0; q < nt; q++)
            free_slice_out(&cand[q]);
        free(cand);
        free(ecand);
        free(taken);
        free(need);
        free(mt);
        free(at);
    }
    free(open);
    for (size_t k = 0; k < ns; k++) {
        free(sl[k].w);
        sl[k].w = NULL;
        if (st == BTDF_OK) {
            if (table_push_slice(t, &sl[k].s) != BTDF_OK) {
                st = BTDF_ENOMEM;
                free_slice_out(&sl[k]);
            }
        } else {
            free_slice_out(&sl[k]);
        }
    }
    free(sl);
    free(tis);
    return st;
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
                     100.0 * (double)samples / (double)facet_node_cap(o));
    if (w > 0 && (size_t)w < msglen && isfinite(e)) /* e is NaN when not estimated */
        snprintf(msg + w, msglen - (size_t)w, " and reached %.3g, %.2f times the tolerance %g",
                 e, e / tol, tol);
}

/* One part: the transmission, or the reflection when o->part is REFLECTION. */
static btdf_status build_part(const btdf_table_opts *o, btdf_table **out, char *msg,
                              size_t msglen)
{
    int refl = opts_refl(o);
    btdf_table_kind kind = refl ? BTDF_TABLE_FACET_REFLECTION : o->kind;
    btdf_table *t;
    btdf_status st = btdf_table_new(kind, &o->params, &t, msg, msglen);
    if (st != BTDF_OK)
        return st;
    if (o->kind != BTDF_TABLE_GRID)
        t->rule = refl ? BTDF_RULE_FRESNEL : BTDF_RULE_CHI; /* btdf.h: adaptive tables interpolate rho / K */
    if (o->kind == BTDF_TABLE_GRID) {
        st = build_grid(o, t, msg, msglen);
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
    size_t first = facet_first_slices(&ob) * SLICE_MIN_NODES;
    if (first > facet_node_cap(&ob)) {
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
        t->kind = BTDF_TABLE_FACET;
        t->p = ob.params;
        budget_hit = 0;
        st = build_facet_pass(&ob, fs, ft, t, &budget_hit, &evals);
        t->kind = recip ? BTDF_TABLE_FACET_RECIPROCAL : kind;
        t->p = o->params;
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
            st = btdf_table_new(kind, &o->params, &fresh, msg, msglen);
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
    if (o->part != BTDF_PART_BOTH)
        return build_part(o, out, msg, msglen);
    /* Both parts: each its own table, refined to the tolerance with the whole budget;
       the reflection is attached to the transmission. A part the budget stopped makes
       the whole BTDF_EBUDGET, with that part's message. */
    btdf_table_opts ot = *o, orr = *o;
    ot.part = BTDF_PART_TRANSMISSION;
    orr.part = BTDF_PART_REFLECTION;
    char mt[512] = "", mr[512] = "";
    btdf_table *t = NULL, *r = NULL;
    btdf_status st_t = build_part(&ot, &t, mt, sizeof mt);
    if (st_t != BTDF_OK && st_t != BTDF_EBUDGET) {
        if (msg && msglen)
            snprintf(msg, msglen, "transmission: %s", mt);
        return st_t;
    }
    btdf_status st_r = build_part(&orr, &r, mr, sizeof mr);
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
