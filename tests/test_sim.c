/* SPDX-License-Identifier: MIT */
/* test_sim.c: the Monte Carlo goniophotometer (btdf_sim.h) against what must hold:
   Fresnel on a flat surface, energy, Eq. 25 where single scattering is exact,
   reciprocity, independence of the grid, and bytes independent of threads and of the
   traversal. Tolerances are multiples of the run's own standard errors; each says why. */
#include <string.h>

#include "btdf_sim.h"
#include "btdf_test.h"

#define DEG (M_PI / 180.0)

static btdf_sim_result *run(double n, double s, const double *ti, size_t nti, uint64_t rays,
                            void (*tweak)(btdf_sim_opts *))
{
    btdf_sim_opts o;
    btdf_sim_opts_default(&o);
    o.ior[0] = n;
    o.smoothness = s;
    o.theta_i = ti;
    o.n_theta = nti;
    o.rays = rays;
    o.seed = 7;
    o.threads = 2;
    if (tweak)
        tweak(&o);
    btdf_sim_result *r = NULL;
    char msg[256] = "";
    btdf_status st = btdf_sim_run(&o, &r, msg, sizeof msg);
    if (st != BTDF_OK)
        print_error("%s\n", msg);
    assert_status(BTDF_OK, st);
    assert_non_null(r);
    return r;
}

/* Within k combined standard errors. */
static void assert_within_se(double a, double b, double se, double k, const char *what)
{
    if (!(fabs(a - b) <= k * se)) {
        print_error("%s: %.6f vs %.6f, %.2f standard errors (allowed %g)\n", what, a, b,
                    se > 0 ? fabs(a - b) / se : INFINITY, k);
        fail();
    }
}

/* s = 1e6: slopes of RMS 2e-6, so every facet is flat to 1e-11 in Fresnel's terms and
   R must be the flat-interface Fresnel reflectance. The paths pick reflection with
   probability R, so the estimate is binomial, with a standard error of about
   sqrt(R(1-R)/rays) (3e-4 here); 4 standard errors is a false alarm once in 16,000
   for a correct tracer. Past the critical angle every path reflects: R = 1 exactly. */
static void flat_is_fresnel(void **state)
{
    (void)state;
    const struct { double n, ti; } c[] = {{1.5, 0}, {1.5, 30}, {1.5, 75}, {1 / 1.5, 0},
                                           {1 / 1.5, 35}, {1 / 1.4, 20}};
    for (size_t k = 0; k < sizeof c / sizeof c[0]; k++) {
        double ti = c[k].ti * DEG;
        btdf_sim_result *r = run(c[k].n, 1e6, &ti, 1, 200000, NULL);
        const btdf_sim_tally *t = &r->tally[0];
        double fr = btdf_fresnel_r(c[k].n, ti);
        assert_true(t->R.se > 0.0);
        assert_within_se(t->R.mean, fr, t->R.se, 4.0, "flat R");
        assert_within_se(t->T.mean, 1.0 - fr, t->T.se, 4.0, "flat T");
        /* a facet tilted by 1e-5 rad sends nothing back into the surface */
        assert_true(t->R_order[1].mean == 0.0 && t->T_order[1].mean == 0.0);
        btdf_sim_result_free(r);
    }
    double ti = 60 * DEG; /* sin 60 = 0.866 > 1/1.5: total internal reflection */
    btdf_sim_result *r = run(1 / 1.5, 1e6, &ti, 1, 20000, NULL);
    assert_true(r->tally[0].R.mean == 1.0 && r->tally[0].T.mean == 0.0);
    btdf_sim_result_free(r);
}

/* Every path ends in R or T with weight one, so R + T = 1 and the orders add up, to
   the rounding of the divisions (1e-12 is 4500 ulps of 1); no path may be lost. */
static void energy_is_conserved(void **state)
{
    (void)state;
    const double ti[] = {0, 30 * DEG, 60 * DEG, 80 * DEG};
    const double ns[] = {1.5, 1 / 1.5};
    const double ss[] = {0.5, 1, 3};
    for (size_t a = 0; a < 2; a++)
        for (size_t b = 0; b < 3; b++) {
            btdf_sim_result *r = run(ns[a], ss[b], ti, 4, 20000, NULL);
            for (size_t k = 0; k < r->count; k++) {
                const btdf_sim_tally *t = &r->tally[k];
                assert_int_equal(t->lost, 0);
                assert_close(t->R.mean + t->T.mean, 1.0, 0, 1e-12);
                double sr = 0, st = 0;
                for (int o = 0; o < BTDF_SIM_ORDERS; o++) {
                    assert_true(t->R_order[o].mean >= 0 && t->T_order[o].mean >= 0);
                    sr += t->R_order[o].mean;
                    st += t->T_order[o].mean;
                }
                assert_close(sr, t->R.mean, 0, 1e-12);
                assert_close(st, t->T.mean, 0, 1e-12);
                assert_true(t->mean_hits.mean >= 1.0);
            }
            btdf_sim_result_free(r);
        }
}

