/* SPDX-License-Identifier: MIT */
/* preview.c: the pictures of btdf_preview.h: polar lobes, slice montages and face renders. */
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "btdf_preview.h"
#include "model_impl.h"
#include "table_impl.h"
#include "plot.h"

#define DEG (180.0 / M_PI)

static const plot_rgb white = {255, 255, 255};
static const plot_rgb ink = {25, 25, 30};
static const plot_rgb grey = {120, 120, 125};
static const plot_rgb light = {222, 222, 226};
static const plot_rgb below_range = {30, 30, 30};

/* Curve colours, picked to stay apart from each other on white. */
static const plot_rgb palette[BTDF_PREVIEW_MAX_CURVES] = {
    {20, 90, 200}, {230, 110, 10}, {30, 150, 60}, {200, 30, 40},
    {130, 80, 190}, {120, 80, 40}, {220, 80, 170}, {90, 90, 90},
};

#define say btdf_say /* model_impl.h */

static const char *channel_name(int channels)
{
    return channels == 3 ? "R" : "Y";
}

/* "n = 1.4" or "n = 1.4/1.41/1.42" for three channels. */
static void format_n(char *buf, size_t len, const btdf_params *p)
{
    if (p->channels == 3)
        snprintf(buf, len, "n = %.4g/%.4g/%.4g (R/G/B)", p->ior[0], p->ior[1], p->ior[2]);
    else
        snprintf(buf, len, "n = %.4g", p->ior[0]);
}

/* ------------------------------------------------------------------------- */
/* POLAR                                                                     */
/* ------------------------------------------------------------------------- */

#define POLAR_STEPS 6000 /* per side: 0.015 degree steps, finer than an s = 100 lobe */

typedef struct curve {
    const btdf_params *p;
    double ti; /* radians */
    double peak, peak_to;
} curve;

/* rho |cos to| of channel 0 in the plane of incidence; side +1 forward (phi = pi). */
static double polar_value(const curve *cv, double to, int side)
{
    double v = btdf_rho(cv->p->ior[0], cv->p->smoothness, cv->p->k0, cv->ti, to,
                        side > 0 ? M_PI : 0.0);
    return v * fabs(cos(to));
}

