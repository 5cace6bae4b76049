/* test_prefilter_lookup.c DIR -- the texture layout of `mfkit prefilter` (DIR its output) and a C twin
 * of its lookup snippet (DIR/prefilter_lookup.glsl, line for line: four view layers blended bilinearly
 * over (theta, phi), each sampled with the hardware's trilinear filter: bilinear with REPEAT wrap at
 * two MIP levels, blended linearly, MIP level k - 1 = prefilter level k), reading the EXR view
 * atlases, against the .npy arrays:
 *   - at every texel centre, integer level of detail and tabulated view, the twin returns the .npy
 *     matrix and magnitude of that texel, level and view;
 *   - at 4000 random (uv, lod, theta, phi) (fixed seed) it equals the same filter computed directly
 *     on the .npy arrays (their own indexing, no atlas).
 *   - the split lookup (DIR/prefilter_lookup.glsl's mfpfLookupTap, eight texel taps read with
 *     texelFetch): at the same random points its twin over the atlases has weights summing to 1, its
 *     taps blended with their weights give mfpfLookup's M and magnitude (the filter is linear), and
 *     tap k equals tap k of mf_prefilter_lookup_taps (mf_prefilter_lookup.h, split texel + level) on
 *     the .npy arrays, so the renderer's taps are the shader's.
 * Tolerance 1e-12 relative to max(1, |value|): both evaluate the same float32 texels in double with
 * weights that differ only by rounding (the view grid theta_i = i / (n - 1) theta_max mapped back,
 * the summation order), a few ulps of double; a layout or channel error is O(|value|). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mfkit/fit/mf_image_oiio.h"
#include "mfkit/fit/mf_prefilter.h"
#include "mfkit/fit/mf_prefilter_lookup.h"
#include "mfkit/io/mf_image.h"
#include "mfkit/mf_rng.h"

#define MAXL 16
static int g_fail = 0, g_checks = 0;

typedef struct { int w, h; float *m, *mag; mf_image tex[3]; } level;
static level L[MAXL];
static int nlev, nt, np;

static float *read_npy(const char *path, int *dims, int *nd)
{
    FILE *f = fopen(path, "rb");
    unsigned char pre[10];
    if (!f || fread(pre, 1, 10, f) != 10) {
        fprintf(stderr, "%s: cannot read\n", path);
        exit(1);
    }
    int hl = pre[8] | pre[9] << 8;
    char *h = calloc((size_t)hl + 1, 1);
    if (fread(h, 1, (size_t)hl, f) != (size_t)hl || !strstr(h, "'<f4'")) {
        fprintf(stderr, "%s: not a float32 .npy\n", path);
        exit(1);
    }
    char *s = strchr(strstr(h, "'shape'"), '(') + 1;
    size_t n = 1;
    *nd = 0;
    while (*s != ')') {
        dims[(*nd)++] = (int)strtol(s, &s, 10);
        n *= (size_t)dims[*nd - 1];
        while (*s == ',' || *s == ' ')
            ++s;
    }
    float *d = malloc(n * sizeof *d);
    if (fread(d, sizeof *d, n, f) != n) {
        fprintf(stderr, "%s: truncated\n", path);
        exit(1);
    }
    fclose(f);
    free(h);
    return d;
}

/* ---- the twin: the snippet's arithmetic over the atlases ---------------------------------- */

/* texel (x, y) of layer `layer` at array MIP level lv, texture t: the atlas pixel of that view tile */
static const float *atlas(int t, int lv, int layer, int x, int y)
{
    const level *l = &L[lv];
    int a = layer / np, p = layer % np;
    size_t px = (size_t)(a * l->h + y) * (size_t)l->tex[t].width + (size_t)(p * l->w + x);
    return l->tex[t].pixels + 4 * px;
}

static int wrap(int i, int n) { return ((i % n) + n) % n; }

static void bilinear_atlas(int t, int lv, double u, double v, int layer, double out[4])
{
    const level *l = &L[lv];
    double xf = u * l->w - 0.5, yf = v * l->h - 0.5, x0 = floor(xf), y0 = floor(yf), fx = xf - x0, fy = yf - y0;
    for (int c = 0; c < 4; ++c)
        out[c] = 0.0;
    for (int k = 0; k < 4; ++k) {
        int dx = k & 1, dy = k >> 1;
        double w = (dx ? fx : 1.0 - fx) * (dy ? fy : 1.0 - fy);
        const float *p = atlas(t, lv, layer, wrap((int)x0 + dx, l->w), wrap((int)y0 + dy, l->h));
        for (int c = 0; c < 4; ++c)
            out[c] += w * p[c];
    }
}