static void hist_fine(btdf_sim_opts *o)
{
    o->theta_bins = 360; /* 0.25 degree */
    o->phi_bins = 1;
}

/* Fraction of the incident flux Eq. 25 sends into polar bin [a, b] of the lower
   hemisphere (angles from the downward normal), all azimuths: Gauss-Legendre in theta
   (4 points) times the midpoint rule in phi on 4000 points over [0, pi] (0.045
   degree; the lobe at s = 30 is about 4 degrees wide in phi here). */
static double eq25_bin(double n, double s, double ti, double a, double b)
{
    static const double x[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                0.8611363115940526};
    static const double w[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                0.3478548451374538};
    double sum = 0;
    for (int g = 0; g < 4; g++) {
        double th = 0.5 * (a + b) + 0.5 * (b - a) * x[g];
        double inner = 0;
        for (int p = 0; p < 4000; p++) {
            double phi = (p + 0.5) * (M_PI / 4000);
            inner += btdf_rho(n, s, 0.7, ti, M_PI - th, phi);
        }
        inner *= 2 * (M_PI / 4000);
        sum += w[g] * 0.5 * (b - a) * inner * cos(th) * sin(th);
    }
    return sum;
}

/* chi^2 of the one-hit histogram against Eq. 25 of smoothness s_model, over the bins
   where Eq. 25 expects at least 50 paths (the normal approximation of each count). */
static double chi2_one_hit(const btdf_sim_result *r, double n, double s_model, double ti,
                           int *dof)
{
    const btdf_sim_tally *t = &r->tally[0];
    double chi = 0, w = (M_PI / 2) / r->theta_bins;
    *dof = 0;
    for (int i = 0; i < r->theta_bins; i++) {
        double m = eq25_bin(n, s_model, ti, i * w, (i + 1) * w);
        if (m * (double)t->rays < 50)
            continue;
        const btdf_sim_est *e = &t->hist_T1[i];
        /* The batch-means error: it holds the spread between surface realisations as
           well as the paths' own (binomial) noise. A bin expecting 50 paths has one
           in every batch only rarely empty, so se > 0; the guard is for safety. */
        double se = e->se > 0 ? e->se : sqrt(m * (1 - m) / (double)t->rays);
        chi += (e->mean - m) * (e->mean - m) / (se * se);
        (*dof)++;
    }
    return chi;
}

/* At s = 30 the surface has RMS slope 0.067: V = 1 to 1e-200 at 30 degrees, and a path
   that hits twice is rare (0.0 % here), so one hit is Eq. 25's single scattering, and
   the one-hit histogram must be Eq. 25's transmitted lobe. The bound dof + 5 sqrt(2 dof)
   is five standard deviations of the chi^2 distribution: a correct simulation fails it
   once in millions. That the test can fail: Eq. 25 of s = 28 (a lobe 7 % wider) is
   rejected by the same bound. */
static void large_s_is_eq25(void **state)
{
    (void)state;
    const double n = 1.5, s = 30, ti = 30 * DEG;
    btdf_sim_result *r = run(n, s, &ti, 1, 400000, hist_fine);
    int dof = 0, dof2 = 0;
    double chi = chi2_one_hit(r, n, s, ti, &dof);
    double chi_wrong = chi2_one_hit(r, n, 28, ti, &dof2);
    print_message("s = 30: chi2 %.1f on %d bins; against s = 28: %.1f on %d\n", chi, dof,
                  chi_wrong, dof2);
    assert_true(dof >= 10);
    assert_true(chi < dof + 5 * sqrt(2.0 * dof));
    assert_true(chi_wrong > dof2 + 5 * sqrt(2.0 * dof2));
    btdf_sim_result_free(r);
}

/* The per-bin errors of the batch means, from the variance decomposition. Batch b holds
   n rays on realisation b; its bin fraction is p_b + e_b, with p_b the surface's own
   fraction (spread sigma_s^2 between surfaces) and e_b the paths' binomial noise
   (variance V = p (1 - p) / n). The sample variance of the B batch means, S^2 = B se^2,
   therefore estimates V + sigma_s^2: the binomial error sqrt(V / B) is a lower bound,
   and how far above it depends on n. Two runs on the same 32 surfaces (the surface
   stream depends on the seed and the batch only) with independent rays (the second
   run's second angle, equal to the first, draws stream RAYS + 1): A, the one checked,
   with n_A = 12,500 rays per batch (that of large_s_is_eq25), B with n_B = 50,000.
   B gives sigma_s^2 = S_B^2 - V_B, so A must have S_A^2 = V_A + sigma_s^2, i.e.
   (se_A / sqrt(V_A / B))^2 = 1 + sigma_s^2 / V_A (this replaces a fixed band for that
   ratio). The difference S_A^2 - S_B^2 - (V_A - V_B) holds no surface term (same
   surfaces) and has variance (2 V_A^2 + 2 V_B^2 + 4 sigma_s^2 (V_A + V_B)) / (B - 1)
   (sample variances of B normal values, and the surface-noise cross terms). Per bin,
   5 of its standard deviations either side (a chi^2 of 31 degrees of freedom passes 5
   deviations above its mean once in 20,000); a band this wide is what 32 batches
   allow (S^2 alone has a 25 % error), so the bins' standardised differences are also
   pooled (the bins' counts are nearly independent: p < 0.1 each): their sum over
   sqrt(bins) within 5. Bins with at least 1000 paths (the normal approximation). */
