/* SPDX-License-Identifier: MIT */
/* run.c: building, reporting and writing a .bsdf, for `tabulate -o F.bsdf` and `build`. */
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "run.h"

double run_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int run_parse_side(const char *word)
{
    static const char *const names[4] = {NULL, "enter", "leave", "both"};
    for (int s = BTDF_SIDE_ENTER; s <= BTDF_SIDE_BOTH; s++)
        if (!strcmp(word, names[s]))
            return s;
    return 0;
}

int run_parse_metric(const char *word, btdf_metric *metric)
{
    if (strcmp(word, "l1") && strcmp(word, "max"))
        return 0;
    *metric = word[0] == 'l' ? BTDF_METRIC_L1 : BTDF_METRIC_MAX;
    return 1;
}

static int fail(const char *prog, int code, const char *path, const char *what)
{
    fprintf(stderr, "%s: %s: %s\n", prog, path, what);
    return code;
}

int run_series(const char *prog, const char *path, const btdf_params *p, double tol, int sides,
               int threads, int quiet, int best_effort, const char *prov)
{
    char msg[512] = "";
    btdf_scatfun *f = NULL;
    double t0 = run_now();
    btdf_status st = btdf_scatfun_build(p, tol, (btdf_side)sides, threads, &f, msg, sizeof msg);
    double t1 = run_now();
    if (st != BTDF_OK && st != BTDF_EBUDGET)
        return fail(prog, st == BTDF_EINVAL ? 2 : 1, path, msg[0] ? msg : btdf_strerror(st));
    if (!f)
        return fail(prog, 1, path, msg[0] ? msg : btdf_strerror(st));
    /* The error a renderer will see: the format's own evaluation, per side. */
    int met = 1;
    char meta[1024];
    int k = snprintf(meta, sizeof meta, "{\"program\": \"btdftab %s\", \"tolerance\": %g",
                     btdf_version_string(), tol);
    for (int s = BTDF_SIDE_ENTER; s <= BTDF_SIDE_LEAVE; s++) {
        if (!(sides & s))
            continue;
        btdf_report r;
        memset(&r, 0, sizeof r);
        double e0 = run_now();
        btdf_status es = btdf_scatfun_report(f, p, (btdf_side)s, 0, 0, REPORT_SEED, threads, &r);
        double e1 = run_now();
        if (es != BTDF_OK) {
            btdf_scatfun_free(f);
            fprintf(stderr, "%s: %s: error estimate: %s\n", prog, path, btdf_strerror(es));
            return 1;
        }
        int ok = r.e_l1_max <= tol;
        met = met && ok;
        const char *name = s == BTDF_SIDE_ENTER ? "enter" : "leave";
        if (!quiet)
            fprintf(stderr,
                    "%s: %s (%s, as a renderer reads it): %zu nodes, %zu coefficients; "
                    "build %.3f s, estimate %.3f s (%zu angles, %zu points); e_L1 max %.3g "
                    "mean %.3g; e_max max %.3g; e_T max %.3g%s\n",
                    prog, path, name, btdf_scatfun_node_count(f), btdf_scatfun_coeff_count(f),
                    t1 - t0, e1 - e0, r.test_angles, r.test_points, r.e_l1_max, r.e_l1_mean,
                    r.e_max_max, r.e_t_max, ok ? "; tolerance met" : "; TOLERANCE NOT MET");
        if (k > 0 && (size_t)k < sizeof meta)
            k += snprintf(meta + k, sizeof meta - (size_t)k,
                          ", \"%s\": {\"e_l1_max\": %.4g, \"e_max_max\": %.4g, \"e_t_max\": %.4g}",
                          name, r.e_l1_max, r.e_max_max, r.e_t_max);
        btdf_report_clear(&r);
    }
    if (k > 0 && (size_t)k < sizeof meta)
        snprintf(meta + k, sizeof meta - (size_t)k, ", \"command\": \"%s\"}", prov ? prov : "");
    int code = 0;
    if (!met && !best_effort) {
        fprintf(stderr, "%s: %s: tolerance %g not met%s%s; nothing written (pass --best-effort "
                        "to write it anyway)\n",
                prog, path, tol, msg[0] ? ": " : "", msg);
        code = 3;
    } else {
        btdf_output what = {NULL, f, NULL, NULL, meta};
        st = btdf_write(&what, path, msg, sizeof msg);
        if (st != BTDF_OK)
            code = fail(prog, 1, path, msg[0] ? msg : btdf_strerror(st));
    }
    btdf_scatfun_free(f);
    return code;
}
