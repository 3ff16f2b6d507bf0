/* SPDX-License-Identifier: MIT */
/* numfmt.c: the shortest decimal that reads back to the same double. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "btdf.h"

/* Of %.15g, %.16g and %.17g, the shortest text that strtod reads back exactly.
   17 significant digits always do for an IEEE double (DBL_DECIMAL_DIG), and 15 keep
   any decimal written with at most 15, so 0.7 prints as "0.7". Fewer digits can mean
   more characters (1.2345678901234567e16 is "12345678901234568" at 17 digits but
   "1.234567890123457e+16" at 16), hence the comparison of lengths. Below 15 digits
   a shorter round-trip string may exist; %g drops trailing zeros, which is what a
   reader sees. */
BTDF_API int btdf_format_double(double x, char *buf, size_t len)
{
    char best[40] = "", tmp[40];
    if (!buf || len == 0)
        return -1;
    if (!isfinite(x)) /* no output of this library holds one; say what it is anyway */
        return snprintf(buf, len, "%s", isnan(x) ? "nan" : (x > 0 ? "inf" : "-inf"));
    for (int prec = 17; prec >= 15; prec--) {
        snprintf(tmp, sizeof tmp, "%.*g", prec, x);
        if (prec == 17 || (strtod(tmp, NULL) == x && strlen(tmp) <= strlen(best)))
            memcpy(best, tmp, sizeof best);
    }
    return snprintf(buf, len, "%s", best);
}
