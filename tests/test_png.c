/* SPDX-License-Identifier: MIT */
/* test_png.c: every picture kind is written, read back with libpng and checked by its
   structure: where curves, panels and colours are, compared with Eq. 25; text layout is
   checked from the boxes the drawing records (no two texts overlap, none leaves the
   picture), never from the glyphs, which depend on the font installed. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cmocka.h>
#include <png.h>

#include "btdf.h"
#include "btdf_preview.h"
#include "preview/plot.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* The first curve's colour and the map's ends (src/preview/preview.c, src/preview/plot.c). */
static const int curve0[3] = {20, 90, 200};
static const int below[3] = {30, 30, 30};
static const int yellow[3] = {252, 232, 36};
static const int violet[3] = {69, 0, 84};

typedef struct picture {
    int w, h;
    unsigned char *px;
} picture;

static void temp_path(char *buf, size_t len, const char *tag)
{
    const char *dir = getenv("TMPDIR");
    snprintf(buf, len, "%s/btdf-test-%s-%ld.png", dir && *dir ? dir : "/tmp", tag,
             (long)getpid());
}

/* Reads an 8-bit RGB picture with libpng's simplified API. */
static picture read_png(const char *path)
{
    png_image img;
    memset(&img, 0, sizeof img);
    img.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&img, path))
        fail_msg("%s: %s", path, img.message);
    img.format = PNG_FORMAT_RGB;
    picture p = {(int)img.width, (int)img.height, malloc(PNG_IMAGE_SIZE(img))};
    assert_non_null(p.px);
    if (!png_image_finish_read(&img, NULL, p.px, 0, NULL))
        fail_msg("%s: %s", path, img.message);
    return p;
}

static const unsigned char *at(const picture *p, int x, int y)
{
    assert_true(x >= 0 && y >= 0 && x < p->w && y < p->h);
    return p->px + 3 * ((size_t)y * (size_t)p->w + (size_t)x);
}

static int near(const unsigned char *px, const int want[3], int tol)
{
    return abs(px[0] - want[0]) <= tol && abs(px[1] - want[1]) <= tol &&
           abs(px[2] - want[2]) <= tol;
}

static void expect_white(const picture *p, int x, int y)
{
    const unsigned char *c = at(p, x, y);
    if (c[0] != 255 || c[1] != 255 || c[2] != 255)
        fail_msg("pixel (%d, %d) is %d %d %d, not the white background", x, y, c[0], c[1], c[2]);
}

static picture write_and_read(const btdf_preview_opts *o, const char *tag)
{
    char path[256], msg[300] = "";
    temp_path(path, sizeof path, tag);
    btdf_status st = btdf_preview_write(o, path, msg, sizeof msg);
    if (st != BTDF_OK)
        fail_msg("%s: %s", path, msg);
    picture p = read_png(path);
    remove(path);
    return p;
}

/* Eq. 25's rho |cos to| in the plane of incidence, forward side, to in radians. */
static double lobe(const btdf_params *m, double ti_deg, double to)
{
    return btdf_rho(m->ior[0], m->smoothness, m->k0, ti_deg * M_PI / 180, to, M_PI) *
           fabs(cos(to));
}

/* Whether a pixel of colour want lies within r pixels of (x, y). */
static int colour_near(const picture *p, double x, double y, int r, const int want[3], int tol)
{
    for (int dy = -r; dy <= r; dy++)
        for (int dx = -r; dx <= r; dx++) {
            int xx = (int)floor(x) + dx, yy = (int)floor(y) + dy;
            if (xx >= 0 && yy >= 0 && xx < p->w && yy < p->h && near(at(p, xx, yy), want, tol))
                return 1;
        }
    return 0;
}

/* The farthest pixel of colour want from (cx, cy) within 1.2 pixels of the ray at
   angle to from the upward normal (forward side), or 0: below the surface line for
   to > 90 degrees, above it otherwise. */
static double ray_extent(const picture *p, double cx, double cy, double to, const int want[3])
{
    double ux = sin(to), uy = -cos(to), best = 0.0; /* image y grows downwards */
    int y0 = uy > 0 ? (int)cy + 3 : 0, y1 = uy > 0 ? p->h : (int)cy - 3;
    for (int y = y0; y < y1; y++)
        for (int x = 0; x < p->w; x++) {
            double dx = x + 0.5 - cx, dy = y + 0.5 - cy;
            double along = dx * ux + dy * uy, across = fabs(dx * uy - dy * ux);
            if (along > 0 && across <= 1.2 && near(at(p, x, y), want, 40))
                best = fmax(best, along);
        }
    return best;
}

