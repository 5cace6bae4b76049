/*
 * render_prefilter_scenes.c -- CPU renders of the two evaluation scenes of Nahmias 2022, Ch. 4.1.3
 * (Fig. 4.2): the normal map tiled 5 x 5 on a plane under a quad light, seen from a near-normal
 * view (SCENE 1) and from a grazing view with the light facing the camera (SCENE 2), at several
 * camera distances; each method's image, error map and mean squared error against the ground truth
 * (issue 13, "Ground truth and evaluation").
 *
 *   render_prefilter_scenes --prefilter DIR [--map NORMALMAP] [--ltc-table FILE] [--size N] [--tiles T]
 *       [--distances D,D,...] [--light-half H] [--mc-samples K] [--images 0|1] [--seed S] [--out DIR] [--csv FILE]
 *       [--split none|LIST] [--aniso N] [--oracle STRIDE] [--lobes 1|2]
 * Run from the source directory: the default --ltc-table is tests/data/reference/ltc_code_ggx_64.csv
 * (Heitz et al. 2016's GGX table, the one the thesis shades with); the map is the manifest's (a path
 * relative to where mfkit prefilter ran) unless --map; it is decoded as mfkit prefilter's defaults do.
 *
 * Scene (world: the plane z = 0 over [-2.5, 2.5]^2 carrying the map repeated T x T times, default
 * T = max(5, 640 / W): the thesis tiled its 128 x 128 maps 5 x 5, 640 texels across; texture
 * u = x T / 5, v = -y T / 5, so the tangent frame is the world's: x = +column, y = up the image, z = n;
 * the thesis gives the setup only in outline, so the numbers are ours):
 *   SCENE 1 "normal"   camera at (0.0123, 0.0371, d) looking straight down (off the texel grid's
 *                      symmetry); light: a square of half side H
 *                      (default 1) at height 3, facing down, centred above the origin;
 *   SCENE 2 "grazing"  camera at d (0, -cos 20 deg, sin 20 deg) looking at the origin; light: the
 *                      same square centred at 4 (0, cos 20 deg, sin 20 deg), facing the origin (the
 *                      mirror direction of the view at the origin).
 * Pinhole camera, square image of N x N pixels (default 128), half field of view atan(1/2) (the
 * thesis' frustum x = 1, n = 2): SCENE 1's pixels cover 2^lod texels, lod growing by 1 per doubling
 * of d; default distances d = 5 N / (T W) 2^k, k = -1 .. 4, i.e. SCENE 1 at lod -1 .. 4 (the thesis
 * magnifies its far images by nearest neighbour; ours are written at render size).  The light
 * is not rendered and occludes nothing; radiance 1, specular only, Fresnel 1.
 *
 * Per pixel: the level of detail lod = log2 of the longer of the pixel's two projected edges in
 * level-0 texels (the GL rule, from the plane hits of the neighbouring pixel centres), and
 *   truth     supersampled: S x S stratified sub-pixel points (S = max(4, ceil(2^lod)) <= 32, fixed
 *             seed), each point-sampling its level-0 texel and shading it with the per-texel LTC
 *             [Nahmias 2022, Sec. 4.1: "for each normal, we evaluate the view elevation and use the
 *             standard technique from [HDHN16]"]: the isotropic GGX LTC of the table (alpha of the
 *             prefilter run) at the view's elevation in the texel frame, rotated to the texel's
 *             normal, integrated over the quad (mf_ltc_integrate_polygon), times the table's
 *             magnitude; views below the texel's horizon as in the prefilter (cos clamped to
 *             MF_PREFILTER_COS_MIN, azimuth kept).  This is the thesis' ground truth;
 *   truth_mc  (--mc-samples K > 0) the same sub-samples with the exact GGX integral instead
 *             (the prefilter's effective-BRDF definition, mf_prefilter_mix of the texel's normal),
 *             by Monte Carlo over the light's area, m x m jittered points per sub-sample with
 *             m = ceil(sqrt(16 K / S^2)) (about 16 K points a pixel; default K = 16): the
 *             reference the lobes were fitted to;
 *   mfkit     the prefiltered lobes (mf_prefilter_lookup: trilinear over MIP, bilinear over the view
 *             axes), polygon rotated by -phi, magnitude x LTC integral; at lod < 1 blended linearly
 *             (weight lod) with level 0, the bilinear filter of the four nearest texels' per-texel LTC
 *             shading (docs/prefilter.md: level 0 is shaded with the base's isotropic table);
 *   mfkit_taps the same lobes through the split lookup (mfpfLookupTap, mf_prefilter_lookup_taps): the
 *             eight texel taps of the trilinear filter (four texels at each of two MIP levels, views
 *             blended in M) each shaded and summed with their weights; --split chooses the axes split
 *             (a comma-separated list of texel, level, view; none: mf_prefilter_lookup), for the
 *             per-cause measurements of docs/prefilter_log.md ("Lookup: where the lobes lost, per
 *             cause");
 *   naive     the trilinear MIP filter of the box-averaged normals, normalised, shaded with the
 *             per-texel LTC at the base alpha [Nahmias 2022, Sec. 4.1, the "naive baseline"];
 *   toksvig   the same normal, alpha' = sqrt(alpha^2 + 2 (1 - |n|) / |n|), |n| the filtered normal's
 *             length (mf_toksvig_beckmann_alpha; Toksvig 2005), per-texel LTC at alpha';
 *   leadr     trilinear MIP filter of the LEAN/LEADR moments (mean slopes and second moments,
 *             Olano & Baker 2010, Eq. 3-6), covariance plus alpha^2 / 2 per axis, mfkit's LEADR
 *             specular [Dupuy 2013, Eq. 17], integrated over the light's area by Monte Carlo with
 *             8 x 8 jittered points per pixel.
 * --aniso N (default 1, off): every method filtered anisotropically as a texture unit does: n =
 * min(N, ceil(longer / shorter projected edge)) lookups spread along the pixel's longer edge, each at the
 * level of detail of longer edge / n, averaged (naive, Toksvig: the filtered normal; LEADR: the moments;
 * mfkit: M and magnitude; mfkit_taps and mfkit's level 0: the shading).
 * --lobes 2: mfkit and mfkit_taps shade the two-lobe table instead (mfkit prefilter --lobes 2: DIR/lobe_a and
 * DIR/lobe_b looked up the same way, their shadings summed, as a renderer calls mfpfLookup or mfpfLookupTap
 * once per half's textures); the other methods are unchanged.
 * --oracle STRIDE (0: off): every STRIDE-th pixel in x and y also gets one lobe fitted to its own
 * footprint at its own view (shade_oracle: no interpolation of any kind), and
 * DIR/prefilter_scenes_oracle.csv gets every method's MSE against truth on those pixels.
 * MSE over the pixels that see the plane, per scene, distance and method, against truth and
 * (with --mc-samples) truth_mc.  Images (--images 1): DIR/<scene>_d<d>_<method>.exr (float) and
 * .png (value / the truth's largest value, gamma 1/2.2), error maps <scene>_d<d>_<method>_err.png
 * (|method - truth| / (0.1 x the truth's largest value), clamped).  CSV (first line the provenance
 * header): scene,distance,pixels,mean_lod,method,mse,rel_rms,mse_mc,mean_value.
 */
