/* SPDX-License-Identifier: MIT */
/* stamp.h: the stamps of manifest outputs and their folders (stamp.c). */
#ifndef BTDFTAB_STAMP_H
#define BTDFTAB_STAMP_H

#include <stddef.h>

/* Why out must be (re)built against its stamp text, or NULL when it is up to date. */
const char *why_stale(const char *out, const char *stamp, int force);
int up_to_date(const char *out, const char *stamp);
/* Creates the missing folders of path; 0 on failure. */
int make_parents(const char *path);
/* Whether path's folder exists (*exists) or can be created (0 and why when not). */
int parents_creatable(const char *path, int *exists, char *why, size_t whylen);
/* Writes the stamp of a file just written (the stamp text, then its size and hash). */
int write_stamp_for(const char *out, const char *stamp);

#endif
