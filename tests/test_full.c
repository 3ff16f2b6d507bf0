/* SPDX-License-Identifier: MIT */
/* test_full.c: the model full (btdf.h, docs/model.md section 12): energy, its walk
   against smith's quadrature, bytes independent of threads, reciprocity, and T, R and
   the plane-of-incidence distribution against the explicit-surface simulation on
   cases picked by a seed.

   The tolerance. TOL = 1e-2 in units of the incident flux (T, R, R + T): the accuracy
   the issue asks of a full table at 1e-2. The tally's own noise is a binomial fraction
   over P paths, at most 0.5/sqrt(P) = 1.6e-3 at the P = 1e5 of these tests (TOL is 6
   of those); the rest of TOL is the linear interpolation between the ladder's angles
   (docs/model.md 12 measures both). A pointwise value of the multiply scattered part
   differing by d everywhere moves the energy by pi d at most, so a pointwise tolerance
   of TOL/pi (1/sr) is the same budget. */
#include <stdlib.h>
#include <string.h>

#include "btdf_sim.h"
#include "btdf_test.h"
#include "model/full.h" /* full_rho_row_deg, the pane's sampling of full */

#define DEG (M_PI / 180.0)

/* splitmix64 (the cases' picker): an index in [0, k). */
static int pick(uint64_t *x, int k)
{
    uint64_t z = (*x += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return (int)(z % (uint64_t)k);
}
#define TOL 1e-2
#define TEST_PATHS 100000u

static btdf_full *make(double n, double s, uint64_t paths, int threads)
{
    btdf_full_opts o;
    btdf_full_opts_default(&o);
    o.paths = paths;
    o.threads = threads;
    btdf_full *f = NULL;
    char msg[256] = "";
    btdf_status st = btdf_full_new(n, s, &o, &f, msg, sizeof msg);
    if (st != BTDF_OK)
        print_message("btdf_full_new: %s\n", msg);
    assert_int_equal(st, BTDF_OK);
    return f;
}

/* R + T = 1 at s = 0.5 to 100, ti = 0 to 89 by 1 degree, both sides; the walk's
   order-1 fraction against the quadrature of smith (a check of the walk itself: they
   are two independent computations of the same single scattering) within 5 binomial
   errors; no path lost. */
static void energy(void **state)
{
    (void)state;
    static const double ns[] = {1.5, 1.0 / 1.5};
    static const double ss[] = {0.5, 1, 3, 10, 100};
    for (size_t a = 0; a < 2; a++)
        for (size_t b = 0; b < sizeof ss / sizeof ss[0]; b++) {
            btdf_full *f = make(ns[a], ss[b], TEST_PATHS, 2);
            double worst = 0, at = 0;
            for (int t = 0; t <= 89; t++) {
                btdf_full_albedos al;
                assert_int_equal(btdf_full_albedo(f, t * DEG, &al), BTDF_OK);
                assert_true(isfinite(al.T) && isfinite(al.R) && al.T >= 0 && al.R >= 0);
                double d = fabs(al.T + al.R - 1.0);
                if (d > worst) {
                    worst = d;
                    at = t;
                }
            }
            btdf_full_stats st;
            btdf_full_info(f, &st);
            print_message("n %.4g s %g: max |R + T - 1| %.2e at %g deg; order-1 gap %.2e; "
                          "lost %.1e; %.2f s\n",
                          ns[a], ss[b], worst, at, st.order1_gap, st.lost, st.seconds);
            assert_true(worst <= TOL);
            assert_true(st.order1_gap <= 5 * 0.5 / sqrt((double)TEST_PATHS));
            assert_true(st.lost == 0);
            btdf_full_free(f);
        }
}

/* The same object, value for value, on 1 and on 2 threads (and the same for every
   evaluation: the tally's chunks have their own streams and are summed in order). */
static void threads(void **state)
{
    (void)state;
    btdf_full *a = make(1.5, 1, 30000, 1), *b = make(1.5, 1, 30000, 2);
    for (int t = 0; t <= 90; t += 5)
        for (int o = 90; o <= 180; o += 5)
            for (int p = 0; p <= 180; p += 45) {
                double x = btdf_full_rho_deg(a, t, o, p), y = btdf_full_rho_deg(b, t, o, p);
                double xr = btdf_full_rho_r_deg(a, t, o - 90, p);
                double yr = btdf_full_rho_r_deg(b, t, o - 90, p);
                assert_memory_equal(&x, &y, sizeof x);
                assert_memory_equal(&xr, &yr, sizeof xr);
                assert_true(isfinite(x) && x >= 0 && isfinite(xr) && xr >= 0);
            }
    btdf_full_free(a);
    btdf_full_free(b);
}

/* MODEL.md section 4: rho(n; ti, to, phi) = n^2 rho(1/n; pi - to, pi - ti, phi) for the
   transmission, rho_r(ti, tr) = rho_r(tr, ti) for the reflection. smith is reciprocal
   to 1e-8 on its own; what is left is the multiply scattered part of each side, each
   within TOL/pi of its own expectation in the mean over the hemisphere (the header's
   energy budget), so the two sides of the transmission's relation may differ by
   (1 + n^2) TOL/pi in the mean over the grid, the reflection's by 2 TOL/pi. The
   reflection meets that pointwise as well; the transmission's largest pointwise
   departure is printed (0.12 1/sr, where the lobe into the thin medium bends at the
   critical angle and a degree-7 series in |cos to| rounds it; docs/model.md 12). */
static void reciprocity(void **state)
{
    (void)state;
    const double n = 1.5, s = 1;
    btdf_full *f = make(n, s, TEST_PATHS, 2), *g = make(1 / n, s, TEST_PATHS, 2);
    double worst_t = 0, worst_r = 0, sum_t = 0, sum_r = 0;
    int count = 0;
    for (int ti = 0; ti <= 85; ti += 5)
        for (int to = 95; to <= 180; to += 5)
            for (int p = 0; p <= 180; p += 30, count++) {
                double x = btdf_full_rho_deg(f, ti, to, p);
                double y = n * n * btdf_full_rho_deg(g, 180 - to, 180 - ti, p);
                double d = fmax(0, fabs(x - y) - 1e-8 * fmax(x, y));
                worst_t = fmax(worst_t, d);
                sum_t += d;
                double xr = btdf_full_rho_r_deg(f, ti, to - 90, p);
                double yr = btdf_full_rho_r_deg(f, to - 90, ti, p);
                d = fmax(0, fabs(xr - yr) - 1e-8 * fmax(xr, yr));
                worst_r = fmax(worst_r, d);
                sum_r += d;
            }
    print_message("reciprocity: transmission mean %.2e max %.2e (bound %.2e), reflection mean "
                  "%.2e max %.2e (%.2e) 1/sr\n",
                  sum_t / count, worst_t, (1 + n * n) * TOL / M_PI, sum_r / count, worst_r,
                  2 * TOL / M_PI);
    assert_true(sum_t / count <= (1 + n * n) * TOL / M_PI);
    assert_true(worst_r <= 2 * TOL / M_PI);
    btdf_full_free(f);
    btdf_full_free(g);
}

/* The model's fraction of the incident flux into the simulator's bin (theta_bin,
   phi_bin) of side h (0 T, 1 R): Gauss-Legendre (4) in theta times the midpoint rule
   (16) in |phi|, both halves of phi. */
static double full_bin(const btdf_full *f, int h, double ti_deg, int tb, int pb, int nt, int np,
                       double n, double sm)
{
    static const double x[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                0.8611363115940526};
    static const double w[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                0.3478548451374538};
    double a = tb * 90.0 / nt, b = (tb + 1) * 90.0 / nt, sum = 0;
    double pa = pb * 180.0 / np, pw = 180.0 / np;
    for (int g = 0; g < 4; g++) {
        double th = 0.5 * (a + b) + 0.5 * (b - a) * x[g]; /* from the side's normal */
        double inner = 0;
        for (int q = 0; q < 16; q++) {
            double phi = pa + (q + 0.5) * pw / 16;
            if (!f) /* smith alone, of index n and smoothness sm */
                inner += h ? btdf_rho_r_smith_deg(n, sm, ti_deg, th, phi)
                           : btdf_rho_smith_deg(n, sm, ti_deg, 180 - th, phi);
            else
                inner += h ? btdf_full_rho_r_deg(f, ti_deg, th, phi)
                           : btdf_full_rho_deg(f, ti_deg, 180 - th, phi);
        }
        inner *= 2 * (pw / 16) * DEG;
        sum += w[g] * 0.5 * (b - a) * DEG * inner * cos(th * DEG) * sin(th * DEG);
    }
    return sum;
}

/* T, R and the plane-of-incidence distribution against btdftab simulate (the explicit
   Gaussian surface, every order). The cases come from a pool by a seed, so they are
   not the ones the model's ladder or basis were chosen on (n = 1.5, s = 1, 3). T and
   R: within TOL plus 3 standard errors of the difference (the simulation's batch
   means and the tally's binomial error). The distribution, in the forward and the
   backward plane (the |phi| bins next to 180 and 0 degrees, 10 degrees of theta by
   20 of |phi|): rho |cos t| averaged over a bin, its departure beyond 3 standard
   errors of the bin, in the mean over the plane's bins within TOL/pi (1/sr, the
   header's energy budget), for s >= 1. Below s = 1 the Smith assumption itself (heights
   uncorrelated along a path) departs from the correlated surface by more than that:
   at n = 1/1.5, s = 0.7, ti = 65 smith's single scattering alone is 0.652 1/sr in the
   bin 60-70 degrees of the forward plane where the surface's one-hit paths give 0.579
   +- 0.013 (docs/model.md 12); there the distribution is printed, not held. The
   largest single bin is printed too (pointwise it is not always within TOL/pi). */
static void simulation(void **state)
{
    (void)state;
    static const double pool_n[] = {1.5, 1.33, 1.0 / 1.5, 1.7};
    static const double pool_s[] = {0.7, 1.5, 2, 4, 6};
    static const double pool_t[] = {10, 25, 40, 50, 65, 75};
    uint64_t seed = 20261202u;
    const int nt = 9, np = 9;
    for (int c = 0; c < 5; c++) {
        double n = pool_n[pick(&seed, 4)], s = pool_s[pick(&seed, 5)];
        double ti = pool_t[pick(&seed, 6)];
        btdf_sim_opts o;
        btdf_sim_opts_default(&o);
        o.ior[0] = n;
        o.smoothness = s;
        double tir = ti * DEG;
        o.theta_i = &tir;
        o.n_theta = 1;
        o.rays = 400000;
        o.seed = 11;
        o.threads = 2;
        o.theta_bins = nt;
        o.phi_bins = np;
        btdf_sim_result *r = NULL;
        char msg[256] = "";
        assert_int_equal(btdf_sim_run(&o, &r, msg, sizeof msg), BTDF_OK);
        btdf_full *f = make(n, s, TEST_PATHS, 2);
        btdf_full_albedos al;
        assert_int_equal(btdf_full_albedo(f, tir, &al), BTDF_OK);
        const btdf_sim_tally *t = &r->tally[0];
        double eT = 3 * sqrt(t->T.se * t->T.se + al.Tms_se * al.Tms_se);
        double eR = 3 * sqrt(t->R.se * t->R.se + al.Rms_se * al.Rms_se);
        print_message("n %.4g s %g ti %g: T %.4f sim %.4f (+- %.4f), R %.4f sim %.4f (+- %.4f)"
                      "; smith T %.4f, one-hit sim %.4f\n",
                      n, s, ti, al.T, t->T.mean, t->T.se, al.R, t->R.mean, t->R.se, al.T1,
                      t->T_order[0].mean);
        /* Held where the Smith microsurface is the Gaussian surface to TOL: n > 1 at
           every s measured (0.5 to 10), n < 1 for s >= 3. From the dense side at s <= 1.5
           the surface keeps more light below than the walk (n = 1/1.5, s = 1.5: T 0.524
           +- 0.002 at ti = 0 against 0.491, docs/model.md 12): the valleys' correlated
           heights send totally reflected light back onto the surface, which the
           uncorrelated heights of Smith's walk do not; there it is printed, not held. */
        if (n > 1 || s >= 3) {
            assert_true(fabs(al.T - t->T.mean) <= TOL + eT);
            assert_true(fabs(al.R - t->R.mean) <= TOL + eR);
        } else if (fabs(al.T - t->T.mean) > TOL + eT) {
            print_message("  outside the model's domain: T departs by %.4f\n",
                          fabs(al.T - t->T.mean));
        }
        double worst = 0, sum = 0; /* the departures beyond 3 se: largest and sum */
        int bins = 0;
        for (int h = 0; h < 2; h++)
            for (int tb = 0; tb < nt; tb++)
                for (int pb = 0; pb < np; pb += np - 1) {
                    const btdf_sim_est *e = &(h ? t->hist_R : t->hist_T)[tb * np + pb];
                    double om = btdf_sim_bin_solid_angle(nt, np, tb, pb);
                    double sim = e->mean / om, se = e->se / om;
                    double mod = full_bin(f, h, ti, tb, pb, nt, np, n, s) / om;
                    double d = fmax(0, fabs(mod - sim) - 3 * se);
                    worst = fmax(worst, d);
                    sum += d;
                    bins++;
                    const btdf_sim_est *e1 = &(h ? t->hist_R1 : t->hist_T1)[tb * np + pb];
                    double s1 = full_bin(NULL, h, ti, tb, pb, nt, np, n, s) / om;
                    if (d > TOL / M_PI)
                        print_message("  %s bin theta %d phi %d: model %.4f sim %.4f +- %.4f; "
                                      "sim one-hit %.4f smith %.4f, sim 2+ %.4f model %.4f\n",
                                      h ? "R" : "T", tb, pb, mod, sim, se, e1->mean / om, s1,
                                      sim - e1->mean / om, mod - s1);
                }
        print_message("  distribution: mean departure %.4f, largest %.4f 1/sr (bound on the "
                      "mean %.4f)\n", sum / bins, worst, TOL / M_PI);
        if (s >= 1 && (n > 1 || s >= 3)) /* the domain of T and R above, and s >= 1 */
            assert_true(sum / bins <= TOL / M_PI);
        btdf_full_free(f);
        btdf_sim_result_free(r);
    }
}

/* At normal incidence the light has no azimuth, and neither has what it scatters: full
   at ti = 0 is the same number at every phi, bit for bit (the tally's cos(m phi) modes,
   m >= 1, are zero there; smith's kernel sees phi only through sin ti = 0). Before,
   those modes held the walks' noise, a few 1e-3 1/sr at 1e5 walks. Both parts, light
   entering and leaving, a rough and a smoother surface. */
static void normal_incidence(void **state)
{
    (void)state;
    static const double ns[2] = {1.5, 1.0 / 1.5}, ss[2] = {0.5, 3.0};
    static const double phis[5] = {0.0, 37.0, 90.0, 180.0, 271.5};
    btdf_full_opts o;
    btdf_full_opts_default(&o);
    o.paths = 20000;
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++) {
            btdf_full *f = NULL;
            assert_status(BTDF_OK, btdf_full_new(ns[a], ss[b], &o, &f, NULL, 0));
            for (double t = 5.0; t < 90.0; t += 12.0) {
                double t0 = btdf_full_rho_deg(f, 0.0, 180.0 - t, phis[0]);
                double r0 = btdf_full_rho_r_deg(f, 0.0, t, phis[0]);
                assert_true(t0 > 0.0 && r0 > 0.0);
                for (int k = 1; k < 5; k++) {
                    assert_true(btdf_full_rho_deg(f, 0.0, 180.0 - t, phis[k]) == t0);
                    assert_true(btdf_full_rho_r_deg(f, 0.0, t, phis[k]) == r0);
                }
            }
            btdf_full_free(f);
        }
}

