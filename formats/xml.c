/* SPDX-License-Identifier: MIT */
/* xml.c: LBNL WINDOW / Radiance BSDF XML (renderer-formats.md section 3), TensorTree3 or
   Klems, from a btdf_rad built in src/radiance/radiance.c. Values are the BTDF in 1/sr, no cosine. */
#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "btdf_io.h"
#include "btdf_radiance.h"
#include "core/core.h"
#include "formats/formats.h"
#include "radiance/radiance.h"

/* Text a reader takes literally: &, < and > escaped, control characters dropped, a
   byte outside any UTF-8 sequence (a Latin-1 name) written as the character it is in
   Latin-1, so the file stays the UTF-8 its prolog declares. */
/* A byte >= 0x80 at s: its whole UTF-8 sequence, or the byte as its Latin-1 character
   in UTF-8; returns the bytes of s used. */
static size_t put_high(FILE *f, const unsigned char *u)
{
    size_t n = *u >= 0xF0 && *u <= 0xF4 ? 4 : *u >= 0xE0 && *u < 0xF0 ? 3
               : *u >= 0xC2 && *u < 0xE0 ? 2 : 1;
    int whole = n > 1;
    for (size_t j = 1; whole && j < n; j++)
        whole = (u[j] & 0xC0) == 0x80;
    if (whole) {
        fwrite(u, 1, n, f);
        return n;
    }
    fputc(0xC0 | (*u >> 6), f);
    fputc(0x80 | (*u & 0x3F), f);
    return 1;
}

static void put_text(FILE *f, const char *s)
{
    for (; s && *s; s++) {
        if ((unsigned char)*s >= 0x80) {
            s += put_high(f, (const unsigned char *)s) - 1;
            continue;
        }
        if (*s == '&')
            fputs("&amp;", f);
        else if (*s == '<')
            fputs("&lt;", f);
        else if (*s == '>')
            fputs("&gt;", f);
        else if ((unsigned char)*s >= 0x20)
            fputc(*s, f);
    }
}

/* A value as written: 6 significant digits (FLT_DIG: reads back to the stored float),
   in as few characters as C's strtod and Radiance's reader take: no "0" before the
   point (".0123"), no "+" or leading zeros in the exponent ("1.2e-5"). Tree leaves
   are rounded to 4 digits already (ttree.c), so they print as such; a colour tree's
   u', v' are plain floats, written with 9 digits (FLT_DECIMAL_DIG: the very float). */
static void put_value_digits(FILE *f, float v, int digits)
{
    char t[32], o[32];
    snprintf(t, sizeof t, "%.*g", digits, (double)v);
    const char *s = t;
    size_t k = 0;
    if (s[0] == '0' && s[1] == '.')
        s++; /* "0.0123" -> ".0123" */
    for (; *s && k + 1 < sizeof o; s++) {
        o[k++] = *s;
        if (*s == 'e') {
            s++;
            if (*s == '-')
                o[k++] = '-';
            else if (*s != '+')
                s--; /* not printf's form: copy as it is */
            while (s[1] == '0' && s[2] != '\0')
                s++; /* "e-05" -> "e-5" */
        }
    }
    o[k] = '\0';
    fputs(o, f);
}

static void put_value(FILE *f, float v) { put_value_digits(f, v, 6); }

/* What node k of block b holds in tree `what`: 0 the Y tree (the node's value), 1 and
   2 the u' and v' trees of a colour file (the same structure). */
static float node_value(const rad_block *b, size_t k, int what)
{
    return what == 0 ? b->nodes[k].v : b->cv[k * RAD_CV + 2 + (size_t)what];
}

/* Node k: a leaf { v }, a grid of 8 leaves { v0 .. v7 } (dimension 0 slowest, as
   Radiance reads a 2 x 2 x 2 grid), or { child0 .. child7 }. */
static void put_node(FILE *f, const rad_block *b, size_t k, int what)
{
    const rad_node *nd = b->nodes;
    if (nd[k].child < 0) {
        fputc('{', f);
        put_value_digits(f, node_value(b, k, what), what ? 9 : 6);
        fputc('}', f);
        return;
    }
    const rad_node *c = nd + nd[k].child;
    int flat = 1;
    for (int n = 0; n < 8; n++)
        flat &= c[n].child < 0;
    fputc('{', f);
    if (flat) {
        for (int g = 0; g < 8; g++) {
            /* grid index g = i0 i1 i2 (i0 slowest); child index n = i0 + 2 i1 + 4 i2 */
            int n = ((g >> 2) & 1) | (((g >> 1) & 1) << 1) | ((g & 1) << 2);
            if (g)
                fputc(' ', f);
            put_value_digits(f, node_value(b, (size_t)nd[k].child + (size_t)n, what),
                             what ? 9 : 6);
        }
        fputs("}\n", f);
        return;
    }
    for (int n = 0; n < 8; n++)
        put_node(f, b, (size_t)nd[k].child + (size_t)n, what);
    fputs("}\n", f);
}

