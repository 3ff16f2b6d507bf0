/* SPDX-License-Identifier: MIT */
/* run.c: building, reporting and writing a .bsdf, for `tabulate -o F.bsdf` and `build`. */
#include <pthread.h>
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

void run_progress_start(run_progress *pr, int on, const char *label)
{
    memset(pr, 0, sizeof *pr);
    pr->on = on;
    size_t l = strlen(label);
    if (l > 20) /* the end of a long path says which file: keep the line for the bar */
        snprintf(pr->label, sizeof pr->label, "...%s", label + l - 17);
    else
        snprintf(pr->label, sizeof pr->label, "%s", label);
    pr->t0 = run_now();
}

/* One line of at most 79 columns: label, bar, percent, stage, time left. Called with
   pr->lock held (or before the ticker runs). */
static void draw(run_progress *pr, int force)
{
    double now = run_now(), el = now - pr->t0;
    if (!pr->on || !pr->stage[0] || el < 1.0 || (!force && pr->drawn && now - pr->last < 0.1))
        return;
    pr->last = now;
    pr->drawn = 1;
    char line[256], bar[17], eta[32] = "";
    double frac = pr->frac;
    if (frac >= 0.0) {
        int fill = (int)(frac * 16.0 + 0.5);
        for (int k = 0; k < 16; k++)
            bar[k] = k < fill ? '#' : '-';
        bar[16] = 0;
        if (frac >= 0.05 && frac < 1.0) /* too early an estimate says nothing */
            snprintf(eta, sizeof eta, "  ETA %.0f s", el * (1.0 - frac) / frac);
        snprintf(line, sizeof line, "%s [%s] %3.0f%% %s%s", pr->label, bar, 100.0 * frac,
                 pr->stage, eta);
    } else {
        snprintf(line, sizeof line, "%s: %s (%.0f s)", pr->label, pr->stage, el);
    }
    line[79] = 0; /* one terminal line: a longer one would scroll on every redraw */
    fprintf(stderr, "\r\033[K%s", line);
    fflush(stderr);
}

/* The ticker: redraws every quarter second, so the bar appears after a second and its
   time keeps moving even while one unit of work runs long. */
static void *ticker(void *arg)
{
    run_progress *pr = arg;
    struct timespec q = {0, 250000000L};
    for (;;) {
        nanosleep(&q, NULL);
        pthread_mutex_lock(&pr->lock);
        int stop = pr->stop;
        if (!stop)
            draw(pr, 1);
        pthread_mutex_unlock(&pr->lock);
        if (stop)
            return NULL;
    }
}

/* Sets what is shown, starting the ticker at the first update. */
static void update(run_progress *pr, const char *stage, double frac)
{
    if (!pr->on)
        return;
    if (!pr->running) {
        pr->stop = 0;
        if (pthread_mutex_init(&pr->lock, NULL) != 0)
            return;
        if (pthread_create(&pr->tid, NULL, ticker, pr) != 0) {
            pthread_mutex_destroy(&pr->lock);
            return; /* no ticker: no bar, the work goes on */
        }
        pr->running = 1;
    }
    pthread_mutex_lock(&pr->lock);
    snprintf(pr->stage, sizeof pr->stage, "%s", stage);
    pr->frac = frac;
    draw(pr, 0);
    pthread_mutex_unlock(&pr->lock);
}

void run_progress_cb(void *user, const char *stage, size_t done, size_t todo)
{
    run_progress *pr = user;
    char what[96];
    snprintf(what, sizeof what, "%s %zu/%zu", stage, done, done + todo);
    update(pr, what, done + todo ? (double)done / (double)(done + todo) : 0.0);
}

void run_progress_stage(run_progress *pr, const char *stage)
{
    update(pr, stage, -1.0);
}

void run_progress_end(run_progress *pr)
{
    if (pr->running) {
        pthread_mutex_lock(&pr->lock);
        pr->stop = 1;
        pthread_mutex_unlock(&pr->lock);
        pthread_join(pr->tid, NULL);
        pthread_mutex_destroy(&pr->lock);
        pr->running = 0;
    }
    if (pr->drawn) {
        fprintf(stderr, "\r\033[K");
        fflush(stderr);
    }
    pr->drawn = 0;
    pr->stage[0] = 0;
}

static int fail(const char *prog, int code, const char *path, const char *what)
{
    fprintf(stderr, "%s: %s: %s\n", prog, path, what);
    return code;
}

int run_series(const char *prog, const char *path, const btdf_params *p, double tol, int sides,
               int threads, int quiet, int best_effort, const char *prov, run_progress *pr)
{
    char msg[512] = "";
    btdf_scatfun *f = NULL;
    double t0 = run_now();
    btdf_status st = btdf_scatfun_build_progress(p, tol, (btdf_side)sides, threads,
                                                 run_progress_cb, pr, &f, msg, sizeof msg);
    double t1 = run_now();
    run_progress_stage(pr, "estimating the error");
    if (st != BTDF_OK && st != BTDF_EBUDGET) {
        run_progress_end(pr);
        return fail(prog, st == BTDF_EINVAL ? 2 : 1, path, msg[0] ? msg : btdf_strerror(st));
    }
    if (!f) {
        run_progress_end(pr);
        return fail(prog, 1, path, msg[0] ? msg : btdf_strerror(st));
    }
    /* The error a renderer will see: the format's own evaluation, per side. */
    int met = 1;
    char meta[1024];
    char nb[3][40];
    int k = snprintf(meta, sizeof meta, "{\"program\": \"btdftab %s\", \"ior\": [",
                     btdf_version_string());
    for (int c = 0; c < p->channels && k > 0 && (size_t)k < sizeof meta; c++) {
        btdf_format_double(p->ior[c], nb[0], sizeof nb[0]);
        k += snprintf(meta + k, sizeof meta - (size_t)k, "%s%s", c ? ", " : "", nb[0]);
    }
    btdf_format_double(p->smoothness, nb[0], sizeof nb[0]);
    btdf_format_double(p->k0, nb[1], sizeof nb[1]);
    btdf_format_double(tol, nb[2], sizeof nb[2]);
    if (k > 0 && (size_t)k < sizeof meta)
        k += snprintf(meta + k, sizeof meta - (size_t)k,
                      "], \"smoothness\": %s, \"k0\": %s, \"tolerance\": %s", nb[0], nb[1],
                      nb[2]);
    for (int s = BTDF_SIDE_ENTER; s <= BTDF_SIDE_LEAVE; s++) {
        if (!(sides & s))
            continue;
        btdf_report r;
        memset(&r, 0, sizeof r);
        double e0 = run_now();
        btdf_status es = btdf_scatfun_report(f, p, (btdf_side)s, 0, 0, REPORT_SEED, threads, &r);
        double e1 = run_now();
        run_progress_end(pr); /* the report line replaces the bar */
        if (es != BTDF_OK) {
            run_progress_end(pr);
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
        run_progress_stage(pr, "writing");
        st = btdf_write(&what, path, msg, sizeof msg);
        run_progress_end(pr);
        if (st != BTDF_OK)
            code = fail(prog, 1, path, msg[0] ? msg : btdf_strerror(st));
    }
    btdf_scatfun_free(f);
    return code;
}
