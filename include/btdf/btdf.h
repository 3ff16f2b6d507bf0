/* SPDX-License-Identifier: MIT */
/* btdf.h: public C API of libbtdf, the rough-interface BTDF of Xu & Sun (2008), Eq. 25. */
#ifndef BTDF_H
#define BTDF_H

#include <stddef.h>
#include <stdint.h>

#include "btdf_config.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Conventions
 * -----------
 * Frame: z is the mean surface normal and points into the medium the light comes
 * from (the "upper" medium). Every direction vector points AWAY from the surface.
 *
 * Angles: radians everywhere in this API (the btdftab tool speaks degrees).
 *   ti  polar angle of the incident direction, [0, pi/2]
 *   to  polar angle of the transmitted direction, [pi/2, pi]
 *   phi azimuth of the transmitted direction relative to the incident one,
 *       any finite value; rho depends on cos(phi) only. phi = pi is the forward
 *       plane, where the undeviated and the refracted directions lie.
 *
 * Index: n = (index of the lower medium) / (index of the upper medium).
 *   Light entering glass from air: n = 1.5; leaving glass into air: n = 1/1.5.
 *   n = 1 has no BTDF (the transmission is a delta) and is rejected.
 *
 * Value: rho is the BTDF in 1/sr, WITHOUT any cosine factor: a renderer multiplies
 *   by |cos to| itself. Reciprocity:
 *   rho(n; ti, to, phi) = n^2 rho(1/n; pi - to, pi - ti, phi).
 *
 * Out of domain: directions the model cannot connect (transmitted direction in the
 *   upper hemisphere, grazing ti = pi/2 or to = pi/2, no facet refracting e_i into e_o)
 *   give rho = 0. Values below the smallest normal double are returned as 0. No
 *   function of this library ever returns NaN or inf as a value.
 *
 * Errors: every fallible function returns btdf_status; results go through
 *   out-parameters, which are left untouched on error unless said otherwise.
 *   Messages (with the offending value) go to a caller buffer `msg` of `msglen`
 *   bytes, which may be NULL.
 *
 * Threads: the model functions are pure and thread-safe. A btdf_table is immutable
 *   once built, so it may be evaluated from many threads at once; building and
 *   freeing one are not concurrent with other uses of the same table.
 *
 * Files: every writer writes under a temporary name beside the output and renames it
 *   at the end, so an output appears whole or not at all; on error the temporary file
 *   is removed. The library installs no signal handler (the btdftab tool removes its
 *   temporary files on SIGINT, SIGTERM and SIGHUP). The same inputs give the same
 *   bytes, whatever the thread count.
 *
 * Ownership: objects returned through `**out` belong to the caller, who frees them
 *   with the matching *_free function; every *_free(NULL) is a no-op. Views returned
 *   by btdf_table_slice point into the table and live as long as it does.
 */

#define BTDF_VERSION_MAJOR 0
#define BTDF_VERSION_MINOR 4
#define BTDF_VERSION_PATCH 0
#define BTDF_VERSION_STRING "0.4.0"

/* The library's own version, which may differ from the header it was built against. */
BTDF_API const char *btdf_version_string(void);

/* Status codes: append-only, never renumbered. One list, so codes and messages agree. */
#define BTDF_STATUS_LIST(X)                                                        \
    X(BTDF_OK, "success")                                                          \
    X(BTDF_EINVAL, "invalid argument")                                             \
    X(BTDF_ENOMEM, "out of memory")                                                \
    X(BTDF_EOVERFLOW, "size overflow")                                             \
    X(BTDF_EDOMAIN, "value outside its domain")                                    \
    X(BTDF_EIO, "input/output error")                                              \
    X(BTDF_EFORMAT, "malformed or foreign file")                                   \
    X(BTDF_ENOTSUP, "not supported by this build")                                 \
    X(BTDF_EBUDGET, "budget exhausted before the tolerance was met")

#define BTDF_STATUS_ENUM_(name, text) name,
typedef enum { BTDF_STATUS_LIST(BTDF_STATUS_ENUM_) BTDF_STATUS_COUNT_ } btdf_status;
#undef BTDF_STATUS_ENUM_

/* A static message for every status; "unknown status" for anything else. */
BTDF_API const char *btdf_strerror(btdf_status status);

/* ------------------------------------------------------------------------- */
/* Model parameters                                                          */
/* ------------------------------------------------------------------------- */

#define BTDF_MAX_CHANNELS 3

/* Accepted parameter ranges (inclusive). Outside them btdf_params_check fails. */
#define BTDF_IOR_MIN 1e-3
#define BTDF_IOR_MAX 1e3
#define BTDF_IOR_ONE_EPS 1e-9 /* |n - 1| below this is treated as n = 1 */
#define BTDF_S_MIN 1e-3
#define BTDF_S_MAX 1e6
#define BTDF_K0_MAX 100.0

