/* SPDX-License-Identifier: MIT */
/* csv.c: tables as CSV, one row per node, with everything needed to rebuild them exactly. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "formats/formats.h"
#include "table/table.h"

/*
 * Layout (docs/formats.md): a header row; then comment lines starting with '#' carry
 * the version, the kind, the parameters and the error report; then one row per node,
 * slice by slice, row by row, column by column:
 *   theta_i_deg, theta_o_deg, phi_deg, rho (or rho_r, rho_g, rho_b), ti_rad, row_rad, col_rad
 * The three *_rad columns are the node coordinates the rule uses (for facet tables
 * row = facet tilt tn and col = facet azimuth psi; for grid tables row = to, col = phi),
 * printed as the shortest decimal that reads back to the same double, so that they
 * and rho read back bit for bit.
 * theta_o_deg and phi_deg give the node's outgoing direction for people (for facet
 * tables that of channel 0; empty where no facet refracts into the lower hemisphere).
 * A comment line "# rows: N" before the first node row gives the number of them, and
 * the last line is "# end: N rows": a file cut anywhere, or missing rows, is refused.
 * Files of btdftab 0.3.0 and earlier have neither line (nor the part column): they are
 * read to their end, which must be a complete line (docs/formats.md).
 * A file holding both parts (transmission and reflection, docs/formats.md) has a last
 * column, part, and a "# parts:" line; the reflection's rows follow the transmission's.
 */

/* pre, the shortest decimal that reads back to x, post. */
static void put_num(FILE *f, const char *pre, double x, const char *post)
{
    char b[40];
    btdf_format_double(x, b, sizeof b);
    fprintf(f, "%s%s%s", pre, b, post);
}

/* Writes to b the shortest decimal of the angle deg (degrees) that a reader converting
   degrees as the command line does (d * M_PI / 180.0) turns into rad: "30", not
   "29.999999999999996", and every digit a grid step of 90/89 deg needs; no exponent
   above 1e-4 deg, where %g has a fixed form. Failing that, the shortest form of a
   double within 8 ulps of deg that converts to rad; and where none does
   (d * M_PI / 180.0 rounds twice and skips some doubles: 10,800 of the 72,900 angles
   of --grid 90,90,3), the shortest form that reads back to deg. Readers take the *_rad columns,
   which always read back exactly; the degrees are for people. */
static void fmt_angle(char *b, size_t len, double deg, double rad)
{
    for (int prec = 1; prec <= 17; prec++) {
        snprintf(b, len, "%.*g", prec, deg);
        if (strchr(b, 'e') && fabs(deg) >= 1e-4) /* "9e+01": more digits give "90" */
            continue;
        if (strtod(b, NULL) * M_PI / 180.0 == rad)
            return;
    }
    /* deg = rad * 180 / M_PI rounds twice: a neighbour a few ulps off may be the one */
    double lo = deg, hi = deg;
    for (int k = 0; k < 8; k++) {
        lo = nextafter(lo, -HUGE_VAL);
        hi = nextafter(hi, HUGE_VAL);
        if (hi * M_PI / 180.0 == rad || lo * M_PI / 180.0 == rad) {
            btdf_format_double(hi * M_PI / 180.0 == rad ? hi : lo, b, len);
            return;
        }
    }
    btdf_format_double(deg, b, len);
}

/* fmt_angle of an angle known in degrees only (the facet nodes' outgoing directions). */
static void fmt_deg(char *b, size_t len, double deg)
{
    fmt_angle(b, len, deg, deg * M_PI / 180.0);
}

/* The node rows of one part's table; suffix ends each row (",reflection\n" in a file
   holding both parts, "\n" otherwise). */
