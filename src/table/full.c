/* SPDX-License-Identifier: MIT */
/* full.c: tables of the model full (docs/model.md section 12). The slices hold the
   single scattering, smith's, with its rules; the table keeps each channel's tally and
   adds its multiply scattered part at the query's own directions, so that part carries
   no table error: a full table's error is that of its smith slices, measured against
   full (smith's kernel plus the same tally) and relative to full's T. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "table/table.h"

btdf_params table_single_params(const btdf_params *p)
{
    btdf_params q = *p;
    if (q.model == BTDF_MODEL_FULL)
        q.model = BTDF_MODEL_SMITH;
    return q;
}

/* The index the tally of channel c is made for: the material's, whatever the kind. */
static btdf_status take_ms(btdf_table *t, const btdf_full *const *ms, char *msg,
                           size_t msglen)
{
    for (int c = 0; c < t->p.channels; c++) {
        if (!ms[c] || ms[c]->n != t->p.ior[c] || ms[c]->s != t->p.smoothness)
            return core_say(BTDF_EINVAL, msg, msglen,
                            "channel %d: the multiple scattering is of another material "
                            "(n %.9g, s %.9g; the table's n %.9g, s %.9g)",
                            c, ms[c] ? ms[c]->n : 0.0, ms[c] ? ms[c]->s : 0.0, t->p.ior[c],
                            t->p.smoothness);
    }
    btdf_full *got[BTDF_MAX_CHANNELS] = {NULL, NULL, NULL};
    for (int c = 0; c < t->p.channels; c++) {
        got[c] = full_clone(ms[c]);
        if (!got[c]) {
            for (int d = 0; d < c; d++)
                btdf_full_free(got[d]);
            return core_say(BTDF_ENOMEM, msg, msglen, "out of memory");
        }
    }
    for (int c = 0; c < t->p.channels; c++) {
        btdf_full_free(t->ms[c]);
        t->ms[c] = got[c];
    }
    t->p.model = BTDF_MODEL_FULL;
    return BTDF_OK;
}

btdf_status table_make_full(btdf_table *t, const btdf_full *const *ms, char *msg,
                            size_t msglen)
{
    if (!t || !ms || t->kind == BTDF_TABLE_GRID)
        return core_say(BTDF_EINVAL, msg, msglen, "model full: needs a facet table");
    if (t->refl) {
        btdf_status st = take_ms(t->refl, ms, msg, msglen);
        if (st != BTDF_OK)
            return st;
    }
    return take_ms(t, ms, msg, msglen);
}

void table_strip_full(btdf_table *t)
{
    for (int c = 0; c < BTDF_MAX_CHANNELS; c++) {
        btdf_full_free(t->ms[c]);
        t->ms[c] = NULL;
    }
    if (t->p.model == BTDF_MODEL_FULL)
        t->p.model = BTDF_MODEL_SMITH;
}

void table_add_ms(const btdf_table *t, double ti, double cti, double cto, double cph,
                  double *out)
{
    if (t->p.model != BTDF_MODEL_FULL)
        return;
    /* outside the tabulated incidence range the table is 0 (btdf.h); a reciprocal table
       covers every ti */
    if (t->kind != BTDF_TABLE_FACET_RECIPROCAL &&
        (t->ns == 0 || !(ti >= t->s[0].ti && ti <= t->s[t->ns - 1].ti)))
        return;
    double mu = fabs(cto);
    if (!(cti > 0.0) || !(mu > 0.0))
        return; /* grazing in or out: no flux crosses, as btdf_full_rho_deg */
    int refl = kind_is_reflection(t->kind);
    for (int c = 0; c < t->p.channels; c++)
        if (t->ms[c]) /* the same expression as the estimate's truth (estimate.c) */
            out[c] += full_ms(t->ms[c], refl, ti * (180.0 / M_PI), mu, cph);
}

btdf_status table_estimate_full(const btdf_table *t, double ti_min, double ti_max,
                                size_t test_angles, size_t points_per_angle, uint64_t seed,
                                int threads, const double *knots, size_t nk, est_eval_fn fn,
                                btdf_report *r)
{
    est_opts opt;
    memset(&opt, 0, sizeof opt);
    opt.full = t->ms;
    int refl = kind_is_reflection(t->kind);
    btdf_status st = est_knots_part_opt(&t->p, refl, ti_min, ti_max, test_angles,
                                                  points_per_angle, seed, threads, knots, nk,
                                                  fn, t, &opt, r);
    if (st != BTDF_OK)
        return st;
    r->ms_noise = 0.0;
    for (int c = 0; c < t->p.channels; c++)
        r->ms_noise = fmax(r->ms_noise, full_ms_noise(t->ms[c], refl, ti_min, ti_max));
    return BTDF_OK;
}

/* ------------------------------------------------------------------------- */
/* The tally in a file                                                        */
/* ------------------------------------------------------------------------- */

char *table_ms_write(const btdf_table *t, int c)
{
    const btdf_full *f = c >= 0 && c < t->p.channels ? t->ms[c] : NULL;
    if (!f)
        return NULL;
    size_t cap = 96 + (size_t)f->nodes * (FULL_NODE_TEXT_MAX + 1), at;
    char *buf = malloc(cap);
    if (!buf)
        return NULL;
    int w = snprintf(buf, cap, "paths %llu seed %llu nodes %d\n", (unsigned long long)f->paths,
                     (unsigned long long)f->seed, f->nodes);
    at = w > 0 ? (size_t)w : 0;
    for (int k = 0; k < f->nodes; k++) {
        w = full_node_text(f, k, buf + at, cap - at - 1);
        if (w < 0 || (size_t)w >= cap - at - 1) {
            free(buf); /* a node is far below FULL_NODE_TEXT_MAX: not reached */
            return NULL;
        }
        at += (size_t)w;
        buf[at++] = '\n';
        buf[at] = '\0';
    }
    return buf;
}

