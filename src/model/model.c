/* SPDX-License-Identifier: MIT */
/* model.c: Eq. 25 of Xu & Sun (2008), its validation and its grids (the hemispherical
   transmittance and reflectance are in albedo.c). */
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "btdf.h"
#include "core/core.h"
#include "model/kernel.h"

BTDF_API const char *btdf_version_string(void) { return BTDF_VERSION_STRING; }

BTDF_API const char *btdf_strerror(btdf_status status)
{
#define BTDF_STATUS_TEXT_(name, text) case name: return text;
    switch (status) {
        BTDF_STATUS_LIST(BTDF_STATUS_TEXT_)
    default:
        break;
    }
#undef BTDF_STATUS_TEXT_
    return "unknown status";
}

BTDF_API void btdf_params_default(btdf_params *p)
{
    memset(p, 0, sizeof *p);
    p->channels = 1;
    p->ior[0] = p->ior[1] = p->ior[2] = 1.5;
    p->smoothness = 3.0;
    p->k0 = 0.7;
}

BTDF_API const char *btdf_model_name(btdf_model model)
{
    switch (model) {
    case BTDF_MODEL_XU_SUN: return "xu-sun";
    case BTDF_MODEL_SMITH: return "smith";
    case BTDF_MODEL_FULL: return "full";
    }
    return "unknown";
}

BTDF_API int btdf_model_parse(const char *name, btdf_model *model)
{
    static const btdf_model all[] = {BTDF_MODEL_XU_SUN, BTDF_MODEL_SMITH, BTDF_MODEL_FULL};
    if (!name)
        return 0;
    for (size_t k = 0; k < sizeof all / sizeof all[0]; k++)
        if (!strcmp(name, btdf_model_name(all[k]))) {
            if (model)
                *model = all[k];
            return 1;
        }
    return 0;
}

BTDF_API btdf_status btdf_params_check(const btdf_params *p, char *msg, size_t msglen)
{
    if (!p)
        return core_say(BTDF_EINVAL, msg, msglen, "parameters missing (NULL)");
    if (p->channels != 1 && p->channels != 3)
        return core_say(BTDF_EINVAL, msg, msglen, "channels %d: must be 1 or 3", p->channels);
    char t[32]; /* the value as given (core_num), not rounded to %g's 6 digits */
    for (int c = 0; c < p->channels; c++) {
        double n = p->ior[c];
        if (!isfinite(n))
            return core_say(BTDF_EINVAL, msg, msglen, "index of refraction %s: must be a finite number", core_num(n, t));
        if (n <= 0.0)
            return core_say(BTDF_EINVAL, msg, msglen, "index of refraction %s: must be > 0", core_num(n, t));
        if (fabs(n - 1.0) < BTDF_IOR_ONE_EPS)
            return core_say(BTDF_EINVAL, msg, msglen,
                        "index of refraction %s: n = 1 has no BTDF (every facet transmits "
                        "undeviated, so the transmission is a delta); use n != 1, "
                        "e.g. 1.0001",
                        core_num(n, t));
        if (n < BTDF_IOR_MIN || n > BTDF_IOR_MAX)
            return core_say(BTDF_EINVAL, msg, msglen, "index of refraction %s: must lie in [0.001, 1000]", core_num(n, t));
    }
    double s = p->smoothness;
    if (!isfinite(s))
        return core_say(BTDF_EINVAL, msg, msglen, "smoothness %s: must be a finite number", core_num(s, t));
    if (s <= 0.0)
        return core_say(BTDF_EINVAL, msg, msglen, "smoothness %s: must be > 0", core_num(s, t));
    if (s < BTDF_S_MIN || s > BTDF_S_MAX)
        return core_say(BTDF_EINVAL, msg, msglen, "smoothness %s: must lie in [0.001, 1e6]", core_num(s, t));
    if (!isfinite(p->k0) || p->k0 < 0.0 || p->k0 > BTDF_K0_MAX)
        return core_say(BTDF_EINVAL, msg, msglen, "k0 %s: must lie in [0, 100]", core_num(p->k0, t));
    if (p->model == BTDF_MODEL_FULL)
        return core_say(BTDF_ENOTSUP, msg, msglen,
                        "model full: made once per material by btdf_model_ctx_new or "
                        "btdf_full_new (its tally), not by the functions of btdf_params");
    if (p->model != BTDF_MODEL_XU_SUN && p->model != BTDF_MODEL_SMITH)
        return core_say(BTDF_EINVAL, msg, msglen, "model %d: must be xu-sun (0) or smith (1)",
                        (int)p->model);
    return BTDF_OK;
}

