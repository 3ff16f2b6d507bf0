/* SPDX-License-Identifier: MIT */
/* chart.c: BTDF_PREVIEW_CHART, panels of curves from plain arrays (btdf_preview.h):
   markers with error bars or lines, one shared x axis (linear or log10), a y scale per
   panel from 0, a legend per panel. What the simulator's pictures are drawn with. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "preview/style.h"

#define CHART_PANEL_W 480 /* default pixels per panel */
#define CHART_PANEL_H 360
#define CHART_MIN_W 320   /* smallest readable panel */
#define CHART_MIN_H 240
#define CHART_MAX_POINTS 100000

static const plot_rgb palette[BTDF_CHART_MAX_SERIES] = {
    {20, 90, 200}, {200, 30, 40}, {30, 150, 60}, {230, 110, 10},
    {130, 80, 190}, {120, 80, 40}, {220, 80, 170}, {90, 90, 90},
};

/* Checks the chart; 0, or the status after a message naming what is wrong. */
static int check(const btdf_chart *ch, char *msg, size_t msglen)
{
    if (!ch || !ch->panels || ch->npanels == 0 || ch->npanels > BTDF_CHART_MAX_PANELS)
        return say(BTDF_EINVAL, msg, msglen, "chart: 1 to %d panels needed",
                   BTDF_CHART_MAX_PANELS);
    if (ch->columns < 0 || ch->columns > BTDF_CHART_MAX_PANELS)
        return say(BTDF_EINVAL, msg, msglen, "chart: %d columns: 0 to %d", ch->columns,
                   BTDF_CHART_MAX_PANELS);
    if (!isfinite(ch->xmin) || !isfinite(ch->xmax) || ch->xmin > ch->xmax ||
        (ch->logx && ch->xmax > 0 && !(ch->xmin > 0)))
        return say(BTDF_EINVAL, msg, msglen, "chart: x range %g to %g", ch->xmin, ch->xmax);
    for (size_t p = 0; p < ch->npanels; p++) {
        const btdf_chart_panel *pn = &ch->panels[p];
        if (pn->nseries > BTDF_CHART_MAX_SERIES || (pn->nseries && !pn->series))
            return say(BTDF_EINVAL, msg, msglen, "chart panel %zu: at most %d series", p + 1,
                       BTDF_CHART_MAX_SERIES);
        for (size_t k = 0; k < pn->nseries; k++) {
            const btdf_chart_series *se = &pn->series[k];
            if (se->n > CHART_MAX_POINTS || (se->n && (!se->x || !se->y)))
                return say(BTDF_EINVAL, msg, msglen,
                           "chart panel %zu, series %zu: 0 to %d points with x and y", p + 1,
                           k + 1, CHART_MAX_POINTS);
            for (size_t i = 0; i < se->n; i++) {
                double e = se->yerr ? se->yerr[i] : 0.0;
                if (!isfinite(se->x[i]) || !isfinite(se->y[i]) || !isfinite(e) || e < 0.0 ||
                    (ch->logx && !(se->x[i] > 0.0)))
                    return say(BTDF_EINVAL, msg, msglen,
                               "chart panel %zu, series %zu, point %zu: x %g, y %g, error %g "
                               "(finite, error >= 0%s)",
                               p + 1, k + 1, i + 1, se->x[i], se->y[i], e,
                               ch->logx ? ", x > 0 on a log axis" : "");
            }
        }
    }
    return 0;
}

/* The x range: given, or the data's (a single value widened so the axis has length). */
static void x_range(const btdf_chart *ch, double *lo, double *hi)
{
    if (ch->xmax > ch->xmin) {
        *lo = ch->xmin;
        *hi = ch->xmax;
        return;
    }
    *lo = DBL_MAX;
    *hi = -DBL_MAX;
    for (size_t p = 0; p < ch->npanels; p++)
        for (size_t k = 0; k < ch->panels[p].nseries; k++) {
            const btdf_chart_series *se = &ch->panels[p].series[k];
            for (size_t i = 0; i < se->n; i++) {
                *lo = se->x[i] < *lo ? se->x[i] : *lo;
                *hi = se->x[i] > *hi ? se->x[i] : *hi;
            }
        }
    if (*lo > *hi) { /* no points at all */
        *lo = ch->logx ? 1.0 : 0.0;
        *hi = ch->logx ? 10.0 : 1.0;
    }
    if (!(*hi > *lo)) { /* one x: a unit around it (a factor of 2 on a log axis) */
        *lo = ch->logx ? *lo / 2.0 : *lo - 0.5;
        *hi = ch->logx ? *hi * 2.0 : *hi + 0.5;
    }
}

typedef struct axis {
    double lo, hi; /* in axis units (log10 x on a log axis) */
    double x0, x1; /* pixels */
} axis;

