/* mf_sh.c -- real spherical harmonics to order 2, projection and irradiance (see mf_sh.h). */
#include "mfkit/mf_sh.h"
#include "mfkit/mf_quad.h"

#include <stdlib.h>

/* |w.w - 1| <= 1e-6: the unit-vector domain of every direction argument. */
static int is_unit(mf_vec3 w)
{
    return mf_vec3_isfinite(w) && fabs(mf_vec3_dot(w, w) - 1.0) <= 1e-6;
}

static void fill_nan(double c[MF_SH_COEFFS])
{
    for (int i = 0; i < MF_SH_COEFFS; ++i)
        c[i] = NAN;
}

void mf_sh_eval(mf_vec3 w, double y[MF_SH_COEFFS])
{
    if (!is_unit(w)) {
        fill_nan(y);
        return;
    }
    /* [R&H 2001, Eq. 3], exact constants (docs/math.md, correction C-L9) */
    y[0] = MF_SH_Y00;
    y[1] = MF_SH_Y1 * w.y;
    y[2] = MF_SH_Y1 * w.z;
    y[3] = MF_SH_Y1 * w.x;
    y[4] = MF_SH_Y2 * w.x * w.y;
    y[5] = MF_SH_Y2 * w.y * w.z;
    y[6] = MF_SH_Y20 * (3.0 * w.z * w.z - 1.0);
    y[7] = MF_SH_Y2 * w.x * w.z;
    y[8] = MF_SH_Y22 * (w.x * w.x - w.y * w.y);
}

double mf_sh_reconstruct(const double c[MF_SH_COEFFS], mf_vec3 w)
{
    double y[MF_SH_COEFFS], s = 0.0;
    mf_sh_eval(w, y);
    for (int i = 0; i < MF_SH_COEFFS; ++i)
        s += c[i] * y[i];
    return s;
}

double mf_sh_cosine_lobe(int l)
{
    if (l < 0)
        return NAN;
    if (l == 0)
        return MF_PI;
    if (l == 1)
        return 2.0 * MF_PI / 3.0;
    if (l % 2 == 1)
        return 0.0;
    /* [R&H 2001, Eq. 8]; l! / (2^l ((l/2)!)^2) = prod_{k=1}^{l/2} (2k - 1)/(2k), no overflow */
    double ratio = 1.0;
    for (int k = 1; k <= l / 2; ++k)
        ratio *= (2.0 * k - 1.0) / (2.0 * k);
    double sign = ((l / 2 - 1) % 2 == 0) ? 1.0 : -1.0;
    return 2.0 * MF_PI * sign / ((double)(l + 2) * (double)(l - 1)) * ratio;
}

void mf_sh_convolve_cosine(const double radiance[MF_SH_COEFFS], double irradiance[MF_SH_COEFFS])
{
    /* [R&H 2001, Eq. 7, 9]: A_0 = pi, A_1 = 2 pi/3, A_2 = pi/4 */
    static const double a[3] = {MF_PI, 2.0 * MF_PI / 3.0, 0.25 * MF_PI};
    for (int i = 0; i < MF_SH_COEFFS; ++i) {
        int l = (i == 0) ? 0 : (i < 4 ? 1 : 2);
        irradiance[i] = a[l] * radiance[i];
    }
}

double mf_sh_irradiance(const double radiance[MF_SH_COEFFS], mf_vec3 n)
{
    double e[MF_SH_COEFFS];
    mf_sh_convolve_cosine(radiance, e);
    return mf_sh_reconstruct(e, n);
}

void mf_sh_add_directional(double c[MF_SH_COEFFS], mf_vec3 d, double power)
{
    double y[MF_SH_COEFFS];
    if (!isfinite(power)) {
        fill_nan(c);
        return;
    }
    mf_sh_eval(d, y); /* NaNs for a non-unit d, which then propagate */
    /* [Dupuy 2013, Algorithm 2] with correction C-L1: every line is c += Y P, including L00 */
    for (int i = 0; i < MF_SH_COEFFS; ++i)
        c[i] += power * y[i];
}

