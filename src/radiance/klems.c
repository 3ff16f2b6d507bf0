/* SPDX-License-Identifier: MIT */
/* klems.c: Klems matrices of patch-pair averages of Eq. 25 (transmission blocks) and of
 * the reflection rho_r of the same facets (MODEL.md 8; reflection blocks).
 *
 * Entry (o, i) is the projected-solid-angle average of rho (or rho_r) over the incident
 * patch i and the outgoing patch o (renderer-formats.md 3.3):
 *   M[o][i] = 1/(L_i L_o) * int_i int_o rho cos(t_i) |cos(t_o)| dw_i dw_o,
 * L the projected solid angle of a patch. An incident patch is named by the direction
 * the light travels (its source azimuth + 180 deg), as Radiance indexes it, so the
 * straight-through light (or the mirror reflection) lies on the diagonal. Both patches'
 * polar angles are measured from the normal of their own side, as Radiance's bsdf_m.c
 * does for every block (its fi/bi/fo/bo index maps differ only in the signs that bring
 * a vector to the upper hemisphere; the incident one reverses x and y, the outgoing one
 * does not, on either side). With w = sin^2(theta), the projected solid
 * angle is dw/2 dphi, so a patch is a rectangle [w0, w1] x [phi0, phi1].
 *  - outgoing: adaptive 2-D Gauss-Legendre (4 x 4 against the sum of its 4 quarters)
 *    per patch, to an absolute error of KL_EPS in the transmittance the patch receives;
 *    the lobe is narrower than a patch, so a fixed rule would miss or blur it;
 *    the reflection's lobe is narrow too, and for the light inside the glass (1/n) its
 *    Fresnel factor has the edge of total internal reflection (Fr reaches 1 with an
 *    infinite slope at the facet's critical angle): the quarters straddling that curve
 *    disagree with their parent until they are small: the reflection's rule is global
 *    (adapt_global below), so that it refines there only as far as the patch needs;
 *  - incident: 4 x 4 Gauss-Legendre over the patch in (w, phi); the patch-integrated
 *    outgoing function is smooth in the incident direction inside a patch. For the
 *    reflection more nodes in its grazing band and over its polar cap (KL_GRAZE_PANELS,
 *    KL_CAP_PANELS).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "radiance/radiance_impl.h"

#define KL_EPS 1e-7   /* absolute, per outgoing patch, in transmittance (reflectance) units */
#define KL_DEPTH 10   /* quarterings at most: a 90 deg patch down to 0.1 deg */
/* Reflection, the grazing band (up to 90 deg): R(ti) and the lobe change fast as the
   shadowing V(ti) falls to 0, and 4 nodes in w = sin^2 ti miss R's band average by up
   to 0.6 % (Klems quarter, 66-90 deg). In u = cos ti (w = 1 - u^2, dw = 2u du) with
   8 panels of 4 nodes the average is within 1e-6 relative (n = 1.5 and 1/1.5, s = 3,
   the last band of each basis, against 256 panels in w). */
#define KL_GRAZE_PANELS 8
/* Reflection, the polar cap (one patch around the normal): with 4 azimuth nodes over its
   full turn the light's direction reaches an outgoing patch's edge of total internal
   reflection (light inside, 83.6 deg from the source at n = 1/1.5) in 4 places only, and
   pairs of the cap and the grazing band missed their reciprocal twins by up to 2 % (Klems
   full, s = 3). 4 panels of 4 nodes. */
#define KL_CAP_PANELS 4

static const double full_t[] = {0, 5, 15, 25, 35, 45, 55, 65, 75, 90};
static const int full_n[] = {1, 8, 16, 20, 24, 24, 24, 16, 12};
/* The half and quarter bases as Radiance knows them by name (its bsdf_m.c, since its
   2022 change "corrected Klems half and quarter bases to match WINDOW"): for a name it
   knows, Radiance reads the matrix with its own bands and ignores the file's blocks. */
static const double half_t[] = {0, 6.5, 19.5, 32.5, 45.5, 58.5, 71.5, 90};
static const int half_n[] = {1, 8, 12, 16, 20, 12, 8};
static const double quarter_t[] = {0, 9, 27, 45, 63, 90};
static const int quarter_n[] = {1, 8, 12, 12, 8};

