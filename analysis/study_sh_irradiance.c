/*
 * study_sh_irradiance.c -- error of the order-2 SH irradiance (9 coefficients) over the sphere of
 * normals, for four analytic environments (issue 6).
 *
 *   build-dir/analysis/study_sh_irradiance [--thetas T] [--phis P] [--windows LIST] [--out FILE]
 *
 * For each environment L(w) (radiance, in units of the sky's zenith radiance) and each normal n of
 * a T x P grid of cell centres (theta_n = 180 (j + 1/2)/T deg from +z, phi_n = 360 (k + 1/2)/P deg
 * from +x towards +y; the whole sphere, downward normals included):
 *   e_sh     order-2 irradiance mf_sh_irradiance(L_lm, n) = sum A_l L_lm Y_lm(n)  [R&H 2001, Eq. 7-13],
 *            the coefficients L_lm optionally windowed (mf_sh_apply_window, width 3 [Sloan 2008]);
 *   e_exact  E(n) = integral L(w) max(0, n.w) dw  [R&H 2001, Eq. 1] by quadrature (below), with
 *            e_exact_err its error estimate;
 *   abs_err  |e_sh - e_exact|;  rel_err  abs_err / e_exact (nan where e_exact = 0);
 *   norm_err abs_err / integral L dw.  For any L >= 0, norm_err <= 3/32 = 0.09375, attained only by
 *            a directional light at n perpendicular to it (docs/math.md, "Error of the order-2
 *            irradiance": E_SH(n) = integral L(w) k(n.w) dw, |k(c) - max(0, c)| <= 3/32).
 *
 * Environments (mf_sh.h has no shared list: these follow tests/test_sh.c, whose sun-lobe and
 * overcast skies are the same functions, and the directional light of its 3/32 check):
 *   overcast     CIE standard overcast sky, L = (1 + 2 cos theta)/3 above the horizon, 0 below
 *                [Moon & Spencer 1942; CIE S 011/E:2003, sky type 1]: a sky gradient.
 *   sun_sky      the smooth whole-sphere sky of tests/test_sh.c: 1 + 0.5 x + 3 exp(4 (w.s - 1)),
 *                s = normalize(0.3, 0.2, 0.9): ambient, a horizontal gradient, a soft sun lobe.
 *   sun_disc     the overcast sky plus a small bright sun: a uniform disc of angular radius
 *                0.2666 deg (the solar disc) at elevation 40 deg, azimuth 30 deg, whose
 *                irradiance at normal incidence is P = 20 (8.2 x the sky's horizontal 7 pi/9).
 *   directional  a single directional light of irradiance P = 1 from the same direction.
 * SH coefficients: the skies by mf_sh_project_fn (split Gauss-Legendre product rule; overcast
 * n = 16 is exact, a polynomial of degree 1 per hemisphere; sun_sky n = 48, error estimate
 * printed); the directional light exactly, L_lm = P Y_lm(d) (mf_sh_add_directional); the disc in
 * closed form: a uniform cap of radius delta around d is zonal, so by the addition theorem
 * [R&H 2001, Eq. 5; Sloan 2008, "rotating zonal harmonics"] L_lm = L_s 2 pi (integral over
 * [cos delta, 1] of P_l(t) dt) Y_lm(d), i.e. with P = L_s pi sin^2 delta:
 *   L_lm = P w_l Y_lm(d),  w_0 = 1/cos^2(delta/2),  w_1 = 1,  w_2 = cos delta
 * (integrals of P_0, P_1, P_2 over [c, 1]: 1 - c = 2 sin^2(delta/2), (1 - c^2)/2, c (1 - c^2)/2;
 * checked below against quadrature).
 *
 * Exact irradiance, by component (each error estimate added into e_exact_err):
 *   skies        in the frame (s, t, n) around n, w = sin a (cos b s + sin b t) + cos a n:
 *                E = integral_0^{pi/2} sin a cos a integral_0^{2pi} L(w) db da.  For a sky that is 0
 *                below the horizon, w.z = A + B cos(b - b0) (A = cos a n.z, B = sin a |(s.z, t.z)|):
 *                the inner integral runs over the lit arc b0 +- acos(-A/B) only (a smooth integrand:
 *                Gauss-Legendre), otherwise over the full circle (periodic trapezoid rule, spectrally
 *                accurate).  The outer integral is adaptive Gauss-Kronrod (mf_quad_adaptive, relative
 *                1e-13), split at a* = |elevation of n| where the arc appears.  Error: the outer
 *                estimate plus |inner(48 GL / 96 trapezoid) - inner(24 / 48)|, an estimate of the
 *                coarser rule, so conservative.
 *   disc         in the frame around the sun direction d, n.w = A + B cos(b - b0) with
 *                A = cos a n.d, B = sin a |n - (n.d) d|; the inner integral of max(0, n.w) is closed:
 *                2 pi A (A >= B), 0 (A <= -B), else 2 (A h + sqrt(B^2 - A^2)), h = acos(-A/B); the
 *                outer over a in [0, delta] by adaptive Gauss-Kronrod, split where the disc meets
 *                the horizon of n (a* = |pi/2 - angle(n, d)|).
 *   directional  P max(0, n.d), exact.
 * A self-check before the study: L = max(0, z)^2, for which the order-2 irradiance is exact
 * (docs/math.md), must agree with the sky quadrature to 1e-12; the disc's closed-form
 * coefficients must agree with their own quadrature to 1e-12 (radius 0.3 rad and the solar disc).
 *
 * Columns: env, window, theta_deg, phi_deg, e_exact, e_exact_err, e_sh, abs_err, rel_err,
 * norm_err, light_theta_deg, light_phi_deg (the direction of the sun or of sun_sky's lobe, for the
 * plots; nan for overcast).  First line: provenance header (seed "none": nothing is random).  The CSV is written
 * to a temporary beside it (mfkit/io/mf_io.h) and renamed over FILE; it is generated, not committed.
 * Exit status: 0, 1 (a quadrature or self-check failed), 2 (usage), 3 (I/O).
 */