/* The surface of a polar plot: the dark line across the whole width, 2 pixels wide;
   the y of its centre, which is the plot's. */
static double surface_y(const picture *p)
{
    double sy = 0.0;
    int n = 0;
    for (int y = 0; y < p->h; y++)
        if (at(p, 2, y)[0] < 100 && at(p, p->w - 3, y)[0] < 100) {
            sy += y + 0.5;
            n++;
        }
    assert_true(n >= 1 && n <= 4);
    return sy / n;
}

/* A polar plot of one material, n = 1.4, s = 3, at ti = 30 deg (o points at m and ti). */
static void polar_setup(btdf_params *m, double *ti, btdf_preview_opts *o)
{
    btdf_params_default(m);
    m->ior[0] = 1.4;
    m->smoothness = 3.0;
    *ti = 30.0;
    btdf_preview_opts_default(o);
    o->kind = BTDF_PREVIEW_POLAR;
    o->materials = m;
    o->nmaterials = 1;
    o->ti_deg = ti;
    o->nti = 1;
}

/* POLAR: the curve is where Eq. 25 puts it: along rays from the centre the lobe's radii
   stand in the ratio of Eq. 25's values. */
static void test_polar(void **state)
{
    (void)state;
    btdf_params m;
    double ti;
    btdf_preview_opts o;
    polar_setup(&m, &ti, &o);
    picture p = write_and_read(&o, "polar");
    assert_int_equal(p.w, 960);
    assert_int_equal(p.h, 720);
    expect_white(&p, 0, 0);
    expect_white(&p, p.w - 1, 0);

    double cx = p.w / 2.0, cy = surface_y(&p);

    double best = 0.0, peak_to = M_PI;
    for (int j = 0; j <= 20000; j++) {
        double to = M_PI / 2 + M_PI / 2 * j / 20000.0;
        if (lobe(&m, ti, to) > best) {
            best = lobe(&m, ti, to);
            peak_to = to;
        }
    }
    double r0 = ray_extent(&p, cx, cy, peak_to, curve0);
    assert_true(r0 > 150); /* the default picture's lobe is large */
    /* Beyond the peak the lobe falls smoothly: there the curve passes through the points
       Eq. 25 gives, scaled by the peak's radius (the farthest pixel less the line's half
       width, 1.1), within 2 pixels (half width and pixel grid), and near the peak not 15 % further out.
       Before the peak Eq. 25 drops to 0 within a few degrees (about 141 degrees here), so
       the lobe's edge is nearly a radius: 20 degrees before the peak no lobe is left. */
    double k = (r0 - 1.1) / best;
    for (int q = 1; q <= 4; q++) {
        double to = peak_to + q * 4 * M_PI / 180, r = k * lobe(&m, ti, to);
        if (!colour_near(&p, cx + r * sin(to), cy - r * cos(to), 2, curve0, 40))
            fail_msg("no curve within 2 px of Eq. 25's point at to = %.1f deg, r = %.1f px",
                     to * 180 / M_PI, r);
        /* Further from the peak the narrow lobe meets the ray at a shallow angle and
           runs beside it: the "not further out" test holds near the peak only. */
        if (q <= 2 &&
            colour_near(&p, cx + 1.15 * r * sin(to), cy - 1.15 * r * cos(to), 2, curve0, 40))
            fail_msg("curve colour 15 %% beyond Eq. 25's point at to = %.1f deg, r = %.1f px "
                     "(%.1f, %.1f)", to * 180 / M_PI, r, cx + 1.15 * r * sin(to),
                     cy - 1.15 * r * cos(to));
    }
    assert_true(lobe(&m, ti, peak_to - 20 * M_PI / 180) < 1e-6 * best);
    assert_true(ray_extent(&p, cx, cy, peak_to - 20 * M_PI / 180, curve0) < 0.1 * r0);
    free(p.px);
}

/* POLAR with the reflection: its lobe above the surface where MODEL.md section 8 puts
   it, on its own scale (its peak is 1e-3 of the transmission's here), the transmission
   still below. */
