/* SPDX-License-Identifier: MIT */
/* radiance.h: WINDOW/Radiance BSDF data in memory (tensor tree and Klems matrices), built
   from Eq. 25 and read back by Radiance's own lookup rule. No bytes here: formats/xml.c
   writes the file. */
#ifndef BTDF_RADIANCE_H
#define BTDF_RADIANCE_H

#include <stddef.h>
#include <stdint.h>

#include "btdf.h"
#include "btdf_radiance.h"

/*
 * Sides and Radiance's frame (docs/radiance.md). The BSDF material's surface normal
 * (Radiance +Z) points into the dense medium; light from -Z enters it (index n), light
 * from +Z leaves it (index 1/n).
 *
 * How Radiance uses the blocks (measured with rtrace and its BSDF query): it traces
 * from the eye, and for a view direction p and a light direction q on opposite sides it
 * takes the block loaded for p's side ("Transmission Front" for p on -Z, "Transmission
 * Back" for p on +Z) and looks it up with p as the incident direction and q as the
 * outgoing one, the reciprocity of a thin surface in air. Eq. 25 is not reciprocal in
 * that plain sense: rho(n; q -> p) = n^2 rho(1/n; p -> q) (MODEL.md 4). So that a
 * render gets the BTDF of the light's direction, each block holds, with p as incident:
 *   block 0: "Transmission Front" (p on -Z, light from +Z leaving, index 1/n):
 *            rho(1/n; q -> p) = rho(n; p -> q) / n^2;
 *   block 1: "Transmission Back"  (p on +Z, light from -Z entering, index n):
 *            rho(n; q -> p) = n^2 rho(1/n; p -> q).
 * Reflection (rho_r is reciprocal, so no swap and no scale):
 *   block 2: "Reflection Front" (p and q on -Z, outside): rho_r(n);
 *   block 3: "Reflection Back"  (p and q on +Z, inside the dense medium): rho_r(1/n).
 *
 * Values are BTDF in 1/sr without a cosine factor (MODEL.md section 1).
 */
typedef btdf_rad_basis rad_basis;
#define RAD_BASIS_TREE3 BTDF_RAD_TREE3
#define RAD_BASIS_KLEMS_FULL BTDF_RAD_KLEMS_FULL
#define RAD_BASIS_KLEMS_HALF BTDF_RAD_KLEMS_HALF
#define RAD_BASIS_KLEMS_QUARTER BTDF_RAD_KLEMS_QUARTER

#define RAD_MAX_BLOCKS 4 /* two transmissions, two reflections */

/* One tensor-tree node: a constant leaf (child < 0) or 8 children stored at
   nodes[child .. child + 7], child index bit d set = upper half of dimension d. */
typedef struct rad_node {
    int32_t child;
    float v; /* the leaf value exactly as written to the file (CIE Y in colour) */
} rad_node;

/* Floats per node of a colour tree (rad_block.cv): R, G, B, u', v'. */
#define RAD_CV 5

/* A Klems angle basis: nbands theta bands, band k from theta[k] to theta[k + 1]
   (degrees) with nphi[k] patches. */
typedef struct rad_klems_basis {
    const char *name; /* "LBNL/Klems Full" */
    int nbands;
    const double *theta; /* nbands + 1 bounds */
    const int *nphi;
    int npatch;
} rad_klems_basis;

typedef struct rad_block {
    btdf_side side;      /* the tree's own geometry: ENTER (p on -Z) or LEAVE (p on +Z) */
    const char *label;   /* "Transmission Front" */
    double n;            /* index of the tree's own geometry, p as incident */
    double scale;        /* values are scale * rho(n; p -> q) */
    int reflect;         /* 1: a reflection block, rho_r(n) for p and q on its side */
    btdf_side light;     /* the light this block serves in a render */
    double n_light;      /* its index: rho(n_light; q -> p) is what a render needs */
    /* TensorTree3 */
    rad_node *nodes;
    size_t nnodes, leaves;
    int depth;
    /* A colour tree (three channels): per node RAD_CV floats, cv[RAD_CV k + c] channel
       c (R, G, B) as the builder chose it, then the CIE u', v' the file holds (with
       nodes[k].v, CIE Y, Radiance reads back these channels: rad_colour_xyz); else NULL */
    float *cv;
    /* Klems: values[out * npatch + in], the file's row-major order: CIE Y ("Visible");
       with three channels also CIE X and Z (NULL for one channel) */
    float *klems;
    float *klems_x, *klems_z;
} rad_block;

