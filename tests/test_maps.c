/*
 * test_maps.c -- mf_maps.h (slopes, moments, the box-filtered MIP chain) and, as the helper of
 * tests/test_maps_cli.sh and tests/test_sh_cli.sh, the images and checks of `mfkit maps` and
 * `mfkit sh project`.
 *
 * Without arguments: unit tests of mf_maps.h.  With arguments (used by the shell tests):
 *   --write-height PATH              the analytic height field below as a float EXR (channel Y)
 *   --write-normals PATH [dx|enc]    its exact unit normals (float EXR, R,G,B = n), "dx": green
 *                                    flipped (DirectX), "enc": encoded c = (n + 1)/2 (to be
 *                                    quantised by oiiotool into PNG)
 *   --write-bad KIND PATH            invalid inputs: twochannel, unnormalised, negz, nan, heightnan
 *   --check PREFIX MODE SOURCE BASE  reads every level written by `mfkit maps MODE` and compares it
 *                                    with the analytic moments (MODE leadr|lean|bump-roughness|toksvig,
 *                                    SOURCE height|float|png16|png8, BASE the --base-alpha)
 *   --write-env KIND PATH            lat-long environments: constant (1.5 everywhere), texel (one
 *                                    texel 100 at (17, 5) in a 48 x 24 map, else 0)
 *   --check-sh JSON KIND UP [LIGHTS] checks the JSON of `mfkit sh project` (UP z|y; LIGHTS: the
 *                                    light of test_sh_cli.sh was added)
 *
 * Analytic height field (W x H = 64 x 32 texels, texel size T = 1/64, height scale 1):
 *   h(i, j) = sum_k A_k sin(theta_k),  theta_k = 2 pi (p_k i / W + q_k j / H) + phi_k,
 * column i, row j from the top; the frame's y is up the image, so y = -j T.  Central differences
 * (periodic) give exactly, per wave,
 *   s_x = A sin(2 pi p / W) / T cos(theta),   s_y = -A sin(2 pi q / H) / T cos(theta),
 * i.e. the continuous slope A w cos(theta) (w = 2 pi p / (W T)) times sinc(w T): the
 * discretisation error of the slope of one wave is 1 - sinc(w T) <= (w T)^2 / 6, and of its
 * second moment 1 - sinc^2(w T) <= (w T)^2 / 3.  Over the whole image (full periods, distinct wave
 * vectors, so the cross terms vanish by discrete orthogonality):
 *   E[x] = E[y] = 0,  E[x^2] = sum a_k^2 / 2,  E[y^2] = sum b_k^2 / 2,  E[xy] = sum a_k b_k / 2,
 * with (a_k, b_k) the discrete slope amplitudes.  Every level texel of the chain is the average of
 * its 2^L x 2^L block (W, H powers of two), which the check computes directly.
 */
#define _POSIX_C_SOURCE 200809L

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <mfkit/io/mf_image.h>
#include <mfkit/mfkit.h>
#include <mfkit/fit/mf_image_oiio.h>

#include "mf_test.h"
#include "test_files.h"

#define W 64
#define H 32
#define TEXEL (1.0 / 64.0)

typedef struct {
    double a;
    int p, q;
    double phi;
} wave;

static const wave k_waves[] = {{0.05, 1, 0, 0.3}, {0.01, 3, 2, 1.1}, {0.004, 0, 5, 2.0}, {0.002, 7, -3, 0.7}};
#define NWAVES ((int)(sizeof k_waves / sizeof k_waves[0]))

static double theta(const wave *w, int i, int j)
{
    return 2.0 * MF_PI * ((double)w->p * i / W + (double)w->q * j / H) + w->phi;
}

static double height_at(int i, int j)
{
    double h = 0.0;
    for (int k = 0; k < NWAVES; ++k)
        h += k_waves[k].a * sin(theta(&k_waves[k], i, j));
    return h;
}

