/*
 * study_prefilter_cell.c -- one `prefilter-eval` record taken apart (issue 13, "Ground truth and
 * evaluation"; docs/prefilter_log.md, "Where the lost eval cells come from"): for one footprint (level
 * L, texel (x, y)) and one tabulated view (i_theta, i_phi) of a `mfkit prefilter` output, in the
 * view-azimuth-aligned frame prefilter-eval uses, and for square lights of half side h centred on
 * the view's mirror direction (elevation clamped to 75 deg, as prefilter-eval and the fit's ladder
 * place them), the shading of
 *   truth    the footprint's effective BRDF (mf_prefilter_mix, every texel) by Monte Carlo over the
 *            light (--samples points, even: half uniform on the light's area, half from the
 *            mixture, balance heuristic, as prefilter-eval);
 *   stored   the stored lobe: magnitude x the LTC integral (ltc_mip<L>.npy, magnitude_mip<L>.npy);
 *   lookup   the lobe of the C twin of the GLSL lookup (mf_prefilter_lookup) at the texel's centre,
 *            lod L and the tabulated view: whether the table's filter returns the stored lobe;
 *   albedo   the stored lobe with the magnitude set to the stored albedo (albedo_mip<L>.npy) instead
 *            of the albedo over the lobe's mass above the horizon: whether the magnitude matters;
 *   fresh    a lobe fitted here, exactly at this view, from the closed-form start
 *            (mf_ltcfit_aniso_entry_fit_mirrored with the prefilter's options: 4096 directions,
 *            100 iterations, seed 1, the ladder at the base's alpha; y-mirror symmetry held where
 *            the footprint's normals are y-mirror symmetric on the 3/255 grid, snapped pairwise):
 *            whether the stored lobe is the fit's own answer at this view or a product of the
 *            warm-start chain and the continuity rule;
 *   two      two lobes instead of one, fitted fresh at this view (what `mfkit prefilter --lobes 2` stores
 *            comes from its chains instead): the footprint's normals split in two by the prefilter's
 *            2-means (mf_prefilter_split_two), each half's mixture fitted at the view as
 *            `fresh` is (without the mirror symmetry), with the magnitude of its own albedo over its
 *            horizon mass, the two shadings weighted by the halves' texel counts;
 *   naive, toksvig  the baselines of prefilter-eval, on the same light points.
 * Also the smallest texel-frame view cosine (the below-horizon clamp acts under 0.001) and, with
 * --grid STEP, a 21 x 21 map of the truth's f cos over the plane of the lights (STEP apart, the
 * rows along the light's elevation axis), to see where the effective BRDF puts its energy.
 *
 *   study_prefilter_cell --prefilter DIR [--map NORMALMAP] [--level L] [--texel X,Y] [--view I,J]
 *       [--lights H,H,...] [--samples N] [--grid STEP]
 * Run from the directory mfkit prefilter ran in (the manifest's map path is relative to it) or give
 * --map.  Unorm maps (8/16-bit) are decoded as mfkit prefilter's defaults do (green up).
 */
#include "mfkit/fit/mf_image_oiio.h"
#include "mfkit/fit/mf_ltcfit_aniso.h"
#include "mfkit/fit/mf_prefilter.h"
#include "mfkit/fit/mf_prefilter_lookup.h"
#include "mfkit/io/mf_image.h"
#include "mfkit/mf_brdf.h"
#include "mfkit/mf_ltc.h"
#include "mfkit/mf_moments.h"
#include "mfkit/mf_polygon.h"
#include "mfkit/mf_rng.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define CELL_MAX_LIGHTS 16
#define CELL_LIGHT_MAX_ELEV (75.0 * MF_PI / 180.0)

static int usage(void)
{
    fprintf(stderr, "usage: study_prefilter_cell --prefilter DIR [--map NORMALMAP] [--level L] [--texel X,Y] "
                    "[--view I,J] [--lights H,H,...] [--samples N] [--grid STEP]\n");
    return 2;
}

/* The light of prefilter-eval: a square of half side h at distance 1 facing the origin, centred on
 * the mirror direction of the view (sin theta, 0, cos theta), its elevation clamped to 75 deg. */