void model_sincos_deg(double deg, double *s, double *c)
{
    /* Quadrant reduction in degrees is exact (Sterbenz) for |deg| < 2^40, so
       sin(180) = 0 and cos(90) = 0 come out exactly. */
    double q = nearbyint(deg / 90.0);
    double r = (deg - 90.0 * q) * (M_PI / 180.0);
    double sr = sin(r), cr = cos(r);
    long k = (long)fmod(q, 4.0);
    if (k < 0)
        k += 4;
    switch (k) {
    case 0: *s = sr; *c = cr; break;
    case 1: *s = cr; *c = -sr; break;
    case 2: *s = -sr; *c = -cr; break;
    default: *s = -cr; *c = sr; break;
    }
}

/* Parameters rho accepts; anything else gives 0 (btdf_rho validates nothing else). */
static int params_ok(double n, double s, double k0)
{
    return n > 0.0 && fabs(n - 1.0) >= BTDF_IOR_ONE_EPS && n >= BTDF_IOR_MIN &&
           n <= BTDF_IOR_MAX && s >= BTDF_S_MIN && s <= BTDF_S_MAX && k0 >= 0.0 &&
           k0 <= BTDF_K0_MAX;
}

/* One evaluation: the shadowing only where some facet connects the directions. */
BT_INLINE double rho_point(double n, double s, double k0, bt_io *io, const bt_az *az)
{
    return bt_rho_one(n, n - 1.0, s, k0, io, az->h2, az->sphi);
}

BT_CLONES BTDF_API double btdf_rho(double n, double s, double k0, double ti, double to,
                                   double phi)
{
    if (!params_ok(n, s, k0) || !(ti >= 0.0 && ti <= M_PI / 2 + 1e-15 &&
                                  to >= M_PI / 2 - 1e-15 && to <= M_PI + 1e-15 &&
                                  isfinite(phi)))
        return 0.0;
    bt_io io;
    bt_az az;
    bt_io_geom_rad(&io, ti, to);
    bt_az_rad(&az, bt_fold_rad(phi));
    return rho_point(n, s, k0, &io, &az);
}

/* One Smith evaluation (BTDF_MODEL_SMITH): the same geometry, the Smith prefactor. */
BT_INLINE double rho_point_smith(double n, double s, bt_io *io, const bt_az *az)
{
    return bt_rho_one_smith(n, n - 1.0, s, io, az->h2, az->sphi);
}

/* One evaluation in the model of p (validated by the caller). */
BT_INLINE double rho_point_m(const btdf_params *p, double n, bt_io *io, const bt_az *az)
{
    return p->model == BTDF_MODEL_SMITH ? rho_point_smith(n, p->smoothness, io, az)
                                        : rho_point(n, p->smoothness, p->k0, io, az);
}

BT_CLONES BTDF_API double btdf_rho_smith(double n, double s, double ti, double to,
                                         double phi)
{
    if (!params_ok(n, s, 0.0) || !(ti >= 0.0 && ti <= M_PI / 2 + 1e-15 &&
                                   to >= M_PI / 2 - 1e-15 && to <= M_PI + 1e-15 &&
                                   isfinite(phi)))
        return 0.0;
    bt_io io;
    bt_az az;
    bt_io_geom_rad(&io, ti, to);
    bt_az_rad(&az, bt_fold_rad(phi));
    return rho_point_smith(n, s, &io, &az);
}

