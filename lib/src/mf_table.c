/* mf_table.c -- n-dimensional tables with self-describing axes (see mf_table.h). */
#include "mfkit/mf_table.h"

#include <float.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const k_mapping_names[] = {"identity", "one_minus_square", "square", "cos"};

const char *mf_axis_mapping_name(mf_axis_mapping m)
{
    return ((unsigned)m < 4u) ? k_mapping_names[m] : "unknown";
}

int mf_axis_mapping_parse(const char *name, mf_axis_mapping *out)
{
    for (int i = 0; i < 4; ++i)
        if (name && strcmp(name, k_mapping_names[i]) == 0) {
            *out = (mf_axis_mapping)i;
            return 0;
        }
    return -1;
}

void mf_axis_describe(const mf_table_axis *a, char *buf, size_t size)
{
    const char *p = a->name, *x = a->physical;
    char clamp[64] = "";
    if (isfinite(a->physical_min))
        snprintf(clamp, sizeof clamp, ", clamped to >= %.17g", a->physical_min);
    switch (a->mapping) {
    case MF_AXIS_IDENTITY: snprintf(buf, size, "%s = %s%s", x, p, clamp); break;
    case MF_AXIS_ONE_MINUS_SQUARE: snprintf(buf, size, "%s = 1 - %s^2%s", x, p, clamp); break;
    case MF_AXIS_SQUARE: snprintf(buf, size, "%s = %s^2%s", x, p, clamp); break;
    case MF_AXIS_COS: snprintf(buf, size, "%s = cos(%s)%s", x, p, clamp); break;
    default: snprintf(buf, size, "unknown mapping"); break;
    }
}

static int valid_name(const char *s)
{
    size_t n = strlen(s);
    if (n == 0 || n >= MF_TABLE_NAME_LEN)
        return 0;
    for (size_t i = 0; i < n; ++i) {
        char c = s[i];
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_'))
            return 0;
    }
    return 1;
}

mf_status mf_table_create(mf_table *t, int naxes, const mf_table_axis *axes, int nfields,
                          const char *const *field_names)
{
    memset(t, 0, sizeof *t);
    if (naxes < 1 || naxes > MF_TABLE_MAX_AXES || !axes || nfields < 1 || nfields > MF_TABLE_MAX_FIELDS || !field_names)
        return MF_ERR_DOMAIN;
    size_t texels = 1;
    for (int k = 0; k < naxes; ++k) {
        const mf_table_axis *a = &axes[k];
        if (a->size < 1 || a->size > (1 << 20) || !isfinite(a->lo) || !isfinite(a->hi) || (a->size > 1 && a->lo == a->hi)
            || (unsigned)a->mapping > 3u || isnan(a->physical_min) || !valid_name(a->name)
            || !valid_name(a->physical))
            return MF_ERR_DOMAIN;
        if (texels > ((size_t)1 << 32) / (size_t)a->size)
            return MF_ERR_DOMAIN; /* more than 2^32 texels: not a lookup table */
        texels *= (size_t)a->size;
        for (int j = 0; j < k; ++j)
            if (strcmp(axes[j].name, a->name) == 0)
                return MF_ERR_DOMAIN;
    }
    for (int f = 0; f < nfields; ++f) {
        if (!field_names[f] || !valid_name(field_names[f]))
            return MF_ERR_DOMAIN;
        for (int g = 0; g < f; ++g)
            if (strcmp(field_names[f], field_names[g]) == 0)
                return MF_ERR_DOMAIN;
    }
    double *data = calloc(texels * (size_t)nfields, sizeof(double));
    if (!data)
        return MF_ERR_ALLOC;
    t->naxes = naxes;
    memcpy(t->axes, axes, sizeof(mf_table_axis) * (size_t)naxes);
    t->nfields = nfields;
    for (int f = 0; f < nfields; ++f)
        snprintf(t->fields[f], MF_TABLE_NAME_LEN, "%s", field_names[f]);
    t->data = data;
    return MF_OK;
}

void mf_table_free(mf_table *t)
{
    if (!t)
        return;
    free(t->data);
    memset(t, 0, sizeof *t);
}

mf_status mf_table_copy(mf_table *dst, const mf_table *src)
{
    size_t n = mf_table_texels(src) * (size_t)src->nfields;
    double *data = malloc(n * sizeof(double));
    if (!data) {
        memset(dst, 0, sizeof *dst);
        return MF_ERR_ALLOC;
    }
    *dst = *src;
    memcpy(data, src->data, n * sizeof(double));
    dst->data = data;
    return MF_OK;
}

