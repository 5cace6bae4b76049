/* mf_maps.c -- see mf_maps.h. */
#include "mfkit/mf_maps.h"
#include "mfkit/mf_table_kind.h"

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

mf_status mf_map_alloc(mf_map *m, int width, int height, int channels)
{
    if (!m)
        return MF_ERR_DOMAIN;
    memset(m, 0, sizeof *m);
    if (width < 1 || height < 1 || channels < 1)
        return MF_ERR_DOMAIN;
    size_t n = (size_t)width * (size_t)height;
    if (n / (size_t)width != (size_t)height || n > SIZE_MAX / sizeof(double) / (size_t)channels)
        return MF_ERR_ALLOC;
    m->data = calloc(n * (size_t)channels, sizeof(double));
    if (!m->data)
        return MF_ERR_ALLOC;
    m->width = width;
    m->height = height;
    m->channels = channels;
    return MF_OK;
}

void mf_map_free(mf_map *m)
{
    if (!m)
        return;
    free(m->data);
    memset(m, 0, sizeof *m);
}

int mf_map_mip_dim(int n)
{
    if (n < 1)
        return 0;
    return n / 2 > 1 ? n / 2 : 1;
}

int mf_map_mip_count(int width, int height)
{
    if (width < 1 || height < 1)
        return 0;
    int n = width > height ? width : height, levels = 1;
    while (n > 1) {
        n /= 2;
        ++levels;
    }
    return levels;
}

static int map_valid(const mf_map *m)
{
    return m && m->data && m->width >= 1 && m->height >= 1 && m->channels >= 1;
}

/* Box weights of an axis of n texels reduced to m: output texel o covers [o n, (o + 1) n) and
 * input texel k covers [k m, (k + 1) m), both in units of 1/m of an input texel; the weight is
 * their overlap divided by the footprint length n.  Each output texel touches at most 3 inputs
 * (n/m <= 3 for m = floor(n/2) >= 1, n >= 2; n = m = 1: one).  first[o] is the first input,
 * w[3 o + t] the weight of input first[o] + t. */
static void box_weights(int n, int m, int *first, double *w)
{
    for (int o = 0; o < m; ++o) {
        long a = (long)o * n, b = (long)(o + 1) * n;
        int k0 = (int)(a / m);
        first[o] = k0;
        for (int t = 0; t < 3; ++t) {
            long lo = (long)(k0 + t) * m, hi = lo + m;
            long ov = (hi < b ? hi : b) - (lo > a ? lo : a);
            w[3 * o + t] = (k0 + t < n && ov > 0) ? (double)ov / (double)n : 0.0;
        }
    }
}

mf_status mf_map_box_downsample(const mf_map *in, mf_map *out)
{
    if (!out)
        return MF_ERR_DOMAIN;
    memset(out, 0, sizeof *out);
    if (!map_valid(in))
        return MF_ERR_DOMAIN;
    const int w = in->width, h = in->height, c = in->channels;
    const int w2 = mf_map_mip_dim(w), h2 = mf_map_mip_dim(h);
    mf_map tmp; /* horizontal pass: w2 x h */
    mf_status st = mf_map_alloc(&tmp, w2, h, c);
    if (st != MF_OK)
        return st;
    st = mf_map_alloc(out, w2, h2, c);
    int *fx = malloc(sizeof(int) * (size_t)w2), *fy = malloc(sizeof(int) * (size_t)h2);
    double *wx = malloc(sizeof(double) * 3 * (size_t)w2), *wy = malloc(sizeof(double) * 3 * (size_t)h2);
    if (st != MF_OK || !fx || !fy || !wx || !wy) {
        free(fx), free(fy), free(wx), free(wy);
        mf_map_free(&tmp);
        mf_map_free(out);
        return MF_ERR_ALLOC;
    }
    box_weights(w, w2, fx, wx);
    box_weights(h, h2, fy, wy);
    for (int j = 0; j < h; ++j)
        for (int o = 0; o < w2; ++o)
            for (int t = 0; t < 3; ++t) {
                double wt = wx[3 * o + t];
                if (wt == 0.0)
                    continue;
                const double *src = in->data + ((size_t)j * w + (size_t)(fx[o] + t)) * c;
                double *dst = tmp.data + ((size_t)j * w2 + o) * c;
                for (int k = 0; k < c; ++k)
                    dst[k] += wt * src[k];
            }
    for (int o = 0; o < h2; ++o)
        for (int t = 0; t < 3; ++t) {
            double wt = wy[3 * o + t];
            if (wt == 0.0)
                continue;
            const double *src = tmp.data + (size_t)(fy[o] + t) * w2 * c;
            double *dst = out->data + (size_t)o * w2 * c;
            for (size_t k = 0; k < (size_t)w2 * c; ++k)
                dst[k] += wt * src[k];
        }
    free(fx), free(fy), free(wx), free(wy);
    mf_map_free(&tmp);
    return MF_OK;
}

