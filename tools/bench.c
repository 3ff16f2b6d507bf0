/* SPDX-License-Identifier: MIT */
/* bench.c: evaluator throughput and a table's error against its run time, with the machine;
   the sections of the public API (bench_api.c) and of the simulator (bench_sim.c) apart. */
#define _DEFAULT_SOURCE /* wait4: the peak memory of one child process */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/utsname.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "btdf.h"
#include "btdf_scatfun.h"
#include "bench.h"
#include "model/kernel.h"
#include "table/table.h"

double now(void)
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

double median(double *v, int n)
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

void eval_slice(void *arg, size_t i)
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
    double tb, te, e_l1, e_max, e_t, peak_mib, cpu;
    size_t samples, evals, slices;
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
            r.slices = btdf_table_slice_count(t);
            r.evals = t->build_evals;
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
    res->cpu = (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
               (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec;
    return 1;
}

/* The program named `name` beside this one into path; 0 when there is none. */
static int beside(const char *name, char *path, size_t len)
{
    ssize_t m = readlink("/proc/self/exe", path, len - 64);
    if (m <= 0)
        return 0;
    path[m] = 0;
    char *slash = strrchr(path, '/');
    if (!slash)
        return 0;
    snprintf(slash + 1, 64, "%s", name);
    return access(path, X_OK) == 0;
}

/* The dense e_L1 max of btdf-densescan for the same request (it builds the same table:
   the build is deterministic); NaN when the program is missing or says nothing. */
static double dense_l1(const btdf_table_opts *o)
{
    char prog[4096], cmd[4400], line[1024];
    if (!beside("btdf-densescan", prog, sizeof prog))
        return NAN;
    snprintf(cmd, sizeof cmd, "'%s' --ior %.17g -s %.17g --tolerance %.17g --theta-i %.17g:%.17g",
             prog, o->params.ior[0], o->params.smoothness, o->tolerance,
             o->ti_min * 180.0 / M_PI, o->ti_max * 180.0 / M_PI);
    FILE *f = popen(cmd, "r");
    if (!f)
        return NAN;
    double d = NAN;
    while (fgets(line, sizeof line, f)) {
        const char *q = strstr(line, " dense ");
        if (q)
            d = strtod(q + 7, NULL);
    }
    pclose(f);
    return d;
}

/* One row of the n-near-1 comparison: the median of reps builds, and the dense scan. */
/* reps builds of o, each in its child (run_child): their times and peaks into the
   arrays (reps <= 9), the last result into r; 0 when a child failed. */
static int repeat_child(btdf_table_opts *o, int reps, result *r, double *tb, double *te,
                        double *cpu, double *pk)
{
    memset(r, 0, sizeof *r);
    for (int k = 0; k < reps; k++) {
        if (!run_child(o, r))
            return 0;
        tb[k] = r->tb;
        te[k] = r->te;
        cpu[k] = r->cpu;
        pk[k] = r->peak_mib;
    }
    return 1;
}

static void run_near(const char *label, btdf_table_opts *o, int reps)
{
    double tb[9], te[9], cpu[9], pk[9];
    result r;
    if (!repeat_child(o, reps, &r, tb, te, cpu, pk))
        return;
    double d = dense_l1(o);
    printf("%s,%.9g,%g,%g,%.0f:%.0f,%zu,%zu,%zu,%.3f,%.3f,%.1f,%.4g,%.4g,%s\n", label,
           o->params.ior[0], o->params.smoothness, o->tolerance, o->ti_min * 180.0 / M_PI,
           o->ti_max * 180.0 / M_PI, r.slices, r.samples, r.evals, median(tb, reps),
           median(cpu, reps), median(pk, reps), r.e_l1, d,
           r.status == BTDF_OK ? "ok" : "budget");
    fflush(stdout);
}

static void run(FILE *out, const char *method, const char *label, btdf_table_opts *o, int reps)
{
    double tb[9], te[9], cpu[9], pk[9];
    result r;
    if (!repeat_child(o, reps, &r, tb, te, cpu, pk))
        return;
    fprintf(out, "%s,%s,%g,%g,%g,%.0f,%zu,%.4f,%.4f,%.1f,%.4g,%.4g,%.4g,%s\n", method, label,
            o->params.ior[0], o->params.smoothness,
            o->kind == BTDF_TABLE_GRID ? 0.0 : o->tolerance, o->ti_max * 180.0 / M_PI, r.samples,
            median(tb, reps), median(te, reps), median(pk, reps), r.e_l1, r.e_max, r.e_t,
            r.status == BTDF_OK ? "ok" : "budget");
    fflush(out);
}


/* .bsdf (SCATFUN) builds: n = 1.5, both sides, all cores; median wall and CPU seconds
   of reps builds (the builds are deterministic, so the file of the last one stands for
   all), its size in bytes, nodes, coefficients, longest and median series, and e_L1 per
   side measured through the file's own evaluation with the seed btdftab reports with. */
static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

static void bsdf_bench(int reps)
{
    const struct {
        double s, tol;
    } cases[] = {{3, 1e-2}, {3, 1e-3}, {20, 1e-3}, {100, 1e-2}, {1000, 1e-2}};
    printf("bsdf,s,tolerance,status,build_wall_s_median,build_cpu_s_median,bytes,nodes,"
           "coefficients,mmax,median_length,e_l1_enter,e_l1_leave,bytes_per_unit_accuracy,"
           "a0_peak\n");
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        btdf_params p;
        btdf_params_default(&p);
        p.smoothness = cases[k].s;
        double v[9], c[9];
        btdf_scatfun *f = NULL;
        btdf_status st = BTDF_OK;
        char msg[512] = "";
        for (int r = 0; r < reps; r++) {
            btdf_scatfun_free(f);
            f = NULL;
            double t0 = now(), c0 = cpu_now();
            st = btdf_scatfun_build(&p, cases[k].tol, BTDF_SIDE_BOTH, 0, &f, msg, sizeof msg);
            v[r] = now() - t0;
            c[r] = cpu_now() - c0;
            if (!f)
                break; /* refused: no file, nothing to repeat */
        }
        int n = f ? reps : 1;
        double wall = median(v, n), cpu = median(c, n);
        if (!f) {
            printf("bsdf,%g,%g,%s: %s,%.3f,%.3f,,,,,,,,,\n", cases[k].s, cases[k].tol,
                   btdf_strerror(st), msg, wall, cpu);
            fflush(stdout);
            continue;
        }
        double e[2] = {0, 0};
        for (int sd = 0; sd < 2; sd++) {
            btdf_report r;
            memset(&r, 0, sizeof r);
            if (btdf_scatfun_report(f, &p, sd ? BTDF_SIDE_LEAVE : BTDF_SIDE_ENTER, 0, 0,
                                    20081231u, 0, &r) == BTDF_OK)
                e[sd] = r.e_l1_max;
            else
                e[sd] = NAN;
            btdf_report_clear(&r);
        }
        size_t nn = btdf_scatfun_node_count(f), bytes = btdf_scatfun_file_size(f, NULL);
        /* median series length over the pairs that hold one */
        uint32_t *len = malloc(nn * nn * sizeof *len);
        size_t nl = 0;
        for (size_t i = 0; len && i < nn; i++)
            for (size_t o = 0; o < nn; o++) {
                size_t off = 0, m = 0;
                if (btdf_scatfun_pair(f, i, o, &off, &m) == BTDF_OK && m > 0)
                    len[nl++] = (uint32_t)m;
            }
        uint32_t med = 0;
        if (len && nl) {
            qsort(len, nl, sizeof *len, cmp_u32);
            med = len[nl / 2];
        }
        free(len);
        double emax = fmax(e[0], e[1]);
        /* bytes per unit of accuracy: bytes times the error reached (bytes x e_L1) */
        printf("bsdf,%g,%g,%s,%.3f,%.3f,%zu,%zu,%zu,%zu,%u,%.3g,%.3g,%.4g,%.4g\n", cases[k].s,
               cases[k].tol, st == BTDF_OK ? "met" : "not met", wall, cpu, bytes, nn,
               btdf_scatfun_coeff_count(f), btdf_scatfun_max_order(f), med, e[0], e[1],
               (double)bytes * emax, btdf_scatfun_a0_peak(f));
        fflush(stdout);
        btdf_scatfun_free(f);
    }
}


