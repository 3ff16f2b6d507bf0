/* SPDX-License-Identifier: MIT */
/* manifest_read.c: a scene manifest's sections and keys into materials, every value
   checked as the options of the same names check it (the format: tools/manifest.c). */
#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "numparse.h"

#include "manifest_impl.h"
#include "pathnorm.h"
#include "run.h"

/* The keys of a section, in the order of material.key_line. */
static const char *const KEYS[NKEYS] = {"ior",     "smoothness", "k0",    "theta_i", "tolerance",
                                        "metric",  "sides",      "enter", "leave",   "bsdf",
                                        "part",    "model",      "xml",   "basis", "back",
                                        "thickness", "absorption", "grid", "grid_size"};
static int set_why(manifest *mf, const char *fmt, const char *a, const char *b)
{
    if (!mf->why[0])
        snprintf(mf->why, sizeof mf->why, fmt, a, b);
    return 0; /* the reader: an error at this line */
}

/* A number by the tool's one rule (numparse.h), or an error naming key and value. */
static int num(manifest *mf, const char *key, const char *s, double *out)
{
    const char *r = num_double(s, out);
    if (!r)
        return 1;
    snprintf(mf->why, sizeof mf->why, "%s '%.200s' %s", key, s, r);
    return 0;
}

static int split_outputs(manifest *mf, const char *key, const char *value, char **list, int *n)
{
    char *buf = malloc(strlen(value) + 1);
    if (!buf)
        return set_why(mf, "out of memory%s%s", "", "");
    strcpy(buf, value);
    int ok = 1;
    for (char *tok = strtok(buf, " \t,"); tok && ok; tok = strtok(NULL, " \t,")) {
        if (*n == MAX_OUTPUTS) {
            ok = set_why(mf, "'%s': at most 8 outputs%s", key, "");
            break;
        }
        const char *dir = tok[0] == '/' ? "" : mf->dir; /* relative to the manifest */
        list[*n] = malloc(strlen(dir) + strlen(tok) + 1);
        if (!list[*n]) {
            ok = set_why(mf, "out of memory%s%s", "", "");
            break;
        }
        strcpy(list[*n], dir);
        strcat(list[(*n)++], tok);
    }
    free(buf);
    if (ok && *n == 0)
        return set_why(mf, "'%s' names no file%s", key, "");
    return ok;
}

static int ends_with(const char *s, const char *x)
{
    size_t ls = strlen(s), lx = strlen(x);
    if (ls < lx)
        return 0;
    for (size_t i = 0; i < lx; i++) /* extensions in any case, as the formats' registry */
        if (tolower((unsigned char)s[ls - lx + i]) != tolower((unsigned char)x[i]))
            return 0;
    return 1;
}

/* A section that sets nothing is a mistake (a misspelt name, a lost block). */
int manifest_check_not_empty(manifest *mf)
{
    if (mf->n == 0)
        return 1;
    material *m = &mf->m[mf->n - 1];
    for (int k = 0; k < NKEYS; k++)
        if (m->key_line[k])
            return 1;
    snprintf(mf->why, sizeof mf->why, "material [%s] is empty (no keys)", m->name);
    mf->why_line = m->line;
    return 0;
}