static void test_polar_reflection(void **state)
{
    (void)state;
    btdf_params m;
    double ti;
    btdf_preview_opts o;
    polar_setup(&m, &ti, &o);
    o.part = BTDF_PART_BOTH;
    picture p = write_and_read(&o, "polar-both");
    double cx = p.w / 2.0, cy = surface_y(&p);
    /* the reflection's peak in the plane, specular side */
    double best = 0.0, peak_tr = 0.0;
    for (int j = 0; j <= 9000; j++) {
        double tr = (M_PI / 2) * j / 9000.0;
        double v = btdf_rho_r(1.4, 3.0, 0.7, ti * M_PI / 180, tr, M_PI) * cos(tr);
        if (v > best) {
            best = v;
            peak_tr = tr;
        }
    }
    /* the farthest curve pixel along the peak's ray, above the surface */
    double r0 = ray_extent(&p, cx, cy, peak_tr, curve0);
    assert_true(r0 > 100); /* on its own scale the small lobe is large */
    double k = (r0 - 1.1) / best;
    for (int q = 1; q <= 3; q++) { /* further out on the specular side, as rho_r says */
        double tr = peak_tr + q * 6 * M_PI / 180;
        double r = k * btdf_rho_r(1.4, 3.0, 0.7, ti * M_PI / 180, tr, M_PI) * cos(tr);
        if (!colour_near(&p, cx + r * sin(tr), cy - r * cos(tr), 2, curve0, 40))
            fail_msg("no curve within 2 px of rho_r's point at tr = %.1f deg, r = %.1f px",
                     tr * 180 / M_PI, r);
    }
    /* and the transmission below the surface, as without the reflection */
    double pt = 0.0, peak_to = M_PI;
    for (int j = 0; j <= 9000; j++) {
        double to = M_PI / 2 + M_PI / 2 * j / 9000.0;
        if (lobe(&m, ti, to) > pt) {
            pt = lobe(&m, ti, to);
            peak_to = to;
        }
    }
    assert_true(ray_extent(&p, cx, cy, peak_to, curve0) > 100);
    free(p.px);
    /* a bad part is refused */
    o.part = (btdf_part)9;
    unsigned char *rgb = NULL;
    int w = 0, h = 0;
    char msg[256] = "";
    assert_int_equal(btdf_preview_render(&o, &rgb, &w, &h, msg, sizeof msg), BTDF_EINVAL);
    assert_non_null(strstr(msg, "part 9"));
}

/* An R,G,B material is three curves, each in its channel's hue. */
static void test_polar_rgb(void **state)
{
    (void)state;
    btdf_params m;
    btdf_params_default(&m);
    m.channels = 3;
    m.ior[0] = 1.3;
    m.ior[1] = 1.5;
    m.ior[2] = 1.7;
    double ti = 40.0;
    btdf_preview_opts o;
    btdf_preview_opts_default(&o);
    o.materials = &m;
    o.nmaterials = 1;
    o.ti_deg = &ti;
    o.nti = 1;
    o.width = 640;
    o.height = 480;
    picture p = write_and_read(&o, "polar-rgb");
    static const int hue[3][3] = {{215, 35, 35}, {25, 150, 55}, {30, 80, 215}};
    for (int ch = 0; ch < 3; ch++) {
        long count = 0;
        for (int y = p.h / 3; y < p.h; y++)
            for (int x = 0; x < p.w; x++)
                count += near(at(&p, x, y), hue[ch], 30);
        if (count < 200)
            fail_msg("channel %d: %ld pixels of its colour, want a curve (>= 200)", ch, count);
    }
    free(p.px);
}

/* The caller's values of test_polar_pane: 1 on the backward side (phi = 0), 0 forward,
   so that no lobe is drawn on the forward side where the guides are. */
static void backward_only(void *user, int reflection, double ti, double to, double phi,
                          double *out)
{
    (void)user, (void)reflection, (void)ti, (void)to;
    out[0] = fabs(phi) < 1.0 ? 1.0 : 0.0;
}

/* POLAR of a pane (o.pane): air on both sides, so the dashed guide below the surface is
   the straight-through direction, theta_o = 180 - ti, not the Snell direction of n; and
   a pane's plot without its values (eval) is refused. */
static void test_polar_pane(void **state)
{
    (void)state;
    btdf_params m;
    double ti;
    btdf_preview_opts o;
    polar_setup(&m, &ti, &o);
    o.eval = backward_only;
    o.pane = 1;
    picture p = write_and_read(&o, "polar-pane");
    double cx = p.w / 2.0, cy = surface_y(&p);
    double straight = M_PI - ti * M_PI / 180; /* to of the straight-through direction */
    double snell = M_PI - asin(sin(ti * M_PI / 180) / m.ior[0]); /* 20.9 deg off the normal */
    /* the dashed guide runs to the plot's radius (over 150 pixels in the default picture)
       along the straight-through ray; along the Snell ray, 9 degrees away, only the
       pixels near the centre, where the two rays are within the 1.2-pixel band (about 8
       pixels out) and the line's width: 20 pixels bound both */
    double r_straight = ray_extent(&p, cx, cy, straight, curve0);
    double r_snell = ray_extent(&p, cx, cy, snell, curve0);
    if (!(r_straight > 150.0 && r_snell < 20.0))
        fail_msg("guide along the straight-through ray %.1f px, along Snell's %.1f px: want "
                 "> 150 and < 20", r_straight, r_snell);
    free(p.px);
    o.eval = NULL;
    unsigned char *rgb = NULL;
    int w = 0, h = 0;
    char msg[256] = "";
    assert_int_equal(btdf_preview_render(&o, &rgb, &w, &h, msg, sizeof msg), BTDF_EINVAL);
    assert_non_null(strstr(msg, "pane"));
}