/* full_rho_row_deg (the pane's sampling) against btdf_full_rho_deg and _r_deg at every
   azimuth of its row. Smith's part is the same call, bit for bit; the multiply scattered
   part sums the same 40 products of O(1) coefficients and polynomials in another order
   (the modes first), so the two differ by some ulps of those terms: 1e-13 absolute
   (a few hundred ulps of 1) plus 1e-12 relative. Grazing rows are 0 in both. */
static void row(void **state)
{
    (void)state;
    static const double ns[2] = {1.5, 1.0 / 1.5}, ss[2] = {1.0, 10.0};
    static const double tis[6] = {0.0, 12.3, 45.0, 80.5, 89.9, 90.0};
    double out[513], worst = 0.0;
    int lit = 0;
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++) {
            btdf_full *f = make(ns[a], ss[b], 20000, 0);
            for (int i = 0; i < 6; i++)
                for (double t = 0.0; t <= 90.0; t += 7.5)
                    for (int h = 0; h < 2; h++) {
                        double ti = tis[i], to = h ? t : 180.0 - t;
                        int np = (i & 1) ? 37 : 513;
                        full_rho_row_deg(f, h, ti, to, np, out);
                        for (int p = 0; p < np; p++) {
                            double phi = 180.0 * p / (np - 1);
                            double ref = h ? btdf_full_rho_r_deg(f, ti, to, phi)
                                           : btdf_full_rho_deg(f, ti, to, phi);
                            lit += ref > 0.0;
                            worst = fmax(worst, fabs(out[p] - ref));
                            assert_close(out[p], ref, 1e-12, 1e-13);
                        }
                    }
            btdf_full_free(f);
        }
    print_message("full_rho_row_deg: %d lit values, largest difference %.3g 1/sr\n", lit, worst);
    assert_true(lit > 10000); /* the rows must reach the lobes */
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(energy),
        cmocka_unit_test(threads),
        cmocka_unit_test(reciprocity),
        cmocka_unit_test(simulation),
        cmocka_unit_test(normal_incidence),
        cmocka_unit_test(row),
    };
    /* BTDF_TEST_FILTER=name runs one test (a pattern of cmocka_set_test_filter) */
    const char *flt = getenv("BTDF_TEST_FILTER");
    if (flt)
        cmocka_set_test_filter(flt);
    return cmocka_run_group_tests(tests, NULL, NULL);
}
