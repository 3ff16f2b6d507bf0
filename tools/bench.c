/* SPDX-License-Identifier: MIT */
/* bench.c: evaluator throughput and a table's error against its run time, with the machine. */
#define _DEFAULT_SOURCE /* wait4: the peak memory of one child process */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/utsname.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "btdf.h"
#include "model_impl.h"
#include "table_impl.h"

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

typedef struct eval_job {
    double *buf, *cph, *sph;
    size_t NI, NO, NP;
} eval_job;

static void eval_slice(void *arg, size_t i)
{
    eval_job *e = arg;
    double ti = (89.0 * M_PI / 180.0) * (double)i / (double)(e->NI - 1);
    rho_in a;
    rho_in_init(&a, sin(ti), cos(ti), 3.0, 0.7);
    for (size_t o = 0; o < e->NO; o++) {
        double to = M_PI / 2 + (M_PI / 2) * (double)o / (double)(e->NO - 1);
        rho_out b;
        rho_out_init(&b, sin(to), fmin(cos(to), 0.0), 3.0, 0.7);
        double *row = e->buf + (i * e->NO + o) * e->NP;
        for (size_t j = 0; j < e->NP; j++)
            row[j] = rho_kernel(1.5, 3.0, &a, &b, e->cph[j], e->sph[j]);
    }
}

typedef struct result {
    double tb, te, e_l1, e_max, e_t, peak_mib;
    size_t samples;
    int status;
} result;

/* Builds and estimates one table in a child process, so that its peak resident
   memory is its own (ru_maxrss of the child), not the largest of all runs so far. */
static int run_child(const btdf_table_opts *o, result *res)
{
    int fd[2];
    if (pipe(fd) != 0)
        return 0;
    pid_t pid = fork();
    if (pid < 0)
        return 0;
    if (pid == 0) {
        close(fd[0]);
        result r;
        memset(&r, 0, sizeof r);
        btdf_table *t = NULL;
        double t0 = now();
        btdf_status st = btdf_table_build(o, &t, NULL, 0);
        r.tb = now() - t0;
        r.status = st;
        if (t) {
            btdf_report rep;
            memset(&rep, 0, sizeof rep);
            btdf_table_estimate(t, o->ti_min, o->ti_max, 0, 0, 20081231u, o->threads, &rep);
            r.te = rep.seconds_estimate;
            r.e_l1 = rep.e_l1_max;
            r.e_max = rep.e_max_max;
            r.e_t = rep.e_t_max;
            r.samples = btdf_table_node_count(t);
            btdf_report_clear(&rep);
            btdf_table_free(t);
        }
        if (write(fd[1], &r, sizeof r) != (ssize_t)sizeof r)
            _exit(1);
        _exit(0);
    }
    close(fd[1]);
    ssize_t got = read(fd[0], res, sizeof *res);
    close(fd[0]);
    int wst;
    struct rusage ru;
    if (wait4(pid, &wst, 0, &ru) < 0 || got != (ssize_t)sizeof *res)
        return 0;
    res->peak_mib = (double)ru.ru_maxrss / 1024.0;
    return 1;
}

static void run(FILE *out, const char *method, const char *label, btdf_table_opts *o, int reps)
{
    double tb[9], te[9], pk[9];
    result r;
    memset(&r, 0, sizeof r);
    for (int k = 0; k < reps; k++) {
        if (!run_child(o, &r))
            return;
        tb[k] = r.tb;
        te[k] = r.te;
        pk[k] = r.peak_mib;
    }
    fprintf(out, "%s,%s,%g,%g,%g,%.0f,%zu,%.4f,%.4f,%.1f,%.4g,%.4g,%.4g,%s\n", method, label,
            o->params.ior[0], o->params.smoothness,
            o->kind == BTDF_TABLE_GRID ? 0.0 : o->tolerance, o->ti_max * 180.0 / M_PI, r.samples,
            median(tb, reps), median(te, reps), median(pk, reps), r.e_l1, r.e_max, r.e_t,
            r.status == BTDF_OK ? "ok" : "budget");
    fflush(out);
}

