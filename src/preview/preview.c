/* SPDX-License-Identifier: MIT */
/* preview.c: the pictures of btdf_preview.h: polar lobes, slice montages and face renders,
   drawn with cairo (plot.h). Without cairo and libpng (-Dpng=disabled) only the checks of
   the public functions remain and they answer BTDF_ENOTSUP. */
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "btdf_preview.h"
#include "model/kernel.h"
#include "table/table.h"

#define say core_say /* core/core.h */

#if BTDF_HAVE_PNG

#include "preview/plot.h"

#define DEG (180.0 / M_PI)

static const plot_rgb white = {255, 255, 255};
static const plot_rgb ink = {25, 25, 30};
static const plot_rgb grey = {105, 105, 112};
static const plot_rgb light = {218, 218, 224};
static const plot_rgb below_range = {30, 30, 30};

/* Curve colours, picked to stay apart from each other on white. */
static const plot_rgb palette[BTDF_PREVIEW_MAX_CURVES] = {
    {20, 90, 200}, {230, 110, 10}, {30, 150, 60}, {200, 30, 40},
    {130, 80, 190}, {120, 80, 40}, {220, 80, 170}, {90, 90, 90},
};

#define MIN_TEXT 9.0 /* pixels per em: the smallest text any picture uses */

static double clampd(double v, double lo, double hi)
{
    return v < lo ? lo : (v > hi ? hi : v);
}

static const char *channel_letter(int channels, int ch)
{
    static const char *const rgb[3] = {"R", "G", "B"};
    return channels == 3 ? rgb[ch] : "";
}

/* "n = 1.4" or "n = 1.4/1.41/1.42 (R/G/B)" for three channels. */
static void format_n(char *buf, size_t len, const btdf_params *p)
{
    if (p->channels == 3)
        snprintf(buf, len, "n = %.4g/%.4g/%.4g (R/G/B)", p->ior[0], p->ior[1], p->ior[2]);
    else
        snprintf(buf, len, "n = %.4g", p->ior[0]);
}

/* Writes 10 to the power e with superscript digits: "10\u207b\u00b3" for 1e-3. */
static void format_decade(char *buf, size_t len, int e)
{
    static const char *const sup[10] = {"\xe2\x81\xb0", "\xc2\xb9", "\xc2\xb2", "\xc2\xb3",
                                        "\xe2\x81\xb4", "\xe2\x81\xb5", "\xe2\x81\xb6",
                                        "\xe2\x81\xb7", "\xe2\x81\xb8", "\xe2\x81\xb9"};
    char digits[16];
    snprintf(digits, sizeof digits, "%d", e < 0 ? -e : e);
    size_t k = (size_t)snprintf(buf, len, "10%s", e < 0 ? "\xe2\x81\xbb" : "");
    for (const char *d = digits; *d && k < len; d++)
        k += (size_t)snprintf(buf + k, len - k, "%s", sup[*d - '0']);
}

/* Text split at "; " into lines that fit maxw, drawn from (x, y) down when draw is set;
   a piece wider than maxw alone is broken at spaces, and a word wider than maxw gets a
   smaller size (>= MIN_TEXT). Returns the height used. */
static double para(plot_canvas *c, double x, double y, const char *s, double size, double maxw,
                   plot_rgb col, int draw)
{
    char line[1024], joined[1024];
    double lh = plot_text_height(c, size) * 1.1, used = 0.0;
    line[0] = '\0';
    const char *p = s;
    while (*p) {
        const char *e = strstr(p, "; ");
        int l = (int)(e ? (size_t)(e - p) : strlen(p));
        snprintf(joined, sizeof joined, "%s%s%.*s", line, line[0] ? "; " : "", l, p);
        p = e ? e + 2 : p + l;
        if (line[0] && plot_text_width(c, joined, size) > maxw) { /* the piece starts a line */
            if (draw)
                plot_text(c, x, y + used, 0, 0, line, size, col);
            used += lh;
            snprintf(joined, sizeof joined, "%.*s", l, e ? e - l : p - l);
        }
        memcpy(line, joined, sizeof line);
        /* Break a line still too wide at its last space that fits. */
        while (plot_text_width(c, line, size) > maxw) {
            char *cut = NULL;
            for (char *q = strchr(line, ' '); q; q = strchr(q + 1, ' ')) {
                *q = '\0';
                int fits = plot_text_width(c, line, size) <= maxw;
                *q = ' ';
                if (!fits)
                    break;
                cut = q;
            }
            if (!cut)
                break;
            *cut = '\0';
            if (draw)
                plot_text(c, x, y + used, 0, 0, line, size, col);
            used += lh;
            memmove(line, cut + 1, strlen(cut + 1) + 1);
        }
    }
    if (line[0]) {
        if (draw)
            plot_text(c, x, y + used, 0, 0, line, plot_text_fit(c, line, size, MIN_TEXT, maxw),
                      col);
        used += lh;
    }
    return used;
}

/* A title's size: 1.2 times the body text, down to the body text's size to fit on one
   line; para() breaks it if it is still too wide. */
static double title_size(plot_canvas *c, const char *s, double fs, double maxw)
{
    return plot_text_fit(c, s, 1.2 * fs, fs, maxw);
}

/* A vertical colour bar at (x, y), w x h, top = value t 1 of map(t), and its labels at the
   right: top and bottom ends always, the marks between when they do not collide. Returns
   the x just right of the widest label. */
typedef plot_rgb (*bar_map)(double t);

static plot_rgb grey_map(double t)
{
    unsigned char v = (unsigned char)lround(255.0 * clampd(t, 0.0, 1.0));
    return (plot_rgb){v, v, v};
}

typedef struct bar_mark {
    double t; /* 0 bottom, 1 top */
    char text[48];
} bar_mark;

static double colour_bar(plot_canvas *c, double x, double y, double w, double h, bar_map map,
                         const char *top, const char *bottom, const bar_mark *marks,
                         int nmarks, double size)
{
    int iw = (int)lround(w), ih = (int)lround(h);
    unsigned char *px = malloc((size_t)(iw > 0 ? iw : 1) * (size_t)(ih > 0 ? ih : 1) * 3);
    if (px && iw > 0 && ih > 0) {
        for (int j = 0; j < ih; j++) {
            plot_rgb col = map(1.0 - (j + 0.5) / ih);
            for (int i = 0; i < iw; i++) {
                unsigned char *q = px + 3 * ((size_t)j * (size_t)iw + (size_t)i);
                q[0] = col.r;
                q[1] = col.g;
                q[2] = col.b;
            }
        }
        plot_image(c, (int)lround(x), (int)lround(y), iw, ih, px);
    }
    free(px);
    plot_frame(c, lround(x), lround(y), lround(x) + iw, lround(y) + ih, 1.0, grey);
    double tx = x + w + 0.6 * size, right = tx;
    plot_box b = plot_text(c, tx, y, 0, 0.5, top, size, ink);
    right = fmax(right, b.x1);
    plot_line(c, x + w, y, x + w + 0.35 * size, y, 1.0, 0, ink);
    b = plot_text(c, tx, y + h, 0, 0.5, bottom, size, ink);
    right = fmax(right, b.x1);
    plot_line(c, x + w, y + h, x + w + 0.35 * size, y + h, 1.0, 0, ink);
    for (int k = 0; k < nmarks; k++) {
        double yy = y + (1.0 - marks[k].t) * h;
        plot_box mb = plot_text_box(c, tx, yy, 0, 0.5, marks[k].text, size);
        if (plot_text_collides(c, mb, 1.0))
            continue;
        plot_text(c, tx, yy, 0, 0.5, marks[k].text, size, grey);
        plot_line(c, x + w, yy, x + w + 0.3 * size, yy, 1.0, 0, grey);
        right = fmax(right, mb.x1);
    }
    return right;
}

/* ------------------------------------------------------------------------- */
/* POLAR                                                                     */
/* ------------------------------------------------------------------------- */

