/* SPDX-License-Identifier: MIT */
/* pane_table.c: a pane's system BSDF on a regular grid, to CSV (both sides and both parts,
   named in every row) or to EXR (a grid table of the front's transmission with the three
   other blocks and the back's mirror as layers), with the grid's error against the
   system by the metric of MODEL.md section 6 (docs/pane.md, "Tables"). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "btdf.h"
#include "btdf_io.h"
#include "btdf_pane.h"
#include "cli.h"
#include "pane_write.h"
#include "textout.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#define DEG (M_PI / 180.0)

/* Blocks in file order: light front transmission, front reflection, back transmission,
   back reflection. */
static const char *const light_name[2] = {"front", "back"};
static const char *const part_name[2] = {"transmission", "reflection"};

typedef struct pgrid {
    size_t nti, nto, nphi, nch;
    double *v; /* v[(((b * nch + c) * nti + i) * nto + j) * nphi + m] */
    double *spec; /* spec[((b * nch + c) * nti + i)]: the delta's weight (b even: none) */
} pgrid;

static double ti_deg(const pgrid *g, size_t i) { return 90.0 * (double)i / (double)(g->nti - 1); }
/* the outgoing node j: its angle from the lit face's normal, towards the surface */
static double t_deg(const pgrid *g, size_t j) { return 90.0 * (double)j / (double)(g->nto - 1); }
static double phi_deg(const pgrid *g, size_t m) { return 180.0 * (double)m / (double)(g->nphi - 1); }
/* the direction's theta_o as btdf_pane.h takes it: to = 180 - t (transmission), tr = t */
static double out_deg(int part, double t) { return part ? t : 180.0 - t; }

static size_t at(const pgrid *g, int b, size_t c, size_t i, size_t j, size_t m)
{
    return ((((size_t)b * g->nch + c) * g->nti + i) * g->nto + j) * g->nphi + m;
}

static int fill(const btdf_pane *P, pgrid *g)
{
    double *phi = malloc(g->nphi * sizeof *phi);
    if (!phi)
        return 0;
    for (size_t m = 0; m < g->nphi; m++)
        phi[m] = phi_deg(g, m) * DEG;
    for (int b = 0; b < 4; b++) {
        btdf_pane_side sd = b < 2 ? BTDF_PANE_FRONT : BTDF_PANE_BACK;
        btdf_part pt = b & 1 ? BTDF_PART_REFLECTION : BTDF_PART_TRANSMISSION;
        for (size_t c = 0; c < g->nch; c++)
            for (size_t i = 0; i < g->nti; i++) {
                double ti = ti_deg(g, i) * DEG;
                for (size_t j = 0; j < g->nto; j++)
                    btdf_pane_eval_phis(P, sd, pt, (int)c, ti, out_deg(b & 1, t_deg(g, j)) * DEG,
                                        g->nphi, phi, g->v + at(g, b, c, i, j, 0));
                g->spec[((size_t)b * g->nch + c) * g->nti + i] =
                    btdf_pane_specular(P, sd, pt, (int)c, ti);
            }
    }
    free(phi);
    return 1;
}

/* The grid read back: trilinear in (ti, t, phi) degrees, channel 0. */
static double lerp_grid(const pgrid *g, int b, double ti, double t, double ph)
{
    double x[3] = {ti / 90.0 * (double)(g->nti - 1), t / 90.0 * (double)(g->nto - 1),
                   ph / 180.0 * (double)(g->nphi - 1)};
    size_t n[3] = {g->nti, g->nto, g->nphi}, k[3];
    double w[3];
    for (int d = 0; d < 3; d++) {
        double f = floor(x[d]);
        if (f < 0.0)
            f = 0.0;
        if (f > (double)(n[d] - 2))
            f = (double)(n[d] - 2); /* n >= 2 on every axis (checked) */
        k[d] = (size_t)f;
        w[d] = x[d] - f;
    }
    double s = 0.0;
    for (int a = 0; a < 2; a++)
        for (int bb = 0; bb < 2; bb++)
            for (int cc = 0; cc < 2; cc++) {
                double wt = (a ? w[0] : 1.0 - w[0]) * (bb ? w[1] : 1.0 - w[1]) *
                            (cc ? w[2] : 1.0 - w[2]);
                s += wt * g->v[at(g, b, 0, k[0] + a, k[1] + bb, k[2] + cc)];
            }
    return s;
}

typedef struct perr {
    double l1_max, l1_mean, t_max, l1_ti;
    double l1_max80; /* the largest e_L1 up to 80 degrees, below the grazing lobes */
    int l1_block;
} perr;

