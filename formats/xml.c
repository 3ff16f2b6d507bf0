/* SPDX-License-Identifier: MIT */
/* xml.c: LBNL WINDOW / Radiance BSDF XML (renderer-formats.md section 3), TensorTree3 or
   Klems, from a btdf_rad built in src/radiance/radiance.c. Values are the BTDF in 1/sr, no cosine. */
#include <stdio.h>
#include <string.h>

#include "formats/formats.h"
#include "radiance/radiance.h"

/* Text a reader takes literally: &, < and > escaped, control characters dropped. */
static void put_text(FILE *f, const char *s)
{
    for (; s && *s; s++) {
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

/* In a comment "--" is not allowed: write it as "- -". */
static void put_comment_text(FILE *f, const char *s)
{
    for (; s && *s; s++) {
        if ((unsigned char)*s < 0x20)
            continue;
        fputc(*s, f);
        if (*s == '-' && s[1] == '-')
            fputc(' ', f);
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
    if (c->opts->provenance) {
        fputs("     Command: ", f);
        put_comment_text(f, c->opts->provenance);
        fputc('\n', f);
    }
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

const btdf_format_ops btdf_format_xml = {
    .name = "Radiance BSDF XML",
    .ext = ".xml",
    .available = 1,
    .needs = BTDF_NEEDS_RADIANCE,
    .write_stream = xml_write,
};
