/* fmt_dds.c -- .dds tables: DirectDraw Surface, DX10 header, RGBA32F or RGBA16F, one mip level;
 * metadata in "<file>.dds.json" (mf_table_io.h); a table of more than 2 axes as its 2D atlas
 * (mf_table.h), the layout in the sidecar's "atlas".  Written and read here: OpenImageIO 2.4 handles
 * neither uncompressed float DDS direction. */
#include "io_internal.h"

#include <stdio.h>
#include <stdlib.h>

/* DDS with the DX10 extended header (148 bytes), then rows top to bottom, RGBA interleaved. */
#define DDS_HEADER_BYTES 148
#define DXGI_R32G32B32A32_FLOAT 2u
#define DXGI_R16G16B16A16_FLOAT 10u

/* legacy: no DX10 header, FourCC 116 (D3DFMT_A32B32G32R32F) or 113 (D3DFMT_A16B16G16R16F), data at 128 */
static void build_dds(mf_buf *b, const mf_table *t, const mf_table_atlas *a, const int *ch, int half, int legacy)
{
    uint32_t w = (uint32_t)a->width, hgt = (uint32_t)a->height;
    uint32_t bpp = half ? 8u : 16u;
    mf_buf_put(b, "DDS ", 4);
    mf_buf_u32le(b, 124);                           /* dwSize */
    mf_buf_u32le(b, 0x1u | 0x2u | 0x4u | 0x8u | 0x1000u); /* CAPS | HEIGHT | WIDTH | PITCH | PIXELFORMAT */
    mf_buf_u32le(b, hgt);
    mf_buf_u32le(b, w);
    mf_buf_u32le(b, w * bpp);                       /* pitch of a row in bytes */
    mf_buf_u32le(b, 0);                             /* depth */
    mf_buf_u32le(b, 1);                             /* mip levels (flag not set: one) */
    for (int i = 0; i < 11; ++i)
        mf_buf_u32le(b, 0);                         /* dwReserved1 */
    mf_buf_u32le(b, 32);                            /* DDS_PIXELFORMAT.dwSize */
    mf_buf_u32le(b, 0x4u);                          /* DDPF_FOURCC */
    if (legacy)
        mf_buf_u32le(b, half ? 113u : 116u);
    else
        mf_buf_put(b, "DX10", 4);
    for (int i = 0; i < 5; ++i)
        mf_buf_u32le(b, 0);                         /* bit count and masks */
    mf_buf_u32le(b, 0x1000u);                       /* DDSCAPS_TEXTURE */
    for (int i = 0; i < 4; ++i)
        mf_buf_u32le(b, 0);                         /* caps2..4, reserved2 */
    if (!legacy) {
        mf_buf_u32le(b, half ? DXGI_R16G16B16A16_FLOAT : DXGI_R32G32B32A32_FLOAT);
        mf_buf_u32le(b, 3);                         /* D3D10_RESOURCE_DIMENSION_TEXTURE2D */
        mf_buf_u32le(b, 0);                         /* miscFlag */
        mf_buf_u32le(b, 1);                         /* arraySize */
        mf_buf_u32le(b, 0);                         /* miscFlags2: alpha mode unknown */
    }
    size_t pixels = (size_t)a->width * (size_t)a->height;
    mf_buf_reserve(b, pixels * bpp);
    for (size_t p = 0; p < pixels && !b->failed; ++p) {
        long long i = io_atlas_texel(a, p); /* the identity for <= 2 axes */
        for (int c = 0; c < 4; ++c) {
            double v = ch[c] < 0 || i < 0 ? 0.0 : t->data[(size_t)i * (size_t)t->nfields + (size_t)ch[c]];
            if (half)
                mf_buf_u16le(b, mf_half_from_double(v));
            else
                mf_buf_f32le(b, (float)v);
        }
    }
}

