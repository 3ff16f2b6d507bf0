/* SPDX-License-Identifier: MIT */
/* formats.h: the table of file formats; one writer or reader per file in formats/. */
#ifndef BTDF_FORMATS_H
#define BTDF_FORMATS_H

#include <stdio.h>

#include "btdf.h"

/* What a writer gets: the table and what to record beside it. */
struct btdf_rad;

typedef struct btdf_output_ctx {
    const btdf_table *table;
    const btdf_write_opts *opts; /* never NULL inside a writer */
    const struct btdf_rad *rad;  /* .xml: the Radiance BSDF built from the model, else NULL */
} btdf_output_ctx;

typedef struct btdf_format_ops {
    const char *name;    /* "csv" */
    const char *ext;     /* ".csv" */
    const char *feature; /* the Meson feature that provides it, NULL if always built */
    int available;       /* 0 when its feature was switched off at build time */
    /* Writes to a stream (formats that can go to standard output), or NULL. */
    btdf_status (*write_stream)(const btdf_output_ctx *c, FILE *f, char *msg, size_t msglen);
    /* Writes to a file path (the caller passes a temporary name and renames). */
    btdf_status (*write_path)(const btdf_output_ctx *c, const char *path, char *msg,
                              size_t msglen);
    /* Reads a table back, or NULL. */
    btdf_status (*read_path)(const char *path, btdf_table **out, char *msg, size_t msglen);
} btdf_format_ops;

/* The format a path's extension names (case-insensitive), or NULL if none. */
const btdf_format_ops *btdf_format_for_path(const char *path);

/* Writes path through write_path/write_stream under a temporary name and renames
   (src/tmpfile.h); on failure nothing is left at path. */
btdf_status btdf_write_atomic(const btdf_format_ops *f, const btdf_output_ctx *c,
                              const char *path, char *msg, size_t msglen);

/* Format entries defined in their own files. */
extern const btdf_format_ops btdf_format_csv;
extern const btdf_format_ops btdf_format_exr;
extern const btdf_format_ops btdf_format_xml;

#endif
