/* SPDX-License-Identifier: MIT */
/* bench_api.c: the public evaluation entry points beside the internal kernel, the tool's
   number I/O and the model full (btdf-bench api, full). */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "btdf.h"
#include "bench.h"
#include "fastnum.h"
#include "model/kernel.h"
#include "table/table.h"

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

double cpu_now(void)
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

void api_bench(int reps)
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


/* The model full at (1.5, 1): its tally (the per-material precomputation) on 1 and 2
   threads at the default paths, then the cost of one evaluation of the transmission
   and of the reflection over a 90 x 180 x 19 grid, beside btdf_rho_smith on the same
   grid (full = smith + a 40-term series). */
void bench_full(FILE *out, int reps)
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