#define POLAR_STEPS 6000 /* per side: 0.015 degree steps, finer than an s = 100 lobe */
#define POLAR_MIN_W 480
#define POLAR_MIN_H 360

typedef struct curve {
    const btdf_params *p;
    const btdf_full *full; /* model full: the material's tally, else NULL */
    int ch;
    double ti; /* radians */
    double peak, peak_to;
    double peak_r, peak_tr; /* the reflection's (0 when it is not drawn) */
} curve;

/* rho |cos to| of channel ch in the plane of incidence; side +1 forward (phi = pi). */
static double polar_value(const curve *cv, double to, int side)
{
    double v = cv->full ? btdf_full_rho(cv->full, cv->ti, to, side > 0 ? M_PI : 0.0)
                        : btdf_rho_model(cv->p->model, cv->p->ior[cv->ch], cv->p->smoothness,
                                         cv->p->k0, cv->ti, to, side > 0 ? M_PI : 0.0);
    return v * fabs(cos(to));
}

/* rho_r |cos tr| of channel ch in the plane of incidence; side +1 the specular side
   (phi = pi). */
static double polar_value_r(const curve *cv, double tr, int side)
{
    double v = cv->full ? btdf_full_rho_r(cv->full, cv->ti, tr, side > 0 ? M_PI : 0.0)
                        : btdf_rho_r_model(cv->p->model, cv->p->ior[cv->ch], cv->p->smoothness,
                                cv->p->k0, cv->ti, tr, side > 0 ? M_PI : 0.0);
    return v * fabs(cos(tr));
}

/* Whether the segment (x0, y0)-(x1, y1) passes through box b. */
static int segment_hits(plot_box b, double x0, double y0, double x1, double y1)
{
    for (int i = 0; i <= 64; i++) {
        double x = x0 + (x1 - x0) * i / 64.0, y = y0 + (y1 - y0) * i / 64.0;
        if (x >= b.x0 && x <= b.x1 && y >= b.y0 && y <= b.y1)
            return 1;
    }
    return 0;
}

/* The radius of the half circle in a picture H high: `fixed` pixels of texts, a band
   above the surface of at least band0 (the legend) and 0.3 R (the arrows), R <= Rh. */
static double polar_radius(int H, double fixed, double Rh, double band0, double *band)
{
    *band = band0;
    double R = fmin(Rh, H - fixed - band0);
    if (band0 < 0.3 * R) {
        *band = 0.3 * R;
        R = fmin(Rh, H - fixed - *band);
        if (R < Rh) /* R + 0.3 R = H - fixed */
            R = (H - fixed) / 1.3;
        *band = fmax(band0, 0.3 * R);
    }
    return R;
}

