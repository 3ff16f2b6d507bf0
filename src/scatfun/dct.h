/* SPDX-License-Identifier: MIT */
/* dct.h: the builder's cosine transforms on the DCT-I grid phi_j = j pi / N (dct.c);
   private to scatfun/dct.c and scatfun/build*.c. FFTW's plan type is named by its
   struct so that only dct.c includes <fftw3.h>. */
#ifndef BTDF_SF_DCT_H
#define BTDF_SF_DCT_H

#include <stddef.h>

struct fftw_plan_s; /* fftw_plan, as <fftw3.h> defines it */

#define SF_DCT_LOG2_MAX 31

/* One worker's transform state: work arrays, its copy of the shared plans, and the
   cos/sin tables of the grid its lengths divide. */
typedef struct sf_fftbuf {
    size_t cap;                      /* doubles in in and out */
    double *in, *out;                /* work */
    struct fftw_plan_s *plan[SF_DCT_LOG2_MAX]; /* this worker's copy of the shared plans */
    const double *cosg, *sing;       /* cos and sin of j pi / nmax, j = 0..nmax */
    size_t nmax;                     /* the tables' grid; every N divides it */
} sf_fftbuf;

/* Makes room for L doubles in b's work arrays; 0 on success, -1 when out of memory. */
int sf_fft_reserve(sf_fftbuf *b, size_t L);

/* Frees b's work arrays and zeroes it (the plans are shared and stay). */
void sf_fft_free(sf_fftbuf *b);

/* Coefficients a[0..N] with g(phi) = sum a_k cos(k phi) from samples x[0..N] on the
   DCT-I grid (trapezoid rule, exact for degree < N; higher degrees alias). */
int sf_dct_forward(sf_fftbuf *b, const double *x, size_t N, double *a);

/* The L1 over the circle of the series a[0..m-1] minus the samples x[0..N] (or of the
   series alone, x = NULL), from the series' values in y[0..N] on the DCT-I grid of N.
   -1 when out of memory. */
double sf_series_l1(sf_fftbuf *b, const double *a, size_t m, size_t N, const double *x,
                    double *y);

/* Y[0..N] = the DCT-I of x[0..N], Y_k = x_0 + (-1)^k x_N + 2 sum_{j=1}^{N-1} x_j
   cos(pi j k / N), as the builder computes it (one real DFT of N points); N a power of
   two from 2 to 2^20. 0 on success, -1 for another N or out of memory. For tests. */
int sf_dct1(const double *x, size_t N, double *Y);

#endif /* BTDF_SF_DCT_H */
