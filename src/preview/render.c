/* SPDX-License-Identifier: MIT */
/* render.c: the face of a rough slab lit by a beam, as in Figs. 10 and 11 of Xu & Sun
   (2008), from the table or from the model itself. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model/kernel.h"
#include "preview/style.h"
#include "table/table.h"

#define EYE_HEIGHT 0.8  /* face widths, Xu & Sun Sec. 5 */
#define LIGHT_FAR 100.0 /* face widths below the face: nearly normal incidence */
#define LIGHT_NEAR 0.8  /* Fig. 11 */
#define RENDER_MIN_PANEL 100

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

/* The zoom of a render asked for with zoom < 0 (auto): the spot's extent x_e on the
   face, the largest |x| on the y = 0 line where either row (far, near light) still
   reaches a visible fraction of its maximum (one grey step, 1/255, linear; 10^-D on a
   log scale), is made 90% of the shown half width: Z = 0.45 / x_e, rounded down to 1,
   2 or 5 times a power of ten, and 1 (the paper's whole face) below 2. The spot of an
   on-axis eye and light is round about the axis, so one line gives its extent. */
#define ZOOM_STEPS 2000 /* per half width: 2.5e-4 face widths, under a pixel at zoom 1000 x 300 px */
static double auto_zoom(const btdf_table *t, double decades)
{
    double frac = decades > 0.0 ? pow(10.0, -decades) : 1.0 / 255.0, xe = 0.0;
    for (int row = 0; row < 2; row++) {
        double depth = row == 0 ? LIGHT_FAR : LIGHT_NEAR, vmax = 0.0;
        for (int pass = 0; pass < 2; pass++) /* the row's maximum, then from the edge in */
            for (int j = 0; j <= ZOOM_STEPS; j++) {
                int k = pass == 0 ? j : ZOOM_STEPS - j;
                double v[BTDF_MAX_CHANNELS], u = 0.0;
                face_radiance(t, 0, 0.5 * k / ZOOM_STEPS, 0.0, depth, v);
                for (int ch = 0; ch < btdf_table_get_params(t)->channels; ch++)
                    u = fmax(u, v[ch]);
                if (pass == 0) {
                    vmax = fmax(vmax, u);
                } else if (vmax > 0.0 && u >= frac * vmax) { /* vmax 0: nothing lit */
                    xe = fmax(xe, 0.5 * k / ZOOM_STEPS);
                    break;
                }
            }
    }
    /* xe = 0: the spot is under one step; the finest step's zoom stands for it */
    double z = 0.45 / fmax(xe, 0.5 / ZOOM_STEPS), nice = 1.0;
    for (double d = 1.0; d <= 1000.0; d *= 10.0)
        for (int k = 0; k < 3; k++) {
            double c = d * (k == 0 ? 1.0 : k == 1 ? 2.0 : 5.0);
            if (c <= z && c <= 1000.0)
                nice = c;
        }
    return nice < 2.0 ? 1.0 : nice;
}

/* Grey level in [0, 1] of radiance u of a row whose maximum is umax: linear, or log10
   over `decades` below umax. */
static double tone(double u, double umax, double decades)
{
    if (!(umax > 0.0) || !(u > 0.0))
        return 0.0; /* nothing lit, or this pixel dark: black (and no log of 0) */
    if (decades <= 0.0)
        return fmin(1.0, u / umax);
    return pv_clampd((log10(u / umax) + decades) / decades, 0.0, 1.0);
}

/* The title: which side the light and the eye are on follows from n = n_eye / n_light. */
static void render_title(char *buf, size_t len, const btdf_params *p)
{
    int below = 0, above = 0;
    for (int ch = 0; ch < p->channels; ch++) {
        below += p->ior[ch] < 1.0;
        above += p->ior[ch] > 1.0;
    }
    char nbuf[64];
    pv_format_n(nbuf, sizeof nbuf, p);
    const char *what = below == p->channels   ? "Rough face of a dense block lit from inside"
                       : above == p->channels ? "Rough face of a dense block lit from outside"
                                              : "Rough face between two media";
    snprintf(buf, len, "%s: %s  s = %.4g", what, nbuf, p->smoothness);
}

