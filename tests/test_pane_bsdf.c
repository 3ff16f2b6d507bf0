/* SPDX-License-Identifier: MIT */
/* test_pane_bsdf.c: SCATFUN files of a caller's BSDF (btdf_scatfun_build_source) and of a
   pane's system (its four blocks, front face up): a source with a known integral, the
   pane's albedo through pbrt-v3's own sampling route (tests/pbrt_route.h), values at the
   lobes against btdf_pane_eval, bytes for any thread count, bad sources. */
#include "btdf_test.h"

#include <float.h>
#include <stdlib.h>
#include <string.h>

#include "btdf_pane.h"
#include "btdf_radiance.h"
#include "btdf_scatfun.h"
#include "pbrt_route.h"

/* ---- a source with a known answer ---------------------------------------------------- */

/* rho = C (1 + cos phi / 2) in every block: T = R = C pi (the cos term integrates to 0
   over phi, mu over [0, 1] gives 1/2, 2 pi / 2 = pi), so C = 0.5 / pi makes each 0.5. */
#define KNOWN_C (0.5 / M_PI)
static void known_modes(void *user, int block, double mu_l, double mu_v, double *c)
{
    (void)user;
    (void)block;
    (void)mu_l;
    (void)mu_v;
    c[0] = KNOWN_C;
    c[1] = 0.5 * KNOWN_C;
    c[2] = 0.0;
}

static void known_nodes(double *nodes, size_t n)
{
    for (size_t k = 0; k < n; k++) /* Gauss-like: denser towards both ends */
        nodes[k] = 0.5 - 0.5 * cos(M_PI * ((double)k + 0.5) / (double)n);
}

/* The file of a known source reads back its value with phi = pi forward (the series in
   phi_d = pi - phi carries (-1)^m), and its T (importance mode, the slow index the
   light's) is 0.5. A constant in mu is reproduced by the spline up to the float
   rounding of the nodes and coefficients (1e-7), except next to grazing, where the
   nodes at 0 hold 0: at 30 and 60 deg the values are within 1e-6. T is integrated on
   400 x 400 midpoint cells in (mu_v, phi), a rule exact for the cos phi term and, for
   the linear-in-mu_v integrand, exact but for the interval next to grazing (the spline
   drops to 0 at mu_v = 0 there), which moves T by less than the builder's own e_T
   bound (tolerance 1e-3), the allowance below. */
static void known_source(void **state)
{
    (void)state;
    double nodes[40];
    known_nodes(nodes, 40);
    btdf_scatfun_source s = {NULL, BTDF_SCATFUN_ALL, 3, known_modes, nodes, 40, 1.0, 0.0};
    btdf_scatfun *f = NULL;
    btdf_scatfun_source_error e;
    char msg[256] = "";
    btdf_status st = btdf_scatfun_build_source(&s, 1e-3, 1, &f, &e, msg, sizeof msg);
    if (st != BTDF_OK)
        print_error("%s\n", msg);
    assert_status(BTDF_OK, st);
    assert_true(e.e_l1 <= 1e-3 && e.e_t <= 1e-3);
    assert_int_equal(BTDF_SCATFUN_ALL, btdf_scatfun_sides(f));
    assert_close(1.0, btdf_scatfun_eta(f), 0.0, 0.0);
    static const int blocks[4] = {BTDF_SCATFUN_T_ENTER, BTDF_SCATFUN_T_LEAVE,
                                  BTDF_SCATFUN_R_TOP, BTDF_SCATFUN_R_BOTTOM};
    for (int b = 0; b < 4; b++) {
        int refl = blocks[b] & BTDF_SCATFUN_REFLECTION;
        for (int a = 0; a < 2; a++) {
            double ti = rad(a ? 60.0 : 30.0), t = rad(40.0), to = refl ? t : M_PI - t, v;
            assert_status(BTDF_OK, btdf_scatfun_eval_side(f, (btdf_side)blocks[b],
                                                          BTDF_SCATFUN_DIRECT, ti, to, M_PI, &v));
            assert_close(0.5 * KNOWN_C, v, 1e-6, 0.0); /* forward: 1 + cos(pi) / 2 */
            assert_status(BTDF_OK, btdf_scatfun_eval_side(f, (btdf_side)blocks[b],
                                                          BTDF_SCATFUN_DIRECT, ti, to, 0.0, &v));
            assert_close(1.5 * KNOWN_C, v, 1e-6, 0.0);
            double T = 0.0;
            for (int j = 0; j < 400; j++)
                for (int q = 0; q < 400; q++) {
                    double mu = (j + 0.5) / 400.0, phi = (q + 0.5) * 2.0 * M_PI / 400.0;
                    double o = refl ? acos(mu) : M_PI - acos(mu);
                    assert_status(BTDF_OK,
                                  btdf_scatfun_eval_side(f, (btdf_side)blocks[b],
                                                         BTDF_SCATFUN_DIRECT, ti, o,
                                                         phi > M_PI ? 2.0 * M_PI - phi : phi,
                                                         &v));
                    T += v * mu * (1.0 / 400.0) * (2.0 * M_PI / 400.0);
                }
            assert_close(0.5, T, 1e-3, 0.0);
        }
    }
    btdf_scatfun_free(f);
}