static void csv_rows(FILE *f, const btdf_table *t, const char *suffix)
{
    const btdf_params *p = &t->p;
    int nch = p->channels;
    int refl = kind_is_reflection(t->kind);
    for (size_t k = 0; k < t->ns; k++) {
        const tslice *s = &t->s[k];
        double ti = s->ti, sti = sin(ti), cti = cos(ti);
        int recip = t->kind == BTDF_TABLE_FACET_RECIPROCAL;
        double n0 = recip ? 1.0 / p->ior[0] : p->ior[0]; /* the slices' own index */
        rho_in a;
        rho_in_init(&a, sti, cti, p->smoothness, p->k0);
        /* A grid's angles repeat along its rows and columns: each formatted once (the
           search of fmt_angle costs up to 17 conversions). No memory: per node. */
        char ti_k[40], to_i[40] = "";
        fmt_angle(ti_k, sizeof ti_k, ti * 180.0 / M_PI, ti);
        int grid = t->kind == BTDF_TABLE_GRID;
        char (*ph_j)[40] = grid ? malloc(s->nc * sizeof *ph_j) : NULL;
        for (size_t j = 0; ph_j && j < s->nc; j++)
            fmt_angle(ph_j[j], sizeof ph_j[j], s->cols[j] * 180.0 / M_PI, s->cols[j]);
        for (size_t i = 0; i < s->nr; i++) {
            if (grid)
                fmt_angle(to_i, sizeof to_i, s->rows[i] * 180.0 / M_PI, s->rows[i]);
            for (size_t j = 0; j < s->nc; j++) {
                char ti_s[40], to_s[40] = "", ph_s[40] = "";
                memcpy(ti_s, ti_k, sizeof ti_s);
                if (grid) {
                    memcpy(to_s, to_i, sizeof to_s);
                    if (ph_j)
                        memcpy(ph_s, ph_j[j], sizeof ph_s);
                    else
                        fmt_angle(ph_s, sizeof ph_s, s->cols[j] * 180.0 / M_PI, s->cols[j]);
                } else {
                    facet_geo g;
                    double stn = sin(s->rows[i]), ctn = cos(s->rows[i]);
                    double cps = cos(s->cols[j]), sps = sin(s->cols[j]);
                    if (refl ? facet_eval_r(n0, p->smoothness, p->k0, &a, stn, ctn, cps, sps, &g)
                             : facet_eval(n0, p->smoothness, p->k0, &a, stn, ctn, cps, sps, &g)) {
                        double to = atan2(g.sin_to, g.cos_to) * 180.0 / M_PI;
                        if (recip) { /* the node's directions for light leaving: swapped */
                            fmt_deg(ti_s, sizeof ti_s, 180.0 - to);
                            to = 180.0 - ti * 180.0 / M_PI;
                        }
                        fmt_deg(to_s, sizeof to_s, to);
                        fmt_deg(ph_s, sizeof ph_s, fabs(atan2(g.sin_phi, g.cos_phi)) * 180.0 / M_PI);
                    }
                }
                fprintf(f, "%s,%s,%s", recip && !to_s[0] ? "" : ti_s, to_s, ph_s);
                for (int ch = 0; ch < nch; ch++)
                    put_num(f, ",", s->vals[(i * s->nc + j) * (size_t)nch + (size_t)ch], "");
                put_num(f, ",", ti, "");
                put_num(f, ",", s->rows[i], "");
                put_num(f, ",", s->cols[j], suffix);
            }
        }
        free(ph_j);
    }
}

static void csv_error_line(FILE *f, const char *key, const btdf_report *r)
{
    fprintf(f,
            "# %s: e_L1 max %.4g mean %.4g; e_max max %.4g mean %.4g; e_T max %.4g mean "
            "%.4g; %zu test angles, %zu test points\n",
            key, r->e_l1_max, r->e_l1_mean, r->e_max_max, r->e_max_mean, r->e_t_max,
            r->e_t_mean, r->test_angles, r->test_points);
}

static const char *rule_text(const btdf_table *t)
{
    btdf_table_kind k = t->kind;
    if (k == BTDF_TABLE_GRID)
        return "bilinear in (theta_o, phi) per slice, linear in theta_i after dividing by "
               "V(theta_i)/cos(theta_i)";
    if (t->rule == BTDF_RULE_FRESNEL)
        return "bilinear in facet (tilt, azimuth) per slice of rho_r/Fr at the facet mirroring "
               "e_i into e_r, Fr the facet's Fresnel reflectance at ca, linear in theta_i after "
               "dividing by V(theta_i)/cos(theta_i), times the query's Fr";
    if (t->rule == BTDF_RULE_CHI)
        return "bilinear in facet (tilt, azimuth) per slice of rho/K at the facet "
               "refracting e_i into e_o, K = cb (ca + n cb)^2, linear in theta_i after "
               "dividing by V(theta_i)/cos(theta_i), times the query's K";
    return k == BTDF_TABLE_FACET_REFLECTION
               ? "bilinear in facet (tilt, azimuth) per slice at the facet mirroring e_i into "
                 "e_r, linear in theta_i after dividing by V(theta_i)/cos(theta_i)"
               : "bilinear in facet (tilt, azimuth) per slice at the facet refracting e_i "
                 "into e_o, linear in theta_i after dividing by V(theta_i)/cos(theta_i)";
}

