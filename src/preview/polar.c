/* SPDX-License-Identifier: MIT */
/* polar.c: the lobes of one or more materials in the plane of incidence, like Figs. 5
   and 6 of Xu & Sun (2008): rho |cos to| below the surface, rho_r |cos tr| above. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model/kernel.h"
#include "preview/style.h"
#include "table/table.h"

/* Curve colours, picked to stay apart from each other on white. */
static const plot_rgb palette[BTDF_PREVIEW_MAX_CURVES] = {
    {20, 90, 200}, {230, 110, 10}, {30, 150, 60}, {200, 30, 40},
    {130, 80, 190}, {120, 80, 40}, {220, 80, 170}, {90, 90, 90},
};

static const char *channel_letter(int channels, int ch)
{
    static const char *const rgb[3] = {"R", "G", "B"};
    return channels == 3 ? rgb[ch] : "";
}

#define POLAR_STEPS 6000 /* per side: 0.015 degree steps, finer than an s = 100 lobe */
#define POLAR_MIN_W 480
#define POLAR_MIN_H 360

typedef struct curve {
    const btdf_params *p;
    const btdf_full *full; /* model full: the material's tally, else NULL */
    const btdf_preview_opts *o; /* o->eval, when set, gives the values */
    int ch;
    double ti; /* radians */
    double peak, peak_to;
    double peak_r, peak_tr; /* the reflection's (0 when it is not drawn) */
} curve;

/* rho |cos to| of channel ch in the plane of incidence; side +1 forward (phi = pi). */
/* The caller's value of channel ch (o->eval); 0 for what is not a finite value >= 0. */
static double polar_eval(const curve *cv, int reflection, double to, int side)
{
    double out[BTDF_MAX_CHANNELS] = {0};
    cv->o->eval(cv->o->eval_user, reflection, cv->ti, to, side > 0 ? M_PI : 0.0, out);
    double v = out[cv->ch];
    return isfinite(v) && v > 0.0 ? v : 0.0;
}

static double polar_value(const curve *cv, double to, int side)
{
    if (cv->o->eval)
        return polar_eval(cv, 0, to, side) * fabs(cos(to));
    double v = cv->full ? btdf_full_rho(cv->full, cv->ti, to, side > 0 ? M_PI : 0.0)
                        : btdf_rho_model(cv->p->model, cv->p->ior[cv->ch], cv->p->smoothness,
                                         cv->p->k0, cv->ti, to, side > 0 ? M_PI : 0.0);
    return v * fabs(cos(to));
}

/* rho_r |cos tr| of channel ch in the plane of incidence; side +1 the specular side
   (phi = pi). */
