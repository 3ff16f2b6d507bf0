/* SPDX-License-Identifier: MIT */
/* simulate_out.h: what cmd_simulate.c shares with simulate_out.c, its writers of the
   outgoing distribution (CSV, EXR) and of the --preview chart. */
#ifndef BTDFTAB_SIMULATE_OUT_H
#define BTDFTAB_SIMULATE_OUT_H

#include <stdarg.h>

#include <btdf/btdf_sim.h>

#define MAX_ANGLES 1000
#define DEG (3.14159265358979323846 / 180.0)

extern double deg_given[MAX_ANGLES]; /* the angles as given, for the report */
extern int profile_1d;               /* --profile 1d: bins measure radians of theta_o */

/* "PROG: simulate: " and the message on standard error; returns code */
int simulate_vfail(int code, const char *fmt, va_list ap);

/* Each returns 0, or the exit status after its message; a failure leaves no file. */
int write_dist(const char *path, const char *prov, const btdf_sim_opts *o,
               const btdf_sim_result *r);
int write_dist_exr(const char *path, const char *prov, const btdf_sim_opts *o,
                   const btdf_sim_result *r);
int write_preview(const char *path, const btdf_sim_result *r);

#endif
