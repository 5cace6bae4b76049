/* fmt_ktx2.c -- .ktx2 tables: Khronos KTX 2.0, VK_FORMAT_R32G32B32A32_SFLOAT (109) or
 * VK_FORMAT_R16G16B16A16_SFLOAT (97), one mip level, optionally Zstandard-supercompressed (scheme 2).
 *
 * Layout (docs/tables.md): the image is n0 x n1 texels (axis 0 along x, axis 1 along y, row i1 = 0
 * first); the fields go four at a time into RGBA, one array layer per group of four ("groups"),
 * and tables of more than 2 axes add one array layer per combination of the further axes:
 * layer = group + groups * (i2 + n2 (i3 + ...)).  With a channel selection (dds_fields) there is
 * one group of the chosen four.  A 2-axis table of at most 4 fields is a plain 2D texture
 * (layerCount 0), otherwise a 2D array texture.  Key/value data: "KTXwriter" and two mfkit keys,
 * "mfkit:table" (the metadata JSON) and "mfkit:channels" (a JSON array naming the field of every
 * channel of every group, null for a channel of zeros), so a KTX2 reads back as the whole table.
 *
 * Container: KTX 2.0 specification (Khronos, 2020), sections 3 (file structure), 3.9 (level index),
 * 3.10 (data format descriptor) and 3.11 (key/value data); the DFD is the Khronos Data Format
 * Specification 1.3 basic descriptor block (section 5), one sample per channel. */
#include "io_internal.h"

#include <stdio.h>
#include <stdlib.h>

#include <zstd.h>

static const unsigned char k_ktx2_magic[12] = {0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A};

#define VK_FORMAT_R16G16B16A16_SFLOAT 97u
#define VK_FORMAT_R32G32B32A32_SFLOAT 109u
#define KTX_SS_NONE 0u
#define KTX_SS_ZSTD 2u
#define KTX2_HEADER_BYTES 80u  /* identifier, 9 u32, the index (4 u32, 2 u64) */
#define KTX2_LEVEL_BYTES 24u   /* one level index entry */
#define KTX2_DFD_BYTES (4u + 24u + 4u * 16u) /* dfdTotalSize, basic block header, 4 samples */
#define KTX2_MAX_LAYERS 65536u

static void put_u64(mf_buf *b, uint64_t v)
{
    mf_buf_u32le(b, (uint32_t)(v & 0xffffffffu));
    mf_buf_u32le(b, (uint32_t)(v >> 32));
}

static uint64_t get_u64(const unsigned char *p) { return (uint64_t)io_get_u32(p) | ((uint64_t)io_get_u32(p + 4) << 32); }

/* The Khronos basic data format descriptor of RGBA float (half: 16-bit) samples, linear, BT.709
 * primaries, straight alpha (Data Format Specification 1.3, section 5). */
static void put_dfd(mf_buf *b, int half)
{
    uint32_t bits = half ? 16u : 32u, bytes = bits / 8u * 4u;
    mf_buf_u32le(b, KTX2_DFD_BYTES);          /* dfdTotalSize */
    mf_buf_u32le(b, 0u);                       /* vendorId 0 (Khronos), descriptorType 0 (basic) */
    mf_buf_u32le(b, 2u | ((24u + 4u * 16u) << 16)); /* versionNumber 2 (1.3), descriptorBlockSize */
    mf_buf_u32le(b, 1u | (1u << 8) | (1u << 16) | (0u << 24)); /* model RGBSDA, primaries BT709,
                                                                   transfer LINEAR, flags straight alpha */
    mf_buf_u32le(b, 0u);                       /* texelBlockDimension 1x1x1x1 (stored minus one) */
    mf_buf_u32le(b, bytes);                    /* bytesPlane0 = bytes per texel, planes 1-3 = 0 */
    mf_buf_u32le(b, 0u);                       /* bytesPlane4-7 */
    static const uint32_t channel[4] = {0u, 1u, 2u, 15u}; /* R, G, B, A (KHR_DF_CHANNEL_RGBSDA_*) */
    for (int c = 0; c < 4; ++c) {
        /* bitOffset | bitLength - 1 | channelType: channel id, qualifiers FLOAT (0x80) | SIGNED (0x40) */
        mf_buf_u32le(b, (uint32_t)c * bits | ((bits - 1u) << 16) | ((channel[c] | 0xC0u) << 24));
        mf_buf_u32le(b, 0u);          /* samplePosition0-3 */
        mf_buf_u32le(b, 0xBF800000u); /* sampleLower: -1.0f (signed float: the nominal range) */
        mf_buf_u32le(b, 0x3F800000u); /* sampleUpper: 1.0f */
    }
}

