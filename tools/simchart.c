/* SPDX-License-Identifier: MIT */
/* simchart.c: see simchart.h. */
#include "simchart.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int simchart_lobe(const btdf_sim_result *r, size_t k, double k0, simchart_panel *p, char *msg,
                  size_t msglen)
{
    memset(p, 0, sizeof *p);
    const btdf_sim_tally *t = &r->tally[k];
    int nt = r->theta_bins, np = r->phi_bins;
    if (nt < 1 || !t->hist_T) {
        snprintf(msg, msglen, "no histograms to draw");
        return -1;
    }
    size_t n = 2 * (size_t)nt, bins = (size_t)nt * (size_t)np;
    /* x, y, yerr of the simulation, y of two models, and the models' bins */
    p->buf = calloc(5 * n + 2 * bins, sizeof *p->buf);
    if (!p->buf) {
        snprintf(msg, msglen, "out of memory");
        return -1;
    }
    double *x = p->buf, *y = x + n, *e = y + n, *m1 = e + n, *m2 = m1 + n;
    double *b1 = m2 + n, *b2 = b1 + bins;
    int models = !r->profile;
    if (models &&
        (btdf_sim_model_bins(r, k, BTDF_SIM_TRANSMISSION, BTDF_MODEL_XU_SUN, k0, b1, msg,
                             msglen) != BTDF_OK ||
         btdf_sim_model_bins(r, k, BTDF_SIM_TRANSMISSION, BTDF_MODEL_SMITH, k0, b2, msg,
                             msglen) != BTDF_OK))
        return -1;
    double w = 1.5707963267948966 / nt;
    for (size_t i = 0; i < n; i++) {
        /* i < nt: backward, theta bin nt - 1 - i (from grazing to the normal); then
           forward, theta bin i - nt */
        int back = i < (size_t)nt;
        int it = back ? nt - 1 - (int)i : (int)i - nt, ip = back ? 0 : np - 1;
        size_t h = (size_t)it * (size_t)np + (size_t)ip;
        /* per sr for a surface; per radian of theta_o for a profile (two |phi| bins) */
        double om = r->profile ? w : btdf_sim_bin_solid_angle(nt, np, it, ip);
        double inv = om > 0.0 ? 1.0 / om : 0.0; /* om > 0 for every bin; kept safe */
        x[i] = (back ? -1.0 : 1.0) * (it + 0.5) * w * 57.29577951308232;
        y[i] = t->hist_T[h].mean * inv;
        e[i] = t->hist_T[h].se * inv;
        m1[i] = models ? b1[h] * inv : 0.0;
        m2[i] = models ? b2[h] * inv : 0.0;
    }
    snprintf(p->title, sizeof p->title, "n = %g, s = %g, %s = %g%s", t->ior, r->smoothness,
             "\xce\xb8i", t->theta_i * 57.29577951308232, "\xc2\xb0");
    p->series[0] = (btdf_chart_series){"simulation \xc2\xb1 1 s.e.", n, x, y, e, 1};
    p->nseries = 1;
    if (models) {
        p->series[1] = (btdf_chart_series){"Eq. 25 (same bins)", n, x, m1, NULL, 0};
        p->series[2] = (btdf_chart_series){"Smith (same bins)", n, x, m2, NULL, 0};
        p->nseries = 3;
    }
    return 0;
}

void simchart_panel_free(simchart_panel *p)
{
    free(p->buf);
    p->buf = NULL;
}