static void errors_follow_the_decomposition(void **state)
{
    (void)state;
    const double n = 1.5, s = 30, t30 = 30 * DEG, ti2[2] = {t30, t30};
    btdf_sim_result *a = run(n, s, &t30, 1, 400000, hist_fine);
    btdf_sim_result *b = run(n, s, ti2, 2, 1600000, hist_fine);
    assert_int_equal(32, a->tally[0].batches);
    assert_int_equal(32, b->tally[1].batches);
    const double B = 32, nA = 12500, nB = 50000;
    int checked = 0;
    double zsum = 0;
    for (int i = 0; i < a->theta_bins; i++) {
        const btdf_sim_est *ea = &a->tally[0].hist_T1[i], *eb = &b->tally[1].hist_T1[i];
        double p = ea->mean;
        if (p * (double)a->tally[0].rays < 1000)
            continue;
        double vA = p * (1 - p) / nA, vB = p * (1 - p) / nB;
        double sA = B * ea->se * ea->se, sB = B * eb->se * eb->se;
        double sig = sB - vB > 0 ? sB - vB : 0; /* an estimate; clipped where noise leaves it < 0 */
        double sd = sqrt((2 * vA * vA + 2 * vB * vB + 4 * sig * (vA + vB)) / (B - 1));
        double ratio2 = sA / vA, want = 1 + sig / vA, sd1 = sd / vA;
        print_message("bin %d: (se / binomial)^2 %.3f, decomposition %.3f +- %.3f\n", i, ratio2,
                      want, sd1);
        assert_true(fabs(ratio2 - want) <= 5 * sd1);
        zsum += (ratio2 - want) / sd1;
        checked++;
    }
    print_message("%d bins, pooled z %.2f\n", checked, zsum / sqrt(checked));
    assert_true(checked >= 8);
    assert_true(fabs(zsum / sqrt(checked)) < 5);
    btdf_sim_result_free(a);
    btdf_sim_result_free(b);
}

static void hist_coarse(btdf_sim_opts *o)
{
    o->theta_bins = 45;
    o->phi_bins = 18;
}

static void hist_cmp(btdf_sim_opts *o)
{
    o->theta_bins = 360; /* 0.25 degree: the s = 30 lobe spreads over some 20 bins */
    o->phi_bins = 18;    /* 10 degrees */
}

/* btdf_sim_compare: at s = 30 (RMS slope 0.067, V = 1 and Smith's G = 1 to rounding at
   30 degrees, 0.0 % of two hits) the one-hit lobe is Eq. 25's and Smith's: chi^2 below
   its mean plus 5 standard deviations (the mean is dof (B - 1) / (B - 3) = 1.069 dof,
   the errors being estimated from B = 32 batches), e_T within 5 standard errors, and
   e_L1 within 5 of its spreads e_L1_floor_sd above its floor (the value with no model
   error, in the normal approximation; bins with few paths make the true value lower).
   Both binnings: 0.25 x 10 degrees (the lobe over some 30 bins) and the default 2 x 10
   (the lobe in four, so e_L1 is as noisy as four terms). At s = 1, Eq. 25's shadowing
   takes 40 % of T (docs/simulation.md): e_T must exceed 100 floors, e_L1 its floor
   plus 20 spreads, and the one-hit chi^2 10 times its dof. */