#include "mfkit/mfkit.h"
#include "mfkit/fit/mf_image_oiio.h"
#include "mfkit/fit/mf_ltcfit_aniso.h"
#include "mfkit/fit/mf_prefilter.h"
#include "mfkit/fit/mf_prefilter_lookup.h"
#include "mfkit/io/mf_image.h"
#include "mfkit/io/mf_ltc_reference.h"
#include "mfkit/io/mf_table_io.h"

#include "study_header.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define PROG "render_prefilter_scenes"
#define MAXD 16
#define NMETH 7
enum { R_TRUTH, R_TRUTH_MC, R_MFKIT, R_NAIVE, R_TOKSVIG, R_LEADR, R_MFKIT_TAPS };
static const char *const k_meth[NMETH] = {"truth", "truth_mc", "mfkit", "naive", "toksvig", "leadr", "mfkit_taps"};

/* ---- small helpers ------------------------------------------------------------------------------- */

static int die(const char *fmt, const char *a, const char *b)
{
    fprintf(stderr, PROG ": ");
    fprintf(stderr, fmt, a, b);
    fprintf(stderr, "\n");
    return 2;
}

static mf_vec3 v3(double x, double y, double z) { return mf_vec3_make(x, y, z); }

/* ---- the isotropic LTC table (per-texel shading) ------------------------------------------------ */

static mf_table g_tab;
static int g_field[5];

static int load_table(const char *path)
{
    char msg[1024] = "";
    mf_table_format fmt = mf_table_format_from_path(path);
    mf_status st = fmt == MF_TABLE_FORMAT_CSV ? mf_ltc_reference_read_csv(path, &g_tab, msg, sizeof msg)
                                              : mf_table_read(path, &g_tab, NULL, msg, sizeof msg);
    if (st != MF_OK) {
        fprintf(stderr, PROG ": --ltc-table %s: %s\n", path, msg[0] ? msg : mf_status_str(st));
        return 3;
    }
    int ok = g_tab.naxes == 2 && g_tab.axes[0].mapping == MF_AXIS_SQUARE &&
             g_tab.axes[1].mapping == MF_AXIS_ONE_MINUS_SQUARE;
    for (int k = 0; k < 5; ++k)
        ok = ok && (g_field[k] = mf_table_field(&g_tab, mf_ltc_table_fields[k])) >= 0;
    if (!ok) {
        fprintf(stderr, PROG ": --ltc-table %s: not an isotropic LTC table layout (mf_ltc_table.h)\n", path);
        return 3;
    }
    return 0;
}

static double shade_texel_ltc(mf_vec3 n, double alpha, mf_vec3 wo, const mf_vec3 *q)
{
    return mf_prefilter_texel_ltc(&g_tab, g_field, n, alpha, wo, q, 4);
}

/* ---- the map and its MIP pyramids ------------------------------------------------------------------- */

static int W, H, NL; /* map size, levels 0 .. NL - 1 of the pyramids */
static double g_tiles; /* the map repeats g_tiles x g_tiles times over the 5 x 5 plane */
static double *g_n;  /* level-0 unit normals */
/* pyramid of C channels per level: box averages of level 0 */
typedef struct { int c; int w[16], h[16]; double *d[16]; } pyramid;
static pyramid g_nrm, g_mom;

static void pyr_build(pyramid *p, int c, const double *base)
{
    p->c = c;
    p->w[0] = W, p->h[0] = H;
    p->d[0] = malloc(sizeof(double) * c * W * H);
    memcpy(p->d[0], base, sizeof(double) * c * W * H);
    for (int k = 1; k < NL; ++k) {
        int w = p->w[k - 1] > 1 ? p->w[k - 1] / 2 : 1, h = p->h[k - 1] > 1 ? p->h[k - 1] / 2 : 1;
        p->w[k] = w, p->h[k] = h;
        p->d[k] = calloc((size_t)c * w * h, sizeof(double));
        int fx = p->w[k - 1] / w, fy = p->h[k - 1] / h;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                for (int j = 0; j < fy; ++j)
                    for (int i = 0; i < fx; ++i)
                        for (int ch = 0; ch < c; ++ch)
                            p->d[k][(y * w + x) * c + ch] +=
                                p->d[k - 1][((y * fy + j) * p->w[k - 1] + x * fx + i) * c + ch] / (fx * fy);
    }
}

static int wrapi(int i, int n) { return ((i % n) + n) % n; }

static void pyr_bilinear(const pyramid *p, int k, double u, double v, double *out)
{
    int w = p->w[k], h = p->h[k];
    double xf = u * w - 0.5, yf = v * h - 0.5, x0 = floor(xf), y0 = floor(yf), fx = xf - x0, fy = yf - y0;
    for (int ch = 0; ch < p->c; ++ch)
        out[ch] = 0.0;
    for (int j = 0; j < 4; ++j) {
        int dx = j & 1, dy = j >> 1;
        double wt = (dx ? fx : 1.0 - fx) * (dy ? fy : 1.0 - fy);
        int x = wrapi((int)fmod(x0, w) + dx, w), y = wrapi((int)fmod(y0, h) + dy, h);
        for (int ch = 0; ch < p->c; ++ch)
            out[ch] += wt * p->d[k][(y * w + x) * p->c + ch];
    }
}

static void pyr_trilinear(const pyramid *p, double u, double v, double lod, double *out)
{
    double l = fmin(fmax(lod, 0.0), NL - 1.0), a[8], b[8];
    int l0 = (int)floor(l), l1 = l0 + 1 < NL ? l0 + 1 : l0;
    double f = l - l0;
    pyr_bilinear(p, l0, u, v, a);
    pyr_bilinear(p, l1, u, v, b);
    for (int ch = 0; ch < p->c; ++ch)
        out[ch] = (1.0 - f) * a[ch] + f * b[ch];
}