/* Slope amplitudes of wave k: discrete (central differences) or continuous (exact). */
static void amplitude(int k, int discrete, double *ax, double *ay)
{
    const wave *w = &k_waves[k];
    double wx = 2.0 * MF_PI * w->p / (W * TEXEL), wy = 2.0 * MF_PI * w->q / (H * TEXEL);
    if (discrete) {
        *ax = w->a * sin(wx * TEXEL) / TEXEL;
        *ay = -w->a * sin(wy * TEXEL) / TEXEL;
    } else {
        *ax = w->a * wx;
        *ay = -w->a * wy;
    }
}

static void slope_at(int i, int j, int discrete, double s[2])
{
    s[0] = s[1] = 0.0;
    for (int k = 0; k < NWAVES; ++k) {
        double ax, ay, c = cos(theta(&k_waves[k], i, j));
        amplitude(k, discrete, &ax, &ay);
        s[0] += ax * c;
        s[1] += ay * c;
    }
}

/* S1 = sum |a_k| + |b_k|: a bound on |slope| components. */
static double slope_bound(int discrete)
{
    double s = 0.0;
    for (int k = 0; k < NWAVES; ++k) {
        double ax, ay;
        amplitude(k, discrete, &ax, &ay);
        s += fabs(ax) + fabs(ay);
    }
    return s;
}

static void unit_normal(const double s[2], double n[3])
{
    double inv = 1.0 / sqrt(1.0 + s[0] * s[0] + s[1] * s[1]);
    n[0] = -s[0] * inv;
    n[1] = -s[1] * inv;
    n[2] = inv;
}

static int write_image(const char *path, int w, int h, int c, const float *px, const char *const *names)
{
    mf_image img = {w, h, c, (float *)px};
    mf_image_write_options o;
    memset(&o, 0, sizeof o);
    o.channel_names = names;
    char msg[512];
    mf_status st = mf_image_write_ex(path, &img, &o, msg, sizeof msg);
    if (st != MF_OK) {
        fprintf(stderr, "test_maps: %s\n", msg);
        return 1;
    }
    return 0;
}

/* ---- unit tests of mf_maps.h ----------------------------------------------------------------- */

static void test_mip_sizes(void)
{
    CHECK(mf_map_mip_dim(1) == 1 && mf_map_mip_dim(2) == 1 && mf_map_mip_dim(3) == 1 && mf_map_mip_dim(5) == 2);
    CHECK(mf_map_mip_dim(0) == 0);
    CHECK(mf_map_mip_count(64, 32) == 7 && mf_map_mip_count(1, 1) == 1 && mf_map_mip_count(5, 3) == 3);
    CHECK(mf_map_mip_count(0, 4) == 0);
}

/* Odd sizes: 5 -> 2 has weights (0.4, 0.4, 0.2) and (0.2, 0.4, 0.4); the mean of every channel is
 * kept at every level (to a few ulps of the values: the weights are exact rationals rounded once). */
