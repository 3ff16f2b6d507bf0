/* SPDX-License-Identifier: MIT */
/* table.c: the table object, its interpolation rule, evaluation and estimate. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "table/table.h"

double chi_shape(double n, double ca)
{
    if (!(ca > 0.0))
        return 0.0; /* the facet faces away from e_i */
    double sb2 = (1.0 - ca * ca) / (n * n); /* n > 0 (btdf_params_check) */
    if (!(sb2 < 1.0))
        return 0.0; /* total internal reflection on this facet */
    double cb = sqrt(1.0 - sb2), d = ca + n * cb;
    return cb * d * d;
}

double rule_factor(btdf_table_rule rule, double n, double ca)
{
    if (rule == BTDF_RULE_CHI)
        return chi_shape(n, ca);
    if (rule == BTDF_RULE_FRESNEL) /* the facet faces away from e_i: no reflection */
        return ca > 0.0 ? bt_fresnel_r(n, n - 1.0, ca) : 0.0;
    return 1.0;
}

/* The slices' own index for channel c (1/n for a reciprocal table). */
static double slice_index(const btdf_table *t, int c)
{
    return t->kind == BTDF_TABLE_FACET_RECIPROCAL ? 1.0 / t->p.ior[c] : t->p.ior[c];
}

double model_dir_factor(const btdf_params *p, int refl, double sti, double cti, double sto,
                        double cto)
{
    switch (p->model) {
    case BTDF_MODEL_SMITH:
    case BTDF_MODEL_FULL: { /* its slices hold the single scattering, smith's */
        if (refl && !(cto > 0.0))
            return 0.0; /* a grazing reflection carries no flux (MODEL.md 3.5) */
        /* reflection: G2 ~ cos tr and G2 / cos tr tends to a finite limit at the
           horizon; below cos tr = 1e-9 that limit is reached to 1e-9 relative, and the
           floor keeps Lambda(tr) and the division finite */
        double ct = refl ? (cto > 1e-9 ? cto : 1e-9) : cto;
        double s = p->smoothness, li = bt_lambda(sti, cti > 0.0 ? cti : 0.0, s);
        double lo = bt_lambda(sto, ct > 0.0 ? ct : 0.0, s);
        /* (1 + li) G2 = e^(ln(1 + li) - (-ln G2)): the exponent is <= 0 since
           G2 <= G1(ti) = 1/(1 + li) */
        double x = bt_log1p(li) - (refl ? bt_smith_r_exponent(li, lo)
                                        : bt_smith_t_exponent(li, lo));
        return bt_exp_mul(x < 0.0 ? x : 0.0, 1.0) / (refl ? ct : 1.0); /* ct >= 1e-9 */
    }
    default:
        return 1.0; /* xu-sun: V(ti) V(to), and V(to) stays in the nodes */
    }
}

double model_node_factor(const btdf_params *p, int refl, double n, double sti, double cti,
                         double stn, double ctn, double cpsi)
{
    if (p->model == BTDF_MODEL_XU_SUN)
        return 1.0;
    double spsi = sqrt(fmax(0.0, 1.0 - cpsi * cpsi)); /* psi in [0, pi]: sin psi >= 0 */
    if (refl) {
        rho_in a;
        rho_in_init(&a, sti, cti, 1.0, 0.0); /* geometry only */
        double ca, rx, ry, rz;
        if (!facet_mirror(&a, stn, ctn, cpsi, spsi, &ca, &rx, &ry, &rz) && !(ca > 0.0))
            return 0.0; /* the facet faces away from the light: the node's rho_r is 0 */
        /* a facet that mirrors below the horizon takes the factor of the mirror image
           of its direction (|cos tr|), as its node's continued rho_r does (facet_rho_r
           in slice.c): the reduced value rho_r / K is the Beckmann factor on both
           sides of the horizon, and no query reads a direction below it */
        return model_dir_factor(p, 1, sti, cti, sqrt(rx * rx + ry * ry), fabs(rz) > 1e-9 ? fabs(rz) : 1e-9);
    }
    facet_ray r;
    if (!facet_refract(n, sti, cti, stn, ctn, cpsi, spsi, &r))
        return 0.0; /* no transmitted direction: the node's rho is 0 */
    return model_dir_factor(p, 0, sti, cti, sqrt(r.ox * r.ox + r.oy * r.oy), -r.oz);
}

