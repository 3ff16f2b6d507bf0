/* SPDX-License-Identifier: MIT */
/* bench.c: evaluator throughput and a table's error against its run time, with the machine. */
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
#include "btdf_sim.h"
#include "fastnum.h"
#include "model/kernel.h"
#include "sim/rng.h"
#include "sim/surface.h"
#include "sim/trace.h"
#if BENCH_EMBREE
#include <embree3/rtcore.h>
#endif
#include "table/table.h"

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

/* ------------------------------------------------------------------------- */
/* The public entry points beside the internal kernel, on one grid, one run  */
/* ------------------------------------------------------------------------- */

typedef struct api_grid {
    size_t NI, NO, NP;
    double *ti, *to, *phi;          /* the axes, radians */
    double *ati, *ato, *aphi;       /* the same grid as flat arrays, for the batch */
    double *out;
    btdf_params p;
} api_grid;

static volatile double api_sink; /* keeps the scalar loops from being optimised out */

static void api_rho(api_grid *g)
{
    double acc = 0.0;
    for (size_t i = 0; i < g->NI; i++)
        for (size_t j = 0; j < g->NO; j++)
            for (size_t k = 0; k < g->NP; k++)
                acc += btdf_rho(g->p.ior[0], g->p.smoothness, g->p.k0, g->ti[i], g->to[j],
                                g->phi[k]);
    api_sink = acc;
}

static void api_eval(api_grid *g)
{
    double *o = g->out;
    for (size_t i = 0; i < g->NI; i++)
        for (size_t j = 0; j < g->NO; j++)
            for (size_t k = 0; k < g->NP; k++)
                btdf_eval(&g->p, g->ti[i], g->to[j], g->phi[k], o++);
}

static void api_batch(api_grid *g)
{
    btdf_eval_batch(&g->p, g->NI * g->NO * g->NP, g->ati, g->ato, g->aphi, g->out, NULL);
}

/* The same entry points in the Smith model (BTDF_MODEL_SMITH), side by side. */
static void api_rho_smith(api_grid *g)
{
    double acc = 0.0;
    for (size_t i = 0; i < g->NI; i++)
        for (size_t j = 0; j < g->NO; j++)
            for (size_t k = 0; k < g->NP; k++)
                acc += btdf_rho_smith(g->p.ior[0], g->p.smoothness, g->ti[i], g->to[j],
                                      g->phi[k]);
    api_sink = acc;
}

static void api_eval_smith(api_grid *g)
{
    g->p.model = BTDF_MODEL_SMITH;
    api_eval(g);
    g->p.model = BTDF_MODEL_XU_SUN;
}

static void api_batch_smith(api_grid *g)
{
    g->p.model = BTDF_MODEL_SMITH;
    api_batch(g);
    g->p.model = BTDF_MODEL_XU_SUN;
}

static int api_threads;
static void api_grid_fn(api_grid *g)
{
    btdf_eval_grid(&g->p, g->NI, g->ti, g->NO, g->to, g->NP, g->phi, api_threads, g->out);
}

static void api_grid_smith(api_grid *g)
{
    g->p.model = BTDF_MODEL_SMITH;
    api_grid_fn(g);
    g->p.model = BTDF_MODEL_XU_SUN;
}

static eval_job api_kernel_job;
static void api_kernel(api_grid *g)
{
    core_parallel_for(api_threads, g->NI, eval_slice, &api_kernel_job);
}

static double cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Median wall and CPU seconds (all threads of this process) of reps runs of fn after
   one warm-up run. On a shared machine the wall time includes the time other
   processes held the cores; the CPU time does not. */
static void api_time(void (*fn)(api_grid *), api_grid *g, int reps, double *wall, double *cpu)
{
    double v[9], c[9];
    fn(g);
    for (int k = 0; k < reps; k++) {
        double t0 = now(), c0 = cpu_now();
        fn(g);
        v[k] = now() - t0;
        c[k] = cpu_now() - c0;
    }
    *wall = median(v, reps);
    *cpu = median(c, reps);
}