/* One key/value entry: keyAndValueByteLength, key NUL, value NUL, padding to 4 bytes. */
static void put_kv(mf_buf *b, const char *key, const char *value)
{
    size_t kl = strlen(key) + 1, vl = strlen(value) + 1;
    mf_buf_u32le(b, (uint32_t)(kl + vl));
    mf_buf_put(b, key, kl);
    mf_buf_put(b, value, vl);
    static const char zeros[4] = {0, 0, 0, 0};
    mf_buf_put(b, zeros, (4u - (kl + vl) % 4u) % 4u);
}

typedef struct {
    int groups;             /* groups of four channels */
    int slices;             /* combinations of axes 2.. */
    int ch[MF_TABLE_MAX_FIELDS + 4]; /* field of channel c of group g at [4 g + c]; -1 zeros */
} ktx2_layout;

static void layout_of(const mf_table *t, const io_write_ctx *c, ktx2_layout *l)
{
    l->slices = 1;
    for (int k = 2; k < t->naxes; ++k)
        l->slices *= t->axes[k].size;
    if (c->ch_set) {
        l->groups = 1;
        for (int k = 0; k < 4; ++k)
            l->ch[k] = c->ch[k];
    } else {
        l->groups = (t->nfields + 3) / 4;
        for (int k = 0; k < 4 * l->groups; ++k)
            l->ch[k] = k < t->nfields ? k : -1;
    }
}