static void light_frame(double theta, mf_vec3 *c, mf_vec3 *e1, mf_vec3 *e2)
{
    double tl = theta < CELL_LIGHT_MAX_ELEV ? theta : CELL_LIGHT_MAX_ELEV;
    *c = mf_vec3_make(-sin(tl), 0.0, cos(tl));
    *e1 = mf_vec3_make(cos(tl), 0.0, sin(tl));
    *e2 = mf_vec3_make(0.0, 1.0, 0.0);
}

static mf_vec3 light_point(mf_vec3 c, mf_vec3 e1, mf_vec3 e2, double a, double b)
{
    return mf_vec3_make(c.x + a * e1.x + b * e2.x, c.y + a * e1.y + b * e2.y, c.z + a * e1.z + b * e2.z);
}

static double lobe_shading(const double m[9], double magnitude, double theta, double h)
{
    mf_vec3 c, e1, e2, v[4];
    light_frame(theta, &c, &e1, &e2);
    for (int k = 0; k < 4; ++k)
        v[k] = light_point(c, e1, e2, (k == 0 || k == 3) ? -h : h, k < 2 ? -h : h);
    mf_polygon poly = mf_polygon_make(4, v);
    mf_mat3 M;
    for (int i = 0; i < 9; ++i)
        M.m[i / 3][i % 3] = m[i];
    mf_ltc ltc;
    if (mf_ltc_init(&ltc, M) != MF_OK)
        return NAN;
    return magnitude * mf_ltc_integrate_polygon(&ltc, &poly, MF_POLYGON_TWO_SIDED);
}

/* The lobe's mass above the horizon, (1 + n.z) / 2 with n = M^T z / |M^T z| (mf_prefilter.c). */
static double horizon_mass(const double m[9])
{
    return 0.5 * (1.0 + m[8] / sqrt(m[6] * m[6] + m[7] * m[7] + m[8] * m[8]));
}

/* truth, naive and Toksvig on the same points and weights (prefilter-eval's estimator: half uniform on
 * the light, half from the footprint's mixture, mf_prefilter_quad_mis_sample). */
static void mc_shading(mf_prefilter_mix *truth, mf_prefilter_mix *naive, double alpha, double alpha_t, double theta,
                       double h, int samples, double out[3])
{
    mf_prefilter_quad q;
    light_frame(theta, &q.c, &q.e1, &q.e2);
    q.h = h;
    mf_vec3 wo = mf_vec3_make(sin(theta), 0.0, cos(theta));
    mf_brdf_params p = mf_brdf_params_iso(alpha), pt = mf_brdf_params_iso(alpha_t);
    mf_pcg32 rng;
    mf_pcg32_seed(&rng, 1, 0);
    double s[3] = {0, 0, 0};
    for (int i = 0; i < samples; ++i) {
        double u[2] = {mf_pcg32_next_double(&rng), mf_pcg32_next_double(&rng)}, f;
        mf_vec3 wi;
        double w = mf_prefilter_quad_mis_sample(truth, &p, wo, &q, i & 1, u, &wi, &f);
        if (!(w > 0.0))
            continue;
        s[0] += f * w;
        s[1] += naive->model.eval_cos(&naive->model, &p, wo, wi) * w;
        s[2] += naive->model.eval_cos(&naive->model, &pt, wo, wi) * w;
    }
    for (int k = 0; k < 3; ++k)
        out[k] = s[k] / samples;
}

/* y-mirror symmetry on the 3/255 grid (mf_prefilter.h, MF_PREFILTER_MIRROR_TOL_NORMAL): every normal
 * has a partner (x, -y, z) within the tolerance; then each pair is snapped to an exactly symmetric
 * pair (normals on the mirror plane get y = 0).  Returns 1 (snapped) or 0 (left as is). */
