/* SPDX-License-Identifier: MIT */
/* fuzz_scatfun.c: libFuzzer harness for the SCATFUN v1 reader and the evaluation of what it accepts. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

#include "btdf.h"
#include "btdf_scatfun.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    btdf_scatfun *f = NULL;
    char msg[256];
    if (btdf_scatfun_read_mem(data, size, &f, msg, sizeof msg) != BTDF_OK)
        return 0;
    /* an accepted file must evaluate anywhere without reading out of bounds */
    double out[3];
    static const double mus[] = {-1.0, -0.7, -0.01, 0.0, 0.3, 0.999, 1.0};
    for (size_t i = 0; i < sizeof mus / sizeof mus[0]; i++)
        for (size_t o = 0; o < sizeof mus / sizeof mus[0]; o++)
            btdf_scatfun_eval_mu(f, mus[i], mus[o], 0.5, 1, out);
    unsigned char *buf = NULL;
    size_t len = 0;
    if (btdf_scatfun_to_mem(f, NULL, &buf, &len, msg, sizeof msg) == BTDF_OK)
        free(buf);
    btdf_scatfun_free(f);
    return 0;
}
