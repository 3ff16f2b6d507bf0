/* SPDX-License-Identifier: MIT */
/* grid.c: a table on a uniform (ti, to, phi) grid of Eq. 25. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "table/build.h"

typedef struct grid_job {
    const btdf_table_opts *o;
    tslice *s;
} grid_job;

static void grid_slice(void *arg, size_t k)
{
    grid_job *g = arg;
    const btdf_params *p = &g->o->params;
    tslice *s = &g->s[k];
    size_t nr = s->nr, nc = s->nc, nch = (size_t)p->channels;
    double *cph = malloc(nc * sizeof(double)), *sph = malloc(nc * sizeof(double));
    double *row = malloc(nc * sizeof(double));
    if (!cph || !sph || !row) {
        free(cph);
        free(sph);
        free(row);
        s->nr = 0; /* reported as BTDF_ENOMEM by the caller */
        return;
    }
    for (size_t j = 0; j < nc; j++) {
        cph[j] = cos(s->cols[j]);
        sph[j] = sin(s->cols[j]);
    }
    rho_in a;
    for (size_t c = 0; c < nch; c++) {
        double n = p->ior[c];
        rho_in_init_m(&a, sin(s->ti), cos(s->ti), p->smoothness, p->k0, p->model);
        for (size_t i = 0; i < nr; i++) {
            rho_out b;
            rho_out_init_m(&b, sin(s->rows[i]), fmin(cos(s->rows[i]), 0.0), p->smoothness,
                           p->k0, &a);
            /* The inner loop has no per-sample trigonometry and no calls: it vectorises. */
            for (size_t j = 0; j < nc; j++)
                row[j] = rho_kernel(n, p->smoothness, &a, &b, cph[j], sph[j]);
            for (size_t j = 0; j < nc; j++)
                s->vals[(i * nc + j) * nch + c] = row[j];
        }
    }
    free(cph);
    free(sph);
    free(row);
}

btdf_status tb_build_grid(const btdf_table_opts *o, btdf_table *t, char *msg,
                              size_t msglen)
{
    size_t nt = o->grid_ti, nr = o->grid_to, nc = o->grid_phi, nch = (size_t)o->params.channels;
    size_t max_samples = o->max_samples ? o->max_samples : DEFAULT_MAX_SAMPLES;
    size_t max_bytes = o->max_bytes ? o->max_bytes : DEFAULT_MAX_BYTES;
    /* counts are <= 1e5 each: nt * nr * nc < 1e15 fits size_t; bytes checked below */
    size_t total = nt * nr * nc;
    if (total > max_samples || total > max_bytes / (nch * sizeof(double))) {
        if (msg && msglen)
            snprintf(msg, msglen,
                     "grid of %zu x %zu x %zu = %zu samples exceeds the budget of %zu samples "
                     "or %zu bytes",
                     nt, nr, nc, total, max_samples, max_bytes);
        return BTDF_EBUDGET;
    }
    tslice *s = calloc(nt, sizeof *s);
    if (!s)
        return BTDF_ENOMEM;
    btdf_status st = BTDF_OK;
    for (size_t k = 0; k < nt && st == BTDF_OK; k++) {
        s[k].ti = nt > 1 ? o->ti_min + (o->ti_max - o->ti_min) * (double)k / (double)(nt - 1)
                         : o->ti_min;
        s[k].nr = nr;
        s[k].nc = nc;
        s[k].rows = malloc(nr * sizeof(double));
        s[k].cols = malloc(nc * sizeof(double));
        s[k].vals = malloc(nr * nc * nch * sizeof(double));
        if (!s[k].rows || !s[k].cols || !s[k].vals) {
            st = BTDF_ENOMEM;
            break;
        }
        for (size_t i = 0; i < nr; i++)
            s[k].rows[i] = o->to_min + (o->to_max - o->to_min) * (double)i / (double)(nr - 1);
        for (size_t j = 0; j < nc; j++)
            s[k].cols[j] = o->phi_min + (o->phi_max - o->phi_min) * (double)j / (double)(nc - 1);
    }
    if (st == BTDF_OK) {
        grid_job g = {o, s};
        core_parallel_for(o->threads, nt, grid_slice, &g);
        for (size_t k = 0; k < nt; k++)
            if (s[k].nr == 0)
                st = BTDF_ENOMEM;
    }
    for (size_t k = 0; k < nt; k++) {
        if (st == BTDF_OK && table_push_slice(t, &s[k]) != BTDF_OK)
            st = BTDF_ENOMEM;
        if (st != BTDF_OK) {
            free(s[k].rows);
            free(s[k].cols);
            free(s[k].vals);
        }
    }
    free(s);
    return st;
}

