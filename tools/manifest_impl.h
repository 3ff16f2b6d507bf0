/* SPDX-License-Identifier: MIT */
/* manifest_impl.h: a scene manifest as read (manifest_read.c) and run (manifest.c): its
   materials, their keys and outputs; private to the two. */
#ifndef MANIFEST_IMPL_H
#define MANIFEST_IMPL_H

#include <stddef.h>

#include <btdf/btdf.h>
#include <btdf/btdf_radiance.h>

#include "pane_write.h"

#define MAX_MATERIALS 64
#define MAX_OUTPUTS 8
#define NKEYS 19

typedef struct material {
    char name[64];
    btdf_params p;
    double ti0, ti1, tol;
    btdf_metric metric;
    int sides; /* btdf_side */
    btdf_part part; /* of the enter and leave tables */
    int has_ior, has_s;
    char *enter[MAX_OUTPUTS], *leave[MAX_OUTPUTS], *bsdf[MAX_OUTPUTS], *xml[MAX_OUTPUTS];
    char *grid[MAX_OUTPUTS]; /* a pane's grids */
    int nenter, nleave, nbsdf, nxml, ngrid;
    size_t grid_n[3];     /* key grid_size: NI, NO, NPHI */
    btdf_rad_basis basis; /* of the .xml outputs */
    pane_spec pane;       /* keys back, thickness, absorption (key_line[K_BACK]: a pane) */
    int line;          /* of the [name] header */
    int key_line[NKEYS];  /* of each key (KEYS order), 0 if not given */
} material;

/* The keys of a section (manifest_keys in manifest_read.c), in the order of
   material.key_line. */
enum { K_IOR, K_S, K_K0, K_THETA, K_TOL, K_METRIC, K_SIDES, K_ENTER, K_LEAVE, K_BSDF, K_PART,
       K_MODEL, K_XML, K_BASIS, K_BACK, K_THICK, K_ABS, K_GRID, K_GRID_SIZE };

/* The number of outputs of m. */
static inline int n_outputs(const material *m)
{
    return m->nenter + m->nleave + m->nbsdf + m->nxml + m->ngrid;
}

/* Output k of m in manifest order (enter, leave, bsdf, xml, grid) and its key. */
static inline const char *output_at(const material *m, int k, int *key)
{
    if (k < m->nenter)
        return *key = K_ENTER, m->enter[k];
    k -= m->nenter;
    if (k < m->nleave)
        return *key = K_LEAVE, m->leave[k];
    k -= m->nleave;
    if (k < m->nbsdf)
        return *key = K_BSDF, m->bsdf[k];
    k -= m->nbsdf;
    if (k < m->nxml)
        return *key = K_XML, m->xml[k];
    return *key = K_GRID, m->grid[k - m->nxml];
}

typedef struct manifest {
    material m[MAX_MATERIALS];
    int n;
    char why[512]; /* reason for the first error */
    int why_line;  /* its line when not the line being read */
    char dir[4096]; /* the manifest's folder with a final '/', or "" for the current one */
} manifest;

/* ini_read's callback: one key of a section, or a section's header; 0 with mf->why set
   at an error. */
int manifest_on_entry(void *user, const char *section, const char *key, const char *value,
                      int line);
/* 0 with mf->why and why_line set when the last section is empty. */
int manifest_check_not_empty(manifest *mf);
/* Frees the output lists of every material. */
void manifest_free(manifest *mf);

#endif