static int draw_polar_in(const btdf_preview_opts *o, btdf_model_ctx *const *mx,
                         plot_canvas *c, char *msg, size_t msglen)
{
    if (!o->materials || !o->ti_deg || o->nmaterials == 0 || o->nti == 0)
        return say(BTDF_EINVAL, msg, msglen, "a polar plot needs materials and ti values");
    if (o->nmaterials > BTDF_PREVIEW_MAX_CURVES || o->nti > BTDF_PREVIEW_MAX_CURVES)
        return say(BTDF_EINVAL, msg, msglen,
                   "%zu materials x %zu angles: at most %d curves fit a polar plot",
                   o->nmaterials, o->nti, BTDF_PREVIEW_MAX_CURVES);
    size_t ncurves = 0;
    for (size_t m = 0; m < o->nmaterials; m++) {
        btdf_params q = o->materials[m];
        if (q.model == BTDF_MODEL_FULL)
            q.model = BTDF_MODEL_SMITH; /* full has smith's parameters (its tally is mx) */
        btdf_status st = btdf_params_check(&q, msg, msglen);
        if (st != BTDF_OK)
            return st;
        ncurves += (size_t)o->materials[m].channels * o->nti;
    }
    if (ncurves > BTDF_PREVIEW_MAX_CURVES)
        return say(BTDF_EINVAL, msg, msglen,
                   "%zu materials x %zu angles = %zu curves (an R,G,B material counts 3); "
                   "at most %d fit a polar plot",
                   o->nmaterials, o->nti, ncurves, BTDF_PREVIEW_MAX_CURVES);
    for (size_t k = 0; k < o->nti; k++)
        if (!(o->ti_deg[k] >= 0.0 && o->ti_deg[k] < 90.0))
            return say(BTDF_EINVAL, msg, msglen, "ti = %g degrees outside [0, 90)",
                       o->ti_deg[k]);
    if (o->part != 0 && o->part != BTDF_PART_TRANSMISSION && o->part != BTDF_PART_REFLECTION &&
        o->part != BTDF_PART_BOTH)
        return say(BTDF_EINVAL, msg, msglen, "part %d: must be transmission (1), reflection (2) "
                   "or both (3)", (int)o->part);
    /* the reflection above the surface (reflection alone: the transmission is not drawn) */
    int refl = o->part == BTDF_PART_REFLECTION || o->part == BTDF_PART_BOTH;
    int trans = o->part != BTDF_PART_REFLECTION;
    int W = o->width ? o->width : 960, H = o->height ? o->height : 720;
    if (W < POLAR_MIN_W || H < POLAR_MIN_H)
        return say(BTDF_EINVAL, msg, msglen,
                   "a polar plot of %d x %d pixels would not be readable: at least %d x %d", W,
                   H, POLAR_MIN_W, POLAR_MIN_H);

    curve cs[BTDF_PREVIEW_MAX_CURVES];
    double vmax = 0.0, vmax_r = 0.0;
    size_t i = 0;
    for (size_t m = 0; m < o->nmaterials; m++)
        for (int ch = 0; ch < o->materials[m].channels; ch++)
            for (size_t k = 0; k < o->nti; k++, i++) {
                curve *cu = &cs[i];
                cu->p = &o->materials[m];
                cu->full = mx[m] && btdf_model_ctx_params(mx[m])->model == BTDF_MODEL_FULL
                               ? btdf_model_ctx_full(mx[m], ch)
                               : NULL;
                cu->ch = ch;
                cu->ti = o->ti_deg[k] / DEG;
                cu->peak = 0.0;
                cu->peak_to = M_PI;
                /* Forward first: at to = 180 degrees both sides meet, and that peak is
                   not on the backward side. */
                for (int side = 1; side >= -1 && trans; side -= 2)
                    for (int j = 0; j <= POLAR_STEPS; j++) {
                        double to = M_PI / 2 + (M_PI / 2) * j / POLAR_STEPS;
                        double v = polar_value(cu, to, side);
                        if (v > cu->peak) {
                            cu->peak = v;
                            cu->peak_to = side > 0 ? to : -to;
                        }
                    }
                /* the reflection's peak (tr in [0, 90), the specular side first) */
                cu->peak_r = 0.0;
                cu->peak_tr = 0.0;
                for (int side = 1; side >= -1 && refl; side -= 2)
                    for (int j = 0; j <= POLAR_STEPS; j++) {
                        double tr = (M_PI / 2) * j / POLAR_STEPS;
                        double v = polar_value_r(cu, tr, side);
                        if (v > cu->peak_r) {
                            cu->peak_r = v;
                            cu->peak_tr = side > 0 ? tr : -tr;
                        }
                    }
                vmax = cu->peak > vmax ? cu->peak : vmax;
                vmax_r = cu->peak_r > vmax_r ? cu->peak_r : vmax_r;
            }
    /* Peaks more than 3 times apart would flatten the small lobes: then every curve is
       scaled to its own peak, and the legend gives the peaks. The reflection (its peak
       is 4e-3 of the transmission's for n = 1.5, s = 3, ti = 30) has its own scale. */
    double pmin = vmax, pmin_r = vmax_r;
    for (i = 0; i < ncurves; i++) {
        pmin = cs[i].peak < pmin ? cs[i].peak : pmin;
        pmin_r = cs[i].peak_r < pmin_r ? cs[i].peak_r : pmin_r;
    }
    int own = vmax > 0.0 && !(pmin * 3.0 >= vmax);
    int own_r = vmax_r > 0.0 && !(pmin_r * 3.0 >= vmax_r);
    /* Colours: one per curve; when every material is R,G,B, the channel's own hue, darker
       for the second (material, ti) pair (8 curves allow at most two such pairs). */
    plot_rgb colour[BTDF_PREVIEW_MAX_CURVES];
    int all_rgb = 1;
    for (size_t q = 0; q < o->nmaterials; q++)
        all_rgb &= o->materials[q].channels == 3;
    for (i = 0; i < ncurves; i++) {
        colour[i] = palette[i];
        if (all_rgb) {
            static const plot_rgb hue[3] = {{215, 35, 35}, {25, 150, 55}, {30, 80, 215}};
            size_t pair = i / (3 * o->nti) * o->nti + i % o->nti; /* (material, ti) */
            double f = pair == 0 ? 1.0 : 0.55;
            colour[i] = (plot_rgb){(unsigned char)lround(hue[cs[i].ch].r * f),
                                   (unsigned char)lround(hue[cs[i].ch].g * f),
                                   (unsigned char)lround(hue[cs[i].ch].b * f)};
        }
    }
    int nt;
    double step = plot_ticks(own ? 1.0 : vmax, 4, &nt), rmax = step * nt;
    int nt_r = 1;
    double step_r = refl ? plot_ticks(own_r ? 1.0 : vmax_r, 4, &nt_r) : 1.0;
    double rmax_r = step_r * nt_r;

    if (plot_canvas_init(c, W, H, white) != 0)
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for a %d x %d picture", W, H);
    double fs = clampd(fmin(W, H * 4.0 / 3.0) / 62.0, 10.0, 16.0), fsS = fmax(MIN_TEXT, 0.88 * fs);
    double m = 0.8 * fs, lineS = plot_text_height(c, fsS);

    /* Title. */
    int smith = o->materials[0].model == BTDF_MODEL_SMITH; /* polar shares one model */
    int full = o->materials[0].model == BTDF_MODEL_FULL;
    const char *title =
        o->title ? o->title
        : full ? (!trans ? PLOT_RHO "r |cos " PLOT_THETA "r| in the plane of incidence: the "
                           "Smith facets with their multiple scattering (model full)"
                  : refl ? PLOT_RHO " |cos " PLOT_THETA "o| below, " PLOT_RHO "r |cos "
                           PLOT_THETA "r| above: the Smith facets with their multiple "
                           "scattering (model full)"
                         : PLOT_RHO " |cos " PLOT_THETA "o| in the plane of incidence: the "
                           "Smith facets with their multiple scattering (model full)")
        : smith ? (!trans ? PLOT_RHO "r |cos " PLOT_THETA "r| in the plane of incidence: the "
                            "same facets with the height-correlated Smith term"
                   : refl ? PLOT_RHO " |cos " PLOT_THETA "o| below, " PLOT_RHO "r |cos "
                            PLOT_THETA "r| above: the facets of Eq. 25 with the "
                            "height-correlated Smith term"
                          : PLOT_RHO " |cos " PLOT_THETA "o| in the plane of incidence: the "
                            "facets of Eq. 25 with the height-correlated Smith term")
        : !trans ? PLOT_RHO "r |cos " PLOT_THETA "r| in the plane of incidence: the reflection "
                   "of the facets of Xu & Sun 2008, Eq. 25"
        : refl   ? PLOT_RHO " |cos " PLOT_THETA "o| below the surface (Xu & Sun 2008, Eq. 25), "
                   PLOT_RHO "r |cos " PLOT_THETA "r| of the same facets above it"
                 : PLOT_RHO " |cos " PLOT_THETA "o| in the plane of incidence (Xu & Sun 2008, "
                   "Eq. 25)";
    double th = para(c, m, m, title, title_size(c, title, fs, W - 2 * m), W - 2 * m, ink, 1);
    double top0 = m + th + 0.5 * m;

    /* Legend texts: one line per curve, or two when one does not fit. */
    char lab[BTDF_PREVIEW_MAX_CURVES][160], peak[BTDF_PREVIEW_MAX_CURVES][80];
    double lx = W / 2.0 + 0.05 * W, sw = 2.2 * fsS, textx = lx + sw + 0.5 * fsS;
    double lw_avail = W - m - textx, lw_one = 0.0;
    for (i = 0; i < ncurves; i++) {
        const curve *cu = &cs[i];
        const char *chn = channel_letter(cu->p->channels, cu->ch);
        snprintf(lab[i], sizeof lab[i], "n = %.4g%s%s%s  s = %.4g  " PLOT_THETA "i = %.4g" PLOT_DEG,
                 cu->p->ior[cu->ch], *chn ? " (" : "", chn, *chn ? ")" : "", cu->p->smoothness,
                 cu->ti * DEG);
        if (!trans)
            snprintf(peak[i], sizeof peak[i], "peak %.3g at %.1f" PLOT_DEG "%s", cu->peak_r,
                     fabs(cu->peak_tr) * DEG, cu->peak_tr < 0 ? " back" : "");
        else if (refl)
            snprintf(peak[i], sizeof peak[i], "peak %.3g at %.1f" PLOT_DEG "%s, r %.3g at %.1f"
                     PLOT_DEG "%s", cu->peak, fabs(cu->peak_to) * DEG,
                     cu->peak_to < 0 ? " back" : "", cu->peak_r, fabs(cu->peak_tr) * DEG,
                     cu->peak_tr < 0 ? " back" : "");
        else
            snprintf(peak[i], sizeof peak[i], "peak %.3g at %.1f" PLOT_DEG "%s", cu->peak,
                     fabs(cu->peak_to) * DEG, cu->peak_to < 0 ? " back" : "");
        double w = plot_text_width(c, lab[i], fsS) + plot_text_width(c, "   ", fsS) +
                   plot_text_width(c, peak[i], fsS);
        lw_one = fmax(lw_one, w);
    }
    int two = lw_one > lw_avail;
    double entry = (two ? 2.0 : 1.0) * lineS + 0.25 * lineS;
    double legend_h = ncurves * entry;

    /* Footer paragraph. */
    char foot[800];
    int same_k0 = 1;
    for (size_t k = 1; k < o->nmaterials; k++)
        same_k0 &= o->materials[k].k0 == o->materials[0].k0;
    char k0s[40] = "";
    if (smith)
        snprintf(k0s, sizeof k0s, "; model smith");
    else if (full)
        snprintf(k0s, sizeof k0s, "; model full");
    else if (same_k0)
        snprintf(k0s, sizeof k0s, "; k0 = %.3g", o->materials[0].k0);
    snprintf(foot, sizeof foot,
             "radius: " PLOT_RHO " |cos " PLOT_THETA "o| (1/sr), linear%s; dashed: Snell direction "
             "through the mean surface, per material%s; " PLOT_RHO ": the BTDF without cosine "
             "factor; " PLOT_THETA "o from the upper normal; btdftab " BTDF_VERSION_STRING,
             own ? ", each curve divided by its own peak (peaks in the legend)" : "", k0s);
    if (refl) { /* the upper half */
        size_t fl = strlen(foot);
        snprintf(foot + fl, sizeof foot - fl,
                 "; above the surface: " PLOT_RHO "r |cos " PLOT_THETA "r|, the reflection of the "
                 "same facets (1/sr), on its own linear scale%s (ticks above the surface line%s), "
                 PLOT_THETA "r from the upper normal, dashed: the mirror direction",
                 own_r ? ", each curve divided by its own peak" : "",
                 trans ? "; the transmission's below it" : "");
    }
    double foot_h = para(c, m, 0, foot, fsS, W - 2 * m, grey, 0);

    /* Geometry: upper band (legend, arrows, tick labels), lower half circle, labels. */
    double labw = plot_text_width(c, "150" PLOT_DEG, fsS) + 0.4 * fsS;
    double band0 = legend_h + 1.6 * lineS, band = band0;
    double Rh = fmin((W / 2.0 - m - labw) / 0.87, W / 2.0 - m);
    double fixed = m + foot_h + 0.6 * m + 1.3 * lineS + top0; /* all but band and radius */
    double R = polar_radius(H, fixed, Rh, band0, &band);
    if (refl) { /* a whole half circle above the surface, below the legend */
        R = fmin(Rh, (H - fixed - band0) / 2.0);
        band = band0 + R;
    }
    /* The plot must stay large beside its texts: a radius of at least 0.28 of the
       picture's smaller side (in 4:3 terms), 0.19 with both halves. */
    double rf = refl ? 0.19 : 0.28;
    double Rmin = rf * fmin(W, H * 4.0 / 3.0);
    if (R < Rmin) {
        int Hn = H;
        while (Hn < BTDF_PREVIEW_MAX_SIDE &&
               (refl ? fmin(Rh, (Hn - fixed - band0) / 2.0)
                     : polar_radius(Hn, fixed, Rh, band0, &band)) < rf * fmin(W, Hn * 4.0 / 3.0))
            Hn++;
        plot_canvas_free(c);
        return say(BTDF_EINVAL, msg, msglen,
                   "%d x %d pixels leave a plot radius of %.0f pixels beside the legend of %zu "
                   "curves: at least %d pixels high at this width",
                   W, H, R, ncurves, Hn);
    }
    double cx = W / 2.0, cy = top0 + band;

    /* Lower medium, grid circles at the round tick values, spokes every 15 degrees. */
    plot_rect(c, 0, cy, W, cy + R + 1, (plot_rgb){246, 248, 252});
    for (int k = 1; k <= nt; k++) {
        double r = R * k / nt;
        cairo_new_path(c->cr);
        cairo_arc(c->cr, cx, cy, r, 0.0, M_PI);
        cairo_set_source_rgb(c->cr, light.r / 255.0, light.g / 255.0, light.b / 255.0);
        cairo_set_line_width(c->cr, 1.0);
        cairo_stroke(c->cr);
    }
    for (int a = 15; a < 180; a += 15) {
        double x = cx + R * cos(a / DEG), y = cy + R * sin(a / DEG);
        plot_line(c, cx, cy, x, y, 1.0, 0, light);
    }
    for (int a = 30; a < 180; a += 30) {
        if (a == 90)
            continue;
        char t[16];
        snprintf(t, sizeof t, "%d" PLOT_DEG, a < 90 ? 90 + a : 270 - a);
        plot_text(c, cx + (R + 0.3 * fsS) * cos(a / DEG), cy + (R + 0.3 * fsS) * sin(a / DEG),
                  a < 90 ? 0.0 : 1.0, 0.3, t, fsS, grey);
    }
    plot_text(c, cx, cy + R + 0.2 * lineS, 0.5, 0.0, PLOT_THETA "o = 180" PLOT_DEG, fsS, grey);
    if (refl) { /* the upper half: the reflection's circles, spokes and angles */
        for (int k = 1; k <= nt_r; k++) {
            cairo_new_path(c->cr);
            cairo_arc(c->cr, cx, cy, R * k / nt_r, M_PI, 2.0 * M_PI);
            cairo_set_source_rgb(c->cr, light.r / 255.0, light.g / 255.0, light.b / 255.0);
            cairo_set_line_width(c->cr, 1.0);
            cairo_stroke(c->cr);
        }
        for (int a = 15; a < 180; a += 15)
            plot_line(c, cx, cy, cx + R * cos(a / DEG), cy - R * sin(a / DEG), 1.0, 0, light);
        for (int a = 30; a < 180; a += 30) {
            if (a == 90)
                continue;
            char t[16];
            snprintf(t, sizeof t, "%d" PLOT_DEG, a < 90 ? 90 - a : a - 90);
            plot_box b = plot_text_box(c, cx + (R + 0.3 * fsS) * cos(a / DEG),
                                       cy - (R + 0.3 * fsS) * sin(a / DEG), a < 90 ? 0.0 : 1.0,
                                       0.7, t, fsS);
            if (!plot_text_collides(c, b, 1.0))
                plot_text(c, cx + (R + 0.3 * fsS) * cos(a / DEG),
                          cy - (R + 0.3 * fsS) * sin(a / DEG), a < 90 ? 0.0 : 1.0, 0.7, t, fsS,
                          grey);
        }
        plot_box b = plot_text_box(c, cx, cy - R - 0.2 * lineS, 0.5, 1.0,
                                   PLOT_THETA "r = 0" PLOT_DEG, fsS);
        if (!plot_text_collides(c, b, 1.0))
            plot_text(c, cx, cy - R - 0.2 * lineS, 0.5, 1.0, PLOT_THETA "r = 0" PLOT_DEG, fsS,
                      grey);
    }
    plot_line(c, 0, cy, W, cy, 2.0, 0, ink);

    /* Radial scale above the surface, right of the centre; with the reflection, its
       scale there and the transmission's below the line. */
    char tl[32];
    for (int half = 0; half <= refl; half++) {
        int below = half == 0 && refl; /* the transmission's ticks, under the line */
        int n_h = half ? nt_r : nt;
        double st_h = half ? step_r : step, vm_h = half ? vmax_r : (trans ? vmax : 0.0);
        double yl = below ? cy + 0.3 * fsS : cy - 0.3 * fsS, ay = below ? 0.0 : 1.0;
        for (int k = 1; k <= n_h && (vm_h > 0.0); k++) {
            double x = cx + R * k / n_h;
            plot_tick_label(tl, sizeof tl, st_h * k, st_h);
            double ax = x + plot_text_width(c, tl, fsS) / 2 > W - m ? 1.0 : 0.5;
            plot_box b = plot_text_box(c, x, yl, ax, ay, tl, fsS);
            plot_line(c, x, below ? cy : cy - 0.25 * fsS, x, below ? cy + 0.25 * fsS : cy, 1.2,
                      0, ink);
            if (!plot_text_collides(c, b, 0.5 * fsS))
                plot_text(c, x, yl, ax, ay, tl, fsS, ink);
        }
    }
    (void)rmax;
    (void)rmax_r;

    /* Snell directions: one dashed line per distinct (n, ti), in the curve's colour, or
       dark grey when several curves share it. */
    for (i = 0; i < ncurves; i++) {
        const curve *cu = &cs[i];
        int seen = 0, shared = 0;
        for (size_t j = 0; j < ncurves; j++) {
            int same = cs[j].p->ior[cs[j].ch] == cu->p->ior[cu->ch] && cs[j].ti == cu->ti;
            seen |= same && j < i;
            shared |= same && j != i;
        }
        double sn = sin(cu->ti) / cu->p->ior[cu->ch]; /* n > 0: btdf_params_check passed */
        if (refl) { /* the mirror direction: tr = ti on the specular side */
            int seen_r = 0, shared_r = 0;
            for (size_t j = 0; j < ncurves; j++) {
                seen_r |= cs[j].ti == cu->ti && j < i;
                shared_r |= cs[j].ti == cu->ti && j != i;
            }
            if (!seen_r)
                plot_line(c, cx, cy, cx + R * sin(cu->ti), cy - R * cos(cu->ti), 1.4, 5.0,
                          shared_r ? grey : colour[i]);
        }
        if (seen || sn > 1.0 || !trans) /* past the critical angle: no refracted direction */
            continue;
        double tt = asin(sn);
        plot_line(c, cx, cy, cx + R * sin(tt), cy + R * cos(tt), 1.4, 5.0,
                  shared ? grey : colour[i]);
    }

    /* Lobes, then the incident directions on top. */
    double *xy = malloc(sizeof *xy * 2 * (2 * (POLAR_STEPS + 1)));
    if (!xy) {
        plot_canvas_free(c);
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for the curves");
    }
    double L = fmin(band - 0.3 * lineS, 0.45 * R);
    for (i = 0; i < ncurves; i++) {
        const curve *cu = &cs[i];
        /* A curve with peak 0 has nothing to draw (and must not be divided by). */
        /* the transmission below the surface, then the reflection above it, each on its
           own scale */
        for (int half = trans ? 0 : 1; half <= refl; half++) {
            double pk = half ? cu->peak_r : cu->peak, rm = half ? rmax_r : rmax;
            int own_h = half ? own_r : own;
            /* rm > 0 (plot_ticks); a curve with peak 0 has nothing to draw */
            double scale = own_h ? (pk > 0.0 ? R / pk : 0.0) : R / rm;
            if (!(scale > 0.0))
                continue;
            size_t np = 0;
            for (int side = -1; side <= 1; side += 2)
                for (int j = 0; j <= POLAR_STEPS; j++) {
                    int jj = side < 0 ? POLAR_STEPS - j : j; /* backward side in, forward out */
                    double to = half ? (M_PI / 2) * (POLAR_STEPS - jj) / POLAR_STEPS
                                     : M_PI / 2 + (M_PI / 2) * jj / POLAR_STEPS;
                    double r = (half ? polar_value_r(cu, to, side) : polar_value(cu, to, side)) *
                               scale;
                    double x = cx + side * r * sin(to), y = cy - r * cos(to);
                    if (np > 0 && j != POLAR_STEPS &&
                        fabs(x - xy[2 * np - 2]) + fabs(y - xy[2 * np - 1]) < 0.4)
                        continue;
                    xy[2 * np] = x;
                    xy[2 * np + 1] = y;
                    np++;
                }
            plot_polyline(c, xy, np, 2.2, colour[i]);
        }
    }
    free(xy);
    /* One arrow per distinct ti: in the curve's colour, or ink when curves share it. */
    for (i = 0; i < ncurves; i++) {
        const curve *cu = &cs[i];
        int seen = 0, shared = 0;
        for (size_t j = 0; j < ncurves; j++) {
            seen |= cs[j].ti == cu->ti && j < i;
            shared |= cs[j].ti == cu->ti && j != i;
        }
        if (seen)
            continue;
        plot_rgb col = shared ? ink : colour[i];
        double ex = cx - L * sin(cu->ti), ey = cy - L * cos(cu->ti);
        double ux = sin(cu->ti), uy = cos(cu->ti); /* unit, towards the surface */
        double hl = fmin(14.0, 0.3 * L), hw = 0.4 * hl;
        double hx = cx - hl * ux, hy = cy - hl * uy;
        plot_line(c, ex, ey, hx, hy, 2.0, 0, col);
        double tri[6] = {cx, cy, hx - hw * uy, hy + hw * ux, hx + hw * uy, hy - hw * ux};
        plot_triangle(c, tri, col);
    }

    /* Side labels where no arrow passes. */
    const char *up = "upper medium: the light comes from here", *lo = "lower medium";
    plot_box ub = plot_text_box(c, m, cy - 0.3 * fsS, 0, 1, up, fsS);
    int hit = 0;
    for (i = 0; i < ncurves; i++)
        hit |= segment_hits(ub, cx, cy, cx - L * sin(cs[i].ti), cy - L * cos(cs[i].ti));
    if (!hit && !plot_text_collides(c, ub, 2.0))
        plot_text(c, m, cy - 0.3 * fsS, 0, 1, up, fsS, grey);
    plot_text(c, m, cy + 0.3 * fsS, 0, 0, lo, fsS, grey);
    const char *bw = "backward (" PLOT_PHI " = 0" PLOT_DEG ")",
               *fw = "forward (" PLOT_PHI " = 180" PLOT_DEG ")";
    plot_box bb = plot_text_box(c, m, cy + R, 0, 1, bw, fsS);
    if (!plot_text_collides(c, bb, 2.0))
        plot_text(c, m, cy + R, 0, 1, bw, fsS, grey);
    plot_box fb = plot_text_box(c, W - m, cy + R, 1, 1, fw, fsS);
    if (!plot_text_collides(c, fb, 2.0))
        plot_text(c, W - m, cy + R, 1, 1, fw, fsS, grey);

    /* Legend: upper right, above the tick labels, clear of the arrows (x > cx). */
    for (i = 0; i < ncurves; i++) {
        double y = top0 + i * entry;
        plot_line(c, lx, y + lineS / 2, lx + sw, y + lineS / 2, 3.0, 0, colour[i]);
        double fsz = plot_text_fit(c, lab[i], fsS, MIN_TEXT, lw_avail);
        plot_box b = plot_text(c, textx, y, 0, 0, lab[i], fsz, ink);
        if (two)
            plot_text(c, textx, y + lineS, 0, 0, peak[i], fsz, grey);
        else
            plot_text(c, b.x1 + plot_text_width(c, "   ", fsS), y, 0, 0, peak[i], fsS, grey);
    }
    if (trans && !(vmax > 0.0))
        plot_text(c, cx, cy + R / 2, 0.5, 0.5, "no transmission", fs, ink);
    if (refl && !(vmax_r > 0.0))
        plot_text(c, cx, cy - R / 2, 0.5, 0.5, "no reflection", fs, ink);
    para(c, m, H - m - foot_h, foot, fsS, W - 2 * m, grey, 1);
    return BTDF_OK;
}