BT_CLONES BTDF_API double btdf_rho_smith_deg(double n, double s, double ti, double to,
                                             double phi)
{
    if (!params_ok(n, s, 0.0) ||
        !(ti >= 0.0 && ti <= 90.0 && to >= 90.0 && to <= 180.0 && isfinite(phi)))
        return 0.0;
    bt_io io;
    bt_az az;
    bt_io_geom_deg(&io, ti, to);
    bt_az_deg(&az, bt_fold_deg(phi));
    return rho_point_smith(n, s, &io, &az);
}

BT_CLONES BTDF_API double btdf_rho_r_smith(double n, double s, double ti, double tr,
                                           double phi)
{
    if (!params_ok(n, s, 0.0) || !(ti >= 0.0 && ti <= M_PI / 2 + 1e-15 && tr >= 0.0 &&
                                   tr <= M_PI / 2 + 1e-15 && isfinite(phi)))
        return 0.0;
    bt_ir ir;
    bt_az az;
    bt_ir_rad_m(&ir, ti, tr, s, 0.0, 1);
    bt_az_rad(&az, bt_fold_rad(phi));
    return bt_rho_r(n, n - 1.0, s, &ir, az.h2, az.sphi);
}

BT_CLONES BTDF_API double btdf_rho_r_smith_deg(double n, double s, double ti, double tr,
                                               double phi)
{
    if (!params_ok(n, s, 0.0) ||
        !(ti >= 0.0 && ti <= 90.0 && tr >= 0.0 && tr <= 90.0 && isfinite(phi)))
        return 0.0;
    bt_ir ir;
    bt_az az;
    bt_ir_deg_m(&ir, ti, tr, s, 0.0, 1);
    bt_az_deg(&az, bt_fold_deg(phi));
    return bt_rho_r(n, n - 1.0, s, &ir, az.h2, az.sphi);
}

BT_CLONES BTDF_API double btdf_rho_deg(double n, double s, double k0, double ti,
                                       double to, double phi)
{
    if (!params_ok(n, s, k0) ||
        !(ti >= 0.0 && ti <= 90.0 && to >= 90.0 && to <= 180.0 && isfinite(phi)))
        return 0.0;
    bt_io io;
    bt_az az;
    bt_io_geom_deg(&io, ti, to);
    bt_az_deg(&az, bt_fold_deg(phi));
    return rho_point(n, s, k0, &io, &az);
}

BT_CLONES BTDF_API double btdf_rho_r(double n, double s, double k0, double ti, double tr,
                                     double phi)
{
    if (!params_ok(n, s, k0) || !(ti >= 0.0 && ti <= M_PI / 2 + 1e-15 && tr >= 0.0 &&
                                  tr <= M_PI / 2 + 1e-15 && isfinite(phi)))
        return 0.0;
    bt_ir ir;
    bt_az az;
    bt_ir_rad(&ir, ti, tr, s, k0);
    bt_az_rad(&az, bt_fold_rad(phi));
    return bt_rho_r(n, n - 1.0, s, &ir, az.h2, az.sphi);
}

BT_CLONES BTDF_API double btdf_rho_r_deg(double n, double s, double k0, double ti,
                                         double tr, double phi)
{
    if (!params_ok(n, s, k0) ||
        !(ti >= 0.0 && ti <= 90.0 && tr >= 0.0 && tr <= 90.0 && isfinite(phi)))
        return 0.0;
    bt_ir ir;
    bt_az az;
    bt_ir_deg(&ir, ti, tr, s, k0);
    bt_az_deg(&az, bt_fold_deg(phi));
    return bt_rho_r(n, n - 1.0, s, &ir, az.h2, az.sphi);
}

BTDF_API double btdf_rho_model(btdf_model m, double n, double s, double k0, double ti,
                               double to, double phi)
{
    return m == BTDF_MODEL_XU_SUN  ? btdf_rho(n, s, k0, ti, to, phi)
           : m == BTDF_MODEL_SMITH ? btdf_rho_smith(n, s, ti, to, phi)
                                   : 0.0;
}

