/* SPDX-License-Identifier: MIT */
/* model.c: Eq. 25 of Xu & Sun (2008), its validation, and the hemispherical transmittance. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "btdf.h"
#include "model_impl.h"

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

btdf_status btdf_say(btdf_status st, char *msg, size_t msglen, const char *fmt, ...)
{
    if (msg && msglen) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(msg, msglen, fmt, ap);
        va_end(ap);
    }
    return st;
}

static btdf_status fail(char *msg, size_t msglen, const char *fmt, double v)
{
    if (msg && msglen)
        snprintf(msg, msglen, fmt, v);
    return BTDF_EINVAL;
}

BTDF_API btdf_status btdf_params_check(const btdf_params *p, char *msg, size_t msglen)
{
    if (!p)
        return fail(msg, msglen, "parameters missing%.0s", 0.0);
    if (p->channels != 1 && p->channels != 3)
        return fail(msg, msglen, "channels %g: must be 1 or 3", (double)p->channels);
    for (int c = 0; c < p->channels; c++) {
        double n = p->ior[c];
        if (!isfinite(n))
            return fail(msg, msglen, "index of refraction %g: must be a finite number", n);
        if (n <= 0.0)
            return fail(msg, msglen, "index of refraction %g: must be > 0", n);
        if (fabs(n - 1.0) < BTDF_IOR_ONE_EPS)
            return fail(msg, msglen,
                        "index of refraction %.17g: n = 1 has no BTDF (every facet transmits "
                        "undeviated, so the transmission is a delta); use n != 1, "
                        "e.g. 1.0001",
                        n);
        if (n < BTDF_IOR_MIN || n > BTDF_IOR_MAX)
            return fail(msg, msglen, "index of refraction %g: must lie in [0.001, 1000]", n);
    }
    double s = p->smoothness;
    if (!isfinite(s))
        return fail(msg, msglen, "smoothness %g: must be a finite number", s);
    if (s <= 0.0)
        return fail(msg, msglen, "smoothness %g: must be > 0", s);
    if (s < BTDF_S_MIN || s > BTDF_S_MAX)
        return fail(msg, msglen, "smoothness %g: must lie in [0.001, 1e6]", s);
    if (!isfinite(p->k0) || p->k0 < 0.0 || p->k0 > BTDF_K0_MAX)
        return fail(msg, msglen, "k0 %g: must lie in [0, 100]", p->k0);
    return BTDF_OK;
}

void btdf_sincos_deg(double deg, double *s, double *c)
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

/* pi to 64 bits and beyond, for the long double paths below. */
#define PI_L 3.141592653589793238462643383279502884L

/* sin and cos of degrees in long double, exact at multiples of 90 degrees. */
static void sincos_deg_l(double deg, long double *s, long double *c)
{
    double q = nearbyint(deg / 90.0);
    long double r = ((long double)deg - 90.0L * (long double)q) * (PI_L / 180.0L);
    long double sr = sinl(r), cr = cosl(r);
    long double k = fmodl((long double)q, 4.0L);
    if (k < 0)
        k += 4;
    switch ((int)k) {
    case 0: *s = sr; *c = cr; break;
    case 1: *s = cr; *c = -sr; break;
    case 2: *s = -sr; *c = -cr; break;
    default: *s = -cr; *c = sr; break;
    }
}

/* rho from sines and cosines given in long double; a bad parameter or angle gives 0.
   v = e_i + n e_o and its two dot products are formed in long double: near the
   straight-through direction with n near 1, v is a difference of nearly equal
   terms (1e-6 of them at n = 1.0001), and the Beckmann exponent, hundreds of units
   in the tail, multiplies its relative error. In double this cost 4e-8 relative at
   n = 1.0001, s = 1e4 (tests/mp_reference.py); in long double (64-bit mantissa on
   x86-64) it stays below 1e-10. Where long double is double, it is as before. */