static double children_cpu(void)
{
    struct rusage ru;
    getrusage(RUSAGE_CHILDREN, &ru);
    return (double)ru.ru_utime.tv_sec + 1e-6 * (double)ru.ru_utime.tv_usec +
           (double)ru.ru_stime.tv_sec + 1e-6 * (double)ru.ru_stime.tv_usec;
}

/* The tool's number I/O against the C library's, per number, on the values and
   strings of the CLI row below: printf("%.17g") against fastnum_g17 (the same bytes),
   strtod against fastnum_strtod (the same values). */
static void number_io(api_grid *g, int reps)
{
    size_t N = g->NI * g->NO * g->NP;
    char buf[64];
    double v[4][9];
    for (int k = 0; k < reps; k++) {
        size_t bytes = 0;
        double c0 = cpu_now();
        for (size_t i = 0; i < N; i += 7)
            bytes += (size_t)snprintf(buf, sizeof buf, "%.17g", g->out[i]);
        double c1 = cpu_now();
        for (size_t i = 0; i < N; i += 7)
            bytes += (size_t)fastnum_g17(g->out[i], buf);
        double c2 = cpu_now();
        double acc = 0.0;
        for (size_t i = 0; i < N; i += 7) {
            snprintf(buf, sizeof buf, "%g", g->ati[i] * 57.29577951308232);
            acc += strtod(buf, NULL);
        }
        double c3 = cpu_now();
        for (size_t i = 0; i < N; i += 7) {
            snprintf(buf, sizeof buf, "%g", g->ati[i] * 57.29577951308232);
            acc += fastnum_strtod(buf, NULL);
        }
        double c4 = cpu_now();
        for (size_t i = 0; i < N; i += 7) /* the formatting both parse loops share */
            snprintf(buf, sizeof buf, "%g", g->ati[i] * 57.29577951308232);
        double c5 = cpu_now();
        api_sink = acc + (double)bytes;
        double per = 1e9 / (double)((N + 6) / 7);
        v[0][k] = (c1 - c0) * per;
        v[1][k] = (c2 - c1) * per;
        v[2][k] = (c3 - c2 - (c5 - c4)) * per;
        v[3][k] = (c4 - c3 - (c5 - c4)) * per;
    }
    const char *name[4] = {"printf %.17g", "fastnum_g17 (same bytes)", "strtod",
                           "fastnum_strtod (same values)"};
    printf("# number I/O of btdftab eval, CPU ns per number, median of %d\n", reps);
    for (int k = 0; k < 4; k++)
        printf("%s,%.1f ns\n", name[k], median(v[k], reps));
}

/* btdftab eval on rows piped through a file: rows/s of parsing, evaluating, printing,
   by wall time and by the CPU time of the child processes. */
static int cli_rows(const char *tool, size_t rows, int reps, double *wall, double *cpu)
{
    /* the rows go to a file in $TMPDIR (or the current folder) for the shell to redirect */
    const char *dir = getenv("TMPDIR");
    char in[4096];
    snprintf(in, sizeof in, "%s/btdf-bench-in-XXXXXX", dir && *dir ? dir : ".");
    int fd = mkstemp(in);
    if (fd < 0)
        return 0;
    FILE *f = fdopen(fd, "w");
    if (!f) {
        close(fd);
        unlink(in);
        return 0;
    }
    for (size_t r = 0; r < rows; r++) /* a grid of angles as a user would write them */
        fprintf(f, "%g %g %g\n", (double)(r % 90), 90.0 + (double)((r / 90) % 91),
                (double)((r / 8190) % 181));
    fclose(f);
    char cmd[2 * 4096 + 256];
    snprintf(cmd, sizeof cmd, "'%s' eval --ior 1.5 -s 3 < '%s' > /dev/null", tool, in);
    double v[9], c[9];
    int ok = 1;
    for (int k = 0; k < reps && ok; k++) {
        double t0 = now(), c0 = children_cpu();
        ok = system(cmd) == 0;
        v[k] = now() - t0;
        c[k] = children_cpu() - c0;
    }
    unlink(in);
    *wall = median(v, reps);
    *cpu = median(c, reps);
    return ok;
}

