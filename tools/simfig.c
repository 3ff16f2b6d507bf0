/* SPDX-License-Identifier: MIT */
/* simfig.c: btdf-simfig, the simulator's figures from the public API
   (docs/simulation.md):
     fig8 F.png    the paper's Fig. 8 redrawn: ti = 30, n = 1/1.4, s = 6, 3, 1, 0.5, the
                   simulated lobe in the plane of incidence with error bars beside
                   Eq. 25 and Smith over the same bins;
     fig9 F.png    the same for n = 1.4 (the paper's Fig. 9);
     orders F.png  T by order of scattering (1, 2, 3+) and in all, with errors, and
                   Eq. 25's T, against s from 0.5 to 30, ti = 30, n = 1.5 and 1/1.5;
     models F.png  T(ti) of n = 1.5 under xu-sun, smith and full (1 degree steps) beside
                   the simulation (every 5 degrees, 0 to 85, with errors) for s = 0.5,
                   1, 3, 10 (docs/model.md section 12).
   Options: --rays K (per case; default 400000 for the lobes, 100000 for the orders),
   --seed X (default 1), --threads T (default all). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <btdf/btdf.h>
#include <btdf/btdf_preview.h>
#include <btdf/btdf_sim.h>

#include "simchart.h"

#define DEG (3.14159265358979323846 / 180.0)

static int usage(void)
{
    fprintf(stderr, "usage: btdf-simfig fig8|fig9|orders|models OUT.png [--rays K] [--seed X] "
                    "[--threads T]\n");
    return 2;
}

static btdf_sim_result *simulate(double n, double s, double ti, unsigned long long rays,
                                 unsigned long long seed, int threads, int bins)
{
    btdf_sim_opts o;
    btdf_sim_opts_default(&o);
    o.ior[0] = n;
    o.smoothness = s;
    o.theta_i = &ti;
    o.n_theta = 1;
    o.rays = rays;
    o.seed = seed;
    o.threads = threads;
    o.theta_bins = bins ? 45 : 0; /* 2 degrees in theta_o */
    o.phi_bins = bins ? 36 : 1;   /* 5 degrees of |phi| either side of the plane */
    btdf_sim_result *r = NULL;
    char msg[512];
    if (btdf_sim_run(&o, &r, msg, sizeof msg) != BTDF_OK) {
        fprintf(stderr, "btdf-simfig: n %g s %g: %s\n", n, s, msg);
        return NULL;
    }
    fprintf(stderr, "n %g s %g: T %.4f +- %.4f (one hit %.4f)\n", n, s, r->tally[0].T.mean,
            r->tally[0].T.se, r->tally[0].T_order[0].mean);
    return r;
}

static int write(const btdf_chart *ch, const char *title, const char *path)
{
    btdf_preview_opts po;
    btdf_preview_opts_default(&po);
    po.kind = BTDF_PREVIEW_CHART;
    po.chart = ch;
    po.title = title;
    char msg[512];
    if (btdf_preview_write(&po, path, msg, sizeof msg) != BTDF_OK) {
        fprintf(stderr, "btdf-simfig: %s: %s\n", path, msg);
        return 1;
    }
    return 0;
}

static int lobes(double n, const char *title, const char *path, unsigned long long rays,
                 unsigned long long seed, int threads)
{
    const double ss[4] = {6, 3, 1, 0.5};
    simchart_panel pn[4];
    btdf_chart_panel cp[4];
    btdf_sim_result *r[4] = {NULL, NULL, NULL, NULL};
    int code = 0, made = 0;
    char msg[256];
    for (int k = 0; k < 4 && !code; k++) {
        r[k] = simulate(n, ss[k], 30 * DEG, rays, seed, threads, 1);
        if (!r[k] || simchart_lobe(r[k], 0, 0.7, &pn[k], msg, sizeof msg) != 0) {
            if (r[k])
                fprintf(stderr, "btdf-simfig: %s\n", msg);
            code = 1;
            break;
        }
        made++;
        snprintf(pn[k].title, sizeof pn[k].title, "(%c) s = %g: T %.3f (one hit %.3f)",
                 'a' + k, ss[k], r[k]->tally[0].T.mean, r[k]->tally[0].T_order[0].mean);
        cp[k] = (btdf_chart_panel){pn[k].title, pn[k].series, pn[k].nseries};
    }
    if (!code) {
        btdf_chart ch = {"\xce\xb8o from the downward normal (\xc2\xb0; < 0 backward, > 0 forward)",
                         "\xcf\x81 |cos \xce\xb8o| (1/sr)", 0, -90.0, 90.0, cp, 4, 2};
        code = write(&ch, title, path);
    }
    for (int k = 0; k < made; k++)
        simchart_panel_free(&pn[k]);
    for (int k = 0; k < 4; k++)
        btdf_sim_result_free(r[k]);
    return code;
}

