/* SPDX-License-Identifier: MIT */
/* test_pane.c: the system BSDF of a pane (src/pane/): a flat pane against the closed form
   of a slab, energy with the model full, reciprocity, convergence, bad input. */
#include "btdf_test.h"

#include <string.h>

#include "btdf_pane.h"

/* A flat slab of index n with absorption a d, light at ti: the Fresnel series
   R = Fr + Ft^2 Fr t^2 / (1 - Fr^2 t^2), T = Ft^2 t / (1 - Fr^2 t^2), t = exp(-a d / mu_in),
   the same Fr on both faces (Fresnel is symmetric at matched angles). */
static void slab(double n, double ti, double ad, double *T, double *R)
{
    double fr = btdf_fresnel_r(n, ti), ft = 1.0 - fr, su = sin(ti) / n;
    double t = exp(-ad / sqrt(1.0 - su * su)), den = 1.0 - fr * fr * t * t;
    *T = ft * ft * t / den;
    *R = fr + ft * ft * fr * t * t / den;
}

static btdf_pane *make(const btdf_pane_opts *o)
{
    btdf_pane *p = NULL;
    char msg[256] = "";
    btdf_status st = btdf_pane_new(o, &p, msg, sizeof msg);
    if (st != BTDF_OK)
        print_error("%s\n", msg);
    assert_status(BTDF_OK, st);
    return p;
}

/* Both faces flat: every part a delta whose weight is the closed form. The weights are
   exact at the Gauss nodes (diagonal operators) and interpolated between them by a cubic
   in cos theta; with 64 nodes that is below 1e-5 up to 88 deg (measured 1.4e-4 with 24 at
   86 deg), so 1e-4 holds with a margin. The old code had no pane: this fails there. */
static void flat_slab(void **state)
{
    (void)state;
    btdf_pane_opts o;
    btdf_pane_opts_default(&o);
    o.front_smooth = 1;
    o.thickness_mm = 4.0;
    o.absorption_per_mm = 0.1;
    btdf_pane *p = make(&o);
    for (int side = 1; side <= 2; side++)
        for (double d = 0.0; d <= 88.0; d += 0.7) {
            double T, R, Tc, Rc;
            slab(1.5, rad(d), 0.4, &Tc, &Rc);
            btdf_pane_albedo(p, (btdf_pane_side)side, 0, rad(d), &T, &R);
            assert_close(T, Tc, 0.0, 1e-4);
            assert_close(R, Rc, 0.0, 1e-4);
            assert_close(btdf_pane_specular(p, side, BTDF_PART_TRANSMISSION, 0, rad(d)), Tc,
                         0.0, 1e-4);
            /* nothing spreads */
            assert_true(btdf_pane_eval(p, side, BTDF_PART_TRANSMISSION, 0, rad(d),
                                       rad(180.0 - d), M_PI) == 0.0);
        }
    btdf_pane_free(p);
}

/* A rough front at s = 100 (lobes 1 deg wide) and a flat back tends to the flat slab:
   the rough face's T differs from the flat Fresnel Ft by below 1e-3 at s = 100 for
   ti <= 60 (MODEL.md 4) and the system follows; the lobes are sampled coarsely (64 nodes,
   32 modes, to keep the test short) but every node's column is scaled to the face's
   own T and R, so the albedos stay right: 2e-3. */
static void rough_tends_to_flat(void **state)
{
    (void)state;
    btdf_pane_opts o;
    btdf_pane_opts_default(&o);
    o.front.smoothness = 100.0;
    o.nodes = 64;
    o.modes = 32;
    o.thickness_mm = 4.0;
    o.absorption_per_mm = 0.1;
    btdf_pane *p = make(&o);
    for (double d = 0.0; d <= 60.0; d += 7.5) {
        double T, R, Tc, Rc;
        slab(1.5, rad(d), 0.4, &Tc, &Rc);
        btdf_pane_albedo(p, BTDF_PANE_FRONT, 0, rad(d), &T, &R);
        assert_close(T, Tc, 0.0, 2e-3);
        assert_close(R, Rc, 0.0, 2e-3);
    }
    btdf_pane_free(p);
}

/* Model full, no absorption: R + T = 1 from either side. The faces' operators are scaled
   to the model's own T and R at every node, so what is left is the tally's binomial
   error (about 1e-3 at 200000 paths for T_ms of order 0.1, btdf_full_albedo) and the
   cubic interpolation between nodes: measured 1.1e-3 at worst, up to 88 deg; 3e-3. */