/*
 * Which shadowing-masking the facets get (docs/model.md section 11). The facets, their
 * Beckmann density D (RMS slope 2/s), the Fresnel terms and the Jacobian are the same
 * in every model; only the term G that multiplies them differs.
 *  BTDF_MODEL_XU_SUN: Eq. 25 as the paper writes it, G = V(ti) V(to) with the constant
 *    k0 (the default; a zero-initialised btdf_params means this model).
 *  BTDF_MODEL_SMITH: the height-correlated Smith term of the same Gaussian surface
 *    (Walter et al. 2007; Heitz 2014), with Lambda of the Beckmann slopes of RMS 2/s:
 *    transmission G = B(1 + Lambda(ti), 1 + Lambda(to)) (Beta function), reflection
 *    G = 1/(1 + Lambda(ti) + Lambda(tr)). k0 plays no part. One scattering event.
 *  BTDF_MODEL_FULL: smith plus the light scattered two or more times (section 12); made
 *    once per material by btdf_model_ctx_new or btdf_full_new, not by the functions
 *    taking a btdf_params (btdf_params_check refuses it with BTDF_ENOTSUP).
 */
typedef enum {
    BTDF_MODEL_XU_SUN = 0,
    BTDF_MODEL_SMITH = 1,
    BTDF_MODEL_FULL = 2
} btdf_model;

/* "xu-sun", "smith", "full"; parse returns 0 for an unknown name (it accepts "full":
   btdf_params_check is what refuses it). */
BTDF_API const char *btdf_model_name(btdf_model model);
BTDF_API int btdf_model_parse(const char *name, btdf_model *model);

typedef struct btdf_params {
    int channels;                  /* 1, or 3 for R, G, B */
    double ior[BTDF_MAX_CHANNELS]; /* n per channel (dispersion); ior[0] when channels = 1 */
    double smoothness;             /* s = tau / sigma, shared by all channels */
    double k0;                     /* shadowing constant of Eq. 25, 0.7 in the paper */
    btdf_model model;              /* shadowing-masking; 0 = BTDF_MODEL_XU_SUN */
} btdf_params;

/* Defaults: one channel, n = 1.5, s = 3, k0 = 0.7, model xu-sun. */
BTDF_API void btdf_params_default(btdf_params *p);

/* BTDF_OK, or BTDF_EINVAL for NaN/inf, channels not 1 or 3, n <= 0 or outside
   [BTDF_IOR_MIN, BTDF_IOR_MAX], |n - 1| < BTDF_IOR_ONE_EPS, s outside
   [BTDF_S_MIN, BTDF_S_MAX], k0 outside [0, BTDF_K0_MAX], a model other than xu-sun
   or smith; BTDF_ENOTSUP for BTDF_MODEL_FULL (made by btdf_model_ctx_new or
   btdf_full_new). */
BTDF_API btdf_status btdf_params_check(const btdf_params *p, char *msg, size_t msglen);

/* ------------------------------------------------------------------------- */
/* The model                                                                 */
/* ------------------------------------------------------------------------- */

/* Eq. 25 for one channel. No validation: for parameters that fail
   btdf_params_check, or angles out of range, the result is 0 (never NaN). */
BTDF_API double btdf_rho(double n, double s, double k0, double ti, double to, double phi);

/* btdf_rho with the three angles in degrees, exact at multiples of 90 degrees
   (the form the btdftab tool uses). */
BTDF_API double btdf_rho_deg(double n, double s, double k0, double ti, double to,
                             double phi);

/* The same facets with the height-correlated Smith term of BTDF_MODEL_SMITH in place
   of V(ti) V(to) (k0 plays no part); same rules as btdf_rho. */
BTDF_API double btdf_rho_smith(double n, double s, double ti, double to, double phi);
BTDF_API double btdf_rho_smith_deg(double n, double s, double ti, double to, double phi);

/* Flat-interface Fresnel transmittance Ft(ti) for index n (0 past the critical angle). */
BTDF_API double btdf_fresnel_t(double n, double ti);

/* rho for every channel of p into out[p->channels]. BTDF_EDOMAIN for angles outside
   ti in [0, pi/2], to in [pi/2, pi], finite phi; BTDF_EINVAL for bad parameters. */
BTDF_API btdf_status btdf_eval(const btdf_params *p, double ti, double to, double phi,
                               double *out);

/* The same by direction vectors (unit length within 1e-6, pointing away from the
   surface). wo in the upper hemisphere gives 0 (btdf_rho_r is that lobe), wi in the
   lower gives BTDF_EDOMAIN. */
BTDF_API btdf_status btdf_eval_dir(const btdf_params *p, const double wi[3],
                                   const double wo[3], double *out);