#define NS 10
static int orders(const char *path, unsigned long long rays, unsigned long long seed,
                  int threads)
{
    const double ss[NS] = {0.5, 0.7, 1, 1.5, 2, 3, 4, 6, 10, 30};
    const double ns[2] = {1.5, 1 / 1.5};
    static double x[2][NS], y[2][5][NS], e[2][5][NS];
    static btdf_chart_series se[2][5];
    btdf_chart_panel cp[2];
    static const char *labels[5] = {"one hit", "two hits", "three or more", "all orders",
                                    "Eq. 25"};
    for (int a = 0; a < 2; a++) {
        for (int k = 0; k < NS; k++) {
            btdf_sim_result *r = simulate(ns[a], ss[k], 30 * DEG, rays, seed, threads, 0);
            if (!r)
                return 1;
            const btdf_sim_tally *t = &r->tally[0];
            x[a][k] = ss[k];
            for (int q = 0; q < 3; q++) {
                y[a][q][k] = t->T_order[q].mean;
                e[a][q][k] = t->T_order[q].se;
            }
            y[a][3][k] = t->T.mean;
            e[a][3][k] = t->T.se;
            btdf_params p;
            btdf_params_default(&p);
            p.ior[0] = ns[a];
            p.smoothness = ss[k];
            if (btdf_transmittance(&p, 30 * DEG, &y[a][4][k]) != BTDF_OK)
                y[a][4][k] = 0.0;
            e[a][4][k] = 0.0;
            btdf_sim_result_free(r);
        }
        for (int q = 0; q < 5; q++)
            se[a][q] = (btdf_chart_series){labels[q], NS, x[a], y[a][q], q < 4 ? e[a][q] : NULL,
                                           q < 4};
        cp[a] = (btdf_chart_panel){a ? "n = 1/1.5 (from the dense side), \xce\xb8i = 30\xc2\xb0"
                                     : "n = 1.5, \xce\xb8i = 30\xc2\xb0",
                                   se[a], 5};
    }
    btdf_chart ch = {"s = \xcf\x84 / \xcf\x83 (log scale)", "T, fraction of the incident flux",
                     1, 0.4, 40.0, cp, 2, 2};
    return write(&ch, "Transmission by order of scattering against smoothness", path);
}