struct btdf_rad {
    rad_basis basis;
    btdf_params p;
    double tolerance;
    int channels; /* 1 (Visible only) or 3 (R, G, B: Klems Y, X and Z matrices, or the
                     tree's Y with u', v') */
    double to_rgb[3][3]; /* X, Y, Z -> R, G, B (rad_xyz_to_rgb), for lookups in colour */
    int nblocks;
    rad_block b[RAD_MAX_BLOCKS];
    const rad_klems_basis *kb; /* Klems bases only */
    double seconds_build;
    /* Filled by the caller before writing, for the file's descriptive fields. */
    char name[128];               /* the material's name in the scene */
    char system[512];             /* a caller's BSDF (btdf_rad_build_source): what it is;
                                     "" for Eq. 25's own files */
    int reported;                 /* 1 when e_l1, e_t below hold the blocks' reports */
    double e_l1[RAD_MAX_BLOCKS], e_t[RAD_MAX_BLOCKS];
    /* Model full (p.model): channel c's tally at ior[c] ([c][0]) and at 1 / ior[c]
       ([c][1]), the blocks' two indices; NULL for the other models (and a file read
       back, whose values hold it already). */
    btdf_full *ms[BTDF_MAX_CHANNELS][2];
};

const rad_klems_basis *rad_klems(rad_basis b);
const char *rad_basis_name(rad_basis b);

/* Radiance's own RGB (its default primaries, equal-energy white; docs/radiance.md
   "Colour") to CIE XYZ: m[row X, Y, Z][column R, G, B], and its inverse. */
void rad_rgb_to_xyz(double m[3][3]);
void rad_xyz_to_rgb(double m[3][3]);

/* A colour tree leaf (ttree.c): from the channels rgb as the builder chose them, the
   file's CIE Y (4 digits, as every tree value) and u', v' (floats, written to read back
   exactly: Radiance reads them as floats; rounded to 6 digits they would move a small
   channel of a saturated colour by up to 0.4 %; the white point's where X + 15 Y + 3 Z
   = 0), with m = rad_rgb_to_xyz. */
void rad_colour_leaf(const double m[3][3], const float rgb[3], float *y, float uv[2]);
/* X, Y, Z of a file's (Y, u', v'), as Radiance forms them; 0 for v' <= 0. */
void rad_colour_xyz(double y, double u, double v, double xyz[3]);



/* Block k (0-3, above) for the index nc: label, sides, n, scale, n_light (radiance.c;
   formats/xml.c sets up the blocks of a file it reads with it). */
void rad_block_of(int k, double nc, rad_block *b);

/* The tolerance of a tree is met up to this incidence of the light (80 deg). A light at
   ti is the ring of radius sin ti of the tree's square, so the last 10 degrees lie in
   r > 0.985, where the BTDF changes by orders of magnitude from ring to ring: resolving
   them takes cells of side ~1e-4 there, and the octree halves the view's coordinate
   and the ring's at the same time, so tens of millions of leaves (measured: 39 million
   leaves for e_L1 0.11 at 89 deg, n = 1.5, s = 3). The report still covers 0-90. */
#define RAD_TI_CHECKED (BTDF_RAD_TI_CHECKED_DEG * 3.14159265358979323846 / 180.0)


/* Radiance's concentric square <-> disk maps (Shirley and Chiu 1997), square [0,1)^2. */
void rad_square_to_disk(double a, double b, double *x, double *y);
void rad_disk_to_square(double x, double y, double *a, double *b);

#endif
