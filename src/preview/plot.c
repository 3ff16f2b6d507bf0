/* SPDX-License-Identifier: MIT */
/* plot.c: the drawing layer of plot.h on a cairo RGB24 image surface. */
#include "preview/plot.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cairo-ft.h>
#include <fontconfig/fontconfig.h>

static void set_colour(cairo_t *cr, plot_rgb col)
{
    cairo_set_source_rgb(cr, col.r / 255.0, col.g / 255.0, col.b / 255.0);
}

/* The pattern of PLOT_FONT's file: the name is matched with the machine's configuration,
   then only the file and the rendering options below are kept, so that settings such as
   hinting or sub-pixel order in a fonts.conf do not change the pictures. NULL if no file. */
static FcPattern *font_pattern(void)
{
    FcPattern *want = FcNameParse((const FcChar8 *)PLOT_FONT);
    if (!want)
        return NULL;
    FcConfigSubstitute(NULL, want, FcMatchPattern);
    FcDefaultSubstitute(want);
    FcResult res;
    FcPattern *got = FcFontMatch(NULL, want, &res);
    FcPatternDestroy(want);
    if (!got)
        return NULL;
    FcChar8 *file = NULL;
    int index = 0;
    FcPattern *clean = NULL;
    if (FcPatternGetString(got, FC_FILE, 0, &file) == FcResultMatch && file) {
        if (FcPatternGetInteger(got, FC_INDEX, 0, &index) != FcResultMatch)
            index = 0;
        clean = FcPatternCreate();
        if (clean) {
            FcPatternAddString(clean, FC_FILE, file);
            FcPatternAddInteger(clean, FC_INDEX, index);
            FcPatternAddBool(clean, FC_ANTIALIAS, FcTrue);
            FcPatternAddBool(clean, FC_HINTING, FcFalse);
            FcPatternAddInteger(clean, FC_HINT_STYLE, FC_HINT_NONE);
            FcPatternAddBool(clean, FC_AUTOHINT, FcFalse);
            FcPatternAddInteger(clean, FC_RGBA, FC_RGBA_NONE);
            FcPatternAddBool(clean, FC_EMBEDDED_BITMAP, FcFalse);
        }
    }
    FcPatternDestroy(got);
    return clean;
}

const char *plot_font_file(char *buf, size_t len)
{
    FcPattern *p = font_pattern();
    FcChar8 *file = NULL;
    const char *out = NULL;
    if (p && FcPatternGetString(p, FC_FILE, 0, &file) == FcResultMatch && file) {
        snprintf(buf, len, "%s", (const char *)file);
        out = buf;
    }
    if (p)
        FcPatternDestroy(p);
    return out;
}

int plot_canvas_init(plot_canvas *c, int w, int h, plot_rgb bg)
{
    memset(c, 0, sizeof *c);
    c->surf = cairo_image_surface_create(CAIRO_FORMAT_RGB24, w, h);
    if (cairo_surface_status(c->surf) != CAIRO_STATUS_SUCCESS) {
        cairo_surface_destroy(c->surf);
        c->surf = NULL;
        return -1;
    }
    c->cr = cairo_create(c->surf);
    if (cairo_status(c->cr) != CAIRO_STATUS_SUCCESS) {
        plot_canvas_free(c);
        return -1;
    }
    c->w = w;
    c->h = h;
    /* One font, no hinting: glyph positions then depend on the font file alone, not
       on the machine's hinting settings, and scale smoothly with the size. */
    FcPattern *pat = font_pattern();
    if (pat) {
        c->face = cairo_ft_font_face_create_for_pattern(pat); /* cairo keeps its own copy */
        FcPatternDestroy(pat);
        if (cairo_font_face_status(c->face) != CAIRO_STATUS_SUCCESS) {
            cairo_font_face_destroy(c->face);
            c->face = NULL;
        }
    }
    if (c->face)
        cairo_set_font_face(c->cr, c->face);
    else /* no font file found: cairo's own choice for the name */
        cairo_select_font_face(c->cr, PLOT_FONT, CAIRO_FONT_SLANT_NORMAL,
                               CAIRO_FONT_WEIGHT_NORMAL);
    cairo_font_options_t *fo = cairo_font_options_create();
    cairo_font_options_set_antialias(fo, CAIRO_ANTIALIAS_GRAY);
    cairo_font_options_set_hint_style(fo, CAIRO_HINT_STYLE_NONE);
    cairo_font_options_set_hint_metrics(fo, CAIRO_HINT_METRICS_OFF);
    cairo_set_font_options(c->cr, fo);
    cairo_font_options_destroy(fo);
    cairo_set_line_cap(c->cr, CAIRO_LINE_CAP_ROUND);
    cairo_set_line_join(c->cr, CAIRO_LINE_JOIN_ROUND);
    set_colour(c->cr, bg);
    cairo_paint(c->cr);
    return 0;
}