/* Derivative along one axis of n samples spaced `step` apart in memory at position p; returns
 * the difference quotient in units of height per texel. */
static double axis_diff(const double *base, int p, int n, size_t step, mf_map_edge edge)
{
    if (n == 1)
        return 0.0;
    if (edge == MF_MAP_EDGE_WRAP) {
        int a = p + 1 < n ? p + 1 : 0, b = p > 0 ? p - 1 : n - 1;
        return (base[(size_t)a * step] - base[(size_t)b * step]) / 2.0;
    }
    if (p == 0)
        return base[step] - base[0];
    if (p == n - 1)
        return base[(size_t)p * step] - base[(size_t)(p - 1) * step];
    return (base[(size_t)(p + 1) * step] - base[(size_t)(p - 1) * step]) / 2.0;
}

mf_status mf_map_slopes_from_heights(const mf_map *heights, int channel, double height_scale, double texel_size,
                                     mf_map_edge edge, mf_map *out, size_t *bad)
{
    if (!out)
        return MF_ERR_DOMAIN;
    memset(out, 0, sizeof *out);
    if (!map_valid(heights) || channel < 0 || channel >= heights->channels || !isfinite(height_scale) ||
        !(texel_size > 0.0) || !isfinite(texel_size) || (edge != MF_MAP_EDGE_WRAP && edge != MF_MAP_EDGE_CLAMP))
        return MF_ERR_DOMAIN;
    const int w = heights->width, h = heights->height, c = heights->channels;
    size_t n = (size_t)w * h;
    for (size_t t = 0; t < n; ++t)
        if (!isfinite(heights->data[t * c + channel])) {
            if (bad)
                *bad = t;
            return MF_ERR_DOMAIN;
        }
    mf_status st = mf_map_alloc(out, w, h, 2);
    if (st != MF_OK)
        return st;
    const double k = height_scale / texel_size;
    for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
            const double *row = heights->data + (size_t)j * w * c + channel;
            const double *col = heights->data + (size_t)i * c + channel;
            double dx = axis_diff(row, i, w, (size_t)c, edge);
            /* y is up: dh/dy = -(dh/d row) */
            double dy = -axis_diff(col, j, h, (size_t)w * c, edge);
            out->data[((size_t)j * w + i) * 2 + 0] = k * dx;
            out->data[((size_t)j * w + i) * 2 + 1] = k * dy;
        }
    return MF_OK;
}

mf_status mf_map_slopes_from_normals(const mf_map *normals, mf_map *out, size_t *bad)
{
    if (!out)
        return MF_ERR_DOMAIN;
    memset(out, 0, sizeof *out);
    if (!map_valid(normals) || normals->channels < 3)
        return MF_ERR_DOMAIN;
    const int c = normals->channels;
    size_t n = (size_t)normals->width * normals->height;
    for (size_t t = 0; t < n; ++t) {
        const double *p = normals->data + t * c;
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]) || !(p[2] > 0.0)) {
            if (bad)
                *bad = t;
            return MF_ERR_DOMAIN;
        }
    }
    mf_status st = mf_map_alloc(out, normals->width, normals->height, 2);
    if (st != MF_OK)
        return st;
    for (size_t t = 0; t < n; ++t) {
        const double *p = normals->data + t * c;
        out->data[2 * t + 0] = -p[0] / p[2];
        out->data[2 * t + 1] = -p[1] / p[2];
    }
    return MF_OK;
}

mf_status mf_map_moments_from_slopes(const mf_map *slopes, mf_map *out)
{
    if (!out)
        return MF_ERR_DOMAIN;
    memset(out, 0, sizeof *out);
    if (!map_valid(slopes) || slopes->channels != 2)
        return MF_ERR_DOMAIN;
    mf_status st = mf_map_alloc(out, slopes->width, slopes->height, MF_MAP_MOMENTS);
    if (st != MF_OK)
        return st;
    size_t n = (size_t)slopes->width * slopes->height;
    for (size_t t = 0; t < n; ++t) {
        double sx = slopes->data[2 * t], sy = slopes->data[2 * t + 1];
        double *m = out->data + t * MF_MAP_MOMENTS;
        m[MF_MAP_MEAN_X] = sx;
        m[MF_MAP_MEAN_Y] = sy;
        m[MF_MAP_M_XX] = sx * sx;
        m[MF_MAP_M_XY] = sx * sy;
        m[MF_MAP_M_YY] = sy * sy;
    }
    return MF_OK;
}