static void compare_with_models(void **state)
{
    (void)state;
    const double n = 1.5, ti = 30 * DEG;
    char msg[256];
    btdf_sim_cmp c;
    btdf_sim_result *r = run(n, 30, &ti, 1, 400000, hist_cmp);
    const btdf_model models[2] = {BTDF_MODEL_XU_SUN, BTDF_MODEL_SMITH};
    for (int m = 0; m < 2; m++) {
        assert_status(BTDF_OK, btdf_sim_compare(r, 0, BTDF_SIM_TRANSMISSION, 1, models[m], 0.7, &c,
                                                msg, sizeof msg));
        double mean = c.dof * 31.0 / 29.0, sd = sqrt(2.0 * c.dof) * 31.0 / 29.0;
        print_message("s = 30, %s: chi2 %.1f on %d, e_T %.2g (floor %.2g), e_L1 %.3g (floor "
                      "%.3g +- %.3g), model in bins %.6f of %.6f\n",
                      m ? "smith" : "eq25", c.chi2, c.dof, c.e_T, c.e_T_floor, c.e_L1,
                      c.e_L1_floor, c.e_L1_floor_sd, c.model_in_bins, c.model_total);
        assert_true(c.dof >= 30);
        assert_true(c.chi2 < mean + 5 * sd);
        assert_true(c.e_T < 5 * c.e_T_floor / 0.7978845608);
        assert_true(c.e_L1 < c.e_L1_floor + 5 * c.e_L1_floor_sd);
        /* the quadrature of the bins: their sum is the model's T to 1e-6 */
        assert_close(c.model_in_bins, c.model_total, 0, 1e-6);
    }
    btdf_sim_result_free(r);
    r = run(n, 30, &ti, 1, 400000, hist_coarse);
    assert_status(BTDF_OK, btdf_sim_compare(r, 0, BTDF_SIM_TRANSMISSION, 1, BTDF_MODEL_XU_SUN,
                                            0.7, &c, msg, sizeof msg));
    print_message("s = 30, 2 degree bins: e_L1 %.3g (floor %.3g +- %.3g)\n", c.e_L1,
                  c.e_L1_floor, c.e_L1_floor_sd);
    assert_true(c.e_L1 < c.e_L1_floor + 5 * c.e_L1_floor_sd);
    btdf_sim_result_free(r);
    r = run(n, 1, &ti, 1, 400000, hist_coarse);
    assert_status(BTDF_OK, btdf_sim_compare(r, 0, BTDF_SIM_TRANSMISSION, 0, BTDF_MODEL_XU_SUN,
                                            0.7, &c, msg, sizeof msg));
    print_message("s = 1, all orders: e_T %.3g (floor %.2g), e_L1 %.3g (floor %.3g +- %.3g)\n",
                  c.e_T, c.e_T_floor, c.e_L1, c.e_L1_floor, c.e_L1_floor_sd);
    assert_true(c.e_T > 100 * c.e_T_floor);
    assert_true(c.e_L1 > c.e_L1_floor + 20 * c.e_L1_floor_sd);
    assert_status(BTDF_OK, btdf_sim_compare(r, 0, BTDF_SIM_TRANSMISSION, 1, BTDF_MODEL_XU_SUN,
                                            0.7, &c, msg, sizeof msg));
    print_message("s = 1, one hit: chi2 %.1f on %d\n", c.chi2, c.dof);
    assert_true(c.chi2 > 10.0 * c.dof);
    /* bad arguments are named */
    assert_status(BTDF_EINVAL, btdf_sim_compare(r, 5, BTDF_SIM_TRANSMISSION, 1,
                                                BTDF_MODEL_XU_SUN, 0.7, &c, msg, sizeof msg));
    assert_non_null(strstr(msg, "case 5"));
    btdf_sim_result_free(r);
}

/* The reflection comparisons (MODEL.md section 8: Eq. 25's companion reflection, and
   Smith's for one hit). At s = 30 and ti = 30 the one-hit reflected lobe is a
   Beckmann lobe of RMS slope 0.067 with V = G = 1 to rounding, so both models must
   hold within the noise, by the criteria of compare_with_models: chi^2 below its
   mean 1.069 dof plus 5 standard deviations, e_T within 5 standard errors, e_L1
   within 5 spreads of its floor; the bins' sum is the model's R to 1e-6. The
   reflected lobe is twice as wide in theta_o as its slopes (the mirror doubles an
   angle), so the 0.25 degree bins hold it in some 60 bins. At s = 1 (RMS slope 2)
   Eq. 25's shadowing V(ti) V(to) removes most of the reflection: it gives R = 0.0030
   where the surface reflects 0.0088 +- 0.0002 (all orders, seed 7), so e_T of all
   orders must exceed 20 floors (the floor is the Monte Carlo error alone: 20 of them
   is no fluctuation). */
static void compare_reflection(void **state)
{
    (void)state;
    const double n = 1.5, ti = 30 * DEG;
    char msg[256];
    btdf_sim_cmp c;
    btdf_sim_result *r = run(n, 30, &ti, 1, 400000, hist_cmp);
    const btdf_model models[2] = {BTDF_MODEL_XU_SUN, BTDF_MODEL_SMITH};
    for (int m = 0; m < 2; m++) {
        assert_status(BTDF_OK, btdf_sim_compare(r, 0, BTDF_SIM_REFLECTION, 1, models[m], 0.7, &c,
                                                msg, sizeof msg));
        double mean = c.dof * 31.0 / 29.0, sd = sqrt(2.0 * c.dof) * 31.0 / 29.0;
        print_message("R, s = 30, %s: R1 %.5f +- %.5f, model %.5f; chi2 %.1f on %d, e_T %.2g "
                      "(floor %.2g), e_L1 %.3g (floor %.3g +- %.3g)\n",
                      m ? "smith" : "eq25", c.total, c.total_se, c.model_total, c.chi2, c.dof,
                      c.e_T, c.e_T_floor, c.e_L1, c.e_L1_floor, c.e_L1_floor_sd);
        assert_true(c.dof >= 30);
        assert_true(c.chi2 < mean + 5 * sd);
        assert_true(c.e_T < 5 * c.e_T_floor / 0.7978845608);
        assert_true(c.e_L1 < c.e_L1_floor + 5 * c.e_L1_floor_sd);
        assert_close(c.model_in_bins, c.model_total, 0, 1e-6);
    }
    btdf_sim_result_free(r);
    r = run(n, 1, &ti, 1, 400000, hist_coarse);
    assert_status(BTDF_OK, btdf_sim_compare(r, 0, BTDF_SIM_REFLECTION, 0, BTDF_MODEL_XU_SUN,
                                            0.7, &c, msg, sizeof msg));
    print_message("R, s = 1, all orders: R %.5f +- %.5f, Eq. 25 %.5f; e_T %.3g (floor %.2g), "
                  "e_L1 %.3g (floor %.3g +- %.3g)\n", c.total, c.total_se, c.model_total, c.e_T,
                  c.e_T_floor, c.e_L1, c.e_L1_floor, c.e_L1_floor_sd);
    assert_true(c.e_T > 20 * c.e_T_floor);
    btdf_sim_result_free(r);
}

