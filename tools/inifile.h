/* SPDX-License-Identifier: MIT */
/* inifile.h: a reader of INI files with lines of any length and the line of every entry. */
#ifndef BTDF_INIFILE_H
#define BTDF_INIFILE_H

#include <stddef.h>

/*
 * Syntax: blank lines; comment lines starting with ';' or '#'; "[name]" opens a
 * section; "key = value" sets a key in it. A ';' or '#' after a blank ends the value
 * (an inline comment). Blanks around names, keys and values are dropped. Lines may be
 * of any length; a NUL byte is an error.
 *
 * The callback gets every section header (key and value NULL) and every entry, with
 * its line (from 1), and returns 0 to stop with an error at that line.
 */
typedef int (*ini_handler)(void *user, const char *section, const char *key,
                           const char *value, int line);

/* 0 when the whole file was read; the line of the first error (syntax, or the
   handler's) with why set for a syntax error; -1 when the file cannot be read, with
   why set (a folder, a missing file, a read error). */
int ini_read(const char *path, ini_handler fn, void *user, char *why, size_t whylen);

#endif
