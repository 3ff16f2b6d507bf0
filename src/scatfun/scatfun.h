/* SPDX-License-Identifier: MIT */
/* scatfun.h: the in-memory SCATFUN v1 file shared by the builder (build*.c), the
   object (object.c), the readings (lookup.c, report.c) and the byte layout
   (formats/bsdf.c). */
#ifndef BTDF_SF_OBJECT_H
#define BTDF_SF_OBJECT_H

#include <stddef.h>
#include <stdint.h>

#include "btdf.h"
#include "btdf_scatfun.h"
#include "estimate/estimate.h"

/* Rec. 709 luminance weights used by pbrt-v3 and layerlab, and pbrt's inverse for G. */
#define LUM_R 0.212671
#define LUM_G 0.715160
#define LUM_B 0.072169
#define INV_GY 1.39829
#define INV_GB 0.100913
#define INV_GR 0.297375
/* The floor MODEL.md section 6 puts under the transmittance in relative errors. */
#define T_FLOOR 0.01
/* A series longer than this cannot come out of a build; readers refuse more so a
   scratch buffer sized by mMax stays small. */
#define MAX_ORDER_READ (1u << 20)
/* Coefficient budget of a build (floats): 2^27 floats is a 512 MiB file. */
#define MAX_COEFFS_BUILD ((size_t)1 << 27)
/* The outermost elevation nodes: the largest float below 1 (1 - 2^-24), not 1 itself.
   pbrt-v3's Sample_f divides sin^2 of the sampled direction by sin^2 of the view; with
   a view exactly on the normal (cos = 1 in float, any view within 0.014 deg) and a
   sampled cosine of exactly +-1, that is 0/0 and the path tracer aborts on a NaN. With
   the nodes ending below 1, a renderer never samples +-1 (a sampled cosine lies between
   nodes) and a view with cos = +-1 lies outside the nodes, where the renderer returns
   no sample (pdf 0) instead of NaN. docs/scatfun.md, "Views on the normal". */
#define POLE_NODE 0.999999940395355224609375
/* The highest incident angle a report of smith's file tests, 1e-5 rad (5.7e-4 deg)
   short of grazing (xu-sun's, whose rho vanishes there, test 90 deg itself), and the
   floor below which the builder splits no elevation interval, |mu| = 1e-6, a tenth of
   that angle's cosine. At 90 deg exactly the light lies in the surface: a reader
   returns 0 where that cosine is the fast index (f = stored / |mu_f|, pbrt-v3
   included), and double's cos(pi/2) is 6.1e-17, not 0, so "90 deg" tested a direction
   6e-17 rad above the horizon, where smith's T, which falls like 1/ln(1/mu), is still
   0.0876 (n = 1.5, s = 3) and its R 0.162. Following that took the builder's nodes to
   |mu| = 1.4e-12 with 16385 harmonics per grazing pair, a 515 MB file. The band left
   out holds light at cos ti < 1e-5; docs/scatfun.md, "Files of smith: the grazing
   band", gives the file's values there. */
#define SF_TI_TOP (M_PI / 2 - 1e-5)
#define SF_MU_FLOOR 1e-6

struct btdf_scatfun {
    uint32_t n, ncoeffs, mmax, channels;
    float eta, alpha[2];
    float *nodes;      /* n */
    double *xd;        /* the nodes as doubles, for the spline weights */
    uint32_t *xcell;   /* nxcell + 1 entries: the largest i with xd[i] <= the cell's
                          lower edge, cells of equal width over [xd[0], xd[n-1]];
                          NULL when the nodes span no width (binary search then) */
    uint32_t nxcell;
    double xcell_scale; /* cells per unit of mu */
    float *cdf;        /* n * n */
    uint32_t *offsets; /* 2 * n * n: offset, length */
    float *coeffs;     /* ncoeffs */
    char *meta;        /* metadata bytes read from a file, or NULL */
    size_t metalen;
    int built;         /* 1 when made by btdf_scatfun_build: params and tolerance valid */
    btdf_params params;
    double tolerance, seconds_build;
    int sides;         /* btdf_side mask of the blocks present */
    albedo_memo *memo; /* T and R of the reports' test angles (NULL: computed each time) */
    /* model full, a built file: the tallies its multiply scattered part came from, per
       index ([0] n, the blocks lit from above; [1] 1/n) and channel, owned; its reports
       are measured against smith plus these. NULL otherwise (a file read back does not
       keep them: formats/bsdf.c). */
    btdf_full *ms[2][3];
};