static void put_klems_basis(FILE *f, const rad_klems_basis *kb)
{
    fprintf(f, "\t\t\t<AngleBasis>\n\t\t\t\t<AngleBasisName>%s</AngleBasisName>\n", kb->name);
    for (int k = 0; k < kb->nbands; k++) {
        double lo = kb->theta[k], hi = kb->theta[k + 1];
        double centre = k == 0 ? 0.0 : 0.5 * (lo + hi);
        fprintf(f,
                "\t\t\t\t<AngleBasisBlock>\n\t\t\t\t\t<Theta>%g</Theta>\n"
                "\t\t\t\t\t<nPhis>%d</nPhis>\n\t\t\t\t\t<ThetaBounds>\n"
                "\t\t\t\t\t\t<LowerTheta>%g</LowerTheta>\n"
                "\t\t\t\t\t\t<UpperTheta>%g</UpperTheta>\n\t\t\t\t\t</ThetaBounds>\n"
                "\t\t\t\t</AngleBasisBlock>\n",
                centre, kb->nphi[k], lo, hi);
    }
    fprintf(f, "\t\t\t</AngleBasis>\n");
}

static btdf_status xml_write(const btdf_output_ctx *c, FILE *f, char *msg, size_t msglen)
{
    const btdf_rad *r = c->rad;
    if (!r) {
        if (msg && msglen)
            snprintf(msg, msglen, "an .xml BSDF is built from the model (btdf_rad_build), "
                                  "not written from a table");
        return BTDF_EINVAL;
    }
    int tree = r->basis == RAD_BASIS_TREE3;
    fprintf(f, "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    fprintf(f, "<!-- Written by btdftab %s: Xu & Sun (2008) Eq. 25, the BTDF of a rough "
               "dielectric interface. Values are the BTDF in 1/sr (no cosine factor).\n",
            BTDF_VERSION_STRING);
    /* a model other than xu-sun says so (xu-sun files keep their bytes) */
    if (r->p.model == BTDF_MODEL_SMITH)
        fprintf(f, "     Model: smith: the facets of Eq. 25 with the height-correlated Smith "
                   "shadowing-masking of the same Gaussian surface in place of V(ti) V(to) "
                   "(k0 unused).\n");
    if (r->channels == 3)
        fprintf(f, "     Colour: R, G, B in Radiance's RGB (its default primaries, equal-energy "
                   "white) for n = %.9g, %.9g, %.9g, written as CIE %s.\n",
                r->p.ior[0], r->p.ior[1], r->p.ior[2], tree ? "Y, u', v'" : "X, Y, Z");
    fprintf(f, "     In Radiance the surface normal points into the dense medium (index n = %.9g).\n"
               "     Transmission Front serves light from the dense side (leaving it, 1/n), "
               "Transmission Back light entering it (n);\n     Reflection Front light "
               "reflected outside (n), Reflection Back inside (1/n).\n",
            r->p.ior[0]);
    fputs("-->\n", f);
    fprintf(f, "<WindowElement xmlns=\"http://windows.lbl.gov\" "
               "xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" "
               "xsi:schemaLocation=\"http://windows.lbl.gov/BSDF-v1.4.xsd\">\n");
    fprintf(f, "<WindowElementType>System</WindowElementType>\n<FileType>BSDF</FileType>\n");
    fprintf(f, "<Optical>\n<Layer>\n\t<Material>\n\t\t<Name>");
    put_text(f, r->name[0] ? r->name : "rough_interface");
    fprintf(f, "</Name>\n\t\t<Manufacturer>btdftab %s</Manufacturer>\n", BTDF_VERSION_STRING);
    fprintf(f, "\t\t<Thickness unit=\"Millimeter\">0</Thickness>\n"
               "\t\t<DeviceType>Other</DeviceType>\n");
    const char *what = r->p.model == BTDF_MODEL_SMITH
                           ? "Xu and Sun 2008 facets with the Smith term (model smith)"
                           : "Xu and Sun 2008 Eq. 25";
    if (r->channels == 3)
        fprintf(f, "\t\t<Comments>%s rough interface: n = %.9g (R), "
                   "%.9g (G), %.9g (B) in Radiance's RGB, written as CIE %s; s = %.9g, "
                   "k0 = %.9g; basis %s",
                what, r->p.ior[0], r->p.ior[1], r->p.ior[2], tree ? "Y, u', v'" : "X, Y, Z",
                r->p.smoothness, r->p.k0, rad_basis_name(r->basis));
    else
        fprintf(f, "\t\t<Comments>%s rough interface: n = %.9g, s = %.9g, "
                   "k0 = %.9g; basis %s",
                what, r->p.ior[0], r->p.smoothness, r->p.k0, rad_basis_name(r->basis));
    if (tree)
        fprintf(f, ", tolerance %g", r->tolerance);
    if (r->reported)
        for (int k = 0; k < r->nblocks; k++)
            fprintf(f, "; %s: e_L1 max %.4g, e_T max %.4g as Radiance reads it%s", r->b[k].label,
                    r->e_l1[k], r->e_t[k], r->channels == 3 ? " (the worst of R, G, B)" : "");
    /* the command in the element's text, where "--ior" stays as typed (a comment may
       not hold "--"); last, after every key the reader looks for */
    if (c->opts->provenance) {
        fputs("; command: ", f);
        put_text(f, c->opts->provenance);
    }
    fprintf(f, "</Comments>\n\t</Material>\n");
    fprintf(f, "\t<DataDefinition>\n");
    if (tree) {
        fprintf(f, "\t\t<IncidentDataStructure>TensorTree3</IncidentDataStructure>\n");
    } else {
        fprintf(f, "\t\t<IncidentDataStructure>Columns</IncidentDataStructure>\n");
        put_klems_basis(f, r->kb);
    }
    fprintf(f, "\t</DataDefinition>\n");
    /* One WavelengthData per channel: Visible (CIE Y), and for colour CIE-X and CIE-Z
       (Klems) or CIE-u and CIE-v (trees of u', v' of the Y tree's structure)
       (renderer-formats.md 3.4), each with the four blocks. */
    const char *const *wl = tree ? (const char *const[3]){"Visible", "CIE-u", "CIE-v"}
                                 : (const char *const[3]){"Visible", "CIE-X", "CIE-Z"};
    /* informational: the 1931 observer's function, or the chromaticity taken from them */
    const char *const *det =
        tree ? (const char *const[3]){"ASTM E308 1931 Y.dsp", "CIE 1976 u' (ASTM E308 1931)",
                                      "CIE 1976 v' (ASTM E308 1931)"}
             : (const char *const[3]){"ASTM E308 1931 Y.dsp", "ASTM E308 1931 X.dsp",
                                      "ASTM E308 1931 Z.dsp"};
    for (int ch = 0; ch < (r->channels == 3 ? 3 : 1); ch++) {
        fprintf(f, "\t<WavelengthData>\n\t\t<LayerNumber>System</LayerNumber>\n"
                   "\t\t<Wavelength unit=\"Integral\">%s</Wavelength>\n"
                   "\t\t<SourceSpectrum>CIE Illuminant D65 1nm.ssp</SourceSpectrum>\n"
                   "\t\t<DetectorSpectrum>%s</DetectorSpectrum>\n",
                wl[ch], det[ch]);
        for (int k = 0; k < r->nblocks; k++) {
            const rad_block *b = &r->b[k];
            fprintf(f, "\t\t<WavelengthDataBlock>\n\t\t\t<WavelengthDataDirection>%s"
                       "</WavelengthDataDirection>\n",
                    b->label);
            if (tree) {
                fprintf(f, "\t\t\t<AngleBasis>LBNL/Shirley-Chiu</AngleBasis>\n");
            } else {
                fprintf(f, "\t\t\t<ColumnAngleBasis>%s</ColumnAngleBasis>\n"
                           "\t\t\t<RowAngleBasis>%s</RowAngleBasis>\n",
                        r->kb->name, r->kb->name);
            }
            fprintf(f, "\t\t\t<ScatteringDataType>BTDF</ScatteringDataType>\n"
                       "\t\t\t<ScatteringData>\n");
            if (tree) {
                put_node(f, b, 0, ch);
            } else {
                const float *m = ch == 0 ? b->klems : (ch == 1 ? b->klems_x : b->klems_z);
                size_t np = (size_t)r->kb->npatch;
                for (size_t o = 0; o < np; o++) { /* one row per outgoing patch */
                    for (size_t i = 0; i < np; i++) {
                        if (i)
                            fputc(' ', f);
                        put_value(f, m[o * np + i]);
                    }
                    fputc('\n', f);
                }
            }
            fprintf(f, "\t\t\t</ScatteringData>\n\t\t</WavelengthDataBlock>\n");
        }
        fprintf(f, "\t</WavelengthData>\n");
    }
    fprintf(f, "</Layer>\n</Optical>\n</WindowElement>\n");
    return ferror(f) ? BTDF_EIO : BTDF_OK;
}