size_t mf_table_texels(const mf_table *t)
{
    size_t n = 1;
    for (int k = 0; k < t->naxes; ++k)
        n *= (size_t)t->axes[k].size;
    return n;
}

double *mf_table_record(const mf_table *t, const int *idx)
{
    size_t offset = 0;
    for (int k = t->naxes - 1; k >= 0; --k) {
        if (idx[k] < 0 || idx[k] >= t->axes[k].size)
            return NULL;
        offset = offset * (size_t)t->axes[k].size + (size_t)idx[k];
    }
    return t->data + offset * (size_t)t->nfields;
}

int mf_table_field(const mf_table *t, const char *name)
{
    for (int f = 0; f < t->nfields; ++f)
        if (strcmp(t->fields[f], name) == 0)
            return f;
    return -1;
}

mf_status mf_table_set_meta(mf_table *t, const char *key, const char *value)
{
    if (!key || !value || !valid_name(key) || strlen(value) >= MF_TABLE_TEXT_LEN)
        return MF_ERR_DOMAIN;
    for (int i = 0; i < t->nmeta; ++i)
        if (strcmp(t->meta[i].key, key) == 0) {
            snprintf(t->meta[i].value, MF_TABLE_TEXT_LEN, "%s", value);
            return MF_OK;
        }
    if (t->nmeta >= MF_TABLE_MAX_META)
        return MF_ERR_DOMAIN;
    snprintf(t->meta[t->nmeta].key, MF_TABLE_NAME_LEN, "%s", key);
    snprintf(t->meta[t->nmeta].value, MF_TABLE_TEXT_LEN, "%s", value);
    t->nmeta++;
    return MF_OK;
}

const char *mf_table_get_meta(const mf_table *t, const char *key)
{
    for (int i = 0; i < t->nmeta; ++i)
        if (strcmp(t->meta[i].key, key) == 0)
            return t->meta[i].value;
    return NULL;
}

double mf_table_axis_param(const mf_table_axis *a, int i)
{
    if (a->size <= 1)
        return a->lo;
    if (i == a->size - 1)
        return a->hi; /* exactly, whatever the rounding of the formula */
    return a->lo + (a->hi - a->lo) * (double)i / (double)(a->size - 1);
}

double mf_table_axis_physical(const mf_table_axis *a, double p)
{
    double x;
    switch (a->mapping) {
    case MF_AXIS_IDENTITY: x = p; break;
    case MF_AXIS_ONE_MINUS_SQUARE: x = 1.0 - p * p; break;
    case MF_AXIS_SQUARE: x = p * p; break;
    case MF_AXIS_COS: x = cos(p); break;
    default: return NAN;
    }
    return (x < a->physical_min) ? a->physical_min : x;
}

double mf_table_uv_from_param(const mf_table_axis *a, double p)
{
    if (a->size <= 1)
        return 0.5;
    double n = (double)a->size;
    return (p - a->lo) / (a->hi - a->lo) * (n - 1.0) / n + 0.5 / n;
}

double mf_table_param_from_uv(const mf_table_axis *a, double uv)
{
    if (a->size <= 1)
        return a->lo;
    double n = (double)a->size;
    return a->lo + (uv - 0.5 / n) * n / (n - 1.0) * (a->hi - a->lo);
}

mf_status mf_table_lookup(const mf_table *t, const double *p, double *out)
{
    int i0[MF_TABLE_MAX_AXES];
    double w[MF_TABLE_MAX_AXES];
    for (int k = 0; k < t->naxes; ++k) {
        const mf_table_axis *a = &t->axes[k];
        if (isnan(p[k]))
            return MF_ERR_DOMAIN;
        if (a->size == 1) {
            i0[k] = 0;
            w[k] = 0.0;
            continue;
        }
        double x = (p[k] - a->lo) / (a->hi - a->lo) * (double)(a->size - 1);
        if (!(x > 0.0))
            x = 0.0; /* clamp to edge (also for -inf) */
        if (x > a->size - 1)
            x = a->size - 1;
        double r = nearbyint(x);
        if (fabs(x - r) <= 8.0 * DBL_EPSILON * fmax(1.0, r))
            x = r; /* within 8 ulp of a texel centre: that centre */
        int i = (int)floor(x);
        if (i >= a->size - 1)
            i = a->size - 2;
        i0[k] = i;
        w[k] = x - i;
    }
    for (int f = 0; f < t->nfields; ++f)
        out[f] = -0.0; /* -0 + x == x for every x, -0 included */
    /* sum over the 2^naxes corners, skipping zero weights so that an exact texel centre returns
     * the record bit for bit (0 * NaN or 0 * inf from a neighbour would spoil it) */
    for (int corner = 0; corner < (1 << t->naxes); ++corner) {
        double weight = 1.0;
        int idx[MF_TABLE_MAX_AXES];
        for (int k = 0; k < t->naxes; ++k) {
            int up = (corner >> k) & 1;
            idx[k] = i0[k] + up;
            weight *= up ? w[k] : 1.0 - w[k];
        }
        if (weight == 0.0)
            continue;
        const double *rec = mf_table_record(t, idx);
        for (int f = 0; f < t->nfields; ++f)
            out[f] += weight * rec[f];
    }
    return MF_OK;
}