/* MONTAGE: a slice that is 0 on the left half and large on the right shows the
   below-range colour left and the top of the map right; the colour bar runs from the
   map's top to its bottom. */
static void test_montage(void **state)
{
    (void)state;
    btdf_params par;
    btdf_params_default(&par);
    btdf_table *t = NULL;
    char msg[300] = "";
    assert_int_equal(btdf_table_new(BTDF_TABLE_GRID, &par, &t, msg, sizeof msg), BTDF_OK);
    double rows[3] = {M_PI / 2, 3 * M_PI / 4, M_PI}, cols[4] = {0, 1.0, 2.0, M_PI};
    double vals[12];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++)
            vals[r * 4 + c] = c >= 2 ? 5.0 : 0.0;
    for (int k = 0; k < 2; k++)
        assert_int_equal(
            btdf_table_add_slice(t, 0.3 * k, 3, rows, 4, cols, vals, msg, sizeof msg), BTDF_OK);
    btdf_preview_opts o;
    btdf_preview_opts_default(&o);
    o.kind = BTDF_PREVIEW_MONTAGE;
    o.table = t;
    o.width = 800;
    picture p = write_and_read(&o, "montage");
    btdf_table_free(t);
    assert_int_equal(p.w, 800);
    expect_white(&p, 0, 0);
    expect_white(&p, p.w - 1, p.h - 1);
    long ny = 0, nb = 0;
    double xy = 0, xb = 0;
    int bar_top = -1, bar_bottom = -1;
    for (int y = 0; y < p.h; y++)
        for (int x = 0; x < p.w; x++) {
            const unsigned char *c = at(&p, x, y);
            if (x >= p.w - 160) { /* the colour bar */
                if (near(c, yellow, 3) && bar_top < 0)
                    bar_top = y;
                if (near(c, violet, 3))
                    bar_bottom = y;
                continue;
            }
            if (near(c, yellow, 3)) {
                ny++;
                xy += x;
            } else if (near(c, below, 0)) {
                nb++;
                xb += x;
            }
        }
    assert_true(ny > 1000);
    assert_true(nb > 1000);
    /* Columns 0 and 1 (x < 1 rad) are 0; x >= 2 rad is 5: yellow lies to the right. */
    assert_true(xy / ny > xb / nb);
    assert_true(bar_top > 0 && bar_bottom > bar_top + 60);
    free(p.px);
}

/* A 13 x 46 x 19 grid table of n = 1/1.5, s = 6, 0 to 60 degrees. */
static btdf_table *small_table(int threads)
{
    btdf_table_opts to;
    btdf_table_opts_default(&to);
    to.params.ior[0] = 1.0 / 1.5;
    to.params.smoothness = 6.0;
    to.kind = BTDF_TABLE_GRID;
    to.ti_max = 60 * M_PI / 180;
    to.grid_ti = 13;
    to.grid_to = 46;
    to.grid_phi = 19;
    to.threads = threads;
    btdf_table *t = NULL;
    char msg[300] = "";
    assert_int_equal(btdf_table_build(&to, &t, msg, sizeof msg), BTDF_OK);
    return t;
}

/* The dark runs of at least `len` pixels on row y: their starts in x0[], count returned. */
static int dark_runs(const picture *p, int y, int len, int *x0, int most)
{
    int n = 0, run = 0;
    for (int x = 0; x <= p->w; x++) {
        int dark = x < p->w && at(p, x, y)[0] < 20 && at(p, x, y)[1] < 20;
        if (dark) {
            run++;
        } else {
            if (run >= len && n < most)
                x0[n++] = x - run;
            run = 0;
        }
    }
    return n;
}

/* The pixels brighter than 64 in the first panel of a render, found by its frame: the
   first row with 100 pixels of the frame's grey in a row is the frame's top edge. */