/* ------------------------------------------------------------------------- */
/* Reading back: the files xml_write writes                                  */
/* ------------------------------------------------------------------------- */

/* The reader takes what xml_write writes (its elements in its order, no attributes
   on the elements it reads but Wavelength's) and refuses anything else with a message
   naming the first thing wrong; it never returns part of a file. Limits: a tree of at
   most RAD_READ_MAX_NODES nodes and RAD_READ_MAX_DEPTH levels (the builder's trees
   stop at RAD_MAX_NODES and depth 16 or so; docs/radiance.md). */
#define RAD_READ_MAX_NODES ((size_t)1 << 24)
#define RAD_READ_MAX_DEPTH 40

typedef struct xml_in {
    const char *s, *end; /* the text, not NUL-terminated */
    char *msg;
    size_t msglen;
} xml_in;

/* The body of the first <tag>...</tag> in [from, end): *b and *e, or 0. */
static int xml_elem(const char *from, const char *end, const char *tag, const char **b,
                    const char **e)
{
    size_t lt = strlen(tag);
    for (const char *p = from; p + lt + 2 <= end; p++) {
        if (p[0] != '<' || memcmp(p + 1, tag, lt) != 0 || (p[1 + lt] != '>' && p[1 + lt] != ' '))
            continue;
        const char *q = memchr(p, '>', (size_t)(end - p));
        if (!q)
            return 0;
        q++;
        for (const char *r = q; r + lt + 3 <= end; r++)
            if (r[0] == '<' && r[1] == '/' && memcmp(r + 2, tag, lt) == 0 && r[2 + lt] == '>') {
                *b = q;
                *e = r;
                return 1;
            }
        return 0;
    }
    return 0;
}

