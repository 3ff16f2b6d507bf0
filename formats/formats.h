/* SPDX-License-Identifier: MIT */
/* formats.h: one ops table per file format, all registered in registry.c. */
#ifndef BTDF_FORMATS_H
#define BTDF_FORMATS_H

#include <stdio.h>

#include "btdf.h"

/* What a writer gets: the object its format needs and what to record beside it. */
typedef struct fmt_output_ctx {
    const btdf_table *table;     /* BTDF_NEEDS_TABLE */
    const btdf_write_opts *opts; /* never NULL inside a writer */
    const btdf_scatfun *scatfun; /* BTDF_NEEDS_SERIES */
    const char *metadata_json;   /* BTDF_NEEDS_SERIES, may be NULL */
    /* BTDF_NEEDS_PICTURE: the picture, drawn by the registry before the write. */
    const unsigned char *rgb;    /* width x height 8-bit RGB, rows from the top */
    int width, height;
    const char *description;     /* stored in the file, may be NULL */
    const struct btdf_rad *rad;  /* BTDF_NEEDS_RADIANCE */
    const struct btdf_layer *layers; /* tables: more layers (btdf_output), may be NULL */
    size_t nlayers;
    const char *value;           /* tables: what the values are; NULL: Eq. 25's */
} fmt_output_ctx;

typedef struct fmt_ops {
    const char *name;    /* "CSV" */
    const char *ext;     /* ".csv" */
    const char *feature; /* the Meson feature that provides it, NULL if always built */
    int available;       /* 0 when its feature was switched off at build time */
    btdf_needs needs;    /* what the writer is made from */
    /* Writes to a stream (formats that can go to standard output), or NULL. */
    btdf_status (*write_stream)(const fmt_output_ctx *c, FILE *f, char *msg, size_t msglen);
    /* Writes a file that cannot go to a pipe (it seeks, or is made whole in memory): f is
       a new empty file opened safely under a temporary name, path that name for
       messages; the caller closes f and renames. Never opens path itself. */
    btdf_status (*write_path)(const fmt_output_ctx *c, FILE *f, const char *path, char *msg,
                              size_t msglen);
    /* Reads a table back (BTDF_NEEDS_TABLE), or NULL. */
    btdf_status (*read_path)(const char *path, btdf_table **out, char *msg, size_t msglen);
    /* Reads a series back (BTDF_NEEDS_SERIES), or NULL. */
    btdf_status (*read_series)(const char *path, btdf_scatfun **out, char *msg, size_t msglen);
    /* Reads a Radiance BSDF back (BTDF_NEEDS_RADIANCE), or NULL. */
    btdf_status (*read_rad)(const char *path, struct btdf_rad **out, char *msg, size_t msglen);
    /* Prints what the file stores beside the values (the error report, provenance),
       one "key: value" line each, or NULL when the format stores nothing more. */
    btdf_status (*stored)(const char *path, FILE *out);
    /* Prints what was read; NULL: the registry's table summary. */
    btdf_status (*inspect)(const btdf_input *in, FILE *out);
} fmt_ops;

/* The format a path's extension names (case-insensitive), or NULL if none. */
const fmt_ops *fmt_for_path(const char *path);

/* Writes path through write_path/write_stream under a temporary name and renames
   (src/tmpfile.h); on failure nothing is left at path. */
btdf_status fmt_write_atomic(const fmt_ops *f, const fmt_output_ctx *c,
                              const char *path, char *msg, size_t msglen);

/* Format entries, each defined in its own file. */
extern const fmt_ops fmt_csv;
extern const fmt_ops fmt_exr;
extern const fmt_ops fmt_bsdf;
extern const fmt_ops fmt_png;
extern const fmt_ops fmt_xml;

#endif
