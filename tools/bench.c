/* SPDX-License-Identifier: MIT */
/* bench.c: evaluator throughput and a table's error against its run time, with the machine. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/utsname.h>
#include <time.h>
#include <unistd.h>

#include "btdf.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static void machine(FILE *f)
{
    struct utsname u;
    char cpu[256] = "unknown";
    FILE *c = fopen("/proc/cpuinfo", "r");
    if (c) {
        char line[512];
        while (fgets(line, sizeof line, c))
            if (!strncmp(line, "model name", 10)) {
                char *p = strchr(line, ':');
                if (p) {
                    snprintf(cpu, sizeof cpu, "%s", p + 2);
                    cpu[strcspn(cpu, "\n")] = 0;
                }
                break;
            }
        fclose(c);
    }
    uname(&u);
    fprintf(f, "# machine: %s; %ld cores online; %s %s %s; libbtdf %s\n", cpu,
            sysconf(_SC_NPROCESSORS_ONLN), u.sysname, u.release, u.machine,
            btdf_version_string());
}

/* Builds (and estimates) one table; returns seconds of build + estimate. */
static int run(FILE *out, const char *method, const char *label, double n, double s,
               btdf_table_opts *o, int reps)
{
    double tb[9], te[9];
    btdf_report r;
    memset(&r, 0, sizeof r);
    btdf_status st = BTDF_OK;
    size_t samples = 0;
    for (int k = 0; k < reps; k++) {
        btdf_table *t = NULL;
        double t0 = now();
        st = btdf_table_build(o, &t, NULL, 0);
        double t1 = now();
        if (!t)
            return 0;
        btdf_report_clear(&r);
        memset(&r, 0, sizeof r);
        btdf_table_estimate(t, o->ti_min, o->ti_max, 0, 0, 20081231u, o->threads, &r);
        tb[k] = t1 - t0;
        te[k] = r.seconds_estimate;
        samples = btdf_table_node_count(t);
        btdf_table_free(t);
    }
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    fprintf(out, "%s,%s,%g,%g,%g,%zu,%.4f,%.4f,%.1f,%.4g,%.4g,%.4g,%s\n", method, label, n, s,
            o->kind == BTDF_TABLE_GRID ? 0.0 : o->tolerance, samples, median(tb, reps),
            median(te, reps), (double)ru.ru_maxrss / 1024.0, r.e_l1_max, r.e_max_max,
            r.e_t_max, st == BTDF_OK ? "ok" : "budget");
    fflush(out);
    btdf_report_clear(&r);
    return 1;
}

int main(int argc, char **argv)
{
    const char *what = argc > 1 ? argv[1] : "all";
    int reps = argc > 2 ? atoi(argv[2]) : 3;
    if (reps < 1 || reps > 9)
        reps = 3;
    machine(stdout);
    if (!strcmp(what, "all") || !strcmp(what, "throughput")) {
        /* Eq. 25 on a full 90 x 180 x 181 grid (the GRID table builder: hoisted per-ti
           and per-to terms, a vectorisable loop over phi). */
        btdf_table_opts o;
        btdf_table_opts_default(&o);
        o.kind = BTDF_TABLE_GRID;
        o.grid_ti = 90;
        o.grid_to = 180;
        o.grid_phi = 181;
        o.ti_max = 89.0 * M_PI / 180.0;
        const int th[2] = {1, 0};
        for (int a = 0; a < 2; a++) {
            o.threads = th[a];
            double v[9];
            for (int k = 0; k < reps; k++) {
                btdf_table *t = NULL;
                double t0 = now();
                btdf_table_build(&o, &t, NULL, 0);
                v[k] = now() - t0;
                btdf_table_free(t);
            }
            double m = median(v, reps);
            printf("throughput,threads=%s,grid 90x180x181,%.3f s median of %d,%.3g samples/s\n",
                   th[a] ? "1" : "all", m, reps, 90.0 * 180 * 181 / m);
        }
    }
    if (!strcmp(what, "all") || !strcmp(what, "sweep")) {
        printf("method,case,n,s,tolerance,samples,seconds_tabulation,seconds_estimate,"
               "peak_rss_mib,e_l1,e_max,e_t,status\n");
        const struct {
            const char *label;
            double n, s;
        } cases[] = {{"1.5/3", 1.5, 3}, {"1.5/100", 1.5, 100}, {"1/1.5/6", 1 / 1.5, 6},
                     {"1.0001/3", 1.0001, 3}};
        const double tols[] = {3e-2, 1e-2, 3e-3, 1e-3};
        const size_t grids[][3] = {{9, 46, 46}, {17, 91, 91}, {33, 181, 181}, {41, 361, 361}};
        for (int c = 0; c < 4; c++) {
            btdf_table_opts o;
            btdf_table_opts_default(&o);
            o.params.ior[0] = cases[c].n;
            o.params.smoothness = cases[c].s;
            o.ti_max = 80.0 * M_PI / 180.0;
            for (int k = 0; k < 4; k++) {
                o.kind = BTDF_TABLE_FACET;
                o.tolerance = tols[k];
                run(stdout, "adaptive", cases[c].label, cases[c].n, cases[c].s, &o, reps);
            }
            for (int k = 0; k < 4; k++) {
                o.kind = BTDF_TABLE_GRID;
                o.grid_ti = grids[k][0];
                o.grid_to = grids[k][1];
                o.grid_phi = grids[k][2];
                run(stdout, "uniform", cases[c].label, cases[c].n, cases[c].s, &o, reps);
            }
        }
    }
    return 0;
}