static long lit_first_panel(const picture *p)
{
    static const int frame[3] = {105, 105, 112};
    for (int y = 0; y < p->h; y++)
        for (int x = 0, run = 0; x < p->w; x++) {
            run = near(at(p, x, y), frame, 8) ? run + 1 : 0;
            if (run < 100)
                continue;
            int x0 = x - run + 2, y0 = y + 1; /* the frame lies just outside the panel */
            long n = 0;
            for (int j = 0; j < 300; j++)
                for (int i = 0; i < 300; i++)
                    n += at(p, x0 + i, y0 + j)[0] > 64;
            return n;
        }
    fail_msg("no panel frame found");
    return 0;
}

/* RENDER: the far light makes the face brightest in its middle and dark in its corners;
   panels are 300 pixels by default; the log scale lights more of the face. */
static void test_render(void **state)
{
    (void)state;
    btdf_table *t = small_table(0);
    btdf_preview_opts o;
    btdf_preview_opts_default(&o);
    o.kind = BTDF_PREVIEW_RENDER;
    o.table = t;
    o.analytic = 1;
    picture p = write_and_read(&o, "render");
    expect_white(&p, 0, 0);
    expect_white(&p, p.w - 1, p.h - 1);
    /* The first row where two dark runs of 100 pixels begin is the top of the panels. */
    int xs[4], y0 = -1;
    for (int y = 0; y < p.h && y0 < 0; y++)
        if (dark_runs(&p, y, 100, xs, 4) >= 2)
            y0 = y;
    assert_true(y0 > 0);
    assert_int_equal(dark_runs(&p, y0, 100, xs, 4), 2); /* table and Eq. 25 */
    int P = 0;
    while (y0 + P < p.h && at(&p, xs[0] + 1, y0 + P)[0] < 20)
        P++;
    assert_int_equal(P, 300);
    for (int k = 0; k < 2; k++) {
        const unsigned char *mid = at(&p, xs[k] + 150, y0 + 150);
        assert_true(mid[0] > 240 && mid[1] > 240 && mid[2] > 240);
        assert_true(at(&p, xs[k] + 3, y0 + 3)[0] < 20);
    }
    /* The near-light panels below are dark at the rim as well. */
    int y1 = -1;
    for (int y = y0 + P + 2; y < p.h && y1 < 0; y++)
        if (dark_runs(&p, y, 100, xs, 4) >= 2)
            y1 = y;
    assert_true(y1 > y0 + P);
    assert_true(at(&p, xs[0] + 150, y1 + 3)[0] < 20);

    /* Log scale over 6 decades: the same middle, more of the face lit. */
    long lit_lin = lit_first_panel(&p);
    free(p.px);
    o.analytic = 0;
    o.log_decades = 6.0;
    p = write_and_read(&o, "render-log");
    long lit_log = lit_first_panel(&p);
    if (!(lit_log > 2 * lit_lin))
        fail_msg("log scale lights %ld pixels, linear %ld: want more than twice", lit_log,
                 lit_lin);
    free(p.px);
    /* Zoom 2: the same face points at twice the scale, so the lit area (the same face
       region: each row is scaled to the same central maximum) is 4 times larger, to the
       pixels along its rim (about 2 pi r / (pi r^2) = 5 % for r = 40 pixels). */
    o.log_decades = 0.0;
    o.zoom = 2.0;
    p = write_and_read(&o, "render-zoom");
    long lit_zoom = lit_first_panel(&p);
    if (!(lit_zoom > 3.6 * lit_lin && lit_zoom < 4.4 * lit_lin))
        fail_msg("zoom 2 lights %ld pixels, zoom 1 %ld: want 4 times (3.6 to 4.4)", lit_zoom,
                 lit_lin);
    btdf_table_free(t);
    free(p.px);
}

/* Same inputs, same pixels: twice in one process, and from tables built with 1 and 2
   threads. */
static void test_deterministic(void **state)
{
    (void)state;
    btdf_table *t1 = small_table(1), *t2 = small_table(2);
    btdf_preview_opts o;
    btdf_preview_opts_default(&o);
    o.kind = BTDF_PREVIEW_RENDER;
    o.analytic = 1;
    o.width = 700;
    unsigned char *a = NULL, *b = NULL;
    int wa, ha, wb, hb;
    char msg[300] = "";
    for (int kind = 1; kind <= 2; kind++) {
        o.kind = (btdf_preview_kind)kind;
        o.table = t1;
        assert_int_equal(btdf_preview_render(&o, &a, &wa, &ha, msg, sizeof msg), BTDF_OK);
        o.table = t2;
        assert_int_equal(btdf_preview_render(&o, &b, &wb, &hb, msg, sizeof msg), BTDF_OK);
        assert_int_equal(wa, wb);
        assert_int_equal(ha, hb);
        assert_memory_equal(a, b, (size_t)wa * (size_t)ha * 3);
        btdf_preview_free(b);
        assert_int_equal(btdf_preview_render(&o, &b, &wb, &hb, msg, sizeof msg), BTDF_OK);
        assert_memory_equal(a, b, (size_t)wa * (size_t)ha * 3);
        btdf_preview_free(a);
        btdf_preview_free(b);
    }
    btdf_table_free(t1);
    btdf_table_free(t2);
}