/* build.c: btdf_params_check for a file's parameters: model full is checked as its
   single scattering, smith (its tally is the builder's). */
btdf_status sf_check_params(const btdf_params *p, char *msg, size_t msglen);

/* lookup.c: btdf_scatfun_eval_side from cosines: ci = cos ti and co = |cos to| in
   [0, 1], cpd = cos phi_d = -cos phi in [-1, 1]; side and mode checked by the caller. */
btdf_status sf_eval_side_cos(const btdf_scatfun *f, btdf_side side, btdf_scatfun_mode mode,
                             double ci, double co, double cpd, double *out);

/* lookup.c: a reading of one block at one light angle (the reports' reading). */
typedef struct sf_fixed_read sf_fixed_read;

/* The reader of (f, side, mode) at light cosine ci in [0, 1]; NULL when out of memory. */
sf_fixed_read *sf_fixed_new(const btdf_scatfun *f, btdf_side side, btdf_scatfun_mode mode,
                            double ci);

/* Frees r (NULL: nothing). */
void sf_fixed_free(sf_fixed_read *r);

/* sf_eval_side_cos of each of the nr (1 or 2) readings r[] at view cosine co and
   cpd = cos phi_d, the channels of reading i at out + i channels. */
void sf_fixed_eval_n(const sf_fixed_read *const *r, int nr, double co, double cpd,
                     double *out);

/* report.c: btdf_scatfun_report's work without its checks and summary fields, T and R taken from
   memo (NULL: computed); fills r's errors and per-angle rows. opt (NULL: none) as
   est_knots_prep's, but for nread, which the reading sets. */
btdf_status sf_report_mis(const btdf_scatfun *f, const btdf_params *p, btdf_side side,
                               size_t angles, size_t ppa, uint64_t seed, int threads,
                               const struct est_opts *opt, albedo_memo *memo,
                               btdf_report *r);

/* One reading (mode, both = 0) or both at once (both = 1, mode DIRECT) of block side of
   f, as the reports make them, with T and R computed (no memo); for tests. */
btdf_status sf_report_reading(const btdf_scatfun *f, const btdf_params *p,
                                   btdf_side side, btdf_scatfun_mode mode, int both,
                                   size_t angles, size_t ppa, uint64_t seed, int threads,
                                   btdf_report *r);

/* The builder: 1 when Eq. 25 is 0 at every azimuth for light at cosine mu_s and the view at cosine
   -mu_f (a transmission pair of the builder, both in [0, 1]) for each of the channels'
   indices ior[] and smoothness s: no facet refracts one into the other, or the slope
   it would need underflows the exponential. 0 when some azimuth may reach, including
   every case within rounding of the edge (the builder then samples). */
int sf_unreachable(const double *ior, int channels, double s, double mu_s,
                        double mu_f);

/* A file of n nodes, ncoeffs coefficients and channels channels, with its arrays
   allocated but not filled, and metalen + 1 bytes of metadata when with_meta; NULL when
   out of memory. */
btdf_scatfun *sf_alloc(uint32_t n, uint32_t ncoeffs, uint32_t mmax, uint32_t channels,
                       int with_meta, size_t metalen);

/* Fills f->xd and f->xcell from f->nodes; 0 on success, -1 when out of memory. */
int sf_index(btdf_scatfun *f);

#endif /* BTDF_SF_OBJECT_H */
