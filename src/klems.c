/* SPDX-License-Identifier: MIT */
/* klems.c: Klems matrices of patch-pair averages of Eq. 25.
 *
 * Entry (o, i) is the projected-solid-angle average of rho over the incident patch i and
 * the outgoing patch o (renderer-formats.md 3.3):
 *   M[o][i] = 1/(L_i L_o) * int_i int_o rho cos(t_i) |cos(t_o)| dw_i dw_o,
 * L the projected solid angle of a patch. An incident patch is named by the direction
 * the light travels (its source azimuth + 180 deg), as Radiance indexes it, so the
 * straight-through light lies on the diagonal. With w = sin^2(theta), the projected solid
 * angle is dw/2 dphi, so a patch is a rectangle [w0, w1] x [phi0, phi1].
 *  - outgoing: adaptive 2-D Gauss-Legendre (4 x 4 against the sum of its 4 quarters)
 *    per patch, to an absolute error of KL_EPS in the transmittance the patch receives;
 *    the lobe is narrower than a patch, so a fixed rule would miss or blur it;
 *  - incident: 4 x 4 Gauss-Legendre over the patch in (w, phi); the patch-integrated
 *    outgoing function is smooth in the incident direction inside a patch.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "radiance_impl.h"

#define KL_EPS 1e-7   /* absolute, per outgoing patch, in transmittance units */
#define KL_DEPTH 10   /* quarterings at most: a 90 deg patch down to 0.1 deg */

static const double full_t[] = {0, 5, 15, 25, 35, 45, 55, 65, 75, 90};
static const int full_n[] = {1, 8, 16, 20, 24, 24, 24, 16, 12};
static const double half_t[] = {0, 6.5, 19.5, 32.5, 46.5, 61.5, 76.5, 90};
static const int half_n[] = {1, 8, 12, 16, 20, 12, 4};
static const double quarter_t[] = {0, 9, 27, 46, 66, 90};
static const int quarter_n[] = {1, 8, 12, 12, 8};

static const rad_klems_basis kb_full = {"LBNL/Klems Full", 9, full_t, full_n, 145};
static const rad_klems_basis kb_half = {"LBNL/Klems Half", 7, half_t, half_n, 73};
static const rad_klems_basis kb_quarter = {"LBNL/Klems Quarter", 5, quarter_t, quarter_n, 41};

const rad_klems_basis *rad_klems(rad_basis b)
{
    switch (b) {
    case RAD_BASIS_KLEMS_FULL:
        return &kb_full;
    case RAD_BASIS_KLEMS_HALF:
        return &kb_half;
    case RAD_BASIS_KLEMS_QUARTER:
        return &kb_quarter;
    default:
        return NULL;
    }
}

int rad_klems_patch(const rad_klems_basis *kb, double theta_deg, double phi_deg)
{
    if (!(theta_deg >= 0.0 && theta_deg < 90.0))
        return -1; /* theta = 90 belongs to no band, as in Radiance */
    int band = 0, first = 0;
    while (band + 1 < kb->nbands && kb->theta[band + 1] <= theta_deg)
        first += kb->nphi[band++];
    double az = fmod(phi_deg, 360.0);
    if (az < 0.0)
        az += 360.0;
    int j = (int)(az * kb->nphi[band] / 360.0 + 0.5);
    if (j >= kb->nphi[band])
        j = 0;
    return first + j;
}

/* Patch p's rectangle in (w = sin^2 theta, phi in radians); patch 0 of a band is
   centred on phi = 0. */
static void patch_rect(const rad_klems_basis *kb, int p, double *w0, double *w1, double *p0,
                       double *p1)
{
    int band = 0;
    while (p >= kb->nphi[band])
        p -= kb->nphi[band++];
    double t0 = kb->theta[band] * M_PI / 180.0, t1 = kb->theta[band + 1] * M_PI / 180.0;
    *w0 = sin(t0) * sin(t0);
    *w1 = sin(t1) * sin(t1);
    double dp = 2.0 * M_PI / kb->nphi[band];
    *p0 = (p - 0.5) * dp;
    *p1 = (p + 0.5) * dp;
}

static const double gl_x[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                               0.8611363115940526};
static const double gl_w[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                               0.3478548451374538};

typedef struct kl_ctx {
    double n, s, k0;
    rho_in ri;
    double alpha; /* azimuth the light travels towards, radians */
} kl_ctx;

/* rho at outgoing (w, phi_o) for the incident direction in c. */
static double kl_f(const kl_ctx *c, double w, double po)
{
    double sto = sqrt(fmin(1.0, fmax(0.0, w)));
    rho_out ro;
    rho_out_init(&ro, sto, -sqrt(fmax(0.0, 1.0 - sto * sto)), c->s, c->k0);
    double phi = po - c->alpha + M_PI; /* MODEL.md azimuth: pi = straight on */
    return rho_kernel(c->n, c->s, &c->ri, &ro, cos(phi), sin(phi));
}

