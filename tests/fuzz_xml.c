/* SPDX-License-Identifier: MIT */
/* fuzz_xml.c: libFuzzer harness for the Radiance BSDF XML reader and the lookups of what it accepts. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include "btdf.h"
#include "btdf_radiance.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    btdf_rad *r = NULL;
    char msg[256];
    if (btdf_rad_read_mem(data, size, &r, msg, sizeof msg) != BTDF_OK)
        return 0;
    /* an accepted file must be looked up anywhere without reading out of bounds, and
       give finite values */
    static const double ang[] = {0.0, 0.3, 1.0, 1.5, 1.5707963};
    int nch = btdf_rad_channels(r);
    for (size_t i = 0; i < sizeof ang / sizeof ang[0]; i++)
        for (size_t o = 0; o < sizeof ang / sizeof ang[0]; o++)
            for (int c = -1; c < nch; c++) {
                double v = btdf_rad_render(r, BTDF_SIDE_ENTER, c, ang[i], 3.14159265 - ang[o], 0.7);
                double w = btdf_rad_render(r, BTDF_SIDE_LEAVE, c, ang[i], 3.14159265 - ang[o], 2.1);
                if (!isfinite(v) || !isfinite(w))
                    abort();
            }
    btdf_rad_free(r);
    return 0;
}