#define _POSIX_C_SOURCE 200809L
#include <mfkit/mfkit.h>
#include <mfkit/io/mf_io.h>

#include "study_header.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define DEG (MF_PI / 180.0)
#define N_ENV 4
#define SUN_RADIUS (0.2666 * DEG)
#define SUN_POWER 20.0
#define SUN_ELEVATION_DEG 40.0
#define SUN_AZIMUTH_DEG 30.0
#define QUAD_REL 1e-13
#define QUAD_ABS 1e-15

/* ---- radiance fields ------------------------------------------------------------------------ */
typedef double (*radiance_fn)(mf_vec3 w, void *user);

static double f_overcast(mf_vec3 w, void *u) { (void)u; return w.z > 0.0 ? (1.0 + 2.0 * w.z) / 3.0 : 0.0; }
static double f_sun_sky(mf_vec3 w, void *u)
{
    (void)u;
    mf_vec3 s = mf_vec3_normalize(mf_vec3_make(0.3, 0.2, 0.9));
    return 1.0 + 0.5 * w.x + 3.0 * exp(4.0 * (mf_vec3_dot(w, s) - 1.0));
}
static double f_zplus_sq(mf_vec3 w, void *u) { (void)u; return w.z > 0.0 ? w.z * w.z : 0.0; }

/* ---- exact irradiance of a sky: nested quadrature around n ----------------------------------- */
typedef struct {
    radiance_fn f;
    int upper_only; /* L = 0 below the horizon z = 0 */
    mf_frame fr;
    int n_gl, n_trap;
    const double *gx, *gw;
} sky_ctx;