BTDF_API double btdf_rho_model_deg(btdf_model m, double n, double s, double k0, double ti,
                                   double to, double phi)
{
    return m == BTDF_MODEL_XU_SUN  ? btdf_rho_deg(n, s, k0, ti, to, phi)
           : m == BTDF_MODEL_SMITH ? btdf_rho_smith_deg(n, s, ti, to, phi)
                                   : 0.0;
}

BTDF_API double btdf_rho_r_model(btdf_model m, double n, double s, double k0, double ti,
                                 double tr, double phi)
{
    return m == BTDF_MODEL_XU_SUN  ? btdf_rho_r(n, s, k0, ti, tr, phi)
           : m == BTDF_MODEL_SMITH ? btdf_rho_r_smith(n, s, ti, tr, phi)
                                   : 0.0;
}

BTDF_API double btdf_rho_r_model_deg(btdf_model m, double n, double s, double k0, double ti,
                                     double tr, double phi)
{
    return m == BTDF_MODEL_XU_SUN  ? btdf_rho_r_deg(n, s, k0, ti, tr, phi)
           : m == BTDF_MODEL_SMITH ? btdf_rho_r_smith_deg(n, s, ti, tr, phi)
                                   : 0.0;
}

BTDF_API double btdf_fresnel_r(double n, double ti)
{
    if (!(n > 0.0) || !isfinite(n) || !(ti >= 0.0 && ti <= M_PI / 2))
        return 0.0;
    double c = cos(ti);
    c = c > 0.0 ? c : 0.0;
    if (n > 1e4) {
        /* The kernel's form squares n twice (n^4 overflows past 1e77, giving inf / inf);
           far from n = 1 it needs no care for cancellation, so the textbook form with
           g = n cos b taken as n sqrt(1 - (sin ti / n)^2) serves, scaled by 1/n where it
           would overflow. 1e4: both forms agree to a few ulps there (tests/test_model.c). */
        double sa = sin(ti), r = sa / n;
        double gn = sqrt(1.0 - r * r); /* g / n = cos b, in (0, 1] for n > 1 */
        double g = n * gn;
        double rs = (c - g) / (c + g);         /* c + g >= g > 0 */
        double rp = (n * c - gn) / (n * c + gn); /* n c + gn >= gn > 0 */
        return 0.5 * (rs * rs + rp * rp);
    }
    return bt_fresnel_r(n, n - 1.0, c);
}

BTDF_API double btdf_fresnel_t(double n, double ti)
{
    if (!(n > 0.0) || !isfinite(n) || !(ti >= 0.0 && ti < M_PI / 2))
        return 0.0;
    double ca = cos(ti), sa = sin(ti);
    double sb2 = sa * sa / (n * n);
    if (!(sb2 < 1.0))
        return 0.0; /* total internal reflection past the critical angle */
    double cb = sqrt(1.0 - sb2);
    double d1 = ca + n * cb, d2 = n * ca + cb; /* > 0: ca > 0 and cb > 0 here */
    return 2.0 * n * ca * cb * (1.0 / (d1 * d1) + 1.0 / (d2 * d2));
}

static int angles_ok(double ti, double to, double phi)
{
    return ti >= 0.0 && ti <= M_PI / 2 && to >= M_PI / 2 && to <= M_PI && isfinite(phi);
}

/* btdf_params_check's verdict without its messages: the per-call check of btdf_eval. */
static int params_valid(const btdf_params *p)
{
    if (!p || !(p->channels == 1 || p->channels == 3) ||
        !(p->model == BTDF_MODEL_XU_SUN || p->model == BTDF_MODEL_SMITH))
        return 0;
    for (int c = 0; c < p->channels; c++)
        if (!params_ok(p->ior[c], p->smoothness, p->k0))
            return 0;
    return 1;
}