static void bad_sources(void **state)
{
    (void)state;
    double nodes[4] = {0.1, 0.4, 0.7, 0.9};
    btdf_scatfun_source good = {NULL, BTDF_SCATFUN_ALL, 3, known_modes, nodes, 4, 1.0, 0.0};
    btdf_scatfun *f = NULL;
    btdf_scatfun_source_error e;
    char msg[256];
    btdf_scatfun_source s = good;
    s.blocks = 16;
    assert_status(BTDF_EINVAL, btdf_scatfun_build_source(&s, 1e-2, 1, &f, &e, msg, sizeof msg));
    assert_non_null(strstr(msg, "blocks = 16"));
    s = good;
    s.modes = 0;
    assert_status(BTDF_EINVAL, btdf_scatfun_build_source(&s, 1e-2, 1, &f, &e, msg, sizeof msg));
    assert_non_null(strstr(msg, "modes = 0"));
    double back[4] = {0.1, 0.7, 0.4, 0.9};
    s = good;
    s.nodes = back;
    assert_status(BTDF_EINVAL, btdf_scatfun_build_source(&s, 1e-2, 1, &f, &e, msg, sizeof msg));
    assert_non_null(strstr(msg, "node 2"));
    s = good;
    s.modes_at = NULL;
    assert_status(BTDF_EINVAL, btdf_scatfun_build_source(&s, 1e-2, 1, &f, &e, msg, sizeof msg));
    s = good;
    s.eta = 0.0;
    assert_status(BTDF_EINVAL, btdf_scatfun_build_source(&s, 1e-2, 1, &f, &e, msg, sizeof msg));
    assert_status(BTDF_EINVAL,
                  btdf_scatfun_build_source(&good, 0.6, 1, &f, &e, msg, sizeof msg));
    assert_non_null(strstr(msg, "tolerance"));
    assert_null(f);
}

/* ---- a pane ---------------------------------------------------------------------------- */

static void pane_modes(void *user, int block, double mu_l, double mu_v, double *c)
{
    btdf_pane_side side = block == BTDF_SCATFUN_T_ENTER || block == BTDF_SCATFUN_R_TOP
                              ? BTDF_PANE_FRONT
                              : BTDF_PANE_BACK;
    btdf_part part = block & BTDF_SCATFUN_TRANSMISSION ? BTDF_PART_TRANSMISSION
                                                       : BTDF_PART_REFLECTION;
    btdf_pane_modes(user, side, part, 0, mu_l, mu_v, c);
}

/* n = 1.5, front s = 3, back s = 6 (rough: no delta; the two sides differ), 4 mm, no
   absorption, xu-sun. */
static btdf_pane *the_pane(void)
{
    btdf_pane_opts o;
    btdf_pane_opts_default(&o);
    o.front.ior[0] = 1.5;
    o.front.smoothness = 3.0;
    o.back_smooth = 0;
    o.back_smoothness = 6.0;
    o.thickness_mm = 4.0;
    o.threads = 1;
    btdf_pane *P = NULL;
    char msg[256] = "";
    btdf_status st = btdf_pane_new(&o, &P, msg, sizeof msg);
    if (st != BTDF_OK)
        print_error("%s\n", msg);
    assert_status(BTDF_OK, st);
    return P;
}

/* The pane of the tests below and its file at 1e-2 (all threads), made once. */
static btdf_pane *g_pane;
static btdf_scatfun *g_file;
static btdf_scatfun_source_error g_err;

static btdf_scatfun *pane_file(const btdf_pane *P, double tol, int threads,
                               btdf_scatfun_source_error *e);

