/* SPDX-License-Identifier: MIT */
/* png_off.c: the PNG entry of a build without libpng, so errors can name the switch. */
#include "formats/formats.h"

const fmt_ops fmt_png = {
    .name = "PNG", .ext = ".png", .feature = "png", .needs = BTDF_NEEDS_PICTURE};