static const rad_klems_basis kb_full = {"LBNL/Klems Full", 9, full_t, full_n, 145};
static const rad_klems_basis kb_half = {"LBNL/Klems Half", 7, half_t, half_n, 77};
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
    btdf_model model; /* the shadowing-masking (kernel.h) */
    int reflect;  /* 1: rho_r of MODEL.md 8, 0: Eq. 25 */
    rho_in ri;
    double ti;    /* the incident polar angle (reflection) */
    double alpha; /* azimuth the light travels towards, radians */
} kl_ctx;

/* The 4 x 4 Gauss-Legendre rule of rho (or rho_r) over the outgoing cell
   [w0, w1] x [p0, p1] for the incident direction in c, in projected solid angle. The
   outgoing polar terms are computed once per w node and the azimuth's once per phi
   node. */
static double gl2(const kl_ctx *c, double w0, double w1, double p0, double p1)
{
    double hw = 0.5 * (w1 - w0), hp = 0.5 * (p1 - p0), sum = 0.0;
    double cph[4], sph[4];
    bt_az az[4];
    for (int b = 0; b < 4; b++) {
        double po = p0 + hp * (1.0 + gl_x[b]);
        if (c->reflect) {
            /* MODEL.md 8's azimuth is from the source's (alpha + pi): pi is the mirror
               direction, and rho_r depends on it through the folded angle only. */
            bt_az_rad(&az[b], bt_fold_rad(po - c->alpha - M_PI));
        } else {
            double phi = po - c->alpha + M_PI; /* MODEL.md azimuth: pi = straight on */
            cph[b] = cos(phi);
            sph[b] = sin(phi);
        }
    }
    for (int a = 0; a < 4; a++) {
        double w = w0 + hw * (1.0 + gl_x[a]);
        double sto = sqrt(fmin(1.0, fmax(0.0, w)));
        if (c->reflect) {
            bt_ir ir;
            bt_ir_rad_m(&ir, c->ti, asin(sto), c->s, c->k0, c->model == BTDF_MODEL_SMITH);
            for (int b = 0; b < 4; b++)
                sum += gl_w[a] * gl_w[b] *
                       bt_rho_r(c->n, c->n - 1.0, c->s, &ir, az[b].h2, az[b].sphi);
        } else {
            rho_out ro;
            rho_out_init_m(&ro, sto, -sqrt(fmax(0.0, 1.0 - sto * sto)), c->s, c->k0, &c->ri);
            for (int b = 0; b < 4; b++)
                sum += gl_w[a] * gl_w[b] * rho_kernel(c->n, c->s, &c->ri, &ro, cph[b], sph[b]);
        }
    }
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

/* The reflection's outgoing rule: global instead of local adaptivity. Along the edge of
   total internal reflection (light inside the glass) the error of a cell that the edge
   crosses falls only as h^2.5 (Fr ~ 1 - K sqrt(distance) beside the edge), slower than
   the cell's share eps h^2 of a local rule, which then quarters every such cell down to
   KL_DEPTH although their errors sum to far less. So the patch's cells are kept in a
   list and the one with the largest error estimate (|its 4 quarters - its own rule|) is
   quartered until the estimates sum to at most KL_EPS: the same target, met where the
   error is. Measured, one thread, one Klems-quarter block at n = 1/1.5, s = 3 (4 x 4
   incident nodes in every patch): the local rule 42 s, this one 7.1 s; against this rule at eps = 1e-9 (68 s) every column's
   reflectance within 3.5e-6, inside its 41 patches' budget of 1e-7 each. */
#define KL_CELLS 4096 /* cells per patch at most; then the sum so far is taken */

typedef struct kl_cell {
    double w0, w1, p0, p1;
    double q[4]; /* the rule on its quarters: (w lo, p lo), (w hi, p lo), (w lo, p hi), (w hi, p hi) */
    double err;  /* |q[0] + .. + q[3] - the rule on the whole cell| */
    int depth;
} kl_cell;

static void cell_set(const kl_ctx *c, kl_cell *k, double w0, double w1, double p0, double p1,
                     double whole, int depth)
{
    double wm = 0.5 * (w0 + w1), pm = 0.5 * (p0 + p1);
    k->w0 = w0;
    k->w1 = w1;
    k->p0 = p0;
    k->p1 = p1;
    k->q[0] = gl2(c, w0, wm, p0, pm);
    k->q[1] = gl2(c, wm, w1, p0, pm);
    k->q[2] = gl2(c, w0, wm, pm, p1);
    k->q[3] = gl2(c, wm, w1, pm, p1);
    k->err = fabs(k->q[0] + k->q[1] + k->q[2] + k->q[3] - whole);
    k->depth = depth;
}

static double adapt_global(const kl_ctx *c, double w0, double w1, double p0, double p1,
                           double whole, double eps, kl_cell *cells)
{
    int nc = 1;
    cell_set(c, &cells[0], w0, w1, p0, p1, whole, 0);
    for (;;) {
        double total = 0.0, worst = -1.0;
        int at = -1;
        for (int k = 0; k < nc; k++) {
            total += cells[k].err;
            if (cells[k].depth < KL_DEPTH && cells[k].err > worst) {
                worst = cells[k].err;
                at = k;
            }
        }
        if (total <= eps || at < 0 || nc + 3 > KL_CELLS)
            break;
        kl_cell pa = cells[at];
        double wm = 0.5 * (pa.w0 + pa.w1), pm = 0.5 * (pa.p0 + pa.p1);
        cell_set(c, &cells[at], pa.w0, wm, pa.p0, pm, pa.q[0], pa.depth + 1);
        cell_set(c, &cells[nc++], wm, pa.w1, pa.p0, pm, pa.q[1], pa.depth + 1);
        cell_set(c, &cells[nc++], pa.w0, wm, pm, pa.p1, pa.q[2], pa.depth + 1);
        cell_set(c, &cells[nc++], wm, pa.w1, pm, pa.p1, pa.q[3], pa.depth + 1);
    }
    double sum = 0.0;
    for (int k = 0; k < nc; k++)
        sum += cells[k].q[0] + cells[k].q[1] + cells[k].q[2] + cells[k].q[3];
    return sum;
}

typedef struct kl_job {
    const btdf_params *p;
    double n, scale;
    const rad_klems_basis *kb;
    int reflect;
    const btdf_full *ms; /* model full: the tally at n, else NULL */
    double *acc; /* acc[out * np + in] */
} kl_job;

/* Panels of at most pi/4 in azimuth for a patch of width dp: cos(m phi), m <= 4, then
   has at most half a period per panel, which 4 Gauss nodes integrate to ~1e-5. */
static int kl_ms_panels(double dp)
{
    int k = (int)ceil(dp / (0.25 * M_PI) - 1e-9);
    return k < 1 ? 1 : k;
}

/* Model full: the tally's multiply scattered part added to column i's patch integrals
   (col[o], as kl_column sums them: the mean over the incident patch of the integral
   over patch o in projected solid angle). The part is a smooth series (degree 7 in mu,
   cos(m phi) to m = 4, linear in ti between the ladder's angles, clipped at 0), so a
   fixed product Gauss rule does: over the incident patch 4 nodes in w = sin^2 t, over
   the outgoing one KL_MS_UPANELS panels of 4 nodes in mu = |cos t| (in w the series
   has a square-root end at grazing, which cost 7e-3 of the energy of a grazing
   reflection inside the glass at n = 1/1.5, s = 1; in mu, two panels: 1.4e-3, against
   a 400 x 400 midpoint sum), and 4 per azimuth panel (kl_ms_panels). The azimuth is
   MODEL.md's, pi straight on (transmission) or at the mirror (reflection), as gl2
   forms it: cos phi = -cos(po - alpha). */
#define KL_MS_UPANELS 2
static void kl_ms_column(const btdf_full *ms, int reflect, const rad_klems_basis *kb, int i,
                         double *col)
{
    double w0, w1, p0, p1;
    patch_rect(kb, i, &w0, &w1, &p0, &p1);
    int ni = kl_ms_panels(p1 - p0), np = kb->npatch;
    double hw = 0.5 * (w1 - w0), hp = 0.5 * (p1 - p0) / ni;
    for (int a = 0; a < 4; a++) {
        double w = w0 + hw * (1.0 + gl_x[a]);
        double ti_deg = asin(sqrt(fmin(1.0, w))) * (180.0 / M_PI);
        for (int b = 0; b < 4 * ni; b++) {
            double alpha = p0 + hp * (2.0 * (b / 4) + 1.0 + gl_x[b % 4]);
            double wt = gl_w[a] * 0.5 * gl_w[b % 4] * 0.5 / ni; /* sums to 1 */
            for (int o = 0; o < np; o++) {
                double v0, v1, q0, q1;
                patch_rect(kb, o, &v0, &v1, &q0, &q1);
                int no = kl_ms_panels(q1 - q0);
                double u0 = sqrt(fmax(0.0, 1.0 - v1)), u1 = sqrt(fmax(0.0, 1.0 - v0));
                double hu = 0.5 * (u1 - u0) / KL_MS_UPANELS, hq = 0.5 * (q1 - q0) / no, sum = 0.0;
                for (int c = 0; c < 4 * KL_MS_UPANELS; c++) {
                    double mu = u0 + hu * (2.0 * (c / 4) + 1.0 + gl_x[c % 4]);
                    for (int d = 0; d < 4 * no; d++) {
                        double po = q0 + hq * (2.0 * (d / 4) + 1.0 + gl_x[d % 4]);
                        sum += gl_w[c % 4] * gl_w[d % 4] * mu *
                               full_ms(ms, reflect, ti_deg, mu, -cos(po - alpha));
                    }
                }
                col[o] += wt * sum * hu * hq; /* projected solid angle mu dmu dphi */
            }
        }
    }
}

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
    c.model = j->p->model;
    c.reflect = j->reflect;
    double *col = calloc((size_t)np, sizeof *col);
    kl_cell *cells = c.reflect ? malloc(KL_CELLS * sizeof *cells) : NULL;
    if (!col || (c.reflect && !cells)) {
        free(col);
        free(cells);
        return; /* the caller sees the NaN sentinel left in acc */
    }
    double hw = 0.5 * (w1 - w0), hp = 0.5 * (p1 - p0);
    /* Incident nodes in the polar direction: 4 in w, or in the reflection's grazing band
       cti and a weight, summing to 1 over them. */
    double nc[4 * KL_GRAZE_PANELS], nw[4 * KL_GRAZE_PANELS];
    int nn = 4;
    for (int a = 0; a < 4; a++)
        nw[a] = gl_w[a] * 0.5; /* 4 nodes in w: gl_w hw / (w1 - w0) */
    if (c.reflect && w1 >= 1.0) {
        /* the grazing band: KL_GRAZE_PANELS panels in u = cos(ti), w = 1 - u^2 */
        double u1 = sqrt(1.0 - w0), hu = u1 / KL_GRAZE_PANELS;
        nn = 4 * KL_GRAZE_PANELS;
        for (int m = 0; m < KL_GRAZE_PANELS; m++)
            for (int a = 0; a < 4; a++) {
                double u = hu * (m + 0.5 * (1.0 + gl_x[a]));
                nc[4 * m + a] = u;
                nw[4 * m + a] = gl_w[a] * 0.5 * hu * 2.0 * u / (w1 - w0); /* dw = 2u du */
            }
    }
    /* Panels in azimuth: 1, or KL_CAP_PANELS over the reflection's polar cap. */
    int np_phi = c.reflect && w0 <= 0.0 ? KL_CAP_PANELS : 1;
    for (int a = 0; a < nn; a++) {
        double sti, cti;
        if (nn == 4) { /* the transmission's nodes exactly as they always were */
            double w = w0 + hw * (1.0 + gl_x[a]);
            sti = sqrt(w);
            cti = sqrt(fmax(0.0, 1.0 - w));
        } else {
            cti = nc[a];
            sti = sqrt(fmax(0.0, 1.0 - cti * cti));
        }
        rho_in_init_m(&c.ri, sti, cti, c.s, c.k0, c.model);
        c.ti = nn == 4 ? asin(fmin(1.0, sti)) : acos(cti);
        for (int b = 0; b < 4 * np_phi; b++) {
            int bp = b / 4, bb = b % 4;
            c.alpha = p0 + hp / np_phi * (2.0 * bp + 1.0 + gl_x[bb]);
            /* sums to 1: (w weight) (phi weight) / li, li = hw hp 2 */
            double wt = nn == 4 && np_phi == 1 ? gl_w[a] * gl_w[b] * hw * hp * 0.5 / li
                                               : nw[a] * gl_w[bb] * 0.5 / np_phi;
            for (int o = 0; o < np; o++) {
                double v0, v1, q0, q1;
                patch_rect(kb, o, &v0, &v1, &q0, &q1);
                double whole = gl2(&c, v0, v1, q0, q1);
                col[o] += wt * (c.reflect ? adapt_global(&c, v0, v1, q0, q1, whole, KL_EPS, cells)
                                          : adapt(&c, v0, v1, q0, q1, whole, KL_EPS, 0));
            }
        }
    }
    if (j->ms)
        kl_ms_column(j->ms, c.reflect, kb, (int)i, col);
    for (int o = 0; o < np; o++) {
        double v0, v1, q0, q1;
        patch_rect(kb, o, &v0, &v1, &q0, &q1);
        double lo = 0.5 * (v1 - v0) * (q1 - q0);
        j->acc[(size_t)o * np + i] = j->scale * col[o] / lo; /* lo > 0 for every patch */
    }
    free(cells);
    free(col);
}