static mf_status write_ktx2(const char *path, const mf_table *t, const io_write_ctx *c, char *msg, size_t msg_size)
{
    const int half = c->half_float;
    ktx2_layout l;
    layout_of(t, c, &l);
    const size_t w = (size_t)t->axes[0].size, h = t->naxes > 1 ? (size_t)t->axes[1].size : 1;
    const size_t layers = (size_t)l.groups * (size_t)l.slices;
    if (layers > KTX2_MAX_LAYERS) {
        mf_io_msg(msg, msg_size, path, "%zu array layers: more than a KTX2 writer here allows (%u)", layers,
                  KTX2_MAX_LAYERS);
        return MF_ERR_UNSUPPORTED;
    }
    const size_t texel_bytes = half ? 8u : 16u;
    const size_t level_bytes = layers * w * h * texel_bytes;

    /* the level data, layer-major (KTX 2.0 section 3.13: layers, then faces, slices, rows) */
    mf_buf data = {0};
    mf_buf_reserve(&data, level_bytes);
    const size_t nf = (size_t)t->nfields, plane = w * h;
    for (size_t s = 0; s < (size_t)l.slices && !data.failed; ++s)
        for (int g = 0; g < l.groups; ++g)
            for (size_t p = 0; p < plane; ++p)
                for (int k = 0; k < 4; ++k) {
                    int f = l.ch[4 * g + k];
                    double v = f < 0 ? 0.0 : t->data[(s * plane + p) * nf + (size_t)f];
                    if (half)
                        mf_buf_u16le(&data, mf_half_from_double(v));
                    else
                        mf_buf_f32le(&data, (float)v);
                }
    if (data.failed) {
        mf_buf_free(&data);
        mf_io_msg(msg, msg_size, path, "out of memory");
        return MF_ERR_ALLOC;
    }
    mf_buf zdata = {0};
    const mf_buf *level = &data;
    if (c->zstd_level > 0) {
        size_t cap = ZSTD_compressBound(data.len);
        if (!mf_buf_reserve(&zdata, cap)) {
            mf_buf_free(&data);
            mf_io_msg(msg, msg_size, path, "out of memory");
            return MF_ERR_ALLOC;
        }
        size_t n = ZSTD_compress(zdata.data, cap, data.data, data.len, c->zstd_level);
        if (ZSTD_isError(n)) {
            mf_buf_free(&data);
            mf_buf_free(&zdata);
            mf_io_msg(msg, msg_size, path, "Zstandard compression failed: %s", ZSTD_getErrorName(n));
            return MF_ERR_INTERNAL;
        }
        zdata.len = n;
        level = &zdata;
    }

    /* key/value data, keys sorted by their bytes (section 3.11.1) */
    mf_buf meta = {0}, chans = {0}, kvd = {0};
    io_header_extra x = {half ? "float16" : "float32", half ? c->half : NULL, NULL, NULL};
    io_header_text(&meta, t, &x);
    mf_buf_put(&meta, "", 1);
    mf_buf_puts(&chans, "[");
    for (int k = 0; k < 4 * l.groups; ++k) {
        if (k)
            mf_buf_puts(&chans, ", ");
        if (l.ch[k] < 0)
            mf_buf_puts(&chans, "null");
        else
            mf_json_string(&chans, t->fields[l.ch[k]]);
    }
    mf_buf_puts(&chans, "]");
    mf_buf_put(&chans, "", 1);
    if (!meta.failed && !chans.failed) {
        put_kv(&kvd, "KTXwriter", "mfkit");
        put_kv(&kvd, "mfkit:channels", chans.data);
        put_kv(&kvd, "mfkit:table", meta.data);
    }

    /* offsets: header, level index, DFD, KVD, then the level aligned to lcm(texel size, 4) (none
     * for supercompressed data, section 3.9.7) */
    const uint32_t dfd_off = KTX2_HEADER_BYTES + KTX2_LEVEL_BYTES;
    const uint32_t kvd_off = dfd_off + KTX2_DFD_BYTES;
    size_t end = (size_t)kvd_off + kvd.len;
    size_t align = c->zstd_level > 0 ? 1u : texel_bytes;
    size_t level_off = (end + align - 1) / align * align;

    mf_buf b = {0};
    mf_buf_put(&b, k_ktx2_magic, 12);
    mf_buf_u32le(&b, half ? VK_FORMAT_R16G16B16A16_SFLOAT : VK_FORMAT_R32G32B32A32_SFLOAT);
    mf_buf_u32le(&b, half ? 2u : 4u);                   /* typeSize */
    mf_buf_u32le(&b, (uint32_t)w);
    mf_buf_u32le(&b, (uint32_t)h);                      /* pixelHeight (1 for a 1D table) */
    mf_buf_u32le(&b, 0u);                               /* pixelDepth: not a 3D texture */
    mf_buf_u32le(&b, layers > 1 ? (uint32_t)layers : 0u); /* layerCount: 0 = not an array */
    mf_buf_u32le(&b, 1u);                               /* faceCount */
    mf_buf_u32le(&b, 1u);                               /* levelCount */
    mf_buf_u32le(&b, c->zstd_level > 0 ? KTX_SS_ZSTD : KTX_SS_NONE);
    mf_buf_u32le(&b, dfd_off);
    mf_buf_u32le(&b, KTX2_DFD_BYTES);
    mf_buf_u32le(&b, kvd.len ? kvd_off : 0u);
    mf_buf_u32le(&b, (uint32_t)kvd.len);
    put_u64(&b, 0u); /* sgdByteOffset */
    put_u64(&b, 0u); /* sgdByteLength */
    put_u64(&b, level_off);
    put_u64(&b, level->len);
    put_u64(&b, level_bytes); /* uncompressedByteLength */
    put_dfd(&b, half);
    mf_buf_put(&b, kvd.data, kvd.len);
    static const char zeros[16] = {0};
    mf_buf_put(&b, zeros, level_off - end);
    mf_buf_put(&b, level->data, level->len);
    mf_status st;
    if (b.failed || meta.failed || chans.failed || kvd.failed) {
        mf_io_msg(msg, msg_size, path, "out of memory");
        st = MF_ERR_ALLOC;
    } else {
        st = mf_io_write_buf_atomic(path, &b, msg, msg_size);
    }
    mf_buf_free(&b);
    mf_buf_free(&meta);
    mf_buf_free(&chans);
    mf_buf_free(&kvd);
    mf_buf_free(&data);
    mf_buf_free(&zdata);
    return st;
}

/* ---- reading ------------------------------------------------------------------------------- */