static btdf_status draw_polar(const btdf_preview_opts *o, plot_canvas *cv_out, char *msg,
                              size_t msglen)
{
    size_t ncurves = o->nmaterials * o->nti;
    if (!o->materials || !o->ti_deg || o->nmaterials == 0 || o->nti == 0)
        return say(BTDF_EINVAL, msg, msglen, "a polar plot needs materials and ti values");
    if (o->nmaterials > BTDF_PREVIEW_MAX_CURVES || ncurves > BTDF_PREVIEW_MAX_CURVES)
        return say(BTDF_EINVAL, msg, msglen,
                   "%zu materials x %zu angles = %zu curves; at most %d fit a polar plot",
                   o->nmaterials, o->nti, ncurves, BTDF_PREVIEW_MAX_CURVES);
    curve cs[BTDF_PREVIEW_MAX_CURVES];
    for (size_t m = 0; m < o->nmaterials; m++) {
        btdf_status st = btdf_params_check(&o->materials[m], msg, msglen);
        if (st != BTDF_OK)
            return st;
    }
    for (size_t k = 0; k < o->nti; k++)
        if (!(o->ti_deg[k] >= 0.0 && o->ti_deg[k] < 90.0))
            return say(BTDF_EINVAL, msg, msglen, "ti = %g degrees outside [0, 90)",
                       o->ti_deg[k]);
    double vmax = 0.0;
    for (size_t m = 0, i = 0; m < o->nmaterials; m++)
        for (size_t k = 0; k < o->nti; k++, i++) {
            curve *c = &cs[i];
            c->p = &o->materials[m];
            c->ti = o->ti_deg[k] / DEG;
            c->peak = 0.0;
            c->peak_to = M_PI;
            for (int side = -1; side <= 1; side += 2)
                for (int j = 0; j <= POLAR_STEPS; j++) {
                    double to = M_PI / 2 + (M_PI / 2) * j / POLAR_STEPS;
                    double v = polar_value(c, to, side);
                    if (v > c->peak) {
                        c->peak = v;
                        c->peak_to = side > 0 ? to : -to;
                    }
                }
            vmax = c->peak > vmax ? c->peak : vmax;
        }

    /* Peaks more than 3 times apart would flatten the small lobes: then every curve is
       scaled to its own peak, and the legend gives the peaks. */
    double pmin = vmax;
    for (size_t i = 0; i < ncurves; i++)
        pmin = cs[i].peak < pmin ? cs[i].peak : pmin;
    int own = vmax > 0.0 && !(pmin * 3.0 >= vmax);
    int same_ti = 1;
    for (size_t i = 1; i < ncurves; i++)
        same_ti &= cs[i].ti == cs[0].ti;

    int W = o->width ? o->width : 960, H = o->height ? o->height : 720;
    if (plot_canvas_init(cv_out, W, H, white) != 0)
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for a %d x %d picture", W, H);
    plot_canvas *c = cv_out;
    int ts = W >= 700 ? 2 : 1; /* text scale */
    int top = 12 + 2 * 11 * ts, bottom = 3 * 11 * ts + 10;
    double R = fmin((W - 40) / 2.0, (H - top - bottom - 8 * ts) / 1.42);
    if (R < 40)
        R = 40;
    double cx = W / 2.0, cy = top + 0.42 * R;

    plot_text(c, 10, 8, 0, 0,
              o->title ? o->title
                       : PLOT_RHO " |cos " PLOT_THETA "o| in the plane of incidence (Xu & Sun "
                                  "2008, Eq. 25)",
              ts, ink);
    /* Upper and lower medium, surface, grid. */
    plot_rect(c, 0, (int)cy, W, (int)(cy + R + 2), (plot_rgb){246, 248, 252});
    for (int f = 1; f <= 4; f++) {
        double r = R * f / 4.0;
        double prevx = cx - r, prevy = cy;
        for (int a = 1; a <= 180; a++) {
            double x = cx - r * cos(a / DEG), y = cy + r * sin(a / DEG);
            plot_line(c, prevx, prevy, x, y, 1.0, light);
            prevx = x;
            prevy = y;
        }
    }
    for (int a = 0; a <= 180; a += 15) { /* spokes every 15 degrees of to */
        double x = cx + R * cos(a / DEG), y = cy + R * sin(a / DEG);
        plot_line(c, cx, cy, x, y, 1.0, light);
        if (a % 30 == 0 && a != 0 && a != 90 && a != 180) {
            char lab[16];
            snprintf(lab, sizeof lab, "%d" PLOT_DEG, a < 90 ? 90 + a : 270 - a);
            plot_text(c, (int)(cx + (R + 6) * cos(a / DEG)), (int)(cy + (R + 6) * sin(a / DEG)),
                      a < 90 ? 0.0 : 1.0, 0.0, lab, ts > 1 ? ts - 1 : 1, grey);
        }
    }
    plot_text(c, (int)cx, (int)(cy + R + 6), 0.5, 0.0, PLOT_THETA "o = 180" PLOT_DEG,
              ts > 1 ? ts - 1 : 1, grey);
    plot_line(c, 0, cy, W, cy, 2.0, ink);
    plot_text(c, 10, (int)cy - 6, 0, 1, "upper medium (light comes from here)",
              ts > 1 ? ts - 1 : 1, grey);
    plot_text(c, 10, (int)cy + 8, 0, 0, "lower medium", ts > 1 ? ts - 1 : 1, grey);
    plot_text(c, W - 10, (int)(cy + R - 4), 1, 1, "forward (" PLOT_PHI " = 180" PLOT_DEG ")",
              ts > 1 ? ts - 1 : 1, grey);
    plot_text(c, 10, (int)(cy + R - 4), 0, 1, "backward (" PLOT_PHI " = 0" PLOT_DEG ")",
              ts > 1 ? ts - 1 : 1, grey);
    /* Radial scale along the surface, right of the centre. */
    for (int f = 1; f <= 4 && vmax > 0.0; f++) {
        char lab[32];
        snprintf(lab, sizeof lab, "%.3g", (own ? 1.0 : vmax) * f / 4.0);
        plot_line(c, cx + R * f / 4.0, cy - 4, cx + R * f / 4.0, cy + 4, 1.5, ink);
        plot_text(c, (int)(cx + R * f / 4.0), (int)cy + 8, f == 4 ? 1.0 : 0.5, 0.0, lab,
                  ts > 1 ? ts - 1 : 1, ink);
    }

    /* Incident directions (upper half), refracted directions (dashed), lobes. */
    for (size_t i = 0; i < ncurves; i++) {
        const curve *cu = &cs[i];
        plot_rgb col = same_ti ? ink : palette[i];
        /* A curve with peak 0 has nothing to draw (and must not be divided by). */
        double scale = own ? (cu->peak > 0.0 ? R / cu->peak : 0.0)
                           : (vmax > 0.0 ? R / vmax : 0.0);
        double L = 0.40 * R;
        double ex = cx - L * sin(cu->ti), ey = cy - L * cos(cu->ti);
        plot_line(c, ex, ey, cx, cy, 2.0, col);
        /* Arrow head pointing at the surface: light travels towards it. */
        double ux = (cx - ex) / L, uy = (cy - ey) / L; /* L = 0.4 R >= 16 pixels */
        double hx = cx - 14 * ux, hy = cy - 14 * uy;
        plot_line(c, cx, cy, hx - 6 * uy, hy + 6 * ux, 2.0, col);
        plot_line(c, cx, cy, hx + 6 * uy, hy - 6 * ux, 2.0, col);
        double sn = sin(cu->ti) / cu->p->ior[0]; /* n > 0: btdf_params_check passed */
        if (sn <= 1.0) { /* Snell direction of the mean surface; none past the critical angle */
            double tt = asin(sn);
            plot_dashed(c, cx, cy, cx + R * sin(tt), cy + R * cos(tt), 1.5, 6.0, palette[i]);
        }
        col = palette[i];
        if (!(scale > 0.0))
            continue;
        double px = cx, py = cy;
        for (int side = -1; side <= 1; side += 2)
            for (int j = 0; j <= POLAR_STEPS; j++) {
                int jj = side < 0 ? j : POLAR_STEPS - j; /* back side out, forward side in */
                double to = M_PI / 2 + (M_PI / 2) * jj / POLAR_STEPS;
                double r = polar_value(cu, to, side) * scale;
                double x = cx + side * r * sin(to), y = cy - r * cos(to);
                if (fabs(x - px) + fabs(y - py) >= 0.7 || j == POLAR_STEPS) {
                    plot_line(c, px, py, x, y, 2.5, col);
                    px = x;
                    py = y;
                }
            }
    }
    /* Legend in the upper half, right. */
    int ls = ts > 1 ? ts - 1 : 1, lh = 11 * ls;
    int lx = (int)(cx + 0.10 * R), ly = top + 2;
    for (size_t i = 0; i < ncurves; i++) {
        const curve *cu = &cs[i];
        char nbuf[64], lab[200];
        format_n(nbuf, sizeof nbuf, cu->p);
        snprintf(lab, sizeof lab, "%s  s = %.4g  " PLOT_THETA "i = %.4g" PLOT_DEG, nbuf,
                 cu->p->smoothness, cu->ti * DEG);
        int y = ly + (int)i * (2 * lh + 4);
        plot_line(c, lx, y + 3.5 * ls, lx + 28, y + 3.5 * ls, 3.0, palette[i]);
        plot_text(c, lx + 36, y, 0, 0, lab, ls, ink);
        snprintf(lab, sizeof lab, "peak %.3g at " PLOT_THETA "o = %.1f" PLOT_DEG " %s",
                 cu->peak, fabs(cu->peak_to) * DEG, cu->peak_to < 0 ? "(backward)" : "");
        plot_text(c, lx + 36, y + lh, 0, 0, lab, ls, grey);
    }
    /* Footer: units and conventions. */
    char foot[300];
    snprintf(foot, sizeof foot,
             "radius: " PLOT_RHO " |cos " PLOT_THETA "o| (1/sr), linear, %s %.4g;  "
             "dashed: refraction by the mean surface;  k0 = %.3g",
             own ? "each curve / its peak; largest peak" : "max", vmax, o->materials[0].k0);
    plot_text(c, 10, H - 10 - 2 * 11 * (ts > 1 ? ts - 1 : 1) - 4, 0, 1, foot,
              ts > 1 ? ts - 1 : 1, ink);
    plot_text(c, 10, H - 10, 0, 1,
              PLOT_RHO ": the BTDF without cosine factor; " PLOT_THETA "o measured from the "
                       "upper normal; btdftab " BTDF_VERSION_STRING,
              ts > 1 ? ts - 1 : 1, grey);
    if (!(vmax > 0.0))
        plot_text(c, (int)cx, (int)(cy + R / 2), 0.5, 0.5, "no transmission", ts, ink);
    return BTDF_OK;
}

