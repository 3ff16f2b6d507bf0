/* SPDX-License-Identifier: MIT */
/* surface.c: Gaussian random height fields by spectral filtering of white noise.

   A field h = g * w (periodic convolution of white noise w of unit variance with
   g(r) = exp(-2 r^2 / tau^2)) has covariance (g * g)(r), and the convolution of two
   such Gaussians is proportional to exp(-r^2 / tau^2): the autocorrelation
   C(r) = sigma^2 exp(-r^2 / tau^2) asked for. Its variance is sum g^2 exactly on the
   grid, so dividing by sqrt(sum g^2) makes the ensemble sigma 1. The convolution is
   done with one real FFT of the noise and the precomputed transform of g. */
#include "sim/surface.h"

#include <fftw3.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim/rng.h"

struct sim_gen {
    int n;
    int rows;           /* n for a square tile, 1 for a profile's strip */
    double dx, tau;
    double scale;       /* 1 / (rows n sqrt(sum g^2)): FFTW's round trip is rows n times */
    double *real;       /* rows * n, for planning and the filter */
    fftw_complex *spec; /* rows * (n/2 + 1) */
    fftw_complex *kern; /* transform of g */
    fftw_plan fwd, inv;
};

struct sim_scratch {
    int n;
    double *real;
    fftw_complex *spec;
};

size_t sim_scratch_bytes(int n, int rows)
{
    return (size_t)rows * (size_t)n * sizeof(double) +
           (size_t)rows * (size_t)(n / 2 + 1) * sizeof(fftw_complex) + 64;
}

sim_scratch *sim_scratch_new(const sim_gen *g)
{
    sim_scratch *w = calloc(1, sizeof *w);
    if (!w)
        return NULL;
    int n = g->n;
    w->n = n;
    /* fftw_malloc: the alignment the plans were made for */
    w->real = fftw_malloc((size_t)g->rows * (size_t)n * sizeof *w->real);
    w->spec = fftw_malloc((size_t)g->rows * (size_t)(n / 2 + 1) * sizeof *w->spec);
    if (!w->real || !w->spec) {
        sim_scratch_free(w);
        return NULL;
    }
    return w;
}

void sim_scratch_free(sim_scratch *w)
{
    if (!w)
        return;
    fftw_free(w->real);
    fftw_free(w->spec);
    free(w);
}

void sim_gen_free(sim_gen *g)
{
    if (!g)
        return;
    if (g->fwd)
        fftw_destroy_plan(g->fwd);
    if (g->inv)
        fftw_destroy_plan(g->inv);
    fftw_free(g->real);
    fftw_free(g->spec);
    fftw_free(g->kern);
    free(g);
}

static sim_gen *gen_new(int n, int rows, double dx, double tau)
{
    sim_gen *g = calloc(1, sizeof *g);
    if (!g)
        return NULL;
    size_t nr = (size_t)rows * (size_t)n, nc = (size_t)rows * (size_t)(n / 2 + 1);
    g->n = n;
    g->rows = rows;
    g->dx = dx;
    g->tau = tau;
    g->real = fftw_malloc(nr * sizeof *g->real);
    g->spec = fftw_malloc(nc * sizeof *g->spec);
    g->kern = fftw_malloc(nc * sizeof *g->kern);
    if (!g->real || !g->spec || !g->kern) {
        sim_gen_free(g);
        return NULL;
    }
    /* FFTW_ESTIMATE: the plan, and so every bit of the result, does not depend on
       timings of this machine. */
    if (rows == 1) {
        g->fwd = fftw_plan_dft_r2c_1d(n, g->real, g->spec, FFTW_ESTIMATE);
        g->inv = fftw_plan_dft_c2r_1d(n, g->spec, g->real, FFTW_ESTIMATE);
    } else {
        g->fwd = fftw_plan_dft_r2c_2d(n, n, g->real, g->spec, FFTW_ESTIMATE);
        g->inv = fftw_plan_dft_c2r_2d(n, n, g->spec, g->real, FFTW_ESTIMATE);
    }
    if (!g->fwd || !g->inv) {
        sim_gen_free(g);
        return NULL;
    }
    double sum2 = 0.0, a = 2.0 * dx * dx / (tau * tau);
    for (int j = 0; j < rows; j++) {
        int dj = j < n - j ? j : n - j; /* periodic distance (0 for a strip) */
        for (int i = 0; i < n; i++) {
            int di = i < n - i ? i : n - i;
            double v = exp(-a * (double)(di * di + dj * dj));
            g->real[(size_t)j * (size_t)n + (size_t)i] = v;
            sum2 += v * v;
        }
    }
    fftw_execute(g->fwd);
    memcpy(g->kern, g->spec, nc * sizeof *g->kern);
    /* sum2 >= 1 (the g(0) = 1 term), so the root is safe. */
    g->scale = 1.0 / ((double)nr * sqrt(sum2));
    return g;
}

