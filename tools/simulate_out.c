/* SPDX-License-Identifier: MIT */
/* simulate_out.c: btdftab simulate's tables and picture: the outgoing distribution as
   CSV and as an EXR grid table, and the --preview chart. */
#include "simulate_out.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <btdf/btdf.h>
#include <btdf/btdf_io.h>
#include <btdf/btdf_preview.h>
#include <btdf/btdf_sim.h>

#include "cmd_simulate_pane.h"
#include "simchart.h"
#include "textout.h"

static int fail(int code, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    code = simulate_vfail(code, fmt, ap);
    va_end(ap);
    return code;
}

/* Integral of |cos to| over histogram bin (theta_bin, any phi bin), sr: the bin's
   solid angle weighted by the cosine, both halves of |phi| counted. */

static double cos_sr(int nt, int np, int it)
{
    double w = 1.5707963267948966 / nt, a = sin(w * it), b = sin(w * (it + 1));
    if (profile_1d) /* integral of |cos to| d to over the bin, one side of the normal */
        return b - a;
    return 0.5 * (b * b - a * a) * 2.0 * (3.141592653589793 / np);
}

/* The outgoing distribution as CSV (docs/simulation.md): the header row, the comment
   block of docs/formats.md's conventions, one row per (case, part, bin), the end line.
   Built in memory and written whole by btdf_write_buffer (a temporary renamed at the
   end), so an error leaves no file. */
int write_dist(const char *path, const char *prov, const btdf_sim_opts *o,
                      const btdf_sim_result *r)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    if (!f)
        return fail(1, "%s: out of memory for the table", path);
    int nt = r->theta_bins, np = r->phi_bins;
    unsigned long long rows = (unsigned long long)r->count * 2ull * (unsigned long long)nt *
                              (unsigned long long)np;
    fputs("theta_i_deg,theta_o_deg,phi_deg,channel,part,rho,rho_se,rho_1,rho_1_se,ti_rad,"
          "to_rad,phi_rad,cos_sr\n", f);
    fprintf(f, "# btdftab %s simulation\n# kind: simulated\n# channels: %d\n# ior:",
            btdf_version_string(), o->channels);
    for (int c = 0; c < o->channels; c++) {
        fputc(c ? ',' : ' ', f);
        text_num(f, o->ior[c]);
    }
    fputs("\n# smoothness: ", f);
    text_num(f, o->smoothness);
    simpane_csv(f, o);
    if (profile_1d)
        fputs("\n# units: a 1D profile (rays in the plane of incidence): rho in 1/rad, no cosine "
              "factor, the fraction of the incident flux in the bin / cos_sr, cos_sr the "
              "integral of |cos theta_o| d theta_o over the bin (rad); phi 0 backward, 180 "
              "forward; rho_se its standard error; angles in degrees and radians\n",
              f);
    else
        fputs("\n# units: rho in 1/sr, no cosine factor, the bin's mean weighted by |cos "
              "theta_o| (fraction of the incident flux in the bin / cos_sr); rho_se its "
              "standard error; angles in degrees and radians; cos_sr in sr\n",
              f);
    fprintf(f, "# bins: %d in theta_o per hemisphere, %d in |phi| over [0, 180] degrees "
               "(180 is forward); nodes at the bins' centres\n",
            nt, np);
    fprintf(f, "# rays: %llu per angle and channel, seed %llu, %llu batches (one surface "
               "realisation each)\n",
            (unsigned long long)o->rays, (unsigned long long)o->seed,
            (unsigned long long)r->tally[0].batches);
    text_provenance(f, prov);
    fprintf(f, "# rows: %llu\n", rows);
    double wt = 90.0 / nt, wp = 180.0 / np;
    for (size_t k = 0; k < r->count; k++) {
        const btdf_sim_tally *t = &r->tally[k];
        for (int part = 0; part < 2; part++) {
            const btdf_sim_est *all = part ? t->hist_R : t->hist_T;
            const btdf_sim_est *one = part ? t->hist_R1 : t->hist_T1;
            for (int it = 0; it < nt; it++) {
                double cs = cos_sr(nt, np, it);
                double inv = cs > 0.0 ? 1.0 / cs : 0.0; /* cs > 0 for every bin; kept safe */
                double tc = (it + 0.5) * wt, to = part ? tc : 180.0 - tc;
                for (int ip = 0; ip < np; ip++) {
                    size_t i = (size_t)it * (size_t)np + (size_t)ip;
                    double pc = (ip + 0.5) * wp;
                    text_num(f, deg_given[k % o->n_theta]); /* the shortest decimals, as tables */
                    fputc(',', f);
                    text_num(f, to);
                    fputc(',', f);
                    text_num(f, pc);
                    fprintf(f, ",%d,%s,", t->channel, part ? "reflection" : "transmission");
                    text_num(f, all[i].mean * inv);
                    fputc(',', f);
                    text_num(f, all[i].se * inv);
                    fputc(',', f);
                    text_num(f, one[i].mean * inv);
                    fputc(',', f);
                    text_num(f, one[i].se * inv);
                    fputc(',', f);
                    text_num(f, t->theta_i);
                    fputc(',', f);
                    text_num(f, to * DEG);
                    fputc(',', f);
                    text_num(f, pc * DEG);
                    fputc(',', f);
                    text_num(f, cs);
                    fputc('\n', f);
                }
            }
        }
    }
    fprintf(f, "# end: %llu rows\n", rows);
    if (fclose(f) != 0) {
        free(buf);
        return fail(1, "%s: out of memory for the table", path);
    }
    char msg[512];
    btdf_status st = btdf_write_buffer(path, ".csv", buf, len, msg, sizeof msg);
    free(buf);
    if (st != BTDF_OK)
        return fail(1, "%s: %s", path, msg);
    return 0;
}

