/* SPDX-License-Identifier: MIT */
/* bench_pane.c: btdf-bench pane: a pane's system (front n = 1.5, s = 3, flat back, 4 mm)
   built and written as Klems full and tree3 (docs/benchmarks.md). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "btdf.h"
#include "btdf_pane.h"
#include "btdf_radiance.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

void bench_pane(FILE *f, int reps);

static btdf_pane_side side_of(int k) { return k == 1 || k == 2 ? BTDF_PANE_FRONT : BTDF_PANE_BACK; }

static double ev(void *u, int k, double ti, double to, double phi)
{
    return k >= 2 ? btdf_pane_eval(u, side_of(k), BTDF_PART_REFLECTION, 0, ti, to, phi)
                  : btdf_pane_eval(u, side_of(k), BTDF_PART_TRANSMISSION, 0, ti, M_PI - to, phi);
}

static void ev_phis(void *u, int k, double ti, double to, size_t n, const double *phi, double *out)
{
    if (k >= 2)
        btdf_pane_eval_phis(u, side_of(k), BTDF_PART_REFLECTION, 0, ti, to, n, phi, out);
    else
        btdf_pane_eval_phis(u, side_of(k), BTDF_PART_TRANSMISSION, 0, ti, M_PI - to, n, phi, out);
}

static double spec(void *u, int k, double ti)
{
    return btdf_pane_specular(u, side_of(k), k >= 2 ? BTDF_PART_REFLECTION : BTDF_PART_TRANSMISSION,
                              0, ti);
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Medians over reps of the system's build and of each file's build (2 threads), and
   the system's e_L1 and e_T against nodes and modes x 1.5 (MODEL.md 6, 0-80 deg). */
void bench_pane(FILE *f, int reps)
{
    btdf_pane_opts o;
    btdf_pane_opts_default(&o);
    o.thickness_mm = 4.0;
    o.threads = 2;
    double ts[9], tk[9], tt[9];
    btdf_pane *P = NULL;
    for (int r = 0; r < reps; r++) {
        btdf_pane_free(P);
        P = NULL;
        if (btdf_pane_new(&o, &P, NULL, 0) != BTDF_OK)
            return;
        ts[r] = btdf_pane_seconds_build(P);
        btdf_rad_source s = {P, ev, spec, ev_phis, "bench pane", {NULL, NULL, NULL}, 0.0};
        btdf_rad *x = NULL;
        tk[r] = tt[r] = 0.0;
        if (btdf_rad_build_source(&s, &o.front, BTDF_RAD_KLEMS_FULL, 0, 2, &x, NULL, 0) == BTDF_OK)
            tk[r] = btdf_rad_seconds_build(x);
        btdf_rad_free(x);
        x = NULL;
        if (btdf_rad_build_source(&s, &o.front, BTDF_RAD_TREE3, 6, 2, &x, NULL, 0) == BTDF_OK)
            tt[r] = btdf_rad_seconds_build(x);
        btdf_rad_free(x);
    }
    qsort(ts, (size_t)reps, sizeof ts[0], cmp);
    qsort(tk, (size_t)reps, sizeof tk[0], cmp);
    qsort(tt, (size_t)reps, sizeof tt[0], cmp);
    int n, m;
    btdf_pane_size(P, &n, &m);
    btdf_pane_opts o2 = o;
    o2.nodes = n + n / 2;
    o2.modes = m + m / 2;
    btdf_pane *Q = NULL;
    btdf_pane_error e = {0};
    if (btdf_pane_new(&o2, &Q, NULL, 0) == BTDF_OK)
        btdf_pane_compare(P, Q, 80.0 * M_PI / 180.0, 0, 0, 0, &e);
    fprintf(f, "case,nodes,modes,seconds_system,seconds_klems_full,seconds_tree3,e_l1,e_t\n");
    fprintf(f, "1.5/3 flat back 4 mm,%d,%d,%.3f,%.3f,%.3f,%.3g,%.3g\n", n, m, ts[reps / 2],
            tk[reps / 2], tt[reps / 2], e.e_l1, e.e_t);
    btdf_pane_free(P);
    btdf_pane_free(Q);
}
