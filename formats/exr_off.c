/* SPDX-License-Identifier: MIT */
/* exr_off.c: the .exr entry of a build without OpenEXR, so callers can say why. */
#include "formats.h"

/* available = 0 and no functions: the registry answers BTDF_ENOTSUP and names the
   feature, e.g. "OpenEXR support was switched off at build time (-Dopenexr=disabled)". */
const btdf_format_ops btdf_format_exr = {
    "exr", ".exr", "openexr", 0, NULL, NULL, NULL,
};