/* The element's text with &amp; &lt; &gt; undone, into out (cut at outlen - 1 bytes,
   never inside a UTF-8 sequence). */
static void xml_text(const char *b, const char *e, char *out, size_t outlen)
{
    size_t k = 0;
    while (b < e && k + 1 < outlen) {
        char c = *b;
        size_t adv = 1;
        if (c == '&') {
            static const char *const ent[3] = {"&amp;", "&lt;", "&gt;"};
            static const char rep[3] = {'&', '<', '>'};
            for (int i = 0; i < 3; i++) {
                size_t l = strlen(ent[i]);
                if ((size_t)(e - b) >= l && memcmp(b, ent[i], l) == 0) {
                    c = rep[i];
                    adv = l;
                }
            }
        }
        out[k++] = c;
        b += adv;
    }
    if (b < e) { /* cut: drop a UTF-8 sequence the cut left incomplete */
        size_t j = k, cont = 0;
        while (j > 0 && cont < 3 && ((unsigned char)out[j - 1] & 0xC0) == 0x80) {
            j--;
            cont++;
        }
        if (j > 0 && (unsigned char)out[j - 1] >= 0xC0) {
            unsigned char lead = (unsigned char)out[j - 1];
            size_t need = lead >= 0xF0 ? 3 : lead >= 0xE0 ? 2 : 1;
            if (cont < need)
                k = j - 1;
        }
    }
    out[k] = 0;
}

/* One number at *p (skipping white space) below e, finite and >= 0: 1 and *p moved
   past it, or 0. */
static int xml_value(const char **p, const char *e, float *v)
{
    const char *q = *p;
    while (q < e && (*q == ' ' || *q == '\n' || *q == '\t' || *q == '\r'))
        q++;
    char buf[40];
    size_t k = 0;
    while (q < e && k + 1 < sizeof buf && (isdigit((unsigned char)*q) || *q == '.' ||
                                          *q == 'e' || *q == 'E' || *q == '-' || *q == '+'))
        buf[k++] = *q++;
    if (k == 0 || k + 1 >= sizeof buf)
        return 0;
    buf[k] = 0;
    char *endp;
    double d = strtod(buf, &endp);
    if (*endp || !(d >= 0.0) || !(d <= FLT_MAX))
        return 0;
    *v = (float)d;
    *p = q;
    return 1;
}

static const char *xml_skip(const char *p, const char *e)
{
    while (p < e && (*p == ' ' || *p == '\n' || *p == '\t' || *p == '\r'))
        p++;
    return p;
}