/* Draws o and checks the recorded text boxes: inside the picture, no two overlapping. */
static void check_layout(const btdf_preview_opts *o, const char *what)
{
    plot_canvas c;
    char msg[300] = "";
    int st = pv_draw(o, &c, msg, sizeof msg);
    if (st != BTDF_OK)
        fail_msg("%s: %s", what, msg);
    assert_true(c.nboxes > 5 && c.nboxes < PLOT_MAX_BOXES);
    for (int i = 0; i < c.nboxes; i++) {
        plot_box b = c.boxes[i];
        /* Half a pixel: anti-aliasing of a glyph's edge on the picture's border. */
        if (b.x0 < -0.5 || b.y0 < -0.5 || b.x1 > c.w + 0.5 || b.y1 > c.h + 0.5)
            fail_msg("%s (%d x %d): text %d at [%.1f, %.1f] x [%.1f, %.1f] leaves the picture",
                     what, c.w, c.h, i, b.x0, b.x1, b.y0, b.y1);
        for (int j = 0; j < i; j++) {
            plot_box q = c.boxes[j];
            if (b.x0 < q.x1 && q.x0 < b.x1 && b.y0 < q.y1 && q.y0 < b.y1)
                fail_msg("%s (%d x %d): texts %d and %d overlap: [%.1f, %.1f] x [%.1f, %.1f] "
                         "and [%.1f, %.1f] x [%.1f, %.1f]",
                         what, c.w, c.h, j, i, q.x0, q.x1, q.y0, q.y1, b.x0, b.x1, b.y0, b.y1);
        }
    }
    plot_canvas_free(&c);
}

/* BTDF_PREVIEW_CHART (the simulator's pictures): four panels of lobes with error bars
   and two model lines, and a log-x chart of five series like the orders picture; the
   layout rules as for every kind, at the default and the smallest size; the same bytes
   twice; a NaN, a negative error and a size below the minimum named. */
static void test_chart(void **state)
{
    (void)state;
    static double x[90], y[90], e[90], m[90], xs[10], ys[5][10], es[10];
    for (int i = 0; i < 90; i++) {
        x[i] = -89 + 2 * i;
        y[i] = 6 * exp(-(x[i] - 25) * (x[i] - 25) / 200.0);
        e[i] = 0.05 * y[i];
        m[i] = 0.9 * y[i];
    }
    for (int k = 0; k < 10; k++) {
        xs[k] = 0.5 * pow(1.5, k);
        es[k] = 0.003;
        for (int q = 0; q < 5; q++)
            ys[q][k] = (q + 1) / (5.0 + k);
    }
    btdf_chart_series sr[3] = {{"simulation \xc2\xb1 1 s.e.", 90, x, y, e, 1},
                               {"Eq. 25 (same bins)", 90, x, m, NULL, 0},
                               {"Smith (same bins)", 90, x, y, NULL, 0}};
    btdf_chart_panel pn[4] = {{"(a) s = 6", sr, 3}, {"(b) s = 3", sr, 3}, {"(c) s = 1", sr, 3},
                              {"(d) s = 0.5", sr, 3}};
    btdf_chart ch = {"\xce\xb8o (\xc2\xb0)", "\xcf\x81 |cos \xce\xb8o| (1/sr)", 0, -90, 90,
                     pn, 4, 2};
    btdf_preview_opts o;
    btdf_preview_opts_default(&o);
    o.kind = BTDF_PREVIEW_CHART;
    o.chart = &ch;
    o.title = "Fig. 9 redrawn: n = 1.4, \xce\xb8i = 30\xc2\xb0";
    check_layout(&o, "chart of lobes");
    o.width = 640;
    o.height = 514; /* 2 x 240 and the title's 34 */
    check_layout(&o, "chart of lobes, smallest");
    btdf_chart_series so[5];
    const char *lab[5] = {"one hit", "two hits", "three or more", "all orders", "Eq. 25"};
    for (int q = 0; q < 5; q++)
        so[q] = (btdf_chart_series){lab[q], 10, xs, ys[q], q < 4 ? es : NULL, q < 4};
    btdf_chart_panel po[2] = {{"n = 1.5", so, 5}, {"n = 1/1.5", so, 5}};
    btdf_chart cl = {"s (log scale)", "T", 1, 0.4, 40, po, 2, 2};
    btdf_preview_opts_default(&o);
    o.kind = BTDF_PREVIEW_CHART;
    o.chart = &cl;
    o.title = "Transmission by order";
    check_layout(&o, "chart of orders");
    unsigned char *a = NULL, *b = NULL;
    int w1, h1, w2, h2;
    char msg[300];
    assert_int_equal(BTDF_OK, btdf_preview_render(&o, &a, &w1, &h1, msg, sizeof msg));
    assert_int_equal(BTDF_OK, btdf_preview_render(&o, &b, &w2, &h2, msg, sizeof msg));
    assert_true(w1 == w2 && h1 == h2 && memcmp(a, b, (size_t)w1 * (size_t)h1 * 3) == 0);
    btdf_preview_free(a);
    btdf_preview_free(b);
    ys[1][2] = NAN;
    assert_int_equal(BTDF_EINVAL, btdf_preview_render(&o, &a, &w1, &h1, msg, sizeof msg));
    assert_non_null(strstr(msg, "panel 1, series 2, point 3"));
    ys[1][2] = 0.1;
    es[4] = -1;
    assert_int_equal(BTDF_EINVAL, btdf_preview_render(&o, &a, &w1, &h1, msg, sizeof msg));
    assert_non_null(strstr(msg, "error -1"));
    es[4] = 0.003;
    o.width = 300;
    assert_int_equal(BTDF_EINVAL, btdf_preview_render(&o, &a, &w1, &h1, msg, sizeof msg));
    assert_non_null(strstr(msg, "at least 640"));
}