static void energy_full(void **state)
{
    (void)state;
    btdf_pane_opts o;
    btdf_pane_opts_default(&o);
    o.front.model = BTDF_MODEL_FULL;
    o.nodes = 36;
    o.modes = 48;
    o.thickness_mm = 4.0;
    btdf_pane *p = make(&o);
    for (int side = 1; side <= 2; side++)
        for (double d = 0.0; d <= 88.0; d += 4.0) {
            double T, R;
            btdf_pane_albedo(p, (btdf_pane_side)side, 0, rad(d), &T, &R);
            assert_close(R + T, 1.0, 0.0, 3e-3);
        }
    btdf_pane_free(p);
}

/* Xu-sun loses what V(ti) V(to) shadows (MODEL.md 8), and a pane shadows on every pass:
   from the rough front at 80 deg R + T is 0.15 (measured), not 1. The check is that it
   loses and never gains. */
static void energy_xu_sun(void **state)
{
    (void)state;
    btdf_pane_opts o;
    btdf_pane_opts_default(&o);
    o.nodes = 36;
    o.modes = 48;
    btdf_pane *p = make(&o);
    double T, R;
    for (double d = 0.0; d <= 88.0; d += 4.0) {
        btdf_pane_albedo(p, BTDF_PANE_FRONT, 0, rad(d), &T, &R);
        /* 1e-9: the albedos are sums of positive terms scaled to the model's own */
        assert_true(R + T <= 1.0 + 1e-9);
    }
    btdf_pane_albedo(p, BTDF_PANE_FRONT, 0, rad(80.0), &T, &R);
    assert_true(R + T < 0.2);
    btdf_pane_free(p);
}

/* Air to air, the system is reciprocal: f_T(FRONT; ti, to) = f_T(BACK; pi - to, pi - ti)
   and f_R(ti, tr) = f_R(tr, ti). The discrete adding equations are exactly reciprocal
   (1e-12 before the energy scaling); the scaling moves each incidence node's column by
   up to 0.8 % for xu-sun (measured), differently for the two directions, so 2e-2 of the
   larger value (above a floor of 1e-3 of the BSDF) is what is checked; measured 3e-3. */
static void reciprocity(void **state)
{
    (void)state;
    btdf_pane_opts o;
    btdf_pane_opts_default(&o);
    o.thickness_mm = 4.0;
    o.absorption_per_mm = 0.05;
    o.back_smooth = 0;
    o.back_smoothness = 5.0;
    o.nodes = 40;
    o.modes = 64;
    btdf_pane *p = make(&o);
    double worst = 0.0;
    for (int a = 5; a < 85; a += 13)
        for (int b = 3; b < 85; b += 11)
            for (int c = 0; c <= 180; c += 45) {
                double ti = rad(a), tt = rad(b), ph = rad(c);
                double f1 = btdf_pane_eval(p, BTDF_PANE_FRONT, BTDF_PART_TRANSMISSION, 0, ti,
                                           M_PI - tt, ph);
                double f2 = btdf_pane_eval(p, BTDF_PANE_BACK, BTDF_PART_TRANSMISSION, 0, tt,
                                           M_PI - ti, ph);
                double g1 = btdf_pane_eval(p, BTDF_PANE_FRONT, BTDF_PART_REFLECTION, 0, ti, tt, ph);
                double g2 = btdf_pane_eval(p, BTDF_PANE_FRONT, BTDF_PART_REFLECTION, 0, tt, ti, ph);
                double e1 = fabs(f1 - f2) / fmax(fmax(f1, f2), 1e-3);
                double e2 = fabs(g1 - g2) / fmax(fmax(g1, g2), 1e-3);
                worst = fmax(worst, fmax(e1, e2));
            }
    assert_true(worst < 2e-2);
    btdf_pane_free(p);
}

/* The default quadrature against a finer one (nodes and modes x 1.5): MODEL.md 6's e_L1
   over 0-80 deg, both sides, both parts. Measured at n = 1.5, s = 3, flat back, 4 mm:
   1.24e-3 at (72, 96) against (108, 144) (btdf-bench pane), 6.5e-4 against (96, 128);
   36 nodes against 72 gave 3.1e-2, so the bound 2e-3 fails a quadrature that is too
   coarse. */
static void convergence(void **state)
{
    (void)state;
    btdf_pane_opts o;
    btdf_pane_opts_default(&o);
    o.thickness_mm = 4.0;
    btdf_pane *a = make(&o);
    int n, m;
    btdf_pane_size(a, &n, &m);
    o.nodes = n + n / 2;
    o.modes = m + m / 2;
    btdf_pane *b = make(&o);
    btdf_pane_error e;
    assert_status(BTDF_OK, btdf_pane_compare(a, b, rad(80.0), 0, 0, 0, &e));
    assert_true(e.e_l1 < 2e-3);
    assert_true(e.e_t < 2e-3);
    btdf_pane_free(a);
    btdf_pane_free(b);
}