static double map(const axis *a, double v)
{
    return a->x0 + (v - a->lo) / (a->hi - a->lo) * (a->x1 - a->x0); /* hi > lo (x_range) */
}

/* One panel in the cell [cx, cx + cw) x [cy, cy + chh). */
static void draw_panel(plot_canvas *c, const btdf_chart *ch, const btdf_chart_panel *pn,
                       double cx, double cy, double cw, double chh, double xlo, double xhi,
                       double fs)
{
    double th = plot_text_height(c, fs);
    double left = cx + 3.2 * fs + th + 8, right = cx + cw - 12;
    double top = cy + th * 1.6 + 6, bottom = cy + chh - 2.6 * th - 10;
    if (pn->title)
        plot_text(c, 0.5 * (left + right), cy + 4, 0.5, 0.0, pn->title,
                  plot_text_fit(c, pn->title, fs * 1.1, PV_MIN_TEXT, right - left), pv_ink);
    /* y scale: 0 to the largest y + error */
    double ymax = 0.0;
    for (size_t k = 0; k < pn->nseries; k++)
        for (size_t i = 0; i < pn->series[k].n; i++) {
            double v = pn->series[k].y[i] + (pn->series[k].yerr ? pn->series[k].yerr[i] : 0.0);
            ymax = v > ymax ? v : ymax;
        }
    int nt = 1;
    /* headroom for the legend (top right), about one line of its height each */
    size_t nlab = 0;
    for (size_t k = 0; k < pn->nseries; k++)
        nlab += pn->series[k].label != NULL;
    double step = plot_ticks(ymax * (1.0 + 0.08 * (double)nlab), 5, &nt);
    axis ay = {0.0, step * nt, bottom, top};
    int lg = ch->logx;
    axis ax = {lg ? log10(xlo) : xlo, lg ? log10(xhi) : xhi, left, right};
    plot_rect(c, left, top, right, bottom, pv_white);
    /* y grid and labels */
    for (int k = 0; k <= nt; k++) {
        double y = map(&ay, step * k);
        char tl[32];
        plot_tick_label(tl, sizeof tl, step * k, step);
        if (k > 0)
            plot_line(c, left, y, right, y, 1.0, 0.0, pv_light);
        plot_text(c, left - 4, y, 1.0, 0.5, tl, fs * 0.9, pv_grey);
    }
    /* x ticks: round steps on a linear axis, 1-2-5 on a log axis */
    if (lg) {
        for (int e = (int)floor(ax.lo) - 1; e <= (int)ceil(ax.hi); e++)
            for (int m = 0; m < 3; m++) {
                double v = (m == 0 ? 1.0 : m == 1 ? 2.0 : 5.0) * pow(10.0, e);
                double lv = log10(v);
                if (lv < ax.lo - 1e-9 || lv > ax.hi + 1e-9)
                    continue;
                double x = map(&ax, lv);
                char tl[32];
                snprintf(tl, sizeof tl, "%g", v);
                plot_line(c, x, bottom, x, bottom + 4, 1.0, 0.0, pv_grey);
                plot_text(c, x, bottom + 6, 0.5, 0.0, tl, fs * 0.9, pv_grey);
            }
    } else {
        int nx = 1;
        double xs = plot_ticks(xhi - xlo, 6, &nx); /* xhi > xlo: a positive span */
        for (double v = ceil(xlo / xs - 1e-9) * xs; v <= xhi + 1e-9 * xs; v += xs) {
            double x = map(&ax, v);
            char tl[32];
            plot_tick_label(tl, sizeof tl, fabs(v) < 1e-9 * xs ? 0.0 : v, xs);
            plot_line(c, x, bottom, x, bottom + 4, 1.0, 0.0, pv_grey);
            plot_text(c, x, bottom + 6, 0.5, 0.0, tl, fs * 0.9, pv_grey);
        }
    }
    if (ch->xlabel)
        plot_text(c, 0.5 * (left + right), bottom + 8 + th, 0.5, 0.0, ch->xlabel,
                  plot_text_fit(c, ch->xlabel, fs, PV_MIN_TEXT, right - left), pv_ink);
    if (ch->ylabel)
        plot_text_up(c, cx + 4 + 0.5 * th, 0.5 * (top + bottom), ch->ylabel, fs, pv_ink);
    /* the series, clipped to the axes' box by skipping what lies outside it */
    for (size_t k = 0; k < pn->nseries; k++) {
        const btdf_chart_series *se = &pn->series[k];
        plot_rgb col = palette[k];
        if (se->points) {
            for (size_t i = 0; i < se->n; i++) {
                double xv = lg ? log10(se->x[i]) : se->x[i];
                if (xv < ax.lo || xv > ax.hi)
                    continue;
                double x = map(&ax, xv), y = map(&ay, se->y[i]);
                if (se->yerr && se->yerr[i] > 0.0) {
                    double y0 = map(&ay, se->y[i] - se->yerr[i] > 0 ? se->y[i] - se->yerr[i] : 0);
                    double y1 = map(&ay, se->y[i] + se->yerr[i]);
                    plot_line(c, x, y0, x, y1, 1.2, 0.0, col);
                    plot_line(c, x - 2.5, y0, x + 2.5, y0, 1.0, 0.0, col);
                    plot_line(c, x - 2.5, y1, x + 2.5, y1, 1.0, 0.0, col);
                }
                plot_rect(c, x - 2.0, y - 2.0, x + 2.0, y + 2.0, col);
            }
        } else if (se->n > 1) {
            double xy[2 * 512];
            size_t m = 0;
            for (size_t i = 0; i < se->n; i++) {
                double xv = lg ? log10(se->x[i]) : se->x[i];
                int in = xv >= ax.lo && xv <= ax.hi;
                if (in) {
                    xy[2 * m] = map(&ax, xv);
                    xy[2 * m + 1] = map(&ay, se->y[i]);
                    m++;
                }
                if (m == 512 || (!in && m) || (i + 1 == se->n && m)) {
                    plot_polyline(c, xy, m, 1.6, col);
                    if (m == 512) { /* go on from the last point */
                        xy[0] = xy[2 * 511];
                        xy[1] = xy[2 * 511 + 1];
                        m = 1;
                    } else
                        m = 0;
                }
            }
        }
    }
    plot_frame(c, left, top, right, bottom, 1.0, pv_grey);
    /* the legend, top right inside the axes, one line per labelled series */
    double ly = top + 4, lw = 0.0;
    for (size_t k = 0; k < pn->nseries; k++)
        if (pn->series[k].label) {
            double w = plot_text_width(c, pn->series[k].label, fs * 0.9);
            lw = w > lw ? w : lw;
        }
    lw = lw < right - left - 40 ? lw : right - left - 40;
    for (size_t k = 0; k < pn->nseries; k++) {
        const btdf_chart_series *se = &pn->series[k];
        if (!se->label)
            continue;
        double x1 = right - 6, x0 = x1 - lw, my = ly + 0.5 * th;
        plot_rect(c, x0 - 26, ly - 1, x1 + 2, ly + th + 1, pv_white);
        if (se->points)
            plot_rect(c, x0 - 16, my - 2, x0 - 12, my + 2, palette[k]);
        else
            plot_line(c, x0 - 22, my, x0 - 6, my, 1.6, 0.0, palette[k]);
        plot_text(c, x0, ly, 0.0, 0.0, se->label,
                  plot_text_fit(c, se->label, fs * 0.9, PV_MIN_TEXT, lw), pv_ink);
        ly += th + 2;
    }
}