static const mf_vec3 *texel_normal(double u, double v)
{
    int x = wrapi((int)floor(fmod(u, 1.0) * W), W), y = wrapi((int)floor(fmod(v, 1.0) * H), H);
    return (const mf_vec3 *)(g_n + 3 * ((size_t)y * W + x));
}

/* ---- scenes -------------------------------------------------------------------------------------- */

typedef struct {
    const char *name;
    mf_vec3 cam, fwd, right, up;
    mf_vec3 quad[4]; /* world corners */
    mf_vec3 lc, ln;  /* light centre and unit normal (towards the scene) */
    double area;
} scene;

static void make_scene(scene *s, int which, double d, double hl)
{
    double e = 20.0 * MF_PI / 180.0;
    mf_vec3 e1, e2;
    if (which == 0) {
        s->name = "normal";
        s->cam = v3(0.0123, 0.0371, d); /* off the texel grid's symmetry: pixel centres do not land on texel centres */
        s->lc = v3(0.0, 0.0, 3.0), s->ln = v3(0.0, 0.0, -1.0);
        e1 = v3(1.0, 0.0, 0.0), e2 = v3(0.0, 1.0, 0.0);
    } else {
        s->name = "grazing";
        s->cam = v3(0.0, -d * cos(e), d * sin(e));
        s->lc = v3(0.0, 4.0 * cos(e), 4.0 * sin(e)), s->ln = v3(0.0, -cos(e), -sin(e));
        e1 = v3(1.0, 0.0, 0.0), e2 = v3(0.0, -sin(e), cos(e));
    }
    for (int k = 0; k < 4; ++k) {
        double a = (k == 0 || k == 3) ? -hl : hl, b = k < 2 ? -hl : hl;
        s->quad[k] = mf_vec3_add(s->lc, mf_vec3_add(mf_vec3_scale(e1, a), mf_vec3_scale(e2, b)));
    }
    s->area = 4.0 * hl * hl;
    s->fwd = which == 0 ? v3(0.0, 0.0, -1.0) : mf_vec3_normalize(mf_vec3_scale(s->cam, -1.0));
    s->right = mf_vec3_normalize(mf_vec3_cross(s->fwd, v3(0.0, 1.0, 0.0)));
    if (which == 1)
        s->right = v3(1.0, 0.0, 0.0);
    s->up = mf_vec3_cross(s->right, s->fwd);
}

/* plane hit of the ray through image point (px, py) (pixel units); 0 if it misses the 5 x 5 tiles
 * (*P is still the hit on the infinite plane when the ray goes down) */
static int hit(const scene *s, int N, double px, double py, mf_vec3 *P)
{
    double t = 0.5; /* tan of the half field of view */
    double sx = (2.0 * px / N - 1.0) * t, sy = (1.0 - 2.0 * py / N) * t;
    mf_vec3 dir = mf_vec3_add(s->fwd, mf_vec3_add(mf_vec3_scale(s->right, sx), mf_vec3_scale(s->up, sy)));
    if (!(dir.z < 0.0))
        return 0;
    double l = -s->cam.z / dir.z;
    *P = mf_vec3_add(s->cam, mf_vec3_scale(dir, l));
    return fabs(P->x) <= 2.5 && fabs(P->y) <= 2.5;
}

static void quad_rel(const scene *s, mf_vec3 P, mf_vec3 q[4])
{
    for (int k = 0; k < 4; ++k)
        q[k] = mf_vec3_sub(s->quad[k], P);
}

/* ---- per-pixel methods ---------------------------------------------------------------------------- */

static double g_alpha;
static int g_aniso = 1; /* --aniso N: every method filtered with up to N taps along the longer axis (1: off) */
static int g_an_n = 1;       /* this pixel's anisotropic taps (1: the isotropic filter) */
static double g_an_u, g_an_v; /* the pixel's longer projected edge in texture coordinates */

/* the anisotropic filter's tap i of g_an_n: offset along the longer edge */
static double an_t(int i) { return (i + 0.5) / g_an_n - 0.5; }
static int g_oracle; /* --oracle STRIDE: every STRIDE-th pixel in x and y also gets shade_oracle (0: off) */
static int g_split = MF_PREFILTER_SPLIT_TEXEL | MF_PREFILTER_SPLIT_LEVEL; /* mfkit_taps' axes (--split) */
static mf_prefilter_lookup_levels g_pf;
/* --lobes 2: the two-lobe tables (DIR/lobe_a, DIR/lobe_b); mfkit and mfkit_taps sum their shadings */
static int g_lobes = 1;
static mf_prefilter_lookup_levels g_pf2[2];
static mf_prefilter_mix *g_mix; /* one per level-0 texel (the exact GGX of that normal) */

/* pyr_trilinear averaged over the pixel's anisotropic taps (a texture unit's anisotropic filter) */
static void pyr_aniso(const pyramid *p, int nc, double u, double v, double lod, double *out)
{
    double t[8];
    for (int c = 0; c < nc; ++c)
        out[c] = 0.0;
    for (int ia = 0; ia < g_an_n; ++ia) {
        pyr_trilinear(p, u + an_t(ia) * g_an_u, v + an_t(ia) * g_an_v, lod, t);
        for (int c = 0; c < nc; ++c)
            out[c] += t[c] / g_an_n;
    }
}