static double sky_inner(double a, void *vctx)
{
    const sky_ctx *c = vctx;
    double sa = sin(a), ca = cos(a);
    double A = ca * c->fr.n.z, B = sa * hypot(c->fr.s.z, c->fr.t.z), b0 = atan2(c->fr.t.z, c->fr.s.z);
    double s = 0.0;
    if (c->upper_only && B > fabs(A)) { /* the lit arc b0 +- h */
        double h = acos(-A / B);
        for (int k = 0; k < c->n_gl; ++k) {
            double b = b0 + h * c->gx[k];
            mf_vec3 w = mf_vec3_add(mf_vec3_add(mf_vec3_scale(c->fr.s, sa * cos(b)), mf_vec3_scale(c->fr.t, sa * sin(b))),
                                    mf_vec3_scale(c->fr.n, ca));
            w = mf_vec3_normalize(w);
            s += h * c->gw[k] * (w.z > 0.0 ? c->f(w, NULL) : 0.0);
        }
    } else if (c->upper_only && A <= 0.0) {
        return 0.0; /* the whole circle is below the horizon */
    } else {
        for (int k = 0; k < c->n_trap; ++k) {
            double b = 2.0 * MF_PI * (k + 0.5) / c->n_trap;
            mf_vec3 w = mf_vec3_add(mf_vec3_add(mf_vec3_scale(c->fr.s, sa * cos(b)), mf_vec3_scale(c->fr.t, sa * sin(b))),
                                    mf_vec3_scale(c->fr.n, ca));
            w = mf_vec3_normalize(w);
            s += (2.0 * MF_PI / c->n_trap) * c->f(w, NULL);
        }
    }
    return s * sa * ca;
}

static double gl_x[2][48], gl_w[2][48]; /* 48- and 24-point Gauss-Legendre on [-1, 1] */

/* One nested integral with the given inner resolution; adds the outer error estimate to *err. */
static int sky_pass(sky_ctx *c, int level, mf_vec3 n, double *val, double *err)
{
    c->n_gl = level == 0 ? 48 : 24;
    c->n_trap = level == 0 ? 96 : 48;
    c->gx = gl_x[level];
    c->gw = gl_w[level];
    double a_star = asin(fmin(1.0, fabs(n.z)));
    double v = 0.0, e = 0.0;
    const double cut[3] = {0.0, a_star, 0.5 * MF_PI};
    for (int p = 0; p < 2; ++p) {
        if (!(cut[p + 1] > cut[p]))
            continue;
        mf_result r;
        if (mf_quad_adaptive(sky_inner, c, cut[p], cut[p + 1], QUAD_ABS, QUAD_REL, MF_QUAD_MAX_INTERVALS, &r) != MF_OK)
            return 0;
        v += r.val;
        e += r.err;
    }
    *val = v;
    *err = e;
    return 1;
}

/* E(n) of a sky; *err: outer estimate + |fine - coarse inner|.  0 on a quadrature failure. */
static int sky_irradiance(radiance_fn f, int upper_only, mf_vec3 n, double *val, double *err)
{
    sky_ctx c;
    memset(&c, 0, sizeof c);
    c.f = f;
    c.upper_only = upper_only;
    c.fr = mf_frame_from_normal(n);
    double v0, e0, v1, e1;
    if (!sky_pass(&c, 0, n, &v0, &e0) || !sky_pass(&c, 1, n, &v1, &e1))
        return 0;
    *val = v0;
    *err = e0 + fabs(v0 - v1);
    return 1;
}

/* ---- the sun disc ------------------------------------------------------------------------------ */
typedef struct {
    double nd, nperp; /* n.d and |n - (n.d) d| */
} disc_ctx;

/* sin a * integral over b of max(0, A + B cos(b - b0)) db, closed form (see the header). */
static double disc_inner(double a, void *vctx)
{
    const disc_ctx *c = vctx;
    double A = cos(a) * c->nd, B = sin(a) * c->nperp, g;
    if (A >= B)
        g = 2.0 * MF_PI * A;
    else if (A <= -B)
        g = 0.0;
    else
        g = 2.0 * (A * acos(-A / B) + sqrt(B * B - A * A));
    return sin(a) * g;
}