int pv_draw_chart(const btdf_preview_opts *o, plot_canvas *c, char *msg, size_t msglen)
{
    const btdf_chart *ch = o->chart;
    int bad = check(ch, msg, msglen);
    if (bad)
        return bad;
    int cols = ch->columns ? ch->columns : ch->npanels > 1 ? 2 : 1;
    cols = (size_t)cols < ch->npanels ? cols : (int)ch->npanels;
    int rows = (int)((ch->npanels + (size_t)cols - 1) / (size_t)cols);
    double fs = 13.0, title_h = o->title ? 34.0 : 0.0;
    int w = o->width ? o->width : cols * CHART_PANEL_W;
    int h = o->height ? o->height : (int)(rows * CHART_PANEL_H + title_h);
    if (w < cols * CHART_MIN_W || h < rows * CHART_MIN_H + title_h)
        return say(BTDF_EINVAL, msg, msglen,
                   "chart of %d x %d panels: at least %d x %.0f pixels (asked %d x %d)", cols,
                   rows, cols * CHART_MIN_W, rows * CHART_MIN_H + title_h, w, h);
    if (plot_canvas_init(c, w, h, pv_white) != 0)
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for a %d x %d picture", w, h);
    if (o->title)
        plot_text(c, 0.5 * w, 8, 0.5, 0.0, o->title,
                  plot_text_fit(c, o->title, fs * 1.25, PV_MIN_TEXT, w - 20.0), pv_ink);
    double xlo, xhi;
    x_range(ch, &xlo, &xhi);
    double cw = (double)w / cols, chh = (h - title_h) / rows;
    for (size_t p = 0; p < ch->npanels; p++) {
        int r = (int)(p / (size_t)cols), q = (int)(p % (size_t)cols);
        draw_panel(c, ch, &ch->panels[p], q * cw, title_h + r * chh, cw, chh, xlo, xhi, fs);
    }
    return BTDF_OK;
}