static double shade_mfkit(const scene *s, mf_vec3 P, double u, double v, double lod, int split)
{
    mf_vec3 wo = mf_vec3_normalize(mf_vec3_sub(s->cam, P)), q[4];
    quad_rel(s, P, q);
    double s0 = 0.0, s1 = 0.0;
    if (lod < 1.0) /* level 0: bilinear filter of the per-texel shading (per anisotropic tap) */
        for (int ia = 0; ia < g_an_n; ++ia) {
            double ua = u + an_t(ia) * g_an_u, va = v + an_t(ia) * g_an_v;
            double xf = ua * W - 0.5, yf = va * H - 0.5, x0 = floor(xf), y0 = floor(yf), fx = xf - x0, fy = yf - y0;
            for (int j = 0; j < 4; ++j) {
                int dx = j & 1, dy = j >> 1;
                double wt = (dx ? fx : 1.0 - fx) * (dy ? fy : 1.0 - fy) / g_an_n;
                int x = wrapi((int)fmod(x0, W) + dx, W), y = wrapi((int)fmod(y0, H) + dy, H);
                const double *n = g_n + 3 * ((size_t)y * W + x);
                s0 += wt * shade_texel_ltc(v3(n[0], n[1], n[2]), g_alpha, wo, q);
            }
        }
    if (lod <= 0.0)
        return s0;
    double theta = acos(fmin(1.0, wo.z)), phi = atan2(wo.y, wo.x);
    double c = cos(phi), sn = sin(phi);
    mf_vec3 r[4];
    for (int k = 0; k < 4; ++k)
        r[k] = v3(c * q[k].x + sn * q[k].y, -sn * q[k].x + c * q[k].y, q[k].z);
    mf_polygon poly = mf_polygon_make(4, r);
    for (int h = 0; h < g_lobes; ++h) { /* the one-lobe table, or each half of the two-lobe table */
        const mf_prefilter_lookup_levels *pf = g_lobes == 2 ? &g_pf2[h] : &g_pf;
        if (!split) { /* mfpfLookup: one blended M (the anisotropic taps' mean, as a texture unit filters) */
            double M[9] = {0}, mag = 0.0;
            for (int ia = 0; ia < g_an_n; ++ia) {
                double Ma[9], ma;
                mf_prefilter_lookup(pf, u + an_t(ia) * g_an_u, v + an_t(ia) * g_an_v, lod, theta, phi, Ma, &ma);
                for (int k = 0; k < 9; ++k)
                    M[k] += Ma[k] / g_an_n;
                mag += ma / g_an_n;
            }
            mf_ltc ltc;
            if (mf_ltc_init(&ltc, mf_ltc_matrix_general(M)) != MF_OK)
                return NAN;
            s1 += mag * mf_ltc_integrate_polygon(&ltc, &poly, MF_POLYGON_TWO_SIDED);
        } else { /* mfpfLookupTap (split texel + level) or --split: the corner lobes shaded one by one */
            double M[32 * 9], mag[32], w[32];
            for (int ia = 0; ia < g_an_n; ++ia) {
                int nt = mf_prefilter_lookup_taps(pf, u + an_t(ia) * g_an_u, v + an_t(ia) * g_an_v, lod, theta, phi, split,
                                                  M, mag, w);
                for (int k = 0; k < nt; ++k) {
                    if (!(w[k] > 0.0))
                        continue;
                    mf_ltc ltc;
                    if (mf_ltc_init(&ltc, mf_ltc_matrix_general(M + 9 * k)) != MF_OK)
                        return NAN;
                    s1 += w[k] / g_an_n * mag[k] * mf_ltc_integrate_polygon(&ltc, &poly, MF_POLYGON_TWO_SIDED);
                }
            }
        }
    }
    return lod < 1.0 ? (1.0 - lod) * s0 + lod * s1 : s1;
}

/* --oracle: one lobe fitted to the pixel's own footprint (the level-0 texels its truth sub-samples hit,
 * weighted by their counts) at the pixel's own view, no interpolation of any kind: the single lobe's
 * own error, the floor of any lookup of one lobe per pixel.  The fit as the prefilter's rows do it
 * (normals rotated by -phi, mf_ltcfit_aniso_entry_fit_mirrored from the closed-form start, 4096
 * directions), the magnitude the texels' mean albedo over the lobe's mass above the horizon (the
 * prefilter's keep_albedo rule). */
static double shade_oracle(const scene *s, mf_vec3 P, const int *tex, int ntex)
{
    mf_vec3 wo = mf_vec3_normalize(mf_vec3_sub(s->cam, P)), q[4];
    quad_rel(s, P, q);
    double theta = acos(fmin(1.0, wo.z)), phi = atan2(wo.y, wo.x), c = cos(phi), sn = sin(phi);
    double *nr = malloc(sizeof(double) * 3 * (size_t)ntex), alb = 0.0;
    for (int k = 0; k < ntex; ++k) {
        const double *n = g_n + 3 * (size_t)tex[k];
        mf_result r;
        if (mf_prefilter_texel_albedo(g_alpha, n, wo, 0, &r) != MF_OK) {
            free(nr);
            return NAN;
        }
        alb += r.val / ntex;
        nr[3 * k] = c * n[0] + sn * n[1], nr[3 * k + 1] = -sn * n[0] + c * n[1], nr[3 * k + 2] = n[2];
    }
    mf_prefilter_mix mix;
    mf_brdf_params bp = {g_alpha, g_alpha};
    mf_ltcfit_aniso_options fo;
    mf_ltcfit_aniso_options_default(&fo);
    mf_ltcfit_aniso_entry e;
    mf_status st = mf_prefilter_mix_init(&mix, mf_brdf_model_find("ggx"), nr, ntex);
    free(nr);
    if (st != MF_OK)
        return NAN;
    st = mf_ltcfit_aniso_entry_fit_mirrored(&mix.model, bp, fmin(theta, MF_PREFILTER_THETA_MAX), 0, alb, 0.0, NULL,
                                            NULL, &fo, &e);
    mf_prefilter_mix_free(&mix);
    if (st != MF_OK)
        return NAN;
    double hm = 0.5 * (1.0 + e.m[8] / sqrt(e.m[6] * e.m[6] + e.m[7] * e.m[7] + e.m[8] * e.m[8]));
    mf_vec3 r[4];
    for (int k = 0; k < 4; ++k)
        r[k] = v3(c * q[k].x + sn * q[k].y, -sn * q[k].x + c * q[k].y, q[k].z);
    mf_polygon poly = mf_polygon_make(4, r);
    mf_ltc ltc;
    if (mf_ltc_init(&ltc, mf_ltc_matrix_general(e.m)) != MF_OK)
        return NAN;
    return alb / fmax(hm, MF_PREFILTER_HORIZON_MIN) * mf_ltc_integrate_polygon(&ltc, &poly, MF_POLYGON_TWO_SIDED);
}

static void shade_naive_toksvig(const scene *s, mf_vec3 P, double u, double v, double lod, double *naive,
                                double *toksvig)
{
    mf_vec3 wo = mf_vec3_normalize(mf_vec3_sub(s->cam, P)), q[4];
    quad_rel(s, P, q);
    double n[3];
    pyr_aniso(&g_nrm, 3, u, v, lod, n);
    double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    mf_vec3 nb = v3(n[0] / len, n[1] / len, n[2] / len);
    *naive = shade_texel_ltc(nb, g_alpha, wo, q);
    *toksvig = shade_texel_ltc(nb, mf_toksvig_beckmann_alpha(fmin(len, 1.0), g_alpha), wo, q);
}