static int pane_setup(void **state)
{
    (void)state;
    g_pane = the_pane();
    g_file = pane_file(g_pane, 1e-2, 0, &g_err);
    return 0;
}

static int pane_teardown(void **state)
{
    (void)state;
    btdf_scatfun_free(g_file);
    btdf_pane_free(g_pane);
    return 0;
}

static btdf_scatfun *pane_file(const btdf_pane *P, double tol, int threads,
                               btdf_scatfun_source_error *e)
{
    const double *mu, *coef;
    int nodes, modes;
    assert_status(BTDF_OK, btdf_pane_get_series(P, BTDF_PANE_FRONT, BTDF_PART_TRANSMISSION, 0,
                                                &mu, &coef, &nodes, &modes));
    btdf_scatfun_source s = {(void *)P, BTDF_SCATFUN_ALL, modes, pane_modes, mu,
                             (size_t)nodes, 1.0, 2.0 / 3.0};
    btdf_scatfun *f = NULL;
    char msg[256] = "";
    btdf_status st = btdf_scatfun_build_source(&s, tol, threads, &f, e, msg, sizeof msg);
    if (st != BTDF_OK)
        print_error("%s\n", msg);
    assert_status(BTDF_OK, st);
    return f;
}

static double unif(uint64_t *x)
{
    *x = *x * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*x >> 11) * (1.0 / 9007199254740992.0);
}

/* What pbrt-v3 renders: its Sample_f through the file (tests/pbrt_route.h, single
   precision), views on both sides, in radiance mode (eta = 1: the same as importance
   mode). The Monte Carlo albedo of a view must be the pane's T + R for light on that
   side at that angle (btdf_pane_albedo; reciprocity of the air-to-air system), within
   the file's own error (e_T <= tolerance relative to max(T, 0.01) and max(R, 0.01) per
   block, which the build checks) plus 4 standard errors; every sample finite and no
   loop capped. The estimator has no variance here (one channel, sampled in proportion
   to the file's value): measured within 1.9e-4 of the pane at every view. The two sides
   differ (at 70 deg T + R is 0.302 from the front and 0.471 from the back), so blocks
   swapped between the sides fail, as a lost |mu_f| or 2 pi does. */
static void pane_route(void **state)
{
    (void)state;
    const btdf_pane *P = g_pane;
    const btdf_scatfun *f = g_file;
    double tol = 1e-2;
    assert_true(g_err.e_l1 <= tol && g_err.e_t <= tol);
    pr_table t;
    assert_int_equal(0, pr_table_init(&t, f));
    static const double views[] = {1.0, 20.0, 45.0, 70.0, 85.0};
    for (int side = 0; side < 2; side++)
        for (size_t v = 0; v < sizeof views / sizeof views[0]; v++) {
            double th = rad(views[v]);
            float wo[3] = {(float)sin(th), 0.0f, (float)(side ? -cos(th) : cos(th))};
            double T, R;
            btdf_pane_albedo(P, side ? BTDF_PANE_BACK : BTDF_PANE_FRONT, 0, th, &T, &R);
            pr_stats st;
            memset(&st, 0, sizeof st);
            uint64_t rng = 0x9a4e0000ULL + v * 2 + (uint64_t)side;
            long N = 8000, capped = 0;
            double sum = 0.0, sum2 = 0.0;
            for (long i = 0; i < N; i++) {
                float u[2] = {(float)unif(&rng),
                              fminf((float)(((double)i + unif(&rng)) / (double)N),
                                    1.0f - FLT_EPSILON / 2)};
                float wi[3], rgb[3], pdf;
                capped += !pr_sample_f(&t, wo, u, 1, wi, rgb, &pdf, &st);
                double est = pdf > 0 ? (double)rgb[0] * fabs((double)wi[2]) / (double)pdf : 0.0;
                sum += est;
                sum2 += est * est;
            }
            double mean = sum / (double)N;
            double se = sqrt(fmax(0.0, sum2 / (double)N - mean * mean) / (double)N);
            double allow = tol * (fmax(T, 0.01) + fmax(R, 0.01)) + 4.0 * se;
            print_message("side %d view %4.1f: pbrt route %.5f +- %.5f, pane T + R %.5f "
                          "(T %.5f, R %.5f)\n", side, views[v], mean, se, T + R, T, R);
            assert_int_equal(0, st.nonfinite);
            assert_int_equal(0, capped);
            assert_true(fabs(mean - (T + R)) <= allow);
        }
    pr_table_free(&t);
}

