/* SPDX-License-Identifier: MIT */
/* dct.c: the builder's cosine transforms (DCT-I from one FFTW real DFT), the one place
   of scatfun/ that includes <fftw3.h>. */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include <fftw3.h>

#include "model/kernel.h"
#include "scatfun/dct.h"

/* ------------------------------------------------------------------------- */
/* Cosine transform on the DCT-I grid phi_j = j pi / N (FFTW's REDFT00)      */
/* ------------------------------------------------------------------------- */

/* The DCT-I of n = N + 1 points, Y_k = x_0 + (-1)^k x_N + 2 sum_{j=1}^{N-1} x_j
   cos(pi j k / N) (FFTW's REDFT00), is computed here from one real DFT of N points.
   FFTW's own REDFT00 allocates a work buffer on every execution (its split-radix
   algorithm), and with the builder's many small series that malloc, with the
   consolidations it set off, was 13% of an s = 20 build. With u_j = (x_j + x_{N-j})/2,
   v_j = x_j - x_{N-j} and f_j = u_j - sin(pi j / N) v_j (f_0 = (x_0 + x_N)/2), the real
   DFT F_m = sum_j f_j e^{-2 pi i j m / N} gives (the v part of Re F_m and the u part of
   Im F_m cancel by symmetry in j <-> N - j; 2 sin(pi j/N) sin(2 pi j m/N) =
   cos(pi j (2m - 1)/N) - cos(pi j (2m + 1)/N)):
     Y_{2m} = 2 Re F_m,   Y_{2m+1} = Y_{2m-1} - 2 Im F_m,
   Y_1 = x_0 - x_N + 2 sum_{j=1}^{N-1} x_j cos(pi j / N) summed directly (the standard
   construction, e.g. Press et al., Numerical Recipes, "cosine transform"). The running
   sum adds at most N/2 terms: its rounding stays near N eps of the largest term.
   Plans (FFTW_R2HC of N points) are made once per length N = 2^k with FFTW_ESTIMATE
   (no timing runs, so the same plan and the same bytes every run) and FFTW_UNALIGNED
   (any array may be passed); the planner is not reentrant, so planning holds a lock,
   and the planner is made thread-safe once for hosts that plan on threads of their
   own. Executing a plan on new arrays is thread-safe. */
static fftw_plan dct_plans[SF_DCT_LOG2_MAX];
static pthread_mutex_t dct_plan_lock = PTHREAD_MUTEX_INITIALIZER;
static pthread_once_t dct_once = PTHREAD_ONCE_INIT;

static void dct_init(void) { fftw_make_planner_thread_safe(); }

int sf_fft_reserve(sf_fftbuf *b, size_t L)
{
    if (b->cap >= L)
        return 0;
    double *in = realloc(b->in, L * sizeof *in);
    if (!in)
        return -1;
    b->in = in;
    double *out = realloc(b->out, L * sizeof *out);
    if (!out)
        return -1;
    b->out = out;
    b->cap = L;
    return 0;
}

void sf_fft_free(sf_fftbuf *b)
{
    free(b->in);
    free(b->out);
    memset(b, 0, sizeof *b);
}

/* The R2HC plan of N points (N a power of two, 2 <= N <= 2^30); NULL if FFTW cannot
   make one (out of memory). */
static fftw_plan dct_plan(sf_fftbuf *b, size_t N)
{
    int k = 0;
    while (((size_t)1 << k) < N)
        k++;
    if (b->plan[k])
        return b->plan[k];
    pthread_once(&dct_once, dct_init);
    pthread_mutex_lock(&dct_plan_lock);
    if (!dct_plans[k]) {
        double *i = fftw_malloc(N * sizeof *i), *o = fftw_malloc(N * sizeof *o);
        if (i && o) /* ESTIMATE plans never touch the arrays */
            dct_plans[k] = fftw_plan_r2r_1d((int)N, i, o, FFTW_R2HC,
                                            FFTW_ESTIMATE | FFTW_UNALIGNED);
        fftw_free(i);
        fftw_free(o);
    }
    b->plan[k] = dct_plans[k];
    pthread_mutex_unlock(&dct_plan_lock);
    return b->plan[k];
}

/* Y[0..N] = the DCT-I of x[0..N] (above); N a power of two, 2 <= N <= nmax; Y may be
   x. 0 on success. */