/* The transmitted distribution as an EXR grid table (rows theta_o increasing over
   (90, 180], cols the |phi| bins' centres, one slice per incident angle in increasing
   order, a channel per --ior value) with layers error, one_hit and one_hit_error
   (btdf_write_table_layers): the values of the CSV's rho, rho_se, rho_1, rho_1_se
   rows of part transmission, as 32-bit floats. The reflection is in the CSV only: a
   grid table holds transmission. */
int write_dist_exr(const char *path, const char *prov, const btdf_sim_opts *o,
                          const btdf_sim_result *r)
{
    size_t nti = o->n_theta, order[MAX_ANGLES];
    for (size_t k = 0; k < nti; k++)
        order[k] = k;
    for (size_t i = 1; i < nti; i++) /* insertion sort of the angles, few of them */
        for (size_t j = i; j > 0 && o->theta_i[order[j]] < o->theta_i[order[j - 1]]; j--) {
            size_t t = order[j];
            order[j] = order[j - 1];
            order[j - 1] = t;
        }
    for (size_t i = 1; i < nti; i++)
        if (o->theta_i[order[i]] == o->theta_i[order[i - 1]])
            return fail(2, "-o %s: angle %g deg given twice (a table's slices need distinct "
                           "angles)", path, deg_given[order[i]]);
    int nt = r->theta_bins, np = r->phi_bins, ch = o->channels;
    size_t nodes = (size_t)nt * (size_t)np;
    double *rows = malloc((size_t)nt * sizeof *rows), *cols = malloc((size_t)np * sizeof *cols);
    double *val = malloc(4 * nodes * (size_t)ch * sizeof *val);
    btdf_table *tab[4] = {NULL, NULL, NULL, NULL};
    char msg[512] = "";
    int code = 0;
    if (!rows || !cols || !val) {
        code = fail(1, "%s: out of memory for the table", path);
        goto out;
    }
    for (int it = 0; it < nt; it++) /* row i: theta bin nt - 1 - i, so to increases */
        rows[it] = 3.14159265358979323846 - (nt - 1 - it + 0.5) * (1.5707963267948966 / nt);
    for (int ip = 0; ip < np; ip++)
        cols[ip] = (ip + 0.5) * (3.14159265358979323846 / np);
    btdf_params p;
    btdf_params_default(&p);
    p.channels = ch;
    for (int c = 0; c < ch; c++)
        p.ior[c] = o->ior[c];
    p.smoothness = o->smoothness;
    for (int l = 0; l < 4 && !code; l++)
        if (btdf_table_new(BTDF_TABLE_GRID, &p, &tab[l], msg, sizeof msg) != BTDF_OK)
            code = fail(1, "%s: %s", path, msg);
    for (size_t i = 0; i < nti && !code; i++) {
        size_t k = order[i];
        for (int c = 0; c < ch; c++) {
            const btdf_sim_tally *t = &r->tally[(size_t)c * nti + k];
            for (int it = 0; it < nt; it++) {
                int bin = nt - 1 - it;
                double cs = cos_sr(nt, np, bin);
                double inv = cs > 0.0 ? 1.0 / cs : 0.0; /* cs > 0 for every bin; kept safe */
                for (int ip = 0; ip < np; ip++) {
                    size_t h = (size_t)bin * (size_t)np + (size_t)ip;
                    size_t at = ((size_t)it * (size_t)np + (size_t)ip) * (size_t)ch + (size_t)c;
                    val[at] = t->hist_T[h].mean * inv;
                    val[nodes * (size_t)ch + at] = t->hist_T[h].se * inv;
                    val[2 * nodes * (size_t)ch + at] = t->hist_T1[h].mean * inv;
                    val[3 * nodes * (size_t)ch + at] = t->hist_T1[h].se * inv;
                }
            }
        }
        for (int l = 0; l < 4 && !code; l++)
            if (btdf_table_add_slice(tab[l], o->theta_i[k], (size_t)nt, rows, (size_t)np, cols,
                                     val + (size_t)l * nodes * (size_t)ch, msg,
                                     sizeof msg) != BTDF_OK)
                code = fail(1, "%s: %s", path, msg);
    }
    if (!code) {
        btdf_layer layers[3] = {{"error", tab[1]}, {"one_hit", tab[2]}, {"one_hit_error", tab[3]}};
        btdf_write_opts w = {NULL, prov, NULL};
        btdf_status st = btdf_write_table_layers(
            tab[0], layers, 3,
            o->profile ? "rho of a 1D profile simulated by btdftab simulate (all orders), "
                         "1/rad: the bin's flux over the integral of |cos theta_o| d theta_o; "
                         "layers: error (its standard error), one_hit and one_hit_error"
                       : "rho simulated by btdftab simulate (all orders), the bin's mean "
                         "weighted by |cos theta_o|, no cosine factor; layers: error (its "
                         "standard error), one_hit and one_hit_error (one surface hit)",
            &w, path, msg, sizeof msg);
        if (st != BTDF_OK)
            code = fail(1, "%s: %s", path, msg);
    }
out:
    for (int l = 0; l < 4; l++)
        btdf_table_free(tab[l]);
    free(rows);
    free(cols);
    free(val);
    return code;
}

