/* SPDX-License-Identifier: MIT */
/* png_impl.h: the PNG encoder behind btdf_preview_write (libpng stays inside formats/png.c). */
#ifndef BTDF_PNG_IMPL_H
#define BTDF_PNG_IMPL_H

#include <stddef.h>

#include "btdf.h"

/* Writes 8-bit RGB rows (top first) to path, with a Software and a Description text
   chunk (description may be NULL). Only in builds with libpng: btdf_preview_write answers
   BTDF_ENOTSUP itself otherwise. */
btdf_status btdf_png_write_rgb(const char *path, const unsigned char *rgb, int width,
                               int height, const char *description, char *msg,
                               size_t msglen);

#endif
