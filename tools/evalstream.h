/* SPDX-License-Identifier: MIT */
/* evalstream.h: `btdftab eval` on rows from a stream, in blocks, on several threads,
   with the output in input order (the same bytes whatever the thread count). */
#ifndef BTDF_EVALSTREAM_H
#define BTDF_EVALSTREAM_H

#include <stdio.h>

#include <btdf/btdf.h>

/* Reads rows "TI TO PHI" (degrees; blanks or commas between; '#' starts a comment;
   blank lines are skipped) and writes one line of %.17g values per row: rho, or with
   reflection set rho_r of rows "TI TR PHI". Returns 0; 2 at the first bad row, after
   writing every row before it, with the message in err; 1 when reading or writing
   fails (message in err). threads: 0 = all cores. */
int eval_stream(FILE *in, FILE *out, const btdf_params *p, int reflection, int threads,
                char *err, size_t errlen);

#endif