static int mirror_snap_pairs(double *n, int count)
{
    const double tol = MF_PREFILTER_MIRROR_TOL_NORMAL;
    int *partner = malloc(sizeof(int) * (size_t)count);
    if (!partner)
        return 0;
    for (int i = 0; i < count; ++i)
        partner[i] = -1;
    int ok = 1;
    for (int i = 0; i < count && ok; ++i) {
        if (partner[i] >= 0)
            continue;
        int found = -1;
        for (int j = i; j < count && found < 0; ++j)
            if (partner[j] < 0 && fabs(n[3 * i] - n[3 * j]) <= tol && fabs(n[3 * i + 1] + n[3 * j + 1]) <= tol &&
                fabs(n[3 * i + 2] - n[3 * j + 2]) <= tol)
                found = j;
        if (found < 0)
            ok = 0;
        else
            partner[i] = found, partner[found] = i;
    }
    if (ok)
        for (int i = 0; i < count; ++i) {
            int j = partner[i];
            if (j < i)
                continue;
            double x = 0.5 * (n[3 * i] + n[3 * j]), y = j == i ? 0.0 : 0.5 * (n[3 * i + 1] - n[3 * j + 1]),
                   z = 0.5 * (n[3 * i + 2] + n[3 * j + 2]), l = sqrt(x * x + y * y + z * z);
            n[3 * i] = n[3 * j] = x / l, n[3 * i + 1] = y / l, n[3 * j + 1] = -y / l, n[3 * i + 2] = n[3 * j + 2] = z / l;
        }
    free(partner);
    return ok;
}


/* `fresh` for the mixture of `count` normals: magnitude x the fitted lobe's shading per light (out[nl]);
 * returns 0, or -1 if the mixture or the fit failed. */
static int fit_part(const mf_brdf_model *ggx, const double *nrm, int count, double alpha, double theta,
                    const mf_ltcfit_aniso_options *fo, const double *hs, int nl, double *out)
{
    mf_prefilter_mix mix;
    if (mf_prefilter_mix_init(&mix, ggx, nrm, count) != MF_OK)
        return -1;
    mf_brdf_params p = mf_brdf_params_iso(alpha);
    mf_result rho;
    mf_ltcfit_aniso_entry e;
    int rc = -1;
    if (mf_prefilter_mix_albedo(&mix, &p, mf_vec3_make(sin(theta), 0.0, cos(theta)), &rho) == MF_OK &&
        mf_ltcfit_aniso_entry_fit_mirrored(&mix.model, p, theta, 0, rho.val, 0.0, NULL, NULL, fo, &e) == MF_OK) {
        double mag = rho.val / fmax(horizon_mass(e.m), MF_PREFILTER_HORIZON_MIN);
        for (int k = 0; k < nl; ++k)
            out[k] = lobe_shading(e.m, mag, theta, hs[k]);
        rc = 0;
    }
    mf_prefilter_mix_free(&mix);
    return rc;
}

static int parse_pair(const char *s, int *a, int *b) { return sscanf(s, "%d,%d", a, b) == 2 ? 0 : -1; }

