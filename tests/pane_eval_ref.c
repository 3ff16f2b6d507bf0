/* SPDX-License-Identifier: MIT */
/* pane_eval_ref.c: btdf_pane_eval of a pane with a flat or rough back, for pane_cli.sh to
   hold `btdftab eval --back` against: pane_eval_ref N S BACK(smooth|S) D A SIDE(front|back)
   PART(t|r) TI TO PHI (degrees), one value in %.17g. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "btdf_pane.h"

int main(int argc, char **argv)
{
    if (argc != 11) {
        fprintf(stderr, "usage: pane_eval_ref N S BACK D A SIDE PART TI TO PHI\n");
        return 2;
    }
    btdf_pane_opts o;
    btdf_pane_opts_default(&o);
    o.front.ior[0] = atof(argv[1]);
    o.front.smoothness = atof(argv[2]);
    o.back_smooth = !strcmp(argv[3], "smooth");
    o.back_smoothness = o.back_smooth ? o.front.smoothness : atof(argv[3]);
    o.thickness_mm = atof(argv[4]);
    o.absorption_per_mm = atof(argv[5]);
    btdf_pane *P = NULL;
    char msg[256] = "";
    if (btdf_pane_new(&o, &P, msg, sizeof msg) != BTDF_OK) {
        fprintf(stderr, "pane_eval_ref: %s\n", msg);
        return 1;
    }
    const double d = 3.14159265358979323846 / 180.0;
    double v = btdf_pane_eval(P, !strcmp(argv[6], "back") ? BTDF_PANE_BACK : BTDF_PANE_FRONT,
                              argv[7][0] == 'r' ? BTDF_PART_REFLECTION : BTDF_PART_TRANSMISSION,
                              0, atof(argv[8]) * d, atof(argv[9]) * d, atof(argv[10]) * d);
    printf("%.17g\n", v);
    btdf_pane_free(P);
    return 0;
}
