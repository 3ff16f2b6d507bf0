/* SPDX-License-Identifier: MIT */
/* montage.c: a table's slices side by side, one tile per theta_i, on one colour scale. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "model/kernel.h"
#include "preview/style.h"
#include "table/table.h"

static const plot_rgb below_range = {30, 30, 30};

#define DECADES 6.0
#define MONTAGE_MIN_W 480
#define MIN_TILE 16

/* One montage, filled in by the phases below: the slices shown and the value range,
   the layout measured on a scratch canvas, the tiles, then the axes and colour bar. */
typedef struct montage_plot {
    const btdf_preview_opts *o;
    const btdf_table *t;
    const btdf_params *p;
    size_t n, shown, idx[BTDF_PREVIEW_MAX_TILES]; /* slices, shown, which */
    double vmax, lo;                             /* the colour scale's ends */
    int recip, facet;
    int W, H;
    char title[300], sub[600], top_s[48], bot_s[48];
    const char *head;
    double fs, fsS, fsT, m, lineS, th, barw;
    double left, right, gap, labh, top, gh;
    int cols, rows, tile;
} montage_plot;

/* The checks, the slices shown (evenly spaced, first and last included) and the
   largest value of channel 0 over all slices. */
static int montage_scan(montage_plot *mp, char *msg, size_t msglen)
{
    const btdf_preview_opts *o = mp->o;
    const btdf_table *t = o->table;
    if (!t)
        return say(BTDF_EINVAL, msg, msglen, "a montage needs a table");
    size_t n = btdf_table_slice_count(t);
    if (n == 0)
        return say(BTDF_EINVAL, msg, msglen, "the table has no slices");
    mp->W = o->width ? o->width : 1000;
    if (mp->W < MONTAGE_MIN_W)
        return say(BTDF_EINVAL, msg, msglen,
                   "a montage %d pixels wide would not be readable: at least %d", mp->W,
                   MONTAGE_MIN_W);
    mp->t = t;
    mp->n = n;
    mp->p = btdf_table_get_params(t);
    btdf_table_kind kind = btdf_table_get_kind(t);
    mp->shown = n < BTDF_PREVIEW_MAX_TILES ? n : BTDF_PREVIEW_MAX_TILES;
    size_t shown = mp->shown;
    for (size_t k = 0; k < shown; k++) /* evenly spaced, first and last included */
        mp->idx[k] = shown > 1 ? (k * (n - 1) + (shown - 1) / 2) / (shown - 1) : 0;
    double vmax = 0.0;
    for (size_t k = 0; k < n; k++) {
        btdf_slice s;
        btdf_table_slice(t, k, &s);
        for (size_t q = 0; q < s.nrows * s.ncols; q++) {
            double v = s.values[q * (size_t)mp->p->channels];
            vmax = v > vmax ? v : vmax;
        }
    }
    mp->vmax = vmax;
    mp->lo = vmax * pow(10.0, -DECADES);
    mp->recip = kind == BTDF_TABLE_FACET_RECIPROCAL;
    mp->facet = kind != BTDF_TABLE_GRID;
    return BTDF_OK;
}

