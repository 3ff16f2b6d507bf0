/* SPDX-License-Identifier: MIT */
/* png_off.c: the PNG encoder of a build without libpng: says so. */
#include <stdio.h>

#include "png_impl.h"

btdf_status btdf_png_write_rgb(const char *path, const unsigned char *rgb, int width,
                               int height, const char *description, char *msg,
                               size_t msglen)
{
    (void)path;
    (void)rgb;
    (void)width;
    (void)height;
    (void)description;
    if (msg && msglen)
        snprintf(msg, msglen, "PNG support was switched off at build time (-Dpng=disabled)");
    return BTDF_ENOTSUP;
}
