/* SPDX-License-Identifier: MIT */
/* xml_read.c: reading back the Radiance BSDF XML that xml.c writes (renderer-formats.md
   section 3): btdf_rad_read_mem and the file reader of the .xml format. */
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

/* Room for node k's eight children at the end of the Y tree's nodes, and k pointing at
   them (the caller fills them and adds 8 to nnodes); 0 at the node cap or out of memory. */
static int tree_children(tree_in *t, size_t k)
{
    rad_block *b = t->b;
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
    return 1;
}

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
            if (!tree_children(t, k))
                return 0;
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
        if (!tree_children(t, k))
            return 0;
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
    /* the model the writer named (xml.c: "(model smith)", "(model full)"; none: xu-sun) */
    static const char *const models[2] = {"(model smith)", "(model full)"};
    for (int m = 0; m < 2; m++) {
        size_t lk = strlen(models[m]);
        for (const char *q = b; q + lk <= be; q++)
            if (memcmp(q, models[m], lk) == 0) {
                r->p.model = m ? BTDF_MODEL_FULL : BTDF_MODEL_SMITH;
                break;
            }
    }
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

btdf_status xml_read(const char *path, btdf_rad **out, char *msg, size_t msglen)
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