static void api_bench(int reps)
{
    api_grid g;
    g.NI = 90;
    g.NO = 180;
    g.NP = 181;
    size_t N = g.NI * g.NO * g.NP;
    btdf_params_default(&g.p);
    g.ti = malloc(g.NI * sizeof(double));
    g.to = malloc(g.NO * sizeof(double));
    g.phi = malloc(g.NP * sizeof(double));
    g.ati = malloc(N * sizeof(double));
    g.ato = malloc(N * sizeof(double));
    g.aphi = malloc(N * sizeof(double));
    g.out = malloc(N * sizeof(double));
    api_kernel_job.buf = malloc(N * sizeof(double));
    api_kernel_job.cph = malloc(g.NP * sizeof(double));
    api_kernel_job.sph = malloc(g.NP * sizeof(double));
    if (!g.ti || !g.to || !g.phi || !g.ati || !g.ato || !g.aphi || !g.out ||
        !api_kernel_job.buf || !api_kernel_job.cph || !api_kernel_job.sph) {
        fprintf(stderr, "btdf-bench: out of memory\n");
        exit(1);
    }
    for (size_t i = 0; i < g.NI; i++)
        g.ti[i] = (89.0 * M_PI / 180.0) * (double)i / (double)(g.NI - 1);
    for (size_t j = 0; j < g.NO; j++)
        g.to[j] = M_PI / 2 + (M_PI / 2) * (double)j / (double)(g.NO - 1);
    for (size_t k = 0; k < g.NP; k++) {
        g.phi[k] = M_PI * (double)k / (double)(g.NP - 1);
        api_kernel_job.cph[k] = cos(g.phi[k]);
        api_kernel_job.sph[k] = sin(g.phi[k]);
    }
    for (size_t i = 0, r = 0; i < g.NI; i++)
        for (size_t j = 0; j < g.NO; j++)
            for (size_t k = 0; k < g.NP; k++, r++) {
                g.ati[r] = g.ti[i];
                g.ato[r] = g.to[j];
                g.aphi[r] = g.phi[k];
            }
    api_kernel_job.NI = g.NI;
    api_kernel_job.NO = g.NO;
    api_kernel_job.NP = g.NP;
    printf("# public entry points and the internal kernel, n = 1.5, s = 3, the same "
           "90x180x181 (ti, to, phi) grid, median of %d runs each, one process\n", reps);
    double la[3] = {0, 0, 0};
    FILE *lf = fopen("/proc/loadavg", "r");
    if (lf) {
        if (fscanf(lf, "%lf %lf %lf", &la[0], &la[1], &la[2]) != 3)
            la[0] = la[1] = la[2] = 0;
        fclose(lf);
    }
    printf("# load average at the start: %.2f %.2f %.2f (on %ld cores)\n", la[0], la[1], la[2],
           sysconf(_SC_NPROCESSORS_ONLN));
    printf("entry,threads,wall_seconds,per_wall_second,cpu_seconds,per_cpu_second\n");
    struct {
        const char *name;
        void (*fn)(api_grid *);
        int threads;
    } rows[] = {
        {"btdf_rho", api_rho, 1},           {"btdf_eval", api_eval, 1},
        {"btdf_eval_batch", api_batch, 1},  {"btdf_eval_grid", api_grid_fn, 1},
        {"btdf_eval_grid", api_grid_fn, 2}, {"kernel (rho_kernel, tables)", api_kernel, 1},
        {"kernel (rho_kernel, tables)", api_kernel, 2},
        {"btdf_rho_smith", api_rho_smith, 1}, {"btdf_eval (smith)", api_eval_smith, 1},
        {"btdf_eval_batch (smith)", api_batch_smith, 1},
        {"btdf_eval_grid (smith)", api_grid_smith, 1},
    };
    for (size_t r = 0; r < sizeof rows / sizeof rows[0]; r++) {
        api_threads = rows[r].threads;
        double w, c;
        api_time(rows[r].fn, &g, reps, &w, &c);
        printf("%s,%d,%.4f,%.3g,%.4f,%.3g\n", rows[r].name, rows[r].threads, w,
               (double)N / w, c, (double)N / c);
        fflush(stdout);
    }
    number_io(&g, reps);
    /* the tool beside this program */
    char self[4096];
    ssize_t len = readlink("/proc/self/exe", self, sizeof self - 16);
    if (len > 0) {
        self[len] = 0;
        char *slash = strrchr(self, '/');
        if (slash) {
            strcpy(slash + 1, "btdftab");
            if (access(self, X_OK) == 0) {
                size_t rows = 2000000;
                double w, c;
                if (cli_rows(self, rows, reps < 5 ? reps : 5, &w, &c))
                    printf("btdftab eval rows (stdin to stdout),all,%.4f,%.3g,%.4f,%.3g\n", w,
                           (double)rows / w, c, (double)rows / c);
            }
        }
    }
    free(g.ti);
    free(g.to);
    free(g.phi);
    free(g.ati);
    free(g.ato);
    free(g.aphi);
    free(g.out);
    free(api_kernel_job.buf);
    free(api_kernel_job.cph);
    free(api_kernel_job.sph);
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

/* The Monte Carlo surface (btdf_sim.h): rays per second on one thread at n = 1.5,
   ti = 30, for the min/max hierarchy and the plain cell DDA on the same rays (both
   find the same hits, so T agrees to the bit), with the hits per ray and the time a
   standard error of 1e-3 on T would take. 2e6 rays: 32 realisations of 62,500 rays,
   so making the surfaces is a small share. CPU seconds of this process, the median of
   REPS runs: the machine may be shared, and one thread's CPU time is what a thread
   costs. */
static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void bench_sim(FILE *f, int reps)
{
    fprintf(f, "method,s,rays,realisations,cpu_seconds_median,rays_per_s_thread,mean_hits,T,"
               "T_se,seconds_to_T_se_1e-3,tile_mib\n");
    const double ss[] = {0.5, 1, 3, 6, 30};
    double ti = 30.0 * M_PI / 180.0;
    for (int k = 0; k < 5; k++)
        for (int accel = 1; accel >= 0; accel--) {
            btdf_sim_opts o;
            btdf_sim_opts_default(&o);
            o.smoothness = ss[k];
            o.theta_i = &ti;
            o.n_theta = 1;
            o.rays = 2000000;
            o.threads = 1;
            o.accel = accel;
            double cpu[9];
            btdf_sim_result *keep = NULL;
            for (int r = 0; r < reps; r++) {
                btdf_sim_result *res = NULL;
                clock_t c0 = clock();
                if (btdf_sim_run(&o, &res, NULL, 0) != BTDF_OK) {
                    btdf_sim_result_free(keep);
                    return;
                }
                cpu[r] = (double)(clock() - c0) / CLOCKS_PER_SEC;
                btdf_sim_result_free(keep); /* every run gives the same numbers */
                keep = res;
            }
            qsort(cpu, (size_t)reps, sizeof cpu[0], cmp_double);
            double med = reps % 2 ? cpu[reps / 2] : 0.5 * (cpu[reps / 2 - 1] + cpu[reps / 2]);
            const btdf_sim_tally *t = &keep->tally[0];
            double rate = (double)o.rays / (med > 0 ? med : 1e-9); /* clock() may read 0 */
            double need = (double)o.rays * (t->T.se / 1e-3) * (t->T.se / 1e-3);
            fprintf(f, "%s,%g,%llu,%llu,%.3f,%.4g,%.4f,%.5f,%.2g,%.3g,%.2f\n",
                    accel ? "hierarchy" : "plain-dda", ss[k], (unsigned long long)o.rays,
                    (unsigned long long)t->batches, med, rate, t->mean_hits.mean, t->T.mean,
                    t->T.se, need / rate, (double)keep->surface.tile_bytes / 1048576.0);
            fflush(f);
            btdf_sim_result_free(keep);
        }
}

/* First hits on one surface: the traversal alone, the plain DDA and the min/max
   hierarchy of src/sim/trace.c against Embree (when the benchmark was built with it),
   on the same rays: from the top of the slab at a uniform point of the tile, ti = 30,
   uniform azimuth, to the bottom of the slab. Embree gets the same triangles (two per
   cell, the same diagonal) in the same units (grid cells across, sigma up) as a mesh of
   the periodic tile with a margin the rays cannot cross, in 32-bit floats (its only
   vertex format), so its hit parameters differ from the double ones in the last
   float digits: the rows give the largest relative difference of t and the rays where
   one finds a hit and the other not. CPU seconds of the query loop, the median of REPS;
   the BVH build is timed apart. */
#define HIT_RAYS 1000000
static void bench_simhit(FILE *f, int reps)
{
    fprintf(f, "method,s,rays,cpu_seconds_median,hits_per_s_thread,hit_fraction,"
               "max_rel_dt_vs_dda,disagreements,build_seconds\n");
    const double ss[] = {0.5, 1, 3, 6, 30};
    const double ti = 30.0 * M_PI / 180.0;
    for (int k = 0; k < 5; k++) {
        int n = 256;
        double tau = ss[k], dx = tau / 16.0;
        sim_gen *g = sim_gen_new(n, dx, tau);
        sim_scratch *w = g ? sim_scratch_new(g) : NULL;
        sim_surface surf;
        if (!w || sim_gen_surface(g, w, sim_stream(1, 1, 0), &surf, NULL) != 0) {
            fprintf(stderr, "btdf-bench: out of memory\n");
            sim_scratch_free(w);
            sim_gen_free(g);
            return;
        }
        double *ray = malloc((size_t)HIT_RAYS * 7 * sizeof *ray); /* o, d, tmax */
        double *tref = malloc((size_t)HIT_RAYS * sizeof *tref);
        if (!ray || !tref) {
            free(ray);
            free(tref);
            sim_surface_free(&surf);
            sim_scratch_free(w);
            sim_gen_free(g);
            return;
        }
        uint64_t rng = sim_stream(1, 2, (uint64_t)k);
        for (int r = 0; r < HIT_RAYS; r++) {
            double p = 2.0 * M_PI * sim_uniform(&rng), *q = ray + (size_t)r * 7;
            q[0] = sim_uniform(&rng) * n;
            q[1] = sim_uniform(&rng) * n;
            q[2] = surf.hmax;
            q[3] = -sin(ti) * cos(p) / dx;
            q[4] = -sin(ti) * sin(p) / dx;
            q[5] = -cos(ti);
            q[6] = (surf.hmin - surf.hmax) / q[5]; /* to the slab's bottom; q[5] < 0 */
        }
        for (int accel = 0; accel <= 1; accel++) {
            double cpu[9];
            long hits = 0;
            for (int rep = 0; rep < reps; rep++) {
                clock_t c0 = clock();
                hits = 0;
                for (int r = 0; r < HIT_RAYS; r++) {
                    const double *q = ray + (size_t)r * 7;
                    double t, nrm[3];
                    int h = sim_first_hit(&surf, q, q + 3, 1, q[6], accel, &t, nrm);
                    hits += h;
                    if (accel == 0)
                        tref[r] = h ? t : -1.0;
                }
                cpu[rep] = (double)(clock() - c0) / CLOCKS_PER_SEC;
            }
            qsort(cpu, (size_t)reps, sizeof cpu[0], cmp_double);
            double med = cpu[reps / 2];
            fprintf(f, "%s,%g,%d,%.3f,%.4g,%.4f,0,0,0\n", accel ? "hierarchy" : "plain-dda",
                    ss[k], HIT_RAYS, med, HIT_RAYS / (med > 0 ? med : 1e-9),
                    (double)hits / HIT_RAYS);
            fflush(f);
        }
#if BENCH_EMBREE
        {
            /* the margin: a ray crosses at most (hmax - hmin) tan(ti) / dx cells */
            int m = (int)ceil((surf.hmax - surf.hmin) * tan(ti) / dx) + 2, side = n + 2 * m;
            clock_t b0 = clock();
            RTCDevice dev = rtcNewDevice("threads=1");
            RTCScene sc = rtcNewScene(dev);
            RTCGeometry geo = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
            float *v = rtcSetNewGeometryBuffer(geo, RTC_BUFFER_TYPE_VERTEX, 0,
                                               RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                               (size_t)(side + 1) * (size_t)(side + 1));
            unsigned *ix = rtcSetNewGeometryBuffer(geo, RTC_BUFFER_TYPE_INDEX, 0,
                                                   RTC_FORMAT_UINT3, 3 * sizeof(unsigned),
                                                   2 * (size_t)side * (size_t)side);
            for (int j = 0; j <= side; j++)
                for (int i = 0; i <= side; i++) {
                    size_t q = (size_t)j * (size_t)(side + 1) + (size_t)i;
                    int ii = ((i - m) % n + n) % n, jj = ((j - m) % n + n) % n;
                    v[3 * q] = (float)(i - m);
                    v[3 * q + 1] = (float)(j - m);
                    v[3 * q + 2] = (float)surf.h[(size_t)jj * (size_t)n + (size_t)ii];
                }
            for (int j = 0; j < side; j++)
                for (int i = 0; i < side; i++) {
                    unsigned a = (unsigned)(j * (side + 1) + i), b = a + 1;
                    unsigned c = a + (unsigned)(side + 1), d = c + 1;
                    unsigned *t = ix + 6 * ((size_t)j * (size_t)side + (size_t)i);
                    t[0] = a; t[1] = b; t[2] = d; /* (0,0) (1,0) (1,1) */
                    t[3] = a; t[4] = d; t[5] = c; /* (0,0) (1,1) (0,1) */
                }
            rtcCommitGeometry(geo);
            rtcAttachGeometry(sc, geo);
            rtcReleaseGeometry(geo);
            rtcSetSceneBuildQuality(sc, RTC_BUILD_QUALITY_HIGH);
            rtcCommitScene(sc);
            double build = (double)(clock() - b0) / CLOCKS_PER_SEC;
            double cpu[9], maxrel = 0.0;
            long hits = 0, dis = 0;
            for (int rep = 0; rep < reps; rep++) {
                struct RTCIntersectContext ctx;
                rtcInitIntersectContext(&ctx);
                clock_t c0 = clock();
                hits = dis = 0;
                maxrel = 0.0;
                for (int r = 0; r < HIT_RAYS; r++) {
                    const double *q = ray + (size_t)r * 7;
                    struct RTCRayHit rh;
                    rh.ray.org_x = (float)q[0];
                    rh.ray.org_y = (float)q[1];
                    rh.ray.org_z = (float)q[2];
                    rh.ray.dir_x = (float)q[3];
                    rh.ray.dir_y = (float)q[4];
                    rh.ray.dir_z = (float)q[5];
                    rh.ray.tnear = 0.0f;
                    rh.ray.tfar = (float)q[6];
                    rh.ray.mask = ~0u;
                    rh.ray.flags = 0;
                    rh.ray.time = 0.0f;
                    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                    rtcIntersect1(sc, &ctx, &rh);
                    int h = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
                    hits += h;
                    if (h != (tref[r] >= 0.0))
                        dis++;
                    else if (h) {
                        double rel = fabs((double)rh.ray.tfar - tref[r]) / tref[r];
                        maxrel = rel > maxrel ? rel : maxrel;
                    }
                }
                cpu[rep] = (double)(clock() - c0) / CLOCKS_PER_SEC;
            }
            qsort(cpu, (size_t)reps, sizeof cpu[0], cmp_double);
            double med = cpu[reps / 2];
            fprintf(f, "embree,%g,%d,%.3f,%.4g,%.4f,%.2g,%ld,%.3f\n", ss[k], HIT_RAYS, med,
                    HIT_RAYS / (med > 0 ? med : 1e-9), (double)hits / HIT_RAYS, maxrel, dis,
                    build);
            fflush(f);
            rtcReleaseScene(sc);
            rtcReleaseDevice(dev);
        }
#endif
        free(ray);
        free(tref);
        sim_surface_free(&surf);
        sim_scratch_free(w);
        sim_gen_free(g);
    }
}

void bench_pane(FILE *f, int reps); /* bench_pane.c */

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
    "           and its evaluations; not part of all), or pane (a pane's system,\n"
    "           1.5/3, flat back, 4 mm, and its Klems full and tree3 files; not part\n"
    "           of all)\n"
    "  REPS     runs per table, 1 to 9 (default 3); each row reports the median\n"
    "Timings depend on the machine's load: quote medians and the machine line.\n";

/* The model full at (1.5, 1): its tally (the per-material precomputation) on 1 and 2
   threads at the default paths, then the cost of one evaluation of the transmission
   and of the reflection over a 90 x 180 x 19 grid, beside btdf_rho_smith on the same
   grid (full = smith + a 40-term series). */
static void bench_full(FILE *out, int reps)
{
    fprintf(out, "# model full, n = 1.5, s = 1, %llu walks per ladder angle, median of %d\n",
            (unsigned long long)BTDF_FULL_PATHS_DEFAULT, reps);
    fprintf(out, "part,threads,wall_seconds,cpu_seconds,per_second\n");
    btdf_full *keep = NULL;
    for (int th = 1; th <= 2; th++) {
        double ws[9], cs[9];
        for (int r = 0; r < reps; r++) {
            btdf_full_opts o;
            btdf_full_opts_default(&o);
            o.threads = th;
            btdf_full *f = NULL;
            double w0 = now(), c0 = cpu_now();
            if (btdf_full_new(1.5, 1.0, &o, &f, NULL, 0) != BTDF_OK) {
                fprintf(stderr, "btdf-bench: btdf_full_new failed\n");
                exit(1);
            }
            ws[r] = now() - w0;
            cs[r] = cpu_now() - c0;
            if (!keep)
                keep = f;
            else
                btdf_full_free(f);
        }
        btdf_full_stats st;
        btdf_full_info(keep, &st);
        double w = median(ws, reps), c = median(cs, reps);
        fprintf(out, "tally (%d angles x %llu walks),%d,%.3f,%.3f,%.3g walks\n", st.nodes,
                (unsigned long long)st.paths, th, w, c, st.nodes * (double)st.paths / w);
    }
    for (int part = 0; part < 3; part++) {
        double ws[9], cs[9], acc = 0;
        size_t N = 0;
        for (int r = 0; r < reps; r++) {
            double w0 = now(), c0 = cpu_now();
            N = 0;
            for (int ti = 0; ti < 90; ti++)
                for (int to = 0; to < 180; to++)
                    for (int p = 0; p <= 180; p += 10, N++)
                        acc += part == 0   ? btdf_full_rho_deg(keep, ti, 90 + 0.5 * to, p)
                               : part == 1 ? btdf_full_rho_r_deg(keep, ti, 0.5 * to, p)
                                           : btdf_rho_smith_deg(1.5, 1.0, ti, 90 + 0.5 * to, p);
            ws[r] = now() - w0;
            cs[r] = cpu_now() - c0;
        }
        api_sink = acc;
        double w = median(ws, reps), c = median(cs, reps);
        fprintf(out, "%s,1,%.4f,%.4f,%.3g evaluations\n",
                part == 0 ? "btdf_full_rho_deg" : part == 1 ? "btdf_full_rho_r_deg"
                                                           : "btdf_rho_smith_deg (beside)",
                w, c, (double)N / w);
    }
    btdf_full_free(keep);
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
        strcmp(what, "sim") && strcmp(what, "simhit") && strcmp(what, "full") &&
        strcmp(what, "pane")) {
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
    if (!strcmp(what, "pane")) { /* tools/bench_pane.c */
        bench_pane(stdout, reps);
        return 0;
    }
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
    if (!strcmp(what, "all") || !strcmp(what, "nearone")) {
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
    if (!strcmp(what, "all") || !strcmp(what, "api"))
        api_bench(reps < 5 ? 5 : reps);
    if (!strcmp(what, "all") || !strcmp(what, "bsdf"))
        bsdf_bench(reps);
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