/* Values at the lobes, the file read as pbrt-v3 reads it (DIRECT and ADJOINT) against
   btdf_pane_eval in the frame of the lit face. At these smooth peaks the file is within
   2e-4 of the system (measured: spline and float rounding); its e_L1 bound (1e-2) is an
   average, so 1 % is allowed pointwise. A flipped azimuth reads the value at phi = 0
   instead, 29 to 2100 times smaller in these forward and mirror lobes. ADJOINT reads the other
   block of the pair (reciprocity): the system's own reciprocity (1e-5 relative,
   docs/pane.md) plus the same 1 %. */
static void pane_values(void **state)
{
    (void)state;
    const btdf_pane *P = g_pane;
    const btdf_scatfun *f = g_file;
    static const struct {
        int block;
        double ti, to, phi; /* degrees */
    } pt[] = {
        {BTDF_SCATFUN_T_ENTER, 30, 150, 180},  {BTDF_SCATFUN_T_ENTER, 60, 125, 170},
        {BTDF_SCATFUN_T_LEAVE, 45, 140, 175},  {BTDF_SCATFUN_R_TOP, 60, 60, 180},
        {BTDF_SCATFUN_R_BOTTOM, 50, 50, 175}, {BTDF_SCATFUN_R_BOTTOM, 70, 65, 180},
    };
    for (size_t k = 0; k < sizeof pt / sizeof pt[0]; k++) {
        int b = pt[k].block;
        btdf_pane_side side = b == BTDF_SCATFUN_T_ENTER || b == BTDF_SCATFUN_R_TOP
                                  ? BTDF_PANE_FRONT
                                  : BTDF_PANE_BACK;
        btdf_part part = b & BTDF_SCATFUN_TRANSMISSION ? BTDF_PART_TRANSMISSION
                                                       : BTDF_PART_REFLECTION;
        double ti = rad(pt[k].ti), to = rad(pt[k].to), phi = rad(pt[k].phi), d, a;
        double want = btdf_pane_eval(P, side, part, 0, ti, to, phi);
        double back = btdf_pane_eval(P, side, part, 0, ti, to, 0.0);
        assert_status(BTDF_OK, btdf_scatfun_eval_side(f, (btdf_side)b, BTDF_SCATFUN_DIRECT, ti,
                                                      to, phi, &d));
        assert_status(BTDF_OK, btdf_scatfun_eval_side(f, (btdf_side)b, BTDF_SCATFUN_ADJOINT, ti,
                                                      to, phi, &a));
        print_message("block %d (%g, %g, %g): pane %.6g (phi 0: %.3g), file %.6g, adjoint "
                      "%.6g\n", b, pt[k].ti, pt[k].to, pt[k].phi, want, back, d, a);
        assert_true(want > 2.0 * back);
        assert_close(want, d, 1e-2, 0.0);
        assert_close(want, a, 1e-2, 0.0);
    }
}

/* The same bytes whatever the thread count (1, 2, and all cores: the shared file). */
static void pane_threads(void **state)
{
    (void)state;
    const btdf_pane *P = g_pane;
    btdf_scatfun_source_error e1, e2;
    btdf_scatfun *f1 = pane_file(P, 1e-2, 1, &e1), *f2 = pane_file(P, 1e-2, 2, &e2);
    unsigned char *b1 = NULL, *b2 = NULL;
    size_t l1 = 0, l2 = 0;
    char msg[128];
    assert_status(BTDF_OK, btdf_scatfun_to_mem(f1, "{}", &b1, &l1, msg, sizeof msg));
    assert_status(BTDF_OK, btdf_scatfun_to_mem(f2, "{}", &b2, &l2, msg, sizeof msg));
    assert_int_equal(l1, l2);
    assert_memory_equal(b1, b2, l1);
    assert_true(e1.e_l1 == e2.e_l1 && e1.e_t == e2.e_t);
    unsigned char *b3 = NULL;
    size_t l3 = 0;
    assert_status(BTDF_OK, btdf_scatfun_to_mem(g_file, "{}", &b3, &l3, msg, sizeof msg));
    assert_int_equal(l1, l3);
    assert_memory_equal(b1, b3, l1);
    free(b1);
    free(b2);
    free(b3);
    btdf_scatfun_free(f1);
    btdf_scatfun_free(f2);
}

/* ---- a pane's adaptive tree3 ------------------------------------------------------- */

