/* SPDX-License-Identifier: MIT */
/* pane_write.h: a pane's description (--back, --thickness, --absorption, or the manifest's
   keys back, thickness, absorption) and its system written to a Radiance .xml, shared by
   tabulate and build (tools/cmd_pane.c). */
#ifndef PANE_WRITE_H
#define PANE_WRITE_H

#include <stddef.h>

#include <btdf/btdf.h>

typedef struct pane_spec {
    int back_smooth;   /* 1: the back face is flat */
    double back_s;     /* its smoothness when rough */
    double thickness;  /* mm */
    double absorption; /* per mm */
} pane_spec;

/* A flat back, 4 mm (simulate's default), no absorption. */
void pane_spec_default(pane_spec *ps);

/* Sets the value of key "back", "thickness" or "absorption" with the checks of the options
   of the same names: 1, or 0 with why naming the value and what is allowed. */
int pane_spec_set(pane_spec *ps, const char *key, const char *value, char *why, size_t len);

/* Why a manifest section's pane keys are refused, as tabulate --back refuses the
   options, or NULL: back given, thickness or absorption given, the number of enter and
   leave outputs, whether a key for tables is given (tolerance counts only without a bsdf
   output), the channels a tree3 .xml or a .bsdf is asked with (1 when none is: a Klems
   .xml and a grid take three), the number of bsdf outputs, and whether the back is flat. */
const char *pane_keys_refusal(int back, int thick_abs, int interface_outputs,
                              int table_keys, int channels, int bsdf_outputs, int back_smooth);

/* Writes the system of the pane whose front face is p to path in the basis (a tree3
   adaptive with merge > 0: btdf_rad_source.merge); 0, or the exit code after a message
   on stderr. */
int pane_write_xml(const char *path, const btdf_params *p, const pane_spec *ps,
                   btdf_rad_basis basis, double merge, int threads, int quiet,
                   const char *prov);

/* The pane whose front face is p and the rest ps, on threads threads; 0, or the exit
   code after a message on stderr. */
struct btdf_pane;
int pane_make(const btdf_params *p, const pane_spec *ps, int threads, struct btdf_pane **out);

/* Writes the system of pane P on a regular grid of nti x nto x nphi nodes a block to
   path, .csv (every block, the sides and parts named in each row) or .exr (grid tables,
   the other blocks as layers), with the grid's error (tools/pane_table.c); 0, or the
   exit code after a message on stderr. */
int pane_write_table(const char *path, const struct btdf_pane *P, size_t nti, size_t nto,
                     size_t nphi, int quiet, const char *prov);

/* Writes the system of pane P to a SCATFUN .bsdf at tolerance tol (e_L1 of the file
   against the system, tools/pane_bsdf.c); 0, 3 when the tolerance was not met (no
   file), or the exit code after a message on stderr. */
int pane_write_bsdf(const char *path, const struct btdf_pane *P, double tol, int threads,
                    int quiet, const char *prov);

#endif