/* Text on one comment line: a newline or other control byte in it (an argument of the
   command line may hold one) would end the comment and start a bad row, so control
   bytes and the backslash are written as C escapes (\n, \r, \t, \\, \xHH). */
static void comment_text(FILE *f, const char *s)
{
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '\n')
            fputs("\\n", f);
        else if (*p == '\r')
            fputs("\\r", f);
        else if (*p == '\t')
            fputs("\\t", f);
        else if (*p == '\\')
            fputs("\\\\", f);
        else if (*p < 0x20 || *p == 0x7f)
            fprintf(f, "\\x%02x", *p);
        else
            fputc(*p, f);
    }
}

static btdf_status csv_write(const fmt_output_ctx *c, FILE *f, char *msg, size_t msglen)
{
    const btdf_table *t = c->table;
    const btdf_table *tr = t->refl; /* a table holding both parts: its reflection */
    const btdf_params *p = &t->p;
    int nch = p->channels;
    int refl = kind_is_reflection(t->kind);
    /* The header row comes first and the comment block after it, so that one call
       reads the file: numpy.genfromtxt(f, delimiter=',', names=True) takes its names
       from the first line, and pandas.read_csv(f, comment='#') skips the comments
       wherever they are (docs/formats.md). A file holding both parts has a last
       column, part, naming each row's. */
    fprintf(f, "theta_i_deg,theta_o_deg,phi_deg,%s,ti_rad,row_rad,col_rad%s\n",
            nch == 1 ? "rho" : "rho_r,rho_g,rho_b", tr ? ",part" : "");
    fprintf(f, "# btdftab %s table\n", BTDF_VERSION_STRING);
    fprintf(f, "# kind: %s\n", table_kind_name(t->kind));
    if (tr)
        fprintf(f, "# parts: transmission, reflection (%s)\n", table_kind_name(tr->kind));
    fprintf(f, "# channels: %d\n", nch);
    fprintf(f, "# ior:");
    for (int ch = 0; ch < nch; ch++)
        put_num(f, " ", p->ior[ch], "");
    put_num(f, "\n# smoothness: ", p->smoothness, "\n");
    put_num(f, "# k0: ", p->k0, "\n");
    /* Read by machines; absent (every file before the key, and every xu-sun file, which
       keeps its bytes) means xu-sun. */
    if (p->model != BTDF_MODEL_XU_SUN)
        fprintf(f, "# model: %s\n", btdf_model_name(p->model));
    if (tr)
        fprintf(f, "# units: rho in 1/sr, no cosine factor (rho_r on the reflection rows, "
                   "theta_o_deg their reflected angle in [0, 90]); angles in degrees and "
                   "radians\n");
    else if (refl)
        fprintf(f, "# units: rho_r in 1/sr, no cosine factor; theta_o_deg is the reflected "
                   "angle theta_r in [0, 90]; angles in degrees and radians\n");
    else
        fprintf(f, "# units: rho in 1/sr, no cosine factor; angles in degrees and radians\n");
    fprintf(f, "# rule: %s\n", rule_text(t));
    if (tr)
        fprintf(f, "# rule reflection: %s\n", rule_text(tr));
    if (p->model == BTDF_MODEL_FULL)
        fprintf(f, "# model-rule full: rho is the slices' value (smith's, by the rule "
                   "below) plus the multiply scattered part of the tally in the '# ms' lines "
                   "(docs/model.md section 12)\n");
    if (p->model != BTDF_MODEL_XU_SUN)
        fprintf(f, "# model-rule: smith: the incident factor is 1/((1 + Lambda(theta_i)) "
                   "cos(theta_i)) in place of V(theta_i)/cos(theta_i), and facet slices divide "
                   "each node by (1 + Lambda(theta_i)) G2 beside K, G2 the Smith term of its "
                   "directions at the slice's theta_i (docs/tables.md)\n");
    if (tr && p->model != BTDF_MODEL_XU_SUN)
        fprintf(f, "# model-rule reflection: smith: reflection slices divide each node by "
                   "(1 + Lambda(theta_i)) G2 / cos(theta_r) beside Fr; a node whose facet "
                   "mirrors e_i below the horizon holds the value at the mirror image of its "
                   "direction (|cos theta_r|), which no direction reads (docs/tables.md)\n");
    /* Read by machines: files without these lines are read with the plain rule. */
    if (t->kind != BTDF_TABLE_GRID)
        fprintf(f, "# slice-rule: %s\n", btdf_table_rule_name(t->rule));
    if (tr)
        fprintf(f, "# slice-rule reflection: %s\n", btdf_table_rule_name(tr->rule));
    if (t->kind == BTDF_TABLE_FACET_RECIPROCAL)
        fprintf(f, "# reciprocal: slices hold the table of index 1/n, indexed by ti_rad = pi - "
                   "theta_o; rho(n; ti, to, phi) = n^2 rho(1/n; pi - to, pi - ti, phi)\n");
    if (c->opts->provenance) {
        fputs("# provenance: ", f);
        comment_text(f, c->opts->provenance);
        fputc('\n', f);
    }
    if (c->opts->report)
        csv_error_line(f, "error", c->opts->report);
    if (tr && c->opts->report_reflection)
        csv_error_line(f, "error reflection", c->opts->report_reflection);
    if (p->model == BTDF_MODEL_FULL && c->opts->report)
        fprintf(f, "# error against: full, whose tally has the noise floor %.4g (the largest "
                   "standard error of its multiply scattered energy over the range)\n",
                c->opts->report->ms_noise);
    /* Model full: each channel's tally, which the table adds to its slices. */
    for (int ch = 0; p->model == BTDF_MODEL_FULL && ch < nch; ch++) {
        char *txt = table_ms_write(t, ch);
        if (!txt)
            return core_say(BTDF_ENOMEM, msg, msglen, "out of memory");
        for (char *q = txt; *q;) {
            size_t n = strcspn(q, "\n");
            fprintf(f, "# ms %d: %.*s\n", ch, (int)n, q);
            q += n + (q[n] == '\n');
        }
        free(txt);
    }
    /* The row count here and the end line make a cut or a lost row detectable. */
    size_t nrows = btdf_table_node_count(t) + (tr ? btdf_table_node_count(tr) : 0);
    fprintf(f, "# rows: %zu\n", nrows);
    csv_rows(f, t, tr ? ",transmission\n" : "\n");
    if (tr)
        csv_rows(f, tr, ",reflection\n");
    fprintf(f, "# end: %zu rows\n", nrows);
    return BTDF_OK;
}