static const char usage[] =
    "usage: btdf-bench [SECTION [REPS]]\n"
    "Prints the machine, then CSV rows of timings and errors (docs/benchmarks.md).\n"
    "  SECTION  all (default), sweep (adaptive and uniform tables: error against run\n"
    "           time for four materials), scaling (work against the range and the\n"
    "           channels asked), tolerances (1.5/3 over 0:90 at 1e-1 to 1e-4),\n"
    "           fullrange (other materials over 0:90), nearone (n = 1.5, 1.0001, 0.9999,\n"
    "           1.00001 at s = 3, 1e-3, 0:80, with btdf-densescan's error), api (the\n"
    "           public evaluation entry points beside the\n"
    "           internal kernel, at least 5 runs), or throughput (Eq. 25 evaluations\n"
    "           per second), or bsdf (.bsdf builds: time, bytes, nodes, series\n"
    "           length and measured error for s = 3, 20, 100, 1000), or sim (the\n"
    "           Monte Carlo surface: rays/s/thread at s = 0.5 to 30, hierarchy and\n"
    "           plain DDA; not part of all), simhit (first hits only: the DDA,\n"
    "           the hierarchy and, if built with it, Embree on the same rays), or\n"
    "           full (the model full at n = 1.5, s = 1: its tally on 1 and 2 threads,\n"
    "           and its evaluations; not part of all)\n"
    "  REPS     runs per table, 1 to 9 (default 3); each row reports the median\n"
    "Timings depend on the machine's load: quote medians and the machine line.\n";