static double tree_eval(void *user, int k, double ti, double to, double phi)
{
    btdf_pane_side side = k == 1 || k == 2 ? BTDF_PANE_FRONT : BTDF_PANE_BACK;
    if (k >= 2)
        return btdf_pane_eval(user, side, BTDF_PART_REFLECTION, 0, ti, to, phi);
    return btdf_pane_eval(user, side, BTDF_PART_TRANSMISSION, 0, ti, M_PI - to, phi);
}

/* btdf_rad_source.merge: every value of the merged tree is within merge * max(|v|,
   0.01 / pi) of the full tree's at the same direction (the merged leaf is the mean of
   full-tree leaves each within that of it; float rounding of the mean adds 1e-7
   relative), and the tree is smaller. 2000 random pairs of directions per block, depth
   5: measured up to 0.96 of the bound. A merge checked against the means one level
   down instead of the leaves fails it (1.1 of the bound in the front's reflection). */
static void pane_tree_merge(void **state)
{
    (void)state;
    btdf_params p;
    btdf_params_default(&p);
    p.ior[0] = 1.5;
    btdf_rad_source s = {g_pane, tree_eval, NULL, NULL, "test pane", {NULL, NULL, NULL}, 0.0};
    btdf_rad *full = NULL, *m = NULL;
    char msg[256] = "";
    assert_status(BTDF_OK, btdf_rad_build_source(&s, &p, BTDF_RAD_TREE3, 5, 1, &full, msg,
                                                 sizeof msg));
    s.merge = 0.05;
    assert_status(BTDF_OK, btdf_rad_build_source(&s, &p, BTDF_RAD_TREE3, 5, 1, &m, msg,
                                                 sizeof msg));
    uint64_t rng = 0x7ee3ULL;
    for (int k = 0; k < 4; k++) {
        btdf_rad_block_info bf, bm;
        assert_status(BTDF_OK, btdf_rad_block(full, k, &bf));
        assert_status(BTDF_OK, btdf_rad_block(m, k, &bm));
        print_message("block %d: %zu leaves, merged within 0.05: %zu\n", k, bf.values,
                      bm.values);
        assert_true(bm.values < bf.values);
        double worst = 0.0;
        for (int i = 0; i < 2000; i++) {
            double pv[3], qv[3];
            for (int v = 0; v < 2; v++) { /* uniform on the hemisphere (z >= 0 for now) */
                double z = unif(&rng), a = 2.0 * M_PI * unif(&rng), r = sqrt(1.0 - z * z);
                double *d = v ? qv : pv;
                d[0] = r * cos(a);
                d[1] = r * sin(a);
                d[2] = z;
            }
            /* the block's sides: the view p and the light q on their own sides */
            int pz = k == 1 || k == 3 ? 1 : -1, qz = k >= 2 ? pz : -pz;
            pv[2] *= pz;
            qv[2] *= qz;
            double vf = btdf_rad_lookup(full, k, pv, qv), vm = btdf_rad_lookup(m, k, pv, qv);
            double lim = 0.05 * fmax(fabs(vm), 0.01 / M_PI) * (1.0 + 1e-6);
            worst = fmax(worst, fabs(vm - vf) / lim);
            if (!(fabs(vm - vf) <= lim))
                print_error("block %d p (%g %g %g) q (%g %g %g): full %.9g merged %.9g\n", k,
                            pv[0], pv[1], pv[2], qv[0], qv[1], qv[2], vf, vm);
            assert_true(fabs(vm - vf) <= lim);
        }
        print_message("  largest difference: %.3f of the bound\n", worst);
    }
    s.merge = 0.6;
    btdf_rad *bad = NULL;
    assert_status(BTDF_EINVAL, btdf_rad_build_source(&s, &p, BTDF_RAD_TREE3, 5, 1, &bad, msg,
                                                     sizeof msg));
    assert_non_null(strstr(msg, "merge 0.6"));
    btdf_rad_free(full);
    btdf_rad_free(m);
}

int main(void)
{
    const struct CMUnitTest known[] = {
        cmocka_unit_test(known_source),
        cmocka_unit_test(bad_sources),
    };
    const struct CMUnitTest pane[] = {
        cmocka_unit_test(pane_route),
        cmocka_unit_test(pane_values),
        cmocka_unit_test(pane_threads),
        cmocka_unit_test(pane_tree_merge),
    };
    int failed = cmocka_run_group_tests(known, NULL, NULL);
    return failed + cmocka_run_group_tests(pane, pane_setup, pane_teardown);
}