/* ------------------------------------------------------------------------- */
/* Reader                                                                    */
/* ------------------------------------------------------------------------- */

typedef struct dvec {
    double *v;
    size_t n, cap;
} dvec;

static int push(dvec *d, double x)
{
    if (d->n == d->cap) {
        size_t nc = d->cap ? 2 * d->cap : 256;
        double *nv = realloc(d->v, nc * sizeof *nv);
        if (!nv)
            return 0;
        d->v = nv;
        d->cap = nc;
    }
    d->v[d->n++] = x;
    return 1;
}

static btdf_status ferr(char *msg, size_t msglen, const char *path, long line, const char *why)
{
    if (msg && msglen)
        snprintf(msg, msglen, "%s:%ld: %s", path, line, why);
    return BTDF_EFORMAT;
}

/* Parses n comma-separated fields; empty fields allowed where allow_empty[i]. */
static int split(char *s, char **fld, int maxf)
{
    int n = 0;
    fld[n++] = s;
    for (char *q = s; *q; q++) {
        if (*q == ',') {
            *q = 0;
            if (n == maxf)
                return -1;
            fld[n++] = q + 1;
        } else if (*q == '\n' || *q == '\r') {
            *q = 0;
            break;
        }
    }
    return n;
}

/* s is a plain decimal: digits with one point and an exponent at most, a sign in front;
   no blanks, hexadecimal, inf or nan (the tool's one rule for numbers). */
static int decimal(const char *s)
{
    const char *p = s + (*s == '+' || *s == '-');
    size_t a = strspn(p, "0123456789"), b = 0;
    p += a;
    if (*p == '.') {
        b = strspn(p + 1, "0123456789");
        p += 1 + b;
    }
    if (a + b == 0)
        return 0;
    if (*p == 'e' || *p == 'E') {
        p += 1 + (p[1] == '+' || p[1] == '-');
        size_t c = strspn(p, "0123456789");
        if (c == 0)
            return 0;
        p += c;
    }
    return *p == '\0';
}

/* The numbers of a header line after its key, each after one blank, up to the line's
   end: how many (at most max), or -1 if anything else is there. */
static int header_nums(const char *s, double *v, int max)
{
    int n = 0;
    while (*s == ' ') {
        size_t l = strcspn(++s, " \r\n");
        char tok[64];
        if (n == max || l == 0 || l >= sizeof tok)
            return -1;
        memcpy(tok, s, l);
        tok[l] = '\0';
        char *e;
        errno = 0;
        v[n] = strtod(tok, &e);
        if (!decimal(tok) || *e || errno == ERANGE || !isfinite(v[n]))
            return -1;
        n++;
        s += l;
    }
    return strspn(s, "\r\n") == strlen(s) && n > 0 ? n : -1;
}