static void test_box_odd(void)
{
    mf_map m;
    CHECK(mf_map_alloc(&m, 5, 3, 2) == MF_OK);
    uint64_t x = 12345;
    double sum[2] = {0, 0};
    for (int t = 0; t < 15; ++t)
        for (int c = 0; c < 2; ++c) {
            x = x * 6364136223846793005ULL + 1442695040888963407ULL;
            m.data[2 * t + c] = (double)(x >> 11) * 0x1p-53 - 0.25 * c;
            sum[c] += m.data[2 * t + c];
        }
    mf_map cur = m;
    for (int level = 1; level < mf_map_mip_count(5, 3); ++level) {
        mf_map next;
        CHECK(mf_map_box_downsample(&cur, &next) == MF_OK);
        if (level == 1) {
            CHECK(next.width == 2 && next.height == 1);
            /* texel (0, 0), channel 0: rows 0..2 weight 1/3 each, columns 0.4, 0.4, 0.2 */
            double e = 0.0;
            for (int j = 0; j < 3; ++j)
                e += (0.4 * m.data[2 * (5 * j + 0)] + 0.4 * m.data[2 * (5 * j + 1)] + 0.2 * m.data[2 * (5 * j + 2)]) / 3.0;
            CHECK_ABS(next.data[0], e, 8 * DBL_EPSILON);
        }
        for (int c = 0; c < 2; ++c) {
            double s = 0.0;
            for (int t = 0; t < next.width * next.height; ++t)
                s += next.data[2 * t + c];
            CHECK_ABS(s / (next.width * next.height), sum[c] / 15.0, 16 * DBL_EPSILON);
        }
        mf_map_free(&cur);
        cur = next;
    }
    CHECK(cur.width == 1 && cur.height == 1);
    mf_map_free(&cur);
    /* a constant stays exactly constant (weights sum to 1 up to rounding) */
    CHECK(mf_map_alloc(&m, 7, 1, 1) == MF_OK);
    for (int t = 0; t < 7; ++t)
        m.data[t] = 0.75;
    mf_map d;
    CHECK(mf_map_box_downsample(&m, &d) == MF_OK);
    CHECK(d.width == 3 && d.height == 1);
    for (int t = 0; t < 3; ++t)
        CHECK_ABS(d.data[t], 0.75, 2 * DBL_EPSILON);
    mf_map_free(&d);
    mf_map_free(&m);
    CHECK(mf_map_box_downsample(NULL, &d) == MF_ERR_DOMAIN);
}

/* The analytic field in double: slopes by central differences are the discrete slopes to
 * rounding (a few ulps of the heights divided by T), and every level of the chain holds the block
 * averages of the moments; the 1 x 1 level holds the whole-image moments of the header comment. */
static void test_height_chain(void)
{
    mf_map hm, s, m;
    CHECK(mf_map_alloc(&hm, W, H, 1) == MF_OK);
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i)
            hm.data[j * W + i] = height_at(i, j);
    size_t bad = 0;
    CHECK(mf_map_slopes_from_heights(&hm, 0, 1.0, TEXEL, MF_MAP_EDGE_WRAP, &s, &bad) == MF_OK);
    const double tol_s = 16 * DBL_EPSILON * 0.07 / TEXEL; /* |h| <= sum A = 0.066 */
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            double e[2];
            slope_at(i, j, 1, e);
            CHECK_ABS(s.data[2 * (j * W + i)], e[0], tol_s);
            CHECK_ABS(s.data[2 * (j * W + i) + 1], e[1], tol_s);
        }
    CHECK(mf_map_moments_from_slopes(&s, &m) == MF_OK);
    mf_map_free(&s);
    for (int level = 1; level < mf_map_mip_count(W, H); ++level) {
        mf_map next;
        CHECK(mf_map_box_downsample(&m, &next) == MF_OK);
        mf_map_free(&m);
        m = next;
    }
    CHECK(m.width == 1 && m.height == 1);
    double exx = 0, eyy = 0, exy = 0, cxx = 0;
    for (int k = 0; k < NWAVES; ++k) {
        double ax, ay, cx, cy;
        amplitude(k, 1, &ax, &ay);
        amplitude(k, 0, &cx, &cy);
        exx += ax * ax / 2, eyy += ay * ay / 2, exy += ax * ay / 2, cxx += cx * cx / 2;
    }
    mf_slope_moments top = mf_map_moments_at(&m, 0, 0);
    CHECK_ABS(top.mean_x, 0.0, 64 * DBL_EPSILON);
    CHECK_ABS(top.mean_y, 0.0, 64 * DBL_EPSILON);
    CHECK_REL(top.m_xx, exx, 1e-12);
    CHECK_REL(top.m_yy, eyy, 1e-12);
    CHECK_REL(top.m_xy, exy, 1e-11);
    /* discretisation: E[x^2] below the continuous value by at most max (w T)^2 / 3 */
    double wt = 2.0 * MF_PI * 7 / W;
    CHECK(top.m_xx < cxx && 1.0 - top.m_xx / cxx <= wt * wt / 3.0);
    mf_map_free(&m);
    /* clamp: one-sided differences at the borders; a linear ramp has the exact slope everywhere */
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i)
            hm.data[j * W + i] = 0.5 * i - 0.25 * j;
    CHECK(mf_map_slopes_from_heights(&hm, 0, 2.0, 0.5, MF_MAP_EDGE_CLAMP, &s, &bad) == MF_OK);
    for (int t = 0; t < W * H; ++t) {
        CHECK_ABS(s.data[2 * t], 2.0, 1e-12);
        CHECK_ABS(s.data[2 * t + 1], 1.0, 1e-12); /* y up: h grows by 0.25 per row upwards */
    }
    mf_map_free(&s);
    hm.data[5 * W + 9] = NAN;
    CHECK(mf_map_slopes_from_heights(&hm, 0, 1.0, 1.0, MF_MAP_EDGE_WRAP, &s, &bad) == MF_ERR_DOMAIN);
    CHECK(bad == (size_t)(5 * W + 9));
    CHECK(mf_map_slopes_from_heights(&hm, 0, 1.0, 0.0, MF_MAP_EDGE_WRAP, &s, &bad) == MF_ERR_DOMAIN);
    mf_map_free(&hm);
}

