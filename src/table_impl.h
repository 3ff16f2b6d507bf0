/* SPDX-License-Identifier: MIT */
/* table_impl.h: the table object and the facet-space geometry shared by build and estimate. */
#ifndef BTDF_TABLE_IMPL_H
#define BTDF_TABLE_IMPL_H

#include <math.h>
#include <stddef.h>

#include "btdf.h"
#include "model_impl.h"
#include "scatfun_impl.h"

typedef struct tslice {
    double ti;
    size_t nr, nc;
    double *rows, *cols, *vals; /* vals[(r * nc + c) * channels + ch] */
    double g;                   /* incident factor V(ti)/cos ti, set when the slice is added */
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
};

/* 1 for the kinds that hold rho_r (MODEL.md section 8). */
static inline int kind_is_reflection(btdf_table_kind k)
{
    return k == BTDF_TABLE_FACET_REFLECTION;
}

/* Refraction of e_i(ti) through the facet of tilt tn and azimuth psi (psi = 0 leans
   towards e_i). On success (1) fills the outgoing geometry and rho; 0 where the
   facet cannot refract e_i into the lower hemisphere, and rho = 0 there. */
typedef struct facet_geo {
    double sin_to, cos_to, cos_phi, sin_phi; /* e_o in MODEL.md's angles */
    double rho;                              /* Eq. 25 at (ti, e_o) */
    double weight;                           /* |cos to| / chi: d(omega_o) = weight d(omega_h) */
} facet_geo;

int facet_eval(double n, double s, double k0, const rho_in *a, double tn_sin, double tn_cos,
               double cpsi, double spsi, facet_geo *g);

/* The mirror direction of e_i = (sin ti, 0, cos ti) on the facet h = (stn cpsi,
   stn spsi, ctn): ca = e_i.h and e_r = 2 ca h - e_i = (rx, ry, rz). 0 when the facet
   faces away from e_i (ca <= 0) or mirrors it into the lower medium (rz <= 0). */
static inline int facet_mirror(const rho_in *a, double stn, double ctn, double cpsi,
                               double spsi, double *ca, double *rx, double *ry, double *rz)
{
    *ca = stn * cpsi * a->sin_ti + ctn * a->cos_ti;
    if (!(*ca > 0.0))
        return 0;
    *rx = 2.0 * *ca * stn * cpsi - a->sin_ti;
    *ry = 2.0 * *ca * stn * spsi;
    *rz = 2.0 * *ca * ctn - a->cos_ti;
    return *rz > 0.0;
}

/* The same for reflection: the facet (tn, psi) mirrors e_i into e_r = 2 (e_i.h) h - e_i;
   g gets e_r (sin_to, cos_to = cos tr > 0), rho_r, and weight = cos tr 4 (e_i.h), so
   that cos tr d(omega_r) = weight d(omega_h). 0 where e_r would leave the upper
   hemisphere (rho_r = 0 there). */
int facet_eval_r(double n, double s, double k0, const rho_in *a, double tn_sin,
                 double tn_cos, double cpsi, double spsi, facet_geo *g);

/* The facet (tn, psi) that mirrors e_i into e_r (h along e_i + e_r) and its
   ca = e_i.h = |e_i + e_r|/2; 0 if none (both grazing). */
int facet_of_r(double sti, double cti, double str, double ctr, double cph, double sph,
               double *tn, double *psi, double *ca);

/* The facet (tn, psi) that refracts e_i into e_o for index n; 0 if none. */
int facet_of(double n, double sti, double cti, double sto, double cto, double cph,
             double sph, double *tn, double *psi);
/* The same, also giving ca = e_i . h of that facet. */
int facet_of_ca(double n, double sti, double cti, double sto, double cto, double cph,
                double sph, double *tn, double *psi, double *ca);

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

/* Sets up s->geo for table t's rule (no-op for the plain rule and grid tables);
   0 when out of memory. */
int slice_prepare(const btdf_table *t, tslice *s);

/* Eq. 25's incident factor V(ti)/cos ti (0 at grazing incidence). */
double incident_factor(const btdf_params *p, double ti);

/* The rule's blend of two slice values at weight w in ti, with the incident factors
   g (query), g0, g1 (the two slices): g ((1 - w) v0/g0 + w v1/g1). */
double blend_ti(double v0, double v1, double w, double g, double g0, double g1);

/* "facet", "grid" or "facet-reciprocal", as files name the kinds; parse returns 0
   for an unknown name. */
const char *table_kind_name(btdf_table_kind k);
int table_kind_parse(const char *name, btdf_table_kind *k);

/* An evaluation under test: rho~ for every channel at incidence ti and outgoing
   direction q = {sin ti, cos ti, sin to, cos to, cos phi, sin phi, |phi| folded to
   [0, pi], to}. */
typedef void (*est_eval_fn)(const void *obj, double ti, const double *q, double *out);

/* The error of fn against Eq. 25 with parameters p (MODEL.md section 6), as
   btdf_table_estimate computes it for tables. */
btdf_status btdf_estimate_fn(const btdf_params *p, double ti_min, double ti_max,
                             size_t test_angles, size_t points_per_angle, uint64_t seed,
                             int threads, est_eval_fn fn, const void *obj, btdf_report *r);

/* The same with knots (their interval midpoints are test angles too). */
btdf_status btdf_estimate_knots(const btdf_params *p, double ti_min, double ti_max,
                                size_t test_angles, size_t points_per_angle, uint64_t seed,
                                int threads, const double *knots, size_t nknots,
                                est_eval_fn fn, const void *obj, albedo_memo *memo,
                                btdf_report *r);

