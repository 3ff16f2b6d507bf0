/* SPDX-License-Identifier: MIT */
/* pane.h: light through a pane, two faces a thickness apart with absorption between
   them (btdf_sim_opts.pane). */
#ifndef SIM_PANE_H
#define SIM_PANE_H

#include <stddef.h>
#include <stdint.h>

#include "btdf_sim.h"
#include "sim/surface.h"
#include "sim/trace.h"

/* The faces as the light meets them: face[0] the lit face, face[1] the far one; NULL
   is a flat face. Each face is used in its own frame, the outside above and the pane
   below: face[1] is mirrored in z (h and -h have the same law, and the faces are
   independent realisations). */
typedef struct sim_pane {
    const sim_surface *face[2];
    double n;            /* pane index / outside index */
    double thickness;    /* mm */
    double absorption;   /* per mm */
} sim_pane;

/* BTDF_OK, or BTDF_EINVAL naming the pane's value that is out of range (checked only
   when o->pane is set). */
btdf_status sim_pane_check(const btdf_sim_opts *o, char *msg, size_t msglen);

/* One path of light arriving on face[0] at polar angle ti, azimuth 0, until it leaves
   the pane (SIM_END_R on the lit side, SIM_END_T on the other), is absorbed
   (SIM_END_ABSORBED) or is stopped (SIM_END_LOST, after SIM_MAX_HITS hits over both
   faces). At every visit of a rough face the light enters its tile at a fresh uniform
   point and azimuth. out->dir is the outgoing direction, z > 0 on the lit side. */
void sim_pane_path(const sim_pane *p, double ti, int accel, uint64_t *rng, sim_path *out);

#endif