typedef struct tree_in {
    rad_block *b;
    size_t cap;
    int what; /* 0: the Y tree (builds the nodes), 1, 2: u', v' (the same structure) */
    int depth;
} tree_in;

/* Node k of the tree at *p: "{v}", "{v0 .. v7}" or "{child0 .. child7}" (put_node). */
static int tree_node(tree_in *t, const char **p, const char *e, size_t k, int depth)
{
    rad_block *b = t->b;
    const char *q = xml_skip(*p, e);
    if (depth > RAD_READ_MAX_DEPTH || q >= e || *q != '{')
        return 0;
    q = xml_skip(q + 1, e);
    if (q < e && *q == '{') { /* eight subtrees */
        if (t->what == 0) {
            if (b->nnodes + 8 > RAD_READ_MAX_NODES)
                return 0;
            if (b->nnodes + 8 > t->cap) {
                size_t nc = t->cap * 2 + 64;
                rad_node *nn = realloc(b->nodes, nc * sizeof *nn);
                if (!nn)
                    return 0;
                b->nodes = nn;
                t->cap = nc;
            }
            b->nodes[k].child = (int32_t)b->nnodes;
            for (int n = 0; n < 8; n++)
                b->nodes[b->nnodes + (size_t)n] = (rad_node){-1, 0.0f};
            b->nnodes += 8;
        } else if (b->nodes[k].child < 0) {
            return 0; /* not the Y tree's structure */
        }
        for (int n = 0; n < 8; n++)
            if (!tree_node(t, &q, e, (size_t)b->nodes[k].child + (size_t)n, depth + 1))
                return 0;
        q = xml_skip(q, e);
        if (q >= e || *q != '}')
            return 0;
        *p = q + 1;
        t->depth = depth + 1 > t->depth ? depth + 1 : t->depth;
        return 1;
    }
    float v[8];
    int nv = 0;
    while (nv < 8 && xml_value(&q, e, &v[nv]))
        nv++;
    q = xml_skip(q, e);
    if ((nv != 1 && nv != 8) || q >= e || *q != '}')
        return 0;
    *p = q + 1;
    if (nv == 1) {
        if (t->what == 0) {
            b->nodes[k].v = v[0];
            b->leaves++;
        } else if (b->nodes[k].child >= 0) {
            return 0;
        } else {
            b->cv[k * RAD_CV + 2 + (size_t)t->what] = v[0];
        }
        return 1;
    }
    /* a grid of eight leaves: grid index g = i0 i1 i2, child n = i0 + 2 i1 + 4 i2 */
    if (t->what == 0) {
        if (b->nnodes + 8 > RAD_READ_MAX_NODES)
            return 0;
        if (b->nnodes + 8 > t->cap) {
            size_t nc = t->cap * 2 + 64;
            rad_node *nn = realloc(b->nodes, nc * sizeof *nn);
            if (!nn)
                return 0;
            b->nodes = nn;
            t->cap = nc;
        }
        b->nodes[k].child = (int32_t)b->nnodes;
        b->nnodes += 8;
        b->leaves += 8;
    } else if (b->nodes[k].child < 0) {
        return 0;
    }
    size_t c0 = (size_t)b->nodes[k].child;
    for (int g = 0; g < 8; g++) {
        int n = ((g >> 2) & 1) | (((g >> 1) & 1) << 1) | ((g & 1) << 2);
        if (t->what == 0) {
            b->nodes[c0 + (size_t)n] = (rad_node){-1, v[g]};
        } else {
            if (b->nodes[c0 + (size_t)n].child >= 0)
                return 0;
            b->cv[(c0 + (size_t)n) * RAD_CV + 2 + (size_t)t->what] = v[g];
        }
    }
    t->depth = depth + 1 > t->depth ? depth + 1 : t->depth;
    return 1;
}

/* A number after the text key in [b, e) ("n = "): 1 and *v, or 0. */
static int after_key(const char *b, const char *e, const char *key, double *v)
{
    size_t lk = strlen(key);
    for (const char *p = b; p + lk < e; p++)
        if (memcmp(p, key, lk) == 0) {
            char buf[40];
            size_t k = 0;
            p += lk;
            while (p < e && k + 1 < sizeof buf && (isdigit((unsigned char)*p) || *p == '.' ||
                                                  *p == 'e' || *p == '-' || *p == '+'))
                buf[k++] = *p++;
            buf[k] = 0;
            char *endp;
            *v = strtod(buf, &endp);
            return k > 0 && *endp == 0 && isfinite(*v);
        }
    return 0;
}

static btdf_status bad(xml_in *x, const char *what)
{
    return core_say(BTDF_EFORMAT, x->msg, x->msglen, "not a btdftab Radiance BSDF: %s", what);
}