static void hist_recip(btdf_sim_opts *o)
{
    o->theta_bins = 45; /* 2 degrees */
    o->phi_bins = 18;   /* 10 degrees of |phi| */
}

/* rho(n; A -> B) = n^2 rho(1/n; B -> A) (MODEL.md section 4), with every order of
   scattering: it holds for the whole surface, not only for Eq. 25. Bins of 2 x 10
   degrees around the forward plane; the angles are the bins' centres, so both sides
   average the same function over the same |phi| bin, and the theta averaging differs
   by O(bin^2 / 24) = 5e-5 relative, far below the noise (about 3 % per bin). Four
   combined standard errors, as for Fresnel. */
static void reciprocity(void **state)
{
    (void)state;
    const double n = 1.5, s = 1;
    const double ti[2] = {21 * DEG, 41 * DEG}; /* centres of bins 10 and 20 */
    const int bin[2] = {10, 20}, fwd = 17;     /* |phi| in [170, 180] */
    btdf_sim_result *up = run(n, s, ti, 2, 600000, hist_recip);
    btdf_sim_result *dn = run(1 / n, s, ti, 2, 600000, hist_recip);
    for (int a = 0; a < 2; a++) {
        int b = 1 - a;
        /* rho |cos to| = P / solid angle; rho needs the bin's cosine too */
        size_t ia = (size_t)bin[b] * 18 + fwd, ib = (size_t)bin[a] * 18 + fwd;
        double om_b = btdf_sim_bin_solid_angle(45, 18, bin[b], fwd);
        double om_a = btdf_sim_bin_solid_angle(45, 18, bin[a], fwd);
        double c_b = cos(ti[b]), c_a = cos(ti[a]);
        double r1 = up->tally[a].hist_T[ia].mean / om_b / c_b;
        double e1 = up->tally[a].hist_T[ia].se / om_b / c_b;
        double r2 = n * n * dn->tally[b].hist_T[ib].mean / om_a / c_a;
        double e2 = n * n * dn->tally[b].hist_T[ib].se / om_a / c_a;
        print_message("reciprocity %d: %.4f +- %.4f vs %.4f +- %.4f\n", a, r1, e1, r2, e2);
        assert_true(e1 > 0 && e2 > 0 && e1 < 0.1 * r1);
        assert_within_se(r1, r2, sqrt(e1 * e1 + e2 * e2), 4.0, "reciprocity");
    }
    btdf_sim_result_free(up);
    btdf_sim_result_free(dn);
}

static void fine_grid(btdf_sim_opts *o)
{
    o->cells_per_tau = 32;
}

static void big_tile(btdf_sim_opts *o)
{
    o->tile_tau = 32;
}

/* Halving the spacing or doubling the tile moves R and T by less than 2 standard
   errors of the difference (the runs use different surfaces, so they are independent):
   the grid's own error, the 0.1 % lower RMS slope of the triangles at 16 cells per tau
   (the default; 1 - dx^2 / (4 tau^2)), is below the noise of 2e5 rays. s = 1 has 10 % of multiple scattering, the order
   most sensitive to the surface's shape. */
static void grid_independence(void **state)
{
    (void)state;
    double ti = 30 * DEG;
    btdf_sim_result *a = run(1.5, 1, &ti, 1, 200000, NULL);
    btdf_sim_result *b = run(1.5, 1, &ti, 1, 200000, fine_grid);
    btdf_sim_result *c = run(1.5, 1, &ti, 1, 200000, big_tile);
    const btdf_sim_tally *ta = &a->tally[0], *tb = &b->tally[0], *tc = &c->tally[0];
    print_message("grid: T %.5f +- %.5f, fine %.5f +- %.5f, big tile %.5f +- %.5f\n",
                  ta->T.mean, ta->T.se, tb->T.mean, tb->T.se, tc->T.mean, tc->T.se);
    assert_within_se(ta->T.mean, tb->T.mean, hypot(ta->T.se, tb->T.se), 2.0, "T, spacing");
    assert_within_se(ta->R.mean, tb->R.mean, hypot(ta->R.se, tb->R.se), 2.0, "R, spacing");
    assert_within_se(ta->T.mean, tc->T.mean, hypot(ta->T.se, tc->T.se), 2.0, "T, tile");
    assert_within_se(ta->R.mean, tc->R.mean, hypot(ta->R.se, tc->R.se), 2.0, "R, tile");
    assert_within_se(ta->T_order[1].mean, tb->T_order[1].mean,
                     hypot(ta->T_order[1].se, tb->T_order[1].se), 2.0, "T order 2, spacing");
    btdf_sim_result_free(a);
    btdf_sim_result_free(b);
    btdf_sim_result_free(c);
}