/* MODEL.md section 6 for the grid against the system, channel 0: at the midpoints
   between the grid's incidence nodes up to 88 degrees (where linear interpolation is
   worst), e_L1 = sum over 96 x 96 cells in cos theta_o and phi of |f_grid - f| cos, and
   e_T the same for the difference of the two sums, both over max(the part's T or R,
   0.01); the deltas are exact in both (the grid holds their weights at its nodes, the
   error counts the spread part). */
static void grid_error(const btdf_pane *P, const pgrid *g, perr *e)
{
    enum { NMU = 96, NPH = 96 };
    double phis[NPH], vals[NPH];
    for (int m = 0; m < NPH; m++)
        phis[m] = (m + 0.5) * (M_PI / NPH);
    memset(e, 0, sizeof *e);
    size_t count = 0;
    for (int b = 0; b < 4; b++) {
        btdf_pane_side sd = b < 2 ? BTDF_PANE_FRONT : BTDF_PANE_BACK;
        btdf_part pt = b & 1 ? BTDF_PART_REFLECTION : BTDF_PART_TRANSMISSION;
        for (size_t i = 0; i + 1 < g->nti; i++) {
            double tid = 0.5 * (ti_deg(g, i) + ti_deg(g, i + 1));
            if (tid > 88.0)
                break;
            double T, R;
            btdf_pane_albedo(P, sd, 0, tid * DEG, &T, &R);
            double A = pt == BTDF_PART_TRANSMISSION ? T : R;
            double fl = A > 0.01 ? A : 0.01;
            double l1 = 0.0, sg = 0.0, sf = 0.0;
            for (int k = 0; k < NMU; k++) {
                double mu = (k + 0.5) / NMU, t = acos(mu) / DEG;
                btdf_pane_eval_phis(P, sd, pt, 0, tid * DEG, out_deg(b & 1, t) * DEG, NPH, phis,
                                    vals);
                for (int m = 0; m < NPH; m++) {
                    double fg = lerp_grid(g, b, tid, t, phis[m] / DEG);
                    l1 += fabs(fg - vals[m]) * mu;
                    sg += fg * mu;
                    sf += vals[m] * mu;
                }
            }
            double cell = (1.0 / NMU) * (M_PI / NPH) * 2.0; /* both halves of phi */
            l1 *= cell / fl;
            double et = fabs(sg - sf) * cell / fl;
            e->l1_mean += l1;
            count++;
            if (tid <= 80.0 && l1 > e->l1_max80)
                e->l1_max80 = l1;
            if (l1 > e->l1_max) {
                e->l1_max = l1;
                e->l1_ti = tid;
                e->l1_block = b;
            }
            if (et > e->t_max)
                e->t_max = et;
        }
    }
    if (count)
        e->l1_mean /= (double)count;
}

static void describe(FILE *f, const btdf_pane_opts *o, const char *prov, const perr *e,
                     const pgrid *g)
{
    fprintf(f, "# btdftab %s pane\n# kind: pane-grid\n# channels: %d\n# ior:",
            btdf_version_string(), o->front.channels);
    for (int c = 0; c < o->front.channels; c++) {
        fputc(c ? ',' : ' ', f);
        text_num(f, o->front.ior[c]);
    }
    fputs("\n# smoothness: ", f);
    text_num(f, o->front.smoothness);
    fprintf(f, "\n# model: %s\n# k0: ", btdf_model_name(o->front.model));
    text_num(f, o->front.k0);
    fputs("\n# back: ", f);
    if (o->back_smooth)
        fputs("smooth", f);
    else
        text_num(f, o->back_smoothness);
    fputs("\n# thickness_mm: ", f);
    text_num(f, o->thickness_mm);
    fputs("\n# absorption_per_mm: ", f);
    text_num(f, o->absorption_per_mm);
    fputs("\n# units: f in 1/sr, no cosine factor, air to air (btdf_pane.h): light on the "
          "face `light` names, angles in degrees in that face's frame, theta_o in [90, 180] "
          "for transmission and [0, 90] for reflection, phi 180 forward; a row of part "
          "reflection-delta holds the weight of the mirror reflection of a flat face (the "
          "share of the incident power, no unit) at theta_o = theta_i, phi 180\n", f);
    fprintf(f, "# grid: %zu theta_i x %zu theta_o x %zu phi nodes, uniform over [0, 90], "
               "[0, 90] from the face (to = 180 - t for transmission), [0, 180] degrees; "
               "trilinear in degrees between them\n",
            g->nti, g->nto, g->nphi);
    text_provenance(f, prov);
    fprintf(f, "# error: e_L1 max %.4g mean %.4g (worst: light %s, %s, theta_i %.4g deg), "
               "max %.4g up to theta_i 80 deg; e_T max %.4g: the grid read trilinearly "
               "against the system, MODEL.md section 6 on channel 0, at the midpoints "
               "between the grid's theta_i up to 88 deg\n",
            e->l1_max, e->l1_mean, light_name[e->l1_block >> 1], part_name[e->l1_block & 1],
            e->l1_ti, e->l1_max80, e->t_max);
}