static void test_normals(void)
{
    mf_map n, s;
    CHECK(mf_map_alloc(&n, 2, 1, 3) == MF_OK);
    double v[6] = {0.6, 0.0, 0.8, 0.0, -0.28, 0.96};
    memcpy(n.data, v, sizeof v);
    size_t bad = 99;
    CHECK(mf_map_slopes_from_normals(&n, &s, &bad) == MF_OK);
    CHECK_ABS(s.data[0], -0.75, 1e-15);
    CHECK_ABS(s.data[1], 0.0, 0.0);
    CHECK_ABS(s.data[3], 0.28 / 0.96, 1e-15);
    mf_map_free(&s);
    n.data[5] = 0.0;
    CHECK(mf_map_slopes_from_normals(&n, &s, &bad) == MF_ERR_DOMAIN && bad == 1);
    mf_map_free(&n);
}

/* ---- images for the shell tests ------------------------------------------------------------- */

static int write_height(const char *path)
{
    float *px = malloc(sizeof(float) * W * H);
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i)
            px[j * W + i] = (float)height_at(i, j);
    static const char *const y[] = {"Y"};
    int rc = write_image(path, W, H, 1, px, y);
    free(px);
    return rc;
}

static int write_normals(const char *path, const char *variant)
{
    float *px = malloc(sizeof(float) * 3 * W * H);
    int dx = variant && !strcmp(variant, "dx"), enc = variant && !strcmp(variant, "enc");
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            double s[2], n[3];
            slope_at(i, j, 0, s);
            unit_normal(s, n);
            if (dx)
                n[1] = -n[1];
            for (int c = 0; c < 3; ++c)
                px[3 * (j * W + i) + c] = (float)(enc ? 0.5 * (n[c] + 1.0) : n[c]);
        }
    static const char *const rgb[] = {"R", "G", "B"};
    int rc = write_image(path, W, H, 3, px, rgb);
    free(px);
    return rc;
}

static int write_bad(const char *kind, const char *path)
{
    float px[4 * 3 * 3];
    for (int t = 0; t < 12; ++t)
        px[3 * t + 0] = 0.0f, px[3 * t + 1] = 0.0f, px[3 * t + 2] = 1.0f;
    static const char *const rgb[] = {"R", "G", "B"}, *const rg[] = {"R", "G"}, *const y[] = {"Y"};
    if (!strcmp(kind, "twochannel"))
        return write_image(path, 4, 3, 2, px, rg);
    if (!strcmp(kind, "heightnan")) {
        px[7] = NAN;
        return write_image(path, 4, 3, 1, px, y);
    }
    float *t = px + 3 * (1 * 4 + 2); /* texel (2, 1) */
    if (!strcmp(kind, "unnormalised"))
        t[2] = 0.9f;
    else if (!strcmp(kind, "negz"))
        t[0] = 0.6f, t[2] = -0.8f;
    else if (!strcmp(kind, "nan"))
        t[1] = NAN;
    else
        return fprintf(stderr, "test_maps: unknown bad kind %s\n", kind), 1;
    return write_image(path, 4, 3, 3, px, rgb);
}