BT_CLONES BTDF_API btdf_status btdf_eval(const btdf_params *p, double ti, double to,
                                         double phi, double *out)
{
    if (!params_valid(p) || !out)
        return BTDF_EINVAL;
    if (!angles_ok(ti, to, phi))
        return BTDF_EDOMAIN;
    bt_io io;
    bt_az az;
    bt_io_geom_rad(&io, ti, to);
    bt_az_rad(&az, bt_fold_rad(phi));
    for (int c = 0; c < p->channels; c++)
        out[c] = rho_point_m(p, p->ior[c], &io, &az);
    return BTDF_OK;
}

BTDF_API btdf_status btdf_eval_r(const btdf_params *p, double ti, double tr, double phi,
                                 double *out)
{
    if (btdf_params_check(p, NULL, 0) != BTDF_OK || !out)
        return BTDF_EINVAL;
    if (!(ti >= 0.0 && ti <= M_PI / 2 && tr >= 0.0 && tr <= M_PI / 2 && isfinite(phi)))
        return BTDF_EDOMAIN;
    bt_ir ir;
    bt_az az;
    bt_ir_rad_m(&ir, ti, tr, p->smoothness, p->k0, p->model == BTDF_MODEL_SMITH);
    bt_az_rad(&az, bt_fold_rad(phi));
    for (int c = 0; c < p->channels; c++)
        out[c] = bt_rho_r(p->ior[c], p->ior[c] - 1.0, p->smoothness, &ir, az.h2, az.sphi);
    return BTDF_OK;
}

BTDF_API btdf_status btdf_eval_dir(const btdf_params *p, const double wi[3],
                                   const double wo[3], double *out)
{
    if (btdf_params_check(p, NULL, 0) != BTDF_OK || !out || !wi || !wo)
        return BTDF_EINVAL;
    for (int k = 0; k < 3; k++)
        if (!isfinite(wi[k]) || !isfinite(wo[k]))
            return BTDF_EDOMAIN;
    double li = wi[0] * wi[0] + wi[1] * wi[1] + wi[2] * wi[2];
    double lo = wo[0] * wo[0] + wo[1] * wo[1] + wo[2] * wo[2];
    if (fabs(li - 1.0) > 2e-6 || fabs(lo - 1.0) > 2e-6 || wi[2] < 0.0)
        return BTDF_EDOMAIN;
    double s = p->smoothness, k0 = p->k0;
    double ri = hypot(wi[0], wi[1]), ro = hypot(wo[0], wo[1]);
    if (wo[2] >= 0.0) {
        for (int c = 0; c < p->channels; c++)
            out[c] = 0.0; /* reflection side: btdf_rho_r holds that lobe */
        return BTDF_OK;
    }
    /* v = (wi + wo) + d wo: each sum of the first vector is rounded once, so v keeps
       the accuracy near n = 1 that the angle forms get from their half-angle products. */
    rho_in a;
    rho_out b;
    rho_in_init(&a, ri, wi[2], s, k0);
    rho_out_init(&b, ro, wo[2], s, k0);
    if (p->model == BTDF_MODEL_SMITH) {
        /* G2 does not factor into an incoming and an outgoing part: all of it goes to
           the incoming prefactor (rho is their product); 1/cos as rho_in_init's guards */
        double ci = wi[2], co = -wo[2];
        double g2 = bt_exp_mul(-bt_smith_t_exponent(bt_lambda(ri, ci > 0.0 ? ci : 0.0, s),
                                                    bt_lambda(ro, co > 0.0 ? co : 0.0, s)),
                               1.0);
        a.pref = ci > 0.0 ? s * s / (4.0 * M_PI) * g2 / ci : 0.0;
        b.pref = co > 0.0 ? 1.0 / co : 0.0;
    }
    for (int c = 0; c < p->channels; c++) {
        double n = p->ior[c], d = n - 1.0;
        double vx = (wi[0] + wo[0]) + d * wo[0], vy = (wi[1] + wo[1]) + d * wo[1];
        double vz = (wi[2] + wo[2]) + d * wo[2];
        double ei_v = wi[0] * vx + wi[1] * vy + wi[2] * vz;
        double eo_v = wo[0] * vx + wo[1] * vy + wo[2] * vz;
        /* the kernel's frame has e_i at azimuth 0; v's horizontal part enters through
           vx^2 + vy^2 only, so any rotation of the frame gives the same value */
        out[c] = rho_kernel_v(n, s, &a, &b, vx, vy, vz, ei_v, eo_v);
    }
    return BTDF_OK;
}