/* ------------------------------------------------------------------------- */
/* MONTAGE                                                                   */
/* ------------------------------------------------------------------------- */

#define DECADES 6.0
#define MONTAGE_MIN_W 480
#define MIN_TILE 16

static int draw_montage(const btdf_preview_opts *o, plot_canvas *c, char *msg, size_t msglen)
{
    const btdf_table *t = o->table;
    if (!t)
        return say(BTDF_EINVAL, msg, msglen, "a montage needs a table");
    size_t n = btdf_table_slice_count(t);
    if (n == 0)
        return say(BTDF_EINVAL, msg, msglen, "the table has no slices");
    int W = o->width ? o->width : 1000;
    if (W < MONTAGE_MIN_W)
        return say(BTDF_EINVAL, msg, msglen,
                   "a montage %d pixels wide would not be readable: at least %d", W,
                   MONTAGE_MIN_W);
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
        for (size_t q = 0; q < s.nrows * s.ncols; q++) {
            double v = s.values[q * (size_t)p->channels];
            vmax = v > vmax ? v : vmax;
        }
    }
    double lo = vmax * pow(10.0, -DECADES);
    int recip = kind == BTDF_TABLE_FACET_RECIPROCAL, facet = kind != BTDF_TABLE_GRID;

    /* Measure on a scratch canvas first: the height depends on the wrapped texts. */
    plot_canvas scratch;
    if (plot_canvas_init(&scratch, 8, 8, white) != 0)
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for the montage");
    double fs = clampd(W / 70.0, 10.0, 15.0), fsS = fmax(MIN_TEXT, 0.88 * fs);
    double m = 0.8 * fs, lineS = plot_text_height(&scratch, fsS);
    char title[300], nbuf[64], sub[600];
    format_n(nbuf, sizeof nbuf, p);
    snprintf(title, sizeof title, "%s table: %s  s = %.4g  k0 = %.3g;  %zu slices, %zu nodes",
             recip ? "facet-reciprocal" : (facet ? "facet" : "grid"), nbuf, p->smoothness,
             p->k0, n, btdf_table_node_count(t));
    int k = snprintf(sub, sizeof sub,
                     "%s%s" PLOT_RHO " (1/sr) of channel %s on a log scale, %g decades; tiles "
                     "in the table's coordinates, row 0 on top%s",
                     o->title ? title : "", o->title ? "; " : "", p->channels == 3 ? "R" : "Y",
                     DECADES, shown < n ? "; evenly spaced slices" : "");
    if (recip && k > 0 && (size_t)k < sizeof sub)
        /* The slices are the facet table of 1/n at ti' = pi - to (btdf.h): say so, and
           label each tile with the outgoing angle of the light leaving. */
        snprintf(sub + k, sizeof sub - (size_t)k,
                 "; reciprocal: each tile is the facet table of index 1/n = %.4g at " PLOT_THETA
                 "i' = 180" PLOT_DEG " " PLOT_MINUS " " PLOT_THETA "o; " PLOT_RHO " = n" "\xc2\xb2"
                 " " PLOT_RHO "(1/n)",
                 1.0 / p->ior[0]);
    const char *head = o->title ? o->title : title;
    double fsT = title_size(&scratch, head, fs, W - 2 * m);
    double th = para(&scratch, m, m, head, fsT, W - 2 * m, ink, 0);
    double sub_h = para(&scratch, m, 0, sub, fsS, W - 2 * m, grey, 0);
    /* Widths of the side columns: row labels at the left, the colour bar at the right. */
    char lab[64];
    double rlw = 0.0;
    for (size_t q = 0; q < shown; q++) {
        btdf_slice s;
        btdf_table_slice(t, idx[q], &s);
        for (int e = 0; e < 2; e++) {
            snprintf(lab, sizeof lab, "%.4g", (e ? s.rows[s.nrows - 1] : s.rows[0]) * DEG);
            rlw = fmax(rlw, plot_text_width(&scratch, lab, fsS));
        }
    }
    char top_s[48], bot_s[48];
    snprintf(top_s, sizeof top_s, "%.3g", vmax);
    snprintf(bot_s, sizeof bot_s, "%.3g", lo);
    double barw = fmax(12.0, fs);
    double blw = fmax(plot_text_width(&scratch, top_s, fsS), plot_text_width(&scratch, bot_s, fsS));
    blw = fmax(blw, plot_text_width(&scratch, "10" "\xe2\x81\xbb" "\xc2\xb9" "\xc2\xb9", fsS));
    blw = fmax(blw, plot_text_width(&scratch, "< max/10" "\xe2\x81\xb6", fsS));
    plot_canvas_free(&scratch);

    double left = m + lineS + 0.5 * fsS + rlw + 0.5 * fsS;
    double right = 1.5 * fs + barw + 0.6 * fsS + blw + m;
    double gap = fmax(8.0, 0.7 * fs), labh = lineS + 2.0;
    double top = m + th + 0.4 * m + sub_h + 0.5 * m;
    double bottom = 0.3 * fsS + lineS + 0.4 * lineS + lineS + m;
    int cols = (int)ceil(sqrt((double)shown));
    int rows = (int)((shown + (size_t)cols - 1) / (size_t)cols);
    int tile = (int)floor((W - left - right - (cols - 1) * gap) / cols);
    int H = o->height;
    if (H) { /* fit the height too */
        int tht = (int)floor((H - top - bottom - rows * (labh + gap) + gap) / rows);
        tile = tht < tile ? tht : tile;
    }
    if (tile < MIN_TILE)
        return say(BTDF_EINVAL, msg, msglen,
                   "%d x %d pixels leave tiles of %d pixels for %zu slices; at least %d: make "
                   "the picture larger",
                   W, H, tile, shown, MIN_TILE);
    double gh = rows * (labh + tile + gap) - gap;
    double minbar = labh + 80.0 + 4.0 * lineS;
    if (!H)
        H = (int)ceil(top + fmax(gh, minbar) + bottom);
    else if (top + minbar + bottom > H)
        return say(BTDF_EINVAL, msg, msglen,
                   "a montage %d pixels high has no room for its colour bar: at least %.0f", H,
                   ceil(top + minbar + bottom));
    if (plot_canvas_init(c, W, H, white) != 0)
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for a %d x %d picture", W, H);
    para(c, m, m, head, fsT, W - 2 * m, ink, 1);
    para(c, m, m + th + 0.4 * m, sub, fsS, W - 2 * m, grey, 1);

    unsigned char *px = malloc((size_t)tile * (size_t)tile * 3);
    if (!px) {
        plot_canvas_free(c);
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for the montage");
    }
    for (size_t q = 0; q < shown; q++) {
        btdf_slice s;
        btdf_table_slice(t, idx[q], &s);
        int gx = (int)(q % (size_t)cols), gy = (int)(q / (size_t)cols);
        double x0 = left + gx * (tile + gap), y0 = top + gy * (tile + labh + gap) + labh;
        double la = recip ? 180.0 - s.ti * DEG : s.ti * DEG;
        snprintf(lab, sizeof lab, "%s = %.2f" PLOT_DEG, recip ? PLOT_THETA "o" : PLOT_THETA "i",
                 la);
        if (plot_text_width(c, lab, fsS) > tile + gap - 2) /* narrow tiles: the angle only */
            snprintf(lab, sizeof lab, "%.4g" PLOT_DEG, la);
        plot_text(c, x0, y0 - 1, 0, 1, lab, plot_text_fit(c, lab, fsS, MIN_TEXT * 0.9, tile + gap - 2), ink);
        double r0 = s.rows[0], r1 = s.rows[s.nrows - 1];
        double c0 = s.cols[0], c1 = s.cols[s.ncols - 1];
        for (int y = 0; y < tile; y++)
            for (int x = 0; x < tile; x++) {
                double rq = r0 + (r1 - r0) * (y + 0.5) / tile;
                double cq = c0 + (c1 - c0) * (x + 0.5) / tile;
                double v = slice_interp(t, idx[q], rq, cq, 0); /* the table's own rule */
                /* lo = 0 when the table is all zeros: everything is below range. */
                plot_rgb col = v > lo && lo > 0.0
                                   ? plot_cmap((log10(v) - log10(lo)) / DECADES)
                                   : below_range;
                unsigned char *d = px + 3 * ((size_t)y * (size_t)tile + (size_t)x);
                d[0] = col.r;
                d[1] = col.g;
                d[2] = col.b;
            }
        plot_image(c, (int)lround(x0), (int)lround(y0), tile, tile, px);
        x0 = lround(x0);
        y0 = lround(y0);
        plot_frame(c, x0, y0, x0 + tile, y0 + tile, 1.0, grey);
        if (gx == 0) {
            snprintf(lab, sizeof lab, "%.4g", r0 * DEG);
            plot_text(c, x0 - 0.4 * fsS, y0, 1, 0, lab, fsS, ink);
            snprintf(lab, sizeof lab, "%.4g", r1 * DEG);
            plot_text(c, x0 - 0.4 * fsS, y0 + tile, 1, 1, lab, fsS, ink);
        }
        if (gy == rows - 1 || q + (size_t)cols >= shown) {
            snprintf(lab, sizeof lab, "%.4g", c0 * DEG);
            plot_box b = plot_text_box(c, x0, y0 + tile + 0.3 * fsS, 0, 0, lab, fsS);
            if (!plot_text_collides(c, b, 1.0))
                plot_text(c, x0, y0 + tile + 0.3 * fsS, 0, 0, lab, fsS, ink);
            snprintf(lab, sizeof lab, "%.4g", c1 * DEG);
            b = plot_text_box(c, x0 + tile, y0 + tile + 0.3 * fsS, 1, 0, lab, fsS);
            if (!plot_text_collides(c, b, 1.0))
                plot_text(c, x0 + tile, y0 + tile + 0.3 * fsS, 1, 0, lab, fsS, ink);
        }
    }
    free(px);
    const char *rl = facet ? "rows: " PLOT_THETA "n, facet tilt (deg)" : "rows: " PLOT_THETA "o (deg)";
    plot_text_up(c, m + lineS / 2, top + gh / 2, rl, plot_text_fit(c, rl, fsS, MIN_TEXT, gh), ink);
    const char *cl = facet ? "cols: " PLOT_PSI ", facet azimuth (deg)" : "cols: " PLOT_PHI " (deg)";
    plot_text(c, left + (cols * (tile + gap) - gap) / 2, top + gh + 0.3 * fsS + lineS + 0.4 * lineS,
              0.5, 0, cl, fsS, ink);

    /* Colour bar: its ends are the table's maximum and maximum / 10^6, decades between. */
    double bx = W - right + 1.5 * fs, by = top + labh + 1.6 * lineS;
    double bh = fmin(fmax(gh - labh - 4.0 * lineS, 80.0), 420.0);
    plot_text(c, bx, top + labh, 0, 0.5, PLOT_RHO " (1/sr)", fsS, ink);
    bar_mark marks[16];
    int nm = 0;
    if (vmax > 0.0) {
        for (double d = floor(log10(vmax)); d > log10(lo) && nm < 16; d -= 1.0) {
            marks[nm].t = 1.0 - (log10(vmax) - d) / DECADES;
            format_decade(marks[nm].text, sizeof marks[nm].text, (int)d);
            nm++;
        }
    }
    colour_bar(c, bx, by, barw, bh, plot_cmap, top_s, bot_s, marks, nm, fsS);
    double sy = by + bh + 0.8 * lineS;
    plot_rect(c, bx, sy, bx + barw, sy + lineS * 0.8, below_range);
    plot_text(c, bx + barw + 0.5 * fsS, sy + lineS * 0.4, 0, 0.5, "< max/10" "\xe2\x81\xb6", fsS, ink);
    return BTDF_OK;
}

