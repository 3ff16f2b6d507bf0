/* SPDX-License-Identifier: MIT */
/* pathnorm.h: whether two output paths name one file, before their folders exist. */
#ifndef BTDF_PATHNORM_H
#define BTDF_PATHNORM_H

#include <stddef.h>

/* Writes into out the absolute form of path with "//", "." and ".." resolved and every
   symbolic link among its existing leading components followed (the part that does not
   exist yet holds no link, so it is resolved by its text). 1 on success, 0 if it does not
   fit in outlen or the working folder cannot be named. */
int path_normalise(const char *path, char *out, size_t outlen);

/* 1 if a and b name the same file, or will once their folders are made: btdf_same_file,
   or the same normalised path. */
int path_same(const char *a, const char *b);

#endif