/* count evaluations; out holds count * channels values, channel fastest; the values
   are those of btdf_eval, bit for bit. All angles are checked first: the first bad one
   gives BTDF_EDOMAIN, sets *bad_index (may be NULL) and leaves out untouched. One
   thread, a vectorised loop; btdf_eval_grid is the threaded form for grids. */
BTDF_API btdf_status btdf_eval_batch(const btdf_params *p, size_t count, const double *ti,
                                     const double *to, const double *phi, double *out,
                                     size_t *bad_index);

/* rho on the tensor grid ti[i] x to[j] x phi[k] (radians), written to
   out[((i * nto + j) * nphi + k) * channels + c], on `threads` threads (0 = all
   cores). The values are those of btdf_eval, bit for bit, whatever the thread count.
   BTDF_EDOMAIN for any angle outside the ranges of btdf_eval (out untouched),
   BTDF_EINVAL for bad parameters, BTDF_ENOMEM, BTDF_EOVERFLOW. */
BTDF_API btdf_status btdf_eval_grid(const btdf_params *p, size_t nti, const double *ti,
                                    size_t nto, const double *to, size_t nphi,
                                    const double *phi, int threads, double *out);

/* Hemispherical transmittance T(ti) = integral of rho |cos to| over the lower
   hemisphere, per channel, by quadrature in facet-slope space; absolute error below
   1e-7 for n > 1 and 1e-6 for n < 1 over the parameter ranges above. */
BTDF_API btdf_status btdf_transmittance(const btdf_params *p, double ti, double *out);

/* ------------------------------------------------------------------------- */
/* The reflection of the same interface (MODEL.md section 8)                 */
/* ------------------------------------------------------------------------- */

/*
 * The same Beckmann facets (RMS slope 2/s) and shadowing V(ti) V(tr) reflect what
 * they do not transmit, with the facet's Fresnel reflectance (1 past the critical
 * angle when n < 1): the Torrance-Sparrow / Walter et al. (2007) BRDF
 *   rho_r = Fr D V(ti) V(tr) / (4 cos ti cos tr),  h = (e_i + e_r)/|e_i + e_r|.
 * tr is the polar angle of the reflected direction, [0, pi/2]; phi as for rho, with
 * phi = pi the specular plane. rho_r is in 1/sr without a cosine factor, reciprocal:
 * rho_r(ti, tr, phi) = rho_r(tr, ti, phi). Same rules as rho: 0 out of range or below
 * the smallest normal double, never NaN or inf.
 */
BTDF_API double btdf_rho_r(double n, double s, double k0, double ti, double tr, double phi);
BTDF_API double btdf_rho_r_deg(double n, double s, double k0, double ti, double tr,
                               double phi);
/* rho_r with the height-correlated Smith term 1/(1 + Lambda(ti) + Lambda(tr)). */
BTDF_API double btdf_rho_r_smith(double n, double s, double ti, double tr, double phi);
BTDF_API double btdf_rho_r_smith_deg(double n, double s, double ti, double tr, double phi);

/* btdf_rho, btdf_rho_deg, btdf_rho_r and btdf_rho_r_deg in the model m (a model this
   build does not evaluate gives 0): for callers that carry a btdf_params' model. */
BTDF_API double btdf_rho_model(btdf_model m, double n, double s, double k0, double ti,
                               double to, double phi);
BTDF_API double btdf_rho_model_deg(btdf_model m, double n, double s, double k0, double ti,
                                   double to, double phi);
BTDF_API double btdf_rho_r_model(btdf_model m, double n, double s, double k0, double ti,
                                 double tr, double phi);
BTDF_API double btdf_rho_r_model_deg(btdf_model m, double n, double s, double k0, double ti,
                                     double tr, double phi);

/* ------------------------------------------------------------------------- */
/* The model full: smith plus multiple scattering (docs/model.md section 12)  */
/* ------------------------------------------------------------------------- */

/*
 * rho_full = rho_smith + rho_ms, where rho_ms is the light the interface scatters two or
 * more times on the Smith microsurface. rho_ms is tallied once per material (n, s) by the
 * dielectric random walk of Heitz et al. 2016 at a ladder of incidence angles and kept
 * as a series sum_km a_km(ti) p_k(|cos to|) cos(m phi) (p_k orthonormal for the weight
 * |cos to|), a_km linear in ti between the ladder's angles. The tally is deterministic:
 * fixed random streams per (seed, angle, chunk of paths), summed in a fixed order, so
 * the object has the same bits whatever the thread count. Make one object per
 * material and reuse it: evaluations are cheap, the tally is not (btdf-bench).
 */
#define BTDF_FULL_PATHS_DEFAULT 200000ull /* per incidence angle of the ladder */
#define BTDF_FULL_PATHS_MAX 1000000000ull

