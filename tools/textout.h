/* SPDX-License-Identifier: MIT */
/* textout.h: what the tool's own text files (simulate's CSV and report, a pane's grid)
   print alike: numbers as shortest round-trip decimals, and the provenance comment. */
#ifndef BTDFTAB_TEXTOUT_H
#define BTDFTAB_TEXTOUT_H

#include <stdio.h>

/* x as the shortest decimal that reads back to it; a non-finite x as 0 (never NaN in a
   file). */
void text_num(FILE *f, double x);

/* "# provenance: PROV\n", control bytes as C escapes (\xHH); nothing when prov is NULL. */
void text_provenance(FILE *f, const char *prov);

#endif