/* ------------------------------------------------------------------------- */
/* MONTAGE                                                                   */
/* ------------------------------------------------------------------------- */

#define DECADES 6.0

static btdf_status draw_montage(const btdf_preview_opts *o, plot_canvas *c, char *msg,
                                size_t msglen)
{
    const btdf_table *t = o->table;
    if (!t)
        return say(BTDF_EINVAL, msg, msglen, "a montage needs a table");
    size_t n = btdf_table_slice_count(t);
    if (n == 0)
        return say(BTDF_EINVAL, msg, msglen, "the table has no slices");
    const btdf_params *p = btdf_table_get_params(t);
    btdf_table_kind kind = btdf_table_get_kind(t);
    size_t shown = n < BTDF_PREVIEW_MAX_TILES ? n : BTDF_PREVIEW_MAX_TILES;
    size_t idx[BTDF_PREVIEW_MAX_TILES];
    for (size_t k = 0; k < shown; k++) /* evenly spaced, first and last included */
        idx[k] = shown > 1 ? (k * (n - 1) + (shown - 1) / 2) / (shown - 1) : 0;
    double vmax = 0.0;
    for (size_t k = 0; k < n; k++) {
        btdf_slice s;
        btdf_table_slice(t, k, &s);
        for (size_t i = 0; i < s.nrows * s.ncols; i++) {
            double v = s.values[i * (size_t)p->channels];
            vmax = v > vmax ? v : vmax;
        }
    }
    int W = o->width ? o->width : 1000;
    int ts = W >= 700 ? 2 : 1, small = 1;
    int cols = (int)ceil(sqrt((double)shown));
    int rows = (int)((shown + (size_t)cols - 1) / (size_t)cols);
    int left = 40 + 6 * 9 * small, right = 150, top = 2 * 11 * ts + 20, gap = 10;
    int labh = 11 * small + 4;
    int tile = (W - left - right - (cols - 1) * gap) / cols;
    int H = o->height;
    if (H) { /* fit the height too */
        int th = (H - top - 50 - rows * (labh + gap)) / rows;
        tile = th < tile ? th : tile;
    } else {
        H = top + rows * (tile + labh + gap) + 50;
    }
    if (tile < 16)
        return say(BTDF_EINVAL, msg, msglen, "%d x %d pixels are too small for %zu tiles", W,
                   H, shown);
    if (plot_canvas_init(c, W, H, white) != 0)
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for a %d x %d picture", W, H);
    char title[300], nbuf[64];
    format_n(nbuf, sizeof nbuf, p);
    int recip = kind == BTDF_TABLE_FACET_RECIPROCAL, facet = kind != BTDF_TABLE_GRID;
    snprintf(title, sizeof title, "%s table: %s  s = %.4g  k0 = %.3g;  %zu slices, %zu nodes",
             recip ? "facet-reciprocal" : (facet ? "facet" : "grid"), nbuf, p->smoothness,
             p->k0, n, btdf_table_node_count(t));
    const char *head = o->title ? o->title : title;
    /* A narrow picture takes the title at the small scale rather than cutting it. */
    plot_text(c, 10, 8, 0, 0, head, plot_text_width(head, ts) > W - 20 ? small : ts, ink);
    char sub[200];
    snprintf(sub, sizeof sub,
             "log10 " PLOT_RHO " (1/sr), channel %s; tiles in coordinates, row 0 on top%s",
             channel_name(p->channels), shown < n ? "; evenly spaced slices" : "");
    if (o->title)
        plot_text(c, 10, 8 + 11 * ts, 0, 0, title, small, grey);
    plot_text(c, 10, 8 + 11 * ts + 11, 0, 0, sub, small, grey);
    if (recip) {
        /* The slices are the facet table of 1/n at ti' = pi - to (btdf.h): say so, and
           label each tile with the outgoing angle of the light leaving. */
        char rn[200];
        snprintf(rn, sizeof rn,
                 "reciprocal: each tile is the facet table of index 1/n (1/%.4g = %.4g) at "
                 PLOT_THETA "i' = 180" PLOT_DEG " - " PLOT_THETA "o; " PLOT_RHO
                 " = n^2 " PLOT_RHO "(1/n)",
                 p->ior[0], 1.0 / p->ior[0]);
        plot_text(c, 10, 8 + 11 * ts + 22, 0, 0, rn, small, grey);
    }
    double lo = vmax * pow(10.0, -DECADES);
    for (size_t k = 0; k < shown; k++) {
        btdf_slice s;
        btdf_table_slice(t, idx[k], &s);
        int gx = (int)(k % (size_t)cols), gy = (int)(k / (size_t)cols);
        int x0 = left + gx * (tile + gap), y0 = top + gy * (tile + labh + gap) + labh;
        char lab[64];
        double la = recip ? 180.0 - s.ti * DEG : s.ti * DEG;
        snprintf(lab, sizeof lab, "%s = %.2f" PLOT_DEG, recip ? PLOT_THETA "o" : PLOT_THETA "i",
                 la);
        if (plot_text_width(lab, small) > tile + gap - 2) /* narrow tiles: the angle only */
            snprintf(lab, sizeof lab, "%.4g" PLOT_DEG, la);
        plot_text(c, x0, y0 - 3, 0, 1, lab, small, ink);
        double r0 = s.rows[0], r1 = s.rows[s.nrows - 1];
        double c0 = s.cols[0], c1 = s.cols[s.ncols - 1];
        for (int y = 0; y < tile; y++)
            for (int x = 0; x < tile; x++) {
                double rq = r0 + (r1 - r0) * (y + 0.5) / tile;
                double cq = c0 + (c1 - c0) * (x + 0.5) / tile;
                double v = slice_interp(t, idx[k], rq, cq, 0); /* the table's own rule */
                /* lo = 0 when the table is all zeros: everything is below range. */
                plot_rgb col = v > lo && lo > 0.0
                                   ? plot_cmap((log10(v) - log10(lo)) / DECADES)
                                   : below_range;
                plot_rect(c, x0 + x, y0 + y, x0 + x + 1, y0 + y + 1, col);
            }
        plot_frame(c, x0, y0, x0 + tile, y0 + tile, grey);
        if (gx == 0) {
            snprintf(lab, sizeof lab, "%.4g", r0 * DEG);
            plot_text(c, x0 - 4, y0, 1, 0, lab, small, ink);
            snprintf(lab, sizeof lab, "%.4g", r1 * DEG);
            plot_text(c, x0 - 4, y0 + tile, 1, 1, lab, small, ink);
        }
        if (gy == rows - 1 || k + (size_t)cols >= shown) {
            snprintf(lab, sizeof lab, "%.4g", c0 * DEG);
            plot_text(c, x0, y0 + tile + 4, 0, 0, lab, small, ink);
            snprintf(lab, sizeof lab, "%.4g", c1 * DEG);
            plot_text(c, x0 + tile, y0 + tile + 4, 1, 0, lab, small, ink);
        }
    }
    int gh = rows * (tile + labh + gap) - gap;
    plot_text_up(c, 14, top + gh / 2,
                 facet ? "rows: " PLOT_THETA "n, facet tilt (deg)"
                                          : "rows: " PLOT_THETA "o (deg)",
                 small, ink);
    plot_text(c, left + (cols * (tile + gap) - gap) / 2, H - 12, 0.5, 1,
              facet ? "cols: " PLOT_PSI ", facet azimuth (deg)"
                                       : "cols: " PLOT_PHI " (deg)",
              small, ink);
    /* Colour bar, decades labelled. */
    int bx = W - right + 30, bw = 22, by = top + labh, bh = gh - labh < 360 ? gh - labh : 360;
    if (bh < 60)
        bh = 60;
    for (int y = 0; y < bh; y++)
        plot_rect(c, bx, by + y, bx + bw, by + y + 1, plot_cmap(1.0 - (y + 0.5) / bh));
    plot_frame(c, bx, by, bx + bw, by + bh, grey);
    plot_text(c, bx, by - 3, 0, 1, PLOT_RHO " (1/sr)", small, ink);
    if (vmax > 0.0) {
        double top_dec = floor(log10(vmax));
        for (double d = top_dec; d >= log10(lo) - 1e-9; d -= 1.0) {
            double f = (log10(vmax) - d) / DECADES; /* 0 at the top */
            int y = by + (int)lround(f * bh);
            char lab[32];
            snprintf(lab, sizeof lab, "1e%+d", (int)d);
            plot_rect(c, bx + bw, y, bx + bw + 5, y + 1, ink);
            plot_text(c, bx + bw + 8, y, 0, 0.5, lab, small, ink);
        }
        char lab[48];
        snprintf(lab, sizeof lab, "max %.3g", vmax);
        plot_text(c, bx, by + bh + 8, 0, 0, lab, small, ink);
    }
    plot_rect(c, bx, by + bh + 24, bx + bw, by + bh + 36, below_range);
    plot_text(c, bx + bw + 8, by + bh + 30, 0, 0.5, "< max/1e6", small, ink);
    return BTDF_OK;
}

