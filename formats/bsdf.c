/* SPDX-License-Identifier: MIT */
/* bsdf.c: the SCATFUN v1 (.bsdf) format: its byte layout (writes, reads, checks and
   describes the files) and its entry of the format registry. The object is
   src/scatfun/; its series are built there. */
#include <errno.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "btdf.h"
#include "btdf_scatfun.h"
#include "core/core.h"
#include "formats/formats.h"
#include "io/tmpfile.h"
#include "scatfun/scatfun.h"

/* Layout constants of SCATFUN v1 (docs/scatfun.md). */
#define HEADER_BYTES 64u
#define FLAG_BSDF 1u
/* A series longer than this cannot come out of a build; readers refuse more so a
   scratch buffer sized by mMax stays small. */
#define MAX_ORDER_READ (1u << 20)

/* ------------------------------------------------------------------------- */
/* Bytes: writing and reading                                                */
/* ------------------------------------------------------------------------- */

static void put_u32(unsigned char *b, uint32_t v)
{
    b[0] = (unsigned char)(v & 0xff);
    b[1] = (unsigned char)((v >> 8) & 0xff);
    b[2] = (unsigned char)((v >> 16) & 0xff);
    b[3] = (unsigned char)((v >> 24) & 0xff);
}

static void put_f32(unsigned char *b, float v)
{
    uint32_t u;
    memcpy(&u, &v, 4); /* IEEE 754 binary32 assumed, as every supported host has */
    put_u32(b, u);
}

static uint32_t get_u32(const unsigned char *b)
{
    return (uint32_t)b[0] | ((uint32_t)b[1] << 8) | ((uint32_t)b[2] << 16) |
           ((uint32_t)b[3] << 24);
}

static float get_f32(const unsigned char *b)
{
    uint32_t u = get_u32(b);
    float v;
    memcpy(&v, &u, 4);
    return v;
}

/* a * b + c into *out, 0 on success, -1 when it does not fit in uint64_t. */
static int mul_add_u64(uint64_t a, uint64_t b, uint64_t c, uint64_t *out)
{
    if (b != 0 && a > (UINT64_MAX - c) / b)
        return -1;
    *out = a * b + c;
    return 0;
}

/* The file size a header declares (nBases = 1, no parameters), or -1 on overflow. */
static int declared_size(uint64_t n, uint64_t ncoeffs, uint64_t meta, uint64_t *out)
{
    uint64_t nn, s = 64;
    if (mul_add_u64(n, n, 0, &nn))
        return -1;
    if (mul_add_u64(n, 4, s, &s) || mul_add_u64(nn, 12, s, &s) ||
        mul_add_u64(ncoeffs, 4, s, &s) || mul_add_u64(meta, 1, s, &s))
        return -1;
    *out = s;
    return 0;
}

static const char *default_meta(const btdf_scatfun *f, char *buf, size_t len)
{
    if (!f->built)
        return "";
    const btdf_params *p = &f->params;
    /* transmission-only files keep the words they always had */
    char words[64];
    const char *sides = f->sides == BTDF_SIDE_BOTH    ? "both"
                        : f->sides == BTDF_SIDE_ENTER ? "enter"
                        : f->sides == BTDF_SIDE_LEAVE ? "leave"
                                                      : words;
    snprintf(words, sizeof words, "%s%s%s%s", f->sides & BTDF_SCATFUN_T_ENTER ? "T_enter " : "",
             f->sides & BTDF_SCATFUN_T_LEAVE ? "T_leave " : "",
             f->sides & BTDF_SCATFUN_R_TOP ? "R_top " : "",
             f->sides & BTDF_SCATFUN_R_BOTTOM ? "R_bottom" : "");
    /* xu-sun keeps the words it always had; another model names itself */
    const char *model = p->model == BTDF_MODEL_XU_SUN ? "Xu & Sun 2008 Eq. 25"
                                                      : btdf_model_name(p->model);
    if (p->channels == 3)
        snprintf(buf, len,
                 "{\"generator\": \"btdftab %s\", \"model\": \"%s\", "
                 "\"ior\": [%.9g, %.9g, %.9g], \"smoothness\": %.9g, \"k0\": %.9g, "
                 "\"tolerance\": %.3g, \"sides\": \"%s\", \"channels\": \"Y,R,B\"}",
                 BTDF_VERSION_STRING, model, p->ior[0], p->ior[1], p->ior[2], p->smoothness,
                 p->k0, f->tolerance, sides);
    else
        snprintf(buf, len,
                 "{\"generator\": \"btdftab %s\", \"model\": \"%s\", "
                 "\"ior\": %.9g, \"smoothness\": %.9g, \"k0\": %.9g, \"tolerance\": %.3g, "
                 "\"sides\": \"%s\", \"channels\": \"Y\"}",
                 BTDF_VERSION_STRING, model, p->ior[0], p->smoothness, p->k0, f->tolerance,
                 sides);
    return buf;
}

