/* SPDX-License-Identifier: MIT */
/* table.h: the table object, its slices and interpolation rule, shared by table.c, build.c
   and the table formats. */
#ifndef BTDF_TABLE_H
#define BTDF_TABLE_H

#include <math.h>
#include <stddef.h>

#include "btdf.h"
#include "core/core.h"
#include "estimate/estimate.h"
#include "model/facet.h"
#include "model/full.h"
#include "model/kernel.h"

typedef struct tslice {
    double ti;
    size_t nr, nc;
    double *rows, *cols, *vals; /* vals[(r * nc + c) * channels + ch] */
    double g;                   /* incident factor V(ti)/cos ti (incident_factor: the
                                   model's), set when the slice is added */
    double *geo; /* BTDF_RULE_CHI facet slices: sin tn (nr), cos tn (nr), cos psi (nc) of the
                    nodes, set when the slice is added; NULL otherwise */
} tslice;

struct btdf_table {
    btdf_table_kind kind;
    btdf_table_rule rule; /* how slices interpolate: rho itself or rho / chi_shape */
    btdf_params p;
    size_t ns, cap;
    tslice *s;
    /* The builder's last check, which btdf_table_estimate returns for the same request
       (the estimate is deterministic); cleared when a slice is added. */
    btdf_report check;
    int check_valid;
    double check_ti0, check_ti1;
    size_t check_angles, check_ppa;
    uint64_t check_seed;
    /* A table holding both parts: the reflection (kind FACET_REFLECTION), owned. */
    struct btdf_table *refl;
    int attached; /* this reflection table is owned by a transmission table */
    size_t build_evals; /* points where the builder evaluated Eq. 25, over all its passes */
    /* Model full: each channel's tally (owned). The slices hold the single scattering
       (smith's, with its rules); evaluation adds the multiply scattered part of the
       tally at the query's own directions (table/full.c). NULL for the other models. */
    btdf_full *ms[BTDF_MAX_CHANNELS];
};

/* 1 for the kinds that hold rho_r (MODEL.md section 8). */
static inline int kind_is_reflection(btdf_table_kind k)
{
    return k == BTDF_TABLE_FACET_REFLECTION;
}

/* Interpolates slice k of t at facet or grid coordinates (x = row coordinate,
   y = col coordinate) for channel ch: rho at the slice's own ti. 0 outside the node range. */
double slice_interp(const btdf_table *t, size_t k, double x, double y, int ch);

/* The slice's reduced value at (x, y): under BTDF_RULE_CHI the bilinear interpolant of
   rho / chi_shape at the nodes (chi_shape of the slice's own ti); under the plain rule
   rho's. slice_interp is this times chi_shape at (x, y). */
double slice_interp_red(const btdf_table *t, size_t k, double x, double y, int ch);

/* The rule's reduction factor for a facet with cos a = ca (between e_i and h) and index
   n: cb (ca + n cb)^2, cb = sqrt(1 - (1 - ca^2)/n^2) the refracted cosine. It is the
   Jacobian chi = n^2 cb / (ca - n cb)^2 times the constant (n^2 - 1)^2 / n^2, since
   ca - n cb = -(n^2 - 1)/(ca + n cb): chi's shape without its (n - 1)^-2 scale, so it
   stays finite at n = 1. 0 where the facet refracts nothing (ca <= 0 or total internal
   reflection). */
double chi_shape(double n, double ca);

/* The factor K a rule divides the nodes by: chi_shape for CHI, the facet's Fresnel
   reflectance Fr(ca) (1 past the critical angle, > 0 for every ca > 0 and n != 1) for
   FRESNEL, 1 for PLAIN; 0 where ca <= 0. */
double rule_factor(btdf_table_rule rule, double n, double ca);

/* The part of the model's shadowing-masking a facet table's rule divides its nodes by
   beside K (docs/tables.md): 1 for xu-sun, whose V(ti) is the incident factor and whose
   V(to) is smooth; for smith (1 + Lambda(ti)) G2, the share of G2 that the incident
   factor G1(ti) = 1/(1 + Lambda(ti)) leaves out. G2 does not factor, and this share has
   a logarithmic singularity at grazing incidence that no blend in ti follows: divided
   out exactly at each node, the reduced values are smooth. model_dir_factor takes the
   two directions (sin, |cos| of each; refl: G2 of reflection), model_node_factor the
   node's facet (tn, psi) at incidence ti for the slices' own index n; 0 where the facet
   sends no light (the node's rho is 0 there). */