/* a jittered point of the light, stratum (i, j) of m x m; returns wi and the area Jacobian */
static mf_vec3 light_point(const scene *s, mf_vec3 P, int i, int j, int m, mf_pcg32 *rng, double *jac)
{
    double a = ((i + mf_pcg32_next_double(rng)) / m), b = ((j + mf_pcg32_next_double(rng)) / m);
    mf_vec3 x = mf_vec3_add(mf_vec3_scale(s->quad[0], (1 - a) * (1 - b)),
                            mf_vec3_add(mf_vec3_scale(s->quad[1], a * (1 - b)),
                                        mf_vec3_add(mf_vec3_scale(s->quad[2], a * b), mf_vec3_scale(s->quad[3], (1 - a) * b))));
    mf_vec3 d = mf_vec3_sub(x, P);
    double r2 = mf_vec3_dot(d, d);
    mf_vec3 wi = mf_vec3_scale(d, 1.0 / sqrt(r2));
    *jac = s->area * fabs(mf_vec3_dot(wi, s->ln)) / r2 / (m * m);
    return wi;
}

static double shade_leadr(const scene *s, mf_vec3 P, double u, double v, double lod, mf_pcg32 *rng)
{
    mf_vec3 wo = mf_vec3_normalize(mf_vec3_sub(s->cam, P));
    double mo[5];
    pyr_aniso(&g_mom, 5, u, v, lod, mo);
    mf_gaussian_slopes g;
    g.mean_x = mo[0], g.mean_y = mo[1];
    g.var_x = mo[2] - mo[0] * mo[0] + 0.5 * g_alpha * g_alpha;
    g.var_y = mo[3] - mo[1] * mo[1] + 0.5 * g_alpha * g_alpha;
    g.cov_xy = mo[4] - mo[0] * mo[1];
    mf_fresnel fr;
    memset(&fr, 0, sizeof fr);
    fr.type = MF_FRESNEL_NONE;
    double sum = 0.0;
    for (int i = 0; i < 8; ++i)
        for (int j = 0; j < 8; ++j) {
            double jac;
            mf_vec3 wi = light_point(s, P, i, j, 8, rng, &jac);
            if (wi.z > 0.0)
                sum += mf_leadr_specular(&g, fr, wo, wi) * jac;
        }
    return sum;
}

/* ---- main --------------------------------------------------------------------------------------------- */

static int parse_list(const char *s, double *d, int *n)
{
    *n = 0;
    for (const char *p = s;;) {
        char *e;
        double x = strtod(p, &e);
        if (e == p || !(x > 0.05 && x <= 1e4) || *n >= MAXD)
            return -1;
        d[(*n)++] = x;
        if (!*e)
            return 0;
        if (*e != ',')
            return -1;
        p = e + 1;
    }
}

static int write_img(const char *path, const double *v, int N, double scale, int gamma)
{
    mf_image im = {N, N, 1, malloc(sizeof(float) * N * N)};
    for (int i = 0; i < N * N; ++i) {
        double x = v[i] * scale;
        if (gamma)
            x = pow(fmin(fmax(x, 0.0), 1.0), 1.0 / 2.2);
        im.pixels[i] = (float)x;
    }
    char msg[512];
    mf_status st = mf_image_write(path, &im, 0, msg, sizeof msg);
    free(im.pixels);
    if (st != MF_OK) {
        fprintf(stderr, PROG ": %s\n", msg);
        return 3;
    }
    return 0;
}

