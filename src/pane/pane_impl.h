/* SPDX-License-Identifier: MIT */
/* pane_impl.h: what src/pane/pane.c (the build) and src/pane/eval.c (the readers) share. */
#ifndef BTDF_PANE_IMPL_H
#define BTDF_PANE_IMPL_H

#include "btdf_pane.h"

/* Blocks: light FRONT or BACK, TRANSMISSION or REFLECTION. */
#define PANE_BLOCKS 4
static inline int pane_block(btdf_pane_side side, btdf_part part)
{
    return (side == BTDF_PANE_BACK ? 2 : 0) + (part == BTDF_PART_REFLECTION ? 1 : 0);
}

typedef struct pane_ch {
    /* per block: the spread part's cosine coefficients in the phi of btdf.h,
       coef[(m * n + j) * n + o] for incidence node j, outgoing node o;
       the delta part's weight spec[j] and the hemispherical albedo alb[j] (both parts) */
    double *coef[PANE_BLOCKS];
    double *spec[PANE_BLOCKS];
    double *alb[PANE_BLOCKS];
} pane_ch;

struct btdf_pane {
    btdf_pane_opts o;
    btdf_full_opts full; /* o.full points here when it was given */
    int n, m;            /* nodes in air (cos theta, ascending), modes */
    double *mu, *w;      /* Gauss-Legendre on [0, 1] */
    pane_ch ch[BTDF_MAX_CHANNELS];
    double seconds;
};

/* Gauss-Legendre nodes and weights on [a, b], ascending (pane.c). */
void pane_gauss(int n, double a, double b, double *x, double *w);

#endif