/* Evaluations are done in blocks: a scalar pass folds the azimuths (fmod for the
   rare azimuth beyond one turn), then a branch-free loop the compiler vectorises. */
#define BT_BLOCK 256

BT_CLONES static void batch_block(const btdf_params *p, size_t count, const double *ti,
                        const double *to, const double *phi, double *out)
{
    double c[BT_BLOCK];
    const double s = p->smoothness, k0 = p->k0;
    const int nc = p->channels;
    for (size_t i = 0; i < count; i++)
        c[i] = bt_fold_rad(phi[i]);
    if (p->model == BTDF_MODEL_SMITH) {
        /* the Smith prefactor (bt_io_pref_smith) in passes, so that the log-Beta's two
           forms (bt_smith_t_exponent) do not keep the loops from vectorising: the
           geometry and both Lambdas; the series form for every point (its arguments
           clamped to its range, which changes nothing where it is the form used); the
           Stirling form, scalar, for the points beyond; then the value */
        bt_io io[BT_BLOCK];
        double li[BT_BLOCK], lo[BT_BLOCK], sh[BT_BLOCK];
        for (size_t i = 0; i < count; i++) {
            bt_io_geom_rad(&io[i], ti[i], to[i]);
            li[i] = bt_lambda(io[i].sti, io[i].cti, s);
            lo[i] = bt_lambda(io[i].sto, io[i].cto, s);
        }
        for (size_t i = 0; i < count; i++) {
            double x = li[i] > lo[i] ? li[i] : lo[i], y = li[i] > lo[i] ? lo[i] : li[i];
            sh[i] = bt_smith_t_exponent_small(x < 0.5 ? x : 0.5, y < 0.5 ? y : 0.5);
        }
        for (size_t i = 0; i < count; i++)
            if (li[i] > 0.5 || lo[i] > 0.5)
                sh[i] = bt_smith_t_exponent_stirling(li[i], lo[i]);
        for (size_t i = 0; i < count; i++)
            bt_io_pref_smith_sh(&io[i], s, sh[i]);
        for (size_t i = 0; i < count; i++) {
            bt_az az;
            bt_az_rad(&az, c[i]);
            for (int k = 0; k < nc; k++)
                out[i * (size_t)nc + (size_t)k] =
                    bt_rho(p->ior[k], p->ior[k] - 1.0, s, &io[i], az.h2, az.sphi);
        }
        return;
    }
    if (nc == 1) {
        const double n = p->ior[0], d = n - 1.0;
        for (size_t i = 0; i < count; i++) {
            bt_io io;
            bt_az az;
            bt_io_rad(&io, ti[i], to[i], s, k0);
            bt_az_rad(&az, c[i]);
            out[i] = bt_rho(n, d, s, &io, az.h2, az.sphi);
        }
        return;
    }
    for (size_t i = 0; i < count; i++) {
        bt_io io;
        bt_az az;
        bt_io_rad(&io, ti[i], to[i], s, k0);
        bt_az_rad(&az, c[i]);
        for (int k = 0; k < nc; k++)
            out[i * (size_t)nc + (size_t)k] =
                bt_rho(p->ior[k], p->ior[k] - 1.0, s, &io, az.h2, az.sphi);
    }
}