int slice_prepare(const btdf_table *t, tslice *s)
{
    free(s->geo);
    s->geo = NULL;
    if (t->rule == BTDF_RULE_PLAIN || t->kind == BTDF_TABLE_GRID)
        return 1;
    size_t nch = (size_t)t->p.channels, nsm = t->p.model == BTDF_MODEL_XU_SUN ? 0
                                                   : s->nr * s->nc * nch;
    s->geo = malloc((2 * s->nr + s->nc + nsm) * sizeof(double));
    if (!s->geo)
        return 0;
    for (size_t i = 0; i < s->nr; i++) {
        s->geo[i] = sin(s->rows[i]);
        s->geo[s->nr + i] = cos(s->rows[i]);
    }
    for (size_t j = 0; j < s->nc; j++)
        s->geo[2 * s->nr + j] = cos(s->cols[j]);
    /* the model's node factors (model_node_factor) after them, node by node */
    double *sm = s->geo + 2 * s->nr + s->nc, sti = sin(s->ti), cti = cos(s->ti);
    int refl = kind_is_reflection(t->kind);
    for (size_t i = 0; nsm && i < s->nr; i++)
        for (size_t j = 0; j < s->nc; j++)
            for (size_t c = 0; c < nch; c++)
                sm[(i * s->nc + j) * nch + c] =
                    model_node_factor(&t->p, refl, slice_index(t, (int)c), sti, cti,
                                      s->geo[i], s->geo[s->nr + i], s->geo[2 * s->nr + j]);
    return 1;
}