/* E(n) of a uniform disc of radius delta around d with irradiance P at normal incidence. */
static int disc_irradiance(mf_vec3 d, double delta, double power, mf_vec3 n, double *val, double *err)
{
    disc_ctx c;
    c.nd = fmax(-1.0, fmin(1.0, mf_vec3_dot(n, d)));
    c.nperp = mf_vec3_length(mf_vec3_sub(n, mf_vec3_scale(d, c.nd)));
    double radiance = power / (MF_PI * sin(delta) * sin(delta)); /* P = L_s pi sin^2 delta */
    double a_star = fabs(0.5 * MF_PI - acos(c.nd));
    const double cut[3] = {0.0, fmin(a_star, delta), delta};
    double v = 0.0, e = 0.0;
    for (int p = 0; p < 2; ++p) {
        if (!(cut[p + 1] > cut[p]))
            continue;
        mf_result r;
        if (mf_quad_adaptive(disc_inner, &c, cut[p], cut[p + 1], 0.0, QUAD_REL, MF_QUAD_MAX_INTERVALS, &r) != MF_OK)
            return 0;
        v += r.val;
        e += r.err;
    }
    *val = radiance * v;
    *err = radiance * e;
    return 1;
}

/* Closed-form SH of the disc (header): c_lm += P w_l Y_lm(d). */
static void disc_add_sh(double c[MF_SH_COEFFS], mf_vec3 d, double delta, double power)
{
    double y[MF_SH_COEFFS];
    mf_sh_eval(d, y);
    double h = cos(0.5 * delta);
    const double w[3] = {1.0 / (h * h), 1.0, cos(delta)};
    for (int l = 0; l <= 2; ++l)
        for (int m = -l; m <= l; ++m)
            c[mf_sh_index(l, m)] += power * w[l] * y[mf_sh_index(l, m)];
}

/* Self-check of disc_add_sh: integral over the cap of Y_i by quadrature in the sun frame (the inner
 * integral over b: 16-point periodic trapezoid, exact for the degree-2 trigonometric polynomials
 * in b that Y_i restricted to a circle is). */
typedef struct {
    mf_frame fr;
    int i;
} cap_ctx;
static double cap_inner(double a, void *vctx)
{
    const cap_ctx *c = vctx;
    double s = 0.0;
    for (int k = 0; k < 16; ++k) {
        double b = 2.0 * MF_PI * (k + 0.5) / 16.0;
        mf_vec3 w = mf_frame_to_world(c->fr, mf_vec3_make(sin(a) * cos(b), sin(a) * sin(b), cos(a)));
        double y[MF_SH_COEFFS];
        mf_sh_eval(mf_vec3_normalize(w), y);
        s += (2.0 * MF_PI / 16.0) * y[c->i];
    }
    return sin(a) * s;
}
static double check_disc_sh(mf_vec3 d, double delta)
{
    double closed[MF_SH_COEFFS] = {0};
    disc_add_sh(closed, d, delta, 1.0);
    double radiance = 1.0 / (MF_PI * sin(delta) * sin(delta)), worst = 0.0;
    cap_ctx c;
    c.fr = mf_frame_from_normal(d);
    for (c.i = 0; c.i < MF_SH_COEFFS; ++c.i) {
        mf_result r;
        if (mf_quad_adaptive(cap_inner, &c, 0.0, delta, 0.0, QUAD_REL, MF_QUAD_MAX_INTERVALS, &r) != MF_OK)
            return INFINITY;
        worst = fmax(worst, fabs(radiance * r.val - closed[c.i]));
    }
    return worst;
}

/* ---- the environments ------------------------------------------------------------------------- */
typedef struct {
    const char *name;
    radiance_fn sky;     /* NULL: none */
    int sky_upper_only;
    int sky_quad_n;      /* mf_sh_project_fn order */
    int has_sun;         /* 1: disc, 2: directional */
    double sun_power;
    double c[MF_SH_COEFFS];
    double total;        /* integral L dw = 2 sqrt(pi) L_00 */
    double proj_err;
    double light_theta_deg, light_phi_deg; /* the sun or sun lobe, for the plots (NAN: none) */
} environment;

static int exact_irradiance(const environment *env, mf_vec3 sun, mf_vec3 n, double *val, double *err)
{
    double v = 0.0, e = 0.0, vv, ee;
    if (env->sky) {
        if (!sky_irradiance(env->sky, env->sky_upper_only, n, &vv, &ee))
            return 0;
        v += vv;
        e += ee;
    }
    if (env->has_sun == 1) {
        if (!disc_irradiance(sun, SUN_RADIUS, env->sun_power, n, &vv, &ee))
            return 0;
        v += vv;
        e += ee;
    } else if (env->has_sun == 2) {
        v += env->sun_power * fmax(0.0, mf_vec3_dot(n, sun));
    }
    *val = v;
    *err = e;
    return 1;
}

