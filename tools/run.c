/* SPDX-License-Identifier: MIT */
/* run.c: building, reporting and writing a .bsdf, for `tabulate -o F.bsdf` and `build`. */
#define _GNU_SOURCE /* open_memstream, as tools/btdftab.c uses it */
#include <math.h>
#include <stdint.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include <btdf/btdf_io.h>
#include <btdf/btdf_scatfun.h>

#include "report_json.h"
#include "run.h"

size_t run_json_escape(const char *s, char *out)
{
    size_t k = 0;
    const unsigned char *u = (const unsigned char *)(s ? s : "");
    while (*u) {
        /* a whole UTF-8 sequence passes as it is (RFC 8259 8.1) */
        size_t n = *u >= 0xF0 && *u <= 0xF4 ? 4 : *u >= 0xE0 ? 3 : *u >= 0xC2 && *u < 0xE0 ? 2 : 1;
        int whole = *u >= 0x80 && n > 1;
        for (size_t j = 1; whole && j < n; j++)
            whole = (u[j] & 0xC0) == 0x80;
        if (whole) {
            memcpy(out + k, u, n);
            k += n;
            u += n;
            continue;
        }
        if (*u == '"' || *u == '\\') {
            out[k++] = '\\';
            out[k++] = (char)*u;
        } else if (*u < 0x20 || *u >= 0x80) {
            /* control characters, and a byte no UTF-8 sequence holds, read as Latin-1 */
            k += (size_t)sprintf(out + k, "\\u%04x", (unsigned)*u);
        } else {
            out[k++] = (char)*u;
        }
        u++;
    }
    out[k] = 0;
    return k;
}

void run_json_open(FILE *f, const char *prov)
{
    fprintf(f, "{\n  \"program\": \"btdftab\",\n  \"version\": \"%s\",\n  \"command\": \"",
            btdf_version_string());
    size_t l = prov ? strlen(prov) : 0;
    char *e = malloc(6 * l + 1);
    if (e) {
        run_json_escape(prov, e);
        fputs(e, f);
        free(e);
    }
    fprintf(f, "\",\n");
}

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

/* Fewer units than this give no time left: four blocks of a Radiance file, or a few
   passes, differ too much in cost for one's time to predict the next. */
#define ETA_MIN_UNITS 8

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