/* One pass of the split product rule with n Gauss-Legendre nodes per hemisphere. */
static mf_status project_rule(mf_sh_fn f, void *user, int n, double c[MF_SH_COEFFS])
{
    double *x = malloc(sizeof(double) * 2 * (size_t)n);
    if (!x)
        return MF_ERR_ALLOC;
    double *w = x + n;
    mf_status st = mf_quad_gauss_legendre(n, x, w);
    if (st != MF_OK) {
        free(x);
        return st;
    }
    const int m = 4 * n;
    const double dphi = 2.0 * MF_PI / m;
    double acc[MF_SH_COEFFS] = {0};
    for (int half = 0; half < 2; ++half)
        for (int a = 0; a < n; ++a) {
            /* z on [0, 1] (half 0) or [-1, 0] (half 1); weight of dz is w/2 */
            double z = half == 0 ? 0.5 * (x[a] + 1.0) : 0.5 * (x[a] - 1.0);
            double sin_t = sqrt(fmax(0.0, (1.0 - z) * (1.0 + z)));
            double ring[MF_SH_COEFFS] = {0};
            for (int k = 0; k < m; ++k) {
                double phi = (k + 0.5) * dphi;
                mf_vec3 d = mf_vec3_make(sin_t * cos(phi), sin_t * sin(phi), z);
                double v = f(d, user);
                if (!isfinite(v)) {
                    free(x);
                    return MF_ERR_DOMAIN;
                }
                double y[MF_SH_COEFFS];
                mf_sh_eval(d, y);
                for (int i = 0; i < MF_SH_COEFFS; ++i)
                    ring[i] += v * y[i];
            }
            for (int i = 0; i < MF_SH_COEFFS; ++i)
                acc[i] += 0.5 * w[a] * dphi * ring[i];
        }
    for (int i = 0; i < MF_SH_COEFFS; ++i)
        c[i] = acc[i];
    free(x);
    return MF_OK;
}

mf_status mf_sh_project_fn(mf_sh_fn f, void *user, int n, double c[MF_SH_COEFFS], double *err)
{
    fill_nan(c);
    if (err)
        *err = NAN;
    if (!f || n < 2 || n > 1024)
        return MF_ERR_DOMAIN;
    double fine[MF_SH_COEFFS], coarse[MF_SH_COEFFS];
    mf_status st = project_rule(f, user, n, fine);
    if (st == MF_OK && err)
        st = project_rule(f, user, (n + 1) / 2, coarse);
    if (st != MF_OK)
        return st;
    double e = 0.0;
    for (int i = 0; i < MF_SH_COEFFS; ++i) {
        c[i] = fine[i];
        if (err)
            e = fmax(e, fabs(fine[i] - coarse[i]));
    }
    if (err)
        *err = e;
    return MF_OK;
}

mf_status mf_sh_project_latlong(const float *pixels, int width, int height, int pixel_stride, int row_stride,
                                double c[MF_SH_COEFFS])
{
    fill_nan(c);
    if (!pixels || width < 1 || height < 1 || pixel_stride < 1 || (long long)row_stride < (long long)width * pixel_stride)
        return MF_ERR_DOMAIN;
    const double dphi = 2.0 * MF_PI / width, dtheta = MF_PI / height;
    /* cos(theta0) - cos(theta1) = 2 sin(theta_c) sin(dtheta/2): no cancellation at the poles */
    const double half_chord = 2.0 * sin(0.5 * dtheta);
    double acc[MF_SH_COEFFS] = {0};
    for (int j = 0; j < height; ++j) {
        double theta = (j + 0.5) * dtheta;
        double sin_t = sin(theta), cos_t = cos(theta);
        double solid_angle = dphi * half_chord * sin_t;
        const float *row = pixels + (size_t)j * (size_t)row_stride;
        double ring[MF_SH_COEFFS] = {0};
        for (int i = 0; i < width; ++i) {
            double v = row[(size_t)i * (size_t)pixel_stride];
            if (!isfinite(v))
                return MF_ERR_DOMAIN;
            double phi = (i + 0.5) * dphi;
            double y[MF_SH_COEFFS];
            mf_sh_eval(mf_vec3_make(sin_t * cos(phi), sin_t * sin(phi), cos_t), y);
            for (int k = 0; k < MF_SH_COEFFS; ++k)
                ring[k] += v * y[k];
        }
        for (int k = 0; k < MF_SH_COEFFS; ++k)
            acc[k] += solid_angle * ring[k];
    }
    for (int k = 0; k < MF_SH_COEFFS; ++k)
        c[k] = acc[k];
    return MF_OK;
}

