/* SPDX-License-Identifier: MIT */
/* png.c: the PNG entry of the format registry: 8-bit RGB pictures through libpng, whose
   setjmp error handling stays here. */
#include <errno.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include <png.h>

#include "formats/formats.h"

/* Where libpng's messages go: the first error, for the caller's buffer. */
typedef struct png_err {
    char text[200];
} png_err;

static void on_png_error(png_structp png, png_const_charp text)
{
    png_err *e = png_get_error_ptr(png);
    /* libpng's own writer says "Write Error" when fwrite fails: the cause is errno's
       (a full disk, a file size limit) */
    int io = errno != 0 && strcmp(text, "Write Error") == 0;
    if (e && e->text[0] == '\0')
        snprintf(e->text, sizeof e->text, "%s%s%s", text, io ? ": " : "",
                 io ? strerror(errno) : "");
    png_longjmp(png, 1);
}

static void on_png_warning(png_structp png, png_const_charp text)
{
    (void)png; /* warnings do not stop the write and are not worth reporting */
    (void)text;
}

/* The libpng part: no local of this function is changed after setjmp, so nothing
   needs to be volatile. Returns 0 on success. */
static int encode(FILE *f, const unsigned char *rgb, int width, int height,
                  const char *description, png_err *err)
{
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, err, on_png_error,
                                              on_png_warning);
    if (!png) {
        snprintf(err->text, sizeof err->text, "out of memory");
        return -1;
    }
    png_infop info = png_create_info_struct(png);
    if (!info) {
        snprintf(err->text, sizeof err->text, "out of memory");
        png_destroy_write_struct(&png, NULL);
        return -1;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return -1;
    }
    png_init_io(png, f);
    png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_text text[2];
    memset(text, 0, sizeof text);
    text[0].compression = PNG_TEXT_COMPRESSION_NONE;
    text[0].key = (png_charp) "Software";
    text[0].text = (png_charp) "btdftab " BTDF_VERSION_STRING;
    text[1].compression = PNG_TEXT_COMPRESSION_NONE;
    text[1].key = (png_charp) "Description";
    text[1].text = (png_charp)(description ? description : "");
    png_set_text(png, info, text, description ? 2 : 1);
    png_write_info(png, info);
    for (int y = 0; y < height; y++)
        png_write_row(png, rgb + (size_t)y * (size_t)width * 3);
    png_write_end(png, info);
    png_destroy_write_struct(&png, &info);
    return 0;
}

/* Writes the picture of c (drawn by the registry) to path. */
static btdf_status png_write(const fmt_output_ctx *c, FILE *f, const char *path, char *msg,
                             size_t msglen)
{
    const unsigned char *rgb = c->rgb;
    int width = c->width, height = c->height;
    const char *description = c->description;
    if (width <= 0 || height <= 0 || !rgb) {
        if (msg && msglen)
            snprintf(msg, msglen, "empty picture (%d x %d)", width, height);
        return BTDF_EINVAL;
    }
    (void)path;
    png_err err;
    err.text[0] = '\0';
    int bad = encode(f, rgb, width, height, description, &err);
    if (fflush(f) != 0 && !bad) {
        bad = 1;
        snprintf(err.text, sizeof err.text, "writing the file failed: %s", strerror(errno));
    }
    if (bad) {
        if (msg && msglen)
            snprintf(msg, msglen, "PNG: %s", err.text);
        return BTDF_EIO;
    }
    return BTDF_OK;
}

const fmt_ops fmt_png = {
    .name = "PNG",
    .ext = ".png",
    .feature = "png",
    .available = 1,
    .needs = BTDF_NEEDS_PICTURE,
    .write_path = png_write,
};
