/* SPDX-License-Identifier: MIT */
/* exr.c: tables as multi-part OpenEXR files (one 32-bit float part per ti slice): the
   format's entry and the error records both directions share; the bytes are written in
   exr_write.c and read in exr_read.c. */
#include <stdio.h>

#include "formats/exr_impl.h"

void bexr_note_error(exr_err *e, exr_result_t code, const char *text)
{
    if (e->have)
        return; /* keep the first: later ones are usually consequences */
    e->have = 1;
    snprintf(e->text, sizeof e->text, "%s", text ? text : exr_get_default_error_message(code));
}

/* Reading contexts: the record is the context's user data. */
void bexr_on_read_error(exr_const_context_t ctx, exr_result_t code, const char *text)
{
    void *ud = NULL;
    if (exr_get_user_data(ctx, &ud) != EXR_ERR_SUCCESS || ud == NULL)
        return;
    bexr_note_error(ud, code, text);
}

/* The OpenEXR message for a failed call rc, or its default text. */
const char *bexr_text(const exr_err *e, exr_result_t rc)
{
    return e->have ? e->text : exr_get_default_error_message(rc);
}

static const char *const chan_rgb[3] = {"R", "G", "B"};
static const char *const chan_y[1] = {"Y"};

const char *const *bexr_chan_names(int channels)
{
    return channels == 3 ? chan_rgb : chan_y;
}

const fmt_ops fmt_exr = {
    .name = "OpenEXR",
    .ext = ".exr",
    .feature = "openexr",
    .available = 1,
    .needs = BTDF_NEEDS_TABLE,
    .write_path = bexr_write,
    .read_path = bexr_read,
    .stored = bexr_stored,
};