/* The <ScatteringData> [b, be) of channel w of block rb: a tensor tree (the Visible
   tree makes the nodes, a colour tree fills their values) or an npatch x npatch Klems
   matrix. */
static btdf_status xml_block_data(xml_in *x, rad_block *rb, int w, int tree, size_t np,
                                  const char *b, const char *be)
{
    if (tree) {
        if (w > 0 && !rb->cv) {
            if (!rb->nodes)
                return bad(x, "a colour tree before its Visible tree");
            rb->cv = calloc(rb->nnodes * RAD_CV, sizeof *rb->cv);
            if (!rb->cv)
                return core_say(BTDF_ENOMEM, x->msg, x->msglen, "out of memory");
        }
        tree_in t = {rb, w == 0 ? 0 : rb->nnodes, w, 0};
        if (w == 0) {
            rb->nodes = malloc(64 * sizeof *rb->nodes);
            if (!rb->nodes)
                return core_say(BTDF_ENOMEM, x->msg, x->msglen, "out of memory");
            t.cap = 64;
            rb->nodes[0] = (rad_node){-1, 0.0f};
            rb->nnodes = 1;
        }
        const char *tp = b;
        if (!tree_node(&t, &tp, be, 0, 0) || xml_skip(tp, be) != be)
            return bad(x, "a tensor tree that is not nested {...} of 1 or 8 values "
                          "(or the Visible tree's structure)");
        if (w == 0)
            rb->depth = t.depth;
    } else {
        float **m = w == 0 ? &rb->klems : (w == 1 ? &rb->klems_x : &rb->klems_z);
        *m = malloc(np * np * sizeof **m);
        if (!*m)
            return core_say(BTDF_ENOMEM, x->msg, x->msglen, "out of memory");
        const char *vp = b;
        for (size_t i = 0; i < np * np; i++)
            if (!xml_value(&vp, be, &(*m)[i]))
                return bad(x, "a Klems matrix without its npatch x npatch values "
                              "(finite, >= 0)");
        if (xml_skip(vp, be) != be)
            return bad(x, "a Klems matrix with more values than npatch x npatch");
    }
    return BTDF_OK;
}

