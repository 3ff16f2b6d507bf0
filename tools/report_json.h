/* SPDX-License-Identifier: MIT */
/* report_json.h: a btdf_report as JSON, the --report file of every output kind. */
#ifndef BTDFTAB_REPORT_JSON_H
#define BTDFTAB_REPORT_JSON_H

#include <stdio.h>

#include <btdf/btdf.h>
#include <btdf/btdf_scatfun.h>

/* A table's report (docs/tables.md): r is the table's first part's, r2 the reflection's
   of a table holding both parts, or NULL. Written atomically at path; 0, or 1 after a
   message "prog: path: why" on standard error. */
int report_json_table(const char *prog, const char *path, const btdf_table_opts *o,
                      btdf_table_kind kind, const btdf_report *r, const char *prov,
                      const btdf_report *r2);

/* A .bsdf's blocks as reports and messages name them, by bit (btdf_scatfun_block). */
extern const char *const report_block_name[4];

/* A .bsdf's report: reps[b] the report of block b (test_angles 0: not held), seconds
   the build's. Written atomically at report; 0, or 1 after a message. */
int report_json_series(const char *prog, const char *report, const btdf_params *p,
                       const btdf_scatfun *f, const btdf_report reps[4], double tol,
                       double seconds, int met, const char *prov);

/* The channels of a three-channel .xml as reports name them. */
extern const char *const report_rad_channel[3];

/* A .xml's report into f: per block the error report, and for the estimate's own
   error the same report at a quarter of the points (coarse; "T_file_coarse"), and
   probes, the directions at which Radiance's lookup must return the value the file
   holds. rep[k * 3 + c], coarse likewise: block k, channel c. */
void report_json_radiance(FILE *f, const btdf_rad *x, const btdf_params *p,
                          const btdf_report *rep, const btdf_report *coarse, const char *prov);

#endif
