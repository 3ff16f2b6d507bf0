/* SPDX-License-Identifier: MIT */
/* energy.c: btdf-energy, the model full's R + T as evaluated against its own albedo. */
/*
 * Usage: btdf-energy [--cells N] [--paths K] [--threads T]
 *
 * For n = 1.5 and 1/1.5, s = 0.5, 1, 3, 10 and ti = 30, 60, 80, 85, 89 degrees (the
 * sweep of docs/model.md section 12) it integrates the evaluated model,
 * btdf_full_rho |cos to| over the lower hemisphere and btdf_full_rho_r cos tr over the
 * upper, by a midpoint rule on N x N cells (default 800) in (|cos t|, phi), phi over
 * [0, pi] doubled (the model is even in phi), and prints that R + T beside
 * btdf_full_albedo's (single scattering by quadrature, the rest from the tally) and
 * their difference. Only the public API is used. The last lines give the range of the
 * evaluated R + T and the largest difference; the exit status is 0 (1 if a tally fails).
 *
 * The midpoint rule's own error: the integrand is smooth in (|cos t|, phi) except at
 * the sharp lobes of s = 10 and the critical angle of n < 1, where 800 cells per axis
 * resolve a lobe of some 10 degrees with tens of cells; halving N moves the figures by
 * the amounts the program prints with --cells 400 (docs/model.md quotes both).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <btdf/btdf.h>

#define PI 3.14159265358979323846

/* The integral of the evaluated full at ti (radians), both parts, on n x n cells. */
static void integrate(const btdf_full *f, double ti, int n, double *T, double *R)
{
    double t = 0, r = 0;
    double du = 1.0 / n, dphi = PI / n;
    for (int a = 0; a < n; a++) {
        double mu = (a + 0.5) * du; /* |cos t| of the cell's centre, in (0, 1) */
        double th = acos(mu);
        for (int b = 0; b < n; b++) {
            double phi = (b + 0.5) * dphi;
            t += btdf_full_rho(f, ti, PI - th, phi) * mu;
            r += btdf_full_rho_r(f, ti, th, phi) * mu;
        }
    }
    /* d(omega) = d(mu) d(phi); the factor 2 is the other half of the azimuths */
    *T = 2 * t * du * dphi;
    *R = 2 * r * du * dphi;
}

static int usage(void)
{
    fprintf(stderr, "usage: btdf-energy [--cells N (8 to 4000)] [--paths K (1000 to 1e9)] "
                    "[--threads T (0 to 256)]\n");
    return 2;
}

int main(int argc, char **argv)
{
    int cells = 800, threads = 0;
    unsigned long long paths = BTDF_FULL_PATHS_DEFAULT;
    for (int k = 1; k < argc; k += 2) {
        char *end = NULL;
        if (k + 1 >= argc)
            return usage();
        double v = strtod(argv[k + 1], &end);
        if (!end || *end || v != floor(v)) {
            fprintf(stderr, "btdf-energy: %s '%s': a whole number\n", argv[k], argv[k + 1]);
            return usage();
        }
        if (!strcmp(argv[k], "--cells") && v >= 8 && v <= 4000)
            cells = (int)v;
        else if (!strcmp(argv[k], "--paths") && v >= 1000 && v <= 1e9)
            paths = (unsigned long long)v;
        else if (!strcmp(argv[k], "--threads") && v >= 0 && v <= 256)
            threads = (int)v;
        else
            return usage();
    }
    const double ns[] = {1.5, 1 / 1.5}, ss[] = {0.5, 1, 3, 10};
    const double tis[] = {30, 60, 80, 85, 89};
    double lo = INFINITY, hi = -INFINITY, worst = 0;
    printf("# btdf-energy: %d x %d midpoint cells per hemisphere, %llu walks per angle\n",
           cells, cells, paths);
    printf("n,s,ti_deg,T_eval,R_eval,RT_eval,RT_albedo,difference\n");
    for (int i = 0; i < 2; i++)
        for (int j = 0; j < 4; j++) {
            btdf_full_opts o;
            btdf_full_opts_default(&o);
            o.paths = paths;
            o.threads = threads;
            btdf_full *f = NULL;
            char msg[256];
            if (btdf_full_new(ns[i], ss[j], &o, &f, msg, sizeof msg) != BTDF_OK) {
                fprintf(stderr, "btdf-energy: %s\n", msg);
                return 1;
            }
            for (int k = 0; k < 5; k++) {
                double ti = tis[k] * PI / 180, T, R;
                btdf_full_albedos a;
                if (btdf_full_albedo(f, ti, &a) != BTDF_OK) {
                    fprintf(stderr, "btdf-energy: btdf_full_albedo failed at %g deg\n", tis[k]);
                    btdf_full_free(f);
                    return 1;
                }
                integrate(f, ti, cells, &T, &R);
                double d = (T + R) - (a.T + a.R);
                lo = fmin(lo, T + R);
                hi = fmax(hi, T + R);
                worst = fmax(worst, fabs(d));
                printf("%.6g,%g,%g,%.6f,%.6f,%.6f,%.6f,%+.2e\n", ns[i], ss[j], tis[k], T, R,
                       T + R, a.T + a.R, d);
                fflush(stdout);
            }
            btdf_full_free(f);
        }
    printf("# evaluated R + T in [%.5f, %.5f]; largest |evaluated - albedo| %.1e\n", lo, hi,
           worst);
    return 0;
}