void mf_sh_rotate(const double in[MF_SH_COEFFS], mf_mat3 r, double out[MF_SH_COEFFS])
{
    double dev = 0.0;
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
            double s = 0.0;
            for (int k = 0; k < 3; ++k)
                s += r.m[a][k] * r.m[b][k];
            dev = fmax(dev, fabs(s - (a == b ? 1.0 : 0.0)));
        }
    if (!(dev <= 1e-9)) {
        fill_nan(out);
        return;
    }
    /* band 1: f_1(w) = Y1 (c11 x + c1-1 y + c10 z) = v.w, and v.(R^T w) = (R v).w */
    double v[3] = {in[3], in[1], in[2]};
    double rv[3];
    for (int a = 0; a < 3; ++a)
        rv[a] = r.m[a][0] * v[0] + r.m[a][1] * v[1] + r.m[a][2] * v[2];
    /* band 2 as w^T Q w (on the unit sphere, 3 z^2 - 1 = 2 z^2 - x^2 - y^2):
     *   Q = [[-Y20 c20 + Y22 c22, Y2 c2-2 / 2,          Y2 c21 / 2 ],
     *        [Y2 c2-2 / 2,          -Y20 c20 - Y22 c22, Y2 c2-1 / 2],
     *        [Y2 c21 / 2,           Y2 c2-1 / 2,         2 Y20 c20 ]]  (traceless) */
    double q[3][3];
    q[0][0] = -MF_SH_Y20 * in[6] + MF_SH_Y22 * in[8];
    q[1][1] = -MF_SH_Y20 * in[6] - MF_SH_Y22 * in[8];
    q[2][2] = 2.0 * MF_SH_Y20 * in[6];
    q[0][1] = q[1][0] = 0.5 * MF_SH_Y2 * in[4];
    q[1][2] = q[2][1] = 0.5 * MF_SH_Y2 * in[5];
    q[0][2] = q[2][0] = 0.5 * MF_SH_Y2 * in[7];
    /* Q' = R Q R^T */
    double rq[3][3], qp[3][3];
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
            rq[a][b] = r.m[a][0] * q[0][b] + r.m[a][1] * q[1][b] + r.m[a][2] * q[2][b];
    for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
            qp[a][b] = rq[a][0] * r.m[b][0] + rq[a][1] * r.m[b][1] + rq[a][2] * r.m[b][2];
    out[0] = in[0];
    out[1] = rv[1];
    out[2] = rv[2];
    out[3] = rv[0];
    out[4] = (qp[0][1] + qp[1][0]) / MF_SH_Y2;
    out[5] = (qp[1][2] + qp[2][1]) / MF_SH_Y2;
    out[7] = (qp[0][2] + qp[2][0]) / MF_SH_Y2;
    /* the trace of Q' is 0 up to rounding; read c20 from the traceless part of the diagonal */
    out[6] = (2.0 * qp[2][2] - qp[0][0] - qp[1][1]) / (6.0 * MF_SH_Y20);
    out[8] = (qp[0][0] - qp[1][1]) / (2.0 * MF_SH_Y22);
}

void mf_sh_to_frame(const double world[MF_SH_COEFFS], mf_frame f, double local[MF_SH_COEFFS])
{
    mf_mat3 r = {{{f.s.x, f.s.y, f.s.z}, {f.t.x, f.t.y, f.t.z}, {f.n.x, f.n.y, f.n.z}}};
    mf_sh_rotate(world, r, local);
}

double mf_sh_window_factor(mf_sh_window window, int l, double width)
{
    if (window != MF_SH_WINDOW_NONE && window != MF_SH_WINDOW_HANNING && window != MF_SH_WINDOW_LANCZOS)
        return NAN;
    if (l < 0 || !isfinite(width) || !(width > 0.0))
        return NAN;
    if (window == MF_SH_WINDOW_NONE || l == 0)
        return 1.0;
    if (l >= width)
        return 0.0;
    double t = MF_PI * l / width;
    /* [Sloan 2008, windowing] */
    return window == MF_SH_WINDOW_HANNING ? 0.5 * (1.0 + cos(t)) : sin(t) / t;
}

void mf_sh_apply_window(double c[MF_SH_COEFFS], mf_sh_window window, double width)
{
    for (int i = 0; i < MF_SH_COEFFS; ++i) {
        int l = (i == 0) ? 0 : (i < 4 ? 1 : 2);
        c[i] *= mf_sh_window_factor(window, l, width);
    }
}
