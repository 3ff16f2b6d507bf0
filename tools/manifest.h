/* SPDX-License-Identifier: MIT */
/* manifest.h: the scene manifest command of the btdftab tool. */
#ifndef BTDFTAB_MANIFEST_H
#define BTDFTAB_MANIFEST_H

#include "btdf.h"

typedef struct manifest_opts {
    const char *prog, *path;
    int force, quiet, progress, best_effort, threads;
} manifest_opts;

/* Runs a manifest; returns the exit status (0, 1 failed run, 2 bad manifest, 3 budget). */
int manifest_run(const manifest_opts *mo);

/* Builds, reports and writes one .bsdf (btdftab.c); returns an exit status. */
int run_bsdf(const char *path, const btdf_params *p, double tol, int sides, int threads,
             int quiet, int best_effort, const char *prov);

/* Writes the stale .bsdf outputs of one material. */
int manifest_bsdf(const manifest_opts *mo, const char *name, const btdf_params *p, double tol,
                  int sides, char **outs, int nouts, int *done, int total);

#endif
