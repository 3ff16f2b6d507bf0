/* SPDX-License-Identifier: MIT */
/* btdf_preview.h: PNG pictures of the model and of tables (polar lobes, slice montages, renders). */
#ifndef BTDF_PREVIEW_H
#define BTDF_PREVIEW_H

#include "btdf.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Three kinds of picture, drawn with cairo (text in DejaVu Sans) and encoded with
 * libpng; both come with the png build feature: when it was switched off,
 * btdf_preview_render and btdf_preview_write return BTDF_ENOTSUP. Sizes below a kind's
 * readable minimum (polar 480 x 360, montage 480 wide, render panels of 100 pixels)
 * are refused with BTDF_EINVAL and a message naming the minimum.
 *
 *  BTDF_PREVIEW_POLAR: rho |cos to| (1/sr) in the plane of incidence as a polar plot,
 *    like Figs. 5 and 6 of Xu & Sun (2008): the surface horizontal, the incident
 *    direction drawn in the upper half, the lobe below it, one curve for every
 *    (material, channel, ti), at most BTDF_PREVIEW_MAX_CURVES (an R,G,B material
 *    gives three), with a legend above the surface, round radial ticks and one dashed
 *    Snell direction per distinct (n, ti) (for a pane, `pane`: the straight-through one).
 *  BTDF_PREVIEW_MONTAGE: every slice of a table in false colour on a log scale
 *    (six decades below the table's maximum), one tile per slice labelled with its
 *    ti, plus a colour bar. Channel 0. At most BTDF_PREVIEW_MAX_TILES tiles: larger
 *    tables show evenly spaced slices and say so.
 *  BTDF_PREVIEW_RENDER: like Figs. 10 and 11: the flat rough face of a semi-infinite
 *    block, one face width wide, seen from 0.8 face widths away on its axis, lit by a
 *    point light on the axis inside the block (the medium the table's light comes
 *    from), far (100 widths) and near (0.8 widths), rendered from the table.
 *    Radiance per pixel: rho~ cos ti I / r^2. Scaled linearly so that the brightest
 *    component of each row is 255, as the paper does, or on a log10 scale
 *    (log_decades); `zoom` shows the central part of the face. With `analytic`, the same
 *    pictures from Eq. 25 and the relative difference |table - Eq. 25| / max Eq. 25
 *    beside them. Every false-colour or grey panel has a bar with its ends labelled.
 */
typedef enum {
    BTDF_PREVIEW_POLAR = 0,
    BTDF_PREVIEW_MONTAGE = 1,
    BTDF_PREVIEW_RENDER = 2,
    BTDF_PREVIEW_CHART = 3
} btdf_preview_kind;

/*
 * BTDF_PREVIEW_CHART: panels of curves from plain arrays, one x axis shared by all
 * (the simulator's pictures, docs/simulation.md: lobes with error bars against a model,
 * energy per order against s). A series is drawn as markers with bars of +- yerr
 * (points = 1) or as a line; every panel has its own y scale from 0 to its largest
 * y + yerr, a legend and a title. At most BTDF_CHART_MAX_PANELS panels of at most
 * BTDF_CHART_MAX_SERIES series; every number must be finite (yerr >= 0, x > 0 with
 * logx), or BTDF_EINVAL names the panel, series and point.
 */
#define BTDF_CHART_MAX_PANELS 16
#define BTDF_CHART_MAX_SERIES 8
typedef struct btdf_chart_series {
    const char *label;
    size_t n;             /* points, at most 100000 */
    const double *x, *y;
    const double *yerr;   /* NULL: no bars */
    int points;           /* 1: markers (and bars); 0: a line through the points */
} btdf_chart_series;
typedef struct btdf_chart_panel {
    const char *title;
    const btdf_chart_series *series;
    size_t nseries;
} btdf_chart_panel;
typedef struct btdf_chart {
    const char *xlabel, *ylabel;
    int logx;                  /* 1: log10 x axis */
    double xmin, xmax;         /* both 0: the data's range */
    const btdf_chart_panel *panels;
    size_t npanels;
    int columns;               /* panels per row; 0: 2 (1 for a single panel) */
} btdf_chart;

#define BTDF_PREVIEW_MAX_CURVES 8
#define BTDF_PREVIEW_MAX_TILES 48
#define BTDF_PREVIEW_MAX_SIDE 8192 /* largest width or height accepted, pixels */

typedef struct btdf_preview_opts {
    btdf_preview_kind kind;
    int width, height;             /* pixels; 0 = the kind's default (see below) */
    /* POLAR: materials x incident angles, one curve per pair. */
    const btdf_params *materials;  /* nmaterials entries */
    size_t nmaterials;
    const double *ti_deg;          /* incident angles in DEGREES, [0, 90) */
    size_t nti;
    /* MONTAGE and RENDER. */
    const btdf_table *table;
    int analytic;                  /* RENDER: add the Eq. 25 and difference panels */
    const char *title;             /* replaces the picture's own title when not NULL */
    double log_decades;            /* RENDER: 0 linear (the paper's); 1 to 12: log10 scale
                                      over that many decades below each row's maximum */
    double zoom;                   /* RENDER: 0 or 1 the whole face (the paper's); Z in
                                      (1, 1000]: the central 1/Z of it, for narrow lobes;
                                      < 0: Z from the lobe, so that the lit spot fills 90%
                                      of the picture (1, 2 or 5 times a power of ten; 1
                                      when the spot fills the face already) */
    btdf_part part;                /* POLAR: 0 or TRANSMISSION the lobe below the surface;
                                      REFLECTION or BOTH also rho_r |cos tr| of the same
                                      facets (MODEL.md section 8) above it, mirrored like the
                                      paper's figures of both halves, on the same scale */
    const btdf_chart *chart;       /* CHART: what to draw (title: the picture's title) */
    /* POLAR: when not NULL, the curves are eval's values instead of the model's (a file
       read back, say): eval(user, reflection, ti, to, phi, out) writes the materials'
       channels of rho (reflection 0) or rho_r (1) at those angles in radians into out.
       The materials then only name the curves and draw the Snell directions; their
       model is not evaluated (model full makes no tally). It must be finite and >= 0. */
    void (*eval)(void *user, int reflection, double ti, double to, double phi, double *out);
    void *eval_user;
    /* POLAR: 1 when eval gives the system of a pane in air (btdf_pane.h), not an interface:
       air on both sides, so the dashed guide below the surface is the straight-through
       direction (light leaves a pane parallel to how it came in: theta_o = pi - ti in the
       forward plane), one per ti, not a Snell direction; the texts name the pane's media.
       Needs eval (BTDF_EINVAL without it). */
    int pane;
} btdf_preview_opts;

/* Zeroes o and sets kind = POLAR. Defaults when width/height are 0: POLAR 960 x 720;
   MONTAGE 1000 wide, height to fit; RENDER 300-pixel panels, size to fit; CHART 480 x
   360 per panel (the smallest accepted: 320 x 240 per panel). */
BTDF_API void btdf_preview_opts_default(btdf_preview_opts *o);

/* Draws the picture into a new buffer of *width x *height RGB pixels, 8 bits per
   component, rows from the top. The caller frees *rgb with btdf_preview_free.
   BTDF_EINVAL (with the reason) for missing or bad inputs, BTDF_ENOMEM. */
BTDF_API btdf_status btdf_preview_render(const btdf_preview_opts *o, unsigned char **rgb,
                                         int *width, int *height, char *msg, size_t msglen);
BTDF_API void btdf_preview_free(unsigned char *rgb);

/* btdf_preview_render, then a PNG file at path, written under a temporary name in
   the same folder and renamed: on error no file is left at path. BTDF_ENOTSUP when
   PNG support was switched off at build time, BTDF_EIO when writing fails. */
BTDF_API btdf_status btdf_preview_write(const btdf_preview_opts *o, const char *path,
                                        char *msg, size_t msglen);

#ifdef __cplusplus
}
#endif

#endif /* BTDF_PREVIEW_H */
