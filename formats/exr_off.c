/* SPDX-License-Identifier: MIT */
/* exr_off.c: the OpenEXR entry of a build without OpenEXR, so errors can name the switch. */
#include "formats/formats.h"

const fmt_ops fmt_exr = {
    .name = "OpenEXR", .ext = ".exr", .feature = "openexr", .needs = BTDF_NEEDS_TABLE};