int main(int argc, char **argv)
{
    const char *dir = NULL, *map = NULL, *lights = "0.05,0.1,0.2,0.3,0.5,1";
    int level = 2, tx = 0, ty = 0, ia = -1, ip = 1, samples = 65536;
    double grid = 0.0;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!v)
            return usage();
        if (!strcmp(a, "--prefilter"))
            dir = v;
        else if (!strcmp(a, "--map"))
            map = v;
        else if (!strcmp(a, "--level"))
            level = atoi(v);
        else if (!strcmp(a, "--texel")) {
            if (parse_pair(v, &tx, &ty))
                return usage();
        } else if (!strcmp(a, "--view")) {
            if (parse_pair(v, &ia, &ip))
                return usage();
        } else if (!strcmp(a, "--lights"))
            lights = v;
        else if (!strcmp(a, "--samples"))
            samples = atoi(v);
        else if (!strcmp(a, "--grid"))
            grid = atof(v);
        else
            return usage();
        ++i;
    }
    double hs[CELL_MAX_LIGHTS];
    int nl = 0;
    for (const char *p = lights; *p && nl < CELL_MAX_LIGHTS;) {
        char *end;
        hs[nl] = strtod(p, &end);
        if (end == p || !(hs[nl] > 0.0 && hs[nl] <= 10.0)) {
            fprintf(stderr, "study_prefilter_cell: --lights %s: expected half sides in (0, 10]\n", lights);
            return 2;
        }
        ++nl;
        p = *end == ',' ? end + 1 : end;
    }
    if (!dir || level < 1 || samples < 16 || samples % 2 || nl < 1)
        return usage();

    char path[4200], msg[4400], mapbuf[4096];
    size_t jl;
    snprintf(path, sizeof path, "%s/prefilter.json", dir);
    char *js = mf_prefilter_read_file(path, &jl, msg, sizeof msg);
    if (!js) {
        fprintf(stderr, "study_prefilter_cell: %s\n", msg);
        return 3;
    }
    if (!map) {
        if (!mf_prefilter_json_string(js, "map", mapbuf, sizeof mapbuf)) {
            fprintf(stderr, "study_prefilter_cell: %s: no \"map\" entry\n", path);
            free(js);
            return 2;
        }
        map = mapbuf;
    }
    const char *key = "\"base_brdf\": {\"model\": \"ggx\", \"alpha\": ";
    const char *ap = strstr(js, key);
    double alpha = 0.0;
    if (!ap || sscanf(ap + strlen(key), "%lf", &alpha) != 1 || !(alpha > 0.0 && alpha <= 1.0)) {
        fprintf(stderr, "study_prefilter_cell: %s: no GGX base with an alpha in (0, 1]\n", path);
        free(js);
        return 2;
    }
    free(js);

    /* the stored level (and every level, for the lookup) */
    int nlev = 0;
    mf_prefilter_lookup_level lv[16];
    float *alb = NULL;
    long d[6] = {0}, dm[4] = {0};
    for (int k = 1; k <= 16; ++k) {
        snprintf(path, sizeof path, "%s/ltc_mip%d.npy", dir, k);
        FILE *f = fopen(path, "rb");
        if (!f)
            break;
        fclose(f);
        long dk[6], dmk[4];
        lv[k - 1].m = mf_prefilter_read_npy(path, 6, dk, msg, sizeof msg);
        snprintf(path, sizeof path, "%s/magnitude_mip%d.npy", dir, k);
        lv[k - 1].mag = lv[k - 1].m ? mf_prefilter_read_npy(path, 4, dmk, msg, sizeof msg) : NULL;
        if (!lv[k - 1].m || !lv[k - 1].mag) {
            fprintf(stderr, "study_prefilter_cell: %s\n", msg);
            return 3;
        }
        lv[k - 1].w = (int)dk[1], lv[k - 1].h = (int)dk[0];
        if (k == level) {
            memcpy(d, dk, sizeof d), memcpy(dm, dmk, sizeof dm);
            snprintf(path, sizeof path, "%s/albedo_mip%d.npy", dir, k);
            long da[4];
            alb = mf_prefilter_read_npy(path, 4, da, msg, sizeof msg);
        }
        nlev = k;
    }
    if (level > nlev || !alb) {
        fprintf(stderr, "study_prefilter_cell: %s: no level %d with ltc, magnitude and albedo files\n", dir, level);
        return 2;
    }
    int nt = (int)d[2], np = (int)d[3];
    if (ia < 0)
        ia = nt - 1;
    if (tx < 0 || ty < 0 || tx >= d[1] || ty >= d[0] || ia < 0 || ia >= nt || ip < 0 || ip >= np) {
        fprintf(stderr, "study_prefilter_cell: --texel %d,%d / --view %d,%d outside level %d (%ld x %ld, %d x %d views)\n",
                tx, ty, ia, ip, level, d[1], d[0], nt, np);
        return 2;
    }
    mf_prefilter_options po;
    mf_prefilter_options_default(&po);
    po.n_theta = nt, po.n_phi = np;
    double theta = mf_prefilter_theta(&po, ia), phi = mf_prefilter_phi(&po, ip);

    /* the footprint, decoded as mfkit prefilter's defaults do, rotated by -phi about z */
    mf_image_set_backend(mf_image_oiio_backend());
    mf_image img;
    mf_image_info info;
    mf_status st = mf_image_read_ex(map, &img, NULL, &info, msg, sizeof msg);
    if (st != MF_OK) {
        fprintf(stderr, "study_prefilter_cell: %s\n", msg[0] ? msg : mf_status_str(st));
        return 3;
    }
    int unorm = !strncmp(info.pixel_type, "uint", 4);
    int fw = img.width / (int)d[1], fh = img.height / (int)d[0], count = fw * fh;
    double *nrm = malloc(sizeof(double) * 3 * (size_t)count), *sym = malloc(sizeof(double) * 3 * (size_t)count);
    if (!nrm || !sym || img.channels < 3)
        return 3;
    double mean[3] = {0, 0, 0}, cmin = 2.0;
    mf_vec3 wo = mf_vec3_make(sin(theta), 0.0, cos(theta));
    for (int y = 0, q = 0; y < fh; ++y)
        for (int x = 0; x < fw; ++x, ++q) {
            const float *px = img.pixels + ((size_t)(ty * fh + y) * img.width + (size_t)(tx * fw + x)) * img.channels;
            double n[3];
            for (int c = 0; c < 3; ++c)
                n[c] = unorm ? 2.0 * (double)px[c] - 1.0 : (double)px[c];
            double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            double r[3] = {(cos(phi) * n[0] + sin(phi) * n[1]) / l, (-sin(phi) * n[0] + cos(phi) * n[1]) / l, n[2] / l};
            memcpy(nrm + 3 * q, r, sizeof r);
            for (int c = 0; c < 3; ++c)
                mean[c] += r[c] / count;
            double cv = r[0] * wo.x + r[1] * wo.y + r[2] * wo.z;
            cmin = cv < cmin ? cv : cmin;
        }
    mf_image_free(&img);
    mf_image_info_free(&info);
    memcpy(sym, nrm, sizeof(double) * 3 * (size_t)count);
    int mir = mirror_snap_pairs(sym, count) ? MF_LTCFIT_ANISO_MIRROR_Y : 0;

    const mf_brdf_model *ggx = mf_brdf_model_find("ggx");
    double len = sqrt(mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2]);
    double nbar[3] = {mean[0] / len, mean[1] / len, mean[2] / len};
    double alpha_t = mf_toksvig_beckmann_alpha(len > 1.0 ? 1.0 : len, alpha);
    mf_prefilter_mix truth, fitmix, naive;
    if (!ggx || mf_prefilter_mix_init(&truth, ggx, nrm, count) != MF_OK ||
        mf_prefilter_mix_init(&fitmix, ggx, mir ? sym : nrm, count) != MF_OK ||
        mf_prefilter_mix_init(&naive, ggx, nbar, 1) != MF_OK) {
        fprintf(stderr, "study_prefilter_cell: the footprint's normals are not valid (n.z > 0)\n");
        return 2;
    }

    size_t idx = (((size_t)ty * (size_t)d[1] + (size_t)tx) * (size_t)nt + (size_t)ia) * (size_t)np + (size_t)ip;
    double ms[9], ml[9], mag = lv[level - 1].mag[idx], magl, albedo = alb[idx];
    for (int i = 0; i < 9; ++i)
        ms[i] = lv[level - 1].m[9 * idx + i];
    mf_prefilter_lookup_levels ls = {nlev, nt, np, lv};
    mf_prefilter_lookup(&ls, (tx + 0.5) / (double)d[1], (ty + 0.5) / (double)d[0], (double)level, theta, phi, ml, &magl);

    mf_ltcfit_aniso_options fo;
    mf_ltcfit_aniso_options_default(&fo);
    fo.samples = po.samples, fo.max_iterations = po.max_iterations, fo.seed = po.seed, fo.ladder_alpha = alpha;
    mf_ltcfit_aniso_entry e;
    if (mf_ltcfit_aniso_entry_fit_mirrored(&fitmix.model, mf_brdf_params_iso(alpha), theta, mir, albedo, 0.0, NULL,
                                               NULL, &fo, &e) != MF_OK) {
        fprintf(stderr, "study_prefilter_cell: the fresh fit failed\n");
        return 3;
    }
    double magf = albedo / fmax(horizon_mass(e.m), MF_PREFILTER_HORIZON_MIN);

    /* two lobes: the halves of a 2-means split, each fitted as `fresh` (one lobe if the split fails) */
    int *side = malloc(sizeof(int) * (size_t)count);
    double *half = malloc(sizeof(double) * 3 * (size_t)count), two[CELL_MAX_LIGHTS];
    if (!side || !half)
        return 3;
    int n1 = mf_prefilter_split_two(nrm, count, side), nh[2] = {count - n1, n1}; /* the prefilter's --lobes 2 split */
    for (int k = 0; k < nl; ++k)
        two[k] = n1 ? 0.0 : lobe_shading(e.m, magf, theta, hs[k]);
    for (int c = 0; c < 2 && n1; ++c) {
        double part[CELL_MAX_LIGHTS];
        int m = 0;
        for (int q = 0; q < count; ++q)
            if (side[q] == c)
                memcpy(half + 3 * m++, nrm + 3 * q, sizeof(double) * 3);
        if (fit_part(ggx, half, m, alpha, theta, &fo, hs, nl, part) != 0) {
            fprintf(stderr, "study_prefilter_cell: the fit of half %d (%d normals) failed\n", c, m);
            return 3;
        }
        for (int k = 0; k < nl; ++k)
            two[k] += part[k] * m / (double)count;
    }
    free(side), free(half);

    printf("# study_prefilter_cell --prefilter %s --level %d --texel %d,%d --view %d,%d --samples %d, mfkit=%s\n", dir,
           level, tx, ty, ia, ip, samples, MFKIT_VERSION);
    printf("footprint: %d texels, mean normal length %.4f (Toksvig alpha %.4f); view theta %.4f deg, phi %.2f deg; "
           "smallest texel-frame view cosine %.5f (the below-horizon clamp acts below %.3f); y-mirror symmetric: %s\n",
           count, len, alpha_t, theta * 180.0 / MF_PI, phi * 180.0 / MF_PI, cmin, MF_PREFILTER_COS_MIN, mir ? "yes" : "no");
    double dl = 0.0;
    for (int i = 0; i < 9; ++i)
        dl = fmax(dl, fabs(ml[i] - ms[i]));
    printf("stored: magnitude %.5f, albedo %.5f, horizon mass %.4f, M", mag, albedo, horizon_mass(ms));
    for (int i = 0; i < 9; ++i)
        printf(" %.4f", ms[i]);
    printf("\nlookup: |M - stored| <= %.2g, magnitude %.5f\n", dl, magl);
    printf("fresh:  residual %.5f, iterations %d, magnitude %.5f, M", e.residual, e.iterations, magf);
    for (int i = 0; i < 9; ++i)
        printf(" %.4f", e.m[i]);
    printf("\ntwo: halves of %d and %d texels\n", nh[0], nh[1]);
    printf("h,truth,stored,lookup,stored_mag_albedo,fresh,two,naive,toksvig\n");
    for (int k = 0; k < nl; ++k) {
        double mc[3];
        mc_shading(&truth, &naive, alpha, alpha_t, theta, hs[k], samples, mc);
        printf("%g,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f,%.6f\n", hs[k], mc[0], lobe_shading(ms, mag, theta, hs[k]),
               lobe_shading(ml, magl, theta, hs[k]), lobe_shading(ms, albedo, theta, hs[k]),
               lobe_shading(e.m, magf, theta, hs[k]), two[k], mc[1], mc[2]);
    }
    if (grid > 0.0) {
        mf_vec3 c, e1, e2;
        light_frame(theta, &c, &e1, &e2);
        mf_brdf_params p = mf_brdf_params_iso(alpha);
        printf("truth f cos on the lights' plane: rows a = +10 .. -10 steps of %g along the elevation axis, "
               "columns b = -10 .. 10 along y; '-' below the horizon\n", grid);
        for (int a = 10; a >= -10; --a) {
            for (int b = -10; b <= 10; ++b) {
                mf_vec3 x = light_point(c, e1, e2, a * grid, b * grid);
                double rl = sqrt(x.x * x.x + x.y * x.y + x.z * x.z);
                mf_vec3 wi = mf_vec3_make(x.x / rl, x.y / rl, x.z / rl);
                if (wi.z > 0.0)
                    printf(" %6.2f", truth.model.eval_cos(&truth.model, &p, wo, wi));
                else
                    printf("      -");
            }
            printf("\n");
        }
    }
    mf_prefilter_mix_free(&truth), mf_prefilter_mix_free(&fitmix), mf_prefilter_mix_free(&naive);
    free(nrm), free(sym), free(alb);
    for (int k = 0; k < nlev; ++k)
        free((void *)lv[k].m), free((void *)lv[k].mag);
    return 0;
}