/* ------------------------------------------------------------------------- */
/* RENDER                                                                    */
/* ------------------------------------------------------------------------- */

#define EYE_HEIGHT 0.8  /* face widths, Xu & Sun Sec. 5 */
#define LIGHT_FAR 100.0 /* face widths below the face: nearly normal incidence */
#define LIGHT_NEAR 0.8  /* Fig. 11 */

/* Radiance of the face point (x, y) per channel, from the table or from Eq. 25.
   World frame: face at z = 0, eye above at (0, 0, EYE_HEIGHT), light below at
   (0, 0, -depth). The model frame's z points into the light's medium: z_m = -z. */
static void face_radiance(const btdf_table *t, int analytic, double x, double y, double depth,
                          double *out)
{
    const btdf_params *p = btdf_table_get_params(t);
    double rl = sqrt(x * x + y * y + depth * depth); /* > 0: depth > 0 */
    double re = sqrt(x * x + y * y + EYE_HEIGHT * EYE_HEIGHT);
    /* e_i (model) = (L - P)/rl with z flipped = (-x, -y, depth)/rl; e_o = (-x, -y, -h)/re. */
    double cti = depth / rl, cto = -EYE_HEIGHT / re; /* re >= EYE_HEIGHT > 0 */
    double ti = acos(fmin(1.0, cti)), to = acos(fmax(-1.0, cto));
    /* Both directions lean the same way, towards the axis, so phi = 0 (backward side);
       on the axis itself ti = 0 and phi does not matter. */
    double phi = 0.0;
    double v[BTDF_MAX_CHANNELS] = {0, 0, 0};
    btdf_status st = analytic ? btdf_eval(p, ti, to, phi, v) : btdf_table_eval(t, ti, to, phi, v);
    for (int ch = 0; ch < p->channels; ch++)
        out[ch] = st == BTDF_OK && isfinite(v[ch]) ? v[ch] * cti / (rl * rl) : 0.0;
}