void plot_canvas_free(plot_canvas *c)
{
    if (c->cr)
        cairo_destroy(c->cr);
    if (c->surf)
        cairo_surface_destroy(c->surf);
    if (c->face)
        cairo_font_face_destroy(c->face);
    c->face = NULL;
    c->cr = NULL;
    c->surf = NULL;
}

unsigned char *plot_canvas_rgb(plot_canvas *c)
{
    cairo_surface_flush(c->surf);
    const unsigned char *data = cairo_image_surface_get_data(c->surf);
    int stride = cairo_image_surface_get_stride(c->surf);
    unsigned char *out = malloc((size_t)c->w * (size_t)c->h * 3);
    if (!out || !data) {
        free(out);
        return NULL;
    }
    for (int y = 0; y < c->h; y++) {
        /* RGB24: one native-endian 32-bit word per pixel, 0x00RRGGBB. */
        const unsigned char *row = data + (size_t)y * (size_t)stride;
        unsigned char *o = out + (size_t)y * (size_t)c->w * 3;
        for (int x = 0; x < c->w; x++) {
            uint32_t v;
            memcpy(&v, row + 4 * (size_t)x, 4);
            o[3 * x] = (unsigned char)(v >> 16);
            o[3 * x + 1] = (unsigned char)(v >> 8);
            o[3 * x + 2] = (unsigned char)v;
        }
    }
    return out;
}

void plot_rect(plot_canvas *c, double x0, double y0, double x1, double y1, plot_rgb col)
{
    set_colour(c->cr, col);
    cairo_rectangle(c->cr, x0, y0, x1 - x0, y1 - y0);
    cairo_fill(c->cr);
}

void plot_frame(plot_canvas *c, double x0, double y0, double x1, double y1, double width,
                plot_rgb col)
{
    set_colour(c->cr, col);
    cairo_set_line_width(c->cr, width);
    cairo_rectangle(c->cr, x0 - width / 2, y0 - width / 2, x1 - x0 + width, y1 - y0 + width);
    cairo_stroke(c->cr);
}

void plot_line(plot_canvas *c, double x0, double y0, double x1, double y1, double width,
               double dash, plot_rgb col)
{
    set_colour(c->cr, col);
    cairo_set_line_width(c->cr, width);
    if (dash > 0.0) {
        double d[2] = {dash, dash * 0.7};
        cairo_set_dash(c->cr, d, 2, 0.0);
        cairo_set_line_cap(c->cr, CAIRO_LINE_CAP_BUTT);
    }
    cairo_move_to(c->cr, x0, y0);
    cairo_line_to(c->cr, x1, y1);
    cairo_stroke(c->cr);
    if (dash > 0.0) {
        cairo_set_dash(c->cr, NULL, 0, 0.0);
        cairo_set_line_cap(c->cr, CAIRO_LINE_CAP_ROUND);
    }
}

void plot_polyline(plot_canvas *c, const double *xy, size_t n, double width, plot_rgb col)
{
    if (n < 2)
        return;
    set_colour(c->cr, col);
    cairo_set_line_width(c->cr, width);
    cairo_move_to(c->cr, xy[0], xy[1]);
    for (size_t i = 1; i < n; i++)
        cairo_line_to(c->cr, xy[2 * i], xy[2 * i + 1]);
    cairo_stroke(c->cr);
}