static int num(const char *s, double *out)
{
    char *e;
    if (!decimal(s))
        return 0;
    errno = 0;
    double v = strtod(s, &e);
    if (e == s || *e || errno == ERANGE || !isfinite(v))
        return 0;
    *out = v;
    return 1;
}

/* Flushes the rows of one slice into the table: they must form a full tensor grid. */
static btdf_status flush_slice(btdf_table *t, double ti, dvec *rr, dvec *cc, dvec *vv,
                               const char *path, long line, char *msg, size_t msglen)
{
    if (rr->n == 0)
        return BTDF_OK;
    size_t npts = rr->n;
    size_t nc = 1;
    while (nc < npts && rr->v[nc] == rr->v[0])
        nc++;
    if (npts % nc != 0)
        return ferr(msg, msglen, path, line, "slice rows are not a full grid");
    size_t nr = npts / nc;
    double *rows = malloc(nr * sizeof(double)), *cols = malloc(nc * sizeof(double));
    if (!rows || !cols) {
        free(rows);
        free(cols);
        return BTDF_ENOMEM;
    }
    for (size_t i = 0; i < nr; i++)
        rows[i] = rr->v[i * nc];
    for (size_t j = 0; j < nc; j++)
        cols[j] = cc->v[j];
    for (size_t q = 0; q < npts; q++) {
        if (rr->v[q] != rows[q / nc] || cc->v[q] != cols[q % nc]) {
            free(rows);
            free(cols);
            return ferr(msg, msglen, path, line,
                        "slice nodes are not a full grid in row-major order");
        }
    }
    char why[200];
    btdf_status st = btdf_table_add_slice(t, ti, nr, rows, nc, cols, vv->v, why, sizeof why);
    free(rows);
    free(cols);
    if (st == BTDF_EINVAL)
        return ferr(msg, msglen, path, line, why);
    rr->n = cc->n = vv->n = 0;
    return st;
}

/* What csv_read knows so far: the keys seen, the tables and the slice being read. */
typedef struct csv_state {
    btdf_params p;
    int have_kind, have_ch, have_ior, have_s, have_k0, header;
    int have_rows, have_end, last_nl;
    char version[80]; /* from "# btdftab VERSION table" */
    int part_col, have_parts; /* a file holding both parts */
    size_t declared, ended, seen;
    btdf_table_kind kind;
    btdf_table_rule rule; /* files from before the rule had a name: plain */
    btdf_table_rule rule_r; /* the reflection's, in a file holding both */
    btdf_table *t, *tr, *cur; /* cur: the part being read */
    dvec rr, cc, vv;
    double cur_ti;
    long ln;
    table_ms_text mst; /* model full: the tally's lines, per channel */
} csv_state;

static void csv_state_init(csv_state *s)
{
    memset(s, 0, sizeof *s);
    btdf_params_default(&s->p);
    s->last_nl = 1;
    snprintf(s->version, sizeof s->version, "an unnamed version");
    s->kind = BTDF_TABLE_FACET;
    s->rule = BTDF_RULE_PLAIN;
    s->rule_r = BTDF_RULE_PLAIN;
    s->cur_ti = -1.0;
}

