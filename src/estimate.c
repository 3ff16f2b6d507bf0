/* SPDX-License-Identifier: MIT */
/* estimate.c: a table's error against Eq. 25 (MODEL.md section 6) at points it was not built on. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "table_impl.h"

void table_eval_sc(const btdf_table *t, double ti, double sti, double cti, double sto,
                   double cto, double cph, double sph, double phi_fold, double to,
                   double *out);

/* splitmix64: a small, well-mixed generator; one stream per test angle, so the
   points do not depend on which thread handles which angle. */
static uint64_t mix(uint64_t *x)
{
    uint64_t z = (*x += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double unif(uint64_t *x) { return (double)(mix(x) >> 11) * (1.0 / 9007199254740992.0); }

typedef struct est_job {
    const btdf_params *p; /* the truth: Eq. 25 with these parameters */
    est_eval_fn fn;       /* the evaluation under test */
    const void *obj;
    double ti_min, span;
    size_t angles, nu, npsi, nmu, nphi;
    uint64_t seed;
    btdf_ti_error *res;
    size_t *points;
} est_job;

/*
 * Two sample sets per incident angle, combined by the balance heuristic (multiple
 * importance sampling) on the measure |cos to| d(omega_o):
 *  A: facet slopes stratified in w = 1 - exp(-u^2) and psi, which follows the lobe
 *     however narrow it is; a sample stands for V_A = |cos to|/chi d(omega_h) of it;
 *  B: outgoing directions stratified in (cos to, phi), V_B = |cos to| d(cos to) d(phi).
 * Each sample counts with V_A V_B / (V_A + V_B) (V_A = infinity where A cannot reach).
 * A alone has unbounded weights for n < 1, where chi -> 0 at the critical angle;
 * B alone misses narrow lobes; together they are bounded and follow the lobe.
 */
#define U_EST 7.0 /* A's neglected tail holds exp(-49) of the facet distribution */

typedef struct est_acc {
    double l1, sgn, dmax, vmax;
} est_acc;

static void est_add(est_acc *e, double tab, double rho, double weight)
{
    double d = tab - rho;
    e->l1 += fabs(d) * weight;
    e->sgn += d * weight;
    e->dmax = fmax(e->dmax, fabs(d));
    e->vmax = fmax(e->vmax, rho);
}

/* Measure one A sample of slope u (tan tn = 2u/s) stands for, per unit outgoing
   weight |cos to|/chi: d(omega_h)/(dw dpsi) (2/s^2) e^{u^2} / q^{3/2}, q = 1 + tan^2 tn,
   times the stratum size, doubled for psi < 0. */
static double a_measure(double u, double s, double dw, double dpsi)
{
    double rr = 2.0 * u / s, q = 1.0 + rr * rr;
    return (2.0 / (s * s)) * exp(u * u) / (q * sqrt(q)) * dw * dpsi * 2.0;
}

static void est_angle(void *arg, size_t k)
{
    est_job *j = arg;
    const btdf_params *p = j->p;
    uint64_t rng = j->seed ^ (0xa0761d6478bd642full * (uint64_t)(k + 1));
    double ti = j->ti_min + j->span * ((double)k + unif(&rng)) / (double)j->angles;
    if (ti > M_PI / 2)
        ti = M_PI / 2;
    double sti = sin(ti), cti = cos(ti), s = p->smoothness;
    rho_in a;
    rho_in_init(&a, sti, cti, s, p->k0);
    btdf_ti_error *r = &j->res[k];
    memset(r, 0, sizeof *r);
    r->ti = ti;
    double Tall[BTDF_MAX_CHANNELS];
    btdf_transmittance(p, ti, Tall);
    double wmax = -expm1(-U_EST * U_EST);
    double dw = wmax / (double)j->nu, dpsi = M_PI / (double)j->npsi;
    double dmu = 1.0 / (double)j->nmu, dphi = M_PI / (double)j->nphi;
    size_t pts = 0;
    double tab[BTDF_MAX_CHANNELS];
    for (int c = 0; c < p->channels; c++) {
        double n = p->ior[c], T = Tall[c];
        est_acc acc = {0.0, 0.0, 0.0, 0.0};
        for (size_t iu = 0; iu < j->nu; iu++) {
            for (size_t ip = 0; ip < j->npsi; ip++) {
                double w = wmax * ((double)iu + unif(&rng)) / (double)j->nu;
                double psi = M_PI * ((double)ip + unif(&rng)) / (double)j->npsi;
                double u = sqrt(-log1p(-w)); /* w < 1: finite */
                double rr = 2.0 * u / s;
                double ctn = 1.0 / sqrt(1.0 + rr * rr), stn = rr * ctn;
                facet_geo g;
                pts++;
                if (!facet_eval(n, s, p->k0, &a, stn, ctn, cos(psi), sin(psi), &g))
                    continue; /* no outgoing direction: both the table and Eq. 25 are 0 */
                double va = g.weight * a_measure(u, s, dw, dpsi);
                double vb = -g.cos_to * dmu * dphi * 2.0;
                double to = atan2(g.sin_to, g.cos_to);
                double pf = fabs(atan2(g.sin_phi, g.cos_phi));
                const double q[8] = {sti, cti, g.sin_to, g.cos_to, g.cos_phi, g.sin_phi, pf, to};
                j->fn(j->obj, ti, q, tab);
                /* g.rho is Eq. 25 through the kernel, independent of the table */
                est_add(&acc, tab[c], g.rho, va > 0.0 ? va * vb / (va + vb) : 0.0);
            }
        }
        for (size_t im = 0; im < j->nmu; im++) {
            for (size_t ip = 0; ip < j->nphi; ip++) {
                double mu = -((double)im + unif(&rng)) / (double)j->nmu; /* cos to */
                double ph = M_PI * ((double)ip + unif(&rng)) / (double)j->nphi;
                double sto = sqrt(fmax(0.0, 1.0 - mu * mu)), cph = cos(ph), sph = sin(ph);
                double vb = -mu * dmu * dphi * 2.0, share = vb, tn, ps;
                pts++;
                if (facet_of(n, sti, cti, sto, mu, cph, sph, &tn, &ps)) {
                    double u = 0.5 * s * tan(tn);
                    facet_geo g;
                    if (u < U_EST &&
                        facet_eval(n, s, p->k0, &a, sin(tn), cos(tn), cos(ps), sin(ps), &g)) {
                        double va = g.weight * a_measure(u, s, dw, dpsi);
                        share = va * vb / (va + vb);
                    }
                }
                rho_out b;
                rho_out_init(&b, sto, mu, s, p->k0);
                double rho = rho_kernel(n, s, &a, &b, cph, sph);
                const double q[8] = {sti, cti, sto, mu, cph, sph, ph, atan2(sto, mu)};
                j->fn(j->obj, ti, q, tab);
                est_add(&acc, tab[c], rho, share);
            }
        }
        double fl = fmax(T, 0.01); /* MODEL.md section 6 floor */
        double el1 = acc.l1 / fl, et = fabs(acc.sgn) / fl;
        double em = (T >= 0.01 && acc.vmax > 0.0) ? acc.dmax / acc.vmax : 0.0;
        if (c == 0) {
            r->T = T;
            r->T_table = T + acc.sgn;
        }
        r->e_l1 = fmax(r->e_l1, el1);
        r->e_t = fmax(r->e_t, et);
        r->e_max = fmax(r->e_max, em);
    }
    j->points[k] = pts;
}

static void table_fn(const void *obj, double ti, const double *q, double *out)
{
    table_eval_sc(obj, ti, q[0], q[1], q[2], q[3], q[4], q[5], q[6], q[7], out);
}

btdf_status btdf_estimate_fn(const btdf_params *p, double ti_min, double ti_max,
                             size_t test_angles, size_t points_per_angle, uint64_t seed,
                             int threads, est_eval_fn fn, const void *obj, btdf_report *r)
{
    if (!p || !fn || !r || !(ti_min >= 0.0 && ti_max <= M_PI / 2 && ti_min <= ti_max))
        return BTDF_EINVAL;
    if (test_angles == 0)
        test_angles = 48;
    if (points_per_angle == 0)
        points_per_angle = 8192;
    if (test_angles > 100000 || points_per_angle > 100000000)
        return BTDF_EINVAL;
    double t0 = btdf_now();
    est_job j;
    j.p = p;
    j.fn = fn;
    j.obj = obj;
    j.ti_min = ti_min;
    j.span = ti_max - ti_min;
    j.angles = test_angles;
    j.npsi = 32;
    j.nu = (points_per_angle + 31) / 32;
    j.nmu = 64;
    j.nphi = 64;
    j.seed = seed;
    j.res = calloc(test_angles, sizeof *j.res);
    j.points = calloc(test_angles, sizeof *j.points);
    if (!j.res || !j.points) {
        free(j.res);
        free(j.points);
        return BTDF_ENOMEM;
    }
    btdf_parallel_for(threads, test_angles, est_angle, &j);
    memset(r, 0, sizeof *r);
    r->test_angles = test_angles;
    r->per_ti = j.res;
    for (size_t k = 0; k < test_angles; k++) {
        const btdf_ti_error *e = &j.res[k];
        r->test_points += j.points[k];
        r->e_l1_max = fmax(r->e_l1_max, e->e_l1);
        r->e_t_max = fmax(r->e_t_max, e->e_t);
        r->e_max_max = fmax(r->e_max_max, e->e_max);
        r->e_l1_mean += e->e_l1 / (double)test_angles;
        r->e_t_mean += e->e_t / (double)test_angles;
        if (e->T >= 0.01)
            r->e_max_angles++;
    }
    for (size_t k = 0; k < test_angles; k++) /* e_max's mean is over the angles it has */
        if (j.res[k].T >= 0.01)
            r->e_max_mean += j.res[k].e_max / (double)r->e_max_angles;
    free(j.points);
    r->seconds_estimate = btdf_now() - t0;
    return BTDF_OK;
}

BTDF_API btdf_status btdf_table_estimate(const btdf_table *t, double ti_min, double ti_max,
                                         size_t test_angles, size_t points_per_angle,
                                         uint64_t seed, int threads, btdf_report *r)
{
    if (!t)
        return BTDF_EINVAL;
    btdf_status st = btdf_estimate_fn(&t->p, ti_min, ti_max, test_angles, points_per_angle,
                                      seed, threads, table_fn, t, r);
    if (st == BTDF_OK) {
        r->slices = t->ns;
        r->samples = btdf_table_node_count(t);
    }
    return st;
}

BTDF_API void btdf_report_clear(btdf_report *r)
{
    if (!r)
        return;
    free(r->per_ti);
    r->per_ti = NULL;
}