static double rho_scl(double n, double s, double k0, long double sti, long double cti,
                      long double sto, long double cto, long double cph, long double sph)
{
    if (!(n > 0.0) || !(fabs(n - 1.0) >= BTDF_IOR_ONE_EPS) || !isfinite(n) ||
        !(s >= BTDF_S_MIN && s <= BTDF_S_MAX) || !(k0 >= 0.0 && k0 <= BTDF_K0_MAX))
        return 0.0;
    if (!(cti >= 0.0L && sti >= 0.0L && cto <= 0.0L && sto >= 0.0L) || !isfinite((double)cph) ||
        !isfinite((double)sph))
        return 0.0;
    rho_in a;
    rho_out b;
    rho_in_init(&a, (double)sti, (double)cti, s, k0);
    rho_out_init(&b, (double)sto, (double)cto, s, k0);
    long double nl = n;
    long double vx = sti + nl * sto * cph, vy = nl * sto * sph, vz = cti + nl * cto;
    long double ei_v = sti * vx + cti * vz;
    long double eo_v = sto * (cph * vx + sph * vy) + cto * vz;
    return rho_kernel_v(n, s, &a, &b, (double)vx, (double)vy, (double)vz, (double)ei_v,
                        (double)eo_v);
}

BTDF_API double btdf_rho(double n, double s, double k0, double ti, double to, double phi)
{
    if (!(ti >= 0.0 && ti <= M_PI / 2 + 1e-15 && to >= M_PI / 2 - 1e-15 &&
          to <= M_PI + 1e-15 && isfinite(phi)))
        return 0.0;
    long double tl = ti, ol = to, pl = phi;
    return rho_scl(n, s, k0, sinl(tl), cosl(tl), fabsl(sinl(ol)), fminl(cosl(ol), 0.0L),
                   cosl(pl), sinl(pl));
}