btdf_status rad_klems_acc(const btdf_params *p, double n, double scale, int reflect,
                          const rad_klems_basis *kb, const btdf_full *ms, int threads,
                          double **out, char *msg, size_t msglen)
{
    size_t np = (size_t)kb->npatch;
    btdf_params single = rad_single(p); /* full: the single scattering is smith's */
    kl_job j = {&single, n, scale, kb, reflect, ms, malloc(np * np * sizeof(double))};
    *out = NULL;
    if (!j.acc) {
        if (msg && msglen)
            snprintf(msg, msglen, "out of memory for a %zu x %zu Klems matrix", np, np);
        return BTDF_ENOMEM;
    }
    for (size_t k = 0; k < np * np; k++)
        j.acc[k] = NAN; /* sentinel: a column whose scratch could not be allocated */
    core_parallel_for(threads, np, kl_column, &j);
    for (size_t k = 0; k < np * np; k++) {
        if (isnan(j.acc[k])) {
            free(j.acc);
            if (msg && msglen)
                snprintf(msg, msglen, "out of memory integrating the Klems matrix");
            return BTDF_ENOMEM;
        }
    }
    *out = j.acc;
    return BTDF_OK;
}

float rad_klems_value(double v)
{
    char t[32];
    snprintf(t, sizeof t, "%.6g", v);
    return (float)strtod(t, NULL); /* the value exactly as the file holds it */
}

btdf_status rad_klems_build(const btdf_params *p, double n, double scale,
                            const rad_klems_basis *kb, const btdf_full *ms, int threads,
                            rad_block *blk, char *msg, size_t msglen)
{
    size_t np = (size_t)kb->npatch;
    double *acc = NULL;
    btdf_status st = rad_klems_acc(p, n, scale, blk->reflect, kb, ms, threads, &acc, msg,
                                   msglen);
    if (st != BTDF_OK)
        return st;
    float *m = malloc(np * np * sizeof *m);
    if (!m) {
        free(acc);
        if (msg && msglen)
            snprintf(msg, msglen, "out of memory for a %zu x %zu Klems matrix", np, np);
        return BTDF_ENOMEM;
    }
    for (size_t k = 0; k < np * np; k++)
        m[k] = rad_klems_value(acc[k]);
    free(acc);
    blk->klems = m;
    return BTDF_OK;
}