void plot_triangle(plot_canvas *c, const double *xy, plot_rgb col)
{
    set_colour(c->cr, col);
    cairo_move_to(c->cr, xy[0], xy[1]);
    cairo_line_to(c->cr, xy[2], xy[3]);
    cairo_line_to(c->cr, xy[4], xy[5]);
    cairo_close_path(c->cr);
    cairo_fill(c->cr);
}

void plot_image(plot_canvas *c, int x0, int y0, int w, int h, const unsigned char *rgb)
{
    cairo_surface_flush(c->surf); /* finish cairo's drawing before touching pixels */
    unsigned char *data = cairo_image_surface_get_data(c->surf);
    int stride = cairo_image_surface_get_stride(c->surf);
    if (!data)
        return;
    for (int y = 0; y < h; y++) {
        int yy = y0 + y;
        if (yy < 0 || yy >= c->h)
            continue;
        for (int x = 0; x < w; x++) {
            int xx = x0 + x;
            if (xx < 0 || xx >= c->w)
                continue;
            const unsigned char *p = rgb + 3 * ((size_t)y * (size_t)w + (size_t)x);
            uint32_t v = (uint32_t)p[0] << 16 | (uint32_t)p[1] << 8 | (uint32_t)p[2];
            memcpy(data + (size_t)yy * (size_t)stride + 4 * (size_t)xx, &v, 4);
        }
    }
    cairo_surface_mark_dirty(c->surf);
}

double plot_text_width(plot_canvas *c, const char *s, double size)
{
    cairo_text_extents_t te;
    cairo_set_font_size(c->cr, size);
    cairo_text_extents(c->cr, s, &te);
    return te.x_advance;
}

double plot_text_height(plot_canvas *c, double size)
{
    cairo_font_extents_t fe;
    cairo_set_font_size(c->cr, size);
    cairo_font_extents(c->cr, &fe);
    return fe.ascent + fe.descent;
}

static void record(plot_canvas *c, plot_box b)
{
    if (c->nboxes < PLOT_MAX_BOXES)
        c->boxes[c->nboxes++] = b;
}

plot_box plot_text_box(plot_canvas *c, double x, double y, double ax, double ay, const char *s,
                       double size)
{
    cairo_font_extents_t fe;
    cairo_text_extents_t te;
    cairo_set_font_size(c->cr, size);
    cairo_font_extents(c->cr, &fe);
    cairo_text_extents(c->cr, s, &te);
    double w = te.x_advance, h = fe.ascent + fe.descent;
    plot_box b = {x - ax * w, y - ay * h, x - ax * w + w, y - ay * h + h};
    return b;
}

plot_box plot_text(plot_canvas *c, double x, double y, double ax, double ay, const char *s,
                   double size, plot_rgb col)
{
    cairo_font_extents_t fe;
    cairo_text_extents_t te;
    cairo_set_font_size(c->cr, size);
    cairo_font_extents(c->cr, &fe);
    cairo_text_extents(c->cr, s, &te);
    double w = te.x_advance, h = fe.ascent + fe.descent;
    plot_box b = {x - ax * w, y - ay * h, x - ax * w + w, y - ay * h + h};
    set_colour(c->cr, col);
    cairo_move_to(c->cr, b.x0, b.y0 + fe.ascent);
    cairo_show_text(c->cr, s);
    cairo_new_path(c->cr);
    record(c, b);
    return b;
}

plot_box plot_text_up(plot_canvas *c, double x, double y, const char *s, double size,
                      plot_rgb col)
{
    cairo_font_extents_t fe;
    cairo_text_extents_t te;
    cairo_set_font_size(c->cr, size);
    cairo_font_extents(c->cr, &fe);
    cairo_text_extents(c->cr, s, &te);
    double w = te.x_advance, h = fe.ascent + fe.descent;
    cairo_save(c->cr);
    cairo_translate(c->cr, x, y);
    cairo_rotate(c->cr, -1.57079632679489662); /* a quarter turn counter-clockwise */
    set_colour(c->cr, col);
    cairo_move_to(c->cr, -w / 2, -h / 2 + fe.ascent);
    cairo_show_text(c->cr, s);
    cairo_new_path(c->cr);
    cairo_restore(c->cr);
    plot_box b = {x - h / 2, y - w / 2, x + h / 2, y + w / 2};
    record(c, b);
    return b;
}

