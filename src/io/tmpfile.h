/* SPDX-License-Identifier: MIT */
/* tmpfile.h: temporary names of files being written, removable from a signal handler. */
#ifndef BTDF_TMPFILE_H
#define BTDF_TMPFILE_H

#include <stddef.h>
#include <stdio.h>

#include "btdf.h"

/* Writes into tmp a fresh temporary name beside path (random digits), ending in ext (may
   be NULL), and records it as being written; nothing is created. Returns the slot to pass
   to tmp_end (>= 0); -1 when it could not be recorded (tmp usable, just not removed
   on a signal); -2 when the name does not fit in tmplen (tmp unusable). */
int tmp_begin(const char *path, const char *ext, char *tmp, size_t tmplen);

/* The write of that slot has ended (renamed or removed). */
void tmp_end(int slot);

/* Removes every file being written; async-signal-safe, for signal handlers. */
void tmp_remove_all(void);

/* Writes the file into f, a new empty file opened for writing under the temporary name
   tmp (for messages; never to be opened again by name). The writer does not close f.
   BTDF_OK or an error with msg set. */
typedef btdf_status (*io_file_writer)(void *ctx, FILE *f, const char *tmp, char *msg,
                                        size_t msglen);

/* Writes path through writer under a recorded temporary name ending in ext, created with
   O_CREAT|O_EXCL|O_NOFOLLOW (so a planted link is never followed) and mode 0666 less the
   umask, and renames it into place; on any error the temporary file is removed and
   nothing is left at path. Refuses (BTDF_EINVAL) to replace what is not a regular file. */
btdf_status io_write_file_atomic(const char *path, const char *ext, io_file_writer writer,
                                   void *ctx, char *msg, size_t msglen);

/* Removes, from the folder of path, temporary files of this scheme
   (`.NAME.btdftmpR.EXT`, R sixteen hexadecimal digits) that are regular files of this
   user, older than a minute and locked by no writer (theirs was killed outright);
   returns how many. io_write_file_atomic calls it before each write. */
size_t tmp_sweep(const char *path);

/* 1 if name (a directory entry) has the shape of this scheme's temporaries, else 0. */
int tmp_name_ours(const char *name);

/* btdf_output_check and btdf_same_file are public: btdf_io.h. */

/* Outputs of one run that appear together or not at all. Between group_begin and
   group_commit, every io_write_file_atomic of this process leaves its finished file
   under its temporary name; commit renames them all into place (if one rename fails,
   those already renamed are undone and the earlier files put back: kept as hard links,
   or as copies where links are refused), and fails without renaming anything if any
   write of the group failed or an earlier file cannot be kept. SIGINT, SIGTERM, SIGHUP
   and SIGQUIT wait while the files are renamed, and tmp_remove_all run from a
   handler in another thread completes the renames: a group is never left half new.
   abort removes them. One group at a time, from one thread. */
void tmp_group_begin(void);
btdf_status tmp_group_commit(char *msg, size_t msglen);
void tmp_group_abort(void);

/* A writer for bytes in memory: ctx is a io_bytes. */
typedef struct io_bytes {
    const void *data;
    size_t len;
} io_bytes;
btdf_status io_write_bytes(void *ctx, FILE *f, const char *tmp, char *msg, size_t msglen);

#endif
