/* SPDX-License-Identifier: MIT */
/* style.c: the colours, text layout and colour bars of style.h. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "preview/style.h"

const plot_rgb pv_white = {255, 255, 255};
const plot_rgb pv_ink = {25, 25, 30};
const plot_rgb pv_grey = {105, 105, 112};
const plot_rgb pv_light = {218, 218, 224};

double pv_clampd(double v, double lo, double hi)
{
    return v < lo ? lo : (v > hi ? hi : v);
}

/* "n = 1.4" or "n = 1.4/1.41/1.42 (R/G/B)" for three channels. */
void pv_format_n(char *buf, size_t len, const btdf_params *p)
{
    if (p->channels == 3)
        snprintf(buf, len, "n = %.4g/%.4g/%.4g (R/G/B)", p->ior[0], p->ior[1], p->ior[2]);
    else
        snprintf(buf, len, "n = %.4g", p->ior[0]);
}

/* Writes 10 to the power e with superscript digits: "10\u207b\u00b3" for 1e-3. */
void pv_format_decade(char *buf, size_t len, int e)
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
double pv_para(plot_canvas *c, double x, double y, const char *s, double size, double maxw,
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
            plot_text(c, x, y + used, 0, 0, line, plot_text_fit(c, line, size, PV_MIN_TEXT, maxw),
                      col);
        used += lh;
    }
    return used;
}

/* A title's size: 1.2 times the body text, down to the body text's size to fit on one
   line; para() breaks it if it is still too wide. */
double pv_title_size(plot_canvas *c, const char *s, double fs, double maxw)
{
    return plot_text_fit(c, s, 1.2 * fs, fs, maxw);
}

/* A vertical colour bar at (x, y), w x h, top = value t 1 of map(t), and its labels at the
   right: top and bottom ends always, the marks between when they do not collide. Returns
   the x just right of the widest label. */
plot_rgb pv_grey_map(double t)
{
    unsigned char v = (unsigned char)lround(255.0 * pv_clampd(t, 0.0, 1.0));
    return (plot_rgb){v, v, v};
}

double pv_colour_bar(plot_canvas *c, double x, double y, double w, double h, pv_bar_map map,
                         const char *top, const char *bottom, const pv_bar_mark *marks,
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
    plot_frame(c, lround(x), lround(y), lround(x) + iw, lround(y) + ih, 1.0, pv_grey);
    double tx = x + w + 0.6 * size, right = tx;
    plot_box b = plot_text(c, tx, y, 0, 0.5, top, size, pv_ink);
    right = fmax(right, b.x1);
    plot_line(c, x + w, y, x + w + 0.35 * size, y, 1.0, 0, pv_ink);
    b = plot_text(c, tx, y + h, 0, 0.5, bottom, size, pv_ink);
    right = fmax(right, b.x1);
    plot_line(c, x + w, y + h, x + w + 0.35 * size, y + h, 1.0, 0, pv_ink);
    for (int k = 0; k < nmarks; k++) {
        double yy = y + (1.0 - marks[k].t) * h;
        plot_box mb = plot_text_box(c, tx, yy, 0, 0.5, marks[k].text, size);
        if (plot_text_collides(c, mb, 1.0))
            continue;
        plot_text(c, tx, yy, 0, 0.5, marks[k].text, size, pv_grey);
        plot_line(c, x + w, yy, x + w + 0.3 * size, yy, 1.0, 0, pv_grey);
        right = fmax(right, mb.x1);
    }
    return right;
}

