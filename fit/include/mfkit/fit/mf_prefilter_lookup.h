/*
 * mf_prefilter_lookup.h -- the lookup of `mfkit prefilter`'s lobes, on the arrays of its .npy
 * files (header only, C11 + libm): the filter the GLSL/HLSL snippet (prefilter_lookup.glsl)
 * computes on the EXR view atlases, written once for C programs (analysis/render_prefilter_scenes.c)
 * and tests.
 *
 * Filter (docs/prefilter.md, "Textures and the lookup"): bilinear over the view axes (theta
 * clamped to [0, MF_PREFILTER_THETA_MAX], theta_i = i / (n_theta - 1) MF_PREFILTER_THETA_MAX;
 * phi periodic, phi_j = 2 pi j / n_phi) of the trilinear texture filter of each view layer:
 * bilinear with REPEAT wrap (texel centres at (i + 0.5) / size) at the two MIP levels around
 * lod - 1 (prefilter level k is MIP level k - 1), clamped to the levels present, blended
 * linearly.  Level 0 of the map is not in the arrays: at lod < 1 this returns level 1's filter
 * (the snippet's max(lod - 1, 0)); a renderer blends with its own level-0 shading there.
 * The result: the forward M (row-major, view-azimuth-aligned frame) and the magnitude.
 *
 * Also here: mf_prefilter_texel_ltc, the per-texel LTC shading of one texel, the thesis' ground
 * truth and naive baseline [Nahmias 2022, Sec. 4.1] and mfkit's level 0; and
 * mf_prefilter_texel_lambert, one texel's exact Lambert shading (the diffuse table's ground truth).
 */
#ifndef MF_PREFILTER_LOOKUP_H
#define MF_PREFILTER_LOOKUP_H

#include <math.h>
#include <stddef.h>

#include "mfkit/fit/mf_prefilter.h"
#include "mfkit/mf_ltc.h"
#include "mfkit/mf_ltc_table.h"
#include "mfkit/mf_polygon.h"
#include "mfkit/mf_table.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One level k >= 1 as stored: m = ltc_mip<k>.npy (h, w, n_theta, n_phi, 3, 3), mag =
 * magnitude_mip<k>.npy (h, w, n_theta, n_phi), float32. */
typedef struct mf_prefilter_lookup_level {
    int w, h;
    const float *m, *mag;
} mf_prefilter_lookup_level;

typedef struct mf_prefilter_lookup_levels {
    int nlev;          /* levels 1 .. nlev in lev[0 .. nlev - 1] */
    int n_theta, n_phi;
    const mf_prefilter_lookup_level *lev;
} mf_prefilter_lookup_levels;

static inline int mf_prefilter_lookup_wrap_(int i, int n) { return ((i % n) + n) % n; }

/* Entry q (0..8: M row-major, 9: magnitude) of level index lv (0 = level 1), texel (x, y), view (a, p). */
static inline double mf_prefilter_lookup_value_(const mf_prefilter_lookup_levels *s, int lv, int x, int y, int a, int p,
                                                int q)
{
    const mf_prefilter_lookup_level *l = &s->lev[lv];
    size_t idx = (((size_t)y * (size_t)l->w + (size_t)x) * (size_t)s->n_theta + (size_t)a) * (size_t)s->n_phi + (size_t)p;
    return q < 9 ? (double)l->m[9 * idx + (size_t)q] : (double)l->mag[idx];
}

/* The filter's cell: the view corners (elevation row a0, azimuth column p0) and MIP levels (l0) around
 * (theta, phi, lod) with their linear weights, shared by both lookups. */
typedef struct {
    int a0, p0, l0;
    double wa[2], wp[2], wl[2];
} mf_prefilter_lookup_cell_;

static inline mf_prefilter_lookup_cell_ mf_prefilter_lookup_cell(const mf_prefilter_lookup_levels *s, double lod,
                                                                 double theta, double phi)
{
    const int nt = s->n_theta, np = s->n_phi;
    mf_prefilter_lookup_cell_ c;
    double ft = fmin(fmax(theta / MF_PREFILTER_THETA_MAX, 0.0), 1.0) * (nt - 1);
    c.a0 = (int)ft < nt - 2 ? (int)ft : nt - 2;
    double fp = fmod(phi / (2.0 * MF_PI) * np, (double)np);
    if (fp < 0)
        fp += np;
    c.p0 = (int)fp < np - 1 ? (int)fp : np - 1;
    c.wa[0] = 1.0 - (ft - c.a0), c.wa[1] = ft - c.a0;
    c.wp[0] = 1.0 - (fp - c.p0), c.wp[1] = fp - c.p0;
    double l = fmin(fmax(lod - 1.0, 0.0), s->nlev - 1.0);
    c.l0 = (int)floor(l);
    c.wl[0] = 1.0 - (l - c.l0), c.wl[1] = l - c.l0;
    return c;
}