static btdf_status draw_render(const btdf_preview_opts *o, plot_canvas *c, char *msg,
                               size_t msglen)
{
    const btdf_table *t = o->table;
    if (!t)
        return say(BTDF_EINVAL, msg, msglen, "a render needs a table");
    size_t n = btdf_table_slice_count(t);
    if (n == 0)
        return say(BTDF_EINVAL, msg, msglen, "the table has no slices");
    const btdf_params *p = btdf_table_get_params(t);
    int ncol = o->analytic ? 3 : 1, C = p->channels;
    int ts = 2, small = 1;
    int left = 34, top = 2 * 11 * ts + 36, gap = 14, capt = 30, bottom = 56;
    int P = 300;
    if (o->width)
        P = (o->width - left - 10 - (ncol - 1) * gap) / ncol;
    if (o->height) {
        int ph = (o->height - top - bottom - 2 * capt - gap) / 2;
        P = ph < P ? ph : P;
    }
    if (P < 32)
        return say(BTDF_EINVAL, msg, msglen, "the picture is too small for the panels");
    int W = o->width ? o->width : left + ncol * P + (ncol - 1) * gap + 10;
    int H = o->height ? o->height : top + 2 * (P + capt) + gap + bottom;
    if (W < 560 && !o->width)
        W = 560;
    size_t npix = (size_t)P * (size_t)P;
    double *img = malloc(npix * 2 * BTDF_MAX_CHANNELS * sizeof *img);
    if (!img || plot_canvas_init(c, W, H, white) != 0) {
        free(img);
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for the render");
    }
    double *tab = img, *ana = img + npix * BTDF_MAX_CHANNELS;
    btdf_slice s0, s1;
    btdf_table_slice(t, 0, &s0);
    btdf_table_slice(t, n - 1, &s1);
    char title[300], nbuf[64];
    format_n(nbuf, sizeof nbuf, p);
    snprintf(title, sizeof title, "Rough face lit from inside: %s  s = %.4g", nbuf,
             p->smoothness);
    plot_text(c, 10, 8, 0, 0, o->title ? o->title : title, ts, ink);
    plot_text(c, 10, 8 + 11 * ts + 2, 0, 0,
              "face 1 W wide seen from 0.8 W on its axis; point light on the axis in the "
              "light's medium",
              small, grey);
    const char *heads[3] = {"from the table", "Eq. 25", "|table - Eq. 25| / max"};
    for (int k = 0; k < ncol; k++)
        plot_text(c, left + k * (P + gap) + P / 2, top - 6, 0.5, 1, heads[k], small, ink);
    for (int row = 0; row < 2; row++) {
        double depth = row == 0 ? LIGHT_FAR : LIGHT_NEAR;
        double vmax = 0.0, amax = 0.0;
        for (int j = 0; j < P; j++)
            for (int i = 0; i < P; i++) {
                double x = (i + 0.5) / P - 0.5, y = 0.5 - (j + 0.5) / P;
                size_t at = ((size_t)j * (size_t)P + (size_t)i) * BTDF_MAX_CHANNELS;
                face_radiance(t, 0, x, y, depth, tab + at);
                if (o->analytic)
                    face_radiance(t, 1, x, y, depth, ana + at);
                for (int ch = 0; ch < C; ch++) {
                    vmax = tab[at + (size_t)ch] > vmax ? tab[at + (size_t)ch] : vmax;
                    if (o->analytic)
                        amax = ana[at + (size_t)ch] > amax ? ana[at + (size_t)ch] : amax;
                }
            }
        double scale_max = vmax > amax ? vmax : amax;
        int y0 = top + row * (P + capt + gap);
        double dmax = 0.0;
        for (int k = 0; k < ncol; k++) {
            int x0 = left + k * (P + gap);
            for (int j = 0; j < P; j++)
                for (int i = 0; i < P; i++) {
                    size_t at = ((size_t)j * (size_t)P + (size_t)i) * BTDF_MAX_CHANNELS;
                    double rgb[3];
                    if (k < 2) {
                        const double *v = (k == 0 ? tab : ana) + at;
                        for (int e = 0; e < 3; e++) {
                            double u = v[C == 3 ? e : 0];
                            /* scale_max = 0 when nothing is lit: the panel stays black. */
                            rgb[e] = scale_max > 0.0 ? u / scale_max : 0.0;
                        }
                        plot_rect(c, x0 + i, y0 + j, x0 + i + 1, y0 + j + 1,
                                  (plot_rgb){(unsigned char)lround(255 * fmin(1, rgb[0])),
                                             (unsigned char)lround(255 * fmin(1, rgb[1])),
                                             (unsigned char)lround(255 * fmin(1, rgb[2]))});
                    } else {
                        double d = 0.0;
                        for (int ch = 0; ch < C; ch++)
                            d = fmax(d, fabs(tab[at + (size_t)ch] - ana[at + (size_t)ch]));
                        /* amax = 0: no light at all, so no difference to show. */
                        d = amax > 0.0 ? d / amax : 0.0;
                        dmax = d > dmax ? d : dmax;
                        ana[at] = d; /* reuse: the value is no longer needed */
                    }
                }
            if (k == 2) {
                for (int j = 0; j < P; j++)
                    for (int i = 0; i < P; i++) {
                        double d = ana[((size_t)j * (size_t)P + (size_t)i) * BTDF_MAX_CHANNELS];
                        plot_rect(c, x0 + i, y0 + j, x0 + i + 1, y0 + j + 1,
                                  dmax > 0.0 ? plot_cmap(d / dmax) : plot_cmap(0.0));
                    }
            }
            plot_frame(c, x0, y0, x0 + P, y0 + P, grey);
            char cap[120];
            if (k < 2)
                snprintf(cap, sizeof cap, "255 = %.3g (row max)", scale_max);
            else
                snprintf(cap, sizeof cap, "yellow = %.2g", dmax);
            plot_text(c, x0, y0 + P + 5, 0, 0, cap, small, ink);
        }
        char rl[80];
        snprintf(rl, sizeof rl, "light %s: %.3g W below the face", row == 0 ? "far" : "near",
                 depth);
        plot_text_up(c, left / 2, y0 + P / 2, rl, small, ink);
    }
    char foot[300];
    if (btdf_table_get_kind(t) == BTDF_TABLE_FACET_RECIPROCAL) /* slices at ti' = pi - to */
        snprintf(foot, sizeof foot,
                 "radiance " PLOT_RHO " cos " PLOT_THETA "i I / r^2, linear as in the paper; "
                 "reciprocal table, slices cover " PLOT_THETA "o %.4g-%.4g" PLOT_DEG
                 " (the eye needs 138.5-180" PLOT_DEG ")",
                 180.0 - s1.ti * DEG, 180.0 - s0.ti * DEG);
    else
        snprintf(foot, sizeof foot,
                 "radiance " PLOT_RHO " cos " PLOT_THETA "i I / r^2, linear as in the paper; "
                 "table covers " PLOT_THETA "i %.3g-%.3g" PLOT_DEG
                 " (near light needs 0-41.5" PLOT_DEG ")",
                 s0.ti * DEG, s1.ti * DEG);
    plot_text(c, 10, H - 30, 0, 1, foot, small, ink);
    plot_text(c, 10, H - 12, 0, 1,
              "far: 100 W, nearly normal incidence (Fig. 10); near: 0.8 W (Fig. 11); "
              "btdftab " BTDF_VERSION_STRING,
              small, grey);
    free(img);
    return BTDF_OK;
}

