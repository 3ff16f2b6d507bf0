/* SPDX-License-Identifier: MIT */
/* bench.h: what the benchmark's files share: the clocks, the median, Eq. 25's inner
   loop on one ti, and the sections kept in bench_api.c and bench_sim.c. */
#ifndef BTDF_TOOLS_BENCH_H
#define BTDF_TOOLS_BENCH_H

#include <stddef.h>
#include <stdio.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* wall seconds (CLOCK_MONOTONIC) and CPU seconds of this process, all threads */
double now(void);
double cpu_now(void);
/* the median of v[0..n), sorted in place */
double median(double *v, int n);

/* Eq. 25 at n = 1.5, s = 3 over a (to, phi) grid for the i-th of NI incidences */
typedef struct eval_job {
    double *buf, *cph, *sph;
    size_t NI, NO, NP;
} eval_job;
void eval_slice(void *arg, size_t i);

void api_bench(int reps);             /* bench_api.c */
void bench_full(FILE *out, int reps); /* bench_api.c */
void bench_sim(FILE *f, int reps);    /* bench_sim.c */
void bench_simhit(FILE *f, int reps); /* bench_sim.c */

#endif