/* One render, filled in by the phases below: the checks and texts, the layout measured
   on a scratch canvas, then one row per light distance. */
typedef struct render_plot {
    const btdf_preview_opts *o;
    const btdf_table *t;
    const btdf_params *p;
    double D, Z;              /* log decades (0: linear) and zoom */
    int nimg, npanels, C;     /* face images, panels with the difference, channels */
    char title[300], sub[400], foot[700];
    const char *head;
    double fs, fsS, fsT, m, lineS;
    double barw, blw, barblock, gap, left;
    double th, foot_h, top, rowgap;
    int P, Wi, Hi;            /* panel side and picture size in pixels */
    double xs[3], gbar;       /* the panels' and the grey bar's x */
} render_plot;

/* The checks of the options and the title, subtitle and footer texts. */
static int render_texts(render_plot *rp, char *msg, size_t msglen)
{
    const btdf_preview_opts *o = rp->o;
    const btdf_table *t = o->table;
    if (!t)
        return say(BTDF_EINVAL, msg, msglen, "a render needs a table");
    size_t n = btdf_table_slice_count(t);
    if (n == 0)
        return say(BTDF_EINVAL, msg, msglen, "the table has no slices");
    double D = o->log_decades;
    if (!(D == 0.0 || (D >= 1.0 && D <= 12.0)))
        return say(BTDF_EINVAL, msg, msglen,
                   "log_decades = %g: 0 for a linear scale, or 1 to 12 decades", D);
    double Z = o->zoom == 0.0 ? 1.0 : o->zoom < 0.0 ? auto_zoom(t, D) : o->zoom;
    if (!(Z >= 1.0 && Z <= 1000.0))
        return say(BTDF_EINVAL, msg, msglen,
                   "zoom = %g: 1 (or 0) for the whole face, up to 1000 for its central "
                   "1/1000, or < 0 for a zoom chosen from the lobe", o->zoom);
    const btdf_params *p = btdf_table_get_params(t);
    rp->t = t;
    rp->p = p;
    rp->D = D;
    rp->Z = Z;
    rp->nimg = o->analytic ? 2 : 1;
    rp->npanels = rp->nimg + (o->analytic ? 1 : 0);
    rp->C = p->channels;
    btdf_slice s0, s1;
    btdf_table_slice(t, 0, &s0);
    btdf_table_slice(t, n - 1, &s1);

    char *foot = rp->foot;
    size_t footlen = sizeof rp->foot;
    render_title(rp->title, sizeof rp->title, p);
    int lit_inside = p->ior[0] < 1.0;
    /* lengths in face widths ("W" read as watts) */
    char shown[120] = "a square face; lengths in face widths";
    if (Z > 1.0)
        snprintf(shown, sizeof shown, "the central %.3g of a square face (zoom %g%s); lengths "
                 "in face widths", 1.0 / Z, Z, o->zoom < 0.0 ? ", from the lobe's width" : "");
    snprintf(rp->sub, sizeof rp->sub,
             "%s; point light on its axis in the light's medium (%s the block); eye "
             "0.8 widths from the face on its axis, %s",
             shown, lit_inside ? "inside" : "outside", lit_inside ? "outside" : "inside");
    char scale[160];
    if (D > 0.0)
        snprintf(scale, sizeof scale, "log10 scale over %g decades below each row's maximum", D);
    else
        snprintf(scale, sizeof scale, "linear, each row scaled to its maximum as in the paper");
    int k = snprintf(foot, footlen,
                     "radiance " PLOT_RHO " cos " PLOT_THETA "i I / r" "\xc2\xb2" ", %s%s; ",
                     scale, rp->C == 3 ? " (R, G, B)" : "");
    if (k > 0 && (size_t)k < footlen) {
        if (btdf_table_get_kind(t) == BTDF_TABLE_FACET_RECIPROCAL) /* slices at ti' = pi - to */
            k += snprintf(foot + k, footlen - (size_t)k,
                          "reciprocal table: slices cover " PLOT_THETA "o %.4g to %.4g" PLOT_DEG
                          " (the eye needs 138.5 to 180" PLOT_DEG ")",
                          180.0 - s1.ti * PV_DEG, 180.0 - s0.ti * PV_DEG);
        else
            k += snprintf(foot + k, footlen - (size_t)k,
                          "the table covers " PLOT_THETA "i %.3g to %.3g" PLOT_DEG
                          " (the near light needs 0 to 41.5" PLOT_DEG ")",
                          s0.ti * PV_DEG, s1.ti * PV_DEG);
    }
    if (k > 0 && (size_t)k < footlen)
        snprintf(foot + k, footlen - (size_t)k,
                 "; far: 100 widths, nearly normal incidence (Fig. 10); near: 0.8 widths (Fig. 11); "
                 "btdftab " BTDF_VERSION_STRING);
    rp->head = o->title ? o->title : rp->title;
    return BTDF_OK;
}

