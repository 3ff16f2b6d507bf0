/* SPDX-License-Identifier: MIT */
/* test_sim_pane.c: the simulator's pane (btdf_sim_opts.pane): a flat slab against the
   closed form of its Fresnel series with absorption, energy, and bad pane values. The
   tolerances are multiples of the run's own standard errors; each says why. */
#include <string.h>

#include "btdf_sim.h"
#include "btdf_test.h"

#define DEG (M_PI / 180.0)

typedef struct pane_case {
    double n, s_front, s_back, thickness, absorption;
    int front_flat, from_back;
} pane_case;

static int hist_bins; /* theta bins of the next runs (18 |phi| bins), 0: none */

static btdf_status try_run(const pane_case *c, const double *ti, size_t nti, uint64_t rays,
                           btdf_sim_result **r, char *msg, size_t msglen)
{
    btdf_sim_opts o;
    btdf_sim_opts_default(&o);
    o.ior[0] = c->n;
    o.smoothness = c->s_front;
    o.theta_i = ti;
    o.n_theta = nti;
    o.rays = rays;
    o.seed = 11;
    o.threads = 2;
    o.cells_per_tau = 8; /* 64 x 64 tiles: the rough cases here need no finer grid */
    o.tile_tau = 8;
    o.pane = 1;
    o.front_flat = c->front_flat;
    o.back_smoothness = c->s_back;
    o.thickness_mm = c->thickness;
    o.absorption_per_mm = c->absorption;
    o.from_back = c->from_back;
    o.theta_bins = hist_bins;
    o.phi_bins = 18;
    return btdf_sim_run(&o, r, msg, msglen);
}

static btdf_sim_result *run(const pane_case *c, const double *ti, size_t nti, uint64_t rays)
{
    btdf_sim_result *r = NULL;
    char msg[256] = "";
    btdf_status st = try_run(c, ti, nti, rays, &r, msg, sizeof msg);
    if (st != BTDF_OK)
        print_error("%s\n", msg);
    assert_status(BTDF_OK, st);
    assert_non_null(r);
    return r;
}

static void assert_within_se(double a, double b, double se, double k, const char *what)
{
    if (!(fabs(a - b) <= k * se)) {
        print_error("%s: %.6f vs %.6f, %.2f standard errors (allowed %g)\n", what, a, b,
                    se > 0 ? fabs(a - b) / se : INFINITY, k);
        fail();
    }
}

/* The closed form of a flat slab as the simulator treats light: unpolarised Fresnel
   reflectance R chosen at every hit (the same R at the entry and, by reciprocity, at
   the inside of either face), survival tau = exp(-a d / cos theta_t) per crossing:
   R_sys = R + (1 - R)^2 R tau^2 / (1 - R^2 tau^2), T_sys = (1 - R)^2 tau / (1 - R^2
   tau^2). */
static void slab(double n, double ti, double d, double a, double *R, double *T)
{
    double r = btdf_fresnel_r(n, ti), st = sin(ti) / n;
    if (st >= 1.0) { /* total reflection at the entry */
        *R = 1.0;
        *T = 0.0;
        return;
    }
    double tau = exp(-a * d / sqrt(1.0 - st * st)), den = 1.0 - r * r * tau * tau;
    *R = r + (1.0 - r) * (1.0 - r) * r * tau * tau / den;
    *T = (1.0 - r) * (1.0 - r) * tau / den;
}

/* Both faces flat (front_flat, back 0), and both rough with s = 1e6 (slopes of RMS
   2e-6: flat to 1e-11 in Fresnel's terms, so the same law through the walk of the
   tiles, mirrored for the back face): R, T and A against the closed form within 4
   standard errors (a false alarm once in 16,000 per number for a correct tracer; the
   batch-means errors are about sqrt(p (1 - p) / rays), 3e-4 to 5e-4 here), from the
   front and from the back. Past the critical angle of a pane less dense than its
   surroundings every path reflects at the entry: R = 1 exactly. The angles of a run
   draw from their own streams, the same in every case of one seed, so the cases'
   deviations at one angle are alike (not independent trials). */