/* A comment line of the table (# kind, # ior, # rows, # end, ...) into the state. */
static btdf_status csv_comment(csv_state *s, const char *line, const char *path, char *msg,
                               size_t msglen)
{
    btdf_status st = BTDF_OK;
    char word[64];
    int ms_ch = 0, ms_at = 0; /* "# ms C:" lines of model full */
    if (s->header && !strncmp(line, "# end:", 6)) {
        char tail;
        if (!s->have_rows)
            return ferr(msg, msglen, path, s->ln,
                        "an '# end' line but no '# rows' line before the node rows");
        if (sscanf(line, "# end: %zu rows%c", &s->ended, &tail) != 2 || tail != '\n' ||
            line[7] < '0' || line[7] > '9')
            st = ferr(msg, msglen, path, s->ln, "malformed '# end: N rows' line");
        s->have_end = 1;
    } else if (!s->t && !strncmp(line, "# rows:", 7)) {
        char tail;
        if (sscanf(line, "# rows: %zu%c", &s->declared, &tail) != 2 || tail != '\n' ||
            line[8] < '0' || line[8] > '9')
            st = ferr(msg, msglen, path, s->ln, "malformed '# rows: N' line");
        s->have_rows = 1;
    } else if (!s->t && sscanf(line, "# btdftab %63s table", word) == 1) {
        snprintf(s->version, sizeof s->version, "btdftab %s", word);
    } else if (sscanf(line, "# kind: %63s", word) == 1) {
        s->have_kind = 1;
        if (!table_kind_parse(word, &s->kind))
            st = ferr(msg, msglen, path, s->ln,
                      "kind must be facet, facet-reciprocal, grid or facet-reflection");
    } else if (!strncmp(line, "# parts: transmission, reflection", 33)) {
        s->have_parts = 1;
    } else if (sscanf(line, "# slice-rule reflection: %63s", word) == 1) {
        if (!btdf_table_rule_parse(word, &s->rule_r))
            st = ferr(msg, msglen, path, s->ln, "slice-rule must be plain, chi or fresnel");
    } else if (sscanf(line, "# slice-rule: %63s", word) == 1) {
        if (!btdf_table_rule_parse(word, &s->rule))
            st = ferr(msg, msglen, path, s->ln, "slice-rule must be plain, chi or fresnel");
    } else if (!strncmp(line, "# channels:", 11)) {
        double c = 0;
        if (header_nums(line + 11, &c, 1) != 1 || (c != 1 && c != 3))
            st = ferr(msg, msglen, path, s->ln, "'# channels' must be 1 or 3");
        s->p.channels = (int)c;
        s->have_ch = 1;
    } else if (!strncmp(line, "# ior:", 6)) {
        s->have_ior = header_nums(line + 6, s->p.ior, 3);
        if (s->have_ior < 0)
            st = ferr(msg, msglen, path, s->ln, "'# ior' must be 1 or 3 decimal numbers");
    } else if (!strncmp(line, "# smoothness:", 13)) {
        if (header_nums(line + 13, &s->p.smoothness, 1) != 1)
            st = ferr(msg, msglen, path, s->ln, "'# smoothness' must be a decimal number");
        s->have_s = 1;
    } else if (!strncmp(line, "# k0:", 5)) {
        if (header_nums(line + 5, &s->p.k0, 1) != 1)
            st = ferr(msg, msglen, path, s->ln, "'# k0' must be a decimal number");
        s->have_k0 = 1;
    } else if (sscanf(line, "# ms %d:%n", &ms_ch, &ms_at) == 1 && ms_at > 0) {
        char why[200];
        const char *txt = line + ms_at + (line[ms_at] == ' ');
        if (table_ms_text_add(&s->mst, ms_ch, txt, why, sizeof why) != BTDF_OK)
            st = ferr(msg, msglen, path, s->ln, why);
    } else if (sscanf(line, "# model: %63s", word) == 1) {
        if (!btdf_model_parse(word, &s->p.model)) {
            char why[160];
            snprintf(why, sizeof why, "model '%s': must be xu-sun, smith or full",
                     word);
            st = ferr(msg, msglen, path, s->ln, why);
        }
    }
    return st;
}

/* The first node row: every key the rows need is there; the table is made. The
   comments may come before the header row or after it (btdftab writes them after
   it): the parameters are needed by the first node row. */
static btdf_status csv_begin(csv_state *s, const char *path, char *msg, size_t msglen)
{
    if (s->part_col != s->have_parts || (s->part_col && kind_is_reflection(s->kind)))
        return ferr(msg, msglen, path, s->ln,
                    "a part column needs the '# parts: transmission, reflection' line "
                    "and a transmission kind, and that line the column");
    /* Name every missing key, and the writer: a file of another version
       says so rather than look damaged. '# rows' is not required: without it
       the file is of the format before row counts (0.3.0 and earlier). */
    if (!s->have_kind || !s->have_ch || !s->have_s || !s->have_k0 || s->have_ior <= 0) {
        char why[320];
        snprintf(why, sizeof why,
                 "missing%s%s%s%s%s comment before the first node row (the file "
                 "says it was written by %s; this reader is btdftab %s)",
                 s->have_kind ? "" : " '# kind'", s->have_ch ? "" : " '# channels'",
                 s->have_ior > 0 ? "" : " '# ior'", s->have_s ? "" : " '# smoothness'",
                 s->have_k0 ? "" : " '# k0'", s->version, BTDF_VERSION_STRING);
        return ferr(msg, msglen, path, s->ln, why);
    }
    if (s->have_ior != s->p.channels) {
        char why[160];
        snprintf(why, sizeof why,
                 "'# ior' gives %d values but '# channels' says %d (written by %s)",
                 s->have_ior, s->p.channels, s->version);
        return ferr(msg, msglen, path, s->ln, why);
    }
    if (!s->have_rows && s->part_col)
        return ferr(msg, msglen, path, s->ln,
                    "a part column needs the '# rows' line before the node rows");
    char why[200];
    btdf_params single = table_single_params(&s->p); /* full: smith's slices */
    if (btdf_table_new(s->kind, &single, &s->t, why, sizeof why) != BTDF_OK ||
        btdf_table_set_rule(s->t, s->rule, why, sizeof why) != BTDF_OK) {
        return ferr(msg, msglen, path, s->ln, why);
    }
    s->cur = s->t;
    return BTDF_OK;
}

