/* SPDX-License-Identifier: MIT */
/* btdf_scatfun.h: SCATFUN v1 Fourier-series files (.bsdf) for pbrt-v3 "fourier" and Mitsuba 0.5 "tabulated". */
#ifndef BTDF_SCATFUN_H
#define BTDF_SCATFUN_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "btdf.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * A SCATFUN v1 file holds, for every pair of elevation nodes (slow mu_s = pbrt-v3's
 * wo.z, fast mu_f = -wi.z), the cosine series in phi_d of rho * |mu_f|, where
 * phi_d = pi - phi (phi_d = 0 is the forward plane for transmission and the specular
 * plane for reflection) and rho is the radiance-form BSDF for light arriving from the
 * slow direction and leaving towards the fast one. Four blocks (btdf_scatfun_block):
 *   T_ENTER  mu_s > 0, mu_f > 0: transmission entering, Eq. 25 with index n,
 *       ti = acos(mu_s), to = pi - acos(mu_f);
 *   T_LEAVE  mu_s < 0, mu_f < 0: transmission leaving, Eq. 25 with index 1/n, mirrored:
 *       ti = acos(|mu_s|), to = pi - acos(|mu_f|);
 *   R_TOP    mu_s > 0, mu_f < 0: reflection back into the upper medium, rho_r
 *       (MODEL.md 8) with index n, ti = acos(mu_s), tr = acos(|mu_f|);
 *   R_BOTTOM mu_s < 0, mu_f > 0: reflection inside the dense medium, rho_r with index
 *       1/n (total internal reflection included), ti = acos(|mu_s|), tr = acos(mu_f).
 * Blocks not built are empty. The header eta is n (ior[1], green, for three
 * channels). Three-channel files store the series of Y, R and B, with the transmission
 * blocks of channel c scaled so that pbrt-v3's radiance-mode factor e^2 (one eta for
 * all channels) gives each channel its own value: T_ENTER by (n_G/n_c)^2, T_LEAVE by
 * (n_c/n_G)^2 (BTDF_SCATFUN_ADJOINT reads them right; DIRECT reads them as stored).
 * docs/scatfun.md describes the file, the node placement and the measured sizes.
 *
 * Threads: a btdf_scatfun is immutable once built or read; it may be evaluated,
 * reported on and written from many threads at once. Freeing is not concurrent
 * with other uses.
 * Ownership: objects returned through **out belong to the caller, who frees them
 * with btdf_scatfun_free (NULL is a no-op). Out-parameters are untouched on error
 * unless said otherwise. Messages go to msg (msglen bytes, may be NULL).
 */
typedef struct btdf_scatfun btdf_scatfun;

/* The blocks of a file, as a mask. The values 1 and 2 are BTDF_SIDE_ENTER and
   BTDF_SIDE_LEAVE (a btdf_side of 1..3 asks for transmission only, as before). */
typedef enum {
    BTDF_SCATFUN_T_ENTER = 1,  /* transmission, light from above (index n) */
    BTDF_SCATFUN_T_LEAVE = 2,  /* transmission, light from below (index 1/n) */
    BTDF_SCATFUN_R_TOP = 4,    /* reflection above the surface (index n) */
    BTDF_SCATFUN_R_BOTTOM = 8, /* reflection below, inside the dense medium (1/n) */
    BTDF_SCATFUN_TRANSMISSION = 3,
    BTDF_SCATFUN_REFLECTION = 12,
    BTDF_SCATFUN_ALL = 15      /* a full dielectric interface */
} btdf_scatfun_block;

/* How a value is read back from a file, matching pbrt-v3's two transport modes. */
typedef enum {
    /* The block whose slow index is the light's side, no eta factor: Eq. 25 directly
       (pbrt-v3 in importance mode with the light direction as wo). */
    BTDF_SCATFUN_DIRECT = 0,
    /* The block whose slow index is the camera's side, times pbrt-v3's radiance-mode
       factor e^2: what pbrt-v3 renders; equal to DIRECT by reciprocity. */
    BTDF_SCATFUN_ADJOINT = 1
} btdf_scatfun_mode;