btdf_status table_ms_text_add(table_ms_text *m, int c, const char *line, char *msg,
                              size_t msglen)
{
    if (c < 0 || c >= BTDF_MAX_CHANNELS)
        return core_say(BTDF_EFORMAT, msg, msglen,
                        "multiple scattering of channel %d: channels are 0 to %d", c,
                        BTDF_MAX_CHANNELS - 1);
    size_t n = strcspn(line, "\r\n"), have = m->len[c];
    if (have + n + 2 > (size_t)(96 + FULL_NODES_MAX * (FULL_NODE_TEXT_MAX + 1)))
        return core_say(BTDF_EFORMAT, msg, msglen,
                        "multiple scattering of channel %d: more text than %d nodes hold", c,
                        FULL_NODES_MAX);
    char *g = realloc(m->text[c], have + n + 2);
    if (!g)
        return core_say(BTDF_ENOMEM, msg, msglen, "out of memory");
    memcpy(g + have, line, n);
    g[have + n] = '\n';
    g[have + n + 1] = '\0';
    m->text[c] = g;
    m->len[c] = have + n + 1;
    return BTDF_OK;
}

void table_ms_text_free(table_ms_text *m)
{
    for (int c = 0; c < BTDF_MAX_CHANNELS; c++) {
        free(m->text[c]);
        m->text[c] = NULL;
        m->len[c] = 0;
    }
}

/* One channel's text (table_ms_text) into its object. */
static btdf_status ms_parse(const char *text, double n, double s, btdf_full **out, char *msg,
                            size_t msglen)
{
    unsigned long long paths, seed;
    int nodes, used = 0;
    if (sscanf(text, "paths %llu seed %llu nodes %d%n", &paths, &seed, &nodes, &used) != 3 ||
        text[used] != '\n')
        return core_say(BTDF_EFORMAT, msg, msglen, "multiple scattering: the first line must "
                        "be 'paths P seed S nodes N'");
    if (nodes < 2 || nodes > FULL_NODES_MAX || paths < 1 || paths > BTDF_FULL_PATHS_MAX)
        return core_say(BTDF_EFORMAT, msg, msglen, "multiple scattering: %d nodes of %llu "
                        "paths: must be 2 to %d nodes of 1 to %llu paths", nodes, paths,
                        FULL_NODES_MAX, (unsigned long long)BTDF_FULL_PATHS_MAX);
    const char *lines[FULL_NODES_MAX];
    const char *p = text + used + 1;
    int k = 0;
    while (*p && k < FULL_NODES_MAX) {
        lines[k++] = p;
        p += strcspn(p, "\n");
        if (*p)
            p++;
    }
    if (k != nodes || *p)
        return core_say(BTDF_EFORMAT, msg, msglen, "multiple scattering: %d node lines, the "
                        "first line says %d", k + (*p ? 1 : 0), nodes);
    /* full_from_text reads each line up to its end: cut them apart in a copy */
    size_t len = strlen(text);
    char *cp = malloc(len + 1);
    if (!cp)
        return core_say(BTDF_ENOMEM, msg, msglen, "out of memory");
    memcpy(cp, text, len + 1);
    for (char *q = cp; *q; q++)
        if (*q == '\n')
            *q = '\0';
    for (int i = 0; i < k; i++)
        lines[i] = cp + (lines[i] - text);
    btdf_status st = full_from_text(n, s, paths, seed, lines, nodes, out, msg, msglen);
    free(cp);
    return st;
}

btdf_status table_full_from_text(btdf_table *t, btdf_model model, const table_ms_text *m,
                                 char *msg, size_t msglen)
{
    if (model != BTDF_MODEL_FULL) {
        for (int c = 0; c < BTDF_MAX_CHANNELS; c++)
            if (m->text[c])
                return core_say(BTDF_EFORMAT, msg, msglen, "multiple scattering in a table "
                                "of model %s (only full has it)", btdf_model_name(model));
        return BTDF_OK;
    }
    const btdf_full *ms[BTDF_MAX_CHANNELS] = {NULL, NULL, NULL};
    btdf_full *own[BTDF_MAX_CHANNELS] = {NULL, NULL, NULL};
    btdf_status st = BTDF_OK;
    for (int c = 0; c < t->p.channels && st == BTDF_OK; c++) {
        if (!m->text[c]) {
            st = core_say(BTDF_EFORMAT, msg, msglen, "model full but no multiple scattering "
                          "for channel %d (the tally is part of the table)", c);
            break;
        }
        st = ms_parse(m->text[c], t->p.ior[c], t->p.smoothness, &own[c], msg, msglen);
        ms[c] = own[c];
    }
    for (int c = t->p.channels; c < BTDF_MAX_CHANNELS && st == BTDF_OK; c++)
        if (m->text[c])
            st = core_say(BTDF_EFORMAT, msg, msglen, "multiple scattering for channel %d of "
                          "a table of %d", c, t->p.channels);
    if (st == BTDF_OK)
        st = table_make_full(t, ms, msg, msglen);
    for (int c = 0; c < BTDF_MAX_CHANNELS; c++)
        btdf_full_free(own[c]);
    return st;
}