/* textureLod of a 2D array texture, LINEAR_MIPMAP_LINEAR: lod clamped to [0, levels - 1] */
static void texture_lod(int t, double u, double v, int layer, double lod, double out[4])
{
    double l = fmin(fmax(lod, 0.0), nlev - 1.0);
    int l0 = (int)floor(l), l1 = l0 + 1 < nlev ? l0 + 1 : l0;
    double f = l - l0, a[4], b[4];
    bilinear_atlas(t, l0, u, v, layer, a);
    bilinear_atlas(t, l1, u, v, layer, b);
    for (int c = 0; c < 4; ++c)
        out[c] = (1.0 - f) * a[c] + f * b[c];
}

static void twin_lookup(double u, double v, double lod, double theta, double phi, double M[9], double *mag)
{
    double ft = fmin(fmax(theta / MF_PREFILTER_THETA_MAX, 0.0), 1.0) * (nt - 1);
    int i0 = (int)ft < nt - 2 ? (int)ft : nt - 2;
    double wt = ft - i0;
    double fp = phi * (np / 6.28318530717958648);
    fp -= np * floor(fp / np);
    int j0 = (int)fp < np - 1 ? (int)fp : np - 1;
    double wp = fp - j0;
    int j1 = (j0 + 1) % np;
    double l = fmax(lod - 1.0, 0.0), a[4] = {0}, b[4] = {0}, c[4] = {0}, s[4];
    for (int k = 0; k < 4; ++k) {
        int di = k & 1, dj = k >> 1;
        double w = (di ? wt : 1.0 - wt) * (dj ? wp : 1.0 - wp);
        int layer = (i0 + di) * np + (dj ? j1 : j0);
        texture_lod(0, u, v, layer, l, s);
        for (int q = 0; q < 4; ++q)
            a[q] += w * s[q];
        texture_lod(1, u, v, layer, l, s);
        for (int q = 0; q < 4; ++q)
            b[q] += w * s[q];
        texture_lod(2, u, v, layer, l, s);
        for (int q = 0; q < 4; ++q)
            c[q] += w * s[q];
    }
    /* the snippet's mat3(a.x, a.w, b.z, a.y, b.x, b.w, a.z, b.y, c.x) in columns, as rows here */
    double rows[9] = {a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3], c[0]};
    memcpy(M, rows, sizeof rows);
    *mag = c[1];
}

/* mfpfLookupTap, line for line: tap k (0..7) of the texel-split filter; returns its weight */
static double twin_tap(int k, double u, double v, double lod, double theta, double phi, double M[9], double *mag)
{
    double ft = fmin(fmax(theta / MF_PREFILTER_THETA_MAX, 0.0), 1.0) * (nt - 1);
    int i0 = (int)ft < nt - 2 ? (int)ft : nt - 2;
    double wt = ft - i0;
    double fp = phi * (np / 6.28318530717958648);
    fp -= np * floor(fp / np);
    int j0 = (int)fp < np - 1 ? (int)fp : np - 1;
    double wp = fp - j0;
    int j1 = (j0 + 1) % np;
    double l = fmin(fmax(lod - 1.0, 0.0), nlev - 1.0);
    int l0 = (int)floor(l), il = k >> 2, lv = l0 + il < nlev - 1 ? l0 + il : nlev - 1;
    int sw = L[lv].w, sh = L[lv].h;
    double fx = u * sw - 0.5, fy = v * sh - 0.5, f0x = floor(fx), f0y = floor(fy);
    int ix = k & 1, iy = (k >> 1) & 1;
    int x = ((int)(f0x - sw * floor(f0x / sw)) + ix) % sw, y = ((int)(f0y - sh * floor(f0y / sh)) + iy) % sh;
    double weight = (il == 1 ? l - l0 : 1.0 - (l - l0)) * (ix ? fx - f0x : 1.0 - (fx - f0x)) *
                    (iy ? fy - f0y : 1.0 - (fy - f0y));
    double a[4] = {0}, b[4] = {0}, c[4] = {0};
    for (int q = 0; q < 4; ++q) {
        int di = q & 1, dj = q >> 1;
        double w = (di ? wt : 1.0 - wt) * (dj ? wp : 1.0 - wp);
        int layer = (i0 + di) * np + (dj ? j1 : j0);
        const float *pa = atlas(0, lv, layer, x, y), *pb = atlas(1, lv, layer, x, y), *pc = atlas(2, lv, layer, x, y);
        for (int e = 0; e < 4; ++e)
            a[e] += w * pa[e], b[e] += w * pb[e], c[e] += w * pc[e];
    }
    double rows[9] = {a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3], c[0]};
    memcpy(M, rows, sizeof rows);
    *mag = c[1];
    return weight;
}

