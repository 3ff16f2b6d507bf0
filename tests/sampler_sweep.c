/* SPDX-License-Identifier: MIT */
/* sampler_sweep.c: builds .bsdf files over a sweep of materials and drives pbrt-v3's sampling route
   (tests/pbrt_route.h) through each at views on both sides: termination, finite values, and the
   Monte Carlo albedo against T(ti) (+ R(ti) when the file holds reflection). Prints one line per
   case; exit 1 on a failure.
   usage: sampler_sweep [-t TOL] [-n SAMPLES] [-s S1,S2,...] [-c 1|3|13] [-b BLOCKS] [-m 0|1]
                        [-f FILE.bsdf]
   (-b: the blocks built, a btdf_scatfun_block mask, default 3 = transmission; -m 1: pbrt's
   radiance mode, whose e^2 makes the albedo T(q, ti)/q^2 + R(q, ti) for the view's index q,
   default 0 = importance mode, T + R; three-channel files are always compared in radiance mode,
   where their fold factors are right;
   -f: sweep a written one-channel file of n = 1.5 and the first s given, tolerance TOL) */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "btdf.h"
#include "btdf_scatfun.h"
#include "pbrt_route.h"

static double wall(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* A small fixed-seed generator for the azimuth sample (splitmix64). */
static double next_u(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return (double)(z >> 40) / (double)(1ULL << 24); /* a float's 24 bits, in [0, 1) */
}

typedef struct sweep_totals {
    long cases, fail_terminate_double, fail_nonfinite, fail_albedo, float_capped_cases,
        pole_cases;
} sweep_totals;

static int run_file(const btdf_scatfun *f, const btdf_params *p, double tol, long N, int radiance,
                    sweep_totals *tot)
{
    int blocks = btdf_scatfun_sides(f);
    if (btdf_scatfun_channels(f) == 3)
        radiance = 1; /* the fold factors are right on the radiance path only */
    pr_table t;
    if (pr_table_init(&t, f))
        return -1;
    double peak = pr_a0_peak(&t);
    static const double views[] = {0.0, 1e-3, 0.5, 1.0, 30.0, 60.0, 89.0};
    int nch = btdf_scatfun_channels(f);
    for (int side = 0; side < 2; side++) {
        btdf_params q = *p;
        for (int k = 0; k < q.channels; k++)
            q.ior[k] = side == 0 ? p->ior[k] : 1.0 / p->ior[k];
        for (size_t v = 0; v < sizeof views / sizeof views[0]; v++) {
            double th = views[v] * M_PI / 180.0;
            float wo[3] = {(float)sin(th), 0.0f, (float)(side == 0 ? cos(th) : -cos(th))};
            double T[3] = {0, 0, 0}, R[3] = {0, 0, 0};
            btdf_transmittance(&q, th, T);
            /* the blocks whose slow index is the view's side: T_ENTER and R_TOP above */
            int hasT = blocks & (side == 0 ? BTDF_SCATFUN_T_ENTER : BTDF_SCATFUN_T_LEAVE);
            int hasR = blocks & (side == 0 ? BTDF_SCATFUN_R_TOP : BTDF_SCATFUN_R_BOTTOM);
            if (hasR)
                btdf_reflectance(&q, th, R);
            pr_stats st;
            memset(&st, 0, sizeof st);
            double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
            long capped_d = 0;
            uint64_t rng = 0x5eed0000ULL + (uint64_t)v * 2 + (uint64_t)side;
            for (long i = 0; i < N; i++) {
                float u[2];
                u[0] = (float)next_u(&rng);
                /* stratified in the elevation sample, below 1 as a renderer's are */
                u[1] = fminf((float)(((double)i + next_u(&rng)) / (double)N), 1.0f - FLT_EPSILON / 2);
                float wi[3], rgb[3], pdf;
                pr_sample_f(&t, wo, u, radiance, wi, rgb, &pdf, &st);
                double mud;
                int itd;
                if (!pr_sample_mu_d(&t, wo[2], u[1], &mud, &itd))
                    capped_d++;
                double est[3] = {0, 0, 0};
                if (pdf > 0)
                    for (int c = 0; c < 3; c++)
                        est[c] = (double)rgb[c] * fabs((double)wi[2]) / (double)pdf;
                for (int c = 0; c < 3; c++) {
                    sum[c] += est[c];
                    sum2[c] += est[c] * est[c];
                }
            }
            /* On the normal in single precision (cos rounds to 1): outside the nodes, the
               renderer returns no sample; reported, not compared. */
            int pole = fabsf(wo[2]) >= 1.0f;
            int ok_alb = 1;
            char buf[256] = "";
            size_t used = 0;
            for (int c = 0; c < (nch == 1 ? 1 : 3); c++) {
                double mean = sum[c] / (double)N;
                double var = fmax(0.0, sum2[c] / (double)N - mean * mean);
                double se = sqrt(var / (double)N);
                double Tc = nch == 1 ? T[0] : T[c], Rc = nch == 1 ? R[0] : R[c];
                double qc = q.ior[nch == 1 ? 0 : c];
                /* radiance mode: pbrt's e^2 turns the block into the other direction's
                   value, whose albedo is T(q)/q^2 by reciprocity (ior > 0) */
                double sc = radiance ? 1.0 / (qc * qc) : 1.0;
                double want = (hasT ? Tc * sc : 0.0) + (hasR ? Rc : 0.0);
                /* the file's own error per block (e_T <= e_L1 <= tol, relative to
                   max(T, 0.01) and max(R, 0.01)) plus 4 standard errors of the estimate */
                double allow = tol * ((hasT ? fmax(Tc, 0.01) * sc : 0.0) +
                                      (hasR ? fmax(Rc, 0.01) : 0.0)) + 4.0 * se;
                Tc = want;
                int okc = pole || fabs(mean - Tc) <= allow;
                ok_alb &= okc;
                used += (size_t)snprintf(buf + used, sizeof buf - used,
                                         " %c %.5f/%.5f(+-%.1e)%s", nch == 1 ? 'Y' : "RGB"[c],
                                         mean, Tc, allow, okc ? "" : "!");
            }
            int ok = st.nonfinite == 0 && capped_d == 0 && ok_alb;
            printf("s %-6g n %-7.5g ch %d view %s%-5g a0peak %-9.4g float-capped %ld/%ld "
                   "double-capped %ld nonfinite %ld maxit %d/%d%s%s %s\n",
                   p->smoothness, q.ior[q.channels == 3 ? 1 : 0], nch, side ? "-" : "+",
                   views[v], peak, st.capped_mu + st.capped_phi, N, capped_d, st.nonfinite,
                   st.max_iter_mu, st.max_iter_phi, buf, pole ? " (on the normal: no sample)" : "",
                   ok ? "ok" : "FAIL");
            tot->cases++;
            tot->fail_terminate_double += capped_d > 0;
            tot->fail_nonfinite += st.nonfinite > 0;
            tot->fail_albedo += !ok_alb;
            tot->float_capped_cases += st.capped_mu + st.capped_phi > 0;
            tot->pole_cases += pole;
        }
    }
    pr_table_free(&t);
    return 0;
}

int main(int argc, char **argv)
{
    double tol = 1e-2;
    long N = 20000;
    const char *slist = "0.5,1,3,10,30,100,1000";
    int chmask = 3; /* 1: one channel, 2: three */
    const char *file = NULL;
    int blocks = BTDF_SCATFUN_TRANSMISSION, radiance = 0;
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!strcmp(argv[i], "-t"))
            tol = atof(argv[i + 1]);
        else if (!strcmp(argv[i], "-n"))
            N = atol(argv[i + 1]);
        else if (!strcmp(argv[i], "-s"))
            slist = argv[i + 1];
        else if (!strcmp(argv[i], "-f"))
            file = argv[i + 1];
        else if (!strcmp(argv[i], "-b"))
            blocks = atoi(argv[i + 1]);
        else if (!strcmp(argv[i], "-m"))
            radiance = atoi(argv[i + 1]) != 0;
        else if (!strcmp(argv[i], "-c"))
            chmask = atoi(argv[i + 1]) == 1 ? 1 : atoi(argv[i + 1]) == 3 ? 2 : 3;
        else {
            fprintf(stderr, "usage: sampler_sweep [-t TOL] [-n SAMPLES] [-s S1,S2] [-c 1|3|13] "
                            "[-b BLOCKS] [-m 0|1] [-f FILE.bsdf]\n");
            return 2;
        }
    }
    if (!(tol > 0) || N < 100 || blocks < 1 || blocks > BTDF_SCATFUN_ALL) {
        fprintf(stderr, "sampler_sweep: -t must be > 0, -n at least 100, -b in 1..15\n");
        return 2;
    }
    sweep_totals tot;
    memset(&tot, 0, sizeof tot);
    if (file) {
        btdf_params p;
        btdf_params_default(&p);
        p.smoothness = atof(slist);
        btdf_scatfun *f = NULL;
        char msg[512] = "";
        if (btdf_scatfun_read(file, &f, msg, sizeof msg) != BTDF_OK || btdf_scatfun_channels(f) != 1) {
            fprintf(stderr, "sampler_sweep: %s: %s\n", file, msg[0] ? msg : "not one channel");
            btdf_scatfun_free(f);
            return 2;
        }
        printf("# file %s, s %g, n 1.5\n", file, p.smoothness);
        int r = run_file(f, &p, tol, N, radiance, &tot);
        btdf_scatfun_free(f);
        if (r)
            return 2;
        printf("# %ld cases: %ld capped in double precision, %ld with non-finite values, %ld "
               "albedo mismatches; %ld cases capped in single precision; %ld views on the normal\n",
               tot.cases, tot.fail_terminate_double, tot.fail_nonfinite, tot.fail_albedo,
               tot.float_capped_cases, tot.pole_cases);
        return tot.fail_terminate_double || tot.fail_nonfinite || tot.fail_albedo ? 1 : 0;
    }
    long built = 0, notbuilt = 0;
    char *sl = strdup(slist);
    for (char *tok = strtok(sl, ","); tok; tok = strtok(NULL, ",")) {
        double s = atof(tok);
        for (int inv = 0; inv < 2; inv++)
            for (int ch = 1; ch <= 3; ch += 2) {
                if (!(chmask & (ch == 1 ? 1 : 2)))
                    continue;
                btdf_params p;
                btdf_params_default(&p);
                p.smoothness = s;
                p.channels = ch;
                static const double rgb[3] = {1.45, 1.5, 1.55};
                for (int k = 0; k < ch; k++)
                    p.ior[k] = inv ? 1.0 / (ch == 3 ? rgb[k] : 1.5) : (ch == 3 ? rgb[k] : 1.5);
                btdf_scatfun *f = NULL;
                char msg[512] = "";
                double t0 = wall();
                btdf_status stb = btdf_scatfun_build(&p, tol, (btdf_side)blocks, 0, &f, msg,
                                                     sizeof msg);
                printf("# build s %g n %g ch %d tol %g blocks %d: %s %s (%.1f s)\n", s,
                       p.ior[ch == 3 ? 1 : 0], ch, tol, blocks, btdf_strerror(stb), msg,
                       wall() - t0);
                fflush(stdout);
                if (!f) {
                    notbuilt++;
                    continue;
                }
                built++;
                if (run_file(f, &p, tol, N, radiance, &tot)) {
                    btdf_scatfun_free(f);
                    free(sl);
                    return 2;
                }
                fflush(stdout);
                btdf_scatfun_free(f);
            }
    }
    free(sl);
    printf("# %ld files built, %ld not; %ld cases: %ld capped in double precision, %ld with "
           "non-finite values, %ld albedo mismatches; %ld cases capped in single precision; %ld "
           "views on the normal\n",
           built, notbuilt, tot.cases, tot.fail_terminate_double, tot.fail_nonfinite,
           tot.fail_albedo, tot.float_capped_cases, tot.pole_cases);
    return tot.fail_terminate_double || tot.fail_nonfinite || tot.fail_albedo ? 1 : 0;
}
