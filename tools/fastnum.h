/* SPDX-License-Identifier: MIT */
/* fastnum.h: decimal parsing and printing of doubles for streaming rows, with the
   results of strtod and printf("%.17g") byte for byte, at a fraction of their cost. */
#ifndef BTDF_FASTNUM_H
#define BTDF_FASTNUM_H

/* strtod's value and end pointer for every input (errno as strtod sets it on the rare
   inputs the fast path hands over to strtod). Plain decimals of up to 19 significant
   digits and a power of ten within 10^+-22 are converted exactly without strtod. */
double fastnum_strtod(const char *s, char **end);

/* Writes x as printf("%.17g", x) would, with a terminating NUL, into buf (at least
   32 bytes); returns the length. Digits come from an extended-precision product,
   checked against the rounding boundary; where it is too close to decide, printf
   decides. */
int fastnum_g17(double x, char *buf);

#endif
