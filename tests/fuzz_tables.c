/* SPDX-License-Identifier: MIT */
/* fuzz_tables.c: libFuzzer harness for the table readers (CSV, and OpenEXR when built
   with -DFUZZ_EXR), and the evaluation of what they accept. */
#define _DEFAULT_SOURCE /* mkstemps */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "btdf.h"

#ifdef FUZZ_EXR
#define SUFFIX ".exr"
#else
#define SUFFIX ".csv"
#endif

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* The readers take a path: each input goes to one file, rewritten every time. */
static char path[256];
static int fd = -1;

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (fd < 0) {
        const char *d = getenv("TMPDIR");
        snprintf(path, sizeof path, "%s/fuzz-table-XXXXXX" SUFFIX, d && *d ? d : "/tmp");
        fd = mkstemps(path, (int)strlen(SUFFIX));
        if (fd < 0)
            abort();
    }
    if (ftruncate(fd, 0) != 0 || pwrite(fd, data, size, 0) != (ssize_t)size)
        abort();
    btdf_table *t = NULL;
    char msg[256];
    if (btdf_table_read(path, &t, msg, sizeof msg) != BTDF_OK)
        return 0;
    /* an accepted table evaluates anywhere without reading out of bounds, never NaN */
    static const double ti[] = {0.0, 0.3, 1.0, 1.5707963267948966};
    static const double to[] = {1.5707963267948966, 2.0, 2.8, 3.141592653589793};
    static const double ph[] = {0.0, 1.0, 3.141592653589793};
    double out[3];
    for (size_t i = 0; i < 4; i++)
        for (size_t o = 0; o < 4; o++)
            for (size_t p = 0; p < 3; p++)
                if (btdf_table_eval(t, ti[i], to[o], ph[p], out) == BTDF_OK)
                    for (int c = 0; c < btdf_table_get_params(t)->channels; c++)
                        if (!isfinite(out[c]))
                            abort();
    btdf_table_free(t);
    return 0;
}
