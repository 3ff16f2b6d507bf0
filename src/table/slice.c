/* SPDX-License-Identifier: MIT */
/* slice.c: one facet-space slice of the adaptive table, its rows and columns bisected
   where the linear rule misses the target (the scheme in build.h). */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "table/build.h"


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
    int up = facet_mirror(a, stn, ctn, cpsi, spsi, &ca, &rx, &ry, &rz);
    if (!up && !(a->model != BTDF_MODEL_XU_SUN && ca > 0.0))
        return 0.0; /* no reflected direction in the upper medium */
    if (!up) {
        /* smith: its rho_r stays finite at the horizon (G2 ~ cos tr), so a node whose
           facet mirrors below it holds the value at the mirror image (|rz|, floored at
           1e-9 as model_dir_factor floors it): continued, not cut to 0, so that the
           interpolant sees the smooth Beckmann factor. Weight 0: no direction there. */
        rz = fabs(rz) > 1e-9 ? fabs(rz) : 1e-9;
    }
    double vo = rho_out_shadow_r(a, sqrt(rx * rx + ry * ry), rz, s, k0); /* rz > 0 */
    *w = up ? rz * 4.0 * ca * stn : 0.0;
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
double tb_trap(const double *a, size_t m, size_t i)
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

/* The nodes of one slice while it is refined: rows x cols, values (all channels) and
   the channel-0 measure weight. */
typedef struct slice_grid {
    double *rows, *cols, *vals, *w;
    size_t nr, nc;
} slice_grid;

/* One refinement pass: the midpoints of row intervals x columns (vr, wr) and rows x
   midpoints of column intervals (vc, wc), the error of every interval (er, ec) and the
   marks of those to bisect (mr, mc). */
typedef struct slice_pass {
    double *rm, *cm, *vr, *wr, *vc, *wc, *er, *ec;
    unsigned char *mr, *mc;
} slice_pass;

static void slice_pass_free(slice_pass *ps)
{
    free(ps->rm); free(ps->cm); free(ps->vr); free(ps->wr); free(ps->vc); free(ps->wc);
    free(ps->er); free(ps->ec); free(ps->mr); free(ps->mc);
    memset(ps, 0, sizeof *ps);
}

static void slice_grid_free(slice_grid *g)
{
    free(g->rows); free(g->cols); free(g->vals); free(g->w);
    memset(g, 0, sizeof *g);
}

/* The pass's midpoints and their values; 0 when out of memory. */
static int slice_pass_eval(const slice_target *tg, const rho_in *a, const slice_grid *g,
                           slice_pass *ps, size_t *evals)
{
    const btdf_params *p = tg->p;
    size_t nch = (size_t)p->channels, nr = g->nr, nc = g->nc;
    ps->rm = malloc((nr - 1) * sizeof(double));
    ps->cm = malloc((nc - 1) * sizeof(double));
    ps->vr = malloc((nr - 1) * nc * nch * sizeof(double));
    ps->wr = malloc((nr - 1) * nc * sizeof(double));
    ps->vc = malloc(nr * (nc - 1) * nch * sizeof(double));
    ps->wc = malloc(nr * (nc - 1) * sizeof(double));
    ps->er = calloc(nr, sizeof(double));
    ps->ec = calloc(nc, sizeof(double));
    ps->mr = calloc(nr, 1);
    ps->mc = calloc(nc, 1);
    if (!ps->rm || !ps->cm || !ps->vr || !ps->wr || !ps->vc || !ps->wc || !ps->er ||
        !ps->ec || !ps->mr || !ps->mc)
        return 0;
    for (size_t i = 0; i + 1 < nr; i++)
        ps->rm[i] = 0.5 * (g->rows[i] + g->rows[i + 1]);
    for (size_t j = 0; j + 1 < nc; j++)
        ps->cm[j] = 0.5 * (g->cols[j] + g->cols[j + 1]);
    if (!eval_nodes(p, tg->refl, a, ps->rm, nr - 1, g->cols, nc, ps->vr, ps->wr) ||
        !eval_nodes(p, tg->refl, a, g->rows, nr, ps->cm, nc - 1, ps->vc, ps->wc))
        return 0;
    *evals += (nr - 1) * nc + nr * (nc - 1);
    return 1;
}

/* The error of every row and column interval (er, ec): the linear interpolant of the
   table's rule against the value at the midpoint, per interval the worst channel (the
   metric's, MODEL.md 6), not their sum. Sets the sum and the largest; 0 when out of
   memory. */