static double polar_value_r(const curve *cv, double tr, int side)
{
    if (cv->o->eval)
        return polar_eval(cv, 1, tr, side) * fabs(cos(tr));
    double v = cv->full ? btdf_full_rho_r(cv->full, cv->ti, tr, side > 0 ? M_PI : 0.0)
                        : btdf_rho_r_model(cv->p->model, cv->p->ior[cv->ch],
                                           cv->p->smoothness, cv->p->k0, cv->ti, tr,
                                           side > 0 ? M_PI : 0.0);
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

/* One polar picture, filled in by the phases below in order: the checks, the curves'
   peaks and colours, the texts, the layout, then the drawing (grid, Snell directions,
   lobes, arrows, labels). Text placement avoids what is already drawn, so the order
   of the drawing phases is part of the picture. */
typedef struct polar_plot {
    const btdf_preview_opts *o;
    btdf_model_ctx *mx[BTDF_PREVIEW_MAX_CURVES]; /* per material: full's tally, or NULL */
    size_t ncurves;
    curve cs[BTDF_PREVIEW_MAX_CURVES];
    plot_rgb colour[BTDF_PREVIEW_MAX_CURVES];
    int refl, trans; /* which halves are drawn */
    int smith, full; /* polar shares one model */
    int W, H;
    int H_needed;        /* the height the layout asked for when H was too small */
    double vmax, vmax_r; /* the largest peaks below and above */
    int own, own_r;      /* each curve on its own scale (below, above) */
    int nt, nt_r;        /* tick counts and steps of the radial scales */
    double step, step_r, rmax, rmax_r;
    double fs, fsS, m, lineS; /* text sizes, margin, line height */
    double top0;              /* the first line under the title */
    char lab[BTDF_PREVIEW_MAX_CURVES][160], peak[BTDF_PREVIEW_MAX_CURVES][80];
    double lx, sw, textx, lw_avail, entry; /* the legend's columns and line pitch */
    int two;                               /* legend entries on two lines */
    double legend_h;
    char foot[800];
    double foot_h;
    double cx, cy, R, band; /* the centre, radius and upper band */
    double L;               /* the incident arrows' length */
    double *pts;            /* every lobe's drawn points, x y pairs (tick labels avoid them) */
    size_t npts;
} polar_plot;

static int polar_check(polar_plot *pp, char *msg, size_t msglen)
{
    const btdf_preview_opts *o = pp->o;
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
    if (o->pane && !o->eval)
        return say(BTDF_EINVAL, msg, msglen, "a polar plot of a pane needs its values (eval): "
                   "the system's BSDF is the caller's");
    pp->ncurves = ncurves;
    /* the reflection above the surface (reflection alone: the transmission is not drawn) */
    pp->refl = o->part == BTDF_PART_REFLECTION || o->part == BTDF_PART_BOTH;
    pp->trans = o->part != BTDF_PART_REFLECTION;
    pp->W = o->width ? o->width : 960;
    pp->H = o->height ? o->height : 720;
    if (pp->W < POLAR_MIN_W || pp->H < POLAR_MIN_H)
        return say(BTDF_EINVAL, msg, msglen,
                   "a polar plot of %d x %d pixels would not be readable: at least %d x %d",
                   pp->W, pp->H, POLAR_MIN_W, POLAR_MIN_H);
    pp->smith = o->materials[0].model == BTDF_MODEL_SMITH;
    pp->full = o->materials[0].model == BTDF_MODEL_FULL;
    /* the model objects of the materials: tallied here for model full, once per
       material; nothing is made for the others */
    for (size_t m = 0; m < o->nmaterials && !o->eval; m++)
        if (o->materials[m].model == BTDF_MODEL_FULL) {
            btdf_status st = btdf_model_ctx_new(&o->materials[m], NULL, &pp->mx[m], msg, msglen);
            if (st != BTDF_OK)
                return st;
        }
    return BTDF_OK;
}

/* The curves, their peaks below and above the surface, their colours and the scales. */
static void polar_peaks(polar_plot *pp)
{
    const btdf_preview_opts *o = pp->o;
    curve *cs = pp->cs;
    size_t i = 0, ncurves = pp->ncurves;
    pp->vmax = 0.0;
    pp->vmax_r = 0.0;
    for (size_t m = 0; m < o->nmaterials; m++)
        for (int ch = 0; ch < o->materials[m].channels; ch++)
            for (size_t k = 0; k < o->nti; k++, i++) {
                curve *cu = &cs[i];
                cu->p = &o->materials[m];
                cu->o = o;
                cu->full = pp->mx[m] && btdf_model_ctx_params(pp->mx[m])->model == BTDF_MODEL_FULL
                               ? btdf_model_ctx_full(pp->mx[m], ch)
                               : NULL;
                cu->ch = ch;
                cu->ti = o->ti_deg[k] / PV_DEG;
                cu->peak = 0.0;
                cu->peak_to = M_PI;
                /* Forward first: at to = 180 degrees both sides meet, and that peak is
                   not on the backward side. */
                for (int side = 1; side >= -1 && pp->trans; side -= 2)
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
                for (int side = 1; side >= -1 && pp->refl; side -= 2)
                    for (int j = 0; j <= POLAR_STEPS; j++) {
                        double tr = (M_PI / 2) * j / POLAR_STEPS;
                        double v = polar_value_r(cu, tr, side);
                        if (v > cu->peak_r) {
                            cu->peak_r = v;
                            cu->peak_tr = side > 0 ? tr : -tr;
                        }
                    }
                pp->vmax = cu->peak > pp->vmax ? cu->peak : pp->vmax;
                pp->vmax_r = cu->peak_r > pp->vmax_r ? cu->peak_r : pp->vmax_r;
            }
    /* Peaks more than 3 times apart would flatten the small lobes: then every curve is
       scaled to its own peak, and the legend gives the peaks. The reflection (its peak
       is 4e-3 of the transmission's for n = 1.5, s = 3, ti = 30) has its own scale. */
    double pmin = pp->vmax, pmin_r = pp->vmax_r;
    for (i = 0; i < ncurves; i++) {
        pmin = cs[i].peak < pmin ? cs[i].peak : pmin;
        pmin_r = cs[i].peak_r < pmin_r ? cs[i].peak_r : pmin_r;
    }
    pp->own = pp->vmax > 0.0 && !(pmin * 3.0 >= pp->vmax);
    pp->own_r = pp->vmax_r > 0.0 && !(pmin_r * 3.0 >= pp->vmax_r);
    /* Colours: one per curve; when every material is R,G,B, the channel's own hue, darker
       for the second (material, ti) pair (8 curves allow at most two such pairs). */
    int all_rgb = 1;
    for (size_t q = 0; q < o->nmaterials; q++)
        all_rgb &= o->materials[q].channels == 3;
    for (i = 0; i < ncurves; i++) {
        pp->colour[i] = palette[i];
        if (all_rgb) {
            static const plot_rgb hue[3] = {{215, 35, 35}, {25, 150, 55}, {30, 80, 215}};
            size_t pair = i / (3 * o->nti) * o->nti + i % o->nti; /* (material, ti) */
            double f = pair == 0 ? 1.0 : 0.55;
            pp->colour[i] = (plot_rgb){(unsigned char)lround(hue[cs[i].ch].r * f),
                                       (unsigned char)lround(hue[cs[i].ch].g * f),
                                       (unsigned char)lround(hue[cs[i].ch].b * f)};
        }
    }
    pp->step = plot_ticks(pp->own ? 1.0 : pp->vmax, 4, &pp->nt);
    pp->rmax = pp->step * pp->nt;
    pp->nt_r = 1;
    pp->step_r = pp->refl ? plot_ticks(pp->own_r ? 1.0 : pp->vmax_r, 4, &pp->nt_r) : 1.0;
    pp->rmax_r = pp->step_r * pp->nt_r;
}

/* The title (drawn), the legend's texts and the footer (measured; drawn last). */
static void polar_texts(polar_plot *pp, plot_canvas *c)
{
    const btdf_preview_opts *o = pp->o;
    int W = pp->W, trans = pp->trans, refl = pp->refl;
    double fs = pp->fs, fsS = pp->fsS, m = pp->m;
    const char *title =
        o->title ? o->title
        : o->pane ? (!trans ? PLOT_RHO "r |cos " PLOT_THETA "r| of a pane in air, in the plane "
                              "of incidence"
                     : refl ? PLOT_RHO " |cos " PLOT_THETA "o| below, " PLOT_RHO "r |cos "
                              PLOT_THETA "r| above: a pane in air, in the plane of incidence"
                            : PLOT_RHO " |cos " PLOT_THETA "o| of a pane in air, in the plane "
                              "of incidence")
        : pp->full ? (!trans ? PLOT_RHO "r |cos " PLOT_THETA "r| in the plane of incidence: the "
                               "Smith facets with their multiple scattering (model full)"
                      : refl ? PLOT_RHO " |cos " PLOT_THETA "o| below, " PLOT_RHO "r |cos "
                               PLOT_THETA "r| above: the Smith facets with their multiple "
                               "scattering (model full)"
                             : PLOT_RHO " |cos " PLOT_THETA "o| in the plane of incidence: the "
                               "Smith facets with their multiple scattering (model full)")
        : pp->smith ? (!trans ? PLOT_RHO "r |cos " PLOT_THETA "r| in the plane of incidence: "
                                "the same facets with the height-correlated Smith term"
                       : refl ? PLOT_RHO " |cos " PLOT_THETA "o| below, " PLOT_RHO "r |cos "
                                PLOT_THETA "r| above: the facets of Eq. 25 with the "
                                "height-correlated Smith term"
                              : PLOT_RHO " |cos " PLOT_THETA "o| in the plane of incidence: "
                                "the facets of Eq. 25 with the height-correlated Smith term")
        : !trans ? PLOT_RHO "r |cos " PLOT_THETA "r| in the plane of incidence: the reflection "
                   "of the facets of Xu & Sun 2008, Eq. 25"
        : refl   ? PLOT_RHO " |cos " PLOT_THETA "o| below the surface (Xu & Sun 2008, Eq. 25), "
                   PLOT_RHO "r |cos " PLOT_THETA "r| of the same facets above it"
                 : PLOT_RHO " |cos " PLOT_THETA "o| in the plane of incidence (Xu & Sun 2008, "
                   "Eq. 25)";
    double th = pv_para(c, m, m, title, pv_title_size(c, title, fs, W - 2 * m), W - 2 * m,
                        pv_ink, 1);
    pp->top0 = m + th + 0.5 * m;

    /* Legend texts: one line per curve, or two when one does not fit. */
    pp->lx = W / 2.0 + 0.05 * W;
    pp->sw = 2.2 * fsS;
    pp->textx = pp->lx + pp->sw + 0.5 * fsS;
    pp->lw_avail = W - m - pp->textx;
    double lw_one = 0.0;
    for (size_t i = 0; i < pp->ncurves; i++) {
        const curve *cu = &pp->cs[i];
        char *lab = pp->lab[i], *peak = pp->peak[i];
        const char *chn = channel_letter(cu->p->channels, cu->ch);
        snprintf(lab, sizeof pp->lab[i],
                 "n = %.4g%s%s%s  s = %.4g  " PLOT_THETA "i = %.4g" PLOT_DEG,
                 cu->p->ior[cu->ch], *chn ? " (" : "", chn, *chn ? ")" : "", cu->p->smoothness,
                 cu->ti * PV_DEG);
        if (!trans)
            snprintf(peak, sizeof pp->peak[i], "peak %.3g at %.1f" PLOT_DEG "%s", cu->peak_r,
                     fabs(cu->peak_tr) * PV_DEG, cu->peak_tr < 0 ? " back" : "");
        else if (refl)
            snprintf(peak, sizeof pp->peak[i], "peak %.3g at %.1f" PLOT_DEG "%s, r %.3g at %.1f"
                     PLOT_DEG "%s", cu->peak, fabs(cu->peak_to) * PV_DEG,
                     cu->peak_to < 0 ? " back" : "", cu->peak_r, fabs(cu->peak_tr) * PV_DEG,
                     cu->peak_tr < 0 ? " back" : "");
        else
            snprintf(peak, sizeof pp->peak[i], "peak %.3g at %.1f" PLOT_DEG "%s", cu->peak,
                     fabs(cu->peak_to) * PV_DEG, cu->peak_to < 0 ? " back" : "");
        double w = plot_text_width(c, lab, fsS) + plot_text_width(c, "   ", fsS) +
                   plot_text_width(c, peak, fsS);
        lw_one = fmax(lw_one, w);
    }
    pp->two = lw_one > pp->lw_avail;
    pp->entry = (pp->two ? 2.0 : 1.0) * pp->lineS + 0.25 * pp->lineS;
    pp->legend_h = pp->ncurves * pp->entry;

    /* Footer paragraph. */
    char *foot = pp->foot;
    size_t footlen = sizeof pp->foot;
    int same_k0 = 1;
    for (size_t k = 1; k < o->nmaterials; k++)
        same_k0 &= o->materials[k].k0 == o->materials[0].k0;
    char k0s[40] = "";
    if (pp->smith)
        snprintf(k0s, sizeof k0s, "; model smith");
    else if (pp->full)
        snprintf(k0s, sizeof k0s, "; model full");
    else if (same_k0)
        snprintf(k0s, sizeof k0s, "; k0 = %.3g", o->materials[0].k0);
    if (o->pane) /* air on both sides: what leaves the pane is parallel to what came in */
        snprintf(foot, footlen,
                 "radius: " PLOT_RHO " |cos " PLOT_THETA "o| (1/sr), linear%s; dashed: the "
                 "straight-through direction (air on both sides)%s; " PLOT_RHO ": the spread "
                 "part of the pane's system BSDF without cosine factor, delta parts not drawn; "
                 PLOT_THETA "o from the normal of the lit face; btdftab " BTDF_VERSION_STRING,
                 pp->own ? ", each curve divided by its own peak (peaks in the legend)" : "", k0s);
    else
        snprintf(foot, footlen,
                 "radius: " PLOT_RHO " |cos " PLOT_THETA "o| (1/sr), linear%s; dashed: Snell "
                 "direction through the mean surface, per material%s; " PLOT_RHO ": the BTDF "
                 "without cosine factor; " PLOT_THETA "o from the upper normal; btdftab "
                 BTDF_VERSION_STRING,
                 pp->own ? ", each curve divided by its own peak (peaks in the legend)" : "", k0s);
    if (refl) { /* the upper half */
        size_t fl = strlen(foot);
        snprintf(foot + fl, footlen - fl,
                 "; above the surface: " PLOT_RHO "r |cos " PLOT_THETA "r|, the reflection of %s "
                 "(1/sr), on its own linear scale%s (ticks above the surface line%s), "
                 PLOT_THETA "r from the upper normal, dashed: the mirror direction",
                 o->pane ? "the pane" : "the same facets",
                 pp->own_r ? ", each curve divided by its own peak" : "",
                 trans ? "; the transmission's below it" : "");
    }
    pp->foot_h = pv_para(c, m, 0, foot, fsS, W - 2 * m, pv_grey, 0);
}

/* Geometry: upper band (legend, arrows, tick labels), lower half circle, labels. Fails
   when the picture is too small for the plot beside its texts, naming the height that
   would do. */
static int polar_layout(polar_plot *pp, plot_canvas *c, char *msg, size_t msglen)
{
    int W = pp->W, H = pp->H, refl = pp->refl;
    double m = pp->m, fsS = pp->fsS, lineS = pp->lineS;
    double labw = plot_text_width(c, "150" PLOT_DEG, fsS) + 0.4 * fsS;
    double band0 = pp->legend_h + 1.6 * lineS, band = band0;
    double Rh = fmin((W / 2.0 - m - labw) / 0.87, W / 2.0 - m);
    double fixed = m + pp->foot_h + 0.6 * m + 1.3 * lineS + pp->top0; /* all but band, R */
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
        pp->H_needed = Hn;
        return say(BTDF_EINVAL, msg, msglen,
                   "%d x %d pixels leave a plot radius of %.0f pixels beside the legend of %zu "
                   "curves: at least %d pixels high at this width",
                   W, H, R, pp->ncurves, Hn);
    }
    pp->R = R;
    pp->band = band;
    pp->cx = W / 2.0;
    pp->cy = pp->top0 + band;
    return BTDF_OK;
}

