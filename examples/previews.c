/* SPDX-License-Identifier: MIT */
/* previews.c: writes the sample pictures of docs/formats.md (polar, montage, render). */
/* Usage: previews [picture folder [table folder]]; both default to the current one. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <btdf/btdf.h>

#define PI 3.14159265358979323846

static int check(btdf_status st, const char *what, const char *msg)
{
    if (st == BTDF_OK)
        return 0;
    fprintf(stderr, "previews: %s: %s (%s)\n", what, msg, btdf_strerror(st));
    return 1;
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : ".";
    char path[1024], msg[300] = "";
    int bad = 0;

    /* Fig. 5 of the paper: ti = 30, n = 1/1.4 and 1.4, s = 1, 3, 6. */
    btdf_params mats[6];
    const double ns[2] = {1.0 / 1.4, 1.4}, ss[3] = {1.0, 3.0, 6.0};
    for (int i = 0; i < 6; i++) {
        btdf_params_default(&mats[i]);
        mats[i].ior[0] = ns[i / 3];
        mats[i].smoothness = ss[i % 3];
    }
    btdf_preview_opts o;
    for (int half = 0; half < 2; half++) {
        double ti = 30.0;
        btdf_preview_opts_default(&o);
        o.kind = BTDF_PREVIEW_POLAR;
        o.materials = mats + 3 * half;
        o.nmaterials = 3;
        o.ti_deg = &ti;
        o.nti = 1;
        snprintf(path, sizeof path, "%s/polar-fig5-%s.png", dir, half ? "n1.4" : "n0.714");
        bad |= check(btdf_preview_write(&o, path, msg, sizeof msg), path, msg);
    }
    /* Several incident angles for one material. */
    double tis[4] = {0.0, 20.0, 40.0, 60.0};
    btdf_params fig7;
    btdf_params_default(&fig7);
    fig7.ior[0] = 1.411;
    fig7.smoothness = 2.5;
    btdf_preview_opts_default(&o);
    o.materials = &fig7;
    o.nmaterials = 1;
    o.ti_deg = tis;
    o.nti = 4;
    snprintf(path, sizeof path, "%s/polar-ti.png", dir);
    bad |= check(btdf_preview_write(&o, path, msg, sizeof msg), path, msg);

    /* Tables leaving glass (n = 1/1.5, s = 6), 0 to 60 degrees: the adaptive table at
       its default tolerance (built through reciprocity, kind facet-reciprocal, since
       n < 1), and a coarse uniform grid for comparison. */
    for (int k = 0; k < 2; k++) {
        btdf_table_opts to;
        btdf_table_opts_default(&to);
        to.params.ior[0] = 1.0 / 1.5;
        to.params.smoothness = 6.0;
        to.ti_min = 0.0;
        to.ti_max = 60.0 * PI / 180.0;
        if (k == 1) {
            to.kind = BTDF_TABLE_GRID;
            to.grid_ti = 7;
            to.grid_to = 46;
            to.grid_phi = 37;
        }
        btdf_table *t = NULL;
        btdf_status st = btdf_table_build(&to, &t, msg, sizeof msg);
        if (st != BTDF_OK && st != BTDF_EBUDGET)
            return check(st, "table", msg);
        /* The pictures should show a table that meets its tolerance; if the budget
           stopped refinement, draw the best table reached but fail. */
        if (st == BTDF_EBUDGET)
            bad |= check(st, "table", msg);
        const char *name = k ? "grid" : "facet";
        btdf_table_kind kind = btdf_table_get_kind(t);
        printf("%s table: %s, %zu slices, %zu nodes%s\n", name,
               kind == BTDF_TABLE_GRID ? "grid"
                                       : (kind == BTDF_TABLE_FACET ? "facet" : "facet-reciprocal"),
               btdf_table_slice_count(t), btdf_table_node_count(t),
               k ? "" : (st == BTDF_OK ? ", tolerance met" : ", TOLERANCE NOT MET"));
#if BTDF_HAVE_OPENEXR
        /* The table file the pictures are made from. */
        btdf_write_opts w = {NULL, "examples/previews", NULL};
        snprintf(path, sizeof path, "%s/table-%s.exr", argc > 2 ? argv[2] : dir, name);
        bad |= check(btdf_table_write(t, path, &w, msg, sizeof msg), path, msg);
#endif
        btdf_preview_opts_default(&o);
        o.kind = BTDF_PREVIEW_MONTAGE;
        o.table = t;
        snprintf(path, sizeof path, "%s/montage-%s.png", dir, name);
        bad |= check(btdf_preview_write(&o, path, msg, sizeof msg), path, msg);
        o.kind = BTDF_PREVIEW_RENDER;
        o.analytic = 1;
        snprintf(path, sizeof path, "%s/render-%s.png", dir, name);
        bad |= check(btdf_preview_write(&o, path, msg, sizeof msg), path, msg);
        btdf_table_free(t);
    }
    return bad;
}