/* sweep: adaptive and uniform tables, error against run time, four materials */
static void bench_sweep(const char *header, int reps)
{
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

/* tolerances: 1.5/3 over 0:90 at 1e-1 to 1e-4 */
static void bench_tolerances(const char *header, int reps)
{
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

/* fullrange: other materials over 0:90 */
static void bench_fullrange(const char *header, int reps)
{
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

/* nearone: n near 1 beside n = 1.5 */
static void bench_nearone(int reps)
{
    /* n near 1 beside n = 1.5: s = 3, ti 0:80, tolerance 1e-3, default budget. nodes:
       the table's; evaluations: Eq. 25 points the builder computed (all passes,
       dropped candidates too); cpu: the build and its check, all threads. */
    printf("case,n,s,tolerance,ti_deg,slices,nodes,evaluations,seconds_wall,"
           "seconds_cpu,peak_rss_mib,e_l1_reported,e_l1_dense,status\n");
    const double ns[] = {1.5, 1.0001, 0.9999, 1.00001};
    for (int c = 0; c < 4; c++) {
        btdf_table_opts o;
        btdf_table_opts_default(&o);
        o.params.ior[0] = ns[c];
        o.params.smoothness = 3.0;
        o.ti_max = 80.0 * M_PI / 180.0;
        run_near("near-one", &o, reps);
    }
}

/* scaling: work against the range and the channels asked */
static void bench_scaling(const char *header, int reps)
{
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

/* throughput: the evaluator alone */
static void bench_evaluator(void)
{
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
            core_parallel_for(th2[a], NI, eval_slice, &ej);
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

/* throughput: the GRID table builder */
static void bench_grid(void)
{
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

int main(int argc, char **argv)
{
    const char *what = argc > 1 ? argv[1] : "all";
    if (!strcmp(what, "--help") || !strcmp(what, "-h")) {
        fputs(usage, stdout);
        return 0;
    }
    char *end = NULL;
    long r = argc > 2 ? strtol(argv[2], &end, 10) : 3;
    if (strcmp(what, "all") && strcmp(what, "sweep") && strcmp(what, "scaling") &&
        strcmp(what, "api") && strcmp(what, "throughput") && strcmp(what, "tolerances") &&
        strcmp(what, "fullrange") && strcmp(what, "nearone") && strcmp(what, "bsdf") &&
        strcmp(what, "sim") && strcmp(what, "simhit") && strcmp(what, "full")) {
        fprintf(stderr, "btdf-bench: unknown section '%s'\n%s", what, usage);
        return 2;
    }
    if (argc > 3 || (end && *end) || r < 1 || r > 9) {
        fprintf(stderr, "btdf-bench: REPS must be an integer from 1 to 9\n%s", usage);
        return 2;
    }
    int reps = (int)r;
    machine(stdout);
    if (!strcmp(what, "sim")) {
        bench_sim(stdout, reps);
        return 0;
    }
    if (!strcmp(what, "simhit")) {
        bench_simhit(stdout, reps);
        return 0;
    }
    if (!strcmp(what, "full")) {
        bench_full(stdout, reps);
        return 0;
    }
    const char *header = "method,case,n,s,tolerance,ti_max_deg,samples,seconds_tabulation,"
                         "seconds_estimate,peak_rss_mib,e_l1,e_max,e_t,status\n";
    if (!strcmp(what, "all") || !strcmp(what, "sweep"))
        bench_sweep(header, reps);
    if (!strcmp(what, "all") || !strcmp(what, "tolerances"))
        bench_tolerances(header, reps);
    if (!strcmp(what, "all") || !strcmp(what, "fullrange"))
        bench_fullrange(header, reps);
    if (!strcmp(what, "all") || !strcmp(what, "nearone"))
        bench_nearone(reps);
    if (!strcmp(what, "all") || !strcmp(what, "scaling"))
        bench_scaling(header, reps);
    if (!strcmp(what, "all") || !strcmp(what, "api"))
        api_bench(reps < 5 ? 5 : reps);
    if (!strcmp(what, "all") || !strcmp(what, "bsdf"))
        bsdf_bench(reps);
    /* Last: the child processes above must not inherit this section's buffers, or
       their peak memory would include them. */
    if (!strcmp(what, "all") || !strcmp(what, "throughput"))
        bench_evaluator();
    if (!strcmp(what, "all") || !strcmp(what, "throughput"))
        bench_grid();
    return 0;
}