/* Measure on a scratch canvas first: the height depends on the wrapped texts. */
static int montage_layout(montage_plot *mp, char *msg, size_t msglen)
{
    const btdf_preview_opts *o = mp->o;
    const btdf_table *t = mp->t;
    const btdf_params *p = mp->p;
    int W = mp->W, recip = mp->recip;
    size_t shown = mp->shown;
    plot_canvas scratch;
    if (plot_canvas_init(&scratch, 8, 8, pv_white) != 0)
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for the montage");
    double fs = pv_clampd(W / 70.0, 10.0, 15.0), fsS = fmax(PV_MIN_TEXT, 0.88 * fs);
    double m = 0.8 * fs, lineS = plot_text_height(&scratch, fsS);
    char nbuf[64], *sub = mp->sub;
    size_t sublen = sizeof mp->sub;
    pv_format_n(nbuf, sizeof nbuf, p);
    snprintf(mp->title, sizeof mp->title,
             "%s table: %s  s = %.4g  k0 = %.3g;  %zu slices, %zu nodes",
             recip ? "facet-reciprocal" : (mp->facet ? "facet" : "grid"), nbuf, p->smoothness,
             p->k0, mp->n, btdf_table_node_count(t));
    int k = snprintf(sub, sublen,
                     "%s%s" PLOT_RHO " (1/sr) of channel %s on a log scale, %g decades; tiles "
                     "in the table's coordinates, row 0 on top%s",
                     o->title ? mp->title : "", o->title ? "; " : "",
                     p->channels == 3 ? "R" : "Y", DECADES,
                     shown < mp->n ? "; slices picked evenly by index, first and last included "
                                  "(their angles label them)" : "");
    if (recip && k > 0 && (size_t)k < sublen)
        /* The slices are the facet table of 1/n at ti' = pi - to (btdf.h): say so, and
           label each tile with the outgoing angle of the light leaving. */
        snprintf(sub + k, sublen - (size_t)k,
                 "; reciprocal: each tile is the facet table of index 1/n = %.4g at " PLOT_THETA
                 "i' = 180" PLOT_DEG " " PLOT_MINUS " " PLOT_THETA "o; " PLOT_RHO " = n" "\xc2\xb2"
                 " " PLOT_RHO "(1/n)",
                 1.0 / p->ior[0]);
    mp->head = o->title ? o->title : mp->title;
    mp->fsT = pv_title_size(&scratch, mp->head, fs, W - 2 * m);
    mp->th = pv_para(&scratch, m, m, mp->head, mp->fsT, W - 2 * m, pv_ink, 0);
    double sub_h = pv_para(&scratch, m, 0, sub, fsS, W - 2 * m, pv_grey, 0);
    /* Widths of the side columns: row labels at the left, the colour bar at the right. */
    char lab[64];
    double rlw = 0.0;
    for (size_t q = 0; q < shown; q++) {
        btdf_slice s;
        btdf_table_slice(t, mp->idx[q], &s);
        for (int e = 0; e < 2; e++) {
            snprintf(lab, sizeof lab, "%.4g", (e ? s.rows[s.nrows - 1] : s.rows[0]) * PV_DEG);
            rlw = fmax(rlw, plot_text_width(&scratch, lab, fsS));
        }
    }
    snprintf(mp->top_s, sizeof mp->top_s, "%.3g", mp->vmax);
    snprintf(mp->bot_s, sizeof mp->bot_s, "%.3g", mp->lo);
    double barw = fmax(12.0, fs);
    double blw = fmax(plot_text_width(&scratch, mp->top_s, fsS),
                      plot_text_width(&scratch, mp->bot_s, fsS));
    blw = fmax(blw, plot_text_width(&scratch, "10" "\xe2\x81\xbb" "\xc2\xb9" "\xc2\xb9", fsS));
    blw = fmax(blw, plot_text_width(&scratch, "< max/10" "\xe2\x81\xb6", fsS));
    plot_canvas_free(&scratch);

    double left = m + lineS + 0.5 * fsS + rlw + 0.5 * fsS;
    double right = 1.5 * fs + barw + 0.6 * fsS + blw + m;
    double gap = fmax(8.0, 0.7 * fs), labh = lineS + 2.0;
    double top = m + mp->th + 0.4 * m + sub_h + 0.5 * m;
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
    mp->H = H;
    mp->fs = fs;
    mp->fsS = fsS;
    mp->m = m;
    mp->lineS = lineS;
    mp->barw = barw;
    mp->left = left;
    mp->right = right;
    mp->gap = gap;
    mp->labh = labh;
    mp->top = top;
    mp->gh = gh;
    mp->cols = cols;
    mp->rows = rows;
    mp->tile = tile;
    return BTDF_OK;
}

/* The tiles, each at the table's own interpolation rule, with their labels; px holds
   tile x tile RGB. */