double model_dir_factor(const btdf_params *p, int refl, double sti, double cti, double sto,
                        double cto);
double model_node_factor(const btdf_params *p, int refl, double n, double sti, double cti,
                         double stn, double ctn, double cpsi);

/* Sets up s->geo for table t's rule (no-op for the plain rule and grid tables);
   for a model other than xu-sun it also holds the nodes' model_node_factor per channel
   (nr * nc * channels after sin tn, cos tn, cos psi); 0 when out of memory. */
int slice_prepare(const btdf_table *t, tslice *s);

/* The incident factor of the model of p: Eq. 25's V(ti)/cos ti, 1/((1 + Lambda(ti))
   cos ti) for smith (0 at grazing incidence). */
double incident_factor(const btdf_params *p, double ti);

/* The rule's blend of two slice values at weight w in ti, with the incident factors
   g (query), g0, g1 (the two slices): g ((1 - w) v0/g0 + w v1/g1). */
double blend_ti(double v0, double v1, double w, double g, double g0, double g1);

/* "facet", "grid" or "facet-reciprocal", as files name the kinds; parse returns 0
   for an unknown name. */
const char *table_kind_name(btdf_table_kind k);
int table_kind_parse(const char *name, btdf_table_kind *k);

/* Adds slice s to t, taking ownership of its three arrays on success. */
btdf_status table_push_slice(btdf_table *t, tslice *s);

/* rho~ of t for every channel at one query given its sines and cosines (the rule of
   btdf.h); phi_fold is |phi| folded to [0, pi], to the outgoing polar angle. */
void table_eval_sc(const btdf_table *t, double ti, double sti, double cti, double sto,
                   double cto, double cph, double sph, double phi_fold, double to,
                   double *out);

/* Model full (table/full.c). The params of a full table with model smith, for the
   checks and objects that take a btdf_params (btdf_params_check refuses full). */
btdf_params table_single_params(const btdf_params *p);
/* Makes t, built or read with model smith, a table of model full: t->p.model becomes
   full and t (and its reflection, if attached) keeps copies of ms[0..channels). Each
   ms must be of t's index and smoothness: BTDF_EINVAL naming the difference;
   BTDF_ENOMEM. */
btdf_status table_make_full(btdf_table *t, const btdf_full *const *ms, char *msg,
                            size_t msglen);
/* Back to smith's slices alone: frees t's tally (the builder's passes compare the
   table with smith's kernel). */
void table_strip_full(btdf_table *t);
/* Adds the multiply scattered part to out[] for a query of a full table (no-op for
   other models): refl for a reflection table (to is then tr); the angles as
   table_eval_sc takes them, before any swap. */
void table_add_ms(const btdf_table *t, double ti, double cti, double cto, double cph,
                  double *out);
/* The estimate of a full table: against full (smith's kernel plus the same tally), T
   of full in the norm, and the tally's noise floor in r->ms_noise. */
btdf_status table_estimate_full(const btdf_table *t, double ti_min, double ti_max,
                                size_t test_angles, size_t points_per_angle, uint64_t seed,
                                int threads, const double *knots, size_t nk, est_eval_fn fn,
                                btdf_report *r);

/* The tally of channel c of a full table as text, as files keep it: "paths P seed S
   nodes N" and one line per ladder node (full_node_text), each ending in a newline;
   malloc'd, NULL for another model or out of memory. */
char *table_ms_write(const btdf_table *t, int c);
/* A reader's gathering of that text, line by line per channel. Zero it first. */
typedef struct table_ms_text {
    char *text[BTDF_MAX_CHANNELS];
    size_t len[BTDF_MAX_CHANNELS];
} table_ms_text;
btdf_status table_ms_text_add(table_ms_text *m, int c, const char *line, char *msg,
                              size_t msglen);
void table_ms_text_free(table_ms_text *m);
/* A table read (made with table_single_params) whose file says `model`: for full,
   makes it full from m's text (BTDF_EFORMAT naming what is missing or wrong); for
   another model m must be empty. */
btdf_status table_full_from_text(btdf_table *t, btdf_model model, const table_ms_text *m,
                                 char *msg, size_t msglen);

#endif