/* ------------------------------------------------------------------------- */
/* Public                                                                    */
/* ------------------------------------------------------------------------- */

BTDF_API void btdf_preview_opts_default(btdf_preview_opts *o)
{
    memset(o, 0, sizeof *o);
    o->kind = BTDF_PREVIEW_POLAR;
}

BTDF_API btdf_status btdf_preview_render(const btdf_preview_opts *o, unsigned char **rgb,
                                         int *width, int *height, char *msg, size_t msglen)
{
    if (!o || !rgb || !width || !height)
        return say(BTDF_EINVAL, msg, msglen, "missing argument");
    if (o->width < 0 || o->height < 0 || o->width > BTDF_PREVIEW_MAX_SIDE ||
        o->height > BTDF_PREVIEW_MAX_SIDE)
        return say(BTDF_EINVAL, msg, msglen, "picture size %d x %d outside 1 to %d", o->width,
                   o->height, BTDF_PREVIEW_MAX_SIDE);
    if ((o->width && o->width < 200) || (o->height && o->height < 150))
        return say(BTDF_EINVAL, msg, msglen, "picture size %d x %d: at least 200 x 150",
                   o->width, o->height);
    plot_canvas c = {0, 0, NULL};
    btdf_status st;
    switch (o->kind) {
    case BTDF_PREVIEW_POLAR: st = draw_polar(o, &c, msg, msglen); break;
    case BTDF_PREVIEW_MONTAGE: st = draw_montage(o, &c, msg, msglen); break;
    case BTDF_PREVIEW_RENDER: st = draw_render(o, &c, msg, msglen); break;
    default: st = say(BTDF_EINVAL, msg, msglen, "unknown picture kind %d", (int)o->kind);
    }
    if (st != BTDF_OK) {
        plot_canvas_free(&c);
        return st;
    }
    *rgb = c.px;
    *width = c.w;
    *height = c.h;
    return BTDF_OK;
}

BTDF_API void btdf_preview_free(unsigned char *rgb)
{
    free(rgb);
}
