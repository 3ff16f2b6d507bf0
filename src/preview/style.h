/* SPDX-License-Identifier: MIT */
/* style.h: what the picture kinds of preview/ share: colours, text layout, colour bars.
   Built with cairo only (-Dpng=enabled). */
#ifndef BTDF_PREVIEW_STYLE_H
#define BTDF_PREVIEW_STYLE_H

#include <stddef.h>

#include "btdf_preview.h"
#include "core/core.h"
#include "preview/plot.h"

#define say core_say /* core/core.h */
#define PV_DEG (180.0 / M_PI)
#define PV_MIN_TEXT 9.0 /* pixels per em: the smallest text any picture uses */

extern const plot_rgb pv_white, pv_ink, pv_grey, pv_light;

double pv_clampd(double v, double lo, double hi);
/* "n = 1.4" or "n = 1.4/1.41/1.42 (R/G/B)" for three channels. */
void pv_format_n(char *buf, size_t len, const btdf_params *p);
/* Writes 10 to the power e with superscript digits: "10\u207b\u00b3" for 1e-3. */
void pv_format_decade(char *buf, size_t len, int e);
/* Text split at "; " into lines that fit maxw, drawn from (x, y) down when draw is set;
   a piece wider than maxw alone is broken at spaces, and a word wider than maxw gets a
   smaller size (>= PV_MIN_TEXT). Returns the height used. */
double pv_para(plot_canvas *c, double x, double y, const char *s, double size, double maxw,
               plot_rgb col, int draw);
/* A title's size: 1.2 times the body text, down to the body text's size to fit on one
   line; pv_para() breaks it if it is still too wide. */
double pv_title_size(plot_canvas *c, const char *s, double fs, double maxw);

/* A vertical colour bar at (x, y), w x h, top = value t 1 of map(t), and its labels at the
   right: top and bottom ends always, the marks between when they do not collide. Returns
   the x just right of the widest label. */
typedef plot_rgb (*pv_bar_map)(double t);
typedef struct pv_bar_mark {
    double t; /* 0 bottom, 1 top */
    char text[48];
} pv_bar_mark;
plot_rgb pv_grey_map(double t);
double pv_colour_bar(plot_canvas *c, double x, double y, double w, double h, pv_bar_map map,
                     const char *top, const char *bottom, const pv_bar_mark *marks,
                     int nmarks, double size);

/* The picture kinds (polar.c, montage.c, render.c); o is checked by the caller for
   size only. */
int pv_draw_polar(const btdf_preview_opts *o, plot_canvas *c, char *msg, size_t msglen);
int pv_draw_montage(const btdf_preview_opts *o, plot_canvas *c, char *msg, size_t msglen);
int pv_draw_render(const btdf_preview_opts *o, plot_canvas *c, char *msg, size_t msglen);

#endif