/* A node row: its part (a file holding both), angles and values onto the slice. */
static btdf_status csv_row(csv_state *s, char *line, const char *path, char *msg,
                           size_t msglen)
{
    btdf_status st = BTDF_OK;
    char *fld[16];
    int nf = split(line, fld, 16);
    int want = 3 + s->p.channels + 3 + s->part_col;
    if (nf != want) {
        char why[80];
        snprintf(why, sizeof why, "expected %d fields, found %d", want, nf);
        return ferr(msg, msglen, path, s->ln, why);
    }
    if (s->part_col) {
        const char *pw = fld[nf - 1];
        int is_r = !strcmp(pw, "reflection");
        if (!is_r && strcmp(pw, "transmission"))
            return ferr(msg, msglen, path, s->ln, "part must be transmission or reflection");
        if (!is_r && s->tr)
            return ferr(msg, msglen, path, s->ln,
                        "a transmission row after the reflection rows began");
        if (is_r && !s->tr) { /* the transmission is complete: on to the reflection */
            st = flush_slice(s->t, s->cur_ti, &s->rr, &s->cc, &s->vv, path, s->ln, msg, msglen);
            char why[200];
            if (st == BTDF_OK &&
                (btdf_table_new(BTDF_TABLE_FACET_REFLECTION, &s->t->p, &s->tr, why,
                                sizeof why) != BTDF_OK ||
                 btdf_table_set_rule(s->tr, s->rule_r, why, sizeof why) != BTDF_OK))
                st = ferr(msg, msglen, path, s->ln, why);
            if (st != BTDF_OK)
                return st;
            s->cur = s->tr;
            s->cur_ti = -1.0;
        }
        nf--; /* the numbers end before the part */
    }
    double ti, row, col, v[BTDF_MAX_CHANNELS];
    int ok = num(fld[nf - 3], &ti) && num(fld[nf - 2], &row) && num(fld[nf - 1], &col);
    for (int ch = 0; ch < s->p.channels && ok; ch++)
        ok = num(fld[3 + ch], &v[ch]);
    if (!ok)
        return ferr(msg, msglen, path, s->ln, "a number is malformed or not finite");
    if (++s->seen > s->declared && s->have_rows)
        return ferr(msg, msglen, path, s->ln, "more node rows than '# rows' declares");
    if (ti != s->cur_ti) {
        st = flush_slice(s->cur, s->cur_ti, &s->rr, &s->cc, &s->vv, path, s->ln, msg, msglen);
        s->cur_ti = ti;
    }
    if (st == BTDF_OK && !(push(&s->rr, row) && push(&s->cc, col)))
        st = BTDF_ENOMEM;
    for (int ch = 0; ch < s->p.channels && st == BTDF_OK; ch++)
        if (!push(&s->vv, v[ch]))
            st = BTDF_ENOMEM;
    return st;
}

/* The checks after the last line (st: the reading's status so far): the header,
   the counts, the last slice, the reflection attached. */
