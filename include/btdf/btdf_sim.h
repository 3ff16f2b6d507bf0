/* SPDX-License-Identifier: MIT */
/* btdf_sim.h: a Monte Carlo goniophotometer on generated Gaussian rough surfaces,
   the ground truth Eq. 25 is checked against (Xu & Sun 2008, Sec. 4). */
#ifndef BTDF_SIM_H
#define BTDF_SIM_H

#include <stddef.h>
#include <stdint.h>

#include "btdf.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Conventions (those of btdf.h, plus)
 * ------------------------------------
 * Surface: a periodic square tile of a Gaussian random height field z = h(x, y) with
 *   mean 0 and autocorrelation C(r) = sigma^2 exp(-r^2 / tau^2), sigma = 1 and
 *   tau = s (so s = tau / sigma, and the facet slopes are Beckmann with RMS slope
 *   2/s, the D of Eq. 25). It is made by filtering white noise with FFTW and sampled
 *   on an N x N grid of spacing dx = tau / cells_per_tau, N = tile_tau *
 *   cells_per_tau (a power of two). Representation: two planar triangles per grid
 *   cell, split along the diagonal from (i, j) to (i+1, j+1); the surface is
 *   continuous and every intersection is exact (up to rounding).
 *
 * Light: unpolarised, from the upper medium (z > h) towards -z, at polar angle ti,
 *   landing uniformly over the tile. At every hit, the Fresnel reflectance of the
 *   local facet normal picks reflection or refraction (total internal reflection when
 *   there is no refracted ray), so every ray ends, with weight one, in R (leaving
 *   upward above the highest point) or T (leaving downward below the lowest). Orders
 *   count the surface hits of a ray: 1, 2, and 3 or more.
 *
 * Index: n = (lower index) / (upper index), as in btdf.h; n < 1 is light from the
 *   dense side.
 *
 * Errors: Monte Carlo standard errors are batch means: the rays are cut into batches,
 *   one per surface realisation (32 up to 3.2e6 rays, then one per 1e5 rays up to 128;
 *   every angle and channel of batch b sees realisation b, with rays from its own
 *   stream seeded from the seed, the angle and b), and the error of a mean is the
 *   spread of the batch means over sqrt(batches), which holds the spread between
 *   surfaces. Batches are summed in batch order, so the same options give
 *   the same bytes whatever the thread count.
 *
 * Outgoing distribution: optional histograms over (theta, |phi|) per hemisphere, as
 *   the fraction of the incident flux per bin; divided by a bin's solid angle this is
 *   rho |cos t| (btdf_sim_bin_solid_angle). phi is folded into [0, pi] (the surface is
 *   isotropic); phi = pi is the forward plane.
 */

/* Accepted ranges (inclusive). */
#define BTDF_SIM_RAYS_MAX 100000000000ull /* 1e11 per angle and channel */
#define BTDF_SIM_CELLS_PER_TAU_MIN 2
#define BTDF_SIM_CELLS_PER_TAU_MAX 64
#define BTDF_SIM_TILE_TAU_MIN 4
#define BTDF_SIM_TILE_TAU_MAX 256
#define BTDF_SIM_N_MAX 4096 /* grid points per side */
#define BTDF_SIM_ORDERS 3   /* order 1, 2, 3 or more */