static int write_csv(const char *path, const btdf_pane_opts *o, const pgrid *g,
                     const perr *e, const char *prov)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    if (!f)
        return fail(1, "%s: out of memory for the table", path);
    size_t ndelta = 0; /* a delta row where any channel has a weight */
    for (int b = 0; b < 4; b++)
        for (size_t i = 0; i < g->nti; i++) {
            int any = 0;
            for (size_t c = 0; c < g->nch; c++)
                any |= g->spec[((size_t)b * g->nch + c) * g->nti + i] > 0.0;
            ndelta += (size_t)any;
        }
    unsigned long long rows = 4ull * g->nti * g->nto * g->nphi + ndelta;
    fputs(g->nch == 3 ? "light,part,theta_i_deg,theta_o_deg,phi_deg,f_r,f_g,f_b,ti_rad,to_rad,"
                        "phi_rad\n"
                      : "light,part,theta_i_deg,theta_o_deg,phi_deg,f,ti_rad,to_rad,phi_rad\n",
          f);
    describe(f, o, prov, e, g);
    fprintf(f, "# rows: %llu\n", rows);
    for (int b = 0; b < 4; b++) {
        for (size_t i = 0; i < g->nti; i++)
            for (size_t j = 0; j < g->nto; j++)
                for (size_t m = 0; m < g->nphi; m++) {
                    double a = ti_deg(g, i), t = out_deg(b & 1, t_deg(g, j)), p = phi_deg(g, m);
                    fprintf(f, "%s,%s,", light_name[b >> 1], part_name[b & 1]);
                    text_num(f, a);
                    fputc(',', f);
                    text_num(f, t);
                    fputc(',', f);
                    text_num(f, p);
                    for (size_t c = 0; c < g->nch; c++) {
                        fputc(',', f);
                        text_num(f, g->v[at(g, b, c, i, j, m)]);
                    }
                    fputc(',', f);
                    text_num(f, a * DEG);
                    fputc(',', f);
                    text_num(f, t * DEG);
                    fputc(',', f);
                    text_num(f, p * DEG);
                    fputc('\n', f);
                }
        for (size_t i = 0; i < g->nti; i++) {
            const double *sp = g->spec + (size_t)b * g->nch * g->nti + i;
            int any = 0;
            for (size_t c = 0; c < g->nch; c++)
                any |= sp[c * g->nti] > 0.0;
            if (!any)
                continue;
            double a = ti_deg(g, i), t = b & 1 ? a : 180.0 - a;
            fprintf(f, "%s,%s-delta,", light_name[b >> 1], part_name[b & 1]);
            text_num(f, a);
            fputc(',', f);
            text_num(f, t);
            fputs(",180", f);
            for (size_t c = 0; c < g->nch; c++) {
                fputc(',', f);
                text_num(f, sp[c * g->nti]);
            }
            fputc(',', f);
            text_num(f, a * DEG);
            fputc(',', f);
            text_num(f, t * DEG);
            fputc(',', f);
            text_num(f, M_PI);
            fputc('\n', f);
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
    return st == BTDF_OK ? 0 : fail(1, "%s: %s", path, msg);
}

/* EXR: grid tables (rows: to increasing over [90, 180], cols phi, one slice per theta_i),
   the front's transmission the main values, the other blocks layers in the same nodes
   (a reflection at row to holds tr = 180 - to, the mirror image through the surface),
   back_delta the back's mirror weight at every node of its slice. */
static int write_exr(const char *path, const btdf_pane_opts *o, const pgrid *g,
                     const perr *e, const char *prov)
{
    size_t nodes = g->nto * g->nphi, nch = g->nch;
    double *rows = malloc(g->nto * sizeof *rows), *cols = malloc(g->nphi * sizeof *cols);
    double *val = malloc(nodes * nch * sizeof *val);
    btdf_table *tab[5] = {NULL, NULL, NULL, NULL, NULL};
    char msg[512] = "";
    int code = 0, has_delta = 0;
    for (size_t i = 0; i < g->nti * nch; i++)
        has_delta |= g->spec[3 * nch * g->nti + i] > 0.0;
    int ntab = has_delta ? 5 : 4;
    if (!rows || !cols || !val)
        code = fail(1, "%s: out of memory for the table", path);
    for (size_t j = 0; !code && j < g->nto; j++) /* row j: to = 90 + t_j, increasing */
        rows[j] = (90.0 + t_deg(g, j)) * DEG;
    for (size_t m = 0; !code && m < g->nphi; m++)
        cols[m] = phi_deg(g, m) * DEG;
    for (int l = 0; l < ntab && !code; l++)
        if (btdf_table_new(BTDF_TABLE_GRID, &o->front, &tab[l], msg, sizeof msg) != BTDF_OK)
            code = fail(1, "%s: %s", path, msg);
    for (size_t i = 0; i < g->nti && !code; i++)
        for (int l = 0; l < ntab && !code; l++) {
            for (size_t c = 0; c < nch; c++)
                for (size_t j = 0; j < g->nto; j++)
                    for (size_t m = 0; m < g->nphi; m++) {
                        /* transmission: to = 90 + t_j is node nto - 1 - j of the grid's t
                           (t from the face); reflection: tr = 180 - to, node the same */
                        size_t jj = g->nto - 1 - j;
                        double x = l == 4 ? g->spec[(3 * nch + c) * g->nti + i]
                                          : g->v[at(g, l, c, i, jj, m)];
                        val[(j * g->nphi + m) * nch + c] = x;
                    }
            if (btdf_table_add_slice(tab[l], ti_deg(g, i) * DEG, g->nto, rows, g->nphi, cols,
                                     val, msg, sizeof msg) != BTDF_OK)
                code = fail(1, "%s: %s", path, msg);
        }
    if (!code) {
        btdf_layer layers[4] = {{"front_reflection", tab[1]},
                                {"back_transmission", tab[2]},
                                {"back_reflection", tab[3]},
                                {"back_delta", tab[4]}};
        char value[900];
        snprintf(value, sizeof value,
                 "f of a pane in air (btdf_pane.h), 1/sr, no cosine factor: the values are "
                 "light on the front face, transmission (to = row); layers front_reflection, "
                 "back_transmission, back_reflection (a reflection's tr = 180 deg - row)%s; "
                 "front n = %.9g, s = %.9g, model %s, back %s, %.9g mm, %.9g per mm; grid "
                 "error e_L1 max %.4g (%.4g up to 80 deg), e_T max %.4g",
                 has_delta ? ", back_delta (the flat back's mirror weight, no unit)" : "",
                 o->front.ior[0], o->front.smoothness, btdf_model_name(o->front.model),
                 o->back_smooth ? "smooth" : "rough", o->thickness_mm, o->absorption_per_mm,
                 e->l1_max, e->l1_max80, e->t_max);
        btdf_write_opts w = {NULL, prov, NULL};
        btdf_status st = btdf_write_table_layers(tab[0], layers, (size_t)ntab - 1, value, &w,
                                                 path, msg, sizeof msg);
        if (st != BTDF_OK)
            code = fail(1, "%s: %s", path, msg);
    }
    for (int l = 0; l < 5; l++)
        btdf_table_free(tab[l]);
    free(rows);
    free(cols);
    free(val);
    return code;
}

int pane_write_table(const char *path, const btdf_pane *P, size_t nti, size_t nto,
                     size_t nphi, int quiet, const char *prov)
{
    const btdf_pane_opts *o = btdf_pane_get_opts(P);
    if (nti < 2 || nto < 2 || nphi < 2)
        return fail(EXIT_USAGE, "%s: --grid %zu,%zu,%zu: a pane's grid needs 2 nodes or more "
                                "on every axis",
                    path, nti, nto, nphi);
    int exr = ends_with(path, ".exr");
    pgrid g = {nti, nto, nphi, (size_t)o->front.channels, NULL, NULL};
    size_t nv = 4 * g.nch * nti * nto * nphi;
    if (nv > ((size_t)1 << 28))
        return fail(EXIT_USAGE, "%s: --grid %zu,%zu,%zu: %zu values, more than 2^28", path,
                    nti, nto, nphi, nv);
    g.v = malloc(nv * sizeof *g.v);
    g.spec = calloc(4 * g.nch * nti, sizeof *g.spec);
    int code = 0;
    if (!g.v || !g.spec || !fill(P, &g))
        code = fail(1, "%s: out of memory for the grid", path);
    perr e;
    if (!code) {
        grid_error(P, &g, &e);
        code = exr ? write_exr(path, o, &g, &e, prov) : write_csv(path, o, &g, &e, prov);
    }
    if (!code && !quiet)
        fprintf(stderr,
                "btdftab: %s: a pane's system on %zu x %zu x %zu nodes a block; grid error "
                "e_L1 max %.4g mean %.4g (light %s, %s, theta_i %.4g deg), %.4g up to 80 "
                "deg; e_T max %.4g\n",
                path, nti, nto, nphi, e.l1_max, e.l1_mean, light_name[e.l1_block >> 1],
                part_name[e.l1_block & 1], e.l1_ti, e.l1_max80, e.t_max);
    free(g.v);
    free(g.spec);
    return code;
}
