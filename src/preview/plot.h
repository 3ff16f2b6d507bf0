/* SPDX-License-Identifier: MIT */
/* plot.h: a small drawing layer over cairo for the pictures of preview.c: lines, rectangles,
   text in one fixed font, raster panels, colour maps, round tick values. Coordinates are
   pixels from the top left corner, as doubles (cairo anti-aliases). */
#ifndef BTDF_PLOT_H
#define BTDF_PLOT_H

#include <stddef.h>

#include <cairo.h>

typedef struct plot_rgb {
    unsigned char r, g, b;
} plot_rgb;

/* A rectangle [x0, x1] x [y0, y1] in pixels. */
typedef struct plot_box {
    double x0, y0, x1, y1;
} plot_box;

/* Every text drawn is recorded (up to this many), so layouts can avoid each other and
   tests can check that no two texts overlap and none leaves the picture. */
#define PLOT_MAX_BOXES 512

typedef struct plot_canvas {
    int w, h;
    cairo_surface_t *surf;
    cairo_t *cr;
    cairo_font_face_t *face; /* PLOT_FONT from its file, or NULL: cairo's toy choice */
    plot_box boxes[PLOT_MAX_BOXES];
    int nboxes;
} plot_canvas;

/* The one font of every picture: fontconfig finds its file by this name; it is then
   drawn unhinted and anti-aliased in grey, whatever the machine's font settings. */
#define PLOT_FONT "DejaVu Sans"

/* UTF-8 letters the pictures use (all in DejaVu Sans). */
#define PLOT_DEG "\xc2\xb0"
#define PLOT_RHO "\xcf\x81"
#define PLOT_THETA "\xce\xb8"
#define PLOT_PHI "\xcf\x86"
#define PLOT_PSI "\xcf\x88"
#define PLOT_TIMES "\xc3\x97"
#define PLOT_MINUS "\xe2\x88\x92"

/* 0 on success, -1 when cairo cannot make the surface (out of memory). Fills with bg. */
int plot_canvas_init(plot_canvas *c, int w, int h, plot_rgb bg);
void plot_canvas_free(plot_canvas *c);
/* The picture as packed 8-bit RGB rows from the top (malloc'ed; NULL when out of memory). */
unsigned char *plot_canvas_rgb(plot_canvas *c);

/* The file the pictures' font comes from (for messages and docs), or NULL if fontconfig
   finds none; buf receives it. */
const char *plot_font_file(char *buf, size_t len);

/* Filled rectangle [x0, x1) x [y0, y1). */
void plot_rect(plot_canvas *c, double x0, double y0, double x1, double y1, plot_rgb col);
/* Rectangle outline of the given line width, drawn on the pixel edges of [x0, x1) x [y0, y1). */
void plot_frame(plot_canvas *c, double x0, double y0, double x1, double y1, double width,
                plot_rgb col);
/* Segment of the given width (pixels), round caps. dash > 0: dashes dash pixels long. */
void plot_line(plot_canvas *c, double x0, double y0, double x1, double y1, double width,
               double dash, plot_rgb col);
/* A polyline through n points xy[2i], xy[2i+1], round joins. */
void plot_polyline(plot_canvas *c, const double *xy, size_t n, double width, plot_rgb col);
/* A filled triangle. */
void plot_triangle(plot_canvas *c, const double *xy, plot_rgb col);
/* Copies a w x h block of packed RGB pixels to (x0, y0), clipped to the canvas. */
void plot_image(plot_canvas *c, int x0, int y0, int w, int h, const unsigned char *rgb);

/* Text of font size `size` (pixels per em). The box of a line runs from the font's ascent
   above the baseline to its descent below it. */
double plot_text_width(plot_canvas *c, const char *s, double size);
double plot_text_height(plot_canvas *c, double size);
/* Draws s anchored at (x, y): ax = 0 left, 0.5 centre, 1 right; ay likewise top, middle,
   bottom of the line's box. Returns the box (and records it). */
plot_box plot_text(plot_canvas *c, double x, double y, double ax, double ay, const char *s,
                   double size, plot_rgb col);
/* The same turned 90 degrees counter-clockwise (reads bottom to top), centred on (x, y). */
plot_box plot_text_up(plot_canvas *c, double x, double y, const char *s, double size,
                      plot_rgb col);
/* The box plot_text would give, without drawing or recording it. */
plot_box plot_text_box(plot_canvas *c, double x, double y, double ax, double ay, const char *s,
                       double size);
/* The largest size <= size (and >= min) at which s fits in maxw pixels; min if none. */
double plot_text_fit(plot_canvas *c, const char *s, double size, double min, double maxw);
/* Whether box b overlaps any recorded text box (grown by pad pixels). */
int plot_text_collides(const plot_canvas *c, plot_box b, double pad);

/* A perceptually ordered dark-violet to yellow map, t in [0, 1] (clamped; NaN to 0). */
plot_rgb plot_cmap(double t);

/* Round tick values for the range [0, vmax]: a step of 1, 2, 2.5 or 5 times a power of
   ten giving at most `most` ticks above 0; returns the step and the count of ticks k * step
   (k = 1..count) with the last one >= vmax. vmax <= 0: step 1, count 1. */
double plot_ticks(double vmax, int most, int *count);
/* Formats a tick value v of a scale with step `step` without spurious digits. */
void plot_tick_label(char *buf, size_t len, double v, double step);

/* preview.c's drawing of a picture onto a new canvas (the caller frees it even on error),
   for the unit tests, which inspect the recorded text boxes. */
struct btdf_preview_opts;
int pv_draw(const struct btdf_preview_opts *o, plot_canvas *c, char *msg,
                      size_t msglen);

#endif
