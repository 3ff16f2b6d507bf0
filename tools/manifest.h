/* SPDX-License-Identifier: MIT */
/* manifest.h: `btdftab build`: reads a scene manifest and builds its stale outputs. */
#ifndef BTDFTAB_MANIFEST_H
#define BTDFTAB_MANIFEST_H

#include <btdf/btdf.h>

typedef struct manifest_opts {
    const char *prog, *path;
    int force, quiet, progress, best_effort, threads;
} manifest_opts;

/* Runs a manifest; returns the exit status (0, 1 failed run, 2 bad manifest, 3 budget). */
int manifest_run(const manifest_opts *mo);

#endif