double plot_text_fit(plot_canvas *c, const char *s, double size, double min, double maxw)
{
    double w = plot_text_width(c, s, size);
    if (w <= maxw)
        return size;
    /* Width is proportional to size without hinting; w > maxw >= 0 here, so w > 0. */
    double fit = floor(size * maxw / w * 10.0) / 10.0;
    return fit < min ? min : fit;
}

int plot_text_collides(const plot_canvas *c, plot_box b, double pad)
{
    for (int i = 0; i < c->nboxes; i++) {
        const plot_box *o = &c->boxes[i];
        if (b.x0 < o->x1 + pad && o->x0 < b.x1 + pad && b.y0 < o->y1 + pad &&
            o->y0 < b.y1 + pad)
            return 1;
    }
    return 0;
}

plot_rgb plot_cmap(double t)
{
    /* Anchor colours chosen by eye: dark violet, blue, teal, green, yellow. */
    static const double k[5][3] = {
        {0.27, 0.00, 0.33}, {0.23, 0.32, 0.55}, {0.13, 0.57, 0.55},
        {0.37, 0.79, 0.38}, {0.99, 0.91, 0.14},
    };
    if (!(t > 0.0))
        t = 0.0; /* also maps NaN to the bottom */
    if (t > 1.0)
        t = 1.0;
    double u = t * 4.0;
    int i = (int)u;
    if (i > 3)
        i = 3;
    double f = u - i;
    plot_rgb out;
    out.r = (unsigned char)lround(255.0 * (k[i][0] + f * (k[i + 1][0] - k[i][0])));
    out.g = (unsigned char)lround(255.0 * (k[i][1] + f * (k[i + 1][1] - k[i][1])));
    out.b = (unsigned char)lround(255.0 * (k[i][2] + f * (k[i + 1][2] - k[i][2])));
    return out;
}

double plot_ticks(double vmax, int most, int *count)
{
    if (!(vmax > 0.0) || !isfinite(vmax) || most < 1) {
        *count = 1;
        return 1.0;
    }
    /* vmax / most > 0: log10 is finite. */
    double p = pow(10.0, floor(log10(vmax / most)));
    static const double mant[5] = {1.0, 2.0, 2.5, 5.0, 10.0};
    double step = 10.0 * p;
    for (int i = 0; i < 5; i++)
        if (mant[i] * p * most >= vmax * (1.0 - 1e-12)) {
            step = mant[i] * p;
            break;
        }
    int n = (int)ceil(vmax / step * (1.0 - 1e-12)); /* step > 0 */
    *count = n < 1 ? 1 : n;
    return step;
}

void plot_tick_label(char *buf, size_t len, double v, double step)
{
    double e = floor(log10(step) + 1e-9); /* step > 0 (plot_ticks) */
    double m = step / pow(10.0, e);
    int dec = (int)-e + (fabs(m - 2.5) < 1e-6 ? 1 : 0);
    if (fabs(v) < step * 1e-6)
        snprintf(buf, len, "0");
    else if (step >= 1e5 || step < 1e-4)
        snprintf(buf, len, "%.3g", v);
    else {
        snprintf(buf, len, "%.*f", dec > 0 ? dec : 0, v);
        /* 0.50 -> 0.5, 1.00 -> 1: no digits the value does not have. */
        if (strchr(buf, '.')) {
            size_t l = strlen(buf);
            while (l > 0 && buf[l - 1] == '0')
                buf[--l] = '\0';
            if (l > 0 && buf[l - 1] == '.')
                buf[--l] = '\0';
        }
    }
}