static mf_status read_dds(const char *path, mf_table *t, mf_table_file_info *info, char *msg, size_t msg_size)
{
    unsigned char *data;
    size_t len;
    mf_status st = mf_io_read_file(path, path, &data, &len, NULL, msg, msg_size);
    if (st != MF_OK)
        return st;
    char why[256];
    size_t off = 128;
    mf_table_atlas atlas;
    int have_atlas = 0;
    int half;
    if (len < 128 || memcmp(data, "DDS ", 4) != 0 || io_get_u32(data + 4) != 124 || io_get_u32(data + 76) != 32) {
        mf_io_msg(msg, msg_size, path, "not a DDS file (bad magic or header sizes)");
        goto bad;
    }
    uint32_t height = io_get_u32(data + 12), width = io_get_u32(data + 16), flags = io_get_u32(data + 8),
             depth = io_get_u32(data + 24);
    uint32_t pf_flags = io_get_u32(data + 80), fourcc = io_get_u32(data + 84);
    if (!(pf_flags & 0x4u)) {
        mf_io_msg(msg, msg_size, path, "unsupported DDS pixel format (only RGBA32F and RGBA16F are read)");
        goto bad_unsupported;
    }
    if (fourcc == io_get_u32((const unsigned char *)"DX10")) {
        if (len < DDS_HEADER_BYTES) {
            mf_io_msg(msg, msg_size, path, "truncated DDS header (%zu bytes)", len);
            goto bad;
        }
        uint32_t fmt = io_get_u32(data + 128), dim = io_get_u32(data + 132), misc = io_get_u32(data + 136),
                 arr = io_get_u32(data + 140);
        if (fmt != DXGI_R32G32B32A32_FLOAT && fmt != DXGI_R16G16B16A16_FLOAT) {
            mf_io_msg(msg, msg_size, path, "unsupported DXGI format %u (only 2 = R32G32B32A32_FLOAT, 10 = "
                    "R16G16B16A16_FLOAT are read)", (unsigned)fmt);
            goto bad_unsupported;
        }
        if ((dim != 3 && !(dim == 2 && height == 1)) || arr != 1 || (misc & 0x4u)) {
            mf_io_msg(msg, msg_size, path, "unsupported DDS resource (dimension %u, array size %u, misc 0x%x): "
                    "only one 2D texture is read", (unsigned)dim, (unsigned)arr, (unsigned)misc);
            goto bad_unsupported;
        }
        half = (fmt == DXGI_R16G16B16A16_FLOAT);
        off = DDS_HEADER_BYTES;
    } else if (fourcc == 116u || fourcc == 113u) { /* D3DFMT_A32B32G32R32F, D3DFMT_A16B16G16R16F */
        half = (fourcc == 113u);
    } else {
        mf_io_msg(msg, msg_size, path, "unsupported DDS pixel format (FourCC 0x%08x)", (unsigned)fourcc);
        goto bad_unsupported;
    }
    if ((flags & 0x800000u) && depth > 1) {
        mf_io_msg(msg, msg_size, path, "volume DDS textures are not read");
        goto bad_unsupported;
    }
    if (width < 1 || height < 1 || width > (1u << 20) || height > (1u << 20)) {
        mf_io_msg(msg, msg_size, path, "DDS size %u x %u outside [1, 2^20]", (unsigned)width, (unsigned)height);
        goto bad;
    }
    int sizes[2] = {(int)width, (int)height};
    int naxes = height > 1 ? 2 : 1;
    size_t texels = io_texel_product(sizes, 2);
    size_t bpp = half ? 8 : 16;
    if (texels == 0 || texels > (len - off) / bpp) {
        mf_io_msg(msg, msg_size, path, "%zu data bytes, %u x %u RGBA%s needs %zu (truncated)", len - off,
                  (unsigned)width, (unsigned)height, half ? "16F" : "32F", texels * bpp);
        goto bad;
    }
    if (len - off != texels * bpp) {
        mf_io_msg(msg, msg_size, path, "%zu bytes after the %u x %u RGBA%s image (trailing data; mip levels are not read)",
                  len - off - texels * bpp, (unsigned)width, (unsigned)height, half ? "16F" : "32F");
        goto bad;
    }
    cJSON *side;
    st = io_read_sidecar(path, &side, msg, msg_size);
    if (st != MF_OK) {
        free(data);
        return st;
    }
    if (side) {
        /* the sidecar describes the whole table; the file holds 4 of its fields */
        mf_table full;
        mf_table_file_info fi;
        memset(&fi, 0, sizeof fi);
        const cJSON *dc = cJSON_GetObjectItemCaseSensitive(side, "dds_channels");
        st = io_image_header_to_table(side, sizes[0], sizes[1], 0, &full, &fi, &atlas, why, sizeof why);
        if (st != MF_OK || !cJSON_IsArray(dc) || cJSON_GetArraySize(dc) != 4) {
            if (st == MF_OK)
                snprintf(why, sizeof why, "\"dds_channels\" must be an array of 4 field names or nulls");
            mf_io_msg(msg, msg_size, path, "sidecar %s.json: %s", io_base_name(path), why);
            cJSON_Delete(side);
            if (st == MF_OK)
                mf_table_free(&full);
            free(data);
            return st == MF_OK || st == MF_ERR_FORMAT ? MF_ERR_FORMAT : st;
        }
        have_atlas = 1;
        char names[4][MF_TABLE_NAME_LEN];
        const char *np[4];
        const cJSON *v = dc->child;
        for (int c = 0; c < 4; ++c, v = v->next) {
            fi.dds_fields[c] = cJSON_IsString(v) ? mf_table_field(&full, v->valuestring) : -1;
            if (cJSON_IsString(v) && fi.dds_fields[c] < 0) {
                mf_io_msg(msg, msg_size, path, "sidecar %s.json: DDS channel %d names an unknown field", io_base_name(path), c);
                cJSON_Delete(side);
                mf_table_free(&full);
                goto bad;
            }
            if (fi.dds_fields[c] >= 0)
                snprintf(names[c], sizeof names[c], "%s", full.fields[fi.dds_fields[c]]);
            else
                snprintf(names[c], sizeof names[c], "zero%d", c);
            np[c] = names[c];
        }
        cJSON_Delete(side);
        fi.format = MF_TABLE_FORMAT_DDS;
        st = mf_table_create(t, full.naxes, full.axes, 4, np);
        if (st == MF_OK) {
            for (int i = 0; i < full.nmeta; ++i)
                t->meta[i] = full.meta[i];
            t->nmeta = full.nmeta;
        }
        mf_table_free(&full);
        if (st != MF_OK) {
            mf_io_msg(msg, msg_size, path, "sidecar %s.json: %s", io_base_name(path),
                    st == MF_ERR_ALLOC ? "out of memory" : "channel names clash (a field named zero<c>?)");
            free(data);
            return st == MF_ERR_ALLOC ? st : MF_ERR_FORMAT;
        }
        if (info)
            *info = fi;
    } else {
        const char *np[4] = {"R", "G", "B", "A"};
        st = io_generic_table(t, naxes, sizes, 4, np);
        if (st != MF_OK) {
            mf_io_msg(msg, msg_size, path, "out of memory");
            free(data);
            return st;
        }
        if (info)
            for (int c = 0; c < 4; ++c)
                info->dds_fields[c] = c;
    }
    for (size_t p = 0; p < texels; ++p) {
        long long i = have_atlas ? io_atlas_texel(&atlas, p) : (long long)p;
        if (i < 0)
            continue; /* an unused tile */
        for (size_t c = 0; c < 4; ++c) {
            size_t v = 4 * p + c;
            t->data[4 * (size_t)i + c] =
                half ? mf_half_to_double(io_get_u16(data + off + 2 * v)) : (double)io_get_f32(data + off + 4 * v);
        }
    }
    if (info)
        info->half_float = half;
    free(data);
    return MF_OK;
bad:
    free(data);
    return MF_ERR_FORMAT;
bad_unsupported:
    free(data);
    return MF_ERR_UNSUPPORTED;
}

static mf_status write_dds(const char *path, const mf_table *t, const io_write_ctx *c, char *msg, size_t msg_size)
{
    mf_table_atlas a;
    mf_status st = io_image_layout(path, t, &a, msg, msg_size);
    if (st != MF_OK)
        return st;
    io_header_extra x = {c->half_float ? "float16" : "float32", c->half_float ? c->half : NULL, c->ch,
                         t->naxes > 2 ? &a : NULL};
    mf_buf b = {0};
    build_dds(&b, t, &a, c->ch, c->half_float, c->dds_legacy);
    st = io_write_with_sidecar(path, &b, t, &x, msg, msg_size);
    mf_buf_free(&b);
    return st;
}

static const char *const k_ext[] = {"dds", NULL};
const io_format_ops io_format_dds = {MF_TABLE_FORMAT_DDS,
                                     "dds",
                                     k_ext,
                                     MF_TABLE_MAX_AXES,
                                     IO_CAP_HALF | IO_CAP_METADATA | IO_CAP_SIDECAR | IO_CAP_RGBA,
                                     write_dds,
                                     read_dds};