static void flat_pane_is_the_series(void **state)
{
    (void)state;
    const double ti[4] = {0, 30 * DEG, 60 * DEG, 80 * DEG};
    const pane_case cases[] = {
        {1.5, 3, 0, 4, 0.1, 1, 0},      {1.5, 3, 0, 4, 0.1, 1, 1},
        {1.5, 1e6, 1e6, 2, 0.3, 0, 0},  {1.5, 1e6, 0, 1, 0.0, 0, 1},
        {1 / 1.4, 3, 0, 4, 0.05, 1, 0},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        const pane_case *pc = &cases[c];
        btdf_sim_result *r = run(pc, ti, 4, 400000);
        for (size_t k = 0; k < 4; k++) {
            const btdf_sim_tally *t = &r->tally[k];
            double R, T;
            slab(pc->n, ti[k], pc->thickness, pc->absorption, &R, &T);
            print_message("case %zu ti %g: R %.5f (%.5f +- %.5f) T %.5f (%.5f +- %.5f) A %.5f "
                          "(%.5f +- %.5f)\n", c, ti[k] / DEG, R, t->R.mean, t->R.se, T, t->T.mean,
                          t->T.se, 1 - R - T, t->A.mean, t->A.se);
            assert_int_equal(0, (int)t->lost);
            if (R == 1.0) {
                assert_true(t->R.mean == 1.0 && t->T.mean == 0.0 && t->A.mean == 0.0);
                continue;
            }
            assert_true(t->R.se > 0.0 && t->T.se > 0.0);
            assert_within_se(t->R.mean, R, t->R.se, 4.0, "slab R");
            assert_within_se(t->T.mean, T, t->T.se, 4.0, "slab T");
            if (pc->absorption > 0.0)
                assert_within_se(t->A.mean, 1.0 - R - T, t->A.se, 4.0, "slab A");
            else
                assert_true(t->A.mean == 0.0);
        }
        btdf_sim_result_free(r);
    }
}

/* Every path ends in R, T or A with weight one and none is lost: R + T + A = 1 to the
   rounding of three divisions (1e-12 is 4500 ulps of 1), every order adds up to its
   total, and without absorption A is 0 exactly and R + T = 1. Rough faces on both
   sides (s = 1 front, 3 back, and a flat back), light from both sides. */
static void pane_energy(void **state)
{
    (void)state;
    const double ti[3] = {0, 45 * DEG, 80 * DEG};
    const pane_case cases[] = {
        {1.5, 1, 3, 4, 0.05, 0, 0}, {1.5, 1, 3, 4, 0.05, 0, 1},
        {1.5, 1, 0, 4, 0.0, 0, 0},  {1.5, 1, 0, 4, 0.0, 0, 1},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        btdf_sim_result *r = run(&cases[c], ti, 3, 20000);
        for (size_t k = 0; k < 3; k++) {
            const btdf_sim_tally *t = &r->tally[k];
            assert_int_equal(0, (int)t->lost);
            assert_close(t->R.mean + t->T.mean + t->A.mean, 1.0, 0, 1e-12);
            double so = 0, sr = 0;
            for (int q = 0; q < BTDF_SIM_ORDERS; q++) {
                so += t->T_order[q].mean;
                sr += t->R_order[q].mean;
            }
            assert_close(so, t->T.mean, 0, 1e-12);
            assert_close(sr, t->R.mean, 0, 1e-12);
            /* through a pane takes two hits at least */
            assert_true(t->T_order[0].mean == 0.0);
            if (cases[c].absorption == 0.0) {
                assert_true(t->A.mean == 0.0);
                assert_close(t->R.mean + t->T.mean, 1.0, 0, 1e-12);
            } else {
                assert_true(t->A.mean > 0.0);
            }
        }
        btdf_sim_result_free(r);
    }
}