/* ------------------------------------------------------------------------- */
/* RENDER                                                                    */
/* ------------------------------------------------------------------------- */

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

/* Grey level in [0, 1] of radiance u of a row whose maximum is umax: linear, or log10
   over `decades` below umax. */
static double tone(double u, double umax, double decades)
{
    if (!(umax > 0.0) || !(u > 0.0))
        return 0.0; /* nothing lit, or this pixel dark: black (and no log of 0) */
    if (decades <= 0.0)
        return fmin(1.0, u / umax);
    return clampd((log10(u / umax) + decades) / decades, 0.0, 1.0);
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
    format_n(nbuf, sizeof nbuf, p);
    const char *what = below == p->channels   ? "Rough face of a dense block lit from inside"
                       : above == p->channels ? "Rough face of a dense block lit from outside"
                                              : "Rough face between two media";
    snprintf(buf, len, "%s: %s  s = %.4g", what, nbuf, p->smoothness);
}

static int draw_render(const btdf_preview_opts *o, plot_canvas *c, char *msg, size_t msglen)
{
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
    double Z = o->zoom == 0.0 ? 1.0 : o->zoom;
    if (!(Z >= 1.0 && Z <= 1000.0))
        return say(BTDF_EINVAL, msg, msglen,
                   "zoom = %g: 1 (or 0) for the whole face, up to 1000 for its central 1/1000",
                   o->zoom);
    const btdf_params *p = btdf_table_get_params(t);
    int nimg = o->analytic ? 2 : 1, C = p->channels;
    btdf_slice s0, s1;
    btdf_table_slice(t, 0, &s0);
    btdf_table_slice(t, n - 1, &s1);

    char title[300], sub[400], foot[700];
    render_title(title, sizeof title, p);
    int lit_inside = p->ior[0] < 1.0;
    char shown[80] = "face 1 W wide";
    if (Z > 1.0)
        snprintf(shown, sizeof shown, "the central %.3g W of a face 1 W wide (zoom %g)", 1.0 / Z,
                 Z);
    snprintf(sub, sizeof sub,
             "%s; point light on its axis in the light's medium (%s the block); eye "
             "0.8 W from the face on its axis, %s",
             shown, lit_inside ? "inside" : "outside", lit_inside ? "outside" : "inside");
    char scale[160];
    if (D > 0.0)
        snprintf(scale, sizeof scale, "log10 scale over %g decades below each row's maximum", D);
    else
        snprintf(scale, sizeof scale, "linear, each row scaled to its maximum as in the paper");
    int k = snprintf(foot, sizeof foot,
                     "radiance " PLOT_RHO " cos " PLOT_THETA "i I / r" "\xc2\xb2" ", %s%s; ",
                     scale, C == 3 ? " (R, G, B)" : "");
    if (k > 0 && (size_t)k < sizeof foot) {
        if (btdf_table_get_kind(t) == BTDF_TABLE_FACET_RECIPROCAL) /* slices at ti' = pi - to */
            k += snprintf(foot + k, sizeof foot - (size_t)k,
                          "reciprocal table: slices cover " PLOT_THETA "o %.4g to %.4g" PLOT_DEG
                          " (the eye needs 138.5 to 180" PLOT_DEG ")",
                          180.0 - s1.ti * DEG, 180.0 - s0.ti * DEG);
        else
            k += snprintf(foot + k, sizeof foot - (size_t)k,
                          "the table covers " PLOT_THETA "i %.3g to %.3g" PLOT_DEG
                          " (the near light needs 0 to 41.5" PLOT_DEG ")",
                          s0.ti * DEG, s1.ti * DEG);
    }
    if (k > 0 && (size_t)k < sizeof foot)
        snprintf(foot + k, sizeof foot - (size_t)k,
                 "; far: 100 W, nearly normal incidence (Fig. 10); near: 0.8 W (Fig. 11); "
                 "btdftab " BTDF_VERSION_STRING);

    /* Layout: [row label] panel [panel] grey bar [difference panel, colour bar]. */
    plot_canvas scratch;
    if (plot_canvas_init(&scratch, 8, 8, white) != 0)
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for the render");
    double fs = o->width ? clampd(o->width / 75.0, 10.0, 14.0) : 13.0;
    double fsS = fmax(MIN_TEXT, 0.88 * fs), m = 0.8 * fs, lineS = plot_text_height(&scratch, fsS);
    double barw = fmax(10.0, 0.9 * fs);
    double blw = fmax(plot_text_width(&scratch, "8.88e-88", fsS),
                      plot_text_width(&scratch, "10" "\xe2\x81\xbb" "\xc2\xb9\xc2\xb9", fsS));
    double barblock = 0.6 * fs + barw + 0.5 * fsS + blw;
    double gap = fmax(10.0, fs);
    double left = m + lineS + 0.5 * fs;
    double fixed_w = left + gap + barblock + m + (o->analytic ? gap + barblock + gap : 0.0) +
                     (nimg - 1) * gap;
    int npanels = nimg + (o->analytic ? 1 : 0);
    int P = 300;
    if (o->width)
        P = (int)floor((o->width - fixed_w) / npanels);
    double W = o->width ? o->width : fixed_w + npanels * P;
    /* Auto width: at least as wide as the title needs at its size. */
    if (!o->width)
        W = fmax(W, fmin(plot_text_width(&scratch, title, 1.2 * fs) + 2 * m, 1400.0));
    const char *head = o->title ? o->title : title;
    double fsT = title_size(&scratch, head, fs, W - 2 * m);
    double th = para(&scratch, m, m, head, fsT, W - 2 * m, ink, 0);
    double sub_h = para(&scratch, m, 0, sub, fsS, W - 2 * m, grey, 0);
    double foot_h = para(&scratch, m, 0, foot, fsS, W - 2 * m, grey, 0);
    plot_canvas_free(&scratch);
    double top = m + th + 0.3 * m + sub_h + 0.6 * m + lineS + 0.3 * lineS;
    double rowgap = lineS + 0.3 * lineS + gap;
    if (o->height) {
        int ph = (int)floor((o->height - top - rowgap - foot_h - 2 * m) / 2);
        P = ph < P ? ph : P;
    }
    if (P < RENDER_MIN_PANEL)
        return say(BTDF_EINVAL, msg, msglen,
                   "%d x %d pixels leave render panels of %d pixels; at least %d: make the "
                   "picture larger",
                   o->width, o->height, P, RENDER_MIN_PANEL);
    int Wi = (int)ceil(W);
    int Hi = o->height ? o->height : (int)ceil(top + 2 * P + rowgap + m + foot_h + m);
    size_t npix = (size_t)P * (size_t)P;
    double *img = malloc(npix * 2 * BTDF_MAX_CHANNELS * sizeof *img);
    unsigned char *px = malloc(npix * 3);
    if (!img || !px || plot_canvas_init(c, Wi, Hi, white) != 0) {
        free(img);
        free(px);
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for the render");
    }
    double *tab = img, *ana = img + npix * BTDF_MAX_CHANNELS;
    para(c, m, m, head, fsT, Wi - 2 * m, ink, 1);
    para(c, m, m + th + 0.3 * m, sub, fsS, Wi - 2 * m, grey, 1);

    /* Column x positions. */
    double xs[3];
    xs[0] = left;
    xs[1] = left + P + gap;
    double gbar = left + nimg * P + (nimg - 1) * gap + 0.6 * fs;
    xs[2] = gbar + barw + 0.5 * fsS + blw + gap;
    const char *heads[3] = {"from the table", "Eq. 25",
                            "|table " PLOT_MINUS " Eq. 25| / max Eq. 25"};
    for (int q = 0; q < npanels; q++) {
        double hw = q == 2 ? P + barblock : P;
        plot_text(c, xs[q] + hw / 2 - (q == 2 ? barblock / 2 : 0), top - 0.3 * lineS, 0.5, 1,
                  heads[q], plot_text_fit(c, heads[q], fsS, MIN_TEXT, hw), ink);
    }
    for (int row = 0; row < 2; row++) {
        double depth = row == 0 ? LIGHT_FAR : LIGHT_NEAR;
        double vmax = 0.0, amax = 0.0;
        for (int j = 0; j < P; j++)
            for (int i = 0; i < P; i++) {
                double x = ((i + 0.5) / P - 0.5) / Z, y = (0.5 - (j + 0.5) / P) / Z;
                size_t at = ((size_t)j * (size_t)P + (size_t)i) * BTDF_MAX_CHANNELS;
                face_radiance(t, 0, x, y, depth, tab + at);
                if (o->analytic)
                    face_radiance(t, 1, x, y, depth, ana + at);
                for (int ch = 0; ch < C; ch++) {
                    vmax = fmax(vmax, tab[at + (size_t)ch]);
                    if (o->analytic)
                        amax = fmax(amax, ana[at + (size_t)ch]);
                }
            }
        double smax = vmax > amax ? vmax : amax;
        int y0 = (int)lround(top + row * (P + rowgap));
        for (int q = 0; q < nimg; q++) {
            const double *src = q == 0 ? tab : ana;
            for (size_t e = 0; e < npix; e++)
                for (int b = 0; b < 3; b++)
                    px[3 * e + (size_t)b] = (unsigned char)lround(
                        255.0 * tone(src[e * BTDF_MAX_CHANNELS + (size_t)(C == 3 ? b : 0)], smax, D));
            int x0 = (int)lround(xs[q]);
            plot_image(c, x0, y0, P, P, px);
            plot_frame(c, x0, y0, x0 + P, y0 + P, 1.0, grey);
        }
        /* The grey bar of this row: its ends are 0 (or max / 10^D) and the row maximum. */
        char tops[48], bots[48];
        snprintf(tops, sizeof tops, "%.3g", smax);
        if (D > 0.0)
            snprintf(bots, sizeof bots, "%.3g", smax * pow(10.0, -D));
        else
            snprintf(bots, sizeof bots, "0");
        bar_mark marks[13];
        int nm = 0;
        if (D > 0.0 && smax > 0.0)
            for (double d = floor(log10(smax)); d > log10(smax) - D && nm < 13; d -= 1.0) {
                marks[nm].t = 1.0 - (log10(smax) - d) / D;
                format_decade(marks[nm].text, sizeof marks[nm].text, (int)d);
                nm++;
            }
        colour_bar(c, gbar, y0, barw, P, grey_map, tops, bots, marks, nm, fsS);
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
            int x0 = (int)lround(xs[2]);
            plot_image(c, x0, y0, P, P, px);
            plot_frame(c, x0, y0, x0 + P, y0 + P, 1.0, grey);
            snprintf(tops, sizeof tops, "%.2g", dmax);
            colour_bar(c, x0 + P + 0.6 * fs, y0, barw, P, plot_cmap, tops, "0", NULL, 0, fsS);
        }
        char rl[80];
        snprintf(rl, sizeof rl, "light %s: %.3g W from the face", row == 0 ? "far" : "near",
                 depth);
        if (plot_text_width(c, rl, MIN_TEXT) > P) /* small panels: the short form */
            snprintf(rl, sizeof rl, "%s: %.3g W", row == 0 ? "far" : "near", depth);
        plot_text_up(c, m + lineS / 2, y0 + P / 2.0, rl, plot_text_fit(c, rl, fsS, MIN_TEXT, P),
                     ink);
    }
    para(c, m, Hi - m - foot_h, foot, fsS, Wi - 2 * m, grey, 1);
    free(img);
    free(px);
    return BTDF_OK;
}