/* Index i with a[i] <= x <= a[i + 1], for a strictly increasing array of m >= 2. */
static size_t bracket(const double *a, size_t m, double x)
{
    size_t lo = 0, hi = m - 1;
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2;
        if (a[mid] <= x)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

double slice_interp_red(const btdf_table *t, size_t k, double x, double y, int ch)
{
    const tslice *s = &t->s[k];
    int nch = t->p.channels;
    if (!(x >= s->rows[0] && x <= s->rows[s->nr - 1] && y >= s->cols[0] &&
          y <= s->cols[s->nc - 1]))
        return 0.0; /* outside the tabulated range: the table says 0 */
    size_t i = 0, j = 0;
    double u = 0.0, v = 0.0;
    if (s->nr > 1) {
        i = bracket(s->rows, s->nr, x);
        u = (x - s->rows[i]) / (s->rows[i + 1] - s->rows[i]); /* rows strictly increase */
    }
    if (s->nc > 1) {
        j = bracket(s->cols, s->nc, y);
        v = (y - s->cols[j]) / (s->cols[j + 1] - s->cols[j]);
    }
    size_t i1 = s->nr > 1 ? i + 1 : i, j1 = s->nc > 1 ? j + 1 : j;
    const double *V = s->vals;
    double f00 = V[(i * s->nc + j) * nch + ch], f01 = V[(i * s->nc + j1) * nch + ch];
    double f10 = V[(i1 * s->nc + j) * nch + ch], f11 = V[(i1 * s->nc + j1) * nch + ch];
    if (s->geo) { /* BTDF_RULE_CHI, _FRESNEL: interpolate rho / K of each node */
        double n = slice_index(t, ch), sti = sin(s->ti), cti = cos(s->ti);
        const double *sn = s->geo, *cn = s->geo + s->nr, *cp = s->geo + 2 * s->nr;
        btdf_table_rule rl = t->rule;
        double k00 = rule_factor(rl, n, sn[i] * cp[j] * sti + cn[i] * cti);
        double k01 = rule_factor(rl, n, sn[i] * cp[j1] * sti + cn[i] * cti);
        double k10 = rule_factor(rl, n, sn[i1] * cp[j] * sti + cn[i1] * cti);
        double k11 = rule_factor(rl, n, sn[i1] * cp[j1] * sti + cn[i1] * cti);
        if (t->p.model != BTDF_MODEL_XU_SUN) { /* the nodes' model factors */
            const double *sm = s->geo + 2 * s->nr + s->nc;
            k00 *= sm[(i * s->nc + j) * nch + ch];
            k01 *= sm[(i * s->nc + j1) * nch + ch];
            k10 *= sm[(i1 * s->nc + j) * nch + ch];
            k11 *= sm[(i1 * s->nc + j1) * nch + ch];
        }
        /* K = 0: the node's facet refracts nothing and its rho is 0; so is rho / K */
        f00 = k00 > 0.0 ? f00 / k00 : 0.0;
        f01 = k01 > 0.0 ? f01 / k01 : 0.0;
        f10 = k10 > 0.0 ? f10 / k10 : 0.0;
        f11 = k11 > 0.0 ? f11 / k11 : 0.0;
    }
    return (1.0 - u) * ((1.0 - v) * f00 + v * f01) + u * ((1.0 - v) * f10 + v * f11);
}

double slice_interp(const btdf_table *t, size_t k, double x, double y, int ch)
{
    double r = slice_interp_red(t, k, x, y, ch);
    const tslice *s = &t->s[k];
    if (!s->geo || r == 0.0)
        return r;
    double ti = s->ti;
    double ca = sin(x) * cos(y) * sin(ti) + cos(x) * cos(ti); /* e_i . h of the slice */
    double n = slice_index(t, ch);
    return r * rule_factor(t->rule, n, ca) *
           model_node_factor(&t->p, kind_is_reflection(t->kind), n, sin(ti), cos(ti), sin(x),
                             cos(x), cos(y));
}

double incident_factor(const btdf_params *p, double ti)
{
    double c = cos(ti);
    if (!(c > 0.0))
        return 0.0; /* grazing incidence: the factor -> 0 faster than cos ti, rho is 0 */
    switch (p->model) {
    case BTDF_MODEL_SMITH:
    case BTDF_MODEL_FULL: /* the slices are smith's */
        /* G2 does not factor; its incident part is close to Smith's G1(ti) =
           1/(1 + Lambda(ti)) (exact where Lambda(to) = 0), which carries the same fast
           fall near grazing as V(ti) does in Eq. 25 */
        return 1.0 / ((1.0 + bt_lambda(sin(ti), c, p->smoothness)) * c);
    default:
        return shadow_v(sin(ti) / c, p->smoothness, p->k0) / c;
    }
}

double blend_ti(double v0, double v1, double w, double g, double g0, double g1)
{
    /* A slice whose incident factor is 0 (ti = 90 deg) holds only zeros and says
       nothing about the reduced value rho/g, which stays finite and nonzero as ti -> 90
       deg (Eq. 25 is g times a bounded factor). Reading it as 0 made the blend fall
       linearly to 0 over the last interval and the table lose most of T near grazing;
       the neighbour's reduced value is held instead, and the query's g takes rho to 0. */
    double r0 = g0 > 0.0 ? v0 / g0 : 0.0, r1 = g1 > 0.0 ? v1 / g1 : 0.0;
    if (!(g1 > 0.0))
        r1 = r0;
    else if (!(g0 > 0.0))
        r0 = r1;
    return g * ((1.0 - w) * r0 + w * r1);
}

const char *table_kind_name(btdf_table_kind k)
{
    return k == BTDF_TABLE_GRID                ? "grid"
           : k == BTDF_TABLE_FACET_RECIPROCAL  ? "facet-reciprocal"
           : k == BTDF_TABLE_FACET_REFLECTION  ? "facet-reflection"
                                               : "facet";
}

BTDF_API const char *btdf_part_name(btdf_part part)
{
    return part == BTDF_PART_REFLECTION ? "reflection"
           : part == BTDF_PART_BOTH     ? "both"
                                        : "transmission";
}

BTDF_API int btdf_part_parse(const char *name, btdf_part *part)
{
    const btdf_part all[3] = {BTDF_PART_TRANSMISSION, BTDF_PART_REFLECTION, BTDF_PART_BOTH};
    for (int i = 0; name && i < 3; i++)
        if (!strcmp(name, btdf_part_name(all[i]))) {
            *part = all[i];
            return 1;
        }
    return 0;
}

BTDF_API const btdf_table *btdf_table_part(const btdf_table *t, btdf_part part)
{
    if (!t)
        return NULL;
    int r = kind_is_reflection(t->kind);
    if (part == BTDF_PART_TRANSMISSION)
        return r ? NULL : t;
    if (part == BTDF_PART_REFLECTION)
        return r ? t : t->refl;
    return NULL;
}

BTDF_API btdf_part btdf_table_parts(const btdf_table *t)
{
    if (t && kind_is_reflection(t->kind))
        return BTDF_PART_REFLECTION;
    return t && t->refl ? BTDF_PART_BOTH : BTDF_PART_TRANSMISSION;
}

BTDF_API btdf_status btdf_table_attach_reflection(btdf_table *t, btdf_table *r, char *msg,
                                                  size_t msglen)
{
    const char *why = NULL;
    if (!t || !r)
        why = "no table (NULL)";
    else if (kind_is_reflection(t->kind) || t->refl)
        why = "the table is a reflection or holds one already";
    else if (!kind_is_reflection(r->kind) || r->refl)
        why = "the table to attach is not a reflection table";
    else if (r->attached)
        why = "the reflection table is attached to another table already (each table owns "
              "its reflection, and frees it)";
    else if (t->p.channels != r->p.channels || t->p.smoothness != r->p.smoothness ||
             t->p.k0 != r->p.k0 || t->p.model != r->p.model || memcmp(t->p.ior, r->p.ior, sizeof t->p.ior) != 0)
        why = "the two parts have different parameters";
    if (why) {
        if (msg && msglen)
            snprintf(msg, msglen, "%s", why);
        return BTDF_EINVAL;
    }
    t->refl = r;
    r->attached = 1;
    return BTDF_OK;
}

BTDF_API const char *btdf_table_kind_name(btdf_table_kind kind)
{
    return table_kind_name(kind);
}

int table_kind_parse(const char *name, btdf_table_kind *k)
{
    const btdf_table_kind all[4] = {BTDF_TABLE_FACET, BTDF_TABLE_GRID,
                                    BTDF_TABLE_FACET_RECIPROCAL, BTDF_TABLE_FACET_REFLECTION};
    for (int i = 0; i < 4; i++)
        if (!strcmp(name, table_kind_name(all[i]))) {
            *k = all[i];
            return 1;
        }
    return 0;
}

/* ------------------------------------------------------------------------- */
/* The object                                                                */
/* ------------------------------------------------------------------------- */

BTDF_API btdf_status btdf_table_new(btdf_table_kind kind, const btdf_params *p,
                                    btdf_table **out, char *msg, size_t msglen)
{
    if (!out) {
        core_say(BTDF_OK, msg, msglen, "%s", "no place for the table (out is NULL)");
        return BTDF_EINVAL;
    }
    if (kind != BTDF_TABLE_FACET && kind != BTDF_TABLE_GRID &&
        kind != BTDF_TABLE_FACET_RECIPROCAL && kind != BTDF_TABLE_FACET_REFLECTION) {
        core_say(BTDF_OK, msg, msglen, "%s",
                "table kind: must be facet, grid, facet-reciprocal or facet-reflection");
        return BTDF_EINVAL;
    }
    btdf_status st = btdf_params_check(p, msg, msglen);
    if (st != BTDF_OK)
        return st;
    btdf_table *t = calloc(1, sizeof *t);
    if (!t)
        return BTDF_ENOMEM;
    t->kind = kind;
    t->p = *p;
    *out = t;
    return BTDF_OK;
}

BTDF_API void btdf_table_free(btdf_table *t)
{
    if (!t)
        return;
    for (size_t k = 0; k < t->ns; k++) {
        free(t->s[k].rows);
        free(t->s[k].cols);
        free(t->s[k].vals);
        free(t->s[k].geo);
    }
    free(t->s);
    btdf_report_clear(&t->check);
    btdf_table_free(t->refl);
    for (int c = 0; c < BTDF_MAX_CHANNELS; c++)
        btdf_full_free(t->ms[c]);
    free(t);
}

/* Takes ownership of the three arrays of s on success. */
btdf_status table_push_slice(btdf_table *t, tslice *s)
{
    if (t->ns == t->cap) {
        size_t nc = t->cap ? 2 * t->cap : 16;
        tslice *ns = realloc(t->s, nc * sizeof *ns);
        if (!ns)
            return BTDF_ENOMEM;
        t->s = ns;
        t->cap = nc;
    }
    s->g = incident_factor(&t->p, s->ti);
    if (!slice_prepare(t, s)) /* replaces any geo s had */
        return BTDF_ENOMEM;
    t->s[t->ns++] = *s;
    t->check_valid = 0; /* the check was of the table without this slice */
    return BTDF_OK;
}

static int strictly_increasing(const double *a, size_t m)
{
    for (size_t i = 0; i < m; i++) {
        if (!isfinite(a[i]))
            return 0;
        if (i > 0 && !(a[i] > a[i - 1]))
            return 0;
    }
    return 1;
}

BTDF_API btdf_status btdf_table_add_slice(btdf_table *t, double ti, size_t nrows,
                                          const double *rows, size_t ncols,
                                          const double *cols, const double *values,
                                          char *msg, size_t msglen)
{
    char buf[160];
    if (!t || !rows || !cols || !values) {
        core_say(BTDF_OK, msg, msglen, "%s", !t ? "no table (NULL)"
                                : "slice rows, columns or values missing (NULL): a slice has "
                                  "at least 1 x 1 nodes");
        return BTDF_EINVAL;
    }
    if (!(ti >= 0.0 && ti <= M_PI / 2)) {
        snprintf(buf, sizeof buf, "slice ti %g rad: must lie in [0, pi/2]", ti);
        core_say(BTDF_OK, msg, msglen, "%s", buf);
        return BTDF_EINVAL;
    }
    if (t->ns > 0 && !(ti > t->s[t->ns - 1].ti)) {
        snprintf(buf, sizeof buf, "slice ti %.17g: must exceed the previous slice's %.17g",
                 ti, t->s[t->ns - 1].ti);
        core_say(BTDF_OK, msg, msglen, "%s", buf);
        return BTDF_EINVAL;
    }
    if (nrows < 1 || ncols < 1 || nrows > 1u << 24 || ncols > 1u << 24) {
        snprintf(buf, sizeof buf, "slice size %zu x %zu: each must lie in [1, 2^24]", nrows,
                 ncols);
        core_say(BTDF_OK, msg, msglen, "%s", buf);
        return BTDF_EINVAL;
    }
    if (!strictly_increasing(rows, nrows) || !strictly_increasing(cols, ncols)) {
        core_say(BTDF_OK, msg, msglen, "%s", "slice coordinates: must be finite and strictly increasing");
        return BTDF_EINVAL;
    }
    size_t nch = (size_t)t->p.channels;
    size_t nv = nrows * ncols; /* < 2^48: no overflow */
    if (nv > SIZE_MAX / (nch * sizeof(double)))
        return BTDF_EOVERFLOW;
    /* No parameters the model takes give a value near this (s = 1000 peaks near 6e5,
       docs: MODEL.md; the peak grows as s^2 up to s = 1e6); below it, any interpolation's
       weighted sum of a few values stays far from overflow, so a read table never gives
       inf. */
    const double value_max = 1e100;
    for (size_t i = 0; i < nv * nch; i++) {
        if (!(values[i] >= 0.0 && values[i] <= value_max)) {
            snprintf(buf, sizeof buf,
                     "slice value %g at index %zu: must be finite, >= 0 and <= 1e100 (no "
                     "model gives more)", values[i], i);
            core_say(BTDF_OK, msg, msglen, "%s", buf);
            return BTDF_EINVAL;
        }
    }
    tslice s = {ti, nrows, ncols, malloc(nrows * sizeof(double)),
                malloc(ncols * sizeof(double)), malloc(nv * nch * sizeof(double)), 0.0, NULL};
    if (!s.rows || !s.cols || !s.vals) {
        free(s.rows);
        free(s.cols);
        free(s.vals);
        return BTDF_ENOMEM;
    }
    memcpy(s.rows, rows, nrows * sizeof(double));
    memcpy(s.cols, cols, ncols * sizeof(double));
    memcpy(s.vals, values, nv * nch * sizeof(double));
    btdf_status st = table_push_slice(t, &s);
    if (st != BTDF_OK) {
        free(s.rows);
        free(s.cols);
        free(s.vals);
    }
    return st;
}

BTDF_API btdf_status btdf_table_set_rule(btdf_table *t, btdf_table_rule rule, char *msg,
                                         size_t msglen)
{
    if (!t)
        return BTDF_EINVAL;
    if (rule != BTDF_RULE_PLAIN && rule != BTDF_RULE_CHI && rule != BTDF_RULE_FRESNEL) {
        core_say(BTDF_OK, msg, msglen, "%s", "table rule: must be plain (0), chi (1) or fresnel (2)");
        return BTDF_EINVAL;
    }
    if (t->ns > 0) {
        core_say(BTDF_OK, msg, msglen, "%s", "table rule: must be set before the first slice is added");
        return BTDF_EINVAL;
    }
    if (rule == BTDF_RULE_CHI && (t->kind == BTDF_TABLE_GRID || kind_is_reflection(t->kind))) {
        core_say(BTDF_OK, msg, msglen, "%s", "table rule chi: only for facet and facet-reciprocal tables");
        return BTDF_EINVAL;
    }
    if (rule == BTDF_RULE_FRESNEL && !kind_is_reflection(t->kind)) {
        core_say(BTDF_OK, msg, msglen, "%s", "table rule fresnel: only for facet-reflection tables");
        return BTDF_EINVAL;
    }
    t->rule = rule;
    return BTDF_OK;
}

BTDF_API btdf_table_rule btdf_table_get_rule(const btdf_table *t) { return t->rule; }

BTDF_API const char *btdf_table_rule_name(btdf_table_rule rule)
{
    return rule == BTDF_RULE_CHI ? "chi" : rule == BTDF_RULE_FRESNEL ? "fresnel" : "plain";
}

BTDF_API int btdf_table_rule_parse(const char *name, btdf_table_rule *rule)
{
    if (!name || !rule)
        return 0;
    if (!strcmp(name, "chi"))
        *rule = BTDF_RULE_CHI;
    else if (!strcmp(name, "fresnel"))
        *rule = BTDF_RULE_FRESNEL;
    else if (!strcmp(name, "plain"))
        *rule = BTDF_RULE_PLAIN;
    else
        return 0;
    return 1;
}

BTDF_API btdf_table_kind btdf_table_get_kind(const btdf_table *t) { return t->kind; }
BTDF_API const btdf_params *btdf_table_get_params(const btdf_table *t) { return &t->p; }

BTDF_API const btdf_full *btdf_table_get_full(const btdf_table *t, int ch)
{
    if (!t || t->p.model != BTDF_MODEL_FULL || ch < 0 || ch >= t->p.channels)
        return NULL;
    return t->ms[ch];
}
BTDF_API size_t btdf_table_slice_count(const btdf_table *t) { return t ? t->ns : 0; }

BTDF_API size_t btdf_table_node_count(const btdf_table *t)
{
    size_t n = 0;
    for (size_t k = 0; t && k < t->ns; k++)
        n += t->s[k].nr * t->s[k].nc;
    return n;
}

BTDF_API btdf_status btdf_table_slice(const btdf_table *t, size_t k, btdf_slice *out)
{
    if (!t || !out || k >= t->ns)
        return BTDF_EINVAL;
    const tslice *s = &t->s[k];
    out->ti = s->ti;
    out->nrows = s->nr;
    out->ncols = s->nc;
    out->rows = s->rows;
    out->cols = s->cols;
    out->values = s->vals;
    return BTDF_OK;
}

/* The rule of btdf.h for one query given its sines and cosines. */
void table_eval_sc(const btdf_table *t, double ti, double sti, double cti, double sto,
                   double cto, double cph, double sph, double phi_fold, double to,
                   double *out)
{
    int nch = t->p.channels;
    int recip = t->kind == BTDF_TABLE_FACET_RECIPROCAL;
    for (int c = 0; c < nch; c++)
        out[c] = 0.0;
    table_add_ms(t, ti, cti, cto, cph, out); /* model full: the tally's orders 2+ */
    if (recip) {
        /* rho(n; ti, to) = n^2 rho(1/n; pi - to, pi - ti): swap the two directions. */
        double a = sti, b = cti;
        sti = sto;
        cti = -cto;
        sto = a;
        cto = -b;
        ti = M_PI - to;
    }
    if (t->ns == 0 || !(ti >= t->s[0].ti && ti <= t->s[t->ns - 1].ti))
        return; /* outside the tabulated incidence range */
    size_t k = 0;
    double w = 0.0;
    if (t->ns > 1) {
        size_t lo = 0, hi = t->ns - 1;
        while (hi - lo > 1) {
            size_t mid = lo + (hi - lo) / 2;
            if (t->s[mid].ti <= ti)
                lo = mid;
            else
                hi = mid;
        }
        k = lo;
        w = (ti - t->s[k].ti) / (t->s[k + 1].ti - t->s[k].ti); /* slices strictly increase */
    }
    /* Slices are blended after dividing by Eq. 25's incident factor g = V(ti)/cos ti,
       which the rule multiplies back: it is what changes fastest near grazing. */
    double g = 0.0, g0 = 0.0, g1 = 0.0;
    if (w > 0.0) {
        g = incident_factor(&t->p, ti);
        g0 = t->s[k].g;
        g1 = t->s[k + 1].g;
    }
    int chi = t->rule != BTDF_RULE_PLAIN && t->kind != BTDF_TABLE_GRID;
    for (int c = 0; c < nch; c++) {
        double x, y, ca = 1.0, n = recip ? 1.0 / t->p.ior[c] : t->p.ior[c];
        if (t->kind == BTDF_TABLE_FACET_REFLECTION) {
            if (!facet_of_r(sti, cti, sto, cto, cph, sph, &x, &y, &ca))
                continue; /* both directions graze: rho_r is 0 */
        } else if (t->kind != BTDF_TABLE_GRID) {
            if (!facet_of_ca(n, sti, cti, sto, cto, cph, sph, &x, &y, &ca))
                continue; /* no facet connects the two directions: exactly 0 */
        } else {
            x = to;
            y = phi_fold;
        }
        /* CHI: the slices' reduced values rho / K are blended; the query's K restores rho */
        double kq = chi ? rule_factor(t->rule, n, ca) : 1.0;
        if (chi && t->p.model != BTDF_MODEL_XU_SUN) /* the query's own model factor */
            kq *= model_dir_factor(&t->p, t->kind == BTDF_TABLE_FACET_REFLECTION, sti, cti,
                                   sto, t->kind == BTDF_TABLE_FACET_REFLECTION ? cto : -cto);
        if (!(kq > 0.0))
            continue; /* the query's facet refracts nothing: 0, as Eq. 25 */
        double v = slice_interp_red(t, k, x, y, c);
        if (w > 0.0)
            v = blend_ti(v, slice_interp_red(t, k + 1, x, y, c), w, g, g0, g1);
        v *= kq;
        /* reciprocity factor (1/n')^2 = n^2 with n' = 1/n the table's own index */
        out[c] += recip ? t->p.ior[c] * t->p.ior[c] * v : v;
    }
}

BTDF_API btdf_status btdf_table_eval(const btdf_table *t, double ti, double to, double phi,
                                     double *out)
{
    if (!t || !out)
        return BTDF_EINVAL;
    int refl = kind_is_reflection(t->kind); /* to is tr in [0, pi/2] */
    if (!(ti >= 0.0 && ti <= M_PI / 2 && isfinite(phi) &&
          (refl ? to >= 0.0 && to <= M_PI / 2 : to >= M_PI / 2 && to <= M_PI)))
        return BTDF_EDOMAIN;
    double f = fmod(fabs(phi), 2.0 * M_PI);
    if (f > M_PI)
        f = 2.0 * M_PI - f; /* rho depends on cos phi only */
    table_eval_sc(t, ti, sin(ti), cos(ti), sin(to), cos(to), cos(phi), sin(phi), f, to, out);
    return BTDF_OK;
}

/* ------------------------------------------------------------------------- */
/* The estimate of a table                                                   */
/* ------------------------------------------------------------------------- */

static void table_fn(const void *obj, double ti, const double *q, double *out)
{
    table_eval_sc(obj, ti, q[0], q[1], q[2], q[3], q[4], q[5], q[6], q[7], out);
}

BTDF_API btdf_status btdf_table_estimate(const btdf_table *t, double ti_min, double ti_max,
                                         size_t test_angles, size_t points_per_angle,
                                         uint64_t seed, int threads, btdf_report *r)
{
    if (!t)
        return BTDF_EINVAL;
    if (t->check_valid && t->check_ti0 == ti_min && t->check_ti1 == ti_max &&
        t->check_angles == test_angles && t->check_ppa == points_per_angle &&
        t->check_seed == seed) {
        *r = t->check;
        r->per_ti = malloc(t->check.test_angles * sizeof *r->per_ti);
        if (!r->per_ti)
            return BTDF_ENOMEM;
        memcpy(r->per_ti, t->check.per_ti, t->check.test_angles * sizeof *r->per_ti);
        r->slices = t->ns;
        r->samples = btdf_table_node_count(t);
        r->estimate_in_build = 1;
        return BTDF_OK;
    }
    /* The knots are the slice angles, in the table's own ti: for the reciprocal kind
       those are outgoing angles and say nothing about the incidence, so none. */
    double *knots = NULL;
    size_t nk = 0;
    if (t->kind != BTDF_TABLE_FACET_RECIPROCAL && t->ns > 1) {
        knots = malloc(t->ns * sizeof *knots);
        if (!knots)
            return BTDF_ENOMEM;
        for (size_t k = 0; k < t->ns; k++)
            knots[k] = t->s[k].ti;
        nk = t->ns;
    }
    btdf_status st =
        t->p.model == BTDF_MODEL_FULL
            ? table_estimate_full(t, ti_min, ti_max, test_angles, points_per_angle, seed,
                                  threads, knots, nk, table_fn, r)
            : est_knots_part(&t->p, kind_is_reflection(t->kind), ti_min, ti_max,
                                       test_angles, points_per_angle, seed, threads, knots,
                                       nk, table_fn, t, r);
    free(knots);
    if (st == BTDF_OK) {
        r->slices = t->ns;
        r->samples = btdf_table_node_count(t);
    }
    return st;
}