typedef struct btdf_full_opts {
    uint64_t paths; /* walks per incidence angle; default BTDF_FULL_PATHS_DEFAULT */
    uint64_t seed;  /* default 1 */
    int threads;    /* 0: as many as the machine has; the result does not depend on it */
} btdf_full_opts;

BTDF_API void btdf_full_opts_default(btdf_full_opts *o);

typedef struct btdf_full btdf_full;

/* The object of one material, index n and smoothness s (the ranges of
   btdf_params_check); opts NULL for the defaults. BTDF_EINVAL naming a bad value,
   BTDF_ENOMEM. */
BTDF_API btdf_status btdf_full_new(double n, double s, const btdf_full_opts *opts,
                                   btdf_full **out, char *msg, size_t msglen);
BTDF_API void btdf_full_free(btdf_full *f);

/* rho_full of transmission and of reflection (the angles of btdf_rho and btdf_rho_r);
   0 out of range, never NaN or inf. */
BTDF_API double btdf_full_rho(const btdf_full *f, double ti, double to, double phi);
BTDF_API double btdf_full_rho_deg(const btdf_full *f, double ti, double to, double phi);
BTDF_API double btdf_full_rho_r(const btdf_full *f, double ti, double tr, double phi);
BTDF_API double btdf_full_rho_r_deg(const btdf_full *f, double ti, double tr, double phi);

/* T and R of full at ti (radians): the single scattering by quadrature (as
   btdf_transmittance and btdf_reflectance of smith), the multiple from the tally,
   with its binomial standard error. */
typedef struct btdf_full_albedos {
    double T, R;       /* full */
    double T1, R1;     /* single scattering (smith) */
    double Tms, Rms;   /* two or more */
    double Tms_se, Rms_se;
} btdf_full_albedos;
BTDF_API btdf_status btdf_full_albedo(const btdf_full *f, double ti, btdf_full_albedos *a);

/* What the tally took: its ladder, paths, wall time, the largest fraction of paths lost
   to the event limit, and the largest |(T1 + R1) - walk's order-1 fraction| over the
   ladder (the walk checked against smith's quadrature). */
typedef struct btdf_full_stats {
    int nodes;
    uint64_t paths;
    double seconds, lost, order1_gap;
} btdf_full_stats;
BTDF_API void btdf_full_info(const btdf_full *f, btdf_full_stats *st);

/* The multiply scattered part as f holds it, for a renderer that evaluates it itself
   (the Mitsuba 3 plugin does, on its device). With mu = |cos t| of the outgoing
   direction (to or tr) and w the weight of ti (degrees) between the nodes a and a + 1
   that bracket it (the first a with ti <= node_deg[a + 1], a + 1 < nodes; w clamped to
   [0, 1], so the end nodes hold beyond them), side h = 0 for transmission, 1 for
   reflection:
     rho_ms = c max(0, sum_{j<K, m<M} ((1 - w) coef[a][h][j][m] + w coef[a + 1][h][j][m])
                       sin^m t cos(m phi) sum_{i<K} poly[m][j][i] mu^i),
   c = (1 - u) clip[a][q][h] + u clip[a][q + 1][h], with x = w SUB, q = min(floor(x),
   SUB - 1), u = x - q: the factor (<= 1) that gives the clipped series the tallied
   energy of the series itself (the clip adds the energy of its negative dips), and
   btdf_full_rho_deg = btdf_rho_smith_deg + rho_ms (0 at grazing ti or to). */
#define BTDF_FULL_SERIES_K 8      /* polynomials in mu of degree 0..7 */
#define BTDF_FULL_SERIES_M 5      /* cos(m phi), m = 0..4 */
#define BTDF_FULL_SERIES_NODES 33 /* at most this many incidence angles */
#define BTDF_FULL_SERIES_SUB 8    /* the clip factor's points per node interval, less 1 */
typedef struct btdf_full_series {
    int nodes;
    double node_deg[BTDF_FULL_SERIES_NODES]; /* increasing */
    double poly[BTDF_FULL_SERIES_M][BTDF_FULL_SERIES_K][BTDF_FULL_SERIES_K];
    double coef[BTDF_FULL_SERIES_NODES][2][BTDF_FULL_SERIES_K][BTDF_FULL_SERIES_M];
    double clip[BTDF_FULL_SERIES_NODES][BTDF_FULL_SERIES_SUB + 1][2];
} btdf_full_series;
/* BTDF_EINVAL for a NULL argument. */
BTDF_API btdf_status btdf_full_get_series(const btdf_full *f, btdf_full_series *out);

