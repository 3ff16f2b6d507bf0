/* SPDX-License-Identifier: MIT */
/* test_png.c: every picture kind is written, read back with libpng and checked at known pixels. */
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

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* The first curve's colour and the montage's colours (src/preview.c, src/plot.c). */
static const int curve0[3] = {20, 90, 200};
static const int below[3] = {30, 30, 30};
static const int yellow[3] = {252, 232, 36};

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

/* Whether a pixel of colour want lies within r pixels of (x, y). */
static int colour_near(const picture *p, double x, double y, int r, const int want[3], int tol)
{
    for (int dy = -r; dy <= r; dy++)
        for (int dx = -r; dx <= r; dx++) {
            int xx = (int)lround(x) + dx, yy = (int)lround(y) + dy;
            if (xx >= 0 && yy >= 0 && xx < p->w && yy < p->h && near(at(p, xx, yy), want, tol))
                return 1;
        }
    return 0;
}

static void write_or_fail(const btdf_preview_opts *o, const char *path)
{
    char msg[300] = "";
    btdf_status st = btdf_preview_write(o, path, msg, sizeof msg);
    if (st != BTDF_OK)
        fail_msg("%s: %s", path, msg);
}

/* POLAR: background in the corners; the lobe drawn where Eq. 25 peaks. */
static void test_polar(void **state)
{
    (void)state;
    btdf_params m;
    btdf_params_default(&m);
    m.ior[0] = 1.0 / 1.4;
    m.smoothness = 3.0;
    double ti = 30.0;
    btdf_preview_opts o;
    btdf_preview_opts_default(&o);
    o.kind = BTDF_PREVIEW_POLAR;
    o.materials = &m;
    o.nmaterials = 1;
    o.ti_deg = &ti;
    o.nti = 1;
    char path[256];
    temp_path(path, sizeof path, "polar");
    write_or_fail(&o, path);
    picture p = read_png(path);
    remove(path);
    assert_int_equal(p.w, 960);
    assert_int_equal(p.h, 720);
    expect_white(&p, 0, 0);
    expect_white(&p, p.w - 1, 0);

    /* The surface is the dark line across the whole width; the lobe hangs from its
       middle. Its peak direction, found here from Eq. 25 itself: */
    int cy = -1;
    for (int y = 0; y < p.h && cy < 0; y++)
        if (at(&p, p.w - 2, y)[0] < 80 && at(&p, p.w / 2 + 40, y)[0] < 80)
            cy = y;
    assert_true(cy > 0);
    double best = 0.0, peak_to = M_PI;
    for (int j = 0; j <= 20000; j++) {
        double to = M_PI / 2 + M_PI / 2 * j / 20000.0;
        double v = btdf_rho(m.ior[0], m.smoothness, m.k0, ti * M_PI / 180, to, M_PI) *
                   fabs(cos(to));
        if (v > best) {
            best = v;
            peak_to = to;
        }
    }
    /* The farthest curve pixel from the centre gives the radius of the plot. */
    double cx = p.w / 2.0, rmax = 0.0;
    for (int y = cy + 3; y < p.h; y++)
        for (int x = 0; x < p.w; x++)
            if (near(at(&p, x, y), curve0, 40))
                rmax = fmax(rmax, hypot(x + 0.5 - cx, y + 0.5 - cy));
    assert_true(rmax > 200);
    double tipx = cx + (rmax - 2) * sin(peak_to), tipy = cy - (rmax - 2) * cos(peak_to);
    assert_true(colour_near(&p, tipx, tipy, 3, curve0, 40));
    /* 15 degrees further back, at the same radius, there is no curve. */
    double off = peak_to + 15 * M_PI / 180;
    assert_false(colour_near(&p, cx + (rmax - 2) * sin(off), cy - (rmax - 2) * cos(off), 3,
                             curve0, 40));
    free(p.px);
}