static double gl2(const kl_ctx *c, double w0, double w1, double p0, double p1)
{
    double hw = 0.5 * (w1 - w0), hp = 0.5 * (p1 - p0), sum = 0.0;
    for (int a = 0; a < 4; a++)
        for (int b = 0; b < 4; b++)
            sum += gl_w[a] * gl_w[b] *
                   kl_f(c, w0 + hw * (1.0 + gl_x[a]), p0 + hp * (1.0 + gl_x[b]));
    return sum * hw * hp * 0.5; /* projected solid angle dw/2 dphi */
}

static double adapt(const kl_ctx *c, double w0, double w1, double p0, double p1, double whole,
                    double eps, int depth)
{
    double wm = 0.5 * (w0 + w1), pm = 0.5 * (p0 + p1);
    double q[4] = {gl2(c, w0, wm, p0, pm), gl2(c, wm, w1, p0, pm), gl2(c, w0, wm, pm, p1),
                   gl2(c, wm, w1, pm, p1)};
    double sum = q[0] + q[1] + q[2] + q[3];
    if (fabs(sum - whole) <= eps || depth >= KL_DEPTH)
        return sum;
    return adapt(c, w0, wm, p0, pm, q[0], 0.25 * eps, depth + 1) +
           adapt(c, wm, w1, p0, pm, q[1], 0.25 * eps, depth + 1) +
           adapt(c, w0, wm, pm, p1, q[2], 0.25 * eps, depth + 1) +
           adapt(c, wm, w1, pm, p1, q[3], 0.25 * eps, depth + 1);
}

typedef struct kl_job {
    const btdf_params *p;
    double n, scale;
    const rad_klems_basis *kb;
    double *acc; /* acc[out * np + in] */
} kl_job;

/* Column i of the matrix: one incident patch. */
static void kl_column(void *arg, size_t i)
{
    kl_job *j = arg;
    const rad_klems_basis *kb = j->kb;
    int np = kb->npatch;
    double w0, w1, p0, p1;
    patch_rect(kb, (int)i, &w0, &w1, &p0, &p1);
    double li = 0.5 * (w1 - w0) * (p1 - p0); /* projected solid angle of the patch */
    kl_ctx c;
    c.n = j->n;
    c.s = j->p->smoothness;
    c.k0 = j->p->k0;
    double *col = calloc((size_t)np, sizeof *col);
    if (!col)
        return; /* the caller sees the NaN sentinel left in acc */
    double hw = 0.5 * (w1 - w0), hp = 0.5 * (p1 - p0);
    for (int a = 0; a < 4; a++) {
        double w = w0 + hw * (1.0 + gl_x[a]);
        double sti = sqrt(w), cti = sqrt(fmax(0.0, 1.0 - w));
        rho_in_init(&c.ri, sti, cti, c.s, c.k0);
        for (int b = 0; b < 4; b++) {
            c.alpha = p0 + hp * (1.0 + gl_x[b]);
            double wt = gl_w[a] * gl_w[b] * hw * hp * 0.5 / li; /* sums to 1 */
            for (int o = 0; o < np; o++) {
                double v0, v1, q0, q1;
                patch_rect(kb, o, &v0, &v1, &q0, &q1);
                double whole = gl2(&c, v0, v1, q0, q1);
                col[o] += wt * adapt(&c, v0, v1, q0, q1, whole, KL_EPS, 0);
            }
        }
    }
    for (int o = 0; o < np; o++) {
        double v0, v1, q0, q1;
        patch_rect(kb, o, &v0, &v1, &q0, &q1);
        double lo = 0.5 * (v1 - v0) * (q1 - q0);
        j->acc[(size_t)o * np + i] = j->scale * col[o] / lo; /* lo > 0 for every patch */
    }
    free(col);
}

btdf_status rad_klems_build(const btdf_params *p, double n, double scale,
                            const rad_klems_basis *kb,
                            int threads, rad_block *blk, char *msg, size_t msglen)
{
    size_t np = (size_t)kb->npatch;
    kl_job j = {p, n, scale, kb, malloc(np * np * sizeof(double))};
    float *m = malloc(np * np * sizeof *m);
    if (!j.acc || !m) {
        free(j.acc);
        free(m);
        if (msg && msglen)
            snprintf(msg, msglen, "out of memory for a %zu x %zu Klems matrix", np, np);
        return BTDF_ENOMEM;
    }
    for (size_t k = 0; k < np * np; k++)
        j.acc[k] = NAN; /* sentinel: a column whose scratch could not be allocated */
    btdf_parallel_for(threads, np, kl_column, &j);
    for (size_t k = 0; k < np * np; k++) {
        if (isnan(j.acc[k])) {
            free(j.acc);
            free(m);
            if (msg && msglen)
                snprintf(msg, msglen, "out of memory integrating the Klems matrix");
            return BTDF_ENOMEM;
        }
        char t[32];
        snprintf(t, sizeof t, "%.6g", j.acc[k]);
        m[k] = (float)strtod(t, NULL); /* the value exactly as the file holds it */
    }
    free(j.acc);
    blk->klems = m;
    return BTDF_OK;
}
