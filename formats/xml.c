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
#include "formats/xml_impl.h"
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

static btdf_status xml_write(const fmt_output_ctx *c, FILE *f, char *msg, size_t msglen)
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
    int sys = r->system[0] != 0; /* a caller's BSDF: a pane's system (docs/pane.md) */
    if (sys)
        fprintf(f, "<!-- Written by btdftab %s: the system BSDF of %s, air to air.\n"
                   "     Values are the BSDF in 1/sr (no cosine factor). Radiance's -Z side "
                   "faces the front face: Transmission Front serves light from +Z (on the "
                   "back face),\n     Transmission Back light from -Z (on the front face); "
                   "Reflection Front light on -Z, Reflection Back on +Z.\n",
                BTDF_VERSION_STRING, r->system);
    else
        fprintf(f, "<!-- Written by btdftab %s: Xu & Sun (2008) Eq. 25, the BTDF of a rough "
                   "dielectric interface. Values are the BTDF in 1/sr (no cosine factor).\n",
                BTDF_VERSION_STRING);
    /* a model other than xu-sun says so (xu-sun files keep their bytes) */
    if (r->p.model == BTDF_MODEL_SMITH)
        fprintf(f, "     Model: smith: the facets of Eq. 25 with the height-correlated Smith "
                   "shadowing-masking of the same Gaussian surface in place of V(ti) V(to) "
                   "(k0 unused).\n");
    if (r->p.model == BTDF_MODEL_FULL)
        fprintf(f, "     Model: full: smith (the facets of Eq. 25 with the height-correlated "
                   "Smith shadowing-masking, k0 unused) plus the light scattered two or more "
                   "times,\n     from a random walk on the same microsurface tallied once "
                   "per index (n and 1/n), so that R + T = 1.\n");
    if (r->channels == 3)
        fprintf(f, "     Colour: R, G, B in Radiance's RGB (its default primaries, equal-energy "
                   "white) for n = %.9g, %.9g, %.9g, written as CIE %s.\n",
                r->p.ior[0], r->p.ior[1], r->p.ior[2], tree ? "Y, u', v'" : "X, Y, Z");
    if (!sys)
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
    put_text(f, r->name[0] ? r->name : (sys ? "pane" : "rough_interface"));
    fprintf(f, "</Name>\n\t\t<Manufacturer>btdftab %s</Manufacturer>\n", BTDF_VERSION_STRING);
    fprintf(f, "\t\t<Thickness unit=\"Millimeter\">0</Thickness>\n"
               "\t\t<DeviceType>Other</DeviceType>\n");
    const char *what =
        r->p.model == BTDF_MODEL_SMITH ? "Xu and Sun 2008 facets with the Smith term (model smith)"
        : r->p.model == BTDF_MODEL_FULL ? "Xu and Sun 2008 facets with the Smith term and "
                                          "multiple scattering (model full)"
                                        : "Xu and Sun 2008 Eq. 25";
    if (sys && r->channels == 3)
        fprintf(f, "\t\t<Comments>%s: n = %.9g (R), %.9g (G), %.9g (B) in Radiance's RGB, "
                   "written as CIE X, Y, Z; s = %.9g, k0 = %.9g; basis %s", r->system,
                r->p.ior[0], r->p.ior[1], r->p.ior[2], r->p.smoothness, r->p.k0,
                rad_basis_name(r->basis));
    else if (sys)
        fprintf(f, "\t\t<Comments>%s: n = %.9g, s = %.9g, k0 = %.9g; basis %s", r->system,
                r->p.ior[0], r->p.smoothness, r->p.k0, rad_basis_name(r->basis));
    else if (r->channels == 3)
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
    if (r->p.model != BTDF_MODEL_XU_SUN) /* xu-sun files print what they always did */
        fprintf(out, "model: %s\n", btdf_model_name(r->p.model));
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

const fmt_ops fmt_xml = {
    .name = "Radiance BSDF XML",
    .ext = ".xml",
    .available = 1,
    .needs = BTDF_NEEDS_RADIANCE,
    .write_stream = xml_write,
    .read_rad = xml_read,
    .inspect = xml_inspect,
};