typedef struct btdf_sim_opts {
    int channels;                  /* 1, or 3 for R, G, B */
    double ior[BTDF_MAX_CHANNELS]; /* n per channel */
    double smoothness;             /* s = tau / sigma */
    size_t n_theta;                /* incident angles */
    const double *theta_i;         /* radians, [0, pi/2) */
    uint64_t rays;                 /* rays per incident angle and channel */
    uint64_t seed;
    int threads;          /* 0: as many as the machine has */
    int cells_per_tau;    /* grid spacing dx = tau / this; default 16 */
    int tile_tau;         /* tile side in units of tau; default 16 */
    uint64_t batch_rays;  /* rays per batch; 0: chosen from rays (at least 32 batches) */
    int accel;            /* 0: plain grid DDA (default); 1: min/max hierarchy, same hits */
    /* 0: the 2D surface (default). 1: the paper's setting (Sec. 4), a 1D profile
       z = h(x) with C(x) = sigma^2 exp(-x^2 / tau^2) (slopes of RMS sqrt(2)/s) and
       rays in its plane of incidence: every outgoing direction lies in that plane
       (|phi| = 0 backward or pi forward), R and T are those of the profile. */
    int profile;
    int theta_bins;       /* histogram bins in theta per hemisphere; 0: no histogram */
    int phi_bins;         /* bins of |phi| over [0, pi]; used when theta_bins > 0 */
    size_t max_memory;    /* bytes the surfaces and tallies may take; 0: no limit */
    /* Trace only batches [batch_first, batch_end) (a shard; btdf_sim_batch_count
       gives how many there are); batch_end 0: all of them. */
    uint64_t batch_first, batch_end;
    /* Called after each finished batch with the rays done so far, the total, and the
       standard error of T of the angle in progress (NaN until it is known). From any
       thread, one call at a time; it must not call back into the simulator. */
    void (*progress)(void *ctx, uint64_t done, uint64_t total, double t_se);
    void *progress_ctx;
    /* A pane (issue 33) instead of one interface: 0 (default) the interface above; 1
       a slab of index ratio n = (pane index) / (outside index) between two faces a
       thickness apart, air (index 1 relative) on both sides. The front face is the
       rough surface of s above (or flat with front_flat); the back face is flat
       (back_smoothness 0) or rough with its own s, an independent realisation. Light
       arrives on the front (from_back 0) or on the back. Inside, a path between the
       faces has length thickness_mm / |cos theta| and survives it with probability
       exp(-absorption_per_mm * length) (Beer-Lambert); tallies: R on the lit side, T
       on the other, A absorbed; orders count the hits on both faces. See
       docs/simulation.md for the geometry (a fresh lateral offset at every face). */
    int pane;
    int front_flat;            /* pane only: a flat front face (the slab of the closed form) */
    double back_smoothness;    /* pane only: 0 flat, else s of the back face */
    double thickness_mm;       /* pane only: > 0 */
    double absorption_per_mm;  /* pane only: >= 0 */
    int from_back;             /* pane only: light arrives on the back face */
} btdf_sim_opts;

/* Defaults: n = 1.5, s = 3, one angle (none set: theta_i must be given), 1e6 rays,
   seed 1, cells_per_tau 16, tile_tau 16, plain DDA, no histogram. */
BTDF_API void btdf_sim_opts_default(btdf_sim_opts *o);

/* BTDF_OK, or BTDF_EINVAL naming the value: NaN/inf, channels not 1 or 3, n outside
   [BTDF_IOR_MIN, BTDF_IOR_MAX] or within BTDF_IOR_ONE_EPS of 1, s outside
   [BTDF_S_MIN, BTDF_S_MAX], no angle or one outside [0, pi/2), rays 0 or above
   BTDF_SIM_RAYS_MAX, grid sizes out of range, N not a power of two or above
   BTDF_SIM_N_MAX, bins out of [0, 3600]; BTDF_EBUDGET when the tiles and tallies do
   not fit max_memory (the message gives what they need). */
BTDF_API btdf_status btdf_sim_opts_check(const btdf_sim_opts *o, char *msg, size_t msglen);

/* A mean and its standard error. */
typedef struct btdf_sim_est {
    double mean, se;
} btdf_sim_est;

