/*
 * bench_ltc_aniso_common.h -- the test cases of the anisotropic GGX LTC benchmark (issue 12),
 * shared by analysis/bench_ltc_aniso.c and analysis/study_aniso_oracle.c so that both see exactly
 * the same points, lights and Monte Carlo truth.  Header-only (static functions), analysis only.
 *
 * Case i (i = 0, 1, ...): the i-th point drawn from one PCG32 stream (seed 12, stream "bench"):
 *   alpha_x, alpha_y uniform in [0.02, 1], theta uniform in [0, 0.9999 pi/2], phi in [0, pi/2];
 * the view wo = (sin theta cos phi, sin theta sin phi, cos theta); ABENCH_Q random quads (the
 * even indices of mf_ltc_gate_random_polygons_params(seed 5, stream i, 2 ABENCH_Q polygons)); the
 * truth: a Monte Carlo integral of f cos over each quad (mf_ltc_gate_polygon_mc_params, `samples`
 * directions, seed 9, stream i) with its standard error, and the exact albedo (mf_model_albedo).
 *
 * The published table [Kt, Heitz, Dupuy, Narayanan 2022] is read from its .npy (shape (8, 8, 8,
 * 8, 3, 3), float32) and interpolated quadrilinearly on its own axes, as a shader does; a matrix
 * interpolated to det < 0 (its entries mix flipped gauges) is evaluated as M diag(-1, 1, 1), the
 * same lobe density with positive orientation.
 */
#ifndef BENCH_LTC_ANISO_COMMON_H
#define BENCH_LTC_ANISO_COMMON_H

#include "mfkit/mfkit.h"
#include "mfkit/mf_ltc_gate.h"
#include "mfkit/fit/mf_ltcfit_aniso.h"
#include "mfkit/io/mf_table_io.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The table a program measures: read from table_path, or (NULL) fitted with o.  1: fitted (r holds
 * the fit's result), 0: read, -1: an error (printed, prefixed with prog). */
static inline int abench_table_get_u(const char *prog, const char *table_path, const mf_ltcfit_aniso_options *o,
                                     mf_table *t, mf_ltcfit_aniso_result *r, double *storage_u)
{
    char msg[256];
    if (storage_u)
        *storage_u = 0.0; /* a table fitted in memory: doubles */
    if (table_path) {
        mf_table_file_info info;
        memset(&info, 0, sizeof info);
        if (mf_table_read(table_path, t, &info, msg, sizeof msg) != MF_OK) {
            fprintf(stderr, "%s: %s\n", prog, msg); /* msg names the file */
            return -1;
        }
        printf("mfkit table read from %s\n", table_path);
        if (storage_u) /* every table file mfkit writes stores float32 or halves */
            *storage_u = mf_table_storage_roundoff(info.half_float);
        return 0;
    }
    if (mf_ltcfit_aniso_table(mf_brdf_model_find("ggx"), o, t, r, msg, sizeof msg) != MF_OK) {
        fprintf(stderr, "%s: fit failed: %s\n", prog, msg);
        return -1;
    }
    return 1;
}

/* The same without the storage rounding. */
static inline int abench_table_get(const char *prog, const char *table_path, const mf_ltcfit_aniso_options *o,
                                   mf_table *t, mf_ltcfit_aniso_result *r)
{
    return abench_table_get_u(prog, table_path, o, t, r, NULL);
}

enum { ABENCH_Q = 12 };

static inline float *abench_read_kt(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    unsigned char h[10];
    if (fread(h, 1, 10, f) != 10 || memcmp(h, "\x93NUMPY", 6)) {
        fclose(f);
        return NULL;
    }
    int hl = h[8] | h[9] << 8;
    char hdr[512] = {0};
    if (hl >= 512 || fread(hdr, 1, (size_t)hl, f) != (size_t)hl || !strstr(hdr, "(8, 8, 8, 8, 3, 3)") ||
        !strstr(hdr, "<f4")) {
        fclose(f);
        return NULL;
    }
    size_t n = 8 * 8 * 8 * 8 * 9;
    float *d = malloc(n * sizeof *d);
    if (d && fread(d, sizeof *d, n, f) != n) {
        free(d);
        d = NULL;
    }
    fclose(f);
    return d;
}

/* Quadrilinear interpolation of the published table at (alpha_x, alpha_y, theta, phi). */
static inline void abench_kt_lookup(const float *d, const double p[4], double m[9])
{
    const double hi[4] = {1.0, 1.0, 0.9999 * 0.5 * MF_PI, 0.5 * MF_PI};
    int i[4];
    double w[4];
    for (int k = 0; k < 4; ++k) {
        double x = fmin(fmax(p[k] / hi[k], 0.0), 1.0) * 7.0;
        i[k] = (int)fmin(floor(x), 6.0);
        w[k] = x - i[k];
    }
    memset(m, 0, 9 * sizeof *m);
    for (int c = 0; c < 16; ++c) {
        double wt = 1.0;
        int j[4];
        for (int k = 0; k < 4; ++k) {
            int b = (c >> k) & 1;
            j[k] = i[k] + b;
            wt *= b ? w[k] : 1.0 - w[k];
        }
        const float *e = d + ((((size_t)j[0] * 8 + j[1]) * 8 + j[2]) * 8 + j[3]) * 9;
        for (int a = 0; a < 9; ++a)
            m[a] += wt * e[a];
    }
}

static inline double abench_det9(const double *m)
{
    return m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6]) + m[2] * (m[3] * m[7] - m[4] * m[6]);
}

/* The published table's matrix at p as the benchmark evaluates it; returns 1 if it was flipped. */
static inline int abench_published(const float *pub, const double p[4], double m[9])
{
    abench_kt_lookup(pub, p, m);
    if (abench_det9(m) < 0.0) {
        m[0] = -m[0], m[3] = -m[3], m[6] = -m[6];
        return 1;
    }
    return 0;
}

