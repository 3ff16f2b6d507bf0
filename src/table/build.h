/* SPDX-License-Identifier: MIT */
/* build.h: what the table builder's files share (build.c: options and the parts;
   grid.c: the uniform grid; slice.c: one facet-space slice; facet.c: the incidence
   refinement). Private to src/table/. */
#ifndef BTDF_TABLE_BUILD_H
#define BTDF_TABLE_BUILD_H

#include "table/table.h"

#define DEFAULT_MAX_SAMPLES ((size_t)8000000)
/* Which limit stopped refinement (bits of budget_hit). */
#define BUDGET_SAMPLES 1 /* the table's node budget */
#define BUDGET_MEMORY 2  /* the memory cap */
#define BUDGET_SLICE 4   /* one slice reached its share, an eighth of the smaller of the two */
#define DEFAULT_MAX_BYTES ((size_t)256 << 20)

/*
 * Nodes: a slice at ti holds rho at facet normals h(tn, psi). Rows start uniform in
 * u = (s/2) tan tn, the facet slope in units where the Beckmann factor is exp(-u^2),
 * so the same nodes suit every s; columns start uniform in psi. Each pass compares
 * the linear interpolant with Eq. 25 at the midpoint of every row and column
 * interval, weighted by the outgoing measure |cos to| d(omega_o) = |cos to|/chi
 * d(omega_h), and bisects the intervals whose share of the error exceeds the
 * average allowed share. Incidence nodes are bisected the same way, by comparing
 * the blend of two neighbouring slices with a slice built at their midpoint.
 */


typedef struct slice_target {
    const btdf_params *p;
    double ti;
    double target; /* allowed error: absolute L1 (already times max(T, 0.01)) or relative max */
    btdf_metric metric;
    double U; /* last row at u = U */
    size_t max_nodes;
    int refl; /* the reflection's lobe (facet_rho_r) instead of the transmission's */
} slice_target;

typedef struct slice_out {
    tslice s;
    double *w; /* measure weight per node (channel 0), for incidence refinement */
    int budget_hit;
    int nomem;
    size_t evals; /* Eq. 25 evaluations made building it */
} slice_out;

/* tb_build_slice's first grid: no slice has fewer nodes. */
#define SLICE_MIN_NODES ((size_t)17 * 13)

/* grid.c: the uniform grid of o->grid_* nodes into t. */
btdf_status tb_build_grid(const btdf_table_opts *o, btdf_table *t, char *msg, size_t msglen);

/* slice.c: one slice at tg->ti refined to tg->target within tg->max_nodes. */
void tb_build_slice(const slice_target *tg, slice_out *o);
/* Trapezoid weight of node i on a non-uniform axis. */
double tb_trap(const double *a, size_t m, size_t i);

/* facet.c */
void tb_free_slice_out(slice_out *s);
/* The part being built (BOTH never reaches the builder: it builds each part). */
int tb_opts_refl(const btdf_table_opts *o);
/* The node budget of an adaptive build, a bound at every moment of it. */
size_t tb_node_cap(const btdf_table_opts *o);
/* Incidence slices of the first pass, at most 5 degrees apart. */
size_t tb_first_slices(const btdf_table_opts *o);
/* One adaptive build with the given shares of the tolerance. */
btdf_status tb_facet_pass(const btdf_table_opts *o, double frac_slice, double frac_ti,
                          btdf_table *t, int *budget_hit, size_t *evals);

#endif
