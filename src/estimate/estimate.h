/* SPDX-License-Identifier: MIT */
/* estimate.h: the error of an evaluation against Eq. 25 (MODEL.md section 6) at points it
   was not built on, for tables, .bsdf files and Radiance trees alike. */
#ifndef BTDF_ESTIMATE_H
#define BTDF_ESTIMATE_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "btdf.h"

/* T(ti) or R(ti) per channel (btdf_transmittance / btdf_reflectance), remembered by
   the parameters and the exact angle, so the builder's repeated measurements of a file
   (the same knot midpoints each time) and the file's reports compute each once.
   Thread-safe; a value is the same whether it was remembered or computed. */
typedef struct albedo_memo albedo_memo;
albedo_memo *albedo_memo_new(void);
void albedo_memo_free(albedo_memo *m);
/* out[0..p->channels-1]; m may be NULL (computes). Returns btdf_transmittance's or
   btdf_reflectance's status. */
btdf_status albedo_memo_get(albedo_memo *m, const btdf_params *p, int refl, double ti,
                            double *out);

/* An evaluation under test: rho~ for every channel at incidence ti and outgoing
   direction q = {sin ti, cos ti, sin to, cos to, cos phi, sin phi, |phi| folded to
   [0, pi], to}. */
typedef void (*est_eval_fn)(const void *obj, double ti, const double *q, double *out);

/* The error of fn against Eq. 25 with parameters p (MODEL.md section 6), as
   btdf_table_estimate computes it for tables. */
btdf_status est_fn(const btdf_params *p, double ti_min, double ti_max,
                             size_t test_angles, size_t points_per_angle, uint64_t seed,
                             int threads, est_eval_fn fn, const void *obj, btdf_report *r);

/* The same with knots (their interval midpoints are test angles too). */
btdf_status est_knots(const btdf_params *p, double ti_min, double ti_max,
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
    /* Model full: each channel's tally; the truth is then smith's kernel plus the
       tally's multiply scattered part at the same directions, and the norm T (or R) is
       full's, smith's plus the tally's energy. NULL for the other models. */
    btdf_full *const *full;
} est_opts;

/* est_knots with a per-angle context from prep (freed by done); fn then reads
   q[0..5] only (q[6] and q[7], the angles, are left 0: no atan2 per point). */
btdf_status est_knots_prep(const btdf_params *p, double ti_min, double ti_max,
                                     size_t test_angles, size_t points_per_angle,
                                     uint64_t seed, int threads, const double *knots,
                                     size_t nknots, est_eval_fn fn, est_prep_fn prep,
                                     est_done_fn done, const void *obj, const est_opts *opt,
                                     albedo_memo *memo, btdf_report *r);

/* est_knots_prep for the transmission (refl = 0) or the reflection (refl = 1,
   as est_fn_r: q holds tr for to). */
btdf_status est_knots_prep_part(const btdf_params *p, int refl, double ti_min, double ti_max,
                                size_t test_angles, size_t points_per_angle, uint64_t seed,
                                int threads, const double *knots, size_t nknots,
                                est_eval_fn fn, est_prep_fn prep, est_done_fn done,
                                const void *obj, const est_opts *opt, albedo_memo *memo,
                                btdf_report *r);
/* The same for an evaluation of the reflection: against rho_r (MODEL.md section 8)
   over the upper hemisphere, relative to max(R(ti), 0.01); q holds tr for to. */
btdf_status est_fn_r(const btdf_params *p, double ti_min, double ti_max,
                               size_t test_angles, size_t points_per_angle, uint64_t seed,
                               int threads, est_eval_fn fn, const void *obj, btdf_report *r);

/* est_knots for the transmission (refl = 0) or the reflection (refl = 1,
   as est_fn_r), without a memo. */
btdf_status est_knots_part(const btdf_params *p, int refl, double ti_min,
                                     double ti_max, size_t test_angles,
                                     size_t points_per_angle, uint64_t seed, int threads,
                                     const double *knots, size_t nknots, est_eval_fn fn,
                                     const void *obj, btdf_report *r);

/* est_knots_part with options (NULL: as est_knots_part). */
btdf_status est_knots_part_opt(const btdf_params *p, int refl, double ti_min,
                                         double ti_max, size_t test_angles,
                                         size_t points_per_angle, uint64_t seed, int threads,
                                         const double *knots, size_t nknots, est_eval_fn fn,
                                         const void *obj, const est_opts *opt, btdf_report *r);

#endif