/* One evaluation entry for every model: an object made once from a btdf_params (any
   model; for full it holds one btdf_full per channel, made with opts or the defaults),
   evaluated per channel. xu-sun and smith give exactly btdf_rho_model_deg and
   btdf_rho_r_model_deg. */
typedef struct btdf_model_ctx btdf_model_ctx;
BTDF_API btdf_status btdf_model_ctx_new(const btdf_params *p, const btdf_full_opts *opts,
                                        btdf_model_ctx **out, char *msg, size_t msglen);
BTDF_API void btdf_model_ctx_free(btdf_model_ctx *m);
BTDF_API const btdf_params *btdf_model_ctx_params(const btdf_model_ctx *m);
/* The tally of channel ch (model full), else NULL. */
BTDF_API const btdf_full *btdf_model_ctx_full(const btdf_model_ctx *m, int ch);
BTDF_API double btdf_model_ctx_rho_deg(const btdf_model_ctx *m, int ch, double ti, double to,
                                       double phi);
BTDF_API double btdf_model_ctx_rho_r_deg(const btdf_model_ctx *m, int ch, double ti,
                                         double tr, double phi);
/* T and R at ti (radians) for every channel into T[channels], R[channels]. */
BTDF_API btdf_status btdf_model_ctx_albedo(const btdf_model_ctx *m, double ti, double *T,
                                           double *R);

/* Flat-interface Fresnel reflectance Fr(ti) = 1 - Ft(ti) (1 past the critical angle),
   formed without that cancellation, so it keeps its digits when n is near 1. */
BTDF_API double btdf_fresnel_r(double n, double ti);

/* rho_r for every channel of p into out[p->channels]. BTDF_EDOMAIN for angles outside
   ti, tr in [0, pi/2], finite phi; BTDF_EINVAL for bad parameters. */
BTDF_API btdf_status btdf_eval_r(const btdf_params *p, double ti, double tr, double phi,
                                 double *out);

/* Hemispherical reflectance R(ti) = integral of rho_r cos tr over the upper
   hemisphere, per channel, by the same facet-slope quadrature as T; within 1e-8 of
   reference-albedo-r.csv (tests/test_model.c). R + T <= 1: what neither holds is
   the light the shadowing removes. */
BTDF_API btdf_status btdf_reflectance(const btdf_params *p, double ti, double *out);

/* ------------------------------------------------------------------------- */
/* Tables                                                                    */
/* ------------------------------------------------------------------------- */

/*
 * A table is a stack of slices at increasing incident angles ti_k. Each slice is a
 * rectilinear grid of nodes (rows x cols) holding rho for every channel, and one
 * interpolation rule turns it into rho~(ti, to, phi) everywhere:
 *
 *  BTDF_TABLE_FACET: rows are facet tilts tn, cols facet azimuths psi in [0, pi]
 *    (psi = 0: the facet leans towards the incident direction). For a query
 *    (ti, to, phi) the facet normal h that refracts e_i into e_o is computed; each of
 *    the two slices bracketing ti is interpolated bilinearly at h's (tn, |psi|); the
 *    two values are blended linearly in ti. The lobe is stationary in facet space,
 *    so few nodes follow it. Queries outside the nodes' range give 0.
 *  BTDF_TABLE_GRID: rows are to, cols phi in [0, pi]; bilinear in (to, |phi| folded to
 *    [0, pi]) inside a slice, linear in ti between slices. What a plain engine does.
 *  BTDF_TABLE_FACET_RECIPROCAL: for light leaving the dense medium (every n < 1). The
 *    slices are a FACET table of index 1/n, indexed by pi - to, and the rule answers
 *    rho~(n; ti, to, phi) = n^2 rho~(1/n; pi - to, pi - ti, phi) (MODEL.md section 4).
 *    Facet space of n < 1 is badly conditioned near the critical angle (its measure
 *    |cos to|/chi diverges there); facet space of 1/n > 1 is not.
 *
 * The blend in ti divides both slice values by Eq. 25's incident factor V(ti)/cos ti
 * and multiplies the result by the query's; a slice where that factor is 0 (ti = 90
 * deg) holds zeros, and its neighbour's divided value stands in for it. Outside the
 * slices' ti range the table gives 0.
 *
 * Facet tables have one of two rules for what is interpolated (btdf_table_rule):
 *  BTDF_RULE_PLAIN: rho itself, as above (every table written before the rule had a
 *    name, and the default of btdf_table_new).
 *  BTDF_RULE_CHI: rho / K, K = cb (ca + n cb)^2, where ca = e_i.h at the slice's own ti
 *    for each node (0 where ca <= 0: the facet refracts nothing, and so does the node)
 *    and cb = sqrt(1 - (1 - ca^2)/n^2); the blend in ti is of those reduced values (each
 *    also divided by its slice's incident factor), and the result is multiplied by the
 *    query's K (its own ca) and incident factor. K is the Jacobian chi of Eq. 25 times
 *    (n^2 - 1)^2 / n^2: rho / K is smooth in facet space for every n, while rho grows
 *    like ca^3 / (n - 1)^2 near n = 1. btdf_table_build makes CHI tables.
 *
 * Reflection (MODEL.md section 8) has a kind of its own:
 *  BTDF_TABLE_FACET_REFLECTION: slices hold rho_r at facet normals (tn, psi) like
 *    FACET, for the facet h = (e_i + e_r)/|e_i + e_r| that mirrors e_i into e_r; tn = 0
 *    is the mirror direction (tr = ti, phi = pi), the centre of the specular lobe. The
 *    rule is FACET's with K = Fr(ca) (BTDF_RULE_FRESNEL, ca = e_i.h = |e_i + e_r|/2):
 *    bilinear in (tn, |psi|) of rho_r / Fr, linear in ti after dividing by V(ti)/cos ti
 *    (the incident factor rho_r shares with rho), times the query's Fr. For this kind
 *    btdf_table_eval's `to` is the reflected polar angle tr in [0, pi/2].
 */