/* The LTC of a row-major matrix; all zeros (every integral NaN) where mf_ltc_init refuses it. */
static inline mf_ltc abench_ltc_of(const double *m9)
{
    mf_ltc l;
    if (mf_ltc_init(&l, mf_ltc_matrix_general(m9)) != MF_OK)
        memset(&l, 0, sizeof l);
    return l;
}

typedef struct {
    mf_pcg32 rng;
} abench_points;

/* The benchmark's points: seed 12.  Another seed gives a second, independent set of points from
 * the same distribution (the check that a change is not tuned to the first set). */
enum { ABENCH_POINT_SEED = 12 };

static inline void abench_points_init_seed(abench_points *s, uint64_t seed)
{
    mf_pcg32_seed(&s->rng, seed, 0x62656e6368ull);
}

static inline void abench_points_init(abench_points *s)
{
    abench_points_init_seed(s, ABENCH_POINT_SEED);
}

/* The next point (alpha_x, alpha_y, theta, phi). */
static inline void abench_next_point(abench_points *s, double p[4])
{
    p[0] = 0.02 + 0.98 * mf_pcg32_next_double(&s->rng);
    p[1] = 0.02 + 0.98 * mf_pcg32_next_double(&s->rng);
    p[2] = 0.9999 * 0.5 * MF_PI * mf_pcg32_next_double(&s->rng);
    p[3] = 0.5 * MF_PI * mf_pcg32_next_double(&s->rng);
}

typedef struct {
    double p[4];
    mf_polygon quads[ABENCH_Q];
    double mc[ABENCH_Q], se[ABENCH_Q]; /* the truth and its standard error per quad */
    double albedo;                     /* exact albedo (mf_model_albedo) */
} abench_case;

/* The light distributions.  ABENCH_LIGHTS_QUADS is the benchmark's (the even indices of
 * mf_ltc_gate_random_polygons_params: quads with half-extents log-uniform in [0.03, 1.2] at
 * distance 1, a third towards the lobe, a third across the horizon, a third anywhere).  The others
 * are second distributions, to check that a fitter whose lights follow the benchmark's
 * distribution is not tuned to it: the odd indices of the same stream (the generator's
 * triangles, same centres and sizes), and the quads scaled about their centres by 1/4 (small:
 * half-extents 0.0075 .. 0.3) or by 2.5 (large: 0.075 .. 3, many of them across the horizon). */
enum { ABENCH_LIGHTS_QUADS = 0, ABENCH_LIGHTS_TRIANGLES, ABENCH_LIGHTS_SMALL, ABENCH_LIGHTS_LARGE };

static inline const char *abench_lights_name(int kind)
{
    static const char *names[4] = {"quads", "triangles", "small", "large"};
    return kind >= 0 && kind < 4 ? names[kind] : "?";
}

/* Case i at point p with the lights of `kind`: its lights, Monte Carlo truth and albedo.  0 if
 * either computation failed (the benchmark then skips the point). */
static inline int abench_case_make_lights(const mf_brdf_model *ggx, const double p[4], int i, int samples, int kind,
                                          abench_case *c)
{
    memcpy(c->p, p, sizeof c->p);
    mf_brdf_params prm = {p[0], p[1]};
    mf_vec3 wo = mf_vec3_make(sin(p[2]) * cos(p[3]), sin(p[2]) * sin(p[3]), cos(p[2]));
    mf_polygon polys[2 * ABENCH_Q];
    mf_ltc_gate_random_polygons_params(ggx, &prm, wo, 5, (uint64_t)i, 2 * ABENCH_Q, polys);
    for (int k = 0; k < ABENCH_Q; ++k) {
        c->quads[k] = polys[2 * k + (kind == ABENCH_LIGHTS_TRIANGLES)];
        if (kind == ABENCH_LIGHTS_SMALL || kind == ABENCH_LIGHTS_LARGE) {
            double f = kind == ABENCH_LIGHTS_SMALL ? 0.25 : 2.5;
            mf_polygon *q = &c->quads[k];
            mf_vec3 m = mf_vec3_make(0.0, 0.0, 0.0);
            for (int v = 0; v < q->n; ++v)
                m = mf_vec3_add(m, mf_vec3_scale(q->v[v], 1.0 / q->n));
            for (int v = 0; v < q->n; ++v)
                q->v[v] = mf_vec3_add(m, mf_vec3_scale(mf_vec3_sub(q->v[v], m), f));
        }
    }
    mf_result alb;
    if (mf_ltc_gate_polygon_mc_params(ggx, &prm, wo, c->quads, ABENCH_Q, samples, 9, (uint64_t)i, c->mc, c->se, NULL) !=
            MF_OK ||
        mf_model_albedo(ggx, &prm, wo, MF_MODEL_ALBEDO_N, &alb) != MF_OK)
        return 0;
    c->albedo = alb.val;
    return 1;
}

/* Case i at point p with the benchmark's quads. */
static inline int abench_case_make(const mf_brdf_model *ggx, const double p[4], int i, int samples, abench_case *c)
{
    return abench_case_make_lights(ggx, p, i, samples, ABENCH_LIGHTS_QUADS, c);
}

/* The benchmark's per-quad errors of a shaded value v against the truth mc. */
static inline double abench_abs_err(double v, double mc)
{
    return fabs(v - mc);
}
static inline double abench_rel_err(double v, double mc, double albedo)
{
    return fabs(v - mc) / fmax(mc, 0.01 * albedo);
}

#endif /* BENCH_LTC_ANISO_COMMON_H */