static btdf_status xml_parse(xml_in *x, btdf_rad *r)
{
    const char *s = x->s, *e = x->end, *b, *be;
    /* the prolog's comment holds the command line: read after it */
    const char *c0 = NULL;
    for (const char *p = s; p + 4 <= e; p++)
        if (memcmp(p, "<!--", 4) == 0) {
            c0 = p;
            break;
        }
    if (c0) {
        const char *c1 = NULL;
        for (const char *p = c0 + 4; p + 3 <= e; p++)
            if (memcmp(p, "-->", 3) == 0) {
                c1 = p + 3;
                break;
            }
        if (!c1)
            return bad(x, "a comment never ends");
        s = c1;
    }
    const char *we, *wb;
    if (!xml_elem(s, e, "WindowElement", &wb, &we))
        return bad(x, "no <WindowElement> element");
    s = wb;
    e = we;
    if (!xml_elem(s, e, "Comments", &b, &be))
        return bad(x, "no <Comments> with the material's parameters");
    btdf_params_default(&r->p);
    double v[3];
    if (!after_key(b, be, "n = ", &v[0]) || !after_key(b, be, "s = ", &r->p.smoothness) ||
        !after_key(b, be, "k0 = ", &r->p.k0))
        return bad(x, "the <Comments> lack 'n = ', 's = ' or 'k0 = '");
    r->p.ior[0] = v[0];
    r->p.channels = 1;
    if (after_key(b, be, " (R), ", &v[1]) && after_key(b, be, " (G), ", &v[2])) {
        r->p.channels = 3;
        r->p.ior[1] = v[1];
        r->p.ior[2] = v[2];
    }
    char pm[256];
    if (btdf_params_check(&r->p, pm, sizeof pm) != BTDF_OK)
        return bad(x, pm);
    double tol;
    r->tolerance = after_key(b, be, ", tolerance ", &tol) ? tol : 0.0;
    r->channels = r->p.channels;
    if (xml_elem(s, e, "Name", &b, &be))
        xml_text(b, be, r->name, sizeof r->name);
    if (!xml_elem(s, e, "IncidentDataStructure", &b, &be))
        return bad(x, "no <IncidentDataStructure>");
    if ((size_t)(be - b) == 11 && memcmp(b, "TensorTree3", 11) == 0) {
        r->basis = RAD_BASIS_TREE3;
    } else if ((size_t)(be - b) == 7 && memcmp(b, "Columns", 7) == 0) {
        if (!xml_elem(s, e, "AngleBasisName", &b, &be))
            return bad(x, "a Columns file without <AngleBasisName>");
        int found = 0;
        for (int k = RAD_BASIS_KLEMS_FULL; k <= RAD_BASIS_KLEMS_QUARTER; k++) {
            const char *nm = rad_klems((rad_basis)k)->name;
            if ((size_t)(be - b) == strlen(nm) && memcmp(b, nm, strlen(nm)) == 0) {
                r->basis = (rad_basis)k;
                found = 1;
            }
        }
        if (!found)
            return bad(x, "an angle basis other than LBNL/Klems Full, Half or Quarter");
        r->kb = rad_klems(r->basis);
    } else {
        return bad(x, "an <IncidentDataStructure> other than TensorTree3 or Columns");
    }
    r->nblocks = 4;
    rad_xyz_to_rgb(r->to_rgb);
    for (int k = 0; k < 4; k++)
        rad_block_of(k, r->p.ior[0], &r->b[k]);
    int tree = r->basis == RAD_BASIS_TREE3, nch = r->channels == 3 ? 3 : 1;
    const char *const names[2][3] = {{"Visible", "CIE-X", "CIE-Z"}, {"Visible", "CIE-u", "CIE-v"}};
    int seen[3][4] = {{0}};
    size_t np = tree ? 0 : (size_t)r->kb->npatch;
    int nblk = 4; /* the writer writes two (transmission) or four */
    const char *p = s;
    for (int w = 0; w < nch; w++) {
        const char *db, *de;
        if (!xml_elem(p, e, "WavelengthData", &db, &de))
            return bad(x, "fewer <WavelengthData> elements than its channels");
        p = de;
        if (!xml_elem(db, de, "Wavelength", &b, &be) ||
            (size_t)(be - b) != strlen(names[tree][w]) ||
            memcmp(b, names[tree][w], (size_t)(be - b)) != 0)
            return bad(x, "a <Wavelength> out of its order (Visible, then CIE-X and CIE-Z, "
                          "or CIE-u and CIE-v)");
        const char *q = db;
        for (int blk = 0; blk < nblk; blk++) {
            const char *bb, *bbe;
            if (!xml_elem(q, de, "WavelengthDataBlock", &bb, &bbe)) {
                if (w == 0 && blk == 2) { /* the transmission blocks alone */
                    nblk = 2;
                    break;
                }
                return bad(x, "a <WavelengthData> with other than two or four blocks");
            }
            q = bbe;
            if (!xml_elem(bb, bbe, "WavelengthDataDirection", &b, &be))
                return bad(x, "a block without <WavelengthDataDirection>");
            int k = -1;
            for (int j = 0; j < 4; j++)
                if ((size_t)(be - b) == strlen(r->b[j].label) &&
                    memcmp(b, r->b[j].label, (size_t)(be - b)) == 0)
                    k = j;
            if (k < 0 || k >= nblk || seen[w][k])
                return bad(x, "a block direction unknown, given twice or out of its place");
            seen[w][k] = 1;
            if (!xml_elem(bb, bbe, "ScatteringData", &b, &be))
                return bad(x, "a block without <ScatteringData>");
            btdf_status st = xml_block_data(x, &r->b[k], w, tree, np, b, be);
            if (st != BTDF_OK)
                return st;
        }
        if (xml_elem(q, de, "WavelengthDataBlock", &b, &be))
            return bad(x, "a <WavelengthData> with more than four blocks");
    }
    r->nblocks = nblk;
    /* the errors the file reports, when it does ("LABEL: e_L1 max X, e_T max Y") */
    if (xml_elem(s, e, "Comments", &b, &be)) {
        int all = 1;
        for (int k = 0; k < nblk; k++) {
            char key[64];
            snprintf(key, sizeof key, "%s: e_L1 max ", r->b[k].label);
            all &= after_key(b, be, key, &r->e_l1[k]);
            snprintf(key, sizeof key, "%s: e_L1 max %.4g, e_T max ", r->b[k].label, r->e_l1[k]);
            if (!after_key(b, be, key, &r->e_t[k]))
                r->e_t[k] = 0.0;
        }
        r->reported = all;
    }
    return BTDF_OK;
}