BTDF_API btdf_status btdf_eval_batch(const btdf_params *p, size_t count, const double *ti,
                                     const double *to, const double *phi, double *out,
                                     size_t *bad_index)
{
    if (btdf_params_check(p, NULL, 0) != BTDF_OK || (count && (!ti || !to || !phi || !out)))
        return BTDF_EINVAL;
    for (size_t i = 0; i < count; i++)
        if (!angles_ok(ti[i], to[i], phi[i])) {
            if (bad_index)
                *bad_index = i;
            return BTDF_EDOMAIN;
        }
    for (size_t i = 0; i < count; i += BT_BLOCK) {
        size_t m = count - i < BT_BLOCK ? count - i : BT_BLOCK;
        batch_block(p, m, ti + i, to + i, phi + i, out + i * (size_t)p->channels);
    }
    return BTDF_OK;
}

typedef struct grid_job {
    const btdf_params *p;
    size_t nto, nphi;
    const double *ti, *to, *h2, *sphi;
    double *out;
} grid_job;

/* The loop over phi of one (ti, to) row: branch-free and vectorised. */
BT_CLONES static void grid_line(const btdf_params *p, const bt_io *io, size_t nphi,
                                const double *h2, const double *sp, double *o)
{
    const int nc = p->channels;
    const double s = p->smoothness;
    if (nc == 1) {
        const double n = p->ior[0], d = n - 1.0;
        for (size_t k = 0; k < nphi; k++)
            o[k] = bt_rho(n, d, s, io, h2[k], sp[k]);
        return;
    }
    for (int c = 0; c < nc; c++) {
        const double n = p->ior[c], d = n - 1.0;
        for (size_t k = 0; k < nphi; k++)
            o[k * (size_t)nc + (size_t)c] = bt_rho(n, d, s, io, h2[k], sp[k]);
    }
}

static void grid_row(void *arg, size_t r)
{
    const grid_job *g = arg;
    const btdf_params *p = g->p;
    size_t i = r / g->nto, j = r % g->nto;
    bt_io io;
    if (p->model == BTDF_MODEL_SMITH) {
        bt_io_geom_rad(&io, g->ti[i], g->to[j]);
        bt_io_pref_smith(&io, p->smoothness);
    } else {
        bt_io_rad(&io, g->ti[i], g->to[j], p->smoothness, p->k0);
    }
    grid_line(p, &io, g->nphi, g->h2, g->sphi, g->out + r * g->nphi * (size_t)p->channels);
}

BTDF_API btdf_status btdf_eval_grid(const btdf_params *p, size_t nti, const double *ti,
                                    size_t nto, const double *to, size_t nphi,
                                    const double *phi, int threads, double *out)
{
    if (btdf_params_check(p, NULL, 0) != BTDF_OK || threads < 0 ||
        ((nti && nto && nphi) && (!ti || !to || !phi || !out)))
        return BTDF_EINVAL;
    if (!nti || !nto || !nphi)
        return BTDF_OK;
    if (nto > SIZE_MAX / nti || nphi > SIZE_MAX / BTDF_MAX_CHANNELS / sizeof(double) ||
        nti * nto > SIZE_MAX / BTDF_MAX_CHANNELS / sizeof(double) / nphi)
        return BTDF_EOVERFLOW;
    for (size_t i = 0; i < nti; i++)
        if (!(ti[i] >= 0.0 && ti[i] <= M_PI / 2))
            return BTDF_EDOMAIN;
    for (size_t j = 0; j < nto; j++)
        if (!(to[j] >= M_PI / 2 && to[j] <= M_PI))
            return BTDF_EDOMAIN;
    for (size_t k = 0; k < nphi; k++)
        if (!isfinite(phi[k]))
            return BTDF_EDOMAIN;
    double *az = malloc(2 * nphi * sizeof *az);
    if (!az)
        return BTDF_ENOMEM;
    for (size_t k = 0; k < nphi; k++) {
        bt_az a;
        bt_az_rad(&a, bt_fold_rad(phi[k]));
        az[k] = a.h2;
        az[nphi + k] = a.sphi;
    }
    grid_job g = {p, nto, nphi, ti, to, az, az + nphi, out};
    core_parallel_for(threads, nti * nto, grid_row, &g);
    free(az);
    return BTDF_OK;
}