/* Lower medium, grid circles at the round tick values, spokes every 15 degrees; the
   upper half's when the reflection is drawn; the surface line; the radial scales. */
static void polar_grid(const polar_plot *pp, plot_canvas *c)
{
    int W = pp->W, refl = pp->refl, nt = pp->nt, nt_r = pp->nt_r;
    double cx = pp->cx, cy = pp->cy, R = pp->R, fsS = pp->fsS, lineS = pp->lineS;
    plot_rect(c, 0, cy, W, cy + R + 1, (plot_rgb){246, 248, 252});
    for (int k = 1; k <= nt; k++) {
        double r = R * k / nt;
        cairo_new_path(c->cr);
        cairo_arc(c->cr, cx, cy, r, 0.0, M_PI);
        cairo_set_source_rgb(c->cr, pv_light.r / 255.0, pv_light.g / 255.0, pv_light.b / 255.0);
        cairo_set_line_width(c->cr, 1.0);
        cairo_stroke(c->cr);
    }
    for (int a = 15; a < 180; a += 15) {
        double x = cx + R * cos(a / PV_DEG), y = cy + R * sin(a / PV_DEG);
        plot_line(c, cx, cy, x, y, 1.0, 0, pv_light);
    }
    for (int a = 30; a < 180; a += 30) {
        if (a == 90)
            continue;
        char t[16];
        snprintf(t, sizeof t, "%d" PLOT_DEG, a < 90 ? 90 + a : 270 - a);
        plot_text(c, cx + (R + 0.3 * fsS) * cos(a / PV_DEG),
                  cy + (R + 0.3 * fsS) * sin(a / PV_DEG), a < 90 ? 0.0 : 1.0, 0.3, t, fsS,
                  pv_grey);
    }
    plot_text(c, cx, cy + R + 0.2 * lineS, 0.5, 0.0, PLOT_THETA "o = 180" PLOT_DEG, fsS, pv_grey);
    if (refl) { /* the upper half: the reflection's circles, spokes and angles */
        for (int k = 1; k <= nt_r; k++) {
            cairo_new_path(c->cr);
            cairo_arc(c->cr, cx, cy, R * k / nt_r, M_PI, 2.0 * M_PI);
            cairo_set_source_rgb(c->cr, pv_light.r / 255.0, pv_light.g / 255.0,
                                 pv_light.b / 255.0);
            cairo_set_line_width(c->cr, 1.0);
            cairo_stroke(c->cr);
        }
        for (int a = 15; a < 180; a += 15)
            plot_line(c, cx, cy, cx + R * cos(a / PV_DEG), cy - R * sin(a / PV_DEG), 1.0, 0,
                      pv_light);
        for (int a = 30; a < 180; a += 30) {
            if (a == 90)
                continue;
            char t[16];
            snprintf(t, sizeof t, "%d" PLOT_DEG, a < 90 ? 90 - a : a - 90);
            double tx = cx + (R + 0.3 * fsS) * cos(a / PV_DEG);
            double ty = cy - (R + 0.3 * fsS) * sin(a / PV_DEG);
            plot_box b = plot_text_box(c, tx, ty, a < 90 ? 0.0 : 1.0, 0.7, t, fsS);
            if (!plot_text_collides(c, b, 1.0))
                plot_text(c, tx, ty, a < 90 ? 0.0 : 1.0, 0.7, t, fsS, pv_grey);
        }
        plot_box b = plot_text_box(c, cx, cy - R - 0.2 * lineS, 0.5, 1.0,
                                   PLOT_THETA "r = 0" PLOT_DEG, fsS);
        if (!plot_text_collides(c, b, 1.0))
            plot_text(c, cx, cy - R - 0.2 * lineS, 0.5, 1.0, PLOT_THETA "r = 0" PLOT_DEG, fsS,
                      pv_grey);
    }
    plot_line(c, 0, cy, W, cy, 2.0, 0, pv_ink);

    /* Radial scale above the surface, right of the centre; with the reflection, its
       scale there and the transmission's below the line (their labels: polar_ticks). */
    for (int half = 0; half <= refl; half++) {
        int below = half == 0 && refl; /* the transmission's ticks, under the line */
        int n_h = half ? nt_r : nt;
        double vm_h = half ? pp->vmax_r : (pp->trans ? pp->vmax : 0.0);
        for (int k = 1; k <= n_h && (vm_h > 0.0); k++) {
            double x = cx + R * k / n_h;
            plot_line(c, x, below ? cy : cy - 0.25 * fsS, x, below ? cy + 0.25 * fsS : cy, 1.2,
                      0, pv_ink);
        }
    }
}