BTDF_API btdf_status btdf_rad_read_mem(const void *data, size_t len, btdf_rad **out, char *msg,
                                       size_t msglen)
{
    if (!out || (!data && len))
        return core_say(BTDF_EINVAL, msg, msglen, "data or out pointer missing");
    *out = NULL;
    btdf_rad *r = calloc(1, sizeof *r);
    if (!r)
        return core_say(BTDF_ENOMEM, msg, msglen, "out of memory");
    xml_in x = {data, (const char *)data + len, msg, msglen};
    btdf_status st = xml_parse(&x, r);
    if (st != BTDF_OK) {
        btdf_rad_free(r);
        return st;
    }
    *out = r;
    return BTDF_OK;
}

/* A file of at most XML_READ_MAX bytes (a Klems Full colour file is about 3 MB, a
   colour tree at its node budget some tens of MB), read whole: a FIFO or /dev/zero ends
   at the cap, never in a hang on memory. */
#define XML_READ_MAX ((size_t)1 << 28)

static btdf_status xml_read(const char *path, btdf_rad **out, char *msg, size_t msglen)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return core_say(BTDF_EIO, msg, msglen, "cannot open: %s", strerror(errno));
    size_t cap = 1 << 16, len = 0;
    char *buf = malloc(cap);
    btdf_status st = BTDF_OK;
    while (buf) {
        if (len == cap) {
            if (cap >= XML_READ_MAX) {
                st = core_say(BTDF_EFORMAT, msg, msglen, "larger than %zu bytes: not a "
                              "btdftab Radiance BSDF", XML_READ_MAX);
                break;
            }
            char *nb = realloc(buf, cap * 2);
            if (!nb)
                break;
            buf = nb;
            cap *= 2;
        }
        size_t got = fread(buf + len, 1, cap - len, f);
        len += got;
        if (got == 0)
            break;
    }
    if (!buf) {
        fclose(f);
        return core_say(BTDF_ENOMEM, msg, msglen, "out of memory");
    }
    if (st == BTDF_OK && ferror(f))
        st = core_say(BTDF_EIO, msg, msglen, "read error: %s", strerror(errno));
    fclose(f);
    if (st == BTDF_OK)
        st = btdf_rad_read_mem(buf, len, out, msg, msglen);
    free(buf);
    return st;
}

/* What a read .xml holds: basis, material, per block its size and value range. */
static btdf_status xml_inspect(const btdf_input *in, FILE *out)
{
    const btdf_rad *r = in->radiance;
    char b[40];
    fprintf(out, "basis: %s\nchannels: %d\nior:", rad_basis_name(r->basis), r->channels);
    for (int c = 0; c < r->channels; c++) {
        btdf_format_double(r->p.ior[c], b, sizeof b);
        fprintf(out, " %s", b);
    }
    btdf_format_double(r->p.smoothness, b, sizeof b);
    fprintf(out, "\nsmoothness: %s\n", b);
    btdf_format_double(r->p.k0, b, sizeof b);
    fprintf(out, "k0: %s\n", b);
    if (r->name[0])
        fprintf(out, "name: %s\n", r->name);
    if (r->basis == RAD_BASIS_TREE3)
        fprintf(out, "tolerance: %g\n", r->tolerance);
    for (int k = 0; k < r->nblocks; k++) {
        const rad_block *rb = &r->b[k];
        double lo = HUGE_VAL, hi = 0.0;
        size_t n = r->basis == RAD_BASIS_TREE3 ? rb->nnodes
                                               : (size_t)r->kb->npatch * (size_t)r->kb->npatch;
        for (size_t i = 0; i < n; i++) {
            double v = r->basis == RAD_BASIS_TREE3 ? (rb->nodes[i].child < 0 ? rb->nodes[i].v : -1.0)
                                                   : rb->klems[i];
            if (v < 0.0)
                continue;
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
        if (r->basis == RAD_BASIS_TREE3)
            fprintf(out, "%s: %zu leaves, depth %d", rb->label, rb->leaves, rb->depth);
        else
            fprintf(out, "%s: %zu x %zu patches", rb->label, (size_t)r->kb->npatch,
                    (size_t)r->kb->npatch);
        fprintf(out, ", values %.6g to %.6g 1/sr (Y)", lo < HUGE_VAL ? lo : 0.0, hi);
        if (r->reported)
            fprintf(out, "; stored e_L1 max %.4g, e_T max %.4g", r->e_l1[k], r->e_t[k]);
        fputc('\n', out);
    }
    return ferror(out) ? BTDF_EIO : BTDF_OK;
}

const btdf_format_ops btdf_format_xml = {
    .name = "Radiance BSDF XML",
    .ext = ".xml",
    .available = 1,
    .needs = BTDF_NEEDS_RADIANCE,
    .write_stream = xml_write,
    .read_rad = xml_read,
    .inspect = xml_inspect,
};