/* The metadata bytes a write would append. */
static void meta_bytes(const btdf_scatfun *f, const char *metadata_json, char *buf,
                       size_t buflen, const char **m, size_t *mlen)
{
    if (metadata_json) {
        *m = metadata_json;
        *mlen = strlen(metadata_json);
    } else if (f->meta) {
        *m = f->meta;
        *mlen = f->metalen;
    } else {
        *m = default_meta(f, buf, buflen);
        *mlen = strlen(*m);
    }
}

BTDF_API size_t btdf_scatfun_file_size(const btdf_scatfun *f, const char *metadata_json)
{
    if (!f)
        return 0;
    char buf[512];
    const char *m;
    size_t ml;
    meta_bytes(f, metadata_json, buf, sizeof buf, &m, &ml);
    uint64_t s;
    if (declared_size(f->n, f->ncoeffs, ml, &s) || s > SIZE_MAX)
        return 0;
    return (size_t)s;
}

BTDF_API btdf_status btdf_scatfun_to_mem(const btdf_scatfun *f, const char *metadata_json,
                                         unsigned char **buf, size_t *len, char *msg,
                                         size_t msglen)
{
    if (!f || !buf || !len)
        return core_say(BTDF_EINVAL, msg, msglen, "file, buffer or length pointer missing");
    char mb[512];
    const char *m;
    size_t ml;
    meta_bytes(f, metadata_json, mb, sizeof mb, &m, &ml);
    uint64_t size;
    if (ml > UINT32_MAX || declared_size(f->n, f->ncoeffs, ml, &size) || size > SIZE_MAX)
        return core_say(BTDF_EOVERFLOW, msg, msglen, "file would not fit the format's sizes");
    unsigned char *b = malloc((size_t)size);
    if (!b)
        return core_say(BTDF_ENOMEM, msg, msglen, "cannot allocate %llu bytes",
                   (unsigned long long)size);
    memset(b, 0, HEADER_BYTES);
    memcpy(b, "SCATFUN", 7);
    b[7] = 1;
    put_u32(b + 8, FLAG_BSDF);
    put_u32(b + 12, f->n);
    put_u32(b + 16, f->ncoeffs);
    put_u32(b + 20, f->mmax);
    put_u32(b + 24, f->channels);
    put_u32(b + 28, 1);            /* nBases */
    put_u32(b + 32, (uint32_t)ml); /* nMetadataBytes */
    put_u32(b + 36, 0);            /* nParameters */
    put_u32(b + 40, 0);            /* nParameterValues */
    put_f32(b + 44, f->eta);
    put_f32(b + 48, f->alpha[0]);
    put_f32(b + 52, f->alpha[1]);
    put_f32(b + 56, 0.0f);
    put_f32(b + 60, 0.0f);
    size_t pos = HEADER_BYTES, n = f->n;
    for (size_t i = 0; i < n; i++, pos += 4)
        put_f32(b + pos, f->nodes[i]);
    for (size_t i = 0; i < n * n; i++, pos += 4)
        put_f32(b + pos, f->cdf[i]);
    for (size_t i = 0; i < 2 * n * n; i++, pos += 4)
        put_u32(b + pos, f->offsets[i]);
    for (size_t i = 0; i < f->ncoeffs; i++, pos += 4)
        put_f32(b + pos, f->coeffs[i]);
    if (ml)
        memcpy(b + pos, m, ml);
    pos += ml;
    if (pos != size) { /* cannot happen: the layout above is the size formula */
        free(b);
        return core_say(BTDF_EFORMAT, msg, msglen, "internal size mismatch %zu != %llu", pos,
                   (unsigned long long)size);
    }
    *buf = b;
    *len = pos;
    return BTDF_OK;
}

/* btdf_scatfun_write is the registry's (formats/registry.c): one atomic write path. */

#define FMT_FAIL(...) core_say(BTDF_EFORMAT, msg, msglen, __VA_ARGS__)