static void montage_tiles(const montage_plot *mp, plot_canvas *c, unsigned char *px)
{
    const btdf_table *t = mp->t;
    int tile = mp->tile, cols = mp->cols, recip = mp->recip;
    double fsS = mp->fsS, gap = mp->gap, lo = mp->lo;
    char lab[64];
    for (size_t q = 0; q < mp->shown; q++) {
        btdf_slice s;
        btdf_table_slice(t, mp->idx[q], &s);
        int gx = (int)(q % (size_t)cols), gy = (int)(q / (size_t)cols);
        double x0 = mp->left + gx * (tile + gap);
        double y0 = mp->top + gy * (tile + mp->labh + gap) + mp->labh;
        double la = recip ? 180.0 - s.ti * PV_DEG : s.ti * PV_DEG;
        snprintf(lab, sizeof lab, "%s = %.2f" PLOT_DEG, recip ? PLOT_THETA "o" : PLOT_THETA "i",
                 la);
        if (plot_text_width(c, lab, fsS) > tile + gap - 2) /* narrow tiles: the angle only */
            snprintf(lab, sizeof lab, "%.4g" PLOT_DEG, la);
        plot_text(c, x0, y0 - 1, 0, 1, lab,
                  plot_text_fit(c, lab, fsS, PV_MIN_TEXT * 0.9, tile + gap - 2), pv_ink);
        double r0 = s.rows[0], r1 = s.rows[s.nrows - 1];
        double c0 = s.cols[0], c1 = s.cols[s.ncols - 1];
        for (int y = 0; y < tile; y++)
            for (int x = 0; x < tile; x++) {
                double rq = r0 + (r1 - r0) * (y + 0.5) / tile;
                double cq = c0 + (c1 - c0) * (x + 0.5) / tile;
                double v = slice_interp(t, mp->idx[q], rq, cq, 0); /* the table's own rule */
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
        plot_frame(c, x0, y0, x0 + tile, y0 + tile, 1.0, pv_grey);
        if (gx == 0) {
            snprintf(lab, sizeof lab, "%.4g", r0 * PV_DEG);
            plot_text(c, x0 - 0.4 * fsS, y0, 1, 0, lab, fsS, pv_ink);
            snprintf(lab, sizeof lab, "%.4g", r1 * PV_DEG);
            plot_text(c, x0 - 0.4 * fsS, y0 + tile, 1, 1, lab, fsS, pv_ink);
        }
        if (gy == mp->rows - 1 || q + (size_t)cols >= mp->shown) {
            snprintf(lab, sizeof lab, "%.4g", c0 * PV_DEG);
            plot_box b = plot_text_box(c, x0, y0 + tile + 0.3 * fsS, 0, 0, lab, fsS);
            if (!plot_text_collides(c, b, 1.0))
                plot_text(c, x0, y0 + tile + 0.3 * fsS, 0, 0, lab, fsS, pv_ink);
            snprintf(lab, sizeof lab, "%.4g", c1 * PV_DEG);
            b = plot_text_box(c, x0 + tile, y0 + tile + 0.3 * fsS, 1, 0, lab, fsS);
            if (!plot_text_collides(c, b, 1.0))
                plot_text(c, x0 + tile, y0 + tile + 0.3 * fsS, 1, 0, lab, fsS, pv_ink);
        }
    }
}

/* The axis names and the colour bar: its ends are the table's maximum and maximum /
   10^6, decades between. */
static void montage_axes(const montage_plot *mp, plot_canvas *c)
{
    double fs = mp->fs, fsS = mp->fsS, m = mp->m, lineS = mp->lineS, top = mp->top;
    double gh = mp->gh, labh = mp->labh, barw = mp->barw;
    const char *rl = mp->facet ? "rows: " PLOT_THETA "n, facet tilt (deg)"
                               : "rows: " PLOT_THETA "o (deg)";
    plot_text_up(c, m + lineS / 2, top + gh / 2, rl, plot_text_fit(c, rl, fsS, PV_MIN_TEXT, gh),
                 pv_ink);
    const char *cl = mp->facet ? "cols: " PLOT_PSI ", facet azimuth (deg)"
                               : "cols: " PLOT_PHI " (deg)";
    plot_text(c, mp->left + (mp->cols * (mp->tile + mp->gap) - mp->gap) / 2,
              top + gh + 0.3 * fsS + lineS + 0.4 * lineS, 0.5, 0, cl, fsS, pv_ink);

    double bx = mp->W - mp->right + 1.5 * fs, by = top + labh + 1.6 * lineS;
    double bh = fmin(fmax(gh - labh - 4.0 * lineS, 80.0), 420.0);
    plot_text(c, bx, top + labh, 0, 0.5, PLOT_RHO " (1/sr)", fsS, pv_ink);
    pv_bar_mark marks[16];
    int nm = 0;
    if (mp->vmax > 0.0) {
        for (double d = floor(log10(mp->vmax)); d > log10(mp->lo) && nm < 16; d -= 1.0) {
            marks[nm].t = 1.0 - (log10(mp->vmax) - d) / DECADES;
            pv_format_decade(marks[nm].text, sizeof marks[nm].text, (int)d);
            nm++;
        }
    }
    pv_colour_bar(c, bx, by, barw, bh, plot_cmap, mp->top_s, mp->bot_s, marks, nm, fsS);
    double sy = by + bh + 0.8 * lineS;
    plot_rect(c, bx, sy, bx + barw, sy + lineS * 0.8, below_range);
    plot_text(c, bx + barw + 0.5 * fsS, sy + lineS * 0.4, 0, 0.5, "< max/10" "\xe2\x81\xb6", fsS,
              pv_ink);
}

int pv_draw_montage(const btdf_preview_opts *o, plot_canvas *c, char *msg, size_t msglen)
{
    montage_plot *mp = calloc(1, sizeof *mp); /* some 1 KiB of texts: not on the stack */
    if (!mp)
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for the montage");
    mp->o = o;
    int st = montage_scan(mp, msg, msglen);
    if (st == BTDF_OK)
        st = montage_layout(mp, msg, msglen);
    if (st == BTDF_OK && plot_canvas_init(c, mp->W, mp->H, pv_white) != 0)
        st = say(BTDF_ENOMEM, msg, msglen, "out of memory for a %d x %d picture", mp->W, mp->H);
    if (st != BTDF_OK) {
        free(mp);
        return st;
    }
    double m = mp->m;
    pv_para(c, m, m, mp->head, mp->fsT, mp->W - 2 * m, pv_ink, 1);
    pv_para(c, m, m + mp->th + 0.4 * m, mp->sub, mp->fsS, mp->W - 2 * m, pv_grey, 1);
    unsigned char *px = malloc((size_t)mp->tile * (size_t)mp->tile * 3);
    if (!px) {
        plot_canvas_free(c);
        free(mp);
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for the montage");
    }
    montage_tiles(mp, c, px);
    free(px);
    montage_axes(mp, c);
    free(mp);
    return BTDF_OK;
}
