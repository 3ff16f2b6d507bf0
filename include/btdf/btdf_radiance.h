/* SPDX-License-Identifier: MIT */
/* btdf_radiance.h: WINDOW/Radiance BSDF XML (TensorTree3 or Klems) built from Eq. 25,
   written by btdf_write to a .xml path (docs/radiance.md). */
#ifndef BTDF_RADIANCE_H_PUBLIC
#define BTDF_RADIANCE_H_PUBLIC

#include <stddef.h>
#include <stdint.h>

#include "btdf.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * The file's blocks, as Radiance uses them. Radiance traces from the eye: for a view
 * direction p and a light direction q on opposite sides it takes the block loaded for
 * p's side and looks it up with p as the incident direction (the reciprocity of a thin
 * surface in air). Eq. 25 is not reciprocal in that plain sense
 * (rho(n; q -> p) = n^2 rho(1/n; p -> q)), so each block holds what a render needs:
 *   block 0 "Transmission Front" (p on -Z; light from +Z, leaving the dense side, 1/n);
 *   block 1 "Transmission Back"  (p on +Z; light from -Z, entering it, index n);
 *   block 2 "Reflection Front"   (p and light on -Z, outside: rho_r(n));
 *   block 3 "Reflection Back"    (p and light on +Z, inside: rho_r(1/n)).
 * The BSDF material's surface normal (+Z) points into the dense medium.
 */
typedef struct btdf_rad btdf_rad;

typedef enum {
    BTDF_RAD_TREE3 = 0,        /* TensorTree3 (Shirley-Chiu), adaptive, to a tolerance */
    BTDF_RAD_KLEMS_FULL = 1,   /* 145 x 145 patch-pair averages */
    BTDF_RAD_KLEMS_HALF = 2,   /* 77 x 77 */
    BTDF_RAD_KLEMS_QUARTER = 3 /* 41 x 41 */
} btdf_rad_basis;

/* "tree3", "klems-full", "klems-half", "klems-quarter": 1 and *b set, or 0. */
BTDF_API int btdf_rad_basis_parse(const char *s, btdf_rad_basis *b);
BTDF_API const char *btdf_rad_basis_name(btdf_rad_basis b);

/* Builds the blocks. tree3: the two transmission and two reflection
   blocks, leaves whose e_L1 (MODEL.md 6) as Radiance reads them meets tolerance
   ([1e-3, 0.5]) for light up to BTDF_RAD_TI_CHECKED_DEG, checked by estimates of its
   own; Klems: the same four blocks, exact patch averages (tolerance ignored).
   threads: 0 = all cores; the result does not depend on it. BTDF_OK; BTDF_EBUDGET when the tolerance could not be met (*out holds the best
   file); BTDF_EINVAL (parameters, two channels, tolerance); BTDF_ENOMEM.
   Three channels: per block CIE X, Y, Z matrices (Klems) or a tree of CIE Y with trees
   of u', v' of its structure, split where any channel needs it (docs/radiance.md
   "Colour"). */
#define BTDF_RAD_TI_CHECKED_DEG 80.0
BTDF_API btdf_status btdf_rad_build(const btdf_params *p, btdf_rad_basis basis,
                                    double tolerance, int threads, btdf_rad **out, char *msg,
                                    size_t msglen);
/* btdf_rad_build with a progress callback (btdf/btdf.h), called from the calling thread
   before each block's build pass; progress may be NULL. */
BTDF_API btdf_status btdf_rad_build_progress(const btdf_params *p, btdf_rad_basis basis,
                                             double tolerance, int threads,
                                             btdf_progress_fn progress, void *user,
                                             btdf_rad **out, char *msg, size_t msglen);
BTDF_API void btdf_rad_free(btdf_rad *r);

typedef struct btdf_rad_block_info {
    const char *label;  /* "Transmission Front" */
    btdf_side light;    /* the light the block serves: ENTER (from -Z) or LEAVE */
    double n_light;     /* its index */
    size_t values;      /* tree leaves, or Klems entries */
    int depth;          /* deepest tree level (0 for Klems) */
} btdf_rad_block_info;

BTDF_API int btdf_rad_block_count(const btdf_rad *r);
/* 1 (a Visible, CIE Y, file) or 3 (colour: R, G, B in Radiance's RGB, written as CIE
   X, Y, Z, or a tree's Y, u', v'; docs/radiance.md "Colour"). */
BTDF_API int btdf_rad_channels(const btdf_rad *r);
/* Radiance's RGB (its default primaries, equal-energy white) to CIE XYZ:
   m[X, Y, Z][R, G, B]. */
BTDF_API void btdf_rad_rgb_to_xyz(double m[3][3]);
BTDF_API btdf_status btdf_rad_block(const btdf_rad *r, int k, btdf_rad_block_info *info);
BTDF_API btdf_rad_basis btdf_rad_get_basis(const btdf_rad *r);
/* The material the file was built for (a file read back: from its Comments). */
BTDF_API const btdf_params *btdf_rad_get_params(const btdf_rad *r);
BTDF_API double btdf_rad_seconds_build(const btdf_rad *r);

/* What Radiance's library returns from block k for p on the block's side (the view)
   and q on the other (the light): unit vectors in Radiance's local frame (z the
   surface normal, y up), pointing away from the surface. 0 off the block. */
BTDF_API double btdf_rad_lookup(const btdf_rad *r, int k, const double p[3],
                                const double q[3]);
/* The same for the file's CIE X, Y, Z (one channel: Y three times), and for channel c
   (0, 1, 2: R, G, B) recovered from them (one channel: c = 0 only; 0 otherwise). */
