/* SPDX-License-Identifier: MIT */
/* preview.c: the public functions of btdf_preview.h and the choice of a picture kind
   (polar.c, montage.c, render.c, drawn with cairo through plot.h and style.h). Without
   cairo and libpng (-Dpng=disabled) only this file is built: the checks of the public
   functions remain and they answer BTDF_ENOTSUP. */
#include <stdlib.h>
#include <string.h>

#include "btdf_preview.h"
#include "core/core.h"

#define say core_say /* core/core.h */

#if BTDF_HAVE_PNG

#include "preview/style.h"

int pv_draw(const btdf_preview_opts *o, plot_canvas *c, char *msg, size_t msglen)
{
    memset(c, 0, sizeof *c);
    if (o->width < 0 || o->height < 0 || o->width > BTDF_PREVIEW_MAX_SIDE ||
        o->height > BTDF_PREVIEW_MAX_SIDE)
        return say(BTDF_EINVAL, msg, msglen, "picture size %d x %d outside 1 to %d", o->width,
                   o->height, BTDF_PREVIEW_MAX_SIDE);
    switch (o->kind) {
    case BTDF_PREVIEW_POLAR: return pv_draw_polar(o, c, msg, msglen);
    case BTDF_PREVIEW_MONTAGE: return pv_draw_montage(o, c, msg, msglen);
    case BTDF_PREVIEW_RENDER: return pv_draw_render(o, c, msg, msglen);
    case BTDF_PREVIEW_CHART: return pv_draw_chart(o, c, msg, msglen);
    default: return say(BTDF_EINVAL, msg, msglen, "unknown picture kind %d", (int)o->kind);
    }
}

#endif /* BTDF_HAVE_PNG */

/* ------------------------------------------------------------------------- */
/* Public                                                                    */
/* ------------------------------------------------------------------------- */

BTDF_API void btdf_preview_opts_default(btdf_preview_opts *o)
{
    memset(o, 0, sizeof *o);
    o->kind = BTDF_PREVIEW_POLAR;
}

BTDF_API btdf_status btdf_preview_render(const btdf_preview_opts *o, unsigned char **rgb,
                                         int *width, int *height, char *msg, size_t msglen)
{
    if (!o || !rgb || !width || !height)
        return say(BTDF_EINVAL, msg, msglen, "missing argument");
#if BTDF_HAVE_PNG
    plot_canvas c;
    btdf_status st = (btdf_status)pv_draw(o, &c, msg, msglen);
    if (st != BTDF_OK) {
        plot_canvas_free(&c);
        return st;
    }
    *rgb = plot_canvas_rgb(&c);
    *width = c.w;
    *height = c.h;
    plot_canvas_free(&c);
    if (!*rgb)
        return say(BTDF_ENOMEM, msg, msglen, "out of memory for a %d x %d picture", *width,
                   *height);
    return BTDF_OK;
#else
    return say(BTDF_ENOTSUP, msg, msglen,
               "pictures were switched off at build time (-Dpng=disabled)");
#endif
}

BTDF_API void btdf_preview_free(unsigned char *rgb)
{
    free(rgb);
}