BTDF_API btdf_status btdf_scatfun_read_mem(const void *vbuf, size_t len, btdf_scatfun **out,
                                           char *msg, size_t msglen)
{
    const unsigned char *b = vbuf;
    if (!out || (!b && len))
        return core_say(BTDF_EINVAL, msg, msglen, "buffer or output pointer missing");
    if (len < HEADER_BYTES)
        return FMT_FAIL("file of %zu bytes is shorter than the 64-byte SCATFUN header", len);
    if (memcmp(b, "SCATFUN", 7) != 0)
        return FMT_FAIL("not a SCATFUN file (magic bytes differ)");
    if (b[7] != 1)
        return FMT_FAIL("version %u: only SCATFUN version 1 is supported", (unsigned)b[7]);
    uint32_t flags = get_u32(b + 8), n = get_u32(b + 12), nco = get_u32(b + 16),
             mmax = get_u32(b + 20), ch = get_u32(b + 24), nb = get_u32(b + 28),
             nmeta = get_u32(b + 32), npar = get_u32(b + 36), npv = get_u32(b + 40);
    if (flags != FLAG_BSDF)
        return FMT_FAIL("flags = %u: must be 1 (a BSDF without harmonic extrapolation)", flags);
    if (ch != 1 && ch != 3)
        return FMT_FAIL("nChannels = %u: must be 1 or 3", ch);
    if (nb != 1)
        return FMT_FAIL("nBases = %u: must be 1", nb);
    if (npar != 0)
        return FMT_FAIL("nParameters = %u: must be 0", npar);
    if (npv != 0)
        return FMT_FAIL("nParameterValues = %u: must be 0", npv);
    if (n < 2)
        return FMT_FAIL("nNodes = %u: at least 2 nodes (-1 and +1) are needed", n);
    if (mmax > MAX_ORDER_READ)
        return FMT_FAIL("nMaxOrder = %u: larger than %u", mmax, MAX_ORDER_READ);
    uint64_t size;
    if (declared_size(n, nco, nmeta, &size) || size != (uint64_t)len)
        return FMT_FAIL("size %zu bytes does not match the header (nNodes = %u, nCoeffs = %u, "
                        "nMetadataBytes = %u)",
                        len, n, nco, nmeta);
    float eta = get_f32(b + 44);
    if (!isfinite(eta) || !(eta > 0.0f))
        return FMT_FAIL("eta = %g: must be finite and > 0", (double)eta);
    for (int k = 0; k < 4; k++) {
        float v = get_f32(b + 48 + 4 * k);
        if (!isfinite(v))
            return FMT_FAIL("header float at byte %d is not finite", 48 + 4 * k);
    }
    btdf_scatfun *f = sf_alloc(n, nco, mmax, ch, 1, nmeta);
    if (!f)
        return core_say(BTDF_ENOMEM, msg, msglen, "out of memory");
    size_t nn = (size_t)n * n; /* fits: 12 n^2 <= len */
    f->eta = eta;
    f->alpha[0] = get_f32(b + 48);
    f->alpha[1] = get_f32(b + 52);
    btdf_status st = BTDF_OK;
    size_t pos = HEADER_BYTES;
    for (uint32_t i = 0; i < n; i++, pos += 4) {
        float v = get_f32(b + pos);
        if (!isfinite(v)) {
            st = FMT_FAIL("node %u is not finite", i);
            goto fail;
        }
        if (i > 0 && !(v >= f->nodes[i - 1])) {
            st = FMT_FAIL("nodes not ascending: node %u = %g after %g", i, (double)v,
                          (double)f->nodes[i - 1]);
            goto fail;
        }
        f->nodes[i] = v;
    }
    /* Files reach the poles: +-1 (older files, layerlab) or within 1e-6 of them (the
       largest float below 1, which this library writes: see POLE_NODE). */
    if (!(f->nodes[0] >= -1.0f && f->nodes[0] <= -0.999999f && f->nodes[n - 1] <= 1.0f &&
          f->nodes[n - 1] >= 0.999999f)) {
        st = FMT_FAIL("nodes must span -1 to +1 (within 1e-6), found %g to %g",
                      (double)f->nodes[0], (double)f->nodes[n - 1]);
        goto fail;
    }
    for (size_t i = 0; i < nn; i++, pos += 4) {
        float v = get_f32(b + pos);
        if (!isfinite(v)) {
            st = FMT_FAIL("cdf entry %zu (row %zu) is not finite", i, i / n);
            goto fail;
        }
        f->cdf[i] = v;
    }
    for (size_t i = 0; i < nn; i++, pos += 8) {
        uint32_t off = get_u32(b + pos), m = get_u32(b + pos + 4);
        if (m > mmax) {
            st = FMT_FAIL("pair (%zu, %zu): series length %u exceeds nMaxOrder = %u", i / n,
                          i % n, m, mmax);
            goto fail;
        }
        uint64_t end = (uint64_t)off + (uint64_t)m * ch;
        if (end > nco) {
            st = FMT_FAIL("pair (%zu, %zu): offset %u + length %u x %u channels runs past "
                          "nCoeffs = %u",
                          i / n, i % n, off, m, ch, nco);
            goto fail;
        }
        f->offsets[2 * i] = off;
        f->offsets[2 * i + 1] = m;
    }
    for (uint32_t i = 0; i < nco; i++, pos += 4) {
        float v = get_f32(b + pos);
        if (!isfinite(v)) {
            st = FMT_FAIL("coefficient %u is not finite", i);
            goto fail;
        }
        f->coeffs[i] = v;
    }
    if (sf_index(f)) {
        st = core_say(BTDF_ENOMEM, msg, msglen, "out of memory");
        goto fail;
    }
    memcpy(f->meta, b + pos, nmeta);
    f->meta[nmeta] = '\0';
    f->sides = 0;
    for (size_t i = 0; i < nn; i++) {
        if (!f->offsets[2 * i + 1])
            continue;
        double ms = f->nodes[i / n], mf = f->nodes[i % n];
        if (ms > 0 && mf > 0)
            f->sides |= BTDF_SCATFUN_T_ENTER;
        else if (ms < 0 && mf < 0)
            f->sides |= BTDF_SCATFUN_T_LEAVE;
        else if (ms > 0 && mf < 0)
            f->sides |= BTDF_SCATFUN_R_TOP;
        else if (ms < 0 && mf > 0)
            f->sides |= BTDF_SCATFUN_R_BOTTOM;
    }
    *out = f;
    return BTDF_OK;
fail:
    btdf_scatfun_free(f);
    return st;
}