/* The realised surfaces: sigma, RMS slope 2/s and correlation length s within 3 %.
   Over 32 realisations of a 16 tau tile, the RMS height about the tile's mean is
   expected 0.6 % low (the mean takes pi tau^2 / L^2 of the variance) with a spread of
   about 1 %; 3 % is three times both. */
static void surface_statistics(void **state)
{
    (void)state;
    double ti = 0;
    btdf_sim_result *r = run(1.5, 2, &ti, 1, 20000, NULL);
    const btdf_sim_surface *sf = &r->surface;
    print_message("surface: h %.4f slope %.4f tau %.4f over %d\n", sf->rms_height,
                  sf->rms_slope, sf->corr_length, sf->realisations);
    assert_int_equal(sf->n, 256);
    assert_true(sf->realisations >= 32);
    assert_close(sf->rms_height, 1.0, 0.03, 0);
    assert_close(sf->rms_slope, 1.0, 0.03, 0);
    assert_close(sf->corr_length, 2.0, 0.03, 0);
    btdf_sim_result_free(r);
}

static void one_thread(btdf_sim_opts *o)
{
    o->threads = 1;
    o->accel = 1; /* the hierarchy; the default is the plain DDA */
    o->theta_bins = 18;
    o->phi_bins = 4;
}
static void three_threads_plain(btdf_sim_opts *o)
{
    o->threads = 3;
    o->accel = 0; /* the default, named */
    o->theta_bins = 18;
    o->phi_bins = 4;
}

/* Same bytes with one thread and hierarchy as with three and the plain DDA: the batch
   order fixes the sums, and both walks find the same first hit exactly. */
static void deterministic(void **state)
{
    (void)state;
    const double ti[2] = {10 * DEG, 70 * DEG};
    btdf_sim_result *a = run(1.5, 0.7, ti, 2, 30000, one_thread);
    btdf_sim_result *b = run(1.5, 0.7, ti, 2, 30000, three_threads_plain);
    for (size_t k = 0; k < 2; k++) {
        const btdf_sim_tally *x = &a->tally[k], *y = &b->tally[k];
        assert_memory_equal(&x->R, &y->R, sizeof x->R);
        assert_memory_equal(&x->T_order, &y->T_order, sizeof x->T_order);
        assert_memory_equal(&x->mean_hits, &y->mean_hits, sizeof x->mean_hits);
        assert_memory_equal(x->hist_T, y->hist_T, 72 * sizeof *x->hist_T);
        assert_memory_equal(x->hist_R1, y->hist_R1, 72 * sizeof *x->hist_R1);
    }
    assert_memory_equal(&a->surface, &b->surface, sizeof a->surface);
    btdf_sim_result_free(a);
    btdf_sim_result_free(b);
}

static btdf_status check(void (*set)(btdf_sim_opts *), char *msg, size_t len)
{
    static const double ti = 0.5;
    btdf_sim_opts o;
    btdf_sim_opts_default(&o);
    o.theta_i = &ti;
    o.n_theta = 1;
    set(&o);
    return btdf_sim_opts_check(&o, msg, len);
}
static void bad_s(btdf_sim_opts *o) { o->smoothness = 0; }
static void bad_n(btdf_sim_opts *o) { o->ior[0] = 1; }
static void bad_nan(btdf_sim_opts *o) { o->ior[0] = NAN; }
static void bad_rays(btdf_sim_opts *o) { o->rays = BTDF_SIM_RAYS_MAX + 1; }
static void bad_grid(btdf_sim_opts *o) { o->tile_tau = 12; }
static void bad_mem(btdf_sim_opts *o) { o->max_memory = 1000; }

static void bad_input(void **state)
{
    (void)state;
    char msg[256];
    assert_status(BTDF_EINVAL, check(bad_s, msg, sizeof msg));
    assert_non_null(strstr(msg, "smoothness 0"));
    assert_status(BTDF_EINVAL, check(bad_n, msg, sizeof msg));
    assert_non_null(strstr(msg, "n = 1"));
    assert_status(BTDF_EINVAL, check(bad_nan, msg, sizeof msg));
    assert_non_null(strstr(msg, "nan"));
    assert_status(BTDF_EINVAL, check(bad_rays, msg, sizeof msg));
    assert_non_null(strstr(msg, "rays 100000000001"));
    assert_status(BTDF_EINVAL, check(bad_grid, msg, sizeof msg));
    assert_non_null(strstr(msg, "192 points"));
    assert_status(BTDF_EBUDGET, check(bad_mem, msg, sizeof msg));
    assert_non_null(strstr(msg, "memory limit"));
}