typedef enum {
    BTDF_TABLE_FACET = 0,
    BTDF_TABLE_GRID = 1,
    BTDF_TABLE_FACET_RECIPROCAL = 2,
    BTDF_TABLE_FACET_REFLECTION = 3
} btdf_table_kind;

/* Which lobes of the interface a table holds: its transmission (Eq. 25), its
   reflection (MODEL.md section 8), or both, each a table of its own kind, with the
   reflection attached to the transmission table (btdf_table_part). */
typedef enum {
    BTDF_PART_TRANSMISSION = 1,
    BTDF_PART_REFLECTION = 2,
    BTDF_PART_BOTH = 3
} btdf_part;

/* "transmission", "reflection", "both"; parse returns 0 for an unknown name. */
BTDF_API const char *btdf_part_name(btdf_part part);
BTDF_API int btdf_part_parse(const char *name, btdf_part *part);

typedef struct btdf_table btdf_table;

/* FRESNEL: the rule of reflection tables, CHI's with K = Fr(ca), the facet's Fresnel
   reflectance (1 past the critical angle): rho_r / Fr is smooth where Fr has its kink. */
typedef enum { BTDF_RULE_PLAIN = 0, BTDF_RULE_CHI = 1, BTDF_RULE_FRESNEL = 2 } btdf_table_rule;

/* A read-only view of slice k. values[(r * ncols + c) * channels + ch]. */
typedef struct btdf_slice {
    double ti;
    size_t nrows, ncols;
    const double *rows, *cols;
    const double *values;
} btdf_slice;

typedef enum { BTDF_METRIC_L1 = 0, BTDF_METRIC_MAX = 1 } btdf_metric;

/* Progress of a long build, for a caller's progress bar: `stage` names what is being
   refined ("slices", "incidence angles", "elevation nodes", ...), `done` counts the
   units of it finished so far and `todo` those known to remain; refinement may find
   more, so done / (done + todo) is an estimate that may step back. Called from the
   thread that called the build, between units of work, never concurrently; it must
   not call back into the build. NULL: no calls. */
typedef void (*btdf_progress_fn)(void *user, const char *stage, size_t done, size_t todo);

/* How the builder checks a FACET table against the tolerance: FULL (the default) is
   the estimate btdf_table_estimate makes with its defaults; FAST uses 16 stratified
   angles of 2048 points (plus every slice interval); NONE builds one pass without a
   check, so whether the tolerance is met is not known. */
typedef enum {
    BTDF_ESTIMATE_FULL = 0,
    BTDF_ESTIMATE_FAST = 1,
    BTDF_ESTIMATE_NONE = 2
} btdf_estimate_mode;

/* How to build a table. Fill with btdf_table_opts_default, then change fields. */
typedef struct btdf_table_opts {
    btdf_params params;
    double ti_min, ti_max;  /* incident range, radians, within [0, pi/2] */
    btdf_table_kind kind;   /* FACET: adaptive (RECIPROCAL is chosen for n < 1); GRID */
    double tolerance;       /* target error for FACET (default 1e-3) */
    btdf_metric metric;     /* which error must meet the tolerance */
    size_t grid_ti, grid_to, grid_phi; /* GRID counts (default 90 x 90 x 181) */
    size_t max_samples;     /* node budget, 0 = default 5e7 */
    size_t max_bytes;       /* memory cap for the node values, 0 = default 1 GiB */
    int threads;            /* 0 = all cores */
    double to_min, to_max;  /* GRID: outgoing range, radians within [pi/2, pi] */
    double phi_min, phi_max; /* GRID: azimuth range, radians within [0, pi] (rho depends
                               on cos phi only, so [0, pi] holds every azimuth) */
    btdf_progress_fn progress; /* may be NULL (the default) */
    void *progress_user;       /* passed to progress */
    btdf_estimate_mode estimate; /* FACET: the builder's check (default FULL) */
    btdf_part part;         /* which lobes (default TRANSMISSION; REFLECTION and BOTH
                               need kind FACET); each part is refined to the tolerance
                               and has the whole budget to itself */
} btdf_table_opts;