BTDF_API void btdf_rad_lookup_xyz(const btdf_rad *r, int k, const double p[3],
                                  const double q[3], double xyz[3]);
BTDF_API double btdf_rad_lookup_channel(const btdf_rad *r, int k, int c, const double p[3],
                                        const double q[3]);

/* What a render gets for light of the given side (ENTER: from -Z, LEAVE: from +Z) in
   that light's MODEL.md frame (ti in [0, pi/2], to in [pi/2, pi], phi): the block of
   the view's side at (p = view, q = light), channel c (-1: Y; 0..2: R, G, B of a colour
   file). Compare with rho(n_light; ti, to, phi). */
BTDF_API double btdf_rad_render(const btdf_rad *r, btdf_side light, int c, double ti,
                                double to, double phi);

/* The model's value that block k serves, for channel c (0 for one channel): what
   btdf_rad_render (or the reflection block's lookup) is compared with. Transmission:
   rho(n_light; ti, to, phi), to in [pi/2, pi]; reflection: rho_r(n_light; ti, tr, phi).
   Model full: with the tallies the builder made (a file read back keeps none: 0). */
BTDF_API double btdf_rad_model_rho(const btdf_rad *r, int k, int c, double ti, double to,
                                   double phi);

/* Reads a file btdf_write wrote as .xml (TensorTree3 or Klems, one channel or colour)
   from len bytes at data: the material's parameters from its Comments, each block's
   tree or matrix, the name and the stored errors. Anything else is refused
   (BTDF_EFORMAT, msg naming the first thing wrong); BTDF_EINVAL for NULL pointers,
   BTDF_ENOMEM. Free *out with btdf_rad_free. */
BTDF_API btdf_status btdf_rad_read_mem(const void *data, size_t len, btdf_rad **out,
                                       char *msg, size_t msglen);

/* The error (MODEL.md 6) of what a render gets from block k against Eq. 25 (rho_r
   for a reflection block, R for T) for the light it serves, at test_angles incidences over 0-90 deg (0 = 48) with about
   points_per_angle points (0 = 8192). rep->met: the tolerance holds up to
   BTDF_RAD_TI_CHECKED_DEG. Clear rep with btdf_report_clear. */
BTDF_API btdf_status btdf_rad_report(const btdf_rad *r, int k, size_t test_angles,
                                     size_t points_per_angle, uint64_t seed, int threads,
                                     btdf_report *rep);
/* The same for channel c of a three-channel file (R, G, B recovered from the file's
   X, Y, Z, against Eq. 25 at that channel's index); btdf_rad_report is channel 0. */
BTDF_API btdf_status btdf_rad_report_channel(const btdf_rad *r, int k, int c,
                                             size_t test_angles, size_t points_per_angle,
                                             uint64_t seed, int threads, btdf_report *rep);
/* The largest per-angle e_L1 of a report up to BTDF_RAD_TI_CHECKED_DEG. */
BTDF_API double btdf_rad_e_l1_checked(const btdf_report *rep);

/* What the file's descriptive fields say: the material name, and per block the
   reported e_L1 and e_T (set both before writing; unset: not written). */
BTDF_API void btdf_rad_set_name(btdf_rad *r, const char *name);
BTDF_API void btdf_rad_set_errors(btdf_rad *r, int k, double e_l1, double e_t);

/* A file of a caller's BSDF in place of Eq. 25 (the system of a pane, btdf_pane.h):
   eval(user, k, ti, to, phi) is what block k (above: 0 transmission of light from +Z,
   1 from -Z, 2 reflection on -Z, 3 on +Z) serves, light at ti from its side's normal,
   view at to from the view side's normal (both [0, pi/2]), phi of btdf.h; 1/sr without
   a cosine, reciprocal air to air. specular(user, k, ti) (may be NULL) is a delta's
   weight in the mirror or straight-through direction, put on the diagonal (Klems) or in
   the leaf holding that direction (tree). Klems: 3 x 3 Gauss points over every patch
   pair; tree3: a full tree of `depth` levels, each leaf the value at its centre. p gives
   n for the frame and the Comments: one channel, or three for the Klems bases (user_ch;
   BTDF_ENOTSUP for a colour tree). */
typedef struct btdf_rad_source {
    void *user;
    double (*eval)(void *user, int k, double ti, double to, double phi);
    double (*specular)(void *user, int k, double ti);
    /* may be NULL: eval at count azimuths for one (ti, to), into out (faster Klems) */
    void (*eval_phis)(void *user, int k, double ti, double to, size_t count,
                      const double *phi, double *out);
    const char *description; /* the file's account of itself, e.g. the pane; may be NULL */
    /* Three channels (p->channels == 3, the Klems bases): each callback is called with
       user_ch[c] for channel c (n = p->ior[c]), and the file holds CIE X, Y, Z made
       from the three, as an interface's colour Klems file does. Unused (NULL) for one
       channel. */
    void *user_ch[3];
    /* tree3: 0 keeps the full tree; merge (up to 0.5) > 0 makes it adaptive, bottom up:
       8 sibling leaves whose full-tree leaves are all within merge * max(|mean|,
       0.01 / pi) of their mean become one leaf of that mean (0.01 / pi: MODEL.md 6's
       floor of T, as a diffuse value), so no value moves by more than that bound from
       the full tree's and the tree keeps its integral */
    double merge;
} btdf_rad_source;
#define BTDF_RAD_SOURCE_DEPTH_MAX 7
BTDF_API btdf_status btdf_rad_build_source(const btdf_rad_source *s, const btdf_params *p,
                                           btdf_rad_basis basis, int depth, int threads,
                                           btdf_rad **out, char *msg, size_t msglen);

#ifdef __cplusplus
}
#endif

#endif