static int slice_pass_errors(const slice_target *tg, const rho_in *a, const slice_grid *g,
                             slice_pass *ps, double *total_out, double *worst_out)
{
    const btdf_params *p = tg->p;
    size_t nch = (size_t)p->channels, nr = g->nr, nc = g->nc;
    const double *rows = g->rows, *cols = g->cols, *vals = g->vals, *w = g->w;
    int is_max = tg->metric == BTDF_METRIC_MAX;
    /* The table's rule (BTDF_RULE_CHI) interpolates rho / K, K = chi_shape(n, e_i.h):
       the error of an interval is that of the reduced values, times K at the midpoint.
       The reflection's (BTDF_RULE_FRESNEL) has K = Fr(e_i.h). */
    btdf_table_rule rl = tg->refl ? BTDF_RULE_FRESNEL : BTDF_RULE_CHI;
    double *sr = malloc((2 * nr + nc + 2 * (nr - 1) + (nc - 1)) * sizeof(double));
    if (!sr)
        return 0;
    double *cr = sr + nr, *cp = cr + nr, *smr = cp + nc, *cmr = smr + (nr - 1),
           *cpm = cmr + (nr - 1);
    for (size_t i = 0; i < nr; i++) {
        sr[i] = sin(rows[i]);
        cr[i] = cos(rows[i]);
    }
    for (size_t i = 0; i + 1 < nr; i++) {
        smr[i] = sin(ps->rm[i]);
        cmr[i] = cos(ps->rm[i]);
    }
    for (size_t j = 0; j < nc; j++)
        cp[j] = cos(cols[j]);
    for (size_t j = 0; j + 1 < nc; j++)
        cpm[j] = cos(ps->cm[j]);
    double sti = a->sin_ti, cti = a->cos_ti;
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
                double d = fabs(ps->vr[(i * nc + j) * nch + c] - lin);
                if (is_max)
                    ech[c] = fmax(ech[c], d * norm);
                else
                    ech[c] += d * mid_weight(ps->wr[i * nc + j], w[i * nc + j],
                                             w[(i + 1) * nc + j]) *
                              tb_trap(cols, nc, j) * (rows[i + 1] - rows[i]) * 2.0;
            }
        double e = fmax(ech[0], fmax(ech[1], ech[2]));
        ps->er[i] = e;
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
                double d = fabs(ps->vc[(i * (nc - 1) + j) * nch + c] - lin);
                if (is_max)
                    ech[c] = fmax(ech[c], d * norm);
                else
                    ech[c] += d * mid_weight(ps->wc[i * (nc - 1) + j], w[i * nc + j],
                                             w[i * nc + j + 1]) *
                              tb_trap(rows, nr, i) * (cols[j + 1] - cols[j]) * 2.0;
            }
        double e = fmax(ech[0], fmax(ech[1], ech[2]));
        ps->ec[j] = e;
        total += e;
        worst = fmax(worst, e);
    }
#undef NODE_F
    free(sr);
    *total_out = total;
    *worst_out = worst;
    return 1;
}

/* The grid after bisecting the marked intervals. It reuses every value already
   computed: old nodes, and the midpoints just evaluated; only (new row, new column)
   crossings are new. Replaces g; 0 when out of memory (g unchanged). */
static int slice_regrid(const slice_target *tg, const rho_in *a, slice_grid *g,
                        const slice_pass *ps, size_t *evals)
{
    const btdf_params *p = tg->p;
    size_t nch = (size_t)p->channels, nc = g->nc;
    axis_map ra = {0}, ca = {0};
    double *nrows = NULL, *ncols = NULL;
    int ok = axis_refine(g->rows, g->nr, ps->mr, &nrows, &ra) &&
             axis_refine(g->cols, g->nc, ps->mc, &ncols, &ca);
    size_t NR = ra.m, NC = ca.m;
    double *nv = ok ? malloc(NR * NC * nch * sizeof(double)) : NULL;
    double *nw = ok ? malloc(NR * NC * sizeof(double)) : NULL;
    double *cross = ok ? malloc(nch * sizeof(double)) : NULL;
    if (!nv || !nw || !cross) {
        free(ra.idx); free(ra.mid); free(ca.idx); free(ca.mid);
        free(nrows); free(ncols); free(nv); free(nw); free(cross);
        return 0;
    }
    for (size_t I = 0; I < NR; I++) {
        size_t i = ra.idx[I];
        for (size_t J = 0; J < NC; J++) {
            size_t j = ca.idx[J];
            const double *src;
            double sw = 0.0;
            if (!ra.mid[I] && !ca.mid[J]) {
                src = g->vals + (i * nc + j) * nch;
                sw = g->w[i * nc + j];
            } else if (ra.mid[I] && !ca.mid[J]) {
                src = ps->vr + (i * nc + j) * nch;
                sw = ps->wr[i * nc + j];
            } else if (!ra.mid[I]) {
                src = ps->vc + (i * (nc - 1) + j) * nch;
                sw = ps->wc[i * (nc - 1) + j];
            } else {
                /* no allocation to fail: one column */
                eval_nodes(p, tg->refl, a, &nrows[I], 1, &ncols[J], 1, cross, &sw);
                (*evals)++;
                src = cross;
            }
            memcpy(nv + (I * NC + J) * nch, src, nch * sizeof(double));
            nw[I * NC + J] = sw;
        }
    }
    free(ra.idx); free(ra.mid); free(ca.idx); free(ca.mid); free(cross);
    slice_grid_free(g);
    g->rows = nrows;
    g->cols = ncols;
    g->vals = nv;
    g->w = nw;
    g->nr = NR;
    g->nc = NC;
    return 1;
}