/* ---- the reference: the same filter on the .npy arrays ------------------------------------------- */

static double npy_val(int lv, int x, int y, int a, int p, int q)
{
    const level *l = &L[lv];
    size_t idx = (((size_t)y * l->w + x) * nt + a) * np + p;
    return q < 9 ? l->m[9 * idx + q] : l->mag[idx];
}

static double ref_value(double u, double v, double lod, double theta, double phi, int q)
{
    double ft = fmin(fmax(theta / MF_PREFILTER_THETA_MAX, 0.0), 1.0) * (nt - 1);
    int a0 = (int)ft < nt - 2 ? (int)ft : nt - 2;
    double fp = fmod(phi / (2.0 * MF_PI) * np, (double)np);
    if (fp < 0)
        fp += np;
    int p0 = (int)fp < np - 1 ? (int)fp : np - 1;
    double wa[2] = {1.0 - (ft - a0), ft - a0}, wp[2] = {1.0 - (fp - p0), fp - p0};
    double l = fmin(fmax(lod - 1.0, 0.0), nlev - 1.0);
    int l0 = (int)floor(l);
    double wl[2] = {1.0 - (l - l0), l - l0}, sum = 0.0;
    for (int il = 0; il < 2; ++il) {
        int lv = l0 + il < nlev ? l0 + il : nlev - 1;
        const level *L1 = &L[lv];
        double xf = u * L1->w - 0.5, yf = v * L1->h - 0.5;
        int x0 = (int)floor(xf), y0 = (int)floor(yf);
        double wx[2] = {1.0 - (xf - x0), xf - x0}, wy[2] = {1.0 - (yf - y0), yf - y0};
        for (int ia = 0; ia < 2; ++ia)
            for (int ip = 0; ip < 2; ++ip)
                for (int iy = 0; iy < 2; ++iy)
                    for (int ix = 0; ix < 2; ++ix)
                        sum += wl[il] * wa[ia] * wp[ip] * wy[iy] * wx[ix] *
                               npy_val(lv, wrap(x0 + ix, L1->w), wrap(y0 + iy, L1->h), a0 + ia, (p0 + ip) % np, q);
    }
    return sum;
}