/* Same bytes whatever the thread count: each row of an operator is one item. */
static void threads(void **state)
{
    (void)state;
    btdf_pane_opts o;
    btdf_pane_opts_default(&o);
    o.nodes = 24;
    o.modes = 16;
    o.threads = 1;
    btdf_pane *a = make(&o);
    o.threads = 2;
    btdf_pane *b = make(&o);
    for (int d = 0; d < 90; d += 10) {
        double x = btdf_pane_eval(a, BTDF_PANE_FRONT, BTDF_PART_TRANSMISSION, 0, rad(d), rad(150), 1.0);
        double y = btdf_pane_eval(b, BTDF_PANE_FRONT, BTDF_PART_TRANSMISSION, 0, rad(d), rad(150), 1.0);
        assert_memory_equal(&x, &y, sizeof x);
    }
    btdf_pane_free(a);
    btdf_pane_free(b);
}

/* btdf_pane_get_series: the rule its comment states, written out here on its own (a
   linear scan for the stencil, the Lagrange products, the cosines by cos() itself),
   gives btdf_pane_eval on every block. The two sum the same terms in other orders, so
   they agree to rounding: 1e-12 of the value plus 1e-12 of the largest coefficient
   (40 modes of 16 products each). */
static double series_rule(const double *mu, const double *c, int n, int modes, double mui,
                          double muo, double phi)
{
    int k[2];
    double w[2][4], wp[2][4], r[2], x[2] = {mui, muo};
    for (int d = 0; d < 2; d++) {
        int last = -1;
        for (int j = 0; j < n; j++)
            if (mu[j] <= x[d])
                last = j;
        int kk = last - 1;
        kk = kk < 0 ? 0 : (kk > n - 4 ? n - 4 : kk);
        k[d] = kk;
        for (int a = 0; a < 4; a++) {
            double v = 1.0;
            for (int b = 0; b < 4; b++)
                if (b != a)
                    v *= (x[d] - mu[kk + b]) / (mu[kk + a] - mu[kk + b]);
            w[d][a] = v;
            /* towards the pole, past the last node: mode m is the last node's times r^m */
            wp[d][a] = x[d] > mu[n - 1] ? (a == 3 ? 1.0 : 0.0) : v;
        }
        r[d] = x[d] > mu[n - 1] ? sqrt((1.0 - x[d] * x[d]) / (1.0 - mu[n - 1] * mu[n - 1])) : 1.0;
    }
    double sum = 0.0;
    for (int m = 0; m < modes; m++) {
        double cm = 0.0;
        double(*u)[4] = m ? wp : w;
        for (int a = 0; a < 4; a++)
            for (int b = 0; b < 4; b++)
                cm += u[0][a] * u[1][b] * c[((size_t)m * n + k[0] + a) * n + k[1] + b];
        sum += cm * pow(r[0] * r[1], m) * cos(m * phi);
    }
    return sum > 0.0 ? sum : 0.0;
}

static void series(void **state)
{
    (void)state;
    btdf_pane_opts o;
    btdf_pane_opts_default(&o);
    o.front.smoothness = 2.0;
    o.back_smooth = 0;
    o.back_smoothness = 5.0;
    o.absorption_per_mm = 0.02;
    o.nodes = 32; /* the rule does not depend on the size: a small pane builds fast */
    o.modes = 40;
    btdf_pane *p = make(&o);
    const double *mu = NULL, *c = NULL;
    int n = 0, m = 0;
    for (int side = 1; side <= 2; side++)
        for (int part = 1; part <= 2; part++) {
            assert_status(BTDF_OK, btdf_pane_get_series(p, (btdf_pane_side)side, (btdf_part)part,
                                                        0, &mu, &c, &n, &m));
            int pn, pm;
            btdf_pane_size(p, &pn, &pm);
            assert_int_equal(n, pn);
            assert_int_equal(m, pm);
            double cmax = 0.0;
            for (size_t q = 0; q < (size_t)m * n * n; q++)
                cmax = fabs(c[q]) > cmax ? fabs(c[q]) : cmax;
            for (double ti = 0.0; ti < 89.0; ti += ti < 1.0 ? 0.4 : 7.3)
                for (double t = 0.0; t < 89.5; t += t < 1.0 ? 0.4 : 4.9)
                    for (double ph = 0.0; ph <= 180.0; ph += 22.5) {
                        double to = part == BTDF_PART_TRANSMISSION ? 180.0 - t : t;
                        double v = btdf_pane_eval(p, side, part, 0, rad(ti), rad(to), rad(ph));
                        double r = series_rule(mu, c, n, m, cos(rad(ti)), cos(rad(t)), rad(ph));
                        assert_close(v, r, 1e-12, 1e-12 * cmax);
                    }
        }
    assert_status(BTDF_EINVAL, btdf_pane_get_series(p, BTDF_PANE_FRONT, BTDF_PART_TRANSMISSION,
                                                    1, &mu, &c, &n, &m));
    assert_status(BTDF_EINVAL, btdf_pane_get_series(p, (btdf_pane_side)3, BTDF_PART_TRANSMISSION,
                                                    0, &mu, &c, &n, &m));
    assert_status(BTDF_EINVAL, btdf_pane_get_series(NULL, BTDF_PANE_FRONT,
                                                    BTDF_PART_TRANSMISSION, 0, &mu, &c, &n, &m));
    btdf_pane_free(p);
}

