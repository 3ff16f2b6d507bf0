/* SPDX-License-Identifier: MIT */
/* report.c: the error report of one block as a render reads it (MODEL.md section 6):
   transmission blocks through the estimator, reflection blocks on the probes. */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "radiance/radiance_impl.h"

typedef struct rad_est {
    const btdf_rad *r;
    btdf_side light;
    int c, chosen;
} rad_est;

static void rad_est_fn(const void *obj, double ti, const double *q, double *out)
{
    const rad_est *e = obj;
    /* q = {sin ti, cos ti, sin to, cos to, cos phi, sin phi, |phi|, to} */
    out[0] = rad_render(e->r, e->light, e->c, e->chosen, ti, q[7], atan2(q[5], q[4]));
}

/* A reflection block's report: the probe estimate (stratified light angles over 0-90
   degrees, views stratified in projected solid angle) against rho_r, since the
   transmission estimator follows Eq. 25's lobe. */
static btdf_status rad_reflect_report(const btdf_rad *r, int k, int c, int chosen,
                                      size_t test_angles, size_t points_per_angle,
                                      uint64_t seed, int threads, btdf_report *rep)
{
    double t0 = core_now();
    size_t m = test_angles ? test_angles : 48, ppa = points_per_angle ? points_per_angle : 8192;
    size_t ns = (size_t)sqrt((double)ppa / 2.0);
    ns = ns < 4 ? 4 : ns;
    rad_probes pr;
    btdf_status st = rad_probes_make(r, k, c, M_PI / 2, m, ns, 2 * ns, seed, threads, &pr);
    if (st != BTDF_OK)
        return st;
    memset(rep, 0, sizeof *rep);
    rep->per_ti = malloc(m * sizeof *rep->per_ti);
    if (!rep->per_ti) {
        rad_probes_free(&pr);
        return BTDF_ENOMEM;
    }
    int tree = r->basis == RAD_BASIS_TREE3;
    pr.chosen = chosen;
    rad_probes_eval(&pr, tree ? &r->b[k] : NULL, threads, rep->per_ti);
    rep->test_angles = m;
    rep->test_points = m * pr.kv;
    for (size_t i = 0; i < m; i++) {
        const btdf_ti_error *e = &rep->per_ti[i];
        rep->e_l1_max = fmax(rep->e_l1_max, e->e_l1);
        rep->e_l1_mean += e->e_l1 / (double)m;
        rep->e_t_max = fmax(rep->e_t_max, e->e_t);
        rep->e_t_mean += e->e_t / (double)m;
        if (e->T >= 0.01) {
            rep->e_max_max = fmax(rep->e_max_max, e->e_max);
            rep->e_max_mean += e->e_max;
            rep->e_max_angles++;
        }
    }
    if (rep->e_max_angles)
        rep->e_max_mean /= (double)rep->e_max_angles;
    rad_probes_free(&pr);
    rep->seconds_estimate = core_now() - t0;
    rep->seconds_build = r->seconds_build;
    rep->tolerance = r->tolerance;
    rep->metric = BTDF_METRIC_L1;
    const btdf_full *ms = rad_ms(r, c, rad_n_light(r, k, c));
    rep->ms_noise = ms ? full_ms_noise(ms, 1, 0.0, M_PI / 2) : 0.0;
    /* a Klems matrix has no tolerance: its entries are exact averages */
    rep->met = !tree || btdf_rad_e_l1_checked(rep) <= r->tolerance;
    rep->slices = tree ? (size_t)r->b[k].depth : (size_t)r->kb->npatch;
    rep->samples = tree ? r->b[k].leaves : (size_t)r->kb->npatch * (size_t)r->kb->npatch;
    return BTDF_OK;
}

BTDF_API btdf_status btdf_rad_report(const btdf_rad *r, int k, size_t test_angles,
                                     size_t points_per_angle, uint64_t seed, int threads,
                                     btdf_report *rep)
{
    return btdf_rad_report_channel(r, k, 0, test_angles, points_per_angle, seed, threads, rep);
}

BTDF_API btdf_status btdf_rad_report_channel(const btdf_rad *r, int k, int c,
                                             size_t test_angles, size_t points_per_angle,
                                             uint64_t seed, int threads, btdf_report *rep)
{
    return rad_report_ch(r, k, c, 0, test_angles, points_per_angle, seed, threads, rep);
}

/* btdf_rad_report_channel; chosen: a colour tree's channels as its builder chose them
   (the builder's own check), not as read back from the file's Y, u', v'. */
btdf_status rad_report_ch(const btdf_rad *r, int k, int c, int chosen,
                                 size_t test_angles, size_t points_per_angle, uint64_t seed,
                                 int threads, btdf_report *rep)
{
    if (!r || !rep || k < 0 || k >= r->nblocks || c < 0 || c >= (r->channels == 3 ? 3 : 1))
        return BTDF_EINVAL;
    if (r->b[k].reflect)
        return rad_reflect_report(r, k, c, chosen, test_angles, points_per_angle, seed,
                                  threads, rep);
    btdf_params q = rad_single(&r->p);
    q.channels = 1;
    q.ior[0] = rad_n_light(r, k, c);
    rad_est e = {r, r->b[k].light, r->channels == 3 ? c : -1, chosen};
    /* full: measured against smith's kernel plus the tally at the light's index */
    btdf_full *ms[1] = {rad_ms(r, c, q.ior[0])};
    est_opts opt;
    memset(&opt, 0, sizeof opt);
    opt.full = ms;
    btdf_status st =
        ms[0] ? est_knots_part_opt(&q, 0, 0.0, M_PI / 2, test_angles, points_per_angle, seed,
                                   threads, NULL, 0, rad_est_fn, &e, &opt, rep)
              : est_fn(&q, 0.0, M_PI / 2, test_angles, points_per_angle, seed, threads,
                       rad_est_fn, &e, rep);
    if (st == BTDF_OK) {
        rep->ms_noise = ms[0] ? full_ms_noise(ms[0], 0, 0.0, M_PI / 2) : 0.0;
        rep->seconds_build = r->seconds_build;
        rep->tolerance = r->tolerance;
        rep->metric = BTDF_METRIC_L1;
        rep->met = r->basis != RAD_BASIS_TREE3 || btdf_rad_e_l1_checked(rep) <= r->tolerance;
        if (r->basis == RAD_BASIS_TREE3) {
            rep->slices = (size_t)r->b[k].depth;
            rep->samples = r->b[k].leaves;
        } else {
            rep->slices = (size_t)r->kb->npatch;
            rep->samples = (size_t)r->kb->npatch * (size_t)r->kb->npatch;
        }
    }
    return st;
}