BTDF_API btdf_status btdf_scatfun_read(const char *path, btdf_scatfun **out, char *msg,
                                       size_t msglen)
{
    if (!path || !out)
        return core_say(BTDF_EINVAL, msg, msglen, "path or output pointer missing");
    FILE *fp = fopen(path, "rb");
    if (!fp)
        return core_say(BTDF_EIO, msg, msglen, "%s: %s", path, strerror(errno));
    size_t cap = 1 << 16, len = 0;
    unsigned char *b = malloc(cap);
    btdf_status st = BTDF_OK;
    if (!b) {
        fclose(fp);
        return core_say(BTDF_ENOMEM, msg, msglen, "out of memory");
    }
    for (;;) {
        if (len == cap) {
            if (cap > SIZE_MAX / 2) {
                st = core_say(BTDF_EOVERFLOW, msg, msglen, "%s: file too large", path);
                break;
            }
            unsigned char *nb = realloc(b, cap * 2);
            if (!nb) {
                st = core_say(BTDF_ENOMEM, msg, msglen, "%s: out of memory", path);
                break;
            }
            b = nb;
            cap *= 2;
        }
        size_t got = fread(b + len, 1, cap - len, fp);
        len += got;
        if (got == 0) {
            if (ferror(fp))
                st = core_say(BTDF_EIO, msg, msglen, "%s: read failed", path);
            break;
        }
    }
    fclose(fp);
    if (st == BTDF_OK) {
        st = btdf_scatfun_read_mem(b, len, out, msg, msglen);
        if (st == BTDF_EFORMAT && msg && msglen) {
            /* prefix the path to the reason */
            char *tmp = malloc(msglen);
            if (tmp) {
                snprintf(tmp, msglen, "%s: %s", path, msg);
                memcpy(msg, tmp, msglen);
                free(tmp);
            }
        }
    }
    free(b);
    return st;
}

/* ------------------------------------------------------------------------- */
/* Inspection and getters                                                    */
/* ------------------------------------------------------------------------- */

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

/* The model a file holds: its builder's, or the metadata's "model" (btdftab writes the
   name of any model but xu-sun, whose files say "Xu & Sun 2008 Eq. 25" or nothing). */
static const char *file_model(const btdf_scatfun *f)
{
    if (f->built)
        return btdf_model_name(f->params.model);
    const char *m = f->metalen ? strstr(f->meta, "\"model\": \"") : NULL;
    if (m) {
        m += strlen("\"model\": \"");
        if (!strncmp(m, "smith\"", 6))
            return "smith";
        if (!strncmp(m, "full\"", 5))
            return "full";
    }
    return "xu-sun";
}