/* One line of at most 79 columns: label, stage and counts, the bar where the fraction
   is known, the time elapsed, and the time left where it is honest. Called with
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
        /* The time left, where two updates in a row agreed on it (run_progress_cb) */
        if (pr->cb_end > now)
            snprintf(eta, sizeof eta, ", about %.0f s left", pr->cb_end - now);
        snprintf(line, sizeof line, "%s [%s] %s, %.0f s%s", pr->label, bar, pr->stage, el, eta);
    } else {
        snprintf(line, sizeof line, "%s: %s, %.0f s", pr->label, pr->stage, el);
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
    if (!pr->on)
        return;
    size_t total = done + todo;
    double frac = total ? (double)done / (double)total : 0.0;
    if (strncmp(pr->cb_stage, stage, sizeof pr->cb_stage - 1) != 0) { /* a new stage */
        snprintf(pr->cb_stage, sizeof pr->cb_stage, "%s", stage);
        pr->cb_total = total;
        pr->cb_frac = frac;
        pr->cb_t0 = run_now();
        pr->cb_unsure = 0;
        for (int g = 0; g < 4; g++) /* a stage seen to grow before, back after another */
            pr->cb_unsure |= !strcmp(pr->cb_grew[g], pr->cb_stage);
        pr->cb_end_prev = 0.0;
    } else if (total != pr->cb_total || frac < pr->cb_frac) {
        /* the work grew (refinement splits what it checks): the fraction says nothing */
        pr->cb_unsure = 1;
        for (int g = 0; g < 4; g++)
            if (!pr->cb_grew[g][0] || !strcmp(pr->cb_grew[g], pr->cb_stage)) {
                snprintf(pr->cb_grew[g], sizeof pr->cb_grew[g], "%s", pr->cb_stage);
                break;
            }
    }
    /* The time left from the stage's own pace, shown only for a stage of at least
       ETA_MIN_UNITS units whose total never changed, once a tenth of it is done, and
       while this update's prediction of its end agrees with the last one's to a fifth
       of the time left (units of unequal cost make it jump: then none is shown). */
    double now = run_now(), sel = now - pr->cb_t0, end = 0.0;
    if (!pr->cb_unsure && total >= ETA_MIN_UNITS && frac >= 0.1 && frac < 1.0)
        end = now + sel * (1.0 - frac) / frac; /* frac >= 0.1 */
    int agree = end > 0.0 && pr->cb_end_prev > 0.0 &&
                fabs(end - pr->cb_end_prev) <= 0.2 * (end - now);
    pr->cb_end_prev = end;
    pr->cb_total = total;
    pr->cb_frac = frac;
    if (pr->running)
        pthread_mutex_lock(&pr->lock);
    pr->cb_end = agree ? end : 0.0;
    if (pr->running)
        pthread_mutex_unlock(&pr->lock);
    char what[96];
    if (pr->cb_unsure)
        snprintf(what, sizeof what, "%s %zu (+%zu)", stage, done, todo);
    else
        snprintf(what, sizeof what, "%s %zu/%zu", stage, done, total);
    update(pr, what, pr->cb_unsure ? -1.0 : frac);
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

/* "prog: path: what" on standard error ("prog: what" for an empty path); returns code. */
static int fail(const char *prog, int code, const char *path, const char *what)
{
    if (path[0])
        fprintf(stderr, "%s: %s: %s\n", prog, path, what);
    else
        fprintf(stderr, "%s: %s\n", prog, what);
    return code;
}

int run_series_blocks(int sides, int part)
{
    if (!sides)
        sides = BTDF_SIDE_BOTH;
    if (!part)
        part = BTDF_PART_BOTH;
    return ((part & BTDF_PART_TRANSMISSION) ? sides : 0) |
           ((part & BTDF_PART_REFLECTION) ? sides << 2 : 0);
}

double run_series_tolerance(int part, int given, double tol)
{
    /* Default tolerance: 1e-3 for transmission blocks alone (about 20 s, 12 MB for
       s = 3), 1e-2 once the file holds reflection: four blocks at 1e-3 outgrow the
       format's node budget (s = 3: 964 nodes, 368 million coefficients after 619 s,
       not met; at 1e-2: 296 nodes, 21.5 MB in 34 s; docs/scatfun.md) */
    if (given)
        return tol;
    return (!part || (part & BTDF_PART_REFLECTION)) ? 1e-2 : tol;
}

/* What the request needs at least (the builder refuses what cannot fit) and the
   reflection below 1e-2, said before the work (unless quiet). */
static void series_warnings(const char *prog, const char *path, const btdf_params *p,
                            double tol, int sides, int quiet)
{
    /* What the request needs at least (the builder refuses what cannot fit): said
       before the work when it is large, with the numbers. */
    btdf_scatfun_need nd;
    if (!quiet && btdf_scatfun_predict(p, tol, (btdf_side)sides, &nd, NULL, 0) == BTDF_OK &&
        nd.half_nodes <= BTDF_SCATFUN_MAX_HALF_NODES &&
        (nd.half_nodes > BTDF_SCATFUN_MAX_HALF_NODES / 2 || nd.build_bytes > ((size_t)1 << 30)))
        fprintf(stderr,
                "%s: %s: warning: this request needs at least %zu of the format's %d half "
                "nodes (a lobe %.3g deg wide, nodes %.3g deg apart), a file of %.3g MB and "
                "%.3g MB to build, likely minutes; --max-memory and --max-samples bound it\n",
                prog, path, nd.half_nodes, BTDF_SCATFUN_MAX_HALF_NODES, nd.lobe_deg,
                nd.spacing_deg, 1e-6 * (double)nd.file_bytes, 1e-6 * (double)nd.build_bytes);
    /* Reflection below 1e-2: the reflection inside the glass has a cusp where total
       reflection starts, which the lobe's width does not predict; the measured case
       (docs/scatfun.md, "What a request needs") is said before the work. */
    if (!quiet && (sides & (BTDF_SCATFUN_R_TOP | BTDF_SCATFUN_R_BOTTOM)) && tol < 1e-2)
        fprintf(stderr,
                "%s: %s: warning: reflection blocks at tolerance %g: n = 1.5, s = 3 with all "
                "four blocks at 1e-3 measured 592 nodes, 99.7 million coefficients, 2.9 GB "
                "and 278 CPU s before the coefficient budget stopped it, not met; --part "
                "transmission, or --max-memory and --max-samples to bound the build\n",
                prog, path, tol);
}

/* The .bsdf metadata's JSON up to the material (program, ior, smoothness, k0,
   tolerance, the model unless xu-sun) into meta; returns snprintf's count so far. */
static int series_meta(char *meta, size_t len, const btdf_params *p, double tol)
{
    char nb[3][40];
    int k = snprintf(meta, len, "{\"program\": \"btdftab %s\", \"ior\": [",
                     btdf_version_string());
    for (int c = 0; c < p->channels && k > 0 && (size_t)k < len; c++) {
        btdf_format_double(p->ior[c], nb[0], sizeof nb[0]);
        k += snprintf(meta + k, len - (size_t)k, "%s%s", c ? ", " : "", nb[0]);
    }
    btdf_format_double(p->smoothness, nb[0], sizeof nb[0]);
    btdf_format_double(p->k0, nb[1], sizeof nb[1]);
    btdf_format_double(tol, nb[2], sizeof nb[2]);
    if (k > 0 && (size_t)k < len)
        k += snprintf(meta + k, len - (size_t)k,
                      "], \"smoothness\": %s, \"k0\": %s, \"tolerance\": %s", nb[0], nb[1],
                      nb[2]);
    /* the model, for every model but xu-sun (whose files keep their bytes: no key is
       xu-sun) */
    if (p->model != BTDF_MODEL_XU_SUN && k > 0 && (size_t)k < len)
        k += snprintf(meta + k, len - (size_t)k, ", \"model\": \"%s\"",
                      btdf_model_name(p->model));
    return k;
}

/* meta (k bytes of a buffer of len) with the command whole and escaped (a quote or a
   newline in a path, any length) and the closing brace; NULL when out of memory. */
static char *series_metafull(const char *meta, size_t len, int k, const char *prov)
{
    size_t lp = prov ? strlen(prov) : 0;
    char *metafull = malloc(len + 6 * lp + 32);
    if (metafull && k > 0 && (size_t)k < len) {
        memcpy(metafull, meta, (size_t)k);
        size_t q = (size_t)k;
        q += (size_t)sprintf(metafull + q, ", \"command\": \"");
        q += run_json_escape(prov, metafull + q);
        memcpy(metafull + q, "\"}", 3);
    } else if (metafull) {
        snprintf(metafull, len, "%s", meta);
    }
    return metafull;
}

int run_series(const char *prog, const char *path, const btdf_params *p, double tol, int sides,
               int threads, int quiet, int best_effort, const char *prov, run_progress *pr)
{
    return run_series_ex(prog, path, p, tol, sides, threads, quiet, best_effort, prov, NULL, 0, 0,
                         pr);
}

int run_series_ex(const char *prog, const char *path, const btdf_params *p, double tol,
                  int sides, int threads, int quiet, int best_effort, const char *prov,
                  const char *report, size_t max_coeffs, size_t max_bytes, run_progress *pr)
{
    char msg[512] = "";
    btdf_scatfun *f = NULL;
    series_warnings(prog, path, p, tol, sides, quiet);
    double t0 = run_now();
    btdf_status st = btdf_scatfun_build_progress(p, tol, (btdf_side)sides, threads, max_coeffs,
                                                 max_bytes, run_progress_cb, pr, &f, msg,
                                                 sizeof msg);
    double t1 = run_now();
    run_progress_stage(pr, "estimating the error");
    if (!f || (st != BTDF_OK && st != BTDF_EBUDGET))
        run_progress_end(pr);
    if (st == BTDF_EBUDGET && !f) /* refused before any work: the request cannot be met */
        return fail(prog, 3, path, msg);
    if (st != BTDF_OK && st != BTDF_EBUDGET)
        return fail(prog, st == BTDF_EINVAL ? 2 : 1, path, msg[0] ? msg : btdf_strerror(st));
    if (!f)
        return fail(prog, 1, path, msg[0] ? msg : btdf_strerror(st));
    /* The error a renderer will see: the format's own evaluation, per side. */
    int met = 1;
    double worst = -1.0; /* the largest e_L1 max the report lines show, and its block */
    const char *worst_name = "";
    /* the builder's reason without its own estimate (its test angles are not the
       report's): the message quotes the report's number */
    char *own = strstr(msg, "; its own estimate");
    if (own)
        *own = 0;
    char meta[1024];
    int k = series_meta(meta, sizeof meta, p, tol);
    btdf_report reps[4];
    memset(reps, 0, sizeof reps);
    for (int bi = 0; bi < 4; bi++) {
        int s = 1 << bi; /* btdf_scatfun_block */
        if (!(sides & s))
            continue;
        btdf_report r;
        memset(&r, 0, sizeof r);
        double e0 = run_now();
        btdf_status es = btdf_scatfun_report(f, p, (btdf_side)s, 0, 0, REPORT_SEED, threads, &r);
        double e1 = run_now();
        run_progress_end(pr); /* the report line replaces the bar */
        if (es != BTDF_OK) {
            for (int q = 0; q < 4; q++)
                btdf_report_clear(&reps[q]);
            btdf_scatfun_free(f);
            fprintf(stderr, "%s: %s: error estimate: %s\n", prog, path, btdf_strerror(es));
            return 1;
        }
        int ok = r.e_l1_max <= tol;
        met = met && ok;
        const char *name = report_block_name[bi];
        if (r.e_l1_max > worst) {
            worst = r.e_l1_max;
            worst_name = name;
        }
        char upto[96];
        double top = 0.0;
        for (size_t a = 0; a < r.test_angles; a++)
            top = fmax(top, r.per_ti[a].ti);
        int n = snprintf(upto, sizeof upto, " (up to %.6g deg", top * 180.0 / M_PI);
        snprintf(upto + n, sizeof upto - (size_t)n, p->model == BTDF_MODEL_FULL ? "; its "
                 "tally's noise floor %.2g)" : ")", r.ms_noise); /* full: and its noise */
        if (!quiet)
            fprintf(stderr,
                    "%s: %s (%s, as a renderer reads it): %zu nodes, %zu coefficients and "
                    "build %.3f s of the whole file; this block's estimate %.3f s (%zu angles, "
                    "%zu points)%s%s%s; e_L1 max %.3g "
                    "mean %.3g; e_max max %.3g; e_T max %.3g%s\n",
                    prog, path, name, btdf_scatfun_node_count(f), btdf_scatfun_coeff_count(f),
                    t1 - t0, e1 - e0, r.test_angles, r.test_points,
                    /* xu-sun's line keeps its words; another model is named, with the
                       report's top test angle */
                    p->model == BTDF_MODEL_XU_SUN ? "" : "; error against ",
                    p->model == BTDF_MODEL_XU_SUN ? "" : btdf_model_name(p->model),
                    p->model == BTDF_MODEL_XU_SUN ? "" : upto,
                    r.e_l1_max, r.e_l1_mean,
                    r.e_max_max, r.e_t_max, ok ? "; tolerance met" : "; TOLERANCE NOT MET");
        if (k > 0 && (size_t)k < sizeof meta)
            k += snprintf(meta + k, sizeof meta - (size_t)k,
                          ", \"%s\": {\"e_l1_max\": %.4g, \"e_max_max\": %.4g, \"e_t_max\": %.4g}",
                          name, r.e_l1_max, r.e_max_max, r.e_t_max);
        reps[bi] = r; /* cleared below */
    }
    double peak = btdf_scatfun_a0_peak(f);
    if (!quiet && peak > BTDF_SCATFUN_PBRT_FLOAT_SAFE_A0)
        fprintf(stderr,
                "%s: %s: warning: values reach %.4g (a_0 peak) > %g: pbrt-v3 built with "
                "single-precision floats (its default) can loop forever sampling this file; "
                "render it with pbrt-v3 built with PBRT_FLOAT_AS_DOUBLE (docs/scatfun.md)\n",
                prog, path, peak, BTDF_SCATFUN_PBRT_FLOAT_SAFE_A0);
    /* the command whole and escaped (a quote or a newline in a path, any length): the
       numbers above fit the buffer, the command goes on in its own */
    char *metafull = series_metafull(meta, sizeof meta, k, prov);
    int code = 0;
    if (!met && !best_effort) {
        fprintf(stderr, "%s: %s: tolerance %g not met: e_L1 max %.3g (%s)%s%s; nothing written "
                        "(pass --best-effort to write it anyway)\n",
                prog, path, tol, worst, worst_name, msg[0] ? "; " : "", msg);
        code = 3;
    } else {
        /* the file and its report appear together or not at all */
        btdf_outputs_begin();
        btdf_output what = {NULL, f, NULL, NULL, metafull ? metafull : meta, NULL};
        run_progress_stage(pr, "writing");
        st = btdf_write(&what, path, msg, sizeof msg);
        run_progress_end(pr);
        if (st == BTDF_OK && report &&
            report_json_series(prog, report, p, f, reps, tol, t1 - t0, met, prov) != 0) {
            btdf_outputs_abort();
            code = 1; /* the report's failure is said */
        } else if (st == BTDF_OK) {
            st = btdf_outputs_commit(msg, sizeof msg);
        } else {
            btdf_outputs_abort();
        }
        if (code == 0 && st != BTDF_OK) {
            code = fail(prog, 1, path, msg[0] ? msg : btdf_strerror(st));
        } else if (code == 0 && !met) {
            /* --best-effort wrote it, but the run did not do what was asked */
            fprintf(stderr, "%s: %s: tolerance %g not met: e_L1 max %.3g (%s)%s%s; written "
                            "anyway (--best-effort), exit 3\n",
                    prog, path, tol, worst, worst_name, msg[0] ? "; " : "", msg);
            code = 3;
        }
    }
    for (int q = 0; q < 4; q++)
        btdf_report_clear(&reps[q]);
    free(metafull);
    btdf_scatfun_free(f);
    return code;
}

/* The report's own estimate of the file's integral is a sum too: each report is also
   run at a quarter of the points (same seed, so the same stratified angles), and the
   JSON gives that estimate beside it ("T_file_coarse", report_json.h). */
#define RAD_COARSE 4

int run_radiance(const char *prog, const char *path, const char *report, const btdf_params *p,
                 btdf_rad_basis basis, double tol, int threads, int quiet, int best_effort,
                 const char *prov, run_progress *pr)
{
    char msg[512] = "";
    btdf_rad *x = NULL;
    btdf_status st = btdf_rad_build_progress(p, basis, tol, threads, run_progress_cb, pr, &x,
                                             msg, sizeof msg);
    run_progress_stage(pr, "estimating the error");
    if (st != BTDF_OK && st != BTDF_EBUDGET) {
        run_progress_end(pr);
        return fail(prog, st == BTDF_EINVAL ? 2 : 1, path, msg[0] ? msg : btdf_strerror(st));
    }
    /* The material's name in the scene: the file's base name without .xml. */
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    char name[128];
    size_t len = strlen(base) > 4 ? strlen(base) - 4 : strlen(base);
    if (len > sizeof name - 1) { /* cut at a character's start, never inside UTF-8 */
        len = sizeof name - 1;
        while (len > 0 && ((unsigned char)base[len] & 0xC0) == 0x80)
            len--;
    }
    snprintf(name, sizeof name, "%.*s", (int)len, base);
    btdf_rad_set_name(x, name);
    btdf_report rep[4 * 3], coarse[4 * 3];
    memset(rep, 0, sizeof rep);
    memset(coarse, 0, sizeof coarse);
    int met = 1, code = 0, nb = btdf_rad_block_count(x), nch = btdf_rad_channels(x);
    for (int k = 0; k < nb && code == 0; k++) {
        btdf_rad_block_info b;
        btdf_rad_block(x, k, &b);
        double el1 = 0.0, et = 0.0;
        for (int c = 0; c < nch && code == 0; c++) {
            btdf_report *rk = &rep[k * 3 + c];
            btdf_status es = btdf_rad_report_channel(x, k, c, 0, 0, REPORT_SEED, threads, rk);
            if (es == BTDF_OK && report) /* 8192 / RAD_COARSE points, the same angles */
                es = btdf_rad_report_channel(x, k, c, 0, 8192 / RAD_COARSE, REPORT_SEED,
                                             threads, &coarse[k * 3 + c]);
            if (es != BTDF_OK) {
                code = fail(prog, 1, path, btdf_strerror(es));
                break;
            }
            el1 = fmax(el1, rk->e_l1_max);
            et = fmax(et, rk->e_t_max);
            met = met && rk->met;
            if (k == 0 && c == 0)
                run_progress_end(pr); /* the report lines replace the bar */
            /* every line its verdict, with the range it covers: a tree's tolerance
               holds up to BTDF_RAD_TI_CHECKED_DEG (docs/radiance.md); a Klems matrix
               holds exact patch averages, its e_L1 is the basis's resolution */
            char verdict[160];
            if (basis == BTDF_RAD_TREE3)
                snprintf(verdict, sizeof verdict, "; %s %g %s for light up to %g deg (not "
                         "held beyond)", rk->met ? "tolerance" : "TOLERANCE", tol,
                         rk->met ? "met" : "NOT MET", BTDF_RAD_TI_CHECKED_DEG);
            else
                snprintf(verdict, sizeof verdict, "; verdict: exact patch averages over "
                         "0-90 deg (no tolerance: the basis sets e_L1)");
            char against[96] = ""; /* full: and the noise floor of its tally */
            if (p->model == BTDF_MODEL_FULL)
                snprintf(against, sizeof against, "; error against full (its tally's noise "
                         "floor %.2g)", rk->ms_noise);
            char chn[48] = "";
            if (nch == 3)
                snprintf(chn, sizeof chn, ", channel %s (n = %.6g)", report_rad_channel[c],
                         p->ior[c]);
            if (!quiet)
                fprintf(stderr,
                        "%s: %s: %s (light %s, as Radiance reads it%s): %zu %s; build %.3f s "
                        "of all blocks, this block's estimate %.3f s (%zu angles, %zu points); "
                        "e_L1 max %.3g (%.3g up to "
                        "%g deg) mean %.3g; e_max max %.3g; e_T max %.3g%s%s\n",
                        prog, path, b.label,
                        b.light == BTDF_SIDE_ENTER ? "entering, n" : "leaving, 1/n", chn,
                        b.values, basis == BTDF_RAD_TREE3 ? "leaves" : "entries",
                        btdf_rad_seconds_build(x), rk->seconds_estimate, rk->test_angles,
                        rk->test_points, rk->e_l1_max, btdf_rad_e_l1_checked(rk),
                        BTDF_RAD_TI_CHECKED_DEG, rk->e_l1_mean, rk->e_max_max, rk->e_t_max,
                        against, verdict);
        }
        btdf_rad_set_errors(x, k, el1, et);
    }
    if (code == 0 && !met && !best_effort) {
        fprintf(stderr, "%s: %s: tolerance %g not met%s%s; nothing written (pass --best-effort "
                        "to write it anyway)\n",
                prog, path, tol, msg[0] ? ": " : "", msg);
        code = 3;
    }
    char *buf = NULL;
    size_t blen = 0;
    if (code == 0 && report) {
        FILE *f = open_memstream(&buf, &blen);
        if (!f) {
            code = fail(prog, 1, report, "out of memory");
        } else {
            report_json_radiance(f, x, p, rep, coarse, prov);
            if (fclose(f) != 0)
                code = fail(prog, 1, report, "out of memory");
        }
    }
    if (code == 0) { /* the file and its report appear together or not at all */
        btdf_outputs_begin();
        btdf_write_opts w = {NULL, prov, NULL};
        btdf_output what = {NULL, NULL, NULL, &w, NULL, x};
        st = btdf_write(&what, path, msg, sizeof msg);
        if (st == BTDF_OK && report)
            st = btdf_write_buffer(report, ".json", buf, blen, msg, sizeof msg);
        if (st == BTDF_OK)
            st = btdf_outputs_commit(msg, sizeof msg);
        else
            btdf_outputs_abort();
        if (st != BTDF_OK)
            code = fail(prog, 1, path, msg[0] ? msg : btdf_strerror(st));
    }
    run_progress_end(pr); /* if no block was reported */
    free(buf);
    for (int k = 0; k < 4 * 3; k++) {
        btdf_report_clear(&rep[k]);
        btdf_report_clear(&coarse[k]);
    }
    btdf_rad_free(x);
    return code;
}

/* ------------------------------------------------------------------------- */
/* tables                                                                    */
/* ------------------------------------------------------------------------- */

size_t run_peak_rss(void)
{
    struct rusage ru; /* Linux reports KiB */
    return getrusage(RUSAGE_SELF, &ru) == 0 ? (size_t)ru.ru_maxrss * 1024u : 0;
}

/* One part's line for standard error (without the total time, added when printed). */
static void table_line(char *line, size_t len, const run_table_req *rq, const btdf_table *pt,
                       const btdf_report *rk, int estimated)
{
    const btdf_table_opts *o = &rq->o;
    /* "table" as before for the transmission alone; the part's name otherwise */
    int refl = btdf_table_get_kind(pt) == BTDF_TABLE_FACET_REFLECTION;
    const char *what = !rq->name_parts ? "table"
                       : refl          ? "reflection table"
                                       : "transmission table";
    if (!estimated) {
        snprintf(line, len,
                 "%s: %s: %zu slices, %zu samples; tabulation %.3f s; error not estimated "
                 "(--estimate none); peak memory %.1f MiB",
                 rq->prog, what, rk->slices, rk->samples, rk->seconds_build,
                 (double)rk->peak_bytes / 1048576.0);
        return;
    }
    char emax[96];
    if (rk->e_max_angles)
        snprintf(emax, sizeof emax, "e_max max %.3g mean %.3g", rk->e_max_max, rk->e_max_mean);
    else
        snprintf(emax, sizeof emax, "e_max n/a (%s < 0.01 at every test angle)",
                 refl ? "R" : "T");
    char against[96]; /* full: and the noise floor of its tally */
    snprintf(against, sizeof against, "%s", btdf_model_name(o->params.model));
    if (o->params.model == BTDF_MODEL_FULL)
        snprintf(against, sizeof against, "full (its tally's noise floor %.2g)", rk->ms_noise);
    snprintf(line, len,
             "%s: %s: %zu slices, %zu samples; tabulation %.3f s, estimate %.3f s "
             "(%s, %zu angles, %zu points%s); error against %s: e_L1 max %.3g mean %.3g; %s; "
             "e_T max %.3g mean %.3g; peak memory %.1f MiB%s",
             rq->prog, what, rk->slices, rk->samples, rk->seconds_build, rk->seconds_estimate,
             o->estimate == BTDF_ESTIMATE_FAST ? "fast" : "full", rk->test_angles,
             rk->test_points,
             rk->estimate_in_build ? "; the builder's last check, inside the tabulation" : "",
             against, rk->e_l1_max, rk->e_l1_mean, emax, rk->e_t_max,
             rk->e_t_mean,
             (double)rk->peak_bytes / 1048576.0,
             o->kind == BTDF_TABLE_GRID ? ""
                                        : (rk->met ? "; tolerance met" : "; TOLERANCE NOT MET"));
}

int run_table(const run_table_req *rq)
{
    const btdf_table_opts *o = &rq->o;
    const char *prog = rq->prog;
    run_progress *pr = rq->pr;
    char msg[512] = "";
    btdf_table *t = NULL;
    btdf_report rs[2]; /* one per part: the table's own, and the reflection of both */
    memset(rs, 0, sizeof rs);
    char lines[2][640];
    lines[0][0] = lines[1][0] = '\0';
    int code = 0, nparts = 0, estimated = o->estimate != BTDF_ESTIMATE_NONE, met_all = 1;
    double t0 = run_now(), e_worst = 0.0;
    const char *prov = rq->prov;
    char prov2[1200];
    btdf_status st = btdf_table_build(o, &t, msg, sizeof msg);
    double t1 = run_now();
    run_progress_stage(pr, "estimating the error");
    if (st != BTDF_OK && st != BTDF_EBUDGET) {
        run_progress_end(pr);
        code = fail(prog, st == BTDF_EINVAL ? 2 : 1, "", msg[0] ? msg : btdf_strerror(st));
        goto done;
    }
    if (!t) { /* the budget cannot hold the coarsest table: nothing was built */
        run_progress_end(pr);
        code = fail(prog, st == BTDF_EBUDGET ? 3 : 1, "", msg[0] ? msg : btdf_strerror(st));
        goto done;
    }
    nparts = btdf_table_parts(t) == BTDF_PART_BOTH ? 2 : 1;
    const btdf_table *pt[2] = {t, btdf_table_part(t, BTDF_PART_REFLECTION)};
    for (int k = 0; k < nparts; k++) {
        btdf_report *rk = &rs[k];
        if (estimated) {
            /* For an adaptive table this is the builder's own check (the same request
               returns it): the report and the builder's verdict cannot differ. */
            int fast = o->estimate == BTDF_ESTIMATE_FAST;
            btdf_status es = btdf_table_estimate(pt[k], o->ti_min, o->ti_max, fast ? 16 : 0,
                                                 fast ? 2048 : 0, REPORT_SEED, o->threads, rk);
            if (es != BTDF_OK) {
                run_progress_end(pr);
                fprintf(stderr, "%s: error estimate: %s\n", prog, btdf_strerror(es));
                code = 1;
                goto done;
            }
        } else {
            rk->slices = btdf_table_slice_count(pt[k]);
            rk->samples = btdf_table_node_count(pt[k]);
        }
        rk->seconds_build = t1 - t0;
        rk->peak_bytes = run_peak_rss();
        rk->tolerance = o->kind == BTDF_TABLE_GRID ? 0.0 : o->tolerance;
        rk->metric = o->metric;
        double e = o->metric == BTDF_METRIC_MAX ? rk->e_max_max : rk->e_l1_max;
        rk->met = o->kind == BTDF_TABLE_GRID || !estimated ? 1 : e <= o->tolerance;
        met_all &= rk->met;
        e_worst = fmax(e_worst, e);
        table_line(lines[k], sizeof lines[k], rq, pt[k], rk, estimated);
    }
    if (!estimated && msg[0])
        fprintf(stderr, "%s: %s\n", prog, msg); /* the budget stopped the unchecked pass */
    if (o->kind != BTDF_TABLE_GRID && !met_all) {
        for (int k = 0; k < nparts; k++) {
            if (!rq->quiet)
                fprintf(stderr, "%s; total %.3f s\n", lines[k], run_now() - t0);
            lines[k][0] = '\0'; /* printed */
        }
        fprintf(stderr, "%s: %s: the table reached %s error %.3g, above the tolerance %g%s%s\n",
                prog, rq->name ? rq->name : "table", o->metric == BTDF_METRIC_MAX ? "max" : "L1",
                e_worst, o->tolerance, msg[0] ? ": " : "", msg);
        if (!rq->best_effort) {
            fprintf(stderr, "%s: nothing written; %s, loosen --tolerance, or pass "
                            "--best-effort\n", prog,
                    strstr(msg, "memory") ? "raise --max-memory"
                    : strstr(msg, "budget") ? "raise --max-samples (and --max-memory)"
                                             : "try again with --estimate full");
            code = 3;
        } else if (rq->missed) {
            *rq->missed = 1;
        }
    }
    if (!estimated) {
        snprintf(prov2, sizeof prov2, "%s; error not estimated", prov ? prov : "btdftab");
        prov = prov2;
    }
    btdf_write_opts w = {estimated ? &rs[0] : NULL, prov, estimated && nparts == 2 ? &rs[1] : NULL};
    /* The tables, their pictures and the report appear together or not at all. */
    btdf_outputs_begin();
    for (int k = 0; k < rq->nouts && code == 0; k++) {
        const run_table_out *out = &rq->outs[k];
        btdf_preview_opts po;
        if (out->preview) {
            po = *out->preview;
            po.table = t;
        }
        int table = !out->preview || out->with_table;
        btdf_output what = {table ? t : NULL, NULL, out->preview ? &po : NULL, &w, NULL, NULL};
        if (table && strcmp(out->path, "-"))
            run_progress_stage(pr, "writing");
        st = btdf_write(&what, out->path, msg, sizeof msg);
        if (table)
            run_progress_end(pr);
        if (st != BTDF_OK)
            code = fail(prog, 1, out->path, msg[0] ? msg : btdf_strerror(st));
    }
    if (code == 0 && rq->report)
        code = report_json_table(prog, rq->report, o, btdf_table_get_kind(t), &rs[0], prov,
                                 nparts == 2 ? &rs[1] : NULL);
    if (code == 0) {
        st = btdf_outputs_commit(msg, sizeof msg);
        if (st != BTDF_OK)
            code = fail(prog, 1, "", msg[0] ? msg : btdf_strerror(st));
    } else {
        btdf_outputs_abort();
    }
    /* The one-line report, last: the total covers tabulation, estimate and writing. */
    for (int k = 0; k < nparts; k++)
        if (!rq->quiet && lines[k][0])
            fprintf(stderr, "%s; total %.3f s\n", lines[k], run_now() - t0);
done:
    run_progress_end(pr);
    btdf_report_clear(&rs[0]);
    btdf_report_clear(&rs[1]);
    btdf_table_free(t);
    return code;
}
