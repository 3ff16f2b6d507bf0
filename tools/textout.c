/* SPDX-License-Identifier: MIT */
/* textout.c: numbers and the provenance line of the tool's own text files. */
#include "textout.h"

#include <math.h>

#include <btdf/btdf_io.h>

void text_num(FILE *f, double x)
{
    char b[40];
    btdf_format_double(isfinite(x) ? x : 0.0, b, sizeof b); /* never NaN in a file */
    fputs(b, f);
}

void text_provenance(FILE *f, const char *prov)
{
    if (!prov)
        return;
    fputs("# provenance: ", f);
    for (const unsigned char *c = (const unsigned char *)prov; *c; c++) {
        if (*c < 0x20 || *c == 0x7f)
            fprintf(f, "\\x%02x", *c); /* control bytes as C escapes */
        else
            fputc(*c, f);
    }
    fputc('\n', f);
}
