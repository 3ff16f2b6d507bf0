/* SPDX-License-Identifier: MIT */
/* manifest.h: `btdftab build`: reads a scene manifest and builds its stale outputs. */
#ifndef BTDFTAB_MANIFEST_H
#define BTDFTAB_MANIFEST_H

#include <btdf/btdf.h>

typedef struct manifest_opts {
    const char *prog, *path;
    int force, quiet, progress, best_effort, threads;
    int dry_run;          /* list what would be built and why, build nothing */
    int shard_k, shard_n; /* build jobs k-1, k-1+n, ... only (n <= 1: all) */
} manifest_opts;

/* Runs a manifest; returns the exit status (0, 1 failed run, 2 bad manifest, 3 budget). */
int manifest_run(const manifest_opts *mo);

#endif