/* Largest half-node count and series length a build may use (its budget). */
#define BTDF_SCATFUN_MAX_HALF_NODES 1024
#define BTDF_SCATFUN_MAX_PHI 16384

/* Builds the nodes and coefficients from Eq. 25 and rho_r (not from a table) for the
   blocks asked: `side` is a btdf_scatfun_block mask, 1..15 (BTDF_SCATFUN_ALL for a full
   interface; BTDF_SIDE_BOTH = 3 for transmission only), refining the elevation nodes and each
   pair's series until midpoint checks against Eq. 25 pass and then an internal
   btdf_scatfun_report (24 angles x 8192 points, its own fixed seed) finds e_L1 (MODEL.md 6)
   at most `tolerance` on every block built (btdf_scatfun_report). threads: 0 = all cores, 1 = none;
   the result is byte-identical for any thread count.
   BTDF_OK when the tolerance was met; BTDF_EBUDGET when the node or series budget
   stopped refinement first: *out then still holds the best file reached and msg
   says the error reached; or, with *out NULL, when the lobe is too narrow for the
   format's node budget to follow at all (btdf_scatfun_build_limits). Errors: BTDF_EINVAL (parameters, tolerance outside
   [1e-6, 0.5], side not 1..15), BTDF_ENOMEM, BTDF_EOVERFLOW. */
BTDF_API btdf_status btdf_scatfun_build(const btdf_params *p, double tolerance,
                                        btdf_side side, int threads, btdf_scatfun **out,
                                        char *msg, size_t msglen);

/* btdf_scatfun_build_limits (below) with a progress callback (btdf.h,
   btdf_progress_fn): stages "elevation nodes" (nodes checked, intervals to split) and
   "series (tighter)"; progress may be NULL. */
BTDF_API btdf_status btdf_scatfun_build_progress(const btdf_params *p, double tolerance,
                                                 btdf_side side, int threads, size_t max_coeffs,
                                                 size_t max_bytes, btdf_progress_fn progress,
                                                 void *user, btdf_scatfun **out, char *msg,
                                                 size_t msglen);

/* btdf_scatfun_build with budgets: max_coeffs caps the stored coefficients (0 or more
   than 2^27: 2^27), max_bytes the builder's working memory in series and pair
   records (0: no cap; the file's float copy and per-thread scratch come on top).
   Reaching one returns BTDF_EBUDGET with the best file reached within the budgets
   (never a state that passed one; the build stops before a pass whose growth in pairs
   alone would pass one), as above; *out is left NULL when even the first pass passes
   one. A request whose need (btdf_scatfun_predict) exceeds the node budget, max_coeffs
   or max_bytes stops before any work: BTDF_EBUDGET, *out left NULL, the numbers in msg
   (btdf_scatfun_build does the same). msg of a budget reached ends with "; its own
   estimate e_L1 X > tolerance T", the builder's own measurement (not the report's). */
BTDF_API btdf_status btdf_scatfun_build_limits(const btdf_params *p, double tolerance,
                                               btdf_side side, int threads, size_t max_coeffs,
                                               size_t max_bytes, btdf_scatfun **out,
                                               char *msg, size_t msglen);

/* What a request needs at least, before any work (btdf_scatfun_predict): the half
   nodes the narrowest transmitted lobe asks of the spline (its spread from the facet
   slopes of RMS 2/s refracted by Snell's law, the node spacing from a Catmull-Rom
   spline's L1 error on a Gaussian of that spread at `tolerance`), and the pairs,
   coefficients, file bytes and builder memory those nodes imply. Lower bounds: the
   build needs more where reflection, the pole or grazing angles ask more (docs/scatfun.md,
   "What a request needs"). */
typedef struct btdf_scatfun_need {
    size_t half_nodes;  /* elevation nodes per hemisphere, at least */
    size_t coeffs;      /* stored coefficients, at least */
    size_t file_bytes;  /* the file, at least */
    size_t build_bytes; /* the builder's memory (series, pair records, the file), at least */
    double lobe_deg;    /* the narrowest lobe's spread, degrees */
    double spacing_deg; /* the node spacing the spline needs across it, degrees */
} btdf_scatfun_need;

