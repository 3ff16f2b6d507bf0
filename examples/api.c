/* SPDX-License-Identifier: MIT */
/* api.c: evaluate the model, build, query and write a table through the installed library. */
#include <btdf/btdf.h>
#include <stdio.h>

int main(void)
{
    btdf_table_opts o;
    btdf_table_opts_default(&o);            /* n = 1.5, s = 3, tolerance 1e-3 */
    o.params.smoothness = 6;
    o.ti_max = 1.0;                         /* incidence 0 to 1 rad is all this scene needs */
    double rho = 0.0, tab = 0.0;
    btdf_eval(&o.params, 0.5, 2.7, 3.1, &rho); /* radians: ti, to, phi */
    btdf_table *t = NULL;
    char msg[256] = "";
    btdf_status st = btdf_table_build(&o, &t, msg, sizeof msg);
    if (st == BTDF_OK)
        st = btdf_table_eval(t, 0.5, 2.7, 3.1, &tab);
    if (st == BTDF_OK)
        st = btdf_table_write(t, "api-example.csv", NULL, msg, sizeof msg);
    printf("libbtdf %s: rho %.6g, table %.6g: %s %s\n", btdf_version_string(), rho, tab,
           btdf_strerror(st), msg);
    btdf_table_free(t);
    return st == BTDF_OK ? 0 : 1;
}