static btdf_status csv_finish(csv_state *s, btdf_status st, const char *path, char *msg,
                              size_t msglen)
{
    if (st == BTDF_OK && !s->header)
        st = ferr(msg, msglen, path, s->ln, "no header row: empty or foreign file");
    if (st == BTDF_OK && !s->have_rows && s->t && !s->last_nl)
        st = ferr(msg, msglen, path, s->ln,
                  "the last node row has no line end: the file is cut short");
    if (st == BTDF_OK && !s->have_end && (s->have_rows || !s->t)) {
        char why[160];
        snprintf(why, sizeof why,
                 "the file is cut short: no '# end' line (%zu of the %zu declared rows read)",
                 s->seen, s->declared);
        st = ferr(msg, msglen, path, s->ln, why);
    }
    if (st == BTDF_OK && s->have_rows && (s->ended != s->declared || s->seen != s->declared)) {
        char why[160];
        snprintf(why, sizeof why, "'# rows: %zu' and '# end: %zu rows' but %zu node rows",
                 s->declared, s->ended, s->seen);
        st = ferr(msg, msglen, path, s->ln, why);
    }
    if (st == BTDF_OK && !s->t)
        st = ferr(msg, msglen, path, s->ln, "no table rows");
    if (st == BTDF_OK)
        st = flush_slice(s->cur, s->cur_ti, &s->rr, &s->cc, &s->vv, path, s->ln, msg, msglen);
    if (st == BTDF_OK && s->t->ns == 0)
        st = ferr(msg, msglen, path, s->ln, "no table rows");
    if (st == BTDF_OK && s->part_col && (!s->tr || s->tr->ns == 0))
        st = ferr(msg, msglen, path, s->ln, "the file declares both parts but has no reflection rows");
    if (st == BTDF_OK && s->tr) {
        char why[200];
        if (btdf_table_attach_reflection(s->t, s->tr, why, sizeof why) != BTDF_OK)
            st = ferr(msg, msglen, path, s->ln, why);
        else
            s->tr = NULL; /* owned by t */
    }
    if (st == BTDF_OK) { /* model full: its tally (after the reflection, which gets it too) */
        char why[200];
        if (table_full_from_text(s->t, s->p.model, &s->mst, why, sizeof why) != BTDF_OK)
            st = ferr(msg, msglen, path, s->ln, why);
    }
    return st;
}

static btdf_status csv_read(const char *path, btdf_table **out, char *msg, size_t msglen)
{
    FILE *f = fopen(path, "r");
    if (!f) {
        if (msg && msglen)
            snprintf(msg, msglen, "cannot open %s: %s", path, strerror(errno));
        return BTDF_EIO;
    }
    csv_state s;
    csv_state_init(&s);
    char line[4096];
    btdf_status st = BTDF_OK;
    while (st == BTDF_OK && fgets(line, sizeof line, f)) {
        s.ln++;
        s.last_nl = strchr(line, '\n') != NULL;
        if (!s.last_nl && !feof(f)) {
            st = ferr(msg, msglen, path, s.ln, "line longer than 4095 bytes");
            break;
        }
        if (s.have_end) {
            if (strspn(line, " \t\r\n") != strlen(line))
                st = ferr(msg, msglen, path, s.ln, "text after the '# end' line");
            continue;
        }
        if (line[0] == '#') {
            st = csv_comment(&s, line, path, msg, msglen);
            continue;
        }
        if (!s.header) {
            if (strncmp(line, "theta_i_deg,", 12) != 0) {
                st = ferr(msg, msglen, path, s.ln,
                          "not a btdftab table CSV (expected the header row theta_i_deg,...)");
                break;
            }
            s.header = 1;
            size_t hl = strcspn(line, "\r\n");
            s.part_col = hl >= 5 && !strncmp(line + hl - 5, ",part", 5);
            continue;
        }
        if (!s.t && (st = csv_begin(&s, path, msg, msglen)) != BTDF_OK)
            break;
        st = csv_row(&s, line, path, msg, msglen);
    }
    if (st == BTDF_OK && ferror(f))
        st = ferr(msg, msglen, path, s.ln, "read error");
    st = csv_finish(&s, st, path, msg, msglen);
    table_ms_text_free(&s.mst);
    btdf_table_free(s.tr);
    fclose(f);
    free(s.rr.v);
    free(s.cc.v);
    free(s.vv.v);
    if (st != BTDF_OK) {
        btdf_table_free(s.t);
        return st;
    }
    *out = s.t;
    return BTDF_OK;
}

/* The comment lines a reader does not need, as they were written: the provenance and
   the error report. They sit in the comment block at the top of the file. */
static btdf_status csv_stored(const char *path, FILE *out)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return BTDF_EIO;
    char line[4096];
    int rows = 0;
    while (fgets(line, sizeof line, f) && rows < 2) {
        if (line[0] != '#') {
            rows++; /* the header row, then the first node row ends the block */
            continue;
        }
        if (!strncmp(line, "# provenance: ", 14) || !strncmp(line, "# error: ", 9) ||
            !strncmp(line, "# error reflection: ", 20) || !strncmp(line, "# error against: ", 17))
            fputs(line + 2, out);
    }
    fclose(f);
    return ferror(out) ? BTDF_EIO : BTDF_OK;
}

const fmt_ops fmt_csv = {
    .name = "CSV",
    .ext = ".csv",
    .available = 1,
    .needs = BTDF_NEEDS_TABLE,
    .write_stream = csv_write,
    .read_path = csv_read,
    .stored = csv_stored,
};