/* MONTAGE: a slice that is 0 on the left half and large on the right shows the
   below-range colour left and the top of the map right. */
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
    char path[256];
    temp_path(path, sizeof path, "montage");
    write_or_fail(&o, path);
    btdf_table_free(t);
    picture p = read_png(path);
    remove(path);
    assert_int_equal(p.w, 800);
    expect_white(&p, 0, 0);
    expect_white(&p, p.w - 1, p.h - 1);
    long ny = 0, nb = 0;
    double xy = 0, xb = 0;
    for (int y = 0; y < p.h; y++)
        for (int x = 0; x < p.w - 160; x++) { /* the tiles, not the colour bar */
            const unsigned char *c = at(&p, x, y);
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
    free(p.px);
}

/* RENDER: the far light makes the face brightest in its middle and dark in its corners. */
static void test_render(void **state)
{
    (void)state;
    btdf_table_opts to;
    btdf_table_opts_default(&to);
    to.params.ior[0] = 1.0 / 1.5;
    to.params.smoothness = 6.0;
    to.kind = BTDF_TABLE_GRID;
    to.ti_max = 60 * M_PI / 180;
    to.grid_ti = 13;
    to.grid_to = 46;
    to.grid_phi = 19;
    btdf_table *t = NULL;
    char msg[300] = "";
    assert_int_equal(btdf_table_build(&to, &t, msg, sizeof msg), BTDF_OK);
    btdf_preview_opts o;
    btdf_preview_opts_default(&o);
    o.kind = BTDF_PREVIEW_RENDER;
    o.table = t;
    o.analytic = 1;
    char path[256];
    temp_path(path, sizeof path, "render");
    write_or_fail(&o, path);
    picture p = read_png(path);
    remove(path);
    /* Default layout: 300-pixel panels, the first at (34, 80), 14 pixels apart. */
    assert_int_equal(p.w, 34 + 3 * 300 + 2 * 14 + 10);
    expect_white(&p, 0, 0);
    expect_white(&p, p.w - 1, p.h - 1);
    for (int k = 0; k < 2; k++) { /* table and Eq. 25 panels */
        int x0 = 34 + k * 314, y0 = 80;
        const unsigned char *mid = at(&p, x0 + 150, y0 + 150);
        const unsigned char *corner = at(&p, x0 + 3, y0 + 3);
        assert_true(mid[0] > 240 && mid[1] > 240 && mid[2] > 240);
        assert_true(corner[0] < 20);
    }
    /* The near-light panels are dark at the rim as well. */
    assert_true(at(&p, 34 + 150, 80 + 300 + 30 + 14 + 3)[0] < 20);
    btdf_table_free(t);
    free(p.px);
}

/* Bad requests fail with a reason and leave no file. */
static void test_errors(void **state)
{
    (void)state;
    char path[256], msg[300] = "";
    temp_path(path, sizeof path, "bad");
    btdf_preview_opts o;
    btdf_preview_opts_default(&o);
    o.kind = BTDF_PREVIEW_MONTAGE; /* no table */
    assert_int_equal(btdf_preview_write(&o, path, msg, sizeof msg), BTDF_EINVAL);
    assert_true(strlen(msg) > 5);
    assert_int_equal(access(path, F_OK), -1);
    btdf_params m[9];
    for (int i = 0; i < 9; i++)
        btdf_params_default(&m[i]);
    double ti = 10.0;
    o.kind = BTDF_PREVIEW_POLAR;
    o.materials = m;
    o.nmaterials = 9;
    o.ti_deg = &ti;
    o.nti = 1;
    assert_int_equal(btdf_preview_write(&o, path, msg, sizeof msg), BTDF_EINVAL);
    o.nmaterials = 1;
    ti = 90.0;
    assert_int_equal(btdf_preview_write(&o, path, msg, sizeof msg), BTDF_EINVAL);
    ti = 10.0;
    assert_int_equal(btdf_preview_write(&o, "/nonexistent-folder/x.png", msg, sizeof msg),
                     BTDF_EIO);
    assert_int_equal(access(path, F_OK), -1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_polar),
        cmocka_unit_test(test_montage),
        cmocka_unit_test(test_render),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests_name("png", tests, NULL, NULL);
}