/* Layout: [row label] panel [panel] grey bar [difference panel, colour bar], measured
   on a scratch canvas: the panel side P and the picture's size. */
static int render_layout(render_plot *rp, char *msg, size_t msglen)
{
    const btdf_preview_opts *o = rp->o;
    plot_canvas scratch;
    if (plot_canvas_init(&scratch, 8, 8, pv_white) != 0)
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for the render");
    double fs = o->width ? pv_clampd(o->width / 75.0, 10.0, 14.0) : 13.0;
    double fsS = fmax(PV_MIN_TEXT, 0.88 * fs), m = 0.8 * fs, lineS = plot_text_height(&scratch, fsS);
    double barw = fmax(10.0, 0.9 * fs);
    double blw = fmax(plot_text_width(&scratch, "8.88e-88", fsS),
                      plot_text_width(&scratch, "10" "\xe2\x81\xbb" "\xc2\xb9\xc2\xb9", fsS));
    double barblock = 0.6 * fs + barw + 0.5 * fsS + blw;
    double gap = fmax(10.0, fs);
    double left = m + lineS + 0.5 * fs;
    double fixed_w = left + gap + barblock + m + (o->analytic ? gap + barblock + gap : 0.0) +
                     (rp->nimg - 1) * gap;
    int P = 300;
    if (o->width)
        P = (int)floor((o->width - fixed_w) / rp->npanels);
    double W = o->width ? o->width : fixed_w + rp->npanels * P;
    /* Auto width: at least as wide as the title needs at its size. */
    if (!o->width)
        W = fmax(W, fmin(plot_text_width(&scratch, rp->title, 1.2 * fs) + 2 * m, 1400.0));
    rp->fsT = pv_title_size(&scratch, rp->head, fs, W - 2 * m);
    rp->th = pv_para(&scratch, m, m, rp->head, rp->fsT, W - 2 * m, pv_ink, 0);
    double sub_h = pv_para(&scratch, m, 0, rp->sub, fsS, W - 2 * m, pv_grey, 0);
    rp->foot_h = pv_para(&scratch, m, 0, rp->foot, fsS, W - 2 * m, pv_grey, 0);
    plot_canvas_free(&scratch);
    rp->top = m + rp->th + 0.3 * m + sub_h + 0.6 * m + lineS + 0.3 * lineS;
    rp->rowgap = lineS + 0.3 * lineS + gap;
    if (o->height) {
        int ph = (int)floor((o->height - rp->top - rp->rowgap - rp->foot_h - 2 * m) / 2);
        P = ph < P ? ph : P;
    }
    if (P < RENDER_MIN_PANEL)
        return say(BTDF_EINVAL, msg, msglen,
                   "%d x %d pixels leave render panels of %d pixels; at least %d: make the "
                   "picture larger",
                   o->width, o->height, P, RENDER_MIN_PANEL);
    rp->fs = fs;
    rp->fsS = fsS;
    rp->m = m;
    rp->lineS = lineS;
    rp->barw = barw;
    rp->blw = blw;
    rp->barblock = barblock;
    rp->gap = gap;
    rp->left = left;
    rp->P = P;
    rp->Wi = (int)ceil(W);
    rp->Hi = o->height ? o->height : (int)ceil(rp->top + 2 * P + rp->rowgap + m + rp->foot_h + m);
    /* Column x positions. */
    rp->xs[0] = left;
    rp->xs[1] = left + P + gap;
    rp->gbar = left + rp->nimg * P + (rp->nimg - 1) * gap + 0.6 * fs;
    rp->xs[2] = rp->gbar + barw + 0.5 * fsS + blw + gap;
    return BTDF_OK;
}