/* ---- checks of `mfkit maps` outputs ------------------------------------------------------------- */

static int read_level(const char *prefix, const char *tag, int level, mf_image *img, mf_image_info *info)
{
    char path[4096], msg[512];
    snprintf(path, sizeof path, "%s_%s_mip%d.exr", prefix, tag, level);
    if (mf_image_read_ex(path, img, NULL, info, msg, sizeof msg) != MF_OK) {
        MF_FAIL_AT("cannot read %s: %s", path, msg);
        return -1;
    }
    return 0;
}

static int channel(const mf_image_info *info, const char *name)
{
    for (int c = 0; c < info->nchannels; ++c)
        if (!strcmp(info->channel_names[c], name))
            return c;
    MF_FAIL_AT("no channel %s", name);
    return 0;
}

static int check_maps(const char *prefix, const char *mode, const char *source, double base)
{
    const int discrete = !strcmp(source, "height");
    /* Tolerance of one slope component (derivations in the file comment of each source):
     * height: float heights (|h| <= 0.066, rounding 2^-24 |h|) differenced over 2T, twice;
     * float normals: 2^-24 per component; png16 / png8: 1/65535 / 1/255 per component (half the
     * step 2/(2^bits - 1) of n = 2c - 1); slope = -n.x/n.z moves by (|dn.x| + |s| |dn.z|)/n.z. */
    const double smax = slope_bound(discrete);
    double dn = !strcmp(source, "png16") ? 1.0 / 65535 : !strcmp(source, "png8") ? 1.0 / 255 : 0x1p-24;
    double tol_s = discrete ? 2.0 * 0.066 * 0x1p-24 / (2.0 * TEXEL) * 1.01
                            : 1.01 * dn * (1.0 + smax) * sqrt(1.0 + smax * smax) + 4 * DBL_EPSILON;
    const double f32 = 0x1p-23; /* float output rounding, relative, with margin */
    const double tol_e = tol_s + f32 * smax;
    const double tol_m = 2.0 * smax * tol_s + tol_s * tol_s + f32 * smax * smax;
    const double b = 0.5 * base * base;
    const int levels = mf_map_mip_count(W, H);
    const int lean = !strcmp(mode, "lean"), bump = !strcmp(mode, "bump-roughness"), tok = !strcmp(mode, "toksvig");
    const char *tag = bump ? "roughness" : tok ? "toksvig" : "m1";
    char path[4096];
    snprintf(path, sizeof path, "%s_%s_mip%d.exr", prefix, tag, levels);
    CHECK(!mf_test_file_exists(path)); /* exactly `levels` levels */
    /* level-0 analytic quantities: moments (5) and unit normals (3) per texel */
    double *m0 = malloc(sizeof(double) * 8 * W * H);
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            double s[2], *p = m0 + 8 * (j * W + i);
            slope_at(i, j, discrete, s);
            p[0] = s[0], p[1] = s[1], p[2] = s[0] * s[0], p[3] = s[0] * s[1], p[4] = s[1] * s[1];
            unit_normal(s, p + 5);
        }
    double worst = 0.0;
    for (int level = 0; level < levels; ++level) {
        int w = W >> level > 0 ? W >> level : 1, h = H >> level > 0 ? H >> level : 1;
        int bw = W / w, bh = H / h;
        mf_image a = {0, 0, 0, NULL}, a2 = {0, 0, 0, NULL};
        mf_image_info ia, ia2;
        memset(&ia2, 0, sizeof ia2);
        if (read_level(prefix, tag, level, &a, &ia) != 0)
            break;
        if (!bump && !tok && read_level(prefix, "m2", level, &a2, &ia2) != 0) {
            mf_image_free(&a);
            mf_image_info_free(&ia);
            break;
        }
        CHECK(a.width == w && a.height == h);
        for (int J = 0; J < h; ++J)
            for (int I = 0; I < w; ++I) {
                double e[8] = {0};
                for (int j = J * bh; j < (J + 1) * bh; ++j)
                    for (int i = I * bw; i < (I + 1) * bw; ++i)
                        for (int c = 0; c < 8; ++c)
                            e[c] += m0[8 * (j * W + i) + c];
                for (int c = 0; c < 8; ++c)
                    e[c] /= (double)(bw * bh);
                const float *p = a.pixels + (size_t)(J * w + I) * a.channels;
                if (!bump && !tok) {
                    const float *q = a2.pixels + (size_t)(J * w + I) * a2.channels;
                    double sg = lean ? -1.0 : 1.0;
                    CHECK_ABS(p[channel(&ia, "R")], sg * e[0], tol_e);
                    CHECK_ABS(p[channel(&ia, "G")], sg * e[1], tol_e);
                    CHECK_ABS(p[channel(&ia, "B")], 0.0, 0.0);
                    CHECK_ABS(q[channel(&ia2, "R")], e[2] + b, tol_m + f32 * b);
                    CHECK_ABS(q[channel(&ia2, "G")], e[4] + b, tol_m + f32 * b);
                    CHECK_ABS(q[channel(&ia2, "B")], e[3], tol_m);
                    double d = fabs(p[channel(&ia, "R")] - sg * e[0]) / tol_e;
                    worst = d > worst ? d : worst;
                } else if (bump) {
                    /* trace and determinant of diag(base^2) + 2 Sigma, Sigma = M - E E^T */
                    double vx = e[2] - e[0] * e[0], vy = e[4] - e[1] * e[1], cxy = e[3] - e[0] * e[1];
                    double tol_v = tol_m + 2.0 * smax * tol_e + tol_e * tol_e;
                    double a1 = p[channel(&ia, "alpha_1")], a2v = p[channel(&ia, "alpha_2")];
                    double dx = p[channel(&ia, "dir_x")], dy = p[channel(&ia, "dir_y")];
                    double tr = 2 * base * base + 2 * (vx + vy);
                    double det = (base * base + 2 * vx) * (base * base + 2 * vy) - 4 * cxy * cxy;
                    CHECK(a1 >= a2v && a2v >= 0.0);
                    CHECK_ABS(a1 * a1 + a2v * a2v, tr, 4 * tol_v + 4 * f32 * tr);
                    CHECK_ABS(a1 * a1 * a2v * a2v, det, 4 * tol_v * (tr + 4 * tol_v) + 8 * f32 * tr * tr);
                    CHECK_ABS(dx * dx + dy * dy, 1.0, 4 * f32);
                    CHECK(dx >= 0.0);
                } else {
                    double len = sqrt(e[5] * e[5] + e[6] * e[6] + e[7] * e[7]);
                    /* a unit normal moves by at most |ds| per slope component, sqrt(2) |ds| in all */
                    double tol_len = 2.0 * tol_s + 2 * f32;
                    double fl = p[channel(&ia, "len")], fa = p[channel(&ia, "alpha")];
                    CHECK_ABS(fl, len, tol_len);
                    double a_sq = base * base + 2.0 * (1.0 - len) / len;
                    CHECK_ABS(fa * fa, a_sq, 2.0 * tol_len / (len * len) * 1.01 + 4 * f32 * a_sq);
                    for (int c = 0; c < 3; ++c)
                        CHECK_ABS(p[channel(&ia, (const char *[]){"n_x", "n_y", "n_z"}[c])], e[5 + c] / len,
                                  4.0 * tol_len / len);
                }
            }
        if (level == levels - 1 && !bump && !tok) {
            /* the whole image: E = 0, second moments sum a_k^2 / 2 (discrete orthogonality) */
            double exx = 0, eyy = 0, exy = 0;
            for (int k = 0; k < NWAVES; ++k) {
                double ax, ay;
                amplitude(k, discrete, &ax, &ay);
                exx += ax * ax / 2, eyy += ay * ay / 2, exy += ax * ay / 2;
            }
            CHECK_ABS(a.pixels[channel(&ia, "R")], 0.0, tol_e);
            CHECK_ABS(a.pixels[channel(&ia, "G")], 0.0, tol_e);
            CHECK_ABS(a2.pixels[channel(&ia2, "R")], exx + b, tol_m + f32 * b);
            CHECK_ABS(a2.pixels[channel(&ia2, "G")], eyy + b, tol_m + f32 * b);
            CHECK_ABS(a2.pixels[channel(&ia2, "B")], exy, tol_m);
        }
        mf_image_free(&a);
        mf_image_free(&a2);
        mf_image_info_free(&ia);
        mf_image_info_free(&ia2);
    }
    free(m0);
    printf("check %s %s %s: worst E error / tolerance %.3g (tolerance of a slope %.3g)\n", mode, source, prefix,
           worst, tol_s);
    MF_TEST_MAIN_END();
}