static int dct1(sf_fftbuf *b, const double *x, size_t N, double *Y)
{
    if (sf_fft_reserve(b, N))
        return -1;
    fftw_plan pl = dct_plan(b, N);
    if (!pl)
        return -1;
    size_t g = b->nmax / N; /* N divides nmax: both powers of two */
    double *f = b->in, *F = b->out;
    double y1 = x[0] - x[N];
    f[0] = 0.5 * (x[0] + x[N]);
    for (size_t j = 1; j < N; j++) {
        double u = 0.5 * (x[j] + x[N - j]), v = x[j] - x[N - j];
        f[j] = u - b->sing[j * g] * v;
        y1 += 2.0 * x[j] * b->cosg[j * g];
    }
    fftw_execute_r2r(pl, f, F); /* halfcomplex: Re F_m at m, Im F_m at N - m */
    size_t h = N / 2;
    for (size_t m = 0; m <= h; m++)
        Y[2 * m] = 2.0 * F[m];
    double odd = y1;
    Y[1] = odd;
    for (size_t m = 1; m < h; m++) {
        odd -= 2.0 * F[N - m];
        Y[2 * m + 1] = odd;
    }
    return 0;
}

/* Declared in scatfun/dct.h: dct1 with tables of its own, for the tests. */
int sf_dct1(const double *x, size_t N, double *Y)
{
    if (N < 2 || (N & (N - 1)) != 0 || N > ((size_t)1 << 20))
        return -1;
    double *cg = malloc((N + 1) * sizeof *cg), *sg = malloc((N + 1) * sizeof *sg);
    sf_fftbuf b;
    memset(&b, 0, sizeof b);
    int r = -1;
    if (cg && sg) {
        for (size_t j = 0; j <= N; j++) {
            cg[j] = cos(M_PI * (double)j / (double)N);
            sg[j] = sin(M_PI * (double)j / (double)N);
        }
        b.cosg = cg;
        b.sing = sg;
        b.nmax = N;
        r = dct1(&b, x, N, Y);
    }
    sf_fft_free(&b);
    free(cg);
    free(sg);
    return r;
}

/* Coefficients a[0..N] with g(phi) = sum a_k cos(k phi) from samples x[0..N] on the
   DCT-I grid (trapezoid rule, exact for degree < N; higher degrees alias). */
int sf_dct_forward(sf_fftbuf *b, const double *x, size_t N, double *a)
{
    if (dct1(b, x, N, a))
        return -1;
    double L = 2.0 * (double)N;
    a[0] /= L;
    for (size_t k = 1; k < N; k++)
        a[k] /= (double)N;
    a[N] /= L;
    return 0;
}

/* Series values y[0..N] at phi_j = j pi / N from coefficients a[0..m-1], m <= N + 1:
   the DCT-I of (a_0, a_1/2, ..., a_{N-1}/2, a_N) is a_0 + (-1)^j a_N + sum a_k cos. */
static int dct_inverse(sf_fftbuf *b, const double *a, size_t m, size_t N, double *y)
{
    for (size_t k = 0; k <= N; k++)
        y[k] = k >= m ? 0.0 : (k == 0 || k == N) ? a[k] : 0.5 * a[k];
    return dct1(b, y, N, y);
}

/* The L1 over the circle of the series a[0..m-1] minus the samples x[0..N] (or of the
   series alone, x = NULL), from the series' values in y[0..N] on the DCT-I grid of N:
   the trapezoid rule over [0, pi], doubled for the circle. -1 when out of memory. */
double sf_series_l1(sf_fftbuf *b, const double *a, size_t m, size_t N, const double *x,
                        double *y)
{
    if (m == 0 && !x)
        return 0.0; /* an empty series alone */
    if (m == 0) { /* an empty series is 0 at every point: the same sum, no transform */
        double sum = 0.5 * fabs(x[0]); /* in the order of the loop below */
        for (size_t j = 1; j < N; j++)
            sum += fabs(x[j]);
        sum += 0.5 * fabs(x[N]);
        return 2.0 * sum * M_PI / (double)N; /* N >= 2 */
    }
    if (dct_inverse(b, a, m, N, y))
        return -1.0;
    double sum = 0.0;
    for (size_t j = 0; j <= N; j++) {
        double d = fabs(x ? y[j] - x[j] : y[j]);
        sum += (j == 0 || j == N) ? 0.5 * d : d;
    }
    return 2.0 * sum * M_PI / (double)N; /* N >= 2 */
}