/* The bilinear filter's texels of one level at (u, v): the lower corner (x0, y0), wrapped (REPEAT),
 * and the weights along x and y. */
static inline void mf_prefilter_lookup_texels_(const mf_prefilter_lookup_level *L1, double u, double v, int *x0, int *y0,
                                               double wx[2], double wy[2])
{
    double xf = u * L1->w - 0.5, yf = v * L1->h - 0.5;
    double x0f = floor(xf), y0f = floor(yf);
    *x0 = mf_prefilter_lookup_wrap_((int)fmod(x0f, (double)L1->w), L1->w);
    *y0 = mf_prefilter_lookup_wrap_((int)fmod(y0f, (double)L1->h), L1->h);
    wx[0] = 1.0 - (xf - x0f), wx[1] = xf - x0f;
    wy[0] = 1.0 - (yf - y0f), wy[1] = yf - y0f;
}

/* The lookup at texture coordinates (u, v) (u along the columns, v down the rows; any real: REPEAT),
 * level of detail lod (log2 of the footprint in level-0 texels), view (theta, phi) in the tangent
 * frame.  M[9] and *magnitude receive the filtered entries. */
static inline void mf_prefilter_lookup(const mf_prefilter_lookup_levels *s, double u, double v, double lod, double theta,
                                       double phi, double M[9], double *magnitude)
{
    const int np = s->n_phi;
    const mf_prefilter_lookup_cell_ c = mf_prefilter_lookup_cell(s, lod, theta, phi);
    const int a0 = c.a0, p0 = c.p0, l0 = c.l0;
    const double *wa = c.wa, *wp = c.wp, *wl = c.wl;
    double acc[10] = {0};
    for (int il = 0; il < 2; ++il) {
        int lv = l0 + il < s->nlev ? l0 + il : s->nlev - 1;
        const mf_prefilter_lookup_level *L1 = &s->lev[lv];
        int x0, y0;
        double wx[2], wy[2];
        mf_prefilter_lookup_texels_(L1, u, v, &x0, &y0, wx, wy);
        for (int ia = 0; ia < 2; ++ia)
            for (int ip = 0; ip < 2; ++ip)
                for (int iy = 0; iy < 2; ++iy)
                    for (int ix = 0; ix < 2; ++ix) {
                        double w = wl[il] * wa[ia] * wp[ip] * wy[iy] * wx[ix];
                        int x = (x0 + ix) % L1->w, y = (y0 + iy) % L1->h, p = (p0 + ip) % np;
                        for (int q = 0; q < 10; ++q)
                            acc[q] += w * mf_prefilter_lookup_value_(s, lv, x, y, a0 + ia, p, q);
                    }
    }
    for (int q = 0; q < 9; ++q)
        M[q] = acc[q];
    *magnitude = acc[9];
}

/* The same filter split into taps (the corner lobes) that the renderer shades one by one and sums
 * with their weights, instead of shading the one blended M.  split: a combination of
 * MF_PREFILTER_SPLIT_TEXEL (the four texels of the bilinear filter), MF_PREFILTER_SPLIT_LEVEL (the two
 * MIP levels) and MF_PREFILTER_SPLIT_VIEW (the four tabulated views): along a split axis each corner
 * is its own tap, along the others the entries are blended as by mf_prefilter_lookup.  Up to 32 taps
 * (all three split); tap k gets M[9 k .. 9 k + 8], magnitude mag[k] and weight w[k] (the taps'
 * weights sum to 1, a tap's M and magnitude are its normalised blend).  The shading
 * sum_k w[k] mag[k] integral D_{M_k} is linear in the corners' shading along the split axes, so two
 * texels whose lobes reflect opposite facets give the mean of their two highlights, where the
 * blended M gives one lobe between them (docs/prefilter.md, "Textures and the lookup").  Returns the
 * number of taps; a tap of weight 0 (the sample sits on a texel centre, an integer level or a tabulated
 * view) has M = 0 and magnitude 0: skip it. */
