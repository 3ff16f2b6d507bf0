/* SPDX-License-Identifier: MIT */
/* run.h: work shared by the commands of btdftab (tabulate and build). */
#ifndef BTDFTAB_RUN_H
#define BTDFTAB_RUN_H

#include <btdf/btdf.h>

/* Seed of the reported error estimates; the builders check themselves with others. */
#define REPORT_SEED 20081231u

/* Seconds on a monotonic clock. */
double run_now(void);

/* The words the command line and the manifest share: "enter", "leave", "both" as a
   btdf_side (0 for any other word); "l1", "max" as a metric (0 for any other). */
int run_parse_side(const char *word);
int run_parse_metric(const char *word, btdf_metric *metric);

/* Builds a .bsdf from Eq. 25, reports its error per side on standard error (unless
   quiet) and writes it at path unless the tolerance was missed without best_effort.
   Returns an exit status: 0, 1 failed run, 2 bad parameters, 3 tolerance not met. */
int run_series(const char *prog, const char *path, const btdf_params *p, double tol, int sides,
               int threads, int quiet, int best_effort, const char *prov);

/* Builds a Radiance BSDF (.xml) from Eq. 25 in the given basis, reports each block's
   error as Radiance reads it on standard error (unless quiet), and writes it (and the
   JSON report with probes, if report is not NULL) together, unless a tree missed its
   tolerance without best_effort. Exit status as run_series. */
int run_radiance(const char *prog, const char *path, const char *report, const btdf_params *p,
                 btdf_rad_basis basis, double tol, int threads, int quiet, int best_effort,
                 const char *prov);

#endif