static void test_layout(void **state)
{
    (void)state;
    btdf_params m[4];
    for (int i = 0; i < 4; i++) {
        btdf_params_default(&m[i]);
        m[i].ior[0] = i % 2 ? 1.0 / 1.4 : 1.4;
        m[i].smoothness = 1.0 + 5 * i;
    }
    double tis[2] = {0.0, 60.0};
    btdf_preview_opts o;
    btdf_preview_opts_default(&o);
    o.materials = m;
    o.nmaterials = 4;
    o.ti_deg = tis;
    o.nti = 2; /* 8 curves: the largest legend */
    static const int sizes[4][2] = {{0, 0}, {640, 480}, {480, 360}, {1600, 600}};
    for (int k = 0; k < 4; k++) {
        o.width = sizes[k][0];
        o.height = sizes[k][1];
        if (k != 2)
            check_layout(&o, "polar");
    }
    /* At the smallest size 8 curves' legend leaves too small a plot: refused, naming the
       height that works; that height works. Two curves fit. */
    o.width = 480;
    o.height = 360;
    unsigned char *rgb = NULL;
    int w, h;
    char msg[300] = "";
    assert_int_equal(btdf_preview_render(&o, &rgb, &w, &h, msg, sizeof msg), BTDF_EINVAL);
    const char *need = strstr(msg, "at least ");
    assert_non_null(need);
    o.height = atoi(need + 9);
    assert_true(o.height > 360 && o.height < 1000);
    check_layout(&o, "polar, 8 curves");
    o.height = 360;
    o.nmaterials = 1;
    check_layout(&o, "polar, 2 curves");
    btdf_table *t = small_table(0);
    o.table = t;
    for (int kind = 1; kind <= 2; kind++)
        for (int an = 0; an <= 1; an++)
            for (int k = 0; k < 3; k++) {
                o.kind = (btdf_preview_kind)kind;
                o.analytic = an;
                o.log_decades = an ? 0.0 : 5.0;
                o.width = sizes[k][0];
                o.height = kind == 1 && k == 2 ? 0 : sizes[k][1];
                if (kind == 2 && k == 2) { /* the smallest render: 100-pixel panels */
                    o.width = an ? 560 : 240;
                    o.height = 0;
                }
                check_layout(&o, kind == 1 ? "montage" : "render");
            }
    btdf_table_free(t);
}