#define NM_SIM 18 /* simulated angles: 0 to 85 by 5 degrees */
#define NM_CURVE 90 /* model curves: 0 to 89 by 1 degree */
static int models(const char *path, unsigned long long rays, unsigned long long seed,
                  int threads)
{
    const double ss[4] = {0.5, 1, 3, 10};
    static double xs[NM_SIM], ys[4][NM_SIM], es[4][NM_SIM], xc[NM_CURVE], yc[4][3][NM_CURVE];
    static btdf_chart_series se[4][4];
    static char titles[4][64];
    btdf_chart_panel cp[4];
    static const char *labels[4] = {"simulation (all orders)", "xu-sun (Eq. 25)", "smith",
                                    "full"};
    double ti[NM_SIM];
    for (int k = 0; k < NM_SIM; k++)
        ti[k] = xs[k] = 5.0 * k;
    for (int k = 0; k < NM_CURVE; k++)
        xc[k] = k;
    for (int q = 0; q < 4; q++) {
        btdf_sim_opts o;
        btdf_sim_opts_default(&o);
        o.ior[0] = 1.5;
        o.smoothness = ss[q];
        double tr[NM_SIM];
        for (int k = 0; k < NM_SIM; k++)
            tr[k] = ti[k] * DEG;
        o.theta_i = tr;
        o.n_theta = NM_SIM;
        o.rays = rays;
        o.seed = seed;
        o.threads = threads;
        o.theta_bins = 0;
        o.phi_bins = 1;
        btdf_sim_result *r = NULL;
        char msg[512];
        if (btdf_sim_run(&o, &r, msg, sizeof msg) != BTDF_OK) {
            fprintf(stderr, "btdf-simfig: s %g: %s\n", ss[q], msg);
            return 1;
        }
        for (int k = 0; k < NM_SIM; k++) {
            ys[q][k] = r->tally[k].T.mean;
            es[q][k] = r->tally[k].T.se;
        }
        btdf_sim_result_free(r);
        btdf_params p;
        btdf_params_default(&p);
        p.smoothness = ss[q];
        btdf_full_opts fo;
        btdf_full_opts_default(&fo);
        fo.threads = threads;
        btdf_full *f = NULL;
        if (btdf_full_new(1.5, ss[q], &fo, &f, msg, sizeof msg) != BTDF_OK) {
            fprintf(stderr, "btdf-simfig: s %g: %s\n", ss[q], msg);
            return 1;
        }
        for (int k = 0; k < NM_CURVE; k++) {
            btdf_full_albedos al;
            p.model = BTDF_MODEL_XU_SUN;
            if (btdf_transmittance(&p, xc[k] * DEG, &yc[q][0][k]) != BTDF_OK)
                yc[q][0][k] = 0.0;
            p.model = BTDF_MODEL_SMITH;
            if (btdf_transmittance(&p, xc[k] * DEG, &yc[q][1][k]) != BTDF_OK)
                yc[q][1][k] = 0.0;
            yc[q][2][k] = btdf_full_albedo(f, xc[k] * DEG, &al) == BTDF_OK ? al.T : 0.0;
        }
        btdf_full_free(f);
        se[q][0] = (btdf_chart_series){labels[0], NM_SIM, xs, ys[q], es[q], 1};
        for (int m = 0; m < 3; m++)
            se[q][m + 1] = (btdf_chart_series){labels[m + 1], NM_CURVE, xc, yc[q][m], NULL, 0};
        snprintf(titles[q], sizeof titles[q], "(%c) s = %g", 'a' + q, ss[q]);
        cp[q] = (btdf_chart_panel){titles[q], se[q], 4};
    }
    btdf_chart ch = {"\xce\xb8i (\xc2\xb0)", "T, fraction of the incident flux", 0, 0.0, 90.0,
                     cp, 4, 2};
    return write(&ch, "T(\xce\xb8i) of n = 1.5 under each model beside the simulated surface",
                 path);
}

int main(int argc, char **argv)
{
    if (argc < 3)
        return usage();
    if (!btdf_format_available(".png")) {
        fprintf(stderr, "btdf-simfig: this build has no pictures (meson -Dpng=enabled)\n");
        return 2;
    }
    unsigned long long rays = 0, seed = 1;
    int threads = 0;
    for (int k = 3; k < argc; k++) {
        char *end = NULL;
        if (k + 1 >= argc)
            return usage();
        double v = strtod(argv[k + 1], &end);
        if (!end || *end || !(v >= 0 && v <= 1e11) || v != floor(v)) {
            fprintf(stderr, "btdf-simfig: %s '%s': a whole number in [0, 1e11]\n", argv[k],
                    argv[k + 1]);
            return 2;
        }
        if (!strcmp(argv[k], "--rays") && v >= 2)
            rays = (unsigned long long)v;
        else if (!strcmp(argv[k], "--seed"))
            seed = (unsigned long long)v;
        else if (!strcmp(argv[k], "--threads") && v <= 256)
            threads = (int)v;
        else
            return usage();
        k++;
    }
    if (!strcmp(argv[1], "fig8"))
        return lobes(1 / 1.4, "Fig. 8 redrawn: n = 1/1.4, \xce\xb8i = 30\xc2\xb0 (2D Gaussian surface)",
                     argv[2], rays ? rays : 400000, seed, threads);
    if (!strcmp(argv[1], "fig9"))
        return lobes(1.4, "Fig. 9 redrawn: n = 1.4, \xce\xb8i = 30\xc2\xb0 (2D Gaussian surface)",
                     argv[2], rays ? rays : 400000, seed, threads);
    if (!strcmp(argv[1], "orders"))
        return orders(argv[2], rays ? rays : 100000, seed, threads);
    if (!strcmp(argv[1], "models"))
        return models(argv[2], rays ? rays : 200000, seed, threads);
    return usage();
}