int main(int argc, char **argv)
{
    const char *pfdir = NULL, *table = "tests/data/reference/ltc_code_ggx_64.csv", *out = "prefilter_scenes",
               *csv = NULL, *dlist = NULL,
               *map_opt = NULL;
    int N = 128, mc = 16, images = 1;
    double hl = 1.0;
    long seed = 1;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *val = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            printf("usage: " PROG " --prefilter DIR [--map NORMALMAP] [--ltc-table FILE] [--size N] [--tiles T] [--distances D,D,...] "
                   "[--light-half H] [--mc-samples K] [--images 0|1] [--seed S] [--out DIR] [--csv FILE] [--split none|LIST] "
                   "[--aniso N] [--oracle STRIDE] [--lobes 1|2]\n");
            return 0;
        }
        if (!val)
            return die("%s: needs a value%s", a, "");
        ++i;
        char *e = NULL;
        if (!strcmp(a, "--prefilter"))
            pfdir = val;
        else if (!strcmp(a, "--map"))
            map_opt = val;
        else if (!strcmp(a, "--ltc-table"))
            table = val;
        else if (!strcmp(a, "--out"))
            out = val;
        else if (!strcmp(a, "--csv"))
            csv = val;
        else if (!strcmp(a, "--distances"))
            dlist = val;
        else if (!strcmp(a, "--aniso")) {
            g_aniso = (int)strtol(val, &e, 10);
            if (*e || g_aniso < 1 || g_aniso > 64)
                return die("--aniso %s: expected a tap count in [1, 64] (1: off)%s", val, "");
        } else if (!strcmp(a, "--lobes")) {
            g_lobes = (int)strtol(val, &e, 10);
            if (*e || g_lobes < 1 || g_lobes > 2)
                return die("--lobes %s: expected 1 or 2 (2: the two-lobe tables DIR/lobe_a and lobe_b)%s", val, "");
        } else if (!strcmp(a, "--oracle")) {
            g_oracle = (int)strtol(val, &e, 10);
            if (*e || g_oracle < 0 || g_oracle > 4096)
                return die("--oracle %s: expected a pixel stride in [0, 4096] (0: off)%s", val, "");
        } else if (!strcmp(a, "--split")) {
            g_split = 0;
            for (const char *t = val; *t;) {
                size_t n = strcspn(t, ",");
                if (n == 5 && !strncmp(t, "texel", 5))
                    g_split |= MF_PREFILTER_SPLIT_TEXEL;
                else if (n == 5 && !strncmp(t, "level", 5))
                    g_split |= MF_PREFILTER_SPLIT_LEVEL;
                else if (n == 4 && !strncmp(t, "view", 4))
                    g_split |= MF_PREFILTER_SPLIT_VIEW;
                else if (!(n == 4 && !strncmp(t, "none", 4)))
                    return die("--split %s: expected none or a comma-separated list of texel, level, view%s", val, "");
                t += n + (t[n] == ',');
            }
        }
        else if (!strcmp(a, "--tiles")) {
            g_tiles = strtod(val, &e);
            if (*e || !(g_tiles >= 1.0 && g_tiles <= 4096.0))
                return die("--tiles %s: expected a repeat count in [1, 4096]%s", val, "");
        } else if (!strcmp(a, "--size")) {
            N = (int)strtol(val, &e, 10);
            if (*e || N < 8 || N > 4096)
                return die("--size %s: expected an integer in [8, 4096]%s", val, "");
        } else if (!strcmp(a, "--mc-samples")) {
            mc = (int)strtol(val, &e, 10);
            if (*e || mc < 0 || mc > 4096)
                return die("--mc-samples %s: expected an integer in [0, 4096]%s", val, "");
        } else if (!strcmp(a, "--images")) {
            images = (int)strtol(val, &e, 10);
            if (*e || (images != 0 && images != 1))
                return die("--images %s: expected 0 or 1%s", val, "");
        } else if (!strcmp(a, "--seed")) {
            seed = strtol(val, &e, 10);
            if (*e || seed < 0)
                return die("--seed %s: expected a non-negative integer%s", val, "");
        } else if (!strcmp(a, "--light-half")) {
            hl = strtod(val, &e);
            if (*e || !(hl > 0.0 && hl <= 1.5))
                return die("--light-half %s: expected a half side in (0, 1.5] (the grazing light must stay above "
                           "the plane)%s", val, "");
        } else
            return die("%s: unknown option%s", a, "");
    }
    if (!pfdir)
        return die("--prefilter DIR is required (an output directory of mfkit prefilter)%s%s", "", "");
    mf_image_set_backend(mf_image_oiio_backend());
    if (load_table(table))
        return 3;

    /* the manifest: map and alpha */
    char path[4400], map[4096];
    size_t jl;
    snprintf(path, sizeof path, "%s/prefilter.json", pfdir);
    char msg[8800];
    char *js = mf_prefilter_read_file(path, &jl, msg, sizeof msg);
    if (!js)
        return die("%s%s", msg, ""), 3;
    const char *key = "\"base_brdf\": {\"model\": \"ggx\", \"alpha\": ";
    const char *ap = strstr(js, key);
    if (!mf_prefilter_json_string(js, "map", map, sizeof map) || !ap || sscanf(ap + strlen(key), "%lf", &g_alpha) != 1 ||
        !(g_alpha > 0.0 && g_alpha <= 1.0)) {
        free(js);
        return die("%s: not a manifest of mfkit prefilter with a GGX base%s", path, "");
    }
    free(js);
    if (map_opt)
        snprintf(map, sizeof map, "%s", map_opt);

    /* the map, decoded as mfkit prefilter's defaults do (8/16-bit: unorm, float: raw; green up) */
    mf_image img;
    mf_image_info info;
    if (mf_image_read_ex(map, &img, NULL, &info, msg, sizeof msg) != MF_OK)
        return die("%s%s", msg, ""), 3;
    int unorm = !strncmp(info.pixel_type, "uint", 4);
    W = img.width, H = img.height;
    if ((img.channels != 3 && img.channels != 4) || (W & (W - 1)) || (H & (H - 1)))
        return die("%s: expected a 3- or 4-channel map with power-of-two sides%s", map, "");
    g_n = malloc(sizeof(double) * 3 * W * H);
    double *mom = malloc(sizeof(double) * 5 * W * H);
    for (int t = 0; t < W * H; ++t) {
        double n[3];
        for (int c = 0; c < 3; ++c)
            n[c] = unorm ? 2.0 * img.pixels[t * img.channels + c] - 1.0 : img.pixels[t * img.channels + c];
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(l > 0.5 && l < 1.5) || !(n[2] > 0.0))
            return die("%s: a texel is not a unit normal with n.z > 0%s", map, "");
        for (int c = 0; c < 3; ++c)
            g_n[3 * t + c] = n[c] / l;
        double px = -g_n[3 * t] / g_n[3 * t + 2], py = -g_n[3 * t + 1] / g_n[3 * t + 2];
        mom[5 * t] = px, mom[5 * t + 1] = py, mom[5 * t + 2] = px * px, mom[5 * t + 3] = py * py,
        mom[5 * t + 4] = px * py;
    }
    mf_image_free(&img);
    mf_image_info_free(&info);
    if (!(g_tiles > 0.0))
        g_tiles = fmax(5.0, 640.0 / W);
    double dist[MAXD];
    int nd = 0;
    if (dlist) {
        if (parse_list(dlist, dist, &nd) != 0)
            return die("--distances %s: expected 1 to 16 comma-separated distances in (0.05, 1e4]%s", dlist, "");
    } else /* SCENE 1's centre pixel covers 2^lod texels, lod = -1, 0, ..., 4 */
        for (nd = 0; nd < 6; ++nd)
            dist[nd] = 5.0 * N / (g_tiles * W) * ldexp(1.0, nd - 1);
    NL = 1;
    while ((W >> (NL - 1)) > 1 || (H >> (NL - 1)) > 1)
        ++NL;
    pyr_build(&g_nrm, 3, g_n);
    pyr_build(&g_mom, 5, mom);
    free(mom);

    /* the prefiltered levels: the one-lobe table, with --lobes 2 also its halves */
    static mf_prefilter_lookup_level lev[3][16];
    for (int t = 0; t < (g_lobes == 2 ? 3 : 1); ++t) {
        char tdir[4200];
        snprintf(tdir, sizeof tdir, t ? "%s/lobe_%c" : "%s", pfdir, "ab"[t ? t - 1 : 0]);
        mf_prefilter_lookup_levels *pf = t ? &g_pf2[t - 1] : &g_pf;
        int nlev = 0, nt = 0, np = 0;
        for (int k = 1; k < NL && k <= 16; ++k) {
            long d[6], dm[4];
            snprintf(path, sizeof path, "%s/ltc_mip%d.npy", tdir, k);
            float *m = mf_prefilter_read_npy(path, 6, d, msg, sizeof msg), *g = NULL;
            if (m) { /* else the message names the matrices' file */
                snprintf(path, sizeof path, "%s/magnitude_mip%d.npy", tdir, k);
                g = mf_prefilter_read_npy(path, 4, dm, msg, sizeof msg);
            }
            if (!m || !g || d[0] != (H >> k ? H >> k : 1) || d[1] != (W >> k ? W >> k : 1) || d[4] != 3 || d[5] != 3 ||
                (k > 1 && (d[2] != nt || d[3] != np)) || dm[0] != d[0] || dm[1] != d[1])
                return die("%s: missing or not the shape of level %s of the map", path, k == 1 ? "1" : ">1"), 3;
            nt = (int)d[2], np = (int)d[3];
            lev[t][nlev].w = (int)d[1], lev[t][nlev].h = (int)d[0], lev[t][nlev].m = m, lev[t][nlev].mag = g;
            ++nlev;
        }
        pf->nlev = nlev, pf->n_theta = nt, pf->n_phi = np, pf->lev = lev[t];
        if (nlev < 1 || nt < 2)
            return die("%s: no prefiltered level with >= 2 elevations%s", tdir, "");
        if (t && (nlev != g_pf.nlev || nt != g_pf.n_theta || np != g_pf.n_phi))
            return die("%s: not the levels and views of %s", tdir, pfdir);
    }

    /* exact GGX per texel for truth_mc */
    const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
    g_mix = calloc((size_t)W * H, sizeof *g_mix);
    if (mc > 0)
        for (int t = 0; t < W * H; ++t)
            if (mf_prefilter_mix_init(&g_mix[t], ggx, g_n + 3 * t, 1) != MF_OK)
                return die("%s: mixture of a texel failed%s", map, "");
    mf_brdf_params bp = mf_brdf_params_iso(g_alpha);

    if (mkdir(out, 0777) != 0 && errno != EEXIST)
        return die("--out %s: cannot create: %s", out, strerror(errno)), 3;
    char csvpath[4200];
    snprintf(csvpath, sizeof csvpath, "%s", csv ? csv : "");
    if (!csv)
        snprintf(csvpath, sizeof csvpath, "%s/prefilter_scenes.csv", out);
    char tmp[4300];
    snprintf(tmp, sizeof tmp, "%s.tmp", csvpath);
    FILE *fc = fopen(tmp, "w");
    if (!fc)
        return die("%s: cannot write: %s", tmp, strerror(errno)), 3;
    char sd[32];
    snprintf(sd, sizeof sd, "%ld", seed);
    study_write_header(fc, PROG, argc, argv, sd);
    fprintf(fc, "scene,distance,pixels,mean_lod,method,mse,rel_rms,mse_mc,mean_value\n");

    double *img_v[NMETH], *lodmap = malloc(sizeof(double) * N * N);
    unsigned char *mask = malloc((size_t)N * N), *omask = calloc((size_t)N * N, 1);
    double *oimg = calloc((size_t)N * N, sizeof(double));
    int *otex = malloc(sizeof(int) * 32 * 32);
    FILE *fo = NULL;
    if (g_oracle > 0) {
        snprintf(path, sizeof path, "%s/prefilter_scenes_oracle.csv", out);
        if (!(fo = fopen(path, "w")))
            return die("%s: %s", path, strerror(errno)), 3;
        study_write_header(fo, PROG, argc, argv, sd);
        fprintf(fo, "scene,distance,pixels,mean_lod,method,mse,mean_value\n");
    }
    for (int m = 0; m < NMETH; ++m)
        img_v[m] = malloc(sizeof(double) * N * N);
    int rc = 0;
    for (int sc = 0; sc < 2 && !rc; ++sc)
        for (int di = 0; di < nd && !rc; ++di) {
            scene S;
            make_scene(&S, sc, dist[di], hl);
            long npx = 0;
            for (int py = 0; py < N; ++py)
                for (int px = 0; px < N; ++px) {
                    size_t pi = (size_t)py * N + px;
                    for (int m = 0; m < NMETH; ++m)
                        img_v[m][pi] = 0.0;
                    mf_vec3 P, Px, Py;
                    mask[pi] = 0, omask[pi] = 0;
                    lodmap[pi] = 0.0;
                    if (!hit(&S, N, px + 0.5, py + 0.5, &P))
                        continue;
                    /* the footprint: plane hits one pixel over (ray differentials by finite differences) */
                    Px = Py = P; /* a neighbour ray that misses the plane (above the horizon): lod from the other */
                    (void)hit(&S, N, px + 1.5, py + 0.5, &Px);
                    (void)hit(&S, N, px + 0.5, py + 1.5, &Py);
                    double tu = g_tiles / 5.0; /* texture repeats per world unit */
                    double dx = hypot(Px.x - P.x, Px.y - P.y) * tu * W, dy = hypot(Py.x - P.x, Py.y - P.y) * tu * H;
                    double rho = fmax(dx, dy), lod = log2(rho);
                    mask[pi] = 1, lodmap[pi] = lod, ++npx;
                    double u = P.x * tu, v = -P.y * tu;
                    mf_pcg32 rng;
                    mf_pcg32_seed(&rng, (uint64_t)seed, ((uint64_t)sc * 64 + di) * 1048576u + pi);
                    /* supersampled truths */
                    int ss = (int)ceil(rho);
                    ss = ss < 4 ? 4 : ss > 32 ? 32 : ss;
                    double tl = 0.0, tm = 0.0;
                    long nsub = 0;
                    int ntex = 0;
                    for (int j = 0; j < ss; ++j)
                        for (int i = 0; i < ss; ++i) {
                            mf_vec3 Q;
                            double ox = (i + mf_pcg32_next_double(&rng)) / ss, oy = (j + mf_pcg32_next_double(&rng)) / ss;
                            if (!hit(&S, N, px + ox, py + oy, &Q))
                                continue;
                            mf_vec3 wo = mf_vec3_normalize(mf_vec3_sub(S.cam, Q)), q[4];
                            quad_rel(&S, Q, q);
                            const mf_vec3 *n = texel_normal(Q.x * tu, -Q.y * tu);
                            tl += shade_texel_ltc(*n, g_alpha, wo, q);
                            otex[ntex++] = (int)(n - (const mf_vec3 *)g_n);
                            if (mc > 0) {
                                size_t t = (size_t)(n - (const mf_vec3 *)g_n);
                                int m = (int)ceil(sqrt(16.0 * mc / (ss * ss))); /* >= 16 K points a pixel */
                                double sum = 0.0;
                                for (int a = 0; a < m; ++a)
                                    for (int b = 0; b < m; ++b) {
                                        double jac;
                                        mf_vec3 wi = light_point(&S, Q, a, b, m, &rng, &jac);
                                        if (wi.z > 0.0)
                                            sum += g_mix[t].model.eval_cos(&g_mix[t].model, &bp, wo, wi) * jac;
                                    }
                                tm += sum;
                            }
                            ++nsub;
                        }
                    if (nsub == 0) {
                        mask[pi] = 0, omask[pi] = 0, --npx;
                        continue;
                    }
                    img_v[R_TRUTH][pi] = tl / nsub;
                    img_v[R_TRUTH_MC][pi] = mc > 0 ? tm / nsub : 0.0;
                    /* --aniso: n taps along the longer edge, each at the level of detail of rho / n */
                    g_an_n = 1, g_an_u = g_an_v = 0.0;
                    double flod = lod;
                    if (g_aniso > 1) {
                        int na = (int)ceil(fmax(dx, dy) / fmax(fmin(dx, dy), 1e-9));
                        g_an_n = na < 1 ? 1 : na > g_aniso ? g_aniso : na;
                        mf_vec3 A = dx >= dy ? Px : Py;
                        g_an_u = (A.x - P.x) * tu, g_an_v = -(A.y - P.y) * tu;
                        flod = log2(rho / g_an_n);
                    }
                    img_v[R_MFKIT][pi] = shade_mfkit(&S, P, u, v, flod, 0);
                    img_v[R_MFKIT_TAPS][pi] = shade_mfkit(&S, P, u, v, flod, g_split);
                    shade_naive_toksvig(&S, P, u, v, flod, &img_v[R_NAIVE][pi], &img_v[R_TOKSVIG][pi]);
                    img_v[R_LEADR][pi] = shade_leadr(&S, P, u, v, flod, &rng);
                    omask[pi] = g_oracle > 0 && px % g_oracle == 0 && py % g_oracle == 0;
                    if (omask[pi])
                        oimg[pi] = shade_oracle(&S, P, otex, ntex);
                    for (int m = 0; m < NMETH; ++m)
                        if (!isfinite(img_v[m][pi])) {
                            fprintf(stderr, PROG ": %s d=%g pixel (%d, %d): non-finite %s\n", S.name, dist[di], px, py,
                                    k_meth[m]);
                            rc = 4;
                        }
                }
            /* statistics and files */
            double tmax = 0.0, lsum = 0.0, tmean = 0.0;
            for (int i = 0; i < N * N; ++i)
                if (mask[i])
                    tmax = fmax(tmax, img_v[R_TRUTH][i]), lsum += lodmap[i], tmean += img_v[R_TRUTH][i];
            tmean /= npx > 0 ? npx : 1;
            for (int m = 0; m < NMETH && !rc; ++m) {
                if (m == R_TRUTH_MC && mc == 0)
                    continue;
                double e = 0.0, emc = 0.0, mv = 0.0;
                for (int i = 0; i < N * N; ++i)
                    if (mask[i]) {
                        double a = img_v[m][i] - img_v[R_TRUTH][i], b = img_v[m][i] - img_v[R_TRUTH_MC][i];
                        e += a * a, emc += b * b, mv += img_v[m][i];
                    }
                double n1 = npx > 0 ? (double)npx : 1.0;
                fprintf(fc, "%s,%g,%ld,%.6f,%s,%.9g,%.9g,", S.name, dist[di], npx, lsum / n1, k_meth[m], e / n1,
                        tmean > 0 ? sqrt(e / n1) / tmean : 0.0);
                if (mc > 0)
                    fprintf(fc, "%.9g", emc / n1);
                else
                    fprintf(fc, "nan");
                fprintf(fc, ",%.9g\n", mv / n1);
                if (images) {
                    char base[4300];
                    snprintf(base, sizeof base, "%s/%s_d%g_%s", out, S.name, dist[di], k_meth[m]);
                    snprintf(path, sizeof path, "%s.exr", base);
                    rc = write_img(path, img_v[m], N, 1.0, 0);
                    snprintf(path, sizeof path, "%s.png", base);
                    if (!rc)
                        rc = write_img(path, img_v[m], N, tmax > 0 ? 1.0 / tmax : 1.0, 1);
                    if (!rc && m != R_TRUTH) {
                        double *err = malloc(sizeof(double) * N * N);
                        for (int i = 0; i < N * N; ++i)
                            err[i] = mask[i] ? fabs(img_v[m][i] - img_v[R_TRUTH][i]) : 0.0;
                        snprintf(path, sizeof path, "%s_err.png", base);
                        rc = write_img(path, err, N, tmax > 0 ? 10.0 / tmax : 1.0, 0);
                        if (!rc) {
                            for (int i = 0; i < N * N; ++i)
                                if (!mask[i])
                                    err[i] = 0.0;
                            snprintf(path, sizeof path, "%s_err.exr", base);
                            rc = write_img(path, err, N, 1.0, 0);
                        }
                        free(err);
                    }
                }
            }
            if (fo) { /* every method on the oracle's pixels, against truth */
                long no = 0;
                double ol = 0.0;
                for (int i = 0; i < N * N; ++i)
                    if (omask[i] && mask[i])
                        ++no, ol += lodmap[i];
                for (int m = 0; m <= NMETH; ++m) {
                    if (m == R_TRUTH || (m == R_TRUTH_MC && mc == 0))
                        continue;
                    const double *im = m < NMETH ? img_v[m] : oimg;
                    double e = 0.0, mv = 0.0;
                    for (int i = 0; i < N * N; ++i)
                        if (omask[i] && mask[i]) {
                            double a = im[i] - img_v[R_TRUTH][i];
                            e += a * a, mv += im[i];
                        }
                    double n1 = no > 0 ? (double)no : 1.0;
                    fprintf(fo, "%s,%g,%ld,%.6f,%s,%.9g,%.9g\n", S.name, dist[di], no, ol / n1,
                            m < NMETH ? k_meth[m] : "oracle", e / n1, mv / n1);
                }
            }
            fprintf(stderr, PROG ": %s d=%g: %ld plane pixels, mean lod %.2f\n", S.name, dist[di], npx,
                    lsum / (npx > 0 ? npx : 1));
        }
    if (fclose(fc) != 0 && !rc)
        rc = 3;
    if (!rc && rename(tmp, csvpath) != 0)
        rc = 3;
    if (rc)
        remove(tmp);
    else
        printf("wrote %s\n", csvpath);
    for (int m = 0; m < NMETH; ++m)
        free(img_v[m]);
    free(lodmap), free(mask), free(omask), free(oimg), free(otex);
    if (fo && fclose(fo) != 0 && !rc)
        rc = 3;
    if (mc > 0)
        for (int t = 0; t < W * H; ++t)
            mf_prefilter_mix_free(&g_mix[t]);
    free(g_mix);
    for (int t = 0; t < (g_lobes == 2 ? 3 : 1); ++t)
        for (int k = 0; k < (t ? g_pf2[t - 1].nlev : g_pf.nlev); ++k)
            free((void *)lev[t][k].m), free((void *)lev[t][k].mag);
    for (int k = 0; k < NL; ++k)
        free(g_nrm.d[k]), free(g_mom.d[k]);
    free(g_n);
    mf_table_free(&g_tab);
    return rc;
}
