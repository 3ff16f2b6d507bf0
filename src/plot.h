/* SPDX-License-Identifier: MIT */
/* plot.h: a tiny RGB canvas: antialiased lines, rectangles, a built-in bitmap font, colour maps. */
#ifndef BTDF_PLOT_H
#define BTDF_PLOT_H

#include <stddef.h>

typedef struct plot_rgb {
    unsigned char r, g, b;
} plot_rgb;

/* 8-bit RGB pixels, row after row from the top, 3 bytes each. */
typedef struct plot_canvas {
    int w, h;
    unsigned char *px;
} plot_canvas;

/* Text in the font: ASCII plus these UTF-8 letters: degree, rho, theta, phi, psi. */
#define PLOT_DEG "\xc2\xb0"
#define PLOT_RHO "\xcf\x81"
#define PLOT_THETA "\xce\xb8"
#define PLOT_PHI "\xcf\x86"
#define PLOT_PSI "\xcf\x88"

/* Glyph cell: 5 x 9 pixels (caps 7 high, 2 for descenders), advance 6, at scale 1. */
#define PLOT_GLYPH_W 6
#define PLOT_GLYPH_H 9

/* 0 on success, -1 when out of memory. Fills with bg. */
int plot_canvas_init(plot_canvas *c, int w, int h, plot_rgb bg);
void plot_canvas_free(plot_canvas *c);

/* Mixes colour col into pixel (x, y) with opacity a in [0, 1]; outside: nothing. */
void plot_blend(plot_canvas *c, int x, int y, plot_rgb col, double a);
/* Filled rectangle [x0, x1) x [y0, y1), clipped. */
void plot_rect(plot_canvas *c, int x0, int y0, int x1, int y1, plot_rgb col);
/* One-pixel rectangle outline around [x0, x1) x [y0, y1). */
void plot_frame(plot_canvas *c, int x0, int y0, int x1, int y1, plot_rgb col);
/* Antialiased segment of the given width (pixels), round caps. */
void plot_line(plot_canvas *c, double x0, double y0, double x1, double y1, double width,
               plot_rgb col);
/* The same in dashes of dash pixels on and dash off. */
void plot_dashed(plot_canvas *c, double x0, double y0, double x1, double y1, double width,
                 double dash, plot_rgb col);

/* Width in pixels of s at the given integer scale. */
int plot_text_width(const char *s, int scale);
/* Draws s with its anchor at (x, y): ax = 0 left, 0.5 centre, 1 right; likewise ay
   for top, middle, bottom of the cap height. */
void plot_text(plot_canvas *c, int x, int y, double ax, double ay, const char *s, int scale,
               plot_rgb col);
/* The same turned 90 degrees counter-clockwise (reads bottom to top), centred on (x, y). */
void plot_text_up(plot_canvas *c, int x, int y, const char *s, int scale, plot_rgb col);

/* A perceptually ordered dark-blue to yellow map, t in [0, 1] (clamped). */
plot_rgb plot_cmap(double t);

#endif