/* What one incident angle and channel gave. */
typedef struct btdf_sim_tally {
    double theta_i;
    int channel;
    double ior;
    btdf_sim_est R, T;                       /* all orders */
    btdf_sim_est R_order[BTDF_SIM_ORDERS];   /* order 1, 2, 3+ */
    btdf_sim_est T_order[BTDF_SIM_ORDERS];
    btdf_sim_est mean_hits;                  /* surface hits per ray */
    btdf_sim_est A;                          /* absorbed (a pane; 0 otherwise) */
    uint64_t rays;
    uint64_t lost;       /* rays stopped by the path limit (counted in neither R nor T) */
    uint64_t batches;
    /* Histograms (NULL without): [theta_bin * phi_bins + phi_bin], theta_bin 0 at the
       mean normal of its hemisphere (t = 0 for R, t = pi for T). */
    btdf_sim_est *hist_T, *hist_T1; /* transmitted, all orders and order 1 */
    btdf_sim_est *hist_R, *hist_R1;
} btdf_sim_tally;

/* The surfaces' realised statistics (sigma = 1), averaged over the first 32
   realisations (one per batch). */
typedef struct btdf_sim_surface {
    int n;                 /* grid points per side */
    double dx;             /* spacing */
    double tile;           /* tile side */
    int realisations;      /* measured */
    double rms_height;     /* target 1 */
    double rms_slope;      /* of the triangles, target 2/s */
    double corr_length;    /* where the realised autocorrelation falls to 1/e, target s */
    size_t tile_bytes;     /* memory of one tile with its hierarchy */
} btdf_sim_surface;

typedef struct btdf_sim_result {
    size_t count;          /* n_theta * channels */
    btdf_sim_tally *tally; /* [channel * n_theta + k] */
    btdf_sim_surface surface;
    int theta_bins, phi_bins;
    double seconds;        /* wall time of the tracing */
    uint64_t rays_traced;  /* over every angle and channel */
    uint64_t hits_traced;
    /* The raw integers of batches [batch_first, batch_end) of batches_total, for
       btdf_sim_merge: raw_counts[(case * (end - first) + b - first) * BTDF_SIM_RAW_Q +
       q], q = R orders 1, 2, 3+, T orders 1, 2, 3+, lost, hits; raw_hist (NULL without
       histograms) [((case * 4 + h) * bins + bin) * 3 + {sum c, sum c^2, sum c n}] over
       the batches, h = T, T1, R, R1; raw_stats[(b - first) * 3 + {rms height, rms
       slope, correlation length}] of the realisations b < 32 (zero past them). */
    uint64_t batches_total, batch_first, batch_end;
    uint64_t *raw_counts;
    uint64_t *raw_hist;
    double *raw_stats;
    double smoothness; /* s of the run (for btdf_sim_compare) */
    int profile;       /* the run's opts.profile */
    int pane;          /* the run's opts.pane */
} btdf_sim_result;

#define BTDF_SIM_RAW_Q 8
#define BTDF_SIM_STATS_REALISATIONS 32

/* Batches the options cut each angle and channel into (the realisations). */
BTDF_API uint64_t btdf_sim_batch_count(const btdf_sim_opts *o);

/* The result of all batches from parts that together hold each batch of o once (runs
   of o with batch ranges, or results rebuilt from their raw integers): the same
   numbers, to the bit, as one run of o; seconds is the parts' sum. BTDF_EINVAL naming
   a batch missing or held twice, or a part of other options. */
BTDF_API btdf_status btdf_sim_merge(const btdf_sim_opts *o, const btdf_sim_result *const *parts,
                                    size_t nparts, btdf_sim_result **out, char *msg,
                                    size_t msglen);

/* Runs the simulation. BTDF_EINVAL/BTDF_EBUDGET as btdf_sim_opts_check, BTDF_ENOMEM. */
BTDF_API btdf_status btdf_sim_run(const btdf_sim_opts *o, btdf_sim_result **out, char *msg,
                                  size_t msglen);

BTDF_API void btdf_sim_result_free(btdf_sim_result *r);

