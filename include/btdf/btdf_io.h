/* SPDX-License-Identifier: MIT */
/* btdf_io.h: every file format through one write and one read path, by extension. */
#ifndef BTDF_IO_H
#define BTDF_IO_H

#include <stddef.h>
#include <stdio.h>

#include "btdf.h"

#ifdef __cplusplus
extern "C" {
#endif

/*
 * Each file format is named by its extension and made from one kind of object:
 *   .csv .exr   a table (btdf_table_build)
 *   .bsdf       a Fourier series built from Eq. 25 (btdf_scatfun_build)
 *   .png        a picture (btdf_preview_opts: a polar plot, or a montage or render
 *               of a table)
 *   .xml        a WINDOW/Radiance BSDF built from Eq. 25 (btdf_rad_build)
 * btdf_write writes any of them the same way: under a temporary name beside the
 * output, renamed at the end; on any error nothing is left at the path. The
 * temporary files of writes in progress can be removed from a signal handler with
 * btdf_remove_partial_files.
 */

/* What a format is made from. */
typedef enum {
    BTDF_NEEDS_NONE = 0,    /* no format has this extension */
    BTDF_NEEDS_TABLE = 1,   /* a btdf_table */
    BTDF_NEEDS_SERIES = 2,  /* a btdf_scatfun */
    BTDF_NEEDS_PICTURE = 3, /* btdf_preview_opts, drawn when written */
    BTDF_NEEDS_RADIANCE = 4 /* a btdf_rad (btdf_radiance.h) */
} btdf_needs;

typedef struct btdf_format_info {
    const char *name;    /* "CSV", "OpenEXR", "SCATFUN", "PNG" */
    const char *ext;     /* ".csv" */
    const char *feature; /* the Meson feature that provides it, NULL if always built */
    int available;       /* 0 when that feature was switched off at build time */
    btdf_needs needs;
    int can_stream;      /* 1 if it can be written to standard output (path "-") */
    int can_read;        /* 1 if btdf_read reads it back */
} btdf_format_info;

/* The format the extension of path names (case-insensitive): 1 and *info filled, or 0
   when no format has that extension (info may be NULL). */
BTDF_API int btdf_format_find(const char *path, btdf_format_info *info);

/* The known extensions, space-separated (".csv .exr .bsdf .png .xml"), for messages. */
BTDF_API const char *btdf_format_list(void);

/* What to write: the member the format needs must be set, the others are ignored. */
typedef struct btdf_output {
    const btdf_table *table;                 /* BTDF_NEEDS_TABLE */
    const struct btdf_scatfun *scatfun;      /* BTDF_NEEDS_SERIES */
    const struct btdf_preview_opts *picture; /* BTDF_NEEDS_PICTURE */
    const btdf_write_opts *opts;             /* tables: report and provenance, may be NULL */
    const char *metadata_json; /* .bsdf: the text stored in the file; NULL: the parameters */
    const struct btdf_rad *radiance;         /* BTDF_NEEDS_RADIANCE */
} btdf_output;

/* Writes what to path in the format its extension names; path "-" is standard output
   for formats that can stream (CSV). BTDF_EINVAL for an unknown extension or a missing
   object, BTDF_ENOTSUP when the format was switched off at build time (the message
   names the feature), BTDF_EIO when writing fails, or the format's own errors. */
BTDF_API btdf_status btdf_write(const btdf_output *what, const char *path, char *msg,
                                size_t msglen);

/* One more layer of a table file: a table of the same layout (kind, slices, nodes,
   channels) whose values are written beside the table's, e.g. a standard error per
   node. */
typedef struct btdf_layer {
    const char *name; /* letters, digits and '_', under 24 bytes */
    const btdf_table *table;
} btdf_layer;

/* Writes table t to path like btdf_write, with nlayers more layers (at most 8) where
   the format can hold them: EXR writes layer L as channels L.Y (or L.R, L.G, L.B) in
   every part, which btdf_read leaves aside; other formats refuse layers (BTDF_EINVAL).
   value says what the numbers are (EXR's btdftab.value); NULL: Eq. 25's rho. */
BTDF_API btdf_status btdf_write_table_layers(const btdf_table *t, const btdf_layer *layers,
                                             size_t nlayers, const char *value,
                                             const btdf_write_opts *w, const char *path,
                                             char *msg, size_t msglen);

/* What was read: exactly one member is set; free it with its own *_free. */
typedef struct btdf_input {
    btdf_table *table;
    struct btdf_scatfun *scatfun;
    struct btdf_rad *radiance; /* .xml (btdf_radiance.h: btdf_rad_free) */
} btdf_input;

/* Reads a file written by btdf_write (.csv, .exr, .bsdf, .xml) into *in (zeroed first).
   BTDF_EINVAL for an unknown extension or one that cannot be read back (.png),
   BTDF_ENOTSUP when switched off, BTDF_EFORMAT or BTDF_EIO from the reader. */
BTDF_API btdf_status btdf_read(const char *path, btdf_input *in, char *msg, size_t msglen);

/* Reads path and prints its header and statistics to out. Errors as btdf_read, and
   BTDF_EIO when printing fails. */
BTDF_API btdf_status btdf_inspect(const char *path, FILE *out, char *msg, size_t msglen);

/* Writes len bytes to path the same atomic way (a temporary name ending in ext, which
   may be NULL, then a rename): for files that go beside the outputs (reports, stamps). */
BTDF_API btdf_status btdf_write_buffer(const char *path, const char *ext, const void *data,
                                       size_t len, char *msg, size_t msglen);

/* Writes to buf the shortest of %.15g, %.16g and %.17g of x that reads back (strtod)
   to the same double: "0.7", not "0.69999999999999996". Returns what snprintf returns
   (the length it needed); 32 bytes always suffice. Every number btdftab writes as
   text goes through it. */
BTDF_API int btdf_format_double(double x, char *buf, size_t len);

/* Removes the temporary files of the writes in progress; async-signal-safe, for a
   signal handler that then ends the process. */
BTDF_API void btdf_remove_partial_files(void);

/* Whether path may be written, before any work: its folder exists and is writable,
   its name is legal (at most 255 bytes), and what is there now, if anything, is a
   regular file (btdf_write never replaces a folder, device, pipe or link). BTDF_OK, or
   an error with msg saying why (without the path). Nothing is created. */
BTDF_API btdf_status btdf_output_check(const char *path, char *msg, size_t msglen);

/* 1 when a and b name the same file (the same inode, or the same folder and name when
   one does not exist yet), else 0: for refusing two outputs, or an output and an
   input, that are one file. */
BTDF_API int btdf_same_file(const char *a, const char *b);

/* Outputs of one run that appear together or not at all. After btdf_outputs_begin,
   every write of this process (btdf_write, btdf_write_buffer, ...) leaves its
   finished file under its temporary name; btdf_outputs_commit renames them all into
   place, or none: it fails if any write since begin failed, and if a rename fails,
   the outputs already renamed are undone and the earlier files put back.
   btdf_outputs_abort removes them. One group at a time, from one thread. */
BTDF_API void btdf_outputs_begin(void);
BTDF_API btdf_status btdf_outputs_commit(char *msg, size_t msglen);
BTDF_API void btdf_outputs_abort(void);

#ifdef __cplusplus
}
#endif

#endif /* BTDF_IO_H */