/* ---- SH environments --------------------------------------------------------------------------- */

#define ENV_W 48
#define ENV_H 24
#define TEX_I 17
#define TEX_J 5
#define TEX_V 100.0
#define CONST_L 1.5

static int write_env(const char *kind, const char *path)
{
    float *px = calloc(3 * ENV_W * ENV_H, sizeof(float));
    for (int t = 0; t < 3 * ENV_W * ENV_H; ++t)
        px[t] = !strcmp(kind, "constant") ? (float)CONST_L : 0.0f;
    if (!strcmp(kind, "texel"))
        for (int c = 0; c < 3; ++c)
            px[3 * (TEX_J * ENV_W + TEX_I) + c] = (float)(TEX_V * (c + 1));
    static const char *const rgb[] = {"R", "G", "B"};
    int rc = write_image(path, ENV_W, ENV_H, 3, px, rgb);
    free(px);
    return rc;
}

/* The value of "name" inside the object of channel ch in the JSON text. */
static double json_coeff(const char *json, const char *ch, const char *name)
{
    char key[64];
    snprintf(key, sizeof key, "\"%s\": {", ch);
    const char *p = strstr(json, key);
    if (!p)
        return NAN;
    const char *end = strchr(p, '}');
    snprintf(key, sizeof key, "\"%s\": ", name);
    const char *q = strstr(p, key);
    if (!q || q > end)
        return NAN;
    return strtod(q + strlen(key), NULL);
}

