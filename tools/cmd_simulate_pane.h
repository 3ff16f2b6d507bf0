/* SPDX-License-Identifier: MIT */
/* cmd_simulate_pane.h: btdftab simulate's pane options (--back, --thickness,
   --absorption, --light) and the pane's lines in the report, the table and the
   summary. */
#ifndef BTDFTAB_CMD_SIMULATE_PANE_H
#define BTDFTAB_CMD_SIMULATE_PANE_H

#include <stdio.h>

#include <btdf/btdf_sim.h>

/* One of the pane's options (an opt_id) with its value into o; -1 to go on, or the
   exit status after a message. */
int simpane_option(const char *prog, int id, const char *v, btdf_sim_opts *o);

/* After every option: the pane's options need --back, and a pane is written as CSV
   and JSON only. -1 to go on, or the exit status after a message. */
int simpane_finish(const char *prog, const btdf_sim_opts *o, const char *dist,
                   const char *preview);

/* The pane's part of the run's fingerprint (nothing without a pane). */
int simpane_fingerprint(const btdf_sim_opts *o, char *out, size_t len);

/* The report's "pane" object and "A", "A_se" (nothing without a pane), each line
   ending with ",\n". */
void simpane_json(FILE *f, const btdf_sim_opts *o, const btdf_sim_result *r);

/* The CSV table's comment line of the pane (nothing without a pane). */
void simpane_csv(FILE *f, const btdf_sim_opts *o);

/* The summary on standard error of case k (a pane only). */
void simpane_summary(FILE *f, const btdf_sim_opts *o, const btdf_sim_tally *t);

#endif