BTDF_API void btdf_table_opts_default(btdf_table_opts *o);

/* The checks btdf_table_build makes of o before any work: BTDF_OK, or BTDF_EINVAL
   with msg naming the value and what is allowed. */
BTDF_API btdf_status btdf_table_opts_check(const btdf_table_opts *o, char *msg, size_t msglen);

/* Builds a table. BTDF_OK when the tolerance was met (or for GRID). When the budget
   stops refinement first, *out still holds the best table reached and the status is
   BTDF_EBUDGET. Errors: BTDF_EINVAL (options), BTDF_ENOMEM, BTDF_EOVERFLOW. */
BTDF_API btdf_status btdf_table_build(const btdf_table_opts *o, btdf_table **out,
                                      char *msg, size_t msglen);

BTDF_API void btdf_table_free(btdf_table *t);

/* Builds a table from slices (for readers): btdf_table_new, then
   btdf_table_add_slice in increasing ti. Rows and cols must increase strictly;
   values are copied. BTDF_EINVAL says which rule was broken. */
BTDF_API btdf_status btdf_table_new(btdf_table_kind kind, const btdf_params *p,
                                    btdf_table **out, char *msg, size_t msglen);
BTDF_API btdf_status btdf_table_add_slice(btdf_table *t, double ti, size_t nrows,
                                          const double *rows, size_t ncols,
                                          const double *cols, const double *values,
                                          char *msg, size_t msglen);

/* The table of one part: t itself when it is that part, the reflection attached to a
   transmission table for REFLECTION, NULL when t does not hold it (BOTH: NULL). */
BTDF_API const btdf_table *btdf_table_part(const btdf_table *t, btdf_part part);
/* Which parts t holds: TRANSMISSION, REFLECTION or BOTH. */
BTDF_API btdf_part btdf_table_parts(const btdf_table *t);
/* Attaches r, a FACET_REFLECTION table of the same parameters, to the transmission
   table t, which takes ownership of it (readers of files holding both parts).
   BTDF_EINVAL when t is not a transmission table, already holds a reflection, or the
   parameters differ; r is then not taken. */
BTDF_API btdf_status btdf_table_attach_reflection(btdf_table *t, btdf_table *r, char *msg,
                                                  size_t msglen);

/* The interpolation rule (above). set_rule only on a table with no slices yet and of a
   facet kind (grid tables are plain): BTDF_EINVAL otherwise, saying why. */
BTDF_API btdf_status btdf_table_set_rule(btdf_table *t, btdf_table_rule rule, char *msg,
                                         size_t msglen);
BTDF_API btdf_table_rule btdf_table_get_rule(const btdf_table *t);
/* "plain", "chi" or "fresnel", as files name the rules; parse gives 0 for an unknown
   name. */
BTDF_API const char *btdf_table_rule_name(btdf_table_rule rule);
BTDF_API int btdf_table_rule_parse(const char *name, btdf_table_rule *rule);

BTDF_API btdf_table_kind btdf_table_get_kind(const btdf_table *t);
BTDF_API const btdf_params *btdf_table_get_params(const btdf_table *t);
/* Model full: the tally of channel ch that the table adds to its slices (made for the
   material's own index n, whatever the kind), for a renderer that evaluates a full
   table itself (btdf_full_get_series); the table's, valid until btdf_table_free. NULL
   for another model, a NULL table or a channel out of range. */
BTDF_API const btdf_full *btdf_table_get_full(const btdf_table *t, int ch);
BTDF_API size_t btdf_table_slice_count(const btdf_table *t);
/* Total number of stored nodes (sum of rows * cols over the slices). */
BTDF_API size_t btdf_table_node_count(const btdf_table *t);
/* BTDF_EINVAL if k is out of range. */
BTDF_API btdf_status btdf_table_slice(const btdf_table *t, size_t k, btdf_slice *out);

/* rho~ per channel into out[channels]. Same domain rules as btdf_eval; for a
   FACET_REFLECTION table, rho_r~ with `to` the reflected angle tr in [0, pi/2] (the
   rules of btdf_eval_r). A table holding both parts evaluates its transmission here:
   btdf_table_part gives the reflection. */
BTDF_API btdf_status btdf_table_eval(const btdf_table *t, double ti, double to, double phi,
                                     double *out);