static int check_sh(const char *json_path, const char *kind, const char *up, int lights)
{
    static const char *const names[9] = {"L00", "L1m1", "L10", "L11", "L2m2", "L2m1", "L20", "L21", "L22"};
    FILE *f = fopen(json_path, "r");
    if (!f)
        return fprintf(stderr, "cannot open %s\n", json_path), 1;
    static char json[1 << 16];
    size_t n = fread(json, 1, sizeof json - 1, f);
    json[n] = '\0';
    fclose(f);
    const int up_y = !strcmp(up, "y");
    const mf_mat3 r = {{{1, 0, 0}, {0, 0, 1}, {0, -1, 0}}}; /* world = R map-local (cli_sh.c) */
    const double delta = MF_PI / (2.0 * ENV_H);           /* half the row height in theta */
    for (int c = 0; c < 3; ++c) {
        const char *ch = (const char *[]){"R", "G", "B"}[c];
        double e[9] = {0};
        if (!strcmp(kind, "constant")) {
            /* L00 = 2 sqrt(pi) L (the solid angles sum to 4 pi).  Band 1 and the m != 0 terms of
             * band 2 vanish by symmetry.  L20 is the midpoint rule's error on cos^2: over the ring
             * [theta_c - delta, theta_c + delta] (exact weights 2 pi 2 sin theta_c sin delta),
             *   integral cos^2 sin dtheta - cos^2(theta_c) 2 sin theta_c sin delta
             *     = -2 cos^2 theta_c sin theta_c sin^3 delta + (2/3) sin^3 theta_c sin^3 delta,
             * so  L20 = L c20 2 pi sin^3(delta) sum_j (6 cos^2 theta_j sin theta_j - 2 sin^3 theta_j)
             * ~ L c20 (4 pi / 3) delta^2 (the sum ~ (1/(2 delta)) integral = 2/(3 delta)): O(H^-2). */
            e[0] = 2.0 * MF_SQRT_PI * CONST_L;
            double s = 0.0;
            for (int j = 0; j < ENV_H; ++j) {
                double th = MF_PI * (j + 0.5) / ENV_H, ct = cos(th), st = sin(th);
                s += 6.0 * ct * ct * st - 2.0 * st * st * st;
            }
            double l20 = CONST_L * MF_SH_Y20 * 2.0 * MF_PI * pow(sin(delta), 3) * s;
            CHECK_REL(l20, CONST_L * MF_SH_Y20 * 4.0 * MF_PI / 3.0 * delta * delta, 0.01);
            if (up_y) { /* Y20 about y: rotate the z-axis term */
                double in[9] = {e[0], 0, 0, 0, 0, 0, l20, 0, 0};
                mf_sh_rotate(in, r, e);
            } else {
                e[6] = l20;
            }
        } else {
            /* one texel of value V: c_i = V Omega Y_i(w_centre) (midpoint rule, exact weights) */
            double th = MF_PI * (TEX_J + 0.5) / ENV_H, ph = 2.0 * MF_PI * (TEX_I + 0.5) / ENV_W;
            double omega = (2.0 * MF_PI / ENV_W) * 2.0 * sin(th) * sin(delta);
            mf_vec3 w = mf_vec3_spherical(th, ph);
            if (up_y)
                w = mf_mat3_apply(r, w);
            double y[9];
            mf_sh_eval(w, y);
            for (int i = 0; i < 9; ++i)
                e[i] = TEX_V * (c + 1) * omega * y[i];
        }
        if (lights) { /* test_sh_cli.sh's lights: (0, 0, 2) -> +z with r,g,b = 1, 2, 3; (1, 1, 0) with 0.5 */
            mf_sh_add_directional(e, mf_vec3_make(0, 0, 1), 1.0 + c);
            mf_sh_add_directional(e, mf_vec3_make(MF_SQRT2 / 2, MF_SQRT2 / 2, 0), 0.5);
        }
        double scale = fabs(e[0]) + 1.0;
        for (int i = 0; i < 9; ++i) {
            double got = json_coeff(json, ch, names[i]);
            /* %.17g round trip; sums of W H terms: 64 eps relative to the largest coefficient */
            CHECK_ABS(got, e[i], 64 * DBL_EPSILON * scale);
        }
    }
    MF_TEST_MAIN_END();
}

int main(int argc, char **argv)
{
    mf_image_set_backend(mf_image_oiio_backend()); /* EXR files */
    if (argc >= 3 && !strcmp(argv[1], "--write-height"))
        return write_height(argv[2]);
    if (argc >= 3 && !strcmp(argv[1], "--write-normals"))
        return write_normals(argv[2], argc >= 4 ? argv[3] : NULL);
    if (argc >= 4 && !strcmp(argv[1], "--write-bad"))
        return write_bad(argv[2], argv[3]);
    if (argc >= 6 && !strcmp(argv[1], "--check"))
        return check_maps(argv[2], argv[3], argv[4], atof(argv[5]));
    if (argc >= 4 && !strcmp(argv[1], "--write-env"))
        return write_env(argv[2], argv[3]);
    if (argc >= 5 && !strcmp(argv[1], "--check-sh"))
        return check_sh(argv[2], argv[3], argv[4], argc >= 6);
    if (argc > 1)
        return fprintf(stderr, "test_maps: unknown arguments (see the file comment)\n"), 2;
    test_mip_sizes();
    test_box_odd();
    test_height_chain();
    test_normals();
    MF_TEST_MAIN_END();
}