mf_slope_moments mf_map_moments_at(const mf_map *moments, int i, int j)
{
    mf_slope_moments r;
    if (!map_valid(moments) || moments->channels < MF_MAP_MOMENTS || i < 0 || j < 0 || i >= moments->width ||
        j >= moments->height) {
        r.mean_x = r.mean_y = r.m_xx = r.m_xy = r.m_yy = NAN;
        return r;
    }
    const double *m = moments->data + ((size_t)j * moments->width + i) * moments->channels;
    r.mean_x = m[MF_MAP_MEAN_X];
    r.mean_y = m[MF_MAP_MEAN_Y];
    r.m_xx = m[MF_MAP_M_XX];
    r.m_xy = m[MF_MAP_M_XY];
    r.m_yy = m[MF_MAP_M_YY];
    return r;
}

/* ---- moment maps as tables (mf_maps.h, mf_table_kind.h) --------------------------------------- */

static mf_table_axis moment_axis(const char *name, const char *physical, int n, int reversed)
{
    mf_table_axis a;
    memset(&a, 0, sizeof a);
    snprintf(a.name, sizeof a.name, "%s", name);
    snprintf(a.physical, sizeof a.physical, "%s", physical);
    a.size = n;
    a.lo = 0.5 / n;
    a.hi = 1.0 - 0.5 / n;
    if (reversed) {
        a.lo = 1.0 - 0.5 / n;
        a.hi = 0.5 / n;
    }
    a.mapping = MF_AXIS_IDENTITY;
    a.physical_min = -INFINITY;
    return a;
}

mf_status mf_map_moments_to_table(const mf_map *m, int level, mf_table *out)
{
    if (out)
        memset(out, 0, sizeof *out);
    if (!m || !out || !m->data || m->channels != MF_MAP_MOMENTS || m->width < 1 || m->height < 1 || level < 0)
        return MF_ERR_DOMAIN;
    const mf_table_kind *k = mf_table_kind_find("moment_map");
    mf_table_axis axes[2] = {moment_axis(k->axes[0].name, k->axes[0].physical, m->width, 0),
                             moment_axis(k->axes[1].name, k->axes[1].physical, m->height, 1)};
    mf_status st = mf_table_create(out, 2, axes, MF_MOMENT_TABLE_NFIELDS, mf_moment_table_fields);
    if (st != MF_OK)
        return st;
    memcpy(out->data, m->data, sizeof(double) * (size_t)m->width * (size_t)m->height * MF_MAP_MOMENTS);
    char lv[32];
    snprintf(lv, sizeof lv, "%d", level);
    if (mf_table_kind_tag(out, k) != MF_OK || mf_table_set_meta(out, "level", lv) != MF_OK ||
        mf_table_set_meta(out, "slopes",
                          "mfkit slopes (dh/dx, dh/dy) = (-n.x/n.z, -n.y/n.z), y up; LEAN's B = -s") != MF_OK) {
        mf_table_free(out);
        return MF_ERR_INTERNAL;
    }
    return MF_OK;
}

mf_status mf_map_chain_to_tables(const mf_map *levels, int nlevels, mf_table *out)
{
    if (!levels || !out || nlevels < 1)
        return MF_ERR_DOMAIN;
    for (int l = 0; l < nlevels; ++l) {
        mf_status st = mf_map_moments_to_table(&levels[l], l, &out[l]);
        if (st != MF_OK) {
            for (int k = 0; k < l; ++k)
                mf_table_free(&out[k]);
            return st;
        }
    }
    return MF_OK;
}

mf_status mf_map_moments_from_table(const mf_table *t, mf_map *out)
{
    if (out)
        memset(out, 0, sizeof *out);
    const mf_table_kind *k = mf_table_kind_find("moment_map");
    if (!t || !out || !k->layout_ok(t, NULL, 0))
        return MF_ERR_DOMAIN;
    mf_status st = mf_map_alloc(out, t->axes[0].size, t->axes[1].size, MF_MAP_MOMENTS);
    if (st != MF_OK)
        return st;
    int f[MF_MOMENT_TABLE_NFIELDS];
    for (int c = 0; c < MF_MOMENT_TABLE_NFIELDS; ++c)
        f[c] = mf_table_field(t, mf_moment_table_fields[c]);
    size_t n = (size_t)out->width * (size_t)out->height;
    for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < MF_MOMENT_TABLE_NFIELDS; ++c)
            out->data[i * MF_MAP_MOMENTS + (size_t)c] = t->data[i * (size_t)t->nfields + (size_t)f[c]];
    return MF_OK;
}