void mf_table_field_range(const mf_table *t, int field, double *min, double *max, size_t *nan_count)
{
    size_t n = mf_table_texels(t), nans = 0;
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < n; ++i) {
        double v = t->data[i * (size_t)t->nfields + (size_t)field];
        if (isnan(v)) {
            ++nans;
            continue;
        }
        lo = fmin(lo, v);
        hi = fmax(hi, v);
    }
    *min = lo;
    *max = hi;
    if (nan_count)
        *nan_count = nans;
}

/* ---- the 2D atlas (mf_table.h) --------------------------------------------------------------- */

#define ATLAS_MAX_SIDE 65536

mf_status mf_table_atlas_layout(const mf_table *t, int tiles_x, mf_table_atlas *a)
{
    memset(a, 0, sizeof *a);
    if (!t || t->naxes < 1 || t->naxes > MF_TABLE_MAX_AXES || tiles_x < 0)
        return MF_ERR_DOMAIN;
    long tiles = 1;
    for (int k = 2; k < t->naxes; ++k) {
        tiles *= t->axes[k].size;
        if (tiles > (long)ATLAS_MAX_SIDE * ATLAS_MAX_SIDE)
            return MF_ERR_DOMAIN;
    }
    if (tiles_x == 0)
        tiles_x = t->naxes > 2 ? t->axes[2].size : 1;
    if (tiles_x > tiles)
        tiles_x = (int)tiles;
    long tiles_y = (tiles + tiles_x - 1) / tiles_x;
    long tw = t->axes[0].size, th = t->naxes > 1 ? t->axes[1].size : 1;
    if (tw * tiles_x > ATLAS_MAX_SIDE || th * tiles_y > ATLAS_MAX_SIDE)
        return MF_ERR_DOMAIN;
    a->tile_w = (int)tw;
    a->tile_h = (int)th;
    a->tiles = (int)tiles;
    a->tiles_x = tiles_x;
    a->tiles_y = (int)tiles_y;
    a->width = (int)(tw * tiles_x);
    a->height = (int)(th * tiles_y);
    return MF_OK;
}

/* The record index of texel (i0, i1) of tile `tile` (first axis fastest, mf_table.h). */
static size_t atlas_texel_index(const mf_table *t, int i0, int i1, long tile)
{
    size_t n01 = (size_t)t->axes[0].size * (size_t)(t->naxes > 1 ? t->axes[1].size : 1);
    return (size_t)i0 + (size_t)t->axes[0].size * (size_t)i1 + n01 * (size_t)tile;
}

void mf_table_atlas_fill(const mf_table *t, const mf_table_atlas *a, double *out)
{
    const size_t nf = (size_t)t->nfields;
    for (int y = 0; y < a->height; ++y)
        for (int x = 0; x < a->width; ++x) {
            double *o = out + ((size_t)y * (size_t)a->width + (size_t)x) * nf;
            long tile = (long)(x / a->tile_w) + (long)a->tiles_x * (long)(y / a->tile_h);
            if (tile >= a->tiles) {
                for (size_t f = 0; f < nf; ++f)
                    o[f] = 0.0;
                continue;
            }
            const double *r = t->data + atlas_texel_index(t, x % a->tile_w, y % a->tile_h, tile) * nf;
            memcpy(o, r, nf * sizeof *o);
        }
}

mf_status mf_table_atlas_record(mf_table *t, const mf_table_atlas *a)
{
    char v[MF_TABLE_TEXT_LEN];
    snprintf(v, sizeof v, "tiles_x=%d tiles_y=%d tile_w=%d tile_h=%d order=axis2_fastest", a->tiles_x, a->tiles_y,
             a->tile_w, a->tile_h);
    return mf_table_set_meta(t, "atlas", v);
}