/* The value of key in the KVD block (NUL-terminated inside the entry), or NULL. */
static const char *kvd_find(const unsigned char *kvd, size_t len, const char *key, size_t *vlen)
{
    size_t p = 0, kl = strlen(key);
    while (p + 4 <= len) {
        uint32_t n = io_get_u32(kvd + p);
        if (n > len - p - 4)
            return NULL;
        const unsigned char *e = kvd + p + 4;
        if (n > kl && memcmp(e, key, kl + 1) == 0) {
            *vlen = n - kl - 1;
            /* the value must be a NUL-terminated string */
            if (*vlen == 0 || e[n - 1] != 0 || memchr(e + kl + 1, 0, *vlen) != e + n - 1)
                return NULL;
            *vlen -= 1;
            return (const char *)(e + kl + 1);
        }
        p += 4 + (size_t)n;
        p = (p + 3) / 4 * 4;
    }
    return NULL;
}

static mf_status read_ktx2(const char *path, mf_table *t, mf_table_file_info *info, char *msg, size_t msg_size)
{
    unsigned char *d;
    size_t len;
    mf_status st = mf_io_read_file(path, path, &d, &len, NULL, msg, msg_size);
    if (st != MF_OK)
        return st;
    unsigned char *raw = NULL;
    cJSON *meta = NULL, *chans = NULL;
    char why[256];
    st = MF_ERR_FORMAT;
    if (len < KTX2_HEADER_BYTES + KTX2_LEVEL_BYTES || memcmp(d, k_ktx2_magic, 12) != 0) {
        mf_io_msg(msg, msg_size, path, "not a KTX 2.0 file (bad identifier or shorter than its header)");
        goto done;
    }
    uint32_t vk = io_get_u32(d + 12), type_size = io_get_u32(d + 16), w = io_get_u32(d + 20), h = io_get_u32(d + 24),
             depth = io_get_u32(d + 28), layers = io_get_u32(d + 32), faces = io_get_u32(d + 36),
             levels = io_get_u32(d + 40), scheme = io_get_u32(d + 44);
    uint32_t dfd_off = io_get_u32(d + 48), dfd_len = io_get_u32(d + 52), kvd_off = io_get_u32(d + 56),
             kvd_len = io_get_u32(d + 60);
    uint64_t lvl_off = get_u64(d + 80), lvl_len = get_u64(d + 88), lvl_raw = get_u64(d + 96);
    int half = vk == VK_FORMAT_R16G16B16A16_SFLOAT;
    if (!half && vk != VK_FORMAT_R32G32B32A32_SFLOAT) {
        mf_io_msg(msg, msg_size, path, "unsupported vkFormat %u (only 97 = R16G16B16A16_SFLOAT and 109 = "
                  "R32G32B32A32_SFLOAT are read)", (unsigned)vk);
        st = MF_ERR_UNSUPPORTED;
        goto done;
    }
    if (type_size != (half ? 2u : 4u) || depth != 0 || faces != 1 || levels != 1 ||
        (scheme != KTX_SS_NONE && scheme != KTX_SS_ZSTD)) {
        mf_io_msg(msg, msg_size, path, "unsupported KTX2 layout (typeSize %u, depth %u, %u faces, %u levels, "
                  "supercompression %u): one 2D (array) level, none or Zstandard, is read", (unsigned)type_size,
                  (unsigned)depth, (unsigned)faces, (unsigned)levels, (unsigned)scheme);
        st = MF_ERR_UNSUPPORTED;
        goto done;
    }
    if (w < 1 || h < 1 || w > (1u << 20) || h > (1u << 20) || layers > KTX2_MAX_LAYERS) {
        mf_io_msg(msg, msg_size, path, "KTX2 size %u x %u x %u layers outside [1, 2^20]^2 x [0, %u]", (unsigned)w,
                  (unsigned)h, (unsigned)layers, KTX2_MAX_LAYERS);
        goto done;
    }
    if ((uint64_t)dfd_off + dfd_len > len || (uint64_t)kvd_off + kvd_len > len || lvl_off > len ||
        lvl_len > len - lvl_off) {
        mf_io_msg(msg, msg_size, path, "truncated KTX2 file (a section ends past its %zu bytes)", len);
        goto done;
    }
    if (lvl_off + lvl_len != len) {
        mf_io_msg(msg, msg_size, path, "%llu bytes after the level data (trailing data)",
                  (unsigned long long)(len - lvl_off - lvl_len));
        goto done;
    }
    size_t nl = layers ? layers : 1, plane = (size_t)w * h, texel_bytes = half ? 8u : 16u;
    size_t need = nl * plane * texel_bytes;
    if (lvl_raw != need || (scheme == KTX_SS_NONE && lvl_len != need)) {
        mf_io_msg(msg, msg_size, path, "level of %llu bytes (%llu uncompressed), %u x %u x %zu RGBA%s needs %zu",
                  (unsigned long long)lvl_len, (unsigned long long)lvl_raw, (unsigned)w, (unsigned)h, nl,
                  half ? "16F" : "32F", need);
        goto done;
    }
    /* the DFD must describe these four float channels (the writer's own block) */
    if (dfd_len != KTX2_DFD_BYTES || io_get_u32(d + dfd_off) != KTX2_DFD_BYTES ||
        (io_get_u32(d + dfd_off + 16) & 0xffu) != 0 /* texel block 1x1 */) {
        mf_io_msg(msg, msg_size, path, "unsupported data format descriptor (%u bytes): 4 samples of RGBA expected",
                  (unsigned)dfd_len);
        st = MF_ERR_UNSUPPORTED;
        goto done;
    }
    const unsigned char *level = d + lvl_off;
    if (scheme == KTX_SS_ZSTD) {
        raw = malloc(need ? need : 1);
        if (!raw) {
            mf_io_msg(msg, msg_size, path, "out of memory");
            st = MF_ERR_ALLOC;
            goto done;
        }
        unsigned long long fs = ZSTD_getFrameContentSize(level, (size_t)lvl_len);
        size_t n = ZSTD_decompress(raw, need, level, (size_t)lvl_len);
        if (ZSTD_isError(n) || n != need || (fs != ZSTD_CONTENTSIZE_UNKNOWN && fs != need)) {
            mf_io_msg(msg, msg_size, path, "corrupt Zstandard level data (%s)",
                      ZSTD_isError(n) ? ZSTD_getErrorName(n) : "wrong size");
            goto done;
        }
        level = raw;
    }
    size_t vlen;
    const char *mv = kvd_len ? kvd_find(d + kvd_off, kvd_len, "mfkit:table", &vlen) : NULL;
    const char *cv = kvd_len ? kvd_find(d + kvd_off, kvd_len, "mfkit:channels", &vlen) : NULL;
    int nch = 4 * (int)nl;
    int chf[4 * 64]; /* field of each channel (with metadata) */
    size_t slices = 1;
    if (mv && cv) {
        if (io_json_parse(mv, strlen(mv), &meta, why, sizeof why) != MF_OK ||
            io_json_parse(cv, strlen(cv), &chans, why, sizeof why) != MF_OK) {
            mf_io_msg(msg, msg_size, path, "key mfkit:table or mfkit:channels: %s", why);
            goto done;
        }
        st = io_header_to_table(meta, IO_TEXELS_ANY, 0, t, info, why, sizeof why);
        if (st != MF_OK) {
            mf_io_msg(msg, msg_size, path, "key mfkit:table: %s", why);
            st = st == MF_ERR_ALLOC ? st : MF_ERR_FORMAT;
            goto done;
        }
        st = MF_ERR_FORMAT;
        for (int k = 2; k < t->naxes; ++k)
            slices *= (size_t)t->axes[k].size;
        int n = cJSON_IsArray(chans) ? cJSON_GetArraySize(chans) : -1;
        if (t->axes[0].size != (int)w || (t->naxes > 1 ? t->axes[1].size : 1) != (int)h || n < 4 || n % 4 ||
            n > (int)(sizeof chf / sizeof chf[0]) || (size_t)(n / 4) * slices != nl) {
            mf_io_msg(msg, msg_size, path, "the metadata's axes and mfkit:channels (%d) do not give this %u x %u x %zu "
                      "texture", n, (unsigned)w, (unsigned)h, nl);
            goto done;
        }
        nch = n;
        const cJSON *v = chans->child;
        int used[MF_TABLE_MAX_FIELDS] = {0};
        for (int k = 0; k < n; ++k, v = v->next) {
            chf[k] = cJSON_IsString(v) ? mf_table_field(t, v->valuestring) : -1;
            if ((cJSON_IsString(v) && chf[k] < 0) || (!cJSON_IsString(v) && !cJSON_IsNull(v)) ||
                (chf[k] >= 0 && used[chf[k]]++)) {
                mf_io_msg(msg, msg_size, path, "mfkit:channels entry %d is not a field name used once, or null", k);
                goto done;
            }
        }
        /* a channel selection keeps only the stored fields, as DDS does */
        {
            char names[MF_TABLE_MAX_FIELDS][MF_TABLE_NAME_LEN];
            const char *np[MF_TABLE_MAX_FIELDS];
            int keep = 0, map[MF_TABLE_MAX_FIELDS];
            for (int f = 0; f < t->nfields; ++f)
                if (used[f]) {
                    snprintf(names[keep], sizeof names[keep], "%s", t->fields[f]);
                    np[keep] = names[keep];
                    map[f] = keep++;
                }
            if (keep == 0) {
                mf_io_msg(msg, msg_size, path, "mfkit:channels names no field");
                goto done;
            }
            if (keep != t->nfields) {
                mf_table full = *t;
                mf_table sub;
                st = mf_table_create(&sub, full.naxes, full.axes, keep, np);
                if (st == MF_OK) {
                    for (int i = 0; i < full.nmeta; ++i)
                        sub.meta[i] = full.meta[i];
                    sub.nmeta = full.nmeta;
                }
                mf_table_free(t);
                if (st != MF_OK) {
                    memset(t, 0, sizeof *t);
                    mf_io_msg(msg, msg_size, path, "out of memory");
                    goto done;
                }
                *t = sub;
                st = MF_ERR_FORMAT;
            }
            for (int k = 0; k < n; ++k)
                chf[k] = chf[k] < 0 ? -1 : map[chf[k]];
        }
    } else {
        /* no mfkit metadata: a 2D table, fields R, G, B, A of each layer ("R", "G", ... for one layer,
         * "R0", "G0", ... "A<L-1>" for L layers) */
        if (nch > MF_TABLE_MAX_FIELDS) {
            mf_io_msg(msg, msg_size, path, "%zu layers without mfkit metadata: more than %d channels", nl,
                      MF_TABLE_MAX_FIELDS);
            st = MF_ERR_UNSUPPORTED;
            goto done;
        }
        char names[MF_TABLE_MAX_FIELDS][MF_TABLE_NAME_LEN];
        const char *np[MF_TABLE_MAX_FIELDS];
        for (int k = 0; k < nch; ++k) {
            if (nl == 1)
                snprintf(names[k], sizeof names[k], "%c", "RGBA"[k]);
            else
                snprintf(names[k], sizeof names[k], "%c%d", "RGBA"[k % 4], k / 4);
            np[k] = names[k];
            chf[k] = k;
        }
        int sizes[2] = {(int)w, (int)h};
        st = io_generic_table(t, h > 1 ? 2 : 1, sizes, nch, np);
        if (st != MF_OK) {
            mf_io_msg(msg, msg_size, path, "out of memory");
            goto done;
        }
        st = MF_ERR_FORMAT;
    }
    const size_t nf = (size_t)t->nfields;
    const int groups = nch / 4;
    for (size_t layer = 0; layer < nl; ++layer) {
        size_t s = layer / (size_t)groups;
        int g = (int)(layer % (size_t)groups);
        for (size_t p = 0; p < plane; ++p)
            for (int k = 0; k < 4; ++k) {
                int f = chf[4 * g + k];
                if (f < 0)
                    continue;
                size_t v = (layer * plane + p) * 4 + (size_t)k;
                t->data[(s * plane + p) * nf + (size_t)f] =
                    half ? mf_half_to_double(io_get_u16(level + 2 * v)) : (double)io_get_f32(level + 4 * v);
            }
    }
    if (info) {
        info->format = MF_TABLE_FORMAT_KTX2;
        info->half_float = half;
    }
    st = MF_OK;
done:
    if (st != MF_OK && t->data)
        mf_table_free(t);
    cJSON_Delete(meta);
    cJSON_Delete(chans);
    free(raw);
    free(d);
    return st;
}

static const char *const k_ext[] = {"ktx2", NULL};
const io_format_ops io_format_ktx2 = {MF_TABLE_FORMAT_KTX2,
                                      "ktx2",
                                      k_ext,
                                      MF_TABLE_MAX_AXES,
                                      IO_CAP_HALF | IO_CAP_METADATA | IO_CAP_RGBA_OPTIONAL,
                                      write_ktx2,
                                      read_ktx2};