sim_gen *sim_gen_new(int n, double dx, double tau)
{
    return gen_new(n, n, dx, tau);
}

sim_gen *sim_gen_new_profile(int n, double dx, double tau)
{
    return gen_new(n, 1, dx, tau);
}

size_t sim_surface_bytes(int n, int rows)
{
    size_t nn = (size_t)rows * (size_t)n;
    /* heights, cell bounds (two arrays), upper levels (at most a third more) */
    return nn * sizeof(double) * 3 + nn * sizeof(double) * 2 / 3 + 256;
}

void sim_surface_free(sim_surface *s)
{
    if (!s)
        return;
    free(s->h);
    for (int k = 0; k < SIM_MAX_LEVELS; k++) {
        free(s->lo[k]);
        free(s->hi[k]);
    }
    memset(s, 0, sizeof *s);
}

/* Level 0 from the heights, level k from 4 x 4 units of level k - 1; a strip has
   level 0 only. */
static int build_bounds(sim_surface *s)
{
    int n = s->n, rows = (int)s->ymask + 1;
    s->levels = 0;
    for (int k = 0; k < SIM_MAX_LEVELS; k++) {
        int sh = 2 * k, side = n >> sh;
        if (k > 0 && (side < 2 || rows == 1))
            break;
        int side_y = rows == 1 ? 1 : side;
        size_t m = (size_t)side * (size_t)side_y;
        s->lo[k] = malloc(m * sizeof(double));
        s->hi[k] = malloc(m * sizeof(double));
        if (!s->lo[k] || !s->hi[k])
            return -1;
        s->shift[k] = sh;
        s->levels = k + 1;
        for (int j = 0; j < side_y; j++)
            for (int i = 0; i < side; i++) {
                double lo = INFINITY, hi = -INFINITY;
                if (k == 0) {
                    for (int c = 0; c < 4; c++) {
                        int ii = (i + (c & 1)) & (n - 1), jj = (j + (c >> 1)) & (rows - 1);
                        double v = s->h[(size_t)jj * (size_t)n + (size_t)ii];
                        lo = v < lo ? v : lo;
                        hi = v > hi ? v : hi;
                    }
                } else {
                    int cs = side * 4;
                    for (int c = 0; c < 16; c++) {
                        size_t q = (size_t)(4 * j + (c >> 2)) * (size_t)cs +
                                   (size_t)(4 * i + (c & 3));
                        lo = s->lo[k - 1][q] < lo ? s->lo[k - 1][q] : lo;
                        hi = s->hi[k - 1][q] > hi ? s->hi[k - 1][q] : hi;
                    }
                }
                s->lo[k][(size_t)j * (size_t)side + (size_t)i] = lo;
                s->hi[k][(size_t)j * (size_t)side + (size_t)i] = hi;
            }
    }
    return 0;
}

