/* SPDX-License-Identifier: MIT */
/* simchart.h: the simulator's pictures as charts (btdf_preview.h's BTDF_PREVIEW_CHART):
   the outgoing lobe of a case in the plane of incidence against the models, and energy
   per order against s. For btdftab simulate --preview and btdf-simfig. */
#ifndef BTDFTAB_SIMCHART_H
#define BTDFTAB_SIMCHART_H

#include <stddef.h>

#include <btdf/btdf_preview.h>
#include <btdf/btdf_sim.h>

/* One panel's arrays (owned by it). */
typedef struct simchart_panel {
    char title[96];
    btdf_chart_series series[3];
    size_t nseries;
    double *buf;
} simchart_panel;

/* The transmitted lobe of case k in the plane of incidence: the bins next to |phi| = 0
   (backward, drawn at negative theta_o, degrees from the downward normal) and
   |phi| = 180 (forward, positive), as the bin's mean of rho |cos theta_o| with bars of
   one standard error, beside Eq. 25 (k0 = 0.7) and Smith over the same bins (lines).
   A profile run (1D) has per-radian values and no model. 0, or -1 (message in msg). */
int simchart_lobe(const btdf_sim_result *r, size_t k, double k0, simchart_panel *p, char *msg,
                  size_t msglen);
void simchart_panel_free(simchart_panel *p);

#endif