/* One row of panels, lit from `depth` (row 0 far, 1 near): the face from the table (and
   from the model), the row's grey bar, the difference panel and the row's label. tab
   and ana hold P x P pixels of BTDF_MAX_CHANNELS, px P x P RGB. */
static void render_row(const render_plot *rp, plot_canvas *c, int row, double *tab,
                       double *ana, unsigned char *px)
{
    const btdf_preview_opts *o = rp->o;
    int P = rp->P, C = rp->C;
    size_t npix = (size_t)P * (size_t)P;
    double D = rp->D, Z = rp->Z, fs = rp->fs, fsS = rp->fsS, m = rp->m, lineS = rp->lineS;
    double depth = row == 0 ? LIGHT_FAR : LIGHT_NEAR;
    double vmax = 0.0, amax = 0.0;
    for (int j = 0; j < P; j++)
        for (int i = 0; i < P; i++) {
            double x = ((i + 0.5) / P - 0.5) / Z, y = (0.5 - (j + 0.5) / P) / Z;
            size_t at = ((size_t)j * (size_t)P + (size_t)i) * BTDF_MAX_CHANNELS;
            face_radiance(rp->t, 0, x, y, depth, tab + at);
            if (o->analytic)
                face_radiance(rp->t, 1, x, y, depth, ana + at);
            for (int ch = 0; ch < C; ch++) {
                vmax = fmax(vmax, tab[at + (size_t)ch]);
                if (o->analytic)
                    amax = fmax(amax, ana[at + (size_t)ch]);
            }
        }
    double smax = vmax > amax ? vmax : amax;
    int y0 = (int)lround(rp->top + row * (P + rp->rowgap));
    for (int q = 0; q < rp->nimg; q++) {
        const double *src = q == 0 ? tab : ana;
        for (size_t e = 0; e < npix; e++)
            for (int b = 0; b < 3; b++)
                px[3 * e + (size_t)b] = (unsigned char)lround(
                    255.0 * tone(src[e * BTDF_MAX_CHANNELS + (size_t)(C == 3 ? b : 0)], smax, D));
        int x0 = (int)lround(rp->xs[q]);
        plot_image(c, x0, y0, P, P, px);
        plot_frame(c, x0, y0, x0 + P, y0 + P, 1.0, pv_grey);
    }
    /* The grey bar of this row: its ends are 0 (or max / 10^D) and the row maximum. */
    char tops[48], bots[48];
    snprintf(tops, sizeof tops, "%.3g", smax);
    if (D > 0.0)
        snprintf(bots, sizeof bots, "%.3g", smax * pow(10.0, -D));
    else
        snprintf(bots, sizeof bots, "0");
    pv_bar_mark marks[13];
    int nm = 0;
    if (D > 0.0 && smax > 0.0)
        for (double d = floor(log10(smax)); d > log10(smax) - D && nm < 13; d -= 1.0) {
            marks[nm].t = 1.0 - (log10(smax) - d) / D;
            pv_format_decade(marks[nm].text, sizeof marks[nm].text, (int)d);
            nm++;
        }
    pv_colour_bar(c, rp->gbar, y0, rp->barw, P, pv_grey_map, tops, bots, marks, nm, fsS);
    if (o->analytic) {
        double dmax = 0.0;
        for (size_t e = 0; e < npix; e++) {
            double d = 0.0;
            for (int ch = 0; ch < C; ch++)
                d = fmax(d, fabs(tab[e * BTDF_MAX_CHANNELS + (size_t)ch] -
                                 ana[e * BTDF_MAX_CHANNELS + (size_t)ch]));
            /* amax = 0: no light at all, so no difference to show. */
            ana[e * BTDF_MAX_CHANNELS] = amax > 0.0 ? d / amax : 0.0;
            dmax = fmax(dmax, ana[e * BTDF_MAX_CHANNELS]);
        }
        for (size_t e = 0; e < npix; e++) {
            /* dmax = 0: table and Eq. 25 agree everywhere; the panel is the map's bottom. */
            plot_rgb col = plot_cmap(dmax > 0.0 ? ana[e * BTDF_MAX_CHANNELS] / dmax : 0.0);
            px[3 * e] = col.r;
            px[3 * e + 1] = col.g;
            px[3 * e + 2] = col.b;
        }
        int x0 = (int)lround(rp->xs[2]);
        plot_image(c, x0, y0, P, P, px);
        plot_frame(c, x0, y0, x0 + P, y0 + P, 1.0, pv_grey);
        snprintf(tops, sizeof tops, "%.2g", dmax);
        pv_colour_bar(c, x0 + P + 0.6 * fs, y0, rp->barw, P, plot_cmap, tops, "0", NULL, 0, fsS);
    }
    char rl[80];
    snprintf(rl, sizeof rl, "light %s: %.3g widths from the face", row == 0 ? "far" : "near", depth);
    if (plot_text_width(c, rl, PV_MIN_TEXT) > P) /* small panels: the short form */
        snprintf(rl, sizeof rl, "%s: %.3g widths", row == 0 ? "far" : "near", depth);
    plot_text_up(c, m + lineS / 2, y0 + P / 2.0, rl, plot_text_fit(c, rl, fsS, PV_MIN_TEXT, P),
                 pv_ink);
}