/* On the axis (ti = 0, or to = 180 / tr = 0) a direction has no azimuth: the value
   cannot depend on phi. Before the modes were made to vanish at the pole, a cubic
   extrapolated them past the last node and the value moved with phi by 10 % (n = 1.5,
   s = 3, ti = 30, to = 180: 0.1745 at phi = 0, 0.2163 at 180). Now only m = 0 is left
   there, so the values are equal to the bit; and the change is continuous at the last
   node (1e-9 rad either side of it, the values within 1e-6 of each other: the series'
   slope there is of order 1 per radian). */
static void pole(void **state)
{
    (void)state;
    btdf_pane_opts o;
    btdf_pane_opts_default(&o);
    o.nodes = 32;
    o.modes = 40;
    btdf_pane *p = make(&o);
    for (int side = 1; side <= 2; side++)
        for (int part = 1; part <= 2; part++) {
            int tr = part == BTDF_PART_TRANSMISSION;
            double ax = tr ? M_PI : 0.0;
            for (double ph = 0.0; ph <= 180.0; ph += 45.0) {
                double a = btdf_pane_eval(p, side, part, 0, 0.0, rad(tr ? 150.0 : 30.0), rad(ph));
                double b = btdf_pane_eval(p, side, part, 0, 0.0, rad(tr ? 150.0 : 30.0), 0.0);
                assert_true(a == b && a > 0.0);
                a = btdf_pane_eval(p, side, part, 0, rad(30.0), ax, rad(ph));
                b = btdf_pane_eval(p, side, part, 0, rad(30.0), ax, 0.0);
                assert_true(a == b && a > 0.0);
            }
            const double *mu, *c;
            int n, m;
            assert_status(BTDF_OK, btdf_pane_get_series(p, side, part, 0, &mu, &c, &n, &m));
            double tl = acos(mu[n - 1]);
            for (double ph = 0.0; ph <= 180.0; ph += 60.0) {
                double to = tr ? M_PI - rad(40.0) : rad(40.0);
                double a = btdf_pane_eval(p, side, part, 0, tl - 1e-9, to, rad(ph));
                double b = btdf_pane_eval(p, side, part, 0, tl + 1e-9, to, rad(ph));
                assert_close(a, b, 1e-6, 0.0);
                a = btdf_pane_eval(p, side, part, 0, rad(20.0), tr ? M_PI - tl + 1e-9 : tl - 1e-9, rad(ph));
                b = btdf_pane_eval(p, side, part, 0, rad(20.0), tr ? M_PI - tl - 1e-9 : tl + 1e-9, rad(ph));
                assert_close(a, b, 1e-6, 0.0);
            }
        }
    btdf_pane_free(p);
}

static void bad_input(void **state)
{
    (void)state;
    btdf_pane_opts o;
    btdf_pane *p = NULL;
    char msg[256];
    btdf_pane_opts_default(&o);
    o.front.ior[0] = 0.8;
    assert_status(BTDF_EINVAL, btdf_pane_new(&o, &p, msg, sizeof msg));
    assert_non_null(strstr(msg, "0.8"));
    btdf_pane_opts_default(&o);
    o.thickness_mm = -1.0;
    assert_status(BTDF_EINVAL, btdf_pane_new(&o, &p, msg, sizeof msg));
    assert_non_null(strstr(msg, "thickness"));
    btdf_pane_opts_default(&o);
    o.absorption_per_mm = NAN;
    assert_status(BTDF_EINVAL, btdf_pane_new(&o, &p, msg, sizeof msg));
    btdf_pane_opts_default(&o);
    o.back_smooth = 0;
    o.back_smoothness = 0.0;
    assert_status(BTDF_EINVAL, btdf_pane_new(&o, &p, msg, sizeof msg));
    assert_null(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(flat_slab),   cmocka_unit_test(rough_tends_to_flat),
        cmocka_unit_test(energy_full), cmocka_unit_test(energy_xu_sun),
        cmocka_unit_test(reciprocity), cmocka_unit_test(convergence),
        cmocka_unit_test(threads),     cmocka_unit_test(bad_input),
        cmocka_unit_test(series),      cmocka_unit_test(pole),
    };
    const char *flt = getenv("BTDF_TEST_FILTER");
    if (flt)
        cmocka_set_test_filter(flt);
    return cmocka_run_group_tests(tests, NULL, NULL);
}