static void check(double got, double want, const char *what, double u, double v, double lod, double th, double ph, int q)
{
    ++g_checks;
    if (!(fabs(got - want) <= 1e-12 * fmax(1.0, fabs(want)))) {
        if (++g_fail <= 10)
            fprintf(stderr, "FAIL %s: entry %d at uv (%.6g, %.6g) lod %.6g theta %.6g phi %.6g: twin %.17g, npy %.17g\n",
                    what, q, u, v, lod, th, ph, got, want);
    }
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: test_prefilter_lookup DIR\n");
        return 2;
    }
    mf_image_set_backend(mf_image_oiio_backend());
    const char *dir = argv[1];
    char path[4096], msg[512];
    for (nlev = 0; nlev < MAXL; ++nlev) {
        int d[8], nd;
        snprintf(path, sizeof path, "%s/ltc_mip%d.npy", dir, nlev + 1);
        FILE *f = fopen(path, "rb");
        if (!f)
            break;
        fclose(f);
        level *l = &L[nlev];
        l->m = read_npy(path, d, &nd);
        if (nd != 6 || d[4] != 3 || d[5] != 3) {
            fprintf(stderr, "%s: shape of %d axes\n", path, nd);
            return 1;
        }
        l->h = d[0], l->w = d[1], nt = d[2], np = d[3];
        snprintf(path, sizeof path, "%s/magnitude_mip%d.npy", dir, nlev + 1);
        l->mag = read_npy(path, d, &nd);
        for (int t = 0; t < 3; ++t) {
            snprintf(path, sizeof path, "%s/prefilter_mip%d_%d.exr", dir, nlev + 1, t);
            if (mf_image_read(path, &l->tex[t], msg, sizeof msg) != MF_OK || l->tex[t].channels != 4 ||
                l->tex[t].width != l->w * np || l->tex[t].height != l->h * nt) {
                fprintf(stderr, "FAIL %s: %s (expected RGBA %d x %d)\n", path, msg, l->w * np, l->h * nt);
                return 1;
            }
        }
    }
    if (nlev < 2 || nt < 2 || np < 2) {
        fprintf(stderr, "FAIL %s: %d levels, %d x %d views (the test needs >= 2 of each)\n", dir, nlev, nt, np);
        return 1;
    }
    mf_prefilter_options o;
    mf_prefilter_options_default(&o);
    o.n_theta = nt, o.n_phi = np;
    /* texel centres, integer lods, tabulated views: the stored lobe itself */
    for (int k = 0; k < nlev; ++k)
        for (int y = 0; y < L[k].h; ++y)
            for (int x = 0; x < L[k].w; ++x)
                for (int a = 0; a < nt; ++a)
                    for (int p = 0; p < np; ++p) {
                        double u = (x + 0.5) / L[k].w, v = (y + 0.5) / L[k].h, th = mf_prefilter_theta(&o, a),
                               ph = mf_prefilter_phi(&o, p), M[9], mag;
                        twin_lookup(u, v, k + 1.0, th, ph, M, &mag);
                        for (int q = 0; q < 9; ++q)
                            check(M[q], npy_val(k, x, y, a, p, q), "texel centre", u, v, k + 1.0, th, ph, q);
                        check(mag, npy_val(k, x, y, a, p, 9), "texel centre", u, v, k + 1.0, th, ph, 9);
                    }
    /* the header's lookup over the same .npy arrays (for the split lookup's taps) */
    mf_prefilter_lookup_level hlev[MAXL];
    for (int k = 0; k < nlev; ++k)
        hlev[k].w = L[k].w, hlev[k].h = L[k].h, hlev[k].m = L[k].m, hlev[k].mag = L[k].mag;
    mf_prefilter_lookup_levels hl = {nlev, nt, np, hlev};
    /* anywhere: the filter on the .npy arrays */
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, 13, 1);
    for (int i = 0; i < 4000; ++i) {
        double u = mf_pcg32_next_double(&rng), v = mf_pcg32_next_double(&rng);
        double lod = 0.5 + (nlev + 0.5) * mf_pcg32_next_double(&rng);
        double th = 0.5 * MF_PI * mf_pcg32_next_double(&rng), ph = -MF_PI + 4.0 * MF_PI * mf_pcg32_next_double(&rng);
        double M[9], mag;
        twin_lookup(u, v, lod, th, ph, M, &mag);
        for (int q = 0; q < 9; ++q)
            check(M[q], ref_value(u, v, lod, th, ph, q), "random", u, v, lod, th, ph, q);
        check(mag, ref_value(u, v, lod, th, ph, 9), "random", u, v, lod, th, ph, 9);
        /* the split lookup */
        double TM[8 * 9], tmag[8], tw[8], HM[32 * 9], hmag[32], hw[32], sM[10] = {0}, wsum = 0.0;
        int nh = mf_prefilter_lookup_taps(&hl, u, v, lod, th, ph, MF_PREFILTER_SPLIT_TEXEL | MF_PREFILTER_SPLIT_LEVEL,
                                          HM, hmag, hw);
        check(nh, 8, "tap count", u, v, lod, th, ph, 0);
        for (int k = 0; k < 8; ++k) {
            tw[k] = twin_tap(k, u, v, lod, th, ph, TM + 9 * k, &tmag[k]);
            wsum += tw[k];
            for (int q = 0; q < 9; ++q)
                sM[q] += tw[k] * TM[9 * k + q];
            sM[9] += tw[k] * tmag[k];
            check(tw[k], hw[k], "tap weight", u, v, lod, th, ph, k);
            if (hw[k] > 0.0) {
                for (int q = 0; q < 9; ++q)
                    check(TM[9 * k + q], HM[9 * k + q], "tap matrix", u, v, lod, th, ph, q);
                check(tmag[k], hmag[k], "tap magnitude", u, v, lod, th, ph, 9);
            }
        }
        check(wsum, 1.0, "tap weights' sum", u, v, lod, th, ph, 0);
        for (int q = 0; q < 9; ++q)
            check(sM[q], M[q], "taps blended", u, v, lod, th, ph, q);
        check(sM[9], mag, "taps blended", u, v, lod, th, ph, 9);
    }
    for (int k = 0; k < nlev; ++k) {
        free(L[k].m), free(L[k].mag);
        for (int t = 0; t < 3; ++t)
            mf_image_free(&L[k].tex[t]);
    }
    printf("test_prefilter_lookup: %d levels, %d x %d views: %d checks, %d failed\n", nlev, nt, np, g_checks, g_fail);
    return g_fail ? 1 : 0;
}