/* --preview: a panel per case, the transmitted lobe in the plane of incidence. */
int write_preview(const char *path, const btdf_sim_result *r)
{
    simchart_panel pn[BTDF_CHART_MAX_PANELS];
    btdf_chart_panel cp[BTDF_CHART_MAX_PANELS];
    char msg[512] = "";
    size_t n = r->count;
    int code = 0;
    for (size_t k = 0; k < n && !code; k++) {
        if (simchart_lobe(r, k, 0.7, &pn[k], msg, sizeof msg) != 0) {
            code = fail(1, "--preview: %s", msg);
            n = k + 1;
            break;
        }
        cp[k] = (btdf_chart_panel){pn[k].title, pn[k].series, pn[k].nseries};
    }
    if (!code) {
        btdf_chart ch = {"\xce\xb8o from the downward normal (" "\xc2\xb0" "; < 0 backward, > 0 forward)",
                         r->profile ? "\xcf\x81 |cos \xce\xb8o| (1/rad), 1D profile"
                                    : "\xcf\x81 |cos \xce\xb8o| (1/sr), bin mean",
                         0, -90.0, 90.0, cp, n, 0};
        btdf_preview_opts po;
        btdf_preview_opts_default(&po);
        po.kind = BTDF_PREVIEW_CHART;
        po.chart = &ch;
        po.title = "btdftab simulate: the transmitted lobe in the plane of incidence";
        if (btdf_preview_write(&po, path, msg, sizeof msg) != BTDF_OK)
            code = fail(1, "%s: %s", path, msg);
    }
    for (size_t k = 0; k < n; k++)
        simchart_panel_free(&pn[k]);
    return code;
}