int pv_draw_render(const btdf_preview_opts *o, plot_canvas *c, char *msg, size_t msglen)
{
    render_plot *rp = calloc(1, sizeof *rp); /* some 1.5 KiB of texts: not on the stack */
    if (!rp)
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for the render");
    rp->o = o;
    int st = render_texts(rp, msg, msglen);
    if (st == BTDF_OK)
        st = render_layout(rp, msg, msglen);
    if (st != BTDF_OK) {
        free(rp);
        return st;
    }
    int P = rp->P;
    double m = rp->m;
    size_t npix = (size_t)P * (size_t)P;
    double *img = malloc(npix * 2 * BTDF_MAX_CHANNELS * sizeof *img);
    unsigned char *px = malloc(npix * 3);
    if (!img || !px || plot_canvas_init(c, rp->Wi, rp->Hi, pv_white) != 0) {
        free(img);
        free(px);
        free(rp);
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for the render");
    }
    double *tab = img, *ana = img + npix * BTDF_MAX_CHANNELS;
    pv_para(c, m, m, rp->head, rp->fsT, rp->Wi - 2 * m, pv_ink, 1);
    pv_para(c, m, m + rp->th + 0.3 * m, rp->sub, rp->fsS, rp->Wi - 2 * m, pv_grey, 1);
    const char *heads[3] = {"from the table", "Eq. 25",
                            "|table " PLOT_MINUS " Eq. 25| / max Eq. 25"};
    for (int q = 0; q < rp->npanels; q++) {
        double hw = q == 2 ? P + rp->barblock : P;
        plot_text(c, rp->xs[q] + hw / 2 - (q == 2 ? rp->barblock / 2 : 0),
                  rp->top - 0.3 * rp->lineS, 0.5, 1, heads[q],
                  plot_text_fit(c, heads[q], rp->fsS, PV_MIN_TEXT, hw), pv_ink);
    }
    for (int row = 0; row < 2; row++)
        render_row(rp, c, row, tab, ana, px);
    pv_para(c, m, rp->Hi - m - rp->foot_h, rp->foot, rp->fsS, rp->Wi - 2 * m, pv_grey, 1);
    free(img);
    free(px);
    free(rp);
    return BTDF_OK;
}