/* The realisation's statistics; dd is scratch for rows * n doubles. */
static void measure(const sim_surface *s, int profile, double *dd, sim_surface_stats *st)
{
    int n = s->n, rows = (int)s->ymask + 1;
    size_t nn = (size_t)rows * (size_t)n;
    double mean = 0.0, var = 0.0, sl = 0.0;
    for (size_t q = 0; q < nn; q++)
        mean += s->h[q];
    mean /= (double)nn;
    for (size_t q = 0; q < nn; q++)
        dd[q] = s->h[q] - mean;
    for (int j = 0; j < rows; j++)
        for (int i = 0; i < n; i++) {
            int i1 = (i + 1) & (n - 1), j1 = (j + 1) & (rows - 1);
            double h00 = s->h[(size_t)j * n + i], h10 = s->h[(size_t)j * n + i1];
            double h01 = s->h[(size_t)j1 * n + i], h11 = s->h[(size_t)j1 * n + i1];
            double d = dd[(size_t)j * n + i];
            var += d * d;
            /* the two triangles' gradients (see trace.c), in height per grid unit */
            double b1 = h10 - h00, c1 = h11 - h10, b2 = h11 - h01, c2 = h01 - h00;
            sl += 0.5 * (b1 * b1 + c1 * c1 + b2 * b2 + c2 * c2);
        }
    st->rms_height = sqrt(var / (double)nn);
    st->rms_slope = sqrt(sl / (double)nn) / s->dx;
    /* Autocorrelation along x and y at integer lags, until it drops below 1/e. Four
       lags are summed at once, each over the points in the same order as alone (so
       each sum is the same to the bit), which lets their four chains of additions run
       side by side; the lags after the crossing are left unused. */
    double c0 = var / (double)nn, prev = 1.0, len = NAN;
    for (int k0 = 1; k0 < n / 2 && !isfinite(len); k0 += 4) {
        double acc[4] = {0.0, 0.0, 0.0, 0.0};
        for (int j = 0; j < rows; j++) {
            const double *row = dd + (size_t)j * n;
            for (int i = 0; i < n; i++) {
                double d = row[i];
                for (int c = 0; c < 4; c++) {
                    int k = k0 + c;
                    double ax = d * row[(i + k) & (n - 1)];
                    acc[c] += ax;
                    /* a profile is constant along y: only its x lags say anything */
                    acc[c] += profile ? ax : d * dd[(size_t)((j + k) & (n - 1)) * n + i];
                }
            }
        }
        for (int c = 0; c < 4 && k0 + c < n / 2; c++) {
            int k = k0 + c;
            /* c0 > 0 for any realisation of nonzero noise; the guard keeps 0 out */
            double r = c0 > 0.0 ? acc[c] / (2.0 * (double)nn * c0) : 0.0;
            if (r < exp(-1.0)) {
                /* linear between the lags; prev > 1/e > r, so prev - r > 0 */
                len = ((double)(k - 1) + (prev - exp(-1.0)) / (prev - r)) * s->dx;
                break;
            }
            prev = r;
        }
    }
    st->corr_length = isfinite(len) ? len : 0.0;
}

int sim_gen_surface(const sim_gen *g, sim_scratch *w, uint64_t stream, sim_surface *s,
                    sim_surface_stats *st)
{
    int n = g->n;
    size_t nn = (size_t)g->rows * (size_t)n, nc = (size_t)g->rows * (size_t)(n / 2 + 1);
    memset(s, 0, sizeof *s);
    s->n = n;
    s->ymask = (uint64_t)g->rows - 1u;
    s->dx = g->dx;
    for (s->log2n = 0; (1 << s->log2n) < n; s->log2n++)
        ;
    s->h = malloc(nn * sizeof *s->h);
    if (!s->h)
        return -1;
    uint64_t rs = stream;
    for (size_t q = 0; q + 1 < nn; q += 2)
        sim_gauss2(&rs, &w->real[q], &w->real[q + 1]);
    fftw_execute_dft_r2c(g->fwd, w->real, w->spec);
    for (size_t q = 0; q < nc; q++) {
        double ar = w->spec[q][0], ai = w->spec[q][1];
        double br = g->kern[q][0], bi = g->kern[q][1];
        w->spec[q][0] = ar * br - ai * bi;
        w->spec[q][1] = ar * bi + ai * br;
    }
    fftw_execute_dft_c2r(g->inv, w->spec, w->real);
    s->hmin = INFINITY;
    s->hmax = -INFINITY;
    for (size_t q = 0; q < nn; q++) {
        double v = w->real[q] * g->scale;
        s->h[q] = v;
        s->hmin = v < s->hmin ? v : s->hmin;
        s->hmax = v > s->hmax ? v : s->hmax;
    }
    if (build_bounds(s) != 0) {
        sim_surface_free(s);
        return -1;
    }
    if (st)
        measure(s, 0, w->real, st);
    return 0;
}

int sim_gen_profile(const sim_gen *g, sim_scratch *w, uint64_t stream, sim_surface *s,
                    sim_surface_stats *st)
{
    /* g is a strip's generator: the profile z = h(x), one row of cells whose row
       j + 1 is row j itself (ymask 0), so the triangles slope along x only and a ray
       in an x-z plane stays in it */
    if (sim_gen_surface(g, w, stream, s, NULL) != 0)
        return -1;
    if (st)
        measure(s, 1, w->real, st);
    return 0;
}