static uint64_t est_seed;
static void seed_of(btdf_sim_opts *o) { o->seed = est_seed; }

/* The batch-means error is the realisation's: all rays of a batch see one surface, so
   the spread between batch means holds the spread between surfaces. Checked against
   the spread of T over 24 independent runs (seeds) at s = 1, where the surfaces
   differ most: the sample standard deviation of 24 means has a relative error of
   1/sqrt(46) = 15 %, and the mean of 24 reported errors about 13 %/sqrt(24) = 3 %, so
   their ratio lies in [0.55, 1.45] (3 of those either side of 1). An error taken over
   sub-batches of one surface, which leaves the surface spread out, fails the lower
   bound when that spread matters. */
static void error_is_honest(void **state)
{
    (void)state;
    const int runs = 24;
    double ti = 30 * DEG, m = 0, m2 = 0, se = 0;
    for (int k = 0; k < runs; k++) {
        est_seed = 1000 + (uint64_t)k;
        btdf_sim_result *r = run(1.5, 1, &ti, 1, 64000, seed_of);
        double t = r->tally[0].T.mean;
        m += t;
        m2 += t * t;
        se += r->tally[0].T.se;
        btdf_sim_result_free(r);
    }
    m /= runs;
    double sd = sqrt((m2 / runs - m * m) * runs / (runs - 1.0));
    se /= runs;
    print_message("s = 1: spread of T over %d runs %.3g, mean reported error %.3g\n", runs, sd,
                  se);
    assert_true(sd > 0.55 * se && sd < 1.45 * se);
}

static uint64_t shard_first, shard_end;
static void shard_of(btdf_sim_opts *o)
{
    o->theta_bins = 9;
    o->phi_bins = 3;
    o->batch_first = shard_first;
    o->batch_end = shard_end;
}

static int same_est(const btdf_sim_est *a, const btdf_sim_est *b, size_t n)
{
    return memcmp(a, b, n * sizeof *a) == 0;
}

/* Shards by batch range merged are one run, to the bit: the counts of every batch are
   integers put back in batch order, the histograms' sums are integers. Two angles, a
   split inside the first 32 realisations (whose statistics are averaged) and three
   parts given out of order. */
static void shards_merge_to_one_run(void **state)
{
    (void)state;
    double ti[2] = {10 * DEG, 50 * DEG};
    shard_first = shard_end = 0;
    btdf_sim_result *whole = run(1.5, 2, ti, 2, 40000, shard_of);
    uint64_t nb = whole->batches_total;
    assert_int_equal(32, nb);
    const uint64_t cut[4] = {0, 5, 20, nb};
    btdf_sim_result *part[3];
    for (int k = 0; k < 3; k++) {
        shard_first = cut[k];
        shard_end = cut[k + 1];
        part[k] = run(1.5, 2, ti, 2, 40000, shard_of);
        assert_int_equal(cut[k + 1] - cut[k], part[k]->tally[0].batches);
    }
    btdf_sim_opts o;
    btdf_sim_opts_default(&o);
    o.smoothness = 2;
    o.theta_i = ti;
    o.n_theta = 2;
    o.rays = 40000;
    o.seed = 7;
    shard_first = shard_end = 0;
    shard_of(&o);
    const btdf_sim_result *order[3] = {part[2], part[0], part[1]};
    btdf_sim_result *m = NULL;
    char msg[256];
    assert_status(BTDF_OK, btdf_sim_merge(&o, order, 3, &m, msg, sizeof msg));
    for (size_t k = 0; k < whole->count; k++) {
        const btdf_sim_tally *a = &whole->tally[k], *b = &m->tally[k];
        assert_true(same_est(&a->R, &b->R, 1) && same_est(&a->T, &b->T, 1));
        assert_true(same_est(a->T_order, b->T_order, 3) && same_est(a->R_order, b->R_order, 3));
        assert_true(same_est(&a->mean_hits, &b->mean_hits, 1));
        assert_true(same_est(a->hist_T, b->hist_T, 27) && same_est(a->hist_R1, b->hist_R1, 27));
        assert_int_equal(a->batches, b->batches);
    }
    assert_memory_equal(&whole->surface, &m->surface, sizeof whole->surface);
    /* a batch held twice, or missing, is named */
    const btdf_sim_result *twice[3] = {part[0], part[0], part[1]};
    assert_status(BTDF_EINVAL, btdf_sim_merge(&o, twice, 3, &m, msg, sizeof msg));
    assert_non_null(strstr(msg, "batch 0 is in two parts"));
    const btdf_sim_result *gap[2] = {part[0], part[2]};
    assert_status(BTDF_EINVAL, btdf_sim_merge(&o, gap, 2, &m, msg, sizeof msg));
    assert_non_null(strstr(msg, "batch 5 of 32 is in no part"));
    btdf_sim_result_free(m);
    for (int k = 0; k < 3; k++)
        btdf_sim_result_free(part[k]);
    btdf_sim_result_free(whole);
}

static void profile_1d(btdf_sim_opts *o)
{
    o->profile = 1;
    o->theta_bins = 45;
    o->phi_bins = 18;
}