/* The air-to-air system is reciprocal: rho(front lit; i -> o) = rho(back lit; o -> i)
   for the transmission (no n^2: air on both sides), whatever the faces, absorption
   included (the path is the same backwards, its survival too). A pane with a rough
   front (s = 1), a rough back (s = 3), 4 mm and 0.05 per mm, bins of 2 x 10 degrees
   in the forward plane; the angles are the bins' centres, as in test_sim.c's
   reciprocity (the averaging over a bin differs between the sides by O(bin^2 / 24) =
   5e-5 relative, far below the noise of about 3 % per bin). Four combined standard
   errors. */
static void pane_reciprocity(void **state)
{
    (void)state;
    const double ti[2] = {21 * DEG, 41 * DEG}; /* centres of bins 10 and 20 */
    const int bin[2] = {10, 20}, fwd = 17;     /* |phi| in [170, 180] */
    pane_case front = {1.5, 1, 3, 4, 0.05, 0, 0}, back = front;
    back.from_back = 1;
    hist_bins = 45;
    btdf_sim_result *f = run(&front, ti, 2, 400000);
    btdf_sim_result *b = run(&back, ti, 2, 400000);
    hist_bins = 0;
    for (int a = 0; a < 2; a++) {
        int o = 1 - a;
        /* rho = P / (solid angle cos to), the bin's centre cosine */
        size_t ia = (size_t)bin[o] * 18 + fwd, ib = (size_t)bin[a] * 18 + fwd;
        double om_o = btdf_sim_bin_solid_angle(45, 18, bin[o], fwd);
        double om_a = btdf_sim_bin_solid_angle(45, 18, bin[a], fwd);
        double r1 = f->tally[a].hist_T[ia].mean / om_o / cos(ti[o]);
        double e1 = f->tally[a].hist_T[ia].se / om_o / cos(ti[o]);
        double r2 = b->tally[o].hist_T[ib].mean / om_a / cos(ti[a]);
        double e2 = b->tally[o].hist_T[ib].se / om_a / cos(ti[a]);
        print_message("pane reciprocity %d: %.4f +- %.4f vs %.4f +- %.4f\n", a, r1, e1, r2, e2);
        assert_true(e1 > 0 && e2 > 0 && e1 < 0.1 * r1);
        assert_within_se(r1, r2, sqrt(e1 * e1 + e2 * e2), 4.0, "pane reciprocity");
    }
    btdf_sim_result_free(f);
    btdf_sim_result_free(b);
}

/* Out-of-range pane values are refused with a message naming them. */
static void pane_bad_input(void **state)
{
    (void)state;
    const double ti = 30 * DEG;
    const struct {
        pane_case c;
        const char *says;
    } bad[] = {
        {{1.5, 3, 0, 0, 0, 0, 0}, "thickness 0"},
        {{1.5, 3, 0, NAN, 0, 0, 0}, "thickness nan"},
        {{1.5, 3, 0, 4, -1, 0, 0}, "absorption -1"},
        {{1.5, 3, -2, 4, 0, 0, 0}, "smoothness -2"},
        {{1.5, 3, 0, 4, INFINITY, 0, 0}, "absorption inf"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        btdf_sim_result *r = NULL;
        char msg[256] = "";
        assert_status(BTDF_EINVAL, try_run(&bad[k].c, &ti, 1, 1000, &r, msg, sizeof msg));
        assert_null(r);
        if (!strstr(msg, bad[k].says)) {
            print_error("message '%s' does not name '%s'\n", msg, bad[k].says);
            fail();
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(flat_pane_is_the_series),
        cmocka_unit_test(pane_energy),
        cmocka_unit_test(pane_reciprocity),
        cmocka_unit_test(pane_bad_input),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