int main(int argc, char **argv)
{
    const char *what = argc > 1 ? argv[1] : "all";
    int reps = argc > 2 ? atoi(argv[2]) : 3;
    if (reps < 1 || reps > 9)
        reps = 3;
    machine(stdout);
    const char *header = "method,case,n,s,tolerance,ti_max_deg,samples,seconds_tabulation,"
                         "seconds_estimate,peak_rss_mib,e_l1,e_max,e_t,status\n";
    if (!strcmp(what, "all") || !strcmp(what, "sweep")) {
        printf("%s", header);
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
                run(stdout, "adaptive", cases[c].label, &o, reps);
            }
            for (int k = 0; k < 4; k++) {
                o.kind = BTDF_TABLE_GRID;
                o.grid_ti = grids[k][0];
                o.grid_to = grids[k][1];
                o.grid_phi = grids[k][2];
                run(stdout, "uniform", cases[c].label, &o, reps);
            }
        }
    }
    if (!strcmp(what, "all") || !strcmp(what, "tolerances")) {
        /* The full range 0:90 at tolerances 1e-1 to 1e-4 with the default budget, and
           1e-4 again with a larger one; then the other materials over 0:90. */
        printf("%s", header);
        const double tols[] = {1e-1, 3e-2, 2e-2, 1e-2, 5e-3, 3e-3, 1e-3, 3e-4, 1e-4};
        btdf_table_opts o;
        btdf_table_opts_default(&o);
        for (int k = 0; k < 9; k++) {
            o.tolerance = tols[k];
            run(stdout, "adaptive", "1.5/3", &o, reps);
        }
        o.max_samples = 40000000;
        o.max_bytes = (size_t)1536 << 20;
        run(stdout, "adaptive-40M", "1.5/3", &o, reps);
    }
    if (!strcmp(what, "all") || !strcmp(what, "fullrange")) {
        printf("%s", header);
        btdf_table_opts o;
        const struct {
            const char *label;
            double n, s;
        } more[] = {{"1.5/100", 1.5, 100}, {"1/1.5/6", 1 / 1.5, 6}, {"1.31/20", 1.31, 20},
                    {"3/1000", 3, 1000}};
        btdf_table_opts_default(&o);
        for (int c = 0; c < 4; c++) {
            o.params.ior[0] = more[c].n;
            o.params.smoothness = more[c].s;
            for (int k = 0; k < 2; k++) {
                o.tolerance = k ? 1e-3 : 1e-2;
                run(stdout, "adaptive", more[c].label, &o, reps);
            }
        }
    }
    if (!strcmp(what, "all") || !strcmp(what, "scaling")) {
        /* Work follows what is asked: the full range, half of it, three channels. */
        printf("%s", header);
        btdf_table_opts o;
        btdf_table_opts_default(&o);
        o.ti_max = M_PI / 2;
        run(stdout, "adaptive", "1.5/3 ti 0-90", &o, reps);
        o.ti_max = M_PI / 4;
        run(stdout, "adaptive", "1.5/3 ti 0-45", &o, reps);
        o.ti_max = M_PI / 2;
        o.params.channels = 3;
        o.params.ior[0] = 1.49;
        o.params.ior[1] = 1.5;
        o.params.ior[2] = 1.51;
        run(stdout, "adaptive", "1.49,1.5,1.51/3 ti 0-90", &o, reps);
    }
    /* Last: the child processes above must not inherit this section's buffers, or
       their peak memory would include them. */
    if (!strcmp(what, "all") || !strcmp(what, "throughput")) {
        /* The evaluator alone: Eq. 25 on 90 x 180 x 181 (ti, to, phi) into a buffer
           allocated once, per-ti and per-to terms hoisted, no per-sample trigonometry. */
        size_t NI = 90, NO = 180, NP = 181;
        eval_job ej;
        ej.buf = malloc(NI * NO * NP * sizeof(double));
        ej.cph = malloc(NP * sizeof(double));
        ej.sph = malloc(NP * sizeof(double));
        ej.NO = NO;
        ej.NP = NP;
        ej.NI = NI;
        for (size_t j = 0; j < NP; j++) {
            ej.cph[j] = cos(M_PI * (double)j / (double)(NP - 1));
            ej.sph[j] = sin(M_PI * (double)j / (double)(NP - 1));
        }
        const int th2[2] = {1, 0};
        for (int a = 0; a < 2; a++) {
            double v[9];
            for (int k = -1; k < 9; k++) {
                double t0 = now();
                btdf_parallel_for(th2[a], NI, eval_slice, &ej);
                if (k >= 0)
                    v[k] = now() - t0;
            }
            double m = median(v, 9);
            printf("evaluator,threads=%s,90x180x181 into one buffer,%.4f s median of 9,%.3g "
                   "evaluations/s\n", th2[a] ? "1" : "all", m, (double)(NI * NO * NP) / m);
        }
        free(ej.buf);
        free(ej.cph);
        free(ej.sph);
    }
    if (!strcmp(what, "all") || !strcmp(what, "throughput")) {
        /* Eq. 25 on a full 90 x 180 x 181 grid (the GRID table builder: hoisted per-ti
           and per-to terms, a vectorisable loop over phi). One warm-up run first. */
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
            for (int k = -1; k < 9; k++) {
                btdf_table *t = NULL;
                double t0 = now();
                btdf_table_build(&o, &t, NULL, 0);
                if (k >= 0)
                    v[k] = now() - t0;
                btdf_table_free(t);
            }
            double m = median(v, 9);
            printf("throughput,threads=%s,grid 90x180x181,%.4f s median of 9,%.3g samples/s\n",
                   th[a] ? "1" : "all", m, 90.0 * 180 * 181 / m);
        }
    }
    return 0;
}