#define MF_PREFILTER_SPLIT_TEXEL 1
#define MF_PREFILTER_SPLIT_LEVEL 2
#define MF_PREFILTER_SPLIT_VIEW 4
static inline int mf_prefilter_lookup_taps(const mf_prefilter_lookup_levels *s, double u, double v, double lod,
                                           double theta, double phi, int split, double M[32 * 9], double mag[32],
                                           double w[32])
{
    const int np = s->n_phi;
    const mf_prefilter_lookup_cell_ c = mf_prefilter_lookup_cell(s, lod, theta, phi);
    const int a0 = c.a0, p0 = c.p0, l0 = c.l0;
    const double *wa = c.wa, *wp = c.wp, *wl = c.wl;
    int nx = split & MF_PREFILTER_SPLIT_TEXEL ? 4 : 1, nl = split & MF_PREFILTER_SPLIT_LEVEL ? 2 : 1,
        nv = split & MF_PREFILTER_SPLIT_VIEW ? 4 : 1, ntap = nx * nl * nv;
    double acc[32 * 10] = {0};
    for (int k = 0; k < ntap; ++k)
        w[k] = 0.0;
    for (int il = 0; il < 2; ++il) {
        int lv = l0 + il < s->nlev ? l0 + il : s->nlev - 1;
        const mf_prefilter_lookup_level *L1 = &s->lev[lv];
        int x0, y0;
        double wx[2], wy[2];
        mf_prefilter_lookup_texels_(L1, u, v, &x0, &y0, wx, wy);
        for (int ia = 0; ia < 2; ++ia)
            for (int ip = 0; ip < 2; ++ip)
                for (int iy = 0; iy < 2; ++iy)
                    for (int ix = 0; ix < 2; ++ix) {
                        double wt = wl[il] * wa[ia] * wp[ip] * wy[iy] * wx[ix];
                        int tx = nx > 1 ? 2 * iy + ix : 0, tl = nl > 1 ? il : 0, tv = nv > 1 ? 2 * ip + ia : 0;
                        int k = (tv * nl + tl) * nx + tx;
                        int x = (x0 + ix) % L1->w, y = (y0 + iy) % L1->h, p = (p0 + ip) % np;
                        w[k] += wt;
                        for (int q = 0; q < 10; ++q)
                            acc[10 * k + q] += wt * mf_prefilter_lookup_value_(s, lv, x, y, a0 + ia, p, q);
                    }
    }
    for (int k = 0; k < ntap; ++k) {
        double d = w[k];
        for (int q = 0; q < 9; ++q)
            M[9 * k + q] = d > 0.0 ? acc[10 * k + q] / d : 0.0;
        mag[k] = d > 0.0 ? acc[10 * k + 9] / d : 0.0;
    }
    return ntap;
}

/* A view wl in a texel's frame, moved up to the elevation of cos theta = MF_PREFILTER_COS_MIN at its
 * own azimuth when it lies below (azimuth 0 when it has none): the horizon rule of mf_prefilter.h. */
static inline mf_vec3 mf_prefilter_clamp_view(mf_vec3 wl)
{
    if (wl.z < MF_PREFILTER_COS_MIN) {
        double h = sqrt(wl.x * wl.x + wl.y * wl.y), c = MF_PREFILTER_COS_MIN, s = sqrt(1.0 - c * c);
        wl = h > 0.0 ? mf_vec3_make(wl.x / h * s, wl.y / h * s, c) : mf_vec3_make(s, 0.0, c);
    }
    return wl;
}

/* Per-texel LTC shading [Nahmias 2022, Sec. 4.1: "for each normal, we evaluate the view elevation
 * and use the standard technique from [HDHN16] to integrate over the light"]: the isotropic LTC of
 * table t (mf_ltc_table.h layout; field[0..4] the indices of minv_00, minv_20, minv_02, minv_22,
 * magnitude) at (alpha, the view's elevation in the texel frame), in the texel's frame (normal n,
 * a unit vector of the tangent frame; any rotation about n: the lobe is isotropic), integrated over
 * the polygon q[0..nq-1] (vertices relative to the shading point, tangent frame; two-sided), times
 * the table's magnitude.  A view below the texel's horizon is handled as by the prefilter
 * (mf_prefilter.h): its texel-frame cosine clamped to MF_PREFILTER_COS_MIN, azimuth kept.  The
 * polygon is clipped at the texel's horizon (by the LTC integral), not at the geometric one.
 * NaN if the lookup or the table's matrix fails. */