/* --profile 1d: a profile z = h(x) and rays in its plane. Every outgoing direction
   lies in the plane, so only the |phi| bins [0, 10) and [170, 180] degrees receive
   paths, exactly (the normals have no y part and the ray none to begin with); energy
   holds as on the surface; the profile's mean square slope along x is 2/s^2 within 4
   standard errors of its mean over the 32 measured realisations (the error from
   their own spread: a profile 16 tau long holds some 20 independent slopes, so one
   realisation's mean square spreads by about 30 %, the mean of 32 by 5 %; the grid's
   bias, 0.1 %, is far below); comparisons with the 2D models are refused.
   The profile is a strip, one row of cells: its tile takes at most 30 bytes a point
   (a height, two bounds and a third of that for the levels' room) where a square
   tile took n times that, so a profile 256 tau long (4096 points) fits in 16 MB, and the hierarchy (level 0 only on a
   strip) gives the same bits as the plain walk. */
static void profile_long(btdf_sim_opts *o)
{
    profile_1d(o);
    o->tile_tau = 256;
    o->max_memory = (size_t)16 << 20;
}

static void profile_long_accel(btdf_sim_opts *o)
{
    profile_long(o);
    o->accel = 1;
}

/* Mean square slope of the measured realisations of r, and its standard error. */
static void slope2(const btdf_sim_result *r, double *mean, double *se)
{
    int B = r->surface.realisations;
    double m = 0.0, m2 = 0.0;
    for (int b = 0; b < B; b++) {
        double v = r->raw_stats[b * 3 + 1] * r->raw_stats[b * 3 + 1];
        m += v;
        m2 += v * v;
    }
    assert_true(B >= 32);
    m /= B;
    double var = (m2 / B - m * m) * B / (B - 1.0);
    *mean = m;
    *se = sqrt(var > 0.0 ? var : 0.0) / sqrt((double)B);
}

static void profile_in_plane(void **state)
{
    (void)state;
    const double ti[2] = {30 * DEG, 60 * DEG};
    btdf_sim_result *r = run(1.4, 1, ti, 2, 40000, profile_1d);
    for (size_t k = 0; k < r->count; k++) {
        const btdf_sim_tally *t = &r->tally[k];
        assert_int_equal(t->lost, 0);
        assert_close(t->R.mean + t->T.mean, 1.0, 0, 1e-12);
        double off = 0, in = 0;
        for (int it = 0; it < 45; it++)
            for (int ip = 0; ip < 18; ip++) {
                size_t i = (size_t)it * 18 + (size_t)ip;
                double m = t->hist_T[i].mean + t->hist_R[i].mean;
                if (ip == 0 || ip == 17)
                    in += m;
                else
                    off += m;
            }
        assert_true(off == 0.0);
        assert_close(in, 1.0, 0, 1e-12);
    }
    double m, se;
    slope2(r, &m, &se);
    print_message("profile: slope^2 %.4f +- %.4f (target 2), tau %.4f\n", m, se,
                  r->surface.corr_length);
    assert_within_se(m, 2.0, se, 4.0, "profile slope^2");
    char msg[128];
    btdf_sim_cmp c;
    assert_status(BTDF_EINVAL, btdf_sim_compare(r, 0, BTDF_SIM_TRANSMISSION, 1,
                                                BTDF_MODEL_XU_SUN, 0.7, &c, msg, sizeof msg));
    assert_non_null(strstr(msg, "1D profile"));
    assert_true(r->surface.tile_bytes <= 30 * (size_t)r->surface.n + 256);
    btdf_sim_result_free(r);
    r = run(1.4, 1, ti, 2, 20000, profile_long);
    btdf_sim_result *h = run(1.4, 1, ti, 2, 20000, profile_long_accel);
    assert_int_equal(4096, r->surface.n);
    assert_memory_equal(r->raw_counts, h->raw_counts,
                        r->count * r->batches_total * BTDF_SIM_RAW_Q * sizeof *r->raw_counts);
    slope2(r, &m, &se);
    print_message("profile of 256 tau: slope^2 %.4f +- %.4f, tau %.4f, rms height %.4f\n", m,
                  se, r->surface.corr_length, r->surface.rms_height);
    assert_within_se(m, 2.0, se, 4.0, "long profile slope^2");
    btdf_sim_result_free(h);
    btdf_sim_result_free(r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(bad_input),
        cmocka_unit_test(flat_is_fresnel),
        cmocka_unit_test(energy_is_conserved),
        cmocka_unit_test(surface_statistics),
        cmocka_unit_test(deterministic),
        cmocka_unit_test(large_s_is_eq25),
        cmocka_unit_test(errors_follow_the_decomposition),
        cmocka_unit_test(compare_with_models),
        cmocka_unit_test(compare_reflection),
        cmocka_unit_test(reciprocity),
        cmocka_unit_test(grid_independence),
        cmocka_unit_test(error_is_honest),
        cmocka_unit_test(shards_merge_to_one_run),
        cmocka_unit_test(profile_in_plane),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