int manifest_on_entry(void *user, const char *section, const char *key, const char *value,
                      int line)
{
    manifest *mf = user;
    if (!key) { /* a section header */
        if (!manifest_check_not_empty(mf))
            return 0;
        for (int i = 0; i < mf->n; i++)
            if (!strcmp(mf->m[i].name, section)) {
                snprintf(mf->why, sizeof mf->why, "material [%.100s] appears twice (first at "
                         "line %d)", section, mf->m[i].line);
                return 0;
            }
        if (mf->n == MAX_MATERIALS)
            return set_why(mf, "more than 64 materials%s%s", "", "");
        material *m = &mf->m[mf->n];
        if (strlen(section) >= sizeof m->name)
            return set_why(mf, "material name '%.100s' is longer than 63 bytes%s", section, "");
        mf->n++;
        memset(m, 0, sizeof *m);
        snprintf(m->name, sizeof m->name, "%s", section);
        btdf_params_default(&m->p);
        m->ti0 = 0.0;
        m->ti1 = 90.0;
        m->tol = 1e-3;
        m->metric = BTDF_METRIC_L1;
        m->sides = BTDF_SIDE_BOTH;
        m->part = BTDF_PART_TRANSMISSION;
        m->basis = BTDF_RAD_TREE3;
        pane_spec_default(&m->pane);
        m->grid_n[0] = 46; /* 2, 2 and 5 degrees: tabulate --back's default grid */
        m->grid_n[1] = 46;
        m->grid_n[2] = 37;
        m->line = line;
        return 1;
    }
    if (!section[0] || mf->n == 0)
        return set_why(mf, "'%.100s' before any [material] section%s", key, "");
    material *m = &mf->m[mf->n - 1];
    int ki = -1;
    for (int k = 0; k < NKEYS; k++)
        if (!strcmp(key, KEYS[k]))
            ki = k;
    if (ki < 0)
        return set_why(mf, "unknown key '%.100s' (known: ior, smoothness, k0, model, theta_i, "
                           "tolerance, metric, part, sides, enter, leave, bsdf, xml, basis, back, "
                           "thickness, absorption)%s", key, "");
    if (m->key_line[ki]) {
        snprintf(mf->why, sizeof mf->why, "'%s' given twice in [%s] (first at line %d)", key,
                 m->name, m->key_line[ki]);
        return 0;
    }
    m->key_line[ki] = line;
    if (ki == K_IOR) {
        int k = 0;
        const char *r = num_double_list_blanks(value, m->p.ior, 1, 3, &k);
        if (r || k == 2) {
            snprintf(mf->why, sizeof mf->why, "ior '%.200s': %s", value,
                     r ? r : "expected one number or three (R,G,B)");
            return 0;
        }
        m->p.channels = k;
        m->has_ior = 1;
    } else if (ki == K_S) {
        if (!num(mf, key, value, &m->p.smoothness))
            return 0;
        m->has_s = 1;
    } else if (ki == K_K0) {
        if (!num(mf, key, value, &m->p.k0))
            return 0;
    } else if (ki == K_MODEL) {
        if (!btdf_model_parse(value, &m->p.model))
            return set_why(mf, "model '%.100s': must be xu-sun, smith or full%s", value, "");
    } else if (ki == K_TOL) {
        if (!num(mf, key, value, &m->tol))
            return 0;
    } else if (ki == K_METRIC) {
        if (!run_parse_metric(value, &m->metric))
            return set_why(mf, "metric '%.100s': must be l1 or max%s", value, "");
    } else if (ki == K_THETA) {
        const char *colon = strchr(value, ':');
        if (!colon || colon - value >= 64)
            return set_why(mf, "theta_i '%.100s': expected A:B in degrees%s", value, "");
        char a[64];
        snprintf(a, sizeof a, "%.*s", (int)(colon - value), value);
        if (!num(mf, "theta_i", a, &m->ti0) || !num(mf, "theta_i", colon + 1, &m->ti1))
            return 0;
        if (!(m->ti0 >= 0 && m->ti0 <= m->ti1 && m->ti1 <= 90))
            return set_why(mf, "theta_i '%.100s': need 0 <= A <= B <= 90 degrees%s", value, "");
    } else if (ki == K_PART) {
        if (!btdf_part_parse(value, &m->part))
            return set_why(mf, "part '%.100s': must be transmission, reflection or both%s", value,
                           "");
    } else if (ki == K_SIDES) {
        if (!(m->sides = run_parse_side(value)))
            return set_why(mf, "sides '%.100s': must be enter, leave or both%s", value, "");
    } else if (ki == K_ENTER || ki == K_LEAVE) {
        char **list = ki == K_ENTER ? m->enter : m->leave;
        int *n = ki == K_ENTER ? &m->nenter : &m->nleave;
        if (!split_outputs(mf, key, value, list, n))
            return 0;
        for (int i = 0; i < *n; i++)
            if (!ends_with(list[i], ".csv") && !ends_with(list[i], ".exr") &&
                !ends_with(list[i], ".png"))
                return set_why(mf, "output '%.200s': tables are .csv, .exr or .png%s", list[i], "");
    } else if (ki == K_BSDF) {
        if (!split_outputs(mf, key, value, m->bsdf, &m->nbsdf))
            return 0;
        for (int i = 0; i < m->nbsdf; i++)
            if (!ends_with(m->bsdf[i], ".bsdf"))
                return set_why(mf, "output '%.200s': must end in .bsdf%s", m->bsdf[i], "");
    } else if (ki == K_XML) {
        if (!split_outputs(mf, key, value, m->xml, &m->nxml))
            return 0;
        for (int i = 0; i < m->nxml; i++)
            if (!ends_with(m->xml[i], ".xml"))
                return set_why(mf, "output '%.200s': must end in .xml%s", m->xml[i], "");
    } else if (ki == K_GRID) {
        if (!split_outputs(mf, key, value, m->grid, &m->ngrid))
            return 0;
        for (int i = 0; i < m->ngrid; i++)
            if (!ends_with(m->grid[i], ".csv") && !ends_with(m->grid[i], ".exr"))
                return set_why(mf, "output '%.200s': a pane's grid is .csv or .exr%s",
                               m->grid[i], "");
    } else if (ki == K_GRID_SIZE) {
        /* a grid needs two nodes on every axis (pane_write_table) */
        const char *r = num_size_list(value, 2, 100000, m->grid_n, 3);
        if (r)
            return set_why(mf, "grid_size '%.100s': %.200s (NI,NO,NPHI, as --grid)", value, r);
    } else if (ki >= K_BACK) {
        return pane_spec_set(&m->pane, key, value, mf->why, sizeof mf->why);
    } else if (ki == K_BASIS) {
        if (!btdf_rad_basis_parse(value, &m->basis))
            return set_why(mf, "basis '%.100s': must be tree3, klems-full, klems-half or "
                               "klems-quarter%s", value, "");
    }
    return 1;
}

void manifest_free(manifest *mf)
{
    for (int i = 0; i < mf->n; i++) {
        material *m = &mf->m[i]; /* the lists are NULL past their count (memset) */
        for (int k = 0; k < MAX_OUTPUTS; k++)
            free(m->enter[k]), free(m->leave[k]), free(m->bsdf[k]), free(m->xml[k]),
                free(m->grid[k]);
    }
}
