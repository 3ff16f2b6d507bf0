/* SPDX-License-Identifier: MIT */
/* numparse.h: the one reader of numbers for command-line options and manifest values. */
#ifndef BTDF_NUMPARSE_H
#define BTDF_NUMPARSE_H

#include <stddef.h>

/*
 * Every function returns NULL on success, or a short reason ("is not a number", "is out
 * of range ...") that the caller puts after the option name and the value. The text
 * must be the number and nothing else: no blanks, no hexadecimal, no inf or nan.
 */

/* A decimal number: [+-] digits [. digits] [e [+-] digits] (or . digits), finite, and
   representable: magnitudes above DBL_MAX or below DBL_MIN (other than 0) are out of
   range. */
const char *num_double(const char *s, double *out);

/* A whole number in [lo, hi], decimal digits only (an optional leading +). */
const char *num_size(const char *s, size_t lo, size_t hi, size_t *out);

/* n comma-separated numbers, min_n <= n <= max_n, each as num_double. */
const char *num_double_list(const char *s, double *out, int min_n, int max_n, int *n);

/* num_double_list with blanks (spaces, tabs) around the commas allowed, as around a
   manifest's values; at most 255 bytes. */
const char *num_double_list_blanks(const char *s, double *out, int min_n, int max_n, int *n);

/* n comma-separated whole numbers, each in [lo, hi], exactly want of them. */
const char *num_size_list(const char *s, size_t lo, size_t hi, size_t *out, int want);

#endif