/* draw_polar_in with the model objects of the materials (tallied here for model full,
   once per material; nothing is made for the others). */
static int draw_polar(const btdf_preview_opts *o, plot_canvas *c, char *msg, size_t msglen)
{
    btdf_model_ctx *mx[BTDF_PREVIEW_MAX_CURVES] = {NULL};
    size_t nm = o->materials && o->nmaterials <= BTDF_PREVIEW_MAX_CURVES ? o->nmaterials : 0;
    int rc = BTDF_OK;
    for (size_t m = 0; m < nm && rc == BTDF_OK; m++)
        if (o->materials[m].model == BTDF_MODEL_FULL)
            rc = btdf_model_ctx_new(&o->materials[m], NULL, &mx[m], msg, msglen);
    if (rc == BTDF_OK)
        rc = draw_polar_in(o, mx, c, msg, msglen);
    for (size_t m = 0; m < nm; m++)
        btdf_model_ctx_free(mx[m]);
    return rc;
}

int btdf_preview_draw(const btdf_preview_opts *o, plot_canvas *c, char *msg, size_t msglen)
{
    memset(c, 0, sizeof *c);
    if (o->width < 0 || o->height < 0 || o->width > BTDF_PREVIEW_MAX_SIDE ||
        o->height > BTDF_PREVIEW_MAX_SIDE)
        return say(BTDF_EINVAL, msg, msglen, "picture size %d x %d outside 1 to %d", o->width,
                   o->height, BTDF_PREVIEW_MAX_SIDE);
    switch (o->kind) {
    case BTDF_PREVIEW_POLAR: return draw_polar(o, c, msg, msglen);
    case BTDF_PREVIEW_MONTAGE: return draw_montage(o, c, msg, msglen);
    case BTDF_PREVIEW_RENDER: return draw_render(o, c, msg, msglen);
    default: return say(BTDF_EINVAL, msg, msglen, "unknown picture kind %d", (int)o->kind);
    }
}

#endif /* BTDF_HAVE_PNG */

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
#if BTDF_HAVE_PNG
    plot_canvas c;
    btdf_status st = (btdf_status)btdf_preview_draw(o, &c, msg, msglen);
    if (st != BTDF_OK) {
        plot_canvas_free(&c);
        return st;
    }
    *rgb = plot_canvas_rgb(&c);
    *width = c.w;
    *height = c.h;
    plot_canvas_free(&c);
    if (!*rgb)
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for a %d x %d picture", *width,
                   *height);
    return BTDF_OK;
#else
    return say(BTDF_ENOTSUP, msg, msglen,
               "pictures were switched off at build time (-Dpng=disabled)");
#endif
}

BTDF_API void btdf_preview_free(unsigned char *rgb)
{
    free(rgb);
}