/* Whether box b (padded by pad) holds a point of a drawn lobe. */
static int lobe_hits(const polar_plot *pp, plot_box b, double pad)
{
    for (size_t k = 0; k < pp->npts; k++) {
        double x = pp->pts[2 * k], y = pp->pts[2 * k + 1];
        if (x > b.x0 - pad && x < b.x1 + pad && y > b.y0 - pad && y < b.y1 + pad)
            return 1;
    }
    return 0;
}

/* The radial ticks' labels, drawn after the lobes so that they go where no curve is:
   right of the centre as the ticks, or else mirrored left of it (the same radius, with
   its own tick mark), or not at all when both places hold a curve or a text. */
static void polar_ticks(const polar_plot *pp, plot_canvas *c)
{
    double cx = pp->cx, cy = pp->cy, R = pp->R, fsS = pp->fsS, W = pp->W, m = pp->m;
    char tl[32];
    for (int half = 0; half <= pp->refl; half++) {
        int below = half == 0 && pp->refl; /* the transmission's ticks, under the line */
        int n_h = half ? pp->nt_r : pp->nt;
        double st_h = half ? pp->step_r : pp->step;
        double vm_h = half ? pp->vmax_r : (pp->trans ? pp->vmax : 0.0);
        double yl = below ? cy + 0.3 * fsS : cy - 0.3 * fsS, ay = below ? 0.0 : 1.0;
        for (int k = 1; k <= n_h && (vm_h > 0.0); k++) {
            plot_tick_label(tl, sizeof tl, st_h * k, st_h);
            double tw = plot_text_width(c, tl, fsS);
            for (int side = 1; side >= -1; side -= 2) {
                double x = cx + side * R * k / n_h;
                double ax = side > 0 ? (x + tw / 2 > W - m ? 1.0 : 0.5)
                                     : (x - tw / 2 < m ? 0.0 : 0.5);
                plot_box b = plot_text_box(c, x, yl, ax, ay, tl, fsS);
                if (plot_text_collides(c, b, 0.5 * fsS) || lobe_hits(pp, b, 0.15 * fsS))
                    continue;
                if (side < 0)
                    plot_line(c, x, below ? cy : cy - 0.25 * fsS, x,
                              below ? cy + 0.25 * fsS : cy, 1.2, 0, pv_ink);
                plot_text(c, x, yl, ax, ay, tl, fsS, pv_ink);
                break;
            }
        }
    }
}