static void usage(FILE *f)
{
    fprintf(f,
            "usage: study_sh_irradiance [--thetas T] [--phis P] [--windows LIST] [--out FILE]\n\n"
            "Order-2 SH irradiance (mf_sh_irradiance, 9 coefficients) against the exact irradiance by\n"
            "quadrature, for the environments overcast, sun_sky, sun_disc, directional, over a T x P grid\n"
            "of normals covering the sphere (cell centres; defaults 36 x 72).  LIST: comma-separated windows\n"
            "from none, hanning, lanczos (width 3, mf_sh_apply_window; default none,hanning,lanczos).\n"
            "Writes FILE (default notebooks_data/sh_irradiance.csv): provenance header, then env, window,\n"
            "theta_deg, phi_deg, e_exact, e_exact_err, e_sh, abs_err, rel_err, norm_err, light_theta_deg,\n"
            "light_phi_deg.\n"
            "exit status: 0 success, 1 quadrature or self-check failure, 2 usage, 3 I/O error\n");
}

static int parse_int(const char *opt, const char *v, int lo, int hi, int *out)
{
    char *end;
    errno = 0;
    long x = strtol(v, &end, 10);
    if (errno || end == v || *end || x < lo || x > hi) {
        fprintf(stderr, "study_sh_irradiance: %s: '%s' is not an integer in [%d, %d]\n", opt, v, lo, hi);
        return 0;
    }
    *out = (int)x;
    return 1;
}

