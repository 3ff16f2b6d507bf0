/* SPDX-License-Identifier: MIT */
/* exr_impl.h: what exr.c, exr_write.c and exr_read.c share (private to formats/). */
#ifndef BTDF_FORMATS_EXR_IMPL_H
#define BTDF_FORMATS_EXR_IMPL_H

#include <stddef.h>
#include <stdio.h>

#include <openexr.h>

#include "formats/formats.h"
#include "model/kernel.h"
#include "table/table.h"

/* Layout (docs/formats.md is the reference):
 *   part k = slice k, scanline storage, ZIP, FLOAT channels "Y" or "B","G","R";
 *   pixel (x = col, y = row), data window (0, 0) - (ncols - 1, nrows - 1);
 *   per part:  btdf.ti (double, radians), btdf.rows / btdf.cols (string, %.17g
 *              radians separated by spaces), btdf.rowAxis / btdf.colAxis (string);
 *   part 0:    the table (kind, channels, n per channel, s, k0, units, report);
 *   a file holding both parts: the reflection's slices after the transmission's, each
 *   with btdf.part "reflection", and btdf.refl.* on part 0 (docs/formats.md). */

#define ATTR_PREFIX "btdf."
#define say core_say /* core/core.h */

/* The first OpenEXR error message of a context, for our own messages. */
typedef struct exr_err {
    int have;
    char text[256];
} exr_err;

/* Keeps the first message of a context in e. */
void bexr_note_error(exr_err *e, exr_result_t code, const char *text);
/* The error handler of reading contexts: the record is the context's user data. */
void bexr_on_read_error(exr_const_context_t ctx, exr_result_t code, const char *text);
/* The OpenEXR message for a failed call rc, or its default text. */
const char *bexr_text(const exr_err *e, exr_result_t rc);
/* "R", "G", "B" for three channels, "Y" for one. */
const char *const *bexr_chan_names(int channels);

/* exr_write.c */
btdf_status bexr_write(const fmt_output_ctx *c, FILE *f, const char *path, char *msg,
                       size_t msglen);
/* exr_read.c */
btdf_status bexr_read(const char *path, btdf_table **out, char *msg, size_t msglen);
btdf_status bexr_stored(const char *path, FILE *out);

#endif