BTDF_API btdf_status btdf_scatfun_info(const btdf_scatfun *f, FILE *out)
{
    if (!f || !out)
        return BTDF_EINVAL;
    size_t nn = (size_t)f->n * f->n, nz = 0;
    uint32_t *len = malloc((nn ? nn : 1) * sizeof *len);
    if (!len)
        return BTDF_ENOMEM;
    for (size_t i = 0; i < nn; i++)
        if (f->offsets[2 * i + 1])
            len[nz++] = f->offsets[2 * i + 1];
    qsort(len, nz, sizeof *len, cmp_u32);
    int ok = 1;
    ok &= fprintf(out, "format            SCATFUN v1 (flags 1, nBases 1, no parameters)\n") > 0;
    ok &= fprintf(out, "nodes             %u (mu from %g to %g)\n", f->n, (double)f->nodes[0],
                  (double)f->nodes[f->n - 1]) > 0;
    ok &= fprintf(out, "channels          %u (%s)\n", f->channels,
                  f->channels == 3 ? "Y, R, B series" : "one series") > 0;
    ok &= fprintf(out, "eta               %.9g\n", (double)f->eta) > 0;
    ok &= fprintf(out, "alpha             %.6g %.6g\n", (double)f->alpha[0], (double)f->alpha[1]) > 0;
    ok &= fprintf(out, "sides             %s%s%s\n", f->sides & BTDF_SIDE_ENTER ? "enter " : "",
                  f->sides & BTDF_SIDE_LEAVE ? "leave" : "",
                  f->sides & BTDF_SCATFUN_TRANSMISSION ? "" : "none") > 0;
    ok &= fprintf(out, "reflection        %s%s%s\n", f->sides & BTDF_SCATFUN_R_TOP ? "top " : "",
                  f->sides & BTDF_SCATFUN_R_BOTTOM ? "bottom" : "",
                  f->sides & BTDF_SCATFUN_REFLECTION ? "" : "none") > 0;
    ok &= fprintf(out, "model             %s\n", file_model(f)) > 0;
    ok &= fprintf(out, "coefficients      %u floats\n", f->ncoeffs) > 0;
    ok &= fprintf(out, "mMax              %u\n", f->mmax) > 0;
    ok &= fprintf(out, "pairs             %zu, %zu with a series, %zu empty\n", nn, nz, nn - nz) > 0;
    if (nz)
        ok &= fprintf(out, "series length     min %u, median %u, max %u\n", len[0], len[nz / 2],
                      len[nz - 1]) > 0;
    ok &= fprintf(out, "file size         %zu bytes\n", btdf_scatfun_file_size(f, NULL)) > 0;
    double peak = btdf_scatfun_a0_peak(f);
    ok &= fprintf(out, "a0 peak           %.6g: %s\n", peak,
                  peak <= BTDF_SCATFUN_PBRT_FLOAT_SAFE_A0
                      ? "safe for pbrt-v3 in single precision"
                      : "pbrt-v3 in single precision can loop forever sampling it; build "
                        "pbrt-v3 with PBRT_FLOAT_AS_DOUBLE") > 0;
    if (f->built)
        ok &= fprintf(out, "build             tolerance %g, %.3f s\n", f->tolerance,
                      f->seconds_build) > 0;
    else if (f->metalen)
        ok &= fprintf(out, "metadata          %s\n", f->meta) > 0;
    free(len);
    return ok ? BTDF_OK : BTDF_EIO;
}

/* ------------------------------------------------------------------------- */
/* The registry's entry                                                      */
/* ------------------------------------------------------------------------- */

static btdf_status bsdf_write(const fmt_output_ctx *c, FILE *f, const char *path, char *msg,
                              size_t msglen)
{
    unsigned char *b = NULL;
    size_t len = 0;
    btdf_status st = btdf_scatfun_to_mem(c->scatfun, c->metadata_json, &b, &len, msg, msglen);
    if (st != BTDF_OK)
        return st;
    io_bytes bytes = {b, len};
    st = io_write_bytes(&bytes, f, path, msg, msglen);
    free(b);
    return st;
}

static btdf_status bsdf_inspect(const btdf_input *in, FILE *out)
{
    return btdf_scatfun_info(in->scatfun, out);
}

const fmt_ops fmt_bsdf = {
    .name = "SCATFUN",
    .ext = ".bsdf",
    .available = 1,
    .needs = BTDF_NEEDS_SERIES,
    .write_path = bsdf_write,
    .read_series = btdf_scatfun_read,
    .inspect = bsdf_inspect,
};