/* Round ticks: 2, 4, 6, 8 for a maximum of 7.28, never 1.82, 3.64. */
static void test_ticks(void **state)
{
    (void)state;
    static const double vmax[6] = {7.28, 1.0, 28.12, 0.0173, 3.31, 950.0};
    static const double step_want[6] = {2.0, 0.25, 10.0, 0.005, 1.0, 250.0};
    for (int i = 0; i < 6; i++) {
        int n;
        double step = plot_ticks(vmax[i], 4, &n);
        assert_float_equal(step, step_want[i], 1e-12 * step_want[i]);
        assert_true(n <= 4 && n * step >= vmax[i] && (n - 1) * step < vmax[i]);
        for (int k = 1; k <= n; k++) {
            char lab[32];
            plot_tick_label(lab, sizeof lab, k * step, step);
            /* The label reads back as the tick's value exactly, to the label's digits. */
            assert_float_equal(strtod(lab, NULL), k * step, 1e-9 * step);
            assert_true(strlen(lab) <= 5);
        }
    }
    char lab[32];
    plot_tick_label(lab, sizeof lab, 0.5, 0.25);
    assert_string_equal(lab, "0.5");
    plot_tick_label(lab, sizeof lab, 1.0, 0.25);
    assert_string_equal(lab, "1");
}

/* Bad requests fail with a reason and leave no file. */
static void test_errors(void **state)
{
    (void)state;
    char path[256], msg[300] = "";
    temp_path(path, sizeof path, "bad");
    /* the name holds the pid, which the system reuses: a file left by an earlier process
       (a crashed run) must not count as one this test's calls wrote */
    remove(path);
    btdf_preview_opts o;
    btdf_preview_opts_default(&o);
    o.kind = BTDF_PREVIEW_MONTAGE; /* no table */
    assert_int_equal(btdf_preview_write(&o, path, msg, sizeof msg), BTDF_EINVAL);
    assert_true(strlen(msg) > 5);
    assert_int_equal(access(path, F_OK), -1);
    btdf_params m[9];
    for (int i = 0; i < 9; i++)
        btdf_params_default(&m[i]);
    double ti[3] = {10.0, 20.0, 30.0};
    o.kind = BTDF_PREVIEW_POLAR;
    o.materials = m;
    o.nmaterials = 9;
    o.ti_deg = ti;
    o.nti = 1;
    assert_int_equal(btdf_preview_write(&o, path, msg, sizeof msg), BTDF_EINVAL);
    /* An R,G,B material at 3 angles: 9 curves. */
    m[0].channels = 3;
    m[0].ior[1] = m[0].ior[2] = 1.5;
    o.nmaterials = 1;
    o.nti = 3;
    assert_int_equal(btdf_preview_write(&o, path, msg, sizeof msg), BTDF_EINVAL);
    assert_non_null(strstr(msg, "9 curves"));
    m[0].channels = 1;
    o.nti = 1;
    ti[0] = 90.0;
    assert_int_equal(btdf_preview_write(&o, path, msg, sizeof msg), BTDF_EINVAL);
    ti[0] = 10.0;
    /* Below the readable minimum: refused, naming it. */
    o.width = 400;
    o.height = 300;
    assert_int_equal(btdf_preview_write(&o, path, msg, sizeof msg), BTDF_EINVAL);
    assert_non_null(strstr(msg, "at least 480 x 360"));
    o.width = o.height = 0;
    assert_int_equal(btdf_preview_write(&o, "/nonexistent-folder/x.png", msg, sizeof msg),
                     BTDF_EIO);
    assert_int_equal(access(path, F_OK), -1);
    btdf_table *t = small_table(0);
    o.kind = BTDF_PREVIEW_RENDER;
    o.table = t;
    o.log_decades = 0.5;
    assert_int_equal(btdf_preview_write(&o, path, msg, sizeof msg), BTDF_EINVAL);
    assert_non_null(strstr(msg, "log_decades"));
    o.log_decades = 0.0;
    o.zoom = 0.5;
    assert_int_equal(btdf_preview_write(&o, path, msg, sizeof msg), BTDF_EINVAL);
    assert_non_null(strstr(msg, "zoom"));
    o.zoom = 0.0;
    o.log_decades = 0.0;
    o.width = 200;
    assert_int_equal(btdf_preview_write(&o, path, msg, sizeof msg), BTDF_EINVAL);
    assert_non_null(strstr(msg, "at least 100"));
    o.kind = BTDF_PREVIEW_MONTAGE;
    o.width = 300;
    assert_int_equal(btdf_preview_write(&o, path, msg, sizeof msg), BTDF_EINVAL);
    assert_non_null(strstr(msg, "at least 480"));
    assert_int_equal(access(path, F_OK), -1);
    btdf_table_free(t);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_polar),         cmocka_unit_test(test_polar_reflection),
        cmocka_unit_test(test_polar_rgb),     cmocka_unit_test(test_polar_pane),
        cmocka_unit_test(test_montage),
        cmocka_unit_test(test_render),
        cmocka_unit_test(test_deterministic), cmocka_unit_test(test_layout),
        cmocka_unit_test(test_chart),
        cmocka_unit_test(test_ticks),         cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests_name("png", tests, NULL, NULL);
}