/* Fills need for the request (arguments as btdf_scatfun_build); BTDF_OK, or BTDF_EINVAL
   as btdf_scatfun_check. Costs about a millisecond. */
BTDF_API btdf_status btdf_scatfun_predict(const btdf_params *p, double tolerance,
                                          btdf_side side, btdf_scatfun_need *need,
                                          char *msg, size_t msglen);

/* The checks btdf_scatfun_build makes of its arguments before any work: BTDF_OK, or
   BTDF_EINVAL with msg naming the value and what is allowed. */
BTDF_API btdf_status btdf_scatfun_check(const btdf_params *p, double tolerance,
                                        btdf_side side, char *msg, size_t msglen);

/* A caller's BSDF given by its azimuthal modes, for btdf_scatfun_build_source: a
   pane's system (btdf_pane.h, docs/pane.md), which tools/ passes in. Each block is
   read in its own frame, as an interface's are (above): the light's cosine mu_l =
   cos ti, the view's mu_v = |cos to| (or cos tr); the slow index is the light's. */
typedef struct btdf_scatfun_source {
    void *user;
    int blocks; /* the blocks it has: a btdf_scatfun_block mask, 1..15 */
    int modes;  /* its series length, 1..BTDF_SCATFUN_MAX_PHI */
    /* c[0 .. modes) with rho(mu_l, mu_v, phi) = max(0, sum_m c[m] cos(m phi)), 1/sr
       without a cosine, phi = pi forward (straight through or the mirror), for block
       `block` (one btdf_scatfun_block) at mu_l, mu_v in (0, 1] */
    void (*modes_at)(void *user, int block, double mu_l, double mu_v, double *c);
    const double *nodes; /* the source's own cosine nodes, ascending in (0, 1) */
    size_t nnodes;       /* 2 .. BTDF_SCATFUN_MAX_HALF_NODES */
    double eta;          /* the header's eta: 1 with the same medium on both sides */
    double alpha;        /* the header's roughness alpha (pbrt-v3 ignores it), >= 0 */
} btdf_scatfun_source;

/* The error of a file built from a source, against the source: MODEL.md section 6's
   e_L1 (relative to max(T or R, 0.01)) and e_T, the worst over every block and light
   angle tested (btdf_scatfun_build_source), read as pbrt-v3 reads the file (DIRECT). */
typedef struct btdf_scatfun_source_error {
    double e_l1, e_t;
    double e_l1_ti; /* where e_l1 is worst (radians) */
    int block;      /* its block (one btdf_scatfun_block) */
    size_t angles;  /* light angles tested per block */
    size_t half_nodes; /* the file's half nodes */
    double seconds; /* the build's wall time, checks included */
} btdf_scatfun_source_error;

/* Builds a file from a source: the half nodes are the source's (float-rounded) and the
   pole node (1 - 2^-24, as every file here), both signs and two at 0; pair (slow,
   fast) holds (-1)^m c[m] |mu_f| (phi_d = pi - phi), cut after the first m whose tail
   sum_{k >= m} |a_k| is within tolerance / 4 of the light row's max(T, 0.01) / (2 pi),
   so the cut adds at most tolerance / 4 to e_L1. The error is then measured against
   the source (48 light angles per block: 24 stratified on [0, pi/2), 24 at midpoints
   between the file's nodes; 128 x 128 midpoint cells in (mu_v, phi)), and while e_L1
   or e_T is above tolerance every node interval is split at its middle angle, up to
   BTDF_SCATFUN_MAX_HALF_NODES. BTDF_OK with *err when the tolerance was met;
   BTDF_EBUDGET with the best file in *out and its *err when the node budget stopped
   refinement first; BTDF_EINVAL (source, tolerance outside [1e-6, 0.5]), BTDF_ENOMEM,
   BTDF_EOVERFLOW. threads: 0 = all cores; the bytes do not depend on it. */
BTDF_API btdf_status btdf_scatfun_build_source(const btdf_scatfun_source *s, double tolerance,
                                               int threads, btdf_scatfun **out,
                                               btdf_scatfun_source_error *err, char *msg,
                                               size_t msglen);