/* Snell directions: one dashed line per distinct (n, ti), in the curve's colour, or
   dark grey when several curves share it; with the reflection, the mirror directions.
   A pane (o->pane) has air on both sides: its guide is the straight-through direction,
   one per distinct ti, as if n were 1. */
static void polar_snell(const polar_plot *pp, plot_canvas *c)
{
    const curve *cs = pp->cs;
    size_t ncurves = pp->ncurves;
    double cx = pp->cx, cy = pp->cy, R = pp->R;
    for (size_t i = 0; i < ncurves; i++) {
        const curve *cu = &cs[i];
        int seen = 0, shared = 0;
        for (size_t j = 0; j < ncurves; j++) {
            int same = (pp->o->pane || cs[j].p->ior[cs[j].ch] == cu->p->ior[cu->ch]) &&
                       cs[j].ti == cu->ti;
            seen |= same && j < i;
            shared |= same && j != i;
        }
        /* n > 0: btdf_params_check passed; a pane: air to air, sin to = sin ti */
        double sn = pp->o->pane ? sin(cu->ti) : sin(cu->ti) / cu->p->ior[cu->ch];
        if (pp->refl) { /* the mirror direction: tr = ti on the specular side */
            int seen_r = 0, shared_r = 0;
            for (size_t j = 0; j < ncurves; j++) {
                seen_r |= cs[j].ti == cu->ti && j < i;
                shared_r |= cs[j].ti == cu->ti && j != i;
            }
            if (!seen_r)
                plot_line(c, cx, cy, cx + R * sin(cu->ti), cy - R * cos(cu->ti), 1.4, 5.0,
                          shared_r ? pv_grey : pp->colour[i]);
        }
        if (seen || sn > 1.0 || !pp->trans) /* past the critical angle: no refracted ray */
            continue;
        double tt = asin(sn);
        plot_line(c, cx, cy, cx + R * sin(tt), cy + R * cos(tt), 1.4, 5.0,
                  shared ? pv_grey : pp->colour[i]);
    }
}

