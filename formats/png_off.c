/* SPDX-License-Identifier: MIT */
/* png_off.c: the PNG entry of a build without libpng, so errors can name the switch. */
#include "formats/formats.h"

const btdf_format_ops btdf_format_png = {
    .name = "PNG", .ext = ".png", .feature = "png", .needs = BTDF_NEEDS_PICTURE};