/* A context for one incident angle ti, made from obj before the angle's points and
   passed to the est_eval_fn in obj's place (NULL: out of memory, obj is passed). */
typedef void *(*est_prep_fn)(const void *obj, double ti);
typedef void (*est_done_fn)(void *ctx);

/* One reading's sums at one test angle and channel: the integrals of |difference| and of
   the difference, the largest |difference| and the model's largest value. */
typedef struct est_acc {
    double l1, sgn, dmax, vmax;
} est_acc;

static inline void est_add(est_acc *e, double tab, double rho, double weight)
{
    double d = tab - rho;
    e->l1 += fabs(d) * weight;
    e->sgn += d * weight;
    e->dmax = fmax(e->dmax, fabs(d));
    e->vmax = fmax(e->vmax, rho);
}

/* Channel c's sums a into the angle's errors r, relative to max(T, 0.01) (T: the
   model's T, or R for reflection; MODEL.md section 6), e_max where T >= 0.01; channel 0
   sets r->T and r->T_table. */
void est_fold(btdf_ti_error *r, const est_acc *a, double T, int c);

/* out's errors := the worse of nr (1 or 2) readings rr at one angle: each error's
   larger value, T_table of the larger e_L1 (the first on a tie); out->ti is kept. */
void est_worse(const btdf_ti_error *rr, int nr, btdf_ti_error *out);

/* Options of the estimates below (NULL: all 0, one reading).
   l1_only: the refinement rounds follow e_L1 alone (for a caller that reads no other
     error; the other fields are still filled at the angles tested);
   nread: 2 when fn returns two readings of the same truth per point (out[0..ch) and
     out[ch..2 ch)): both are compared with one evaluation of Eq. 25 and each angle
     reports the worse (each error's larger value, T_table of the larger e_L1);
   stop_above: when > 0 and the first angles (stratified, ends, knot midpoints) already
     hold an e_L1 above it, no refinement rounds (for a caller that only asks whether
     the worst is below it, and where: the answer is already no). */
typedef struct est_opts {
    int l1_only;
    int nread;
    double stop_above;
    /* Screening (l1_only callers): the first angles are measured with screen_ppa
       facet points and a screen_nuni x screen_nuni direction grid, and only those
       whose e_L1 reaches screen_at again with the full sets; 0: no screening. */
    size_t screen_ppa, screen_nuni;
    double screen_at;
} est_opts;

/* btdf_estimate_knots with a per-angle context from prep (freed by done); fn then reads
   q[0..5] only (q[6] and q[7], the angles, are left 0: no atan2 per point). */
btdf_status btdf_estimate_knots_prep(const btdf_params *p, double ti_min, double ti_max,
                                     size_t test_angles, size_t points_per_angle,
                                     uint64_t seed, int threads, const double *knots,
                                     size_t nknots, est_eval_fn fn, est_prep_fn prep,
                                     est_done_fn done, const void *obj, const est_opts *opt,
                                     albedo_memo *memo, btdf_report *r);

/* A whole per-angle estimate: fills res (zeroed, res->ti set) at incidence ti with p
   the truth's parameters, from the generator state rng (fixed by ti and the seed),
   with about points_per_angle lobe-following points and an nuni x nuni grid of
   directions; res->T is the norm's quantity (T, or R for reflection). Returns the
   points used. */
typedef size_t (*est_angle_fn)(const void *obj, const btdf_params *p, double ti, uint64_t rng,
                               size_t points_per_angle, size_t nuni, btdf_ti_error *res);

/* The angle choice of btdf_estimate_knots (stratified, knot midpoints, refinement
   rounds) around a per-angle estimate of the caller's (opt->nread is fn's business:
   it fills res with the worse of its readings). */
btdf_status btdf_estimate_angles(const btdf_params *p, double ti_min, double ti_max,
                                 size_t test_angles, size_t points_per_angle, uint64_t seed,
                                 int threads, const double *knots, size_t nknots,
                                 est_angle_fn fn, const void *obj, const est_opts *opt,
                                 albedo_memo *memo, btdf_report *r);
/* The same for an evaluation of the reflection: against rho_r (MODEL.md section 8)
   over the upper hemisphere, relative to max(R(ti), 0.01); q holds tr for to. */
btdf_status btdf_estimate_fn_r(const btdf_params *p, double ti_min, double ti_max,
                               size_t test_angles, size_t points_per_angle, uint64_t seed,
                               int threads, est_eval_fn fn, const void *obj, btdf_report *r);

/* Monotonic wall clock in seconds. */
double btdf_now(void);

/* Number of worker threads for a request (0 = all cores), at least 1. */
int btdf_thread_count(int requested);

/* Runs fn(arg, i) for i in [0, count) on up to `threads` threads. Which thread runs
   which i does not change any result: each i writes only its own output. */
void btdf_parallel_for(int threads, size_t count, void (*fn)(void *arg, size_t i), void *arg);

/* The same with a workspace per thread from ws_new (NULL: none), freed by ws_free.
   Returns 0, or -1 when some items were not run (no mutex, or no workspace could be
   made). */
int btdf_parallel_for_ws(int threads, size_t count, void (*fn)(void *ctx, void *ws, size_t i),
                         void *ctx, void *(*ws_new)(void *ctx), void (*ws_free)(void *ws));

#endif