/* The lobes: the transmission below the surface, then the reflection above it, each
   on its own scale. */
static int polar_lobes(polar_plot *pp, plot_canvas *c, char *msg, size_t msglen)
{
    double cx = pp->cx, cy = pp->cy, R = pp->R;
    /* every curve's points, both halves, kept for the tick labels (polar_ticks) */
    pp->pts = malloc(sizeof *pp->pts * 2 * (2 * (POLAR_STEPS + 1)) * 2 * pp->ncurves);
    pp->npts = 0;
    if (!pp->pts)
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for the curves");
    for (size_t i = 0; i < pp->ncurves; i++) {
        const curve *cu = &pp->cs[i];
        for (int half = pp->trans ? 0 : 1; half <= pp->refl; half++) {
            double pk = half ? cu->peak_r : cu->peak, rm = half ? pp->rmax_r : pp->rmax;
            int own_h = half ? pp->own_r : pp->own;
            /* rm > 0 (plot_ticks); a curve with peak 0 has nothing to draw */
            double scale = own_h ? (pk > 0.0 ? R / pk : 0.0) : R / rm;
            if (!(scale > 0.0))
                continue;
            size_t np = 0;
            double *xy = pp->pts + 2 * pp->npts;
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
            plot_polyline(c, xy, np, 2.2, pp->colour[i]);
            pp->npts += np;
        }
    }
    return BTDF_OK;
}