BTDF_API double btdf_rho_deg(double n, double s, double k0, double ti, double to,
                             double phi)
{
    if (!(ti >= 0.0 && ti <= 90.0 && to >= 90.0 && to <= 180.0 && isfinite(phi)))
        return 0.0;
    long double sti, cti, sto, cto, sph, cph;
    sincos_deg_l(ti, &sti, &cti);
    sincos_deg_l(to, &sto, &cto);
    sincos_deg_l(phi, &sph, &cph);
    return rho_scl(n, s, k0, sti, cti, sto, cto, cph, sph);
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

BTDF_API btdf_status btdf_eval(const btdf_params *p, double ti, double to, double phi,
                               double *out)
{
    if (btdf_params_check(p, NULL, 0) != BTDF_OK || !out)
        return BTDF_EINVAL;
    if (!angles_ok(ti, to, phi))
        return BTDF_EDOMAIN;
    long double tl = ti, ol = to, pl = phi;
    long double sti = sinl(tl), cti = cosl(tl), sto = sinl(ol), cto = cosl(ol);
    long double cph = cosl(pl), sph = sinl(pl);
    for (int c = 0; c < p->channels; c++)
        out[c] = rho_scl(p->ior[c], p->smoothness, p->k0, sti, fmaxl(cti, 0.0L), fabsl(sto),
                         fminl(cto, 0.0L), cph, sph);
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
    if (wo[2] >= 0.0) {
        for (int c = 0; c < p->channels; c++)
            out[c] = 0.0; /* reflection side: this model transmits only */
        return BTDF_OK;
    }
    /* Rotate the azimuths so that e_i lies at azimuth 0; phi = po - pi. */
    double ri = hypot(wi[0], wi[1]), ro = hypot(wo[0], wo[1]);
    double cph = 1.0, sph = 0.0;
    if (ri > 0.0 && ro > 0.0) { /* otherwise phi is undefined and irrelevant */
        cph = (wi[0] * wo[0] + wi[1] * wo[1]) / (ri * ro);
        sph = (wi[0] * wo[1] - wi[1] * wo[0]) / (ri * ro);
    }
    for (int c = 0; c < p->channels; c++)
        out[c] = rho_scl(p->ior[c], p->smoothness, p->k0, ri, wi[2], ro, wo[2], cph, sph);
    return BTDF_OK;
}

BTDF_API btdf_status btdf_eval_batch(const btdf_params *p, size_t count, const double *ti,
                                     const double *to, const double *phi, double *out,
                                     size_t *bad_index)
{
    if (btdf_params_check(p, NULL, 0) != BTDF_OK || (count && (!ti || !to || !phi || !out)))
        return BTDF_EINVAL;
    for (size_t i = 0; i < count; i++) {
        btdf_status st = btdf_eval(p, ti[i], to[i], phi[i], out + i * (size_t)p->channels);
        if (st != BTDF_OK) {
            if (bad_index)
                *bad_index = i;
            return st;
        }
    }
    return BTDF_OK;
}

/* ------------------------------------------------------------------------- */
/* Hemispherical transmittance                                               */
/* ------------------------------------------------------------------------- */

/* 8-point Gauss-Legendre on [0, 1]. */
static const double GL_X[8] = {0.019855071751231856, 0.10166676129318664,
                               0.2372337950418355,   0.4082826787521751,
                               0.5917173212478249,   0.7627662049581645,
                               0.8983332387068134,   0.9801449282487681};
static const double GL_W[8] = {0.05061426814518813, 0.11119051722668724,
                               0.15685332293894363, 0.18134189168918100,
                               0.18134189168918100, 0.15685332293894363,
                               0.11119051722668724, 0.05061426814518813};

/* Integrand of T over the facet azimuth at tilt tn: ca Ft V(to) / cos tn (0 when
   the facet cannot refract e_i into the lower hemisphere). */
static double facet_term(double n, double s, double k0, double sti, double cti,
                         double stn, double ctn, double cpsi)
{
    facet_ray r;
    if (!facet_refract(n, sti, cti, stn, ctn, cpsi, 0.0, &r))
        return 0.0;
    /* only e_o's z component and |sin to| matter here */
    double oz2 = r.oz * r.oz;
    double st2 = 1.0 - oz2;
    double tan_to = st2 > 0.0 ? sqrt(st2) / -r.oz : 0.0; /* -oz > 0 after facet_refract */
    double d1 = r.ca + n * r.cb, d2 = n * r.ca + r.cb;
    double ft = 2.0 * n * r.ca * r.cb * (1.0 / (d1 * d1) + 1.0 / (d2 * d2));
    return r.ca * ft * shadow_v(tan_to, s, k0) / ctn;
}

/* Composite Gauss-Legendre of f over [a, b] in `panels` panels, f(x) = facet sum. */
typedef struct tq_ctx {
    double n, s, k0, sti, cti;
} tq_ctx;

/* Inner integral over psi in [0, pi] at tilt tn, split where the integrand has a
   kink or a square-root edge: the facet turning away (ca = 0) and the critical
   angle (ca = cos theta_c), both monotone in psi. */
static double psi_integral(const tq_ctx *q, double stn, double ctn, int panels)
{
    double A = stn * q->sti, B = ctn * q->cti; /* ca(psi) = A cos psi + B */
    double edges[2];
    int ne = 0;
    edges[ne++] = 0.0; /* ca = 0 */
    if (q->n < 1.0)
        edges[ne++] = sqrt(1.0 - q->n * q->n); /* ca = cos(theta_c) */
    double hi = M_PI; /* the integrand vanishes for psi beyond hi */
    for (int e = 0; e < ne; e++) {
        double c = edges[e];
        if (A > 0.0) {
            double x = (c - B) / A;
            if (x >= 1.0)
                return 0.0; /* even psi = 0 fails */
            if (x > -1.0)
                hi = fmin(hi, acos(x));
        } else if (B <= c) {
            return 0.0;
        }
    }
    /* psi = hi (1 - (1 - x)^2) turns a square-root edge at hi into a smooth end. */
    double sum = 0.0;
    for (int k = 0; k < panels; k++) {
        for (int j = 0; j < 8; j++) {
            double x = (k + GL_X[j]) / panels;
            double om = 1.0 - x;
            double psi = hi * (1.0 - om * om);
            double w = GL_W[j] / panels * 2.0 * hi * om;
            sum += w * facet_term(q->n, q->s, q->k0, q->sti, q->cti, stn, ctn, cos(psi));
        }
    }
    return sum;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}



/* T(ti) for one index: (V(ti)/cos ti) (2/pi) int_0^U u e^{-u^2} int_0^pi g dpsi du,
   with u = (s/2) tan tn the facet slope in units of its RMS value / sqrt 2. */
static double transmittance_one(double n, double s, double k0, double ti, int u_panels,
                                int psi_panels)
{
    double sti = sin(ti), cti = cos(ti);
    if (!(cti > 0.0))
        return 0.0; /* grazing incidence transmits nothing */
    tq_ctx q = {n, s, k0, sti, cti};
    /* Tilts where the set of valid facet azimuths changes shape: tn = 90 - ti (all
       facets face e_i below it), and for n < 1 tn = theta_c -+ ti (critical angle). */
    const double U = 6.5; /* e^{-U^2} = 4e-19: the neglected tail */
    double br[8];
    int nb = 0;
    br[nb++] = 0.0;
    br[nb++] = U;
    double tcs[3] = {M_PI / 2 - ti, -1.0, -1.0};
    if (n < 1.0) {
        double tc = asin(n);
        tcs[1] = tc - ti;
        tcs[2] = tc + ti;
    }
    for (int k = 0; k < 3; k++) {
        if (tcs[k] > 0.0 && tcs[k] < M_PI / 2) {
            double u = 0.5 * s * tan(tcs[k]);
            if (u > 0.0 && u < U)
                br[nb++] = u;
        }
    }
    qsort(br, (size_t)nb, sizeof br[0], cmp_double);
    double sum = 0.0;
    const int panels = u_panels;
    for (int b = 0; b + 1 < nb; b++) {
        double a0 = br[b], a1 = br[b + 1];
        if (!(a1 > a0))
            continue;
        for (int k = 0; k < panels; k++) {
            for (int j = 0; j < 8; j++) {
                /* u = a0 + (a1 - a0) x^2 (3 - 2x): graded at both ends, which turns
                   the square-root edges at the breakpoints into smooth ends. */
                double x = (k + GL_X[j]) / panels;
                double u = a0 + (a1 - a0) * x * x * (3.0 - 2.0 * x);
                double w = GL_W[j] / panels * (a1 - a0) * 6.0 * x * (1.0 - x);
                double r = 2.0 * u / s; /* tan tn */
                double ctn = 1.0 / sqrt(1.0 + r * r), stn = r * ctn;
                sum += w * u * exp(-u * u) * psi_integral(&q, stn, ctn, psi_panels);
            }
        }
    }
    double vi = shadow_v(sti / cti, s, k0);
    return vi / cti * (2.0 / M_PI) * sum;
}

BTDF_API btdf_status btdf_transmittance(const btdf_params *p, double ti, double *out)
{
    if (btdf_params_check(p, NULL, 0) != BTDF_OK || !out)
        return BTDF_EINVAL;
    if (!(ti >= 0.0 && ti <= M_PI / 2))
        return BTDF_EDOMAIN;
    for (int c = 0; c < p->channels; c++)
        out[c] = transmittance_one(p->ior[c], p->smoothness, p->k0, ti, 16, 12);
    /* 16 x 12 panels: 128 x 48 change T by less than 1e-9 on reference-albedo.csv. */
    return BTDF_OK;
}

double btdf_transmittance_coarse(const btdf_params *p, double ti)
{
    /* 4 x 3 panels: within 1e-4 of the converged value, enough for the max(T, 0.01)
       floor the tables are refined against. */
    double m = 1.0;
    for (int c = 0; c < p->channels; c++)
        m = fmin(m, transmittance_one(p->ior[c], p->smoothness, p->k0, ti, 4, 3));
    return m;
}
