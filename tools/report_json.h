/* SPDX-License-Identifier: MIT */
/* report_json.h: a btdf_report as JSON, the --report file of every output kind. */
#ifndef BTDFTAB_REPORT_JSON_H
#define BTDFTAB_REPORT_JSON_H

#include <btdf/btdf.h>

/* A table's report (docs/tables.md): r is the table's first part's, r2 the reflection's
   of a table holding both parts, or NULL. Written atomically at path; 0, or 1 after a
   message "prog: path: why" on standard error. */
int report_json_table(const char *prog, const char *path, const btdf_table_opts *o,
                      btdf_table_kind kind, const btdf_report *r, const char *prov,
                      const btdf_report *r2);

#endif