/* One arrow per distinct ti: in the curve's colour, or ink when curves share it. */
static void polar_arrows(const polar_plot *pp, plot_canvas *c)
{
    const curve *cs = pp->cs;
    double cx = pp->cx, cy = pp->cy, L = pp->L;
    for (size_t i = 0; i < pp->ncurves; i++) {
        const curve *cu = &cs[i];
        int seen = 0, shared = 0;
        for (size_t j = 0; j < pp->ncurves; j++) {
            seen |= cs[j].ti == cu->ti && j < i;
            shared |= cs[j].ti == cu->ti && j != i;
        }
        if (seen)
            continue;
        plot_rgb col = shared ? pv_ink : pp->colour[i];
        double ex = cx - L * sin(cu->ti), ey = cy - L * cos(cu->ti);
        double ux = sin(cu->ti), uy = cos(cu->ti); /* unit, towards the surface */
        double hl = fmin(14.0, 0.3 * L), hw = 0.4 * hl;
        double hx = cx - hl * ux, hy = cy - hl * uy;
        plot_line(c, ex, ey, hx, hy, 2.0, 0, col);
        double tri[6] = {cx, cy, hx - hw * uy, hy + hw * ux, hx + hw * uy, hy - hw * ux};
        plot_triangle(c, tri, col);
    }
}