int main(int argc, char **argv)
{
    int n_theta = 36, n_phi = 72;
    const char *out_path = "notebooks_data/sh_irradiance.csv", *win_list = "none,hanning,lanczos";
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i], *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        } else if (!strcmp(a, "--thetas") && v) {
            if (!parse_int(a, v, 2, 2000, &n_theta))
                return 2;
            ++i;
        } else if (!strcmp(a, "--phis") && v) {
            if (!parse_int(a, v, 1, 4000, &n_phi))
                return 2;
            ++i;
        } else if (!strcmp(a, "--windows") && v) {
            win_list = v;
            ++i;
        } else if (!strcmp(a, "--out") && v) {
            out_path = v;
            ++i;
        } else {
            int known = !strcmp(a, "--thetas") || !strcmp(a, "--phis") || !strcmp(a, "--windows") || !strcmp(a, "--out");
            fprintf(stderr, known ? "study_sh_irradiance: %s needs a value (see --help)\n"
                                  : "study_sh_irradiance: unknown argument '%s' (see --help)\n",
                    a);
            return 2;
        }
    }
    static const char *const k_win_names[3] = {"none", "hanning", "lanczos"};
    const mf_sh_window k_wins[3] = {MF_SH_WINDOW_NONE, MF_SH_WINDOW_HANNING, MF_SH_WINDOW_LANCZOS};
    int use_win[3] = {0, 0, 0}, n_win = 0;
    {
        char buf[256];
        if (strlen(win_list) >= sizeof buf) {
            fprintf(stderr, "study_sh_irradiance: --windows: list too long\n");
            return 2;
        }
        strcpy(buf, win_list);
        for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
            int k = 0;
            while (k < 3 && strcmp(tok, k_win_names[k]))
                ++k;
            if (k == 3) {
                fprintf(stderr, "study_sh_irradiance: --windows: '%s' is not none, hanning or lanczos\n", tok);
                return 2;
            }
            n_win += !use_win[k];
            use_win[k] = 1;
        }
        if (!n_win) {
            fprintf(stderr, "study_sh_irradiance: --windows: empty list\n");
            return 2;
        }
    }
    if (mf_quad_gauss_legendre(48, gl_x[0], gl_w[0]) != MF_OK || mf_quad_gauss_legendre(24, gl_x[1], gl_w[1]) != MF_OK) {
        fprintf(stderr, "study_sh_irradiance: Gauss-Legendre nodes failed\n");
        return 1;
    }
    const mf_vec3 sun = mf_vec3_spherical((90.0 - SUN_ELEVATION_DEG) * DEG, SUN_AZIMUTH_DEG * DEG);

    /* ---- self-checks of the reference machinery ---- */
    {
        double c[MF_SH_COEFFS], perr, worst = 0.0;
        if (mf_sh_project_fn(f_zplus_sq, NULL, 8, c, &perr) != MF_OK)
            return 1;
        for (int k = 0; k < 64; ++k) {
            mf_vec3 n = mf_vec3_spherical(MF_PI * (k + 0.5) / 64.0, 2.399963229728653 * k); /* golden-angle spiral */
            double e, ee;
            if (!sky_irradiance(f_zplus_sq, 1, n, &e, &ee))
                return 1;
            worst = fmax(worst, fabs(mf_sh_irradiance(c, n) - e));
        }
        double d1 = check_disc_sh(sun, 0.3), d2 = check_disc_sh(sun, SUN_RADIUS);
        printf("self-check: L = max(0,z)^2 (order 2 exact): max |E_SH - E_quad| = %.2g; disc SH closed form vs "
               "quadrature: %.2g (radius 0.3 rad), %.2g (solar disc)\n",
               worst, d1, d2);
        if (!(worst <= 1e-12 && d1 <= 1e-12 && d2 <= 1e-12)) {
            fprintf(stderr, "study_sh_irradiance: self-check failed (tolerance 1e-12)\n");
            return 1;
        }
    }

    /* ---- the environments and their coefficients ---- */
    environment envs[N_ENV] = {
        {"overcast", f_overcast, 1, 16, 0, 0.0, {0}, 0.0, 0.0, NAN, NAN},
        {"sun_sky", f_sun_sky, 0, 48, 0, 0.0, {0}, 0.0, 0.0, acos(0.9 / sqrt(0.94)) / DEG, atan2(0.2, 0.3) / DEG},
        {"sun_disc", f_overcast, 1, 16, 1, SUN_POWER, {0}, 0.0, 0.0, 90.0 - SUN_ELEVATION_DEG, SUN_AZIMUTH_DEG},
        {"directional", NULL, 0, 0, 2, 1.0, {0}, 0.0, 0.0, 90.0 - SUN_ELEVATION_DEG, SUN_AZIMUTH_DEG},
    };
    for (int e = 0; e < N_ENV; ++e) {
        environment *env = &envs[e];
        if (env->sky) {
            mf_status st = mf_sh_project_fn(env->sky, NULL, env->sky_quad_n, env->c, &env->proj_err);
            if (st != MF_OK) {
                fprintf(stderr, "study_sh_irradiance: %s: projection: %s\n", env->name, mf_status_str(st));
                return 1;
            }
        }
        if (env->has_sun == 1)
            disc_add_sh(env->c, sun, SUN_RADIUS, env->sun_power);
        else if (env->has_sun == 2)
            mf_sh_add_directional(env->c, sun, env->sun_power);
        env->total = 2.0 * sqrt(MF_PI) * env->c[0];
    }

    /* ---- output ---- */
    /* the one atomic write (mfkit/io/mf_io.h): a temporary beside the file, renamed at the end */
    mf_io_atomic out;
    char io_msg[1024];
    if (mf_io_atomic_begin(&out, out_path, io_msg, sizeof io_msg) != MF_OK) {
        fprintf(stderr, "study_sh_irradiance: %s\n", io_msg);
        return 3;
    }
    FILE *f = out.file;
    study_write_header(f, "study_sh_irradiance", argc, argv, "none");
    fprintf(f, "env,window,theta_deg,phi_deg,e_exact,e_exact_err,e_sh,abs_err,rel_err,norm_err,light_theta_deg,"
               "light_phi_deg\n");

    int n_normals = n_theta * n_phi;
    double *ex = malloc(sizeof *ex * (size_t)n_normals * 2);
    if (!ex) {
        mf_io_atomic_abort(&out);
        fprintf(stderr, "study_sh_irradiance: out of memory\n");
        return 1;
    }
    double *ex_err = ex + n_normals;
    int status = 0;
    printf("%-12s %-8s %10s %10s %18s %10s %10s %12s\n", "environment", "window", "max norm", "mean norm", "at (theta, phi)",
           "max rel", "mean rel", "quad err");
    for (int e = 0; e < N_ENV && !status; ++e) {
        const environment *env = &envs[e];
        double emax = 0.0, worst_quad = 0.0;
        for (int j = 0; j < n_theta && !status; ++j)
            for (int k = 0; k < n_phi; ++k) {
                mf_vec3 n = mf_vec3_spherical(MF_PI * (j + 0.5) / n_theta, 2.0 * MF_PI * (k + 0.5) / n_phi);
                int idx = j * n_phi + k;
                if (!exact_irradiance(env, sun, n, &ex[idx], &ex_err[idx])) {
                    fprintf(stderr, "study_sh_irradiance: %s: quadrature failed at theta %.3f deg, phi %.3f deg\n",
                            env->name, 180.0 * (j + 0.5) / n_theta, 360.0 * (k + 0.5) / n_phi);
                    status = 1;
                    break;
                }
                emax = fmax(emax, ex[idx]);
                worst_quad = fmax(worst_quad, ex_err[idx]);
            }
        for (int w = 0; w < 3 && !status; ++w) {
            if (!use_win[w])
                continue;
            double c[MF_SH_COEFFS];
            memcpy(c, env->c, sizeof c);
            if (k_wins[w] != MF_SH_WINDOW_NONE)
                mf_sh_apply_window(c, k_wins[w], MF_SH_ORDER + 1.0);
            double max_norm = 0.0, sum_norm = 0.0, sum_w = 0.0, max_rel = 0.0, sum_rel = 0.0, sum_wr = 0.0;
            double at_t = NAN, at_p = NAN;
            for (int j = 0; j < n_theta; ++j)
                for (int k = 0; k < n_phi; ++k) {
                    double th = 180.0 * (j + 0.5) / n_theta, ph = 360.0 * (k + 0.5) / n_phi;
                    mf_vec3 n = mf_vec3_spherical(th * DEG, ph * DEG);
                    int idx = j * n_phi + k;
                    double esh = mf_sh_irradiance(c, n), d = fabs(esh - ex[idx]);
                    double rel = ex[idx] > 0.0 ? d / ex[idx] : NAN, norm = d / env->total;
                    fprintf(f, "%s,%s,%.10g,%.10g,%.17g,%.3e,%.17g,%.17g,%.17g,%.17g,%.10g,%.10g\n", env->name,
                            k_win_names[w], th, ph, ex[idx], ex_err[idx], esh, d, rel, norm, env->light_theta_deg,
                            env->light_phi_deg);
                    double sw = sin(th * DEG); /* solid angle of the cell, up to a constant */
                    if (norm > max_norm) {
                        max_norm = norm;
                        at_t = th;
                        at_p = ph;
                    }
                    sum_norm += sw * norm;
                    sum_w += sw;
                    if (ex[idx] >= 0.05 * emax) { /* "lit" normals: relative errors are meaningful */
                        max_rel = fmax(max_rel, rel);
                        sum_rel += sw * rel;
                        sum_wr += sw;
                    }
                }
            char at[64];
            snprintf(at, sizeof at, "(%.1f, %.1f)", at_t, at_p);
            printf("%-12s %-8s %10.5f %10.5f %18s %10.5f %10.5f %12.2g\n", env->name, k_win_names[w], max_norm,
                   sum_norm / sum_w, at, max_rel, sum_rel / sum_wr, worst_quad);
        }
        if (!status)
            printf("%-12s integral L dw = %.6g, max E over the grid = %.6g, projection error estimate %.2g\n", "", env->total,
                   emax, env->proj_err);
    }
    free(ex);
    if (status) {
        mf_io_atomic_abort(&out);
        return status;
    }
    if (mf_io_atomic_commit(&out, io_msg, sizeof io_msg) != MF_OK) {
        fprintf(stderr, "study_sh_irradiance: %s\n", io_msg);
        return 3;
    }
    printf("norm = |E_SH - E| / integral L dw (<= 3/32 = 0.09375 for any L >= 0); rel = |E_SH - E| / E over the "
           "normals with E >= 0.05 max E; means weighted by solid angle\nwrote %s\n",
           out_path);
    return 0;
}