mf_status mf_table_atlas_from_meta(const mf_table *t, mf_table_atlas *a)
{
    const char *v = mf_table_get_meta(t, "atlas");
    int tx, ty, tw, th, used = 0;
    if (!v || sscanf(v, "tiles_x=%d tiles_y=%d tile_w=%d tile_h=%d order=axis2_fastest%n", &tx, &ty, &tw, &th, &used) != 4
        || used == 0 || v[used] != '\0' || tx < 1)
        return MF_ERR_DOMAIN;
    if (mf_table_atlas_layout(t, tx, a) != MF_OK)
        return MF_ERR_DOMAIN;
    if (a->tiles_x != tx || a->tiles_y != ty || a->tile_w != tw || a->tile_h != th) {
        memset(a, 0, sizeof *a);
        return MF_ERR_DOMAIN;
    }
    return MF_OK;
}

/* The in-tile texture coordinate of parameter p on axis ax (clamped to [lo, hi] first). */
static double atlas_uv(const mf_table_axis *ax, double p)
{
    double lo = ax->lo < ax->hi ? ax->lo : ax->hi, hi = ax->lo < ax->hi ? ax->hi : ax->lo;
    if (p < lo)
        p = lo;
    if (p > hi)
        p = hi;
    return mf_table_uv_from_param(ax, p);
}

/* The hardware's bilinear filter of the atlas image at (u, v) in [0, 1]^2 (texel centres at
 * (i + 0.5)/width, clamp to edge), accumulating weight * sample into out. */
static void atlas_bilinear(const mf_table_atlas *a, const double *image, int nf, double u, double v, double weight,
                           double *out)
{
    double xf = u * a->width - 0.5, yf = v * a->height - 0.5;
    double x0 = floor(xf), y0 = floor(yf);
    double fx = xf - x0, fy = yf - y0;
    for (int c = 0; c < 4; ++c) {
        int dx = c & 1, dy = c >> 1;
        double w = weight * (dx ? fx : 1.0 - fx) * (dy ? fy : 1.0 - fy);
        if (w == 0.0)
            continue;
        long x = (long)x0 + dx, y = (long)y0 + dy;
        x = x < 0 ? 0 : (x >= a->width ? a->width - 1 : x);
        y = y < 0 ? 0 : (y >= a->height ? a->height - 1 : y);
        const double *r = image + ((size_t)y * (size_t)a->width + (size_t)x) * (size_t)nf;
        for (int f = 0; f < nf; ++f)
            out[f] += w * r[f];
    }
}

mf_status mf_table_atlas_lookup(const mf_table *t, const mf_table_atlas *a, const double *image, const double *p,
                                double *out)
{
    for (int k = 0; k < t->naxes; ++k)
        if (isnan(p[k]))
            return MF_ERR_DOMAIN;
    double uv0 = atlas_uv(&t->axes[0], p[0]), uv1 = t->naxes > 1 ? atlas_uv(&t->axes[1], p[1]) : 0.5;
    /* the further axes: a manual lerp, as a shader does it */
    int i0[MF_TABLE_MAX_AXES] = {0};
    double w[MF_TABLE_MAX_AXES] = {0.0};
    for (int k = 2; k < t->naxes; ++k) {
        const mf_table_axis *ax = &t->axes[k];
        if (ax->size == 1)
            continue;
        double x = (p[k] - ax->lo) / (ax->hi - ax->lo) * (double)(ax->size - 1);
        if (!(x > 0.0))
            x = 0.0;
        if (x > ax->size - 1)
            x = ax->size - 1;
        int i = (int)floor(x);
        if (i >= ax->size - 1)
            i = ax->size - 2;
        i0[k] = i;
        w[k] = x - i;
    }
    for (int f = 0; f < t->nfields; ++f)
        out[f] = -0.0;
    int further = t->naxes > 2 ? t->naxes - 2 : 0;
    for (int corner = 0; corner < (1 << further); ++corner) {
        double weight = 1.0;
        long tile = 0, stride = 1;
        for (int k = 2; k < t->naxes; ++k) {
            int up = (corner >> (k - 2)) & 1;
            weight *= up ? w[k] : 1.0 - w[k];
            tile += stride * (long)(i0[k] + (t->axes[k].size > 1 ? up : 0));
            stride *= t->axes[k].size;
        }
        if (weight == 0.0)
            continue;
        long col = tile % a->tiles_x, row = tile / a->tiles_x;
        double u = ((double)col + uv0) * a->tile_w / a->width, v = ((double)row + uv1) * a->tile_h / a->height;
        atlas_bilinear(a, image, t->nfields, u, v, weight, out);
    }
    return MF_OK;
}