/* Solid angle of histogram bin (theta_bin, phi_bin), both halves of |phi| counted. */
BTDF_API double btdf_sim_bin_solid_angle(int theta_bins, int phi_bins, int theta_bin,
                                         int phi_bin);

/*
 * Comparison with a model (MODEL.md section 6, the simulation taken as the truth).
 * For case k of r and one part (transmission or reflection) of one tally (all orders,
 * or one hit only), with P_i the simulated fraction of the incident flux in bin i,
 * se_i its standard error, M_i the model's flux in the same bin (its rho |cos| over
 * the bin by quadrature) and X the tally's total (T, T of one hit, R or R of one hit):
 *   e_T  = |X_model - X| / max(X, 0.01), X_model from btdf_transmittance or
 *          btdf_reflectance of the model;
 *   e_L1 = sum_i |P_i - M_i| / max(X, 0.01) (needs histograms; the binned form, a
 *          lower bound of the integral over directions: detail inside a bin is lost);
 *   floors: what each would be from the Monte Carlo error alone if the model were the
 *          truth: E|N(0, se)| = sqrt(2/pi) se, so e_T_floor = sqrt(2/pi) se(X) /
 *          max(X, 0.01) and e_L1_floor = sum_i f_i / max(X, 0.01), f_i the larger of
 *          sqrt(2/pi) se_i and the mean absolute deviation of a Poisson count of mean
 *          M_i rays (over rays; this covers bins with few or no paths), and
 *          e_L1_floor_sd the spread of e_L1 about it from the same terms (a few bins
 *          holding a narrow lobe make it wide);
 *   chi2 = sum_i (P_i - M_i)^2 / se_i^2 over the dof bins where the model expects at
 *          least 50 paths (se_i replaced by the binomial sqrt(M_i (1 - M_i) / rays)
 *          where no batch had a path), the test of "within the noise": about dof
 *          (B - 1) / (B - 3) for B batches when the model is right (se_i is itself
 *          estimated).
 * A model within the noise has e_T, e_L1 near their floors and chi2 near dof; a
 * model that departs has them many floors above.
 */
typedef enum { BTDF_SIM_TRANSMISSION = 0, BTDF_SIM_REFLECTION = 1 } btdf_sim_part;

typedef struct btdf_sim_cmp {
    double total, total_se;   /* X and its standard error */
    double model_total;       /* the model's X */
    double model_in_bins;     /* sum of M_i: model_total to the quadrature's error */
    double e_T, e_T_floor;
    double e_L1, e_L1_floor;  /* 0 without histograms */
    double e_L1_floor_sd;     /* the spread of e_L1 about its floor from the noise alone */
    double chi2;
    int dof;                  /* 0 without histograms */
} btdf_sim_cmp;

/* The comparison above of case k of r, part `part`, all orders (one_hit 0) or one hit
   (1), against model m (BTDF_MODEL_XU_SUN with k0, or BTDF_MODEL_SMITH) at the run's
   smoothness and the case's n. BTDF_EINVAL naming a bad case, part or model, or a
   profile or pane run (neither has a BTDF of one 2D interface to compare with). */
BTDF_API btdf_status btdf_sim_compare(const btdf_sim_result *r, size_t k, btdf_sim_part part,
                                      int one_hit, btdf_model m, double k0, btdf_sim_cmp *out,
                                      char *msg, size_t msglen);

/* The model's flux in every histogram bin of case k (the M_i above), into
   out[theta_bins * phi_bins]: divided by btdf_sim_bin_solid_angle it is the bin's mean
   of rho |cos|, the number to set beside the simulated one. Errors as
   btdf_sim_compare. */
BTDF_API btdf_status btdf_sim_model_bins(const btdf_sim_result *r, size_t k, btdf_sim_part part,
                                         btdf_model m, double k0, double *out, char *msg,
                                         size_t msglen);

#ifdef __cplusplus
}
#endif

#endif