/* ------------------------------------------------------------------------- */
/* Error of a table against Eq. 25 (MODEL.md section 6)                      */
/* ------------------------------------------------------------------------- */

typedef struct btdf_ti_error {
    double ti;                   /* radians */
    double T, T_table;           /* true and tabulated transmittance (channel 0);
                                    R and R~ for a reflection table */
    double e_l1, e_t, e_max;     /* worst channel; e_max = 0 where T < 0.01 */
} btdf_ti_error;

typedef struct btdf_report {
    size_t slices, samples;      /* table size: slices and stored nodes */
    size_t test_angles, test_points; /* points used by the estimate, not table nodes */
    double seconds_build, seconds_estimate;
    double e_l1_max, e_l1_mean, e_t_max, e_t_mean, e_max_max, e_max_mean;
    double tolerance;            /* requested (0 for GRID) */
    btdf_metric metric;
    int met;                     /* 1 when the chosen metric's max <= tolerance */
    size_t peak_bytes;           /* peak memory: btdf_table_estimate leaves it 0 for the
                                    caller to fill (btdftab stores the peak resident size);
                                    btdf_scatfun_report gives the file's data size */
    btdf_ti_error *per_ti;       /* test_angles entries, owned by the report */
    size_t e_max_angles;         /* test angles with T >= 0.01, where e_max is defined;
                                    e_max_* are 0 when there are none */
    int estimate_in_build;       /* 1: this is the builder's own final check, whose time
                                    seconds_estimate is also inside seconds_build */
    double ms_noise;             /* model full: the noise floor of the multiple-scattering
                                    tally the errors are measured against, the largest
                                    standard error of its energy (a fraction of the
                                    incident flux) over the range; 0 for other models */
} btdf_report;

/* Estimates the errors of t over [ti_min, ti_max] at test_angles stratified incident
   angles (0 = default 48) with about points_per_angle stratified outgoing points
   each (0 = default 8192), from the given seed; also at the ends of the range, the
   midpoint of every interval between adjacent slices, and midpoints added in rounds
   where the per-angle error or T changes fast (per_ti lists them all, by ti; the means
   are over the stratified angles). A table the builder checked with the same request
   returns that check. Frees nothing in *r first: pass a
   zeroed report and call btdf_report_clear after. A FACET_REFLECTION table is
   measured against rho_r over the upper hemisphere, with R(ti) in place of T(ti)
   (e_L1 and e_T relative to max(R, 0.01)); a table holding both parts is measured on
   its transmission: estimate btdf_table_part(t, BTDF_PART_REFLECTION) for the other. */
BTDF_API btdf_status btdf_table_estimate(const btdf_table *t, double ti_min, double ti_max,
                                         size_t test_angles, size_t points_per_angle,
                                         uint64_t seed, int threads, btdf_report *r);
BTDF_API void btdf_report_clear(btdf_report *r);


/* ------------------------------------------------------------------------- */
/* Files                                                                     */
/* ------------------------------------------------------------------------- */

/* Sides of the interface a renderer format may hold (MODEL.md section 5). */
typedef enum { BTDF_SIDE_ENTER = 1, BTDF_SIDE_LEAVE = 2, BTDF_SIDE_BOTH = 3 } btdf_side;

typedef struct btdf_write_opts {
    const btdf_report *report; /* error report stored with the table, may be NULL */
    const char *provenance;    /* e.g. the command line, may be NULL */
    const btdf_report *report_reflection; /* a table holding both parts: the report of
                                             its reflection, may be NULL */
} btdf_write_opts;

/* Writes t to path in the format its extension names (.csv, .exr). The file is
   written under a temporary name in the same folder and renamed at the end: on any
   error no file is left at path. BTDF_ENOTSUP when the format was switched off at
   build time (the message says which feature), BTDF_EIO when writing fails. */
BTDF_API btdf_status btdf_table_write(const btdf_table *t, const char *path,
                                      const btdf_write_opts *w, char *msg, size_t msglen);

/* Reads a table written by btdf_table_write (.csv, .exr). BTDF_EFORMAT with the
   reason for truncated, corrupt or foreign files. */
BTDF_API btdf_status btdf_table_read(const char *path, btdf_table **out, char *msg,
                                     size_t msglen);

/* 1 if files of this extension (".exr", "exr") can be written by this build. */
BTDF_API int btdf_format_available(const char *ext);

/* The name of a table kind as files record it: "facet", "facet-reciprocal", "grid",
   "facet-reflection". */
BTDF_API const char *btdf_table_kind_name(btdf_table_kind kind);

#ifdef __cplusplus
}
#endif

#include "btdf_preview.h"
#include "btdf_scatfun.h"
#include "btdf_io.h"
#include "btdf_radiance.h"

#endif /* BTDF_H */