/* Writes f to path (exact SCATFUN v1 layout, float32 little-endian) with the given
   metadata text appended (NULL: a short JSON of the build parameters). The file is
   written under a temporary name in the same folder and renamed at the end; on
   error no file is left at path. BTDF_EIO when writing fails, BTDF_EOVERFLOW when
   the file would not fit the format's 32-bit counts. */
BTDF_API btdf_status btdf_scatfun_write(const btdf_scatfun *f, const char *path,
                                        const char *metadata_json, char *msg,
                                        size_t msglen);

/* Serialises f into a new buffer (caller frees *buf with free()). Same bytes as
   btdf_scatfun_write. */
BTDF_API btdf_status btdf_scatfun_to_mem(const btdf_scatfun *f, const char *metadata_json,
                                         unsigned char **buf, size_t *len, char *msg,
                                         size_t msglen);

/* Reads and checks a SCATFUN v1 file: magic, version, flags, counts, nBases = 1,
   no parameters, exact size, nodes ascending from -1 to +1 (the outer ones within 1e-6), offsets and lengths
   inside the coefficients, lengths <= mMax, every float finite. BTDF_EFORMAT with
   the field and value for corrupt, truncated or foreign files; BTDF_EIO when the
   file cannot be read. */
BTDF_API btdf_status btdf_scatfun_read(const char *path, btdf_scatfun **out, char *msg,
                                       size_t msglen);

/* The same from len bytes at buf (not kept after the call). */
BTDF_API btdf_status btdf_scatfun_read_mem(const void *buf, size_t len, btdf_scatfun **out,
                                           char *msg, size_t msglen);

/* pbrt-v3's FourierBSDF::f in the file's own terms: slow cosine mu_s (pbrt's wo.z),
   fast cosine mu_f (pbrt's -wi.z), cos phi_d; radiance != 0 applies pbrt's e^2 to
   transmission. out[c] for c < btdf_scatfun_channels(f) (R, G, B for three
   channels, G rebuilt from Y as pbrt does). 0 outside the nodes, at mu_f = 0 and
   for empty blocks. BTDF_EINVAL for NULL or non-finite input. */
BTDF_API btdf_status btdf_scatfun_eval_mu(const btdf_scatfun *f, double mu_s, double mu_f,
                                          double cos_phi_d, int radiance, double *out);

/* rho read back from the file in MODEL.md's convention for one block (`side`, a single
   btdf_scatfun_block): T_ENTER gives Eq. 25 at index n, T_LEAVE at index 1/n in that
   side's own (mirrored) frame, ti in [0, pi/2], to in [pi/2, pi]; R_TOP gives rho_r at
   index n, R_BOTTOM rho_r at 1/n (mirrored frame), with `to` the reflected angle tr in
   [0, pi/2]. phi = pi forward (specular), radians. out[channels]. DIRECT reads the
   block whose slow index is the light's side; ADJOINT the block of the other
   direction with pbrt's e^2 (reflection blocks: the same block with the roles of ti
   and tr swapped). Blocks the file does not hold read as 0. BTDF_EDOMAIN for angles
   out of range, BTDF_EINVAL for a bad side or mode. */
BTDF_API btdf_status btdf_scatfun_eval_side(const btdf_scatfun *f, btdf_side side,
                                            btdf_scatfun_mode mode, double ti, double to,
                                            double phi, double *out);

/* btdf_scatfun_eval_side(f, BTDF_SIDE_ENTER, BTDF_SCATFUN_DIRECT, ...): compare with
   btdf_rho(n, s, k0, ti, to, phi). */
BTDF_API btdf_status btdf_scatfun_eval(const btdf_scatfun *f, double ti, double to,
                                       double phi, double *out);