/* One slice at tg->ti: a 17 x 13 grid (rows uniform in u up to U, columns in psi),
   then passes that bisect every interval above its average share of the target (for
   max: above the target) until the target or the node budget is met. */
void tb_build_slice(const slice_target *tg, slice_out *o)
{
    const btdf_params *p = tg->p;
    memset(o, 0, sizeof *o);
    o->s.ti = tg->ti;
    rho_in a;
    rho_in_init_m(&a, sin(tg->ti), cos(tg->ti), p->smoothness, p->k0, p->model);
    int is_max = tg->metric == BTDF_METRIC_MAX;
    size_t evals = 0; /* points where Eq. 25 was evaluated */
    slice_grid g = {0};
    slice_pass ps = {0};
    g.nr = 17;
    g.nc = 13;
    size_t nch = (size_t)p->channels;
    g.rows = malloc(g.nr * sizeof(double));
    g.cols = malloc(g.nc * sizeof(double));
    g.vals = malloc(g.nr * g.nc * nch * sizeof(double));
    g.w = malloc(g.nr * g.nc * sizeof(double));
    if (!g.rows || !g.cols || !g.vals || !g.w)
        goto nomem;
    for (size_t i = 0; i < g.nr; i++)
        g.rows[i] = atan(2.0 * tg->U * (double)i / (double)(g.nr - 1) / p->smoothness);
    for (size_t j = 0; j < g.nc; j++)
        g.cols[j] = M_PI * (double)j / (double)(g.nc - 1);
    if (!eval_nodes(p, tg->refl, &a, g.rows, g.nr, g.cols, g.nc, g.vals, g.w))
        goto nomem;
    evals = g.nr * g.nc;
    for (;;) {
        double total, worst;
        if (!slice_pass_eval(tg, &a, &g, &ps, &evals) ||
            !slice_pass_errors(tg, &a, &g, &ps, &total, &worst))
            goto nomem;
        if ((is_max ? worst : total) <= tg->target)
            break;
        /* Bisect every interval above its average share (for max: above the target). */
        size_t nr = g.nr, nc = g.nc;
        double thresh = is_max ? tg->target : tg->target / (double)(nr - 1 + nc - 1);
        size_t add_r = 0, add_c = 0;
        for (size_t i = 0; i + 1 < nr; i++)
            if (ps.er[i] > thresh && g.rows[i + 1] - g.rows[i] > 1e-12) {
                ps.mr[i] = 1;
                add_r++;
            }
        for (size_t j = 0; j + 1 < nc; j++)
            if (ps.ec[j] > thresh && g.cols[j + 1] - g.cols[j] > 1e-12) {
                ps.mc[j] = 1;
                add_c++;
            }
        if (add_r + add_c == 0)
            break; /* intervals at 1e-12 rad: finer nodes cannot be told apart */
        if ((nr + add_r) * (nc + add_c) > tg->max_nodes) {
            o->budget_hit = BUDGET_SLICE; /* cannot refine further within the budget */
            break;
        }
        if (!slice_regrid(tg, &a, &g, &ps, &evals))
            goto nomem;
        slice_pass_free(&ps);
    }
    slice_pass_free(&ps);
    o->s.nr = g.nr;
    o->s.nc = g.nc;
    o->s.rows = g.rows;
    o->s.cols = g.cols;
    o->s.vals = g.vals;
    o->w = g.w;
    o->evals = evals;
    return;
nomem:
    slice_grid_free(&g);
    slice_pass_free(&ps);
    memset(o, 0, sizeof *o);
    o->nomem = 1;
}