/* Side labels where no arrow passes, the legend, the empty-half notes and the footer. */
static void polar_labels(const polar_plot *pp, plot_canvas *c)
{
    int W = pp->W, H = pp->H;
    double cx = pp->cx, cy = pp->cy, R = pp->R, L = pp->L, m = pp->m;
    double fs = pp->fs, fsS = pp->fsS, lineS = pp->lineS;
    const char *up = pp->o->pane ? "air: the light comes from here"
                                 : "upper medium: the light comes from here";
    const char *lo = pp->o->pane ? "air beyond the pane" : "lower medium";
    plot_box ub = plot_text_box(c, m, cy - 0.3 * fsS, 0, 1, up, fsS);
    int hit = 0;
    for (size_t i = 0; i < pp->ncurves; i++)
        hit |= segment_hits(ub, cx, cy, cx - L * sin(pp->cs[i].ti), cy - L * cos(pp->cs[i].ti));
    if (!hit && !plot_text_collides(c, ub, 2.0))
        plot_text(c, m, cy - 0.3 * fsS, 0, 1, up, fsS, pv_grey);
    plot_text(c, m, cy + 0.3 * fsS, 0, 0, lo, fsS, pv_grey);
    const char *bw = "backward (" PLOT_PHI " = 0" PLOT_DEG ")",
               *fw = "forward (" PLOT_PHI " = 180" PLOT_DEG ")";
    plot_box bb = plot_text_box(c, m, cy + R, 0, 1, bw, fsS);
    if (!plot_text_collides(c, bb, 2.0))
        plot_text(c, m, cy + R, 0, 1, bw, fsS, pv_grey);
    plot_box fb = plot_text_box(c, W - m, cy + R, 1, 1, fw, fsS);
    if (!plot_text_collides(c, fb, 2.0))
        plot_text(c, W - m, cy + R, 1, 1, fw, fsS, pv_grey);

    /* Legend: upper right, above the tick labels, clear of the arrows (x > cx). */
    for (size_t i = 0; i < pp->ncurves; i++) {
        double y = pp->top0 + i * pp->entry;
        plot_line(c, pp->lx, y + lineS / 2, pp->lx + pp->sw, y + lineS / 2, 3.0, 0,
                  pp->colour[i]);
        double fsz = plot_text_fit(c, pp->lab[i], fsS, PV_MIN_TEXT, pp->lw_avail);
        plot_box b = plot_text(c, pp->textx, y, 0, 0, pp->lab[i], fsz, pv_ink);
        if (pp->two)
            plot_text(c, pp->textx, y + lineS, 0, 0, pp->peak[i], fsz, pv_grey);
        else
            plot_text(c, b.x1 + plot_text_width(c, "   ", fsS), y, 0, 0, pp->peak[i], fsS,
                      pv_grey);
    }
    if (pp->trans && !(pp->vmax > 0.0))
        plot_text(c, cx, cy + R / 2, 0.5, 0.5, "no transmission", fs, pv_ink);
    if (pp->refl && !(pp->vmax_r > 0.0))
        plot_text(c, cx, cy - R / 2, 0.5, 0.5, "no reflection", fs, pv_ink);
    pv_para(c, m, H - m - pp->foot_h, pp->foot, fsS, W - 2 * m, pv_grey, 1);
}

int pv_draw_polar(const btdf_preview_opts *o, plot_canvas *c, char *msg, size_t msglen)
{
    polar_plot *pp = calloc(1, sizeof *pp); /* some 4 KiB of texts: not on the stack */
    if (!pp)
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for a polar plot");
    pp->o = o;
    int st = polar_check(pp, msg, msglen);
    if (st != BTDF_OK)
        goto done;
    polar_peaks(pp);
    /* twice at most: a default height too small for the legend grows to what the
       layout asks (a height given is kept, and its refusal names the one needed) */
    for (int pass = 0; pass < 2; pass++) {
        if (plot_canvas_init(c, pp->W, pp->H, pv_white) != 0) {
            st = say(BTDF_ENOMEM, msg, msglen, "out of memory for a %d x %d picture", pp->W,
                     pp->H);
            goto done;
        }
        pp->fs = pv_clampd(fmin(pp->W, pp->H * 4.0 / 3.0) / 62.0, 10.0, 16.0);
        pp->fsS = fmax(PV_MIN_TEXT, 0.88 * pp->fs);
        pp->m = 0.8 * pp->fs;
        pp->lineS = plot_text_height(c, pp->fsS);
        polar_texts(pp, c);
        st = polar_layout(pp, c, msg, msglen);
        if (st == BTDF_OK || o->height || pp->H_needed <= pp->H)
            break;
        plot_canvas_free(c);
        pp->H = pp->H_needed;
    }
    if (st != BTDF_OK)
        goto fail;
    polar_grid(pp, c);
    polar_snell(pp, c);
    pp->L = fmin(pp->band - 0.3 * pp->lineS, 0.45 * pp->R);
    st = polar_lobes(pp, c, msg, msglen);
    if (st != BTDF_OK)
        goto fail;
    polar_ticks(pp, c);
    polar_arrows(pp, c);
    polar_labels(pp, c);
    goto done;
fail:
    plot_canvas_free(c);
done:
    for (size_t m = 0; m < BTDF_PREVIEW_MAX_CURVES; m++)
        btdf_model_ctx_free(pp->mx[m]);
    free(pp->pts);
    free(pp);
    return st;
}