/* Error of one block of the file (`side`: a single btdf_scatfun_block) as a renderer
   reads it, against Eq. 25 (transmission) or rho_r (reflection, e_L1 relative to
   max(R, 0.01)), MODEL.md section 6. A one-channel transmission block and every
   reflection block are read in mode DIRECT; a three-channel transmission block, whose
   stored values carry the fold factors, through the ADJOINT path of the other light
   direction (pbrt-v3's radiance mode), against the truth of that direction. Incident
   angles: test_angles stratified ones in [0, pi/2) (0 = 24), the midpoint of every
   interval between the file's elevation nodes, and midpoints added where the
   per-angle error or T (R) changes fast (btdf_table_estimate's rounds); each with
   points_per_angle facet-space points (0 = 8192) plus 4096 uniform directions,
   combined by the balance heuristic, from the seed. p gives the truth (channel count must match the file). Fills *r
   (zero it first; r->per_ti is malloc'd and owned by the report: free it with
   btdf_report_clear or free()). seconds_build is the build time (0 for a read
   file); slices = node count, samples = coefficient count. */
BTDF_API btdf_status btdf_scatfun_report(const btdf_scatfun *f, const btdf_params *p,
                                         btdf_side side, size_t test_angles,
                                         size_t points_per_angle, uint64_t seed,
                                         int threads, btdf_report *r);

/* Prints header fields and statistics (nodes, coefficient count, mMax, series
   lengths, file size, eta, channels, sides present). BTDF_EIO if printing fails. */
BTDF_API btdf_status btdf_scatfun_info(const btdf_scatfun *f, FILE *out);

/* Small getters. */
BTDF_API int btdf_scatfun_channels(const btdf_scatfun *f);
BTDF_API size_t btdf_scatfun_node_count(const btdf_scatfun *f);
BTDF_API size_t btdf_scatfun_coeff_count(const btdf_scatfun *f);
BTDF_API size_t btdf_scatfun_max_order(const btdf_scatfun *f);
BTDF_API double btdf_scatfun_eta(const btdf_scatfun *f);
/* The metadata text of a file read back (the JSON btdftab writes: ior, smoothness, k0,
   ...), NUL-terminated; NULL for a built object or a file without metadata. */
BTDF_API const char *btdf_scatfun_metadata(const btdf_scatfun *f);
/* Size in bytes of the file btdf_scatfun_write makes with this metadata. */
BTDF_API size_t btdf_scatfun_file_size(const btdf_scatfun *f, const char *metadata_json);
/* Read-only views into f (live as long as f): nodes[node_count], and for pair
   (i, o) its offset and length; cdf[node_count * node_count]; coeffs[coeff_count]. */
BTDF_API const float *btdf_scatfun_nodes(const btdf_scatfun *f);
BTDF_API const float *btdf_scatfun_cdf(const btdf_scatfun *f);
BTDF_API const float *btdf_scatfun_coeffs(const btdf_scatfun *f);
BTDF_API btdf_status btdf_scatfun_pair(const btdf_scatfun *f, size_t i, size_t o,
                                       size_t *offset, size_t *length);

/* Blocks the file holds: a btdf_scatfun_block mask (T_ENTER for mu_s, mu_f > 0 pairs,
   T_LEAVE for mu_s, mu_f < 0, R_TOP for mu_s > 0 > mu_f, R_BOTTOM for mu_s < 0 < mu_f),
   0 when none has a non-empty series. */
BTDF_API int btdf_scatfun_sides(const btdf_scatfun *f);

/* Largest |a_0| of channel 0 over all pairs: the scale of the values pbrt-v3's
   elevation sampler (SampleCatmullRom2D) inverts. That sampler stops on an absolute
   1e-6 tolerance; in single precision its Newton step cannot move t by one unit in
   the last place once the spline value passes 2^25 * 1e-6 = 33.55, and it can loop
   forever. Spline and row interpolation can raise a value by at most (3/2)^2 over
   the stored ones, so files with a peak at most BTDF_SCATFUN_PBRT_FLOAT_SAFE_A0 are
   safe in a single-precision pbrt-v3; larger peaks need pbrt-v3 built with
   PBRT_FLOAT_AS_DOUBLE (docs/scatfun.md, "pbrt-v3's sampler"). */
#define BTDF_SCATFUN_PBRT_FLOAT_SAFE_A0 14.9
BTDF_API double btdf_scatfun_a0_peak(const btdf_scatfun *f);

BTDF_API void btdf_scatfun_free(btdf_scatfun *f);

#ifdef __cplusplus
}
#endif

#endif /* BTDF_SCATFUN_H */