static inline double mf_prefilter_texel_ltc(const mf_table *t, const int field[5], mf_vec3 n, double alpha,
                                            mf_vec3 wo, const mf_vec3 *q, int nq)
{
    mf_frame f = mf_frame_from_normal(n);
    mf_vec3 wl = mf_prefilter_clamp_view(mf_frame_to_local(f, wo));
    mf_frame vf = mf_ltc_view_frame(wl);
    mf_vec3 p[MF_POLYGON_MAX_VERTICES];
    if (nq < 3 || nq > MF_POLYGON_MAX_VERTICES)
        return NAN;
    for (int k = 0; k < nq; ++k)
        p[k] = mf_frame_to_local(vf, mf_frame_to_local(f, q[k]));
    double par[2] = {sqrt(alpha), sqrt(fmax(0.0, 1.0 - fmin(1.0, wl.z)))}, rec[64];
    if (t->nfields > 64 || mf_table_lookup(t, par, rec) != MF_OK)
        return NAN;
    double in4[4] = {rec[field[0]], rec[field[1]], rec[field[2]], rec[field[3]]};
    mf_ltc ltc;
    if (mf_ltc_table_unpack(in4, &ltc) != MF_OK)
        return NAN;
    mf_polygon poly = mf_polygon_make(nq, p);
    return rec[field[4]] * mf_ltc_integrate_polygon(&ltc, &poly, MF_POLYGON_TWO_SIDED);
}

/* Lambert shading of one texel under a polygonal light of unit radiance, exactly: the integral over
 * the polygon q[0..nq-1] (vertices relative to the shading point, tangent frame; two-sided) of
 * max(0, n.wi) / pi over the directions above the geometric horizon, wi.z > 0 -- the one-texel
 * term of the prefilter's diffuse effective BRDF (mf_prefilter_mix with the "lambert" base: f cos =
 * max(0, n(q).wi) / pi for wi.z > 0, independent of the view) [Nahmias 2022, Eq. 2.36].  Closed
 * form: the polygon clipped to z >= 0 (Sutherland & Hodgman 1974; the plane passes through the
 * shading point, so the clipped polygon has the same geodesic edges), expressed in the texel's
 * frame (normal n, a unit vector with n.z > 0), then Lambert's formula, which clips at the
 * texel's horizon (mf_polygon_integrate_cosine) [Lambert 1760; Baum et al. 1989].  nq in
 * [3, MF_POLYGON_MAX_VERTICES - 1] (the clip adds at most one vertex); NaN otherwise; 0 when
 * nothing of the polygon lies above the geometric horizon. */
static inline double mf_prefilter_texel_lambert(mf_vec3 n, const mf_vec3 *q, int nq)
{
    if (nq < 3 || nq > MF_POLYGON_MAX_VERTICES - 1)
        return NAN;
    mf_vec3 c[MF_POLYGON_MAX_VERTICES];
    int m = 0;
    for (int i = 0; i < nq; ++i) {
        mf_vec3 a = q[i], b = q[i + 1 == nq ? 0 : i + 1];
        if (a.z >= 0.0)
            c[m++] = a;
        if ((a.z > 0.0 && b.z < 0.0) || (a.z < 0.0 && b.z > 0.0)) {
            double t = a.z / (a.z - b.z); /* in (0, 1), no cancellation: a.z and -b.z share a sign */
            c[m++] = mf_vec3_make(a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), 0.0);
        }
    }
    if (m < 3)
        return 0.0;
    mf_frame f = mf_frame_from_normal(n);
    for (int i = 0; i < m; ++i)
        c[i] = mf_frame_to_local(f, c[i]);
    mf_polygon poly = mf_polygon_make(m, c);
    return mf_polygon_integrate_cosine(&poly, MF_POLYGON_TWO_SIDED);
}

#ifdef __cplusplus
}
#endif
#endif /* MF_PREFILTER_LOOKUP_H */
